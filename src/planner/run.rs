//! A finished plan with what it was made from: the one door through which a
//! viewer (the terminal UI) reads zone histories and runs what-ifs, without
//! reaching for the rules, history index or runner inside the planner.

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, OnceLock};

use chrono::NaiveDate;

use crate::mechanics::Frame;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::schedule::{DamLayout, Schedules};
use crate::sim::{Checkpoint, History, SimError};
use crate::vocab::ZoneId;

use super::plan::zone_history;
use super::readiness::{Plan, ZoneHistory, ZoneReadiness};
use super::rules::{HistoryIndex, Rules};
use super::runner::Runner;
use super::whatif::{self, WhatIf, WhatIfOutcome};

/// A plan, its scene, mesh and schedules, the baseline's histories and the
/// checkpoints a what-if restarts from.
pub struct PlannedRun {
    pub scene: Scene,
    pub mesh: Mesh,
    pub layout: DamLayout,
    /// the schedules as planned
    pub schedules: Schedules,
    pub plan: Plan,
    pub history: History,
    pub checkpoints: Vec<Checkpoint>,
    /// the scene's mechanical frame, kept from the first what-if for the
    /// next ones ([`Runner::with_frame`])
    frame: OnceLock<Arc<Frame>>,
}

impl PlannedRun {
    /// A plan with what it was made from (as `groutready plan` leaves it
    /// in its run folder).
    pub fn new(
        scene: Scene,
        mesh: Mesh,
        schedules: Schedules,
        plan: Plan,
        history: History,
        checkpoints: Vec<Checkpoint>,
    ) -> PlannedRun {
        PlannedRun {
            layout: crate::sim::dam_layout(&mesh),
            scene,
            mesh,
            schedules,
            plan,
            history,
            checkpoints,
            frame: OnceLock::new(),
        }
    }

    /// The plan's readiness of a zone, if it is in the plan.
    pub fn readiness(&self, zone: ZoneId) -> Option<&ZoneReadiness> {
        self.plan.zones.iter().find(|z| z.zone_id() == zone)
    }

    /// The zone's planned grouting date, if `grouting.csv` has one.
    pub fn planned(&self, zone: ZoneId) -> Option<NaiveDate> {
        self.schedules.grouting_of(zone).map(|g| g.planned)
    }

    /// Aperture and temperature history of any zone of the run, to the
    /// zone's planned date or the end of the run.
    pub fn zone_history(&self, zone: ZoneId) -> ZoneHistory {
        let rules = Rules::new(
            &self.plan.settings,
            &self.layout,
            &self.mesh,
            self.scene.epoch,
            &self.schedules,
        );
        let planned = self.planned(zone).unwrap_or(self.plan.as_of);
        zone_history(&rules, &HistoryIndex::new(&self.history), zone, planned)
    }

    /// Runs a what-if from the baseline's latest checkpoint before its edit
    /// (see [`whatif::run`]); `cancel` stops it between steps.
    pub fn what_if(
        &self,
        w: &WhatIf,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(f64, f64),
    ) -> Result<WhatIfOutcome, SimError> {
        let runner = Runner::from_parts(
            &self.scene,
            &self.mesh,
            self.schedules.clone(),
            self.checkpoints.clone(),
            self.history.clone(),
        )
        .with_frame(self.frame.get().cloned());
        let outcome = whatif::run(&runner, &self.layout, self.plan.as_of, w, cancel, progress);
        if let Some(f) = runner.into_frame() {
            let _ = self.frame.set(f);
        }
        outcome
    }
}
