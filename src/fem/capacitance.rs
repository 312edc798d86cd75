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
//! With U = [A\[f₀,R\], E_N] (m = |R| + |N| columns, zero on F₀) and
//! eliminating x_f, what is left is the m × m capacitance system
//!
//! ```text
//! S w = r,   S = [[A[R,R], 0], [0, 0]] − UᵀK⁻¹U,   r = [b_R; p_N] − UᵀK⁻¹b_f,
//! x_f = K⁻¹(b_f − U w),   x_R = w_R,   x = p on F₀ ∩ F₁.
//! ```
//!
//! The factor is M₀ = Pᵀ L Lᵀ P, so with Y = L⁻¹PU and c = L⁻¹P b_f
//! ([`super::half_solves`]):
//!
//! ```text
//! UᵀK⁻¹U = YᵀY,   UᵀK⁻¹b_f = Yᵀc,   x_f = Pᵀ L⁻ᵀ (c − Y w).
//! ```
//!
//! An application is one forward and one backward half, as a plain solve;
//! a column of Y is a forward half alone, of a vector with few entries
//! (a unit vector, or a column of A), so it is computed on its reach in
//! the elimination tree only: on the demo's live systems 7 % of the rows,
//! where a column of K⁻¹U was two sweeps over the whole factor. Within a
//! step the passes' right-hand sides differ in few rows, so the forward
//! half of an application is the last full one plus the forward half of
//! the difference, on its reach ([`Capacitance::solve`]).
//!
//! A spring added to or removed from a row free in both sets (a grout
//! layer bonded or cracked: its stiffness sits on the diagonal of its
//! pair's rows) changes A₀'s diagonal there by δᵢ, K by Σ δᵢ eᵢeᵢᵀ. Each
//! such row D is bordered with μᵢ = δᵢ x_i: U gains the column e_i (the
//! same Y column as a newly fixed row), S the diagonal entry −1/δᵢ, r a
//! zero (eliminate x_f from K x_f + … + E_D μ = b_f and x_D − μ/δ = 0).
//! The caller then passes the changed matrix (its diagonal the new one)
//! and the base diagonal ([`Capacitance::with_diagonal`]); the rows
//! released or fixed read their own entries from the changed matrix, and
//! the off-diagonal columns U are untouched by springs, so the cached Y
//! columns stay valid.
//!
//! A coupling ([`Coupling`]) is a load on free rows proportional to a row
//! of A x: a slipping joint point's friction force μ_k r_n s on its two
//! tangential rows, r_n = (A x)_n its normal reaction. Each adds an unknown
//! z = a_nᵀx (the whole row: fixed columns at their values, released ones
//! in w), a column −g (its loads) to the rows and a row z − a_nᵀx = 0.
//! Eliminating x_f as above, with Y_G = L⁻¹P g_f (g on the rows free in
//! the base: combinations of unit columns, the same Y columns as newly
//! fixed rows) and Y_V = L⁻¹P A[f₀, n] (the column a released row n would
//! have), the system in (w, z) is
//!
//! ```text
//! [ D − Y_UᵀY_U      Y_UᵀY_G − G_R ] [w]   [r − Y_Uᵀc         ]
//! [ Y_VᵀY_U − V_Rᵀ   I − Y_VᵀY_G   ] [z] = [A[n, held] p + Y_Vᵀc]
//! ```
//!
//! (G_R, V_R: the loads on released rows and the reaction rows' entries
//! in released columns), and x_f = PᵀL⁻ᵀ(c − Y_U w + Y_G z). It is not
//! symmetric; LU solves it all the same.
//!
//! Without couplings S is symmetric quasi-definite (the Schur complement
//! of an SPD matrix in the R block, −E_NᵀK⁻¹E_N in the N block), solved
//! densely by LU (faer's, blocked), equilibrated by its diagonal first:
//! its blocks are in N/m and m/N, twenty orders apart on concrete
//! ([`EquilibratedLu`]). Its
//! factor is kept while the changed rows and the entries of A that S reads
//! (A\[R,R\] and the diagonal changes) stay the same: the refinements and the
//! passes that move only loads (a slip-force round) reuse it, where m³/3
//! per pass dominated the complete Xiaowan-like dam (thousands of changed
//! rows). The columns of Y and
//! their products YᵢᵀYⱼ depend on the base factor only, so they are kept:
//! a later pass pays only for rows it has not met. The products a new S
//! needs are computed together, block of L by block ([`gram`]: one dense
//! matrix product per block over the columns whose reach holds it:
//! 24–30 Gflop/s, where a merge of two columns' spans per pair ran at 5–7
//! and, with S's LUs, took 2.6 s of a 22.5 s late day of the
//! Xiaowan-like arch). The result is
//! exact (no penalty, no tolerance); the caller checks its residual on the
//! F₁ matrix like any solve.
//!
//! Verified by `tests/it/fem_sparse.rs`: the corrected solution equals
//! a fresh factorisation of the F₁ system to round-off for rows fixed,
//! released and both, with prescribed values, and with springs added to and
//! removed from free rows besides; with couplings, it equals the coupled
//! system solved by a fresh factorisation, a solve per coupling and a
//! dense system in z (1e-12).

use std::collections::BTreeMap;

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::{Mat, Par};

use super::half_solves::{gram, ReachColumn, ReachWork};
use super::solver::{CholeskySolver, SolveError};
use super::sparse::SparseSym;

/// Refinements of a corrected solution on its residual, at most.
pub const MAX_REFINEMENTS: usize = 3;
/// Residual relative to the right-hand side that [`Capacitance::solve`]
/// refines to: four digits below the callers' residual checks (1e-8).
pub const REFINE_TO: f64 = 1e-12;

/// The residual rhs + G (A x)_n − A x of the coupled system on the rows not
/// in `fixed` (zero on them), its 2-norm, and A x.
fn free_residual(
    a: &SparseSym,
    fixed: &[bool],
    rhs: &[f64],
    couplings: &[Coupling],
    x: &[f64],
) -> (Vec<f64>, f64, Vec<f64>) {
    let mut ax = vec![0.0; a.n()];
    a.mul_vec(x, &mut ax);
    let mut r: Vec<f64> = (0..a.n())
        .map(|i| if fixed[i] { 0.0 } else { rhs[i] - ax[i] })
        .collect();
    for c in couplings {
        let reaction = ax[c.reaction_row as usize];
        for &(t, coef) in &c.loads {
            if !fixed[t as usize] {
                r[t as usize] += coef * reaction;
            }
        }
    }
    let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
    (r, norm, ax)
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
    held_norms(fixed, presc, &b, x, |i| b[i] - ax[i]).0
}

/// The residual of `x` as the solution of the system that A with the rows
/// `fixed` held at `presc` becomes (b its [`constrained_rhs`]), measured
/// with the whole product A x: rhs − A x on the free rows and presc − x on
/// the fixed ones. That is [`constrained_residual`]'s b − M x where x holds
/// presc on the fixed rows, as a factor of M leaves it (an identity row);
/// the product is returned for the caller's reactions. Returns
/// (‖b − M x‖ / ‖b‖, ‖b − M x‖, A x).
pub fn held_residual(
    a: &SparseSym,
    fixed: &[bool],
    presc: &[f64],
    rhs: &[f64],
    b: &[f64],
    x: &[f64],
) -> (f64, f64, Vec<f64>) {
    let mut ax = vec![0.0; a.n()];
    a.mul_vec(x, &mut ax);
    let (relative, norm) = held_norms(fixed, presc, b, x, |i| rhs[i] - ax[i]);
    (relative, norm, ax)
}

/// (‖r‖ / ‖b‖, ‖r‖) of the residual r = presc − x on the fixed rows and
/// `free(i)` on the others (‖r‖ alone when b = 0).
fn held_norms(
    fixed: &[bool],
    presc: &[f64],
    b: &[f64],
    x: &[f64],
    free: impl Fn(usize) -> f64,
) -> (f64, f64) {
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..fixed.len() {
        let r = if fixed[i] { presc[i] - x[i] } else { free(i) };
        num += r * r;
        den += b[i] * b[i];
    }
    let norm = num.sqrt();
    (if den > 0.0 { norm / den.sqrt() } else { norm }, norm)
}

/// The right-hand side of the system M x = b that A with the rows `fixed`
/// held at `presc` becomes: `rhs` less the fixed columns' loads on the free
/// rows, `presc` on the fixed ones.
pub fn constrained_rhs(a: &SparseSym, fixed: &[bool], presc: &[f64], rhs: &[f64]) -> Vec<f64> {
    let mut b = rhs.to_vec();
    a.dirichlet_correction(fixed, presc, &mut b);
    for i in 0..a.n() {
        if fixed[i] {
            b[i] = presc[i];
        }
    }
    b
}

/// How far [`Capacitance::solve`] refines, and from where.
#[derive(Debug, Clone, PartialEq)]
pub struct Refine {
    /// residual relative to the right-hand side
    pub to: f64,
    /// an earlier solution of the same system to refine (the correction's
    /// own first solution when `None`)
    pub from: Option<Vec<f64>>,
}

impl Default for Refine {
    /// To [`REFINE_TO`], from the correction's own solution.
    fn default() -> Self {
        Refine {
            to: REFINE_TO,
            from: None,
        }
    }
}

/// A corrected solution and its relative residual on the changed system.
#[derive(Debug, Clone, PartialEq)]
pub struct Corrected {
    pub x: Vec<f64>,
    /// ‖b − M x‖ / ‖b‖ of the constrained system, what
    /// [`constrained_residual`] measures (see [`Capacitance::solve`])
    pub residual: f64,
    /// ‖b − M x‖ itself
    pub residual_norm: f64,
    /// A x, the matrix given to [`Capacitance::solve`] (fixed columns
    /// included): the residual's product, which a caller reading reactions
    /// off the solution need not compute again
    pub ax: Vec<f64>,
    /// rows of the capacitance system: the changed rows, then the couplings
    pub rank: usize,
    pub couplings: usize,
}

/// A load proportional to a row of A x: each row `t` of `loads` (free in
/// the solved set) carries `coef · (A x)[reaction_row]`, the whole row of A
/// (fixed columns included). A slipping joint point is one: its friction
/// force μ_k r_n s on its two tangential rows, with r_n its normal
/// reaction. The coupled system is not symmetric; it is solved by the same
/// bordered elimination (see the module doc), exactly, in one pass where a
/// fixed point of the forces took several.
#[derive(Debug, Clone, PartialEq)]
pub struct Coupling {
    pub reaction_row: u32,
    pub loads: Vec<(u32, f64)>,
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
    /// The change whose column of Y this one uses: a diagonal change's
    /// column is L⁻¹Pe_i, the same as a newly fixed row's.
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
    /// columns of Y computed (each the forward half of a solve on its reach)
    pub columns: u64,
    /// rows of those columns (Σ of their reaches)
    #[serde(default)]
    pub column_rows: u64,
    /// flops of their reach solves, as [`CholeskySolver::reach_cost`]
    /// estimates them (the weight of a column in the break-even choice)
    #[serde(default)]
    pub column_flops: f64,
    /// rows of their systems (what dense columns would hold)
    #[serde(default)]
    pub column_dense_rows: u64,
    /// wall time of the columns \[s\] (in `seconds` too)
    #[serde(default)]
    pub column_seconds: f64,
    /// forward halves of an application computed as the last full one
    /// plus the forward half of the difference, on its reach
    #[serde(default)]
    pub forward_reaches: u64,
    /// LU factorisations of a capacitance system S (the others reused the
    /// last one: same changed rows, same entries of A)
    #[serde(default)]
    pub s_factorisations: u64,
    /// flops of those factorisations (m³ · 2/3 each) and their wall time
    /// with S's assembly \[s\] (in `seconds` too)
    #[serde(default)]
    pub s_flops: f64,
    #[serde(default)]
    pub s_seconds: f64,
    /// wall time of the products YᵢᵀYⱼ computed block by block \[s\] (in
    /// `s_seconds` too)
    #[serde(default)]
    pub product_seconds: f64,
    /// their flops
    #[serde(default)]
    pub product_flops: f64,
    /// couplings bordered (Σ over the corrected solves; see [`Coupling`])
    #[serde(default)]
    pub couplings: u64,
    /// largest capacitance system [changed rows]
    pub max_rank: usize,
    /// refinements on the residual
    pub refinements: u64,
    /// wall time of the corrections \[s\]
    pub seconds: f64,
}

impl CapacitanceStats {
    /// Adds `other`'s counts and time (the largest rank of both).
    pub fn add(&mut self, other: &CapacitanceStats) {
        self.solves += other.solves;
        self.columns += other.columns;
        self.column_rows += other.column_rows;
        self.column_dense_rows += other.column_dense_rows;
        self.column_flops += other.column_flops;
        self.forward_reaches += other.forward_reaches;
        self.column_seconds += other.column_seconds;
        self.s_factorisations += other.s_factorisations;
        self.couplings += other.couplings;
        self.s_flops += other.s_flops;
        self.s_seconds += other.s_seconds;
        self.product_seconds += other.product_seconds;
        self.product_flops += other.product_flops;
        self.max_rank = self.max_rank.max(other.max_rank);
        self.refinements += other.refinements;
        self.seconds += other.seconds;
    }

    /// What was added since `before` (the largest rank is this one's).
    pub fn since(&self, before: &CapacitanceStats) -> CapacitanceStats {
        CapacitanceStats {
            solves: self.solves - before.solves,
            columns: self.columns - before.columns,
            column_rows: self.column_rows - before.column_rows,
            column_dense_rows: self.column_dense_rows - before.column_dense_rows,
            column_flops: self.column_flops - before.column_flops,
            forward_reaches: self.forward_reaches - before.forward_reaches,
            column_seconds: self.column_seconds - before.column_seconds,
            s_factorisations: self.s_factorisations - before.s_factorisations,
            couplings: self.couplings - before.couplings,
            s_flops: self.s_flops - before.s_flops,
            s_seconds: self.s_seconds - before.s_seconds,
            product_seconds: self.product_seconds - before.product_seconds,
            product_flops: self.product_flops - before.product_flops,
            max_rank: self.max_rank,
            refinements: self.refinements - before.refinements,
            seconds: self.seconds - before.seconds,
        }
    }
}

/// The LU of a capacitance system and what decides S: the changed rows
/// and the entries of A it reads ([`Capacitance::s_entries`]).
#[derive(Debug)]
struct SFactor {
    changes: Vec<(u32, RowChange)>,
    couplings: Vec<Coupling>,
    entries: Vec<f64>,
    lu: Option<EquilibratedLu>,
}

/// The LU of a capacitance matrix equilibrated by its diagonal: S̃ = D S D
/// with D = diag(|Sᵢᵢ|^(−1/2)) (1 where Sᵢᵢ is zero), solved as
/// w = D S̃⁻¹ D r.
///
/// S mixes units: a released row's entries are stiffnesses (N/m, 1e10 on
/// concrete), a newly fixed row's are compliances (−E_NᵀK⁻¹E_N, m/N,
/// 1e−10), a spring's −1/δ and a coupling's dimensionless. Partial
/// pivoting on the raw matrix then loses digits to the scale alone: on the
/// demo's complete dam the first application of a correction left a
/// residual of up to 1.0e−5 (median 8.6e−13), on the Xiaowan-like arch's
/// late days 1e−8 to 1e−2, so nearly every pass paid a refinement (a
/// forward and a backward sweep over L). Equilibrated, the first
/// application lands at 8e−13 on the demo and 2.4e−11 at worst on the
/// large arch (`fem_sparse::capacitance_first_application_…`).
#[derive(Debug)]
struct EquilibratedLu {
    lu: PartialPivLu<f64>,
    scale: Vec<f64>,
}

impl EquilibratedLu {
    fn new(mut s: Mat<f64>) -> EquilibratedLu {
        let n = s.nrows();
        let scale: Vec<f64> = (0..n)
            .map(|i| {
                let d = s[(i, i)].abs();
                if d.is_finite() && d > 0.0 {
                    1.0 / d.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        for (j, &dj) in scale.iter().enumerate() {
            for (i, &di) in scale.iter().enumerate() {
                s[(i, j)] *= di * dj;
            }
        }
        EquilibratedLu {
            lu: s.partial_piv_lu(),
            scale,
        }
    }

    /// r ← S⁻¹ r, every column of r.
    fn solve_in_place(&self, mut r: faer::MatMut<'_, f64>) {
        let scale_rows = |r: &mut faer::MatMut<'_, f64>| {
            for j in 0..r.ncols() {
                for (i, &d) in self.scale.iter().enumerate() {
                    r[(i, j)] *= d;
                }
            }
        };
        scale_rows(&mut r);
        self.lu.solve_in_place(r.as_mut());
        scale_rows(&mut r);
    }
}

/// The base fixed set of a factor and the columns of Y met so far.
#[derive(Debug)]
pub struct Capacitance {
    base: Vec<bool>,
    /// the base matrix's diagonal when the solved matrices may differ
    /// from it there ([`Capacitance::with_diagonal`])
    base_diag: Option<Vec<f64>>,
    /// index in `y` of the column of each changed row, by (dof, change)
    index: BTreeMap<(u32, RowChange), u32>,
    /// Y = L⁻¹PU, one reach column per key of `index`
    y: Vec<ReachColumn>,
    /// YᵢᵀYⱼ by (j, i), i ≤ j (`dots[j][i]`; NaN where not computed yet)
    dots: Vec<Vec<f64>>,
    /// the right-hand side b_f of the last full forward half and that half
    /// (c = L⁻¹P b_f), from which a right-hand side differing in few rows
    /// starts
    forward_ref: Option<(Vec<f64>, Vec<f64>)>,
    /// the last capacitance matrix's LU and what it was built from
    s_factor: Option<SFactor>,
    work: ReachWork,
    pub stats: CapacitanceStats,
}

impl Capacitance {
    /// For a factor of A with the rows `base` fixed.
    pub fn new(base: Vec<bool>) -> Self {
        Capacitance {
            base,
            base_diag: None,
            index: BTreeMap::new(),
            y: Vec::new(),
            dots: Vec::new(),
            forward_ref: None,
            s_factor: None,
            work: ReachWork::default(),
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

    /// The column keys of `keys` not met yet, each once, in key order.
    fn new_keys(
        &self,
        keys: impl Iterator<Item = (u32, RowChange)>,
    ) -> std::collections::BTreeSet<(u32, RowChange)> {
        keys.map(|(dof, c)| (dof, c.column_key()))
            .filter(|k| !self.index.contains_key(k))
            .collect()
    }

    /// What the new columns of `changes` would cost on `solver`'s factor:
    /// the flops of their reach solves and of their products with the
    /// other columns of S (at most twice the rows of each, for each of the
    /// m changes), and the bytes they would hold with their products.
    /// Each reach is estimated by that of the column's own row (a
    /// released row's column also has entries on its neighbours, whose
    /// paths join it within a few blocks). The products matter when m is
    /// large: on the Xiaowan-like arch's complete dam, thousands of
    /// changed rows took the step to 644 s before they were counted.
    pub fn new_columns_cost(
        &self,
        solver: &CholeskySolver,
        changes: &[(u32, RowChange)],
    ) -> (f64, usize) {
        let dofs: Vec<u32> = self
            .new_keys(changes.iter().copied())
            .iter()
            .map(|&(dof, _)| dof)
            .collect();
        columns_cost(solver, &dofs, changes.len(), self.y.len())
    }

    /// The columns a coupling borders the factor with: its reaction row's
    /// (a released row's) and its loads' on rows free in the base (fixed
    /// rows' unit columns).
    fn coupling_keys<'c>(&'c self, c: &'c Coupling) -> impl Iterator<Item = (u32, RowChange)> + 'c {
        let loads = c.loads.iter().filter(|&&(t, _)| !self.base[t as usize]);
        std::iter::once((c.reaction_row, RowChange::Released))
            .chain(loads.map(|&(t, _)| (t, RowChange::Fixed)))
    }

    /// The column of Y of a change.
    fn y_of(&self, &(dof, change): &(u32, RowChange)) -> u32 {
        self.index[&(dof, change.column_key())]
    }

    /// Bytes held by the cached columns.
    pub fn memory_bytes(&self) -> usize {
        let columns: usize = self.y.iter().map(ReachColumn::memory_bytes).sum();
        columns + 8 * self.dots.iter().map(Vec::len).sum::<usize>()
    }

    /// Solves A x = rhs + Σ couplings with the rows `fixed` held at
    /// `presc`, using `solver`, a factor of A with the base rows fixed
    /// (identity rows). `rhs` is uncorrected: the loads of every prescribed
    /// value are applied here. A coupling's loads on fixed rows are
    /// dropped (a held row takes no load). The correction loses digits when
    /// the capacitance system is ill-conditioned (seen on the demo:
    /// 1.3e-8), so the result is refined on the residual of the free rows
    /// until it stops improving (at most [`MAX_REFINEMENTS`] times).
    ///
    /// The returned residual is the refinement's last one, relative to the
    /// constrained right-hand side: x holds `presc` exactly on the fixed
    /// rows, so rhs − A x on the free rows is b − M x there (b the
    /// constrained right-hand side, M the constrained matrix) and zero on
    /// the fixed rows, i.e. [`constrained_residual`]'s quantity (with the
    /// couplings' loads), without a second product with A.
    /// `refine`: the residual to refine to (relative to the right-hand
    /// side; [`REFINE_TO`] by default) and where from: the correction's
    /// own first solution, or an earlier solution of the same system.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        solver: &CholeskySolver,
        a: &SparseSym,
        fixed: &[bool],
        presc: &[f64],
        rhs: &[f64],
        couplings: &[Coupling],
        refine: Refine,
    ) -> Result<Corrected, SolveError> {
        let t = std::time::Instant::now();
        let n = a.n();
        if fixed.len() != n || presc.len() != n || rhs.len() != n || self.base.len() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                got: fixed.len().min(presc.len()).min(rhs.len()),
            });
        }
        if let Some(c) = couplings
            .iter()
            .find(|c| c.reaction_row as usize >= n || c.loads.iter().any(|&(t, _)| t as usize >= n))
        {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                got: c.reaction_row as usize,
            });
        }
        let changes = self.changes(a, fixed);
        let couplings: Vec<Coupling> = couplings
            .iter()
            .map(|c| Coupling {
                reaction_row: c.reaction_row,
                loads: c
                    .loads
                    .iter()
                    .copied()
                    .filter(|&(t, coef)| !fixed[t as usize] && coef != 0.0)
                    .collect(),
            })
            .filter(|c| !c.loads.is_empty())
            .collect();
        let keys = changes
            .iter()
            .copied()
            .chain(couplings.iter().flat_map(|c| self.coupling_keys(c)));
        let keys = self.new_keys(keys);
        self.fill_columns(solver, a, keys)?;
        let border = Border { changes, couplings };
        self.factor_capacitance(a, &border, solver.parallelism())?;
        // taken out for the applications, which borrow the columns mutably
        let s_factor = self.s_factor.take();
        let system = System {
            a,
            border: &border,
            fixed,
            lu: s_factor.as_ref().and_then(|f| f.lu.as_ref()),
        };
        let solved = self.refined(solver, &system, presc, rhs, refine);
        self.s_factor = s_factor;
        let (x, norm, ax) = solved?;
        let b_norm = constrained_rhs(a, fixed, presc, rhs)
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        let residual = if b_norm > 0.0 { norm / b_norm } else { norm };
        self.stats.solves += 1;
        self.stats.couplings += border.couplings.len() as u64;
        self.stats.max_rank = self.stats.max_rank.max(border.changes.len());
        self.stats.seconds += t.elapsed().as_secs_f64();
        Ok(Corrected {
            x,
            residual,
            residual_norm: norm,
            ax,
            rank: border.changes.len(),
            couplings: border.couplings.len(),
        })
    }

    /// One application of the correction, refined on the residual of the
    /// free rows until it stops improving; returns x, that residual's norm
    /// and A x.
    fn refined(
        &mut self,
        solver: &CholeskySolver,
        system: &System,
        presc: &[f64],
        rhs: &[f64],
        target: Refine,
    ) -> Result<(Vec<f64>, f64, Vec<f64>), SolveError> {
        let System {
            a, border, fixed, ..
        } = *system;
        let n = a.n();
        let mut x = match target.from {
            Some(x0) if x0.len() == n => x0,
            _ => self.apply(solver, system, presc, rhs, false)?,
        };
        let (mut r, mut norm, mut ax) = free_residual(a, fixed, rhs, &border.couplings, &x);
        let zero = vec![0.0; n];
        let enough = target.to * rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        for _ in 0..MAX_REFINEMENTS {
            if norm <= enough {
                break;
            }
            let dx = self.apply(solver, system, &zero, &r, true)?;
            let refined: Vec<f64> = x.iter().zip(&dx).map(|(x, d)| x + d).collect();
            let (r_next, next, ax_next) = free_residual(a, fixed, rhs, &border.couplings, &refined);
            self.stats.refinements += 1;
            if next >= norm {
                break;
            }
            (x, r, norm, ax) = (refined, r_next, next, ax_next);
        }
        Ok((x, norm, ax))
    }

    /// One application of the correction (the columns of the border
    /// filled, its capacitance matrix factorised): the forward half of the
    /// base solve, the (m + k) × (m + k) system, the backward half. A
    /// `refinement`'s right-hand side (a residual) takes a full forward
    /// half.
    fn apply(
        &mut self,
        solver: &CholeskySolver,
        system: &System,
        presc: &[f64],
        rhs: &[f64],
        refinement: bool,
    ) -> Result<Vec<f64>, SolveError> {
        let System {
            a,
            border,
            fixed,
            lu: s,
        } = *system;
        let n = a.n();
        let changes = &border.changes;
        let keep: Vec<bool> = self.base.iter().zip(fixed).map(|(&b, &f)| b && f).collect();
        let mut b = rhs.to_vec();
        a.dirichlet_correction(&keep, presc, &mut b);
        let b_f: Vec<f64> = (0..n)
            .map(|i| if self.base[i] { 0.0 } else { b[i] })
            .collect();
        let mut c = if refinement {
            let mut c = b_f;
            solver.forward_in_place(&mut c)?;
            c
        } else {
            self.forward_half(solver, b_f)?
        };
        let size = border.size();
        let w = match s {
            Some(lu) => {
                // r = [b_R; p_N; 0] − Uᵀy with Uᵢᵀy = Yᵢᵀc; a coupling's
                // row: the reaction's fixed columns, Vᵀy = Y_Vᵀc
                let mut r = Mat::from_fn(size, 1, |i, _| match changes.get(i) {
                    Some(ch) => {
                        let top = match ch.1 {
                            RowChange::Released => b[ch.0 as usize],
                            RowChange::Fixed => presc[ch.0 as usize],
                            RowChange::Diagonal => 0.0,
                        };
                        top - self.y[self.y_of(ch) as usize].dot_dense(&c)
                    }
                    None => {
                        let row = border.couplings[i - changes.len()].reaction_row;
                        let mut held = 0.0;
                        a.column(row as usize, |j, v| {
                            if keep[j] {
                                held += v * presc[j];
                            }
                        });
                        held + self.y[self.y_of(&(row, RowChange::Released)) as usize].dot_dense(&c)
                    }
                });
                lu.solve_in_place(r.as_mut());
                let w: Vec<f64> = (0..size).map(|i| r[(i, 0)]).collect();
                if !w.iter().all(|v| v.is_finite()) {
                    return Err(SolveError::SingularCapacitance { size });
                }
                w
            }
            None => Vec::new(),
        };
        // x_f = Pᵀ L⁻ᵀ (c − Y_U w + Y_G z)
        for (ch, &wj) in changes.iter().zip(w.iter()) {
            if wj != 0.0 {
                self.y[self.y_of(ch) as usize].axpy_into(-wj, &mut c);
            }
        }
        for (coupling, &z) in border
            .couplings
            .iter()
            .zip(&w[changes.len().min(w.len())..])
        {
            for &(t, coef) in &coupling.loads {
                if !self.base[t as usize] && z != 0.0 {
                    self.y[self.y_of(&(t, RowChange::Fixed)) as usize].axpy_into(coef * z, &mut c);
                }
            }
        }
        solver.backward_in_place(&mut c)?;
        let mut x = c;
        for (&(dof, change), &wj) in changes.iter().zip(w.iter()) {
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

    /// c = L⁻¹P b_f. Within a step the passes' right-hand sides differ in
    /// the rows of the joint points whose state or slip force changed (and
    /// the neighbours of a released row), so c is the last full forward
    /// half plus the forward half of the difference, on its reach, while
    /// that reach costs less than a sweep over L (Σ of the rows' path flops
    /// against the entries of L: the paths share their upper blocks, so the
    /// sum overstates the cost). The difference is formed exactly in the
    /// rows that differ, so the result is the full half's to round-off.
    fn forward_half(
        &mut self,
        solver: &CholeskySolver,
        b_f: Vec<f64>,
    ) -> Result<Vec<f64>, SolveError> {
        if let Some((b_ref, c_ref)) = &self.forward_ref {
            let diff: Vec<(usize, f64)> = b_f
                .iter()
                .zip(b_ref)
                .enumerate()
                .filter(|(_, (x, r))| x != r)
                .map(|(i, (x, r))| (i, x - r))
                .collect();
            let flops: f64 = diff.iter().map(|&(i, _)| solver.reach_cost(i).0).sum();
            if flops <= solver.factor_nnz() as f64 {
                let mut c = c_ref.clone();
                solver
                    .forward_reach(&diff, &mut self.work)?
                    .axpy_into(1.0, &mut c);
                self.stats.forward_reaches += 1;
                return Ok(c);
            }
        }
        let mut c = b_f.clone();
        solver.forward_in_place(&mut c)?;
        self.forward_ref = Some((b_f, c.clone()));
        Ok(c)
    }

    /// Computes the columns of Y of `keys` (not met before), each on its
    /// reach.
    fn fill_columns(
        &mut self,
        solver: &CholeskySolver,
        a: &SparseSym,
        keys: std::collections::BTreeSet<(u32, RowChange)>,
    ) -> Result<(), SolveError> {
        let t = std::time::Instant::now();
        let keys: Vec<(u32, RowChange)> = keys.into_iter().collect();
        let columns: Vec<Vec<(usize, f64)>> = keys
            .iter()
            .map(|&(dof, change)| match change {
                RowChange::Fixed | RowChange::Diagonal => vec![(dof as usize, 1.0)],
                RowChange::Released => {
                    let mut entries = Vec::new();
                    a.column(dof as usize, |i, v| {
                        if !self.base[i] {
                            entries.push((i, v));
                        }
                    });
                    entries
                }
            })
            .collect();
        let ys = solver.forward_reach_many(&columns, &mut self.work)?;
        for (&(dof, change), y) in keys.iter().zip(ys) {
            self.index.insert((dof, change), self.y.len() as u32);
            self.dots.push(vec![f64::NAN; self.y.len() + 1]);
            self.stats.column_rows += y.len() as u64;
            self.stats.column_dense_rows += a.n() as u64;
            self.stats.column_flops += solver.reach_cost(dof as usize).0;
            self.y.push(y);
            self.stats.columns += 1;
        }
        self.stats.column_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// δ = A_ii − A₀_ii of a row with a [`RowChange::Diagonal`].
    fn diagonal_change(&self, a: &SparseSym, i: usize) -> f64 {
        self.base_diag.as_ref().map_or(0.0, |d| a.diag_at(i) - d[i])
    }

    /// YᵢᵀYⱼ, computed once per pair of columns ([`Capacitance::fill_dots`]
    /// computes those of a capacitance matrix together).
    fn y_dot(&mut self, i: u32, j: u32) -> f64 {
        let (lo, hi) = (i.min(j) as usize, i.max(j) as usize);
        let d = self.dots[hi][lo];
        if !d.is_nan() {
            return d;
        }
        let d = self.y[lo].dot(&self.y[hi]);
        self.dots[hi][lo] = d;
        d
    }

    /// Computes the products YᵢᵀYⱼ not known yet among `columns`, block
    /// by block ([`gram`]): every product of the columns that cover the
    /// missing pairs ([`cover_missing`]) with every column.
    fn fill_dots(&mut self, mut columns: Vec<u32>, par: Par) {
        columns.sort_unstable();
        columns.dedup();
        let dots = &self.dots;
        let new = cover_missing(&columns, |lo, hi| dots[hi as usize][lo as usize].is_nan());
        if new.is_empty() {
            return;
        }
        let old: Vec<u32> = columns
            .iter()
            .copied()
            .filter(|i| new.binary_search(i).is_err())
            .collect();
        let t = std::time::Instant::now();
        let ys = |set: &[u32]| -> Vec<&ReachColumn> {
            set.iter().map(|&i| &self.y[i as usize]).collect()
        };
        let (g_new, g_old, flops) = gram(&ys(&new), &ys(&old), par);
        self.stats.product_flops += flops;
        for (a, &i) in new.iter().enumerate() {
            for (b, &j) in new[..=a].iter().enumerate() {
                // new is increasing: j ≤ i
                self.dots[i as usize][j as usize] = g_new[(a, b)];
            }
            for (b, &j) in old.iter().enumerate() {
                let (lo, hi) = (i.min(j) as usize, i.max(j) as usize);
                self.dots[hi][lo] = g_old[(a, b)];
            }
        }
        self.stats.product_seconds += t.elapsed().as_secs_f64();
    }

    /// The entries of A that S reads besides the cached products: A\[R,R\]
    /// (each released row's entries in released columns, in dof order),
    /// δ of each diagonal change and each coupling's reaction row in the
    /// released columns. With the changed rows and the couplings they
    /// decide S.
    fn s_entries(&self, a: &SparseSym, border: &Border) -> Vec<f64> {
        let released: Vec<u32> = border
            .changes
            .iter()
            .filter(|c| c.1 == RowChange::Released)
            .map(|c| c.0)
            .collect();
        let mut values = Vec::new();
        let in_released = |row: u32, values: &mut Vec<f64>| {
            a.column(row as usize, |i, v| {
                if released.binary_search(&(i as u32)).is_ok() {
                    values.push(v);
                }
            })
        };
        for &(dof, change) in &border.changes {
            match change {
                RowChange::Released => in_released(dof, &mut values),
                RowChange::Diagonal => values.push(self.diagonal_change(a, dof as usize)),
                RowChange::Fixed => {}
            }
        }
        for c in &border.couplings {
            in_released(c.reaction_row, &mut values);
        }
        values
    }

    /// Makes `s_factor` the LU of the capacitance matrix of `border` (no
    /// LU when it is empty), keeping the last one when S would be the same.
    fn factor_capacitance(
        &mut self,
        a: &SparseSym,
        border: &Border,
        par: Par,
    ) -> Result<(), SolveError> {
        let entries = self.s_entries(a, border);
        if let Some(f) = &self.s_factor {
            if f.changes == border.changes
                && f.couplings == border.couplings
                && f.entries == entries
            {
                return Ok(());
            }
        }
        self.s_factor = None;
        let t = std::time::Instant::now();
        // faer's blocked LU: thousands of rows on the complete large dam
        let lu = self
            .capacitance_matrix(a, border, par)?
            .map(EquilibratedLu::new);
        let size = border.size() as f64;
        if lu.is_some() {
            self.stats.s_factorisations += 1;
            self.stats.s_flops += 2.0 / 3.0 * size * size * size;
        }
        self.stats.s_seconds += t.elapsed().as_secs_f64();
        self.s_factor = Some(SFactor {
            changes: border.changes.clone(),
            couplings: border.couplings.clone(),
            entries,
            lu,
        });
        Ok(())
    }

    /// The capacitance matrix of `border` (`None` when it is empty): with
    /// m changes and k couplings,
    ///
    /// ```text
    /// S = [ D − Y_UᵀY_U        Y_UᵀY_G − G_R ]
    ///     [ Y_VᵀY_U − V_Rᵀ     I − Y_VᵀY_G   ]
    /// ```
    ///
    /// D = [[A\[R,R\], 0], [0, 0]] − diag(1/δ_D); G the couplings' loads
    /// (Y_G from the unit columns of their rows free in the base, G_R their
    /// entries on released rows), V their reaction rows (Y_V the released
    /// column of each, V_R its entries in released columns).
    fn capacitance_matrix(
        &mut self,
        a: &SparseSym,
        border: &Border,
        par: Par,
    ) -> Result<Option<Mat<f64>>, SolveError> {
        let (m, size) = (border.changes.len(), border.size());
        if size == 0 {
            return Ok(None);
        }
        let changes = &border.changes;
        let cols: Vec<u32> = changes.iter().map(|c| self.y_of(c)).collect();
        let coupled = border
            .couplings
            .iter()
            .flat_map(|c| self.coupling_keys(c))
            .map(|key| self.y_of(&key));
        let every: Vec<u32> = cols.iter().copied().chain(coupled).collect();
        self.fill_dots(every, par);
        let mut s = Mat::<f64>::zeros(size, size);
        let mut finite = true;
        for (i, ci) in changes.iter().enumerate() {
            for (j, cj) in changes.iter().enumerate().skip(i) {
                let arr = match (ci.1, cj.1) {
                    (RowChange::Released, RowChange::Released) => {
                        a.get(ci.0 as usize, cj.0 as usize)
                    }
                    (RowChange::Diagonal, RowChange::Diagonal) if i == j => {
                        -1.0 / self.diagonal_change(a, ci.0 as usize)
                    }
                    _ => 0.0,
                };
                let v = arr - self.y_dot(cols[i], cols[j]);
                finite &= v.is_finite();
                s[(i, j)] = v;
                s[(j, i)] = v;
            }
        }
        for (q, coupling) in border.couplings.iter().enumerate() {
            let v_col = self.y_of(&(coupling.reaction_row, RowChange::Released));
            let loads: Vec<(u32, f64, Option<u32>)> = coupling
                .loads
                .iter()
                .map(|&(t, coef)| {
                    let col = (!self.base[t as usize]).then(|| self.y_of(&(t, RowChange::Fixed)));
                    (t, coef, col)
                })
                .collect();
            for (i, ci) in changes.iter().enumerate() {
                // column m + q: Y_iᵀY_G − G_R
                let mut v = 0.0;
                for &(t, coef, col) in &loads {
                    v += match col {
                        Some(col) => coef * self.y_dot(cols[i], col),
                        None if *ci == (t, RowChange::Released) => -coef,
                        None => 0.0,
                    };
                }
                s[(i, m + q)] = v;
                // row m + q: Y_VᵀY_j − V_R
                let held = if ci.1 == RowChange::Released {
                    a.get(coupling.reaction_row as usize, ci.0 as usize)
                } else {
                    0.0
                };
                let v = self.y_dot(v_col, cols[i]) - held;
                finite &= v.is_finite();
                s[(m + q, i)] = v;
            }
            // block I − Y_VᵀY_G: row m + q against every coupling's loads
            for (p, other) in border.couplings.iter().enumerate() {
                let mut v = if p == q { 1.0 } else { 0.0 };
                for &(t, coef) in &other.loads {
                    if !self.base[t as usize] {
                        let col = self.y_of(&(t, RowChange::Fixed));
                        v -= coef * self.y_dot(v_col, col);
                    }
                }
                finite &= v.is_finite();
                s[(m + q, m + p)] = v;
            }
        }
        if !finite {
            return Err(SolveError::SingularCapacitance { size });
        }
        Ok(Some(s))
    }
}

/// What new columns on the rows `dofs` would cost a correction of `rank`
/// rows on `solver`'s factor that keeps `known` columns already: the
/// flops of their reach solves and products and the bytes they would hold
/// ([`Capacitance::new_columns_cost`]).
pub fn columns_cost(
    solver: &CholeskySolver,
    dofs: &[u32],
    rank: usize,
    known: usize,
) -> (f64, usize) {
    let m = rank as f64;
    dofs.iter()
        .enumerate()
        .map(|(k, &dof)| (k, solver.reach_cost(dof as usize)))
        .fold((0.0, 0), |(f, b), (k, (cf, rows))| {
            let bytes = 8 * (rows as usize + known + k + 1);
            (f + cf + 2.0 * rows as f64 * m, b + bytes)
        })
}

/// A few of `columns` (sorted, distinct), in increasing order, that take
/// part in every pair whose product is `missing(lo, hi)` (lo ≤ hi, a
/// column's own included): chosen greedily, the one in the most missing
/// pairs first (ties to the lower index). Charging each missing pair to
/// its newer column instead recomputed whole rows: a slipping point
/// coupled again after a pass without it made every column added in
/// between "new" (day 857 of the Xiaowan-like arch: 927 of 1,803
/// columns' rows for 14,873 missing products; 23.6 Gflop of products
/// that day, where the cover takes 18.5).
fn cover_missing(columns: &[u32], missing: impl Fn(u32, u32) -> bool) -> Vec<u32> {
    let n = columns.len();
    let missing_at = |a: usize, b: usize| missing(columns[a.min(b)], columns[a.max(b)]);
    let mut degree = vec![0usize; n];
    for a in 0..n {
        for b in 0..=a {
            if missing_at(b, a) {
                degree[a] += 1;
                if b != a {
                    degree[b] += 1;
                }
            }
        }
    }
    let mut chosen = vec![false; n];
    while let Some((a, _)) = degree
        .iter()
        .enumerate()
        .filter(|&(_, &d)| d > 0)
        .max_by_key(|&(a, &d)| (d, std::cmp::Reverse(a)))
    {
        chosen[a] = true;
        degree[a] = 0;
        for b in 0..n {
            if !chosen[b] && b != a && missing_at(a, b) {
                degree[b] -= 1;
            }
        }
    }
    (0..n).filter(|&a| chosen[a]).map(|a| columns[a]).collect()
}

/// The system of one corrected solve: the matrix, its border on the base
/// factor, the rows held and the LU of its capacitance matrix (`None`
/// when the border is empty).
#[derive(Clone, Copy)]
struct System<'s> {
    a: &'s SparseSym,
    border: &'s Border,
    fixed: &'s [bool],
    lu: Option<&'s EquilibratedLu>,
}

/// What one corrected solve borders the base factor with: the changed rows
/// (in dof order) and the couplings (loads on rows free in the solved set
/// only).
struct Border {
    changes: Vec<(u32, RowChange)>,
    couplings: Vec<Coupling>,
}

impl Border {
    /// Rows of the capacitance system.
    fn size(&self) -> usize {
        self.changes.len() + self.couplings.len()
    }
}

#[cfg(test)]
mod tests {
    use super::cover_missing;
    use std::collections::BTreeSet;

    /// A column back after passes without it misses its products with
    /// the columns made meanwhile: it alone is recomputed, not all of them.
    #[test]
    fn a_column_back_is_recomputed_alone() {
        let columns: Vec<u32> = (0..10).collect();
        let missing = |lo: u32, hi: u32| lo == 3 && hi >= 5;
        assert_eq!(cover_missing(&columns, missing), vec![3]);
    }

    /// New columns miss every product, their own included: all of them.
    #[test]
    fn new_columns_are_recomputed() {
        let columns: Vec<u32> = (0..8).collect();
        let missing = |_lo: u32, hi: u32| hi >= 6;
        assert_eq!(cover_missing(&columns, missing), vec![6, 7]);
        assert_eq!(cover_missing(&columns, |_, _| false), Vec::<u32>::new());
    }

    /// On scattered missing pairs every one has a recomputed column.
    #[test]
    fn every_missing_pair_is_covered() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        for round in 0..50 {
            let n = 5 + round % 40;
            let columns: Vec<u32> = (0..n as u32).map(|c| 3 * c + 1).collect();
            let mut missing = BTreeSet::new();
            for a in 0..n {
                for b in a..n {
                    seed ^= seed << 13;
                    seed ^= seed >> 7;
                    seed ^= seed << 17;
                    if seed.is_multiple_of(11) {
                        missing.insert((columns[a], columns[b]));
                    }
                }
            }
            let cover = cover_missing(&columns, |lo, hi| missing.contains(&(lo, hi)));
            assert!(cover.windows(2).all(|w| w[0] < w[1]));
            for &(lo, hi) in &missing {
                assert!(
                    cover.contains(&lo) || cover.contains(&hi),
                    "({lo}, {hi}) not covered by {cover:?}"
                );
            }
        }
    }
}
