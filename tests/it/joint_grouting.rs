//! The grouting switch and the life of a grouted joint (DESIGN.md §4, §7),
//! through the full path (hex8 mechanics, joint pairs, contact solve), on two
//! blocks between fixed end walls on a frictionless base:
//! - grouted with a joint of normal stiffness k_n per unit area and heated:
//!   σ = −αΔT·L/(L/E + 1/k_n);
//! - cooled after grouting: tension below the bond strength keeps the layer,
//!   σ = +α|ΔT|·L/(L/E + 1/k_n); above it the layer cracks, the zone is
//!   `reopened` and the blocks contract freely: opening = α|ΔT|·L, σ = 0;
//! - seasonal temperature cycles open and close an ungrouted joint every
//!   year: every step settles in one or two passes, apertures and stresses
//!   follow the closed forms, and the same scene in mm/MPa units gives the
//!   same apertures.
//!
//! Both contact solvers (active set and the condensed cone program) run the
//! grouting cases.

use crate::common;

use common::*;
use groutready::mechanics::joints::PointState;
use groutready::mechanics::{MechanicsModel, MechanicsSettings};
use groutready::mesh::Mesh;
use groutready::scene::{ContactSolverKind, Scene};

const E: f64 = 3.0e10;
const ALPHA: f64 = 1.0e-5;
const L_BLOCK: f64 = 10.0;
const L: f64 = 2.0 * L_BLOCK;
const E_GROUT: f64 = 2.0e10;
const T_GROUT: f64 = 0.5e-3;

const MECH: &str =
    "modulus = { e0_pa = 3.0e10, a = 1.0e6, b = 1.0 }\npoisson = 0.2\nexpansion_per_c = 1.0e-5\n";

fn two_blocks(mu: f64, gap0: f64, contact: ContactSolverKind) -> (Scene, Mesh) {
    let geometry = blocks_geometry(2, L_BLOCK, 5.0, 1, 2, 2);
    let mut sc = scene_with_concrete("\"thermal_strain\", \"joints\"", &geometry, "", MECH);
    let joints = format!(
        "[joints]\nzone_height_m = 3.0\nmu_static = {mu}\nmu_kinetic = {mu}\ninitial_gap_m = {gap0}\n\
         grout_modulus_pa = {E_GROUT}\ngrout_shear_modulus_pa = 8.0e9\ngrout_min_thickness_m = {T_GROUT}\n\
         bond_strength_pa = 1.0e6\n"
    );
    let j: toml::Table = toml::from_str(&joints).unwrap();
    sc.joints = j["joints"].clone().try_into().unwrap();
    sc.solver.contact = contact;
    let mesh = blocks_mesh(&sc);
    (sc, mesh)
}

/// Pours both blocks on day 0 at 20 °C and grouts the (closed) joint on day 1.
fn grouted(contact: ContactSolverKind) -> (MechanicsModel, Mesh) {
    let (sc, mesh) = two_blocks(0.0, 0.0, contact);
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &walls_frictionless_base(&mesh)).unwrap();
    m.pour(1, 1, 0.0);
    m.pour(2, 1, 0.0);
    let t = vec![20.0; mesh.n_thermal_dofs];
    m.step(0.0, 1.0, Some((&t, &t)), None).unwrap();
    let (joint, zone) = (m.points()[0].joint, m.points()[0].zone);
    let n = m.grout(joint, zone, 1.0);
    assert_eq!(
        n,
        m.points().len(),
        "every point of the one zone is grouted"
    );
    (m, mesh)
}

fn uniform_step(m: &mut MechanicsModel, mesh: &Mesh, day: f64, from: f64, to: f64) {
    let t0 = vec![from; mesh.n_thermal_dofs];
    let t1 = vec![to; mesh.n_thermal_dofs];
    m.step(day, day + 1.0, Some((&t0, &t1)), None).unwrap();
}

fn sigma_xx_range(m: &MechanicsModel) -> (f64, f64) {
    m.state
        .stress
        .iter()
        .flatten()
        .map(|g| g[0])
        .fold((f64::MAX, f64::MIN), |(lo, hi), s| (lo.min(s), hi.max(s)))
}

/// σ of the grouted bar: the grout layer (k_n = E_g/t per unit area) in
/// series with the concrete.
fn grouted_sigma(delta_t: f64) -> f64 {
    let k_n = E_GROUT / T_GROUT;
    -ALPHA * delta_t * L / (L / E + 1.0 / k_n)
}

const SOLVERS: [ContactSolverKind; 2] = [ContactSolverKind::ActiveSet, ContactSolverKind::Qp];

#[test]
fn grouted_joint_heated_carries_the_series_spring_stress() {
    for contact in SOLVERS {
        let (mut m, mesh) = grouted(contact);
        uniform_step(&mut m, &mesh, 1.0, 20.0, 30.0);
        let expected = grouted_sigma(10.0);
        let (lo, hi) = sigma_xx_range(&m);
        let err = (lo - expected).abs().max((hi - expected).abs()) / expected.abs();
        eprintln!("{contact:?}: grouted + heated 10 °C: σxx {expected:.6e} Pa (rigid joint {:.6e}), error {err:.2e}", -E * ALPHA * 10.0);
        assert!(
            err < 1e-9,
            "{contact:?}: σxx in [{lo}, {hi}], expected {expected}"
        );
        assert!(m
            .state
            .joints
            .iter()
            .all(|s| s.state == PointState::Grouted));
        assert!(m.equilibrium_residual() < 1e-8);
    }
}

#[test]
fn grouted_joint_cooled_below_the_bond_strength_holds_in_tension() {
    for contact in SOLVERS {
        let (mut m, mesh) = grouted(contact);
        uniform_step(&mut m, &mesh, 1.0, 20.0, 17.0);
        let expected = grouted_sigma(-3.0);
        assert!(expected > 0.0 && expected < 1.0e6);
        let (lo, hi) = sigma_xx_range(&m);
        let err = (lo - expected).abs().max((hi - expected).abs()) / expected;
        eprintln!("{contact:?}: grouted + cooled 3 °C: σxx {expected:.6e} Pa < bond 1 MPa, error {err:.2e}");
        assert!(
            err < 1e-9,
            "{contact:?}: σxx in [{lo}, {hi}], expected {expected}"
        );
        for st in &m.state.joints {
            assert_eq!(st.label(), groutready::vocab::JointState::Grouted);
        }
    }
}

#[test]
fn grouted_joint_cooled_beyond_the_bond_strength_cracks_and_reopens() {
    for contact in SOLVERS {
        let (mut m, mesh) = grouted(contact);
        uniform_step(&mut m, &mesh, 1.0, 20.0, 10.0);
        let expected = ALPHA * 10.0 * L;
        for st in &m.state.joints {
            assert_eq!(
                st.label(),
                groutready::vocab::JointState::Reopened,
                "{contact:?}: {st:?}"
            );
            assert_eq!(st.state, PointState::Open);
            assert!(
                (st.aperture() - expected).abs() < 1e-9 * expected,
                "{contact:?}: aperture {} vs free contraction {expected}",
                st.aperture()
            );
        }
        let (lo, hi) = sigma_xx_range(&m);
        let worst = lo.abs().max(hi.abs());
        eprintln!("{contact:?}: grouted + cooled 10 °C: cracked, aperture {:.6} mm, largest |σxx| {worst:.2e} Pa", 1e3 * m.state.joints[0].aperture());
        // Nothing is loaded after cracking, so the stresses themselves are the
        // equilibrium check (a relative residual would divide round-off by round-off).
        assert!(
            worst < 1e-6 * E * ALPHA * 10.0,
            "{contact:?}: stress {worst} after cracking"
        );
    }
}

/// Two years of monthly steps with a ±8 °C seasonal swing about the
/// casting temperature; joint cast with a 0.1 mm gap, friction 0.6.
/// Returns the apertures per step [length unit of the scene].
fn seasons(scale_len: f64, scale_stress: f64) -> (Vec<f64>, usize, Vec<usize>) {
    let (mut sc, mut mesh) = two_blocks(0.6, 0.1e-3, ContactSolverKind::ActiveSet);
    for p in mesh.nodes.iter_mut() {
        for c in p.iter_mut() {
            *c *= scale_len;
        }
    }
    let law = sc.concrete.modulus.as_mut().unwrap();
    law.e0_pa *= scale_stress;
    sc.joints.initial_gap_m *= scale_len;
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &walls_frictionless_base(&mesh)).unwrap();
    m.pour(1, 1, 0.0);
    m.pour(2, 1, 0.0);
    let temp = |k: usize| 20.0 + 8.0 * (2.0 * std::f64::consts::PI * k as f64 / 12.0).sin();
    let mut apertures = vec![];
    let mut passes = vec![];
    let mut switches = 0;
    let mut last = None;
    for k in 0..24 {
        let before = m.stats.contact_iterations;
        uniform_step(&mut m, &mesh, k as f64, temp(k), temp(k + 1));
        passes.push(m.stats.contact_iterations - before);
        let st = m.state.joints[0].state;
        if last.is_some_and(|l| l != st) {
            switches += 1;
        }
        last = Some(st);
        apertures.push(m.state.joints[0].aperture());
        // Closed forms: free contraction opens the gap; past closure the bar
        // presses with σ = −E(αΔT·L − g0)/L.
        let dt = temp(k + 1) - 20.0;
        let g0 = 0.1e-3;
        let open = g0 - ALPHA * dt * L;
        for st in &m.state.joints {
            let g = st.aperture() / scale_len;
            assert!(
                (g - open.max(0.0)).abs() < 1e-9 * g0,
                "step {k}: gap {g} vs {open}"
            );
        }
        let sigma = -E * (ALPHA * dt * L - g0).max(0.0) / L;
        let (lo, hi) = sigma_xx_range(&m);
        let tol = 1e-6 * E * ALPHA * 8.0;
        assert!(
            (lo / scale_stress - sigma).abs() < tol && (hi / scale_stress - sigma).abs() < tol,
            "step {k}: σxx [{lo}, {hi}] vs {sigma}"
        );
    }
    (apertures, switches, passes)
}

#[test]
fn seasonal_cycles_open_and_close_without_chattering_in_any_units() {
    let (si, switches, passes) = seasons(1.0, 1.0);
    eprintln!("seasons: {switches} open/closed switches in 24 months, passes per step {passes:?}");
    assert!(switches >= 3, "the joint must open and close every year");
    assert!(passes.iter().all(|&p| p <= 3), "passes per step {passes:?}");
    let (mm, _, _) = seasons(1e3, 1e-6);
    let worst = si
        .iter()
        .zip(&mm)
        .map(|(a, b)| (1e3 * a - b).abs() / (1e3 * 0.1e-3))
        .fold(0.0, f64::max);
    eprintln!("seasons: m/Pa vs mm/MPa apertures differ by {worst:.2e} of the initial gap");
    assert!(worst < 1e-9);
}
