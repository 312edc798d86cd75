//! Reading the CSV files: header, field count and cell syntax. Value ranges
//! and cross-row rules live in `check.rs`.

use std::path::Path;

use chrono::NaiveDate;

use crate::vocab::ZonePoint;

use super::check;
use super::error::ScheduleError;
use super::{
    CoolingStage, GroutingPlan, JointMeter, Pour, Schedules, Stage, COOLING_CSV, COOLING_HEADER,
    GROUTING_CSV, GROUTING_HEADER, GROUTING_HEADER_STATUS, JOINT_METERS_CSV, JOINT_METERS_HEADER,
    POURS_CSV, POURS_HEADER, RESERVOIR_CSV, RESERVOIR_HEADER, WEATHER_CSV, WEATHER_HEADER,
};

/// The data rows of one file, fields trimmed, blank lines dropped.
pub(crate) struct Table {
    pub file: &'static str,
    pub header: &'static [&'static str],
    pub rows: Vec<RawRow>,
}

pub(crate) struct RawRow {
    /// 1-based line where the record starts.
    pub line: usize,
    pub fields: Vec<String>,
}

/// Reads `dir/file`. `Ok(None)` when the file is absent and not required.
pub(crate) fn read_table(
    dir: &Path,
    file: &'static str,
    header: &'static [&'static str],
    required: bool,
) -> Result<Option<Table>, ScheduleError> {
    read_table_alt(dir, file, &[header], required)
}

/// [`read_table`] for a file whose header may be any of `headers` (the
/// first is the one error messages name).
pub(crate) fn read_table_alt(
    dir: &Path,
    file: &'static str,
    headers: &[&'static [&'static str]],
    required: bool,
) -> Result<Option<Table>, ScheduleError> {
    let path = dir.join(file);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if required {
                return Err(ScheduleError::MissingFile {
                    file: file.to_string(),
                    dir: dir.to_path_buf(),
                });
            }
            return Ok(None);
        }
        Err(e) => {
            return Err(ScheduleError::Io {
                file: file.to_string(),
                path,
                message: e.to_string(),
            })
        }
    };
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) => t,
        Err(e) => {
            let valid = &bytes[..e.valid_up_to()];
            let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
            let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            // Column in characters: the bytes before the bad one are UTF-8.
            let column = 1 + String::from_utf8_lossy(&valid[line_start..])
                .chars()
                .count();
            return Err(ScheduleError::row(
                file,
                line,
                column,
                "expected UTF-8 text (save the file as CSV UTF-8)",
            ));
        }
    };
    parse_table_alt(text, file, headers).map(Some)
}

/// Parses CSV text (for tests).
#[cfg(test)]
pub(crate) fn parse_table(
    text: &str,
    file: &'static str,
    header: &'static [&'static str],
) -> Result<Table, ScheduleError> {
    parse_table_alt(text, file, &[header])
}

fn parse_table_alt(
    text: &str,
    file: &'static str,
    headers: &[&'static [&'static str]],
) -> Result<Table, ScheduleError> {
    let mut header = headers[0];
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut header_seen = false;
    let mut rows = Vec::new();
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e
                    .position()
                    .map(|p| line_at(text, p.byte() as usize))
                    .unwrap_or(rows.last().map_or(1, |r: &RawRow| r.line + 1));
                return Err(ScheduleError::row(
                    file,
                    line,
                    1,
                    format!("expected a CSV record ({e})"),
                ));
            }
        }
        let line = record
            .position()
            .map_or(1, |p| line_at(text, p.byte() as usize));
        let fields: Vec<String> = record
            .iter()
            .map(|f| f.trim_start_matches('\u{feff}').trim().to_string())
            .collect();
        if fields.iter().all(|f| f.is_empty()) {
            continue; // blank (or whitespace-only) line
        }
        if !header_seen {
            if let Some(h) = headers.iter().find(|h| h.len() == fields.len()) {
                header = h;
            }
            check_header(file, header, line, &fields)?;
            header_seen = true;
            continue;
        }
        if fields.len() != header.len() {
            return Err(ScheduleError::FieldCount {
                file: file.to_string(),
                line,
                expected: header.len(),
                found: fields.len(),
                header: header.join(","),
                text: ScheduleError::excerpt(&fields.join(",")),
            });
        }
        rows.push(RawRow { line, fields });
    }
    if !header_seen {
        return Err(ScheduleError::Header {
            file: file.to_string(),
            line: 1,
            expected: header.join(","),
            found: String::new(),
            detail: " (empty file)".to_string(),
        });
    }
    Ok(Table { file, header, rows })
}

/// 1-based line of the first character at or after byte `offset` that is not
/// a line break (the csv reader may report a record's start before the blank
/// lines it skipped, and its own line counter misses some of them).
pub(crate) fn line_at(text: &str, offset: usize) -> usize {
    let bytes = text.as_bytes();
    let mut at = offset.min(bytes.len());
    while at < bytes.len() && (bytes[at] == b'\n' || bytes[at] == b'\r') {
        at += 1;
    }
    1 + bytes[..at].iter().filter(|&&b| b == b'\n').count()
}

fn check_header(
    file: &str,
    header: &[&str],
    line: usize,
    fields: &[String],
) -> Result<(), ScheduleError> {
    let same = fields.len() == header.len()
        && fields
            .iter()
            .zip(header)
            .all(|(f, h)| f.eq_ignore_ascii_case(h));
    if same {
        return Ok(());
    }
    let has = |name: &str| fields.iter().any(|f| f.eq_ignore_ascii_case(name));
    let mut notes = Vec::new();
    let missing: Vec<String> = header
        .iter()
        .filter(|h| !has(h))
        .map(|h| format!("\"{h}\""))
        .collect();
    if !missing.is_empty() {
        let s = if missing.len() > 1 { "s" } else { "" };
        notes.push(format!("missing column{s} {}", missing.join(", ")));
    }
    let unexpected: Vec<String> = fields
        .iter()
        .filter(|f| !header.iter().any(|h| f.eq_ignore_ascii_case(h)))
        .map(|f| format!("{:?}", ScheduleError::excerpt(f)))
        .collect();
    if !unexpected.is_empty() {
        let s = if unexpected.len() > 1 { "s" } else { "" };
        let shown = unexpected.len().min(UNEXPECTED_SHOWN);
        let more = match unexpected.len() - shown {
            0 => String::new(),
            n => format!(" and {n} more"),
        };
        notes.push(format!(
            "unexpected column{s} {}{more}",
            unexpected[..shown].join(", ")
        ));
    }
    if notes.is_empty() {
        if fields.len() != header.len() {
            notes.push("repeated column".to_string());
        } else {
            notes.push("columns out of order".to_string());
        }
    }
    Err(ScheduleError::Header {
        file: file.to_string(),
        line,
        expected: header.join(","),
        found: ScheduleError::excerpt(&fields.join(",")),
        detail: format!(" ({})", notes.join("; ")),
    })
}

/// Typed access to the cells of one data row.
pub(crate) struct Cells<'a> {
    file: &'static str,
    header: &'static [&'static str],
    row: &'a RawRow,
}

impl<'a> Cells<'a> {
    pub fn new(table: &Table, row: &'a RawRow) -> Self {
        Cells {
            file: table.file,
            header: table.header,
            row,
        }
    }

    pub fn line(&self) -> usize {
        self.row.line
    }

    /// Trimmed text of 0-based column `col`.
    pub fn text(&self, col: usize) -> &str {
        self.row.fields.get(col).map_or("", |s| s.as_str())
    }

    /// A cell error for 0-based column `col`.
    pub fn err(&self, col: usize, expected: impl Into<String>) -> ScheduleError {
        cell_error(
            self.file,
            self.header,
            self.row.line,
            col,
            expected,
            self.text(col),
        )
    }

    /// Whole number ≥ 1 (block, lift, joint, zone).
    pub fn id(&self, col: usize) -> Result<u32, ScheduleError> {
        parse_id(self.text(col)).ok_or_else(|| self.err(col, EXPECTED_ID))
    }

    pub fn date(&self, col: usize) -> Result<NaiveDate, ScheduleError> {
        parse_date(self.text(col)).ok_or_else(|| self.err(col, EXPECTED_DATE))
    }

    pub fn opt_date(&self, col: usize) -> Result<Option<NaiveDate>, ScheduleError> {
        if self.text(col).is_empty() {
            Ok(None)
        } else {
            self.date(col).map(Some)
        }
    }

    /// Finite number; `unit` is shown in the message (`°C`, `m`, `mm`).
    pub fn number(&self, col: usize, unit: &str) -> Result<f64, ScheduleError> {
        match self.text(col).parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(self.err(col, format!("expected a finite number ({unit})"))),
            Err(_) => Err(self.err(col, format!("expected a number ({unit})"))),
        }
    }

    pub fn opt_number(&self, col: usize, unit: &str) -> Result<Option<f64>, ScheduleError> {
        if self.text(col).is_empty() {
            Ok(None)
        } else {
            self.number(col, unit).map(Some)
        }
    }
}

/// Unexpected header columns named in an error; the rest are counted.
const UNEXPECTED_SHOWN: usize = 5;

pub(crate) const EXPECTED_ID: &str = "expected a whole number ≥ 1";
pub(crate) const EXPECTED_DATE: &str = "expected a date YYYY-MM-DD";

pub(crate) fn cell_error(
    file: &str,
    header: &[&str],
    line: usize,
    col: usize,
    expected: impl Into<String>,
    found: &str,
) -> ScheduleError {
    ScheduleError::Cell {
        file: file.to_string(),
        line,
        column: col + 1,
        name: header.get(col).copied().unwrap_or("?").to_string(),
        expected: expected.into(),
        found: ScheduleError::excerpt(found),
    }
}

fn parse_id(text: &str) -> Option<u32> {
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse::<u32>().ok().filter(|&v| v >= 1)
}

/// Strict ISO date: exactly `YYYY-MM-DD`.
pub(crate) fn parse_date(text: &str) -> Option<NaiveDate> {
    let b = text.as_bytes();
    let shape = b.len() == 10
        && b.iter().enumerate().all(|(i, &c)| {
            if i == 4 || i == 7 {
                c == b'-'
            } else {
                c.is_ascii_digit()
            }
        });
    if !shape {
        return None;
    }
    let y = text[0..4].parse().ok()?;
    let m = text[5..7].parse().ok()?;
    let d = text[8..10].parse().ok()?;
    NaiveDate::from_ymd_opt(y, m, d)
}

fn pours(t: &Table) -> Result<Vec<Pour>, ScheduleError> {
    let mut out = Vec::with_capacity(t.rows.len());
    for r in &t.rows {
        let c = Cells::new(t, r);
        let p = Pour {
            block: c.id(0)?,
            lift: c.id(1)?,
            date: c.date(2)?,
            placement_temp_c: c.number(3, "°C")?,
            line: c.line(),
        };
        check::pour_values(&p, &|i| c.text(i).to_string())?;
        out.push(p);
    }
    Ok(out)
}

fn cooling(t: &Table) -> Result<Vec<CoolingStage>, ScheduleError> {
    let mut out = Vec::with_capacity(t.rows.len());
    for r in &t.rows {
        let c = Cells::new(t, r);
        let block = c.id(0)?;
        let lift_from = c.id(1)?;
        let lift_to = c.id(2)?;
        let stage = Stage::parse(c.text(3))
            .ok_or_else(|| c.err(3, "expected one of first, middle, second, extra"))?;
        let s = CoolingStage {
            block,
            lift_from,
            lift_to,
            stage,
            start: c.date(4)?,
            end: c.opt_date(5)?,
            water_temp_c: c.number(6, "°C")?,
            target_temp_c: c.opt_number(7, "°C")?,
            line: c.line(),
        };
        check::cooling_values(&s, &|i| c.text(i).to_string())?;
        out.push(s);
    }
    Ok(out)
}

fn grouting(t: &Table) -> Result<Vec<GroutingPlan>, ScheduleError> {
    let mut out = Vec::with_capacity(t.rows.len());
    for r in &t.rows {
        let c = Cells::new(t, r);
        out.push(GroutingPlan {
            joint: c.id(0)?,
            zone: c.id(1)?,
            planned: c.date(2)?,
            done: match t.header.len() {
                4 => match c.text(3).to_ascii_lowercase().as_str() {
                    "done" => true,
                    "planned" | "" => false,
                    _ => return Err(c.err(3, "expected done, planned or blank")),
                },
                _ => false,
            },
            line: c.line(),
        });
    }
    Ok(out)
}

/// `(line, date, value)` rows of weather.csv / reservoir.csv.
fn series(t: &Table, unit: &str) -> Result<Vec<(usize, NaiveDate, f64)>, ScheduleError> {
    let mut out = Vec::with_capacity(t.rows.len());
    for r in &t.rows {
        let c = Cells::new(t, r);
        let date = c.date(0)?;
        let value = c.number(1, unit)?;
        check::series_value(t.file, c.line(), value, c.text(1))?;
        out.push((c.line(), date, value));
    }
    Ok(out)
}

fn meters(t: &Table) -> Result<Vec<JointMeter>, ScheduleError> {
    let mut out = Vec::with_capacity(t.rows.len());
    for r in &t.rows {
        let c = Cells::new(t, r);
        let joint = c.id(0)?;
        let zone = c.id(1)?;
        let point = ZonePoint::parse(c.text(2))
            .ok_or_else(|| c.err(2, "expected one of upstream, center, downstream, min"))?;
        out.push(JointMeter {
            joint,
            zone,
            point,
            date: c.date(3)?,
            aperture_mm: c.number(4, "mm")?,
            line: c.line(),
        });
    }
    Ok(out)
}

pub(crate) fn load_dir(dir: &Path) -> Result<Schedules, ScheduleError> {
    let pours = match read_table(dir, POURS_CSV, &POURS_HEADER, true)? {
        Some(t) => pours(&t)?,
        None => {
            return Err(ScheduleError::MissingFile {
                file: POURS_CSV.to_string(),
                dir: dir.to_path_buf(),
            })
        }
    };
    check::check_pours(&pours)?;

    let cooling = match read_table(dir, COOLING_CSV, &COOLING_HEADER, false)? {
        Some(t) => cooling(&t)?,
        None => Vec::new(),
    };
    check::check_cooling(&cooling, &pours)?;

    let grouting = match read_table_alt(
        dir,
        GROUTING_CSV,
        &[&GROUTING_HEADER, &GROUTING_HEADER_STATUS],
        false,
    )? {
        Some(t) => grouting(&t)?,
        None => Vec::new(),
    };
    check::check_grouting(&grouting)?;

    let mut weather = None;
    if let Some(t) = read_table(dir, WEATHER_CSV, &WEATHER_HEADER, false)? {
        let rows = series(&t, "°C")?;
        check::check_series(WEATHER_CSV, rows.iter().map(|r| (r.0, r.1)))?;
        weather = Some(rows.into_iter().map(|r| (r.1, r.2)).collect());
    }

    let mut reservoir = None;
    if let Some(t) = read_table(dir, RESERVOIR_CSV, &RESERVOIR_HEADER, false)? {
        let rows = series(&t, "m")?;
        check::check_series(RESERVOIR_CSV, rows.iter().map(|r| (r.0, r.1)))?;
        reservoir = Some(rows.into_iter().map(|r| (r.1, r.2)).collect());
    }

    let mut joint_meters = None;
    if let Some(t) = read_table(dir, JOINT_METERS_CSV, &JOINT_METERS_HEADER, false)? {
        let rows = meters(&t)?;
        check::check_meters(&rows)?;
        joint_meters = Some(rows);
    }

    Ok(Schedules {
        dir: dir.to_path_buf(),
        pours,
        cooling,
        grouting,
        weather,
        reservoir,
        joint_meters,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strict_dates() {
        assert_eq!(
            parse_date("2025-03-01"),
            NaiveDate::from_ymd_opt(2025, 3, 1)
        );
        for bad in [
            "2025-3-01",
            "2025-13-01",
            "2025-02-30",
            "25-03-01",
            "2025/03/01",
            "",
        ] {
            assert_eq!(parse_date(bad), None, "{bad}");
        }
    }

    #[test]
    fn ids() {
        assert_eq!(parse_id("12"), Some(12));
        for bad in ["0", "-3", "+3", "1.0", "", "4294967296", "x"] {
            assert_eq!(parse_id(bad), None, "{bad}");
        }
    }

    #[test]
    fn blank_lines_bom_and_crlf() {
        let text = "\u{feff}block, lift ,pour_date,placement_temp_c\r\n\r\n  \r\n1,1,2025-01-01,15\r\n\r\n1, 2 ,2025-01-09, 14.5 \r\n";
        let t = parse_table(text, POURS_CSV, &POURS_HEADER).unwrap();
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[0].line, 4);
        assert_eq!(t.rows[1].line, 6);
        assert_eq!(t.rows[1].fields, vec!["1", "2", "2025-01-09", "14.5"]);
    }
}
