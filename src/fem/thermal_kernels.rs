//! Element matrices of transient heat conduction, ρc ∂T/∂t = ∇·(λ∇T) + q,
//! on hex8 volumes and quad4 convection faces. Units are the caller's; the
//! crate uses days (λ in J/(day·m·K), β in J/(day·m²·K)).
//!
//! | kernel | integral | rule |
//! |---|---|---|
//! | [`conductivity`] | ∫ λ ∇N ∇Nᵀ dV | 2×2×2 Gauss |
//! | [`capacity_consistent`] | ∫ ρc N Nᵀ dV | 3×3×3 Gauss (exact on any trilinear hex) |
//! | [`capacity_lumped`] | row sums of the consistent matrix | exact, Σ = ρc·V |
//! | [`volume_load`] | ∫ q N dV (uniform q) | exact |
//! | [`face_convection`] | (∫ β N Nᵀ dA, ∫ β N dA) | 2×2 Gauss |
//! | [`face_convection_lumped`] | row sums of the above | 2×2 Gauss |

use nalgebra::SMatrix;

use super::error::ElementError;
use super::hex8;
use super::quad4;
use super::quadrature::{GAUSS2_HEX, GAUSS2_QUAD};

/// 3-point Gauss–Legendre abscissae and weights on [−1, 1].
const G3_X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
const G3_W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];

/// Conductivity matrix K_ab = ∫ λ ∇N_a·∇N_b dV (isotropic, uniform λ).
pub fn conductivity(
    coords: &[[f64; 3]; 8],
    lambda: f64,
) -> Result<SMatrix<f64, 8, 8>, ElementError> {
    let mut k = SMatrix::<f64, 8, 8>::zeros();
    for &q in GAUSS2_HEX.iter() {
        let (g, det) = hex8::shape_grad(coords, q)?;
        let w = lambda * det;
        for a in 0..8 {
            for b in a..8 {
                let v = w * (g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2]);
                k[(a, b)] += v;
            }
        }
    }
    for a in 0..8 {
        for b in 0..a {
            k[(a, b)] = k[(b, a)];
        }
    }
    Ok(k)
}

/// Consistent capacity matrix C_ab = ∫ ρc N_a N_b dV.
pub fn capacity_consistent(
    coords: &[[f64; 3]; 8],
    rho_c: f64,
) -> Result<SMatrix<f64, 8, 8>, ElementError> {
    let mut c = SMatrix::<f64, 8, 8>::zeros();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                let q = [G3_X[i], G3_X[j], G3_X[k]];
                let (jac, det) = hex8::jacobian(coords, q);
                if !hex8::jacobian_ok(&jac, det) {
                    return Err(ElementError::NonPositiveJacobian { det, point: q });
                }
                let w = rho_c * det * G3_W[i] * G3_W[j] * G3_W[k];
                let n = hex8::shape(q);
                for a in 0..8 {
                    for b in a..8 {
                        c[(a, b)] += w * n[a] * n[b];
                    }
                }
            }
        }
    }
    for a in 0..8 {
        for b in 0..a {
            c[(a, b)] = c[(b, a)];
        }
    }
    Ok(c)
}

/// ∫ q N_a dV for a uniform q: the nodal load of a uniform source.
/// Equal to the row sums of the consistent matrix of density q, so the
/// entries add up to q·V exactly.
pub fn volume_load(coords: &[[f64; 3]; 8], q: f64) -> Result<[f64; 8], ElementError> {
    let mut f = [0.0; 8];
    // integrand N_a det J has degree ≤ 3 per direction: 2-point Gauss is exact
    for &p in GAUSS2_HEX.iter() {
        let (j, det) = hex8::jacobian(coords, p);
        if !hex8::jacobian_ok(&j, det) {
            return Err(ElementError::NonPositiveJacobian { det, point: p });
        }
        let n = hex8::shape(p);
        for a in 0..8 {
            f[a] += q * det * n[a];
        }
    }
    Ok(f)
}

/// Row-sum lumped capacity (diagonal) C_a = ∫ ρc N_a dV; Σ_a C_a = ρc·V.
/// All entries are positive for a valid hex8.
pub fn capacity_lumped(coords: &[[f64; 3]; 8], rho_c: f64) -> Result<[f64; 8], ElementError> {
    volume_load(coords, rho_c)
}

/// Volume and centroid (∫ x dV / V), exact for a trilinear hex.
pub fn element_volume_and_centroid(coords: &[[f64; 3]; 8]) -> (f64, [f64; 3]) {
    let mut v = 0.0;
    let mut m = [0.0; 3];
    for &p in GAUSS2_HEX.iter() {
        let (_, det) = hex8::jacobian(coords, p);
        let x = hex8::point(coords, p);
        v += det;
        for i in 0..3 {
            m[i] += det * x[i];
        }
    }
    (v, [m[0] / v, m[1] / v, m[2] / v])
}

/// Convection face matrices for −λ∂T/∂n = β(T − Ta) on a quad4 face:
/// (H_ab = ∫ β N_a N_b dA, h_a = ∫ β N_a dA). The system gets K += H and
/// F += Ta·h. Σ_ab H_ab = Σ_a h_a = β·area.
pub fn face_convection(
    face_coords: &[[f64; 3]; 4],
    beta: f64,
) -> Result<(SMatrix<f64, 4, 4>, [f64; 4]), ElementError> {
    let mut h = SMatrix::<f64, 4, 4>::zeros();
    let mut f = [0.0; 4];
    for &q in GAUSS2_QUAD.iter() {
        let (_, da) = quad4::surface_jacobian(face_coords, q)?;
        let n = quad4::shape(q);
        let w = beta * da;
        for a in 0..4 {
            f[a] += w * n[a];
            for b in a..4 {
                h[(a, b)] += w * n[a] * n[b];
            }
        }
    }
    for a in 0..4 {
        for b in 0..a {
            h[(a, b)] = h[(b, a)];
        }
    }
    Ok((h, f))
}

/// Lumped (row-sum) convection: diagonal H_a = h_a = ∫ β N_a dA.
/// The system gets K_aa += h_a and F_a += Ta·h_a.
pub fn face_convection_lumped(
    face_coords: &[[f64; 3]; 4],
    beta: f64,
) -> Result<[f64; 4], ElementError> {
    face_convection(face_coords, beta).map(|(_, f)| f)
}
