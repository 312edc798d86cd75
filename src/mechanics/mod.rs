//! Staged, incremental small-strain mechanics of the dam and its foundation.
//!
//! Solved per step n (t_{n−1} → t_n) on the live elements:
//!
//!   Σ_e ∫ Bᵀ Δσ dV = Δf_ext      (self-weight at birth, water pressure increments)
//!   Δσ = Ē_n Q(ν) (B Δu − η_n − α ΔT − ΔG),   Ē_n = E(τ̄)/(1 + E(τ̄) q_n)
//!
//! with E(τ) the ageing modulus at the element's mid-step age τ̄, q_n and η_n
//! Zhu's creep recursion (`material::creep`, state ω_s per Gauss point, no
//! history), α ΔT the thermal strain increment from the thermal field, ΔG the
//! autogenous increment. Every element is born stress-free at its pour date:
//! only displacement increments after birth strain it, so its stress-free
//! temperature is its own temperature at birth. The rock foundation is
//! elastic; its far faces are fixed, on rollers or free per side
//! (`[boundary]`, [`supports`]).
//!
//! Because ν is constant, each element's stiffness is Ē_e·K̂_e with K̂_e the
//! unit-modulus stiffness computed once; the global matrix changes every
//! step (ageing) and is refactorised numerically on the symbolic analysis of
//! the live set.
//!
//! With the `joints` effect the unknowns of each live joint point are the
//! relative displacement of its node pair ([`live`]), and the step is solved
//! with the joint states of [`contact_step`]: contact (open / stick / slip)
//! before the zone is grouted, a bonded grout layer after, a contact again
//! once the layer cracks.
//!
//! The model reads no scene: [`MechanicsSettings::from_scene`] resolves what
//! it needs (laws, constants, effects, joint parameters) once.
//!
//! Verified by `tests/it/mechanics_staged.rs` (stress-free birth, restrained
//! thermal stress in the staged driver, relaxation, equilibrium of the
//! accumulated stresses with the accumulated loads) on top of the element
//! tests of `fem::elasticity` and the material tests of `material::creep`;
//! the joints by `tests/it/joint_two_blocks.rs` and `tests/it/joint_friction.rs`.

pub mod ahead;
pub mod contact_step;
mod error;
mod frame;
pub mod grout_stops;
pub mod joints;
pub mod layer_merging;
pub mod live;
pub mod model;
pub mod pours_ahead;
pub mod rock_condensation;
pub mod rock_ties;
pub mod settings;
pub mod supports;

pub use ahead::BirthsPlacement;
pub use error::MechError;
pub use frame::Frame;
pub use model::{
    JointReading, MechState, MechStats, MechanicsModel, StepTemperatures, Supports, ZoneMinimum,
};
pub use settings::{ConcreteMechanics, JointMechanics, MechanicsSettings, RockMechanics};
pub use supports::SupportError;
