//! Symmetric sparse assembly with a fixed pattern.
//!
//! [`Pattern`] is built once from the dof lists of a set of elements (any
//! sizes: hex8 volumes, quad4 faces, joint elements). It stores the **upper
//! triangle** (row ≤ column) of the symmetric matrix in CSC form with sorted
//! row indices and u32 indices — the layout faer's sparse Cholesky reads with
//! `Side::Upper` — plus, per element, a scatter map from each local pair
//! (a ≤ b) to its value index. Numeric assembly ([`SparseSym::add_element`]) is
//! then a pure O(n_e²) scatter with no searching.
//!
//! Every dof 0..n gets a diagonal entry even if no element touches it, so a
//! dof can always be fixed by [`SparseSym::apply_dirichlet`] without changing
//! the pattern. An element dof equal to [`NO_DOF`] is skipped (its rows and
//! columns are dropped), which lets callers assemble elements whose nodes are
//! only partly in the system.

use std::sync::Arc;

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use nalgebra::{DMatrix, Dim, Matrix, RawStorage};
use thiserror::Error;

/// Element dof marker for "not in this system": skipped by the pattern and
/// by assembly.
pub const NO_DOF: u32 = u32::MAX;

/// Marker in the scatter map for a local pair that touches a [`NO_DOF`].
const SKIP: u32 = u32::MAX;

/// Stored entries from which [`SparseSym::mul_vec`] sweeps on two threads:
/// the large arch's mechanical systems (4M entries is about 100,000
/// unknowns of hex8 solids), whose residual checks run at every contact
/// pass while the other core waits; the demo's and the thermal systems
/// stay on one, beside the work of the other core.
pub const PAR_PRODUCT_ENTRIES: usize = 1 << 22;

/// Why a pattern could not be built.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum PatternError {
    #[error("element slot {slot}: dof {dof} is out of range (n_dofs = {n_dofs})")]
    DofOutOfRange {
        slot: usize,
        dof: u32,
        n_dofs: usize,
    },
    #[error("n_dofs = {n_dofs} does not fit the u32 dof indices")]
    TooManyDofs { n_dofs: usize },
    #[error("the pattern needs {nnz} stored entries, more than u32 value indices address")]
    TooManyEntries { nnz: usize },
}

/// Index of local pair (a, b), a ≤ b, in the packed row-major upper triangle
/// of an n×n element matrix: (0,0), (0,1), …, (0,n−1), (1,1), …
#[inline]
pub fn packed_upper_index(n: usize, a: usize, b: usize) -> usize {
    debug_assert!(a <= b && b < n);
    a * (2 * n - a + 1) / 2 + (b - a)
}

/// Upper-triangular CSC structure plus per-element scatter maps.
#[derive(Debug, Clone)]
pub struct Pattern {
    n: usize,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    diag_idx: Vec<u32>,
    elem_dof_ptr: Vec<usize>,
    elem_dofs: Vec<u32>,
    scatter_ptr: Vec<usize>,
    scatter: Vec<u32>,
    /// the strict upper triangle by rows, built on first use by
    /// [`SparseSym::column`]
    rows: std::sync::OnceLock<RowIndex>,
}

/// The strict upper triangle by rows: row i holds `col[ptr[i]..ptr[i + 1]]`
/// (columns j > i) whose values sit at `pos[..]` of the value array.
#[derive(Debug, Clone)]
struct RowIndex {
    ptr: Vec<usize>,
    col: Vec<u32>,
    pos: Vec<u32>,
}

impl RowIndex {
    fn of(n: usize, col_ptr: &[u32], row_idx: &[u32]) -> RowIndex {
        let mut ptr = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize - 1] {
                ptr[i as usize + 1] += 1;
            }
        }
        for i in 0..n {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut col = vec![0u32; ptr[n]];
        let mut pos = vec![0u32; ptr[n]];
        for j in 0..n {
            let (s, e) = (col_ptr[j] as usize, col_ptr[j + 1] as usize - 1);
            for (k, &i) in row_idx.iter().enumerate().take(e).skip(s) {
                let i = i as usize;
                col[fill[i]] = j as u32;
                pos[fill[i]] = k as u32;
                fill[i] += 1;
            }
        }
        RowIndex { ptr, col, pos }
    }
}

/// The element dof lists, flattened: slot `e` owns `dofs[ptr[e]..ptr[e + 1]]`
/// and `scatter_ptr[e]..scatter_ptr[e + 1]` of the scatter map (one entry
/// per local pair a ≤ b).
struct FlatElements {
    ptr: Vec<usize>,
    dofs: Vec<u32>,
    scatter_ptr: Vec<usize>,
}

impl FlatElements {
    /// Checks every dof against `n` (or [`NO_DOF`]) while copying.
    fn new<E: AsRef<[u32]>>(n: usize, elements: &[E]) -> Result<Self, PatternError> {
        let mut ptr = Vec::with_capacity(elements.len() + 1);
        let mut scatter_ptr = Vec::with_capacity(elements.len() + 1);
        ptr.push(0);
        scatter_ptr.push(0);
        let total: usize = elements.iter().map(|e| e.as_ref().len()).sum();
        let mut dofs = Vec::with_capacity(total);
        for (slot, e) in elements.iter().enumerate() {
            let e = e.as_ref();
            for &d in e {
                if d != NO_DOF && d as usize >= n {
                    return Err(PatternError::DofOutOfRange {
                        slot,
                        dof: d,
                        n_dofs: n,
                    });
                }
            }
            dofs.extend_from_slice(e);
            ptr.push(dofs.len());
            let ne = e.len();
            scatter_ptr.push(scatter_ptr[slot] + ne * (ne + 1) / 2);
        }
        Ok(FlatElements {
            ptr,
            dofs,
            scatter_ptr,
        })
    }

    fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    fn dofs(&self, e: usize) -> &[u32] {
        &self.dofs[self.ptr[e]..self.ptr[e + 1]]
    }

    /// The dofs of element `e` in the system, each once, with their first
    /// place in the element's list.
    fn unique_dofs(&self, e: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        let d = self.dofs(e);
        d.iter()
            .enumerate()
            .filter(move |&(k, &x)| x != NO_DOF && !d[..k].contains(&x))
            .map(|(k, &x)| (k, x as usize))
    }

    /// dof → incident elements (each element listed once per dof) and the
    /// dof's first place in the element, as `inc[inc_ptr[d]..inc_ptr[d + 1]]`
    /// and `first[inc_ptr[d]..inc_ptr[d + 1]]`.
    fn incidence(&self, n: usize) -> Incidence {
        let mut ptr = vec![0usize; n + 1];
        for e in 0..self.len() {
            for (_, d) in self.unique_dofs(e) {
                ptr[d + 1] += 1;
            }
        }
        for j in 0..n {
            ptr[j + 1] += ptr[j];
        }
        let mut fill = ptr.clone();
        let mut elem = vec![0u32; ptr[n]];
        let mut first = vec![0u32; ptr[n]];
        for e in 0..self.len() {
            for (k, d) in self.unique_dofs(e) {
                elem[fill[d]] = e as u32;
                first[fill[d]] = k as u32;
                fill[d] += 1;
            }
        }
        Incidence { ptr, elem, first }
    }
}

/// The elements incident to each dof ([`FlatElements::incidence`]).
struct Incidence {
    ptr: Vec<usize>,
    elem: Vec<u32>,
    /// the dof's first place in the element's list
    first: Vec<u32>,
}

/// The upper triangle in CSC form and the scatter map of every element.
struct Columns {
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    diag_idx: Vec<u32>,
    scatter: Vec<u32>,
}

impl Columns {
    /// Column by column: the rows ≤ j coupled to j through an incident
    /// element, sorted, then the value index of every local pair of those
    /// elements that lands in column j. A dof whose elements are the dof
    /// before's (the components of one node) takes that column's rows and
    /// adds itself, instead of gathering and sorting them again (the
    /// demo's run: 1.9 core-seconds in its 440 patterns against 2.6, by a
    /// sampling profile; the same patterns).
    fn build(n: usize, el: &FlatElements, inc: &Incidence) -> Result<Self, PatternError> {
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0u32);
        let mut row_idx: Vec<u32> = Vec::with_capacity(inc.elem.len() * 4 + n);
        let mut diag_idx = Vec::with_capacity(n);
        let mut scatter = vec![SKIP; *el.scatter_ptr.last().unwrap_or(&0)];
        let mut mark = vec![u32::MAX; n];
        let mut pos = vec![0u32; n];
        let mut rows: Vec<u32> = Vec::new();
        for j in 0..n {
            let (lo, hi) = (inc.ptr[j], inc.ptr[j + 1]);
            let incident = &inc.elem[lo..hi];
            if j > 0 && lo < hi && *incident == inc.elem[inc.ptr[j - 1]..lo] {
                // j − 1 has j's elements (a node's next component): j's rows
                // are j − 1's, j − 1 among them, and j itself
                rows.push(j as u32);
            } else {
                rows.clear();
                rows.push(j as u32);
                mark[j] = j as u32;
                for &e in incident {
                    for &d in el.dofs(e as usize) {
                        if d != NO_DOF && (d as usize) < j && mark[d as usize] != j as u32 {
                            mark[d as usize] = j as u32;
                            rows.push(d);
                        }
                    }
                }
                rows.sort_unstable();
            }
            let start = row_idx.len();
            if start + rows.len() >= SKIP as usize {
                return Err(PatternError::TooManyEntries {
                    nnz: start + rows.len(),
                });
            }
            for (k, &r) in rows.iter().enumerate() {
                pos[r as usize] = (start + k) as u32;
            }
            row_idx.extend_from_slice(&rows);
            diag_idx.push(pos[j]);
            col_ptr.push(row_idx.len() as u32);
            for (&e, &first) in incident.iter().zip(&inc.first[lo..hi]) {
                let e = e as usize;
                let sc = &mut scatter[el.scatter_ptr[e]..el.scatter_ptr[e + 1]];
                scatter_column(j, el.dofs(e), first as usize, &pos, sc);
            }
        }
        row_idx.shrink_to_fit();
        Ok(Columns {
            col_ptr,
            row_idx,
            diag_idx,
            scatter,
        })
    }
}

/// The scatter entries of one element in column `j`: every local pair
/// (a, b) with dof b = j and dof a ≤ j gets the value index `pos[dof a]`.
/// `first` is j's first place in `dofs`: the places before it are not j,
/// so an element costs its size squared, not cubed (the condensed rock's
/// dense blocks have hundreds of dofs).
fn scatter_column(j: usize, dofs: &[u32], first: usize, pos: &[u32], sc: &mut [u32]) {
    let ne = dofs.len();
    for (b, &db) in dofs.iter().enumerate().skip(first) {
        if db as usize != j {
            continue;
        }
        for (a, &da) in dofs.iter().enumerate() {
            if da == NO_DOF || da as usize > j {
                continue;
            }
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            sc[packed_upper_index(ne, lo, hi)] = pos[da as usize];
        }
    }
}

impl Pattern {
    /// Builds the pattern of the union of `elements` (each a list of dof
    /// indices, any length). Element `k` of the list is "slot" `k` for
    /// [`SparseSym::add_element`].
    pub fn try_new<E: AsRef<[u32]>>(n_dofs: usize, elements: &[E]) -> Result<Self, PatternError> {
        if n_dofs >= u32::MAX as usize {
            return Err(PatternError::TooManyDofs { n_dofs });
        }
        let n = n_dofs;
        let el = FlatElements::new(n, elements)?;
        let inc = el.incidence(n);
        let cols = Columns::build(n, &el, &inc)?;
        let pattern = Pattern {
            n,
            col_ptr: cols.col_ptr,
            row_idx: cols.row_idx,
            diag_idx: cols.diag_idx,
            elem_dof_ptr: el.ptr,
            elem_dofs: el.dofs,
            scatter_ptr: el.scatter_ptr,
            scatter: cols.scatter,
            rows: std::sync::OnceLock::new(),
        };
        // verify faer's invariants once (sorted, in range, monotone col_ptr)
        let _ = SymbolicSparseColMatRef::new_checked(
            pattern.n,
            pattern.n,
            &pattern.col_ptr,
            None,
            &pattern.row_idx,
        );
        Ok(pattern)
    }

    /// [`Pattern::try_new`] for callers whose dofs are known to be valid.
    ///
    /// # Panics
    /// On any [`PatternError`].
    pub fn new<E: AsRef<[u32]>>(n_dofs: usize, elements: &[E]) -> Self {
        match Self::try_new(n_dofs, elements) {
            Ok(p) => p,
            Err(e) => panic!("Pattern::new: {e}"),
        }
    }

    /// Number of dofs (matrix order).
    pub fn n_dofs(&self) -> usize {
        self.n
    }

    /// Number of element slots.
    pub fn n_elements(&self) -> usize {
        self.elem_dof_ptr.len() - 1
    }

    /// Stored entries (upper triangle including the diagonal).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// CSC column pointers (length n + 1).
    pub fn col_ptr(&self) -> &[u32] {
        &self.col_ptr
    }

    /// CSC row indices, sorted within each column, all ≤ the column.
    pub fn row_idx(&self) -> &[u32] {
        &self.row_idx
    }

    /// Value index of the diagonal entry of each dof.
    pub fn diag_index(&self) -> &[u32] {
        &self.diag_idx
    }

    /// The dofs of element `slot`, as given to the constructor.
    pub fn element_dofs(&self, slot: usize) -> &[u32] {
        &self.elem_dofs[self.elem_dof_ptr[slot]..self.elem_dof_ptr[slot + 1]]
    }

    /// Scatter map of element `slot`: entry [`packed_upper_index`]`(n_e, a, b)`
    /// is the value index of the global entry of local pair (a ≤ b), or
    /// `u32::MAX` when a or b is [`NO_DOF`].
    pub fn scatter_index(&self, slot: usize) -> &[u32] {
        &self.scatter[self.scatter_ptr[slot]..self.scatter_ptr[slot + 1]]
    }

    /// Value index of global entry (i, j) (either order), if stored.
    /// Binary search; for tests and occasional lookups, not for assembly.
    pub fn find(&self, i: usize, j: usize) -> Option<usize> {
        let (r, c) = if i <= j { (i, j) } else { (j, i) };
        if c >= self.n {
            return None;
        }
        let s = self.col_ptr[c] as usize;
        let e = self.col_ptr[c + 1] as usize;
        self.row_idx[s..e]
            .binary_search(&(r as u32))
            .ok()
            .map(|k| s + k)
    }

    /// faer view of the upper-triangular structure.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, u32> {
        // SAFETY: checked by `new_checked` in `try_new`; the arrays are never
        // mutated afterwards.
        unsafe {
            SymbolicSparseColMatRef::new_unchecked(
                self.n,
                self.n,
                &self.col_ptr,
                None,
                &self.row_idx,
            )
        }
    }

    /// Bytes held by the structure and scatter maps (for benchmarks).
    pub fn memory_bytes(&self) -> usize {
        4 * (self.col_ptr.len() + self.row_idx.len() + self.diag_idx.len())
            + 8 * (self.elem_dof_ptr.len() + self.scatter_ptr.len())
            + 4 * (self.elem_dofs.len() + self.scatter.len())
    }
}

/// Symmetric matrix on a shared [`Pattern`], upper triangle stored.
#[derive(Debug, Clone)]
pub struct SparseSym {
    pattern: Arc<Pattern>,
    values: Vec<f64>,
}

impl SparseSym {
    /// Zero matrix on `pattern`.
    pub fn new(pattern: Arc<Pattern>) -> Self {
        let values = vec![0.0; pattern.nnz()];
        SparseSym { pattern, values }
    }

    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// Matrix order.
    pub fn n(&self) -> usize {
        self.pattern.n
    }

    /// Stored values in CSC order of [`Pattern::row_idx`].
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// All values to 0, pattern kept.
    pub fn set_zero(&mut self) {
        self.values.fill(0.0);
    }

    /// self += alpha · other (same pattern).
    ///
    /// # Panics
    /// If the patterns are not the same `Arc`.
    pub fn axpy(&mut self, alpha: f64, other: &SparseSym) {
        assert!(
            Arc::ptr_eq(&self.pattern, &other.pattern),
            "SparseSym::axpy needs the same pattern"
        );
        for (v, o) in self.values.iter_mut().zip(&other.values) {
            *v += alpha * o;
        }
    }

    /// Adds the symmetric element matrix `k` (n_e × n_e, in the order of
    /// the slot's dofs). Only the upper triangle of `k` is read, except that
    /// when two local dofs share a global dof both k_ab and k_ba are added.
    ///
    /// # Panics
    /// If `k` is not n_e × n_e.
    #[inline]
    pub fn add_element<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        slot: usize,
        k: &Matrix<f64, R, C, S>,
    ) {
        self.add_element_scaled(slot, 1.0, k);
    }

    /// Adds alpha · k (see [`SparseSym::add_element`]).
    #[inline]
    pub fn add_element_scaled<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        slot: usize,
        alpha: f64,
        k: &Matrix<f64, R, C, S>,
    ) {
        let ne = self.pattern.element_dofs(slot).len();
        assert!(
            k.nrows() == ne && k.ncols() == ne,
            "element slot {slot} has {ne} dofs, got a {}x{} matrix",
            k.nrows(),
            k.ncols()
        );
        self.scatter_upper(slot, alpha, |_, r, c| k[(r, c)]);
    }

    /// Adds alpha · k for a symmetric element matrix given by its upper
    /// triangle row by row (`packed`, n_e (n_e + 1) / 2 entries; e.g.
    /// [`super::elasticity::PackedSym24`]): the sums of
    /// [`SparseSym::add_element_scaled`] to the bit, reading half as much.
    ///
    /// # Panics
    /// If `packed` does not have the slot's n_e (n_e + 1) / 2 entries.
    #[inline]
    pub fn add_packed_scaled(&mut self, slot: usize, alpha: f64, packed: &[f64]) {
        assert_eq!(
            packed.len(),
            self.pattern.scatter_index(slot).len(),
            "element slot {slot}: packed matrix length"
        );
        self.scatter_upper(slot, alpha, |idx, _, _| packed[idx]);
    }

    /// The scatter of both element adds: over the slot's upper triangle in
    /// the order of its scatter index, `entry(idx, r, c)` gives k_rc, `idx`
    /// the position of {r, c} in that triangle; k_ba is added to k_ab where
    /// local dofs a and b are one global dof (a repeated node).
    #[inline(always)]
    fn scatter_upper(
        &mut self,
        slot: usize,
        alpha: f64,
        entry: impl Fn(usize, usize, usize) -> f64,
    ) {
        let p = &*self.pattern;
        let dofs = p.element_dofs(slot);
        let sc = p.scatter_index(slot);
        let ne = dofs.len();
        let mut idx = 0;
        for a in 0..ne {
            for b in a..ne {
                let v = sc[idx];
                let at = idx;
                idx += 1;
                if v == SKIP {
                    continue;
                }
                let mut x = entry(at, a, b);
                if a != b && dofs[a] == dofs[b] {
                    x += entry(at, b, a);
                }
                self.values[v as usize] += alpha * x;
            }
        }
    }

    /// Adds a diagonal element matrix (lumped capacity, lumped convection):
    /// entry a of `d` goes to the diagonal of the slot's dof a.
    #[inline]
    pub fn add_element_diag(&mut self, slot: usize, alpha: f64, d: &[f64]) {
        let p = &*self.pattern;
        let dofs = p.element_dofs(slot);
        assert_eq!(d.len(), dofs.len(), "element slot {slot}: diagonal length");
        for (&dof, &x) in dofs.iter().zip(d) {
            if dof != NO_DOF {
                self.values[p.diag_idx[dof as usize] as usize] += alpha * x;
            }
        }
    }

    /// A_ii += v.
    #[inline]
    pub fn add_diag(&mut self, dof: usize, v: f64) {
        self.values[self.pattern.diag_idx[dof] as usize] += v;
    }

    /// A_ii.
    #[inline]
    pub fn diag_at(&self, dof: usize) -> f64 {
        self.values[self.pattern.diag_idx[dof] as usize]
    }

    /// Entry (i, j) (0 when not stored). Binary search.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.pattern.find(i, j).map_or(0.0, |k| self.values[k])
    }

    /// Calls `f(i, A_ij)` for every stored entry of column `j` (both
    /// triangles), in increasing i.
    pub fn column(&self, j: usize, mut f: impl FnMut(usize, f64)) {
        let p = &*self.pattern;
        let rows = p
            .rows
            .get_or_init(|| RowIndex::of(p.n, &p.col_ptr, &p.row_idx));
        for k in p.col_ptr[j] as usize..p.col_ptr[j + 1] as usize {
            f(p.row_idx[k] as usize, self.values[k]);
        }
        for k in rows.ptr[j]..rows.ptr[j + 1] {
            f(rows.col[k] as usize, self.values[rows.pos[k] as usize]);
        }
    }

    /// Diagonal.
    pub fn diag(&self) -> Vec<f64> {
        self.pattern
            .diag_idx
            .iter()
            .map(|&k| self.values[k as usize])
            .collect()
    }

    /// y = A x, using the stored upper triangle for both halves.
    ///
    /// # Panics
    /// If `x` or `y` is not of length n.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        self.mul_vec_of(x, y, |v| v);
    }

    /// y = |A| |x| (entrywise absolute values): the size of the forces
    /// A x sums, against which its round-off is measured.
    pub fn abs_mul_vec(&self, x: &[f64], y: &mut [f64]) {
        self.mul_vec_of(x, y, f64::abs);
    }

    /// y = f(A) f(x), f applied entrywise, in one sweep of the upper
    /// triangle (column j's entries add to y_i and to y_j). From
    /// [`PAR_PRODUCT_ENTRIES`] on, the columns are cut in two halves of
    /// about equal entries swept on two threads: the first half's columns
    /// touch only its own rows, the second's also the first's rows, which
    /// it adds into a buffer of its own, added after (a fixed order: the
    /// same bits whichever thread ends first).
    #[inline]
    fn mul_vec_of(&self, x: &[f64], y: &mut [f64], f: impl Fn(f64) -> f64 + Sync) {
        let p = &*self.pattern;
        assert!(x.len() == p.n && y.len() == p.n, "mul_vec: length mismatch");
        y.fill(0.0);
        if p.row_idx.len() < PAR_PRODUCT_ENTRIES {
            self.sweep_columns(0..p.n, x, y, &mut [], &f);
            return;
        }
        let half = p.row_idx.len() as u64 / 2;
        let mid = p.col_ptr.partition_point(|&c| (c as u64) < half).min(p.n);
        let (own_lo, own_hi) = y.split_at_mut(mid);
        let mut lo_from_hi = vec![0.0; mid];
        rayon::join(
            || self.sweep_columns(0..mid, x, own_lo, &mut [], &f),
            || self.sweep_columns(mid..p.n, x, own_hi, &mut lo_from_hi, &f),
        );
        own_lo
            .iter_mut()
            .zip(&lo_from_hi)
            .for_each(|(a, b)| *a += b);
    }

    /// The columns `cols` of [`SparseSym::mul_vec_of`]'s sweep: into
    /// `own` the rows of `cols`, into `below` the rows before them.
    fn sweep_columns(
        &self,
        cols: std::ops::Range<usize>,
        x: &[f64],
        own: &mut [f64],
        below: &mut [f64],
        f: &impl Fn(f64) -> f64,
    ) {
        let p = &*self.pattern;
        let start = cols.start;
        for j in cols {
            let s = p.col_ptr[j] as usize;
            let e = p.col_ptr[j + 1] as usize;
            let xj = f(x[j]);
            let mut acc = 0.0;
            // the last entry of the column is the diagonal
            for (&i, &v) in p.row_idx[s..e - 1].iter().zip(&self.values[s..e - 1]) {
                let (i, v) = (i as usize, f(v));
                match i.checked_sub(start) {
                    Some(k) => own[k] += v * xj,
                    None => below[i] += v * xj,
                }
                acc += v * f(x[i]);
            }
            own[j - start] += acc + f(self.values[e - 1]) * xj;
        }
    }

    /// rhs_i −= Σ_{j fixed} A_ij u_j for every free i: the load of the
    /// prescribed values. Call BEFORE [`SparseSym::apply_dirichlet`]. Fixed
    /// rows of `rhs` are left alone.
    pub fn dirichlet_correction(&self, fixed: &[bool], u: &[f64], rhs: &mut [f64]) {
        let p = &*self.pattern;
        assert!(fixed.len() == p.n && u.len() == p.n && rhs.len() == p.n);
        // Most prescribed values are zero (supports, sticking joint
        // points): walk only the columns that load something.
        let loaded: Vec<usize> = (0..p.n).filter(|&j| fixed[j] && u[j] != 0.0).collect();
        if loaded.len() < p.n / 64 {
            for j in loaded {
                self.column(j, |i, v| {
                    if !fixed[i] {
                        rhs[i] -= v * u[j];
                    }
                });
            }
            return;
        }
        for j in 0..p.n {
            let s = p.col_ptr[j] as usize;
            let e = p.col_ptr[j + 1] as usize;
            for k in s..e - 1 {
                let i = p.row_idx[k] as usize;
                let v = self.values[k];
                match (fixed[i], fixed[j]) {
                    (false, true) => rhs[i] -= v * u[j],
                    (true, false) => rhs[j] -= v * u[i],
                    _ => {}
                }
            }
        }
    }

    /// Zeroes the rows and columns of fixed dofs and puts 1 on their
    /// diagonal. The pattern is unchanged (the zeros stay stored).
    pub fn apply_dirichlet(&mut self, fixed: &[bool]) {
        let p = &*self.pattern;
        assert_eq!(fixed.len(), p.n);
        for j in 0..p.n {
            let s = p.col_ptr[j] as usize;
            let e = p.col_ptr[j + 1] as usize;
            if fixed[j] {
                self.values[s..e - 1].fill(0.0);
                self.values[e - 1] = 1.0;
            } else {
                for k in s..e - 1 {
                    if fixed[p.row_idx[k] as usize] {
                        self.values[k] = 0.0;
                    }
                }
            }
        }
    }

    /// [`dirichlet_correction`](SparseSym::dirichlet_correction), then
    /// [`apply_dirichlet`](SparseSym::apply_dirichlet), then rhs_i = u_i on
    /// fixed dofs: the solution of the modified system has x_fixed = u_fixed.
    pub fn apply_dirichlet_with_rhs(&mut self, fixed: &[bool], u: &[f64], rhs: &mut [f64]) {
        self.dirichlet_correction(fixed, u, rhs);
        self.apply_dirichlet(fixed);
        for i in 0..self.pattern.n {
            if fixed[i] {
                rhs[i] = u[i];
            }
        }
    }

    /// faer view (upper triangle; pass `Side::Upper`).
    pub fn as_faer(&self) -> SparseColMatRef<'_, u32, f64> {
        SparseColMatRef::new(self.pattern.symbolic(), &self.values)
    }

    /// Dense copy with both triangles (tests, debugging).
    pub fn to_dense(&self) -> DMatrix<f64> {
        let p = &*self.pattern;
        let mut m = DMatrix::zeros(p.n, p.n);
        for j in 0..p.n {
            for k in p.col_ptr[j] as usize..p.col_ptr[j + 1] as usize {
                let i = p.row_idx[k] as usize;
                m[(i, j)] = self.values[k];
                m[(j, i)] = self.values[k];
            }
        }
        m
    }

    /// True when every stored value is finite.
    pub fn is_finite(&self) -> bool {
        self.values.iter().all(|v| v.is_finite())
    }
}
