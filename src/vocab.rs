//! The words every layer shares: which zone, which day, which point of a
//! zone, which state a joint point is in.
//!
//! These types sit below every module of the pipeline (scene, schedule,
//! mesh, …, tui) so that a zone is one `ZoneId` from `grouting.csv` to the
//! terminal, a calendar day is one [`Day`] converted to and from a date in
//! one place ([`Epoch`]), a zone point is one [`ZonePoint`], and a joint
//! point's state is one [`JointState`] with one spelling on disk.

use std::fmt;

use chrono::NaiveDate;
use serde::{Deserialize, Serialize};

/// One grouting zone of one transverse joint (both 1-based; joint j lies
/// between blocks j and j+1, zone 1 is the lowest).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, Default,
)]
pub struct ZoneId {
    pub joint: u32,
    pub zone: u32,
}

impl ZoneId {
    pub const fn new(joint: u32, zone: u32) -> ZoneId {
        ZoneId { joint, zone }
    }
}

impl fmt::Display for ZoneId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "joint {} zone {}", self.joint, self.zone)
    }
}

/// A whole simulation day: days since the scene's epoch (day 0 is the
/// epoch's midnight; negative before it). Time inside the physics is a
/// fractional day (`f64`); a `Day` is a calendar day the histories,
/// checkpoints and schedules are keyed by.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, Default,
)]
#[serde(transparent)]
pub struct Day(pub i64);

impl Day {
    /// The time of this day's midnight [days since the epoch].
    pub fn t(self) -> f64 {
        self.0 as f64
    }

    /// The day a time falls in: the last midnight at or before `t`.
    pub fn containing(t: f64) -> Day {
        Day(t.floor() as i64)
    }

    /// `n` days later (earlier when negative).
    pub fn plus(self, n: i64) -> Day {
        Day(self.0 + n)
    }

    /// Whole days from `earlier` to `self`.
    pub fn since(self, earlier: Day) -> i64 {
        self.0 - earlier.0
    }
}

impl fmt::Display for Day {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "day {}", self.0)
    }
}

/// The scene's day 0: the one conversion between calendar dates and
/// simulation days.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Epoch(pub NaiveDate);

impl Epoch {
    /// The simulation day of `date`.
    pub fn day(self, date: NaiveDate) -> Day {
        Day((date - self.0).num_days())
    }

    /// The calendar date of `day`.
    pub fn date(self, day: Day) -> NaiveDate {
        self.0 + chrono::Duration::days(day.0)
    }

    /// The calendar date a time [days since the epoch] falls in.
    pub fn date_at(self, t: f64) -> NaiveDate {
        self.date(Day::containing(t))
    }

    /// The time of `date`'s midnight [days since the epoch].
    pub fn t(self, date: NaiveDate) -> f64 {
        self.day(date).t()
    }
}

impl fmt::Display for Epoch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// Where on a grouting zone an aperture or temperature is read: three
/// points at mid-height of the zone (on the upstream face, at the centre, on
/// the downstream face: the face points lie outside the grout stops), or the
/// zone's smallest aperture inside its grout stops (`Min`: at the joint
/// nodes off the faces, or the minimum of the aperture field over the
/// zone's joint area at least `[joints] grout_stop_inset_m` from both
/// faces, `mechanics::grout_stops`). The
/// spelling in every CSV, JSON and scene key is the lower-case name.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, Default,
)]
#[serde(rename_all = "snake_case")]
pub enum ZonePoint {
    Upstream,
    Center,
    Downstream,
    /// the smallest aperture inside the zone's grout stops
    #[default]
    Min,
}

impl ZonePoint {
    pub const ALL: [ZonePoint; 4] = [
        ZonePoint::Upstream,
        ZonePoint::Center,
        ZonePoint::Downstream,
        ZonePoint::Min,
    ];

    /// The three points that sit at a place on the joint (all but `Min`).
    pub const PLACED: [ZonePoint; 3] = [
        ZonePoint::Upstream,
        ZonePoint::Center,
        ZonePoint::Downstream,
    ];

    /// `upstream`, `center`, `downstream` or `min`.
    pub fn as_str(self) -> &'static str {
        match self {
            ZonePoint::Upstream => "upstream",
            ZonePoint::Center => "center",
            ZonePoint::Downstream => "downstream",
            ZonePoint::Min => "min",
        }
    }

    /// Parses the spelling of [`ZonePoint::as_str`] (case-insensitive,
    /// surrounding blanks ignored).
    pub fn parse(text: &str) -> Option<ZonePoint> {
        let t = text.trim();
        ZonePoint::ALL
            .into_iter()
            .find(|p| p.as_str().eq_ignore_ascii_case(t))
    }
}

impl fmt::Display for ZonePoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The state of a joint point as the tables report it: a contact point
/// before grouting (`Open`, `Stick`, `Slip`), a bonded grout layer after
/// (`Grouted`), or a grout layer that has cracked open again (`Reopened`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointState {
    Open,
    Stick,
    Slip,
    Grouted,
    Reopened,
}

impl JointState {
    /// `open`, `stick`, `slip`, `grouted` or `reopened` (as in `apertures.csv`).
    pub fn as_str(self) -> &'static str {
        match self {
            JointState::Open => "open",
            JointState::Stick => "stick",
            JointState::Slip => "slip",
            JointState::Grouted => "grouted",
            JointState::Reopened => "reopened",
        }
    }

    /// The number a VTU snapshot stores for ParaView's colour map.
    pub fn code(self) -> f64 {
        match self {
            JointState::Open => 1.0,
            JointState::Stick => 2.0,
            JointState::Slip => 3.0,
            JointState::Grouted => 4.0,
            JointState::Reopened => 5.0,
        }
    }
}

impl fmt::Display for JointState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A value a validator refused: the key it was read from (as the user
/// wrote it, relative to the table being checked) and a message that names
/// the key, what was expected and what was found. Every settings or
/// material `validate()` returns this; the scene locates it in its file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct Invalid {
    pub key: String,
    pub message: String,
}

impl Invalid {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Invalid {
        Invalid {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// FNV-1a, 64 bits: the one stable digest (unlike the std hasher, the same
/// across Rust versions and processes) of restart fingerprints, the remedy
/// memo's keys and mesh files.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}
