//! Reports of a plan, written into a folder the caller provides (and makes
//! atomic):
//!
//! - `readiness.csv`: one row per zone (`table`)
//! - `report.md`: the report to read (`markdown`)
//! - `report.json`: the plan for other tools (`json`)
//! - `charts/zone_J<j>_Z<z>.svg`: aperture and temperature history of every
//!   zone the plan has a history of (and the remedy's verified run), and
//!   `charts/meter_J<j>_Z<z>_<point>.svg`: every joint meter against the
//!   prediction (`charts`, drawn by `svg`)
//!
//! and the readiness table for the terminal (`terminal`).

pub mod charts;
pub mod distribution;
pub mod json;
pub mod markdown;
pub mod meters;
pub mod reopening;
pub mod scale;
pub mod summary;
pub mod svg;
pub mod table;
pub mod terminal;
pub mod words;

use std::path::{Path, PathBuf};

use crate::planner::Plan;

pub use distribution::GroutingDistribution;
pub use reopening::Reopening;
pub use summary::Summary;
pub use terminal::readiness_table;

/// A report file that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write \"{}\": {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write the readiness table \"{}\": {source}", path.display())]
    Csv {
        path: PathBuf,
        source: polars::error::PolarsError,
    },
    #[error("cannot write \"{}\": {source}", path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
}

/// The files written, as full paths.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReportFiles {
    pub csv: PathBuf,
    pub markdown: PathBuf,
    pub json: PathBuf,
    /// `charts/zone_J<j>_Z<z>.svg`, in the order of `plan.histories`
    pub zone_charts: Vec<PathBuf>,
    /// `charts/meter_J<j>_Z<z>_<point>.svg`, by joint, zone, point
    pub meter_charts: Vec<PathBuf>,
}

impl ReportFiles {
    /// Every file, tables first.
    pub fn all(&self) -> Vec<&Path> {
        [&self.csv, &self.markdown, &self.json]
            .into_iter()
            .chain(&self.zone_charts)
            .chain(&self.meter_charts)
            .map(PathBuf::as_path)
            .collect()
    }
}

fn write(path: PathBuf, text: &str) -> Result<PathBuf, ReportError> {
    match std::fs::write(&path, text) {
        Ok(()) => Ok(path),
        Err(source) => Err(ReportError::Io { path, source }),
    }
}

/// Writes every report file of `plan` into the existing folder `dir`.
pub fn write_all(dir: &Path, plan: &Plan) -> Result<ReportFiles, ReportError> {
    let csv = dir.join("readiness.csv");
    table::write_csv(&csv, plan).map_err(|source| ReportError::Csv {
        path: csv.clone(),
        source,
    })?;

    let json_path = dir.join("report.json");
    let json_text = json::to_string(plan).map_err(|source| ReportError::Json {
        path: json_path.clone(),
        source,
    })?;
    let json = write(json_path, &json_text)?;

    let series = meters::series(&plan.meters);
    let charts = dir.join("charts");
    if !plan.histories.is_empty() || !series.is_empty() {
        std::fs::create_dir_all(&charts).map_err(|source| ReportError::Io {
            path: charts.clone(),
            source,
        })?;
    }
    let zone_charts = plan
        .histories
        .iter()
        .map(|h| {
            write(
                charts.join(charts::zone_chart_file(h.joint, h.zone)),
                &charts::zone_chart(
                    h,
                    plan.zones
                        .iter()
                        .find(|z| z.joint == h.joint && z.zone == h.zone),
                    &plan.settings,
                ),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let meter_charts = series
        .iter()
        .map(|s| {
            let history = plan
                .histories
                .iter()
                .find(|h| h.joint == s.joint && h.zone == s.zone);
            write(
                charts.join(charts::meter_chart_file(s.joint, s.zone, s.point)),
                &charts::meter_chart(s, history, &plan.settings),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;

    // Written last: its chart links point at files that now exist.
    let markdown = write(dir.join("report.md"), &markdown::render(plan))?;

    Ok(ReportFiles {
        csv,
        markdown,
        json,
        zone_charts,
        meter_charts,
    })
}
