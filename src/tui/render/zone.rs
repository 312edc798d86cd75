//! One zone: aperture and temperature charts on the left (the minimum the
//! aperture rule reads, the warmer block against closure + tolerance as the
//! temperature rule reads it, the remedy's verified run to its date); the
//! readiness rules in words and the plan's remedy on the right, or the
//! what-if form with the plan's and the what-if's answers side by side.

use chrono::NaiveDate;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Gauge, Paragraph, Widget, Wrap};

use super::chart::{self, Series};
use super::Theme;
use crate::planner::whatif::WhatIfOutcome;
use crate::planner::{
    MeterComparison, RemedyChoice, Rule, RuleCheck, Verdict, ZoneHistory, ZoneReadiness,
};
use crate::report::words::{
    deciding_aperture, max_block_temp, mm, opt, remedy_short, temperature_limit, verdict_symbol,
    verdict_words, verified_words,
};
use crate::scene::PlannerSettings;
use crate::tui::app::{App, Field, WhatIfForm, ZoneView};
use crate::tui::data::RunData;
use crate::vocab::{ZoneId, ZonePoint};

pub fn render(app: &App, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let Some(view) = &app.zone else {
        Paragraph::new("No zone open: choose one on the overview or the flagged list (Enter).")
            .render(area, buf);
        return;
    };
    let title_line = title_line(view, data, theme);
    // Wrapped onto a second line when the screen is too narrow for it.
    let title_h = if title_line.width() > area.width as usize {
        2
    } else {
        1
    };
    let [title, body] =
        Layout::vertical([Constraint::Length(title_h), Constraint::Min(0)]).areas(area);
    Paragraph::new(title_line)
        .wrap(Wrap { trim: true })
        .render(title, buf);
    let side_w = 36.min(area.width / 2);
    let [charts, side] =
        Layout::horizontal([Constraint::Min(20), Constraint::Length(side_w)]).areas(body);
    render_charts(view, data, theme, charts, buf);
    match &view.whatif {
        Some(form) => render_whatif(view, form, data, theme, side, buf),
        None => render_rules(view, data, theme, side, buf),
    }
}

/// "Joint 1 zone 4 · lifts 10–12 · EL 27–36 m · planned 2024-09-13 · ✗ not groutable".
fn title_line(view: &ZoneView, data: &RunData, theme: &Theme) -> Line<'static> {
    let mut spans = vec![Span::styled(
        format!("Joint {} zone {}", view.joint, view.zone),
        theme.title(),
    )];
    let extent = data.zone_extent_text(ZoneId::new(view.joint, view.zone));
    if !extent.is_empty() {
        spans.push(Span::raw(format!(" · {extent}")));
    }
    if let Some(p) = view.planned {
        spans.push(Span::raw(format!(" · planned {p}")));
    }
    if let Some(r) = &view.readiness {
        spans.push(Span::raw(" · "));
        if r.history {
            spans.push(Span::styled("■ already grouted", theme.dim()));
        } else {
            spans.push(Span::styled(
                format!("{} {}", verdict_symbol(r.verdict), verdict_words(r.verdict)),
                theme.verdict(r.verdict),
            ));
        }
    }
    Line::from(spans)
}

/// The aperture chart over the temperature chart, from the zone's first
/// history date to the latest of its last, planned and what-if dates.
fn render_charts(view: &ZoneView, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let h = &view.history;
    let result = whatif_result(view);
    let (Some(&t0), Some(&last)) = (h.dates.first(), h.dates.last()) else {
        Paragraph::new("The zone has no history yet: its blocks are not both poured.")
            .block(Block::bordered())
            .render(area, buf);
        return;
    };
    let mut t1 = last;
    if let Some(p) = view.planned {
        t1 = t1.max(p);
    }
    if let Some(r) = result {
        t1 = t1.max(r.what_if.date);
    }
    if let Some(r) = remedy_history(view) {
        t1 = t1.max(r.planned);
    }
    let [top, bottom] =
        Layout::vertical([Constraint::Percentage(58), Constraint::Percentage(42)]).areas(area);
    let s = &data.run.plan.settings;
    let mark = result.map(|r| r.what_if.date).or(view.planned);
    chart::render(
        "mm",
        "mm",
        t0,
        t1,
        &aperture_series(view, data, result, theme, t0),
        Some(("limit", s.min_aperture_mm)),
        mark,
        theme,
        top,
        buf,
    );
    let closure = view
        .readiness
        .as_ref()
        .map_or(s.closure_temp_c, |r| r.closure_temp_c);
    let limit = view
        .readiness
        .as_ref()
        .map_or(closure + s.closure_tolerance_c, |r| temperature_limit(r, s));
    // The limit only: a closure line a degree below it would share its
    // terminal row at this height (the rules pane says closure + tolerance).
    let temps = temperature_series(view, result, theme, t0);
    chart::render(
        "°C",
        "°C",
        t0,
        t1,
        &temps,
        Some(("limit", limit)),
        mark,
        theme,
        bottom,
        buf,
    );
}

/// The remedy's verified run of the zone, when the plan verified one.
fn remedy_history(view: &ZoneView) -> Option<&ZoneHistory> {
    view.readiness
        .as_ref()
        .and_then(|r| r.remedy.as_ref())
        .filter(|r| r.choice != RemedyChoice::None)
        .and_then(|r| r.verified_history.as_ref())
        .filter(|h| !h.dates.is_empty())
}

/// The what-if's outcome, only while it is this zone's: the form keeps it
/// when the view moves to another zone.
fn whatif_result(view: &ZoneView) -> Option<&WhatIfOutcome> {
    view.whatif
        .as_ref()
        .and_then(|f| f.result.as_deref())
        .filter(|r| (r.what_if.joint, r.what_if.zone) == (view.joint, view.zone))
}

/// The zone's three aperture points and the minimum, the remedy's and the
/// what-if's at the plan's deciding point, and the site's joint meters on
/// this zone, as measured.
fn aperture_series(
    view: &ZoneView,
    data: &RunData,
    result: Option<&WhatIfOutcome>,
    theme: &Theme,
    t0: NaiveDate,
) -> Vec<Series> {
    let h = &view.history;
    let names = ["up", "ctr", "down"];
    let mut series: Vec<Series> = [&h.upstream, &h.center, &h.downstream]
        .iter()
        .enumerate()
        .map(|(i, v)| Series::line(names[i], chart::points(h, t0, v), theme, i))
        .collect();
    series.push(Series::own(
        "min",
        chart::points(h, t0, &h.min),
        theme.min_curve(),
        '▪',
        theme,
    ));
    let point = data.run.plan.settings.aperture_point;
    if let Some(r) = remedy_history(view) {
        series.push(remedy_series(r, t0, r.series(point), theme));
    }
    if let Some(r) = result {
        let v = r.history.series(data.run.plan.settings.aperture_point);
        series.push(Series::line(
            "what-if",
            chart::points(&r.history, t0, v),
            theme,
            3,
        ));
    }
    let meters: Vec<(f64, f64)> = zone_meters(view, data)
        .map(|m| (chart::x(t0, m.date), m.measured_mm))
        .collect();
    if !meters.is_empty() {
        series.push(Series {
            name: "meter",
            points: meters,
            style: theme.meter(),
            marker: Marker::Block,
            scatter: true,
        });
    }
    series
}

/// A series of the remedy's verified run, in its own style.
fn remedy_series(r: &ZoneHistory, t0: NaiveDate, v: &[Option<f64>], theme: &Theme) -> Series {
    Series::own(
        "remedy",
        chart::points(r, t0, v),
        theme.remedy(),
        '∘',
        theme,
    )
}

/// The warmer block's mean temperature over the zone (what the rule
/// reads), the remedy's and the what-if's.
fn temperature_series(
    view: &ZoneView,
    result: Option<&WhatIfOutcome>,
    theme: &Theme,
    t0: NaiveDate,
) -> Vec<Series> {
    let h = &view.history;
    let mut temps = vec![Series::line(
        "warmer block",
        chart::points(h, t0, &h.temperature),
        theme,
        1,
    )];
    if let Some(r) = remedy_history(view) {
        temps.push(remedy_series(r, t0, &r.temperature, theme));
    }
    if let Some(r) = result {
        temps.push(Series::line(
            "what-if",
            chart::points(&r.history, t0, &r.history.temperature),
            theme,
            3,
        ));
    }
    temps
}

/// The site's joint-meter readings on the zone: the aperture chart draws
/// them, the rules pane sums up their error.
fn zone_meters<'a>(
    view: &ZoneView,
    data: &'a RunData,
) -> impl Iterator<Item = &'a MeterComparison> {
    let here = (view.joint, view.zone);
    data.run
        .plan
        .meters
        .iter()
        .filter(move |m| (m.joint, m.zone) == here)
}

/// A rule's name and its value against the limit, in words that fit the
/// side panel: "aperture 0.40 mm, min 0.50", "warmer block 14.5 °C, max
/// 14.0", "zone below grouted 29 d after".
fn rule_text(c: &RuleCheck) -> (&'static str, String) {
    let v = |f: &dyn Fn(f64) -> String| opt(c.value, f);
    match c.rule {
        Rule::Aperture => (
            "aperture",
            format!("{} mm, min {}", v(&|x| mm(x)), mm(c.limit)),
        ),
        Rule::Temperature => (
            "warmer block",
            format!("{} °C, max {:.1}", v(&|x| format!("{x:.1}")), c.limit),
        ),
        Rule::Age => (
            "age",
            format!("{} d, min {:.0}", v(&|x| format!("{x:.0}")), c.limit),
        ),
        Rule::Cover => match c.value {
            Some(x) => ("cover", format!("{x:.1} m, min {:.1}", c.limit)),
            None => ("cover", "both blocks complete".into()),
        },
        // The value is the days the zone below is grouted before this one.
        Rule::BottomUp => (
            "zone below",
            match c.value {
                None if c.passed => "none: lowest zone".into(),
                None => "has no grouting date".into(),
                Some(d) if d > 0.0 => format!("grouted {d:.0} d before"),
                Some(d) if d < 0.0 => format!("grouted {:.0} d after", -d),
                Some(_) => "grouted the same day".into(),
            },
        ),
    }
}

fn rule_lines<'a>(r: &ZoneReadiness, s: &PlannerSettings, theme: &Theme) -> Vec<Line<'a>> {
    let mut lines = Vec::new();
    for c in &r.checks {
        let (name, text) = rule_text(c);
        // A zone grouted already gets no verdict: its values, not alarms.
        let (mark, style) = match (r.history, c.passed) {
            (true, _) => ("· ", theme.dim()),
            (false, true) => ("✓ ", theme.pass(true)),
            (false, false) => ("✗ ", theme.pass(false)),
        };
        lines.push(Line::from(vec![
            Span::styled(mark, style),
            Span::raw(format!("{name:<13}{text}")),
        ]));
        if c.rule == Rule::Temperature {
            lines.push(Line::from(Span::styled(
                format!(
                    "  = closure {:.1} + tolerance {:.1}",
                    r.closure_temp_c, s.closure_tolerance_c
                ),
                theme.dim(),
            )));
        }
    }
    lines
}

fn render_rules(view: &ZoneView, data: &RunData, theme: &Theme, area: Rect, buf: &mut Buffer) {
    let mut lines = Vec::new();
    match &view.readiness {
        None => {
            lines.push(Line::from(
                "Not in this plan: the zone is planned after the plan's horizon or not \
                 in grouting.csv.",
            ));
        }
        Some(r) => {
            let title = if r.history {
                format!("Grouted {} · history", r.planned)
            } else {
                format!("Rules on {}", r.planned)
            };
            lines.push(Line::from(Span::styled(title, theme.title())));
            lines.extend(rule_lines(r, &data.run.plan.settings, theme));
            let meters: Vec<_> = zone_meters(view, data).collect();
            if !meters.is_empty() {
                let errors: Vec<f64> = meters
                    .iter()
                    .filter_map(|m| m.predicted_mm.map(|p| p - m.measured_mm))
                    .collect();
                let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
                lines.push(Line::from(Span::styled(
                    format!(
                        "█ {} meter readings, predicted − measured {:+.2} mm on average",
                        meters.len(),
                        mean
                    ),
                    theme.meter(),
                )));
            }
            if let Some(d) = r.reopened {
                lines.push(Line::from(Span::styled(
                    format!("! re-opened {d}"),
                    theme.error(),
                )));
            }
            if let Some(rem) = &r.remedy {
                lines.push(Line::default());
                lines.push(Line::from(Span::styled("Remedy", theme.title())));
                lines.push(Line::from(Span::styled(remedy_short(rem), theme.key())));
                if let Some(v) = verified_words(rem) {
                    lines.push(Line::from(v));
                }
                if !rem.note.is_empty() {
                    lines.push(Line::from(Span::styled(rem.note.clone(), theme.dim())));
                }
            } else if r.verdict != Verdict::NotGroutable && !r.history {
                let a = deciding_aperture(r, data.run.plan.settings.aperture_point);
                lines.push(Line::default());
                lines.push(Line::from(format!(
                    "{} mm at the {} point",
                    opt(a, mm),
                    data.run.plan.settings.aperture_point.as_str()
                )));
            }
        }
    }
    lines.push(Line::default());
    lines.push(Line::from(vec![
        Span::styled("w", theme.key()),
        Span::raw(" what-if: supercool or move the date"),
    ]));
    // Not trimmed: the indented line under a rule stays indented.
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(Block::bordered().title(" Readiness "))
        .render(area, buf);
}

/// The what-if form: its two fields, the re-simulation's progress or last
/// message, and the plan's answer beside the what-if's.
fn render_whatif(
    view: &ZoneView,
    form: &WhatIfForm,
    data: &RunData,
    theme: &Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let block = Block::bordered().title(Span::styled(" What-if ", theme.title()));
    let inner = block.inner(area);
    block.render(area, buf);
    let [fields, progress, compare] = Layout::vertical([
        Constraint::Length(3),
        Constraint::Length(3),
        Constraint::Min(0),
    ])
    .areas(inner);
    let s = &data.run.plan.settings;
    Paragraph::new(whatif_fields(view, form, s, theme)).render(fields, buf);
    render_whatif_progress(form, theme, progress, buf);
    Paragraph::new(whatif_comparison(view, form, s.aperture_point, theme))
        .wrap(Wrap { trim: true })
        .render(compare, buf);
}

/// The supercooling and the grouting date, each with the limit or the plan
/// it is edited against; the selected one marked.
fn whatif_fields(
    view: &ZoneView,
    form: &WhatIfForm,
    s: &PlannerSettings,
    theme: &Theme,
) -> Vec<Line<'static>> {
    let field = |f: Field, name: &str, value: String, hint: String| {
        let on = form.field == f;
        Line::from(vec![
            Span::styled(if on { "▸ " } else { "  " }, theme.key()),
            Span::raw(format!("{name:<10}")),
            Span::styled(
                value,
                if on {
                    theme.selected()
                } else {
                    ratatui::style::Style::new()
                },
            ),
            Span::styled(format!(" {hint}"), theme.dim()),
        ])
    };
    let planned = view.planned.map(|p| p.to_string()).unwrap_or("–".into());
    vec![
        field(
            Field::Supercool,
            "supercool",
            format!("{:.2} °C", form.supercool_c),
            format!("≤ {:.2}", s.max_supercooling_c),
        ),
        field(
            Field::Date,
            "grout on",
            form.date.to_string(),
            format!("plan {}", planned.get(5..).unwrap_or(&planned)),
        ),
        Line::from(Span::styled("Enter run · c cancel · s save", theme.dim())),
    ]
}

/// A gauge while the what-if re-simulates, else its last message, else how
/// long the last re-simulation took.
fn render_whatif_progress(form: &WhatIfForm, theme: &Theme, area: Rect, buf: &mut Buffer) {
    if let Some(r) = &form.running {
        let label = if r.cancelling {
            "cancelling…".to_string()
        } else {
            format!("re-simulating {:.0}%", r.fraction() * 100.0)
        };
        let [gauge, _] = Layout::vertical([Constraint::Length(1), Constraint::Min(0)]).areas(area);
        Gauge::default()
            .ratio(r.fraction())
            .label(label)
            .gauge_style(theme.key())
            .render(gauge, buf);
    } else if let Some(m) = &form.message {
        Paragraph::new(Span::styled(m.clone(), theme.key()))
            .wrap(Wrap { trim: true })
            .render(area, buf);
    } else if let Some(r) = &form.result {
        Paragraph::new(Span::styled(
            format!("re-simulated in {:.1} s", r.seconds),
            theme.dim(),
        ))
        .render(area, buf);
    }
}

/// The plan's and the what-if's aperture, hottest block, date and verdict
/// in two columns, then why the what-if is not groutable and which zones
/// above moved with it.
fn whatif_comparison(
    view: &ZoneView,
    form: &WhatIfForm,
    point: ZonePoint,
    theme: &Theme,
) -> Vec<Line<'static>> {
    let plan = view.readiness.as_ref();
    let result = form.result.as_ref().map(|r| &r.readiness);
    let a = |z: Option<&ZoneReadiness>| {
        z.map(|z| opt(deciding_aperture(z, point), |x| format!("{} mm", mm(x))))
            .unwrap_or("–".into())
    };
    let t = |z: Option<&ZoneReadiness>| {
        z.map(|z| opt(max_block_temp(z), |x| format!("{x:.1} °C")))
            .unwrap_or("–".into())
    };
    let verdict = |name: &str, z: Option<&ZoneReadiness>| {
        let (text, style) = z
            .map(|z| {
                (
                    format!("{} {}", verdict_symbol(z.verdict), verdict_words(z.verdict)),
                    theme.verdict(z.verdict),
                )
            })
            .unwrap_or(("–".into(), ratatui::style::Style::new()));
        Line::from(vec![
            Span::raw(format!("{name:<9}")),
            Span::styled(text, style),
        ])
    };
    let date = |z: Option<&ZoneReadiness>, d: Option<NaiveDate>| {
        z.map(|z| z.planned)
            .or(d)
            .map(|d| d.to_string())
            .unwrap_or("–".into())
    };
    let row = |name: &str, p: String, w: String| Line::from(format!("{name:<9}{p:<12}{w}"));
    let mut lines = vec![
        Line::from(Span::styled(
            format!("{:<9}{:<12}{}", "", "plan", "what-if"),
            theme.dim(),
        )),
        row("aperture", a(plan), a(result)),
        row("hottest", t(plan), t(result)),
        Line::from(format!(
            "{:<9}{} → {}",
            "date",
            date(plan, view.planned),
            date(result, None).get(5..).unwrap_or("–")
        )),
        verdict("plan", plan),
        verdict("what-if", result),
    ];
    if let Some(r) = result.filter(|r| r.verdict == Verdict::NotGroutable) {
        lines.push(Line::from(Span::styled(r.reasons(), theme.dim())));
    }
    if let Some(o) = &form.result {
        if !o.also_moved.is_empty() {
            let z: Vec<String> = o.also_moved.iter().map(u32::to_string).collect();
            lines.push(Line::from(Span::styled(
                format!("zones {} above move too", z.join(", ")),
                theme.dim(),
            )));
        }
    }
    lines
}
