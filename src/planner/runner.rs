//! Simulations for the planner: the baseline run keeps checkpoints, and every
//! re-simulation of an edited schedule restarts from the latest checkpoint on
//! or before the first date the edit changes.

use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};

use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::schedule::Schedules;
use crate::sim::{Checkpoint, History, RunStats, SimError, Simulation};
use crate::vocab::Day;

use super::edit::first_change;
use super::memo::Lineage;

/// The baseline run's restart points and histories.
pub struct Runner<'a> {
    pub scene: &'a Scene,
    pub mesh: &'a Mesh,
    /// the schedules of the baseline run
    pub base: Schedules,
    /// checkpoints of the baseline, by day
    pub checkpoints: Vec<Checkpoint>,
    pub history: History,
    /// other finished runs to restart from (the last plan's verification)
    pub lineages: Vec<Lineage>,
    /// re-simulations run (they may run on several threads; the plan
    /// reports their wall time, measured around the whole search)
    resimulations: AtomicUsize,
}

/// What one run should cover.
#[derive(Debug, Clone, Default)]
pub struct Span {
    /// stop at the start of this day (its events applied and recorded)
    pub end_day: Day,
    /// whole days that must be step ends (recorded rows)
    pub observe: Vec<Day>,
}

impl<'a> Runner<'a> {
    /// Runs the baseline from scratch, or from `restart` (a checkpoint and
    /// the history before it) when given.
    pub fn baseline(
        scene: &'a Scene,
        mesh: &'a Mesh,
        schedules: &Schedules,
        span: &Span,
        restart: Option<(Checkpoint, History)>,
        every_days: i64,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<(Runner<'a>, RunStats), SimError> {
        let mut sim = Simulation::new(scene, mesh, schedules)?;
        sim.set_end_day(span.end_day);
        sim.observe_days(&span.observe);
        sim.checkpoint_every = Some(every_days);
        if let Some((ck, history)) = &restart {
            sim.restore(ck, history);
        }
        let stats = sim.run(None, progress)?;
        let runner = Runner::from_parts(
            scene,
            mesh,
            schedules.clone(),
            std::mem::take(&mut sim.checkpoints),
            sim.history(),
        );
        Ok((runner, stats))
    }

    /// A runner over a finished baseline: its schedules, checkpoints and
    /// histories as a run folder keeps them (`app::restart`).
    pub fn from_parts(
        scene: &'a Scene,
        mesh: &'a Mesh,
        base: Schedules,
        mut checkpoints: Vec<Checkpoint>,
        history: History,
    ) -> Runner<'a> {
        checkpoints.sort_by_key(|c| c.day);
        Runner {
            scene,
            mesh,
            base,
            checkpoints,
            history,
            lineages: Vec::new(),
            resimulations: AtomicUsize::new(0),
        }
    }

    /// Simulates `schedules` over `span`, restarting from the latest baseline
    /// checkpoint on or before the first date they differ from the baseline.
    pub fn simulate(&self, schedules: &Schedules, span: &Span) -> Result<History, SimError> {
        self.simulate_with(schedules, span, None, &mut |_, _| {})
    }

    /// [`Runner::simulate`] that can be cancelled from another thread and
    /// reports its (day, end) after every step.
    pub fn simulate_with(
        &self,
        schedules: &Schedules,
        span: &Span,
        cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<History, SimError> {
        let sim = self.resimulate(schedules, span, None, cancel, progress)?;
        Ok(sim.history())
    }

    /// [`Runner::simulate`] keeping a checkpoint every `every_days`: the run
    /// as a [`Lineage`] later re-simulations can restart from.
    pub fn simulate_lineage(
        &self,
        schedules: &Schedules,
        span: &Span,
        every_days: i64,
    ) -> Result<Lineage, SimError> {
        let mut sim = self.resimulate(schedules, span, Some(every_days), None, &mut |_, _| {})?;
        Ok(Lineage {
            schedules: schedules.clone(),
            checkpoints: std::mem::take(&mut sim.checkpoints),
            history: sim.history(),
        })
    }

    /// The latest checkpoint, of the baseline or another lineage, on or
    /// before the first date `schedules` differ from that run's, with the
    /// history before it. Another lineage recorded only its own step ends,
    /// so its checkpoint must precede the first day `span` observes.
    fn restart_for(&self, schedules: &Schedules, span: &Span) -> Option<(&Checkpoint, &History)> {
        let observed = span.observe.iter().copied().min();
        let base = std::iter::once((&self.base, &self.checkpoints, &self.history, None));
        let others = self
            .lineages
            .iter()
            .map(|l| (&l.schedules, &l.checkpoints, &l.history, observed));
        base.chain(others)
            .filter_map(|(s, cks, h, limit)| {
                let from = first_change(s, schedules).map(|d| self.scene.epoch.day(d));
                let from = match (from, limit) {
                    (Some(f), Some(l)) => Some(f.min(l)),
                    (f, l) => f.or(l),
                };
                cks.iter()
                    .rev()
                    .find(|c| from.is_none_or(|f| c.day <= f))
                    .map(|c| (c, h))
            })
            // the first of equals: the baseline
            .fold(
                None,
                |best: Option<(&Checkpoint, &History)>, x| match best {
                    Some(b) if b.0.day >= x.0.day => Some(b),
                    _ => Some(x),
                },
            )
    }

    /// The day a re-simulation of `schedules` over `span` restarts from
    /// (None: day 0).
    pub fn restart_day(&self, schedules: &Schedules, span: &Span) -> Option<Day> {
        self.restart_for(schedules, span).map(|r| r.0.day)
    }

    fn resimulate(
        &self,
        schedules: &Schedules,
        span: &Span,
        every_days: Option<i64>,
        cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<Simulation<'a>, SimError> {
        let mut sim = Simulation::new(self.scene, self.mesh, schedules)?;
        // The remedy searches run two re-simulations side by side: the
        // second core is theirs.
        sim.set_factor_ahead(false);
        sim.cancel = cancel;
        sim.checkpoint_every = every_days;
        sim.set_end_day(span.end_day);
        let restart = self.restart_for(schedules, span);
        // Observed days before the restart are recorded by the baseline already.
        let restart_day = restart.map_or(Day(0), |c| c.0.day);
        let observe: Vec<Day> = span
            .observe
            .iter()
            .copied()
            .filter(|&d| d >= restart_day)
            .collect();
        sim.observe_days(&observe);
        if let Some((ck, history)) = restart {
            sim.restore(ck, history);
        }
        sim.run(None, progress)?;
        self.resimulations.fetch_add(1, AtomicOrdering::Relaxed);
        Ok(sim)
    }

    /// Adds checkpoints of an earlier run that agree with this baseline
    /// (taken before the day it restarted from).
    pub fn add_older(&mut self, older: Vec<Checkpoint>) {
        let first = self.checkpoints.first().map(|c| c.day);
        self.checkpoints.extend(
            older
                .into_iter()
                .filter(|c| first.is_none_or(|f| c.day < f)),
        );
        self.checkpoints.sort_by_key(|c| c.day);
    }

    /// Re-simulations so far.
    pub fn resimulations(&self) -> usize {
        self.resimulations.load(AtomicOrdering::Relaxed)
    }
}
