//! A [`RawMesh`] (what a mesh file says) turned into the dam [`Mesh`] the
//! simulator runs on: blocks, lifts, joints, zones, zone points, surfaces,
//! with the conventions of the generators (module docs of [`crate::mesh`]).
//!
//! # Steps
//!
//! 1. **Parts**: element groups `block_<n>` (n = 1.. from the left bank, no
//!    gap) and the optional `rock`; every element in exactly one.
//! 2. **Orientation**: each element's corners are re-ordered by the one of
//!    the 48 symmetries of the reference cube that keeps its Jacobian
//!    positive and puts ζ closest to +z, then ξ closest to the dam axis at
//!    the element (in plan, the chord from block j − 1's centroid to block
//!    j + 1's; a rock element takes the nearest block's). η = ζ × ξ then
//!    points downstream. An element whose file corner order is mirrored
//!    (left-handed, negative Jacobian everywhere) is **accepted**: one of the
//!    24 reflections re-orders it, since its shape is sound and only the
//!    numbering differs, as some exporters write it. An element with a corner
//!    Jacobian ≤ 1e-12·h³ (h its diagonal) in that best order is inverted or
//!    degenerate: an error naming it, the corner's node and the Jacobian.
//! 3. **Nodes**: coincident nodes (within 1e-9 of the model's size, found
//!    through a spatial hash) are one point. A point touching concrete of
//!    blocks j and j + 1 and no rock gets two nodes, copy A (block j) and
//!    copy B (block j + 1), on one thermal dof; any other point is one node,
//!    so the dam is bonded to the rock. Nodes are numbered in the file's
//!    order of first use (copy A before copy B), so a generated mesh keeps
//!    its numbering. Blocks j and k ≠ j ± 1 touching is an error.
//! 4. **Faces**: faces are matched by their corner points. A face shared by
//!    block j (its face 3, ξ = +1) and block j + 1 (its face 5) is a joint
//!    [`FacePair`]. A boundary face whose centre lies on a boundary face of
//!    another part (a spatial hash of the boundary faces) is a non-conforming
//!    joint or contact: an error with the face's centre and both parts.
//! 5. **Floating blocks**: every block must reach the rock (or, without rock,
//!    the lowest concrete level) through shared faces.
//! 6. **Layers and lifts**: concrete bottom and top faces are level within
//!    1e-6 of the dam's height; their distinct levels are `layer_z`, and
//!    every concrete element spans exactly one layer. Lifts of each block run
//!    from its foundation by `lift_height`, the crest lift taking the rest
//!    (the arch generator's rule: round((top − base)/lift) lifts); every lift
//!    holds the same number of layers (`layers_per_lift`); every foundation
//!    lies on a zone boundary. Optional groups `block_<n>_lift_<m>` are
//!    checked against these lifts.
//! 7. **Zones, zone points, surfaces** exactly as the generators make them.
//!    Surfaces: concrete faces are `Wet` when upstream (face 2), `Far` at the
//!    bottom of a rock-less model, `Ground` otherwise. A rock side face is
//!    `Far` when the model's boundary below it runs down, through side
//!    faces, to a downward face (the model's walls); a side face whose wall
//!    ends on an upward face is a step of the valley floor. This reproduces
//!    the generators' "edge of the grid" on their curved arches, where a ray
//!    test would not (a ray from a step's riser across the valley leaves the
//!    model). Other rock faces are `Wet` when upstream of the dam (on the
//!    outer side of the nearest upstream concrete face), `Ground` otherwise.
//!    Node groups `far`, `air`, `upstream` override the kind of a boundary
//!    face whose four corners they hold (`Far`, `Ground`, `Wet`; in that
//!    order of precedence).
//!
//! # Verified by
//!
//! `tests/it/mesh_import.rs`: the generated small dam and demo arch come back
//! field for field; the same meshes shuffled, re-oriented and with their
//! joint nodes merged give the same dam; malformed meshes give their exact
//! messages.

use std::collections::{BTreeSet, HashMap};
use std::sync::OnceLock;

use thiserror::Error;

use super::RawMesh;
use crate::fem::quad4;
use crate::mesh::{
    grid, hex_jacobian_det, FacePair, Mesh, MeshError, Part, SurfaceFace, SurfaceKind, Zone,
    ZoneSite, HEX_FACES,
};
use crate::vocab::ZonePoint;

/// What a mesh file gets wrong for a dam. Every message starts with the file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DamMeshError {
    /// The element groups do not name the dam's parts.
    #[error("{file}: {message}")]
    Groups { file: String, message: String },
    /// One element (the file's number).
    #[error("{file}: element {elem}: {message}")]
    Element {
        file: String,
        elem: u64,
        message: String,
    },
    /// One node (the file's number).
    #[error("{file}: node {node}: {message}")]
    Node {
        file: String,
        node: u64,
        message: String,
    },
    /// One block's layers, lifts or place.
    #[error("{file}: block {block}: {message}")]
    Block {
        file: String,
        block: u32,
        message: String,
    },
    /// Joints and zones.
    #[error("{file}: {message}")]
    Dam { file: String, message: String },
    /// The lift or zone height, or the final check of the mesh.
    #[error("{file}: {source}")]
    Mesh {
        file: String,
        #[source]
        source: MeshError,
    },
}

/// Build the dam mesh of `raw` with lifts of `lift_height` m and grouting
/// zones of `zone_height` m (a whole number of lifts); see the module docs.
pub fn build(raw: &RawMesh, lift_height: f64, zone_height: f64) -> Result<Mesh, DamMeshError> {
    let zone_lifts =
        grid::zone_lifts(lift_height, zone_height).map_err(|source| DamMeshError::Mesh {
            file: raw.source.clone(),
            source,
        })?;
    check_raw(raw)?;
    let part = parts(raw)?;
    let n_blocks = part.iter().copied().max().unwrap_or(0);
    let corners = orient(raw, &part, n_blocks)?;
    check_downstream(raw, &part, &corners)?;
    let dam = Dam::new(raw, part, n_blocks, corners);
    let roles = dam.roles()?;
    let adj = dam.faces()?;
    dam.check_joint_faces(&adj)?;
    dam.check_conforming(&adj)?;
    dam.check_floating(&adj)?;
    let layers = dam.layers()?;
    let lifts = dam.lifts(&layers, lift_height, zone_lifts)?;
    let num = dam.number(&roles);
    let per_zone = zone_lifts * lifts.per_lift;
    let face_pairs = dam.face_pairs(&adj, &layers, &num, per_zone);
    let zones = dam.zones(&face_pairs, &layers.z, per_zone)?;
    let zone_points = zone_points(&zones, &face_pairs, &layers.z, per_zone, &num.nodes);
    let surfaces = dam.surfaces(&adj);
    let blocks = super::super::block_infos(&lifts.blocks, &layers.z);
    let parts = (0..dam.part.len())
        .map(|e| match dam.part[e] {
            0 => Part::Rock,
            b => Part::Concrete {
                block: b,
                lift: lifts.lift_of[e],
            },
        })
        .collect();
    let mesh = Mesh {
        nodes: num.nodes,
        elements: num.elements,
        parts,
        thermal_dof: num.thermal_dof,
        n_thermal_dofs: num.n_dofs as usize,
        crest_z: *layers.z.last().unwrap_or(&0.0),
        layer_z: layers.z,
        lift_height,
        zone_lifts,
        layers_per_lift: lifts.per_lift,
        blocks,
        face_pairs,
        zones,
        zone_points,
        surfaces,
        upstream_normal_hint: [0.0, -1.0, 0.0],
        index: OnceLock::new(),
    };
    mesh.validate().map_err(|source| DamMeshError::Mesh {
        file: raw.source.clone(),
        source,
    })?;
    Ok(mesh)
}

const NONE: u32 = u32::MAX;

fn groups_err(raw: &RawMesh, message: String) -> DamMeshError {
    DamMeshError::Groups {
        file: raw.source.clone(),
        message,
    }
}

fn elem_err(raw: &RawMesh, e: usize, message: String) -> DamMeshError {
    DamMeshError::Element {
        file: raw.source.clone(),
        elem: raw.elem_ids.get(e).copied().unwrap_or(e as u64 + 1),
        message,
    }
}

fn dam_err(raw: &RawMesh, message: String) -> DamMeshError {
    DamMeshError::Dam {
        file: raw.source.clone(),
        message,
    }
}

fn block_err(raw: &RawMesh, block: u32, message: String) -> DamMeshError {
    DamMeshError::Block {
        file: raw.source.clone(),
        block,
        message,
    }
}

/// `(x, y, z) m` for messages, to the millimetre.
fn at(p: [f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3}) m", p[0], p[1], p[2])
}

fn part_name(p: u32) -> String {
    if p == 0 {
        "rock".to_string()
    } else {
        format!("block {p}")
    }
}

/// Sizes agree, corners are nodes of the file, used coordinates are finite.
fn check_raw(raw: &RawMesh) -> Result<(), DamMeshError> {
    let nn = raw.nodes.len();
    if raw.node_ids.len() != nn || raw.elem_ids.len() != raw.hexes.len() {
        return Err(dam_err(
            raw,
            format!(
                "{} node numbers for {} nodes, {} element numbers for {} elements",
                raw.node_ids.len(),
                nn,
                raw.elem_ids.len(),
                raw.hexes.len()
            ),
        ));
    }
    if raw.hexes.is_empty() {
        return Err(dam_err(
            raw,
            "no hexahedra: a dam mesh is made of 8-node hexahedra".into(),
        ));
    }
    for (e, h) in raw.hexes.iter().enumerate() {
        for &n in h {
            let Some(p) = raw.nodes.get(n as usize) else {
                return Err(elem_err(
                    raw,
                    e,
                    format!("refers to node index {n}, but the file has {nn} nodes"),
                ));
            };
            if p.iter().any(|c| !c.is_finite()) {
                return Err(DamMeshError::Node {
                    file: raw.source.clone(),
                    node: raw.node_ids[n as usize],
                    message: format!("has a non-finite coordinate {p:?}"),
                });
            }
        }
    }
    Ok(())
}

/// What an element group names.
enum Group {
    Rock,
    Block(u32),
    Lift(u32, u32),
}

fn number(s: &str) -> Option<u32> {
    if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    s.parse().ok().filter(|&n| n >= 1)
}

/// The part a group names; the names match in any case, since Abaqus
/// tools write set names in capitals (`BLOCK_1`, `ROCK`).
fn group_kind(name: &str) -> Option<Group> {
    let name = name.to_ascii_lowercase();
    if name == "rock" {
        return Some(Group::Rock);
    }
    let rest = name.strip_prefix("block_")?;
    match rest.split_once("_lift_") {
        Some((b, l)) => Some(Group::Lift(number(b)?, number(l)?)),
        None => number(rest).map(Group::Block),
    }
}

fn group_name(p: u32) -> String {
    if p == 0 {
        "rock".to_string()
    } else {
        format!("block_{p}")
    }
}

/// Step 1: the part of every element, 0 for rock, n for block n.
fn parts(raw: &RawMesh) -> Result<Vec<u32>, DamMeshError> {
    let ne = raw.hexes.len();
    let mut part: Vec<Option<u32>> = vec![None; ne];
    let mut blocks = BTreeSet::new();
    for (name, elems) in &raw.element_groups {
        let p = match group_kind(name) {
            Some(Group::Rock) => 0,
            Some(Group::Block(n)) => n,
            _ => continue,
        };
        if p > 0 && !elems.is_empty() {
            blocks.insert(p);
        }
        for &e in elems {
            let Some(slot) = part.get_mut(e as usize) else {
                return Err(groups_err(
                    raw,
                    format!("group {name} names element index {e}, but the file has {ne} elements"),
                ));
            };
            match *slot {
                Some(q) if q != p => {
                    return Err(elem_err(
                        raw,
                        e as usize,
                        format!(
                        "is in two parts, {} and {} (an element is in one block_<n> or in rock)",
                        group_name(q),
                        group_name(p)
                    ),
                    ))
                }
                _ => *slot = Some(p),
            }
        }
    }
    let Some(&last) = blocks.last() else {
        let names: Vec<&str> = raw.element_groups.keys().map(|s| s.as_str()).collect();
        return Err(groups_err(
            raw,
            format!(
                "no element group block_<n>: the dam's blocks must be element groups block_1, block_2, … \
                 from the left bank (groups found: {})",
                if names.is_empty() { "none".to_string() } else { names.join(", ") }
            ),
        ));
    };
    if let Some(missing) = (1..=last).find(|b| !blocks.contains(b)) {
        let found: Vec<String> = blocks.iter().map(|&b| group_name(b)).collect();
        return Err(groups_err(
            raw,
            format!(
                "block numbers have a gap: block_{missing} is missing (found {}); blocks are numbered 1, 2, … \
                 from the left bank",
                found.join(", ")
            ),
        ));
    }
    part.iter()
        .enumerate()
        .map(|(e, p)| {
            p.ok_or_else(|| {
                elem_err(
                    raw,
                    e,
                    "is in no part: every element must be in one element group block_<n> or rock"
                        .into(),
                )
            })
        })
        .collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        [0.0; 3]
    }
}
fn mean<const N: usize>(p: &[[f64; 3]; N]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for q in p {
        for k in 0..3 {
            c[k] += q[k] / N as f64;
        }
    }
    c
}

/// A symmetry of the reference cube: new axis k = `signs[k]` · old axis
/// `axes[k]`; new corner c is old corner `perm[c]`.
struct Sym {
    perm: [usize; 8],
    axes: [usize; 3],
    signs: [f64; 3],
    det: f64,
}

/// The 48 symmetries, the identity first (so that it wins ties).
fn symmetries() -> Vec<Sym> {
    const AXES: [([usize; 3], f64); 6] = [
        ([0, 1, 2], 1.0),
        ([1, 2, 0], 1.0),
        ([2, 0, 1], 1.0),
        ([0, 2, 1], -1.0),
        ([1, 0, 2], -1.0),
        ([2, 1, 0], -1.0),
    ];
    let reference = crate::fem::hex8::NODES;
    let mut syms = Vec::with_capacity(48);
    for (axes, parity) in AXES {
        for bits in 0..8 {
            let signs = [0, 1, 2].map(|k| if bits >> k & 1 == 1 { -1.0 } else { 1.0 });
            let perm = std::array::from_fn(|c| {
                let mut old = [0.0; 3];
                for k in 0..3 {
                    old[axes[k]] = signs[k] * reference[c][k];
                }
                reference.iter().position(|r| *r == old).unwrap_or(c)
            });
            syms.push(Sym {
                perm,
                axes,
                signs,
                det: parity * signs[0] * signs[1] * signs[2],
            });
        }
    }
    syms
}

fn coords(raw: &RawMesh, h: &[u32; 8]) -> [[f64; 3]; 8] {
    h.map(|n| raw.nodes[n as usize])
}

/// The dam axis direction in plan at every block: the chord from block
/// j − 1's centroid to block j + 1's (one-sided at the ends), with the plan
/// centroids.
fn block_axes(raw: &RawMesh, part: &[u32], n_blocks: u32) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let nb = n_blocks as usize;
    let mut sum = vec![[0.0; 3]; nb];
    let mut count = vec![0usize; nb];
    for (e, h) in raw.hexes.iter().enumerate() {
        if part[e] > 0 {
            let c = mean(&coords(raw, h));
            let b = part[e] as usize - 1;
            sum[b] = [sum[b][0] + c[0], sum[b][1] + c[1], 0.0];
            count[b] += 1;
        }
    }
    let centroid: Vec<[f64; 3]> = (0..nb)
        .map(|b| {
            [
                sum[b][0] / count[b].max(1) as f64,
                sum[b][1] / count[b].max(1) as f64,
                0.0,
            ]
        })
        .collect();
    let axis = (0..nb)
        .map(|b| {
            let d = unit(sub(
                centroid[(b + 1).min(nb - 1)],
                centroid[b.saturating_sub(1)],
            ));
            if nb == 1 || norm(d) == 0.0 {
                [1.0, 0.0, 0.0]
            } else {
                d
            }
        })
        .collect();
    (axis, centroid)
}

/// Step 2: every element's corners in the dam's order (module docs).
fn orient(raw: &RawMesh, part: &[u32], n_blocks: u32) -> Result<Vec<[u32; 8]>, DamMeshError> {
    let syms = symmetries();
    let (axis, centroid) = block_axes(raw, part, n_blocks);
    let mut out = Vec::with_capacity(raw.hexes.len());
    for (e, h) in raw.hexes.iter().enumerate() {
        let x = coords(raw, h);
        let d = if part[e] > 0 {
            axis[part[e] as usize - 1]
        } else {
            let c = mean(&x);
            let near = (0..centroid.len())
                .min_by(|&a, &b| {
                    let da = (centroid[a][0] - c[0]).hypot(centroid[a][1] - c[1]);
                    let db = (centroid[b][0] - c[0]).hypot(centroid[b][1] - c[1]);
                    da.total_cmp(&db)
                })
                .unwrap_or(0);
            axis[near]
        };
        // ∂x/∂ξ_k at the centre.
        let g: [[f64; 3]; 3] = std::array::from_fn(|k| {
            let mut v = [0.0; 3];
            for (c, p) in x.iter().enumerate() {
                for i in 0..3 {
                    v[i] += 0.125 * crate::fem::hex8::NODES[c][k] * p[i];
                }
            }
            v
        });
        let det_g = dot(g[0], cross(g[1], g[2]));
        let mut best: Option<(f64, f64, usize)> = None;
        for (i, s) in syms.iter().enumerate() {
            if det_g.is_nan() || s.det * det_g <= 0.0 {
                continue;
            }
            let zeta = g[s.axes[2]].map(|v| s.signs[2] * v);
            let xi = g[s.axes[0]].map(|v| s.signs[0] * v);
            let score = (unit(zeta)[2], dot(unit(xi), d));
            if best.is_none_or(|b| score.0 > b.0 || (score.0 == b.0 && score.1 > b.1)) {
                best = Some((score.0, score.1, i));
            }
        }
        let perm = best.map_or(syms[0].perm, |b| syms[b.2].perm);
        let oriented: [u32; 8] = perm.map(|c| h[c]);
        check_jacobian(raw, e, part[e], &oriented)?;
        out.push(oriented);
    }
    Ok(out)
}

/// After orientation η = ζ × ξ points downstream only if the blocks run
/// from the left bank with y downstream: the concrete's mean η must have
/// y > 0, else the numbering or the axes are the other way round.
fn check_downstream(raw: &RawMesh, part: &[u32], corners: &[[u32; 8]]) -> Result<(), DamMeshError> {
    let mut sum = 0.0;
    for (h, _) in corners.iter().zip(part).filter(|(_, &p)| p > 0) {
        let x = coords(raw, h);
        // η runs from face 2 (corners 0, 1, 5, 4) to face 4 (2, 3, 7, 6).
        let up = mean(&[x[0], x[1], x[5], x[4]]);
        let down = mean(&[x[2], x[3], x[7], x[6]]);
        sum += unit(sub(down, up))[1];
    }
    if sum <= 0.0 {
        return Err(groups_err(
            raw,
            "the blocks run from the right bank to the left: number them block_1, block_2, … from the left bank \
             (on the left looking downstream, along +y; z up)"
                .to_string(),
        ));
    }
    Ok(())
}

/// The smallest corner Jacobian must be clearly positive (relative to the
/// element's size), else the element is inverted or degenerate.
fn check_jacobian(raw: &RawMesh, e: usize, part: u32, h: &[u32; 8]) -> Result<(), DamMeshError> {
    let x = coords(raw, h);
    let lo = x
        .iter()
        .fold([f64::INFINITY; 3], |m, p| [0, 1, 2].map(|k| m[k].min(p[k])));
    let hi = x.iter().fold([f64::NEG_INFINITY; 3], |m, p| {
        [0, 1, 2].map(|k| m[k].max(p[k]))
    });
    let diag = norm(sub(hi, lo));
    let (corner, det) = crate::fem::hex8::NODES
        .iter()
        .enumerate()
        .map(|(c, r)| (c, hex_jacobian_det(&x, r[0], r[1], r[2])))
        .fold((0, f64::INFINITY), |m, c| {
            if c.1 < m.1 || c.1.is_nan() {
                c
            } else {
                m
            }
        });
    if det.is_nan() || det <= 1e-12 * diag.powi(3) {
        let n = h[corner] as usize;
        return Err(elem_err(
            raw,
            e,
            format!(
                "({}) is inverted or degenerate: its Jacobian determinant is {det:.3e} m³ at its corner node {} {} \
                 in every corner order (its corners must bound a convex hexahedron)",
                part_name(part),
                raw.node_ids[n],
                at(raw.nodes[n])
            ),
        ));
    }
    Ok(())
}

/// A uniform hash grid of cells of size `h`.
struct Hash3 {
    h: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
    /// Boxes over more than [`Hash3::MAX_CELLS`] cells, tried for every point.
    big: Vec<u32>,
}

impl Hash3 {
    /// A box covering more cells than this goes to `big` (a file's few huge
    /// faces must not fill the memory).
    const MAX_CELLS: i128 = 512;

    fn new(h: f64) -> Hash3 {
        Hash3 {
            h,
            cells: HashMap::new(),
            big: Vec::new(),
        }
    }
    fn key(&self, p: [f64; 3]) -> [i64; 3] {
        p.map(|v| (v / self.h).floor() as i64)
    }
    /// Put `id` in every cell the box [lo, hi] touches.
    fn insert_box(&mut self, lo: [f64; 3], hi: [f64; 3], id: u32) {
        let (a, b) = (self.key(lo), self.key(hi));
        let count: i128 = (0..3).map(|k| b[k] as i128 - a[k] as i128 + 1).product();
        if count > Self::MAX_CELLS {
            self.big.push(id);
            return;
        }
        for i in a[0]..=b[0] {
            for j in a[1]..=b[1] {
                for k in a[2]..=b[2] {
                    self.cells.entry([i, j, k]).or_default().push(id);
                }
            }
        }
    }
    /// The boxes that may hold `p`.
    fn near(&self, p: [f64; 3]) -> impl Iterator<Item = u32> + '_ {
        let cell = self
            .cells
            .get(&self.key(p))
            .map_or(&[][..], |v| v.as_slice());
        cell.iter().chain(&self.big).copied()
    }
}

/// A point of the mesh touched by elements: its parts.
#[derive(Debug, Clone, Copy)]
struct Role {
    rock: bool,
    /// Smallest and largest block touching it (0: none).
    lo: u32,
    hi: u32,
}

impl Role {
    /// Two copies: blocks j and j + 1 meet here away from rock.
    fn dup(&self) -> bool {
        !self.rock && self.lo > 0 && self.hi == self.lo + 1
    }
}

/// The mesh's nodes, elements and thermal dofs.
struct Numbered {
    nodes: Vec<[f64; 3]>,
    elements: Vec<[u32; 8]>,
    thermal_dof: Vec<u32>,
    n_dofs: u32,
}

/// Per element and local face: the element and local face across it
/// (`NONE` on the boundary).
type Adj = Vec<[(u32, u8); 6]>;

/// The concrete layers: boundaries and each element's layer.
struct Layers {
    z: Vec<f64>,
    /// Per element (`NONE` for rock).
    of: Vec<u32>,
}

/// Lifts: layers per lift, (base layer, lifts) per block, each element's lift.
struct Lifts {
    per_lift: u32,
    blocks: Vec<(u32, u32)>,
    lift_of: Vec<u32>,
}

/// The file with its parts and oriented elements, and its coincident points.
struct Dam<'a> {
    raw: &'a RawMesh,
    part: Vec<u32>,
    n_blocks: u32,
    /// File node indices in the dam's corner order.
    corners: Vec<[u32; 8]>,
    /// Per file node: its point (coincident nodes share one; `NONE` unused).
    class: Vec<u32>,
    /// Per point: its first file node.
    class_node: Vec<u32>,
    /// Coincidence tolerance: 1e-9 of the model's size.
    tol: f64,
    /// Level tolerance: 1e-6 of the dam's height.
    tol_z: f64,
    has_rock: bool,
}

impl<'a> Dam<'a> {
    fn new(raw: &'a RawMesh, part: Vec<u32>, n_blocks: u32, corners: Vec<[u32; 8]>) -> Dam<'a> {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let (mut zlo, mut zhi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (e, h) in corners.iter().enumerate() {
            for &n in h {
                let p = raw.nodes[n as usize];
                lo = [0, 1, 2].map(|k| lo[k].min(p[k]));
                hi = [0, 1, 2].map(|k| hi[k].max(p[k]));
                if part[e] > 0 {
                    zlo = zlo.min(p[2]);
                    zhi = zhi.max(p[2]);
                }
            }
        }
        let size = norm(sub(hi, lo));
        let tol = (1e-9 * size).max(f64::MIN_POSITIVE);
        let has_rock = part.contains(&0);
        let mut dam = Dam {
            raw,
            part,
            n_blocks,
            corners,
            class: Vec::new(),
            class_node: Vec::new(),
            tol,
            tol_z: (1e-6 * (zhi - zlo)).max(tol),
            has_rock,
        };
        dam.merge_nodes();
        dam
    }

    /// Coincident used nodes → one point each (union–find over a hash grid
    /// of cells 4·tol, searching the 27 cells around each node).
    fn merge_nodes(&mut self) {
        let nn = self.raw.nodes.len();
        let mut used = vec![false; nn];
        for h in &self.corners {
            for &n in h {
                used[n as usize] = true;
            }
        }
        let mut parent: Vec<u32> = (0..nn as u32).collect();
        let mut grid = Hash3::new(4.0 * self.tol);
        for n in (0..nn).filter(|&n| used[n]) {
            let p = self.raw.nodes[n];
            let k = grid.key(p);
            for di in -1..=1 {
                for dj in -1..=1 {
                    for dk in -1..=1 {
                        let key = [
                            k[0].wrapping_add(di),
                            k[1].wrapping_add(dj),
                            k[2].wrapping_add(dk),
                        ];
                        let Some(list) = grid.cells.get(&key) else {
                            continue;
                        };
                        for &m in list {
                            if norm(sub(p, self.raw.nodes[m as usize])) <= self.tol {
                                union(&mut parent, n as u32, m);
                            }
                        }
                    }
                }
            }
            grid.cells.entry(k).or_default().push(n as u32);
        }
        let mut class = vec![NONE; nn];
        let mut of_root: HashMap<u32, u32> = HashMap::new();
        for n in (0..nn).filter(|&n| used[n]) {
            let r = find(&mut parent, n as u32);
            let next = self.class_node.len() as u32;
            let c = *of_root.entry(r).or_insert(next);
            if c == next {
                self.class_node.push(n as u32);
            }
            class[n] = c;
        }
        self.class = class;
    }

    fn eid(&self, e: usize) -> u64 {
        self.raw.elem_ids[e]
    }

    fn point(&self, c: u32) -> [f64; 3] {
        self.raw.nodes[self.class_node[c as usize] as usize]
    }

    fn face_points(&self, e: usize, f: usize) -> [[f64; 3]; 4] {
        HEX_FACES[f].map(|c| self.raw.nodes[self.corners[e][c] as usize])
    }

    fn face_classes(&self, e: usize, f: usize) -> [u32; 4] {
        HEX_FACES[f].map(|c| self.class[self.corners[e][c] as usize])
    }

    /// The parts touching every point; blocks j and k ≠ j ± 1 must not touch.
    fn roles(&self) -> Result<Vec<Role>, DamMeshError> {
        let mut roles = vec![
            Role {
                rock: false,
                lo: 0,
                hi: 0
            };
            self.class_node.len()
        ];
        for (e, h) in self.corners.iter().enumerate() {
            for &n in h {
                let r = &mut roles[self.class[n as usize] as usize];
                match self.part[e] {
                    0 => r.rock = true,
                    b if r.lo == 0 => (r.lo, r.hi) = (b, b),
                    b => (r.lo, r.hi) = (r.lo.min(b), r.hi.max(b)),
                }
            }
        }
        if let Some(c) = roles.iter().position(|r| r.hi > r.lo + 1) {
            let n = self.class_node[c] as usize;
            return Err(dam_err(
                self.raw,
                format!(
                    "blocks {} and {} touch at node {} {}: only neighbouring blocks j and j + 1 may meet",
                    roles[c].lo,
                    roles[c].hi,
                    self.raw.node_ids[n],
                    at(self.raw.nodes[n])
                ),
            ));
        }
        Ok(roles)
    }

    /// Step 4: faces matched by their corner points; a face of three elements is an error.
    fn faces(&self) -> Result<Adj, DamMeshError> {
        let ne = self.corners.len();
        let mut adj: Adj = vec![[(NONE, 0); 6]; ne];
        let mut map: HashMap<[u32; 4], (u32, u8)> = HashMap::with_capacity(4 * ne);
        for e in 0..ne {
            for f in 0..6 {
                let mut key = self.face_classes(e, f);
                key.sort_unstable();
                match map.get(&key).copied() {
                    None => {
                        map.insert(key, (e as u32, f as u8));
                    }
                    Some((NONE, _)) => {
                        return Err(elem_err(
                            self.raw,
                            e,
                            format!(
                                "its face {f} centred at {} is shared by three or more elements",
                                at(mean(&self.face_points(e, f)))
                            ),
                        ))
                    }
                    Some((e2, f2)) => {
                        adj[e][f] = (e2, f2);
                        adj[e2 as usize][f2 as usize] = (e as u32, f as u8);
                        map.insert(key, (NONE, 0));
                    }
                }
            }
        }
        Ok(adj)
    }

    /// A face between blocks j and j + 1 is block j's face 3 and block
    /// j + 1's face 5, corner for corner.
    fn check_joint_faces(&self, adj: &Adj) -> Result<(), DamMeshError> {
        for (e, faces) in adj.iter().enumerate() {
            for (f, &(e2, f2)) in faces.iter().enumerate() {
                if e2 == NONE {
                    continue;
                }
                let (pa, pb) = (self.part[e], self.part[e2 as usize]);
                if pa == 0 || pb != pa + 1 {
                    continue;
                }
                let matched = f == 3
                    && f2 == 5
                    && [1, 2, 6, 5].map(|c| self.class[self.corners[e][c] as usize])
                        == [0, 3, 7, 4].map(|c| self.class[self.corners[e2 as usize][c] as usize]);
                if !matched {
                    return Err(elem_err(
                        self.raw,
                        e,
                        format!(
                            "(block {pa}) meets block {pb} (element {}) on its face centred at {}, which does not \
                             cross the dam axis: a joint face must be vertical, with both elements' layers level",
                            self.eid(e2 as usize),
                            at(mean(&self.face_points(e, f)))
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A boundary face whose centre lies on a boundary face of another part
    /// (at least one of them concrete) is a non-conforming joint or contact.
    fn check_conforming(&self, adj: &Adj) -> Result<(), DamMeshError> {
        let bound: Vec<(usize, usize)> = (0..adj.len())
            .flat_map(|e| (0..6).map(move |f| (e, f)))
            .filter(|&(e, f)| adj[e][f].0 == NONE)
            .collect();
        let quads: Vec<[[f64; 3]; 4]> =
            bound.iter().map(|&(e, f)| self.face_points(e, f)).collect();
        let diam = |q: &[[f64; 3]; 4]| norm(sub(q[2], q[0])).max(norm(sub(q[3], q[1])));
        let h = quads.iter().map(diam).sum::<f64>() / quads.len().max(1) as f64;
        let mut grid = Hash3::new(h.max(self.tol));
        for (i, q) in quads.iter().enumerate() {
            let lo = q
                .iter()
                .fold([f64::INFINITY; 3], |m, p| [0, 1, 2].map(|k| m[k].min(p[k])));
            let hi = q.iter().fold([f64::NEG_INFINITY; 3], |m, p| {
                [0, 1, 2].map(|k| m[k].max(p[k]))
            });
            grid.insert_box(lo.map(|v| v - self.tol), hi.map(|v| v + self.tol), i as u32);
        }
        for (i, q) in quads.iter().enumerate() {
            let (e, _) = bound[i];
            let c = mean(q);
            let tol_n = 1e-4 * diam(q) + self.tol;
            for j in grid.near(c) {
                let (e2, _) = bound[j as usize];
                let (p, p2) = (self.part[e], self.part[e2]);
                if p == p2 || (p == 0 && p2 == 0) || !on_quad(c, &quads[j as usize], tol_n) {
                    continue;
                }
                let (lo, hi) = (p.min(p2), p.max(p2));
                let what = if lo == 0 {
                    format!("non-conforming contact between block {hi} and the rock")
                } else if hi == lo + 1 {
                    format!("non-conforming joint between block {lo} and block {hi}")
                } else {
                    format!("blocks {lo} and {hi} touch (only neighbouring blocks j and j + 1 may meet)")
                };
                return Err(dam_err(
                    self.raw,
                    format!(
                        "{what}: the face of element {} ({}) centred at {} lies on the face of element {} ({}) \
                         but does not match it node for node",
                        self.eid(e),
                        part_name(p),
                        at(c),
                        self.eid(e2),
                        part_name(p2)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Step 5: every block reaches the rock (or, without rock, the lowest
    /// concrete level) through shared faces.
    fn check_floating(&self, adj: &Adj) -> Result<(), DamMeshError> {
        let ne = self.corners.len();
        let mut parent: Vec<u32> = (0..ne as u32).collect();
        for (e, faces) in adj.iter().enumerate() {
            for &(e2, _) in faces {
                if e2 != NONE {
                    union(&mut parent, e as u32, e2);
                }
            }
        }
        let bottom = |e: usize| {
            (0..4)
                .map(|c| self.raw.nodes[self.corners[e][c] as usize][2])
                .fold(f64::INFINITY, f64::min)
        };
        let z0 = (0..ne)
            .filter(|&e| self.part[e] > 0)
            .map(bottom)
            .fold(f64::INFINITY, f64::min);
        let mut grounded = vec![false; ne];
        for e in 0..ne {
            if (self.has_rock && self.part[e] == 0)
                || (!self.has_rock && bottom(e) <= z0 + self.tol_z)
            {
                grounded[find(&mut parent, e as u32) as usize] = true;
            }
        }
        for b in 1..=self.n_blocks {
            let Some(e) = (0..ne)
                .find(|&e| self.part[e] == b && !grounded[find(&mut parent, e as u32) as usize])
            else {
                continue;
            };
            let to = if self.has_rock {
                "the rock".to_string()
            } else {
                format!("the lowest concrete level (z = {z0:.3} m)")
            };
            let centre = mean(&coords(self.raw, &self.corners[e]));
            return Err(block_err(
                self.raw,
                b,
                format!(
                    "is floating: its element {} at {} shares no face, directly or through other blocks, with {to}",
                    self.eid(e),
                    at(centre)
                ),
            ));
        }
        Ok(())
    }

    /// Step 6a: level faces, the layer boundaries, each element's layer.
    fn layers(&self) -> Result<Layers, DamMeshError> {
        let ne = self.corners.len();
        let mut levels: Vec<(f64, u32)> = Vec::new();
        let mut faces = vec![(0.0, 0.0); ne];
        for e in (0..ne).filter(|&e| self.part[e] > 0) {
            let mut z = [0.0; 2];
            for (side, name) in [(0, "bottom"), (1, "top")] {
                let zs =
                    [0, 1, 2, 3].map(|c| self.raw.nodes[self.corners[e][4 * side + c] as usize][2]);
                let lo = zs.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = zs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                if hi - lo > self.tol_z {
                    return Err(elem_err(
                        self.raw,
                        e,
                        format!(
                            "(block {}) its {name} face is not level: its corners lie at z = {:.3}, {:.3}, {:.3}, \
                             {:.3} m (concrete element layers must be horizontal, to {:.1e} m)",
                            self.part[e], zs[0], zs[1], zs[2], zs[3], self.tol_z
                        ),
                    ));
                }
                z[side] = lo;
                levels.push((lo, e as u32));
            }
            faces[e] = (z[0], z[1]);
        }
        levels.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut z: Vec<f64> = Vec::new();
        let mut first_elem: Vec<u32> = Vec::new();
        for &(v, e) in &levels {
            if z.last().is_none_or(|&l| v - l > self.tol_z) {
                z.push(v);
                first_elem.push(e);
            }
        }
        let index = |v: f64| z.partition_point(|&l| l <= v).saturating_sub(1);
        let mut of = vec![NONE; ne];
        for e in (0..ne).filter(|&e| self.part[e] > 0) {
            let (lb, lt) = (index(faces[e].0), index(faces[e].1));
            if lt == lb + 1 {
                of[e] = lb as u32;
                continue;
            }
            let message = if lt <= lb {
                format!(
                    "(block {}) its top face is not above its bottom face",
                    self.part[e]
                )
            } else {
                let other = first_elem[lb + 1] as usize;
                format!(
                    "(block {}) spans z = {:.3} … {:.3} m across the level z = {:.3} m of element {} (block {}): \
                     element layers must line up across the whole dam",
                    self.part[e],
                    faces[e].0,
                    faces[e].1,
                    z[lb + 1],
                    self.eid(other),
                    self.part[other]
                )
            };
            return Err(elem_err(self.raw, e, message));
        }
        Ok(Layers { z, of })
    }

    /// Step 6b: each block's lifts from its foundation, the layers per lift,
    /// foundations on zone boundaries, named lift groups.
    fn lifts(
        &self,
        layers: &Layers,
        lift_height: f64,
        zone_lifts: u32,
    ) -> Result<Lifts, DamMeshError> {
        let mut per_lift = 0u32;
        let mut blocks = Vec::with_capacity(self.n_blocks as usize);
        for b in 1..=self.n_blocks {
            let bounds = self.lift_bounds(b, layers, lift_height)?;
            for (m, w) in bounds.windows(2).enumerate() {
                let n = w[1] - w[0];
                if per_lift == 0 {
                    per_lift = n;
                } else if n != per_lift {
                    return Err(block_err(
                        self.raw,
                        b,
                        format!(
                            "lift {} (z = {:.3} … {:.3} m) holds {n} element layers, but lift 1 of block 1 holds \
                             {per_lift}: every lift must have the same number of layers",
                            m + 1,
                            layers.z[w[0] as usize],
                            layers.z[w[1] as usize]
                        ),
                    ));
                }
            }
            blocks.push((bounds[0], bounds.len() as u32 - 1));
        }
        let band = zone_lifts as usize * per_lift as usize;
        for (b, &(base, _)) in blocks.iter().enumerate() {
            if !(base as usize).is_multiple_of(band) {
                let below = base as usize / band * band;
                let above = (below + band).min(layers.z.len() - 1);
                return Err(block_err(
                    self.raw,
                    b as u32 + 1,
                    format!(
                        "its foundation at z = {:.3} m is not on a zone boundary: zones are bands of {zone_lifts} \
                         lifts from the lowest concrete level z = {:.3} m; the nearest boundaries are z = {:.3} and \
                         {:.3} m",
                        layers.z[base as usize], layers.z[0], layers.z[below], layers.z[above]
                    ),
                ));
            }
        }
        let lift_of = (0..self.part.len())
            .map(|e| match self.part[e] {
                0 => 0,
                b => (layers.of[e] - blocks[b as usize - 1].0) / per_lift + 1,
            })
            .collect();
        let lifts = Lifts {
            per_lift,
            blocks,
            lift_of,
        };
        self.check_lift_groups(&lifts, layers)?;
        Ok(lifts)
    }

    /// Layer indices of block `b`'s lift boundaries, foundation to top.
    fn lift_bounds(&self, b: u32, layers: &Layers, lift: f64) -> Result<Vec<u32>, DamMeshError> {
        let n_layers = layers.z.len() - 1;
        let mut present = vec![false; n_layers];
        for e in (0..self.part.len()).filter(|&e| self.part[e] == b) {
            present[layers.of[e] as usize] = true;
        }
        let base = present.iter().position(|&p| p).unwrap_or(0);
        let top = present.iter().rposition(|&p| p).map_or(base + 1, |t| t + 1);
        if let Some(gap) = (base..top).find(|&l| !present[l]) {
            return Err(block_err(
                self.raw,
                b,
                format!(
                    "has no element between z = {:.3} and {:.3} m (its layers must run from its foundation to its top)",
                    layers.z[gap],
                    layers.z[gap + 1]
                ),
            ));
        }
        let (zb, zt) = (layers.z[base], layers.z[top]);
        let ratio = (zt - zb) / lift;
        if ratio > 1e6 {
            return Err(block_err(
                self.raw,
                b,
                format!("is more than a million lifts of {lift} m high"),
            ));
        }
        let n = (ratio.round() as usize).max(1);
        let mut bounds = vec![base as u32];
        for m in 1..n {
            let target = zb + m as f64 * lift;
            let l = layers.z.partition_point(|&v| v < target - self.tol_z);
            if l >= top || (layers.z[l] - target).abs() > self.tol_z {
                return Err(block_err(
                    self.raw,
                    b,
                    format!(
                        "its layers do not make lifts of {lift} m from its foundation at z = {zb:.3} m: no layer \
                         boundary at z = {target:.3} m (the nearest are z = {:.3} and {:.3} m)",
                        layers.z[l.saturating_sub(1)],
                        layers.z[l.min(n_layers)]
                    ),
                ));
            }
            bounds.push(l as u32);
        }
        bounds.push(top as u32);
        Ok(bounds)
    }

    /// Groups `block_<n>_lift_<m>` hold exactly the elements of that lift.
    fn check_lift_groups(&self, lifts: &Lifts, layers: &Layers) -> Result<(), DamMeshError> {
        let mut named = vec![false; self.part.len()];
        let mut naming_blocks = BTreeSet::new();
        for (name, elems) in &self.raw.element_groups {
            let Some(Group::Lift(b, m)) = group_kind(name) else {
                continue;
            };
            naming_blocks.insert(b);
            for &e in elems {
                let e = e as usize;
                if e >= self.part.len() || self.part[e] != b {
                    let p = self.part.get(e).copied().unwrap_or(0);
                    return Err(elem_err(
                        self.raw,
                        e,
                        format!("is in {name} but in {}", part_name(p)),
                    ));
                }
                named[e] = true;
                if lifts.lift_of[e] != m {
                    let l = layers.of[e] as usize;
                    return Err(elem_err(
                        self.raw,
                        e,
                        format!(
                            "is in {name} but lies in lift {} of block {b} (z = {:.3} … {:.3} m)",
                            lifts.lift_of[e],
                            layers.z[l],
                            layers.z[l + 1]
                        ),
                    ));
                }
            }
        }
        if let Some(e) =
            (0..self.part.len()).find(|&e| naming_blocks.contains(&self.part[e]) && !named[e])
        {
            return Err(elem_err(
                self.raw,
                e,
                format!(
                    "is in no group block_{}_lift_<m>, although its block names its lifts",
                    self.part[e]
                ),
            ));
        }
        Ok(())
    }

    /// Which copy of point `c` element `e` uses: 1 (copy B) for block j + 1 on a joint point.
    fn copy(&self, roles: &[Role], e: usize, c: u32) -> usize {
        let r = roles[c as usize];
        usize::from(r.dup() && self.part[e] == r.hi)
    }

    /// Step 3: nodes in the file's order of first use, copy A before copy B,
    /// one thermal dof per point.
    fn number(&self, roles: &[Role]) -> Numbered {
        let nn = self.raw.nodes.len();
        let mut served = vec![0u8; nn];
        for (e, h) in self.corners.iter().enumerate() {
            for &n in h {
                served[n as usize] |= 1 << self.copy(roles, e, self.class[n as usize]);
            }
        }
        let mut id = vec![[NONE; 2]; self.class_node.len()];
        let mut dof = vec![NONE; self.class_node.len()];
        let (mut nodes, mut thermal_dof, mut n_dofs) = (Vec::new(), Vec::new(), 0u32);
        for (n, &serves) in served.iter().enumerate() {
            let c = self.class[n] as usize;
            for copy in [0, 1] {
                if serves >> copy & 1 == 0 || id[c][copy] != NONE {
                    continue;
                }
                id[c][copy] = nodes.len() as u32;
                nodes.push(self.point(c as u32));
                if dof[c] == NONE {
                    dof[c] = n_dofs;
                    n_dofs += 1;
                }
                thermal_dof.push(dof[c]);
            }
        }
        let elements = self
            .corners
            .iter()
            .enumerate()
            .map(|(e, h)| {
                h.map(|n| {
                    let c = self.class[n as usize];
                    id[c as usize][self.copy(roles, e, c)]
                })
            })
            .collect();
        Numbered {
            nodes,
            elements,
            thermal_dof,
            n_dofs,
        }
    }

    /// Face pairs sorted by (joint, layer, position upstream → downstream
    /// along the mean s direction of that joint's layer).
    fn face_pairs(
        &self,
        adj: &Adj,
        layers: &Layers,
        num: &Numbered,
        per_zone: u32,
    ) -> Vec<FacePair> {
        let mut found: Vec<(u32, u32, u32, u32)> = Vec::new();
        for (e, faces) in adj.iter().enumerate() {
            let (e2, _) = faces[3];
            if e2 != NONE && self.part[e] > 0 && self.part[e2 as usize] == self.part[e] + 1 {
                found.push((self.part[e], layers.of[e], e as u32, e2));
            }
        }
        let corners =
            |e: u32| [1, 2, 6, 5].map(|c| num.nodes[num.elements[e as usize][c] as usize]);
        let mut across: HashMap<(u32, u32), [f64; 3]> = HashMap::new();
        for &(j, l, ea, _) in &found {
            let q = corners(ea);
            let s = across.entry((j, l)).or_default();
            *s = [0, 1, 2].map(|k| s[k] + q[1][k] - q[0][k]);
        }
        let mut keyed: Vec<(u32, u32, f64, u32, u32)> = found
            .iter()
            .map(|&(j, l, ea, eb)| (j, l, dot(mean(&corners(ea)), unit(across[&(j, l)])), ea, eb))
            .collect();
        keyed.sort_by(|a, b| (a.0, a.1).cmp(&(b.0, b.1)).then(a.2.total_cmp(&b.2)));
        keyed
            .into_iter()
            .map(|(joint, layer, _, ea, eb)| {
                let a = num.elements[ea as usize];
                let b = num.elements[eb as usize];
                FacePair {
                    joint,
                    zone: layer / per_zone + 1,
                    layer,
                    elem_a: ea,
                    elem_b: eb,
                    nodes_a: [a[1], a[2], a[6], a[5]],
                    nodes_b: [b[0], b[3], b[7], b[4]],
                }
            })
            .collect()
    }

    /// Zones: runs of pairs of one (joint, zone), each a whole band with the
    /// same number of faces across in every layer.
    fn zones(
        &self,
        pairs: &[FacePair],
        z: &[f64],
        per_zone: u32,
    ) -> Result<Vec<Zone>, DamMeshError> {
        let n_layers = z.len() as u32 - 1;
        let mut zones: Vec<Zone> = Vec::new();
        for (p, fp) in pairs.iter().enumerate() {
            match zones.last_mut() {
                Some(zn) if zn.joint == fp.joint && zn.zone == fp.zone => zn.pairs.push(p as u32),
                _ => {
                    let first = (fp.zone - 1) * per_zone;
                    let end = (fp.zone * per_zone).min(n_layers);
                    zones.push(Zone {
                        joint: fp.joint,
                        zone: fp.zone,
                        z_bottom: z[first as usize],
                        z_top: z[end as usize],
                        pairs: vec![p as u32],
                    });
                }
            }
        }
        for zn in &zones {
            let first = (zn.zone - 1) * per_zone;
            let end = (zn.zone * per_zone).min(n_layers);
            let counts: Vec<usize> = (first..end)
                .map(|l| {
                    zn.pairs
                        .iter()
                        .filter(|&&p| pairs[p as usize].layer == l)
                        .count()
                })
                .collect();
            if counts.iter().any(|&c| c == 0 || c != counts[0]) {
                return Err(dam_err(
                    self.raw,
                    format!(
                        "joint {} zone {} (z = {:.3} … {:.3} m) has {counts:?} joint faces across in its layers: \
                         a zone needs the same number of faces across in every layer",
                        zn.joint, zn.zone, zn.z_bottom, zn.z_top
                    ),
                ));
            }
        }
        Ok(zones)
    }

    /// Step 7: the outer faces and their kinds (module docs).
    fn surfaces(&self, adj: &Adj) -> Vec<SurfaceFace> {
        let mut bound: Vec<(u32, u8)> = Vec::new();
        for (e, faces) in adj.iter().enumerate() {
            for (f, &(e2, _)) in faces.iter().enumerate() {
                if e2 == NONE {
                    bound.push((e as u32, f as u8));
                }
            }
        }
        let walls = Walls::new(self, &bound);
        let wet: Vec<([f64; 3], [f64; 3])> = bound
            .iter()
            .filter(|&&(e, f)| f == 2 && self.part[e as usize] > 0)
            .map(|&(e, f)| {
                let q = self.face_points(e as usize, f as usize);
                (mean(&q), unit(quad4::normal_scaled(&q, [0.0, 0.0])))
            })
            .collect();
        let nearest = Nearest::new(&wet);
        let overrides = ["far", "upstream", "air"].map(|g| self.group_points(g));
        bound
            .iter()
            .map(|&(e, f)| {
                let (eu, fu) = (e as usize, f as usize);
                let mut kind = if self.part[eu] > 0 {
                    match f {
                        0 if !self.has_rock => SurfaceKind::Far,
                        2 => SurfaceKind::Wet,
                        _ => SurfaceKind::Ground,
                    }
                } else if f != 1 && walls.far(self, eu, fu) {
                    SurfaceKind::Far
                } else {
                    let c = mean(&self.face_points(eu, fu));
                    match nearest.find(&wet, c) {
                        Some(i) if dot(sub(c, wet[i].0), wet[i].1) > 0.0 => SurfaceKind::Wet,
                        _ => SurfaceKind::Ground,
                    }
                };
                let classes = self.face_classes(eu, fu);
                for (g, k) in
                    overrides
                        .iter()
                        .zip([SurfaceKind::Far, SurfaceKind::Wet, SurfaceKind::Ground])
                {
                    if let Some(set) = g {
                        if classes.iter().all(|&c| set[c as usize]) {
                            kind = k;
                            break;
                        }
                    }
                }
                SurfaceFace {
                    elem: e,
                    face: f,
                    kind,
                }
            })
            .collect()
    }

    /// Points in node group `name`, in any case (a point is in it when one
    /// of its file nodes is).
    fn group_points(&self, name: &str) -> Option<Vec<bool>> {
        let (_, nodes) = self
            .raw
            .node_groups
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))?;
        let mut set = vec![false; self.class_node.len()];
        for &n in nodes {
            if let Some(&c) = self.class.get(n as usize).filter(|&&c| c != NONE) {
                set[c as usize] = true;
            }
        }
        Some(set)
    }
}

/// Zone points as the generators place them: at the zone's mid height, on
/// the first, middle (the upstream one of the two middle ones, at its
/// downstream edge, when the count is even) and last pair across.
fn zone_points(
    zones: &[Zone],
    pairs: &[FacePair],
    z: &[f64],
    per_zone: u32,
    nodes: &[[f64; 3]],
) -> Vec<ZoneSite> {
    let mut out = Vec::with_capacity(3 * zones.len());
    for zn in zones {
        let first = ((zn.zone - 1) * per_zone) as usize;
        let end = ((zn.zone * per_zone) as usize).min(z.len() - 1);
        let zm = 0.5 * (zn.z_bottom + zn.z_top);
        let scale = 1e-12 * (1.0 + zm.abs());
        let layer = (first..end)
            .find(|&l| z[l + 1] >= zm - scale)
            .unwrap_or(end - 1);
        let t = (2.0 * (zm - z[layer]) / (z[layer + 1] - z[layer]) - 1.0).clamp(-1.0, 1.0);
        let row: Vec<u32> = zn
            .pairs
            .iter()
            .copied()
            .filter(|&p| pairs[p as usize].layer == layer as u32)
            .collect();
        let n = row.len();
        let center = if n % 2 == 1 {
            (n / 2, 0.0)
        } else {
            (n / 2 - 1, 1.0)
        };
        for (point, (k, s)) in [
            (ZonePoint::Upstream, (0, -1.0)),
            (ZonePoint::Center, center),
            (ZonePoint::Downstream, (n - 1, 1.0)),
        ] {
            let pair = row[k];
            let corners = pairs[pair as usize].nodes_a.map(|m| nodes[m as usize]);
            out.push(ZoneSite {
                joint: zn.joint,
                zone: zn.zone,
                point,
                pair,
                s,
                t,
                xyz: quad4::point(&corners, [s, t]),
            });
        }
    }
    out
}

/// The model's walls: a side face is on a wall when the boundary below it
/// runs down through side faces to a downward face.
struct Walls {
    /// Boundary faces by their edge (two points, sorted).
    by_edge: HashMap<[u32; 2], Vec<(u32, u8)>>,
}

impl Walls {
    fn new(dam: &Dam, bound: &[(u32, u8)]) -> Walls {
        let mut by_edge: HashMap<[u32; 2], Vec<(u32, u8)>> = HashMap::new();
        for &(e, f) in bound {
            let c = dam.face_classes(e as usize, f as usize);
            for k in 0..4 {
                let mut key = [c[k], c[(k + 1) % 4]];
                key.sort_unstable();
                by_edge.entry(key).or_default().push((e, f));
            }
        }
        Walls { by_edge }
    }

    /// Whether rock side face `f` of `e` is on a wall. A side face's first
    /// two corners (`HEX_FACES`) are its bottom edge, its last two its top.
    fn far(&self, dam: &Dam, e: usize, f: usize) -> bool {
        let (mut e, mut f) = (e, f);
        for _ in 0..=self.by_edge.len() {
            if f == 0 {
                return true;
            }
            if f == 1 || dam.part[e] > 0 {
                return false;
            }
            let c = dam.face_classes(e, f);
            let mut key = [c[0], c[1]];
            key.sort_unstable();
            let others = self.by_edge.get(&key).map_or(&[][..], |v| v.as_slice());
            let below = others.iter().find(|&&(e2, f2)| {
                let c2 = dam.face_classes(e2 as usize, f2 as usize);
                (2..6).contains(&f2) && (e2 as usize, f2 as usize) != (e, f) && {
                    let mut top = [c2[2], c2[3]];
                    top.sort_unstable();
                    top == key
                }
            });
            if others.iter().any(|&(_, f2)| f2 == 0) {
                return true;
            }
            match below {
                Some(&(e2, f2)) => (e, f) = (e2 as usize, f2 as usize),
                None => return false,
            }
        }
        false
    }
}

/// Nearest of a set of points, by a plan hash grid searched in growing rings.
struct Nearest {
    h: f64,
    cells: HashMap<[i64; 2], Vec<u32>>,
    /// Rings to search at most (the extent of the set in cells, plus margin).
    max_ring: i64,
}

impl Nearest {
    fn new(points: &[([f64; 3], [f64; 3])]) -> Nearest {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (p, _) in points {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let h = extent / 64.0;
        let mut cells: HashMap<[i64; 2], Vec<u32>> = HashMap::new();
        for (i, (p, _)) in points.iter().enumerate() {
            cells
                .entry([(p[0] / h).floor() as i64, (p[1] / h).floor() as i64])
                .or_default()
                .push(i as u32);
        }
        Nearest {
            h,
            cells,
            max_ring: 66,
        }
    }

    fn find(&self, points: &[([f64; 3], [f64; 3])], q: [f64; 3]) -> Option<usize> {
        let k = [
            (q[0] / self.h).floor() as i64,
            (q[1] / self.h).floor() as i64,
        ];
        let start = self.ring_offset(k);
        // Far outside the set (which spans 64 cells) rings cost more than the set.
        if start > 16 {
            return (0..points.len())
                .min_by(|&a, &b| norm(sub(points[a].0, q)).total_cmp(&norm(sub(points[b].0, q))));
        }
        let mut best: Option<(f64, usize)> = None;
        for r in start..=start + self.max_ring {
            // Every point of ring r is at least (r − 1)·h away in plan.
            if best.is_some_and(|b| b.0 <= (r - 1).max(0) as f64 * self.h) {
                break;
            }
            let perimeter = (-r..=r)
                .flat_map(|i| [[i, -r], [i, r]])
                .chain((1 - r..r).flat_map(|j| [[-r, j], [r, j]]));
            for [i, j] in perimeter {
                let key = [k[0].wrapping_add(i), k[1].wrapping_add(j)];
                for &p in self.cells.get(&key).map_or(&[][..], |v| v.as_slice()) {
                    let d = norm(sub(points[p as usize].0, q));
                    if best.is_none_or(|b| d < b.0 || (d == b.0 && (p as usize) < b.1)) {
                        best = Some((d, p as usize));
                    }
                }
            }
        }
        best.map(|b| b.1)
    }

    /// Rings between a query cell and the set's cells (0 for a query inside).
    fn ring_offset(&self, k: [i64; 2]) -> i64 {
        self.cells
            .keys()
            .map(|c| {
                let d = |a: i64, b: i64| a.saturating_sub(b).saturating_abs();
                d(c[0], k[0]).max(d(c[1], k[1]))
            })
            .min()
            .unwrap_or(0)
    }
}

/// Whether `p` lies on the quad `q` (split in two triangles) within `tol_n`
/// of its plane, inside or on its edges.
fn on_quad(p: [f64; 3], q: &[[f64; 3]; 4], tol_n: f64) -> bool {
    [[0, 1, 2], [0, 2, 3]].iter().any(|t| {
        let (a, b, c) = (q[t[0]], q[t[1]], q[t[2]]);
        let n = cross(sub(b, a), sub(c, a));
        let nn = norm(n);
        if nn == 0.0 {
            return false;
        }
        let u = n.map(|v| v / nn);
        let dist = dot(sub(p, a), u);
        if dist.abs() > tol_n {
            return false;
        }
        let pp = [0, 1, 2].map(|k| p[k] - dist * u[k]);
        let w = [(b, c), (c, a), (a, b)].map(|(x, y)| dot(cross(sub(x, pp), sub(y, pp)), u) / nn);
        w.iter().all(|&v| v >= -1e-9)
    })
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}
