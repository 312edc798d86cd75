//! Grouted zones that open again: what a whole run says of its joints
//! after grouting (`groutready run` writes it into `run.txt` below the
//! distribution on the grouting dates).
//!
//! A grout layer that cracks (its bond strength exceeded) lets the joint
//! open again: the seed paper's reason to simulate past grouting at all, a
//! zone re-opened wide enough is grouted a second time. A recorded point's
//! aperture after grouting is the aperture it was grouted with plus its
//! opening since, so the opening since grouting is the recorded aperture
//! less the point's first grouted one (a point whose layer cracks within
//! its grouting day's step has no grouted sample: it was grouted with its
//! aperture of the day before). Read at the three zone points only:
//! the zone's least aperture (`min`) may sit at another node each day.

use std::fmt;

use chrono::NaiveDate;

use crate::sim::JointRecords;
use crate::vocab::{Epoch, JointState, ZoneId, ZonePoint};

use super::words::mm;

/// The zones whose grout layer cracked open at a zone point, and the widest
/// opening since grouting.
#[derive(Debug, Clone, PartialEq)]
pub struct Reopening {
    /// zones with a point grouted during the run
    pub grouted: usize,
    /// of them, zones with a point re-opened after grouting
    pub zones: usize,
    /// of them, zones whose centre re-opened
    pub centres: usize,
    /// zone points re-opened, and of them by more than [`WIDE_MM`]
    pub points: usize,
    pub wide_points: usize,
    /// the largest opening since grouting
    pub largest: Option<Widest>,
}

/// Openings since grouting above this count as wide [mm]: the planner's
/// default least aperture to grout, so a second grouting could take them.
pub const WIDE_MM: f64 = 0.5;

/// The widest opening since grouting: how much, where, and when.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Widest {
    pub opening_mm: f64,
    pub zone: ZoneId,
    pub point: ZonePoint,
    pub date: NaiveDate,
}

impl Reopening {
    /// Reads every zone point's history in `records`.
    pub fn of(records: &JointRecords, epoch: Epoch) -> Reopening {
        let mut out = Reopening {
            grouted: 0,
            zones: 0,
            centres: 0,
            points: 0,
            wide_points: 0,
            largest: None,
        };
        let mut grouted = std::collections::BTreeSet::<ZoneId>::new();
        let mut reopened = std::collections::BTreeSet::<ZoneId>::new();
        for (i, col) in records.columns.iter().enumerate() {
            if col.point == ZonePoint::Min {
                continue;
            }
            let samples = records.rows.iter().filter_map(|r| r.1[i].map(|s| (r.0, s)));
            let mut at_grouting: Option<f64> = None;
            // the last aperture before grouting: what a point whose layer
            // cracks within its grouting day's step was grouted with
            let mut before = 0.0;
            let mut widest: Option<(f64, crate::vocab::Day)> = None;
            for (day, s) in samples {
                match s.state {
                    JointState::Grouted if at_grouting.is_none() => at_grouting = Some(s.aperture),
                    JointState::Reopened => {
                        let grouted_with = *at_grouting.get_or_insert(before);
                        let since = (s.aperture - grouted_with) * 1e3;
                        if widest.is_none_or(|w| since > w.0) {
                            widest = Some((since, day));
                        }
                    }
                    _ if at_grouting.is_none() => before = s.aperture,
                    _ => {}
                }
            }
            if at_grouting.is_some() {
                grouted.insert(col.zone);
            }
            let Some((since, day)) = widest else {
                continue;
            };
            reopened.insert(col.zone);
            out.points += 1;
            out.wide_points += usize::from(since > WIDE_MM);
            if col.point == ZonePoint::Center {
                out.centres += 1;
            }
            if out.largest.is_none_or(|w| since > w.opening_mm) {
                out.largest = Some(Widest {
                    opening_mm: since,
                    zone: col.zone,
                    point: col.point,
                    date: epoch.date(day),
                });
            }
        }
        out.grouted = grouted.len();
        out.zones = reopened.len();
        out
    }
}

impl fmt::Display for Reopening {
    /// One line, two when a point re-opened.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "re-opened after grouting: {} of {} grouted zones ({} at the centre), {} zone points ({} by more than {} mm)",
            self.zones,
            self.grouted,
            self.centres,
            self.points,
            self.wide_points,
            mm(WIDE_MM)
        )?;
        if let Some(w) = self.largest {
            writeln!(
                f,
                "  widest opening since grouting {} mm: joint {} zone {} {}, {}",
                mm(w.opening_mm),
                w.zone.joint,
                w.zone.zone,
                w.point.as_str(),
                w.date
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{JointColumn, JointSample};

    fn sample(aperture_mm: f64, state: JointState) -> Option<JointSample> {
        Some(JointSample {
            aperture: aperture_mm * 1e-3,
            state,
            temperature: f64::NAN,
            pressure: 0.0,
        })
    }

    /// Two zones: zone 1's downstream point grouted at 0.3 mm opens to
    /// 1.1 mm (0.8 since grouting) and closes again; its centre and zone
    /// 2 stay grouted; zone 3 is never grouted. The minimum column of zone
    /// 1, re-opened wider, is not read.
    #[test]
    fn the_opening_since_grouting_is_read_at_the_zone_points() {
        use JointState::*;
        let z = |zone| ZoneId::new(1, zone);
        let col = |zone, point| JointColumn {
            zone: z(zone),
            point,
            site: None,
        };
        let records = JointRecords {
            columns: vec![
                col(1, ZonePoint::Downstream),
                col(1, ZonePoint::Center),
                col(1, ZonePoint::Min),
                col(2, ZonePoint::Center),
                col(3, ZonePoint::Center),
            ],
            rows: vec![
                (
                    crate::vocab::Day(10),
                    vec![
                        sample(0.3, Open),
                        sample(1.0, Open),
                        sample(0.2, Open),
                        None,
                        sample(0.4, Open),
                    ],
                ),
                (
                    crate::vocab::Day(11),
                    vec![
                        sample(0.3, Grouted),
                        sample(1.0, Grouted),
                        sample(0.2, Grouted),
                        sample(0.9, Grouted),
                        sample(0.4, Open),
                    ],
                ),
                (
                    crate::vocab::Day(40),
                    vec![
                        sample(1.1, Reopened),
                        sample(1.0, Grouted),
                        sample(3.0, Reopened),
                        sample(0.9, Grouted),
                        sample(0.6, Open),
                    ],
                ),
                (
                    crate::vocab::Day(41),
                    vec![
                        sample(0.7, Reopened),
                        sample(1.0, Grouted),
                        sample(2.0, Reopened),
                        sample(0.9, Grouted),
                        sample(0.6, Open),
                    ],
                ),
            ],
        };
        let epoch = Epoch(NaiveDate::from_ymd_opt(2024, 1, 1).unwrap());
        let r = Reopening::of(&records, epoch);
        assert_eq!(
            (r.grouted, r.zones, r.centres, r.points, r.wide_points),
            (2, 1, 0, 1, 1)
        );
        let w = r.largest.unwrap();
        assert!((w.opening_mm - 0.8).abs() < 1e-12, "{w:?}");
        assert_eq!((w.zone, w.point), (z(1), ZonePoint::Downstream));
        assert_eq!(w.date, NaiveDate::from_ymd_opt(2024, 2, 10).unwrap());
        assert_eq!(
            r.to_string(),
            "re-opened after grouting: 1 of 2 grouted zones (0 at the centre), 1 zone points (1 by more than 0.50 mm)\n  widest opening since grouting 0.80 mm: joint 1 zone 1 downstream, 2024-02-10\n"
        );
    }

    /// A point whose layer cracks within its grouting day's step is never
    /// recorded grouted: its opening since grouting is read from its
    /// aperture of the day before (0.6 mm), not from zero.
    #[test]
    fn a_layer_cracked_on_its_grouting_day_is_read_from_the_day_before() {
        use JointState::*;
        let zone = ZoneId::new(2, 3);
        let records = JointRecords {
            columns: vec![crate::sim::JointColumn {
                zone,
                point: ZonePoint::Upstream,
                site: None,
            }],
            rows: vec![
                (crate::vocab::Day(5), vec![sample(0.6, Open)]),
                (crate::vocab::Day(6), vec![sample(0.9, Reopened)]),
                (crate::vocab::Day(7), vec![sample(0.7, Reopened)]),
            ],
        };
        let epoch = Epoch(NaiveDate::from_ymd_opt(2024, 1, 1).unwrap());
        let r = Reopening::of(&records, epoch);
        assert_eq!((r.grouted, r.zones, r.points, r.wide_points), (1, 1, 1, 0));
        let w = r.largest.unwrap();
        assert!((w.opening_mm - 0.3).abs() < 1e-12, "{w:?}");
        assert_eq!(w.date, NaiveDate::from_ymd_opt(2024, 1, 7).unwrap());
    }
}
