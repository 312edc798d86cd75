//! The supports of the far faces, per side (`[boundary.<side>] support`):
//! which displacement components are held at zero, and the check that
//! they leave no rigid motion free.
//!
//! * `fixed`: the three components of every node of the side's faces.
//! * `rollers`: the component along each face's normal; a face whose
//!   normal is not within 1e-6 of ±x, ±y or ±z is refused
//!   ([`SupportError::Oblique`]) rather than constrained in a rotated
//!   frame (the arch's rock sides; the scene refuses rollers there
//!   first, naming the key).
//! * `free`: nothing.
//!
//! A node on two sides gets the union (an edge between two roller planes
//! is held in both normals). The supports must stop the six rigid motions
//! of the whole model: each held component (node x, component c) is one
//! row rᵀ = [e_c, (x − x̄)/L × e_c] of the rigid-motion constraint
//! (translation a, rotation ω about the centre x̄, scaled by the model's
//! size L); the supports are refused ([`SupportError::Rigid`]) when
//! Σ r rᵀ (6 × 6) has an eigenvalue below 1e-9 of its largest, naming the
//! free motions. Only the whole model's rigid motions are checked: a
//! block held only by its joints' contact is the contact solver's affair.
//!
//! Verified by `tests/it/far_boundary.rs`: the default gives today's
//! clamped supports exactly, rollers on a heated block give the free
//! expansion (zero stress) or the restrained stress of a closed form, and
//! a free model is refused with the message.

use nalgebra::{Matrix6, SymmetricEigen, Vector6};

use crate::fem::hex8::FACES;
use crate::mesh::{FarSide, Mesh};
use crate::scene::Support;

use super::model::Supports;

/// Supports a scene asks for that cannot hold.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SupportError {
    /// Rollers on a face not normal to x, y or z.
    #[error("boundary.{side}.support = \"rollers\": element {elem} face {face} has normal ({:.3}, {:.3}, {:.3}), not along x, y or z (rollers need plane faces normal to an axis; use \"fixed\" or \"free\")", normal[0], normal[1], normal[2])]
    Oblique {
        side: FarSide,
        elem: u32,
        face: u8,
        normal: [f64; 3],
    },
    /// The supports leave rigid motions of the model free.
    #[error("the far supports ([boundary]: {sides}) leave the model free to move rigidly: {motions}; hold at least one more side (support = \"fixed\" or \"rollers\")")]
    Rigid { sides: String, motions: String },
}

/// Tolerance on a roller face's normal being along an axis.
const AXIS_TOL: f64 = 1e-6;

impl Supports {
    /// The supports of `mesh`'s far faces for the support of each side
    /// (`supports` in [`FarSide::ALL`] order), checked against rigid
    /// motion. All `fixed` gives [`Supports::far_boundary`] exactly.
    pub fn for_sides(mesh: &Mesh, supports: &[Support; 5]) -> Result<Supports, SupportError> {
        let all_fixed = supports.iter().all(|&s| s == Support::Fixed);
        let out = if all_fixed {
            // no side to tell apart: today's clamped far boundary
            Supports::far_boundary(mesh)
        } else {
            by_side(mesh, supports)?
        };
        check_rigid(mesh, &out, supports)?;
        Ok(out)
    }
}

/// The held components of every far face by its side's support.
fn by_side(mesh: &Mesh, supports: &[Support; 5]) -> Result<Supports, SupportError> {
    let mut fixed = Vec::new();
    for (f, side) in mesh.far_sides() {
        let comps: Vec<u8> = match supports[side.index()] {
            Support::Free => continue,
            Support::Fixed => vec![0, 1, 2],
            Support::Rollers => {
                let (_, n) = crate::mesh::far::face_centre_normal(mesh, &f);
                let axis = (0..3).find(|&c| (n[c].abs() - 1.0).abs() < AXIS_TOL);
                let Some(axis) = axis else {
                    return Err(SupportError::Oblique {
                        side,
                        elem: f.elem,
                        face: f.face,
                        normal: n,
                    });
                };
                vec![axis as u8]
            }
        };
        for &k in &FACES[f.face as usize] {
            let node = mesh.elements[f.elem as usize][k];
            fixed.extend(comps.iter().map(|&c| (node, c)));
        }
    }
    fixed.sort_unstable();
    fixed.dedup();
    Ok(Supports { fixed })
}

/// Refuses supports that leave a rigid motion of the whole model free
/// (module doc).
fn check_rigid(mesh: &Mesh, s: &Supports, supports: &[Support; 5]) -> Result<(), SupportError> {
    let n = mesh.nodes.len().max(1) as f64;
    let centre: [f64; 3] =
        std::array::from_fn(|c| mesh.nodes.iter().map(|p| p[c]).sum::<f64>() / n);
    let size = mesh
        .nodes
        .iter()
        .map(|p| (0..3).map(|c| (p[c] - centre[c]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut g = Matrix6::<f64>::zeros();
    for &(node, c) in &s.fixed {
        let p = mesh.nodes[node as usize];
        let x: [f64; 3] = std::array::from_fn(|k| (p[k] - centre[k]) / size);
        let mut e = [0.0; 3];
        e[c as usize] = 1.0;
        // (x × e_c): the component c of ω × x is ω · (x × e_c)
        let xe = [
            x[1] * e[2] - x[2] * e[1],
            x[2] * e[0] - x[0] * e[2],
            x[0] * e[1] - x[1] * e[0],
        ];
        let r = Vector6::new(e[0], e[1], e[2], xe[0], xe[1], xe[2]);
        g += r * r.transpose();
    }
    let eig = SymmetricEigen::new(g);
    let largest = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let free: Vec<usize> = (0..6)
        .filter(|&i| largest == 0.0 || eig.eigenvalues[i] <= 1e-9 * largest)
        .collect();
    if free.is_empty() {
        return Ok(());
    }
    // unit modes no support touches, when they are the whole free space;
    // otherwise the free eigenvectors in words
    let tol = 1e-9 * largest.max(f64::MIN_POSITIVE);
    let unit: Vec<usize> = (0..6).filter(|&i| g[(i, i)] <= tol).collect();
    let motions: Vec<String> = if unit.len() == free.len() {
        unit.iter().map(|&i| NAMES[i].to_string()).collect()
    } else {
        free.iter()
            .map(|&i| describe(&eig.eigenvectors.column(i).into_owned()))
            .collect()
    };
    let sides: Vec<String> = FarSide::ALL
        .iter()
        .zip(supports)
        .map(|(side, sup)| format!("{side} {}", sup.name()))
        .collect();
    Err(SupportError::Rigid {
        sides: sides.join(", "),
        motions: motions.join("; "),
    })
}

/// The six unit rigid motions, in the order of the constraint rows.
const NAMES: [&str; 6] = [
    "translation along x",
    "translation along y",
    "translation along z",
    "rotation about x",
    "rotation about y",
    "rotation about z",
];

/// A rigid mode in words: its main translations and rotations.
fn describe(v: &Vector6<f64>) -> String {
    let big = v.iter().map(|c| c.abs()).fold(0.0, f64::max);
    let parts: Vec<&str> = (0..6)
        .filter(|&i| v[i].abs() > 0.1 * big)
        .map(|i| NAMES[i])
        .collect();
    parts.join(" with ")
}
