//! Resumable runs: a long `groutready run` keeps a restart point beside its
//! run folder, so that a run stopped on the way (killed, a reboot, a power
//! cut) continues from it instead of from day 0. The Xiaowan-scale
//! construction is a run of hours.
//!
//! While it simulates, a run into the folder `NAME` keeps `.NAME.resume/`
//! next to it:
//! - `restart/`: the fingerprint of the scene and program, the schedules as
//!   run (`inputs/`), the histories recorded so far (`history.bin`) and the
//!   latest checkpoint (`ck-DDDDD.bin`), laid out as a plan's restart
//!   folder ([`super::restart`]), which reads it;
//! - `fields/` and `fields.bin`: links to the field snapshots written so far
//!   and their days.
//!
//! The run takes a checkpoint every `[planner] checkpoint_days` and keeps
//! the first one, then the first at least [`SAVE_EVERY_SECONDS`] after the
//! last kept. Each file is written beside its place and renamed into it,
//! the histories before the checkpoint, so a stop at any moment leaves a
//! consistent restart point (the histories may run past the checkpoint's
//! day; the restore drops those rows).
//!
//! The next `run` into the same folder with the same scene and program
//! continues from the latest checkpoint on or before the first date its
//! schedules differ (a restored run repeats the uninterrupted one exactly:
//! [`crate::sim::checkpoint`]); with nothing usable there, or
//! `--from-scratch`, the folder is removed and the run starts from day 0. A
//! run that ends removes it; one that fails keeps it (a full disk at the
//! end should not cost the hours before it; a failure of the simulation
//! itself recurs from the restart point, minutes later).
//!
//! Verified by `tests/it/cli_run.rs`: a run killed after its first restart
//! point and run again writes the same temperatures, apertures and field
//! files as a run never stopped.

use std::path::{Path, PathBuf};
use std::time::Instant;

use chrono::NaiveDate;

use super::restart::{self, RESTART_DIR};
use super::{io_err, AppError};
use crate::planner::plan::Restart;
use crate::scene::Scene;
use crate::schedule::{Schedules, Warning};
use crate::sim::checkpoint::{read_file, write_file};
use crate::sim::{Checkpoint, Simulation};
use crate::vocab::Day;

/// Least wall time between two kept restart points \[s\]: a Xiaowan-scale
/// checkpoint and history are a few hundred MB, written in a second or two.
pub const SAVE_EVERY_SECONDS: f64 = 120.0;

const FIELDS: &str = "fields";
const FIELDS_INDEX: &str = "fields.bin";

/// The restart point of a run folder being written.
pub struct Resume {
    dir: PathBuf,
    /// when the last restart point was kept (None: none yet)
    saved: Option<Instant>,
    /// the folder and its `fields/` exist
    started: bool,
    /// the fingerprint and this run's schedules are in place. Not so in a
    /// folder continued with schedules that differ after its restart
    /// point: its next restart point comes from this run's schedules,
    /// which must replace the folder's before it is kept (else a run with
    /// the old schedules would continue from it)
    identity: bool,
    /// the snapshots already linked into `fields/`
    linked: usize,
}

/// Where an interrupted run is continued from.
pub struct Resumed {
    pub restart: Restart,
    pub date: NaiveDate,
    /// the snapshots written before the checkpoint's day: (day, file name)
    pub fields: Vec<(f64, String)>,
}

/// What [`Resume::open`] found.
pub struct Opened {
    pub resume: Resume,
    pub resumed: Option<Resumed>,
    /// what was removed or passed over, one line each
    pub notes: Vec<String>,
    pub damaged: Vec<Warning>,
}

/// The restart point of the interrupted run into `dest` that `scene` and
/// `schedules` can continue from, not later than `end` (None: any day),
/// and the damaged files passed over: [`restart::find`] in [`dir_of`].
pub fn find(dest: &Path, scene: &Scene, schedules: &Schedules, end: Option<Day>) -> restart::Found {
    restart::find(&dir_of(dest), scene, schedules, end)
}

/// The restart folder of the run folder `dest`.
pub fn dir_of(dest: &Path) -> PathBuf {
    let name = dest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    dest.with_file_name(format!(".{name}.resume"))
}

impl Resume {
    /// Looks for the restart point of an interrupted run into `dest` (the
    /// caller holds the run folder's lock), usable with `sim`'s scene and
    /// schedules; removes it when it is not (or `from_scratch`).
    pub fn open(
        dest: &Path,
        sim: &Simulation,
        schedules: &Schedules,
        from_scratch: bool,
    ) -> Result<Opened, AppError> {
        let dir = dir_of(dest);
        let mut opened = Opened {
            resume: Resume {
                dir: dir.clone(),
                saved: None,
                started: false,
                identity: false,
                linked: 0,
            },
            resumed: None,
            notes: Vec::new(),
            damaged: Vec::new(),
        };
        if !dir.exists() {
            return Ok(opened);
        }
        let found = if from_scratch {
            None
        } else {
            let f = find(dest, sim.scene, schedules, Some(sim.end_day()));
            opened.damaged = f.damaged;
            f.previous
        };
        let fields: Option<Vec<(f64, String)>> = read_file(&dir.join(FIELDS_INDEX)).ok();
        match (found, fields) {
            (Some(p), Some(fields)) => {
                let day = p.restart.checkpoint.day;
                opened.resumed = Some(Resumed {
                    date: sim.scene.epoch.date(day),
                    fields: fields.into_iter().filter(|f| f.0 < day.t()).collect(),
                    restart: p.restart,
                });
                opened.resume.started = true;
                opened.resume.identity = p.first_change.is_none();
            }
            _ => {
                std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
                opened.notes.push(format!(
                    "removed {} (the restart point of an interrupted run{})",
                    dir.display(),
                    if from_scratch {
                        ": --from-scratch"
                    } else {
                        ", not one these inputs and this program can continue from"
                    }
                ));
            }
        }
        Ok(opened)
    }

    /// Links the snapshots the resumed run keeps into the staged `fields`.
    pub fn link_fields(&mut self, resumed: &Resumed, fields: &Path) -> Result<(), AppError> {
        for (_, name) in &resumed.fields {
            let from = self.dir.join(FIELDS).join(name);
            let to = fields.join(name);
            link_or_copy(&from, &to)?;
        }
        self.linked = resumed.fields.len();
        Ok(())
    }

    /// Keeps `ck` (the simulation's latest checkpoint) as the restart point
    /// when none is kept yet or the last is [`SAVE_EVERY_SECONDS`] old;
    /// `written` are the snapshots in the staged `fields` so far.
    pub fn maybe_save(
        &mut self,
        sim: &Simulation,
        schedules: &Schedules,
        ck: &Checkpoint,
        fields: &Path,
        written: &[(f64, String)],
    ) -> Result<(), AppError> {
        if self
            .saved
            .is_some_and(|t| t.elapsed().as_secs_f64() < SAVE_EVERY_SECONDS)
        {
            return Ok(());
        }
        let dir = self.dir.join(RESTART_DIR);
        if !self.started {
            // `open` removed any folder another run left here
            std::fs::create_dir_all(self.dir.join(FIELDS)).map_err(io_err(&self.dir))?;
            self.started = true;
        }
        if !self.identity {
            restart::write_identity(&dir, sim.scene, schedules)?;
            self.identity = true;
        }
        for (_, name) in &written[self.linked.min(written.len())..] {
            link_or_copy(&fields.join(name), &self.dir.join(FIELDS).join(name))?;
        }
        self.linked = written.len();
        // the histories and the snapshots first: a checkpoint is only ever
        // beside histories that reach its day
        replace(&self.dir.join(FIELDS_INDEX), written, "fields")?;
        replace(&dir.join(restart::HISTORY), &sim.history(), "history")?;
        replace(&dir.join(restart::ck_name(ck.day)), ck, "checkpoint")?;
        for (day, path) in restart::list(&dir)? {
            if day != ck.day {
                std::fs::remove_file(&path).map_err(io_err(&path))?;
            }
        }
        self.saved = Some(Instant::now());
        Ok(())
    }

    /// The run ended: its restart point goes.
    pub fn remove(self) -> Result<(), AppError> {
        match std::fs::remove_dir_all(&self.dir) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_err(&self.dir)(e)),
            _ => Ok(()),
        }
    }
}

/// Writes `value` beside `path` and renames it into place.
fn replace<T: serde::Serialize + ?Sized>(
    path: &Path,
    value: &T,
    what: &'static str,
) -> Result<(), AppError> {
    let tmp = path.with_extension("tmp");
    write_file(&tmp, value, what)?;
    std::fs::rename(&tmp, path).map_err(io_err(path))
}

/// A hard link (the folders are siblings), or a copy where links fail.
fn link_or_copy(from: &Path, to: &Path) -> Result<(), AppError> {
    if to.exists() {
        std::fs::remove_file(to).map_err(io_err(to))?;
    }
    if std::fs::hard_link(from, to).is_err() {
        std::fs::copy(from, to).map_err(io_err(to))?;
    }
    Ok(())
}
