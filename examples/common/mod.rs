//! What the measuring examples share: a scene's inputs from the command
//! line, the joints' node pairs, the complete mesh's stiffness and its factor.

// Each example is its own crate and uses a part of this module.
#![allow(dead_code)]

use std::sync::Arc;
use std::time::Instant;

use faer::Par;
use groutready::app::{self, Inputs};
use groutready::fem::ordering::Ordering;
use groutready::fem::{elasticity, CholeskySolver, Pattern, SparseSym};
use groutready::mesh::Mesh;

/// The inputs of the scene named by the first argument (the demo by
/// default), its path, and its rock's modulus \[Pa\] (20 GPa where the scene
/// gives none): the examples' matrices take mature concrete and this rock.
pub fn scene_from_args() -> anyhow::Result<(String, Inputs, f64)> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = app::load_inputs(std::path::Path::new(&path), None)?;
    let rock_e = inputs
        .scene
        .rock
        .as_ref()
        .and_then(|r| r.modulus_pa)
        .unwrap_or(2e10);
    Ok((path, inputs, rock_e))
}

/// The pairs of distinct joint nodes facing each other: (node of block
/// `joint`, node of block `joint + 1`, joint, zone), each once.
pub fn joint_node_pairs(mesh: &Mesh) -> Vec<(u32, u32, u32, u32)> {
    let mut seen = std::collections::BTreeSet::new();
    let mut pairs = Vec::new();
    for fp in &mesh.face_pairs {
        for k in 0..4 {
            let (a, b) = (fp.nodes_a[k], fp.nodes_b[k]);
            if a != b && seen.insert((a, b)) {
                pairs.push((a, b, fp.joint, fp.zone));
            }
        }
    }
    pairs
}

/// The complete mesh's stiffness, element e of Young's modulus
/// `modulus(e)` (Poisson 0.2), node v numbered `map(v)`, the rows `fixed`
/// held.
pub fn stiffness(
    mesh: &Mesh,
    modulus: &dyn Fn(usize) -> f64,
    map: &dyn Fn(u32) -> u32,
    fixed: &[bool],
) -> anyhow::Result<(Arc<Pattern>, SparseSym)> {
    let local: Vec<[u32; 24]> = mesh
        .elements
        .iter()
        .map(|el| {
            let mut d = [0u32; 24];
            for (i, &nd) in el.iter().enumerate() {
                for c in 0..3 {
                    d[3 * i + c] = 3 * map(nd) + c as u32;
                }
            }
            d
        })
        .collect();
    let pattern = Arc::new(Pattern::new(3 * mesh.nodes.len(), &local));
    let mut a = SparseSym::new(pattern.clone());
    for e in 0..mesh.elements.len() {
        let g = elasticity::gauss_points(&mesh.element_coords(e))?;
        a.add_element(
            e,
            &elasticity::stiffness(&g, &elasticity::isotropic_d(modulus(e), 0.2)),
        );
    }
    a.apply_dirichlet(fixed);
    Ok((pattern, a))
}

/// `a` factorised on its pattern in METIS's order, with its size and time
/// printed.
pub fn factorised(
    pattern: Arc<Pattern>,
    a: &SparseSym,
    what: &str,
) -> anyhow::Result<CholeskySolver> {
    let mut s = CholeskySolver::with_options(pattern, &Ordering::Metis, Par::rayon(0))?;
    let t = Instant::now();
    s.factorize(a)?;
    println!(
        "{what} factor: L {:.1}M entries, {:.1} Gflop, {:.2} s",
        s.factor_nnz() as f64 / 1e6,
        s.factor_flops() / 1e9,
        t.elapsed().as_secs_f64()
    );
    Ok(s)
}

/// The rows held: every dof of the nodes on the mesh's lowest level.
pub fn base_fixed(mesh: &Mesh) -> Vec<bool> {
    let zmin = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    (0..3 * mesh.nodes.len())
        .map(|i| mesh.nodes[i / 3][2] < zmin + 1e-6)
        .collect()
}

/// The dot product of two vectors of one length.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
