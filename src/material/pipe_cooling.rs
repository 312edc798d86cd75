//! Zhu Bofang's equivalent (homogenised) pipe-cooling method.

use serde::{Deserialize, Serialize};

/// Geometry and hydraulics of one embedded cooling-pipe layout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipeLayout {
    /// Horizontal pipe spacing S1 [m].
    pub spacing_horizontal_m: f64,
    /// Vertical pipe spacing S2 [m] (usually the lift height or half of it).
    pub spacing_vertical_m: f64,
    /// Length L of one pipe coil [m].
    pub length_m: f64,
    /// Water flow q_w [L/min].
    pub flow_l_per_min: f64,
    /// Outer pipe radius c [m].
    pub outer_radius_m: f64,
    /// Inner pipe radius r0 [m].
    pub inner_radius_m: f64,
    /// Conductivity of the pipe wall λ1 [W/(m K)]: HDPE ≈ 0.4–1.7, steel ≈ 45.
    pub wall_conductivity_w_mk: f64,
    /// Water density [kg/m³], default 1000.
    #[serde(default = "default_water_density")]
    pub water_density: f64,
    /// Water specific heat [J/(kg K)], default 4186.
    #[serde(default = "default_water_specific_heat")]
    pub water_specific_heat: f64,
}

fn default_water_density() -> f64 {
    1000.0
}
fn default_water_specific_heat() -> f64 {
    4186.0
}

/// φ(t) = exp(−p t^s) of the equivalent cooling cylinder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ZhuPipe {
    pub p: f64,
    pub s: f64,
}
