//! The dam overview's grid: one cell per (joint, zone), joints left bank →
//! right bank across (block 1 is at the left abutment), zones bottom → top,
//! each with the state the engineer reads at a glance.

use chrono::NaiveDate;

use crate::planner::{Plan, Verdict};
use crate::report::words::deciding_aperture;
use crate::schedule::{DamLayout, Schedules};
use crate::vocab::ZoneId;

/// What a cell shows; the order is the legend's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellState {
    /// still to grout and not groutable (short of the aperture or another rule)
    NotGroutable,
    /// groutable, but below the marginal aperture
    Marginal,
    Groutable,
    /// grouted before the as-of date
    Grouted,
    /// grouted before the as-of date and opened again since
    Reopened,
    /// poured, planned after the plan's horizon (or not in grouting.csv)
    Later,
    /// some lift of the zone is not poured by the as-of date
    NotPoured,
}

impl CellState {
    pub const ALL: [CellState; 7] = [
        CellState::NotGroutable,
        CellState::Marginal,
        CellState::Groutable,
        CellState::Grouted,
        CellState::Reopened,
        CellState::Later,
        CellState::NotPoured,
    ];

    /// One character that tells the state without colour.
    pub fn symbol(self) -> &'static str {
        match self {
            CellState::NotGroutable => "✗",
            CellState::Marginal => "~",
            CellState::Groutable => "✓",
            CellState::Grouted => "■",
            CellState::Reopened => "!",
            CellState::Later => "○",
            CellState::NotPoured => "·",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            CellState::NotGroutable => "not groutable",
            CellState::Marginal => "marginal",
            CellState::Groutable => "groutable",
            CellState::Grouted => "grouted",
            CellState::Reopened => "re-opened",
            CellState::Later => "later",
            CellState::NotPoured => "not poured",
        }
    }
}

/// One zone of one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    pub joint: u32,
    pub zone: u32,
    pub state: CellState,
    /// aperture at the deciding point on the planned date \[mm\]
    pub aperture_mm: Option<f64>,
    pub planned: Option<NaiveDate>,
}

/// The grid, `cells[zone_row][joint_col]`, row 0 the lowest zone.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Grid {
    pub joints: Vec<u32>,
    pub zones: Vec<u32>,
    pub cells: Vec<Vec<Option<Cell>>>,
}

impl Grid {
    pub fn new(layout: &DamLayout, schedules: &Schedules, plan: &Plan) -> Grid {
        let joints = layout.joints();
        let mut zones: Vec<u32> = layout.zones.iter().map(|z| z.zone).collect();
        zones.sort_unstable();
        zones.dedup();
        let poured_by = |block: u32, lift: u32| {
            schedules
                .pours
                .iter()
                .find(|p| p.block == block && p.lift == lift)
                .is_some_and(|p| p.date < plan.as_of)
        };
        let cells = zones
            .iter()
            .map(|&zone| {
                joints
                    .iter()
                    .map(|&joint| {
                        let ext = layout.zone(ZoneId::new(joint, zone))?;
                        let planned = schedules
                            .grouting_of(ZoneId::new(joint, zone))
                            .map(|g| g.planned);
                        let r = plan
                            .zones
                            .iter()
                            .find(|z| z.joint == joint && z.zone == zone);
                        let poured = ext.sides().iter().all(|&(b, _, top)| poured_by(b, top));
                        let state = match r {
                            Some(r) if r.history && r.reopened.is_some() => CellState::Reopened,
                            Some(r) if r.history => CellState::Grouted,
                            Some(r) => match r.verdict {
                                Verdict::NotGroutable => CellState::NotGroutable,
                                Verdict::Marginal => CellState::Marginal,
                                Verdict::Groutable => CellState::Groutable,
                            },
                            None if !poured => CellState::NotPoured,
                            None => CellState::Later,
                        };
                        Some(Cell {
                            joint,
                            zone,
                            state,
                            aperture_mm: r
                                .and_then(|r| deciding_aperture(r, plan.settings.aperture_point)),
                            planned,
                        })
                    })
                    .collect()
            })
            .collect();
        Grid {
            joints,
            zones,
            cells,
        }
    }

    pub fn cell(&self, col: usize, row: usize) -> Option<&Cell> {
        self.cells.get(row)?.get(col)?.as_ref()
    }

    /// Column and row of a (joint, zone).
    pub fn position(&self, joint: u32, zone: u32) -> Option<(usize, usize)> {
        let col = self.joints.iter().position(|&j| j == joint)?;
        let row = self.zones.iter().position(|&z| z == zone)?;
        Some((col, row))
    }

    /// How many cells are in each state.
    pub fn count(&self, state: CellState) -> usize {
        self.cells
            .iter()
            .flatten()
            .flatten()
            .filter(|c| c.state == state)
            .count()
    }
}
