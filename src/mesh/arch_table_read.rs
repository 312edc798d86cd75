//! Reading the two CSV tables of the `arch_table` generator (formats in
//! [`super::arch_table`]). Every error names the file, the line, the column
//! and what was expected, as the schedules' errors do
//! ([`crate::schedule::ScheduleError`]); lines starting with `#` are
//! comments and blank lines are skipped.

use std::collections::HashMap;
use std::path::Path;

use super::arch_curves::{ArchType, HalfArch, MAX_ANGLE};
use super::arch_table::{ArchRow, ArchTableGeometry, ArchTables};
use crate::schedule::ScheduleError;

/// An error in an arch table or valley file.
///
/// Display forms:
/// - cell: `models/x/arch.csv:7:4 (thickness_left_abutment_m): expected a thickness > 0 m, found "-3"`
/// - row: `models/x/arch.csv:9:1: elevation 1000 m is not above the previous row's 1010 m (line 8): rows go up`
/// - header: `models/x/arch.csv:1: expected the columns "elevation_m,…", found "…" (missing column "radius_left_m")`
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArchTableError {
    /// The file cannot be read.
    #[error("{file}: cannot read the table: {message}")]
    Io { file: String, message: String },
    /// The header row is absent, has an unknown or duplicate column or
    /// misses one the arch type needs.
    #[error("{file}:{line}: expected the columns \"{expected}\", found {found:?}{detail}")]
    Header {
        file: String,
        line: usize,
        expected: String,
        found: String,
        /// Empty or ` (missing column "x")`-like, with a leading space.
        detail: String,
    },
    /// A data row has the wrong number of fields.
    #[error(
        "{file}:{line}: expected {expected} fields (as the header), found {found} in {text:?}"
    )]
    FieldCount {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
        text: String,
    },
    /// One cell is malformed or out of range; `column` is 1-based.
    #[error("{file}:{line}:{column} ({name}): {expected}, found {found:?}")]
    Cell {
        file: String,
        line: usize,
        column: usize,
        name: String,
        expected: String,
        found: String,
    },
    /// A row contradicts another row or the scene (order, coverage).
    #[error("{file}:{line}:{column}: {message}")]
    Row {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
}

/// The columns every arch table has.
const BASE_COLUMNS: [&str; 7] = [
    "elevation_m",
    "crown_upstream_y_m",
    "crown_downstream_y_m",
    "thickness_left_abutment_m",
    "thickness_right_abutment_m",
    "radius_left_m",
    "radius_right_m",
];

/// The coefficient columns of each arch type.
fn type_columns(kind: ArchType) -> &'static [&'static str] {
    match kind {
        ArchType::Circular | ArchType::Parabolic => &[],
        ArchType::ThreeCentred => &[
            "outer_radius_left_m",
            "outer_radius_right_m",
            "central_half_angle_left_deg",
            "central_half_angle_right_deg",
        ],
        ArchType::Elliptical => &["axis_ratio_left", "axis_ratio_right"],
        ArchType::LogSpiral => &["spiral_growth_left", "spiral_growth_right"],
    }
}

const TYPES: [ArchType; 5] = [
    ArchType::Circular,
    ArchType::ThreeCentred,
    ArchType::Parabolic,
    ArchType::Elliptical,
    ArchType::LogSpiral,
];

const VALLEY_COLUMNS: [&str; 2] = ["crest_distance_m", "foundation_elevation_m"];

/// Reads the arch table and the valley of `g`, both relative to `scene_dir`.
pub fn load_tables(g: &ArchTableGeometry, scene_dir: &Path) -> Result<ArchTables, ArchTableError> {
    let path = scene_dir.join(&g.table);
    let file = path.display().to_string();
    let rows = parse_arch(&read(&path, &file)?, &file, g)?;
    let path = scene_dir.join(&g.valley);
    let file = path.display().to_string();
    let valley = parse_valley(&read(&path, &file)?, &file, g)?;
    Ok(ArchTables { rows, valley })
}

fn read(path: &Path, file: &str) -> Result<String, ArchTableError> {
    std::fs::read_to_string(path).map_err(|e| ArchTableError::Io {
        file: file.to_string(),
        message: e.to_string(),
    })
}

/// A table's header and data rows, with their 1-based lines.
struct Records {
    header_line: usize,
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

fn records(text: &str, file: &str) -> Result<Records, ArchTableError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut out = Records {
        header_line: 1,
        header: Vec::new(),
        rows: Vec::new(),
    };
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e.position().map_or(1, |p| record_line(text, p.byte()));
                return Err(row_err(
                    file,
                    line,
                    1,
                    format!("expected a CSV record ({e})"),
                ));
            }
        }
        let line = record.position().map_or(1, |p| record_line(text, p.byte()));
        let fields: Vec<String> = record
            .iter()
            .map(|f| f.trim_start_matches('\u{feff}').trim().to_string())
            .collect();
        if fields.iter().all(|f| f.is_empty()) {
            continue;
        }
        if out.header.is_empty() {
            out.header_line = line;
            out.header = fields;
        } else {
            out.rows.push((line, fields));
        }
    }
    Ok(out)
}

/// 1-based line of the record the csv reader says starts at byte `offset`:
/// its position may be that of the blank or comment lines it skipped first.
fn record_line(text: &str, offset: u64) -> usize {
    let mut line = crate::schedule::line_at(text, offset as usize);
    let mut lines = text.lines().skip(line - 1);
    while lines
        .next()
        .is_some_and(|l| l.trim().is_empty() || l.starts_with('#'))
    {
        line += 1;
    }
    line
}

fn row_err(file: &str, line: usize, column: usize, message: impl Into<String>) -> ArchTableError {
    ArchTableError::Row {
        file: file.to_string(),
        line,
        column,
        message: message.into(),
    }
}

/// A data row has as many fields as the header.
fn field_count(
    file: &str,
    line: usize,
    fields: &[String],
    expected: usize,
) -> Result<(), ArchTableError> {
    if fields.len() == expected {
        return Ok(());
    }
    Err(ArchTableError::FieldCount {
        file: file.to_string(),
        line,
        expected,
        found: fields.len(),
        text: ScheduleError::excerpt(&fields.join(",")),
    })
}

/// Column index of every header name; an error for an unknown or repeated
/// name or a missing `needed` one.
fn header_map(
    r: &Records,
    file: &str,
    needed: &[&str],
    allowed: &[&str],
) -> Result<HashMap<String, usize>, ArchTableError> {
    let err = |detail: String| ArchTableError::Header {
        file: file.to_string(),
        line: r.header_line,
        expected: needed.join(","),
        found: ScheduleError::excerpt(&r.header.join(",")),
        detail,
    };
    if r.header.is_empty() {
        return Err(err(" (empty file)".to_string()));
    }
    let mut map = HashMap::new();
    for (c, name) in r.header.iter().enumerate() {
        let key = name.to_ascii_lowercase();
        if !allowed.contains(&key.as_str()) {
            return Err(err(format!(" (unknown column {name:?})")));
        }
        if map.insert(key, c).is_some() {
            return Err(err(format!(" (column {name:?} twice)")));
        }
    }
    if let Some(m) = needed.iter().find(|n| !map.contains_key(**n)) {
        return Err(err(format!(" (missing column {m:?})")));
    }
    Ok(map)
}

/// One data row with its line, for typed cell reads.
struct Line<'a> {
    file: &'a str,
    line: usize,
    fields: &'a [String],
    map: &'a HashMap<String, usize>,
}

impl Line<'_> {
    /// The number in column `name`, which must satisfy `ok` (else `expected`).
    fn num(
        &self,
        name: &str,
        expected: &str,
        ok: impl Fn(f64) -> bool,
    ) -> Result<f64, ArchTableError> {
        let c = self.map[name];
        let text = &self.fields[c];
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() && ok(v) => Ok(v),
            _ => Err(self.cell_err(c, expected, text)),
        }
    }

    fn cell_err(&self, c: usize, expected: &str, found: &str) -> ArchTableError {
        ArchTableError::Cell {
            file: self.file.to_string(),
            line: self.line,
            column: c + 1,
            name: self
                .map
                .iter()
                .find(|(_, &i)| i == c)
                .map_or(String::new(), |(n, _)| n.clone()),
            expected: expected.to_string(),
            found: ScheduleError::excerpt(found),
        }
    }
}

/// The arch table's rows, checked (module doc of [`super::arch_table`]).
fn parse_arch(
    text: &str,
    file: &str,
    g: &ArchTableGeometry,
) -> Result<Vec<ArchRow>, ArchTableError> {
    let r = records(text, file)?;
    let kind = g.arch_type;
    let mut needed: Vec<&str> = BASE_COLUMNS.to_vec();
    needed.extend(type_columns(kind));
    let mut allowed: Vec<&str> = BASE_COLUMNS.to_vec();
    TYPES.iter().for_each(|&t| allowed.extend(type_columns(t)));
    let map = header_map(&r, file, &needed, &allowed)?;
    let mut rows: Vec<(usize, ArchRow)> = Vec::with_capacity(r.rows.len());
    for (line, fields) in &r.rows {
        field_count(file, *line, fields, r.header.len())?;
        let l = Line {
            file,
            line: *line,
            fields,
            map: &map,
        };
        // another type's coefficients must be blank: a filled one is a mistake of type
        for (name, &c) in &map {
            if !needed.contains(&name.as_str()) && !fields[c].is_empty() {
                let e = format!(
                    "blank (a coefficient of another arch type; the scene's arch_type is {})",
                    kind.name()
                );
                return Err(l.cell_err(c, &e, &fields[c]));
            }
        }
        let row = arch_row(&l, kind)?;
        if let Some((prev_line, prev)) = rows.last() {
            if row.elevation_m <= prev.elevation_m {
                return Err(row_err(
                    file,
                    *line,
                    map["elevation_m"] + 1,
                    format!(
                        "elevation {} m is not above the previous row's {} m (line {prev_line}): rows go up",
                        row.elevation_m, prev.elevation_m
                    ),
                ));
            }
        }
        rows.push((*line, row));
    }
    covers(file, &rows, g, map["elevation_m"] + 1, r.header_line)?;
    Ok(rows.into_iter().map(|(_, r)| r).collect())
}

/// One row's values, each checked in its cell.
fn arch_row(l: &Line, kind: ArchType) -> Result<ArchRow, ArchTableError> {
    let any = |_: f64| true;
    let pos = |v: f64| v > 0.0;
    let z = l.num("elevation_m", "expected an elevation [m]", any)?;
    let yu = l.num("crown_upstream_y_m", "expected a y [m]", any)?;
    let yd = l.num(
        "crown_downstream_y_m",
        &format!("expected a y [m] downstream of the upstream face's {yu} m (the crown thickness y_d − y_u must be > 0)"),
        |v| v > yu,
    )?;
    let tl = l.num(
        "thickness_left_abutment_m",
        "expected a thickness > 0 m",
        pos,
    )?;
    let tr = l.num(
        "thickness_right_abutment_m",
        "expected a thickness > 0 m",
        pos,
    )?;
    let half = |side: &str| -> Result<HalfArch, ArchTableError> {
        let mut h = HalfArch {
            radius_m: l.num(&format!("radius_{side}_m"), "expected a radius > 0 m", pos)?,
            ..HalfArch::default()
        };
        match kind {
            ArchType::ThreeCentred => {
                h.outer_radius_m = l.num(
                    &format!("outer_radius_{side}_m"),
                    "expected a radius > 0 m",
                    pos,
                )?;
                let max = MAX_ANGLE.to_degrees();
                h.central_half_angle = l
                    .num(
                        &format!("central_half_angle_{side}_deg"),
                        &format!("expected an angle in (0, {max:.0}) degrees"),
                        |v| v > 0.0 && v < max,
                    )?
                    .to_radians();
            }
            ArchType::Elliptical => {
                h.axis_ratio = l.num(
                    &format!("axis_ratio_{side}"),
                    "expected a semi-axis ratio > 0",
                    pos,
                )?;
            }
            ArchType::LogSpiral => {
                h.spiral_growth = l.num(
                    &format!("spiral_growth_{side}"),
                    "expected a growth rate k (a number)",
                    any,
                )?;
            }
            ArchType::Circular | ArchType::Parabolic => {}
        }
        Ok(h)
    };
    Ok(ArchRow {
        elevation_m: z,
        crown_upstream_y_m: yu,
        crown_downstream_y_m: yd,
        thickness_left_abutment_m: tl,
        thickness_right_abutment_m: tr,
        left: half("left")?,
        right: half("right")?,
    })
}

/// The rows must reach from the base to the crest.
fn covers(
    file: &str,
    rows: &[(usize, ArchRow)],
    g: &ArchTableGeometry,
    column: usize,
    header_line: usize,
) -> Result<(), ArchTableError> {
    let (base, crest) = (g.base_elevation_m, g.crest_elevation_m);
    let tol = 1e-9 * (1.0 + (crest - base).abs());
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        return Err(row_err(
            file,
            header_line,
            1,
            "no rows: the table must cover base_elevation_m..crest_elevation_m",
        ));
    };
    if first.1.elevation_m > base + tol {
        return Err(row_err(
            file,
            first.0,
            column,
            format!(
                "the table starts at {} m, above the base (geometry.base_elevation_m = {base} m): the rows must cover base..crest",
                first.1.elevation_m
            ),
        ));
    }
    if last.1.elevation_m < crest - tol {
        return Err(row_err(
            file,
            last.0,
            column,
            format!(
                "the table ends at {} m, below the crest (geometry.crest_elevation_m = {crest} m): the rows must cover base..crest",
                last.1.elevation_m
            ),
        ));
    }
    Ok(())
}

/// The valley profile, checked: increasing distances covering the crest,
/// elevations within the dam.
fn parse_valley(
    text: &str,
    file: &str,
    g: &ArchTableGeometry,
) -> Result<Vec<[f64; 2]>, ArchTableError> {
    let r = records(text, file)?;
    let map = header_map(&r, file, &VALLEY_COLUMNS, &VALLEY_COLUMNS)?;
    let (base, crest, length) = (g.base_elevation_m, g.crest_elevation_m, g.crest_length_m);
    let tol = 1e-9 * (1.0 + (crest - base).abs() + length.abs());
    let mut out: Vec<(usize, [f64; 2])> = Vec::with_capacity(r.rows.len());
    for (line, fields) in &r.rows {
        field_count(file, *line, fields, r.header.len())?;
        let l = Line {
            file,
            line: *line,
            fields,
            map: &map,
        };
        let prev = out.last().map(|p| p.1[0]);
        let s = l.num(
            "crest_distance_m",
            &match prev {
                Some(p) => format!("expected a distance [m] above the previous row's {p} m (rows go along the crest)"),
                None => "expected a distance [m]".to_string(),
            },
            |v| prev.is_none_or(|p| v > p),
        )?;
        let z = l.num(
            "foundation_elevation_m",
            &format!("expected an elevation within the dam, {base} to {crest} m (geometry.base_elevation_m, crest_elevation_m)"),
            |v| v >= base - tol && v <= crest + tol,
        )?;
        out.push((*line, [s, z]));
    }
    let col = map["crest_distance_m"] + 1;
    let (Some(first), Some(last)) = (out.first(), out.last()) else {
        return Err(row_err(
            file,
            r.header_line,
            1,
            "no rows: the valley must cover the crest, 0 to crest_length_m",
        ));
    };
    if first.1[0] > tol {
        return Err(row_err(
            file,
            first.0,
            col,
            format!(
                "the valley starts at {} m along the crest: it must start at the left end, 0 m",
                first.1[0]
            ),
        ));
    }
    if last.1[0] < length - tol {
        return Err(row_err(
            file,
            last.0,
            col,
            format!(
                "the valley ends at {} m along the crest, before its right end (geometry.crest_length_m = {length} m)",
                last.1[0]
            ),
        ));
    }
    Ok(out.into_iter().map(|(_, p)| p).collect())
}
