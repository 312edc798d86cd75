//! Which side of the model a far face is on: base, upstream, downstream,
//! left bank or right bank, by a geometric rule that needs nothing but the
//! [`Mesh`] (so it holds for generated and imported meshes alike).
//!
//! # The rule
//!
//! 1. The face's outward unit normal n is that of its quad (the cross
//!    product of its diagonals, oriented by the `HEX_FACES` order, outward
//!    for a positive Jacobian). If n points down by more than 45°
//!    (n_z ≤ −1/√2) the face is on the **base**. A far face whose normal
//!    has no horizontal part (a flat far top, which the generators never
//!    make) counts with the base too.
//! 2. Otherwise its side is read in the dam's local plan frame at the face:
//!    the axis direction t (left bank → right bank) of the block whose
//!    centroid (of its nodes, 3-D) is nearest to the face's centre, and the downstream
//!    direction d = t turned by +90° about z (t = x̂ gives d = ŷ). The side
//!    is the larger of |n·t| (**right bank** if n·t > 0, **left bank**
//!    otherwise) and |n·d| (**downstream** if n·d > 0, **upstream**
//!    otherwise).
//! 3. A block's axis direction is the mean of the horizontal normals of
//!    its joints (a joint's face pairs point from block j to j + 1); an end
//!    block's is its joint's turned on by half the turn between the last
//!    two joints (the block's own mid-direction on a circular arch). With
//!    one joint both blocks take it (so a two-block arch is read right up
//!    to a 90° central angle); without joints t = x̂ (the meshes'
//!    convention: x along the axis).
//!
//! On the blocks generator every t is x̂ and the faces are axis-aligned, so
//! the rule is exact. On the arch generator the upstream and downstream
//! rock faces follow the rings and the abutment faces the last joint
//! planes; a face is misread only if its normal is more than 45° from the
//! frame of the block nearest to it: with three blocks or more an end
//! block's frame is its mid-direction, so the abutment and corner faces are
//! within half a block's arc of it (< 45° below a 180° central angle, the
//! arch's limit). Nearest in 3-D rather than in plan matters where the
//! downstream margin reaches behind the rings' centre (Xiaowan-like: a
//! 150 m margin behind a 97 m base radius): there the deep crown blocks
//! are nearer than the high abutment blocks whose frames turn 45°.
//! Verified by the unit tests below: every far face of both generators
//! (with margins, graded and not) gets the side of its local hex face
//! (face 0 base, 2 upstream, 3 right bank, 4 downstream, 5 left bank).

use serde::{Deserialize, Serialize};

use super::{Mesh, Part, SurfaceFace, HEX_FACES};

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

/// The dam's local plan frame per block: what [`DamFrame::side`] reads.
#[derive(Debug, Clone)]
pub struct DamFrame {
    /// Per block: centroid of its elements' nodes and unit axis direction (x, y).
    blocks: Vec<([f64; 3], [f64; 2])>,
}

impl DamFrame {
    /// The frame of `mesh`'s blocks (module doc, rule 3).
    pub fn of(mesh: &Mesh) -> DamFrame {
        let n_blocks = mesh.blocks.len();
        let mut sum = vec![[0.0f64; 4]; n_blocks];
        for (e, part) in mesh.parts.iter().enumerate() {
            if let Part::Concrete { block, .. } = *part {
                let Some(s) = sum.get_mut(block as usize - 1) else {
                    continue;
                };
                for &n in &mesh.elements[e] {
                    let p = mesh.nodes[n as usize];
                    s[0] += p[0];
                    s[1] += p[1];
                    s[2] += p[2];
                    s[3] += 1.0;
                }
            }
        }
        let joint_angle = joint_angles(mesh);
        let blocks = (0..n_blocks)
            .map(|b| {
                let count = sum[b][3].max(1.0);
                let c = [sum[b][0] / count, sum[b][1] / count, sum[b][2] / count];
                let a = block_angle(&joint_angle, b);
                (c, [a.cos(), a.sin()])
            })
            .collect();
        DamFrame { blocks }
    }

    /// The side of far face `face` of `mesh` (module doc, rules 1–2).
    pub fn side(&self, mesh: &Mesh, face: &SurfaceFace) -> FarSide {
        let (centre, n) = face_centre_normal(mesh, face);
        let horizontal = n[0].hypot(n[1]);
        if n[2] <= -std::f64::consts::FRAC_1_SQRT_2 || horizontal < 1e-12 {
            return FarSide::Base;
        }
        let t = self.axis_at(centre);
        let d = [-t[1], t[0]];
        let along = n[0] * t[0] + n[1] * t[1];
        let across = n[0] * d[0] + n[1] * d[1];
        if along.abs() > across.abs() {
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

    /// The axis direction of the block whose centroid is nearest to `p`.
    fn axis_at(&self, p: [f64; 3]) -> [f64; 2] {
        self.blocks
            .iter()
            .map(|(c, t)| {
                let d2 = (c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2) + (c[2] - p[2]).powi(2);
                (d2, *t)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or([1.0, 0.0], |(_, t)| t)
    }
}

impl Mesh {
    /// The side of one far face: [`DamFrame::of`] then [`DamFrame::side`].
    /// Builds the frame on each call; for many faces build it once.
    pub fn far_side(&self, face: &SurfaceFace) -> FarSide {
        DamFrame::of(self).side(self, face)
    }
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
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(f64::MIN_POSITIVE);
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
            kind: super::SurfaceKind::Ground,
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
    use crate::mesh::{generate_arch, generate_blocks, SurfaceKind};

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
        let frame = DamFrame::of(mesh);
        let mut counts = [0; 5];
        for f in mesh.surfaces.iter().filter(|f| f.kind == SurfaceKind::Far) {
            let want = by_construction(f.face);
            let got = frame.side(mesh, f);
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
        }
    }

    #[test]
    fn blocks_far_faces_are_read_by_their_side() {
        for (margin, depth, ratio) in [(0.0, 0.0, 1.0), (0.0, 12.0, 1.0), (25.0, 12.0, 1.0), (25.0, 30.0, 1.4)] {
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
