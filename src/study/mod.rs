//! Benchmarks and studies: what accuracy costs in time. Figures are printed,
//! never asserted.

pub mod accuracy;
pub mod compare;
pub mod restart;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::app::{self, AppError, RunSummary};
use crate::mechanics::{MechError, MechStats};
use crate::scene::{approximation, Effect, Scene, ThermalSolverKind};
use crate::schedule::{self, SynthParams};
use crate::sim::{JointRecords, SimError, Simulation};
use crate::thermal::ThermalError;
use crate::vocab::{Day, Epoch};

/// One line per run for the CLI.
pub fn summary_line(s: &RunSummary) -> String {
    let mut out = format!(
        "simulated {} steps, {} pours in {:.2} s ({} elements, {} thermal dofs)\n",
        s.stats.steps, s.stats.pours, s.stats.seconds, s.elements, s.thermal_dofs
    );
    if let Some(t) = &s.stats.thermal {
        out += &format!(
            "thermal: {} symbolic + {} numeric factorisations, {} assemblies; temperatures.csv {} rows, {} snapshots\n",
            t.symbolic, t.numeric, t.assemblies, s.temperature_rows, s.snapshots
        );
    }
    if let Some(m) = &s.stats.mechanics {
        out += &format!(
            "mechanics: {} steps, {} numeric factorisations, {} contact passes ({} steps pivoting in blocks); apertures.csv {} rows\n",
            m.steps, m.numeric, m.contact_iterations, m.block_pivoting_steps, s.aperture_rows
        );
        out += &m.kept_tension_warning();
        if !s.approximations.is_empty() {
            out += &app::approximations_line(&s.approximations);
        }
    }
    out
}

/// What a study can fail on, with the scene or file it was working on.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error(transparent)]
    App(#[from] AppError),
    #[error("planning {scene}: {source}")]
    Plan {
        scene: String,
        // Boxed: an `AppError` beside the scene's name would make every
        // study result large.
        source: Box<AppError>,
    },
    /// A staged run or a complete-dam step that failed while being timed.
    #[error("timing {what}: {source}")]
    Run { what: String, source: SimError },
    #[error("{action} {path}: {source}")]
    Io {
        action: &'static str,
        path: String,
        source: std::io::Error,
    },
    #[error("--solver: expected cholesky, pcg or both, found {0:?}")]
    Solver(String),
    /// `study perf --resume RUN` where RUN has no restart point this scene,
    /// its schedules and this program can continue from.
    #[error("--resume {run}: no restart point of an interrupted `groutready run --out {run}` of this scene, its schedules and this program in {dir}")]
    NoRestart { run: String, dir: String },
    /// `study perf --resume` with more than one scene.
    #[error("--resume times one scene's interrupted run: give exactly one scene, found {0}")]
    ResumeScenes(usize),
    /// `study accuracy --knobs` naming a knob the scene's ladder lacks.
    #[error("--knobs: {0}")]
    Knob(String),
    /// `schedule synth` onto a folder that already holds schedules.
    #[error("{path}: already holds {files}; schedule synth would overwrite them (give --out another folder, or add --force to overwrite)")]
    WouldOverwrite { path: String, files: String },
    /// `study compare` given a path that is neither a run folder with
    /// `apertures.csv` nor such a file.
    #[error("{path}: {why}: expected a run folder of a scene with joints (written by `groutready run` or `plan`) or its apertures.csv")]
    NotARun { path: String, why: &'static str },
    /// An `apertures.csv` that `study compare` cannot read: the file, the
    /// 1-based line, the cell at fault (1-based column and its name) where
    /// there is one, what was expected and what was found.
    #[error("{file}:{line}{}: {message}", .cell.as_ref().map_or(String::new(), |(c, name)| format!(":{c} ({name})")))]
    Apertures {
        file: String,
        line: u64,
        cell: Option<(usize, String)>,
        message: String,
    },
}

/// The thermal solvers a `--solver` value names (`cholesky`, `pcg` or
/// `both`); none means each scene's own.
pub fn parse_solvers(value: Option<&str>) -> Result<Vec<ThermalSolverKind>, StudyError> {
    use ThermalSolverKind as K;
    match value {
        None => Ok(vec![]),
        Some("cholesky") => Ok(vec![K::Cholesky]),
        Some("pcg") => Ok(vec![K::Pcg]),
        Some("both") => Ok(vec![K::Cholesky, K::Pcg]),
        Some(other) => Err(StudyError::Solver(other.to_string())),
    }
}

/// What `perf` times besides each scene's staged history.
#[derive(Debug, Clone)]
pub struct PerfOptions {
    /// Stop each staged run after this many days.
    pub max_days: Option<f64>,
    /// Thermal solvers to time (empty = each scene's own).
    pub solvers: Vec<ThermalSolverKind>,
    /// Time the complete-dam mechanical step above
    /// [`COMPLETE_MECHANICS_MAX_DOFS`] too.
    pub complete_mechanics: bool,
    /// For a scene with joints, run the exact path too (every contact-set
    /// change refactorised) and compare the apertures at the grouting dates.
    pub exact: bool,
    /// Start the staged run from the restart point that an interrupted
    /// `groutready run --out RUN` keeps beside RUN ([`app::resume`]), and
    /// count `max_days` from there: a long run's late days timed without
    /// its first months. One scene, no exact path, complete dam or plan.
    pub resume: Option<PathBuf>,
    /// The plan timed after a whole construction (from scratch whatever
    /// this says): its as-of date, horizon, and the caller's clock.
    pub plan: crate::app::plan::PlanRequest,
}

/// Times the staged history of each scene (no files written), then the
/// cost of one step of the complete dam (every lift live): its symbolic and
/// numeric factorisation and the per-step solve, the figures that decide how
/// a full-size run scales; with mechanics, also one mechanical step of the
/// complete dam (up to [`COMPLETE_MECHANICS_MAX_DOFS`] unless
/// `complete_mechanics`). With `exact`, a scene with joints is run again
/// on the exact path and the two compared where the planner reads them.
/// A scene with joints and a grouting schedule whose whole construction
/// was timed is then planned from scratch, and that is timed too.
pub fn perf(scenes: &[PathBuf], options: &PerfOptions) -> Result<(), StudyError> {
    let PerfOptions {
        max_days,
        ref solvers,
        complete_mechanics,
        exact,
        ref resume,
        ref plan,
    } = *options;
    if resume.is_some() && scenes.len() != 1 {
        return Err(StudyError::ResumeScenes(scenes.len()));
    }
    println!(
        "{:<22} {:>8} {:>9} {:>6} {:>6} {:>6} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "scene/solver",
        "elements",
        "dofs",
        "pours",
        "steps",
        "symb",
        "numeric",
        "wall_s",
        "ms/step",
        "symb_s",
        "num_s",
        "solve_s",
        "asm_s"
    );
    for path in scenes {
        let t_load = Instant::now();
        let (scene0, mesh, schedules) = load_or_synthesize(path)?;
        let load_s = t_load.elapsed().as_secs_f64();
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let kinds = if solvers.is_empty() {
            vec![scene0.solver.thermal]
        } else {
            solvers.to_vec()
        };
        for kind in kinds {
            let mut scene = scene0.clone();
            scene.solver.thermal = kind;
            let timed = Timed {
                path,
                label: format!("{stem}/{}", solver_name(kind)),
                scene: &scene,
                mesh: &mesh,
            };
            let fast = timed.staged_run(&schedules, resume.as_deref(), max_days, load_s)?;
            // a resumed run times the late days only: no exact path, no
            // complete dam
            if resume.is_some() {
                continue;
            }
            let exact_scene = (exact && scene.has(Effect::Joints))
                .then(|| scene.exact_path())
                .filter(|e| *e != scene);
            if let Some(exact_scene) = exact_scene {
                let exact_run = Timed {
                    label: format!("{stem}/exact"),
                    scene: &exact_scene,
                    ..timed.clone()
                }
                .staged_run(&schedules, None, max_days, load_s)?;
                let c = compare_at_grouting_dates(&fast, &exact_run, &schedules, scene.epoch);
                let approximations = scene.approximations();
                let with = if approximations.is_empty() {
                    "no approximation: the exact accelerations alone".to_string()
                } else {
                    format!("with {}", approximation::describe(&approximations))
                };
                println!(
                    "{:<22} fast against exact path: {} zone samples at their grouting dates, apertures differ by at most {:.2e} mm, {} contact states differ ({with})",
                    "", c.samples, 1e3 * c.max_aperture_diff_m, c.states_differ,
                );
            }
            timed.complete_dam(complete_mechanics)?;
        }
        // The planner's cost where the whole construction was timed: the
        // same scene planned from scratch (baseline and remedy searches).
        if max_days.is_none()
            && resume.is_none()
            && own_schedules(&scene0, path).is_some()
            && scene0.has(Effect::Joints)
            && !schedules.grouting.is_empty()
        {
            println!("{:<22} {}", "", restart::plan_from_scratch(path, plan)?);
        }
    }
    Ok(())
}

/// How two runs differ where the planner reads them: every zone point and
/// zone minimum on its zone's planned grouting date.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GroutingDateDiff {
    /// samples present in both runs
    pub samples: usize,
    /// largest aperture difference \[m\]
    pub max_aperture_diff_m: f64,
    /// samples whose contact states differ
    pub states_differ: usize,
}

/// Compares the joint histories `a` and `b` of one scene at its zones'
/// planned grouting dates (those inside both histories).
pub fn compare_at_grouting_dates(
    a: &JointRecords,
    b: &JointRecords,
    schedules: &schedule::Schedules,
    epoch: Epoch,
) -> GroutingDateDiff {
    let mut diff = GroutingDateDiff::default();
    let row = |r: &'_ JointRecords, day: Day| {
        r.rows
            .iter()
            .find(|(d, _)| *d == day)
            .map(|(_, s)| s.clone())
    };
    for g in &schedules.grouting {
        let day = epoch.day(g.planned);
        let (Some(ra), Some(rb)) = (row(a, day), row(b, day)) else {
            continue;
        };
        for (c, col) in a.columns.iter().enumerate() {
            if col.zone != g.zone_id() {
                continue;
            }
            if let (Some(sa), Some(sb)) = (ra[c], rb[c]) {
                diff.samples += 1;
                diff.max_aperture_diff_m = diff
                    .max_aperture_diff_m
                    .max((sa.aperture - sb.aperture).abs());
                diff.states_differ += usize::from(sa.state != sb.state);
            }
        }
    }
    diff
}

/// One scene with one thermal solver, as `perf` times it.
#[derive(Clone)]
struct Timed<'a> {
    path: &'a Path,
    /// `stem/solver`, the first column of the table
    label: String,
    scene: &'a Scene,
    mesh: &'a crate::mesh::Mesh,
}

impl Timed<'_> {
    /// Names the scene and solver in an error, so a failure among several
    /// timed runs says which one.
    fn run_err(&self, part: &str) -> impl FnOnce(SimError) -> StudyError + '_ {
        let what = format!(
            "{} ({}){part}",
            self.path.display(),
            solver_name(self.scene.solver.thermal)
        );
        move |source| StudyError::Run { what, source }
    }

    /// The staged history up to `max_days` (counted from the restart point
    /// of the interrupted run into `resume`, when given): the table's row,
    /// then the load time and solver counters, then the mechanics' own
    /// figures. Returns the joint history.
    fn staged_run(
        &self,
        schedules: &schedule::Schedules,
        resume: Option<&Path>,
        max_days: Option<f64>,
        load_s: f64,
    ) -> Result<JointRecords, StudyError> {
        let mut sim =
            Simulation::new(self.scene, self.mesh, schedules).map_err(self.run_err(""))?;
        let from = match resume {
            Some(run) => self.restore(&mut sim, schedules, run)?,
            None => Day(0),
        };
        if let Some(days) = max_days {
            sim.timeline.end_day = sim.timeline.end_day.min(Day(from.0 + days as i64));
        }
        self.timed_run(sim, load_s)
    }

    /// Restores `sim` from the restart point of the interrupted run into
    /// `run`, as `groutready run` would continue it (the damaged files it
    /// passed over are printed as `run` prints them); returns the day
    /// restored.
    fn restore(
        &self,
        sim: &mut Simulation<'_>,
        schedules: &schedule::Schedules,
        run: &Path,
    ) -> Result<Day, StudyError> {
        let dir = app::resume::dir_of(run);
        let found = app::resume::find(run, self.scene, schedules, Some(sim.end_day()));
        for w in &found.damaged {
            println!("{:<22} warning: {w}", "");
        }
        let Some(previous) = found.previous else {
            return Err(StudyError::NoRestart {
                run: run.display().to_string(),
                dir: dir.display().to_string(),
            });
        };
        let restart = previous.restart;
        sim.restore(&restart.checkpoint, &restart.history);
        let from = restart.checkpoint.day;
        println!(
            "{:<22} resumed from day {} ({}), the restart point in {}",
            "",
            from.0,
            self.scene.epoch.date(from),
            dir.display()
        );
        Ok(from)
    }

    /// Runs `sim` to its end and prints the figures of
    /// [`Timed::staged_run`].
    fn timed_run(&self, mut sim: Simulation<'_>, load_s: f64) -> Result<JointRecords, StudyError> {
        let mesh = self.mesh;
        // a restored run counts from its checkpoint
        let (steps0, pours0) = sim.steps_and_pours();
        let cpu0 = crate::machine::cpu_seconds();
        let mut stats = sim.run(None, &mut |_, _| {}).map_err(self.run_err(""))?;
        let cores_note = cpu0
            .zip(crate::machine::cpu_seconds())
            .map_or(String::new(), |(a, b)| {
                busy_cores_note(b - a, stats.seconds)
            });
        stats.steps -= steps0;
        stats.pours -= pours0;
        let t = stats.thermal.unwrap_or_default();
        println!(
            "{:<22} {:>8} {:>9} {:>6} {:>6} {:>6} {:>7} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
            self.label,
            mesh.elements.len(),
            mesh.n_thermal_dofs,
            stats.pours,
            stats.steps,
            t.symbolic,
            t.numeric,
            stats.seconds,
            1e3 * stats.seconds / stats.steps.max(1) as f64,
            t.seconds_symbolic,
            t.seconds_numeric,
            t.seconds_solve,
            t.seconds_assembly,
        );
        println!(
            "{:<22} inputs+mesh {:.2} s; {:.0} days simulated; largest live system {} dofs; {} PCG iterations{}{cores_note}",
            "", load_s, sim.day, t.max_dofs, t.pcg_iterations, peak_memory_note()
        );
        if let Some(m) = stats.mechanics {
            print_mechanics(&m);
        }
        Ok(sim.joint_records)
    }

    /// One step of the complete dam: mechanical (skipped above
    /// [`COMPLETE_MECHANICS_MAX_DOFS`] unless `complete_mechanics`), then
    /// thermal, for the scene's effects.
    fn complete_dam(&self, complete_mechanics: bool) -> Result<(), StudyError> {
        let (scene, mesh) = (self.scene, self.mesh);
        let mech_dofs = 3 * mesh.nodes.len();
        if scene.any_mechanical() && !complete_mechanics && mech_dofs > COMPLETE_MECHANICS_MAX_DOFS
        {
            println!(
                "{:<22} complete dam mechanics: skipped ({mech_dofs} dofs; --complete-mechanics times it: minutes, several GB)",
                ""
            );
        } else if scene.any_mechanical() {
            let full = full_dam_mechanics_step_cost(scene, mesh)
                .map_err(SimError::from)
                .map_err(self.run_err(", complete dam mechanics"))?;
            println!(
                "{:<22} complete dam mechanics: {} dofs ({} joint pairs), factor {:.1}M entries, {:.2} Gflop; symbolic {:.2} s, step {:.2} s ({} numeric factorisations, {} contact passes){}",
                "",
                full.stats.max_dofs,
                full.pairs,
                full.factor_nnz as f64 / 1e6,
                full.factor_flops / 1e9,
                full.stats.seconds_symbolic,
                full.step_s,
                full.stats.numeric,
                full.stats.contact_iterations,
                peak_memory_note()
            );
            print_mechanics(&full.stats);
            let (read, rows, entries) = full.joint_reach;
            println!(
                "{:<22} complete dam: a contact pass reads {read} rows (joint pairs and their neighbours); their reach in the elimination tree is {:.1} % of the rows and {:.1} % of the entries of L",
                "",
                100.0 * rows as f64 / full.stats.max_dofs.max(1) as f64,
                100.0 * entries as f64 / full.factor_nnz.max(1) as f64
            );
        }
        if scene.any_thermal() {
            let full = full_dam_step_cost(scene, mesh, 10)
                .map_err(SimError::from)
                .map_err(self.run_err(", complete dam"))?;
            println!(
                "{:<22} complete dam: {} dofs, analysis {:.3} s, factorisation {:.3} s, solve {:.1} ms, step {:.1} ms",
                "",
                full.dofs,
                full.symbolic_s,
                full.numeric_s,
                1e3 * full.solve_s_per_step,
                1e3 * full.step_s
            );
        }
        Ok(())
    }
}

/// "; C core-seconds, P % of the N cores over the wall time": the CPU time
/// a run of `wall` seconds used, and the share of the machine's cores it
/// kept busy. A run bound by its chain of factorisations shows it here:
/// on 2 cores, a wall time of half its core-seconds is the most any
/// overlap of its work can reach.
fn busy_cores_note(core_seconds: f64, wall: f64) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "; {core_seconds:.1} core-seconds, {:.0} % of the {cores} cores over the wall time",
        100.0 * core_seconds / (wall * cores as f64).max(f64::MIN_POSITIVE)
    )
}

/// "; peak memory N MiB" or nothing where the platform does not say.
fn peak_memory_note() -> String {
    crate::machine::peak_memory_bytes().map_or(String::new(), |b| {
        format!("; peak memory {:.0} MiB", b as f64 / (1u64 << 20) as f64)
    })
}

/// The mechanics' counters of a staged run: where the factorisations came
/// from and what the capacitance correction took instead.
fn print_mechanics(m: &MechStats) {
    let r = &m.refactor_reasons;
    println!(
        "{:<22} mechanics: {} steps, largest {} dofs, {} symbolic ({:.2} s) + {} numeric ({:.2} s) factorisations, solve {:.2} s, assembly {:.2} s, joints {:.2} s ({} contact passes, {} of them moving slip forces only, {} steps pivoting in blocks, largest tension kept closed {:.2e} Pa); {:.1} ms/step",
        "",
        m.steps,
        m.max_dofs,
        m.symbolic,
        m.seconds_symbolic,
        m.numeric,
        m.seconds_numeric,
        m.seconds_solve,
        m.seconds_assembly,
        m.seconds_joints,
        m.contact_iterations,
        m.slip_force_passes,
        m.block_pivoting_steps,
        m.kept_closed_tension,
        1e3 * (m.seconds_symbolic + m.seconds_numeric + m.seconds_solve + m.seconds_assembly + m.seconds_joints)
            / m.steps.max(1) as f64
    );
    println!(
        "{:<22} orderings: {} METIS calls, {:.2} s; rock condensed once: {} dofs, {:.2} s, then {} solves with its factor, {:.2} s; layer merging tied up to {} nodes; symbolic analyses {:.2} s; over the {} live sets Σ L entries {:.1}M, Σ flops of one factorisation {:.2} Gflop; numeric factorisations {:.1} Gflop in all",
        "",
        m.metis_calls,
        m.seconds_ordering,
        m.condensed_dofs,
        m.seconds_condensation,
        m.rock_solves,
        m.seconds_rock,
        m.max_merged_nodes,
        m.seconds_analysis,
        m.symbolic,
        m.live_sets_factor_nnz as f64 / 1e6,
        m.live_sets_factor_flops / 1e9,
        m.numeric_flops / 1e9
    );
    println!(
        "{:<22} joint factorisations by reason: {} step, {} grout, {} contact change (correction off), {} past break-even; capacitance: {} solves ({} refined; {} forward halves on a reach), {} columns ({:.1} % of their live sets' rows, {:.2} s, {:.1} Gflop estimated), {} LU of S ({:.1} Gflop, {:.2} s with its assembly; its products {:.2} s, {:.1} Gflop), largest rank {}, {:.2} s",
        "",
        r.step,
        r.grout,
        r.contact,
        r.rank,
        m.capacitance.solves,
        m.capacitance.refinements,
        m.capacitance.forward_reaches,
        m.capacitance.columns,
        100.0 * m.capacitance.column_rows as f64 / m.capacitance.column_dense_rows.max(1) as f64,
        m.capacitance.column_seconds,
        m.capacitance.column_flops / 1e9,
        m.capacitance.s_factorisations,
        m.capacitance.s_flops / 1e9,
        m.capacitance.s_seconds,
        m.capacitance.product_seconds,
        m.capacitance.product_flops / 1e9,
        m.capacitance.max_rank,
        m.capacitance.seconds
    );
    let a = &m.ahead;
    println!(
        "{:<22} factorised ahead on the second core: {} made ({:.2} s; {} started while the one before ran; {} on a live set analysed ahead; {:.2} s of analyses on threads of their own), {} used, {} discarded, {} failed; steps waited {:.2} s for them",
        "",
        a.made,
        a.seconds,
        a.started_beside,
        a.on_new_systems,
        a.seconds_analysed,
        a.used,
        a.discarded,
        a.failed,
        a.seconds_waited
    );
    let p = &m.pours_ahead;
    println!(
        "{:<22} live sets of coming pour days analysed ahead: {} started ({:.2} s on threads of their own), {} used, {} discarded",
        "", p.started, p.seconds, p.used, p.discarded
    );
}

fn solver_name(kind: ThermalSolverKind) -> &'static str {
    match kind {
        ThermalSolverKind::Cholesky => "cholesky",
        ThermalSolverKind::Pcg => "pcg",
    }
}

/// Above this many mechanical dofs the complete-dam mechanical step is timed
/// only on request: on the Xiaowan-like arch (410,904 dofs) one numeric
/// factorisation alone takes 4.8 s and 2 GB, and the step needs several.
pub const COMPLETE_MECHANICS_MAX_DOFS: usize = 100_000;

/// Cost of stepping the complete dam.
#[derive(Debug, Clone, Copy)]
pub struct FullDamCost {
    pub dofs: usize,
    /// live-set analysis (pattern, ordering, symbolic Cholesky) of the first step
    pub symbolic_s: f64,
    /// numeric factorisation of the first step (0 for PCG)
    pub numeric_s: f64,
    /// solve time per later step
    pub solve_s_per_step: f64,
    /// wall time of a later step (sources, right-hand side, solve, residual check)
    pub step_s: f64,
}

/// Pours every lift on day 0 and takes `steps` one-day steps.
pub fn full_dam_step_cost(
    scene: &Scene,
    mesh: &crate::mesh::Mesh,
    steps: usize,
) -> Result<FullDamCost, ThermalError> {
    let settings = crate::thermal::ThermalSettings::from_scene(scene);
    let mut th = crate::thermal::ThermalModel::new(mesh, &settings, Vec::new(), None, None)?;
    for (block, lift) in all_lifts(mesh) {
        th.pour(block, lift, 0.0, 15.0);
    }
    th.step(0.0, 1.0)?;
    let first = th.stats;
    let steps = steps.max(2);
    let t = Instant::now();
    for k in 1..steps {
        th.step(k as f64, k as f64 + 1.0)?;
    }
    let n = (steps - 1) as f64;
    Ok(FullDamCost {
        dofs: first.max_dofs,
        symbolic_s: first.seconds_symbolic,
        numeric_s: first.seconds_numeric,
        solve_s_per_step: (th.stats.seconds_solve - first.seconds_solve) / n,
        step_s: t.elapsed().as_secs_f64() / n,
    })
}

/// Every (block, lift) of the mesh, sorted.
fn all_lifts(mesh: &crate::mesh::Mesh) -> Vec<(u32, u32)> {
    use crate::mesh::Part;
    let mut lifts: Vec<(u32, u32)> = mesh
        .parts
        .iter()
        .filter_map(|p| match p {
            Part::Concrete { block, lift } => Some((*block, *lift)),
            Part::Rock => None,
        })
        .collect();
    lifts.sort_unstable();
    lifts.dedup();
    lifts
}

/// Contact passes the complete-dam step may take (at least; a scene's own
/// larger cap stands). Block pivoting has half of them before the step
/// starts again under the flip limit's rule (`contact_step::BlockPivoting`).
/// On the Xiaowan-like complete dam (29 Nov 2026, afternoon) its rounds
/// brought the points in a wrong normal state down from 6,461 through
/// 2,560, 1,030, 502, 318, 186, 97, 57, 29 and 6 to none at pass 240, the
/// answer at pass 259 with no tension kept, in 266.8 s; with 300 passes
/// the restart at pass 150 (502 wrong) ended with 6.8 MPa kept in 235
/// passes and 332 s. With the rounds shortened (that evening) the step
/// ends at pass 149: 300 would now do, with no margin; 600 costs nothing
/// where it is not needed.
pub const COMPLETE_STEP_MAX_PASSES: usize = 600;

/// Cost of one mechanical step of the complete dam.
#[derive(Debug, Clone)]
pub struct FullDamMechCost {
    pub pairs: usize,
    pub step_s: f64,
    /// the model's counters over the step
    pub stats: MechStats,
    /// entries of the factor and flops of one factorisation
    pub factor_nnz: usize,
    pub factor_flops: f64,
    /// rows a contact pass reads (the pairs and their neighbours), and the
    /// rows and entries of L on their reach
    pub joint_reach: (usize, usize, usize),
    /// the step's contact passes
    pub passes: Vec<crate::mechanics::contact_step::PassRecord>,
}

/// Pours every lift on day 0 (no thermal field) and times the first
/// mechanical step: self-weight of the whole dam on its joints, with the
/// scene's mechanical effects and contact solver, allowed
/// [`COMPLETE_STEP_MAX_PASSES`] contact passes.
pub fn full_dam_mechanics_step_cost(
    scene: &Scene,
    mesh: &crate::mesh::Mesh,
) -> Result<FullDamMechCost, MechError> {
    let mut settings =
        crate::mechanics::MechanicsSettings::from_scene(scene).map_err(MechError::from)?;
    // Every joint closing at once is the hard case, not a construction
    // step: the Xiaowan-like arch needs 149 passes (measured), more than a
    // scene's default cap of 60.
    settings.joint.max_iterations = settings.joint.max_iterations.max(COMPLETE_STEP_MAX_PASSES);
    let mut m = crate::mechanics::MechanicsModel::new(
        mesh,
        &settings,
        &crate::mechanics::Supports::for_sides(mesh, &scene.boundary.supports())?,
    )?;
    for (block, lift) in all_lifts(mesh) {
        m.pour(block, lift, 0.0);
    }
    let t = Instant::now();
    m.step(0.0, 1.0, None, None)?;
    let step_s = t.elapsed().as_secs_f64();
    let (factor_nnz, factor_flops) = m.factor_size();
    Ok(FullDamMechCost {
        factor_nnz,
        factor_flops,
        joint_reach: m.joint_rows_reach(),
        pairs: m.state.joints.iter().filter(|j| j.paired).count(),
        step_s,
        passes: m.joint_passes().to_vec(),
        stats: m.stats,
    })
}

/// Scene, mesh and schedules; schedules synthesised when the scene's folder is missing.
/// The scene's own schedules folder, when it holds a pour schedule (else
/// `study` synthesizes one).
fn own_schedules(scene: &Scene, path: &Path) -> Option<PathBuf> {
    scene
        .schedules_dir(path)
        .filter(|d| d.join("pours.csv").exists())
}

fn load_or_synthesize(
    path: &Path,
) -> Result<(Scene, crate::mesh::Mesh, schedule::Schedules), StudyError> {
    let scene = Scene::load(path)?;
    if let Some(dir) = own_schedules(&scene, path) {
        let inputs = app::load_inputs(path, Some(&dir))?;
        return Ok((inputs.scene, inputs.mesh, inputs.schedules));
    }
    let mesh = app::build_mesh(&scene, &path.display().to_string())?;
    let schedules = synthesize_for(&scene, &mesh);
    Ok((scene, mesh, schedules))
}

/// A plausible schedule for the scene's dam: lifts every 12 days (about two
/// years of construction for a 150 m dam), and, when the scene simulates the
/// reservoir, impounding from the middle of the grouting campaign.
fn synthesize_for(scene: &Scene, mesh: &crate::mesh::Mesh) -> schedule::Schedules {
    let layout = app::dam_layout(mesh);
    let params = SynthParams {
        start: scene.epoch.date(Day(30)),
        lift_interval_days: 12,
        ..SynthParams::default()
    };
    let mut s = schedule::synthesize(&layout, &params);
    if scene.has(crate::scene::Effect::ReservoirTemperature) {
        let mut dates: Vec<chrono::NaiveDate> = s.grouting.iter().map(|g| g.planned).collect();
        dates.sort();
        if let (Some(&mid), Some(&last)) = (dates.get(dates.len() / 2), dates.last()) {
            let base = mesh.layer_z.first().copied().unwrap_or(0.0);
            let height = mesh.crest_z - base;
            let end = last + chrono::Duration::days(120);
            s.reservoir = Some(vec![
                (mid, base + 0.25 * height),
                (end, base + 0.8 * height),
            ]);
        }
    }
    s
}

/// The schedule files already in `dir` (a synthesised set would replace
/// or contradict them).
fn existing_schedules(dir: &Path) -> Vec<&'static str> {
    use schedule::{
        COOLING_CSV, GROUTING_CSV, JOINT_METERS_CSV, POURS_CSV, RESERVOIR_CSV, WEATHER_CSV,
    };
    [
        POURS_CSV,
        COOLING_CSV,
        GROUTING_CSV,
        RESERVOIR_CSV,
        WEATHER_CSV,
        JOINT_METERS_CSV,
    ]
    .into_iter()
    .filter(|f| dir.join(f).exists())
    .collect()
}

/// Writes a synthesised schedule set for a scene; returns the number of
/// rows. Refuses a folder that already holds schedule files (the site's
/// edited schedules) unless `force`.
pub fn synth_schedules(scene_path: &Path, out: &Path, force: bool) -> Result<usize, StudyError> {
    let found = existing_schedules(out);
    if !found.is_empty() && !force {
        return Err(StudyError::WouldOverwrite {
            path: out.display().to_string(),
            files: found.join(", "),
        });
    }
    let scene = Scene::load(scene_path)?;
    let mesh = app::build_mesh(&scene, &scene_path.display().to_string())?;
    let s = synthesize_for(&scene, &mesh);
    schedule::write_dir(&s, out).map_err(|source| StudyError::Io {
        action: "writing",
        path: out.display().to_string(),
        source,
    })?;
    Ok(s.pours.len()
        + s.cooling.len()
        + s.grouting.len()
        + s.reservoir.as_ref().map_or(0, |r| r.len()))
}
