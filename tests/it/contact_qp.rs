//! Acceptance tests of the `qp` contact solver (joint::qp): closed forms for
//! the condensed frictional contact problem min ½ rᵀWr + bᵀr with Signorini
//! normals and Coulomb friction (see src/joint/mod.rs for the conventions).

#![allow(clippy::needless_range_loop, clippy::type_complexity)]

use std::time::Instant;

use groutready::joint::{
    kkt_residual, solve, solve_normal, ContactError, ContactProblem, ContactSettings,
    ContactSolution, ContactState, FrictionModel, LocalFrame, NormalProblem,
};
use nalgebra::{DMatrix, DVector};

// ---------------------------------------------------------------- helpers

/// SplitMix64: a seeded generator, so every random problem is reproducible.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
}

/// W = C K⁻¹ Cᵀ and b = g0 + C K⁻¹ f for a small stiffness model.
fn condense(
    k: &DMatrix<f64>,
    c: &DMatrix<f64>,
    f: &DVector<f64>,
    g0: &DVector<f64>,
) -> (DMatrix<f64>, Vec<f64>) {
    let chol = k.clone().cholesky().expect("test stiffness must be SPD");
    let kinv_ct = chol.solve(&c.transpose());
    let w = c * kinv_ct;
    let w = (&w + w.transpose()) * 0.5;
    let b = g0 + c * chol.solve(f);
    (w, b.iter().copied().collect())
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

fn tangential(v: &[f64], i: usize) -> f64 {
    v[3 * i].hypot(v[3 * i + 1])
}

fn solve_default(w: &DMatrix<f64>, b: &[f64], friction: &[FrictionModel]) -> ContactSolution {
    let problem = ContactProblem::new(w, b, friction);
    match solve(&problem, &ContactSettings::default(), None) {
        Ok(s) => s,
        Err(e) => panic!("contact solve failed: {e}"),
    }
}

// ------------------------------------------------------- 1. single point

#[test]
fn single_point_frictionless_open_and_closed() {
    let (kt, kn) = (1.0e9, 2.0e9);
    let w = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0 / kt, 1.0 / kt, 1.0 / kn]));
    let fr = [FrictionModel::Frictionless];

    // Open: the gap stays, no force.
    let b = [2.0e-5, -1.0e-5, 1.0e-3];
    let s = solve_default(&w, &b, &fr);
    assert_eq!(s.states, vec![ContactState::Open]);
    assert_eq!(s.r, vec![0.0; 3], "an open point carries no force");
    for k in 0..3 {
        assert!((s.u[k] - b[k]).abs() <= 1e-15, "u = b when open");
    }

    // Closed: would penetrate by δ, so r_n = k δ and the gap is exactly 0.
    let delta = 2.0e-4;
    let b = [3.0e-5, 0.0, -delta];
    let s = solve_default(&w, &b, &fr);
    assert_eq!(
        s.states,
        vec![ContactState::Slip],
        "frictionless closed = sliding freely"
    );
    assert!(
        rel(s.r[2], kn * delta) <= 1e-9,
        "r_n = {} vs {}",
        s.r[2],
        kn * delta
    );
    assert!(s.u[2].abs() <= 1e-9 * delta, "gap {} must close", s.u[2]);
    assert_eq!(
        (s.r[0], s.r[1]),
        (0.0, 0.0),
        "no tangential force without friction"
    );
    assert!((s.u[0] - 3.0e-5).abs() <= 1e-15, "free slip");
    assert!(s.kkt_residual <= 1e-9, "kkt {}", s.kkt_residual);

    // The normal-only path gives the same force.
    let wn = DMatrix::from_element(1, 1, 1.0 / kn);
    let ns = solve_normal(
        &NormalProblem::new(&wn, &[-delta]),
        &ContactSettings::default(),
    )
    .unwrap();
    assert!(rel(ns.r[0], kn * delta) <= 1e-9);
    assert_eq!(ns.closed(), vec![true]);
    let ns = solve_normal(
        &NormalProblem::new(&wn, &[delta]),
        &ContactSettings::default(),
    )
    .unwrap();
    assert_eq!((ns.r[0], ns.closed()[0]), (0.0, false));

    // Tied: u_t = 0 whatever the tangential push; the normal is still unilateral.
    let b = [1.0e-4, -2.0e-4, -delta];
    let s = solve_default(&w, &b, &[FrictionModel::Tied]);
    assert_eq!(s.states, vec![ContactState::Stick]);
    assert!(rel(s.r[0], -kt * 1.0e-4) <= 1e-9 && rel(s.r[1], kt * 2.0e-4) <= 1e-9);
    assert!(tangential(&s.u, 0) <= 1e-9 * 2.0e-4);
    let b = [1.0e-4, -2.0e-4, delta];
    let s = solve_default(&w, &b, &[FrictionModel::Tied]);
    assert_eq!(s.states, vec![ContactState::Open]);
    assert_eq!(s.r[2], 0.0);
    assert!(
        tangential(&s.u, 0) <= 1e-9 * 2.0e-4,
        "tied stays tied when the normal opens"
    );
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let w = DMatrix::<f64>::identity(3, 3);
    let set = ContactSettings::default();
    let fr = [FrictionModel::coulomb(0.5)];
    let short = [0.0, -1.0];
    let e = solve(&ContactProblem::new(&w, &short, &fr), &set, None).unwrap_err();
    assert!(
        matches!(
            e,
            ContactError::Dimension {
                what: "b",
                expected: 3,
                found: 2
            }
        ),
        "{e}"
    );
    let nan = [0.0, f64::NAN, -1.0];
    assert!(matches!(
        solve(&ContactProblem::new(&w, &nan, &fr), &set, None),
        Err(ContactError::Invalid(_))
    ));
    let b = [0.0, 0.0, -1.0];
    let bad_mu = [FrictionModel::Coulomb {
        mu_s: 0.3,
        mu_k: 0.4,
    }];
    let e = solve(&ContactProblem::new(&w, &b, &bad_mu), &set, None).unwrap_err();
    assert!(e.to_string().contains("mu_k"), "{e}");
    let mut asym = w.clone();
    asym[(0, 2)] = 0.5;
    assert!(matches!(
        solve(&ContactProblem::new(&asym, &b, &fr), &set, None),
        Err(ContactError::Invalid(_))
    ));
    let e = solve(&ContactProblem::new(&w, &b, &fr), &set, Some(&[1.0])).unwrap_err();
    assert!(
        matches!(
            e,
            ContactError::Dimension {
                what: "warm start",
                ..
            }
        ),
        "{e}"
    );
    let bad = ContactSettings {
        relaxation: 0.0,
        ..ContactSettings::default()
    };
    let e = solve(&ContactProblem::new(&w, &b, &fr), &bad, None).unwrap_err();
    assert!(e.to_string().contains("relaxation"), "{e}");
    // A tied point with no tangential compliance pushed tangentially: the
    // program is unbounded; clarabel's status must come back as an error.
    let mut w0 = DMatrix::<f64>::identity(3, 3);
    w0[(0, 0)] = 0.0;
    w0[(1, 1)] = 0.0;
    let e = solve(
        &ContactProblem::new(&w0, &[1.0, 0.0, -1.0], &[FrictionModel::Tied]),
        &set,
        None,
    )
    .unwrap_err();
    assert!(matches!(e, ContactError::Solver { .. }), "{e}");
    assert!(e.to_string().contains("Infeasible"), "{e}");
    // Frame of a zero normal.
    assert!(LocalFrame::from_normal([0.0, 0.0, 0.0]).is_err());
}

#[test]
fn local_frames_are_right_handed_and_orthonormal() {
    let f = LocalFrame::from_normal([2.0, 0.0, 0.0]).unwrap();
    assert_eq!(f.t1, [0.0, 1.0, 0.0]);
    assert_eq!(f.t2, [0.0, 0.0, 1.0]);
    let mut rng = Rng(7);
    for k in 0..200 {
        let n = if k < 6 {
            let mut v = [0.0; 3];
            v[k / 2] = if k % 2 == 0 { 1.0 } else { -1.0 };
            v
        } else {
            [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ]
        };
        let f = LocalFrame::from_normal(n).unwrap();
        let d = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for (a, b, e) in [
            (f.t1, f.t1, 1.0),
            (f.t2, f.t2, 1.0),
            (f.n, f.n, 1.0),
            (f.t1, f.t2, 0.0),
            (f.t1, f.n, 0.0),
            (f.t2, f.n, 0.0),
        ] {
            assert!((d(a, b) - e).abs() < 1e-14);
        }
        let c = [
            f.t1[1] * f.t2[2] - f.t1[2] * f.t2[1],
            f.t1[2] * f.t2[0] - f.t1[0] * f.t2[2],
            f.t1[0] * f.t2[1] - f.t1[1] * f.t2[0],
        ];
        assert!(d(c, f.n) > 1.0 - 1e-14, "t1 × t2 = n");
        let g = f.to_global(f.to_local([0.3, -1.2, 2.5]));
        assert!((g[0] - 0.3).abs() + (g[1] + 1.2).abs() + (g[2] - 2.5).abs() < 1e-14);
    }
}

// --------------------------------------- 2. two blocks between fixed walls

/// Two bars (blocks A, B) between fixed walls, each split into `m` springs,
/// joint normal +x. Every node has 3 DOFs: axial springs EA/h in x, shear
/// springs GA/h in y and z. Returns (W, b, K, C, f) for a uniform ΔT.
struct Bars {
    e: f64,
    area: f64,
    la: f64,
    lb: f64,
    alpha: f64,
    g0: f64,
    m: usize,
}

impl Bars {
    fn model(
        &self,
        dt: f64,
    ) -> (
        DMatrix<f64>,
        Vec<f64>,
        DMatrix<f64>,
        DMatrix<f64>,
        DVector<f64>,
    ) {
        let m = self.m;
        let nn = 2 * m; // free nodes: A1..Am (Am = joint A), B0..B(m-1) (B0 = joint B)
        let ndof = 3 * nn;
        let mut k = DMatrix::zeros(ndof, ndof);
        let mut f = DVector::zeros(ndof);
        let eps0 = self.alpha * dt;
        let g = self.e / 2.5;
        // elements as (node a, node b, length); None = wall
        let mut elems: Vec<(Option<usize>, Option<usize>, f64)> = Vec::new();
        let (ha, hb) = (self.la / m as f64, self.lb / m as f64);
        elems.push((None, Some(0), ha));
        for i in 0..m - 1 {
            elems.push((Some(i), Some(i + 1), ha));
        }
        for i in 0..m - 1 {
            elems.push((Some(m + i), Some(m + i + 1), hb));
        }
        elems.push((Some(2 * m - 1), None, hb));
        for &(a, b, h) in &elems {
            for dir in 0..3 {
                let kk = if dir == 0 { self.e } else { g } * self.area / h;
                let ia = a.map(|a| 3 * a + dir);
                let ib = b.map(|b| 3 * b + dir);
                if let Some(i) = ia {
                    k[(i, i)] += kk;
                }
                if let Some(j) = ib {
                    k[(j, j)] += kk;
                }
                if let (Some(i), Some(j)) = (ia, ib) {
                    k[(i, j)] -= kk;
                    k[(j, i)] -= kk;
                }
            }
            // thermal expansion: the element pushes its ends apart
            let p = self.e * self.area * eps0;
            if let Some(a) = a {
                f[3 * a] -= p;
            }
            if let Some(b) = b {
                f[3 * b] += p;
            }
        }
        let frame = LocalFrame::from_normal([1.0, 0.0, 0.0]).unwrap();
        let rot = frame.rotation();
        let (ja, jb) = (m - 1, m);
        let mut c = DMatrix::zeros(3, ndof);
        for (row, axis) in rot.iter().enumerate() {
            for d in 0..3 {
                c[(row, 3 * jb + d)] += axis[d];
                c[(row, 3 * ja + d)] -= axis[d];
            }
        }
        let g0 = DVector::from_vec(vec![0.0, 0.0, self.g0]);
        let (w, b) = condense(&k, &c, &f, &g0);
        (w, b, k, c, f)
    }
}

#[test]
fn two_blocks_between_walls_cooled_open_heated_closed() {
    let bars = Bars {
        e: 30.0e9,
        area: 1.0,
        la: 15.0,
        lb: 20.0,
        alpha: 1.0e-5,
        g0: 0.2e-3,
        m: 5,
    };
    let l = bars.la + bars.lb;
    for fr in [FrictionModel::Frictionless, FrictionModel::coulomb(0.6)] {
        // Cooled: the joint opens by the free contraction of both blocks.
        let dt = -10.0;
        let (w, b, ..) = bars.model(dt);
        let s = solve_default(&w, &b, &[fr]);
        assert_eq!(s.states, vec![ContactState::Open]);
        assert_eq!(s.r[2], 0.0);
        let aperture = bars.g0 - bars.alpha * dt * l;
        assert!(
            rel(s.u[2], aperture) <= 1e-12,
            "aperture {} vs {aperture}",
            s.u[2]
        );

        // Heated past closure: σ = −E(αΔT·L − g0)/L in both blocks.
        let dt = 12.0;
        let (w, b, k, c, f) = bars.model(dt);
        let s = solve_default(&w, &b, &[fr]);
        assert!(s.states[0].is_closed());
        let sigma = -bars.e * (bars.alpha * dt * l - bars.g0) / l;
        assert!(
            rel(s.r[2], -sigma * bars.area) <= 1e-9,
            "r_n {} vs {}",
            s.r[2],
            -sigma * bars.area
        );
        assert!(s.u[2].abs() <= 1e-9 * bars.g0, "closed gap {}", s.u[2]);
        assert!(s.r[0].abs() + s.r[1].abs() <= 1e-9 * s.r[2], "no shear");
        // Stresses from the displacements under f + Cᵀ r.
        let r = DVector::from_vec(s.r.clone());
        let u = k
            .clone()
            .cholesky()
            .unwrap()
            .solve(&(f + c.transpose() * r));
        let eps0 = bars.alpha * dt;
        let ha = bars.la / bars.m as f64;
        let hb = bars.lb / bars.m as f64;
        let sigma_a = bars.e * (u[0] / ha - eps0); // first element of A (wall → A1)
        let last = 3 * (2 * bars.m - 1);
        let sigma_b = bars.e * ((0.0 - u[last]) / hb - eps0); // last element of B
        assert!(rel(sigma_a, sigma) <= 1e-9, "σ_A {sigma_a} vs {sigma}");
        assert!(rel(sigma_b, sigma) <= 1e-9, "σ_B {sigma_b} vs {sigma}");
        // Heated but not past closure: still open by g0 − αΔT L.
        let dt = 0.5 * bars.g0 / (bars.alpha * l);
        let (w, b, ..) = bars.model(dt);
        let s = solve_default(&w, &b, &[fr]);
        assert_eq!(s.states, vec![ContactState::Open]);
        assert!(rel(s.u[2], 0.5 * bars.g0) <= 1e-10);
    }
}

// ----------------------------------------------------- 3. sliding block

/// Block on a fixed base (n = +z), supported by springs kt (x, y) and kn (z)
/// plus an optional inclined spring k_i along (cos θ, 0, sin θ) that couples
/// the normal and the tangential direction; loads (Tx, Ty, −N).
fn block(
    kt: f64,
    kn: f64,
    k_i: f64,
    theta: f64,
    load: [f64; 3],
) -> (DMatrix<f64>, Vec<f64>, LocalFrame) {
    let e = [theta.cos(), 0.0, theta.sin()];
    let mut k = DMatrix::from_diagonal(&DVector::from_vec(vec![kt, kt, kn]));
    for i in 0..3 {
        for j in 0..3 {
            k[(i, j)] += k_i * e[i] * e[j];
        }
    }
    let frame = LocalFrame::from_normal([0.0, 0.0, 1.0]).unwrap();
    let rot = frame.rotation();
    let c = DMatrix::from_fn(3, 3, |i, j| rot[i][j]);
    let (w, b) = condense(
        &k,
        &c,
        &DVector::from_vec(load.to_vec()),
        &DVector::zeros(3),
    );
    (w, b, frame)
}

#[test]
fn sliding_block_static_kinetic_zero_and_high_friction() {
    let (kt, kn) = (5.0e8, 2.0e9);
    let nload = 1.0e6;
    // (mu_s, mu_k, push/N, expected state)
    let cases = [
        (0.4, 0.3, 0.39, ContactState::Stick),
        (0.4, 0.3, 0.41, ContactState::Slip),
        (0.4, 0.4, 0.3999, ContactState::Stick),
        (0.4, 0.4, 0.4001, ContactState::Slip),
        (0.0, 0.0, 0.05, ContactState::Slip),
        (5.0, 5.0, 4.9, ContactState::Stick),
        (5.0, 4.0, 5.1, ContactState::Slip),
    ];
    for &(mu_s, mu_k, ratio, expect) in &cases {
        // push at 30° in the plane so both tangents work
        let t = ratio * nload;
        let dir = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
        let (w, b, frame) = block(kt, kn, 0.0, 0.0, [t * dir[0], t * dir[1], -nload]);
        let s = solve_default(&w, &b, &[FrictionModel::Coulomb { mu_s, mu_k }]);
        let tag = format!("mu_s {mu_s} mu_k {mu_k} T/N {ratio}");
        assert_eq!(s.states[0], expect, "{tag}");
        assert!(rel(s.r[2], nload) <= 1e-9, "{tag}: r_n {}", s.r[2]);
        assert!(s.u[2].abs() <= 1e-9 * b[2].abs(), "{tag}: gap {}", s.u[2]);
        let rt_global = frame.to_global([s.r[0], s.r[1], 0.0]);
        let ut_global = frame.to_global([s.u[0], s.u[1], 0.0]);
        match expect {
            ContactState::Stick => {
                // friction carries the whole push, no slip
                assert!(
                    rel(rt_global[0], -t * dir[0]) <= 1e-9,
                    "{tag}: r_x {}",
                    rt_global[0]
                );
                assert!(rel(rt_global[1], -t * dir[1]) <= 1e-9, "{tag}");
                assert!(
                    tangential(&s.u, 0) <= 1e-9 * tangential(&b, 0),
                    "{tag}: slip {:?}",
                    s.u
                );
            }
            _ => {
                // kinetic friction against the push, the spring takes the rest
                let f = mu_k * nload;
                assert!(
                    rel(tangential(&s.r, 0), f) <= 1e-8,
                    "{tag}: |r_t| {} vs {f}",
                    tangential(&s.r, 0)
                );
                if f > 0.0 {
                    assert!(rel(rt_global[0], -f * dir[0]) <= 1e-8, "{tag}");
                    assert!(rel(rt_global[1], -f * dir[1]) <= 1e-8, "{tag}");
                } else {
                    assert_eq!(tangential(&s.r, 0), 0.0, "{tag}");
                }
                let slip = (t - f) / kt;
                assert!(
                    rel(ut_global[0], slip * dir[0]) <= 1e-8,
                    "{tag}: u_x {}",
                    ut_global[0]
                );
                assert!(rel(ut_global[1], slip * dir[1]) <= 1e-8, "{tag}");
            }
        }
        assert!(s.kkt_residual <= 1e-9, "{tag}: kkt {}", s.kkt_residual);
    }
}

#[test]
fn sliding_block_with_normal_tangential_coupling() {
    // The inclined spring couples x and z: W_nt ≠ 0, so sliding changes the
    // normal force and the Tresca fixed point has real work to do.
    let (kt, kn, k_i, theta) = (5.0e8, 2.0e9, 1.5e9, 50f64.to_radians());
    let nload = 1.0e6;
    let (mu_s, mu_k) = (0.5, 0.35);
    for (push, expect) in [(0.2, ContactState::Stick), (0.9, ContactState::Slip)] {
        let (w, b, frame) = block(kt, kn, k_i, theta, [push * nload, 0.0, -nload]);
        let s = solve_default(&w, &b, &[FrictionModel::Coulomb { mu_s, mu_k }]);
        assert_eq!(s.states[0], expect, "push {push}");
        // Closed form in the local frame (t2 = +x for n = +z).
        assert_eq!(frame.t2, [1.0, 0.0, 0.0]);
        let wm = w.clone();
        let bv = DVector::from_vec(b.clone());
        let exact = if expect == ContactState::Stick {
            let r = -wm.clone().lu().solve(&bv).unwrap();
            assert!(
                r[0].abs().hypot(r[1]) < mu_s * r[2],
                "stick must be admissible"
            );
            r
        } else {
            // r = (0, −σ μ_k r_n, r_n), u_n = 0, σ = sign(u_t2) = +1 (pushed along +x)
            let sg = 1.0;
            let rn = -b[2] / (wm[(2, 2)] - sg * mu_k * wm[(2, 1)]);
            let r = DVector::from_vec(vec![0.0, -sg * mu_k * rn, rn]);
            let u = &bv + &wm * &r;
            assert!(
                u[1] > 0.0 && u[0].abs() <= 1e-12 * u[1],
                "slip along +x: {u:?}"
            );
            r
        };
        for k in 0..3 {
            assert!(
                (s.r[k] - exact[k]).abs() <= 1e-8 * exact.amax(),
                "push {push}: r {:?} vs {exact:?}",
                s.r
            );
        }
        // The plain Tresca fixed point (no polish) reaches the same answer.
        let plain = ContactSettings {
            polish: false,
            tolerance: 1e-10,
            ..ContactSettings::default()
        };
        let fr = [FrictionModel::Coulomb { mu_s, mu_k }];
        let p = solve(&ContactProblem::new(&w, &b, &fr), &plain, None).unwrap();
        assert_eq!(p.states[0], expect, "push {push}, no polish");
        for k in 0..3 {
            assert!(
                (p.r[k] - exact[k]).abs() <= 1e-8 * exact.amax(),
                "push {push}, no polish: r {:?} vs {exact:?}",
                p.r
            );
        }
        if expect == ContactState::Slip {
            // sliding changed the normal force, so the bounds had to iterate
            assert!(rel(s.r[2], nload) > 1e-3);
            assert!(
                p.fixed_point_iterations >= 4,
                "{}",
                p.fixed_point_iterations
            );
        }
        assert!(s.kkt_residual <= 1e-9);
    }
}

// ------------------------------------------- 4. inclined plane, patch

/// Block on a plane z = x tanα (outward normal (−sinα, 0, cosα)), weight G,
/// horizontal push F towards +x (up the slope), isotropic elastic support k.
fn inclined(f_over_g: f64, tan_a: f64, mu: f64) -> ContactSolution {
    let (g, k) = (1.0e5, 1.0e9);
    let a = tan_a.atan();
    let frame = LocalFrame::from_normal([-a.sin(), 0.0, a.cos()]).unwrap();
    let rot = frame.rotation();
    let c = DMatrix::from_fn(3, 3, |i, j| rot[i][j]);
    let kmat = DMatrix::<f64>::identity(3, 3) * k;
    let f = DVector::from_vec(vec![f_over_g * g, 0.0, -g]);
    let (w, b) = condense(&kmat, &c, &f, &DVector::zeros(3));
    solve_default(&w, &b, &[FrictionModel::coulomb(mu)])
}

#[test]
fn inclined_plane_limit_push() {
    let (tan_a, mu): (f64, f64) = (0.1, 0.3);
    let limit = (tan_a + mu) / (1.0 - mu * tan_a);
    assert_eq!(format!("{limit:.6}"), "0.412371");
    let s = inclined(0.4123, tan_a, mu);
    assert_eq!(s.states[0], ContactState::Stick);
    let s = inclined(0.4124, tan_a, mu);
    assert_eq!(s.states[0], ContactState::Slip);
    // t2 of this frame points up the slope: it slides up.
    assert!(s.u[1] > 0.0, "slides up the slope: {:?}", s.u);
    // Bisection with the solver.
    let (mut lo, mut hi) = (0.2, 0.6);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if inclined(mid, tan_a, mu).states[0] == ContactState::Stick {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let found = 0.5 * (lo + hi);
    eprintln!("inclined plane: limit F/G by bisection {found:.9} (closed form {limit:.9})");
    assert_eq!(format!("{found:.6}"), "0.412371");
    assert!((found - limit).abs() <= 1e-7, "{found} vs {limit}");
}

#[test]
fn contact_patch_on_incline_reaches_the_limit_together() {
    // Four points coupled through the body: W = A ⊗ I3 / k with an exponential
    // kernel A (A⁻¹1 > 0), the same free displacement at every point. The
    // force ratio is then the same everywhere, so the rigid-block limit holds
    // for the patch while the points share load unequally.
    let (tan_a, mu): (f64, f64) = (0.1, 0.3);
    let limit = (tan_a + mu) / (1.0 - mu * tan_a);
    let npts = 4;
    let k = 1.0e9;
    let a = DMatrix::from_fn(npts, npts, |i, j| 0.5f64.powi((i as i32 - j as i32).abs()));
    let w = a.kronecker(&DMatrix::<f64>::identity(3, 3)) / k;
    let alpha = tan_a.atan();
    let frame = LocalFrame::from_normal([-alpha.sin(), 0.0, alpha.cos()]).unwrap();
    let g = 1.0e5;
    for (ratio, expect) in [
        (0.99999 * limit, ContactState::Stick),
        (1.00001 * limit, ContactState::Slip),
    ] {
        let local = frame.to_local([ratio * g, 0.0, -g]);
        let b: Vec<f64> = (0..npts).flat_map(|_| local.map(|v| v / k)).collect();
        let fr = vec![FrictionModel::coulomb(mu); npts];
        let s = solve_default(&w, &b, &fr);
        assert!(
            s.states.iter().all(|&st| st == expect),
            "ratio {ratio}: {:?}",
            s.states
        );
        let rn: Vec<f64> = (0..npts).map(|i| s.r[3 * i + 2]).collect();
        assert!(rel(rn[0], rn[1]) > 0.1, "unequal load sharing: {rn:?}");
        for i in 0..npts {
            let q = tangential(&s.r, i) / rn[i];
            if expect == ContactState::Slip {
                assert!(rel(q, mu) <= 1e-8, "point {i}: |r_t|/r_n = {q}");
            } else {
                assert!(q < mu && q > 0.999 * mu, "point {i}: {q}");
                assert!(tangential(&s.u, i) <= 1e-9 * tangential(&b, i));
            }
        }
        assert!(s.kkt_residual <= 1e-9);
    }
}

// ---------------------------------------------- random problem generator

/// Points on a grid, W = (A ⊗ B)·c + δ·c·I with an exponential kernel A
/// (SPD) and an SPD 3×3 block B with normal–tangential coupling; gaps mixed
/// open/closed, tangential pushes random; mostly Coulomb (μ_k = 0.8 μ_s) with
/// some frictionless and tied points.
fn random_problem(npts: usize, seed: u64) -> (DMatrix<f64>, Vec<f64>, Vec<FrictionModel>) {
    let mut rng = Rng(seed);
    let nx = (npts as f64).sqrt().ceil() as usize;
    let xy: Vec<(f64, f64)> = (0..npts)
        .map(|i| {
            (
                (i % nx) as f64 + rng.range(-0.2, 0.2),
                (i / nx) as f64 + rng.range(-0.2, 0.2),
            )
        })
        .collect();
    let ell = 0.7;
    let a = DMatrix::from_fn(npts, npts, |i, j| {
        let d = (xy[i].0 - xy[j].0).hypot(xy[i].1 - xy[j].1);
        (-d / ell).exp()
    });
    let bblk = DMatrix::from_row_slice(3, 3, &[1.0, 0.1, 0.15, 0.1, 0.9, -0.1, 0.15, -0.1, 1.6]);
    let c = 1.0e-9; // m/N
    let mut w = a.kronecker(&bblk) * c;
    for i in 0..3 * npts {
        w[(i, i)] += 0.3 * c;
    }
    let mut b = vec![0.0; 3 * npts];
    let mut friction = Vec::with_capacity(npts);
    for i in 0..npts {
        b[3 * i] = rng.range(-0.15, 0.15) * 1e-3;
        b[3 * i + 1] = rng.range(-0.15, 0.15) * 1e-3;
        b[3 * i + 2] = rng.range(-1.0, 0.1) * 1e-3;
        let x = rng.uniform();
        friction.push(if x < 0.08 {
            FrictionModel::Frictionless
        } else if x < 0.12 {
            FrictionModel::Tied
        } else {
            let mu_s = rng.range(0.3, 0.8);
            FrictionModel::Coulomb {
                mu_s,
                mu_k: 0.8 * mu_s,
            }
        });
    }
    (w, b, friction)
}

// ------------------------------------------------ 5. unit invariance

#[test]
fn unit_invariance_m_newton_vs_mm_meganewton() {
    let (w, b, fr) = random_problem(16, 11);
    let base = solve_default(&w, &b, &fr);
    let counts = |s: &ContactSolution, st| s.states.iter().filter(|&&x| x == st).count();
    assert!(counts(&base, ContactState::Open) > 0 && counts(&base, ContactState::Slip) > 0);
    // (length factor, force factor): mm & MN, mm & N, km & kN
    for (ll, ff) in [(1.0e3, 1.0e-6), (1.0e3, 1.0), (1.0e-3, 1.0e-3)] {
        let w2 = &w * (ll / ff);
        let b2: Vec<f64> = b.iter().map(|v| v * ll).collect();
        let s = solve_default(&w2, &b2, &fr);
        assert_eq!(s.states, base.states, "units ({ll}, {ff})");
        let rmax = base.r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let umax = base.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..b.len() {
            let r = s.r[k] / ff;
            let u = s.u[k] / ll;
            assert!(
                (r - base.r[k]).abs() <= 1e-9 * rmax,
                "units ({ll}, {ff}) r[{k}] {r} vs {}",
                base.r[k]
            );
            assert!(
                (u - base.u[k]).abs() <= 1e-9 * umax,
                "units ({ll}, {ff}) u[{k}] {u} vs {}",
                base.u[k]
            );
        }
        assert!((s.kkt_residual - base.kkt_residual).abs() <= 1e-9);
    }
}

// ------------------------------------- 6. random problems, KKT, timing

fn check_states(s: &ContactSolution, fr: &[FrictionModel], tag: &str) {
    let d = s.scales.displacement;
    let f = s.scales.force;
    for (i, (&st, &model)) in s.states.iter().zip(fr).enumerate() {
        let (rn, un) = (s.r[3 * i + 2], s.u[3 * i + 2]);
        let (rt, ut) = (tangential(&s.r, i), tangential(&s.u, i));
        let p = format!("{tag} point {i} {st:?} {model:?}");
        match st {
            ContactState::Open => {
                assert_eq!(rn, 0.0, "{p}");
                assert!(un >= -1e-8 * d, "{p}: gap {un}");
                if model != FrictionModel::Tied {
                    assert_eq!(rt, 0.0, "{p}");
                }
            }
            ContactState::Stick => {
                assert!(rn > 0.0 && un.abs() <= 1e-8 * d, "{p}: r_n {rn}, gap {un}");
                assert!(ut <= 1e-8 * d, "{p}: slip {ut}");
                if let FrictionModel::Coulomb { mu_s, .. } = model {
                    assert!(
                        rt <= mu_s * rn + 1e-8 * f,
                        "{p}: |r_t| {rt} > μ_s r_n {}",
                        mu_s * rn
                    );
                }
            }
            ContactState::Slip => {
                assert!(rn > 0.0 && un.abs() <= 1e-8 * d, "{p}: r_n {rn}, gap {un}");
                let mu_k = match model {
                    FrictionModel::Coulomb { mu_k, .. } => mu_k,
                    FrictionModel::Frictionless => 0.0,
                    FrictionModel::Tied => panic!("{p}: a tied point cannot slip"),
                };
                assert!(
                    (rt - mu_k * rn).abs() <= 1e-8 * f,
                    "{p}: |r_t| {rt} vs μ_k r_n {}",
                    mu_k * rn
                );
                if mu_k > 0.0 && ut > 1e-6 * d {
                    // friction opposes the slip
                    let cosang =
                        (s.r[3 * i] * s.u[3 * i] + s.r[3 * i + 1] * s.u[3 * i + 1]) / (rt * ut);
                    assert!(cosang < -1.0 + 1e-6, "{p}: cos(r_t, u_t) = {cosang}");
                }
            }
        }
    }
}

#[test]
fn random_problems_mixed_states_kkt() {
    let settings = ContactSettings::default();
    for (npts, seed) in [(50, 1u64), (120, 2), (200, 3)] {
        let (w, b, fr) = random_problem(npts, seed);
        let problem = ContactProblem::new(&w, &b, &fr);
        let t0 = Instant::now();
        let s = solve(&problem, &settings, None).unwrap_or_else(|e| panic!("n = {npts}: {e}"));
        let tag = format!("n = {npts}");
        let count = |st| s.states.iter().filter(|&&x| x == st).count();
        let (open, stick, slip) = (
            count(ContactState::Open),
            count(ContactState::Stick),
            count(ContactState::Slip),
        );
        eprintln!(
            "{tag}: open {open} stick {stick} slip {slip}, {} cone programs, {} IPM iterations, \
             kkt {:.2e}, {:.3} s",
            s.fixed_point_iterations,
            s.ipm_iterations,
            s.kkt_residual,
            t0.elapsed().as_secs_f64()
        );
        assert!(
            open >= npts / 10 && stick >= npts / 10 && slip >= npts / 10,
            "{tag}: not mixed"
        );
        assert!(
            s.fixed_point_iterations >= 3,
            "{tag}: friction must iterate"
        );
        assert!(s.kkt_residual <= 1e-8, "{tag}: kkt {:?}", s.kkt);
        // independent recomputation of the residual
        let (k, _) = kkt_residual(&problem, &s.r).unwrap();
        assert!(
            k.max() <= 1e-8 && (k.max() - s.kkt_residual).abs() <= 1e-15,
            "{tag}: {k:?}"
        );
        check_states(&s, &fr, &tag);
        // the check discriminates: move one sticking point's force by 1e-5 F
        let i = s
            .states
            .iter()
            .position(|&x| x == ContactState::Stick)
            .unwrap();
        let mut r = s.r.clone();
        r[3 * i] += 1e-5 * s.scales.force;
        let (k, _) = kkt_residual(&problem, &r).unwrap();
        assert!(
            k.max() > 1e-6,
            "{tag}: perturbed forces must fail the check: {k:?}"
        );
        // a warm start from the solution converges to the same answer
        let s2 = solve(&problem, &settings, Some(&s.r)).unwrap();
        assert_eq!(s2.states, s.states, "{tag}: warm start states");
        assert!(
            s2.fixed_point_iterations <= s.fixed_point_iterations,
            "{tag}: warm start"
        );
        let rmax = s.r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..s.r.len() {
            assert!(
                (s2.r[k] - s.r[k]).abs() <= 1e-9 * rmax,
                "{tag}: warm r[{k}]"
            );
        }
        // the plain Tresca fixed point (no polish, no early exit) agrees to
        // its own tolerance
        if npts <= 50 {
            let plain = ContactSettings {
                polish: false,
                kkt_tolerance: 1e-4,
                ..ContactSettings::default()
            };
            let p = solve(&problem, &plain, None).unwrap();
            eprintln!(
                "{tag} without polish: {} cone programs, kkt {:.2e}",
                p.fixed_point_iterations, p.kkt_residual
            );
            assert!(p.fixed_point_iterations > s.fixed_point_iterations);
            // interior-point accuracy: the slip directions are good to ~1e-6
            assert!(p.kkt_residual <= 1e-5, "{tag}: {:?}", p.kkt);
            assert_eq!(p.states, s.states, "{tag}: states without polish");
            for k in 0..s.r.len() {
                assert!(
                    (p.r[k] - s.r[k]).abs() <= 1e-5 * rmax,
                    "{tag}: no-polish r[{k}] {} vs {}",
                    p.r[k],
                    s.r[k]
                );
            }
        }
    }
}

#[test]
fn not_converged_is_reported() {
    let (w, b, fr) = random_problem(30, 5);
    let settings = ContactSettings {
        max_fixed_point: 2,
        polish: false,
        ..ContactSettings::default()
    };
    let e = solve(&ContactProblem::new(&w, &b, &fr), &settings, None).unwrap_err();
    match e {
        ContactError::NotConverged { iterations, change } => {
            assert_eq!(iterations, 2);
            assert!(change > settings.tolerance);
        }
        other => panic!("expected NotConverged, got {other}"),
    }
}

/// Timing (printed, not asserted) for n = 100 and 400 points;
/// `GROUTREADY_CONTACT_TIMING=100,400,1000` chooses other sizes.
#[test]
fn timing_random_problems() {
    let sizes: Vec<usize> = match std::env::var("GROUTREADY_CONTACT_TIMING") {
        Ok(v) => v.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => vec![100, 400],
    };
    time_sizes(&sizes);
}

/// n = 1000 points costs over a minute on 2 cores (dense KKT in QDLDL):
/// `cargo test --release --test contact_qp -- --ignored`.
#[test]
#[ignore]
fn timing_random_problems_1000() {
    time_sizes(&[1000]);
}

fn time_sizes(sizes: &[usize]) {
    for &npts in sizes {
        let (w, b, fr) = random_problem(npts, 100 + npts as u64);
        let t0 = Instant::now();
        let s = solve(
            &ContactProblem::new(&w, &b, &fr),
            &ContactSettings::default(),
            None,
        );
        let dt = t0.elapsed().as_secs_f64();
        match s {
            Ok(s) => {
                let count = |st| s.states.iter().filter(|&&x| x == st).count();
                eprintln!(
                    "timing n = {npts} ({} unknowns): {dt:.3} s (clarabel {:.3} s, polish {:.3} s), \
                     {} cone programs, {} IPM iterations, open {} stick {} slip {}, kkt {:.2e}",
                    3 * npts,
                    s.cone_seconds,
                    s.polish_seconds,
                    s.fixed_point_iterations,
                    s.ipm_iterations,
                    count(ContactState::Open),
                    count(ContactState::Stick),
                    count(ContactState::Slip),
                    s.kkt_residual
                );
                assert!(s.kkt_residual <= 1e-8);
            }
            Err(e) => panic!("timing n = {npts}: {e} after {dt:.3} s"),
        }
    }
}

#[test]
fn stiffness_contrast_and_tiny_apertures() {
    // DESIGN §7 hard cases: compliances spread over 1e6 between points (stiff
    // old concrete next to newborn) and free gaps down to 1e-6 of the largest.
    for seed in [21u64, 22] {
        let (w, mut b, fr) = random_problem(60, seed);
        let mut rng = Rng(seed * 7);
        let d: Vec<f64> = (0..60).map(|_| 10f64.powf(rng.range(0.0, 3.0))).collect();
        let w = DMatrix::from_fn(180, 180, |i, j| d[i / 3] * w[(i, j)] * d[j / 3]);
        for i in 0..60 {
            for k in 0..3 {
                b[3 * i + k] *= d[i];
            }
            if i % 7 == 0 {
                b[3 * i + 2] = 1e-6 * 1e-3 * rng.range(-1.0, 1.0);
            }
        }
        let problem = ContactProblem::new(&w, &b, &fr);
        let s = solve(&problem, &ContactSettings::default(), None)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let count = |st| s.states.iter().filter(|&&x| x == st).count();
        eprintln!(
            "contrast seed {seed}: open {} stick {} slip {}, {} cone programs, kkt {:.2e}",
            count(ContactState::Open),
            count(ContactState::Stick),
            count(ContactState::Slip),
            s.fixed_point_iterations,
            s.kkt_residual
        );
        assert!(s.kkt_residual <= 1e-8, "seed {seed}: {:?}", s.kkt);
        check_states(&s, &fr, &format!("contrast seed {seed}"));
    }
}

#[test]
fn rigid_tangential_rows_are_handled() {
    // A 1-D model condensed to 3 rows: no tangential compliance (W_tt = 0).
    let k = 2.0e9;
    let delta = 1.0e-4;
    let w = DMatrix::from_diagonal(&DVector::from_vec(vec![0.0, 0.0, 1.0 / k]));
    let b = [0.0, 0.0, -delta];
    for fr in [FrictionModel::coulomb(0.5), FrictionModel::Frictionless] {
        let s = solve_default(&w, &b, &[fr]);
        assert!(rel(s.r[2], k * delta) <= 1e-9, "{fr:?}: {:?}", s.r);
        assert!(
            s.r[0].abs() + s.r[1].abs() <= 1e-9 * s.r[2],
            "{fr:?}: {:?}",
            s.r
        );
        assert!(s.states[0].is_closed());
        assert!(s.kkt_residual <= 1e-9);
    }
}
