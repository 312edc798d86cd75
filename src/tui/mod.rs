//! `groutready tui`: the planner's answer for site engineers in a terminal.
//!
//! The dam at a glance (joints across, zones up, each cell the aperture on
//! the planned date and its readiness), the flagged zones, one zone's
//! aperture and temperature histories with its rules and remedy, and
//! what-ifs re-simulated in the background from the run's checkpoints.
//!
//! The pieces, state apart from drawing (gitui / ratatui demo style):
//! - [`data`]: the run folder, loaded once; [`grid`]: the overview's cells;
//! - [`app`]: the state; [`update`](App::update): keys and job reports change
//!   it and return [`Command`]s; `render/`: `impl Widget for &App`, which
//!   never changes it;
//! - [`session`]: the state plus its background jobs, without a terminal
//!   (what the tests drive); [`terminal`]: the crossterm loop around it.
//!
//! Verified by `tests/it/tui_screens.rs` (snapshots of every screen at
//! 80×24 on the small dam, key sequences, a what-if run and one cancelled)
//! and `tests/it/tui_tmux.rs` (the binary in tmux on the demo).

pub mod app;
pub mod data;
pub mod event;
pub mod grid;
pub mod render;
pub mod session;
pub mod terminal;
mod update;

pub use app::{App, Pane};
pub use data::RunData;
pub use event::{Command, Event, JobEvent};
pub use session::Session;

/// Colour unless `NO_COLOR` is set to anything non-empty (no-color.org).
pub fn color_wanted() -> bool {
    std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
}
