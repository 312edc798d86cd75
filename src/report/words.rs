//! Plain-word descriptions of verdicts, remedies and the deciding values of
//! a zone, shared by the terminal table, the Markdown report and the CSV,
//! so every output says the same thing the same way.

use crate::planner::{Remedy, RemedyChoice, Rule, RuleCheck, Verdict, ZoneReadiness};
use crate::scene::{Approximation, PlannerSettings};
use crate::vocab::ZonePoint;

/// A symbol that reads without colour.
pub fn verdict_symbol(v: Verdict) -> &'static str {
    match v {
        Verdict::Groutable => "✓",
        Verdict::Marginal => "~",
        Verdict::NotGroutable => "✗",
    }
}

/// "not groutable" rather than the snake_case of the CSV.
pub fn verdict_words(v: Verdict) -> &'static str {
    match v {
        Verdict::Groutable => "groutable",
        Verdict::Marginal => "marginal",
        Verdict::NotGroutable => "not groutable",
    }
}

/// Millimetres with two decimals: a tenth of a joint meter's resolution is
/// noise, and 0.49 vs 0.50 matters against a 0.5 mm rule.
pub fn mm(v: f64) -> String {
    format!("{v:.2}")
}

/// "–" for a value that could not be measured.
pub fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map(f).unwrap_or_else(|| "–".into())
}

/// The aperture the rule is decided on.
pub fn deciding_aperture(z: &ZoneReadiness, point: ZonePoint) -> Option<f64> {
    let a = &z.apertures_mm;
    match point {
        ZonePoint::Min => a.min,
        ZonePoint::Upstream => a.upstream,
        ZonePoint::Center => a.center,
        ZonePoint::Downstream => a.downstream,
    }
}

/// The warmer of the two blocks.
pub fn max_block_temp(z: &ZoneReadiness) -> Option<f64> {
    match (z.temp_a_c, z.temp_b_c) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// The check of `rule` on the zone, if the plan made it.
fn check(z: &ZoneReadiness, rule: Rule) -> Option<&RuleCheck> {
    z.checks.iter().find(|c| c.rule == rule)
}

/// The aperture limit applied to the zone: its check's, else the settings'.
pub fn aperture_limit(z: &ZoneReadiness, s: &PlannerSettings) -> f64 {
    check(z, Rule::Aperture).map_or(s.min_aperture_mm, |c| c.limit)
}

/// The temperature limit applied to the zone (closure at its mid-height +
/// tolerance): its check's, else the settings'.
pub fn temperature_limit(z: &ZoneReadiness, s: &PlannerSettings) -> f64 {
    check(z, Rule::Temperature).map_or(z.closure_temp_c + s.closure_tolerance_c, |c| c.limit)
}

/// "0.40 < 0.50" or "1.76 ≥ 0.50": the deciding aperture against the limit
/// applied, the sign saying which side it is on [mm].
pub fn aperture_vs_limit(z: &ZoneReadiness, s: &PlannerSettings) -> String {
    let limit = aperture_limit(z, s);
    match deciding_aperture(z, s.aperture_point) {
        Some(a) if a < limit => format!("{} < {}", mm(a), mm(limit)),
        Some(a) => format!("{} ≥ {}", mm(a), mm(limit)),
        None => format!("– vs {}", mm(limit)),
    }
}

/// "16.9 > 13.5" or "13.0 ≤ 13.5": the warmer block against closure +
/// tolerance [°C].
pub fn temperature_vs_limit(z: &ZoneReadiness, s: &PlannerSettings) -> String {
    let limit = temperature_limit(z, s);
    match max_block_temp(z) {
        Some(t) if t > limit => format!("{t:.1} > {limit:.1}"),
        Some(t) => format!("{t:.1} ≤ {limit:.1}"),
        None => format!("– vs {limit:.1}"),
    }
}

/// A rule in a site engineer's words, for a list of the failed ones.
pub fn rule_words(rule: Rule) -> &'static str {
    match rule {
        Rule::Aperture => "aperture",
        Rule::Temperature => "temperature",
        Rule::Age => "age",
        Rule::Cover => "cover",
        Rule::BottomUp => "zone below",
    }
}

/// The failed rules in a few words: "aperture, temperature".
pub fn failed_rules(z: &ZoneReadiness) -> String {
    z.checks
        .iter()
        .filter(|c| !c.passed)
        .map(|c| rule_words(c.rule))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The proposed remedy in a few words: `supercool 1.25 °C → 0.62 mm`,
/// `delay 12 d → 2024-10-03, 0.55 mm (+ zone 4)` (the zones above that move
/// with it) or `no remedy found`.
pub fn remedy_short(r: &Remedy) -> String {
    match (r.choice, &r.supercool, &r.delay) {
        // "supercool 0.00 °C" would read as no remedy at all.
        (RemedyChoice::Supercool, Some(s), _) if r.by_neighbours_alone() => format!(
            "none of its own: its neighbours' supercooling → {} mm",
            mm(s.aperture_mm)
        ),
        (RemedyChoice::Supercool, Some(s), _) => {
            format!("supercool {:.2} °C → {} mm", s.delta_c, mm(s.aperture_mm))
        }
        (RemedyChoice::Delay, _, Some(d)) => {
            let mut s = format!("delay {} d → {}, {} mm", d.days, d.date, mm(d.aperture_mm));
            if !d.also_delayed.is_empty() {
                let zones: Vec<String> = d.also_delayed.iter().map(u32::to_string).collect();
                let z = if zones.len() == 1 { "zone" } else { "zones" };
                s.push_str(&format!(" (+ {z} {})", zones.join(", ")));
            }
            s
        }
        _ => "no remedy found".into(),
    }
}

/// The proposed remedy in fewer words, for a narrow column:
/// `supercool 1.25 °C`, `delay 12 d → 2024-10-03 +1 zone`, `none found`.
pub fn remedy_brief(r: &Remedy) -> String {
    match (r.choice, &r.supercool, &r.delay) {
        (RemedyChoice::Supercool, Some(_), _) if r.by_neighbours_alone() => {
            "neighbours' supercooling".into()
        }
        (RemedyChoice::Supercool, Some(s), _) => format!("supercool {:.2} °C", s.delta_c),
        (RemedyChoice::Delay, _, Some(d)) => {
            let mut s = format!("delay {} d → {}", d.days, d.date);
            match d.also_delayed.len() {
                0 => {}
                1 => s.push_str(" +1 zone"),
                n => s.push_str(&format!(" +{n} zones")),
            }
            s
        }
        _ => "none found".into(),
    }
}

/// The verified outcome of the remedy: `verified groutable, 0.61 mm`.
pub fn verified_words(r: &Remedy) -> Option<String> {
    r.verified.map(|(v, a)| match a {
        Some(a) => format!("verified {}, {} mm", verdict_words(v), mm(a)),
        None => format!("verified {}", verdict_words(v)),
    })
}

/// Why a groutable zone is only marginal.
pub fn marginal_words(z: &ZoneReadiness, s: &PlannerSettings) -> String {
    match deciding_aperture(z, s.aperture_point) {
        Some(a) => format!(
            "aperture {} mm below {} mm",
            mm(a),
            mm(s.marginal_aperture_mm)
        ),
        None => "aperture below the marginal limit".into(),
    }
}

/// What the terminal and the compact tables say about a zone: the failed
/// rules and the remedy, or why it is marginal.
pub fn zone_words(z: &ZoneReadiness, s: &PlannerSettings) -> String {
    match z.verdict {
        Verdict::Groutable => String::new(),
        Verdict::Marginal => marginal_words(z, s),
        Verdict::NotGroutable => {
            let reasons = z.reasons();
            match &z.remedy {
                Some(r) if reasons.is_empty() => remedy_short(r),
                Some(r) => format!("{reasons} — {}", remedy_short(r)),
                None => reasons,
            }
        }
    }
}

/// The caution a plan computed with opt-in approximations carries (None on
/// the exact path): their keys, and that a zone near a limit is decided on
/// an exact run (on the large arch the five together moved deciding
/// apertures by up to 0.39 mm and changed remedies near 0.5 mm).
pub fn approximations_caution(approximations: &[Approximation]) -> Option<String> {
    (!approximations.is_empty()).then(|| {
        format!(
            "Computed with opt-in approximations of the mechanics ({}): the apertures differ from \
             the exact path's (measure by how much with `groutready study compare`); decide a zone \
             near a limit, and its remedy, on a run without them (`--exact`).",
            crate::scene::approximation::describe(approximations)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::{ChosenTogether, DelayOption, SupercoolOption};
    use crate::vocab::ZoneId;

    fn remedy(choice: RemedyChoice) -> Remedy {
        Remedy {
            supercool: Some(SupercoolOption {
                delta_c: 1.25,
                aperture_mm: 0.6234,
                together: None,
            }),
            delay: Some(DelayOption {
                days: 12,
                date: "2024-10-03".parse().unwrap(),
                aperture_mm: 0.551,
                also_delayed: vec![],
            }),
            choice,
            verified: Some((Verdict::Marginal, Some(0.6))),
            note: String::new(),
            verified_history: None,
            limited: Vec::new(),
        }
    }

    #[test]
    fn remedies_in_words() {
        assert_eq!(
            remedy_short(&remedy(RemedyChoice::Supercool)),
            "supercool 1.25 °C → 0.62 mm"
        );
        assert_eq!(
            remedy_short(&remedy(RemedyChoice::Delay)),
            "delay 12 d → 2024-10-03, 0.55 mm"
        );
        assert_eq!(remedy_short(&remedy(RemedyChoice::None)), "no remedy found");
        assert_eq!(
            verified_words(&remedy(RemedyChoice::None)).unwrap(),
            "verified marginal, 0.60 mm"
        );
    }

    /// A zone chosen together with its neighbours at no supercooling of its
    /// own (the demo's joint 7 zone 4) is not offered "supercool 0.00 °C";
    /// one with a supercooling of its own in the set keeps its figure.
    #[test]
    fn a_zone_its_neighbours_supercool_says_so() {
        let together = |delta_c: f64| {
            let mut r = remedy(RemedyChoice::Supercool);
            let o = r.supercool.as_mut().unwrap();
            o.delta_c = delta_c;
            o.together = Some(ChosenTogether {
                with: vec![ZoneId::new(6, 4)],
                zone_by_zone_c: 0.25,
                set_c: 0.5,
                set_zone_by_zone_c: 0.75,
                zone_by_zone_held: true,
            });
            r
        };
        let r = together(0.0);
        assert_eq!(
            remedy_short(&r),
            "none of its own: its neighbours' supercooling → 0.62 mm"
        );
        assert_eq!(remedy_brief(&r), "neighbours' supercooling");
        let r = together(0.25);
        assert_eq!(remedy_short(&r), "supercool 0.25 °C → 0.62 mm");
        assert_eq!(remedy_brief(&r), "supercool 0.25 °C");
        // Alone (not chosen together) a zero supercooling is no special case.
        let mut r = remedy(RemedyChoice::Supercool);
        r.supercool.as_mut().unwrap().delta_c = 0.0;
        assert_eq!(remedy_short(&r), "supercool 0.00 °C → 0.62 mm");
    }
}
