//! The report files of a synthetic plan: readiness.csv, report.md,
//! report.json, the SVG charts and the terminal table, checked value by value.

use std::collections::BTreeMap;
use std::path::Path;

use chrono::NaiveDate;
use groutready::planner::{
    Apertures, ChosenTogether, DelayOption, MeterComparison, Plan, PlanStats, Remedy, RemedyChoice,
    Rule, RuleCheck, SupercoolOption, Verdict, ZoneHistory, ZoneReadiness, CAUTION_MARK,
};
use groutready::report::{self, charts, svg};
use groutready::scene::PlannerSettings;
use groutready::vocab::ZoneId;

fn date(s: &str) -> NaiveDate {
    s.parse().unwrap()
}

fn check(rule: Rule, value: f64, limit: f64, reason: Option<&str>) -> RuleCheck {
    RuleCheck {
        rule,
        value: Some(value),
        limit,
        passed: reason.is_none(),
        reason: reason.map(str::to_string),
    }
}

const REASON_APERTURE_22: &str = "aperture 0.41 mm < 0.5 mm at the min point";
const REASON_TEMP_22: &str = "block B 14.6 °C above closure 13.0 + 1.0 °C";
const REASON_APERTURE_31: &str = "aperture 0.45 mm < 0.5 mm at the min point";
const REASON_AGE_32: &str = "youngest lift 40 days old < 90 days";
const REASON_APERTURE_32: &str = "aperture 0.20 mm at the min point is below 0.50 mm";
const REASON_COVER_32: &str = "only 3.0 m of concrete above the zone on block 4, 6.0 m needed";
const REASON_BELOW_32: &str = "zone 1 below is grouted later (2024-10-13)";
const NOTE_22: &str = "supercooling costs 1.25 against 4.0 for the delay";
const NOTE_32: &str = "neither 3 °C of supercooling nor 60 days of delay make it groutable";

#[allow(clippy::too_many_arguments)]
fn zone(
    joint: u32,
    zone: u32,
    planned: &str,
    history: bool,
    ap: [Option<f64>; 4],
    temps: (Option<f64>, Option<f64>),
    verdict: Verdict,
    checks: Vec<RuleCheck>,
    remedy: Option<Remedy>,
) -> ZoneReadiness {
    ZoneReadiness {
        joint,
        zone,
        planned: date(planned),
        history,
        z_bottom_m: 9.0 * (zone - 1) as f64,
        z_top_m: 9.0 * zone as f64,
        apertures_mm: Apertures {
            upstream: ap[0],
            center: ap[1],
            downstream: ap[2],
            min: ap[3],
        },
        temp_a_c: temps.0,
        temp_b_c: temps.1,
        closure_temp_c: 13.0,
        age_days: Some(120.0),
        cover_m: Some(9.0),
        checks,
        verdict,
        reopened: None,
        remedy,
    }
}

/// 20 weekly dates from 2024-06-01 to 2024-10-12.
fn dates() -> Vec<NaiveDate> {
    (0..20)
        .map(|i| date("2024-06-01") + chrono::Duration::days(7 * i))
        .collect()
}

/// A history opening linearly from `a0` by `rate` mm a week, upstream
/// missing for the first `gap` dates (the zone's blocks did not both exist).
fn history(joint: u32, zone: u32, planned: &str, a0: f64, rate: f64, gap: usize) -> ZoneHistory {
    let n = dates().len();
    let v =
        |k: f64| -> Vec<Option<f64>> { (0..n).map(|i| Some(a0 * k + rate * i as f64)).collect() };
    let mut upstream = v(1.1);
    for u in upstream.iter_mut().take(gap) {
        *u = None;
    }
    ZoneHistory {
        joint,
        zone,
        planned: date(planned),
        dates: dates(),
        upstream,
        center: v(1.0),
        downstream: v(0.9),
        min: v(0.9),
        temperature: vec![Some(14.0); n],
    }
}

fn meter(
    joint: u32,
    zone: u32,
    point: &str,
    d: &str,
    measured: f64,
    predicted: Option<f64>,
) -> MeterComparison {
    MeterComparison {
        joint,
        zone,
        point: groutready::vocab::ZonePoint::parse(point).expect("a point"),
        date: date(d),
        measured_mm: measured,
        predicted_mm: predicted,
    }
}

fn fixture() -> Plan {
    let s = Some;
    let mut grouted = zone(
        1,
        1,
        "2024-08-01",
        true,
        [s(1.0), s(0.95), s(0.9), s(0.9)],
        (s(12.0), s(12.4)),
        Verdict::Groutable,
        vec![],
        None,
    );
    grouted.reopened = Some(date("2024-08-20"));
    let groutable = zone(
        1,
        2,
        "2024-09-10",
        false,
        [s(1.1), s(1.0), s(0.951_234_56), s(0.951_234_56)],
        (s(12.5), s(12.8)),
        Verdict::Groutable,
        vec![check(Rule::Aperture, 0.95, 0.5, None)],
        None,
    );
    let marginal = zone(
        2,
        1,
        "2024-09-15",
        false,
        [s(0.7), s(0.65), s(0.62), s(0.62)],
        (s(13.5), s(13.9)),
        Verdict::Marginal,
        vec![],
        None,
    );
    let supercooled = zone(
        2,
        2,
        "2024-09-20",
        false,
        [s(0.5), s(0.55), s(0.41), s(0.41)],
        (s(13.2), s(14.6)),
        Verdict::NotGroutable,
        vec![
            check(Rule::Aperture, 0.41, 0.5, Some(REASON_APERTURE_22)),
            check(Rule::Temperature, 14.6, 14.0, Some(REASON_TEMP_22)),
            check(Rule::Age, 120.0, 90.0, None),
        ],
        Some(Remedy {
            supercool: Some(SupercoolOption {
                delta_c: 1.25,
                aperture_mm: 0.62,
                together: None,
            }),
            delay: Some(DelayOption {
                days: 20,
                date: date("2024-10-10"),
                aperture_mm: 0.58,
                also_delayed: vec![],
            }),
            choice: RemedyChoice::Supercool,
            verified: Some((Verdict::Marginal, Some(0.61))),
            note: NOTE_22.into(),
            verified_history: None,
            limited: Vec::new(),
        }),
    );
    let delayed = zone(
        3,
        1,
        "2024-10-01",
        false,
        [s(0.6), s(0.5), s(0.45), s(0.45)],
        (s(12.0), s(12.1)),
        Verdict::NotGroutable,
        vec![check(Rule::Aperture, 0.45, 0.5, Some(REASON_APERTURE_31))],
        Some(Remedy {
            supercool: None,
            delay: Some(DelayOption {
                days: 12,
                date: date("2024-10-13"),
                aperture_mm: 0.55,
                also_delayed: vec![2],
            }),
            choice: RemedyChoice::Delay,
            verified: Some((Verdict::Marginal, Some(0.55))),
            note: "no supercooling within 3 °C opens it enough".into(),
            verified_history: None,
            limited: Vec::new(),
        }),
    );
    let mut hopeless = zone(
        3,
        2,
        "2024-10-05",
        false,
        [None, s(0.3), s(0.2), s(0.2)],
        (None, s(12.2)),
        Verdict::NotGroutable,
        vec![check(Rule::Age, 40.0, 90.0, Some(REASON_AGE_32))],
        Some(Remedy {
            supercool: None,
            delay: None,
            choice: RemedyChoice::None,
            verified: None,
            note: NOTE_32.into(),
            verified_history: None,
            limited: Vec::new(),
        }),
    );
    hopeless.cover_m = None;
    Plan {
        scene: "demo-arch".into(),
        as_of: date("2024-09-01"),
        settings: PlannerSettings::default(),
        zones: vec![grouted, groutable, marginal, supercooled, delayed, hopeless],
        histories: vec![
            history(1, 1, "2024-08-01", 0.6, 0.02, 0),
            history(2, 2, "2024-09-20", 0.1, 0.05, 2),
            history(3, 1, "2024-10-01", 0.1, 0.04, 0),
            history(3, 2, "2024-10-05", 0.0, 0.01, 0),
        ],
        meters: vec![
            meter(1, 1, "center", "2024-08-01", 0.90, Some(0.84)),
            meter(1, 1, "center", "2024-07-01", 0.80, Some(0.85)),
            meter(1, 1, "center", "2024-08-15", 0.70, None),
            meter(3, 1, "upstream", "2024-07-10", 0.50, Some(0.60)),
            meter(3, 1, "upstream", "2024-08-10", 0.40, Some(0.30)),
        ],
        warnings: vec![],
        approximations: vec![],
        stats: PlanStats {
            baseline_seconds: 120.5,
            restarted_from: Some(date("2024-08-15")),
            resimulations: 7,
            resimulation_seconds: 310.25,
            reused: vec!["delay search (1 run)".into()],
            total_seconds: 431.0,
        },
    }
}

fn written() -> (tempfile::TempDir, Plan, report::ReportFiles) {
    let dir = tempfile::tempdir().unwrap();
    let plan = fixture();
    let files = report::write_all(dir.path(), &plan).unwrap();
    (dir, plan, files)
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn files_written_are_listed() {
    let (dir, _, files) = written();
    let d = dir.path();
    assert_eq!(files.csv, d.join("readiness.csv"));
    assert_eq!(files.markdown, d.join("report.md"));
    assert_eq!(files.json, d.join("report.json"));
    let names = |v: &[std::path::PathBuf]| -> Vec<String> {
        v.iter()
            .map(|p| {
                p.strip_prefix(d.join("charts"))
                    .unwrap()
                    .display()
                    .to_string()
            })
            .collect()
    };
    assert_eq!(
        names(&files.zone_charts),
        [
            "zone_J1_Z1.svg",
            "zone_J2_Z2.svg",
            "zone_J3_Z1.svg",
            "zone_J3_Z2.svg"
        ]
    );
    assert_eq!(
        names(&files.meter_charts),
        ["meter_J1_Z1_center.svg", "meter_J3_Z1_upstream.svg"]
    );
    assert_eq!(files.all().len(), 9);
    for f in files.all() {
        assert!(f.is_file(), "{} missing", f.display());
    }
    let mut on_disk: Vec<String> = std::fs::read_dir(d.join("charts"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    on_disk.sort();
    assert_eq!(on_disk.len(), 6);
}

#[test]
fn write_all_names_the_path_it_cannot_write() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-folder");
    let err = report::write_all(&missing, &fixture()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("no-such-folder/readiness.csv"), "{msg}");
}

const HEADER: &str = "joint,zone,planned_date,status,z_bottom_m,z_top_m,aperture_upstream_mm,\
aperture_center_mm,aperture_downstream_mm,aperture_min_mm,temp_a_c,temp_b_c,closure_temp_c,age_days,\
cover_m,verdict,groutable,reasons,reopened_date,remedy,supercool_c,supercool_aperture_mm,delay_days,\
delay_date,delay_aperture_mm,verified_verdict,verified_aperture_mm,note";

#[test]
fn readiness_csv_has_one_row_per_zone_with_its_values() {
    let (_dir, _, files) = written();
    let mut r = csv::Reader::from_path(&files.csv).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    assert_eq!(header.join(","), HEADER);
    let rows: Vec<BTreeMap<String, String>> = r
        .records()
        .map(|rec| {
            header
                .iter()
                .cloned()
                .zip(rec.unwrap().iter().map(str::to_string))
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 6);
    let keys: Vec<(&str, &str, &str)> = rows
        .iter()
        .map(|r| {
            (
                r["joint"].as_str(),
                r["zone"].as_str(),
                r["status"].as_str(),
            )
        })
        .collect();
    assert_eq!(
        keys,
        [
            ("1", "1", "history"),
            ("1", "2", "to_grout"),
            ("2", "1", "to_grout"),
            ("2", "2", "to_grout"),
            ("3", "1", "to_grout"),
            ("3", "2", "to_grout")
        ]
    );
    let f = |row: &BTreeMap<String, String>, k: &str| -> f64 { row[k].parse().unwrap() };

    let h = &rows[0];
    assert_eq!(h["planned_date"], "2024-08-01");
    assert_eq!(h["reopened_date"], "2024-08-20");
    assert_eq!(h["remedy"], "");

    let g = &rows[1];
    assert_eq!(g["aperture_min_mm"], "0.951", "rounded to µm");
    assert_eq!(g["verdict"], "groutable");
    assert_eq!(g["groutable"], "true");
    assert_eq!(g["reasons"], "");
    assert_eq!(g["remedy"], "", "no remedy needed: blank");
    assert_eq!(f(g, "closure_temp_c"), 13.0);
    assert_eq!(f(g, "z_top_m"), 18.0);

    assert_eq!(rows[2]["verdict"], "marginal");
    assert_eq!(rows[2]["groutable"], "true");

    let sc = &rows[3];
    assert_eq!(sc["aperture_min_mm"], "0.41");
    assert_eq!(sc["aperture_center_mm"], "0.55");
    assert_eq!(sc["temp_b_c"], "14.6");
    assert_eq!(sc["verdict"], "not_groutable");
    assert_eq!(sc["groutable"], "false");
    assert_eq!(
        sc["reasons"],
        format!("{REASON_APERTURE_22}; {REASON_TEMP_22}")
    );
    assert_eq!(sc["remedy"], "supercool");
    assert_eq!(sc["supercool_c"], "1.25");
    assert_eq!(sc["supercool_aperture_mm"], "0.62");
    assert_eq!(sc["delay_days"], "20", "the other option found is kept");
    assert_eq!(sc["delay_date"], "2024-10-10");
    assert_eq!(sc["verified_verdict"], "marginal");
    assert_eq!(sc["verified_aperture_mm"], "0.61");
    assert_eq!(sc["note"], NOTE_22);

    let dl = &rows[4];
    assert_eq!(dl["remedy"], "delay");
    assert_eq!(dl["delay_days"], "12");
    assert_eq!(dl["delay_date"], "2024-10-13");
    assert_eq!(dl["delay_aperture_mm"], "0.55");
    assert_eq!(dl["supercool_c"], "");

    let no = &rows[5];
    assert_eq!(no["remedy"], "none");
    assert_eq!(no["aperture_upstream_mm"], "");
    assert_eq!(no["aperture_min_mm"], "0.2");
    assert_eq!(no["temp_a_c"], "");
    assert_eq!(no["cover_m"], "");
    assert_eq!(no["delay_date"], "");
    assert_eq!(no["verified_verdict"], "");
    assert_eq!(no["reasons"], REASON_AGE_32);
    assert_eq!(no["note"], NOTE_32);
}

/// The text of a Markdown section, from its `## ` heading to the next one.
fn section<'a>(md: &'a str, heading: &str) -> &'a str {
    let start = md
        .find(&format!("## {heading}\n"))
        .unwrap_or_else(|| panic!("no section {heading}"));
    let rest = &md[start + 3..];
    let end = rest.find("\n## ").map(|e| e + 1).unwrap_or(rest.len());
    &rest[..end]
}

#[test]
fn markdown_report_explains_flagged_zones_and_meters() {
    let (dir, _, files) = written();
    let md = read(&files.markdown);
    assert!(md.starts_with("# Grouting readiness: demo-arch, as of 2024-09-01\n"));

    let summary = section(&md, "Summary");
    assert!(summary.contains(
        "**5** zones to grout: **3** flagged (not groutable), **1** marginal, 1 groutable"
    ));
    assert!(summary.contains("**1** zone grouted before 2024-09-01, **1** of them re-opened"));
    assert!(summary.contains("restarted from the checkpoint of 2024-08-15"));
    assert!(
        summary.contains("7 re-simulations for remedies 310.2 s")
            || summary.contains("7 re-simulations for remedies 310.3 s")
    );

    let flagged = section(&md, "Flagged zones (not groutable)");
    for text in [
        REASON_APERTURE_22,
        REASON_TEMP_22,
        REASON_APERTURE_31,
        REASON_AGE_32,
        "supercool 1.25 °C → 0.62 mm",
        "delay 12 d → 2024-10-13, 0.55 mm (+ zone 2)",
        "no remedy found",
        "verified marginal, 0.61 mm",
        NOTE_32,
    ] {
        assert!(flagged.contains(text), "flagged section lacks {text:?}");
    }
    // One row per flagged zone, and no other zone.
    assert_eq!(
        flagged
            .lines()
            .filter(|l| l.starts_with("| 2 | 2 | 2024-09-20 | 0.41 < 0.50 |"))
            .count(),
        1
    );
    assert_eq!(
        flagged
            .lines()
            .filter(|l| l.starts_with("| 3 | 1 | 2024-10-01 | 0.45 < 0.50 |"))
            .count(),
        1
    );
    assert_eq!(
        flagged
            .lines()
            .filter(|l| l.starts_with("| 3 | 2 | 2024-10-05 | 0.20 < 0.50 |"))
            .count(),
        1
    );
    assert!(!flagged.contains("| 2 | 1 |") && !flagged.contains("| 1 | 2 |"));
    for (j, z) in [(2, 2), (3, 1), (3, 2)] {
        let link = format!(
            "![Aperture and temperature history of joint {j}, zone {z}](charts/zone_J{j}_Z{z}.svg)"
        );
        assert_eq!(flagged.matches(&link).count(), 1, "{link}");
        assert!(dir
            .path()
            .join(format!("charts/zone_J{j}_Z{z}.svg"))
            .is_file());
    }
    assert_eq!(
        md.matches("![Aperture and temperature history").count(),
        3,
        "charts of flagged zones only"
    );

    let marginal = section(&md, "Marginal zones");
    assert!(marginal.contains(
        "| 2 | 1 | 2024-09-15 | 0.62 ≥ 0.50 | 0.65 | 13.9 ≤ 14.0 | aperture 0.62 mm below 0.70 mm |"
    ));

    let reopened = section(&md, "Grouted zones that re-opened");
    assert!(reopened.contains("| 1 | 1 | 2024-08-01 | 2024-08-20 | 19 |"));

    // Errors predicted − measured, by hand: joint 1 over the two readings
    // with a prediction, joint 3 over both.
    let e1 = [0.85 - 0.80, 0.84 - 0.90];
    let mean1 = (e1[0] + e1[1]) / 2.0;
    let rms1 = ((e1[0] * e1[0] + e1[1] * e1[1]) / 2.0f64).sqrt();
    assert_eq!(format!("{mean1:.3} {rms1:.3}"), "-0.005 0.055");
    let meters = section(&md, "Joint meters");
    assert!(
        meters.contains("| 1 | 3 | 2 | -0.005 | 0.055 | 0.060 |"),
        "{meters}"
    );
    assert!(
        meters.contains("| 3 | 2 | 2 | 0.000 | 0.100 | 0.100 |"),
        "{meters}"
    );
    assert!(meters.contains("(charts/meter_J1_Z1_center.svg)"));
    assert!(meters.contains("(charts/meter_J3_Z1_upstream.svg)"));

    let all = section(&md, "All zones to grout");
    assert_eq!(
        all.lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| Joint"))
            .count(),
        5
    );
    assert!(
        !all.contains("2024-08-01"),
        "history zone listed as to grout"
    );
    assert!(all.contains("| 1 | 2 | 2024-09-10 | 0.95 ≥ 0.50 | 1.00 | 12.8 ≤ 14.0 | ✓ groutable |"));
    assert!(all.contains(&format!(
        "| ✗ not groutable | {REASON_AGE_32} — no remedy found |"
    )));
}

#[test]
fn markdown_report_says_warnings_reopenings_and_history_plainly() {
    let dir = tempfile::tempdir().unwrap();
    let files = report::write_all(dir.path(), &fixture_with_warning_and_reopening()).unwrap();
    let md = read(&files.markdown);
    let w = section(&md, "Warnings");
    assert!(
        w.contains("- cooling.csv:12:4 (target_c): target 4.0 °C is below the closure"),
        "{w}"
    );
    let planned = section(&md, "Planned zones that re-open after grouting");
    assert!(
        planned.contains("| 1 | 2 | 2024-09-10 | 2024-10-02 | 22 |"),
        "{planned}"
    );
    // The history zone's re-opening stays in its own section.
    assert!(!planned.contains("| 1 | 1 |"), "{planned}");
    let history = section(&md, "Already grouted (before 2024-09-01)");
    assert!(history.contains("not re-checked"), "{history}");
    assert!(
        history.contains("| 1 | 1 | 2024-08-01 | 0.90 | 12.4 | 2024-08-20 |"),
        "{history}"
    );
    assert!(!history.contains("groutable"), "no verdict: {history}");
    // Each flagged zone's reasons and remedy in full above its chart.
    let flagged = section(&md, "Flagged zones (not groutable)");
    assert!(flagged.contains(&format!("### Joint 2, zone 2\n\n- ✗ {REASON_APERTURE_22}\n- ✗ {REASON_TEMP_22}\n- Remedy: supercool 1.25 °C → 0.62 mm (verified marginal, 0.61 mm)\n")), "{flagged}");
    // Without warnings, no section.
    let (_d, _, plain) = written();
    assert!(!read(&plain.markdown).contains("## Warnings"));
}

#[test]
fn json_report_parses_with_counts_and_zones() {
    let (_dir, _, files) = written();
    let v: serde_json::Value = serde_json::from_str(&read(&files.json)).unwrap();
    assert_eq!(v["scene"], "demo-arch");
    assert_eq!(v["as_of"], "2024-09-01");
    assert_eq!(
        v["summary"],
        serde_json::json!({"to_grout": 5, "flagged": 3, "marginal": 1, "history": 1, "reopened": 1})
    );
    let zones = v["zones"].as_array().unwrap();
    assert_eq!(zones.len(), 6);
    let z = &zones[3];
    assert_eq!(
        (z["joint"].as_u64(), z["zone"].as_u64()),
        (Some(2), Some(2))
    );
    assert_eq!(z["apertures_mm"]["min"], 0.41);
    assert_eq!(z["verdict"], "not_groutable");
    assert_eq!(z["remedy"]["choice"], "supercool");
    assert_eq!(z["remedy"]["supercool"]["delta_c"], 1.25);
    assert_eq!(
        zones[5]["apertures_mm"]["upstream"],
        serde_json::Value::Null
    );
    assert_eq!(v["meters"].as_array().unwrap().len(), 5);
    let e = v["meter_errors"].as_array().unwrap();
    assert_eq!(e.len(), 2);
    assert_eq!(
        (
            e[0]["joint"].as_u64(),
            e[0]["readings"].as_u64(),
            e[0]["compared"].as_u64()
        ),
        (Some(1), Some(3), Some(2))
    );
    assert!((e[0]["rms_error_mm"].as_f64().unwrap() - 0.00305f64.sqrt()).abs() < 1e-9);
    assert!((e[1]["max_abs_error_mm"].as_f64().unwrap() - 0.1).abs() < 1e-9);
    assert_eq!(v["stats"]["resimulations"], 7);
    assert_eq!(v["stats"]["restarted_from"], "2024-08-15");
}

/// Checks that every opened tag is closed in order; returns the tags seen.
fn balanced_tags(doc: &str) -> Vec<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut seen = Vec::new();
    let mut rest = doc;
    while let Some(i) = rest.find('<') {
        let j = rest[i..].find('>').expect("tag not closed") + i;
        let tag = &rest[i + 1..j];
        assert!(!tag.contains('<'), "'<' inside a tag: {tag}");
        let name: String = tag
            .trim_start_matches('/')
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        if tag.starts_with('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.as_str()),
                "unbalanced </{name}>"
            );
        } else if !tag.ends_with('/') {
            stack.push(name.clone());
        }
        seen.push(name);
        rest = &rest[j + 1..];
    }
    assert!(stack.is_empty(), "unclosed {stack:?}");
    seen
}

/// The attribute `name` of the first element that starts with `start`.
fn attr(doc: &str, start: &str, name: &str) -> String {
    let i = doc.find(start).unwrap_or_else(|| panic!("no {start}"));
    let el = &doc[i..i + doc[i..].find('>').unwrap()];
    let k = el.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
    el[k..k + el[k..].find('"').unwrap()].to_string()
}

#[test]
fn zone_chart_draws_three_series_the_limit_and_the_planned_date() {
    let (dir, plan, _) = written();
    let doc = read(&dir.path().join("charts/zone_J2_Z2.svg"));
    assert!(doc.starts_with("<svg "));
    assert!(doc.trim_end().ends_with("</svg>"));
    let tags = balanced_tags(&doc);
    assert_eq!(tags.iter().filter(|t| *t == "svg").count(), 2);
    assert!(doc.contains(">Joint 2, zone 2</text>"));

    // One polyline per series (no gaps inside), 18 upstream points after the
    // two missing ones, 20 for the others.
    assert_eq!(doc.matches("<polyline").count(), 5);
    for (class, n) in [
        ("upstream", 18),
        ("center", 20),
        ("downstream", 20),
        ("min", 20),
        ("temperature", 20),
    ] {
        let pts = attr(&doc, &format!("<polyline class=\"{class}\""), "points");
        assert_eq!(pts.split(' ').count(), n, "{class}");
    }

    // Values 0.1·k + 0.05·i peak at 1.06 mm (upstream): 5 intervals of at
    // least 0.212 mm round to 0.25 mm, ticks 0..1.25, so the frame (y
    // 330..40 px) spans 0..1.25 mm.
    let h = &plan.histories[1];
    let axes = charts::zone_axes(h, &plan.settings);
    assert_eq!(axes.mm_ticks, [0.0, 0.25, 0.5, 0.75, 1.0, 1.25]);
    let y05 = 330.0 - (330.0 - 40.0) * 0.5 / 1.25;
    assert!((axes.ymm(0.5) - y05).abs() < 1e-9);
    assert_eq!(attr(&doc, "<line class=\"limit\"", "y1"), svg::px(y05));
    assert_eq!(attr(&doc, "<line class=\"limit\"", "y2"), "214.0");
    assert!(doc.contains(">0.5 mm</text>"));

    // 2024-09-20 is day 111 of 133 (2024-06-01 .. 2024-10-12) on 60..700 px.
    let x = 60.0 + 111.0 / 133.0 * 640.0;
    assert!((axes.xd(date("2024-09-20")) - x).abs() < 1e-9);
    assert_eq!(attr(&doc, "<line class=\"planned\"", "x1"), svg::px(x));
    assert_eq!(attr(&doc, "<line class=\"planned\"", "x2"), "594.1");
    assert!(doc.contains(">planned grouting 2024-09-20</text>"));

    // The first upstream point is on 2024-06-15 at 0.11 + 0.1 = 0.21 mm.
    let first = attr(&doc, "<polyline class=\"upstream\"", "points");
    let first = first.split(' ').next().unwrap();
    let expect = format!(
        "{},{}",
        svg::px(60.0 + 14.0 / 133.0 * 640.0),
        svg::px(330.0 - 290.0 * 0.21 / 1.25)
    );
    assert_eq!(first, expect);

    // Month ticks June to October, labelled.
    for m in ["Jun 2024", "Jul 2024", "Aug 2024", "Sep 2024", "Oct 2024"] {
        assert!(doc.contains(&format!(">{m}</text>")), "{m}");
    }
    for t in [
        ">0</text>",
        ">0.25</text>",
        ">0.5</text>",
        ">1</text>",
        ">1.25</text>",
    ] {
        assert!(doc.contains(t), "{t}");
    }
}

#[test]
fn meter_chart_draws_prediction_and_readings() {
    let (dir, plan, _) = written();
    let doc = read(&dir.path().join("charts/meter_J1_Z1_center.svg"));
    balanced_tags(&doc);
    assert!(doc.contains(">Joint 1, zone 1, center meter</text>"));
    // The prediction is the zone's history: one line of 20 points.
    assert_eq!(doc.matches("<polyline class=\"predicted\"").count(), 1);
    assert_eq!(
        attr(&doc, "<polyline class=\"predicted\"", "points")
            .split(' ')
            .count(),
        20
    );
    let g = doc.find("<g class=\"measured\">").unwrap();
    let group = &doc[g..g + doc[g..].find("</g>").unwrap()];
    assert_eq!(group.matches("<circle").count(), 3);

    // The 2024-08-01 reading of 0.90 mm sits where the axes put it.
    let h = &plan.histories[0];
    let series = report::meters::series(&plan.meters);
    let axes = charts::meter_axes(&series[0], Some(h), &plan.settings);
    let (cx, cy) = (
        svg::px(axes.xd(date("2024-08-01"))),
        svg::px(axes.ymm(0.90)),
    );
    assert!(
        group.contains(&format!("cx=\"{cx}\" cy=\"{cy}\"")),
        "{group}"
    );

    // Without a history the prediction is drawn at the reading dates.
    let other = read(&dir.path().join("charts/meter_J3_Z1_upstream.svg"));
    assert!(other.contains(">Joint 3, zone 1, upstream meter</text>"));
    let lone = &series[1];
    let doc = charts::meter_chart(lone, None, &plan.settings);
    assert_eq!(
        attr(&doc, "<polyline class=\"predicted\"", "points")
            .split(' ')
            .count(),
        2
    );
}

/// The fixture with what the console and report.md must also say: an input
/// warning and a zone still to grout that re-opens after its planned date.
fn fixture_with_warning_and_reopening() -> Plan {
    let mut plan = fixture();
    plan.warnings.push(groutready::schedule::Warning {
        file: "cooling.csv".into(),
        line: Some(12),
        column: Some((4, "target_c".into())),
        message: "target 4.0 °C is below the closure temperature by more than 8 °C".into(),
    });
    plan.zones[1].reopened = Some(date("2024-10-02"));
    // More failed rules than the console's last column holds on one line.
    let hopeless = &mut plan.zones[5];
    hopeless.checks.extend([
        check(Rule::Aperture, 0.2, 0.5, Some(REASON_APERTURE_32)),
        check(Rule::Cover, 3.0, 6.0, Some(REASON_COVER_32)),
        check(Rule::BottomUp, -8.0, 0.0, Some(REASON_BELOW_32)),
    ]);
    plan
}

#[test]
fn terminal_table_lists_zones_to_grout_with_limits_and_reasons_in_full() {
    let plan = fixture_with_warning_and_reopening();
    let t = report::readiness_table(&plan);
    for l in t.lines() {
        assert!(l.chars().count() <= 100, "{} chars: {l}", l.chars().count());
    }
    let line = |j: &str, z: &str, date: &str| -> &str {
        t.lines()
            .find(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                w.len() > 3 && w[0] == j && w[1] == z && w[2] == date
            })
            .unwrap_or_else(|| panic!("no line for J{j} Z{z}:\n{t}"))
    };
    // Headers a site engineer reads; each value beside the limit applied
    // (the temperature's is closure + tolerance, from the zone's check).
    let header = t.lines().next().unwrap();
    assert!(
        header.contains("Least aperture mm") && header.contains("Warmer block °C"),
        "{header}"
    );
    let sc = line("2", "2", "2024-09-20");
    assert!(
        sc.contains("0.41 < 0.50") && sc.contains("14.6 > 14.0"),
        "{sc}"
    );
    assert!(sc.contains("✗ not groutable"), "{sc}");
    assert!(sc.ends_with("aperture, temperature"), "{sc}");
    let no = line("3", "2", "2024-10-05");
    assert!(
        no.contains("0.20 < 0.50")
            && no.contains("12.2 ≤ 14.0")
            && no.ends_with("age, aperture, cover,"),
        "{no}"
    );
    // The failed rules wrap under their column rather than being cut.
    let below = t.lines().skip_while(|l| *l != no).nth(1).unwrap();
    assert_eq!(below.trim_start(), "zone below");
    let column = no[..no.find("age").unwrap()].chars().count();
    assert_eq!(below.chars().take_while(|&c| c == ' ').count(), column);
    let mg = line("2", "1", "2024-09-15");
    assert!(
        mg.contains("~ marginal ") && mg.ends_with("aperture below 0.70 mm"),
        "{mg}"
    );
    let ok = line("1", "2", "2024-09-10");
    assert!(
        ok.contains("12.8 ≤ 14.0") && ok.ends_with("✓ groutable"),
        "{ok}"
    );
    // Nothing is cut: every reason and remedy in full below the table.
    assert!(!t.contains('…'), "{t}");
    for text in [
        REASON_APERTURE_22,
        REASON_TEMP_22,
        REASON_APERTURE_31,
        REASON_AGE_32,
        REASON_COVER_32,
        REASON_BELOW_32,
        "→ remedy: supercool 1.25 °C → 0.62 mm (verified marginal, 0.61 mm)",
        "→ remedy: delay 12 d → 2024-10-13, 0.55 mm (+ zone 2) (verified marginal, 0.55 mm)",
        "→ remedy: no remedy found\n    why: neither 3 °C of supercooling nor 60 days",
    ] {
        assert!(t.contains(text), "{text:?} missing:\n{t}");
    }
    // Re-openings of planned zones, the zones already grouted (no verdict),
    // and the warnings.
    assert!(
        t.contains("joint 1 zone 2: grouted 2024-09-10, re-opens 2024-10-02 (22 days later)"),
        "{t}"
    );
    assert!(
        t.contains("Already grouted before 2024-09-01 (1 zone, history: no verdict):"),
        "{t}"
    );
    assert!(t.contains("  J1 Z1 2024-08-01\n"), "{t}");
    assert!(t.contains("joint 1 zone 1 (grouted 2024-08-01) re-opened 2024-08-20"));
    assert!(t.contains(
        "Warnings (1):\n  ! cooling.csv:12:4 (target_c): target 4.0 °C is below the closure"
    ));
    assert_eq!(
        t.lines().last().unwrap(),
        "5 zones to grout: 3 flagged (not groutable), 1 marginal; 1 grouted before 2024-09-01 (1 re-opened)"
    );
    insta::assert_snapshot!("terminal_table", t);

    // Without warnings or re-openings there is no such block.
    let plain = report::readiness_table(&fixture());
    assert!(!plain.contains("Warnings") && !plain.contains("Re-open after"));
}

/// Zones supercooled as one set (the demo's zones 4 of joints 6 to 8): the
/// console says what the set saved, and leaves the site limits the schedule
/// is past already (appended to the note, which the report keeps) to the
/// report, as for a zone supercooled alone; a zone of the set with no
/// supercooling of its own says its neighbours' supercooling fixes it.
#[test]
fn terminal_table_says_what_the_set_saved_and_leaves_the_cautions_to_the_report() {
    let together = "supercooled together with joint 3 zone 1: 1.25 °C in all against \
                    1.50 °C zone by zone (1.25 °C for this zone alone)";
    let caution = "gradient: in block 3, zone 3 above would be 4.3 °C warmer than zone 2 \
                   (4.2 without the remedy), more than 4.0 °C";
    let mut plan = fixture();
    let set = |plan: &mut Plan, delta_c: f64| {
        let z = plan
            .zones
            .iter_mut()
            .find(|z| z.zone_id() == ZoneId::new(2, 2));
        let r = z.unwrap().remedy.as_mut().unwrap();
        r.note = format!("{together}{CAUTION_MARK}{caution}");
        let o = r.supercool.as_mut().unwrap();
        o.delta_c = delta_c;
        o.together = Some(ChosenTogether {
            with: vec![ZoneId::new(3, 1)],
            zone_by_zone_c: 1.25,
            set_c: 1.25,
            set_zone_by_zone_c: 1.5,
            zone_by_zone_held: true,
        });
    };
    set(&mut plan, 1.25);
    let t = report::readiness_table(&plan);
    let flat = t.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat.contains(together), "{t}");
    assert!(!t.contains("site limit") && !t.contains("gradient"), "{t}");
    assert!(
        t.contains("→ remedy: supercool 1.25 °C → 0.62 mm (verified marginal, 0.61 mm)"),
        "{t}"
    );
    let dir = tempfile::tempdir().unwrap();
    let files = report::write_all(dir.path(), &plan).unwrap();
    let md = std::fs::read_to_string(&files.markdown).unwrap();
    assert!(md.contains(caution), "the report keeps the cautions:\n{md}");

    set(&mut plan, 0.0);
    let t = report::readiness_table(&plan);
    assert!(
        t.contains("→ remedy: none of its own: its neighbours' supercooling → 0.62 mm"),
        "{t}"
    );
}

/// A remedy's verified run of joint 2 zone 2 from the as-of date to its
/// new date, 2024-10-06, weekly: opening 0.45 → 0.70 mm, cooling 14.4 → 12.9 °C.
fn verified_run() -> ZoneHistory {
    let dates: Vec<NaiveDate> = (0..6)
        .map(|i| date("2024-09-01") + chrono::Duration::days(7 * i))
        .collect();
    let v =
        |a: f64, b: f64| -> Vec<Option<f64>> { (0..6).map(|i| Some(a + b * i as f64)).collect() };
    ZoneHistory {
        joint: 2,
        zone: 2,
        planned: date("2024-10-06"),
        dates,
        upstream: v(0.6, 0.05),
        center: v(0.55, 0.05),
        downstream: v(0.5, 0.05),
        min: v(0.45, 0.05),
        temperature: v(14.4, -0.3),
    }
}

#[test]
fn zone_chart_draws_minimum_temperature_against_its_limit_and_the_remedy() {
    let mut plan = fixture();
    let z = plan
        .zones
        .iter_mut()
        .find(|z| (z.joint, z.zone) == (2, 2))
        .unwrap();
    z.remedy.as_mut().unwrap().verified_history = Some(verified_run());
    let z = z.clone();
    let h = &plan.histories[1];
    let doc = charts::zone_chart(h, Some(&z), &plan.settings);
    balanced_tags(&doc);
    // The whole chart, to review any change of it by eye.
    insta::assert_snapshot!("zone_chart_svg", doc);
    // The minimum the aperture rule reads, the warmer block's temperature
    // against the closure and the limit the temperature rule reads, and the
    // remedy's run (opening and temperature) to its date.
    for el in [
        "<polyline class=\"min\"",
        "<polyline class=\"temperature\"",
        "<line class=\"closure\"",
        "<line class=\"temperature-limit\"",
        "<polyline class=\"remedy\"",
        "<polyline class=\"remedy-temperature\"",
        "<line class=\"remedy-date\"",
    ] {
        assert!(doc.contains(el), "{el} missing");
    }
    for text in [
        ">warmer block [°C]</text>",
        ">limit 14.0 °C = closure + tolerance</text>",
        ">closure 13.0 °C</text>",
        ">with the remedy (verified), grouted 2024-10-06</text>",
        ">✗ not groutable: aperture, temperature · remedy supercool 1.25 °C → 0.62 mm</text>",
    ] {
        assert!(doc.contains(text), "{text} missing");
    }
    // The remedy's run: its six dates, the first at 0.45 mm on the as-of date.
    let pts = attr(&doc, "<polyline class=\"remedy\"", "points");
    assert_eq!(pts.split(' ').count(), 6);
    let r = verified_run();
    let axes = charts::zone_axes(h, &plan.settings);
    let first = pts.split(' ').next().unwrap();
    let expect = format!(
        "{},{}",
        svg::px(axes.xd(date("2024-09-01"))),
        svg::px(axes.ymm(0.45))
    );
    assert_eq!(first, expect);
    // The limit line sits at 14.0 °C on the temperature panel's axes, below
    // the aperture panel.
    let t_axes = charts::temperature_axes(h, Some(&r), 13.0, 14.0);
    let y = t_axes.ymm(14.0);
    assert!(y > svg::FRAME.bottom && y < svg::TEMPERATURE_FRAME.bottom);
    assert_eq!(
        attr(&doc, "<line class=\"temperature-limit\"", "y1"),
        svg::px(y)
    );
    assert_eq!(
        attr(&doc, "<line class=\"closure\"", "y1"),
        svg::px(t_axes.ymm(13.0))
    );

    // Without a verified run there is no remedy series.
    let plain = charts::zone_chart(
        h,
        plan.zones.iter().find(|z| z.zone == 1 && z.joint == 3),
        &plan.settings,
    );
    assert!(!plain.contains("class=\"remedy"), "no remedy drawn");
}

#[test]
fn a_zone_too_warm_alone_reads_as_a_temperature_failure() {
    let plan = fixture();
    let mut z = plan.zones[3].clone();
    z.checks.retain(|c| c.rule != Rule::Aperture);
    z.remedy = None;
    let doc = charts::zone_chart(&plan.histories[1], Some(&z), &plan.settings);
    assert!(
        doc.contains(">✗ not groutable: temperature</text>"),
        "{doc}"
    );
    assert!(!doc.contains("not groutable: aperture"));
    // The terminal says the same, the opening passing its limit.
    let mut p = fixture();
    p.zones[3] = z;
    p.zones[3].apertures_mm.min = Some(0.8);
    let t = report::readiness_table(&p);
    let row = t.lines().find(|l| l.contains("2024-09-20")).unwrap();
    assert!(
        row.contains("0.80 ≥ 0.50") && row.ends_with("temperature"),
        "{row}"
    );
}

/// A plan whose mechanics was computed with opt-in approximations says so in
/// every report, with their keys; a plan on the exact path says nothing.
#[test]
fn a_plan_with_approximations_says_which_in_every_report() {
    use groutready::scene::Approximation;
    let mut plan = fixture();
    plan.approximations = vec![
        Approximation::LongerSteps { max_days: 3 },
        Approximation::MergedPours,
    ];
    let keys = "time.mechanics_max_step_days = 3, time.mechanics_merge_pours = true";
    let dir = tempfile::tempdir().unwrap();
    let files = report::write_all(dir.path(), &plan).unwrap();
    let md = read(&files.markdown);
    let summary = section(&md, "Summary");
    assert!(
        summary.contains(&format!(
            "> **Computed with opt-in approximations of the mechanics ({keys}):"
        )),
        "{summary}"
    );
    let t = report::readiness_table(&plan);
    let flat = t.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains(&format!(
            "! Computed with opt-in approximations of the mechanics ({keys}): the apertures differ"
        )),
        "{t}"
    );
    assert!(
        t.lines()
            .all(|l| l.chars().count() <= report::terminal::LINE_WIDTH),
        "{t}"
    );
    let v: serde_json::Value = serde_json::from_str(&read(&files.json)).unwrap();
    assert_eq!(
        v["approximations"],
        serde_json::json!([{"longer_steps": {"max_days": 3}}, "merged_pours"])
    );

    let (_d, exact, plain) = written();
    assert!(exact.approximations.is_empty());
    assert!(!read(&plain.markdown).contains("approximations"));
    assert!(!report::readiness_table(&exact).contains("approximations"));
    let v: serde_json::Value = serde_json::from_str(&read(&plain.json)).unwrap();
    assert_eq!(v["approximations"], serde_json::json!([]));
}
