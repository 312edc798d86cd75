//! Drawing the state: `impl Widget for &App`. Nothing here changes the
//! state; scrolling is derived from the cursor, so a frame depends on the
//! state and the terminal size alone.
//!
//! Every screen fits 80×24: a header, the pane tabs, the pane, a status or
//! prompt line and the keys of the pane.

mod chart;
mod flagged;
mod help;
mod overview;
mod planning;
mod theme;
mod zone;

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Style;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use crate::report::summary::Summary;

use super::app::{App, Field, Pane};
pub use theme::Theme;

impl Widget for &App {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let theme = Theme { color: self.color };
        let [header, tabs, body, status, keys] = Layout::vertical([
            Constraint::Length(1),
            Constraint::Length(1),
            Constraint::Min(0),
            Constraint::Length(1),
            Constraint::Length(1),
        ])
        .areas(area);
        let Some(data) = &self.data else {
            planning::render(self, &theme, area, buf);
            if self.help {
                help::render(&theme, area, buf);
            }
            return;
        };
        let s = Summary::of(&data.run.plan);
        Paragraph::new(Line::from(vec![
            Span::styled("groutready", theme.title()),
            Span::raw(format!(
                " · {} · as of {} · {} of {} to grout flagged",
                data.run.plan.scene, data.run.plan.as_of, s.flagged, s.to_grout
            )),
            Span::raw(if s.marginal > 0 {
                format!(", {} marginal", s.marginal)
            } else {
                String::new()
            }),
            // the reports say which approximations; the header that there
            // are some, since they decide zones near a limit
            if data.run.plan.approximations.is_empty() {
                Span::raw("")
            } else {
                Span::styled(" · ! approximate mechanics", theme.error())
            },
        ]))
        .render(header, buf);
        render_tabs(self, &theme, s.flagged, tabs, buf);
        match self.pane {
            Pane::Overview => overview::render(self, data, &theme, body, buf),
            Pane::Flagged => flagged::render(self, &theme, body, buf),
            Pane::Zone => zone::render(self, data, &theme, body, buf),
        }
        render_status(self, &theme, status, buf);
        Paragraph::new(keys_line(self, &theme)).render(keys, buf);
        if self.help {
            help::render(&theme, body, buf);
        }
    }
}

fn render_tabs(app: &App, theme: &Theme, flagged: usize, area: Rect, buf: &mut Buffer) {
    let zone = app
        .zone
        .as_ref()
        .map(|z| format!("3 Zone {}·{}", z.joint, z.zone))
        .unwrap_or_else(|| "3 Zone –".into());
    let names = [
        "1 Overview".to_string(),
        format!("2 Flagged ({flagged})"),
        zone,
    ];
    let mut spans = Vec::new();
    for (pane, name) in Pane::ALL.into_iter().zip(names) {
        let style = if pane == app.pane {
            theme.selected()
        } else if pane == Pane::Zone && app.zone.is_none() {
            theme.dim()
        } else {
            Style::new()
        };
        spans.push(Span::raw(" "));
        spans.push(Span::styled(format!(" {name} "), style));
    }
    Paragraph::new(Line::from(spans)).render(area, buf);
}

fn render_status(app: &App, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let line = if let Some(p) = &app.prompt {
        let mut spans = vec![
            Span::styled("/ jump to joint [zone]: ", theme.key()),
            Span::raw(format!("{}█", p.text)),
        ];
        if let Some(e) = &p.error {
            spans.push(Span::styled(format!("  {e}"), theme.error()));
        }
        Line::from(spans)
    } else if let Some(s) = &app.status {
        Line::from(Span::styled(s.clone(), theme.dim()))
    } else {
        Line::default()
    };
    Paragraph::new(line).render(area, buf);
}

/// The keys of the current pane, most used first (cut at the right edge).
fn keys_line(app: &App, theme: &Theme) -> Line<'static> {
    let keys: &[(&str, &str)] = if app.prompt.is_some() {
        &[("Enter", "go"), ("Esc", "cancel")]
    } else if app.help {
        &[("Esc", "close help"), ("q", "quit")]
    } else {
        match app.pane {
            Pane::Overview => &[
                ("←↓↑→", "move"),
                ("Enter", "open zone"),
                ("Tab", "pane"),
                ("/", "jump"),
                ("?", "help"),
                ("q", "quit"),
            ],
            Pane::Flagged => &[
                ("↑↓", "select"),
                ("Enter", "open zone"),
                ("Tab", "pane"),
                ("/", "jump"),
                ("?", "help"),
                ("q", "quit"),
            ],
            Pane::Zone => match app.zone.as_ref().and_then(|z| z.whatif.as_ref()) {
                Some(f) if f.running.is_some() => {
                    &[("c", "cancel"), ("Tab", "pane"), ("q", "quit")]
                }
                Some(f) if f.field == Field::Date => &[
                    ("↑↓", "field"),
                    ("←→", "−/+ day"),
                    ("PgUp/PgDn", "−/+ week"),
                    ("Enter", "re-simulate"),
                    ("s", "save"),
                    ("Esc", "close"),
                ],
                Some(_) => &[
                    ("↑↓", "field"),
                    ("←→", "less/more"),
                    ("Enter", "re-simulate"),
                    ("s", "save"),
                    ("Esc", "close"),
                    ("q", "quit"),
                ],
                None => &[
                    ("w", "what-if"),
                    ("←↓↑→", "next zone"),
                    ("Esc", "back"),
                    ("Tab", "pane"),
                    ("?", "help"),
                    ("q", "quit"),
                ],
            },
        }
    };
    let mut spans = Vec::new();
    for (k, what) in keys {
        spans.push(Span::styled(format!(" {k}"), theme.key()));
        spans.push(Span::raw(format!(" {what} ")));
    }
    Line::from(spans)
}
