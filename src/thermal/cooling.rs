//! Cooling stages of `cooling.csv` turned into per-lift source increments.
//!
//! While a stage runs on a lift, Zhu's equivalent equation adds per step
//!   ΔS = (T0 − Tw)[φ(s1) − φ(s0)] + [H(s1) − H(s0)],
//!   H(s) = ∫_0^s φ(s − u) θ'(τ_k + u) du,
//! where s is time since the stage started, T0 the region's mean temperature
//! at the start, Tw the water temperature and τ_k the lift's age at the start.
//! Hydration is inside H, so θ' is not added again. A water change inside
//! the stage, from Tw to Tw + δ at day c (a row continuing the stage in
//! cooling.csv), keeps the stage's clock: by superposition the mean gains
//! δ·[1 − φ(t − c)], so each step after c adds −δ[φ(t1 − c) − φ(t0 − c)]
//! (`tests/it/thermal_closed_forms.rs`: an insulated block whose water
//! drops 4 °C on day 15 follows it to 1.4e-15). Outside a stage the
//! source is the adiabatic increment θ(τ1) − θ(τ0) alone. A stage ends at its
//! end date or at the first step end where the region's mean temperature has
//! fallen to its target: the target check is armed once the mean has been
//! above the target during the stage, so a first-stage cooling that starts on
//! fresh concrete cooler than its target runs through the hydration peak.

use serde::{Deserialize, Serialize};

use crate::material::{hydration_under_cooling, AdiabaticRise, ZhuPipe};

/// One cooling row of cooling.csv, resolved to days and lift range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedStage {
    pub block: u32,
    pub lift_from: u32,
    pub lift_to: u32,
    pub start_day: f64,
    pub end_day: Option<f64>,
    /// water temperature from the start [°C]
    pub water_temp_c: f64,
    pub target_temp_c: Option<f64>,
    /// cooling.csv line, for messages (of the stage's first row).
    pub line: usize,
    /// changes inside the stage, in time order: the rows continuing the
    /// first (see [`crate::schedule::cooling_chains`]); the stage's clock
    /// is kept
    #[serde(default)]
    pub changes: Vec<StageChange>,
}

/// New water (and target) from `day` inside a running stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StageChange {
    pub day: f64,
    pub water_temp_c: f64,
    pub target_temp_c: Option<f64>,
}

impl PlannedStage {
    /// The target in effect on `day` (that of the last change on or before
    /// it, else the stage's own).
    pub fn target_on(&self, day: f64) -> Option<f64> {
        self.changes
            .iter()
            .rev()
            .find(|c| c.day <= day)
            .map_or(self.target_temp_c, |c| c.target_temp_c)
    }

    /// The water changes, (day, new water temperature).
    pub fn water_changes(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.changes.iter().map(|c| (c.day, c.water_temp_c))
    }
}

/// Progress of one stage; plain data so it can be checkpointed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum StageStatus {
    Pending,
    Active {
        start_day: f64,
        t0_mean: f64,
        armed: bool,
    },
    Done {
        end_day: f64,
        reached_target: bool,
        /// the stage had a target, but its region was never warmer than it
        /// while the stage ran: the target had no effect (a warning)
        #[serde(default)]
        target_unused: bool,
    },
}

/// Source increment of one lift over [t0, t1], split into the adiabatic
/// hydration heat of the step and the total (hydration + pipes), both in °C
/// of the lift's concrete.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LiftIncrement {
    pub hydration: f64,
    pub total: f64,
}

/// What a lift needs to compute its source: its pour day and, if a stage runs
/// on it, the stage data.
pub struct LiftSourceInput<'a> {
    pub pour_day: f64,
    pub rise: Option<&'a AdiabaticRise>,
    pub stage: Option<ActiveStage<'a>>,
}

/// A running stage as seen by one lift.
pub struct ActiveStage<'a> {
    pub pipe: &'a ZhuPipe,
    pub start_day: f64,
    pub t0_mean: f64,
    pub water_temp_c: f64,
    /// changes of water inside the stage, in time order
    pub changes: &'a [StageChange],
}

/// The increment of one lift over the step [t0, t1] (t0 ≥ pour day).
pub fn lift_increment(input: &LiftSourceInput<'_>, t0: f64, t1: f64) -> LiftIncrement {
    let age0 = (t0 - input.pour_day).max(0.0);
    let age1 = (t1 - input.pour_day).max(0.0);
    let hydration = input
        .rise
        .map(|r| r.theta(age1) - r.theta(age0))
        .unwrap_or(0.0);
    let total = match &input.stage {
        None => hydration,
        Some(st) => {
            let s0 = (t0 - st.start_day).max(0.0);
            let s1 = (t1 - st.start_day).max(0.0);
            let mut pipe_part =
                (st.t0_mean - st.water_temp_c) * (st.pipe.phi(s1) - st.pipe.phi(s0));
            // Superposition of each water change δ at day c: the mean gains
            // δ·[1 − φ(t − c)], so the step's source gains −δ·Δφ after c.
            let mut water = st.water_temp_c;
            for c in st.changes {
                let (c0, c1) = ((t0 - c.day).max(0.0), (t1 - c.day).max(0.0));
                pipe_part -= (c.water_temp_c - water) * (st.pipe.phi(c1) - st.pipe.phi(c0));
                water = c.water_temp_c;
            }
            let heat_part = match input.rise {
                Some(r) => {
                    let tau_k = (st.start_day - input.pour_day).max(0.0);
                    hydration_under_cooling(st.pipe, r, tau_k, s1)
                        - hydration_under_cooling(st.pipe, r, tau_k, s0)
                }
                None => 0.0,
            };
            pipe_part + heat_part
        }
    };
    LiftIncrement { hydration, total }
}
