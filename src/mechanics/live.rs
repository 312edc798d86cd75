//! The unknowns of a mechanical step: live node displacements and, for every
//! joint point whose two nodes are live, the relative displacement of its
//! pair in the point's local frame.
//!
//! A point pairs node a (block A) with node b (block B, coincident). Instead
//! of u_b the system carries d = R(u_b − u_a) (R: rows t1, t2, n), so that
//!
//! ```text
//! u_a = ũ_a,        u_b = ũ_a + Rᵀ d,        u = T ũ,   K̃ = Tᵀ K T,   f̃ = Tᵀ f.
//! ```
//!
//! T is invertible, so K̃ is as positive definite as K; the sparsity is that of
//! the mesh with each pair merged into one 6-dof node, so the symbolic
//! Cholesky is shared by every contact state. A closed point is then an exact
//! constraint on its own unknowns (d_n = −gap, and d_t = 0 while it sticks):
//! Dirichlet rows, no penalty. The row of d is the equilibrium of the pair:
//! (K̃ ũ − f̃)_d = change of the contact force on side B in the local frame.
//!
//! Tied rock nodes ([`super::rock_ties`], `solver.rock_coarsening`) enter
//! the same T: a tied node has no unknowns of its own, u_s = (1 − w) ũ_lo +
//! w ũ_hi, so an element with one takes its masters' unknowns instead.
//! T then drops columns (the tied rows), and K̃ = Tᵀ K T is the stiffness on
//! that subspace.
//!
//! Each live set is analysed (faer's symbolic Cholesky) in an elimination
//! order chosen by [`OrderingPlan`]. The default computes METIS's nested
//! dissection once, on the complete dam ([`ConstructionOrdering`]), and
//! restricts it to each live set: a pour then costs a sort and a symbolic
//! analysis instead of a METIS call. Measured over the demo's whole
//! construction (`groutready study perf`): Σ L over its 220 live sets +5.8 %
//! and Σ flops +11.4 % against a METIS call per set; over the first 40 days
//! of the Xiaowan-like arch (4 live sets, mostly foundation) +5.2 % and
//! +17 %, for one METIS call instead of one per pour (several seconds each
//! at 150k dofs). `solver.ordering = "metis_live_set"` keeps a call per
//! set. The solutions are the same to round-off (`tests/it/fast_path.rs`,
//! `tests/it/reproducible.rs` run on it).

use std::sync::Arc;
use std::time::Instant;

use nalgebra::DMatrix;

use crate::fem::elasticity::PackedSym24;
use crate::fem::{
    metis_nested_dissection, metis_nested_dissection_with, CholeskySolver, MetisError, MetisKnobs,
    Ordering, Pattern, SolveError, SparseSym, NO_DOF,
};

use super::joints::JointPoint;
use super::layer_merging::LayerMerge;
use super::rock_condensation::CondensedRock;
use super::rock_ties::{Tie, Ties};

/// Marks a dof without an unknown.
pub const NONE: u32 = u32::MAX;

/// Live systems of this many dofs or more are factorised on both cores
/// (faer's `Par::rayon`; their solves stay on one,
/// [`crate::fem::CholeskySolver`]'s `SOLVE_PAR`); smaller ones on one, and the next step's made
/// ahead on the second core ([`super::ahead`]). On the demo's systems of up
/// to 25,458 dofs two threads made the whole run slower (221 against
/// 165 s). On the Xiaowan-like arch with the rock tied every 4th level
/// (live sets of up to 80,760 dofs in its first 240 days) one core and the
/// factor made ahead took 263.6 s against 361.2 s on both cores with a
/// threshold of 30,000 (99.1 against 115.9 s over 120 days): the step's
/// own work overlaps the factorisation. Larger sets (the untied arch from
/// its first weeks, the complete dams) stay on both cores: on the tied
/// arch's days 870–890 (resumed from one checkpoint, alone on the 2 cores,
/// 27 Nov 2026) the threshold removed (one core, and the factor made ahead
/// where it fits [`super::ahead`]'s memory limit) took the same 20 days in
/// 420 s as both cores: no gain to take. The untied arch's days 576–618
/// (its restart point, alone, 27–28 Nov 2026; live sets of 225k–234k
/// dofs, 177M entries of L) likewise: 420 s as now, 428 s with the next
/// step's factor made ahead on one core and 426 s on both, beside the
/// passes (made on every other day, those without a pour at the next
/// step's start, 8–10 s on one core, never waited for): the passes'
/// solves, bound by memory, slow down beside it by what it saves.
pub const PARALLEL_FROM_DOFS: usize = 100_000;

/// One element in the reduced unknowns.
#[derive(Debug, Clone)]
pub struct LiveElement {
    pub elem: u32,
    /// reduced dofs of the element's local columns, three per column block
    pub dofs: Vec<u32>,
    /// the element's T block by block; None when it is the identity (node
    /// k's displacement is column block k)
    pub terms: Option<Box<[Term]>>,
    /// Tᵀ K̂ T of the unit-modulus stiffness when `terms` is not None
    pub k_unit: Option<DMatrix<f64>>,
    /// every dof condensed ([`super::rock_condensation`]): the element
    /// adds nothing to the system's matrix
    pub condensed: bool,
}

/// One 3 × 3 block of an element's T: the displacement of the element's
/// node `node` takes the column block `col` (reduced dofs `dofs[3 col..3 col
/// + 3]`)
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Term {
    /// times `weight`: a node's own unknowns (1), or a tied node's master's
    /// ([`Tie::masters`]);
    Scaled { node: u8, col: u8, weight: f64 },
    /// through the axes of the live pair `pair` (u_b = ũ_a + Rᵀ d: the
    /// pair's relative unknowns).
    Axes { node: u8, col: u8, pair: u32 },
}

/// A live pair: its joint point and the first of its three reduced dofs (t1, t2, n).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LivePair {
    pub point: u32,
    pub first: u32,
}

/// The numbering, pattern and symbolic factorisation of one live set.
pub struct LiveSystem {
    /// unknowns of the system solved (the condensed rock's not counted)
    pub n: usize,
    /// the condensed rock's unknowns, numbered after the system's
    /// (`n..n + n_condensed`; 0 when nothing is condensed)
    pub n_condensed: usize,
    /// the condensed rock, when this system has it condensed
    pub rock: Option<Arc<CondensedRock>>,
    /// the rock's part of the system's matrix (its elements, −C of the
    /// condensed rock), which no step changes: each step's stiffness
    /// starts from it (set by the model, which knows the rock's modulus)
    pub rock_matrix: Option<SparseSym>,
    /// reduced dof of each global node dof (NONE for dead nodes and the b side of live pairs)
    pub index_of: Vec<u32>,
    /// pair slot of each node on the b side of a live pair (NONE otherwise)
    pub pair_of_b: Vec<u32>,
    pub pairs: Vec<LivePair>,
    /// pair slot of each joint point (NONE when not live)
    pub slot_of_point: Vec<u32>,
    pub elements: Vec<LiveElement>,
    pub pattern: Arc<Pattern>,
    pub solver: CholeskySolver,
    /// supported reduced dofs
    pub supported: Vec<bool>,
    /// global node dofs that own a reduced dof: (global dof, reduced dof)
    pub node_dofs: Vec<(u32, u32)>,
    /// the tied nodes of the live elements, by node
    pub tied: Vec<(u32, Tie)>,
    /// what choosing the elimination order of this set cost
    pub ordering: OrderingCost,
}

/// The cost of a live set's elimination order: METIS calls (1 per live set
/// with [`OrderingPlan::MetisLiveSet`], 0 for a restriction) and seconds
/// (the restriction's or METIS's, not faer's symbolic analysis).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OrderingCost {
    pub metis_calls: usize,
    pub seconds: f64,
}

/// Error of the numbering.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Ordering(#[from] MetisError),
    #[error("joint node {node} is supported in a direction that is not an axis of its joint, or its partner is not: a joint face may not touch the far supports")]
    SupportedPairNode { node: u32 },
    #[error("node {node} is on two joints (side b of one, side a of another): each block needs at least one element between its two joints")]
    ChainedPair { node: u32 },
}

/// The elements a live system is numbered from: connectivity, which are
/// live, the unit-modulus stiffness of each, and the tied rock nodes.
#[derive(Clone, Copy)]
pub struct ElementSet<'a> {
    pub conn: &'a [[u32; 8]],
    pub live: &'a [bool],
    pub k_unit: &'a [PackedSym24],
    pub ties: &'a Ties,
    /// the rock to condense, when every one of its unknowns is live
    pub rock: Option<&'a Arc<CondensedRock>>,
}

impl LiveSystem {
    /// The system of no live element: what a model holds until its first
    /// rebuild.
    pub fn empty(points: &[JointPoint], n_nodes: usize) -> Result<LiveSystem, LiveError> {
        let no_pair = vec![false; points.len()];
        let none = ElementSet {
            conn: &[],
            live: &[],
            k_unit: &[],
            ties: &Ties::none(),
            rock: None,
        };
        LiveSystem::build(none, points, &no_pair, &[], n_nodes, &OrderingPlan::Amd)
    }

    /// Numbers the unknowns of the live elements and pairs and analyses the
    /// pattern in the elimination order `plan` gives. `pair_live[p]` says
    /// whether point p is live (both nodes born); `supported[g]` marks fixed
    /// global dofs.
    pub fn build(
        elements: ElementSet,
        points: &[JointPoint],
        pair_live: &[bool],
        supported: &[bool],
        n_nodes: usize,
        plan: &OrderingPlan,
    ) -> Result<LiveSystem, LiveError> {
        let k_unit = elements.k_unit;
        let rock = elements.rock.cloned();
        let mut numbered = Numbered::new(elements, points, pair_live, n_nodes)?;
        let rock = rock.filter(|r| numbered.condense(r));
        let n_all = numbered.n;
        let n_condensed = rock.as_ref().map_or(0, |r| r.n());
        let n = n_all - n_condensed;
        let pattern = Arc::new(numbered.pattern_without(n, rock.as_deref()));
        let par = if n < PARALLEL_FROM_DOFS {
            faer::Par::Seq
        } else {
            faer::Par::rayon(0)
        };
        let t = Instant::now();
        let (ordering, metis_calls) = match plan {
            OrderingPlan::Amd => (Ordering::Amd, 0),
            OrderingPlan::MetisLiveSet => (Ordering::Custom(metis_nested_dissection(&pattern)?), 1),
            OrderingPlan::Construction(c) => {
                let mut fwd = c.restrict(&numbered, points);
                fwd.retain(|&d| (d as usize) < n);
                (Ordering::Custom(fwd), 0)
            }
        };
        let ordering_seconds = t.elapsed().as_secs_f64();
        let Numbered {
            index_of,
            node_dofs,
            pairs,
            pair_of_b,
            slot_of_point,
            elements: numbered_elements,
            tied,
            ..
        } = numbered;
        let mut supported_r = reduced_supports(n_all, &node_dofs, &pairs, points, supported)?;
        supported_r.truncate(n);
        // every matrix the step factorises holds the supports
        let solver = CholeskySolver::with_held(pattern.clone(), &ordering, par, &supported_r)?;
        let live_elements = numbered_elements
            .into_iter()
            .map(|el| {
                let k_unit = el.terms.as_ref().map(|terms| {
                    let t = transform(terms, el.dofs.len(), &pairs, points);
                    let k = k_unit[el.elem as usize].to_full();
                    t.transpose() * DMatrix::from_column_slice(24, 24, k.as_slice()) * &t
                });
                let condensed = el.dofs.iter().all(|&d| d as usize >= n);
                LiveElement {
                    k_unit,
                    condensed,
                    ..el
                }
            })
            .collect();
        Ok(LiveSystem {
            n,
            n_condensed,
            rock,
            rock_matrix: None,
            index_of,
            pair_of_b,
            pairs,
            slot_of_point,
            elements: live_elements,
            pattern,
            solver,
            supported: supported_r,
            node_dofs,
            tied,
            ordering: OrderingCost {
                metis_calls,
                seconds: ordering_seconds,
            },
        })
    }

    /// Unknowns with the condensed rock's: the length of the vectors of
    /// [`LiveSystem::reduce`], [`LiveSystem::expand`] and
    /// [`LiveSystem::add_element_vector`].
    pub fn n_all(&self) -> usize {
        self.n + self.n_condensed
    }

    /// Adds the element vector `f` (24 entries, global node order) as Tᵀf.
    pub fn add_element_vector(
        &self,
        slot: usize,
        f: &[f64; 24],
        points: &[JointPoint],
        out: &mut [f64],
    ) {
        let el = &self.elements[slot];
        let Some(terms) = &el.terms else {
            for (&d, &v) in el.dofs.iter().zip(f) {
                out[d as usize] += v;
            }
            return;
        };
        for term in terms.iter() {
            let (node, col) = term.blocks();
            let fk = [f[3 * node], f[3 * node + 1], f[3 * node + 2]];
            let add = match *term {
                Term::Scaled { weight, .. } => fk.map(|v| weight * v),
                Term::Axes { pair, .. } => points[self.pairs[pair as usize].point as usize]
                    .frame
                    .to_local(fk),
            };
            for j in 0..3 {
                out[el.dofs[3 * col + j] as usize] += add[j];
            }
        }
    }

    /// Tᵀ g for a vector over the global node dofs.
    pub fn reduce(&self, g: &[f64], points: &[JointPoint]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_all()];
        for &(gd, i) in &self.node_dofs {
            out[i as usize] += g[gd as usize];
        }
        for pair in &self.pairs {
            let pt = &points[pair.point as usize];
            let b = pt.b as usize;
            let fb = [g[3 * b], g[3 * b + 1], g[3 * b + 2]];
            let local = pt.frame.to_local(fb);
            for c in 0..3 {
                out[self.index_of[3 * pt.a as usize + c] as usize] += fb[c];
                out[pair.first as usize + c] += local[c];
            }
        }
        for &(s, tie) in &self.tied {
            for (m, w) in tie.masters() {
                for c in 0..3 {
                    out[self.index_of[3 * m as usize + c] as usize] += w * g[3 * s as usize + c];
                }
            }
        }
        out
    }

    /// u = T ũ on the global node dofs (zero where nothing is live).
    pub fn expand(&self, x: &[f64], points: &[JointPoint], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for &(gd, i) in &self.node_dofs {
            out[gd as usize] = x[i as usize];
        }
        for pair in &self.pairs {
            let pt = &points[pair.point as usize];
            let f = pair.first as usize;
            let rel = pt.frame.to_global([x[f], x[f + 1], x[f + 2]]);
            for c in 0..3 {
                out[3 * pt.b as usize + c] =
                    x[self.index_of[3 * pt.a as usize + c] as usize] + rel[c];
            }
        }
        for &(s, tie) in &self.tied {
            for c in 0..3 {
                out[3 * s as usize + c] = tie
                    .masters()
                    .iter()
                    .map(|&(m, w)| w * x[self.index_of[3 * m as usize + c] as usize])
                    .sum();
            }
        }
    }

    /// Folds a vector over the global node dofs onto the kept nodes: each
    /// tied node's entries go to its masters by their weights (Tᵀ on the
    /// tied rows) and are zeroed; a residual of the live system is then
    /// read node by node.
    pub fn fold_tied(&self, g: &mut [f64]) {
        for &(s, tie) in &self.tied {
            for c in 0..3 {
                let v = std::mem::take(&mut g[3 * s as usize + c]);
                for (m, w) in tie.masters() {
                    g[3 * m as usize + c] += w * v;
                }
            }
        }
    }
}

impl Term {
    /// The element node and the column block of the term.
    fn blocks(&self) -> (usize, usize) {
        match *self {
            Term::Scaled { node, col, .. } | Term::Axes { node, col, .. } => {
                (node as usize, col as usize)
            }
        }
    }
}

/// The unknowns of one live set, numbered in the order the live elements
/// first use them, before any analysis.
pub struct Numbered {
    pub n: usize,
    /// reduced dof of each global node dof (NONE for dead nodes and the b side of live pairs)
    pub index_of: Vec<u32>,
    /// (global dof, reduced dof) of every numbered node dof
    pub node_dofs: Vec<(u32, u32)>,
    pub pairs: Vec<LivePair>,
    /// pair slot of each node on the b side of a live pair (NONE otherwise)
    pub pair_of_b: Vec<u32>,
    /// pair slot of each joint point (NONE when not live)
    pub slot_of_point: Vec<u32>,
    /// the live elements, their stiffness not yet transformed (`k_unit` none)
    pub elements: Vec<LiveElement>,
    /// the tied nodes of the live elements, by node
    pub tied: Vec<(u32, Tie)>,
}

impl Numbered {
    /// Numbers the unknowns of the live `elements` (their stiffness is not
    /// read) and of the pairs `pair_live` marks.
    pub fn new(
        elements: ElementSet,
        points: &[JointPoint],
        pair_live: &[bool],
        n_nodes: usize,
    ) -> Result<Numbered, LiveError> {
        let LivePairs {
            mut pairs,
            pair_of_b,
            slot_of_point,
        } = LivePairs::new(points, pair_live, n_nodes)?;
        let mut numbering = Numbering {
            index_of: vec![NONE; 3 * n_nodes],
            node_dofs: Vec::new(),
            n: 0,
        };
        let mut live_elements = Vec::new();
        let mut tied = Vec::new();
        let links = Links {
            pair_of_b: &pair_of_b,
            points,
            ties: elements.ties,
            n_nodes: n_nodes as u32,
        };
        for (e, conn) in elements.conn.iter().enumerate() {
            if elements.live[e] {
                let (dofs, terms) = numbering.element(conn, &links, &mut pairs);
                tied.extend(
                    conn.iter()
                        .filter_map(|&v| elements.ties.of(v).map(|t| (v, t))),
                );
                live_elements.push(LiveElement {
                    elem: e as u32,
                    dofs,
                    terms,
                    k_unit: None,
                    condensed: false,
                });
            }
        }
        tied.sort_unstable_by_key(|&(v, _)| v);
        tied.dedup_by_key(|&mut (v, _)| v);
        // A pair whose a node belongs to no live element (cannot happen for
        // live pairs, whose nodes are born with their elements) keeps NONE.
        Ok(Numbered {
            n: numbering.n as usize,
            index_of: numbering.index_of,
            node_dofs: numbering.node_dofs,
            pairs,
            pair_of_b,
            slot_of_point,
            elements: live_elements,
            tied,
        })
    }

    /// The sparsity pattern of the set's matrix.
    pub fn pattern(&self) -> Pattern {
        let lists: Vec<&[u32]> = self.elements.iter().map(|e| e.dofs.as_slice()).collect();
        Pattern::new(self.n, &lists)
    }

    /// The pattern of the first `n` unknowns (the others condensed): the
    /// elements on them, then `rock`'s blocks of C, one slot each.
    pub fn pattern_without(&self, n: usize, rock: Option<&CondensedRock>) -> Pattern {
        let Some(rock) = rock else {
            return self.pattern();
        };
        let mut lists: Vec<Vec<u32>> = self
            .elements
            .iter()
            .map(|e| {
                e.dofs
                    .iter()
                    .map(|&d| if d as usize >= n { NO_DOF } else { d })
                    .collect()
            })
            .collect();
        lists.extend(
            rock.blocks
                .iter()
                .map(|b| b.dofs.iter().map(|&g| self.index_of[g as usize]).collect()),
        );
        Pattern::new(n, &lists)
    }

    /// Numbers `rock`'s unknowns last, in its order (`n − rock.n()..n`),
    /// the others first in their order. False (nothing changed) unless
    /// every unknown of `rock` and of its blocks' boundaries has an unknown
    /// of its own (live, not on side b of a pair) and none is a pair's.
    fn condense(&mut self, rock: &CondensedRock) -> bool {
        let n_r = rock.n();
        let own = |g: &u32| self.index_of[*g as usize] != NONE;
        let all_live =
            rock.dofs.iter().all(own) && rock.blocks.iter().all(|b| b.dofs.iter().all(own));
        if !all_live || n_r == 0 || n_r > self.n {
            return false;
        }
        let mut new = vec![NONE; self.n];
        for &g in &rock.dofs {
            new[self.index_of[g as usize] as usize] =
                (self.n - n_r) as u32 + rock.index[g as usize];
        }
        if self
            .pairs
            .iter()
            .any(|p| p.first != NONE && new[p.first as usize] != NONE)
        {
            return false;
        }
        for (next, slot) in new.iter_mut().filter(|s| **s == NONE).enumerate() {
            *slot = next as u32;
        }
        let map = |d: &mut u32| {
            if *d != NONE {
                *d = new[*d as usize];
            }
        };
        self.index_of.iter_mut().for_each(map);
        self.node_dofs.iter_mut().for_each(|(_, i)| map(i));
        self.pairs.iter_mut().for_each(|p| map(&mut p.first));
        self.elements
            .iter_mut()
            .for_each(|e| e.dofs.iter_mut().for_each(map));
        true
    }

    /// The key of each reduced dof in the unknowns of the complete dam
    /// ([`ConstructionOrdering`]): a node dof is its global dof, a pair's
    /// relative dof j of point p is 3·n_nodes + 3p + j, and a dof of a node
    /// on side b of a point whose pair is not live yet takes that pair's
    /// key (it sits where the pair's unknowns will: coupled to block B and,
    /// once block A is born, to node a).
    fn keys(&self, point_of_b: &[u32]) -> Vec<u32> {
        let n_nodes = self.index_of.len() / 3;
        let pair_key = |p: u32, j: u32| (3 * n_nodes) as u32 + 3 * p + j;
        let mut keys = vec![NONE; self.n];
        for &(g, i) in &self.node_dofs {
            let p = point_of_b[g as usize / 3];
            keys[i as usize] = if p == NONE { g } else { pair_key(p, g % 3) };
        }
        for pair in self.pairs.iter().filter(|p| p.first != NONE) {
            for j in 0..3 {
                keys[(pair.first + j) as usize] = pair_key(pair.point, j);
            }
        }
        keys
    }
}

/// How a live system's elimination order is chosen (`solver.ordering`).
#[derive(Debug, Clone)]
pub enum OrderingPlan {
    /// faer's AMD on each live pattern.
    Amd,
    /// METIS's nested dissection of each live pattern.
    MetisLiveSet,
    /// The complete dam's nested dissection restricted to each live set.
    Construction(Arc<ConstructionOrdering>),
}

/// One nested dissection for the whole construction: METIS on the graph of
/// the complete dam's unknowns (every element live, every joint pair
/// merged, as [`LiveSystem`] couples them), computed once. A live set is
/// eliminated in the restriction of that order to its own unknowns
/// (relative order kept): the live graph is a subgraph of the complete one
/// (its couplings are the complete graph's between live unknowns, a side-b
/// node of an unpaired point standing in for its pair), and a separator of
/// the complete graph still separates the induced subgraph, so the
/// restriction is a nested dissection of each live set without a METIS
/// call per live set.
#[derive(Debug, Clone)]
pub struct ConstructionOrdering {
    /// position in the complete elimination order of each key (see
    /// [`Numbered::keys`]); NONE for a key with no unknown
    rank: Vec<u32>,
    /// point of each node on side b of a point (NONE otherwise)
    point_of_b: Vec<u32>,
    /// METIS's calls on the complete graph ([`CONSTRUCTION_KNOBS`])
    pub metis_calls: usize,
    /// METIS's seconds on the complete graph, and the symbolic analyses
    /// that chose among its orders
    pub seconds: f64,
}

/// The METIS knobs the construction ordering tries, in turn; it keeps the
/// order whose factor of the complete dam costs the fewest flops (the
/// first of equals). METIS's order is one good nested dissection among
/// many, and which of them fills least is partly chance: over the demo's
/// whole construction (30 Nov 2026) Σ of the numeric factorisations'
/// flops was 1,086 Gflop with METIS's defaults, 1,056, 1,022, 1,063 and
/// 1,014 with 4, 8, 16 and 32 separators a bisection (METIS 0.34, 0.36,
/// 0.47, 0.66 and 1.02 s), 1,025 with an imbalance of 400 and 1,087 with
/// both 8 and 400. The complete dam's factor ranks METIS's defaults, 8
/// and 32 separators as the whole construction does (2.78, 2.69 and 2.66
/// Gflop), and its symbolic analysis costs a fraction of a METIS call. On
/// the Xiaowan-like arch (344,643 unknowns) the three complete factors
/// are 374.9, 370.6 and 368.3 Gflop for METIS calls of 2.3, 7.2 and 27.4
/// s: 32 separators would add 20 s to every run of the large arch for
/// 0.6 % fewer flops, so the construction tries METIS's defaults and 8.
pub const CONSTRUCTION_KNOBS: [MetisKnobs; 2] = [
    MetisKnobs {
        separators: None,
        imbalance: None,
    },
    MetisKnobs {
        separators: Some(8),
        imbalance: None,
    },
];

/// METIS's order of `pattern` under each of [`CONSTRUCTION_KNOBS`], the
/// one whose Cholesky factor costs the fewest flops with the rows `held`
/// held, as the steps factorise it.
fn least_flops_order(pattern: Pattern, held: &[bool]) -> Result<Vec<u32>, LiveError> {
    let pattern = Arc::new(pattern);
    let mut best: Option<(f64, Vec<u32>)> = None;
    for knobs in CONSTRUCTION_KNOBS {
        let fwd = metis_nested_dissection_with(&pattern, knobs)?;
        let ordering = Ordering::Custom(fwd.clone());
        let flops = CholeskySolver::with_held(pattern.clone(), &ordering, faer::Par::Seq, held)?
            .factor_flops();
        if best.as_ref().is_none_or(|(f, _)| flops < *f) {
            best = Some((flops, fwd));
        }
    }
    Ok(best.map(|(_, fwd)| fwd).unwrap_or_default())
}

impl ConstructionOrdering {
    /// METIS on the complete dam of `conn` with all of `points` paired and
    /// the nodes `ties` ties tied, and those `merge` may tie tied too; a
    /// node merging may tie comes just before the first of its masters
    /// (measured in [`super::layer_merging`]). The global node dofs
    /// `supported` are held in every step's factor, so the order is
    /// chosen by the flops of a factor that holds them.
    pub fn new(
        conn: &[[u32; 8]],
        points: &[JointPoint],
        supported: &[bool],
        n_nodes: usize,
        ties: &Ties,
        merge: &LayerMerge,
    ) -> Result<ConstructionOrdering, LiveError> {
        let t = Instant::now();
        let mut point_of_b = vec![NONE; n_nodes];
        for (p, pt) in points.iter().enumerate() {
            point_of_b[pt.b as usize] = p as u32;
        }
        let mut node_used = vec![false; n_nodes];
        conn.iter()
            .flatten()
            .for_each(|&k| node_used[k as usize] = true);
        let pair_live: Vec<bool> = points
            .iter()
            .map(|p| node_used[p.a as usize] && node_used[p.b as usize])
            .collect();
        let all = vec![true; conn.len()];
        let merged = merge.all();
        let ties = ties.with(merged.iter().copied(), n_nodes);
        let elements = ElementSet {
            conn,
            live: &all,
            k_unit: &[],
            ties: &ties,
            rock: None,
        };
        let complete = Numbered::new(elements, points, &pair_live, n_nodes)?;
        let held = reduced_supports(
            complete.n,
            &complete.node_dofs,
            &complete.pairs,
            points,
            supported,
        )?;
        let fwd = least_flops_order(complete.pattern(), &held)?;
        let keys = complete.keys(&point_of_b);
        // even ranks are free for the nodes merging may tie: each is
        // eliminated with the master outside the separator the other is in
        let mut rank = vec![NONE; 3 * (n_nodes + points.len())];
        for (k, &d) in fwd.iter().enumerate() {
            rank[keys[d as usize] as usize] = 2 * k as u32 + 1;
        }
        for &(v, tie) in &merged {
            for c in 0..3 {
                let (lo, hi) = (rank[3 * tie.lo as usize + c], rank[3 * tie.hi as usize + c]);
                rank[3 * v as usize + c] = lo.min(hi) - 1;
            }
        }
        Ok(ConstructionOrdering {
            rank,
            point_of_b,
            metis_calls: CONSTRUCTION_KNOBS.len(),
            seconds: t.elapsed().as_secs_f64(),
        })
    }

    /// The global node dofs of the complete dam of `conn` (all of `points`
    /// paired) whose columns are frozen in this order
    /// ([`super::rock_condensation::frozen_columns`]): `rock_only(node)`
    /// for them and every column below them. In elimination order.
    pub fn frozen(
        &self,
        conn: &[[u32; 8]],
        points: &[JointPoint],
        rock_only: &dyn Fn(usize) -> bool,
    ) -> Result<Vec<u32>, LiveError> {
        let n_nodes = self.point_of_b.len();
        let all = vec![true; conn.len()];
        let pair_live = vec![true; points.len()];
        let elements = ElementSet {
            conn,
            live: &all,
            k_unit: &[],
            ties: &Ties::none(),
            rock: None,
        };
        let complete = Numbered::new(elements, points, &pair_live, n_nodes)?;
        let fwd = self.restrict(&complete, points);
        let global: Vec<u32> = {
            let mut g = vec![NONE; complete.n];
            for &(gd, i) in &complete.node_dofs {
                g[i as usize] = gd;
            }
            g
        };
        let frozen = super::rock_condensation::frozen_columns(&complete.pattern(), &fwd, &|d| {
            global[d] != NONE && rock_only(global[d] as usize / 3)
        });
        Ok(frozen.into_iter().map(|d| global[d as usize]).collect())
    }

    /// The elimination order of a live set (`fwd[k]`: the reduced dof
    /// eliminated k-th): its unknowns in their complete-dam order; one
    /// without a rank (none in a live set of the same mesh) goes last, in
    /// reduced order.
    pub fn restrict(&self, set: &Numbered, points: &[JointPoint]) -> Vec<u32> {
        debug_assert_eq!(self.point_of_b.len(), set.index_of.len() / 3);
        debug_assert!(self.rank.len() == 3 * (self.point_of_b.len() + points.len()));
        let keys = set.keys(&self.point_of_b);
        let mut fwd: Vec<u32> = (0..set.n as u32).collect();
        fwd.sort_unstable_by_key(|&d| (self.rank[keys[d as usize] as usize], d));
        fwd
    }
}

/// The live pairs and the maps to them.
struct LivePairs {
    pairs: Vec<LivePair>,
    /// pair slot of each node on the b side of a live pair (NONE otherwise)
    pair_of_b: Vec<u32>,
    /// pair slot of each joint point (NONE when not live)
    slot_of_point: Vec<u32>,
}

impl LivePairs {
    /// The live pairs in point order, their dofs not numbered yet; a node on
    /// side a of one pair and side b of another is an error.
    fn new(points: &[JointPoint], pair_live: &[bool], n_nodes: usize) -> Result<Self, LiveError> {
        let mut pair_of_b = vec![NONE; n_nodes];
        let mut slot_of_point = vec![NONE; points.len()];
        let mut is_a = vec![false; n_nodes];
        let mut pairs = Vec::new();
        for (p, pt) in points.iter().enumerate() {
            if !pair_live[p] {
                continue;
            }
            pair_of_b[pt.b as usize] = pairs.len() as u32;
            slot_of_point[p] = pairs.len() as u32;
            is_a[pt.a as usize] = true;
            pairs.push(LivePair {
                point: p as u32,
                first: NONE,
            });
        }
        if let Some(node) = (0..n_nodes).find(|&k| is_a[k] && pair_of_b[k] != NONE) {
            return Err(LiveError::ChainedPair { node: node as u32 });
        }
        Ok(LivePairs {
            pairs,
            pair_of_b,
            slot_of_point,
        })
    }
}

/// The reduced dofs numbered so far, in the order the live elements first
/// use them.
struct Numbering {
    /// reduced dof of each global node dof (NONE until numbered)
    index_of: Vec<u32>,
    /// (global dof, reduced dof) of every numbered node dof
    node_dofs: Vec<(u32, u32)>,
    /// dofs numbered so far
    n: u32,
}

impl Numbering {
    /// The reduced dof of global node dof `g`, numbered now if new.
    fn node_dof(&mut self, g: usize) -> u32 {
        if self.index_of[g] == NONE {
            self.index_of[g] = self.n;
            self.node_dofs.push((g as u32, self.n));
            self.n += 1;
        }
        self.index_of[g]
    }

    /// The column block of node `v` among an element's `keys`, its dofs
    /// numbered and pushed when new.
    fn node_block(&mut self, keys: &mut Vec<u32>, v: u32, dofs: &mut Vec<u32>) -> u8 {
        if let Some(col) = keys.iter().position(|&k| k == v) {
            return col as u8;
        }
        keys.push(v);
        for c in 0..3 {
            dofs.push(self.node_dof(3 * v as usize + c));
        }
        (keys.len() - 1) as u8
    }

    /// Numbers the unknowns of one live element: three per ordinary node;
    /// for a node on side b of a live pair, node a's three and the pair's
    /// relative three; for a tied node, its two masters' three each. A node
    /// met twice (a master of two tied nodes, or one of the element's own
    /// nodes) is one column block. Returns the element's reduced dofs and
    /// its T's terms (None: the identity).
    fn element(
        &mut self,
        conn: &[u32; 8],
        links: &Links,
        pairs: &mut [LivePair],
    ) -> (Vec<u32>, Option<Box<[Term]>>) {
        let mut dofs = Vec::with_capacity(24);
        // key of each column block: a node, or n_nodes + pair slot
        let mut keys: Vec<u32> = Vec::with_capacity(8);
        let mut terms = Vec::with_capacity(8);
        let mut plain = true;
        for (k, &node) in conn.iter().enumerate() {
            let k = k as u8;
            if let Some(tie) = links.ties.of(node) {
                plain = false;
                for (m, weight) in tie.masters() {
                    let col = self.node_block(&mut keys, m, &mut dofs);
                    terms.push(Term::Scaled {
                        node: k,
                        col,
                        weight,
                    });
                }
                continue;
            }
            let slot = links.pair_of_b[node as usize];
            if slot == NONE {
                let col = self.node_block(&mut keys, node, &mut dofs);
                terms.push(Term::Scaled {
                    node: k,
                    col,
                    weight: 1.0,
                });
                continue;
            }
            plain = false;
            let a = links.points[pairs[slot as usize].point as usize].a;
            let col = self.node_block(&mut keys, a, &mut dofs);
            terms.push(Term::Scaled {
                node: k,
                col,
                weight: 1.0,
            });
            let pair = &mut pairs[slot as usize];
            if pair.first == NONE {
                pair.first = self.n;
                self.n += 3;
            }
            let first = pair.first;
            let key = links.n_nodes + slot;
            let col = match keys.iter().position(|&k| k == key) {
                Some(col) => col as u8,
                None => {
                    keys.push(key);
                    dofs.extend(first..first + 3);
                    (keys.len() - 1) as u8
                }
            };
            terms.push(Term::Axes {
                node: k,
                col,
                pair: slot,
            });
        }
        (dofs, (!plain).then(|| terms.into_boxed_slice()))
    }
}

/// What a node of a live element may be besides itself: side b of a live
/// pair, or tied.
struct Links<'a> {
    pair_of_b: &'a [u32],
    points: &'a [JointPoint],
    ties: &'a Ties,
    n_nodes: u32,
}

/// Supported reduced dofs: those of supported node dofs, and the relative
/// components the supports of a pair's two nodes fix.
fn reduced_supports(
    n: usize,
    node_dofs: &[(u32, u32)],
    pairs: &[LivePair],
    points: &[JointPoint],
    supported: &[bool],
) -> Result<Vec<bool>, LiveError> {
    let mut supported_r = vec![false; n];
    for &(g, i) in node_dofs {
        supported_r[i as usize] = supported[g as usize];
    }
    // A support of node b in a direction its node a shares and that is
    // one of the pair's local axes (a joint reaching a symmetry plane or
    // a frictionless base) fixes that relative component.
    for pair in pairs {
        let pt = &points[pair.point as usize];
        let axes = [pt.frame.t1, pt.frame.t2, pt.frame.n];
        for c in 0..3 {
            if !supported[3 * pt.b as usize + c] {
                continue;
            }
            let j = (0..3).find(|&j| (axes[j][c].abs() - 1.0).abs() < 1e-12);
            match (supported[3 * pt.a as usize + c], j) {
                (true, Some(j)) => supported_r[pair.first as usize + j] = true,
                _ => return Err(LiveError::SupportedPairNode { node: pt.b }),
            }
        }
    }
    Ok(supported_r)
}

/// T of one element: 24 rows (global node dofs), `m` columns (its reduced
/// dofs), block by block from its terms.
fn transform(terms: &[Term], m: usize, pairs: &[LivePair], points: &[JointPoint]) -> DMatrix<f64> {
    let mut t = DMatrix::zeros(24, m);
    for term in terms {
        let (node, col) = term.blocks();
        match *term {
            Term::Scaled { weight, .. } => {
                for c in 0..3 {
                    t[(3 * node + c, 3 * col + c)] += weight;
                }
            }
            Term::Axes { pair, .. } => {
                let frame = &points[pairs[pair as usize].point as usize].frame;
                // u_b[c] = ũ_a[c] + Σ_j axes[j][c] d_j
                for (j, axis) in [frame.t1, frame.t2, frame.n].iter().enumerate() {
                    for c in 0..3 {
                        t[(3 * node + c, 3 * col + j)] = axis[c];
                    }
                }
            }
        }
    }
    t
}
