//! Is faer's numeric Cholesky with `Par::rayon` bit-reproducible for a fixed
//! thread count? Factorises the complete mechanical matrix of a scene (every
//! element live, base fixed; the systems the models factor with all rayon
//! threads are this large) and solves one right-hand side, repeatedly:
//! sequentially, with `Par::rayon(t)` for each thread count `t`, and with two
//! factorisations at once on the same pool (as the planner's two searches
//! run). Prints, per setting, the number of distinct solutions (by their
//! bits) and the largest difference from the sequential one.
//!
//!     cargo run --release --example factor_determinism [SCENE] [REPEATS]
use std::collections::BTreeSet;
use std::sync::Arc;

use groutready::fem::{elasticity, CholeskySolver, Ordering, Pattern, SparseSym};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or("models/xiaowan_like.toml".into());
    let repeats: usize = args.next().map_or(Ok(5), |a| a.parse())?;
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let (pattern, a) = complete_matrix(&inputs.mesh);
    let n = pattern.n_dofs();
    // A load with every digit in play (not all ones, which may cancel exactly).
    let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.618).sin()).collect();
    let seq = solve(&pattern, &a, &b, faer::Par::Seq)?;
    println!("{path}: n = {n}");
    report("sequential", &seq, &seq, std::slice::from_ref(&seq));
    for t in [1, 2, 4] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build()?;
        let par = faer::Par::rayon(t);
        let runs: Vec<Vec<f64>> = pool.install(|| {
            (0..repeats)
                .map(|_| solve(&pattern, &a, &b, par))
                .collect::<Result<_, _>>()
        })?;
        report(&format!("rayon({t})"), &runs[0], &seq, &runs);
        // Two factorisations at once on the same pool: the tiles of a
        // product go to whichever thread is free first.
        let both: Vec<Vec<f64>> = pool.install(|| {
            let (x, y) = rayon::join(
                || solve(&pattern, &a, &b, par),
                || solve(&pattern, &a, &b, par),
            );
            vec![x.expect("factorises"), y.expect("factorises")]
        });
        let mut all = runs.clone();
        all.extend(both);
        report(&format!("rayon({t}) x2 at once"), &runs[0], &seq, &all);
    }
    Ok(())
}

/// Stiffness of every element (E = 20 GPa, ν = 0.2) with the base fixed.
fn complete_matrix(mesh: &groutready::mesh::Mesh) -> (Arc<Pattern>, SparseSym) {
    let n = 3 * mesh.nodes.len();
    let local: Vec<[u32; 24]> = mesh.elements.iter().map(elasticity::element_dofs).collect();
    let pattern = Arc::new(Pattern::new(n, &local));
    let mut a = SparseSym::new(pattern.clone());
    let d = elasticity::isotropic_d(2e10, 0.2);
    for e in 0..mesh.elements.len() {
        let g = elasticity::gauss_points(&mesh.element_coords(e)).expect("valid element");
        a.add_element(e, &elasticity::stiffness(&g, &d));
    }
    let zmin = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    let fixed: Vec<bool> = (0..n).map(|i| mesh.nodes[i / 3][2] < zmin + 1e-6).collect();
    a.apply_dirichlet(&fixed);
    (pattern, a)
}

fn solve(
    pattern: &Arc<Pattern>,
    a: &SparseSym,
    b: &[f64],
    par: faer::Par,
) -> Result<Vec<f64>, groutready::fem::SolveError> {
    let mut s = CholeskySolver::with_options(pattern.clone(), &Ordering::Amd, par)?;
    s.factorize(a)?;
    let mut x = b.to_vec();
    s.solve_in_place(&mut x)?;
    Ok(x)
}

/// Distinct solutions among `runs` (by bits) and the largest difference of
/// `x` from `reference`, relative to the largest |reference| entry.
fn report(what: &str, x: &[f64], reference: &[f64], runs: &[Vec<f64>]) {
    let distinct: BTreeSet<Vec<u64>> = runs
        .iter()
        .map(|r| r.iter().map(|v| v.to_bits()).collect())
        .collect();
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = x
        .iter()
        .zip(reference)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    println!(
        "{what:24} runs {:2}  distinct {}  max |x - x_seq| / max |x_seq| = {:.2e}",
        runs.len(),
        distinct.len(),
        diff / scale
    );
}
