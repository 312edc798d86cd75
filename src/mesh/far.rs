//! Which side of the model a far face is on: base, upstream, downstream,
//! left bank or right bank, by a geometric rule that needs nothing but the
//! [`Mesh`] (so it holds for generated and imported meshes alike).
//!
//! # The rule
//!
//! 1. Each far face's outward unit normal n is that of its quad (the cross
//!    product of its diagonals, oriented by the `HEX_FACES` order, outward
//!    for a positive Jacobian). If n points down by more than 45°
//!    (n_z ≤ −1/√2) the face is on the **base**; so is a far face whose
//!    normal has no horizontal part (a flat far top, which the generators
//!    never make).
//! 2. Otherwise the face is read in the dam's local plan frame at it: the
//!    axis direction t (left bank → right bank) of the block whose plan
//!    centroid (of its elements' nodes) is nearest to the face's centre,
//!    and the downstream direction d = t turned by +90° about z (t = x̂
//!    gives d = ŷ). Its reading is the larger of |n·t| (**right bank** if
//!    n·t > 0, **left bank** otherwise) and |n·d| (**downstream** if
//!    n·d > 0, **upstream** otherwise) — but a face whose normal points
//!    across towards the dam's other side (n·d and (centre − block
//!    centroid)·d of opposite signs) is read by n·t: on the arch, the end
//!    faces of the downstream margin beyond an abutment are planes x =
//!    const (the margin is laid along +y), 60° from the end block's axis
//!    at a 120° central angle, and they lie downstream of it.
//! 3. A block's axis direction is the mean of the horizontal normals of
//!    its joints (a joint's face pairs point from block j to j + 1); an end
//!    block's is its joint's turned on by half the turn between the last
//!    two joints (the block's own mid-direction on a circular arch). With
//!    one joint both blocks take it; without joints t = x̂ (the meshes'
//!    convention: x along the axis).
//! 4. The far faces are then grouped into patches: faces sharing an edge
//!    whose normals are within 45° of each other belong together (so a
//!    patch ends at the model's corners). Every face of a patch gets the
//!    patch's side: the reading of rules 1–2 with the largest total area in
//!    it.
//!
//! Rule 4 is what makes the arch right: where the downstream margin
//! reaches behind the rings' centre (Xiaowan-like: a 150 m margin behind a
//! 97 m base radius), the nearest block in plan to a downstream face near
//! an abutment may be a block across the valley, whose frame is 90° off;
//! such faces are a minority of the downstream patch, whose other faces
//! read it right. On the blocks generator every t is x̂ and the faces are
//! axis-aligned, so every face already reads right. Verified by the unit
//! tests below: every far face of both generators (with and without rock
//! margins, graded and uniform, arches of 2 to 12 blocks over 80° to 150°,
//! margins behind the centre) gets the side of its local hex face (face 0
//! base, 2 upstream, 3 right bank, 4 downstream, 5 left bank).

use serde::{Deserialize, Serialize};

use std::collections::HashMap;

use super::{Mesh, Part, SurfaceFace, SurfaceKind, HEX_FACES};

/// The side of the model a far face is on (see the module doc for the rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FarSide {
    Base,
    Upstream,
    Downstream,
    LeftBank,
    RightBank,
}

impl FarSide {
    /// Every side, in the order of the scene's `[boundary]` tables.
    pub const ALL: [FarSide; 5] = [
        FarSide::Base,
        FarSide::Upstream,
        FarSide::Downstream,
        FarSide::LeftBank,
        FarSide::RightBank,
    ];

    /// The name in scene files (`left_bank`).
    pub fn name(self) -> &'static str {
        match self {
            FarSide::Base => "base",
            FarSide::Upstream => "upstream",
            FarSide::Downstream => "downstream",
            FarSide::LeftBank => "left_bank",
            FarSide::RightBank => "right_bank",
        }
    }

    /// Index into [`FarSide::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

impl std::fmt::Display for FarSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The dam's local plan frame per block: what [`DamFrame::face_reading`] reads.
#[derive(Debug, Clone)]
pub struct DamFrame {
    /// Per block: plan centroid of its elements' nodes and unit axis direction (x, y).
    blocks: Vec<([f64; 2], [f64; 2])>,
}

impl DamFrame {
    /// The frame of `mesh`'s blocks (module doc, rule 3).
    pub fn of(mesh: &Mesh) -> DamFrame {
        let n_blocks = mesh.blocks.len();
        let mut sum = vec![[0.0f64; 3]; n_blocks];
        for (e, part) in mesh.parts.iter().enumerate() {
            if let Part::Concrete { block, .. } = *part {
                let Some(s) = sum.get_mut(block as usize - 1) else {
                    continue;
                };
                for &n in &mesh.elements[e] {
                    let p = mesh.nodes[n as usize];
                    s[0] += p[0];
                    s[1] += p[1];
                    s[2] += 1.0;
                }
            }
        }
        let joint_angle = joint_angles(mesh);
        let blocks = (0..n_blocks)
            .map(|b| {
                let count = sum[b][2].max(1.0);
                let a = block_angle(&joint_angle, b);
                ([sum[b][0] / count, sum[b][1] / count], [a.cos(), a.sin()])
            })
            .collect();
        DamFrame { blocks }
    }

    /// The reading of one face by rules 1–2 of the module doc (no patch).
    pub fn face_reading(&self, mesh: &Mesh, face: &SurfaceFace) -> FarSide {
        let (centre, n) = face_centre_normal(mesh, face);
        let horizontal = n[0].hypot(n[1]);
        if n[2] <= -std::f64::consts::FRAC_1_SQRT_2 || horizontal < 1e-12 {
            return FarSide::Base;
        }
        let (c, t) = self.nearest(centre);
        let d = [-t[1], t[0]];
        let along = n[0] * t[0] + n[1] * t[1];
        let across = n[0] * d[0] + n[1] * d[1];
        // where the face lies across the dam, from the block's centroid
        let offset = (centre[0] - c[0]) * d[0] + (centre[1] - c[1]) * d[1];
        let facing_away = across * offset < 0.0;
        if along.abs() > across.abs() || facing_away {
            if along > 0.0 {
                FarSide::RightBank
            } else {
                FarSide::LeftBank
            }
        } else if across > 0.0 {
            FarSide::Downstream
        } else {
            FarSide::Upstream
        }
    }

    /// Plan centroid and axis direction of the block whose plan centroid
    /// is nearest to `p` (the origin and x̂ without blocks).
    fn nearest(&self, p: [f64; 3]) -> ([f64; 2], [f64; 2]) {
        self.blocks
            .iter()
            .map(|&(c, t)| ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2), c, t))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(([0.0, 0.0], [1.0, 0.0]), |(_, c, t)| (c, t))
    }
}

impl Mesh {
    /// The side of every [`SurfaceKind::Far`] face, in the order of
    /// [`Mesh::surfaces`] (module doc, rules 1–4).
    pub fn far_sides(&self) -> Vec<(SurfaceFace, FarSide)> {
        let frame = DamFrame::of(self);
        let far: Vec<SurfaceFace> = self
            .surfaces
            .iter()
            .filter(|f| f.kind == SurfaceKind::Far)
            .copied()
            .collect();
        let geometry: Vec<([f64; 3], f64)> = far
            .iter()
            .map(|f| {
                let (_, n) = face_centre_normal(self, f);
                (n, face_area(self, f))
            })
            .collect();
        let patch = patches(self, &far, &geometry);
        // area of each reading per patch root
        let mut votes: HashMap<usize, [f64; 5]> = HashMap::new();
        for (i, f) in far.iter().enumerate() {
            let side = frame.face_reading(self, f);
            votes.entry(patch[i]).or_insert([0.0; 5])[side.index()] += geometry[i].1;
        }
        far.iter()
            .enumerate()
            .map(|(i, f)| {
                let v = votes[&patch[i]];
                let best = (0..5).fold(0, |b, s| if v[s] > v[b] { s } else { b });
                (*f, FarSide::ALL[best])
            })
            .collect()
    }

    /// The side of one far face; classifies every far face (rule 4 needs
    /// the patch), so for many faces call [`Mesh::far_sides`] once.
    pub fn far_side(&self, face: &SurfaceFace) -> Option<FarSide> {
        self.far_sides()
            .into_iter()
            .find(|(f, _)| f.elem == face.elem && f.face == face.face)
            .map(|(_, s)| s)
    }
}

/// Patch root of each far face (module doc, rule 4): union of faces that
/// share an edge and whose normals are within 45°.
fn patches(mesh: &Mesh, far: &[SurfaceFace], geometry: &[([f64; 3], f64)]) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..far.len()).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (i, f) in far.iter().enumerate() {
        let conn = &mesh.elements[f.elem as usize];
        let q = HEX_FACES[f.face as usize].map(|k| conn[k]);
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    for faces in by_edge.values() {
        for (x, &i) in faces.iter().enumerate() {
            for &j in &faces[x + 1..] {
                let (ni, nj) = (geometry[i].0, geometry[j].0);
                let dot = ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2];
                if dot >= std::f64::consts::FRAC_1_SQRT_2 {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    parent[ri.max(rj)] = ri.min(rj);
                }
            }
        }
    }
    (0..far.len()).map(|i| root(&mut parent, i)).collect()
}

/// Area of a hex face (half the norm of its diagonals' cross product,
/// exact for a plane quad).
fn face_area(mesh: &Mesh, face: &SurfaceFace) -> f64 {
    let conn = &mesh.elements[face.elem as usize];
    let p = HEX_FACES[face.face as usize].map(|k| mesh.nodes[conn[k] as usize]);
    let a: [f64; 3] = std::array::from_fn(|c| p[2][c] - p[0][c]);
    let b: [f64; 3] = std::array::from_fn(|c| p[3][c] - p[1][c]);
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// Centre and outward unit normal of a hex face.
pub fn face_centre_normal(mesh: &Mesh, face: &SurfaceFace) -> ([f64; 3], [f64; 3]) {
    let conn = &mesh.elements[face.elem as usize];
    let p = HEX_FACES[face.face as usize].map(|k| mesh.nodes[conn[k] as usize]);
    let centre = std::array::from_fn(|c| 0.25 * (p[0][c] + p[1][c] + p[2][c] + p[3][c]));
    let a: [f64; 3] = std::array::from_fn(|c| p[2][c] - p[0][c]);
    let b: [f64; 3] = std::array::from_fn(|c| p[3][c] - p[1][c]);
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        .sqrt()
        .max(f64::MIN_POSITIVE);
    (centre, n.map(|v| v / len))
}

/// Plan angle (from x̂, towards ŷ) of each joint's mean horizontal normal,
/// joints 1..; `None` for a joint without face pairs.
fn joint_angles(mesh: &Mesh) -> Vec<Option<f64>> {
    let n_joints = mesh.joint_count() as usize;
    let mut sum = vec![[0.0f64; 2]; n_joints];
    for fp in &mesh.face_pairs {
        let Some(s) = sum.get_mut(fp.joint as usize - 1) else {
            continue;
        };
        let face = SurfaceFace {
            elem: fp.elem_a,
            face: 3,
            kind: SurfaceKind::Ground,
        };
        let (_, n) = face_centre_normal(mesh, &face);
        s[0] += n[0];
        s[1] += n[1];
    }
    sum.iter()
        .map(|s| (s[0].hypot(s[1]) > 0.0).then(|| s[1].atan2(s[0])))
        .collect()
}

/// Axis angle of block `b` (0-based) from its joints' angles (module doc,
/// rule 3); 0 (x̂) without any joint.
fn block_angle(joints: &[Option<f64>], b: usize) -> f64 {
    let at = |j: isize| -> Option<f64> {
        usize::try_from(j)
            .ok()
            .and_then(|j| joints.get(j).copied().flatten())
    };
    let (left, right) = (at(b as isize - 1), at(b as isize));
    match (left, right) {
        (Some(l), Some(r)) => l + 0.5 * wrap(r - l),
        (Some(l), None) => l + at(b as isize - 2).map_or(0.0, |ll| 0.5 * wrap(l - ll)),
        (None, Some(r)) => r - at(b as isize + 1).map_or(0.0, |rr| 0.5 * wrap(rr - r)),
        (None, None) => 0.0,
    }
}

/// An angle difference brought into (−π, π].
fn wrap(a: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let w = a.rem_euclid(two_pi);
    if w > std::f64::consts::PI {
        w - two_pi
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::geometry::{ArchGeometry, BlocksGeometry};
    use crate::mesh::{generate_arch, generate_blocks};

    /// The side a generated far face is on by construction: its local face.
    fn by_construction(face: u8) -> FarSide {
        match face {
            0 => FarSide::Base,
            2 => FarSide::Upstream,
            3 => FarSide::RightBank,
            4 => FarSide::Downstream,
            5 => FarSide::LeftBank,
            f => panic!("a generated far face is never local face {f}"),
        }
    }

    /// Every far face of `mesh` is read as its local face says; returns
    /// how many faces each side has.
    fn check_all(mesh: &Mesh) -> [usize; 5] {
        let mut counts = [0; 5];
        let sides = mesh.far_sides();
        assert_eq!(
            sides.len(),
            mesh.surfaces
                .iter()
                .filter(|f| f.kind == SurfaceKind::Far)
                .count()
        );
        for (f, got) in sides {
            let want = by_construction(f.face);
            assert_eq!(got, want, "element {} face {}", f.elem, f.face);
            counts[got.index()] += 1;
        }
        counts
    }

    fn blocks(margin: f64, depth: f64, ratio: f64) -> BlocksGeometry {
        BlocksGeometry {
            n_blocks: 3,
            block_length_m: 15.0,
            thickness_m: 20.0,
            n_lifts: 4,
            elements_per_block: 2,
            elements_across: 3,
            layers_per_lift: 1,
            rock_depth_m: depth,
            rock_layers: 2,
            rock_margin_m: margin,
            rock_margin_elements: 2,
            rock_grading_ratio: ratio,
            face_element_m: None,
            joint_element_m: None,
            base_elevation_m: 10.0,
        }
    }

    fn arch(n_blocks: u32, angle: f64, margin: f64, ratio: f64) -> ArchGeometry {
        ArchGeometry {
            n_blocks,
            height_m: 60.0,
            base_elevation_m: 0.0,
            crest_radius_m: 100.0,
            base_radius_m: 60.0,
            central_angle_deg: angle,
            crest_thickness_m: 6.0,
            base_thickness_m: 18.0,
            thickness_exponent: 1.0,
            overhang_m: 4.0,
            valley_exponent: 2.0,
            min_block_height_fraction: 0.3,
            elements_per_block: 2,
            elements_across: 2,
            rock_depth_m: 40.0,
            rock_layers: 2,
            rock_margin_m: margin,
            rock_margin_elements: 2,
            rock_grading_ratio: ratio,
            face_element_m: None,
            joint_element_m: None,
        }
    }

    #[test]
    fn blocks_far_faces_are_read_by_their_side() {
        for (margin, depth, ratio) in [
            (0.0, 0.0, 1.0),
            (0.0, 12.0, 1.0),
            (25.0, 12.0, 1.0),
            (25.0, 30.0, 1.4),
        ] {
            let mesh = generate_blocks(&blocks(margin, depth, ratio), 3.0, 6.0).unwrap();
            let counts = check_all(&mesh);
            assert!(counts[FarSide::Base.index()] > 0);
            if depth > 0.0 {
                // rock sides are far faces on all four sides
                assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
            } else {
                assert_eq!(counts[1..], [0, 0, 0, 0]);
            }
        }
    }

    #[test]
    fn arch_far_faces_are_read_by_their_side_though_curved() {
        // three blocks over 150° and two over 80° are the hardest cases
        // the rule claims; wide margins put downstream far faces behind the
        // centre of curvature (margin 120 m > base downstream radius 42 m).
        for (n, angle, margin, ratio) in [
            (12, 95.0, 60.0, 1.0),
            (6, 120.0, 30.0, 1.3),
            (3, 150.0, 20.0, 1.0),
            (2, 80.0, 20.0, 1.0),
            (5, 100.0, 120.0, 1.5),
            (8, 92.0, 150.0, 1.0),
        ] {
            let mesh = generate_arch(&arch(n, angle, margin, ratio), 3.0, 9.0).unwrap();
            let counts = check_all(&mesh);
            assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
        }
    }

    #[test]
    fn wrap_keeps_differences_small() {
        assert!((wrap(0.3) - 0.3).abs() < 1e-15);
        assert!((wrap(-0.3) + 0.3).abs() < 1e-15);
        assert!((wrap(2.0 * std::f64::consts::PI - 0.1) + 0.1).abs() < 1e-12);
    }
}
