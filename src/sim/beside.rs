//! A mechanical step and the next day's thermal steps on two threads.
//!
//! The thermal model never reads the mechanical one: temperatures drive the
//! strains, and no stress, joint state or grouting changes a temperature.
//! So once the thermal model has reached a midnight d where a mechanical
//! step ends, that step and the thermal steps from d to the next midnight d'
//! are independent work. [`Simulation::step_beside`] runs them together:
//!
//! 1. the step's order is made ([`super::MechanicalJob`]: its interval, the
//!    water level, the step after it for the factorisation ahead), and the
//!    mechanical model moves to a scoped thread with copies of the
//!    temperatures at the step's start and at d;
//! 2. on the run's thread: the thermal part of d's events (pours, cooling
//!    stages), the start of the next mechanical step (the temperatures at
//!    d after them), d's temperature rows, a rewind point, and the thermal
//!    steps to d';
//! 3. the step joined: the mechanical part of d's events (grouting, then
//!    pours, as in [`Simulation::apply_events`]), d's joint row (read with
//!    the temperatures kept at d), the progress, and the stop rule, which
//!    is shown the run as it stood at d (the rewind point swapped in, and
//!    swapped back unless the run stops there).
//!
//! The loop then goes on at d' as if its thermal steps had just been taken.
//! Only the order of independent work changes, so the answer is the same
//! to the bit (`tests/it/reproducible.rs` compares a run with and without).
//! A day with a checkpoint runs beside too: the run's thread takes the
//! thermal half of the checkpoint at d before d's events, as the run in
//! order takes it, and the mechanical half is added once the step has
//! joined, before d's mechanical events (the same bytes:
//! `tests/it/reproducible.rs`). A day with a snapshot, which holds both
//! models' fields after d's events, runs in order, as does a run told its
//! second core is busy ([`Simulation::set_factor_ahead`]).
//!
//! The demo's whole construction on 2 cores (28 Nov 2026, the binaries
//! alternated three times): 92.9–94.4 s against 98.5–101.8 s in order. Its
//! thermal steps are about 10 s of the run's thread; the mechanical
//! step's thread waits for the factorisations made ahead on the other
//! core, and the thermal steps fill part of those waits.

use crate::mechanics::{MechanicsModel, StepTemperatures};
use crate::thermal::ThermalRewind;
use crate::vocab::Day;

use super::timeline::Ladder;
use super::{Checkpoint, SimError, Simulation, StopWhen};

/// The run as it stood at the midnight its thermal model stepped on from.
struct Rewind {
    thermal: Option<ThermalRewind>,
    day: f64,
    ladder: Ladder,
    steps: usize,
}

/// What the run's thread made while the mechanical step ran.
struct Ahead {
    rewind: Rewind,
    /// the zone-point temperatures recorded at d
    sites: Option<Vec<f64>>,
    /// the error of a thermal step after d, reported only if the run goes on
    thermal: Result<(), SimError>,
    /// d's checkpoint, when one is due, but for its mechanical state (the
    /// step is still running when it is taken)
    checkpoint: Option<Checkpoint>,
}

impl Simulation<'_> {
    /// The mechanical model, taken out of the run, when the step ending now
    /// may run beside the next day's thermal steps: the second core is the
    /// run's, both models exist, and this day has no snapshot.
    pub(super) fn take_for_beside(&mut self, end: f64) -> Option<MechanicsModel> {
        let fits = self.thermal_beside
            && self.thermal.is_some()
            && self.day < end
            && !self.timeline.at(self.day).is_some_and(|e| e.snapshot);
        fits.then(|| self.mechanics.take()).flatten()
    }

    /// Runs the mechanical step of `m` ending at this midnight beside the
    /// thermal steps to the next (see the module doc). True when `stop`
    /// ends the run at this midnight.
    pub(super) fn step_beside(
        &mut self,
        mut m: MechanicsModel,
        end: f64,
        progress: &mut dyn FnMut(f64, f64),
        stop: &mut StopWhen,
    ) -> Result<bool, SimError> {
        let day = self.day;
        let job = self.mechanical_job();
        let temps = self
            .mech_temps0
            .take()
            .zip(self.thermal.as_ref().map(|th| th.state.temperature.clone()));
        let mesh = self.mesh;
        let (m, stepped, ahead) = std::thread::scope(|s| {
            let worker = s.spawn(move || {
                let temps = temps.as_ref().map(|(start, end)| StepTemperatures {
                    start,
                    inside: &job.inside,
                    end,
                });
                let stepped = job.run(&mut m, mesh, temps);
                (m, stepped)
            });
            let ahead = self.thermal_to_next_midnight(end);
            let (m, stepped) = worker
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (m, stepped, ahead)
        });
        self.mechanics = Some(m);
        self.mech_steps_beside += 1;
        stepped?;
        let Ahead {
            mut rewind,
            sites,
            thermal,
            checkpoint,
        } = ahead?;
        if let Some(mut ck) = checkpoint {
            // the model as the step left it, before d's mechanical events
            ck.mechanics = self.mechanics.as_ref().map(|m| m.state.clone());
            self.keep_checkpoint(ck);
        }
        if let Some(events) = self.timeline.at(day).cloned() {
            self.apply_mechanics_events(day, &events.grouting, &events.pours);
        }
        let dofs = rewind.thermal.as_ref().map(|r| r.temperature());
        if let Some(row) = self.joint_row(sites.as_deref().zip(dofs)) {
            self.joint_records.rows.push((Day::containing(day), row));
        }
        progress(day, end);
        self.swap_rewind(&mut rewind);
        if stop(Day(day as i64), self) {
            return Ok(true);
        }
        self.swap_rewind(&mut rewind);
        thermal?;
        self.thermal_ahead = true;
        Ok(false)
    }

    /// The run's thread while a mechanical step runs (the mechanical model
    /// is out): the ladder's growth at this midnight, the checkpoint due at
    /// it (but for its mechanical state), the day's events (their thermal
    /// part), the next mechanical step's start, the day's temperature rows,
    /// then the thermal steps to the next midnight.
    fn thermal_to_next_midnight(&mut self, end: f64) -> Result<Ahead, SimError> {
        self.ladder.grow(&self.scene.time);
        // the mechanical model is out: its part is added after the join
        let checkpoint = self.checkpoint_due().then(|| self.checkpoint());
        self.apply_events(None)?;
        self.mark_mechanical_start();
        let sites = self.record_temperatures();
        let rewind = Rewind {
            thermal: self.thermal.as_ref().map(|th| th.rewind_point()),
            day: self.day,
            ladder: self.ladder,
            steps: self.steps,
        };
        let thermal = self.thermal_steps_to_midnight(end);
        Ok(Ahead {
            rewind,
            sites,
            thermal,
            checkpoint,
        })
    }

    /// Thermal steps up to the next midnight (or the end), each but the last
    /// followed by the ladder's growth as in [`Simulation::run_until`].
    fn thermal_steps_to_midnight(&mut self, end: f64) -> Result<(), SimError> {
        loop {
            self.thermal_step()?;
            if self.day.fract() == 0.0 || self.day >= end {
                return Ok(());
            }
            self.ladder.grow(&self.scene.time);
        }
    }

    /// Exchanges the run's day, ladder, step count and thermal state with
    /// `r`'s.
    fn swap_rewind(&mut self, r: &mut Rewind) {
        if let (Some(th), Some(r)) = (self.thermal.as_mut(), r.thermal.as_mut()) {
            th.swap_rewind(r);
        }
        std::mem::swap(&mut self.day, &mut r.day);
        std::mem::swap(&mut self.ladder, &mut r.ladder);
        std::mem::swap(&mut self.steps, &mut r.steps);
    }
}
