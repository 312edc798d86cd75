//! `qp`: the condensed contact problem as a sequence of convex cone programs
//! solved by clarabel (Tresca fixed point for Coulomb friction), polished to
//! round-off by Newton's method on the identified active set.
//!
//! Each cone program, in scaled variables, is
//!
//! ```text
//! min ½ r̃ᵀ W̃ r̃ + b̃ᵀ r̃   s.t.  r̃_n,i ≥ 0              (one nonnegative cone for all normals)
//!                             (s̃_i, r̃_t,i) ∈ SOC(3)   (Coulomb points with a bound s̃_i > 0)
//!                             r̃_t,i = 0                (frictionless points, and Coulomb points
//!                                                       with s̃_i = 0: the variables are left out)
//!                             r̃_t,i free               (tied points: u_t = 0 is then the
//!                                                       optimality condition)
//! ```
//!
//! with W̃ = sym(W)/ω, b̃ = b/β, r = r̃ β/ω (ω = mean diagonal of W,
//! β = max|b|), so every tolerance is relative and the answer does not depend
//! on the units. Only the upper triangle of W̃ over the kept variables is
//! passed to clarabel (dense: its KKT factorisation costs O((3n)³) per
//! interior-point iteration with the default QDLDL).
//!
//! Friction (static μ_s, kinetic μ_k): the fixed point s̃_i ← μ_i r̃_n,i runs
//! with μ_i = μ_s for every point until ‖Δs̃‖∞ ≤ tolerance·(‖s̃‖∞ + 1). Points
//! then found closed with the tangential force on the μ_s bound start to slide:
//! their coefficient becomes μ_k and the fixed point continues; this repeats
//! until no new point reaches its static bound (the sliding set only grows;
//! every cone program counts against `max_fixed_point`). A warm start gives
//! the initial bounds s̃_i = μ_s r_n,i. The first program (all bounds 0) is
//! the normal-only QP.
//!
//! Polish. An interior point resolves the slip directions only to ~1e-6, so
//! the states of the last iterate (open / stick / slip) define equalities —
//! open r = 0; stick u = 0; slip u_n = 0, r_t = μ_k r_n (cos φ, sin φ) with
//! u_t ∥ −(cos φ, sin φ) — solved by Newton's method (dense LU, faer); violated
//! inequalities switch the point's state (r_n < 0 → open, u_n < 0 → closed,
//! ‖r_t‖ > μ_s r_n → slip, slip along the friction force → stick) for a few
//! rounds. The polished answer replaces the interior-point one when its KKT
//! residual is not larger. It also ends the fixed point early: when two
//! successive iterates have the same states (and, if some μ_k < μ_s, the bounds
//! are within `early_exit_change` of μ r_n) and their polished solution has a
//! KKT residual ≤ `polish_tolerance`, that solution satisfies every contact
//! condition and s = μ r_n exactly, i.e. it is the fixed point.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
    SupportedConeT::{NonnegativeConeT, SecondOrderConeT},
};
use nalgebra::DMatrix;
use std::time::Instant;

use super::contact::{
    apply, check_dims, kkt_of, max_abs, mean_diagonal, point_rows_3d, point_rows_normal, scales_of,
    ContactError, ContactProblem, ContactSolution, ContactState, FrictionModel, KktResidual,
    NormalProblem, PointRows, Scales,
};

/// Settings of the `qp` contact solver. All tolerances are relative (see
/// [`Scales`]); the defaults are what the acceptance tests use.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSettings {
    /// Interior-point tolerance handed to clarabel as `tol_gap_abs`,
    /// `tol_gap_rel` and `tol_feas` (the problem is already scaled).
    /// Default `1e-9` (at 1e-10 clarabel often stops at `AlmostSolved`).
    /// The interior point alone resolves slip directions to ~1e-6; the polish
    /// takes the answer to round-off.
    pub ipm_tolerance: f64,
    /// Interior-point iteration limit per cone program. Default `200`.
    pub ipm_max_iter: u32,
    /// Accept clarabel's `AlmostSolved` (reduced accuracy) status: the
    /// answer is still polished and must pass the own KKT check
    /// (`kkt_tolerance`). With `false` any status but `Solved` is a
    /// [`ContactError::Solver`]. Default `true`.
    pub accept_almost_solved: bool,
    /// Friction fixed point stops when ‖Δs̃‖∞ ≤ tolerance·(‖s̃‖∞ + 1), s̃ the
    /// slip bounds in units of [`Scales::force`]. Default `1e-7` (about the
    /// interior-point noise; the polish makes the answer exact).
    pub tolerance: f64,
    /// Maximum number of cone programs in the friction fixed point (all
    /// static/kinetic rounds together). Default `100`.
    pub max_fixed_point: usize,
    /// Under-relaxation of the bound update s̃ ← s̃ + ρ(μ r̃_n − s̃), in (0, 1].
    /// Default `1.0`.
    pub relaxation: f64,
    /// A point is open when r_n ≤ max(open_tolerance·F, u_n·F/D), F and D the
    /// force and displacement scales (i.e. the smaller member of the
    /// complementary pair is the zero one). Open points get r = 0 exactly
    /// (tied points keep r_t). Default `1e-9`.
    pub open_tolerance: f64,
    /// A closed point slides when its bound s minus ‖r_t‖ is at most
    /// max(slip_tolerance·s, ‖u_t‖·F/D). Default `1e-7`.
    pub slip_tolerance: f64,
    /// The solve fails with [`ContactError::Kkt`] when the relative KKT
    /// residual of the returned solution exceeds this. Default `1e-6`.
    pub kkt_tolerance: f64,
    /// W must be symmetric to this times max|W_ij|. Default `1e-8`.
    pub symmetry_tolerance: f64,
    /// Polish the interior-point answer: solve the equalities of its active
    /// set exactly (dense LU), correct violated inequalities (at most
    /// `polish_max_rounds` rounds) and keep the result when its KKT residual
    /// is not worse. Also stops the friction fixed point early once two
    /// successive iterates have the same states and their polished solution
    /// has a KKT residual ≤ `polish_tolerance`. Default `true`.
    pub polish: bool,
    /// KKT residual an early-exit polished solution must reach; also the
    /// feasibility margin of the polish's switching tests. Default `1e-11`.
    pub polish_tolerance: f64,
    /// Active-set rounds of the polish. Default `8`.
    pub polish_max_rounds: usize,
    /// Early exit (see `polish`) when some point has μ_k < μ_s needs the
    /// bounds of the iterate within this relative change of μ r_n, so that
    /// "reaches the static bound" is decided on a nearly converged Tresca
    /// solution. Default `1e-3`.
    pub early_exit_change: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            ipm_tolerance: 1e-9,
            ipm_max_iter: 200,
            accept_almost_solved: true,
            tolerance: 1e-7,
            max_fixed_point: 100,
            relaxation: 1.0,
            open_tolerance: 1e-9,
            slip_tolerance: 1e-7,
            kkt_tolerance: 1e-6,
            symmetry_tolerance: 1e-8,
            polish: true,
            polish_tolerance: 1e-11,
            polish_max_rounds: 8,
            early_exit_change: 1e-3,
        }
    }
}

impl ContactSettings {
    /// `Err` names the field and its value.
    pub fn validate(&self) -> Result<(), ContactError> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ContactError::Settings(format!(
                    "{name} must be finite and > 0, got {v}"
                )))
            }
        };
        let nonneg = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(ContactError::Settings(format!(
                    "{name} must be finite and >= 0, got {v}"
                )))
            }
        };
        positive("ipm_tolerance", self.ipm_tolerance)?;
        positive("tolerance", self.tolerance)?;
        nonneg("open_tolerance", self.open_tolerance)?;
        nonneg("slip_tolerance", self.slip_tolerance)?;
        positive("kkt_tolerance", self.kkt_tolerance)?;
        nonneg("symmetry_tolerance", self.symmetry_tolerance)?;
        positive("polish_tolerance", self.polish_tolerance)?;
        nonneg("early_exit_change", self.early_exit_change)?;
        if !(self.relaxation.is_finite() && self.relaxation > 0.0 && self.relaxation <= 1.0) {
            return Err(ContactError::Settings(format!(
                "relaxation must be in (0, 1], got {}",
                self.relaxation
            )));
        }
        if self.ipm_max_iter == 0 {
            return Err(ContactError::Settings(
                "ipm_max_iter must be >= 1, got 0".into(),
            ));
        }
        if self.max_fixed_point == 0 {
            return Err(ContactError::Settings(
                "max_fixed_point must be >= 1, got 0".into(),
            ));
        }
        if self.slip_tolerance >= 1.0 {
            return Err(ContactError::Settings(format!(
                "slip_tolerance must be < 1, got {}",
                self.slip_tolerance
            )));
        }
        Ok(())
    }
}

/// Result of the normal-only path.
#[derive(Debug, Clone)]
pub struct NormalSolution {
    /// Normal contact forces (compressive ≥ 0), N.
    pub r_n: Vec<f64>,
    /// Gaps with the forces, `gap + W r_n`.
    pub u_n: Vec<f64>,
    /// `true` where the point carries force.
    pub closed: Vec<bool>,
    /// Interior-point iterations.
    pub ipm_iterations: usize,
    /// Wall time in clarabel (setup + solve), s.
    pub cone_seconds: f64,
    /// Wall time in the polish, s.
    pub polish_seconds: f64,
    /// `kkt.max()`, relative.
    pub kkt_residual: f64,
    /// KKT residual by component (friction is 0).
    pub kkt: KktResidual,
    /// Reference magnitudes.
    pub scales: Scales,
}

/// Solves the condensed frictional contact problem of one step.
///
/// `warm`: contact forces of a previous solve (3n, N) whose normal components
/// seed the slip bounds. Errors: [`ContactError::Dimension`] /
/// [`ContactError::Invalid`] / [`ContactError::Settings`] for bad input,
/// [`ContactError::Solver`] when clarabel does not return `Solved`,
/// [`ContactError::NotConverged`] when the fixed point exhausts
/// `max_fixed_point`, [`ContactError::Kkt`] when the own check fails.
pub fn solve(
    problem: &ContactProblem,
    settings: &ContactSettings,
    warm: Option<&[f64]>,
) -> Result<ContactSolution, ContactError> {
    settings.validate()?;
    problem.validate(settings.symmetry_tolerance)?;
    let points = point_rows_3d(problem.friction);
    let warm_rn = match warm {
        Some(r) => {
            check_dims("warm start", r.len(), 3 * points.len())?;
            if let Some(k) = r.iter().position(|v| !v.is_finite()) {
                return Err(ContactError::Invalid(format!(
                    "warm start r[{k}] is not finite"
                )));
            }
            Some(points.iter().map(|p| r[p.n]).collect::<Vec<_>>())
        }
        None => None,
    };
    let out = run(problem.w, problem.b, &points, settings, warm_rn.as_deref())?;
    Ok(ContactSolution {
        r: out.r,
        u: out.u,
        states: out.states,
        fixed_point_iterations: out.cone_programs,
        ipm_iterations: out.ipm_iterations,
        cone_seconds: out.cone_seconds,
        polish_seconds: out.polish_seconds,
        kkt_residual: out.kkt.max(),
        kkt: out.kkt,
        scales: out.scales,
    })
}

/// Normal-only path: min ½ rᵀ W r + gapᵀ r, r ≥ 0 (one nonnegative cone).
pub fn solve_normal(
    problem: &NormalProblem,
    settings: &ContactSettings,
) -> Result<NormalSolution, ContactError> {
    settings.validate()?;
    problem.validate(settings.symmetry_tolerance)?;
    let points = point_rows_normal(problem.gap.len());
    let out = run(problem.w, problem.gap, &points, settings, None)?;
    Ok(NormalSolution {
        closed: out.states.iter().map(|s| s.is_closed()).collect(),
        r_n: out.r,
        u_n: out.u,
        ipm_iterations: out.ipm_iterations,
        cone_seconds: out.cone_seconds,
        polish_seconds: out.polish_seconds,
        kkt_residual: out.kkt.max(),
        kkt: out.kkt,
        scales: out.scales,
    })
}

struct CoreOut {
    cone_seconds: f64,
    polish_seconds: f64,
    r: Vec<f64>,
    u: Vec<f64>,
    states: Vec<ContactState>,
    cone_programs: usize,
    ipm_iterations: usize,
    kkt: KktResidual,
    scales: Scales,
}

/// Coefficients of a Coulomb point (`None` for the other models).
fn coulomb(model: FrictionModel) -> Option<(f64, f64)> {
    match model {
        FrictionModel::Coulomb { mu_s, mu_k } => Some((mu_s, mu_k)),
        _ => None,
    }
}

fn run(
    w: &DMatrix<f64>,
    b: &[f64],
    points: &[PointRows],
    settings: &ContactSettings,
    warm_rn: Option<&[f64]>,
) -> Result<CoreOut, ContactError> {
    let m = b.len();
    let omega = mean_diagonal(w);
    let beta = max_abs(b);
    if points.is_empty() || beta == 0.0 {
        // Nothing pushes the sides together: r = 0 is optimal (W is PSD).
        let r = vec![0.0; m];
        let u = b.to_vec();
        let scales = scales_of(w, b, Some(&u));
        let kkt = kkt_of(points, &r, &u, &scales);
        return Ok(CoreOut {
            r,
            u,
            states: vec![ContactState::Open; points.len()],
            cone_programs: 0,
            ipm_iterations: 0,
            cone_seconds: 0.0,
            polish_seconds: 0.0,
            kkt,
            scales,
        });
    }
    let bt: Vec<f64> = b.iter().map(|v| v / beta).collect();
    let to_scaled_force = omega / beta;
    let unit = Scales {
        displacement: 1.0,
        compliance: 1.0,
        force: 1.0,
    };

    let n = points.len();
    // Current friction coefficient (μ_s, or μ_k once sliding) and bounds s̃.
    let mut mu: Vec<f64> = points
        .iter()
        .map(|p| coulomb(p.model).map_or(0.0, |(s, _)| s))
        .collect();
    let mut sliding = vec![false; n];
    let mut s: Vec<f64> = match warm_rn {
        Some(rn) => (0..n)
            .map(|i| mu[i] * (rn[i] * to_scaled_force).max(0.0))
            .collect(),
        None => vec![0.0; n],
    };
    let friction_iterates = mu.iter().any(|&v| v > 0.0);
    let kinetic = points
        .iter()
        .any(|p| coulomb(p.model).is_some_and(|(mu_s, mu_k)| mu_k < mu_s));

    let mut ipm_iterations = 0usize;
    let mut cone_seconds = 0.0f64;
    let mut polish_seconds = 0.0f64;
    let mut iteration = 0usize;
    let mut previous_states: Option<Vec<ContactState>> = None;
    let mut polished: Option<(Vec<f64>, Vec<ContactState>)> = None;
    let (rt, s_used) = loop {
        iteration += 1;
        let include_t: Vec<bool> = points
            .iter()
            .zip(&s)
            .zip(&mu)
            .map(|((p, &si), &mui)| match p.model {
                FrictionModel::Tied => p.t.is_some(),
                FrictionModel::Coulomb { .. } => {
                    p.t.is_some() && si > 0.0 && si > settings.open_tolerance * mui
                }
                FrictionModel::Frictionless => false,
            })
            .collect();
        let clock = Instant::now();
        let cone = solve_cone(w, omega, &bt, points, &s, &include_t, settings, iteration);
        cone_seconds += clock.elapsed().as_secs_f64();
        let (rt, its) = cone?;
        ipm_iterations += its;
        if !friction_iterates {
            break (rt, s);
        }
        let ut = apply_scaled(w, omega, &bt, &rt);
        let target: Vec<f64> = (0..n).map(|i| mu[i] * rt[points[i].n].max(0.0)).collect();
        let mut diff = 0.0f64;
        let mut size = 0.0f64;
        for i in 0..n {
            diff = diff.max((target[i] - s[i]).abs());
            size = size.max(target[i]);
        }
        let change = diff / (size + 1.0);
        // Early exit: the states repeat, the bounds are close to μ r_n (so a
        // point on its bound could not stick with μ_s) and the polished
        // solution of these states checks out.
        let states = classify(points, &rt, &ut, &s, settings);
        if settings.polish
            && previous_states.as_ref() == Some(&states)
            && (change <= settings.early_exit_change || !kinetic)
        {
            let clock = Instant::now();
            let attempt = polish(w, omega, &bt, points, &rt, &ut, &states, settings);
            polish_seconds += clock.elapsed().as_secs_f64();
            if let Some((rp, sp)) = attempt {
                let up = apply_scaled(w, omega, &bt, &rp);
                if kkt_of(points, &rp, &up, &unit).max() <= settings.polish_tolerance {
                    polished = Some((rp, sp));
                    break (rt, s);
                }
            }
        }
        previous_states = Some(states);
        if change <= settings.tolerance {
            // Converged for the current coefficients: do points reach μ_s?
            let mut new_sliders = false;
            for (i, p) in points.iter().enumerate() {
                let Some((mu_s, mu_k)) = coulomb(p.model) else {
                    continue;
                };
                if sliding[i] || mu_k >= mu_s || !is_closed(rt[p.n], ut[p.n], settings) {
                    continue;
                }
                if at_bound(p, &rt, &ut, s[i], settings) {
                    sliding[i] = true;
                    mu[i] = mu_k;
                    new_sliders = true;
                }
            }
            if !new_sliders {
                break (rt, s);
            }
            for i in 0..n {
                s[i] = mu[i] * rt[points[i].n].max(0.0);
            }
        } else {
            for i in 0..n {
                s[i] += settings.relaxation * (target[i] - s[i]);
            }
        }
        if iteration >= settings.max_fixed_point {
            return Err(ContactError::NotConverged {
                iterations: iteration,
                change,
            });
        }
    };

    // The interior-point answer, cleaned: open points carry no force.
    let ut = apply_scaled(w, omega, &bt, &rt);
    let states = classify(points, &rt, &ut, &s_used, settings);
    let mut rt = rt;
    for (p, st) in points.iter().zip(&states) {
        if *st == ContactState::Open {
            rt[p.n] = 0.0;
            if let (Some([t1, t2]), false) = (p.t, matches!(p.model, FrictionModel::Tied)) {
                rt[t1] = 0.0;
                rt[t2] = 0.0;
            }
        }
    }
    let (rt, states) = match polished {
        Some(x) => x,
        None if settings.polish => {
            let ut = apply_scaled(w, omega, &bt, &rt);
            let k_ipm = kkt_of(points, &rt, &ut, &unit).max();
            let clock = Instant::now();
            let attempt = polish(w, omega, &bt, points, &rt, &ut, &states, settings);
            polish_seconds += clock.elapsed().as_secs_f64();
            match attempt {
                Some((rp, sp)) => {
                    let up = apply_scaled(w, omega, &bt, &rp);
                    if kkt_of(points, &rp, &up, &unit).max() <= k_ipm {
                        (rp, sp)
                    } else {
                        (rt, states)
                    }
                }
                None => (rt, states),
            }
        }
        None => (rt, states),
    };

    let force = beta / omega;
    let r: Vec<f64> = rt.iter().map(|v| v * force).collect();
    let u = apply(w, b, &r);
    if let Some(k) = r.iter().chain(u.iter()).position(|v| !v.is_finite()) {
        return Err(ContactError::Solver {
            status: format!("non-finite result at entry {k}"),
            iteration,
        });
    }
    let scales = scales_of(w, b, Some(&u));
    let kkt = kkt_of(points, &r, &u, &scales);
    if kkt.max().is_nan() || kkt.max() > settings.kkt_tolerance {
        return Err(ContactError::Kkt {
            residual: kkt.max(),
            limit: settings.kkt_tolerance,
        });
    }
    Ok(CoreOut {
        r,
        u,
        states,
        cone_programs: iteration,
        ipm_iterations,
        cone_seconds,
        polish_seconds,
        kkt,
        scales,
    })
}

/// States of an interior-point iterate solved with the bounds `s` (scaled).
fn classify(
    points: &[PointRows],
    rt: &[f64],
    ut: &[f64],
    s: &[f64],
    settings: &ContactSettings,
) -> Vec<ContactState> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if !is_closed(rt[p.n], ut[p.n], settings) {
                return ContactState::Open;
            }
            match p.model {
                FrictionModel::Frictionless => ContactState::Slip,
                FrictionModel::Tied => ContactState::Stick,
                FrictionModel::Coulomb { .. } => {
                    if at_bound(p, rt, ut, s[i], settings) {
                        ContactState::Slip
                    } else {
                        ContactState::Stick
                    }
                }
            }
        })
        .collect()
}

/// Active set of one point in the polish.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Active {
    /// r = 0.
    Open,
    /// Tied point with the normal open: r_n = 0, u_t = 0.
    OpenTied,
    /// u = 0 on all rows of the point.
    Stick,
    /// u_n = 0 and r_t = 0 (frictionless or μ_k = 0).
    SlipFree,
    /// u_n = 0, r_t = μ r_n (cos φ, sin φ) with u_t ∥ −(cos φ, sin φ).
    Slip { mu: f64, phi: f64 },
}

impl Active {
    fn state(self) -> ContactState {
        match self {
            Active::Open | Active::OpenTied => ContactState::Open,
            Active::Stick => ContactState::Stick,
            Active::SlipFree | Active::Slip { .. } => ContactState::Slip,
        }
    }
    /// Unknowns of the point: OpenTied (r_t1, r_t2), Stick (r_t1, r_t2, r_n),
    /// SlipFree (r_n), Slip (r_n, φ).
    fn n_unknowns(self) -> usize {
        match self {
            Active::Open => 0,
            Active::SlipFree => 1,
            Active::OpenTied | Active::Slip { .. } => 2,
            Active::Stick => 3,
        }
    }
}

/// Polish: Newton's method on the equalities of an active set taken from the
/// interior-point iterate (stick u = 0; slip u_n = 0, r_t = μ_k r_n d(φ),
/// u_t × d = 0; open r = 0), then the inequalities are checked and violators
/// switched (r_n < 0 → open, u_n < 0 → closed, ‖r_t‖ > μ_s r_n → slip,
/// u_t·d > 0 → stick) for at most `polish_max_rounds` rounds. Returns the
/// scaled forces and states of the last round, `None` if the Newton systems
/// fail.
#[allow(clippy::too_many_arguments)]
fn polish(
    w: &DMatrix<f64>,
    omega: f64,
    bt: &[f64],
    points: &[PointRows],
    rt: &[f64],
    ut: &[f64],
    states: &[ContactState],
    settings: &ContactSettings,
) -> Option<(Vec<f64>, Vec<ContactState>)> {
    let tol = settings.polish_tolerance;
    // Initial active set and unknowns from the iterate.
    let mut active: Vec<Active> = Vec::with_capacity(points.len());
    let mut x: Vec<Vec<f64>> = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let tied = matches!(p.model, FrictionModel::Tied);
        let a = match (states[i], p.t, p.model) {
            (ContactState::Open, Some(_), _) if tied => Active::OpenTied,
            (ContactState::Open, _, _) => Active::Open,
            (ContactState::Stick, Some(_), _) => Active::Stick,
            (_, Some([t1, t2]), FrictionModel::Coulomb { mu_k, .. }) if mu_k > 0.0 => {
                let phi = if rt[t1].hypot(rt[t2]) > 0.0 {
                    rt[t2].atan2(rt[t1])
                } else {
                    (-ut[t2]).atan2(-ut[t1])
                };
                Active::Slip { mu: mu_k, phi }
            }
            _ => Active::SlipFree,
        };
        active.push(a);
        x.push(initial_unknowns(a, p, rt));
    }
    let mut result = None;
    for _round in 0..settings.polish_max_rounds.max(1) {
        newton(w, omega, bt, points, &active, &mut x, tol)?;
        let r_new = forces(points, &active, &x, bt.len());
        let u_new = apply_scaled(w, omega, bt, &r_new);
        // Check the inequalities, switch the violators.
        let mut changed = false;
        for (i, p) in points.iter().enumerate() {
            let (rn, un) = (r_new[p.n], u_new[p.n]);
            let a = active[i];
            let next = match a {
                Active::Open | Active::OpenTied => {
                    if un < -tol {
                        match (p.model, p.t) {
                            (FrictionModel::Frictionless, _) | (_, None) => Active::SlipFree,
                            _ => Active::Stick,
                        }
                    } else {
                        a
                    }
                }
                _ if rn < -tol => {
                    if a == Active::Stick && matches!(p.model, FrictionModel::Tied) {
                        Active::OpenTied
                    } else {
                        Active::Open
                    }
                }
                Active::Stick => match (p.model, p.t) {
                    (FrictionModel::Coulomb { mu_s, mu_k }, Some([t1, t2])) => {
                        let rtn = r_new[t1].hypot(r_new[t2]);
                        if rtn > mu_s * rn + tol {
                            if mu_k > 0.0 {
                                Active::Slip {
                                    mu: mu_k,
                                    phi: r_new[t2].atan2(r_new[t1]),
                                }
                            } else {
                                Active::SlipFree
                            }
                        } else {
                            a
                        }
                    }
                    _ => a,
                },
                Active::Slip { phi, .. } => {
                    let Some([t1, t2]) = p.t else { continue };
                    if u_new[t1] * phi.cos() + u_new[t2] * phi.sin() > tol {
                        Active::Stick // slipping along the friction force: it sticks
                    } else {
                        a
                    }
                }
                Active::SlipFree => a,
            };
            if next != a {
                changed = true;
                active[i] = next;
                x[i] = initial_unknowns(next, p, &r_new);
            }
        }
        let st: Vec<ContactState> = active.iter().map(|a| a.state()).collect();
        let done = !changed;
        result = Some((r_new, st));
        if done {
            break;
        }
    }
    result
}

fn initial_unknowns(a: Active, p: &PointRows, r: &[f64]) -> Vec<f64> {
    let rn = r[p.n].max(0.0);
    match (a, p.t) {
        (Active::Open, _) => vec![],
        (Active::OpenTied, Some([t1, t2])) => vec![r[t1], r[t2]],
        (Active::Stick, Some([t1, t2])) => vec![r[t1], r[t2], rn],
        (Active::Slip { phi, .. }, _) => vec![rn, phi],
        (Active::SlipFree, _) => vec![rn],
        _ => vec![0.0; a.n_unknowns()],
    }
}

/// Forces (scaled) of the unknowns.
fn forces(points: &[PointRows], active: &[Active], x: &[Vec<f64>], m: usize) -> Vec<f64> {
    let mut r = vec![0.0; m];
    for ((p, a), xi) in points.iter().zip(active).zip(x) {
        match (*a, p.t) {
            (Active::OpenTied, Some([t1, t2])) => {
                r[t1] = xi[0];
                r[t2] = xi[1];
            }
            (Active::Stick, Some([t1, t2])) => {
                r[t1] = xi[0];
                r[t2] = xi[1];
                r[p.n] = xi[2];
            }
            (Active::Slip { mu, .. }, Some([t1, t2])) => {
                r[p.n] = xi[0];
                r[t1] = mu * xi[0] * xi[1].cos();
                r[t2] = mu * xi[0] * xi[1].sin();
            }
            (Active::SlipFree, _) => r[p.n] = xi[0],
            _ => {}
        }
    }
    r
}

/// Newton's method for the equalities of a fixed active set (dense LU).
fn newton(
    w: &DMatrix<f64>,
    omega: f64,
    bt: &[f64],
    points: &[PointRows],
    active: &[Active],
    x: &mut [Vec<f64>],
    tol: f64,
) -> Option<()> {
    use faer::prelude::Solve;
    let m = bt.len();
    let data = w.as_slice();
    let inv = 1.0 / omega;
    // Unknown index → (point, local index); derivative of r w.r.t. it.
    let mut owner: Vec<(usize, usize)> = Vec::new();
    for (i, a) in active.iter().enumerate() {
        for k in 0..a.n_unknowns() {
            owner.push((i, k));
        }
    }
    let nz = owner.len();
    if nz == 0 {
        return Some(());
    }
    let dr = |i: usize, k: usize, xi: &[f64]| -> Vec<(usize, f64)> {
        let p = &points[i];
        match (active[i], p.t) {
            (Active::OpenTied, Some(t)) => vec![(t[k], 1.0)],
            (Active::Stick, Some([t1, t2])) => vec![([t1, t2, p.n][k], 1.0)],
            (Active::Slip { mu, .. }, Some([t1, t2])) => {
                let (c, s) = (xi[1].cos(), xi[1].sin());
                if k == 0 {
                    vec![(p.n, 1.0), (t1, mu * c), (t2, mu * s)]
                } else {
                    vec![(t1, -mu * xi[0] * s), (t2, mu * xi[0] * c)]
                }
            }
            _ => vec![(p.n, 1.0)],
        }
    };
    let mut last = f64::INFINITY;
    let mut slow = 0usize;
    for _ in 0..30 {
        let r = forces(points, active, x, m);
        let u = apply_scaled(w, omega, bt, &r);
        // Residual rows: (kind, point); kind 0 = u row, 1 = slip alignment.
        let mut rows: Vec<(usize, usize, usize)> = Vec::with_capacity(nz); // (point, row, kind)
        let mut f: Vec<f64> = Vec::with_capacity(nz);
        for (i, (p, a)) in points.iter().zip(active).enumerate() {
            match (*a, p.t) {
                (Active::OpenTied, Some([t1, t2])) => {
                    for row in [t1, t2] {
                        rows.push((i, row, 0));
                        f.push(u[row]);
                    }
                }
                (Active::Stick, Some([t1, t2])) => {
                    for row in [t1, t2, p.n] {
                        rows.push((i, row, 0));
                        f.push(u[row]);
                    }
                }
                (Active::Slip { .. }, Some([t1, t2])) => {
                    rows.push((i, p.n, 0));
                    f.push(u[p.n]);
                    let phi = x[i][1];
                    rows.push((i, t1, 1));
                    f.push(u[t1] * phi.sin() - u[t2] * phi.cos());
                    let _ = t2;
                }
                (Active::Open, _) => {}
                _ => {
                    rows.push((i, p.n, 0));
                    f.push(u[p.n]);
                }
            }
        }
        let norm = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !norm.is_finite() {
            return None;
        }
        if norm <= 1e-3 * tol || (norm >= 0.5 * last && norm <= tol) {
            return Some(());
        }
        if norm >= 0.5 * last {
            // not converging quadratically: stop after a few such steps and
            // let the caller's KKT comparison judge the iterate
            slow += 1;
            if slow >= 3 {
                return Some(());
            }
        }
        last = norm;
        // Jacobian.
        let cols: Vec<Vec<(usize, f64)>> = owner.iter().map(|&(i, k)| dr(i, k, &x[i])).collect();
        let jac = faer::Mat::<f64>::from_fn(nz, nz, |e, z| {
            let (i, row, kind) = rows[e];
            let wu = |rr: usize| -> f64 {
                cols[z]
                    .iter()
                    .map(|&(c, v)| v * data[c * m + rr])
                    .sum::<f64>()
                    * inv
            };
            if kind == 0 {
                wu(row)
            } else {
                let p = &points[i];
                let Some([t1, t2]) = p.t else { return 0.0 };
                let phi = x[i][1];
                let (c, s) = (phi.cos(), phi.sin());
                let mut v = s * wu(t1) - c * wu(t2);
                if owner[z] == (i, 1) {
                    v += u[t1] * c + u[t2] * s;
                }
                v
            }
        });
        let mut rhs = faer::Mat::<f64>::from_fn(nz, 1, |e, _| -f[e]);
        jac.partial_piv_lu().solve_in_place(&mut rhs);
        for (z, &(i, k)) in owner.iter().enumerate() {
            let d = rhs[(z, 0)];
            if !d.is_finite() {
                return None;
            }
            x[i][k] += d;
        }
    }
    Some(())
}

/// Closed when the force is the larger member of the complementary pair
/// (both scaled) and above the open tolerance.
fn is_closed(rn: f64, un: f64, settings: &ContactSettings) -> bool {
    rn > settings.open_tolerance.max(un)
}

/// Tangential force on its bound (scaled quantities).
fn at_bound(p: &PointRows, rt: &[f64], ut: &[f64], bound: f64, settings: &ContactSettings) -> bool {
    let Some([t1, t2]) = p.t else { return true };
    let rnorm = rt[t1].hypot(rt[t2]);
    let unorm = ut[t1].hypot(ut[t2]);
    bound - rnorm <= (settings.slip_tolerance * bound).max(unorm)
}

/// ũ = b̃ + W̃ r̃ with W̃ = W/ω.
fn apply_scaled(w: &DMatrix<f64>, omega: f64, bt: &[f64], rt: &[f64]) -> Vec<f64> {
    let wr = apply(w, &vec![0.0; bt.len()], rt);
    bt.iter().zip(wr).map(|(b, v)| b + v / omega).collect()
}

/// One cone program for the bounds `s` (scaled). Returns r̃ (all rows, zeros
/// for left-out variables) and the interior-point iterations.
#[allow(clippy::too_many_arguments)]
fn solve_cone(
    w: &DMatrix<f64>,
    omega: f64,
    bt: &[f64],
    points: &[PointRows],
    s: &[f64],
    include_t: &[bool],
    settings: &ContactSettings,
    iteration: usize,
) -> Result<(Vec<f64>, usize), ContactError> {
    let m = bt.len();
    let n = points.len();
    // Variables (rows of W) and their constraint rows.
    let mut var_rows: Vec<usize> = Vec::with_capacity(3 * n);
    let mut var_con: Vec<Option<usize>> = Vec::with_capacity(3 * n);
    let mut b_con: Vec<f64> = vec![0.0; n];
    let mut cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(n)];
    for (k, p) in points.iter().enumerate() {
        var_rows.push(p.n);
        var_con.push(Some(k));
        if !include_t[k] {
            continue;
        }
        let Some([t1, t2]) = p.t else { continue };
        match p.model {
            FrictionModel::Coulomb { .. } => {
                let base = b_con.len();
                b_con.extend_from_slice(&[s[k], 0.0, 0.0]);
                cones.push(SecondOrderConeT(3));
                var_rows.push(t1);
                var_con.push(Some(base + 1));
                var_rows.push(t2);
                var_con.push(Some(base + 2));
            }
            FrictionModel::Tied => {
                var_rows.push(t1);
                var_con.push(None);
                var_rows.push(t2);
                var_con.push(None);
            }
            FrictionModel::Frictionless => {}
        }
    }
    let nv = var_rows.len();
    let n_con = b_con.len();

    // P = triu(sym(W)/ω) over the kept variables.
    let data = w.as_slice();
    let inv = 0.5 / omega;
    let mut colptr = Vec::with_capacity(nv + 1);
    let mut rowval = Vec::with_capacity(nv * (nv + 1) / 2);
    let mut nzval = Vec::with_capacity(nv * (nv + 1) / 2);
    colptr.push(0);
    for (c, &rc) in var_rows.iter().enumerate() {
        for (a, &ra) in var_rows.iter().enumerate().take(c + 1) {
            let v = (data[rc * m + ra] + data[ra * m + rc]) * inv;
            if v != 0.0 {
                rowval.push(a);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let p_mat = CscMatrix::new(nv, nv, colptr, rowval, nzval);
    let q: Vec<f64> = var_rows.iter().map(|&r| bt[r]).collect();

    // A: −1 at (constraint row, variable) so that s = b − A x = (r_n, (s_i, r_t)).
    let mut colptr = Vec::with_capacity(nv + 1);
    let mut rowval = Vec::with_capacity(nv);
    let mut nzval = Vec::with_capacity(nv);
    colptr.push(0);
    for con in &var_con {
        if let Some(row) = con {
            rowval.push(*row);
            nzval.push(-1.0);
        }
        colptr.push(rowval.len());
    }
    let a_mat = CscMatrix::new(n_con, nv, colptr, rowval, nzval);

    let cl_settings = DefaultSettings::<f64> {
        verbose: false,
        max_iter: settings.ipm_max_iter,
        tol_gap_abs: settings.ipm_tolerance,
        tol_gap_rel: settings.ipm_tolerance,
        tol_feas: settings.ipm_tolerance,
        ..DefaultSettings::default()
    };
    let mut solver =
        DefaultSolver::new(&p_mat, &q, &a_mat, &b_con, &cones, cl_settings).map_err(|e| {
            ContactError::Solver {
                status: format!("setup failed: {e}"),
                iteration,
            }
        })?;
    solver.solve();
    let sol = &solver.solution;
    let ok = match sol.status {
        SolverStatus::Solved => true,
        SolverStatus::AlmostSolved => settings.accept_almost_solved,
        _ => false,
    };
    if !ok {
        return Err(ContactError::Solver {
            status: format!("{:?}", sol.status),
            iteration,
        });
    }
    let mut rt = vec![0.0; m];
    for (v, &row) in var_rows.iter().enumerate() {
        let x = sol.x.get(v).copied().unwrap_or(f64::NAN);
        if !x.is_finite() {
            return Err(ContactError::Solver {
                status: format!("{:?} with a non-finite force", sol.status),
                iteration,
            });
        }
        rt[row] = x;
    }
    Ok((rt, sol.iterations as usize))
}
