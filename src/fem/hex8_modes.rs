//! Hex8 with Wilson–Taylor incompatible modes (the "C3D8I" element).
//!
//! # Why
//!
//! The trilinear hex8 of [`super::elasticity`] cannot bend: a field
//! u_x = κ·x·z needs u_z = −κx²/2 to be shear-free, which a trilinear
//! element lacks, so it carries a parasitic shear strain and is too stiff
//! in bending (shear locking). A block whose top cools on a restrained base
//! curls this way; on the small dam the aperture of the top zones moved by
//! 0.6 mm between 3 and 6 elements along each 18 m block. The modes below
//! add the missing quadratic terms inside each element at no cost in
//! global dofs.
//!
//! # Equations
//!
//! Each displacement component gets three bubble modes,
//!
//! ```text
//! u_i(ξ) = Σ_a N_a(ξ) u_ia + Σ_m φ_m(ξ) α_im,   φ = (1 − ξ², 1 − η², 1 − ζ²)
//! ```
//!
//! nine internal unknowns α per element, zero at every node. Their strains
//! are G α with the gradients taken with the Jacobian at the element's
//! centre and scaled (Taylor, Beresford & Wilson 1976):
//!
//! ```text
//! ∇ₓφ_m(ξ) = (det J₀ / det J(ξ)) J₀⁻ᵀ ∇_ξ φ_m(ξ)
//! ```
//!
//! so that ∫ G dV = det J₀ J₀⁻ᵀ ∫ ∇_ξφ dξ = 0 on any shape: a constant
//! stress does no work on the modes, and the element passes the patch test.
//! With D = E·Q the element equations
//!
//! ```text
//! ⎡K_uu  K_uα⎤ ⎡u⎤   ⎡f_u⎤      K_xy = E Σ_g X_gᵀ Q Y_g w_g,
//! ⎣K_αu  K_αα⎦ ⎣α⎦ = ⎣f_α⎦      f_x = E Σ_g X_gᵀ Q ε0_g w_g   (X, Y ∈ {B, G})
//! ```
//!
//! are condensed element by element: with T = K̂_αα⁻¹ K̂_αu and P = K̂_αα⁻¹
//! (hats: E = 1, so both are independent of the ageing modulus),
//!
//! ```text
//! K_c = E (K̂_uu − K̂_uα T),   f_c = f_u − Tᵀ f_α,   α = P f̂_α − T u
//! ```
//!
//! and the strain at a Gauss point is B_g u + G_g α. The system keeps the
//! nodal dofs and the pattern of the plain element; only K_c, the
//! condensed load and the strain recovery differ.
//!
//! # How it is verified (unit tests below)
//!
//! * Σ_g G_g w_g = 0 on a distorted element (the patch-test condition), so
//!   a linear displacement field leaves α = 0 and the plain element's
//!   constant strain;
//! * the condensed stiffness has exactly the six rigid-body modes in its
//!   null space;
//! * pure bending of a rectangular brick: the strain energy of the exact
//!   nodal displacements equals the exact energy ½∫Eκ²z² dV to 1e-12 (the
//!   plain element overestimates it — it locks), and the recovered strain
//!   at every Gauss point is the exact one.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::elasticity::{Mat24, Mat6, SolidGauss};
use super::error::ElementError;
use super::hex8;

/// 6×9 strain of the nine modes at one Gauss point.
pub type GMatrix = SMatrix<f64, 6, 9>;
/// 9×24 map of the nodal displacements to the modes (T).
pub type Mat9x24 = SMatrix<f64, 9, 24>;
/// 9×9 (P = K̂_αα⁻¹).
pub type Mat9 = SMatrix<f64, 9, 9>;

/// The modes of one element and what recovers them at E = 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes {
    /// G_g at the 8 Gauss points ([`super::quadrature::GAUSS2_HEX`] order).
    pub g: [GMatrix; 8],
    /// T = K̂_αα⁻¹ K̂_αu.
    pub t: Mat9x24,
    /// P = K̂_αα⁻¹.
    pub p: Mat9,
}

/// Strain–mode matrix from the physical gradients h_m of the three bubbles:
/// mode 3·c + m moves component c with bubble m (same Voigt layout as the
/// plain B matrix).
fn g_matrix(h: &[Vector3<f64>; 3]) -> GMatrix {
    let mut g = GMatrix::zeros();
    for (m, hm) in h.iter().enumerate() {
        let (dx, dy, dz) = (hm[0], hm[1], hm[2]);
        for c in 0..3 {
            let k = 3 * m + c;
            match c {
                0 => {
                    g[(0, k)] = dx;
                    g[(3, k)] = dy;
                    g[(5, k)] = dz;
                }
                1 => {
                    g[(1, k)] = dy;
                    g[(3, k)] = dx;
                    g[(4, k)] = dz;
                }
                _ => {
                    g[(2, k)] = dz;
                    g[(4, k)] = dy;
                    g[(5, k)] = dx;
                }
            }
        }
    }
    g
}

/// The modes of the element with nodal coordinates `coords` and Gauss
/// points `gauss` ([`super::elasticity::gauss_points`]), condensed with the
/// dimensionless material matrix `q` (D = E·q): the condensed stiffness at
/// E = 1, K̂_uu − K̂_uα T, and the modes.
///
/// Fails with [`ElementError::NonPositiveJacobian`] where the Jacobian at
/// the centre is not positive (the Gauss points were checked already).
pub fn modes(
    coords: &[[f64; 3]; 8],
    gauss: &[SolidGauss; 8],
    q: &Mat6,
) -> Result<(Mat24, Modes), ElementError> {
    let centre = [0.0; 3];
    let (j0, det0) = hex8::jacobian(coords, centre);
    if !hex8::jacobian_ok(&j0, det0) {
        return Err(ElementError::NonPositiveJacobian {
            det: det0,
            point: centre,
        });
    }
    let j0_inv_t: Matrix3<f64> = j0
        .try_inverse()
        .ok_or(ElementError::NonPositiveJacobian {
            det: det0,
            point: centre,
        })?
        .transpose();
    let mut g = [GMatrix::zeros(); 8];
    for (gm, gp) in g.iter_mut().zip(gauss) {
        let [x, y, z] = gp.xi;
        // ∇_ξ of (1 − ξ², 1 − η², 1 − ζ²); gp.weight is det J(ξ_g)
        let scale = det0 / gp.weight;
        let h = [
            j0_inv_t * Vector3::new(-2.0 * x, 0.0, 0.0) * scale,
            j0_inv_t * Vector3::new(0.0, -2.0 * y, 0.0) * scale,
            j0_inv_t * Vector3::new(0.0, 0.0, -2.0 * z) * scale,
        ];
        *gm = g_matrix(&h);
    }
    let mut k_au = Mat9x24::zeros();
    let mut k_aa = Mat9::zeros();
    for (gm, gp) in g.iter().zip(gauss) {
        let qg = q * gm * gp.weight;
        k_au += qg.transpose() * gp.b();
        k_aa += gm.transpose() * qg;
    }
    let k_aa = 0.5 * (k_aa + k_aa.transpose());
    let p = k_aa
        .cholesky()
        .ok_or(ElementError::NonPositiveJacobian {
            det: det0,
            point: centre,
        })?
        .inverse();
    let t = p * k_au;
    let mut k_unit = super::elasticity::stiffness(gauss, q) - k_au.transpose() * t;
    for a in 0..24 {
        for b in 0..a {
            let v = 0.5 * (k_unit[(a, b)] + k_unit[(b, a)]);
            k_unit[(a, b)] = v;
            k_unit[(b, a)] = v;
        }
    }
    Ok((k_unit, Modes { g, t, p }))
}

impl Modes {
    /// f̂_α = Σ_g G_gᵀ q ε0_g w_g: the modes' share of an initial strain's
    /// load at E = 1.
    pub fn mode_load(
        &self,
        gauss: &[SolidGauss; 8],
        q: &Mat6,
        eps0: &[[f64; 6]; 8],
    ) -> SVector<f64, 9> {
        let mut f = SVector::<f64, 9>::zeros();
        for ((gm, gp), e) in self.g.iter().zip(gauss).zip(eps0) {
            if e.iter().all(|&v| v == 0.0) {
                continue;
            }
            let s = q * SVector::<f64, 6>::from_column_slice(e) * gp.weight;
            f += gm.transpose() * s;
        }
        f
    }

    /// The condensed nodal load of an initial strain at E = 1: the plain
    /// element's `f_u` minus Tᵀ f̂_α (multiply by E as the stiffness).
    pub fn condense_load(&self, f_u: &[f64; 24], f_alpha: &SVector<f64, 9>) -> [f64; 24] {
        let corr = self.t.transpose() * f_alpha;
        std::array::from_fn(|k| f_u[k] - corr[k])
    }

    /// The modes' amplitudes α = P f̂_α − T u_e.
    pub fn amplitudes(&self, u_e: &[f64; 24], f_alpha: &SVector<f64, 9>) -> SVector<f64, 9> {
        self.p * f_alpha - self.t * SVector::<f64, 24>::from_column_slice(u_e)
    }

    /// The modes' strain G_g α at Gauss point `g`, to add to B_g u_e.
    pub fn strain(&self, g: usize, alpha: &SVector<f64, 9>) -> [f64; 6] {
        let e = self.g[g] * alpha;
        [e[0], e[1], e[2], e[3], e[4], e[5]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::elasticity::{gauss_points, poisson_matrix, strain};

    fn brick(a: f64, b: f64, c: f64) -> [[f64; 3]; 8] {
        hex8::NODES.map(|n| {
            [
                0.5 * a * (n[0] + 1.0),
                0.5 * b * (n[1] + 1.0),
                0.5 * c * (n[2] + 1.0),
            ]
        })
    }

    fn distorted() -> [[f64; 3]; 8] {
        [
            [0.0, 0.0, 0.0],
            [2.1, 0.2, -0.1],
            [2.4, 1.9, 0.3],
            [-0.2, 1.5, 0.1],
            [0.1, -0.3, 1.8],
            [1.9, 0.1, 2.2],
            [2.2, 2.3, 2.0],
            [0.3, 1.7, 1.6],
        ]
    }

    #[test]
    fn modes_do_no_work_under_constant_stress() {
        let x = distorted();
        let gauss = gauss_points(&x).unwrap();
        let (_, m) = modes(&x, &gauss, &poisson_matrix(0.2)).unwrap();
        let mut sum = GMatrix::zeros();
        for (gm, gp) in m.g.iter().zip(&gauss) {
            sum += gm * gp.weight;
        }
        assert!(sum.amax() < 1e-13 * m.g[0].amax(), "{sum}");
        // a linear field: no mode amplitude, the plain element's strain
        let u: [f64; 24] = std::array::from_fn(|k| {
            let (a, c) = (k / 3, k % 3);
            let p = x[a];
            [
                1e-3 * p[0] + 2e-4 * p[2],
                -3e-4 * p[1] + 1e-4 * p[0],
                5e-4 * p[2],
            ][c]
        });
        let alpha = m.amplitudes(&u, &SVector::zeros());
        assert!(alpha.amax() < 1e-15, "{alpha}");
    }

    #[test]
    fn condensed_stiffness_keeps_six_rigid_modes() {
        let x = distorted();
        let gauss = gauss_points(&x).unwrap();
        let (k, _) = modes(&x, &gauss, &poisson_matrix(0.25)).unwrap();
        let eig = k.symmetric_eigenvalues();
        let max = eig.amax();
        let zero = eig.iter().filter(|v| v.abs() < 1e-10 * max).count();
        assert_eq!(zero, 6, "{eig}");
        assert!(eig.iter().all(|&v| v > -1e-10 * max), "{eig}");
    }

    /// Pure bending about y: σ_xx = Eκz, the exact field
    /// u = (κxz, −νκyz, −κ(x² + ν(z² − y²))/2) on a centred brick.
    #[test]
    fn pure_bending_is_exact_where_the_plain_element_locks() {
        let (a, b, c, nu, kappa) = (6.0, 2.0, 3.0, 0.2, 1e-4);
        let x0 = brick(a, b, c);
        let x: [[f64; 3]; 8] = x0.map(|p| [p[0] - a / 2.0, p[1] - b / 2.0, p[2] - c / 2.0]);
        let u: [f64; 24] = std::array::from_fn(|k| {
            let [px, py, pz] = x[k / 3];
            [
                kappa * px * pz,
                -nu * kappa * py * pz,
                -0.5 * kappa * (px * px + nu * (pz * pz - py * py)),
            ][k % 3]
        });
        let q = poisson_matrix(nu);
        let gauss = gauss_points(&x).unwrap();
        let (k, m) = modes(&x, &gauss, &q).unwrap();
        let uv = SVector::<f64, 24>::from_column_slice(&u);
        let energy = 0.5 * (uv.transpose() * k * uv)[0];
        // ½ ∫ E κ² z² dV at E = 1
        let exact = 0.5 * kappa * kappa * a * b * c.powi(3) / 12.0;
        assert!(
            (energy - exact).abs() < 1e-12 * exact,
            "{energy} vs {exact}"
        );
        let plain = 0.5 * (uv.transpose() * crate::fem::elasticity::stiffness(&gauss, &q) * uv)[0];
        assert!(
            plain > 1.5 * exact,
            "the plain element should lock: {plain} vs {exact}"
        );
        let alpha = m.amplitudes(&u, &SVector::zeros());
        for (g, gp) in gauss.iter().enumerate() {
            let plain = strain(gp, &u);
            let modes = m.strain(g, &alpha);
            let z = hex8::point(&x, gp.xi)[2];
            let want = [kappa * z, -nu * kappa * z, -nu * kappa * z, 0.0, 0.0, 0.0];
            for k in 0..6 {
                assert!((plain[k] + modes[k] - want[k]).abs() < 1e-14, "{g} {k}");
            }
        }
    }
}
