//! The planner: will each grouting zone be groutable on its planned date,
//! and if not, what is the least supercooling or delay that fixes it?
//!
//! The pipeline, one file each:
//! - [`runner`]: the baseline simulation up to the last zone due, keeping
//!   checkpoints; every re-simulation restarts from the latest checkpoint on
//!   or before the first date its edited schedules differ ([`edit::first_change`]);
//! - [`rules`]: the readiness rules on a zone and a day, read from a run's
//!   histories (aperture at the deciding point inside the grout stops, both
//!   blocks at closure temperature, age, cover, bottom-up order);
//! - [`edit`]: the schedule edits a remedy makes (supercooling from the as-of
//!   date on, moved grouting dates);
//! - [`search`]: the remedy search, every answer a re-simulation;
//! - [`joint_remedy`]: neighbouring zones' supercooling chosen together as
//!   a least-cost linear program, verified by re-simulation;
//! - [`whatif`]: one zone's remedy of the engineer's choosing, re-simulated
//!   the same way (the TUI's what-if);
//! - [`plan()`]: all of it for one scene and schedules, into a [`Plan`]
//!   ([`readiness`]) that the reports and the TUI read.
//!
//! Verified by: `tests/it/restart.rs` (a restarted run equals an uninterrupted
//! one, also after schedule edits, to 1e-15 relative), `tests/it/planner_supercool.rs`
//! (the supercooling found is the least on the grid that makes the zone
//! groutable when the remedied schedules are simulated from scratch),
//! `tests/it/demo_plan.rs` (the same for the demo's delays), `tests/it/cli_plan.rs`
//! (exit codes, atomic run folders, weekly restart, joint meters, bad input).

pub mod edit;
pub mod joint_remedy;
pub mod limits;
pub mod memo;
pub mod plan;
pub mod readiness;
pub mod rules;
pub mod run;
pub mod runner;
pub mod search;
pub mod whatif;

pub use plan::{judge_planned, plan, PlanOptions, PlanOutput, Progress};
pub use readiness::*;
pub use run::PlannedRun;
