//! Old concrete with fewer unknowns: Zhu Bofang's layer merging as a tie
//! (`solver.layer_merging_age_days = A`; 0, the default, is off).
//!
//! # Why
//!
//! A staged dam is meshed lift by lift (one element layer per 3.6 m lift on
//! the Xiaowan-like arch), because each lift is born, heats and cools on
//! its own. Once the concrete is old its displacement is smooth over a
//! grouting zone's height, but every lift level keeps its unknowns, and a
//! factorisation of the near-complete dam is paid every day. Zhu's layer
//! merging replaces old thin layers by thick elements; this module does the
//! same kinematically and keeps every element, Gauss point, stress and
//! creep history as it is.
//!
//! # The tie
//!
//! A vertical grid line of the concrete (local node k of a hex below node
//! k + 4, every element agreeing) keeps the nodes on the elevations of the
//! grouting zones' boundaries (the `z_bottom`, `z_top` of the mesh's
//! zones), its ends, the nodes of the joint faces (the joint points keep
//! their own unknowns and contact states: a line on a joint face keeps all
//! its nodes) and the nodes of rock elements (the foundation); a node
//! between two kept ones (lo below, hi above) may be tied to them, linearly
//! in the distance along the line, as [`super::rock_ties`] ties the rock.
//! A line with a supported node is left as it is. The tie of a segment between two
//! kept nodes is on from the first step whose start finds every element
//! round its tied nodes live and at least A days old; it stays on (ages
//! only grow), so the tied subspaces only shrink and each step stays a
//! Ritz–Galerkin solve: the accumulated state is in equilibrium with
//! the loads on every subspace the run has used since.
//!
//! The lines bend (the arch's overhang: up to 0.06 m off the chord between
//! two zone levels on the demo, 0.48 m on the Xiaowan-like arch), so with
//! merging on the mechanics moves every node it may tie onto that chord
//! from day 0 ([`LayerMerge::straighten`]): then a displacement linear in
//! space (a free thermal expansion, a rigid motion) is one the tie takes
//! exactly (`tests/it/layer_merging.rs`).
//!
//! # What it costs and gives
//!
//! Measured with `examples/rock_condensation.rs` (part 5) on the fill:
//! the Xiaowan-like complete dam with every zone tied off the joints 172.4
//! against 375.9 Gflop per factorisation (tying the joint faces' lines too:
//! 174.5, nothing more); the dam poured to a half, three quarters and all
//! of its height with the top three zones untied, in the construction
//! ordering below, 155.9, 174.1 and 196.8 Gflop against 209.3, 278.2 and
//! 375.9 untied (a METIS call per tied set: 140.3, 168.7, 194.4). The
//! elimination order is METIS's on the complete dam with every tie on,
//! each node that may be tied just before the first of its masters
//! ([`super::live::ConstructionOrdering`]); the untied dam's order
//! restricted to a tied set costs 1.5–4 times as much. Its cost is on the
//! sets still untied: 208.7, 319.6 and 502.6 Gflop against 209.3, 278.2
//! and 375.9, which is why a run whose concrete is mostly young pays for
//! merging instead of gaining (the Xiaowan-like first 150 days,
//! `docs/PERFORMANCE.md`).
//!
//! It is an approximation (stiffer than the untied mesh by the energy the
//! tie removes, and the straightened geometry): its error against the
//! untied run is measured in `tests/it/fast_path.rs` and, with its time,
//! in the README (its opt-in approximations), `docs/PERFORMANCE.md` ("Layer
//! merging") and `groutready study accuracy`.

use crate::mesh::{Mesh, Part};

use super::rock_ties::{ties_along, vertical_lines, vertical_links, Tie};

/// The ties layer merging may switch on, by segment.
#[derive(Debug, Clone, Default)]
pub struct LayerMerge {
    /// per node: its tie when it lies between two kept nodes of a line
    tie: Vec<Option<Tie>>,
    /// the segments: their tied nodes and the elements round them
    segments: Vec<Segment>,
    /// days every element round a segment must have been live
    age_days: f64,
}

#[derive(Debug, Clone)]
struct Segment {
    nodes: Vec<u32>,
    elements: Vec<u32>,
}

impl LayerMerge {
    /// The ties of `mesh` for merging after `age_days` (none when 0 or the
    /// mesh has no grouting zones); `supported[3v + c]` marks fixed dofs.
    pub fn build(mesh: &Mesh, supported: &[bool], age_days: u32) -> LayerMerge {
        let nn = mesh.nodes.len();
        let mut levels: Vec<f64> = mesh
            .zones
            .iter()
            .flat_map(|z| [z.z_bottom, z.z_top])
            .collect();
        if age_days == 0 || levels.is_empty() {
            return LayerMerge::default();
        }
        levels.sort_by(f64::total_cmp);
        levels.dedup();
        let on_level = |z: f64| {
            let i = levels.partition_point(|&l| l < z - LEVEL_TOLERANCE);
            i < levels.len() && (levels[i] - z).abs() <= LEVEL_TOLERANCE
        };
        let mut kept = vec![false; nn];
        for p in &mesh.face_pairs {
            for k in 0..4 {
                kept[p.nodes_a[k] as usize] = true;
                kept[p.nodes_b[k] as usize] = true;
            }
        }
        let mut elements_of: Vec<Vec<u32>> = vec![Vec::new(); nn];
        for (e, conn) in mesh.elements.iter().enumerate() {
            for &v in conn {
                if mesh.parts[e] == Part::Rock {
                    kept[v as usize] = true;
                }
                elements_of[v as usize].push(e as u32);
            }
        }
        let held = |v: u32| {
            supported[3 * v as usize..3 * v as usize + 3]
                .iter()
                .any(|&s| s)
        };
        let concrete = |e: usize| mesh.parts[e] != Part::Rock;
        let (above, below) = vertical_links(&mesh.elements, &mesh.nodes, &concrete);
        let mut merge = LayerMerge {
            tie: vec![None; nn],
            segments: Vec::new(),
            age_days: age_days as f64,
        };
        for line in vertical_lines(&above, &below) {
            // a tied node's supports would be its masters' (none in the concrete)
            if line.iter().any(|&v| held(v)) {
                continue;
            }
            let keep: Vec<bool> = (0..line.len())
                .map(|k| {
                    let v = line[k];
                    k == 0
                        || k + 1 == line.len()
                        || kept[v as usize]
                        || on_level(mesh.nodes[v as usize][2])
                })
                .collect();
            merge.tie_line(&line, &keep, &mesh.nodes, &elements_of);
        }
        merge
    }

    /// Ties the nodes of `line` between its kept ones ([`ties_along`]), one
    /// segment per pair of consecutive kept nodes with nodes between.
    fn tie_line(
        &mut self,
        line: &[u32],
        keep: &[bool],
        nodes: &[[f64; 3]],
        elements_of: &[Vec<u32>],
    ) {
        let ties = ties_along(line, keep, nodes);
        for chunk in ties.chunk_by(|a, b| a.1.lo == b.1.lo) {
            let tied: Vec<u32> = chunk.iter().map(|&(v, _)| v).collect();
            let mut elements: Vec<u32> = tied
                .iter()
                .flat_map(|&v| elements_of[v as usize].iter().copied())
                .collect();
            elements.sort_unstable();
            elements.dedup();
            for &(v, tie) in chunk {
                self.tie[v as usize] = Some(tie);
            }
            self.segments.push(Segment {
                nodes: tied,
                elements,
            });
        }
    }

    /// Whether any node may be tied.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// The tie `node` takes once merged, if it may be.
    pub fn tie_of(&self, node: u32) -> Option<Tie> {
        self.tie.get(node as usize).copied().flatten()
    }

    /// Every tie merging may switch on, by node.
    pub fn all(&self) -> Vec<(u32, Tie)> {
        (0..self.tie.len() as u32)
            .filter_map(|v| self.tie_of(v).map(|t| (v, t)))
            .collect()
    }

    /// The nodes tied at a step starting on day `t0`: those of the segments
    /// whose elements are all live (`live`) and born (`birth`) at least the
    /// merging age before `t0`. Sorted.
    pub fn tied_at(&self, live: &[bool], birth: &[f64], t0: f64) -> Vec<u32> {
        let old = |e: u32| live[e as usize] && t0 - birth[e as usize] >= self.age_days;
        let mut nodes: Vec<u32> = self
            .segments
            .iter()
            .filter(|s| s.elements.iter().all(|&e| old(e)))
            .flat_map(|s| s.nodes.iter().copied())
            .collect();
        nodes.sort_unstable();
        nodes
    }

    /// Moves each node that may be tied onto the chord between its
    /// masters, where its weight puts it (module doc).
    pub fn straighten(&self, nodes: &mut [[f64; 3]]) {
        for v in 0..self.tie.len() {
            if let Some(t) = self.tie[v] {
                let (lo, hi) = (nodes[t.lo as usize], nodes[t.hi as usize]);
                nodes[v] = std::array::from_fn(|k| (1.0 - t.w) * lo[k] + t.w * hi[k]);
            }
        }
    }
}

/// A node is on a zone boundary's elevation within this \[m\].
const LEVEL_TOLERANCE: f64 = 1e-6;
