//! Sparse assembly, Dirichlet elimination and the faer Cholesky wrapper of
//! `groutready::fem`, checked against dense nalgebra computations.

#![allow(clippy::needless_range_loop)]

use crate::common;

use common::Rng;

use std::sync::Arc;
use std::time::Instant;

use faer::Mat;
use groutready::fem::{
    capacity_consistent, capacity_lumped, conductivity, elasticity, face_convection, hex8,
    nested_dissection, relative_residual, volume_load, Capacitance, CholeskySolver, Coupling,
    Ordering, Pattern, PatternError, ReachColumn, SolveError, SparseSym, NO_DOF,
};
use nalgebra::{DMatrix, DVector, SMatrix};

/// Structured hex grid of nx×ny×nz elements (spacing h), interior nodes
/// jittered by `jitter`·h, node → dof through a shuffled numbering.
struct Grid {
    coords: Vec<[f64; 3]>,
    elems: Vec<[u32; 8]>,
    /// (element, local face) on the bottom (z = 0) and top boundaries
    bottom: Vec<(usize, usize)>,
    top: Vec<(usize, usize)>,
    dof: Vec<u32>,
}

fn grid(n: [usize; 3], h: f64, jitter: f64, shuffle: bool, rng: &mut Rng) -> Grid {
    let [nx, ny, nz] = n;
    let id = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let mut coords = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let mut x = [i as f64 * h, j as f64 * h, k as f64 * h];
                let interior = [(i, nx), (j, ny), (k, nz)]
                    .iter()
                    .all(|&(a, m)| a > 0 && a < m);
                if interior && jitter > 0.0 {
                    for v in x.iter_mut() {
                        *v += rng.range(-jitter, jitter) * h;
                    }
                }
                coords.push(x);
            }
        }
    }
    let mut elems = Vec::new();
    let (mut bottom, mut top) = (Vec::new(), Vec::new());
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if k == 0 {
                    bottom.push((elems.len(), 0));
                }
                if k == nz - 1 {
                    top.push((elems.len(), 1));
                }
                elems.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    let mut dof: Vec<u32> = (0..coords.len() as u32).collect();
    if shuffle {
        for a in (1..dof.len()).rev() {
            let b = (rng.next() * (a + 1) as f64) as usize;
            dof.swap(a, b.min(a));
        }
    }
    Grid {
        coords,
        elems,
        bottom,
        top,
        dof,
    }
}

impl Grid {
    fn hex(&self, e: usize) -> [[f64; 3]; 8] {
        self.elems[e].map(|v| self.coords[v as usize])
    }
    fn hex_dofs(&self, e: usize) -> Vec<u32> {
        self.elems[e]
            .iter()
            .map(|&v| self.dof[v as usize])
            .collect()
    }
    fn face_dofs(&self, (e, f): (usize, usize)) -> Vec<u32> {
        hex8::FACES[f]
            .iter()
            .map(|&a| self.dof[self.elems[e][a] as usize])
            .collect()
    }
    fn n_dofs(&self) -> usize {
        self.coords.len()
    }
}

fn add_dense(m: &mut DMatrix<f64>, dofs: &[u32], k: &DMatrix<f64>, alpha: f64) {
    for (a, &da) in dofs.iter().enumerate() {
        for (b, &db) in dofs.iter().enumerate() {
            if da != NO_DOF && db != NO_DOF {
                m[(da as usize, db as usize)] += alpha * k[(a, b)];
            }
        }
    }
}

fn to_dmatrix<const N: usize>(k: &SMatrix<f64, N, N>) -> DMatrix<f64> {
    DMatrix::from_fn(N, N, |i, j| k[(i, j)])
}

/// Thermal step matrix (ρc/dt)·C + K + H on hexes and top faces, both sparse
/// and dense, plus the slot lists.
fn assemble_both(g: &Grid, dt: f64, consistent: bool) -> (SparseSym, DMatrix<f64>) {
    let (lambda, rho_c, beta) = (2.0 * 86400.0, 2.3e6, 10.0 * 86400.0);
    let mut slots: Vec<Vec<u32>> = (0..g.elems.len()).map(|e| g.hex_dofs(e)).collect();
    slots.extend(g.top.iter().map(|&f| g.face_dofs(f)));
    let pattern = Arc::new(Pattern::new(g.n_dofs(), &slots));
    let mut a = SparseSym::new(pattern);
    let mut d = DMatrix::zeros(g.n_dofs(), g.n_dofs());
    for e in 0..g.elems.len() {
        let c = g.hex(e);
        let k = conductivity(&c, lambda).unwrap();
        a.add_element(e, &k);
        add_dense(&mut d, &slots[e], &to_dmatrix(&k), 1.0);
        if consistent {
            let m = capacity_consistent(&c, rho_c).unwrap();
            a.add_element_scaled(e, 1.0 / dt, &m);
            add_dense(&mut d, &slots[e], &to_dmatrix(&m), 1.0 / dt);
        } else {
            let m = capacity_lumped(&c, rho_c).unwrap();
            a.add_element_diag(e, 1.0 / dt, &m);
            add_dense(
                &mut d,
                &slots[e],
                &DMatrix::from_diagonal(&DVector::from_row_slice(&m)),
                1.0 / dt,
            );
        }
    }
    for (s, &(e, f)) in g.top.iter().enumerate() {
        let slot = g.elems.len() + s;
        let (h, _) = face_convection(&hex8::face_coords(&g.hex(e), f), beta).unwrap();
        a.add_element(slot, &h);
        add_dense(&mut d, &slots[slot], &to_dmatrix(&h), 1.0);
    }
    (a, d)
}

/// The unknowns and the elasticity matrix of a jittered, shuffled grid of
/// unit cells of `size` (the setup of the factor's tests).
fn elastic_grid(size: [usize; 3], rng: &mut Rng) -> (usize, SparseSym) {
    let g = grid(size, 1.0, 0.2, true, rng);
    let (a, _) = assemble_both(&g, 1.0, false);
    (g.n_dofs(), a)
}

fn max_abs_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax()
}

#[test]
fn pattern_is_upper_sorted_and_scatter_maps_hit_the_right_entries() {
    let mut rng = Rng(3);
    let g = grid([3, 2, 2], 1.0, 0.2, true, &mut rng);
    let mut slots: Vec<Vec<u32>> = (0..g.elems.len()).map(|e| g.hex_dofs(e)).collect();
    slots.extend(g.bottom.iter().map(|&f| g.face_dofs(f)));
    let p = Pattern::new(g.n_dofs(), &slots);
    assert_eq!(p.n_dofs(), g.n_dofs());
    assert_eq!(p.n_elements(), slots.len());
    for j in 0..p.n_dofs() {
        let rows = &p.row_idx()[p.col_ptr()[j] as usize..p.col_ptr()[j + 1] as usize];
        assert!(
            rows.windows(2).all(|w| w[0] < w[1]),
            "column {j} not sorted"
        );
        assert_eq!(*rows.last().unwrap() as usize, j, "diagonal last");
        assert_eq!(p.diag_index()[j] as usize, p.col_ptr()[j + 1] as usize - 1);
    }
    // a structured hex grid couples exactly the nodes of shared elements:
    // nnz(upper) = (Σ_node #neighbours incl. itself + n) / 2
    let mut dense = DMatrix::<u8>::zeros(p.n_dofs(), p.n_dofs());
    for s in &slots {
        for &a in s {
            for &b in s {
                dense[(a as usize, b as usize)] = 1;
            }
        }
    }
    let full: usize = dense.iter().map(|&v| v as usize).sum();
    assert_eq!(p.nnz(), (full + p.n_dofs()) / 2);
    for (slot, dofs) in slots.iter().enumerate() {
        let sc = p.scatter_index(slot);
        let ne = dofs.len();
        assert_eq!(sc.len(), ne * (ne + 1) / 2);
        assert_eq!(p.element_dofs(slot), &dofs[..]);
        let mut idx = 0;
        for a in 0..ne {
            for b in a..ne {
                let want = p.find(dofs[a] as usize, dofs[b] as usize).unwrap();
                assert_eq!(sc[idx] as usize, want);
                assert_eq!(groutready::fem::sparse::packed_upper_index(ne, a, b), idx);
                idx += 1;
            }
        }
    }
}

/// A node's components share their elements, and the pattern takes the
/// column before's rows for them: the pattern of a vector field (3 dofs a
/// node, some components fixed, a dof no element touches, a repeated node)
/// equals the one gathered column by column by brute force.
#[test]
fn vector_field_patterns_equal_brute_force_column_by_column() {
    let mut rng = Rng(17);
    let g = grid([3, 2, 2], 1.0, 0.2, true, &mut rng);
    let n_nodes = g.n_dofs();
    // node v's components 3v, 3v + 1, 3v + 2; every fifth node's z fixed
    let dof = |v: u32, c: u32| {
        if c == 2 && v.is_multiple_of(5) {
            NO_DOF
        } else {
            3 * v + c
        }
    };
    let mut slots: Vec<Vec<u32>> = (0..g.elems.len())
        .map(|e| {
            let nodes = g.hex_dofs(e);
            nodes
                .iter()
                .flat_map(|&v| (0..3).map(move |c| dof(v, c)))
                .collect()
        })
        .collect();
    // a spring pair repeating one node (both ends on it), and one more dof
    // (3 n_nodes) that no element touches
    slots.push(vec![dof(4, 0), dof(4, 1), dof(4, 0), dof(4, 1)]);
    let n = 3 * n_nodes + 1;
    let p = Pattern::new(n, &slots);
    let mut coupled = vec![std::collections::BTreeSet::new(); n];
    for s in &slots {
        for &a in s.iter().filter(|&&a| a != NO_DOF) {
            for &b in s.iter().filter(|&&b| b != NO_DOF && b <= a) {
                coupled[a as usize].insert(b);
            }
        }
    }
    for (j, rows) in coupled.iter_mut().enumerate() {
        rows.insert(j as u32);
        let got = &p.row_idx()[p.col_ptr()[j] as usize..p.col_ptr()[j + 1] as usize];
        assert_eq!(got, rows.iter().copied().collect::<Vec<_>>(), "column {j}");
    }
    for (slot, dofs) in slots.iter().enumerate() {
        let sc = p.scatter_index(slot);
        let ne = dofs.len();
        let mut idx = 0;
        for a in 0..ne {
            for b in a..ne {
                let want = (dofs[a] != NO_DOF && dofs[b] != NO_DOF)
                    .then(|| p.find(dofs[a] as usize, dofs[b] as usize).unwrap());
                assert_eq!(
                    (sc[idx] != u32::MAX).then_some(sc[idx] as usize),
                    want,
                    "slot {slot} ({a}, {b})"
                );
                idx += 1;
            }
        }
    }
}

#[test]
fn sparse_assembly_equals_dense_assembly() {
    let mut rng = Rng(5);
    let g = grid([3, 3, 2], 0.8, 0.25, true, &mut rng);
    for consistent in [true, false] {
        let (a, d) = assemble_both(&g, 0.5, consistent);
        let scale = d.amax();
        assert!(max_abs_diff(&a.to_dense(), &d) <= 1e-13 * scale);
        let x = DVector::from_fn(g.n_dofs(), |i, _| (i as f64 * 0.37).sin());
        let mut y = vec![0.0; g.n_dofs()];
        a.mul_vec(x.as_slice(), &mut y);
        let yd = &d * &x;
        for i in 0..g.n_dofs() {
            assert!((y[i] - yd[i]).abs() <= 1e-12 * scale);
        }
        let diag = a.diag();
        for i in 0..g.n_dofs() {
            assert_eq!(diag[i], a.get(i, i));
            assert!((diag[i] - d[(i, i)]).abs() <= 1e-13 * scale);
        }
        // set_zero keeps the pattern, re-assembly reproduces the values
        let mut b = a.clone();
        b.set_zero();
        assert!(b.values().iter().all(|&v| v == 0.0));
        b.axpy(2.0, &a);
        assert!(max_abs_diff(&b.to_dense(), &(&d * 2.0)) <= 2e-13 * scale);
    }
}

#[test]
fn repeated_and_missing_dofs_assemble_like_dense() {
    // element 0 repeats dof 1 (a joint pair sharing a thermal dof),
    // element 1 has a node outside the system, dof 6 is touched by no element
    let slots: Vec<Vec<u32>> = vec![vec![0, 1, 1, 2], vec![3, NO_DOF, 4, 0], vec![2, 5, 4, 3]];
    let p = Arc::new(Pattern::new(7, &slots));
    let mut a = SparseSym::new(p.clone());
    let mut d = DMatrix::zeros(7, 7);
    let mut rng = Rng(9);
    for (s, dofs) in slots.iter().enumerate() {
        let r = DMatrix::from_fn(4, 4, |_, _| rng.range(-1.0, 1.0));
        let k = &r * r.transpose();
        a.add_element(s, &k);
        add_dense(&mut d, dofs, &k, 1.0);
    }
    assert!(max_abs_diff(&a.to_dense(), &d) < 1e-15);
    assert_eq!(p.find(6, 6), Some(p.diag_index()[6] as usize));
    assert_eq!(p.find(0, 6), None);
    assert_eq!(a.get(6, 6), 0.0);
}

/// A symmetric element matrix by its packed upper triangle assembles the
/// same bits as the full matrix, repeated and missing dofs included.
#[test]
fn packed_element_matrices_assemble_like_full_ones_to_the_bit() {
    let slots: Vec<Vec<u32>> = vec![vec![0, 1, 1, 2], vec![3, NO_DOF, 4, 0], vec![2, 5, 4, 3]];
    let p = Arc::new(Pattern::new(7, &slots));
    let (mut full, mut packed) = (SparseSym::new(p.clone()), SparseSym::new(p.clone()));
    let mut rng = Rng(11);
    for s in 0..slots.len() {
        let r = DMatrix::from_fn(4, 4, |_, _| rng.range(-1.0, 1.0));
        let k = &r * r.transpose();
        let k = (&k + k.transpose()) * 0.5;
        let upper: Vec<f64> = (0..4)
            .flat_map(|a| (a..4).map(move |b| (a, b)))
            .map(|(a, b)| k[(a, b)])
            .collect();
        full.add_element_scaled(s, 2.5e10, &k);
        packed.add_packed_scaled(s, 2.5e10, &upper);
    }
    assert_eq!(full.values(), packed.values());
    // the hex8's packed stiffness reads back as the full one
    let unit = [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];
    let c: [[f64; 3]; 8] = std::array::from_fn(|i| {
        let [x, y, _] = unit[i % 4];
        let z = (i / 4) as f64;
        [x + 0.1 * y, y + 0.05 * z, z + 0.2 * x * y]
    });
    let k = groutready::fem::elasticity::stiffness_of(&c, 1.0, 0.2).unwrap();
    let pk = groutready::fem::elasticity::PackedSym24::from_upper(&k);
    assert_eq!(pk.to_full(), k);
}

#[test]
fn pattern_rejects_out_of_range_dofs() {
    let slots = [[0u32, 1, 5]];
    assert_eq!(
        Pattern::try_new(5, &slots).unwrap_err(),
        PatternError::DofOutOfRange {
            slot: 0,
            dof: 5,
            n_dofs: 5
        }
    );
}

#[test]
fn dirichlet_elimination_equals_dense_reduced_solution() {
    let mut rng = Rng(11);
    let g = grid([4, 3, 3], 1.5, 0.2, true, &mut rng);
    let n = g.n_dofs();
    let (mut a, d) = assemble_both(&g, 2.0, true);
    // bottom face held at a prescribed field, a source in the volume, top convection to Ta
    let mut fixed = vec![false; n];
    let mut u = vec![0.0; n];
    for &(e, f) in &g.bottom {
        for &ln in &hex8::FACES[f] {
            let node = g.elems[e][ln] as usize;
            let dof = g.dof[node] as usize;
            fixed[dof] = true;
            u[dof] = 12.0 + 0.3 * g.coords[node][0] - 0.2 * g.coords[node][1];
        }
    }
    let mut rhs = vec![0.0; n];
    for e in 0..g.elems.len() {
        let q = volume_load(&g.hex(e), 2.3e6 * 0.8).unwrap();
        for (a_, &dof) in g.hex_dofs(e).iter().enumerate() {
            rhs[dof as usize] += q[a_];
        }
    }
    for &(e, f) in &g.top {
        let (_, h) = face_convection(&hex8::face_coords(&g.hex(e), f), 10.0 * 86400.0).unwrap();
        for (a_, &dof) in g.face_dofs((e, f)).iter().enumerate() {
            rhs[dof as usize] += 5.0 * h[a_];
        }
    }
    let rhs_orig = rhs.clone();
    a.apply_dirichlet_with_rhs(&fixed, &u, &mut rhs);
    // the eliminated matrix: fixed rows/cols are unit vectors
    let ad = a.to_dense();
    for i in 0..n {
        for j in 0..n {
            if fixed[i] || fixed[j] {
                assert_eq!(ad[(i, j)], if i == j { 1.0 } else { 0.0 });
            }
        }
    }
    let mut solver = CholeskySolver::new(a.pattern().clone()).unwrap();
    solver.factorize(&a).unwrap();
    let mut x = rhs.clone();
    solver.solve_in_place(&mut x).unwrap();
    assert!(relative_residual(&a, &x, &rhs) < 1e-12);
    // dense reduced system K_ff x_f = f_f − K_fc u_c
    let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
    let fix: Vec<usize> = (0..n).filter(|&i| fixed[i]).collect();
    let kff = DMatrix::from_fn(free.len(), free.len(), |i, j| d[(free[i], free[j])]);
    let kfc = DMatrix::from_fn(free.len(), fix.len(), |i, j| d[(free[i], fix[j])]);
    let uc = DVector::from_fn(fix.len(), |i, _| u[fix[i]]);
    let ff = DVector::from_fn(free.len(), |i, _| rhs_orig[free[i]]);
    let xf = kff.cholesky().unwrap().solve(&(ff - kfc * uc));
    for (k, &i) in free.iter().enumerate() {
        assert!(
            (x[i] - xf[k]).abs() <= 1e-11 * xf.amax(),
            "dof {i}: {} vs {}",
            x[i],
            xf[k]
        );
    }
    for &i in &fix {
        assert_eq!(x[i], u[i]);
    }
    // and the full (unmodified) system is satisfied on the free rows
    let xv = DVector::from_row_slice(&x);
    let r = &d * &xv;
    for &i in &free {
        assert!((r[i] - rhs_orig[i]).abs() <= 1e-10 * DVector::from_row_slice(&rhs_orig).amax());
    }
}

#[test]
fn cholesky_solves_assembled_spd_system_single_and_multi_rhs() {
    let mut rng = Rng(13);
    let g = grid([6, 5, 4], 1.0, 0.25, true, &mut rng);
    let n = g.n_dofs();
    let (a, _) = assemble_both(&g, 1.0, true);
    let mut solver = CholeskySolver::new(a.pattern().clone()).unwrap();
    assert!(!solver.is_factorized());
    assert_eq!(
        solver.solve_in_place(&mut vec![1.0; n]),
        Err(SolveError::NotFactorized)
    );
    solver.factorize(&a).unwrap();
    assert!(solver.factor_nnz() >= a.pattern().nnz());
    let mut b = Mat::<f64>::zeros(n, 3);
    for j in 0..3 {
        for i in 0..n {
            b[(i, j)] = rng.range(-1.0, 1.0) * 1e5;
        }
    }
    let mut x = b.clone();
    solver.solve_columns(&mut x).unwrap();
    for j in 0..3 {
        let bj: Vec<f64> = (0..n).map(|i| b[(i, j)]).collect();
        let xj: Vec<f64> = (0..n).map(|i| x[(i, j)]).collect();
        let res = relative_residual(&a, &xj, &bj);
        assert!(res < 1e-12, "column {j}: residual {res:e}");
        let mut single = bj.clone();
        solver.solve_in_place(&mut single).unwrap();
        for i in 0..n {
            assert!(
                (single[i] - xj[i]).abs() <= 1e-14 * xj.iter().fold(0.0f64, |m, v| m.max(v.abs()))
            );
        }
    }
    let s = solver.stats();
    assert_eq!(
        (s.n_symbolic, s.n_numeric, s.n_solves, s.n_rhs),
        (1, 1, 4, 6)
    );
}

#[test]
fn symbolic_factorization_is_reused_across_numeric_matrices() {
    let mut rng = Rng(17);
    let g = grid([5, 4, 4], 1.0, 0.2, false, &mut rng);
    let n = g.n_dofs();
    let (a1, _) = assemble_both(&g, 0.25, true);
    // a second matrix on the same pattern, built from a separately constructed
    // (structurally equal) pattern, with other values
    let (mut a2, _) = assemble_both(&g, 5.0, false);
    for v in a2.values_mut() {
        *v *= 3.0;
    }
    let mut solver = CholeskySolver::new(a1.pattern().clone()).unwrap();
    let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
    for a in [&a1, &a2] {
        solver.factorize(a).unwrap();
        let mut x = b.clone();
        solver.solve_in_place(&mut x).unwrap();
        let res = relative_residual(a, &x, &b);
        assert!(res < 1e-12, "residual {res:e}");
    }
    let s = solver.stats();
    assert_eq!((s.n_symbolic, s.n_numeric, s.n_solves), (1, 2, 2));
    assert!(s.symbolic_seconds >= 0.0 && s.numeric_seconds > 0.0 && s.solve_seconds > 0.0);
}

#[test]
fn solver_reports_errors_instead_of_nan() {
    let slots = vec![vec![0u32, 1, 2, 3], vec![2, 3, 4, 5]];
    let p = Arc::new(Pattern::new(7, &slots));
    let mut a = SparseSym::new(p.clone());
    let k = DMatrix::from_fn(4, 4, |i, j| if i == j { 4.0 } else { -1.0 });
    a.add_element(0, &k);
    a.add_element(1, &k);
    a.add_diag(6, -2.0); // an isolated dof with a negative pivot
    let mut solver = CholeskySolver::new(p.clone()).unwrap();
    match solver.factorize(&a) {
        Err(SolveError::NotPositiveDefinite { dof, .. }) => assert_eq!(dof, 6),
        other => panic!("expected NotPositiveDefinite, got {other:?}"),
    }
    assert!(!solver.is_factorized());
    a.add_diag(6, 3.0);
    solver.factorize(&a).unwrap();
    let mut b = vec![1.0; 7];
    b[3] = f64::NAN;
    assert_eq!(
        solver.solve_in_place(&mut b),
        Err(SolveError::NonFinite {
            what: "right-hand side",
            index: 3
        })
    );
    assert!(matches!(
        solver.solve_in_place(&mut [1.0; 3]),
        Err(SolveError::DimensionMismatch {
            expected: 7,
            got: 3
        })
    ));
    let mut bad = a.clone();
    bad.values_mut()[0] = f64::INFINITY;
    assert!(matches!(
        solver.factorize(&bad),
        Err(SolveError::NonFinite { what: "matrix", .. })
    ));
    let other = Arc::new(Pattern::new(7, &[vec![0u32, 6]]));
    let mut c = SparseSym::new(other);
    for i in 0..7 {
        c.add_diag(i, 1.0);
    }
    assert_eq!(solver.factorize(&c), Err(SolveError::PatternMismatch));
}

#[test]
fn nested_dissection_is_a_permutation_and_gives_the_same_solution() {
    let mut rng = Rng(23);
    let g = grid([7, 6, 5], 1.0, 0.2, true, &mut rng);
    let n = g.n_dofs();
    let (a, _) = assemble_both(&g, 1.0, false);
    let mut dof_coords = vec![[0.0; 3]; n];
    for (node, &d) in g.dof.iter().enumerate() {
        dof_coords[d as usize] = g.coords[node];
    }
    let nd = nested_dissection(a.pattern(), &dof_coords, 8);
    let mut seen = vec![false; n];
    for &d in &nd {
        assert!(!seen[d as usize]);
        seen[d as usize] = true;
    }
    assert_eq!(nd.len(), n);
    let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
    let mut xs = Vec::new();
    for ordering in [Ordering::Amd, Ordering::Custom(nd.clone()), Ordering::Metis] {
        let mut solver =
            CholeskySolver::with_options(a.pattern().clone(), &ordering, faer::Par::Seq).unwrap();
        solver.factorize(&a).unwrap();
        let mut x = b.clone();
        solver.solve_in_place(&mut x).unwrap();
        assert!(relative_residual(&a, &x, &b) < 1e-12);
        xs.push(x);
    }
    let scale = xs[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for other in &xs[1..] {
        assert!(xs[0]
            .iter()
            .zip(other)
            .all(|(p, q)| (p - q).abs() <= 1e-12 * scale));
    }
    let metis = groutready::fem::metis_nested_dissection(a.pattern()).unwrap();
    let mut sorted = metis.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..n as u32).collect::<Vec<_>>(),
        "METIS gives a permutation"
    );
    assert_eq!(
        metis,
        groutready::fem::metis_nested_dissection(a.pattern()).unwrap(),
        "METIS is deterministic"
    );
    let mut not_perm = nd.clone();
    not_perm[0] = not_perm[1];
    assert!(matches!(
        CholeskySolver::with_options(
            a.pattern().clone(),
            &Ordering::Custom(not_perm),
            faer::Par::Seq
        ),
        Err(SolveError::InvalidOrdering { .. })
    ));
}

/// The capacitance correction of a changed Dirichlet set, on the factor
/// of the old set, equals a fresh factorisation of the changed system to
/// round-off: rows newly fixed, rows released, and both, with prescribed
/// values on every fixed row. A second solve whose changes it has met
/// needs no new column.
/// On a simplicial factor (a small grid, AMD) and a supernodal one (a
/// larger grid, METIS), whose reach solves walk different blocks.
#[test]
fn capacitance_correction_equals_a_fresh_factorisation() {
    for (size, ordering, supernodal) in [
        ([6, 5, 4], Ordering::Amd, false),
        ([18, 16, 14], Ordering::Metis, true),
    ] {
        capacitance_correction_on_grid(size, ordering, supernodal);
    }
}

fn capacitance_correction_on_grid(size: [usize; 3], ordering: Ordering, supernodal: bool) {
    let mut rng = Rng(31);
    let g = grid(size, 1.0, 0.2, true, &mut rng);
    let n = g.n_dofs();
    let (a, base, solver) = base_factor(&g, &ordering);
    let presc: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
    let rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
    assert_eq!(solver.is_supernodal(), supernodal, "{size:?}");
    let mut cap = Capacitance::new(base.clone());
    let fix_more = |i: usize| base[i] || i % 7 == 1;
    let release = |i: usize| base[i] && !i.is_multiple_of(10);
    let both = |i: usize| (base[i] && !i.is_multiple_of(10)) || i % 7 == 1;
    let cases: [(&str, &dyn Fn(usize) -> bool); 4] = [
        ("fixed", &fix_more),
        ("released", &release),
        ("both", &both),
        ("unchanged", &|i| base[i]),
    ];
    for (name, rule) in cases {
        let fixed: Vec<bool> = (0..n).map(rule).collect();
        let mut m1 = a.clone();
        let mut rhs1 = rhs.clone();
        m1.apply_dirichlet_with_rhs(&fixed, &presc, &mut rhs1);
        let x_ref = fresh_solution(&m1, &rhs1);
        let columns = cap.stats.columns;
        let corrected = cap
            .solve(&solver, &a, &fixed, &presc, &rhs, &[], Default::default())
            .unwrap();
        let x = corrected.x;
        let (diff, scale) = max_difference(&x, &x_ref);
        let changed = cap.changes(&a, &fixed).len();
        eprintln!(
            "{name}: {changed} changed rows, max difference {:.2e} of {scale:.3e}",
            diff
        );
        assert!(
            diff <= 1e-11 * scale,
            "{name}: differs by {diff:.3e} (scale {scale:.3e})"
        );
        let res = relative_residual(&m1, &x, &rhs1);
        assert!(res < 1e-12, "{name}");
        // the residual without forming the constrained matrix measures the same
        let unformed = |x: &[f64]| {
            groutready::fem::capacitance::constrained_residual(&a, &fixed, &presc, &rhs, x)
        };
        assert!(unformed(&x) < 1e-12, "{name}");
        // the residual the correction returns is the same quantity
        assert!(
            (corrected.residual - unformed(&x)).abs() <= 1e-14,
            "{name}: {:e} vs {:e}",
            corrected.residual,
            unformed(&x)
        );
        // the product the correction returns is A x of its answer, and the
        // held residual measured with it (rhs − A x free, presc − x held)
        // is the same quantity again
        let mut ax = vec![0.0; n];
        a.mul_vec(&x, &mut ax);
        assert_eq!(corrected.ax, ax, "{name}");
        let b = groutready::fem::capacitance::constrained_rhs(&a, &fixed, &presc, &rhs);
        let (held, held_norm, held_ax) =
            groutready::fem::capacitance::held_residual(&a, &fixed, &presc, &rhs, &b, &x);
        assert_eq!(held_ax, ax, "{name}");
        assert!(
            (held - unformed(&x)).abs() <= 1e-14 && (held - corrected.residual).abs() <= 1e-14,
            "{name}: {held:e} vs {:e} and {:e}",
            unformed(&x),
            corrected.residual
        );
        let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((held_norm / b_norm - held).abs() <= 1e-12 * held, "{name}");
        let mut off = x.clone();
        off[1] += 0.1;
        off[2] -= 0.2;
        let (formed, unformed) = (relative_residual(&m1, &off, &rhs1), unformed(&off));
        assert!(
            (formed - unformed).abs() <= 1e-10 * formed,
            "{name}: {formed:e} vs {unformed:e}"
        );
        // refined from another solution of the same system: none when the
        // target is loose (the start is returned), to the tight target
        // otherwise (the contact passes refine their answer so)
        let solve_from = |cap: &mut Capacitance, to: f64, from: &[f64]| {
            let refine = groutready::fem::Refine {
                to,
                from: Some(from.to_vec()),
            };
            cap.solve(&solver, &a, &fixed, &presc, &rhs, &[], refine)
                .unwrap()
        };
        let mut start = x.clone();
        for i in (0..n).filter(|&i| !fixed[i]).step_by(5) {
            start[i] *= 1.0 + 1e-6;
        }
        let refinements = cap.stats.refinements;
        let kept = solve_from(&mut cap, 1.0, &start);
        assert_eq!(kept.x, start, "{name}");
        let off_residual = relative_residual(&m1, &start, &rhs1);
        assert!(off_residual > 1e-9, "{name}: {off_residual:e}");
        assert!((kept.residual - off_residual).abs() <= 1e-6 * off_residual);
        assert_eq!(cap.stats.refinements, refinements, "{name}");
        let refined = solve_from(&mut cap, groutready::fem::REFINE_TO, &start);
        assert!(refined.residual <= 1e-12, "{name}: {:e}", refined.residual);
        assert!(relative_residual(&m1, &refined.x, &rhs1) <= 1e-12, "{name}");
        assert!(cap.stats.refinements > refinements, "{name}");
        let (diff, scale) = max_difference(&refined.x, &x_ref);
        assert!(diff <= 1e-11 * scale, "{name}: {diff:e}");
        if name == "both" {
            assert!(changed > 20, "the case changes rows both ways");
            assert_eq!(
                cap.stats.columns, columns,
                "every change was met by the first two cases"
            );
        }
    }
}

/// The first application of a correction, before any refinement, is as
/// accurate as a fresh factorisation's solve on an elastic matrix of
/// concrete's stiffness: the capacitance matrix then mixes stiffnesses
/// (released rows, 1e10 N/m) and compliances (newly fixed rows, 1e−10
/// m/N), and its LU is equilibrated by its diagonal. Without the
/// equilibration this grid's first application leaves 4.4e−11 (9.3e−16
/// with it, a fresh solve 5.8e−16).
#[test]
fn capacitance_first_application_is_accurate_on_mixed_units() {
    let mut rng = Rng(47);
    let g = grid([10, 9, 8], 1.5, 0.2, true, &mut rng);
    let n = 3 * g.coords.len();
    let dofs: Vec<[u32; 24]> = g.elems.iter().map(elasticity::element_dofs).collect();
    let mut a = SparseSym::new(Arc::new(Pattern::new(n, &dofs)));
    for e in 0..g.elems.len() {
        a.add_element(
            e,
            &elasticity::stiffness_of(&g.hex(e), 2.5e10, 0.2).unwrap(),
        );
    }
    let on_base = |i: usize| g.coords[i / 3][2] == 0.0;
    let base: Vec<bool> = (0..n).map(|i| on_base(i) || i % 5 == 0).collect();
    let mut m0 = a.clone();
    m0.apply_dirichlet(&base);
    let mut solver =
        CholeskySolver::with_options(a.pattern().clone(), &Ordering::Metis, faer::Par::Seq)
            .unwrap();
    solver.factorize(&m0).unwrap();
    let presc: Vec<f64> = (0..n).map(|_| rng.range(-1e-3, 1e-3)).collect();
    let rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
    let fixed: Vec<bool> = (0..n)
        .map(|i| on_base(i) || (base[i] && i % 3 != 0) || i % 11 == 4)
        .collect();
    let mut cap = Capacitance::new(base);
    let no_refinement = groutready::fem::Refine {
        to: 1.0,
        from: None,
    };
    let first = cap
        .solve(&solver, &a, &fixed, &presc, &rhs, &[], no_refinement)
        .unwrap();
    let changed = cap.changes(&a, &fixed);
    let released = changed
        .iter()
        .filter(|c| c.1 == groutready::fem::RowChange::Released)
        .count();
    assert!(
        released > 50 && changed.len() - released > 50,
        "{released} of {}",
        changed.len()
    );
    assert_eq!(cap.stats.refinements, 0);
    let mut m1 = a.clone();
    let mut rhs1 = rhs.clone();
    m1.apply_dirichlet_with_rhs(&fixed, &presc, &mut rhs1);
    let fresh = fresh_solution(&m1, &rhs1);
    let (fresh_res, res) = (relative_residual(&m1, &fresh, &rhs1), first.residual);
    eprintln!(
        "{} changed rows ({released} released): first application {res:.2e}, fresh solve {fresh_res:.2e}",
        changed.len()
    );
    assert!(
        res <= 1e-13,
        "first application {res:e} (a fresh solve {fresh_res:e})"
    );
    let (diff, scale) = max_difference(&first.x, &fresh);
    assert!(diff <= 1e-11 * scale, "differs by {diff:e} of {scale:e}");
}

/// Couplings (loads on free rows proportional to a row of A x, as a
/// slipping joint point's friction force μ_k r_n s on its tangential rows)
/// bordered on the factor of another fixed set equal the coupled system
/// solved another way: a fresh factorisation of the new set, one solve per
/// coupling's loads and a dense k × k system for the reactions. Reaction
/// and load rows are drawn free in the base, released and held, on a
/// simplicial and a supernodal factor; the LU of S is reused for another
/// load and remade for other coefficients.
#[test]
fn capacitance_couplings_equal_the_coupled_system_solved_directly() {
    for (size, ordering) in [([6, 5, 4], Ordering::Amd), ([12, 10, 8], Ordering::Metis)] {
        let mut rng = Rng(43);
        let g = grid(size, 1.0, 0.2, true, &mut rng);
        let n = g.n_dofs();
        let (a, base, solver) = base_factor(&g, &ordering);
        let presc: Vec<f64> = (0..n).map(|_| rng.range(-1e-3, 1e-3)).collect();
        let rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
        let mut cap = Capacitance::new(base.clone());
        let fixed: Vec<bool> = (0..n)
            .map(|i| (base[i] && !i.is_multiple_of(10)) || i % 7 == 1)
            .collect();
        let pick = |rng: &mut Rng| ((rng.next() * n as f64) as usize).min(n - 1) as u32;
        let mut couplings: Vec<Coupling> = (0..12)
            .map(|_| Coupling {
                reaction_row: pick(&mut rng),
                loads: vec![
                    (pick(&mut rng), rng.range(-0.6, 0.6)),
                    (pick(&mut rng), rng.range(-0.6, 0.6)),
                ],
            })
            .collect();
        // a released load row and reaction row, a held reaction row, a
        // load on a held row (dropped)
        let released = (0..n).find(|&i| base[i] && !fixed[i]).unwrap() as u32;
        let held = (0..n).find(|&i| fixed[i]).unwrap() as u32;
        couplings[0].loads[0].0 = released;
        couplings[1].reaction_row = released;
        couplings[2].reaction_row = held;
        couplings[3].loads[1].0 = held;
        let other_rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
        let mut scaled = couplings.clone();
        scaled.iter_mut().for_each(|c| c.loads[0].1 *= 0.5);
        for (name, load, coupled, new_lu) in [
            ("coupled", &rhs, &couplings, 1),
            ("another load", &other_rhs, &couplings, 0),
            ("other coefficients", &rhs, &scaled, 1),
        ] {
            let x_ref = coupled_reference(&a, &fixed, &presc, load, coupled);
            let lus = cap.stats.s_factorisations;
            let corrected = cap
                .solve(
                    &solver,
                    &a,
                    &fixed,
                    &presc,
                    load,
                    coupled,
                    Default::default(),
                )
                .unwrap();
            let (diff, scale) = max_difference(&corrected.x, &x_ref);
            eprintln!(
                "{size:?} {name}: max difference {diff:.2e} of {scale:.3e}, residual {:.2e}",
                corrected.residual
            );
            assert!(
                diff <= 1e-10 * scale,
                "{size:?} {name}: {diff:e} of {scale:e}"
            );
            assert!(corrected.residual < 1e-12, "{size:?} {name}");
            assert_eq!(cap.stats.s_factorisations - lus, new_lu, "{size:?} {name}");
        }
    }
}

/// The elasticity matrix of `g`, the base fixed set (every 5th row) and
/// the factor of the matrix with it held, in `ordering`.
fn base_factor(g: &Grid, ordering: &Ordering) -> (SparseSym, Vec<bool>, CholeskySolver) {
    let n = g.n_dofs();
    let (a, _) = assemble_both(g, 1.0, false);
    let base: Vec<bool> = (0..n).map(|i| i.is_multiple_of(5)).collect();
    let mut m0 = a.clone();
    m0.apply_dirichlet(&base);
    let mut solver =
        CholeskySolver::with_options(a.pattern().clone(), ordering, faer::Par::Seq).unwrap();
    solver.factorize(&m0).unwrap();
    (a, base, solver)
}

/// The coupled system x = M⁻¹(b + G z), z = V x (M, b: A and `rhs` with
/// `fixed` held at `presc`; G the couplings' loads on free rows, V their
/// reaction rows of A) by a fresh factorisation of M, a solve per coupling
/// and the dense k × k system (I − V M⁻¹G) z = V M⁻¹b.
fn coupled_reference(
    a: &SparseSym,
    fixed: &[bool],
    presc: &[f64],
    rhs: &[f64],
    couplings: &[Coupling],
) -> Vec<f64> {
    let n = a.n();
    let mut m = a.clone();
    let mut b = rhs.to_vec();
    m.apply_dirichlet_with_rhs(fixed, presc, &mut b);
    let mut fresh =
        CholeskySolver::with_options(m.pattern().clone(), &Ordering::Amd, faer::Par::Seq).unwrap();
    fresh.factorize(&m).unwrap();
    let solve = |mut v: Vec<f64>| {
        fresh.solve_in_place(&mut v).unwrap();
        v
    };
    let x0 = solve(b);
    let xg: Vec<Vec<f64>> = couplings
        .iter()
        .map(|c| {
            let mut g = vec![0.0; n];
            for &(t, coef) in &c.loads {
                if !fixed[t as usize] {
                    g[t as usize] += coef;
                }
            }
            solve(g)
        })
        .collect();
    let row = |c: &Coupling, x: &[f64]| {
        let mut v = 0.0;
        a.column(c.reaction_row as usize, |j, aj| v += aj * x[j]);
        v
    };
    let k = couplings.len();
    let lhs = DMatrix::from_fn(k, k, |q, p| {
        (if q == p { 1.0 } else { 0.0 }) - row(&couplings[q], &xg[p])
    });
    let r = DVector::from_fn(k, |q, _| row(&couplings[q], &x0));
    let z = lhs.lu().solve(&r).unwrap();
    (0..n)
        .map(|i| x0[i] + (0..k).map(|p| z[p] * xg[p][i]).sum::<f64>())
        .collect()
}

/// The forward half then the backward half is a solve; a reach column
/// (the forward half of a right-hand side with few entries, computed on
/// its reach only) equals the dense forward half of the same vector, which
/// is exactly zero outside that reach; on a simplicial and a supernodal
/// factor.
#[test]
fn half_solves_compose_to_a_solve_and_reach_columns_equal_forward_halves() {
    for (size, ordering, supernodal) in [
        ([6, 5, 4], Ordering::Amd, false),
        ([18, 16, 14], Ordering::Metis, true),
    ] {
        let mut rng = Rng(41);
        let (n, a) = elastic_grid(size, &mut rng);
        let mut solver =
            CholeskySolver::with_options(a.pattern().clone(), &ordering, faer::Par::Seq).unwrap();
        let mut work = groutready::fem::ReachWork::default();
        assert_eq!(
            solver.forward_reach(&[(0, 1.0)], &mut work),
            Err(SolveError::NotFactorized)
        );
        solver.factorize(&a).unwrap();
        assert_eq!(solver.is_supernodal(), supernodal, "{size:?}");
        let b: Vec<f64> = (0..n).map(|_| rng.range(-1e5, 1e5)).collect();
        let mut full = b.clone();
        solver.solve_in_place(&mut full).unwrap();
        let mut halves = b.clone();
        solver.forward_in_place(&mut halves).unwrap();
        solver.backward_in_place(&mut halves).unwrap();
        let (diff, scale) = max_difference(&halves, &full);
        assert!(diff <= 1e-13 * scale, "{size:?}: {diff:e} of {scale:e}");
        // unit vectors and a column of the matrix
        let mut column = Vec::new();
        a.column(n / 2, |i, v| column.push((i, v)));
        let mut reach_rows = Vec::new();
        let columns = vec![
            vec![(0, 1.0)],
            vec![(n - 1, -2.5)],
            vec![(n / 3, 1.0)],
            column,
        ];
        // solved together: each on its own reach, its single solve's values
        let batch = solver.forward_reach_many(&columns, &mut work).unwrap();
        assert_each_its_single_solve(&solver, &columns, &batch, &format!("{size:?}"));
        for entries in columns {
            let y = solver.forward_reach(&entries, &mut work).unwrap();
            let mut dense = vec![0.0; n];
            for &(i, v) in &entries {
                dense[i] += v;
            }
            solver.forward_in_place(&mut dense).unwrap();
            let reach = y.to_dense(n);
            let (diff, scale) = max_difference(&reach, &dense);
            assert!(diff <= 1e-13 * scale, "{size:?}: {diff:e} of {scale:e}");
            let mut inside = vec![false; n];
            y.rows().for_each(|k| inside[k] = true);
            let outside = (0..n).filter(|&k| !inside[k] && dense[k] != 0.0).count();
            assert_eq!(
                outside, 0,
                "{size:?}: the forward half is zero outside the reach"
            );
            // a reach column's products are the dense ones
            assert!(
                (y.dot(&y) - dense.iter().map(|v| v * v).sum::<f64>()).abs() <= 1e-12 * y.dot(&y)
            );
            assert!((y.dot_dense(&dense) - y.dot(&y)).abs() <= 1e-12 * y.dot(&y));
            reach_rows.push(y.len());
        }
        eprintln!(
            "{size:?} (supernodal {supernodal}): {n} rows, reach columns of {reach_rows:?} rows"
        );
        if supernodal {
            assert!(
                reach_rows.iter().all(|&r| r < n / 2),
                "a reach is a part of the factor: {reach_rows:?} of {n}"
            );
        }
        let s = solver.stats();
        assert_eq!(s.n_reach_columns, 12);
    }
}

/// A product of a matrix past `PAR_PRODUCT_ENTRIES` (swept on two
/// threads, its columns cut in two halves) equals the sum of its columns
/// entry by entry, and the entrywise-absolute product too; the same bits on
/// every call.
#[test]
fn products_on_two_threads_equal_the_columns_summed() {
    let mut rng = Rng(47);
    let g = grid([70, 70, 70], 1.0, 0.2, true, &mut rng);
    let n = g.n_dofs();
    let slots: Vec<Vec<u32>> = (0..g.elems.len()).map(|e| g.hex_dofs(e)).collect();
    let pattern = Arc::new(Pattern::new(n, &slots));
    assert!(pattern.nnz() >= groutready::fem::sparse::PAR_PRODUCT_ENTRIES);
    let mut a = SparseSym::new(pattern);
    for e in 0..g.elems.len() {
        a.add_element(e, &conductivity(&g.hex(e), 2.0 * 86400.0).unwrap());
    }
    let x: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
    let (mut y, mut y_abs) = (vec![0.0; n], vec![0.0; n]);
    a.mul_vec(&x, &mut y);
    a.abs_mul_vec(&x, &mut y_abs);
    let (mut worst, mut worst_abs) = (0.0f64, 0.0f64);
    for i in 0..n {
        let (mut r, mut r_abs, mut size) = (0.0, 0.0, 0.0);
        a.column(i, |j, v| {
            r += v * x[j];
            r_abs += v.abs() * x[j].abs();
            size += (v * x[j]).abs();
        });
        worst = worst.max((y[i] - r).abs() / size.max(f64::MIN_POSITIVE));
        worst_abs = worst_abs.max((y_abs[i] - r_abs).abs() / r_abs.max(f64::MIN_POSITIVE));
    }
    eprintln!("{n} rows: worst relative {worst:e}, absolute product {worst_abs:e}");
    assert!(worst < 1e-14 && worst_abs < 1e-14);
    let mut again = vec![0.0; n];
    a.mul_vec(&x, &mut again);
    assert_eq!(again, y);
}

/// A factor made on two cores and solved by sweeps on two cores, the
/// elimination tree cut into two forests and the blocks above them
/// (`fem::two_cores`), equals faer's to round-off, whole and in halves;
/// with the supports held (roots of their own) and without; the cuts put
/// most of the work on the two sides, about evenly; the same bits on
/// every call; and a matrix that is not positive definite is refused with
/// its pivot, as on one core.
#[test]
fn factor_and_sweeps_on_two_cores_equal_faers() {
    let mut rng = Rng(43);
    let (n, a) = elastic_grid([18, 16, 14], &mut rng);
    let base: Vec<bool> = (0..n).map(|i| i % 97 == 0).collect();
    let mut m = a.clone();
    m.apply_dirichlet(&base);
    for held in [false, true] {
        let make = || {
            let pattern = a.pattern().clone();
            let par = faer::Par::rayon(2);
            let mut s = if held {
                CholeskySolver::with_held(pattern, &Ordering::Metis, par, &base).unwrap()
            } else {
                CholeskySolver::with_options(pattern, &Ordering::Metis, par).unwrap()
            };
            s.factorize(&m).unwrap();
            s
        };
        let one = make();
        let mut two = make();
        assert!(
            one.is_supernodal() && one.sweep_split().is_none(),
            "small: one core"
        );
        two.on_two_cores();
        two.factorize(&m).unwrap();
        // the factorisation's top runs on both cores: a larger part of it
        for (what, [top, left, right], most) in [
            ("entries", two.sweep_split().unwrap(), 0.25),
            ("flops", two.factor_split().unwrap(), 0.6),
        ] {
            let total = (top + left + right) as f64;
            eprintln!("held {held}: top {top}, sides {left} and {right} {what}");
            assert!(
                (top as f64) < most * total,
                "{what}: the top is a small part"
            );
            assert!(
                left.abs_diff(right) as f64 <= 0.25 * total,
                "{what}: the sides about even"
            );
            assert!(left > 0 && right > 0);
        }
        let b: Vec<f64> = (0..n).map(|_| rng.range(-1e5, 1e5)).collect();
        let (mut x1, mut x2) = (b.clone(), b.clone());
        one.solve_in_place(&mut x1).unwrap();
        two.solve_in_place(&mut x2).unwrap();
        let (diff, scale) = max_difference(&x2, &x1);
        assert!(diff <= 1e-13 * scale, "held {held}: {diff:e} of {scale:e}");
        let mut halves = b.clone();
        two.forward_in_place(&mut halves).unwrap();
        two.backward_in_place(&mut halves).unwrap();
        let (diff, scale) = max_difference(&halves, &x1);
        assert!(
            diff <= 1e-13 * scale,
            "held {held}, halves: {diff:e} of {scale:e}"
        );
        // the same cut gives the same bits on every call
        let mut again = b.clone();
        two.solve_in_place(&mut again).unwrap();
        assert_eq!(again, x2);
        let res = groutready::fem::relative_residual(&m, &x2, &b);
        assert!(res < 1e-12, "held {held}: residual {res:e}");
        // factorised again: the same bits
        two.factorize(&m).unwrap();
        let mut again = b.clone();
        two.solve_in_place(&mut again).unwrap();
        assert_eq!(again, x2);
        // not positive definite: the same pivot refused as on one core
        let mut bad = m.clone();
        let k = n / 2 + 1;
        bad.add_diag(k, -1e3 * bad.diag()[k]);
        let (mut e1, mut e2) = (one.fork().unwrap(), two.fork().unwrap());
        let r1 = e1.factorize(&bad).unwrap_err();
        let r2 = e2.factorize(&bad).unwrap_err();
        assert!(
            matches!(r2, SolveError::NotPositiveDefinite { .. }),
            "{r2:?}"
        );
        assert_eq!(r1.pivot_dof(), r2.pivot_dof(), "held {held}");
    }
}

/// The products of reach columns computed block by block (`gram`, what
/// the capacitance matrices use) equal the products pair by pair, on and
/// below the diagonal of the new columns' block and against the old
/// columns, and are zero above that diagonal; on a simplicial and a
/// supernodal factor, with columns whose reaches overlap in part (and
/// solved in batches in the factor's order, each equal to its own solve).
#[test]
fn reach_columns_products_block_by_block_equal_them_pair_by_pair() {
    use groutready::fem::half_solves::gram;
    for (size, ordering) in [([6, 5, 4], Ordering::Amd), ([18, 16, 14], Ordering::Metis)] {
        let mut rng = Rng(43);
        let (n, a) = elastic_grid(size, &mut rng);
        let mut solver =
            CholeskySolver::with_options(a.pattern().clone(), &ordering, faer::Par::Seq).unwrap();
        solver.factorize(&a).unwrap();
        let mut work = groutready::fem::ReachWork::default();
        // more than a batch (`REACH_BATCH`), solved in the factor's order
        // and returned in this one
        let mut columns: Vec<Vec<(usize, f64)>> = (0..47)
            .map(|k| vec![((k * 7919) % n, rng.range(-2.0, 2.0))])
            .collect();
        let mut column = Vec::new();
        a.column(n / 2, |i, v| column.push((i, v)));
        columns.push(column);
        let ys = solver.forward_reach_many(&columns, &mut work).unwrap();
        assert_each_its_single_solve(&solver, &columns, &ys, &format!("{size:?}"));
        let (new, old) = ys.split_at(9);
        fn refs(s: &[ReachColumn]) -> Vec<&ReachColumn> {
            s.iter().collect()
        }
        let (g_new, g_old, _) = gram(&refs(new), &refs(old), faer::Par::Seq);
        let close = |got: f64, want: f64, scale: f64| (got - want).abs() <= 1e-13 * scale;
        for (i, yi) in new.iter().enumerate() {
            let scale = yi.dot(yi);
            for (j, yj) in new.iter().enumerate() {
                let want = if j <= i { yi.dot(yj) } else { 0.0 };
                assert!(close(g_new[(i, j)], want, scale), "{size:?} new {i}, {j}");
            }
            for (j, yj) in old.iter().enumerate() {
                assert!(
                    close(g_old[(i, j)], yi.dot(yj), scale),
                    "{size:?} old {i}, {j}"
                );
            }
        }
        // nothing new: nothing to compute
        let (g_new, g_old, flops) = gram(&[], &refs(old), faer::Par::Seq);
        assert_eq!(
            (g_new.nrows(), g_old.nrows(), g_old.ncols()),
            (0, 0, old.len())
        );
        assert_eq!(flops, 0.0);
    }
}

/// Each column of a batch of reach solves (`forward_reach_many`) equals
/// its single solve, on the same reach.
fn assert_each_its_single_solve(
    solver: &CholeskySolver,
    columns: &[Vec<(usize, f64)>],
    batch: &[ReachColumn],
    label: &str,
) {
    let mut work = groutready::fem::ReachWork::default();
    for (entries, together) in columns.iter().zip(batch) {
        let alone = solver.forward_reach(entries, &mut work).unwrap();
        assert!(alone.rows().eq(together.rows()), "{label}: the same reach");
        let n = solver.n();
        let (diff, scale) = max_difference(&together.to_dense(n), &alone.to_dense(n));
        assert!(diff <= 1e-13 * scale, "{label}: {diff:e} of {scale:e}");
    }
}

/// The solution of `m` (already constrained) by a fresh factorisation.
fn fresh_solution(m: &SparseSym, rhs: &[f64]) -> Vec<f64> {
    let mut fresh =
        CholeskySolver::with_options(m.pattern().clone(), &Ordering::Amd, faer::Par::Seq).unwrap();
    fresh.factorize(m).unwrap();
    let mut x = rhs.to_vec();
    fresh.solve_in_place(&mut x).unwrap();
    x
}

/// The largest difference between `x` and `x_ref`, and the largest |x_ref|.
fn max_difference(x: &[f64], x_ref: &[f64]) -> (f64, f64) {
    let scale = x_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = x
        .iter()
        .zip(x_ref)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    (diff, scale)
}

/// Springs added to and removed from the diagonal of free rows (a grout
/// layer bonded, one cracked), alone and with rows fixed and released, are
/// corrected on the factor of the old springs to round-off of a fresh
/// factorisation of the new matrix; their Z columns are those of fixed rows.
#[test]
fn capacitance_correction_of_changed_springs_equals_a_fresh_factorisation() {
    let mut rng = Rng(37);
    let (n, a) = elastic_grid([6, 5, 4], &mut rng);
    let scale = a.diag().iter().fold(0.0f64, |m, v| m.max(*v));
    // springs of the base on every 9th row, of the new matrix on every 6th
    // (some kept, some removed, some added), 10× the stiffest diagonal
    let springs = |every: usize| {
        let mut m = a.clone();
        for i in (0..n).filter(|i| i % every == 3) {
            m.add_diag(i, 10.0 * scale * (1.0 + (i % 4) as f64));
        }
        m
    };
    let (a0, a1) = (springs(9), springs(6));
    let base: Vec<bool> = (0..n).map(|i| i.is_multiple_of(5)).collect();
    let presc: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
    let rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
    let mut m0 = a0.clone();
    m0.apply_dirichlet(&base);
    let mut solver =
        CholeskySolver::with_options(a.pattern().clone(), &Ordering::Amd, faer::Par::Seq).unwrap();
    solver.factorize(&m0).unwrap();
    let mut cap = Capacitance::with_diagonal(base.clone(), a0.diag());
    let both = |i: usize| (base[i] && !i.is_multiple_of(10)) || i % 7 == 1;
    let cases: [(&str, &dyn Fn(usize) -> bool); 2] = [("springs", &|i| base[i]), ("both", &both)];
    for (name, rule) in cases {
        let fixed: Vec<bool> = (0..n).map(rule).collect();
        let mut m1 = a1.clone();
        let mut rhs1 = rhs.clone();
        m1.apply_dirichlet_with_rhs(&fixed, &presc, &mut rhs1);
        let x_ref = fresh_solution(&m1, &rhs1);
        let changes = cap.changes(&a1, &fixed);
        let diagonal = changes
            .iter()
            .filter(|c| c.1 == groutready::fem::RowChange::Diagonal)
            .count();
        let corrected = cap
            .solve(&solver, &a1, &fixed, &presc, &rhs, &[], Default::default())
            .unwrap();
        let (diff, x_scale) = max_difference(&corrected.x, &x_ref);
        eprintln!(
            "{name}: {} changed rows ({diagonal} springs), max difference {:.2e} of {x_scale:.3e}, residual {:.2e}",
            changes.len(),
            diff,
            corrected.residual
        );
        assert!(diagonal > 10, "{name}: springs changed on free rows");
        assert!(
            diff <= 1e-12 * x_scale,
            "{name}: differs by {diff:.3e} (scale {x_scale:.3e})"
        );
        assert!(
            relative_residual(&m1, &corrected.x, &rhs1) < 1e-12,
            "{name}"
        );
    }
    // a diagonal change shares the column of the row fixed at the same dof
    let fixed: Vec<bool> = (0..n).map(|i| base[i] || i % 6 == 3).collect();
    let before = cap.stats.columns;
    let _ = cap
        .solve(&solver, &a1, &fixed, &presc, &rhs, &[], Default::default())
        .unwrap();
    let spring_rows_base_free = (0..n).filter(|&i| i % 6 == 3 && !base[i]).count();
    assert!(spring_rows_base_free > 0);
    assert!(
        cap.stats.columns - before < spring_rows_base_free as u64,
        "the rows newly fixed reuse the spring rows' columns"
    );
    // S is factorised once per distinct system: the same changed rows and
    // springs under another load reuse its LU; the same rows with other
    // spring values (another δ) do not, and all three equal a fresh
    // factorisation
    let respring = {
        let mut m = a.clone();
        for i in (0..n).filter(|i| i % 6 == 3) {
            m.add_diag(i, 3.0 * scale * (1.0 + (i % 5) as f64));
        }
        m
    };
    let fixed: Vec<bool> = (0..n).map(both).collect();
    let other_rhs: Vec<f64> = (0..n).map(|_| rng.range(-1e6, 1e6)).collect();
    for (name, matrix, load, new_lu) in [
        ("both again", &a1, &rhs, 1),
        ("another load", &a1, &other_rhs, 0),
        ("other springs", &respring, &rhs, 1),
    ] {
        let mut m1 = matrix.clone();
        let mut rhs1 = load.clone();
        m1.apply_dirichlet_with_rhs(&fixed, &presc, &mut rhs1);
        let x_ref = fresh_solution(&m1, &rhs1);
        let lus = cap.stats.s_factorisations;
        let corrected = cap
            .solve(
                &solver,
                matrix,
                &fixed,
                &presc,
                load,
                &[],
                Default::default(),
            )
            .unwrap();
        let (diff, x_scale) = max_difference(&corrected.x, &x_ref);
        assert!(
            diff <= 1e-12 * x_scale,
            "{name}: differs by {diff:.3e} (scale {x_scale:.3e})"
        );
        assert_eq!(cap.stats.s_factorisations - lus, new_lu, "{name}");
    }
}

/// Timing of pattern, assembly, symbolic and numeric Cholesky and one solve
/// on structured scalar hex grids (25³ and 50³ elements), with faer's AMD and
/// with geometric nested dissection. Run with
/// `cargo test --release --test fem_sparse -- --ignored --nocapture`.
#[test]
#[ignore]
fn bench_cholesky_structured_grids() {
    let mut rng = Rng(19);
    for m in [25usize, 50] {
        let t = Instant::now();
        let g = grid([m, m, m], 1.0, 0.0, false, &mut rng);
        let slots: Vec<[u32; 8]> = (0..g.elems.len())
            .map(|e| {
                let d = g.hex_dofs(e);
                [d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]]
            })
            .collect();
        let t_mesh = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let pattern = Arc::new(Pattern::new(g.n_dofs(), &slots));
        let t_pattern = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut a = SparseSym::new(pattern.clone());
        let (lambda, rho_c, dt) = (2.0 * 86400.0, 2.3e6, 1.0);
        for e in 0..g.elems.len() {
            let c = g.hex(e);
            a.add_element(e, &conductivity(&c, lambda).unwrap());
            a.add_element_diag(e, 1.0 / dt, &capacity_lumped(&c, rho_c).unwrap());
        }
        let t_assembly = t.elapsed().as_secs_f64();
        println!(
            "grid {m}^3 elements: n = {}, nnz(upper) = {}, mesh {:.3}s, pattern {:.3}s, assembly {:.3}s",
            g.n_dofs(),
            pattern.nnz(),
            t_mesh,
            t_pattern,
            t_assembly
        );
        let mut dof_coords = vec![[0.0; 3]; g.n_dofs()];
        for (node, &d) in g.dof.iter().enumerate() {
            dof_coords[d as usize] = g.coords[node];
        }
        let t = Instant::now();
        let nd = nested_dissection(&pattern, &dof_coords, 64);
        let t_nd = t.elapsed().as_secs_f64();
        for (name, ordering) in [
            ("amd", Ordering::Amd),
            ("nested dissection", Ordering::Custom(nd.clone())),
        ] {
            let mut solver =
                CholeskySolver::with_options(pattern.clone(), &ordering, faer::Par::rayon(0))
                    .unwrap();
            solver.factorize(&a).unwrap();
            let t_numeric1 = solver.stats().numeric_seconds;
            let mut x: Vec<f64> = (0..g.n_dofs()).map(|i| (i % 17) as f64).collect();
            let b = x.clone();
            solver.solve_in_place(&mut x).unwrap();
            let res = relative_residual(&a, &x, &b);
            // second numeric factorisation on the same symbolic analysis
            solver.factorize(&a).unwrap();
            let s = solver.stats();
            println!(
                "  {name:>17}: nnz(L) = {} ({}), ordering {:.3}s, symbolic {:.3}s, numeric {:.3}s (2nd {:.3}s), \
                 solve {:.4}s, residual {:.1e}",
                solver.factor_nnz(),
                if solver.is_supernodal() { "supernodal" } else { "simplicial" },
                if name == "amd" { 0.0 } else { t_nd },
                s.symbolic_seconds,
                t_numeric1,
                s.numeric_seconds - t_numeric1,
                s.solve_seconds,
                res
            );
            assert!(res < 1e-10);
        }
    }
}
