//! Numeric factorisation cost of the complete mechanical matrix of a scene
//! (every element live, joint nodes not merged, base fixed) with AMD,
//! METIS's nested dissection and the geometric nested dissection,
//! sequential and parallel; and the same for a scalar (thermal-like) pattern.
//!
//!     cargo run --release --example factor_orderings [SCENE] [fast]
//!
//! `fast` leaves out the geometric nested dissection (its fill explodes on
//! large arches); `metis` times only METIS with the supports held, the
//! mechanical steps' factor.
use groutready::fem::{
    elasticity, nested_dissection, CholeskySolver, Ordering, Pattern, SparseSym,
};
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let mode = std::env::args().nth(2).unwrap_or_default();
    let only_amd = mode == "fast" || mode == "metis";
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let mesh = &inputs.mesh;
    if !only_amd {
        scalar(mesh)?;
    }
    let n = 3 * mesh.nodes.len();
    let local: Vec<[u32; 24]> = mesh.elements.iter().map(elasticity::element_dofs).collect();
    let pattern = Arc::new(Pattern::new(n, &local));
    let mut a = SparseSym::new(pattern.clone());
    for (e, _) in mesh.elements.iter().enumerate() {
        let g = elasticity::gauss_points(&mesh.element_coords(e)).unwrap();
        let k = elasticity::stiffness(&g, &elasticity::isotropic_d(2e10, 0.2));
        a.add_element(e, &k);
    }
    let zmin = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    let fixed: Vec<bool> = (0..n).map(|i| mesh.nodes[i / 3][2] < zmin + 1e-6).collect();
    a.apply_dirichlet(&fixed);
    let xyz: Vec<[f64; 3]> = (0..n).map(|d| mesh.nodes[d / 3]).collect();
    let mut orderings = vec![("metis", Ordering::Metis)];
    if mode != "metis" {
        orderings.insert(0, ("amd", Ordering::Amd));
    }
    if !only_amd {
        orderings.push((
            "nd64",
            Ordering::Custom(nested_dissection(&pattern, &xyz, 64)),
        ));
        orderings.push((
            "nd256",
            Ordering::Custom(nested_dissection(&pattern, &xyz, 256)),
        ));
    }
    let mut runs = Vec::new();
    for (name, ord) in orderings {
        if mode != "metis" {
            runs.push((name.to_string(), ord.clone(), false));
        }
        runs.push((format!("{name}+held"), ord, true));
    }
    for (name, ord, held) in runs {
        for (pname, par) in [("seq", faer::Par::Seq), ("rayon", faer::Par::rayon(0))] {
            let t = Instant::now();
            let mut s = if held {
                CholeskySolver::with_held(pattern.clone(), &ord, par, &fixed)?
            } else {
                CholeskySolver::with_options(pattern.clone(), &ord, par)?
            };
            let ts = t.elapsed().as_secs_f64();
            let t = Instant::now();
            s.factorize(&a)?;
            let t1 = t.elapsed().as_secs_f64();
            let t = Instant::now();
            s.factorize(&a)?;
            let t2 = t.elapsed().as_secs_f64();
            // one right-hand side is swept on two cores where the factor is
            // large and made in parallel (`fem::two_cores`), several
            // sequentially (`fem::solver`'s SOLVE_PAR): best of 5, for 1, 4
            // and 16 right-hand sides
            let solves: Vec<String> = [1, 4, 16]
                .into_iter()
                .map(|k| {
                    let mut best = f64::MAX;
                    for _ in 0..5 {
                        let mut x = faer::Mat::<f64>::from_fn(n, k, |i, j| ((i + j) % 7) as f64);
                        let t = Instant::now();
                        s.solve_columns(&mut x)?;
                        best = best.min(t.elapsed().as_secs_f64());
                    }
                    Ok(format!("{k}: {:.1} ms", best * 1e3))
                })
                .collect::<anyhow::Result<_>>()?;
            let split = match (s.sweep_split(), s.factor_split()) {
                (Some([top, a, b]), Some([ft, fa, fb])) => format!(
                    " (on two cores: top {top}, sides {a} and {b} entries; top {:.1}, sides {:.1} and {:.1} Gflop)",
                    ft as f64 * 1e-9,
                    fa as f64 * 1e-9,
                    fb as f64 * 1e-9
                ),
                _ => String::new(),
            };
            println!(
                "{name:10} {pname:5} n={n} nnzL={} {:.2} Gflop symb {ts:.3} num {t1:.3}/{t2:.3} solves {}{split}",
                s.factor_nnz(),
                s.factor_flops() * 1e-9,
                solves.join(", ")
            );
        }
    }
    Ok(())
}

/// The same comparison on a scalar (thermal-like) pattern of the mesh.
fn scalar(mesh: &groutready::mesh::Mesh) -> anyhow::Result<()> {
    let n = mesh.nodes.len();
    let local: Vec<[u32; 8]> = mesh.elements.clone();
    let pattern = Arc::new(Pattern::new(n, &local));
    let mut a = SparseSym::new(pattern.clone());
    for (e, conn) in mesh.elements.iter().enumerate() {
        let _ = conn;
        let k = nalgebra::DMatrix::<f64>::from_fn(8, 8, |i, j| if i == j { 8.0 } else { -1.0 });
        a.add_element(e, &k);
    }
    for i in 0..n {
        a.add_diag(i, 1.0);
    }
    let xyz: Vec<[f64; 3]> = mesh.nodes.clone();
    for (name, ord) in [
        ("amd", Ordering::Amd),
        ("metis", Ordering::Metis),
        (
            "nd64",
            Ordering::Custom(nested_dissection(&pattern, &xyz, 64)),
        ),
    ] {
        let mut s = CholeskySolver::with_options(pattern.clone(), &ord, faer::Par::Seq)?;
        let t = Instant::now();
        s.factorize(&a)?;
        println!(
            "scalar {name} n={n} nnzL={} num {:.4}",
            s.factor_nnz(),
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
