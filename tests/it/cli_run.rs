//! The `groutready` binary as a site engineer runs it.

use std::path::{Path, PathBuf};

use crate::common::{bin, copy_dir, repo, small_dam_scene_text};

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

/// `models/<model>.toml` written into `dir` as `scene.toml` with `edit`
/// applied and its schedules folder made absolute; returns its path.
fn edited_scene(dir: &Path, model: &str, edit: impl FnOnce(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(repo(&format!("models/{model}.toml")))
        .unwrap()
        .replace(
            &format!("../schedules/{model}"),
            &repo(&format!("schedules/{model}")).display().to_string(),
        );
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, edit(text)).unwrap();
    scene
}

/// `groutready run SCENE --out DIR/out`, which must fail with exit code 1;
/// returns its standard error.
fn refused_run(scene: &Path, dir: &Path) -> String {
    let o = bin()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The quick scene with thermal, mechanics and joints (the demo itself runs
/// in `.ci/run`, where its apertures are checked against the paper's pattern).
#[test]
fn run_writes_temperatures_apertures_and_snapshots() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let status = bin()
        .args(["run", "models/small_dam_joints.toml", "--out"])
        .arg(&out)
        .output()
        .unwrap();
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
    assert!(rows.len() > 5_000, "{} rows", rows.len());
    for r in &rows {
        let t: f64 = r[5].parse().unwrap();
        assert!((-10.0..60.0).contains(&t), "implausible temperature {r:?}");
        assert!(["upstream", "center", "downstream"].contains(&r[2]));
    }
    // Hydration heats the fresh concrete well above its placement temperature.
    let peak = rows
        .iter()
        .map(|r| r[5].parse::<f64>().unwrap())
        .fold(f64::MIN, f64::max);
    assert!(peak > 24.0, "peak {peak}");
    // Each point's history starts on the day the lift that completes its
    // face is poured (at its placement temperature), not the day after.
    let pours = std::fs::read_to_string("schedules/small_dam/pours.csv").unwrap();
    let pour_dates: std::collections::HashSet<&str> = pours
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap())
        .collect();
    let mut first: std::collections::BTreeMap<(&str, &str, &str), &str> = Default::default();
    for r in &rows {
        first.entry((r[0], r[1], r[2])).or_insert(r[3]);
    }
    for (point, date) in &first {
        assert!(
            pour_dates.contains(date),
            "{point:?} starts on {date}, not a pour date"
        );
    }

    let csv = std::fs::read_to_string(out.join("apertures.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 1_000, "{} rows", rows.len());
    let mut states = std::collections::BTreeSet::new();
    let mut widest: f64 = 0.0;
    for r in &rows {
        assert!(
            ["upstream", "center", "downstream", "min"].contains(&r[2]),
            "{r:?}"
        );
        let a: f64 = r[5].parse().unwrap();
        assert!((-1e-3..4.0).contains(&a), "implausible aperture {r:?}");
        widest = widest.max(a);
        states.insert(r[6].to_string());
    }
    assert!(widest > 0.5, "cooling opens the joints: widest {widest} mm");
    for s in &states {
        assert!(
            ["open", "stick", "slip", "grouted", "reopened"].contains(&s.as_str()),
            "{s}"
        );
    }
    assert!(
        states.contains("open") && states.contains("grouted"),
        "{states:?}"
    );

    grouting_distribution_reads_the_csv(&out, &rows);
    reopening_reads_the_csv(&out, &rows);
    // The small dam's mechanics is exact: run.txt says so, the console
    // names approximations only when there are some.
    let text = std::fs::read_to_string(out.join("run.txt")).unwrap();
    assert!(
        text.contains("mechanics approximations: none (the exact path)\n"),
        "{text}"
    );
    assert!(!String::from_utf8_lossy(&status.stdout).contains("approximations"));

    only(
        &out,
        &[
            ".groutready-run",
            "apertures.csv",
            "fields",
            "run.txt",
            "temperatures.csv",
        ],
    );
    let fields = out.join("fields");
    let pvd = std::fs::read_to_string(fields.join("fields.pvd")).unwrap();
    assert!(pvd.contains("fields_2024-07-01.vtu"), "{pvd}");
    let vtu = std::fs::read_to_string(fields.join("fields_2024-07-01.vtu")).unwrap();
    for field in [
        "temperature_c",
        "ux_m",
        "sxx_mpa",
        "joint_aperture_mm",
        "joint_pressure_mpa",
    ] {
        assert!(
            vtu.contains(&format!("Name=\"{field}\"")),
            "{field} missing"
        );
    }
    only(tmp.path(), &["run"]);
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
    let scene = edited_scene(tmp.path(), "two_blocks", |text| {
        assert!(
            text.contains("conductivity_w_mk = 2.2"),
            "fixture changed: update the test"
        );
        text.replace("conductivity_w_mk = 2.2", "conductivity_w_mk = -2.2")
    });
    let err = refused_run(&scene, tmp.path());
    assert!(
        err.contains("concrete.conductivity_w_mk must be > 0, got -2.2"),
        "{err}"
    );
    only(tmp.path(), &["scene.toml"]);
}

/// A pour dated before the scene's epoch is refused before the run at its
/// cell (it used to fail 43 days in as "matrix is not positive definite"),
/// and nothing is written.
#[test]
fn a_pour_before_the_epoch_is_refused_before_the_run() {
    let tmp = tempfile::tempdir().unwrap();
    let first_pour = std::fs::read_to_string(repo("schedules/two_blocks/pours.csv"))
        .unwrap()
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').nth(2).map(String::from))
        .unwrap();
    // the epoch a day after the first pour
    let day_after = chrono::NaiveDate::parse_from_str(&first_pour, "%Y-%m-%d").unwrap()
        + chrono::Duration::days(1);
    let scene = edited_scene(tmp.path(), "two_blocks", |text| {
        let epoch_line = text
            .lines()
            .find(|l| l.starts_with("epoch"))
            .unwrap()
            .to_string();
        text.replace(&epoch_line, &format!("epoch = {day_after}"))
    });
    let err = refused_run(&scene, tmp.path());
    assert!(
        err.contains(&format!(
            "pours.csv:2:3 (pour_date): expected a date on or after the scene's epoch {day_after}, found \"{first_pour}\""
        )),
        "{err}"
    );
    only(tmp.path(), &["scene.toml"]);
}

/// A mesh that cannot fit in the machine's memory is refused at once with
/// the estimate (it used to abort on a 17 GB allocation), nothing written.
#[test]
fn a_mesh_beyond_the_machine_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = edited_scene(tmp.path(), "demo_arch", |text| {
        let line = text
            .lines()
            .find(|l| l.starts_with("elements_per_block"))
            .unwrap()
            .to_string();
        text.replace(&line, "elements_per_block = 100000")
    });
    let t = std::time::Instant::now();
    let err = refused_run(&scene, tmp.path());
    let seconds = t.elapsed().as_secs_f64();
    assert!(err.contains("mesh too large for this machine: "), "{err}");
    assert!(err.contains("GiB, the machine has "), "{err}");
    eprintln!("refused in {seconds:.3} s: {err}");
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

/// `run.txt`'s distribution of the deciding (`min`) apertures on the
/// planned grouting dates counts what `apertures.csv` holds on those dates.
fn grouting_distribution_reads_the_csv(out: &Path, rows: &[Vec<&str>]) {
    let grouting = std::fs::read_to_string("schedules/small_dam/grouting.csv").unwrap();
    let planned: std::collections::HashSet<(String, String, String)> = grouting
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), f[1].to_string(), f[2].to_string())
        })
        .collect();
    let apertures: Vec<f64> = rows
        .iter()
        .filter(|r| r[2] == "min")
        .filter(|r| planned.contains(&(r[0].into(), r[1].into(), r[3].into())))
        .map(|r| r[5].parse().unwrap())
        .collect();
    assert_eq!(
        apertures.len(),
        planned.len(),
        "one `min` row per zone on its date"
    );
    let count = |lo: f64, hi: f64| apertures.iter().filter(|&&a| a >= lo && a < hi).count();
    let expected = format!(
        "apertures on the planned grouting dates: {} zones, point min, rule >= 0.50 mm\n  \
         closed {}, open below 0.50 mm {}, 0.50-1.00 mm {}, 1.00-2.00 mm {}, 2.00-3.00 mm {}, >= 3.00 mm {}\n",
        planned.len(),
        count(f64::MIN, 0.005),
        count(0.005, 0.5),
        count(0.5, 1.0),
        count(1.0, 2.0),
        count(2.0, 3.0),
        count(3.0, f64::MAX),
    );
    let text = std::fs::read_to_string(out.join("run.txt")).unwrap();
    assert!(text.contains(&expected), "{text}\nexpected:\n{expected}");
    // every zone is judged once, and each below the rule fails it
    let verdicts = text.lines().find(|l| l.contains("verdicts:")).unwrap();
    let n: Vec<usize> = verdicts
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|w| w.parse().ok())
        .collect();
    assert_eq!(n.len(), 3, "{verdicts}");
    assert_eq!(n.iter().sum::<usize>(), planned.len(), "{verdicts}");
    assert!(n[2] >= count(f64::MIN, 0.5), "{verdicts}");
}

/// `run.txt`'s grouted zones that re-opened agree with `apertures.csv`,
/// which samples the daily history weekly and on the grouting dates: every
/// zone point the CSV shows re-opened is counted, and the widest opening
/// since grouting is at least the CSV's (the CSV's aperture less the
/// point's first grouted one).
fn reopening_reads_the_csv(out: &Path, rows: &[Vec<&str>]) {
    use std::collections::{BTreeMap, BTreeSet};
    // a point's first grouted aperture, else (its layer cracked within its
    // grouting day's step) its last aperture before
    let mut grouted: BTreeMap<(&str, &str, &str), f64> = BTreeMap::new();
    let mut before: BTreeMap<(&str, &str, &str), f64> = BTreeMap::new();
    let mut zones = BTreeSet::new();
    let mut widest = 0.0f64;
    for r in rows.iter().filter(|r| r[2] != "min") {
        let key = (r[0], r[1], r[2]);
        let a: f64 = r[5].parse().unwrap();
        match r[6] {
            "grouted" => {
                grouted.entry(key).or_insert(a);
            }
            "reopened" => {
                zones.insert((r[0], r[1]));
                let from = before.get(&key).copied().unwrap_or(0.0);
                widest = widest.max(a - *grouted.entry(key).or_insert(from));
            }
            _ if !grouted.contains_key(&key) => {
                before.insert(key, a);
            }
            _ => {}
        }
    }
    assert!(
        !zones.is_empty(),
        "the small dam's faces crack open in winter"
    );
    let text = std::fs::read_to_string(out.join("run.txt")).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("re-opened after grouting: "))
        .unwrap_or_else(|| panic!("{text}"));
    let n: usize = line["re-opened after grouting: ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(n >= zones.len(), "{line}: the CSV shows {}", zones.len());
    let wide = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("widest opening since grouting "))
        .unwrap_or_else(|| panic!("{text}"));
    let mm: f64 = wide.split(' ').next().unwrap().parse().unwrap();
    assert!(mm >= widest - 0.005, "{wide}: the CSV shows {widest:.4} mm");
}

/// Starts `groutready run SCENE --out OUT` and kills it (SIGKILL: no
/// clean-up runs) once it has kept its first restart point.
fn killed_after_first_restart_point(scene: &Path, out: &Path) {
    killed_after_restart_point(scene, out, &[], None);
}

/// `groutready run SCENE --out OUT` (extra arguments `args`) killed once it
/// has kept a restart point other than the checkpoint file `other`;
/// returns the kept checkpoint's file name.
fn killed_after_restart_point(
    scene: &Path,
    out: &Path,
    args: &[&std::ffi::OsStr],
    other: Option<&str>,
) -> String {
    let name = out.file_name().unwrap().to_string_lossy().into_owned();
    let restart = out
        .with_file_name(format!(".{name}.resume"))
        .join("restart");
    let mut child = bin()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // a whole checkpoint: `ck-DDDDD.tmp` is one being written, which a
    // kill leaves unread (the run then starts from day 0)
    let kept = || {
        std::fs::read_dir(&restart).ok().and_then(|rd| {
            rd.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .find(|n| n.starts_with("ck-") && n.ends_with(".bin") && Some(n.as_str()) != other)
        })
    };
    let start = std::time::Instant::now();
    let kept = loop {
        if let Some(ck) = kept() {
            break ck;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before keeping a restart point"
        );
        assert!(start.elapsed().as_secs() < 120, "no restart point kept");
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.exists(), "a killed run wrote its run folder");
    kept
}

/// A run continued with schedules that differ after its restart point
/// keeps its next restart point with those schedules, so a run with the
/// old ones does not continue from states it never had (the folder used
/// to keep the schedules of the run that started it).
#[test]
fn a_run_continued_with_changed_schedules_keeps_them_with_its_restart_point() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = small_dam_restarting_at_day_120(tmp.path());
    let run = tmp.path().join("runs").join("changed");
    let day = |ck: &str| -> i64 { ck[3..8].parse().unwrap() };
    let first = killed_after_restart_point(&scene, &run, &[], None);
    assert!(day(&first) < 162, "{first}");
    // a lift of 11 June 2024 (day 162) poured a degree warmer
    let changed = tmp.path().join("changed_schedules");
    copy_dir(&repo("schedules/small_dam"), &changed);
    let pours = changed.join("pours.csv");
    let text = std::fs::read_to_string(&pours).unwrap();
    assert!(text.contains("3,12,2024-06-11,12.6\n"));
    std::fs::write(
        &pours,
        text.replace("3,12,2024-06-11,12.6\n", "3,12,2024-06-11,13.6\n"),
    )
    .unwrap();
    let args = [std::ffi::OsStr::new("--schedules"), changed.as_os_str()];
    let second = killed_after_restart_point(&scene, &run, &args, Some(&first));
    assert!(day(&second) > 162, "{second}");
    let kept = groutready::schedule::load(&tmp.path().join("runs/.changed.resume/restart/inputs"))
        .unwrap();
    let edited = groutready::schedule::load(&changed).unwrap();
    assert_eq!(
        groutready::planner::edit::first_change(&kept, &edited),
        None
    );
    let err = run_again(&scene, &run, &[]);
    assert!(!err.contains("continuing"), "{err}");
    assert!(
        err.contains("not one these inputs and this program can continue from"),
        "{err}"
    );
}

/// `groutready run SCENE` again into OUT (extra arguments `args`); returns
/// its standard error.
fn run_again(scene: &Path, out: &Path, args: &[&str]) -> String {
    let o = bin()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

/// The small dam with joints in `dir`, its first restart point after
/// months of histories and a snapshot (day 120).
fn small_dam_restarting_at_day_120(dir: &Path) -> PathBuf {
    let text = small_dam_scene_text(&repo("schedules/small_dam")).replace(
        "snapshots = [2024-07-01]",
        "snapshots = [2024-01-05, 2024-03-01, 2024-07-01]",
    ) + "\n[planner]\ncheckpoint_days = 120\n";
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    scene
}

/// `study perf --resume RUN --days N` times N days from the restart point
/// of an interrupted run into RUN (a long run's late days), and leaves the
/// restart point as it was; a folder without one is refused by name.
#[test]
fn study_perf_times_an_interrupted_run_from_its_restart_point() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = small_dam_restarting_at_day_120(tmp.path());
    let run = tmp.path().join("runs").join("long");
    killed_after_first_restart_point(&scene, &run);
    let restart = tmp.path().join("runs").join(".long.resume").join("restart");
    let listing = |d: &Path| -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (
                    e.file_name().to_string_lossy().into_owned(),
                    e.metadata().unwrap().len(),
                )
            })
            .collect();
        v.sort();
        v
    };
    let before = listing(&restart);
    // ten days timed from the restart point: (success, stdout, stderr)
    let perf_resumed = || {
        let o = bin()
            .args(["study", "perf"])
            .arg(&scene)
            .arg("--resume")
            .arg(&run)
            .args(["--days", "10"])
            .output()
            .unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (ok, out, err) = perf_resumed();
    assert!(ok, "{out}{err}");
    let number_after = |key: &str| -> u64 {
        let at = out
            .find(key)
            .unwrap_or_else(|| panic!("no {key:?} in {out}"))
            + key.len();
        out[at..]
            .split(|c: char| !c.is_ascii_digit())
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let from = number_after("resumed from day ");
    assert!((100..=140).contains(&from), "{out}");
    assert!(
        out.contains(&format!("{} days simulated", from + 10)),
        "{out}"
    );
    // the ten days' mechanical steps only, none of the 100 days before
    let steps = number_after("mechanics: ");
    assert!((1..=10).contains(&steps), "{out}");
    assert!(
        !out.contains("exact"),
        "no exact path from a restart point: {out}"
    );
    assert_eq!(listing(&restart), before, "the restart point was changed");

    let o = bin()
        .args(["study", "perf"])
        .arg(&scene)
        .arg("--resume")
        .arg(tmp.path().join("runs").join("never"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("no restart point") && err.contains(".never.resume"),
        "{err}"
    );

    // a truncated checkpoint is passed over and said, as `run` says it
    let checkpoint = std::fs::read_dir(&restart)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.file_name().unwrap().to_string_lossy().starts_with("ck-"))
        .expect("a checkpoint");
    let bytes = std::fs::read(&checkpoint).unwrap();
    std::fs::write(&checkpoint, &bytes[..bytes.len() / 2]).unwrap();
    let (ok, out, err) = perf_resumed();
    let warning = format!("warning: {}: damaged restart file", checkpoint.display());
    assert!(out.contains(&warning), "{out}{err}");
    assert!(!ok && err.contains("no restart point"), "{err}");
}

/// A run killed on the way continues from its restart point when run
/// again, and writes what a run from day 0 writes, byte for byte (the
/// temperatures, the apertures with their states, every field file, those
/// written before the restart point too); with `--from-scratch` it starts
/// from day 0 and removes the restart point.
#[test]
fn a_killed_run_continues_from_its_restart_point() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = small_dam_restarting_at_day_120(tmp.path());
    let runs = tmp.path().join("runs");
    let (resumed, scratch) = (runs.join("resumed"), runs.join("scratch"));
    killed_after_first_restart_point(&scene, &resumed);
    let err = run_again(&scene, &resumed, &[]);
    assert!(
        err.contains("continuing the interrupted run from 2024-"),
        "{err}"
    );
    killed_after_first_restart_point(&scene, &scratch);
    let err = run_again(&scene, &scratch, &["--from-scratch"]);
    assert!(
        err.contains(".scratch.resume (the restart point of an interrupted run: --from-scratch)"),
        "{err}"
    );
    assert!(!err.contains("continuing"), "{err}");
    for f in ["temperatures.csv", "apertures.csv"] {
        let (a, b) = (
            std::fs::read(resumed.join(f)).unwrap(),
            std::fs::read(scratch.join(f)).unwrap(),
        );
        assert!(
            a == b,
            "{f} differs between the resumed run and the run from day 0"
        );
    }
    let names = |d: &Path| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d.join("fields"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names(&resumed), names(&scratch));
    assert_eq!(names(&resumed).len(), 4, "{:?}", names(&resumed));
    for n in names(&resumed) {
        let (a, b) = (
            std::fs::read(resumed.join("fields").join(&n)).unwrap(),
            std::fs::read(scratch.join("fields").join(&n)).unwrap(),
        );
        assert!(a == b, "fields/{n} differs");
    }
    let run_txt = std::fs::read_to_string(resumed.join("run.txt")).unwrap();
    assert!(
        run_txt.contains("continued from the restart point of 2024-"),
        "{run_txt}"
    );
    // nothing left beside the two run folders: no restart point, lock or staging
    only(&runs, &["resumed", "scratch"]);
}

/// A scene with opt-in approximations: `run` lists them on the console and
/// in run.txt; `--exact` turns them off, says which, and takes the exact
/// path's daily mechanical steps.
#[test]
fn run_lists_the_approximations_and_exact_turns_them_off() {
    let tmp = tempfile::tempdir().unwrap();
    let text = small_dam_scene_text(&repo("schedules/small_dam")).replace(
        "[time]\n",
        "[time]\nmechanics_max_step_days = 3\nmechanics_merge_pours = true\n",
    );
    let scene = tmp.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let keys = "time.mechanics_max_step_days = 3, time.mechanics_merge_pours = true";
    let run = |exact: bool, out: &str| {
        let o = bin()
            .arg("run")
            .arg(&scene)
            .arg("--out")
            .arg(tmp.path().join(out))
            .args(exact.then_some("--exact"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let run_txt = std::fs::read_to_string(tmp.path().join(out).join("run.txt")).unwrap();
        (o, run_txt)
    };
    let steps = |run_txt: &str| -> u32 {
        let line = run_txt
            .lines()
            .find(|l| l.starts_with("mechanics: "))
            .unwrap();
        line["mechanics: ".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };

    let (approx, approx_txt) = run(false, "approx");
    let listed = format!("mechanics approximations: {keys}\n");
    assert!(
        String::from_utf8_lossy(&approx.stdout).contains(&listed),
        "{}",
        String::from_utf8_lossy(&approx.stdout)
    );
    assert!(approx_txt.contains(&listed), "{approx_txt}");

    let (exact, exact_txt) = run(true, "exact");
    let stderr = String::from_utf8_lossy(&exact.stderr);
    assert!(
        stderr.contains(&format!(
            "note: --exact: simulating without the scene's {keys}\n"
        )),
        "{stderr}"
    );
    assert!(
        exact_txt.contains("mechanics approximations: none (the exact path)\n"),
        "{exact_txt}"
    );
    assert!(!String::from_utf8_lossy(&exact.stdout).contains("approximations"));
    // the exact path steps every midnight: more steps than the 3-day steps
    // with pours merged (264 against 130 steps)
    assert!(
        steps(&exact_txt) > steps(&approx_txt),
        "{exact_txt}\n{approx_txt}"
    );
}

/// `study perf` compares a scene with its exact path whenever the two
/// differ: here a scene whose only approximation is layer merging (the
/// comparison once looked at three settings and timed such a scene against
/// itself), and the line names it.
#[test]
fn study_perf_compares_a_scene_with_any_approximation_against_its_exact_path() {
    let tmp = tempfile::tempdir().unwrap();
    let text = small_dam_scene_text(&repo("schedules/small_dam"));
    let text = if text.contains("[solver]\n") {
        text.replace("[solver]\n", "[solver]\nlayer_merging_age_days = 30\n")
    } else {
        format!("{text}\n[solver]\nlayer_merging_age_days = 30\n")
    };
    let scene = tmp.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let o = bin()
        .args(["study", "perf"])
        .arg(&scene)
        .args(["--days", "200"])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let line = out
        .lines()
        .find(|l| l.contains("fast against exact path"))
        .unwrap_or_else(|| panic!("no exact comparison in\n{out}"));
    assert!(
        line.ends_with("(with solver.layer_merging_age_days = 30)"),
        "{line}"
    );
    assert!(out.contains("scene/exact"), "{out}");
    // the exact path without the layer merging: its apertures differ by
    // far more than the exact accelerations' round-off (measured 0.041 mm
    // over the first 200 days' 32 samples, against 1e-11 mm)
    let mm: f64 = line
        .split("apertures differ by at most ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!(mm > 1e-3, "{line}");
}
