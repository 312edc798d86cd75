//! Site limits stop a supercooling (issue 15 item 2). The small dam planned
//! from 15 July 2024 supercools zone 4 of joints 1 and 4 by 1.00 °C
//! (`common::small_plan_running`, the control: without a tighter limit the
//! remedy is proposed). That supercooling, in its verification run against
//! the baseline, takes block 2 from 0.3 to 0.8 °C below closure, its
//! cooling rate from 0.15 to 0.19 °C/day, and the gradient between zones 5
//! and 6 of block 1 from 4.2 to 4.6 °C. Each test sets one limit between
//! those two values: the plan no longer proposes the supercooling, proposes
//! the delay instead, and the report says which limit stopped it.

use std::sync::OnceLock;

use groutready::app::{self, Inputs};
use groutready::planner::plan::Restart;
use groutready::planner::{self, Plan, PlanOptions, PlanOutput, RemedyChoice};
use groutready::scene::PlannerSettings;
use groutready::vocab::ZoneId;

use crate::common::{date, repo};

fn options() -> PlanOptions {
    PlanOptions {
        as_of: date(2024, 7, 15),
        horizon_days: Some(60),
    }
}

/// The inputs and the baseline plan (default limits), shared: each test
/// restarts from its checkpoints and re-runs only the remedy search.
fn base() -> &'static (Inputs, PlanOutput) {
    static B: OnceLock<(Inputs, PlanOutput)> = OnceLock::new();
    B.get_or_init(|| {
        let inputs = app::load_inputs(&repo("models/small_dam_joints.toml"), None).unwrap();
        let out = planner::plan(
            &inputs.scene,
            &inputs.mesh,
            &inputs.schedules,
            &options(),
            None,
            &mut |_| {},
        )
        .unwrap();
        (inputs, out)
    })
}

/// The plan with one planner setting changed, and its report.md.
fn plan_with(change: impl Fn(&mut PlannerSettings)) -> (Plan, String) {
    let (inputs, out) = base();
    let mut scene = inputs.scene.clone();
    change(&mut scene.planner);
    scene.planner.validate().unwrap();
    let mut cks = out.checkpoints.clone();
    let checkpoint = cks.pop().expect("a checkpoint");
    let restart = Restart {
        checkpoint,
        history: out.history.clone(),
        older: cks,
        last_plan: None,
    };
    let p = planner::plan(
        &scene,
        &inputs.mesh,
        &inputs.schedules,
        &options(),
        Some(restart),
        &mut |_| {},
    )
    .unwrap()
    .plan;
    let tmp = tempfile::tempdir().unwrap();
    groutready::report::write_all(tmp.path(), &p).unwrap();
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    (p, md)
}

/// Zone 4 of joint 1 is not supercooled: the delay is proposed, and the
/// limit that stopped it is named in the remedy and the report.
fn stopped_by(p: &Plan, md: &str, limit: &str) {
    let z = p
        .zones
        .iter()
        .find(|z| z.zone_id() == ZoneId::new(1, 4))
        .unwrap();
    let r = z.remedy.as_ref().expect("a remedy");
    assert_eq!(r.choice, RemedyChoice::Delay, "{}", r.note);
    assert!(r.supercool.is_some(), "the search found a supercooling");
    assert!(
        !r.limited.is_empty() && r.limited.iter().all(|b| b.starts_with(limit)),
        "{:?}",
        r.limited
    );
    assert!(
        md.contains(&format!("is stopped by a site limit ({limit}")),
        "{md}"
    );
    // ...and the delay it proposes instead was verified groutable.
    assert!(
        r.verified.is_some_and(|v| v.0.groutable()),
        "{:?}",
        r.verified
    );
}

/// The control: with the default limits the plan supercools the zone.
#[test]
fn without_a_tighter_limit_the_zone_is_supercooled() {
    let (_, out) = base();
    let z = out
        .plan
        .zones
        .iter()
        .find(|z| z.zone_id() == ZoneId::new(1, 4))
        .unwrap();
    let r = z.remedy.as_ref().unwrap();
    assert_eq!(r.choice, RemedyChoice::Supercool, "{}", r.note);
    assert!(r.limited.is_empty());
}

#[test]
fn the_largest_supercooling_below_closure_stops_it() {
    let (p, md) = plan_with(|s| s.max_below_closure_c = 0.5);
    stopped_by(&p, &md, "below closure: block 2 would be at");
}

#[test]
fn the_cooling_rate_stops_it() {
    let (p, md) = plan_with(|s| s.max_cooling_rate_c_per_day = 0.17);
    stopped_by(&p, &md, "cooling rate: block 2 would cool at");
}

#[test]
fn the_gradient_to_the_zones_above_stops_it() {
    let (p, md) = plan_with(|s| s.max_zone_gradient_c = 4.4);
    stopped_by(&p, &md, "gradient: in block");
}
