//! What a plan's remedy search leaves for the next plan, so that a weekly
//! re-plan costs what changed.
//!
//! The search has three parts: the supercooling search, the delay search and
//! the verification of all remedies together. Each part is a function of
//! what it read, and a simulation is causal: its history up to a day depends
//! on the schedules up to that day only (the restarts rely on the same fact,
//! `tests/it/restart.rs`). So a part's answer is reused, exactly, when
//!
//! - its key is the same: the as-of date, the planner's settings, the
//!   flagged zones' readiness (and, for the verification, the zones still to
//!   grout and the remedies proposed), digested ([`digest`]);
//! - the schedules did not change before the last day it read
//!   (`read_until`): the first date they differ from the last plan's is
//!   later, or there is none.
//!
//! A part that cannot be reused is re-run. The verification's run keeps
//! checkpoints ([`Lineage`]): re-run after an edit, it restarts from its own
//! checkpoint before the edit instead of from the as-of date.
//!
//! Verified by `tests/it/restart.rs` (a re-plan with nothing changed runs no
//! re-simulation and gives the same plan; after moving the last zone a week
//! the searches are reused, the verification restarts at the edit, and the
//! plan equals the one from scratch).

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::schedule::Schedules;
use crate::sim::{Checkpoint, History};
use crate::vocab::{Day, ZoneId};

use super::readiness::{DelayOption, Remedy, SupercoolOption, ZoneReadiness};

/// Per zone, a remedy found (None: none) and why not.
pub type Found<T> = HashMap<ZoneId, (Option<T>, String)>;

/// One part of a search and what it depended on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Part<T> {
    /// digest of the part's inputs besides the schedules
    pub key: u64,
    /// the last day its runs were read: later edits leave it valid
    pub read_until: Day,
    /// the re-simulations it took
    pub runs: usize,
    pub value: T,
}

impl<T> Part<T> {
    /// Whether the part holds for inputs digested to `key` and schedules
    /// that first changed on `first_change` (None: not at all).
    pub fn valid(&self, key: u64, first_change: Option<Day>) -> bool {
        self.key == key && first_change.is_none_or(|d| d > self.read_until)
    }
}

/// The verification of all remedies together: the remedies as verified (a
/// remedy may have been strengthened) and the zones they newly flag.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verified {
    pub remedies: Vec<(ZoneId, Remedy)>,
    pub newly_flagged: Vec<ZoneReadiness>,
}

pub type SupercoolPart = Part<Found<SupercoolOption>>;
pub type DelayPart = Part<Found<DelayOption>>;

/// The three parts of a plan's search (None: the part did not run).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SearchMemo {
    pub supercool: Option<SupercoolPart>,
    pub delay: Option<DelayPart>,
    pub verified: Option<Part<Verified>>,
}

/// A finished run that re-simulations may restart from: its schedules, its
/// checkpoints and its history (before the first checkpoint too).
#[derive(Debug, Clone)]
pub struct Lineage {
    pub schedules: Schedules,
    pub checkpoints: Vec<Checkpoint>,
    pub history: History,
}

/// FNV-1a of the postcard bytes of `value`: stable across Rust versions,
/// unlike the std hasher. `value` must not hold a hash map (its order
/// changes from run to run).
pub fn digest<T: Serialize>(value: &T) -> u64 {
    fnv1a(&postcard::to_allocvec(value).unwrap_or_default())
}

pub use crate::vocab::fnv1a;

#[cfg(test)]
mod tests {
    use super::*;

    /// A part holds for its own key while the schedules first change after
    /// the last day it read, and never for another key or an earlier change.
    #[test]
    fn a_part_holds_until_an_edit_reaches_what_it_read() {
        let p = Part {
            key: 7,
            read_until: Day(100),
            runs: 2,
            value: (),
        };
        assert!(p.valid(7, None));
        assert!(p.valid(7, Some(Day(101))));
        assert!(!p.valid(7, Some(Day(100))));
        assert!(!p.valid(7, Some(Day(3))));
        assert!(!p.valid(8, None));
    }

    #[test]
    fn the_digest_is_stable_and_sees_every_byte() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_ne!(digest(&(1u32, 2.0f64)), digest(&(1u32, 2.0000001f64)));
    }
}
