//! What-if: the engineer's own remedy for one zone (supercooling ΔT, a new
//! grouting date, or both), re-simulated from the baseline's checkpoints and
//! checked by the same rules as the plan.
//!
//! The edit is the planner's: supercooling from the as-of date on
//! ([`edit::supercool`]), a new date moving the zones above on the same joint
//! that would otherwise be grouted before it (bottom-up order), as the delay
//! search does.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use chrono::NaiveDate;

use crate::schedule::{DamLayout, Schedules};
use crate::sim::SimError;
use crate::vocab::{Day, ZoneId};

use super::edit::{self, Supercool};
use super::plan::zone_history;
use super::readiness::{ZoneHistory, ZoneReadiness};
use super::rules::{HistoryIndex, Rules};
use super::runner::{Runner, Span};
use super::search::{grout_days, lifts_above};

/// One what-if on one zone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WhatIf {
    pub joint: u32,
    pub zone: u32,
    /// supercooling of the zone's cooling from the as-of date [°C] (0: none)
    pub supercool_c: f64,
    /// the grouting date to check (the planned date: no delay)
    pub date: NaiveDate,
}

impl WhatIf {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }
}

/// The what-if's answer.
#[derive(Debug, Clone)]
pub struct WhatIfOutcome {
    pub what_if: WhatIf,
    /// the edited schedules (what the site would be sent)
    pub schedules: Schedules,
    /// the zone's readiness on the what-if date
    pub readiness: ZoneReadiness,
    pub history: ZoneHistory,
    /// zones above on the same joint moved with it
    pub also_moved: Vec<u32>,
    /// why the supercooling could not be applied (its cooling stage runs
    /// from before the as-of date past the grouting date)
    pub not_applied: Option<String>,
    pub seconds: f64,
}

/// The schedules of a what-if: returns them, the zones above that move with
/// it, and how much of the supercooling found a stage it may edit.
pub fn edit_schedules(
    base: &Schedules,
    layout: &DamLayout,
    rules: &Rules,
    as_of: NaiveDate,
    w: &WhatIf,
) -> (Schedules, Vec<u32>, Applied) {
    let mut s = base.clone();
    let mut also = Vec::new();
    let planned = base.grouting_of(w.zone_id()).map(|g| g.planned);
    if planned.is_some_and(|p| p != w.date) {
        also = base
            .grouting
            .iter()
            .filter(|g| g.joint == w.joint && g.zone > w.zone && g.planned < w.date)
            .map(|g| g.zone)
            .collect();
        let moves: Vec<(ZoneId, NaiveDate)> = std::iter::once(w.zone)
            .chain(also.iter().copied())
            .map(|z| (ZoneId::new(w.joint, z), w.date))
            .collect();
        s = edit::regrout(&s, &moves);
    }
    let mut applied = Applied::Yes;
    if w.supercool_c > 0.0 {
        let sc = [Supercool {
            zone: w.zone_id(),
            delta_c: w.supercool_c,
            planned: w.date,
            from: as_of,
        }];
        let coldest = rules.settings.min_water_temp_c;
        let (cooled, not_editable) =
            edit::supercool_with_water(&s, layout, &sc, lifts_above(rules), coldest);
        // The zone's own lifts alone: is their stage editable?
        let (_, own_not_editable) = edit::supercool_with_water(&s, layout, &sc, 0, coldest);
        applied = if !not_editable.is_empty() {
            Applied::No
        } else if !own_not_editable.is_empty() {
            Applied::OnlyAbove
        } else {
            Applied::Yes
        };
        s = cooled;
    }
    (s, also, applied)
}

/// How much of a what-if's supercooling could be applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Applied {
    Yes,
    /// only the lifts above the zone: its own stage started before the
    /// as-of date and runs past the grouting date, or has no target
    OnlyAbove,
    /// no lift at all
    No,
}

/// Runs a what-if: edits the baseline's schedules, re-simulates from the
/// latest checkpoint before the edit (to the later of the what-if date and
/// the baseline's end), and checks the zone. `cancel` stops it between steps
/// with [`SimError::Cancelled`]; `progress` gets (day, end).
pub fn run(
    runner: &Runner,
    layout: &DamLayout,
    as_of: NaiveDate,
    w: &WhatIf,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(f64, f64),
) -> Result<WhatIfOutcome, SimError> {
    let t = Instant::now();
    let settings = &runner.scene.planner;
    let epoch = runner.scene.epoch;
    let rules = Rules::new(settings, layout, runner.mesh, epoch, &runner.base);
    let (schedules, also_moved, applied) = edit_schedules(&runner.base, layout, &rules, as_of, w);
    let base_end = runner
        .history
        .joint_records
        .rows
        .last()
        .map_or(Day(0), |r| r.0);
    let span = Span {
        end_day: rules.epoch.day(w.date).max(base_end),
        observe: vec![],
    };
    let history = runner.simulate_with(&schedules, &span, cancel, progress)?;
    let rules = Rules::new(settings, layout, runner.mesh, epoch, &schedules);
    let idx = HistoryIndex::new(&history);
    let grout = grout_days(&rules, &schedules);
    let mut readiness = rules.evaluate(&idx, w.zone_id(), rules.epoch.day(w.date), &grout);
    readiness.history = false;
    let zone_h = zone_history(&rules, &idx, w.zone_id(), w.date);
    Ok(WhatIfOutcome {
        what_if: *w,
        schedules,
        readiness,
        history: zone_h,
        also_moved,
        not_applied: match applied {
            Applied::Yes => None,
            Applied::OnlyAbove => Some(format!(
                "only the lifts above were supercooled: the zone's own lifts have no \
                 cooling stage with a target starting before {}",
                w.date
            )),
            Applied::No => Some(format!(
                "nothing supercooled: no lift of the zone has a cooling stage with a \
                 target starting before {} (from {as_of})",
                w.date
            )),
        },
        seconds: t.elapsed().as_secs_f64(),
    })
}
