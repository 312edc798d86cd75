//! Heat bookkeeping of a run: every joule that enters or leaves the live
//! concrete and rock, so a test can prove
//!   E(end) − E(start) = births + hydration + pipes + air + water + far
//! to round-off, with E = Σ c_i T_i (lumped nodal capacities, J).

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HeatLedger {
    /// Stored heat Σ c_i T_i at the start of the run \[J\].
    pub stored_start: f64,
    /// Heat brought in by newborn elements at their placement temperature \[J\].
    pub births: f64,
    /// Adiabatic hydration heat released \[J\].
    pub hydration: f64,
    /// Heat removed (negative) or added by pipes, net of hydration \[J\].
    pub pipes: f64,
    /// Convective exchange with air \[J\].
    pub air: f64,
    /// Heat through submerged (prescribed-temperature) nodes \[J\].
    pub water: f64,
    /// Heat through far faces held at a fixed temperature (`[boundary]`) \[J\].
    #[serde(default)]
    pub far: f64,
}

impl HeatLedger {
    pub fn inflow(&self) -> f64 {
        self.births + self.hydration + self.pipes + self.air + self.water + self.far
    }
}
