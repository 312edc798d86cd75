//! Simulations for the planner: the baseline run keeps checkpoints, and every
//! re-simulation of an edited schedule restarts from the latest checkpoint on
//! or before the first date the edit changes.

use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};
use std::sync::{Arc, OnceLock};

use crate::mechanics::Frame;
use crate::mesh::Mesh;
use crate::scene::{Approximation, Scene};
use crate::schedule::Schedules;
use crate::sim::{Checkpoint, History, RunStats, SimError, Simulation, StopWhen};
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
    /// the scene with its thermal effects alone, made on first use
    /// ([`Runner::simulate_temperatures`])
    thermal_scene: OnceLock<Scene>,
    /// the scene the remedy searches run, made on first use
    /// ([`Runner::search_scene`])
    search_scene: OnceLock<Scene>,
    /// the scene's mechanical frame, which every re-simulation with
    /// mechanics is made on ([`Simulation::like`]): the baseline's, or the
    /// first re-simulation's when the runner was made from a run folder
    frame: OnceLock<Arc<Frame>>,
}

/// Which checkpoints the baseline keeps.
#[derive(Debug, Clone, Copy)]
pub struct Keep {
    /// one every this many days
    pub every_days: i64,
    /// none before this day once a later one is taken
    pub from: Day,
    /// and one on this day (the as-of date), where the remedies' runs restart
    pub on: Day,
}

/// How a re-simulation runs, besides what it covers.
struct Control<'c> {
    /// factorise each mechanical step on the second core
    /// (`solver.factor_ahead`); off where the remedy searches run two
    /// re-simulations side by side, whose second core is the other's,
    /// but for the longest of them ([`Runner::simulate_until`])
    factor_ahead: bool,
    /// keep a checkpoint every this many days
    every_days: Option<i64>,
    /// set from another thread to cancel the run
    cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// called after every step with (day, end)
    progress: Option<&'c mut dyn FnMut(f64, f64)>,
    /// asked at every midnight whether the rows so far suffice
    stop: Option<&'c mut StopWhen<'c>>,
}

impl Control<'_> {
    /// No checkpoints, no cancelling, no progress, to the span's end.
    fn plain() -> Self {
        Control {
            factor_ahead: false,
            every_days: None,
            cancel: None,
            progress: None,
            stop: None,
        }
    }
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
        keep: Keep,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<(Runner<'a>, RunStats), SimError> {
        let mut sim = Simulation::new(scene, mesh, schedules)?;
        sim.set_end_day(span.end_day);
        sim.observe_days(&span.observe);
        sim.checkpoint_every = Some(keep.every_days);
        sim.checkpoints_kept_from = Some(keep.from);
        sim.checkpoint_on = Some(keep.on);
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
        if let Some(frame) = sim.mechanics_frame() {
            let _ = runner.frame.set(frame);
        }
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
            thermal_scene: OnceLock::new(),
            search_scene: OnceLock::new(),
            frame: OnceLock::new(),
        }
    }

    /// This runner, its re-simulations made on `frame` (the mechanical
    /// frame of another run of its scene and mesh) when given.
    pub fn with_frame(self, frame: Option<Arc<Frame>>) -> Self {
        if let Some(f) = frame {
            let _ = self.frame.set(f);
        }
        self
    }

    /// The mechanical frame re-simulations are made on, once the baseline
    /// or a first re-simulation has made it.
    pub fn into_frame(self) -> Option<Arc<Frame>> {
        self.frame.into_inner()
    }

    /// Simulates `schedules` over `span`, restarting from the latest baseline
    /// checkpoint on or before the first date they differ from the baseline.
    pub fn simulate(&self, schedules: &Schedules, span: &Span) -> Result<History, SimError> {
        self.simulate_with(schedules, span, None, &mut |_, _| {})
    }

    /// The scene the remedy searches simulate: this runner's, its
    /// mechanical steps lengthened to `planner.search_max_step_days` when
    /// that is longer than the scene's own, with pours merged into them (a
    /// dam poured every day would otherwise step every day): an
    /// approximation of the searches alone; the verification runs the
    /// scene itself.
    pub fn search_scene(&self) -> &Scene {
        let days = self.scene.planner.search_max_step_days;
        if days <= self.scene.time.mechanics_max_step_days {
            return self.scene;
        }
        self.search_scene.get_or_init(|| {
            let mut s = self.scene.clone();
            for a in [
                Approximation::LongerSteps { max_days: days },
                Approximation::MergedPours,
            ] {
                a.turn_on(&mut s);
            }
            s
        })
    }

    /// [`Runner::simulate`] of a remedy search: on [`Runner::search_scene`].
    pub fn simulate_search(&self, schedules: &Schedules, span: &Span) -> Result<History, SimError> {
        let sim = self.resimulate(self.search_scene(), schedules, span, Control::plain())?;
        Ok(sim.history())
    }

    /// [`Runner::simulate`] with the thermal effects alone: the same
    /// temperatures (the mechanics never feeds back into the heat
    /// equation), no stresses or apertures, at a fraction of the cost. For
    /// searches whose criterion is a temperature; an answer they find is
    /// confirmed by a run with every effect.
    pub fn simulate_temperatures(
        &self,
        schedules: &Schedules,
        span: &Span,
    ) -> Result<History, SimError> {
        let scene = self.thermal_scene.get_or_init(|| {
            let mut s = self.scene.clone();
            s.effects.retain(|e| e.is_thermal());
            s
        });
        let sim = self.resimulate(scene, schedules, span, Control::plain())?;
        Ok(sim.history())
    }

    /// [`Runner::simulate_search`] that ends at the first midnight where `stop`
    /// says the rows so far suffice (checked at every midnight; its
    /// argument builds [`Simulation::history`] when asked). With
    /// `factor_ahead` it factorises each mechanical step ahead on the
    /// second core (the same rows to round-off, not to the bit): the
    /// delay search's run, the longest of the searches, outlasts the
    /// supercooling search beside it (on the demo 8.9 s against 6.2 s) and
    /// then has the second core to itself (the demo's re-simulations
    /// 12.9–13.4 s against 13.8–16.8 s, alternated; the same plan).
    pub fn simulate_until(
        &self,
        schedules: &Schedules,
        span: &Span,
        stop: &mut StopWhen,
        factor_ahead: bool,
    ) -> Result<History, SimError> {
        let control = Control {
            stop: Some(stop),
            factor_ahead,
            ..Control::plain()
        };
        let sim = self.resimulate(self.search_scene(), schedules, span, control)?;
        Ok(sim.history())
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
        let control = Control {
            cancel,
            progress: Some(progress),
            ..Control::plain()
        };
        let sim = self.resimulate(self.scene, schedules, span, control)?;
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
        let control = Control {
            every_days: Some(every_days),
            // the plan's last run, with nothing beside it
            factor_ahead: true,
            ..Control::plain()
        };
        let mut sim = self.resimulate(self.scene, schedules, span, control)?;
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

    /// A run of `scene` (this runner's, or its thermal part) restarted from
    /// the latest checkpoint that serves `schedules` (a checkpoint's
    /// mechanical state is left out when `scene` has no mechanics).
    fn resimulate<'s>(
        &'s self,
        scene: &'s Scene,
        schedules: &Schedules,
        span: &Span,
        control: Control,
    ) -> Result<Simulation<'s>, SimError> {
        let Control {
            factor_ahead,
            every_days,
            cancel,
            progress,
            stop,
        } = control;
        let (mut quiet, mut never) = (|_, _| {}, |_: Day, _: &Simulation| false);
        let progress = progress.unwrap_or(&mut quiet);
        let stop = stop.unwrap_or(&mut never);
        let mut sim = self.start(scene, schedules)?;
        sim.set_factor_ahead(factor_ahead);
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
        sim.run_until(None, progress, stop)?;
        self.resimulations.fetch_add(1, AtomicOrdering::Relaxed);
        Ok(sim)
    }

    /// A run of `scene` (this runner's, its search scene or its thermal
    /// part) over `schedules`, not started: its mechanics made on the
    /// runner's frame when there is one, else built, and its frame kept.
    /// The search scene differs in its time steps alone, which no frame
    /// reads.
    fn start<'s>(
        &'s self,
        scene: &'s Scene,
        schedules: &Schedules,
    ) -> Result<Simulation<'s>, SimError> {
        let framed = std::ptr::eq(scene, self.scene)
            || self
                .search_scene
                .get()
                .is_some_and(|s| std::ptr::eq(scene, s));
        if !scene.any_mechanical() || !framed {
            return Simulation::new(scene, self.mesh, schedules);
        }
        if let Some(frame) = self.frame.get() {
            return Simulation::like(scene, self.mesh, schedules, Arc::clone(frame));
        }
        let sim = Simulation::new(scene, self.mesh, schedules)?;
        if let Some(frame) = sim.mechanics_frame() {
            let _ = self.frame.set(frame);
        }
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
