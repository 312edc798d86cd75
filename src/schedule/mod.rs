//! CSV schedules: pours, cooling, grouting, weather, reservoir, joint meters.
//!
//! A schedule folder (`schedules/<site>/`) holds one CSV file per kind of
//! event. [`load`] reads a folder, checks every cell and the rows against each
//! other, and returns [`Schedules`]; [`check_against`] then checks it against
//! the dam being simulated ([`DamLayout`]). [`write_dir`] writes a
//! [`Schedules`] back in the same formats, and [`synthesize`] builds a
//! plausible construction schedule for a layout (demo scenes).
//!
//! # Common rules
//!
//! - Comma-separated, UTF-8 (a byte-order mark is ignored), a header row is
//!   required and must name the columns below in this order (case is
//!   ignored). Fields may be quoted.
//! - Blank lines are ignored; whitespace around a field is trimmed.
//! - Dates are ISO `YYYY-MM-DD`; numbers use `.` as the decimal separator and
//!   must be finite. Blocks, lifts, joints and zones are whole numbers ≥ 1,
//!   numbered as on site: blocks from the left bank, joint *j* between blocks
//!   *j* and *j + 1*, lifts and zones from the bottom.
//! - Rows may come in any order unless said otherwise.
//! - Every error names the file, the 1-based line, and for a bad cell the
//!   1-based column number and name, what was expected and the text found:
//!   `pours.csv:12:3 (pour_date): expected a date YYYY-MM-DD, found "2025-13-01"`.
//!   Errors between rows name both lines.
//!
//! # Files
//!
//! `pours.csv` (required): `block,lift,pour_date,placement_temp_c`
//! - one row per lift; lift 1 is the first lift on the block's foundation;
//!   a block's lifts are numbered without gaps; no duplicate (block, lift);
//! - each lift is poured strictly after the lift below it (a later day);
//! - placement temperature within 0–40 °C.
//!
//! `cooling.csv` (optional; absent = no pipe cooling):
//! `block,lift_from,lift_to,stage,start_date,end_date,water_temp_c,target_temp_c`
//! - one pipe-cooling stage of lifts `lift_from..=lift_to` of one block;
//!   `stage` ∈ `first`, `middle`, `second`, `extra`;
//! - `end_date` or `target_temp_c` may be blank, not both. A stage ends at its
//!   end date (exclusive: the water stops at the start of that day) or when
//!   the mean temperature of the cooled region falls to `target_temp_c`,
//!   whichever comes first; the target must be above the water temperature;
//! - water temperature within 0–30 °C, target within 0–40 °C;
//!   `end_date` after `start_date`; `lift_from ≤ lift_to`;
//! - every lift of the range is poured on or before `start_date`;
//! - stages on the same lift must not overlap. A stage with an end date
//!   occupies `[start_date, end_date)`, so the next stage may start on the end
//!   date. A stage without an end date runs until its target is reached; a
//!   later stage on the same lift may start while it runs, and that start ends
//!   it (an implicit end, not an overlap). Two stages of the same lift may not
//!   start on the same day;
//! - **a water change inside a running stage** is written as the stage split
//!   at the change date: a row with the same block, lifts and stage as a row
//!   that ends on its start date *continues* that row. It is the same cooling
//!   with new water from its start date: the stage's clock is kept (Zhu's
//!   superposition: the region's mean gains δ·[1 − φ(t − t₁)] for a change δ
//!   at t₁), where an unrelated new stage would restart it. Each row's
//!   target applies while that row runs.
//!
//! `grouting.csv` (optional for now): `joint,zone,planned_date[,status]`
//! - one row per (joint, zone), no duplicates;
//! - the optional `status` column is `done` for a zone already grouted (the
//!   planner's default as-of date is the day after the last of these),
//!   `planned` or blank otherwise. [`check_against`] checks that
//!   the joint and zone exist and that every lift of both blocks spanning the
//!   zone is poured before the planned date.
//!
//! `weather.csv` (optional): `date,air_temp_c` — daily (or sparser) mean air
//! temperature, dates strictly increasing, −60–60 °C.
//!
//! `reservoir.csv` (optional): `date,level_m` — reservoir level (elevation, m),
//! dates strictly increasing, finite levels.
//!
//! `joint_meters.csv` (optional): `joint,zone,point,date,aperture_mm` —
//! measured apertures; `point` ∈ `upstream`, `center`, `downstream`, `min`;
//! no duplicate (joint, zone, point, date).

mod check;
mod error;
mod layout;
mod read;
mod synth;
mod warning;
mod write;

use std::fmt;
use std::path::{Path, PathBuf};

use chrono::NaiveDate;

use crate::vocab::{ZoneId, ZonePoint};

pub(crate) use check::lifts_label;
pub use check::{
    check_dates, check_reservoir, validate, warnings, MAX_LEVEL_ABOVE_CREST, MAX_SCHEDULE_YEARS,
};
pub use error::ScheduleError;
pub use layout::{check_against, DamLayout, ZoneExtent};
pub(crate) use read::line_at;
pub use synth::{synthesize, SynthParams};
pub use warning::Warning;
pub use write::write_dir;

/// File names inside a schedule folder.
pub const POURS_CSV: &str = "pours.csv";
pub const COOLING_CSV: &str = "cooling.csv";
pub const GROUTING_CSV: &str = "grouting.csv";
pub const WEATHER_CSV: &str = "weather.csv";
pub const RESERVOIR_CSV: &str = "reservoir.csv";
pub const JOINT_METERS_CSV: &str = "joint_meters.csv";

/// Header rows, in column order.
pub const POURS_HEADER: [&str; 4] = ["block", "lift", "pour_date", "placement_temp_c"];
pub const COOLING_HEADER: [&str; 8] = [
    "block",
    "lift_from",
    "lift_to",
    "stage",
    "start_date",
    "end_date",
    "water_temp_c",
    "target_temp_c",
];
pub const GROUTING_HEADER: [&str; 3] = ["joint", "zone", "planned_date"];
/// `grouting.csv` with the optional `status` column.
pub const GROUTING_HEADER_STATUS: [&str; 4] = ["joint", "zone", "planned_date", "status"];
pub const WEATHER_HEADER: [&str; 2] = ["date", "air_temp_c"];
pub const RESERVOIR_HEADER: [&str; 2] = ["date", "level_m"];
pub const JOINT_METERS_HEADER: [&str; 5] = ["joint", "zone", "point", "date", "aperture_mm"];

/// One lift poured: its elements are born on `date` at `placement_temp_c`.
#[derive(Debug, Clone, PartialEq)]
pub struct Pour {
    pub block: u32,
    pub lift: u32,
    pub date: NaiveDate,
    pub placement_temp_c: f64,
    /// 1-based line in `pours.csv` (for error messages).
    pub line: usize,
}

/// Pipe-cooling stage kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// First-stage cooling right after pouring (peak control, to ≈ 20 °C).
    First,
    /// Intermediate stage holding/slowly lowering the temperature.
    Middle,
    /// Second stage down to the closure (grouting) temperature.
    Second,
    /// Any additional stage (e.g. supercooling before regrouting).
    Extra,
}

impl Stage {
    /// All stages, in the order of the CSV vocabulary.
    pub const ALL: [Stage; 4] = [Stage::First, Stage::Middle, Stage::Second, Stage::Extra];

    /// The CSV spelling: `first`, `middle`, `second`, `extra`.
    pub fn as_str(self) -> &'static str {
        match self {
            Stage::First => "first",
            Stage::Middle => "middle",
            Stage::Second => "second",
            Stage::Extra => "extra",
        }
    }

    /// Parses the CSV spelling (case-insensitive, surrounding blanks ignored).
    pub fn parse(text: &str) -> Option<Stage> {
        let t = text.trim();
        Stage::ALL
            .into_iter()
            .find(|s| s.as_str().eq_ignore_ascii_case(t))
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One pipe-cooling stage of lifts `lift_from..=lift_to` of one block.
///
/// It ends at `end` (exclusive) or when the cooled region's mean temperature
/// falls to `target_temp_c`, whichever comes first; at least one is `Some`.
/// A stage without `end` is also ended by the start of the next stage on the
/// same lift.
#[derive(Debug, Clone, PartialEq)]
pub struct CoolingStage {
    pub block: u32,
    pub lift_from: u32,
    pub lift_to: u32,
    pub stage: Stage,
    pub start: NaiveDate,
    pub end: Option<NaiveDate>,
    pub water_temp_c: f64,
    pub target_temp_c: Option<f64>,
    /// 1-based line in `cooling.csv`.
    pub line: usize,
}

impl CoolingStage {
    /// Whether the stage cools `lift` of `block`.
    pub fn covers(&self, block: u32, lift: u32) -> bool {
        self.block == block && self.lift_from <= lift && lift <= self.lift_to
    }

    /// Whether `next` continues this row: the same cooling (block, lifts,
    /// stage) with new water from this row's end date.
    pub fn continued_by(&self, next: &CoolingStage) -> bool {
        (self.block, self.lift_from, self.lift_to, self.stage)
            == (next.block, next.lift_from, next.lift_to, next.stage)
            && self.end == Some(next.start)
    }
}

/// The cooling rows grouped into stages: each chain lists the rows of one
/// stage in time order (a row, then the rows continuing it, see
/// [`CoolingStage::continued_by`]), chains in the order of their first row.
pub fn cooling_chains(cooling: &[CoolingStage]) -> Vec<Vec<usize>> {
    let continues = |i: usize| cooling.iter().any(|c| c.continued_by(&cooling[i]));
    let mut chains = Vec::new();
    for head in (0..cooling.len()).filter(|&i| !continues(i)) {
        let mut chain = vec![head];
        // Bounded: every step moves to a later start date.
        while let Some(next) = (0..cooling.len())
            .find(|&j| cooling[*chain.last().unwrap_or(&head)].continued_by(&cooling[j]))
        {
            chain.push(next);
        }
        chains.push(chain);
    }
    chains
}

/// Planned grouting date of one zone of one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct GroutingPlan {
    pub joint: u32,
    pub zone: u32,
    pub planned: NaiveDate,
    /// `status` = `done`: grouted (its date is history for the planner).
    pub done: bool,
    /// 1-based line in `grouting.csv`.
    pub line: usize,
}

impl GroutingPlan {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }
}

/// One measured joint aperture.
#[derive(Debug, Clone, PartialEq)]
pub struct JointMeter {
    pub joint: u32,
    pub zone: u32,
    /// where the meter reads (the `point` column; `min` is the zone's minimum)
    pub point: ZonePoint,
    pub date: NaiveDate,
    pub aperture_mm: f64,
    /// 1-based line in `joint_meters.csv`.
    pub line: usize,
}

impl JointMeter {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }
}

/// Everything read from one schedule folder. Rows keep the file order.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedules {
    /// Folder the CSVs were read from (empty for a synthesized schedule).
    pub dir: PathBuf,
    pub pours: Vec<Pour>,
    /// Empty when `cooling.csv` is absent.
    pub cooling: Vec<CoolingStage>,
    /// Empty when `grouting.csv` is absent.
    pub grouting: Vec<GroutingPlan>,
    /// `(date, air temperature °C)`, dates strictly increasing.
    pub weather: Option<Vec<(NaiveDate, f64)>>,
    /// `(date, level m)`, dates strictly increasing.
    pub reservoir: Option<Vec<(NaiveDate, f64)>>,
    pub joint_meters: Option<Vec<JointMeter>>,
}

impl Schedules {
    /// The pour of `lift` of `block`, if any (linear search).
    pub fn pour(&self, block: u32, lift: u32) -> Option<&Pour> {
        self.pours
            .iter()
            .find(|p| p.block == block && p.lift == lift)
    }

    /// The zones of `grouting.csv` by planned date (then zone), those
    /// planned on or before `last` when given.
    pub fn grouting_by_date(&self, last: Option<NaiveDate>) -> Vec<(NaiveDate, ZoneId)> {
        let mut rows: Vec<(NaiveDate, ZoneId)> = self
            .grouting
            .iter()
            .filter(|g| last.is_none_or(|l| g.planned <= l))
            .map(|g| (g.planned, g.zone_id()))
            .collect();
        rows.sort();
        rows
    }

    /// The grouting plan of `zone` of `joint`, if any (linear search).
    pub fn grouting_of(&self, zone: ZoneId) -> Option<&GroutingPlan> {
        self.grouting.iter().find(|g| g.zone_id() == zone)
    }

    /// The first and last dates of pours, cooling starts/ends and grouting
    /// plans (weather, reservoir and meters are not events), or `None` when
    /// there is no event.
    pub fn event_span(&self) -> Option<(NaiveDate, NaiveDate)> {
        let dates = self
            .pours
            .iter()
            .map(|p| p.date)
            .chain(self.cooling.iter().map(|c| c.start))
            .chain(self.cooling.iter().filter_map(|c| c.end))
            .chain(self.grouting.iter().map(|g| g.planned));
        dates.fold(None, |acc, d| match acc {
            None => Some((d, d)),
            Some((a, b)) => Some((a.min(d), b.max(d))),
        })
    }
}

/// Reads and checks a schedule folder.
///
/// `pours.csv` is required; the other files are optional. Checks every cell
/// and the rows against each other (see the module documentation); the first
/// error found is returned. Files are checked in the order pours, cooling,
/// grouting, weather, reservoir, joint meters.
pub fn load(dir: &Path) -> Result<Schedules, ScheduleError> {
    read::load_dir(dir)
}
