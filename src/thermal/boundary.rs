//! Boundary temperatures: air (annual law or weather.csv) and reservoir water
//! (level from reservoir.csv, temperature by depth).

use chrono::{Datelike, NaiveDate};

use crate::scene::{Air, Reservoir};
use crate::vocab::Epoch;

/// Piecewise-linear series of (day, value), days strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    days: Vec<f64>,
    values: Vec<f64>,
}

impl Series {
    /// Builds a series from dated rows; `epoch` is day 0.
    pub fn from_dated(epoch: Epoch, rows: &[(NaiveDate, f64)]) -> Series {
        Series {
            days: rows.iter().map(|(d, _)| epoch.t(*d)).collect(),
            values: rows.iter().map(|(_, v)| *v).collect(),
        }
    }

    pub fn first_day(&self) -> Option<f64> {
        self.days.first().copied()
    }

    pub fn last_day(&self) -> Option<f64> {
        self.days.last().copied()
    }

    /// Linear interpolation; `None` outside the covered range.
    pub fn at(&self, day: f64) -> Option<f64> {
        let n = self.days.len();
        if n == 0 || day < self.days[0] || day > self.days[n - 1] {
            return None;
        }
        let k = self.days.partition_point(|&d| d <= day);
        if k == n {
            return Some(self.values[n - 1]);
        }
        let (d0, d1) = (self.days[k - 1], self.days[k]);
        let w = (day - d0) / (d1 - d0);
        Some(self.values[k - 1] * (1.0 - w) + self.values[k] * w)
    }
}

/// Fractional day of year (1-based) of simulation day `day`.
fn day_of_year(epoch: Epoch, day: f64) -> f64 {
    let whole = day.floor();
    let date = epoch.date_at(whole);
    date.ordinal() as f64 + (day - whole)
}

/// Air temperature: weather.csv inside its date range, the scene's annual law outside.
#[derive(Debug, Clone)]
pub struct AirTemperature {
    epoch: Epoch,
    law: Air,
    weather: Option<Series>,
}

impl AirTemperature {
    pub fn new(epoch: Epoch, law: Air, weather: Option<Series>) -> Self {
        AirTemperature {
            epoch,
            law,
            weather,
        }
    }

    pub fn film_w_m2k(&self) -> f64 {
        self.law.film_w_m2k
    }

    pub fn at(&self, day: f64) -> f64 {
        if let Some(t) = self.weather.as_ref().and_then(|w| w.at(day)) {
            return t;
        }
        self.law.temperature_c(day_of_year(self.epoch, day))
    }
}

/// Reservoir: level by date, water temperature by depth below the surface.
#[derive(Debug, Clone)]
pub struct Water {
    epoch: Epoch,
    law: Reservoir,
    level: Series,
}

impl Water {
    pub fn new(epoch: Epoch, law: Reservoir, level: Series) -> Self {
        Water { epoch, law, level }
    }

    /// Water level \[m\]; `None` before impounding (before the first reservoir.csv row).
    /// After the last row the last level holds.
    pub fn level(&self, day: f64) -> Option<f64> {
        let first = self.level.first_day()?;
        if day < first {
            return None;
        }
        let last = self.level.last_day()?;
        self.level.at(day.min(last))
    }

    /// T(y, t) = bottom + (surface(t) − bottom)·e^{−decay·y}, y = depth below the surface.
    pub fn temperature(&self, day: f64, depth: f64) -> f64 {
        self.law.temperature_c(depth, day_of_year(self.epoch, day))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn epoch() -> Epoch {
        Epoch(NaiveDate::from_ymd_opt(2024, 1, 1).unwrap())
    }

    #[test]
    fn series_interpolates_and_refuses_outside() {
        let s = Series::from_dated(
            epoch(),
            &[
                (NaiveDate::from_ymd_opt(2024, 1, 11).unwrap(), 10.0),
                (NaiveDate::from_ymd_opt(2024, 1, 21).unwrap(), 20.0),
            ],
        );
        assert_eq!(s.at(15.0), Some(15.0));
        assert_eq!(s.at(10.0), Some(10.0));
        assert_eq!(s.at(20.0), Some(20.0));
        assert_eq!(s.at(9.9), None);
        assert_eq!(s.at(20.1), None);
    }

    #[test]
    fn air_law_peaks_on_warmest_day() {
        let air = AirTemperature::new(
            epoch(),
            Air {
                mean_c: 16.0,
                amplitude_c: 8.0,
                warmest_day_of_year: 200.0,
                film_w_m2k: 15.0,
            },
            None,
        );
        // day-of-year 200 of 2024 is simulation day 199
        assert!((air.at(199.0) - 24.0).abs() < 1e-12);
        // half a year before the peak (day-of-year 17.5 = simulation day 16.5)
        assert!((air.at(16.5) - 8.0).abs() < 1e-9);
    }

    #[test]
    fn weather_replaces_the_law_inside_its_dates_only() {
        let law = Air {
            mean_c: 16.0,
            amplitude_c: 0.0,
            warmest_day_of_year: 200.0,
            film_w_m2k: 15.0,
        };
        let weather = Series::from_dated(
            epoch(),
            &[
                (NaiveDate::from_ymd_opt(2024, 2, 1).unwrap(), 2.0),
                (NaiveDate::from_ymd_opt(2024, 2, 3).unwrap(), 6.0),
            ],
        );
        let air = AirTemperature::new(epoch(), law, Some(weather));
        assert_eq!(air.at(31.0), 2.0);
        assert_eq!(air.at(32.0), 4.0);
        assert_eq!(air.at(33.0), 6.0);
        assert_eq!(air.at(30.0), 16.0);
        assert_eq!(air.at(34.0), 16.0);
    }

    #[test]
    fn water_temperature_decays_to_bottom_value() {
        let w = Water::new(
            epoch(),
            Reservoir {
                surface_mean_c: 17.0,
                surface_amplitude_c: 0.0,
                warmest_day_of_year: 200.0,
                bottom_temp_c: 11.0,
                decay_per_m: 0.04,
            },
            Series::from_dated(
                epoch(),
                &[(NaiveDate::from_ymd_opt(2024, 6, 1).unwrap(), 100.0)],
            ),
        );
        assert!((w.temperature(0.0, 0.0) - 17.0).abs() < 1e-12);
        assert!((w.temperature(0.0, 25.0) - (11.0 + 6.0 * (-1.0f64).exp())).abs() < 1e-12);
        assert_eq!(w.level(10.0), None);
        assert_eq!(w.level(400.0), Some(100.0));
    }
}
