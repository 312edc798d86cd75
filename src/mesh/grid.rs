//! Shared builder: a structured logical grid of classified cells → [`Mesh`].
//!
//! Both generators describe their grid as a [`BlockRow`] (cell counts: a row
//! of blocks inside a rock margin on rock layers) and hand over the node
//! positions and the concrete [`Layers`]; the row classifies every cell.
//! Node (i, j, k) has index `i + (ni+1)·(j + (nj+1)·k)`, cell (i, j, k)
//! `i + ni·(j + nj·k)`. Cells are void, rock, or concrete of (block, global
//! layer). Joint duplication, face pairs, zones, zone points, surfaces and
//! thermal dofs all follow from the classification, one step each (see the
//! module docs of [`super`]).

use std::collections::HashMap;
use std::sync::OnceLock;

use crate::fem::quad4;

use crate::vocab::ZonePoint;

use super::{BlockInfo, FacePair, Mesh, MeshError, Part, SurfaceFace, SurfaceKind, Zone, ZoneSite};

/// Largest node/element count a mesh may have (indices are `u32`).
pub(crate) const MAX_ENTITIES: u64 = u32::MAX as u64 / 2;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cell {
    Void,
    Rock,
    Concrete { block: u32, layer: u32 },
}

/// The logical grid both generators lay out: a row of `n_blocks` blocks along
/// i (`elements_per_block` cells each), `elements_across` cells thick along
/// j, inside margins of rock cells (a count per side), on `rock_layers`
/// layers of rock with `layers` concrete layers above them along k.
pub(crate) struct BlockRow {
    pub n_blocks: u32,
    pub elements_per_block: u32,
    pub elements_across: u32,
    /// Cells beyond the blocks per side (0: no margin there).
    pub margin: Margins,
    /// Rock cell layers below the lowest concrete layer.
    pub rock_layers: usize,
    /// Concrete element layers of the dam.
    pub layers: u64,
    /// Rock fills the margins beyond the abutments up to the crest (the arch's
    /// valley sides); without it they are rock only below the concrete.
    pub rock_beyond_abutments: bool,
}

/// Rock cells beyond the blocks on each side of a [`BlockRow`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Margins {
    /// Beyond the left abutment (low i).
    pub left: usize,
    /// Beyond the right abutment (high i).
    pub right: usize,
    /// Upstream (low j).
    pub upstream: usize,
    /// Downstream (high j).
    pub downstream: usize,
}

/// How the rock cells of one margin (or of the layers below the dam) are
/// spaced: `count` cells over `length` metres, from the dam outwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Spacing {
    pub count: usize,
    pub length: f64,
    /// Ratio of neighbouring cells' sizes, the outer over the inner
    /// (1 = uniform, the only case [`Spacing::graded`] does not make).
    pub ratio: f64,
}

impl Spacing {
    /// Uniform cells: `count` over `length`.
    pub fn uniform(count: usize, length: f64) -> Spacing {
        Spacing {
            count,
            length,
            ratio: 1.0,
        }
    }

    /// Geometric cells growing by `ratio` (> 1) away from the dam, over
    /// exactly `length`: the count is the least whose first cell,
    /// s = length·(r − 1)/(rⁿ − 1), is no larger than `first` (the size of
    /// the concrete cell it touches), so s ∈ (first/r, first]. `length <=
    /// first` gives one cell. The count is capped at 10,000 (a ratio of
    /// 1.001 on a 1 km margin of 0.1 m cells would be 4,000), so the size
    /// check of [`BlockRow::size`] sees any absurd request.
    pub fn graded(length: f64, first: f64, ratio: f64) -> Spacing {
        let n = if length <= first {
            1.0
        } else {
            ((1.0 + length * (ratio - 1.0) / first).ln() / ratio.ln()).ceil()
        };
        let mut count = (n.max(1.0) as usize).min(10_000);
        // ceil of a quotient that is a whole number up to round-off
        while count > 1 && length * (ratio - 1.0) / (ratio.powi(count as i32 - 1) - 1.0) <= first {
            count -= 1;
        }
        Spacing {
            count,
            length,
            ratio,
        }
    }

    /// Distance from the dam of the cell boundary `k` (0 at the dam, `count`
    /// at the far edge, which is exactly `length` when graded).
    pub fn distance(&self, k: usize) -> f64 {
        // uniform first: the expression of the first version, bit for bit
        if self.ratio == 1.0 {
            return self.length * k as f64 / self.count as f64;
        }
        if k >= self.count {
            return self.length;
        }
        let r = self.ratio;
        self.length * (r.powi(k as i32) - 1.0) / (r.powi(self.count as i32) - 1.0)
    }
}

/// Where the `n + 1` grid lines over a segment `t` long lie, as fractions
/// 0 = a₀ < … < aₙ = 1: across a section from its upstream face
/// (`face_element_m`), or along a block from its left joint
/// (`joint_element_m`).
///
/// Without `face` (or where `n·face ≥ t`, or `n ≤ 2`) the cells are equal:
/// aⱼ = j/n, by the expression of the first version. With it, the cells at
/// both ends are `face` long and grow by one ratio r ≥ 1 towards the
/// middle, cell i being face·r^min(i, n−1−i); r is the root of
/// Σᵢ face·r^min(i, n−1−i) = t (the sum rises with r, so bisection finds
/// it to round-off). Across a section, the faces' grid lines then lie
/// exactly `face` in from each face at every elevation, whatever the
/// thickness there: with `face` the grout stops' inset, the zone minimum
/// is read on node rows ([`crate::mechanics::grout_stops`]).
pub(crate) fn graded_fractions(n: usize, t: f64, face: Option<f64>) -> Vec<f64> {
    let uniform = || (0..=n).map(|j| j as f64 / n as f64).collect();
    let Some(s) = face else {
        return uniform();
    };
    if n <= 2 || n as f64 * s >= t {
        return uniform();
    }
    let sizes = |r: f64| (0..n).map(move |i| s * r.powi(i.min(n - 1 - i) as i32));
    let total = |r: f64| sizes(r).sum::<f64>();
    let (mut lo, mut hi) = (1.0_f64, 2.0_f64);
    while total(hi) < t {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if total(mid) < t {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = 0.5 * (lo + hi);
    // Built from both faces towards the middle, so each face's first line
    // is `face` in to round-off; an odd n's middle cell takes the rest.
    let mut a = vec![0.0; n + 1];
    let (mut up, mut down) = (0.0, 0.0);
    for (i, c) in sizes(r).enumerate().take(n / 2) {
        up += c;
        down += c;
        a[i + 1] = up / t;
        a[n - 1 - i] = 1.0 - down / t;
    }
    a[n] = 1.0;
    a
}

/// The concrete layers and lifts a generator chose for its [`BlockRow`].
pub(crate) struct Layers {
    /// Elevations of the concrete layer boundaries, `layers + 1` of them.
    pub z: Vec<f64>,
    pub lift_height: f64,
    pub zone_lifts: u32,
    pub per_lift: u32,
    /// Per block (index block − 1): (base layer, lifts). Rock fills the
    /// block's column below its base layer.
    pub blocks: Vec<(u32, u32)>,
}

/// A classified logical grid: what [`build`] turns into a mesh.
struct Grid {
    ni: usize,
    nj: usize,
    nk: usize,
    /// Node positions, `(ni+1)(nj+1)(nk+1)`.
    pos: Vec<[f64; 3]>,
    /// Cell classes, `ni·nj·nk`.
    cells: Vec<Cell>,
    /// Concrete cells across are `j ∈ [j0, j1)`; cells with `j < j0` are upstream.
    j0: usize,
    j1: usize,
    layers: Layers,
}

/// Check that a grid of this size can be indexed; call before allocating it.
fn check_size(ni: usize, nj: usize, nk: usize) -> Result<(), MeshError> {
    let nodes = (ni as u64 + 1)
        .saturating_mul(nj as u64 + 1)
        .saturating_mul(nk as u64 + 1);
    let elements = (ni as u64)
        .saturating_mul(nj as u64)
        .saturating_mul(nk as u64);
    // Duplicated joint nodes at most double the node count.
    if nodes.saturating_mul(2) > MAX_ENTITIES || elements > MAX_ENTITIES {
        return Err(MeshError::TooLarge {
            nodes,
            elements,
            limit: MAX_ENTITIES,
        });
    }
    // the mesh's own share of a simulation, before anything is allocated
    let needed = crate::machine::simulation_memory_lower_bound(elements, nodes, false, false);
    if let Some(total) = crate::machine::total_memory_bytes().filter(|&t| needed > t) {
        return Err(MeshError::TooMuchMemory {
            nodes,
            elements,
            needed_gib: crate::machine::gib(needed),
            total_gib: crate::machine::gib(total),
        });
    }
    Ok(())
}

/// An inconsistency the generators must never produce.
fn bug(m: String) -> MeshError {
    MeshError::Invalid(format!("generator: {m}"))
}

impl BlockRow {
    /// Cells along i, j and k; checked before anything of that size is
    /// allocated (a count beyond `u32`, or more nodes or elements than
    /// [`MAX_ENTITIES`], is [`MeshError::TooLarge`]).
    pub fn size(&self) -> Result<(usize, usize, usize), MeshError> {
        let m = self.margin;
        let ni = (self.n_blocks as u64)
            .saturating_mul(self.elements_per_block as u64)
            .saturating_add(m.left as u64)
            .saturating_add(m.right as u64);
        let nj = (self.elements_across as u64)
            .saturating_add(m.upstream as u64)
            .saturating_add(m.downstream as u64);
        let nk = self.layers.saturating_add(self.rock_layers as u64);
        if [ni, nj, nk].iter().any(|&s| s > u32::MAX as u64) {
            return Err(MeshError::TooLarge {
                nodes: u64::MAX,
                elements: u64::MAX,
                limit: MAX_ENTITIES,
            });
        }
        let (ni, nj, nk) = (ni as usize, nj as usize, nk as usize);
        check_size(ni, nj, nk)?;
        Ok((ni, nj, nk))
    }

    /// Elevations of the logical levels k: `rock_layers` layers over
    /// `rock_depth` below `base` (equal ones, or graded by `below` when it
    /// is not uniform), then the concrete layer boundaries `layer_z`.
    pub fn level_z(&self, base: f64, rock_depth: f64, below: Spacing, layer_z: &[f64]) -> Vec<f64> {
        let rl = self.rock_layers;
        (0..rl + layer_z.len())
            .map(|k| {
                if k < rl && below.ratio != 1.0 {
                    base - below.distance(rl - k)
                } else if k < rl {
                    base - rock_depth + rock_depth * k as f64 / rl as f64
                } else {
                    layer_z[k - rl]
                }
            })
            .collect()
    }

    /// What cell (i, j, k) is made of: rock below the concrete layers and
    /// under each block's base layer, concrete of the block in the columns
    /// across the dam, void elsewhere (and beyond the abutments unless
    /// [`BlockRow::rock_beyond_abutments`]).
    fn cell(&self, i: usize, j: usize, k: usize, blocks: &[(u32, u32)]) -> Cell {
        let (m, rl) = (self.margin, self.rock_layers);
        let epb = self.elements_per_block as usize;
        if k < rl {
            return Cell::Rock;
        }
        if i < m.left || i >= m.left + self.n_blocks as usize * epb {
            return if self.rock_beyond_abutments {
                Cell::Rock
            } else {
                Cell::Void
            };
        }
        let layer = (k - rl) as u32;
        let b = (i - m.left) / epb;
        if layer < blocks[b].0 {
            Cell::Rock
        } else if j >= m.upstream && j < m.upstream + self.elements_across as usize {
            Cell::Concrete {
                block: b as u32 + 1,
                layer,
            }
        } else {
            Cell::Void
        }
    }

    /// Classify the cells and build the validated mesh on the node positions
    /// `pos` (`(ni+1)(nj+1)(nk+1)`, i fastest, then j, then k).
    pub fn build(&self, pos: Vec<[f64; 3]>, layers: Layers) -> Result<Mesh, MeshError> {
        let (ni, nj, nk) = self.size()?;
        let mut cells = Vec::with_capacity(ni * nj * nk);
        for k in 0..nk {
            for j in 0..nj {
                for i in 0..ni {
                    cells.push(self.cell(i, j, k, &layers.blocks));
                }
            }
        }
        build(Grid {
            ni,
            nj,
            nk,
            pos,
            cells,
            j0: self.margin.upstream,
            j1: self.margin.upstream + self.elements_across as usize,
            layers,
        })
    }
}

/// Which logical nodes become mesh nodes, and which of them get two copies.
struct NodeClasses {
    used: Vec<bool>,
    dup: Vec<bool>,
}

/// Mesh nodes of the used logical nodes: copy A of each, copy B of the joint
/// nodes, both copies on one thermal dof.
struct Numbering {
    id_a: Vec<u32>,
    id_b: Vec<u32>,
    nodes: Vec<[f64; 3]>,
    thermal_dof: Vec<u32>,
    n_dofs: u32,
}

/// One hex element per non-void cell, in cell order.
struct Elements {
    elements: Vec<[u32; 8]>,
    parts: Vec<Part>,
    /// Cell → element (`u32::MAX` for void cells).
    cell_elem: Vec<u32>,
}

/// Face pair of (joint, global layer, cell across j), for the zone points.
type PairAt = HashMap<(u32, u32, usize), u32>;

/// Build the mesh and validate it. Each step reads the cell classes and what
/// the steps before it made: nodes, elements, face pairs, zones and their
/// points, surfaces.
fn build(g: Grid) -> Result<Mesh, MeshError> {
    debug_assert_eq!(g.pos.len(), (g.ni + 1) * (g.nj + 1) * (g.nk + 1));
    debug_assert_eq!(g.cells.len(), g.ni * g.nj * g.nk);
    let numbering = g.number_nodes(&g.classify_nodes()?);
    let el = g.elements(&numbering)?;
    let (face_pairs, pair_at) = g.face_pairs(&el)?;
    let zones = g.zones(&face_pairs);
    let zone_points = g.zone_points(&zones, &face_pairs, &pair_at, &numbering.nodes)?;
    let surfaces = g.surfaces(&el.cell_elem);
    let blocks = g.block_infos();
    let layers = g.layers;
    let mesh = Mesh {
        nodes: numbering.nodes,
        elements: el.elements,
        parts: el.parts,
        thermal_dof: numbering.thermal_dof,
        n_thermal_dofs: numbering.n_dofs as usize,
        crest_z: *layers.z.last().unwrap_or(&0.0),
        layer_z: layers.z,
        lift_height: layers.lift_height,
        zone_lifts: layers.zone_lifts,
        layers_per_lift: layers.per_lift,
        blocks,
        face_pairs,
        zones,
        zone_points,
        surfaces,
        upstream_normal_hint: [0.0, -1.0, 0.0],
        index: OnceLock::new(),
    };
    mesh.validate()?;
    Ok(mesh)
}

impl Grid {
    fn node(&self, i: usize, j: usize, k: usize) -> usize {
        i + (self.ni + 1) * (j + (self.nj + 1) * k)
    }
    fn cell_index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.ni * (j + self.nj * k)
    }
    fn cell(&self, i: isize, j: isize, k: isize) -> Cell {
        if i < 0 || j < 0 || k < 0 {
            return Cell::Void;
        }
        let (i, j, k) = (i as usize, j as usize, k as usize);
        if i >= self.ni || j >= self.nj || k >= self.nk {
            return Cell::Void;
        }
        self.cells[self.cell_index(i, j, k)]
    }
    fn inside(&self, i: isize, j: isize, k: isize) -> bool {
        i >= 0
            && j >= 0
            && k >= 0
            && (i as usize) < self.ni
            && (j as usize) < self.nj
            && (k as usize) < self.nk
    }
    /// Global layers per zone.
    fn zone_layers(&self) -> usize {
        (self.layers.zone_lifts as u64 * self.layers.per_lift as u64).min(u32::MAX as u64) as usize
    }
    /// Global layers `[first, end)` of zone `zone` (1-based), clipped at the crest.
    fn zone_band(&self, zone: u32) -> (usize, usize) {
        let zone_layers = self.zone_layers();
        let n_layers = self.layers.z.len() - 1;
        let first = (zone as usize - 1) * zone_layers;
        (first, (zone as usize * zone_layers).min(n_layers))
    }

    /// Step 1: every node a non-void cell touches is used; a node where two
    /// blocks meet away from rock is a joint node and gets two copies.
    fn classify_nodes(&self) -> Result<NodeClasses, MeshError> {
        let nn = (self.ni + 1) * (self.nj + 1) * (self.nk + 1);
        let mut used = vec![false; nn];
        let mut dup = vec![false; nn];
        for k in 0..=self.nk {
            for j in 0..=self.nj {
                for i in 0..=self.ni {
                    let n = self.node(i, j, k);
                    (used[n], dup[n]) = self.node_class(i, j, k)?;
                }
            }
        }
        Ok(NodeClasses { used, dup })
    }

    /// (used, duplicated) of node (i, j, k) from its eight cells. The cells on
    /// its low-i side must belong to one block, those on its high-i side to
    /// that block or the next.
    fn node_class(&self, i: usize, j: usize, k: usize) -> Result<(bool, bool), MeshError> {
        let mut any = false;
        let mut rock = false;
        let mut left: Option<u32> = None;
        let mut right: Option<u32> = None;
        for dk in 0..2isize {
            for dj in 0..2isize {
                for di in 0..2isize {
                    let c = self.cell(
                        i as isize - 1 + di,
                        j as isize - 1 + dj,
                        k as isize - 1 + dk,
                    );
                    match c {
                        Cell::Void => {}
                        Cell::Rock => {
                            any = true;
                            rock = true;
                        }
                        Cell::Concrete { block, .. } => {
                            any = true;
                            let side = if di == 0 { &mut left } else { &mut right };
                            match *side {
                                None => *side = Some(block),
                                Some(b) if b == block => {}
                                Some(_) => {
                                    return Err(bug(format!(
                                        "two blocks on one side of node ({i},{j},{k})"
                                    )))
                                }
                            }
                        }
                    }
                }
            }
        }
        let mut dup = false;
        if let (Some(l), Some(r)) = (left, right) {
            if l != r {
                if r != l + 1 {
                    return Err(bug(format!(
                        "blocks {l} and {r} meet at node ({i},{j},{k})"
                    )));
                }
                dup = !rock;
            }
        }
        Ok((any, dup))
    }

    /// Step 2: mesh nodes in logical order, copy B right after copy A.
    fn number_nodes(&self, classes: &NodeClasses) -> Numbering {
        let nn = classes.used.len();
        let mut id_a = vec![u32::MAX; nn];
        let mut id_b = vec![u32::MAX; nn];
        let mut nodes = Vec::new();
        let mut thermal_dof = Vec::new();
        let mut n_dofs: u32 = 0;
        for n in 0..nn {
            if !classes.used[n] {
                continue;
            }
            id_a[n] = nodes.len() as u32;
            nodes.push(self.pos[n]);
            thermal_dof.push(n_dofs);
            id_b[n] = id_a[n];
            if classes.dup[n] {
                id_b[n] = nodes.len() as u32;
                nodes.push(self.pos[n]);
                thermal_dof.push(n_dofs);
            }
            n_dofs += 1;
        }
        Numbering {
            id_a,
            id_b,
            nodes,
            thermal_dof,
            n_dofs,
        }
    }

    /// Step 3: one hex per non-void cell, corners in VTK order; the corners on
    /// the cell's low-i side take copy B, so block j + 1 sits on the copies.
    fn elements(&self, ids: &Numbering) -> Result<Elements, MeshError> {
        let mut elements: Vec<[u32; 8]> = Vec::new();
        let mut parts: Vec<Part> = Vec::new();
        let mut cell_elem = vec![u32::MAX; self.ni * self.nj * self.nk];
        for k in 0..self.nk {
            for j in 0..self.nj {
                for i in 0..self.ni {
                    let Some(part) = self.part(self.cells[self.cell_index(i, j, k)])? else {
                        continue;
                    };
                    let corner = |di: usize, dj: usize, dk: usize| {
                        let n = self.node(i + di, j + dj, k + dk);
                        if di == 0 {
                            ids.id_b[n]
                        } else {
                            ids.id_a[n]
                        }
                    };
                    cell_elem[self.cell_index(i, j, k)] = elements.len() as u32;
                    elements.push([
                        corner(0, 0, 0),
                        corner(1, 0, 0),
                        corner(1, 1, 0),
                        corner(0, 1, 0),
                        corner(0, 0, 1),
                        corner(1, 0, 1),
                        corner(1, 1, 1),
                        corner(0, 1, 1),
                    ]);
                    parts.push(part);
                }
            }
        }
        Ok(Elements {
            elements,
            parts,
            cell_elem,
        })
    }

    /// The part of a cell's element (`None` for void); a concrete layer's
    /// lift counts from its block's base layer.
    fn part(&self, c: Cell) -> Result<Option<Part>, MeshError> {
        Ok(match c {
            Cell::Void => None,
            Cell::Rock => Some(Part::Rock),
            Cell::Concrete { block, layer } => {
                let lpl = self.layers.per_lift;
                let (base, n_lifts) = *self
                    .layers
                    .blocks
                    .get((block as usize).wrapping_sub(1))
                    .ok_or_else(|| bug(format!("unknown block {block}")))?;
                if layer < base || (layer - base) / lpl >= n_lifts {
                    return Err(bug(format!("layer {layer} outside block {block}")));
                }
                Some(Part::Concrete {
                    block,
                    lift: (layer - base) / lpl + 1,
                })
            }
        })
    }

    /// Step 4: a face pair wherever concrete cells of two neighbouring blocks
    /// touch along i, sorted by (joint, layer, j).
    fn face_pairs(&self, el: &Elements) -> Result<(Vec<FacePair>, PairAt), MeshError> {
        let zone_layers = self.zone_layers();
        let mut keyed: Vec<(u32, u32, usize, u32, u32)> = Vec::new(); // joint, layer, j, ea, eb
        for k in 0..self.nk {
            for j in 0..self.nj {
                for i in 1..self.ni {
                    let l = self.cells[self.cell_index(i - 1, j, k)];
                    let r = self.cells[self.cell_index(i, j, k)];
                    if let (
                        Cell::Concrete { block: bl, layer },
                        Cell::Concrete {
                            block: br,
                            layer: lr,
                        },
                    ) = (l, r)
                    {
                        if bl == br {
                            continue;
                        }
                        if br != bl + 1 || layer != lr {
                            return Err(bug(format!("bad joint face at cell ({i},{j},{k})")));
                        }
                        keyed.push((
                            bl,
                            layer,
                            j,
                            el.cell_elem[self.cell_index(i - 1, j, k)],
                            el.cell_elem[self.cell_index(i, j, k)],
                        ));
                    }
                }
            }
        }
        keyed.sort_unstable_by_key(|x| (x.0, x.1, x.2));
        let mut face_pairs = Vec::with_capacity(keyed.len());
        let mut pair_at: PairAt = HashMap::new();
        for &(joint, layer, j, ea, eb) in &keyed {
            let a = el.elements[ea as usize];
            let b = el.elements[eb as usize];
            pair_at.insert((joint, layer, j), face_pairs.len() as u32);
            face_pairs.push(FacePair {
                joint,
                zone: layer / zone_layers as u32 + 1,
                layer,
                elem_a: ea,
                elem_b: eb,
                nodes_a: [a[1], a[2], a[6], a[5]],
                nodes_b: [b[0], b[3], b[7], b[4]],
            });
        }
        Ok((face_pairs, pair_at))
    }

    /// Step 5: a zone per run of face pairs of one (joint, zone), its
    /// elevations those of the whole band.
    fn zones(&self, face_pairs: &[FacePair]) -> Vec<Zone> {
        let mut zones: Vec<Zone> = Vec::new();
        for (p, fp) in face_pairs.iter().enumerate() {
            match zones.last_mut() {
                Some(z) if z.joint == fp.joint && z.zone == fp.zone => z.pairs.push(p as u32),
                _ => {
                    let (first, end) = self.zone_band(fp.zone);
                    zones.push(Zone {
                        joint: fp.joint,
                        zone: fp.zone,
                        z_bottom: self.layers.z[first],
                        z_top: self.layers.z[end],
                        pairs: vec![p as u32],
                    });
                }
            }
        }
        zones
    }

    /// Step 6: the upstream, centre and downstream point of every zone at its
    /// mid height, on the face pair that holds it (see the module docs of
    /// [`super`] for which pair gets a point on an element edge).
    fn zone_points(
        &self,
        zones: &[Zone],
        face_pairs: &[FacePair],
        pair_at: &PairAt,
        nodes: &[[f64; 3]],
    ) -> Result<Vec<ZoneSite>, MeshError> {
        let n_across = self.j1 - self.j0;
        let center = if n_across % 2 == 1 {
            (self.j0 + n_across / 2, 0.0)
        } else {
            (self.j0 + n_across / 2 - 1, 1.0)
        };
        let mut zone_points = Vec::with_capacity(zones.len() * 3);
        for z in zones {
            let (layer, t) = self.mid_height(z);
            for (point, (j, s)) in [
                (ZonePoint::Upstream, (self.j0, -1.0)),
                (ZonePoint::Center, center),
                (ZonePoint::Downstream, (self.j1 - 1, 1.0)),
            ] {
                let pair = *pair_at.get(&(z.joint, layer as u32, j)).ok_or_else(|| {
                    bug(format!(
                        "no face pair for joint {} zone {} at layer {layer}, across {j}",
                        z.joint, z.zone
                    ))
                })?;
                let corners = face_pairs[pair as usize].nodes_a.map(|n| nodes[n as usize]);
                zone_points.push(ZoneSite {
                    joint: z.joint,
                    zone: z.zone,
                    point,
                    pair,
                    s,
                    t,
                    xyz: quad4::point(&corners, [s, t]),
                });
            }
        }
        Ok(zone_points)
    }

    /// The layer holding a zone's mid height (the lower one when it falls on a
    /// layer boundary) and the height there as t ∈ [−1, 1].
    fn mid_height(&self, z: &Zone) -> (usize, f64) {
        let zm = 0.5 * (z.z_bottom + z.z_top);
        let (first, end) = self.zone_band(z.zone);
        let scale = 1e-12 * (1.0 + zm.abs());
        let layer_z = &self.layers.z;
        let layer = (first..end)
            .find(|&l| layer_z[l + 1] >= zm - scale)
            .unwrap_or(end - 1);
        let (z0, z1) = (layer_z[layer], layer_z[layer + 1]);
        (layer, (2.0 * (zm - z0) / (z1 - z0) - 1.0).clamp(-1.0, 1.0))
    }

    /// Step 7: every face of a non-void cell that borders void or the edge of
    /// the grid is on the outer boundary of the complete mesh.
    fn surfaces(&self, cell_elem: &[u32]) -> Vec<SurfaceFace> {
        // Neighbour offsets in the order of the hex8 local faces.
        const DIRS: [(isize, isize, isize); 6] = [
            (0, 0, -1),
            (0, 0, 1),
            (0, -1, 0),
            (1, 0, 0),
            (0, 1, 0),
            (-1, 0, 0),
        ];
        let mut surfaces = Vec::new();
        for k in 0..self.nk {
            for j in 0..self.nj {
                for i in 0..self.ni {
                    let c = self.cells[self.cell_index(i, j, k)];
                    if c == Cell::Void {
                        continue;
                    }
                    let elem = cell_elem[self.cell_index(i, j, k)];
                    for (face, &(di, dj, dk)) in DIRS.iter().enumerate() {
                        let (a, b, cc) = (i as isize + di, j as isize + dj, k as isize + dk);
                        if self.cell(a, b, cc) != Cell::Void {
                            continue;
                        }
                        surfaces.push(SurfaceFace {
                            elem,
                            face: face as u8,
                            kind: self.surface_kind(c, j, face, !self.inside(a, b, cc)),
                        });
                    }
                }
            }
        }
        surfaces
    }

    /// Boundary family of local face `face` of a cell of class `c` in column
    /// `j`; `outside` when the face is on the edge of the grid.
    fn surface_kind(&self, c: Cell, j: usize, face: usize, outside: bool) -> SurfaceKind {
        match c {
            Cell::Rock => {
                if outside && face != 1 {
                    SurfaceKind::Far
                } else if j < self.j0 {
                    SurfaceKind::Wet
                } else {
                    SurfaceKind::Ground
                }
            }
            _ => {
                if outside && face == 0 {
                    SurfaceKind::Far
                } else if face == 2 {
                    SurfaceKind::Wet
                } else {
                    SurfaceKind::Ground
                }
            }
        }
    }

    fn block_infos(&self) -> Vec<BlockInfo> {
        super::block_infos(&self.layers.blocks, &self.layers.z)
    }
}

/// `rock_grading_ratio` in [1, 3]: 1 is uniform rock, above 3 the cells
/// grow too fast for the rock's stresses and temperatures to be resolved.
pub(crate) fn grading_ratio(r: f64) -> Result<(), MeshError> {
    if !(r.is_finite() && (1.0..=3.0).contains(&r)) {
        return Err(MeshError::param(
            "rock_grading_ratio",
            format!("must be in [1, 3] (1 = uniform rock), got {r}"),
        ));
    }
    Ok(())
}

/// `face_element_m` or `joint_element_m` (`key`), where given: finite and > 0.
pub(crate) fn end_element(key: &str, size: Option<f64>) -> Result<(), MeshError> {
    match size {
        Some(s) if !(s.is_finite() && s > 0.0) => {
            Err(MeshError::param(key, format!("must be > 0, got {s}")))
        }
        _ => Ok(()),
    }
}

/// Lifts per zone from the two heights; the error names `zone_height_m`.
pub(crate) fn zone_lifts(lift_height: f64, zone_height: f64) -> Result<u32, MeshError> {
    if !(lift_height.is_finite() && lift_height > 0.0) {
        return Err(MeshError::param(
            "lift_height_m",
            format!("must be > 0, got {lift_height}"),
        ));
    }
    if !(zone_height.is_finite() && zone_height > 0.0) {
        return Err(MeshError::param(
            "zone_height_m",
            format!("must be > 0, got {zone_height}"),
        ));
    }
    let r = zone_height / lift_height;
    let n = r.round();
    if n < 1.0 || (r - n).abs() > 1e-9 * r.max(1.0) || n > u32::MAX as f64 / 4.0 {
        return Err(MeshError::param(
            "zone_height_m",
            format!(
                "must be a whole number of lifts (lift height {lift_height} m), got {zone_height}"
            ),
        ));
    }
    Ok(n as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graded_fractions_uniform_without_a_face_element() {
        let a = graded_fractions(3, 20.0, None);
        assert_eq!(a, vec![0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]);
        // too thin for graded cells, or too few of them: uniform
        assert_eq!(
            graded_fractions(4, 3.0, Some(1.0)),
            graded_fractions(4, 3.0, None)
        );
        assert_eq!(
            graded_fractions(2, 30.0, Some(1.0)),
            graded_fractions(2, 30.0, None)
        );
    }

    #[test]
    fn graded_fractions_graded_from_both_faces() {
        for (n, t) in [(8, 35.0), (7, 24.0), (5, 8.0), (10, 24.0)] {
            let a = graded_fractions(n, t, Some(1.0));
            assert_eq!(a.len(), n + 1);
            assert_eq!((a[0], a[n]), (0.0, 1.0));
            let cells: Vec<f64> = a.windows(2).map(|w| (w[1] - w[0]) * t).collect();
            assert!((cells[0] - 1.0).abs() < 1e-12, "{n} {t}: {cells:?}");
            assert!((cells[n - 1] - 1.0).abs() < 1e-12, "{n} {t}: {cells:?}");
            // one ratio from each face to the middle, symmetric
            let r = cells[1] / cells[0];
            assert!(r > 1.0, "{n} {t}: {cells:?}");
            for i in 0..n {
                let k = i.min(n - 1 - i) as i32;
                assert!(
                    (cells[i] - r.powi(k)).abs() < 1e-9 * t,
                    "{n} {t}: {cells:?}"
                );
            }
        }
    }

    #[test]
    fn graded_cells_follow_the_geometric_law() {
        for (length, first, ratio) in [
            (60.0, 3.0, 1.3),
            (150.0, 4.2, 1.5),
            (40.0, 3.0, 2.0),
            (10.0, 3.0, 1.2),
        ] {
            let s = Spacing::graded(length, first, ratio);
            let sizes: Vec<f64> = (0..s.count)
                .map(|k| s.distance(k + 1) - s.distance(k))
                .collect();
            // first cell within (first/r, first]
            assert!(
                sizes[0] <= first * (1.0 + 1e-12) && sizes[0] > first / ratio,
                "{sizes:?}"
            );
            // each cell r times the one before
            for w in sizes.windows(2) {
                assert!((w[1] / w[0] - ratio).abs() < 1e-12, "{sizes:?}");
            }
            // the margin exactly, and the count the least that does it
            assert_eq!(s.distance(s.count), length);
            assert_eq!(s.distance(0), 0.0);
            let sum: f64 = sizes.iter().sum();
            assert!((sum - length).abs() < 1e-12 * length);
            let fewer = length * (ratio - 1.0) / (ratio.powi(s.count as i32 - 1) - 1.0);
            assert!(
                s.count == 1 || fewer > first,
                "one cell fewer would start at {fewer}"
            );
        }
        // a margin no wider than the first cell is one cell
        assert_eq!(Spacing::graded(2.0, 3.0, 1.3).count, 1);
    }

    #[test]
    fn uniform_spacing_keeps_the_first_versions_expression() {
        let s = Spacing::uniform(3, 70.0);
        for k in 0..=3 {
            assert_eq!(s.distance(k).to_bits(), (70.0 * k as f64 / 3.0).to_bits());
        }
    }
}
