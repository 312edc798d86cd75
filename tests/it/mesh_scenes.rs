//! Meshes from files run as scenes (issue 14). Round trips: a generated
//! dam written by `groutready mesh --out x.msh` (or `.inp`) and read back
//! as `[geometry] kind = "mesh"` is the generator's mesh, bit for bit, so it
//! gives the same apertures (the three-block scene is run both ways; the
//! small dam and the demo arch are compared mesh against mesh, which decides
//! the run).
//!
//! A mesh made by Gmsh itself: `tests/fixtures/three_blocks/
//! three_blocks.geo`, three blocks on rock in transfinite hexahedra, is
//! meshed by the `gmsh` binary (Debian's 4.8, which `.ci/run` installs),
//! read as `[geometry] kind = "mesh"` and run with every effect of its twin
//! scene `three_blocks.toml`, which the `blocks` generator draws. The two
//! meshes number their nodes and elements differently (Gmsh orders them by
//! its entities, the generator by its grid) and Gmsh shares the nodes of
//! the joint faces (groutready duplicates them), so the runs assemble the
//! same equations in another order: the apertures and joint states at every
//! zone point and date agree to round-off.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use groutready::mesh::Mesh;
use groutready::scene::Scene;

use crate::common::{bin, repo};

/// `(joint, zone, point, date)` → (aperture mm, state) of an apertures.csv.
fn apertures(path: &Path) -> BTreeMap<(String, String, String, String), (f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (j, z, p, d, a, s) = (
        col("joint"),
        col("zone"),
        col("point"),
        col("date"),
        col("aperture_mm"),
        col("state"),
    );
    rows.map(|l| {
        let f: Vec<&str> = l.split(',').collect();
        (
            (f[j].into(), f[z].into(), f[p].into(), f[d].into()),
            (f[a].parse().unwrap(), f[s].to_string()),
        )
    })
    .collect()
}

/// The twin scene with its `[geometry]` table replaced by the Gmsh file.
fn mesh_scene(generator_scene: &str, schedules: &Path, msh: &str) -> String {
    let mut out = String::new();
    let mut skipping = false;
    for line in generator_scene.lines() {
        if line.starts_with('[') {
            skipping = line.trim() == "[geometry]";
            if skipping {
                out += &format!("[geometry]\nkind = \"mesh\"\nfile = \"{msh}\"\n");
                continue;
            }
        }
        if skipping {
            continue;
        }
        if line.starts_with("schedules =") {
            out += &format!("schedules = {:?}\n", schedules.display().to_string());
        } else {
            out += line;
            out.push('\n');
        }
    }
    out
}

#[test]
fn a_gmsh_mesh_runs_and_agrees_with_the_blocks_generator() {
    if Command::new("gmsh").arg("--version").output().is_err() {
        eprintln!("gmsh is not installed: test skipped (.ci/run installs Debian's gmsh)");
        return;
    }
    let fixture = repo("tests/fixtures/three_blocks");
    let dir = tempfile::tempdir().unwrap();
    let gmsh = Command::new("gmsh")
        .args(["-3", "-format", "msh41"])
        .arg(fixture.join("three_blocks.geo"))
        .arg("-o")
        .arg(dir.path().join("three_blocks.msh"))
        .output()
        .unwrap();
    assert!(gmsh.status.success(), "gmsh failed: {gmsh:?}");
    let twin = std::fs::read_to_string(fixture.join("three_blocks.toml")).unwrap();
    let scene = dir.path().join("three_blocks_gmsh.toml");
    std::fs::write(&scene, mesh_scene(&twin, &fixture, "three_blocks.msh")).unwrap();

    let run = |scene: &Path, out: &Path| groutready("run", scene, out);
    let from_gmsh = run(&scene, &dir.path().join("gmsh"));
    let from_generator = run(
        &fixture.join("three_blocks.toml"),
        &dir.path().join("generator"),
    );
    // Same size of model: 96 elements, 189 thermal dofs.
    let first = |s: &str| {
        s.lines()
            .next()
            .unwrap_or("")
            .split(": ")
            .nth(1)
            .map(str::to_string)
    };
    assert_eq!(first(&from_gmsh), first(&from_generator));

    let a = apertures(&dir.path().join("gmsh/apertures.csv"));
    let b = apertures(&dir.path().join("generator/apertures.csv"));
    assert_eq!(a.len(), b.len());
    assert!(a.len() > 100, "{} aperture rows", a.len());
    let mut worst = 0.0f64;
    let mut widest = 0.0f64;
    for (key, (aperture, state)) in &b {
        let (other, other_state) = &a[key];
        assert_eq!(state, other_state, "state at {key:?}");
        worst = worst.max((aperture - other).abs());
        widest = widest.max(aperture.abs());
    }
    assert!(widest > 0.1, "the joints open: widest {widest} mm");
    // apertures.csv keeps 4 decimals (0.1 µm): equal to the last digit
    assert!(worst <= 1e-4, "largest aperture difference {worst} mm");
}

/// `groutready COMMAND SCENE --out OUT`, asserting success; its stdout.
fn groutready(command: &str, scene: &Path, out: &Path) -> String {
    let o = bin()
        .arg(command)
        .arg(scene)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// `groutready mesh SCENE --out FILE`.
fn write_mesh(scene: &Path, out: &Path) {
    groutready("mesh", scene, out);
}

/// `groutready run SCENE --out DIR`.
fn run_scene(scene: &Path, out: &Path) {
    groutready("run", scene, out);
}

/// The scene's own mesh, from its generator or its file.
fn scene_mesh(scene: &Path) -> Mesh {
    let sc = Scene::load(scene).unwrap();
    groutready::app::build_mesh(&sc, &scene.display().to_string()).unwrap()
}

/// Every field of a mesh, for an exact comparison.
fn fields(m: &Mesh) -> String {
    serde_json::to_string(m).unwrap()
}

#[test]
fn written_meshes_run_as_mesh_scenes_with_the_same_apertures() {
    let fixture = repo("tests/fixtures/three_blocks");
    let twin_path = fixture.join("three_blocks.toml");
    let twin = std::fs::read_to_string(&twin_path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_scene(&twin_path, &dir.path().join("generator"));
    let want = std::fs::read(dir.path().join("generator/apertures.csv")).unwrap();
    for ext in ["msh", "inp"] {
        let file = format!("three_blocks.{ext}");
        write_mesh(&twin_path, &dir.path().join(&file));
        let scene = dir.path().join(format!("three_blocks_{ext}.toml"));
        std::fs::write(&scene, mesh_scene(&twin, &fixture, &file)).unwrap();
        assert_eq!(
            fields(&scene_mesh(&scene)),
            fields(&scene_mesh(&twin_path)),
            "{ext}"
        );
        run_scene(&scene, &dir.path().join(ext));
        let got = std::fs::read(dir.path().join(ext).join("apertures.csv")).unwrap();
        assert!(
            got == want,
            "apertures.csv through .{ext} differs from the generator's"
        );
    }
}

#[test]
fn the_small_dam_and_the_demo_come_back_from_their_files() {
    let dir = tempfile::tempdir().unwrap();
    for model in ["models/small_dam_joints.toml", "models/demo_arch.toml"] {
        let path = repo(model);
        let text = std::fs::read_to_string(&path).unwrap();
        let schedules = Scene::load(&path).unwrap().schedules_dir(&path).unwrap();
        let generated = fields(&scene_mesh(&path));
        for ext in ["msh", "inp"] {
            let file = format!("dam.{ext}");
            write_mesh(&path, &dir.path().join(&file));
            let scene = dir.path().join(format!("dam_{ext}.toml"));
            std::fs::write(&scene, mesh_scene(&text, &schedules, &file)).unwrap();
            assert!(
                fields(&scene_mesh(&scene)) == generated,
                "{model} through .{ext}"
            );
        }
    }
}

#[test]
fn a_run_folder_of_a_mesh_scene_finds_its_file_and_sees_it_change() {
    let fixture = repo("tests/fixtures/three_blocks");
    let twin = std::fs::read_to_string(fixture.join("three_blocks.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("three_blocks.msh");
    write_mesh(&fixture.join("three_blocks.toml"), &msh);
    let scene_path = dir.path().join("scene.toml");
    std::fs::write(&scene_path, mesh_scene(&twin, &fixture, "three_blocks.msh")).unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    // As a run folder keeps it: the file is found from anywhere.
    let elsewhere = dir.path().join("run/scene.toml");
    let mesh = groutready::app::build_mesh(&scene, &elsewhere.display().to_string()).unwrap();
    assert_eq!(mesh.elements.len(), 96);
    // An edited file no longer matches the scene's digest.
    let mut bytes = std::fs::read(&msh).unwrap();
    bytes.extend_from_slice(b"\n");
    std::fs::write(&msh, bytes).unwrap();
    let err = groutready::app::build_mesh(&scene, &elsewhere.display().to_string())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("three_blocks.msh: the mesh file has changed"),
        "{err}"
    );
}
