//! A run is bit-reproducible for a given build and thread count
//! (docs/ARCHITECTURE.md, "Reproducibility"): the small dam with joints and
//! friction, shortened to a few days after its first groutings (stick, slip,
//! grouted and open labels all occur), run twice in this process and twice
//! as separate `groutready run` processes.
//!
//! An iteration over a `HashMap` shows in both pairs: every process draws
//! fresh random hash keys, and within a process every map gets keys of its
//! own. The separate processes also cover whatever a process sets up once.
//! The CSVs round to 0.1 µm and 1 mK, so the snapshot (full-precision binary
//! fields) is compared too.

use std::path::{Path, PathBuf};

use groutready::app::{self, Inputs};
use groutready::mechanics::BirthsPlacement;
use groutready::sim::{History, RunStats, Simulation};
use groutready::vocab::JointState;

use crate::common::{bin, repo};

/// Last day of the shortened runs: a few days after the first groutings
/// (2024-05-26..28), so that grouted, stick and slip points exist.
const END_DATE: &str = "2024-06-01";
/// The snapshot date of the shortened runs.
const SNAPSHOT_DATE: &str = "2024-05-31";

fn inputs() -> Inputs {
    app::load_inputs(&repo("models/small_dam_joints.toml"), None).unwrap()
}

/// One in-process run to [`END_DATE`], set up by `setup`: its histories,
/// the histories and the final state serialised (postcard writes every f64
/// as its bits, and a NaN of a point not yet poured equals itself there),
/// and its counters.
fn run_in_process(
    inputs: &Inputs,
    setup: impl FnOnce(&mut Simulation),
) -> (History, Vec<u8>, RunStats) {
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
    setup(&mut sim);
    let end = inputs.scene.epoch.day(END_DATE.parse().unwrap());
    sim.set_end_day(end);
    let stats = sim.run(None, &mut |_, _| {}).unwrap();
    let bits = postcard::to_stdvec(&(sim.history(), sim.checkpoint(), &sim.checkpoints)).unwrap();
    (sim.history(), bits, stats)
}

/// Asserts that two runs' bits are the same; `what` names the two in the
/// message, which says how far their histories are apart.
fn assert_same_bits(
    a: &(History, Vec<u8>, RunStats),
    b: &(History, Vec<u8>, RunStats),
    what: &str,
) {
    let (labels, total, da, dt) = differences(&a.0, &b.0);
    assert!(
        a.1 == b.1,
        "{what} differ: {labels} of {total} labels, apertures by {da:.3e} m, \
         zone temperatures by {dt:.3e} °C"
    );
}

/// The labels that differ, the largest aperture difference [m] and the
/// largest zone-point temperature difference [°C] between two histories of
/// the same run: what a failure reports.
fn differences(a: &History, b: &History) -> (usize, usize, f64, f64) {
    let (mut labels, mut total, mut aperture, mut temperature) = (0, 0, 0.0f64, 0.0f64);
    for (ra, rb) in a.joint_records.rows.iter().zip(&b.joint_records.rows) {
        for (sa, sb) in ra.1.iter().zip(&rb.1) {
            if let (Some(sa), Some(sb)) = (sa, sb) {
                total += 1;
                labels += usize::from(sa.state != sb.state);
                aperture = aperture.max((sa.aperture - sb.aperture).abs());
            }
        }
    }
    for (ra, rb) in a.records.rows.iter().zip(&b.records.rows) {
        for (ta, tb) in ra.1.iter().zip(&rb.1) {
            if ta.is_finite() && tb.is_finite() {
                temperature = temperature.max((ta - tb).abs());
            }
        }
    }
    (labels, total, aperture, temperature)
}

/// Two runs in one process, side by side, give the same bits: histories
/// (apertures, labels, temperatures) and the final state.
#[test]
fn reproducible_in_one_process() {
    let inputs = inputs();
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| run_in_process(&inputs, |_| {}));
        let b = run_in_process(&inputs, |_| {});
        (a.join().unwrap(), b)
    });
    let states: Vec<JointState> =
        a.0.joint_records
            .rows
            .iter()
            .flat_map(|r| r.1.iter().flatten().map(|s| s.state))
            .collect();
    for s in [JointState::Stick, JointState::Slip, JointState::Grouted] {
        assert!(
            states.contains(&s),
            "no {s:?} point: the test misses friction"
        );
    }
    assert_same_bits(&a, &b, "two runs");
}

/// The next live set analysed on a thread of its own or on the step's
/// thread (where `BirthsPlacement::Balanced` puts it, by the waits) gives
/// the same bits, and both analyse live sets ahead.
#[test]
fn the_next_live_set_is_the_same_on_either_thread() {
    let inputs = inputs();
    let run = |placement| {
        run_in_process(&inputs, |sim| {
            sim.mechanics
                .as_mut()
                .unwrap()
                .set_births_placement(placement)
        })
    };
    let (a, b) = (run(BirthsPlacement::Thread), run(BirthsPlacement::Step));
    let ahead = |r: &(History, Vec<u8>, RunStats)| r.2.mechanics.unwrap().ahead.on_new_systems;
    assert!(
        ahead(&a) > 0 && ahead(&a) == ahead(&b),
        "live sets analysed ahead: {} on threads, {} on the step's",
        ahead(&a),
        ahead(&b)
    );
    assert_same_bits(&a, &b, "the placements");
}

/// The coming pour days' live systems analysed ahead on threads of their
/// own (the default) or when their steps are ordered give the same bits;
/// every analysis made ahead is taken by its pour day, but the last, held
/// for a pour day after the shortened run's end.
#[test]
fn live_systems_analysed_ahead_change_no_bit() {
    let inputs = inputs();
    let run = |on| {
        run_in_process(&inputs, |sim| {
            sim.mechanics.as_mut().unwrap().set_pours_ahead(on)
        })
    };
    let (a, b) = (run(true), run(false));
    let ahead = |r: &(History, Vec<u8>, RunStats)| r.2.mechanics.unwrap().pours_ahead;
    let (on, off) = (ahead(&a), ahead(&b));
    assert!(
        on.started > 1 && on.used + 1 == on.started && on.discarded == 0,
        "analysed ahead: {on:?}"
    );
    assert_eq!(off.started, 0, "analysed ahead when off: {off:?}");
    assert_eq!(
        a.2.mechanics.unwrap().symbolic,
        b.2.mechanics.unwrap().symbolic,
        "live systems analysed"
    );
    assert_same_bits(&a, &b, "analysed ahead and not");
}

/// The thermal steps run beside the mechanical steps (the default) or in
/// order on the run's thread give the same bits, and the same checkpoints:
/// a checkpoint day runs beside too, its thermal half taken before the
/// day's events and its mechanical half after the join (every third day
/// here, so that checkpoint days with pours and groutings occur).
#[test]
fn the_thermal_steps_beside_the_mechanics_change_no_bit() {
    let inputs = inputs();
    let run = |beside| {
        run_in_process(&inputs, |sim| {
            sim.set_thermal_beside(beside);
            sim.checkpoint_every = Some(3);
        })
    };
    let (a, b) = (run(true), run(false));
    let (beside_on, beside_off) = (a.2.mechanical_steps_beside, b.2.mechanical_steps_beside);
    assert!(
        beside_on > 0 && beside_off == 0,
        "mechanical steps beside the thermal steps: {beside_on} when on, {beside_off} when off"
    );
    // every step but the last (none follows it) and those of snapshot days
    let snapshot_days = inputs.scene.output.snapshots.len();
    let steps = a.2.mechanics.as_ref().unwrap().steps;
    assert!(
        beside_on + 1 + snapshot_days >= steps,
        "{beside_on} of {steps} mechanical steps ran beside (checkpoint days in order?)"
    );
    assert_eq!(a.2.steps, b.2.steps, "thermal steps");
    assert_same_bits(&a, &b, "beside and in order");
}

/// Mechanical steps that may span several days (`mechanics_max_step_days
/// = 3`), with pours ending them and merged into them
/// (`mechanics_merge_pours`), and groutings merged as well
/// (`mechanics_merge_groutings`: a zone grouted inside a step changes the
/// states the factor made ahead guessed, a change its correction takes),
/// are factorised ahead on the second core too (the next step's end
/// foreseen from the days with events, and the lifts born inside it), with the answer of a run that factorises each step on
/// its own thread to round-off (a factor made ahead starts from the step
/// before's states, corrected exactly, so the bits may differ as for steps
/// of a day): the same labels, the apertures within 1e-12 m, the
/// temperatures to the bit; and with checkpoints every 10 days, every
/// step's end foreseen (no factor made ahead is discarded), and the
/// first later step that pours (no live set analysed ahead is discarded).
#[test]
fn longer_mechanical_steps_factorised_ahead_agree_to_round_off() {
    // not a multiple of 3: checkpoints end steps the events do not
    const CHECKPOINT_DAYS: i64 = 10;
    let mut inputs = inputs();
    inputs.scene.time.mechanics_max_step_days = 3;
    for (merge_pours, merge_groutings) in [(false, false), (true, false), (true, true)] {
        inputs.scene.time.mechanics_merge_pours = merge_pours;
        inputs.scene.time.mechanics_merge_groutings = merge_groutings;
        let merged = format!("pours merged {merge_pours}, groutings {merge_groutings}");
        let run = |ahead| {
            run_in_process(&inputs, |sim| {
                sim.set_factor_ahead(ahead);
                sim.checkpoint_every = Some(CHECKPOINT_DAYS);
            })
        };
        let (a, b) = (run(true), run(false));
        let (ma, mb) = (a.2.mechanics.unwrap(), b.2.mechanics.unwrap());
        let days = inputs.scene.epoch.day(END_DATE.parse().unwrap()).t() as usize;
        eprintln!(
            "{merged}: {} mechanical steps over {days} days; ahead: {} made \
             ({} on a live set of its own), {} used, {} discarded; live sets analysed ahead: \
             {} started, {} used, {} discarded",
            ma.steps,
            ma.ahead.made,
            ma.ahead.on_new_systems,
            ma.ahead.used,
            ma.ahead.discarded,
            ma.pours_ahead.started,
            ma.pours_ahead.used,
            ma.pours_ahead.discarded
        );
        assert!(ma.steps < days, "no step spanned several days");
        assert!(
            ma.ahead.used > ma.steps / 2 && mb.ahead.made == 0,
            "factorised ahead: {} of {} steps",
            ma.ahead.used,
            ma.steps
        );
        assert!(
            ma.ahead.on_new_systems > 0,
            "steps whose lifts are born in them are factorised ahead too"
        );
        // each step's end foreseen: past a longer thermal step, at a checkpoint
        assert_eq!(ma.ahead.discarded, 0, "factors made ahead for another step");
        // and the steps after it walked alike to the first that pours
        assert!(ma.pours_ahead.started > 0, "live sets analysed ahead");
        assert_eq!(
            ma.pours_ahead.discarded, 0,
            "live sets analysed ahead for another step"
        );
        assert_eq!(ma.steps, mb.steps, "mechanical steps");
        let (labels, total, aperture, temperature) = differences(&a.0, &b.0);
        assert!(
            labels == 0 && aperture <= 1e-12 && temperature == 0.0,
            "{merged}, ahead and not: {labels} of {total} labels, \
             apertures by {aperture:.3e} m, temperatures by {temperature:.3e} °C"
        );
    }
}

/// A run stopped at a midnight whose mechanical step ran beside the next
/// day's thermal steps shows its stop rule the run as it stands at that
/// midnight (the thermal model not yet stepped on), and goes on from there
/// to the bits of a run never stopped.
#[test]
fn a_run_stopped_beside_a_mechanical_step_goes_on_to_the_same_bits() {
    let inputs = inputs();
    let epoch = inputs.scene.epoch;
    let end = epoch.day(END_DATE.parse().unwrap());
    let stop_at = epoch.day("2024-05-26".parse().unwrap());
    // what the stop rule sees at `stop_at`: the day, the thermal steps so
    // far and the temperature bits, then the whole run's bits
    let run = |beside: bool, stop: bool| {
        let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
        sim.set_thermal_beside(beside);
        sim.set_end_day(end);
        let mut seen = None;
        let mut rule = |day: groutready::vocab::Day, s: &Simulation| {
            if day == stop_at {
                let th = s.thermal.as_ref().unwrap();
                seen = Some((s.day, postcard::to_stdvec(&th.state).unwrap()));
                return stop;
            }
            false
        };
        let first = sim.run_until(None, &mut |_, _| {}, &mut rule).unwrap();
        let mut beside_steps = first.mechanical_steps_beside;
        if stop {
            assert_eq!(sim.day, stop_at.t(), "the run stops at the rule's day");
            beside_steps = sim
                .run(None, &mut |_, _| {})
                .unwrap()
                .mechanical_steps_beside;
        }
        let bits = postcard::to_stdvec(&(sim.history(), sim.checkpoint())).unwrap();
        (seen.unwrap(), bits, beside_steps)
    };
    let stopped = run(true, true);
    let in_order = run(false, false);
    assert!(stopped.2 > 0, "no mechanical step ran beside");
    assert!(
        stopped.0 == in_order.0,
        "the stop rule saw day {} and another thermal state than the run in order (day {})",
        stopped.0 .0,
        in_order.0 .0
    );
    assert!(
        stopped.1 == in_order.1,
        "the run stopped and gone on differs from the run in order"
    );
}

/// The small dam scene shortened to [`END_DATE`] with a snapshot on
/// [`SNAPSHOT_DATE`], written into `dir`.
fn short_scene(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo("models/small_dam_joints.toml")).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with("snapshots =") {
            out.push_str(&format!("snapshots = [{SNAPSHOT_DATE}]\n"));
            continue;
        }
        out.push_str(line);
        out.push('\n');
        if line == "[time]" {
            out.push_str(&format!("end_date = {END_DATE}\n"));
        }
    }
    let path = dir.join("short.toml");
    std::fs::write(&path, out).unwrap();
    path
}

/// Every file of a run folder but `run.txt` (it holds the wall time), by
/// relative path.
fn run_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for rel in ["apertures.csv", "temperatures.csv"] {
        files.push((rel.to_string(), std::fs::read(dir.join(rel)).unwrap()));
    }
    let mut fields: Vec<_> = std::fs::read_dir(dir.join("fields"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    fields.sort();
    for p in fields {
        let rel = format!("fields/{}", p.file_name().unwrap().to_string_lossy());
        files.push((rel, std::fs::read(&p).unwrap()));
    }
    files
}

/// Two `groutready run` processes (each with its own hasher seeds, running
/// at the same time) write the same bytes.
#[test]
fn reproducible_across_processes() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = short_scene(tmp.path());
    let outs = [tmp.path().join("A"), tmp.path().join("B")];
    let children: Vec<_> = outs
        .iter()
        .map(|out| {
            bin()
                .arg("run")
                .arg(&scene)
                .arg("--schedules")
                .arg(repo("schedules/small_dam"))
                .arg("--out")
                .arg(out)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        let o = child.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let (a, b) = (run_files(&outs[0]), run_files(&outs[1]));
    assert_eq!(
        a.len(),
        4,
        "apertures, temperatures, the pvd and one snapshot"
    );
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    let differing: Vec<String> = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.1 != y.1)
        .map(|(x, y)| {
            let at = x.1.iter().zip(&y.1).position(|(p, q)| p != q);
            format!("{} (first differing byte {at:?})", x.0)
        })
        .collect();
    assert!(
        differing.is_empty(),
        "the two runs wrote different files: {differing:?}"
    );
}
