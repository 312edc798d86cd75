//! Staged mechanics against closed forms.

use crate::common;

use common::*;
use groutready::material::AdiabaticRise;
use groutready::mechanics::{MechanicsModel, MechanicsSettings};
use groutready::thermal::boundary::AirTemperature;
use groutready::thermal::{ThermalModel, ThermalSettings};

const MECH: &str =
    "modulus = { e0_pa = 3.0e10, a = 0.40, b = 0.34 }\npoisson = 0.2\nexpansion_per_c = 1.0e-5\n";

fn mech_scene(effects: &str, geometry: &str, extra: &str) -> groutready::scene::Scene {
    scene_with_concrete(effects, geometry, extra, MECH)
}

#[test]
fn newborn_lifts_placed_warm_are_stress_free_while_nothing_moves() {
    let extra =
        "[air]\nmean_c = 27.0\namplitude_c = 0.0\nwarmest_day_of_year = 200.0\nfilm_w_m2k = 10.0\n";
    let sc = mech_scene(
        "\"ambient\", \"thermal_strain\"",
        &blocks_geometry(1, 6.0, 4.0, 3, 2, 2),
        extra,
    );
    let mesh = blocks_mesh(&sc);
    let air = AirTemperature::new(sc.epoch, sc.air.clone().unwrap(), None);
    let thermal = ThermalSettings::from_scene(&sc);
    let mut th = ThermalModel::new(&mesh, &thermal, vec![], Some(air), None).unwrap();
    // Fully restrained: any spurious thermal strain would show as stress.
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &rollers(&mesh, true, true, true)).unwrap();
    let mut t = 0.0;
    for lift in 1..=3 {
        th.pour(1, lift, t, 27.0);
        m.pour(1, lift, t);
        for _ in 0..4 {
            let before = th.state.temperature.clone();
            th.step(t, t + 1.0).unwrap();
            m.step(t, t + 1.0, Some((&before, &th.state.temperature)), None)
                .unwrap();
            t += 1.0;
        }
    }
    let worst = m
        .state
        .stress
        .iter()
        .flatten()
        .flatten()
        .map(|s| s.abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-6,
        "a stress of {worst} Pa in concrete placed at the ambient temperature"
    );
    assert!(m.state.u.iter().all(|u| u.abs() < 1e-15));
}

#[test]
fn self_weight_of_a_column_poured_lift_by_lift_is_statically_exact() {
    let sc = mech_scene(
        "\"self_weight\"",
        &blocks_geometry(1, 6.0, 4.0, 5, 2, 2),
        "",
    );
    let mesh = blocks_mesh(&sc);
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &rollers(&mesh, true, true, false)).unwrap();
    let mut t = 0.0;
    for lift in 1..=5 {
        m.pour(1, lift, t);
        for _ in 0..3 {
            m.step(t, t + 2.0, None, None).unwrap();
            t += 2.0;
        }
    }
    let top = mesh.nodes.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    let rho_g = sc.concrete.density_kg_m3 * 9.81;
    let mut worst: f64 = 0.0;
    for (e, s) in m.state.stress.iter().enumerate() {
        let zc = (0..8)
            .map(|k| mesh.nodes[mesh.elements[e][k] as usize][2])
            .sum::<f64>()
            / 8.0;
        let mean_szz = s.iter().map(|g| g[2]).sum::<f64>() / 8.0;
        let exact = -rho_g * (top - zc);
        worst = worst.max((mean_szz - exact).abs() / (rho_g * top));
    }
    eprintln!(
        "column: worst relative σzz error {worst:.2e}, equilibrium {:.2e}",
        m.equilibrium_residual()
    );
    assert!(worst < 1e-10, "σzz off by {worst:.2e} relative");
    assert!(m.equilibrium_residual() < 1e-10);
}

/// One block of one lift, 6 × 4 m, heated by hydration (θ0 = 25 °C,
/// m = 0.35 a day) with its thermal strain, and that adiabatic rise.
fn hydrating_block() -> (groutready::scene::Scene, AdiabaticRise) {
    let mut sc = mech_scene(
        "\"hydration\", \"thermal_strain\"",
        &blocks_geometry(1, 6.0, 4.0, 1, 2, 2),
        "",
    );
    let rise = AdiabaticRise::Exponential {
        theta0: 25.0,
        m: 0.35,
    };
    sc.concrete.adiabatic = Some(rise.clone());
    (sc, rise)
}

/// Restrained block heated by hydration with an ageing modulus:
/// σ = −α/(1−2ν) ∫ E(τ) dθ(τ); the staged driver integrates with E at
/// mid-step ages (second order).
fn restrained_hydration_stress(dt: f64, days: f64, b_exponent: f64) -> (f64, f64) {
    let (mut sc, rise) = hydrating_block();
    if let Some(m) = sc.concrete.modulus.as_mut() {
        m.b = b_exponent;
    }
    let mesh = blocks_mesh(&sc);
    let thermal = ThermalSettings::from_scene(&sc);
    let mut th = ThermalModel::new(&mesh, &thermal, vec![], None, None).unwrap();
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &rollers(&mesh, true, true, true)).unwrap();
    th.pour(1, 1, 0.0, 15.0);
    m.pour(1, 1, 0.0);
    let n = (days / dt).round() as usize;
    for k in 0..n {
        let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
        let before = th.state.temperature.clone();
        th.step(t0, t1).unwrap();
        m.step(t0, t1, Some((&before, &th.state.temperature)), None)
            .unwrap();
    }
    let modulus = sc.concrete.modulus.unwrap();
    let (alpha, nu) = (1.0e-5, 0.2);
    // ∫_0^T E(τ) θ'(τ) dτ by composite Gauss–Legendre on a graded grid (E has τ^b, b<1).
    let gl = groutready::fem::gauss_legendre(20);
    let mut integral = 0.0;
    let mut lo = 0.0;
    for j in 0..60 {
        let hi = days * ((j + 1) as f64 / 60.0).powi(4);
        for (x, w) in gl.iter() {
            let tau = lo + (hi - lo) * 0.5 * (x[0] + 1.0);
            integral += 0.5 * (hi - lo) * w * modulus.modulus(tau) * rise.rate(tau);
        }
        lo = hi;
    }
    let exact = -alpha / (1.0 - 2.0 * nu) * integral;
    let s = &m.state.stress;
    let mut worst_dev: f64 = 0.0;
    for e in s {
        for g in e {
            for k in 0..3 {
                worst_dev = worst_dev.max((g[k] - e[0][0]).abs());
            }
            for k in 3..6 {
                worst_dev = worst_dev.max(g[k].abs());
            }
        }
    }
    assert!(
        worst_dev < 1e-6 * exact.abs(),
        "stress not uniform and hydrostatic: {worst_dev}"
    );
    (s[0][0][0], exact)
}

/// Fitted rate of the restrained-hydration stress against the exact integral.
fn restrained_rate(b_exponent: f64) -> (f64, Vec<f64>, f64) {
    let dts = [1.0, 0.5, 0.25, 0.125];
    let mut errs = vec![];
    let mut exact = 0.0;
    for &dt in &dts {
        let (got, ex) = restrained_hydration_stress(dt, 10.0, b_exponent);
        exact = ex;
        errs.push((got - ex).abs() / ex.abs());
    }
    let slope = fitted_slope(&dts, &errs);
    eprintln!("restrained hydration, modulus exponent b = {b_exponent}: σ = {exact:.6e} Pa, errors {errs:?}, slope {slope:.3}");
    (slope, errs, exact)
}

#[test]
fn restrained_block_under_hydration_converges_at_second_order_for_a_smooth_modulus() {
    let (slope, errs, exact) = restrained_rate(1.0);
    assert!(
        (slope - 2.0).abs() < 0.15,
        "rate {slope:.3}, errors {errs:?}"
    );
    assert!(errs[3] < 1e-3, "finest error {}", errs[3]);
    assert!(
        exact < -5.0e6,
        "a restrained block heated by hydration is compressed: {exact}"
    );
}

/// E(τ) = E0(1 − e^{−aτ^b}) with the usual b ≈ 0.34 grows like τ^b at birth:
/// the mid-step modulus then integrates the first step to O(Δt^{1+b}), and
/// that sets the global rate. Measured, not assumed: 1 + b.
#[test]
fn with_the_usual_modulus_exponent_the_rate_is_one_plus_b() {
    let b = 0.34;
    let (slope, errs, _) = restrained_rate(b);
    assert!(
        (slope - (1.0 + b)).abs() < 0.1,
        "rate {slope:.3}, errors {errs:?}"
    );
}

/// A mechanical step spanning several days (`time.mechanics_max_step_days`
/// above 1) strains the concrete by each day's change of temperature at
/// that day's modulus, E(τ_k)/E(τ̄) α ΔT_k: a restrained block heated by
/// hydration (no creep) takes in one 3-day step, given the temperatures at
/// the midnights inside it, the stress of three daily steps, Σ E(τ_k) α
/// ΔT_k/(1 − 2ν), to round-off. From its ends alone, α (T₃ − T₀) at the one
/// mid-step modulus, it takes 10 % more compression: the first day's heat,
/// most of the rise, counted at the stiffness of a day and a half.
#[test]
fn a_longer_step_strains_each_days_heat_at_that_days_modulus() {
    use groutready::mechanics::StepTemperatures;
    let (sc, _) = hydrating_block();
    let mesh = blocks_mesh(&sc);
    let mut th =
        ThermalModel::new(&mesh, &ThermalSettings::from_scene(&sc), vec![], None, None).unwrap();
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let supports = rollers(&mesh, true, true, true);
    let model = || {
        let mut m = MechanicsModel::new(&mesh, &mechanics, &supports).unwrap();
        m.pour(1, 1, 0.0);
        m
    };
    th.pour(1, 1, 0.0, 15.0);
    let mut temps = vec![th.state.temperature.clone()];
    for day in 0..3 {
        th.step(f64::from(day), f64::from(day + 1)).unwrap();
        temps.push(th.state.temperature.clone());
    }
    let mut daily = model();
    for day in 0..3 {
        let (t0, t1) = (f64::from(day), f64::from(day + 1));
        let pair = (
            temps[day as usize].as_slice(),
            temps[day as usize + 1].as_slice(),
        );
        daily.step(t0, t1, Some(pair), None).unwrap();
    }
    let inside = vec![(1.0, temps[1].clone()), (2.0, temps[2].clone())];
    let mut through = model();
    let step = StepTemperatures {
        start: &temps[0],
        inside: &inside,
        end: &temps[3],
    };
    through.step_through(0.0, 3.0, Some(step), None).unwrap();
    let mut ends = model();
    ends.step(0.0, 3.0, Some((&temps[0], &temps[3])), None)
        .unwrap();
    let sigma = |m: &MechanicsModel| m.state.stress[0][0][0];
    let (d, t, e) = (sigma(&daily), sigma(&through), sigma(&ends));
    eprintln!("restrained block, 3 days of hydration: daily steps {d:.6e} Pa, one step through the days {t:.6e} Pa, from its ends {e:.6e} Pa");
    assert!(d < -1e6, "compressed: {d}");
    assert!((t - d).abs() <= 1e-10 * d.abs(), "{t} against {d}");
    assert!(e < d && (e - d).abs() > 0.05 * d.abs(), "{e} against {d}");
}

/// A scene built in code without a value the mechanics needs is an error
/// that names the key, never a panic (validation refuses it from a file).
#[test]
fn mechanics_settings_name_a_missing_value() {
    let mut sc = mech_scene(
        "\"self_weight\"",
        &blocks_geometry(1, 6.0, 4.0, 3, 2, 2),
        "",
    );
    assert!(MechanicsSettings::from_scene(&sc).is_ok());
    sc.concrete.poisson = None;
    let e = MechanicsSettings::from_scene(&sc).unwrap_err();
    assert_eq!(e.key, "concrete.poisson");
    assert_eq!(
        e.to_string(),
        "concrete.poisson is missing: the mechanical effects need it"
    );
}

/// The stresses and the largest displacement error of a free column (one
/// block, 2 × 2 elements, 4 lifts of 3 m) heated by g·y across its
/// thickness, on the element `element`: supported by rollers on its base
/// and on its x = 0 face and at one base node along y (a support set that
/// lets it curl freely).
fn curled_column(element: &str) -> (f64, f64, f64) {
    let sc = mech_scene(
        "\"thermal_strain\"",
        &blocks_geometry(1, 4.0, 2.0, 4, 2, 2),
        &format!("[solver]\nelement = \"{element}\"\n"),
    );
    let mesh = blocks_mesh(&sc);
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut fixed = vec![];
    for (i, p) in mesh.nodes.iter().enumerate() {
        if p[2].abs() < 1e-9 {
            fixed.push((i as u32, 2u8));
        }
        if p[0].abs() < 1e-9 {
            fixed.push((i as u32, 0u8));
        }
        if p.iter().all(|v| v.abs() < 1e-9) {
            fixed.push((i as u32, 1u8));
        }
    }
    let supports = groutready::mechanics::Supports { fixed };
    let mut m = MechanicsModel::new(&mesh, &mechanics, &supports).unwrap();
    for lift in 1..=4 {
        m.pour(1, lift, 0.0);
    }
    let g = 5.0; // °C per m across the thickness
    let before = vec![20.0; mesh.n_thermal_dofs];
    let mut after = before.clone();
    for (i, p) in mesh.nodes.iter().enumerate() {
        after[mesh.thermal_dof[i] as usize] = 20.0 + g * p[1];
    }
    m.step(0.0, 1.0, Some((&before, &after)), None).unwrap();
    let ag = 1.0e-5 * g;
    let mut u_err: f64 = 0.0;
    for (i, p) in mesh.nodes.iter().enumerate() {
        let [x, y, z] = *p;
        let exact = [ag * x * y, 0.5 * ag * (y * y - x * x - z * z), ag * y * z];
        for d in 0..3 {
            u_err = u_err.max((m.state.u[3 * i + d] - exact[d]).abs());
        }
    }
    let sigma = m
        .state
        .stress
        .iter()
        .flatten()
        .flatten()
        .fold(0.0f64, |a, s| a.max(s.abs()));
    // nothing loads the column: the residual's own scale is round-off
    // (`equilibrium_residual_parts`), so it is taken in newtons
    (sigma, u_err, m.equilibrium_residual_parts().0)
}

/// A linear temperature across a free column curls it without stress:
/// u = αg(xy, (y² − x² − z²)/2, yz). The field is quadratic: the plain
/// hex8 cannot follow it and stresses itself (MPa), the incompatible modes
/// follow it exactly — which also checks that their amplitudes are
/// recovered right when the step's strains are committed.
#[test]
fn a_linear_temperature_curls_a_free_column_without_stress_on_incompatible_hex8() {
    let (sigma, u_err, residual) = curled_column("hex8_incompatible");
    let (plain_sigma, plain_err, _) = curled_column("hex8");
    // the tip moves αg·z²/2 = 3.6 mm; the stress scale is E·α·g·t ~ 3 MPa
    eprintln!(
        "curled column: incompatible |σ| ≤ {sigma:.2e} Pa, |u − exact| ≤ {u_err:.2e} m, \
         equilibrium residual {residual:.1e} N; plain hex8 |σ| ≤ {plain_sigma:.2e} Pa, {plain_err:.2e} m"
    );
    assert!(sigma < 1e-3, "stress {sigma} Pa");
    assert!(u_err < 1e-12, "displacement off by {u_err} m");
    // against forces of E·α·g·t² ≈ 6 MN per metre of column
    assert!(residual < 1e-3, "equilibrium residual {residual} N");
    assert!(
        plain_sigma > 1e5,
        "the plain hex8 should stress itself: {plain_sigma} Pa"
    );
    assert!(plain_err > 1e-5, "{plain_err}");
}
