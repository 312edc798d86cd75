//! The zones that are not groutable, by planned date, each with the rules
//! it fails and its remedy in brief; the reasons and the remedy of the
//! selected one in full below the table.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Row, Table, Widget, Wrap};

use super::Theme;
use crate::report::words::{failed_rules, remedy_brief, remedy_short, verified_words};
use crate::tui::app::App;

pub fn render(app: &App, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let flagged = app.flagged();
    let [table_area, detail] =
        Layout::vertical([Constraint::Min(4), Constraint::Length(7)]).areas(area);
    let block = Block::bordered().title(Span::styled(
        format!(
            " Not groutable on the planned date: {} zones ",
            flagged.len()
        ),
        theme.title(),
    ));
    if flagged.is_empty() {
        Paragraph::new("Every zone still to grout is groutable on its planned date.")
            .block(block)
            .render(area, buf);
        return;
    }
    let rows_vis = table_area.height.saturating_sub(3) as usize;
    let first = if rows_vis == 0 {
        0
    } else {
        app.flagged_row.saturating_sub(rows_vis - 1)
    };
    let rows: Vec<Row> = flagged
        .iter()
        .enumerate()
        .skip(first)
        .map(|(i, z)| {
            let style = if i == app.flagged_row {
                theme.selected()
            } else {
                theme.verdict(z.verdict)
            };
            Row::new(vec![
                format!("{:>5}", z.joint),
                format!("{:>4}", z.zone),
                z.planned.to_string(),
                failed_rules(z),
                z.remedy
                    .as_ref()
                    .map_or("not searched".into(), remedy_brief),
            ])
            .style(style)
        })
        .collect();
    // No aperture column: the rules that fail and the remedy are what the
    // list is read for (the values are in the detail below).
    let header = Row::new(vec!["Joint", "Zone", "Planned", "Fails", "Remedy"]).style(theme.dim());
    Table::new(
        rows,
        [
            Constraint::Length(5),
            Constraint::Length(4),
            Constraint::Length(10),
            Constraint::Length(28),
            Constraint::Min(10),
        ],
    )
    .header(header)
    .block(block)
    .render(table_area, buf);

    let Some(z) = flagged.get(app.flagged_row) else {
        return;
    };
    let mut lines = vec![Line::from(Span::styled(
        format!("Joint {} zone {} · {}", z.joint, z.zone, z.planned),
        theme.title(),
    ))];
    for c in z.checks.iter().filter(|c| !c.passed) {
        if let Some(r) = &c.reason {
            lines.push(Line::from(vec![
                Span::styled("✗ ", theme.pass(false)),
                Span::raw(r.clone()),
            ]));
        }
    }
    if let Some(r) = &z.remedy {
        let mut s = format!("Remedy: {}", remedy_short(r));
        if let Some(v) = verified_words(r) {
            s.push_str(&format!(" ({v})"));
        }
        lines.push(Line::from(Span::styled(s, theme.key())));
    }
    Paragraph::new(lines)
        .wrap(Wrap { trim: true })
        .block(Block::bordered().title(" Enter: open the zone "))
        .render(detail, buf);
}
