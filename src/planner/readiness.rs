//! What the planner answers per grouting zone: the rules checked on the
//! planned date, the verdict, and the remedy found. Plain data, read by the
//! report writers and the TUI.

use chrono::NaiveDate;
use serde::{Deserialize, Serialize};

use crate::scene::PlannerSettings;
use crate::vocab::{ZoneId, ZonePoint};

/// A readiness rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rule {
    /// aperture at the deciding point ≥ `min_aperture_mm`
    Aperture,
    /// both adjacent blocks at or below closure + tolerance over the zone
    Temperature,
    /// youngest lift of the zone at least `min_age_days` old
    Age,
    /// at least `min_cover_m` of concrete above the zone on both blocks
    Cover,
    /// the zone below on the same joint grouted on or before this date
    BottomUp,
}

impl Rule {
    pub const ALL: [Rule; 5] = [
        Rule::Aperture,
        Rule::Temperature,
        Rule::Age,
        Rule::Cover,
        Rule::BottomUp,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Rule::Aperture => "aperture",
            Rule::Temperature => "temperature",
            Rule::Age => "age",
            Rule::Cover => "cover",
            Rule::BottomUp => "bottom_up",
        }
    }
}

/// One rule checked on one zone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RuleCheck {
    pub rule: Rule,
    /// the value checked (mm, °C, days, m; for bottom-up the days the zone
    /// below is grouted before this one), None where it could not be measured
    pub value: Option<f64>,
    /// the limit it is checked against, same unit
    pub limit: f64,
    pub passed: bool,
    /// plain words, set when the rule fails
    pub reason: Option<String>,
}

/// Apertures of a zone on one date \[mm\]; None where the zone's two blocks do
/// not both exist yet.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Apertures {
    pub upstream: Option<f64>,
    pub center: Option<f64>,
    pub downstream: Option<f64>,
    pub min: Option<f64>,
}

impl Apertures {
    /// The aperture at `point` \[mm\].
    pub fn at(&self, point: ZonePoint) -> Option<f64> {
        match point {
            ZonePoint::Upstream => self.upstream,
            ZonePoint::Center => self.center,
            ZonePoint::Downstream => self.downstream,
            ZonePoint::Min => self.min,
        }
    }
}

/// The planner's verdict on a zone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// every rule passes
    Groutable,
    /// every rule passes, but the aperture is below `marginal_aperture_mm`
    Marginal,
    /// at least one rule fails
    NotGroutable,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Groutable => "groutable",
            Verdict::Marginal => "marginal",
            Verdict::NotGroutable => "not_groutable",
        }
    }

    pub fn groutable(self) -> bool {
        self != Verdict::NotGroutable
    }
}

/// Readiness of one (joint, zone) on its planned date.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneReadiness {
    pub joint: u32,
    pub zone: u32,
    pub planned: NaiveDate,
    /// grouted before the as-of date: history, not in the readiness table
    pub history: bool,
    pub z_bottom_m: f64,
    pub z_top_m: f64,
    pub apertures_mm: Apertures,
    /// mean temperature of the zone's concrete in block `joint` (A) and
    /// `joint + 1` (B) on the planned date [°C]
    pub temp_a_c: Option<f64>,
    pub temp_b_c: Option<f64>,
    pub closure_temp_c: f64,
    /// age of the zone's youngest lift on the planned date \[days\]
    pub age_days: Option<f64>,
    /// least height of concrete above the zone's top over both blocks \[m\];
    /// None where both blocks are complete (the rule is waived)
    pub cover_m: Option<f64>,
    pub checks: Vec<RuleCheck>,
    pub verdict: Verdict,
    /// first date after grouting on which a point of the zone re-opened
    /// (the grout layer cracked), within the simulated period
    pub reopened: Option<NaiveDate>,
    pub remedy: Option<Remedy>,
}

impl ZoneReadiness {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }

    /// The failed rules' reasons, joined for one table cell.
    pub fn reasons(&self) -> String {
        self.checks
            .iter()
            .filter_map(|c| c.reason.as_deref())
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// Supercooling of the zone's second-stage cooling (and the region above).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SupercoolOption {
    /// lowering of the cooling target [°C]
    pub delta_c: f64,
    /// aperture at the deciding point on the planned date with it \[mm\]
    pub aperture_mm: f64,
    /// set when the supercooling was chosen together with neighbouring
    /// zones (`planner::joint_remedy`): at less cost than zone by zone, or,
    /// when the zone-by-zone steps failed applied together, the least set
    /// a re-simulation verified
    #[serde(default)]
    pub together: Option<ChosenTogether>,
}

/// A supercooling chosen with its neighbours' as one least-cost set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChosenTogether {
    /// the other zones of the set
    pub with: Vec<ZoneId>,
    /// this zone's supercooling by the zone-by-zone search [°C]
    pub zone_by_zone_c: f64,
    /// the set's supercooling summed over its zones, chosen together and
    /// zone by zone [°C]
    pub set_c: f64,
    pub set_zone_by_zone_c: f64,
    /// whether the zone-by-zone steps, applied together, made every zone
    /// of the search groutable (in the search's own runs: on temperatures
    /// when it ran the thermal effects alone); when not, `set_c` may exceed
    /// `set_zone_by_zone_c` (it is what holding them together costs)
    #[serde(default = "held")]
    pub zone_by_zone_held: bool,
}

/// A file written before `zone_by_zone_held` existed only held sets that
/// cost less than zone by zone.
fn held() -> bool {
    true
}

/// Delay of the zone's grouting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DelayOption {
    pub days: u32,
    pub date: NaiveDate,
    /// aperture at the deciding point on the new date \[mm\]
    pub aperture_mm: f64,
    /// zones above on the same joint that move with it (bottom-up order)
    pub also_delayed: Vec<u32>,
}

/// Which remedy the planner proposes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RemedyChoice {
    Supercool,
    Delay,
    /// neither works within the limits
    None,
}

/// The remedies found for a zone that is not groutable, each verified by
/// re-simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Remedy {
    pub supercool: Option<SupercoolOption>,
    pub delay: Option<DelayOption>,
    pub choice: RemedyChoice,
    /// the verdict and deciding aperture of this zone when every proposed
    /// remedy is applied together and re-simulated
    pub verified: Option<(Verdict, Option<f64>)>,
    /// plain words: why this remedy, or why none works
    pub note: String,
    /// the zone's history in that verification run, to the remedy's date
    /// (the date it is grouted on with the remedy): the charts draw it
    /// beside the baseline
    #[serde(default)]
    pub verified_history: Option<ZoneHistory>,
    /// the site limits its supercooling broke in the verification run, in
    /// words (`planner::limits`); the supercooling is then not proposed
    #[serde(default)]
    pub limited: Vec<String>,
}

/// Joins a supercooling's note and the site limits the schedule is past
/// already and the supercooling too (the verification's cautions, which do
/// not stop it).
pub const CAUTION_MARK: &str =
    "; the schedule is past a site limit already, and the supercooling too: ";

impl Remedy {
    /// The note without the cautions after [`CAUTION_MARK`]: the console
    /// prints a supercooling's note only to say what choosing it together
    /// saved, and leaves the cautions to the report, as for every zone.
    pub fn note_without_cautions(&self) -> &str {
        self.note
            .find(CAUTION_MARK)
            .map_or(self.note.as_str(), |i| &self.note[..i])
    }

    /// Whether the zone is supercooled by its neighbours' remedies alone:
    /// chosen together with them at no supercooling of its own.
    pub fn by_neighbours_alone(&self) -> bool {
        self.choice == RemedyChoice::Supercool
            && self
                .supercool
                .as_ref()
                .is_some_and(|o| o.together.is_some() && o.delta_c <= 0.0)
    }
}

/// Aperture and temperature history of one zone, for charts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneHistory {
    pub joint: u32,
    pub zone: u32,
    pub planned: NaiveDate,
    pub dates: Vec<NaiveDate>,
    /// \[mm\] per date
    pub upstream: Vec<Option<f64>>,
    pub center: Vec<Option<f64>>,
    pub downstream: Vec<Option<f64>>,
    pub min: Vec<Option<f64>>,
    /// the warmer of the two blocks' mean temperatures over the zone [°C]:
    /// the quantity the temperature rule checks against closure + tolerance
    pub temperature: Vec<Option<f64>>,
}

impl ZoneHistory {
    /// The aperture series of `point` [mm per date].
    pub fn series(&self, point: ZonePoint) -> &[Option<f64>] {
        match point {
            ZonePoint::Upstream => &self.upstream,
            ZonePoint::Center => &self.center,
            ZonePoint::Downstream => &self.downstream,
            ZonePoint::Min => &self.min,
        }
    }
}

/// One joint-meter reading against the prediction at its point and date.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeterComparison {
    pub joint: u32,
    pub zone: u32,
    pub point: ZonePoint,
    pub date: NaiveDate,
    pub measured_mm: f64,
    /// None where the zone did not exist yet on that date in the simulation
    pub predicted_mm: Option<f64>,
}

/// How the plan was computed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanStats {
    /// seconds of the baseline simulation (from day 0 or a restart)
    pub baseline_seconds: f64,
    /// first day simulated by the baseline: None from scratch, else the date
    /// of the checkpoint it restarted from
    pub restarted_from: Option<NaiveDate>,
    /// re-simulations of the remedy search
    pub resimulations: usize,
    /// wall time of the remedy search (its re-simulations run two at a
    /// time, so this is not their sum)
    pub resimulation_seconds: f64,
    /// the parts of the remedy search taken from the last plan, in words
    /// ("delay search (1 runs)")
    pub reused: Vec<String>,
    pub total_seconds: f64,
}

/// The planner's answer for one scene and one set of schedules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub scene: String,
    pub as_of: NaiveDate,
    pub settings: PlannerSettings,
    /// every (joint, zone) of grouting.csv, by planned date then joint, zone
    pub zones: Vec<ZoneReadiness>,
    /// histories of the zones still to grout that are flagged (and of the
    /// zones with joint meters)
    pub histories: Vec<ZoneHistory>,
    pub meters: Vec<MeterComparison>,
    pub stats: PlanStats,
    /// inputs the plan accepted but that look wrong (the report repeats them)
    #[serde(default)]
    pub warnings: Vec<crate::schedule::Warning>,
    /// the opt-in approximations the scene's mechanics was computed with
    /// (empty: the exact path; the reports say which)
    #[serde(default)]
    pub approximations: Vec<crate::scene::Approximation>,
}

impl Plan {
    /// Zones still to grout (planned on or after the as-of date).
    pub fn to_grout(&self) -> impl Iterator<Item = &ZoneReadiness> {
        self.zones.iter().filter(|z| !z.history)
    }

    /// Zones still to grout that are not groutable.
    pub fn flagged(&self) -> impl Iterator<Item = &ZoneReadiness> {
        self.to_grout().filter(|z| !z.verdict.groutable())
    }
}
