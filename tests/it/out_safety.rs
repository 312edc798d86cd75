//! `--out` never destroys what groutready did not write (issue 16, item 1):
//! every data-loss case refused before simulating, the foreign files
//! byte-identical; `--force` where it makes sense; what-ifs kept across
//! plans; the run folder's lock; the leftovers of interrupted runs cleaned;
//! `schedule synth` never overwrites silently.
//!
//! The run cases use `models/two_blocks.toml` (a run of it takes
//! milliseconds) and the plan cases the small dam planned over one day of
//! February (a fraction of a second); refusals simulate nothing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

use groutready::output::lock::Holder;
use groutready::output::run_dir::{MARKER, RUN_FOLDER_NAMES};

use crate::common::{bin, copy_dir, repo};

const RUN_SCENE: &str = "models/two_blocks.toml";
const PLAN_SCENE: &str = "models/small_dam_joints.toml";

/// Every file under `dir` (relative path → bytes); folders end with `/`.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_dir() {
                out.insert(format!("{rel}/"), vec![]);
                walk(root, &p, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `groutready run RUN_SCENE --out OUT` plus `extra`.
fn run(out: &Path, extra: &[&str]) -> Output {
    bin()
        .args(["run", RUN_SCENE, "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// The small dam planned over one day (no zone due: a fraction of a second).
fn plan(out: &Path, extra: &[&str]) -> Output {
    bin()
        .args([
            "plan",
            PLAN_SCENE,
            "--as-of",
            "2024-02-01",
            "--horizon-days",
            "1",
            "--out",
        ])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// Exit 1, a message naming `path` and saying `why`, nothing simulated.
fn assert_refused(o: &Output, path: &Path, why: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("{}: {why}", path.display())),
        "expected `{}: {why}` in:\n{err}",
        path.display()
    );
    assert!(
        o.stdout.is_empty(),
        "nothing may run: {}",
        String::from_utf8_lossy(&o.stdout)
    );
}

fn assert_written(o: &Output, out: &Path) {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
    assert!(
        out.join(MARKER).is_file(),
        "no run folder at {}",
        out.display()
    );
}

/// A folder of the site's documents: three files and a sub-folder.
fn documents(dir: &Path) {
    std::fs::create_dir_all(dir.join("photos")).unwrap();
    std::fs::write(dir.join("minutes.docx"), b"\x50\x4b\x03\x04 minutes").unwrap();
    std::fs::write(dir.join("notes.txt"), "pour 12 delayed\r\n").unwrap();
    std::fs::write(dir.join("survey.csv"), "a,b\n1,2\n").unwrap();
    std::fs::write(dir.join("photos/crest.jpg"), [0xffu8, 0xd8, 0xff, 0]).unwrap();
}

#[test]
fn a_folder_of_other_files_is_refused_by_run_plan_and_tui_and_replaced_only_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let docs = tmp.path().join("mydocs");
    documents(&docs);
    let before = tree(&docs);
    let why = "holds 3 files and 1 folder groutready did not write (minutes.docx, notes.txt, photos/, survey.csv)";
    assert_refused(&run(&docs, &[]), &docs, why);
    assert_refused(&plan(&docs, &[]), &docs, why);
    // The TUI refuses before it takes the terminal over.
    let o = bin()
        .args(["tui", PLAN_SCENE, "--as-of", "2024-02-01", "--out"])
        .arg(&docs)
        .output()
        .unwrap();
    assert_refused(&o, &docs, why);
    assert_eq!(tree(&docs), before, "the documents were touched");
    assert_eq!(names(tmp.path()), ["mydocs"], "nothing next to them either");

    assert_written(&run(&docs, &["--force"]), &docs);
    assert!(!docs.join("notes.txt").exists());
    assert_eq!(names(tmp.path()), ["mydocs"]);
}

#[test]
fn a_run_folder_holding_a_file_of_the_user_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    assert_written(&run(&out, &[]), &out);
    std::fs::write(out.join("notes.txt"), "checked by JB").unwrap();
    let before = tree(&out);
    assert_refused(
        &run(&out, &[]),
        &out,
        "is a run folder, but also holds 1 file groutready did not write (notes.txt)",
    );
    assert_eq!(tree(&out), before);
    assert_written(&run(&out, &["--force"]), &out);
    assert!(!out.join("notes.txt").exists());
}

#[test]
fn a_file_is_refused_and_replaced_only_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let notes = tmp.path().join("notes.txt");
    std::fs::write(&notes, "the site's notes\n").unwrap();
    let why = "is a file, not a folder; give --out a folder, or add --force to replace the file";
    assert_refused(&run(&notes, &[]), &notes, why);
    assert_refused(&plan(&notes, &[]), &notes, why);
    assert_eq!(std::fs::read(&notes).unwrap(), b"the site's notes\n");
    assert_eq!(names(tmp.path()), ["notes.txt"]);

    assert_written(&run(&notes, &["--force"]), &notes);
    assert_eq!(names(tmp.path()), ["notes.txt"], "no leftover of the file");
}

#[test]
fn the_schedules_folder_or_a_folder_containing_it_is_refused_even_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let sched = tmp.path().join("sched");
    copy_dir(&repo("schedules/two_blocks"), &sched);
    let before = tree(tmp.path());
    for force in [&[][..], &["--force"][..]] {
        let args = [&["--schedules", sched.to_str().unwrap()][..], force].concat();
        assert_refused(&run(&sched, &args), &sched, "is the schedules folder");
        assert_refused(
            &run(tmp.path(), &args),
            tmp.path(),
            &format!("contains the schedules folder {}", sched.display()),
        );
    }
    // The bundled scene's own schedules, through its `schedules` key.
    let bundled = repo("schedules/two_blocks");
    let o = run(&bundled, &["--force"]);
    assert_refused(&o, &bundled, "is the schedules folder");
    assert_eq!(tree(tmp.path()), before);
}

#[test]
fn the_current_folder_and_its_parents_are_refused_even_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("site/week");
    std::fs::create_dir_all(&cwd).unwrap();
    std::fs::write(cwd.join("todo.txt"), "grout joint 3").unwrap();
    let before = tree(tmp.path());
    let scene = repo(RUN_SCENE);
    for out in [".", "..", "../week"] {
        for force in [false, true] {
            let mut c = bin();
            c.current_dir(&cwd)
                .arg("run")
                .arg(&scene)
                .args(["--out", out]);
            if force {
                c.arg("--force");
            }
            let o = c.output().unwrap();
            assert_refused(
                &o,
                Path::new(out),
                "is the current folder or one of its parents",
            );
        }
    }
    assert_eq!(tree(tmp.path()), before);
}

/// A folder, and a folder above it, that cannot be written.
#[cfg(unix)]
#[test]
fn a_read_only_folder_is_refused_before_simulating() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let ro = tmp.path().join("readonly");
    std::fs::create_dir_all(&ro).unwrap();
    let old = ro.join("run");
    assert_written(&run(&old, &[]), &old);
    let before = tree(tmp.path());
    let mode = |p: &Path, m: u32| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
    mode(&old, 0o555).unwrap();
    let o1 = run(&old, &[]);
    let o2 = plan(&old, &["--force"]);
    mode(&old, 0o755).unwrap();
    mode(&ro, 0o555).unwrap();
    let o3 = run(&ro.join("new"), &[]);
    let o4 = run(&ro.join("deeper/new"), &[]);
    mode(&ro, 0o755).unwrap();
    let why = |dir: &Path| format!("cannot be written: {} is read-only", dir.display());
    assert_refused(&o1, &old, &why(&old));
    assert_refused(&o2, &old, &why(&old));
    assert_refused(&o3, &ro.join("new"), &why(&ro));
    assert_refused(&o4, &ro.join("deeper/new"), &why(&ro));
    assert_eq!(tree(tmp.path()), before);
}

#[test]
fn a_folder_containing_the_scene_is_refused_even_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    std::fs::create_dir_all(&site).unwrap();
    let text = std::fs::read_to_string(repo(RUN_SCENE)).unwrap().replace(
        "../schedules/two_blocks",
        &repo("schedules/two_blocks").display().to_string(),
    );
    let scene = site.join("dam.toml");
    std::fs::write(&scene, &text).unwrap();
    let before = tree(tmp.path());
    let above = tmp.path().to_path_buf();
    for (out, force) in [(&site, false), (&site, true), (&above, true)] {
        let mut c = bin();
        c.arg("run").arg(&scene).arg("--out").arg(out);
        if force {
            c.arg("--force");
        }
        let o = c.output().unwrap();
        let why = format!("contains the scene {}", scene.display());
        assert_refused(&o, out, &why);
    }
    assert_eq!(tree(tmp.path()), before);
}

#[test]
fn earlier_run_folders_with_or_without_the_marker_are_replaced() {
    let tmp = tempfile::tempdir().unwrap();
    // Written before the marker existed: run.txt with fields/ (run) or
    // restart/ (plan).
    for (name, sub) in [("old_run", "fields"), ("old_plan", "restart")] {
        let out = tmp.path().join(name);
        std::fs::create_dir_all(out.join(sub)).unwrap();
        std::fs::write(out.join("run.txt"), "scene: last week\n").unwrap();
        std::fs::write(out.join("temperatures.csv"), "last week\n").unwrap();
        assert_written(&run(&out, &[]), &out);
        assert_ne!(
            std::fs::read(out.join("run.txt")).unwrap(),
            b"scene: last week\n"
        );
    }
    // An empty folder, and a plan's folder planned again.
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert_written(&plan(&empty, &[]), &empty);
    for name in names(&empty) {
        assert!(
            RUN_FOLDER_NAMES.contains(&name.as_str()),
            "{name} is written but not in RUN_FOLDER_NAMES"
        );
    }
    assert_written(&plan(&empty, &[]), &empty);
    assert_eq!(names(tmp.path()), ["empty", "old_plan", "old_run"]);
}

#[test]
fn saved_what_ifs_survive_the_next_plan_even_when_it_reads_one_of_them() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    assert_written(&plan(&out, &[]), &out);
    // What the TUI saves: a whole schedule set per what-if.
    let saved = out.join("whatif/j2-z1-sc1.00-2024-06-03");
    copy_dir(&repo("schedules/small_dam"), &saved);
    let grouting = std::fs::read_to_string(saved.join("grouting.csv")).unwrap();
    std::fs::write(
        saved.join("grouting.csv"),
        grouting.replace("2,1,2024-05-26", "2,1,2024-06-03"),
    )
    .unwrap();
    let other = out.join("whatif/j3-z1-sc0.50-2024-05-26");
    copy_dir(&repo("schedules/small_dam"), &other);
    let before = tree(&out.join("whatif"));

    // Planned again from the site's schedules: the what-ifs are kept.
    assert_written(&plan(&out, &[]), &out);
    assert_eq!(tree(&out.join("whatif")), before);
    // Planned from one of them, into the folder that holds it.
    let o = plan(&out, &["--schedules", saved.to_str().unwrap()]);
    assert_written(&o, &out);
    assert_eq!(tree(&out.join("whatif")), before);
    let planned = std::fs::read_to_string(out.join("restart/inputs/grouting.csv")).unwrap();
    assert!(planned.contains("2,1,2024-06-03"), "{planned}");
    assert_eq!(names(tmp.path()), ["run"], "no staging or old folder left");
    // A plan's remedied schedules are not a what-if: reading them from the
    // folder the plan replaces is refused.
    let remedied = out.join("remedied");
    copy_dir(&repo("schedules/small_dam"), &remedied);
    let o = plan(&out, &["--schedules", remedied.to_str().unwrap()]);
    assert_refused(
        &o,
        &out,
        &format!("contains the schedules folder {}", remedied.display()),
    );
}

/// A process id that is not running (for a lock or folder left by a killed run).
fn dead_pid() -> u32 {
    (999_999..)
        .find(|p| !Path::new(&format!("/proc/{p}")).exists())
        .unwrap()
}

#[test]
fn a_second_run_while_the_folder_is_locked_is_refused_and_says_who_holds_it() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let lock = tmp.path().join(".run.lock");
    // The lock as a running groutready holds it: the file locked, its
    // holder (this test's process) written in it.
    let me = Holder::me();
    let file = std::fs::File::create(&lock).unwrap();
    file.try_lock().unwrap();
    std::fs::write(&lock, me.to_text()).unwrap();
    let why = format!(
        "is being written by process {} on {} since {} (lock file {})",
        me.pid,
        me.host,
        me.started,
        lock.display()
    );
    assert_refused(&run(&out, &[]), &out, &why);
    assert_refused(&plan(&out, &["--force"]), &out, &why);
    // Released but still naming a live process (a shared drive where the
    // file lock is not seen): still refused.
    drop(file);
    if cfg!(target_os = "linux") {
        assert_refused(&run(&out, &[]), &out, &why);
    }
    assert_eq!(names(tmp.path()), [".run.lock"]);
    assert_eq!(std::fs::read_to_string(&lock).unwrap(), me.to_text());
}

#[cfg(target_os = "linux")]
#[test]
fn a_lock_left_by_a_dead_process_is_taken_over_and_released() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let lock = tmp.path().join(".run.lock");
    let dead = Holder {
        pid: dead_pid(),
        ..Holder::me()
    };
    std::fs::write(&lock, dead.to_text()).unwrap();
    let o = run(&out, &[]);
    assert_written(&o, &out);
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "note: took over the lock {} left by process {} on {}",
            lock.display(),
            dead.pid,
            dead.host
        )) && err.contains("which is not running any more"),
        "{err}"
    );
    assert_eq!(names(tmp.path()), ["run"], "the lock is released");
}

#[cfg(target_os = "linux")]
#[test]
fn leftovers_of_interrupted_runs_are_cleaned_and_said() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    assert_written(&run(&out, &[]), &out);
    let pid = dead_pid();
    let staging = tmp.path().join(format!(".run.staging-{pid}"));
    let old = tmp.path().join(format!(".run.old-{pid}"));
    // A live process's staging folder (this test's) is not touched, nor a
    // leftover of another run folder.
    let live = tmp
        .path()
        .join(format!(".run.staging-{}", std::process::id()));
    let other = tmp.path().join(format!(".other.staging-{pid}"));
    for d in [&staging, &old, &live, &other] {
        std::fs::create_dir_all(d.join("fields")).unwrap();
        std::fs::write(d.join("run.txt"), "half a run").unwrap();
    }
    let o = run(&out, &[]);
    assert_written(&o, &out);
    let err = stderr(&o);
    for (d, what) in [(&staging, "unfinished run"), (&old, "old run folder")] {
        let note = format!(
            "note: removed {} (the {what} of process {pid}, no longer running)",
            d.display()
        );
        assert!(err.contains(&note), "expected `{note}` in:\n{err}");
    }
    let mut want = vec![
        format!(".other.staging-{pid}"),
        format!(".run.staging-{}", std::process::id()),
        "run".to_string(),
    ];
    want.sort();
    assert_eq!(names(tmp.path()), want);
}

/// Stopped between its two renames, a run leaves the previous run folder as
/// `.NAME.old-PID` and no run folder: the next run puts it back first (its
/// what-ifs are carried over), never deletes it.
#[cfg(target_os = "linux")]
#[test]
fn an_old_folder_without_its_run_folder_is_put_back_not_deleted() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    assert_written(&run(&out, &[]), &out);
    let saved = out.join("whatif/j1-z1-sc1.00-2024-03-01");
    copy_dir(&repo("schedules/two_blocks"), &saved);
    let before = tree(&out.join("whatif"));
    let pid = dead_pid();
    let old = tmp.path().join(format!(".run.old-{pid}"));
    std::fs::rename(&out, &old).unwrap();
    let o = run(&out, &[]);
    assert_written(&o, &out);
    let note = format!("note: put back {} from {}", out.display(), old.display());
    assert!(stderr(&o).contains(&note), "{}", stderr(&o));
    assert_eq!(tree(&out.join("whatif")), before);
    assert_eq!(names(tmp.path()), ["run"]);
}

fn synth(out: &Path, force: bool) -> Output {
    let mut c = bin();
    c.args(["schedule", "synth", RUN_SCENE, "--out"]).arg(out);
    if force {
        c.arg("--force");
    }
    c.output().unwrap()
}

#[test]
fn schedule_synth_refuses_existing_schedules_unless_forced() {
    let tmp = tempfile::tempdir().unwrap();
    let sched: PathBuf = tmp.path().join("sched");
    let o = synth(&sched, false);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The site edits its schedule.
    std::fs::write(
        sched.join("pours.csv"),
        "block,lift,pour_date\n1,1,2024-02-01\n",
    )
    .unwrap();
    let before = tree(&sched);
    let o = synth(&sched, false);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "{}: already holds pours.csv, cooling.csv, grouting.csv; schedule synth would overwrite them",
            sched.display()
        )),
        "{err}"
    );
    assert_eq!(tree(&sched), before);

    let o = synth(&sched, true);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let pours = std::fs::read_to_string(sched.join("pours.csv")).unwrap();
    assert!(pours.lines().count() > 2, "{pours}");
}
