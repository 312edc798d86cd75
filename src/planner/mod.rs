//! The planner: readiness of each grouting zone on its planned date, and the
//! least supercooling or delay that makes a flagged zone groutable.

pub mod readiness;
pub mod settings;

pub use readiness::*;
pub use settings::{DecidingPoint, PlannerSettings};
pub mod edit;
pub mod plan;
pub mod rules;
pub mod runner;
pub mod search;

pub use plan::{plan, PlanOptions, PlanOutput, Progress};
