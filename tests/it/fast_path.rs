//! The fast path of the mechanics equals the exact path where the planner
//! reads it: on the small dam with joints (five blocks, pipe cooling, creep,
//! self-weight, friction), the whole construction solved once with the
//! capacitance correction of contact-set changes (the default) and once
//! refactorising at every change (`solver.contact_capacitance = false`).
//! Compared: the aperture and the state of every zone point and zone
//! minimum on each zone's planned grouting date (ISSUE 12: within 0.01 mm,
//! same states), and that the fast path did take fewer factorisations.

use std::path::Path;

use groutready::app;
use groutready::mechanics::MechStats;
use groutready::sim::{JointRecords, Simulation};
use groutready::vocab::ZoneId;

fn run(capacitance: bool) -> (JointRecords, MechStats, Vec<(ZoneId, chrono::NaiveDate)>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut inputs = app::load_inputs(&root.join("models/small_dam_joints.toml"), None).unwrap();
    inputs.scene.solver.contact_capacitance = capacitance;
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
    let stats = sim.run(None, &mut |_, _| {}).unwrap();
    let dates = inputs
        .schedules
        .grouting
        .iter()
        .map(|g| (g.zone_id(), g.planned))
        .collect();
    (
        sim.joint_records.clone(),
        stats.mechanics.expect("the scene has mechanics"),
        dates,
    )
}

#[test]
fn capacitance_path_equals_refactorising_at_the_grouting_dates() {
    let (fast, fast_stats, dates) = run(true);
    let (exact, exact_stats, _) = run(false);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = groutready::scene::Scene::load(&root.join("models/small_dam_joints.toml")).unwrap();
    let (mut compared, mut largest, mut closed) = (0, 0.0f64, 0);
    for (zone, date) in &dates {
        let day = scene.epoch.day(*date);
        let row = |r: &JointRecords| {
            r.rows
                .iter()
                .find(|(d, _)| *d == day)
                .map(|(_, s)| s.clone())
                .unwrap_or_else(|| panic!("{zone:?}: no joint row on {date}"))
        };
        let (f, e) = (row(&fast), row(&exact));
        for (c, col) in fast.columns.iter().enumerate() {
            if col.zone != *zone {
                continue;
            }
            let (Some(f), Some(e)) = (f[c], e[c]) else {
                panic!(
                    "{zone:?} {:?}: no sample on its grouting date {date}",
                    col.point
                );
            };
            let diff = (f.aperture - e.aperture).abs();
            largest = largest.max(diff);
            assert!(
                diff <= 1e-5,
                "{zone:?} {:?} on {date}: apertures {:.6} mm (fast) and {:.6} mm (exact)",
                col.point,
                1e3 * f.aperture,
                1e3 * e.aperture
            );
            assert_eq!(f.state, e.state, "{zone:?} {:?} on {date}", col.point);
            closed += usize::from(f.state != groutready::vocab::JointState::Open);
            compared += 1;
        }
    }
    eprintln!(
        "{compared} zone samples at their grouting dates ({closed} closed): apertures differ by at most {:.2e} mm; \
         factorisations {} (fast, {} capacitance solves, largest rank {}) against {} (exact)",
        1e3 * largest,
        fast_stats.numeric,
        fast_stats.capacitance_solves,
        fast_stats.capacitance_max_rank,
        exact_stats.numeric
    );
    assert!(compared >= 4 * dates.len(), "every zone is read");
    assert_eq!(exact_stats.capacitance_solves, 0);
    assert!(
        exact_stats.refactor_reasons.contact > 0,
        "the contact set changes within steps"
    );
    assert!(fast_stats.capacitance_solves > 0);
    assert!(
        fast_stats.numeric < exact_stats.numeric,
        "the correction replaces factorisations"
    );
}
