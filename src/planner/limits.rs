//! Site limits on supercooling (issue 15 item 2): what the temperature
//! control team will not do to the concrete to make a zone groutable.
//!
//! Read on the run verifying the remedies, against the baseline over the
//! same days (the schedule's own cooling is the site's, not the remedy's):
//!
//! - **below closure**: neither block of the zone colder at grouting than
//!   closure − `max_below_closure_c`;
//! - **cooling rate**: neither block's zone mean cooling faster than
//!   `max_cooling_rate_c_per_day` between two recorded days from the as-of
//!   date to grouting;
//! - **gradient**: in each block, no zone of the supercooled region (the
//!   zone and those above it within `supercool_above_m`, and the first zone
//!   above that) more than `max_zone_gradient_c` warmer than the zone below
//!   it, on the grouting day.
//!
//! The fourth limit, the coldest water (`min_water_temp_c`), is kept by the
//! edit itself (`edit::supercool_with_water`), and the search says when it
//! held a zone's water.
//!
//! A remedy breaks a limit when its run is past the limit (by more than
//! [`SLACK`]) where the baseline is not: the remedy is what crosses it.
//! Where the baseline's own schedule is past the limit already (fresh,
//! warm concrete above a cooled zone is the usual case for the gradient),
//! the remedy is not stopped, but its note says so (a caution). Verified by `tests/it/planner_limits.rs` (each limit stops a
//! remedy the plan proposes without it, and the report says which).

use crate::vocab::{Day, ZoneId};

use super::rules::{HistoryIndex, Rules};

/// What a remedied value may exceed its limit and the baseline's by
/// before it counts (°C or °C/day): round-off and the solver's tolerance.
pub const SLACK: f64 = 1e-3;

/// A limit a remedy breaks, in words ("cooling rate: block 4 would cool at
/// 0.62 °C/day (0.41 without the remedy), faster than 0.50 °C/day").
pub type Breach = String;

/// What the limits say of one remedy.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Verdict {
    /// limits the remedy crosses: it is not proposed
    pub broken: Vec<Breach>,
    /// limits the baseline is past already, and the remedy too
    pub cautions: Vec<Breach>,
}

impl Verdict {
    /// Files a remedied value `v` against its `limit` and the baseline's `b`
    /// (both "larger is worse").
    fn file(&mut self, v: f64, b: f64, limit: f64, words: String) {
        if v <= limit + SLACK {
            return;
        }
        if b <= limit + SLACK {
            self.broken.push(words);
        } else {
            self.cautions.push(words);
        }
    }
}

/// The limits of a supercooled zone in the remedied run `with`, against the
/// baseline `without`, from the as-of day `from` to its grouting `day`.
pub fn breaches(
    rules: &Rules,
    with: &HistoryIndex,
    without: &HistoryIndex,
    zone: ZoneId,
    closure_c: f64,
    from: Day,
    day: Day,
) -> Verdict {
    let s = rules.settings;
    let blocks = [zone.joint, zone.joint + 1];
    let mut out = Verdict::default();
    let [ta, tb] = with.block_temps(zone, day);
    let [ba, bb] = without.block_temps(zone, day);
    for (i, (t, b)) in [(ta, ba), (tb, bb)].into_iter().enumerate() {
        if let (Some(t), Some(b)) = (t, b) {
            // "larger is worse": how far below the closure temperature
            out.file(closure_c - t, closure_c - b, s.max_below_closure_c, format!(
                "below closure: block {} would be at {t:.1} °C at grouting ({b:.1} without the remedy), more than {:.1} °C below closure {closure_c:.1} °C",
                blocks[i], s.max_below_closure_c
            ));
        }
    }
    let limit = s.max_cooling_rate_c_per_day;
    for (i, (r, b)) in cooling_rates(with, zone, from, day)
        .into_iter()
        .zip(cooling_rates(without, zone, from, day))
        .enumerate()
    {
        out.file(r, b, limit, format!(
            "cooling rate: block {} would cool at {r:.2} °C/day ({b:.2} without the remedy), faster than {limit:.2} °C/day",
            blocks[i]
        ));
    }
    let limit = s.max_zone_gradient_c;
    let height = rules.zone_z.get(&zone).map_or(f64::INFINITY, |z| z.1 - z.0);
    let zones_up = 1 + (s.supercool_above_m / height).ceil() as u32;
    for k in zone.zone..zone.zone + zones_up {
        let (lower, upper) = (ZoneId::new(zone.joint, k), ZoneId::new(zone.joint, k + 1));
        let g = gradient(with, lower, upper, day);
        let g0 = gradient(without, lower, upper, day);
        for i in 0..2 {
            if let (Some(g), Some(g0)) = (g[i], g0[i]) {
                out.file(g, g0, limit, format!(
                    "gradient: in block {}, zone {} above would be {g:.1} °C warmer than zone {k} ({g0:.1} without the remedy), more than {limit:.1} °C",
                    blocks[i],
                    k + 1
                ));
            }
        }
    }
    out
}

/// Each block's fastest cooling of the zone's mean between two recorded
/// days in `[from, to]` [°C/day] (0 when it only warms).
fn cooling_rates(h: &HistoryIndex, zone: ZoneId, from: Day, to: Day) -> [f64; 2] {
    let mut fastest = [0.0f64; 2];
    let mut last: Option<(Day, [Option<f64>; 2])> = None;
    for r in &h.history.zone_temps.rows {
        let day = r.0;
        if day < from || day > to {
            continue;
        }
        let t = h.block_temps(zone, day);
        if let Some((d0, t0)) = last {
            let dt = day.since(d0) as f64;
            for i in 0..2 {
                if let (Some(a), Some(b)) = (t0[i], t[i]) {
                    if dt > 0.0 {
                        fastest[i] = fastest[i].max((a - b) / dt);
                    }
                }
            }
        }
        last = Some((day, t));
    }
    fastest
}

/// How much warmer `upper` is than `lower` in each block on `day`.
fn gradient(h: &HistoryIndex, lower: ZoneId, upper: ZoneId, day: Day) -> [Option<f64>; 2] {
    let (l, u) = (h.block_temps(lower, day), h.block_temps(upper, day));
    [0, 1].map(|i| match (l[i], u[i]) {
        (Some(l), Some(u)) => Some(u - l),
        _ => None,
    })
}
