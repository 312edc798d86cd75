//! What `groutready plan` does, as a library call: load and check every
//! input, restart from the run folder's checkpoints when the scene is the
//! same, plan, and write the run folder atomically (reports, histories,
//! remedied schedules, checkpoints for the next weekly update).

use std::path::{Path, PathBuf};

use chrono::NaiveDate;

use crate::output::{self, RunDir};
use crate::planner::{self, Plan, PlanOptions, Progress};
use crate::schedule;
use crate::vocab::ZoneId;

use super::restart;
use super::{io_err, run_text, AppError, Inputs, OutDir};

/// Options of one plan. Made with [`PlanRequest::on`]: there is no
/// default "today" (a made-up clock would plan from 1970).
#[derive(Debug, Clone)]
pub struct PlanRequest {
    /// the as-of date (default: [`planner::plan::default_as_of`] with `today`)
    pub as_of: Option<NaiveDate>,
    /// the caller's clock: the as-of date when the schedules mark no zone
    /// done and `as_of` is not given (the library reads no clock)
    pub today: NaiveDate,
    /// overrides the scene's `planner.horizon_days`
    pub horizon_days: Option<u32>,
    /// ignore the run folder's checkpoints
    pub from_scratch: bool,
}

impl PlanRequest {
    /// The plan on the caller's clock `today`: the default as-of date and
    /// horizon, restarted from the run folder's checkpoints.
    pub fn on(today: NaiveDate) -> Self {
        PlanRequest {
            as_of: None,
            today,
            horizon_days: None,
            from_scratch: false,
        }
    }

    /// The planner's options for `inputs`: the as-of date and horizon.
    pub fn options(&self, inputs: &Inputs) -> PlanOptions {
        PlanOptions {
            as_of: self
                .as_of
                .unwrap_or_else(|| planner::plan::default_as_of(&inputs.schedules, self.today)),
            horizon_days: self.horizon_days.or(inputs.scene.planner.horizon_days),
        }
    }
}

/// Whether `out` already holds this plan (same scene, schedules, meters,
/// as-of date, horizon and settings): opening it shows what planning again
/// would. Never when the request plans from scratch.
pub fn is_current(inputs: &Inputs, out: &Path, request: &PlanRequest) -> bool {
    let options = request.options(inputs);
    !request.from_scratch && restart::up_to_date(out, &inputs.scene, &inputs.schedules, &options)
}

/// A finished plan and where it was written.
pub struct PlanSummary {
    pub out: PathBuf,
    pub plan: Plan,
    /// remedied schedules written to `out/remedied`
    pub remedied: bool,
    /// zones groutable as scheduled that the remedies make not groutable
    pub newly_flagged: Vec<(ZoneId, String)>,
    pub checkpoints_kept: usize,
}

/// The folder of the remedied schedules inside a run folder.
pub const REMEDIED_DIR: &str = "remedied";

/// Plans `inputs` into the run folder `out` (checked and locked by
/// [`OutDir::prepare`]): restarts from its checkpoints, and carries its
/// saved what-ifs into the new run folder.
pub fn plan(
    inputs: &Inputs,
    out: &OutDir,
    request: &PlanRequest,
    progress: &mut dyn FnMut(Progress),
) -> Result<PlanSummary, AppError> {
    let scene = &inputs.scene;
    if !scene.has(crate::scene::Effect::Joints) {
        let effects: Vec<String> = scene.effects.iter().map(|e| e.to_string()).collect();
        return Err(AppError::PlanNeedsJoints(
            inputs.scene_path.display().to_string(),
            if effects.is_empty() {
                "nothing".into()
            } else {
                effects.join(", ")
            },
        ));
    }
    let options = request.options(inputs);
    nothing_left_by_today(inputs, request, &options)?;
    let epoch = scene.epoch;
    // The restart may not be later than this plan's own end.
    let end = options.end_day(epoch, &inputs.schedules);
    let dest = out.dest();
    let found = if request.from_scratch {
        restart::Found {
            previous: None,
            damaged: Vec::new(),
        }
    } else {
        restart::find(dest, scene, &inputs.schedules, Some(end))
    };
    let previous = found.previous;
    let prev_dir = previous.as_ref().map(|p| p.dir.clone());
    let mut out_plan = planner::plan(
        scene,
        &inputs.mesh,
        &inputs.schedules,
        &options,
        previous.map(|p| p.restart),
        progress,
    )?;
    let warnings = &mut out_plan.plan.warnings;
    let questionable = out_plan.baseline.warnings.iter().cloned();
    let all = inputs
        .warnings
        .iter()
        .cloned()
        .chain(found.damaged)
        .chain(questionable);
    warnings.splice(0..0, all);

    let checkpoints_kept = write_folder(inputs, dest, &out_plan, prev_dir.as_deref())?;
    Ok(PlanSummary {
        out: out.path().to_path_buf(),
        remedied: out_plan.remedied.is_some(),
        newly_flagged: out_plan
            .newly_flagged
            .iter()
            .map(|z| (z.zone_id(), z.reasons()))
            .collect(),
        plan: out_plan.plan,
        checkpoints_kept,
    })
}

/// Refuses a plan whose as-of date came from the clock (no `--as-of`, no
/// zone marked done) when every zone was due before it: refused before
/// anything is simulated or written ([`AppError::NothingToPlan`]).
fn nothing_left_by_today(
    inputs: &Inputs,
    request: &PlanRequest,
    options: &PlanOptions,
) -> Result<(), AppError> {
    let schedules = &inputs.schedules;
    if request.as_of.is_some() || planner::plan::as_of_after_done(schedules).is_some() {
        return Ok(());
    }
    match schedules.grouting.iter().map(|g| g.planned).max() {
        Some(last) if last < options.as_of => Err(AppError::NothingToPlan {
            grouting: inputs
                .schedules_dir
                .join(schedule::GROUTING_CSV)
                .display()
                .to_string(),
            today: options.as_of,
            last,
        }),
        _ => Ok(()),
    }
}

/// Writes the run folder of a finished plan atomically (staged, then renamed
/// over `dest`); returns the number of checkpoints kept. `previous` is the
/// run folder the plan restarted from, whose older checkpoints are copied.
fn write_folder(
    inputs: &Inputs,
    dest: &Path,
    out_plan: &planner::PlanOutput,
    previous: Option<&Path>,
) -> Result<usize, AppError> {
    let (scene, epoch) = (&inputs.scene, inputs.scene.epoch);
    let staging = RunDir::create(dest).map_err(io_err(dest))?;
    let dir = staging.path();
    crate::report::write_all(dir, &out_plan.plan)?;
    let h = &out_plan.history;
    if !h.records.rows.is_empty() {
        let p = dir.join("temperatures.csv");
        output::temperatures::write(&p, epoch, &h.records).map_err(io_err(&p))?;
    }
    if !h.joint_records.columns.is_empty() {
        let p = dir.join(output::apertures::FILE_NAME);
        output::apertures::write(&p, epoch, &h.joint_records, &inputs.aperture_days())
            .map_err(io_err(&p))?;
    }
    if let Some(s) = &out_plan.remedied {
        let p = dir.join(REMEDIED_DIR);
        schedule::write_dir(s, &p).map_err(io_err(&p))?;
    }
    let checkpoints_kept = restart::save(
        dir,
        scene,
        &inputs.schedules,
        h,
        &out_plan.checkpoints,
        out_plan.checkpoints_kept_from,
        previous,
    )?;
    restart::save_plan(dir, scene, &out_plan.plan)?;
    restart::save_search(dir, &out_plan.memo, out_plan.verified.as_ref())?;
    let p = dir.join("run.txt");
    std::fs::write(&p, run_text(inputs, &out_plan.baseline)).map_err(io_err(&p))?;
    staging.commit().map_err(io_err(dest))?;
    Ok(checkpoints_kept)
}
