//! Two blocks between fixed end walls on a frictionless base (DESIGN.md §7),
//! through the full path: hex8 mechanics, joint contact points, condensed
//! contact solve.

use crate::common;

use common::*;
use groutready::mechanics::joints::PointState;
use groutready::mechanics::{MechanicsModel, MechanicsSettings};
use groutready::mesh::Mesh;

const E: f64 = 3.0e10;
const ALPHA: f64 = 1.0e-5;
const L_BLOCK: f64 = 10.0;

/// Modulus that is E at any positive age (a = 1e6), no creep.
const MECH: &str =
    "modulus = { e0_pa = 3.0e10, a = 1.0e6, b = 1.0 }\npoisson = 0.2\nexpansion_per_c = 1.0e-5\n";

/// Both blocks poured on day 0 at 20 °C, then a uniform ΔT in one day.
fn run(delta_t: f64, gap0: f64) -> (MechanicsModel, Mesh) {
    let text_geometry = blocks_geometry(2, L_BLOCK, 5.0, 1, 2, 2);
    let mut sc = scene_with_concrete("\"thermal_strain\", \"joints\"", &text_geometry, "", MECH);
    set_joints(
        &mut sc,
        &format!(
            "zone_height_m = 3.0\nmu_static = 0.0\nmu_kinetic = 0.0\ninitial_gap_m = {gap0}\n"
        ),
    );
    let mesh = blocks_mesh(&sc);
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &walls_frictionless_base(&mesh)).unwrap();
    m.pour(1, 1, 0.0);
    m.pour(2, 1, 0.0);
    let t0 = vec![20.0; mesh.n_thermal_dofs];
    let t1 = vec![20.0 + delta_t; mesh.n_thermal_dofs];
    m.step(0.0, 1.0, Some((&t0, &t0)), None).unwrap();
    m.step(1.0, 2.0, Some((&t0, &t1)), None).unwrap();
    (m, mesh)
}

#[test]
fn cooled_blocks_open_the_joint_by_their_free_contraction_without_stress() {
    let (m, mesh) = run(-10.0, 0.0);
    let expected = -ALPHA * -10.0 * (2.0 * L_BLOCK);
    assert!(!m.points().is_empty());
    for st in &m.state.joints {
        assert_eq!(st.state, PointState::Open);
        assert!(
            (st.gap - expected).abs() < 1e-9 * expected,
            "gap {} vs {expected}",
            st.gap
        );
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
        worst < 1e-6 * E * ALPHA * 10.0,
        "stress {worst} Pa in freely contracting blocks"
    );
    eprintln!(
        "cooled: aperture {:.6} mm, largest stress {worst:.2e} Pa",
        1e3 * m.state.joints[0].gap
    );
    for r in zone_readings(&m, &mesh) {
        assert_eq!(r.pressure, 0.0, "an open joint carries no pressure");
        assert!((r.aperture - expected).abs() < 1e-9 * expected);
    }
}

#[test]
fn heated_past_closure_the_blocks_press_with_the_closed_form_stress() {
    let g0 = 0.5e-3;
    let (m, mesh) = run(10.0, g0);
    let l = 2.0 * L_BLOCK;
    let expected = -E * (ALPHA * 10.0 * l - g0) / l;
    let mut worst: f64 = 0.0;
    for e in &m.state.stress {
        for g in e {
            worst = worst.max((g[0] - expected).abs() / expected.abs());
            assert!(
                g[1].abs() < 1e-6 * expected.abs() && g[2].abs() < 1e-6 * expected.abs(),
                "{g:?}"
            );
        }
    }
    for st in &m.state.joints {
        assert!(st.state != PointState::Open, "{st:?}");
        assert!(st.gap.abs() < 1e-9 * g0, "gap {}", st.gap);
    }
    eprintln!(
        "heated: σxx {expected:.6e} Pa, worst relative error {worst:.2e}, equilibrium {:.2e}",
        m.equilibrium_residual()
    );
    assert!(worst < 1e-6, "σxx off by {worst:.2e}");
    assert!(m.equilibrium_residual() < 1e-8);
    // What a pressure cell in the joint reads (apertures.csv's
    // pressure_mpa): −σxx, at every zone point.
    for r in zone_readings(&m, &mesh) {
        assert!(
            (r.pressure + expected).abs() < 1e-6 * expected.abs(),
            "joint pressure {} against σxx {expected}",
            r.pressure
        );
    }
}

/// The joint read at each grouting-zone point of the mesh.
fn zone_readings(m: &MechanicsModel, mesh: &Mesh) -> Vec<groutready::mechanics::JointReading> {
    assert!(!mesh.zone_points.is_empty());
    mesh.zone_points
        .iter()
        .map(|zp| m.point_aperture(mesh, zp).expect("both blocks exist"))
        .collect()
}

#[test]
fn heated_short_of_closure_the_joint_stays_open() {
    let g0 = 3.0e-3; // αΔT·L = 2 mm < 3 mm
    let (m, _) = run(10.0, g0);
    for st in &m.state.joints {
        assert_eq!(st.state, PointState::Open);
        assert!((st.gap - (g0 - 2.0e-3)).abs() < 1e-9, "gap {}", st.gap);
    }
}
