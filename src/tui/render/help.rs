//! The keys, over the current pane.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Widget};

use super::Theme;

/// (where, keys, what they do).
pub const KEYS: [(&str, &str, &str); 13] = [
    (
        "Everywhere",
        "Tab S-Tab",
        "next / previous pane (1 2 3: straight)",
    ),
    ("", "/", "jump: 5 = joint 5 · 5 3 = joint 5 zone 3"),
    ("", "?  Esc", "this help · close it"),
    ("", "q  Ctrl-C", "quit"),
    (
        "Overview",
        "←↓↑→ hjkl",
        "move (↑ is up the dam) · Enter open",
    ),
    ("Flagged", "↑↓ jk", "select · Enter open the zone"),
    ("Zone", "←↓↑→ hjkl", "next zone · w what-if · Esc back"),
    ("What-if", "↑↓ jk", "supercooling ΔT or grouting date"),
    ("", "←→ hl - +", "change it: → more cooling, a later day"),
    ("", "PgDn PgUp", "date a week later · a week earlier"),
    ("", "Enter", "re-simulate from the checkpoint"),
    ("", "c  Esc", "cancel the re-simulation"),
    ("", "s", "save the schedules as a CSV set"),
];

pub fn render(theme: &Theme, area: Rect, buf: &mut Buffer) {
    let w = 66.min(area.width);
    let h = (KEYS.len() as u16 + 2).min(area.height);
    let popup = Rect {
        x: area.x + (area.width - w) / 2,
        y: area.y + (area.height - h) / 2,
        width: w,
        height: h,
    };
    Clear.render(popup, buf);
    let lines: Vec<Line> = KEYS
        .iter()
        .map(|(pane, k, what)| {
            Line::from(vec![
                Span::styled(format!("{pane:<11}"), theme.title()),
                Span::styled(format!("{k:<11}"), theme.key()),
                Span::raw(*what),
            ])
        })
        .collect();
    Paragraph::new(lines)
        .block(Block::bordered().title(Span::styled(" Keys ", theme.title())))
        .render(popup, buf);
}
