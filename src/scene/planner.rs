//! The scene's `[planner]` table: the readiness rules' thresholds, remedy
//! limits and costs. The data lives with the scene; the rules that read it
//! live in `planner`.

use serde::{Deserialize, Serialize};

use crate::vocab::{Invalid, ZonePoint};

/// Readiness rules and remedy search (`[planner]`, every key optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerSettings {
    /// Least aperture that takes grout \[mm\]; default 0.5.
    pub min_aperture_mm: f64,
    /// Groutable zones below this aperture are reported as marginal \[mm\];
    /// default 0.7.
    pub marginal_aperture_mm: f64,
    /// Which point decides the aperture rule: `min` (default), `upstream`,
    /// `center` or `downstream`.
    pub aperture_point: ZonePoint,
    /// Closure (grouting) temperature of the concrete [°C]; default 13.
    pub closure_temp_c: f64,
    /// Optional closure temperature by elevation, `[[z_m, temp_c], ...]` with
    /// z increasing, interpolated linearly (held constant beyond the ends);
    /// replaces `closure_temp_c` when given.
    pub closure_temp_profile: Vec<[f64; 2]>,
    /// A block passes the temperature rule at closure + this [°C]; default 1.
    pub closure_tolerance_c: f64,
    /// Least concrete age of the zone's youngest lift at grouting \[days\];
    /// default 90.
    pub min_age_days: f64,
    /// Least height of concrete above the zone's top on both blocks \[m\]
    /// (waived where a block is complete); default 6.
    pub min_cover_m: f64,
    /// Largest supercooling of a zone's second-stage target [°C]; default 3.
    pub max_supercooling_c: f64,
    /// Supercooling is searched on this grid [°C]; default 0.25.
    pub supercooling_step_c: f64,
    /// Height of the cooling region above a zone that is supercooled with it
    /// \[m\]; default 9 (one zone of the demo; practice cools the zone above
    /// with it so the gradient stays small).
    pub supercool_above_m: f64,
    /// Site limit: the concrete of a supercooled zone may not be colder at
    /// grouting than closure − this [°C]; default 3 (practice: 2–3).
    pub max_below_closure_c: f64,
    /// Site limit: a supercooled zone's concrete may not cool faster than
    /// this between two recorded days [°C/day]; default 0.5.
    pub max_cooling_rate_c_per_day: f64,
    /// Site limit: in a block, a zone of the supercooled region (and the
    /// first zone above it) may not be warmer than the zone below it by
    /// more than this at grouting [°C]; default 4 (an estimate of common
    /// specifications; set the project's).
    pub max_zone_gradient_c: f64,
    /// Site limit: the coldest cooling water the chillers deliver [°C];
    /// default 4. Supercooling never lowers a stage's water below it.
    pub min_water_temp_c: f64,
    /// Longest delay searched \[days\]; default 60.
    pub max_delay_days: u32,
    /// Cost of 1 °C of supercooling of one zone, in the same unit as
    /// `cost_per_day`; default 1.
    pub cost_per_degree_c: f64,
    /// Cost of one day of delay of one zone; default 0.2 (1 °C ≈ 5 days).
    pub cost_per_day: f64,
    /// Days between checkpoints of the simulation state; default 14.
    pub checkpoint_days: u32,
    /// Plan only the zones due within this many days of the as-of date
    /// (the simulation stops at the last of them); default: every zone.
    pub horizon_days: Option<u32>,
    /// Longest mechanical step of the remedy searches' re-simulations
    /// [whole days], default 1 (the scene's own steps). Above 1 an
    /// approximation for speed, of the searches alone: their runs take
    /// mechanical steps of up to this many days with the pours inside a
    /// step merged into it (`time.mechanics_max_step_days` and
    /// `mechanics_merge_pours`, when the scene's own steps are shorter: a
    /// dam poured every day would step every day otherwise), and the delay
    /// run reads every this-many-th day, so a delay is found to this many
    /// days. The baseline and the run that verifies every proposal
    /// together stay on the scene's own steps: every verdict the plan
    /// reports is the exact path's, and a remedy that fails there is
    /// strengthened and verified again as ever; what the searches' runs
    /// read themselves (an option's aperture) is theirs. Measured in
    /// `tests/it/planner_search_steps.rs` and docs/PERFORMANCE.md; at
    /// most 30.
    pub search_max_step_days: u32,
}

impl Default for PlannerSettings {
    fn default() -> Self {
        PlannerSettings {
            min_aperture_mm: 0.5,
            marginal_aperture_mm: 0.7,
            aperture_point: ZonePoint::Min,
            closure_temp_c: 13.0,
            closure_temp_profile: Vec::new(),
            closure_tolerance_c: 1.0,
            min_age_days: 90.0,
            min_cover_m: 6.0,
            max_supercooling_c: 3.0,
            supercooling_step_c: 0.25,
            supercool_above_m: 9.0,
            max_below_closure_c: 3.0,
            max_cooling_rate_c_per_day: 0.5,
            max_zone_gradient_c: 4.0,
            min_water_temp_c: 4.0,
            max_delay_days: 60,
            cost_per_degree_c: 1.0,
            cost_per_day: 0.2,
            checkpoint_days: 14,
            horizon_days: None,
            search_max_step_days: 1,
        }
    }
}

impl PlannerSettings {
    /// Closure temperature at elevation `z`.
    pub fn closure_temp_at(&self, z: f64) -> f64 {
        let p = &self.closure_temp_profile;
        match p.len() {
            0 => self.closure_temp_c,
            _ if z <= p[0][0] => p[0][1],
            _ if z >= p[p.len() - 1][0] => p[p.len() - 1][1],
            _ => {
                let i = p.iter().position(|q| q[0] > z).unwrap_or(p.len() - 1);
                let (a, b) = (p[i - 1], p[i]);
                a[1] + (b[1] - a[1]) * (z - a[0]) / (b[0] - a[0])
            }
        }
    }

    /// The site limits on supercooling.
    fn validate_limits(&self) -> Result<(), Invalid> {
        let bad = |k: &str, what: &str, v: f64| {
            Err(Invalid::new(
                format!("planner.{k}"),
                format!("planner.{k} must be {what}, got {v}"),
            ))
        };
        if !(self.min_water_temp_c.is_finite() && (0.0..=30.0).contains(&self.min_water_temp_c)) {
            return bad("min_water_temp_c", "within 0..30 °C", self.min_water_temp_c);
        }
        for (k, v) in [
            ("max_below_closure_c", self.max_below_closure_c),
            (
                "max_cooling_rate_c_per_day",
                self.max_cooling_rate_c_per_day,
            ),
            ("max_zone_gradient_c", self.max_zone_gradient_c),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, "> 0", v);
            }
        }
        Ok(())
    }

    /// Checks the values; the error names the key and what was expected.
    pub fn validate(&self) -> Result<(), Invalid> {
        let key = |k: &str| format!("planner.{k}");
        let bad = |k: &str, what: &str, v: f64| {
            Err(Invalid::new(
                key(k),
                format!("planner.{k} must be {what}, got {v}"),
            ))
        };
        if !(self.min_aperture_mm.is_finite() && self.min_aperture_mm > 0.0) {
            return bad("min_aperture_mm", "> 0", self.min_aperture_mm);
        }
        if !(self.marginal_aperture_mm.is_finite()
            && self.marginal_aperture_mm >= self.min_aperture_mm)
        {
            return bad(
                "marginal_aperture_mm",
                "finite and >= planner.min_aperture_mm",
                self.marginal_aperture_mm,
            );
        }
        if !(self.closure_temp_c.is_finite() && (-10.0..=40.0).contains(&self.closure_temp_c)) {
            return bad("closure_temp_c", "within -10..40 °C", self.closure_temp_c);
        }
        for (i, q) in self.closure_temp_profile.iter().enumerate() {
            if !(q[0].is_finite() && q[1].is_finite() && (-10.0..=40.0).contains(&q[1])) {
                return Err(Invalid::new(
                    key("closure_temp_profile"),
                    format!("planner.closure_temp_profile[{i}] must be [z_m, temp_c] with temp_c within -10..40 °C, got [{}, {}]", q[0], q[1]),
                ));
            }
            if i > 0 && q[0] <= self.closure_temp_profile[i - 1][0] {
                return Err(Invalid::new(
                    key("closure_temp_profile"),
                    format!(
                        "planner.closure_temp_profile: elevations must increase, {} follows {}",
                        q[0],
                        self.closure_temp_profile[i - 1][0]
                    ),
                ));
            }
        }
        if !(self.closure_tolerance_c.is_finite() && self.closure_tolerance_c >= 0.0) {
            return bad("closure_tolerance_c", ">= 0", self.closure_tolerance_c);
        }
        if !(self.min_age_days.is_finite() && self.min_age_days >= 0.0) {
            return bad("min_age_days", ">= 0", self.min_age_days);
        }
        if !(self.min_cover_m.is_finite() && self.min_cover_m >= 0.0) {
            return bad("min_cover_m", ">= 0", self.min_cover_m);
        }
        self.validate_limits()?;
        if !(self.max_supercooling_c.is_finite() && (0.0..=10.0).contains(&self.max_supercooling_c))
        {
            return bad(
                "max_supercooling_c",
                "within 0..10 °C",
                self.max_supercooling_c,
            );
        }
        if !(self.supercooling_step_c.is_finite()
            && self.supercooling_step_c > 0.0
            && self.supercooling_step_c <= self.max_supercooling_c.max(self.supercooling_step_c))
        {
            return bad("supercooling_step_c", "> 0", self.supercooling_step_c);
        }
        if !(self.supercool_above_m.is_finite() && self.supercool_above_m >= 0.0) {
            return bad("supercool_above_m", ">= 0", self.supercool_above_m);
        }
        if !(self.cost_per_degree_c.is_finite() && self.cost_per_degree_c >= 0.0) {
            return bad("cost_per_degree_c", ">= 0", self.cost_per_degree_c);
        }
        if !(self.cost_per_day.is_finite() && self.cost_per_day >= 0.0) {
            return bad("cost_per_day", ">= 0", self.cost_per_day);
        }
        if self.horizon_days == Some(0) {
            return Err(Invalid::new(
                key("horizon_days"),
                "planner.horizon_days must be >= 1, got 0",
            ));
        }
        if self.checkpoint_days == 0 {
            return Err(Invalid::new(
                key("checkpoint_days"),
                "planner.checkpoint_days must be >= 1, got 0",
            ));
        }
        if !(1..=30).contains(&self.search_max_step_days) {
            return Err(Invalid::new(
                key("search_max_step_days"),
                format!(
                    "planner.search_max_step_days must be a whole number of days in 1..=30, got {}",
                    self.search_max_step_days
                ),
            ));
        }
        Ok(())
    }
}
