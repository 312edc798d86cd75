//! Acceptance checks of concrete ageing (`material::ageing`) and of Zhu
//! Bofang's creep recursion (`material::creep`): the relaxation closed form
//! of DESIGN §7 with its Δt² convergence, constant and variable stress on the
//! ageing law against the superposition integral, newborn elements,
//! telescoping autogenous strain, 3-D consistency, restart equality and the
//! exact validation messages.

// Index loops read best where several arrays share the index.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::{assert_rel, rel};

use groutready::material::ageing::{mid_step_age, AgeStepError};
use groutready::material::{
    coefficients, commit, commit_scalar, eta, eta_scalar, AutogenousLaw, CreepLaw, CreepState,
    CreepTerm, ModulusLaw, Poisson, ScalarCreepState,
};

/// Least-squares slope of ln(err) against ln(dt).
fn loglog_slope(dts: &[f64], errs: &[f64]) -> f64 {
    let x: Vec<f64> = dts.iter().map(|d| d.ln()).collect();
    let y: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

const DTS: [f64; 6] = [0.2, 0.1, 0.05, 0.025, 0.0125, 0.00625];

// ------------------------------------------------------------ relaxation

const E_R: f64 = 20e9;
const PHI: f64 = 2.0;
const R: f64 = 0.3;
const EPS0: f64 = 1e-4;

/// σ(t) = ε0 E/(1+φ) [1 + φ e^{−(1+φ) r t}] (DESIGN §7).
fn relaxation_closed_form(t: f64) -> f64 {
    EPS0 * E_R / (1.0 + PHI) * (1.0 + PHI * (-(1.0 + PHI) * R * t).exp())
}

/// Scalar strain-driven relaxation: ε0 applied at t = 0 in a zero-length
/// step (Zhu's elastic jump), then held for `n` steps of `dt`. Returns σ
/// after each step, index 0 = just after the jump.
fn relax_scalar<M: groutready::material::ModulusOfAge>(
    modulus: &M,
    law: &CreepLaw,
    load_age: f64,
    dt: f64,
    n: usize,
) -> Vec<f64> {
    let mut st = ScalarCreepState::new(law.n_terms());
    let c = coefficients(modulus, law, load_age, load_age).unwrap();
    let e = eta_scalar(&st, &c);
    assert_eq!(e, 0.0);
    let mut sigma = c.stress_increment_scalar(EPS0, e);
    commit_scalar(&mut st, &c, sigma);
    let mut out = vec![sigma];
    for k in 1..=n {
        let a0 = load_age + (k - 1) as f64 * dt;
        let a1 = load_age + k as f64 * dt;
        let c = coefficients(modulus, law, a0, a1).unwrap();
        let e = eta_scalar(&st, &c);
        let ds = c.stress_increment_scalar(0.0, e);
        commit_scalar(&mut st, &c, ds);
        sigma += ds;
        out.push(sigma);
    }
    out
}

#[test]
fn relaxation_closed_form_reproduces_design_values() {
    // 1.20876 MPa and 0.681479 MPa to the quoted 6 digits.
    assert!((relaxation_closed_form(1.0) / 1e6 - 1.20876).abs() < 5e-6);
    assert!((relaxation_closed_form(5.0) / 1e6 - 0.681479).abs() < 5e-7);
    // and the limits: E ε0 at t = 0, E ε0/(1+φ) for t → ∞.
    assert_rel(relaxation_closed_form(0.0), E_R * EPS0, 1e-15, "σ(0)");
    assert_rel(relaxation_closed_form(1e4), E_R * EPS0 / 3.0, 1e-15, "σ(∞)");
}

#[test]
fn relaxation_converges_second_order() {
    // Non-ageing: constant E and C = (φ/E)(1 − e^{−r(t−τ)}); the loading age
    // is immaterial, 28 d is used so the jump step is not at age 0.
    let law = CreepLaw::non_ageing(PHI, R, E_R);
    let mut errs1 = Vec::new();
    let mut errs5 = Vec::new();
    for &dt in &DTS {
        let n5 = (5.0 / dt).round() as usize;
        let n1 = (1.0 / dt).round() as usize;
        let s = relax_scalar(&E_R, &law, 28.0, dt, n5);
        // The jump is elastic and exact.
        assert_eq!(s[0], E_R * EPS0);
        let e1 = rel(s[n1], relaxation_closed_form(1.0));
        let e5 = rel(s[n5], relaxation_closed_form(5.0));
        println!("relaxation dt = {dt:<8} rel. error t=1 d: {e1:.3e}   t=5 d: {e5:.3e}");
        errs1.push(e1);
        errs5.push(e5);
    }
    let (k1, k5) = (loglog_slope(&DTS, &errs1), loglog_slope(&DTS, &errs5));
    println!("fitted slopes: t=1 d {k1:.4}, t=5 d {k5:.4}");
    assert!((k1 - 2.0).abs() < 0.2, "slope at t = 1 d: {k1}");
    assert!((k5 - 2.0).abs() < 0.2, "slope at t = 5 d: {k5}");
    // Every halving gains about a factor 4 (not just on average).
    for w in errs1.windows(2).chain(errs5.windows(2)) {
        let ratio = w[0] / w[1];
        assert!((3.5..4.5).contains(&ratio), "error ratio {ratio}");
    }
    assert!(errs1.last().unwrap() < &1e-4 && errs5.last().unwrap() < &1e-4);
    // The 0.025 d run of the brief, on its own.
    assert!(errs1[3] < 1e-4 && errs5[3] < 1e-4);
}

#[test]
fn relaxation_in_3d_matches_scalar_and_keeps_lateral_stress_zero() {
    // Hold the strain ε0 (1, −ν, −ν, 0, 0, 0): the uniaxial stress state of
    // the scalar test, through Ē Q and Q⁻¹ in the 3-D recursion.
    let nu = Poisson(0.167);
    let law = CreepLaw::non_ageing(PHI, R, E_R);
    let dt = 0.05;
    let n = 100;
    let scalar = relax_scalar(&E_R, &law, 28.0, dt, n);
    let mut st = CreepState::new(1);
    let eps = [EPS0, -0.167 * EPS0, -0.167 * EPS0, 0.0, 0.0, 0.0];
    let c = coefficients(&E_R, &law, 28.0, 28.0).unwrap();
    let e = eta(&st, &c);
    let mut sigma = c.stress_increment(nu, &eps, &e);
    commit(&mut st, &c, nu, &sigma);
    for k in 1..=n {
        let c = coefficients(&E_R, &law, 28.0 + (k - 1) as f64 * dt, 28.0 + k as f64 * dt).unwrap();
        let e = eta(&st, &c);
        let ds = c.stress_increment(nu, &[0.0; 6], &e);
        commit(&mut st, &c, nu, &ds);
        for i in 0..6 {
            sigma[i] += ds[i];
        }
        assert_rel(sigma[0], scalar[k], 1e-12, "3-D σxx vs scalar");
        for &s in &sigma[1..] {
            assert!(s.abs() < 1e-12 * sigma[0], "lateral/shear stress {s}");
        }
    }
}

#[test]
fn ageing_relaxation_self_converges_second_order() {
    let m = ModulusLaw {
        e0_pa: 35e9,
        a: 0.40,
        b: 0.34,
    };
    let law = CreepLaw::zhu_typical(35e9);
    let dts: [f64; 6] = [0.4, 0.2, 0.1, 0.05, 0.025, 0.0125];
    let sig: Vec<f64> = dts
        .iter()
        .map(|&dt| {
            let n = (10.0 / dt).round() as usize;
            *relax_scalar(&m, &law, 3.0, dt, n).last().unwrap()
        })
        .collect();
    let diffs: Vec<f64> = sig.windows(2).map(|w| (w[0] - w[1]).abs()).collect();
    let k = loglog_slope(&dts[..diffs.len()], &diffs);
    println!(
        "ageing relaxation σ(13 d) = {:?}, difference slope {k:.4}",
        sig
    );
    assert!((k - 2.0).abs() < 0.2, "self-convergence slope {k}");
    // Relaxed, but not below the long-term share.
    let s0 = m.modulus(3.0) * EPS0;
    let last = *sig.last().unwrap();
    assert!(
        last < 0.7 * s0 && last > 0.2 * s0,
        "σ(13 d) = {last}, σ(3 d) = {s0}"
    );
    assert!(diffs.last().unwrap() / last < 1e-4);
}

// ------------------------------------------------------ creep under stress

fn zhu_modulus() -> ModulusLaw {
    ModulusLaw {
        e0_pa: 35e9,
        a: 0.40,
        b: 0.34,
    }
}

#[test]
fn constant_stress_on_ageing_law_is_exact() {
    // A stress applied in a zero-length step at τ0 and held: the recursion
    // integrates the exponential kernels exactly, for any steps.
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    let sigma = -2.5e6;
    for &tau0 in &[1.0, 7.0, 28.0] {
        // Steps growing geometrically from 0.01 d, as a staged run does.
        let mut st = ScalarCreepState::new(2);
        let c = coefficients(&m, &law, tau0, tau0).unwrap();
        let mut eps = c.strain_increment_scalar(sigma, eta_scalar(&st, &c));
        let mut creep = commit_scalar(&mut st, &c, sigma);
        assert_eq!(eps, sigma / m.modulus(tau0));
        assert_eq!(creep, 0.0);
        let (mut age, mut dt) = (tau0, 0.01);
        while age < tau0 + 400.0 {
            let c = coefficients(&m, &law, age, age + dt).unwrap();
            let e = eta_scalar(&st, &c);
            eps += c.strain_increment_scalar(0.0, e);
            creep += commit_scalar(&mut st, &c, 0.0);
            age += dt;
            dt *= 1.15;
            let want_c = sigma * law.compliance(age, tau0);
            assert_rel(creep, want_c, 1e-12, "creep strain");
            assert_rel(eps, sigma / m.modulus(tau0) + want_c, 1e-12, "total strain");
        }
        // Most of the final creep of the fast term has been released.
        assert!(creep / (sigma * law.final_compliance(tau0)) > 0.6);
    }
    // Younger concrete creeps more (g_s ≠ 0 matters).
    assert!(law.compliance(38.0, 10.0) > 1.3 * law.compliance(58.0, 30.0));
}

/// Stress history: jump σ0 at τ0, then σ1 (1 − e^{−λ(τ−τ0)}) on top.
const TAU0: f64 = 7.0;
const S0: f64 = 1.0e6;
const S1: f64 = 2.0e6;
const LAMBDA: f64 = 0.5;

fn stress(age: f64) -> f64 {
    S0 + S1 * -(-LAMBDA * (age - TAU0)).exp_m1()
}

/// ε(t) = σ0 J(t, τ0) + ∫_{τ0}^{t} J(t, τ) σ′(τ) dτ by composite Simpson.
fn superposition(m: &ModulusLaw, law: &CreepLaw, t: f64, n: usize) -> f64 {
    let j = |tau: f64| 1.0 / m.modulus(tau) + law.compliance(t, tau);
    let f = |tau: f64| j(tau) * S1 * LAMBDA * (-LAMBDA * (tau - TAU0)).exp();
    let h = (t - TAU0) / n as f64;
    let mut s = f(TAU0) + f(t);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(TAU0 + i as f64 * h);
    }
    S0 * j(TAU0) + s * h / 3.0
}

#[test]
fn variable_stress_on_ageing_law_converges_second_order() {
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    let checks = [TAU0 + 2.0, TAU0 + 20.0];
    let refs: Vec<f64> = checks
        .iter()
        .map(|&t| {
            let a = superposition(&m, &law, t, 100_000);
            let b = superposition(&m, &law, t, 200_000);
            assert_rel(a, b, 1e-13, "reference quadrature converged");
            b
        })
        .collect();
    let mut errs = [Vec::new(), Vec::new()];
    for &dt in &DTS {
        let mut st = ScalarCreepState::new(2);
        let c = coefficients(&m, &law, TAU0, TAU0).unwrap();
        let mut eps = c.strain_increment_scalar(S0, eta_scalar(&st, &c));
        commit_scalar(&mut st, &c, S0);
        let n = (20.0 / dt).round() as usize;
        for k in 1..=n {
            let (a0, a1) = (TAU0 + (k - 1) as f64 * dt, TAU0 + k as f64 * dt);
            let c = coefficients(&m, &law, a0, a1).unwrap();
            let e = eta_scalar(&st, &c);
            let ds = stress(a1) - stress(a0);
            eps += c.strain_increment_scalar(ds, e);
            commit_scalar(&mut st, &c, ds);
            for (i, &t) in checks.iter().enumerate() {
                if (a1 - t).abs() < 1e-9 {
                    errs[i].push(rel(eps, refs[i]));
                }
            }
        }
    }
    for (i, t) in checks.iter().enumerate() {
        let k = loglog_slope(&DTS, &errs[i]);
        println!(
            "variable stress, age {t} d: errors {:?}, slope {k:.4}",
            errs[i]
        );
        assert!((k - 2.0).abs() < 0.2, "slope at {t} d: {k}");
        assert!(*errs[i].last().unwrap() < 1e-5);
    }
}

// ---------------------------------------------------- newborn and ageing

#[test]
fn newborn_step_has_positive_stiffness() {
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    for &dt in &[1e-9, 1e-3, 0.1, 0.5, 1.0, 3.0] {
        let e = m.modulus_mid_step(0.0, dt).unwrap();
        assert!(e > 0.0, "E for a newborn step of {dt} d");
        assert_eq!(e, m.modulus(0.5 * dt));
        let c = coefficients(&m, &law, 0.0, dt).unwrap();
        assert_eq!(c.mid_age, 0.5 * dt);
        assert_eq!(c.e_mid, e);
        assert!(c.q.is_finite() && c.q > 0.0);
        assert!(c.e_eff > 0.0 && c.e_eff < c.e_mid);
        assert_rel(c.e_eff, e / (1.0 + e * c.q), 1e-15, "Ē");
    }
    // E(0) is zero: a zero-length step at birth is refused, not floored.
    assert_eq!(m.modulus(0.0), 0.0);
    assert_eq!(m.modulus(-2.0), 0.0);
    assert_eq!(
        m.modulus_mid_step(0.0, 0.0),
        Err(AgeStepError::NewbornInstant)
    );
    assert_eq!(
        coefficients(&m, &law, 0.0, 0.0).unwrap_err(),
        AgeStepError::NewbornInstant
    );
    // A zero-length step at a positive age is the instantaneous load.
    let c = coefficients(&m, &law, 5.0, 5.0).unwrap();
    assert_eq!(
        (c.q, c.e_mid, c.e_eff),
        (0.0, m.modulus(5.0), m.modulus(5.0))
    );
    assert_eq!(
        mid_step_age(-0.5, 1.0),
        Err(AgeStepError::BeforeBirth { age0: -0.5 })
    );
    assert_eq!(
        mid_step_age(2.0, 1.0),
        Err(AgeStepError::Backwards {
            age0: 2.0,
            age1: 1.0
        })
    );
    assert!(matches!(
        mid_step_age(f64::NAN, 1.0),
        Err(AgeStepError::NotFinite { .. })
    ));
    assert_eq!(mid_step_age(1.0, 3.0), Ok(2.0));
    assert_eq!(
        AgeStepError::NewbornInstant.to_string(),
        "zero-length step at age 0: newborn concrete has no stiffness; \
         give an element's first step a positive length"
    );
    assert_eq!(
        AgeStepError::Backwards {
            age0: 2.0,
            age1: 1.5
        }
        .to_string(),
        "step runs backwards: age 2 to 1.5"
    );
}

#[test]
fn modulus_ageing_is_monotone_and_matches_the_formula() {
    let m = zhu_modulus();
    let mut prev = 0.0;
    for i in 0..=120 {
        let age = 10f64.powf(-6.0 + 0.075 * i as f64); // 1e-6 … 1e3 d
        let e = m.modulus(age);
        assert!(e > prev && e < m.e0_pa, "E({age}) = {e} after {prev}");
        let want = 35e9 * (1.0 - (-0.4 * age.powf(0.34)).exp());
        let tol = 1e-15 / (0.4 * age.powf(0.34)).min(1.0) + 1e-15;
        assert_rel(e, want, tol, "E(τ)");
        prev = e;
    }
    // a = 0.40, b = 0.34 reaches 71 % of E0 at 28 d and 95 % at 365 d.
    let r28 = m.modulus(28.0) / m.e0_pa;
    assert!((0.710..0.712).contains(&r28), "E(28)/E0 = {r28}");
    let r365 = m.modulus(365.0) / m.e0_pa;
    assert!((0.948..0.950).contains(&r365), "E(365)/E0 = {r365}");
    assert_eq!(m.final_modulus(), 35e9);
}

#[test]
fn autogenous_increments_telescope() {
    let g = AutogenousLaw {
        eps_inf: -40e-6,
        c: 0.25,
        d: 0.55,
    };
    assert_eq!(g.strain(0.0), 0.0);
    assert_eq!(g.strain(-1.0), 0.0);
    assert_rel(
        g.strain(10.0),
        -40e-6 * (1.0 - (-0.25 * 10f64.powf(0.55)).exp()),
        1e-14,
        "G(10)",
    );
    // Irregular steps (a deterministic LCG), including zero-length ones.
    let mut seed: u64 = 12345;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut age = 0.0;
    let mut sum = 0.0;
    let mut n = 0;
    while age < 365.0 {
        let dt = if n % 17 == 5 {
            0.0
        } else {
            3.0 * rnd() * rnd()
        };
        let inc = g.increment(age, age + dt);
        assert!(inc <= 0.0, "shrinkage increments are ≤ 0");
        if dt == 0.0 {
            assert_eq!(inc, 0.0);
        }
        sum += inc;
        age += dt;
        n += 1;
        assert_rel(sum, g.strain(age), 1e-13, "Σ ΔG = G(τ)");
    }
    assert!(n > 200);
    // A step from before the pour counts from age 0; reversing negates.
    assert_eq!(g.increment(-3.0, 2.0), g.increment(0.0, 2.0));
    assert_eq!(g.increment(2.0, 5.0), -g.increment(5.0, 2.0));
    // Short late steps keep relative precision (no cancellation): G′(300)·Δτ
    // with the step actually representable (Δτ = (300 + 1e-9) − 300 exactly),
    // the curvature term is ~1e-12 relative. G(τ1) − G(τ0) would miss by ~1e-5.
    let a1 = 300.0 + 1e-9;
    let dtau = a1 - 300.0;
    let tiny = g.increment(300.0, a1);
    let rate = -40e-6 * 0.25 * 0.55 * 300f64.powf(-0.45) * (-0.25 * 300f64.powf(0.55)).exp();
    assert_rel(tiny, rate * dtau, 1e-11, "short late step");
    assert!(rel(g.strain(a1) - g.strain(300.0), rate * dtau) > 1e-7);
    assert_eq!(g.final_strain(), -40e-6);
}

// ------------------------------------------------------- 3-D consistency

#[test]
fn poisson_matrices_are_inverse() {
    let nu = Poisson(0.167);
    let (q, qi) = (nu.q_matrix(), nu.q_inv_matrix());
    for i in 0..6 {
        for j in 0..6 {
            let p: f64 = (0..6).map(|k| q[i][k] * qi[k][j]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((p - want).abs() < 1e-15, "(Q Q⁻¹)[{i}][{j}] = {p}");
        }
    }
    let v = [1.0, -2.0, 0.5, 0.3, -0.7, 1.1];
    let (a, b) = (nu.q_apply(&v), nu.q_inv_apply(&v));
    for i in 0..6 {
        let qa: f64 = (0..6).map(|k| q[i][k] * v[k]).sum();
        let qb: f64 = (0..6).map(|k| qi[i][k] * v[k]).sum();
        assert!((a[i] - qa).abs() < 1e-15 && (b[i] - qb).abs() < 1e-15);
    }
    // Engineering shear: γ = 2(1+ν) τ / E.
    assert_eq!(qi[3][3], 2.0 * 1.167);
    assert_eq!(nu.nu(), 0.167);
}

#[test]
fn uniaxial_stress_in_3d_creeps_laterally_by_minus_nu() {
    let nu = Poisson(0.2);
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    let mut s3 = CreepState::new(2);
    let mut s1 = ScalarCreepState::new(2);
    let (mut c3, mut c1) = ([0.0; 6], 0.0);
    let mut step = |a0: f64, a1: f64, ds: f64, first: bool| {
        let c = coefficients(&m, &law, a0, a1).unwrap();
        let e3 = eta(&s3, &c);
        let e1 = eta_scalar(&s1, &c);
        assert_eq!(e3[0], e1);
        let d3 = commit(&mut s3, &c, nu, &[ds, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let d1 = commit_scalar(&mut s1, &c, ds);
        for k in 0..6 {
            c3[k] += d3[k];
        }
        c1 += d1;
        if !first {
            assert!(c1 > 0.0);
        }
        assert_rel(c3[0], c1, 1e-15, "axial 3-D vs scalar");
        assert_rel(c3[1], -0.2 * c1, 1e-14, "lateral yy = −ν axial");
        assert_rel(c3[2], -0.2 * c1, 1e-14, "lateral zz = −ν axial");
        assert!(c3[3..].iter().all(|&x| x == 0.0));
    };
    step(TAU0, TAU0, S0, true);
    for k in 1..=200 {
        let (a0, a1) = (TAU0 + (k - 1) as f64 * 0.1, TAU0 + k as f64 * 0.1);
        step(a0, a1, stress(a1) - stress(a0), false);
    }
}

#[test]
fn pure_shear_creeps_with_engineering_shear_factor() {
    let nu = Poisson(0.167);
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    let tau = 1.5e6;
    let mut st = CreepState::new(2);
    let c = coefficients(&m, &law, 28.0, 28.0).unwrap();
    commit(&mut st, &c, nu, &[0.0, 0.0, 0.0, tau, 0.0, 0.0]);
    let mut creep = [0.0; 6];
    for k in 1..=90 {
        let c = coefficients(&m, &law, 27.0 + k as f64, 28.0 + k as f64).unwrap();
        let d = commit(&mut st, &c, nu, &[0.0; 6]);
        for i in 0..6 {
            creep[i] += d[i];
        }
    }
    let want = 2.0 * 1.167 * tau * law.compliance(118.0, 28.0);
    assert_rel(creep[3], want, 1e-12, "γ_xy creep");
    assert!(creep.iter().enumerate().all(|(i, &x)| i == 3 || x == 0.0));
}

#[test]
fn restart_from_serialized_state_equals_uninterrupted_run() {
    let nu = Poisson(0.167);
    let m = zhu_modulus();
    let law = CreepLaw::zhu_typical(35e9);
    let run = |split: Option<usize>| {
        let mut st = CreepState::new(2);
        let mut sig = [0.0; 6];
        for k in 0..60 {
            if Some(k) == split {
                let text = toml::to_string(&st).unwrap();
                st = toml::from_str(&text).unwrap();
            }
            let (a0, a1) = (0.25 * k as f64, 0.25 * (k + 1) as f64);
            let c = coefficients(&m, &law, a0, a1).unwrap();
            let e = eta(&st, &c);
            let x = 1e-6 * (k as f64).sin();
            let deps = [x, -0.5 * x, 0.2 * x, 0.1 * x, 0.0, -x];
            let ds = c.stress_increment(nu, &deps, &e);
            commit(&mut st, &c, nu, &ds);
            for i in 0..6 {
                sig[i] += ds[i];
            }
        }
        (st, sig)
    };
    assert_eq!(run(None), run(Some(31)));
}

// ------------------------------------------------------- scene input

#[test]
fn laws_parse_from_toml_and_reject_unknown_keys() {
    let m: ModulusLaw = toml::from_str("e0_pa = 3.5e10\na = 0.4\nb = 0.34").unwrap();
    assert_eq!(m, zhu_modulus());
    assert!(toml::from_str::<ModulusLaw>("e0 = 3.5e10\na = 0.4\nb = 0.34").is_err());
    let g: AutogenousLaw = toml::from_str("eps_inf = -3e-5\nc = 0.2\nd = 0.6").unwrap();
    assert_eq!(g.eps_inf, -3e-5);
    let law: CreepLaw = toml::from_str(
        "[[terms]]\nf = 6.6e-12\ng = 6.0e-11\np = 0.45\nr = 0.30\n\
         [[terms]]\nf = 1.5e-11\ng = 2.5e-11\np = 0.45\nr = 0.005\n",
    )
    .unwrap();
    assert_eq!(law.n_terms(), 2);
    assert_eq!(law.terms[1].r, 0.005);
    assert!(
        toml::from_str::<CreepLaw>("[[terms]]\nf = 1e-11\ng = 0\np = 0\nr = 1\nq = 2").is_err()
    );
}

#[test]
fn zhu_typical_matches_the_quoted_formula() {
    let e2 = 35e9;
    let law = CreepLaw::zhu_typical(e2);
    assert!(law.validate().map_err(|e| e.message).is_ok());
    for &(t, tau) in &[(8.0, 3.0), (60.0, 28.0), (400.0, 90.0)] {
        let d: f64 = t - tau;
        let want = 0.23 / e2 * (1.0 + 9.20 * tau.powf(-0.45)) * (1.0 - (-0.30 * d).exp())
            + 0.52 / e2 * (1.0 + 1.70 * tau.powf(-0.45)) * (1.0 - (-0.0050 * d).exp());
        assert_rel(law.compliance(t, tau), want, 1e-14, "C(t, τ)");
    }
    assert_eq!(law.compliance(5.0, 5.0), 0.0);
    assert_eq!(law.compliance(4.0, 5.0), 0.0);
    assert_rel(
        law.final_compliance(28.0),
        (0.23 * (1.0 + 9.20 * 28f64.powf(-0.45)) + 0.52 * (1.0 + 1.70 * 28f64.powf(-0.45))) / e2,
        1e-15,
        "C(∞, 28)",
    );
}

// ------------------------------------------------------- validation

#[test]
fn validation_messages_name_the_field() {
    let m = |e0_pa, a, b| ModulusLaw { e0_pa, a, b }.validate().map_err(|e| e.message);
    assert_eq!(m(35e9, 0.4, 0.34), Ok(()));
    assert_eq!(
        m(35.0, 0.4, 0.34),
        Err("e0_pa must be between 1e8 and 1e12 Pa, got 35".to_string())
    );
    assert_eq!(
        m(f64::NAN, 0.4, 0.34),
        Err("e0_pa must be between 1e8 and 1e12 Pa, got NaN".to_string())
    );
    assert_eq!(m(35e9, 0.0, 0.34), Err("a must be > 0, got 0".to_string()));
    assert_eq!(
        m(35e9, f64::INFINITY, 0.34),
        Err("a must be finite, got inf".to_string())
    );
    assert_eq!(
        m(35e9, 0.4, 0.0),
        Err("b must be in (0, 3], got 0".to_string())
    );

    let g = |eps_inf, c, d| {
        AutogenousLaw { eps_inf, c, d }
            .validate()
            .map_err(|e| e.message)
    };
    assert_eq!(g(-50e-6, 0.2, 0.6), Ok(()));
    assert_eq!(g(0.0, 0.2, 0.6), Ok(()));
    assert_eq!(
        g(50.0, 0.2, 0.6),
        Err("eps_inf must be a strain between -1e-3 and 1e-3, got 50".to_string())
    );
    assert_eq!(
        g(-50e-6, -1.0, 0.6),
        Err("c must be > 0, got -1".to_string())
    );
    assert_eq!(
        g(-50e-6, 0.2, 4.0),
        Err("d must be in (0, 3], got 4".to_string())
    );

    assert_eq!(Poisson(0.167).validate().map_err(|e| e.message), Ok(()));
    assert_eq!(
        Poisson(0.5).validate().map_err(|e| e.message),
        Err("poisson must be in [0, 0.5), got 0.5".to_string())
    );
    assert_eq!(
        Poisson(-0.1).validate().map_err(|e| e.message),
        Err("poisson must be in [0, 0.5), got -0.1".to_string())
    );

    let term = CreepTerm {
        f: 6.6e-12,
        g: 6.0e-11,
        p: 0.45,
        r: 0.3,
    };
    let law = |t: Vec<CreepTerm>| CreepLaw { terms: t }.validate().map_err(|e| e.message);
    assert_eq!(law(vec![term]), Ok(()));
    assert_eq!(
        law(vec![]),
        Err("terms must hold at least one creep term".to_string())
    );
    assert_eq!(
        law(vec![CreepTerm { f: 0.23, ..term }]),
        Err("terms[0].f must be in [0, 1e-6) 1/Pa, got 0.23".to_string())
    );
    assert_eq!(
        law(vec![term, CreepTerm { g: -2.0, ..term }]),
        Err("terms[1].g must be in [0, 1e-6) 1/Pa, got -2".to_string())
    );
    assert_eq!(
        law(vec![CreepTerm { p: 1.5, ..term }]),
        Err("terms[0].p must be in [0, 1], got 1.5".to_string())
    );
    assert_eq!(
        law(vec![term, CreepTerm { r: 0.0, ..term }]),
        Err("terms[1].r must be > 0, got 0".to_string())
    );
    assert_eq!(
        law(vec![CreepTerm {
            r: f64::NAN,
            ..term
        }]),
        Err("terms[0].r must be > 0, got NaN".to_string())
    );
    assert_eq!(
        CreepLaw::non_ageing(2.0, 0.3, 20e9)
            .validate()
            .map_err(|e| e.message),
        Ok(())
    );
}
