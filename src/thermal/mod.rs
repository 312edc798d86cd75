//! Transient heat conduction in the staged dam.
//!
//! Solved (time in days, temperatures in °C):
//!
//!   ρc ∂T/∂t = ∇·(λ∇T) + ρc ∂S/∂t   in the live concrete and rock,
//!   −λ ∂T/∂n = β (T − Ta(t))        on faces exposed to air (`ambient`),
//!   T = T_w(depth, t)                on submerged upstream faces (`reservoir_temperature`),
//!   T = T_far(side)                  on far faces of a side given a temperature (`[boundary]`),
//!   ∂T/∂n = 0                        on the other far faces and wherever no effect applies,
//!
//! where S is the adiabatic rise θ(τ) (`hydration`) or, while a cooling stage
//! runs, Zhu's equivalent pipe-cooling temperature (see [`cooling`]). Hex8
//! elements, θ-method in time (θ = 1 backward Euler by default), lumped or
//! consistent capacity. The source is added per step as its exact increment
//! S(t_{n+1}) − S(t_n), so an insulated block follows the adiabatic curve and
//! Zhu's T̄(t) to round-off whatever the step.
//!
//! Elements are born at their lift's pour date with the placement
//! temperature; dofs already live keep theirs. The linear system is that of
//! the live elements only ([`live`]).
//!
//! Fixed temperatures — the reservoir's on submerged nodes and a far side's
//! (`[boundary.<side>] temperature_c`, sides by [`crate::mesh::far`]) — are
//! Dirichlet rows eliminated exactly: the row and column become the
//! identity, the known values move to the right-hand side, and the
//! reactions of those rows are the heat through them (`ledger.water`,
//! `ledger.far`). No penalty, so no parameter changes the answer. A far
//! node takes its side's value from the first step after its element is
//! born (the rock's initial field holds only at day 0).
//!
//! **Placement temperature on shared nodes.** A new lift's bottom nodes
//! (and the nodes of its faces against an older neighbour block or the
//! rock) are shared with concrete or rock already live: they keep the older
//! material's temperature, and only the lift's own new nodes start at the
//! placement temperature. The heat the lift brings in is therefore
//! Σ c_i T_i over its elements with those shared values, which the ledger
//! counts as `births`; the interface starts at the old side's temperature
//! (as the fresh concrete would take it within hours). Measured effect of
//! the alternative (shared nodes reset to the placement temperature) on
//! `models/small_dam_joints.toml`: see `tests/it/far_boundary.rs`
//! (`placement_on_shared_nodes_effect`) and the README.
//!
//! The model reads no scene: [`ThermalSettings::from_scene`] resolves what it
//! needs (materials, effects, θ, solver) once.
//!
//! Verified by `tests/it/thermal_closed_forms.rs`: adiabatic curves, Zhu's T̄
//! with a stage change, the Bi = 1 slab series solution with fitted
//! convergence rates in h and Δt, and the heat balance of a staged run; the
//! far sides' fixed temperatures by `tests/it/far_boundary.rs` (a rock
//! column with a fixed base against the series solution, a linear steady
//! profile between two fixed sides, the balance with `ledger.far`).

pub mod boundary;
pub mod cooling;
pub mod elements;
pub mod ledger;
pub mod live;
pub mod model;
pub mod settings;

pub use ledger::HeatLedger;
pub use model::{
    ThermalCheckpoint, ThermalError, ThermalModel, ThermalState, ThermalStats, UNUSED_TARGET_DAYS,
    WARM_WATER_MARGIN_C,
};
pub use settings::{RockThermal, ThermalMaterial, ThermalSettings};
