//! The real terminal: raw mode and the alternate screen for the session's
//! life, restored on every way out (return, error, panic: ratatui's
//! `init` hooks the panic handler, and [`Restore`] covers the rest).

use std::time::Duration;

use ratatui::crossterm::event::{self, Event as CEvent};

use super::event::Event;
use super::session::Session;

/// Set, the loop panics after its first frame: how `tests/it/tui_tmux.rs`
/// proves the terminal is restored on a panic too.
pub const PANIC_TEST_VAR: &str = "GROUTREADY_TUI_PANIC_TEST";

/// Restores the terminal when dropped.
struct Restore;

impl Drop for Restore {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

/// Runs `session` until the engineer quits.
pub fn run_until_quit(session: &mut Session) -> std::io::Result<()> {
    let mut terminal = ratatui::try_init()?;
    let _restore = Restore;
    let panic_test = std::env::var_os(PANIC_TEST_VAR).is_some();
    loop {
        terminal.draw(|f| f.render_widget(&session.app, f.area()))?;
        if panic_test {
            panic!("{PANIC_TEST_VAR} is set: panicking after the first frame");
        }
        if session.app.quit {
            return Ok(());
        }
        // Short polls keep a running job's progress moving on screen.
        if event::poll(Duration::from_millis(100))? {
            match event::read()? {
                CEvent::Key(k) => session.handle(Event::Key(k)),
                CEvent::Resize(..) => {
                    terminal.autoresize()?;
                    session.handle(Event::Resize);
                }
                _ => {}
            }
        }
        session.pump();
    }
}
