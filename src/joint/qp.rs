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
    ContactError, ContactProblem, ContactSolution, ContactState, FrictionModel, NormalProblem,
    PointRows, Scales,
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
    run(problem.w, problem.b, &points, settings, warm_rn.as_deref())
}

/// Normal-only path: min ½ rᵀ W r + gapᵀ r, r ≥ 0 (one nonnegative cone).
/// The solution has one row per point: `r` the normal forces, `u` the gaps
/// with them, closed points in state `Slip` (they are frictionless).
pub fn solve_normal(
    problem: &NormalProblem,
    settings: &ContactSettings,
) -> Result<ContactSolution, ContactError> {
    settings.validate()?;
    problem.validate(settings.symmetry_tolerance)?;
    let points = point_rows_normal(problem.gap.len());
    run(problem.w, problem.gap, &points, settings, None)
}

/// Coefficients of a Coulomb point (`None` for the other models).
fn coulomb(model: FrictionModel) -> Option<(f64, f64)> {
    match model {
        FrictionModel::Coulomb { mu_s, mu_k } => Some((mu_s, mu_k)),
        _ => None,
    }
}

/// The problem in scaled variables (module doc): W̃ = W/ω, b̃ = b/β, with
/// the points and settings every step of the solve reads.
struct Scaled<'a> {
    w: &'a DMatrix<f64>,
    omega: f64,
    bt: Vec<f64>,
    points: &'a [PointRows],
    settings: &'a ContactSettings,
}

/// Scales of the scaled problem: its KKT residual is already relative.
const UNIT: Scales = Scales {
    displacement: 1.0,
    compliance: 1.0,
    force: 1.0,
};

/// Work counters of one solve.
#[derive(Default)]
struct Counters {
    /// Cone programs solved.
    iteration: usize,
    ipm_iterations: usize,
    cone_seconds: f64,
    polish_seconds: f64,
}

/// The friction fixed point: per point the current coefficient (μ_s, or μ_k
/// once sliding) and the slip bounds s̃ of the next cone program.
struct FixedPoint {
    mu: Vec<f64>,
    sliding: Vec<bool>,
    s: Vec<f64>,
    /// Some point has friction, so the bounds iterate at all.
    friction_iterates: bool,
    /// Some point has μ_k < μ_s.
    kinetic: bool,
    previous_states: Option<Vec<ContactState>>,
    /// The polished solution that ended the iteration early.
    polished: Option<(Vec<f64>, Vec<ContactState>)>,
    counters: Counters,
}

fn run(
    w: &DMatrix<f64>,
    b: &[f64],
    points: &[PointRows],
    settings: &ContactSettings,
    warm_rn: Option<&[f64]>,
) -> Result<ContactSolution, ContactError> {
    let omega = mean_diagonal(w);
    let beta = max_abs(b);
    if points.is_empty() || beta == 0.0 {
        // Nothing pushes the sides together: r = 0 is optimal (W is PSD).
        let (r, u) = (vec![0.0; b.len()], b.to_vec());
        let states = vec![ContactState::Open; points.len()];
        return Ok(solution(w, b, points, r, u, states, Counters::default()));
    }
    let sc = Scaled {
        w,
        omega,
        bt: b.iter().map(|v| v / beta).collect(),
        points,
        settings,
    };
    let mut fp = FixedPoint::new(points, warm_rn, omega / beta);
    let (rt, s_used) = fp.iterate(&sc)?;
    let (rt, states) = match fp.polished.take() {
        Some(x) => x,
        None => sc.final_answer(rt, &s_used, &mut fp.counters.polish_seconds),
    };

    let force = beta / omega;
    let r: Vec<f64> = rt.iter().map(|v| v * force).collect();
    let u = apply(w, b, &r);
    if let Some(k) = r.iter().chain(u.iter()).position(|v| !v.is_finite()) {
        return Err(ContactError::Solver {
            status: format!("non-finite result at entry {k}"),
            iteration: fp.counters.iteration,
        });
    }
    let sol = solution(w, b, points, r, u, states, fp.counters);
    if sol.kkt_residual.is_nan() || sol.kkt_residual > settings.kkt_tolerance {
        return Err(ContactError::Kkt {
            residual: sol.kkt_residual,
            limit: settings.kkt_tolerance,
        });
    }
    Ok(sol)
}

/// The solution with forces `r` (N) and u = b + W r, with the own KKT check.
fn solution(
    w: &DMatrix<f64>,
    b: &[f64],
    points: &[PointRows],
    r: Vec<f64>,
    u: Vec<f64>,
    states: Vec<ContactState>,
    counters: Counters,
) -> ContactSolution {
    let scales = scales_of(w, b, Some(&u));
    let kkt = kkt_of(points, &r, &u, &scales);
    ContactSolution {
        r,
        u,
        states,
        fixed_point_iterations: counters.iteration,
        ipm_iterations: counters.ipm_iterations,
        cone_seconds: counters.cone_seconds,
        polish_seconds: counters.polish_seconds,
        kkt_residual: kkt.max(),
        kkt,
        scales,
    }
}

impl FixedPoint {
    /// μ_s everywhere; the bounds from the warm start's normal forces
    /// (`to_scaled_force` = ω/β), else 0 (the first program is the
    /// normal-only QP).
    fn new(points: &[PointRows], warm_rn: Option<&[f64]>, to_scaled_force: f64) -> Self {
        let n = points.len();
        let mu: Vec<f64> = points
            .iter()
            .map(|p| coulomb(p.model).map_or(0.0, |(s, _)| s))
            .collect();
        let s: Vec<f64> = match warm_rn {
            Some(rn) => (0..n)
                .map(|i| mu[i] * (rn[i] * to_scaled_force).max(0.0))
                .collect(),
            None => vec![0.0; n],
        };
        let friction_iterates = mu.iter().any(|&v| v > 0.0);
        let kinetic = points
            .iter()
            .any(|p| coulomb(p.model).is_some_and(|(mu_s, mu_k)| mu_k < mu_s));
        FixedPoint {
            mu,
            sliding: vec![false; n],
            s,
            friction_iterates,
            kinetic,
            previous_states: None,
            polished: None,
            counters: Counters::default(),
        }
    }

    /// Cone programs until the bounds s̃ stop changing (static coefficients
    /// first, then kinetic for the points that reach their static bound), or
    /// until a polished solution of repeating states checks out. Returns the
    /// last iterate r̃ and the bounds it was solved with.
    fn iterate(&mut self, sc: &Scaled) -> Result<(Vec<f64>, Vec<f64>), ContactError> {
        let settings = sc.settings;
        let n = sc.points.len();
        loop {
            let rt = self.cone_program(sc)?;
            if !self.friction_iterates {
                return Ok((rt, std::mem::take(&mut self.s)));
            }
            let ut = sc.u(&rt);
            let target: Vec<f64> = (0..n)
                .map(|i| self.mu[i] * rt[sc.points[i].n].max(0.0))
                .collect();
            let mut diff = 0.0f64;
            let mut size = 0.0f64;
            for (&t, &si) in target.iter().zip(&self.s) {
                diff = diff.max((t - si).abs());
                size = size.max(t);
            }
            let change = diff / (size + 1.0);
            let states = sc.classify(&rt, &ut, &self.s);
            if self.early_exit(sc, &rt, &ut, &states, change) {
                return Ok((rt, std::mem::take(&mut self.s)));
            }
            self.previous_states = Some(states);
            if change <= settings.tolerance {
                // Converged for the current coefficients: do points reach μ_s?
                if !self.start_sliding(sc, &rt, &ut) {
                    return Ok((rt, std::mem::take(&mut self.s)));
                }
                for i in 0..n {
                    self.s[i] = self.mu[i] * rt[sc.points[i].n].max(0.0);
                }
            } else {
                for (si, &t) in self.s.iter_mut().zip(&target) {
                    *si += settings.relaxation * (t - *si);
                }
            }
            if self.counters.iteration >= settings.max_fixed_point {
                return Err(ContactError::NotConverged {
                    iterations: self.counters.iteration,
                    change,
                });
            }
        }
    }

    /// One cone program for the current bounds, counted and timed.
    fn cone_program(&mut self, sc: &Scaled) -> Result<Vec<f64>, ContactError> {
        self.counters.iteration += 1;
        let include_t: Vec<bool> = sc
            .points
            .iter()
            .zip(&self.s)
            .zip(&self.mu)
            .map(|((p, &si), &mui)| match p.model {
                FrictionModel::Tied => p.t.is_some(),
                FrictionModel::Coulomb { .. } => {
                    p.t.is_some() && si > 0.0 && si > sc.settings.open_tolerance * mui
                }
                FrictionModel::Frictionless => false,
            })
            .collect();
        let clock = Instant::now();
        let cone = sc.solve_cone(&self.s, &include_t, self.counters.iteration);
        self.counters.cone_seconds += clock.elapsed().as_secs_f64();
        let (rt, its) = cone?;
        self.counters.ipm_iterations += its;
        Ok(rt)
    }

    /// Early exit: the states repeat, the bounds are close to μ r_n (so a
    /// point on its bound could not stick with μ_s) and the polished solution
    /// of these states checks out; it is kept in `polished`.
    fn early_exit(
        &mut self,
        sc: &Scaled,
        rt: &[f64],
        ut: &[f64],
        states: &[ContactState],
        change: f64,
    ) -> bool {
        let settings = sc.settings;
        if !(settings.polish
            && self.previous_states.as_deref() == Some(states)
            && (change <= settings.early_exit_change || !self.kinetic))
        {
            return false;
        }
        let clock = Instant::now();
        let attempt = sc.polish(rt, ut, states);
        self.counters.polish_seconds += clock.elapsed().as_secs_f64();
        if let Some((rp, sp)) = attempt {
            let up = sc.u(&rp);
            if kkt_of(sc.points, &rp, &up, &UNIT).max() <= settings.polish_tolerance {
                self.polished = Some((rp, sp));
                return true;
            }
        }
        false
    }

    /// Closed Coulomb points whose tangential force is on its static bound
    /// start to slide with μ_k; `true` when any did.
    fn start_sliding(&mut self, sc: &Scaled, rt: &[f64], ut: &[f64]) -> bool {
        let mut new_sliders = false;
        for (i, p) in sc.points.iter().enumerate() {
            let Some((mu_s, mu_k)) = coulomb(p.model) else {
                continue;
            };
            if self.sliding[i] || mu_k >= mu_s || !is_closed(rt[p.n], ut[p.n], sc.settings) {
                continue;
            }
            if at_bound(p, rt, ut, self.s[i], sc.settings) {
                self.sliding[i] = true;
                self.mu[i] = mu_k;
                new_sliders = true;
            }
        }
        new_sliders
    }
}

impl Scaled<'_> {
    /// ũ = b̃ + W̃ r̃ with W̃ = W/ω.
    fn u(&self, rt: &[f64]) -> Vec<f64> {
        let wr = apply(self.w, &vec![0.0; self.bt.len()], rt);
        self.bt
            .iter()
            .zip(wr)
            .map(|(b, v)| b + v / self.omega)
            .collect()
    }

    /// The interior-point answer `rt` (solved with the bounds `s`), cleaned
    /// (open points carry no force), then replaced by its polish when that
    /// has a KKT residual no larger.
    fn final_answer(
        &self,
        rt: Vec<f64>,
        s: &[f64],
        polish_seconds: &mut f64,
    ) -> (Vec<f64>, Vec<ContactState>) {
        let ut = self.u(&rt);
        let states = self.classify(&rt, &ut, s);
        let mut rt = rt;
        for (p, st) in self.points.iter().zip(&states) {
            if *st == ContactState::Open {
                rt[p.n] = 0.0;
                if let (Some([t1, t2]), false) = (p.t, matches!(p.model, FrictionModel::Tied)) {
                    rt[t1] = 0.0;
                    rt[t2] = 0.0;
                }
            }
        }
        if !self.settings.polish {
            return (rt, states);
        }
        let ut = self.u(&rt);
        let k_ipm = kkt_of(self.points, &rt, &ut, &UNIT).max();
        let clock = Instant::now();
        let attempt = self.polish(&rt, &ut, &states);
        *polish_seconds += clock.elapsed().as_secs_f64();
        match attempt {
            Some((rp, sp)) => {
                let up = self.u(&rp);
                if kkt_of(self.points, &rp, &up, &UNIT).max() <= k_ipm {
                    (rp, sp)
                } else {
                    (rt, states)
                }
            }
            None => (rt, states),
        }
    }

    /// States of an interior-point iterate solved with the bounds `s`.
    fn classify(&self, rt: &[f64], ut: &[f64], s: &[f64]) -> Vec<ContactState> {
        self.points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if !is_closed(rt[p.n], ut[p.n], self.settings) {
                    return ContactState::Open;
                }
                match p.model {
                    FrictionModel::Frictionless => ContactState::Slip,
                    FrictionModel::Tied => ContactState::Stick,
                    FrictionModel::Coulomb { .. } => {
                        if at_bound(p, rt, ut, s[i], self.settings) {
                            ContactState::Slip
                        } else {
                            ContactState::Stick
                        }
                    }
                }
            })
            .collect()
    }
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

    /// The active set of a point of the interior-point iterate in state `st`.
    fn of_iterate(st: ContactState, p: &PointRows, rt: &[f64], ut: &[f64]) -> Active {
        let tied = matches!(p.model, FrictionModel::Tied);
        match (st, p.t, p.model) {
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
        }
    }

    /// The active set after the Newton solve gave forces `r` and
    /// displacements `u`: a violated inequality switches it (r_n < 0 → open,
    /// u_n < 0 → closed, ‖r_t‖ > μ_s r_n → slip, slipping along the friction
    /// force → stick), by more than `tol`.
    fn switched(self, p: &PointRows, r: &[f64], u: &[f64], tol: f64) -> Active {
        let (rn, un) = (r[p.n], u[p.n]);
        match self {
            Active::Open | Active::OpenTied => {
                if un < -tol {
                    match (p.model, p.t) {
                        (FrictionModel::Frictionless, _) | (_, None) => Active::SlipFree,
                        _ => Active::Stick,
                    }
                } else {
                    self
                }
            }
            _ if rn < -tol => {
                if self == Active::Stick && matches!(p.model, FrictionModel::Tied) {
                    Active::OpenTied
                } else {
                    Active::Open
                }
            }
            Active::Stick => match (p.model, p.t) {
                (FrictionModel::Coulomb { mu_s, mu_k }, Some([t1, t2])) => {
                    let rtn = r[t1].hypot(r[t2]);
                    if rtn > mu_s * rn + tol {
                        if mu_k > 0.0 {
                            Active::Slip {
                                mu: mu_k,
                                phi: r[t2].atan2(r[t1]),
                            }
                        } else {
                            Active::SlipFree
                        }
                    } else {
                        self
                    }
                }
                _ => self,
            },
            Active::Slip { phi, .. } => {
                let Some([t1, t2]) = p.t else { return self };
                if u[t1] * phi.cos() + u[t2] * phi.sin() > tol {
                    Active::Stick // slipping along the friction force: it sticks
                } else {
                    self
                }
            }
            Active::SlipFree => self,
        }
    }
}

impl Scaled<'_> {
    /// Polish: Newton's method on the equalities of an active set taken from
    /// the interior-point iterate (stick u = 0; slip u_n = 0, r_t = μ_k r_n
    /// d(φ), u_t × d = 0; open r = 0), then the inequalities are checked and
    /// violators switched ([`Active::switched`]) for at most
    /// `polish_max_rounds` rounds. Returns the scaled forces and states of the
    /// last round, `None` if the Newton systems fail.
    fn polish(
        &self,
        rt: &[f64],
        ut: &[f64],
        states: &[ContactState],
    ) -> Option<(Vec<f64>, Vec<ContactState>)> {
        let tol = self.settings.polish_tolerance;
        let mut active: Vec<Active> = Vec::with_capacity(self.points.len());
        let mut x: Vec<Vec<f64>> = Vec::with_capacity(self.points.len());
        for (i, p) in self.points.iter().enumerate() {
            let a = Active::of_iterate(states[i], p, rt, ut);
            active.push(a);
            x.push(initial_unknowns(a, p, rt));
        }
        let mut result = None;
        for _round in 0..self.settings.polish_max_rounds.max(1) {
            self.newton(&active, &mut x, tol)?;
            let r_new = forces(self.points, &active, &x, self.bt.len());
            let u_new = self.u(&r_new);
            let mut changed = false;
            for (i, p) in self.points.iter().enumerate() {
                let next = active[i].switched(p, &r_new, &u_new, tol);
                if next != active[i] {
                    changed = true;
                    active[i] = next;
                    x[i] = initial_unknowns(next, p, &r_new);
                }
            }
            let st: Vec<ContactState> = active.iter().map(|a| a.state()).collect();
            result = Some((r_new, st));
            if !changed {
                break;
            }
        }
        result
    }

    /// Newton's method for the equalities of a fixed active set (dense LU).
    /// Stops at a residual ≤ 1e-3·`tol`, or ≤ `tol` once the convergence is
    /// no longer quadratic, or after three slow steps (the caller's KKT
    /// comparison judges the iterate); `None` when it blows up.
    fn newton(&self, active: &[Active], x: &mut [Vec<f64>], tol: f64) -> Option<()> {
        use faer::prelude::Solve;
        // Unknown index → (point, local index).
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
        let mut last = f64::INFINITY;
        let mut slow = 0usize;
        for _ in 0..30 {
            let r = forces(self.points, active, x, self.bt.len());
            let u = self.u(&r);
            let (rows, f) = self.residual(active, x, &u);
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
            let jac = self.jacobian(active, x, &owner, &rows, &u);
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

    /// The equalities of the active set at displacements `u`: per row
    /// (point, row of u, kind) with kind 0 = u row, 1 = slip alignment
    /// u_t × (cos φ, sin φ), and the residual values.
    fn residual(
        &self,
        active: &[Active],
        x: &[Vec<f64>],
        u: &[f64],
    ) -> (Vec<(usize, usize, usize)>, Vec<f64>) {
        let mut rows: Vec<(usize, usize, usize)> = Vec::new();
        let mut f: Vec<f64> = Vec::new();
        for (i, (p, a)) in self.points.iter().zip(active).enumerate() {
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
                }
                (Active::Open, _) => {}
                _ => {
                    rows.push((i, p.n, 0));
                    f.push(u[p.n]);
                }
            }
        }
        (rows, f)
    }

    /// Jacobian of the residual rows with respect to the unknowns `owner`
    /// (W̃ times ∂r/∂x, plus ∂/∂φ of the slip alignment).
    fn jacobian(
        &self,
        active: &[Active],
        x: &[Vec<f64>],
        owner: &[(usize, usize)],
        rows: &[(usize, usize, usize)],
        u: &[f64],
    ) -> faer::Mat<f64> {
        let m = self.bt.len();
        let data = self.w.as_slice();
        let inv = 1.0 / self.omega;
        let cols: Vec<Vec<(usize, f64)>> = owner
            .iter()
            .map(|&(i, k)| force_derivative(&self.points[i], active[i], k, &x[i]))
            .collect();
        let nz = owner.len();
        faer::Mat::<f64>::from_fn(nz, nz, |e, z| {
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
                let p = &self.points[i];
                let Some([t1, t2]) = p.t else { return 0.0 };
                let phi = x[i][1];
                let (c, s) = (phi.cos(), phi.sin());
                let mut v = s * wu(t1) - c * wu(t2);
                if owner[z] == (i, 1) {
                    v += u[t1] * c + u[t2] * s;
                }
                v
            }
        })
    }

    /// One cone program for the bounds `s` (scaled). Returns r̃ (all rows,
    /// zeros for left-out variables) and the interior-point iterations.
    fn solve_cone(
        &self,
        s: &[f64],
        include_t: &[bool],
        iteration: usize,
    ) -> Result<(Vec<f64>, usize), ContactError> {
        let settings = self.settings;
        let v = ConeVariables::new(self.points, s, include_t);
        let p_mat = self.p_matrix(&v.rows);
        let q: Vec<f64> = v.rows.iter().map(|&r| self.bt[r]).collect();
        let a_mat = v.a_matrix();
        let cl_settings = DefaultSettings::<f64> {
            verbose: false,
            max_iter: settings.ipm_max_iter,
            tol_gap_abs: settings.ipm_tolerance,
            tol_gap_rel: settings.ipm_tolerance,
            tol_feas: settings.ipm_tolerance,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p_mat, &q, &a_mat, &v.b_con, &v.cones, cl_settings)
            .map_err(|e| ContactError::Solver {
                status: format!("setup failed: {e}"),
                iteration,
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
        let mut rt = vec![0.0; self.bt.len()];
        for (k, &row) in v.rows.iter().enumerate() {
            let x = sol.x.get(k).copied().unwrap_or(f64::NAN);
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

    /// P = triu(sym(W)/ω) over the kept variables (their rows of W).
    fn p_matrix(&self, var_rows: &[usize]) -> CscMatrix<f64> {
        let m = self.bt.len();
        let nv = var_rows.len();
        let data = self.w.as_slice();
        let inv = 0.5 / self.omega;
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
        CscMatrix::new(nv, nv, colptr, rowval, nzval)
    }
}

/// The variables of one cone program: the row of W each one is, its
/// constraint row (`None` for a free tied tangential force), and the cones
/// with their constant vector.
struct ConeVariables {
    rows: Vec<usize>,
    con: Vec<Option<usize>>,
    b_con: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
}

impl ConeVariables {
    /// Every normal in one nonnegative cone; the tangential forces of a
    /// Coulomb point with `include_t` in an SOC (s̃_i, r̃_t) with its bound,
    /// those of a tied point free.
    fn new(points: &[PointRows], s: &[f64], include_t: &[bool]) -> Self {
        let n = points.len();
        let mut rows: Vec<usize> = Vec::with_capacity(3 * n);
        let mut con: Vec<Option<usize>> = Vec::with_capacity(3 * n);
        let mut b_con: Vec<f64> = vec![0.0; n];
        let mut cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(n)];
        for (k, p) in points.iter().enumerate() {
            rows.push(p.n);
            con.push(Some(k));
            if !include_t[k] {
                continue;
            }
            let Some([t1, t2]) = p.t else { continue };
            match p.model {
                FrictionModel::Coulomb { .. } => {
                    let base = b_con.len();
                    b_con.extend_from_slice(&[s[k], 0.0, 0.0]);
                    cones.push(SecondOrderConeT(3));
                    rows.push(t1);
                    con.push(Some(base + 1));
                    rows.push(t2);
                    con.push(Some(base + 2));
                }
                FrictionModel::Tied => {
                    rows.push(t1);
                    con.push(None);
                    rows.push(t2);
                    con.push(None);
                }
                FrictionModel::Frictionless => {}
            }
        }
        ConeVariables {
            rows,
            con,
            b_con,
            cones,
        }
    }

    /// A: −1 at (constraint row, variable) so that s = b − A x = (r_n, (s_i, r_t)).
    fn a_matrix(&self) -> CscMatrix<f64> {
        let nv = self.rows.len();
        let mut colptr = Vec::with_capacity(nv + 1);
        let mut rowval = Vec::with_capacity(nv);
        let mut nzval = Vec::with_capacity(nv);
        colptr.push(0);
        for con in &self.con {
            if let Some(row) = con {
                rowval.push(*row);
                nzval.push(-1.0);
            }
            colptr.push(rowval.len());
        }
        CscMatrix::new(self.b_con.len(), nv, colptr, rowval, nzval)
    }
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

/// ∂r/∂x_k of a point's force rows: (row, derivative) pairs.
fn force_derivative(p: &PointRows, a: Active, k: usize, xi: &[f64]) -> Vec<(usize, f64)> {
    match (a, p.t) {
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
