//! A zone's aperture (upstream, centre, downstream and the minimum the rule
//! reads, with the 0.5 mm line and the planned date: the seed paper's Figs.
//! 4–6) and the warmer block's temperature (against the closure temperature
//! and closure + tolerance, the limit the rule reads) over time, as terminal
//! charts.

use chrono::NaiveDate;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Style;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Widget};

use super::Theme;
use crate::planner::ZoneHistory;

/// One curve: points (day since the history's first date, value).
pub struct Series {
    pub name: &'static str,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
    pub marker: Marker,
    /// points only (joint-meter readings), not a line
    pub scatter: bool,
}

impl Series {
    /// A curve drawn as a line in the theme's `i`-th series colour and marker.
    pub fn line(name: &'static str, points: Vec<(f64, f64)>, theme: &Theme, i: usize) -> Series {
        Series {
            name,
            points,
            style: theme.series(i),
            marker: marker(theme, i),
            scatter: false,
        }
    }
}

impl Series {
    /// A curve in its own style: braille in colour, `glyph` without colour
    /// (so it stays told apart from the numbered series).
    pub fn own(
        name: &'static str,
        points: Vec<(f64, f64)>,
        style: Style,
        glyph: char,
        theme: &Theme,
    ) -> Series {
        Series {
            name,
            points,
            style,
            marker: if theme.color {
                Marker::Braille
            } else {
                Marker::Custom(glyph)
            },
            scatter: false,
        }
    }
}

/// x of a date on the chart: days since `t0`.
pub fn x(t0: NaiveDate, d: NaiveDate) -> f64 {
    (d - t0).num_days() as f64
}

pub fn points(h: &ZoneHistory, t0: NaiveDate, v: &[Option<f64>]) -> Vec<(f64, f64)> {
    h.dates
        .iter()
        .zip(v)
        .filter_map(|(d, v)| v.map(|v| (x(t0, *d), v)))
        .collect()
}

/// Markers that tell the curves apart without colour.
pub fn marker(theme: &Theme, i: usize) -> Marker {
    if theme.color {
        Marker::Braille
    } else {
        // Block (█) is left to the joint meters' readings.
        [Marker::Dot, Marker::Braille, Marker::Bar, Marker::Braille][i % 4]
    }
}

/// The title doubles as the legend: each curve's name in its colour (and,
/// without colour, its marker), then the limit and the date line.
fn title_line(
    title: &str,
    series: &[Series],
    limit: Option<(&'static str, f64)>,
    mark: Option<NaiveDate>,
    theme: &Theme,
) -> Line<'static> {
    let mut spans = vec![Span::styled(format!(" {title} "), theme.title())];
    for s in series {
        let glyph = if theme.color && !s.scatter {
            String::new()
        } else {
            match s.marker {
                Marker::Dot => "•".into(),
                Marker::Block => "█".into(),
                Marker::Bar => "▄".into(),
                Marker::Custom(c) => c.to_string(),
                _ => "⣿".into(),
            }
        };
        spans.push(Span::styled(format!("{glyph}{} ", s.name), s.style));
    }
    if let Some((name, v)) = limit {
        spans.push(Span::styled(format!("{name} {v} "), theme.limit()));
    }
    if mark.is_some() {
        spans.push(Span::styled("┆date ", theme.marker()));
    }
    Line::from(spans)
}

/// A time chart with a horizontal `limit` line and a vertical line on the
/// `mark` date.
#[allow(clippy::too_many_arguments)]
pub fn render(
    title: &str,
    unit: &str,
    t0: NaiveDate,
    t1: NaiveDate,
    series: &[Series],
    limit: Option<(&'static str, f64)>,
    mark: Option<NaiveDate>,
    theme: &Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let xmax = x(t0, t1).max(1.0);
    let values = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let (mut lo, mut hi) = values
        .chain(limit.map(|l| l.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    // Apertures start at 0; temperatures get a margin.
    let (lo, hi) = if unit == "mm" {
        (0.0, (hi * 1.1).max(0.6))
    } else {
        let m = ((hi - lo) * 0.05).max(0.5);
        ((lo - m).floor(), (hi + m).ceil())
    };
    let limit_pts = limit.map(|(_, v)| vec![(0.0, v), (xmax, v)]);
    let mark_pts = mark.map(|d| vec![(x(t0, d), lo), (x(t0, d), hi)]);
    // Limit and date lines behind the curves, meter readings on top.
    let mut datasets: Vec<Dataset> = Vec::new();
    if let (Some((name, _)), Some(p)) = (limit, &limit_pts) {
        datasets.push(
            Dataset::default()
                .name(name)
                .marker(Marker::Dot)
                .graph_type(GraphType::Line)
                .style(theme.limit())
                .data(p),
        );
    }
    if let Some(p) = &mark_pts {
        datasets.push(
            Dataset::default()
                .marker(Marker::Dot)
                .graph_type(GraphType::Line)
                .style(theme.marker())
                .data(p),
        );
    }
    let lines = series.iter().filter(|s| !s.scatter);
    for s in lines.chain(series.iter().filter(|s| s.scatter)) {
        datasets.push(
            Dataset::default()
                .name(s.name)
                .marker(s.marker)
                .graph_type(if s.scatter {
                    GraphType::Scatter
                } else {
                    GraphType::Line
                })
                .style(s.style)
                .data(&s.points),
        );
    }
    let mid = t0 + chrono::Duration::days((xmax / 2.0) as i64);
    let label = |d: NaiveDate| d.format("%y-%m-%d").to_string();
    Chart::new(datasets)
        .block(Block::bordered().title(title_line(title, series, limit, mark, theme)))
        .x_axis(
            Axis::default()
                .bounds([0.0, xmax])
                .labels([label(t0), label(mid), label(t1)])
                .style(theme.dim()),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([format!("{lo:.1}"), format!("{hi:.1}")])
                .style(theme.dim()),
        )
        // The title is the legend.
        .legend_position(None)
        .render(area, buf);
}
