//! The README's main command on the bundled demo: `groutready plan` with no
//! arguments flags the zones that will be too tight on their planned dates,
//! proposes remedies, and the remedied schedules it writes make those zones
//! groutable when they are simulated from scratch (not restarted). It shows
//! both kinds of supercooling (issue 15 item 5): a running second stage
//! split at the as-of date with colder water, and neighbouring zones
//! supercooled together for less than zone by zone.

use std::collections::HashMap;
use std::path::Path;

use groutready::app;
use groutready::planner::rules::{HistoryIndex, Rules};
use groutready::schedule;
use groutready::sim::Simulation;
use groutready::vocab::{Day, ZoneId};

#[test]
fn demo_plan_flags_zones_and_its_remedies_hold_from_scratch() {
    // Exactly the README command, run from an empty folder.
    let p = crate::common::demo_plan();
    let (stdout, stderr) = (p.stdout(), p.stderr());
    assert_eq!(p.output.status.code(), Some(0), "{stdout}\n{stderr}");
    println!("{stdout}");
    let out = &p.out;
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let zones = report["zones"].as_array().unwrap();
    let flagged: Vec<&serde_json::Value> = zones
        .iter()
        .filter(|z| z["history"] == false && z["verdict"] == "not_groutable")
        .collect();
    assert!(!flagged.is_empty(), "the demo must flag zones");
    // The demo's history obeys its own rules: every zone grouted before the
    // as-of date was groutable on its date (its second stage cooled it to
    // closure and held it there).
    let history: Vec<String> = zones
        .iter()
        .filter(|z| z["history"] == true)
        .map(|z| format!("J{} Z{} {}", z["joint"], z["zone"], z["verdict"]))
        .collect();
    assert_eq!(history.len(), 11);
    assert!(
        history.iter().all(|h| h.ends_with("\"groutable\"")),
        "{history:?}"
    );
    for z in &flagged {
        let a = z["apertures_mm"]["min"].as_f64().unwrap_or(0.0);
        let reasons: Vec<&str> = z["checks"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|c| c["reason"].as_str())
            .collect();
        assert!(!reasons.is_empty());
        assert!(a < 0.5 || !reasons.iter().any(|r| r.starts_with("aperture")));
    }

    together_and_running_stages(&stdout, &report, &flagged, out);

    // The remedied schedules, simulated from day 0.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let inputs = app::load_inputs(&root.join("models/demo_arch.toml"), None).unwrap();
    let remedied = schedule::load(&out.join("remedied")).unwrap();
    schedule::check_against(&remedied, &app::dam_layout(&inputs.mesh)).unwrap();
    let days: HashMap<ZoneId, Day> = remedied
        .grouting
        .iter()
        .map(|g| (g.zone_id(), inputs.scene.epoch.day(g.planned)))
        .collect();
    let mut remedied_zones = Vec::new();
    for z in &flagged {
        let key = ZoneId::new(
            z["joint"].as_u64().unwrap() as u32,
            z["zone"].as_u64().unwrap() as u32,
        );
        let choice = z["remedy"]["choice"].as_str().unwrap();
        if choice != "none" {
            remedied_zones.push((key, choice.to_string()));
        }
    }
    assert!(
        !remedied_zones.is_empty(),
        "some flagged zone must have a remedy"
    );
    let end = remedied_zones
        .iter()
        .map(|(k, _)| days[k])
        .fold(Day(0), Day::max);
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &remedied).unwrap();
    sim.set_end_day(end);
    sim.run(None, &mut |_, _| {}).unwrap();
    let layout = app::dam_layout(&inputs.mesh);
    let rules = Rules::new(
        &inputs.scene.planner,
        &layout,
        &inputs.mesh,
        inputs.scene.epoch,
        &remedied,
    );
    let history = sim.history();
    let idx = HistoryIndex::new(&history);
    for (key, choice) in &remedied_zones {
        let (j, z) = (key.joint, key.zone);
        let r = rules.evaluate(&idx, *key, days[key], &days);
        println!(
            "joint {j} zone {z} ({choice}): {} on {}, min aperture {:?} mm",
            r.verdict.as_str(),
            r.planned,
            r.apertures_mm.min
        );
        assert!(
            r.verdict.groutable(),
            "joint {j} zone {z} after {choice}: {}",
            r.reasons()
        );
    }
}

/// The demo's two supercoolings: a set of neighbours chosen together, each
/// too warm (whatever the aperture rule reads), costing strictly less than
/// zone by zone, as the console says; and a running second stage split at
/// the as-of date, continued with colder water and a lower target.
fn together_and_running_stages(
    stdout: &str,
    report: &serde_json::Value,
    flagged: &[&serde_json::Value],
    out: &Path,
) {
    let together: Vec<&serde_json::Value> = flagged
        .iter()
        .copied()
        .filter(|z| z["remedy"]["choice"] == "supercool")
        .filter(|z| z["remedy"]["supercool"]["together"].is_object())
        .collect();
    assert!(together.len() >= 2, "a set of neighbours:\n{stdout}");
    for z in &together {
        let t = &z["remedy"]["supercool"]["together"];
        let (set, zbz) = (
            t["set_c"].as_f64().unwrap(),
            t["set_zone_by_zone_c"].as_f64().unwrap(),
        );
        assert!(set < zbz - 1e-9, "{t}");
        let too_warm = z["checks"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c["rule"] == "temperature" && c["passed"] == false);
        assert!(too_warm, "the set is flagged on temperature: {z}");
        let line = format!("{set:.2} °C in all against {zbz:.2} °C zone by");
        assert!(stdout.contains(&line), "{line:?} missing:\n{stdout}");
    }

    // A stage running on the as-of date, split there: the row before ends
    // on it, the row continuing it starts on it with colder water.
    let as_of: chrono::NaiveDate = report["as_of"].as_str().unwrap().parse().unwrap();
    let base =
        schedule::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("schedules/demo_arch")).unwrap();
    let remedied = schedule::load(&out.join("remedied")).unwrap();
    let split = remedied.cooling.iter().any(|c| {
        c.start == as_of
            && remedied.cooling.iter().any(|b| {
                (b.block, b.lift_from, b.lift_to, b.stage)
                    == (c.block, c.lift_from, c.lift_to, c.stage)
                    && b.start < as_of
                    && b.end == Some(as_of)
                    && base.cooling.iter().any(|o| {
                        (o.block, o.lift_from, o.lift_to, o.start)
                            == (b.block, b.lift_from, b.lift_to, b.start)
                            && o.end.is_some_and(|e| e > as_of)
                            && c.water_temp_c < o.water_temp_c
                    })
            })
    });
    assert!(split, "a running stage split at {as_of} with colder water");
}
