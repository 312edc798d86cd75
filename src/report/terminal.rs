//! The readiness table for the terminal: the zones still to grout in fixed
//! width columns, each value beside the limit it is checked against and each
//! verdict with a symbol so it reads without colour; then, in full, why each
//! flagged zone fails and its remedy, the zones that re-open after grouting,
//! the zones already grouted, the input warnings, and a one-line summary.
//! Lines are kept to `LINE_WIDTH` characters (long words wrap, never cut).

use std::fmt::Write;

use super::summary::Summary;
use super::words;
use crate::planner::{Plan, RemedyChoice, Verdict, ZoneReadiness};
use crate::scene::PlannerSettings;
use crate::vocab::ZonePoint;

/// Widest line of the output, in characters.
pub const LINE_WIDTH: usize = 100;
/// `s` cut to `width` characters, ending in … when cut.
pub fn fit(s: &str, width: usize) -> String {
    if s.chars().count() <= width {
        return s.to_string();
    }
    let mut out: String = s.chars().take(width.saturating_sub(1)).collect();
    out.push('…');
    out
}

/// Left-aligned in `width` characters (chars, not bytes: ✗ and ° are one
/// column each but several bytes).
fn left(s: &str, width: usize) -> String {
    let s = fit(s, width);
    let pad = width - s.chars().count();
    format!("{s}{}", " ".repeat(pad))
}

fn right(s: &str, width: usize) -> String {
    let s = fit(s, width);
    let pad = width - s.chars().count();
    format!("{}{s}", " ".repeat(pad))
}

/// `text` wrapped at spaces into lines of at most `width` characters, the
/// first starting with `first` and the others with `rest` (prefixes written
/// as given; a word longer than a line is left whole rather than cut).
pub fn wrap(text: &str, first: &str, rest: &str, width: usize) -> Vec<String> {
    wrap_tokens(text.split_whitespace(), first, rest, width)
}

/// [`wrap`] over tokens that must not be split (a token may hold spaces).
fn wrap_tokens<'a>(
    tokens: impl IntoIterator<Item = &'a str>,
    first: &str,
    rest: &str,
    width: usize,
) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = first.to_string();
    let mut empty = true;
    for word in tokens {
        let sep = usize::from(!empty);
        let fits = line.chars().count() + sep + word.chars().count() <= width;
        if !empty && !fits {
            lines.push(std::mem::replace(&mut line, rest.to_string()));
            empty = true;
        }
        if !empty {
            line.push(' ');
        }
        line.push_str(word);
        empty = false;
    }
    lines.push(line);
    lines
}

/// Why a zone is not plainly groutable, in a few words: the failed rules,
/// or for a marginal zone the aperture against the marginal limit; one
/// token per rule, so a wrapped cell never splits "zone below".
fn why_tokens(z: &ZoneReadiness, s: &PlannerSettings) -> Vec<String> {
    match z.verdict {
        Verdict::Groutable => Vec::new(),
        Verdict::Marginal => vec![format!(
            "aperture below {} mm",
            words::mm(s.marginal_aperture_mm)
        )],
        Verdict::NotGroutable => {
            let failed: Vec<&str> = z
                .checks
                .iter()
                .filter(|c| !c.passed)
                .map(|c| words::rule_words(c.rule))
                .collect();
            let n = failed.len();
            failed
                .iter()
                .enumerate()
                .map(|(i, w)| format!("{w}{}", if i + 1 < n { "," } else { "" }))
                .collect()
        }
    }
}

/// The aperture column's header: which aperture the rule reads.
fn aperture_header(point: ZonePoint) -> &'static str {
    match point {
        ZonePoint::Min => "Least aperture mm",
        ZonePoint::Upstream => "Aperture mm, up",
        ZonePoint::Center => "Aperture mm, ctr",
        ZonePoint::Downstream => "Aperture mm, down",
    }
}

/// Widths of the fixed columns and the gaps before each column (numbers
/// sit close; the verdict and the words get a wider gap to stand apart); the
/// last column takes what is left of `LINE_WIDTH`.
const W: [usize; 6] = [5, 4, 10, 17, 15, 15];
const GAP: [&str; 7] = ["", " ", " ", "  ", "  ", "  ", "  "];

fn join(cells: [String; 7]) -> String {
    let mut s = String::new();
    for (gap, c) in GAP.iter().zip(&cells) {
        s.push_str(gap);
        s.push_str(c);
    }
    s.trim_end().to_string()
}

/// The fixed-width table of the zones still to grout.
fn table(out: &mut String, plan: &Plan) {
    let s = &plan.settings;
    let why_width =
        LINE_WIDTH - W.iter().sum::<usize>() - GAP.iter().map(|g| g.len()).sum::<usize>();
    let header = [
        right("Joint", W[0]),
        right("Zone", W[1]),
        left("Planned", W[2]),
        right(aperture_header(s.aperture_point), W[3]),
        right("Warmer block °C", W[4]),
        left("Verdict", W[5]),
        "Why".into(),
    ];
    let _ = writeln!(out, "{}", join(header));
    let _ = writeln!(out, "{}", "─".repeat(LINE_WIDTH));
    for z in plan.to_grout() {
        let verdict = format!(
            "{} {}",
            words::verdict_symbol(z.verdict),
            words::verdict_words(z.verdict)
        );
        // The last column wraps under itself rather than being cut.
        let why = why_tokens(z, s);
        let why = wrap_tokens(why.iter().map(String::as_str), "", "", why_width);
        let row = [
            right(&z.joint.to_string(), W[0]),
            right(&z.zone.to_string(), W[1]),
            left(&z.planned.to_string(), W[2]),
            right(&words::aperture_vs_limit(z, s), W[3]),
            right(&words::temperature_vs_limit(z, s), W[4]),
            left(&verdict, W[5]),
            why[0].clone(),
        ];
        let _ = writeln!(out, "{}", join(row));
        for more in &why[1..] {
            let _ = writeln!(out, "{}{more}", " ".repeat(LINE_WIDTH - why_width));
        }
    }
}

/// Each flagged zone's reasons in full, its remedy and how the remedy
/// verified.
fn flagged_details(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan.flagged().collect();
    if zones.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nWhy the flagged zones are not groutable, and the remedy:"
    );
    for z in zones {
        let _ = writeln!(
            out,
            "Joint {} zone {}, planned {}:",
            z.joint, z.zone, z.planned
        );
        for c in z.checks.iter().filter(|c| !c.passed) {
            if let Some(r) = &c.reason {
                for l in wrap(r, "  ✗ ", "    ", LINE_WIDTH) {
                    let _ = writeln!(out, "{l}");
                }
            }
        }
        let remedy = match &z.remedy {
            Some(r) => {
                let mut t = words::remedy_short(r);
                if let Some(v) = words::verified_words(r) {
                    t.push_str(&format!(" ({v})"));
                }
                t
            }
            None => "not searched".into(),
        };
        for l in wrap(&remedy, "  → remedy: ", "    ", LINE_WIDTH) {
            let _ = writeln!(out, "{l}");
        }
        // Neighbours supercooled as one set: say so, and what it saved (or
        // that the zone-by-zone steps failed applied together).
        if let Some(r) = z
            .remedy
            .as_ref()
            .filter(|r| r.choice == RemedyChoice::Supercool)
        {
            if r.supercool.as_ref().is_some_and(|o| o.together.is_some()) {
                for l in wrap(r.note_without_cautions(), "    ", "    ", LINE_WIDTH) {
                    let _ = writeln!(out, "{l}");
                }
            }
        }
        // A supercooling a site limit stopped: which limit, in full.
        if let Some(r) = z.remedy.as_ref() {
            for b in &r.limited {
                for l in wrap(
                    b,
                    "    supercooling stopped by a site limit: ",
                    "    ",
                    LINE_WIDTH,
                ) {
                    let _ = writeln!(out, "{l}");
                }
            }
        }
        // Why none works is what the engineer needs when there is none.
        if let Some(r) = z.remedy.as_ref().filter(|r| r.choice == RemedyChoice::None) {
            for l in wrap(&r.note, "    why: ", "    ", LINE_WIDTH) {
                let _ = writeln!(out, "{l}");
            }
        }
        if let Some(d) = z.reopened {
            let _ = writeln!(out, "  ! re-opens {d}, after its planned grouting");
        }
    }
}

/// Zones still to grout whose grout layer the simulation cracks after the
/// planned date.
fn reopenings(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan.to_grout().filter(|z| z.reopened.is_some()).collect();
    if zones.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nRe-open after the planned grouting (the grout layer cracks):"
    );
    for z in zones {
        let d = z.reopened.expect("filtered on Some");
        let _ = writeln!(
            out,
            "  ! joint {} zone {}: grouted {}, re-opens {d} ({} days later)",
            z.joint,
            z.zone,
            z.planned,
            (d - z.planned).num_days()
        );
    }
}

/// The zones grouted before the as-of date: history, not re-checked, so no
/// verdict; those that re-opened since are named.
fn already_grouted(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan.zones.iter().filter(|z| z.history).collect();
    if zones.is_empty() {
        return;
    }
    let n = zones.len();
    let _ = writeln!(
        out,
        "\nAlready grouted before {} ({n} {}, history: no verdict):",
        plan.as_of,
        if n == 1 { "zone" } else { "zones" }
    );
    let n = zones.len();
    // One token per zone, so a line never breaks inside one.
    let list: Vec<String> = zones
        .iter()
        .enumerate()
        .map(|(i, z)| {
            let comma = if i + 1 < n { "," } else { "" };
            format!("J{} Z{} {}{comma}", z.joint, z.zone, z.planned)
        })
        .collect();
    for l in wrap_tokens(list.iter().map(String::as_str), "  ", "  ", LINE_WIDTH) {
        let _ = writeln!(out, "{l}");
    }
    for z in zones.iter().filter(|z| z.reopened.is_some()) {
        let d = z.reopened.expect("filtered on Some");
        let _ = writeln!(
            out,
            "  ! joint {} zone {} (grouted {}) re-opened {d}",
            z.joint, z.zone, z.planned
        );
    }
}

/// The inputs the plan accepted but that look wrong.
fn warnings(out: &mut String, plan: &Plan) {
    if plan.warnings.is_empty() {
        return;
    }
    let _ = writeln!(out, "\nWarnings ({}):", plan.warnings.len());
    for w in &plan.warnings {
        for l in wrap(&w.to_string(), "  ! ", "    ", LINE_WIDTH) {
            let _ = writeln!(out, "{l}");
        }
    }
}

/// The table of the zones still to grout, the flagged zones in full, the
/// re-openings, the zones already grouted, the warnings, then the summary.
pub fn readiness_table(plan: &Plan) -> String {
    let mut out = String::new();
    table(&mut out, plan);
    flagged_details(&mut out, plan);
    reopenings(&mut out, plan);
    already_grouted(&mut out, plan);
    warnings(&mut out, plan);
    if let Some(caution) = words::approximations_caution(&plan.approximations) {
        out.push('\n');
        for l in wrap(&caution, "! ", "  ", LINE_WIDTH) {
            let _ = writeln!(out, "{l}");
        }
    }
    let _ = writeln!(out, "\n{}", Summary::of(plan).line(plan.as_of));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_cuts_with_ellipsis() {
        assert_eq!(fit("abcdef", 6), "abcdef");
        assert_eq!(fit("abcdefg", 6), "abcde…");
        assert_eq!(left("✗ x", 5), "✗ x  ");
    }

    #[test]
    fn wrap_keeps_words_whole() {
        assert_eq!(
            wrap("aa bb cc dd", " - ", "   ", 8),
            [" - aa bb", "   cc dd"]
        );
        assert_eq!(wrap("abcdefghij", "", "", 4), ["abcdefghij"]);
        // A zone of the already-grouted list stays on one line.
        assert_eq!(
            wrap_tokens(["J1 Z1 05-01,", "J2 Z1 05-02"], "  ", "  ", 16),
            ["  J1 Z1 05-01,", "  J2 Z1 05-02"]
        );
    }
}
