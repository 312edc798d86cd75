//! Adiabatic temperature rise θ(τ) of concrete, τ = age in days.

use serde::{Deserialize, Serialize};

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
