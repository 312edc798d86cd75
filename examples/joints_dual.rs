//! Would a dual (interface) solver of the joints pay? The complete dam with
//! every joint bonded (each pair of joint nodes tied), under a downward load
//! on every free node, solved two ways:
//!
//! - primal: the tied nodes merged and the tied matrix factorised (what the
//!   contact step's first pass does, every point stuck);
//! - dual: the blocks' matrix with every joint open factorised (the blocks
//!   meet only in the rock, so the joints are no longer separators of the
//!   elimination and L is smaller), and the pairs' forces λ found by
//!   conjugate gradients on B K⁻¹ Bᵀ λ = B K⁻¹ f (one solve with the open
//!   factor an iteration), unpreconditioned and with the lumped
//!   preconditioner ¼ B K Bᵀ.
//!
//!     cargo run --release --example joints_dual [SCENE] [MAX_ITERATIONS]
//!
//! A contact solver on the open factor would iterate on λ with the pairs'
//! states as bounds; its iterations cannot be fewer than the bonded
//! problem's, so this counts the least such a solver would pay. Measured
//! (6 Dec 2026, docs/PERFORMANCE.md): on the demo 233 preconditioned
//! iterations to 1e-10 (985 without); on the Xiaowan-like arch more than
//! 3,000 either way (0.13 s each), where the tied factorisation takes 4.3 s.
use faer::Par;
use groutready::fem::ordering::Ordering;
use groutready::fem::{elasticity, CholeskySolver, Pattern, SparseSym};
use groutready::mesh::Part;
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Instant;

mod common;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn main() -> anyhow::Result<()> {
    let (path, inputs, rock_e) = common::scene_from_args()?;
    let mesh = &inputs.mesh;
    let max_iterations: usize = match std::env::args().nth(2) {
        Some(a) => a.parse()?,
        None => 3000,
    };
    let n = 3 * mesh.nodes.len();
    // node pairs (a, b), a != b
    let mut pairs = BTreeSet::new();
    for fp in &mesh.face_pairs {
        for k in 0..4 {
            let (a, b) = (fp.nodes_a[k], fp.nodes_b[k]);
            if a != b {
                pairs.insert((a, b));
            }
        }
    }
    let pairs: Vec<(u32, u32)> = pairs.into_iter().collect();
    let m = 3 * pairs.len();
    let zmin = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    let fixed: Vec<bool> = (0..n).map(|i| mesh.nodes[i / 3][2] < zmin + 1e-6).collect();
    let modulus = |e: usize| match mesh.parts[e] {
        Part::Rock => rock_e,
        _ => 2.5e10,
    };
    // open: the mesh as it is (duplicated joint nodes)
    let assemble = |map: &dyn Fn(u32) -> u32| -> anyhow::Result<(Arc<Pattern>, SparseSym)> {
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
        let pattern = Arc::new(Pattern::new(n, &local));
        let mut a = SparseSym::new(pattern.clone());
        for e in 0..mesh.elements.len() {
            let g = elasticity::gauss_points(&mesh.element_coords(e))?;
            a.add_element(
                e,
                &elasticity::stiffness(&g, &elasticity::isotropic_d(modulus(e), 0.2)),
            );
        }
        Ok((pattern, a))
    };
    let f: Vec<f64> = (0..n)
        .map(|i| if i % 3 == 2 && !fixed[i] { -1e5 } else { 0.0 })
        .collect();
    let (pattern, mut k_open) = assemble(&|nd| nd)?;
    k_open.apply_dirichlet(&fixed);
    let mut open = CholeskySolver::with_options(pattern, &Ordering::Metis, Par::rayon(0))?;
    let t = Instant::now();
    open.factorize(&k_open)?;
    println!(
        "{path}: n {n}, {} pairs ({m} constraints); open factor L {:.1}M, {:.1} Gflop, {:.2} s",
        pairs.len(),
        open.factor_nnz() as f64 / 1e6,
        open.factor_flops() / 1e9,
        t.elapsed().as_secs_f64()
    );
    // tied: node b replaced by node a (b's rows then empty: fix them)
    let mut to = (0..mesh.nodes.len() as u32).collect::<Vec<_>>();
    for &(a, b) in &pairs {
        to[b as usize] = a;
    }
    let (tp, mut k_tied) = assemble(&|nd| to[nd as usize])?;
    let mut fixed_t = fixed.clone();
    for &(_, b) in &pairs {
        for c in 0..3 {
            fixed_t[3 * b as usize + c] = true;
        }
    }
    k_tied.apply_dirichlet(&fixed_t);
    let mut tied = CholeskySolver::with_options(tp, &Ordering::Metis, Par::rayon(0))?;
    let t = Instant::now();
    tied.factorize(&k_tied)?;
    println!(
        "tied factor L {:.1}M, {:.1} Gflop, {:.2} s",
        tied.factor_nnz() as f64 / 1e6,
        tied.factor_flops() / 1e9,
        t.elapsed().as_secs_f64()
    );
    let mut ft = f.clone();
    for &(a, b) in &pairs {
        for c in 0..3 {
            ft[3 * a as usize + c] += f[3 * b as usize + c];
            ft[3 * b as usize + c] = 0.0;
        }
    }
    let t = Instant::now();
    tied.solve_in_place(&mut ft)?;
    println!("tied solve {:.3} s", t.elapsed().as_secs_f64());
    let mut u_ref = ft.clone();
    for &(a, b) in &pairs {
        for c in 0..3 {
            u_ref[3 * b as usize + c] = u_ref[3 * a as usize + c];
        }
    }
    // B u: u_a - u_b per pair; Bᵀ λ
    let bu = |u: &[f64]| -> Vec<f64> {
        let mut r = vec![0.0; m];
        for (p, &(a, b)) in pairs.iter().enumerate() {
            for c in 0..3 {
                r[3 * p + c] = u[3 * a as usize + c] - u[3 * b as usize + c];
            }
        }
        r
    };
    let bt = |l: &[f64]| -> Vec<f64> {
        let mut u = vec![0.0; n];
        for (p, &(a, b)) in pairs.iter().enumerate() {
            for c in 0..3 {
                u[3 * a as usize + c] += l[3 * p + c];
                u[3 * b as usize + c] -= l[3 * p + c];
            }
        }
        u
    };
    let solve = |mut v: Vec<f64>| -> Vec<f64> {
        open.solve_in_place(&mut v).unwrap();
        v
    };
    for precond in [false, true] {
        // F λ = d: F = B K⁻¹ Bᵀ, d = B K⁻¹ f (λ: the pairs' forces, u = K⁻¹(f − Bᵀλ))
        let kf = solve(f.clone());
        let d = bu(&kf);
        let apply_f = |l: &[f64]| bu(&solve(bt(l)));
        let apply_m = |r: &[f64]| -> Vec<f64> {
            if !precond {
                return r.to_vec();
            }
            let mut y = vec![0.0; n];
            k_open.mul_vec(&bt(r), &mut y);
            bu(&y).iter().map(|v| 0.25 * v).collect()
        };
        let t = Instant::now();
        let mut lam = vec![0.0; m];
        let mut r = d.clone();
        let nd = dot(&d, &d).sqrt();
        let mut z = apply_m(&r);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let mut it = 0;
        let mut hist = Vec::new();
        while it < max_iterations {
            let q = apply_f(&p);
            let alpha = rz / dot(&p, &q);
            for i in 0..m {
                lam[i] += alpha * p[i];
                r[i] -= alpha * q[i];
            }
            it += 1;
            let rel = dot(&r, &r).sqrt() / nd;
            if it % 25 == 0 {
                hist.push(format!("{it}:{rel:.1e}"));
            }
            if rel < 1e-10 {
                break;
            }
            z = apply_m(&r);
            let rz1 = dot(&r, &z);
            let beta = rz1 / rz;
            rz = rz1;
            for i in 0..m {
                p[i] = z[i] + beta * p[i];
            }
        }
        let mut rhs = f.clone();
        for (x, y) in rhs.iter_mut().zip(bt(&lam)) {
            *x -= y;
        }
        let u = solve(rhs);
        let err = u
            .iter()
            .zip(&u_ref)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
            / dot(&u_ref, &u_ref).sqrt();
        println!(
            "dual CG ({}): {it} iterations, {:.1} s; relative error of u against the tied solve {err:.1e}\n  {}",
            if precond { "lumped preconditioner" } else { "no preconditioner" },
            t.elapsed().as_secs_f64(),
            hist.join(" ")
        );
    }
    Ok(())
}
