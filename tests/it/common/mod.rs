//! Builders shared by the integration tests.
#![allow(dead_code)]

use chrono::NaiveDate;
use groutready::fem::hex8::FACES;
use groutready::mesh::{self, geometry::BlocksGeometry, Mesh, SurfaceFace, SurfaceKind};
use groutready::scene::Scene;

pub fn date(y: i32, m: u32, d: u32) -> NaiveDate {
    NaiveDate::from_ymd_opt(y, m, d).unwrap()
}

/// A scene from TOML text with the given effects and extra tables.
pub fn scene(effects: &str, geometry: &str, extra: &str) -> Scene {
    scene_with_concrete(effects, geometry, extra, "")
}

/// As [`scene`], with extra keys in `[concrete]` (e.g. the mechanical ones).
pub fn scene_with_concrete(effects: &str, geometry: &str, extra: &str, concrete: &str) -> Scene {
    let text = format!(
        r#"
name = "test"
epoch = "2024-01-01"
effects = [{effects}]
{extra}
[geometry]
{geometry}
[lifts]
height_m = 3.0
[joints]
zone_height_m = 3.0
[concrete]
density_kg_m3 = 2400.0
specific_heat_j_kgk = 950.0
conductivity_w_mk = 2.2
adiabatic = {{ form = "exponential", theta0 = 25.0, m = 0.35 }}
{concrete}
"#
    );
    Scene::from_toml_str(&text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

pub fn blocks_geometry(
    n_blocks: u32,
    length: f64,
    thickness: f64,
    n_lifts: u32,
    nx: u32,
    ny: u32,
) -> String {
    format!(
        "kind = \"blocks\"\nn_blocks = {n_blocks}\nblock_length_m = {length}\nthickness_m = {thickness}\n\
         n_lifts = {n_lifts}\nelements_per_block = {nx}\nelements_across = {ny}\n"
    )
}

pub fn blocks_mesh(scene: &Scene) -> Mesh {
    match &scene.geometry {
        mesh::geometry::Geometry::Blocks(g) => {
            mesh::generate_blocks(g, scene.lifts.height_m, scene.joints.zone_height_m).unwrap()
        }
        _ => panic!("blocks scene expected"),
    }
}

pub fn plain_blocks(g: &BlocksGeometry, lift: f64, zone: f64) -> Mesh {
    mesh::generate_blocks(g, lift, zone).unwrap()
}

/// Marks every outer face Far (adiabatic) except those for which `keep(centroid)` holds.
pub fn only_faces(mesh: &mut Mesh, keep: impl Fn([f64; 3]) -> bool) {
    let mut count = std::collections::HashMap::new();
    for conn in &mesh.elements {
        for f in FACES {
            let mut key: Vec<u32> = f
                .iter()
                .map(|&k| mesh.thermal_dof[conn[k] as usize])
                .collect();
            key.sort_unstable();
            *count.entry(key).or_insert(0) += 1;
        }
    }
    let mut surfaces = Vec::new();
    for (e, conn) in mesh.elements.iter().enumerate() {
        for (fi, f) in FACES.iter().enumerate() {
            let mut key: Vec<u32> = f
                .iter()
                .map(|&k| mesh.thermal_dof[conn[k] as usize])
                .collect();
            key.sort_unstable();
            if count[&key] != 1 {
                continue;
            }
            let mut c = [0.0; 3];
            for &k in f {
                for d in 0..3 {
                    c[d] += 0.25 * mesh.nodes[conn[k] as usize][d];
                }
            }
            let kind = if keep(c) {
                SurfaceKind::Ground
            } else {
                SurfaceKind::Far
            };
            surfaces.push(SurfaceFace {
                elem: e as u32,
                face: fi as u8,
                kind,
            });
        }
    }
    mesh.surfaces = surfaces;
}

/// Least-squares slope of log(err) against log(h).
pub fn fitted_slope(h: &[f64], err: &[f64]) -> f64 {
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Small deterministic generator (xorshift64*), uniform in [lo, hi).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    /// A point in the reference cube [−1, 1)³.
    pub fn point(&mut self) -> [f64; 3] {
        [
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        ]
    }
}

/// Relative difference |a − b|/|b| (0 when equal).
pub fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / b.abs()
    }
}

pub fn assert_rel(got: f64, want: f64, tol: f64, what: &str) {
    let r = rel(got, want);
    assert!(
        r <= tol,
        "{what}: got {got:e}, want {want:e}, relative error {r:e} > {tol:e}"
    );
}

/// Walls at both ends (u_x = 0), a frictionless base (u_z = 0) and one side
/// face held in y (u_y = 0): blocks free to expand sideways and upwards.
pub fn walls_frictionless_base(mesh: &Mesh) -> groutready::mechanics::Supports {
    let xs = mesh.nodes.iter().map(|p| p[0]);
    let (xmin, xmax) = (
        xs.clone().fold(f64::MAX, f64::min),
        xs.fold(f64::MIN, f64::max),
    );
    let ymin = mesh.nodes.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
    let zmin = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    let tol = 1e-9 * (xmax - xmin).abs().max(1.0);
    let mut fixed = vec![];
    for (i, p) in mesh.nodes.iter().enumerate() {
        if (p[0] - xmin).abs() < tol || (p[0] - xmax).abs() < tol {
            fixed.push((i as u32, 0));
        }
        if (p[1] - ymin).abs() < tol {
            fixed.push((i as u32, 1));
        }
        if (p[2] - zmin).abs() < tol {
            fixed.push((i as u32, 2));
        }
    }
    groutready::mechanics::Supports { fixed }
}

/// The `groutready` binary, run from the crate's folder.
pub fn bin() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_groutready"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// A path inside the crate's folder.
pub fn repo(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The text of `models/small_dam_joints.toml` with its schedules read from
/// `schedules` (the repository's, or a copy a test edits), for a test that
/// writes the scene elsewhere, often with a table added.
pub fn small_dam_scene_text(schedules: &std::path::Path) -> String {
    let text = std::fs::read_to_string(repo("models/small_dam_joints.toml")).unwrap();
    let from = "\"../schedules/small_dam\"";
    assert!(text.contains(from), "the small dam reads {from}");
    text.replace(from, &format!("\"{}\"", schedules.display()))
}

/// Copies the files and folders of `from` into `to` (created).
pub fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &to.join(entry.file_name()));
        } else {
            std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
        }
    }
}

/// A `groutready plan` run shared by every test that needs it: planned once
/// per test process into `CARGO_TARGET_TMPDIR` (tests that write into a run
/// folder copy it first).
pub struct Planned {
    /// the folder the command ran in
    pub root: std::path::PathBuf,
    /// the run folder
    pub out: std::path::PathBuf,
    pub output: std::process::Output,
}

impl Planned {
    pub fn stdout(&self) -> String {
        String::from_utf8_lossy(&self.output.stdout).into_owned()
    }
    pub fn stderr(&self) -> String {
        String::from_utf8_lossy(&self.output.stderr).into_owned()
    }
}

fn plan_in(name: &str, args: &[&str], from_crate: bool) -> Planned {
    let root = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_groutready"));
    c.current_dir(if from_crate {
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    } else {
        root.clone()
    });
    c.arg("plan").args(args);
    let out = if from_crate {
        let out = root.join("plan");
        c.arg("--out").arg(&out);
        out
    } else {
        root.join("runs/demo_arch")
    };
    let output = c.output().unwrap();
    Planned { root, out, output }
}

/// The small dam planned from 15 July 2024, while the second stages of the
/// September zones run (their supercooling is a water change inside them).
pub fn small_plan_running() -> &'static Planned {
    static P: std::sync::OnceLock<Planned> = std::sync::OnceLock::new();
    P.get_or_init(|| {
        plan_in(
            "small_plan_running",
            &[
                "models/small_dam_joints.toml",
                "--as-of",
                "2024-07-15",
                "--horizon-days",
                "60",
            ],
            true,
        )
    })
}

/// The README's main command, `groutready plan` with no arguments, run from
/// an empty folder (the demo is found next to the program's sources).
pub fn demo_plan() -> &'static Planned {
    static P: std::sync::OnceLock<Planned> = std::sync::OnceLock::new();
    P.get_or_init(|| plan_in("demo_plan", &[], false))
}

/// The small dam planned from 1 June 2024 over 105 days: zones grouted
/// before, zones too warm with no remedy, zones supercooling fixes, zones
/// not poured yet.
pub fn small_plan() -> &'static Planned {
    static P: std::sync::OnceLock<Planned> = std::sync::OnceLock::new();
    P.get_or_init(|| {
        plan_in(
            "small_plan",
            &[
                "models/small_dam_joints.toml",
                "--as-of",
                "2024-06-01",
                "--horizon-days",
                "105",
            ],
            true,
        )
    })
}

/// Rollers on the faces of the bounding box: `sides` fixes the normal
/// component on the x and y faces, `bottom`/`top` the vertical one.
pub fn rollers(
    mesh: &Mesh,
    sides: bool,
    bottom: bool,
    top: bool,
) -> groutready::mechanics::Supports {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in &mesh.nodes {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let mut fixed = vec![];
    for (i, p) in mesh.nodes.iter().enumerate() {
        for d in 0..3 {
            let on_lo = (p[d] - lo[d]).abs() < 1e-9;
            let on_hi = (p[d] - hi[d]).abs() < 1e-9;
            let fix = match d {
                2 => (bottom && on_lo) || (top && on_hi),
                _ => sides && (on_lo || on_hi),
            };
            if fix {
                fixed.push((i as u32, d as u8));
            }
        }
    }
    groutready::mechanics::Supports { fixed }
}

/// Replaces the scene's `[joints]` table with `text` (its keys).
pub fn set_joints(sc: &mut Scene, text: &str) {
    let j: toml::Table = toml::from_str(&format!("[joints]\n{text}")).unwrap();
    sc.joints = j["joints"].clone().try_into().unwrap();
}

/// Statically determinate 3-2-1 supports on three nodes of the mesh's
/// base (the two ends along x, the one farthest along y): the supports,
/// their (node, component) list, and the first node (the field's origin).
pub fn base_three_two_one(mesh: &Mesh) -> (groutready::mechanics::Supports, Vec<(u32, u8)>, u32) {
    let base = mesh.nodes.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
    let mut on_base: Vec<u32> = (0..mesh.nodes.len() as u32)
        .filter(|&v| mesh.nodes[v as usize][2] == base)
        .collect();
    on_base.sort_by(|&a, &b| mesh.nodes[a as usize][0].total_cmp(&mesh.nodes[b as usize][0]));
    let (a, b) = (on_base[0], on_base[on_base.len() - 1]);
    let c = *on_base
        .iter()
        .max_by(|&&p, &&q| mesh.nodes[p as usize][1].total_cmp(&mesh.nodes[q as usize][1]))
        .unwrap();
    let fixed = vec![(a, 0), (a, 1), (a, 2), (b, 1), (b, 2), (c, 2)];
    let supports = groutready::mechanics::Supports {
        fixed: fixed.clone(),
    };
    (supports, fixed, a)
}

/// The largest displacement off `want(node, component)` [m] and the
/// largest stress component [Pa] of a model's accumulated state.
pub fn misfit_and_stress(
    m: &groutready::mechanics::MechanicsModel,
    n_nodes: usize,
    want: impl Fn(usize, usize) -> f64,
) -> (f64, f64) {
    let worst_u = (0..n_nodes)
        .flat_map(|v| (0..3).map(move |k| (v, k)))
        .map(|(v, k)| (m.state.u[3 * v + k] - want(v, k)).abs())
        .fold(0.0, f64::max);
    let worst_s = m
        .state
        .stress
        .iter()
        .flat_map(|s| s.iter().flatten())
        .map(|v| v.abs())
        .fold(0.0, f64::max);
    (worst_u, worst_s)
}

/// The demo arch's mesh and mechanics settings.
pub fn demo_mechanics() -> (Mesh, groutready::mechanics::MechanicsSettings) {
    let inputs = groutready::app::load_inputs(&repo("models/demo_arch.toml"), None).unwrap();
    let settings = groutready::mechanics::MechanicsSettings::from_scene(&inputs.scene).unwrap();
    (inputs.mesh, settings)
}

/// Distance between two points [m].
pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Mechanics of a free thermal expansion: no joints, weight, water or
/// creep, and the rock expanding as the concrete does; returns that α.
pub fn thermal_strain_only(settings: &mut groutready::mechanics::MechanicsSettings) -> f64 {
    settings.joints = false;
    settings.self_weight = false;
    settings.reservoir_load = false;
    settings.concrete.creep = None;
    let alpha = settings.concrete.expansion_per_c;
    if let Some(rock) = settings.rock.as_mut() {
        rock.expansion_per_c = alpha;
    }
    alpha
}
