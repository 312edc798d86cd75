//! What accuracy costs in time: `groutready study accuracy`.
//!
//! A ladder of settings of one scene (discretisation and solver knobs, each
//! varied alone from the scene as given, the presets, and a reference: the
//! finest affordable run, without the scene's opt-in approximations of the
//! mechanics, so a scene that has some is measured with their error) is
//! simulated to the last zone's planned date.
//! Every zone is judged on its planned date by the planner's own rules
//! ([`Rules::evaluate`]), and each setting is compared with the reference
//! at the zone points (upstream, centre, downstream, minimum), which every
//! mesh of the same geometry has: the largest and RMS error of the deciding
//! aperture, the largest error of the two blocks' zone temperatures, the
//! zones whose verdict differs, against the dofs and wall time it cost.
//!
//! A knob refined geometrically (steps scaled by 2, elements doubled) gets a
//! convergence rate p fitted by least squares to log d against log h, d the
//! largest deciding-aperture difference between successive levels (the
//! differences, not the errors against the reference: those carry the
//! other knobs' error as an offset). The reference's own error is estimated
//! per knob by Richardson from the knob's two finest levels,
//! |a_fine − a_coarse| / (r^p − 1) with r their ratio of h (p = 1 where
//! no rate was fitted or the fitted one is below 0.5), plus the
//! difference between the knob's finest level and the reference's level of
//! it where the reference does not refine it; the knobs' estimates are
//! added (their errors assumed independent). The Pareto front (no other
//! setting both faster and more accurate) is marked in the table and chart.
//!
//! Verified by the unit tests below (front on a hand-made table, the rate
//! of e = C·h² is 2 to 1e-12) and `tests/it/study_accuracy.rs` (a tiny
//! ladder on the small dam: the reference's error is 0, a copy of the
//! reference has error 0, a coarser setting does not, the files exist).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::app;
use crate::mesh::geometry::Geometry;
use crate::planner::rules::{HistoryIndex, Rules};
use crate::planner::search::grout_days;
use crate::planner::{Apertures, Verdict};
use crate::scene::{Approximation, CapacityKind, Preset, Scene, ScheduledStep, ThermalSolverKind};
use crate::schedule::Schedules;
use crate::sim::{dam_layout, Simulation};
use crate::vocab::{fnv1a, Day, ZoneId};

use super::StudyError;

/// An edit of the scene a setting makes.
pub type Edit = Box<dyn Fn(&mut Scene) + Send + Sync>;

/// One setting of the ladder.
pub struct Setting {
    /// short name, unique in the ladder ("steps ×0.5", "reference")
    pub name: String,
    /// the knob varied from the scene as given: settings of one knob with
    /// an `h` form its refinement chain; the scene as given is every
    /// chain's h = 1 ([`SCENE`]), the reference is [`REFERENCE`]
    pub knob: String,
    /// the knob's refinement parameter relative to the scene's (smaller is
    /// finer); None where the knob is not refined geometrically
    pub h: Option<f64>,
    pub edit: Edit,
}

/// Knob name of the scene as given.
pub const SCENE: &str = "scene";
/// Knob name of the reference.
pub const REFERENCE: &str = "reference";

impl Setting {
    pub fn new(
        name: impl Into<String>,
        knob: impl Into<String>,
        h: Option<f64>,
        edit: impl Fn(&mut Scene) + Send + Sync + 'static,
    ) -> Setting {
        Setting {
            name: name.into(),
            knob: knob.into(),
            h,
            edit: Box::new(edit),
        }
    }
}

/// The reference: the finest setting, with its level of each refined knob
/// (knobs not named are at the scene's level, h = 1), on the exact path's
/// mechanics ([`Scene::without_approximations`]).
pub struct Reference {
    pub setting: Setting,
    pub levels: Vec<(String, f64)>,
}

/// One row of the accuracy table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub name: String,
    pub knob: String,
    pub h: Option<f64>,
    pub elements: usize,
    pub thermal_dofs: usize,
    /// largest live mechanical system (0 without mechanics)
    pub mech_dofs: usize,
    pub steps: usize,
    /// mesh generation and simulation \[s\]
    pub seconds: f64,
    /// deciding aperture against the reference, over the zones \[mm\]
    pub max_aperture_err_mm: f64,
    pub rms_aperture_err_mm: f64,
    /// any of the four zone points \[mm\]
    pub max_point_err_mm: f64,
    /// either block's zone temperature [°C]
    pub max_temp_err_c: f64,
    pub verdicts_differ: usize,
    /// of those, the zones the reference decides: a zone is not counted
    /// when the two deciding apertures lie either side of an aperture limit
    /// (`min_aperture_mm`, `marginal_aperture_mm`) and the reference's lies
    /// within its own estimated error of it ([`verdicts_beyond_band`])
    pub verdicts_beyond_band: usize,
    /// fitted rate of this row's knob chain
    pub rate: Option<f64>,
    pub pareto: bool,
}

/// The study's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct AccuracyTable {
    pub scene: String,
    pub zones: usize,
    pub rows: Vec<Row>,
    /// Richardson estimate of the reference's deciding-aperture error \[mm\]
    pub reference_error_mm: f64,
    /// how the estimate was made, knob by knob
    pub reference_note: String,
    /// the same estimate of the warmer block's zone temperature [°C]
    pub reference_error_c: f64,
    pub reference_note_c: String,
    /// settings whose run failed, with the error
    pub failed: Vec<(String, String)>,
    /// every setting's reading of every judged zone, in ladder order
    pub zone_values: Vec<ZoneValues>,
}

/// What one setting read at one zone on its planned date: the rows of
/// `accuracy_zones.csv`, which say where the settings disagree.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneValues {
    pub setting: String,
    pub zone: ZoneId,
    pub planned: chrono::NaiveDate,
    /// the deciding aperture \[mm\]
    pub deciding_mm: Option<f64>,
    /// the zone's mean temperature in blocks A and B [°C]
    pub temps_c: [Option<f64>; 2],
    pub verdict: Verdict,
}

/// What one run gives at a zone on its planned date.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Sample {
    apertures: Apertures,
    deciding: Option<f64>,
    temps: [Option<f64>; 2],
    /// the temperature rule's limit at the zone: closure + tolerance [°C]
    temp_limit_c: f64,
    verdict: Verdict,
}

impl Sample {
    /// The warmer of the two blocks' zone temperatures, which the
    /// temperature rule decides on [°C].
    fn warmer(&self) -> Option<f64> {
        match self.temps {
            [Some(a), Some(b)] => Some(a.max(b)),
            [a, b] => a.or(b),
        }
    }
}

/// What a Richardson estimate is made of: the deciding aperture \[mm\] or
/// the warmer block's zone temperature [°C].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Quantity {
    Aperture,
    Temperature,
}

impl Quantity {
    fn of(self, s: &Sample) -> Option<f64> {
        match self {
            Quantity::Aperture => s.deciding,
            Quantity::Temperature => s.warmer(),
        }
    }

    fn unit(self) -> &'static str {
        match self {
            Quantity::Aperture => "mm",
            Quantity::Temperature => "°C",
        }
    }
}

/// A finished run of one setting.
struct Outcome {
    row: Row,
    samples: HashMap<ZoneId, Sample>,
}

/// The zones judged: every zone of grouting.csv planned within
/// `horizon_days` of the epoch (all without one), by planned day.
fn judged_zones(scene: &Scene, s: &Schedules, horizon_days: Option<i64>) -> Vec<(Day, ZoneId)> {
    let mut z: Vec<(Day, ZoneId)> = s
        .grouting
        .iter()
        .map(|g| (scene.epoch.day(g.planned), g.zone_id()))
        .filter(|(d, _)| horizon_days.is_none_or(|h| d.0 <= h))
        .collect();
    z.sort();
    z
}

/// Simulates one setting to the last judged zone and judges every zone.
fn run_setting(
    base: &Scene,
    schedules: &Schedules,
    zones: &[(Day, ZoneId)],
    setting: &Setting,
) -> Result<Outcome, StudyError> {
    let mut scene = base.clone();
    (setting.edit)(&mut scene);
    let what = format!("{} ({})", scene.name, setting.name);
    scene.validate().map_err(|e| e.with_origin(&what))?;
    let t = Instant::now();
    let mesh = app::build_mesh(&scene, &what)?;
    let run_err = |source| StudyError::Run {
        what: what.clone(),
        source,
    };
    let mut sim = Simulation::new(&scene, &mesh, schedules).map_err(run_err)?;
    if let Some(&(last, _)) = zones.last() {
        sim.timeline.end_day = sim.timeline.end_day.min(last);
    }
    let stats = sim.run(None, &mut |_, _| {}).map_err(run_err)?;
    let seconds = t.elapsed().as_secs_f64();
    let history = sim.history();
    let layout = dam_layout(&mesh);
    let rules = Rules::new(&scene.planner, &layout, &mesh, scene.epoch, schedules);
    let idx = HistoryIndex::new(&history);
    let grout = grout_days(&rules, schedules);
    let samples = zones
        .iter()
        .map(|&(day, id)| {
            let r = rules.evaluate(&idx, id, day, &grout);
            let sample = Sample {
                deciding: r.apertures_mm.at(scene.planner.aperture_point),
                apertures: r.apertures_mm,
                temps: [r.temp_a_c, r.temp_b_c],
                temp_limit_c: r.closure_temp_c + scene.planner.closure_tolerance_c,
                verdict: r.verdict,
            };
            (id, sample)
        })
        .collect();
    let row = Row {
        name: setting.name.clone(),
        knob: setting.knob.clone(),
        h: setting.h,
        elements: mesh.elements.len(),
        thermal_dofs: mesh.n_thermal_dofs,
        mech_dofs: stats.mechanics.map_or(0, |m| m.max_dofs),
        steps: stats.steps,
        seconds,
        max_aperture_err_mm: 0.0,
        rms_aperture_err_mm: 0.0,
        max_point_err_mm: 0.0,
        max_temp_err_c: 0.0,
        verdicts_differ: 0,
        verdicts_beyond_band: 0,
        rate: None,
        pareto: false,
    };
    Ok(Outcome { row, samples })
}

/// Fills the error columns of `row` from its samples against `reference`'s.
fn compare(row: &mut Row, a: &HashMap<ZoneId, Sample>, reference: &HashMap<ZoneId, Sample>) {
    let (mut max, mut sq, mut n, mut points, mut temps, mut differ) =
        (0.0f64, 0.0, 0, 0.0f64, 0.0f64, 0);
    for (id, r) in reference {
        let Some(s) = a.get(id) else {
            differ += 1;
            continue;
        };
        differ += usize::from(s.verdict != r.verdict);
        if let (Some(x), Some(y)) = (s.deciding, r.deciding) {
            max = max.max((x - y).abs());
            sq += (x - y).powi(2);
            n += 1;
        }
        let (sa, ra) = (&s.apertures, &r.apertures);
        for (x, y) in [
            (sa.upstream, ra.upstream),
            (sa.center, ra.center),
            (sa.downstream, ra.downstream),
            (sa.min, ra.min),
        ] {
            if let (Some(x), Some(y)) = (x, y) {
                points = points.max((x - y).abs());
            }
        }
        for (x, y) in s.temps.iter().zip(&r.temps) {
            if let (Some(x), Some(y)) = (x, y) {
                temps = temps.max((x - y).abs());
            }
        }
    }
    row.max_aperture_err_mm = max;
    row.rms_aperture_err_mm = if n > 0 { (sq / n as f64).sqrt() } else { 0.0 };
    row.max_point_err_mm = points;
    row.max_temp_err_c = temps;
    row.verdicts_differ = differ;
}

/// The zones whose verdict in `a` differs from the reference's, leaving
/// out those the reference cannot decide: the two deciding apertures lie
/// either side of the aperture limit that separates the two verdicts, the
/// reference's within `band[0]` \[mm\] (its estimated error) of it; or, for
/// a not-groutable verdict against another, the two warmer zone
/// temperatures lie either side of the temperature limit, the reference's
/// within `band[1]` [°C] of it. `limits` are `[min_aperture_mm,
/// marginal_aperture_mm]`: the first separates not groutable from the
/// others (the side below it is not groutable whatever else holds), the
/// second marginal from groutable. A verdict that differs for any other
/// reason (age, cover, a missing reading) counts.
fn verdicts_beyond_band(
    a: &HashMap<ZoneId, Sample>,
    reference: &HashMap<ZoneId, Sample>,
    limits: [f64; 2],
    band: [f64; 2],
) -> usize {
    reference
        .iter()
        .filter(|(id, r)| {
            let Some(s) = a.get(id) else {
                return true;
            };
            if s.verdict == r.verdict {
                return false;
            }
            let across = |x: Option<f64>, y: Option<f64>, limit: f64, band: f64| {
                x.zip(y).is_some_and(|(x, y)| {
                    (x - limit) * (y - limit) <= 0.0 && (y - limit).abs() <= band
                })
            };
            let ng = |v: Verdict| v == Verdict::NotGroutable;
            let one_ng = ng(s.verdict) != ng(r.verdict);
            let limit = if one_ng { limits[0] } else { limits[1] };
            let by_aperture = across(s.deciding, r.deciding, limit, band[0]);
            let by_temperature = one_ng && across(s.warmer(), r.warmer(), r.temp_limit_c, band[1]);
            !(by_aperture || by_temperature)
        })
        .count()
}

/// The largest difference of `q` between two runs.
fn largest_difference(
    q: Quantity,
    a: &HashMap<ZoneId, Sample>,
    b: &HashMap<ZoneId, Sample>,
) -> f64 {
    a.iter()
        .filter_map(|(id, s)| Some((q.of(s)?, q.of(b.get(id)?)?)))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Least-squares slope of log e against log h: the rate p of e = C·h^p.
/// None with fewer than two usable points (e > 0, h > 0, distinct h).
pub fn fit_rate(h: &[f64], e: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(e)
        .filter(|(h, e)| **h > 0.0 && **e > 0.0 && h.is_finite() && e.is_finite())
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (pts.len() >= 2 && sxx > 0.0).then(|| sxy / sxx)
}

/// Which points (time, error) no other point beats: none both as fast and
/// as accurate and better in one of them.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            !points
                .iter()
                .any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

/// What identifies a reference run: the program, the scene as the
/// reference edits it, the schedule files' bytes and the judged zones.
fn reference_key(
    inputs: &app::Inputs,
    reference: &Setting,
    zones: &[(Day, ZoneId)],
) -> Result<u64, StudyError> {
    let mut scene = inputs.scene.clone();
    (reference.edit)(&mut scene);
    let mut text = format!(
        "groutready {} accuracy reference 1\n{}\n{zones:?}\n",
        env!("CARGO_PKG_VERSION"),
        serde_json::to_string(&scene).unwrap_or_default()
    );
    let dir = &inputs.schedules_dir;
    let io = |source| StudyError::Io {
        action: "reading",
        path: dir.display().to_string(),
        source,
    };
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    for f in files {
        let bytes = std::fs::read(&f).map_err(io)?;
        let _ = writeln!(text, "{} {:016x}", f.display(), fnv1a(&bytes));
    }
    Ok(fnv1a(text.as_bytes()))
}

/// A reference run kept for the next study ([`study`]'s `cache`).
#[derive(Serialize, Deserialize)]
struct CachedReference {
    key: u64,
    row: Row,
    samples: Vec<(ZoneId, Sample)>,
}

/// The reference kept in `path` under `key`; None when there is none, it
/// is unreadable or it was kept for another key.
fn cached_reference(path: &Path, key: u64) -> Option<Outcome> {
    let c: CachedReference = postcard::from_bytes(&std::fs::read(path).ok()?).ok()?;
    (c.key == key).then(|| Outcome {
        row: c.row,
        samples: c.samples.into_iter().collect(),
    })
}

/// Keeps the reference run in `path` (written whole, then renamed).
fn save_reference(path: &Path, key: u64, o: &Outcome) -> Result<(), StudyError> {
    let mut samples: Vec<(ZoneId, Sample)> = o.samples.clone().into_iter().collect();
    samples.sort_by_key(|s| s.0);
    let bytes = postcard::to_allocvec(&CachedReference {
        key,
        row: o.row.clone(),
        samples,
    })
    .unwrap_or_default();
    let io = |source| StudyError::Io {
        action: "writing",
        path: path.display().to_string(),
        source,
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Runs the ladder and the reference; `horizon_days` judges only the zones
/// planned within that many days of the epoch (and ends the runs there).
/// With `cache`, a reference run kept there for the same scene, schedules,
/// zones and program is read instead of run, and a reference that is run
/// is kept there: the reference is the ladder's dearest run, and the same
/// study is often run again with other knobs (`--knobs`).
/// `progress` gets a line per finished setting.
pub fn study(
    scene_path: &Path,
    ladder: Vec<Setting>,
    reference: Reference,
    horizon_days: Option<i64>,
    cache: Option<&Path>,
    progress: &mut dyn FnMut(&str),
) -> Result<AccuracyTable, StudyError> {
    let inputs = app::load_inputs(scene_path, None)?;
    let zones = judged_zones(&inputs.scene, &inputs.schedules, horizon_days);
    let run = |s: &Setting| run_setting(&inputs.scene, &inputs.schedules, &zones, s);
    let key = reference_key(&inputs, &reference.setting, &zones)?;
    let first = match cache.and_then(|c| cached_reference(c, key)) {
        Some(o) => {
            progress(&format!(
                "{:<24} read from {} (the same scene, schedules, zones and program)",
                o.row.name,
                cache.map_or(String::new(), |c| c.display().to_string())
            ));
            o
        }
        None => {
            let o = run(&reference.setting)?;
            if let Some(c) = cache {
                save_reference(c, key, &o)?;
            }
            o
        }
    };
    let reference_samples = first.samples.clone();
    let (mut pending, mut outcomes, mut failed) = (Some(first), Vec::new(), Vec::new());
    let mut zone_values = Vec::new();
    for s in std::iter::once(&reference.setting).chain(&ladder) {
        let mut o = match pending.take() {
            Some(o) => o,
            // A setting the solver refuses (a tolerance its own checks
            // reject) is a finding, not the end of the study.
            None => match run(s) {
                Ok(o) => o,
                Err(e) => {
                    progress(&format!("{:<24} failed: {e}", s.name));
                    failed.push((s.name.clone(), e.to_string()));
                    continue;
                }
            },
        };
        compare(&mut o.row, &o.samples, &reference_samples);
        for &(day, id) in &zones {
            if let Some(x) = o.samples.get(&id) {
                zone_values.push(ZoneValues {
                    setting: s.name.clone(),
                    zone: id,
                    planned: inputs.scene.epoch.date(day),
                    deciding_mm: x.deciding,
                    temps_c: x.temps,
                    verdict: x.verdict,
                });
            }
        }
        progress(&format!(
            "{:<24} {:>6} elements {:>7.1} s  deciding aperture max {:.4} mm, RMS {:.4} mm, temperature {:.3} °C, {} verdicts differ",
            o.row.name, o.row.elements, o.row.seconds, o.row.max_aperture_err_mm, o.row.rms_aperture_err_mm, o.row.max_temp_err_c, o.row.verdicts_differ
        ));
        outcomes.push(o);
    }
    let (chains, note, estimate) =
        chains_and_estimate(&outcomes, &reference.levels, Quantity::Aperture);
    let (_, note_c, estimate_c) =
        chains_and_estimate(&outcomes, &reference.levels, Quantity::Temperature);
    let p = &inputs.scene.planner;
    let limits = [p.min_aperture_mm, p.marginal_aperture_mm];
    for o in outcomes.iter_mut() {
        o.row.verdicts_beyond_band = verdicts_beyond_band(
            &o.samples,
            &reference_samples,
            limits,
            [estimate, estimate_c],
        );
    }
    let mut rows: Vec<Row> = outcomes.into_iter().map(|o| o.row).collect();
    for row in rows.iter_mut() {
        row.rate = chains.get(&row.knob).copied().flatten();
    }
    let front = pareto_front(
        &rows
            .iter()
            .map(|r| (r.seconds, r.max_aperture_err_mm))
            .collect::<Vec<_>>(),
    );
    for (r, f) in rows.iter_mut().zip(front) {
        r.pareto = f;
    }
    Ok(AccuracyTable {
        scene: inputs.scene.name.clone(),
        zones: zones.len(),
        rows,
        failed,
        reference_error_mm: estimate,
        reference_note: note,
        reference_error_c: estimate_c,
        reference_note_c: note_c,
        zone_values,
    })
}

/// The rate of every knob chain (its settings with an `h` and the scene as
/// given at h = 1), and the reference's Richardson estimate of `q` with
/// its note.
fn chains_and_estimate(
    outcomes: &[Outcome],
    levels: &[(String, f64)],
    q: Quantity,
) -> (HashMap<String, Option<f64>>, String, f64) {
    let base = outcomes.iter().find(|o| o.row.knob == SCENE);
    let mut knobs: Vec<&str> = outcomes
        .iter()
        .filter(|o| o.row.h.is_some() && o.row.knob != SCENE && o.row.knob != REFERENCE)
        .map(|o| o.row.knob.as_str())
        .collect();
    let mut seen = std::collections::HashSet::new();
    knobs.retain(|k| seen.insert(*k));
    let (mut rates, mut notes, mut total) = (HashMap::new(), Vec::new(), 0.0);
    for knob in knobs {
        let mut chain: Vec<(f64, &Outcome)> = outcomes
            .iter()
            .filter(|o| o.row.knob == knob)
            .filter_map(|o| Some((o.row.h?, o)))
            .chain(base.map(|b| (1.0, b)))
            .collect();
        chain.sort_by(|a, b| b.0.total_cmp(&a.0));
        chain.dedup_by(|a, b| a.0 == b.0);
        // Coarsest first; d_i between level i and i+1, at the coarser h.
        let (hs, ds): (Vec<f64>, Vec<f64>) = chain
            .windows(2)
            .map(|w| {
                (
                    w[0].0,
                    largest_difference(q, &w[0].1.samples, &w[1].1.samples),
                )
            })
            .unzip();
        let fitted = if ds.len() >= 2 {
            fit_rate(&hs, &ds)
        } else {
            None
        };
        rates.insert(knob.to_string(), fitted);
        let [.., (h2, coarse), (h1, fine)] = chain[..] else {
            continue;
        };
        // A fitted p below 0.5 says the levels are not yet in the
        // asymptotic range; dividing by 2^p − 1 ≈ 0 would blow the
        // estimate up, so first order is assumed there.
        let p = fitted.filter(|p| *p >= 0.5).unwrap_or(1.0);
        let rich =
            largest_difference(q, &fine.samples, &coarse.samples) / ((h2 / h1).powf(p) - 1.0);
        let ref_h = levels.iter().find(|l| l.0 == knob).map_or(1.0, |l| l.1);
        let gap = chain
            .iter()
            .find(|c| (c.0 - ref_h).abs() < 1e-12)
            .map_or(0.0, |c| largest_difference(q, &c.1.samples, &fine.samples));
        total += rich + gap;
        notes.push(format!(
            "{knob}: {:.3} {} (p = {}{}, h {} → {}{})",
            rich + gap,
            q.unit(),
            crate::report::svg::num(p, 2),
            match fitted {
                Some(f) if f >= 0.5 => " fitted".to_string(),
                Some(f) => format!(" assumed: the fitted {f:.2} is not asymptotic"),
                None => " assumed".to_string(),
            },
            crate::report::svg::num(h2, 3),
            crate::report::svg::num(h1, 3),
            if gap > 0.0 {
                format!(
                    "; the reference is at h = {ref_h}, {gap:.3} {} from the finest",
                    q.unit()
                )
            } else {
                String::new()
            }
        ));
    }
    if notes.is_empty() {
        notes.push("not estimated: no knob was refined in two levels".into());
    }
    (rates, notes.join("; "), total)
}

/// The scene's mesh with `along` × and `across` × the elements, and
/// `layers` × the element layers per lift (blocks only); false where the
/// geometry has no such key. A graded mesh keeps its grading: the face
/// element is divided by `across` too, the joint element by `along`.
pub fn refine_mesh(scene: &mut Scene, along: f64, across: f64, layers: u32) -> bool {
    let scale = |n: &mut u32, f: f64| *n = ((*n as f64 * f).round() as u32).max(1);
    let end = |s: &mut Option<f64>, f: f64| *s = s.map(|s| s / f);
    if let Geometry::Blocks(g) = &mut scene.geometry {
        scale(&mut g.elements_per_block, along);
        scale(&mut g.elements_across, across);
        end(&mut g.face_element_m, across);
        end(&mut g.joint_element_m, along);
        g.layers_per_lift *= layers;
        true
    } else if let Geometry::Arch(g) = &mut scene.geometry {
        scale(&mut g.elements_per_block, along);
        scale(&mut g.elements_across, across);
        end(&mut g.face_element_m, across);
        end(&mut g.joint_element_m, along);
        layers == 1
    } else {
        false
    }
}

/// The setting of a knob that switches the scene to the other of two
/// forms (`value`), by `set`.
fn other_form<T: Copy + Send + Sync + 'static>(
    name: String,
    knob: &str,
    value: T,
    set: fn(&mut Scene, T),
) -> Setting {
    Setting::new(name, knob, None, move |s| set(s, value))
}

/// The explicit multi-rate schedule of the issue: 0.1 d for 2 days after
/// each pour, 0.25 d to day 7, then at most 1 d.
pub fn multi_rate(scene: &mut Scene) {
    let t = &mut scene.time;
    t.step_schedule = vec![
        ScheduledStep {
            step_days: 0.1,
            until_days: 2.0,
        },
        ScheduledStep {
            step_days: 0.25,
            until_days: 7.0,
        },
    ];
    t.first_step_days = t.first_step_days.min(1.0);
    t.max_step_days = 1.0;
}

/// Steps × `k`: first and longest step scaled (the growth kept).
fn scale_steps(scene: &mut Scene, k: f64) {
    scene.time.first_step_days *= k;
    scene.time.max_step_days *= k;
}

/// A row that turns the opt-in approximations `on` on.
fn approximate(name: &str, knob: &'static str, on: &[Approximation]) -> Setting {
    let on = on.to_vec();
    Setting::new(name, knob, None, move |s| {
        for a in &on {
            a.turn_on(s)
        }
    })
}

/// The default ladder of `scene`: the scene as given; the thermal steps
/// ×2, ×½, ×¼; the multi-rate schedule; the other capacity form;
/// Crank–Nicolson; PCG at 1e-10; mechanical steps up to 3 days; the other
/// solid element; the rock beside an arch tied every 4th level; elements
/// across ×½ (when even) and ×2, along ×2, layers per lift ×2 (blocks);
/// the presets. The reference: elements along and across ×2, steps ×¼ and
/// consistent capacity.
pub fn default_ladder(scene: &Scene) -> (Vec<Setting>, Reference) {
    let mut l = vec![Setting::new("scene as given", SCENE, Some(1.0), |_| {})];
    for k in [2.0, 0.5, 0.25] {
        l.push(Setting::new(
            format!("steps x{k}"),
            "steps",
            Some(k),
            move |s| scale_steps(s, k),
        ));
    }
    l.push(Setting::new(
        "multi-rate 0.1/0.25/1 d",
        "multi-rate",
        None,
        multi_rate,
    ));
    let capacity = scene.time.capacity.other();
    let name = format!("{} capacity", capacity.name());
    l.push(other_form(name, "capacity", capacity, |s, c| {
        s.time.capacity = c
    }));
    l.push(Setting::new("theta 0.5", "theta", None, |s| {
        s.time.theta = 0.5
    }));
    // The step's own residual check rejects anything above 1e-9.
    l.push(Setting::new("pcg 1e-10", "thermal solver", None, |s| {
        s.solver.thermal = ThermalSolverKind::Pcg;
        s.solver.pcg_tolerance = 1e-10;
    }));
    if scene.any_mechanical() {
        const LONGER: Approximation = Approximation::LongerSteps { max_days: 3 };
        for (name, knob, on) in [
            ("mechanics 3 d", "mechanics step", &[LONGER][..]),
            (
                "mechanics 3 d, pours merged",
                "pours merged",
                &[LONGER, Approximation::MergedPours],
            ),
            (
                "mechanics 3 d, pours and groutings merged",
                "groutings merged",
                &[
                    LONGER,
                    Approximation::MergedPours,
                    Approximation::MergedGroutings,
                ],
            ),
        ] {
            l.push(approximate(name, knob, on));
        }
        let element = scene.solver.element.other();
        let name = format!("element {}", element.name());
        l.push(other_form(name, "element", element, |s, e| {
            s.solver.element = e
        }));
        // the blocks generator founds every block on one level: no rock
        // beside the dam to tie
        if !matches!(scene.geometry, Geometry::Blocks(_)) && scene.solver.rock_coarsening == 1 {
            l.push(approximate(
                "rock ties 1 in 4",
                "rock coarsening",
                &[Approximation::RockCoarsening { every: 4 }],
            ));
        }
        if scene.solver.layer_merging_age_days == 0 {
            l.push(approximate(
                "layer merging 60 d",
                "layer merging",
                &[Approximation::LayerMerging { age_days: 60 }],
            ));
        }
    }
    let mut probe = scene.clone();
    let blocks = refine_mesh(&mut probe, 1.0, 1.0, 2);
    if let Geometry::Blocks(g) = &scene.geometry {
        if g.elements_across % 2 == 0 {
            l.push(Setting::new("across x0.5", "across", Some(2.0), |s| {
                refine_mesh(s, 1.0, 0.5, 1);
            }));
        }
    }
    l.push(Setting::new("across x2", "across", Some(0.5), |s| {
        refine_mesh(s, 1.0, 2.0, 1);
    }));
    l.push(Setting::new("along x2", "along", Some(0.5), |s| {
        refine_mesh(s, 2.0, 1.0, 1);
    }));
    if blocks {
        l.push(Setting::new("layers x2", "layers", Some(0.5), |s| {
            refine_mesh(s, 1.0, 1.0, 2);
        }));
    }
    for p in Preset::ALL {
        l.push(Setting::new(
            format!("preset {}", p.name()),
            "preset",
            None,
            move |s| crate::scene::preset::apply(p, &mut s.time, &|_| false),
        ));
    }
    let reference = Reference {
        setting: Setting::new("reference", REFERENCE, None, |s| {
            *s = s.without_approximations();
            refine_mesh(s, 2.0, 2.0, 1);
            scale_steps(s, 0.25);
            s.time.capacity = CapacityKind::Consistent;
        }),
        levels: vec![
            ("across".into(), 0.5),
            ("along".into(), 0.5),
            ("steps".into(), 0.25),
        ],
    };
    (l, reference)
}

/// Writes `accuracy.csv`, `accuracy.md` and `accuracy.svg` into `out`.
pub fn write(table: &AccuracyTable, out: &Path) -> Result<(), StudyError> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| StudyError::Io {
            action: "writing",
            path,
            source,
        }
    };
    std::fs::create_dir_all(out).map_err(io(out))?;
    for (name, text) in [
        ("accuracy.csv", csv(table)),
        ("accuracy.md", markdown(table)),
        ("accuracy.svg", chart(table)),
        ("accuracy_zones.csv", zones_csv(table)),
    ] {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    Ok(())
}

/// The table as CSV, one row per setting.
pub fn csv(t: &AccuracyTable) -> String {
    let mut s = String::from("setting,knob,h,elements,thermal_dofs,mech_dofs,steps,wall_s,max_aperture_err_mm,rms_aperture_err_mm,max_point_err_mm,max_temp_err_c,verdicts_differ,verdicts_beyond_band,rate,pareto\n");
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
    for r in &t.rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{:.3},{:.6},{:.6},{:.6},{:.4},{},{},{},{}",
            r.name,
            r.knob,
            opt(r.h),
            r.elements,
            r.thermal_dofs,
            r.mech_dofs,
            r.steps,
            r.seconds,
            r.max_aperture_err_mm,
            r.rms_aperture_err_mm,
            r.max_point_err_mm,
            r.max_temp_err_c,
            r.verdicts_differ,
            r.verdicts_beyond_band,
            r.rate.map_or(String::new(), |p| format!("{p:.3}")),
            r.pareto
        );
    }
    s
}

/// Every setting's reading of every judged zone, one row each.
pub fn zones_csv(t: &AccuracyTable) -> String {
    let mut s =
        String::from("setting,joint,zone,planned,deciding_aperture_mm,temp_a_c,temp_b_c,verdict\n");
    let opt = |v: Option<f64>, digits: usize| v.map_or(String::new(), |v| format!("{v:.digits$}"));
    for z in &t.zone_values {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            z.setting,
            z.zone.joint,
            z.zone.zone,
            z.planned,
            opt(z.deciding_mm, 4),
            opt(z.temps_c[0], 3),
            opt(z.temps_c[1], 3),
            z.verdict.as_str()
        );
    }
    s
}

/// The table in Markdown, with the reference's estimated error.
pub fn markdown(t: &AccuracyTable) -> String {
    let mut s = format!(
        "# Accuracy against time: {}\n\n{} zones judged on their planned dates against the reference (estimated error of its deciding aperture {:.3} mm: {}; of the warmer block's zone temperature {:.2} °C: {}). `*` marks the Pareto front (no setting both faster and more accurate). \"beyond band\" leaves out the zones whose deciding aperture (or, for a not-groutable verdict, warmer zone temperature) lies within that error of the limit separating the two verdicts on the reference and across it on the setting: the reference cannot decide them.\n\n",
        t.scene, t.zones, t.reference_error_mm, t.reference_note, t.reference_error_c, t.reference_note_c
    );
    s += "| setting | elements | dofs (thermal / mech.) | wall s | deciding aperture max / RMS err mm | any point mm | temperature err °C | verdicts differ | beyond band | rate p | front |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|\n";
    for r in &t.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} / {} | {:.1} | {:.3} / {:.3} | {:.3} | {:.2} | {} | {} | {} | {} |",
            r.name,
            r.elements,
            r.thermal_dofs,
            r.mech_dofs,
            r.seconds,
            r.max_aperture_err_mm,
            r.rms_aperture_err_mm,
            r.max_point_err_mm,
            r.max_temp_err_c,
            r.verdicts_differ,
            r.verdicts_beyond_band,
            r.rate.map_or(String::new(), |p| format!("{p:.2}")),
            if r.pareto { "*" } else { "" }
        );
    }
    for (name, e) in &t.failed {
        let _ = writeln!(s, "\n{name}: failed: {e}");
    }
    s
}

/// Deciding-aperture error against wall time, one marker per setting, the
/// front joined by a line.
pub fn chart(t: &AccuracyTable) -> String {
    use crate::report::scale::{nice_ticks, tick_decimals, Scale};
    use crate::report::svg::{self, num, Svg, FRAME, HEIGHT, WIDTH};
    let f = FRAME;
    let tmax = t.rows.iter().map(|r| r.seconds).fold(1e-3, f64::max);
    let emax = t
        .rows
        .iter()
        .map(|r| r.max_aperture_err_mm)
        .fold(1e-3, f64::max);
    let (xt, yt) = (nice_ticks(0.0, tmax, 6), nice_ticks(0.0, emax, 5));
    let last = |v: &[f64]| v.last().copied().unwrap_or(1.0);
    let x = Scale::new((0.0, last(&xt)), (f.left, f.right));
    let y = Scale::new((0.0, last(&yt)), (f.bottom, f.top));
    let mut s = Svg::new(WIDTH, HEIGHT);
    svg::title(
        &mut s,
        &format!("{}: deciding-aperture error against time", t.scene),
    );
    s.open_group("axes");
    for (&v, dec) in yt.iter().zip(std::iter::repeat(tick_decimals(
        yt.get(1).copied().unwrap_or(1.0),
    ))) {
        s.line("grid", (f.left, y.map(v)), (f.right, y.map(v)));
        s.text(
            "tick-label",
            (f.left - 6.0, y.map(v) + 4.0),
            "end",
            &num(v, dec),
        );
    }
    for &v in &xt {
        s.line("grid", (x.map(v), f.top), (x.map(v), f.bottom));
        s.text(
            "tick-label",
            (x.map(v), f.bottom + 16.0),
            "middle",
            &num(v, 1),
        );
    }
    s.line("axis", (f.left, f.bottom), (f.right, f.bottom));
    s.line("axis", (f.left, f.top), (f.left, f.bottom));
    s.text(
        "axis-title",
        ((f.left + f.right) / 2.0, f.bottom + 34.0),
        "middle",
        "wall time [s]",
    );
    s.vertical_text(
        "axis-title",
        (16.0, (f.top + f.bottom) / 2.0),
        "largest deciding-aperture error [mm]",
    );
    s.close_group();
    let mut front: Vec<(f64, f64)> = t
        .rows
        .iter()
        .filter(|r| r.pareto)
        .map(|r| (r.seconds, r.max_aperture_err_mm))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let front_px: Vec<(f64, f64)> = front.iter().map(|p| (x.map(p.0), y.map(p.1))).collect();
    s.polyline("front", &front_px);
    for r in &t.rows {
        let c = (x.map(r.seconds), y.map(r.max_aperture_err_mm));
        s.circle(if r.pareto { "on-front" } else { "setting" }, c, 3.5);
        s.text("point-label", (c.0 + 6.0, c.1 - 4.0), "start", &r.name);
    }
    svg::legend(
        &mut s,
        f,
        &[
            ("on-front", "on the Pareto front", true),
            ("setting", "other settings", true),
        ],
    );
    let style = format!(
        "{}{}",
        svg::STYLE,
        ".front{stroke:#d62728;fill:none;stroke-width:1.5}.on-front{fill:#d62728}.setting{fill:#1f77b4}.point-label{fill:#333;font-size:10px}"
    );
    s.finish(&format!("{}: accuracy against time", t.scene), &style)
}

/// Which part of the default ladder [`accuracy`] runs.
#[derive(Debug, Clone, Default)]
pub struct AccuracyOptions {
    /// Judge only the zones planned within this many days of the epoch
    /// (the runs end there). Default: every zone.
    pub horizon_days: Option<i64>,
    /// The scene as given and the presets against a time-only reference
    /// ([`time_reference`]): for scenes too large for the mesh knobs.
    /// Default: false.
    pub presets_only: bool,
    /// Only the scene as given and these knobs' settings (the names of
    /// [`Setting::knob`]); empty (default): every knob.
    pub knobs: Vec<String>,
}

/// The default ladder of the scene at `scene_path`, cut down by `options`,
/// written into `out`; `progress` gets a line per finished setting. An
/// unknown knob name is an error listing the ladder's knobs.
pub fn accuracy(
    scene_path: &Path,
    out: &Path,
    options: &AccuracyOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<AccuracyTable, StudyError> {
    let scene = Scene::load(scene_path)?;
    let (mut ladder, mut reference) = default_ladder(&scene);
    if options.presets_only {
        ladder.retain(|s| s.knob == SCENE || s.knob == "preset");
        reference = time_reference();
    }
    if !options.knobs.is_empty() {
        let known: Vec<&str> = ladder.iter().map(|s| s.knob.as_str()).collect();
        if let Some(k) = options.knobs.iter().find(|k| !known.contains(&k.as_str())) {
            let mut known = known;
            known.dedup();
            return Err(StudyError::Knob(format!(
                "unknown knob `{k}` for this scene; its ladder has: {}",
                known.join(", ")
            )));
        }
        ladder.retain(|s| s.knob == SCENE || options.knobs.contains(&s.knob));
    }
    let cache = out.join("reference.bin");
    let table = study(
        scene_path,
        ladder,
        reference,
        options.horizon_days,
        Some(&cache),
        progress,
    )?;
    write(&table, out)?;
    Ok(table)
}

/// The reference on the scene's own mesh: steps ×¼ and consistent
/// capacity. Its stated error then leaves out the mesh's.
pub fn time_reference() -> Reference {
    Reference {
        setting: Setting::new("reference (time only)", REFERENCE, None, |s| {
            *s = s.without_approximations();
            scale_steps(s, 0.25);
            s.time.capacity = CapacityKind::Consistent;
        }),
        levels: vec![("steps".into(), 0.25)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference computed with the scene's approximations would hide
    /// their error: both references clear them, and nothing else of what
    /// they do changes.
    #[test]
    fn the_references_have_no_approximation() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut scene = Scene::load(&root.join("models/small_dam_joints.toml")).unwrap();
        for a in [
            Approximation::LongerSteps { max_days: 3 },
            Approximation::MergedPours,
            Approximation::LayerMerging { age_days: 60 },
        ] {
            a.turn_on(&mut scene);
        }
        for reference in [default_ladder(&scene).1, time_reference()] {
            let mut with = scene.clone();
            (reference.setting.edit)(&mut with);
            assert!(
                with.approximations().is_empty(),
                "{:?}",
                with.approximations()
            );
            let mut without = scene.without_approximations();
            (reference.setting.edit)(&mut without);
            assert_eq!(with, without);
        }
    }

    #[test]
    fn rate_of_a_second_order_sequence_is_two() {
        let h = [1.0, 0.5, 0.25, 0.125];
        let e: Vec<f64> = h.iter().map(|h| 3.7 * h * h).collect();
        let p = fit_rate(&h, &e).unwrap();
        assert!((p - 2.0).abs() < 1e-12, "p = {p}");
        assert_eq!(fit_rate(&[1.0], &[2.0]), None);
        assert_eq!(fit_rate(&[1.0, 1.0], &[2.0, 3.0]), None);
    }

    /// Zones 1–4 and 6 differ from the reference: zone 1 straddles 0.5 mm
    /// within the band (not counted), zone 2 straddles it farther than the
    /// band, zone 3 straddles 0.7 mm within it (not counted), zone 4 differs
    /// on the same side of both limits (a temperature: counted), zone 6
    /// straddles 0.7 mm but its verdicts (not groutable, groutable) are not
    /// the two that limit separates (counted); zone 5 agrees.
    #[test]
    fn verdicts_within_the_references_band_are_left_out() {
        use Verdict::*;
        let sample = |a: f64, v: Verdict| Sample {
            apertures: Apertures::default(),
            deciding: Some(a),
            temps: [Some(12.0), Some(11.0)],
            temp_limit_c: 13.5,
            verdict: v,
        };
        let zone = |z: u32| ZoneId::new(1, z);
        // zone: (reference, setting)
        let cases = [
            ((0.494, NotGroutable), (0.503, Marginal)),
            ((0.40, NotGroutable), (0.55, Marginal)),
            ((0.69, Marginal), (0.72, Groutable)),
            ((1.20, Groutable), (1.25, NotGroutable)),
            ((1.00, Groutable), (1.01, Groutable)),
            ((0.677, NotGroutable), (1.278, Groutable)),
        ];
        let run = |setting: bool| {
            (1..)
                .zip(&cases)
                .map(|(z, &(r, s))| {
                    let (a, v) = if setting { s } else { r };
                    (zone(z), sample(a, v))
                })
                .collect::<HashMap<ZoneId, Sample>>()
        };
        let (reference, setting) = (run(false), run(true));
        let limits = [0.5, 0.7];
        assert_eq!(
            verdicts_beyond_band(&setting, &reference, limits, [0.062, 0.0]),
            3
        );
        // No band: every differing zone counts; a wide one leaves zone 2 out
        // too, never zone 6.
        assert_eq!(
            verdicts_beyond_band(&setting, &reference, limits, [0.0, 0.0]),
            5
        );
        assert_eq!(
            verdicts_beyond_band(&setting, &reference, limits, [1.8, 0.0]),
            2
        );
        // A zone the setting did not judge counts.
        let missing: HashMap<ZoneId, Sample> = HashMap::new();
        assert_eq!(
            verdicts_beyond_band(&missing, &reference, limits, [0.062, 0.0]),
            6
        );
        // Zone 4 is not groutable on the setting at 13.6 °C (limit 13.5)
        // and groutable on the reference at 13.45 °C: within a 0.1 °C band
        // it is left out, within 0.01 °C it counts; zone 6's
        // temperatures do not straddle the limit, so it counts.
        let mut warm = setting.clone();
        warm.get_mut(&zone(4)).unwrap().temps = [Some(13.6), Some(12.0)];
        let mut cool = reference.clone();
        cool.get_mut(&zone(4)).unwrap().temps = [Some(11.0), Some(13.45)];
        assert_eq!(verdicts_beyond_band(&warm, &cool, limits, [0.062, 0.1]), 2);
        assert_eq!(verdicts_beyond_band(&warm, &cool, limits, [0.062, 0.01]), 3);
    }

    #[test]
    fn front_of_a_hand_made_table() {
        // (time, error): c is beaten by b (faster and more accurate), e ties
        // a in time but is less accurate, d is the slowest but exact.
        let pts = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (10.0, 0.0), (1.0, 0.6)];
        assert_eq!(pareto_front(&pts), vec![true, true, false, true, false]);
        // Two identical points are both on the front.
        assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), vec![true, true]);
    }
}
