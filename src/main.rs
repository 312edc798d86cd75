//! `groutready` command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};

use groutready::app;

/// Will each transverse joint of an arch dam under construction be open
/// enough to grout on its planned date?
#[derive(Parser)]
#[command(name = "groutready", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene with its schedules and write a run folder.
    Run {
        /// Scene file (default: the bundled demo arch dam, models/demo_arch.toml).
        scene: Option<PathBuf>,
        /// Schedules folder (default: the scene's `schedules`).
        #[arg(long)]
        schedules: Option<PathBuf>,
        /// Run folder to write (default: runs/<scene name>): a new or empty
        /// folder, or an earlier run folder, which is replaced.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace --out even when it is a file or holds files groutready
        /// did not write (they are deleted).
        #[arg(long)]
        force: bool,
        /// Start from day 0 even when an interrupted run into --out left a
        /// restart point (`.NAME.resume`, which is then removed).
        #[arg(long)]
        from_scratch: bool,
        /// Simulate on the exact path: the scene's opt-in approximations
        /// (`time.mechanics_max_step_days` above 1, merged pours or
        /// groutings, layer merging, a coarsened rock) off, whatever the
        /// scene file says.
        #[arg(long)]
        exact: bool,
    },
    /// Readiness of every grouting zone on its planned date, remedies for the
    /// zones that are not groutable, and a report (the weekly job).
    Plan {
        /// Scene file (default: the bundled demo arch dam, models/demo_arch.toml).
        scene: Option<PathBuf>,
        #[command(flatten)]
        args: PlanArgs,
        /// Exit with code 3 when any zone still to grout is not groutable.
        #[arg(long)]
        fail_on_flag: bool,
    },
    /// The plan in a terminal UI: the dam's joints at a glance, zone
    /// histories and rules, what-if supercooling or dates re-simulated from
    /// the run's checkpoints.
    Tui {
        /// A run folder written by `groutready plan`, or a scene file to plan
        /// first (default: the bundled demo, planned into runs/demo_arch
        /// unless that folder's plan is up to date).
        target: Option<PathBuf>,
        #[command(flatten)]
        args: PlanArgs,
    },
    /// Benchmarks: what accuracy costs in time.
    Study {
        #[command(subcommand)]
        what: StudyCommand,
    },
    /// Build a scene's mesh, write it for ParaView, Gmsh or Abaqus/CalculiX,
    /// and print its size and element quality.
    Mesh {
        /// Scene file (default: the bundled demo arch dam, models/demo_arch.toml).
        scene: Option<PathBuf>,
        /// File to write: .vtu (ParaView), .msh (Gmsh MSH 4.1) or .inp (Abaqus/CalculiX).
        #[arg(long, value_parser = parse_mesh_out)]
        out: PathBuf,
    },
    /// Schedule tools.
    Schedule {
        #[command(subcommand)]
        what: ScheduleCommand,
    },
}

/// What a plan is made of, for `plan` and for `tui` given a scene.
#[derive(clap::Args)]
struct PlanArgs {
    /// Schedules folder (default: the scene's `schedules`).
    #[arg(long)]
    schedules: Option<PathBuf>,
    /// Run folder to write (default: runs/<scene name>): a new or empty
    /// folder, or an earlier run folder, which is replaced (its checkpoints
    /// are reused when the scene is unchanged, its whatif/ is kept).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace --out even when it is a file or holds files groutready did
    /// not write (they are deleted).
    #[arg(long)]
    force: bool,
    /// Zones planned before this date (YYYY-MM-DD) are history (default:
    /// the day after the last zone marked done in grouting.csv, else today).
    #[arg(long, value_parser = parse_date)]
    as_of: Option<chrono::NaiveDate>,
    /// Plan only the zones due within this many days of the as-of date
    /// (default: the scene's planner.horizon_days, else all).
    #[arg(long)]
    horizon_days: Option<u32>,
    /// Simulate from day 0 even if the run folder has checkpoints (and, in
    /// the TUI, plan again even when its plan is up to date).
    #[arg(long)]
    from_scratch: bool,
    /// Simulate on the exact path: the scene's opt-in approximations
    /// (`time.mechanics_max_step_days` above 1, merged pours or
    /// groutings, layer merging, a coarsened rock) off, whatever the
    /// scene file says.
    #[arg(long)]
    exact: bool,
}

impl PlanArgs {
    fn request(&self) -> app::plan::PlanRequest {
        app::plan::PlanRequest {
            as_of: self.as_of,
            today: today(),
            horizon_days: self.horizon_days,
            from_scratch: self.from_scratch,
        }
    }
}

#[derive(Subcommand)]
enum StudyCommand {
    /// A ladder of discretisations and solver settings against a reference
    /// run: deciding-aperture and temperature errors at every zone's planned
    /// date, verdicts that differ, and the time each cost (accuracy.csv,
    /// accuracy.md, accuracy.svg).
    Accuracy {
        /// Scene (default: models/small_dam_joints.toml).
        scene: Option<PathBuf>,
        /// Folder to write (default: runs/<scene stem>_accuracy).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Judge only the zones planned within this many days of the epoch.
        #[arg(long)]
        horizon_days: Option<i64>,
        /// Only the scene as given and the presets, against a reference on
        /// the scene's own mesh (steps ×1/4, consistent capacity): for
        /// scenes too large for the mesh knobs.
        #[arg(long)]
        presets_only: bool,
        /// Only the scene as given and the settings of these knobs (comma
        /// separated: steps, multi-rate, capacity, theta, thermal solver,
        /// mechanics step, element, rock coarsening, across, along, layers,
        /// preset), against the
        /// default reference: one knob's ladder in a fraction of the time.
        #[arg(long, value_delimiter = ',')]
        knobs: Vec<String>,
    },
    /// An approximation's error against the exact path where the planner
    /// decides: the apertures.csv of two runs of one scene (e.g. one with
    /// `[time] mechanics_max_step_days = 3`, one exact) compared at every
    /// zone's planned grouting date (the deciding aperture: largest and RMS
    /// difference, contact states and verdicts that differ), then over every
    /// row both share; nothing is simulated.
    Compare {
        /// First run: a run folder written by `run` or `plan`, or its
        /// apertures.csv (e.g. the approximation).
        run_a: PathBuf,
        /// Second run, the same way (e.g. the exact path).
        run_b: PathBuf,
        /// Scene both runs were made from: its grouting schedule's planned
        /// dates and its [planner] aperture point and limit (default:
        /// models/demo_arch.toml).
        scene: Option<PathBuf>,
    },
    /// Weekly update: a plan from scratch, the same plan restarted from its
    /// run folder, and the plan after a schedule edit, timed (written to a
    /// scratch folder under the system's temp dir, removed at the end).
    Restart {
        /// Scene (default: models/demo_arch.toml).
        scene: Option<PathBuf>,
    },
    /// Run time by phase (thermal, mechanics, joints): steps, factorisations,
    /// contact passes and peak memory of the demo and the large arch, the
    /// exact path compared, the demo planned.
    Perf {
        /// Scenes to time (default: models/demo_arch.toml, then the first 40
        /// days and the complete-dam steps of models/xiaowan_like.toml).
        scenes: Vec<PathBuf>,
        /// Time only the first (demo) scene.
        #[arg(long)]
        quick: bool,
        /// Stop each staged run after this many days (the complete-dam step is still timed).
        #[arg(long)]
        days: Option<f64>,
        /// Thermal solver(s) to time: cholesky, pcg or both (default: each scene's own).
        #[arg(long)]
        solver: Option<String>,
        /// Also time the complete-dam mechanical step of scenes above 100k
        /// mechanical dofs (minutes and several GB on the large arch).
        #[arg(long)]
        complete_mechanics: bool,
        /// Skip the exact-path run of scenes with joints (every contact-set
        /// change refactorised) and its comparison with the fast path.
        #[arg(long)]
        no_exact: bool,
        /// Time one scene's run from the restart point an interrupted
        /// `groutready run --out RUN` kept (`.RUN.resume`), --days counted
        /// from there: a long run's late days without its first months.
        #[arg(long, value_name = "RUN")]
        resume: Option<PathBuf>,
        /// The as-of date (YYYY-MM-DD) of the plan timed after a scene's
        /// whole construction (default: as `plan`'s).
        #[arg(long, value_parser = parse_date)]
        as_of: Option<chrono::NaiveDate>,
        /// That plan's horizon in days (default: as `plan`'s).
        #[arg(long)]
        horizon_days: Option<u32>,
    },
}

#[derive(Subcommand)]
enum ScheduleCommand {
    /// Write a plausible construction schedule (pours, cooling, grouting) for a scene.
    Synth {
        /// Scene whose dam the schedules are for (blocks, lifts, joints, zones).
        scene: PathBuf,
        /// Folder to write pours.csv, cooling.csv, grouting.csv (and
        /// reservoir.csv when the scene simulates the reservoir) into.
        #[arg(long)]
        out: PathBuf,
        /// Overwrite the schedule files already in --out.
        #[arg(long)]
        force: bool,
    },
}

/// The bundled scene: relative to the working directory, else to the crate.
fn bundled(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        return here;
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn default_out(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("runs").join(stem)
}

fn parse_date(s: &str) -> Result<chrono::NaiveDate, String> {
    chrono::NaiveDate::parse_from_str(s, "%Y-%m-%d")
        .map_err(|_| format!("expected a date YYYY-MM-DD, found {s:?}"))
}

fn parse_mesh_out(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match app::mesh_export::MeshOut::of(&path) {
        Some(_) => Ok(path),
        None => Err(format!(
            "expected a file ending in {}, found {s:?}",
            app::mesh_export::MeshOut::EXPECTED
        )),
    }
}

/// The large arch's factors and matrices on huge pages
/// ([`groutready::machine::LargeBlocksOnHugePages`]).
#[global_allocator]
static ALLOCATOR: groutready::machine::LargeBlocksOnHugePages =
    groutready::machine::LargeBlocksOnHugePages;

/// Exit code of a plan with `--fail-on-flag` and a zone not groutable.
const EXIT_FLAGGED: u8 = 3;

fn main() -> ExitCode {
    groutready::machine::keep_freed_memory();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match dispatch(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // Messages that already quote their cause are not repeated.
            let mut msg = e.to_string();
            for cause in e.chain().skip(1) {
                let c = cause.to_string();
                if !msg.ends_with(&c) {
                    msg = format!("{msg}: {c}");
                }
            }
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}

/// One function per subcommand; each returns the process exit code.
fn dispatch(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        Command::Run {
            scene,
            schedules,
            out,
            force,
            from_scratch,
            exact,
        } => run(scene, schedules, out, force, from_scratch, exact),
        Command::Plan {
            scene,
            args,
            fail_on_flag,
        } => plan(scene, &args, fail_on_flag),
        Command::Tui { target, args } => tui(target, args),
        Command::Study {
            what: StudyCommand::Restart { scene },
        } => study_restart(scene),
        Command::Study {
            what:
                StudyCommand::Compare {
                    run_a,
                    run_b,
                    scene,
                },
        } => study_compare(&run_a, &run_b, scene),
        Command::Study {
            what:
                StudyCommand::Accuracy {
                    scene,
                    out,
                    horizon_days,
                    presets_only,
                    knobs,
                },
        } => study_accuracy(
            scene,
            out,
            groutready::study::accuracy::AccuracyOptions {
                horizon_days,
                presets_only,
                knobs,
            },
        ),
        Command::Study {
            what:
                StudyCommand::Perf {
                    scenes,
                    quick,
                    days,
                    solver,
                    complete_mechanics,
                    no_exact,
                    resume,
                    as_of,
                    horizon_days,
                },
        } => {
            let options = groutready::study::PerfOptions {
                max_days: days,
                solvers: groutready::study::parse_solvers(solver.as_deref())?,
                complete_mechanics,
                exact: !no_exact,
                resume,
                plan: app::plan::PlanRequest {
                    as_of,
                    horizon_days,
                    ..app::plan::PlanRequest::on(today())
                },
            };
            study_perf(scenes, quick, options)
        }
        Command::Schedule {
            what: ScheduleCommand::Synth { scene, out, force },
        } => schedule_synth(&scene, &out, force),
        Command::Mesh { scene, out } => mesh(scene, &out),
    }
}

/// `groutready run`: simulate and write the run folder.
fn run(
    scene: Option<PathBuf>,
    schedules: Option<PathBuf>,
    out: Option<PathBuf>,
    force: bool,
    from_scratch: bool,
    exact: bool,
) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    let out = out.unwrap_or_else(|| default_out(&scene));
    let inputs = load_inputs(&scene, schedules.as_deref(), exact)?;
    let out = prepare_out(&out, &inputs, force)?;
    eprintln!(
        "{}: {} elements, {} thermal dofs, {} pours, effects {:?}",
        inputs.scene.name,
        inputs.mesh.elements.len(),
        inputs.mesh.n_thermal_dofs,
        inputs.schedules.pours.len(),
        inputs.scene.effects
    );
    print_warnings(&inputs.warnings);
    let bar = groutready::progress::bar("simulating");
    let summary = app::run(
        &inputs,
        &out,
        from_scratch,
        &mut |n| bar.suspend(|| eprintln!("note: {n}")),
        &mut |day, end| groutready::progress::update(&bar, day, end),
    )
    .with_context(|| format!("running {}", scene.display()))?;
    bar.finish_and_clear();
    print_warnings(&summary.stats.warnings);
    print!("{}", groutready::study::summary_line(&summary));
    if let Some(g) = &summary.grouting {
        print!("{g}");
    }
    if let Some(r) = &summary.reopening {
        print!("{r}");
    }
    println!("wrote {}", summary.out.display());
    Ok(0)
}

/// Scene, schedules and mesh; with `exact` (`--exact`) the scene's opt-in
/// approximations are turned off, and the console says which were.
fn load_inputs(scene: &Path, schedules: Option<&Path>, exact: bool) -> anyhow::Result<app::Inputs> {
    let mut inputs = app::load_inputs(scene, schedules)?;
    let approximations = inputs.scene.approximations();
    if exact && !approximations.is_empty() {
        eprintln!(
            "note: --exact: simulating without the scene's {}",
            groutready::scene::approximation::describe(&approximations)
        );
        inputs.scene = inputs.scene.without_approximations();
    }
    Ok(inputs)
}

/// Warnings on the inputs, before the long run (the report repeats them).
fn print_warnings(warnings: &[groutready::schedule::Warning]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// `groutready plan`: plan the zones, print the readiness table and what the
/// run cost; exit [`EXIT_FLAGGED`] on request when a zone is not groutable.
fn plan(scene: Option<PathBuf>, args: &PlanArgs, fail_on_flag: bool) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    let out = args.out.clone().unwrap_or_else(|| default_out(&scene));
    let inputs = load_inputs(&scene, args.schedules.as_deref(), args.exact)?;
    let out = prepare_out(&out, &inputs, args.force)?;
    eprintln!(
        "{}: {} elements, {} pours, {} grouting zones, effects {:?}",
        inputs.scene.name,
        inputs.mesh.elements.len(),
        inputs.schedules.pours.len(),
        inputs.schedules.grouting.len(),
        inputs.scene.effects
    );
    print_warnings(&inputs.warnings);
    let request = args.request();
    let bar = groutready::progress::bar("simulating");
    let summary = app::plan::plan(&inputs, &out, &request, &mut |p| match p {
        groutready::planner::Progress::Baseline { day, end } => {
            groutready::progress::update(&bar, day, end)
        }
        groutready::planner::Progress::Resimulation(what) => {
            bar.stage(format!("re-simulating: {what}"))
        }
    })
    .with_context(|| format!("planning {}", scene.display()))?;
    bar.finish_and_clear();
    print_plan(&summary);
    let flagged = summary.plan.flagged().count();
    Ok(if fail_on_flag && flagged > 0 {
        EXIT_FLAGGED
    } else {
        0
    })
}

/// The readiness table, the zones the remedies broke, what the plan cost and
/// where it was written.
fn print_plan(summary: &app::plan::PlanSummary) {
    print!("{}", groutready::report::readiness_table(&summary.plan));
    for (zone, why) in &summary.newly_flagged {
        println!("note: {zone} is no longer groutable once the remedies are applied: {why}");
    }
    let st = &summary.plan.stats;
    let search_days = summary.plan.settings.search_max_step_days;
    println!(
        "simulated in {:.1} s{} + {} re-simulations in {:.1} s{}; {} checkpoints kept",
        st.baseline_seconds,
        st.restarted_from
            .map(|d| format!(" (restarted from {d})"))
            .unwrap_or_default(),
        st.resimulations,
        st.resimulation_seconds,
        if search_days > 1 {
            format!(" (the searches on mechanical steps of up to {search_days} days, verified on the scene's)")
        } else {
            String::new()
        },
        summary.checkpoints_kept
    );
    if !st.reused.is_empty() {
        println!("reused from the last plan: {}", st.reused.join(", "));
    }
    if summary.remedied {
        println!(
            "remedied schedules: {}",
            summary.out.join(app::plan::REMEDIED_DIR).display()
        );
    }
    println!("wrote {}", summary.out.display());
}

/// The binary's clock decides "today"; the library reads none.
fn today() -> chrono::NaiveDate {
    chrono::Local::now().date_naive()
}

/// `groutready study restart`: time the weekly update.
fn study_restart(scene: Option<PathBuf>) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    groutready::study::restart::restart(&scene, today())?;
    Ok(0)
}

/// `groutready study compare`: two runs' apertures at the planned dates.
fn study_compare(run_a: &Path, run_b: &Path, scene: Option<PathBuf>) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    let comparison = groutready::study::compare::compare(run_a, run_b, &scene)?;
    print!("{}", comparison.report());
    Ok(0)
}

/// `groutready study accuracy`: the ladder against its reference.
fn study_accuracy(
    scene: Option<PathBuf>,
    out: Option<PathBuf>,
    options: groutready::study::accuracy::AccuracyOptions,
) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/small_dam_joints.toml"));
    let out = out.unwrap_or_else(|| {
        let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from("runs").join(format!("{stem}_accuracy"))
    });
    let table =
        groutready::study::accuracy::accuracy(&scene, &out, &options, &mut |l| eprintln!("{l}"))?;
    print!("{}", groutready::study::accuracy::markdown(&table));
    println!("wrote {}", out.display());
    Ok(0)
}

/// `groutready study perf`: time the given scenes, or the demo and then the
/// large arch.
fn study_perf(
    scenes: Vec<PathBuf>,
    quick: bool,
    options: groutready::study::PerfOptions,
) -> anyhow::Result<u8> {
    let defaults = scenes.is_empty();
    let scenes = if defaults {
        vec![bundled("models/demo_arch.toml")]
    } else {
        scenes
    };
    groutready::study::perf(&scenes, &options)?;
    if defaults && !quick && options.resume.is_none() {
        // The large arch's whole construction with mechanics takes
        // over an hour on the exact path (README): its first 40 days (17
        // mechanical steps on a 171k-dof system) and its complete-dam
        // steps; no exact-path rerun.
        let large = [bundled("models/xiaowan_like.toml")];
        let options = groutready::study::PerfOptions {
            max_days: Some(options.max_days.unwrap_or(40.0)),
            exact: false,
            ..options
        };
        groutready::study::perf(&large, &options)?;
    }
    Ok(0)
}

/// Checks and locks the run folder before anything is simulated, and says
/// what was cleaned on the way.
fn prepare_out(out: &Path, inputs: &app::Inputs, force: bool) -> anyhow::Result<app::OutDir> {
    let dir = app::OutDir::prepare(out, inputs, force)?;
    for note in dir.notes() {
        eprintln!("note: {note}");
    }
    Ok(dir)
}

/// `groutready mesh`: build, write and summarise a scene's mesh.
fn mesh(scene: Option<PathBuf>, out: &Path) -> anyhow::Result<u8> {
    let scene = scene.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    let summary = app::mesh_export::mesh(&scene, out)?;
    println!("mesh of {}", scene.display());
    print!("{summary}");
    println!("wrote {}", out.display());
    Ok(0)
}

/// `groutready schedule synth`: write a plausible schedule set for a scene.
fn schedule_synth(scene: &Path, out: &Path, force: bool) -> anyhow::Result<u8> {
    let n = groutready::study::synth_schedules(scene, out, force)?;
    println!("wrote {n} rows to {}", out.display());
    Ok(0)
}

fn tui(target: Option<PathBuf>, args: PlanArgs) -> anyhow::Result<u8> {
    use groutready::tui::{self, RunData, Session};
    let color = tui::color_wanted();
    let target = target.unwrap_or_else(|| bundled("models/demo_arch.toml"));
    let session = if target.is_dir() {
        let scene_only = [
            ("--schedules", args.schedules.is_some()),
            ("--out", args.out.is_some()),
            ("--as-of", args.as_of.is_some()),
            ("--horizon-days", args.horizon_days.is_some()),
            ("--from-scratch", args.from_scratch),
            ("--force", args.force),
            ("--exact", args.exact),
        ];
        if let Some((flag, _)) = scene_only.iter().find(|f| f.1) {
            anyhow::bail!(
                "{flag} applies to a scene; {} is a run folder (plan it again with `groutready plan`)",
                target.display()
            );
        }
        let data =
            RunData::load(&target).with_context(|| format!("opening {}", target.display()))?;
        Session::open(data, color)
    } else {
        let out = args.out.clone().unwrap_or_else(|| default_out(&target));
        // Bad input is reported here, before the terminal is taken over.
        let inputs = load_inputs(&target, args.schedules.as_deref(), args.exact)?;
        let request = args.request();
        if app::plan::is_current(&inputs, &out, &request) {
            let data = RunData::load(&out).with_context(|| format!("opening {}", out.display()))?;
            let mut s = Session::open(data, color);
            s.app.status = Some(format!(
                "{}: the plan there is up to date (--from-scratch plans again)",
                out.display()
            ));
            s
        } else {
            let out = prepare_out(&out, &inputs, args.force)?;
            Session::plan(inputs, out, request, color)
        }
    };
    let failed = |s: &Session| s.app.planning.as_ref().and_then(|p| p.error.clone());
    let mut session = session;
    tui::terminal::run_until_quit(&mut session).context("the terminal UI needs a terminal")?;
    if let Some(e) = failed(&session) {
        anyhow::bail!("planning failed: {e}");
    }
    Ok(0)
}
