//! Value ranges of single rows and the rules between rows.
//!
//! The value checks take a `found(col)` closure giving the text to quote for
//! 0-based column `col`: the original cell text when loading, the written
//! form when validating an in-memory [`Schedules`].

use std::collections::{BTreeMap, HashMap};

use chrono::NaiveDate;

use crate::vocab::ZoneId;

use super::error::ScheduleError;
use super::read::{cell_error, EXPECTED_ID};
use super::warning::Warning;
use super::write;
use super::{
    CoolingStage, GroutingPlan, JointMeter, Pour, Schedules, COOLING_CSV, COOLING_HEADER,
    GROUTING_CSV, GROUTING_HEADER, JOINT_METERS_CSV, JOINT_METERS_HEADER, POURS_CSV, POURS_HEADER,
    RESERVOIR_CSV, RESERVOIR_HEADER, WEATHER_CSV, WEATHER_HEADER,
};

/// Placement temperature range, °C.
pub(crate) const PLACEMENT_RANGE_C: (f64, f64) = (0.0, 40.0);
/// Cooling water temperature range, °C.
pub(crate) const WATER_RANGE_C: (f64, f64) = (0.0, 30.0);
/// Cooling target temperature range, °C.
pub(crate) const TARGET_RANGE_C: (f64, f64) = (0.0, 40.0);
/// Air temperature range, °C.
pub(crate) const AIR_RANGE_C: (f64, f64) = (-60.0, 60.0);

type Found<'a> = &'a dyn Fn(usize) -> String;

fn within(x: f64, r: (f64, f64)) -> bool {
    x.is_finite() && r.0 <= x && x <= r.1
}

fn id_ok(
    file: &str,
    header: &[&str],
    line: usize,
    col: usize,
    v: u32,
    found: Found,
) -> Result<(), ScheduleError> {
    if v >= 1 {
        Ok(())
    } else {
        Err(cell_error(
            file,
            header,
            line,
            col,
            EXPECTED_ID,
            &found(col),
        ))
    }
}

pub(crate) fn pour_values(p: &Pour, found: Found) -> Result<(), ScheduleError> {
    let h = &POURS_HEADER;
    id_ok(POURS_CSV, h, p.line, 0, p.block, found)?;
    id_ok(POURS_CSV, h, p.line, 1, p.lift, found)?;
    if !within(p.placement_temp_c, PLACEMENT_RANGE_C) {
        return Err(cell_error(
            POURS_CSV,
            h,
            p.line,
            3,
            "expected a placement temperature within 0–40 °C",
            &found(3),
        ));
    }
    Ok(())
}

pub(crate) fn cooling_values(c: &CoolingStage, found: Found) -> Result<(), ScheduleError> {
    let h = &COOLING_HEADER;
    let err = |col: usize, expected: String| {
        cell_error(COOLING_CSV, h, c.line, col, expected, &found(col))
    };
    id_ok(COOLING_CSV, h, c.line, 0, c.block, found)?;
    id_ok(COOLING_CSV, h, c.line, 1, c.lift_from, found)?;
    id_ok(COOLING_CSV, h, c.line, 2, c.lift_to, found)?;
    if c.lift_to < c.lift_from {
        return Err(err(
            2,
            format!("expected a lift ≥ lift_from {}", c.lift_from),
        ));
    }
    if let Some(end) = c.end {
        if end <= c.start {
            return Err(err(
                5,
                format!("expected a date after start_date {}", c.start),
            ));
        }
    }
    if !within(c.water_temp_c, WATER_RANGE_C) {
        return Err(err(
            6,
            "expected a water temperature within 0–30 °C".to_string(),
        ));
    }
    if let Some(t) = c.target_temp_c {
        if !within(t, TARGET_RANGE_C) {
            return Err(err(
                7,
                "expected a target temperature within 0–40 °C".to_string(),
            ));
        }
        if t <= c.water_temp_c {
            return Err(err(
                7,
                format!(
                    "expected a target temperature above water_temp_c {} °C",
                    c.water_temp_c
                ),
            ));
        }
    }
    if c.end.is_none() && c.target_temp_c.is_none() {
        return Err(err(
            5,
            "expected an end date when target_temp_c is blank".to_string(),
        ));
    }
    Ok(())
}

fn grouting_values(g: &GroutingPlan, found: Found) -> Result<(), ScheduleError> {
    id_ok(GROUTING_CSV, &GROUTING_HEADER, g.line, 0, g.joint, found)?;
    id_ok(GROUTING_CSV, &GROUTING_HEADER, g.line, 1, g.zone, found)
}

fn meter_values(m: &JointMeter, found: Found) -> Result<(), ScheduleError> {
    let h = &JOINT_METERS_HEADER;
    id_ok(JOINT_METERS_CSV, h, m.line, 0, m.joint, found)?;
    id_ok(JOINT_METERS_CSV, h, m.line, 1, m.zone, found)?;
    if !m.aperture_mm.is_finite() {
        return Err(cell_error(
            JOINT_METERS_CSV,
            h,
            m.line,
            4,
            "expected a finite number (mm)",
            &found(4),
        ));
    }
    Ok(())
}

/// Value rule of column 2 of weather.csv / reservoir.csv.
pub(crate) fn series_value(
    file: &str,
    line: usize,
    value: f64,
    found: &str,
) -> Result<(), ScheduleError> {
    if file == WEATHER_CSV {
        if !within(value, AIR_RANGE_C) {
            return Err(cell_error(
                file,
                &WEATHER_HEADER,
                line,
                1,
                "expected an air temperature within −60–60 °C",
                found,
            ));
        }
    } else if !value.is_finite() {
        return Err(cell_error(
            file,
            &super::RESERVOIR_HEADER,
            line,
            1,
            "expected a finite number (m)",
            found,
        ));
    }
    Ok(())
}

/// "lift 5" or "lifts 4-6".
pub(crate) fn lifts_label(from: u32, to: u32) -> String {
    if from == to {
        format!("lift {from}")
    } else {
        format!("lifts {from}-{to}")
    }
}

/// Duplicates, gaps, and each lift strictly after the lift below it.
pub(crate) fn check_pours(pours: &[Pour]) -> Result<(), ScheduleError> {
    let mut by_key: HashMap<(u32, u32), &Pour> = HashMap::with_capacity(pours.len());
    for p in pours {
        if let Some(first) = by_key.get(&(p.block, p.lift)) {
            return Err(ScheduleError::row(
                POURS_CSV,
                p.line,
                1,
                format!(
                    "duplicate row: block {} lift {} is already on line {}",
                    p.block, p.lift, first.line
                ),
            ));
        }
        by_key.insert((p.block, p.lift), p);
    }
    for p in pours.iter().filter(|p| p.lift > 1) {
        if !by_key.contains_key(&(p.block, p.lift - 1)) {
            return Err(ScheduleError::row(
                POURS_CSV,
                p.line,
                2,
                format!(
                    "block {} lift {} has no lift {} below it (lifts are numbered 1, 2, 3, ... without gaps)",
                    p.block,
                    p.lift,
                    p.lift - 1
                ),
            ));
        }
    }
    for p in pours.iter().filter(|p| p.lift > 1) {
        let Some(below) = by_key.get(&(p.block, p.lift - 1)) else {
            continue;
        };
        if p.date < below.date {
            return Err(ScheduleError::row(
                POURS_CSV,
                p.line,
                3,
                format!(
                    "block {} lift {} poured {}, before lift {} (line {}) poured {}",
                    p.block, p.lift, p.date, below.lift, below.line, below.date
                ),
            ));
        }
        if p.date == below.date {
            return Err(ScheduleError::row(
                POURS_CSV,
                p.line,
                3,
                format!(
                    "block {} lift {} poured {}, the same day as lift {} (line {}); a lift must be poured after the lift below it",
                    p.block, p.lift, p.date, below.lift, below.line
                ),
            ));
        }
    }
    Ok(())
}

/// Every cooled lift poured on or before the stage start; no overlapping
/// stages on a lift (see the module documentation for open-ended stages).
pub(crate) fn check_cooling(cooling: &[CoolingStage], pours: &[Pour]) -> Result<(), ScheduleError> {
    let by_key: HashMap<(u32, u32), &Pour> = pours.iter().map(|p| ((p.block, p.lift), p)).collect();
    for c in cooling {
        // Bounded: stops at the first lift that is not poured.
        for lift in c.lift_from..=c.lift_to {
            let what = format!(
                "block {} {}: stage {} starts {}",
                c.block,
                lifts_label(c.lift_from, c.lift_to),
                c.stage,
                c.start
            );
            match by_key.get(&(c.block, lift)) {
                None => {
                    return Err(ScheduleError::row(
                        COOLING_CSV,
                        c.line,
                        if lift == c.lift_from { 2 } else { 3 },
                        format!("{what}, but lift {lift} is not in {POURS_CSV}"),
                    ))
                }
                Some(p) if p.date > c.start => {
                    return Err(ScheduleError::row(
                        COOLING_CSV,
                        c.line,
                        5,
                        format!(
                            "{what}, before lift {lift} is poured {} ({POURS_CSV}:{})",
                            p.date, p.line
                        ),
                    ))
                }
                Some(_) => {}
            }
        }
    }

    // Stages per lift. All lifts are poured here, so the ranges are bounded.
    let mut by_lift: BTreeMap<(u32, u32), Vec<&CoolingStage>> = BTreeMap::new();
    for c in cooling {
        for lift in c.lift_from..=c.lift_to {
            by_lift.entry((c.block, lift)).or_default().push(c);
        }
    }
    // Report the conflict whose later row comes first in the file.
    let mut worst: Option<(usize, ScheduleError)> = None;
    for ((block, lift), mut stages) in by_lift {
        stages.sort_by_key(|c| (c.start, c.line));
        for w in stages.windows(2) {
            let (a, b) = (w[0], w[1]);
            let message = if a.start == b.start {
                Some(format!(
                    "block {block} lift {lift}: stage {} from {} starts on the same day as stage {} (line {})",
                    b.stage, b.start, a.stage, a.line
                ))
            } else {
                match a.end {
                    Some(end) if b.start < end => Some(format!(
                        "block {block} lift {lift}: stage {} from {} overlaps stage {} from {} to {} (line {})",
                        b.stage, b.start, a.stage, a.start, end, a.line
                    )),
                    _ => None,
                }
            };
            if let Some(message) = message {
                if worst.as_ref().is_none_or(|(line, _)| b.line < *line) {
                    worst = Some((b.line, ScheduleError::row(COOLING_CSV, b.line, 5, message)));
                }
            }
        }
    }
    match worst {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

pub(crate) fn check_grouting(grouting: &[GroutingPlan]) -> Result<(), ScheduleError> {
    let mut seen: HashMap<ZoneId, usize> = HashMap::with_capacity(grouting.len());
    for g in grouting {
        if let Some(first) = seen.insert(g.zone_id(), g.line) {
            return Err(ScheduleError::row(
                GROUTING_CSV,
                g.line,
                1,
                format!(
                    "duplicate row: joint {} zone {} is already on line {first}",
                    g.joint, g.zone
                ),
            ));
        }
    }
    Ok(())
}

/// No duplicate date, dates strictly increasing (in file order).
pub(crate) fn check_series(
    file: &str,
    rows: impl Iterator<Item = (usize, NaiveDate)> + Clone,
) -> Result<(), ScheduleError> {
    let mut seen: HashMap<NaiveDate, usize> = HashMap::new();
    for (line, date) in rows.clone() {
        if let Some(first) = seen.insert(date, line) {
            return Err(ScheduleError::row(
                file,
                line,
                1,
                format!("duplicate date {date}, already on line {first}"),
            ));
        }
    }
    let mut prev: Option<(usize, NaiveDate)> = None;
    for (line, date) in rows {
        if let Some((pline, pdate)) = prev {
            if date <= pdate {
                return Err(ScheduleError::row(
                    file,
                    line,
                    1,
                    format!(
                        "date {date} is before the previous date {pdate} (line {pline}); dates must increase"
                    ),
                ));
            }
        }
        prev = Some((line, date));
    }
    Ok(())
}

pub(crate) fn check_meters(meters: &[JointMeter]) -> Result<(), ScheduleError> {
    let mut seen = HashMap::with_capacity(meters.len());
    for m in meters {
        if let Some(first) = seen.insert((m.joint, m.zone, m.point, m.date), m.line) {
            return Err(ScheduleError::row(
                JOINT_METERS_CSV,
                m.line,
                1,
                format!(
                    "duplicate row: joint {} zone {} point {} on {} is already on line {first}",
                    m.joint, m.zone, m.point, m.date
                ),
            ));
        }
    }
    Ok(())
}

/// Runs every check of [`super::load`] on an in-memory schedule (a
/// synthesized or edited one), quoting the values as [`super::write_dir`]
/// would write them. Lines are the rows' `line` fields; weather and reservoir
/// rows, which carry no line, are numbered as written (first row = line 2).
pub fn validate(s: &Schedules) -> Result<(), ScheduleError> {
    for p in &s.pours {
        let f = write::pour_fields(p);
        pour_values(p, &|i| f[i].clone())?;
    }
    check_pours(&s.pours)?;
    for c in &s.cooling {
        let f = write::cooling_fields(c);
        cooling_values(c, &|i| f[i].clone())?;
    }
    check_cooling(&s.cooling, &s.pours)?;
    for g in &s.grouting {
        let f = write::grouting_fields(g, false);
        grouting_values(g, &|i| f[i].clone())?;
    }
    check_grouting(&s.grouting)?;
    for (file, series) in [(WEATHER_CSV, &s.weather), (RESERVOIR_CSV, &s.reservoir)] {
        if let Some(rows) = series {
            for (i, (_, v)) in rows.iter().enumerate() {
                series_value(file, i + 2, *v, &write::num(*v))?;
            }
            check_series(file, rows.iter().enumerate().map(|(i, r)| (i + 2, r.0)))?;
        }
    }
    if let Some(meters) = &s.joint_meters {
        for m in meters {
            let f = write::meter_fields(m);
            meter_values(m, &|i| f[i].clone())?;
        }
        check_meters(meters)?;
    }
    Ok(())
}

/// How far after the scene's epoch a scheduled date may lie \[years\]: the
/// longest dam constructions take about a decade, so a date beyond this is
/// a typo (a grouting planned in 2099 asked for a 27,539-day simulation).
pub const MAX_SCHEDULE_YEARS: i32 = 20;

/// Checks the schedule's dates against the scene's epoch: no pour, cooling
/// stage, grouting or joint meter dated before it (a lift poured before the
/// epoch otherwise failed 43 days into the run as a singular matrix), none
/// more than [`MAX_SCHEDULE_YEARS`] after it. Weather and reservoir series
/// may extend either way (they are interpolated where the run needs them).
/// The first offending row is returned, file by file.
pub fn check_dates(s: &Schedules, epoch: NaiveDate) -> Result<(), ScheduleError> {
    let latest = epoch
        .checked_add_months(chrono::Months::new(12 * MAX_SCHEDULE_YEARS as u32))
        .unwrap_or(NaiveDate::MAX);
    let check = |file: &str, header: &[&str], line: usize, col: usize, date: NaiveDate| {
        let expected = if date < epoch {
            format!("expected a date on or after the scene's epoch {epoch}")
        } else if date > latest {
            format!(
                "expected a date within {MAX_SCHEDULE_YEARS} years of the scene's epoch {epoch} (by {latest})"
            )
        } else {
            return Ok(());
        };
        Err(cell_error(
            file,
            header,
            line,
            col,
            expected,
            &date.to_string(),
        ))
    };
    for p in &s.pours {
        check(POURS_CSV, &POURS_HEADER, p.line, 2, p.date)?;
    }
    for c in &s.cooling {
        check(COOLING_CSV, &COOLING_HEADER, c.line, 4, c.start)?;
        if let Some(end) = c.end {
            check(COOLING_CSV, &COOLING_HEADER, c.line, 5, end)?;
        }
    }
    for g in &s.grouting {
        check(GROUTING_CSV, &GROUTING_HEADER, g.line, 2, g.planned)?;
    }
    for m in s.joint_meters.iter().flatten() {
        check(JOINT_METERS_CSV, &JOINT_METERS_HEADER, m.line, 3, m.date)?;
    }
    Ok(())
}

/// How far above the crest a reservoir level may lie, as a fraction of the
/// dam's height: a flood may overtop a dam under construction a little; a
/// level far above is a typo (a digit too many).
pub const MAX_LEVEL_ABOVE_CREST: f64 = 0.1;

/// Checks the reservoir levels against the dam: none more than
/// [`MAX_LEVEL_ABOVE_CREST`] of its height above its crest. A level below
/// the base is an empty reservoir, which is allowed.
pub fn check_reservoir(s: &Schedules, base_z: f64, crest_z: f64) -> Result<(), ScheduleError> {
    let highest = crest_z + MAX_LEVEL_ABOVE_CREST * (crest_z - base_z);
    for (i, &(_, level)) in s.reservoir.iter().flatten().enumerate() {
        if level > highest {
            return Err(cell_error(
                RESERVOIR_CSV,
                &RESERVOIR_HEADER,
                i + 2,
                1,
                format!(
                    "expected a level at most {highest} m (the dam's crest is at {crest_z} m, its base at {base_z} m)"
                ),
                &write::num(level),
            ));
        }
    }
    Ok(())
}

/// Inputs that are well formed and possible but questionable (the run goes
/// on; the report repeats them): a first-stage cooling whose water is not
/// colder than the placement temperature of a lift it cools. Its pipes warm
/// the fresh concrete until the hydration heat takes it past the water; a
/// site cools fresh concrete with water well below its placement
/// temperature, so this is most likely a typo. (Later stages cool concrete
/// that has warmed since its placement, so their water is compared with
/// the concrete's temperature at their start, during the run:
/// [`crate::sim::Simulation::warnings`].)
pub fn warnings(s: &Schedules) -> Vec<Warning> {
    let pours: HashMap<(u32, u32), &Pour> =
        s.pours.iter().map(|p| ((p.block, p.lift), p)).collect();
    let mut out = Vec::new();
    for c in s.cooling.iter().filter(|c| c.stage == super::Stage::First) {
        let coldest = (c.lift_from..=c.lift_to)
            .filter_map(|l| pours.get(&(c.block, l)))
            .min_by(|a, b| a.placement_temp_c.total_cmp(&b.placement_temp_c));
        let Some(p) = coldest.filter(|p| c.water_temp_c >= p.placement_temp_c) else {
            continue;
        };
        out.push(Warning::cell(
            COOLING_CSV,
            c.line,
            7,
            "water_temp_c",
            format!(
                "water at {} °C is not colder than block {} lift {} placed at {} °C ({POURS_CSV}:{}): the pipes warm that concrete until its hydration heat takes it past the water",
                write::num(c.water_temp_c),
                p.block,
                p.lift,
                write::num(p.placement_temp_c),
                p.line
            ),
        ));
    }
    out
}
