//! Checks of `groutready::material`: adiabatic rise laws, Zhu's pipe-cooling
//! φ and the pipe correction, and the convolution H(t) against closed forms,
//! an independent brute-force quadrature and 25-digit mpmath references.

// References are quoted at the precision they were computed with.
#![allow(clippy::excessive_precision)]

use crate::common;

use common::{assert_rel, rel};

use groutready::material::pipe_cooling::{
    dimensionless_xi, first_eigenvalue_alpha_b, zhu_k_s, ALPHA1_B_AT_100,
};
use groutready::material::{hydration_under_cooling, AdiabaticRise, PipeLayout, ZhuPipe};

const EXP: AdiabaticRise = AdiabaticRise::Exponential {
    theta0: 25.0,
    m: 0.35,
};
const COMP: AdiabaticRise = AdiabaticRise::Compound {
    theta0: 24.0,
    a: 0.4,
    b: 0.6,
};
const HYP: AdiabaticRise = AdiabaticRise::Hyperbolic {
    theta0: 26.0,
    n: 2.5,
};

// ---------------------------------------------------------------- rise laws

#[test]
fn rise_forms_match_closed_forms() {
    for &tau in &[1e-6f64, 0.1, 0.5, 1.0, 3.0, 7.0, 28.0, 90.0, 400.0] {
        let e = 25.0 * (1.0 - (-0.35 * tau).exp());
        let c = 24.0 * (1.0 - (-0.4 * tau.powf(0.6)).exp());
        let h = 26.0 * tau / (2.5 + tau);
        // 1 − e^{−x} loses digits for small x; compare with a tolerance
        // that reflects that cancellation in the reference, not in θ.
        let tol = |x: f64| 1e-15 / x.min(1.0) + 1e-15;
        assert_rel(EXP.theta(tau), e, tol(0.35 * tau), "exponential θ");
        assert_rel(COMP.theta(tau), c, tol(0.4 * tau.powf(0.6)), "compound θ");
        assert_rel(HYP.theta(tau), h, 1e-15, "hyperbolic θ");
    }
    for r in [&EXP, &COMP, &HYP] {
        assert_eq!(r.theta(0.0), 0.0);
        assert_eq!(r.theta(-3.0), 0.0);
        assert!(r.theta(1e9) <= r.theta0() && r.theta(1e9) > 0.999 * r.theta0());
    }
    assert_eq!(EXP.theta0(), 25.0);
    assert_eq!(COMP.theta0(), 24.0);
    assert_eq!(HYP.theta0(), 26.0);
}

#[test]
fn rise_small_ages_keep_relative_precision() {
    // θ(τ) ≈ θ0 m τ for tiny τ: the expm1 form keeps every digit.
    let tau = 1e-12;
    assert_rel(
        EXP.theta(tau),
        25.0 * 0.35 * tau,
        1e-11,
        "exponential θ(1e-12)",
    );
}

#[test]
fn rates_match_central_differences() {
    for r in [&EXP, &COMP, &HYP] {
        for &tau in &[0.05, 0.3, 1.0, 2.0, 10.0, 60.0, 300.0] {
            // Fourth-order central difference; its truncation error is far
            // below the bound, which is set by rounding in θ(τ ± h).
            let h = 1e-3 * tau;
            let d = |k: f64| r.theta(tau + k * h) - r.theta(tau - k * h);
            let fd = (8.0 * d(1.0) - d(2.0)) / (12.0 * h);
            let rounding = 4.0 * f64::EPSILON * r.theta0() / h;
            let err = (r.rate(tau) - fd).abs();
            assert!(
                err <= 1e-9 * r.rate(tau) + rounding,
                "rate {r:?} at {tau}: {} vs {fd} (error {err:e})",
                r.rate(tau)
            );
        }
    }
    // Closed forms of θ′.
    assert_rel(
        EXP.rate(2.0),
        25.0 * 0.35 * (-0.7f64).exp(),
        1e-15,
        "exp θ′",
    );
    assert_rel(HYP.rate(2.0), 26.0 * 2.5 / (4.5 * 4.5), 1e-15, "hyp θ′");
    let c = 24.0 * 0.4 * 0.6 * 2f64.powf(-0.4) * (-0.4 * 2f64.powf(0.6)).exp();
    assert_rel(COMP.rate(2.0), c, 1e-14, "compound θ′");
}

#[test]
fn rates_at_and_before_the_pour() {
    for r in [&EXP, &COMP, &HYP] {
        assert_eq!(r.rate(-1.0), 0.0);
        assert!(r.rate(0.0).is_finite() && r.rate(0.0) > 0.0);
    }
    // Compound with b < 1: infinite at τ = 0, evaluated at τ = 1e-12.
    let at = 24.0 * 0.4 * 0.6 * 1e-12f64.powf(-0.4) * (-0.4 * 1e-12f64.powf(0.6)).exp();
    assert_rel(COMP.rate(0.0), at, 1e-9, "compound θ′(0)");
    assert_rel(EXP.rate(0.0), 25.0 * 0.35, 1e-11, "exponential θ′(0)");
}

#[test]
fn rise_validation_names_the_field() {
    let e = |theta0, m| {
        AdiabaticRise::Exponential { theta0, m }
            .validate()
            .map_err(|e| e.message)
    };
    let c = |a, b| {
        AdiabaticRise::Compound { theta0: 25.0, a, b }
            .validate()
            .map_err(|e| e.message)
    };
    let h = |n| {
        AdiabaticRise::Hyperbolic { theta0: 25.0, n }
            .validate()
            .map_err(|e| e.message)
    };
    assert_eq!(e(-3.0, 0.3), Err("theta0 must be > 0, got -3".to_string()));
    assert_eq!(e(0.0, 0.3), Err("theta0 must be > 0, got 0".to_string()));
    assert_eq!(
        e(120.0, 0.3),
        Err("theta0 must be < 100, got 120".to_string())
    );
    assert_eq!(e(25.0, 0.0), Err("m must be > 0, got 0".to_string()));
    assert_eq!(e(25.0, f64::NAN), Err("m must be > 0, got NaN".to_string()));
    assert_eq!(c(-0.1, 0.5), Err("a must be > 0, got -0.1".to_string()));
    assert_eq!(c(0.4, 3.5), Err("b must be in (0, 3], got 3.5".to_string()));
    assert_eq!(c(0.4, 0.0), Err("b must be in (0, 3], got 0".to_string()));
    assert_eq!(
        h(f64::INFINITY),
        Err("n must be finite, got inf".to_string())
    );
    assert_eq!(h(-2.0), Err("n must be > 0, got -2".to_string()));
    assert_eq!(c(0.4, 3.0), Ok(()));
    assert_eq!(e(99.9, 0.3), Ok(()));
    for r in [&EXP, &COMP, &HYP] {
        assert_eq!(r.validate().map_err(|e| e.message), Ok(()));
    }
}

// ------------------------------------------------------------- pipe layout

fn layout() -> PipeLayout {
    PipeLayout {
        spacing_horizontal_m: 1.5,
        spacing_vertical_m: 1.5,
        length_m: 250.0,
        flow_l_per_min: 20.0,
        outer_radius_m: 0.016,
        inner_radius_m: 0.014,
        wall_conductivity_w_mk: 0.45,
        water_density: 1000.0,
        water_specific_heat: 4186.0,
    }
}

#[test]
fn layout_validation_names_the_field() {
    assert_eq!(layout().validate().map_err(|e| e.message), Ok(()));
    let bad = |f: &dyn Fn(&mut PipeLayout)| {
        let mut l = layout();
        f(&mut l);
        l.validate().map_err(|e| e.message).unwrap_err()
    };
    assert_eq!(
        bad(&|l| l.spacing_horizontal_m = 0.0),
        "spacing_horizontal_m must be > 0, got 0"
    );
    assert_eq!(
        bad(&|l| l.spacing_vertical_m = -1.5),
        "spacing_vertical_m must be > 0, got -1.5"
    );
    assert_eq!(bad(&|l| l.length_m = 0.0), "length_m must be > 0, got 0");
    assert_eq!(
        bad(&|l| l.flow_l_per_min = f64::NAN),
        "flow_l_per_min must be > 0, got NaN"
    );
    assert_eq!(
        bad(&|l| l.outer_radius_m = -0.016),
        "outer_radius_m must be > 0, got -0.016"
    );
    assert_eq!(
        bad(&|l| {
            l.spacing_vertical_m = 1.0;
            l.outer_radius_m = 0.6;
        }),
        "outer_radius_m must be < half the smaller spacing (0.5), got 0.6"
    );
    assert_eq!(
        bad(&|l| l.inner_radius_m = 0.0),
        "inner_radius_m must be > 0, got 0"
    );
    assert_eq!(
        bad(&|l| l.inner_radius_m = 0.016),
        "inner_radius_m must be < outer_radius_m (0.016), got 0.016"
    );
    assert_eq!(
        bad(&|l| l.wall_conductivity_w_mk = -1.0),
        "wall_conductivity_w_mk must be > 0, got -1"
    );
    assert_eq!(
        bad(&|l| l.water_density = 0.0),
        "water_density must be > 0, got 0"
    );
    assert_eq!(
        bad(&|l| l.water_specific_heat = f64::INFINITY),
        "water_specific_heat must be finite, got inf"
    );
}

#[test]
fn layout_defaults_for_water() {
    let l: PipeLayout = toml::from_str(
        "spacing_horizontal_m = 1.5\nspacing_vertical_m = 1.5\nlength_m = 250\n\
         flow_l_per_min = 20\nouter_radius_m = 0.016\ninner_radius_m = 0.014\n\
         wall_conductivity_w_mk = 0.45\n",
    )
    .unwrap();
    assert_eq!(l, layout());
}

// ------------------------------------------------------------- Zhu's φ

/// Hand computation, S1 = S2 = 1.5 m, L = 250 m, q_w = 20 L/min
/// = 3.333…e-4 m³/s, λ = 2 W/(m K), c_w = 4186 J/(kg K), ρ_w = 1000 kg/m³:
/// ξ = 2·250 / (4186·1000·3.333e-4) = 500 / 1395.333 = 0.358 337 314 859 054
/// k = 2.08 − 1.174·0.358337 + 0.256·0.358337² = 1.692 183 833 947 892
/// s = 0.971 + 0.1485·0.358337 − 0.0445·0.358337² = 1.018 499 040 667 262
/// D = 1.167·1.5 = 1.7505 m. With b/c = 100 exactly and a "perfect" wall
/// the correction is the identity, so p = k (a/D²)^s, a = 0.1 m²/day:
/// p = 1.692184·(0.1/3.06425)^1.018499 = 0.051 835 553 367 060 84.
#[test]
fn zhu_coefficients_hand_computed() {
    let mut l = layout();
    l.outer_radius_m = 1.7505 / 2.0 / 100.0;
    l.inner_radius_m = 0.9 * l.outer_radius_m;
    l.wall_conductivity_w_mk = 1e12;
    let xi = dimensionless_xi(&l, 2.0);
    assert_rel(xi, 0.358_337_314_859_054, 1e-14, "ξ");
    let (k, s) = zhu_k_s(xi);
    assert_rel(k, 1.692_183_833_947_892, 1e-14, "k");
    assert_rel(s, 1.018_499_040_667_262, 1e-14, "s");
    let d = ZhuPipe::derive(&l, 0.1, 2.0);
    assert_rel(d.diameter_m, 1.7505, 1e-15, "D");
    assert_rel(d.b_over_c1, 100.0, 1e-12, "b/c1");
    assert_rel(d.alpha1_b, ALPHA1_B_AT_100, 1e-12, "α1 b");
    let pipe = ZhuPipe::new(&l, 0.1, 2.0);
    assert_rel(pipe.p, 0.051_835_553_367_060_84, 1e-11, "p");
    assert_rel(pipe.s, s, 0.0, "s");
}

/// HDPE, c = 16 mm, r0 = 14 mm, λ1 = 0.45, λ = 2 (mpmath, 30 digits):
/// c1 = 0.016·exp(−(2/0.45)·ln(16/14)) = 8.838 488 396 267 91e-3 m,
/// b/c1 = 0.87525/c1 = 99.027 114 225 728 67, α1 b = 0.717 582 950 701 256,
/// a′ = 0.1·(0.717583/0.716691)² = 0.100 249 165 730 319,
/// p = k (a′/D²)^s = 0.051 967 102 101 536 09.
#[test]
fn plastic_pipe_equivalent_radius_and_diffusivity() {
    let d = ZhuPipe::derive(&layout(), 0.1, 2.0);
    assert_rel(d.equivalent_radius_m, 8.838_488_396_267_91e-3, 1e-13, "c1");
    assert_rel(d.b_over_c1, 99.027_114_225_728_67, 1e-13, "b/c1");
    assert_rel(d.alpha1_b, 0.717_582_950_701_256, 1e-12, "α1 b");
    assert_rel(
        d.equivalent_diffusivity_m2_per_day,
        0.100_249_165_730_319,
        1e-12,
        "a′",
    );
    assert_rel(d.p, 0.051_967_102_101_536_09, 1e-11, "p");
    // A steel wall of the same size barely changes anything.
    let mut steel = layout();
    steel.wall_conductivity_w_mk = 45.0;
    let ds = ZhuPipe::derive(&steel, 0.1, 2.0);
    assert!(ds.equivalent_radius_m > 0.0159 && ds.equivalent_radius_m < 0.016);
    // A worse-conducting wall cools more slowly.
    let mut pvc = layout();
    pvc.wall_conductivity_w_mk = 0.2;
    assert!(ZhuPipe::new(&pvc, 0.1, 2.0).p < d.p && d.p < ds.p);
}

#[test]
fn cylinder_eigenvalue_matches_mpmath() {
    // First root of J1(x)Y0(x/r) − Y1(x)J0(x/r), mpmath findroot, 30 digits.
    let refs = [
        (1.2, 9.079_999_577_423_284_9),
        (1.5, 4.334_829_616_404_710_8),
        (2.0, 2.721_554_770_674_016_8),
        (5.0, 1.411_791_463_934_327_3),
        (10.0, 1.102_694_256_211_956_3),
        (20.0, 0.930_171_733_232_975_8),
        (54.7, 0.778_780_267_131_989_5),
        (100.0, 0.716_690_632_468_996_2),
        (1000.0, 0.568_797_897_041_772_2),
        (1e6, 0.391_079_381_721_647_2),
    ];
    for (r, want) in refs {
        assert_rel(
            first_eigenvalue_alpha_b(r),
            want,
            1e-12,
            &format!("α1 b at b/c = {r}"),
        );
    }
    assert!(first_eigenvalue_alpha_b(1.0).is_nan());
    assert!(first_eigenvalue_alpha_b(f64::NAN).is_nan());
    // The smallest b/c a valid layout allows is 2·0.5835 = 1.167.
    assert!(first_eigenvalue_alpha_b(1.167).is_finite());
    // Zhu's k(0) = 2.08 is the leading mode (2 α1 b)² = 2.0546 at b/c = 100
    // to within what his fit absorbs from the higher modes.
    let lead = (2.0 * ALPHA1_B_AT_100).powi(2);
    assert_rel(lead, 2.054_581_850_675_239, 1e-14, "(2 α1 b)²");
    assert!(rel(lead, zhu_k_s(0.0).0) < 0.02);
}

#[test]
fn try_new_checks_inputs_and_xi_range() {
    let l = layout();
    assert_eq!(
        ZhuPipe::try_new(&l, 0.1, 2.0).map_err(|e| e.message),
        Ok(ZhuPipe::new(&l, 0.1, 2.0))
    );
    assert_eq!(
        ZhuPipe::try_new(&l, 0.0, 2.0).map_err(|e| e.message),
        Err("diffusivity_m2_per_day must be > 0, got 0".to_string())
    );
    let mut bad = l.clone();
    bad.length_m = -1.0;
    assert_eq!(
        ZhuPipe::try_new(&bad, 0.1, 2.0).map_err(|e| e.message),
        Err("length_m must be > 0, got -1".to_string())
    );
    let mut long = l.clone();
    long.length_m = 5000.0; // ξ = 7.2
    let err = ZhuPipe::try_new(&long, 0.1, 2.0).unwrap_err().message;
    assert!(err.starts_with("xi = "), "{err}");
    assert!(err.contains("got 7.16"), "{err}");
}

#[test]
fn phi_starts_at_one_and_decreases() {
    let pipe = ZhuPipe::new(&layout(), 0.1, 2.0);
    assert_eq!(pipe.phi(0.0), 1.0);
    assert_eq!(pipe.phi(-5.0), 1.0);
    let mut prev = 1.0;
    for i in 1..=4000 {
        let t = 0.1 * i as f64;
        let v = pipe.phi(t);
        assert!(v < prev && v > 0.0, "φ not decreasing at t = {t}");
        prev = v;
    }
    assert_rel(
        pipe.phi(30.0),
        (-pipe.p * 30f64.powf(pipe.s)).exp(),
        1e-15,
        "φ(30)",
    );
}

// ------------------------------------------------------- H(t) = θ0 ψ(t)

/// s = 1, exponential rise: H = θ0 m e^{−mτk} (e^{−pt} − e^{−mt})/(m − p),
/// written with expm1 so that m ≈ p does not cancel.
fn closed_form_s1(theta0: f64, m: f64, p: f64, tau_k: f64, t: f64) -> f64 {
    theta0 * m * (-m * tau_k).exp() * (-p * t).exp() * -((p - m) * t).exp_m1() / (m - p)
}

#[test]
fn psi_exponential_s1_matches_closed_form() {
    for &m in &[0.05, 0.2, 0.35, 0.8, 2.0] {
        for &p in &[0.005, 0.03, 0.1, 0.34, 0.5] {
            for &tau_k in &[0.0, 0.5, 7.0, 30.0, 200.0] {
                for &t in &[1e-6, 0.01, 0.5, 3.0, 20.0, 60.0, 150.0, 400.0] {
                    let rise = AdiabaticRise::Exponential { theta0: 25.0, m };
                    let h = hydration_under_cooling(&ZhuPipe { p, s: 1.0 }, &rise, tau_k, t);
                    let want = closed_form_s1(25.0, m, p, tau_k, t);
                    if want < 1e-290 {
                        continue;
                    }
                    assert_rel(h, want, 1e-12, &format!("m={m} p={p} τk={tau_k} t={t}"));
                }
            }
        }
    }
}

/// Independent brute force: H in u, split at t/2, each half mapped by
/// u = (t/2) x^12 toward its end (which smooths both u^{b−1} and (t−u)^s),
/// 3000 panels × 8-point Gauss–Legendre per half.
fn brute_force(pipe: &ZhuPipe, rise: &AdiabaticRise, tau_k: f64, t: f64) -> f64 {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let q = 12.0;
    let panels = 3000;
    let half = 0.5 * t;
    let mut sum = 0.0;
    for side in 0..2 {
        for k in 0..panels {
            let x0 = k as f64 / panels as f64;
            let hx = 0.5 / panels as f64;
            for i in 0..4 {
                for sgn in [-1.0, 1.0] {
                    let x = x0 + hx * (1.0 + sgn * X[i]);
                    let d = half * x.powf(q);
                    let jac = half * q * x.powf(q - 1.0);
                    let (u, v) = if side == 0 { (d, t - d) } else { (t - d, d) };
                    sum += W[i] * hx * jac * pipe.phi(v) * rise.rate_exact(tau_k + u);
                }
            }
        }
    }
    sum
}

trait ExactRate {
    fn rate_exact(&self, tau: f64) -> f64;
}

impl ExactRate for AdiabaticRise {
    /// θ′ without the 1e-12 floor of `rate` (the brute force never samples 0).
    fn rate_exact(&self, tau: f64) -> f64 {
        match *self {
            AdiabaticRise::Exponential { theta0, m } => theta0 * m * (-m * tau).exp(),
            AdiabaticRise::Compound { theta0, a, b } => {
                theta0 * a * b * tau.powf(b - 1.0) * (-a * tau.powf(b)).exp()
            }
            AdiabaticRise::Hyperbolic { theta0, n } => theta0 * n / ((n + tau) * (n + tau)),
        }
    }
}

#[test]
fn psi_all_forms_match_brute_force() {
    let rises = [
        EXP,
        COMP,
        HYP,
        AdiabaticRise::Compound {
            theta0: 25.0,
            a: 0.69,
            b: 0.3,
        },
        AdiabaticRise::Compound {
            theta0: 25.0,
            a: 0.05,
            b: 2.2,
        },
        AdiabaticRise::Hyperbolic {
            theta0: 25.0,
            n: 0.6,
        },
    ];
    let mut worst: f64 = 0.0;
    for rise in &rises {
        for &s in &[0.8, 0.93, 1.0, 1.2] {
            for &p in &[0.01, 0.08] {
                for &tau_k in &[0.0, 0.5, 30.0] {
                    for &t in &[0.01, 3.0, 60.0, 400.0] {
                        let pipe = ZhuPipe { p, s };
                        let h = hydration_under_cooling(&pipe, rise, tau_k, t);
                        let want = brute_force(&pipe, rise, tau_k, t);
                        let r = rel(h, want);
                        worst = worst.max(r);
                        assert!(
                            r <= 1e-10,
                            "{rise:?} s={s} p={p} τk={tau_k} t={t}: {h:e} vs {want:e} ({r:e})"
                        );
                    }
                }
            }
        }
    }
    println!("worst relative difference to the brute force: {worst:e}");
}

/// (rise, p, s, τk, t, H) with H from mpmath at 40 digits: tanh-sinh
/// quadrature of θ0 ∫ e^{−y} φ(τ1 − τ(y)) dy over ~500 sub-intervals graded
/// toward both ends (independent of the implementation's panels and
/// substitutions), cross-checked against the u-form ∫ φ(t − u) θ′(τk + u) du.
/// Random parameters: every form, s over [0.8, 1.2], τk from 0 to 200 d.
#[rustfmt::skip]
const MPMATH: [(AdiabaticRise, f64, f64, f64, f64, f64); 24] = [
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.4697885193135555, b: 3.0 }, 0.055544757182321644, 1.0, 0.001, 60.0, 9.5142772141687255856e-1),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.13501807986301737, b: 3.0 }, 0.003349492572708327, 0.9499017968253458, 1e-06, 223.27601910133922, 1.4192911111325135426e1),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.06410950319621553, b: 1.0 }, 0.009601742478321084, 1.1641087712416724, 5.0, 3.0, 3.1227120746489720342),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.12545918036850173, b: 0.42556950669756755 }, 0.0654620607303923, 0.8526314082509044, 0.7, 400.0, 2.5581115622583760082e-1),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.8869800113367072, b: 0.25 }, 0.022196684369075948, 1.0447032338457536, 0.0, 60.0, 5.4915518298233090543),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.10271346088794957, b: 2.0 }, 0.00444623937761196, 0.9066074538600406, 0.0, 400.0, 9.1058037975019869791),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.050523058567851865, b: 1.0 }, 0.006699074325042009, 1.2, 0.0, 20.0, 1.3972753713632708825e1),
    (AdiabaticRise::Compound { theta0: 25.0, a: 0.12062893908574926, b: 2.1728224895634556 }, 0.014958956418861209, 0.8, 0.0, 400.0, 4.1456292053929759749),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.05631938204600312 }, 0.24655029253703847, 1.0, 5.0, 3.0, 2.0511568165527856788),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.13621218734983556 }, 0.03170601667147665, 1.0239727126664049, 0.001, 150.0, 1.6013025649400542584e-1),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.06424038355613963 }, 0.2153522815424375, 0.8710712512793465, 200.0, 0.5, 1.9529405848226844717e-6),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.31905655746508504 }, 0.006700833043700119, 0.8, 5.0, 385.90311245022673, 2.3231438361744404003),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.6057744032484894 }, 0.02264223570967057, 0.9812832418895396, 0.0, 0.5, 6.4933965663188795117),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.2747059054665836 }, 0.3573491348265736, 1.0, 0.0, 150.72110757235606, 8.6712102573842149614e-17),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.10893144114280809 }, 0.6171946558343271, 0.8, 0.0, 20.0, 9.0255344918707455409e-1),
    (AdiabaticRise::Exponential { theta0: 25.0, m: 0.86407851435721 }, 0.024710575364195665, 0.8, 0.0, 400.0, 1.2758938075953118329),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 1.3727343067385587 }, 0.0984824038068133, 1.02561559086774, 30.0, 20.0, 1.5136228489268612716e-1),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 0.6074203969202585 }, 0.0034237472385935876, 1.0, 1e-06, 400.0, 6.4303440756955164761),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 14.94660564168533 }, 0.04427059883121834, 1.2, 1e-06, 3.0, 3.8609507730696904168),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 0.3802216898455316 }, 0.45016709525853177, 1.2, 0.7, 400.0, 1.0894111624487064336e-4),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 2.6710608431129303 }, 0.06428460820942246, 1.0, 0.0, 20.0, 8.1442678474129138768),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 0.5990231051713142 }, 0.38848529204400606, 1.0, 0.0, 400.0, 2.4335704964822414863e-4),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 0.9061300584596644 }, 0.17513668004621558, 0.811900764913033, 0.0, 20.0, 4.1001942204074397728),
    (AdiabaticRise::Hyperbolic { theta0: 25.0, n: 2.418481917357119 }, 0.011003430016636178, 1.2, 0.0, 400.0, 1.8533454297818568542e-2),
];

#[test]
fn psi_matches_mpmath_references() {
    for (rise, p, s, tau_k, t, want) in MPMATH {
        let h = hydration_under_cooling(&ZhuPipe { p, s }, &rise, tau_k, t);
        assert_rel(
            h,
            want,
            1e-12,
            &format!("{rise:?} p={p} s={s} τk={tau_k} t={t}"),
        );
    }
}

#[test]
fn psi_edge_cases() {
    let pipe = ZhuPipe { p: 0.05, s: 0.95 };
    for rise in [&EXP, &COMP, &HYP] {
        assert_eq!(hydration_under_cooling(&pipe, rise, 3.0, 0.0), 0.0);
        assert_eq!(hydration_under_cooling(&pipe, rise, 3.0, -1.0), 0.0);
        // A stage that starts before the pour only sees the rise after it.
        assert_rel(
            hydration_under_cooling(&pipe, rise, -2.0, 10.0),
            hydration_under_cooling(&pipe, rise, 0.0, 8.0),
            1e-15,
            "τk < 0",
        );
        assert_eq!(hydration_under_cooling(&pipe, rise, -20.0, 10.0), 0.0);
        // No cooling: all of the rise stays.
        let none = ZhuPipe { p: 0.0, s: 1.0 };
        for &(tau_k, t) in &[(0.0, 0.3), (0.0, 400.0), (12.0, 40.0)] {
            assert_rel(
                hydration_under_cooling(&none, rise, tau_k, t),
                rise.theta(tau_k + t) - rise.theta(tau_k),
                1e-13,
                "p = 0",
            );
        }
        // 0 ≤ H ≤ θ(τk + t) − θ(τk), increasing with pipe-free heat.
        for &t in &[0.5, 5.0, 50.0, 400.0] {
            let h = hydration_under_cooling(&pipe, rise, 1.0, t);
            assert!(h > 0.0 && h < rise.theta(1.0 + t) - rise.theta(1.0));
        }
        assert!(hydration_under_cooling(&pipe, rise, 1.0, f64::NAN).is_nan());
        assert!(hydration_under_cooling(&pipe, rise, f64::NAN, 1.0).is_nan());
        assert!(hydration_under_cooling(&ZhuPipe { p: -1.0, s: 1.0 }, rise, 0.0, 1.0).is_nan());
        assert!(hydration_under_cooling(&ZhuPipe { p: 0.1, s: 0.0 }, rise, 0.0, 1.0).is_nan());
    }
    let bad = AdiabaticRise::Exponential {
        theta0: 25.0,
        m: -1.0,
    };
    assert!(hydration_under_cooling(&pipe, &bad, 0.0, 1.0).is_nan());
}

#[test]
fn psi_survives_extreme_inputs() {
    // Outside the verified range: finite and within the physical bounds,
    // never a panic.
    for &(p, s) in &[
        (1e-9, 1.0),
        (50.0, 1.0),
        (0.05, 0.3),
        (0.05, 2.5),
        (5.0, 0.5),
    ] {
        for rise in [&EXP, &COMP, &HYP] {
            for &(tau_k, t) in &[
                (0.0, 1e-12),
                (0.0, 1e6),
                (1e6, 1.0),
                (1e-9, 1e4),
                (3.0, 1e-9),
            ] {
                let h = hydration_under_cooling(&ZhuPipe { p, s }, rise, tau_k, t);
                let top = rise.theta(tau_k + t) - rise.theta(tau_k);
                assert!(
                    h.is_finite() && h >= 0.0 && h <= top + 1e-14 * rise.theta0(),
                    "p={p} s={s} {rise:?} τk={tau_k} t={t}: {h:e} (top {top:e})"
                );
            }
        }
    }
}

/// `cargo test --release --test material_laws -- --ignored --nocapture`
#[test]
#[ignore]
fn timing_of_hydration_under_cooling() {
    let pipes = [
        ZhuPipe { p: 0.02, s: 0.85 },
        ZhuPipe { p: 0.052, s: 1.018 },
        ZhuPipe { p: 0.2, s: 1.15 },
    ];
    let rises = [EXP, COMP, HYP];
    for rise in &rises {
        for pipe in &pipes {
            for &tau_k in &[0.0, 30.0] {
                let n = 20_000;
                let start = std::time::Instant::now();
                let mut acc = 0.0;
                for i in 0..n {
                    let t = 400.0 * (i as f64 + 0.5) / n as f64;
                    acc += hydration_under_cooling(pipe, rise, tau_k, t);
                }
                let us = start.elapsed().as_secs_f64() / n as f64 * 1e6;
                std::hint::black_box(acc);
                println!(
                    "{rise:?} p={} s={} τk={tau_k}: {us:.2} µs/call",
                    pipe.p, pipe.s
                );
            }
        }
    }
}
