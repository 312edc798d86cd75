//! `groutready study accuracy` on a tiny ladder: the small dam with joints,
//! judged on its first zones (planned within 150 days, 4 zones), the scene as
//! given, a copy of the reference and thermal steps twice as long, against
//! a reference with half the steps. Checks what the table promises: the
//! reference and its copy have error 0 to the last bit (the runs are
//! deterministic), the coarser setting does not, the three files are
//! written and list every setting. The presets: a preset's `[time]` values
//! and an explicit key beating its preset.

use groutready::scene::{CapacityKind, Preset, Scene};
use groutready::study::accuracy::{self, Reference, Setting, REFERENCE, SCENE};

use crate::common::repo;

fn half_steps(s: &mut Scene) {
    s.time.first_step_days *= 0.5;
    s.time.max_step_days *= 0.5;
}

#[test]
fn tiny_ladder_against_its_reference() {
    let ladder = vec![
        Setting::new("scene as given", SCENE, Some(1.0), |_| {}),
        // The reference's own edit, as the finest level of the steps chain.
        Setting::new("copy of the reference", "steps", Some(0.5), half_steps),
        Setting::new("steps x2", "steps", Some(2.0), |s| {
            s.time.first_step_days *= 2.0;
            s.time.max_step_days *= 2.0;
        }),
    ];
    let reference = Reference {
        setting: Setting::new("reference", REFERENCE, None, half_steps),
        levels: vec![("steps".into(), 0.5)],
    };
    let scene = repo("models/small_dam_joints.toml");
    let cache = tempfile::tempdir().unwrap();
    let kept = cache.path().join("reference.bin");
    let table = accuracy::study(
        &scene,
        ladder,
        reference,
        Some(150),
        Some(&kept),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(table.zones, 4);
    let row = |name: &str| table.rows.iter().find(|r| r.name == name).unwrap();
    for name in ["reference", "copy of the reference"] {
        let r = row(name);
        assert_eq!(r.max_aperture_err_mm, 0.0, "{name}");
        assert_eq!(r.max_point_err_mm, 0.0, "{name}");
        assert_eq!(r.max_temp_err_c, 0.0, "{name}");
        assert_eq!(r.verdicts_differ, 0, "{name}");
    }
    let coarse = row("steps x2");
    assert!(coarse.max_aperture_err_mm > 0.0, "{coarse:?}");
    assert!(coarse.max_temp_err_c > 0.0, "{coarse:?}");
    assert!(coarse.rms_aperture_err_mm <= coarse.max_aperture_err_mm);
    // The steps chain has two differences (h = 2 → 1 → 0.5 with the scene as
    // given at h = 1): a fitted rate, and a Richardson estimate > 0.
    assert!(coarse.rate.is_some(), "{coarse:?}");
    assert!(table.reference_error_mm > 0.0, "{}", table.reference_note);
    // The reference and its copy have error 0: the faster of the two is on
    // the front; the coarser setting is on it exactly when no setting is
    // both as fast and as accurate (wall times vary with the machine's
    // load, so the scene as given may be the one that beats it).
    let (r, c) = (row("reference"), row("copy of the reference"));
    let exact = if r.seconds <= c.seconds { r } else { c };
    assert!(exact.pareto, "{exact:?}");
    let beaten = table.rows.iter().any(|o| {
        o.seconds <= coarse.seconds
            && o.max_aperture_err_mm <= coarse.max_aperture_err_mm
            && (o.seconds < coarse.seconds || o.max_aperture_err_mm < coarse.max_aperture_err_mm)
    });
    assert_eq!(coarse.pareto, !beaten, "{:?}", table.rows);
    assert!(!coarse.pareto || coarse.seconds < exact.seconds);
    // The zones beyond the reference's band are among those that differ.
    assert!(table
        .rows
        .iter()
        .all(|r| r.verdicts_beyond_band <= r.verdicts_differ));

    let out = tempfile::tempdir().unwrap();
    accuracy::write(&table, out.path()).unwrap();
    for f in ["accuracy.csv", "accuracy.md", "accuracy.svg"] {
        let text = std::fs::read_to_string(out.path().join(f)).unwrap();
        for r in &table.rows {
            assert!(text.contains(&r.name), "{f} lacks {}", r.name);
        }
    }
    let csv = std::fs::read_to_string(out.path().join("accuracy.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + table.rows.len());
    // Per zone: every setting's reading of the 4 zones; the reference's
    // copy reads what the reference reads, the coarser setting does not.
    let zones = std::fs::read_to_string(out.path().join("accuracy_zones.csv")).unwrap();
    assert_eq!(zones.lines().count(), 1 + 4 * table.rows.len());
    let readings = |name: &str| -> Vec<String> {
        zones
            .lines()
            .filter(|l| l.starts_with(&format!("{name},")))
            .map(|l| l[name.len()..].to_string())
            .collect()
    };
    assert_eq!(readings("reference"), readings("copy of the reference"));
    assert_ne!(readings("reference"), readings("steps x2"));

    // The reference was kept: the same study again reads it (its row to
    // the bit, wall time included) instead of running it; another
    // reference edit runs.
    let again = |edit: fn(&mut Scene)| {
        let mut lines = vec![];
        let t = accuracy::study(
            &scene,
            vec![Setting::new("scene as given", SCENE, Some(1.0), |_| {})],
            Reference {
                setting: Setting::new("reference", REFERENCE, None, edit),
                levels: vec![("steps".into(), 0.5)],
            },
            Some(150),
            Some(&kept),
            &mut |l| lines.push(l.to_string()),
        )
        .unwrap();
        (t, lines.join("\n"))
    };
    let (t2, said) = again(half_steps);
    assert!(said.contains("read from"), "{said}");
    // (its place on the front depends on the ladder it is in)
    let kept_row = accuracy::Row {
        pareto: row("reference").pareto,
        ..t2.rows[0].clone()
    };
    assert_eq!(kept_row, *row("reference"));
    let (a, b) = (&t2.rows[1], row("scene as given"));
    assert_eq!(
        (a.max_aperture_err_mm, a.max_temp_err_c, a.verdicts_differ),
        (b.max_aperture_err_mm, b.max_temp_err_c, b.verdicts_differ)
    );
    let (_, said) = again(|s| {
        s.time.first_step_days *= 0.25;
        s.time.max_step_days *= 0.25;
    });
    assert!(!said.contains("read from"), "{said}");
}

/// `--knobs` cuts the ladder to the named knobs; a name the ladder lacks
/// is an error listing the ladder's knobs (before anything is simulated).
#[test]
fn unknown_knob_lists_the_ladders_knobs() {
    let scene = repo("models/small_dam_joints.toml");
    let out = tempfile::tempdir().unwrap();
    let options = accuracy::AccuracyOptions {
        knobs: vec!["across".into(), "acros".into()],
        ..Default::default()
    };
    let e = accuracy::accuracy(&scene, out.path(), &options, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown knob `acros`"), "{e}");
    for k in ["steps", "capacity", "across", "along", "preset"] {
        assert!(e.contains(k), "{e}");
    }
    assert!(std::fs::read_dir(out.path()).unwrap().next().is_none());
}

/// The small dam's text with its `[time]` keys `drop` removed and `solver`
/// appended.
fn small_dam_text(drop: &[&str], solver: &str) -> String {
    let text = std::fs::read_to_string(repo("models/small_dam_joints.toml")).unwrap();
    let mut kept: String = text
        .lines()
        .filter(|l| !drop.iter().any(|k| l.starts_with(&format!("{k} ="))))
        .map(|l| format!("{l}\n"))
        .collect();
    kept += solver;
    kept
}

#[test]
fn preset_sets_the_keys_not_written() {
    let text = small_dam_text(
        &["first_step_days", "capacity"],
        "\n[solver]\npreset = \"reference\"\n",
    );
    let s = Scene::from_toml_str(&text, "small.toml").unwrap();
    let want = Preset::Reference.time();
    assert_eq!(s.time.first_step_days, want.first_step_days);
    assert_eq!(s.time.step_schedule, want.step_schedule);
    assert_eq!(s.time.capacity, CapacityKind::Consistent);
    // Written in the scene: the scene's value, not the preset's (1 d).
    assert_eq!(s.time.max_step_days, 4.0);
    assert_ne!(want.max_step_days, 4.0);
}

#[test]
fn bad_step_schedule_names_the_key_and_line() {
    let text = small_dam_text(
        &[],
        "",
    )
    .replace(
        "[time]\n",
        "[time]\nstep_schedule = [{ step_days = 0.1, until_days = 2 }, { step_days = 0.25, until_days = 1 }]\n",
    );
    let e = Scene::from_toml_str(&text, "small.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("small.toml"), "{e}");
    assert!(e.contains("time.step_schedule entry 2"), "{e}");
    assert!(e.contains("until_days > 2"), "{e}");
}
