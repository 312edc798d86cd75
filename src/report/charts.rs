//! The two charts of the report, as SVG text: the aperture history of a
//! zone (`charts/zone_J<j>_Z<z>.svg`) and a joint meter's readings against
//! the prediction (`charts/meter_J<j>_Z<z>_<point>.svg`).

use chrono::NaiveDate;

use super::meters::MeterSeries;
use super::svg::{self, num, DateMmAxes, Svg, FRAME};
use crate::planner::ZoneHistory;
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

/// Axes of a zone's aperture chart: the history's dates and the planned
/// date; the apertures and the least groutable aperture.
pub fn zone_axes(h: &ZoneHistory, settings: &PlannerSettings) -> DateMmAxes {
    let d0 = h.dates.first().copied().unwrap_or(h.planned).min(h.planned);
    let d1 = h.dates.last().copied().unwrap_or(h.planned).max(h.planned);
    let (lo, hi) = range(&[&h.upstream, &h.center, &h.downstream]);
    DateMmAxes::new(d0, d1, lo.min(0.0), hi.max(settings.min_aperture_mm * 1.2))
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
    let y = axes.ymm(min_aperture_mm);
    svg.line("limit", (FRAME.left, y), (FRAME.right, y));
    svg.text(
        "limit-label",
        (FRAME.right - 4.0, y - 5.0),
        "end",
        &format!("{} mm", num(min_aperture_mm, 3)),
    );
}

/// The aperture chart of a zone.
pub fn zone_chart(h: &ZoneHistory, settings: &PlannerSettings) -> String {
    let axes = zone_axes(h, settings);
    let title = format!("Joint {}, zone {}", h.joint, h.zone);
    let mut svg = Svg::new(svg::WIDTH, svg::HEIGHT);
    svg::title(&mut svg, &title);
    axes.draw(&mut svg);
    draw_limit(&mut svg, &axes, settings.min_aperture_mm);
    let x = axes.xd(h.planned);
    svg.line("planned", (x, FRAME.top), (x, FRAME.bottom));
    // Past the middle the label goes left of the line so it stays inside.
    let anchor = if x > (FRAME.left + FRAME.right) / 2.0 {
        ("end", -4.0)
    } else {
        ("start", 4.0)
    };
    svg.text(
        "planned-label",
        (x + anchor.1, FRAME.top + 12.0),
        anchor.0,
        &format!("planned {}", h.planned),
    );
    for (class, vals) in [
        ("upstream", &h.upstream),
        ("center", &h.center),
        ("downstream", &h.downstream),
    ] {
        draw_series(&mut svg, &axes, class, &h.dates, vals);
    }
    svg::legend(
        &mut svg,
        &[
            ("upstream", "upstream", false),
            ("center", "center", false),
            ("downstream", "downstream", false),
            ("limit", "least groutable aperture", false),
            ("planned", "planned grouting", false),
        ],
    );
    svg.finish(&title, svg::STYLE)
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
        let doc = zone_chart(&h, &PlannerSettings::default());
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
