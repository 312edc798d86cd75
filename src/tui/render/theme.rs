//! Colours, and what replaces them under `NO_COLOR`: every state also has a
//! symbol, so colour only ever repeats what the text says.

use ratatui::style::{Color, Modifier, Style};

use crate::planner::Verdict;
use crate::tui::grid::CellState;

#[derive(Debug, Clone, Copy)]
pub struct Theme {
    pub color: bool,
}

impl Theme {
    fn fg(&self, c: Color) -> Style {
        if self.color {
            Style::new().fg(c)
        } else {
            Style::new()
        }
    }

    pub fn state(&self, s: CellState) -> Style {
        match s {
            CellState::NotGroutable => self.fg(Color::Red).add_modifier(Modifier::BOLD),
            CellState::Marginal => self.fg(Color::Yellow),
            CellState::Groutable => self.fg(Color::Green),
            CellState::Grouted => self.fg(Color::Blue),
            CellState::Reopened => self.fg(Color::Magenta).add_modifier(Modifier::BOLD),
            CellState::Later | CellState::NotPoured => self.fg(Color::DarkGray),
        }
    }

    pub fn verdict(&self, v: Verdict) -> Style {
        self.state(match v {
            Verdict::NotGroutable => CellState::NotGroutable,
            Verdict::Marginal => CellState::Marginal,
            Verdict::Groutable => CellState::Groutable,
        })
    }

    pub fn pass(&self, passed: bool) -> Style {
        if passed {
            self.fg(Color::Green)
        } else {
            self.fg(Color::Red).add_modifier(Modifier::BOLD)
        }
    }

    /// The cursor: reverse video reads on any terminal, coloured or not.
    pub fn selected(&self) -> Style {
        Style::new().add_modifier(Modifier::REVERSED)
    }

    pub fn title(&self) -> Style {
        self.fg(Color::Cyan).add_modifier(Modifier::BOLD)
    }

    pub fn dim(&self) -> Style {
        self.fg(Color::DarkGray)
    }

    pub fn key(&self) -> Style {
        self.fg(Color::Yellow).add_modifier(Modifier::BOLD)
    }

    pub fn error(&self) -> Style {
        self.fg(Color::Red).add_modifier(Modifier::BOLD)
    }

    /// Chart lines: upstream, centre, downstream, deciding point of a what-if.
    pub fn series(&self, i: usize) -> Style {
        self.fg([Color::Cyan, Color::Green, Color::Magenta, Color::Yellow][i % 4])
    }

    /// The curve the aperture rule reads (the zone's minimum).
    pub fn min_curve(&self) -> Style {
        self.fg(Color::White).add_modifier(Modifier::BOLD)
    }

    /// The remedy's verified run.
    pub fn remedy(&self) -> Style {
        self.fg(Color::LightBlue)
    }

    /// The limit lines (0.5 mm, closure + tolerance) and the planned date.
    pub fn limit(&self) -> Style {
        self.fg(Color::Red)
    }

    /// Joint-meter readings on the aperture chart.
    pub fn meter(&self) -> Style {
        self.fg(Color::White).add_modifier(Modifier::BOLD)
    }

    pub fn marker(&self) -> Style {
        self.fg(Color::Yellow)
    }
}
