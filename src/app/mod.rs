//! What `groutready run` does, as a library call: load and check every input,
//! check where the run folder goes ([`out::OutDir`]), only then simulate,
//! and write the run folder atomically.

pub mod mesh_export;
pub mod out;
pub mod plan;
pub mod restart;
pub mod resume;

use std::path::{Path, PathBuf};

use crate::mesh::{self, geometry::Geometry, Mesh};
use crate::output::{self, RunDir};
use crate::scene::Scene;
use crate::schedule::{self, Schedules};
use crate::sim::{RunStats, Simulation};
use crate::vocab::Day;

pub use out::OutDir;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error(transparent)]
    Schedule(#[from] crate::schedule::ScheduleError),
    #[error("mesh of {scene}: {source}")]
    Mesh {
        scene: String,
        source: crate::mesh::MeshError,
    },
    /// A `kind = "mesh"` scene's mesh file does not make a dam (the message names the file).
    #[error(transparent)]
    DamMesh(#[from] crate::mesh::import::dam::DamMeshError),
    /// A `kind = "mesh"` scene's mesh file cannot be read (the message names the file and line).
    #[error(transparent)]
    MeshFile(#[from] crate::mesh::import::MeshFileError),
    /// The mesh file differs from the one the scene (or run folder) was made with.
    #[error(
        "{0}: the mesh file has changed since the scene was loaded (plan again with the new file)"
    )]
    MeshChanged(String),
    #[error("{0}: no schedules folder: give --schedules DIR or set `schedules` in the scene")]
    NoSchedules(String),
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    #[error("{0}: planning needs the `joints` effect (apertures come from the joint element); the scene simulates {1}")]
    PlanNeedsJoints(String, String),
    /// `plan` without `--as-of` on schedules that mark no zone done takes
    /// today as its as-of date; when every zone was due before it there is
    /// nothing to plan, and the baseline would simulate the whole
    /// construction for a report of history alone (well over an hour on
    /// the large arch).
    #[error("{grouting}: no zone is marked done, so the as-of date is today ({today}), and every zone was due by {last}: nothing is left to plan. Give --as-of DATE (the day the plan starts from; --horizon-days N to plan the weeks after it), or mark the grouted zones `done` in the status column; `groutready run` judges every zone on its planned date")]
    NothingToPlan {
        grouting: String,
        today: chrono::NaiveDate,
        last: chrono::NaiveDate,
    },
    #[error(transparent)]
    Checkpoint(#[from] crate::sim::checkpoint::CheckpointError),
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
    #[error(transparent)]
    Out(#[from] out::OutError),
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
}

pub(crate) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> AppError + '_ {
    move |source| AppError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Inputs of a run, all loaded and cross-checked.
pub struct Inputs {
    pub scene_path: PathBuf,
    pub scene: Scene,
    /// the folder the schedules were read from
    pub schedules_dir: PathBuf,
    pub schedules: Schedules,
    pub mesh: Mesh,
    /// inputs accepted but questionable ([`schedule::warnings`])
    pub warnings: Vec<schedule::Warning>,
}

impl Inputs {
    /// The days a run's or a plan's `apertures.csv` holds besides its
    /// weekly rows: the planned grouting dates and the snapshot dates.
    pub fn aperture_days(&self) -> std::collections::BTreeSet<Day> {
        let epoch = self.scene.epoch;
        let grouting = self.schedules.grouting.iter().map(|g| g.planned);
        let snapshots = self.scene.output.snapshots.iter().copied();
        grouting.chain(snapshots).map(|d| epoch.day(d)).collect()
    }
}

/// Builds the scene's mesh.
pub fn build_mesh(scene: &Scene, origin: &str) -> Result<Mesh, AppError> {
    let (lift, zone) = (scene.lifts.height_m, scene.joints.zone_height_m);
    let mesh = match &scene.geometry {
        Geometry::Blocks(g) => mesh::generate_blocks(g, lift, zone),
        Geometry::Arch(g) => mesh::generate_arch(g, lift, zone),
        Geometry::ArchTable(g) => mesh::generate_arch_table(g, lift, zone),
        Geometry::Mesh(g) => {
            let path = match &g.resolved {
                Some(r) => PathBuf::from(&r.path),
                None => Path::new(origin)
                    .parent()
                    .unwrap_or_else(|| Path::new(""))
                    .join(&g.file),
            };
            return load_mesh_file(&path, g.resolved.as_ref().map(|r| r.digest), lift, zone);
        }
    };
    mesh.map_err(|source| AppError::Mesh {
        scene: origin.to_string(),
        source,
    })
}

/// The dam of a `kind = "mesh"` scene from its file (resolved against the
/// scene's folder by the caller): what the file says, then the dam's rules.
fn load_mesh_file(
    path: &Path,
    digest: Option<u64>,
    lift: f64,
    zone: f64,
) -> Result<Mesh, AppError> {
    if let Some(digest) = digest {
        let bytes = std::fs::read(path).map_err(io_err(path))?;
        if crate::vocab::fnv1a(&bytes) != digest {
            return Err(AppError::MeshChanged(path.display().to_string()));
        }
    }
    let raw = mesh::import::read_file(path)?;
    Ok(mesh::import::dam::build(&raw, lift, zone)?)
}

pub use crate::sim::dam_layout;

/// Loads scene, schedules and mesh and checks them against each other.
pub fn load_inputs(scene_path: &Path, schedules_dir: Option<&Path>) -> Result<Inputs, AppError> {
    let scene = Scene::load(scene_path)?;
    let dir = match schedules_dir {
        Some(d) => d.to_path_buf(),
        None => scene
            .schedules_dir(scene_path)
            .ok_or_else(|| AppError::NoSchedules(scene_path.display().to_string()))?,
    };
    let schedules = schedule::load(&dir)?;
    let mesh = build_mesh(&scene, &scene_path.display().to_string())?;
    schedule::check_against(&schedules, &dam_layout(&mesh))?;
    schedule::check_dates(&schedules, scene.epoch.0)?;
    if let Some(&base) = mesh.layer_z.first() {
        schedule::check_reservoir(&schedules, base, mesh.crest_z)?;
    }
    Ok(Inputs {
        scene_path: scene_path.to_path_buf(),
        scene,
        schedules_dir: dir,
        warnings: schedule::warnings(&schedules),
        schedules,
        mesh,
    })
}

/// Summary of a finished run.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub out: PathBuf,
    pub stats: RunStats,
    pub elements: usize,
    pub thermal_dofs: usize,
    pub temperature_rows: usize,
    pub aperture_rows: usize,
    pub snapshots: usize,
    /// the zones planned within the run, judged on their planned dates
    /// (a run with joints and a grouting schedule)
    pub grouting: Option<crate::report::GroutingDistribution>,
    /// the grouted zones that cracked open again (a run with joints)
    pub reopening: Option<crate::report::Reopening>,
    /// the date an interrupted run was continued from ([`resume`])
    pub resumed_from: Option<chrono::NaiveDate>,
    /// the scene's opt-in approximations of the mechanics (empty: exact)
    pub approximations: Vec<crate::scene::Approximation>,
}

/// Simulates to the end, keeping a restart point at the checkpoints
/// ([`resume::Resume::maybe_save`]) and only the latest checkpoint in
/// memory; `written` collects the snapshots in `fields`.
fn simulate(
    inputs: &Inputs,
    sim: &mut Simulation,
    keep: &mut resume::Resume,
    fields: &Path,
    written: &mut Vec<(f64, String)>,
    progress: &mut dyn FnMut(f64, f64),
) -> Result<RunStats, AppError> {
    let mesh = &inputs.mesh;
    let end = sim.end_day().t();
    let mut seconds = 0.0;
    loop {
        let seen = sim.checkpoints.last().map(|c| c.day);
        let mut sink = |snap: &crate::sim::Snapshot| -> std::io::Result<()> {
            let name = format!("fields_{}.vtu", snap.date);
            let path = fields.join(&name);
            output::snapshot::write(&path, mesh, snap)
                .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
            written.push((snap.day.t(), name));
            Ok(())
        };
        // returns at each new checkpoint's midnight
        let mut stats = sim.run_until(Some(&mut sink), progress, &mut |_, s| {
            s.checkpoints.last().map(|c| c.day) != seen
        })?;
        seconds += stats.seconds;
        if sim.day >= end {
            stats.seconds = seconds;
            return Ok(stats);
        }
        // the next checkpoint's day counts from the last one only
        let last = sim.checkpoints.len().saturating_sub(1);
        sim.checkpoints.drain(..last);
        let sim: &Simulation = sim;
        if let Some(ck) = sim.checkpoints.last() {
            keep.maybe_save(sim, &inputs.schedules, ck, fields, written)?;
        }
    }
}

/// Runs the simulation and writes the run folder `out` (checked and locked
/// by [`OutDir::prepare`]) atomically. The run keeps a restart point beside
/// the folder while it simulates and continues from one an interrupted run
/// left, unless `from_scratch` ([`resume`]); `note` hears where it
/// continues from and what it removed, before the simulation.
pub fn run(
    inputs: &Inputs,
    out: &OutDir,
    from_scratch: bool,
    note: &mut dyn FnMut(&str),
    progress: &mut dyn FnMut(f64, f64),
) -> Result<RunSummary, AppError> {
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules)?;
    sim.checkpoint_every = Some(i64::from(inputs.scene.planner.checkpoint_days));
    let dest = out.dest();
    let staging = RunDir::create(dest).map_err(io_err(dest))?;
    let fields = staging.path().join("fields");
    std::fs::create_dir_all(&fields).map_err(io_err(&fields))?;
    let opened = resume::Resume::open(dest, &sim, &inputs.schedules, from_scratch)?;
    let mut keep = opened.resume;
    for n in &opened.notes {
        note(n);
    }
    for w in &opened.damaged {
        note(&format!("warning: {w}"));
    }
    let mut written: Vec<(f64, String)> = Vec::new();
    let resumed_from = match &opened.resumed {
        Some(r) => {
            note(&format!(
                "continuing the interrupted run from {} (its restart point {})",
                r.date,
                resume::dir_of(dest).display()
            ));
            sim.restore(&r.restart.checkpoint, &r.restart.history);
            keep.link_fields(r, &fields)?;
            written.clone_from(&r.fields);
            Some(r.date)
        }
        None => None,
    };
    drop(opened.resumed);
    let stats = simulate(inputs, &mut sim, &mut keep, &fields, &mut written, progress)?;
    let temps = staging.path().join("temperatures.csv");
    let temperature_rows = if sim.thermal.is_some() {
        output::temperatures::write(&temps, inputs.scene.epoch, &sim.records)
            .map_err(io_err(&temps))?
    } else {
        0
    };
    let aperture_rows = if sim.joint_records.columns.is_empty() {
        0
    } else {
        let path = staging.path().join(output::apertures::FILE_NAME);
        let epoch = inputs.scene.epoch;
        output::apertures::write(&path, epoch, &sim.joint_records, &inputs.aperture_days())
            .map_err(io_err(&path))?
    };
    let pvd = fields.join("fields.pvd");
    mesh::vtu::write_pvd(&pvd, &written).map_err(io_err(&pvd))?;
    let grouting = grouting_distribution(inputs, &sim);
    let reopening = (!sim.joint_records.columns.is_empty())
        .then(|| crate::report::Reopening::of(&sim.joint_records, inputs.scene.epoch));
    let summary = staging.path().join("run.txt");
    let mut text = run_text(inputs, &stats);
    if let Some(d) = resumed_from {
        text += &format!(
            "continued from the restart point of {d} (the figures above count this process only)\n"
        );
    }
    if let Some(g) = &grouting {
        text += &g.to_string();
    }
    if let Some(r) = &reopening {
        text += &r.to_string();
    }
    std::fs::write(&summary, text).map_err(io_err(&summary))?;
    let snapshots = written.len();
    staging.commit().map_err(io_err(dest))?;
    keep.remove()?;
    Ok(RunSummary {
        resumed_from,
        out: out.path().to_path_buf(),
        stats,
        elements: inputs.mesh.elements.len(),
        thermal_dofs: inputs.mesh.n_thermal_dofs,
        temperature_rows,
        aperture_rows,
        snapshots,
        grouting,
        reopening,
        approximations: inputs.scene.approximations(),
    })
}

/// The deciding apertures and verdicts of the zones planned within a run
/// with joints, on their planned dates.
fn grouting_distribution(
    inputs: &Inputs,
    sim: &Simulation,
) -> Option<crate::report::GroutingDistribution> {
    if sim.joint_records.columns.is_empty() || inputs.schedules.grouting.is_empty() {
        return None;
    }
    let judged = crate::planner::judge_planned(
        &inputs.scene,
        &inputs.mesh,
        &inputs.schedules,
        &sim.history(),
        Day::containing(sim.day),
    );
    Some(crate::report::GroutingDistribution::of(
        &judged,
        &inputs.scene.planner,
    ))
}

/// How `run.txt` (and the console) starts the line of the mechanics'
/// approximations (`study compare` reads it back).
pub const APPROXIMATIONS_LINE: &str = "mechanics approximations: ";

/// The line of `run.txt` (and the console) naming the mechanics'
/// approximations, "none (the exact path)" when there are none.
pub fn approximations_line(approximations: &[crate::scene::Approximation]) -> String {
    format!(
        "{APPROXIMATIONS_LINE}{}\n",
        crate::scene::approximation::describe(approximations)
    )
}

pub(crate) fn run_text(inputs: &Inputs, stats: &RunStats) -> String {
    let mut s = format!(
        "scene: {} ({})\nepoch: {}\neffects: {:?}\nelements: {}\nthermal dofs: {}\nsteps: {}\npours: {}\nwall seconds: {:.2}\n",
        inputs.scene.name,
        inputs.scene_path.display(),
        inputs.scene.epoch,
        inputs.scene.effects,
        inputs.mesh.elements.len(),
        inputs.mesh.n_thermal_dofs,
        stats.steps,
        stats.pours,
        stats.seconds
    );
    if let Some(t) = &stats.thermal {
        s += &format!(
            "thermal: {} symbolic, {} numeric factorisations, {} assemblies, {} pipe terms, max live dofs {}\n",
            t.symbolic, t.numeric, t.assemblies, t.pipe_terms, t.max_dofs
        );
    }
    if let Some(m) = &stats.mechanics {
        s += &format!(
            "mechanics: {} steps, {} symbolic, {} numeric factorisations, {} contact passes ({} steps pivoting in blocks), max live dofs {} ({} free, the others supported)\n",
            m.steps, m.symbolic, m.numeric, m.contact_iterations, m.block_pivoting_steps, m.max_dofs, m.max_free_dofs
        );
        s += &m.kept_tension_warning();
        s += &approximations_line(&inputs.scene.approximations());
    }
    for w in inputs.warnings.iter().chain(&stats.warnings) {
        s += &format!("warning: {w}\n");
    }
    s
}
