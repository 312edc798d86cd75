//! The zones' deciding apertures on their planned grouting dates as one
//! distribution, with the verdicts: what a whole run says of its joints
//! (`groutready run` writes it into `run.txt`). A plan judges the zones
//! of its weeks; a run of the large arch's whole construction judges all
//! 749, and this is how its joints read: how many zones are closed, below
//! the rule, or open by how much.

use std::fmt;

use crate::planner::{Verdict, ZoneReadiness};
use crate::scene::PlannerSettings;
use crate::vocab::ZonePoint;

use super::words::{deciding_aperture, mm};

/// Apertures below this read as closed: 0.00 in every table [mm].
const CLOSED_MM: f64 = 0.005;
/// Class edges above the rule's limit [mm].
const EDGES_MM: [f64; 3] = [1.0, 2.0, 3.0];

/// Deciding apertures and verdicts of the zones judged on their planned dates.
#[derive(Debug, Clone, PartialEq)]
pub struct GroutingDistribution {
    pub zones: usize,
    pub point: ZonePoint,
    /// the rule's least aperture [mm]
    pub limit_mm: f64,
    /// zones closed (< 0.005 mm) on their date
    pub closed: usize,
    /// (lower edge, upper edge or None for the last class, zones) [mm]
    pub classes: Vec<(f64, Option<f64>, usize)>,
    /// zones whose deciding point recorded no aperture on the date
    pub unrecorded: usize,
    /// 10 %, 50 % and 90 % of the recorded apertures (nearest rank) [mm]
    pub quantiles: Option<[f64; 3]>,
    /// groutable, marginal, not groutable
    pub verdicts: [usize; 3],
}

impl GroutingDistribution {
    pub fn of(zones: &[ZoneReadiness], settings: &PlannerSettings) -> GroutingDistribution {
        let point = settings.aperture_point;
        let limit = settings.min_aperture_mm;
        let mut edges = vec![CLOSED_MM];
        edges.extend(
            std::iter::once(limit)
                .chain(EDGES_MM)
                .filter(|&e| e > CLOSED_MM),
        );
        edges.sort_by(f64::total_cmp);
        edges.dedup();
        let mut classes: Vec<(f64, Option<f64>, usize)> = edges
            .iter()
            .enumerate()
            .map(|(i, &lo)| (lo, edges.get(i + 1).copied(), 0))
            .collect();
        let mut recorded: Vec<f64> = zones
            .iter()
            .filter_map(|z| deciding_aperture(z, point))
            .collect();
        let mut closed = 0;
        for &a in &recorded {
            match classes.iter_mut().rev().find(|c| a >= c.0) {
                Some(c) => c.2 += 1,
                None => closed += 1,
            }
        }
        recorded.sort_by(f64::total_cmp);
        let rank = |q: f64| recorded[((q * recorded.len() as f64).ceil() as usize).max(1) - 1];
        let quantiles = (!recorded.is_empty()).then(|| [rank(0.1), rank(0.5), rank(0.9)]);
        let count = |v: Verdict| zones.iter().filter(|z| z.verdict == v).count();
        GroutingDistribution {
            zones: zones.len(),
            point,
            limit_mm: limit,
            closed,
            unrecorded: zones.len() - recorded.len(),
            classes,
            quantiles,
            verdicts: [
                count(Verdict::Groutable),
                count(Verdict::Marginal),
                count(Verdict::NotGroutable),
            ],
        }
    }
}

impl fmt::Display for GroutingDistribution {
    /// Three lines: the classes, the quantiles, the verdicts.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "apertures on the planned grouting dates: {} zones, point {}, rule >= {} mm",
            self.zones,
            self.point.as_str(),
            mm(self.limit_mm)
        )?;
        let mut parts = vec![format!("closed {}", self.closed)];
        for &(lo, hi, n) in &self.classes {
            parts.push(match hi {
                Some(hi) if lo == CLOSED_MM => format!("open below {} mm {n}", mm(hi)),
                Some(hi) => format!("{}-{} mm {n}", mm(lo), mm(hi)),
                None => format!(">= {} mm {n}", mm(lo)),
            });
        }
        if self.unrecorded > 0 {
            parts.push(format!("not recorded {}", self.unrecorded));
        }
        writeln!(f, "  {}", parts.join(", "))?;
        if let Some([p10, p50, p90]) = self.quantiles {
            writeln!(
                f,
                "  10 % {} mm, median {} mm, 90 % {} mm",
                mm(p10),
                mm(p50),
                mm(p90)
            )?;
        }
        let [g, m, n] = self.verdicts;
        writeln!(
            f,
            "  verdicts: {g} groutable, {m} marginal, {n} not groutable"
        )
    }
}
