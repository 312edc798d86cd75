//! A solve's two sweeps on two cores: the elimination tree cut into two
//! forests of whole subtrees and the blocks above them.
//!
//! A triangular sweep of one right-hand side reads every entry of L once
//! and does two flops with it: it is bound by how fast one core streams L,
//! and faer's parallel supernodal sweep (which splits the work inside a
//! block) only adds scheduling to it (`solver::SOLVE_PAR`). Subtrees of
//! the elimination tree, though, are independent: the forward sweep
//! L c = P b of one subtree reads and writes only its own rows and adds
//! into the rows of its ancestors, and the backward sweep Lᵀ y = c of one
//! subtree reads its ancestors' finished rows and writes only its own. So
//! the blocks are cut into a *top* (a set of blocks closed under taking
//! parents) and the subtrees hanging below it, dealt to two *sides* with
//! about equal entries of L (largest first, each to the lighter side):
//!
//! - forward: each side sweeps its subtrees, the second in a copy of the
//!   vector whose top rows start at zero, so that what it adds there is
//!   added to the first side's afterwards (in one fixed order: the result
//!   does not depend on which thread finishes first); then the top;
//! - backward: the top, then each side its subtrees, the second in a copy
//!   whose rows are copied back.
//!
//! The cut is chosen once per symbolic analysis: starting from the roots,
//! the heaviest subtree is opened (its root block joins the top, its
//! children become subtrees) while that lowers the estimated time, the
//! top's entries plus the heavier side's ([`SolveSplit::new`]).
//!
//! Verified by `tests/it/fem_sparse.rs` (the split solve against faer's
//! solve, supernodal factors with many blocks, to round-off) and by the
//! unit test below on a factor whose tree has one root and one whose
//! roots are all single held rows.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::{Accum, MatMut, MatRef, Par};

use super::half_solves::{block, Block, BlockTree};

/// Subtrees opened at most while looking for the best cut.
const MAX_OPENED: usize = 512;

/// Blocks of the top and of each side, each in increasing order (children
/// before parents: an order of the forward sweep).
#[derive(Debug, Clone, Default)]
pub(super) struct SolveSplit {
    top: Vec<u32>,
    sides: [Vec<u32>; 2],
    /// entries of L in the top and on each side
    entries: [u64; 3],
}

impl SolveSplit {
    /// The cut of `tree` (see the module doc); `entries[b]` the entries of
    /// block b.
    pub(super) fn new(tree: &BlockTree, entries: &[u64]) -> Self {
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
        let mut frontier = roots;
        let mut top: Vec<u32> = Vec::new();
        let mut top_entries = 0u64;
        let mut best: Option<(u64, Vec<u32>, Vec<u32>)> = None;
        for _ in 0..=MAX_OPENED {
            frontier.sort_unstable_by_key(|&b| (std::cmp::Reverse(subtree[b as usize]), b));
            let heavier = deal(&frontier, &subtree).1.into_iter().max().unwrap_or(0);
            let cost = top_entries + heavier;
            if best.as_ref().is_none_or(|(c, _, _)| cost < *c) {
                best = Some((cost, top.clone(), frontier.clone()));
            }
            let Some(&heaviest) = frontier.first() else {
                break;
            };
            frontier.remove(0);
            top.push(heaviest);
            top_entries += entries[heaviest as usize];
            frontier.extend_from_slice(&children[heaviest as usize]);
        }
        let Some((_, mut top, frontier)) = best else {
            return SolveSplit::default();
        };
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
        SolveSplit {
            entries: [sum(&top), sum(&sides[0]), sum(&sides[1])],
            top,
            sides,
        }
    }

    /// Entries of L in the top and on each side.
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
