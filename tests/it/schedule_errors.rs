//! Schedule CSV loading: exact error messages for malformed input, plus the
//! happy path and a write/load round trip.
//!
//! Every case starts from the valid set in `tests/fixtures/schedules/small`
//! (3 blocks × 6 lifts, 2 joints × 2 zones of 3 lifts), copied into a temp
//! folder, and changes one file.

use std::fs;
use std::path::{Path, PathBuf};

use chrono::NaiveDate;
use groutready::schedule::{
    check_against, check_dates, check_reservoir, load, synthesize, validate, write_dir, DamLayout,
    Schedules, Stage, SynthParams, ZoneExtent,
};
use groutready::vocab::ZonePoint;
use tempfile::TempDir;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/schedules/small")
}

/// The fixture folder copied to a temp dir.
fn copy_fixture() -> TempDir {
    let tmp = TempDir::new().unwrap();
    for entry in fs::read_dir(fixture()).unwrap() {
        let entry = entry.unwrap();
        fs::copy(entry.path(), tmp.path().join(entry.file_name())).unwrap();
    }
    tmp
}

/// Fixture with `file` replaced by `text`.
fn with_file(file: &str, text: &str) -> TempDir {
    let tmp = copy_fixture();
    fs::write(tmp.path().join(file), text).unwrap();
    tmp
}

/// Fixture with `line` appended to `file`.
fn with_line(file: &str, line: &str) -> TempDir {
    let tmp = copy_fixture();
    let mut text = fs::read_to_string(tmp.path().join(file)).unwrap();
    text.push_str(line);
    text.push('\n');
    fs::write(tmp.path().join(file), text).unwrap();
    tmp
}

fn load_err(dir: &TempDir) -> String {
    match load(dir.path()) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

/// Blocks 1–3 with 6 lifts; joints 1–2, zones 1 (lifts 1–3) and 2 (lifts 4–6).
fn layout() -> DamLayout {
    let mut zones = Vec::new();
    for joint in 1..=2 {
        for (zone, first, last) in [(1, 1, 3), (2, 4, 6)] {
            zones.push(ZoneExtent {
                joint,
                zone,
                lifts_a: (joint, first, last),
                lifts_b: (joint + 1, first, last),
            });
        }
    }
    DamLayout {
        blocks: vec![(1, 6), (2, 6), (3, 6)],
        zones,
    }
}

fn layout_err(dir: &TempDir, layout: &DamLayout) -> String {
    let s = load(dir.path()).expect("the set must load");
    match check_against(&s, layout) {
        Ok(()) => panic!("expected a layout error"),
        Err(e) => e.to_string(),
    }
}

fn d(y: i32, m: u32, day: u32) -> NaiveDate {
    NaiveDate::from_ymd_opt(y, m, day).unwrap()
}

// ---------------------------------------------------------------- cells

#[test]
fn date_wrong_format() {
    let dir = with_file(
        "pours.csv",
        "block,lift,pour_date,placement_temp_c\n1,1,2025-13-01,15\n",
    );
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:2:3 (pour_date): expected a date YYYY-MM-DD, found "2025-13-01""#
    );
}

#[test]
fn date_without_leading_zeros() {
    let dir = with_line("grouting.csv", "2,2,2025-6-1");
    assert_eq!(
        load_err(&dir),
        r#"grouting.csv:5:3 (planned_date): expected a date YYYY-MM-DD, found "2025-6-1""#
    );
}

#[test]
fn non_numeric_temperature() {
    let dir = with_file(
        "pours.csv",
        "block,lift,pour_date,placement_temp_c\n1,1,2025-01-07,warm\n",
    );
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:2:4 (placement_temp_c): expected a number (°C), found "warm""#
    );
}

#[test]
fn non_finite_temperature() {
    let dir = with_line("pours.csv", "1,7,2025-03-01,NaN");
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:20:4 (placement_temp_c): expected a finite number (°C), found "NaN""#
    );
}

#[test]
fn placement_temperature_out_of_range() {
    let dir = with_line("pours.csv", "1,7,2025-03-01,45");
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:20:4 (placement_temp_c): expected a placement temperature within 0–40 °C, found "45""#
    );
}

#[test]
fn negative_block() {
    let dir = with_line("pours.csv", "-3,1,2025-03-01,14");
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:20:1 (block): expected a whole number ≥ 1, found "-3""#
    );
}

#[test]
fn zero_zone() {
    let dir = with_line("grouting.csv", "1,0,2025-06-01");
    assert_eq!(
        load_err(&dir),
        r#"grouting.csv:5:2 (zone): expected a whole number ≥ 1, found "0""#
    );
}

#[test]
fn stage_name_unknown() {
    let dir = with_line("cooling.csv", "3,1,1,third,2025-01-20,2025-02-01,10,20");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:4 (stage): expected one of first, middle, second, extra, found "third""#
    );
}

#[test]
fn water_temperature_out_of_range() {
    let dir = with_line("cooling.csv", "3,1,1,first,2025-01-20,2025-02-01,35,40");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:7 (water_temp_c): expected a water temperature within 0–30 °C, found "35""#
    );
}

#[test]
fn end_and_target_both_blank() {
    let dir = with_line("cooling.csv", "3,1,1,first,2025-01-20,,10,");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:6 (end_date): expected an end date when target_temp_c is blank, found """#
    );
}

#[test]
fn end_before_start() {
    let dir = with_line("cooling.csv", "3,1,1,first,2025-01-20,2025-01-10,10,20");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:6 (end_date): expected a date after start_date 2025-01-20, found "2025-01-10""#
    );
}

#[test]
fn lift_from_above_lift_to() {
    let dir = with_line("cooling.csv", "3,4,2,first,2025-02-01,2025-02-20,10,20");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:3 (lift_to): expected a lift ≥ lift_from 4, found "2""#
    );
}

#[test]
fn target_not_above_water() {
    let dir = with_line("cooling.csv", "3,1,1,first,2025-01-20,,10,9.5");
    assert_eq!(
        load_err(&dir),
        r#"cooling.csv:8:8 (target_temp_c): expected a target temperature above water_temp_c 10 °C, found "9.5""#
    );
}

#[test]
fn reservoir_level_not_finite() {
    let dir = with_line("reservoir.csv", "2025-07-01,inf");
    assert_eq!(
        load_err(&dir),
        r#"reservoir.csv:4:2 (level_m): expected a finite number (m), found "inf""#
    );
}

#[test]
fn meter_point_unknown() {
    let dir = with_line("joint_meters.csv", "1,1,middle,2025-03-01,0.5");
    assert_eq!(
        load_err(&dir),
        r#"joint_meters.csv:5:3 (point): expected one of upstream, center, downstream, min, found "middle""#
    );
}

// ---------------------------------------------------------------- files, headers, field counts

#[test]
fn missing_pours_file() {
    let dir = copy_fixture();
    fs::remove_file(dir.path().join("pours.csv")).unwrap();
    assert_eq!(
        load_err(&dir),
        format!(
            "pours.csv: required file not found in \"{}\"",
            dir.path().display()
        )
    );
}

#[test]
fn header_missing_column() {
    let dir = with_file("pours.csv", "block,lift,pour_date\n1,1,2025-01-07\n");
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:1: expected header "block,lift,pour_date,placement_temp_c", found "block,lift,pour_date" (missing column "placement_temp_c")"#
    );
}

#[test]
fn header_misspelt_column() {
    let tmp = copy_fixture();
    let text = fs::read_to_string(tmp.path().join("cooling.csv")).unwrap();
    let text = text.replacen("water_temp_c", "water_c", 1);
    fs::write(tmp.path().join("cooling.csv"), text).unwrap();
    assert_eq!(
        load_err(&tmp),
        r#"cooling.csv:1: expected header "block,lift_from,lift_to,stage,start_date,end_date,water_temp_c,target_temp_c", found "block,lift_from,lift_to,stage,start_date,end_date,water_c,target_temp_c" (missing column "water_temp_c"; unexpected column "water_c")"#
    );
}

#[test]
fn header_absent() {
    let dir = with_file("grouting.csv", "1,1,2025-04-20\n");
    assert_eq!(
        load_err(&dir),
        r#"grouting.csv:1: expected header "joint,zone,planned_date", found "1,1,2025-04-20" (missing columns "joint", "zone", "planned_date"; unexpected columns "1", "1", "2025-04-20")"#
    );
}

#[test]
fn empty_file() {
    let dir = with_file("weather.csv", "\n\n");
    assert_eq!(
        load_err(&dir),
        r#"weather.csv:1: expected header "date,air_temp_c", found "" (empty file)"#
    );
}

#[test]
fn wrong_field_count() {
    let dir = with_line("pours.csv", "1,7,2025-03-01");
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:20: expected 4 fields (block,lift,pour_date,placement_temp_c), found 3 in "1,7,2025-03-01""#
    );
}

#[test]
fn line_numbers_count_blank_lines() {
    let dir = with_file(
        "pours.csv",
        "block,lift,pour_date,placement_temp_c\n\n1,1,2025-01-07,14\n   \n\n 1 , 2 , 2025-01-15 , x \n",
    );
    assert_eq!(
        load_err(&dir),
        r#"pours.csv:6:4 (placement_temp_c): expected a number (°C), found "x""#
    );
}

// ---------------------------------------------------------------- between rows

#[test]
fn lift_poured_before_lift_below() {
    let dir = with_line("pours.csv", "1,7,2025-02-10,14");
    assert_eq!(
        load_err(&dir),
        "pours.csv:20:3: block 1 lift 7 poured 2025-02-10, before lift 6 (line 13) poured 2025-02-16"
    );
}

#[test]
fn lift_poured_same_day_as_lift_below() {
    let dir = with_line("pours.csv", "1,7,2025-02-16,14");
    assert_eq!(
        load_err(&dir),
        "pours.csv:20:3: block 1 lift 7 poured 2025-02-16, the same day as lift 6 (line 13); a lift must be poured after the lift below it"
    );
}

#[test]
fn duplicate_pour() {
    let dir = with_line("pours.csv", "1,3,2025-01-23,14");
    assert_eq!(
        load_err(&dir),
        "pours.csv:20:1: duplicate row: block 1 lift 3 is already on line 10"
    );
}

#[test]
fn lift_gap() {
    let dir = with_line("pours.csv", "1,8,2025-03-01,14");
    assert_eq!(
        load_err(&dir),
        "pours.csv:20:2: block 1 lift 8 has no lift 7 below it (lifts are numbered 1, 2, 3, ... without gaps)"
    );
}

#[test]
fn duplicate_grouting() {
    let dir = with_line("grouting.csv", "1,1,2025-05-01");
    assert_eq!(
        load_err(&dir),
        "grouting.csv:5:1: duplicate row: joint 1 zone 1 is already on line 2"
    );
}

#[test]
fn cooling_before_pour() {
    let dir = with_line("cooling.csv", "3,1,2,first,2025-01-10,2025-01-30,10,20");
    assert_eq!(
        load_err(&dir),
        "cooling.csv:8:5: block 3 lifts 1-2: stage first starts 2025-01-10, before lift 2 is poured 2025-01-15 (pours.csv:15)"
    );
}

#[test]
fn cooling_of_unpoured_lift() {
    let dir = with_line("cooling.csv", "3,6,7,extra,2025-04-01,2025-04-10,10,");
    assert_eq!(
        load_err(&dir),
        "cooling.csv:8:3: block 3 lifts 6-7: stage extra starts 2025-04-01, but lift 7 is not in pours.csv"
    );
}

#[test]
fn overlapping_stages() {
    let dir = with_line("cooling.csv", "1,3,4,extra,2025-04-01,2025-04-20,10,");
    assert_eq!(
        load_err(&dir),
        "cooling.csv:8:5: block 1 lift 3: stage extra from 2025-04-01 overlaps stage second from 2025-03-01 to 2025-04-15 (line 5)"
    );
}

#[test]
fn stages_starting_the_same_day() {
    let dir = with_line("cooling.csv", "2,2,2,extra,2025-01-13,2025-01-20,10,");
    assert_eq!(
        load_err(&dir),
        "cooling.csv:8:5: block 2 lift 2: stage extra from 2025-01-13 starts on the same day as stage first (line 3)"
    );
}

#[test]
fn weather_dates_not_increasing() {
    let dir = with_line("weather.csv", "2025-01-05,3");
    assert_eq!(
        load_err(&dir),
        "weather.csv:5:1: date 2025-01-05 is before the previous date 2025-01-10 (line 4); dates must increase"
    );
}

#[test]
fn weather_duplicate_date() {
    let dir = with_line("weather.csv", "2025-01-02,3");
    assert_eq!(
        load_err(&dir),
        "weather.csv:5:1: duplicate date 2025-01-02, already on line 3"
    );
}

// ---------------------------------------------------------------- against the layout

#[test]
fn unknown_block() {
    let dir = with_line("pours.csv", "4,1,2025-03-01,14");
    assert_eq!(
        layout_err(&dir, &layout()),
        "pours.csv:20:1: block 4 is not in the dam (blocks 1-3)"
    );
}

#[test]
fn lift_above_block_top() {
    let dir = with_line("pours.csv", "1,7,2025-03-01,14");
    assert_eq!(
        layout_err(&dir, &layout()),
        "pours.csv:20:2: block 1 lift 7 is above the top of the block (lift 6)"
    );
}

#[test]
fn grouting_before_zone_exists() {
    let dir = with_line("grouting.csv", "2,2,2025-02-10");
    assert_eq!(
        layout_err(&dir, &layout()),
        "grouting.csv:5:3: joint 2 zone 2 planned 2025-02-10, before the zone exists: block 3 lift 6 is poured 2025-02-16 (pours.csv:19)"
    );
}

#[test]
fn grouting_of_unpoured_zone() {
    // Blocks 2 and 3 rise to 9 lifts; zone 3 of joint 2 (lifts 7-9) is not poured yet.
    let mut l = layout();
    l.blocks = vec![(1, 6), (2, 9), (3, 9)];
    l.zones.push(ZoneExtent {
        joint: 2,
        zone: 3,
        lifts_a: (2, 7, 9),
        lifts_b: (3, 7, 9),
    });
    let dir = with_line("grouting.csv", "2,3,2025-06-10");
    assert_eq!(
        layout_err(&dir, &l),
        "grouting.csv:5:3: joint 2 zone 3 planned 2025-06-10, before the zone exists: block 2 lift 7 is not in pours.csv"
    );
}

#[test]
fn zone_above_the_dam() {
    let dir = with_line("grouting.csv", "2,3,2025-06-10");
    assert_eq!(
        layout_err(&dir, &layout()),
        "grouting.csv:5:2: joint 2 zone 3 is above the dam (joint 2 has zones 1-2)"
    );
}

#[test]
fn zone_below_the_foundation() {
    // Joint 2 only has zone 2 (block 3 stands higher on the bank).
    let mut l = layout();
    l.zones.retain(|z| !(z.joint == 2 && z.zone == 1));
    let dir = copy_fixture();
    assert_eq!(
        layout_err(&dir, &l),
        "grouting.csv:3:2: joint 2 zone 1 is below the foundation (joint 2 has zone 2)"
    );
}

#[test]
fn joint_does_not_exist() {
    let dir = with_line("grouting.csv", "3,1,2025-06-10");
    assert_eq!(
        layout_err(&dir, &layout()),
        "grouting.csv:5:1: joint 3 does not exist (joints 1-2)"
    );
}

#[test]
fn meter_on_unknown_zone() {
    let dir = with_line("joint_meters.csv", "1,5,center,2025-03-01,0.5");
    assert_eq!(
        layout_err(&dir, &layout()),
        "joint_meters.csv:5:2: joint 1 zone 5 is above the dam (joint 1 has zones 1-2)"
    );
}

#[test]
fn invalid_layout() {
    let mut l = layout();
    l.blocks.push((2, 6));
    let s = load(&fixture()).unwrap();
    assert_eq!(
        check_against(&s, &l).unwrap_err().to_string(),
        "dam layout: block 2 is listed twice"
    );
}

// ---------------------------------------------------------------- happy path

#[test]
fn small_set_loads() {
    let s = load(&fixture()).unwrap();
    assert_eq!(s.dir, fixture());
    assert_eq!(s.pours.len(), 18);
    let p = s.pour(3, 4).unwrap();
    assert_eq!(
        (p.date, p.placement_temp_c, p.line),
        (d(2025, 1, 31), 14.5, 17)
    );

    assert_eq!(s.cooling.len(), 6);
    let middle = &s.cooling[2];
    assert_eq!(
        (middle.block, middle.lift_from, middle.lift_to, middle.stage),
        (1, 1, 3, Stage::Middle)
    );
    assert_eq!((middle.end, middle.target_temp_c), (None, Some(18.0)));
    let extra = &s.cooling[5];
    assert_eq!(extra.stage, Stage::Extra);
    assert_eq!(
        (extra.end, extra.target_temp_c),
        (Some(d(2025, 3, 20)), None)
    );
    assert_eq!(extra.line, 7);

    assert_eq!(s.grouting.len(), 3);
    assert_eq!(
        s.grouting_of(groutready::vocab::ZoneId::new(1, 2))
            .unwrap()
            .planned,
        d(2025, 6, 1)
    );
    assert_eq!(
        s.weather.as_deref(),
        Some(
            &[
                (d(2025, 1, 1), 5.5),
                (d(2025, 1, 2), 6.0),
                (d(2025, 1, 10), -2.25)
            ][..]
        )
    );
    assert_eq!(s.reservoir.as_ref().unwrap()[1], (d(2025, 6, 1), 1120.0));
    let m = s.joint_meters.as_ref().unwrap();
    assert_eq!((m[1].point, m[1].aperture_mm), (ZonePoint::Min, 0.35));
    assert_eq!(s.event_span(), Some((d(2025, 1, 5), d(2025, 6, 1))));

    check_against(&s, &layout()).unwrap();
    validate(&s).unwrap();
}

#[test]
fn optional_files_may_be_absent() {
    let dir = copy_fixture();
    for f in [
        "cooling.csv",
        "grouting.csv",
        "weather.csv",
        "reservoir.csv",
        "joint_meters.csv",
    ] {
        fs::remove_file(dir.path().join(f)).unwrap();
    }
    let s = load(dir.path()).unwrap();
    assert_eq!(s.pours.len(), 18);
    assert!(s.cooling.is_empty() && s.grouting.is_empty());
    assert!(s.weather.is_none() && s.reservoir.is_none() && s.joint_meters.is_none());
}

#[test]
fn whitespace_quotes_case_and_blank_lines() {
    let dir = with_file(
        "pours.csv",
        "\u{feff}Block , LIFT,pour_date , placement_temp_c\r\n\r\n 1 ,1, 2025-01-07,\"14\"\r\n  \r\n1,2,2025-01-15,14.25\r\n",
    );
    fs::write(
        dir.path().join("cooling.csv"),
        "block,lift_from,lift_to,stage,start_date,end_date,water_temp_c,target_temp_c\n1,1,2, First ,2025-01-15,2025-02-01,10,20\n",
    )
    .unwrap();
    fs::remove_file(dir.path().join("grouting.csv")).unwrap();
    fs::remove_file(dir.path().join("joint_meters.csv")).unwrap();
    let s = load(dir.path()).unwrap();
    assert_eq!(s.pours.len(), 2);
    assert_eq!((s.pours[1].placement_temp_c, s.pours[1].line), (14.25, 5));
    assert_eq!((s.pours[0].line, s.cooling[0].stage), (3, Stage::First));
}

/// Clears the fields `write_dir` + `load` renumber.
fn normalized(mut s: Schedules) -> Schedules {
    s.dir = PathBuf::new();
    s.pours.iter_mut().for_each(|r| r.line = 0);
    s.cooling.iter_mut().for_each(|r| r.line = 0);
    s.grouting.iter_mut().for_each(|r| r.line = 0);
    if let Some(m) = s.joint_meters.as_mut() {
        m.iter_mut().for_each(|r| r.line = 0);
    }
    s
}

#[test]
fn write_and_load_round_trip() {
    let s = load(&fixture()).unwrap();
    let out = TempDir::new().unwrap();
    let target = out.path().join("copy");
    write_dir(&s, &target).unwrap();
    let back = load(&target).unwrap();
    assert_eq!(back.dir, target);
    // The fixture has no blank lines, so even the line numbers survive.
    assert_eq!(back.pours, s.pours);
    assert_eq!(back.cooling, s.cooling);
    assert_eq!(normalized(back), normalized(s.clone()));

    // Writing a set without weather over a folder that has one is refused.
    let mut no_weather = s;
    no_weather.weather = None;
    let err = write_dir(&no_weather, &target).unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::AlreadyExists);
}

#[test]
fn synthesized_schedule_round_trips_and_fits_its_layout() {
    let l = layout();
    let s = synthesize(&l, &SynthParams::default());
    validate(&s).unwrap();
    check_against(&s, &l).unwrap();
    assert_eq!(s.pours.len(), 18);
    assert_eq!(s.grouting.len(), 4);
    let out = TempDir::new().unwrap();
    write_dir(&s, out.path()).unwrap();
    let back = load(out.path()).unwrap();
    assert_eq!(normalized(back.clone()), normalized(s.clone()));
    assert_eq!(back.cooling, s.cooling, "line numbers as written");
}

// ------------------------------------------------------- dates vs epoch

/// A lift poured before the scene's epoch is refused before the run, at its
/// cell (it used to fail 43 days in as a singular matrix); so are cooling,
/// grouting and meters dated before it.
#[test]
fn dates_before_the_epoch() {
    let s = load(&fixture()).unwrap();
    assert_eq!(check_dates(&s, d(2025, 1, 1)), Ok(()));
    assert_eq!(
        check_dates(&s, d(2025, 1, 6)).unwrap_err().to_string(),
        "pours.csv:2:3 (pour_date): expected a date on or after the scene's epoch 2025-01-06, found \"2025-01-05\""
    );
    // pours fine, the first cooling stage starts before the epoch
    let mut late_cooling = s.clone();
    late_cooling
        .pours
        .iter_mut()
        .for_each(|p| p.date = d(2025, 2, 1));
    let err = check_dates(&late_cooling, d(2025, 1, 6))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "cooling.csv:2:5 (start_date): expected a date on or after the scene's epoch 2025-01-06, found \"2025-01-05\""
    );
}

/// A date decades after the epoch is a typo, refused at its cell (a
/// grouting planned in 2099 started a 27,539-day simulation without a word).
#[test]
fn dates_decades_after_the_epoch() {
    let dir = copy_fixture();
    let path = dir.path().join("grouting.csv");
    let text = fs::read_to_string(&path)
        .unwrap()
        .replacen("2025-04-22", "2099-04-22", 1);
    fs::write(&path, text).unwrap();
    let s = load(dir.path()).unwrap();
    assert_eq!(
        check_dates(&s, d(2025, 1, 1)).unwrap_err().to_string(),
        "grouting.csv:3:3 (planned_date): expected a date within 20 years of the scene's epoch 2025-01-01 (by 2045-01-01), found \"2099-04-22\""
    );
}

/// A reservoir level far above the crest is a typo (a digit too many),
/// refused at its cell; up to a tenth of the dam's height above the crest
/// (a flood over a dam under construction) and below its base (an empty
/// reservoir) are allowed.
#[test]
fn reservoir_far_above_the_crest() {
    let s = load(with_line("reservoir.csv", "2025-09-01,11300").path()).unwrap();
    // a dam from 1000 m to 1130 m: up to 1143 m is allowed
    assert_eq!(
        check_reservoir(&s, 1000.0, 1130.0).unwrap_err().to_string(),
        "reservoir.csv:4:2 (level_m): expected a level at most 1143 m (the dam's crest is at 1130 m, its base at 1000 m), found \"11300\""
    );
    let s = load(with_line("reservoir.csv", "2025-09-01,1143").path()).unwrap();
    assert_eq!(check_reservoir(&s, 1000.0, 1130.0), Ok(()));
    let s = load(with_line("reservoir.csv", "2025-09-01,900").path()).unwrap();
    assert_eq!(check_reservoir(&s, 1000.0, 1130.0), Ok(()));
}

#[test]
fn a_ten_megabyte_line_is_quoted_in_short() {
    let line = "x".repeat(10_000_000);
    let dir = with_file("pours.csv", &format!("{line}\n"));
    let e = load_err(&dir);
    assert_eq!(
        e,
        format!(
            r#"pours.csv:1: expected header "block,lift,pour_date,placement_temp_c", found "{}… (10000000 characters)" (missing columns "block", "lift", "pour_date", "placement_temp_c"; unexpected column "{}… (10000000 characters)")"#,
            "x".repeat(120),
            "x".repeat(120)
        )
    );
}

#[test]
fn a_long_cell_is_quoted_in_short() {
    let dir = with_line("pours.csv", &format!("3,7,{},15", "9".repeat(5000)));
    assert_eq!(
        load_err(&dir),
        format!(
            r#"pours.csv:20:3 (pour_date): expected a date YYYY-MM-DD, found "{}… (5000 characters)""#,
            "9".repeat(120)
        )
    );
}

#[test]
fn text_that_is_not_utf8_names_its_line_and_column() {
    let tmp = copy_fixture();
    let path = tmp.path().join("pours.csv");
    let mut bytes = fs::read(&path).unwrap();
    bytes.extend_from_slice(b"3,7,2025-06-01,1\xe9\n");
    fs::write(&path, bytes).unwrap();
    assert_eq!(
        load_err(&tmp),
        "pours.csv:20:17: expected UTF-8 text (save the file as CSV UTF-8)"
    );
}

#[test]
fn cooling_water_not_colder_than_the_concrete_is_a_warning() {
    let dir = with_line("cooling.csv", "3,1,1,first,2025-01-20,2025-02-01,25,30");
    let s = load(dir.path()).unwrap();
    let w: Vec<String> = groutready::schedule::warnings(&s)
        .iter()
        .map(|w| w.to_string())
        .collect();
    assert_eq!(
        w,
        ["cooling.csv:8:7 (water_temp_c): water at 25 °C is not colder than block 3 lift 1 placed at 14.5 °C (pours.csv:14): the pipes warm that concrete until its hydration heat takes it past the water"]
    );
    assert!(groutready::schedule::warnings(&load(&fixture()).unwrap()).is_empty());
}

#[test]
fn the_shipped_schedules_raise_no_warning() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("schedules");
    for site in ["demo_arch", "small_dam", "two_blocks", "xiaowan_like"] {
        let s = load(&root.join(site)).unwrap();
        let w = groutready::schedule::warnings(&s);
        assert!(
            w.is_empty(),
            "{site}: {:?}",
            w.first().map(|w| w.to_string())
        );
    }
}

/// A row with the same block, lifts and stage as a row ending on its start
/// date continues that stage with new water (its clock kept): the two rows
/// are one stage, and an unrelated row on another day is not.
#[test]
fn a_row_continuing_a_stage_is_a_water_change_inside_it() {
    let dir = with_line("cooling.csv", "1,1,3,second,2025-04-15,2025-05-01,6,11");
    let s = load(dir.path()).unwrap();
    let chains = groutready::schedule::cooling_chains(&s.cooling);
    let lines = |chain: &Vec<usize>| chain.iter().map(|&i| s.cooling[i].line).collect::<Vec<_>>();
    let long: Vec<Vec<usize>> = chains.iter().filter(|c| c.len() > 1).map(lines).collect();
    assert_eq!(long, [vec![5, 8]]);
    assert_eq!(chains.len(), s.cooling.len() - 1);
    // A day later it is a new stage of its own.
    let dir = with_line("cooling.csv", "1,1,3,second,2025-04-16,2025-05-01,6,11");
    let s = load(dir.path()).unwrap();
    assert!(groutready::schedule::cooling_chains(&s.cooling)
        .iter()
        .all(|c| c.len() == 1));
}
