//! Trilinear 8-node hexahedron in VTK_HEXAHEDRON node order (see
//! `docs/ARCHITECTURE.md`, "Hex8 conventions").
//!
//! Map x(ξ) = Σ_a N_a(ξ) x_a with N_a = ⅛(1 + ξ ξ_a)(1 + η η_a)(1 + ζ ζ_a).
//! The Jacobian is J_ij = ∂x_i/∂ξ_j (row = physical component, column =
//! reference direction), so physical gradients are ∇ₓN = J⁻ᵀ ∇_ξ N.

use nalgebra::{Matrix3, Vector3};

use super::error::ElementError;
use super::quadrature::GAUSS2_HEX;

/// Reference coordinates (ξ, η, ζ) of the 8 nodes, VTK order.
pub const NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Local faces, nodes counter-clockwise seen from outside (right-hand normal
/// points outward). The quad4 reference corners (s, t) = (−1,−1), (1,−1),
/// (1,1), (−1,1) are the face's nodes in this order.
pub const FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1], // 0: ζ = −1 (bottom)
    [4, 5, 6, 7], // 1: ζ = +1 (top)
    [0, 1, 5, 4], // 2: η = −1 (upstream side in generated meshes)
    [1, 2, 6, 5], // 3: ξ = +1 (right-bank side)
    [2, 3, 7, 6], // 4: η = +1 (downstream side)
    [3, 0, 4, 7], // 5: ξ = −1 (left-bank side)
];

/// Shape functions N_a(ξ), a = 0..8.
#[inline]
pub fn shape(xi: [f64; 3]) -> [f64; 8] {
    let mut n = [0.0; 8];
    for (a, na) in n.iter_mut().enumerate() {
        let p = NODES[a];
        *na = 0.125 * (1.0 + xi[0] * p[0]) * (1.0 + xi[1] * p[1]) * (1.0 + xi[2] * p[2]);
    }
    n
}

/// N_a at the points of the 2×2×2 rule, `[g][a]` for ξ = [`GAUSS2_HEX`]`[g]`:
/// [`shape`]'s numbers there, made once and read by every element and step
/// (the mechanics' Gauss-point temperatures, each step's body forces).
pub fn shape_at_gauss2() -> &'static [[f64; 8]; 8] {
    static TABLE: std::sync::OnceLock<[[f64; 8]; 8]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| GAUSS2_HEX.map(shape))
}

/// Reference gradients ∂N_a/∂ξ_j.
#[inline]
pub fn shape_grad_ref(xi: [f64; 3]) -> [[f64; 3]; 8] {
    let mut g = [[0.0; 3]; 8];
    for (a, ga) in g.iter_mut().enumerate() {
        let p = NODES[a];
        let fx = 1.0 + xi[0] * p[0];
        let fy = 1.0 + xi[1] * p[1];
        let fz = 1.0 + xi[2] * p[2];
        *ga = [
            0.125 * p[0] * fy * fz,
            0.125 * fx * p[1] * fz,
            0.125 * fx * fy * p[2],
        ];
    }
    g
}

/// Physical point x(ξ).
#[inline]
pub fn point(coords: &[[f64; 3]; 8], xi: [f64; 3]) -> [f64; 3] {
    let n = shape(xi);
    let mut x = [0.0; 3];
    for a in 0..8 {
        for i in 0..3 {
            x[i] += n[a] * coords[a][i];
        }
    }
    x
}

#[inline]
fn jacobian_from(coords: &[[f64; 3]; 8], g: &[[f64; 3]; 8]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for a in 0..8 {
        for r in 0..3 {
            for c in 0..3 {
                j[(r, c)] += coords[a][r] * g[a][c];
            }
        }
    }
    j
}

/// Relative threshold below which det J counts as zero: det J ≤ TOL·|J₀||J₁||J₂|
/// (columns of J) means the element is collapsed. Scale- and aspect-free, so
/// long thin elements pass.
pub const DEGENERATE_TOL: f64 = 1e-12;

/// True when det J > 0, finite and not degenerate (see [`DEGENERATE_TOL`]).
#[inline]
pub fn jacobian_ok(j: &Matrix3<f64>, det: f64) -> bool {
    det.is_finite()
        && det > DEGENERATE_TOL * j.column(0).norm() * j.column(1).norm() * j.column(2).norm()
}

/// J = ∂x/∂ξ at ξ and its determinant (signed; not checked).
#[inline]
pub fn jacobian(coords: &[[f64; 3]; 8], xi: [f64; 3]) -> (Matrix3<f64>, f64) {
    let j = jacobian_from(coords, &shape_grad_ref(xi));
    let det = j.determinant();
    (j, det)
}

/// Physical gradients ∇ₓN_a at ξ and det J.
///
/// Fails with [`ElementError::NonPositiveJacobian`] when det J is not > 0
/// (NaN coordinates included).
#[inline]
pub fn shape_grad(
    coords: &[[f64; 3]; 8],
    xi: [f64; 3],
) -> Result<([[f64; 3]; 8], f64), ElementError> {
    let gr = shape_grad_ref(xi);
    let j = jacobian_from(coords, &gr);
    let det = j.determinant();
    if !jacobian_ok(&j, det) {
        return Err(ElementError::NonPositiveJacobian { det, point: xi });
    }
    // J⁻ᵀ via the cofactor matrix: J⁻ᵀ = cof(J) / det.
    let c0 = j.column(1).cross(&j.column(2));
    let c1 = j.column(2).cross(&j.column(0));
    let c2 = j.column(0).cross(&j.column(1));
    // rows of J⁻¹ are c_k / det, so J⁻ᵀ has columns c_k / det
    let inv_det = 1.0 / det;
    let mut g = [[0.0; 3]; 8];
    for a in 0..8 {
        let d = Vector3::new(gr[a][0], gr[a][1], gr[a][2]);
        // ∇ₓN = J⁻ᵀ d = Σ_k d_k (row k of J⁻¹)ᵀ
        let v = (c0 * d[0] + c1 * d[1] + c2 * d[2]) * inv_det;
        g[a] = [v[0], v[1], v[2]];
    }
    Ok((g, det))
}

/// Signed volume ∫ det J dξ (2×2×2 Gauss, exact for any trilinear hex).
pub fn volume(coords: &[[f64; 3]; 8]) -> f64 {
    GAUSS2_HEX.iter().map(|&q| jacobian(coords, q).1).sum()
}

/// Smallest det J over the 8 corners and the 8 Gauss points, and where.
pub fn min_jacobian(coords: &[[f64; 3]; 8]) -> (f64, [f64; 3]) {
    NODES
        .iter()
        .chain(GAUSS2_HEX.iter())
        .map(|&p| (jacobian(coords, p).1, p))
        .fold((f64::INFINITY, [0.0; 3]), |acc, cur| {
            if cur.0 < acc.0 || cur.0.is_nan() {
                cur
            } else {
                acc
            }
        })
}

/// Ok when det J is positive and not degenerate ([`jacobian_ok`]) at all
/// corners and Gauss points; otherwise the first failing point.
pub fn check(coords: &[[f64; 3]; 8]) -> Result<(), ElementError> {
    for &p in NODES.iter().chain(GAUSS2_HEX.iter()) {
        let (j, det) = jacobian(coords, p);
        if !jacobian_ok(&j, det) {
            return Err(ElementError::NonPositiveJacobian { det, point: p });
        }
    }
    Ok(())
}

/// Physical coordinates of local face `face` (0..6) in [`FACES`] order.
#[inline]
pub fn face_coords(coords: &[[f64; 3]; 8], face: usize) -> [[f64; 3]; 4] {
    let f = FACES[face];
    [coords[f[0]], coords[f[1]], coords[f[2]], coords[f[3]]]
}

/// Reference point ξ with x(ξ) = x, by Newton iteration from the centre.
/// `None` if Newton does not converge or the point lies outside the element
/// (by more than `1e-9` in reference coordinates).
pub fn locate(coords: &[[f64; 3]; 8], x: [f64; 3]) -> Option<[f64; 3]> {
    let mut xi = Vector3::zeros();
    for _ in 0..50 {
        let p = point(coords, [xi[0], xi[1], xi[2]]);
        let r = Vector3::new(x[0] - p[0], x[1] - p[1], x[2] - p[2]);
        let (j, _) = jacobian(coords, [xi[0], xi[1], xi[2]]);
        let dxi = j.try_inverse()? * r;
        xi += dxi;
        if dxi.amax() < 1e-13 {
            let inside = xi.iter().all(|v| v.abs() <= 1.0 + 1e-9);
            return inside.then_some([xi[0], xi[1], xi[2]]);
        }
        if !xi.iter().all(|v| v.is_finite() && v.abs() < 1e3) {
            return None;
        }
    }
    None
}
