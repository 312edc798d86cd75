//! `groutready study compare` through the binary on two tiny
//! `apertures.csv` files against the demo's grouting schedule
//! (schedules/demo_arch/grouting.csv, epoch 2024-01-01): three zones at
//! their planned dates (joint 6 zone 1 on 2024-05-25, day 145; joint 5
//! zone 1 on 2024-05-27, day 147; joint 11 zone 14 on 2025-09-15, day 623),
//! one of them flipping across the 0.5 mm limit and changing state; and a
//! malformed aperture refused with its file, line and column. No
//! simulation: well under a second.

use std::path::Path;

use crate::common::bin;

const HEADER: &str = "joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa\n";

/// Run A: the three planned zones' deciding points, an upstream row and a
/// weekly row B lacks.
const A: &str = "6,1,min,2024-05-25,145,0.5300,open,14.210,0.0000
6,1,upstream,2024-05-25,145,0.9000,open,15.000,0.0000
5,1,min,2024-05-27,147,0.8000,open,,0.0000
11,14,min,2025-09-15,623,1.5647,open,12.800,0.0000
11,14,min,2025-09-08,616,1.5000,open,12.900,0.0000
";

/// Run B: joint 6 zone 1 below the limit and sticking, joint 11 zone 14
/// 0.1710 mm wider, the upstream row 0.1 mm wider: three shared rows apart
/// by more than 0.05 mm.
const B: &str = "6,1,min,2024-05-25,145,0.4700,stick,14.200,0.1000
6,1,upstream,2024-05-25,145,1.0000,open,15.000,0.0000
5,1,min,2024-05-27,147,0.8000,open,,0.0000
11,14,min,2025-09-15,623,1.7357,open,12.800,0.0000
";

fn write(dir: &Path, name: &str, rows: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, format!("{HEADER}{rows}")).unwrap();
    path
}

#[test]
fn compare_reports_the_planned_dates_and_the_shared_rows() {
    let tmp = tempfile::tempdir().unwrap();
    // A as a run folder (its run.txt naming its approximations), B as the
    // file itself; the demo scene by default
    let a = write(tmp.path(), "a/apertures.csv", A);
    std::fs::write(
        tmp.path().join("a/run.txt"),
        "steps: 3\nmechanics approximations: time.mechanics_max_step_days = 3\n",
    )
    .unwrap();
    let b = write(tmp.path(), "b.csv", B);
    let o = bin()
        .args(["study", "compare"])
        .arg(tmp.path().join("a"))
        .arg(&b)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let rms = ((0.06f64.powi(2) + 0.171f64.powi(2)) / 3.0).sqrt();
    let files = format!(
        "A: {} (mechanics approximations: time.mechanics_max_step_days = 3)\nB: {}\n",
        a.display(),
        b.display()
    );
    assert!(
        stdout.starts_with(&files),
        "{files}not at the start of\n{stdout}"
    );
    for line in [
        "(133 zones in grouting.csv, point min): 3 compared, 130 missing from A, 130 missing from B",
        "largest difference 0.1710 mm at joint 11 zone 14 on 2025-09-15 (A 1.5647 mm, B 1.7357 mm)",
        &format!("RMS {rms:.4} mm"),
        "contact states differing: 1; verdicts differing (aperture >= 0.5000 mm in one run only): 1 (joint 6 zone 1 on 2024-05-25)",
        "4 rows, largest difference 0.1710 mm at joint 11 zone 14 min on 2025-09-15",
        "3 differ by more than 0.0500 mm",
        "rows in one file only: 1 only in A, 0 only in B",
    ] {
        assert!(stdout.contains(line), "{line}\nnot in\n{stdout}");
    }
}

#[test]
fn compare_refuses_a_malformed_aperture_and_a_folder_without_apertures() {
    let tmp = tempfile::tempdir().unwrap();
    let a = write(tmp.path(), "a.csv", A);
    let bad = write(tmp.path(), "bad.csv", &B.replace("0.8000", "0.8 mm"));
    let o = bin()
        .args(["study", "compare"])
        .arg(&a)
        .arg(&bad)
        .arg("models/demo_arch.toml")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    let want = format!(
        "error: {}:4:6 (aperture_mm): expected a number [mm], found \"0.8 mm\"",
        bad.display()
    );
    assert!(stderr.contains(&want), "{stderr}");
    let o = bin()
        .args(["study", "compare"])
        .arg(tmp.path())
        .arg(&a)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no apertures.csv in this folder: expected a run folder"),
        "{stderr}"
    );
}
