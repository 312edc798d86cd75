//! TEMPORARY placeholder until the report module lands (same API).
use std::path::{Path, PathBuf};

use crate::planner::Plan;

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
}

#[derive(Debug, Default)]
pub struct ReportFiles {
    pub files: Vec<PathBuf>,
}

pub fn write_all(_dir: &Path, _plan: &Plan) -> Result<ReportFiles, ReportError> {
    Ok(ReportFiles::default())
}

pub fn readiness_table(plan: &Plan) -> String {
    let mut s = String::new();
    for z in plan.to_grout() {
        s += &format!(
            "{} {} {} {:?} {:?} {} {:?}\n",
            z.joint,
            z.zone,
            z.planned,
            z.apertures_mm.min,
            z.verdict,
            z.reasons(),
            z.remedy
        );
    }
    s
}
