//! The `arch_table` generator: tables sampled from the parametric arch give
//! its mesh back; every arch type's reference curve has the crown radius and
//! tangent it was given; table errors name file:line:column; the
//! Xiaowan-like scene's gross dimensions.

use std::path::{Path, PathBuf};

use groutready::app;
use groutready::mesh::arch::overhang_bump;
use groutready::mesh::arch_curves::{ArchType, HalfArch, HalfCurve};
use groutready::mesh::geometry::{ArchGeometry, Geometry};
use groutready::mesh::{generate_arch, Mesh};
use groutready::scene::Scene;

const HEADER: &str =
    "elevation_m,crown_upstream_y_m,crown_downstream_y_m,thickness_left_abutment_m,\
thickness_right_abutment_m,radius_left_m,radius_right_m";

fn demo_scene_text() -> String {
    std::fs::read_to_string("models/demo_arch.toml").unwrap()
}

/// `text` with its `[geometry]` table replaced by `geometry`.
fn with_geometry(text: &str, geometry: &str) -> String {
    let start = text.find("\n[geometry]").unwrap() + 1;
    let end = start + text[start + 1..].find("\n[").unwrap() + 2;
    format!("{}{geometry}\n{}", &text[..start], &text[end..])
}

/// The parametric arch's ring at z: (upstream radius, thickness, y of the centre).
fn ring(p: &ArchGeometry, z: f64) -> (f64, f64, f64) {
    let zeta = ((z - p.base_elevation_m) / p.height_m).clamp(0.0, 1.0);
    let r_up = p.base_radius_m + (p.crest_radius_m - p.base_radius_m) * zeta;
    let t = p.crest_thickness_m
        + (p.base_thickness_m - p.crest_thickness_m) * (1.0 - zeta).powf(p.thickness_exponent);
    (r_up, t, r_up - p.overhang_m * overhang_bump(zeta))
}

/// Writes the scene and its two tables into `dir`; returns the scene's path.
fn write_case(dir: &Path, geometry: &str, table: &str, valley: &str) -> PathBuf {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, with_geometry(&demo_scene_text(), geometry)).unwrap();
    std::fs::write(dir.join("arch.csv"), table).unwrap();
    std::fs::write(dir.join("valley.csv"), valley).unwrap();
    scene
}

/// The tables of the parametric arch `p` with `lift` m lifts: a row at every
/// layer boundary (linear interpolation is then exact at every level), the
/// centre-line radius R − t/2 and the thickness t at crown and abutments; the
/// valley at every block centre and both ends. Returns the geometry table
/// text, the arch table and the valley.
fn sampled_tables(p: &ArchGeometry, lift: f64) -> (String, String, String) {
    let n_layers = (p.height_m / lift).round() as usize;
    let mut zs: Vec<f64> = (0..n_layers)
        .map(|l| p.base_elevation_m + l as f64 * lift)
        .collect();
    zs.push(p.base_elevation_m + p.height_m);
    let mut table = format!("# sampled from the parametric arch\n{HEADER}\n");
    for &z in &zs {
        let (r_up, t, yc) = ring(p, z);
        let yu = yc - r_up;
        let rc = r_up - 0.5 * t;
        table += &format!("{z:?},{yu:?},{:?},{t:?},{t:?},{rc:?},{rc:?}\n", yu + t);
    }
    let crest = p.base_elevation_m + p.height_m;
    let (r_up, t, _) = ring(p, crest);
    let length = (r_up - 0.5 * t) * p.central_angle_deg.to_radians();
    let n = p.n_blocks as f64;
    let fs: Vec<f64> = (1..=p.n_blocks)
        .map(|b| (2.0 * b as f64 - 1.0 - n) / n)
        .collect();
    let f_min = fs.iter().fold(f64::INFINITY, |m, f| m.min(f.abs()));
    let found = |f: f64| {
        let shape = (1.0 - f.abs().powf(p.valley_exponent)) / (1.0 - f_min.powf(p.valley_exponent));
        crest - p.height_m * shape.max(p.min_block_height_fraction).min(1.0)
    };
    let mut valley = format!(
        "crest_distance_m,foundation_elevation_m\n0.0,{:?}\n",
        found(fs[0])
    );
    for &f in &fs {
        valley += &format!("{:?},{:?}\n", 0.5 * (f + 1.0) * length, found(f));
    }
    valley += &format!("{length:?},{:?}\n", found(fs[fs.len() - 1]));
    let geometry = format!(
        "[geometry]\nkind = \"arch_table\"\narch_type = \"circular\"\ntable = \"arch.csv\"\nvalley = \"valley.csv\"\n\
         base_elevation_m = {:?}\ncrest_elevation_m = {crest:?}\nn_blocks = {}\ncrest_length_m = {length:?}\n\
         crest_left_length_m = {:?}\nelements_per_block = {}\nelements_across = {}\nrock_depth_m = {:?}\n\
         rock_layers = {}\nrock_margin_m = {:?}\nrock_margin_elements = {}\n",
        p.base_elevation_m,
        p.n_blocks,
        0.5 * length,
        p.elements_per_block,
        p.elements_across,
        p.rock_depth_m,
        p.rock_layers,
        p.rock_margin_m,
        p.rock_margin_elements
    );
    (geometry, table, valley)
}

fn demo() -> (Scene, ArchGeometry) {
    let scene = Scene::load(Path::new("models/demo_arch.toml")).unwrap();
    let Geometry::Arch(p) = scene.geometry.clone() else {
        panic!("demo_arch is an arch")
    };
    (scene, p)
}

#[test]
fn tables_of_the_parametric_arch_give_its_mesh() {
    let (scene, p) = demo();
    let (lift, zone) = (scene.lifts.height_m, scene.joints.zone_height_m);
    let want = generate_arch(&p, lift, zone).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (geometry, table, valley) = sampled_tables(&p, lift);
    let path = write_case(dir.path(), &geometry, &table, &valley);
    let s = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let got = app::build_mesh(&s, "scene.toml").unwrap_or_else(|e| panic!("{e}"));
    same_mesh(&got, &want);
}

/// Same topology and classification, nodes within 1e-9 m.
fn same_mesh(got: &Mesh, want: &Mesh) {
    assert_eq!(got.nodes.len(), want.nodes.len(), "node count");
    let worst = got
        .nodes
        .iter()
        .zip(&want.nodes)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "largest node distance {worst:e} m");
    assert_eq!(got.elements, want.elements);
    assert_eq!(got.parts, want.parts);
    assert_eq!(got.thermal_dof, want.thermal_dof);
    assert_eq!(got.blocks, want.blocks);
    assert_eq!(got.layer_z, want.layer_z);
    assert_eq!(got.face_pairs, want.face_pairs);
    assert_eq!(got.zones, want.zones);
    assert_eq!(got.surfaces, want.surfaces);
    assert_eq!(got.zone_points.len(), want.zone_points.len());
    for (a, b) in got.zone_points.iter().zip(&want.zone_points) {
        assert_eq!(
            (a.joint, a.zone, a.point, a.pair),
            (b.joint, b.zone, b.point, b.pair)
        );
        assert!((0..3).all(|c| (a.xyz[c] - b.xyz[c]).abs() < 1e-9));
    }
}

/// One half-curve of every type with crown radius `r`.
fn curves(r: f64) -> Vec<HalfCurve> {
    let base = HalfArch {
        radius_m: r,
        ..HalfArch::default()
    };
    let with = |kind, arch| HalfCurve { kind, arch };
    vec![
        with(ArchType::Circular, base),
        with(
            ArchType::ThreeCentred,
            HalfArch {
                outer_radius_m: 2.5 * r,
                central_half_angle: 0.3,
                ..base
            },
        ),
        with(ArchType::Parabolic, base),
        with(
            ArchType::Elliptical,
            HalfArch {
                axis_ratio: 1.7,
                ..base
            },
        ),
        with(
            ArchType::LogSpiral,
            HalfArch {
                spiral_growth: 0.8,
                ..base
            },
        ),
    ]
}

#[test]
fn every_arch_type_has_its_crown_radius_and_tangent() {
    let r = 237.0;
    for c in curves(r) {
        let name = c.kind.name();
        assert_eq!(c.point(0.0), [0.0, 0.0], "{name} passes through the crown");
        // central differences in φ across the crown (each closed form is analytic there)
        let h = 1e-3;
        let (m, p) = (c.point(-h), c.point(h));
        let dx = (p[0] - m[0]) / (2.0 * h);
        let dy = (p[1] - m[1]) / (2.0 * h);
        let ddx = (p[0] + m[0]) / (h * h);
        let ddy = (p[1] + m[1]) / (h * h);
        let kappa = (dx * ddy - dy * ddx) / (dx * dx + dy * dy).powf(1.5);
        assert!(
            (kappa * r - 1.0).abs() < 1e-6,
            "{name}: crown curvature {kappa} against 1/R = {}",
            1.0 / r
        );
        // φ is the tangent angle and s the arc length, along the whole half
        let phi_end = 1.2;
        let n = 20_000;
        let mut chords = 0.0;
        for i in 0..n {
            let (a, b) = (
                c.point(phi_end * i as f64 / n as f64),
                c.point(phi_end * (i + 1) as f64 / n as f64),
            );
            chords += (b[0] - a[0]).hypot(b[1] - a[1]);
        }
        let s = c.arc_length(phi_end);
        assert!(
            (chords / s - 1.0).abs() < 1e-6,
            "{name}: s = {s}, chords {chords}"
        );
        let back = c.angle_at_length(s).unwrap();
        assert!((back - phi_end).abs() < 1e-12, "{name}: angle at s {back}");
        // at φ = 0: tangent to x at the crown
        for phi in [0.0, 0.2, 0.5, 1.0] {
            let (a, b) = (c.point(phi - 1e-6), c.point(phi + 1e-6));
            let dir = (b[1] - a[1]).atan2(b[0] - a[0]);
            assert!(
                (dir - phi).abs() < 1e-8,
                "{name}: tangent at φ = {phi} points at {dir}"
            );
        }
    }
}

/// A circular arch 60 m high on 12 m zones: the error cases' base.
fn small_case(table: &str, valley: &str) -> Result<Scene, String> {
    let dir = tempfile::tempdir().unwrap();
    let geometry = "[geometry]\nkind = \"arch_table\"\narch_type = \"circular\"\ntable = \"arch.csv\"\n\
        valley = \"valley.csv\"\nbase_elevation_m = 0.0\ncrest_elevation_m = 60.0\nn_blocks = 4\n\
        crest_length_m = 120.0\ncrest_left_length_m = 60.0\nelements_per_block = 1\nelements_across = 2\n\
        rock_depth_m = 20.0\nrock_margin_m = 20.0\n";
    let path = write_case(dir.path(), geometry, table, valley);
    Scene::load(&path).map_err(|e| {
        e.to_string()
            .replace(&dir.path().display().to_string(), "DIR")
    })
}

const VALLEY: &str = "crest_distance_m,foundation_elevation_m\n0,40\n60,0\n120,40\n";

fn table(rows: &[&str]) -> String {
    format!("# design table\n{HEADER}\n{}\n", rows.join("\n"))
}

#[test]
fn a_good_small_table_meshes() {
    let s = small_case(
        &table(&["0,0,10,10,10,80,80", "60,0,4,6,6,100,100"]),
        VALLEY,
    )
    .unwrap();
    let m = app::build_mesh(&s, "x").unwrap();
    assert_eq!(m.blocks.len(), 4);
    // founded at the valley at the block centres (15, 45, 75, 105 m along: 30, 10, 10, 30 m), rounded down to 9 m zones
    let found: Vec<f64> = m.blocks.iter().map(|b| b.foundation_z).collect();
    assert_eq!(found, vec![27.0, 9.0, 9.0, 27.0]);
}

#[test]
fn table_errors_name_file_line_and_column() {
    let cases: [(&str, String, &str); 6] = [
        (
            "elevations go up",
            table(&["0,0,10,10,10,80,80", "30,0,8,10,10,90,90", "30,0,6,6,6,100,100", "60,0,4,6,6,100,100"]),
            "DIR/arch.csv:5:1: elevation 30 m is not above the previous row's 30 m (line 4): rows go up",
        ),
        (
            "thickness > 0",
            table(&["0,0,10,10,10,80,80", "60,0,4,6,-1,100,100"]),
            "DIR/arch.csv:4:5 (thickness_right_abutment_m): expected a thickness > 0 m, found \"-1\"",
        ),
        (
            "radius > 0",
            table(&["0,0,10,10,10,0,80", "60,0,4,6,6,100,100"]),
            "DIR/arch.csv:3:6 (radius_left_m): expected a radius > 0 m, found \"0\"",
        ),
        (
            "covers the crest",
            table(&["0,0,10,10,10,80,80", "50,0,4,6,6,100,100"]),
            "DIR/arch.csv:4:1: the table ends at 50 m, below the crest (geometry.crest_elevation_m = 60 m): the rows must cover base..crest",
        ),
        (
            "crown thickness",
            table(&["0,0,10,10,10,80,80", "60,5,4,6,6,100,100"]),
            "DIR/arch.csv:4:3 (crown_downstream_y_m): expected a y [m] downstream of the upstream face's 5 m (the crown thickness y_d − y_u must be > 0), found \"4\"",
        ),
        (
            "another type's coefficient",
            format!("{HEADER},axis_ratio_left\n0,0,10,10,10,80,80,\n60,0,4,6,6,100,100,1.5\n"),
            "DIR/arch.csv:3:8 (axis_ratio_left): blank (a coefficient of another arch type; the scene's arch_type is circular), found \"1.5\"",
        ),
    ];
    for (what, t, want) in cases {
        let got = small_case(&t, VALLEY).unwrap_err();
        assert_eq!(got, want, "{what}");
    }
    let ok = table(&["0,0,10,10,10,80,80", "60,0,4,6,6,100,100"]);
    let got = small_case(
        &ok,
        "crest_distance_m,foundation_elevation_m\n0,40\n60,-3\n100,40\n",
    )
    .unwrap_err();
    assert_eq!(
        got,
        "DIR/valley.csv:3:2 (foundation_elevation_m): expected an elevation within the dam, 0 to 60 m (geometry.base_elevation_m, crest_elevation_m), found \"-3\""
    );
    let got = small_case(
        &ok,
        "crest_distance_m,foundation_elevation_m\n0,40\n60,0\n100,40\n",
    )
    .unwrap_err();
    assert_eq!(
        got,
        "DIR/valley.csv:4:1: the valley ends at 100 m along the crest, before its right end (geometry.crest_length_m = 120 m)"
    );
    let got = small_case(&ok.replace("radius_right_m", "radius_rigth_m"), VALLEY).unwrap_err();
    assert!(
        got.starts_with("DIR/arch.csv:2: expected the columns"),
        "{got}"
    );
    assert!(
        got.ends_with("(unknown column \"radius_rigth_m\")"),
        "{got}"
    );
}

#[test]
fn xiaowan_like_has_the_published_gross_dimensions() {
    let path = Path::new("models/xiaowan_like.toml");
    let inputs = app::load_inputs(path, None).unwrap_or_else(|e| panic!("{e}"));
    let m = &inputs.mesh;
    let Geometry::ArchTable(g) = &inputs.scene.geometry else {
        panic!("xiaowan_like is an arch_table scene")
    };
    assert_eq!(m.blocks.len(), 43);
    assert_eq!(m.joint_count(), 42);
    assert_eq!(m.n_zones(), 27);
    assert_eq!(m.layer_z[0], 953.0);
    assert_eq!(m.crest_z, 1245.0);
    assert_eq!(g.crest_length_m, 900.0);
    let tables = g.tables.as_ref().unwrap();
    let crown = |z: f64| {
        let r = tables.row_at(z);
        r.crown_downstream_y_m - r.crown_upstream_y_m
    };
    assert_eq!(crown(1245.0), 13.0);
    assert!((crown(953.0) - 70.0).abs() < 3.0);
    // the deepest block reaches the base
    assert_eq!(m.blocks.iter().map(|b| b.base_layer).min(), Some(0));
}

#[test]
fn every_arch_type_meshes_with_its_faces_at_the_crown_and_abutment() {
    let types: [(&str, &str, &str); 5] = [
        ("circular", "", ""),
        (
            "three_centred",
            ",outer_radius_left_m,outer_radius_right_m,central_half_angle_left_deg,central_half_angle_right_deg",
            ",150,160,15,20",
        ),
        ("parabolic", "", ""),
        ("elliptical", ",axis_ratio_left,axis_ratio_right", ",1.5,1.3"),
        ("log_spiral", ",spiral_growth_left,spiral_growth_right", ",0.3,0.2"),
    ];
    for (name, cols, coefs) in types {
        let dir = tempfile::tempdir().unwrap();
        let geometry = format!(
            "[geometry]\nkind = \"arch_table\"\narch_type = \"{name}\"\ntable = \"arch.csv\"\n\
             valley = \"valley.csv\"\nbase_elevation_m = 0.0\ncrest_elevation_m = 60.0\nn_blocks = 4\n\
             crest_length_m = 120.0\ncrest_left_length_m = 60.0\nelements_per_block = 2\nelements_across = 2\n\
             rock_depth_m = 20.0\nrock_margin_m = 20.0\n"
        );
        let table =
            format!("{HEADER}{cols}\n0,0,10,10,10,80,80{coefs}\n60,0,4,6,6,100,100{coefs}\n");
        let path = write_case(dir.path(), &geometry, &table, VALLEY);
        let s = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let m = app::build_mesh(&s, "x").unwrap_or_else(|e| panic!("{name}: {e}"));
        let Geometry::ArchTable(g) = &s.geometry else {
            unreachable!()
        };
        let row = g.tables.as_ref().unwrap().row_at(60.0);
        let has = |p: [f64; 2]| {
            m.nodes
                .iter()
                .any(|n| n[2] == 60.0 && (n[0] - p[0]).abs() < 1e-9 && (n[1] - p[1]).abs() < 1e-9)
        };
        // the crown's faces are the table's (a joint lies at the crown, 60 m along)
        assert!(has([0.0, 0.0]) && has([0.0, 4.0]), "{name}: crown faces");
        // at the left abutment the faces are T_A = 6 m apart along the normal
        let kind = g.arch_type;
        let left = HalfCurve {
            kind,
            arch: row.left,
        };
        let phi = left.angle_at_length(60.0).unwrap();
        let p = left.point(phi);
        let (c, n) = ([-p[0], 2.0 + p[1]], [-phi.sin(), -phi.cos()]);
        let up = [c[0] + 3.0 * n[0], c[1] + 3.0 * n[1]];
        let down = [c[0] - 3.0 * n[0], c[1] - 3.0 * n[1]];
        assert!(
            has(up) && has(down),
            "{name}: abutment faces {up:?} {down:?}"
        );
    }
}
