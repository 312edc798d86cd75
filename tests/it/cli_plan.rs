//! `groutready plan` as a site engineer runs it every week: exit codes, the
//! run folder, the restart from its checkpoints, and bad input.

use std::path::Path;
use std::process::Output;

use crate::common::{bin, copy_dir, repo, small_dam_scene_text};

fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

const SCENE: &str = "models/small_dam_joints.toml";

/// The first zones of the small dam: grouted at the end of May 2024, when
/// most of them are still too tight.
fn plan(out: &Path, extra: &[&str]) -> Output {
    bin()
        .args([
            "plan",
            SCENE,
            "--as-of",
            "2024-05-20",
            "--horizon-days",
            "10",
            "--out",
        ])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn readiness(out: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(out.join("readiness.csv")).unwrap();
    r.records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect()
}

#[test]
fn plan_writes_the_run_folder_exits_3_when_flagged_and_restarts_from_checkpoints() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("plan");
    // The site's joint meters on joint 2, zone 1.
    let sched = tmp.path().join("sched");
    copy_dir(&repo("schedules/small_dam"), &sched);
    std::fs::write(
        sched.join("joint_meters.csv"),
        "joint,zone,point,date,aperture_mm\n2,1,center,2024-04-01,0.20\n2,1,center,2024-05-01,0.35\n2,1,min,2024-05-15,0.10\n",
    )
    .unwrap();
    let sched_arg = sched.display().to_string();
    let o = plan(&out, &["--fail-on-flag", "--schedules", &sched_arg]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stdout}\n{stderr}");
    // A log (stderr is not a terminal here) says each remedy re-simulation.
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("re-simulating: supercooling")),
        "{stderr}"
    );
    for f in [
        "readiness.csv",
        "report.md",
        "report.json",
        "apertures.csv",
        "restart",
        "run.txt",
        "charts",
    ] {
        assert!(out.join(f).exists(), "{f} missing:\n{stdout}");
    }
    // Only the run folder: no staging folder left behind.
    assert_eq!(
        names(tmp.path()),
        vec!["plan".to_string(), "sched".to_string()]
    );
    // Meters against the prediction: per-joint errors in report.md agree
    // with the predictions in report.json, and a chart per meter.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let meters = json["meters"].as_array().unwrap();
    assert_eq!(meters.len(), 3);
    let errors: Vec<f64> = meters
        .iter()
        .map(|m| {
            m["predicted_mm"].as_f64().expect("predicted") - m["measured_mm"].as_f64().unwrap()
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / 3.0;
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Joint meters"), "{md}");
    assert!(
        md.contains(&format!("| 2 | 3 | 3 | {mean:.3} |")),
        "mean error {mean:.3}:\n{md}"
    );
    for f in ["meter_J2_Z1_center.svg", "meter_J2_Z1_min.svg"] {
        assert!(out.join("charts").join(f).exists(), "{f}");
    }
    let first = readiness(&out);
    assert!(first
        .iter()
        .any(|r| r.contains(&"not_groutable".to_string())));

    // The same week again: restarts from the run folder, same answer.
    let o = plan(&out, &["--schedules", &sched_arg]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("restarted from"), "{stdout}");
    assert_eq!(readiness(&out), first);
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        vec!["plan", "--as-of", "2024-13-01"],
        vec!["plan", "--horizon-days", "-3"],
        vec!["plan", "--no-such-flag"],
    ] {
        let o = bin().args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
    }
    let o = bin()
        .args(["plan", "--as-of", "2024-13-01"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("expected a date YYYY-MM-DD, found \"2024-13-01\""),
        "{err}"
    );
}

/// Edits one schedule file of a copy of the small dam's schedules.
enum Edit {
    /// replace 1-based line `n` of `file`
    Line(&'static str, usize, &'static str),
    /// append a line to `file`
    Append(&'static str, &'static str),
    /// write `file` with this text
    Write(&'static str, &'static str),
    Remove(&'static str),
}

fn apply(dir: &Path, edit: &Edit) {
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    match *edit {
        Edit::Line(f, n, text) => {
            let mut lines: Vec<String> = read(f).lines().map(String::from).collect();
            lines[n - 1] = text.to_string();
            std::fs::write(dir.join(f), lines.join("\n") + "\n").unwrap();
        }
        Edit::Append(f, text) => std::fs::write(dir.join(f), read(f) + text + "\n").unwrap(),
        Edit::Write(f, text) => std::fs::write(dir.join(f), text).unwrap(),
        Edit::Remove(f) => std::fs::remove_file(dir.join(f)).unwrap(),
    }
}

/// Malformed or inconsistent schedules: each is refused with its exact
/// message (file, line, column where there is one), exit code 1, and no run
/// folder is written.
#[test]
fn bad_schedules_are_refused_with_their_exact_error_and_nothing_is_written() {
    use Edit::*;
    let x = "x".repeat(10_000_000);
    let long_line: &str = Box::leak(format!("{x}\n").into_boxed_str());
    let long_line_error: &str = Box::leak(
        format!(
            "pours.csv:1: expected header \"block,lift,pour_date,placement_temp_c\", found \"{}… (10000000 characters)\"",
            &x[..120]
        )
        .into_boxed_str(),
    );
    let cases: Vec<(Edit, &str)> = vec![
        (
            Line("pours.csv", 2, "3,1,31/01/2024,17.9"),
            "pours.csv:2:3 (pour_date): expected a date YYYY-MM-DD, found \"31/01/2024\"",
        ),
        (
            Line("pours.csv", 2, "3,1,2024-01-31,warm"),
            "pours.csv:2:4 (placement_temp_c): expected a number (°C), found \"warm\"",
        ),
        (
            Line("pours.csv", 7, "3,2,2024-01-30,17.7"),
            "pours.csv:7:3: block 3 lift 2 poured 2024-01-30, before lift 1 (line 2) poured 2024-01-31",
        ),
        (Append("pours.csv", "9,1,2024-03-01,15"), "pours.csv:102:1: block 9 is not in the dam (blocks 1-5)"),
        (
            Line("cooling.csv", 2, "3,1,1,third,2024-01-31,2024-02-21,10,20"),
            "cooling.csv:2:4 (stage): expected one of first, middle, second, extra, found \"third\"",
        ),
        (Line("cooling.csv", 2, "3,1,1,first,2024-01-20,2024-02-21,10,20"), "cooling.csv:2:5: block 3 lift 1: stage first starts 2024-01-20, before lift 1 is poured 2024-01-31 (pours.csv:2)"),
        (Line("cooling.csv", 2, "3,1,1,first,2024-01-31,2024-02-21,10,8"), "cooling.csv:2:8 (target_temp_c): expected a target temperature above water_temp_c 10 °C, found \"8\""),
        (Line("grouting.csv", 2, "2,1,2024-01-15,"), "grouting.csv:2:3: joint 2 zone 1 planned 2024-01-15, before the zone exists: block 2 lift 3 is poured 2024-02-26 (pours.csv:13)"),
        (Append("grouting.csv", "2,9,2025-06-01,"), "grouting.csv:30:2: joint 2 zone 9 is above the dam (joint 2 has zones 1-7)"),
        (Append("grouting.csv", "7,1,2024-06-01,"), "grouting.csv:30:1: joint 7 does not exist (joints 1-4)"),
        (Append("grouting.csv", "2,1,2024-05-27,"), "grouting.csv:30:1: duplicate row: joint 2 zone 1 is already on line 2"),
        (Line("grouting.csv", 1, "joint,zone,planed_date"), "grouting.csv:1: expected header \"joint,zone,planned_date\", found \"joint,zone,planed_date\" (missing column \"planned_date\"; unexpected column \"planed_date\")"),
        (
            Write("grouting.csv", "joint,zone,planned_date,status\n2,1,2024-05-26,finished\n"),
            "grouting.csv:2:4 (status): expected done, planned or blank, found \"finished\"",
        ),
        (Line("reservoir.csv", 2, "2024-09-13,high"), "reservoir.csv:2:2 (level_m): expected a number (m), found \"high\""),
        (
            Write("joint_meters.csv", "joint,zone,point,date,aperture_mm\n2,9,center,2024-06-01,0.6\n"),
            "joint_meters.csv:2:2: joint 2 zone 9 is above the dam (joint 2 has zones 1-7)",
        ),
        (
            Write("joint_meters.csv", "joint,zone,point,date,aperture_mm\n2,1,middle,2024-06-01,0.6\n"),
            "joint_meters.csv:2:3 (point): expected one of upstream, center, downstream, min, found \"middle\"",
        ),
        (Remove("pours.csv"), "pours.csv: required file not found in"),
        // A 10 MB one-line file: the message quotes 120 characters of it.
        (Write("pours.csv", long_line), long_line_error),
        (
            Append("reservoir.csv", "2025-06-01,1500"),
            "reservoir.csv:4:2 (level_m): expected a level at most 66 m (the dam's crest is at 60 m, its base at 0 m), found \"1500\"",
        ),
    ];
    assert!(cases.len() >= 15);
    let mut failures = Vec::new();
    for (i, (edit, expected)) in cases.iter().enumerate() {
        let tmp = tempfile::tempdir().unwrap();
        let sched = tmp.path().join("sched");
        copy_dir(&repo("schedules/small_dam"), &sched);
        apply(&sched, edit);
        let out = tmp.path().join("out");
        let o = bin()
            .args(["plan", SCENE, "--schedules"])
            .arg(&sched)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        // No message quotes a whole file (the 10 MB line above).
        if o.status.code() != Some(1) || !err.contains(expected) || err.len() > 1_000 {
            failures.push(format!("case {i}: exit {:?}: {err}", o.status.code()));
        }
        assert_eq!(
            names(tmp.path()),
            vec!["sched".to_string()],
            "case {i} wrote files"
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn bad_planner_settings_and_a_scene_without_joints_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let text = small_dam_scene_text(&repo("schedules/small_dam"));
    let bad = format!("{text}\n[planner]\nmin_aperture_mm = -0.5\n");
    let scene = tmp.path().join("bad.toml");
    std::fs::write(&scene, bad).unwrap();
    let out = tmp.path().join("out");
    let o = bin()
        .arg("plan")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("planner.min_aperture_mm must be > 0, got -0.5"),
        "{err}"
    );

    let o = bin()
        .args(["plan", "models/two_blocks.toml", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("planning needs the `joints` effect"), "{err}");
    assert_eq!(names(tmp.path()), vec!["bad.toml".to_string()]);
}

/// The small dam with no zone marked done, in `dir`: its scene's path and
/// its `grouting.csv`. Its zones are due in 2024, before any day this runs.
fn small_dam_with_no_zone_done(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let schedules = dir.join("schedules");
    copy_dir(&repo("schedules/small_dam"), &schedules);
    let grouting = schedules.join("grouting.csv");
    let text = std::fs::read_to_string(&grouting).unwrap();
    assert!(text.contains(",done"), "the small dam marks zones done");
    std::fs::write(&grouting, text.replace(",done", ",planned")).unwrap();
    let scene = small_dam_scene_text(&schedules);
    let scene_path = dir.join("undone.toml");
    std::fs::write(&scene_path, scene).unwrap();
    (scene_path, grouting)
}

/// Schedules that mark no zone done leave the as-of date to the clock:
/// once every zone was due before today the plan is refused before
/// anything is simulated (the large arch's whole construction would run
/// for a report of history alone), and it says how to give the date.
#[test]
fn a_plan_with_nothing_left_to_grout_by_today_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (scene_path, grouting) = small_dam_with_no_zone_done(tmp.path());
    let o = bin()
        .arg("plan")
        .arg(&scene_path)
        .arg("--out")
        .arg(tmp.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("{}: no zone is marked done", grouting.display()))
            && err.contains("nothing is left to plan")
            && err.contains("--as-of DATE"),
        "{err}"
    );
    assert!(
        !err.contains("simulating"),
        "refused before simulating: {err}"
    );
    assert_eq!(
        names(tmp.path()),
        vec!["schedules".to_string(), "undone.toml".to_string()]
    );
}

/// `study perf` plans a scene after timing its whole construction, on the
/// binary's clock: with nothing left to plan by today it says so and
/// succeeds (the construction's figures stand), rather than planning
/// every zone from a made-up date or failing after the run; given
/// `--as-of` it times that plan.
#[test]
fn study_perf_says_why_it_times_no_plan_when_nothing_is_left() {
    let tmp = tempfile::tempdir().unwrap();
    let (scene_path, grouting) = small_dam_with_no_zone_done(tmp.path());
    let perf = |extra: &[&str]| {
        let o = bin()
            .args(["study", "perf"])
            .arg(&scene_path)
            .arg("--no-exact")
            .args(extra)
            .output()
            .unwrap();
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{out}{err}");
        out
    };
    let out = perf(&[]);
    assert!(
        out.contains(&format!(
            "plan not timed: {}: no zone is marked done",
            grouting.display()
        )) && out.contains("nothing is left to plan"),
        "{out}"
    );
    assert!(!out.contains("plan from scratch"), "{out}");
    let out = perf(&["--as-of", "2024-05-20", "--horizon-days", "10"]);
    assert!(
        out.contains("plan from scratch") && !out.contains("plan not timed"),
        "{out}"
    );
}

#[test]
fn a_failed_plan_keeps_the_previous_run_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("report.md"), "last week").unwrap();
    let sched = tmp.path().join("sched");
    copy_dir(&repo("schedules/small_dam"), &sched);
    std::fs::write(
        sched.join("grouting.csv"),
        "joint,zone,planned_date\n2,1,someday\n",
    )
    .unwrap();
    let o = bin()
        .args(["plan", SCENE, "--schedules"])
        .arg(&sched)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(out.join("report.md")).unwrap(),
        "last week"
    );
    assert_eq!(
        names(tmp.path()),
        vec!["out".to_string(), "sched".to_string()]
    );
}

/// A weekly re-plan costs what changed (issue 15 item 4): the same plan
/// again takes both remedy searches and their verification from the run
/// folder (`restart/search.bin`), re-simulates nothing and writes the same
/// readiness table and report. A damaged `search.bin` is named, and the
/// plan searches again instead.
#[test]
fn the_same_plan_again_reuses_the_remedy_search() {
    let shared = crate::common::small_plan();
    assert!(shared.output.status.success(), "{}", shared.stderr());
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("plan");
    copy_dir(&shared.out, &out);
    let again = |horizon: &str| {
        bin()
            .args([
                "plan",
                "models/small_dam_joints.toml",
                "--as-of",
                "2024-06-01",
                "--horizon-days",
                horizon,
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = again("105");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    assert!(stdout.contains("+ 0 re-simulations"), "{stdout}");
    assert!(
        stdout.contains("reused from the last plan: supercooling search (")
            && stdout.contains("delay search (")
            && stdout.contains("verification ("),
        "{stdout}"
    );
    assert!(shared.stdout().contains("re-simulations in"));
    assert!(!shared.stdout().contains("reused"), "{}", shared.stdout());
    assert_eq!(readiness(&out), readiness(&shared.out));
    let zones = |dir: &Path| -> serde_json::Value {
        let text = std::fs::read_to_string(dir.join("report.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()["zones"].clone()
    };
    assert_eq!(zones(&out), zones(&shared.out));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("reused from the last plan: supercooling search"));

    // A damaged search file: said so, and searched again (a short horizon
    // here, so that the search is quick).
    let search = out.join("restart/search.bin");
    std::fs::write(&search, b"\x07not a search").unwrap();
    let o = again("1");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    // The table wraps long warnings: compare with single spaces.
    let all = format!("{stdout}{stderr}")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        all.contains("search.bin: damaged restart file (")
            && all.contains("searching the remedies again instead"),
        "{all}"
    );
    assert!(!stdout.contains("reused"), "{stdout}");
}
