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
//! factor is made with the rows and springs that step n's *first pass*
//! found (its corrections make most of a step's open/closed changes), and
//! step n+1 starts from it as from any factor whose rows differ from its
//! guess, through the exact capacitance correction of
//! [`crate::fem::capacitance`] (refactorising past the usual break-even).
//! The answer is the same as the factorisation made at the step's start,
//! to round-off.
//!
//! When to start it is a trade measured on the demo's whole construction
//! (`groutready study perf`): from step n's start states the factor is
//! never waited for, but its rows differ from step n+1's guess by the
//! changes of all of step n (16,133 correction columns against 11,602 made
//! at the step's start); from step n's converged states the columns are
//! back to 11,629 but the step waits 19.8 s in all; after the first pass,
//! 13,041 columns and 6.2 s waited, the least wall time of the three. The
//! factorisation shares the memory bus with the passes' solves, so the
//! passes run slower beside it (joints 71.5 against 65.6 s).
//!
//! The factor is made only when the driver can name the next step
//! ([`FactorAhead::set_next`]): no pour at its start (a new live set, a
//! new pattern) and no zone grouted then (a zone's springs would exceed the
//! break-even). It is used only if the next step is that interval on the
//! same live system and its assembled K̃ equals the one factorised, bit for
//! bit; otherwise it is discarded (counted). The main thread always waits
//! for it, so whether it is used never depends on timing: a run stays
//! bit-reproducible.
//!
//! Off (`solver.factor_ahead = false`) where the second core is busy: the
//! planner's two remedy searches already run side by side.

use std::thread::{Scope, ScopedJoinHandle};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::{CholeskySolver, SolveError, SparseSym};

use super::contact_step::Prepared;
use super::joints::JointPointState;
use super::live::LiveSystem;

/// The largest factor [bytes] a second copy is kept of: two factors of the
/// complete Xiaowan-like arch (324M entries, 2.6 GB each) would pass its
/// 8 GB budget with the capacitance columns and the model.
const AHEAD_MAX_BYTES: usize = 3 << 29;

/// What factorising ahead did (`groutready study perf`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AheadStats {
    /// factors made ahead (also counted in the numeric factorisations)
    pub made: usize,
    /// of them, used by their step
    pub used: usize,
    /// made for an interval or live system the next step did not have
    pub discarded: usize,
    /// factorisations that failed (the step then factorises itself and
    /// reports the error)
    pub failed: usize,
    /// wall time of the factorisations ahead, on the second core [s]
    pub seconds: f64,
    /// time the step waited for a factorisation ahead to finish [s]
    pub seconds_waited: f64,
}

/// The factor being made or made for the next step, and its spare solver.
#[derive(Debug, Default)]
pub struct FactorAhead {
    /// `solver.factor_ahead`
    enabled: bool,
    /// the next step's interval, when the driver knows it
    next: Option<(f64, f64)>,
    /// a solver on the live system's symbolic analysis, to factorise into
    spare: Option<CholeskySolver>,
    ready: Option<Made>,
    pub stats: AheadStats,
}

/// A factor made for the step over `interval`.
#[derive(Debug)]
struct Made {
    interval: (f64, f64),
    solver: CholeskySolver,
    prepared: Prepared,
    /// K̃ of that step, as assembled ahead
    stiffness: SparseSym,
}

/// The next step's interval and K̃, waiting for this step's states to settle.
pub struct Order {
    interval: (f64, f64),
    stiffness: SparseSym,
    /// a solver to factorise into, when one is left from an earlier step
    spare: Option<CholeskySolver>,
}

impl Order {
    /// The factorisation of the next step's first pass, guessed from this
    /// step's first-pass `states` on `live`.
    pub fn job(self, live: &LiveSystem, states: &[JointPointState]) -> Result<Job, SolveError> {
        let prepared = Prepared::first_pass(&self.stiffness, live, states);
        let solver = match self.spare {
            Some(s) if std::sync::Arc::ptr_eq(s.pattern(), live.solver.pattern()) => s,
            _ => live.solver.fork()?,
        };
        Ok(Job {
            interval: self.interval,
            solver,
            prepared,
            stiffness: self.stiffness,
        })
    }
}

/// A factorisation to run on the other core.
pub struct Job {
    interval: (f64, f64),
    solver: CholeskySolver,
    prepared: Prepared,
    stiffness: SparseSym,
}

/// A finished [`Job`].
pub struct Done {
    made: Made,
    result: Result<(), SolveError>,
    seconds: f64,
}

impl Job {
    /// Spawns the factorisation on `scope`.
    pub fn spawn<'s>(self, scope: &'s Scope<'s, '_>) -> ScopedJoinHandle<'s, Done> {
        scope.spawn(move || {
            let Job {
                interval,
                mut solver,
                prepared,
                stiffness,
            } = self;
            let t = Instant::now();
            let result = solver.factorize(&prepared.m);
            Done {
                seconds: t.elapsed().as_secs_f64(),
                result,
                made: Made {
                    interval,
                    solver,
                    prepared,
                    stiffness,
                },
            }
        })
    }
}

impl FactorAhead {
    pub fn new(enabled: bool) -> FactorAhead {
        FactorAhead {
            enabled,
            ..FactorAhead::default()
        }
    }

    pub fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
        if !on {
            self.next = None;
            self.ready = None;
            self.spare = None;
        }
    }

    /// The interval of the step after the one about to run, or None when
    /// its start changes the live system or grouts a zone (or is unknown).
    pub fn set_next(&mut self, next: Option<(f64, f64)>) {
        self.next = next.filter(|_| self.enabled);
    }

    /// Forgets everything made for the live system before a rebuild or a
    /// restore.
    pub fn forget(&mut self) {
        if self.ready.take().is_some() {
            self.stats.discarded += 1;
        }
        self.spare = None;
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
        let mut made = self.ready.take()?;
        let same_system = std::sync::Arc::ptr_eq(made.solver.pattern(), live.solver.pattern());
        if made.interval != (t0, t1) || !same_system || made.stiffness.values() != a.values() {
            self.stats.discarded += 1;
            if same_system {
                self.spare = Some(made.solver);
            }
            return None;
        }
        std::mem::swap(&mut live.solver, &mut made.solver);
        self.spare = Some(made.solver);
        self.stats.used += 1;
        Some(made.prepared)
    }

    /// The interval of the next step when its factorisation is due now
    /// (once per step: it is taken).
    pub fn due(&mut self, live: &LiveSystem) -> Option<(f64, f64)> {
        let interval = self.next.take()?;
        (8 * live.solver.factor_nnz() <= AHEAD_MAX_BYTES).then_some(interval)
    }

    /// The order for the next step's factor over `interval`, whose K̃ is
    /// `stiffness`: the step fills it with its first pass's states.
    pub fn order(&mut self, interval: (f64, f64), stiffness: SparseSym) -> Order {
        Order {
            interval,
            stiffness,
            spare: self.spare.take(),
        }
    }

    /// A factorisation ordered but never started (the step failed before
    /// its first pass, or no solver could be forked).
    pub fn not_made(&mut self) {
        self.stats.failed += 1;
    }

    /// Keeps a finished factorisation for its step; `waited` is how long
    /// the step waited for it. True when a factor was made.
    pub fn finish(&mut self, done: Done, waited: f64) -> bool {
        self.stats.seconds += done.seconds;
        self.stats.seconds_waited += waited;
        match done.result {
            Ok(()) => {
                self.stats.made += 1;
                self.ready = Some(done.made);
                true
            }
            Err(_) => {
                self.stats.failed += 1;
                self.spare = Some(done.made.solver);
                false
            }
        }
    }
}
