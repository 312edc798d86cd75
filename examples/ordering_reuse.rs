//! Whether a live set can reuse the complete dam's METIS ordering: for the
//! rock and the concrete below a few elevations, the factorisation flops
//! and the analysis time of a fresh METIS ordering against the complete
//! mesh's ordering restricted to the live dofs (relative order kept).
//!
//!     cargo run --release --example ordering_reuse [SCENE]
use groutready::fem::{metis_nested_dissection, CholeskySolver, Ordering, Pattern};
use groutready::mesh::Part;
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let mesh = &inputs.mesh;
    let nn = mesh.nodes.len();
    let pairs: Vec<[u32; 2]> = mesh
        .face_pairs
        .iter()
        .flat_map(|p| (0..4).map(|k| [p.nodes_a[k], p.nodes_b[k]]))
        .filter(|[a, b]| a != b)
        .collect();
    let node_dofs = |v: u32| [3 * v, 3 * v + 1, 3 * v + 2];
    let pattern_of = |live: &[bool], map: &[u32], n: usize| {
        let m = |v: u32| node_dofs(map[v as usize]);
        let mut elems: Vec<Vec<u32>> = mesh
            .elements
            .iter()
            .enumerate()
            .filter(|&(e, _)| live[e])
            .map(|(_, c)| c.iter().flat_map(|&v| m(v)).collect())
            .collect();
        elems.extend(
            pairs
                .iter()
                .filter(|&&[a, b]| map[a as usize] != u32::MAX && map[b as usize] != u32::MAX)
                .map(|&[a, b]| [m(a), m(b)].concat()),
        );
        Arc::new(Pattern::new(3 * n, &elems))
    };
    let all = vec![true; mesh.elements.len()];
    let identity: Vec<u32> = (0..nn as u32).collect();
    let complete = pattern_of(&all, &identity, nn);
    let t = Instant::now();
    let complete_perm = metis_nested_dissection(&complete)?;
    println!(
        "complete: {} dofs, METIS {:.2} s",
        complete.n_dofs(),
        t.elapsed().as_secs_f64()
    );
    let zmin = mesh.layer_z[0];
    let zmax = mesh.crest_z;
    for frac in [0.25, 0.5, 0.75, 1.0] {
        let zcut = zmin + frac * (zmax - zmin);
        let live: Vec<bool> = mesh
            .elements
            .iter()
            .enumerate()
            .map(|(e, c)| match mesh.parts[e] {
                Part::Rock => true,
                Part::Concrete { .. } => {
                    c.iter().map(|&v| mesh.nodes[v as usize][2]).sum::<f64>() / 8.0 < zcut
                }
            })
            .collect();
        let mut map = vec![u32::MAX; nn];
        let mut n = 0u32;
        for (e, c) in mesh.elements.iter().enumerate() {
            if live[e] {
                for &v in c {
                    if map[v as usize] == u32::MAX {
                        map[v as usize] = n;
                        n += 1;
                    }
                }
            }
        }
        let pattern = pattern_of(&live, &map, n as usize);
        let t = Instant::now();
        let fresh =
            CholeskySolver::with_options(pattern.clone(), &Ordering::Metis, faer::Par::Seq)?;
        let t_fresh = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let restricted: Vec<u32> = complete_perm
            .iter()
            .filter_map(|&d| {
                let m = map[d as usize / 3];
                (m != u32::MAX).then(|| 3 * m + d % 3)
            })
            .collect();
        let reused = CholeskySolver::with_options(
            pattern.clone(),
            &Ordering::Custom(restricted),
            faer::Par::Seq,
        )?;
        let t_reused = t.elapsed().as_secs_f64();
        println!(
            "concrete below {zcut:7.1} m: {:7} dofs; fresh METIS {:7.2} Gflop nnz(L) {:10} in {t_fresh:.2} s; \
             complete order restricted {:7.2} Gflop nnz(L) {:10} in {t_reused:.2} s",
            pattern.n_dofs(),
            fresh.factor_flops() / 1e9,
            fresh.factor_nnz(),
            reused.factor_flops() / 1e9,
            reused.factor_nnz(),
        );
    }
    Ok(())
}
