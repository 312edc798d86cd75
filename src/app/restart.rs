//! Weekly updates: a plan's run folder keeps what the next plan needs to
//! restart instead of simulating from day 0.
//!
//! `restart/` holds the schedules as run (`inputs/`), a fingerprint of the
//! scene and program, the histories (`history.bin`) and checkpoints
//! (`ck-DDDDD.bin`, DDDDD the day since the epoch). The next plan with the
//! same scene restarts from the latest checkpoint on or before the first date
//! its schedules differ from `inputs/` (and not after its own end).
//!
//! The folder also keeps the scene as simulated (`scene.json`) and the whole
//! plan (`plan.bin`), so `groutready tui RUN_DIR` can show a run and
//! re-simulate what-ifs from its checkpoints without the scene's file.

use std::path::{Path, PathBuf};

use chrono::NaiveDate;

use crate::planner::edit::first_change;
use crate::planner::memo::{Lineage, SearchMemo};
use crate::planner::plan::{LastPlan, Restart};
use crate::planner::{Plan, PlanOptions};
use crate::scene::Scene;
use crate::schedule::{self, Schedules, Warning};
use crate::sim::checkpoint::{read_file, write_file, CheckpointError};
use crate::sim::{Checkpoint, History};
use crate::vocab::{Day, ZoneId, ZonePoint};

pub const RESTART_DIR: &str = "restart";
const FINGERPRINT: &str = "fingerprint.txt";
pub(super) const HISTORY: &str = "history.bin";
const INPUTS: &str = "inputs";
const SCENE: &str = "scene.json";
const PLAN: &str = "plan.bin";
/// the remedy search's parts and what they read (`planner::memo`)
const SEARCH: &str = "search.bin";
/// the run verifying the remedies: its `inputs/`, `history.bin`, checkpoints
const VERIFIED: &str = "verified";

/// The layout of the postcard files (checkpoints, history, plan): postcard
/// is positional, so a file written before a field was added would decode
/// into the wrong fields. Bump it with any change of a type they hold.
/// 2: cooling stages with water changes, warnings in the thermal state.
/// 3: the remedy search kept (`search.bin`, `verified/`), `PlanStats::reused`.
/// 4: `SupercoolOption::together` (neighbours supercooled together).
/// 5: `PlannerSettings::search_max_step_days` (in `plan.bin`).
/// 6: `Plan::approximations`.
const FORMAT: u32 = 6;

/// What decides whether a checkpoint is valid: the scene without its
/// `[planner]` table (which changes no simulated value), and the program.
pub fn fingerprint(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.planner = Default::default();
    let text = serde_json::to_string(&s).unwrap_or_default();
    // FNV-1a: stable across Rust versions, unlike the std hasher.
    let h = crate::planner::memo::fnv1a(text.as_bytes());
    format!(
        "groutready {} format {FORMAT} scene {h:016x}\n",
        env!("CARGO_PKG_VERSION")
    )
}

pub(super) fn ck_name(day: Day) -> String {
    format!("ck-{:05}.bin", day.0)
}

fn ck_day(name: &str) -> Option<Day> {
    name.strip_prefix("ck-")?
        .strip_suffix(".bin")?
        .parse::<i64>()
        .ok()
        .map(Day)
}

/// A restart found in an earlier run folder.
pub struct Previous {
    /// the checkpoint, the history before it and the folder's earlier
    /// checkpoints (remedy searches restart from them)
    pub restart: Restart,
    /// the first date the schedules differ from the earlier run's (None: same)
    pub first_change: Option<chrono::NaiveDate>,
    pub dir: PathBuf,
}

/// What [`find`] found: a restart, or none, and the damaged files it passed
/// over on the way (each says what the plan did instead).
pub struct Found {
    pub previous: Option<Previous>,
    pub damaged: Vec<Warning>,
}

/// Looks for a usable restart in `run_dir`; none when there is none, the
/// scene or program changed, or no checkpoint precedes the first change.
/// A damaged checkpoint (truncated, or holding a non-finite value) is passed
/// over for the one before it; a damaged history means starting from
/// scratch. Either is reported in [`Found::damaged`], never an error: the
/// plan can always be made without the folder's restart data. The restart
/// is not later than `end_day` (None: any day).
pub fn find(run_dir: &Path, scene: &Scene, schedules: &Schedules, end_day: Option<Day>) -> Found {
    let mut found = Found {
        previous: None,
        damaged: Vec::new(),
    };
    let dir = run_dir.join(RESTART_DIR);
    match std::fs::read_to_string(dir.join(FINGERPRINT)) {
        Ok(f) if f == fingerprint(scene) => {}
        _ => return found,
    }
    let Ok(old) = schedule::load(&dir.join(INPUTS)) else {
        return found;
    };
    let first = first_change(&old, schedules);
    let limit = first
        .map(|d| scene.epoch.day(d))
        .into_iter()
        .chain(end_day)
        .min();
    let mut usable: Vec<(Day, PathBuf)> = list(&dir)
        .unwrap_or_default()
        .into_iter()
        .filter(|&(d, _)| limit.is_none_or(|l| d <= l))
        .collect();
    usable.sort_by_key(|u| u.0);
    let history: History = match read_file(&dir.join(HISTORY)) {
        Ok(h) => h,
        Err(e) => {
            if !usable.is_empty() {
                found.damaged.push(damaged(&dir.join(HISTORY), &e, None));
            }
            return found;
        }
    };
    // Good checkpoints, oldest first; a damaged one is reported with the
    // checkpoint the plan falls back to (the previous good one, if any).
    let mut good: Vec<Checkpoint> = Vec::new();
    let mut bad: Vec<(PathBuf, CheckpointError)> = Vec::new();
    for (_, path) in &usable {
        match read_checkpoint(path) {
            Ok(ck) => good.push(ck),
            Err(e) => bad.push((path.clone(), e)),
        }
    }
    let latest = good.pop();
    for (path, e) in &bad {
        let instead = latest.as_ref().map(|c| (c.day, scene.epoch.date(c.day)));
        found.damaged.push(damaged(path, e, instead));
    }
    let last_plan = latest
        .as_ref()
        .and_then(|_| last_plan(&dir, first, &mut found.damaged));
    found.previous = latest.map(|checkpoint| Previous {
        restart: Restart {
            checkpoint,
            older: good,
            history,
            last_plan,
        },
        first_change: first,
        dir,
    });
    found
}

/// The last plan's remedy search and its verification's run, when the
/// folder kept them. A damaged file means searching again, and says so.
fn last_plan(
    dir: &Path,
    first_change: Option<NaiveDate>,
    damaged: &mut Vec<Warning>,
) -> Option<LastPlan> {
    let path = dir.join(SEARCH);
    if !path.is_file() {
        return None;
    }
    let redo = |e: &CheckpointError| {
        Warning::about_file(
            path.display().to_string(),
            format!(
                "damaged restart file ({}); searching the remedies again instead",
                e.cause()
            ),
        )
    };
    let memo: SearchMemo = match read_file(&path) {
        Ok(m) => m,
        Err(e) => {
            damaged.push(redo(&e));
            return None;
        }
    };
    let verified = match read_lineage(&dir.join(VERIFIED)) {
        Ok(l) => l,
        Err(e) => {
            damaged.push(redo(&e));
            return None;
        }
    };
    Some(LastPlan {
        memo,
        verified,
        first_change,
    })
}

/// A run kept in `dir` (None when there is none).
fn read_lineage(dir: &Path) -> Result<Option<Lineage>, CheckpointError> {
    if !dir.is_dir() {
        return Ok(None);
    }
    let inputs = dir.join(INPUTS);
    let schedules = schedule::load(&inputs).map_err(|e| CheckpointError::Schedules {
        path: inputs.display().to_string(),
        message: e.to_string(),
    })?;
    let mut checkpoints: Vec<Checkpoint> = list(dir)?
        .iter()
        .map(|(_, p)| read_checkpoint(p))
        .collect::<Result<_, _>>()?;
    checkpoints.sort_by_key(|c| c.day);
    Ok(Some(Lineage {
        schedules,
        checkpoints,
        history: read_file(&dir.join(HISTORY))?,
    }))
}

/// Writes the remedy search and its verification's run into the staged
/// `restart/`, for the next plan to reuse (`planner::memo`).
pub fn save_search(
    staging: &Path,
    memo: &SearchMemo,
    verified: Option<&Lineage>,
) -> Result<(), CheckpointError> {
    let dir = staging.join(RESTART_DIR);
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    write_file(&dir.join(SEARCH), memo, "remedy search")?;
    let Some(l) = verified else {
        return Ok(());
    };
    let v = dir.join(VERIFIED);
    let inputs = v.join(INPUTS);
    schedule::write_dir(&l.schedules, &inputs).map_err(io_err(&inputs))?;
    write_file(&v.join(HISTORY), &l.history, "history")?;
    for ck in &l.checkpoints {
        write_file(&v.join(ck_name(ck.day)), ck, "checkpoint")?;
    }
    Ok(())
}

/// Reads a checkpoint and refuses one holding a non-finite value.
fn read_checkpoint(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let ck: Checkpoint = read_file(path)?;
    match ck.non_finite() {
        None => Ok(ck),
        Some(what) => Err(CheckpointError::NonFinite {
            path: path.display().to_string(),
            what,
        }),
    }
}

/// The warning for a damaged restart file; `instead` is the checkpoint used
/// in its place (None: from scratch).
fn damaged(path: &Path, e: &CheckpointError, instead: Option<(Day, NaiveDate)>) -> Warning {
    let cause = e.cause();
    let what = match instead {
        Some((day, date)) => {
            format!(
                "restarting from the checkpoint of {date} ({}) instead",
                ck_name(day)
            )
        }
        None => "planning from scratch instead".to_string(),
    };
    Warning::about_file(
        path.display().to_string(),
        format!("damaged restart file ({cause}); {what}"),
    )
}

/// The checkpoints in `dir`, by the day in their names (unordered).
pub(super) fn list(dir: &Path) -> Result<Vec<(Day, PathBuf)>, CheckpointError> {
    let rd = std::fs::read_dir(dir).map_err(|source| CheckpointError::Io {
        path: dir.display().to_string(),
        source,
    })?;
    Ok(rd
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            ck_day(&name).map(|d| (d, e.path()))
        })
        .collect())
}

/// Writes what decides whether the restart folder `dir` (created) is
/// usable: the schedules as run, then the fingerprint of the scene and
/// program (last, so that a folder stopped on the way is never used).
/// Replaces the folder's own, the fingerprint removed first: a folder
/// stopped on the way is then never used with either schedules.
pub(super) fn write_identity(
    dir: &Path,
    scene: &Scene,
    schedules: &Schedules,
) -> Result<(), CheckpointError> {
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let f = dir.join(FINGERPRINT);
    if f.exists() {
        std::fs::remove_file(&f).map_err(io_err(&f))?;
    }
    let inputs = dir.join(INPUTS);
    if inputs.exists() {
        std::fs::remove_dir_all(&inputs).map_err(io_err(&inputs))?;
    }
    schedule::write_dir(schedules, &inputs).map_err(io_err(&inputs))?;
    std::fs::write(&f, fingerprint(scene)).map_err(io_err(&f))
}

/// Writes `restart/` into the run folder being staged: the checkpoints on or
/// after `keep_from` (from this run, else copied from `previous`).
pub fn save(
    staging: &Path,
    scene: &Scene,
    schedules: &Schedules,
    history: &History,
    checkpoints: &[Checkpoint],
    keep_from: Day,
    previous: Option<&Path>,
) -> Result<usize, CheckpointError> {
    let dir = staging.join(RESTART_DIR);
    write_identity(&dir, scene, schedules)?;
    write_file(&dir.join(HISTORY), history, "history")?;
    let mut n = 0;
    let mut have: Vec<Day> = Vec::new();
    for ck in checkpoints.iter().filter(|c| c.day >= keep_from) {
        write_file(&dir.join(ck_name(ck.day)), ck, "checkpoint")?;
        have.push(ck.day);
        n += 1;
    }
    if let Some(prev) = previous {
        let first_new = checkpoints.iter().map(|c| c.day).min();
        for (day, path) in list(prev)? {
            // Older checkpoints stay valid: the runs agree before the restart.
            let before_new = first_new.is_none_or(|f| day < f);
            if day >= keep_from && before_new && !have.contains(&day) {
                let to = dir.join(ck_name(day));
                std::fs::copy(&path, &to).map_err(io_err(&to))?;
                n += 1;
            }
        }
    }
    Ok(n)
}

fn json_err(path: &Path) -> impl FnOnce(serde_json::Error) -> CheckpointError + '_ {
    move |source| CheckpointError::Json {
        path: path.display().to_string(),
        source,
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> CheckpointError + '_ {
    move |source| CheckpointError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Writes the scene as simulated and the plan into the staged `restart/`.
pub fn save_plan(staging: &Path, scene: &Scene, plan: &Plan) -> Result<(), CheckpointError> {
    let dir = staging.join(RESTART_DIR);
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    let path = dir.join(SCENE);
    let text = serde_json::to_string_pretty(scene).map_err(json_err(&path))?;
    std::fs::write(&path, text).map_err(io_err(&path))?;
    // postcard, not JSON: a plan may hold NaN (an aperture not measured).
    write_file(&dir.join(PLAN), plan, "plan")
}

/// A planned run folder, everything loaded: what the TUI shows and the
/// what-if re-simulates from.
pub struct Opened {
    pub dir: PathBuf,
    pub scene: Scene,
    /// the schedules as planned
    pub schedules: Schedules,
    pub plan: Plan,
    pub history: History,
    /// the checkpoints kept, by day
    pub checkpoints: Vec<Checkpoint>,
}

/// Whether `dir` looks like a planned run folder.
pub fn is_run_folder(dir: &Path) -> bool {
    dir.join(RESTART_DIR).join(PLAN).is_file()
}

/// Opens a planned run folder.
pub fn open(dir: &Path) -> Result<Opened, CheckpointError> {
    let r = dir.join(RESTART_DIR);
    let read = |name: &str| -> Result<String, CheckpointError> {
        let p = r.join(name);
        std::fs::read_to_string(&p).map_err(|source| {
            if source.kind() == std::io::ErrorKind::NotFound {
                CheckpointError::NotARunFolder {
                    path: dir.display().to_string(),
                    missing: format!("{RESTART_DIR}/{name}"),
                }
            } else {
                CheckpointError::Io {
                    path: p.display().to_string(),
                    source,
                }
            }
        })
    };
    let scene_path = r.join(SCENE);
    let scene: Scene = serde_json::from_str(&read(SCENE)?).map_err(json_err(&scene_path))?;
    if read(FINGERPRINT)? != fingerprint(&scene) {
        return Err(CheckpointError::OtherVersion(dir.display().to_string()));
    }
    if !r.join(PLAN).is_file() {
        return Err(CheckpointError::NotARunFolder {
            path: dir.display().to_string(),
            missing: format!("{RESTART_DIR}/{PLAN}"),
        });
    }
    let plan: Plan = read_file(&r.join(PLAN))?;
    let inputs = r.join(INPUTS);
    let schedules = schedule::load(&inputs).map_err(|e| CheckpointError::Schedules {
        path: inputs.display().to_string(),
        message: e.to_string(),
    })?;
    let mut checkpoints: Vec<Checkpoint> = list(&r)?
        .iter()
        .map(|(_, p)| read_checkpoint(p))
        .collect::<Result<_, _>>()?;
    checkpoints.sort_by_key(|c| c.day);
    Ok(Opened {
        dir: dir.to_path_buf(),
        scene,
        schedules,
        plan,
        history: read_file(&r.join(HISTORY))?,
        checkpoints,
    })
}

/// Whether `dir` holds a plan of exactly this scene, these schedules and
/// these options: opening it shows what planning again would.
pub fn up_to_date(dir: &Path, scene: &Scene, schedules: &Schedules, options: &PlanOptions) -> bool {
    let r = dir.join(RESTART_DIR);
    let same_fingerprint =
        std::fs::read_to_string(r.join(FINGERPRINT)).is_ok_and(|f| f == fingerprint(scene));
    if !same_fingerprint {
        return false;
    }
    let Ok(old) = schedule::load(&r.join(INPUTS)) else {
        return false;
    };
    let Ok(plan) = read_file::<Plan>(&r.join(PLAN)) else {
        return false;
    };
    let want = options.zones(schedules).len();
    // Line numbers differ between the site's files and `inputs/`; what is
    // simulated and what the plan reads must not.
    let meters = |s: &Schedules| -> Vec<(ZoneId, ZonePoint, NaiveDate, u64)> {
        s.joint_meters
            .iter()
            .flatten()
            .map(|m| (m.zone_id(), m.point, m.date, m.aperture_mm.to_bits()))
            .collect()
    };
    first_change(&old, schedules).is_none()
        && meters(&old) == meters(schedules)
        && plan.as_of == options.as_of
        && plan.settings == scene.planner
        && plan.zones.len() == want
}
