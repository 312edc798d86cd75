//! Factorising the next mechanical step on the second core while this
//! step's contact passes run.
//!
//! A daily step with joints needs one numeric factorisation of
//!
//! ```text
//! M_{n+1} = K̃(t_n, t_{n+1}) + springs of the intact grout layers, the rows
//!           of the closed joint points held
//! ```
//!
//! and then its contact passes, which solve with that factor (single
//! right-hand sides, memory-bound, on one core). K̃ depends on the schedule
//! only — the elements' ages and creep coefficients over the step — not on
//! step n's solution, so it can be assembled before step n's passes and
//! factorised while they run. Only the joint states are not known yet: the
//! factor is made with the rows and springs of step n's *start* states,
//! and step n+1 starts from it as from any factor whose rows differ from
//! its guess, through the exact capacitance correction of
//! [`crate::fem::capacitance`] (refactorising past the usual break-even).
//! The answer is the same as the factorisation made at the step's start,
//! to round-off.
//!
//! When to start it is a trade measured on the demo's whole construction
//! (`groutready study perf`): the earlier the guess, the longer the
//! factorisation overlaps step n's passes, and the more rows of step n+1
//! differ from it. With the correction's columns two full sweeps each,
//! the states after step n's first pass cost the least wall time; with
//! the columns forward halves on their reach (about 7 % of the rows) and
//! the slip forces solved with the states (3.3 passes a step), the start
//! states do: the whole step's passes overlap the factorisation. A guess
//! that lags a step would make a run restarted from a checkpoint (which
//! has no factor made ahead) differ in the last bits from the run it
//! continues, and the planner reuses a remedy search only on equal bits:
//! so the checkpoint carries the guess ([`FactorGuess`], in
//! [`super::MechState`]) and the restarted run's first step factorises
//! from it. The factorisation shares the memory bus with the passes'
//! solves, so the passes run slower beside it.
//!
//! The K̃ and element coefficients assembled ahead are the step's own: the
//! step reuses them ([`FactorAhead::assembled`]) when its elements were
//! born on the days they were assembled for, rather than assemble twice.
//!
//! The factorisation runs on a thread of its own until the next step
//! needs it ([`FactorAhead::settle`]), so it overlaps the thermal steps,
//! the commit and the records between the two mechanical steps as well as
//! this step's passes: on the demo's first 700 days (`study perf --days
//! 700`, alternated, 27 Nov 2026) 88.0 and 86.5 s against 93.5 and 99.7 s
//! when it was joined at the end of its step (waits 15.7 against 24–25 s).
//!
//! The next step's order ([`Order`]: its K̃, the matrix of its first pass
//! and the guess) is made and its job started before the step waits for
//! its own factor, so two factorisations may run at once while the step
//! waits, and the cores never wait for an order. With the order made
//! after the wait, the other core idled 21.8 s of the demo's 78.6 s
//! between a factor and the next (28 Nov 2026); with the order made before
//! the wait and the job started after it (the spare solver came free only
//! then), 6.8 s of 52.3 s (a timeline of one run, 30 Nov 2026): each day
//! the wake from the wait, the order and a thread's start. A step that
//! pours lifts orders after its rebuild (the next live system is the one
//! being factorised). Three solvers rotate: the step's, the one being
//! made for the next step, and the one for the step after it.
//!
//! The factor is made only when the driver can name the next step
//! ([`FactorAhead::set_next`]). When zones are grouted at its start, the
//! guess opens their points: the step frees the rows the layers bond and
//! adds their springs to the diagonal, a change the correction takes
//! (`MechanicsModel::grouting_guess`); guessed as this step's states, the
//! layers' rows and springs together passed the break-even and the step
//! factorised on its own thread. When lifts are poured at
//! its start, the next live set is numbered and analysed ahead too
//! ([`Births`]), its new joint pairs guessed in the state a rebuild gives
//! them, and the rebuild after the pours adopts that system if its live
//! elements are those. That analysis (with the step's K̃ and first-pass
//! matrix) runs on a thread of its own from the order, which the job
//! joins before it factorises ([`BuildBirths`]), unless the other core is
//! the busier one; which thread made it changes no bit. A factor is used
//! only if the next step is that interval on that live system and its
//! assembled K̃ equals the one factorised, bit for bit; otherwise it is
//! discarded (counted). The main thread always waits for it, so whether it
//! is used never depends on timing: a run stays bit-reproducible.
//!
//! Off (`solver.factor_ahead = false`) where the second core is busy: the
//! planner's two remedy searches already run side by side.

use std::collections::VecDeque;
use std::thread::JoinHandle;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::{CholeskySolver, SolveError, SparseSym};
use crate::material::creep::StepCoefficients;

use super::contact_step::Prepared;
use super::joints::JointPointState;
use super::live::{LiveSystem, PARALLEL_FROM_DOFS};
use crate::vocab::ZoneId;

/// The largest factor \[bytes\] a second copy is kept of: two factors of the
/// complete Xiaowan-like arch (324M entries, 2.6 GB each) would pass its
/// 8 GB budget with the capacitance columns and the model.
const AHEAD_MAX_BYTES: usize = 3 << 29;

/// A wait for the factor made ahead longer than this \[s\] says the other
/// core is the busier one ([`FactorAhead::births_here`]).
const BUSY_WAIT: f64 = 1e-3;

/// Where the next live set is analysed when the next step pours lifts
/// ([`BuildBirths`]). The answer is the same to the bit in each.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum BirthsPlacement {
    /// on a thread of its own, unless the last step waited for its factor
    /// made ahead (the other core is then the busier one)
    #[default]
    Balanced,
    /// always on a thread of its own
    Thread,
    /// always on the step's thread
    Step,
}

/// What factorising ahead did (`groutready study perf`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AheadStats {
    /// factors made ahead (also counted in the numeric factorisations)
    pub made: usize,
    /// of them, on the next step's live system numbered and analysed
    /// ahead (lifts poured at its start)
    #[serde(default)]
    pub on_new_systems: usize,
    /// of them, used by their step
    pub used: usize,
    /// made for an interval or live system the next step did not have
    pub discarded: usize,
    /// factorisations (or analyses of the next live system) that failed
    /// (the step then rebuilds or factorises itself and reports the error)
    pub failed: usize,
    /// wall time of the factorisations ahead, on the second core \[s\]
    pub seconds: f64,
    /// wall time of the next live systems' analyses and K̃ (lifts poured
    /// at the next step's start) made on threads of their own from their
    /// orders (those made on the step's thread count as its symbolic
    /// time) \[s\]
    #[serde(default)]
    pub seconds_analysed: f64,
    /// time the step waited for a factorisation ahead to finish \[s\]
    pub seconds_waited: f64,
    /// of those made, started while the one before was still running
    /// (its step waiting for it): two at once
    #[serde(default)]
    pub started_beside: usize,
}

/// The factor being made or made for the next step, and its spare solver.
#[derive(Default)]
pub struct FactorAhead {
    /// `solver.factor_ahead`
    enabled: bool,
    /// the next step, when the driver knows it
    next: Option<NextStep>,
    /// a solver on the live system's symbolic analysis, to factorise into
    spare: Option<CholeskySolver>,
    /// the factorisations running, the next step's first: each outlives
    /// the step that started it, so it also overlaps the thermal steps and
    /// the commit before the step it is for, which waits for it
    /// ([`FactorAhead::settle`]); a step starts the next step's before it
    /// waits for its own, so two run at once while it waits
    running: VecDeque<JoinHandle<Done>>,
    ready: Option<Made>,
    /// how long the last step waited for its factor made ahead \[s\]
    last_waited: f64,
    placement: BirthsPlacement,
    pub stats: AheadStats,
}

impl Drop for FactorAhead {
    /// A run that ends (or fails) with a factorisation running waits for it.
    fn drop(&mut self) {
        for handle in self.running.drain(..) {
            let _ = handle.join();
        }
    }
}

/// Lifts (block, lift) poured during a mechanical step, grouped by day
/// with the day's time, in order.
pub type PoursByDay = Vec<(f64, Vec<(u32, u32)>)>;

/// The step after the one about to run, as the driver knows it.
#[derive(Debug, Clone, PartialEq)]
pub struct NextStep {
    /// (t0, t1) of that step
    pub interval: (f64, f64),
    /// the lifts (block, lift) poured at its start and, with pours merged
    /// into longer steps (`time.mechanics_merge_pours`), on the days inside
    /// it, grouped by day with the day's time, the start's first
    pub pours: PoursByDay,
    /// the zones grouted at its start
    pub grouting: Vec<ZoneId>,
    /// the first step from its end on whose span pours lifts: that step's
    /// start and its lifts by day, as in `pours` (their live set is
    /// analysed ahead: [`super::pours_ahead`])
    pub later_pours: Option<(f64, PoursByDay)>,
}

/// The live system of a next step whose start pours lifts: numbered and
/// analysed ahead, adopted by the rebuild after those pours.
pub struct Births {
    /// the elements live after the pours
    pub live: Vec<bool>,
    /// the nodes layer merging ties then
    pub merged: Vec<u32>,
    /// the points the pours pair, with the state each starts in
    pub paired: Vec<(usize, JointPointState)>,
    pub sys: LiveSystem,
}

/// The next step's K̃ and what it was assembled from: its elements'
/// coefficients over the step and birth days, per slot of its live system.
/// The step reuses both when its elements were born on those days
/// ([`FactorAhead::assembled`]): the coefficients are a function of the
/// birth day and the interval only.
#[derive(Clone)]
pub struct Assembled {
    pub stiffness: SparseSym,
    pub coeffs: Vec<StepCoefficients>,
    pub born: Vec<f64>,
}

/// Where a factor is made: a solver on this step's live system, or the
/// next step's own live system.
enum Target {
    Solver(Box<CholeskySolver>),
    Born(Box<Births>),
    /// the live system adopted (its solver holds the factor)
    Adopted,
}

/// A factor made for the step over `interval`.
struct Made {
    interval: (f64, f64),
    target: Target,
    prepared: Prepared,
    /// K̃ of that step, as assembled ahead; None once the step has taken
    /// it ([`FactorAhead::assembled`])
    assembled: Option<Assembled>,
}

impl Made {
    /// Whether it was made for the step over (t0, t1) on `live`.
    fn is_for(&self, t0: f64, t1: f64, live: &LiveSystem) -> bool {
        let same_system = match &self.target {
            Target::Solver(s) => std::sync::Arc::ptr_eq(s.pattern(), live.solver.pattern()),
            Target::Adopted => true,
            Target::Born(_) => false,
        };
        same_system && self.interval == (t0, t1)
    }
}

/// The next live system's analysis, its step's K̃ and the first pass's
/// matrix: made by the job, which joins the thread making them since the
/// step was ordered, or takes them made already (on the step's thread when
/// the other core was the busier one). None when the analysis or the
/// assembly fails (the step then rebuilds and reports the error).
pub type BuildBirths = Box<dyn FnOnce() -> Option<Analysed> + Send>;

/// The next step's own live system, analysed ahead with its K̃ and the
/// matrix of its first pass.
pub struct Analysed {
    pub births: Births,
    pub assembled: Assembled,
    pub prepared: Prepared,
    /// wall time of the analysis and assembly on a thread of its own (0
    /// when made on the step's thread) \[s\]
    pub seconds: f64,
}

/// The next step's factorisation but the solver it is made in: its
/// interval, the states its first pass is guessed from, and its K̃ and
/// first-pass matrix or what makes them. Made before the step waits for
/// its own factor, so the other core starts on it as soon as it is free
/// ([`FactorAhead::job`]).
pub struct Order {
    interval: (f64, f64),
    states: Vec<JointPointState>,
    work: Work,
}

/// What a job does before it factorises.
enum Work {
    /// nothing: K̃ and the first pass's matrix on this live system are made
    Made {
        assembled: Assembled,
        prepared: Prepared,
    },
    /// the next step pours lifts: its live system numbered and analysed,
    /// its K̃ assembled ([`BuildBirths`])
    Births(BuildBirths),
}

impl Order {
    /// The order for the next step's factor over `interval` on `live`,
    /// whose K̃ is `assembled`, guessed from this step's start `states`.
    pub fn new(
        interval: (f64, f64),
        assembled: Assembled,
        live: &LiveSystem,
        states: &[JointPointState],
    ) -> Order {
        let prepared = Prepared::first_pass(&assembled.stiffness, live, states);
        Order {
            interval,
            states: states.to_vec(),
            work: Work::Made {
                assembled,
                prepared,
            },
        }
    }

    /// Whether the next step pours lifts: its own live system is analysed
    /// by the job.
    pub fn pours(&self) -> bool {
        matches!(self.work, Work::Births(_))
    }

    /// The order for the next step's factor over `interval` on its own live
    /// system, which `build` is making; `states` are this step's
    /// start states with the new pairs as a rebuild starts them.
    pub fn births(interval: (f64, f64), states: Vec<JointPointState>, build: BuildBirths) -> Order {
        Order {
            interval,
            states,
            work: Work::Births(build),
        }
    }
}

/// What the factor made ahead for the next step was guessed from: its
/// interval and the joint states (this step's start states, the new pairs
/// of a pour as a rebuild makes them). A checkpoint carries it, so a run
/// restarted there factorises its first step from the same guess, on the
/// main thread, and gives the bits of the run it continues.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FactorGuess {
    pub interval: (f64, f64),
    pub states: Vec<JointPointState>,
}

/// A factorisation to run on the other core.
pub struct Job {
    interval: (f64, f64),
    states: Vec<JointPointState>,
    work: JobWork,
}

/// What a job factorises into, and what.
enum JobWork {
    /// a solver on this live system, and the order's K̃ and first-pass
    /// matrix
    Solver(Box<(CholeskySolver, Assembled, Prepared)>),
    /// the next step's own live system, from its analysis
    Births(BuildBirths),
}

/// A finished [`Job`].
pub struct Done {
    /// None when the next live system could not be analysed
    made: Option<Made>,
    result: Result<(), SolveError>,
    seconds: f64,
    /// [`Analysed::seconds`]
    analysed: f64,
}

impl Job {
    /// What the factor is guessed from (a checkpoint carries it).
    pub fn guess(&self) -> FactorGuess {
        FactorGuess {
            interval: self.interval,
            states: self.states.clone(),
        }
    }

    /// Spawns the analysis, if any, and the factorisation on a thread of
    /// its own.
    fn spawn(self) -> JoinHandle<Done> {
        std::thread::spawn(move || {
            let t = Instant::now();
            let mut analysed = 0.0;
            let Job { interval, work, .. } = self;
            let (target, assembled, prepared) = match work {
                JobWork::Solver(made) => {
                    let (solver, assembled, prepared) = *made;
                    (Target::Solver(Box::new(solver)), assembled, prepared)
                }
                JobWork::Births(build) => match build() {
                    Some(a) => {
                        analysed = a.seconds;
                        (Target::Born(Box::new(a.births)), a.assembled, a.prepared)
                    }
                    None => {
                        return Done {
                            made: None,
                            result: Ok(()),
                            seconds: t.elapsed().as_secs_f64(),
                            analysed,
                        };
                    }
                },
            };
            let mut made = Made {
                interval,
                target,
                prepared,
                assembled: Some(assembled),
            };
            let result = match &mut made.target {
                Target::Solver(solver) => solver.factorize(&made.prepared.m),
                Target::Born(births) => births.sys.solver.factorize(&made.prepared.m),
                Target::Adopted => unreachable!("a job factorises into its own target"),
            };
            Done {
                made: Some(made),
                result,
                seconds: t.elapsed().as_secs_f64(),
                analysed,
            }
        })
    }
}

impl FactorAhead {
    pub fn new(enabled: bool) -> FactorAhead {
        let mut ahead = FactorAhead::default();
        ahead.enabled = enabled;
        ahead
    }

    /// Starts `job` on a thread of its own (beside one still running for
    /// the step about to take it); the settles wait for them in order.
    pub fn start(&mut self, job: Job) {
        if !self.running.is_empty() {
            self.stats.started_beside += 1;
        }
        self.running.push_back(job.spawn());
    }

    /// Waits for the first factorisation running, if any, and keeps it for
    /// its step; returns the flops of the factor made, when one was. Every
    /// use of what was made ahead settles first.
    pub fn settle(&mut self) -> Option<f64> {
        let handle = self.running.pop_front()?;
        let t = Instant::now();
        let done = handle
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        self.last_waited = t.elapsed().as_secs_f64();
        let flops = match done.made.as_ref().map(|m| &m.target) {
            Some(Target::Solver(s)) => s.factor_flops(),
            Some(Target::Born(b)) => b.sys.solver.factor_flops(),
            _ => 0.0,
        };
        self.finish(done, t.elapsed().as_secs_f64())
            .then_some(flops)
    }

    /// Whether the next live set is analysed on the step's thread
    /// ([`BirthsPlacement`]): by default when the last step waited for its
    /// factor made ahead, the other core being the busier one.
    pub fn births_here(&self) -> bool {
        match self.placement {
            BirthsPlacement::Balanced => self.last_waited > BUSY_WAIT,
            BirthsPlacement::Thread => false,
            BirthsPlacement::Step => true,
        }
    }

    pub fn set_births_placement(&mut self, placement: BirthsPlacement) {
        self.placement = placement;
    }

    pub fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
        if !on {
            self.next = None;
            self.ready = None;
            self.spare = None;
        }
    }

    /// The step after the one about to run, or None when it is unknown.
    pub fn set_next(&mut self, next: Option<NextStep>) {
        self.next = next.filter(|_| self.enabled);
    }

    /// The step after the one about to run, as [`FactorAhead::set_next`]
    /// named it (until its factorisation is [`FactorAhead::due`]).
    pub fn next_step(&self) -> Option<&NextStep> {
        self.next.as_ref()
    }

    /// Forgets everything made for the live system before a rebuild or a
    /// restore.
    pub fn forget(&mut self) {
        if self.ready.take().is_some() {
            self.stats.discarded += 1;
        }
        self.spare = None;
    }

    /// The live system made ahead for the elements `live`, if one was (its
    /// solver holds the next step's factor); None otherwise, and anything
    /// made ahead is forgotten.
    pub fn adopt(&mut self, live: &[bool], merged: &[u32]) -> Option<LiveSystem> {
        if let Some(made) = self.ready.as_mut() {
            if matches!(&made.target, Target::Born(b) if b.live == live && b.merged == merged) {
                if let Target::Born(births) = std::mem::replace(&mut made.target, Target::Adopted) {
                    self.spare = None;
                    return Some(births.sys);
                }
            }
        }
        self.forget();
        None
    }

    /// The factor made for the step over (t0, t1) with stiffness `a`, put
    /// into `live.solver` (its old factor becomes the spare), or None (then
    /// `live.solver` is untouched).
    pub fn take(
        &mut self,
        t0: f64,
        t1: f64,
        live: &mut LiveSystem,
        a: &SparseSym,
    ) -> Option<Prepared> {
        let made = self.ready.take()?;
        // a K̃ the step took from here is the one factorised by construction
        let same_k = made
            .assembled
            .as_ref()
            .is_none_or(|m| m.stiffness.values() == a.values());
        if !made.is_for(t0, t1, live) || !same_k {
            self.stats.discarded += 1;
            if let Target::Solver(s) = made.target {
                if std::sync::Arc::ptr_eq(s.pattern(), live.solver.pattern()) {
                    self.spare = Some(*s);
                }
            }
            return None;
        }
        if let Target::Solver(mut solver) = made.target {
            std::mem::swap(&mut live.solver, &mut *solver);
            self.spare = Some(*solver);
        }
        self.stats.used += 1;
        Some(made.prepared)
    }

    /// The K̃ and coefficients made ahead for the step over (t0, t1) on
    /// `live`, if its elements were born on the days they were assembled
    /// for (`birth`, per element): taken, not copied (the step's K̃ is then
    /// the one factorised, which [`FactorAhead::take`] need not compare).
    pub fn assembled(
        &mut self,
        t0: f64,
        t1: f64,
        live: &LiveSystem,
        birth: &[f64],
    ) -> Option<Assembled> {
        let made = self.ready.as_mut()?;
        let a = made.assembled.as_ref()?;
        let same_births = live.elements.len() == a.born.len()
            && live
                .elements
                .iter()
                .zip(&a.born)
                .all(|(el, &b)| birth[el.elem as usize].to_bits() == b.to_bits());
        if made.is_for(t0, t1, live) && same_births {
            made.assembled.take()
        } else {
            None
        }
    }

    /// The next step when its factorisation is due now (once per step: it
    /// is taken). Not where the live system's factorisation already runs on
    /// both cores ([`PARALLEL_FROM_DOFS`]): on the Xiaowan-like arch's first
    /// 40 days (live sets of up to 152,871 dofs) factorising ahead took
    /// 54.2 s against 53.4 s without, at a peak of 4.5 against 2.8 GB (the
    /// threshold was 30,000 dofs then).
    pub fn due(&mut self, live: &LiveSystem) -> Option<NextStep> {
        let next = self.next.take()?;
        (live.n < PARALLEL_FROM_DOFS && 8 * live.solver.factor_nnz() <= AHEAD_MAX_BYTES)
            .then_some(next)
    }

    /// The factorisation of `order`: into the next step's own live system,
    /// or into the spare solver on `live` (a fork of its solver when no
    /// spare fits).
    pub fn job(&mut self, order: Order, live: &LiveSystem) -> Result<Job, SolveError> {
        let work = match order.work {
            Work::Births(build) => JobWork::Births(build),
            Work::Made {
                assembled,
                prepared,
            } => {
                let solver = match self.spare.take() {
                    Some(s) if std::sync::Arc::ptr_eq(s.pattern(), live.solver.pattern()) => s,
                    _ => live.solver.fork()?,
                };
                JobWork::Solver(Box::new((solver, assembled, prepared)))
            }
        };
        Ok(Job {
            interval: order.interval,
            states: order.states,
            work,
        })
    }

    /// A factorisation ordered but never started (no solver could be
    /// forked for it).
    pub fn not_made(&mut self) {
        self.stats.failed += 1;
    }

    /// Keeps a finished factorisation for its step; `waited` is how long
    /// the step waited for it. Whether it was made.
    fn finish(&mut self, done: Done, waited: f64) -> bool {
        self.stats.seconds += done.seconds;
        self.stats.seconds_analysed += done.analysed;
        self.stats.seconds_waited += waited;
        let Some(made) = done.made else {
            self.stats.failed += 1;
            return false;
        };
        match done.result {
            Ok(()) => {
                self.stats.made += 1;
                if matches!(made.target, Target::Born(_)) {
                    self.stats.on_new_systems += 1;
                }
                self.ready = Some(made);
                true
            }
            Err(_) => {
                self.stats.failed += 1;
                if let Target::Solver(s) = made.target {
                    self.spare = Some(*s);
                }
                false
            }
        }
    }

    /// The next step's own live system made ahead and not adopted yet.
    pub fn born(&self) -> Option<&LiveSystem> {
        match &self.ready.as_ref()?.target {
            Target::Born(births) => Some(&births.sys),
            _ => None,
        }
    }
}
