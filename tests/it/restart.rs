//! A restarted run equals an uninterrupted one (DESIGN.md §7): the small dam
//! with every effect (thermal, pipes, creep, self-weight, joints), with the
//! same schedules and with schedules edited after the checkpoint, in memory
//! and through a checkpoint file.

use std::path::Path;

use groutready::app::{self, Inputs};
use groutready::planner::edit;
use groutready::schedule::Schedules;
use groutready::sim::checkpoint::{read_file, write_file};
use groutready::sim::{Checkpoint, History, Simulation};
use groutready::vocab::{Day, ZoneId};

const END: Day = Day(200);

fn inputs() -> Inputs {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    app::load_inputs(&root.join("models/small_dam_joints.toml"), None).unwrap()
}

fn run(
    inputs: &Inputs,
    s: &Schedules,
    restart: Option<(&Checkpoint, &History)>,
) -> Simulation<'static> {
    // Leaked so the simulation may outlive this helper's borrows.
    let scene = Box::leak(Box::new(inputs.scene.clone()));
    let mesh = Box::leak(Box::new(inputs.mesh.clone()));
    let mut sim = Simulation::new(scene, mesh, s).unwrap();
    sim.set_end_day(END);
    sim.checkpoint_every = Some(30);
    if let Some((ck, h)) = restart {
        sim.restore(ck, h);
    }
    sim.run(None, &mut |_, _| {}).unwrap();
    sim
}

/// Largest aperture difference relative to the widest aperture on the days
/// both histories hold, number of such days, and the number of differing
/// labels; and the largest temperature difference [°C].
fn compare(a: &History, b: &History, from: Day) -> (f64, usize, usize, f64) {
    let widest = a
        .joint_records
        .rows
        .iter()
        .flat_map(|r| r.1.iter().flatten().map(|s| s.aperture.abs()))
        .fold(0.0, f64::max);
    assert!(
        widest > 1e-4,
        "the joints must open in this test ({widest} m)"
    );
    let (mut diff, mut days, mut labels) = (0.0f64, 0, 0);
    for ra in &a.joint_records.rows {
        let Some(rb) = b.joint_records.rows.iter().find(|r| r.0 == ra.0) else {
            continue;
        };
        if ra.0 < from {
            continue;
        }
        days += 1;
        for (x, y) in ra.1.iter().zip(&rb.1) {
            match (x, y) {
                (Some(x), Some(y)) => {
                    diff = diff.max((x.aperture - y.aperture).abs() / widest);
                    labels += usize::from(x.state != y.state);
                }
                (None, None) => {}
                _ => labels += 1,
            }
        }
    }
    let mut dt = 0.0f64;
    for ra in &a.records.rows {
        let Some(rb) = b.records.rows.iter().find(|r| r.0 == ra.0) else {
            continue;
        };
        for (x, y) in ra.1.iter().zip(&rb.1) {
            if x.is_finite() || y.is_finite() {
                dt = dt.max((x - y).abs());
            }
        }
    }
    (diff, days, labels, dt)
}

#[test]
fn restart_with_the_same_schedules_repeats_the_run() {
    let inputs = inputs();
    let a = run(&inputs, &inputs.schedules, None);
    assert!(
        a.checkpoints.len() >= 5,
        "{} checkpoints",
        a.checkpoints.len()
    );
    let ck = a
        .checkpoints
        .iter()
        .find(|c| c.day >= Day(90))
        .unwrap()
        .clone();
    // Through a file, as the weekly update reads it.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ck.bin");
    write_file(&path, &ck, "checkpoint").unwrap();
    let back: Checkpoint = read_file(&path).unwrap();
    // (bytes, not ==: unborn elements carry NaN birth days)
    let bytes = |c: &Checkpoint| postcard::to_stdvec(c).unwrap();
    assert!(bytes(&back) == bytes(&ck), "checkpoint file round trip");
    let hpath = dir.path().join("history.bin");
    write_file(&hpath, &a.history(), "history").unwrap();
    let h: History = read_file(&hpath).unwrap();
    assert!(postcard::to_stdvec(&h).unwrap() == postcard::to_stdvec(&a.history()).unwrap());

    let b = run(&inputs, &inputs.schedules, Some((&back, &h)));
    let (diff, days, labels, dt) = compare(&a.history(), &b.history(), ck.day);
    println!("same schedules, restart at {}: {days} days compared, aperture diff {diff:e}, {labels} labels, temperature diff {dt:e} °C", ck.day);
    assert!(days > 50);
    assert_eq!(
        a.history().joint_records.rows.len(),
        b.history().joint_records.rows.len()
    );
    assert!(diff <= 1e-9, "relative aperture difference {diff:e}");
    assert_eq!(labels, 0);
    assert!(dt <= 1e-9);
}

#[test]
fn restart_before_an_edit_equals_the_edited_run_from_scratch() {
    let inputs = inputs();
    let base = run(&inputs, &inputs.schedules, None);
    // Supercool zone 3 of joint 2 by 2 °C and move the grouting of zone 2 of
    // joint 3 ten days later: the weekly update of a site.
    let g = inputs
        .schedules
        .grouting_of(ZoneId::new(3, 2))
        .unwrap()
        .planned;
    let z = inputs
        .schedules
        .grouting_of(ZoneId::new(2, 3))
        .unwrap()
        .planned;
    let layout = app::dam_layout(&inputs.mesh);
    let (cooled, missing) = edit::supercool(
        &inputs.schedules,
        &layout,
        &[edit::Supercool {
            zone: ZoneId::new(2, 3),
            delta_c: 2.0,
            planned: z,
            from: inputs.scene.epoch.date(Day(100)),
        }],
        3,
    );
    assert!(missing.is_empty());
    let edited = edit::regrout(
        &cooled,
        &[(ZoneId::new(3, 2), g + chrono::Duration::days(10))],
    );
    groutready::schedule::validate(&edited).unwrap();
    let first = edit::first_change(&inputs.schedules, &edited).unwrap();
    let first_day = inputs.scene.epoch.day(first);
    let ck = base
        .checkpoints
        .iter()
        .rev()
        .find(|c| c.day <= first_day)
        .expect("a checkpoint before the edit")
        .clone();
    assert!(ck.day > Day(0));

    let scratch = run(&inputs, &edited, None);
    let restarted = run(&inputs, &edited, Some((&ck, &base.history())));
    let (diff, days, labels, dt) = compare(&scratch.history(), &restarted.history(), ck.day);
    println!("edited on {first}, restart at {}: {days} days compared, aperture diff {diff:e}, {labels} labels, temperature diff {dt:e} °C", ck.day);
    assert!(diff <= 1e-9, "relative aperture difference {diff:e}");
    assert_eq!(labels, 0);
    assert!(dt <= 1e-9);
    // ...and the edit did change the run (the comparison is not vacuous).
    let (changed, ..) = compare(&base.history(), &scratch.history(), ck.day);
    assert!(
        changed > 1e-3,
        "the edit changed apertures by only {changed:e}"
    );
}

/// Supercooling a running stage splits its row at the as-of date into a
/// row continuing it with colder water (issue 15). The schedules first
/// differ on that date, not at the stage's start, and a run restarted from
/// the checkpoint before it equals the edited run from scratch.
#[test]
fn a_water_change_inside_a_running_stage_restarts_at_its_date() {
    let inputs = inputs();
    let base = run(&inputs, &inputs.schedules, None);
    let zone = ZoneId::new(2, 2);
    let planned = inputs.schedules.grouting_of(zone).unwrap().planned;
    let from = inputs.scene.epoch.date(Day(150));
    let layout = app::dam_layout(&inputs.mesh);
    let (edited, missing) = edit::supercool(
        &inputs.schedules,
        &layout,
        &[edit::Supercool {
            zone,
            delta_c: 2.0,
            planned,
            from,
        }],
        0,
    );
    assert!(missing.is_empty());
    groutready::schedule::validate(&edited).unwrap();
    // The zone's second stages were running on day 150: each is now two rows.
    let continued = edited
        .cooling
        .iter()
        .filter(|c| edited.cooling.iter().any(|a| a.continued_by(c)))
        .count();
    assert!(continued >= 2, "{continued} rows continue a stage");
    assert_eq!(edit::first_change(&inputs.schedules, &edited), Some(from));
    let ck = base
        .checkpoints
        .iter()
        .rev()
        .find(|c| c.day <= Day(150))
        .expect("a checkpoint before the edit")
        .clone();
    let scratch = run(&inputs, &edited, None);
    let restarted = run(&inputs, &edited, Some((&ck, &base.history())));
    let (diff, days, labels, dt) = compare(&scratch.history(), &restarted.history(), ck.day);
    println!("water change on {from}, restart at {}: {days} days, aperture diff {diff:e}, temperature diff {dt:e} °C", ck.day);
    assert!(diff <= 1e-9, "relative aperture difference {diff:e}");
    assert_eq!(labels, 0);
    assert!(dt <= 1e-9);
    // The past is untouched: before the change the runs agree exactly.
    let (before, ..) = compare(&base.history(), &scratch.history(), Day(0));
    let (after, ..) = compare(&base.history(), &scratch.history(), Day(150));
    println!("edited against the base: {before:e} over all days, {after:e} from day 150");
    let t_base = &base.history().zone_temps;
    let t_new = &scratch.history().zone_temps;
    let bits = |r: &(Day, Vec<[f64; 2]>)| -> Vec<u64> {
        r.1.iter().flatten().map(|v| v.to_bits()).collect()
    };
    for (ra, rb) in t_base
        .rows
        .iter()
        .zip(&t_new.rows)
        .filter(|(r, _)| r.0 < Day(150))
    {
        assert_eq!(
            bits(ra),
            bits(rb),
            "day {:?} changed before the water did",
            ra.0
        );
    }
    // ...and the colder water cooled the zone.
    let cooler = t_base
        .rows
        .iter()
        .zip(&t_new.rows)
        .filter(|(r, _)| r.0 > Day(170))
        .any(|(a, b)| {
            a.1.iter()
                .zip(&b.1)
                .any(|(x, y)| (x[0] - y[0]).max(x[1] - y[1]) > 0.3)
        });
    assert!(cooler, "the colder water must cool the zone by day 170+");
}

/// The last plan's remedy on the small dam: zone 3 of joint 2 supercooled
/// 2 °C from day 100.
fn remedy(inputs: &Inputs) -> Schedules {
    let layout = app::dam_layout(&inputs.mesh);
    let zone = ZoneId::new(2, 3);
    let planned = inputs.schedules.grouting_of(zone).unwrap().planned;
    let (remedied, _) = edit::supercool(
        &inputs.schedules,
        &layout,
        &[edit::Supercool {
            zone,
            delta_c: 2.0,
            planned,
            from: inputs.scene.epoch.date(Day(100)),
        }],
        3,
    );
    remedied
}

/// A planner's runner over the baseline run `base`.
fn runner<'a>(inputs: &'a Inputs, base: &Simulation) -> groutready::planner::runner::Runner<'a> {
    groutready::planner::runner::Runner::from_parts(
        &inputs.scene,
        &inputs.mesh,
        inputs.schedules.clone(),
        base.checkpoints.clone(),
        base.history(),
    )
}

/// A re-simulation restarts from the latest checkpoint of any run the
/// runner holds — the baseline or the last plan's verification run (a
/// lineage, issue 15 item 4) — before the first date it differs from that
/// run, and equals the run from the baseline's checkpoint.
#[test]
fn a_resimulation_restarts_from_the_latest_run_it_agrees_with() {
    use groutready::planner::runner::Span;
    let inputs = inputs();
    let base = run(&inputs, &inputs.schedules, None);
    let remedied = remedy(&inputs);
    // This week's edit on top: zone 2 of joint 2 grouted a week later.
    let moved = ZoneId::new(2, 2);
    let g = inputs.schedules.grouting_of(moved).unwrap().planned;
    let edited = edit::regrout(&remedied, &[(moved, g + chrono::Duration::days(7))]);
    let edit_day = inputs.scene.epoch.day(g);
    let day_of = |d| inputs.scene.epoch.day(d);
    // The remedy acts from the first stage it lowers, a month before the edit.
    let remedy_day = day_of(edit::first_change(&inputs.schedules, &remedied).unwrap());
    assert_eq!(
        day_of(edit::first_change(&remedied, &edited).unwrap()),
        edit_day
    );
    assert!(
        edit_day > remedy_day.plus(30) && edit_day < END,
        "remedy on {remedy_day:?}, edit on {edit_day:?}"
    );

    let mut runner = runner(&inputs, &base);
    let span = Span {
        end_day: END,
        observe: vec![],
    };
    let from_base = runner.restart_day(&edited, &span).unwrap();
    assert!(from_base <= remedy_day, "{from_base:?}");
    let lineage = runner.simulate_lineage(&remedied, &span, 30).unwrap();
    assert!(lineage.checkpoints.len() >= 3);
    let via_base = runner.simulate(&edited, &span).unwrap();
    runner.lineages.push(lineage);
    let from_lineage = runner.restart_day(&edited, &span).unwrap();
    assert!(
        from_lineage > remedy_day && from_lineage <= edit_day,
        "restarts from {from_lineage:?}, the edit is on {edit_day:?}"
    );
    // A span observing days before that checkpoint cannot use it: the
    // lineage did not record them.
    let observing = Span {
        end_day: END,
        observe: vec![remedy_day.plus(5)],
    };
    assert!(runner.restart_day(&edited, &observing).unwrap() <= remedy_day.plus(5));
    let via_lineage = runner.simulate(&edited, &span).unwrap();
    let (diff, days, labels, dt) = compare(&via_base, &via_lineage, from_base);
    println!("restarted from day {from_lineage:?} instead of {from_base:?}: {days} days, aperture diff {diff:e}, temperature diff {dt:e} °C");
    assert!(days > 50);
    assert!(diff <= 1e-9, "relative aperture difference {diff:e}");
    assert_eq!(labels, 0);
    assert!(dt <= 1e-9);
    // The edit did change the run after its date (the comparison is not vacuous).
    let (changed, ..) = compare(&runner.lineages[0].history, &via_lineage, edit_day);
    assert!(
        changed > 1e-4,
        "the edit changed apertures by only {changed:e}"
    );
}

/// The planner's two cheaper runs read what the whole run reads: a run of
/// the thermal effects alone (its temperature searches) has the same zone
/// temperatures to the bit, and a run stopped when a search has its answer
/// (the delay search) has the same rows up to its stop, and none after.
#[test]
fn a_thermal_run_and_a_stopped_run_read_what_the_whole_run_reads() {
    use groutready::planner::runner::Span;
    let inputs = inputs();
    let base = run(&inputs, &inputs.schedules, None);
    let remedied = remedy(&inputs);
    let runner = runner(&inputs, &base);
    let span = Span {
        end_day: END,
        observe: vec![],
    };
    let restart = runner.restart_day(&remedied, &span).unwrap();
    assert!(restart < Day(150), "restarts on {restart:?}");
    let whole = runner.simulate(&remedied, &span).unwrap();

    let thermal = runner.simulate_temperatures(&remedied, &span).unwrap();
    let temps = |h: &History| -> Vec<(Day, Vec<u64>)> {
        h.zone_temps
            .rows
            .iter()
            .map(|(d, r)| (*d, r.iter().flatten().map(|t| t.to_bits()).collect()))
            .collect()
    };
    assert_eq!(temps(&thermal), temps(&whole));
    assert!(
        whole.zone_temps.rows.iter().any(|r| r.0 > restart),
        "the re-simulation recorded temperatures"
    );
    let last_aperture = |h: &History| h.joint_records.rows.last().map(|r| r.0);
    assert!(
        last_aperture(&thermal) < Some(restart.plus(1)),
        "no apertures without the mechanics: {:?}",
        last_aperture(&thermal)
    );
    assert_eq!(last_aperture(&whole), Some(END));

    let stop_at = Day(150);
    let stopped = runner
        .simulate_until(&remedied, &span, &mut |d, _| d >= stop_at, false)
        .unwrap();
    let up_to = |h: &History, end: Day| {
        let mut h = h.clone();
        h.joint_records.rows.retain(|r| r.0 <= end);
        h.zone_temps.rows.retain(|r| r.0 <= end);
        h.records.rows.retain(|r| r.0 <= end);
        h
    };
    assert_eq!(last_aperture(&stopped), Some(stop_at));
    let (diff, days, labels, dt) = compare(&up_to(&whole, stop_at), &stopped, restart);
    assert!(days >= 20, "compared {days} days");
    assert_eq!(
        (diff, labels, dt),
        (0.0, 0, 0.0),
        "bit for bit up to the stop"
    );
}

/// `planner.search_max_step_days` lengthens the mechanical steps of the
/// remedy searches' re-simulations alone: restarted from the same exact
/// checkpoint, a search's run records fewer step ends than the exact
/// re-simulation (the effect is there) and its apertures stay near it,
/// while the runner's exact re-simulation (the verification's path) is the
/// same bytes as with the setting off.
#[test]
fn the_searches_take_longer_steps_and_the_exact_runs_stay_exact() {
    use groutready::planner::runner::{Runner, Span};
    let inputs = inputs();
    let base = run(&inputs, &inputs.schedules, None);
    let remedied = remedy(&inputs);
    let span = Span {
        end_day: END,
        observe: vec![],
    };
    let mut longer = inputs.scene.clone();
    longer.planner.search_max_step_days = 3;
    let plain = runner(&inputs, &base);
    let searching = Runner::from_parts(
        &longer,
        &inputs.mesh,
        inputs.schedules.clone(),
        base.checkpoints.clone(),
        base.history(),
    );
    let restart = searching.restart_day(&remedied, &span).unwrap();
    let bytes = |h: &History| postcard::to_stdvec(h).unwrap();
    let exact = plain.simulate(&remedied, &span).unwrap();
    assert!(
        bytes(&searching.simulate(&remedied, &span).unwrap()) == bytes(&exact),
        "the exact re-simulation changed with the setting"
    );
    assert!(
        bytes(&plain.simulate_search(&remedied, &span).unwrap()) == bytes(&exact),
        "with the setting off a search runs the exact path"
    );
    let search = searching.simulate_search(&remedied, &span).unwrap();
    // A day inside a longer step holds the step's apertures: the rows after
    // the restart that repeat the row before, bit for bit, and the largest
    // aperture difference where both record [mm].
    let held = |h: &History| {
        let apertures: Vec<Vec<u64>> = h
            .joint_records
            .rows
            .iter()
            .filter(|r| r.0 > restart)
            .map(|r| r.1.iter().flatten().map(|s| s.aperture.to_bits()).collect())
            .collect();
        apertures.windows(2).filter(|w| w[0] == w[1]).count()
    };
    let mut diff_mm = 0.0f64;
    for (a, b) in exact
        .joint_records
        .rows
        .iter()
        .zip(&search.joint_records.rows)
    {
        assert_eq!(a.0, b.0, "the same days recorded");
        for (x, y) in a.1.iter().zip(&b.1) {
            if let (Some(x), Some(y)) = (x, y) {
                diff_mm = diff_mm.max(1e3 * (x.aperture - y.aperture).abs());
            }
        }
    }
    let rows = exact
        .joint_records
        .rows
        .iter()
        .filter(|r| r.0 > restart)
        .count();
    println!(
        "search on 3-day steps from day {restart:?}: of {rows} days, {} held a step's apertures (exact: {}); apertures within {diff_mm:.3} mm",
        held(&search),
        held(&exact)
    );
    assert_eq!(held(&exact), 0, "the exact path steps every recorded day");
    assert!(
        3 * held(&search) > rows,
        "{} of {rows} days held",
        held(&search)
    );
    // the small dam's 3-day steps over its whole construction: 0.464 mm
    // at the grouting dates (`tests/it/fast_path.rs`)
    assert!(diff_mm > 0.0 && diff_mm < 0.464, "{diff_mm} mm");
}

/// The days of the checkpoints a thermal run of the small dam keeps, one
/// every 30 days, none before `kept_from` once a later one is taken, and
/// one on `on` (the temperatures alone: the checkpoints' days are what is
/// tested).
fn checkpoint_days(kept_from: Option<Day>, on: Option<Day>) -> Vec<Day> {
    let inputs = inputs();
    let mut scene = inputs.scene.clone();
    scene.effects.retain(|e| !e.is_mechanical());
    let mut sim = Simulation::new(&scene, &inputs.mesh, &inputs.schedules).unwrap();
    sim.set_end_day(END);
    sim.checkpoint_every = Some(30);
    sim.checkpoints_kept_from = kept_from;
    sim.checkpoint_on = on;
    sim.run(None, &mut |_, _| {}).unwrap();
    sim.checkpoints.iter().map(|c| c.day).collect()
}

/// The planner keeps in memory the checkpoints its run folder keeps
/// (`PlanOptions::checkpoints_kept_from`): a run told a day drops the older
/// ones as it takes newer ones, and keeps the same ones from that day on.
#[test]
fn a_run_keeps_no_checkpoint_before_the_day_it_is_told() {
    let all = checkpoint_days(None, None);
    let kept = checkpoint_days(Some(Day(100)), None);
    assert_eq!(all.len(), 6, "{all:?}");
    let expected: Vec<Day> = all.into_iter().filter(|&d| d >= Day(100)).collect();
    assert_eq!(kept, expected);
}

/// The plan's baseline also keeps a checkpoint on its as-of date
/// (`Simulation::checkpoint_on`), where every remedy acts from, so the
/// remedies' re-simulations restart there instead of at the regular
/// checkpoint before it; the regular interval then counts from it.
#[test]
fn a_run_keeps_a_checkpoint_on_the_day_it_is_told() {
    let regular = checkpoint_days(None, None);
    let told = checkpoint_days(None, Some(Day(100)));
    assert!(!regular.contains(&Day(100)), "{regular:?}");
    let before: Vec<Day> = regular.iter().copied().filter(|&d| d < Day(100)).collect();
    let after: Vec<Day> = told.iter().copied().filter(|&d| d > Day(100)).collect();
    assert_eq!(told[..before.len()], before[..], "{told:?}");
    assert_eq!(told[before.len()], Day(100), "{told:?}");
    assert_eq!(after.first(), Some(&Day(130)), "{told:?}");
}

/// A re-simulation makes its mechanics on the frame of another run of the
/// scene (`Simulation::like`) instead of building one: no construction
/// ordering, no rock condensation, and the same run to the bit — on its
/// own and through the planner's runner (whose first re-simulation builds
/// the frame it keeps, the second shares it).
#[test]
fn a_run_on_a_shared_frame_is_the_run_on_a_built_one() {
    use groutready::planner::runner::Span;
    let inputs = inputs();
    let (scene, mesh) = (&inputs.scene, &inputs.mesh);
    let bytes = |h: &History| postcard::to_stdvec(h).unwrap();
    let run_to_end = |mut sim: Simulation| {
        sim.set_end_day(Day(60));
        let stats = sim.run(None, &mut |_, _| {}).unwrap();
        (sim.history(), stats.mechanics.expect("mechanics"))
    };
    let built = Simulation::new(scene, mesh, &inputs.schedules).unwrap();
    let frame = built.mechanics_frame().expect("a scene with mechanics");
    let shared = Simulation::like(scene, mesh, &inputs.schedules, frame).unwrap();
    let (h_built, s_built) = run_to_end(built);
    let (h_shared, s_shared) = run_to_end(shared);
    println!(
        "built: {} METIS calls, {} rock dofs condensed in {:.3} s; shared: {} calls, {} dofs, {:.3} s",
        s_built.metis_calls,
        s_built.condensed_dofs,
        s_built.seconds_condensation,
        s_shared.metis_calls,
        s_shared.condensed_dofs,
        s_shared.seconds_condensation
    );
    assert_eq!(
        s_built.metis_calls,
        groutready::mechanics::live::CONSTRUCTION_KNOBS.len()
    );
    assert!(s_built.condensed_dofs > 0 && s_built.seconds_condensation > 0.0);
    assert_eq!(s_shared.metis_calls, 0, "the shared frame ordered again");
    assert_eq!(
        s_shared.seconds_condensation, 0.0,
        "the shared frame condensed again"
    );
    assert_eq!(s_shared.condensed_dofs, s_built.condensed_dofs);
    assert!(bytes(&h_built) == bytes(&h_shared), "the runs differ");

    let base = run(&inputs, &inputs.schedules, None);
    let runner = runner(&inputs, &base);
    let remedied = remedy(&inputs);
    let span = Span {
        end_day: END,
        observe: vec![],
    };
    let first = runner.simulate(&remedied, &span).unwrap();
    let second = runner.simulate(&remedied, &span).unwrap();
    assert!(
        bytes(&first) == bytes(&second),
        "the runner's re-simulations differ"
    );
}

/// With layer merging on (`solver.layer_merging_age_days`), a run
/// restarted from a checkpoint taken once nodes are tied repeats the run:
/// the tied set is derived from the checkpointed live set and birth days,
/// never stored.
#[test]
fn restart_with_layer_merging_repeats_the_run() {
    let mut inputs = inputs();
    inputs.scene.solver.layer_merging_age_days = 30;
    let merged_nodes = |end: Day, restart: Option<(&Checkpoint, &History)>| {
        let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
        sim.set_end_day(end);
        sim.checkpoint_every = Some(30);
        if let Some((ck, h)) = restart {
            sim.restore(ck, h);
        }
        let stats = sim.run(None, &mut |_, _| {}).unwrap();
        let tied = stats.mechanics.expect("mechanics").max_merged_nodes;
        (sim, tied)
    };
    let (a, tied_a) = merged_nodes(END, None);
    let ck = a
        .checkpoints
        .iter()
        .rev()
        .find(|c| c.day <= END.plus(-40))
        .unwrap()
        .clone();
    let (_, tied_before) = merged_nodes(ck.day, None);
    let (b, tied_b) = merged_nodes(END, Some((&ck, &a.history())));
    let (diff, days, labels, dt) = compare(&a.history(), &b.history(), ck.day);
    println!(
        "layer merging 30 d, restart at {:?}: {tied_before} nodes tied by then, {tied_a} in the run, {tied_b} after the restart; {days} days compared, aperture diff {diff:e}, {labels} labels, temperature diff {dt:e} °C",
        ck.day
    );
    assert!(tied_before > 0, "nothing tied at the restart point");
    assert!(tied_b >= tied_before);
    assert!(days > 20);
    assert!(diff <= 1e-9, "relative aperture difference {diff:e}");
    assert_eq!(labels, 0);
    assert!(dt <= 1e-9);
}
