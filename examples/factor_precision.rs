//! Would a single-precision factor pay? The complete mechanical matrix of a
//! scene (every element live, base fixed, METIS order) factorised in f64
//! and in f32 on the same symbolic analysis, and the f32 factor used as the
//! preconditioner of iterative refinement in f64 (residuals in f64, so the
//! answer is the f64 one to the refinement's tolerance): the factorisation's
//! time against the extra sweeps of refinement.
//!
//!     cargo run --release --example factor_precision [SCENE]
//!
//! Two matrices: every lift mature (concrete 25 GPa, the scene's rock), and
//! the top lift of every block newborn (0.5 GPa), the contrast of a day
//! with pours.
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side};
use groutready::fem::{elasticity, metis_nested_dissection, Pattern, SparseSym};
use groutready::mesh::Part;
use std::sync::Arc;
use std::time::Instant;

mod common;

fn main() -> anyhow::Result<()> {
    let (path, inputs, rock_e) = common::scene_from_args()?;
    let mesh = &inputs.mesh;
    let n = 3 * mesh.nodes.len();
    let local: Vec<[u32; 24]> = mesh.elements.iter().map(elasticity::element_dofs).collect();
    let pattern = Arc::new(Pattern::new(n, &local));
    let fwd = metis_nested_dissection(&pattern)?;
    let mut inv = vec![0u32; n];
    for (k, &d) in fwd.iter().enumerate() {
        inv[d as usize] = k as u32;
    }
    let t = Instant::now();
    let symbolic = factorize_symbolic_cholesky(
        pattern.symbolic(),
        Side::Upper,
        SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)),
        Default::default(),
    )
    .map_err(|e| anyhow::anyhow!("symbolic: {e:?}"))?;
    println!(
        "{path}: n = {n}, L {:.1}M entries, symbolic {:.2} s",
        symbolic.len_val() as f64 / 1e6,
        t.elapsed().as_secs_f64()
    );
    let top: std::collections::HashMap<u32, u32> =
        mesh.parts.iter().fold(Default::default(), |mut m, p| {
            if let Part::Concrete { block, lift } = *p {
                let e = m.entry(block).or_insert(lift);
                *e = (*e).max(lift);
            }
            m
        });
    for (name, young) in [("mature", false), ("newborn top lifts", true)] {
        let mut a = SparseSym::new(pattern.clone());
        for (e, part) in mesh.parts.iter().enumerate() {
            let modulus = match *part {
                Part::Rock => rock_e,
                Part::Concrete { block, lift } if young && top.get(&block) == Some(&lift) => 5e8,
                Part::Concrete { .. } => 2.5e10,
            };
            let g = elasticity::gauss_points(&mesh.element_coords(e))?;
            a.add_element(
                e,
                &elasticity::stiffness(&g, &elasticity::isotropic_d(modulus, 0.2)),
            );
        }
        let fixed = common::base_fixed(mesh);
        a.apply_dirichlet(&fixed);
        // self-weight-like load: downward on every free node
        let b: Vec<f64> = (0..n)
            .map(|i| if i % 3 == 2 && !fixed[i] { -1e5 } else { 0.0 })
            .collect();
        println!("{name}:");
        compare(&symbolic, &a, &b)?;
    }
    Ok(())
}

/// Factorises `a` in both precisions, then refines A x = b in f64 with each.
fn compare(symbolic: &SymbolicCholesky<u32>, a: &SparseSym, b: &[f64]) -> anyhow::Result<()> {
    let l64 = factorize::<f64>(symbolic, a.as_faer())?;
    let v32: Vec<f32> = a.values().iter().map(|&v| v as f32).collect();
    let a32 = SparseColMatRef::new(a.as_faer().symbolic(), &v32);
    let l32 = factorize::<f32>(symbolic, a32)?;
    println!(
        "  factorisation f64 {:.3} s, f32 {:.3} s ({:.2}×)",
        l64.1,
        l32.1,
        l64.1 / l32.1
    );
    refine("f64", a, b, |r| solve::<f64>(symbolic, &l64.0, r))?;
    refine("f32", a, b, |r| {
        let mut r32: Vec<f32> = r.iter().map(|&v| v as f32).collect();
        let s = solve::<f32>(symbolic, &l32.0, &mut r32);
        for (x, y) in r.iter_mut().zip(&r32) {
            *x = f64::from(*y);
        }
        s
    })
}

/// Numeric LLᵀ (best of two), its values and seconds.
fn factorize<T: faer::traits::RealField + Copy + Default>(
    symbolic: &SymbolicCholesky<u32>,
    a: SparseColMatRef<'_, u32, T>,
) -> anyhow::Result<(Vec<T>, f64)> {
    let par = Par::rayon(0);
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default()))?;
    let mut l = vec![T::default(); symbolic.len_val()];
    let mut best = f64::MAX;
    for _ in 0..2 {
        let t = Instant::now();
        symbolic
            .factorize_numeric_llt::<T>(
                &mut l,
                a,
                Side::Upper,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| anyhow::anyhow!("factorisation: {e:?}"))?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok((l, best))
}

/// One solve with the factor `l` in place; its seconds.
fn solve<T: faer::traits::RealField + Copy>(
    symbolic: &SymbolicCholesky<u32>,
    l: &[T],
    r: &mut [T],
) -> f64 {
    let n = r.len();
    let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<T>(1, Par::Seq));
    let t = Instant::now();
    LltRef::new(symbolic, l).solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(r, n, 1),
        Par::Seq,
        MemStack::new(&mut mem),
    );
    t.elapsed().as_secs_f64()
}

/// x ← x + M⁻¹(b − A x) from x = 0 until ‖b − A x‖ ≤ 5e-12 ‖b‖ (f64 round-off on these matrices: 1.5e-12).
fn refine(
    name: &str,
    a: &SparseSym,
    b: &[f64],
    mut precond: impl FnMut(&mut [f64]) -> f64,
) -> anyhow::Result<()> {
    let n = b.len();
    let nb = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut x = vec![0.0; n];
    let mut ax = vec![0.0; n];
    let (mut solve_s, mut history) = (0.0, Vec::new());
    for _ in 0..12 {
        a.mul_vec(&x, &mut ax);
        let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        let rel = r.iter().map(|v| v * v).sum::<f64>().sqrt() / nb;
        history.push(rel);
        if rel <= 5e-12 || !rel.is_finite() {
            break;
        }
        solve_s += precond(&mut r);
        for (x, d) in x.iter_mut().zip(&r) {
            *x += d;
        }
    }
    let sweeps = history.len() - 1;
    let shown: Vec<String> = history.iter().map(|r| format!("{r:.1e}")).collect();
    println!(
        "  {name}: {sweeps} solves ({:.1} ms each), residuals {}",
        1e3 * solve_s / sweeps.max(1) as f64,
        shown.join(" ")
    );
    Ok(())
}
