//! The deciding aperture inside the grout stops (`mechanics::grout_stops`):
//! two blocks opened by a prescribed separation linear across the
//! thickness, g(y) = g0 + g1·y (y from the upstream face), whose zone
//! minimum is the closed form g0 + g1·inset on any mesh across.
//!
//! Each block is moved rigidly by its end wall (a rotation about z and a
//! translation, exact in the hex8 space), so the blocks stay stress-free,
//! the joint open, and the aperture field is exactly g(y).

use std::collections::BTreeMap;

use crate::common::*;
use groutready::mechanics::grout_stops::node_rows;
use groutready::mechanics::{MechanicsModel, MechanicsSettings, Supports};
use groutready::mesh::Mesh;
use groutready::vocab::JointState;

const L_BLOCK: f64 = 10.0;
const THICKNESS: f64 = 6.0;
/// separation at the upstream face [m] and its slope across [m/m]
const G0: f64 = 0.1e-3;
const G1: f64 = 0.2e-3;

/// Walls at both ends held in x and y, a frictionless base.
fn walls(mesh: &Mesh) -> Supports {
    let mut fixed = vec![];
    for (i, p) in mesh.nodes.iter().enumerate() {
        if p[0].abs() < 1e-9 || (p[0] - 2.0 * L_BLOCK).abs() < 1e-9 {
            fixed.extend([(i as u32, 0), (i as u32, 1)]);
        }
        if p[2].abs() < 1e-9 {
            fixed.push((i as u32, 2));
        }
    }
    Supports { fixed }
}

/// The two-block joint with `across` elements across, opened by g(y), and
/// the minimum of each of its zones: (aperture [m], state).
fn opened(across: u32, inset: Option<f64>) -> Vec<(f64, JointState)> {
    let geometry = blocks_geometry(2, L_BLOCK, THICKNESS, 2, 2, across);
    let mech = "modulus = { e0_pa = 3.0e10, a = 1.0e6, b = 1.0 }\npoisson = 0.2\n\
                expansion_per_c = 1.0e-5\n";
    let mut sc = scene_with_concrete("\"thermal_strain\", \"joints\"", &geometry, "", mech);
    let stops = inset.map_or(String::new(), |d| format!("grout_stop_inset_m = {d}\n"));
    set_joints(
        &mut sc,
        &format!("zone_height_m = 3.0\nmu_static = 0.0\nmu_kinetic = 0.0\n{stops}"),
    );
    let mesh = blocks_mesh(&sc);
    let settings = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &settings, &walls(&mesh)).unwrap();
    for lift in 1..=2 {
        m.pour(1, lift, 0.0);
        m.pour(2, lift, 0.0);
    }
    let t = vec![20.0; mesh.n_thermal_dofs];
    m.step(0.0, 1.0, Some((&t, &t)), None).unwrap();
    // block 1 turns by +g1/2 and block 2 by −g1/2 about z: u_x = ∓g(y)/2 at
    // the walls, u_y = 0 there (the rotation centres on the walls' axis)
    for (i, p) in mesh.nodes.iter().enumerate() {
        let half = 0.5 * (G0 + G1 * p[1]);
        if p[0].abs() < 1e-9 {
            m.prescribe(i as u32, 0, -half).unwrap();
        } else if (p[0] - 2.0 * L_BLOCK).abs() < 1e-9 {
            m.prescribe(i as u32, 0, half).unwrap();
        }
    }
    m.step(1.0, 2.0, Some((&t, &t)), None).unwrap();
    for (p, st) in m.points().iter().zip(&m.state.joints) {
        let y = mesh.nodes[p.a as usize][1];
        assert_rel(st.aperture(), G0 + G1 * y, 1e-9, "the prescribed field");
    }
    (1..=2)
        .map(|z| {
            let min = m.zone_min_aperture(1, z).unwrap();
            (min.reading.aperture, min.reading.state)
        })
        .collect()
}

#[test]
fn the_zone_minimum_is_the_field_at_the_inset_on_any_mesh() {
    // 1.5 m and 0.857 m elements across: the inset line falls between
    // nodes on both, at a different fraction of an element
    for across in [4, 7] {
        for (zone, (aperture, state)) in opened(across, Some(1.0)).into_iter().enumerate() {
            let what = format!("{across} across, zone {}", zone + 1);
            assert_rel(aperture, G0 + G1 * 1.0, 1e-9, &what);
            assert_eq!(state, JointState::Open, "{what}");
        }
    }
    // inset 2.5 m on the 4-across mesh: between the nodes at 1.5 and 3 m
    let (aperture, _) = opened(4, Some(2.5))[0];
    assert_rel(aperture, G0 + G1 * 2.5, 1e-9, "inset 2.5 m");
}

#[test]
fn without_an_inset_the_minimum_is_one_node_in_and_moves_with_the_mesh() {
    // the default reading: the joint nodes off the faces, the nearest one
    // element width from the upstream face (6/4 and 6/7 m). Zone 1 only:
    // zone 2's own row is the dam's top, all on a face, so it keeps all of
    // its points (faces included), as this reading always did.
    for across in [4, 7] {
        let h = THICKNESS / f64::from(across);
        let (aperture, state) = opened(across, None)[0];
        assert_rel(aperture, G0 + G1 * h, 1e-9, &format!("{across} across"));
        assert_eq!(state, JointState::Open);
    }
}

#[test]
fn a_section_thinner_than_two_insets_reads_its_centre_and_inset_zero_its_face() {
    let (aperture, _) = opened(7, Some(3.5))[0];
    assert_rel(aperture, G0 + G1 * 0.5 * THICKNESS, 1e-9, "centre");
    let (aperture, _) = opened(7, Some(0.0))[1];
    assert_rel(aperture, G0, 1e-9, "the upstream face");
}

/// Every zone's layers are node rows from the upstream to the downstream
/// edge: two per layer, each one node longer than the layer's pairs (the
/// structure `grout_stops` needs of every mesh kind).
pub(crate) fn assert_full_rows(mesh: &Mesh, what: &str) {
    for zone in &mesh.zones {
        let mut per_layer: BTreeMap<u32, usize> = BTreeMap::new();
        for &p in &zone.pairs {
            *per_layer
                .entry(mesh.face_pairs[p as usize].layer)
                .or_default() += 1;
        }
        let rows = node_rows(mesh, &zone.pairs);
        assert_eq!(
            rows.len(),
            2 * per_layer.len(),
            "{what}: joint {} zone {}",
            zone.joint,
            zone.zone
        );
        for (row, n) in rows.chunks(2).zip(per_layer.values()) {
            assert!(row.iter().all(|r| r.len() == n + 1), "{what}: {row:?}");
        }
    }
}

#[test]
fn every_generated_kind_has_full_rows() {
    for model in ["small_dam_joints", "demo_arch", "xiaowan_like"] {
        let path = repo(&format!("models/{model}.toml"));
        let scene = groutready::scene::Scene::load(&path).unwrap();
        let mesh = groutready::app::build_mesh(&scene, model).unwrap();
        assert_full_rows(&mesh, model);
    }
}
