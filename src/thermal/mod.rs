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
//! (as the fresh concrete would take it within hours). The alternative,
//! `concrete.placement_on_shared_nodes = "placement"`, resets them to the
//! placement temperature (the ledger counts the change of stored heat as
//! births). On a mesh of one element layer per lift that reset gives the
//! older lift's top half-layer of capacity the new temperature, heat no
//! concrete lost: measured on `models/small_dam_joints.toml` (`groutready
//! run` with each choice, 2026-11-24), the zone-point temperatures differ
//! by up to 13.7 K the day after a pour, 0.77 K on average over the run,
//! 0.45 K on average (0.88 K at most) at each zone's last row; apertures by
//! 0.58 mm on average, 2.1 mm at most, and 844 of 3,628 aperture rows
//! change state. Hence `keep` is the default; the balance with either
//! choice is checked by `tests/it/thermal_closed_forms.rs`
//! (`staged_run_with_a_fixed_far_base_and_reset_shared_nodes_balances_heat`).
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
    ThermalCheckpoint, ThermalError, ThermalModel, ThermalRewind, ThermalState, ThermalStats,
    UNUSED_TARGET_DAYS, WARM_WATER_MARGIN_C,
};
pub use settings::{RockThermal, ThermalMaterial, ThermalSettings};
