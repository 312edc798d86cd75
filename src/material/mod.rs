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

/// `Err("{field} must be > 0, got {v}")` unless v is a finite positive number
/// (`must be finite` for +∞): the field check of every law's `validate`.
// `!(v > 0.0)` is the comparison that also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub(crate) fn positive(field: &str, v: f64) -> Result<(), Invalid> {
    if !(v > 0.0) {
        return Err(Invalid::new(field, format!("{field} must be > 0, got {v}")));
    }
    if !v.is_finite() {
        return Err(Invalid::new(
            field,
            format!("{field} must be finite, got {v}"),
        ));
    }
    Ok(())
}
use crate::vocab::Invalid;
