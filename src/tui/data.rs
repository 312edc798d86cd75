//! A planned run folder as the TUI holds it: the plan, the histories the
//! zone charts are drawn from, and what a what-if re-simulates from.

use std::path::{Path, PathBuf};

use crate::app::{self, restart, AppError};
use crate::mesh::Mesh;
use crate::planner::plan::zone_history;
use crate::planner::rules::{HistoryIndex, Rules};
use crate::planner::runner::Runner;
use crate::planner::{Plan, ZoneHistory, ZoneReadiness};
use crate::scene::Scene;
use crate::schedule::{DamLayout, Schedules};
use crate::sim::{Checkpoint, History};

use super::grid::Grid;

/// Everything shown, loaded once.
pub struct RunData {
    pub dir: PathBuf,
    pub scene: Scene,
    pub mesh: Mesh,
    pub layout: DamLayout,
    /// the schedules as planned
    pub schedules: Schedules,
    pub plan: Plan,
    pub history: History,
    pub checkpoints: Vec<Checkpoint>,
    pub grid: Grid,
}

impl RunData {
    /// Opens a run folder written by `groutready plan`.
    pub fn load(dir: &Path) -> Result<RunData, AppError> {
        let o = restart::open(dir)?;
        let mesh = app::build_mesh(&o.scene, &dir.display().to_string())?;
        let layout = app::dam_layout(&mesh);
        let grid = Grid::new(&layout, &o.schedules, &o.plan);
        Ok(RunData {
            dir: o.dir,
            scene: o.scene,
            mesh,
            layout,
            schedules: o.schedules,
            plan: o.plan,
            history: o.history,
            checkpoints: o.checkpoints,
            grid,
        })
    }

    /// The plan's readiness of a zone, if it is in the plan.
    pub fn readiness(&self, joint: u32, zone: u32) -> Option<&ZoneReadiness> {
        self.plan
            .zones
            .iter()
            .find(|z| z.joint == joint && z.zone == zone)
    }

    /// Aperture and temperature history of any zone of the run, to the
    /// zone's planned date or the end of the run.
    pub fn zone_history(&self, joint: u32, zone: u32) -> ZoneHistory {
        let rules = Rules::new(
            &self.plan.settings,
            &self.layout,
            &self.mesh,
            self.scene.epoch,
            &self.schedules,
        );
        let planned = self
            .schedules
            .grouting_of(joint, zone)
            .map_or(self.plan.as_of, |g| g.planned);
        zone_history(
            &rules,
            &HistoryIndex::new(&self.history),
            joint,
            zone,
            planned,
        )
    }

    /// A runner over the run's baseline, for a what-if.
    pub fn runner(&self) -> Runner<'_> {
        Runner::from_parts(
            &self.scene,
            &self.mesh,
            self.schedules.clone(),
            self.checkpoints.clone(),
            self.history.clone(),
        )
    }

    /// Lift range and elevations of a zone, for its title.
    pub fn zone_extent_text(&self, joint: u32, zone: u32) -> String {
        let lifts = self.layout.zone(joint, zone).map(|e| {
            let [(ba, a0, a1), (bb, b0, b1)] = e.sides();
            if (a0, a1) == (b0, b1) {
                format!("lifts {a0}–{a1}")
            } else {
                format!("lifts {a0}–{a1} of block {ba}, {b0}–{b1} of block {bb}")
            }
        });
        let el = self
            .mesh
            .zones
            .iter()
            .find(|z| z.joint == joint && z.zone == zone)
            .map(|z| format!("EL {:.0}–{:.0} m", z.z_bottom, z.z_top));
        [lifts, el]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" · ")
    }
}
