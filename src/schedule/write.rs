//! Writing a [`Schedules`] back as a CSV folder, in the formats `load` reads.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::{
    CoolingStage, GroutingPlan, JointMeter, Pour, Schedules, COOLING_CSV, COOLING_HEADER,
    GROUTING_CSV, GROUTING_HEADER, GROUTING_HEADER_STATUS, JOINT_METERS_CSV, JOINT_METERS_HEADER,
    POURS_CSV, POURS_HEADER, RESERVOIR_CSV, RESERVOIR_HEADER, WEATHER_CSV, WEATHER_HEADER,
};

/// Shortest text that parses back to the same `f64` (no exponent).
pub(crate) fn num(x: f64) -> String {
    format!("{x}")
}

pub(crate) fn pour_fields(p: &Pour) -> Vec<String> {
    vec![
        p.block.to_string(),
        p.lift.to_string(),
        p.date.to_string(),
        num(p.placement_temp_c),
    ]
}

pub(crate) fn cooling_fields(c: &CoolingStage) -> Vec<String> {
    vec![
        c.block.to_string(),
        c.lift_from.to_string(),
        c.lift_to.to_string(),
        c.stage.as_str().to_string(),
        c.start.to_string(),
        c.end.map(|d| d.to_string()).unwrap_or_default(),
        num(c.water_temp_c),
        c.target_temp_c.map(num).unwrap_or_default(),
    ]
}

pub(crate) fn grouting_fields(g: &GroutingPlan, with_status: bool) -> Vec<String> {
    let mut f = vec![
        g.joint.to_string(),
        g.zone.to_string(),
        g.planned.to_string(),
    ];
    if with_status {
        f.push(if g.done { "done" } else { "planned" }.to_string());
    }
    f
}

pub(crate) fn meter_fields(m: &JointMeter) -> Vec<String> {
    vec![
        m.joint.to_string(),
        m.zone.to_string(),
        m.point.as_str().to_string(),
        m.date.to_string(),
        num(m.aperture_mm),
    ]
}

fn csv_text(header: &[&str], rows: impl Iterator<Item = Vec<String>>) -> io::Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(header).map_err(io::Error::other)?;
    for r in rows {
        w.write_record(&r).map_err(io::Error::other)?;
    }
    w.into_inner().map_err(|e| io::Error::other(e.to_string()))
}

/// Writes `s` into `dir` (created if needed) as `pours.csv`, `cooling.csv`,
/// `grouting.csv` (always, possibly with a header only) and `weather.csv`,
/// `reservoir.csv`, `joint_meters.csv` (when present in `s`), in row order.
/// Line numbers of `s` are not used; [`super::load`] on the folder gives back
/// `s` with `dir` and `line` fields renumbered.
///
/// Refuses (error `AlreadyExists`, nothing written) when `dir` holds an
/// optional file that `s` does not carry, since loading the folder would then
/// read it. Files are written to temporary names first and renamed at the
/// end, so an I/O error leaves no half-written CSV behind.
pub fn write_dir(s: &Schedules, dir: &Path) -> io::Result<()> {
    let optional = [
        (WEATHER_CSV, s.weather.is_some()),
        (RESERVOIR_CSV, s.reservoir.is_some()),
        (JOINT_METERS_CSV, s.joint_meters.is_some()),
    ];
    for (file, present) in optional {
        if !present && dir.join(file).exists() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!(
                    "{} exists but the schedule has no {file}; write to an empty folder",
                    dir.join(file).display()
                ),
            ));
        }
    }

    let mut files: Vec<(&str, Vec<u8>)> = vec![
        (
            POURS_CSV,
            csv_text(&POURS_HEADER, s.pours.iter().map(pour_fields))?,
        ),
        (
            COOLING_CSV,
            csv_text(&COOLING_HEADER, s.cooling.iter().map(cooling_fields))?,
        ),
        (
            GROUTING_CSV,
            // The status column is written only when some zone is done.
            if s.grouting.iter().any(|g| g.done) {
                csv_text(
                    &GROUTING_HEADER_STATUS,
                    s.grouting.iter().map(|g| grouting_fields(g, true)),
                )?
            } else {
                csv_text(
                    &GROUTING_HEADER,
                    s.grouting.iter().map(|g| grouting_fields(g, false)),
                )?
            },
        ),
    ];
    let series = |rows: &Vec<(chrono::NaiveDate, f64)>| {
        rows.iter()
            .map(|(d, v)| vec![d.to_string(), num(*v)])
            .collect::<Vec<_>>()
            .into_iter()
    };
    if let Some(w) = &s.weather {
        files.push((WEATHER_CSV, csv_text(&WEATHER_HEADER, series(w))?));
    }
    if let Some(r) = &s.reservoir {
        files.push((RESERVOIR_CSV, csv_text(&RESERVOIR_HEADER, series(r))?));
    }
    if let Some(m) = &s.joint_meters {
        files.push((
            JOINT_METERS_CSV,
            csv_text(&JOINT_METERS_HEADER, m.iter().map(meter_fields))?,
        ));
    }

    fs::create_dir_all(dir)?;
    let mut written: Vec<(PathBuf, PathBuf)> = Vec::new();
    let result = (|| {
        for (file, bytes) in &files {
            let tmp = dir.join(format!(".{file}.tmp"));
            let mut f = fs::File::create(&tmp)?;
            written.push((tmp.clone(), dir.join(file)));
            f.write_all(bytes)?;
            f.sync_all()?;
        }
        Ok(())
    })();
    if let Err(e) = result {
        for (tmp, _) in &written {
            let _ = fs::remove_file(tmp);
        }
        return Err(e);
    }
    for (tmp, dest) in &written {
        fs::rename(tmp, dest)?;
    }
    Ok(())
}
