//! The joint problem of one mechanical step, in the unknowns of
//! [`LiveSystem`](super::live::LiveSystem): node displacements ũ and the
//! relative displacement d = R(u_b − u_a) of every live pair.
//!
//! The step's equilibrium is
//!
//! ```text
//! K̃ x = f̃ + E(r − r_old)          (E selects the d rows)
//! ```
//!
//! with r the total force on side B of each pair in its local frame. Per pair:
//! - open: r = 0, the gap g = g_old + x_n stays ≥ 0;
//! - closed (stick): x_n = −g_old (gap exactly 0) and x_t = 0, r from the
//!   equilibrium rows, r_n ≥ 0 (no tension) and ‖r_t‖ ≤ μ_s r_n;
//! - closed (slip): x_n = −g_old, r_t = μ_k r_n·s with s the unit direction
//!   opposing the slip increment x_t;
//! - grouted: r = r_old − k∘x (the grout layer carries the force of the
//!   moment of grouting plus its elastic change); tension above the bond
//!   strength cracks it and it becomes a contact point again.
//!
//! Two solvers share this contract ([`ContactSolverKind`]):
//! - [`active_set`]: the states are guessed (warm start: the last step's;
//!   a new pair starts closed), closed points become exact Dirichlet rows of
//!   their own unknowns, the system is solved, and the states are corrected
//!   from the gaps and reactions until nothing changes. The symbolic
//!   factorisation is shared by every state; a numeric one is needed only
//!   when the set of constrained rows changes. Friction is a return mapping:
//!   a point that slipped in the last step starts as a stick trial, slips if
//!   its trial force exceeds μ_k·r_n (μ_s for a point at rest), in the trial
//!   force's direction for the whole step; the slip forces μ_k·r_n(x) are a
//!   fixed point solved by Anderson mixing (re-solves, no refactorisation).
//!   A point may switch open ↔ closed or slip → stick [`MAX_FLIPS`] times
//!   per step, then only close or slip, so the iteration ends.
//! - [`condensed_qp`]: the Delassus operator W = Eᵀ K̃⁻¹ E of the contact
//!   pairs from multi-column solves, handed to the clarabel cone program of
//!   [`crate::joint::solve`] (maximum dissipation; relative components held
//!   by supports are left out). Dense in the pairs: for checks and small
//!   scenes.
//!
//! Verified by `tests/it/joint_two_blocks.rs`, `tests/it/joint_grouting.rs`,
//! `tests/it/joint_friction.rs` (closed forms, both solvers) and
//! `tests/it/contact_solvers_agree.rs` (the two solvers on a staged dam).

use std::time::Instant;

use crate::fem::{relative_residual, SolveError, SparseSym};
use crate::joint::{ContactProblem, ContactSettings, FrictionModel};
use crate::scene::ContactSolverKind;

use super::joints::{JointPoint, JointPointState, PointState};
use super::live::LiveSystem;

/// Relative residual above which a linear solve of the contact loop is rejected.
const RESIDUAL_TOLERANCE: f64 = 1e-8;
/// Open ↔ closed and slip → stick switches of one point within a step after
/// which the point may only close or start slipping for the rest of the
/// step, so the state iteration ends. A point whose gap and
/// pressure are both near zero can otherwise alternate for ever (seen on the
/// small dam and the demo); kept closed, its aperture stays exact and it may
/// carry a small tension (the price, instead of a small overlap).
const MAX_FLIPS: usize = 3;
/// Slip-force iterates Anderson mixing remembers.
const ANDERSON_DEPTH: usize = 8;

/// Settings of the joint solve (from the scene's `[joints]` and `[solver]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSolveSettings {
    pub method: ContactSolverKind,
    /// static and kinetic Coulomb coefficients
    pub mu_static: f64,
    pub mu_kinetic: f64,
    /// passes (active set) or cracking rounds × fixed-point solves (qp) per step
    pub max_iterations: usize,
    /// a gap below −gap_tolerance closes an open point [m]
    pub gap_tolerance: f64,
    /// forces are compared to force_tolerance × the step's force scale
    pub force_tolerance: f64,
    /// tensile strength of a grout layer [Pa]
    pub bond_strength: f64,
}

/// Why a joint solve failed.
#[derive(Debug, thiserror::Error)]
pub enum JointStepError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("linear solve inside the contact loop: relative residual {0:.3e}")]
    Residual(f64),
    #[error("contact states still changing after {iterations} passes ({changes} points changed state in the last pass)")]
    NotConverged { iterations: usize, changes: usize },
    #[error("contact cone program: {0}")]
    Qp(#[from] crate::joint::ContactError),
}

/// What a joint solve did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointStepOutcome {
    /// the step's solution in the reduced unknowns
    pub x: Vec<f64>,
    /// passes (active set) or cone-program fixed-point iterations (qp)
    pub iterations: usize,
    pub factorizations: usize,
    pub solves: usize,
    pub seconds_numeric: f64,
    /// largest tension [Pa] left on a point kept closed by the flip limit
    pub kept_closed_tension: f64,
}

/// The step's system before contact: K̃ (no springs, no constraints) and f̃.
pub struct StepSystem<'a> {
    pub a: &'a SparseSym,
    pub b: &'a [f64],
    /// increments of the supported unknowns (zero but for jacks and settlements)
    pub prescribed: &'a [f64],
    pub points: &'a [JointPoint],
    pub day: f64,
}

/// Solves the step with the configured method; `states` are updated only on success.
pub fn solve(
    sys: &StepSystem,
    live: &mut LiveSystem,
    states: &mut [JointPointState],
    settings: &JointSolveSettings,
) -> Result<JointStepOutcome, JointStepError> {
    match settings.method {
        ContactSolverKind::ActiveSet => active_set(sys, live, states, settings),
        ContactSolverKind::Qp => condensed_qp(sys, live, states, settings),
    }
}

/// Largest force of the step: right-hand side and committed contact forces.
fn force_scale(b: &[f64], live: &LiveSystem, states: &[JointPointState]) -> f64 {
    let fb = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let fr = live
        .pairs
        .iter()
        .map(|p| &states[p.point as usize].force)
        .flat_map(|f| f.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    fb.max(fr).max(f64::MIN_POSITIVE)
}

/// K̃ plus the springs of the intact grout layers.
fn with_springs(a: &SparseSym, live: &LiveSystem, states: &[JointPointState]) -> SparseSym {
    let mut m = a.clone();
    for pair in &live.pairs {
        let st = &states[pair.point as usize];
        if let (PointState::Grouted, Some(g)) = (st.state, &st.grout) {
            for k in 0..3 {
                m.add_diag(pair.first as usize + k, g.stiffness[k]);
            }
        }
    }
    m
}

/// Gap at the start of the step as the current guess sees it: a layer that
/// cracks in this step starts as closed faces (its elastic compression is
/// released with its force), never as an overlap.
fn start_gap(old: &JointPointState, guess: &JointPointState) -> f64 {
    if old.state == PointState::Grouted && guess.state != PointState::Grouted {
        old.gap.max(0.0)
    } else {
        old.gap
    }
}

fn norm2(v: [f64; 2]) -> f64 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Cracks the intact grout layers whose normal tension exceeds the bond
/// strength; returns how many cracked.
fn crack(
    live: &LiveSystem,
    points: &[JointPoint],
    work: &mut [JointPointState],
    bond: f64,
    day: f64,
) -> usize {
    let mut n = 0;
    for pair in &live.pairs {
        let p = pair.point as usize;
        let st = &mut work[p];
        if st.state != PointState::Grouted {
            continue;
        }
        let tension = -st.force[2] / points[p].area;
        if tension > bond {
            if let Some(g) = st.grout.as_mut() {
                g.cracked_day = Some(day);
            }
            st.state = PointState::Open;
            n += 1;
        }
    }
    n
}

/// The open/stick/slip state iteration (see the module doc).
pub fn active_set(
    sys: &StepSystem,
    live: &mut LiveSystem,
    states: &mut [JointPointState],
    s: &JointSolveSettings,
) -> Result<JointStepOutcome, JointStepError> {
    let n = live.n;
    let old: Vec<JointPointState> = states.to_vec();
    let mut work = old.clone();
    // Return mapping: a point that slipped in the last step starts as a stick
    // trial; the trial force gives this step's slip direction, and it keeps
    // slipping if that force exceeds the kinetic (not the static) limit.
    // A direction carried over from the last step would grow sideways from
    // step to step (measured ×5–100 per step across an incline).
    let kinetic: Vec<bool> = live
        .pairs
        .iter()
        .map(|p| old[p.point as usize].state == PointState::Slip)
        .collect();
    for (q, p) in live.pairs.iter().enumerate() {
        if kinetic[q] {
            work[p.point as usize].state = PointState::Stick;
        }
    }
    let f_scale = force_scale(sys.b, live, states);
    let tol_f = s.force_tolerance * f_scale;
    let tol_g = s.gap_tolerance;
    let frictionless = s.mu_static == 0.0;
    // friction force of each slipping point used in the current pass
    let mut slip_force: Vec<[f64; 2]> = live
        .pairs
        .iter()
        .map(|p| {
            let st = &old[p.point as usize];
            let mag = s.mu_kinetic * st.force[2].max(0.0);
            [mag * st.slip_dir[0], mag * st.slip_dir[1]]
        })
        .collect();
    let mut out = JointStepOutcome::default();
    let mut factored_key: Option<(Vec<bool>, Vec<bool>)> = None;
    let mut a_cur = SparseSym::new(sys.a.pattern().clone());
    let mut m = SparseSym::new(sys.a.pattern().clone());
    let mut last_changes = 0;
    let mut anderson = Anderson::new(ANDERSON_DEPTH);
    let limit: Vec<f64> = kinetic
        .iter()
        .map(|&k| if k { s.mu_kinetic } else { s.mu_static })
        .collect();
    let mut flips = vec![0usize; live.pairs.len()];
    for pass in 1..=s.max_iterations {
        out.iterations = pass;
        // Constraints and right-hand side of the guessed states.
        let mut fixed = live.supported.clone();
        let mut presc = sys.prescribed.to_vec();
        let mut rhs = sys.b.to_vec();
        let mut springs = vec![false; live.pairs.len()];
        for (q, pair) in live.pairs.iter().enumerate() {
            let p = pair.point as usize;
            let f = pair.first as usize;
            let (st, r_old, g_old) = (&work[p], old[p].force, start_gap(&old[p], &work[p]));
            match st.state {
                PointState::Open => {
                    for k in 0..3 {
                        rhs[f + k] -= r_old[k];
                    }
                }
                PointState::Stick => {
                    fixed[f..f + 3].iter_mut().for_each(|v| *v = true);
                    presc[f + 2] = -g_old;
                }
                PointState::Slip => {
                    fixed[f + 2] = true;
                    presc[f + 2] = -g_old;
                    for k in 0..2 {
                        rhs[f + k] += slip_force[q][k] - r_old[k];
                    }
                }
                PointState::Grouted => springs[q] = true,
            }
        }
        let key = (fixed.clone(), springs.clone());
        if factored_key.as_ref() != Some(&key) {
            a_cur = with_springs(sys.a, live, &work);
            m = a_cur.clone();
            m.apply_dirichlet(&fixed);
            let t = Instant::now();
            live.solver.factorize(&m)?;
            out.seconds_numeric += t.elapsed().as_secs_f64();
            out.factorizations += 1;
            factored_key = Some(key);
        }
        a_cur.dirichlet_correction(&fixed, &presc, &mut rhs);
        for i in 0..n {
            if fixed[i] {
                rhs[i] = presc[i];
            }
        }
        let mut x = rhs.clone();
        live.solver.solve_in_place(&mut x)?;
        out.solves += 1;
        let res = relative_residual(&m, &x, &rhs);
        if !(res <= RESIDUAL_TOLERANCE) {
            return Err(JointStepError::Residual(res));
        }
        // Forces and gaps of the pass.
        let mut kx = vec![0.0; n];
        sys.a.mul_vec(&x, &mut kx);
        let mut changes = 0;
        // slip forces the pass's reactions call for (the fixed-point map)
        let mut mapped = slip_force.clone();
        let mut reversed: Vec<usize> = Vec::new();
        for (q, pair) in live.pairs.iter().enumerate() {
            let p = pair.point as usize;
            let f = pair.first as usize;
            let (r_old, g_old) = (old[p].force, start_gap(&old[p], &work[p]));
            let xd = [x[f], x[f + 1], x[f + 2]];
            // Supported relative components carry support reactions, not contact.
            let reaction: [f64; 3] = std::array::from_fn(|k| {
                if live.supported[f + k] {
                    0.0
                } else {
                    r_old[k] + kx[f + k] - sys.b[f + k]
                }
            });
            let st = &mut work[p];
            st.gap = g_old + xd[2];
            match st.state {
                PointState::Open => {
                    st.force = [0.0; 3];
                    if st.gap < -tol_g {
                        flips[q] += 1;
                        st.state = if frictionless {
                            PointState::Slip
                        } else {
                            PointState::Stick
                        };
                        changes += 1;
                    }
                }
                PointState::Stick => {
                    st.force = reaction;
                    st.gap = 0.0;
                    let rt = [reaction[0], reaction[1]];
                    if reaction[2] < -tol_f && flips[q] < MAX_FLIPS {
                        flips[q] += 1;
                        st.state = PointState::Open;
                        changes += 1;
                    } else if norm2(rt) > limit[q] * reaction[2].max(0.0) + tol_f {
                        let mag = norm2(rt);
                        st.slip_dir = [rt[0] / mag, rt[1] / mag];
                        st.state = PointState::Slip;
                        let fs = s.mu_kinetic * reaction[2].max(0.0);
                        mapped[q] = [fs * st.slip_dir[0], fs * st.slip_dir[1]];
                        changes += 1;
                    }
                }
                PointState::Slip => {
                    st.force = [slip_force[q][0], slip_force[q][1], reaction[2]];
                    st.gap = 0.0;
                    let slip = [xd[0], xd[1]];
                    let applied = norm2(slip_force[q]);
                    let along = if applied > 0.0 {
                        (slip[0] * slip_force[q][0] + slip[1] * slip_force[q][1]) / applied
                    } else {
                        0.0
                    };
                    if reaction[2] < -tol_f && flips[q] < MAX_FLIPS {
                        flips[q] += 1;
                        st.state = PointState::Open;
                        changes += 1;
                    } else {
                        if !frictionless && along > tol_g && flips[q] < MAX_FLIPS {
                            // Moving with the friction force: it sticks once
                            // the slip forces have settled.
                            reversed.push(q);
                        }
                        // The direction is the trial force's for the whole
                        // step (taken from each pass's slip, the iteration
                        // cycles between nearby angles on 3-D joints).
                        let fs = s.mu_kinetic * reaction[2].max(0.0);
                        mapped[q] = [fs * st.slip_dir[0], fs * st.slip_dir[1]];
                    }
                }
                PointState::Grouted => {
                    let k = st.grout.map_or([0.0; 3], |g| g.stiffness);
                    st.force = std::array::from_fn(|i| r_old[i] - k[i] * xd[i]);
                }
            }
        }
        changes += crack(live, sys.points, &mut work, s.bond_strength, sys.day);
        last_changes = changes;
        let slipping: Vec<usize> = (0..live.pairs.len())
            .filter(|&q| work[live.pairs[q].point as usize].state == PointState::Slip)
            .collect();
        if changes > 0 {
            // New states: restart the slip-force iteration from their forces.
            anderson.clear();
            for &q in &slipping {
                slip_force[q] = mapped[q];
            }
        } else {
            let residual = slipping
                .iter()
                .map(|&q| {
                    norm2([
                        mapped[q][0] - slip_force[q][0],
                        mapped[q][1] - slip_force[q][1],
                    ])
                })
                .fold(0.0, f64::max);
            if residual <= tol_f && reversed.is_empty() {
                for (q, pair) in live.pairs.iter().enumerate() {
                    let st = &work[pair.point as usize];
                    if flips[q] >= MAX_FLIPS && st.state.is_closed() {
                        let t = -st.force[2] / sys.points[pair.point as usize].area;
                        out.kept_closed_tension = out.kept_closed_tension.max(t);
                    }
                }
                out.x = x;
                states.copy_from_slice(&work);
                return Ok(out);
            } else if residual <= tol_f {
                for &q in &reversed {
                    work[live.pairs[q].point as usize].state = PointState::Stick;
                    flips[q] += 1;
                }
                last_changes = reversed.len();
                anderson.clear();
            } else {
                // The slip forces are a fixed point of (forces → solve →
                // μ_k·r_n), affine for fixed directions. Anderson mixing
                // converges in a few passes where the plain iteration
                // contracts slowly (0.94 per pass measured on the small dam).
                let xs: Vec<f64> = slipping.iter().flat_map(|&q| slip_force[q]).collect();
                let fx: Vec<f64> = slipping.iter().flat_map(|&q| mapped[q]).collect();
                let next = anderson.next(&xs, &fx);
                for (i, &q) in slipping.iter().enumerate() {
                    slip_force[q] = [next[2 * i], next[2 * i + 1]];
                }
            }
        }
    }
    Err(JointStepError::NotConverged {
        iterations: s.max_iterations,
        changes: last_changes,
    })
}

/// The condensed cone program (see the module doc). Cracked grout layers
/// restart the solve with those points as contacts.
pub fn condensed_qp(
    sys: &StepSystem,
    live: &mut LiveSystem,
    states: &mut [JointPointState],
    s: &JointSolveSettings,
) -> Result<JointStepOutcome, JointStepError> {
    let n = live.n;
    let old: Vec<JointPointState> = states.to_vec();
    let mut work = old.clone();
    let mut out = JointStepOutcome::default();
    let friction = if s.mu_static == 0.0 {
        FrictionModel::Frictionless
    } else {
        FrictionModel::Coulomb {
            mu_s: s.mu_static,
            mu_k: s.mu_kinetic,
        }
    };
    for _round in 0..s.max_iterations {
        let mut m = with_springs(sys.a, live, &work);
        let mut rhs = sys.b.to_vec();
        m.dirichlet_correction(&live.supported, sys.prescribed, &mut rhs);
        m.apply_dirichlet(&live.supported);
        let t = Instant::now();
        live.solver.factorize(&m)?;
        out.seconds_numeric += t.elapsed().as_secs_f64();
        out.factorizations += 1;
        let contact: Vec<usize> = (0..live.pairs.len())
            .filter(|&q| work[live.pairs[q].point as usize].state != PointState::Grouted)
            .collect();
        for &q in &contact {
            let pair = &live.pairs[q];
            for k in 0..3 {
                rhs[pair.first as usize + k] -= old[pair.point as usize].force[k];
            }
        }
        for i in 0..n {
            if live.supported[i] {
                rhs[i] = sys.prescribed[i];
            }
        }
        let mut x = rhs.clone();
        live.solver.solve_in_place(&mut x)?;
        out.solves += 1;
        let res = relative_residual(&m, &x, &rhs);
        if !(res <= RESIDUAL_TOLERANCE) {
            return Err(JointStepError::Residual(res));
        }
        if !contact.is_empty() {
            let cols = 3 * contact.len();
            let mut g = faer::Mat::<f64>::zeros(n, cols);
            for (j, &q) in contact.iter().enumerate() {
                for k in 0..3 {
                    g[(live.pairs[q].first as usize + k, 3 * j + k)] = 1.0;
                }
            }
            live.solver.solve_columns(&mut g)?;
            out.solves += cols;
            let row = |i: usize| live.pairs[contact[i / 3]].first as usize + i % 3;
            let mut w = nalgebra::DMatrix::from_fn(cols, cols, |i, j| {
                0.5 * (g[(row(i), j)] + g[(row(j), i)])
            });
            // A relative component held by a support is not a contact
            // unknown: decouple it with a compliance of the problem's scale
            // (its identity row of the constrained matrix would otherwise read
            // 1 m/N against ~1e-10) and pin its force to zero below.
            let held: Vec<bool> = (0..cols).map(|i| live.supported[row(i)]).collect();
            let free_diag: Vec<f64> = (0..cols).filter(|&i| !held[i]).map(|i| w[(i, i)]).collect();
            let scale = free_diag.iter().sum::<f64>() / free_diag.len().max(1) as f64;
            for i in (0..cols).filter(|&i| held[i]) {
                for j in 0..cols {
                    w[(i, j)] = 0.0;
                    w[(j, i)] = 0.0;
                }
                w[(i, i)] = if scale > 0.0 { scale } else { 1.0 };
            }
            let mut b = vec![0.0; cols];
            let mut r_old = vec![0.0; cols];
            for (j, &q) in contact.iter().enumerate() {
                let p = live.pairs[q].point as usize;
                for k in 0..3 {
                    b[3 * j + k] = x[row(3 * j + k)];
                    r_old[3 * j + k] = old[p].force[k];
                }
                b[3 * j + 2] += start_gap(&old[p], &work[p]);
            }
            for i in (0..cols).filter(|&i| held[i]) {
                b[i] = 0.0;
            }
            let fr = vec![friction; contact.len()];
            let problem = ContactProblem::new(&w, &b, &fr);
            let mut sol = crate::joint::solve(&problem, &ContactSettings::default(), Some(&r_old))?;
            out.iterations += sol.fixed_point_iterations;
            for i in (0..cols).filter(|&i| held[i]) {
                sol.r[i] = 0.0;
            }
            for i in 0..n {
                let mut acc = 0.0;
                for k in 0..cols {
                    acc += g[(i, k)] * sol.r[k];
                }
                x[i] += acc;
            }
            for (j, &q) in contact.iter().enumerate() {
                let p = live.pairs[q].point as usize;
                let st = &mut work[p];
                st.force = [sol.r[3 * j], sol.r[3 * j + 1], sol.r[3 * j + 2]];
                st.gap = sol.u[3 * j + 2];
                st.state = sol.states[j].into();
                let t = [st.force[0], st.force[1]];
                if st.state == PointState::Slip && norm2(t) > 0.0 {
                    st.slip_dir = [t[0] / norm2(t), t[1] / norm2(t)];
                }
            }
        }
        for pair in &live.pairs {
            let p = pair.point as usize;
            if work[p].state == PointState::Grouted {
                let f = pair.first as usize;
                let k = work[p].grout.map_or([0.0; 3], |g| g.stiffness);
                work[p].force = std::array::from_fn(|i| old[p].force[i] - k[i] * x[f + i]);
                work[p].gap = old[p].gap + x[f + 2];
            }
        }
        if crack(live, sys.points, &mut work, s.bond_strength, sys.day) == 0 {
            out.x = x;
            states.copy_from_slice(&work);
            return Ok(out);
        }
    }
    Err(JointStepError::NotConverged {
        iterations: s.max_iterations,
        changes: 0,
    })
}

/// Anderson mixing (type II) for a fixed point x = F(x): the next iterate
/// combines the last F values so that the combined residual F(x) − x is least
/// in the 2-norm. On an affine map it is GMRES in disguise.
struct Anderson {
    depth: usize,
    xs: Vec<Vec<f64>>,
    fs: Vec<Vec<f64>>,
}

impl Anderson {
    fn new(depth: usize) -> Self {
        Anderson {
            depth,
            xs: Vec::new(),
            fs: Vec::new(),
        }
    }

    fn clear(&mut self) {
        self.xs.clear();
        self.fs.clear();
    }

    fn next(&mut self, x: &[f64], fx: &[f64]) -> Vec<f64> {
        if self.xs.first().is_some_and(|v| v.len() != x.len()) {
            self.clear();
        }
        self.xs.push(x.to_vec());
        self.fs.push(fx.to_vec());
        if self.xs.len() > self.depth + 1 {
            self.xs.remove(0);
            self.fs.remove(0);
        }
        let k = self.xs.len();
        let r = |i: usize| -> Vec<f64> {
            self.fs[i]
                .iter()
                .zip(&self.xs[i])
                .map(|(f, x)| f - x)
                .collect()
        };
        let rk = r(k - 1);
        if k == 1 {
            return fx.to_vec();
        }
        let n = x.len();
        let m = k - 1;
        let mut dr = nalgebra::DMatrix::zeros(n, m);
        for j in 0..m {
            let (a, b) = (r(j + 1), r(j));
            for i in 0..n {
                dr[(i, j)] = a[i] - b[i];
            }
        }
        let rhs = nalgebra::DVector::from_column_slice(&rk);
        let scale = dr.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let Ok(gamma) = dr
            .clone()
            .svd(true, true)
            .solve(&rhs, 1e-12 * scale.max(f64::MIN_POSITIVE))
        else {
            self.clear();
            return fx.to_vec();
        };
        let mut next = fx.to_vec();
        for j in 0..m {
            for i in 0..n {
                next[i] -= gamma[j] * (self.fs[j + 1][i] - self.fs[j][i]);
            }
        }
        next
    }
}
