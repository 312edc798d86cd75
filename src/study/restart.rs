//! What a weekly update saves: the plan from scratch, the same plan again
//! (restarted from its own run folder, the remedy search reused), and the
//! plan after a schedule edit (the last zone's grouting moved a week later:
//! an edit in the plan's last month), each timed, and whether the restarted
//! plans' readiness tables equal the plans from scratch.

use std::path::Path;
use std::time::Instant;

use chrono::NaiveDate;

use super::StudyError;
use crate::app::{self, plan::PlanRequest};

/// Prints the three timings and the largest aperture difference between the
/// restarted and the from-scratch plan of the edited schedules.
pub fn restart(scene: &Path, today: NaiveDate) -> Result<(), StudyError> {
    let mut inputs = app::load_inputs(scene, None)?;
    let tmp = tempfile_dir()?;
    let out = tmp.join("plan");
    println!(
        "planning into {} (a scratch folder, removed at the end)",
        out.display()
    );
    let time = |inputs: &app::Inputs, req: &PlanRequest, out: &Path| timed(scene, inputs, req, out);
    let again = PlanRequest::on(today);
    let scratch = PlanRequest {
        from_scratch: true,
        ..again.clone()
    };
    let (t0, p0) = time(&inputs, &scratch, &out)?;
    println!("{}: {}", inputs.scene.name, from_scratch_line(t0, &p0));
    let (t1, p1) = time(&inputs, &again, &out)?;
    println!(
        "same schedules again: {t1:.1} s, {:.1}× faster (baseline {:.1} s, restarted from {}; {} re-simulations; reused: {}); same readiness table: {}",
        t0 / t1,
        p1.stats.baseline_seconds,
        p1.stats
            .restarted_from
            .map(|d| d.to_string())
            .unwrap_or_else(|| "day 0".into()),
        p1.stats.resimulations,
        reused(&p1),
        yes_no(p1.zones == p0.zones)
    );
    // The weekly edit: the last zone to grout moves a week later.
    let Some(last) = p0.to_grout().map(|z| (z.planned, z.joint, z.zone)).max() else {
        println!("no zone to grout: nothing to edit");
        return Ok(());
    };
    for g in inputs.schedules.grouting.iter_mut() {
        if (g.joint, g.zone) == (last.1, last.2) {
            g.planned += chrono::Duration::days(7);
        }
    }
    let (t2, p2) = time(&inputs, &again, &out)?;
    let (t3, p3) = time(&inputs, &scratch, &tmp.join("scratch"))?;
    let mut diff = 0.0f64;
    for (a, b) in p2.zones.iter().zip(&p3.zones) {
        if let (Some(x), Some(y)) = (a.apertures_mm.min, b.apertures_mm.min) {
            diff = diff.max((x - y).abs() / x.abs().max(1e-9));
        }
    }
    println!(
        "joint {} zone {} moved to {}: restarted {t2:.1} s (baseline {:.1} s from {}; {} re-simulations in {:.1} s; reused: {}) vs from scratch {t3:.1} s (baseline {:.1} s): {:.1}× faster; same readiness table: {}; largest relative difference of a zone's min aperture {diff:.1e}",
        last.1,
        last.2,
        last.0 + chrono::Duration::days(7),
        p2.stats.baseline_seconds,
        p2.stats.restarted_from.map(|d| d.to_string()).unwrap_or_else(|| "day 0".into()),
        p2.stats.resimulations,
        p2.stats.resimulation_seconds,
        reused(&p2),
        p3.stats.baseline_seconds,
        t3 / t2,
        yes_no(p2.zones == p3.zones)
    );
    let _ = std::fs::remove_dir_all(&tmp);
    Ok(())
}

/// The plan of `scene` (loaded as `inputs`) asked by `req`, written into
/// `out` (a scratch folder), and its wall time.
fn timed(
    scene: &Path,
    inputs: &app::Inputs,
    req: &PlanRequest,
    out: &Path,
) -> Result<(f64, crate::planner::Plan), StudyError> {
    let t = Instant::now();
    let plan_err = |source: app::AppError| StudyError::Plan {
        scene: scene.display().to_string(),
        source: Box::new(source),
    };
    let out = app::OutDir::prepare(out, inputs, false).map_err(|e| plan_err(e.into()))?;
    let s = app::plan::plan(inputs, &out, req, &mut |_| {}).map_err(plan_err)?;
    Ok((t.elapsed().as_secs_f64(), s.plan))
}

/// "plan from scratch 38.5 s (baseline 18.8 s, 11 re-simulations 19.6 s)"
fn from_scratch_line(t: f64, p: &crate::planner::Plan) -> String {
    format!(
        "plan from scratch {t:.1} s (baseline {:.1} s, {} re-simulations {:.1} s)",
        p.stats.baseline_seconds, p.stats.resimulations, p.stats.resimulation_seconds
    )
}

/// The plan `request` of `scene` (its own schedules) from scratch, timed,
/// for `study perf`: one line. Schedules with nothing left to plan by the
/// request's clock (no `as_of`, no zone marked done, every zone due before
/// today) are not planned: the line says so, and how to give the date.
pub fn plan_from_scratch(scene: &Path, request: &PlanRequest) -> Result<String, StudyError> {
    let inputs = app::load_inputs(scene, None)?;
    let tmp = tempfile_dir()?;
    let scratch = PlanRequest {
        from_scratch: true,
        ..request.clone()
    };
    let timed = timed(scene, &inputs, &scratch, &tmp.join("plan"));
    let _ = std::fs::remove_dir_all(&tmp);
    match timed {
        Ok((t, p)) => Ok(from_scratch_line(t, &p)),
        Err(StudyError::Plan { source, .. })
            if matches!(*source, app::AppError::NothingToPlan { .. }) =>
        {
            Ok(format!("plan not timed: {source}"))
        }
        Err(e) => Err(e),
    }
}

fn reused(p: &crate::planner::Plan) -> String {
    if p.stats.reused.is_empty() {
        "nothing".into()
    } else {
        p.stats.reused.join(", ")
    }
}

fn yes_no(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "NO"
    }
}

fn tempfile_dir() -> Result<std::path::PathBuf, StudyError> {
    let d = std::env::temp_dir().join(format!("groutready-study-{}", std::process::id()));
    std::fs::create_dir_all(&d).map_err(|source| StudyError::Io {
        action: "creating",
        path: d.display().to_string(),
        source,
    })?;
    Ok(d)
}
