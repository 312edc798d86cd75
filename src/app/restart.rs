//! Weekly updates: a plan's run folder keeps what the next plan needs to
//! restart instead of simulating from day 0.
//!
//! `restart/` holds the schedules as run (`inputs/`), a fingerprint of the
//! scene and program, the histories (`history.bin`) and checkpoints
//! (`ck-DDDDD.bin`, DDDDD the day since the epoch). The next plan with the
//! same scene restarts from the latest checkpoint on or before the first date
//! its schedules differ from `inputs/` (and not after its own end).

use std::path::{Path, PathBuf};

use crate::planner::edit::first_change;
use crate::scene::Scene;
use crate::schedule::{self, Schedules};
use crate::sim::checkpoint::{read_file, write_file, CheckpointError};
use crate::sim::{Checkpoint, History};

pub const RESTART_DIR: &str = "restart";
const FINGERPRINT: &str = "fingerprint.txt";
const HISTORY: &str = "history.bin";
const INPUTS: &str = "inputs";

/// What decides whether a checkpoint is valid: the scene without its
/// `[planner]` table (which changes no simulated value), and the program.
pub fn fingerprint(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.planner = Default::default();
    let text = serde_json::to_string(&s).unwrap_or_default();
    // FNV-1a: stable across Rust versions, unlike the std hasher.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("groutready {} scene {h:016x}\n", env!("CARGO_PKG_VERSION"))
}

fn ck_name(day: f64) -> String {
    format!("ck-{:05}.bin", day as i64)
}

fn ck_day(name: &str) -> Option<f64> {
    name.strip_prefix("ck-")?
        .strip_suffix(".bin")?
        .parse::<i64>()
        .ok()
        .map(|d| d as f64)
}

/// A restart found in an earlier run folder.
pub struct Previous {
    pub checkpoint: Checkpoint,
    /// the folder's earlier checkpoints (remedy searches restart from them)
    pub older: Vec<Checkpoint>,
    pub history: History,
    /// the first date the schedules differ from the earlier run's (None: same)
    pub first_change: Option<chrono::NaiveDate>,
    pub dir: PathBuf,
}

/// Looks for a usable restart in `run_dir`; None when there is none, the
/// scene or program changed, or no checkpoint precedes the first change.
pub fn find(
    run_dir: &Path,
    scene: &Scene,
    schedules: &Schedules,
    end_day: f64,
) -> Result<Option<Previous>, CheckpointError> {
    let dir = run_dir.join(RESTART_DIR);
    match std::fs::read_to_string(dir.join(FINGERPRINT)) {
        Ok(f) if f == fingerprint(scene) => {}
        _ => return Ok(None),
    }
    let Ok(old) = schedule::load(&dir.join(INPUTS)) else {
        return Ok(None);
    };
    let first = first_change(&old, schedules);
    let limit = first
        .map(|d| (d - scene.epoch).num_days() as f64)
        .unwrap_or(f64::INFINITY)
        .min(end_day);
    let mut usable: Vec<(f64, PathBuf)> = list(&dir)?
        .into_iter()
        .filter(|&(d, _)| d <= limit)
        .collect();
    usable.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some((_, path)) = usable.pop() else {
        return Ok(None);
    };
    let older = usable
        .iter()
        .map(|(_, p)| read_file(p))
        .collect::<Result<_, _>>()?;
    Ok(Some(Previous {
        checkpoint: read_file(&path)?,
        older,
        history: read_file(&dir.join(HISTORY))?,
        first_change: first,
        dir,
    }))
}

fn list(dir: &Path) -> Result<Vec<(f64, PathBuf)>, CheckpointError> {
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

/// Writes `restart/` into the run folder being staged: the checkpoints on or
/// after `keep_from` (from this run, else copied from `previous`).
pub fn save(
    staging: &Path,
    scene: &Scene,
    schedules: &Schedules,
    history: &History,
    checkpoints: &[Checkpoint],
    keep_from: f64,
    previous: Option<&Path>,
) -> Result<usize, CheckpointError> {
    let dir = staging.join(RESTART_DIR);
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| CheckpointError::Io { path, source }
    };
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    let inputs = dir.join(INPUTS);
    schedule::write_dir(schedules, &inputs).map_err(io(&inputs))?;
    std::fs::write(dir.join(FINGERPRINT), fingerprint(scene))
        .map_err(io(&dir.join(FINGERPRINT)))?;
    write_file(&dir.join(HISTORY), history, "history")?;
    let mut n = 0;
    let mut have: Vec<f64> = Vec::new();
    for ck in checkpoints.iter().filter(|c| c.day >= keep_from) {
        write_file(&dir.join(ck_name(ck.day)), ck, "checkpoint")?;
        have.push(ck.day);
        n += 1;
    }
    if let Some(prev) = previous {
        let first_new = checkpoints
            .iter()
            .map(|c| c.day)
            .fold(f64::INFINITY, f64::min);
        for (day, path) in list(prev)? {
            // Older checkpoints stay valid: the runs agree before the restart.
            if day >= keep_from && day < first_new && !have.contains(&day) {
                let to = dir.join(ck_name(day));
                std::fs::copy(&path, &to).map_err(io(&to))?;
                n += 1;
            }
        }
    }
    Ok(n)
}
