//! `readiness.csv`: one row per zone of the plan (history and to grout), as
//! a polars DataFrame written with polars' CSV writer. Missing values are
//! empty cells, dates ISO, values rounded to what the model resolves
//! (µm, 0.01 °C, 0.1 day, mm of elevation).

use std::fs::File;
use std::path::Path;

use polars::prelude::*;

use crate::planner::{Plan, RemedyChoice, ZoneReadiness};

/// Header of `readiness.csv`, in column order.
pub const COLUMNS: [&str; 28] = [
    "joint",
    "zone",
    "planned_date",
    "status",
    "z_bottom_m",
    "z_top_m",
    "aperture_upstream_mm",
    "aperture_center_mm",
    "aperture_downstream_mm",
    "aperture_min_mm",
    "temp_a_c",
    "temp_b_c",
    "closure_temp_c",
    "age_days",
    "cover_m",
    "verdict",
    "groutable",
    "reasons",
    "reopened_date",
    "remedy",
    "supercool_c",
    "supercool_aperture_mm",
    "delay_days",
    "delay_date",
    "delay_aperture_mm",
    "verified_verdict",
    "verified_aperture_mm",
    "note",
];

fn round(v: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (v * k).round() / k
}

fn rounded(v: Option<f64>, decimals: i32) -> Option<f64> {
    v.filter(|v| v.is_finite()).map(|v| round(v, decimals))
}

/// Columns of the frame built from a per-zone accessor.
struct Cols<'a>(&'a [ZoneReadiness]);

impl Cols<'_> {
    fn f64(&self, name: &str, decimals: i32, f: impl Fn(&ZoneReadiness) -> Option<f64>) -> Column {
        let v: Vec<Option<f64>> = self.0.iter().map(|z| rounded(f(z), decimals)).collect();
        Column::new(name.into(), v)
    }

    fn u32(&self, name: &str, f: impl Fn(&ZoneReadiness) -> Option<u32>) -> Column {
        let v: Vec<Option<u32>> = self.0.iter().map(f).collect();
        Column::new(name.into(), v)
    }

    fn str(&self, name: &str, f: impl Fn(&ZoneReadiness) -> Option<String>) -> Column {
        let v: Vec<Option<String>> = self.0.iter().map(f).collect();
        Column::new(name.into(), v)
    }

    fn bool(&self, name: &str, f: impl Fn(&ZoneReadiness) -> bool) -> Column {
        let v: Vec<bool> = self.0.iter().map(f).collect();
        Column::new(name.into(), v)
    }
}

/// The readiness table, one row per zone of `plan.zones`, in plan order.
pub fn frame(plan: &Plan) -> PolarsResult<DataFrame> {
    let c = Cols(&plan.zones);
    let supercool = |z: &ZoneReadiness| z.remedy.as_ref().and_then(|r| r.supercool.clone());
    let delay = |z: &ZoneReadiness| z.remedy.as_ref().and_then(|r| r.delay.clone());
    let verified = |z: &ZoneReadiness| z.remedy.as_ref().and_then(|r| r.verified);
    let columns = vec![
        c.u32("joint", |z| Some(z.joint)),
        c.u32("zone", |z| Some(z.zone)),
        c.str("planned_date", |z| Some(z.planned.to_string())),
        c.str("status", |z| {
            Some(if z.history { "history" } else { "to_grout" }.into())
        }),
        c.f64("z_bottom_m", 3, |z| Some(z.z_bottom_m)),
        c.f64("z_top_m", 3, |z| Some(z.z_top_m)),
        c.f64("aperture_upstream_mm", 3, |z| z.apertures_mm.upstream),
        c.f64("aperture_center_mm", 3, |z| z.apertures_mm.center),
        c.f64("aperture_downstream_mm", 3, |z| z.apertures_mm.downstream),
        c.f64("aperture_min_mm", 3, |z| z.apertures_mm.min),
        c.f64("temp_a_c", 2, |z| z.temp_a_c),
        c.f64("temp_b_c", 2, |z| z.temp_b_c),
        c.f64("closure_temp_c", 2, |z| Some(z.closure_temp_c)),
        c.f64("age_days", 1, |z| z.age_days),
        c.f64("cover_m", 3, |z| z.cover_m),
        c.str("verdict", |z| Some(z.verdict.as_str().into())),
        c.bool("groutable", |z| z.verdict.groutable()),
        c.str("reasons", |z| Some(z.reasons()).filter(|r| !r.is_empty())),
        c.str("reopened_date", |z| z.reopened.map(|d| d.to_string())),
        c.str("remedy", |z| {
            z.remedy.as_ref().map(|r| {
                match r.choice {
                    RemedyChoice::Supercool => "supercool",
                    RemedyChoice::Delay => "delay",
                    RemedyChoice::None => "none",
                }
                .into()
            })
        }),
        c.f64("supercool_c", 2, |z| supercool(z).map(|s| s.delta_c)),
        c.f64("supercool_aperture_mm", 3, |z| {
            supercool(z).map(|s| s.aperture_mm)
        }),
        c.u32("delay_days", |z| delay(z).map(|d| d.days)),
        c.str("delay_date", |z| delay(z).map(|d| d.date.to_string())),
        c.f64("delay_aperture_mm", 3, |z| delay(z).map(|d| d.aperture_mm)),
        c.str("verified_verdict", |z| {
            verified(z).map(|(v, _)| v.as_str().into())
        }),
        c.f64("verified_aperture_mm", 3, |z| {
            verified(z).and_then(|(_, a)| a)
        }),
        c.str("note", |z| {
            z.remedy
                .as_ref()
                .map(|r| r.note.clone())
                .filter(|n| !n.is_empty())
        }),
    ];
    debug_assert_eq!(
        columns
            .iter()
            .map(|c| c.name().as_str())
            .collect::<Vec<_>>(),
        COLUMNS
    );
    DataFrame::new(plan.zones.len(), columns)
}

/// Writes `readiness.csv` at `path`.
pub fn write_csv(path: &Path, plan: &Plan) -> PolarsResult<()> {
    let mut df = frame(plan)?;
    let file = File::create(path)?;
    CsvWriter::new(file).include_header(true).finish(&mut df)
}
