//! The joint problem of one mechanical step, in the unknowns of
//! [`LiveSystem`]: node displacements ũ and the
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
//! Two solvers share this contract ([`ContactSolverKind`]) and one trial:
//! the states at the start of the step and the states being tried, which
//! replace the caller's only when the solve succeeds.
//! - `active_set`: the states are guessed (warm start: the last step's;
//!   a new pair starts closed), closed points become exact Dirichlet rows of
//!   their own unknowns, the system is solved, and the states are corrected
//!   from the gaps and reactions until nothing changes. The symbolic
//!   factorisation is shared by every state; the step's numeric factor
//!   serves every pass: a pass whose constrained rows differ from the
//!   factor's is solved exactly by the capacitance correction of
//!   [`crate::fem::capacitance`] (a forward half-solve on its reach in
//!   the elimination tree for each of the m changed rows, kept for later
//!   passes, and a dense m × m system); a grout layer that cracks
//!   within the step removes its springs from the diagonal of its pair's
//!   rows, a diagonal change the same correction takes. The step
//!   refactorises only when the new rows would cost more solves than a
//!   factorisation (counted by flops, so the choice is deterministic).
//!   `solver.contact_capacitance = false` refactorises at every change
//!   instead (the exact path it is compared with). Friction is a return mapping:
//!   a point that slipped in the last step starts as a stick trial, slips if
//!   its trial force exceeds μ_k·r_n (μ_s for a point at rest), in the trial
//!   force's direction for the whole step. The slip forces μ_k·r_n(x)·s
//!   are linear in x for fixed directions, so a pass solves them with the
//!   states: each slipping point's tangential rows are coupled to its
//!   normal reaction row ([`crate::fem::Coupling`]), a non-symmetric
//!   border of the same capacitance system (exact; on the demo's whole
//!   construction 2,125 passes where the fixed point took 4,401). Where
//!   the border's columns, their products and its LU would cost more
//!   than a factorisation (thousands of slipping points on the complete
//!   Xiaowan-like dam loaded at once; decided on the states alone, so the
//!   exact path decides alike), or a
//!   point slipped in tension (its force is then μ_k·max(r_n, 0) = 0), the
//!   slip forces are a fixed point solved by Anderson mixing (re-solves,
//!   no refactorisation), preconditioned after a step's first change of
//!   states by the secants of its earlier rounds ([`RoundSecants`]).
//!   A point may switch open ↔ closed or slip → stick [`MAX_FLIPS`] times
//!   per step with the others; after that it is cycling. Without friction
//!   the cycling points switch open ↔ closed one per pass, the least index
//!   first (Murty's least-index rule, which ends for the frictionless
//!   normal problem), so the iteration ends without leaving a point closed
//!   in tension or open with an overlap. With friction, once a point
//!   cycles, the step's normal states switch by block pivoting
//!   ([`BlockPivoting`]): only after the friction forces have settled on
//!   the current normal states, every wrong point at once while that
//!   lowers the count of wrong points, else the least-index one, and the
//!   slipping points then found moving with their force stick in the same
//!   pass. The step ends once the slip forces hold to the force
//!   tolerance, or to that fraction of the largest joint force where that
//!   is less ([`ActiveSet::friction_tolerance`]). Past
//!   its budget of single switches a cycling point may only close or slip,
//!   and the tension it may keep is reported.
//! - `condensed_qp`: the Delassus operator W = Eᵀ K̃⁻¹ E of the contact
//!   pairs from multi-column solves, handed to the clarabel cone program of
//!   [`crate::joint::solve`] (maximum dissipation; relative components held
//!   by supports are left out). Dense in the pairs: for checks and small
//!   scenes.
//!
//! Verified by `tests/it/joint_two_blocks.rs`, `tests/it/joint_grouting.rs`,
//! `tests/it/joint_friction.rs` (closed forms, both solvers) and
//! `tests/it/contact_solvers_agree.rs` (the two solvers on a staged dam).

use std::time::Instant;

use crate::fem::capacitance::{columns_cost, constrained_rhs, held_residual};
use crate::fem::{
    relative_residual, Capacitance, CapacitanceStats, Coupling, Refine, SolveError, SparseSym,
    REFINE_TO,
};
use crate::joint::{ContactProblem, ContactSettings, FrictionModel};
use crate::scene::ContactSolverKind;

use super::joints::{JointPoint, JointPointState, PointState};
use super::live::LiveSystem;

/// Rows of the first pass's correction (two per point that slipped in the
/// last step) from which a step's first factor holds its start states'
/// rows ([`start_rows`]). Below it the later passes' smaller corrections
/// save less than the first pass's correction and its full forward half
/// cost: the demo's steps (a few dozen such rows) took 39.5–40.6 s
/// against 38.7–39.5 s for its whole construction; a late day of the
/// Xiaowan-like arch (~800 rows) 7.5–8.2 against 8.1–8.5 s (5 Dec 2026,
/// alternated).
const START_ROWS_FROM: usize = 200;
/// Relative residual above which a linear solve of the contact loop is rejected.
const RESIDUAL_TOLERANCE: f64 = 1e-8;
/// Residual a pass's corrected solve is refined to: enough for the states
/// it decides (a digit below [`RESIDUAL_TOLERANCE`]); the pass whose
/// states hold is refined on to [`REFINE_TO`] and its states checked again
/// before it is the answer, so a state decided wrongly on a looser
/// solution costs passes, never the answer. Each refinement is a full
/// forward and backward sweep: on the Xiaowan-like complete dam (27 Nov
/// 2026, alone on the 2 cores, alternated twice) 1e-9 took 128
/// refinements and 211.6–215.7 s against 144 and 226.3–228.1 s at 1e-10,
/// the same 85 passes and states; the demo's whole construction is the
/// same to the byte.
const PASS_REFINE_TO: f64 = 1e-9;
/// Slip-force residual, in the step's friction tolerances
/// (`ActiveSet::friction_tolerance`), below which a pass is refined to
/// [`REFINE_TO`] rather than [`PASS_REFINE_TO`]: the reactions of a solve
/// refined to 1e-9 of the load's 2-norm carry errors of several
/// tolerances (1e-9 of the largest force), so the slip forces' fixed
/// point could not settle below them. On the Xiaowan-like complete dam
/// (29 Nov 2026) its residual stalled at 10–20 tolerances for 30 passes
/// without; such a pass also needs no second solve to check its states.
const FINE_PASS_FACTOR: f64 = 1e3;
/// Open ↔ closed and slip → stick switches of one point within a step after
/// which the point is cycling: its normal state switches only as the single
/// least-index switch of a pass ([`ActiveSet::pivot`]). A point whose gap
/// and pressure are both near zero can otherwise alternate for ever (seen
/// on the small dam and the demo). Freezing it instead left points closed
/// in tension: 0.57 MPa on the demo loaded at once
/// (`tests/it/hard_cases.rs`).
const MAX_FLIPS: usize = 3;
/// Passes of [`BlockPivoting`] that switch every wrong normal state
/// without lowering the least count of wrong points seen so far, before
/// the single least-index switches take over (Júdice and Pires's p̄).
const BLOCK_PASSES: usize = 3;
/// Slip-force iterates Anderson mixing remembers.
const ANDERSON_DEPTH: usize = 8;
/// Secants of the slip forces' map that [`RoundSecants`] carries from a
/// step's earlier rounds into the next. On the Xiaowan-like complete dam
/// (5 Dec 2026): 16, 32 and 64 took 125, 122 and 127 passes (149
/// without), the same states at the end.
const SECANT_DEPTH: usize = 32;
/// Slipping points found moving with their friction force stick once the
/// slip forces' residual is below this many force tolerances (1e-4 of the
/// step's largest force at the default 1e-9), not only at the last digit:
/// on the complete Xiaowan-like dam the set of such points stopped
/// changing at 1e-3 to 1e-5 of the largest force. A point stuck too early
/// slips again in the next pass (a flip), which costs passes, never the
/// answer: the step still ends only on a residual within the force
/// tolerance itself. That step, untied, traced pass by pass (27 Nov
/// 2026), stuck the same sets of reversed points (387, 164, 39, 11, 1)
/// and reached the same final states (504 stick, 13,173 slip, 2,052 open)
/// in 85 passes and 228.1 s with 1e5, against 103 passes and 236.4 s with
/// 1e3: each of its four Anderson rounds had settled its set 4–5 passes
/// before 1e3 was reached.
const SETTLED_FACTOR: f64 = 1e5;
/// [`BlockPivoting`] switches normal states, and sticks the slipping
/// points moving with their force, in the pass after the slip forces'
/// residual fell below this many force tolerances (1e-2 of the step's
/// largest force at the default 1e-9): the normal reactions that decide
/// them are then right but near zero, and a point decided wrongly costs
/// passes, never the answer. The demo's complete dam under its weight at
/// once (29 Nov 2026): 66 passes, against 77 with 1e6, 54 with 1e8, 50
/// with 3e8 and 329 (6.4 MPa kept) with 1e9; on the Xiaowan-like complete
/// dam 1e8 took 123 passes against 149 but the same 205 s, so the factor
/// keeps its margin from the cliff.
const NORMAL_SETTLED_FACTOR: f64 = 1e7;
/// Cost of one flop of a capacitance column's reach solve
/// ([`crate::fem::CholeskySolver::reach_cost`]) relative to one flop of
/// the numeric factorisation: the correction is chosen while its new
/// columns cost less than a factorisation. Set when the columns were
/// scalar loops (demo, 26 Nov 2026: 3.5 against 19.6 Gflop/s). Solved in
/// batches (27 Nov 2026) they run at 9.8 Gflop/s on the demo and 15.7 on
/// the Xiaowan-like complete dam, against 17.7 and 49 Gflop/s of
/// factorisation; a weight of 2 changed nothing on the demo's whole
/// construction and made its complete-dam step slower (2.84 against
/// 2.40 s: larger corrections need more refinements), so 5.5 stayed. With
/// the columns batched in the factor's order and the products of S block
/// by block (29 Nov 2026), 3 — the rates' ratio on the large arch — keeps
/// the large arch's late days from refactorising past a break-even they
/// had not reached: days 856–862 (`study perf --resume`, 6 steps, 79
/// passes) 6 factorisations against 9, 28.4 against 41.9 s, the joints
/// 56.9 against 55.7 s, the steps 91.5 against 104.4 s (and 123.3
/// against 125.8 s for the whole command in a first pair); the demo's run
/// 0 refactorisations past it against 2, its complete dam's step the
/// same 10 (30 Nov 2026). With the factorisation and the columns' batches
/// on two cores (5 Dec 2026) the rates moved: on the large arch's days
/// 856–862 the columns ran at 43.5 Gflop/s (246.9 Gflop estimated, 5.67 s)
/// and the factorisations at 58.5 (1,181 Gflop, 20.2 s), so the weight is
/// their ratio again, 1.3: the large complete dam's step corrects the
/// 314 switches of its fourth round (rank 2,075: 114 Gflop of columns)
/// instead of refactorising, 9 factorisations against 10, the same 122
/// passes and final states, 68.6 against 72.5 s; the next pass past it
/// (rank 2,722, 206 Gflop) still refactorises. The demo's run and its
/// complete dam are the same at 1.3 and 3 (no choice near the break-even).
/// `groutready study perf` prints what both cost.
const CAPACITANCE_SOLVE_WEIGHT: f64 = 1.3;
/// The same weight in the choice to solve the slip forces with the states
/// (a border of the system, [`crate::fem::Coupling`]): its columns' cost
/// against a factorisation's. Kept at the 5.5 of the break-even before
/// (30 Nov 2026): at 3 the demo's complete dam under its weight at once
/// couples sooner and takes 73 passes against 66 (2.50 against 1.97 s);
/// the large arch's days 856–862 couple alike at either.
const COUPLING_SOLVE_WEIGHT: f64 = 5.5;
/// Memory the capacitance columns of one step may hold \[bytes\]; above it
/// the step refactorises.
const CAPACITANCE_MAX_BYTES: usize = 1 << 30;

/// Settings of the joint solve (from the scene's `[joints]` and `[solver]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSolveSettings {
    pub method: ContactSolverKind,
    /// static and kinetic Coulomb coefficients
    pub mu_static: f64,
    pub mu_kinetic: f64,
    /// passes (active set) or cracking rounds × fixed-point solves (qp) per step
    pub max_iterations: usize,
    /// a gap below −gap_tolerance closes an open point \[m\]
    pub gap_tolerance: f64,
    /// forces are compared to force_tolerance × the step's force scale
    pub force_tolerance: f64,
    /// tensile strength of a grout layer \[Pa\]
    pub bond_strength: f64,
    /// active set: a pass whose constrained rows differ from the factor's
    /// is solved by the capacitance correction (exact) instead of a new
    /// factorisation, while that is cheaper
    pub capacitance: bool,
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
    /// of the passes, those that changed no state and moved only the slip
    /// forces the pass did not solve with the states (a step of Anderson
    /// mixing of their fixed point, [`ActiveSet::next_slip_forces`])
    pub slip_force_passes: usize,
    pub factorizations: usize,
    pub solves: usize,
    pub seconds_numeric: f64,
    /// largest tension \[Pa\] left on a point kept closed by the flip limit
    pub kept_closed_tension: f64,
    /// the step's normal states switched by [`BlockPivoting`]
    pub block_pivoting: bool,
    /// why each factorisation was made
    pub refactor_reasons: RefactorCounts,
    /// the capacitance corrections that replaced factorisations
    pub capacitance: CapacitanceStats,
    /// the active set's passes, one record each
    pub passes: Vec<PassRecord>,
}

/// One contact pass of the active set, as [`JointStepOutcome::passes`]
/// logs it: how a hard step's passes go (rounds of state switches, each
/// followed by passes of the slip forces' fixed point), which
/// `examples/complete_step.rs --passes` prints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassRecord {
    pub kind: PassKind,
    /// points whose state the pass changed for the next one
    /// ([`PassKind::Switched`]) or whose normal state [`BlockPivoting`]
    /// held for it ([`PassKind::Settled`]); 0 otherwise
    pub changes: usize,
    /// live points open, sticking and slipping after the pass
    pub open: usize,
    pub stick: usize,
    pub slip: usize,
    /// the pass factorised (the step's first factor, or rows changed past
    /// the correction's break-even)
    pub factorised: bool,
    /// rows of the pass's capacitance correction: rows changed from its
    /// factor's, and slip forces coupled to their normal reactions (both 0:
    /// solved on its factor alone)
    pub rank: usize,
    pub couplings: usize,
    /// the slip forces' fixed-point residual after the pass, in
    /// [`ActiveSet::friction_tolerance`]s (infinite after a change of
    /// states)
    pub slip_residual: f64,
    /// normal states [`BlockPivoting`] found wrong in its last switching
    /// pass (None before it has switched)
    pub wrong_normal: Option<usize>,
}

/// What a contact pass did ([`PassRecord`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    /// states changed: switches, sticks, a grout layer cracked
    Switched,
    /// no state changed: a step of Anderson mixing moved the slip forces
    /// not solved with the states
    SlipForces,
    /// the friction holds on the states; the normal states
    /// [`BlockPivoting`] held switch in the next pass
    Settled,
    /// the step's answer
    Answer,
}

/// Why the joint solve factorised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefactorReason {
    /// the step's first pass (the stiffness has aged, elements were born)
    Step,
    /// grout springs appeared or cracked and the correction is off
    Grout,
    /// the constrained rows changed and the correction is off
    Contact,
    /// the constrained rows changed more than the correction's break-even
    Rank,
}

/// Factorisations counted by [`RefactorReason`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RefactorCounts {
    pub step: usize,
    pub grout: usize,
    pub contact: usize,
    pub rank: usize,
}

impl RefactorCounts {
    pub fn count(&mut self, reason: RefactorReason) {
        match reason {
            RefactorReason::Step => self.step += 1,
            RefactorReason::Grout => self.grout += 1,
            RefactorReason::Contact => self.contact += 1,
            RefactorReason::Rank => self.rank += 1,
        }
    }

    pub fn add(&mut self, other: &RefactorCounts) {
        self.step += other.step;
        self.grout += other.grout;
        self.contact += other.contact;
        self.rank += other.rank;
    }
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

/// Solves the step with the configured method; `states` are updated only on
/// success. `prepared`: `live.solver` already holds the factor of
/// [`Prepared::m`], made before the step (the active set starts from it;
/// the cone program factorises its own matrix and ignores it).
pub fn solve(
    sys: &StepSystem,
    live: &mut LiveSystem,
    states: &mut [JointPointState],
    settings: &JointSolveSettings,
    prepared: Option<Prepared>,
) -> Result<JointStepOutcome, JointStepError> {
    let mut trial = Trial {
        old: states.to_vec(),
        work: states.to_vec(),
        out: JointStepOutcome::default(),
    };
    let x = match settings.method {
        ContactSolverKind::ActiveSet => active_set(sys, live, settings, &mut trial, prepared)?,
        ContactSolverKind::Qp => condensed_qp(sys, live, settings, &mut trial)?,
    };
    states.copy_from_slice(&trial.work);
    Ok(JointStepOutcome { x, ..trial.out })
}

/// A factorisation made before its step: the step's K̃ with the grout
/// springs and constrained rows of a guess of the states, which the step's
/// passes then correct from (exactly, [`crate::fem::capacitance`]) like
/// any other change of rows. Made by [`super::ahead`] on the other core
/// while the step before runs its passes.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// the rows held (supports and the guess's closed points)
    pub fixed: Vec<bool>,
    /// per live pair: an intact grout layer's springs are on its diagonal
    pub springs: Vec<bool>,
    /// K̃ with those springs, before the rows are held: its diagonal
    pub base_diag: Vec<f64>,
    /// the matrix factorised: K̃ with the springs, the rows `fixed` identity
    pub m: SparseSym,
}

impl Prepared {
    /// The matrix a step with stiffness `a` factorises first when its
    /// states start as `states`: their rows held ([`start_rows`]).
    pub fn first_pass(a: &SparseSym, live: &LiveSystem, states: &[JointPointState]) -> Prepared {
        let (fixed, springs) = start_rows(live, states);
        let with = with_springs(a, live, states);
        let base_diag = with.diag();
        let mut m = with;
        m.apply_dirichlet(&fixed);
        Prepared {
            fixed,
            springs,
            base_diag,
            m,
        }
    }
}

/// The states a step's first pass tries: the last step's, a point that
/// slipped in it as a stick trial (the return mapping of
/// [`ActiveSet::start`]).
fn first_guess(live: &LiveSystem, old: &[JointPointState]) -> Vec<JointPointState> {
    let mut work = old.to_vec();
    for p in &live.pairs {
        let st = &mut work[p.point as usize];
        if st.state == PointState::Slip {
            st.state = PointState::Stick;
        }
    }
    work
}

/// The rows a step's first factor holds with the correction on: those of
/// the step's start states, where a point that slipped holds its normal
/// row alone although the first pass tries it stuck ([`first_guess`]).
/// Most such points slip again, so the first pass corrects their held
/// tangential rows (the columns a stuck point's release needs anyway) and
/// the passes after it correct only the few that stick; a factor of the
/// stick trials had every slipping point's two rows released in every
/// later pass (a late day of the Xiaowan-like arch: corrections of rank
/// ~1,150 against ~150–540). The answer is the same: the correction is
/// exact. Where the first pass's correction would have fewer than
/// [`START_ROWS_FROM`] rows, or cost more than a factorisation (thousands
/// of points slipped), the first pass's own rows, as the exact path (no
/// correction) always factorises.
fn start_rows(live: &LiveSystem, states: &[JointPointState]) -> (Vec<bool>, Vec<bool>) {
    let (start, springs) = guess_rows(live, states);
    let (trial, _) = guess_rows(live, &first_guess(live, states));
    let corrected: Vec<u32> = (0..start.len() as u32)
        .filter(|&i| start[i as usize] != trial[i as usize])
        .collect();
    let (flops, bytes) = columns_cost(&live.solver, &corrected, corrected.len(), 0);
    if corrected.len() < START_ROWS_FROM || past_break_even(live, flops, corrected.len(), bytes) {
        (trial, springs)
    } else {
        (start, springs)
    }
}

/// Whether a correction of `rank` rows whose new columns cost
/// `column_flops` would cost more than a factorisation of `live`'s
/// system, or hold more than [`CAPACITANCE_MAX_BYTES`] with `bytes`.
fn past_break_even(live: &LiveSystem, column_flops: f64, rank: usize, bytes: usize) -> bool {
    let rank = rank as f64;
    let cost = column_flops * CAPACITANCE_SOLVE_WEIGHT + rank * rank * rank / 3.0;
    cost > live.solver.factor_flops() || bytes > CAPACITANCE_MAX_BYTES
}

/// The rows a guess holds (the supports, all three of a stick point, the
/// normal one of a slipping point) and its intact grout layers, per live pair.
fn guess_rows(live: &LiveSystem, work: &[JointPointState]) -> (Vec<bool>, Vec<bool>) {
    let mut fixed = live.supported.clone();
    let mut springs = vec![false; live.pairs.len()];
    for (q, pair) in live.pairs.iter().enumerate() {
        let f = pair.first as usize;
        match work[pair.point as usize].state {
            PointState::Open => {}
            PointState::Stick => fixed[f..f + 3].iter_mut().for_each(|v| *v = true),
            PointState::Slip => fixed[f + 2] = true,
            PointState::Grouted => springs[q] = true,
        }
    }
    (fixed, springs)
}

/// The states a joint solve starts from, the states it tries, and its counters.
struct Trial {
    /// the states at the start of the step: the forces and gaps of the step
    /// are changes of these
    old: Vec<JointPointState>,
    /// the states being tried, the caller's only once the solve succeeds
    work: Vec<JointPointState>,
    out: JointStepOutcome,
}

/// Largest force of the step: right-hand side and committed contact forces.
fn force_scale(b: &[f64], live: &LiveSystem, states: &[JointPointState]) -> f64 {
    let fb = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    fb.max(largest_joint_force(live, states))
        .max(f64::MIN_POSITIVE)
}

/// Largest component of the live pairs' forces in `states`.
fn largest_joint_force(live: &LiveSystem, states: &[JointPointState]) -> f64 {
    live.pairs
        .iter()
        .flat_map(|p| states[p.point as usize].force)
        .fold(0.0f64, |m, v| m.max(v.abs()))
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

/// A contact pass's solution `x` and `ax` = A x, A the pass's matrix (K̃
/// with the springs of its grouted points, before its rows are held): the
/// product its residual check computed, from which the reactions are read
/// rather than from a second product (one sweep of K̃ a pass, 1.7 % of the
/// demo's run).
struct PassSolution {
    x: Vec<f64>,
    ax: Vec<f64>,
}

/// The contact reaction and the gap of each live pair at a pass's solution:
/// r = r_old + K̃x − b on the pair's relative rows (a supported row carries
/// a support reaction, not contact: zero), g = g_start + x_n. K̃x is A x
/// less the springs `a` adds to K̃'s diagonal.
fn pass_reactions(
    sys: &StepSystem,
    live: &LiveSystem,
    trial: &Trial,
    a: &SparseSym,
    sol: &PassSolution,
) -> Vec<([f64; 3], f64)> {
    let (x, ax) = (&sol.x, &sol.ax);
    let kx = |i: usize| {
        let spring = a.diag_at(i) - sys.a.diag_at(i);
        if spring == 0.0 {
            ax[i]
        } else {
            ax[i] - spring * x[i]
        }
    };
    live.pairs
        .iter()
        .map(|pair| {
            let (p, f) = (pair.point as usize, pair.first as usize);
            let old = &trial.old[p];
            let reaction = std::array::from_fn(|k| {
                if live.supported[f + k] {
                    0.0
                } else {
                    old.force[k] + kx(f + k) - sys.b[f + k]
                }
            });
            (reaction, start_gap(old, &trial.work[p]) + x[f + 2])
        })
        .collect()
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

/// Numeric factorisation of `m` on the live system's symbolic analysis, timed.
fn factorize(
    live: &mut LiveSystem,
    m: &SparseSym,
    out: &mut JointStepOutcome,
) -> Result<(), JointStepError> {
    let t = Instant::now();
    live.solver.factorize(m)?;
    out.seconds_numeric += t.elapsed().as_secs_f64();
    out.factorizations += 1;
    Ok(())
}

/// Solves with the factor of `m`; a solution that does not satisfy `m`
/// to [`RESIDUAL_TOLERANCE`] is an error.
fn solve_checked(
    live: &LiveSystem,
    m: &SparseSym,
    rhs: &[f64],
    out: &mut JointStepOutcome,
) -> Result<Vec<f64>, JointStepError> {
    let mut x = rhs.to_vec();
    live.solver.solve_in_place(&mut x)?;
    out.solves += 1;
    let res = relative_residual(m, &x, rhs);
    let norm = res * rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
    accept(res, norm, m, &vec![false; live.n], x)
}

/// Solves the system of `a` with the rows `fixed` held at `presc` (loads
/// `rhs` before the held columns' are moved to it) by the factor in `live`,
/// which must be of exactly that system, and checks it with the one
/// product A x the reactions read too ([`held_residual`]).
fn solve_held(
    live: &LiveSystem,
    a: &SparseSym,
    fixed: &[bool],
    presc: &[f64],
    rhs: &[f64],
    out: &mut JointStepOutcome,
) -> Result<PassSolution, JointStepError> {
    let b = constrained_rhs(a, fixed, presc, rhs);
    let mut x = b.clone();
    live.solver.solve_in_place(&mut x)?;
    out.solves += 1;
    let (relative, norm, ax) = held_residual(a, fixed, presc, rhs, &b, &x);
    let x = accept(relative, norm, a, fixed, x)?;
    Ok(PassSolution { x, ax })
}

/// A pass's solution `x` of the system of `a` with the rows `fixed` held,
/// if its residual (`relative` to the constrained right-hand side b, of
/// 2-norm `norm`) passes [`RESIDUAL_TOLERANCE`]. When b holds little but
/// prescribed displacements (a motion imposed without loads: ‖b‖ is then
/// metres, not newtons) the residual is measured instead against the
/// forces the solution sums, ‖(|A||x|)_free‖: the normwise backward error.
/// Seen in `joint_friction`: 1.6e-11 N of residual, 5.2e-7 of a ‖b‖ of
/// 3e-5 but 4e-17 of the 4e5 N the rows sum; an exact solution to
/// round-off, which a solve that happened to cancel exactly had passed.
fn accept(
    relative: f64,
    norm: f64,
    a: &SparseSym,
    fixed: &[bool],
    x: Vec<f64>,
) -> Result<Vec<f64>, JointStepError> {
    if relative.is_nan() {
        return Err(JointStepError::Residual(relative));
    }
    if relative <= RESIDUAL_TOLERANCE {
        return Ok(x);
    }
    let mut sums = vec![0.0; a.n()];
    a.abs_mul_vec(&x, &mut sums);
    let forces = (0..a.n())
        .filter(|&i| !fixed[i])
        .map(|i| sums[i] * sums[i])
        .sum::<f64>()
        .sqrt();
    if norm <= RESIDUAL_TOLERANCE * forces {
        Ok(x)
    } else {
        Err(JointStepError::Residual(relative))
    }
}

/// The open/stick/slip state iteration (see the module doc); returns the
/// step's solution.
fn active_set(
    sys: &StepSystem,
    live: &mut LiveSystem,
    s: &JointSolveSettings,
    trial: &mut Trial,
    prepared: Option<Prepared>,
) -> Result<Vec<f64>, JointStepError> {
    let mut it = ActiveSet::start(sys, live, s, trial, prepared);
    let mut last_changes = 0;
    for pass in 1..=s.max_iterations {
        trial.out.iterations = pass;
        let factorised_before = trial.out.factorizations;
        if it.pivoting.is_some_and(|b| b.last_wrong > 0) && pass > s.max_iterations / 2 {
            it = it.restart_without_pivoting(sys, live, s, trial);
        }
        let pass_refine = Refine {
            to: it.pass_refine_to(),
            from: None,
        };
        let (mut sol, mut loose) = it.solve_guess(sys, live, trial, pass_refine)?;
        loop {
            let mut outcome = it.correct_states(sys, live, s, trial, &sol);
            outcome.changes += crack(live, sys.points, &mut trial.work, s.bond_strength, sys.day);
            match it.next_slip_forces(live, trial, outcome) {
                Some((kind, changes)) => {
                    last_changes = changes;
                    let record = it.record(live, trial, kind, changes, factorised_before);
                    trial.out.passes.push(record);
                    break;
                }
                // the states hold: the same system refined to the answer's
                // tolerance, and its states checked again
                None if loose => {
                    let last = Refine {
                        to: REFINE_TO,
                        from: Some(sol.x),
                    };
                    (sol, _) = it.solve_guess(sys, live, trial, last)?;
                    loose = false;
                }
                None => {
                    it.record_kept_closed(sys, live, trial);
                    let record = it.record(live, trial, PassKind::Answer, 0, factorised_before);
                    trial.out.passes.push(record);
                    return Ok(sol.x);
                }
            }
        }
    }
    Err(JointStepError::NotConverged {
        iterations: s.max_iterations,
        changes: last_changes,
    })
}

/// The working data of the active-set iteration of one step.
struct ActiveSet {
    /// Coulomb coefficient a stick trial is held to, per live pair: μ_k for
    /// a point that slipped in the last step, μ_s for one at rest
    limit: Vec<f64>,
    /// friction force of each slipping point used in the current pass (of
    /// a coupled one: the force its solution applied)
    slip_force: Vec<[f64; 2]>,
    /// per live pair: a slipping point's friction force μ_k r_n(x) s is
    /// solved with the pass (a [`Coupling`] of its tangential rows to its
    /// normal reaction) rather than iterated; off for a point that slipped
    /// in tension (its force is then held at zero, μ_k max(r_n, 0))
    coupled: Vec<bool>,
    /// per live pair: its slip force was coupled in the last pass
    coupled_in_pass: Vec<bool>,
    mu_kinetic: f64,
    /// open ↔ closed and slip → stick switches so far, per live pair
    flips: Vec<usize>,
    /// a point has reached [`MAX_FLIPS`]
    cycling: bool,
    /// cycling points (at the flip limit) whose normal state this pass
    /// found wrong: the one of least index switches (Murty's rule)
    pending: Vec<usize>,
    /// single switches left before a cycling point is kept as it is
    pivots_left: usize,
    /// with friction, once a point cycles: how the normal states switch
    pivoting: Option<BlockPivoting>,
    /// false once the step has restarted without [`BlockPivoting`]
    may_pivot: bool,
    /// force below which a reaction counts as zero \[N\]
    tol_f: f64,
    /// the step's force tolerance (relative)
    force_tolerance: f64,
    /// gap below which an open point closes \[m\]
    tol_g: f64,
    frictionless: bool,
    anderson: Anderson,
    /// the slip forces' secants of the step's earlier rounds
    secants: RoundSecants,
    /// the grout springs of the factor in `live` and the correction of
    /// its constrained rows and springs to the current guess's
    factored: Option<(Vec<bool>, Capacitance)>,
    /// the grout springs of the current guess (per live pair): those of
    /// `a_cur`
    springs: Vec<bool>,
    /// K̃ with the springs of the current guess, before its Dirichlet rows
    a_cur: SparseSym,
    /// correct a changed set of constrained rows instead of refactorising
    capacitance: bool,
    /// rank and couplings of the last pass's correction
    /// ([`PassRecord::rank`])
    last_correction: (usize, usize),
    /// the slip forces' fixed-point residual after the last pass, in
    /// [`ActiveSet::friction_tolerance`]s (infinite after a change of
    /// states)
    slip_residual: f64,
}

/// What correcting the states after a pass found.
struct PassOutcome {
    /// points that changed state
    changes: usize,
    /// the slip forces the pass's reactions call for (the fixed-point map)
    mapped: Vec<[f64; 2]>,
    /// slipping points that moved with their friction force: they stick
    /// once the slip forces have settled
    reversed: Vec<usize>,
    /// points left in a wrong normal state while the friction settles
    /// ([`BlockPivoting::hold`])
    held: usize,
}

/// How a frictional step whose points cycle switches its normal states:
/// block principal pivoting with Murty's least-index safeguard (Júdice and
/// Pires, 1994), on normal states decided only once the friction forces
/// have settled on them.
///
/// Opening a point releases its shear as well as its pressure, and
/// closing one as a stick trial adds a shear constraint, so with friction
/// the open set and the slip forces move each other. Switching every wrong
/// point in every pass, as the step does before anything cycles, swings:
/// the demo's complete dam loaded at once opened and re-closed hundreds of
/// points per pass and, at the flip limit, kept 500 of its 1,552 points
/// closed in tension up to 7.7 MPa. Here a pass switches no normal state
/// until the slip forces have settled ([`NORMAL_SETTLED_FACTOR`];
/// `hold`); then every wrong point switches while the count of wrong
/// points reaches a new least within [`BLOCK_PASSES`] passes, else only
/// the one of least index (`single`), which ends for a P-matrix (the
/// frictionless normal problem; with friction it is a safeguard, not a
/// proof). The slipping points found moving with their friction force
/// stick in that same pass: sticking them in settling rounds of their own
/// (before 29 Nov 2026) restarted the slip forces' mixing for each batch
/// while the count of wrong normal states did not move (on the
/// Xiaowan-like complete dam, 2,560 from pass 44 to 85 while 38, 5, 3, 1
/// and 1 points stuck). Measured on the demo's complete dam (29 Nov
/// 2026): self-weight at once 66 passes and 10 factorisations (88 with
/// the rounds of their own, 29 and 12 with the flip limit alone), no
/// tension kept against 7.7 MPa; weight, water and cooling at once
/// (`hard_cases`) 37 passes (54), tension 0 against 1.5 MPa. Past half
/// the step's passes the step starts again under the flip limit's rule
/// alone. On the Xiaowan-like complete dam under its weight (15,729
/// points) the rounds take 7–12 passes each (wrong points 6,602, 2,678,
/// 1,042, 484, 324, 183, 98, 85, 41, 24, 10, 1, 1, 0) and the step ends
/// at pass 149 with no tension kept, where the rounds of their own took
/// 259 (`study::COMPLETE_STEP_MAX_PASSES` allows 600).
#[derive(Debug, Clone, Copy)]
struct BlockPivoting {
    /// least count of wrong normal states after a pass that switched
    fewest_wrong: usize,
    /// the count after the last pass that switched
    last_wrong: usize,
    /// passes left that switch every wrong point without a new least
    block_passes_left: usize,
    /// this pass switches the wrong point of least index only
    single: bool,
    /// this pass switches no normal state: the friction is settling
    hold: bool,
    /// the last pass left the friction states and forces settled
    settled: bool,
}

impl BlockPivoting {
    fn new() -> Self {
        BlockPivoting {
            fewest_wrong: usize::MAX,
            last_wrong: usize::MAX,
            block_passes_left: BLOCK_PASSES,
            single: false,
            hold: true,
            settled: false,
        }
    }

    /// Every wrong point switches while the count falls to a new least
    /// within [`BLOCK_PASSES`] passes, else one.
    fn choose(&mut self, wrong: usize) {
        self.last_wrong = wrong;
        if wrong < self.fewest_wrong {
            self.fewest_wrong = wrong;
            self.block_passes_left = BLOCK_PASSES;
            self.single = false;
        } else if self.block_passes_left > 0 {
            self.block_passes_left -= 1;
            self.single = false;
        } else {
            self.single = true;
        }
    }
}

impl ActiveSet {
    /// The first guess: the last step's states, a point that slipped in the
    /// last step as a stick trial.
    fn start(
        sys: &StepSystem,
        live: &LiveSystem,
        s: &JointSolveSettings,
        trial: &mut Trial,
        prepared: Option<Prepared>,
    ) -> Self {
        let old = &trial.old;
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
        trial.work = first_guess(live, old);
        let (_, springs) = guess_rows(live, &trial.work);
        let f_scale = force_scale(sys.b, live, old);
        let slip_force = live
            .pairs
            .iter()
            .map(|p| {
                let st = &old[p.point as usize];
                let mag = s.mu_kinetic * st.force[2].max(0.0);
                [mag * st.slip_dir[0], mag * st.slip_dir[1]]
            })
            .collect();
        let mut it = ActiveSet {
            limit: kinetic
                .iter()
                .map(|&k| if k { s.mu_kinetic } else { s.mu_static })
                .collect(),
            slip_force,
            coupled: vec![s.mu_kinetic > 0.0; live.pairs.len()],
            coupled_in_pass: vec![false; live.pairs.len()],
            mu_kinetic: s.mu_kinetic,
            flips: vec![0usize; live.pairs.len()],
            cycling: false,
            pending: Vec::new(),
            pivoting: None,
            may_pivot: true,
            // Least-index switching ends only without friction (see `pivot`).
            pivots_left: if s.mu_static == 0.0 {
                s.max_iterations / 2
            } else {
                0
            },
            tol_f: s.force_tolerance * f_scale,
            force_tolerance: s.force_tolerance,
            tol_g: s.gap_tolerance,
            frictionless: s.mu_static == 0.0,
            anderson: Anderson::new(ANDERSON_DEPTH),
            secants: RoundSecants::new(2 * live.pairs.len(), SECANT_DEPTH),
            factored: None,
            a_cur: with_springs(sys.a, live, &trial.work),
            springs,
            capacitance: s.capacitance,
            last_correction: (0, 0),
            slip_residual: f64::INFINITY,
        };
        // the prepared matrix was factorised already: not kept
        if let Some(p) = prepared {
            it.factored = Some((p.springs, Capacitance::with_diagonal(p.fixed, p.base_diag)));
        }
        it
    }

    /// The step started again from its first guess under the flip limit's
    /// rule alone, keeping the factor: [`BlockPivoting`] has not ended in
    /// half the passes (normal states still wrong: a step whose rounds
    /// have ended and whose slip forces are settling goes on). Continuing from where block pivoting left the
    /// states did not end either (the Xiaowan-like complete dam: not in
    /// the 150 passes left, where the rule from the start takes 85).
    fn restart_without_pivoting(
        mut self,
        sys: &StepSystem,
        live: &LiveSystem,
        s: &JointSolveSettings,
        trial: &mut Trial,
    ) -> Self {
        let mut it = ActiveSet::start(sys, live, s, trial, None);
        it.factored = self.factored.take();
        it.may_pivot = false;
        it
    }

    /// Solves the system of the guessed states: closed points are Dirichlet
    /// rows of their own unknowns, slip forces and old forces loads;
    /// refactorises only when the constrained rows or springs change.
    fn solve_guess(
        &mut self,
        sys: &StepSystem,
        live: &mut LiveSystem,
        trial: &mut Trial,
        refine: Refine,
    ) -> Result<(PassSolution, bool), JointStepError> {
        let (fixed, springs) = guess_rows(live, &trial.work);
        self.factor_for(sys, live, trial, &fixed, springs)?;
        // the slip forces with the pass while their border costs less than
        // a factorisation (else the fixed point of `next_slip_forces`);
        // decided on the states and the live system alone, so the exact
        // path and the correction decide alike. A coupling's new column is
        // its reaction row's: a point that slips from a stick trial (the
        // usual case) already has its tangential rows' columns, as
        // released rows, and its loads fall on them. Counting those too
        // (before 29 Nov 2026) never coupled the Xiaowan-like arch's late
        // days; coupled, days 913–916 took 35 passes against 49 and their
        // joints 31.1 against 34.3 s (run alternately; the demo's whole
        // construction the same to the last digit of `apertures.csv`).
        let slipping: Vec<u32> = live
            .pairs
            .iter()
            .enumerate()
            .filter(|&(q, pair)| {
                trial.work[pair.point as usize].state == PointState::Slip
                    && self.can_couple(live, q)
            })
            .map(|(_, pair)| pair.first)
            .collect();
        let k = slipping.len() as f64;
        let border_flops: f64 = slipping
            .iter()
            .map(|&f| {
                let (flops, rows) = live.solver.reach_cost(f as usize + 2);
                flops + 2.0 * rows as f64 * 3.0 * k
            })
            .sum();
        let direct = border_flops * COUPLING_SOLVE_WEIGHT + 2.0 / 3.0 * k.powi(3)
            <= live.solver.factor_flops();
        let (presc, rhs, couplings) = self.pass_loads(sys, live, trial, direct);
        let Some((factored_springs, cap)) = self.factored.as_mut() else {
            unreachable!("factorised above")
        };
        if couplings.is_empty()
            && cap.base() == fixed.as_slice()
            && &self.springs == factored_springs
        {
            let sol = solve_held(live, &self.a_cur, &fixed, &presc, &rhs, &mut trial.out)?;
            self.last_correction = (0, 0);
            return Ok((sol, false));
        }
        let before = cap.stats;
        let loose = refine.to > REFINE_TO;
        let corrected = cap.solve(
            &live.solver,
            &self.a_cur,
            &fixed,
            &presc,
            &rhs,
            &couplings,
            refine,
        )?;
        trial.out.capacitance.add(&cap.stats.since(&before));
        trial.out.solves += 1;
        self.last_correction = (corrected.rank, corrected.couplings);
        // the residual on the system of this pass's rows, as a fresh factor's
        // (the correction's last refinement measured it)
        let x = accept(
            corrected.residual,
            corrected.residual_norm,
            &self.a_cur,
            &fixed,
            corrected.x,
        )?;
        Ok((
            PassSolution {
                x,
                ax: corrected.ax,
            },
            loose,
        ))
    }

    /// The residual a pass is refined to: the answer's once the slip
    /// forces are near settling ([`FINE_PASS_FACTOR`]).
    fn pass_refine_to(&self) -> f64 {
        if self.slip_residual <= FINE_PASS_FACTOR {
            REFINE_TO
        } else {
            PASS_REFINE_TO
        }
    }

    /// Makes `a_cur` the matrix of a pass holding the rows `fixed` with the
    /// grout `springs`, and refactorises when the factor cannot serve it
    /// ([`ActiveSet::refactor_reason`]).
    fn factor_for(
        &mut self,
        sys: &StepSystem,
        live: &mut LiveSystem,
        trial: &mut Trial,
        fixed: &[bool],
        springs: Vec<bool>,
    ) -> Result<(), JointStepError> {
        if self.springs != springs {
            // the matrix of this pass: the factor's, or the one the
            // correction solves (springs as a diagonal change)
            self.a_cur = with_springs(sys.a, live, &trial.work);
            self.springs = springs;
        }
        if let Some(reason) = self.refactor_reason(live, fixed) {
            let held = if reason == RefactorReason::Step && self.capacitance {
                start_rows(live, &trial.old).0
            } else {
                fixed.to_vec()
            };
            let mut m = self.a_cur.clone();
            m.apply_dirichlet(&held);
            factorize(live, &m, &mut trial.out)?;
            trial.out.refactor_reasons.count(reason);
            let base_diag = self.a_cur.diag();
            self.factored = Some((
                self.springs.clone(),
                Capacitance::with_diagonal(held, base_diag),
            ));
        }
        Ok(())
    }

    /// The prescribed values, loads and couplings of the guessed states: a
    /// closed point's gap closes (x_n = −g_old), an open one sheds its old
    /// force, a slipping one carries its friction force, `direct`ly as a
    /// coupling to its normal reaction where [`ActiveSet::coupled`] allows,
    /// else the force of the fixed point's current iterate.
    fn pass_loads(
        &mut self,
        sys: &StepSystem,
        live: &LiveSystem,
        trial: &Trial,
        direct: bool,
    ) -> (Vec<f64>, Vec<f64>, Vec<Coupling>) {
        let (old, work) = (&trial.old, &trial.work);
        let mut presc = sys.prescribed.to_vec();
        let mut rhs = sys.b.to_vec();
        let mut couplings = Vec::new();
        self.coupled_in_pass.fill(false);
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
                PointState::Stick => presc[f + 2] = -g_old,
                PointState::Slip if direct && self.can_couple(live, q) => {
                    presc[f + 2] = -g_old;
                    // μ_k s r_n with r_n = r_old_n + (K̃x)_n − b_n: the
                    // constant part here, (K̃x)_n through the coupling
                    let mu = self.mu_kinetic;
                    let held = mu * (r_old[2] - sys.b[f + 2]);
                    for k in 0..2 {
                        rhs[f + k] += held * st.slip_dir[k] - r_old[k];
                    }
                    self.coupled_in_pass[q] = true;
                    couplings.push(Coupling {
                        reaction_row: (f + 2) as u32,
                        loads: vec![
                            (f as u32, mu * st.slip_dir[0]),
                            ((f + 1) as u32, mu * st.slip_dir[1]),
                        ],
                    });
                }
                PointState::Slip => {
                    presc[f + 2] = -g_old;
                    for k in 0..2 {
                        rhs[f + k] += self.slip_force[q][k] - r_old[k];
                    }
                }
                PointState::Grouted => {}
            }
        }
        (presc, rhs, couplings)
    }

    /// Whether slipping pair `q`'s friction force may be a coupling: it
    /// has not slipped in tension and its normal reaction is not a
    /// support's.
    fn can_couple(&self, live: &LiveSystem, q: usize) -> bool {
        self.coupled[q] && !live.supported[live.pairs[q].first as usize + 2]
    }

    /// Why the factor in `live` cannot serve the guess with rows `fixed`
    /// constrained and the grout springs of `self.a_cur`, or `None` when it
    /// can (directly or through the capacitance correction).
    fn refactor_reason(&self, live: &LiveSystem, fixed: &[bool]) -> Option<RefactorReason> {
        let Some((factored_springs, cap)) = &self.factored else {
            return Some(RefactorReason::Step);
        };
        let same_springs = &self.springs == factored_springs;
        if cap.base() == fixed && same_springs {
            return None;
        }
        if !self.capacitance {
            return Some(if same_springs {
                RefactorReason::Contact
            } else {
                RefactorReason::Grout
            });
        }
        let changes = cap.changes(&self.a_cur, fixed);
        let (column_flops, column_bytes) = cap.new_columns_cost(&live.solver, &changes);
        let memory = cap.memory_bytes() + column_bytes;
        if past_break_even(live, column_flops, changes.len(), memory) {
            Some(RefactorReason::Rank)
        } else {
            None
        }
    }

    /// Corrects the guessed states from the gaps and reactions of the pass's
    /// solution `x`.
    fn correct_states(
        &mut self,
        sys: &StepSystem,
        live: &LiveSystem,
        s: &JointSolveSettings,
        trial: &mut Trial,
        sol: &PassSolution,
    ) -> PassOutcome {
        let at = pass_reactions(sys, live, trial, &self.a_cur, sol);
        let x = &sol.x;
        self.choose_pivoting(live, s, trial, &at);
        let mut outcome = PassOutcome {
            changes: 0,
            mapped: self.slip_force.clone(),
            reversed: Vec::new(),
            held: 0,
        };
        for (q, (pair, &(reaction, gap))) in live.pairs.iter().zip(&at).enumerate() {
            let p = pair.point as usize;
            let f = pair.first as usize;
            let r_old = trial.old[p].force;
            let xd = [x[f], x[f + 1], x[f + 2]];
            let st = &mut trial.work[p];
            st.gap = gap;
            match st.state {
                PointState::Open => {
                    st.force = [0.0; 3];
                    if self.overlaps(st.gap) {
                        // Out of single switches, a cycling point closes
                        // as before the limit: the closed state ends the cycle.
                        if !self.held(q) || self.may_only_close() {
                            self.flip(q);
                            st.state = self.closed_state();
                            outcome.changes += 1;
                        } else {
                            self.pending.push(q);
                        }
                    }
                }
                PointState::Stick => self.check_stick(q, st, reaction, s, &mut outcome),
                PointState::Slip => self.check_slip(q, st, reaction, xd, s, &mut outcome),
                PointState::Grouted => {
                    let k = st.grout.map_or([0.0; 3], |g| g.stiffness);
                    st.force = std::array::from_fn(|i| r_old[i] - k[i] * xd[i]);
                }
            }
        }
        self.pivot(live, trial, &mut outcome);
        outcome
    }

    /// An open point whose gap overlaps: it should close.
    fn overlaps(&self, gap: f64) -> bool {
        gap < -self.tol_g
    }

    /// A closed point pulled apart: it should open.
    fn in_tension(&self, reaction: [f64; 3]) -> bool {
        reaction[2] < -self.tol_f
    }

    /// One more open ↔ closed or slip → stick switch of `q`.
    fn flip(&mut self, q: usize) {
        self.flips[q] += 1;
        self.cycling |= self.flips[q] >= MAX_FLIPS;
    }

    /// Slip-force residual, in force tolerances, at which the reversed
    /// points stick: [`NORMAL_SETTLED_FACTOR`] once [`BlockPivoting`]
    /// decides the normal states on it, else [`SETTLED_FACTOR`].
    fn settled_factor(&self) -> f64 {
        if self.pivoting.is_some() {
            NORMAL_SETTLED_FACTOR
        } else {
            SETTLED_FACTOR
        }
    }

    /// True when this pass may not switch the normal state of `q` on its
    /// own: it is cycling, or [`BlockPivoting`] holds or pivots singly.
    fn held(&self, q: usize) -> bool {
        match self.pivoting {
            Some(b) => b.single || b.hold,
            None => self.flips[q] >= MAX_FLIPS,
        }
    }

    /// A held open point with an overlap closes anyway: the single
    /// switches have run out (unless the friction is still settling).
    fn may_only_close(&self) -> bool {
        self.pivots_left == 0 && !self.pivoting.is_some_and(|b| b.hold)
    }

    /// Starts [`BlockPivoting`] when, with friction, a point has reached
    /// [`MAX_FLIPS`] (its single switches: half the passes; past them the
    /// step restarts without it, [`ActiveSet::restart_without_pivoting`]),
    /// and decides how this pass switches normal states from the pass's
    /// reactions and gaps `at`.
    fn choose_pivoting(
        &mut self,
        live: &LiveSystem,
        s: &JointSolveSettings,
        trial: &mut Trial,
        at: &[([f64; 3], f64)],
    ) {
        if self.pivoting.is_none() && self.may_pivot && !self.frictionless && self.cycling {
            self.pivoting = Some(BlockPivoting::new());
            self.pivots_left = s.max_iterations / 2;
            trial.out.block_pivoting = true;
        }
        let Some(mut b) = self.pivoting else {
            return;
        };
        b.hold = !b.settled;
        b.settled = false;
        if !b.hold {
            b.choose(self.wrong_normal_states(live, trial, at));
        }
        self.pivoting = Some(b);
    }

    /// Points whose normal state the pass finds wrong: closed in tension,
    /// or open with an overlap.
    fn wrong_normal_states(
        &self,
        live: &LiveSystem,
        trial: &Trial,
        at: &[([f64; 3], f64)],
    ) -> usize {
        let wrong = |&(pair, &(reaction, gap)): &(&super::live::LivePair, &([f64; 3], f64))| {
            !live.supported[pair.first as usize + 2]
                && match trial.work[pair.point as usize].state {
                    PointState::Open => self.overlaps(gap),
                    PointState::Stick | PointState::Slip => self.in_tension(reaction),
                    PointState::Grouted => false,
                }
        };
        live.pairs.iter().zip(at).filter(wrong).count()
    }

    /// The state a point closes in.
    fn closed_state(&self) -> PointState {
        if self.frictionless {
            PointState::Slip
        } else {
            PointState::Stick
        }
    }

    /// Switches the normal state of the cycling point of least index that
    /// this pass found wrong, if any. Switching one cycling point at a time,
    /// always the least index, ends for the frictionless normal problem (its
    /// Delassus operator is positive definite: Murty's least-index
    /// principal pivoting); the other points keep switching together, so
    /// the bulk of the set still settles in a few passes. With friction the
    /// rule has no such guarantee (measured: μ = 1.5 on a staged three-block
    /// dam switched for tens of passes); there it is the safeguard of
    /// [`BlockPivoting`], and a pass that holds every normal state while
    /// the friction settles switches none. When the single switches run
    /// out (`pivots_left`, half the pass budget), a cycling point may only
    /// close, as the flip limit alone did, and a tension it keeps is
    /// reported (`kept_closed_tension`).
    fn pivot(&mut self, live: &LiveSystem, trial: &mut Trial, outcome: &mut PassOutcome) {
        let pending = std::mem::take(&mut self.pending);
        if self.pivoting.is_some_and(|b| b.hold) {
            outcome.held = pending.len();
            return;
        }
        let Some(&q) = pending.iter().min() else {
            return;
        };
        if self.pivots_left == 0 {
            return;
        }
        self.pivots_left -= 1;
        self.flip(q);
        let st = &mut trial.work[live.pairs[q].point as usize];
        st.state = if st.state == PointState::Open {
            self.closed_state()
        } else {
            st.force = [0.0; 3];
            PointState::Open
        };
        outcome.changes += 1;
    }

    /// A sticking point opens under tension or slips when its tangential
    /// reaction exceeds its Coulomb limit.
    fn check_stick(
        &mut self,
        q: usize,
        st: &mut JointPointState,
        reaction: [f64; 3],
        s: &JointSolveSettings,
        outcome: &mut PassOutcome,
    ) {
        st.force = reaction;
        st.gap = 0.0;
        let rt = [reaction[0], reaction[1]];
        let tension = self.in_tension(reaction);
        if tension && self.held(q) {
            self.pending.push(q);
        }
        if tension && !self.held(q) {
            self.flip(q);
            st.state = PointState::Open;
            outcome.changes += 1;
        } else if norm2(rt) > self.limit[q] * reaction[2].max(0.0) + self.tol_f {
            let mag = norm2(rt);
            st.slip_dir = [rt[0] / mag, rt[1] / mag];
            st.state = PointState::Slip;
            let fs = s.mu_kinetic * reaction[2].max(0.0);
            outcome.mapped[q] = [fs * st.slip_dir[0], fs * st.slip_dir[1]];
            outcome.changes += 1;
        }
    }

    /// A slipping point opens under tension; otherwise its slip force is
    /// mapped from its normal reaction, and one moving with its friction
    /// force is marked to stick.
    fn check_slip(
        &mut self,
        q: usize,
        st: &mut JointPointState,
        reaction: [f64; 3],
        xd: [f64; 3],
        s: &JointSolveSettings,
        outcome: &mut PassOutcome,
    ) {
        if self.coupled_in_pass[q] {
            // the force the pass applied: μ_k r_n s of its own solution
            let mag = s.mu_kinetic * reaction[2];
            self.slip_force[q] = [mag * st.slip_dir[0], mag * st.slip_dir[1]];
        }
        let slip_force = self.slip_force[q];
        st.force = [slip_force[0], slip_force[1], reaction[2]];
        st.gap = 0.0;
        let slip = [xd[0], xd[1]];
        let applied = norm2(slip_force);
        let along = if applied > 0.0 {
            (slip[0] * slip_force[0] + slip[1] * slip_force[1]) / applied
        } else {
            0.0
        };
        let tension = self.in_tension(reaction);
        if reaction[2] < 0.0 && self.coupled_in_pass[q] {
            // no friction force in tension: held at μ_k max(r_n, 0) = 0
            // by the fixed point from here on
            self.coupled[q] = false;
            outcome.changes += 1;
        }
        if tension && self.held(q) {
            self.pending.push(q);
        }
        if tension && !self.held(q) {
            self.flip(q);
            st.state = PointState::Open;
            outcome.changes += 1;
        } else {
            if !self.frictionless && along > self.tol_g && self.flips[q] < MAX_FLIPS {
                // Moving with the friction force: it sticks once
                // the slip forces have settled.
                outcome.reversed.push(q);
            }
            // The direction is the trial force's for the whole
            // step (taken from each pass's slip, the iteration
            // cycles between nearby angles on 3-D joints).
            let fs = s.mu_kinetic * reaction[2].max(0.0);
            outcome.mapped[q] = [fs * st.slip_dir[0], fs * st.slip_dir[1]];
        }
    }

    /// After a pass: restarts the slip-force iteration on new states,
    /// sticks the reversed points once the slip forces have settled, or
    /// advances the slip forces by Anderson mixing. Returns what the pass
    /// was and the state changes to report if the step does not converge,
    /// or `None` when it has converged.
    fn next_slip_forces(
        &mut self,
        live: &LiveSystem,
        trial: &mut Trial,
        outcome: PassOutcome,
    ) -> Option<(PassKind, usize)> {
        let PassOutcome {
            changes,
            mapped,
            reversed,
            held,
        } = outcome;
        let slipping: Vec<usize> = (0..live.pairs.len())
            .filter(|&q| trial.work[live.pairs[q].point as usize].state == PointState::Slip)
            .collect();
        // BlockPivoting: the reversed points stick with the normal
        // switches of the pass after the friction settled, not in a
        // settling round of their own
        let holding = self.pivoting.is_some_and(|b| b.hold);
        let switching = self.pivoting.is_some_and(|b| !b.hold);
        if changes > 0 {
            let changes = if switching {
                changes + self.stick(live, trial, &reversed)
            } else {
                changes
            };
            self.slip_residual = f64::INFINITY;
            // New states: restart the slip-force iteration from their forces.
            // (Keeping Anderson's history through changes of a few points
            // was tried on the complete Xiaowan-like dam: its secants mix
            // two maps and it took 214 passes against 140. The round's
            // secants precondition the next rounds instead: `RoundSecants`.)
            self.new_round();
            for &q in &slipping {
                self.slip_force[q] = mapped[q];
            }
            return Some((PassKind::Switched, changes));
        }
        let residual = slipping
            .iter()
            .map(|&q| {
                norm2([
                    mapped[q][0] - self.slip_force[q][0],
                    mapped[q][1] - self.slip_force[q][1],
                ])
            })
            .fold(0.0, f64::max);
        let end = self.friction_tolerance(live, trial);
        self.slip_residual = residual / end;
        let settled = residual <= self.tol_f * NORMAL_SETTLED_FACTOR;
        if let (Some(b), true) = (self.pivoting.as_mut(), settled) {
            b.settled = true;
        }
        if residual <= end && reversed.is_empty() {
            // the friction holds; the held normal states switch next pass
            (held > 0).then_some((PassKind::Settled, held))
        } else if !reversed.is_empty() && !holding && residual <= self.tol_f * self.settled_factor()
        {
            self.new_round();
            self.slip_residual = f64::INFINITY;
            Some((PassKind::Switched, self.stick(live, trial, &reversed)))
        } else {
            // The slip forces are a fixed point of (forces → solve →
            // μ_k·r_n), affine for fixed directions. Anderson mixing
            // converges in a few passes where the plain iteration
            // contracts slowly (0.94 per pass measured on the small dam).
            let xs: Vec<f64> = slipping.iter().flat_map(|&q| self.slip_force[q]).collect();
            let mut fx: Vec<f64> = slipping.iter().flat_map(|&q| mapped[q]).collect();
            self.precondition(&slipping, &mapped, &mut fx);
            let next = self.anderson.next(&xs, &fx);
            for (i, &q) in slipping.iter().enumerate() {
                self.slip_force[q] = [next[2 * i], next[2 * i + 1]];
            }
            trial.out.slip_force_passes += 1;
            Some((PassKind::SlipForces, changes))
        }
    }

    /// The states changed: the slip forces' map is another one, so
    /// Anderson's history starts empty and the ended round's secants join
    /// the earlier rounds' ([`RoundSecants`]).
    fn new_round(&mut self) {
        self.anderson.clear();
        self.secants.end_round();
    }

    /// Records this pass's slip forces and their residual for the next
    /// rounds, and replaces the map's values `fx` (of the points
    /// `slipping`, in order) by x + H r, H the earlier rounds' secant
    /// inverse ([`RoundSecants`]); unchanged in a step's first round.
    fn precondition(&mut self, slipping: &[usize], mapped: &[[f64; 2]], fx: &mut [f64]) {
        let mut x = vec![0.0; self.secants.n];
        let mut r = vec![0.0; self.secants.n];
        for &q in slipping {
            for k in 0..2 {
                x[2 * q + k] = self.slip_force[q][k];
                r[2 * q + k] = mapped[q][k] - self.slip_force[q][k];
            }
        }
        if let Some(h) = self.secants.apply(&r) {
            for (i, &q) in slipping.iter().enumerate() {
                for k in 0..2 {
                    fx[2 * i + k] = self.slip_force[q][k] + h[2 * q + k];
                }
            }
        }
        self.secants.observe(x, r);
    }

    /// The residual the slip forces settle to before the step may end:
    /// the force tolerance, or that fraction of the largest joint force
    /// where that is less. A step whose loads dwarf its joint forces (the
    /// demo's complete dam cooled 10 °C at once: 3.9 N against 5.7e7 N,
    /// 6.8e-8 of it) would otherwise end with the friction law held
    /// more loosely than the tolerance asks.
    fn friction_tolerance(&self, live: &LiveSystem, trial: &Trial) -> f64 {
        self.tol_f
            .min(self.force_tolerance * largest_joint_force(live, &trial.work))
            .max(f64::MIN_POSITIVE)
    }

    /// Sticks the slipping points found moving with their friction force;
    /// returns how many.
    fn stick(&mut self, live: &LiveSystem, trial: &mut Trial, reversed: &[usize]) -> usize {
        for &q in reversed {
            trial.work[live.pairs[q].point as usize].state = PointState::Stick;
            self.flip(q);
        }
        reversed.len()
    }

    /// The log's record of the pass just ended ([`PassRecord`]);
    /// `factorised_before`: the step's factorisations when it began.
    fn record(
        &self,
        live: &LiveSystem,
        trial: &Trial,
        kind: PassKind,
        changes: usize,
        factorised_before: usize,
    ) -> PassRecord {
        let mut count = [0usize; 3];
        for pair in &live.pairs {
            match trial.work[pair.point as usize].state {
                PointState::Open => count[0] += 1,
                PointState::Stick => count[1] += 1,
                PointState::Slip => count[2] += 1,
                PointState::Grouted => {}
            }
        }
        PassRecord {
            kind,
            changes,
            open: count[0],
            stick: count[1],
            slip: count[2],
            factorised: trial.out.factorizations > factorised_before,
            rank: self.last_correction.0,
            couplings: self.last_correction.1,
            slip_residual: self.slip_residual,
            wrong_normal: self
                .pivoting
                .map(|b| b.last_wrong)
                .filter(|&w| w != usize::MAX),
        }
    }

    /// The largest tension left on a point the flip limit kept closed.
    fn record_kept_closed(&self, sys: &StepSystem, live: &LiveSystem, trial: &mut Trial) {
        for (q, pair) in live.pairs.iter().enumerate() {
            let st = &trial.work[pair.point as usize];
            if self.flips[q] >= MAX_FLIPS && st.state.is_closed() {
                let t = -st.force[2] / sys.points[pair.point as usize].area;
                trial.out.kept_closed_tension = trial.out.kept_closed_tension.max(t);
            }
        }
    }
}

/// The condensed cone program (see the module doc); returns the step's
/// solution. Cracked grout layers restart the solve with those points as
/// contacts.
fn condensed_qp(
    sys: &StepSystem,
    live: &mut LiveSystem,
    s: &JointSolveSettings,
    trial: &mut Trial,
) -> Result<Vec<f64>, JointStepError> {
    let friction = if s.mu_static == 0.0 {
        FrictionModel::Frictionless
    } else {
        FrictionModel::Coulomb {
            mu_s: s.mu_static,
            mu_k: s.mu_kinetic,
        }
    };
    for round in 0..s.max_iterations {
        let mut m = with_springs(sys.a, live, &trial.work);
        let mut rhs = sys.b.to_vec();
        m.dirichlet_correction(&live.supported, sys.prescribed, &mut rhs);
        m.apply_dirichlet(&live.supported);
        factorize(live, &m, &mut trial.out)?;
        trial.out.refactor_reasons.count(if round == 0 {
            RefactorReason::Step
        } else {
            RefactorReason::Grout
        });
        let contact: Vec<usize> = (0..live.pairs.len())
            .filter(|&q| trial.work[live.pairs[q].point as usize].state != PointState::Grouted)
            .collect();
        for &q in &contact {
            let pair = &live.pairs[q];
            for k in 0..3 {
                rhs[pair.first as usize + k] -= trial.old[pair.point as usize].force[k];
            }
        }
        for ((r, &held), &value) in rhs.iter_mut().zip(&live.supported).zip(sys.prescribed) {
            if held {
                *r = value;
            }
        }
        let mut x = solve_checked(live, &m, &rhs, &mut trial.out)?;
        if !contact.is_empty() {
            solve_contacts(live, trial, &contact, friction, &mut x)?;
        }
        for pair in &live.pairs {
            let p = pair.point as usize;
            let work = &mut trial.work[p];
            if work.state == PointState::Grouted {
                let f = pair.first as usize;
                let k = work.grout.map_or([0.0; 3], |g| g.stiffness);
                let old = &trial.old[p];
                work.force = std::array::from_fn(|i| old.force[i] - k[i] * x[f + i]);
                work.gap = old.gap + x[f + 2];
            }
        }
        if crack(live, sys.points, &mut trial.work, s.bond_strength, sys.day) == 0 {
            return Ok(x);
        }
    }
    Err(JointStepError::NotConverged {
        iterations: s.max_iterations,
        changes: 0,
    })
}

/// Reduced row of component `i` (3 per point) of the contact points.
fn contact_row(live: &LiveSystem, contact: &[usize], i: usize) -> usize {
    live.pairs[contact[i / 3]].first as usize + i % 3
}

/// The contact forces of the points `contact` (live pair slots) from the
/// cone program on W = Eᵀ K̃⁻¹ E, given `x`, the solution without them;
/// adds their displacements to `x` and sets the points' states.
fn solve_contacts(
    live: &LiveSystem,
    trial: &mut Trial,
    contact: &[usize],
    friction: FrictionModel,
    x: &mut [f64],
) -> Result<(), JointStepError> {
    let cols = 3 * contact.len();
    let mut g = faer::Mat::<f64>::zeros(live.n, cols);
    for (j, &q) in contact.iter().enumerate() {
        for k in 0..3 {
            g[(live.pairs[q].first as usize + k, 3 * j + k)] = 1.0;
        }
    }
    live.solver.solve_columns(&mut g)?;
    trial.out.solves += cols;
    let (w, held) = delassus(live, contact, &g);
    let mut b = vec![0.0; cols];
    let mut r_old = vec![0.0; cols];
    for (j, &q) in contact.iter().enumerate() {
        let p = live.pairs[q].point as usize;
        for k in 0..3 {
            b[3 * j + k] = x[contact_row(live, contact, 3 * j + k)];
            r_old[3 * j + k] = trial.old[p].force[k];
        }
        b[3 * j + 2] += start_gap(&trial.old[p], &trial.work[p]);
    }
    for i in (0..cols).filter(|&i| held[i]) {
        b[i] = 0.0;
    }
    let fr = vec![friction; contact.len()];
    let problem = ContactProblem::new(&w, &b, &fr);
    let mut sol = crate::joint::solve(&problem, &ContactSettings::default(), Some(&r_old))?;
    trial.out.iterations += sol.fixed_point_iterations;
    for i in (0..cols).filter(|&i| held[i]) {
        sol.r[i] = 0.0;
    }
    for (i, xi) in x.iter_mut().enumerate() {
        let mut acc = 0.0;
        for k in 0..cols {
            acc += g[(i, k)] * sol.r[k];
        }
        *xi += acc;
    }
    for (j, &q) in contact.iter().enumerate() {
        let st = &mut trial.work[live.pairs[q].point as usize];
        st.force = [sol.r[3 * j], sol.r[3 * j + 1], sol.r[3 * j + 2]];
        st.gap = sol.u[3 * j + 2];
        st.state = sol.states[j].into();
        let t = [st.force[0], st.force[1]];
        if st.state == PointState::Slip && norm2(t) > 0.0 {
            st.slip_dir = [t[0] / norm2(t), t[1] / norm2(t)];
        }
    }
    Ok(())
}

/// The Delassus operator W of the contact points from the solved unit
/// columns `g` (symmetrised), and which of its components a support holds.
fn delassus(
    live: &LiveSystem,
    contact: &[usize],
    g: &faer::Mat<f64>,
) -> (nalgebra::DMatrix<f64>, Vec<bool>) {
    let cols = 3 * contact.len();
    let row = |i: usize| contact_row(live, contact, i);
    let mut w =
        nalgebra::DMatrix::from_fn(cols, cols, |i, j| 0.5 * (g[(row(i), j)] + g[(row(j), i)]));
    // A relative component held by a support is not a contact
    // unknown: decouple it with a compliance of the problem's scale
    // (its identity row of the constrained matrix would otherwise read
    // 1 m/N against ~1e-10) and pin its force to zero (the caller).
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
    (w, held)
}

/// The secants of the slip forces' map from a step's earlier rounds, as
/// an approximate inverse that preconditions the next rounds' Anderson
/// mixing.
///
/// Within a round the slip forces x are the fixed point of an affine map
/// F(x) = A x + c (fixed states and directions); r = F(x) − x. Two
/// iterates of a round give a secant Δr = (A − I) Δx. A round of block
/// pivoting switches few points, so A changes little from one round to
/// the next, yet Anderson's history starts empty each round (kept through
/// a change, its least squares mix two maps: 214 passes against 140 on
/// the Xiaowan-like complete dam). Here the last [`SECANT_DEPTH`] secants
/// of the earlier rounds make the multisecant inverse
///
/// ```text
/// H r = r − (ΔX + ΔR) γ,   γ = argmin ‖r − ΔR γ‖,
/// ```
///
/// a Newton step (I − A)⁻¹ r on the span of ΔR and the plain step r
/// beside it, and the round's Anderson mixing runs on x + H r instead of
/// F(x). H stays fixed within a round, so Anderson sees one map. It only
/// steers the iteration: the step still ends on the residual of F itself
/// ([`ActiveSet::next_slip_forces`]), so a poor H costs passes, never the
/// answer. A step's first round has no secants and iterates as before, to
/// the bit.
///
/// On the Xiaowan-like complete dam under its weight (5 Dec 2026,
/// alternated): 122 passes and 109.1 s against 149 and 122.7 s, 76 of
/// them moving slip forces only against 100, the same factorisations (10)
/// and the same final states; the demo's complete dam 63 passes against
/// 66. A round here is the passes between two changes of states (block
/// pivoting's switches, or reversed points stuck).
#[derive(Debug)]
struct RoundSecants {
    /// length of the vectors: two per live pair
    n: usize,
    depth: usize,
    /// Δx and Δr of the earlier rounds, oldest first
    dx: Vec<Vec<f64>>,
    dr: Vec<Vec<f64>>,
    /// the current round's, used from the next round on
    round_dx: Vec<Vec<f64>>,
    round_dr: Vec<Vec<f64>>,
    /// the round's last iterate and residual
    last: Option<(Vec<f64>, Vec<f64>)>,
    /// H of the earlier rounds' secants, made once a round
    inverse: Option<SecantInverse>,
}

/// H r = r − S γ with γ = P r: P = ΔR⁺ (m × n, the least squares of
/// [`RoundSecants`] by its SVD) and S = ΔX + ΔR, made when a round ends
/// so that a pass pays two products of n × m, not an SVD (43 ms a pass at
/// 32 secants of the Xiaowan-like complete dam).
#[derive(Debug)]
struct SecantInverse {
    pinv: nalgebra::DMatrix<f64>,
    step: nalgebra::DMatrix<f64>,
}

impl RoundSecants {
    fn new(n: usize, depth: usize) -> Self {
        RoundSecants {
            n,
            depth,
            dx: Vec::new(),
            dr: Vec::new(),
            round_dx: Vec::new(),
            round_dr: Vec::new(),
            last: None,
            inverse: None,
        }
    }

    /// An iterate x of the round and its residual r.
    fn observe(&mut self, x: Vec<f64>, r: Vec<f64>) {
        if let Some((lx, lr)) = &self.last {
            self.round_dx
                .push(x.iter().zip(lx).map(|(a, b)| a - b).collect());
            self.round_dr
                .push(r.iter().zip(lr).map(|(a, b)| a - b).collect());
        }
        self.last = Some((x, r));
    }

    /// The states changed: the round's secants join the earlier ones.
    fn end_round(&mut self) {
        self.dx.append(&mut self.round_dx);
        self.dr.append(&mut self.round_dr);
        let excess = self.dx.len().saturating_sub(self.depth);
        self.dx.drain(..excess);
        self.dr.drain(..excess);
        self.last = None;
        self.inverse = self.secant_inverse();
    }

    /// H of the secants kept, or None without secants (or when their
    /// least squares fail).
    fn secant_inverse(&self) -> Option<SecantInverse> {
        let m = self.dx.len();
        if m == 0 {
            return None;
        }
        let dr = nalgebra::DMatrix::from_fn(self.n, m, |i, j| self.dr[j][i]);
        let cutoff = singular_cutoff(&dr);
        let pinv = dr.svd(true, true).pseudo_inverse(cutoff).ok()?;
        let step = nalgebra::DMatrix::from_fn(self.n, m, |i, j| self.dx[j][i] + self.dr[j][i]);
        Some(SecantInverse { pinv, step })
    }

    /// H r, or None without an inverse (a step's first round).
    fn apply(&self, r: &[f64]) -> Option<Vec<f64>> {
        let inv = self.inverse.as_ref()?;
        let r = nalgebra::DVector::from_column_slice(r);
        let gamma = &inv.pinv * &r;
        Some((r - &inv.step * gamma).as_slice().to_vec())
    }
}

/// Singular values of a matrix of secant differences below which its
/// least squares ([`Anderson`], [`RoundSecants`]) ignore a direction:
/// 1e-12 of its largest entry.
fn singular_cutoff(dr: &nalgebra::DMatrix<f64>) -> f64 {
    let scale = dr.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    1e-12 * scale.max(f64::MIN_POSITIVE)
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
        let Ok(gamma) = dr.clone().svd(true, true).solve(&rhs, singular_cutoff(&dr)) else {
            self.clear();
            return fx.to_vec();
        };
        let mut next = fx.to_vec();
        for j in 0..m {
            for ((v, a), b) in next.iter_mut().zip(&self.fs[j + 1]).zip(&self.fs[j]) {
                *v -= gamma[j] * (a - b);
            }
        }
        next
    }
}

#[cfg(test)]
mod tests {
    use super::RoundSecants;
    use nalgebra::{DMatrix, DVector};

    /// F(x) = A x + c on four unknowns, A not symmetric, ‖A‖ < 1.
    fn affine() -> (DMatrix<f64>, DVector<f64>) {
        let a = DMatrix::from_row_slice(
            4,
            4,
            &[
                0.30, 0.20, -0.10, 0.05, //
                -0.15, 0.40, 0.10, 0.00, //
                0.05, -0.20, 0.25, 0.10, //
                0.10, 0.05, -0.05, 0.35,
            ],
        );
        (a, DVector::from_column_slice(&[1.0, -2.0, 0.5, 3.0]))
    }

    fn residual(a: &DMatrix<f64>, c: &DVector<f64>, x: &[f64]) -> Vec<f64> {
        let x = DVector::from_column_slice(x);
        (a * &x + c - &x).as_slice().to_vec()
    }

    /// With as many independent secants as unknowns the multisecant
    /// inverse is (I − A)⁻¹, so x + H r is the fixed point from any x; a
    /// round's secants serve only from the next round on, and only the
    /// last `depth` are kept.
    #[test]
    fn round_secants_invert_an_affine_map_from_the_next_round_on() {
        let (a, c) = affine();
        let fixed = (DMatrix::identity(4, 4) - &a).lu().solve(&c).unwrap();
        let mut secants = RoundSecants::new(4, 8);
        let points = [
            [0.0, 0.0, 0.0, 0.0],
            [1.0, 0.5, -0.5, 2.0],
            [-1.0, 2.0, 0.3, 0.0],
            [0.2, -1.5, 1.0, 1.0],
            [2.0, 1.0, 1.0, -1.0],
        ];
        let y = [0.7, 0.1, -1.2, 2.0];
        let ry = residual(&a, &c, &y);
        assert!(secants.apply(&ry).is_none(), "no secants in a first round");
        for x in points {
            secants.observe(x.to_vec(), residual(&a, &c, &x));
        }
        assert!(secants.apply(&ry).is_none(), "the round's own secants wait");
        secants.end_round();
        let h = secants.apply(&ry).expect("secants of the round before");
        for k in 0..4 {
            assert!(
                (y[k] + h[k] - fixed[k]).abs() < 1e-12,
                "unknown {k}: {} against {}",
                y[k] + h[k],
                fixed[k]
            );
        }
        // two secants kept: H is the plain step off their span
        let mut two = RoundSecants::new(4, 2);
        for x in points {
            two.observe(x.to_vec(), residual(&a, &c, &x));
        }
        two.end_round();
        assert_eq!((two.dx.len(), two.dr.len()), (2, 2));
        let h2 = two.apply(&ry).expect("two secants");
        let miss: f64 = (0..4).map(|k| (y[k] + h2[k] - fixed[k]).abs()).sum();
        assert!(miss > 1e-6, "two secants cannot invert a 4 × 4 map");
    }
}
