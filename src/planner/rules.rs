//! The readiness rules of one zone on one day, read from a run's histories.
//!
//! Aperture: the deciding point's aperture (zone minimum by default) on the
//! day. Temperature: the capacity-weighted mean temperature of the zone's
//! lifts in each of the two blocks, against the closure temperature at the
//! zone's mid-height plus the tolerance. Age: the youngest lift of the zone
//! (both blocks) on the day. Cover: the concrete poured above the zone's top
//! on each block that is not yet complete. Bottom-up: the next lower zone of
//! the same joint is grouted on or before the day.

use std::collections::HashMap;

use crate::scene::PlannerSettings;
use crate::schedule::{DamLayout, Schedules, ZoneExtent};
use crate::sim::{History, JointSample};
use crate::vocab::{Day, Epoch, JointState, ZoneId, ZonePoint};

use super::readiness::{Apertures, Rule, RuleCheck, Verdict, ZoneReadiness};

/// What the rules need besides a run's histories: the schedules as run, the
/// dam's zones and the settings.
pub struct Rules<'a> {
    pub settings: &'a PlannerSettings,
    pub layout: &'a DamLayout,
    pub epoch: Epoch,
    pub lift_height: f64,
    /// (block) → (foundation elevation, number of lifts)
    pub blocks: HashMap<u32, (f64, u32)>,
    /// zone → (z_bottom, z_top)
    pub zone_z: HashMap<ZoneId, (f64, f64)>,
    /// (block, lift) → pour day
    pour_day: HashMap<(u32, u32), Day>,
}

/// Column indices of one zone in a [`History`].
#[derive(Debug, Clone, Copy, Default)]
struct ZoneColumns {
    /// the joint-record column of each point, in [`ZonePoint::ALL`] order
    points: [Option<usize>; 4],
    temps: Option<usize>,
}

impl ZoneColumns {
    fn at(&self, point: ZonePoint) -> Option<usize> {
        self.points[point as usize]
    }
}

/// Fast lookups into a [`History`].
pub struct HistoryIndex<'h> {
    pub history: &'h History,
    zones: HashMap<ZoneId, ZoneColumns>,
}

impl<'h> HistoryIndex<'h> {
    pub fn new(history: &'h History) -> HistoryIndex<'h> {
        let mut zones: HashMap<ZoneId, ZoneColumns> = HashMap::new();
        for (i, col) in history.joint_records.columns.iter().enumerate() {
            zones.entry(col.zone).or_default().points[col.point as usize] = Some(i);
        }
        for (i, z) in history.zone_temps.zones.iter().enumerate() {
            zones.entry(z.zone_id()).or_default().temps = Some(i);
        }
        HistoryIndex { history, zones }
    }

    fn joint_row(&self, day: Day) -> Option<usize> {
        let rows = &self.history.joint_records.rows;
        rows.binary_search_by(|r| r.0.cmp(&day)).ok()
    }

    /// Apertures of a zone on a recorded day \[mm\].
    pub fn apertures(&self, zone: ZoneId, day: Day) -> Apertures {
        let mm = |p| self.sample(zone, day, p).map(|s| s.aperture * 1e3);
        Apertures {
            upstream: mm(ZonePoint::Upstream),
            center: mm(ZonePoint::Center),
            downstream: mm(ZonePoint::Downstream),
            min: mm(ZonePoint::Min),
        }
    }

    /// The joint at one point of a zone on a recorded day.
    pub fn sample(&self, zone: ZoneId, day: Day, point: ZonePoint) -> Option<JointSample> {
        let i = self.zones.get(&zone)?.at(point)?;
        self.history.joint_records.rows[self.joint_row(day)?].1[i]
    }

    /// The first recorded day after `after` on which a point of the zone is
    /// labelled `reopened`.
    pub fn reopened_after(&self, zone: ZoneId, after: Day) -> Option<Day> {
        let c = self.zones.get(&zone)?;
        let cols: Vec<usize> = c.points.into_iter().flatten().collect();
        self.history
            .joint_records
            .rows
            .iter()
            .filter(|r| r.0 > after)
            .find(|r| {
                cols.iter()
                    .any(|&i| r.1[i].is_some_and(|s| s.state == JointState::Reopened))
            })
            .map(|r| r.0)
    }

    /// Mean temperature of the zone's concrete in blocks A and B on a
    /// recorded day (None where not all its lifts are poured, or no thermal model).
    pub fn block_temps(&self, zone: ZoneId, day: Day) -> [Option<f64>; 2] {
        let rows = &self.history.zone_temps.rows;
        let (Some(i), Ok(r)) = (
            self.zones.get(&zone).and_then(|c| c.temps),
            rows.binary_search_by(|r| r.0.cmp(&day)),
        ) else {
            return [None, None];
        };
        let t = rows[r].1[i];
        [t[0], t[1]].map(|v| v.is_finite().then_some(v))
    }

    /// Recorded days in `[from, to]`.
    pub fn days_between(&self, from: Day, to: Day) -> impl Iterator<Item = Day> + '_ {
        self.history
            .joint_records
            .rows
            .iter()
            .map(|r| r.0)
            .filter(move |&d| d >= from && d <= to)
    }
}

impl<'a> Rules<'a> {
    pub fn new(
        settings: &'a PlannerSettings,
        layout: &'a DamLayout,
        mesh: &crate::mesh::Mesh,
        epoch: Epoch,
        schedules: &Schedules,
    ) -> Rules<'a> {
        let mut rules = Rules {
            settings,
            layout,
            epoch,
            lift_height: mesh.lift_height,
            blocks: mesh
                .blocks
                .iter()
                .map(|b| (b.block, (b.foundation_z, b.n_lifts)))
                .collect(),
            zone_z: mesh
                .zones
                .iter()
                .map(|z| (z.zone_id(), (z.z_bottom, z.z_top)))
                .collect(),
            pour_day: HashMap::new(),
        };
        rules.set_pours(schedules);
        rules
    }

    fn set_pours(&mut self, schedules: &Schedules) {
        self.pour_day = schedules
            .pours
            .iter()
            .map(|p| ((p.block, p.lift), self.epoch.day(p.date)))
            .collect();
    }

    /// The deciding aperture of a zone on a day \[mm\].
    pub fn deciding_aperture(&self, h: &HistoryIndex, zone: ZoneId, day: Day) -> Option<f64> {
        h.apertures(zone, day).at(self.settings.aperture_point)
    }

    /// The next lower zone of the same joint that exists in the dam.
    pub fn zone_below(&self, zone: ZoneId) -> Option<ZoneId> {
        self.layout
            .zones
            .iter()
            .filter(|z| z.joint == zone.joint && z.zone < zone.zone)
            .map(|z| z.zone_id())
            .max()
    }

    /// Checks every rule for a zone grouted on `day`; `grout_day` gives the
    /// grouting day of every zone as planned in the run.
    pub fn evaluate(
        &self,
        h: &HistoryIndex,
        id: ZoneId,
        day: Day,
        grout_day: &HashMap<ZoneId, Day>,
    ) -> ZoneReadiness {
        let s = self.settings;
        let ext = self.layout.zone(id).copied();
        let (z_bottom, z_top) = self
            .zone_z
            .get(&id)
            .copied()
            .unwrap_or((f64::NAN, f64::NAN));
        let closure = s.closure_temp_at(0.5 * (z_bottom + z_top));
        let apertures = h.apertures(id, day);
        let a = apertures.at(s.aperture_point);

        let [ta, tb] = h.block_temps(id, day);
        let age = self.youngest_age(ext.as_ref(), day);
        let cover = self.cover_check(ext.as_ref(), z_top, day);
        let cover_m = cover.value;
        let checks = vec![
            self.aperture_check(h.sample(id, day, s.aperture_point)),
            self.temperature_check(h, ext.as_ref(), [ta, tb], closure),
            self.age_check(age),
            cover,
            self.bottom_up_check(id, day, grout_day),
        ];
        let groutable = checks.iter().all(|c| c.passed);
        let verdict = match (groutable, a) {
            (false, _) => Verdict::NotGroutable,
            (true, Some(v)) if v < s.marginal_aperture_mm => Verdict::Marginal,
            _ => Verdict::Groutable,
        };
        ZoneReadiness {
            joint: id.joint,
            zone: id.zone,
            planned: self.epoch.date(day),
            history: false,
            z_bottom_m: z_bottom,
            z_top_m: z_top,
            apertures_mm: apertures,
            temp_a_c: ta,
            temp_b_c: tb,
            closure_temp_c: closure,
            age_days: age,
            cover_m,
            checks,
            verdict,
            reopened: h.reopened_after(id, day).map(|d| self.epoch.date(d)),
            remedy: None,
        }
    }

    /// The deciding point's aperture against the least that takes grout;
    /// where the joint is shut there, how hard it is pressed (the pressure
    /// a further cooling must first relieve).
    fn aperture_check(&self, deciding: Option<JointSample>) -> RuleCheck {
        let s = self.settings;
        let point = s.aperture_point.as_str();
        let shut = deciding
            .filter(|d| matches!(d.state, JointState::Stick | JointState::Slip))
            .map(|d| d.pressure)
            .filter(|&p| p > 0.0);
        match deciding.map(|d| d.aperture * 1e3) {
            Some(v) => RuleCheck {
                rule: Rule::Aperture,
                value: Some(v),
                limit: s.min_aperture_mm,
                passed: v >= s.min_aperture_mm,
                reason: (v < s.min_aperture_mm).then(|| {
                    let pressed = shut.map_or(String::new(), |p| {
                        format!(" (shut, pressed at {:.2} MPa)", 1e-6 * p)
                    });
                    format!(
                        "aperture {v:.2} mm at the {point} point is below {:.2} mm{pressed}",
                        s.min_aperture_mm
                    )
                }),
            },
            None => RuleCheck {
                rule: Rule::Aperture,
                value: None,
                limit: s.min_aperture_mm,
                passed: false,
                reason: Some("the joint does not exist yet on this date (a block is not poured up to the zone)".into()),
            },
        }
    }

    /// Each block's mean zone temperature against closure + tolerance.
    fn temperature_check(
        &self,
        h: &HistoryIndex,
        ext: Option<&ZoneExtent>,
        [ta, tb]: [Option<f64>; 2],
        closure: f64,
    ) -> RuleCheck {
        let s = self.settings;
        let limit = closure + s.closure_tolerance_c;
        match (ta, tb, ext) {
            (Some(ta), Some(tb), Some(e)) => {
                let mut hot = Vec::new();
                for (t, (block, ..)) in [(ta, e.lifts_a), (tb, e.lifts_b)] {
                    if t > limit {
                        hot.push(format!("block {block} is at {t:.1} °C"));
                    }
                }
                RuleCheck {
                    rule: Rule::Temperature,
                    value: Some(ta.max(tb)),
                    limit,
                    passed: hot.is_empty(),
                    reason: (!hot.is_empty()).then(|| {
                        format!(
                            "{}, above closure {closure:.1} + {:.1} °C",
                            hot.join(" and "),
                            s.closure_tolerance_c
                        )
                    }),
                }
            }
            _ if h.history.zone_temps.rows.is_empty() => RuleCheck {
                rule: Rule::Temperature,
                value: None,
                limit,
                passed: true,
                reason: None, // no thermal model: nothing to check
            },
            _ => RuleCheck {
                rule: Rule::Temperature,
                value: None,
                limit,
                passed: false,
                reason: Some("the zone's concrete is not all poured on this date".into()),
            },
        }
    }

    /// The age of the zone's youngest lift (both blocks) on `day` \[days\];
    /// None before every lift is poured.
    fn youngest_age(&self, ext: Option<&ZoneExtent>, day: Day) -> Option<f64> {
        let youngest = ext.and_then(|e| {
            e.sides()
                .iter()
                .flat_map(|&(b, from, to)| (from..=to).map(move |l| (b, l)))
                .map(|k| self.pour_day.get(&k).copied())
                .collect::<Option<Vec<Day>>>()
                .and_then(|v| v.into_iter().max())
        });
        youngest.map(|p| day.since(p) as f64).filter(|a| *a >= 0.0)
    }

    fn age_check(&self, age: Option<f64>) -> RuleCheck {
        let s = self.settings;
        RuleCheck {
            rule: Rule::Age,
            value: age,
            limit: s.min_age_days,
            passed: age.is_some_and(|a| a >= s.min_age_days),
            reason: match age {
                None => Some("a lift of the zone is not poured by this date".into()),
                Some(a) if a < s.min_age_days => Some(format!(
                    "the youngest lift is {a:.0} days old, {:.0} needed",
                    s.min_age_days
                )),
                _ => None,
            },
        }
    }

    /// The concrete above the zone on the blocks not yet complete.
    fn cover_check(&self, ext: Option<&ZoneExtent>, z_top: f64, day: Day) -> RuleCheck {
        let s = self.settings;
        match ext.map(|e| self.cover(e, z_top, day)) {
            Some(Some((c, block))) => RuleCheck {
                rule: Rule::Cover,
                value: Some(c),
                limit: s.min_cover_m,
                passed: c >= s.min_cover_m - 1e-9,
                reason: (c < s.min_cover_m - 1e-9).then(|| {
                    format!(
                        "only {c:.1} m of concrete above the zone on block {block}, {:.1} m needed",
                        s.min_cover_m
                    )
                }),
            },
            _ => RuleCheck {
                rule: Rule::Cover,
                value: None,
                limit: s.min_cover_m,
                passed: true,
                reason: None, // both blocks complete: waived
            },
        }
    }

    /// The next lower zone of the joint is grouted on or before `day`.
    fn bottom_up_check(&self, id: ZoneId, day: Day, grout_day: &HashMap<ZoneId, Day>) -> RuleCheck {
        let Some(below) = self.zone_below(id) else {
            return RuleCheck {
                rule: Rule::BottomUp,
                value: None,
                limit: 0.0,
                passed: true,
                reason: None,
            };
        };
        match grout_day.get(&below) {
            Some(&d) => RuleCheck {
                rule: Rule::BottomUp,
                value: Some(day.since(d) as f64),
                limit: 0.0,
                passed: d <= day,
                reason: (d > day).then(|| {
                    format!(
                        "zone {} below is grouted later ({})",
                        below.zone,
                        self.epoch.date(d)
                    )
                }),
            },
            None => RuleCheck {
                rule: Rule::BottomUp,
                value: None,
                limit: 0.0,
                passed: false,
                reason: Some(format!("zone {} below has no grouting date", below.zone)),
            },
        }
    }

    /// The least cover over the blocks of the zone that are not complete on
    /// `day`, with that block; None when both are complete.
    fn cover(&self, e: &ZoneExtent, z_top: f64, day: Day) -> Option<(f64, u32)> {
        let mut least: Option<(f64, u32)> = None;
        for (block, ..) in e.sides() {
            let Some(&(foundation, n_lifts)) = self.blocks.get(&block) else {
                continue;
            };
            let poured = (1..=n_lifts)
                .take_while(|&l| self.pour_day.get(&(block, l)).is_some_and(|&d| d <= day))
                .count() as u32;
            if poured == n_lifts {
                continue;
            }
            let top = foundation + poured as f64 * self.lift_height;
            let c = (top - z_top).max(0.0);
            if least.is_none_or(|l| c < l.0) {
                least = Some((c, block));
            }
        }
        least
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rules<'a>(settings: &'a PlannerSettings, layout: &'a DamLayout) -> Rules<'a> {
        Rules {
            settings,
            layout,
            epoch: Epoch(chrono::NaiveDate::from_ymd_opt(2024, 1, 1).unwrap()),
            lift_height: 3.0,
            blocks: HashMap::new(),
            zone_z: HashMap::new(),
            pour_day: HashMap::new(),
        }
    }

    fn sample(state: JointState, pressure: f64) -> Option<JointSample> {
        opened(0.0, state, pressure)
    }

    fn opened(aperture_mm: f64, state: JointState, pressure: f64) -> Option<JointSample> {
        Some(JointSample {
            aperture: aperture_mm * 1e-3,
            state,
            temperature: 12.0,
            pressure,
        })
    }

    /// A zone too tight to grout says whether its deciding point is shut,
    /// and how hard it is pressed there; an open point or a grout layer
    /// is not "shut".
    #[test]
    fn a_shut_joint_is_reported_with_its_contact_pressure() {
        let (settings, layout) = (PlannerSettings::default(), DamLayout::default());
        let r = rules(&settings, &layout);
        let reason = |s| r.aperture_check(s).reason.unwrap();
        assert_eq!(
            reason(sample(JointState::Stick, 4.2e5)),
            "aperture 0.00 mm at the min point is below 0.50 mm (shut, pressed at 0.42 MPa)"
        );
        assert!(reason(sample(JointState::Slip, 1.5e6)).ends_with("(shut, pressed at 1.50 MPa)"));
        for s in [
            sample(JointState::Open, 0.0),
            sample(JointState::Grouted, 4.2e5),
            sample(JointState::Stick, 0.0),
        ] {
            assert_eq!(
                reason(s),
                "aperture 0.00 mm at the min point is below 0.50 mm",
                "{s:?}"
            );
        }
        assert!(
            r.aperture_check(opened(0.6, JointState::Stick, 4.2e5))
                .passed
        );
    }
}
