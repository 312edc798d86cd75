//! Creep of concrete: Zhu Bofang's compliance and its exponential recursion.
//!
//! # Law
//!
//! The strain at age t under a unit stress applied at age τ is
//! J(t, τ) = 1/E(τ) + C(t, τ) with the creep part
//!
//! ```text
//! C(t, τ) = Σ_s ψ_s(τ) (1 − e^{−r_s (t − τ)}),   ψ_s(τ) = f_s + g_s τ^{−p_s}
//! ```
//!
//! (f_s, g_s in 1/Pa, r_s in 1/day, p_s dimensionless; [`CreepLaw`],
//! [`CreepTerm`]). E(τ) is an [`ModulusOfAge`], usually
//! [`super::ageing::ModulusLaw`]. In 3-D both parts share the Poisson matrix:
//! ε = Q⁻¹σ/E(τ) + Q⁻¹σ C(t, τ) (see [`super::ageing`] for Q, Voigt
//! \[xx, yy, zz, xy, yz, zx\], engineering shear).
//!
//! [`CreepLaw::zhu_typical`] gives Zhu's commonly quoted mass-concrete law
//! (two terms; see its docs for the numbers and the source).
//!
//! # Incremental algorithm (Zhu's exponential recursion)
//!
//! Step n runs from t_{n−1} to t_n (Δt_n) and the element's age from τ_{n−1}
//! to τ_n, mid-step age τ̄_n = (τ_{n−1} + τ_n)/2. The stress is taken to
//! change by Δσ_n at the middle of the step (midpoint rule on the hereditary
//! integral: second order in Δt). Then, exactly for that stress history,
//!
//! ```text
//! Δε^c_n = η_n + q_n Q⁻¹Δσ_n
//! q_n    = C(t_n, τ̄_n) = Σ_s ψ_s(τ̄_n) (1 − e^{−r_s Δt_n/2})
//! η_n    = Σ_s (1 − e^{−r_s Δt_n}) ω_{s,n}
//! ω_{s,n+1} = ω_{s,n} e^{−r_s Δt_n} + Q⁻¹Δσ_n ψ_s(τ̄_n) e^{−r_s Δt_n/2},  ω_{s,1} = 0
//! ```
//!
//! ω_{s,n} = Σ_{i<n} Q⁻¹Δσ_i ψ_s(τ̄_i) e^{−r_s (t_{n−1} − t̄_i)} is the part of
//! term s's creep potential not yet released at t_{n−1}: the whole history
//! in one strain vector per term, with no stored history. η_n is the creep
//! strain the step gets at constant stress (the "pseudo load").
//! With the elastic strain Δσ_n Q⁻¹/E_n, E_n = E(τ̄_n), the step's stress is
//!
//! ```text
//! Δσ_n = Ē_n Q (Δε_n − η_n − Δε^T_n − Δε^0_n),   Ē_n = E_n / (1 + E_n q_n)
//! ```
//!
//! (Δε^T thermal, Δε^0 autogenous). A finite-element driver does, per step:
//!
//! 1. per element (age is per element): `c = coefficients(&modulus, &law,
//!    age0, age1)?` ([`StepCoefficients`]);
//! 2. per Gauss point: `eta(&state, &c)`; assemble the stiffness with
//!    `c.e_eff · Q` and the pseudo-load ∫Bᵀ Ē Q (η + Δε^T + Δε^0) dV;
//! 3. solve for the displacement increment;
//! 4. per Gauss point: `dσ = c.stress_increment(nu, &(Δε − Δε^T − Δε^0), &η)`,
//!    then `commit(&mut state, &c, nu, &dσ)`, which advances ω to the next
//!    step (and returns the step's creep strain).
//!
//! [`CreepState`] (one per Gauss point, plain data for checkpoints) holds
//! only the ω_s. [`ScalarCreepState`], [`eta_scalar`], [`commit_scalar`]
//! are the 1-D version (uniaxial stress, Q⁻¹ = 1).
//!
//! # Instantaneous loads (stress jumps)
//!
//! As Zhu does, a load that appears at an instant t0 is applied in a step of
//! length Δt → 0: a **zero-length step** (age0 = age1 = τ0 > 0). Its
//! coefficients are q = 0, η = 0, Ē = E(τ0), so the jump is elastic, and its
//! commit adds Q⁻¹Δσ ψ_s(τ0) to ω_s: the creep of the jump is then released
//! exactly, with loading age τ0, by the following steps. Applying the jump
//! in a step of finite length instead would date it to the step's middle and
//! cost one order of accuracy. A zero-length step at age 0 is rejected (see
//! [`super::ageing::mid_step_age`]).
//!
//! # Verification (`tests/it/material_creep.rs`)
//!
//! * Relaxation of a non-ageing material (DESIGN §7):
//!   σ/ε0 = E/(1+φ)\[1 + φ e^{−(1+φ) r t}\]; the error at t = 1 d and 5 d falls
//!   as Δt² (least-squares log–log slope) for Δt from 0.2 d down to 0.00625 d.
//! * Constant stress with Zhu's ageing law: ε = σ/E(τ0) + σ C(t, τ0) to
//!   rounding (the recursion is exact for jumps at step boundaries), and a
//!   smoothly varying stress against a converged quadrature of the
//!   superposition integral, error ∝ Δt².
//! * Ageing relaxation converges as Δt² (self-convergence).
//! * 3-D: uniaxial stress gives lateral creep −ν × axial, the 3-D recursion
//!   equals the scalar one, pure shear creeps with 2(1+ν).

// `!(x > 0.0)` is the comparison that also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::vocab::Invalid;
use serde::{Deserialize, Serialize};

use super::ageing::{mid_step_age, AgeStepError, ModulusOfAge, Poisson};
use super::positive;

/// One term of the creep compliance: (f + g τ^{−p})(1 − e^{−r (t − τ)}).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CreepTerm {
    /// f \[1/Pa\], the non-ageing part of the final creep of this term.
    pub f: f64,
    /// g \[1/Pa · day^p\], the ageing part.
    pub g: f64,
    /// p \[−\], the ageing exponent.
    pub p: f64,
    /// r \[1/day\], the rate of this term.
    pub r: f64,
}

impl CreepTerm {
    /// ψ(τ) = f + g τ^{−p} \[1/Pa\], the final creep of a unit stress applied
    /// at age τ. Infinite at τ = 0 when g > 0 and p > 0.
    pub fn psi(&self, load_age: f64) -> f64 {
        if self.g == 0.0 {
            self.f
        } else {
            self.f + self.g * load_age.powf(-self.p)
        }
    }
}

/// Zhu Bofang's creep compliance C(t, τ) = Σ_s (f_s + g_s τ^{−p_s})(1 − e^{−r_s(t − τ)}).
///
/// Scene input: `terms = \[{ f = 6.6e-12, g = 6.0e-11, p = 0.45, r = 0.30 }, ...\]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CreepLaw {
    /// The exponential terms, at least one.
    pub terms: Vec<CreepTerm>,
}

impl CreepLaw {
    /// Zhu Bofang's commonly quoted creep law of mass concrete, for final
    /// modulus E2 = `e_final_pa` (the E0 of the [`super::ageing::ModulusLaw`],
    /// used with a = 0.40, b = 0.34):
    ///
    /// ```text
    /// C(t, τ) = (0.23/E2)(1 + 9.20 τ^{−0.45})(1 − e^{−0.30 (t−τ)})
    ///         + (0.52/E2)(1 + 1.70 τ^{−0.45})(1 − e^{−0.0050 (t−τ)})
    /// ```
    ///
    /// i.e. terms (f, g, p, r) = (0.23/E2, 0.23·9.20/E2, 0.45, 0.30) and
    /// (0.52/E2, 0.52·1.70/E2, 0.45, 0.0050). Source: Zhu Bofang, *Thermal
    /// Stresses and Temperature Control of Mass Concrete* (Tsinghua Univ.
    /// Press / Butterworth-Heinemann, 2014), chapter on creep of concrete,
    /// as quoted by the project brief; the stored reference corpus holds no
    /// copy to cross-check the digits against.
    pub fn zhu_typical(e_final_pa: f64) -> Self {
        let e2 = e_final_pa;
        CreepLaw {
            terms: vec![
                CreepTerm {
                    f: 0.23 / e2,
                    g: 0.23 * 9.20 / e2,
                    p: 0.45,
                    r: 0.30,
                },
                CreepTerm {
                    f: 0.52 / e2,
                    g: 0.52 * 1.70 / e2,
                    p: 0.45,
                    r: 0.0050,
                },
            ],
        }
    }

    /// The non-ageing one-term law C = (φ/E)(1 − e^{−r(t−τ)}) of the
    /// relaxation check (DESIGN §7): creep coefficient φ, rate r \[1/day\].
    pub fn non_ageing(phi: f64, r: f64, e_pa: f64) -> Self {
        CreepLaw {
            terms: vec![CreepTerm {
                f: phi / e_pa,
                g: 0.0,
                p: 0.0,
                r,
            }],
        }
    }

    /// Number of exponential terms (the length of a [`CreepState`]).
    pub fn n_terms(&self) -> usize {
        self.terms.len()
    }

    /// C(t, τ) \[1/Pa\] for observation age t and loading age τ (both days of
    /// concrete age); 0 for t ≤ τ. τ must be > 0 when some g_s ≠ 0.
    pub fn compliance(&self, age_t: f64, load_age: f64) -> f64 {
        let dur = age_t - load_age;
        if !(dur > 0.0) {
            return 0.0;
        }
        self.terms
            .iter()
            .map(|t| t.psi(load_age) * -(-t.r * dur).exp_m1())
            .sum()
    }

    /// Final creep Σ_s ψ_s(τ) = C(∞, τ) \[1/Pa\] of a load applied at age τ.
    pub fn final_compliance(&self, load_age: f64) -> f64 {
        self.terms.iter().map(|t| t.psi(load_age)).sum()
    }

    /// Checks the parameters; the error names the offending field with its
    /// 0-based index, e.g. `terms\[1\].r must be > 0, got 0` or
    /// `terms\[0\].f must be in [0, 1e-6) 1/Pa, got 0.23` (a coefficient not
    /// divided by E).
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.terms.is_empty() {
            return Err(Invalid::new(
                "terms",
                "terms must hold at least one creep term",
            ));
        }
        for (i, t) in self.terms.iter().enumerate() {
            for (name, v) in [("f", t.f), ("g", t.g)] {
                if !(0.0..1e-6).contains(&v) {
                    return Err(Invalid::new(
                        format!("terms[{i}].{name}"),
                        format!("terms[{i}].{name} must be in [0, 1e-6) 1/Pa, got {v}"),
                    ));
                }
            }
            if !(0.0..=1.0).contains(&t.p) {
                return Err(Invalid::new(
                    format!("terms[{i}].p"),
                    format!("terms[{i}].p must be in [0, 1], got {}", t.p),
                ));
            }
            positive(&format!("terms[{i}].r"), t.r)?;
        }
        Ok(())
    }
}

/// Everything a step needs that depends on the element (its ages) but not
/// on the Gauss point. Built by [`coefficients`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepCoefficients {
    /// Age at the step's start τ_{n−1} \[days\].
    pub age0: f64,
    /// Age at the step's end τ_n \[days\].
    pub age1: f64,
    /// Δt = τ_n − τ_{n−1} \[days\] (≥ 0).
    pub dt: f64,
    /// Mid-step age τ̄ = (τ_{n−1} + τ_n)/2 > 0 \[days\].
    pub mid_age: f64,
    /// E(τ̄) \[Pa\], the elastic modulus of the step.
    pub e_mid: f64,
    /// q = C(τ_n, τ̄) \[1/Pa\], creep of the step's own stress increment.
    pub q: f64,
    /// Ē = E(τ̄)/(1 + E(τ̄) q) \[Pa\], the effective modulus of the step.
    pub e_eff: f64,
    /// Per term: 1 − e^{−r_s Δt}, the weights of ω_s in η.
    pub release: Vec<f64>,
    /// Per term: e^{−r_s Δt}, the decay of ω_s over the step.
    pub carry: Vec<f64>,
    /// Per term: ψ_s(τ̄) e^{−r_s Δt/2}, what a unit stress increment of this
    /// step adds to ω_s for the next step.
    pub inject: Vec<f64>,
}

impl StepCoefficients {
    /// Number of creep terms.
    pub fn n_terms(&self) -> usize {
        self.release.len()
    }

    /// Δσ = Ē Q (Δε_net − η) \[Pa\], where Δε_net = Δε − Δε^T − Δε^0 is the
    /// step's total strain increment minus its free (thermal, autogenous)
    /// strains and η = [`eta`] of the Gauss point.
    pub fn stress_increment(&self, nu: Poisson, deps_net: &[f64; 6], eta: &[f64; 6]) -> [f64; 6] {
        let mut d = [0.0; 6];
        for k in 0..6 {
            d[k] = deps_net[k] - eta[k];
        }
        let s = nu.q_apply(&d);
        s.map(|x| self.e_eff * x)
    }

    /// 1-D form: Δσ = Ē (Δε_net − η).
    pub fn stress_increment_scalar(&self, deps_net: f64, eta: f64) -> f64 {
        self.e_eff * (deps_net - eta)
    }

    /// 1-D inverse: the total (mechanical) strain increment of a stress
    /// increment, Δε_net = Δσ/E(τ̄) + q Δσ + η = Δσ/Ē + η.
    pub fn strain_increment_scalar(&self, dsigma: f64, eta: f64) -> f64 {
        dsigma * (1.0 / self.e_mid + self.q) + eta
    }
}

/// The step coefficients of an element whose age runs from `age0` to `age1`
/// over the step (Δt = age1 − age0; ages advance with time).
///
/// `modulus` is the ageing [`super::ageing::ModulusLaw`] or an `f64` for a
/// constant E. Errors are those of [`mid_step_age`]: in particular a
/// zero-length step at age 0. A zero-length step at a positive age is the
/// instantaneous-load step (q = 0, Ē = E(age0), see the module docs).
pub fn coefficients<M: ModulusOfAge + ?Sized>(
    modulus: &M,
    creep: &CreepLaw,
    age0: f64,
    age1: f64,
) -> Result<StepCoefficients, AgeStepError> {
    let mid_age = mid_step_age(age0, age1)?;
    let dt = age1 - age0;
    let e_mid = modulus.modulus_at(mid_age);
    let n = creep.terms.len();
    let (mut release, mut carry, mut inject) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    let mut q = 0.0;
    for t in &creep.terms {
        let psi = t.psi(mid_age);
        let half = (-0.5 * t.r * dt).exp();
        q += psi * -(-0.5 * t.r * dt).exp_m1();
        release.push(-(-t.r * dt).exp_m1());
        carry.push((-t.r * dt).exp());
        inject.push(psi * half);
    }
    let e_eff = e_mid / (1.0 + e_mid * q);
    Ok(StepCoefficients {
        age0,
        age1,
        dt,
        mid_age,
        e_mid,
        q,
        e_eff,
        release,
        carry,
        inject,
    })
}

/// Creep state of one Gauss point: ω_s per term, in strain (Voigt,
/// engineering shear). A newborn point has all ω_s = 0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CreepState {
    /// ω_s at the start of the next step, one Voigt vector per term.
    pub omega: Vec<[f64; 6]>,
}

impl CreepState {
    /// The state of a newborn (never stressed) point.
    pub fn new(n_terms: usize) -> Self {
        CreepState {
            omega: vec![[0.0; 6]; n_terms],
        }
    }
}

/// η = Σ_s (1 − e^{−r_s Δt}) ω_s: the creep strain this step adds at
/// constant stress (the pseudo load). Panics if the state and coefficients
/// have different numbers of terms.
pub fn eta(state: &CreepState, c: &StepCoefficients) -> [f64; 6] {
    assert_eq!(
        state.omega.len(),
        c.n_terms(),
        "creep terms of state and step"
    );
    let mut e = [0.0; 6];
    for (w, &a) in state.omega.iter().zip(&c.release) {
        for k in 0..6 {
            e[k] += a * w[k];
        }
    }
    e
}

/// Ends the step once its stress increment Δσ is known: advances ω_s to the
/// start of the next step (ω_s ← ω_s e^{−r_sΔt} + Q⁻¹Δσ ψ_s(τ̄) e^{−r_sΔt/2})
/// and returns the step's creep strain increment η + q Q⁻¹Δσ. Call it
/// exactly once per step, with the coefficients used for [`eta`].
pub fn commit(
    state: &mut CreepState,
    c: &StepCoefficients,
    nu: Poisson,
    dsigma: &[f64; 6],
) -> [f64; 6] {
    let x = nu.q_inv_apply(dsigma);
    let e = eta(state, c);
    let mut dec = [0.0; 6];
    for k in 0..6 {
        dec[k] = e[k] + c.q * x[k];
    }
    for ((w, &k_carry), &k_inject) in state.omega.iter_mut().zip(&c.carry).zip(&c.inject) {
        for k in 0..6 {
            w[k] = k_carry * w[k] + k_inject * x[k];
        }
    }
    dec
}

/// 1-D creep state (uniaxial stress): ω_s per term, in strain.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScalarCreepState {
    /// ω_s at the start of the next step.
    pub omega: Vec<f64>,
}

impl ScalarCreepState {
    /// The state of a newborn (never stressed) point.
    pub fn new(n_terms: usize) -> Self {
        ScalarCreepState {
            omega: vec![0.0; n_terms],
        }
    }
}

/// 1-D [`eta`].
pub fn eta_scalar(state: &ScalarCreepState, c: &StepCoefficients) -> f64 {
    assert_eq!(
        state.omega.len(),
        c.n_terms(),
        "creep terms of state and step"
    );
    state.omega.iter().zip(&c.release).map(|(w, a)| a * w).sum()
}

/// 1-D [`commit`]: returns the step's creep strain increment η + q Δσ.
pub fn commit_scalar(state: &mut ScalarCreepState, c: &StepCoefficients, dsigma: f64) -> f64 {
    let dec = eta_scalar(state, c) + c.q * dsigma;
    for ((w, &k_carry), &k_inject) in state.omega.iter_mut().zip(&c.carry).zip(&c.inject) {
        *w = k_carry * *w + k_inject * dsigma;
    }
    dec
}
