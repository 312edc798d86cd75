//! One plan: the baseline run to the last zone due, the rules on every zone,
//! the remedy search on the flagged ones, and the data the reports need.

use std::time::Instant;

use chrono::NaiveDate;

use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::schedule::Schedules;
use crate::sim::{dam_layout, Checkpoint, History, RunStats, SimError};
use crate::vocab::{Day, Epoch, ZoneId};

use super::memo::{Lineage, SearchMemo};
use super::readiness::{MeterComparison, Plan, PlanStats, ZoneHistory, ZoneReadiness};
use super::rules::{HistoryIndex, Rules};
use super::runner::{Keep, Runner, Span};
use super::search::{grout_days, search};

/// What to plan: the as-of date that separates history from plan, and
/// how far ahead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanOptions {
    /// separates history from plan ([`default_as_of`] gives the usual one)
    pub as_of: NaiveDate,
    /// only zones due within this many days of the as-of date (None: all)
    pub horizon_days: Option<u32>,
}

impl PlanOptions {
    /// The zones of `grouting.csv` this plan covers, by planned date: those
    /// due within the horizon (every zone without one).
    pub fn zones(&self, s: &Schedules) -> Vec<(NaiveDate, ZoneId)> {
        let last = self
            .horizon_days
            .map(|h| self.as_of + chrono::Duration::days(h as i64));
        s.grouting_by_date(last)
    }

    /// The first day whose checkpoints the plan keeps, in memory and in its
    /// run folder: two checkpoint intervals before the as-of date. A remedy
    /// acts from the as-of date on, so its re-simulations restart from a
    /// checkpoint this keeps, as does next week's plan; the older ones would
    /// only hold memory (on the Xiaowan-like arch some 80 MB each).
    pub fn checkpoints_kept_from(&self, epoch: Epoch, checkpoint_days: u32) -> Day {
        epoch.day(self.as_of).plus(-2 * checkpoint_days as i64)
    }

    /// The day the plan's baseline ends: the last zone it covers is due,
    /// or the as-of date if that is later.
    pub fn end_day(&self, epoch: Epoch, s: &Schedules) -> Day {
        self.zones(s)
            .iter()
            .map(|r| epoch.day(r.0))
            .fold(epoch.day(self.as_of), Day::max)
    }
}

/// Everything a plan produces besides the [`Plan`]: the baseline's
/// histories and checkpoints (kept in the run folder for weekly restarts)
/// and the remedied schedules.
pub struct PlanOutput {
    pub plan: Plan,
    pub history: History,
    /// the baseline's checkpoints from `checkpoints_kept_from` on
    pub checkpoints: Vec<Checkpoint>,
    /// [`PlanOptions::checkpoints_kept_from`]
    pub checkpoints_kept_from: Day,
    pub baseline: RunStats,
    pub remedied: Option<Schedules>,
    /// zones that become not groutable once the remedies are applied
    pub newly_flagged: Vec<ZoneReadiness>,
    /// the remedy search, for the next plan to reuse
    pub memo: SearchMemo,
    /// the run verifying the remedies, with its checkpoints
    pub verified: Option<Lineage>,
}

/// The as-of date the schedules imply: the day after the last zone marked
/// done, else `today` (the caller's clock: the library reads none).
pub fn default_as_of(s: &Schedules, today: NaiveDate) -> NaiveDate {
    as_of_after_done(s).unwrap_or(today)
}

/// The day after the last zone marked done (None: no zone is done, so the
/// as-of date is the caller's clock unless given).
pub fn as_of_after_done(s: &Schedules) -> Option<NaiveDate> {
    s.grouting
        .iter()
        .filter(|g| g.done)
        .map(|g| g.planned.succ_opt().unwrap_or(g.planned))
        .max()
}

/// Plans `schedules` on `scene`. `restart` continues the baseline from a
/// checkpoint of an earlier run (weekly update); `progress` gets the
/// baseline's (day, end) and a line per re-simulation.
pub fn plan(
    scene: &Scene,
    mesh: &Mesh,
    schedules: &Schedules,
    options: &PlanOptions,
    restart: Option<Restart>,
    progress: &mut dyn FnMut(Progress),
) -> Result<PlanOutput, SimError> {
    let t0 = Instant::now();
    let settings = &scene.planner;
    let layout = dam_layout(mesh);
    let rules = Rules::new(settings, &layout, mesh, scene.epoch, schedules);
    let as_of = options.as_of;
    let rows = options.zones(schedules);
    let end_day = options.end_day(scene.epoch, schedules);
    let span = Span {
        end_day,
        observe: vec![],
    };
    let restarted_from = restart.as_ref().map(|r| scene.epoch.date(r.checkpoint.day));
    let (restart, older, last) = match restart {
        Some(r) => (Some((r.checkpoint, r.history)), r.older, r.last_plan),
        None => (None, Vec::new(), None),
    };
    let keep = Keep {
        every_days: settings.checkpoint_days as i64,
        from: options.checkpoints_kept_from(scene.epoch, settings.checkpoint_days),
        on: scene.epoch.day(as_of),
    };
    let (mut runner, baseline) =
        Runner::baseline(scene, mesh, schedules, &span, restart, keep, &mut |d, e| {
            progress(Progress::Baseline { day: d, end: e })
        })?;
    runner.add_older(older);
    let last = last.map(|l| {
        runner.lineages.extend(l.verified);
        (l.memo, l.first_change.map(|d| scene.epoch.day(d)))
    });
    let baseline_seconds = t0.elapsed().as_secs_f64();

    let grout = grout_days(&rules, schedules);
    let idx = HistoryIndex::new(&runner.history);
    let mut zones: Vec<ZoneReadiness> = rows
        .iter()
        .map(|&(date, zone)| ZoneReadiness {
            history: date < as_of,
            ..rules.evaluate(&idx, zone, scene.epoch.day(date), &grout)
        })
        .collect();
    let flagged: Vec<ZoneReadiness> = zones
        .iter()
        .filter(|z| !z.history && !z.verdict.groutable())
        .cloned()
        .collect();
    let to_grout: Vec<ZoneId> = zones
        .iter()
        .filter(|z| !z.history)
        .map(|z| z.zone_id())
        .collect();
    let t_search = Instant::now();
    let outcome = search(
        &runner,
        as_of,
        &rules,
        &layout,
        &flagged,
        &to_grout,
        last.as_ref().map(|(m, first)| (m, *first)),
        &mut |what| progress(Progress::Resimulation(what.to_string())),
    )?;
    for z in zones.iter_mut() {
        z.remedy = outcome.remedies.get(&z.zone_id()).cloned();
    }

    let idx = HistoryIndex::new(&runner.history);
    let meters = meter_comparisons(&rules, &idx, schedules, end_day);
    let histories = charted(&rules, &idx, schedules, &flagged, &meters);
    let plan = Plan {
        scene: scene.name.clone(),
        as_of,
        settings: settings.clone(),
        zones,
        histories,
        meters,
        warnings: Vec::new(),
        approximations: scene.approximations(),
        stats: PlanStats {
            baseline_seconds,
            restarted_from,
            resimulations: runner.resimulations(),
            resimulation_seconds: t_search.elapsed().as_secs_f64(),
            reused: outcome.reused,
            total_seconds: t0.elapsed().as_secs_f64(),
        },
    };
    Ok(PlanOutput {
        plan,
        history: runner.history,
        checkpoints: runner.checkpoints,
        checkpoints_kept_from: keep.from,
        baseline,
        remedied: outcome.schedules,
        newly_flagged: outcome.newly_flagged,
        memo: outcome.memo,
        verified: outcome.lineage,
    })
}

/// Every zone of `grouting.csv` planned on or before `end`, judged by the
/// rules on its planned date in a run's histories: what `plan` finds
/// before its remedies, which `run` summarises (over the whole
/// construction, where a plan covers its weeks). By planned date, then
/// zone.
pub fn judge_planned(
    scene: &Scene,
    mesh: &Mesh,
    schedules: &Schedules,
    history: &History,
    end: Day,
) -> Vec<ZoneReadiness> {
    let layout = dam_layout(mesh);
    let rules = Rules::new(&scene.planner, &layout, mesh, scene.epoch, schedules);
    let grout = grout_days(&rules, schedules);
    let idx = HistoryIndex::new(history);
    schedules
        .grouting_by_date(None)
        .into_iter()
        .map(|(date, zone)| (scene.epoch.day(date), zone))
        .filter(|&(day, _)| day <= end)
        .map(|(day, zone)| rules.evaluate(&idx, zone, day, &grout))
        .collect()
}

/// The histories the charts draw: every flagged zone's, then those of the
/// zones with joint meters.
fn charted(
    rules: &Rules,
    idx: &HistoryIndex,
    schedules: &Schedules,
    flagged: &[ZoneReadiness],
    meters: &[MeterComparison],
) -> Vec<ZoneHistory> {
    let mut charted: Vec<(ZoneId, NaiveDate)> =
        flagged.iter().map(|z| (z.zone_id(), z.planned)).collect();
    for m in meters {
        let id = ZoneId::new(m.joint, m.zone);
        if !charted.iter().any(|c| c.0 == id) {
            if let Some(g) = schedules.grouting_of(id) {
                charted.push((id, g.planned));
            }
        }
    }
    charted
        .iter()
        .map(|&(id, planned)| zone_history(rules, idx, id, planned))
        .collect()
}

/// A restart of the baseline from an earlier run folder.
pub struct Restart {
    pub checkpoint: Checkpoint,
    pub history: History,
    /// earlier checkpoints of that run, for the remedy searches
    pub older: Vec<Checkpoint>,
    /// that run's remedy search, when the folder kept it
    pub last_plan: Option<LastPlan>,
}

/// The last plan's remedy search, for [`super::memo`]'s reuse.
pub struct LastPlan {
    pub memo: SearchMemo,
    /// its verification's run
    pub verified: Option<Lineage>,
    /// the first date the schedules differ from that plan's (None: same)
    pub first_change: Option<NaiveDate>,
}

/// Progress of a plan, for a progress bar or a log.
#[derive(Debug, Clone)]
pub enum Progress {
    /// the baseline reached `day` of `end` [days since the epoch]
    Baseline {
        day: f64,
        end: f64,
    },
    Resimulation(String),
}

/// The daily history of one zone as the charts show it.
pub fn zone_history(
    rules: &Rules,
    idx: &HistoryIndex,
    id: ZoneId,
    planned: NaiveDate,
) -> ZoneHistory {
    let mut h = ZoneHistory {
        joint: id.joint,
        zone: id.zone,
        planned,
        dates: Vec::new(),
        upstream: Vec::new(),
        center: Vec::new(),
        downstream: Vec::new(),
        min: Vec::new(),
        temperature: Vec::new(),
    };
    for row in &idx.history.joint_records.rows {
        let day = row.0;
        let a = idx.apertures(id, day);
        if a.min.is_none() && h.dates.is_empty() {
            continue; // before the zone exists
        }
        let [ta, tb] = idx.block_temps(id, day);
        h.dates.push(rules.epoch.date(day));
        h.upstream.push(a.upstream);
        h.center.push(a.center);
        h.downstream.push(a.downstream);
        h.min.push(a.min);
        // The warmer block, as the temperature rule reads it (a mean of the
        // two would sit under the limit while the rule fails).
        h.temperature.push(match (ta, tb) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        });
    }
    h
}

/// Joint-meter readings against the baseline, interpolated linearly in time
/// between the recorded days around each reading (at most one step apart).
fn meter_comparisons(
    rules: &Rules,
    idx: &HistoryIndex,
    s: &Schedules,
    end: Day,
) -> Vec<MeterComparison> {
    let Some(meters) = &s.joint_meters else {
        return Vec::new();
    };
    let days: Vec<Day> = idx.history.joint_records.rows.iter().map(|r| r.0).collect();
    let at = |m: &crate::schedule::JointMeter, day: Day| -> Option<f64> {
        idx.apertures(m.zone_id(), day).at(m.point)
    };
    let mut out: Vec<MeterComparison> = meters
        .iter()
        .map(|m| {
            let day = rules.epoch.day(m.date);
            let predicted = if day > end {
                None
            } else {
                let i = days.partition_point(|&d| d < day);
                match (days.get(i), i.checked_sub(1).and_then(|j| days.get(j))) {
                    (Some(&d1), _) if d1 == day => at(m, d1),
                    (Some(&d1), Some(&d0)) => match (at(m, d0), at(m, d1)) {
                        (Some(a0), Some(a1)) => {
                            let w = day.since(d0) as f64 / d1.since(d0) as f64;
                            Some(a0 + (a1 - a0) * w)
                        }
                        _ => None,
                    },
                    _ => None,
                }
            };
            MeterComparison {
                joint: m.joint,
                zone: m.zone,
                point: m.point,
                date: m.date,
                measured_mm: m.aperture_mm,
                predicted_mm: predicted,
            }
        })
        .collect();
    out.sort_by(|a, b| {
        // by the point's spelling, as the reports have always listed them
        let key = |m: &MeterComparison| (m.joint, m.zone, m.point.as_str(), m.date);
        key(a).cmp(&key(b))
    });
    out
}
