//! A coarser rock for the mechanics without a coarser mesh: rock nodes tied
//! to their vertical grid line (`solver.rock_coarsening = N`).
//!
//! # Why
//!
//! The generators lay the foundation out as a structured grid, so the rock
//! beside the dam carries every lift level of the dam: below a block
//! founded high on a bank and in the margins beyond the abutments, one node
//! level every 3.6 m through up to 290 m of rock whose displacement is
//! smooth. On the Xiaowan-like arch 37,890 of its 43,210 rock elements lie
//! above the deepest foundation, and the rock is 64 % of a factorisation's
//! flops (`examples/rock_condensation.rs`). The rock below the deepest
//! foundation has keys of its own (`rock_layers`, `rock_grading_ratio`);
//! what no key coarsens is those lift levels.
//!
//! # The tie
//!
//! A vertical grid line is a chain of nodes joined by the vertical edges of
//! rock hexes (local node k below node k + 4, every element agreeing, the
//! elevation rising). On each line, from the first node at or above the
//! deepest concrete node, only every N-th node is kept, and a node between
//! two kept ones (lo below, hi above) moves with them, linearly in the
//! distance s along the line:
//!
//! ```text
//! u = (1 − w) u_lo + w u_hi,      w = (s − s_lo) / (s_hi − s_lo).
//! ```
//!
//! The grid lines bend a little (the generators place the rock's nodes
//! after the arch's rings: the tied nodes are 0.06 m at most off the chord
//! between their masters on the demo, 0.32 m over a 20 m span on the
//! Xiaowan-like arch), so the mechanics moves each tied node onto that
//! chord ([`Ties::straighten`]): the rock between two kept levels is
//! then a stack of hexes on straight lines, and a displacement linear in
//! space is one the tie can take exactly.
//!
//! Kept besides: both ends of a line, every node below the deepest
//! foundation, every node of an element that touches the concrete (the
//! foundation and its first ring of rock elements stay the mesh's), and a
//! node whose supports differ from a neighbour's on its line (then a tied
//! node's supports are exactly its two masters', and it needs no row of its
//! own).
//!
//! The tied displacements are a subspace of the mesh's (a field given at
//! the nodes, continuous, conforming, linear over N levels on each line),
//! so a step stays a Ritz–Galerkin solve: symmetric positive definite,
//! exact for any displacement linear along the lines (the patch test of
//! `tests/it/rock_ties.rs`), and stiffer than the fine rock by the energy
//! the tie removes. It is an approximation: off by default (N = 1), its
//! error against the untied run measured in `groutready study accuracy`.
//! [`super::live`] carries it in each element's T, as it carries the joint
//! pairs.

use crate::mesh::Part;

/// A tied node: it moves as `(1 − w) u_lo + w u_hi`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tie {
    pub lo: u32,
    pub hi: u32,
    pub w: f64,
}

impl Tie {
    /// The two masters with their weights.
    pub fn masters(&self) -> [(u32, f64); 2] {
        [(self.lo, 1.0 - self.w), (self.hi, self.w)]
    }
}

/// The tie of every node (none for a node with unknowns of its own): the
/// rock's ([`Ties::build`]) and, in a live system, those layer merging
/// has switched on ([`Ties::with`], [`super::layer_merging`]).
#[derive(Debug, Clone, Default)]
pub struct Ties {
    /// per node; empty when nothing is tied
    tie: Vec<Option<Tie>>,
    tied: usize,
}

const NONE: u32 = u32::MAX;
/// More than one element gives a node a different neighbour along its line.
const CONFLICT: u32 = u32::MAX - 1;

impl Ties {
    /// Nothing tied (`rock_coarsening = 1`).
    pub fn none() -> Ties {
        Ties::default()
    }

    /// The tie of `node`, if it is tied.
    pub fn of(&self, node: u32) -> Option<Tie> {
        self.tie.get(node as usize).copied().flatten()
    }

    /// How many nodes are tied.
    pub fn count(&self) -> usize {
        self.tied
    }

    /// Moves each tied node onto the chord between its masters, where its
    /// weight puts it: then the rock between two kept levels is a stack of
    /// hexes on straight lines, and a displacement linear in space is one
    /// the tie can take (the patch test).
    pub fn straighten(&self, nodes: &mut [[f64; 3]]) {
        for v in 0..self.tie.len() {
            if let Some(t) = self.tie[v] {
                let (lo, hi) = (nodes[t.lo as usize], nodes[t.hi as usize]);
                nodes[v] = std::array::from_fn(|k| (1.0 - t.w) * lo[k] + t.w * hi[k]);
            }
        }
    }

    /// The rock's ties of a mesh keeping every `every`-th level (module doc);
    /// `supported[3v + c]` marks fixed node dofs.
    pub fn build(
        elements: &[[u32; 8]],
        parts: &[Part],
        nodes: &[[f64; 3]],
        supported: &[bool],
        every: u32,
    ) -> Ties {
        if every <= 1 {
            return Ties::none();
        }
        let nn = nodes.len();
        let mut ties = Ties {
            tie: vec![None; nn],
            tied: 0,
        };
        let is_rock = |e: usize| parts[e] == Part::Rock;
        let mut concrete = vec![false; nn];
        for (_, c) in elements.iter().enumerate().filter(|&(e, _)| !is_rock(e)) {
            c.iter().for_each(|&v| concrete[v as usize] = true);
        }
        let Some(foundation) = (0..nn)
            .filter(|&v| concrete[v])
            .map(|v| nodes[v][2])
            .min_by(f64::total_cmp)
        else {
            return Ties::none();
        };
        let mut kept = concrete.clone();
        for (_, c) in elements.iter().enumerate().filter(|&(e, _)| is_rock(e)) {
            if c.iter().any(|&v| concrete[v as usize]) {
                c.iter().for_each(|&v| kept[v as usize] = true);
            }
        }
        let (above, below) = vertical_links(elements, nodes, &is_rock);
        let supports = |v: u32| &supported[3 * v as usize..3 * v as usize + 3];
        for line in vertical_lines(&above, &below) {
            let start = line
                .iter()
                .position(|&v| nodes[v as usize][2] >= foundation)
                .unwrap_or(line.len());
            let keep: Vec<bool> = (0..line.len())
                .map(|k| {
                    let v = line[k];
                    let differs = |j: usize| supports(line[j]) != supports(v);
                    k <= start
                        || k + 1 == line.len()
                        || (k - start) % every as usize == 0
                        || kept[v as usize]
                        || differs(k - 1)
                        || differs(k + 1)
                })
                .collect();
            ties.tie_line(&line, &keep, nodes);
        }
        ties
    }

    /// Ties the nodes of `line` between its kept ones ([`ties_along`]).
    fn tie_line(&mut self, line: &[u32], keep: &[bool], nodes: &[[f64; 3]]) {
        for (v, tie) in ties_along(line, keep, nodes) {
            self.tie[v as usize] = Some(tie);
            self.tied += 1;
        }
    }

    /// These ties and `extra` (nodes these leave free), over `n_nodes` nodes.
    pub fn with(&self, extra: impl Iterator<Item = (u32, Tie)>, n_nodes: usize) -> Ties {
        let mut out = self.clone();
        if out.tie.is_empty() {
            out.tie = vec![None; n_nodes];
        }
        for (v, tie) in extra {
            debug_assert!(out.tie[v as usize].is_none());
            out.tie[v as usize] = Some(tie);
            out.tied += 1;
        }
        out
    }
}

/// The ties of the nodes of `line` between its kept ones (`keep`), each to
/// the kept nodes below and above it, linearly in the distance along the line.
pub(super) fn ties_along(line: &[u32], keep: &[bool], nodes: &[[f64; 3]]) -> Vec<(u32, Tie)> {
    let mut s = vec![0.0; line.len()];
    for k in 1..line.len() {
        let (a, b) = (nodes[line[k - 1] as usize], nodes[line[k] as usize]);
        let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
        s[k] = s[k - 1] + d;
    }
    let mut out = Vec::new();
    let mut lo = 0;
    for hi in 1..line.len() {
        if !keep[hi] {
            continue;
        }
        for k in lo + 1..hi {
            let w = (s[k] - s[lo]) / (s[hi] - s[lo]);
            out.push((
                line[k],
                Tie {
                    lo: line[lo],
                    hi: line[hi],
                    w,
                },
            ));
        }
        lo = hi;
    }
    out
}

/// Whether a link of [`vertical_links`] leads to a node.
pub(super) fn linked(x: u32) -> bool {
    x != NONE && x != CONFLICT
}

/// The chains of [`vertical_links`], each from its foot up.
pub(super) fn vertical_lines(above: &[u32], below: &[u32]) -> Vec<Vec<u32>> {
    let mut lines = Vec::new();
    for foot in 0..above.len() as u32 {
        if !linked(above[foot as usize]) || linked(below[foot as usize]) {
            continue;
        }
        let mut line = vec![foot];
        loop {
            let last = *line.last().unwrap_or(&foot);
            let next = above[last as usize];
            if !linked(next) || below[next as usize] != last {
                break;
            }
            line.push(next);
        }
        lines.push(line);
    }
    lines
}

/// Each node's neighbour above and below along the vertical edges of the
/// hexes `of` selects (local node k below k + 4): NONE without one,
/// CONFLICT where two elements disagree or the edge does not rise.
pub(super) fn vertical_links(
    elements: &[[u32; 8]],
    nodes: &[[f64; 3]],
    of: &dyn Fn(usize) -> bool,
) -> (Vec<u32>, Vec<u32>) {
    let nn = nodes.len();
    let (mut above, mut below) = (vec![NONE; nn], vec![NONE; nn]);
    let link = |slot: &mut u32, to: u32, rises: bool| {
        *slot = if !rises || (*slot != NONE && *slot != to) {
            CONFLICT
        } else {
            to
        };
    };
    for (e, c) in elements.iter().enumerate() {
        if !of(e) {
            continue;
        }
        for k in 0..4 {
            let (a, b) = (c[k], c[k + 4]);
            let rises = nodes[b as usize][2] > nodes[a as usize][2];
            link(&mut above[a as usize], b, rises);
            link(&mut below[b as usize], a, rises);
        }
    }
    (above, below)
}
