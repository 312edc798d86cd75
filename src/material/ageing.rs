//! Ageing of concrete: elastic modulus E(τ) and autogenous deformation G(τ).
//!
//! τ is the concrete age in days (0 at the element's birth, its pour).
//!
//! | law | formula | typical |
//! |---|---|---|
//! | [`ModulusLaw`] | E(τ) = E0 (1 − e^{−a τ^b}) | a ≈ 0.40, b ≈ 0.34, E0 = final modulus \[Pa\] |
//! | [`AutogenousLaw`] | G(τ) = ε∞ (1 − e^{−c τ^d}) | ε∞ from −50e-6 (shrinkage) to +50e-6 (expansion) |
//! | [`Poisson`] | ν, constant in time | 0.167 for dam concrete |
//!
//! # Mid-step modulus and the newborn element
//!
//! A time step from age τ0 to τ1 uses the modulus at the mid-step age
//! τ½ = (τ0 + τ1)/2 ([`ModulusLaw::modulus_mid_step`], [`mid_step_age`]):
//! this is the second-order choice of Zhu Bofang's incremental method (the
//! stress increment of a step is taken to act at its middle), and it keeps a
//! newborn element stiff: a step of positive length Δτ starting at the birth
//! (τ0 = 0) uses E(Δτ/2) > 0, never E(0) = 0.
//!
//! The one step that has no positive mid-step age, a **zero-length step at
//! age 0**, is rejected with [`AgeStepError::NewbornInstant`]: concrete at
//! the instant of pouring is a fluid and cannot take an instantaneous load.
//! Zero-length steps at a positive age are allowed and use E(τ0): they are
//! how an instantaneous load (a stress jump) is applied (see
//! [`super::creep`]). Steps that run backwards, start before the birth
//! (τ0 < 0) or carry non-finite ages are errors too; no age is clamped.
//!
//! # Autogenous increments
//!
//! [`AutogenousLaw::increment`] returns G(τ1) − G(τ0) in a form that keeps
//! relative precision for short late steps, ε∞ e^{−cτ0^d}(1 − e^{−c(τ1^d −
//! τ0^d)}) with `expm1`/`ln_1p` (no cancellation in τ1^d − τ0^d either); the
//! increments of consecutive steps telescope, so their sum equals G at the
//! last age to rounding (≤ 1e-13 relative over hundreds of irregular steps),
//! for any step sequence.
//!
//! # The Poisson matrix Q
//!
//! Voigt order \[xx, yy, zz, xy, yz, zx\] with **engineering** shear strains
//! (γ_xy = 2ε_xy). The isotropic elastic law is ε = Q⁻¹σ / E with
//!
//! ```text
//!        ⎡ 1  −ν  −ν                    ⎤
//!        ⎢−ν   1  −ν                    ⎥
//! Q⁻¹ =  ⎢−ν  −ν   1                    ⎥
//!        ⎢            2(1+ν)            ⎥
//!        ⎢                  2(1+ν)      ⎥
//!        ⎣                        2(1+ν)⎦
//! ```
//!
//! and σ = E Q ε, Q = 1/((1+ν)(1−2ν)) · `[[1−ν, ν, ν], [ν, 1−ν, ν], [ν, ν, 1−ν]]`
//! on the normal block and 1/(2(1+ν)) on the shear diagonal. The creep
//! strain uses the same Q⁻¹ (a creep Poisson ratio equal to the elastic one).
//!
//! Verified in `tests/it/material_creep.rs`: E(Δτ/2) > 0 for newborn steps,
//! monotone ageing, exact telescoping of G, Q Q⁻¹ = I, and exact `validate`
//! messages.

// `!(x > 0.0)` is the comparison that also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::vocab::Invalid;
use serde::{Deserialize, Serialize};

use super::positive;

/// Why a time step's ages cannot give a mid-step age (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum AgeStepError {
    /// An age is NaN or infinite.
    #[error("step ages must be finite, got {age0} to {age1}")]
    NotFinite { age0: f64, age1: f64 },
    /// The step starts before the element exists (τ0 < 0).
    #[error("step starts before the concrete is poured: age {age0} < 0")]
    BeforeBirth { age0: f64 },
    /// τ1 < τ0.
    #[error("step runs backwards: age {age0} to {age1}")]
    Backwards { age0: f64, age1: f64 },
    /// A zero-length step at age 0: the modulus there is E(0) = 0.
    #[error(
        "zero-length step at age 0: newborn concrete has no stiffness; \
         give an element's first step a positive length"
    )]
    NewbornInstant,
}

/// Mid-step age τ½ = (τ0 + τ1)/2 of a step from age τ0 to τ1 \[days\].
///
/// Guaranteed > 0 and finite on success: steps of positive length from
/// τ0 ≥ 0, and zero-length steps at τ0 > 0 (instantaneous loads). Errors are
/// listed on [`AgeStepError`].
pub fn mid_step_age(age0: f64, age1: f64) -> Result<f64, AgeStepError> {
    if !age0.is_finite() || !age1.is_finite() {
        return Err(AgeStepError::NotFinite { age0, age1 });
    }
    if age0 < 0.0 {
        return Err(AgeStepError::BeforeBirth { age0 });
    }
    if age1 < age0 {
        return Err(AgeStepError::Backwards { age0, age1 });
    }
    let mid = 0.5 * (age0 + age1);
    if mid > 0.0 {
        Ok(mid)
    } else {
        Err(AgeStepError::NewbornInstant)
    }
}

/// Something that gives the elastic modulus \[Pa\] at an age \[days\]: the
/// ageing [`ModulusLaw`], or a plain `f64` for a non-ageing (constant)
/// modulus. Used by [`super::creep::coefficients`].
pub trait ModulusOfAge {
    /// E(τ) \[Pa\].
    fn modulus_at(&self, age: f64) -> f64;
}

impl ModulusOfAge for f64 {
    /// A constant modulus: E(τ) ≡ self.
    fn modulus_at(&self, _age: f64) -> f64 {
        *self
    }
}

/// Zhu Bofang's compound-exponential modulus E(τ) = E0 (1 − e^{−a τ^b}).
///
/// Scene input: `{ e0_pa = 3.5e10, a = 0.40, b = 0.34 }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModulusLaw {
    /// Final modulus E0 \[Pa\] (the limit for τ → ∞).
    pub e0_pa: f64,
    /// a \[day^−b\], typically 0.40.
    pub a: f64,
    /// b \[−\], typically 0.34.
    pub b: f64,
}

impl ModulusLaw {
    /// E(τ) \[Pa\]; 0 for τ ≤ 0 (not yet poured), strictly increasing for
    /// τ > 0 and below E0. Evaluated with `expm1`, so small ages keep their
    /// relative precision.
    pub fn modulus(&self, age: f64) -> f64 {
        if age.is_nan() {
            return f64::NAN;
        }
        if age <= 0.0 {
            return 0.0;
        }
        -self.e0_pa * (-self.a * age.powf(self.b)).exp_m1()
    }

    /// E(τ½) \[Pa\] at the mid-step age of a step from τ0 to τ1 (see
    /// [`mid_step_age`]). For a valid law the result is > 0 whenever it is
    /// `Ok`: a newborn step (τ0 = 0, τ1 > 0) gives E(τ1/2) > 0; a
    /// zero-length step at age 0 is an error.
    pub fn modulus_mid_step(&self, age0: f64, age1: f64) -> Result<f64, AgeStepError> {
        Ok(self.modulus(mid_step_age(age0, age1)?))
    }

    /// Final modulus E0 \[Pa\].
    pub fn final_modulus(&self) -> f64 {
        self.e0_pa
    }

    /// Checks the parameters; the error names the offending field, e.g.
    /// `e0_pa must be between 1e8 and 1e12 Pa, got 35` (a modulus typed in
    /// GPa).
    pub fn validate(&self) -> Result<(), Invalid> {
        let e0 = self.e0_pa;
        if !(1e8..=1e12).contains(&e0) {
            return Err(Invalid::new(
                "e0_pa",
                format!("e0_pa must be between 1e8 and 1e12 Pa, got {e0}"),
            ));
        }
        positive("a", self.a)?;
        exponent("b", self.b)
    }
}

impl ModulusOfAge for ModulusLaw {
    fn modulus_at(&self, age: f64) -> f64 {
        self.modulus(age)
    }
}

/// Autogenous deformation G(τ) = ε∞ (1 − e^{−c τ^d}); ε∞ < 0 is shrinkage.
///
/// Scene input: `{ eps_inf = -30e-6, c = 0.2, d = 0.6 }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutogenousLaw {
    /// Final autogenous strain ε∞ \[−\], negative for shrinkage.
    pub eps_inf: f64,
    /// c \[day^−d\].
    pub c: f64,
    /// d \[−\].
    pub d: f64,
}

impl AutogenousLaw {
    /// G(τ) \[−\]; 0 for τ ≤ 0.
    pub fn strain(&self, age: f64) -> f64 {
        if age.is_nan() {
            return f64::NAN;
        }
        if age <= 0.0 {
            return 0.0;
        }
        -self.eps_inf * (-self.c * age.powf(self.d)).exp_m1()
    }

    /// G(τ1) − G(τ0), the free strain of a step (volumetric: the same in
    /// xx, yy and zz, no shear). Ages ≤ 0 count as 0. Computed as
    /// ε∞ e^{−cτ0^d} (1 − e^{−c(τ1^d − τ0^d)}) with τ1^d − τ0^d =
    /// τ0^d (e^{d ln(1 + Δτ/τ0)} − 1) through `expm1`/`ln_1p`, which keeps
    /// full relative precision for short steps at late ages (a 1e-9 d step at
    /// 300 d is exact to ~1e-15, where G(τ1) − G(τ0) would keep 4 digits).
    /// `increment(a, a) == 0` and `increment(b, a) == −increment(a, b)`
    /// exactly; consecutive increments telescope to G to rounding.
    pub fn increment(&self, age0: f64, age1: f64) -> f64 {
        if age0.is_nan() || age1.is_nan() {
            return f64::NAN;
        }
        if age1 < age0 {
            return -self.increment(age1, age0);
        }
        let (a0, a1) = (age0.max(0.0), age1.max(0.0));
        let x0 = self.c * a0.powf(self.d);
        // c(τ1^d − τ0^d) without cancellation: τ0^d (e^{d ln(1 + Δ/τ0)} − 1).
        let dx = if a0 > 0.0 {
            x0 * (self.d * ((a1 - a0) / a0).ln_1p()).exp_m1()
        } else {
            self.c * a1.powf(self.d)
        };
        -self.eps_inf * (-x0).exp() * (-dx).exp_m1()
    }

    /// Final autogenous strain ε∞.
    pub fn final_strain(&self) -> f64 {
        self.eps_inf
    }

    /// Checks the parameters; the error names the offending field, e.g.
    /// `eps_inf must be a strain between -1e-3 and 1e-3, got 50` (a value
    /// typed in microstrain).
    pub fn validate(&self) -> Result<(), Invalid> {
        let e = self.eps_inf;
        if !(-1e-3..=1e-3).contains(&e) {
            return Err(Invalid::new(
                "eps_inf",
                format!("eps_inf must be a strain between -1e-3 and 1e-3, got {e}"),
            ));
        }
        positive("c", self.c)?;
        exponent("d", self.d)
    }
}

/// Poisson's ratio ν of concrete, constant in time, and its matrices Q⁻¹, Q
/// (see the module docs). Serialised as the bare number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Poisson(pub f64);

impl Poisson {
    /// ν.
    pub fn nu(self) -> f64 {
        self.0
    }

    /// `Err("poisson must be in [0, 0.5), got 0.5")` outside [0, 0.5).
    pub fn validate(&self) -> Result<(), Invalid> {
        let nu = self.0;
        if !(0.0..0.5).contains(&nu) {
            return Err(Invalid::new(
                "poisson",
                format!("poisson must be in [0, 0.5), got {nu}"),
            ));
        }
        Ok(())
    }

    /// Q⁻¹ (dimensionless): strain = Q⁻¹ σ / E, engineering shear.
    pub fn q_inv_matrix(self) -> [[f64; 6]; 6] {
        let nu = self.0;
        let s = 2.0 * (1.0 + nu);
        [
            [1.0, -nu, -nu, 0.0, 0.0, 0.0],
            [-nu, 1.0, -nu, 0.0, 0.0, 0.0],
            [-nu, -nu, 1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, s, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, s, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, s],
        ]
    }

    /// Q = (Q⁻¹)⁻¹ (dimensionless): σ = E Q ε. The element stiffness of a
    /// creep step uses the effective modulus Ē times this matrix.
    pub fn q_matrix(self) -> [[f64; 6]; 6] {
        let nu = self.0;
        let k = 1.0 / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let (d, o) = (k * (1.0 - nu), k * nu);
        let g = 0.5 / (1.0 + nu);
        [
            [d, o, o, 0.0, 0.0, 0.0],
            [o, d, o, 0.0, 0.0, 0.0],
            [o, o, d, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, g, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, g, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, g],
        ]
    }

    /// Q⁻¹ σ without forming the matrix.
    pub fn q_inv_apply(self, s: &[f64; 6]) -> [f64; 6] {
        let nu = self.0;
        let g = 2.0 * (1.0 + nu);
        [
            s[0] - nu * (s[1] + s[2]),
            s[1] - nu * (s[0] + s[2]),
            s[2] - nu * (s[0] + s[1]),
            g * s[3],
            g * s[4],
            g * s[5],
        ]
    }

    /// Q ε without forming the matrix.
    pub fn q_apply(self, e: &[f64; 6]) -> [f64; 6] {
        let nu = self.0;
        let k = 1.0 / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let tr = e[0] + e[1] + e[2];
        let g = 0.5 / (1.0 + nu);
        // k[(1−ν)e_i + ν(e_j + e_k)] = k[(1−2ν)e_i + ν tr]
        let n = |x: f64| k * ((1.0 - 2.0 * nu) * x + nu * tr);
        [n(e[0]), n(e[1]), n(e[2]), g * e[3], g * e[4], g * e[5]]
    }
}

/// `Err("{field} must be in (0, 3], got {v}")` for an age exponent.
fn exponent(field: &str, v: f64) -> Result<(), Invalid> {
    if !(v > 0.0 && v <= 3.0) {
        return Err(Invalid::new(
            field,
            format!("{field} must be in (0, 3], got {v}"),
        ));
    }
    Ok(())
}
