//! Sparse Cholesky (LLᵀ) on a fixed [`Pattern`], wrapping faer.
//!
//! The symbolic analysis (fill-reducing ordering — faer's AMD or a custom one
//! such as [`nested_dissection`](super::ordering::nested_dissection) —,
//! elimination tree, supernodes) is done once in [`CholeskySolver::new`] /
//! [`CholeskySolver::with_options`]; each [`CholeskySolver::factorize`] reuses
//! it and the factor's value buffer, so a changed matrix with the same
//! pattern costs one numeric factorisation only. Every phase is counted and
//! timed in [`SolverStats`].
//!
//! No NaN passes silently: the matrix, the right-hand sides and the solutions
//! are checked to be finite.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError as DenseLltError;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::simplicial;
use faer::sparse::linalg::cholesky::supernodal::{self, SupernodalLltRef};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::triangular_solve as sparse_triangular;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, Par, Side};
use thiserror::Error;

use super::half_solves::{
    forward_reach_many, reach_size, BlockTree, ReachColumn, ReachWork, REACH_BATCH,
};
use super::ordering::{metis_nested_dissection, Ordering};
use super::permuted_lower::{left_out, PermutedLower};
use super::sparse::{Pattern, SparseSym};
use super::two_cores::TwoCores;

impl SolveError {
    /// The unknown (in the matrix's numbering) whose pivot failed.
    pub fn pivot_dof(&self) -> Option<usize> {
        match self {
            SolveError::NotPositiveDefinite { dof, .. } => Some(*dof),
            _ => None,
        }
    }
}

/// Why a factorisation or solve failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    /// A pivot ≤ 0 appeared: the matrix is singular or indefinite (a
    /// floating part, a dof without stiffness, a negative coefficient).
    #[error(
        "matrix is not positive definite: pivot {pivot} of the elimination (dof {dof}) is not > 0"
    )]
    NotPositiveDefinite { pivot: usize, dof: usize },
    /// A NaN or infinity in the input or the result.
    #[error("non-finite value in the {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error("the matrix pattern differs from the pattern this solver was analysed for")]
    PatternMismatch,
    #[error("solve called before a successful factorize")]
    NotFactorized,
    #[error("dimension mismatch: the system has {expected} rows, got {got}")]
    DimensionMismatch { expected: usize, got: usize },
    #[error("the custom ordering is not a permutation of 0..{n}")]
    InvalidOrdering { n: usize },
    /// A matrix couples a row the solver was analysed to hold
    /// ([`CholeskySolver::with_held`]) to another: a held row must be an
    /// identity row and column.
    #[error("row {held} is held, but the matrix couples it to row {other}")]
    HeldRowCoupled { held: usize, other: usize },
    #[error("{got} held flags for a system of {expected} rows")]
    HeldLength { expected: usize, got: usize },
    /// The capacitance system of a changed Dirichlet set is singular: the
    /// new set leaves a part of the structure without support.
    #[error("the capacitance system of {size} changed rows is singular")]
    SingularCapacitance { size: usize },
    #[error("faer: {0}")]
    Faer(String),
}

/// Counts and wall-clock seconds of every phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverStats {
    pub n_symbolic: u64,
    pub n_numeric: u64,
    /// Solve calls (a multi-column solve counts once).
    pub n_solves: u64,
    /// Right-hand-side columns solved.
    pub n_rhs: u64,
    pub symbolic_seconds: f64,
    pub numeric_seconds: f64,
    /// full solves and the halves of [`CholeskySolver::forward_in_place`]
    /// and [`CholeskySolver::backward_in_place`] (a pair counts once)
    pub solve_seconds: f64,
    /// forward solves on a reach ([`CholeskySolver::forward_reach`])
    pub n_reach_columns: u64,
    pub reach_seconds: f64,
}

/// Parallelism of every triangular solve, whatever the factorisation's.
/// A solve reads each entry of L once per right-hand side: it is bound by
/// memory, and faer's parallel supernodal sweeps only add rayon's
/// scheduling. Measured alone on the 2 cores (27 Nov 2026, METIS, the
/// complete mechanical matrices; `Par::Seq` against `Par::rayon(0)`): the
/// Xiaowan-like arch's (344,643 dofs, L 144.7M entries) 197 against
/// 206–216 ms for one right-hand side, 319–321 against 423–459 ms for 4,
/// 564–595 against 762–803 ms for 16; the demo's (25,458 dofs) 4.7 against
/// 4.7–4.9 ms, 9.5–10.2 against 14.5 ms and 19.7 against 33.6 ms.
/// `cargo run --release --example factor_orderings [SCENE] fast` times
/// them (the parallel ones: its version before this constant).
const SOLVE_PAR: Par = Par::Seq;

/// Entries of L from which a supernodal factor made on two or more
/// threads is also factorised and swept on two ([`TwoCores`]), its elimination tree
/// cut into two forests: a sweep of 16M entries reads 128 MB, tens of
/// milliseconds against a thread's start of microseconds. Smaller systems
/// are solved beside other work (the factor made ahead, the thermal
/// steps) on one core.
pub const SPLIT_FROM_ENTRIES: usize = 1 << 24;

/// A solver whose sweeps run on two cores: supernodal, at least
/// [`SPLIT_FROM_ENTRIES`], factorised on two or more threads.
fn large_for_two_cores(symbolic: &SymbolicCholesky<u32>, par: Par) -> bool {
    matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
        && symbolic.len_val() >= SPLIT_FROM_ENTRIES
        && matches!(par, Par::Rayon(n) if n.get() >= 2)
}

/// Sparse Cholesky solver: symbolic analysis once per pattern, numeric
/// factorisation per matrix, any number of solves.
pub struct CholeskySolver {
    pattern: Arc<Pattern>,
    /// shared by forks: one symbolic analysis serves several numeric factors
    symbolic: Arc<SymbolicCholesky<u32>>,
    /// the blocks and elimination tree of `symbolic`, for reach solves
    tree: Arc<BlockTree>,
    /// the tree cut for sweeps on two cores: a supernodal factor of at
    /// least [`SPLIT_FROM_ENTRIES`] entries factorised in parallel
    split: Option<Arc<TwoCores>>,
    /// the matrix's structure in the elimination order (made once, shared
    /// by forks): always for a supernodal analysis, and for a simplicial
    /// one with held rows (else faer permutes it)
    permuted: Option<Arc<PermutedLower>>,
    /// the rows every factorised matrix holds, left out of the analysis
    held: Option<Arc<Vec<bool>>>,
    /// the matrix's values in that structure, placed per factorisation
    placed: Vec<f64>,
    l_values: Vec<f64>,
    scratch: MemBuffer,
    factorized: bool,
    par: Par,
    stats: Mutex<SolverStats>,
}

impl std::fmt::Debug for CholeskySolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskySolver")
            .field("n", &self.n())
            .field("factor_nnz", &self.factor_nnz())
            .field("supernodal", &self.is_supernodal())
            .field("factorized", &self.factorized)
            .field("stats", &self.stats())
            .finish_non_exhaustive()
    }
}

impl CholeskySolver {
    /// Symbolic analysis of `pattern` (AMD fill-reducing ordering), using all
    /// rayon threads for later numeric work.
    pub fn new(pattern: Arc<Pattern>) -> Result<Self, SolveError> {
        Self::with_parallelism(pattern, Par::rayon(0))
    }

    /// [`CholeskySolver::new`] with an explicit faer parallelism.
    pub fn with_parallelism(pattern: Arc<Pattern>, par: Par) -> Result<Self, SolveError> {
        Self::with_options(pattern, &Ordering::Amd, par)
    }

    /// Symbolic analysis with a chosen fill-reducing ordering and parallelism.
    pub fn with_options(
        pattern: Arc<Pattern>,
        ordering: &Ordering,
        par: Par,
    ) -> Result<Self, SolveError> {
        Self::analyse(pattern, ordering, par, None)
    }

    /// [`CholeskySolver::with_options`] for matrices that all hold the rows
    /// `held` (Dirichlet rows: the supports). Their couplings are left out
    /// of the analysis, so they are eliminated without fill: on the demo's
    /// live sets the supports are about 1,200 of up to 18,000 unknowns and
    /// 29 % of the flops of a factorisation that keeps them in its
    /// structure. [`CholeskySolver::factorize`] refuses a matrix that
    /// couples a held row ([`SolveError::HeldRowCoupled`]).
    pub fn with_held(
        pattern: Arc<Pattern>,
        ordering: &Ordering,
        par: Par,
        held: &[bool],
    ) -> Result<Self, SolveError> {
        if held.len() != pattern.n_dofs() {
            return Err(SolveError::HeldLength {
                expected: pattern.n_dofs(),
                got: held.len(),
            });
        }
        let held = held.iter().any(|&h| h).then(|| Arc::new(held.to_vec()));
        Self::analyse(pattern, ordering, par, held)
    }

    fn analyse(
        pattern: Arc<Pattern>,
        ordering: &Ordering,
        par: Par,
        held: Option<Arc<Vec<bool>>>,
    ) -> Result<Self, SolveError> {
        let t = Instant::now();
        let decoupled = held.as_deref().map(|h| Decoupled::new(&pattern, h));
        let structure = decoupled
            .as_ref()
            .map_or_else(|| pattern.symbolic(), Decoupled::symbolic);
        let symbolic = match ordering {
            Ordering::Amd => factorize_symbolic_cholesky(
                structure,
                Side::Upper,
                SymmetricOrdering::Amd,
                Default::default(),
            ),
            Ordering::Metis => {
                let fwd = metis_nested_dissection(&pattern)
                    .map_err(|e| SolveError::Faer(e.to_string()))?;
                symbolic_custom(structure, &held_first(fwd, held.as_deref()))?
            }
            Ordering::Custom(fwd) => {
                symbolic_custom(structure, &held_first(fwd.clone(), held.as_deref()))?
            }
        }
        .map_err(|e| SolveError::Faer(format!("symbolic Cholesky: {e:?}")))?;
        let permuted = permuted_lower(&pattern, &symbolic, held.as_deref().map(|h| h.as_slice()))
            .map(Arc::new);
        let scratch = factor_scratch(&symbolic, permuted.is_some(), par)?;
        let stats = SolverStats {
            n_symbolic: 1,
            symbolic_seconds: t.elapsed().as_secs_f64(),
            ..Default::default()
        };
        let tree = BlockTree::new(&symbolic);
        let split = large_for_two_cores(&symbolic, par)
            .then(|| TwoCores::new(&symbolic, &tree).map(Arc::new))
            .flatten();
        Ok(CholeskySolver {
            pattern,
            tree: Arc::new(tree),
            split,
            symbolic: Arc::new(symbolic),
            permuted,
            held,
            placed: Vec::new(),
            l_values: Vec::new(),
            scratch,
            factorized: false,
            par,
            stats: Mutex::new(stats),
        })
    }

    /// A second solver on the same symbolic analysis (no new analysis), with
    /// its own numeric factor: lets a caller keep factors of several matrices
    /// of one pattern, e.g. one per time-step length.
    pub fn fork(&self) -> Result<Self, SolveError> {
        let scratch = factor_scratch(&self.symbolic, self.permuted.is_some(), self.par)?;
        Ok(CholeskySolver {
            pattern: self.pattern.clone(),
            symbolic: self.symbolic.clone(),
            tree: self.tree.clone(),
            split: self.split.clone(),
            permuted: self.permuted.clone(),
            held: self.held.clone(),
            placed: Vec::new(),
            l_values: Vec::new(),
            scratch,
            factorized: false,
            par: self.par,
            stats: Mutex::new(SolverStats::default()),
        })
    }

    /// The pattern the solver was analysed for.
    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// Matrix order.
    pub fn n(&self) -> usize {
        self.pattern.n_dofs()
    }

    /// Entries of the factor L (fill included).
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Floating-point operations of one numeric factorisation, Σ c_k² over
    /// the columns of L (c_k: entries of column k): a deterministic measure
    /// of its cost, to weigh against solves ([`CholeskySolver::factor_nnz`]
    /// entries are read twice per right-hand side).
    pub fn factor_flops(&self) -> f64 {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => s
                .col_ptr()
                .windows(2)
                .map(|w| {
                    let c = (w[1] - w[0]) as f64;
                    c * c
                })
                .sum(),
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (begin, end, rows) = (
                    s.supernode_begin(),
                    s.supernode_end(),
                    s.col_ptr_for_row_idx(),
                );
                (0..s.n_supernodes())
                    .map(|k| {
                        let w = (end[k] - begin[k]) as f64;
                        let below = (rows[k + 1] - rows[k]) as f64;
                        // Σ_{i<w} (w − i + below)²
                        (0..w as usize)
                            .map(|i| {
                                let c = w - i as f64 + below;
                                c * c
                            })
                            .sum::<f64>()
                    })
                    .sum()
            }
        }
    }

    /// True when faer chose its supernodal (dense-block) factorisation.
    /// Sweeps every later solve of one right-hand side, and every half, on
    /// two cores ([`TwoCores`]), and its numeric factorisations too,
    /// whatever the factor's size; a simplicial
    /// factor is left as it is. What the solver does by itself from
    /// [`SPLIT_FROM_ENTRIES`] on; for tests and benchmarks of smaller ones.
    pub fn on_two_cores(&mut self) {
        if self.is_supernodal() {
            self.split = TwoCores::new(&self.symbolic, &self.tree).map(Arc::new);
        }
    }

    /// Entries of L in the top and on each side of the cut its sweeps run
    /// on two cores with ([`SPLIT_FROM_ENTRIES`]), None where they run on
    /// one.
    pub fn sweep_split(&self) -> Option<[u64; 3]> {
        self.split.as_ref().map(|s| s.sweep.entries())
    }

    /// Flops of the top and of each side of the cut its numeric
    /// factorisation runs on two cores with, None where it runs as faer's.
    pub fn factor_split(&self) -> Option<[u64; 3]> {
        self.split.as_ref().map(|s| s.factor.entries())
    }

    pub fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// True after a successful [`CholeskySolver::factorize`].
    pub fn is_factorized(&self) -> bool {
        self.factorized
    }

    /// The parallelism of its numeric factorisations.
    pub fn parallelism(&self) -> Par {
        self.par
    }

    pub fn set_parallelism(&mut self, par: Par) -> Result<(), SolveError> {
        self.scratch = factor_scratch(&self.symbolic, self.permuted.is_some(), par)?;
        self.par = par;
        Ok(())
    }

    /// Counters and timings so far.
    pub fn stats(&self) -> SolverStats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn record(&self, f: impl FnOnce(&mut SolverStats)) {
        f(&mut self.stats.lock().unwrap_or_else(|e| e.into_inner()));
    }

    /// Numeric LLᵀ of `matrix` (same pattern), reusing the symbolic analysis.
    /// On error the solver is left unfactorised.
    pub fn factorize(&mut self, matrix: &SparseSym) -> Result<(), SolveError> {
        self.factorized = false;
        let mp = matrix.pattern();
        if !Arc::ptr_eq(mp, &self.pattern)
            && (mp.col_ptr() != self.pattern.col_ptr() || mp.row_idx() != self.pattern.row_idx())
        {
            return Err(SolveError::PatternMismatch);
        }
        if let Some(index) = matrix.values().iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "matrix",
                index,
            });
        }
        let t = Instant::now();
        let len = self.symbolic.len_val();
        if self.l_values.len() != len {
            self.l_values = Vec::new();
            self.l_values = zeroed(len).ok_or_else(|| {
                SolveError::Faer(format!("out of memory for {len} factor entries"))
            })?;
        }
        if let Some(p) = &self.permuted {
            p.place(matrix.values(), &mut self.placed)
                .map_err(|k| held_coupling(&self.pattern, self.held.as_deref(), k))?;
        }
        let result = match (self.symbolic.raw(), &self.permuted) {
            (SymbolicCholeskyRaw::Supernodal(s), Some(p)) if self.split.is_some() => {
                let two = self.split.as_deref().expect("checked");
                two.factorize(s, p.matrix(&self.placed), &mut self.l_values, self.par)
            }
            (SymbolicCholeskyRaw::Supernodal(s), Some(p)) => {
                supernodal::factorize_supernodal_numeric_llt(
                    &mut self.l_values,
                    p.matrix(&self.placed),
                    Default::default(),
                    s,
                    self.par,
                    MemStack::new(&mut self.scratch),
                    Default::default(),
                )
                .map(|_| ())
            }
            (SymbolicCholeskyRaw::Simplicial(s), Some(p)) => {
                simplicial::factorize_simplicial_numeric_llt(
                    &mut self.l_values,
                    p.matrix(&self.placed),
                    Default::default(),
                    s,
                    MemStack::new(&mut self.scratch),
                )
                .map(|_| ())
            }
            _ => self
                .symbolic
                .factorize_numeric_llt::<f64>(
                    &mut self.l_values,
                    matrix.as_faer(),
                    Side::Upper,
                    Default::default(),
                    self.par,
                    MemStack::new(&mut self.scratch),
                    Default::default(),
                )
                .map(|_| ()),
        };
        let seconds = t.elapsed().as_secs_f64();
        self.record(|s| {
            s.n_numeric += 1;
            s.numeric_seconds += seconds;
        });
        match result {
            Ok(_) => {
                self.factorized = true;
                Ok(())
            }
            Err(DenseLltError::NonPositivePivot { index }) => {
                // simplicial reports 1-based, supernodal 0-based positions in
                // the permuted (elimination) order
                let pos = match self.symbolic.raw() {
                    SymbolicCholeskyRaw::Simplicial(_) => index.saturating_sub(1),
                    SymbolicCholeskyRaw::Supernodal(_) => index,
                };
                let dof = match self.symbolic.perm() {
                    Some(perm) => perm.arrays().0.get(pos).map_or(pos, |&d| d as usize),
                    None => pos,
                };
                Err(SolveError::NotPositiveDefinite { pivot: pos, dof })
            }
        }
    }

    fn solve_mat(&self, rhs: MatMut<'_, f64>) -> Result<(), SolveError> {
        if !self.factorized {
            return Err(SolveError::NotFactorized);
        }
        let n = self.n();
        if rhs.nrows() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                got: rhs.nrows(),
            });
        }
        let k = rhs.ncols();
        for j in 0..k {
            for i in 0..n {
                if !rhs[(i, j)].is_finite() {
                    return Err(SolveError::NonFinite {
                        what: "right-hand side",
                        index: i + j * n,
                    });
                }
            }
        }
        let t = Instant::now();
        let mut rhs = rhs;
        match &self.split {
            Some(split) if k == 1 => self.solve_on_two_cores(split, rhs.as_mut().col_mut(0)),
            _ => {
                let mut mem =
                    MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(k, SOLVE_PAR))
                        .map_err(|e| SolveError::Faer(format!("scratch allocation: {e}")))?;
                LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
                    Conj::No,
                    rhs.as_mut(),
                    SOLVE_PAR,
                    MemStack::new(&mut mem),
                );
            }
        }
        let seconds = t.elapsed().as_secs_f64();
        self.record(|s| {
            s.n_solves += 1;
            s.n_rhs += k as u64;
            s.solve_seconds += seconds;
        });
        for j in 0..k {
            for i in 0..n {
                if !rhs[(i, j)].is_finite() {
                    return Err(SolveError::NonFinite {
                        what: "solution",
                        index: i + j * n,
                    });
                }
            }
        }
        Ok(())
    }

    /// One right-hand side solved by the two sweeps of `split`, permuted
    /// in and out.
    fn solve_on_two_cores(&self, split: &TwoCores, mut b: faer::ColMut<'_, f64>) {
        let mut c = self.permuted(|i| b[i]);
        split
            .sweep
            .sweep(&self.symbolic, &self.l_values, &mut c, true);
        split
            .sweep
            .sweep(&self.symbolic, &self.l_values, &mut c, false);
        self.unpermute(&c, |i, v| b[i] = v);
    }

    /// P b, the vector `b` (the matrix's numbering, read by index) in the
    /// factor's numbering.
    fn permuted(&self, b: impl Fn(usize) -> f64) -> Vec<f64> {
        match self.symbolic.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| b(i as usize)).collect(),
            None => (0..self.n()).map(b).collect(),
        }
    }

    /// Pᵀ y: each entry of `y` (the factor's numbering) handed to `out`
    /// with its index in the matrix's numbering.
    fn unpermute(&self, y: &[f64], mut out: impl FnMut(usize, f64)) {
        match self.symbolic.perm() {
            Some(p) => (p.arrays().0.iter().zip(y)).for_each(|(&i, &v)| out(i as usize, v)),
            None => y.iter().enumerate().for_each(|(i, &v)| out(i, v)),
        }
    }

    /// Solves A x = b in place (`rhs` = b on entry, x on exit).
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let n = rhs.len();
        self.solve_mat(MatMut::from_column_major_slice_mut(rhs, n, 1))
    }

    /// Solves A X = B for all columns of `rhs` at once.
    pub fn solve_columns(&self, rhs: &mut Mat<f64>) -> Result<(), SolveError> {
        self.solve_mat(rhs.as_mut())
    }
}

/// The halves of a solve (see [`super::half_solves`]).
impl CholeskySolver {
    /// The row of L (permuted numbering) of each unknown.
    fn permuted_row(&self, dof: usize) -> usize {
        self.symbolic
            .perm()
            .map_or(dof, |p| p.arrays().1[dof] as usize)
    }

    /// Checks that a half solve can run on `v` (factorised, `n` rows, finite).
    fn check_half(&self, v: &[f64], what: &'static str) -> Result<(), SolveError> {
        if !self.factorized {
            return Err(SolveError::NotFactorized);
        }
        if v.len() != self.n() {
            return Err(SolveError::DimensionMismatch {
                expected: self.n(),
                got: v.len(),
            });
        }
        match v.iter().position(|x| !x.is_finite()) {
            Some(index) => Err(SolveError::NonFinite { what, index }),
            None => Ok(()),
        }
    }

    /// One triangle of the factor applied to `x` (permuted numbering):
    /// L⁻¹x when `lower`, L⁻ᵀx otherwise.
    fn triangle_solve(&self, x: &mut [f64], lower: bool) -> Result<(), SolveError> {
        if let Some(split) = &self.split {
            split.sweep.sweep(&self.symbolic, &self.l_values, x, lower);
            return Ok(());
        }
        let n = x.len();
        let mut mem = MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(1, SOLVE_PAR))
            .map_err(|e| SolveError::Faer(format!("scratch allocation: {e}")))?;
        let stack = MemStack::new(&mut mem);
        let rhs = MatMut::from_column_major_slice_mut(x, n, 1);
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                if lower {
                    sparse_triangular::solve_lower_triangular_in_place(l, Conj::No, rhs, SOLVE_PAR);
                } else {
                    sparse_triangular::solve_lower_triangular_transpose_in_place(
                        l,
                        Conj::No,
                        rhs,
                        SOLVE_PAR,
                    );
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLltRef::new(s, &self.l_values);
                if lower {
                    l.l_solve_with_conj(Conj::No, rhs, SOLVE_PAR, stack);
                } else {
                    l.l_transpose_solve_with_conj(Conj::No, rhs, SOLVE_PAR, stack);
                }
            }
        }
        Ok(())
    }

    /// The forward half c = L⁻¹ P b: `b` on entry (the matrix's numbering),
    /// c on exit (the factor's numbering).
    pub fn forward_in_place(&self, b: &mut [f64]) -> Result<(), SolveError> {
        self.check_half(b, "right-hand side")?;
        let t = Instant::now();
        let mut c = self.permuted(|i| b[i]);
        self.triangle_solve(&mut c, true)?;
        b.copy_from_slice(&c);
        let seconds = t.elapsed().as_secs_f64();
        self.record(|s| {
            s.n_solves += 1;
            s.n_rhs += 1;
            s.solve_seconds += seconds;
        });
        self.check_half(b, "forward solution")
    }

    /// The backward half x = Pᵀ L⁻ᵀ c: `c` on entry (the factor's
    /// numbering), x on exit (the matrix's numbering). After
    /// [`CholeskySolver::forward_in_place`], a solve.
    pub fn backward_in_place(&self, c: &mut [f64]) -> Result<(), SolveError> {
        self.check_half(c, "forward solution")?;
        let t = Instant::now();
        let mut y = c.to_vec();
        self.triangle_solve(&mut y, false)?;
        self.unpermute(&y, |i, v| c[i] = v);
        let seconds = t.elapsed().as_secs_f64();
        self.record(|s| s.solve_seconds += seconds);
        self.check_half(c, "solution")
    }

    /// L⁻¹ P u for a `u` given by its entries (unknown, value), computed on
    /// the reach of the entries only (a batch of one).
    pub fn forward_reach(
        &self,
        entries: &[(usize, f64)],
        work: &mut ReachWork,
    ) -> Result<ReachColumn, SolveError> {
        let mut ys = self.forward_reach_many(&[entries.to_vec()], work)?;
        Ok(ys.pop().unwrap_or_default())
    }

    /// [`CholeskySolver::forward_reach`] of several right-hand sides at
    /// once (at most [`REACH_BATCH`] per batch, solved with matrix
    /// products on the union of their reaches), each returned on its own
    /// reach.
    pub fn forward_reach_many(
        &self,
        columns: &[Vec<(usize, f64)>],
        work: &mut ReachWork,
    ) -> Result<Vec<ReachColumn>, SolveError> {
        if !self.factorized {
            return Err(SolveError::NotFactorized);
        }
        let n = self.n();
        for col in columns {
            if let Some(&(i, _)) = col.iter().find(|&&(i, v)| i >= n || !v.is_finite()) {
                return Err(SolveError::NonFinite {
                    what: "reach right-hand side",
                    index: i,
                });
            }
        }
        let t = Instant::now();
        let mut permuted: Vec<Vec<(usize, f64)>> = columns
            .iter()
            .map(|col| {
                col.iter()
                    .map(|&(i, v)| (self.permuted_row(i), v))
                    .collect()
            })
            .collect();
        // batched in the factor's order: neighbours in it share the most
        // of their reaches, so a batch's union holds few blocks only some
        // of its columns need
        let mut order: Vec<usize> = (0..columns.len()).collect();
        order.sort_by_key(|&c| permuted[c].iter().map(|e| e.0).min());
        let batches: Vec<Vec<Vec<(usize, f64)>>> = order
            .chunks(REACH_BATCH)
            .map(|batch| {
                (batch.iter())
                    .map(|&c| std::mem::take(&mut permuted[c]))
                    .collect()
            })
            .collect();
        let solve = |cols: &Vec<Vec<(usize, f64)>>, work: &mut ReachWork| {
            forward_reach_many(&self.symbolic, &self.l_values, &self.tree, cols, work)
        };
        // batches are independent: on two cores where the sweeps are
        // (each batch the same bits wherever it runs)
        let solved: Vec<Vec<ReachColumn>> = if self.split.is_some() && batches.len() > 1 {
            use rayon::prelude::*;
            (batches.par_iter())
                .map_init(ReachWork::default, |w, cols| solve(cols, w))
                .collect()
        } else {
            batches.iter().map(|cols| solve(cols, work)).collect()
        };
        let mut out = vec![ReachColumn::default(); columns.len()];
        for (&c, y) in order.iter().zip(solved.into_iter().flatten()) {
            out[c] = y;
        }
        let seconds = t.elapsed().as_secs_f64();
        self.record(|s| {
            s.n_reach_columns += columns.len() as u64;
            s.reach_seconds += seconds;
        });
        if let Some(i) = out.iter().position(|y| !y.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "reach solution",
                index: i,
            });
        }
        Ok(out)
    }

    /// Rows and entries of L on the union of the reaches of `dofs`: what a
    /// half solve restricted to them would read (a measurement).
    pub fn reach_size(&self, dofs: &[usize]) -> (usize, usize) {
        let rows = dofs.iter().map(|&d| self.permuted_row(d));
        reach_size(&self.symbolic, &self.tree, rows)
    }

    /// Flops and rows of the reach solve of a unit vector on `dof`: what a
    /// capacitance column costs (a deterministic measure, compared with
    /// [`CholeskySolver::factor_flops`]).
    pub fn reach_cost(&self, dof: usize) -> (f64, u64) {
        self.tree.path_of_column(self.permuted_row(dof))
    }
}

/// The permuted structure a numeric factorisation reads: for a supernodal
/// analysis always, for a simplicial one only with `held` rows (else faer
/// permutes the matrix itself).
fn permuted_lower(
    pattern: &Pattern,
    symbolic: &SymbolicCholesky<u32>,
    held: Option<&[bool]>,
) -> Option<PermutedLower> {
    let upper = match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(_) => false,
        SymbolicCholeskyRaw::Simplicial(_) if held.is_some() => true,
        SymbolicCholeskyRaw::Simplicial(_) => return None,
    };
    let inv: Vec<u32> = match symbolic.perm() {
        Some(p) => p.arrays().1.to_vec(),
        None => (0..pattern.n_dofs() as u32).collect(),
    };
    Some(PermutedLower::new(pattern, &inv, upper, held))
}

/// The elimination order `fwd` with the `held` rows first. A held row is
/// a root of its own in the elimination tree wherever it stands, so it
/// adds no fill anywhere; but left inside a separator it splits the
/// separator's dense block into smaller supernodes: on the Xiaowan-like
/// complete dam the factorisations then took 76.0 against 52.3 s for
/// fewer flops.
fn held_first(fwd: Vec<u32>, held: Option<&Vec<bool>>) -> Vec<u32> {
    let Some(held) = held else {
        return fwd;
    };
    let is_held = |d: &u32| held.get(*d as usize).copied().unwrap_or(false);
    let (mut first, rest): (Vec<u32>, Vec<u32>) = fwd.into_iter().partition(is_held);
    first.extend(rest);
    first
}

/// The error of a matrix whose entry `k` (a held row's coupling) is not
/// zero.
fn held_coupling(pattern: &Pattern, held: Option<&Vec<bool>>, k: usize) -> SolveError {
    let col = pattern.col_ptr().partition_point(|&p| p as usize <= k) - 1;
    let row = pattern.row_idx()[k] as usize;
    let row_held = held.is_some_and(|h| h[row]);
    let (held, other) = if row_held { (row, col) } else { (col, row) };
    SolveError::HeldRowCoupled { held, other }
}

/// A pattern's upper structure without the off-diagonal entries of its
/// held rows: what the analysis of [`CholeskySolver::with_held`] reads.
struct Decoupled {
    n: usize,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
}

impl Decoupled {
    fn new(pattern: &Pattern, held: &[bool]) -> Self {
        let n = pattern.n_dofs();
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0u32);
        let mut row_idx = Vec::with_capacity(ri.len());
        for j in 0..n {
            let rows = &ri[cp[j] as usize..cp[j + 1] as usize];
            row_idx.extend(
                rows.iter()
                    .filter(|&&i| !left_out(i as usize, j, Some(held))),
            );
            col_ptr.push(row_idx.len() as u32);
        }
        Decoupled {
            n,
            col_ptr,
            row_idx,
        }
    }

    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, u32> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// Workspace of a numeric factorisation: faer's whole one, or only its
/// supernodal part when the matrix comes permuted ([`PermutedLower`]).
fn factor_scratch(
    symbolic: &SymbolicCholesky<u32>,
    permuted: bool,
    par: Par,
) -> Result<MemBuffer, SolveError> {
    let req = match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) if permuted => {
            supernodal::factorize_supernodal_numeric_llt_scratch::<u32, f64>(
                s,
                par,
                Default::default(),
            )
        }
        SymbolicCholeskyRaw::Simplicial(_) if permuted => {
            simplicial::factorize_simplicial_numeric_llt_scratch::<u32, f64>(symbolic.nrows())
        }
        _ => symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
    };
    MemBuffer::try_new(req).map_err(|e| SolveError::Faer(format!("scratch allocation: {e}")))
}

/// faer's symbolic Cholesky of `pattern` in the elimination order `fwd`
/// (`fwd[k]` is the dof eliminated k-th).
fn symbolic_custom(
    structure: SymbolicSparseColMatRef<'_, u32>,
    fwd: &[u32],
) -> Result<Result<SymbolicCholesky<u32>, faer::sparse::FaerError>, SolveError> {
    let n = structure.nrows();
    let mut inv = vec![u32::MAX; n];
    let valid = fwd.len() == n
        && fwd.iter().enumerate().all(|(k, &d)| {
            let ok = (d as usize) < n && inv[d as usize] == u32::MAX;
            if ok {
                inv[d as usize] = k as u32;
            }
            ok
        });
    if !valid {
        return Err(SolveError::InvalidOrdering { n });
    }
    Ok(factorize_symbolic_cholesky(
        structure,
        Side::Upper,
        SymmetricOrdering::Custom(PermRef::new_checked(fwd, &inv, n)),
        Default::default(),
    ))
}

/// ‖b − A x‖₂ / ‖b‖₂ (or ‖A x‖₂ when b = 0).
pub fn relative_residual(matrix: &SparseSym, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; matrix.n()];
    matrix.mul_vec(x, &mut ax);
    let r: f64 = ax
        .iter()
        .zip(b)
        .map(|(a, b)| (b - a) * (b - a))
        .sum::<f64>()
        .sqrt();
    let nb: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    if nb > 0.0 {
        r / nb
    } else {
        r
    }
}

/// `len` zeros, or `None` where the memory is not there. Asked of the
/// allocator as zeroed memory, so that a new block's pages are zeroed by
/// the kernel where they are first written: for a large factor, inside
/// the factorisation, by the thread that factorises each block (the
/// two-core factorisation shares them out), rather than by one thread
/// writing zeros over all of it first (the large complete dam's first
/// factor: 2 GB, 3 s on one core of this virtual machine, whose fresh
/// pages come from the host).
fn zeroed(len: usize) -> Option<Vec<f64>> {
    let layout = std::alloc::Layout::array::<f64>(len).ok()?;
    if layout.size() == 0 {
        return Some(Vec::new());
    }
    // SAFETY: a non-zero layout for `len` f64s; all-zero bytes are the
    // f64 0.0, and the block is handed to a Vec of the same layout, whose
    // drop frees it with the global allocator that made it.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout) as *mut f64;
        (!p.is_null()).then(|| Vec::from_raw_parts(p, len, len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 7-point Laplacian of an `m`³ grid of nodes, one two-node element
    /// per edge, with a diagonal shift (positive definite).
    fn laplacian(m: usize) -> SparseSym {
        let node = |i: usize, j: usize, k: usize| (i + m * (j + m * k)) as u32;
        let mut edges = Vec::new();
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let here = node(i, j, k);
                    if i + 1 < m {
                        edges.push([here, node(i + 1, j, k)]);
                    }
                    if j + 1 < m {
                        edges.push([here, node(i, j + 1, k)]);
                    }
                    if k + 1 < m {
                        edges.push([here, node(i, j, k + 1)]);
                    }
                }
            }
        }
        let mut a = SparseSym::new(Arc::new(Pattern::new(m * m * m, &edges)));
        let ke = nalgebra::Matrix2::new(1.0, -1.0, -1.0, 1.0);
        for e in 0..edges.len() {
            a.add_element(e, &ke);
        }
        for d in 0..m * m * m {
            a.add_diag(d, 0.1 + (d % 5) as f64 * 0.01);
        }
        a
    }

    /// The supernodal factor made from the matrix permuted once per
    /// analysis ([`PermutedLower`]) is faer's own, made with its
    /// permutation at the call, to the bit.
    #[test]
    fn the_factor_from_the_map_is_faers_to_the_bit() {
        let a = laplacian(20);
        for ordering in [Ordering::Metis, Ordering::Amd] {
            let mut s = CholeskySolver::with_options(a.pattern().clone(), &ordering, Par::Seq)
                .expect("analysis");
            assert!(s.is_supernodal(), "{ordering:?}: a supernodal analysis");
            s.factorize(&a).expect("positive definite");
            let mut faers = vec![0.0; s.symbolic.len_val()];
            let mut mem = MemBuffer::new(
                s.symbolic
                    .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            );
            s.symbolic
                .factorize_numeric_llt::<f64>(
                    &mut faers,
                    a.as_faer(),
                    Side::Upper,
                    Default::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .expect("positive definite");
            assert_eq!(faers.len(), s.l_values.len());
            assert!(
                faers
                    .iter()
                    .zip(&s.l_values)
                    .all(|(x, y)| x.to_bits() == y.to_bits()),
                "{ordering:?}: the factors differ"
            );
        }
    }

    /// Rows held in every matrix ([`CholeskySolver::with_held`]) leave the
    /// analysis: the factor has fewer flops, solves as the factor that
    /// keeps them does (supernodal and simplicial), and a matrix that
    /// still couples a held row is refused.
    #[test]
    fn held_rows_are_eliminated_without_fill() {
        for (m, supernodal) in [(24, true), (3, false)] {
            let a = laplacian(m);
            let n = m * m * m;
            // a plane through the middle, which the analysis would cut at
            let held: Vec<bool> = (0..n).map(|d| d % m == m / 2).collect();
            let mut held_a = a.clone();
            held_a.apply_dirichlet(&held);
            let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
            for ordering in [Ordering::Metis, Ordering::Amd] {
                let mut kept =
                    CholeskySolver::with_options(a.pattern().clone(), &ordering, Par::Seq)
                        .expect("analysis");
                let mut left =
                    CholeskySolver::with_held(a.pattern().clone(), &ordering, Par::Seq, &held)
                        .expect("analysis");
                assert_eq!(left.is_supernodal(), supernodal, "{m}³ {ordering:?}");
                assert!(
                    left.factor_flops() < 0.9 * kept.factor_flops(),
                    "{m}³ {ordering:?}: {} against {} flops",
                    left.factor_flops(),
                    kept.factor_flops()
                );
                kept.factorize(&held_a).expect("positive definite");
                left.factorize(&held_a).expect("positive definite");
                let (mut x, mut y) = (b.clone(), b.clone());
                kept.solve_in_place(&mut x).expect("solve");
                left.solve_in_place(&mut y).expect("solve");
                let scale = x.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                let diff = x
                    .iter()
                    .zip(&y)
                    .fold(0.0f64, |s, (p, q)| s.max((p - q).abs()));
                assert!(
                    diff <= 1e-13 * scale,
                    "{m}³ {ordering:?}: {diff:e} of {scale:e}"
                );
                assert!(relative_residual(&held_a, &y, &b) < 1e-13);
                match left.factorize(&a) {
                    Err(SolveError::HeldRowCoupled { held: h, other }) => {
                        assert!(held[h], "row {h} is not held");
                        assert!(
                            a.pattern().find(h, other).is_some(),
                            "{h}, {other} not coupled"
                        );
                    }
                    other => panic!("{m}³ {ordering:?}: a coupled held row gave {other:?}"),
                }
                assert!(!left.is_factorized());
            }
        }
    }
}
