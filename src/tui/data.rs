//! A planned run folder as the TUI holds it: the plan, the histories the
//! zone charts are drawn from, and what a what-if re-simulates from.

use std::path::{Path, PathBuf};

use crate::app::{self, restart, AppError};
use crate::planner::PlannedRun;
use crate::vocab::ZoneId;

use super::grid::Grid;

/// Everything shown, loaded once.
pub struct RunData {
    pub dir: PathBuf,
    pub run: PlannedRun,
    pub grid: Grid,
}

impl RunData {
    /// Opens a run folder written by `groutready plan`.
    pub fn load(dir: &Path) -> Result<RunData, AppError> {
        let o = restart::open(dir)?;
        let mesh = app::build_mesh(&o.scene, &dir.display().to_string())?;
        let run = PlannedRun::new(o.scene, mesh, o.schedules, o.plan, o.history, o.checkpoints);
        let grid = Grid::new(&run.layout, &run.schedules, &run.plan);
        Ok(RunData {
            dir: o.dir,
            run,
            grid,
        })
    }

    /// Lift range and elevations of a zone, for its title.
    pub fn zone_extent_text(&self, id: ZoneId) -> String {
        let lifts = self.run.layout.zone(id).map(|e| {
            let [(ba, a0, a1), (bb, b0, b1)] = e.sides();
            if (a0, a1) == (b0, b1) {
                format!("lifts {a0}–{a1}")
            } else {
                format!("lifts {a0}–{a1} of block {ba}, {b0}–{b1} of block {bb}")
            }
        });
        let el = self
            .run
            .mesh
            .zones
            .iter()
            .find(|z| z.zone_id() == id)
            .map(|z| format!("EL {:.0}–{:.0} m", z.z_bottom, z.z_top));
        [lifts, el]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" · ")
    }
}
