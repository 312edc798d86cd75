//! Warnings: inputs that are well formed and physically possible but that a
//! site engineer would want to look at twice (cooling water warmer than the
//! concrete it is meant to cool, a cooling target the concrete never
//! reaches from above). Errors stop a run; warnings do not, so the console
//! prints them before the run and the report repeats them.

use std::fmt;

use serde::{Deserialize, Serialize};

/// One warning, located like a [`super::ScheduleError`]:
/// `cooling.csv:14:7 (water_temp_c): …`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    pub file: String,
    /// 1-based line
    pub line: usize,
    /// 1-based column and its name, when the warning is about one cell
    pub column: Option<(usize, String)>,
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.column {
            Some((c, name)) => write!(
                f,
                "{}:{}:{c} ({name}): {}",
                self.file, self.line, self.message
            ),
            None => write!(f, "{}:{}: {}", self.file, self.line, self.message),
        }
    }
}
