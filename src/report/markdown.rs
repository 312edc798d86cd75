//! `report.md`: the report an engineer reads. Summary and rules, the input
//! warnings, the flagged zones with their reasons, remedy and chart (aperture
//! and temperature), the marginal zones, the zones that re-open after
//! grouting, the zones already grouted (history, no verdict), the joint
//! meters against the prediction, and a compact table of every zone still
//! to grout. Values stand beside the limit applied to them.

use std::fmt::Write;

use super::charts::{meter_chart_file, zone_chart_file};
use super::meters;
use super::summary::Summary;
use super::words::{self, mm, opt};
use crate::planner::{Plan, Verdict, ZoneReadiness};

/// A table cell: a `|` would end the cell and a newline the row.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn row(out: &mut String, cells: &[String]) {
    let cells: Vec<String> = cells.iter().map(|c| cell(c)).collect();
    let _ = writeln!(out, "| {} |", cells.join(" | "));
}

fn header(out: &mut String, names: &[&str]) {
    let _ = writeln!(out, "| {} |", names.join(" | "));
    let _ = writeln!(out, "|{}", "---|".repeat(names.len()));
}

fn summary(out: &mut String, plan: &Plan) {
    let s = Summary::of(plan);
    let st = &plan.settings;
    let p = &plan.stats;
    let _ = writeln!(out, "## Summary\n");
    let _ = writeln!(
        out,
        "- **{}** zones to grout: **{}** flagged (not groutable), **{}** marginal, {} groutable",
        s.to_grout,
        s.flagged,
        s.marginal,
        s.to_grout - s.flagged - s.marginal
    );
    let _ = writeln!(
        out,
        "- **{}** {} grouted before {}, **{}** of them re-opened",
        s.history,
        if s.history == 1 { "zone" } else { "zones" },
        plan.as_of,
        s.reopened
    );
    let _ = writeln!(
        out,
        "- Rules: aperture ≥ {} mm at the {} point (marginal below {} mm); both blocks ≤ closure + {} °C; \
         youngest lift ≥ {} days old; ≥ {} m of concrete above; the zone below grouted first",
        st.min_aperture_mm,
        st.aperture_point.as_str(),
        st.marginal_aperture_mm,
        st.closure_tolerance_c,
        st.min_age_days,
        st.min_cover_m
    );
    let from = match p.restarted_from {
        Some(d) => format!("restarted from the checkpoint of {d}"),
        None => "from scratch".into(),
    };
    let reused = if p.reused.is_empty() {
        String::new()
    } else {
        format!("; reused from the last plan: {}", p.reused.join(", "))
    };
    let _ = writeln!(
        out,
        "- Computed in {:.1} s: baseline simulation {:.1} s ({from}), {} re-simulations for remedies {:.1} s{reused}\n",
        p.total_seconds, p.baseline_seconds, p.resimulations, p.resimulation_seconds
    );
    if let Some(caution) = words::approximations_caution(&plan.approximations) {
        let _ = writeln!(out, "> **{caution}**\n");
    }
}

fn flagged(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan.flagged().collect();
    let _ = writeln!(out, "## Flagged zones (not groutable)\n");
    if zones.is_empty() {
        let _ = writeln!(
            out,
            "Every zone still to grout is groutable on its planned date.\n"
        );
        return;
    }
    header(
        out,
        &[
            "Joint",
            "Zone",
            "Planned",
            "Aperture mm (limit)",
            "Reasons",
            "Remedy",
            "Verified",
            "Note",
        ],
    );
    for z in &zones {
        let r = z.remedy.as_ref();
        row(
            out,
            &[
                z.joint.to_string(),
                z.zone.to_string(),
                z.planned.to_string(),
                words::aperture_vs_limit(z, &plan.settings),
                z.reasons(),
                r.map(words::remedy_short)
                    .unwrap_or_else(|| "not searched".into()),
                r.and_then(words::verified_words).unwrap_or_default(),
                r.map(|r| r.note.clone()).unwrap_or_default(),
            ],
        );
    }
    out.push('\n');
    for z in &zones {
        flagged_zone(out, plan, z);
    }
}

/// One flagged zone: its reasons in full, the remedy, a re-opening, the chart.
fn flagged_zone(out: &mut String, plan: &Plan, z: &ZoneReadiness) {
    let _ = writeln!(out, "### Joint {}, zone {}\n", z.joint, z.zone);
    for c in z.checks.iter().filter(|c| !c.passed) {
        if let Some(r) = &c.reason {
            let _ = writeln!(out, "- ✗ {r}");
        }
    }
    if let Some(r) = &z.remedy {
        let mut t = words::remedy_short(r);
        if let Some(v) = words::verified_words(r) {
            t.push_str(&format!(" ({v})"));
        }
        let _ = writeln!(out, "- Remedy: {t}");
    }
    if let Some(d) = z.reopened {
        let _ = writeln!(out, "- Re-opens {d}, after its planned grouting");
    }
    out.push('\n');
    if plan
        .histories
        .iter()
        .any(|h| h.joint == z.joint && h.zone == z.zone)
    {
        let _ = writeln!(
            out,
            "![Aperture and temperature history of joint {}, zone {}](charts/{})\n",
            z.joint,
            z.zone,
            zone_chart_file(z.joint, z.zone)
        );
    } else {
        let _ = writeln!(out, "No history in the plan for this zone.\n");
    }
}

fn marginal(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan
        .to_grout()
        .filter(|z| z.verdict == Verdict::Marginal)
        .collect();
    if zones.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Marginal zones\n");
    header(
        out,
        &[
            "Joint",
            "Zone",
            "Planned",
            "Aperture mm (limit)",
            "Center mm",
            "Warmer block °C (limit)",
            "Why",
        ],
    );
    for z in zones {
        row(
            out,
            &[
                z.joint.to_string(),
                z.zone.to_string(),
                z.planned.to_string(),
                words::aperture_vs_limit(z, &plan.settings),
                opt(z.apertures_mm.center, mm),
                words::temperature_vs_limit(z, &plan.settings),
                words::marginal_words(z, &plan.settings),
            ],
        );
    }
    out.push('\n');
}

/// The zones whose grout layer the simulation cracks after grouting: the
/// ones grouted already, and the ones still to grout (after their planned
/// date, as planned).
fn reopened(out: &mut String, plan: &Plan) {
    for (history, title) in [
        (true, "Grouted zones that re-opened"),
        (false, "Planned zones that re-open after grouting"),
    ] {
        let zones: Vec<&ZoneReadiness> = plan
            .zones
            .iter()
            .filter(|z| z.history == history && z.reopened.is_some())
            .collect();
        if zones.is_empty() {
            continue;
        }
        let _ = writeln!(out, "## {title}\n");
        let grouted = if history { "Grouted" } else { "Planned" };
        header(
            out,
            &["Joint", "Zone", grouted, "Re-opened", "Days after grouting"],
        );
        for z in zones {
            let d = z.reopened.expect("filtered on Some");
            row(
                out,
                &[
                    z.joint.to_string(),
                    z.zone.to_string(),
                    z.planned.to_string(),
                    d.to_string(),
                    (d - z.planned).num_days().to_string(),
                ],
            );
        }
        out.push('\n');
    }
}

/// The zones grouted before the as-of date: history, listed with what the
/// simulation gave on their grouting date but without a verdict (today's
/// rules do not re-judge a zone already grouted).
fn already_grouted(out: &mut String, plan: &Plan) {
    let zones: Vec<&ZoneReadiness> = plan.zones.iter().filter(|z| z.history).collect();
    if zones.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Already grouted (before {})\n", plan.as_of);
    let _ = writeln!(
        out,
        "History: these zones were grouted before the as-of date; they are not re-checked \
         and get no verdict. Values are the simulation's on the grouting date.\n"
    );
    header(
        out,
        &[
            "Joint",
            "Zone",
            "Grouted",
            "Least aperture mm",
            "Warmer block °C",
            "Re-opened",
        ],
    );
    for z in zones {
        row(
            out,
            &[
                z.joint.to_string(),
                z.zone.to_string(),
                z.planned.to_string(),
                opt(z.apertures_mm.min, mm),
                opt(words::max_block_temp(z), |t| format!("{t:.1}")),
                z.reopened.map(|d| d.to_string()).unwrap_or("no".into()),
            ],
        );
    }
    out.push('\n');
}

/// The inputs the plan accepted but that look wrong, each where it is.
fn warnings(out: &mut String, plan: &Plan) {
    if plan.warnings.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Warnings\n");
    for w in &plan.warnings {
        let _ = writeln!(out, "- {}", cell(&w.to_string()));
    }
    out.push('\n');
}

fn meters_section(out: &mut String, plan: &Plan) {
    if plan.meters.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Joint meters\n");
    let _ = writeln!(
        out,
        "Error = predicted − measured aperture, over the readings the simulation predicts \
         (the zone exists on that date).\n"
    );
    header(
        out,
        &[
            "Joint",
            "Readings",
            "Compared",
            "Mean error mm",
            "RMS error mm",
            "Max abs error mm",
        ],
    );
    let f3 = |v: f64| {
        // A mean error that rounds to zero would print as "-0.000".
        let s = format!("{v:.3}");
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        }
    };
    for e in meters::errors(&plan.meters) {
        row(
            out,
            &[
                e.joint.to_string(),
                e.readings.to_string(),
                e.compared.to_string(),
                opt(e.mean_error_mm, f3),
                opt(e.rms_error_mm, f3),
                opt(e.max_abs_error_mm, f3),
            ],
        );
    }
    out.push('\n');
    for s in meters::series(&plan.meters) {
        let _ = writeln!(
            out,
            "### Joint {}, zone {}, {} meter\n",
            s.joint, s.zone, s.point
        );
        let _ = writeln!(
            out,
            "![Joint {}, zone {}, {} meter: predicted and measured](charts/{})\n",
            s.joint,
            s.zone,
            s.point,
            meter_chart_file(s.joint, s.zone, s.point)
        );
    }
}

fn all_to_grout(out: &mut String, plan: &Plan) {
    let _ = writeln!(out, "## All zones to grout\n");
    header(
        out,
        &[
            "Joint",
            "Zone",
            "Planned",
            "Aperture mm (limit)",
            "Center mm",
            "Warmer block °C (limit)",
            "Verdict",
            "Reasons — remedy",
        ],
    );
    for z in plan.to_grout() {
        row(
            out,
            &[
                z.joint.to_string(),
                z.zone.to_string(),
                z.planned.to_string(),
                words::aperture_vs_limit(z, &plan.settings),
                opt(z.apertures_mm.center, mm),
                words::temperature_vs_limit(z, &plan.settings),
                format!(
                    "{} {}",
                    words::verdict_symbol(z.verdict),
                    words::verdict_words(z.verdict)
                ),
                words::zone_words(z, &plan.settings),
            ],
        );
    }
    out.push('\n');
}

/// The Markdown text; chart links are relative to the report's folder.
pub fn render(plan: &Plan) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Grouting readiness: {}, as of {}\n",
        plan.scene, plan.as_of
    );
    summary(&mut out, plan);
    warnings(&mut out, plan);
    flagged(&mut out, plan);
    marginal(&mut out, plan);
    reopened(&mut out, plan);
    already_grouted(&mut out, plan);
    meters_section(&mut out, plan);
    all_to_grout(&mut out, plan);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_cannot_break_the_table() {
        assert_eq!(cell("a | b\nc"), "a \\| b c");
    }
}
