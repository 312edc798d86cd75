//! One plan: the baseline run to the last zone due, the rules on every zone,
//! the remedy search on the flagged ones, and the data the reports need.

use std::time::Instant;

use chrono::NaiveDate;

use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::schedule::Schedules;
use crate::sim::{dam_layout, Checkpoint, History, RunStats, SimError};

use super::readiness::{MeterComparison, Plan, PlanStats, ZoneHistory, ZoneReadiness};
use super::rules::{HistoryIndex, Rules};
use super::runner::{Runner, Span};
use super::search::{grout_days, search};

/// What to plan.
#[derive(Debug, Clone, Default)]
pub struct PlanOptions {
    /// separates history from plan (default: the day after the last zone
    /// marked done in grouting.csv, else today)
    pub as_of: Option<NaiveDate>,
    /// only zones due within this many days of the as-of date (default: all)
    pub horizon_days: Option<u32>,
}

/// Everything a plan produces besides the [`Plan`]: the baseline's
/// histories and checkpoints (kept in the run folder for weekly restarts)
/// and the remedied schedules.
pub struct PlanOutput {
    pub plan: Plan,
    pub history: History,
    pub checkpoints: Vec<Checkpoint>,
    pub baseline: RunStats,
    pub remedied: Option<Schedules>,
    /// zones that become not groutable once the remedies are applied
    pub newly_flagged: Vec<ZoneReadiness>,
}

/// The as-of date the schedules imply: the day after the last zone marked
/// done, else `today`.
pub fn default_as_of(s: &Schedules, today: NaiveDate) -> NaiveDate {
    s.grouting
        .iter()
        .filter(|g| g.done)
        .map(|g| g.planned.succ_opt().unwrap_or(g.planned))
        .max()
        .unwrap_or(today)
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
    let today = chrono::Local::now().date_naive();
    let as_of = options
        .as_of
        .unwrap_or_else(|| default_as_of(schedules, today));
    let as_of_day = rules.day(as_of);
    let horizon = options.horizon_days.map(|d| as_of_day + d as f64);

    let mut rows: Vec<(NaiveDate, u32, u32)> = schedules
        .grouting
        .iter()
        .filter(|g| horizon.is_none_or(|h| rules.day(g.planned) <= h))
        .map(|g| (g.planned, g.joint, g.zone))
        .collect();
    rows.sort();
    let end_day = rows
        .iter()
        .map(|r| rules.day(r.0))
        .fold(as_of_day, f64::max) as i64;
    let span = Span {
        end_day,
        observe: vec![],
    };
    let restarted_from = restart.as_ref().map(|r| rules.date(r.checkpoint.day));
    let (restart, older) = match restart {
        Some(r) => (Some((r.checkpoint, r.history)), r.older),
        None => (None, Vec::new()),
    };
    let every = settings.checkpoint_days as f64;
    let (mut runner, baseline) = Runner::baseline(
        scene,
        mesh,
        schedules,
        &span,
        restart,
        every,
        &mut |d, e| progress(Progress::Baseline { day: d, end: e }),
    )?;
    runner.add_older(older);
    let baseline_seconds = t0.elapsed().as_secs_f64();

    let grout = grout_days(&rules, schedules);
    let idx = HistoryIndex::new(&runner.history);
    let mut zones: Vec<ZoneReadiness> = rows
        .iter()
        .map(|&(date, joint, zone)| {
            let mut r = rules.evaluate(&idx, joint, zone, rules.day(date), &grout);
            r.history = date < as_of;
            r
        })
        .collect();
    let flagged: Vec<ZoneReadiness> = zones
        .iter()
        .filter(|z| !z.history && !z.verdict.groutable())
        .cloned()
        .collect();
    let to_grout: Vec<(u32, u32)> = zones
        .iter()
        .filter(|z| !z.history)
        .map(|z| (z.joint, z.zone))
        .collect();
    let outcome = search(
        &runner,
        as_of,
        &rules,
        &layout,
        &flagged,
        &to_grout,
        &mut |what| progress(Progress::Resimulation(what.to_string())),
    )?;
    for z in zones.iter_mut() {
        z.remedy = outcome.remedies.get(&(z.joint, z.zone)).cloned();
    }

    let idx = HistoryIndex::new(&runner.history);
    let mut charted: Vec<(u32, u32, NaiveDate)> = flagged
        .iter()
        .map(|z| (z.joint, z.zone, z.planned))
        .collect();
    let meters = meter_comparisons(&rules, &idx, schedules, end_day as f64);
    for m in &meters {
        if !charted.iter().any(|c| c.0 == m.joint && c.1 == m.zone) {
            if let Some(g) = schedules.grouting_of(m.joint, m.zone) {
                charted.push((m.joint, m.zone, g.planned));
            }
        }
    }
    let histories = charted
        .iter()
        .map(|&(j, z, planned)| zone_history(&rules, &idx, j, z, planned))
        .collect();
    let plan = Plan {
        scene: scene.name.clone(),
        as_of,
        settings: settings.clone(),
        zones,
        histories,
        meters,
        stats: PlanStats {
            baseline_seconds,
            restarted_from,
            resimulations: runner.resimulations().0,
            resimulation_seconds: runner.resimulations().1,
            total_seconds: t0.elapsed().as_secs_f64(),
        },
    };
    Ok(PlanOutput {
        plan,
        history: runner.history,
        checkpoints: runner.checkpoints,
        baseline,
        remedied: outcome.schedules,
        newly_flagged: outcome.newly_flagged,
    })
}

/// A restart of the baseline from an earlier run folder.
pub struct Restart {
    pub checkpoint: Checkpoint,
    pub history: History,
    /// earlier checkpoints of that run, for the remedy searches
    pub older: Vec<Checkpoint>,
}

/// Progress of a plan, for a progress bar or a log.
#[derive(Debug, Clone)]
pub enum Progress {
    Baseline { day: f64, end: f64 },
    Resimulation(String),
}

pub fn zone_history(
    rules: &Rules,
    idx: &HistoryIndex,
    joint: u32,
    zone: u32,
    planned: NaiveDate,
) -> ZoneHistory {
    let mut h = ZoneHistory {
        joint,
        zone,
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
        let a = idx.apertures(joint, zone, day);
        if a.min.is_none() && h.dates.is_empty() {
            continue; // before the zone exists
        }
        let [ta, tb] = idx.block_temps(joint, zone, day);
        h.dates.push(rules.date(day));
        h.upstream.push(a.upstream);
        h.center.push(a.center);
        h.downstream.push(a.downstream);
        h.min.push(a.min);
        h.temperature.push(match (ta, tb) {
            (Some(a), Some(b)) => Some(0.5 * (a + b)),
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
    end: f64,
) -> Vec<MeterComparison> {
    let Some(meters) = &s.joint_meters else {
        return Vec::new();
    };
    let days: Vec<f64> = idx.history.joint_records.rows.iter().map(|r| r.0).collect();
    let at = |m: &crate::schedule::JointMeter, day: f64| -> Option<f64> {
        let a = idx.apertures(m.joint, m.zone, day);
        match m.point {
            crate::schedule::MeterPoint::Upstream => a.upstream,
            crate::schedule::MeterPoint::Center => a.center,
            crate::schedule::MeterPoint::Downstream => a.downstream,
            crate::schedule::MeterPoint::Min => a.min,
        }
    };
    let mut out: Vec<MeterComparison> = meters
        .iter()
        .map(|m| {
            let day = rules.day(m.date);
            let predicted = if day > end {
                None
            } else {
                let i = days.partition_point(|&d| d < day);
                match (days.get(i), i.checked_sub(1).and_then(|j| days.get(j))) {
                    (Some(&d1), _) if d1 == day => at(m, d1),
                    (Some(&d1), Some(&d0)) => match (at(m, d0), at(m, d1)) {
                        (Some(a0), Some(a1)) => Some(a0 + (a1 - a0) * (day - d0) / (d1 - d0)),
                        _ => None,
                    },
                    _ => None,
                }
            };
            MeterComparison {
                joint: m.joint,
                zone: m.zone,
                point: m.point.as_str().to_string(),
                date: m.date,
                measured_mm: m.aperture_mm,
                predicted_mm: predicted,
            }
        })
        .collect();
    out.sort_by(|a, b| {
        (a.joint, a.zone, &a.point, a.date).cmp(&(b.joint, b.zone, &b.point, b.date))
    });
    out
}
