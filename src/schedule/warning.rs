//! Warnings: inputs that are well formed and physically possible but that a
//! site engineer would want to look at twice (cooling water warmer than the
//! concrete it is meant to cool, a cooling target the concrete never
//! reaches from above). Errors stop a run; warnings do not, so the console
//! prints them before the run and the report repeats them.

use std::fmt;

use serde::{Deserialize, Serialize};

/// One warning, located like a [`super::ScheduleError`]:
/// `cooling.csv:14:7 (water_temp_c): …`, or a whole file
/// (`restart/ck-00120.bin: …`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    pub file: String,
    /// 1-based line, when the warning is about a row
    pub line: Option<usize>,
    /// 1-based column and its name, when the warning is about one cell
    pub column: Option<(usize, String)>,
    pub message: String,
}

impl Warning {
    /// A warning about a whole file.
    pub fn about_file(file: impl Into<String>, message: impl Into<String>) -> Warning {
        Warning {
            file: file.into(),
            line: None,
            column: None,
            message: message.into(),
        }
    }

    /// A warning about one cell (`column` is 1-based).
    pub fn cell(file: &str, line: usize, column: usize, name: &str, message: String) -> Warning {
        Warning {
            file: file.to_string(),
            line: Some(line),
            column: Some((column, name.to_string())),
            message,
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some((c, name)) = &self.column {
            write!(f, ":{c} ({name})")?;
        }
        write!(f, ": {}", self.message)
    }
}
