//! Axis scales of the SVG charts: a linear map from data to pixels, round
//! ticks for millimetres and month ticks for dates.

use chrono::{Datelike, NaiveDate};

/// Linear map of the data interval `[d0, d1]` onto the pixel interval
/// `[p0, p1]` (p1 < p0 for a y axis, whose pixels grow downwards).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    pub d0: f64,
    pub d1: f64,
    pub p0: f64,
    pub p1: f64,
}

impl Scale {
    pub fn new(domain: (f64, f64), pixels: (f64, f64)) -> Scale {
        // A zero-width domain (one date, one value) would divide by zero.
        let (d0, d1) = if domain.1 > domain.0 {
            domain
        } else {
            (domain.0 - 0.5, domain.0 + 0.5)
        };
        Scale {
            d0,
            d1,
            p0: pixels.0,
            p1: pixels.1,
        }
    }

    /// Pixel of the data value `v`.
    pub fn map(&self, v: f64) -> f64 {
        self.p0 + (v - self.d0) / (self.d1 - self.d0) * (self.p1 - self.p0)
    }
}

/// Days since the common era, the x coordinate of a date on a chart.
pub fn day_number(d: NaiveDate) -> f64 {
    d.num_days_from_ce() as f64
}

/// Round ticks (1, 2, 2.5 or 5 × 10ⁿ apart) covering `[lo, hi]` with about
/// `target` intervals; the first tick ≤ lo and the last ≥ hi, so the axis can
/// span exactly from the first to the last tick.
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, lo + 0.5)
    };
    let step = nice_step((hi - lo) / target.max(1) as f64);
    let first = (lo / step + 1e-9).floor() as i64;
    let last = (hi / step - 1e-9).ceil() as i64;
    // Integer multiples of the step rather than repeated additions: one
    // rounding per tick, so labels print as 0.3, not 0.30000000000000004.
    (first..=last).map(|i| i as f64 * step).collect()
}

/// Smallest round step ≥ `raw`.
pub fn nice_step(raw: f64) -> f64 {
    let raw = if raw.is_finite() && raw > 0.0 {
        raw
    } else {
        1.0
    };
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let m = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|&m| f <= m * (1.0 + 1e-9))
        .unwrap_or(10.0);
    m * mag
}

/// Decimals that print every multiple of `step` exactly (at most 3).
pub fn tick_decimals(step: f64) -> usize {
    (0..=3)
        .find(|&d| {
            let s = step * 10f64.powi(d as i32);
            (s - s.round()).abs() < 1e-6
        })
        .unwrap_or(3)
}

/// First days of the months within `[d0, d1]`, thinned to every 1, 2, 3, 6
/// or 12 months so that at most `max_ticks` remain.
pub fn month_ticks(d0: NaiveDate, d1: NaiveDate, max_ticks: usize) -> Vec<NaiveDate> {
    let mut months = Vec::new();
    let mut m = NaiveDate::from_ymd_opt(d0.year(), d0.month(), 1).expect("first of a month");
    if m < d0 {
        m = next_month(m);
    }
    while m <= d1 {
        months.push(m);
        m = next_month(m);
    }
    let max_ticks = max_ticks.max(1);
    let every = [1, 2, 3, 6, 12]
        .into_iter()
        .find(|&k| months.len().div_ceil(k) <= max_ticks)
        .unwrap_or(12);
    // Keeping months whose number is a multiple of the stride puts ticks on
    // quarters and years, which read better than "every third from the start".
    let kept: Vec<NaiveDate> = months
        .iter()
        .copied()
        .filter(|d| (d.month0() as usize).is_multiple_of(every))
        .collect();
    if kept.is_empty() && every > 1 {
        months.into_iter().step_by(every).collect()
    } else {
        kept
    }
}

fn next_month(d: NaiveDate) -> NaiveDate {
    let (y, m) = if d.month() == 12 {
        (d.year() + 1, 1)
    } else {
        (d.year(), d.month() + 1)
    };
    NaiveDate::from_ymd_opt(y, m, 1).expect("first of a month")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn date(s: &str) -> NaiveDate {
        s.parse().unwrap()
    }

    #[test]
    fn scale_maps_ends_and_middle() {
        let s = Scale::new((0.0, 2.0), (300.0, 100.0));
        assert_eq!(s.map(0.0), 300.0);
        assert_eq!(s.map(2.0), 100.0);
        assert_eq!(s.map(0.5), 250.0);
    }

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(nice_ticks(0.0, 1.37, 5), vec![0.0, 0.5, 1.0, 1.5]);
        let t = nice_ticks(0.0, 0.9, 5);
        assert_eq!(t.len(), 6);
        assert!((t[1] - 0.2).abs() < 1e-12 && (t[5] - 1.0).abs() < 1e-12);
        assert_eq!(nice_step(0.23), 0.25);
        assert_eq!(tick_decimals(0.25), 2);
        assert_eq!(tick_decimals(0.5), 1);
        assert_eq!(tick_decimals(5.0), 0);
    }

    #[test]
    fn month_ticks_thin_to_quarters() {
        let t = month_ticks(date("2024-01-15"), date("2024-06-30"), 6);
        assert_eq!(t.first(), Some(&date("2024-02-01")));
        assert_eq!(t.len(), 5);
        let t = month_ticks(date("2024-01-01"), date("2025-12-31"), 8);
        assert_eq!(t.len(), 8);
        assert!(t.iter().all(|d| d.month0() % 3 == 0));
    }
}
