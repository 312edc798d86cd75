//! The remedy search. Every answer comes from a re-simulation of an edited
//! schedule that restarts from the baseline checkpoint before the edit:
//!
//! - **supercooling**: the zones whose only failures are aperture and
//!   temperature are searched together on the grid `k·step ≤ max`. One run at
//!   the largest ΔT tells which zones supercooling can fix at all; then each
//!   round runs every unresolved zone at the middle of its bracket (resolved
//!   zones at their upper end) and halves each bracket by that zone's own
//!   verdict. Cooling a zone opens its neighbours too, so the combined
//!   answer is verified by one more run (and a zone that fails there gets
//!   one step more, up to the maximum). When every candidate fails on its
//!   temperature alone (its joint already open enough), the search and the
//!   set chosen together below run the thermal effects alone
//!   ([`Runner::simulate_temperatures`]: the same temperatures to the bit,
//!   10–15× cheaper on the demo) and their answer is confirmed by a run
//!   with every effect, whose apertures it reports; a joint that closes
//!   under it sends the search back to runs with every effect;
//! - **supercooling together**: zones that are neighbours (sharing a block,
//!   at the same or the next level) are then chosen as one least-cost set
//!   from that answer by a linear program on finite-difference
//!   sensitivities, each set verified by re-simulation ([`super::joint_remedy`]);
//!   the zone-by-zone answer stays when nothing cheaper is verified. It is
//!   part of the supercooling search (and of its memo part);
//! - **delay**: one run with the flagged zones left ungrouted and every day
//!   of the delay window a step end, read bottom-up per joint; zones above
//!   on the same joint planned earlier than the new date move with it. The
//!   run stops once every zone has its day ([`Simulation::run_until`]; an
//!   answer reads no row after its day, so the rest of the window would
//!   change nothing);
//! - the cheaper remedy by the scene's cost weights is proposed, and all
//!   proposals are applied together in a final run that re-checks every zone
//!   still to grout and keeps each remedied zone's history in that run, from
//!   the as-of date to its date with the remedy (`Remedy::verified_history`,
//!   drawn by the charts). That run is the plan's last and runs alone, so
//!   it factorises each mechanical step ahead on the second core; the
//!   searches' runs, two side by side, do not, but for the delay run,
//!   which outlasts the supercooling search beside it. With
//!   `planner.search_max_step_days` above 1 the searches' runs (not the
//!   verification) take longer mechanical steps ([`Runner::search_scene`])
//!   and the delay run reads every that-many-th day: the plan's verdicts
//!   stay the verification's, on the scene's own steps.
//!
//! Verified by `tests/it/planner_*.rs`, `tests/it/demo_plan.rs`,
//! `tests/it/cli_plan.rs` and `tests/it/restart.rs` (a thermal run's zone
//! temperatures equal the whole run's to the bit, a stopped run's rows its
//! prefix).

use std::collections::{BTreeMap, HashMap};

use chrono::NaiveDate;

use crate::scene::PlannerSettings;
use crate::schedule::{DamLayout, Schedules};
use crate::sim::{History, SimError, Simulation};
use crate::vocab::{Day, ZoneId};

use super::edit::{self, Supercool};
use super::joint_remedy;
use super::limits;
use super::memo::{digest, DelayPart, Found, Lineage, Part, SearchMemo, SupercoolPart, Verified};
use super::plan::zone_history;
use super::readiness::{
    ChosenTogether, DelayOption, Remedy, RemedyChoice, Rule, SupercoolOption, Verdict, ZoneHistory,
    ZoneReadiness, CAUTION_MARK,
};
use super::rules::{HistoryIndex, Rules};
use super::runner::{Runner, Span};

/// What the search proposes, and the schedules with every proposal applied.
pub struct Outcome {
    pub remedies: HashMap<ZoneId, Remedy>,
    /// the remedied schedules (None when nothing is proposed)
    pub schedules: Option<Schedules>,
    /// zones still to grout that were groutable but fail once the remedies
    /// are applied, with their readiness then
    pub newly_flagged: Vec<ZoneReadiness>,
    /// what the next plan may reuse
    pub memo: SearchMemo,
    /// the verification's run, with its checkpoints
    pub lineage: Option<Lineage>,
    /// the parts taken from the last plan, in words
    pub reused: Vec<String>,
}

/// The grouting day of every zone in `s`.
pub fn grout_days(rules: &Rules, s: &Schedules) -> HashMap<ZoneId, Day> {
    s.grouting
        .iter()
        .map(|g| (g.zone_id(), rules.epoch.day(g.planned)))
        .collect()
}

pub(super) struct Ctx<'x, 'r, 'a> {
    pub(super) runner: &'x Runner<'a>,
    /// remedies act from this date on
    as_of: NaiveDate,
    pub(super) rules: &'x Rules<'r>,
    layout: &'x DamLayout,
    pub(super) progress: &'x mut dyn FnMut(&str),
    /// the runs this search made, and the last day it read
    pub(super) runs: usize,
    read_until: Day,
    /// runs simulate the thermal effects alone and checks leave the
    /// aperture out (a search on temperatures; see [`supercool_search`])
    pub(super) temperatures_only: bool,
}

impl<'x, 'r, 'a> Ctx<'x, 'r, 'a> {
    fn new(
        runner: &'x Runner<'a>,
        as_of: NaiveDate,
        rules: &'x Rules<'r>,
        layout: &'x DamLayout,
        progress: &'x mut dyn FnMut(&str),
    ) -> Self {
        Ctx {
            runner,
            as_of,
            rules,
            layout,
            progress,
            runs: 0,
            read_until: Day(i64::MIN),
            temperatures_only: false,
        }
    }

    fn run(&mut self, what: &str, s: &Schedules, span: &Span) -> Result<History, SimError> {
        (self.progress)(what);
        self.runs += 1;
        simulate(self.runner, self.temperatures_only, s, span)
    }

    /// Notes that the search's answer depends on the runs up to `day`.
    fn read(&mut self, day: Day) {
        self.read_until = self.read_until.max(day);
    }

    pub(super) fn check(&self, h: &History, s: &Schedules, key: ZoneId, day: Day) -> ZoneReadiness {
        let grout = grout_days(self.rules, s);
        let mut r = self.rules.evaluate(&HistoryIndex::new(h), key, day, &grout);
        if self.temperatures_only {
            // a thermal run has no apertures: the search reads the other rules
            r.checks.retain(|c| c.rule != Rule::Aperture);
            if r.checks.iter().all(|c| c.passed) {
                r.verdict = Verdict::Groutable;
            }
        }
        r
    }
}

/// A re-simulation of `s`: of every effect, or of the thermal ones alone.
pub(super) fn simulate(
    runner: &Runner,
    temperatures_only: bool,
    s: &Schedules,
    span: &Span,
) -> Result<History, SimError> {
    if temperatures_only {
        runner.simulate_temperatures(s, span)
    } else {
        runner.simulate_search(s, span)
    }
}

/// What a search part's answer depends on besides the schedules: the as-of
/// date, the settings (but the verification's limits), the flagged zones' readiness on their dates (not
/// whether they re-open later: the baseline's end decides that) and the
/// grouting dates of the zones below them (the bottom-up rule reads them,
/// whatever the date).
fn search_key(
    as_of: NaiveDate,
    rules: &Rules,
    grout: &HashMap<ZoneId, Day>,
    flagged: &[ZoneReadiness],
) -> u64 {
    let below: Vec<(ZoneId, Option<Day>)> = flagged
        .iter()
        .filter_map(|z| rules.zone_below(z.zone_id()))
        .map(|b| (b, grout.get(&b).copied()))
        .collect();
    let on_their_dates: Vec<ZoneReadiness> = flagged
        .iter()
        .map(|z| ZoneReadiness {
            reopened: None,
            ..z.clone()
        })
        .collect();
    // The limits read only by the verification are in its own key: a
    // tighter limit re-runs the verification, not the searches.
    let searched = PlannerSettings {
        max_below_closure_c: 0.0,
        max_cooling_rate_c_per_day: 0.0,
        max_zone_gradient_c: 0.0,
        ..rules.settings.clone()
    };
    digest(&(as_of, searched, on_their_dates, below))
}

/// Searches remedies for the `flagged` zones; `to_grout` are all zones still
/// to grout (re-checked in the final run). `last` holds the last plan's
/// search and the first day the schedules changed since: the parts whose
/// inputs did not change are taken from it ([`super::memo`]).
#[allow(clippy::too_many_arguments)]
pub fn search(
    runner: &Runner<'_>,
    as_of: NaiveDate,
    rules: &Rules<'_>,
    layout: &DamLayout,
    flagged: &[ZoneReadiness],
    to_grout: &[ZoneId],
    last: Option<(&SearchMemo, Option<Day>)>,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, SimError> {
    let base = runner.base.clone();
    let grout = grout_days(rules, &base);
    let key = search_key(as_of, rules, &grout, flagged);
    let mut ctx = Ctx::new(runner, as_of, rules, layout, progress);
    let mut reused = Vec::new();
    let (supercool, delay) = both_searches(&mut ctx, &base, flagged, key, last, &mut reused)?;
    let remedies: HashMap<ZoneId, Remedy> = flagged
        .iter()
        .map(|z| {
            (
                z.zone_id(),
                propose(z.zone_id(), &supercool.value, &delay.value, rules.settings),
            )
        })
        .collect();
    let sorted: BTreeMap<ZoneId, &Remedy> = remedies.iter().map(|(k, r)| (*k, r)).collect();
    let grouting: BTreeMap<ZoneId, Day> = grout.into_iter().collect();
    let vkey = digest(&(key, rules.settings, to_grout, sorted, grouting));
    let old = last.and_then(|(m, first)| m.verified.as_ref().filter(|p| p.valid(vkey, first)));
    let (verified, schedules, lineage) = match old {
        Some(p) => {
            (ctx.progress)("reusing the last plan's verification");
            reused.push(runs_saved("verification", p.runs));
            let remedies: HashMap<ZoneId, Remedy> = p.value.remedies.iter().cloned().collect();
            let schedules = remedied_schedules(&ctx, &base, flagged, &remedies);
            (p.clone(), schedules, runner.lineages.first().cloned())
        }
        None => {
            ctx.runs = 0;
            ctx.read_until = Day(i64::MIN);
            let mut remedies = remedies;
            let (schedules, newly_flagged, lineage) =
                verify_together(&mut ctx, &base, flagged, to_grout, &mut remedies)?;
            let mut value = Verified {
                remedies: remedies.into_iter().collect(),
                newly_flagged,
            };
            value.remedies.sort_by_key(|r| r.0);
            (part(vkey, &ctx, value), schedules, lineage)
        }
    };
    Ok(Outcome {
        remedies: verified.value.remedies.iter().cloned().collect(),
        schedules,
        newly_flagged: verified.value.newly_flagged.clone(),
        memo: SearchMemo {
            supercool: Some(supercool),
            delay: Some(delay),
            verified: Some(verified),
        },
        lineage,
        reused,
    })
}

/// The supercooling and the delay search, each taken from `last` (the last
/// plan's memo and the first day the schedules changed since) when its
/// inputs did not change, else run. The two are independent: the delay
/// search runs beside the supercooling search (the simulations are
/// single-threaded at this size). Each returns its own findings, joined by
/// name later, so the outcome does not depend on which finishes first.
fn both_searches(
    ctx: &mut Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
    key: u64,
    last: Option<(&SearchMemo, Option<Day>)>,
    reused: &mut Vec<String>,
) -> Result<(SupercoolPart, DelayPart), SimError> {
    let first = last.and_then(|l| l.1);
    let sc_hit = last
        .and_then(|l| l.0.supercool.as_ref())
        .filter(|p| p.valid(key, first))
        .cloned();
    let dl_hit = last
        .and_then(|l| l.0.delay.as_ref())
        .filter(|p| p.valid(key, first))
        .cloned();
    let (runner, as_of, rules, layout) = (ctx.runner, ctx.as_of, ctx.rules, ctx.layout);
    let (supercool, delay) = std::thread::scope(|sc| {
        let delay = sc.spawn(|| {
            if let Some(p) = &dl_hit {
                return Ok::<_, SimError>(p.clone());
            }
            let mut quiet = |_: &str| {};
            let mut c = Ctx::new(runner, as_of, rules, layout, &mut quiet);
            let value = delay_search(&mut c, base, flagged)?;
            Ok(part(key, &c, value))
        });
        let supercool = match &sc_hit {
            Some(p) => Ok(p.clone()),
            None => supercool_search(ctx, base, flagged).map(|v| part(key, ctx, v)),
        };
        (
            supercool,
            delay.join().expect("the delay search does not panic"),
        )
    });
    let (supercool, delay) = (supercool?, delay?);
    for (hit, what, runs) in [
        (sc_hit.is_some(), "supercooling search", supercool.runs),
        (dl_hit.is_some(), "delay search", delay.runs),
    ] {
        if hit {
            (ctx.progress)(&format!("reusing the last plan's {what}"));
            reused.push(runs_saved(what, runs));
        }
    }
    Ok((supercool, delay))
}

/// "delay search (1 run)": a reused part and the runs it saved.
fn runs_saved(what: &str, runs: usize) -> String {
    format!("{what} ({runs} run{})", if runs == 1 { "" } else { "s" })
}

/// A search part's answer with what it depended on.
fn part<T>(key: u64, ctx: &Ctx, value: T) -> Part<T> {
    Part {
        key,
        read_until: ctx.read_until,
        runs: ctx.runs,
        value,
    }
}

/// The cheaper of the two remedies found for a zone, by the scene's costs.
fn propose(
    key: ZoneId,
    supercool: &Found<SupercoolOption>,
    delay: &Found<DelayOption>,
    s: &PlannerSettings,
) -> Remedy {
    let (sc, note_sc) = supercool
        .get(&key)
        .cloned()
        .unwrap_or((None, String::new()));
    let (dl, note_dl) = delay.get(&key).cloned().unwrap_or((None, String::new()));
    let cost_sc = sc.as_ref().map(|o| o.delta_c * s.cost_per_degree_c);
    let cost_dl = dl
        .as_ref()
        .map(|o| o.days as f64 * s.cost_per_day * (1 + o.also_delayed.len()) as f64);
    let choice = match (cost_sc, cost_dl) {
        (Some(a), Some(b)) if a <= b => RemedyChoice::Supercool,
        (Some(_), Some(_)) => RemedyChoice::Delay,
        (Some(_), None) => RemedyChoice::Supercool,
        (None, Some(_)) => RemedyChoice::Delay,
        (None, None) => RemedyChoice::None,
    };
    let together = sc.as_ref().and_then(|o| o.together.as_ref());
    let note = match choice {
        RemedyChoice::Supercool if together.is_some() => {
            let t = together.expect("some");
            let with: Vec<String> = t.with.iter().map(ZoneId::to_string).collect();
            if t.zone_by_zone_held {
                format!(
                    "supercooled together with {}: {:.2} °C in all against {:.2} °C zone by zone \
                     ({:.2} °C for this zone alone)",
                    with.join(", "),
                    t.set_c,
                    t.set_zone_by_zone_c,
                    t.zone_by_zone_c
                )
            } else {
                format!(
                    "supercooled together with {}: {:.2} °C in all, verified; the zone-by-zone \
                     steps ({:.2} °C in all, {:.2} °C for this zone) failed applied together",
                    with.join(", "),
                    t.set_c,
                    t.set_zone_by_zone_c,
                    t.zone_by_zone_c
                )
            }
        }
        RemedyChoice::Supercool => match cost_dl {
            Some(c) => format!(
                "supercooling costs {:.2} against {:.2} for the delay",
                cost_sc.unwrap_or(0.0),
                c
            ),
            None => format!("supercooling; {note_dl}"),
        },
        RemedyChoice::Delay => match cost_sc {
            Some(c) => format!(
                "the delay costs {:.2} against {:.2} for supercooling",
                cost_dl.unwrap_or(0.0),
                c
            ),
            None => format!("delay; {note_sc}"),
        },
        RemedyChoice::None => {
            format!("neither remedy works within the limits: {note_sc}; {note_dl}")
        }
    };
    Remedy {
        supercool: sc,
        delay: dl,
        choice,
        verified: None,
        note,
        verified_history: None,
        limited: Vec::new(),
    }
}

/// All proposals together, re-simulated. A remedied zone that fails there
/// (its neighbours' remedies differ from those of the search) gets one
/// supercooling step or one week more, up to the limits, and the run is
/// repeated (at most three rounds). Returns the remedied schedules (None
/// when nothing is proposed), the zones the remedies newly flag and the
/// last round's run with its checkpoints.
type Together = (Option<Schedules>, Vec<ZoneReadiness>, Option<Lineage>);

fn verify_together(
    ctx: &mut Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
    to_grout: &[ZoneId],
    remedies: &mut HashMap<ZoneId, Remedy>,
) -> Result<Together, SimError> {
    let rules = ctx.rules;
    let baseline = HistoryIndex::new(&ctx.runner.history);
    let closure: HashMap<ZoneId, f64> = flagged
        .iter()
        .map(|z| (z.zone_id(), z.closure_temp_c))
        .collect();
    let mut round = 0;
    loop {
        let Some(remedied) = remedied_schedules(ctx, base, flagged, remedies) else {
            return Ok((None, Vec::new(), None));
        };
        let new_days = grout_days(rules, &remedied);
        let end = to_grout
            .iter()
            .filter_map(|k| new_days.get(k))
            .fold(Day(0), |a, &b| a.max(b));
        (ctx.progress)("verifying all remedies together");
        ctx.runs += 1;
        ctx.read(end);
        let span = Span {
            end_day: end,
            observe: vec![],
        };
        let every = rules.settings.checkpoint_days as i64;
        let lineage = ctx.runner.simulate_lineage(&remedied, &span, every)?;
        let idx = HistoryIndex::new(&lineage.history);
        let mut newly_flagged = Vec::new();
        let mut failing = Vec::new();
        // a supercooling a site limit stopped: the set changed, run it again
        let mut limited = false;
        for &key in to_grout {
            let Some(&day) = new_days.get(&key) else {
                continue;
            };
            let r = rules.evaluate(&idx, key, day, &new_days);
            match remedies.get_mut(&key) {
                Some(rem) => {
                    let a = rules.deciding_aperture(&idx, key, day);
                    rem.verified = Some((r.verdict, a));
                    // Without a remedy the run is no answer for this zone.
                    rem.verified_history = (rem.choice != RemedyChoice::None).then(|| {
                        let h = zone_history(rules, &idx, key, rules.epoch.date(day));
                        clip(h, ctx.as_of)
                    });
                    if rem.choice == RemedyChoice::Supercool {
                        if let (Some(o), Some(a)) = (rem.supercool.as_mut(), a) {
                            o.aperture_mm = a;
                        }
                        let from = rules.epoch.day(ctx.as_of);
                        let c = closure.get(&key).copied().unwrap_or(f64::NAN);
                        let v = limits::breaches(rules, &idx, &baseline, key, c, from, day);
                        if !v.broken.is_empty() {
                            stop_supercooling(rem, v.broken);
                            limited = true;
                            continue;
                        }
                        caution(rem, &v.cautions);
                    }
                    if rem.choice != RemedyChoice::None && !r.verdict.groutable() {
                        failing.push(key);
                    }
                }
                None if !r.verdict.groutable() => newly_flagged.push(r),
                None => {}
            }
        }
        if !limited && (failing.is_empty() || round >= 2) {
            return Ok((Some(remedied), newly_flagged, Some(lineage)));
        }
        for key in failing {
            if let Some(rem) = remedies.get_mut(&key) {
                strengthen(rem, rules.settings);
            }
        }
        round += 1;
    }
}

/// A verification run's history of a zone from the as-of date (before it
/// the run is the baseline) to the zone's date with the remedy (after it
/// the zone is grouted).
fn clip(mut h: ZoneHistory, from: NaiveDate) -> ZoneHistory {
    let keep: Vec<bool> = h
        .dates
        .iter()
        .map(|&d| d >= from && d <= h.planned)
        .collect();
    let mut k = keep.iter();
    h.dates.retain(|_| *k.next().expect("one flag per date"));
    for v in [
        &mut h.upstream,
        &mut h.center,
        &mut h.downstream,
        &mut h.min,
        &mut h.temperature,
    ] {
        let mut k = keep.iter();
        v.retain(|_| *k.next().expect("one flag per date"));
    }
    h
}

/// The base schedules with every proposed remedy applied; None when nothing
/// is proposed.
fn remedied_schedules(
    ctx: &Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
    remedies: &HashMap<ZoneId, Remedy>,
) -> Option<Schedules> {
    let cooled: Vec<Supercool> = flagged
        .iter()
        .filter_map(|z| {
            let r = &remedies[&z.zone_id()];
            (r.choice == RemedyChoice::Supercool).then(|| Supercool {
                zone: z.zone_id(),
                delta_c: r.supercool.as_ref().map_or(0.0, |o| o.delta_c),
                planned: z.planned,
                from: ctx.as_of,
            })
        })
        .collect();
    let mut moves: Vec<(ZoneId, NaiveDate)> = Vec::new();
    for z in flagged {
        let r = &remedies[&z.zone_id()];
        if let (RemedyChoice::Delay, Some(d)) = (r.choice, &r.delay) {
            moves.push((z.zone_id(), d.date));
            for &above in &d.also_delayed {
                moves.push((ZoneId::new(z.joint, above), d.date));
            }
        }
    }
    if cooled.is_empty() && moves.is_empty() {
        return None;
    }
    let coldest = ctx.rules.settings.min_water_temp_c;
    let (cooled_s, _) =
        edit::supercool_with_water(base, ctx.layout, &cooled, lifts_above(ctx.rules), coldest);
    Some(edit::regrout(&cooled_s, &moves))
}

/// A supercooling that breaks site limits is not proposed: the delay is,
/// if one was found, and the note says which limits stopped it.
fn stop_supercooling(rem: &mut Remedy, broken: Vec<limits::Breach>) {
    let dt = rem.supercool.as_ref().map_or(0.0, |o| o.delta_c);
    let instead = if rem.delay.is_some() {
        rem.choice = RemedyChoice::Delay;
        "the delay instead"
    } else {
        rem.choice = RemedyChoice::None;
        "no other remedy was found"
    };
    rem.note = format!(
        "supercooling {dt:.2} °C is stopped by a site limit ({}); {instead}",
        broken.join("; ")
    );
    rem.verified_history = None;
    rem.limited = broken;
}

/// Notes the limits the schedule is past already and the remedy too (once
/// per verification round: the last round's stand).
fn caution(rem: &mut Remedy, cautions: &[limits::Breach]) {
    if let Some(i) = rem.note.find(CAUTION_MARK) {
        rem.note.truncate(i);
    }
    if !cautions.is_empty() {
        rem.note = format!("{}{CAUTION_MARK}{}", rem.note, cautions.join("; "));
    }
}

/// One supercooling step or one week more for a remedy that failed among
/// the others, within the limits.
fn strengthen(rem: &mut Remedy, s: &PlannerSettings) {
    match (rem.choice, rem.supercool.as_mut(), rem.delay.as_mut()) {
        (RemedyChoice::Supercool, Some(o), _)
            if o.delta_c + s.supercooling_step_c <= s.max_supercooling_c + 1e-9 =>
        {
            o.delta_c += s.supercooling_step_c;
            rem.note = format!(
                "{}; raised to {:.2} °C: the zones' remedies together needed more",
                rem.note, o.delta_c
            );
        }
        (RemedyChoice::Delay, _, Some(d)) if d.days + 7 <= s.max_delay_days => {
            d.days += 7;
            d.date += chrono::Duration::days(7);
            rem.note = format!(
                "{}; lengthened to {} days: the zones' remedies together needed more",
                rem.note, d.days
            );
        }
        _ => {}
    }
}

pub(crate) fn lifts_above(rules: &Rules) -> u32 {
    (rules.settings.supercool_above_m / rules.lift_height).round() as u32
}

/// How far a zone is from passing the rules cooling can fix, per rule
/// (aperture in mm above the limit, temperature in °C below the limit);
/// every entry ≥ 0 when they pass.
pub(super) fn margins(r: &ZoneReadiness) -> [f64; 2] {
    let mut m = [f64::INFINITY; 2];
    for c in &r.checks {
        match (c.rule, c.value) {
            (Rule::Aperture, Some(v)) => m[0] = v - c.limit,
            (Rule::Aperture, None) => m[0] = f64::NEG_INFINITY,
            (Rule::Temperature, Some(v)) => m[1] = c.limit - v,
            _ => {}
        }
    }
    m
}

/// The grid point where every margin is predicted to reach 0, by linear
/// interpolation between a failing (`lo`) and a passing (`hi`) run; inside
/// (lo, hi).
fn interpolate(lo: (u32, [f64; 2]), hi: (u32, [f64; 2])) -> u32 {
    let mut k = lo.0 as f64 + 1.0;
    for r in 0..2 {
        let (f0, f1) = (lo.1[r], hi.1[r]);
        if f0 < 0.0 && f0.is_finite() && f1.is_finite() && f1 > f0 {
            let x = lo.0 as f64 + (hi.0 - lo.0) as f64 * (-f0) / (f1 - f0);
            k = k.max(x.ceil());
        } else if f0 < 0.0 {
            k = k.max(((lo.0 + hi.0) / 2) as f64);
        }
    }
    (k as u32).clamp(lo.0 + 1, hi.0 - 1)
}

/// One zone's bracket: a failing and a passing grid point with their
/// margins, and which end moved last (two moves of the same end in a row
/// switch the next proposal to bisection, as in the Illinois method).
struct Bracket {
    lo: (u32, [f64; 2]),
    hi: (u32, [f64; 2]),
    same_side: u32,
    last_hi: Option<bool>,
}

impl Bracket {
    fn open(&self) -> bool {
        self.hi.0 - self.lo.0 > 1
    }

    fn proposal(&self) -> u32 {
        if !self.open() {
            self.hi.0
        } else if self.same_side >= 1 {
            (self.lo.0 + self.hi.0) / 2
        } else {
            interpolate(self.lo, self.hi)
        }
    }

    fn update(&mut self, k: u32, m: [f64; 2], passed: bool) {
        self.same_side = if self.last_hi == Some(passed) {
            self.same_side + 1
        } else {
            0
        };
        self.last_hi = Some(passed);
        if passed {
            self.hi = (k, m);
        } else {
            self.lo = (k, m);
        }
    }
}

/// Supercooling on the grid `k·step ≤ max`, all candidate zones in the
/// same runs: one run at the largest ΔT brackets each zone, then each round
/// halves every open bracket (see the module doc).
///
/// When every candidate fails on its temperature alone (its joint already
/// open enough), the least supercooling is a question for the heat
/// equation: the grid search and the set chosen together run the thermal
/// effects alone ([`Runner::simulate_temperatures`], the same temperatures
/// at a fraction of the cost), and the answer is confirmed by a run with
/// every effect ([`confirm_with_mechanics`]), whose apertures it reports.
/// Should a joint close under the answer there, the search runs again with
/// every effect.
fn supercool_search(
    ctx: &mut Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
) -> Result<Found<SupercoolOption>, SimError> {
    let s = ctx.rules.settings;
    let mut out: Found<SupercoolOption> = HashMap::new();
    let k_max = (s.max_supercooling_c / s.supercooling_step_c + 1e-9).floor() as u32;
    let cands = supercool_candidates(flagged, k_max, &mut out);
    if cands.is_empty() {
        return Ok(out);
    }
    let step = s.supercooling_step_c;
    let above = lifts_above(ctx.rules);
    let from = ctx.as_of;
    let end = cands
        .iter()
        .map(|z| ctx.rules.epoch.day(z.planned))
        .fold(Day(0), Day::max);
    let span = Span {
        end_day: end,
        observe: vec![],
    };
    ctx.read(end);
    let edits = |ks: &BTreeMap<ZoneId, u32>| -> Vec<Supercool> {
        cands
            .iter()
            .filter_map(|z| {
                ks.get(&z.zone_id()).map(|&k| Supercool {
                    zone: z.zone_id(),
                    delta_c: k as f64 * step,
                    planned: z.planned,
                    from,
                })
            })
            .collect()
    };
    let layout = ctx.layout;
    let build = |ks: &BTreeMap<ZoneId, u32>| {
        edit::supercool_with_water(base, layout, &edits(ks), above, s.min_water_temp_c)
    };
    let open_enough = |z: &&ZoneReadiness| {
        z.checks
            .iter()
            .any(|c| c.rule == Rule::Aperture && c.passed)
    };
    if cands.iter().all(open_enough) {
        ctx.temperatures_only = true;
        let found = grid_search(ctx, &cands, k_max, &span, &build);
        ctx.temperatures_only = false;
        if let Some(found) = confirm_with_mechanics(ctx, &cands, found?, &span, &build)? {
            out.extend(found);
            return Ok(out);
        }
        (ctx.progress)("a joint closes under the supercooling found on temperatures: searching with every effect");
    }
    out.extend(grid_search(ctx, &cands, k_max, &span, &build)?);
    Ok(out)
}

/// The search of [`supercool_search`] on the runs `ctx` makes: the
/// brackets, their rounds and the sets chosen together.
fn grid_search(
    ctx: &mut Ctx,
    cands: &[&ZoneReadiness],
    k_max: u32,
    span: &Span,
    build: &BuildSupercooled,
) -> Result<Found<SupercoolOption>, SimError> {
    let s = ctx.rules.settings;
    let step = s.supercooling_step_c;
    let mut out: Found<SupercoolOption> = HashMap::new();
    let mut brackets = bracket_at_max(ctx, cands, k_max, span, build, &mut out)?;
    // Bracketed search on the grid, all zones in the same runs.
    while brackets.values().any(Bracket::open) {
        let ks: BTreeMap<ZoneId, u32> = brackets.iter().map(|(&k, b)| (k, b.proposal())).collect();
        let (sched, _) = build(&ks);
        let h = ctx.run(
            &format!("supercooling search, {} zones", brackets.len()),
            &sched,
            span,
        )?;
        for (key, b) in brackets.iter_mut() {
            if !b.open() {
                continue;
            }
            let z = cands
                .iter()
                .find(|z| z.zone_id() == *key)
                .expect("candidate");
            let r = ctx.check(&h, &sched, *key, ctx.rules.epoch.day(z.planned));
            b.update(ks[key], margins(&r), r.verdict.groutable());
        }
    }
    for (key, b) in &brackets {
        out.insert(
            *key,
            (
                Some(SupercoolOption {
                    delta_c: b.hi.0 as f64 * step,
                    // the deciding aperture of the run that passed
                    aperture_mm: b.hi.1[0] + s.min_aperture_mm,
                    together: None,
                }),
                String::new(),
            ),
        );
    }
    // Neighbours chosen together, at least cost (issue 15 item 3).
    let group: Vec<&ZoneReadiness> = cands
        .iter()
        .copied()
        .filter(|z| brackets.contains_key(&z.zone_id()))
        .collect();
    let zbz: Vec<u32> = group.iter().map(|z| brackets[&z.zone_id()].hi.0).collect();
    if let Some(t) = joint_remedy::optimise(ctx, &group, &zbz, k_max, span, build)? {
        chosen_together(&t, step, &mut out);
    }
    Ok(out)
}

/// Runs the supercooling `found` on temperatures with every effect, once:
/// the proposed steps. Returns `found` with the deciding apertures of that
/// run, or None when a proposed zone is not groutable there (a joint
/// closed).
///
/// Where a set was chosen together, whether the zone-by-zone steps held
/// applied together stays as the temperature runs that found the set read
/// it (`Together::zone_by_zone_held`): every candidate here was open enough
/// and failed on temperature alone. A second run with every effect for it
/// cost the demo's plan a whole re-simulation (2 s of its 32 s; its
/// searches' runs share the 2 cores) to word a note about a remedy not
/// proposed.
fn confirm_with_mechanics(
    ctx: &mut Ctx,
    cands: &[&ZoneReadiness],
    mut found: Found<SupercoolOption>,
    span: &Span,
    build: &BuildSupercooled,
) -> Result<Option<Found<SupercoolOption>>, SimError> {
    let step = ctx.rules.settings.supercooling_step_c;
    let grid = |c: f64| (c / step).round() as u32;
    let proposed: BTreeMap<ZoneId, u32> = found
        .iter()
        .filter_map(|(k, (o, _))| o.as_ref().map(|o| (*k, grid(o.delta_c))))
        .collect();
    if proposed.is_empty() {
        return Ok(Some(found));
    }
    let group: Vec<&ZoneReadiness> = cands
        .iter()
        .copied()
        .filter(|z| proposed.contains_key(&z.zone_id()))
        .collect();
    let ids: Vec<ZoneId> = group.iter().map(|z| z.zone_id()).collect();
    let ks = vec![ids.iter().map(|z| proposed[z]).collect()];
    let run = joint_remedy::evaluate(ctx, &group, span, build, &ks)?
        .pop()
        .expect("one run");
    if !run.passed {
        return Ok(None);
    }
    for (i, z) in ids.iter().enumerate() {
        if let Some((Some(o), _)) = found.get_mut(z) {
            o.aperture_mm = run.apertures[i];
        }
    }
    Ok(Some(found))
}

/// Writes each set of neighbours the joint step changed into `out` (each
/// zone of the set names the others); the sets together cost less than
/// zone by zone (`joint_remedy::optimise` keeps no dearer point).
fn chosen_together(t: &joint_remedy::Together, step: f64, out: &mut Found<SupercoolOption>) {
    for set in &t.sets {
        if set.iter().all(|z| t.ks[z] == t.zone_by_zone[z]) {
            continue;
        }
        let sum =
            |ks: &BTreeMap<ZoneId, u32>| -> f64 { set.iter().map(|z| ks[z] as f64 * step).sum() };
        let (set_c, set_zone_by_zone_c) = (sum(&t.ks), sum(&t.zone_by_zone));
        for z in set {
            out.insert(
                *z,
                (
                    Some(SupercoolOption {
                        delta_c: t.ks[z] as f64 * step,
                        aperture_mm: t.apertures[z],
                        together: Some(ChosenTogether {
                            with: set.iter().copied().filter(|w| w != z).collect(),
                            zone_by_zone_c: t.zone_by_zone[z] as f64 * step,
                            set_c,
                            set_zone_by_zone_c,
                            zone_by_zone_held: t.zone_by_zone_held,
                        }),
                    }),
                    String::new(),
                ),
            );
        }
    }
}

/// The flagged zones that supercooling may fix: those failing only the
/// aperture and temperature rules; the others get their reason in `out`.
fn supercool_candidates<'z>(
    flagged: &'z [ZoneReadiness],
    k_max: u32,
    out: &mut Found<SupercoolOption>,
) -> Vec<&'z ZoneReadiness> {
    let mut cands: Vec<&ZoneReadiness> = Vec::new();
    for z in flagged {
        let blocking: Vec<&str> = z
            .checks
            .iter()
            .filter(|c| !c.passed && !matches!(c.rule, Rule::Aperture | Rule::Temperature))
            .map(|c| c.rule.as_str())
            .collect();
        if !blocking.is_empty() {
            out.insert(
                z.zone_id(),
                (
                    None,
                    format!("cooling cannot fix the {} rule", blocking.join(", ")),
                ),
            );
        } else if k_max == 0 {
            out.insert(
                z.zone_id(),
                (None, "supercooling is not allowed (max 0 °C)".into()),
            );
        } else {
            cands.push(z);
        }
    }
    cands
}

/// Builds the schedules with each zone supercooled by its grid step count;
/// returns them and the zones none of whose stages could be edited.
pub(super) type BuildSupercooled<'b> =
    dyn Fn(&BTreeMap<ZoneId, u32>) -> (Schedules, Vec<ZoneId>) + 'b;

/// Runs every candidate at the largest supercooling: the zones it makes
/// groutable get a bracket [0, max]; the others their reason in `out`.
fn bracket_at_max(
    ctx: &mut Ctx,
    cands: &[&ZoneReadiness],
    k_max: u32,
    span: &Span,
    build: &BuildSupercooled,
    out: &mut Found<SupercoolOption>,
) -> Result<BTreeMap<ZoneId, Bracket>, SimError> {
    let step = ctx.rules.settings.supercooling_step_c;
    // Can the largest supercooling fix each zone at all?
    let all_max: BTreeMap<ZoneId, u32> = cands.iter().map(|z| (z.zone_id(), k_max)).collect();
    let (s_max, not_editable) = build(&all_max);
    let h = ctx.run(
        &format!(
            "supercooling {} zones by {:.2} °C",
            cands.len(),
            k_max as f64 * step
        ),
        &s_max,
        span,
    )?;
    let mut brackets: BTreeMap<ZoneId, Bracket> = BTreeMap::new();
    for z in cands {
        let key = z.zone_id();
        if not_editable.contains(&key) {
            out.insert(
                key,
                (
                    None,
                    "its lifts have no cooling stage with a target to lower".into(),
                ),
            );
            continue;
        }
        let r = ctx.check(&h, &s_max, key, ctx.rules.epoch.day(z.planned));
        if r.verdict.groutable() {
            brackets.insert(
                key,
                Bracket {
                    lo: (0, margins(z)),
                    hi: (k_max, margins(&r)),
                    same_side: 0,
                    last_hi: None,
                },
            );
        } else {
            let why = format!(
                "even {:.2} °C of supercooling leaves it not groutable ({}){}",
                k_max as f64 * step,
                r.reasons(),
                water_note(ctx, z, k_max as f64 * step)
            );
            out.insert(key, (None, why));
        }
    }
    Ok(brackets)
}

/// "; the coldest water allowed, 8.0 °C, held its water" when that limit
/// kept a stage the zone's supercooling edits from its full ΔT.
fn water_note(ctx: &Ctx, z: &ZoneReadiness, delta_c: f64) -> String {
    let s = ctx.rules.settings;
    let sc = Supercool {
        zone: z.zone_id(),
        delta_c,
        planned: z.planned,
        from: ctx.as_of,
    };
    let above = lifts_above(ctx.rules);
    if edit::water_held(&ctx.runner.base, ctx.layout, &sc, above, s.min_water_temp_c) {
        format!(
            "; the coldest water allowed, {:.1} °C, held its water (site limit)",
            s.min_water_temp_c
        )
    } else {
        String::new()
    }
}

fn delay_search(
    ctx: &mut Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
) -> Result<Found<DelayOption>, SimError> {
    let s = ctx.rules.settings;
    let mut out: Found<DelayOption> = HashMap::new();
    if flagged.is_empty() || s.max_delay_days == 0 {
        for z in flagged {
            out.insert(
                z.zone_id(),
                (None, "delays are not allowed (max 0 days)".into()),
            );
        }
        return Ok(out);
    }
    let keys: Vec<ZoneId> = flagged.iter().map(|z| z.zone_id()).collect();
    let days = flagged.iter().map(|z| ctx.rules.epoch.day(z.planned));
    let first = days.clone().min().unwrap_or_default();
    let last = days.fold(Day(0), Day::max);
    let end = last.plus(s.max_delay_days as i64);
    // every day, or every `search_max_step_days`-th: the run's step ends
    let every = s.search_max_step_days.max(1) as usize;
    let span = Span {
        end_day: end,
        observe: (first.0..=end.0).step_by(every).map(Day).collect(),
    };
    let sched = edit::ungrout(base, &keys);
    (ctx.progress)(&format!(
        "{} zones left ungrouted for up to {} days",
        keys.len(),
        s.max_delay_days
    ));
    ctx.runs += 1;
    // The run stops once every zone has its day: an answer reads no row
    // after it, so the rest of the window would change nothing.
    let rules = ctx.rules;
    let mut stop = |day: Day, sim: &Simulation| {
        day > first
            && (day.0 - first.0) % DELAY_STOP_CHECK_DAYS == 0
            && delay_days(rules, base, flagged, &sim.history())
                .iter()
                .all(|(_, d)| d.found())
    };
    let h = ctx.runner.simulate_until(&sched, &span, &mut stop, true)?;
    for (key, d) in delay_days(rules, base, flagged, &h) {
        match d {
            DelayDay::Found {
                days,
                day,
                also,
                aperture_mm,
            } => {
                ctx.read(day);
                let option = DelayOption {
                    days,
                    date: ctx.rules.epoch.date(day),
                    aperture_mm,
                    also_delayed: also,
                };
                out.insert(key, (Some(option), String::new()));
            }
            DelayDay::NotFound { last, at_last } => {
                ctx.read(last);
                let why = format!(
                    "still not groutable after {} days of delay ({})",
                    s.max_delay_days,
                    at_last.reasons()
                );
                out.insert(key, (None, why));
            }
        }
    }
    Ok(out)
}

/// How often (in days) the delay run asks whether it may stop: each ask
/// reads the whole history so far.
const DELAY_STOP_CHECK_DAYS: i64 = 5;

/// A flagged zone's outcome in the delay run.
enum DelayDay {
    /// groutable after `days` of delay, on `day`, with the zones above on
    /// the same joint planned before it (they move with it) and the
    /// deciding aperture then \[mm\]
    Found {
        days: u32,
        day: Day,
        also: Vec<u32>,
        aperture_mm: f64,
    },
    /// not groutable up to `last` (the window's or the run's end); its
    /// readiness then
    NotFound {
        last: Day,
        at_last: Box<ZoneReadiness>,
    },
}

impl DelayDay {
    fn found(&self) -> bool {
        matches!(self, DelayDay::Found { .. })
    }
}

/// Each flagged zone's first day within the delay window on which every
/// rule passes in the run `h`, bottom-up per joint so that a lower zone's
/// new date is known above it. An answer reads no row after its day.
fn delay_days(
    rules: &Rules,
    base: &Schedules,
    flagged: &[ZoneReadiness],
    h: &History,
) -> Vec<(ZoneId, DelayDay)> {
    let s = rules.settings;
    let idx = HistoryIndex::new(h);
    let sim_end = h.joint_records.rows.last().map_or(Day(0), |r| r.0);
    let mut grout = grout_days(rules, base);
    let mut order: Vec<&ZoneReadiness> = flagged.iter().collect();
    order.sort_by_key(|z| (z.joint, z.zone));
    let mut out = Vec::with_capacity(order.len());
    for z in order {
        let (key, planned) = (z.zone_id(), rules.epoch.day(z.planned));
        let mut found = None;
        for d in 1..=s.max_delay_days {
            let day = planned.plus(d as i64);
            if day > sim_end {
                break;
            }
            grout.insert(key, day);
            if rules
                .evaluate(&idx, key, day, &grout)
                .checks
                .iter()
                .all(|c| c.passed)
            {
                found = Some((d, day));
                break;
            }
        }
        let outcome = match found {
            Some((days, day)) => {
                let also: Vec<u32> = base
                    .grouting
                    .iter()
                    .filter(|g| g.joint == z.joint && g.zone > z.zone)
                    .filter(|g| rules.epoch.day(g.planned) < day)
                    .map(|g| g.zone)
                    .collect();
                for &above in &also {
                    grout.insert(ZoneId::new(z.joint, above), day);
                }
                let aperture_mm = rules.deciding_aperture(&idx, key, day).unwrap_or(f64::NAN);
                DelayDay::Found {
                    days,
                    day,
                    also,
                    aperture_mm,
                }
            }
            None => {
                grout.insert(key, planned);
                let last = planned.plus(s.max_delay_days as i64).min(sim_end);
                let at_last = Box::new(rules.evaluate(&idx, key, last, &grout));
                DelayDay::NotFound { last, at_last }
            }
        };
        out.push((key, outcome));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A set chosen together is described by what it saved, or, when the
    /// zone-by-zone steps failed applied together, as what holding them
    /// together costs: never as a saving it is not.
    #[test]
    fn a_set_dearer_than_zone_by_zone_is_not_called_a_saving() {
        let key = ZoneId::new(6, 4);
        let option = |set_c: f64, held: bool| SupercoolOption {
            delta_c: 3.0,
            aperture_mm: 1.9,
            together: Some(ChosenTogether {
                with: vec![ZoneId::new(7, 4)],
                zone_by_zone_c: 2.75,
                set_c,
                set_zone_by_zone_c: 3.25,
                zone_by_zone_held: held,
            }),
        };
        let s = PlannerSettings::default();
        let note = |o: SupercoolOption| {
            let found: Found<SupercoolOption> = [(key, (Some(o), String::new()))].into();
            propose(key, &found, &Found::new(), &s).note
        };
        let saved = note(option(2.5, true));
        assert!(
            saved.contains("2.50 °C in all against 3.25 °C zone by zone"),
            "{saved}"
        );
        let dearer = note(option(4.5, false));
        assert!(!dearer.contains("against"), "{dearer}");
        assert!(
            dearer.contains("4.50 °C in all, verified; the zone-by-zone steps (3.25 °C in all, 2.75 °C for this zone) failed applied together"),
            "{dearer}"
        );
    }
}
