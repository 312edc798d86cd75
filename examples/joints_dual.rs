//! Would a dual (interface) solver of the joints pay? The complete dam with
//! every joint bonded (each pair of joint nodes tied), under a downward load
//! on every free node, solved two ways:
//!
//! - primal: the tied nodes merged and the tied matrix factorised (what the
//!   contact step's first pass does, every point stuck);
//! - dual: the blocks' matrix with every joint open factorised (the blocks
//!   meet only in the rock, so the joints are no longer separators of the
//!   elimination and L is smaller), and the pairs' forces λ found by
//!   conjugate gradients on F λ = d, F = B K⁻¹ Bᵀ, d = B K⁻¹ f (one solve
//!   with the open factor an iteration): unpreconditioned, with the lumped
//!   preconditioner ¼ B K Bᵀ, and with that preconditioner deflated by a
//!   coarse space W of smooth force fields (Saad et al.'s deflated CG:
//!   each iteration's direction kept F-orthogonal to W, whose F W is
//!   computed once, 32 columns a solve) — the fields constant and linear
//!   in x, y, z over each joint, then over each grouting zone.
//!
//!     cargo run --release --example joints_dual [SCENE] [MAX_ITERATIONS] [--deflated-only]
//!
//! A contact solver on the open factor would iterate on λ with the pairs'
//! states as bounds; its iterations cannot be fewer than the bonded
//! problem's, so this counts the least such a solver would pay. Measured
//! (6 Dec 2026, docs/PERFORMANCE.md): on the demo 986 iterations to 1e-10
//! unpreconditioned, 236 lumped, 35 deflated by each joint's fields, 12 by
//! each zone's; on the Xiaowan-like arch more than 3,000 unpreconditioned or
//! lumped (0.13 s each), 213 deflated by each joint's 504 fields (F W 21 s,
//! the iterations 45 s) and 52 by each zone's 7,587 (F W 354 s, 27 s),
//! where the tied factorisation takes 4.3–6.6 s and a solve 0.2 s.
use faer::Mat;
use groutready::fem::CholeskySolver;
use groutready::mesh::{Mesh, Part};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::time::Instant;

mod common;

/// The tied pairs of joint nodes and B, their relative displacements.
struct Pairs {
    /// (node a, node b, joint, zone)
    pairs: Vec<(u32, u32, u32, u32)>,
    n: usize,
}

impl Pairs {
    fn new(mesh: &Mesh) -> Pairs {
        Pairs {
            pairs: common::joint_node_pairs(mesh),
            n: 3 * mesh.nodes.len(),
        }
    }

    fn m(&self) -> usize {
        3 * self.pairs.len()
    }

    /// B u: u_a − u_b of each pair.
    fn b(&self, u: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; self.m()];
        for (p, &(a, b, ..)) in self.pairs.iter().enumerate() {
            for c in 0..3 {
                r[3 * p + c] = u[3 * a as usize + c] - u[3 * b as usize + c];
            }
        }
        r
    }

    /// Bᵀ λ.
    fn bt(&self, l: &[f64]) -> Vec<f64> {
        let mut u = vec![0.0; self.n];
        for (p, &(a, b, ..)) in self.pairs.iter().enumerate() {
            for c in 0..3 {
                u[3 * a as usize + c] += l[3 * p + c];
                u[3 * b as usize + c] -= l[3 * p + c];
            }
        }
        u
    }

    /// Orthonormal force fields constant and linear in x, y, z over each
    /// group of pairs (by joint, or by joint and zone), each direction
    /// apart: the columns of W.
    fn coarse(&self, mesh: &Mesh, by_zone: bool) -> Vec<Vec<(usize, f64)>> {
        let mut groups: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
        for (p, &(a, _, joint, zone)) in self.pairs.iter().enumerate() {
            let _ = a;
            groups
                .entry((joint, if by_zone { zone } else { 0 }))
                .or_default()
                .push(p);
        }
        let mut cols: Vec<Vec<(usize, f64)>> = Vec::new();
        for members in groups.values() {
            let at = |p: usize| mesh.nodes[self.pairs[p].0 as usize];
            let mean = (0..3)
                .map(|k| members.iter().map(|&p| at(p)[k]).sum::<f64>() / members.len() as f64);
            let mean: Vec<f64> = mean.collect();
            for c in 0..3 {
                let mut basis: Vec<Vec<f64>> = Vec::new();
                for f in 0..4 {
                    let mut v: Vec<f64> = members
                        .iter()
                        .map(|&p| {
                            if f == 0 {
                                1.0
                            } else {
                                at(p)[f - 1] - mean[f - 1]
                            }
                        })
                        .collect();
                    let norm0 = common::dot(&v, &v).sqrt();
                    for q in &basis {
                        let s = common::dot(&v, q);
                        v.iter_mut().zip(q).for_each(|(x, y)| *x -= s * y);
                    }
                    let norm = common::dot(&v, &v).sqrt();
                    if norm > 1e-6 * norm0 {
                        v.iter_mut().for_each(|x| *x /= norm);
                        basis.push(v);
                    }
                }
                for v in basis {
                    cols.push(members.iter().map(|&p| 3 * p + c).zip(v).collect());
                }
            }
        }
        cols
    }
}

/// The coarse space of a deflated CG: W (sparse columns), F W and the
/// Cholesky factor of E = Wᵀ F W.
struct Deflation {
    w: Vec<Vec<(usize, f64)>>,
    fw: DMatrix<f64>,
    e: nalgebra::Cholesky<f64, nalgebra::Dyn>,
}

impl Deflation {
    fn new(
        w: Vec<Vec<(usize, f64)>>,
        pairs: &Pairs,
        open: &CholeskySolver,
    ) -> anyhow::Result<Deflation> {
        let c = w.len();
        let mut fw = DMatrix::zeros(pairs.m(), c);
        for j0 in (0..c).step_by(32) {
            let k = 32.min(c - j0);
            let cols: Vec<Vec<f64>> = (j0..j0 + k)
                .map(|j| {
                    let mut l = vec![0.0; pairs.m()];
                    w[j].iter().for_each(|&(i, v)| l[i] = v);
                    pairs.bt(&l)
                })
                .collect();
            let mut rhs = Mat::<f64>::from_fn(pairs.n, k, |i, j| cols[j][i]);
            open.solve_columns(&mut rhs)?;
            for j in 0..k {
                let u: Vec<f64> = (0..pairs.n).map(|i| rhs[(i, j)]).collect();
                fw.set_column(j0 + j, &DVector::from_vec(pairs.b(&u)));
            }
        }
        let mut e = DMatrix::zeros(c, c);
        for (i, wi) in w.iter().enumerate() {
            for j in 0..c {
                e[(i, j)] = wi.iter().map(|&(r, v)| v * fw[(r, j)]).sum::<f64>();
            }
        }
        // Wᵀ F W is symmetric to round-off; the Cholesky reads its lower half
        let e = nalgebra::Cholesky::new(e)
            .ok_or_else(|| anyhow::anyhow!("Wᵀ F W is not positive definite"))?;
        Ok(Deflation { w, fw, e })
    }

    /// W E⁻¹ Wᵀ v, or W E⁻¹ (F W)ᵀ v when `through_f`.
    fn project(&self, through_f: bool, v: &[f64]) -> Vec<f64> {
        let xt_v = if through_f {
            self.fw.tr_mul(&DVector::from_column_slice(v))
        } else {
            DVector::from_iterator(
                self.w.len(),
                self.w
                    .iter()
                    .map(|col| col.iter().map(|&(i, x)| x * v[i]).sum::<f64>()),
            )
        };
        let y = self.e.solve(&xt_v);
        let mut out = vec![0.0; v.len()];
        for (col, &yj) in self.w.iter().zip(y.iter()) {
            col.iter().for_each(|&(i, x)| out[i] += x * yj);
        }
        out
    }
}

/// Preconditioned (and optionally deflated) conjugate gradients on F λ = d
/// to a relative residual of 1e-10: λ, the iterations and the residual
/// every 25 of them.
fn cg(
    apply_f: &dyn Fn(&[f64]) -> Vec<f64>,
    apply_m: &dyn Fn(&[f64]) -> Vec<f64>,
    d: &[f64],
    deflation: Option<&Deflation>,
    max_iterations: usize,
) -> (Vec<f64>, usize, Vec<String>) {
    let m = d.len();
    let nd = common::dot(d, d).sqrt();
    let mut lam = vec![0.0; m];
    let mut r = d.to_vec();
    if let Some(df) = deflation {
        lam = df.project(false, d);
        let f_lam = apply_f(&lam);
        r.iter_mut().zip(&f_lam).for_each(|(x, y)| *x -= y);
    }
    let deflate = |z: &[f64]| -> Vec<f64> {
        match deflation {
            Some(df) => {
                let c = df.project(true, z);
                z.iter().zip(&c).map(|(a, b)| a - b).collect()
            }
            None => z.to_vec(),
        }
    };
    let mut z = apply_m(&r);
    let mut p = deflate(&z);
    let mut rz = common::dot(&r, &z);
    let (mut it, mut hist) = (0, Vec::new());
    while it < max_iterations {
        let q = apply_f(&p);
        let alpha = rz / common::dot(&p, &q);
        for i in 0..m {
            lam[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        it += 1;
        let rel = common::dot(&r, &r).sqrt() / nd;
        if it % 25 == 0 {
            hist.push(format!("{it}:{rel:.1e}"));
        }
        if rel < 1e-10 {
            break;
        }
        z = apply_m(&r);
        let rz1 = common::dot(&r, &z);
        let beta = rz1 / rz;
        rz = rz1;
        let zd = deflate(&z);
        for i in 0..m {
            p[i] = zd[i] + beta * p[i];
        }
    }
    (lam, it, hist)
}

/// The tied problem solved directly: the displacements, b's equal to a's.
fn tied_solution(
    mesh: &Mesh,
    rock_e: f64,
    pairs: &Pairs,
    fixed: &[bool],
    f: &[f64],
) -> anyhow::Result<Vec<f64>> {
    let mut to: Vec<u32> = (0..mesh.nodes.len() as u32).collect();
    let mut fixed_t = fixed.to_vec();
    let mut ft = f.to_vec();
    for &(a, b, ..) in &pairs.pairs {
        to[b as usize] = a;
        for c in 0..3 {
            fixed_t[3 * b as usize + c] = true;
            ft[3 * a as usize + c] += f[3 * b as usize + c];
            ft[3 * b as usize + c] = 0.0;
        }
    }
    let modulus = |e: usize| {
        if mesh.parts[e] == Part::Rock {
            rock_e
        } else {
            2.5e10
        }
    };
    let (tp, k_tied) = common::stiffness(mesh, &modulus, &|v| to[v as usize], &fixed_t)?;
    let tied = common::factorised(tp, &k_tied, "tied (every pair bonded)")?;
    let t = Instant::now();
    tied.solve_in_place(&mut ft)?;
    println!("tied solve {:.3} s", t.elapsed().as_secs_f64());
    for &(a, b, ..) in &pairs.pairs {
        for c in 0..3 {
            ft[3 * b as usize + c] = ft[3 * a as usize + c];
        }
    }
    Ok(ft)
}

fn main() -> anyhow::Result<()> {
    let (path, inputs, rock_e) = common::scene_from_args()?;
    let max_iterations: usize = match std::env::args().nth(2) {
        Some(a) => a.parse()?,
        None => 3000,
    };
    let mesh = &inputs.mesh;
    let pairs = Pairs::new(mesh);
    let n = pairs.n;
    println!(
        "{path}: n {n}, {} pairs ({} constraints)",
        pairs.pairs.len(),
        pairs.m()
    );
    let fixed = common::base_fixed(mesh);
    let f: Vec<f64> = (0..n)
        .map(|i| if i % 3 == 2 && !fixed[i] { -1e5 } else { 0.0 })
        .collect();
    let modulus = |e: usize| {
        if mesh.parts[e] == Part::Rock {
            rock_e
        } else {
            2.5e10
        }
    };
    let (pattern, k_open) = common::stiffness(mesh, &modulus, &|v| v, &fixed)?;
    let open = common::factorised(pattern, &k_open, "open (every joint open)")?;
    let u_ref = tied_solution(mesh, rock_e, &pairs, &fixed, &f)?;
    let solve = |mut v: Vec<f64>| -> Vec<f64> {
        open.solve_in_place(&mut v)
            .expect("a solve with the open factor");
        v
    };
    let apply_f = |l: &[f64]| pairs.b(&solve(pairs.bt(l)));
    let lumped = |r: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; n];
        k_open.mul_vec(&pairs.bt(r), &mut y);
        pairs.b(&y).iter().map(|v| 0.25 * v).collect()
    };
    let identity = |r: &[f64]| r.to_vec();
    let d = pairs.b(&solve(f.clone()));
    let run = |name: &str, deflation: Option<&Deflation>, precond: bool| {
        let t = Instant::now();
        let m_apply: &dyn Fn(&[f64]) -> Vec<f64> = if precond { &lumped } else { &identity };
        let (lam, it, hist) = cg(&apply_f, m_apply, &d, deflation, max_iterations);
        let mut rhs = f.clone();
        rhs.iter_mut()
            .zip(pairs.bt(&lam))
            .for_each(|(x, y)| *x -= y);
        let u = solve(rhs);
        let diff: Vec<f64> = u.iter().zip(&u_ref).map(|(a, b)| a - b).collect();
        let err = (common::dot(&diff, &diff) / common::dot(&u_ref, &u_ref)).sqrt();
        println!(
            "dual CG, {name}: {it} iterations, {:.1} s; u against the tied solve {err:.1e}\n  {}",
            t.elapsed().as_secs_f64(),
            hist.join(" ")
        );
    };
    if std::env::args().nth(3).as_deref() != Some("--deflated-only") {
        run("no preconditioner", None, false);
        run("lumped preconditioner", None, true);
    }
    for by_zone in [false, true] {
        let t = Instant::now();
        let w = pairs.coarse(mesh, by_zone);
        let c = w.len();
        let df = Deflation::new(w, &pairs, &open)?;
        let what = if by_zone { "each zone" } else { "each joint" };
        println!(
            "coarse space of {what}: {c} fields, F W and E in {:.1} s",
            t.elapsed().as_secs_f64()
        );
        run(
            &format!("lumped, deflated by {what}'s fields ({c})"),
            Some(&df),
            true,
        );
    }
    Ok(())
}
