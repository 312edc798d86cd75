//! `temperatures.csv`: `joint,zone,point,date,day,temperature_c`, one row per
//! grouting-zone point and recorded whole day, from the day its concrete exists.

use std::io::{self, Write};
use std::path::Path;

use chrono::NaiveDate;

use crate::mesh::PointKind;
use crate::sim::ZoneRecords;

pub fn point_name(kind: PointKind) -> &'static str {
    match kind {
        PointKind::Upstream => "upstream",
        PointKind::Center => "center",
        PointKind::Downstream => "downstream",
    }
}

pub fn write(path: &Path, epoch: NaiveDate, records: &ZoneRecords) -> io::Result<usize> {
    let mut w = io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "joint,zone,point,date,day,temperature_c")?;
    let mut rows = 0;
    for (col, &(joint, zone, kind)) in records.points.iter().enumerate() {
        for (day, values) in &records.rows {
            let v = values[col];
            if v.is_nan() {
                continue;
            }
            let date = epoch + chrono::Duration::days(*day as i64);
            writeln!(w, "{joint},{zone},{},{date},{day},{v:.4}", point_name(kind))?;
            rows += 1;
        }
    }
    w.flush()?;
    Ok(rows)
}
