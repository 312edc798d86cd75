//! Malformed scenes give exact, located error messages; the shipped models load.

use std::path::{Path, PathBuf};

use groutready::scene::{Effect, Scene, SceneError};

const ORIGIN: &str = "models/x.toml";

/// A small valid scene; each test breaks one thing in it.
const BASE: &str = r#"name = "Test dam"
epoch = 2024-01-01
effects = ["hydration", "pipe_cooling", "ambient"]

[geometry]
kind = "blocks"
n_blocks = 2
block_length_m = 20.0
thickness_m = 10.0
n_lifts = 6
elements_per_block = 2
elements_across = 2

[lifts]
height_m = 3.0

[joints]
zone_height_m = 9.0

[concrete]
density_kg_m3 = 2400.0
specific_heat_j_kgk = 950.0
conductivity_w_mk = 2.2

[concrete.adiabatic]
form = "exponential"
theta0 = 24.0
m = 0.35

[pipes]
spacing_horizontal_m = 1.5
spacing_vertical_m = 1.5
length_m = 250.0
flow_l_per_min = 18.0
outer_radius_m = 0.016
inner_radius_m = 0.014
wall_conductivity_w_mk = 1.66

[air]
mean_c = 17.5
amplitude_c = 7.0
warmest_day_of_year = 200.0
film_w_m2k = 15.0
"#;

/// A small valid arch scene.
const ARCH: &str = r#"name = "Arch"
epoch = "2024-01-01"
effects = ["hydration"]

[geometry]
kind = "arch"
n_blocks = 4
height_m = 30.0
crest_radius_m = 100.0
base_radius_m = 60.0
central_angle_deg = 90.0
crest_thickness_m = 5.0
base_thickness_m = 12.0
elements_per_block = 1
elements_across = 2
rock_depth_m = 0.0
rock_margin_m = 0.0

[lifts]
height_m = 3.0

[joints]
zone_height_m = 9.0

[concrete]
density_kg_m3 = 2400.0
specific_heat_j_kgk = 950.0
conductivity_w_mk = 2.2
adiabatic = { form = "compound", theta0 = 25.0, a = 0.4, b = 0.85 }
"#;

fn replaced(base: &str, from: &str, to: &str) -> String {
    assert!(
        base.contains(from),
        "test bug: {from:?} not in the base scene"
    );
    base.replacen(from, to, 1)
}

fn err(text: &str) -> String {
    match Scene::from_toml_str(text, ORIGIN) {
        Ok(_) => panic!("scene unexpectedly valid:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn base_scenes_are_valid() {
    let s = Scene::from_toml_str(BASE, ORIGIN).expect("BASE");
    assert!(s.has(Effect::PipeCooling));
    assert!(!s.has(Effect::ReservoirTemperature));
    assert!(s.any_thermal());
    assert_eq!(s.lifts_per_zone(), 3);
    let a = s.concrete_diffusivity_m2_per_day();
    assert!((a - 2.2 * 86400.0 / (2400.0 * 950.0)).abs() < 1e-15);
    assert_eq!(s.concrete_conductivity_j_per_m_day_k(), 2.2 * 86400.0);
    Scene::from_toml_str(ARCH, ORIGIN).expect("ARCH");
}

#[test]
fn unknown_key() {
    let text = replaced(BASE, "conductivity_w_mk = 2.2", "conductivty = 2.2");
    assert_eq!(
        err(&text),
        "models/x.toml:23:1: unknown key `conductivty` in [concrete], expected one of \
         `density_kg_m3`, `specific_heat_j_kgk`, `conductivity_w_mk`, `adiabatic`, `modulus`, `poisson`, `expansion_per_c`, `creep`, `autogenous`, `placement_on_shared_nodes`"
    );
}

#[test]
fn unknown_key_in_geometry_is_located() {
    let text = replaced(BASE, "thickness_m = 10.0", "thicknes_m = 10.0");
    // The list of expected keys belongs to mesh::geometry; check up to it.
    let e = err(&text);
    let head =
        "models/x.toml:9:1: unknown key `thicknes_m` in [geometry], expected one of `n_blocks`, ";
    assert!(e.starts_with(head), "{e}");
}

#[test]
fn misspelled_effect() {
    let text = replaced(BASE, "\"ambient\"]", "\"ambiant\"]");
    assert_eq!(err(&text), "models/x.toml:3:41: effects: unknown variant `ambiant`, expected one of `hydration`, `pipe_cooling`, `ambient`, `reservoir_temperature`, `thermal_strain`, `self_weight`, `creep`, `autogenous`, `reservoir_load`, `joints`");
}

#[test]
fn missing_concrete_table() {
    let start = BASE.find("[concrete]").unwrap();
    let end = BASE.find("[pipes]").unwrap();
    let text = format!("{}{}", &BASE[..start], &BASE[end..]);
    assert_eq!(err(&text), "models/x.toml: missing table [concrete]");
}

#[test]
fn missing_key_in_table() {
    let text = replaced(BASE, "specific_heat_j_kgk = 950.0\n", "");
    assert_eq!(
        err(&text),
        "models/x.toml:20:1: missing key `specific_heat_j_kgk` in [concrete]"
    );
}

#[test]
fn negative_conductivity() {
    let text = replaced(BASE, "conductivity_w_mk = 2.2", "conductivity_w_mk = -2.1");
    assert_eq!(
        err(&text),
        "models/x.toml:23:21: concrete.conductivity_w_mk must be > 0, got -2.1"
    );
}

#[test]
fn zero_density() {
    let text = replaced(BASE, "density_kg_m3 = 2400.0", "density_kg_m3 = 0.0");
    assert_eq!(
        err(&text),
        "models/x.toml:21:17: concrete.density_kg_m3 must be > 0, got 0"
    );
}

#[test]
fn zone_not_whole_lifts() {
    let text = replaced(BASE, "zone_height_m = 9.0", "zone_height_m = 10");
    assert_eq!(
        err(&text),
        "models/x.toml:18:17: joints.zone_height_m = 10 is not a whole number of lifts (lifts.height_m = 3)"
    );
}

#[test]
fn hydration_without_adiabatic() {
    let text = replaced(
        BASE,
        "[concrete.adiabatic]\nform = \"exponential\"\ntheta0 = 24.0\nm = 0.35\n",
        "",
    );
    assert_eq!(
        err(&text),
        "models/x.toml:20:2: effect `hydration` needs a [concrete.adiabatic] table, which is missing"
    );
}

#[test]
fn pipe_cooling_without_pipes() {
    let start = BASE.find("[pipes]").unwrap();
    let end = BASE.find("[air]").unwrap();
    let text = format!("{}{}", &BASE[..start], &BASE[end..]);
    assert_eq!(
        err(&text),
        "models/x.toml: effect `pipe_cooling` needs a [pipes] table, which is missing"
    );
}

#[test]
fn inner_radius_not_below_outer() {
    let text = replaced(BASE, "inner_radius_m = 0.014", "inner_radius_m = 0.016");
    assert_eq!(
        err(&text),
        "models/x.toml:36:18: pipes.inner_radius_m = 0.016 must be < pipes.outer_radius_m = 0.016"
    );
}

#[test]
fn theta_out_of_range() {
    let text = format!("{BASE}\n[time]\ntheta = 0.4\n");
    assert_eq!(
        err(&text),
        "models/x.toml:46:9: time.theta must be in [0.5, 1], got 0.4"
    );
}

#[test]
fn mechanics_step_out_of_range() {
    for bad in [0, 31] {
        let text = format!("{BASE}\n[time]\nmechanics_max_step_days = {bad}\n");
        assert_eq!(
            err(&text),
            format!("models/x.toml:46:27: time.mechanics_max_step_days must be a whole number of days in 1..=30, got {bad}")
        );
    }
    let text = format!("{BASE}\n[time]\nmechanics_max_step_days = 2.5\n");
    assert!(
        err(&text).contains("mechanics_max_step_days"),
        "{}",
        err(&text)
    );
}

#[test]
fn search_step_out_of_range() {
    for bad in [0, 31] {
        let text = format!("{BASE}\n[planner]\nsearch_max_step_days = {bad}\n");
        assert_eq!(
            err(&text),
            format!("models/x.toml:46:24: planner.search_max_step_days must be a whole number of days in 1..=30, got {bad}")
        );
    }
}

#[test]
fn merged_pours_and_groutings_need_longer_mechanical_steps() {
    for (key, what, column) in [
        ("mechanics_merge_pours", "pours", 25),
        ("mechanics_merge_groutings", "groutings", 29),
    ] {
        let text = format!("{BASE}\n[time]\n{key} = true\n");
        assert_eq!(
            err(&text),
            format!(
                "models/x.toml:46:{column}: time.{key} merges {what} into mechanical steps of \
                 several days: it needs time.mechanics_max_step_days above 1"
            )
        );
        let text = format!("{BASE}\n[time]\nmechanics_max_step_days = 2\n{key} = true\n");
        let scene = Scene::from_toml_str(&text, ORIGIN).expect("merged with 2-day steps");
        let merged = [
            scene.time.mechanics_merge_pours,
            scene.time.mechanics_merge_groutings,
        ];
        assert_eq!(merged.iter().filter(|&&m| m).count(), 1, "{key}");
    }
}

#[test]
fn bad_epoch_string() {
    let text = replaced(BASE, "epoch = 2024-01-01", "epoch = \"2024-13-01\"");
    assert_eq!(
        err(&text),
        "models/x.toml:2:9: epoch: expected a date YYYY-MM-DD, found \"2024-13-01\""
    );
}

#[test]
fn bad_epoch_bare_date() {
    let text = replaced(BASE, "epoch = 2024-01-01", "epoch = 2024-02-30");
    assert_eq!(
        err(&text),
        "models/x.toml:2:9: invalid date, expected day between 01 and 29"
    );
}

#[test]
fn arch_base_radius_above_crest() {
    let text = replaced(ARCH, "base_radius_m = 60.0", "base_radius_m = 120.0");
    assert_eq!(
        err(&text),
        "models/x.toml:10:17: geometry.base_radius_m = 120 must be <= geometry.crest_radius_m = 100"
    );
}

#[test]
fn duplicate_effect() {
    let text = replaced(BASE, "\"ambient\"]", "\"ambient\", \"hydration\"]");
    assert_eq!(
        err(&text),
        "models/x.toml:3:11: effects lists `hydration` more than once"
    );
}

#[test]
fn geometry_wrong_type_is_located() {
    let text = replaced(BASE, "n_blocks = 2", "n_blocks = -2");
    assert_eq!(
        err(&text),
        "models/x.toml:7:12: geometry.n_blocks: invalid value: integer `-2`, expected u32"
    );
}

#[test]
fn wrong_value_type() {
    let text = replaced(BASE, "mean_c = 17.5", "mean_c = \"warm\"");
    assert_eq!(
        err(&text),
        "models/x.toml:40:10: air.mean_c: invalid type: string \"warm\", expected f64"
    );
}

#[test]
fn unknown_geometry_kind() {
    let text = replaced(BASE, "kind = \"blocks\"", "kind = \"gravity\"");
    assert_eq!(
        err(&text),
        "models/x.toml:6:8: geometry.kind: unknown variant `gravity`, expected one of `blocks`, `arch`, `arch_table`, `mesh`"
    );
}

#[test]
fn toml_syntax_error() {
    let text = replaced(BASE, "height_m = 3.0", "height_m = 3.0.0");
    assert_eq!(
        err(&text),
        "models/x.toml:15:15: invalid float, expected nothing"
    );
}

#[test]
fn rock_depth_without_rock() {
    let text = replaced(
        BASE,
        "elements_across = 2",
        "elements_across = 2\nrock_depth_m = 10.0",
    );
    assert_eq!(
        err(&text),
        "models/x.toml: geometry.rock_depth_m = 10 needs a [rock] table, which is missing"
    );
}

#[test]
fn snapshot_before_epoch() {
    let text = format!("{BASE}\n[output]\nsnapshots = [2024-06-01, 2023-12-31]\n");
    assert_eq!(
        err(&text),
        "models/x.toml:46:13: output.snapshots: 2023-12-31 is before epoch 2024-01-01"
    );
}

#[test]
fn arch_height_not_whole_lifts() {
    let text = replaced(ARCH, "height_m = 30.0", "height_m = 31.0");
    assert_eq!(
        err(&text),
        "models/x.toml:8:12: geometry.height_m = 31 is not a whole number of lifts (lifts.height_m = 3)"
    );
}

#[test]
fn validate_without_origin() {
    let mut s = Scene::from_toml_str(BASE, ORIGIN).unwrap();
    s.lifts.height_m = f64::NAN;
    let e = s.validate().unwrap_err();
    assert_eq!(e.key(), Some("lifts.height_m"));
    assert_eq!(
        e.to_string(),
        "lifts.height_m must be a finite number, got NaN"
    );
}

#[test]
fn missing_file() {
    let e = Scene::load(Path::new("models/does_not_exist.toml")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert!(e
        .to_string()
        .starts_with("models/does_not_exist.toml: cannot read the scene file: "));
}

fn model(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models")
        .join(name)
}

#[test]
fn shipped_models_load() {
    for name in [
        "demo_arch.toml",
        "xiaowan_like.toml",
        "two_blocks.toml",
        "small_dam.toml",
    ] {
        let path = model(name);
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let dir = scene.schedules_dir(&path).expect("schedules set");
        let stem = name.trim_end_matches(".toml");
        assert_eq!(
            dir,
            model("").join("../schedules").join(stem),
            "{name}: schedules folder"
        );
    }
}

#[test]
fn mechanical_effect_without_modulus() {
    let text = replaced(
        BASE,
        "effects = [\"hydration\", \"pipe_cooling\", \"ambient\"]",
        "effects = [\"hydration\", \"self_weight\"]",
    );
    assert_eq!(
        err(&text),
        "models/x.toml:20:2: effect `self_weight` needs concrete.modulus, which is missing"
    );
}

#[test]
fn thermal_strain_without_expansion() {
    let text = replaced(
        BASE,
        "effects = [\"hydration\", \"pipe_cooling\", \"ambient\"]",
        "effects = [\"hydration\", \"thermal_strain\"]",
    )
    .replace(
        "conductivity_w_mk = 2.2",
        "conductivity_w_mk = 2.2\nmodulus = { e0_pa = 3.0e10, a = 0.4, b = 0.34 }\npoisson = 0.2",
    );
    assert_eq!(
        err(&text),
        "models/x.toml:20:2: effect `thermal_strain` needs concrete.expansion_per_c, which is missing"
    );
}

#[test]
fn poisson_ratio_out_of_range() {
    let text = replaced(
        BASE,
        "effects = [\"hydration\", \"pipe_cooling\", \"ambient\"]",
        "effects = [\"hydration\", \"self_weight\"]",
    )
    .replace(
        "conductivity_w_mk = 2.2",
        "conductivity_w_mk = 2.2\nmodulus = { e0_pa = 3.0e10, a = 0.4, b = 0.34 }\npoisson = 0.5",
    );
    assert_eq!(
        err(&text),
        "models/x.toml:25:11: concrete.poisson must be in [0, 0.5), got 0.5"
    );
}

#[test]
fn grout_stop_inset_must_be_a_distance() {
    for (value, found) in [("-0.5", "-0.5"), ("nan", "NaN")] {
        let text = replaced(
            BASE,
            "zone_height_m = 9.0",
            &format!("zone_height_m = 9.0\ngrout_stop_inset_m = {value}"),
        );
        let e = err(&text);
        assert!(
            e.contains("joints.grout_stop_inset_m") && e.contains(found),
            "{e}"
        );
    }
}

#[test]
fn rock_coarsening_must_be_at_least_one() {
    let text = format!("{BASE}\n[solver]\nrock_coarsening = 0\n");
    assert_eq!(
        err(&text),
        "models/x.toml:46:19: solver.rock_coarsening must be >= 1 (1: the mesh's rock), got 0"
    );
}
