//! The two halves of a Cholesky solve, and the first half for a right-hand
//! side with few entries, computed on its reach in the elimination tree.
//!
//! faer factors M = Pᵀ L Lᵀ P (P the fill-reducing permutation), so a solve
//! M x = b is a forward half c = L⁻¹ P b and a backward half x = Pᵀ L⁻ᵀ c.
//! The capacitance correction ([`super::capacitance`]) needs UᵀM⁻¹U = YᵀY
//! with Y = L⁻¹ P U, forward halves only; and a column u of U has few
//! entries (a unit vector, or a column of the stiffness restricted to the
//! free rows). The forward solve of such a column is non-zero only on the
//! rows of its *reach*: the blocks on the paths from the blocks of u's
//! entries to the root of the elimination tree (Gilbert and Peierls;
//! T. A. Davis, *Direct Methods for Sparse Linear Systems*, SIAM 2006,
//! §3.2 and §4.4). It is computed on those blocks alone — for a nested-
//! dissection order a path through the separators, a small part of the
//! factor — instead of two sweeps over all of L.
//!
//! A block is one of faer's supernodes (a dense column block with a common
//! row pattern below it) or one column of a simplicial factor; both are
//! stored column-major as the diagonal block over the rows below. Every row
//! below a block lies in an ancestor block, and a block's parent is the
//! block of its smallest row below, so visiting the reach in increasing
//! order is a topological order of the forward substitution.
//!
//! The columns of one correction are solved together, [`REACH_BATCH`] at
//! a time, on the union of their reaches: per block a dense triangular
//! solve of the panel's rows and one matrix product for the rows below,
//! so L is read once per batch. On the demo's whole construction the
//! 40,452 columns took 4.3 s instead of 13.1 s one at a time; on the
//! Xiaowan-like complete dam the 4,546 columns 10.9 s instead of 84.2 s
//! (`groutready study perf`, 27 Nov 2026). The batches are made in the
//! factor's order (`CholeskySolver::forward_reach_many`), where neighbours
//! share most of their reaches: the Xiaowan-like arch's days 913–916 took
//! 8.5–8.8 s for their 5,962 columns against 13.4–13.5 s batched in dof
//! order (29 Nov 2026, alternated).
//!
//! Verified by `tests/it/fem_sparse.rs`: forward then backward equals a
//! full solve; a reach column equals the dense forward solve of the same
//! column, and is zero outside its reach; a column solved in a batch
//! equals its single solve, on the same reach; on simplicial and
//! supernodal factors.

use std::ops::Range;

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// No parent: a root of the elimination tree.
const ROOT: u32 = u32::MAX;

/// The block structure of a factor and its elimination tree, computed once
/// per symbolic analysis.
#[derive(Debug, Clone)]
pub(super) struct BlockTree {
    /// block of each column of L (the permuted numbering)
    block_of: Vec<u32>,
    /// parent block, [`ROOT`] at a root
    parent: Vec<u32>,
    /// flops of the forward solve of one column whose reach starts at the
    /// block: the sum over the path to the root of width·(width + 2·below)
    path_flops: Vec<f64>,
    /// rows of that reach (Σ widths on the path)
    path_rows: Vec<u64>,
}

/// One block of L: its first column, width, rows below and values
/// (column-major, (width + below) × width).
pub(super) struct Block<'a> {
    pub start: usize,
    pub width: usize,
    pub below: &'a [u32],
    pub values: &'a [f64],
}

/// The shape of block `b`: first column, width, rows below, and the range
/// of its values in the factor's value array.
fn block_shape(symbolic: &SymbolicCholesky<u32>, b: usize) -> (usize, usize, &[u32], Range<usize>) {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let (lo, hi) = (s.col_ptr()[b] as usize, s.col_ptr()[b + 1] as usize);
            (b, 1, &s.row_idx()[lo + 1..hi], lo..hi)
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let start = s.supernode_begin()[b] as usize;
            let width = s.supernode_end()[b] as usize - start;
            let vals = s.col_ptr_for_val()[b] as usize..s.col_ptr_for_val()[b + 1] as usize;
            (start, width, s.supernode(b).pattern(), vals)
        }
    }
}

/// Block `b` of a factor with its values.
pub(super) fn block<'a>(
    symbolic: &'a SymbolicCholesky<u32>,
    values: &'a [f64],
    b: usize,
) -> Block<'a> {
    let (start, width, below, vals) = block_shape(symbolic, b);
    Block {
        start,
        width,
        below,
        values: &values[vals],
    }
}

/// Stored entries of each block of a factor (its diagonal block whole).
pub(super) fn block_entries(symbolic: &SymbolicCholesky<u32>) -> Vec<u64> {
    (0..n_blocks(symbolic))
        .map(|b| block_shape(symbolic, b).3.len() as u64)
        .collect()
}

/// Number of blocks of a factor.
fn n_blocks(symbolic: &SymbolicCholesky<u32>) -> usize {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.nrows(),
        SymbolicCholeskyRaw::Supernodal(s) => s.n_supernodes(),
    }
}

impl BlockTree {
    /// The tree of a symbolic factor (no values needed: the structure only).
    pub(super) fn new(symbolic: &SymbolicCholesky<u32>) -> Self {
        let n = symbolic.nrows();
        let nb = n_blocks(symbolic);
        let mut block_of = vec![0u32; n];
        let mut widths = vec![(0usize, 0usize); nb];
        for (b, w) in widths.iter_mut().enumerate() {
            let (start, width, below, _) = block_shape(symbolic, b);
            block_of[start..start + width].fill(b as u32);
            *w = (width, below.len());
        }
        let mut parent = vec![ROOT; nb];
        for (b, p) in parent.iter_mut().enumerate() {
            if let Some(&first) = block_shape(symbolic, b).2.iter().min() {
                *p = block_of[first as usize];
            }
        }
        // parents come after their children: fill the paths from the roots down
        let mut path_flops = vec![0.0; nb];
        let mut path_rows = vec![0u64; nb];
        for b in (0..nb).rev() {
            let (w, below) = (widths[b].0 as f64, widths[b].1 as f64);
            let (up_flops, up_rows) = match parent[b] {
                ROOT => (0.0, 0),
                p => (path_flops[p as usize], path_rows[p as usize]),
            };
            path_flops[b] = up_flops + w * (w + 2.0 * below);
            path_rows[b] = up_rows + widths[b].0 as u64;
        }
        BlockTree {
            block_of,
            parent,
            path_flops,
            path_rows,
        }
    }

    /// Flops and rows of the reach of one column of L (permuted numbering).
    pub(super) fn path_of_column(&self, column: usize) -> (f64, u64) {
        let b = self.block_of[column] as usize;
        (self.path_flops[b], self.path_rows[b])
    }

    pub(super) fn n_blocks(&self) -> usize {
        self.parent.len()
    }

    /// The block of a column of L (the permuted numbering).
    pub(super) fn block_of(&self, column: usize) -> usize {
        self.block_of[column] as usize
    }

    /// The parent of block `b`, None at a root.
    pub(super) fn parent(&self, b: usize) -> Option<usize> {
        match self.parent[b] {
            ROOT => None,
            p => Some(p as usize),
        }
    }

    /// Marks the blocks on the path from `row`'s block to the root that
    /// are not marked yet, and appends them to `reach`: with `mark` kept
    /// across rows, the union of their reaches.
    fn mark_path(&self, row: usize, mark: &mut [bool], reach: &mut Vec<u32>) {
        let mut b = self.block_of[row];
        while b != ROOT && !mark[b as usize] {
            mark[b as usize] = true;
            reach.push(b);
            b = self.parent[b as usize];
        }
    }
}

/// A column of Y = L⁻¹ P u stored on the blocks of its reach: the spans of
/// rows (first row, length; increasing) and their values, concatenated.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReachColumn {
    spans: Vec<(u32, u32)>,
    values: Vec<f64>,
}

impl ReachColumn {
    /// Rows held.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// True when every value is finite.
    pub(super) fn is_finite(&self) -> bool {
        self.values.iter().all(|v| v.is_finite())
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        8 * self.values.len() + 8 * self.spans.len()
    }

    /// The spans with their values.
    fn segments(&self) -> impl Iterator<Item = (usize, &[f64])> + '_ {
        let mut off = 0;
        self.spans.iter().map(move |&(start, len)| {
            let v = &self.values[off..off + len as usize];
            off += len as usize;
            (start as usize, v)
        })
    }

    /// The rows held (the reach), increasing.
    pub fn rows(&self) -> impl Iterator<Item = usize> + '_ {
        self.spans
            .iter()
            .flat_map(|&(start, len)| start as usize..(start + len) as usize)
    }

    /// The column as a dense vector of `n` rows (the permuted numbering).
    pub fn to_dense(&self, n: usize) -> Vec<f64> {
        let mut d = vec![0.0; n];
        for (start, v) in self.segments() {
            d[start..start + v.len()].copy_from_slice(v);
        }
        d
    }

    /// yᵀz of two reach columns (of the same factor).
    pub fn dot(&self, other: &ReachColumn) -> f64 {
        let (mut a, mut b) = (self.segments().peekable(), other.segments().peekable());
        let mut s = 0.0;
        while let (Some(&(sa, va)), Some(&(sb, vb))) = (a.peek(), b.peek()) {
            // spans are whole blocks: equal starts are the same block
            match sa.cmp(&sb) {
                std::cmp::Ordering::Less => {
                    a.next();
                }
                std::cmp::Ordering::Greater => {
                    b.next();
                }
                std::cmp::Ordering::Equal => {
                    s += dot(va, vb);
                    a.next();
                    b.next();
                }
            }
        }
        s
    }

    /// yᵀc with a dense vector in the permuted numbering.
    pub fn dot_dense(&self, c: &[f64]) -> f64 {
        self.segments()
            .map(|(start, v)| dot(v, &c[start..start + v.len()]))
            .sum()
    }

    /// c ← c + alpha·y, c dense in the permuted numbering.
    pub fn axpy_into(&self, alpha: f64, c: &mut [f64]) {
        for (start, v) in self.segments() {
            for (ci, vi) in c[start..start + v.len()].iter_mut().zip(v) {
                *ci += alpha * vi;
            }
        }
    }
}

/// Flops of one block's products above which [`gram`] runs them in
/// parallel: the blocks near the root of the elimination tree (thousands
/// of rows, every column), where the Xiaowan-like complete dam's products
/// are.
pub const GRAM_PAR_FLOPS: f64 = 1e7;

/// The products of reach columns (of one factor) block by block: `g_new`
/// = YₙᵀYₙ on and below its diagonal (entry (a, b), b ≤ a; zero above) and
/// `g_old` = YₙᵀY_o, for the columns `new` and `old`; and the flops of
/// their products. A block's products of more than [`GRAM_PAR_FLOPS`]
/// run with `par`, the others on this thread.
///
/// Per block of L, the columns whose reach holds it are gathered into one
/// dense panel Z (the block's rows × those columns) and its products are
/// one matrix product, Z_nᵀZ_n (lower half) and Z_nᵀZ_o. Summed over the
/// blocks that is every YᵢᵀYⱼ, the same flops as the products pair by
/// pair, but in BLAS-3 kernels instead of a merge of both columns' spans
/// for each pair (the capacitance matrices of the Xiaowan-like arch's late
/// days: rank ~1,000, half a million pairs of columns of ~12,000 rows).
pub fn gram(new: &[&ReachColumn], old: &[&ReachColumn], par: Par) -> (Mat<f64>, Mat<f64>, f64) {
    let n_new = new.len();
    let column = |c: usize| if c < n_new { new[c] } else { old[c - n_new] };
    // (block's first row, column in new ++ old, offset of its values, width)
    let mut at: Vec<(u32, u32, u32, u32)> = Vec::new();
    for (c, col) in new.iter().chain(old).enumerate() {
        let mut off = 0;
        for &(start, len) in &col.spans {
            at.push((start, c as u32, off, len));
            off += len;
        }
    }
    // spans are whole blocks: equal starts are the same block, and within
    // one the new columns come first
    at.sort_unstable();
    let mut g_new = Mat::<f64>::zeros(n_new, n_new);
    let mut g_old = Mat::<f64>::zeros(n_new, old.len());
    let (mut panel, mut product) = (Vec::new(), Vec::new());
    let mut flops = 0.0;
    for group in at.chunk_by(|a, b| a.0 == b.0) {
        let k_new = group.partition_point(|e| (e.1 as usize) < n_new);
        if k_new == 0 {
            continue;
        }
        let (g, w) = (group.len(), group[0].3 as usize);
        let block_flops = w as f64 * k_new as f64 * (k_new + 1 + 2 * (g - k_new)) as f64;
        flops += block_flops;
        let par = if block_flops > GRAM_PAR_FLOPS {
            par
        } else {
            Par::Seq
        };
        panel.clear();
        for &(_, c, off, _) in group {
            let off = off as usize;
            panel.extend_from_slice(&column(c as usize).values[off..off + w]);
        }
        let z = MatRef::from_column_major_slice(&panel, w, g);
        let (z_new, z_old) = z.split_at_col(k_new);
        product.clear();
        product.resize(k_new * g, 0.0);
        let (p_new, p_old) = product.split_at_mut(k_new * k_new);
        let mut p_new = MatMut::from_column_major_slice_mut(p_new, k_new, k_new);
        triangular::matmul(
            p_new.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            z_new.transpose(),
            BlockStructure::Rectangular,
            z_new,
            BlockStructure::Rectangular,
            1.0,
            par,
        );
        for b in 0..k_new {
            let cb = group[b].1 as usize;
            for a in b..k_new {
                g_new[(group[a].1 as usize, cb)] += p_new[(a, b)];
            }
        }
        if g == k_new {
            continue;
        }
        let mut p_old = MatMut::from_column_major_slice_mut(p_old, k_new, g - k_new);
        matmul(
            p_old.as_mut(),
            Accum::Replace,
            z_new.transpose(),
            z_old,
            1.0,
            par,
        );
        for (b, e) in group[k_new..].iter().enumerate() {
            let cb = e.1 as usize - n_new;
            for a in 0..k_new {
                g_old[(group[a].1 as usize, cb)] += p_old[(a, b)];
            }
        }
    }
    (g_new, g_old, flops)
}

/// xᵀy of two slices of one length, in eight interleaved partial sums: a
/// single running sum is a chain of dependent additions the compiler may
/// not reorder into SIMD lanes (the capacitance matrix's YᵢᵀYⱼ spent 6 %
/// of the Xiaowan-like run's late days in it).
fn dot(x: &[f64], y: &[f64]) -> f64 {
    debug_assert_eq!(x.len(), y.len());
    let mut acc = [0.0f64; 8];
    let (xc, yc) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xc.zip(yc) {
        for k in 0..8 {
            acc[k] += a[k] * b[k];
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// Rows and entries of L in the union of the reaches of `rows` (permuted
/// numbering): what a half solve restricted to them would read.
pub(super) fn reach_size(
    symbolic: &SymbolicCholesky<u32>,
    tree: &BlockTree,
    rows: impl Iterator<Item = usize>,
) -> (usize, usize) {
    let mut mark = vec![false; tree.n_blocks()];
    let mut reach = Vec::new();
    for row in rows {
        tree.mark_path(row, &mut mark, &mut reach);
    }
    reach.iter().fold((0, 0), |(n_rows, entries), &b| {
        let (_, width, _, vals) = block_shape(symbolic, b as usize);
        (n_rows + width, entries + vals.len())
    })
}

/// Scratch of the reach solves of one factor: the marks of the blocks
/// visited, each block's first row in the panel and the panel (rows of the
/// union of the reaches, a row's columns side by side) with the product
/// buffer.
#[derive(Debug, Default)]
pub struct ReachWork {
    mark: Vec<bool>,
    panel_row: Vec<u32>,
    panel: Vec<f64>,
    product: Vec<f64>,
}

/// Columns [`forward_reach_many`] solves together at most: each block of
/// L is then read once per batch, in matrix products, instead of once per
/// column in scalar loops. A batch computes each of its columns on every
/// block of the union of their reaches (zeros outside a column's own), so
/// larger batches waste flops on the leaves: with the columns in the
/// factor's order, the Xiaowan-like arch's days 913–916 took 8.5–8.8 s
/// for their 5,962 columns at 32, 9.8–10.0 s at 64 and 10.9 s at 16 (29
/// Nov 2026, alternated).
pub const REACH_BATCH: usize = 32;

/// L⁻¹ u of several columns at once (each its entries: row in the permuted
/// numbering, value), on the union of their reaches (see the module doc);
/// each column is returned on its own reach. A block of the union outside
/// a column's reach receives no update from it, so the column is exactly
/// zero there and equal to its solve alone up to the order of the sums
/// (`tests/it/fem_sparse.rs`).
pub(super) fn forward_reach_many(
    symbolic: &SymbolicCholesky<u32>,
    values: &[f64],
    tree: &BlockTree,
    columns: &[Vec<(usize, f64)>],
    work: &mut ReachWork,
) -> Vec<ReachColumn> {
    let k = columns.len();
    let nb = tree.n_blocks();
    if work.mark.len() != nb || work.panel_row.len() != nb {
        work.mark = vec![false; nb];
        work.panel_row = vec![u32::MAX; nb];
    }
    let own: Vec<Vec<u32>> = columns
        .iter()
        .map(|col| {
            let mut r = Vec::new();
            for &(row, _) in col {
                tree.mark_path(row, &mut work.mark, &mut r);
            }
            r.iter().for_each(|&b| work.mark[b as usize] = false);
            r.sort_unstable();
            r
        })
        .collect();
    let mut union: Vec<u32> = own.iter().flatten().copied().collect();
    union.sort_unstable();
    union.dedup();
    let mut rows = 0usize;
    for &b in &union {
        work.panel_row[b as usize] = rows as u32;
        rows += block_shape(symbolic, b as usize).1;
    }
    let ReachWork {
        panel_row,
        panel,
        product,
        ..
    } = work;
    let local = |row: usize| {
        let b = tree.block_of[row] as usize;
        panel_row[b] as usize + row - block_shape(symbolic, b).0
    };
    panel.clear();
    panel.resize(rows * k, 0.0);
    for (c, col) in columns.iter().enumerate() {
        for &(row, v) in col {
            panel[local(row) * k + c] += v;
        }
    }
    for &b in &union {
        let blk = block(symbolic, values, b as usize);
        let (w, below) = (blk.width, blk.below.len());
        let first = panel_row[b as usize] as usize * k;
        let l = MatRef::from_column_major_slice(blk.values, w + below, w);
        let (l11, l21) = l.split_at_row(w);
        let x1 = &mut panel[first..first + w * k];
        solve_lower_triangular_in_place(l11, MatMut::from_row_major_slice_mut(x1, w, k), Par::Seq);
        if below == 0 {
            continue;
        }
        product.clear();
        product.resize(below * k, 0.0);
        matmul(
            MatMut::from_row_major_slice_mut(product, below, k),
            Accum::Replace,
            l21,
            MatRef::from_row_major_slice(&panel[first..first + w * k], w, k),
            1.0,
            Par::Seq,
        );
        for (i, &row) in blk.below.iter().enumerate() {
            let at = local(row as usize) * k;
            let dst = &mut panel[at..at + k];
            dst.iter_mut()
                .zip(&product[i * k..(i + 1) * k])
                .for_each(|(d, p)| *d -= p);
        }
    }
    own.iter()
        .enumerate()
        .map(|(c, reach)| {
            let mut out = ReachColumn::default();
            for &b in reach {
                let blk = block(symbolic, values, b as usize);
                out.spans.push((blk.start as u32, blk.width as u32));
                let first = panel_row[b as usize] as usize;
                out.values
                    .extend((first..first + blk.width).map(|r| panel[r * k + c]));
            }
            out
        })
        .collect()
}
