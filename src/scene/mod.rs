//! Scene files (`models/*.toml`): what is simulated, on which geometry, with
//! which materials. Loading validates every value and names the offending key.
//!
//! # Format
//!
//! A scene is one TOML document. Top-level keys: `name`, `epoch` (day 0 of the
//! simulation, `YYYY-MM-DD`, quoted or bare), `schedules` (folder of the CSV
//! inputs, relative to the scene file's folder) and `effects` (a list of
//! `hydration`, `pipe_cooling`, `ambient`, `reservoir_temperature`). Tables:
//!
//! | table | required | content |
//! |---|---|---|
//! | `[geometry]` | yes | `kind = "blocks"`, `"arch"` or `"arch_table"` (with its CSV tables beside the scene, read by [`Scene::load`]) plus the generator's parameters ([`Geometry`]) |
//! | `[lifts]` | yes | `height_m` |
//! | `[joints]` | yes | `zone_height_m`, a whole number of lifts |
//! | `[concrete]` | yes | `density_kg_m3`, `specific_heat_j_kgk`, `conductivity_w_mk`, `[concrete.adiabatic]` |
//! | `[rock]` | when `geometry.rock_depth_m > 0` | rock properties and initial temperature |
//! | `[boundary.<side>]` | no | per far side (`base`, `upstream`, `downstream`, `left_bank`, `right_bank`): `temperature_c` (absent = adiabatic) and `support` (`fixed` default, `rollers`, `free`) ([`Boundary`]) |
//! | `[pipes]` | with `pipe_cooling` | cooling-pipe layout ([`PipeLayout`]) |
//! | `[air]` | with `ambient` | annual air temperature and surface film coefficient |
//! | `[reservoir]` | with `reservoir_temperature` | reservoir water temperature by depth |
//! | `[time]` | no | step ladder and θ-method |
//! | `[output]` | no | snapshot dates |
//!
//! Unknown keys are errors (`deny_unknown_fields` everywhere). Keys carrying a
//! unit other than the code's (m, day, °C) say so in their name. The commented
//! reference for every key is `models/demo_arch.toml`.
//!
//! ```no_run
//! use groutready::scene::Scene;
//! let path = std::path::Path::new("models/demo_arch.toml");
//! let scene = Scene::load(path)?;
//! let csv_dir = scene.schedules_dir(path);
//! # Ok::<(), groutready::scene::SceneError>(())
//! ```

pub mod approximation;
mod boundary;
mod error;
mod planner;
pub mod preset;
mod validate;

use std::path::{Path, PathBuf};

use chrono::NaiveDate;
use serde::{Deserialize, Serialize};

use crate::material::{AdiabaticRise, AutogenousLaw, CreepLaw, ModulusLaw, PipeLayout};
use crate::mesh::geometry::Geometry;
use crate::vocab::{Epoch, Invalid};

pub use approximation::Approximation;
pub use boundary::{Boundary, FarFace, Support};
pub use error::SceneError;
pub use planner::PlannerSettings;
pub use preset::Preset;

/// Seconds per day: heat flows in W are turned into J/day with this factor.
pub const SECONDS_PER_DAY: f64 = 86_400.0;

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
    /// Stresses from temperature changes (needs the thermal field, or none if no thermal effect).
    ThermalStrain,
    /// Self-weight of each lift, applied when it is poured.
    SelfWeight,
    /// Creep of concrete (Zhu's compliance, exponential recursion).
    Creep,
    /// Autogenous volume change of concrete.
    Autogenous,
    /// Hydrostatic water pressure on the upstream face (reservoir.csv).
    ReservoirLoad,
    /// Contact–joint composite elements on the transverse joints.
    Joints,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Human name shown in reports.
    pub name: String,
    /// Day 0 of the simulation (`YYYY-MM-DD`, quoted or a bare TOML date).
    #[serde(deserialize_with = "dates::epoch")]
    pub epoch: Epoch,
    /// Default schedules folder, relative to the scene file's folder.
    #[serde(default)]
    pub schedules: Option<PathBuf>,
    /// Effects simulated (see [`Effect`]).
    #[serde(default)]
    pub effects: Vec<Effect>,
    /// Mesh generator and its parameters (`[geometry]`, `kind = "blocks" | "arch" | "arch_table"`).
    pub geometry: Geometry,
    /// Lift (pour layer) height.
    pub lifts: Lifts,
    /// Transverse joints: grouting-zone height.
    pub joints: JointSettings,
    /// Dam concrete.
    pub concrete: Concrete,
    /// Foundation rock; required when `geometry.rock_depth_m > 0`.
    #[serde(default)]
    pub rock: Option<Rock>,
    /// Far faces per side: fixed temperature or adiabatic, support
    /// (`[boundary.<side>]`; default adiabatic and fixed everywhere).
    #[serde(default, skip_serializing_if = "Boundary::is_default")]
    pub boundary: Boundary,
    /// Cooling-pipe layout; required by `pipe_cooling`.
    #[serde(default)]
    pub pipes: Option<PipeLayout>,
    /// Air temperature and surface film; required by `ambient`.
    #[serde(default)]
    pub air: Option<Air>,
    /// Reservoir water temperature; required by `reservoir_temperature`.
    #[serde(default)]
    pub reservoir: Option<Reservoir>,
    /// Time stepping (all keys optional).
    #[serde(default)]
    pub time: TimeStepping,
    /// Output settings (all keys optional).
    #[serde(default)]
    pub output: OutputSettings,
    #[serde(default)]
    pub solver: SolverSettings,
    /// Readiness rules and remedy search (all keys optional).
    #[serde(default)]
    pub planner: crate::scene::PlannerSettings,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lifts {
    /// Lift height \[m\]; element layers follow lifts.
    pub height_m: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSettings {
    /// Grouting-zone height \[m\]; must be a whole number of lifts.
    pub zone_height_m: f64,
    /// Static Coulomb friction of an ungrouted joint, default 0.6.
    #[serde(default = "default_mu_static")]
    pub mu_static: f64,
    /// Kinetic Coulomb friction (≤ static), default 0.5.
    #[serde(default = "default_mu_kinetic")]
    pub mu_kinetic: f64,
    /// Gap of a joint when its second block is poured \[m\], default 0.
    #[serde(default)]
    pub initial_gap_m: f64,
    /// Normal modulus E_z of the grout layer \[Pa\], default 2.0e10.
    #[serde(default = "default_grout_modulus")]
    pub grout_modulus_pa: f64,
    /// Shear moduli G_x = G_y of the grout layer \[Pa\], default 8.0e9.
    #[serde(default = "default_grout_shear")]
    pub grout_shear_modulus_pa: f64,
    /// Smallest grout-layer thickness \[m\]: a zone grouted with a smaller
    /// aperture gets this thickness (k = D/t stays finite); default 0.5e-3.
    #[serde(default = "default_grout_min_thickness")]
    pub grout_min_thickness_m: f64,
    /// Tensile bond strength of a grouted joint \[Pa\]: a larger normal tension
    /// cracks it and the zone is recorded as reopened; default 1.0e6.
    #[serde(default = "default_bond_strength")]
    pub bond_strength_pa: f64,
    /// Distance \[m\] of a zone's grout stops from the upstream and
    /// downstream faces, along the joint face: the zone's deciding aperture
    /// (`min`) is the smallest of the aperture field at least this far from
    /// both faces. Absent (the default): the smallest at the joint nodes off
    /// the faces, i.e. one element in from each face, a point that moves
    /// with the mesh across the thickness (see `mechanics::grout_stops`).
    #[serde(default)]
    pub grout_stop_inset_m: Option<f64>,
}

fn default_grout_modulus() -> f64 {
    2.0e10
}
fn default_grout_shear() -> f64 {
    8.0e9
}
fn default_grout_min_thickness() -> f64 {
    0.5e-3
}
fn default_bond_strength() -> f64 {
    1.0e6
}

fn default_mu_static() -> f64 {
    0.6
}
fn default_mu_kinetic() -> f64 {
    0.5
}

/// λ, ρ and c of a material, and what the heat equation needs from them:
/// the one implementation behind [`Concrete`] and [`Rock`].
///
/// Both tables keep the three keys as their own fields. Embedding one
/// struct with `#[serde(flatten)]` would keep the TOML format, but serde
/// cannot combine `flatten` with `deny_unknown_fields`: a misspelt key then
/// reads as the correct key missing, and unknown keys lose their position
/// and the list of expected keys (`tests/it/scene_errors.rs`).
pub trait ThermalProperties {
    /// Density ρ [kg/m³].
    fn density_kg_m3(&self) -> f64;
    /// Specific heat c [J/(kg K)].
    fn specific_heat_j_kgk(&self) -> f64;
    /// Thermal conductivity λ [W/(m K)].
    fn conductivity_w_mk(&self) -> f64;

    /// λ in J/(m·day·K).
    fn conductivity_j_per_m_day_k(&self) -> f64 {
        self.conductivity_w_mk() * SECONDS_PER_DAY
    }

    /// Volumetric heat capacity ρc [J/(m³ K)].
    fn heat_capacity_j_m3k(&self) -> f64 {
        self.density_kg_m3() * self.specific_heat_j_kgk()
    }

    /// Diffusivity a = λ/(ρc) [m²/day].
    fn diffusivity_m2_per_day(&self) -> f64 {
        self.conductivity_j_per_m_day_k() / self.heat_capacity_j_m3k()
    }
}

/// `[concrete]`: the dam concrete's thermal properties
/// ([`ThermalProperties`]) and its laws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Concrete {
    /// Density ρ [kg/m³].
    pub density_kg_m3: f64,
    /// Specific heat c [J/(kg K)].
    pub specific_heat_j_kgk: f64,
    /// Thermal conductivity λ [W/(m K)].
    pub conductivity_w_mk: f64,
    /// Adiabatic temperature rise; required by the `hydration` effect.
    #[serde(default)]
    pub adiabatic: Option<AdiabaticRise>,
    /// E(τ) = e0_pa·(1 − exp(−a τ^b)); required by any mechanical effect.
    #[serde(default)]
    pub modulus: Option<ModulusLaw>,
    /// Poisson's ratio; required by any mechanical effect.
    #[serde(default)]
    pub poisson: Option<f64>,
    /// Linear thermal expansion α [1/°C]; required by `thermal_strain`.
    #[serde(default)]
    pub expansion_per_c: Option<f64>,
    /// Creep compliance terms; required by `creep`.
    #[serde(default)]
    pub creep: Option<CreepLaw>,
    /// G(τ) = eps_inf·(1 − exp(−c τ^d)); required by `autogenous`.
    #[serde(default)]
    pub autogenous: Option<AutogenousLaw>,
    /// The temperature a new lift's nodes shared with older concrete or
    /// rock take at its pour: `keep` (default, the older material's) or
    /// `placement` (the pour's placement temperature).
    #[serde(default, skip_serializing_if = "SharedNodes::is_keep")]
    pub placement_on_shared_nodes: SharedNodes,
}

/// `concrete.placement_on_shared_nodes` (see the thermal module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SharedNodes {
    /// Shared nodes keep the temperature of the concrete or rock below.
    #[default]
    Keep,
    /// Shared nodes take the new lift's placement temperature.
    Placement,
}

impl SharedNodes {
    fn is_keep(&self) -> bool {
        *self == SharedNodes::Keep
    }
}

/// `[rock]`: the foundation rock's thermal properties
/// ([`ThermalProperties`]), initial temperature and elastic constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rock {
    /// Density ρ [kg/m³].
    pub density_kg_m3: f64,
    /// Specific heat c [J/(kg K)].
    pub specific_heat_j_kgk: f64,
    /// Thermal conductivity λ [W/(m K)].
    pub conductivity_w_mk: f64,
    /// Initial rock temperature at the deepest foundation elevation [°C].
    pub initial_temp_c: f64,
    /// Initial temperature gradient, positive = warmer with depth [°C/m], default 0.
    #[serde(default)]
    pub gradient_c_per_m: f64,
    /// Elastic modulus of the rock \[Pa\]; required by any mechanical effect when the mesh has rock.
    #[serde(default)]
    pub modulus_pa: Option<f64>,
    /// Poisson's ratio of the rock.
    #[serde(default)]
    pub poisson: Option<f64>,
    /// Thermal expansion of the rock [1/°C] (default: none).
    #[serde(default)]
    pub expansion_per_c: Option<f64>,
}

/// Air temperature Ta = mean + amplitude·cos(2π(d − warmest_day)/365), d = day of year.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Air {
    /// Annual mean air temperature A [°C].
    pub mean_c: f64,
    /// Annual amplitude B [°C] (≥ 0).
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
    /// Annual mean temperature of the surface water [°C].
    pub surface_mean_c: f64,
    /// Annual amplitude of the surface water temperature [°C] (≥ 0).
    pub surface_amplitude_c: f64,
    /// Day of year (1–366) of the warmest surface water.
    pub warmest_day_of_year: f64,
    /// Temperature of the deep water [°C] (constant in time).
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

impl CapacityKind {
    /// The scene key's value.
    pub fn name(self) -> &'static str {
        match self {
            CapacityKind::Lumped => "lumped",
            CapacityKind::Consistent => "consistent",
        }
    }

    /// The other form (the accuracy study's capacity knob).
    pub fn other(self) -> CapacityKind {
        match self {
            CapacityKind::Lumped => CapacityKind::Consistent,
            CapacityKind::Consistent => CapacityKind::Lumped,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TimeStepping {
    /// First step after a pour or a stage change \[d\], default 0.25.
    pub first_step_days: f64,
    /// Growth factor of the step while nothing happens, default 2.
    pub growth: f64,
    /// Longest step \[d\], default 4.
    pub max_step_days: f64,
    /// Explicit multi-rate steps after each pour or stage change, e.g.
    /// `[{ step_days = 0.1, until_days = 2 }, { step_days = 0.25, until_days = 7 }]`:
    /// 0.1 d steps for the first 2 days, then 0.25 d to day 7; past the last
    /// entry the ladder's own step (`first_step_days` grown since the pour,
    /// at most `max_step_days`). Default none (the ladder alone).
    pub step_schedule: Vec<ScheduledStep>,
    /// θ of the θ-method: 1 = backward Euler (default), 0.5 = Crank–Nicolson.
    pub theta: f64,
    /// Capacity matrix, `lumped` (default) or `consistent`.
    pub capacity: CapacityKind,
    /// Longest mechanical step [whole days], default 1 (the exact path: a
    /// step every midnight). Above 1 an approximation for speed: while
    /// nothing is poured or grouted and no history row is read, the
    /// mechanics takes one step over up to this many days (the joint
    /// history holds the last step's apertures in between); at most 30.
    /// A cooling stage's start or end alone does not end such a step (the
    /// mechanics sees the pipes only through the temperatures at its ends
    /// and midnights: each day's change of temperature strains the concrete
    /// at that day's modulus). Measured with 3: the small dam 151 against
    /// 264 steps, its apertures at the grouting dates off by up to 0.464 mm
    /// (`tests/it/fast_path.rs`); the demo 386 against 779 steps, 0.082 mm
    /// at most at the planned dates; the Xiaowan-like arch's whole
    /// construction 569 against 1,109 steps, 48 against 84 min, its deciding
    /// apertures within 0.162 mm (`study compare`, measured before the days
    /// inside a step were weighted): for screening, not for planning.
    pub mechanics_max_step_days: u32,
    /// With `mechanics_max_step_days` above 1, a day that pours no longer
    /// ends a mechanical step (default false: every pour day does): a lift
    /// poured inside a step is part of it from the step's start, born on its
    /// own day (its modulus, creep and weight from then on) and strained
    /// from the temperatures at its pour. An approximation for speed on
    /// schedules that pour on most days, whose cost is the longer steps'
    /// own over young concrete: measured with 3-day steps, the small dam 130
    /// against 151 steps, 0.132 mm more at most at the grouting dates
    /// (`tests/it/fast_path.rs`); the demo 311 against 386 steps but 0.694
    /// against 0.082 mm from the exact path at the planned dates; the
    /// Xiaowan-like arch's first 300 days 105 against 140 steps.
    pub mechanics_merge_pours: bool,
    /// With `mechanics_max_step_days` above 1, a day that grouts zones no
    /// longer ends a mechanical step (default false: every grouting day
    /// does): a zone grouted inside a step is grouted at the step's start,
    /// its layer taking the joint's state there and bonding the joint for
    /// the whole step, so its aperture on its grouting date is the one of
    /// the step's start, up to `mechanics_max_step_days − 1` days earlier.
    /// The days whose rows are read (snapshots, the planner's observed
    /// days) still end steps. An approximation for speed on schedules that
    /// grout on most days once the dam is high (the Xiaowan-like arch
    /// grouts on 360 of its days): measured with 3-day steps and the pours
    /// merged, the small dam 123 against 130 steps, 0.116 mm more at most
    /// at the grouting dates (`tests/it/fast_path.rs`); the Xiaowan-like
    /// arch's whole construction with the other four approximations 414
    /// against 519 steps, 26.5 against 29.4 min, its deciding apertures
    /// within 0.390 mm of the exact path's against 0.282 mm
    /// (docs/PERFORMANCE.md).
    pub mechanics_merge_groutings: bool,
    /// Last simulated date; default = 60 days after the last scheduled event.
    #[serde(deserialize_with = "dates::opt_date")]
    pub end_date: Option<NaiveDate>,
}

impl Default for TimeStepping {
    fn default() -> Self {
        TimeStepping {
            first_step_days: 0.25,
            growth: 2.0,
            max_step_days: 4.0,
            step_schedule: Vec::new(),
            theta: 1.0,
            capacity: CapacityKind::Lumped,
            mechanics_max_step_days: 1,
            mechanics_merge_pours: false,
            mechanics_merge_groutings: false,
            end_date: None,
        }
    }
}

/// One rate of `time.step_schedule`: steps of `step_days` until
/// `until_days` after the pour or stage change.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduledStep {
    /// Step length \[d\] (> 0).
    pub step_days: f64,
    /// Days after the pour this rate ends (increasing along the list).
    pub until_days: f64,
}

impl TimeStepping {
    /// The scheduled step `elapsed` days after the last pour or stage
    /// change, cut at the end of its rate; None past the schedule.
    pub fn scheduled_step(&self, elapsed: f64) -> Option<f64> {
        // 1e-9: a step that ends within round-off of a rate's end is past it.
        let rate = self
            .step_schedule
            .iter()
            .find(|r| elapsed < r.until_days - 1e-9)?;
        Some(rate.step_days.min(rate.until_days - elapsed))
    }
}

/// How the heat equations of a step are solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThermalSolverKind {
    /// Sparse Cholesky (faer): symbolic analysis once per live set, numeric
    /// factor once per step length; exact to round-off. Default.
    Cholesky,
    /// Jacobi-preconditioned conjugate gradients from the previous
    /// temperatures: no factorisation at births. C + θΔtK is dominated by the
    /// capacity for the steps of a dam, so it converges in tens of iterations;
    /// it wins on large dams with thousands of pours.
    Pcg,
}

/// How the joint contact of a mechanical step is solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSolverKind {
    /// Open/stick/slip state iteration on the whole system, warm started
    /// from the last step: closed points are exact constraints on the
    /// relative displacement of their node pair. Default.
    ActiveSet,
    /// The condensed joint problem (Delassus operator W from multi-column
    /// solves) as a cone program for clarabel. Dense in the contact points:
    /// for checks and small scenes.
    Qp,
}

/// Linear-solver settings (`[solver]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// `fast`, `standard` or `reference`: the `[time]` keys of that
    /// accuracy level ([`preset`]); keys written in `[time]` override it.
    /// Default none (each key its own default, the same as `standard`).
    pub preset: Option<Preset>,
    /// `cholesky` (default) or `pcg`.
    pub thermal: ThermalSolverKind,
    /// PCG stops at ‖r‖ ≤ tol·‖b‖; default 1e-12, at most 1e-6.
    pub pcg_tolerance: f64,
    /// PCG gives up (an error naming the day) after this many iterations; default 2000.
    pub pcg_max_iterations: u32,
    /// Joint contact: `active_set` (default) or `qp`.
    pub contact: ContactSolverKind,
    /// Contact passes per step before the step fails (an error naming the
    /// date); default 60.
    pub contact_max_iterations: u32,
    /// Active set: solve a pass whose closed joint points or intact grout
    /// layers differ from the factored ones by the capacitance correction
    /// on the step's factor (exact, no new factorisation) while that is
    /// cheaper than refactorising; default true. `false` refactorises at every change
    /// (the path it is compared with in `groutready study perf`).
    pub contact_capacitance: bool,
    /// Fill-reducing ordering of the mechanical factorisation: `metis`
    /// (nested dissection of the complete dam restricted to each live set,
    /// default), `metis_live_set` (nested dissection of each live set) or
    /// `amd`.
    pub ordering: OrderingKind,
    /// The solid element of the mechanics: `hex8` (trilinear, default) or
    /// `hex8_incompatible` (with Wilson–Taylor bending modes, condensed per
    /// element: the same dofs, no shear locking). Not written when it is
    /// the default, so the restart fingerprints of scenes from before the
    /// key stay what they were.
    #[serde(skip_serializing_if = "SolidElement::is_default")]
    pub element: SolidElement,
    /// Factorise the next mechanical step's stiffness on the second core
    /// while a step's contact passes run (active set with
    /// `contact_capacitance`; the next step starts from that factor through
    /// the correction): the same answer to round-off, default true. Not
    /// written when true (restart fingerprints of older scenes).
    #[serde(skip_serializing_if = "is_true")]
    pub factor_ahead: bool,
    /// Mechanics: keep every N-th node level of the rock beside the dam
    /// (above the deepest foundation, beyond the first ring of rock
    /// elements round the concrete) and tie the nodes between to them,
    /// linearly along their vertical grid line
    /// ([`crate::mechanics::rock_ties`]). 1 (default): the mesh's rock. An
    /// approximation: its error and time are in `groutready study
    /// accuracy`. Not written when 1 (restart fingerprints).
    #[serde(skip_serializing_if = "is_one")]
    pub rock_coarsening: u32,
    /// Mechanics: condense once per run the rock whose columns of the
    /// factor no step changes (the rock-only subtrees of the construction
    /// ordering's elimination tree; [`crate::mechanics::rock_condensation`]):
    /// the same answer to round-off, default true. Only with `ordering =
    /// "metis"` and `rock_coarsening = 1`. Not written when true (restart
    /// fingerprints of older scenes).
    #[serde(skip_serializing_if = "is_true")]
    pub condense_rock: bool,
    /// Mechanics: once every lift round a segment of a vertical grid line
    /// of the concrete (off the joints) between two grouting-zone
    /// boundaries is this many days old, tie its nodes to the segment's
    /// ends, linearly (Zhu's layer merging, kept element by element;
    /// [`crate::mechanics::layer_merging`]). 0 (default): off. An
    /// approximation: its error and time are in `groutready study
    /// accuracy`. Not written when 0 (restart fingerprints).
    #[serde(skip_serializing_if = "is_zero")]
    pub layer_merging_age_days: u32,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

fn is_one(v: &u32) -> bool {
    *v == 1
}

fn is_true(v: &bool) -> bool {
    *v
}

/// The solid element of the mechanics (`solver.element`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolidElement {
    /// Trilinear hex8, 2×2×2 Gauss points ([`crate::fem::elasticity`]).
    /// Default. Too stiff in bending: it needs several elements along a
    /// block to resolve a block that curls as its top cools.
    #[default]
    Hex8,
    /// Hex8 with nine incompatible modes condensed element by element
    /// ([`crate::fem::hex8_modes`]): bending of rectangular elements exact,
    /// the patch test passed on any shape; the same global dofs, a 9×9
    /// condensation per element once, and the modes' amplitudes recovered
    /// at each step.
    Hex8Incompatible,
}

impl SolidElement {
    /// The scene key's value.
    pub fn name(self) -> &'static str {
        match self {
            SolidElement::Hex8 => "hex8",
            SolidElement::Hex8Incompatible => "hex8_incompatible",
        }
    }

    /// The other element (the accuracy study's element knob).
    pub fn other(self) -> SolidElement {
        match self {
            SolidElement::Hex8 => SolidElement::Hex8Incompatible,
            SolidElement::Hex8Incompatible => SolidElement::Hex8,
        }
    }
}

impl SolidElement {
    fn is_default(&self) -> bool {
        *self == SolidElement::default()
    }
}

/// Fill-reducing ordering of a sparse factorisation (`solver.ordering`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OrderingKind {
    /// METIS's multilevel nested dissection of the complete dam, computed
    /// once and restricted to each live set (one METIS call per run instead
    /// of one per pour). On the mechanical systems nested dissection fills
    /// less than AMD at every size measured: the complete demo arch with
    /// its joint pairs (25,458 dofs) 8.0M entries of L and 2.8 Gflop per
    /// factorisation against 10.2M and 5.0 Gflop (`groutready study perf`);
    /// the complete Xiaowan-like arch without pairs (410,904 dofs) 169M
    /// against 248M, 6.1 s against 8.8 s on 2 cores
    /// (`examples/factor_orderings.rs`). The restriction's fill against a
    /// METIS call per live set is in `docs/PERFORMANCE.md`.
    Metis,
    /// METIS's nested dissection of each live set's own pattern (one call
    /// per pour: 0.18 s each on the demo).
    MetisLiveSet,
    /// faer's approximate minimum degree.
    Amd,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            preset: None,
            thermal: ThermalSolverKind::Cholesky,
            pcg_tolerance: 1e-12,
            pcg_max_iterations: 2000,
            contact: ContactSolverKind::ActiveSet,
            contact_max_iterations: 60,
            contact_capacitance: true,
            ordering: OrderingKind::Metis,
            element: SolidElement::Hex8,
            factor_ahead: true,
            rock_coarsening: 1,
            condense_rock: true,
            layer_merging_age_days: 0,
        }
    }
}

impl SolverSettings {
    /// Checks the values; the error names the key.
    pub fn validate(&self) -> Result<(), Invalid> {
        if !(self.pcg_tolerance > 0.0 && self.pcg_tolerance <= 1e-6) {
            return Err(Invalid::new(
                "solver.pcg_tolerance",
                format!(
                    "solver.pcg_tolerance must be in (0, 1e-6], got {}",
                    self.pcg_tolerance
                ),
            ));
        }
        if self.pcg_max_iterations == 0 {
            return Err(Invalid::new(
                "solver.pcg_max_iterations",
                "solver.pcg_max_iterations must be >= 1, got 0",
            ));
        }
        if self.rock_coarsening == 0 {
            return Err(Invalid::new(
                "solver.rock_coarsening",
                "solver.rock_coarsening must be >= 1 (1: the mesh's rock), got 0",
            ));
        }
        if self.contact_max_iterations == 0 {
            return Err(Invalid::new(
                "solver.contact_max_iterations",
                "solver.contact_max_iterations must be >= 1, got 0",
            ));
        }
        Ok(())
    }
}

#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSettings {
    /// Dates of VTU snapshots (not before the epoch).
    #[serde(deserialize_with = "dates::dates")]
    pub snapshots: Vec<NaiveDate>,
}

impl Effect {
    /// Is this a thermal effect (one that needs the heat solve)?
    pub fn is_thermal(self) -> bool {
        matches!(
            self,
            Effect::Hydration
                | Effect::PipeCooling
                | Effect::Ambient
                | Effect::ReservoirTemperature
        )
    }

    /// Is this a mechanical effect (one that needs the stress solve)?
    pub fn is_mechanical(self) -> bool {
        !self.is_thermal()
    }

    /// Every effect, in declaration order.
    pub const ALL: [Effect; 10] = [
        Effect::Hydration,
        Effect::PipeCooling,
        Effect::Ambient,
        Effect::ReservoirTemperature,
        Effect::ThermalStrain,
        Effect::SelfWeight,
        Effect::Creep,
        Effect::Autogenous,
        Effect::ReservoirLoad,
        Effect::Joints,
    ];

    /// The name used in scene files (`pipe_cooling`).
    pub fn name(self) -> &'static str {
        match self {
            Effect::Hydration => "hydration",
            Effect::PipeCooling => "pipe_cooling",
            Effect::Ambient => "ambient",
            Effect::ReservoirTemperature => "reservoir_temperature",
            Effect::ThermalStrain => "thermal_strain",
            Effect::SelfWeight => "self_weight",
            Effect::Creep => "creep",
            Effect::Autogenous => "autogenous",
            Effect::ReservoirLoad => "reservoir_load",
            Effect::Joints => "joints",
        }
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Scene {
    /// Read, parse and validate a scene file. Errors name the file (as given
    /// in `path`), the line and column or the dotted key.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut scene = Scene::from_toml_str(&text, &path.display().to_string())?;
        scene.read_geometry_tables(path)?;
        Ok(scene)
    }

    /// Reads the CSV tables of an `arch_table` geometry, relative to the
    /// folder of the scene file at `scene_path`, into the geometry (so a
    /// scene kept as JSON carries them), and finds a `mesh` geometry's file
    /// there ([`crate::mesh::geometry::MeshGeometry::resolve`]); nothing to
    /// do for the generators.
    pub fn read_geometry_tables(&mut self, scene_path: &Path) -> Result<(), SceneError> {
        let dir = scene_path.parent().unwrap_or_else(|| Path::new(""));
        match &mut self.geometry {
            Geometry::ArchTable(g) => {
                g.tables = Some(crate::mesh::arch_table::load_tables(g, dir)?);
            }
            Geometry::Mesh(g) => {
                g.resolve(dir).map_err(|source| SceneError::Io {
                    path: dir.join(&g.file),
                    source,
                })?;
            }
            Geometry::Blocks(_) | Geometry::Arch(_) => {}
        }
        Ok(())
    }

    /// Parse and validate scene text; `origin` names it in error messages
    /// (usually the file name, e.g. `models/demo_arch.toml`).
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let mut scene: Scene =
            toml::from_str(text).map_err(|e| error::from_toml_error(text, origin, e))?;
        if let Some(p) = scene.solver.preset {
            // The text parsed above, so it parses as a table too.
            let table: toml::Table = toml::from_str(text).unwrap_or_default();
            let time = table.get("time").and_then(|t| t.as_table());
            preset::apply(p, &mut scene.time, &|k| {
                time.is_some_and(|t| t.contains_key(k))
            });
        }
        scene
            .validate()
            .map_err(|e| e.with_origin(origin).located(text))?;
        Ok(scene)
    }

    /// Check every value and the consistency between tables. The error of a
    /// scene not read from a file carries no origin; [`Scene::load`] and
    /// [`Scene::from_toml_str`] add it.
    pub fn validate(&self) -> Result<(), SceneError> {
        validate::validate(self)
    }

    /// The schedules folder: `schedules` resolved against the folder of the
    /// scene file at `scene_path` (absolute paths are kept as they are).
    pub fn schedules_dir(&self, scene_path: &Path) -> Option<PathBuf> {
        let dir = self.schedules.as_ref()?;
        if dir.is_absolute() {
            return Some(dir.clone());
        }
        let base = scene_path.parent().unwrap_or_else(|| Path::new(""));
        Some(base.join(dir))
    }

    /// Is `effect` switched on?
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(&effect)
    }

    /// Is any thermal effect on (i.e. is there a heat problem to solve)?
    pub fn any_thermal(&self) -> bool {
        self.effects.iter().any(|e| e.is_thermal())
    }

    /// Does the scene ask for any mechanical effect (and so the stress solve)?
    pub fn any_mechanical(&self) -> bool {
        self.effects.iter().any(|e| e.is_mechanical())
    }

    /// Lift height \[m\].
    pub fn lift_height_m(&self) -> f64 {
        self.lifts.height_m
    }

    /// Grouting-zone height \[m\].
    pub fn zone_height_m(&self) -> f64 {
        self.joints.zone_height_m
    }

    /// Lifts per grouting zone (`zone_height_m / height_m`, a whole number in a
    /// validated scene).
    pub fn lifts_per_zone(&self) -> u32 {
        let n = (self.joints.zone_height_m / self.lifts.height_m).round();
        if n.is_finite() && n >= 1.0 {
            n as u32
        } else {
            1
        }
    }

    /// Thermal diffusivity of the concrete a = λ/(ρc) [m²/day].
    pub fn concrete_diffusivity_m2_per_day(&self) -> f64 {
        self.concrete.diffusivity_m2_per_day()
    }

    /// Conductivity of the concrete in J/(m·day·K) (λ·86400).
    pub fn concrete_conductivity_j_per_m_day_k(&self) -> f64 {
        self.concrete.conductivity_j_per_m_day_k()
    }

    /// Conductivity of the rock in J/(m·day·K), if there is a `[rock]` table.
    pub fn rock_conductivity_j_per_m_day_k(&self) -> Option<f64> {
        self.rock.as_ref().map(Rock::conductivity_j_per_m_day_k)
    }

    /// Thermal diffusivity of the rock [m²/day], if there is a `[rock]` table.
    pub fn rock_diffusivity_m2_per_day(&self) -> Option<f64> {
        self.rock.as_ref().map(Rock::diffusivity_m2_per_day)
    }
}

/// [`ThermalProperties`] of tables that carry the three keys as fields of
/// the same names.
macro_rules! thermal_properties_of_fields {
    ($($table:ty),+) => {$(
        impl ThermalProperties for $table {
            fn density_kg_m3(&self) -> f64 {
                self.density_kg_m3
            }
            fn specific_heat_j_kgk(&self) -> f64 {
                self.specific_heat_j_kgk
            }
            fn conductivity_w_mk(&self) -> f64 {
                self.conductivity_w_mk
            }
        }
    )+};
}

thermal_properties_of_fields!(Concrete, Rock);

impl Rock {
    /// Initial rock temperature at elevation `z` [°C], given the elevation of
    /// the deepest foundation `z_ref` (where it is `initial_temp_c`).
    pub fn initial_temp_at(&self, z: f64, z_ref: f64) -> f64 {
        self.initial_temp_c + self.gradient_c_per_m * (z_ref - z)
    }
}

impl Air {
    /// Film coefficient β in J/(m²·day·K).
    pub fn film_j_per_m2_day_k(&self) -> f64 {
        self.film_w_m2k * SECONDS_PER_DAY
    }

    /// Air temperature [°C] on a (possibly fractional) day of the year.
    pub fn temperature_c(&self, day_of_year: f64) -> f64 {
        annual(
            self.mean_c,
            self.amplitude_c,
            self.warmest_day_of_year,
            day_of_year,
        )
    }
}

impl Reservoir {
    /// Surface water temperature [°C] on a (possibly fractional) day of the year.
    pub fn surface_temperature_c(&self, day_of_year: f64) -> f64 {
        annual(
            self.surface_mean_c,
            self.surface_amplitude_c,
            self.warmest_day_of_year,
            day_of_year,
        )
    }

    /// Water temperature [°C] at `depth_m` below the surface on a day of the year:
    /// bottom + (surface(t) − bottom)·e^{−decay·depth}.
    pub fn temperature_c(&self, depth_m: f64, day_of_year: f64) -> f64 {
        let surface = self.surface_temperature_c(day_of_year);
        let depth = depth_m.max(0.0);
        self.bottom_temp_c + (surface - self.bottom_temp_c) * (-self.decay_per_m * depth).exp()
    }
}

/// mean + amplitude·cos(2π(d − d_warmest)/365).
fn annual(mean: f64, amplitude: f64, warmest_day: f64, day_of_year: f64) -> f64 {
    mean + amplitude * (2.0 * std::f64::consts::PI * (day_of_year - warmest_day) / 365.0).cos()
}

/// Dates as `"YYYY-MM-DD"` strings or bare TOML dates (`epoch = 2024-01-01`).
mod dates {
    use std::fmt;

    use chrono::NaiveDate;
    use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};

    fn parse<E: de::Error>(s: &str) -> Result<NaiveDate, E> {
        let ok_shape = s.len() == 10 && s.as_bytes()[4] == b'-' && s.as_bytes()[7] == b'-';
        match NaiveDate::parse_from_str(s, "%Y-%m-%d") {
            Ok(d) if ok_shape => Ok(d),
            _ => Err(E::custom(format!(
                "expected a date YYYY-MM-DD, found \"{s}\""
            ))),
        }
    }

    struct DateVisitor;

    impl<'de> Visitor<'de> for DateVisitor {
        type Value = NaiveDate;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a date YYYY-MM-DD")
        }

        fn visit_str<E: de::Error>(self, s: &str) -> Result<NaiveDate, E> {
            parse(s)
        }

        // toml hands a bare date/date-time over as a one-entry map.
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NaiveDate, A::Error> {
            let Some(_key) = map.next_key::<String>()? else {
                return Err(de::Error::custom(
                    "expected a date YYYY-MM-DD, found a table",
                ));
            };
            let text: String = map.next_value()?;
            parse(&text)
        }
    }

    pub(super) fn date<'de, D: Deserializer<'de>>(d: D) -> Result<NaiveDate, D::Error> {
        d.deserialize_any(DateVisitor)
    }

    pub(super) fn epoch<'de, D: Deserializer<'de>>(d: D) -> Result<crate::vocab::Epoch, D::Error> {
        date(d).map(crate::vocab::Epoch)
    }

    struct Wrapped(NaiveDate);

    impl<'de> serde::Deserialize<'de> for Wrapped {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            date(d).map(Wrapped)
        }
    }

    pub(super) fn opt_date<'de, D: Deserializer<'de>>(d: D) -> Result<Option<NaiveDate>, D::Error> {
        // A run folder's scene.json writes a date left out as null.
        <Option<Wrapped> as serde::Deserialize>::deserialize(d).map(|o| o.map(|w| w.0))
    }

    struct SeqVisitor;

    impl<'de> Visitor<'de> for SeqVisitor {
        type Value = Vec<NaiveDate>;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a list of dates YYYY-MM-DD")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<NaiveDate>, A::Error> {
            let mut out = Vec::new();
            while let Some(Wrapped(d)) = seq.next_element()? {
                out.push(d);
            }
            Ok(out)
        }
    }

    pub(super) fn dates<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<NaiveDate>, D::Error> {
        d.deserialize_seq(SeqVisitor)
    }
}
