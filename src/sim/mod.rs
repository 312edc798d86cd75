//! The staged driver: lifts are born on their pour dates, cooling stages start
//! and stop on theirs, and the enabled physics advance step by step between
//! events ([`timeline`]). Results are recorded at whole-day step ends.
//!
//! A run is bit-identical for a given build, machine and rayon thread count,
//! in one process or in several: no hash map's order reaches a result, and
//! the parallel factorisations of large systems are deterministic per thread
//! count (docs/ARCHITECTURE.md, "Reproducibility"; `tests/it/reproducible.rs`).

mod beside;
pub mod checkpoint;
pub mod snapshot;
pub mod timeline;

use std::sync::Arc;

use chrono::NaiveDate;

use crate::mechanics::ahead::{NextStep, PoursByDay};
use crate::mechanics::{Frame, MechError, MechStats, MechanicsModel, StepTemperatures, Supports};
use crate::mesh::Mesh;
use crate::scene::{Effect, Scene, TimeStepping};
use crate::schedule::{DamLayout, Schedules, Warning, ZoneExtent, COOLING_CSV};
use crate::thermal::boundary::{AirTemperature, Series, Water};
use crate::thermal::cooling::{PlannedStage, StageChange};
use crate::thermal::{ThermalError, ThermalModel, ThermalStats, WARM_WATER_MARGIN_C};
use crate::vocab::{Day, Epoch, JointState, ZoneId, ZonePoint};

pub use checkpoint::{Checkpoint, History};

pub use snapshot::Snapshot;
use timeline::{DayEvents, Ladder, Timeline};

/// Receives the snapshots of a run, on the scene's snapshot dates.
pub type SnapshotSink<'s> = dyn FnMut(&Snapshot) -> std::io::Result<()> + 's;

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Thermal(#[from] ThermalError),
    #[error(transparent)]
    Mechanics(#[from] MechError),
    #[error("mechanical step {step} ending {date}: {source}{at}")]
    MechanicsAt {
        step: usize,
        date: NaiveDate,
        source: MechError,
        /// where the failing pivot sits (`; the failing pivot is …`), or empty
        at: String,
    },
    #[error("thermal step ending {date}: {source}{at}")]
    ThermalAt {
        date: NaiveDate,
        source: ThermalError,
        /// where the failing pivot sits (`; the failing pivot is …`), or empty
        at: String,
    },
    #[error("the scene has the reservoir_temperature effect but {0} has no reservoir.csv")]
    NoReservoir(String),
    #[error("cancelled on {0}")]
    Cancelled(NaiveDate),
    /// The scene's models would not fit in the machine's memory.
    #[error("the simulation needs at least {needed_gib:.1} GiB ({elements} elements, {nodes} nodes{what}), the machine has {total_gib:.1} GiB: use a coarser mesh")]
    TooLarge {
        elements: u64,
        nodes: u64,
        what: &'static str,
        needed_gib: f64,
        total_gib: f64,
    },
    #[error("writing the snapshot of {date}: {source}")]
    Snapshot {
        date: NaiveDate,
        source: std::io::Error,
    },
}

/// Temperature history at the grouting-zone points, one row per whole day.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ZoneRecords {
    /// the zone and point of each column
    pub points: Vec<(ZoneId, ZonePoint)>,
    /// (day, value per point; NaN where the point's concrete is not yet poured)
    pub rows: Vec<(Day, Vec<f64>)>,
}

/// One column of the joint history: a zone point read at its mesh site, or
/// the zone's smallest aperture (`ZonePoint::Min`, no site).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct JointColumn {
    pub zone: ZoneId,
    pub point: ZonePoint,
    /// index into `Mesh::zone_points` (None for `Min`)
    pub site: Option<u32>,
}

/// One joint sample: aperture \[m\], state, temperature [°C] (NaN without a
/// thermal model), pressure across the joint \[Pa\] (compression positive;
/// [`crate::mechanics::JointReading`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointSample {
    pub aperture: f64,
    pub state: JointState,
    pub temperature: f64,
    pub pressure: f64,
}

/// Aperture history at the grouting-zone points and zone minima, one row
/// per whole day; None where the zone's blocks do not both exist yet.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointRecords {
    pub columns: Vec<JointColumn>,
    pub rows: Vec<(Day, Vec<Option<JointSample>>)>,
}

/// Mean temperature of each grouting zone's concrete, per block side, one
/// row per whole day; NaN where a side's lifts are not all poured.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ZoneTemps {
    /// the zones, in [`Mesh::zones`] order
    pub zones: Vec<ZoneExtent>,
    /// (day, [block A, block B] per zone)
    pub rows: Vec<(Day, Vec<[f64; 2]>)>,
}

/// Asked at every midnight of a run (its events applied and recorded)
/// whether it may end there ([`Simulation::run_until`]).
pub type StopWhen<'f> = dyn FnMut(Day, &Simulation) -> bool + 'f;

/// Counters of one run: which systems were assembled and solved.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunStats {
    pub steps: usize,
    pub pours: usize,
    pub thermal: Option<ThermalStats>,
    pub mechanics: Option<MechStats>,
    pub seconds: f64,
    /// mechanical steps run beside the next day's thermal steps, by this
    /// process ([`beside`])
    pub mechanical_steps_beside: usize,
    /// what the run found questionable in its inputs (cooling targets that
    /// had no effect)
    pub warnings: Vec<crate::schedule::Warning>,
}

/// A staged simulation of one scene with one set of schedules.
pub struct Simulation<'a> {
    pub scene: &'a Scene,
    pub mesh: &'a Mesh,
    pub timeline: Timeline,
    pub thermal: Option<ThermalModel>,
    pub mechanics: Option<MechanicsModel>,
    /// reservoir level series (reservoir.csv), when there is one
    levels: Option<Series>,
    pub day: f64,
    ladder: Ladder,
    pub records: ZoneRecords,
    pub joint_records: JointRecords,
    pub zone_temps: ZoneTemps,
    /// Keep a [`Checkpoint`] at the first whole day at least this many days
    /// after the last one (None: no checkpoints).
    pub checkpoint_every: Option<i64>,
    pub checkpoints: Vec<Checkpoint>,
    /// Checkpoints before this day are dropped once a newer one is taken
    /// (None: all are kept). The planner keeps what its run folder keeps:
    /// on the Xiaowan-like arch a checkpoint is some 80 MB.
    pub checkpoints_kept_from: Option<Day>,
    /// Also keep a checkpoint at the first whole day on or after this one,
    /// whatever the interval: the planner's as-of date, where every remedy
    /// acts from and so every re-simulation of one restarts.
    pub checkpoint_on: Option<Day>,
    /// Set from another thread to stop the run at the end of its current step
    /// with [`SimError::Cancelled`] (a what-if the engineer gave up on).
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// the current day's events are still to apply (a fresh or restored run)
    events_pending: bool,
    pours_done: usize,
    steps: usize,
    /// start of the pending mechanical step and the temperatures then
    mech_t0: f64,
    mech_temps0: Option<Vec<f64>>,
    /// the temperatures at the midnights inside the pending mechanical step
    /// (one spanning several days), with their times
    mech_temps_inside: Vec<(f64, Vec<f64>)>,
    mech_steps: usize,
    /// step the thermal model to the next midnight on this thread while the
    /// mechanical step of the day runs on another ([`beside`])
    thermal_beside: bool,
    /// the thermal model has reached `day` already: the next pass of the
    /// loop takes no thermal step
    thermal_ahead: bool,
    /// mechanical steps run beside the thermal steps by this process
    mech_steps_beside: usize,
}

impl<'a> Simulation<'a> {
    /// Prepares a run; nothing is simulated yet. The thermal model exists only
    /// if the scene switches on a thermal effect.
    pub fn new(scene: &'a Scene, mesh: &'a Mesh, schedules: &Schedules) -> Result<Self, SimError> {
        Self::on(scene, mesh, schedules, None)
    }

    /// [`Simulation::new`] whose mechanics is made on `frame`, the
    /// mechanical frame of another run of this scene and mesh
    /// ([`Simulation::mechanics_frame`]), instead of building its own: a
    /// re-simulation of a scene skips its construction ordering and rock
    /// condensation. `frame` is not used when the scene has no mechanics.
    pub fn like(
        scene: &'a Scene,
        mesh: &'a Mesh,
        schedules: &Schedules,
        frame: Arc<Frame>,
    ) -> Result<Self, SimError> {
        Self::on(scene, mesh, schedules, Some(frame))
    }

    /// This run's mechanical frame, for [`Simulation::like`]; None without
    /// mechanics.
    pub fn mechanics_frame(&self) -> Option<Arc<Frame>> {
        self.mechanics.as_ref().map(MechanicsModel::frame)
    }

    fn on(
        scene: &'a Scene,
        mesh: &'a Mesh,
        schedules: &Schedules,
        frame: Option<Arc<Frame>>,
    ) -> Result<Self, SimError> {
        check_memory(scene, mesh)?;
        let epoch = scene.epoch;
        let stages = planned_stages(epoch, schedules);
        let tl = Timeline::of(scene, schedules, &stages);
        let thermal = if scene.any_thermal() {
            let air = scene.air.clone().map(|law| {
                AirTemperature::new(
                    epoch,
                    law,
                    schedules
                        .weather
                        .as_ref()
                        .map(|w| Series::from_dated(epoch, w)),
                )
            });
            let water = if scene.has(Effect::ReservoirTemperature) {
                let levels = schedules
                    .reservoir
                    .as_ref()
                    .ok_or_else(|| SimError::NoReservoir(schedules.dir.display().to_string()))?;
                scene
                    .reservoir
                    .clone()
                    .map(|law| Water::new(epoch, law, Series::from_dated(epoch, levels)))
            } else {
                None
            };
            let settings = crate::thermal::ThermalSettings::from_scene(scene);
            Some(ThermalModel::new(mesh, &settings, stages, air, water)?)
        } else {
            None
        };
        let mechanics = if !scene.any_mechanical() {
            None
        } else if let Some(frame) = frame {
            Some(MechanicsModel::on_frame(frame)?)
        } else {
            Some(MechanicsModel::new(
                mesh,
                &crate::mechanics::MechanicsSettings::from_scene(scene).map_err(MechError::from)?,
                &Supports::for_sides(mesh, &scene.boundary.supports()).map_err(MechError::from)?,
            )?)
        };
        let levels = schedules
            .reservoir
            .as_ref()
            .map(|r| Series::from_dated(epoch, r));
        let records = ZoneRecords {
            points: mesh
                .zone_points
                .iter()
                .map(|p| (ZoneId::new(p.joint, p.zone), p.point))
                .collect(),
            rows: Vec::new(),
        };
        let joint_records = JointRecords {
            columns: if mechanics.as_ref().is_some_and(|m| !m.points().is_empty()) {
                joint_columns(mesh)
            } else {
                Vec::new()
            },
            rows: Vec::new(),
        };
        Ok(Simulation {
            scene,
            mesh,
            ladder: Ladder::new(&scene.time),
            timeline: tl,
            thermal,
            mechanics,
            levels,
            day: 0.0,
            records,
            joint_records,
            zone_temps: ZoneTemps {
                zones: dam_layout(mesh).zones,
                rows: Vec::new(),
            },
            checkpoint_every: None,
            checkpoints: Vec::new(),
            checkpoints_kept_from: None,
            checkpoint_on: None,
            cancel: None,
            events_pending: true,
            pours_done: 0,
            steps: 0,
            mech_t0: 0.0,
            mech_temps0: None,
            mech_temps_inside: Vec::new(),
            mech_steps: 0,
            thermal_beside: scene.solver.factor_ahead,
            thermal_ahead: false,
            mech_steps_beside: 0,
        })
    }

    /// Thermal steps and pours made so far, those before a restored
    /// checkpoint included.
    pub fn steps_and_pours(&self) -> (usize, usize) {
        (self.steps, self.pours_done)
    }

    pub fn end_day(&self) -> Day {
        self.timeline.end_day
    }

    /// Makes each of `days` a step end, so the histories hold a row for it
    /// (the delay search reads daily rows, joint meters their dates).
    pub fn observe_days(&mut self, days: &[Day]) {
        for &d in days {
            if (Day(0)..=self.timeline.end_day).contains(&d) {
                self.timeline.days.entry(d).or_default().observed = true;
            }
        }
    }

    /// Stops the run at the start of `day` (its events applied and recorded)
    /// instead of the scene's end; never later than that end.
    pub fn set_end_day(&mut self, day: Day) {
        self.timeline.end_day = self.timeline.end_day.min(day);
    }

    /// Applies the events of the current day (pours, stage changes).
    fn apply_events(&mut self, sink: Option<&mut SnapshotSink<'_>>) -> Result<(), SimError> {
        let Some(events) = self.timeline.at(self.day).cloned() else {
            return Ok(());
        };
        let mut restart = events.restarts_ladder();
        let DayEvents {
            pours,
            snapshot,
            grouting,
            ..
        } = events;
        self.apply_mechanics_events(self.day, &grouting, &pours);
        for (block, lift, temp) in pours {
            if let Some(th) = self.thermal.as_mut() {
                th.pour(block, lift, self.day, temp);
            }
            self.pours_done += 1;
        }
        if let Some(th) = self.thermal.as_mut() {
            restart |= th.update_stages(self.day);
        }
        if restart {
            self.ladder.restart(&self.scene.time, self.day);
        }
        if let (true, Some(sink)) = (snapshot, sink) {
            let snap = self.snapshot();
            sink(&snap).map_err(|source| SimError::Snapshot {
                date: snap.date,
                source,
            })?;
        }
        Ok(())
    }

    /// The mechanical model's part of the day's events: the zones grouted,
    /// then the lifts poured (the thermal model's part does not depend on
    /// it, nor it on the thermal model's).
    fn apply_mechanics_events(&mut self, day: f64, grouting: &[ZoneId], pours: &[(u32, u32, f64)]) {
        if let Some(m) = self.mechanics.as_mut() {
            for z in grouting {
                m.grout(z.joint, z.zone, day);
            }
            for &(block, lift, _) in pours {
                m.pour(block, lift, day);
            }
        }
    }

    /// Runs to the end of the timeline. `snapshots` receives the fields on
    /// the scene's snapshot dates; `progress` is called after each step with
    /// (day, end).
    pub fn run(
        &mut self,
        snapshots: Option<&mut SnapshotSink<'_>>,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<RunStats, SimError> {
        self.run_until(snapshots, progress, &mut |_, _| false)
    }

    /// [`Simulation::run`] that ends early, at the first midnight (its
    /// events applied and recorded) where `stop` says the rows so far
    /// answer the question asked: a search that has found what it looks
    /// for. Stopping changes nothing before it.
    pub fn run_until(
        &mut self,
        mut snapshots: Option<&mut SnapshotSink<'_>>,
        progress: &mut dyn FnMut(f64, f64),
        stop: &mut StopWhen,
    ) -> Result<RunStats, SimError> {
        let start = std::time::Instant::now();
        let end = self.end_day().t();
        if self.events_pending {
            self.apply_events(snapshots.as_deref_mut())?;
            self.begin_mechanical_step();
            self.record();
            self.events_pending = false;
        }
        while self.day < end || self.thermal_ahead {
            if self
                .cancel
                .as_ref()
                .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
            {
                return Err(SimError::Cancelled(self.scene.epoch.date_at(self.day)));
            }
            if !std::mem::take(&mut self.thermal_ahead) {
                self.thermal_step()?;
            }
            // Mechanics steps from midnight to midnight (or over the longer
            // thermal steps): the thermal strain is a difference of states, so
            // the sub-day thermal steps after a pour add up exactly, and every
            // pour and grouting date is a midnight.
            let stepped =
                (self.day.fract() == 0.0 || self.day >= end) && self.mechanical_step_due(end);
            if let Some(m) = stepped.then(|| self.take_for_beside(end)).flatten() {
                if self.step_beside(m, end, progress, stop)? {
                    break;
                }
                continue;
            }
            if stepped {
                self.mechanical_step()?;
            }
            self.ladder.grow(&self.scene.time);
            if self.day.fract() == 0.0 {
                self.maybe_checkpoint();
            }
            self.apply_events(snapshots.as_deref_mut())?;
            if self.day.fract() == 0.0 {
                if stepped {
                    self.begin_mechanical_step();
                } else {
                    self.mark_mechanical_day();
                }
                self.record();
            }
            progress(self.day, end);
            if self.day.fract() == 0.0 && stop(Day(self.day as i64), self) {
                break;
            }
        }
        Ok(RunStats {
            steps: self.steps,
            pours: self.pours_done,
            thermal: self.thermal.as_ref().map(|t| t.stats),
            mechanics: self.mechanics.as_ref().map(|m| m.stats),
            seconds: start.elapsed().as_secs_f64(),
            mechanical_steps_beside: self.mech_steps_beside,
            warnings: self.warnings(),
        })
    }

    /// What the run found questionable in its inputs: cooling water not
    /// colder than the concrete when its stage started (the pipes warmed
    /// it), and targets that had no effect (the concrete never was warmer
    /// than them while the stage ran, so the stage ran to its end date).
    pub fn warnings(&self) -> Vec<Warning> {
        let Some(th) = &self.thermal else {
            return Vec::new();
        };
        let region = |st: &PlannedStage| {
            let lifts = crate::schedule::lifts_label(st.lift_from, st.lift_to);
            format!("block {} {lifts}", st.block)
        };
        let epoch = self.scene.epoch;
        let warm = th.warm_water().map(|(st, mean)| {
            Warning::cell(
                COOLING_CSV,
                st.line,
                7,
                "water_temp_c",
                format!(
                    "water at {} °C is more than {WARM_WATER_MARGIN_C} °C warmer than {} when the stage started on {} (mean {mean:.1} °C): the pipes warmed the concrete",
                    st.water_temp_c,
                    region(st),
                    epoch.date(Day::containing(st.start_day)),
                ),
            )
        });
        let unused = th.unused_targets(self.day).map(|(st, ended)| {
            let what = if ended {
                "ran until the next stage on the lift started"
            } else {
                "still runs"
            };
            Warning::cell(
                COOLING_CSV,
                st.line,
                8,
                "target_temp_c",
                format!(
                    "{} was never warmer than the target {} °C while this stage ran, and the stage has no end date: it {what}",
                    region(st),
                    st.target_temp_c.unwrap_or(f64::NAN)
                ),
            )
        });
        warm.chain(unused).collect()
    }

    /// One thermal step from `day` on the ladder (ending at the next event
    /// day at the latest); `day` becomes its end.
    fn thermal_step(&mut self) -> Result<(), SimError> {
        let t1 = self
            .timeline
            .thermal_step_end(&self.scene.time, &self.ladder, self.day);
        if let Some(th) = self.thermal.as_mut() {
            if let Err(source) = th.step(self.day, t1) {
                let at = source
                    .pivot_dof()
                    .and_then(|i| th.dof_of_unknown(i))
                    .and_then(|d| self.mesh.node_of_thermal_dof(d))
                    .map(|n| {
                        format!(
                            "; the failing pivot is the temperature of {}",
                            self.mesh.describe_node(n)
                        )
                    })
                    .unwrap_or_default();
                let date = self.scene.epoch.date_at(t1);
                return Err(SimError::ThermalAt { date, source, at });
            }
        }
        self.day = t1;
        self.steps += 1;
        Ok(())
    }

    /// Does the pending mechanical step end at this midnight? Always with
    /// `time.mechanics_max_step_days = 1`; otherwise when it spans that many
    /// days, at the end, on a day that pours or grouts (unless those are
    /// merged) or is read (snapshots, observed days;
    /// [`DayEvents::ends_mechanical_step`]) and on a
    /// checkpoint day (a checkpoint holds no pending step).
    fn mechanical_step_due(&self, end: f64) -> bool {
        let (time, t0) = (&self.scene.time, self.mech_t0);
        self.day >= step_due_from(time, &self.timeline, (t0, end), self.checkpoint_due_from())
    }

    /// Remembers the start of the next mechanical step (after the day's events).
    fn begin_mechanical_step(&mut self) {
        if self.mechanics.is_some() {
            self.mark_mechanical_start();
        }
    }

    /// The next mechanical step starts now, at the temperatures of now.
    fn mark_mechanical_start(&mut self) {
        self.mech_t0 = self.day;
        self.mech_temps0 = self.thermal.as_ref().map(|th| th.state.temperature.clone());
        self.mech_temps_inside.clear();
    }

    /// A midnight inside the pending mechanical step: its temperatures (after
    /// the day's events) are kept for the step's thermal strain.
    fn mark_mechanical_day(&mut self) {
        if let (Some(_), Some(th)) = (&self.mechanics, &self.thermal) {
            self.mech_temps_inside
                .push((self.day, th.state.temperature.clone()));
        }
    }

    fn mechanical_step(&mut self) -> Result<(), SimError> {
        let Some(mut m) = self.mechanics.take() else {
            return Ok(());
        };
        let job = self.mechanical_job();
        let temps = match (&self.mech_temps0, &self.thermal) {
            (Some(start), Some(th)) => Some(StepTemperatures {
                start,
                inside: &job.inside,
                end: &th.state.temperature,
            }),
            _ => None,
        };
        let stepped = job.run(&mut m, self.mesh, temps);
        self.mechanics = Some(m);
        stepped
    }

    /// The mechanical step ending now, but for the model and temperatures.
    fn mechanical_job(&mut self) -> MechanicalJob {
        let t1 = self.day;
        let level = self.levels.as_ref().and_then(|l| {
            let first = l.first_day()?;
            (t1 >= first)
                .then(|| l.at(t1.min(l.last_day().unwrap_or(t1))))
                .flatten()
        });
        self.mech_steps += 1;
        let next = next_mechanical_step(
            &Foresight {
                time: &self.scene.time,
                timeline: &self.timeline,
                end: self.timeline.end_day.t(),
                checkpoint_after: &|day| self.checkpoint_due_after(Some(Day::containing(day))),
            },
            self.ladder,
            t1,
            self.next_checkpoint_from(),
        );
        MechanicalJob {
            step: self.mech_steps,
            t0: self.mech_t0,
            t1,
            level,
            next,
            epoch: self.scene.epoch,
            inside: std::mem::take(&mut self.mech_temps_inside),
        }
    }

    /// Use the second core (`solver.factor_ahead`, on by default): factorise
    /// each mechanical step while the step before runs, and step the thermal
    /// model to the next midnight while a mechanical step runs
    /// ([`beside`]); off where the cores are otherwise busy. The answer is
    /// the same to round-off (the thermal steps beside: to the bit).
    pub fn set_factor_ahead(&mut self, on: bool) {
        if let Some(m) = self.mechanics.as_mut() {
            m.set_factor_ahead(on);
        }
        self.thermal_beside = on && self.scene.solver.factor_ahead;
    }

    /// Step the thermal model beside the mechanical steps (on with
    /// [`Simulation::set_factor_ahead`]); off, everything runs in order on
    /// the run's thread. The answer is the same to the bit.
    pub fn set_thermal_beside(&mut self, on: bool) {
        self.thermal_beside = on;
    }

    fn record(&mut self) {
        let sites = self.record_temperatures();
        let dofs = self
            .thermal
            .as_ref()
            .map(|th| th.state.temperature.as_slice());
        if let Some(row) = self.joint_row(sites.as_deref().zip(dofs)) {
            self.joint_records
                .rows
                .push((Day::containing(self.day), row));
        }
    }

    /// Records the day's zone temperatures and zone-point temperatures, and
    /// returns the latter (NaN where a point's concrete is not poured; None
    /// without a thermal model).
    fn record_temperatures(&mut self) -> Option<Vec<f64>> {
        let th = self.thermal.as_ref()?;
        let side =
            |(block, from, to): (u32, u32, u32)| th.lifts_mean(block, from, to).unwrap_or(f64::NAN);
        let row = self
            .zone_temps
            .zones
            .iter()
            .map(|z| [side(z.lifts_a), side(z.lifts_b)])
            .collect();
        self.zone_temps.rows.push((Day::containing(self.day), row));
        let live = th.live_dofs();
        let values: Vec<f64> = self
            .mesh
            .zone_points
            .iter()
            .map(|p| {
                th.point_temperature(self.mesh, p, &live)
                    .unwrap_or(f64::NAN)
            })
            .collect();
        self.records
            .rows
            .push((Day::containing(self.day), values.clone()));
        Some(values)
    }

    /// The day's joint row; `temps` are the zone-point temperatures (as
    /// [`Simulation::record_temperatures`] returns them) and the thermal-dof
    /// temperatures of the day. None without joint columns.
    fn joint_row(&self, temps: Option<(&[f64], &[f64])>) -> Option<Vec<Option<JointSample>>> {
        let m = self.mechanics.as_ref()?;
        if self.joint_records.columns.is_empty() {
            return None;
        }
        let node_temp = |node: u32| -> f64 {
            temps.map_or(f64::NAN, |(_, dofs)| {
                dofs[self.mesh.thermal_dof[node as usize] as usize]
            })
        };
        let mut row = Vec::with_capacity(self.joint_records.columns.len());
        for col in &self.joint_records.columns {
            let sample = match col.site {
                Some(index) => {
                    let zp = &self.mesh.zone_points[index as usize];
                    m.point_aperture(self.mesh, zp).map(|r| JointSample {
                        aperture: r.aperture,
                        state: r.state,
                        pressure: r.pressure,
                        temperature: temps.map_or(f64::NAN, |(sites, _)| sites[index as usize]),
                    })
                }
                None => m
                    .zone_min_aperture(col.zone.joint, col.zone.zone)
                    .map(|z| JointSample {
                        aperture: z.reading.aperture,
                        state: z.reading.state,
                        pressure: z.reading.pressure,
                        temperature: z
                            .nodes
                            .iter()
                            .filter(|&&(_, w)| w > 0.0)
                            .map(|&(node, w)| w * node_temp(node))
                            .sum(),
                    }),
            };
            row.push(sample);
        }
        Some(row)
    }
}

/// Refuses a scene whose models cannot fit in the machine's memory, before
/// any is built (a lower bound: [`crate::machine::simulation_memory_lower_bound`]).
fn check_memory(scene: &Scene, mesh: &Mesh) -> Result<(), SimError> {
    let (elements, nodes) = (mesh.elements.len() as u64, mesh.nodes.len() as u64);
    let mechanics = scene.any_mechanical();
    let direct =
        scene.any_thermal() && scene.solver.thermal == crate::scene::ThermalSolverKind::Cholesky;
    let needed = crate::machine::simulation_memory_lower_bound(elements, nodes, mechanics, direct);
    match crate::machine::total_memory_bytes() {
        Some(total) if needed > total => Err(SimError::TooLarge {
            elements,
            nodes,
            what: if mechanics { ", with mechanics" } else { "" },
            needed_gib: crate::machine::gib(needed),
            total_gib: crate::machine::gib(total),
        }),
        _ => Ok(()),
    }
}

/// The cooling stages of `cooling.csv` as the thermal model runs them.
fn planned_stages(epoch: Epoch, schedules: &Schedules) -> Vec<PlannedStage> {
    let day = |d: NaiveDate| epoch.t(d);
    let rows = &schedules.cooling;
    crate::schedule::cooling_chains(rows)
        .into_iter()
        .map(|chain| {
            let (head, last) = (&rows[chain[0]], &rows[chain[chain.len() - 1]]);
            PlannedStage {
                block: head.block,
                lift_from: head.lift_from,
                lift_to: head.lift_to,
                start_day: day(head.start),
                end_day: last.end.map(day),
                water_temp_c: head.water_temp_c,
                target_temp_c: head.target_temp_c,
                line: head.line,
                changes: chain[1..]
                    .iter()
                    .map(|&r| StageChange {
                        day: day(rows[r].start),
                        water_temp_c: rows[r].water_temp_c,
                        target_temp_c: rows[r].target_temp_c,
                    })
                    .collect(),
            }
        })
        .collect()
}

/// The columns of the joint history: per zone, its placed points (at their
/// mesh sites) and its minimum.
fn joint_columns(mesh: &Mesh) -> Vec<JointColumn> {
    let mut columns = Vec::new();
    for z in &mesh.zones {
        let zone = z.zone_id();
        for (i, p) in mesh.zone_points.iter().enumerate() {
            if p.joint == z.joint && p.zone == z.zone {
                columns.push(JointColumn {
                    zone,
                    point: p.point,
                    site: Some(i as u32),
                });
            }
        }
        columns.push(JointColumn {
            zone,
            point: ZonePoint::Min,
            site: None,
        });
    }
    columns
}

/// What the schedules may refer to in this mesh: blocks with their lifts, and
/// each joint's zones with the lifts of both blocks they span.
pub fn dam_layout(mesh: &Mesh) -> DamLayout {
    let lift_at = |block: u32, z: f64| -> u32 {
        let b = &mesh.blocks[block as usize - 1];
        ((z - b.foundation_z) / mesh.lift_height).round() as u32
    };
    let zones = mesh
        .zones
        .iter()
        .map(|z| {
            let side = |block: u32| {
                (
                    block,
                    lift_at(block, z.z_bottom) + 1,
                    lift_at(block, z.z_top),
                )
            };
            ZoneExtent {
                joint: z.joint,
                zone: z.zone,
                lifts_a: side(z.joint),
                lifts_b: side(z.joint + 1),
            }
        })
        .collect();
    DamLayout {
        blocks: mesh.blocks.iter().map(|b| (b.block, b.n_lifts)).collect(),
        zones,
    }
}

/// A mechanical step as the driver orders it: everything but the model and
/// the temperatures, so that it can run on another thread
/// ([`Simulation::step_beside`]).
struct MechanicalJob {
    /// its number in the run (1 the first)
    step: usize,
    t0: f64,
    t1: f64,
    /// the reservoir level at `t1`
    level: Option<f64>,
    /// the step after it, for the factorisation ahead
    next: Option<NextStep>,
    epoch: Epoch,
    /// the temperatures at the midnights inside it, with their times
    inside: Vec<(f64, Vec<f64>)>,
}

impl MechanicalJob {
    /// Steps `m`; `temps` are the thermal-dof temperatures of the step.
    fn run(
        &self,
        m: &mut MechanicsModel,
        mesh: &Mesh,
        temps: Option<StepTemperatures<'_>>,
    ) -> Result<(), SimError> {
        m.set_next_step(self.next.clone());
        m.step_through(self.t0, self.t1, temps, self.level)
            .map_err(|source| {
                let at = source
                    .pivot_dof()
                    .and_then(|d| m.node_of_unknown(d))
                    .map(|(n, c)| {
                        let axis = ["x", "y", "z"][c as usize];
                        format!(
                            "; the failing pivot is the {axis} displacement of {}",
                            mesh.describe_node(n)
                        )
                    })
                    .unwrap_or_default();
                SimError::MechanicsAt {
                    step: self.step,
                    date: self.epoch.date_at(self.t1),
                    source,
                    at,
                }
            })
    }
}

/// The end of a mechanical step started at the midnight `t0` that may span
/// several days: `mechanics_max_step_days` on, the next day that pours or
/// grouts (unless those are merged) or is read (snapshots, observed days;
/// not a cooling stage's start or end alone,
/// [`DayEvents::ends_mechanical_step`]), or the end,
/// whichever comes first (every such day is a thermal step's end).
fn longer_step_end(time: &TimeStepping, timeline: &Timeline, t0: f64, end: f64) -> f64 {
    (t0 + f64::from(time.mechanics_max_step_days))
        .min(timeline.next_mechanical_event_after(t0))
        .min(end)
}

/// The day from which the mechanical step started at the midnight `t0`
/// ends at the first midnight the run lands on: any day with a step every
/// midnight (−∞), else [`longer_step_end`] or the next `checkpoint` due,
/// whichever comes first (a checkpoint holds no pending step). The run
/// ([`Simulation::mechanical_step_due`]) and its foresight
/// ([`Foresight::step_end`]) read this one rule.
fn step_due_from(
    time: &TimeStepping,
    timeline: &Timeline,
    (t0, end): (f64, f64),
    checkpoint: Option<f64>,
) -> f64 {
    if time.mechanics_max_step_days <= 1 {
        return f64::NEG_INFINITY;
    }
    longer_step_end(time, timeline, t0, end).min(checkpoint.unwrap_or(f64::INFINITY))
}

/// How the run will move from a midnight on, as far as it can be foreseen:
/// the thermal ladder restarted on the days that pour or change a stage
/// (`Simulation::apply_events`; a cooling target reached inside a step
/// restarts it too, unseen here), the mechanical steps ended where
/// [`longer_step_end`] and the checkpoints end them
/// (`Simulation::mechanical_step_due`).
struct Foresight<'a> {
    time: &'a TimeStepping,
    timeline: &'a Timeline,
    end: f64,
    /// the first day from which a checkpoint is due after one taken on the
    /// given day (`Simulation::checkpoint_due_after`)
    checkpoint_after: &'a dyn Fn(f64) -> Option<f64>,
}

impl Foresight<'_> {
    /// The end of the mechanical step from the midnight `t0` with the
    /// `ladder` as it stands there after its growth, before the day's
    /// events; the ladder is left as it stands at the step's end, and
    /// `checkpoint` (the next one due) moves on past a checkpoint taken
    /// there. A step ends at the first midnight a thermal step lands on
    /// from its foreseen end (where nothing happens the thermal steps grow
    /// past a day, and a step of 3 days may span 4) or a checkpoint's.
    fn step_end(&self, ladder: &mut Ladder, t0: f64, checkpoint: &mut Option<f64>) -> f64 {
        let (time, timeline) = (self.time, self.timeline);
        let events_restart = |ladder: &mut Ladder, t: f64| {
            if timeline.at(t).is_some_and(DayEvents::restarts_ladder) {
                ladder.restart(time, t);
            }
        };
        events_restart(ladder, t0);
        let due = step_due_from(time, timeline, (t0, self.end), *checkpoint);
        let mut t = t0;
        loop {
            t = timeline.thermal_step_end(time, ladder, t);
            ladder.grow(time);
            if (t.fract() == 0.0 && t >= due) || t >= self.end {
                break;
            }
            events_restart(ladder, t);
        }
        if checkpoint.is_some_and(|c| t >= c) {
            *checkpoint = (self.checkpoint_after)(t);
        }
        t
    }

    /// The first mechanical step from the midnight `t` on whose span pours
    /// lifts: its start and its lifts by day (the ladder and the next
    /// checkpoint as they stand at `t`).
    fn first_births_from(
        &self,
        mut ladder: Ladder,
        t: f64,
        mut checkpoint: Option<f64>,
    ) -> Option<(f64, PoursByDay)> {
        if self.time.mechanics_max_step_days <= 1 {
            // a step every midnight: the first pour day from `t` on
            let (day, lifts) = self.timeline.pours_after(t - 1.0)?;
            return Some((day, vec![(day, lifts)]));
        }
        let mut start = t;
        while start < self.end {
            let step_end = self.step_end(&mut ladder, start, &mut checkpoint);
            let pours = self.timeline.pours_within(start, step_end);
            if !pours.is_empty() {
                return Some((start, pours));
            }
            start = step_end;
        }
        None
    }
}

/// The mechanical step after the one ending at `t1`, from the step ladder
/// as it stands before its growth at `t1` and `checkpoint` (the first day
/// from which the run's next checkpoint is due): its interval
/// ([`Foresight::step_end`]), with the lifts poured at `t1` (and inside
/// it, with pours merged), and the first later step that pours; None at
/// the end. The thermal ladder may still restart on a cooling target
/// reached; the step then differs and what was made for it is discarded
/// (counted).
fn next_mechanical_step(
    foresight: &Foresight<'_>,
    mut ladder: Ladder,
    t1: f64,
    mut checkpoint: Option<f64>,
) -> Option<NextStep> {
    if t1 >= foresight.end || t1.fract() != 0.0 {
        return None;
    }
    let timeline = foresight.timeline;
    ladder.grow(foresight.time);
    let grouting = timeline
        .at(t1)
        .map(|e| e.grouting.clone())
        .unwrap_or_default();
    let t = foresight.step_end(&mut ladder, t1, &mut checkpoint);
    Some(NextStep {
        interval: (t1, t),
        pours: timeline.pours_within(t1, t),
        grouting,
        later_pours: foresight.first_births_from(ladder, t, checkpoint),
    })
}
