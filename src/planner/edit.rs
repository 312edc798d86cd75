//! Schedule edits a remedy makes, and the first date two schedules differ
//! (where a re-simulation may restart).

use std::collections::BTreeMap;

use chrono::NaiveDate;

use crate::schedule::{CoolingStage, DamLayout, Schedules};
use crate::vocab::ZoneId;

/// Supercooling of one zone: colder water and a lower target for the cooling
/// stage that brings its lifts (and the lifts `lifts_above` higher) to
/// closure, from `from` (the as-of date: the past cannot be re-cooled) until
/// the zone's grouting date.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Supercool {
    pub zone: ZoneId,
    pub delta_c: f64,
    pub planned: NaiveDate,
    pub from: NaiveDate,
}

/// The lifts a zone's supercooling cools.
fn cooled_lifts(layout: &DamLayout, z: &Supercool, lifts_above: u32) -> Vec<(u32, u32)> {
    let Some(ext) = layout.zone(z.zone) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (block, from, to) in ext.sides() {
        let n = layout.n_lifts(block).unwrap_or(to);
        for lift in from..=(to + lifts_above).min(n) {
            out.push((block, lift));
        }
    }
    out
}

/// Index of the stage to supercool on (block, lift): the latest-starting
/// stage with a target that starts before `before`.
fn stage_to_edit(
    cooling: &[CoolingStage],
    block: u32,
    lift: u32,
    before: NaiveDate,
) -> Option<usize> {
    cooling
        .iter()
        .enumerate()
        .filter(|(_, c)| c.covers(block, lift) && c.start < before && c.target_temp_c.is_some())
        .max_by_key(|(i, c)| (c.start, *i))
        .map(|(i, _)| i)
}

/// The coldest cooling water a site's chillers deliver [°C], unless the
/// scene says otherwise (`planner.min_water_temp_c`).
pub const MIN_WATER_C: f64 = 4.0;

/// [`supercool_with_water`] with the default coldest water, [`MIN_WATER_C`].
pub fn supercool(
    schedules: &Schedules,
    layout: &DamLayout,
    zones: &[Supercool],
    lifts_above: u32,
) -> (Schedules, Vec<ZoneId>) {
    supercool_with_water(schedules, layout, zones, lifts_above, MIN_WATER_C)
}

/// Whether a zone's supercooling meets the coldest water allowed: the
/// water of one of the stages it edits cannot be lowered by its full ΔT.
pub fn water_held(
    schedules: &Schedules,
    layout: &DamLayout,
    z: &Supercool,
    lifts_above: u32,
    coldest_c: f64,
) -> bool {
    cooled_lifts(layout, z, lifts_above)
        .into_iter()
        .any(|(b, l)| {
            stage_to_edit(&schedules.cooling, b, l, z.planned)
                .is_some_and(|row| schedules.cooling[row].water_temp_c - z.delta_c < coldest_c)
        })
}

/// Applies supercooling to `schedules`. A stage row serving several zones
/// takes the largest ΔT and the latest of their grouting dates; rows are
/// edited whole (their cooled region stays what the site planned). The
/// target is lower by ΔT, and the water colder by ΔT, at least 1 °C below
/// the new target, but never colder than `coldest_c` (nor warmer than it
/// was: a site already below that limit keeps its water). The past is not
/// re-cooled:
/// - a stage starting on or after `from` is edited in place and runs until
///   its new target or the grouting date;
/// - a stage that ends (by its end date) before the grouting date is followed
///   by an `extra` stage from its end, or from `from` if it ended earlier, to
///   the grouting date;
/// - a stage that started before `from` and runs past the grouting date is
///   split at `from`: its row ends there, and a row continuing it carries
///   the colder water and lower target (the stage's clock is kept: Zhu's
///   superposition, see `schedule`'s cooling rows), to the later of its end
///   and the grouting date.
///
/// Returns the edited schedules and the zones none of whose lifts could be
/// edited.
pub fn supercool_with_water(
    schedules: &Schedules,
    layout: &DamLayout,
    zones: &[Supercool],
    lifts_above: u32,
    coldest_c: f64,
) -> (Schedules, Vec<ZoneId>) {
    // row → (ΔT, latest grouting date, from)
    let mut per_row: BTreeMap<usize, (f64, NaiveDate, NaiveDate)> = BTreeMap::new();
    let mut not_editable = Vec::new();
    for z in zones.iter().filter(|z| z.delta_c > 0.0) {
        let mut any = false;
        for (block, lift) in cooled_lifts(layout, z, lifts_above) {
            let Some(row) = stage_to_edit(&schedules.cooling, block, lift, z.planned) else {
                continue;
            };
            any = true;
            let e = per_row.entry(row).or_insert((0.0, z.planned, z.from));
            e.0 = e.0.max(z.delta_c);
            e.1 = e.1.max(z.planned);
            e.2 = e.2.min(z.from);
        }
        if !any {
            not_editable.push(z.zone);
        }
    }
    let mut out = schedules.clone();
    let mut extra = Vec::new();
    for (&row, &(dt, until, from)) in &per_row {
        let c = &mut out.cooling[row];
        let target = c.target_temp_c.unwrap_or(0.0) - dt;
        let water = (c.water_temp_c - dt)
            .min(target - 1.0)
            .max(coldest_c.min(c.water_temp_c))
            .max(0.0);
        if c.start >= from {
            c.target_temp_c = Some(target);
            c.water_temp_c = water;
            c.end = c.end.map(|end| end.max(until));
        } else if let Some(end) = c.end.filter(|&e| e < until) {
            let start = end.max(from);
            if start < until {
                extra.push(CoolingStage {
                    stage: crate::schedule::Stage::Extra,
                    start,
                    end: Some(until),
                    water_temp_c: water,
                    target_temp_c: Some(target),
                    ..c.clone()
                });
            }
        } else {
            // Running past the grouting date: colder water from `from`.
            let rest = CoolingStage {
                start: from,
                end: c.end.map(|e| e.max(until)),
                water_temp_c: water,
                target_temp_c: Some(target),
                ..c.clone()
            };
            c.end = Some(from);
            extra.push(rest);
        }
    }
    out.cooling.extend(extra);
    (out, not_editable)
}

type StageKey = (u32, u32, u32, u8, NaiveDate);

/// A stage over time: from each of its rows' start, the water and target
/// bits in effect; and its end.
#[derive(PartialEq)]
struct Profile {
    steps: Vec<(NaiveDate, u64, Option<u64>)>,
    end: Option<NaiveDate>,
}

fn stage_profiles(s: &Schedules) -> BTreeMap<StageKey, Profile> {
    let rows = &s.cooling;
    crate::schedule::cooling_chains(rows)
        .into_iter()
        .map(|chain| {
            let head = &rows[chain[0]];
            let key = (
                head.block,
                head.lift_from,
                head.lift_to,
                head.stage as u8,
                head.start,
            );
            let steps = chain
                .iter()
                .map(|&r| {
                    let c = &rows[r];
                    (
                        c.start,
                        c.water_temp_c.to_bits(),
                        c.target_temp_c.map(f64::to_bits),
                    )
                })
                .collect();
            let end = rows[chain[chain.len() - 1]].end;
            (key, Profile { steps, end })
        })
        .collect()
}

/// The first date two profiles of one stage differ: where the water or
/// target in effect first differs, or the earlier end when the ends differ
/// (the stage runs alike until then).
fn profile_change(a: &Profile, b: &Profile) -> Option<NaiveDate> {
    let in_effect =
        |p: &Profile, d: NaiveDate| p.steps.iter().rev().find(|s| s.0 <= d).map(|s| (s.1, s.2));
    let mut dates: Vec<NaiveDate> = a.steps.iter().chain(&b.steps).map(|s| s.0).collect();
    dates.sort();
    let mut first = dates
        .into_iter()
        .find(|&d| in_effect(a, d) != in_effect(b, d));
    if a.end != b.end {
        // one of them is a date (a missing end never ends)
        let end = a.end.into_iter().chain(b.end).min();
        first = first.into_iter().chain(end).min();
    }
    first
}

/// Moves the grouting of zones to new dates.
pub fn regrout(schedules: &Schedules, moves: &[(ZoneId, NaiveDate)]) -> Schedules {
    let mut out = schedules.clone();
    for g in &mut out.grouting {
        if let Some(m) = moves.iter().find(|m| m.0 == g.zone_id()) {
            g.planned = m.1;
        }
    }
    out
}

/// Drops the grouting of zones (for the delay search).
pub fn ungrout(schedules: &Schedules, zones: &[ZoneId]) -> Schedules {
    let mut out = schedules.clone();
    out.grouting.retain(|g| !zones.contains(&g.zone_id()));
    out
}

/// The first date on which a simulation of `b` may differ from one of `a`
/// (None: the same events). Pours and grouting: the earlier of the two dates
/// of a changed row. Cooling: the start of a changed stage, or the earlier end
/// when only the end moved. Weather and reservoir: the date before the first
/// differing row (levels are interpolated between rows).
pub fn first_change(a: &Schedules, b: &Schedules) -> Option<NaiveDate> {
    let mut first: Option<NaiveDate> = None;
    let mut at = |d: NaiveDate| first = Some(first.map_or(d, |f| f.min(d)));

    let pours = |s: &Schedules| -> BTreeMap<(u32, u32), (NaiveDate, u64)> {
        s.pours
            .iter()
            .map(|p| ((p.block, p.lift), (p.date, p.placement_temp_c.to_bits())))
            .collect()
    };
    diff_maps(&pours(a), &pours(b), |x| x.0, &mut at);

    let grout = |s: &Schedules| -> BTreeMap<ZoneId, NaiveDate> {
        s.grouting
            .iter()
            .map(|g| (g.zone_id(), g.planned))
            .collect()
    };
    diff_maps(&grout(a), &grout(b), |x| *x, &mut at);

    // A stage is its first row's block, lifts, kind and start; its water,
    // targets and end may change, inside it too (rows continuing it).
    let (sa, sb) = (stage_profiles(a), stage_profiles(b));
    for (k, pa) in &sa {
        match sb.get(k) {
            None => at(k.4),
            Some(pb) => {
                if let Some(d) = profile_change(pa, pb) {
                    at(d.max(k.4));
                }
            }
        }
    }
    for k in sb.keys().filter(|k| !sa.contains_key(k)) {
        at(k.4);
    }

    for (x, y) in [(&a.weather, &b.weather), (&a.reservoir, &b.reservoir)] {
        let (x, y) = (x.as_deref().unwrap_or(&[]), y.as_deref().unwrap_or(&[]));
        let n = x.len().min(y.len());
        let differ = (0..n).find(|&i| x[i].0 != y[i].0 || x[i].1.to_bits() != y[i].1.to_bits());
        let i = match differ {
            Some(i) => Some(i),
            None if x.len() != y.len() => Some(n),
            None => None,
        };
        if let Some(i) = i {
            // The segment before the first differing row is interpolated
            // towards it already.
            let d = if i == 0 {
                [x.first(), y.first()]
                    .into_iter()
                    .flatten()
                    .map(|r| r.0)
                    .min()
            } else {
                Some(x[i - 1].0)
            };
            if let Some(d) = d {
                at(d);
            }
        }
    }
    first
}

fn diff_maps<K: Ord, V: PartialEq>(
    a: &BTreeMap<K, V>,
    b: &BTreeMap<K, V>,
    date: impl Fn(&V) -> NaiveDate,
    at: &mut impl FnMut(NaiveDate),
) {
    for (k, va) in a {
        match b.get(k) {
            Some(vb) if vb == va => {}
            Some(vb) => at(date(va).min(date(vb))),
            None => at(date(va)),
        }
    }
    for (k, vb) in b {
        if !a.contains_key(k) {
            at(date(vb));
        }
    }
}
