//! The live system of a coming pour day, numbered and analysed on a thread
//! of its own while the steps before it run.
//!
//! A step whose start pours lifts needs the new live set's numbering, its
//! pattern and faer's symbolic analysis ([`super::frame::Frame::live_system`]):
//! 38 ms on the demo's arch (218 pour days, 8.3 s in all), 1.3 s on the
//! Xiaowan-like arch's late days. Made when the step is ordered, the
//! analysis sits on the chain of the run: the factor made ahead for that
//! step ([`super::ahead`]) starts only once it is done, and without a
//! factor made ahead (the large arch's systems, which factorise on both
//! cores) the step's rebuild waits for it. Yet the live set after a pour
//! depends on the schedule alone — which lifts are poured on which days —
//! not on any solution, so it can be analysed as soon as the pour day is
//! known: here, when the step before the step that orders it starts. The
//! thread fills the time the cores wait on one another (the contact passes
//! run on one core; the factor made ahead and the step's passes wait on
//! each other).
//!
//! The analysis is a function of the live elements, the pairs they make and
//! the nodes layer merging ties, so the system made here is the one the step
//! would make itself, to the bit; it is used only for exactly those live
//! elements and tied nodes, and otherwise discarded (counted). An analysis
//! that fails here is made again where it is needed, which reports the
//! error with its day.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::live::{LiveError, LiveSystem};

/// What analysing ahead did (`groutready study perf`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PoursAheadStats {
    /// analyses started on a thread of their own
    pub started: usize,
    /// of them, taken by the step that poured those lifts
    pub used: usize,
    /// replaced by another before a step took them (the next live set
    /// turned out otherwise)
    pub discarded: usize,
    /// their wall time on their threads \[s\]
    pub seconds: f64,
}

/// The live set a system is analysed for: the live elements and the nodes
/// layer merging ties.
struct Key {
    live: Vec<bool>,
    merged: Vec<u32>,
}

/// The analysis of a coming pour day's live system.
struct Pending {
    key: Key,
    handle: JoinHandle<Result<LiveSystem, LiveError>>,
}

/// A coming pour day's live system, being analysed or analysed.
#[derive(Default)]
pub struct PoursAhead {
    enabled: bool,
    pending: Option<Pending>,
    /// wall time of the analyses on their threads \[ns\], added by them
    nanos: Arc<AtomicU64>,
    stats: PoursAheadStats,
}

impl Drop for PoursAhead {
    /// A run that ends with an analysis running waits for it.
    fn drop(&mut self) {
        if let Some(p) = self.pending.take() {
            let _ = p.handle.join();
        }
    }
}

/// An analysis taken for a step: joined where it is needed, so a step that
/// hands it to a thread of its own never waits for it here.
pub struct Taken(JoinHandle<Result<LiveSystem, LiveError>>);

impl Taken {
    /// The live system, or None when its analysis failed (it is then made
    /// again where it is needed, which reports the error).
    pub fn join(self) -> Option<LiveSystem> {
        self.0.join().ok().and_then(Result::ok)
    }
}

impl PoursAhead {
    pub fn new(enabled: bool) -> PoursAhead {
        let mut ahead = PoursAhead::default();
        ahead.enabled = enabled;
        ahead
    }

    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Off: nothing is analysed ahead and what was is dropped.
    pub fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
        if !on {
            self.discard();
        }
    }

    pub fn stats(&self) -> PoursAheadStats {
        PoursAheadStats {
            seconds: self.nanos.load(Ordering::Relaxed) as f64 * 1e-9,
            ..self.stats
        }
    }

    /// Whether the live set of the elements `live` with the nodes `merged`
    /// tied is being analysed or analysed.
    pub fn holds(&self, live: &[bool], merged: &[u32]) -> bool {
        self.pending
            .as_ref()
            .is_some_and(|p| p.key.live == live && p.key.merged == merged)
    }

    /// Starts `analyse` on a thread of its own for the live set of the
    /// elements `live` with the nodes `merged` tied; what was held before
    /// is discarded.
    pub fn start<F>(&mut self, live: Vec<bool>, merged: Vec<u32>, analyse: F)
    where
        F: FnOnce() -> Result<LiveSystem, LiveError> + Send + 'static,
    {
        if !self.enabled {
            return;
        }
        self.discard();
        let nanos = Arc::clone(&self.nanos);
        let handle = std::thread::spawn(move || {
            crate::machine::lower_this_threads_priority();
            let t = Instant::now();
            let made = analyse();
            nanos.fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
            made
        });
        self.stats.started += 1;
        self.pending = Some(Pending {
            key: Key { live, merged },
            handle,
        });
    }

    /// The analysis of the live set of the elements `live` with the nodes
    /// `merged` tied, if that is the one held (taken; anything else held is
    /// kept for its own day).
    pub fn take(&mut self, live: &[bool], merged: &[u32]) -> Option<Taken> {
        if !self.holds(live, merged) {
            return None;
        }
        let p = self.pending.take()?;
        self.stats.used += 1;
        Some(Taken(p.handle))
    }

    fn discard(&mut self) {
        if let Some(p) = self.pending.take() {
            self.stats.discarded += 1;
            // joined so that two analyses never hold their memory at once
            let _ = p.handle.join();
        }
    }
}
