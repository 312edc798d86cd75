//! Element-level checks of `groutready::fem`: quadrature, hex8, quad4 and the
//! thermal kernels, against closed forms, to tight tolerances.

#![allow(clippy::needless_range_loop)]

use crate::common;

use common::Rng;

use groutready::fem::{
    capacity_consistent, capacity_lumped, conductivity, element_volume_and_centroid,
    face_convection, face_convection_lumped, gauss_hex, gauss_legendre, gauss_quad, hex8, quad4,
    volume_load, ElementError,
};
use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};

fn box_hex(lx: f64, ly: f64, lz: f64, origin: [f64; 3]) -> [[f64; 3]; 8] {
    let mut c = [[0.0; 3]; 8];
    for a in 0..8 {
        let p = hex8::NODES[a];
        c[a] = [
            origin[0] + 0.5 * (p[0] + 1.0) * lx,
            origin[1] + 0.5 * (p[1] + 1.0) * ly,
            origin[2] + 0.5 * (p[2] + 1.0) * lz,
        ];
    }
    c
}

/// Unit-ish cube with every node moved randomly by up to `amp`.
fn distorted_hex(rng: &mut Rng, amp: f64) -> [[f64; 3]; 8] {
    let mut c = box_hex(2.0, 1.5, 1.0, [1.0, -2.0, 3.0]);
    for node in c.iter_mut() {
        for x in node.iter_mut() {
            *x += rng.range(-amp, amp);
        }
    }
    hex8::check(&c).expect("test hex must be valid");
    c
}

/// x = A ξ + b: a parallelepiped (planar faces).
fn affine_hex(a: Matrix3<f64>, b: Vector3<f64>) -> [[f64; 3]; 8] {
    let mut c = [[0.0; 3]; 8];
    for k in 0..8 {
        let x = a * Vector3::from(hex8::NODES[k]) + b;
        c[k] = [x[0], x[1], x[2]];
    }
    c
}

fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-300)
}

// ---------------------------------------------------------------- quadrature

#[test]
fn gauss_legendre_matches_closed_forms() {
    let s = f64::sqrt;
    let expected: Vec<Vec<(f64, f64)>> = vec![
        vec![(0.0, 2.0)],
        vec![(-1.0 / s(3.0), 1.0), (1.0 / s(3.0), 1.0)],
        vec![(-s(0.6), 5.0 / 9.0), (0.0, 8.0 / 9.0), (s(0.6), 5.0 / 9.0)],
        {
            let a = s(3.0 / 7.0 - 2.0 / 7.0 * s(1.2));
            let b = s(3.0 / 7.0 + 2.0 / 7.0 * s(1.2));
            let wa = (18.0 + s(30.0)) / 36.0;
            let wb = (18.0 - s(30.0)) / 36.0;
            vec![(-b, wb), (-a, wa), (a, wa), (b, wb)]
        },
        {
            let a = s(5.0 - 2.0 * s(10.0 / 7.0)) / 3.0;
            let b = s(5.0 + 2.0 * s(10.0 / 7.0)) / 3.0;
            let wa = (322.0 + 13.0 * s(70.0)) / 900.0;
            let wb = (322.0 - 13.0 * s(70.0)) / 900.0;
            vec![(-b, wb), (-a, wa), (0.0, 128.0 / 225.0), (a, wa), (b, wb)]
        },
    ];
    for (n, exp) in (1..=5).zip(expected) {
        let r = gauss_legendre(n);
        assert_eq!(r.len(), n);
        for (q, (x, w)) in exp.iter().enumerate() {
            assert!(
                (r.points[q][0] - x).abs() < 1e-15,
                "n={n} q={q}: {:?} vs {x}",
                r.points[q]
            );
            assert!(
                (r.weights[q] - w).abs() < 1e-15,
                "n={n} q={q}: {} vs {w}",
                r.weights[q]
            );
        }
    }
}

#[test]
fn gauss_rules_are_exact_to_degree_2n_minus_1() {
    let exact = |k: i32| {
        if k % 2 == 1 {
            0.0
        } else {
            2.0 / (k as f64 + 1.0)
        }
    };
    for n in 1..=8 {
        let r = gauss_legendre(n);
        for k in 0..(2 * n as i32) {
            let v = r.integrate(|x| x[0].powi(k));
            assert!((v - exact(k)).abs() < 1e-14, "n={n} k={k}: {v}");
        }
        // and not exact one degree higher (even power)
        let k = 2 * n as i32;
        assert!((r.integrate(|x| x[0].powi(k)) - exact(k)).abs() > 1e-6);
    }
    for n in 1..=4 {
        let h = gauss_hex(n);
        let q = gauss_quad(n);
        assert_eq!(h.len(), n * n * n);
        assert_eq!(q.len(), n * n);
        let d = 2 * n as i32 - 1;
        for (a, b, c) in [
            (d, 0, 0),
            (0, d, 0),
            (0, 0, d),
            (d - 1, d - 1, d - 1),
            (d - 1, 1, d - 1),
        ] {
            let v = h.integrate(|x| x[0].powi(a) * x[1].powi(b) * x[2].powi(c));
            assert!(
                (v - exact(a) * exact(b) * exact(c)).abs() < 1e-14,
                "hex n={n} ({a},{b},{c})"
            );
            let v = q.integrate(|x| x[0].powi(a) * x[1].powi(c));
            assert!(
                (v - exact(a) * exact(c)).abs() < 1e-14,
                "quad n={n} ({a},{c})"
            );
        }
    }
}

// ---------------------------------------------------------------- hex8

#[test]
fn hex8_partition_of_unity_and_kronecker() {
    let mut rng = Rng(7);
    for _ in 0..200 {
        let xi = rng.point();
        let n = hex8::shape(xi);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let g = hex8::shape_grad_ref(xi);
        for j in 0..3 {
            assert!(g.iter().map(|ga| ga[j]).sum::<f64>().abs() < 1e-15);
        }
    }
    for a in 0..8 {
        let n = hex8::shape(hex8::NODES[a]);
        for b in 0..8 {
            assert_eq!(n[b], if a == b { 1.0 } else { 0.0 });
        }
    }
}

/// The table of N at the 2×2×2 rule's points is `shape` there, to the
/// bit; each point's row sums to one and weighs its nearest node
/// ((1 + 1/√3)/(1 − 1/√3))³ = (2 + √3)³ times the opposite one.
#[test]
fn hex8_shape_table_at_the_gauss_points_is_shape_there() {
    let table = hex8::shape_at_gauss2();
    let ratio = (2.0 + 3f64.sqrt()).powi(3);
    for (g, xi) in groutready::fem::quadrature::GAUSS2_HEX.iter().enumerate() {
        assert_eq!(table[g], hex8::shape(*xi), "point {g}");
        assert!((table[g].iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let near = table[g].iter().cloned().fold(f64::MIN, f64::max);
        let far = table[g].iter().cloned().fold(f64::MAX, f64::min);
        assert!((near / far - ratio).abs() < 1e-12 * ratio, "point {g}");
    }
}

#[test]
fn hex8_faces_match_the_contract() {
    assert_eq!(
        hex8::FACES,
        [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7]
        ]
    );
    // each face's nodes share the coordinate of its plane, normal points outward
    let planes = [
        (2, -1.0),
        (2, 1.0),
        (1, -1.0),
        (0, 1.0),
        (1, 1.0),
        (0, -1.0),
    ];
    let c = box_hex(2.0, 2.0, 2.0, [-1.0, -1.0, -1.0]); // = reference cube
    for (f, &(axis, side)) in planes.iter().enumerate() {
        for &a in &hex8::FACES[f] {
            assert_eq!(hex8::NODES[a][axis], side);
        }
        let fc = hex8::face_coords(&c, f);
        let nrm = quad4::normal(&fc, [0.3, -0.2]).unwrap();
        for i in 0..3 {
            let e = if i == axis { side } else { 0.0 };
            assert!((nrm[i] - e).abs() < 1e-15, "face {f}: normal {nrm:?}");
        }
        assert!((quad4::area(&fc) - 4.0).abs() < 1e-14);
    }
}

#[test]
fn hex8_reference_gradients_match_central_differences() {
    let mut rng = Rng(11);
    let h = 1e-5;
    for _ in 0..50 {
        let xi = rng.point();
        let g = hex8::shape_grad_ref(xi);
        for j in 0..3 {
            let (mut xp, mut xm) = (xi, xi);
            xp[j] += h;
            xm[j] -= h;
            let (np, nm) = (hex8::shape(xp), hex8::shape(xm));
            for a in 0..8 {
                let fd = (np[a] - nm[a]) / (2.0 * h);
                assert!(
                    (fd - g[a][j]).abs() < 1e-7,
                    "a={a} j={j}: {fd} vs {}",
                    g[a][j]
                );
            }
        }
    }
}

#[test]
fn hex8_physical_gradients_match_central_differences() {
    let mut rng = Rng(13);
    let h = 1e-5;
    for _ in 0..20 {
        let c = distorted_hex(&mut rng, 0.25);
        let xi = [
            rng.range(-0.8, 0.8),
            rng.range(-0.8, 0.8),
            rng.range(-0.8, 0.8),
        ];
        let (g, det) = hex8::shape_grad(&c, xi).unwrap();
        assert!((det - hex8::jacobian(&c, xi).1).abs() < 1e-15 * det.abs().max(1.0));
        // ∇ₓN reproduces linear fields: Σ_a x_a ⊗ ∇N_a = I, Σ_a ∇N_a = 0
        for i in 0..3 {
            for j in 0..3 {
                let s: f64 = (0..8).map(|a| c[a][i] * g[a][j]).sum();
                assert!((s - if i == j { 1.0 } else { 0.0 }).abs() < 1e-13);
            }
            assert!((0..8).map(|a| g[a][i]).sum::<f64>().abs() < 1e-13);
        }
        // N_a(ξ(x)) differentiated in physical space through the inverse map
        let x = hex8::point(&c, xi);
        assert_eq!(
            hex8::locate(&c, x).map(|p| p.iter().zip(&xi).all(|(a, b)| (a - b).abs() < 1e-12)),
            Some(true)
        );
        for j in 0..3 {
            let (mut xp, mut xm) = (x, x);
            xp[j] += h;
            xm[j] -= h;
            let np = hex8::shape(hex8::locate(&c, xp).unwrap());
            let nm = hex8::shape(hex8::locate(&c, xm).unwrap());
            for a in 0..8 {
                let fd = (np[a] - nm[a]) / (2.0 * h);
                assert!(
                    (fd - g[a][j]).abs() < 1e-7,
                    "a={a} j={j}: {fd} vs {}",
                    g[a][j]
                );
            }
        }
    }
}

#[test]
fn hex8_volume_is_exact_for_parallelepipeds_and_frustums() {
    let a = Matrix3::new(1.3, 0.4, -0.2, 0.1, 0.9, 0.3, -0.25, 0.2, 1.7);
    let c = affine_hex(a, Vector3::new(10.0, -3.0, 250.0));
    let exact = 8.0 * a.determinant();
    assert!(
        rel_close(hex8::volume(&c), exact, 1e-14),
        "{} vs {exact}",
        hex8::volume(&c)
    );
    let (v, centroid) = element_volume_and_centroid(&c);
    assert!(rel_close(v, exact, 1e-14));
    for (x, e) in centroid.iter().zip([10.0, -3.0, 250.0]) {
        assert!((x - e).abs() < 1e-12);
    }
    // square frustum: bottom side p at z = 0, top side q at z = h (planar faces)
    let (p, q, hh) = (3.0, 1.2, 2.5);
    let mut f = [[0.0; 3]; 8];
    for k in 0..8 {
        let r = hex8::NODES[k];
        let side = if r[2] < 0.0 { p } else { q };
        f[k] = [
            0.5 * side * r[0],
            0.5 * side * r[1],
            if r[2] < 0.0 { 0.0 } else { hh },
        ];
    }
    let exact = hh / 3.0 * (p * p + p * q + q * q);
    assert!(rel_close(hex8::volume(&f), exact, 1e-14));
    let (v, centroid) = element_volume_and_centroid(&f);
    assert!(rel_close(v, exact, 1e-14));
    let zc = hh * (p * p + 2.0 * p * q + 3.0 * q * q) / (4.0 * (p * p + p * q + q * q));
    assert!(
        (centroid[2] - zc).abs() < 1e-13 && centroid[0].abs() < 1e-14 && centroid[1].abs() < 1e-14
    );
}

#[test]
fn hex8_volume_of_a_distorted_hex_matches_a_fine_rule() {
    let mut rng = Rng(17);
    let c = distorted_hex(&mut rng, 0.3);
    let fine = gauss_hex(6).integrate(|x| hex8::jacobian(&c, x).1);
    assert!(rel_close(hex8::volume(&c), fine, 1e-14));
}

#[test]
fn hex8_inverted_element_is_rejected() {
    let good = box_hex(1.0, 1.0, 1.0, [0.0; 3]);
    // mirror: swap bottom and top faces → det J < 0 everywhere
    let mut bad = good;
    for a in 0..4 {
        bad.swap(a, a + 4);
    }
    assert!(hex8::volume(&bad) < 0.0);
    match hex8::shape_grad(&bad, [0.0; 3]) {
        Err(ElementError::NonPositiveJacobian { det, point }) => {
            assert!((det + 0.125).abs() < 1e-15);
            assert_eq!(point, [0.0; 3]);
        }
        other => panic!("expected NonPositiveJacobian, got {other:?}"),
    }
    assert!(matches!(
        hex8::check(&bad),
        Err(ElementError::NonPositiveJacobian { .. })
    ));
    assert!(conductivity(&bad, 1.0).is_err());
    assert!(capacity_consistent(&bad, 1.0).is_err());
    assert!(capacity_lumped(&bad, 1.0).is_err());
    // a bow-tie: one node pushed through the opposite face → det < 0 at a corner only
    let mut warped = good;
    warped[6] = [0.2, 0.2, -0.5];
    assert!(matches!(
        hex8::check(&warped),
        Err(ElementError::NonPositiveJacobian { .. })
    ));
    // collapsed element: det = 0
    let mut flat = good;
    for a in 4..8 {
        flat[a][2] = 0.0;
    }
    assert!(hex8::check(&flat).is_err());
    assert!(hex8::check(&good).is_ok());
}

// ---------------------------------------------------------------- kernels

#[test]
fn conductivity_annihilates_constants_is_symmetric_psd_rank_7() {
    let mut rng = Rng(23);
    for _ in 0..20 {
        let c = distorted_hex(&mut rng, 0.3);
        let lambda = 2.3 * 86400.0;
        let k = conductivity(&c, lambda).unwrap();
        let kmax = k.amax();
        let ones = SMatrix::<f64, 8, 1>::repeat(1.0);
        assert!((k * ones).amax() <= 1e-12 * kmax);
        assert!((k - k.transpose()).amax() == 0.0);
        let eig = k.symmetric_eigen().eigenvalues;
        let mut e: Vec<f64> = eig.iter().copied().collect();
        e.sort_by(f64::total_cmp);
        assert!(e[0].abs() <= 1e-12 * kmax, "{e:?}");
        assert!(e[1] > 1e-3 * kmax, "rank deficient: {e:?}");
    }
}

#[test]
fn conductivity_of_a_box_matches_closed_form_energy() {
    // linear field T = g·x: energy Tᵀ K T = λ |g|² V exactly
    let c = box_hex(2.0, 3.0, 0.5, [1.0, 1.0, 1.0]);
    let k = conductivity(&c, 1.7).unwrap();
    let g = [0.3, -1.1, 2.0];
    let t = SMatrix::<f64, 8, 1>::from_fn(|a, _| (0..3).map(|i| g[i] * c[a][i]).sum());
    let e = (t.transpose() * k * t)[(0, 0)];
    let exact = 1.7 * (0.09 + 1.21 + 4.0) * 3.0;
    assert!(rel_close(e, exact, 1e-13), "{e} vs {exact}");
}

/// 3×3×3-node patch of 2×2×2 distorted hexes (one interior node).
fn patch_mesh(rng: &mut Rng) -> (Vec<[f64; 3]>, Vec<[usize; 8]>) {
    let id = |i: usize, j: usize, k: usize| i + 3 * j + 9 * k;
    let mut nodes = vec![[0.0; 3]; 27];
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                let mut x = [i as f64, 1.2 * j as f64, 0.8 * k as f64];
                for v in x.iter_mut() {
                    *v += rng.range(-0.2, 0.2);
                }
                nodes[id(i, j, k)] = x;
            }
        }
    }
    let mut elems = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
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
    (nodes, elems)
}

#[test]
fn patch_test_linear_field_has_zero_interior_residual() {
    let mut rng = Rng(29);
    for _ in 0..10 {
        let (nodes, elems) = patch_mesh(&mut rng);
        let mut k = DMatrix::zeros(27, 27);
        for e in &elems {
            let c = e.map(|n| nodes[n]);
            let ke = conductivity(&c, 3.0).unwrap();
            for a in 0..8 {
                for b in 0..8 {
                    k[(e[a], e[b])] += ke[(a, b)];
                }
            }
        }
        let t = nalgebra::DVector::from_fn(27, |n, _| {
            5.0 + 0.7 * nodes[n][0] - 1.3 * nodes[n][1] + 0.4 * nodes[n][2]
        });
        let r = &k * &t;
        let scale = k.amax() * t.amax();
        assert!(r[13].abs() <= 1e-13 * scale, "interior residual {}", r[13]);
        // total flux balance: Σ r = 0 (K annihilates constants)
        assert!(r.sum().abs() <= 1e-12 * scale);
    }
}

#[test]
fn capacity_lumped_sums_to_rho_c_volume_and_matches_consistent() {
    let mut rng = Rng(31);
    for _ in 0..20 {
        let c = distorted_hex(&mut rng, 0.3);
        let rho_c = 2400.0 * 950.0;
        let v = hex8::volume(&c);
        let lumped = capacity_lumped(&c, rho_c).unwrap();
        assert!(lumped.iter().all(|&m| m > 0.0));
        assert!(rel_close(lumped.iter().sum::<f64>(), rho_c * v, 1e-14));
        let cons = capacity_consistent(&c, rho_c).unwrap();
        assert!((cons - cons.transpose()).amax() == 0.0);
        for a in 0..8 {
            assert!(rel_close(cons.row(a).sum(), lumped[a], 1e-13));
        }
        assert!(rel_close(cons.sum(), rho_c * v, 1e-14));
        // 3×3×3 is exact on a trilinear hex: compare with a 5×5×5 rule
        let r5 = gauss_hex(5);
        for a in 0..8 {
            for b in 0..8 {
                let exact = rho_c
                    * r5.integrate(|x| {
                        let n = hex8::shape(x);
                        n[a] * n[b] * hex8::jacobian(&c, x).1
                    });
                assert!(rel_close(cons[(a, b)], exact, 1e-13));
            }
        }
        let q = volume_load(&c, 3.5).unwrap();
        assert!(rel_close(q.iter().sum::<f64>(), 3.5 * v, 1e-14));
    }
}

#[test]
fn capacity_of_a_box_matches_closed_form() {
    let (lx, ly, lz) = (2.0, 0.5, 3.0);
    let c = box_hex(lx, ly, lz, [0.0; 3]);
    let cons = capacity_consistent(&c, 2.0).unwrap();
    for a in 0..8 {
        for b in 0..8 {
            let f: f64 = (0..3)
                .map(|i| {
                    if hex8::NODES[a][i] == hex8::NODES[b][i] {
                        2.0
                    } else {
                        1.0
                    }
                })
                .product();
            let exact = 2.0 * lx * ly * lz / 216.0 * f;
            assert!(rel_close(cons[(a, b)], exact, 1e-14));
        }
    }
    let lumped = capacity_lumped(&c, 2.0).unwrap();
    for m in lumped {
        assert!(rel_close(m, 2.0 * lx * ly * lz / 8.0, 1e-14));
    }
}

#[test]
fn quad4_shape_area_and_normal() {
    let mut rng = Rng(37);
    for _ in 0..100 {
        let st = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let n = quad4::shape(st);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let g = quad4::shape_grad_ref(st);
        let h = 1e-5;
        for j in 0..2 {
            let (mut p, mut m) = (st, st);
            p[j] += h;
            m[j] -= h;
            let (np, nm) = (quad4::shape(p), quad4::shape(m));
            for a in 0..4 {
                assert!(((np[a] - nm[a]) / (2.0 * h) - g[a][j]).abs() < 1e-7);
            }
        }
    }
    for a in 0..4 {
        let n = quad4::shape(quad4::NODES[a]);
        for b in 0..4 {
            assert_eq!(n[b], if a == b { 1.0 } else { 0.0 });
        }
    }
    // planar trapezoid in a tilted plane: area exact, normal constant
    let (u, v) = (
        Vector3::new(1.0, 2.0, 2.0) / 3.0,
        Vector3::new(2.0, -2.0, 1.0) / 3.0,
    );
    let o = Vector3::new(5.0, 5.0, 100.0);
    let p2 = |s: f64, t: f64| {
        let x = o + u * s + v * t;
        [x[0], x[1], x[2]]
    };
    let face = [p2(0.0, 0.0), p2(4.0, 0.0), p2(3.0, 2.0), p2(1.0, 2.0)];
    assert!(rel_close(
        quad4::area(&face),
        0.5 * (4.0 + 2.0) * 2.0,
        1e-14
    ));
    let w = u.cross(&v);
    for st in [[-0.9, 0.3], [0.5, 0.5], [0.0, -1.0]] {
        let n = quad4::normal(&face, st).unwrap();
        for i in 0..3 {
            assert!((n[i] - w[i]).abs() < 1e-14);
        }
    }
    let degenerate = [p2(0.0, 0.0), p2(1.0, 0.0), p2(2.0, 0.0), p2(3.0, 0.0)];
    assert!(matches!(
        quad4::normal(&degenerate, [0.0, 0.0]),
        Err(ElementError::DegenerateFace { .. })
    ));
    assert!(face_convection(&degenerate, 1.0).is_err());
}

#[test]
fn face_convection_sums_to_beta_area() {
    let mut rng = Rng(41);
    for _ in 0..20 {
        let c = distorted_hex(&mut rng, 0.3);
        for f in 0..6 {
            let fc = hex8::face_coords(&c, f);
            let beta = 15.0 * 86400.0;
            let area = quad4::area(&fc);
            let (h, load) = face_convection(&fc, beta).unwrap();
            assert!((h - h.transpose()).amax() == 0.0);
            assert!(rel_close(h.sum(), beta * area, 1e-14));
            assert!(rel_close(load.iter().sum::<f64>(), beta * area, 1e-14));
            for a in 0..4 {
                assert!(rel_close(h.row(a).sum(), load[a], 1e-13));
            }
            let lumped = face_convection_lumped(&fc, beta).unwrap();
            assert_eq!(lumped, load);
        }
    }
    // flat rectangle: closed form β A/36 [4 2 1 2; …]
    let fc = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
    ];
    let (h, _) = face_convection(&fc, 1.5).unwrap();
    for a in 0..4 {
        for b in 0..4 {
            let f = match (a as i32 - b as i32).rem_euclid(4) {
                0 => 4.0,
                2 => 1.0,
                _ => 2.0,
            };
            assert!(rel_close(h[(a, b)], 1.5 * 6.0 / 36.0 * f, 1e-14));
        }
    }
}
