//! What condensing the rock would save: factorisation flops and L's entries
//! of the complete mechanical matrix of a scene (METIS), against the
//! concrete with the rock's Schur complement on the rock–concrete interface
//! (a dense block), and the one-off factorisation of the rock ordered with
//! the interface last.
//!
//!     cargo run --release --example rock_condensation [SCENE]
use groutready::fem::{elasticity, metis_nested_dissection, CholeskySolver, Ordering, Pattern};
use groutready::mesh::Part;
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let mesh = &inputs.mesh;
    rock_layers(mesh);
    let nn = mesh.nodes.len();
    let (mut in_rock, mut in_conc) = (vec![false; nn], vec![false; nn]);
    for (e, conn) in mesh.elements.iter().enumerate() {
        let flag = match mesh.parts[e] {
            Part::Rock => &mut in_rock,
            Part::Concrete { .. } => &mut in_conc,
        };
        for &v in conn {
            flag[v as usize] = true;
        }
    }
    let pairs: Vec<[u32; 2]> = mesh
        .face_pairs
        .iter()
        .flat_map(|p| (0..4).map(|k| [p.nodes_a[k], p.nodes_b[k]]))
        .filter(|[a, b]| a != b)
        .collect();
    let node_dofs = |v: u32| [3 * v, 3 * v + 1, 3 * v + 2];
    let report = |name: &str, pattern: Arc<Pattern>, ord: Ordering| -> anyhow::Result<()> {
        let t = Instant::now();
        let s = CholeskySolver::with_options(pattern.clone(), &ord, faer::Par::Seq)?;
        println!(
            "{name:10} n={:8} nnz(A)={:10} nnz(L)={:11} flops={:8.2} Gflop (symbolic {:.1} s)",
            pattern.n_dofs(),
            pattern.nnz(),
            s.factor_nnz(),
            s.factor_flops() / 1e9,
            t.elapsed().as_secs_f64()
        );
        Ok(())
    };
    // (a) the complete system
    let mut elems: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .map(|c| elasticity::element_dofs(c).to_vec())
        .collect();
    elems.extend(
        pairs
            .iter()
            .map(|&[a, b]| [node_dofs(a), node_dofs(b)].concat()),
    );
    report(
        "complete",
        Arc::new(Pattern::new(3 * nn, &elems)),
        Ordering::Metis,
    )?;

    // (b) the concrete and the interface, the rock's Schur complement a clique
    let mut map = vec![u32::MAX; nn];
    let mut n_ci = 0u32;
    for v in 0..nn {
        if in_conc[v] {
            map[v] = n_ci;
            n_ci += 1;
        }
    }
    let interface: Vec<usize> = (0..nn).filter(|&v| in_conc[v] && in_rock[v]).collect();
    let m = |v: u32| node_dofs(map[v as usize]);
    let mut elems: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| mesh.parts[e] != Part::Rock)
        .map(|(_, c)| c.iter().flat_map(|&v| m(v)).collect())
        .collect();
    elems.extend(pairs.iter().map(|&[a, b]| [m(a), m(b)].concat()));
    report(
        "concrete",
        Arc::new(Pattern::new(3 * n_ci as usize, &elems)),
        Ordering::Metis,
    )?;
    elems.push(interface.iter().flat_map(|&v| m(v as u32)).collect());
    println!(
        "interface: {} nodes, {} dofs",
        interface.len(),
        3 * interface.len()
    );
    report(
        "condensed",
        Arc::new(Pattern::new(3 * n_ci as usize, &elems)),
        Ordering::Metis,
    )?;

    // (c) the rock, interior first (METIS) and the interface last
    let mut map = vec![u32::MAX; nn];
    let mut n_r = 0u32;
    for v in 0..nn {
        if in_rock[v] && !in_conc[v] {
            map[v] = n_r;
            n_r += 1;
        }
    }
    let mut n_ri = n_r;
    for &v in &interface {
        map[v] = n_ri;
        n_ri += 1;
    }
    let rock: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| mesh.parts[e] == Part::Rock)
        .map(|(_, c)| c.iter().flat_map(|&v| node_dofs(map[v as usize])).collect())
        .collect();
    let interior: Vec<Vec<u32>> = rock
        .iter()
        .map(|d| d.iter().copied().filter(|&x| x < 3 * n_r).collect())
        .collect();
    let mut perm = metis_nested_dissection(&Pattern::new(3 * n_r as usize, &interior))?;
    perm.extend(3 * n_r..3 * n_ri);
    report(
        "rock",
        Arc::new(Pattern::new(3 * n_ri as usize, &rock)),
        Ordering::Custom(perm),
    )?;
    Ok(())
}

/// Rock elements by the elevation of their centres (printed by `main`).
pub fn rock_layers(mesh: &groutready::mesh::Mesh) {
    let mut zs: Vec<i64> = Vec::new();
    for (e, conn) in mesh.elements.iter().enumerate() {
        if mesh.parts[e] == Part::Rock {
            let z: f64 = conn.iter().map(|&v| mesh.nodes[v as usize][2]).sum::<f64>() / 8.0;
            zs.push((z / 50.0).floor() as i64 * 50);
        }
    }
    zs.sort();
    let mut i = 0;
    while i < zs.len() {
        let j = zs[i..].iter().take_while(|&&z| z == zs[i]).count();
        println!(
            "rock elements with centre in [{}, {}) m: {j}",
            zs[i],
            zs[i] + 50
        );
        i += j;
    }
}
