//! Concrete ageing laws and Zhu Bofang's pipe-cooling functions.
//!
//! Everything here is a pure function of concrete age or stage time; the
//! thermal module turns these into per-step source increments.
//!
//! * [`AdiabaticRise`]: θ(τ), θ′(τ) of the exponential, compound and
//!   hyperbolic forms, with field-naming validation.
//! * [`PipeLayout`], [`ZhuPipe`]: Zhu's equivalent cooling cylinder,
//!   φ(t) = exp(−p t^s), corrected for pipe radius and wall material.
//! * [`hydration_under_cooling`]: H(t) = ∫₀ᵗ φ(t − u) θ′(τ_k + u) du, the
//!   hydration heat kept while pipes run.
//!
//! Equations, the pipe-material correction and how each piece is verified
//! are in the submodule docs; the checks live in `tests/it/material_laws.rs`.

pub mod adiabatic;
pub mod ageing;
pub mod creep;
pub mod pipe_cooling;

pub use adiabatic::AdiabaticRise;
pub use ageing::{mid_step_age, AgeStepError, AutogenousLaw, ModulusLaw, ModulusOfAge, Poisson};
pub use creep::{
    coefficients, commit, commit_scalar, eta, eta_scalar, CreepLaw, CreepState, CreepTerm,
    ScalarCreepState, StepCoefficients,
};
pub use pipe_cooling::{hydration_under_cooling, PipeLayout, ZhuPipe};
