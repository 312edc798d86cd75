//! A run folder's restart data damaged on a shared drive (issue 16): a
//! truncated checkpoint, one holding a NaN, a truncated history. The next
//! plan names the file, says it is damaged, and falls back to the last good
//! checkpoint or to a run from scratch, saying which.

use std::path::Path;

use groutready::app::{self, restart, Inputs};
use groutready::sim::checkpoint::{read_file, write_file};
use groutready::sim::{Checkpoint, Simulation};
use groutready::vocab::Day;
use tempfile::TempDir;

const END: Day = Day(70);

fn inputs() -> Inputs {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    app::load_inputs(&root.join("models/small_dam_joints.toml"), None).unwrap()
}

/// A run folder holding the restart data of the small dam's first 70 days,
/// with checkpoints on days 20, 41 and 61 (the first whole day 20 days after the last).
fn run_folder(inputs: &Inputs) -> TempDir {
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
    sim.set_end_day(END);
    sim.checkpoint_every = Some(20);
    sim.run(None, &mut |_, _| {}).unwrap();
    let days: Vec<Day> = sim.checkpoints.iter().map(|c| c.day).collect();
    assert_eq!(days, [Day(20), Day(41), Day(61)]);
    let tmp = TempDir::new().unwrap();
    let history = sim.history();
    restart::save(
        tmp.path(),
        &inputs.scene,
        &inputs.schedules,
        &history,
        &sim.checkpoints,
        Day(0),
        None,
    )
    .unwrap();
    tmp
}

fn ck(dir: &TempDir, day: i64) -> std::path::PathBuf {
    dir.path().join(format!("restart/ck-{day:05}.bin"))
}

fn truncate(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    std::fs::write(path, &bytes[..bytes.len() / 2]).unwrap();
}

fn find(dir: &TempDir, inputs: &Inputs) -> restart::Found {
    restart::find(dir.path(), &inputs.scene, &inputs.schedules, Some(END))
}

fn messages(found: &restart::Found) -> Vec<String> {
    found.damaged.iter().map(|w| w.to_string()).collect()
}

#[test]
fn damaged_checkpoints_fall_back_to_the_last_good_one_or_to_scratch() {
    let inputs = inputs();
    let dir = run_folder(&inputs);
    let found = find(&dir, &inputs);
    assert!(found.damaged.is_empty());
    assert_eq!(found.previous.unwrap().restart.checkpoint.day, Day(61));

    // Truncated: the checkpoint of day 41 is used instead.
    truncate(&ck(&dir, 61));
    let found = find(&dir, &inputs);
    let m = messages(&found);
    assert_eq!(m.len(), 1, "{m:?}");
    assert!(
        m[0].starts_with(&format!(
            "{}: damaged restart file (truncated or not written by this version of groutready: ",
            ck(&dir, 61).display()
        )),
        "{}",
        m[0]
    );
    assert!(
        m[0].ends_with("); restarting from the checkpoint of 2024-02-11 (ck-00041.bin) instead"),
        "{}",
        m[0]
    );
    let previous = found.previous.unwrap();
    assert_eq!(previous.restart.checkpoint.day, Day(41));
    assert_eq!(previous.restart.older.len(), 1);

    // A NaN in a well-formed file is damage too.
    let mut c41: Checkpoint = read_file(&ck(&dir, 41)).unwrap();
    c41.mechanics.as_mut().unwrap().u[7] = f64::NAN;
    write_file(&ck(&dir, 41), &c41, "checkpoint").unwrap();
    let found = find(&dir, &inputs);
    let m = messages(&found);
    assert_eq!(m.len(), 2, "{m:?}");
    assert_eq!(
        m[0],
        format!(
            "{}: damaged restart file (it holds a non-finite displacement); restarting from the checkpoint of 2024-01-21 (ck-00020.bin) instead",
            ck(&dir, 41).display()
        )
    );
    assert_eq!(found.previous.unwrap().restart.checkpoint.day, Day(20));

    // None left: from scratch, and said so.
    truncate(&ck(&dir, 20));
    let found = find(&dir, &inputs);
    assert!(found.previous.is_none());
    let m = messages(&found);
    assert_eq!(m.len(), 3);
    assert!(
        m.iter()
            .all(|m| m.ends_with("; planning from scratch instead")),
        "{m:?}"
    );
}

#[test]
fn a_damaged_history_means_from_scratch() {
    let inputs = inputs();
    let dir = run_folder(&inputs);
    let history = dir.path().join("restart/history.bin");
    truncate(&history);
    let found = find(&dir, &inputs);
    assert!(found.previous.is_none());
    let m = messages(&found);
    assert_eq!(m.len(), 1);
    assert!(
        m[0].starts_with(&format!("{}: damaged restart file (", history.display())),
        "{}",
        m[0]
    );
    assert!(
        m[0].ends_with("; planning from scratch instead"),
        "{}",
        m[0]
    );
}
