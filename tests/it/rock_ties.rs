//! The rock tied to its grid lines (`solver.rock_coarsening`,
//! `mechanics::rock_ties`) on the demo arch, whose banks carry the rock
//! beside the dam at every lift level:
//!
//! - the ties are what the module doc says (masters kept, on the tied
//!   node's own line, moved onto its chord, nothing tied by the concrete,
//!   below the deepest foundation or across a change of supports);
//! - the patch test: a free thermal expansion (every material the same α,
//!   statically determinate supports moved with the field) is linear, so
//!   the tied model gives it exactly, without stress;
//! - a Ritz subspace: under self-weight the tied model's compliance is at
//!   most the untied one's (and close to it), its folded equilibrium
//!   residual round-off, and it has three unknowns fewer per tied node.

use groutready::mechanics::rock_ties::Ties;
use groutready::mechanics::{MechanicsModel, MechanicsSettings, Supports};
use groutready::mesh::{Mesh, Part};

use crate::common::{demo_mechanics as demo, dist};

#[test]
fn ties_keep_the_concrete_its_ring_the_deep_rock_and_the_support_changes() {
    let (mesh, _) = demo();
    let supported = Supports::far_boundary(&mesh).flags(mesh.nodes.len());
    assert_eq!(
        Ties::build(&mesh.elements, &mesh.parts, &mesh.nodes, &supported, 1).count(),
        0
    );
    let ties = Ties::build(&mesh.elements, &mesh.parts, &mesh.nodes, &supported, 4);
    let nn = mesh.nodes.len();
    let mut near = vec![false; nn];
    let concrete = |e: usize| mesh.parts[e] != Part::Rock;
    let mut in_concrete = vec![false; nn];
    for (_, c) in mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| concrete(e))
    {
        c.iter().for_each(|&v| in_concrete[v as usize] = true);
    }
    for c in &mesh.elements {
        if c.iter().any(|&v| in_concrete[v as usize]) {
            c.iter().for_each(|&v| near[v as usize] = true);
        }
    }
    let foundation = mesh
        .blocks
        .iter()
        .map(|b| b.foundation_z)
        .fold(f64::MAX, f64::min);
    let mut straightened = mesh.nodes.clone();
    ties.straighten(&mut straightened);
    let (mut tied, mut bend) = (0, 0.0f64);
    for v in 0..nn as u32 {
        let Some(t) = ties.of(v) else { continue };
        tied += 1;
        let (p, lo, hi) = (
            mesh.nodes[v as usize],
            mesh.nodes[t.lo as usize],
            mesh.nodes[t.hi as usize],
        );
        assert!(!near[v as usize], "node {v} by the concrete is tied");
        assert!(
            p[2] > foundation,
            "node {v} below the deepest foundation is tied"
        );
        assert!(
            ties.of(t.lo).is_none() && ties.of(t.hi).is_none(),
            "masters are kept"
        );
        assert!(lo[2] < p[2] && p[2] < hi[2], "node {v} between its masters");
        assert!(t.w > 0.0 && t.w < 1.0);
        // its line bends little: the mechanics moves it onto the chord
        let span = dist(lo, hi);
        let on_chord = straightened[v as usize];
        let chord: [f64; 3] = std::array::from_fn(|k| lo[k] + t.w * (hi[k] - lo[k]));
        assert!(dist(on_chord, chord) < 1e-12 * span);
        bend = bend.max(dist(p, chord) / span);
        for c in 0..3 {
            let s = supported[3 * v as usize + c];
            assert_eq!(
                s,
                supported[3 * t.lo as usize + c],
                "node {v}: supports differ"
            );
            assert_eq!(
                s,
                supported[3 * t.hi as usize + c],
                "node {v}: supports differ"
            );
        }
    }
    assert_eq!(tied, ties.count());
    assert!(tied > 300, "the demo's banks tie {tied} nodes");
    assert!(
        bend < 0.01,
        "a tied node {bend:.3} of its span off the chord"
    );
    eprintln!("demo, every 4th level: {tied} of {nn} nodes tied, at most {bend:.4} of their span off the chord");
}

/// Pours every lift on day 0 and steps days 0–1 unloaded.
fn poured(mesh: &Mesh, settings: &MechanicsSettings, supports: &Supports) -> MechanicsModel {
    let mut m = MechanicsModel::new(mesh, settings, supports).unwrap();
    for b in &mesh.blocks {
        for l in 1..=b.n_lifts {
            m.pour(b.block, l, 0.0);
        }
    }
    let t = vec![20.0; mesh.n_thermal_dofs];
    m.step(0.0, 1.0, Some((&t, &t)), None).unwrap();
    m
}

#[test]
fn a_free_expansion_is_linear_so_the_tied_rock_gives_it_exactly() {
    let (mesh, mut settings) = demo();
    let alpha = crate::common::thermal_strain_only(&mut settings);
    // 3-2-1 supports on three base nodes, moved with the free field
    let (supports, fixed, a) = crate::common::base_three_two_one(&mesh);
    let dt = 10.0;
    let xa = mesh.nodes[a as usize];
    let supported = supports.flags(mesh.nodes.len());
    for every in [1, 4] {
        settings.rock_coarsening = every;
        // the field at the mechanics' positions: tied nodes on their chords
        let mut x = mesh.nodes.clone();
        Ties::build(&mesh.elements, &mesh.parts, &mesh.nodes, &supported, every).straighten(&mut x);
        let want = |v: usize, k: usize| alpha * dt * (x[v][k] - xa[k]);
        let mut m = poured(&mesh, &settings, &supports);
        for &(n, k) in &fixed {
            m.prescribe(n, k, want(n as usize, k as usize)).unwrap();
        }
        let (t0, t1) = (
            vec![20.0; mesh.n_thermal_dofs],
            vec![20.0 + dt; mesh.n_thermal_dofs],
        );
        m.step(1.0, 2.0, Some((&t0, &t1)), None).unwrap();
        let scale = alpha * dt * 300.0;
        let (worst_u, worst_s) = crate::common::misfit_and_stress(&m, mesh.nodes.len(), want);
        eprintln!(
            "free expansion, every {every}: {} unknowns, displacement off by {worst_u:.1e} m, stress {worst_s:.1e} Pa",
            m.live_dofs()
        );
        assert!(
            worst_u < 1e-10 * scale,
            "displacement off αΔT·x by {worst_u} m"
        );
        // E·ε round-off with E ≤ 3.5e10 and ε ~ 1e-4
        assert!(worst_s < 1e-2, "free expansion left {worst_s} Pa of stress");
    }
}

#[test]
fn the_tied_rock_is_a_ritz_subspace_a_little_stiffer_under_self_weight() {
    let (mut mesh, mut settings) = demo();
    settings.joints = false;
    settings.thermal_strain = false;
    settings.reservoir_load = false;
    settings.concrete.creep = None;
    let supports = Supports::far_boundary(&mesh);
    // both on the mesh the tie straightens (which it then leaves as it is),
    // so that the tied displacements are a subspace of the untied ones
    let tied_nodes = {
        let s = supports.flags(mesh.nodes.len());
        let ties = Ties::build(&mesh.elements, &mesh.parts, &mesh.nodes, &s, 4);
        ties.straighten(&mut mesh.nodes);
        ties.count()
    };
    let mut runs = Vec::new();
    for every in [1, 4] {
        settings.rock_coarsening = every;
        let m = poured(&mesh, &settings, &supports);
        let compliance: f64 = m
            .state
            .f_ext
            .iter()
            .zip(&m.state.u)
            .map(|(f, u)| f * u)
            .sum();
        let (r, scale) = m.equilibrium_residual_parts();
        assert!(
            r <= 1e-8 * scale,
            "every {every}: residual {r:.2e} of {scale:.2e}"
        );
        let crest = (0..mesh.nodes.len())
            .filter(|&v| mesh.nodes[v][2] == mesh.crest_z)
            .map(|v| m.state.u[3 * v + 2])
            .fold(0.0, |a: f64, b| a.min(b));
        runs.push((m.live_dofs(), compliance, crest));
    }
    let ((n1, c1, z1), (n4, c4, z4)) = (runs[0], runs[1]);
    eprintln!(
        "self-weight: {n1} → {n4} unknowns; compliance {c1:.6e} → {c4:.6e} J ({:+.2e}); crest settlement {:.4} → {:.4} mm",
        c4 / c1 - 1.0,
        -1e3 * z1,
        -1e3 * z4
    );
    assert_eq!(n1 - n4, 3 * tied_nodes);
    assert!(
        c1 > 0.0 && c4 <= c1 * (1.0 + 1e-12),
        "a subspace cannot be softer"
    );
    assert!(c4 < c1 * (1.0 - 1e-6), "tying changes nothing");
    assert!(
        c4 >= 0.99 * c1,
        "tying every 4th level stiffens the demo by {:.2e}",
        1.0 - c4 / c1
    );
}
