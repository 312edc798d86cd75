//! The `apertures.csv` of an interrupted run, read from its restart point
//! (the rows `groutready run` writes, up to the restart point's day):
//! a long run's joint history so far, for `tests/aperture_pattern.py`,
//! without waiting for its end.
//!
//!     cargo run --release --example restart_apertures SCENE RUN OUT.csv
//!
//! RUN is the `--out` folder of the interrupted `groutready run` (its
//! restart point is `.RUN.resume` beside it); the scene and its schedules
//! must be the ones it ran.
use std::path::Path;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene, run, out] = args.as_slice() else {
        anyhow::bail!("usage: restart_apertures SCENE RUN OUT.csv");
    };
    let inputs = groutready::app::load_inputs(Path::new(scene), None)?;
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
