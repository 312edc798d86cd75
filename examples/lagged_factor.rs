//! Would a lagged factor pay? ISSUE 12's third lever: the concrete ages
//! every day, so the exact path factorises every mechanical step; on a day
//! that pours nothing the matrix only drifts, and the factor of an earlier
//! day could precondition conjugate gradients on today's. This counts the
//! iterations on the complete dam after its last pour: every joint pair
//! tied (the contact step's first pass, every point stuck), each element at
//! its lift's modulus E(τ) for its age τ on day d (the scene's modulus law,
//! from `pours.csv`; the rock constant), a downward load on every free
//! node, and PCG on K(d) x = b preconditioned by the factor of K(d − k) to
//! a relative residual of 1e-10, for a few days d after the last pour and
//! lags k.
//!
//!     cargo run --release --example lagged_factor [SCENE]
//!
//! A contact pass would pay its PCG iterations in sweeps where the step's
//! own factor pays one (and a refinement). Measured (6 Dec 2026,
//! docs/PERFORMANCE.md, sixteenth session): the same counts on the demo and
//! the Xiaowan-like arch, 8 iterations a day after the last pour (its lift's
//! modulus growing 36 % a day), 5–10 a week later by lag, 4–7 after two
//! months, 3–4 after a year; on the large arch an iteration takes 0.25–0.28 s
//! and a factorisation of the tied dam 5.4–7.8 s, about 25 of them.
use groutready::material::ageing::ModulusOfAge;
use groutready::mesh::Part;
use std::collections::HashMap;
use std::time::Instant;

mod common;

fn main() -> anyhow::Result<()> {
    let (path, inputs, rock_e) = common::scene_from_args()?;
    let mesh = &inputs.mesh;
    let law = inputs
        .scene
        .concrete
        .modulus
        .ok_or_else(|| anyhow::anyhow!("{path}: no ageing modulus law"))?;
    let poured: HashMap<(u32, u32), f64> = inputs
        .schedules
        .pours
        .iter()
        .map(|p| ((p.block, p.lift), inputs.scene.epoch.day(p.date).0 as f64))
        .collect();
    let pour_day = |e: usize| match mesh.parts[e] {
        Part::Concrete { block, lift } => poured.get(&(block, lift)).copied(),
        Part::Rock => None,
    };
    let last = (0..mesh.elements.len())
        .filter_map(pour_day)
        .fold(f64::MIN, f64::max);
    let pairs = common::joint_node_pairs(mesh);
    let mut to: Vec<u32> = (0..mesh.nodes.len() as u32).collect();
    let mut fixed = common::base_fixed(mesh);
    for &(a, b, ..) in &pairs {
        to[b as usize] = a;
        for c in 0..3 {
            fixed[3 * b as usize + c] = true;
        }
    }
    let n = fixed.len();
    let b: Vec<f64> = (0..n)
        .map(|i| if i % 3 == 2 && !fixed[i] { -1e5 } else { 0.0 })
        .collect();
    println!(
        "{path}: n {n}, {} tied pairs, last pour on day {last}",
        pairs.len()
    );
    // day d's matrix: each element at its age (mid-day), the rock constant
    let matrix = |d: f64| {
        let modulus = |e: usize| match pour_day(e) {
            Some(p) => law.modulus_at(d + 0.5 - p),
            None => rock_e,
        };
        common::stiffness(mesh, &modulus, &|v| to[v as usize], &fixed)
    };
    let cases: [(f64, &[f64]); 5] = [
        (1.0, &[1.0]),
        (3.0, &[1.0, 2.0]),
        (8.0, &[1.0, 3.0, 7.0]),
        (60.0, &[1.0, 7.0, 30.0]),
        (365.0, &[1.0, 7.0, 30.0]),
    ];
    for (after, lags) in cases {
        let d = last + after;
        let (pattern, k_d) = matrix(d)?;
        let youngest = law.modulus_at(after + 0.5) / law.modulus_at(after - 0.5) - 1.0;
        println!(
            "day {d} ({after} days after the last pour; the youngest lift's modulus grows {:.2} % a day)",
            100.0 * youngest
        );
        for &k in lags {
            let (_, k_lag) = matrix(d - k)?;
            let lagged = common::factorised(pattern.clone(), &k_lag, &format!("  lag {k} d"))?;
            let t = Instant::now();
            let it = pcg(&k_d, &lagged, &b)?;
            println!(
                "    PCG: {it} iterations to 1e-10, {:.2} s",
                t.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}

/// Conjugate gradients on A x = b preconditioned by `m`'s factor, from
/// x = 0 to ‖r‖ ≤ 1e-10 ‖b‖: the iterations.
fn pcg(
    a: &groutready::fem::SparseSym,
    m: &groutready::fem::CholeskySolver,
    b: &[f64],
) -> anyhow::Result<usize> {
    let n = b.len();
    let nb = common::dot(b, b).sqrt();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut z = r.clone();
    m.solve_in_place(&mut z)?;
    let mut p = z.clone();
    let mut rz = common::dot(&r, &z);
    let mut q = vec![0.0; n];
    for it in 1..=200 {
        a.mul_vec(&p, &mut q);
        let alpha = rz / common::dot(&p, &q);
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        if common::dot(&r, &r).sqrt() <= 1e-10 * nb {
            return Ok(it);
        }
        z.copy_from_slice(&r);
        m.solve_in_place(&mut z)?;
        let rz1 = common::dot(&r, &z);
        for i in 0..n {
            p[i] = z[i] + rz1 / rz * p[i];
        }
        rz = rz1;
    }
    anyhow::bail!("PCG did not reach 1e-10 in 200 iterations")
}
