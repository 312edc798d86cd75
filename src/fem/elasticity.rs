//! Small-strain solid elasticity on hex8: B matrices, stiffness, loads, stresses.
//!
//! # Equations
//!
//! Static equilibrium of a linear elastic solid with an initial (eigen)
//! strain ε0 (thermal α·ΔT·(1, 1, 1, 0, 0, 0), autogenous, creep increments):
//!
//! ```text
//! ∇·σ + b = 0   in Ω,        σ = D (ε − ε0),        ε = ½(∇u + ∇uᵀ)
//! u = ū on Γ_u,               σ·n = −p n on Γ_p   (pressure p pushes into the body)
//! ```
//!
//! The Galerkin form on trilinear hex8 elements, with the strain–displacement
//! matrix B (ε = B u_e) evaluated at the 2×2×2 Gauss points g with weights
//! w_g = det J(ξ_g)·1, is
//!
//! ```text
//! K u = f_body + f_pressure + f_ε0
//! K     = Σ_e Σ_g B_gᵀ D B_g w_g                       [`stiffness`]
//! f_ε0  = Σ_e Σ_g B_gᵀ D ε0_g w_g                      [`initial_strain_load`]
//! f_body = Σ_e ∫ Nᵀ b dV                               [`body_force`]
//! f_p   = −Σ_faces ∫ Nᵀ p(x) n dA  (n outward)         [`face_pressure`]
//! ```
//!
//! and the stress at a Gauss point is recovered as σ_g = D (B_g u_e − ε0_g)
//! ([`stress`]); the element's internal force Σ B_gᵀ σ_g w_g
//! ([`internal_force`]) then equals K_e u_e − f_ε0,e.
//!
//! # Conventions
//!
//! * Units m, Pa, N.
//! * Element dof k = 3·node + component, components (u_x, u_y, u_z), nodes in
//!   VTK_HEXAHEDRON order ([`hex8::NODES`]).
//! * Voigt order for stress and strain: [xx, yy, zz, xy, yz, zx], strains with
//!   **engineering** shears γ_ij = 2ε_ij, so σ·ε (Voigt dot) is the energy
//!   density and D is symmetric.
//! * Gauss point g (0..8) of every per-Gauss-point quantity (B, stresses,
//!   initial strains, creep states) is the point
//!   [`GAUSS2_HEX`]`[g]`, i.e. the reference cube corners (±1/√3) in VTK
//!   corner order — **not** the order of [`gauss_hex`](super::quadrature::gauss_hex)`(2)`,
//!   whose first coordinate varies fastest.
//! * D = E·Q ([`isotropic_d`], [`poisson_matrix`]): everything here is linear
//!   in D, so a driver with an ageing modulus E(τ) per element can cache
//!   K_Q = stiffness(g, Q) once and assemble E(τ)·K_Q.
//!
//! # How it is verified (`tests/it/fem_elasticity.rs`)
//!
//! * MacNeal–Harder 7-element patch test (distorted interior nodes, linear
//!   boundary displacements, sparse assembly + Dirichlet + Cholesky): interior
//!   displacements and the stress at every Gauss point are exact to 1e-10.
//! * O(h²) L2 displacement convergence on a manufactured smooth 3-D solution
//!   whose body force is derived analytically from Lamé's form
//!   (λ+μ)∇(∇·u) + μΔu, on meshes n = 2…32.
//! * Restrained thermal stress on distorted multi-element meshes: bar
//!   −EαΔT, plate −EαΔT/(1−ν), solid −EαΔT/(1−2ν) at every Gauss point.
//! * Element checks: six rigid-body modes in the null space, K symmetric
//!   positive semi-definite with exactly six zero eigenvalues, body force sums
//!   to ρgV, constant pressure sums to p·A·(−n), hydrostatic pressure gives the
//!   exact force, consistent nodal values and moment; D against Lamé's
//!   constants and the compliance matrix; von Mises and principal stresses.

use nalgebra::{Matrix3, SMatrix};

use super::error::ElementError;
use super::hex8;
use super::quad4;
use super::quadrature::{GAUSS2_HEX, GAUSS2_QUAD};

/// 6×6 Voigt material matrix.
pub type Mat6 = SMatrix<f64, 6, 6>;
/// 6×24 strain–displacement matrix of one Gauss point.
pub type BMatrix = SMatrix<f64, 6, 24>;
/// 24×24 element stiffness.
pub type Mat24 = SMatrix<f64, 24, 24>;

/// A symmetric 24 × 24 element matrix by its upper triangle, row by row
/// (entries (a, b) with a ≤ b): the order of the pattern's scatter index
/// ([`super::sparse::packed_upper_index`]), so a daily assembly
/// ([`super::SparseSym::add_packed_scaled`]) streams its 300 numbers
/// where a [`Mat24`] is 576 read across its columns (the demo's unit
/// stiffnesses: 12 against 23 MB read each step).
#[derive(Debug, Clone, PartialEq)]
pub struct PackedSym24(pub [f64; 300]);

impl PackedSym24 {
    /// The upper triangle of `k` (its lower one is not read).
    pub fn from_upper(k: &Mat24) -> PackedSym24 {
        let mut p = [0.0; 300];
        let mut idx = 0;
        for a in 0..24 {
            for b in a..24 {
                p[idx] = k[(a, b)];
                idx += 1;
            }
        }
        PackedSym24(p)
    }

    /// Entry (a, b), either triangle.
    #[inline]
    pub fn get(&self, a: usize, b: usize) -> f64 {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        self.0[super::sparse::packed_upper_index(24, lo, hi)]
    }

    /// The whole symmetric matrix.
    pub fn to_full(&self) -> Mat24 {
        Mat24::from_fn(|a, b| self.get(a, b))
    }
}

/// The dimensionless isotropic matrix Q(ν) with D = E·Q (Voigt
/// [xx, yy, zz, xy, yz, zx], engineering shears):
///
/// ```text
///          1          ⎡1−ν  ν   ν                     ⎤
/// Q = ─────────────── ⎢ ν  1−ν  ν                     ⎥
///     (1+ν)(1−2ν)     ⎢ ν   ν  1−ν                    ⎥
///                     ⎢            (1−2ν)/2           ⎥
///                     ⎢                (1−2ν)/2       ⎥
///                     ⎣                    (1−2ν)/2   ⎦
/// ```
///
/// The shear diagonal is 1/(2(1+ν)) = G/E. Valid for −1 < ν < ½ (the
/// entries are infinite at ν = ½); not checked here — validate ν where it is
/// read. Creep and ageing codes reuse Q with an effective modulus.
pub fn poisson_matrix(nu: f64) -> Mat6 {
    let c = 1.0 / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mut q = Mat6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            q[(i, j)] = if i == j { c * (1.0 - nu) } else { c * nu };
        }
        q[(i + 3, i + 3)] = 0.5 / (1.0 + nu);
    }
    q
}

/// Isotropic elasticity matrix D = E·Q(ν) ([`poisson_matrix`]), in Pa for E
/// in Pa: σ = D ε with Voigt [xx, yy, zz, xy, yz, zx] and engineering shears.
pub fn isotropic_d(e: f64, nu: f64) -> Mat6 {
    poisson_matrix(nu) * e
}

/// Thermal initial strain α·ΔT·[1, 1, 1, 0, 0, 0].
#[inline]
pub fn thermal_strain(alpha: f64, delta_t: f64) -> [f64; 6] {
    let e = alpha * delta_t;
    [e, e, e, 0.0, 0.0, 0.0]
}

/// Global dofs of a hex8 whose node n has dofs 3n, 3n+1, 3n+2 (the element
/// dof order of this module, ready for [`Pattern`](super::sparse::Pattern)).
#[inline]
pub fn element_dofs(nodes: &[u32; 8]) -> [u32; 24] {
    let mut d = [0u32; 24];
    for a in 0..8 {
        for c in 0..3 {
            d[3 * a + c] = 3 * nodes[a] + c as u32;
        }
    }
    d
}

/// One Gauss point of a hex8 solid element, precomputed once per element
/// geometry (the mechanics driver caches the 8 of every element).
///
/// It keeps the physical gradients ∇N_a, not B: B has 6 × 24 entries of
/// which 48 are not zero and all are these 24 numbers, and the daily
/// strain loads and stress updates read the table of every live element
/// (the demo's 5,008 elements: 47 MB of B against 7.7 MB of gradients, a
/// read each of the run's 779 steps, on a memory bus the factorisation on
/// the other core shares). [`SolidGauss::b`] forms B where a dense product
/// wants it; [`strain`] and the Bᵀ sums walk the gradients in B's order,
/// so they give the dense products' sums to the bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidGauss {
    /// ∇N_a = (∂N_a/∂x, ∂N_a/∂y, ∂N_a/∂z) of the 8 nodes (VTK order), 1/m
    pub grad: [[f64; 3]; 8],
    /// det J(ξ) · Gauss weight (the weights of the 2×2×2 rule are 1), m³:
    /// the volume this point represents. Σ over the 8 points = element volume.
    pub weight: f64,
    /// Reference coordinates ξ = [`GAUSS2_HEX`]`[g]`.
    pub xi: [f64; 3],
}

impl SolidGauss {
    /// Strain–displacement matrix: ε = B u_e (Voigt, engineering shears,
    /// element dof k = 3·node + component).
    pub fn b(&self) -> BMatrix {
        b_matrix(&self.grad)
    }
}

/// B matrix from physical shape-function gradients ∇N_a.
#[inline]
fn b_matrix(g: &[[f64; 3]; 8]) -> BMatrix {
    let mut b = BMatrix::zeros();
    for (a, &[dx, dy, dz]) in g.iter().enumerate() {
        let c = 3 * a;
        b[(0, c)] = dx;
        b[(1, c + 1)] = dy;
        b[(2, c + 2)] = dz;
        // γ_xy = ∂u_x/∂y + ∂u_y/∂x
        b[(3, c)] = dy;
        b[(3, c + 1)] = dx;
        // γ_yz = ∂u_y/∂z + ∂u_z/∂y
        b[(4, c + 1)] = dz;
        b[(4, c + 2)] = dy;
        // γ_zx = ∂u_z/∂x + ∂u_x/∂z
        b[(5, c)] = dz;
        b[(5, c + 2)] = dx;
    }
    b
}

/// The 8 Gauss points (order of [`GAUSS2_HEX`]) of the hex8 with nodal
/// coordinates `coords` (VTK order).
///
/// Fails with [`ElementError::NonPositiveJacobian`] at the first Gauss point
/// where det J is not positive (inverted, degenerate or misnumbered element,
/// NaN coordinates).
pub fn gauss_points(coords: &[[f64; 3]; 8]) -> Result<[SolidGauss; 8], ElementError> {
    let mut out = [SolidGauss {
        grad: [[0.0; 3]; 8],
        weight: 0.0,
        xi: [0.0; 3],
    }; 8];
    for (gp, &xi) in out.iter_mut().zip(GAUSS2_HEX.iter()) {
        let (grad, det) = hex8::shape_grad(coords, xi)?;
        *gp = SolidGauss {
            grad,
            weight: det,
            xi,
        };
    }
    Ok(out)
}

/// Element stiffness K = Σ_g B_gᵀ D B_g w_g (24×24, exactly symmetric: the
/// upper triangle is computed and mirrored).
///
/// Linear in `d`: `stiffness(g, &poisson_matrix(nu)) * e` equals
/// `stiffness(g, &isotropic_d(e, nu))` up to rounding.
pub fn stiffness(g: &[SolidGauss; 8], d: &Mat6) -> Mat24 {
    let mut k = Mat24::zeros();
    for gp in g {
        let b = gp.b();
        let db: BMatrix = d * b * gp.weight;
        k.gemm_tr(1.0, &b, &db, 1.0);
    }
    for a in 0..24 {
        for b in 0..a {
            k[(a, b)] = k[(b, a)];
        }
    }
    k
}

/// Stiffness of an isotropic element straight from its coordinates:
/// [`gauss_points`] then [`stiffness`] with [`isotropic_d`]`(e, nu)`.
pub fn stiffness_of(coords: &[[f64; 3]; 8], e: f64, nu: f64) -> Result<Mat24, ElementError> {
    let g = gauss_points(coords)?;
    Ok(stiffness(&g, &isotropic_d(e, nu)))
}

/// f = Σ_g B_gᵀ v_g w_g for per-Gauss-point Voigt vectors v_g.
///
/// Column k of B has its nonzeros in rows (0, 3, 5), (1, 3, 4) or
/// (2, 4, 5) for k = 3a, 3a + 1, 3a + 2 ([`b_matrix`]); each column's sum
/// adds them in row order, as the dense column's would (its zero terms
/// add nothing).
#[inline]
fn bt_sum(g: &[SolidGauss; 8], v: impl Fn(usize) -> [f64; 6]) -> [f64; 24] {
    let mut f = [0.0; 24];
    for (i, gp) in g.iter().enumerate() {
        let s = v(i);
        for (a, &[dx, dy, dz]) in gp.grad.iter().enumerate() {
            let c = 3 * a;
            f[c] += (dx * s[0] + dy * s[3] + dz * s[5]) * gp.weight;
            f[c + 1] += (dy * s[1] + dx * s[3] + dz * s[4]) * gp.weight;
            f[c + 2] += (dz * s[2] + dy * s[4] + dx * s[5]) * gp.weight;
        }
    }
    f
}

/// Nodal load of an initial (eigen) strain: f_ε0 = Σ_g B_gᵀ D ε0_g w_g, with
/// `eps0[g]` the Voigt initial strain (engineering shears) at Gauss point g.
///
/// Sign: the system is K u = f_ext + f_ε0, and the stress is then
/// σ = D(B u − ε0) ([`stress`]). A thermal strain is
/// [`thermal_strain`]`(α, ΔT)`.
pub fn initial_strain_load(g: &[SolidGauss; 8], d: &Mat6, eps0: &[[f64; 6]; 8]) -> [f64; 24] {
    bt_sum(g, |i| {
        let s = d * SMatrix::<f64, 6, 1>::from_column_slice(&eps0[i]);
        [s[0], s[1], s[2], s[3], s[4], s[5]]
    })
}

/// Internal (resisting) force f_int = Σ_g B_gᵀ σ_g w_g of Gauss-point
/// stresses `stress[g]` (Voigt, Pa). Equilibrium of an element is
/// f_int = f_ext on its free dofs; an initial stress σ0 loads the system with
/// −internal_force(g, σ0).
pub fn internal_force(g: &[SolidGauss; 8], stress: &[[f64; 6]; 8]) -> [f64; 24] {
    bt_sum(g, |i| stress[i])
}

/// Strain ε = B u_e at one Gauss point (Voigt, engineering shears).
///
/// Each row sums its nonzeros in column order, as the dense row's would.
#[inline]
pub fn strain(g_point: &SolidGauss, u_e: &[f64; 24]) -> [f64; 6] {
    let mut e = [0.0; 6];
    for (a, &[dx, dy, dz]) in g_point.grad.iter().enumerate() {
        let (ux, uy, uz) = (u_e[3 * a], u_e[3 * a + 1], u_e[3 * a + 2]);
        e[0] += dx * ux;
        e[1] += dy * uy;
        e[2] += dz * uz;
        e[3] += dy * ux;
        e[3] += dx * uy;
        e[4] += dz * uy;
        e[4] += dy * uz;
        e[5] += dz * ux;
        e[5] += dx * uz;
    }
    e
}

/// Stress σ = D(B u_e − ε0) at one Gauss point.
#[inline]
pub fn stress(g_point: &SolidGauss, d: &Mat6, u_e: &[f64; 24], eps0: &[f64; 6]) -> [f64; 6] {
    let e = strain(g_point, u_e);
    let m = SMatrix::<f64, 6, 1>::from_fn(|r, _| e[r] - eps0[r]);
    let s = d * m;
    [s[0], s[1], s[2], s[3], s[4], s[5]]
}

/// Consistent nodal load of a uniform body force b (N/m³):
/// f_{3a+i} = b_i ∫ N_a dV, e.g. self-weight b = (0, 0, −ρg). Exact for any
/// trilinear hex; Σ_a f_{3a+i} = b_i·V.
pub fn body_force(coords: &[[f64; 3]; 8], b: [f64; 3]) -> Result<[f64; 24], ElementError> {
    let mut f = [0.0; 24];
    // N_a det J has degree ≤ 3 per direction: 2-point Gauss is exact
    for &q in GAUSS2_HEX.iter() {
        let (j, det) = hex8::jacobian(coords, q);
        if !hex8::jacobian_ok(&j, det) {
            return Err(ElementError::NonPositiveJacobian { det, point: q });
        }
        let n = hex8::shape(q);
        for a in 0..8 {
            for i in 0..3 {
                f[3 * a + i] += b[i] * n[a] * det;
            }
        }
    }
    Ok(f)
}

/// [`body_force`] from cached Gauss points, those of [`gauss_points`] in
/// its order (same values: the 2×2×2 rule is exact for a uniform b).
pub fn body_force_at(g: &[SolidGauss; 8], b: [f64; 3]) -> [f64; 24] {
    let mut f = [0.0; 24];
    for (gp, n) in g.iter().zip(hex8::shape_at_gauss2()) {
        for a in 0..8 {
            for i in 0..3 {
                f[3 * a + i] += b[i] * n[a] * gp.weight;
            }
        }
    }
    f
}

/// Consistent nodal forces of a pressure p(x) (Pa, positive = compression)
/// acting on a quad4 face **into** the body, i.e. along −n with n the outward
/// normal: f_{3a+i} = −∫ p(x) N_a n_i dA, by 2×2 Gauss at the points
/// x(s, t) of the face.
///
/// The outward normal is the right-hand normal ∂x/∂s × ∂x/∂t of the node
/// order given, which is outward for a [`hex8::FACES`] face
/// ([`hex8::face_coords`]); the 12 entries follow that node order.
/// Exact for p linear in x on a planar face (hydrostatic water load
/// p = ρ_w g (h_w − z) on a fully submerged face); split faces at the
/// waterline, since a kinked p = max(0, …) is only integrated approximately.
/// Fails with [`ElementError::DegenerateFace`] on a degenerate face.
pub fn face_pressure(
    face_coords: &[[f64; 3]; 4],
    p: impl Fn([f64; 3]) -> f64,
) -> Result<[f64; 12], ElementError> {
    let mut f = [0.0; 12];
    for &q in GAUSS2_QUAD.iter() {
        // n_s = ∂x/∂s × ∂x/∂t = n dA/(ds dt)
        let (ns, _) = quad4::surface_jacobian(face_coords, q)?;
        let pq = p(quad4::point(face_coords, q));
        let n = quad4::shape(q);
        for a in 0..4 {
            for i in 0..3 {
                f[3 * a + i] -= pq * n[a] * ns[i];
            }
        }
    }
    Ok(f)
}

/// Von Mises equivalent stress
/// √(½[(σx−σy)² + (σy−σz)² + (σz−σx)²] + 3(τxy² + τyz² + τzx²)).
#[inline]
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let [sx, sy, sz, txy, tyz, tzx] = *s;
    (0.5 * ((sx - sy).powi(2) + (sy - sz).powi(2) + (sz - sx).powi(2))
        + 3.0 * (txy * txy + tyz * tyz + tzx * tzx))
        .sqrt()
}

/// Principal stresses σ1 ≥ σ2 ≥ σ3 of a Voigt stress (tension positive).
pub fn principal_stresses(s: &[f64; 6]) -> [f64; 3] {
    let m = Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]);
    let e = m.symmetric_eigenvalues();
    let mut v = [e[0], e[1], e[2]];
    v.sort_by(|a, b| b.total_cmp(a));
    v
}
