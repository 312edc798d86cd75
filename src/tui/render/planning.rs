//! While the plan is computed: the baseline's progress and each remedy
//! re-simulation as it starts.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Gauge, Paragraph, Widget, Wrap};

use super::Theme;
use crate::scene::approximation;
use crate::tui::app::App;

pub fn render(app: &App, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let Some(p) = &app.planning else {
        return;
    };
    let block = Block::bordered().title(Span::styled(
        format!(" groutready · planning {} ", p.scene),
        theme.title(),
    ));
    let inner = block.inner(area);
    block.render(area, buf);
    // the approximations, when there are some, on lines of their own
    let caution = (!p.approximations.is_empty()).then(|| {
        format!(
            "With opt-in approximations of the mechanics: {}",
            approximation::describe(&p.approximations)
        )
    });
    let [head, gauge, list, keys] = Layout::vertical([
        Constraint::Length(if caution.is_some() { 4 } else { 2 }),
        Constraint::Length(1),
        Constraint::Min(0),
        Constraint::Length(1),
    ])
    .areas(inner);
    if let Some(e) = &p.error {
        Paragraph::new(vec![
            Line::from(Span::styled("The plan failed:", theme.error())),
            Line::from(e.clone()),
        ])
        .wrap(Wrap { trim: true })
        .render(head.union(list), buf);
        Paragraph::new(Span::styled(" q quit", theme.key())).render(keys, buf);
        return;
    }
    let mut lines = vec![Line::from(
        "Simulating the construction to the last zone due, then re-simulating \
         the remedies of the zones that are not groutable.",
    )];
    if let Some(c) = caution {
        lines.push(Line::from(Span::styled(c, theme.error())));
    }
    Paragraph::new(lines)
        .wrap(Wrap { trim: true })
        .render(head, buf);
    let (ratio, label) = match p.baseline {
        Some((day, end)) if end > 0.0 => (
            (day / end).clamp(0.0, 1.0),
            format!("baseline: day {day:.0} of {end:.0}"),
        ),
        _ => (0.0, "reading the inputs".to_string()),
    };
    let ratio = if p.resimulations.is_empty() {
        ratio
    } else {
        1.0
    };
    Gauge::default()
        .ratio(ratio)
        .label(label)
        .gauge_style(theme.key())
        .render(gauge, buf);
    let shown = list.height as usize;
    let lines: Vec<Line> = p
        .resimulations
        .iter()
        .enumerate()
        .skip(p.resimulations.len().saturating_sub(shown))
        .map(|(i, r)| Line::from(format!("re-simulation {}: {r}", i + 1)))
        .collect();
    Paragraph::new(lines).render(list, buf);
    Paragraph::new(Line::from(vec![
        Span::styled(" q", theme.key()),
        Span::raw(" quit (nothing is written until the plan is done)"),
    ]))
    .render(keys, buf);
}
