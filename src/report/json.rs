//! `report.json`: the whole plan for other tools, pretty-printed: scene,
//! as-of date, zone counts, every zone's readiness, the meter readings with
//! their error statistics per joint, and how the plan was computed (with which
//! approximations of the mechanics, if any).

use chrono::NaiveDate;
use serde::Serialize;

use super::meters::{self, MeterError};
use super::summary::Summary;
use crate::planner::{MeterComparison, Plan, PlanStats, ZoneReadiness};
use crate::scene::Approximation;

/// The document written to `report.json`.
#[derive(Debug, Serialize)]
pub struct ReportJson<'a> {
    pub scene: &'a str,
    pub as_of: NaiveDate,
    pub summary: Summary,
    pub zones: &'a [ZoneReadiness],
    pub meters: &'a [MeterComparison],
    pub meter_errors: Vec<MeterError>,
    pub stats: &'a PlanStats,
    /// the opt-in approximations of the mechanics (empty: the exact path)
    pub approximations: &'a [Approximation],
}

impl<'a> ReportJson<'a> {
    pub fn of(plan: &'a Plan) -> ReportJson<'a> {
        ReportJson {
            scene: &plan.scene,
            as_of: plan.as_of,
            summary: Summary::of(plan),
            zones: &plan.zones,
            meters: &plan.meters,
            meter_errors: meters::errors(&plan.meters),
            stats: &plan.stats,
            approximations: &plan.approximations,
        }
    }
}

/// The pretty-printed JSON text.
pub fn to_string(plan: &Plan) -> serde_json::Result<String> {
    let mut s = serde_json::to_string_pretty(&ReportJson::of(plan))?;
    s.push('\n');
    Ok(s)
}
