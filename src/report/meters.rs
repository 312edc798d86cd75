//! Joint meters against the prediction: the readings grouped into one series
//! per meter (joint, zone, point) and the error statistics per joint, shared
//! by the Markdown and JSON reports. An error is predicted − measured, so a
//! positive error means the model opens the joint more than the meter saw.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::planner::MeterComparison;

/// The readings of one joint meter, by date.
#[derive(Debug, Clone, PartialEq)]
pub struct MeterSeries<'a> {
    pub joint: u32,
    pub zone: u32,
    pub point: &'a str,
    pub readings: Vec<&'a MeterComparison>,
}

/// Groups readings by (joint, zone, point), in that order, each by date.
pub fn series(meters: &[MeterComparison]) -> Vec<MeterSeries<'_>> {
    let mut by: BTreeMap<(u32, u32, &str), Vec<&MeterComparison>> = BTreeMap::new();
    for m in meters {
        by.entry((m.joint, m.zone, m.point.as_str()))
            .or_default()
            .push(m);
    }
    by.into_iter()
        .map(|((joint, zone, point), mut readings)| {
            readings.sort_by_key(|m| m.date);
            MeterSeries {
                joint,
                zone,
                point,
                readings,
            }
        })
        .collect()
}

/// Error statistics of the meters of one joint \[mm\].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeterError {
    pub joint: u32,
    /// readings on the joint
    pub readings: usize,
    /// readings with a prediction (the zone existed in the simulation);
    /// the statistics are over these
    pub compared: usize,
    pub mean_error_mm: Option<f64>,
    pub rms_error_mm: Option<f64>,
    pub max_abs_error_mm: Option<f64>,
}

/// Error statistics per joint, by joint.
pub fn errors(meters: &[MeterComparison]) -> Vec<MeterError> {
    let mut by: BTreeMap<u32, Vec<&MeterComparison>> = BTreeMap::new();
    for m in meters {
        by.entry(m.joint).or_default().push(m);
    }
    by.into_iter()
        .map(|(joint, ms)| {
            let e: Vec<f64> = ms
                .iter()
                .filter_map(|m| m.predicted_mm.map(|p| p - m.measured_mm))
                .collect();
            let n = e.len() as f64;
            let some = |v: f64| (!e.is_empty()).then_some(v);
            MeterError {
                joint,
                readings: ms.len(),
                compared: e.len(),
                mean_error_mm: some(e.iter().sum::<f64>() / n),
                rms_error_mm: some((e.iter().map(|x| x * x).sum::<f64>() / n).sqrt()),
                max_abs_error_mm: some(e.iter().fold(0.0, |a: f64, x| a.max(x.abs()))),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(
        joint: u32,
        point: &str,
        day: u32,
        measured: f64,
        predicted: Option<f64>,
    ) -> MeterComparison {
        MeterComparison {
            joint,
            zone: 1,
            point: crate::vocab::ZonePoint::parse(point).expect("a point"),
            date: chrono::NaiveDate::from_ymd_opt(2024, 5, day).unwrap(),
            measured_mm: measured,
            predicted_mm: predicted,
        }
    }

    #[test]
    fn statistics_skip_readings_without_prediction() {
        let ms = vec![
            reading(2, "center", 3, 1.0, Some(1.5)),
            reading(2, "center", 1, 1.0, Some(0.5)),
            reading(2, "upstream", 2, 1.0, None),
            reading(1, "center", 1, 0.4, None),
        ];
        let e = errors(&ms);
        assert_eq!(e.len(), 2);
        assert_eq!((e[0].joint, e[0].readings, e[0].compared), (1, 1, 0));
        assert_eq!(e[0].rms_error_mm, None);
        assert_eq!((e[1].readings, e[1].compared), (3, 2));
        assert!(e[1].mean_error_mm.unwrap().abs() < 1e-12);
        assert!((e[1].rms_error_mm.unwrap() - 0.5).abs() < 1e-12);
        assert!((e[1].max_abs_error_mm.unwrap() - 0.5).abs() < 1e-12);

        let s = series(&ms);
        let keys: Vec<_> = s
            .iter()
            .map(|s| (s.joint, s.point, s.readings.len()))
            .collect();
        assert_eq!(
            keys,
            vec![(1, "center", 1), (2, "center", 2), (2, "upstream", 1)]
        );
        assert!(s[1].readings[0].date < s[1].readings[1].date);
    }
}
