//! The dam seen from upstream: joints left bank → right bank across, zones
//! bottom → top, each cell the aperture at the zone's planned date.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Widget};

use super::Theme;
use crate::report::words::{mm, remedy_short, verdict_symbol, verdict_words};
use crate::tui::app::App;
use crate::tui::data::RunData;
use crate::tui::grid::{Cell, CellState};
use crate::vocab::ZoneId;

/// Columns of the zone labels and of one cell (`✗0.40` and a space).
const LABEL_W: u16 = 5;
const CELL_W: u16 = 6;

pub fn render(app: &App, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let [grid_area, info, legend] = Layout::vertical([
        Constraint::Min(5),
        Constraint::Length(1),
        Constraint::Length(2),
    ])
    .areas(area);
    let block = Block::bordered().title(Span::styled(
        " Aperture at the planned date [mm] · seen from upstream ",
        theme.title(),
    ));
    let inner = block.inner(grid_area);
    block.render(grid_area, buf);
    render_grid(app, data, theme, inner, buf);
    render_info(app, data, theme, info, buf);
    Paragraph::new(legend_lines(theme, legend.width as usize)).render(legend, buf);
}

/// The legend, items packed into lines of `width` (an item never splits).
fn legend_lines(theme: &Theme, width: usize) -> Vec<Line<'static>> {
    let mut lines = vec![Line::default()];
    let mut used = 0;
    for s in CellState::ALL {
        let text = format!(" {}  ", s.label());
        let w = 1 + text.chars().count();
        if used > 0 && used + w > width {
            lines.push(Line::default());
            used = 0;
        }
        let line = lines.last_mut().expect("one line at least");
        line.push_span(Span::styled(s.symbol(), theme.state(s)));
        line.push_span(Span::raw(text));
        used += w;
    }
    lines
}

/// The first of `n` items to show in `visible` places so `cursor` is seen.
fn scroll(cursor: usize, visible: usize, n: usize) -> usize {
    if visible == 0 || n <= visible {
        0
    } else {
        cursor.saturating_sub(visible - 1).min(n - visible)
    }
}

fn cell_text(c: &Cell) -> String {
    let value = match (c.state, c.aperture_mm) {
        (CellState::NotPoured | CellState::Later, _) => String::new(),
        (_, Some(a)) if a < 9.995 => format!("{a:.2}"),
        (_, Some(a)) => format!("{a:.1}"),
        (_, None) => "–".into(),
    };
    format!("{}{value}", c.state.symbol())
}

fn render_grid(app: &App, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let g = &data.grid;
    if area.height < 3 || area.width <= LABEL_W {
        return;
    }
    let cols_vis = ((area.width - LABEL_W) / CELL_W) as usize;
    let rows_vis = (area.height - 2) as usize;
    let (cc, cr) = app.cursor;
    let c0 = scroll(cc, cols_vis, g.joints.len());
    let r0 = scroll(cr, rows_vis, g.zones.len());
    let cols = c0..(c0 + cols_vis).min(g.joints.len());
    let rows = r0..(r0 + rows_vis).min(g.zones.len());

    let mut lines = Vec::new();
    let mut head = vec![Span::styled(format!("{:>4} ", "zone"), theme.dim())];
    for c in cols.clone() {
        let style = if c == cc { theme.title() } else { theme.dim() };
        head.push(Span::styled(
            format!("{:<w$}", format!("J{}", g.joints[c]), w = CELL_W as usize),
            style,
        ));
    }
    lines.push(Line::from(head));
    for r in rows.clone().rev() {
        let mut spans = vec![Span::styled(format!("{:>4} ", g.zones[r]), theme.dim())];
        for c in cols.clone() {
            let (text, style) = match g.cell(c, r) {
                Some(cell) => (cell_text(cell), theme.state(cell.state)),
                None => (String::new(), theme.dim()),
            };
            let style = if (c, r) == (cc, cr) {
                style.patch(theme.selected())
            } else {
                style
            };
            spans.push(Span::styled(format!("{text:<5}"), style));
            spans.push(Span::raw(" "));
        }
        lines.push(Line::from(spans));
    }
    // ◀ and ▶ at the edges when joints are off screen; ▲ ▼ for zones.
    let width = area.width as usize;
    let mut mid = format!("{:>3} left bank → right bank", "");
    if rows.end < g.zones.len() {
        mid.push_str(" ▲ higher zones");
    }
    if r0 > 0 {
        mid.push_str(" ▼ lower zones");
    }
    let mid: String = mid.chars().take(width.saturating_sub(2)).collect();
    let fill = width.saturating_sub(2 + mid.chars().count());
    lines.push(Line::from(Span::styled(
        format!(
            "{}{mid}{}{}",
            if c0 > 0 { "◀" } else { " " },
            " ".repeat(fill),
            if cols.end < g.joints.len() {
                "▶"
            } else {
                " "
            }
        ),
        theme.dim(),
    )));
    // The dam stands on the bottom of the pane.
    let pad = (area.height as usize).saturating_sub(lines.len());
    let mut padded = vec![Line::default(); pad];
    padded.extend(lines);
    Paragraph::new(padded).render(area, buf);
}

fn render_info(app: &App, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let (c, r) = app.cursor;
    let Some(cell) = data.grid.cell(c, r) else {
        Paragraph::new(Span::styled("no grouting zone here", theme.dim())).render(area, buf);
        return;
    };
    let mut spans = vec![Span::styled(
        format!("Joint {} zone {}", cell.joint, cell.zone),
        theme.title(),
    )];
    if let Some(p) = cell.planned {
        spans.push(Span::raw(format!(" · {p}")));
    }
    match data.run.readiness(ZoneId::new(cell.joint, cell.zone)) {
        Some(z) if !z.history => {
            spans.push(Span::raw(" · "));
            spans.push(Span::styled(
                format!("{} {}", verdict_symbol(z.verdict), verdict_words(z.verdict)),
                theme.verdict(z.verdict),
            ));
            if let Some(r) = &z.remedy {
                spans.push(Span::raw(format!(" · {}", remedy_short(r))));
            } else if let Some(a) = cell.aperture_mm {
                spans.push(Span::raw(format!(" · {} mm", mm(a))));
            }
        }
        Some(z) => {
            spans.push(Span::styled(
                format!(" · {} {}", cell.state.symbol(), cell.state.label()),
                theme.state(cell.state),
            ));
            if let Some(d) = z.reopened {
                spans.push(Span::raw(format!(", re-opened {d}")));
            }
        }
        None => spans.push(Span::styled(
            format!(" · {} {}", cell.state.symbol(), cell.state.label()),
            theme.state(cell.state),
        )),
    }
    Paragraph::new(Line::from(spans)).render(area, buf);
}

#[cfg(test)]
mod tests {
    use super::scroll;

    #[test]
    fn scrolling_keeps_the_cursor_in_view() {
        assert_eq!(scroll(0, 5, 20), 0);
        assert_eq!(scroll(4, 5, 20), 0);
        assert_eq!(scroll(5, 5, 20), 1);
        assert_eq!(scroll(19, 5, 20), 15);
        assert_eq!(scroll(3, 10, 4), 0);
        assert_eq!(scroll(3, 0, 4), 0);
    }
}
