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
    let dir = groutready::app::resume::dir_of(Path::new(run));
    let found = groutready::app::restart::find(
        &dir,
        &inputs.scene,
        &inputs.schedules,
        groutready::vocab::Day(i64::from(i32::MAX)),
    );
    for w in &found.damaged {
        eprintln!("warning: {w}");
    }
    let Some(previous) = found.previous else {
        anyhow::bail!("no restart point of this scene in {}", dir.display());
    };
    let epoch = inputs.scene.epoch;
    let history = &previous.restart.history;
    let rows = groutready::output::apertures::write(
        Path::new(out),
        epoch,
        &history.joint_records,
        &inputs.aperture_days(),
    )?;
    println!(
        "{out}: {rows} rows, to day {} ({})",
        previous.restart.checkpoint.day.0,
        epoch.date(previous.restart.checkpoint.day)
    );
    Ok(())
}
