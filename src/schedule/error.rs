//! `ScheduleError`: every message starts with `<file>:<line>` (or `<file>`
//! when no line applies) so an engineer can jump to the offending row.

use std::path::PathBuf;

/// The longest text an error quotes.
pub(crate) const EXCERPT_CHARS: usize = 120;

/// An error in a schedule folder or in its agreement with the dam layout.
///
/// Display forms (the text found is quoted with Rust string escapes):
/// - cell: `pours.csv:12:3 (pour_date): expected a date YYYY-MM-DD, found "2025-13-01"`
/// - row / between rows: `pours.csv:14:3: block 3 lift 5 poured 2025-03-02, before lift 4 (line 13) poured 2025-03-09`
/// - header: `pours.csv:1: expected header "block,lift,pour_date,placement_temp_c", found "block,lift,pour_date" (missing column "placement_temp_c")`
/// - field count: `pours.csv:7: expected 4 fields (block,lift,pour_date,placement_temp_c), found 3 in "1,2,2025-01-01"`
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScheduleError {
    /// A required file is absent.
    #[error("{file}: required file not found in \"{}\"", dir.display())]
    MissingFile { file: String, dir: PathBuf },

    /// The file exists but cannot be read (permissions, not UTF-8 ...).
    #[error("{file}: cannot read \"{}\": {message}", path.display())]
    Io {
        file: String,
        path: PathBuf,
        message: String,
    },

    /// The header row is absent or differs from the expected one.
    #[error("{file}:{line}: expected header \"{expected}\", found {found:?}{detail}")]
    Header {
        file: String,
        line: usize,
        expected: String,
        found: String,
        /// Either empty or ` (missing column "x")`-like, with a leading space.
        detail: String,
    },

    /// A data row has the wrong number of fields.
    #[error("{file}:{line}: expected {expected} fields ({header}), found {found} in {text:?}")]
    FieldCount {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
        header: String,
        text: String,
    },

    /// One cell is malformed or out of range. `column` is 1-based.
    #[error("{file}:{line}:{column} ({name}): {expected}, found {found:?}")]
    Cell {
        file: String,
        line: usize,
        column: usize,
        name: String,
        expected: String,
        found: String,
    },

    /// A row contradicts another row (or another file): duplicates, order,
    /// gaps, overlaps, cooling before pouring.
    #[error("{file}:{line}:{column}: {message}")]
    Row {
        file: String,
        line: usize,
        /// 1-based column of the cell the conflict is about
        column: usize,
        message: String,
    },

    /// A row contradicts the dam layout ([`super::check_against`]).
    #[error("{file}:{line}:{column}: {message}")]
    Layout {
        file: String,
        line: usize,
        /// 1-based column of the cell the conflict is about
        column: usize,
        message: String,
    },

    /// The [`super::DamLayout`] itself is inconsistent (a caller bug, not a
    /// schedule error).
    #[error("dam layout: {0}")]
    InvalidLayout(String),
}

impl ScheduleError {
    /// The file the error is about (`None` for an invalid layout).
    pub fn file(&self) -> Option<&str> {
        match self {
            ScheduleError::MissingFile { file, .. }
            | ScheduleError::Io { file, .. }
            | ScheduleError::Header { file, .. }
            | ScheduleError::FieldCount { file, .. }
            | ScheduleError::Cell { file, .. }
            | ScheduleError::Row { file, .. }
            | ScheduleError::Layout { file, .. } => Some(file),
            ScheduleError::InvalidLayout(_) => None,
        }
    }

    /// The 1-based line the error is about, when there is one.
    pub fn line(&self) -> Option<usize> {
        match self {
            ScheduleError::Header { line, .. }
            | ScheduleError::FieldCount { line, .. }
            | ScheduleError::Cell { line, .. }
            | ScheduleError::Row { line, .. }
            | ScheduleError::Layout { line, .. } => Some(*line),
            _ => None,
        }
    }

    /// At most [`EXCERPT_CHARS`] characters of `text`, ending with `…` when
    /// cut: an error quotes what it found, not a 10 MB line.
    pub(crate) fn excerpt(text: &str) -> String {
        if text.chars().count() <= EXCERPT_CHARS {
            return text.to_string();
        }
        let cut: String = text.chars().take(EXCERPT_CHARS).collect();
        format!("{cut}… ({} characters)", text.chars().count())
    }

    pub(crate) fn row(file: &str, line: usize, column: usize, message: impl Into<String>) -> Self {
        ScheduleError::Row {
            file: file.to_string(),
            line,
            column,
            message: message.into(),
        }
    }

    pub(crate) fn layout(
        file: &str,
        line: usize,
        column: usize,
        message: impl Into<String>,
    ) -> Self {
        ScheduleError::Layout {
            file: file.to_string(),
            line,
            column,
            message: message.into(),
        }
    }
}
