//! Transient heat conduction in the staged dam.
//!
//! Solved (time in days, temperatures in °C):
//!
//!   ρc ∂T/∂t = ∇·(λ∇T) + ρc ∂S/∂t   in the live concrete and rock,
//!   −λ ∂T/∂n = β (T − Ta(t))        on faces exposed to air (`ambient`),
//!   T = T_w(depth, t)                on submerged upstream faces (`reservoir_temperature`),
//!   ∂T/∂n = 0                        on the far rock boundary and wherever no effect applies,
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
//! The model reads no scene: [`ThermalSettings::from_scene`] resolves what it
//! needs (materials, effects, θ, solver) once.
//!
//! Verified by `tests/it/thermal_closed_forms.rs`: adiabatic curves, Zhu's T̄
//! with a stage change, the Bi = 1 slab series solution with fitted
//! convergence rates in h and Δt, and the heat balance of a staged run.

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
