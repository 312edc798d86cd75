//! The counts every report opens with.

use serde::Serialize;

use crate::planner::{Plan, Verdict};

/// Zone counts of a plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Summary {
    /// zones planned on or after the as-of date
    pub to_grout: usize,
    /// zones to grout that are not groutable
    pub flagged: usize,
    /// zones to grout that are groutable but marginal
    pub marginal: usize,
    /// zones grouted before the as-of date
    pub history: usize,
    /// zones grouted before the as-of date that re-opened
    pub reopened: usize,
}

impl Summary {
    pub fn of(plan: &Plan) -> Summary {
        let history = || plan.zones.iter().filter(|z| z.history);
        Summary {
            to_grout: plan.to_grout().count(),
            flagged: plan.flagged().count(),
            marginal: plan
                .to_grout()
                .filter(|z| z.verdict == Verdict::Marginal)
                .count(),
            history: history().count(),
            reopened: history().filter(|z| z.reopened.is_some()).count(),
        }
    }

    /// One line: "5 zones to grout: 2 flagged, 1 marginal; 3 grouted before 2024-09-01 (1 re-opened)".
    pub fn line(&self, as_of: chrono::NaiveDate) -> String {
        let plural =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let mut s = format!(
            "{} to grout: {} flagged (not groutable), {} marginal; {} grouted before {as_of}",
            plural(self.to_grout, "zone", "zones"),
            self.flagged,
            self.marginal,
            self.history,
        );
        if self.reopened > 0 {
            s.push_str(&format!(" ({} re-opened)", self.reopened));
        }
        s
    }
}
