//! Adiabatic temperature rise θ(τ) of concrete, τ = age in days.
//!
//! The three forms of Zhu Bofang's practice:
//!
//! | form | θ(τ) | θ′(τ) |
//! |---|---|---|
//! | exponential | θ0 (1 − e^{−mτ}) | θ0 m e^{−mτ} |
//! | compound | θ0 (1 − e^{−aτ^b}) | θ0 a b τ^{b−1} e^{−aτ^b} |
//! | hyperbolic | θ0 τ/(n + τ) | θ0 n/(n + τ)² |
//!
//! θ is evaluated through `expm1` so that the small increments
//! θ(τ_{n+1}) − θ(τ_n) the thermal step adds keep their relative precision
//! at early age. Verified in `tests/it/material_laws.rs` against the closed
//! forms and (for θ′) against central differences of θ.

// `!(x > 0.0)` is the comparison that also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::vocab::Invalid;
use serde::{Deserialize, Serialize};

use super::positive;

/// The three adiabatic-rise forms of Zhu Bofang's practice.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum AdiabaticRise {
    /// θ0 (1 − e^{−mτ}), m in 1/day.
    Exponential { theta0: f64, m: f64 },
    /// θ0 (1 − e^{−a τ^b}).
    Compound { theta0: f64, a: f64, b: f64 },
    /// θ0 τ / (n + τ), n in days.
    Hyperbolic { theta0: f64, n: f64 },
}

/// Smallest age at which [`AdiabaticRise::rate`] is evaluated: the compound
/// form with b < 1 has an integrable but infinite rate at τ = 0.
pub const MIN_RATE_AGE: f64 = 1e-12;

impl AdiabaticRise {
    /// Final adiabatic rise θ0 \[°C\].
    pub fn theta0(&self) -> f64 {
        match *self {
            AdiabaticRise::Exponential { theta0, .. }
            | AdiabaticRise::Compound { theta0, .. }
            | AdiabaticRise::Hyperbolic { theta0, .. } => theta0,
        }
    }

    /// θ(τ) \[°C\]; 0 for τ ≤ 0 (not yet poured).
    pub fn theta(&self, age: f64) -> f64 {
        if age.is_nan() {
            return f64::NAN;
        }
        if age <= 0.0 {
            return 0.0;
        }
        match *self {
            AdiabaticRise::Exponential { theta0, m } => -theta0 * (-m * age).exp_m1(),
            AdiabaticRise::Compound { theta0, a, b } => -theta0 * (-a * age.powf(b)).exp_m1(),
            AdiabaticRise::Hyperbolic { theta0, n } => theta0 * age / (n + age),
        }
    }

    /// dθ/dτ \[°C/day\]. 0 for τ < 0; for τ ≥ 0 the right derivative at
    /// max(τ, [`MIN_RATE_AGE`]), which keeps the compound form with b < 1
    /// finite at τ = 0.
    pub fn rate(&self, age: f64) -> f64 {
        if age.is_nan() {
            return f64::NAN;
        }
        if age < 0.0 {
            return 0.0;
        }
        let tau = age.max(MIN_RATE_AGE);
        match *self {
            AdiabaticRise::Exponential { theta0, m } => theta0 * m * (-m * tau).exp(),
            AdiabaticRise::Compound { theta0, a, b } => {
                let tb = tau.powf(b);
                theta0 * a * b * tb / tau * (-a * tb).exp()
            }
            AdiabaticRise::Hyperbolic { theta0, n } => {
                let d = n + tau;
                theta0 * n / (d * d)
            }
        }
    }

    /// Checks the parameters; the error names the offending field, e.g.
    /// `theta0 must be > 0, got -3`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let theta0 = self.theta0();
        positive("theta0", theta0)?;
        if !(theta0 < 100.0) {
            return Err(Invalid::new(
                "theta0",
                format!("theta0 must be < 100, got {theta0}"),
            ));
        }
        match *self {
            AdiabaticRise::Exponential { m, .. } => positive("m", m),
            AdiabaticRise::Compound { a, b, .. } => {
                positive("a", a)?;
                if !(b > 0.0 && b <= 3.0) {
                    return Err(Invalid::new("b", format!("b must be in (0, 3], got {b}")));
                }
                Ok(())
            }
            AdiabaticRise::Hyperbolic { n, .. } => positive("n", n),
        }
    }

    /// Cheap allocation-free form of [`validate`](Self::validate) for hot paths.
    pub(crate) fn is_valid(&self) -> bool {
        let ok = |x: f64| x > 0.0 && x.is_finite();
        let theta0 = self.theta0();
        ok(theta0)
            && theta0 < 100.0
            && match *self {
                AdiabaticRise::Exponential { m, .. } => ok(m),
                AdiabaticRise::Compound { a, b, .. } => ok(a) && b > 0.0 && b <= 3.0,
                AdiabaticRise::Hyperbolic { n, .. } => ok(n),
            }
    }
}
