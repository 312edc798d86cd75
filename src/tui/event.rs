//! What reaches the TUI's state (keys, terminal size, background jobs) and
//! what the state asks the runtime to do.

use std::path::PathBuf;
use std::sync::Arc;

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use crate::planner::whatif::{WhatIf, WhatIfOutcome};

use super::data::RunData;

/// An input to [`super::App::update`].
pub enum Event {
    Key(KeyEvent),
    /// the terminal was resized (the next frame lays out anew)
    Resize,
    Job(JobEvent),
}

impl Event {
    /// A key press without modifiers.
    pub fn key(code: KeyCode) -> Event {
        Event::Key(KeyEvent::new(code, KeyModifiers::NONE))
    }

    pub fn char(c: char) -> Event {
        Event::key(KeyCode::Char(c))
    }
}

/// What background work reports.
pub enum JobEvent {
    /// the plan's baseline reached `day` of `end`
    PlanBaseline {
        day: f64,
        end: f64,
    },
    /// the plan started a remedy re-simulation
    PlanResimulation(String),
    Planned(Arc<RunData>),
    PlanFailed(String),
    WhatIfProgress {
        day: f64,
        end: f64,
    },
    WhatIfDone(Box<WhatIfOutcome>),
    WhatIfCancelled,
    WhatIfFailed(String),
    Saved(PathBuf),
    SaveFailed(String),
}

/// Work the state asks for; the runtime carries it out and answers with
/// [`JobEvent`]s.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    RunWhatIf(WhatIf),
    CancelWhatIf,
    /// write the what-if's schedules as a new CSV set
    SaveWhatIf,
}
