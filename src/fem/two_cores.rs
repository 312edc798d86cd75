//! A factor's numeric factorisation and its solves' sweeps on two cores:
//! the elimination tree cut into two forests of whole subtrees and the
//! blocks above them.
//!
//! Subtrees of the elimination tree are independent. faer's supernodal
//! factorisation is left-looking: a block gathers the updates of its
//! descendants (already factorised) into its own columns, factorises its
//! diagonal block and solves the rows below; so the blocks of one subtree
//! read and write only their own subtree's values. A triangular sweep of
//! one right-hand side likewise: the forward sweep L c = P b of a subtree
//! writes its own rows and adds into its ancestors' rows, the backward
//! sweep Lᵀ y = c reads its ancestors' finished rows and writes its own.
//! faer parallelises inside a block only (its dense kernels), which the
//! many small blocks below the top separators do not feed: on the
//! Xiaowan-like complete dam a factorisation on two threads was 1.2× one
//! thread's, a sweep of one right-hand side on two no faster than on one
//! (`solver::SOLVE_PAR`). So the blocks are cut into a *top* (a set of
//! blocks closed under taking parents) and the subtrees hanging below it,
//! dealt to two *sides* of about equal work (largest first, each to the
//! lighter side):
//!
//! - factorisation: each side factorises its subtrees on one thread, the
//!   two side by side; then the top, its dense kernels on both;
//! - forward sweep: each side sweeps its subtrees, the second in a copy of
//!   the vector whose top rows start at zero, so that what it adds there is
//!   added to the first side's afterwards (in one fixed order: the result
//!   does not depend on which thread finishes first); then the top;
//! - backward sweep: the top, then each side its subtrees, the second in a
//!   copy whose rows are copied back.
//!
//! The cut is chosen once per symbolic analysis, one for the sweeps
//! (weighed by entries of L) and one for the factorisation (by flops):
//! starting from the roots, the heaviest subtree is opened (its root block
//! joins the top, its children become subtrees) while that lowers the
//! estimated time, the top's work plus the heavier side's
//! ([`TreeCut::new`]).
//!
//! Verified by `tests/it/fem_sparse.rs` (the factor and the solves on two
//! cores against faer's on one, supernodal factors with many blocks, with
//! and without held rows, to round-off; the same bits on every call).

use std::ops::Range;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::SparseColMatRef;
use faer::{Accum, MatMut, MatRef, Par};

use super::half_solves::{block, block_entries, Block, BlockTree};

/// A supernodal factor's two cuts and what its factorisation reads.
#[derive(Debug)]
pub(super) struct TwoCores {
    /// weighed by entries of L
    pub sweep: TreeCut,
    /// weighed by the flops of each block's factorisation
    pub factor: TreeCut,
    updaters: Updaters,
}

impl TwoCores {
    pub(super) fn new(symbolic: &SymbolicCholesky<u32>, tree: &BlockTree) -> Option<Self> {
        let faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw()
        else {
            return None;
        };
        let (updaters, flops) = Updaters::new(sn, tree);
        Some(TwoCores {
            sweep: TreeCut::new(tree, &block_entries(symbolic), 1.0),
            factor: TreeCut::new(tree, &flops, FACTOR_TOP_SHARE),
            updaters,
        })
    }

    /// The numeric factorisation of `a` (the lower triangle in the
    /// factor's numbering) into `values`, each side's subtrees on one
    /// thread, the top's blocks with `par`: faer's left-looking supernodal
    /// algorithm (`factorize_supernodal_numeric_llt`) block by block.
    pub(super) fn factorize(
        &self,
        sn: &SymbolicSupernodalCholesky<u32>,
        a: SparseColMatRef<'_, u32, f64>,
        values: &mut [f64],
        par: Par,
    ) -> Result<(), LltError> {
        assert_eq!(values.len(), sn.len_val());
        let shared = Shared {
            ptr: values.as_mut_ptr(),
            len: values.len(),
        };
        let run = |blocks: &[u32], par: Par| -> Result<(), LltError> {
            let mut work = FactorWork::new(sn, blocks, par);
            blocks.iter().try_for_each(|&s| {
                // SAFETY: see `Shared`: a side's blocks and their
                // descendants are its own, the top runs after both sides
                unsafe { factor_block(s as usize, sn, &self.updaters, a, &shared, &mut work, par) }
            })
        };
        let [first, second] = &self.factor.sides;
        let (r0, r1) = rayon::join(|| run(first, Par::Seq), || run(second, Par::Seq));
        match (r0, r1) {
            (
                Err(LltError::NonPositivePivot { index: i }),
                Err(LltError::NonPositivePivot { index: j }),
            ) => return Err(LltError::NonPositivePivot { index: i.min(j) }),
            (Err(e), _) | (_, Err(e)) => return Err(e),
            _ => {}
        }
        run(&self.factor.top, par)
    }
}

/// The blocks whose rows below fall in each block's columns (the
/// descendants that update it: faer's row-major structure of the
/// supernodal factor), in increasing order; made once per analysis.
#[derive(Debug)]
struct Updaters {
    ptr: Vec<usize>,
    idx: Vec<u32>,
}

impl Updaters {
    /// The updaters of every block, and the flops of each block's
    /// factorisation: its dense Cholesky and solve of the rows below, and
    /// the updates it gathers.
    fn new(sn: &SymbolicSupernodalCholesky<u32>, tree: &BlockTree) -> (Self, Vec<u64>) {
        let nb = sn.n_supernodes();
        let width = |b: usize| (sn.supernode_end()[b] - sn.supernode_begin()[b]) as u64;
        let mut flops: Vec<u64> = (0..nb)
            .map(|b| {
                let (w, below) = (width(b), sn.supernode(b).pattern().len() as u64);
                w * w * w / 3 + w * w * below
            })
            .collect();
        let mut count = vec![0usize; nb + 1];
        let groups = |d: usize, f: &mut dyn FnMut(usize, u64, u64)| {
            let pattern = sn.supernode(d).pattern();
            let mut at = 0;
            while at < pattern.len() {
                let s = tree.block_of(pattern[at] as usize);
                let m = pattern[at..]
                    .iter()
                    .take_while(|&&r| tree.block_of(r as usize) == s)
                    .count();
                f(s, m as u64, (pattern.len() - at) as u64);
                at += m;
            }
        };
        for d in 0..nb {
            let w = width(d);
            groups(d, &mut |s, m, bot| {
                count[s + 1] += 1;
                flops[s] += w * m * (2 * bot - m);
            });
        }
        for b in 0..nb {
            count[b + 1] += count[b];
        }
        let mut idx = vec![0u32; count[nb]];
        let mut next = count.clone();
        for d in 0..nb {
            groups(d, &mut |s, _, _| {
                idx[next[s]] = d as u32;
                next[s] += 1;
            });
        }
        (Updaters { ptr: count, idx }, flops)
    }

    fn of(&self, s: usize) -> &[u32] {
        &self.idx[self.ptr[s]..self.ptr[s + 1]]
    }
}

/// A factor's values shared by the two sides' threads. Each side writes
/// only its own blocks' values and reads only its own blocks' finished
/// values (a block's updaters are its descendants, which lie in its own
/// subtree); the top is factorised after both sides have finished.
struct Shared {
    ptr: *mut f64,
    len: usize,
}

// SAFETY: the threads touch disjoint ranges (see the struct's doc).
unsafe impl Sync for Shared {}

impl Shared {
    /// # Safety
    /// No thread writes `r` while the slice lives.
    unsafe fn get(&self, r: Range<usize>) -> &[f64] {
        assert!(r.start <= r.end && r.end <= self.len);
        unsafe { std::slice::from_raw_parts(self.ptr.add(r.start), r.len()) }
    }

    /// # Safety
    /// No other thread reads or writes `r` while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn get_mut(&self, r: Range<usize>) -> &mut [f64] {
        assert!(r.start <= r.end && r.end <= self.len);
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(r.start), r.len()) }
    }
}

/// One thread's scratch of the factorisation.
struct FactorWork {
    /// a row's place in the current block (u32::MAX: not in it)
    local: Vec<u32>,
    product: Vec<f64>,
    stack: MemBuffer,
}

impl FactorWork {
    fn new(sn: &SymbolicSupernodalCholesky<u32>, blocks: &[u32], par: Par) -> Self {
        let widest = blocks
            .iter()
            .map(|&b| (sn.supernode_end()[b as usize] - sn.supernode_begin()[b as usize]) as usize)
            .max()
            .unwrap_or(0);
        FactorWork {
            local: vec![u32::MAX; sn.nrows()],
            product: Vec::new(),
            stack: MemBuffer::new(cholesky_in_place_scratch::<f64>(
                widest,
                par,
                Default::default(),
            )),
        }
    }
}

/// Factorises block `s`: A's columns, the updates of its descendants, its
/// dense Cholesky and the rows below solved with it.
///
/// # Safety
/// No other thread touches block `s`'s values or writes those of its
/// updaters while this runs.
unsafe fn factor_block(
    s: usize,
    sn: &SymbolicSupernodalCholesky<u32>,
    updaters: &Updaters,
    a: SparseColMatRef<'_, u32, f64>,
    values: &Shared,
    work: &mut FactorWork,
    par: Par,
) -> Result<(), LltError> {
    let (begin, end, vptr) = (
        sn.supernode_begin(),
        sn.supernode_end(),
        sn.col_ptr_for_val(),
    );
    let (s_start, s_end) = (begin[s] as usize, end[s] as usize);
    let pattern = sn.supernode(s).pattern();
    let w = s_end - s_start;
    for (i, &r) in pattern.iter().enumerate() {
        work.local[r as usize] = (i + w) as u32;
    }
    let own = unsafe { values.get_mut(vptr[s] as usize..vptr[s + 1] as usize) };
    own.fill(0.0);
    let mut ls = MatMut::from_column_major_slice_mut(own, w + pattern.len(), w);
    for j in s_start..s_end {
        for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            if i >= j {
                let ix = if i >= s_end {
                    work.local[i] as usize
                } else {
                    i - s_start
                };
                ls[(ix, j - s_start)] += v;
            }
        }
    }
    for &d in updaters.of(s) {
        let d = d as usize;
        let d_w = (end[d] - begin[d]) as usize;
        let d_pattern = sn.supernode(d).pattern();
        let ld = unsafe { values.get(vptr[d] as usize..vptr[d + 1] as usize) };
        let ld = MatRef::from_column_major_slice(ld, d_w + d_pattern.len(), d_w);
        let first = d_pattern.partition_point(|&r| (r as usize) < s_start);
        let mid = d_pattern[first..].partition_point(|&r| (r as usize) < s_end);
        let rows = &d_pattern[first..];
        let ld_bot = ld.subrows(d_w + first, rows.len());
        let ld_mid = ld_bot.subrows(0, mid);
        work.product.clear();
        work.product.resize(rows.len() * mid, 0.0);
        let p = MatMut::from_column_major_slice_mut(&mut work.product, rows.len(), mid);
        let (p_mid, p_bot) = p.split_at_row_mut(mid);
        triangular::matmul(
            p_mid,
            BlockStructure::TriangularLower,
            Accum::Replace,
            ld_mid,
            BlockStructure::Rectangular,
            ld_mid.transpose(),
            BlockStructure::Rectangular,
            1.0,
            par,
        );
        matmul(
            p_bot,
            Accum::Replace,
            ld_bot.subrows(mid, rows.len() - mid),
            ld_mid.transpose(),
            1.0,
            par,
        );
        let at = |i: usize| {
            let r = rows[i] as usize;
            if i < mid {
                r - s_start
            } else {
                work.local[r] as usize
            }
        };
        for j in 0..mid {
            let col = &work.product[j * rows.len()..(j + 1) * rows.len()];
            let cj = rows[j] as usize - s_start;
            for (i, p) in col.iter().enumerate().skip(j) {
                ls[(at(i), cj)] -= p;
            }
        }
    }
    for &r in pattern {
        work.local[r as usize] = u32::MAX;
    }
    let (mut top, bot) = ls.split_at_row_mut(w);
    match cholesky_in_place(
        top.as_mut(),
        Default::default(),
        par,
        MemStack::new(&mut work.stack),
        Default::default(),
    ) {
        Ok(_) => {}
        Err(LltError::NonPositivePivot { index }) => {
            return Err(LltError::NonPositivePivot {
                index: index + s_start,
            })
        }
    }
    solve_lower_triangular_in_place(top.as_ref(), bot.transpose_mut(), par);
    Ok(())
}

/// Subtrees opened at most while looking for the best cut, and at most
/// past the best so far.
const MAX_OPENED: usize = 4096;
const PATIENCE: usize = 256;

/// The time of a flop in the top against one on a side, for the
/// factorisation's cut: the top holds the largest separators, whose dense
/// kernels run on both cores. On the Xiaowan-like complete dam with its
/// joints (246 Gflop a factorisation, 5 Dec 2026) a side's subtrees ran at
/// 37 Gflop/s on one core and the top at 60–70 Gflop/s on two; weighing
/// the top's flops fully cut it at 51 Gflop with sides of 113 and 82
/// (3.9 s a factorisation), at 0.6 at 81 with sides of 83 and 82 (3.4 s;
/// faer's own on both cores 4.4–4.6 s). The sweeps' top runs on one core
/// and is weighed fully.
const FACTOR_TOP_SHARE: f64 = 0.6;

/// Blocks of the top and of each side, each in increasing order (children
/// before parents: an order of the forward sweep).
#[derive(Debug, Clone, Default)]
pub(super) struct TreeCut {
    top: Vec<u32>,
    sides: [Vec<u32>; 2],
    /// work (entries of L, or flops) of the top and of each side
    entries: [u64; 3],
}

impl TreeCut {
    /// The cut of `tree` (see the module doc); `entries[b]` the work of
    /// block b (entries of L for the sweeps, flops for the factorisation),
    /// `top_share` the time of the top's work against a side's.
    pub(super) fn new(tree: &BlockTree, entries: &[u64], top_share: f64) -> Self {
        let nb = tree.n_blocks();
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); nb];
        let mut subtree = entries.to_vec();
        let mut roots = Vec::new();
        // parents come after their children
        for b in 0..nb {
            match tree.parent(b) {
                Some(p) => {
                    children[p].push(b as u32);
                    subtree[p] += subtree[b];
                }
                None => roots.push(b as u32),
            }
        }
        // the frontier's subtrees, heaviest first
        let key = |b: u32| (std::cmp::Reverse(subtree[b as usize]), b);
        roots.sort_unstable_by_key(|&b| key(b));
        let open = |frontier: &mut Vec<u32>, top: &mut Vec<u32>| {
            let heaviest = frontier.remove(0);
            top.push(heaviest);
            for &c in &children[heaviest as usize] {
                let at = frontier.partition_point(|&f| key(f) < key(c));
                frontier.insert(at, c);
            }
        };
        let (mut frontier, mut top) = (roots.clone(), Vec::new());
        let (mut top_work, mut best, mut best_at) = (0u64, f64::INFINITY, 0);
        loop {
            let heavier = deal(&frontier, &subtree).1.into_iter().max().unwrap_or(0);
            let cost = top_work as f64 * top_share + heavier as f64;
            if cost < best {
                (best, best_at) = (cost, top.len());
            }
            if frontier.is_empty() || top.len() >= MAX_OPENED || top.len() >= best_at + PATIENCE {
                break;
            }
            open(&mut frontier, &mut top);
            top_work += entries[*top.last().expect("opened") as usize];
        }
        // opened again up to the best
        let (mut frontier, mut top) = (roots, Vec::new());
        while top.len() < best_at {
            open(&mut frontier, &mut top);
        }
        let (owner, _) = deal(&frontier, &subtree);
        let mut sides: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
        let mut stack = Vec::new();
        for (&root, &side) in frontier.iter().zip(&owner) {
            stack.push(root);
            while let Some(b) = stack.pop() {
                sides[side].push(b);
                stack.extend_from_slice(&children[b as usize]);
            }
        }
        top.sort_unstable();
        sides.iter_mut().for_each(|s| s.sort_unstable());
        let sum = |bs: &[u32]| bs.iter().map(|&b| entries[b as usize]).sum::<u64>();
        TreeCut {
            entries: [sum(&top), sum(&sides[0]), sum(&sides[1])],
            top,
            sides,
        }
    }

    /// Work of the top and of each side.
    pub(super) fn entries(&self) -> [u64; 3] {
        self.entries
    }

    /// L⁻¹x (`lower`) or L⁻ᵀx in place, `x` in the factor's numbering,
    /// the two sides on two threads of rayon's pool.
    pub(super) fn sweep(
        &self,
        symbolic: &SymbolicCholesky<u32>,
        values: &[f64],
        x: &mut [f64],
        lower: bool,
    ) {
        let blk = |b: &u32| block(symbolic, values, *b as usize);
        let [first, second] = &self.sides;
        let mut copy = x.to_vec();
        if lower {
            for b in self.top.iter().map(blk) {
                copy[b.start..b.start + b.width].fill(0.0);
            }
            rayon::join(
                || {
                    let mut work = Vec::new();
                    first
                        .iter()
                        .map(blk)
                        .for_each(|b| forward_block(&b, x, &mut work))
                },
                || {
                    let mut work = Vec::new();
                    (second.iter().map(blk)).for_each(|b| forward_block(&b, &mut copy, &mut work))
                },
            );
            for b in second.iter().map(blk) {
                x[b.start..b.start + b.width].copy_from_slice(&copy[b.start..b.start + b.width]);
            }
            for b in self.top.iter().map(blk) {
                let rows = b.start..b.start + b.width;
                x[rows.clone()]
                    .iter_mut()
                    .zip(&copy[rows])
                    .for_each(|(xi, ci)| *xi += ci);
            }
            let mut work = Vec::new();
            (self.top.iter().map(blk)).for_each(|b| forward_block(&b, x, &mut work));
        } else {
            let mut work = Vec::new();
            (self.top.iter().rev().map(blk)).for_each(|b| backward_block(&b, x, &mut work));
            copy.copy_from_slice(x);
            rayon::join(
                || (first.iter().rev().map(blk)).for_each(|b| backward_block(&b, x, &mut work)),
                || {
                    let mut work = Vec::new();
                    (second.iter().rev().map(blk))
                        .for_each(|b| backward_block(&b, &mut copy, &mut work))
                },
            );
            for b in second.iter().map(blk) {
                x[b.start..b.start + b.width].copy_from_slice(&copy[b.start..b.start + b.width]);
            }
        }
    }
}

/// Each subtree (largest first) to the side with fewer entries so far:
/// the side of each, and the entries of each side.
fn deal(frontier: &[u32], subtree: &[u64]) -> (Vec<usize>, [u64; 2]) {
    let mut load = [0u64; 2];
    let owner = frontier
        .iter()
        .map(|&b| {
            let side = usize::from(load[1] < load[0]);
            load[side] += subtree[b as usize];
            side
        })
        .collect();
    (owner, load)
}

/// The forward sweep's step at one block: its rows solved with the
/// diagonal block, then their products subtracted from the rows below
/// (`work`: scratch for the products).
fn forward_block(b: &Block<'_>, x: &mut [f64], work: &mut Vec<f64>) {
    let (w, below) = (b.width, b.below.len());
    let l = MatRef::from_column_major_slice(b.values, w + below, w);
    let (l11, l21) = l.split_at_row(w);
    let xb = &mut x[b.start..b.start + w];
    solve_lower_triangular_in_place(l11, MatMut::from_column_major_slice_mut(xb, w, 1), Par::Seq);
    if below == 0 {
        return;
    }
    work.clear();
    work.resize(below, 0.0);
    matmul(
        MatMut::from_column_major_slice_mut(work, below, 1),
        Accum::Replace,
        l21,
        MatRef::from_column_major_slice(&x[b.start..b.start + w], w, 1),
        1.0,
        Par::Seq,
    );
    for (&row, p) in b.below.iter().zip(work.iter()) {
        x[row as usize] -= p;
    }
}

/// The backward sweep's step at one block: the rows below (finished)
/// subtracted through the block's transpose, then its rows solved
/// (`work`: scratch for the rows below).
fn backward_block(b: &Block<'_>, x: &mut [f64], work: &mut Vec<f64>) {
    let (w, below) = (b.width, b.below.len());
    let l = MatRef::from_column_major_slice(b.values, w + below, w);
    let (l11, l21) = l.split_at_row(w);
    if below > 0 {
        work.clear();
        work.extend(b.below.iter().map(|&r| x[r as usize]));
        matmul(
            MatMut::from_column_major_slice_mut(&mut x[b.start..b.start + w], w, 1),
            Accum::Add,
            l21.transpose(),
            MatRef::from_column_major_slice(work, below, 1),
            -1.0,
            Par::Seq,
        );
    }
    let xb = &mut x[b.start..b.start + w];
    solve_upper_triangular_in_place(
        l11.transpose(),
        MatMut::from_column_major_slice_mut(xb, w, 1),
        Par::Seq,
    );
}
