//! The readiness table for the terminal: the zones still to grout in fixed
//! width columns, each verdict with a symbol so it reads without colour,
//! lines kept to `LINE_WIDTH` characters, and a one-line summary.

use std::fmt::Write;

use super::summary::Summary;
use super::words::{self, opt};
use crate::planner::{Plan, Verdict, ZoneReadiness};
use crate::scene::PlannerSettings;

/// Widest line of the table, in characters.
pub const LINE_WIDTH: usize = 120;

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

/// Reasons and remedy in `width` characters: the remedy is what the
/// engineer acts on, so the reasons are cut first.
fn words_cell(z: &ZoneReadiness, s: &PlannerSettings, width: usize) -> String {
    let (Verdict::NotGroutable, Some(r)) = (z.verdict, &z.remedy) else {
        return fit(&words::zone_words(z, s), width);
    };
    let remedy = words::remedy_short(r);
    let reasons = z.reasons();
    if reasons.is_empty() {
        return fit(&remedy, width);
    }
    // Keep at least a few words of the reasons, even if the remedy is then cut.
    let room = width.saturating_sub(remedy.chars().count() + 3).max(12);
    fit(&format!("{} — {remedy}", fit(&reasons, room)), width)
}

/// Widths of the fixed columns and the gaps before each column (numbers
/// sit close; the verdict and the words get a wider gap to stand apart); the
/// last column takes what is left of `LINE_WIDTH`.
const W: [usize; 6] = [5, 4, 10, 10, 10, 15];
const GAP: [&str; 7] = ["", " ", " ", " ", " ", "  ", "  "];

fn join(cells: [String; 7]) -> String {
    let mut s = String::new();
    for (gap, c) in GAP.iter().zip(&cells) {
        s.push_str(gap);
        s.push_str(c);
    }
    s.trim_end().to_string()
}

/// Fixed-width table of the zones still to grout, then the summary line.
pub fn readiness_table(plan: &Plan) -> String {
    let mut out = String::new();
    let words_width =
        LINE_WIDTH - W.iter().sum::<usize>() - GAP.iter().map(|g| g.len()).sum::<usize>();
    let header = [
        right("Joint", W[0]),
        right("Zone", W[1]),
        left("Planned", W[2]),
        right("Min/ctr mm", W[3]),
        right("Tmax/cl °C", W[4]),
        left("Verdict", W[5]),
        "Reasons — remedy".into(),
    ];
    let _ = writeln!(out, "{}", join(header));
    let _ = writeln!(out, "{}", "─".repeat(LINE_WIDTH));
    for z in plan.to_grout() {
        let ap = format!(
            "{}/{}",
            opt(z.apertures_mm.min, words::mm),
            opt(z.apertures_mm.center, words::mm)
        );
        let temp = format!(
            "{}/{:.1}",
            opt(words::max_block_temp(z), |t| format!("{t:.1}")),
            z.closure_temp_c
        );
        let verdict = format!(
            "{} {}",
            words::verdict_symbol(z.verdict),
            words::verdict_words(z.verdict)
        );
        let row = [
            right(&z.joint.to_string(), W[0]),
            right(&z.zone.to_string(), W[1]),
            left(&z.planned.to_string(), W[2]),
            right(&ap, W[3]),
            right(&temp, W[4]),
            left(&verdict, W[5]),
            words_cell(z, &plan.settings, words_width),
        ];
        let _ = writeln!(out, "{}", join(row));
    }
    let _ = writeln!(out, "{}", Summary::of(plan).line(plan.as_of));
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
}
