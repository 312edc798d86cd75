//! Site limits stop a supercooling (issue 15 item 2). The small dam planned
//! from 15 July 2024 supercools zone 4 of joints 1 and 4 by 1.00 °C
//! (`common::small_plan_running`, the control: without a tighter limit the
//! remedy is proposed). That supercooling, in its verification run against
//! the baseline, takes block 2 from 0.3 to 0.8 °C below closure, its
//! cooling rate from 0.15 to 0.19 °C/day, and the gradient between zones 5
//! and 6 of block 1 from 4.2 to 4.6 °C. Each test sets one limit between
//! those two values: the plan no longer proposes the supercooling, proposes
//! the delay instead, and the report says which limit stopped it. The
//! coldest water is checked on the edit itself.

use std::sync::OnceLock;

use groutready::app::restart::Opened;
use groutready::app::{self, Inputs};
use groutready::planner::{self, Plan, PlanOptions, RemedyChoice};
use groutready::scene::PlannerSettings;
use groutready::vocab::ZoneId;

use crate::common::{date, repo};

fn options() -> PlanOptions {
    PlanOptions {
        as_of: date(2024, 7, 15),
        horizon_days: Some(60),
    }
}

/// The inputs and the plan with the default limits: the shared run folder
/// of `common::small_plan_running` (the same scene, dates and horizon).
fn base() -> &'static (Inputs, Opened) {
    static B: OnceLock<(Inputs, Opened)> = OnceLock::new();
    B.get_or_init(|| {
        let shared = crate::common::small_plan_running();
        assert!(shared.output.status.success(), "{}", shared.stderr());
        let inputs = app::load_inputs(&repo("models/small_dam_joints.toml"), None).unwrap();
        let opened = app::restart::open(&shared.out).unwrap();
        (inputs, opened)
    })
}

/// The plan with one planner setting changed, restarted from the shared
/// run folder as a weekly re-plan is: the searches, which read no limit,
/// are reused ([`groutready::planner::memo`]), and only the verification
/// runs again. Returns the plan and its report.md.
fn plan_with(change: impl Fn(&mut PlannerSettings)) -> (Plan, String) {
    let (inputs, opened) = base();
    let mut scene = inputs.scene.clone();
    change(&mut scene.planner);
    scene.planner.validate().unwrap();
    let end = options().end_day(scene.epoch, &inputs.schedules);
    let found = app::restart::find(&opened.dir, &scene, &inputs.schedules, Some(end));
    let restart = found.previous.expect("the shared plan's restart").restart;
    let out = planner::plan(
        &scene,
        &inputs.mesh,
        &inputs.schedules,
        &options(),
        Some(restart),
        &mut |_| {},
    )
    .unwrap();
    assert!(
        out.plan
            .stats
            .reused
            .iter()
            .any(|r| r.starts_with("supercooling search"))
            || scene.planner.min_water_temp_c != PlannerSettings::default().min_water_temp_c,
        "{:?}",
        out.plan.stats.reused
    );
    let p = out.plan;
    let tmp = tempfile::tempdir().unwrap();
    groutready::report::write_all(tmp.path(), &p).unwrap();
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    (p, md)
}

/// The remedy the plan gives zone 4 of joint 1.
fn remedy_of_zone_1_4(p: &Plan) -> &groutready::planner::Remedy {
    p.zones
        .iter()
        .find(|z| z.zone_id() == ZoneId::new(1, 4))
        .and_then(|z| z.remedy.as_ref())
        .expect("zone 4 of joint 1 is flagged and has a remedy")
}

/// Zone 4 of joint 1 is not supercooled: the delay is proposed, and the
/// limit that stopped it is named in the remedy and the report.
fn stopped_by(p: &Plan, md: &str, limit: &str) {
    let r = remedy_of_zone_1_4(p);
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
    let (_, opened) = base();
    let r = remedy_of_zone_1_4(&opened.plan);
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

/// The coldest water: supercooling never lowers a stage's water below
/// `min_water_temp_c`, nor warms one already colder; the target is still
/// lowered by the full ΔT.
#[test]
fn supercooling_never_takes_the_water_below_the_coldest_allowed() {
    use groutready::planner::edit::{self, Supercool};
    let (inputs, _) = base();
    let layout = app::dam_layout(&inputs.mesh);
    let zone = ZoneId::new(1, 4);
    let planned = inputs.schedules.grouting_of(zone).unwrap().planned;
    let sc = Supercool {
        zone,
        delta_c: 3.0,
        planned,
        from: date(2024, 7, 15),
    };
    let s = &inputs.schedules;
    for coldest in [4.0, 6.5, 9.0] {
        let (edited, missing) = edit::supercool_with_water(s, &layout, &[sc], 3, coldest);
        assert!(missing.is_empty());
        assert!(edit::water_held(s, &layout, &sc, 3, coldest) == (coldest > 5.0));
        let mut lowered = 0;
        for c in &edited.cooling {
            // rows the edit made or changed: those with a lower target
            let before = s.cooling.iter().find(|o| {
                (o.block, o.lift_from, o.lift_to, o.stage)
                    == (c.block, c.lift_from, c.lift_to, c.stage)
                    && o.start <= c.start
                    && o.target_temp_c.is_some()
            });
            let Some(o) = before else { continue };
            if c.target_temp_c
                .zip(o.target_temp_c)
                .is_some_and(|(n, t)| n < t - 2.9)
            {
                lowered += 1;
                let want = (o.water_temp_c - 3.0).max(coldest.min(o.water_temp_c));
                assert_eq!(c.water_temp_c, want, "{c:?} from {o:?}");
            }
        }
        assert!(lowered >= 2, "{lowered} rows supercooled");
    }
}

/// The coldest water the site allows at the stage's own 8 °C: the
/// supercooling can only lower the target, which leaves block 1 as warm,
/// so none is found; the delay is proposed and the note names the limit.
/// (The searches read the water, so they run again here.)
#[test]
fn the_coldest_water_stops_it() {
    let (p, md) = plan_with(|s| s.min_water_temp_c = 8.0);
    let r = remedy_of_zone_1_4(&p);
    assert_eq!(r.choice, RemedyChoice::Delay, "{}", r.note);
    assert!(r.supercool.is_none());
    let why = "the coldest water allowed, 8.0 °C, held its water (site limit)";
    assert!(r.note.contains(why), "{}", r.note);
    assert!(md.contains(why), "{md}");
}
