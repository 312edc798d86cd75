//! Layer merging (`solver.layer_merging_age_days`,
//! `mechanics::layer_merging`) on the demo arch:
//!
//! - the ties are what the module doc says (off the joints, the rock and
//!   the supports; masters on the grouting zones' boundary elevations, on
//!   the tied node's own line; moved onto its chord; on once every element
//!   round the segment is old enough, not before);
//! - the patch test: a free thermal expansion (every material the same α,
//!   statically determinate supports moved with the field) is linear, so
//!   the merged model gives it exactly, without stress, with fewer
//!   unknowns;
//! - its error against the untied run at the grouting dates:
//!   `tests/it/fast_path.rs`.

use groutready::mechanics::layer_merging::LayerMerge;
use groutready::mechanics::{MechanicsModel, Supports};
use groutready::mesh::Part;

use crate::common::{demo_mechanics as demo, dist};

#[test]
fn merging_ties_old_concrete_off_the_joints_between_zone_levels() {
    let (mesh, _) = demo();
    let nn = mesh.nodes.len();
    let supported = Supports::far_boundary(&mesh).flags(nn);
    assert!(
        LayerMerge::build(&mesh, &supported, 0).is_empty(),
        "0 is off"
    );
    let merge = LayerMerge::build(&mesh, &supported, 60);
    let mut joint_or_rock = vec![false; nn];
    for p in &mesh.face_pairs {
        for k in 0..4 {
            joint_or_rock[p.nodes_a[k] as usize] = true;
            joint_or_rock[p.nodes_b[k] as usize] = true;
        }
    }
    for (e, c) in mesh.elements.iter().enumerate() {
        if mesh.parts[e] == Part::Rock {
            c.iter().for_each(|&v| joint_or_rock[v as usize] = true);
        }
    }
    let on_zone_level = |z: f64| {
        mesh.zones
            .iter()
            .any(|zn| (zn.z_bottom - z).abs() < 1e-6 || (zn.z_top - z).abs() < 1e-6)
    };
    let mut straightened = mesh.nodes.clone();
    merge.straighten(&mut straightened);
    let (mut tied, mut bend) = (0, 0.0f64);
    for v in 0..nn as u32 {
        let Some(t) = merge.tie_of(v) else { continue };
        tied += 1;
        let (p, lo, hi) = (
            mesh.nodes[v as usize],
            mesh.nodes[t.lo as usize],
            mesh.nodes[t.hi as usize],
        );
        assert!(
            !joint_or_rock[v as usize],
            "node {v} on a joint or the rock is tied"
        );
        assert!(
            (0..3).all(|c| !supported[3 * v as usize + c]),
            "node {v} is supported"
        );
        assert!(!on_zone_level(p[2]), "node {v} on a zone boundary is tied");
        assert!(
            on_zone_level(lo[2]) && on_zone_level(hi[2]),
            "node {v}: masters on zone levels"
        );
        assert!(merge.tie_of(t.lo).is_none() && merge.tie_of(t.hi).is_none());
        assert!(lo[2] < p[2] && p[2] < hi[2], "node {v} between its masters");
        assert!(t.w > 0.0 && t.w < 1.0);
        let span = dist(lo, hi);
        let chord: [f64; 3] = std::array::from_fn(|k| lo[k] + t.w * (hi[k] - lo[k]));
        assert!(dist(straightened[v as usize], chord) < 1e-12 * span);
        bend = bend.max(dist(p, chord) / span);
    }
    eprintln!(
        "demo: {tied} of {nn} nodes may be tied, at most {bend:.4} of their span off the chord"
    );
    assert!(tied > 500, "the demo's blocks tie {tied} nodes");
    assert!(
        bend < 0.01,
        "a tied node {bend:.3} of its span off the chord"
    );

    // on once every element round a segment is 60 days old
    let live = vec![true; mesh.elements.len()];
    let mut birth = vec![0.0; mesh.elements.len()];
    assert!(merge.tied_at(&live, &birth, 59.5).is_empty());
    assert_eq!(merge.tied_at(&live, &birth, 60.0).len(), tied);
    let some = merge.all()[0].0;
    let young = mesh
        .elements
        .iter()
        .position(|c| c.contains(&some))
        .unwrap();
    birth[young] = 10.0;
    let at = merge.tied_at(&live, &birth, 60.0);
    assert!(!at.contains(&some) && at.len() < tied && !at.is_empty());
    let mut not_live = live.clone();
    not_live[young] = false;
    assert!(!merge
        .tied_at(&not_live, &vec![0.0; live.len()], 100.0)
        .contains(&some));
}

#[test]
fn a_free_expansion_is_linear_so_the_merged_concrete_gives_it_exactly() {
    let (mesh, mut settings) = demo();
    let alpha = crate::common::thermal_strain_only(&mut settings);
    // 3-2-1 supports on three base nodes, moved with the free field
    let (supports, fixed, a) = crate::common::base_three_two_one(&mesh);
    let supported = supports.flags(mesh.nodes.len());
    let (dt, age) = (10.0, 60);
    let xa = mesh.nodes[a as usize];
    let mut unknowns = Vec::new();
    for merging in [0, age] {
        settings.layer_merging_age_days = merging;
        // the field at the mechanics' positions: tied nodes on their chords
        let mut x = mesh.nodes.clone();
        LayerMerge::build(&mesh, &supported, merging).straighten(&mut x);
        let want = |v: usize, k: usize| alpha * dt * (x[v][k] - xa[k]);
        let mut m = MechanicsModel::new(&mesh, &settings, &supports).unwrap();
        for bl in &mesh.blocks {
            for l in 1..=bl.n_lifts {
                m.pour(bl.block, l, 0.0);
            }
        }
        let (t0, t1) = (
            vec![20.0; mesh.n_thermal_dofs],
            vec![20.0 + dt; mesh.n_thermal_dofs],
        );
        m.step(0.0, age as f64, Some((&t0, &t0)), None).unwrap();
        for &(n, k) in &fixed {
            m.prescribe(n, k, want(n as usize, k as usize)).unwrap();
        }
        m.step(age as f64, age as f64 + 1.0, Some((&t0, &t1)), None)
            .unwrap();
        let scale = alpha * dt * 300.0;
        let (worst_u, worst_s) = crate::common::misfit_and_stress(&m, mesh.nodes.len(), want);
        eprintln!(
            "free expansion, merging after {merging} d: {} unknowns, displacement off by {worst_u:.1e} m, stress {worst_s:.1e} Pa",
            m.live_dofs()
        );
        assert!(
            worst_u < 1e-10 * scale,
            "displacement off αΔT·x by {worst_u} m"
        );
        assert!(worst_s < 1e-2, "free expansion left {worst_s} Pa of stress");
        unknowns.push(m.live_dofs());
    }
    assert!(
        unknowns[1] < unknowns[0],
        "merged: {} unknowns against {}",
        unknowns[1],
        unknowns[0]
    );
}
