//! Bilinear 4-node quadrilateral embedded in 3-D: the faces of hex8 elements
//! (convection surfaces, joint faces).
//!
//! Reference corners (s, t) = (−1,−1), (1,−1), (1,1), (−1,1); with the nodes of
//! a [`hex8::FACES`](super::hex8::FACES) entry in that order, the normal
//! ∂x/∂s × ∂x/∂t points out of the hex. The area element is
//! dA = |∂x/∂s × ∂x/∂t| ds dt.

use super::error::ElementError;
use super::quadrature::GAUSS2_QUAD;

/// Reference coordinates (s, t) of the 4 nodes.
pub const NODES: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Shape functions N_a(s, t) = ¼(1 + s s_a)(1 + t t_a).
#[inline]
pub fn shape(st: [f64; 2]) -> [f64; 4] {
    let mut n = [0.0; 4];
    for (a, na) in n.iter_mut().enumerate() {
        *na = 0.25 * (1.0 + st[0] * NODES[a][0]) * (1.0 + st[1] * NODES[a][1]);
    }
    n
}

/// Reference gradients [∂N_a/∂s, ∂N_a/∂t].
#[inline]
pub fn shape_grad_ref(st: [f64; 2]) -> [[f64; 2]; 4] {
    let mut g = [[0.0; 2]; 4];
    for (a, ga) in g.iter_mut().enumerate() {
        let p = NODES[a];
        *ga = [
            0.25 * p[0] * (1.0 + st[1] * p[1]),
            0.25 * (1.0 + st[0] * p[0]) * p[1],
        ];
    }
    g
}

/// Physical point x(s, t).
#[inline]
pub fn point(coords: &[[f64; 3]; 4], st: [f64; 2]) -> [f64; 3] {
    let n = shape(st);
    let mut x = [0.0; 3];
    for a in 0..4 {
        for i in 0..3 {
            x[i] += n[a] * coords[a][i];
        }
    }
    x
}

/// Tangents (∂x/∂s, ∂x/∂t).
#[inline]
pub fn tangents(coords: &[[f64; 3]; 4], st: [f64; 2]) -> ([f64; 3], [f64; 3]) {
    let g = shape_grad_ref(st);
    let mut ts = [0.0; 3];
    let mut tt = [0.0; 3];
    for a in 0..4 {
        for i in 0..3 {
            ts[i] += g[a][0] * coords[a][i];
            tt[i] += g[a][1] * coords[a][i];
        }
    }
    (ts, tt)
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Non-normalised normal ∂x/∂s × ∂x/∂t (its length is the area element).
#[inline]
pub fn normal_scaled(coords: &[[f64; 3]; 4], st: [f64; 2]) -> [f64; 3] {
    let (ts, tt) = tangents(coords, st);
    cross(ts, tt)
}

/// Area element |∂x/∂s × ∂x/∂t| at (s, t).
#[inline]
pub fn area_element(coords: &[[f64; 3]; 4], st: [f64; 2]) -> f64 {
    let n = normal_scaled(coords, st);
    (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// Relative threshold for a degenerate face: dA ≤ TOL·|∂x/∂s|·|∂x/∂t|.
pub const DEGENERATE_TOL: f64 = 1e-12;

#[inline]
fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Scaled normal ∂x/∂s × ∂x/∂t and area element at (s, t), or
/// [`ElementError::DegenerateFace`] when the tangents are (nearly) parallel,
/// zero or not finite.
#[inline]
pub fn surface_jacobian(
    coords: &[[f64; 3]; 4],
    st: [f64; 2],
) -> Result<([f64; 3], f64), ElementError> {
    let (ts, tt) = tangents(coords, st);
    let n = cross(ts, tt);
    let da = norm(n);
    if !(da.is_finite() && da > DEGENERATE_TOL * norm(ts) * norm(tt)) {
        return Err(ElementError::DegenerateFace {
            area_element: da,
            point: st,
        });
    }
    Ok((n, da))
}

/// Unit normal at (s, t) (outward for a hex face listed in `FACES` order).
pub fn normal(coords: &[[f64; 3]; 4], st: [f64; 2]) -> Result<[f64; 3], ElementError> {
    let (n, len) = surface_jacobian(coords, st)?;
    Ok([n[0] / len, n[1] / len, n[2] / len])
}

/// Area by 2×2 Gauss (exact for planar faces; the same rule as the face kernels).
pub fn area(coords: &[[f64; 3]; 4]) -> f64 {
    GAUSS2_QUAD.iter().map(|&q| area_element(coords, q)).sum()
}
