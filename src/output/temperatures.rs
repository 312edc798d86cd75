//! `temperatures.csv`: `joint,zone,point,date,day,temperature_c`, one row per
//! grouting-zone point and recorded whole day, from the day its concrete exists.

use std::io::{self, Write};
use std::path::Path;

use crate::sim::ZoneRecords;
use crate::vocab::Epoch;

pub fn write(path: &Path, epoch: Epoch, records: &ZoneRecords) -> io::Result<usize> {
    let mut w = io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "joint,zone,point,date,day,temperature_c")?;
    let mut rows = 0;
    for (col, &(zone, point)) in records.points.iter().enumerate() {
        let (joint, zone) = (zone.joint, zone.zone);
        for &(day, ref values) in &records.rows {
            let v = values[col];
            if v.is_nan() {
                continue;
            }
            let date = epoch.date(day);
            writeln!(w, "{joint},{zone},{point},{date},{},{v:.4}", day.0)?;
            rows += 1;
        }
    }
    w.flush()?;
    Ok(rows)
}
