//! experiment: single- and multi-RHS solve, Par::Seq vs Par::rayon (not landed)
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymmetricOrdering};
use faer::{Conj, Mat, Par, Side};
use groutready::fem::{elasticity, metis_nested_dissection, Pattern, SparseSym};
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let mesh = &inputs.mesh;
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
    let fwd = metis_nested_dissection(&pattern)?;
    let mut inv = vec![0u32; n];
    for (k, &d) in fwd.iter().enumerate() {
        inv[d as usize] = k as u32;
    }
    let sym = factorize_symbolic_cholesky(
        pattern.symbolic(),
        Side::Upper,
        SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)),
        Default::default(),
    )
    .unwrap();
    let par = Par::rayon(0);
    let mut scratch =
        MemBuffer::new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    let mut l = vec![0.0; sym.len_val()];
    let t = Instant::now();
    sym.factorize_numeric_llt::<f64>(
        &mut l,
        a.as_faer(),
        Side::Upper,
        Default::default(),
        par,
        MemStack::new(&mut scratch),
        Default::default(),
    )
    .unwrap();
    println!(
        "n={n} nnzL={:.1}M factor(rayon) {:.2} s",
        sym.len_val() as f64 / 1e6,
        t.elapsed().as_secs_f64()
    );
    for k in [1usize, 4, 16] {
        for (pn, p) in [
            ("seq", Par::Seq),
            ("rayon", Par::rayon(0)),
            ("seq", Par::Seq),
            ("rayon", Par::rayon(0)),
        ] {
            let mut x = Mat::<f64>::from_fn(n, k, |i, j| ((i + j) % 7) as f64);
            let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f64>(k, p));
            let t = Instant::now();
            let reps = 5;
            for _ in 0..reps {
                LltRef::new(&sym, &l).solve_in_place_with_conj(
                    Conj::No,
                    x.as_mut(),
                    p,
                    MemStack::new(&mut mem),
                );
            }
            println!(
                "k={k:2} {pn:5} solve {:.1} ms",
                t.elapsed().as_secs_f64() * 1e3 / reps as f64
            );
        }
    }
    Ok(())
}
