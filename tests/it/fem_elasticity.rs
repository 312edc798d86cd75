//! Acceptance tests of `groutready::fem::elasticity` (small-strain hex8
//! solids): MacNeal–Harder patch test, O(h²) convergence on a manufactured
//! solution, restrained thermal stress (DESIGN §7) and element checks.

#![allow(clippy::needless_range_loop)]

use crate::common;

use common::Rng;

use std::sync::Arc;
use std::time::Instant;

use groutready::fem::elasticity::{
    body_force, body_force_at, element_dofs, face_pressure, gauss_points, initial_strain_load,
    internal_force, isotropic_d, poisson_matrix, principal_stresses, stiffness, stiffness_of,
    strain, stress, thermal_strain, von_mises, Mat24, Mat6, SolidGauss,
};
use groutready::fem::quadrature::GAUSS2_HEX;
use groutready::fem::{
    gauss_hex, hex8, nested_dissection, CholeskySolver, ElementError, Ordering, Pattern, SparseSym,
};
use nalgebra::{Matrix3, SMatrix};

// ---------------------------------------------------------------- helpers

struct Mesh {
    nodes: Vec<[f64; 3]>,
    elems: Vec<[u32; 8]>,
}

impl Mesh {
    fn coords(&self, e: usize) -> [[f64; 3]; 8] {
        self.elems[e].map(|n| self.nodes[n as usize])
    }
    fn n_dofs(&self) -> usize {
        3 * self.nodes.len()
    }
    fn gather(&self, e: usize, u: &[f64]) -> [f64; 24] {
        let d = element_dofs(&self.elems[e]);
        d.map(|k| u[k as usize])
    }
}

/// Structured nx×ny×nz box [0,L]³ whose node (i,j,k) is moved by `map`.
fn box_mesh(n: [usize; 3], map: impl Fn([usize; 3]) -> [f64; 3]) -> Mesh {
    let [nx, ny, nz] = n;
    let id = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let mut nodes = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push(map([i, j, k]));
            }
        }
    }
    let mut elems = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                elems.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    Mesh { nodes, elems }
}

/// Box of size `size` with every node jittered by up to `jitter`·h along each
/// axis in which it is not on the boundary: boundary faces stay planar (so
/// rollers act along the axes) while every element is a general trilinear hex.
fn jittered_box(n: [usize; 3], size: [f64; 3], jitter: f64, rng: &mut Rng) -> Mesh {
    let h = [0, 1, 2].map(|c| size[c] / n[c] as f64);
    let mut r = Vec::new();
    for _ in 0..(n[0] + 1) * (n[1] + 1) * (n[2] + 1) * 3 {
        r.push(rng.range(-jitter, jitter));
    }
    let mesh = box_mesh(n, |ijk| {
        let lin = ijk[0] + (n[0] + 1) * (ijk[1] + (n[1] + 1) * ijk[2]);
        [0, 1, 2].map(|c| {
            let inner = ijk[c] > 0 && ijk[c] < n[c];
            let d = if inner { r[3 * lin + c] * h[c] } else { 0.0 };
            ijk[c] as f64 * h[c] + d
        })
    });
    for e in 0..mesh.elems.len() {
        hex8::check(&mesh.coords(e)).expect("jittered mesh must stay valid");
    }
    mesh
}

/// Assembles the element matrices, applies u = `u_fixed` on `fixed` dofs and
/// solves K u = f by the crate's sparse Cholesky.
fn solve(mesh: &Mesh, ke: &[Mat24], f: &[f64], fixed: &[bool], u_fixed: &[f64]) -> Vec<f64> {
    let dofs: Vec<[u32; 24]> = mesh.elems.iter().map(element_dofs).collect();
    let pattern = Arc::new(Pattern::new(mesh.n_dofs(), &dofs));
    let mut k = SparseSym::new(pattern.clone());
    for (slot, m) in ke.iter().enumerate() {
        k.add_element(slot, m);
    }
    let mut rhs = f.to_vec();
    k.apply_dirichlet_with_rhs(fixed, u_fixed, &mut rhs);
    // geometric nested dissection: on cube meshes about twice as fast as AMD
    let dof_coords: Vec<[f64; 3]> = (0..mesh.n_dofs()).map(|k| mesh.nodes[k / 3]).collect();
    let order = Ordering::Custom(nested_dissection(&pattern, &dof_coords, 64));
    let mut solver =
        CholeskySolver::with_options(pattern, &order, faer::Par::rayon(0)).expect("symbolic");
    solver.factorize(&k).expect("K must be positive definite");
    solver.solve_in_place(&mut rhs).expect("solve");
    rhs
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn vec6(m: &SMatrix<f64, 6, 1>) -> [f64; 6] {
    [m[0], m[1], m[2], m[3], m[4], m[5]]
}

/// Least-squares slope of log(err) against log(h).
fn fitted_slope(h: &[f64], err: &[f64]) -> f64 {
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// A distorted (non-parallelepiped) hex with positive Jacobian.
fn distorted_hex() -> [[f64; 3]; 8] {
    let c = [
        [0.1, -0.05, 0.0],
        [2.1, 0.12, -0.1],
        [2.3, 1.6, 0.15],
        [-0.2, 1.4, 0.05],
        [0.05, 0.1, 1.2],
        [1.9, -0.1, 0.9],
        [2.0, 1.3, 1.1],
        [0.2, 1.5, 1.3],
    ];
    hex8::check(&c).unwrap();
    c
}

// ---------------------------------------------------- a. MacNeal–Harder patch

/// Outer unit-cube corners (VTK order) then the 8 interior nodes of
/// MacNeal & Harder (1985), interior node 8+i paired with corner i.
fn macneal_harder() -> Mesh {
    let mut nodes: Vec<[f64; 3]> = hex8::NODES
        .iter()
        .map(|p| p.map(|v| 0.5 * (v + 1.0)))
        .collect();
    nodes.extend_from_slice(&[
        [0.249, 0.342, 0.192],
        [0.826, 0.288, 0.288],
        [0.850, 0.649, 0.263],
        [0.273, 0.750, 0.230],
        [0.320, 0.186, 0.643],
        [0.677, 0.305, 0.683],
        [0.788, 0.693, 0.644],
        [0.165, 0.745, 0.702],
    ]);
    // centre element, then for every cube face [a,b,c,d] (outward
    // right-hand order) the element with the inner face at ζ = −1 and the
    // outer face at ζ = +1: [a+8, b+8, c+8, d+8, a, b, c, d]
    let mut elems = vec![[8, 9, 10, 11, 12, 13, 14, 15]];
    for f in hex8::FACES {
        let f = f.map(|a| a as u32);
        elems.push([
            f[0] + 8,
            f[1] + 8,
            f[2] + 8,
            f[3] + 8,
            f[0],
            f[1],
            f[2],
            f[3],
        ]);
    }
    Mesh { nodes, elems }
}

#[test]
fn macneal_harder_patch_test_is_exact() {
    let mesh = macneal_harder();
    assert_eq!(mesh.elems.len(), 7);
    // Every element is positively oriented with det J > 0 at all its Gauss
    // points, and together they fill the unit cube exactly. (The standard
    // coordinates leave one corner slightly inverted: in the element between
    // the y = 0 face and the core, det J = −1.58e-3 at the corner on interior
    // node (0.320, 0.186, 0.643), so `hex8::check`, which also tests corners,
    // rejects it; the Gauss-point Jacobians that the stiffness uses are all
    // positive.)
    let mut vol = 0.0;
    let mut min_gauss_det = f64::INFINITY;
    for e in 0..7 {
        let c = mesh.coords(e);
        for &q in GAUSS2_HEX.iter() {
            min_gauss_det = min_gauss_det.min(hex8::jacobian(&c, q).1);
        }
        vol += hex8::volume(&c);
    }
    let min_corner_det = (0..7)
        .flat_map(|e| hex8::NODES.map(|p| hex8::jacobian(&mesh.coords(e), p).1))
        .fold(f64::INFINITY, f64::min);
    eprintln!("MacNeal–Harder mesh: min det J at Gauss points {min_gauss_det:.4e}, at corners {min_corner_det:.4e}");
    assert!(
        min_gauss_det > 1e-3,
        "min Gauss-point det J {min_gauss_det}"
    );
    assert!((vol - 1.0).abs() < 1e-14, "volume {vol}");

    // the standard field u = 1e-3 (2x + y + z, x + 2y + z, x + y + 2z)/2 and a
    // general linear field (non-symmetric gradient: the standard one cannot
    // tell ∂/∂x from ∂/∂y in a shear row), with a translation
    let standard = [
        [1e-3, 0.5e-3, 0.5e-3],
        [0.5e-3, 1e-3, 0.5e-3],
        [0.5e-3, 0.5e-3, 1e-3],
    ];
    let general = [
        [0.7e-3, -1.3e-3, 0.4e-3],
        [2.1e-3, -0.5e-3, 0.9e-3],
        [-0.8e-3, 1.6e-3, 1.2e-3],
    ];
    for (label, grad, t) in [
        ("standard", standard, [0.0; 3]),
        ("general", general, [2e-4, -1e-4, 3e-4]),
    ] {
        let (u_rel, e_rel, s_rel, f_rel) = patch_case(&mesh, label, grad, t);
        assert!(
            u_rel <= 1e-10,
            "{label}: interior displacement error {u_rel:e}"
        );
        assert!(e_rel <= 1e-10, "{label}: strain error {e_rel:e}");
        assert!(s_rel <= 1e-10, "{label}: stress error {s_rel:e}");
        assert!(
            f_rel <= 1e-10,
            "{label}: interior nodes not in equilibrium: {f_rel:e}"
        );
    }
}

/// Solves the 7-element patch with u = grad·x + t on the 8 outer corners;
/// returns the max relative errors of the interior displacements, of the
/// strain and stress at all 56 Gauss points and the interior residual.
fn patch_case(mesh: &Mesh, label: &str, grad: [[f64; 3]; 3], t: [f64; 3]) -> (f64, f64, f64, f64) {
    let (e_mod, nu) = (1e6, 0.25);
    let d = isotropic_d(e_mod, nu);
    let exact =
        |x: [f64; 3]| [0, 1, 2].map(|i| t[i] + (0..3).map(|j| grad[i][j] * x[j]).sum::<f64>());
    // the constant strain of the field (engineering γ)
    let eps = [
        grad[0][0],
        grad[1][1],
        grad[2][2],
        grad[0][1] + grad[1][0],
        grad[1][2] + grad[2][1],
        grad[2][0] + grad[0][2],
    ];
    let e_scale = max_abs(&eps);
    let sigma = vec6(&(d * SMatrix::<f64, 6, 1>::from_column_slice(&eps)));
    let n = mesh.n_dofs();
    let mut fixed = vec![false; n];
    let mut u_fixed = vec![0.0; n];
    for a in 0..8 {
        let ue = exact(mesh.nodes[a]);
        for c in 0..3 {
            fixed[3 * a + c] = true;
            u_fixed[3 * a + c] = ue[c];
        }
    }
    let gps: Vec<[SolidGauss; 8]> = (0..7)
        .map(|e| gauss_points(&mesh.coords(e)).unwrap())
        .collect();
    let ke: Vec<Mat24> = gps.iter().map(|g| stiffness(g, &d)).collect();
    let u = solve(mesh, &ke, &vec![0.0; n], &fixed, &u_fixed);

    let mut u_err = 0.0f64;
    let mut u_scale = 0.0f64;
    for a in 8..16 {
        let ue = exact(mesh.nodes[a]);
        for c in 0..3 {
            u_err = u_err.max((u[3 * a + c] - ue[c]).abs());
            u_scale = u_scale.max(ue[c].abs());
        }
    }
    let u_rel = u_err / u_scale;

    let s_scale = max_abs(&sigma);
    let mut s_rel = 0.0f64;
    let mut e_rel = 0.0f64;
    for (e, g) in gps.iter().enumerate() {
        let ue = mesh.gather(e, &u);
        for gp in g.iter() {
            let s = stress(gp, &d, &ue, &[0.0; 6]);
            let st = strain(gp, &ue);
            for r in 0..6 {
                s_rel = s_rel.max((s[r] - sigma[r]).abs() / s_scale);
                e_rel = e_rel.max((st[r] - eps[r]).abs() / e_scale);
            }
        }
    }
    // equilibrium: assembled internal forces vanish at the 8 interior nodes
    let mut fint = vec![0.0; n];
    for (e, g) in gps.iter().enumerate() {
        let ue = mesh.gather(e, &u);
        let s: [[f64; 6]; 8] = std::array::from_fn(|i| stress(&g[i], &d, &ue, &[0.0; 6]));
        let f = internal_force(g, &s);
        for (k, &dof) in element_dofs(&mesh.elems[e]).iter().enumerate() {
            fint[dof as usize] += f[k];
        }
    }
    let f_rel = max_abs(&fint[24..]) / max_abs(&fint[..24]);
    eprintln!(
        "MacNeal–Harder patch, {label}: max rel. error u = {u_rel:.3e}, ε = {e_rel:.3e}, \
         σ = {s_rel:.3e} (56 Gauss points), interior residual = {f_rel:.3e}"
    );
    (u_rel, e_rel, s_rel, f_rel)
}

// ------------------------------------------- b. manufactured-solution O(h²)

/// 1-D factor: value, first and second derivative.
#[derive(Clone, Copy)]
enum F1 {
    Sin(f64, f64),       // sin(a x + b)
    Cos(f64, f64),       // cos(a x + b)
    Poly(f64, f64, f64), // c0 + c1 x + c2 x²
}

impl F1 {
    fn eval(self, x: f64, order: usize) -> f64 {
        match self {
            F1::Sin(a, b) => match order {
                0 => (a * x + b).sin(),
                1 => a * (a * x + b).cos(),
                _ => -a * a * (a * x + b).sin(),
            },
            F1::Cos(a, b) => match order {
                0 => (a * x + b).cos(),
                1 => -a * (a * x + b).sin(),
                _ => -a * a * (a * x + b).cos(),
            },
            F1::Poly(c0, c1, c2) => match order {
                0 => c0 + c1 * x + c2 * x * x,
                1 => c1 + 2.0 * c2 * x,
                _ => 2.0 * c2,
            },
        }
    }
}

/// u_i(x) = AMP · Π_j F[i][j](x_j): smooth, fully coupled in 3-D.
const AMP: f64 = 1e-3;
const MANUFACTURED: [[F1; 3]; 3] = [
    [
        F1::Sin(2.1, 0.2),
        F1::Cos(1.3, 0.0),
        F1::Poly(1.0, 0.5, 0.0),
    ],
    [
        F1::Poly(1.0, 0.0, 1.0),
        F1::Sin(1.7, 0.3),
        F1::Cos(1.1, 0.4),
    ],
    [
        F1::Cos(1.5, 0.0),
        F1::Poly(1.0, 0.4, -0.3),
        F1::Sin(1.9, 0.1),
    ],
];

/// ∂^{o0+o1+o2} u_i / ∂x^o0 ∂y^o1 ∂z^o2.
fn mfg_deriv(i: usize, x: [f64; 3], o: [usize; 3]) -> f64 {
    AMP * (0..3)
        .map(|j| MANUFACTURED[i][j].eval(x[j], o[j]))
        .product::<f64>()
}

fn mfg_u(x: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| mfg_deriv(i, x, [0, 0, 0]))
}

/// b = −∇·σ(u) = −[(λ+μ)∇(∇·u) + μΔu], from the analytic second derivatives.
fn mfg_body_force(x: [f64; 3], lambda: f64, mu: f64) -> [f64; 3] {
    let unit = |k: usize| {
        let mut o = [0; 3];
        o[k] = 1;
        o
    };
    let hess = |i: usize, k: usize, l: usize| {
        let mut o = unit(k);
        o[l] += 1;
        mfg_deriv(i, x, o)
    };
    [0, 1, 2].map(|i| {
        let grad_div: f64 = (0..3).map(|k| hess(k, k, i)).sum();
        let lap: f64 = (0..3).map(|k| hess(i, k, k)).sum();
        -((lambda + mu) * grad_div + mu * lap)
    })
}

/// Relative L2 displacement error on an n³ mesh of the unit cube, smoothly
/// mapped x = X + δ sin(πX) sin(πY) sin(πZ) (a, b, c) (boundary fixed).
fn manufactured_error(n: usize) -> (f64, f64) {
    let (e_mod, nu) = (3.0e10, 0.3);
    let lambda = e_mod * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e_mod / (2.0 * (1.0 + nu));
    let d = isotropic_d(e_mod, nu);
    let h = 1.0 / n as f64;
    let mesh = box_mesh([n, n, n], |ijk| {
        let xx = ijk.map(|v| v as f64 * h);
        let bump = (std::f64::consts::PI * xx[0]).sin()
            * (std::f64::consts::PI * xx[1]).sin()
            * (std::f64::consts::PI * xx[2]).sin();
        [
            xx[0] + 0.06 * bump,
            xx[1] - 0.04 * bump,
            xx[2] + 0.05 * bump,
        ]
    });
    let ndof = mesh.n_dofs();
    let rule3 = gauss_hex(3);
    let mut ke = Vec::with_capacity(mesh.elems.len());
    let mut f = vec![0.0; ndof];
    for e in 0..mesh.elems.len() {
        let c = mesh.coords(e);
        let g = gauss_points(&c).unwrap();
        ke.push(stiffness(&g, &d));
        // ∫ N b(x) dV by 3×3×3 Gauss (b varies in space)
        let dofs = element_dofs(&mesh.elems[e]);
        for (q, w) in rule3.iter() {
            let (_, det) = hex8::jacobian(&c, q);
            let nq = hex8::shape(q);
            let b = mfg_body_force(hex8::point(&c, q), lambda, mu);
            for a in 0..8 {
                for i in 0..3 {
                    f[dofs[3 * a + i] as usize] += nq[a] * b[i] * det * w;
                }
            }
        }
    }
    let mut fixed = vec![false; ndof];
    let mut u_fixed = vec![0.0; ndof];
    for (a, x) in mesh.nodes.iter().enumerate() {
        if x.iter()
            .any(|&v| v.abs() < 1e-12 || (v - 1.0).abs() < 1e-12)
        {
            let ue = mfg_u(*x);
            for c in 0..3 {
                fixed[3 * a + c] = true;
                u_fixed[3 * a + c] = ue[c];
            }
        }
    }
    let u = solve(&mesh, &ke, &f, &fixed, &u_fixed);
    // L2 error and norm by 3×3×3 Gauss
    let (mut err2, mut norm2) = (0.0, 0.0);
    for e in 0..mesh.elems.len() {
        let c = mesh.coords(e);
        let ue = mesh.gather(e, &u);
        for (q, w) in rule3.iter() {
            let (_, det) = hex8::jacobian(&c, q);
            let nq = hex8::shape(q);
            let ex = mfg_u(hex8::point(&c, q));
            for i in 0..3 {
                let uh: f64 = (0..8).map(|a| nq[a] * ue[3 * a + i]).sum();
                err2 += (uh - ex[i]).powi(2) * det * w;
                norm2 += ex[i].powi(2) * det * w;
            }
        }
    }
    (h, (err2 / norm2).sqrt())
}

#[test]
fn manufactured_solution_converges_at_second_order() {
    // the body force from Lamé's form must be the divergence of σ = D ε
    // built from this module's D: check at a point by central differences
    let (e_mod, nu) = (3.0e10, 0.3);
    let lambda = e_mod * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e_mod / (2.0 * (1.0 + nu));
    let d = isotropic_d(e_mod, nu);
    let sigma_at = |x: [f64; 3]| {
        let du = |i: usize, k: usize| {
            let mut o = [0; 3];
            o[k] = 1;
            mfg_deriv(i, x, o)
        };
        let eps = SMatrix::<f64, 6, 1>::from_column_slice(&[
            du(0, 0),
            du(1, 1),
            du(2, 2),
            du(0, 1) + du(1, 0),
            du(1, 2) + du(2, 1),
            du(2, 0) + du(0, 2),
        ]);
        vec6(&(d * eps))
    };
    let x0 = [0.37, 0.61, 0.23];
    let hfd = 1e-4;
    // rows of σ (Voigt index) per component: σ_i· = (i, j) → Voigt
    let voigt = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
    let b = mfg_body_force(x0, lambda, mu);
    for i in 0..3 {
        let mut div = 0.0;
        for j in 0..3 {
            let mut xp = x0;
            let mut xm = x0;
            xp[j] += hfd;
            xm[j] -= hfd;
            div += (sigma_at(xp)[voigt[i][j]] - sigma_at(xm)[voigt[i][j]]) / (2.0 * hfd);
        }
        assert!(
            (div + b[i]).abs() <= 1e-6 * b[i].abs().max(1.0),
            "component {i}: −div σ = {} but b = {}",
            -div,
            b[i]
        );
    }

    convergence_study(&[2, 4, 8, 16]);
}

/// The same study with n = 32 added (≈ 108k dofs; its Cholesky takes ~20 s
/// on two cores): `cargo test --release --test fem_elasticity -- --ignored`.
#[test]
#[ignore = "slow: n = 32 (108k dofs)"]
fn manufactured_solution_converges_at_second_order_up_to_n32() {
    convergence_study(&[2, 4, 8, 16, 32]);
}

fn convergence_study(ns: &[usize]) {
    let mut hs = Vec::new();
    let mut errs = Vec::new();
    for &n in ns {
        let t = Instant::now();
        let (h, err) = manufactured_error(n);
        eprintln!(
            "manufactured n = {n:2}: h = {h:.5}, relative L2 error = {err:.4e} ({:.2} s)",
            t.elapsed().as_secs_f64()
        );
        hs.push(h);
        errs.push(err);
    }
    let slope = fitted_slope(&hs, &errs);
    let pair: Vec<String> = (1..hs.len())
        .map(|k| {
            format!(
                "{:.3}",
                (errs[k - 1] / errs[k]).ln() / (hs[k - 1] / hs[k]).ln()
            )
        })
        .collect();
    eprintln!("least-squares slope = {slope:.4}; pairwise rates = {pair:?}");
    assert!((slope - 2.0).abs() < 0.15, "slope {slope}");
    // every refinement gains close to a factor 4
    for k in 1..errs.len() {
        let rate = (errs[k - 1] / errs[k]).log2();
        assert!(
            (rate - 2.0).abs() < 0.15,
            "rate {rate} between n = {} and {}",
            ns[k - 1],
            ns[k]
        );
    }
    assert!(*errs.last().unwrap() < 2e-3, "errors {errs:?}");
}

// ------------------------------------------- c. restrained thermal stress

/// Which faces of the box carry rollers (normal displacement 0).
#[derive(Debug, Clone, Copy)]
enum Restraint {
    /// u_x = 0 at x = 0 and x = L; symmetry rollers u_y = 0 at y = 0,
    /// u_z = 0 at z = 0; lateral faces y = b, z = c free.
    Bar,
    /// u_x = 0 at both x faces, u_y = 0 at both y faces, u_z = 0 at z = 0.
    Plate,
    /// normal displacement 0 on all six faces.
    Solid,
}

fn restrained_thermal(kind: Restraint) {
    let (e_mod, nu, alpha, dt) = (3.0e10, 0.2, 1.0e-5, -20.0);
    let size = [3.0, 1.0, 0.7];
    let mut rng = Rng(0x5EED_1234_ABCD_0001 ^ kind as u64);
    let mesh = jittered_box([5, 3, 3], size, 0.22, &mut rng);
    let d = isotropic_d(e_mod, nu);
    let eps0 = thermal_strain(alpha, dt);
    let ea = e_mod * alpha * dt;
    // expected stress and displacement gradient (u = diag(g) x)
    let (sig, grad) = match kind {
        Restraint::Bar => (
            [-ea, 0.0, 0.0],
            [0.0, (1.0 + nu) * alpha * dt, (1.0 + nu) * alpha * dt],
        ),
        Restraint::Plate => {
            let s = -ea / (1.0 - nu);
            (
                [s, s, 0.0],
                [0.0, 0.0, (1.0 + nu) / (1.0 - nu) * alpha * dt],
            )
        }
        Restraint::Solid => {
            let s = -ea / (1.0 - 2.0 * nu);
            ([s, s, s], [0.0, 0.0, 0.0])
        }
    };
    let ndof = mesh.n_dofs();
    let mut fixed = vec![false; ndof];
    for (a, x) in mesh.nodes.iter().enumerate() {
        for c in 0..3 {
            let lo = x[c].abs() < 1e-12;
            let hi = (x[c] - size[c]).abs() < 1e-12;
            let roll = match (kind, c) {
                (Restraint::Bar, 0) | (Restraint::Plate, 0 | 1) | (Restraint::Solid, _) => lo || hi,
                _ => lo,
            };
            fixed[3 * a + c] = roll;
        }
    }
    let gps: Vec<[SolidGauss; 8]> = (0..mesh.elems.len())
        .map(|e| gauss_points(&mesh.coords(e)).unwrap())
        .collect();
    let ke: Vec<Mat24> = gps.iter().map(|g| stiffness(g, &d)).collect();
    let mut f = vec![0.0; ndof];
    for (e, g) in gps.iter().enumerate() {
        let fe = initial_strain_load(g, &d, &[eps0; 8]);
        for (k, &dof) in element_dofs(&mesh.elems[e]).iter().enumerate() {
            f[dof as usize] += fe[k];
        }
    }
    let u = solve(&mesh, &ke, &f, &fixed, &vec![0.0; ndof]);

    // displacements: u_c = grad_c · x_c
    let u_scale = (0..3)
        .map(|c| (grad[c] * size[c]).abs())
        .fold(alpha * dt.abs(), f64::max);
    let mut u_err = 0.0f64;
    for (a, x) in mesh.nodes.iter().enumerate() {
        for c in 0..3 {
            u_err = u_err.max((u[3 * a + c] - grad[c] * x[c]).abs());
        }
    }
    // stresses at every Gauss point, and equilibrium of the free dofs
    let s_ref = sig.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let expected = [sig[0], sig[1], sig[2], 0.0, 0.0, 0.0];
    let mut s_err = 0.0f64;
    let mut fint = vec![0.0; ndof];
    for (e, g) in gps.iter().enumerate() {
        let ue = mesh.gather(e, &u);
        let s: [[f64; 6]; 8] = std::array::from_fn(|i| stress(&g[i], &d, &ue, &eps0));
        for si in &s {
            for r in 0..6 {
                s_err = s_err.max((si[r] - expected[r]).abs() / s_ref);
            }
        }
        let fe = internal_force(g, &s);
        for (k, &dof) in element_dofs(&mesh.elems[e]).iter().enumerate() {
            fint[dof as usize] += fe[k];
        }
    }
    let free_res = (0..ndof)
        .filter(|&k| !fixed[k])
        .fold(0.0f64, |m, k| m.max(fint[k].abs()));
    let react = (0..ndof)
        .filter(|&k| fixed[k])
        .fold(0.0f64, |m, k| m.max(fint[k].abs()));
    eprintln!(
        "restrained {kind:?}: σ = {:.6e} Pa; max rel. error σ = {s_err:.3e} over {} Gauss points, \
         u = {:.3e}, free-dof residual = {:.3e}",
        sig[0],
        8 * mesh.elems.len(),
        u_err / u_scale,
        free_res / react
    );
    assert!(s_err <= 1e-10, "{kind:?}: stress error {s_err:e}");
    assert!(u_err <= 1e-10 * u_scale, "{kind:?}: displacement error");
    assert!(
        free_res <= 1e-10 * react,
        "{kind:?}: free dofs not in equilibrium"
    );
    // reactions of the assembled system, K u − f_ε0, equal the internal
    // forces (this ties the load's sign to σ = D(ε − ε0) even when u = 0),
    // and the x reactions on the face x = L add up to σ_xx·A
    let mut r = vec![0.0; ndof];
    for (e, k) in ke.iter().enumerate() {
        let ku = k * SMatrix::<f64, 24, 1>::from_column_slice(&mesh.gather(e, &u));
        for (i, &dof) in element_dofs(&mesh.elems[e]).iter().enumerate() {
            r[dof as usize] += ku[i];
        }
    }
    let r_err = (0..ndof).fold(0.0f64, |m, k| m.max((r[k] - f[k] - fint[k]).abs()));
    assert!(r_err <= 1e-10 * react, "{kind:?}: K u − f ≠ f_int");
    let face_x: f64 = (0..mesh.nodes.len())
        .filter(|&a| (mesh.nodes[a][0] - size[0]).abs() < 1e-12)
        .map(|a| fint[3 * a])
        .sum();
    let area = size[1] * size[2];
    assert!(
        (face_x - sig[0] * area).abs() <= 1e-10 * (sig[0] * area).abs(),
        "{kind:?}: end reaction {face_x} vs σA = {}",
        sig[0] * area
    );
}

#[test]
fn restrained_bar_thermal_stress_is_minus_e_alpha_dt() {
    restrained_thermal(Restraint::Bar);
}

#[test]
fn restrained_plate_thermal_stress_is_minus_e_alpha_dt_over_1_minus_nu() {
    restrained_thermal(Restraint::Plate);
}

#[test]
fn restrained_solid_thermal_stress_is_minus_e_alpha_dt_over_1_minus_2nu() {
    restrained_thermal(Restraint::Solid);
}

// ------------------------------------------------------- d. element checks

#[test]
fn d_matrix_matches_lame_constants_and_compliance() {
    let (e_mod, nu) = (2.7e10, 0.18);
    let d = isotropic_d(e_mod, nu);
    let lambda = e_mod * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e_mod / (2.0 * (1.0 + nu));
    for i in 0..6 {
        for j in 0..6 {
            let want = match (i < 3, j < 3) {
                (true, true) if i == j => lambda + 2.0 * mu,
                (true, true) => lambda,
                (false, false) if i == j => mu,
                _ => 0.0,
            };
            assert!(
                (d[(i, j)] - want).abs() <= 1e-14 * e_mod,
                "D[{i}][{j}] = {} vs {want}",
                d[(i, j)]
            );
        }
    }
    let c = d.try_inverse().unwrap();
    assert!((c[(0, 0)] * e_mod - 1.0).abs() < 1e-13);
    assert!((c[(0, 1)] * e_mod + nu).abs() < 1e-13);
    assert!((c[(3, 3)] * e_mod - 2.0 * (1.0 + nu)).abs() < 1e-13);
    // bulk: D [1,1,1,0,0,0] = E/(1−2ν) [1,1,1,0,0,0]
    let hyd = d * SMatrix::<f64, 6, 1>::from_column_slice(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    assert!((hyd[0] - e_mod / (1.0 - 2.0 * nu)).abs() < 1e-14 * e_mod);
    let q: Mat6 = poisson_matrix(nu) * e_mod;
    assert!((q - d).amax() <= 1e-15 * e_mod);
    assert_eq!(
        thermal_strain(1e-5, 10.0),
        [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0]
    );
}

#[test]
fn gauss_points_follow_gauss2_hex_and_sum_to_the_volume() {
    let c = distorted_hex();
    let g = gauss_points(&c).unwrap();
    for (i, gp) in g.iter().enumerate() {
        assert_eq!(gp.xi, GAUSS2_HEX[i]);
        assert!(gp.weight > 0.0);
    }
    let v: f64 = g.iter().map(|gp| gp.weight).sum();
    assert!((v - hex8::volume(&c)).abs() <= 1e-14 * v);
    // inverted element (two nodes swapped) is rejected
    let mut bad = c;
    bad.swap(0, 1);
    assert!(matches!(
        gauss_points(&bad),
        Err(ElementError::NonPositiveJacobian { .. })
    ));
    assert!(stiffness_of(&bad, 1e9, 0.2).is_err());
    assert!(body_force(&bad, [0.0, 0.0, -1.0]).is_err());
    assert_eq!(element_dofs(&[0, 1, 2, 3, 4, 5, 6, 10])[21..], [30, 31, 32]);
}

#[test]
fn strain_of_a_linear_field_is_exact_at_every_gauss_point() {
    let c = distorted_hex();
    let g = gauss_points(&c).unwrap();
    let gr = [[0.3, -0.7, 1.1], [0.2, 0.5, -0.4], [-0.9, 0.6, 0.8]]; // ∂u_i/∂x_j
    let t = [0.1, -0.2, 0.3];
    let mut ue = [0.0; 24];
    for a in 0..8 {
        for i in 0..3 {
            ue[3 * a + i] = t[i] + (0..3).map(|j| gr[i][j] * c[a][j]).sum::<f64>();
        }
    }
    let want = [
        gr[0][0],
        gr[1][1],
        gr[2][2],
        gr[0][1] + gr[1][0],
        gr[1][2] + gr[2][1],
        gr[2][0] + gr[0][2],
    ];
    for gp in &g {
        let e = strain(gp, &ue);
        for r in 0..6 {
            assert!((e[r] - want[r]).abs() < 1e-14, "{e:?} vs {want:?}");
        }
    }
}

#[test]
fn rigid_body_modes_produce_no_force() {
    let c = distorted_hex();
    let k = stiffness_of(&c, 3e10, 0.2).unwrap();
    let kmax = k.amax();
    let x0 = [0.4, -0.3, 0.2];
    for mode in 0..6 {
        let mut u = SMatrix::<f64, 24, 1>::zeros();
        for a in 0..8 {
            let r = [0, 1, 2].map(|i| c[a][i] - x0[i]);
            let v = if mode < 3 {
                let mut t = [0.0; 3];
                t[mode] = 1.0;
                t
            } else {
                // ω × r with ω = e_{mode−3}
                let mut w = [0.0; 3];
                w[mode - 3] = 1.0;
                [
                    w[1] * r[2] - w[2] * r[1],
                    w[2] * r[0] - w[0] * r[2],
                    w[0] * r[1] - w[1] * r[0],
                ]
            };
            for i in 0..3 {
                u[3 * a + i] = v[i];
            }
        }
        let f = k * u;
        let rel = f.amax() / (kmax * u.amax());
        assert!(rel <= 1e-10, "mode {mode}: |K u| / (|K||u|) = {rel:e}");
    }
}

#[test]
fn stiffness_is_symmetric_psd_with_exactly_six_zero_eigenvalues() {
    for (c, nu) in [(distorted_hex(), 0.2), (distorted_hex(), 0.45)] {
        let k = stiffness_of(&c, 3e10, nu).unwrap();
        assert_eq!(k, k.transpose(), "K must be exactly symmetric");
        let mut ev: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
        ev.sort_by(|a, b| a.total_cmp(b));
        let top = ev[23];
        eprintln!(
            "ν = {nu}: eigenvalues / λ_max: 6th = {:.2e}, 7th = {:.3e}, min = {:.2e}",
            ev[5] / top,
            ev[6] / top,
            ev[0] / top
        );
        for (i, &l) in ev.iter().enumerate().take(6) {
            assert!(l.abs() <= 1e-12 * top, "eigenvalue {i} = {l:e} not zero");
        }
        assert!(ev[6] >= 1e-3 * top, "7th eigenvalue {:e} too small", ev[6]);
        // linear in D: K(Q)·E = K(D)
        let g = gauss_points(&c).unwrap();
        let kq = stiffness(&g, &poisson_matrix(nu)) * 3e10;
        assert!((kq - k).amax() <= 1e-13 * top);
    }
}

#[test]
fn initial_strain_load_and_internal_force_match_k_times_u() {
    let c = distorted_hex();
    let g = gauss_points(&c).unwrap();
    let d = isotropic_d(3e10, 0.2);
    let k = stiffness(&g, &d);
    // u = αΔT x gives B u = αΔT [1,1,1,0,0,0] everywhere: K u = f_ε0
    let eps0 = thermal_strain(1e-5, 15.0);
    let mut u = [0.0; 24];
    for a in 0..8 {
        for i in 0..3 {
            u[3 * a + i] = 1.5e-4 * c[a][i];
        }
    }
    let ku = k * SMatrix::<f64, 24, 1>::from_column_slice(&u);
    let f0 = initial_strain_load(&g, &d, &[eps0; 8]);
    for i in 0..24 {
        assert!((ku[i] - f0[i]).abs() <= 1e-12 * ku.amax(), "dof {i}");
    }
    // general u: Σ Bᵀ (D B u) w = K u; per-Gauss-point ε0 enters linearly
    let mut rng = Rng(42);
    let u: [f64; 24] = std::array::from_fn(|_| rng.range(-1e-3, 1e-3));
    let ku = k * SMatrix::<f64, 24, 1>::from_column_slice(&u);
    let s: [[f64; 6]; 8] = std::array::from_fn(|i| stress(&g[i], &d, &u, &[0.0; 6]));
    let fi = internal_force(&g, &s);
    for i in 0..24 {
        assert!((ku[i] - fi[i]).abs() <= 1e-12 * ku.amax(), "dof {i}");
    }
    let e0: [[f64; 6]; 8] =
        std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-1e-4, 1e-4)));
    let with0: [[f64; 6]; 8] = std::array::from_fn(|i| stress(&g[i], &d, &u, &e0[i]));
    let fi0 = internal_force(&g, &with0);
    let fl0 = initial_strain_load(&g, &d, &e0);
    for i in 0..24 {
        assert!(
            (fi0[i] - (ku[i] - fl0[i])).abs() <= 1e-12 * ku.amax(),
            "dof {i}: f_int ≠ K u − f_ε0"
        );
    }
}

/// The strains and the Bᵀ sums walk the gradients the Gauss points keep,
/// skipping B's structural zeros: they must give the dense products of B
/// to the bit, so the runs they serve keep every bit of their results.
#[test]
fn strains_and_bt_sums_from_gradients_equal_the_dense_b_products_to_the_bit() {
    let g = gauss_points(&distorted_hex()).unwrap();
    let mut rng = Rng(7);
    let u: [f64; 24] = std::array::from_fn(|_| rng.range(-1e-3, 1e-3));
    let s: [[f64; 6]; 8] = std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-5e6, 5e6)));
    let mut dense = [0.0; 24];
    for (gp, si) in g.iter().zip(&s) {
        let b = gp.b();
        // ε = B u, row by row in column order
        let mut e = [0.0; 6];
        for r in 0..6 {
            for k in 0..24 {
                e[r] += b[(r, k)] * u[k];
            }
        }
        assert_eq!(strain(gp, &u), e);
        // f += (Bᵀ σ) w, column by column in row order
        for k in 0..24 {
            let mut acc = 0.0;
            for r in 0..6 {
                acc += b[(r, k)] * si[r];
            }
            dense[k] += acc * gp.weight;
        }
    }
    assert_eq!(internal_force(&g, &s), dense);
}

#[test]
fn body_force_sums_to_rho_g_v() {
    let (rho, grav) = (2400.0, 9.81);
    // parallelepiped: ∫ N_a dV = V/8 for every node, V = det of the edges
    let e = [[2.0, 0.3, 0.1], [0.4, 1.5, -0.2], [0.3, 0.2, 1.2]];
    let o = [1.0, -2.0, 3.0];
    let c: [[f64; 3]; 8] = std::array::from_fn(|a| {
        let p = hex8::NODES[a].map(|v| 0.5 * (v + 1.0));
        [0, 1, 2].map(|i| o[i] + p[0] * e[0][i] + p[1] * e[1][i] + p[2] * e[2][i])
    });
    let v = Matrix3::from_fn(|i, j| e[j][i]).determinant();
    let f = body_force(&c, [0.0, 0.0, -rho * grav]).unwrap();
    for a in 0..8 {
        assert_eq!(f[3 * a], 0.0);
        assert_eq!(f[3 * a + 1], 0.0);
        assert!((f[3 * a + 2] + rho * grav * v / 8.0).abs() <= 1e-13 * rho * grav * v);
    }
    // distorted hex: the sum is b·V
    let c = distorted_hex();
    let v = hex8::volume(&c);
    let b = [1.0, -2.0, -rho * grav];
    let f = body_force(&c, b).unwrap();
    for i in 0..3 {
        let s: f64 = (0..8).map(|a| f[3 * a + i]).sum();
        assert!(
            (s - b[i] * v).abs() <= 1e-13 * rho * grav * v,
            "component {i}"
        );
    }
    let fg = body_force_at(&gauss_points(&c).unwrap(), b);
    for i in 0..24 {
        assert!((fg[i] - f[i]).abs() <= 1e-13 * rho * grav * v);
    }
}

#[test]
fn constant_pressure_on_a_tilted_quad_sums_to_p_area_minus_n() {
    // orthonormal frame (t1, t2, n = t1 × t2) tilted in all three axes
    let rot = nalgebra::Rotation3::from_euler_angles(0.4, -0.7, 1.1);
    let t1 = rot * nalgebra::Vector3::x();
    let t2 = rot * nalgebra::Vector3::y();
    let n = t1.cross(&t2);
    let o = nalgebra::Vector3::new(0.5, 1.0, -2.0);
    let q2 = [[0.0, 0.0], [2.0, 0.3], [1.7, 1.5], [-0.2, 1.1]]; // convex, CCW
    let face: [[f64; 3]; 4] = std::array::from_fn(|a| {
        let x = o + t1 * q2[a][0] + t2 * q2[a][1];
        [x[0], x[1], x[2]]
    });
    // shoelace area in the plane
    let area = 0.5
        * (0..4)
            .map(|a| {
                let b = (a + 1) % 4;
                q2[a][0] * q2[b][1] - q2[b][0] * q2[a][1]
            })
            .sum::<f64>();
    let p = 2.5e5;
    let f = face_pressure(&face, |_| p).unwrap();
    for i in 0..3 {
        let s: f64 = (0..4).map(|a| f[3 * a + i]).sum();
        assert!(
            (s + p * area * n[i]).abs() <= 1e-12 * p * area,
            "component {i}: {s} vs {}",
            -p * area * n[i]
        );
    }
    // on a hex face (FACES order) the load points into the element
    let cube: [[f64; 3]; 8] = std::array::from_fn(|a| hex8::NODES[a].map(|v| 0.5 * (v + 1.0)));
    let top = face_pressure(&hex8::face_coords(&cube, 1), |_| 1.0).unwrap();
    for a in 0..4 {
        assert!((top[3 * a + 2] + 0.25).abs() < 1e-15 && top[3 * a].abs() < 1e-15);
    }
    let degenerate = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
    assert!(matches!(
        face_pressure(&degenerate, |_| 1.0),
        Err(ElementError::DegenerateFace { .. })
    ));
}

#[test]
fn hydrostatic_pressure_on_a_vertical_face_is_exact() {
    let (rho_w, grav, level) = (1000.0, 9.81, 120.0);
    let p = |x: [f64; 3]| rho_w * grav * (level - x[2]);
    // vertical trapezoid in the plane y = 0, symmetric about x = xc, seen
    // from y < 0 counter-clockwise: outward normal −y (an upstream face)
    let (xc, z0, z1, wb, wt) = (5.0, 40.0, 52.0, 8.0, 5.0);
    let face = [
        [xc - wb / 2.0, 0.0, z0],
        [xc + wb / 2.0, 0.0, z0],
        [xc + wt / 2.0, 0.0, z1],
        [xc - wt / 2.0, 0.0, z1],
    ];
    let f = face_pressure(&face, p).unwrap();
    // width w(z) = a + b z; ∫ (H − z) w dz and ∫ z (H − z) w dz in closed form
    let h = z1 - z0;
    let bw = (wt - wb) / h;
    let aw = wb - bw * z0;
    let f0 = |z: f64| level * aw * z + (level * bw - aw) * z * z / 2.0 - bw * z.powi(3) / 3.0;
    let f1 = |z: f64| {
        level * aw * z * z / 2.0 + (level * bw - aw) * z.powi(3) / 3.0 - bw * z.powi(4) / 4.0
    };
    let force = rho_w * grav * (f0(z1) - f0(z0)); // ρ g ∫ depth dA
    let zmom = rho_w * grav * (f1(z1) - f1(z0)); // ρ g ∫ z·depth dA
    let fx: f64 = (0..4).map(|a| f[3 * a]).sum();
    let fy: f64 = (0..4).map(|a| f[3 * a + 1]).sum();
    let fz: f64 = (0..4).map(|a| f[3 * a + 2]).sum();
    eprintln!("hydrostatic trapezoid: F_y = {fy:.6e} N, exact {force:.6e} N");
    assert!((fy - force).abs() <= 1e-13 * force, "{fy} vs {force}");
    assert!(fx.abs() <= 1e-13 * force && fz.abs() <= 1e-13 * force);
    // moments of the nodal forces = moments of the pressure: Σ x_a f_a,y
    let mx: f64 = (0..4).map(|a| face[a][2] * f[3 * a + 1]).sum();
    let mz: f64 = (0..4).map(|a| face[a][0] * f[3 * a + 1]).sum();
    assert!((mx - zmom).abs() <= 1e-13 * zmom, "{mx} vs {zmom}");
    assert!((mz - xc * force).abs() <= 1e-13 * xc * force);

    // rectangle: the consistent nodal loads are known in closed form
    let (w, x0) = (6.0, 0.0);
    let rect = [
        [x0, 0.0, z0],
        [x0 + w, 0.0, z0],
        [x0 + w, 0.0, z1],
        [x0, 0.0, z1],
    ];
    let f = face_pressure(&rect, p).unwrap();
    let (pb, pt) = (p([0.0, 0.0, z0]), p([0.0, 0.0, z1]));
    let bottom = w / 2.0 * h * (2.0 * pb + pt) / 6.0;
    let topv = w / 2.0 * h * (pb + 2.0 * pt) / 6.0;
    for (a, want) in [bottom, bottom, topv, topv].into_iter().enumerate() {
        assert!(
            (f[3 * a + 1] - want).abs() <= 1e-13 * want,
            "node {a}: {} vs {want}",
            f[3 * a + 1]
        );
    }
}

#[test]
fn von_mises_and_principal_stresses() {
    assert!((von_mises(&[5e6, 0.0, 0.0, 0.0, 0.0, 0.0]) - 5e6).abs() < 1e-8);
    assert!((von_mises(&[0.0, 0.0, 0.0, 2e6, 0.0, 0.0]) - 3f64.sqrt() * 2e6).abs() < 1e-8);
    assert!(von_mises(&[-3e6, -3e6, -3e6, 0.0, 0.0, 0.0]).abs() < 1e-8);
    // a rotated diagonal tensor keeps its principal values and von Mises
    let r = nalgebra::Rotation3::from_euler_angles(0.3, 0.8, -0.5).into_inner();
    let m = r * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, -2.0, 3.0)) * r.transpose();
    let s = [
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        m[(0, 1)],
        m[(1, 2)],
        m[(2, 0)],
    ];
    let pr = principal_stresses(&s);
    for (got, want) in pr.iter().zip([3.0, 1.0, -2.0]) {
        assert!((got - want).abs() < 1e-13, "{pr:?}");
    }
    let vm_diag = von_mises(&[1.0, -2.0, 3.0, 0.0, 0.0, 0.0]);
    assert!((von_mises(&s) - vm_diag).abs() < 1e-13);
}
