//! Neighbouring zones supercooled together, as a small linear program
//! (issue 15 item 3).
//!
//! The supercooling search finds each zone's least grid step with its
//! neighbours at whatever the search tried for them; zones that share a
//! block (same or adjacent joints) help each other, so that answer may
//! over-cool the group. Around the zone-by-zone answer k* (grid steps, one
//! per zone) the margins m_r of the rules cooling can fix (aperture in mm
//! above its limit, temperature in °C below its limit; two rows per zone)
//! are modelled linearly,
//!
//! ```text
//! m(k) ≈ m(k*) + S (k − k*),
//! ```
//!
//! S by one-sided finite differences: one re-simulation at k* and one at
//! k* − e_i for each zone i that has a neighbour (each also a candidate
//! answer). The least-cost set is the linear program
//!
//! ```text
//! min  c·k   s.t.  m(k*) + S (k − k*) ≥ 0,   lo ≤ k ≤ hi,
//! ```
//!
//! c the scene's cost of one step of one zone, lo = k* − [`REACH`] (≥ 0),
//! hi = k* + [`REACH`] (≤ the largest supercooling); zones without a
//! neighbour keep k*. Clarabel solves it ([`least_cost`]); the answer is
//! taken to the grid by trying the floor and ceiling of each free zone and
//! keeping the cheapest point the model predicts passes ([`round_to_grid`]);
//! a point an earlier run refuted is not proposed again. That point is
//! re-simulated: if a zone fails there, the run is a secant (Broyden) update
//! of S along the step taken ([`Linear::secant`]) and the program is solved
//! again, at most [`ROUNDS`] times. The cheapest point a re-simulation
//! verified (k* itself when none is cheaper) is the answer, so the
//! result never costs more than the zone-by-zone search when k* holds.
//! k* need not hold: each zone's steps were found with its neighbours at
//! the search's trial values, not at their final ones. Then the answer is
//! the cheapest verified point, which may cost more, and says so
//! (`Together::zone_by_zone_held`). The site limits:
//! the largest supercooling bounds k, the coldest water is kept by the
//! edit, and the others are read on the plan's verification run as for any
//! remedy (`search::verify_together`).
//!
//! Verified by the unit tests below (a program with a known optimum, the
//! grid rounding, the secant update) and `tests/it/planner_together.rs`
//! (the small dam planned from 1 June: the set chosen together costs less
//! than zone by zone, is groutable when the remedied schedules are
//! simulated from scratch, and one step less on the zone lowered fails).

use std::collections::BTreeMap;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT::NonnegativeConeT,
};
use thiserror::Error;

use crate::schedule::Schedules;
use crate::sim::{History, SimError};
use crate::vocab::ZoneId;

use super::readiness::ZoneReadiness;
use super::runner::Span;
use super::search::{margins, simulate, BuildSupercooled, Ctx};

/// How far from the zone-by-zone answer the program may move a zone [grid
/// steps]: the finite differences are one step wide, so the model is
/// trusted a few steps around it.
pub const REACH: f64 = 4.0;

/// Programs solved (each followed by one verifying re-simulation).
pub const ROUNDS: usize = 3;

/// Errors of the least-cost program.
#[derive(Debug, Error, PartialEq)]
pub enum JointError {
    #[error("joint supercooling: {what} has {found} entries, expected {expected}")]
    Dimension {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    #[error("joint supercooling settings: {0}")]
    Settings(String),
    #[error("joint supercooling: no set within the bounds meets the linearised rules")]
    Infeasible,
    #[error("joint supercooling: the LP solver (clarabel) stopped with status {0}")]
    Solver(String),
}

/// Settings of the least-cost program.
#[derive(Debug, Clone, PartialEq)]
pub struct LpSettings {
    /// Interior-point tolerance handed to clarabel as `tol_gap_abs`,
    /// `tol_gap_rel` and `tol_feas` (grid steps and mm/°C: order 1).
    /// Default `1e-8`.
    pub tolerance: f64,
    /// Interior-point iteration limit. Default `100`.
    pub max_iter: u32,
}

impl Default for LpSettings {
    fn default() -> Self {
        LpSettings {
            tolerance: 1e-8,
            max_iter: 100,
        }
    }
}

impl LpSettings {
    /// Checks the values; the error names the field.
    pub fn validate(&self) -> Result<(), JointError> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance < 1e-2) {
            return Err(JointError::Settings(format!(
                "tolerance must be in (0, 1e-2), got {}",
                self.tolerance
            )));
        }
        if self.max_iter == 0 {
            return Err(JointError::Settings("max_iter must be >= 1, got 0".into()));
        }
        Ok(())
    }
}

/// The margins as a linear function of the grid steps around `x0`. A row
/// whose margin at `x0` is not finite (a rule that was not measured) is
/// left out of the program and of the predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct Linear {
    pub x0: Vec<f64>,
    pub m0: Vec<f64>,
    /// rows × variables
    pub s: Vec<Vec<f64>>,
}

impl Linear {
    /// The predicted margins at `x` (non-finite rows stay as they are).
    pub fn predict(&self, x: &[f64]) -> Vec<f64> {
        self.m0
            .iter()
            .zip(&self.s)
            .map(|(&m, row)| {
                if !m.is_finite() {
                    return m;
                }
                m + row
                    .iter()
                    .zip(x.iter().zip(&self.x0))
                    .map(|(s, (x, x0))| s * (x - x0))
                    .sum::<f64>()
            })
            .collect()
    }

    /// Broyden's update from a run at `x` with margins `m`: each row is
    /// corrected along the step d = x − x0 so that the model reproduces that
    /// run, S_r += (m_r − predicted_r) dᵀ / (d·d); it is unchanged across d.
    pub fn secant(&mut self, x: &[f64], m: &[f64]) {
        let d: Vec<f64> = x.iter().zip(&self.x0).map(|(x, x0)| x - x0).collect();
        let dd: f64 = d.iter().map(|v| v * v).sum();
        if dd == 0.0 {
            return;
        }
        let p = self.predict(x);
        for (r, row) in self.s.iter_mut().enumerate() {
            let miss = m[r] - p[r];
            if !miss.is_finite() {
                continue;
            }
            for (s, di) in row.iter_mut().zip(&d) {
                *s += miss * di / dd;
            }
        }
    }
}

/// The least-cost point of `min c·x s.t. model(x) ≥ 0, lo ≤ x ≤ hi`
/// (continuous), solved by clarabel.
pub fn least_cost(
    model: &Linear,
    cost: &[f64],
    lo: &[f64],
    hi: &[f64],
    settings: &LpSettings,
) -> Result<Vec<f64>, JointError> {
    settings.validate()?;
    let n = model.x0.len();
    for (what, v) in [("cost", cost.len()), ("lo", lo.len()), ("hi", hi.len())] {
        if v != n {
            return Err(JointError::Dimension {
                what,
                expected: n,
                found: v,
            });
        }
    }
    // Rows of A x ≤ b: −S_r x ≤ m0_r − S_r x0, then x ≤ hi, −x ≤ −lo.
    let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
    for (m, s) in model.m0.iter().zip(&model.s) {
        if m.is_finite() {
            let sx0: f64 = s.iter().zip(&model.x0).map(|(a, b)| a * b).sum();
            rows.push((s.iter().map(|v| -v).collect(), m - sx0));
        }
    }
    for i in 0..n {
        let mut e = vec![0.0; n];
        e[i] = 1.0;
        rows.push((e.clone(), hi[i]));
        e[i] = -1.0;
        rows.push((e, -lo[i]));
    }
    let a = CscMatrix::from(&rows.iter().map(|r| r.0.clone()).collect::<Vec<Vec<f64>>>());
    let b: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let p = CscMatrix::new(n, n, vec![0; n + 1], vec![], vec![]);
    let cl = DefaultSettings::<f64> {
        verbose: false,
        max_iter: settings.max_iter,
        tol_gap_abs: settings.tolerance,
        tol_gap_rel: settings.tolerance,
        tol_feas: settings.tolerance,
        ..DefaultSettings::default()
    };
    let cones = [NonnegativeConeT(b.len())];
    let mut solver = DefaultSolver::new(&p, cost, &a, &b, &cones, cl)
        .map_err(|e| JointError::Solver(format!("setup failed: {e}")))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved
            if solver.solution.x.iter().all(|v| v.is_finite()) =>
        {
            Ok(solver.solution.x.clone())
        }
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            Err(JointError::Infeasible)
        }
        s => Err(JointError::Solver(format!("{s:?}"))),
    }
}

/// The cheapest grid point next to `x` (each free variable at its floor or
/// ceiling, within [lo, hi]) the model predicts passes, ties to the larger
/// least margin; `refuted` points are skipped. With more than 12 free
/// variables only the ceiling is tried.
pub fn round_to_grid(
    model: &Linear,
    x: &[f64],
    cost: &[f64],
    lo: &[f64],
    hi: &[f64],
    refuted: &dyn Fn(&[u32]) -> bool,
) -> Option<Vec<u32>> {
    const EPS: f64 = 1e-6;
    let options: Vec<Vec<u32>> = (0..x.len())
        .map(|i| {
            let v = x[i].clamp(lo[i], hi[i]);
            let (f, c) = ((v + EPS).floor(), (v - EPS).ceil());
            let mut o = vec![c.clamp(lo[i], hi[i]) as u32];
            if f < c && f >= lo[i] {
                o.insert(0, f as u32);
            }
            o
        })
        .collect();
    let free = options.iter().filter(|o| o.len() > 1).count();
    let combos = if free > 12 { 1 } else { 1usize << free };
    let mut best: Option<(f64, f64, Vec<u32>)> = None;
    for bits in 0..combos {
        let mut b = 0;
        let k: Vec<u32> = options
            .iter()
            .map(|o| {
                if o.len() == 1 || free > 12 {
                    *o.last().expect("one option")
                } else {
                    b += 1;
                    o[(bits >> (b - 1)) & 1 ^ 1]
                }
            })
            .collect();
        if refuted(&k) {
            continue;
        }
        let kf: Vec<f64> = k.iter().map(|&v| v as f64).collect();
        let least = model
            .predict(&kf)
            .into_iter()
            .filter(|m| m.is_finite())
            .fold(f64::INFINITY, f64::min);
        if least < 0.0 {
            continue;
        }
        let c: f64 = kf.iter().zip(cost).map(|(k, c)| k * c).sum();
        let better = match &best {
            None => true,
            Some((bc, bl, _)) => c < bc - 1e-12 || (c <= bc + 1e-12 && least > *bl),
        };
        if better {
            best = Some((c, least, k));
        }
    }
    best.map(|b| b.2)
}

/// What the joint step found: each zone's grid steps and deciding aperture
/// in the cheapest verified run, and the zone-by-zone steps it started from.
pub(super) struct Together {
    pub ks: BTreeMap<ZoneId, u32>,
    pub apertures: BTreeMap<ZoneId, f64>,
    pub zone_by_zone: BTreeMap<ZoneId, u32>,
    /// whether the zone-by-zone steps passed when run together (the
    /// search found each zone's steps with its neighbours at other trial
    /// values, so they need not)
    pub zone_by_zone_held: bool,
    /// the zones whose steps the program was free to change, in sets of
    /// neighbours
    pub sets: Vec<Vec<ZoneId>>,
}

/// One evaluated grid point: its margins (two per zone), whether every
/// zone passed, and the deciding apertures \[mm\].
pub(super) struct Point {
    k: Vec<u32>,
    m: Vec<f64>,
    pub(super) passed: bool,
    pub(super) apertures: Vec<f64>,
}

/// Runs the grid points two at a time (the machine's cores) and reads every
/// zone's rules in each.
pub(super) fn evaluate(
    ctx: &mut Ctx,
    cands: &[&ZoneReadiness],
    span: &Span,
    build: &BuildSupercooled,
    points: &[Vec<u32>],
) -> Result<Vec<Point>, SimError> {
    let ids: Vec<ZoneId> = cands.iter().map(|z| z.zone_id()).collect();
    let mut out = Vec::new();
    for pair in points.chunks(2) {
        (ctx.progress)(&format!(
            "supercooling {} zones together, {} set{}",
            ids.len(),
            pair.len(),
            if pair.len() == 1 { "" } else { "s" }
        ));
        let scheds: Vec<Schedules> = pair
            .iter()
            .map(|k| build(&ids.iter().copied().zip(k.iter().copied()).collect()).0)
            .collect();
        let (runner, temps) = (ctx.runner, ctx.temperatures_only);
        let hs: Vec<Result<History, SimError>> = std::thread::scope(|sc| {
            let jobs: Vec<_> = scheds
                .iter()
                .map(|s| sc.spawn(move || simulate(runner, temps, s, span)))
                .collect();
            jobs.into_iter()
                .map(|j| j.join().expect("a re-simulation does not panic"))
                .collect()
        });
        ctx.runs += pair.len();
        for ((k, s), h) in pair.iter().zip(&scheds).zip(hs) {
            let h = h?;
            let mut p = Point {
                k: k.clone(),
                m: Vec::new(),
                passed: true,
                apertures: Vec::new(),
            };
            for z in cands {
                let r = ctx.check(&h, s, z.zone_id(), ctx.rules.epoch.day(z.planned));
                let mz = margins(&r);
                p.passed &= r.verdict.groutable();
                p.m.extend(mz);
                p.apertures.push(mz[0] + ctx.rules.settings.min_aperture_mm);
            }
            out.push(p);
        }
    }
    Ok(out)
}

/// Whether zone `a` is a neighbour of zone `b`: another zone on the same
/// or an adjacent joint (they share a block) at the same or the next level
/// (their cooled regions meet: a zone is cooled with the lifts above it).
/// Zones further apart are coupled by conduction only, and spend no
/// finite-difference run.
fn neighbours(a: ZoneId, b: ZoneId) -> bool {
    a != b && a.joint.abs_diff(b.joint) <= 1 && a.zone.abs_diff(b.zone) <= 1
}

/// The free zones in sets of neighbours (connected components), each in
/// the order of `ids`.
fn sets(ids: &[ZoneId], free: &[bool]) -> Vec<Vec<ZoneId>> {
    let mut set_of: Vec<Option<usize>> = vec![None; ids.len()];
    let mut out: Vec<Vec<ZoneId>> = Vec::new();
    for start in (0..ids.len()).filter(|&i| free[i]) {
        if set_of[start].is_some() {
            continue;
        }
        let n = out.len();
        set_of[start] = Some(n);
        let mut stack = vec![start];
        while let Some(i) = stack.pop() {
            for j in 0..ids.len() {
                if set_of[j].is_none() && neighbours(ids[i], ids[j]) {
                    set_of[j] = Some(n);
                    stack.push(j);
                }
            }
        }
        out.push(
            (0..ids.len())
                .filter(|&i| set_of[i] == Some(n))
                .map(|i| ids[i])
                .collect(),
        );
    }
    out
}

/// The least-cost set of supercooling steps for the zones `cands` (see the
/// module doc), starting from the zone-by-zone answer `zbz` (steps per
/// zone, in the order of `cands`). None when no zone has a neighbour.
pub(super) fn optimise(
    ctx: &mut Ctx,
    cands: &[&ZoneReadiness],
    zbz: &[u32],
    k_max: u32,
    span: &Span,
    build: &BuildSupercooled,
) -> Result<Option<Together>, SimError> {
    let ids: Vec<ZoneId> = cands.iter().map(|z| z.zone_id()).collect();
    let free: Vec<bool> = ids
        .iter()
        .map(|&a| ids.iter().any(|&b| neighbours(a, b)))
        .collect();
    if !free.contains(&true) {
        return Ok(None);
    }
    let mut points = vec![zbz.to_vec()];
    for i in (0..ids.len()).filter(|&i| free[i] && zbz[i] > 0) {
        let mut k = zbz.to_vec();
        k[i] -= 1;
        points.push(k);
    }
    let mut seen = evaluate(ctx, cands, span, build, &points)?;
    let x0: Vec<f64> = zbz.iter().map(|&k| k as f64).collect();
    let mut model = Linear {
        x0: x0.clone(),
        m0: seen[0].m.clone(),
        s: vec![vec![0.0; ids.len()]; seen[0].m.len()],
    };
    for p in &seen[1..] {
        let i = (0..ids.len())
            .find(|&i| p.k[i] != zbz[i])
            .expect("one step");
        for (r, row) in model.s.iter_mut().enumerate() {
            let ds = model.m0[r] - p.m[r];
            row[i] = if ds.is_finite() { ds } else { 0.0 };
        }
    }
    let step_cost = ctx.rules.settings.supercooling_step_c * ctx.rules.settings.cost_per_degree_c;
    let cost = vec![step_cost.max(1e-9); ids.len()];
    let (lo, hi): (Vec<f64>, Vec<f64>) = (0..ids.len())
        .map(|i| match free[i] {
            true => ((x0[i] - REACH).max(0.0), (x0[i] + REACH).min(k_max as f64)),
            false => (x0[i], x0[i]),
        })
        .unzip();
    let total = |k: &[u32]| k.iter().map(|&v| v as u64).sum::<u64>();
    for _ in 0..ROUNDS {
        let best = seen.iter().filter(|p| p.passed).map(|p| total(&p.k)).min();
        let x = match least_cost(&model, &cost, &lo, &hi, &LpSettings::default()) {
            Ok(x) => x,
            Err(e) => {
                (ctx.progress)(&format!("{e}; keeping the best set verified so far"));
                break;
            }
        };
        let refuted = |k: &[u32]| seen.iter().any(|p| p.k == k);
        let Some(k) = round_to_grid(&model, &x, &cost, &lo, &hi, &refuted) else {
            break;
        };
        if best.is_some_and(|b| total(&k) >= b) {
            break;
        }
        let p = evaluate(ctx, cands, span, build, std::slice::from_ref(&k))?
            .pop()
            .expect("one run");
        let kf: Vec<f64> = k.iter().map(|&v| v as f64).collect();
        let (passed, m) = (p.passed, p.m.clone());
        seen.push(p);
        if passed {
            break;
        }
        model.secant(&kf, &m);
    }
    let Some(best) = seen.iter().filter(|p| p.passed).min_by_key(|p| total(&p.k)) else {
        return Ok(None);
    };
    Ok(Some(Together {
        ks: ids.iter().copied().zip(best.k.iter().copied()).collect(),
        apertures: ids.iter().copied().zip(best.apertures.clone()).collect(),
        zone_by_zone: ids.iter().copied().zip(zbz.iter().copied()).collect(),
        zone_by_zone_held: seen[0].passed,
        sets: sets(&ids, &free),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two zones sharing a block: each margin rises 0.10 per own step and
    /// 0.05 per the other's; both at 0.13 at k* = (4, 4).
    fn pair() -> Linear {
        Linear {
            x0: vec![4.0, 4.0],
            m0: vec![0.13, 0.13],
            s: vec![vec![0.10, 0.05], vec![0.05, 0.10]],
        }
    }

    /// min x1 + x2 s.t. 0.13 + 0.10 d1 + 0.05 d2 ≥ 0 and its mirror: the
    /// two rows meet at d1 = d2 = −0.13/0.15.
    #[test]
    fn the_program_finds_the_vertex_of_a_known_optimum() {
        let (lo, hi) = ([0.0, 0.0], [8.0, 8.0]);
        let x = least_cost(&pair(), &[1.0, 1.0], &lo, &hi, &LpSettings::default()).unwrap();
        for v in &x {
            assert!((v - (4.0 - 0.13 / 0.15)).abs() < 1e-6, "{x:?}");
        }
        // With the second zone four times dearer it pays to cool the first
        // to its bound: on the second row d2 = −1.3 − 0.5 d1, so the cost
        // d1 + 4 d2 = −d1 − 5.2 falls as d1 rises, to d1 = 4, d2 = −3.3
        // (the first row holds there: 0.13 + 0.4 − 0.165 > 0).
        let x = least_cost(&pair(), &[1.0, 4.0], &lo, &hi, &LpSettings::default()).unwrap();
        assert!((x[0] - 8.0).abs() < 1e-6, "{x:?}");
        assert!((x[1] - 0.7).abs() < 1e-6, "{x:?}");
    }

    /// A program no bound can satisfy is infeasible, not a wrong answer.
    #[test]
    fn an_impossible_set_is_infeasible() {
        let m = Linear {
            x0: vec![0.0],
            m0: vec![-1.0],
            s: vec![vec![0.1]],
        };
        let e = least_cost(&m, &[1.0], &[0.0], &[4.0], &LpSettings::default());
        assert_eq!(e, Err(JointError::Infeasible));
        let bad = LpSettings {
            tolerance: 0.0,
            ..LpSettings::default()
        };
        assert!(matches!(
            least_cost(&m, &[1.0], &[0.0], &[4.0], &bad),
            Err(JointError::Settings(_))
        ));
    }

    /// The LP's (3.13, 3.13) rounds to one zone a step lower, not both
    /// (both would fail: 0.13 − 0.15 < 0), and never to a refuted point.
    #[test]
    fn rounding_keeps_the_cheapest_point_predicted_to_pass() {
        let m = pair();
        let (c, lo, hi) = ([1.0, 1.0], [0.0, 0.0], [8.0, 8.0]);
        let x = [4.0 - 0.13 / 0.15; 2];
        let k = round_to_grid(&m, &x, &c, &lo, &hi, &|_| false).unwrap();
        assert_eq!(k.iter().sum::<u32>(), 7, "{k:?}");
        let refuted = |k: &[u32]| k == [3, 4] || k == [4, 3];
        assert_eq!(
            round_to_grid(&m, &x, &c, &lo, &hi, &refuted),
            Some(vec![4, 4])
        );
    }

    /// Zone 2 of joints 1 to 4 form one chain of neighbours; zone 3 of
    /// joint 4 joins it (the next level); zone 4 of joint 1 does not, and
    /// a zone that is not free is in no set.
    #[test]
    fn neighbours_form_sets_by_shared_blocks_and_levels() {
        let z = ZoneId::new;
        let ids = [
            z(1, 2),
            z(3, 2),
            z(1, 4),
            z(2, 2),
            z(4, 3),
            z(4, 2),
            z(2, 9),
        ];
        let free = [true, true, true, true, true, true, false];
        let s = sets(&ids, &free);
        assert_eq!(
            s,
            vec![
                vec![z(1, 2), z(3, 2), z(2, 2), z(4, 3), z(4, 2)],
                vec![z(1, 4)]
            ]
        );
    }

    /// After a secant update the model reproduces the run it was given,
    /// and is unchanged across the step.
    #[test]
    fn the_secant_update_reproduces_the_run() {
        let mut m = pair();
        m.secant(&[3.0, 3.0], &[-0.2, 0.05]);
        let p = m.predict(&[3.0, 3.0]);
        assert!((p[0] + 0.2).abs() < 1e-12 && (p[1] - 0.05).abs() < 1e-12);
        let across = m.predict(&[5.0, 3.0]);
        let before = pair().predict(&[5.0, 3.0]);
        for r in 0..2 {
            assert!((across[r] - before[r]).abs() < 1e-12);
        }
        // A non-finite row (a rule not measured) is left alone.
        let mut n = pair();
        n.m0[1] = f64::INFINITY;
        n.secant(&[3.0, 3.0], &[-0.2, 0.05]);
        assert_eq!(n.s[1], pair().s[1]);
    }
}
