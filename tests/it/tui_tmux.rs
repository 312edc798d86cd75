//! `groutready tui` in a real terminal: tmux runs the binary, keys are sent
//! with `send-keys` and the screen read with `capture-pane` — the demo's
//! overview, the detail of a flagged zone, a resize, and a clean exit (the
//! terminal back in cooked mode). Then a scene planned behind the progress
//! screen, and opened at once the second time because its plan is current;
//! and a panic, after which the terminal is restored all the same.
//!
//! tmux is installed by `.ci/run`; without it these tests say so and pass
//! locally, and fail under CI.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common;

/// A tmux server of this test's own (its own socket), killed on drop.
struct Tmux {
    socket: String,
}

impl Tmux {
    fn start(name: &str, cmd: &str, w: u16, h: u16) -> Option<Tmux> {
        if Command::new("tmux").arg("-V").output().is_err() {
            assert!(
                std::env::var_os("CI").is_none(),
                "tmux is missing: .ci/run installs it"
            );
            eprintln!("tmux is not installed: skipping the terminal test");
            return None;
        }
        let t = Tmux {
            socket: format!("groutready-{name}-{}", std::process::id()),
        };
        let ok = t
            .cmd(&[
                "new-session",
                "-d",
                "-s",
                "tui",
                "-x",
                &w.to_string(),
                "-y",
                &h.to_string(),
            ])
            .arg(cmd)
            .env("TERM", "xterm-256color")
            .status()
            .unwrap()
            .success();
        assert!(ok, "tmux new-session failed");
        Some(t)
    }

    fn cmd(&self, args: &[&str]) -> Command {
        let mut c = Command::new("tmux");
        c.args(["-L", &self.socket]).args(args);
        c
    }

    fn keys(&self, keys: &[&str]) {
        for k in keys {
            assert!(self
                .cmd(&["send-keys", "-t", "tui", k])
                .status()
                .unwrap()
                .success());
            // One key at a time, as typed: each is drawn before the next.
            std::thread::sleep(Duration::from_millis(150));
        }
    }

    fn screen(&self) -> String {
        let o = self
            .cmd(&["capture-pane", "-p", "-t", "tui"])
            .output()
            .unwrap();
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    /// Polls the screen until `ok` holds (or panics with the last screen).
    fn wait_for(&self, what: &str, secs: u64, ok: impl Fn(&str) -> bool) -> String {
        let until = Instant::now() + Duration::from_secs(secs);
        loop {
            let s = self.screen();
            if ok(&s) {
                return s;
            }
            assert!(
                Instant::now() < until,
                "waited {secs} s for {what}; the screen:\n{s}"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.cmd(&["kill-server"]).status();
    }
}

/// The shell line tmux runs: the TUI, then its exit code and whether the
/// terminal is back in canonical (cooked) mode.
fn line(args: &str) -> String {
    format!(
        "{} tui {args}; echo \"tui exited $?\"; stty -a | grep -o -- '-*icanon'; sleep 60",
        env!("CARGO_BIN_EXE_groutready")
    )
}

/// After the TUI: cooked mode again (`stty` says `icanon`, not `-icanon`)
/// and the shell's own screen, not the alternate one.
fn assert_terminal_restored(s: &str) {
    assert!(
        s.contains("icanon") && !s.contains("-icanon"),
        "the terminal is left in raw mode:\n{s}"
    );
    assert!(
        !s.contains("1 Overview"),
        "the alternate screen is left:\n{s}"
    );
}

fn quote(p: &Path) -> String {
    format!("'{}'", p.display())
}

#[test]
fn tui_in_tmux_shows_the_demo_a_flagged_zone_and_exits_cleanly() {
    let p = common::demo_plan();
    assert_eq!(p.output.status.code(), Some(0), "{}", p.stderr());
    let Some(t) = Tmux::start("demo", &line(&quote(&p.out)), 80, 24) else {
        return;
    };
    let s = t.wait_for("the overview", 60, |s| s.contains("1 Overview"));
    println!("{s}");
    assert!(
        s.contains("Demo arch dam") && s.contains("as of 2024-08-10"),
        "{s}"
    );
    assert!(s.contains("seen from upstream") && s.contains("left bank → right bank"));
    assert!(s.contains("✗0.64"), "the flagged zone 5 of joint 5: {s}");
    // The flagged list, then Enter on its first zone.
    t.keys(&["2"]);
    let s = t.wait_for("the flagged list", 10, |s| {
        s.contains("Not groutable on the planned date")
    });
    println!("{s}");
    t.keys(&["Enter"]);
    let s = t.wait_for("the zone detail", 10, |s| s.contains("Rules on"));
    println!("{s}");
    assert!(
        s.contains("Joint 5 zone 5") && s.contains("✗ not groutable"),
        "{s}"
    );
    assert!(
        s.contains("✓ aperture") && s.contains("✗ warmer block") && s.contains("delay"),
        "{s}"
    );
    // A resize redraws at the new size.
    assert!(t
        .cmd(&["resize-window", "-t", "tui", "-x", "100", "-y", "30"])
        .status()
        .unwrap()
        .success());
    t.keys(&["1"]);
    let s = t.wait_for("the overview at 100×30", 10, |s| {
        s.lines().count() >= 29 && s.contains("1 Overview")
    });
    assert!(s.lines().any(|l| l.chars().count() > 80), "{s}");
    t.keys(&["q"]);
    let s = t.wait_for("the exit", 10, |s| s.contains("tui exited"));
    assert!(s.contains("tui exited 0"), "{s}");
    assert_terminal_restored(&s);
}

#[test]
fn tui_plans_a_scene_behind_a_progress_screen_then_opens_it_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let args = format!(
        "{} --as-of 2024-05-20 --horizon-days 10 --out {}",
        quote(&common::repo("models/small_dam_joints.toml")),
        quote(&out)
    );
    let Some(t) = Tmux::start("plan", &line(&args), 80, 24) else {
        return;
    };
    let s = t.wait_for("the progress screen", 30, |s| {
        s.contains("planning Small dam")
    });
    println!("{s}");
    let s = t.wait_for("the overview", 180, |s| s.contains("1 Overview"));
    println!("{s}");
    assert!(s.contains("4 of 4 to grout flagged"), "{s}");
    assert!(out.join("restart/plan.bin").is_file());
    t.keys(&["q"]);
    t.wait_for("the exit", 10, |s| s.contains("tui exited 0"));
    drop(t);

    // Same scene, schedules and date: the run folder is opened, not re-planned.
    let t = Tmux::start("again", &line(&args), 80, 24).unwrap();
    let s = t.wait_for("the overview", 20, |s| s.contains("1 Overview"));
    assert!(s.contains("the plan there is up to date"), "{s}");
    assert!(!s.contains("planning Small dam"));
    t.keys(&["q"]);
    t.wait_for("the exit", 10, |s| s.contains("tui exited 0"));
}

#[test]
fn a_panic_in_the_tui_restores_the_terminal() {
    let p = common::small_plan();
    assert_eq!(p.output.status.code(), Some(0), "{}", p.stderr());
    let cmd = format!(
        "{}=1 {}",
        groutready::tui::terminal::PANIC_TEST_VAR,
        line(&quote(&p.out))
    );
    let Some(t) = Tmux::start("panic", &cmd, 80, 24) else {
        return;
    };
    let s = t.wait_for("the exit", 30, |s| s.contains("tui exited"));
    assert!(s.contains("tui exited 101"), "{s}");
    assert!(s.contains("panicking after the first frame"), "{s}");
    assert_terminal_restored(&s);
}

#[test]
fn tui_reports_bad_targets_before_taking_the_terminal() {
    // `groutready tui ARGS` with no input: it must fail with exit 1; its stderr.
    let fails = |args: &[&std::ffi::OsStr]| -> String {
        let o = common::bin()
            .arg("tui")
            .args(args)
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(1), "{err}");
        err
    };
    let tmp = tempfile::tempdir().unwrap();
    let err = fails(&[tmp.path().as_os_str()]);
    assert!(
        err.contains("is not a planned run folder") && err.contains("restart/scene.json"),
        "{err}"
    );
    let p = common::small_plan();
    let err = fails(&[p.out.as_os_str(), "--as-of".as_ref(), "2024-06-01".as_ref()]);
    assert!(err.contains("--as-of applies to a scene"), "{err}");
    // Without a terminal it says so (where the tests themselves have no
    // terminal to take over, as under CI).
    if std::fs::File::open("/dev/tty").is_err() {
        let err = fails(&[p.out.as_os_str()]);
        assert!(err.contains("the terminal UI needs a terminal"), "{err}");
    }
    let err = fails(&["models/no_such_scene.toml".as_ref()]);
    assert!(err.contains("no_such_scene.toml"), "{err}");
}
