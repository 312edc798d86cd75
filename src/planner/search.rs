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
//!   one step more, up to the maximum);
//! - **delay**: one run with the flagged zones left ungrouted and every day
//!   of the delay window a step end, read bottom-up per joint; zones above
//!   on the same joint planned earlier than the new date move with it;
//! - the cheaper remedy by the scene's cost weights is proposed, and all
//!   proposals are applied together in a final run that re-checks every zone
//!   still to grout.

use std::collections::{BTreeMap, HashMap};

use chrono::NaiveDate;

use crate::schedule::{DamLayout, Schedules};
use crate::sim::{History, SimError};

use super::edit::{self, Supercool};
use super::readiness::{
    DelayOption, Remedy, RemedyChoice, Rule, SupercoolOption, Verdict, ZoneReadiness,
};
use super::rules::{HistoryIndex, Rules};
use super::runner::{Runner, Span};

type Key = (u32, u32);

/// What the search proposes, and the schedules with every proposal applied.
pub struct Outcome {
    pub remedies: HashMap<Key, Remedy>,
    /// the remedied schedules (None when nothing is proposed)
    pub schedules: Option<Schedules>,
    /// zones still to grout that were groutable but fail once the remedies
    /// are applied, with their readiness then
    pub newly_flagged: Vec<ZoneReadiness>,
}

pub fn grout_days(rules: &Rules, s: &Schedules) -> HashMap<Key, f64> {
    s.grouting
        .iter()
        .map(|g| ((g.joint, g.zone), rules.day(g.planned)))
        .collect()
}

struct Ctx<'x, 'r, 'a> {
    runner: &'x mut Runner<'a>,
    rules: &'x Rules<'r>,
    layout: &'x DamLayout,
    progress: &'x mut dyn FnMut(&str),
}

impl Ctx<'_, '_, '_> {
    fn run(&mut self, what: &str, s: &Schedules, span: &Span) -> Result<History, SimError> {
        (self.progress)(what);
        self.runner.simulate(s, span)
    }

    fn check(&self, h: &History, s: &Schedules, key: Key, day: f64) -> ZoneReadiness {
        let grout = grout_days(self.rules, s);
        self.rules
            .evaluate(&HistoryIndex::new(h), key.0, key.1, day, &grout)
    }
}

/// Searches remedies for the `flagged` zones; `to_grout` are all zones still
/// to grout (re-checked in the final run).
pub fn search(
    runner: &mut Runner<'_>,
    rules: &Rules<'_>,
    layout: &DamLayout,
    flagged: &[ZoneReadiness],
    to_grout: &[Key],
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, SimError> {
    let base = runner.base.clone();
    let mut ctx = Ctx {
        runner,
        rules,
        layout,
        progress,
    };
    let supercool = supercool_search(&mut ctx, &base, flagged)?;
    let delay = delay_search(&mut ctx, &base, flagged)?;
    let s = rules.settings;

    let mut remedies: HashMap<Key, Remedy> = HashMap::new();
    for z in flagged {
        let key = (z.joint, z.zone);
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
        let note = match choice {
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
        remedies.insert(
            key,
            Remedy {
                supercool: sc,
                delay: dl,
                choice,
                verified: None,
                note,
            },
        );
    }

    // All proposals together, re-simulated.
    let cooled: Vec<Supercool> = flagged
        .iter()
        .filter_map(|z| {
            let r = &remedies[&(z.joint, z.zone)];
            (r.choice == RemedyChoice::Supercool).then(|| Supercool {
                joint: z.joint,
                zone: z.zone,
                delta_c: r.supercool.as_ref().map_or(0.0, |o| o.delta_c),
                planned: z.planned,
            })
        })
        .collect();
    let mut moves: Vec<(u32, u32, NaiveDate)> = Vec::new();
    for z in flagged {
        let r = &remedies[&(z.joint, z.zone)];
        if let (RemedyChoice::Delay, Some(d)) = (r.choice, &r.delay) {
            moves.push((z.joint, z.zone, d.date));
            for &above in &d.also_delayed {
                moves.push((z.joint, above, d.date));
            }
        }
    }
    if cooled.is_empty() && moves.is_empty() {
        return Ok(Outcome {
            remedies,
            schedules: None,
            newly_flagged: Vec::new(),
        });
    }
    let lifts_above = lifts_above(rules);
    let (cooled_s, _) = edit::supercool(&base, layout, &cooled, lifts_above);
    let remedied = edit::regrout(&cooled_s, &moves);
    let new_days = grout_days(rules, &remedied);
    let end = to_grout
        .iter()
        .filter_map(|k| new_days.get(k))
        .fold(0.0f64, |a, &b| a.max(b)) as i64;
    let h = ctx.run(
        "verifying all remedies together",
        &remedied,
        &Span {
            end_day: end,
            observe: vec![],
        },
    )?;
    let idx = HistoryIndex::new(&h);
    let mut newly_flagged = Vec::new();
    for &key in to_grout {
        let Some(&day) = new_days.get(&key) else {
            continue;
        };
        let r = rules.evaluate(&idx, key.0, key.1, day, &new_days);
        match remedies.get_mut(&key) {
            Some(rem) => {
                rem.verified = Some((r.verdict, rules.deciding_aperture(&idx, key.0, key.1, day)))
            }
            None if !r.verdict.groutable() => newly_flagged.push(r),
            None => {}
        }
    }
    Ok(Outcome {
        remedies,
        schedules: Some(remedied),
        newly_flagged,
    })
}

fn lifts_above(rules: &Rules) -> u32 {
    (rules.settings.supercool_above_m / rules.lift_height).round() as u32
}

type Found<T> = HashMap<Key, (Option<T>, String)>;

fn supercool_search(
    ctx: &mut Ctx,
    base: &Schedules,
    flagged: &[ZoneReadiness],
) -> Result<Found<SupercoolOption>, SimError> {
    let s = ctx.rules.settings;
    let mut out: Found<SupercoolOption> = HashMap::new();
    let k_max = (s.max_supercooling_c / s.supercooling_step_c).floor() as u32;
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
                (z.joint, z.zone),
                (
                    None,
                    format!("cooling cannot fix the {} rule", blocking.join(", ")),
                ),
            );
        } else if k_max == 0 {
            out.insert(
                (z.joint, z.zone),
                (None, "supercooling is not allowed (max 0 °C)".into()),
            );
        } else {
            cands.push(z);
        }
    }
    if cands.is_empty() {
        return Ok(out);
    }
    let step = s.supercooling_step_c;
    let above = lifts_above(ctx.rules);
    let end = cands
        .iter()
        .map(|z| ctx.rules.day(z.planned))
        .fold(0.0f64, f64::max) as i64;
    let span = Span {
        end_day: end,
        observe: vec![],
    };
    let edits = |ks: &BTreeMap<Key, u32>| -> Vec<Supercool> {
        cands
            .iter()
            .filter_map(|z| {
                ks.get(&(z.joint, z.zone)).map(|&k| Supercool {
                    joint: z.joint,
                    zone: z.zone,
                    delta_c: k as f64 * step,
                    planned: z.planned,
                })
            })
            .collect()
    };
    let layout = ctx.layout;
    let build = |ks: &BTreeMap<Key, u32>| edit::supercool(base, layout, &edits(ks), above);

    // Can the largest supercooling fix each zone at all?
    let all_max: BTreeMap<Key, u32> = cands.iter().map(|z| ((z.joint, z.zone), k_max)).collect();
    let (s_max, not_editable) = build(&all_max);
    let h = ctx.run(
        &format!(
            "supercooling {} zones by {:.2} °C",
            cands.len(),
            k_max as f64 * step
        ),
        &s_max,
        &span,
    )?;
    let mut bracket: BTreeMap<Key, (u32, u32)> = BTreeMap::new();
    for z in &cands {
        let key = (z.joint, z.zone);
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
        let r = ctx.check(&h, &s_max, key, ctx.rules.day(z.planned));
        if r.verdict.groutable() {
            bracket.insert(key, (0, k_max));
        } else {
            out.insert(
                key,
                (
                    None,
                    format!(
                        "even {:.2} °C of supercooling leaves it not groutable ({})",
                        k_max as f64 * step,
                        r.reasons()
                    ),
                ),
            );
        }
    }
    // Bisection, all zones in the same runs.
    while bracket.values().any(|&(lo, hi)| hi - lo > 1) {
        let ks: BTreeMap<Key, u32> = bracket
            .iter()
            .map(|(&k, &(lo, hi))| (k, if hi - lo > 1 { (lo + hi) / 2 } else { hi }))
            .collect();
        let (sched, _) = build(&ks);
        let h = ctx.run(
            &format!("supercooling bisection, {} zones", bracket.len()),
            &sched,
            &span,
        )?;
        for (key, (lo, hi)) in bracket.iter_mut() {
            if *hi - *lo <= 1 {
                continue;
            }
            let mid = ks[key];
            let z = cands
                .iter()
                .find(|z| (z.joint, z.zone) == *key)
                .expect("candidate");
            if ctx
                .check(&h, &sched, *key, ctx.rules.day(z.planned))
                .verdict
                .groutable()
            {
                *hi = mid;
            } else {
                *lo = mid;
            }
        }
    }
    // Together at their upper ends; a zone its neighbours' cooling no longer
    // carries gets one step more.
    let mut ks: BTreeMap<Key, u32> = bracket.iter().map(|(&k, &(_, hi))| (k, hi)).collect();
    for round in 0..3 {
        if ks.is_empty() {
            break;
        }
        let (sched, _) = build(&ks);
        let h = ctx.run("supercooling, verifying the zones together", &sched, &span)?;
        let idx = HistoryIndex::new(&h);
        let mut bumped = false;
        for z in &cands {
            let key = (z.joint, z.zone);
            let Some(k) = ks.get(&key).copied() else {
                continue;
            };
            let day = ctx.rules.day(z.planned);
            let r = ctx.check(&h, &sched, key, day);
            if r.verdict.groutable() {
                let a = ctx
                    .rules
                    .deciding_aperture(&idx, key.0, key.1, day)
                    .unwrap_or(f64::NAN);
                out.insert(
                    key,
                    (
                        Some(SupercoolOption {
                            delta_c: k as f64 * step,
                            aperture_mm: a,
                        }),
                        String::new(),
                    ),
                );
            } else if k < k_max && round < 2 {
                ks.insert(key, k + 1);
                out.remove(&key);
                bumped = true;
            } else {
                ks.remove(&key);
                out.insert(
                    key,
                    (None, format!("supercooling together with its neighbours leaves it not groutable ({})", r.reasons())),
                );
            }
        }
        if !bumped {
            break;
        }
    }
    Ok(out)
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
                (z.joint, z.zone),
                (None, "delays are not allowed (max 0 days)".into()),
            );
        }
        return Ok(out);
    }
    let keys: Vec<Key> = flagged.iter().map(|z| (z.joint, z.zone)).collect();
    let first = flagged
        .iter()
        .map(|z| ctx.rules.day(z.planned))
        .fold(f64::INFINITY, f64::min) as i64;
    let last = flagged
        .iter()
        .map(|z| ctx.rules.day(z.planned))
        .fold(0.0f64, f64::max) as i64;
    let end = last + s.max_delay_days as i64;
    let span = Span {
        end_day: end,
        observe: (first..=end).collect(),
    };
    let sched = edit::ungrout(base, &keys);
    let h = ctx.run(
        &format!(
            "{} zones left ungrouted for up to {} days",
            keys.len(),
            s.max_delay_days
        ),
        &sched,
        &span,
    )?;
    let idx = HistoryIndex::new(&h);
    let sim_end = h.joint_records.rows.last().map_or(0.0, |r| r.0);
    let mut grout = grout_days(ctx.rules, base);
    // Bottom-up per joint, so a lower zone's new date is known above it.
    let mut order: Vec<&ZoneReadiness> = flagged.iter().collect();
    order.sort_by_key(|z| (z.joint, z.zone));
    for z in order {
        let key = (z.joint, z.zone);
        let planned = ctx.rules.day(z.planned);
        let mut found = None;
        for d in 1..=s.max_delay_days {
            let day = planned + d as f64;
            if day > sim_end {
                break;
            }
            grout.insert(key, day);
            if ctx
                .rules
                .evaluate(&idx, key.0, key.1, day, &grout)
                .checks
                .iter()
                .all(|c| c.passed)
            {
                found = Some((d, day));
                break;
            }
        }
        match found {
            Some((days, day)) => {
                let also: Vec<u32> = base
                    .grouting
                    .iter()
                    .filter(|g| g.joint == z.joint && g.zone > z.zone)
                    .filter(|g| ctx.rules.day(g.planned) < day)
                    .map(|g| g.zone)
                    .collect();
                for &above in &also {
                    grout.insert((z.joint, above), day);
                }
                let a = ctx
                    .rules
                    .deciding_aperture(&idx, key.0, key.1, day)
                    .unwrap_or(f64::NAN);
                out.insert(
                    key,
                    (
                        Some(DelayOption {
                            days,
                            date: ctx.rules.date(day),
                            aperture_mm: a,
                            also_delayed: also,
                        }),
                        String::new(),
                    ),
                );
            }
            None => {
                grout.insert(key, planned);
                let at_end = ctx.rules.evaluate(
                    &idx,
                    key.0,
                    key.1,
                    (planned + s.max_delay_days as f64).min(sim_end),
                    &grout,
                );
                out.insert(
                    key,
                    (
                        None,
                        format!(
                            "still not groutable after {} days of delay ({})",
                            s.max_delay_days,
                            at_end.reasons()
                        ),
                    ),
                );
            }
        }
    }
    let _ = Verdict::Groutable;
    Ok(out)
}
