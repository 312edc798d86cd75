//! Restart points of a staged run.
//!
//! A [`Checkpoint`] is the simulation state at the start of a whole day,
//! before that day's events: the thermal state with its stages and pour days,
//! the mechanical state (stresses, creep history, joint states), the step
//! ladder and the counters. The histories recorded before that day travel
//! separately as a [`History`]. A run restored from a checkpoint with the same
//! schedules repeats the uninterrupted run exactly: the live systems are
//! renumbered and refactorised from the same data, and the steps land on the
//! same days. With edited schedules it is exact as long as every edit is on or
//! after the checkpoint's day (the planner's runner and `app::restart` pick it).
//!
//! On disk both are postcard (compact binary serde) files.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{JointRecords, Simulation, ZoneRecords, ZoneTemps};
use crate::mechanics::MechState;
use crate::thermal::ThermalCheckpoint;
use crate::vocab::Day;

use super::timeline::Ladder;

/// The state of a run at the start of `day`, before its events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub day: Day,
    ladder: Ladder,
    pours_done: usize,
    steps: usize,
    mech_steps: usize,
    pub thermal: Option<ThermalCheckpoint>,
    pub mechanics: Option<MechState>,
}

/// The histories a run records ([`Simulation::records`] and friends).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct History {
    pub records: ZoneRecords,
    pub joint_records: JointRecords,
    pub zone_temps: ZoneTemps,
}

impl History {
    /// The rows recorded before `day`.
    pub fn before(&self, day: Day) -> History {
        let mut h = self.clone();
        h.records.rows.retain(|r| r.0 < day);
        h.joint_records.rows.retain(|r| r.0 < day);
        h.zone_temps.rows.retain(|r| r.0 < day);
        h
    }
}

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path} is damaged: {} (plan again with --from-scratch)", self.cause())]
    Decode {
        path: String,
        source: postcard::Error,
    },
    #[error("{path} is damaged: {} (plan again with --from-scratch)", self.cause())]
    NonFinite { path: String, what: &'static str },
    #[error("{path}: {source}")]
    Json {
        path: String,
        source: serde_json::Error,
    },
    #[error(
        "{path} is not a planned run folder: {missing} is missing (run `groutready plan` first)"
    )]
    NotARunFolder { path: String, missing: String },
    #[error(
        "{0} was planned by another version of groutready or its scene.json was edited: plan again"
    )]
    OtherVersion(String),
    #[error("{path}: {message}")]
    Schedules { path: String, message: String },
    #[error("encoding {what}: {source}")]
    Encode {
        what: &'static str,
        source: postcard::Error,
    },
}

impl CheckpointError {
    /// What is wrong with a damaged file, without its path.
    pub fn cause(&self) -> String {
        match self {
            CheckpointError::Decode { source, .. } => {
                format!("truncated or not written by this version of groutready: {source}")
            }
            CheckpointError::NonFinite { what, .. } => format!("it holds a non-finite {what}"),
            other => other.to_string(),
        }
    }
}

/// Writes any serde value as postcard.
pub fn write_file<T: Serialize + ?Sized>(
    path: &Path,
    value: &T,
    what: &'static str,
) -> Result<(), CheckpointError> {
    let bytes =
        postcard::to_stdvec(value).map_err(|source| CheckpointError::Encode { what, source })?;
    std::fs::write(path, bytes).map_err(|source| CheckpointError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Reads a postcard file written by [`write_file`].
pub fn read_file<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
        path: path.display().to_string(),
        source,
    })?;
    postcard::from_bytes(&bytes).map_err(|source| CheckpointError::Decode {
        path: path.display().to_string(),
        source,
    })
}

impl Checkpoint {
    /// The first state variable holding a NaN or an infinity, if any (a
    /// checkpoint is only written from a finished step, so this means the
    /// file was damaged or written by a broken run).
    pub fn non_finite(&self) -> Option<&'static str> {
        let bad = |v: &[f64]| v.iter().any(|x| !x.is_finite());
        if let Some(t) = &self.thermal {
            if bad(&t.state.temperature) {
                return Some("temperature");
            }
        }
        let m = self.mechanics.as_ref()?;
        if bad(&m.u) {
            return Some("displacement");
        }
        if m.stress.iter().any(|e| e.iter().any(|g| bad(g))) {
            return Some("stress");
        }
        if bad(&m.f_ext) || bad(&m.water_load) || bad(&m.f_contact) {
            return Some("nodal force");
        }
        if m.creep.iter().any(|c| c.omega.iter().any(|w| bad(w))) {
            return Some("creep strain");
        }
        m.joints
            .iter()
            .any(|j| !j.gap.is_finite() || bad(&j.force))
            .then_some("joint gap or force")
    }
}

impl Simulation<'_> {
    /// The state now; valid at the start of a whole day, before its events
    /// (where [`Simulation::run`] takes its checkpoints).
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            day: Day::containing(self.day),
            ladder: self.ladder,
            pours_done: self.pours_done,
            steps: self.steps,
            mech_steps: self.mech_steps,
            thermal: self.thermal.as_ref().map(|t| t.checkpoint()),
            mechanics: self.mechanics.as_ref().map(|m| m.state.clone()),
        }
    }

    pub fn history(&self) -> History {
        History {
            records: self.records.clone(),
            joint_records: self.joint_records.clone(),
            zone_temps: self.zone_temps.clone(),
        }
    }

    /// Continues from `ck` (taken from a run of the same scene) with this
    /// simulation's schedules; `history` supplies the rows before its day.
    /// The checkpoint must hold every effect this simulation has (the
    /// thermal part of a run restores from a checkpoint of the whole:
    /// `planner::Runner::simulate_temperatures`).
    pub fn restore(&mut self, ck: &Checkpoint, history: &History) {
        self.day = ck.day.t();
        self.ladder = ck.ladder;
        self.pours_done = ck.pours_done;
        self.steps = ck.steps;
        self.mech_steps = ck.mech_steps;
        if let (Some(th), Some(c)) = (self.thermal.as_mut(), &ck.thermal) {
            th.restore(c);
        }
        if let (Some(m), Some(c)) = (self.mechanics.as_mut(), &ck.mechanics) {
            m.restore(c);
        }
        let h = history.before(ck.day);
        self.records.rows = h.records.rows;
        self.joint_records.rows = h.joint_records.rows;
        self.zone_temps.rows = h.zone_temps.rows;
        self.checkpoints.retain(|c| c.day < ck.day);
        self.checkpoints.push(ck.clone());
        self.events_pending = true;
        self.thermal_ahead = false;
    }

    pub(super) fn maybe_checkpoint(&mut self) {
        if self.checkpoint_due() {
            let ck = self.checkpoint();
            self.keep_checkpoint(ck);
        }
    }

    /// Adds `ck` to the checkpoints kept, dropping those before
    /// `checkpoints_kept_from`.
    pub(super) fn keep_checkpoint(&mut self, ck: Checkpoint) {
        if let Some(from) = self.checkpoints_kept_from {
            self.checkpoints.retain(|c| c.day >= from);
        }
        self.checkpoints.push(ck);
    }

    /// The first day from which a checkpoint is due after the current
    /// day's (taken now if due): a mechanical step spanning several days
    /// ends there (`Simulation::mechanical_step_due`), so the step
    /// factorised ahead is foreseen to end there too.
    pub(super) fn next_checkpoint_from(&self) -> Option<f64> {
        match self.checkpoint_due_from() {
            Some(due) if self.day >= due => {
                self.checkpoint_due_after(Some(Day::containing(self.day)))
            }
            due => due,
        }
    }

    /// Is a checkpoint due at the current day?
    pub(super) fn checkpoint_due(&self) -> bool {
        self.checkpoint_due_from().is_some_and(|d| self.day >= d)
    }

    /// The first day from which the next checkpoint is due (None: no
    /// checkpoint is taken).
    pub(super) fn checkpoint_due_from(&self) -> Option<f64> {
        self.checkpoint_due_after(self.checkpoints.last().map(|c| c.day))
    }

    /// The first day from which a checkpoint is due after the one of day
    /// `last` (None: none taken yet): `checkpoint_on` if not passed, or
    /// `checkpoint_every` days after `last`.
    pub(super) fn checkpoint_due_after(&self, last: Option<Day>) -> Option<f64> {
        let on = self
            .checkpoint_on
            .filter(|&d| last.is_none_or(|l| l < d))
            .map(Day::t);
        let every = self
            .checkpoint_every
            .map(|every| last.map_or(Day(every), |l| l.plus(every)).t());
        on.into_iter().chain(every).reduce(f64::min)
    }
}
