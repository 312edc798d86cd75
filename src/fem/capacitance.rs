//! Solving with a changed set of Dirichlet rows on the factor of another set:
//! the capacitance (bordered Woodbury) correction.
//!
//! A contact iteration fixes and releases a few rows per pass (a joint point
//! closes: its relative displacement becomes prescribed; it opens: the row
//! is free again). faer has no sparse update/downdate, so instead of a new
//! factorisation each pass reuses the factor of
//!
//! ```text
//! M₀ = A with the rows and columns of the fixed set F₀ replaced by identity
//! ```
//!
//! for the system of another fixed set F₁ with prescribed values p. With
//! K = A[f₀, f₀] (f₀ the free set of F₀, what M₀ factors), R = F₀ \ F₁ the
//! released rows and N = F₁ \ F₀ the newly fixed ones (held by multipliers
//! λ), and b the right-hand side corrected for the values of F₀ ∩ F₁, the
//! system is
//!
//! ```text
//! [ K      A[f₀,R]  E_N ] [x_f]   [b_f]
//! [ A[R,f₀] A[R,R]   0  ] [x_R] = [b_R]
//! [ E_Nᵀ     0       0  ] [ λ ]   [p_N]
//! ```
//!
//! With U = [A[f₀,R], E_N] (m = |R| + |N| columns, zero on F₀), Z = K⁻¹U and
//! y = K⁻¹b_f, eliminating x_f leaves the m × m capacitance system
//!
//! ```text
//! S w = r,   S = [[A[R,R], 0], [0, 0]] − UᵀZ,   r = [b_R; p_N] − Uᵀy,
//! x_f = y − Z w,   x_R = w_R,   x = p on F₀ ∩ F₁.
//! ```
//!
//! A spring added to or removed from a row free in both sets (a grout
//! layer bonded or cracked: its stiffness sits on the diagonal of its
//! pair's rows) changes A₀'s diagonal there by δᵢ, K by Σ δᵢ eᵢeᵢᵀ. Each
//! such row D is bordered with μᵢ = δᵢ x_i: U gains the column e_i (the
//! same Z column as a newly fixed row), S the diagonal entry −1/δᵢ, r a
//! zero (eliminate x_f from K x_f + … + E_D μ = b_f and x_D − μ/δ = 0).
//! The caller then passes the changed matrix (its diagonal the new one)
//! and the base diagonal ([`Capacitance::with_diagonal`]); the rows
//! released or fixed read their own entries from the changed matrix, and
//! the off-diagonal columns U are untouched by springs, so the cached Z
//! columns stay valid.
//!
//! S is symmetric quasi-definite (the Schur complement of an SPD matrix in
//! the R block, −E_NᵀK⁻¹E_N in the N block), solved densely by LU. The
//! columns of Z depend on the base factor only, so they are kept per dof:
//! a later pass pays solves only for rows it has not met. The result is
//! exact (no penalty, no tolerance); the caller checks its residual on the
//! F₁ matrix like any solve.
//!
//! Verified by `tests/it/fem_sparse.rs`: the corrected solution equals
//! a fresh factorisation of the F₁ system to round-off for rows fixed,
//! released and both, with prescribed values, and with springs added to and
//! removed from free rows besides.

use std::collections::BTreeMap;

use faer::Mat;
use nalgebra::{DMatrix, DVector};

use super::solver::{CholeskySolver, SolveError};
use super::sparse::SparseSym;

/// Refinements of a corrected solution on its residual, at most.
pub const MAX_REFINEMENTS: usize = 3;

/// The residual rhs − A x on the rows not in `fixed` (zero on them) and its
/// 2-norm.
fn free_residual(a: &SparseSym, fixed: &[bool], rhs: &[f64], x: &[f64]) -> (Vec<f64>, f64) {
    let mut ax = vec![0.0; a.n()];
    a.mul_vec(x, &mut ax);
    let r: Vec<f64> = (0..a.n())
        .map(|i| if fixed[i] { 0.0 } else { rhs[i] - ax[i] })
        .collect();
    let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
    (r, norm)
}

/// ‖b − M x‖ / ‖b‖ of the system M x = b that A with the rows `fixed` held
/// at `presc` becomes (see [`SparseSym::apply_dirichlet_with_rhs`]),
/// without forming M: what [`relative_residual`](super::relative_residual)
/// of a fresh factorisation's solution measures.
pub fn constrained_residual(
    a: &SparseSym,
    fixed: &[bool],
    presc: &[f64],
    rhs: &[f64],
    x: &[f64],
) -> f64 {
    let b = constrained_rhs(a, fixed, presc, rhs);
    // A x on the free rows counts only the free columns: the fixed ones
    // are in b's correction
    let xf: Vec<f64> = (0..a.n())
        .map(|i| if fixed[i] { 0.0 } else { x[i] })
        .collect();
    let mut ax = vec![0.0; a.n()];
    a.mul_vec(&xf, &mut ax);
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..a.n() {
        let r = if fixed[i] {
            presc[i] - x[i]
        } else {
            b[i] - ax[i]
        };
        num += r * r;
        den += b[i] * b[i];
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        num.sqrt()
    }
}

/// The right-hand side of the system M x = b that A with the rows `fixed`
/// held at `presc` becomes: `rhs` less the fixed columns' loads on the free
/// rows, `presc` on the fixed ones.
fn constrained_rhs(a: &SparseSym, fixed: &[bool], presc: &[f64], rhs: &[f64]) -> Vec<f64> {
    let mut b = rhs.to_vec();
    a.dirichlet_correction(fixed, presc, &mut b);
    for i in 0..a.n() {
        if fixed[i] {
            b[i] = presc[i];
        }
    }
    b
}

/// A corrected solution and its relative residual on the changed system.
#[derive(Debug, Clone, PartialEq)]
pub struct Corrected {
    pub x: Vec<f64>,
    /// ‖b − M x‖ / ‖b‖ of the constrained system, what
    /// [`constrained_residual`] measures (see [`Capacitance::solve`])
    pub residual: f64,
}

/// How a row's state differs from the base factor's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum RowChange {
    /// fixed in the base, free now
    Released,
    /// free in the base, fixed now
    Fixed,
    /// free in both, its diagonal entry changed (a spring added or removed)
    Diagonal,
}

impl RowChange {
    /// The change whose column of Z this one uses: a diagonal change's
    /// column is K⁻¹e_i, the same as a newly fixed row's.
    fn column_key(self) -> RowChange {
        match self {
            RowChange::Diagonal => RowChange::Fixed,
            other => other,
        }
    }
}

/// What the corrections cost: counted per factor here, summed per step by
/// the contact solve and per run by the mechanics' counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CapacitanceStats {
    /// corrected solves
    pub solves: u64,
    /// columns of Z computed (each a right-hand side of the base factor)
    pub columns: u64,
    /// largest capacitance system [changed rows]
    pub max_rank: usize,
    /// refinements on the residual
    pub refinements: u64,
    /// wall time of the corrections [s]
    pub seconds: f64,
}

impl CapacitanceStats {
    /// Adds `other`'s counts and time (the largest rank of both).
    pub fn add(&mut self, other: &CapacitanceStats) {
        self.solves += other.solves;
        self.columns += other.columns;
        self.max_rank = self.max_rank.max(other.max_rank);
        self.refinements += other.refinements;
        self.seconds += other.seconds;
    }

    /// What was added since `before` (the largest rank is this one's).
    pub fn since(&self, before: &CapacitanceStats) -> CapacitanceStats {
        CapacitanceStats {
            solves: self.solves - before.solves,
            columns: self.columns - before.columns,
            max_rank: self.max_rank,
            refinements: self.refinements - before.refinements,
            seconds: self.seconds - before.seconds,
        }
    }
}

/// The base fixed set of a factor and the columns of Z met so far.
#[derive(Debug, Clone)]
pub struct Capacitance {
    base: Vec<bool>,
    /// the base matrix's diagonal when the solved matrices may differ
    /// from it there ([`Capacitance::with_diagonal`])
    base_diag: Option<Vec<f64>>,
    /// K⁻¹ U column of each changed row, by (dof, change)
    z: BTreeMap<(u32, RowChange), Vec<f64>>,
    pub stats: CapacitanceStats,
}

impl Capacitance {
    /// For a factor of A with the rows `base` fixed.
    pub fn new(base: Vec<bool>) -> Self {
        Capacitance {
            base,
            base_diag: None,
            z: BTreeMap::new(),
            stats: CapacitanceStats::default(),
        }
    }

    /// For a factor of A₀ with the rows `base` fixed, where `base_diag` is
    /// A₀'s diagonal: the matrices later solved may differ from A₀ on the
    /// diagonal of rows free in both (springs added or removed).
    pub fn with_diagonal(base: Vec<bool>, base_diag: Vec<f64>) -> Self {
        Capacitance {
            base_diag: Some(base_diag),
            ..Capacitance::new(base)
        }
    }

    /// The fixed set of the base factor.
    pub fn base(&self) -> &[bool] {
        &self.base
    }

    /// The rows fixed in one of the base and `fixed` only, and (with a
    /// base diagonal) the rows free in both whose diagonal entry in `a`
    /// differs from the base's, in dof order.
    pub fn changes(&self, a: &SparseSym, fixed: &[bool]) -> Vec<(u32, RowChange)> {
        let diag_changed = |i: usize| {
            self.base_diag
                .as_ref()
                .is_some_and(|d| a.diag_at(i) != d[i])
        };
        self.base
            .iter()
            .zip(fixed)
            .enumerate()
            .filter_map(|(i, (&b, &f))| match (b, f) {
                (true, false) => Some((i as u32, RowChange::Released)),
                (false, true) => Some((i as u32, RowChange::Fixed)),
                (false, false) if diag_changed(i) => Some((i as u32, RowChange::Diagonal)),
                _ => None,
            })
            .collect()
    }

    /// Of `changes`, how many need a new column of Z.
    pub fn uncached(&self, changes: &[(u32, RowChange)]) -> usize {
        let mut keys: Vec<(u32, RowChange)> = changes
            .iter()
            .map(|&(dof, c)| (dof, c.column_key()))
            .filter(|k| !self.z.contains_key(k))
            .collect();
        keys.dedup();
        keys.len()
    }

    /// The cached column of Z of a change.
    fn z_of(&self, &(dof, change): &(u32, RowChange)) -> &[f64] {
        &self.z[&(dof, change.column_key())]
    }

    /// Bytes held by the cached columns.
    pub fn memory_bytes(&self) -> usize {
        self.z.values().map(|c| 8 * c.len()).sum()
    }

    /// Solves A x = rhs with the rows `fixed` held at `presc`, using
    /// `solver`, a factor of A with the base rows fixed (identity rows).
    /// `rhs` is uncorrected: the loads of every prescribed value are
    /// applied here. The correction loses digits when the capacitance
    /// system is ill-conditioned (seen on the demo: 1.3e-8), so the result
    /// is refined on the residual of the free rows until it stops improving
    /// (at most [`MAX_REFINEMENTS`] times).
    ///
    /// The returned residual is the refinement's last one, relative to the
    /// constrained right-hand side: x holds `presc` exactly on the fixed
    /// rows, so rhs − A x on the free rows is b − M x there (b the
    /// constrained right-hand side, M the constrained matrix) and zero on
    /// the fixed rows, i.e. [`constrained_residual`]'s quantity, without a
    /// second product with A.
    pub fn solve(
        &mut self,
        solver: &CholeskySolver,
        a: &SparseSym,
        fixed: &[bool],
        presc: &[f64],
        rhs: &[f64],
    ) -> Result<Corrected, SolveError> {
        let t = std::time::Instant::now();
        let n = a.n();
        if fixed.len() != n || presc.len() != n || rhs.len() != n || self.base.len() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                got: fixed.len().min(presc.len()).min(rhs.len()),
            });
        }
        let changes = self.changes(a, fixed);
        self.fill_columns(solver, a, &changes)?;
        let mut x = self.apply(solver, a, &changes, fixed, presc, rhs)?;
        let (mut r, mut norm) = free_residual(a, fixed, rhs, &x);
        let zero = vec![0.0; n];
        // four digits below the callers' residual checks (1e-8)
        let enough = 1e-12 * rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        for _ in 0..MAX_REFINEMENTS {
            if norm <= enough {
                break;
            }
            let dx = self.apply(solver, a, &changes, fixed, &zero, &r)?;
            let refined: Vec<f64> = x.iter().zip(&dx).map(|(x, d)| x + d).collect();
            let (r_next, next) = free_residual(a, fixed, rhs, &refined);
            self.stats.refinements += 1;
            if next >= norm {
                break;
            }
            (x, r, norm) = (refined, r_next, next);
        }
        let b_norm = constrained_rhs(a, fixed, presc, rhs)
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        let residual = if b_norm > 0.0 { norm / b_norm } else { norm };
        self.stats.solves += 1;
        self.stats.max_rank = self.stats.max_rank.max(changes.len());
        self.stats.seconds += t.elapsed().as_secs_f64();
        Ok(Corrected { x, residual })
    }

    /// One application of the correction (the columns of `changes` filled).
    fn apply(
        &self,
        solver: &CholeskySolver,
        a: &SparseSym,
        changes: &[(u32, RowChange)],
        fixed: &[bool],
        presc: &[f64],
        rhs: &[f64],
    ) -> Result<Vec<f64>, SolveError> {
        let n = a.n();
        let keep: Vec<bool> = self.base.iter().zip(fixed).map(|(&b, &f)| b && f).collect();
        let mut b = rhs.to_vec();
        a.dirichlet_correction(&keep, presc, &mut b);
        let mut y: Vec<f64> = (0..n)
            .map(|i| if self.base[i] { 0.0 } else { b[i] })
            .collect();
        solver.solve_in_place(&mut y)?;
        let w = self.capacitance_solve(a, changes, &b, presc, &y)?;
        let mut x = y;
        for (c, &wj) in changes.iter().zip(&w) {
            if wj != 0.0 {
                for (xi, zi) in x.iter_mut().zip(self.z_of(c)) {
                    *xi -= zi * wj;
                }
            }
        }
        for (&(dof, change), &wj) in changes.iter().zip(&w) {
            if change == RowChange::Released {
                x[dof as usize] = wj;
            }
        }
        for i in 0..n {
            if fixed[i] {
                x[i] = presc[i];
            }
        }
        Ok(x)
    }

    /// Computes the columns of Z not met before, in one multi-column solve.
    fn fill_columns(
        &mut self,
        solver: &CholeskySolver,
        a: &SparseSym,
        changes: &[(u32, RowChange)],
    ) -> Result<(), SolveError> {
        let mut new: Vec<(u32, RowChange)> = changes
            .iter()
            .map(|&(dof, c)| (dof, c.column_key()))
            .filter(|k| !self.z.contains_key(k))
            .collect();
        new.dedup();
        if new.is_empty() {
            return Ok(());
        }
        let n = a.n();
        let mut u = Mat::<f64>::zeros(n, new.len());
        for (k, &(dof, change)) in new.iter().enumerate() {
            match change {
                RowChange::Fixed | RowChange::Diagonal => u[(dof as usize, k)] = 1.0,
                RowChange::Released => a.column(dof as usize, |i, v| {
                    if !self.base[i] {
                        u[(i, k)] = v;
                    }
                }),
            }
        }
        solver.solve_columns(&mut u)?;
        for (k, c) in new.into_iter().enumerate() {
            self.z.insert(c, u.col(k).iter().copied().collect());
        }
        self.stats.columns += u.ncols() as u64;
        Ok(())
    }

    /// δ = A_ii − A₀_ii of a row with a [`RowChange::Diagonal`].
    fn diagonal_change(&self, a: &SparseSym, i: usize) -> f64 {
        self.base_diag.as_ref().map_or(0.0, |d| a.diag_at(i) - d[i])
    }

    /// Assembles and solves S w = r (see the module doc).
    fn capacitance_solve(
        &self,
        a: &SparseSym,
        changes: &[(u32, RowChange)],
        b: &[f64],
        presc: &[f64],
        y: &[f64],
    ) -> Result<Vec<f64>, SolveError> {
        let m = changes.len();
        if m == 0 {
            return Ok(Vec::new());
        }
        // Uᵢᵀv for the column of change i
        let u_dot = |&(dof, change): &(u32, RowChange), v: &[f64]| -> f64 {
            match change {
                RowChange::Fixed | RowChange::Diagonal => v[dof as usize],
                RowChange::Released => {
                    let mut s = 0.0;
                    a.column(dof as usize, |k, akr| {
                        if !self.base[k] {
                            s += akr * v[k];
                        }
                    });
                    s
                }
            }
        };
        let mut s = DMatrix::<f64>::zeros(m, m);
        let mut r = DVector::<f64>::zeros(m);
        for (i, ci) in changes.iter().enumerate() {
            for (j, cj) in changes.iter().enumerate() {
                let arr = match (ci.1, cj.1) {
                    (RowChange::Released, RowChange::Released) => {
                        a.get(ci.0 as usize, cj.0 as usize)
                    }
                    (RowChange::Diagonal, RowChange::Diagonal) if i == j => {
                        -1.0 / self.diagonal_change(a, ci.0 as usize)
                    }
                    _ => 0.0,
                };
                s[(i, j)] = arr - u_dot(ci, self.z_of(cj));
            }
            let top = match ci.1 {
                RowChange::Released => b[ci.0 as usize],
                RowChange::Fixed => presc[ci.0 as usize],
                RowChange::Diagonal => 0.0,
            };
            r[i] = top - u_dot(ci, y);
        }
        let w = s
            .lu()
            .solve(&r)
            .filter(|w| w.iter().all(|v| v.is_finite()))
            .ok_or(SolveError::SingularCapacitance { size: m })?;
        Ok(w.iter().copied().collect())
    }
}
