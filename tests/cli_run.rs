//! The `groutready` binary as a site engineer runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_groutready"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Nothing but `keep` may exist in `dir` (no staging folder left behind).
fn only(dir: &Path, keep: &[&str]) {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut keep: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
    keep.sort();
    assert_eq!(names, keep, "unexpected files in {}", dir.display());
}

#[test]
fn demo_run_writes_temperatures_and_snapshots() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("demo");
    let status = bin().args(["run", "--out"]).arg(&out).output().unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let csv = std::fs::read_to_string(out.join("temperatures.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("joint,zone,point,date,day,temperature_c")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 10_000, "{} rows", rows.len());
    for r in &rows {
        let t: f64 = r[5].parse().unwrap();
        assert!((-10.0..60.0).contains(&t), "implausible temperature {r:?}");
        assert!(["upstream", "center", "downstream"].contains(&r[2]));
    }
    // Hydration heats the fresh concrete above its placement temperature (≤ 18 °C)...
    let peak = rows
        .iter()
        .map(|r| r[5].parse::<f64>().unwrap())
        .fold(f64::MIN, f64::max);
    assert!(peak > 24.0, "peak {peak}");
    only(&out, &["fields", "run.txt", "temperatures.csv"]);
    let fields = out.join("fields");
    let vtus = std::fs::read_dir(&fields).unwrap().filter(|e| {
        e.as_ref()
            .unwrap()
            .path()
            .extension()
            .is_some_and(|x| x == "vtu")
    });
    assert_eq!(vtus.count(), 2);
    let pvd = std::fs::read_to_string(fields.join("fields.pvd")).unwrap();
    assert!(pvd.contains("fields_2025-03-01.vtu") && pvd.contains("fields_2025-09-01.vtu"));
    only(tmp.path(), &["demo"]);
}

#[test]
fn bad_schedule_is_reported_with_file_line_column_and_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let sched = tmp.path().join("sched");
    copy_dir(&repo("schedules/two_blocks"), &sched);
    let pours = std::fs::read_to_string(sched.join("pours.csv")).unwrap();
    let mut lines: Vec<String> = pours.lines().map(String::from).collect();
    let cells: Vec<&str> = lines[2].split(',').collect();
    let bad = format!("{},{},2024-02-30,{}", cells[0], cells[1], cells[3]);
    lines[2] = bad;
    std::fs::write(sched.join("pours.csv"), lines.join("\n") + "\n").unwrap();
    let out = tmp.path().join("out");
    let o = bin()
        .args(["run", "models/two_blocks.toml", "--schedules"])
        .arg(&sched)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("pours.csv:3:3 (pour_date): expected a date YYYY-MM-DD, found \"2024-02-30\""),
        "{err}"
    );
    only(tmp.path(), &["sched"]);
}

#[test]
fn bad_scene_names_the_key_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo("models/two_blocks.toml"))
        .unwrap()
        .replace("conductivity_w_mk = 2.2", "conductivity_w_mk = -2.2")
        .replace(
            "../schedules/two_blocks",
            &repo("schedules/two_blocks").display().to_string(),
        );
    assert!(text.contains("-2.2"), "fixture changed: update the test");
    let scene = tmp.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = tmp.path().join("out");
    let o = bin()
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("concrete.conductivity_w_mk must be > 0, got -2.2"),
        "{err}"
    );
    only(tmp.path(), &["scene.toml"]);
}

#[test]
fn usage_errors_exit_2() {
    let o = bin().args(["run", "--no-such-flag"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin().arg("frobnicate").output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_failed_run_keeps_the_previous_run_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("temperatures.csv"), "previous").unwrap();
    let sched = tmp.path().join("sched");
    copy_dir(&repo("schedules/two_blocks"), &sched);
    std::fs::write(sched.join("pours.csv"), "block,lift,pour_date\n").unwrap();
    let o = bin()
        .args(["run", "models/two_blocks.toml", "--schedules"])
        .arg(&sched)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(out.join("temperatures.csv")).unwrap(),
        "previous"
    );
    only(tmp.path(), &["out", "sched"]);
}
