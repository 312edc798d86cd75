//! Event dates of a run and the step ladder between them.
//!
//! Steps land exactly on every event (pours, cooling-stage starts and ends,
//! snapshots, the end). After a pour or a stage change the step restarts
//! short (`first_step_days`) and grows by `growth` up to `max_step_days`
//! while nothing happens. Sub-day steps never straddle midnight and longer
//! steps start on midnight, so outputs are always at whole-day step ends.

use std::collections::BTreeMap;

use crate::mechanics::ahead::PoursByDay;
use crate::scene::{Effect, Scene, TimeStepping};
use crate::schedule::Schedules;
use crate::thermal::cooling::PlannedStage;
use crate::vocab::{Day, ZoneId};

/// What happens on one day.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DayEvents {
    /// (block, lift, placement temperature)
    pub pours: Vec<(u32, u32, f64)>,
    /// a cooling stage starts or ends
    pub stage_change: bool,
    pub snapshot: bool,
    /// zones grouted at the start of the day
    pub grouting: Vec<ZoneId>,
    /// a day whose rows a reader asks for (`Simulation::observe_days`)
    pub observed: bool,
}

impl DayEvents {
    /// The lifts (block, lift) the day pours.
    pub fn lifts(&self) -> Vec<(u32, u32)> {
        self.pours.iter().map(|&(b, l, _)| (b, l)).collect()
    }

    /// Whether the day restarts the thermal step ladder from its first
    /// step: it pours or changes a cooling stage (a cooling target reached
    /// restarts it too, which the timeline cannot know).
    pub fn restarts_ladder(&self) -> bool {
        self.stage_change || !self.pours.is_empty()
    }

    /// Whether the day ends a mechanical step that may span several days
    /// (`time.mechanics_max_step_days` > 1): it has its fields or rows
    /// read, pours unless pours are `merged` (`time.mechanics_merge_pours`:
    /// a lift poured inside a step is born there, [`Timeline::pours_within`])
    /// or grouts unless groutings are (`time.mechanics_merge_groutings`: a
    /// zone grouted inside a step is grouted at its start). A cooling
    /// stage's start or end alone does not: it changes the pipes' water,
    /// which the mechanics sees only through the temperatures at the
    /// step's ends.
    pub fn ends_mechanical_step(&self, merged: Merged) -> bool {
        (!merged.pours && !self.pours.is_empty())
            || (!merged.groutings && !self.grouting.is_empty())
            || self.snapshot
            || self.observed
    }
}

/// The events that do not end a mechanical step spanning several days
/// (`time.mechanics_merge_pours`, `time.mechanics_merge_groutings`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Merged {
    pub pours: bool,
    pub groutings: bool,
}

/// Events keyed by whole day.
#[derive(Debug, Clone, Default)]
pub struct Timeline {
    pub days: BTreeMap<Day, DayEvents>,
    pub end_day: Day,
    /// the events that do not end a mechanical step spanning several days
    pub merged: Merged,
}

impl Timeline {
    /// The event days of a run: pours, cooling-stage starts and ends (with
    /// pipe cooling), groutings (with joints) and snapshots, to the scene's
    /// end date or 60 days after the last event.
    pub fn of(scene: &Scene, schedules: &Schedules, stages: &[PlannedStage]) -> Timeline {
        let epoch = scene.epoch;
        let mut tl = Timeline::default();
        for p in &schedules.pours {
            tl.days.entry(epoch.day(p.date)).or_default().pours.push((
                p.block,
                p.lift,
                p.placement_temp_c,
            ));
        }
        if scene.has(Effect::PipeCooling) {
            for st in stages {
                let start = Day::containing(st.start_day);
                tl.days.entry(start).or_default().stage_change = true;
                if let Some(end) = st.end_day {
                    tl.days
                        .entry(Day::containing(end))
                        .or_default()
                        .stage_change = true;
                }
            }
        }
        if scene.has(Effect::Joints) {
            for g in &schedules.grouting {
                let day = tl.days.entry(epoch.day(g.planned)).or_default();
                day.grouting.push(g.zone_id());
            }
        }
        for &d in &scene.output.snapshots {
            tl.days.entry(epoch.day(d)).or_default().snapshot = true;
        }
        let last_event = tl.days.keys().next_back().copied().unwrap_or_default();
        tl.end_day = match scene.time.end_date {
            Some(end) => epoch.day(end),
            None => last_event.plus(60),
        };
        let end = tl.end_day;
        tl.days.retain(|&d, _| d <= end);
        tl.merged = Merged {
            pours: scene.time.mechanics_merge_pours,
            groutings: scene.time.mechanics_merge_groutings,
        };
        tl
    }

    /// The events at time `t` \[days\], if `t` is a midnight that has any.
    pub fn at(&self, t: f64) -> Option<&DayEvents> {
        if t.fract() != 0.0 {
            return None;
        }
        self.days.get(&Day::containing(t))
    }

    /// The time of the first day strictly after time `t` that ends a
    /// mechanical step spanning several days
    /// ([`DayEvents::ends_mechanical_step`]), or the end.
    pub fn next_mechanical_event_after(&self, t: f64) -> f64 {
        let next = Day::containing(t).plus(1);
        if next > self.end_day {
            return self.end_day.t();
        }
        self.days
            .range(next..=self.end_day)
            .find(|(_, ev)| ev.ends_mechanical_step(self.merged))
            .map_or(self.end_day.t(), |(&d, _)| d.t())
    }

    /// The lifts (block, lift) poured on the days from the midnight `t0`
    /// up to before `t1`, with each day's time: the births of a mechanical
    /// step over (t0, t1), those of its start first.
    pub fn pours_within(&self, t0: f64, t1: f64) -> PoursByDay {
        let (first, last) = (
            Day::containing(t0),
            Day::containing(t1).min(self.end_day.plus(1)),
        );
        if first >= last {
            return Vec::new();
        }
        self.days
            .range(first..last)
            .filter(|(_, ev)| !ev.pours.is_empty())
            .map(|(&d, ev)| (d.t(), ev.lifts()))
            .collect()
    }

    /// The first day strictly after time `t` (to the end) that pours lifts:
    /// its time and the lifts (block, lift).
    pub fn pours_after(&self, t: f64) -> Option<(f64, Vec<(u32, u32)>)> {
        let next = Day::containing(t).plus(1);
        if next > self.end_day {
            return None;
        }
        self.days
            .range(next..=self.end_day)
            .find(|(_, ev)| !ev.pours.is_empty())
            .map(|(&d, ev)| (d.t(), ev.lifts()))
    }

    /// The time of the first event day strictly after time `t`, or the end.
    pub fn next_event_after(&self, t: f64) -> f64 {
        let next = Day::containing(t).plus(1);
        self.days
            .range(next..)
            .next()
            .map(|(&d, _)| d.min(self.end_day).t())
            .unwrap_or(self.end_day.t())
    }

    /// The end of the thermal step from `day` on `ladder`: its next step,
    /// ending at the next event day at the latest, snapped to a midnight
    /// within round-off. The run's step and its foresight's.
    pub fn thermal_step_end(&self, cfg: &TimeStepping, ladder: &Ladder, day: f64) -> f64 {
        snap(day + ladder.next_step(cfg, day, self.next_event_after(day)))
    }
}

/// The step ladder state: the nominal step grows between events; an
/// explicit `step_schedule` overrides it for its days after a restart.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ladder {
    pub nominal: f64,
    /// time of the last restart (pour or stage change) \[d\]; the schedule
    /// counts from it
    pub since: f64,
}

impl Ladder {
    pub fn new(cfg: &TimeStepping) -> Ladder {
        Ladder {
            nominal: cfg.max_step_days,
            // Before any pour nothing is scheduled.
            since: f64::NEG_INFINITY,
        }
    }

    pub fn restart(&mut self, cfg: &TimeStepping, day: f64) {
        self.nominal = cfg.first_step_days;
        self.since = day;
    }

    /// Length of the next step from `day` given the next event.
    pub fn next_step(&self, cfg: &TimeStepping, day: f64, next_event: f64) -> f64 {
        let nominal = cfg.scheduled_step(day - self.since).unwrap_or(self.nominal);
        let mut dt = nominal.min(next_event - day);
        if day.fract() != 0.0 {
            dt = dt.min(day.ceil() - day);
        }
        dt
    }

    pub fn grow(&mut self, cfg: &TimeStepping) {
        self.nominal = (self.nominal * cfg.growth).min(cfg.max_step_days);
    }
}

/// Snaps a day value to the nearest whole day when round-off put it within 1e-9.
pub fn snap(day: f64) -> f64 {
    let r = day.round();
    if (day - r).abs() < 1e-9 {
        r
    } else {
        day
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladder_hits_whole_days_and_events() {
        let cfg = TimeStepping::default(); // 0.25, ×2, max 4
        let mut tl = Timeline {
            end_day: Day(30),
            ..Default::default()
        };
        tl.days.insert(
            Day(0),
            DayEvents {
                stage_change: true,
                ..Default::default()
            },
        );
        tl.days.insert(
            Day(10),
            DayEvents {
                stage_change: true,
                ..Default::default()
            },
        );
        let mut ladder = Ladder::new(&cfg);
        let mut day = 0.0;
        let mut ends = vec![];
        ladder.restart(&cfg, 0.0);
        while day < 30.0 {
            if tl.at(day).is_some() && day > 0.0 {
                ladder.restart(&cfg, day);
            }
            let dt = ladder.next_step(&cfg, day, tl.next_event_after(day));
            day = snap(day + dt);
            ends.push(day);
            ladder.grow(&cfg);
        }
        assert_eq!(&ends[..6], &[0.25, 0.75, 1.0, 3.0, 7.0, 10.0]);
        assert!(ends.contains(&10.0) && ends.contains(&11.0));
        let mut prev = 0.0;
        for &e in &ends {
            if e - prev >= 1.0 {
                assert_eq!(
                    e.fract(),
                    0.0,
                    "step ({prev}, {e}] does not end at midnight"
                );
                assert_eq!(
                    prev.fract(),
                    0.0,
                    "step ({prev}, {e}] does not start at midnight"
                );
            } else {
                assert!(
                    e.ceil() - prev <= 1.0,
                    "sub-day step ({prev}, {e}] straddles midnight"
                );
            }
            prev = e;
        }
    }

    /// The first pour day strictly after a time, skipping days of other
    /// events, and none past the end.
    #[test]
    fn pours_after_finds_the_next_pour_day() {
        let mut tl = Timeline {
            end_day: Day(30),
            ..Default::default()
        };
        let pours = |p: Vec<(u32, u32, f64)>| DayEvents {
            pours: p,
            ..Default::default()
        };
        tl.days.insert(Day(3), pours(vec![(0, 1, 12.0)]));
        tl.days.insert(
            Day(5),
            DayEvents {
                stage_change: true,
                ..Default::default()
            },
        );
        tl.days
            .insert(Day(8), pours(vec![(1, 0, 12.0), (2, 4, 13.0)]));
        tl.days.insert(Day(31), pours(vec![(3, 0, 12.0)]));
        assert_eq!(tl.pours_after(0.0), Some((3.0, vec![(0, 1)])));
        assert_eq!(tl.pours_after(2.5), Some((3.0, vec![(0, 1)])));
        assert_eq!(tl.pours_after(3.0), Some((8.0, vec![(1, 0), (2, 4)])));
        assert_eq!(tl.pours_after(8.0), None, "day 31 is past the end");
        assert_eq!(tl.pours_after(30.0), None);
        assert_eq!(tl.pours_after(45.0), None);
    }

    /// A longer mechanical step ends on the next day that pours, grouts or
    /// is read, never on a cooling stage's start or end alone, and at the
    /// end at the latest.
    #[test]
    fn mechanical_steps_end_on_pours_groutings_and_read_days_only() {
        let mut tl = Timeline {
            end_day: Day(40),
            ..Default::default()
        };
        let stage = DayEvents {
            stage_change: true,
            ..Default::default()
        };
        tl.days.insert(Day(2), stage.clone());
        tl.days.insert(
            Day(5),
            DayEvents {
                pours: vec![(0, 1, 12.0)],
                stage_change: true,
                ..Default::default()
            },
        );
        tl.days.insert(Day(7), stage.clone());
        tl.days.insert(
            Day(9),
            DayEvents {
                grouting: vec![ZoneId { joint: 1, zone: 1 }],
                ..Default::default()
            },
        );
        tl.days.insert(
            Day(12),
            DayEvents {
                snapshot: true,
                ..Default::default()
            },
        );
        tl.days.insert(
            Day(15),
            DayEvents {
                observed: true,
                ..Default::default()
            },
        );
        tl.days.insert(Day(20), stage);
        assert!(!tl.days[&Day(2)].ends_mechanical_step(Merged::default()));
        assert_eq!(tl.next_event_after(0.0), 2.0, "a thermal step ends on it");
        assert_eq!(tl.next_mechanical_event_after(0.0), 5.0);
        assert_eq!(tl.next_mechanical_event_after(5.0), 9.0);
        assert_eq!(tl.next_mechanical_event_after(9.0), 12.0);
        assert_eq!(tl.next_mechanical_event_after(12.0), 15.0);
        assert_eq!(tl.next_mechanical_event_after(15.0), 40.0, "the end");
        assert_eq!(tl.next_mechanical_event_after(40.0), 40.0);

        // pours merged: day 5's pour is born inside the step from day 0
        tl.merged.pours = true;
        assert!(!tl.days[&Day(5)].ends_mechanical_step(tl.merged));
        assert_eq!(tl.next_mechanical_event_after(0.0), 9.0);
        assert_eq!(tl.pours_within(0.0, 9.0), vec![(5.0, vec![(0, 1)])]);
        assert_eq!(tl.pours_within(5.0, 9.0), vec![(5.0, vec![(0, 1)])]);
        assert!(
            tl.pours_within(0.0, 5.0).is_empty(),
            "day 5 starts the next step"
        );
        assert!(tl.pours_within(6.0, 40.0).is_empty());

        // groutings merged too: day 9's grouting is inside the step from
        // day 0, which the snapshot ends
        tl.merged.groutings = true;
        assert!(!tl.days[&Day(9)].ends_mechanical_step(tl.merged));
        assert_eq!(tl.next_mechanical_event_after(0.0), 12.0);
        assert_eq!(tl.next_mechanical_event_after(12.0), 15.0, "a read day");
    }

    /// 0.1 d for 2 days, 0.25 d to day 7, then the ladder (capped at 1 d):
    /// 20 + 20 + 23 steps to day 30, every one of the scheduled length.
    #[test]
    fn step_schedule_sets_the_steps_after_a_pour() {
        use crate::scene::ScheduledStep;
        let cfg = TimeStepping {
            max_step_days: 1.0,
            step_schedule: vec![
                ScheduledStep {
                    step_days: 0.1,
                    until_days: 2.0,
                },
                ScheduledStep {
                    step_days: 0.25,
                    until_days: 7.0,
                },
            ],
            ..TimeStepping::default()
        };
        let tl = Timeline {
            end_day: Day(30),
            ..Default::default()
        };
        let mut ladder = Ladder::new(&cfg);
        ladder.restart(&cfg, 0.0);
        let (mut day, mut steps) = (0.0, vec![]);
        while day < 30.0 {
            let dt = ladder.next_step(&cfg, day, tl.next_event_after(day));
            steps.push((day, dt));
            day = snap(day + dt);
            ladder.grow(&cfg);
        }
        assert_eq!(steps.len(), 20 + 20 + 23);
        for &(d, dt) in &steps {
            let want = if d < 2.0 - 1e-9 {
                0.1
            } else if d < 7.0 - 1e-9 {
                0.25
            } else {
                1.0
            };
            assert!(
                (dt - want).abs() < 1e-9,
                "step from day {d} is {dt}, expected {want}"
            );
        }
    }
}
