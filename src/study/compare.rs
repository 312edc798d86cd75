//! `groutready study compare RUN_A RUN_B [SCENE]`: how far apart two runs'
//! apertures are where the planner decides.
//!
//! An opt-in approximation (`[time] mechanics_max_step_days = 3`, the
//! capacitance correction, a coarser rock) is only worth its time when its
//! apertures stay close to the exact path's on the dates the planner reads
//! them. This compares the `apertures.csv` of two run folders of one scene
//! (written by `groutready run` or `plan`; a path to the file itself is
//! taken too):
//!
//! - at each zone's planned grouting date of the scene's `grouting.csv`, the
//!   deciding point (`[planner] aperture_point`, `min` by default): zones
//!   compared, planned dates missing from either file, the largest
//!   difference |a − b| and where, the RMS over the zones compared, contact
//!   states differing, and verdicts on the aperture differing (aperture ≥
//!   `[planner] min_aperture_mm` in one run and below it in the other: the
//!   planner's rule, `planner::rules`);
//! - over every row both files share (all points, all dates): rows, the
//!   largest difference and where, rows differing by more than
//!   [`NOTABLE_DIFF_MM`];
//! - rows in one file only (a run that ended earlier, other snapshot dates).
//!
//! A run folder's approximations of the mechanics, as its `run.txt` lists
//! them, are named beside its file, so the report says which run is the
//! exact one.
//!
//! Rows are keyed by (zone, point, day). Each row's `date` must be its `day`
//! counted from the scene's epoch, so a run compared against the wrong
//! scene is refused rather than compared on shifted dates. Differences are
//! those of the values as written (4 decimals, so the resolution is
//! 0.0001 mm). Nothing is simulated: the comparison of two demo runs takes a
//! fraction of a second. Ties for the largest difference go to the first in
//! `grouting.csv` order (planned dates) or in key order (shared rows).
//!
//! Tested here on hand-written files (identical files, a known difference
//! with a state and a verdict flip, rows in one file only, malformed cells)
//! and in `tests/it/study_compare.rs` through the binary on the demo's
//! schedule.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use chrono::NaiveDate;
use serde::Deserialize;

use super::StudyError;
use crate::app::AppError;
use crate::output::apertures;
use crate::scene::{PlannerSettings, Scene};
use crate::schedule::{self, GroutingPlan};
use crate::vocab::{Day, Epoch, JointState, ZoneId, ZonePoint};

/// Shared rows differing by more than this are counted \[mm\]: ten times the
/// file's resolution, well below the planner's 0.5 mm limit.
pub const NOTABLE_DIFF_MM: f64 = 0.05;

/// The columns read (the file has `temperature_c` and `pressure_mpa` too).
const COLUMNS: [&str; 7] = [
    "joint",
    "zone",
    "point",
    "date",
    "day",
    "aperture_mm",
    "state",
];

/// The header `groutready` writes, quoted in messages.
const HEADER: &str = "joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa";

/// One row of `apertures.csv`, as far as the comparison reads it.
#[derive(Debug, Deserialize)]
struct Row {
    joint: u32,
    zone: u32,
    point: ZonePoint,
    date: NaiveDate,
    day: Day,
    aperture_mm: f64,
    state: JointState,
}

/// Where a row sits: zone, point, day.
pub type Key = (ZoneId, ZonePoint, Day);

/// What a row says at its key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub aperture_mm: f64,
    pub state: JointState,
    /// 1-based line in the file
    pub line: u64,
}

/// One run's `apertures.csv`, read and checked.
#[derive(Debug, Clone, Default)]
pub struct Apertures {
    /// the file, as messages name it
    pub file: String,
    pub rows: BTreeMap<Key, Sample>,
}

/// A largest difference and where it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Largest {
    /// |a − b| \[mm\]
    pub diff_mm: f64,
    pub zone: ZoneId,
    pub point: ZonePoint,
    pub date: NaiveDate,
    /// the two runs' apertures \[mm\]
    pub a_mm: f64,
    pub b_mm: f64,
}

/// The deciding aperture at each zone's planned grouting date.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AtPlannedDates {
    /// rows of `grouting.csv`
    pub planned: usize,
    /// planned dates present in both files
    pub compared: usize,
    /// planned dates missing from A, from B
    pub missing: [usize; 2],
    /// the zones whose planned date either file lacks, with the date
    pub missing_zones: Vec<(ZoneId, NaiveDate)>,
    pub largest: Option<Largest>,
    /// root mean square of the differences compared \[mm\]
    pub rms_mm: f64,
    /// zones whose contact states differ
    pub states_differ: usize,
    /// zones at or above the aperture limit in one run and below it in the
    /// other, with their planned dates
    pub verdicts_differ: Vec<(ZoneId, NaiveDate)>,
}

/// Every row both files share.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Shared {
    pub rows: usize,
    pub largest: Option<Largest>,
    /// rows differing by more than [`NOTABLE_DIFF_MM`]
    pub notable: usize,
}

/// Two runs' apertures compared ([`compare`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Comparison {
    /// the files of run A and run B
    pub files: [String; 2],
    /// the deciding point (`[planner] aperture_point`)
    pub point: ZonePoint,
    /// the planner's aperture limit (`[planner] min_aperture_mm`) \[mm\]
    pub limit_mm: f64,
    pub planned: AtPlannedDates,
    pub shared: Shared,
    /// rows only in A, only in B
    pub only_in: [usize; 2],
    /// the mechanics' approximations of A and B as their `run.txt` lists
    /// them (None: a file, or a folder without that line)
    pub approximations: [Option<String>; 2],
}

/// Compares the `apertures.csv` of runs `run_a` and `run_b` (run folders or
/// the files) at the planned grouting dates of `scene`'s schedule, with its
/// planner's deciding point and aperture limit.
pub fn compare(run_a: &Path, run_b: &Path, scene: &Path) -> Result<Comparison, StudyError> {
    let (s, grouting) = grouting_schedule(scene)?;
    let a = Apertures::read(&apertures_csv(run_a)?, s.epoch)?;
    let b = Apertures::read(&apertures_csv(run_b)?, s.epoch)?;
    let mut c = Comparison::of(&a, &b, &grouting, &s.planner, s.epoch);
    c.approximations = [run_a, run_b].map(approximations_of_run);
    Ok(c)
}

/// The approximations a run folder's `run.txt` lists, as written there.
fn approximations_of_run(run: &Path) -> Option<String> {
    let text = std::fs::read_to_string(run.join("run.txt")).ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix(crate::app::APPROXIMATIONS_LINE))
        .map(str::to_string)
}

/// The scene and the rows of its `grouting.csv` (read with the rest of its
/// schedules folder and checked as `groutready run` checks it; no mesh).
fn grouting_schedule(path: &Path) -> Result<(Scene, Vec<GroutingPlan>), StudyError> {
    let scene = Scene::load(path)?;
    let dir = scene
        .schedules_dir(path)
        .ok_or_else(|| AppError::NoSchedules(path.display().to_string()))?;
    let schedules = schedule::load(&dir).map_err(AppError::from)?;
    schedule::check_dates(&schedules, scene.epoch.0).map_err(AppError::from)?;
    Ok((scene, schedules.grouting))
}

/// `run/apertures.csv` for a run folder, `run` itself for a file.
pub fn apertures_csv(run: &Path) -> Result<PathBuf, StudyError> {
    let not_a_run = |why| StudyError::NotARun {
        path: run.display().to_string(),
        why,
    };
    if run.is_dir() {
        let file = run.join(apertures::FILE_NAME);
        if !file.exists() {
            return Err(not_a_run("no apertures.csv in this folder"));
        }
        return Ok(file);
    }
    if !run.exists() {
        return Err(not_a_run("no such file or folder"));
    }
    Ok(run.to_path_buf())
}

impl Apertures {
    /// Reads `path`, checking every row's date against `epoch`.
    pub fn read(path: &Path, epoch: Epoch) -> Result<Apertures, StudyError> {
        let file = std::fs::File::open(path).map_err(|source| StudyError::Io {
            action: "reading",
            path: path.display().to_string(),
            source,
        })?;
        Apertures::parse(file, &path.display().to_string(), epoch)
    }

    /// Reads CSV text from `reader`; `file` names it in messages.
    pub fn parse(reader: impl Read, file: &str, epoch: Epoch) -> Result<Apertures, StudyError> {
        let mut csv = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(reader);
        let headers = csv.headers().map_err(|e| csv_error(file, e, None))?.clone();
        let columns = check_header(file, &headers)?;
        let mut out = Apertures {
            file: file.to_string(),
            rows: BTreeMap::new(),
        };
        let mut record = csv::StringRecord::new();
        while csv
            .read_record(&mut record)
            .map_err(|e| csv_error(file, e, None))?
        {
            let line = record.position().map_or(0, |p| p.line());
            let row: Row = record
                .deserialize(Some(&headers))
                .map_err(|e| csv_error(file, e, Some((&headers, &record))))?;
            let cell = |name: &str, message: String| StudyError::Apertures {
                file: file.to_string(),
                line,
                cell: columns.get(name).map(|&c| (c, name.to_string())),
                message,
            };
            out.insert(row, line, epoch, &cell)?;
        }
        Ok(out)
    }

    /// Adds one row read on `line`: a finite aperture, a date that is its
    /// day from `epoch`, a key not seen before.
    fn insert(
        &mut self,
        row: Row,
        line: u64,
        epoch: Epoch,
        cell: &dyn Fn(&str, String) -> StudyError,
    ) -> Result<(), StudyError> {
        if !row.aperture_mm.is_finite() {
            let found = row.aperture_mm;
            return Err(cell(
                "aperture_mm",
                format!("expected a finite number [mm], found {found}"),
            ));
        }
        let key = (ZoneId::new(row.joint, row.zone), row.point, row.day);
        if epoch.date(row.day) != row.date {
            let (expected, day) = (epoch.date(row.day), row.day.0);
            let message = format!("expected {expected}, day {day} from the scene's epoch {epoch}, found {} (a run of another scene?)", row.date);
            return Err(cell("date", message));
        }
        let sample = Sample {
            aperture_mm: row.aperture_mm,
            state: row.state,
            line,
        };
        if let Some(first) = self.rows.insert(key, sample) {
            let (zone, point, line) = (key.0, key.1, first.line);
            let message = format!("expected one row per zone, point and day, found {zone} {point} {} again (first on line {line})", row.date);
            return Err(cell("", message));
        }
        Ok(())
    }
}

/// The 1-based column of each column read, or an error naming the first
/// one missing.
fn check_header(
    file: &str,
    headers: &csv::StringRecord,
) -> Result<BTreeMap<&'static str, usize>, StudyError> {
    let mut columns = BTreeMap::new();
    for name in COLUMNS {
        let Some(i) = headers.iter().position(|h| h == name) else {
            let found: Vec<&str> = headers.iter().collect();
            return Err(StudyError::Apertures {
                file: file.to_string(),
                line: 1,
                cell: None,
                message: format!(
                    "expected a header with column \"{name}\" ({HEADER}), found {:?}",
                    found.join(",")
                ),
            });
        };
        columns.insert(name, i + 1);
    }
    Ok(columns)
}

/// A csv reader's error as the file, line and (for one cell) column, what
/// was expected and what was found.
fn csv_error(
    file: &str,
    e: csv::Error,
    record: Option<(&csv::StringRecord, &csv::StringRecord)>,
) -> StudyError {
    let line = e.position().map_or(1, |p| p.line());
    let err = |cell: Option<(usize, String)>, message: String| StudyError::Apertures {
        file: file.to_string(),
        line,
        cell,
        message,
    };
    match e.kind() {
        csv::ErrorKind::Io(source) => StudyError::Io {
            action: "reading",
            path: file.to_string(),
            source: std::io::Error::new(source.kind(), source.to_string()),
        },
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => err(
            None,
            format!("expected {expected_len} fields, as in the header, found {len}"),
        ),
        csv::ErrorKind::Deserialize { err: de, .. } => {
            // the reader names the field of a number it cannot read, not
            // that of a date or a word
            let field = de
                .field()
                .map(|f| f as usize)
                .or_else(|| record.and_then(|(h, r)| failing_column(h, r)));
            let name = field.zip(record.map(|r| r.0)).and_then(|(f, h)| h.get(f));
            let found = field.zip(record.map(|r| r.1)).and_then(|(f, r)| r.get(f));
            match (name, found) {
                (Some(name), Some(found)) => err(
                    field.map(|f| (f + 1, name.to_string())),
                    format!("{}, found {found:?}", expected(name)),
                ),
                _ => err(None, format!("expected a row of {HEADER} ({de})")),
            }
        }
        csv::ErrorKind::Utf8 { err: u, .. } => err(
            None,
            format!(
                "expected UTF-8 text, found other bytes in column {}",
                u.field() + 1
            ),
        ),
        _ => err(None, format!("expected CSV text ({e})")),
    }
}

/// The 0-based column of the first cell of `record` that does not read as
/// its column's type on its own.
fn failing_column(headers: &csv::StringRecord, record: &csv::StringRecord) -> Option<usize> {
    COLUMNS.iter().find_map(|&name| {
        let i = headers.iter().position(|h| h == name)?;
        let cell = csv::StringRecord::from(vec![record.get(i)?]);
        let reads = match name {
            "joint" | "zone" => cell.deserialize::<(u32,)>(None).is_ok(),
            "point" => cell.deserialize::<(ZonePoint,)>(None).is_ok(),
            "date" => cell.deserialize::<(NaiveDate,)>(None).is_ok(),
            "day" => cell.deserialize::<(Day,)>(None).is_ok(),
            "aperture_mm" => cell.deserialize::<(f64,)>(None).is_ok(),
            "state" => cell.deserialize::<(JointState,)>(None).is_ok(),
            _ => true,
        };
        (!reads).then_some(i)
    })
}

/// What a column of `apertures.csv` holds.
fn expected(column: &str) -> &'static str {
    match column {
        "joint" | "zone" => "expected a whole number",
        "day" => "expected a whole number of days",
        "date" => "expected a date YYYY-MM-DD",
        "point" => "expected upstream, center, downstream or min",
        "aperture_mm" => "expected a number [mm]",
        "state" => "expected open, stick, slip, grouted or reopened",
        _ => "expected a value",
    }
}

impl Comparison {
    /// Compares `a` and `b` at the planned dates of `grouting` (read at
    /// `settings.aperture_point`, judged against `settings.min_aperture_mm`)
    /// and over the rows they share.
    pub fn of(
        a: &Apertures,
        b: &Apertures,
        grouting: &[GroutingPlan],
        settings: &PlannerSettings,
        epoch: Epoch,
    ) -> Comparison {
        let only = |x: &Apertures, y: &Apertures| {
            x.rows.keys().filter(|k| !y.rows.contains_key(k)).count()
        };
        Comparison {
            files: [a.file.clone(), b.file.clone()],
            point: settings.aperture_point,
            limit_mm: settings.min_aperture_mm,
            planned: at_planned_dates(a, b, grouting, settings, epoch),
            shared: shared(a, b, epoch),
            only_in: [only(a, b), only(b, a)],
            approximations: [None, None],
        }
    }

    /// A few lines of plain text, apertures in mm with 4 decimals.
    pub fn report(&self) -> String {
        let p = &self.planned;
        let [a, b] = &self.files;
        let mut out = String::new();
        for (name, file, approximations) in [
            ("A", a, &self.approximations[0]),
            ("B", b, &self.approximations[1]),
        ] {
            match approximations {
                Some(x) => out += &format!("{name}: {file} (mechanics approximations: {x})\n"),
                None => out += &format!("{name}: {file}\n"),
            }
        }
        out += &format!(
            "at the planned grouting dates ({} zones in grouting.csv, point {}): {} compared, {} missing from A, {} missing from B\n",
            p.planned, self.point, p.compared, p.missing[0], p.missing[1]
        );
        if !p.missing_zones.is_empty() {
            out += &format!(
                "  missing: {} (planned after a run's end, or a run of another scene?)\n",
                zones_list(&p.missing_zones)
            );
        }
        out += &format!(
            "  largest difference {}; RMS {:.4} mm\n",
            largest_text(p.largest.as_ref(), false),
            p.rms_mm
        );
        out += &format!(
            "  contact states differing: {}; verdicts differing (aperture >= {:.4} mm in one run only): {}{}\n",
            p.states_differ,
            self.limit_mm,
            p.verdicts_differ.len(),
            if p.verdicts_differ.is_empty() {
                String::new()
            } else {
                format!(" ({})", zones_list(&p.verdicts_differ))
            }
        );
        let s = &self.shared;
        out += &format!(
            "all rows both files share (every point and date): {} rows, largest difference {}; {} differ by more than {NOTABLE_DIFF_MM:.4} mm\n",
            s.rows,
            largest_text(s.largest.as_ref(), true),
            s.notable
        );
        out += &format!(
            "rows in one file only: {} only in A, {} only in B\n",
            self.only_in[0], self.only_in[1]
        );
        out
    }
}

/// "0.1710 mm at joint 11 zone 14 [min] on 2025-09-15 (A …, B … mm)", or
/// "none (no row compared)".
fn largest_text(l: Option<&Largest>, with_point: bool) -> String {
    let Some(l) = l else {
        return "none (no row compared)".to_string();
    };
    let point = if with_point {
        format!(" {}", l.point)
    } else {
        String::new()
    };
    format!(
        "{:.4} mm at {}{point} on {} (A {:.4} mm, B {:.4} mm)",
        l.diff_mm, l.zone, l.date, l.a_mm, l.b_mm
    )
}

/// "joint 3 zone 4 on 2025-06-01, …, 7 more": the first few of `zones`.
fn zones_list(zones: &[(ZoneId, NaiveDate)]) -> String {
    const SHOWN: usize = 5;
    let mut names: Vec<String> = zones
        .iter()
        .take(SHOWN)
        .map(|(z, d)| format!("{z} on {d}"))
        .collect();
    if zones.len() > SHOWN {
        names.push(format!("{} more", zones.len() - SHOWN));
    }
    names.join(", ")
}

/// Keeps the larger of `best` and the difference at `key`, the earlier on a
/// tie.
fn keep_largest(best: &mut Option<Largest>, key: &Key, a: &Sample, b: &Sample, epoch: Epoch) {
    let diff_mm = (a.aperture_mm - b.aperture_mm).abs();
    if best.is_some_and(|l| l.diff_mm >= diff_mm) {
        return;
    }
    *best = Some(Largest {
        diff_mm,
        zone: key.0,
        point: key.1,
        date: epoch.date(key.2),
        a_mm: a.aperture_mm,
        b_mm: b.aperture_mm,
    });
}

/// The deciding aperture of each zone of `grouting` on its planned date.
fn at_planned_dates(
    a: &Apertures,
    b: &Apertures,
    grouting: &[GroutingPlan],
    settings: &PlannerSettings,
    epoch: Epoch,
) -> AtPlannedDates {
    let mut out = AtPlannedDates {
        planned: grouting.len(),
        ..AtPlannedDates::default()
    };
    let mut sum_sq = 0.0;
    for g in grouting {
        let key = (g.zone_id(), settings.aperture_point, epoch.day(g.planned));
        let (sa, sb) = (a.rows.get(&key), b.rows.get(&key));
        out.missing[0] += usize::from(sa.is_none());
        out.missing[1] += usize::from(sb.is_none());
        let (Some(sa), Some(sb)) = (sa, sb) else {
            out.missing_zones.push((g.zone_id(), g.planned));
            continue;
        };
        out.compared += 1;
        sum_sq += (sa.aperture_mm - sb.aperture_mm).powi(2);
        keep_largest(&mut out.largest, &key, sa, sb, epoch);
        out.states_differ += usize::from(sa.state != sb.state);
        let groutable = |s: &Sample| s.aperture_mm >= settings.min_aperture_mm;
        if groutable(sa) != groutable(sb) {
            out.verdicts_differ.push((g.zone_id(), g.planned));
        }
    }
    out.rms_mm = (sum_sq / out.compared.max(1) as f64).sqrt();
    out
}

/// Every row of `a` that `b` has too.
fn shared(a: &Apertures, b: &Apertures, epoch: Epoch) -> Shared {
    let mut out = Shared::default();
    for (key, sa) in &a.rows {
        let Some(sb) = b.rows.get(key) else { continue };
        out.rows += 1;
        out.notable += usize::from((sa.aperture_mm - sb.aperture_mm).abs() > NOTABLE_DIFF_MM);
        keep_largest(&mut out.largest, key, sa, sb, epoch);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn date(y: i32, m: u32, d: u32) -> NaiveDate {
        NaiveDate::from_ymd_opt(y, m, d).unwrap()
    }

    fn epoch() -> Epoch {
        Epoch(date(2024, 1, 1))
    }

    /// Zone 3/2 planned on day 150 (2024-05-30), zone 4/1 on day 157.
    fn grouting() -> Vec<GroutingPlan> {
        let plan = |joint, zone, planned, line| GroutingPlan {
            joint,
            zone,
            planned,
            done: false,
            line,
        };
        vec![
            plan(3, 2, date(2024, 5, 30), 2),
            plan(4, 1, date(2024, 6, 6), 3),
        ]
    }

    const A: &str = "joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa
3,2,upstream,2024-05-30,150,0.9000,open,14.000,0.0000
3,2,min,2024-05-30,150,0.5200,open,,0.0000
3,2,min,2024-06-06,157,0.6000,open,13.000,0.0000
4,1,min,2024-06-06,157,1.0000,open,13.000,0.0000
";

    fn parse(text: &str, file: &str) -> Result<Apertures, StudyError> {
        Apertures::parse(text.as_bytes(), file, epoch())
    }

    fn compare(a: &str, b: &str) -> Comparison {
        let (a, b) = (parse(a, "a.csv").unwrap(), parse(b, "b.csv").unwrap());
        Comparison::of(&a, &b, &grouting(), &PlannerSettings::default(), epoch())
    }

    #[test]
    fn identical_files_differ_nowhere() {
        let c = compare(A, A);
        let p = &c.planned;
        assert_eq!((p.planned, p.compared, p.missing), (2, 2, [0, 0]));
        assert_eq!(p.largest.unwrap().diff_mm, 0.0);
        assert_eq!((p.rms_mm, p.states_differ), (0.0, 0));
        assert!(p.verdicts_differ.is_empty());
        assert_eq!((c.shared.rows, c.shared.notable), (4, 0));
        assert_eq!(c.shared.largest.unwrap().diff_mm, 0.0);
        assert_eq!(c.only_in, [0, 0]);
        assert!(
            c.report().contains("largest difference 0.0000 mm"),
            "{}",
            c.report()
        );
    }

    #[test]
    fn a_difference_at_a_planned_date_is_found_with_its_place_state_and_verdict() {
        // zone 3/2's deciding aperture drops across the 0.5 mm limit and
        // sticks; zone 4/1 moves by 0.03 mm; upstream moves by 0.2 mm (not
        // a deciding point: counted among the shared rows only)
        let b = A
            .replace(
                "upstream,2024-05-30,150,0.9000",
                "upstream,2024-05-30,150,1.1000",
            )
            .replace(
                "min,2024-05-30,150,0.5200,open",
                "min,2024-05-30,150,0.4800,stick",
            )
            .replace(
                "4,1,min,2024-06-06,157,1.0000",
                "4,1,min,2024-06-06,157,1.0300",
            );
        let c = compare(A, &b);
        let p = &c.planned;
        assert_eq!(p.compared, 2);
        let l = p.largest.unwrap();
        assert!((l.diff_mm - 0.04).abs() < 1e-12, "{l:?}");
        assert_eq!((l.zone, l.point), (ZoneId::new(3, 2), ZonePoint::Min));
        assert_eq!(l.date, date(2024, 5, 30));
        let rms = ((0.04f64.powi(2) + 0.03f64.powi(2)) / 2.0).sqrt();
        assert!((p.rms_mm - rms).abs() < 1e-12, "{}", p.rms_mm);
        assert_eq!(p.states_differ, 1);
        assert_eq!(
            p.verdicts_differ,
            vec![(ZoneId::new(3, 2), date(2024, 5, 30))]
        );
        let s = c.shared.largest.unwrap();
        assert!((s.diff_mm - 0.2).abs() < 1e-12, "{s:?}");
        assert_eq!(s.point, ZonePoint::Upstream);
        assert_eq!(c.shared.notable, 1);
        let report = c.report();
        assert!(
            report.contains("0.0400 mm at joint 3 zone 2 on 2024-05-30"),
            "{report}"
        );
        assert!(report.contains("RMS 0.0354 mm"), "{report}");
        assert!(report.contains("contact states differing: 1"), "{report}");
        assert!(
            report.contains("in one run only): 1 (joint 3 zone 2 on 2024-05-30)"),
            "{report}"
        );
    }

    #[test]
    fn rows_in_one_file_only_are_counted_and_missing_planned_dates_named() {
        // B ended before zone 4/1's planned date and has a snapshot row A lacks
        let b = A.replace("4,1,min,2024-06-06,157,1.0000,open,13.000,0.0000\n", "")
            + "3,2,center,2024-06-01,152,0.7000,open,13.500,0.0000\n";
        let c = compare(A, &b);
        assert_eq!(c.only_in, [1, 1]);
        assert_eq!(c.shared.rows, 3);
        assert_eq!(c.planned.compared, 1);
        assert_eq!(c.planned.missing, [0, 1]);
        assert_eq!(
            c.planned.missing_zones,
            vec![(ZoneId::new(4, 1), date(2024, 6, 6))]
        );
        assert!(
            c.report().contains("1 only in A, 1 only in B"),
            "{}",
            c.report()
        );
    }

    #[test]
    fn a_malformed_aperture_names_file_line_and_column() {
        let bad = A.replace("0.6000", "0.6x00");
        let e = parse(&bad, "runs/a/apertures.csv").unwrap_err().to_string();
        assert_eq!(
            e,
            "runs/a/apertures.csv:4:6 (aperture_mm): expected a number [mm], found \"0.6x00\""
        );
        let nan = A.replace("0.6000", "NaN");
        let e = parse(&nan, "a.csv").unwrap_err().to_string();
        assert!(
            e.starts_with("a.csv:4:6 (aperture_mm): expected a finite"),
            "{e}"
        );
    }

    #[test]
    fn other_bad_rows_name_what_was_expected() {
        let cases = [
            (
                A.replace("aperture_mm,", "aperture,"),
                "a.csv:1: expected a header with column \"aperture_mm\"",
            ),
            (
                A.replace("3,2,min,2024-06-06", "3,2,middle,2024-06-06"),
                "a.csv:4:3 (point): expected upstream, center, downstream or min, found \"middle\"",
            ),
            (
                A.replace("0.5200,open", "0.5200,closed"),
                "a.csv:3:7 (state): expected open, stick, slip, grouted or reopened, found \"closed\"",
            ),
            (
                A.replace("4,1,min,2024-06-06", "4,1,min,2024-06-31"),
                "a.csv:5:4 (date): expected a date YYYY-MM-DD, found \"2024-06-31\"",
            ),
            (
                A.replace("4,1,min", "4,-1,min"),
                "a.csv:5:2 (zone): expected a whole number, found \"-1\"",
            ),
            (
                A.replace(",0.5200,open,,", ",0.5200,open,"),
                "a.csv:3: expected 9 fields, as in the header, found 8",
            ),
            (
                A.replace("2024-06-06,157", "2024-06-07,157"),
                "a.csv:4:4 (date): expected 2024-06-06, day 157",
            ),
            (
                A.to_string() + "4,1,min,2024-06-06,157,1.0000,open,13.000,0.0000\n",
                "a.csv:6: expected one row per zone, point and day, found joint 4 zone 1 min 2024-06-06 again (first on line 5)",
            ),
        ];
        for (text, start) in cases {
            let e = parse(&text, "a.csv").unwrap_err().to_string();
            assert!(e.starts_with(start), "{e}\nexpected: {start}");
        }
    }

    #[test]
    fn a_path_is_a_run_folder_with_apertures_or_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        let e = apertures_csv(tmp.path()).unwrap_err().to_string();
        assert!(
            e.contains("no apertures.csv in this folder: expected a run folder"),
            "{e}"
        );
        let gone = tmp.path().join("gone");
        let e = apertures_csv(&gone).unwrap_err().to_string();
        assert!(e.contains("gone: no such file or folder"), "{e}");
        let file = tmp.path().join(apertures::FILE_NAME);
        std::fs::write(&file, A).unwrap();
        assert_eq!(apertures_csv(tmp.path()).unwrap(), file);
        assert_eq!(apertures_csv(&file).unwrap(), file);
        let read = Apertures::read(&file, epoch()).unwrap();
        assert_eq!(read.rows.len(), 4);
    }
}
