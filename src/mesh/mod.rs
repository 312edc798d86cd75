//! Hex8 meshes of dams: generators, joints, grouting zones, VTU output.
//!
//! # Conventions
//!
//! * Physical axes: **x** along the dam axis (left bank → right bank), **y**
//!   downstream, **z** up (elevation, m). [`Mesh::upstream_normal_hint`] is
//!   `[0, −1, 0]`.
//! * Elements are VTK hexahedra (type 12) in the node order of
//!   `docs/ARCHITECTURE.md`; the generators map the reference axes
//!   ξ → along the axis (logical index `i`), η → across the dam from upstream
//!   to downstream (`j`), ζ → up (`k`). Every generated element has a positive
//!   Jacobian at its 8 corners ([`Mesh::validate`]).
//! * Both generators build one structured logical grid `(i, j, k)` whose cells
//!   are concrete (block, layer), rock or void; void cells are dropped, and so
//!   are the nodes only void cells touch. Element layers are horizontal: every
//!   node of logical level `k` has the same elevation.
//! * Numbering: blocks, joints, lifts and zones are 1-based; nodes, elements,
//!   layers, face pairs 0-based. Joint *j* lies between block *j* and *j + 1*.
//! * **Layers** are the concrete element layers of the whole dam, counted from
//!   0 at its lowest concrete layer; [`Mesh::layer_z`] holds their boundaries.
//!   A lift is `layers_per_lift` layers (always 1 for the arch). Lifts are
//!   numbered per block from its foundation.
//! * **Zones** are global elevation bands of `zone_lifts` lifts: zone *k*
//!   spans layers `[(k−1)·zone_lifts·layers_per_lift, k·zone_lifts·layers_per_lift)`.
//!   Every block foundation lies on a zone boundary, so a joint always holds
//!   whole zones; only the crest zone may hold fewer lifts when the dam height
//!   is not a whole number of zones.
//! * **Joints.** On a joint plane the nodes are duplicated: block *j* keeps
//!   copy A, block *j + 1* gets copy B (same coordinates, one shared thermal
//!   dof). A node that also touches a rock element is *not* duplicated: rock–
//!   concrete and rock–rock nodes are shared, so a joint is closed along its
//!   foundation edge (on a rock foundation) and where it meets rock.
//!   Without rock (`rock_depth_m = 0` in the blocks generator) every joint node
//!   is duplicated down to the base.
//! * **Face pairs.** One [`FacePair`] per facing quad pair: `nodes_a` is
//!   `elem_a`'s face 3 (ξ = +1, nodes `[1, 2, 6, 5]`), `nodes_b[k]` sits at the
//!   same point as `nodes_a[k]` (it is `elem_b`'s nodes `[0, 3, 7, 4]`). On that
//!   quad the bilinear coordinates are `s` = η (−1 upstream edge, +1
//!   downstream edge) and `t` = ζ (−1 bottom, +1 top); `nodes_a` are at
//!   `(s, t) = (−1,−1), (1,−1), (1,1), (−1,1)`, the corner order of
//!   [`crate::fem::quad4`], whose shape functions weigh them.
//! * **Zone points.** Per (joint, zone): upstream, centre, downstream, at the
//!   zone's mid height. Upstream is on the joint's upstream edge (`s = −1` of
//!   the first concrete cell across), downstream on its downstream edge, the
//!   centre at mid thickness (logical middle across). A point on an element
//!   edge is given to the pair below (for height) and upstream (across), with
//!   `t = +1` / `s = +1`.
//! * **Surfaces** ([`SurfaceFace`]) are the faces on the outer boundary of the
//!   complete mesh: rock faces on the model's bottom and sides are
//!   [`SurfaceKind::Far`]; exposed rock ground and concrete faces are
//!   [`SurfaceKind::Ground`], or [`SurfaceKind::Wet`] when they face upstream
//!   (concrete η = −1 faces) or lie upstream of the dam (rock upstream of the
//!   upstream face). Concrete faces on the bottom of a rock-less model are
//!   `Far`. Lift tops and joint faces are internal, not surfaces. Which side
//!   of the model a far face is on (base, upstream, downstream, left or
//!   right bank) is read from the geometry by [`far`], for any mesh.
//!
//! See [`blocks`], [`arch`] and [`arch_table`] for the shapes.

pub mod arch;
pub mod arch_curves;
pub mod arch_table;
mod arch_table_read;
pub mod blocks;
pub mod far;
pub mod geometry;
mod grid;
pub mod import;
pub mod quality;
pub mod vtu;

use std::collections::{BTreeMap, HashMap};
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use arch::generate_arch;
pub use arch_table::generate_arch_table;
pub use blocks::generate_blocks;
pub use far::{DamFrame, FarSide};
pub use vtu::{write_pvd, write_vtu};

/// Local faces of a hex8: the one table of `fem::hex8`.
pub use crate::fem::hex8::FACES as HEX_FACES;
use crate::fem::hex8::NODES as HEX_REF;
use crate::vocab::{ZoneId, ZonePoint};

/// Errors of the generators and of [`Mesh::validate`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    /// A generator parameter is out of range; Display: `"{param} {message}"`,
    /// e.g. `n_blocks must be >= 1, got 0`.
    #[error("{param} {message}")]
    Param {
        /// Parameter name as in the scene (`n_blocks`, `zone_height_m`, ...).
        param: String,
        message: String,
    },
    /// The parameters would give a mesh too large to index with `u32`.
    #[error("mesh too large: {nodes} nodes, {elements} elements (limit {limit} each)")]
    TooLarge {
        nodes: u64,
        elements: u64,
        limit: u64,
    },
    /// Even the mesh of the parameters would not fit in the machine's memory.
    #[error("mesh too large for this machine: {nodes} nodes, {elements} elements need at least {needed_gib:.1} GiB, the machine has {total_gib:.1} GiB (use fewer elements per block, across or per lift)")]
    TooMuchMemory {
        nodes: u64,
        elements: u64,
        needed_gib: f64,
        total_gib: f64,
    },
    /// An element is inverted or degenerate.
    #[error("element {elem}: Jacobian determinant {det:.6e} <= 0 at corner {corner}")]
    NonPositiveJacobian {
        elem: usize,
        corner: usize,
        det: f64,
    },
    /// Any other inconsistency found by [`Mesh::validate`].
    #[error("invalid mesh: {0}")]
    Invalid(String),
}

impl MeshError {
    pub(crate) fn param(param: &str, message: impl Into<String>) -> MeshError {
        MeshError::Param {
            param: param.to_string(),
            message: message.into(),
        }
    }
}

/// What an element is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Part {
    /// Concrete of `block`, poured with `lift` (both 1-based; lift 1 sits on the foundation).
    Concrete {
        block: u32,
        lift: u32,
    },
    Rock,
}

/// One block (column of lifts).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockInfo {
    /// 1-based, from the left bank.
    pub block: u32,
    pub n_lifts: u32,
    /// Global layer index of the bottom layer of lift 1 (0 = lowest concrete layer of the dam).
    pub base_layer: u32,
    /// Elevation of the block's base \[m\].
    pub foundation_z: f64,
}

/// The block infos of per-block (base layer, lifts), numbered from 1, each
/// founded at its base layer's elevation in `layer_z` (both mesh builders).
pub(crate) fn block_infos(blocks: &[(u32, u32)], layer_z: &[f64]) -> Vec<BlockInfo> {
    blocks
        .iter()
        .enumerate()
        .map(|(b, &(base, n_lifts))| BlockInfo {
            block: b as u32 + 1,
            n_lifts,
            base_layer: base,
            foundation_z: layer_z[base as usize],
        })
        .collect()
}

/// One pair of facing joint quads (one composite joint element).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FacePair {
    pub joint: u32,
    pub zone: u32,
    /// Global layer index.
    pub layer: u32,
    /// Element of block `joint`.
    pub elem_a: u32,
    /// Element of block `joint + 1`.
    pub elem_b: u32,
    /// `elem_a`'s face 3 (ξ = +1) in `HEX_FACES[3]` order, i.e. its nodes `[1, 2, 6, 5]`.
    pub nodes_a: [u32; 4],
    /// `nodes_b[k]` coincides with `nodes_a[k]` (duplicated node, or the same node
    /// where the joint meets rock); these are `elem_b`'s nodes `[0, 3, 7, 4]`.
    pub nodes_b: [u32; 4],
}

/// Where on the mesh a zone point (upstream, center or downstream; never
/// `Min`) sits: the aperture and temperature of that point are read there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneSite {
    pub joint: u32,
    pub zone: u32,
    pub point: ZonePoint,
    /// Index into [`Mesh::face_pairs`].
    pub pair: u32,
    /// Bilinear coordinates in [−1, 1]² on `nodes_a` of the pair ([`crate::fem::quad4::shape`]).
    pub s: f64,
    pub t: f64,
    pub xyz: [f64; 3],
}

/// A grouting zone of one joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Zone {
    pub joint: u32,
    pub zone: u32,
    pub z_bottom: f64,
    pub z_top: f64,
    /// Indices into [`Mesh::face_pairs`] (by layer, then upstream → downstream).
    pub pairs: Vec<u32>,
}

impl Zone {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }
}

/// Boundary condition family of an outer face.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// Model boundary in the rock (or the base of a rock-less model): adiabatic / fixed.
    Far,
    /// Ground or concrete surface in air.
    Ground,
    /// Surface that can be under the reservoir (upstream).
    Wet,
}

/// A face on the outer boundary of the complete mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct SurfaceFace {
    pub elem: u32,
    /// Local face 0..6 (`HEX_FACES`).
    pub face: u8,
    pub kind: SurfaceKind,
}

/// A hex8 dam mesh with its joints and grouting zones. See the module docs for conventions.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[u32; 8]>,
    pub parts: Vec<Part>,
    /// Node → thermal dof; the two copies of a joint node share one.
    pub thermal_dof: Vec<u32>,
    pub n_thermal_dofs: usize,
    /// Elevations of the concrete layer boundaries, len = n_layers + 1.
    pub layer_z: Vec<f64>,
    /// Nominal lift height \[m\] (the arch's crest lift absorbs the remainder of the height).
    pub lift_height: f64,
    /// Lifts per grouting zone.
    pub zone_lifts: u32,
    /// Element layers per lift (1 unless the blocks generator asks for more).
    #[serde(default = "one_u32")]
    pub layers_per_lift: u32,
    /// Blocks in order 1..=n.
    pub blocks: Vec<BlockInfo>,
    /// Sorted by (joint, layer, across position).
    pub face_pairs: Vec<FacePair>,
    /// Sorted by (joint, zone).
    pub zones: Vec<Zone>,
    /// Sorted by (joint, zone, kind): three per zone.
    pub zone_points: Vec<ZoneSite>,
    /// Faces on the outer boundary of the complete mesh.
    pub surfaces: Vec<SurfaceFace>,
    /// Elevation of the crest \[m\].
    pub crest_z: f64,
    /// Unit vector pointing upstream, `[0, −1, 0]`.
    pub upstream_normal_hint: [f64; 3],
    /// Per-block/per-lift element lists, built on first use.
    #[serde(skip)]
    index: OnceLock<LiftIndex>,
}

fn one_u32() -> u32 {
    1
}

/// Elements of each block sorted by (lift, element), with lift offsets.
#[derive(Debug, Clone, Default)]
struct LiftIndex {
    /// Per block (index block − 1): elements and `offsets[l−1]..offsets[l]` for lift l.
    blocks: Vec<(Vec<u32>, Vec<usize>)>,
}

/// Determinant of the hex8 Jacobian at reference point (ξ, η, ζ).
pub fn hex_jacobian_det(x: &[[f64; 3]; 8], xi: f64, eta: f64, zeta: f64) -> f64 {
    crate::fem::hex8::jacobian(x, [xi, eta, zeta]).1
}

/// Exact volume of a hex8 (Gauss, exact for trilinear maps).
pub fn hex_volume(x: &[[f64; 3]; 8]) -> f64 {
    crate::fem::hex8::volume(x)
}

impl Mesh {
    /// Where a node is, for an error message: `node 812 at (12.0, 3.5,
    /// 1021.0) m, in block 4 lift 7, on joint 3` (the parts of the elements
    /// using it, the joints whose faces hold it).
    pub fn describe_node(&self, node: u32) -> String {
        let Some(xyz) = self.nodes.get(node as usize) else {
            return format!("node {node}");
        };
        let mut parts: Vec<String> = Vec::new();
        for (e, el) in self.elements.iter().enumerate() {
            if !el.contains(&node) {
                continue;
            }
            let part = match self.parts.get(e) {
                Some(Part::Concrete { block, lift }) => format!("block {block} lift {lift}"),
                Some(Part::Rock) | None => "the rock".to_string(),
            };
            if !parts.contains(&part) {
                parts.push(part);
            }
        }
        let mut joints: Vec<u32> = self
            .face_pairs
            .iter()
            .filter(|p| p.nodes_a.contains(&node) || p.nodes_b.contains(&node))
            .map(|p| p.joint)
            .collect();
        joints.dedup();
        let mut s = format!(
            "node {node} at ({:.1}, {:.1}, {:.1}) m, in {}",
            xyz[0],
            xyz[1],
            xyz[2],
            parts.join(" and ")
        );
        for j in joints {
            s += &format!(", on joint {j}");
        }
        s
    }

    /// A node carrying thermal dof `dof` (nodes paired across a joint share one).
    pub fn node_of_thermal_dof(&self, dof: u32) -> Option<u32> {
        self.thermal_dof
            .iter()
            .position(|&d| d == dof)
            .map(|n| n as u32)
    }

    /// Coordinates of the 8 nodes of element `e`.
    pub fn element_coords(&self, e: usize) -> [[f64; 3]; 8] {
        let c = &self.elements[e];
        std::array::from_fn(|k| self.nodes[c[k] as usize])
    }

    /// Number of concrete element layers of the dam.
    pub fn n_layers(&self) -> u32 {
        self.layer_z.len().saturating_sub(1) as u32
    }

    /// Number of joints (blocks − 1).
    pub fn joint_count(&self) -> u32 {
        self.blocks.len().saturating_sub(1) as u32
    }

    /// Global zone (1-based) holding global layer `layer` (0-based).
    pub fn zone_of_layer(&self, layer: u32) -> u32 {
        layer
            / (self
                .zone_lifts
                .max(1)
                .saturating_mul(self.layers_per_lift.max(1)))
            + 1
    }

    /// Number of global zone bands from the lowest concrete layer to the crest.
    pub fn n_zones(&self) -> u32 {
        let per = self
            .zone_lifts
            .max(1)
            .saturating_mul(self.layers_per_lift.max(1));
        self.n_layers().div_ceil(per)
    }

    /// Global layers `[first, end)` of zone `zone` (1-based), clipped at the crest.
    pub fn zone_layers(&self, zone: u32) -> std::ops::Range<u32> {
        let per = self
            .zone_lifts
            .max(1)
            .saturating_mul(self.layers_per_lift.max(1));
        let n = self.n_layers();
        let first = (zone.max(1) - 1).saturating_mul(per).min(n);
        first..zone.saturating_mul(per).min(n)
    }

    /// Global layer of the bottom of `lift` (1-based) of `block`, if both exist.
    pub fn layer_of_lift(&self, block: u32, lift: u32) -> Option<u32> {
        let b = self.blocks.get((block as usize).checked_sub(1)?)?;
        if lift == 0 || lift > b.n_lifts {
            return None;
        }
        Some(b.base_layer + (lift - 1) * self.layers_per_lift.max(1))
    }

    /// The zone `zone` of joint `joint`, if it exists.
    pub fn zone(&self, joint: u32, zone: u32) -> Option<&Zone> {
        self.zones
            .binary_search_by(|z| (z.joint, z.zone).cmp(&(joint, zone)))
            .ok()
            .map(|i| &self.zones[i])
    }

    /// The three reading points (upstream, center, downstream) of a zone; empty if unknown.
    pub fn zone_points_of(&self, joint: u32, zone: u32) -> &[ZoneSite] {
        let lo = self
            .zone_points
            .partition_point(|p| (p.joint, p.zone) < (joint, zone));
        let hi = self
            .zone_points
            .partition_point(|p| (p.joint, p.zone) <= (joint, zone));
        &self.zone_points[lo..hi]
    }

    /// Point at bilinear coordinates (s, t) on `nodes_a` of face pair `pair`.
    pub fn face_pair_point(&self, pair: usize, s: f64, t: f64) -> [f64; 3] {
        let corners = self.face_pairs[pair]
            .nodes_a
            .map(|n| self.nodes[n as usize]);
        crate::fem::quad4::point(&corners, [s, t])
    }

    fn index(&self) -> &LiftIndex {
        self.index.get_or_init(|| {
            let n_blocks = self.parts.iter().fold(self.blocks.len(), |m, p| match p {
                Part::Concrete { block, .. } => m.max(*block as usize),
                Part::Rock => m,
            });
            let mut lists: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n_blocks];
            for (e, p) in self.parts.iter().enumerate() {
                if let Part::Concrete { block, lift } = *p {
                    if block >= 1 && lift >= 1 {
                        lists[block as usize - 1].push((lift, e as u32));
                    }
                }
            }
            let blocks = lists
                .into_iter()
                .map(|mut l| {
                    l.sort_unstable();
                    let n_lifts = l.last().map_or(0, |x| x.0) as usize;
                    let mut offsets = vec![0usize; n_lifts + 1];
                    for &(lift, _) in &l {
                        offsets[lift as usize] += 1;
                    }
                    for i in 1..offsets.len() {
                        offsets[i] += offsets[i - 1];
                    }
                    (l.into_iter().map(|x| x.1).collect(), offsets)
                })
                .collect();
            LiftIndex { blocks }
        })
    }

    /// Elements of `lift` of `block` (1-based both), sorted; empty if either is unknown.
    pub fn elements_of_lift(&self, block: u32, lift: u32) -> &[u32] {
        let idx = self.index();
        let Some((elems, offsets)) = (block as usize)
            .checked_sub(1)
            .and_then(|b| idx.blocks.get(b))
        else {
            return &[];
        };
        let l = lift as usize;
        if l == 0 || l >= offsets.len() {
            return &[];
        }
        &elems[offsets[l - 1]..offsets[l]]
    }

    /// [`Mesh::elements_of_lift`] of every lift that has elements, keyed by
    /// (block, lift): the owned copy the physics models keep, since they
    /// outlive their borrow of the mesh. Ordered, so that a model iterating
    /// it visits the lifts in the same order in every process.
    pub fn lift_elements(&self) -> BTreeMap<(u32, u32), Vec<u32>> {
        let mut map = BTreeMap::new();
        for (b, (_, offsets)) in self.index().blocks.iter().enumerate() {
            let block = b as u32 + 1;
            for lift in 1..offsets.len() as u32 {
                let elems = self.elements_of_lift(block, lift);
                if !elems.is_empty() {
                    map.insert((block, lift), elems.to_vec());
                }
            }
        }
        map
    }

    /// All elements of `block` (1-based), sorted by lift then element; empty if unknown.
    pub fn elements_of_block(&self, block: u32) -> &[u32] {
        (block as usize)
            .checked_sub(1)
            .and_then(|b| self.index().blocks.get(b))
            .map_or(&[], |(e, _)| e.as_slice())
    }

    /// Rebuild the per-lift index (only needed after editing `parts` by hand).
    pub fn reindex(&mut self) {
        self.index = OnceLock::new();
    }

    /// Check the mesh: sizes and indices, positive Jacobian at the 8 corners of
    /// every hex, face pairs (nodes_a = face 3 of elem_a, nodes_b on elem_b's
    /// face 5, coincident within 1e-9 m, blocks joint/joint+1), zones (whole
    /// bands, pairs of their joint and zone), zone points (on their pair at
    /// (s, t)), and that `thermal_dof` merges exactly the face-pair node pairs.
    pub fn validate(&self) -> Result<(), MeshError> {
        self.validate_sizes()?;
        self.validate_elements()?;
        self.validate_parts()?;
        for (ip, fp) in self.face_pairs.iter().enumerate() {
            self.validate_face_pair(ip, fp)?;
        }
        let mut pairs_in_zones = 0usize;
        for z in &self.zones {
            self.validate_zone(z)?;
            pairs_in_zones += z.pairs.len();
        }
        if pairs_in_zones != self.face_pairs.len() {
            return invalid(format!(
                "{} face pairs but {} in zones",
                self.face_pairs.len(),
                pairs_in_zones
            ));
        }
        self.validate_zone_points()?;
        for s in &self.surfaces {
            if s.elem as usize >= self.elements.len() || s.face >= 6 {
                return invalid(format!(
                    "surface face ({}, {}) out of range",
                    s.elem, s.face
                ));
            }
        }
        self.validate_thermal_dofs()
    }

    /// Lengths of the per-node and per-element arrays, finite coordinates,
    /// increasing layers, non-zero zone and lift sizes.
    fn validate_sizes(&self) -> Result<(), MeshError> {
        let nn = self.nodes.len();
        let ne = self.elements.len();
        if self.parts.len() != ne {
            return invalid(format!("{} parts for {} elements", self.parts.len(), ne));
        }
        if self.thermal_dof.len() != nn {
            return invalid(format!(
                "{} thermal dofs for {} nodes",
                self.thermal_dof.len(),
                nn
            ));
        }
        if let Some(p) = self
            .nodes
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return invalid(format!("node {p} has a non-finite coordinate"));
        }
        if self.layer_z.windows(2).any(|w| w[1] <= w[0]) {
            return invalid("layer_z is not strictly increasing".into());
        }
        if self.zone_lifts == 0 || self.layers_per_lift == 0 {
            return invalid("zone_lifts and layers_per_lift must be >= 1".into());
        }
        Ok(())
    }

    /// Node indices in range and a positive Jacobian at every corner.
    fn validate_elements(&self) -> Result<(), MeshError> {
        let nn = self.nodes.len();
        for (e, conn) in self.elements.iter().enumerate() {
            if let Some(&bad) = conn.iter().find(|&&n| n as usize >= nn) {
                return invalid(format!("element {e} refers to node {bad} of {nn}"));
            }
            let x = self.element_coords(e);
            for (c, r) in HEX_REF.iter().enumerate() {
                let det = hex_jacobian_det(&x, r[0], r[1], r[2]);
                if det.is_nan() || det <= 0.0 {
                    return Err(MeshError::NonPositiveJacobian {
                        elem: e,
                        corner: c,
                        det,
                    });
                }
            }
        }
        Ok(())
    }

    /// Every concrete element names a block and lift that exist; blocks are
    /// numbered 1..=n in order.
    fn validate_parts(&self) -> Result<(), MeshError> {
        for (e, p) in self.parts.iter().enumerate() {
            if let Part::Concrete { block, lift } = *p {
                let ok = block >= 1
                    && (block as usize) <= self.blocks.len()
                    && lift >= 1
                    && lift <= self.blocks[block as usize - 1].n_lifts;
                if !ok {
                    return invalid(format!("element {e}: unknown block {block} / lift {lift}"));
                }
            }
        }
        for (i, b) in self.blocks.iter().enumerate() {
            if b.block as usize != i + 1 {
                return invalid(format!("blocks[{i}] has number {}", b.block));
            }
        }
        Ok(())
    }

    /// Face pair `ip`: the facing faces of concrete of blocks joint and
    /// joint + 1, node by node at the same point, in a layer of its zone.
    fn validate_face_pair(&self, ip: usize, fp: &FacePair) -> Result<(), MeshError> {
        let ne = self.elements.len();
        let (ea, eb) = (fp.elem_a as usize, fp.elem_b as usize);
        if ea >= ne || eb >= ne {
            return invalid(format!("face pair {ip}: element out of range"));
        }
        let a = &self.elements[ea];
        let b = &self.elements[eb];
        if fp.nodes_a != [a[1], a[2], a[6], a[5]] {
            return invalid(format!(
                "face pair {ip}: nodes_a is not face 3 of element {ea}"
            ));
        }
        if fp.nodes_b != [b[0], b[3], b[7], b[4]] {
            return invalid(format!(
                "face pair {ip}: nodes_b is not face 5 of element {eb}"
            ));
        }
        match (self.parts[ea], self.parts[eb]) {
            (Part::Concrete { block: ba, .. }, Part::Concrete { block: bb, .. })
                if ba == fp.joint && bb == fp.joint + 1 => {}
            _ => {
                return invalid(format!(
                    "face pair {ip}: elements are not concrete of blocks {} and {}",
                    fp.joint,
                    fp.joint + 1
                ))
            }
        }
        for k in 0..4 {
            let pa = self.nodes[fp.nodes_a[k] as usize];
            let pb = self.nodes[fp.nodes_b[k] as usize];
            let d = dist(pa, pb);
            if d > COINCIDENT_M {
                return invalid(format!("face pair {ip}: node {k} pair {d:.3e} m apart"));
            }
        }
        if fp.layer >= self.n_layers() || fp.zone != self.zone_of_layer(fp.layer) {
            return invalid(format!(
                "face pair {ip}: layer {} / zone {} inconsistent",
                fp.layer, fp.zone
            ));
        }
        Ok(())
    }

    /// A zone is a whole band: pairs of its joint and zone, the same number in
    /// every layer of the band, and the band's elevations.
    fn validate_zone(&self, z: &Zone) -> Result<(), MeshError> {
        let band = self.zone_layers(z.zone);
        if band.is_empty() {
            return invalid(format!(
                "joint {} zone {} is above the crest",
                z.joint, z.zone
            ));
        }
        let mut per_layer: HashMap<u32, usize> = HashMap::new();
        for &p in &z.pairs {
            let Some(fp) = self.face_pairs.get(p as usize) else {
                return invalid(format!(
                    "joint {} zone {}: pair {p} out of range",
                    z.joint, z.zone
                ));
            };
            if fp.joint != z.joint || fp.zone != z.zone {
                return invalid(format!(
                    "joint {} zone {}: pair {p} belongs elsewhere",
                    z.joint, z.zone
                ));
            }
            *per_layer.entry(fp.layer).or_default() += 1;
        }
        let counts: Vec<usize> = band
            .clone()
            .map(|l| per_layer.get(&l).copied().unwrap_or(0))
            .collect();
        if counts.iter().any(|&c| c == 0 || c != counts[0]) || per_layer.len() != counts.len() {
            return invalid(format!(
                "joint {} zone {} is not a whole zone (pairs per layer {:?})",
                z.joint, z.zone, counts
            ));
        }
        let zb = self.layer_z[band.start as usize];
        let zt = self.layer_z[band.end as usize];
        if (zb - z.z_bottom).abs() > COINCIDENT_M || (zt - z.z_top).abs() > COINCIDENT_M {
            return invalid(format!(
                "joint {} zone {}: wrong elevations",
                z.joint, z.zone
            ));
        }
        Ok(())
    }

    /// Every zone point lies on a pair of its joint and zone, at its (s, t).
    fn validate_zone_points(&self) -> Result<(), MeshError> {
        for (i, p) in self.zone_points.iter().enumerate() {
            let Some(fp) = self.face_pairs.get(p.pair as usize) else {
                return invalid(format!("zone point {i}: pair out of range"));
            };
            if fp.joint != p.joint || fp.zone != p.zone || p.s.abs() > 1.0 || p.t.abs() > 1.0 {
                return invalid(format!(
                    "zone point {i} (joint {} zone {}) is off its pair",
                    p.joint, p.zone
                ));
            }
            let q = self.face_pair_point(p.pair as usize, p.s, p.t);
            if dist(q, p.xyz) > 1e-6 {
                return invalid(format!("zone point {i}: xyz differs from its (s, t)"));
            }
        }
        Ok(())
    }

    /// `thermal_dof` classes == classes of the node identifications by face pairs.
    fn validate_thermal_dofs(&self) -> Result<(), MeshError> {
        let nn = self.nodes.len();
        let mut parent: Vec<u32> = (0..nn as u32).collect();
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                parent[x as usize] = parent[parent[x as usize] as usize];
                x = parent[x as usize];
            }
            x
        }
        for fp in &self.face_pairs {
            for k in 0..4 {
                let ra = find(&mut parent, fp.nodes_a[k]);
                let rb = find(&mut parent, fp.nodes_b[k]);
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        let mut dof_of_root: HashMap<u32, u32> = HashMap::new();
        let mut root_of_dof: Vec<u32> = vec![u32::MAX; self.n_thermal_dofs];
        for n in 0..nn as u32 {
            let r = find(&mut parent, n);
            let d = self.thermal_dof[n as usize];
            if d as usize >= self.n_thermal_dofs {
                return Err(MeshError::Invalid(format!(
                    "node {n}: thermal dof {d} out of range"
                )));
            }
            if *dof_of_root.entry(r).or_insert(d) != d {
                return Err(MeshError::Invalid(format!(
                    "node {n}: joint-paired nodes have different thermal dofs"
                )));
            }
            let slot = &mut root_of_dof[d as usize];
            if *slot == u32::MAX {
                *slot = r;
            } else if *slot != r {
                return Err(MeshError::Invalid(format!(
                    "thermal dof {d} merges nodes that are not a joint pair"
                )));
            }
        }
        if root_of_dof.contains(&u32::MAX) {
            return Err(MeshError::Invalid("some thermal dofs have no node".into()));
        }
        Ok(())
    }
}

/// Distance \[m\] within which two joint nodes (or two elevations) are the same.
const COINCIDENT_M: f64 = 1e-9;

fn invalid<T>(m: String) -> Result<T, MeshError> {
    Err(MeshError::Invalid(m))
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
