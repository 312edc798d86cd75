//! A plausible construction schedule for a dam layout (demo scenes, tests).
//!
//! The rules follow common Chinese arch-dam practice (Xiaowan, Xiluodu,
//! Ertan: "three phases" of pipe cooling):
//!
//! - **Pouring.** Every block rises lift by lift, one lift every
//!   `lift_interval_days`. All blocks share the crest, so a block with fewer
//!   lifts stands on a higher foundation; global layer *L* (counted from the
//!   lowest foundation) is reached in every block at about the same time,
//!   which keeps adjacent blocks within a lift or two of each other. The
//!   deepest (valley) blocks therefore start first, the bank blocks later, and
//!   blocks further from the centre of the block row are delayed by
//!   `block_stagger_days` per block.
//! - **Placement temperature** follows the season with pre-cooling: cooler
//!   in summer (stricter limit, chilled aggregate and ice), warmer in winter:
//!   `mean − amplitude · cos(2π (day_of_year − warmest_day) / 365.25)`,
//!   rounded to 0.1 °C.
//! - **First stage** on every lift from its pour date for `first_days`,
//!   water `first_water_c`, target `first_target_c` (peak control and cooling
//!   to ≈ 20 °C).
//! - **Middle stage** from the end of the first stage to the start of the
//!   second (holding ≈ 18 °C with `middle_water_c` water); without a second
//!   stage it has no end date and stops at its target. When it would last
//!   less than `min_middle_days`, the second stage starts right after the
//!   first instead.
//! - **Second stage** down to the closure (grouting) temperature with
//!   `second_water_c` water. The lifts of zone *k* of a block start
//!   `second_lead_days` before the earlier of (a) zone *k*'s first grouting on
//!   either joint of the block and (b) the grouting of zone *k − 1* (the
//!   cooled region extends one zone above the zone being grouted), but not
//!   before their first stage has ended; the stage ends at the last grouting
//!   of zone *k* on the block's joints (or at the target).
//! - **Grouting**, per joint bottom-up: zone *k* is grouted once both blocks
//!   are poured `cover_zones` zone heights above the zone's top (or to their
//!   top lift), its youngest lift is `min_grout_age_days` old, and at least
//!   `zone_gap_days` after zone *k − 1* of the same joint.

use std::collections::{BTreeMap, HashMap};

use chrono::{Datelike, Days, NaiveDate};

use super::layout::DamLayout;
use super::{CoolingStage, GroutingPlan, Pour, Schedules, Stage};

/// Parameters of [`synthesize`]. `Default` gives a typical high arch dam.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Date of the first pour (lift 1 of the deepest, most central block).
    /// Default 2025-11-01 (start of a dry season).
    pub start: NaiveDate,
    /// Days between successive lifts of a block (values < 1 are taken as 1).
    /// Default 8.
    pub lift_interval_days: u32,
    /// Extra delay per block of distance from the centre of the block row.
    /// Default 2.
    pub block_stagger_days: u32,
    /// Mean placement temperature, °C. Default 15.
    pub placement_mean_c: f64,
    /// Seasonal half-range of the placement temperature, °C; the coolest
    /// placement is on `warmest_day_of_year`. Default 3 (12–18 °C).
    pub placement_amplitude_c: f64,
    /// Day of the year (1–366) of the warmest weather. Default 200 (mid-July).
    pub warmest_day_of_year: u32,
    /// Length of the first cooling stage, days. Default 21.
    pub first_days: u32,
    /// First-stage water temperature, °C. Default 10.
    pub first_water_c: f64,
    /// First-stage target, °C (`None`: ends by date only). Default 20.
    pub first_target_c: Option<f64>,
    /// A middle stage shorter than this is not scheduled: the second stage
    /// then follows the first directly. Default 10.
    pub min_middle_days: u32,
    /// Middle-stage water temperature, °C. Default 15.
    pub middle_water_c: f64,
    /// Middle-stage target, °C. Default 18.
    pub middle_target_c: f64,
    /// Second-stage water temperature, °C. Default 8.
    pub second_water_c: f64,
    /// Closure (grouting) temperature = second-stage target, °C. Default 12.5.
    pub closure_temp_c: f64,
    /// Days the second stage starts before the grouting it prepares. Default 50.
    pub second_lead_days: u32,
    /// Concrete cover required above a zone before grouting, in zone heights
    /// (rounded up to whole lifts, capped at the block's top). Default 1.5.
    pub cover_zones: f64,
    /// Minimum age of a zone's youngest lift at grouting, days. Default 90.
    pub min_grout_age_days: u32,
    /// Minimum days between two successive zones of one joint. Default 7.
    pub zone_gap_days: u32,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            start: NaiveDate::from_ymd_opt(2025, 11, 1).unwrap_or_default(),
            lift_interval_days: 8,
            block_stagger_days: 2,
            placement_mean_c: 15.0,
            placement_amplitude_c: 3.0,
            warmest_day_of_year: 200,
            first_days: 21,
            first_water_c: 10.0,
            first_target_c: Some(20.0),
            min_middle_days: 10,
            middle_water_c: 15.0,
            middle_target_c: 18.0,
            second_water_c: 8.0,
            closure_temp_c: 12.5,
            second_lead_days: 50,
            cover_zones: 1.5,
            min_grout_age_days: 90,
            zone_gap_days: 7,
        }
    }
}

/// A block's part of one zone: first lift, last lift, joints it is grouted on.
type BlockZone = (u32, u32, Vec<u32>);

fn add_days(d: NaiveDate, n: i64) -> NaiveDate {
    let r = if n >= 0 {
        d.checked_add_days(Days::new(n as u64))
    } else {
        d.checked_sub_days(Days::new(n.unsigned_abs()))
    };
    r.unwrap_or(if n >= 0 {
        NaiveDate::MAX
    } else {
        NaiveDate::MIN
    })
}

fn placement_temp(p: &SynthParams, date: NaiveDate) -> f64 {
    let phase = (date.ordinal() as f64 - p.warmest_day_of_year as f64) / 365.25;
    let t =
        p.placement_mean_c - p.placement_amplitude_c * (2.0 * std::f64::consts::PI * phase).cos();
    ((t * 10.0).round() / 10.0).clamp(0.0, 40.0)
}

/// Builds a construction schedule (pours, cooling, grouting) for `layout`.
///
/// Lift ranges of the grouting zones come from `layout.zones`. The result has
/// `dir` empty, no weather/reservoir/meters, rows sorted by date, and `line`
/// fields numbered as [`super::write_dir`] writes them (first row = line 2).
/// With sensible parameters (targets above water temperatures) it passes
/// [`super::validate`] and [`super::check_against`]`(_, layout)`; the
/// parameters themselves are not checked.
pub fn synthesize(layout: &DamLayout, params: &SynthParams) -> Schedules {
    let mut blocks: Vec<(u32, u32)> = layout.blocks.clone();
    blocks.sort();
    blocks.dedup_by_key(|b| b.0);
    let (mut pours, pour_date) = pours(params, &blocks);
    let (mut grouting, grout) = grouting(params, layout, &blocks, &pour_date);
    let dates = Dates {
        p: params,
        pour: pour_date,
        block_zones: block_zones(layout, &grout),
        grout,
    };
    let mut cooling = dates.cooling(&blocks);

    pours.sort_by_key(|r| (r.date, r.block, r.lift));
    cooling.sort_by_key(|c| (c.start, c.block, c.lift_from, c.stage));
    grouting.sort_by_key(|g| (g.planned, g.joint, g.zone));
    for (i, r) in pours.iter_mut().enumerate() {
        r.line = i + 2;
    }
    for (i, r) in cooling.iter_mut().enumerate() {
        r.line = i + 2;
    }
    for (i, r) in grouting.iter_mut().enumerate() {
        r.line = i + 2;
    }
    Schedules {
        dir: Default::default(),
        pours,
        cooling,
        grouting,
        weather: None,
        reservoir: None,
        joint_meters: None,
    }
}

/// Pour date of (block, lift).
type DateOf = HashMap<(u32, u32), NaiveDate>;

/// Every lift of every block (sorted `(block, n_lifts)`), one lift per
/// interval; a block starts as many intervals late as it has lifts fewer than
/// the tallest, plus the stagger of its distance from the centre of the row.
fn pours(p: &SynthParams, blocks: &[(u32, u32)]) -> (Vec<Pour>, DateOf) {
    let interval = p.lift_interval_days.max(1) as i64;
    let n_max = blocks.iter().map(|b| b.1).max().unwrap_or(0);
    let centre = match (blocks.first(), blocks.last()) {
        (Some(a), Some(b)) => (a.0 as f64 + b.0 as f64) / 2.0,
        _ => 0.0,
    };
    let mut pour_date: DateOf = HashMap::new();
    let mut pours = Vec::new();
    for &(block, n) in blocks {
        let base = (n_max - n) as i64;
        let offset = (p.block_stagger_days as f64 * (block as f64 - centre).abs()).round() as i64;
        for lift in 1..=n {
            let date = add_days(p.start, (base + lift as i64 - 1) * interval + offset);
            pour_date.insert((block, lift), date);
            pours.push(Pour {
                block,
                lift,
                date,
                placement_temp_c: placement_temp(p, date),
                line: 0,
            });
        }
    }
    (pours, pour_date)
}

/// Grouting per joint bottom-up: each zone on the first day both blocks
/// cover it, its youngest lift is old enough and the zone below is
/// `zone_gap_days` behind. Returns the rows and the date of (joint, zone).
fn grouting(
    p: &SynthParams,
    layout: &DamLayout,
    blocks: &[(u32, u32)],
    pour_date: &DateOf,
) -> (Vec<GroutingPlan>, DateOf) {
    let n_lifts: HashMap<u32, u32> = blocks.iter().copied().collect();
    let poured = |block: u32, lift: u32| pour_date.get(&(block, lift)).copied();
    let mut by_joint: BTreeMap<u32, Vec<&super::ZoneExtent>> = BTreeMap::new();
    for z in &layout.zones {
        by_joint.entry(z.joint).or_default().push(z);
    }
    let mut grout: DateOf = HashMap::new();
    let mut grouting = Vec::new();
    for (joint, mut zones) in by_joint {
        zones.sort_by_key(|z| z.zone);
        let mut prev: Option<NaiveDate> = None;
        for z in zones {
            let mut date = prev.map(|d| add_days(d, p.zone_gap_days.max(1) as i64));
            let mut later = |d: Option<NaiveDate>| {
                if let Some(d) = d {
                    date = Some(date.map_or(d, |x| x.max(d)));
                }
            };
            for (block, first, last) in z.sides() {
                let top = n_lifts.get(&block).copied().unwrap_or(last).max(last);
                let height = (last.saturating_sub(first) + 1) as f64;
                let cover = (p.cover_zones.max(0.0) * height).ceil() as u32;
                let cover_lift = last.saturating_add(cover).min(top);
                later(poured(block, cover_lift).map(|d| add_days(d, 1)));
                later(poured(block, last).map(|d| add_days(d, p.min_grout_age_days as i64)));
                later(poured(block, last).map(|d| add_days(d, 1)));
            }
            let Some(date) = date else { continue };
            grout.insert((joint, z.zone), date);
            prev = Some(date);
            grouting.push(GroutingPlan {
                joint,
                zone: z.zone,
                planned: date,
                done: false,
                line: 0,
            });
        }
    }
    (grouting, grout)
}

/// Per block: zone → (first, last) lift and the joints it is grouted on
/// (zones that got a grouting date only).
fn block_zones(layout: &DamLayout, grout: &DateOf) -> HashMap<u32, BTreeMap<u32, BlockZone>> {
    let mut block_zones: HashMap<u32, BTreeMap<u32, BlockZone>> = HashMap::new();
    for z in &layout.zones {
        if !grout.contains_key(&(z.joint, z.zone)) {
            continue;
        }
        for (block, first, last) in z.sides() {
            let e = block_zones
                .entry(block)
                .or_default()
                .entry(z.zone)
                .or_insert((first, last, Vec::new()));
            e.0 = e.0.min(first);
            e.1 = e.1.max(last);
            e.2.push(z.joint);
        }
    }
    block_zones
}

/// The dates the cooling stages are timed by.
struct Dates<'a> {
    p: &'a SynthParams,
    pour: DateOf,
    /// Grouting date of (joint, zone).
    grout: DateOf,
    block_zones: HashMap<u32, BTreeMap<u32, BlockZone>>,
}

impl Dates<'_> {
    /// Every lift's first stage, then its middle and second stages, those of
    /// adjacent lifts with the same dates merged into one row.
    fn cooling(&self, blocks: &[(u32, u32)]) -> Vec<CoolingStage> {
        let p = self.p;
        let mut cooling: Vec<CoolingStage> = Vec::new();
        let mut later_stages: Vec<CoolingStage> = Vec::new();
        for &(block, n) in blocks {
            for lift in 1..=n {
                let Some(pd) = self.pour.get(&(block, lift)).copied() else {
                    continue;
                };
                let first_end = add_days(pd, p.first_days.max(1) as i64);
                let one_lift = |stage, start, end, water_temp_c, target_temp_c| CoolingStage {
                    block,
                    lift_from: lift,
                    lift_to: lift,
                    stage,
                    start,
                    end,
                    water_temp_c,
                    target_temp_c,
                    line: 0,
                };
                cooling.push(one_lift(
                    Stage::First,
                    pd,
                    Some(first_end),
                    p.first_water_c,
                    p.first_target_c,
                ));
                let middle = |end| {
                    let target = Some(p.middle_target_c);
                    one_lift(Stage::Middle, first_end, end, p.middle_water_c, target)
                };
                match self.second_stage(block, lift, first_end) {
                    Some((s2, e2)) => {
                        if s2 > first_end {
                            later_stages.push(middle(Some(s2)));
                        }
                        let target = Some(p.closure_temp_c);
                        later_stages.push(one_lift(
                            Stage::Second,
                            s2,
                            Some(e2),
                            p.second_water_c,
                            target,
                        ));
                    }
                    None => later_stages.push(middle(None)),
                }
            }
        }
        cooling.extend(merge_adjacent_lifts(later_stages));
        cooling
    }

    /// The second stage of `lift` of `block`: from `second_lead_days` before
    /// the first grouting of its zone or of the zone below (not before the
    /// first stage ends at `first_end`, and right after it when the middle
    /// stage would be shorter than `min_middle_days`) to the last grouting of
    /// its zone. `None` when the lift is in no grouted zone.
    fn second_stage(
        &self,
        block: u32,
        lift: u32,
        first_end: NaiveDate,
    ) -> Option<(NaiveDate, NaiveDate)> {
        let p = self.p;
        let zones = self.block_zones.get(&block)?;
        let dates_of = |zone: u32| -> Vec<NaiveDate> {
            zones
                .get(&zone)
                .map(|e| {
                    e.2.iter()
                        .filter_map(|j| self.grout.get(&(*j, zone)).copied())
                        .collect()
                })
                .unwrap_or_default()
        };
        let k = zones
            .iter()
            .find(|(_, e)| e.0 <= lift && lift <= e.1)
            .map(|(k, _)| *k)?;
        let own = dates_of(k);
        let below = zones
            .range(..k)
            .next_back()
            .map(|(kb, _)| dates_of(*kb))
            .unwrap_or_default();
        let need = own.iter().chain(below.iter()).min().copied()?;
        let end = own.iter().max().copied()?;
        let mut start = add_days(need, -(p.second_lead_days as i64)).max(first_end);
        if start < add_days(first_end, p.min_middle_days as i64) {
            start = first_end;
        }
        (end > start).then_some((start, end))
    }
}

/// Middle/second stages of adjacent lifts of a block with the same dates
/// become one row.
fn merge_adjacent_lifts(mut stages: Vec<CoolingStage>) -> Vec<CoolingStage> {
    stages.sort_by_key(|c| (c.block, c.stage, c.start, c.end, c.lift_from));
    let mut merged: Vec<CoolingStage> = Vec::new();
    for c in stages {
        if let Some(m) = merged.last_mut() {
            if m.block == c.block
                && m.stage == c.stage
                && m.start == c.start
                && m.end == c.end
                && m.lift_to + 1 == c.lift_from
            {
                m.lift_to = c.lift_to;
                continue;
            }
        }
        merged.push(c);
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schedule::{check_against, validate, ZoneExtent};

    /// A valley: `n_lifts` per block (1-based, left bank first), common crest,
    /// zones of `zl` lifts as global bands (foundations on zone boundaries).
    fn valley(n_lifts: &[u32], zl: u32) -> DamLayout {
        let n_max = *n_lifts.iter().max().unwrap();
        let blocks: Vec<(u32, u32)> = n_lifts
            .iter()
            .enumerate()
            .map(|(i, &n)| (i as u32 + 1, n))
            .collect();
        let base = |b: u32| n_max - blocks[b as usize - 1].1;
        let mut zones = Vec::new();
        for j in 1..blocks.len() as u32 {
            let lo = base(j).max(base(j + 1));
            let mut layer = lo;
            while layer < n_max {
                let zone = layer / zl + 1;
                let top = (zone * zl).min(n_max);
                let side = |b: u32| (b, layer - base(b) + 1, top - base(b));
                zones.push(ZoneExtent {
                    joint: j,
                    zone,
                    lifts_a: side(j),
                    lifts_b: side(j + 1),
                });
                layer = top;
            }
        }
        DamLayout { blocks, zones }
    }

    fn demo() -> DamLayout {
        // 12 blocks, 150 m high with 3 m lifts, 9 m zones; top zone partial.
        valley(&[20, 29, 38, 44, 50, 50, 50, 50, 44, 38, 29, 20], 3)
    }

    #[test]
    fn valley_layout_is_valid() {
        let l = demo();
        l.validate().unwrap();
        assert_eq!(l.zones_of(6).len(), 17);
        assert_eq!(l.zones_of(1).first(), Some(&11)); // bank joint starts higher
    }

    #[test]
    fn demo_schedule_is_valid_and_realistic() {
        let l = demo();
        let p = SynthParams::default();
        let s = synthesize(&l, &p);
        validate(&s).unwrap();
        check_against(&s, &l).unwrap();
        assert_eq!(
            s.pours.len(),
            l.blocks.iter().map(|b| b.1 as usize).sum::<usize>()
        );
        assert_eq!(s.grouting.len(), l.zones.len());

        // Central blocks first, banks later.
        let first_pour = |b: u32| s.pour(b, 1).unwrap().date;
        let earliest = (1..=12).map(first_pour).min().unwrap();
        assert_eq!(first_pour(6), earliest);
        assert_eq!(first_pour(7), earliest);
        assert!(earliest <= p.start + Days::new(2));
        assert!(first_pour(6) < first_pour(3) && first_pour(3) < first_pour(1));
        assert!(first_pour(7) < first_pour(12));

        // Seasonal placement temperature, cooler in summer.
        for q in &s.pours {
            assert!((12.0..=18.0).contains(&q.placement_temp_c), "{q:?}");
            if q.date.month() == 7 {
                assert!(q.placement_temp_c < 12.5, "{q:?}");
            }
            if q.date.month() == 1 {
                assert!(q.placement_temp_c > 17.5, "{q:?}");
            }
        }

        // Every lift has a first stage from its pour date.
        for q in &s.pours {
            let c = s
                .cooling
                .iter()
                .find(|c| c.stage == Stage::First && c.covers(q.block, q.lift))
                .unwrap();
            assert_eq!(c.start, q.date);
            assert_eq!(c.end, Some(add_days(q.date, 21)));
        }

        // Grouting: bottom-up, old enough, covered, every zone's lifts in
        // second-stage cooling right before the grouting date.
        for z in &l.zones {
            let g = s.grouting_of(z.zone_id()).unwrap().planned;
            if let Some(below) =
                s.grouting_of(crate::vocab::ZoneId::new(z.joint, z.zone.saturating_sub(1)))
            {
                assert!(below.planned + Days::new(7) <= g);
            }
            for (b, first, last) in z.sides() {
                let youngest = s.pour(b, last).unwrap().date;
                assert!(youngest + Days::new(90) <= g);
                let n = l.n_lifts(b).unwrap();
                let cover = (last + 5).min(n); // ceil(1.5 × 3) = 5 lifts
                assert!(s.pour(b, cover).unwrap().date < g);
                for lift in first..=last {
                    let day_before = g - Days::new(1);
                    let c = s
                        .cooling
                        .iter()
                        .find(|c| {
                            c.covers(b, lift)
                                && c.start <= day_before
                                && c.end.is_none_or(|e| day_before < e)
                        })
                        .unwrap_or_else(|| panic!("no stage on block {b} lift {lift} before {g}"));
                    assert_eq!(c.stage, Stage::Second);
                    assert_eq!(c.target_temp_c, Some(12.5));
                    assert!(
                        c.start <= g - Days::new(45)
                            || c.start == add_days(s.pour(b, lift).unwrap().date, 21)
                    );
                }
            }
        }

        // 50 lifts at 8 days plus ~90 days to the last grouting.
        let (a, b) = s.event_span().unwrap();
        let days = (b - a).num_days();
        assert!((450..=600).contains(&days), "{days} days");
    }

    #[test]
    fn single_block_without_joints() {
        let l = DamLayout {
            blocks: vec![(1, 4)],
            zones: vec![],
        };
        let s = synthesize(&l, &SynthParams::default());
        validate(&s).unwrap();
        check_against(&s, &l).unwrap();
        assert!(s.grouting.is_empty());
        // first stage per lift + one open-ended middle stage for all lifts
        assert_eq!(s.cooling.len(), 4 + 4);
        assert!(s
            .cooling
            .iter()
            .any(|c| c.stage == Stage::Middle && c.end.is_none()));
    }

    #[test]
    fn empty_layout() {
        let s = synthesize(&DamLayout::default(), &SynthParams::default());
        assert!(s.pours.is_empty() && s.cooling.is_empty() && s.grouting.is_empty());
    }
}
