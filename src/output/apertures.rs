//! `apertures.csv`:
//! `joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa`,
//! for every grouting zone at its upstream, center and downstream points
//! (mid-zone height) and its minimum over the zone's joint points (`min`;
//! its temperature and pressure are that point's). The pressure across the
//! joint is compression positive (the VTU's `joint_pressure_mpa`): a closed
//! joint's contact pressure says how much more cooling it takes to open it
//! (about p / (E α) degrees); a grout layer in tension reads negative.
//!
//! Rows are written weekly (days that are multiples of 7 from the epoch),
//! on every grouting date and snapshot date, and on the last day; days before
//! both blocks of a zone exist are skipped. The run keeps the daily history
//! in memory for the planner.

use std::collections::BTreeSet;
use std::io::{self, Write};
use std::path::Path;

use crate::sim::JointRecords;

/// The file's name in a run folder.
pub const FILE_NAME: &str = "apertures.csv";
use crate::vocab::{Day, Epoch};

/// Writes the file; returns the number of data rows.
pub fn write(
    path: &Path,
    epoch: Epoch,
    records: &JointRecords,
    extra_days: &BTreeSet<Day>,
) -> io::Result<usize> {
    let mut w = io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(
        w,
        "joint,zone,point,date,day,aperture_mm,state,temperature_c,pressure_mpa"
    )?;
    let last = records.rows.last().map(|r| r.0);
    let keep = |day: Day| day.0 % 7 == 0 || extra_days.contains(&day) || Some(day) == last;
    let mut rows = 0;
    for (i, col) in records.columns.iter().enumerate() {
        let (joint, zone) = (col.zone.joint, col.zone.zone);
        for &(day, ref samples) in records.rows.iter().filter(|(d, _)| keep(*d)) {
            let Some(s) = samples[i] else { continue };
            let date = epoch.date(day);
            let day = day.0;
            let temp = if s.temperature.is_nan() {
                String::new()
            } else {
                format!("{:.3}", s.temperature)
            };
            writeln!(
                w,
                "{joint},{zone},{},{date},{day},{},{},{temp},{}",
                col.point.as_str(),
                four_decimals(1e3 * s.aperture),
                s.state,
                four_decimals(1e-6 * s.pressure)
            )?;
            rows += 1;
        }
    }
    w.flush()?;
    Ok(rows)
}

/// `v` to 4 decimals, a value that rounds to zero printed "0.0000" (not
/// "-0.0000": a grout layer compressed by round-off, a point at rest).
fn four_decimals(v: f64) -> String {
    format!("{:.4}", if v.abs() < 5e-5 { 0.0 } else { v })
}

#[cfg(test)]
mod tests {
    use super::four_decimals;

    #[test]
    fn a_value_rounding_to_zero_has_no_sign() {
        assert_eq!(four_decimals(-0.0), "0.0000");
        assert_eq!(four_decimals(-4e-5), "0.0000");
        assert_eq!(four_decimals(-6e-5), "-0.0001");
        assert_eq!(four_decimals(1.73774), "1.7377");
    }
}
