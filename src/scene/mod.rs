//! Scene files (`models/*.toml`): what is simulated, on which geometry, with
//! which materials. Loading validates every value and names the offending key.

use std::path::PathBuf;

use chrono::NaiveDate;
use serde::{Deserialize, Serialize};

use crate::material::{AdiabaticRise, PipeLayout};
use crate::mesh::geometry::Geometry;

/// One physical effect a scene may switch on. Anything not listed costs nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Heat of cement hydration (adiabatic rise by age).
    Hydration,
    /// Embedded pipe cooling (Zhu's equivalent method), driven by cooling.csv.
    PipeCooling,
    /// Convection to air on exposed faces (annual law or weather.csv).
    Ambient,
    /// Reservoir water temperature on submerged faces (reservoir.csv).
    ReservoirTemperature,
}

impl Effect {
    pub fn is_thermal(self) -> bool {
        matches!(
            self,
            Effect::Hydration | Effect::PipeCooling | Effect::Ambient | Effect::ReservoirTemperature
        )
    }
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Human name shown in reports.
    pub name: String,
    /// Day 0 of the simulation.
    pub epoch: NaiveDate,
    /// Default schedules folder, relative to the scene file's folder.
    #[serde(default)]
    pub schedules: Option<PathBuf>,
    /// Effects simulated (see [`Effect`]).
    #[serde(default)]
    pub effects: Vec<Effect>,
    pub geometry: Geometry,
    pub lifts: Lifts,
    pub joints: JointSettings,
    pub concrete: Concrete,
    #[serde(default)]
    pub rock: Option<Rock>,
    #[serde(default)]
    pub pipes: Option<PipeLayout>,
    #[serde(default)]
    pub air: Option<Air>,
    #[serde(default)]
    pub reservoir: Option<Reservoir>,
    #[serde(default)]
    pub time: TimeStepping,
    #[serde(default)]
    pub output: OutputSettings,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lifts {
    /// Lift height [m]; element layers follow lifts.
    pub height_m: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSettings {
    /// Grouting-zone height [m]; must be a whole number of lifts.
    pub zone_height_m: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Concrete {
    pub density_kg_m3: f64,
    pub specific_heat_j_kgk: f64,
    pub conductivity_w_mk: f64,
    /// Adiabatic temperature rise; required by the `hydration` effect.
    #[serde(default)]
    pub adiabatic: Option<AdiabaticRise>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rock {
    pub density_kg_m3: f64,
    pub specific_heat_j_kgk: f64,
    pub conductivity_w_mk: f64,
    /// Initial rock temperature at the deepest foundation elevation [°C].
    pub initial_temp_c: f64,
    /// Initial temperature gradient, positive = warmer with depth [°C/m], default 0.
    #[serde(default)]
    pub gradient_c_per_m: f64,
}

/// Air temperature Ta = mean + amplitude·cos(2π(d − warmest_day)/365), d = day of year.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Air {
    pub mean_c: f64,
    pub amplitude_c: f64,
    /// Day of year (1–366) of the warmest air.
    pub warmest_day_of_year: f64,
    /// Surface film coefficient β [W/(m² K)] between concrete/rock and air.
    pub film_w_m2k: f64,
}

/// Reservoir water temperature T(y, t) = bottom + (surface(t) − bottom)·e^{−decay·y}, y = depth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reservoir {
    pub surface_mean_c: f64,
    pub surface_amplitude_c: f64,
    pub warmest_day_of_year: f64,
    pub bottom_temp_c: f64,
    /// Decay of the surface oscillation with depth [1/m], typically 0.03–0.05.
    pub decay_per_m: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CapacityKind {
    /// Row-summed capacity: monotone, no overshoot after a pour (default).
    Lumped,
    /// Consistent capacity: more accurate on fine meshes, overshoots on coarse ones.
    Consistent,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TimeStepping {
    /// First step after a pour or a stage change [d], default 0.25.
    pub first_step_days: f64,
    /// Growth factor of the step while nothing happens, default 2.
    pub growth: f64,
    /// Longest step [d], default 4.
    pub max_step_days: f64,
    /// θ of the θ-method: 1 = backward Euler (default), 0.5 = Crank–Nicolson.
    pub theta: f64,
    pub capacity: CapacityKind,
    /// Last simulated date; default = 60 days after the last scheduled event.
    pub end_date: Option<NaiveDate>,
}

impl Default for TimeStepping {
    fn default() -> Self {
        TimeStepping {
            first_step_days: 0.25,
            growth: 2.0,
            max_step_days: 4.0,
            theta: 1.0,
            capacity: CapacityKind::Lumped,
            end_date: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSettings {
    /// Dates of VTU snapshots.
    pub snapshots: Vec<NaiveDate>,
}
