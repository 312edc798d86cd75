//! The `apertures.csv` of an interrupted run, read from its restart point
//! (the rows `groutready run` writes, up to the restart point's day):
//! a long run's joint history so far, for `tests/aperture_pattern.py`,
//! without waiting for its end.
//!
//!     cargo run --release --example restart_apertures SCENE RUN OUT.csv [SCHEDULES]
//!
//! RUN is the `--out` folder of the interrupted `groutready run` (its
//! restart point is `.RUN.resume` beside it); the scene and its schedules
//! (the scene's own, or the folder SCHEDULES, as `run --schedules`) must
//! be the ones it ran.
use std::path::Path;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (scene, run, out, schedules) = match args.as_slice() {
        [_, scene, run, out] => (scene, run, out, None),
        [_, scene, run, out, s] => (scene, run, out, Some(Path::new(s))),
        _ => anyhow::bail!("usage: restart_apertures SCENE RUN OUT.csv [SCHEDULES]"),
    };
    let inputs = groutready::app::load_inputs(Path::new(scene), schedules)?;
    let run = Path::new(run);
    let found = groutready::app::resume::find(run, &inputs.scene, &inputs.schedules, None);
    for w in &found.damaged {
        eprintln!("warning: {w}");
    }
    let Some(previous) = found.previous else {
        let dir = groutready::app::resume::dir_of(run);
        anyhow::bail!("no restart point of this scene in {}", dir.display());
    };
    let epoch = inputs.scene.epoch;
    let history = &previous.restart.history;
    // written beside, then renamed: OUT is never left half-written
    let partial = format!("{out}.partial");
    let rows = groutready::output::apertures::write(
        Path::new(&partial),
        epoch,
        &history.joint_records,
        &inputs.aperture_days(),
    )?;
    std::fs::rename(&partial, out)?;
    println!(
        "{out}: {rows} rows, to day {} ({})",
        previous.restart.checkpoint.day.0,
        epoch.date(previous.restart.checkpoint.day)
    );
    Ok(())
}
