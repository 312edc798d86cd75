//! The two charts of the report, as SVG text: the history of a zone
//! (`charts/zone_J<j>_Z<z>.svg`: the opening of the joint with the minimum
//! the aperture rule reads, over the warmer block's temperature against
//! closure + tolerance, the quantity the temperature rule reads; the
//! remedy's verified run dashed to its date) and a joint meter's readings
//! against the prediction (`charts/meter_J<j>_Z<z>_<point>.svg`).

use chrono::NaiveDate;

use super::meters::MeterSeries;
use super::svg::{self, num, DateMmAxes, Frame, Svg, FRAME, TEMPERATURE_FRAME};
use super::words;
use crate::planner::{RemedyChoice, ZoneHistory, ZoneReadiness};
use crate::scene::PlannerSettings;

/// File name of a zone's aperture chart, inside `charts/`.
pub fn zone_chart_file(joint: u32, zone: u32) -> String {
    format!("zone_J{joint}_Z{zone}.svg")
}

/// File name of a meter's chart, inside `charts/`; the point name is kept to
/// characters that are safe in a file name and a Markdown link.
pub fn meter_chart_file(joint: u32, zone: u32, point: &str) -> String {
    let point: String = point
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("meter_J{joint}_Z{zone}_{point}.svg")
}

/// Least and greatest value of the series, for the axis range (infinite
/// when there is none; the axes then fall back to 0 and the limit).
fn range(series: &[&[Option<f64>]]) -> (f64, f64) {
    series
        .iter()
        .flat_map(|s| s.iter())
        .filter_map(|v| v.filter(|v| v.is_finite()))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// The remedy's verified run of the zone, when the search verified one.
fn remedy_history(z: Option<&ZoneReadiness>) -> Option<&ZoneHistory> {
    z.and_then(|z| z.remedy.as_ref())
        .filter(|r| r.choice != RemedyChoice::None)
        .and_then(|r| r.verified_history.as_ref())
        .filter(|h| !h.dates.is_empty())
}

/// First and last date of a zone chart: the history's, the planned date and
/// the remedy's run to its date.
fn zone_dates(h: &ZoneHistory, remedy: Option<&ZoneHistory>) -> (NaiveDate, NaiveDate) {
    let ends = [h.dates.first(), h.dates.last(), Some(&h.planned)]
        .into_iter()
        .chain(
            remedy
                .map(|r| [r.dates.first(), r.dates.last(), Some(&r.planned)])
                .into_iter()
                .flatten(),
        )
        .flatten()
        .copied();
    let d0 = ends.clone().min().unwrap_or(h.planned);
    let d1 = ends.max().unwrap_or(h.planned);
    (d0, d1)
}

/// Axes of a zone chart's aperture panel: the history's dates and the
/// planned date; the apertures and the least groutable aperture.
pub fn zone_axes(h: &ZoneHistory, settings: &PlannerSettings) -> DateMmAxes {
    zone_axes_with(h, None, settings)
}

fn zone_axes_with(
    h: &ZoneHistory,
    remedy: Option<&ZoneHistory>,
    settings: &PlannerSettings,
) -> DateMmAxes {
    let (d0, d1) = zone_dates(h, remedy);
    let empty: &[Option<f64>] = &[];
    let r = remedy.map_or(empty, |r| r.series(settings.aperture_point));
    let (lo, hi) = range(&[&h.upstream, &h.center, &h.downstream, &h.min, r]);
    DateMmAxes::new(d0, d1, lo.min(0.0), hi.max(settings.min_aperture_mm * 1.2))
}

/// Axes of a zone chart's temperature panel: the warmer block's
/// temperature (baseline and remedy), the closure temperature and the limit.
pub fn temperature_axes(
    h: &ZoneHistory,
    remedy: Option<&ZoneHistory>,
    closure: f64,
    limit: f64,
) -> DateMmAxes {
    let (d0, d1) = zone_dates(h, remedy);
    let empty: &[Option<f64>] = &[];
    let r = remedy.map_or(empty, |r| r.temperature.as_slice());
    let (lo, hi) = range(&[&h.temperature, r]);
    DateMmAxes::in_frame(
        TEMPERATURE_FRAME,
        d0,
        d1,
        (lo.min(closure) - 0.5, hi.max(limit) + 0.5),
        "warmer block [°C]",
    )
}

/// Polylines of a series, broken where a value is missing (the zone's two
/// blocks did not both exist); a lone point is drawn as a dot.
fn draw_series(
    svg: &mut Svg,
    axes: &DateMmAxes,
    class: &str,
    dates: &[NaiveDate],
    vals: &[Option<f64>],
) {
    svg.open_group(&format!("series {class}"));
    let mut run: Vec<(f64, f64)> = Vec::new();
    let flush = |svg: &mut Svg, run: &mut Vec<(f64, f64)>| {
        match run.len() {
            0 => {}
            1 => svg.circle(class, run[0], 2.0),
            _ => svg.polyline(class, run),
        }
        run.clear();
    };
    for (d, v) in dates.iter().zip(vals) {
        match v.filter(|v| v.is_finite()) {
            Some(v) => run.push((axes.xd(*d), axes.ymm(v))),
            None => flush(svg, &mut run),
        }
    }
    flush(svg, &mut run);
    svg.close_group();
}

/// Dashed horizontal line at the least groutable aperture, labelled with it.
fn draw_limit(svg: &mut Svg, axes: &DateMmAxes, min_aperture_mm: f64) {
    let f = axes.frame;
    let y = axes.ymm(min_aperture_mm);
    svg.line("limit", (f.left, y), (f.right, y));
    svg.text(
        "limit-label",
        (f.right - 4.0, y - 5.0),
        "end",
        &format!("{} mm", num(min_aperture_mm, 3)),
    );
}

/// A vertical line across the frame on date `d` (its date is in the
/// legend: a label inside the frame would sit on the curves).
fn draw_date(svg: &mut Svg, axes: &DateMmAxes, class: &str, d: NaiveDate) {
    let f: Frame = axes.frame;
    let x = axes.xd(d);
    svg.line(class, (x, f.top), (x, f.bottom));
}

/// The chart of a zone: the opening of the joint (three points and the
/// minimum the rule reads, against the least groutable aperture) over the
/// warmer block's temperature (against the closure temperature and the
/// limit the rule reads, closure plus tolerance); the planned date on both,
/// and the remedy's verified run dashed to its date. `z` is the zone's readiness
/// (its closure temperature, verdict and remedy).
pub fn zone_chart(
    h: &ZoneHistory,
    z: Option<&ZoneReadiness>,
    settings: &PlannerSettings,
) -> String {
    let remedy = remedy_history(z);
    let axes = zone_axes_with(h, remedy, settings);
    let title = format!("Joint {}, zone {}", h.joint, h.zone);
    let mut svg = Svg::new(svg::WIDTH, svg::ZONE_HEIGHT);
    svg::title(&mut svg, &title);
    if let Some(z) = z {
        svg.text(
            "subtitle",
            (svg::WIDTH / 2.0, 24.0 + 14.0),
            "middle",
            &zone_subtitle(z),
        );
    }
    aperture_panel(&mut svg, &axes, h, remedy, settings);
    let closure = z.map_or(settings.closure_temp_c, |z| z.closure_temp_c);
    let limit = z.map_or(closure + settings.closure_tolerance_c, |z| {
        words::temperature_limit(z, settings)
    });
    let t_axes = temperature_axes(h, remedy, closure, limit);
    temperature_panel(&mut svg, &t_axes, h, remedy, closure, limit);
    let planned = format!("planned grouting {}", h.planned);
    let closure_label = format!("closure {closure:.1} °C");
    let limit_label = format!("limit {limit:.1} °C = closure + tolerance");
    let remedy_label = remedy.map(|r| format!("with the remedy (verified), grouted {}", r.planned));
    let mut entries = vec![
        ("upstream", "upstream", false),
        ("center", "center", false),
        ("downstream", "downstream", false),
        ("min", "minimum", false),
        ("limit", "least groutable aperture", false),
        ("planned", planned.as_str(), false),
        ("temperature", "warmer block", false),
        ("closure", closure_label.as_str(), false),
        ("temperature-limit", limit_label.as_str(), false),
    ];
    if let Some(l) = &remedy_label {
        entries.push(("remedy", l.as_str(), false));
    }
    svg::legend(&mut svg, TEMPERATURE_FRAME, &entries);
    svg.finish(&title, svg::STYLE)
}

/// "✗ not groutable: temperature · remedy delay 17 d → 2024-10-01, 1.85 mm":
/// which rules fail, so a zone too warm does not read as one too tight.
fn zone_subtitle(z: &ZoneReadiness) -> String {
    let mut s = format!(
        "{} {}",
        words::verdict_symbol(z.verdict),
        words::verdict_words(z.verdict)
    );
    if z.history {
        s = format!("grouted {}", z.planned);
    } else if !z.verdict.groutable() {
        s.push_str(&format!(": {}", words::failed_rules(z)));
        match &z.remedy {
            Some(r) if r.choice == RemedyChoice::None => s.push_str(" · no remedy found"),
            Some(r) => s.push_str(&format!(" · remedy {}", words::remedy_short(r))),
            None => {}
        }
    }
    s
}

/// The aperture panel: limit, planned date, the points, the minimum on top,
/// and the remedy's run of the deciding point to its date.
fn aperture_panel(
    svg: &mut Svg,
    axes: &DateMmAxes,
    h: &ZoneHistory,
    remedy: Option<&ZoneHistory>,
    settings: &PlannerSettings,
) {
    axes.draw(svg);
    draw_limit(svg, axes, settings.min_aperture_mm);
    draw_date(svg, axes, "planned", h.planned);
    for (class, vals) in [
        ("upstream", &h.upstream),
        ("center", &h.center),
        ("downstream", &h.downstream),
        ("min", &h.min),
    ] {
        draw_series(svg, axes, class, &h.dates, vals);
    }
    if let Some(r) = remedy {
        draw_date(svg, axes, "remedy-date", r.planned);
        let vals = r.series(settings.aperture_point);
        draw_series(svg, axes, "remedy", &r.dates, vals);
    }
}

/// The temperature panel: the closure temperature, the limit the rule
/// reads (closure + tolerance), the planned date, the warmer block, and the
/// remedy's run to its date.
fn temperature_panel(
    svg: &mut Svg,
    axes: &DateMmAxes,
    h: &ZoneHistory,
    remedy: Option<&ZoneHistory>,
    closure: f64,
    limit: f64,
) {
    axes.draw(svg);
    // Labelled in the legend: the curves cross these lines at the right end.
    let f = axes.frame;
    for (class, v) in [("closure", closure), ("temperature-limit", limit)] {
        let y = axes.ymm(v);
        svg.line(class, (f.left, y), (f.right, y));
    }
    draw_date(svg, axes, "planned", h.planned);
    draw_series(svg, axes, "temperature", &h.dates, &h.temperature);
    if let Some(r) = remedy {
        draw_date(svg, axes, "remedy-date", r.planned);
        draw_series(svg, axes, "remedy-temperature", &r.dates, &r.temperature);
    }
}

/// The predicted aperture at a meter's point over the zone's history, when
/// the plan has the history and names the point.
fn history_series<'a>(h: &'a ZoneHistory, point: &str) -> Option<&'a [Option<f64>]> {
    match point {
        "upstream" => Some(&h.upstream),
        "center" => Some(&h.center),
        "downstream" => Some(&h.downstream),
        "min" => Some(&h.min),
        _ => None,
    }
}

/// The predicted line of a meter chart: the zone's daily history when there
/// is one (it shows the trend between readings), else the predictions at
/// the reading dates.
fn predicted_line(
    s: &MeterSeries,
    history: Option<&ZoneHistory>,
) -> (Vec<NaiveDate>, Vec<Option<f64>>) {
    if let Some((h, vals)) = history.and_then(|h| history_series(h, s.point).map(|v| (h, v))) {
        return (h.dates.clone(), vals.to_vec());
    }
    s.readings.iter().map(|m| (m.date, m.predicted_mm)).unzip()
}

/// Axes of a meter chart: predicted line and readings.
pub fn meter_axes(
    s: &MeterSeries,
    history: Option<&ZoneHistory>,
    settings: &PlannerSettings,
) -> DateMmAxes {
    let (dates, pred) = predicted_line(s, history);
    let all_dates = || {
        dates
            .iter()
            .copied()
            .chain(s.readings.iter().map(|m| m.date))
    };
    let d0 = all_dates().min().expect("a meter series has readings");
    let d1 = all_dates().max().expect("a meter series has readings");
    let measured: Vec<Option<f64>> = s.readings.iter().map(|m| Some(m.measured_mm)).collect();
    let (lo, hi) = range(&[&pred, &measured]);
    DateMmAxes::new(d0, d1, lo.min(0.0), hi.max(settings.min_aperture_mm * 1.2))
}

/// The chart of one joint meter.
pub fn meter_chart(
    s: &MeterSeries,
    history: Option<&ZoneHistory>,
    settings: &PlannerSettings,
) -> String {
    let axes = meter_axes(s, history, settings);
    let (dates, pred) = predicted_line(s, history);
    let title = format!("Joint {}, zone {}, {} meter", s.joint, s.zone, s.point);
    let mut svg = Svg::new(svg::WIDTH, svg::HEIGHT);
    svg::title(&mut svg, &title);
    axes.draw(&mut svg);
    draw_limit(&mut svg, &axes, settings.min_aperture_mm);
    draw_series(&mut svg, &axes, "predicted", &dates, &pred);
    svg.open_group("measured");
    for m in &s.readings {
        if m.measured_mm.is_finite() {
            svg.circle("measured", (axes.xd(m.date), axes.ymm(m.measured_mm)), 3.5);
        }
    }
    svg.close_group();
    svg::legend(
        &mut svg,
        FRAME,
        &[
            ("predicted", "predicted", false),
            ("measured", "measured", true),
            ("limit", "least groutable aperture", false),
        ],
    );
    svg.finish(&title, svg::STYLE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_are_safe() {
        assert_eq!(zone_chart_file(3, 12), "zone_J3_Z12.svg");
        assert_eq!(meter_chart_file(3, 1, "center"), "meter_J3_Z1_center.svg");
        assert_eq!(meter_chart_file(3, 1, "a b/c"), "meter_J3_Z1_a_b_c.svg");
    }

    #[test]
    fn gaps_break_the_line() {
        let d = |i: u32| NaiveDate::from_ymd_opt(2024, 3, i).unwrap();
        let h = ZoneHistory {
            joint: 1,
            zone: 2,
            planned: d(10),
            dates: (1..=6).map(d).collect(),
            upstream: vec![None, Some(0.2), Some(0.3), None, Some(0.5), Some(0.6)],
            center: vec![Some(0.1), None, Some(0.3), None, Some(0.5), None],
            downstream: vec![None; 6],
            min: vec![None; 6],
            temperature: vec![None; 6],
        };
        let doc = zone_chart(&h, None, &PlannerSettings::default());
        assert_eq!(doc.matches("<polyline class=\"upstream\"").count(), 2);
        assert_eq!(doc.matches("<polyline class=\"center\"").count(), 0);
        assert_eq!(doc.matches("<circle class=\"center\"").count(), 3);
        assert!(!doc.contains("<polyline class=\"downstream\""));
        // The planned date lies after the last history date: the axis reaches it.
        assert_eq!(
            zone_axes(&h, &PlannerSettings::default()).xd(d(10)),
            FRAME.right
        );
    }
}
