//! The TUI's runtime without a terminal: the state plus the background jobs
//! its commands start (the plan, what-ifs, saving). The terminal loop
//! (`terminal.rs`) and the tests drive the same [`Session`].

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::app::plan::PlanRequest;
use crate::app::{Inputs, OutDir};
use crate::planner::whatif::WhatIf;
use crate::planner::Progress;
use crate::schedule::{self, Schedules};
use crate::sim::SimError;

use super::app::App;
use super::data::RunData;
use super::event::{Command, Event, JobEvent};

/// Folder of the what-if schedule sets inside a run folder (carried over
/// when the folder is planned again).
pub use crate::output::run_dir::WHATIF_DIR;

/// Events of the plan job carry id 0; each what-if has its own id, so a
/// cancelled job's last words cannot reach the job after it.
type Tagged = (u64, JobEvent);

pub struct Session {
    pub app: App,
    tx: Sender<Tagged>,
    rx: Receiver<Tagged>,
    job: u64,
    cancel: Option<Arc<AtomicBool>>,
}

impl Session {
    /// A session on a planned run folder.
    pub fn open(data: RunData, color: bool) -> Session {
        let (tx, rx) = channel();
        Session {
            app: App::open(Arc::new(data), color),
            tx,
            rx,
            job: 0,
            cancel: None,
        }
    }

    /// A session that plans `inputs` into `out` first (in the background),
    /// then opens it; the folder stays locked until the plan is written.
    pub fn plan(inputs: Inputs, out: OutDir, request: PlanRequest, color: bool) -> Session {
        let (tx, rx) = channel();
        let mut app = App::planning(&inputs.scene.name, color);
        if let Some(p) = app.planning.as_mut() {
            p.approximations = inputs.scene.approximations();
        }
        let t = tx.clone();
        std::thread::spawn(move || {
            let send = |e: JobEvent| {
                let _ = t.send((0, e));
            };
            let mut last = f64::NEG_INFINITY;
            let result = crate::app::plan::plan(&inputs, &out, &request, &mut |p| match p {
                Progress::Baseline { day, end } => {
                    // A report per simulated day is plenty for a gauge.
                    if day - last >= 1.0 || day >= end {
                        last = day;
                        send(JobEvent::PlanBaseline { day, end });
                    }
                }
                Progress::Resimulation(what) => send(JobEvent::PlanResimulation(what)),
            });
            match result.and_then(|s| RunData::load(&s.out)) {
                Ok(data) => send(JobEvent::Planned(Arc::new(data))),
                Err(e) => send(JobEvent::PlanFailed(e.to_string())),
            }
        });
        Session {
            app,
            tx,
            rx,
            job: 0,
            cancel: None,
        }
    }

    /// Applies an event and carries out the commands it gives.
    pub fn handle(&mut self, event: Event) {
        for c in self.app.update(event) {
            self.execute(c);
        }
    }

    /// Applies the job reports that arrived; returns how many.
    pub fn pump(&mut self) -> usize {
        let mut n = 0;
        while let Ok(t) = self.rx.try_recv() {
            self.deliver(t);
            n += 1;
        }
        n
    }

    /// Waits until no plan or what-if is running, or `timeout`; returns
    /// whether it finished.
    pub fn wait_idle(&mut self, timeout: Duration) -> bool {
        let until = Instant::now() + timeout;
        while self.busy() {
            let left = until.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(t) => self.deliver(t),
                Err(RecvTimeoutError::Timeout) => return false,
                Err(RecvTimeoutError::Disconnected) => return !self.busy(),
            }
        }
        true
    }

    fn busy(&self) -> bool {
        let planning = self
            .app
            .planning
            .as_ref()
            .is_some_and(|p| p.error.is_none());
        planning || self.app.running().is_some()
    }

    fn deliver(&mut self, (id, e): Tagged) {
        if id == 0 || id == self.job {
            self.app.update(Event::Job(e));
        }
    }

    fn execute(&mut self, c: Command) {
        match c {
            Command::RunWhatIf(w) => self.start_whatif(w),
            Command::CancelWhatIf => {
                if let Some(c) = &self.cancel {
                    c.store(true, Ordering::Relaxed);
                }
            }
            Command::SaveWhatIf => {
                let e = match self.save_whatif() {
                    Ok(p) => JobEvent::Saved(p),
                    Err(e) => JobEvent::SaveFailed(e),
                };
                self.app.update(Event::Job(e));
            }
        }
    }

    fn start_whatif(&mut self, w: WhatIf) {
        let Some(data) = self.app.data.clone() else {
            return;
        };
        self.job += 1;
        let id = self.job;
        let cancel = Arc::new(AtomicBool::new(false));
        self.cancel = Some(cancel.clone());
        let tx = self.tx.clone();
        std::thread::spawn(move || {
            let mut last = f64::NEG_INFINITY;
            let r = data.run.what_if(&w, Some(cancel), &mut |day, end| {
                if day - last >= 1.0 || day >= end {
                    last = day;
                    let _ = tx.send((id, JobEvent::WhatIfProgress { day, end }));
                }
            });
            let e = match r {
                Ok(o) => JobEvent::WhatIfDone(Box::new(o)),
                Err(SimError::Cancelled(_)) => JobEvent::WhatIfCancelled,
                Err(e) => JobEvent::WhatIfFailed(e.to_string()),
            };
            let _ = tx.send((id, e));
        });
    }

    /// Writes the open what-if's schedules to
    /// `RUN/whatif/jJ-zZ-scΔT-DATE/`, whole (a CSV set the site can plan from).
    fn save_whatif(&self) -> Result<PathBuf, String> {
        let data = self.app.data.as_ref().ok_or("nothing loaded")?;
        let result = self
            .app
            .zone
            .as_ref()
            .and_then(|z| z.whatif.as_ref())
            .and_then(|f| f.result.as_ref())
            .ok_or("no what-if result to save")?;
        let w = &result.what_if;
        let name = format!("j{}-z{}-sc{:.2}-{}", w.joint, w.zone, w.supercool_c, w.date);
        let dir = data.dir.join(WHATIF_DIR).join(name);
        write_set(&result.schedules, &dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(dir)
    }
}

/// Writes a schedule set atomically: into a sibling staging folder, then
/// renamed over `dir`.
fn write_set(s: &Schedules, dir: &Path) -> std::io::Result<()> {
    let parent = dir.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent)?;
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let staging = parent.join(format!(".{name}.partial"));
    if staging.exists() {
        std::fs::remove_dir_all(&staging)?;
    }
    std::fs::create_dir_all(&staging)?;
    if let Err(e) = schedule::write_dir(s, &staging) {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    if dir.exists() {
        std::fs::remove_dir_all(dir)?;
    }
    std::fs::rename(&staging, dir)
}
