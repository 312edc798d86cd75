//! The TUI's state. Changed only by [`App::update`] (`update.rs`), drawn by
//! `render/` (which never changes it).

use std::sync::Arc;

use chrono::NaiveDate;

use crate::planner::whatif::WhatIfOutcome;
use crate::planner::{ZoneHistory, ZoneReadiness};

use super::data::RunData;

/// The panes, in Tab order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pane {
    Overview,
    Flagged,
    Zone,
}

impl Pane {
    pub const ALL: [Pane; 3] = [Pane::Overview, Pane::Flagged, Pane::Zone];
}

/// The plan being computed before anything can be shown.
#[derive(Debug, Clone, Default)]
pub struct Planning {
    pub scene: String,
    /// baseline (day, end)
    pub baseline: Option<(f64, f64)>,
    /// remedy re-simulations started so far
    pub resimulations: Vec<String>,
    pub error: Option<String>,
    /// the scene's opt-in approximations of the mechanics (empty: exact)
    pub approximations: Vec<crate::scene::Approximation>,
}

/// Which what-if field the arrows change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    Supercool,
    Date,
}

/// A what-if job in the background.
#[derive(Debug, Clone, PartialEq)]
pub struct Running {
    pub first_day: Option<f64>,
    pub day: f64,
    pub end: f64,
    pub cancelling: bool,
}

impl Running {
    /// Fraction done, from the day the re-simulation restarted.
    pub fn fraction(&self) -> f64 {
        match self.first_day {
            Some(f) if self.end > f => ((self.day - f) / (self.end - f)).clamp(0.0, 1.0),
            _ => 0.0,
        }
    }
}

/// The what-if form of the open zone.
#[derive(Debug, Clone)]
pub struct WhatIfForm {
    pub field: Field,
    pub supercool_c: f64,
    pub date: NaiveDate,
    pub running: Option<Running>,
    pub result: Option<Box<WhatIfOutcome>>,
    /// last job's failure or cancellation, or where the schedules were saved
    pub message: Option<String>,
}

/// The zone shown in the Zone pane.
#[derive(Debug, Clone)]
pub struct ZoneView {
    pub joint: u32,
    pub zone: u32,
    pub planned: Option<NaiveDate>,
    /// the plan's readiness (None: the zone is not in the plan's horizon)
    pub readiness: Option<ZoneReadiness>,
    pub history: ZoneHistory,
    pub whatif: Option<WhatIfForm>,
}

/// The `/` prompt.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Prompt {
    pub text: String,
    pub error: Option<String>,
}

/// The whole state.
pub struct App {
    /// None while the plan is being computed
    pub data: Option<Arc<RunData>>,
    pub planning: Option<Planning>,
    pub pane: Pane,
    /// overview cursor (joint column, zone row; row 0 the lowest zone)
    pub cursor: (usize, usize),
    /// selected row of the flagged list
    pub flagged_row: usize,
    pub zone: Option<ZoneView>,
    pub prompt: Option<Prompt>,
    pub help: bool,
    /// one line at the bottom: what just happened
    pub status: Option<String>,
    /// false under NO_COLOR: symbols and modifiers only
    pub color: bool,
    pub quit: bool,
}

impl App {
    /// An app showing a planned run.
    pub fn open(data: Arc<RunData>, color: bool) -> App {
        let mut app = App::empty(color);
        app.show(data);
        app
    }

    /// An app waiting for a plan of `scene`.
    pub fn planning(scene: &str, color: bool) -> App {
        let mut app = App::empty(color);
        app.planning = Some(Planning {
            scene: scene.to_string(),
            ..Default::default()
        });
        app
    }

    fn empty(color: bool) -> App {
        App {
            data: None,
            planning: None,
            pane: Pane::Overview,
            cursor: (0, 0),
            flagged_row: 0,
            zone: None,
            prompt: None,
            help: false,
            status: None,
            color,
            quit: false,
        }
    }

    /// Shows `data`, the cursor on the first flagged zone (else the lowest
    /// zone still to grout, else the bottom-left cell).
    pub(super) fn show(&mut self, data: Arc<RunData>) {
        let first = data
            .run
            .plan
            .flagged()
            .next()
            .or_else(|| data.run.plan.to_grout().next())
            .and_then(|z| data.grid.position(z.joint, z.zone));
        self.cursor = first.unwrap_or((0, 0));
        self.planning = None;
        self.data = Some(data);
    }

    /// The flagged zones, by planned date (the plan's order).
    pub fn flagged(&self) -> Vec<&ZoneReadiness> {
        self.data
            .as_ref()
            .map(|d| d.run.plan.flagged().collect())
            .unwrap_or_default()
    }

    /// The what-if job running, if any.
    pub fn running(&self) -> Option<&Running> {
        self.zone.as_ref()?.whatif.as_ref()?.running.as_ref()
    }
}
