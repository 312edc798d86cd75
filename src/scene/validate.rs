//! Value and consistency checks of a parsed scene. Every error names the
//! dotted key it is about, e.g. `concrete.conductivity_w_mk must be > 0, got -2.1`.

use crate::material::{AdiabaticRise, PipeLayout};
use crate::mesh::arch_table::ArchTableGeometry;
use crate::mesh::geometry::{ArchGeometry, BlocksGeometry, Geometry};
use crate::vocab::Invalid;

use super::{
    Air, Effect, JointSettings, Reservoir, Rock, Scene, SceneError, ThermalProperties, TimeStepping,
};

type Check = Result<(), SceneError>;

/// Relative tolerance of "a whole number of lifts".
const WHOLE_TOL: f64 = 1e-9;

/// Every check of a parsed scene, table by table; the first failure is the
/// error (the order decides which of several problems a user sees first).
pub(super) fn validate(s: &Scene) -> Check {
    names(s)?;
    lifts_and_zones(s)?;
    mechanical(s)?;
    joints(&s.joints)?;
    concrete(s)?;
    optional_tables(s)?;
    match &s.geometry {
        Geometry::Blocks(g) => blocks(g, s)?,
        Geometry::Arch(g) => arch(g, s)?,
        Geometry::ArchTable(g) => arch_table(g, s)?,
        // The file's blocks, rock and layers are checked when it is read (mesh::import::dam).
        Geometry::Mesh(g) => {
            if g.file.trim().is_empty() {
                return Err(SceneError::invalid(
                    "geometry.file",
                    "geometry.file must name a mesh file".to_string(),
                ));
            }
        }
    }
    time(&s.time, s)?;
    boundary(s)?;
    if let Err(Invalid { key, message }) = s.solver.validate() {
        return Err(SceneError::invalid(&key, message));
    }
    if let Err(Invalid { key, message }) = s.planner.validate() {
        return Err(SceneError::invalid(&key, message));
    }
    for d in &s.output.snapshots {
        if *d < s.epoch.0 {
            return Err(SceneError::invalid(
                "output.snapshots",
                format!("output.snapshots: {d} is before epoch {}", s.epoch),
            ));
        }
    }
    Ok(())
}

/// A name, and no effect listed twice.
fn names(s: &Scene) -> Check {
    if s.name.trim().is_empty() {
        return Err(SceneError::invalid("name", "name must not be empty"));
    }
    for (i, e) in s.effects.iter().enumerate() {
        if s.effects[..i].contains(e) {
            return Err(SceneError::invalid(
                "effects",
                format!("effects lists `{e}` more than once"),
            ));
        }
    }
    Ok(())
}

/// Lift and zone heights, a zone being a whole number of lifts.
fn lifts_and_zones(s: &Scene) -> Check {
    positive("lifts.height_m", s.lifts.height_m)?;
    positive("joints.zone_height_m", s.joints.zone_height_m)?;
    if whole_multiple(s.joints.zone_height_m, s.lifts.height_m).is_none() {
        return Err(SceneError::invalid(
            "joints.zone_height_m",
            format!(
                "joints.zone_height_m = {} is not a whole number of lifts (lifts.height_m = {})",
                s.joints.zone_height_m, s.lifts.height_m
            ),
        ));
    }
    Ok(())
}

/// Friction, initial gap, grout layer and grout stops of the joints.
fn joints(j: &JointSettings) -> Check {
    if !(j.mu_static.is_finite() && j.mu_static >= 0.0) {
        return Err(SceneError::invalid(
            "joints.mu_static",
            format!("joints.mu_static must be >= 0, got {}", j.mu_static),
        ));
    }
    if !(j.mu_kinetic.is_finite() && j.mu_kinetic >= 0.0 && j.mu_kinetic <= j.mu_static) {
        return Err(SceneError::invalid(
            "joints.mu_kinetic",
            format!(
                "joints.mu_kinetic = {} must be in [0, joints.mu_static = {}]",
                j.mu_kinetic, j.mu_static
            ),
        ));
    }
    if !(j.initial_gap_m.is_finite() && j.initial_gap_m >= 0.0) {
        return Err(SceneError::invalid(
            "joints.initial_gap_m",
            format!("joints.initial_gap_m must be >= 0, got {}", j.initial_gap_m),
        ));
    }
    positive("joints.grout_modulus_pa", j.grout_modulus_pa)?;
    positive("joints.grout_shear_modulus_pa", j.grout_shear_modulus_pa)?;
    positive("joints.grout_min_thickness_m", j.grout_min_thickness_m)?;
    positive("joints.bond_strength_pa", j.bond_strength_pa)?;
    match j.grout_stop_inset_m {
        Some(inset) => non_negative("joints.grout_stop_inset_m", inset),
        None => Ok(()),
    }
}

/// The concrete's thermal properties and adiabatic rise (required by
/// `hydration`).
fn concrete(s: &Scene) -> Check {
    let c = &s.concrete;
    thermal_properties("concrete", c)?;
    if let Some(rise) = &c.adiabatic {
        adiabatic("concrete.adiabatic", rise)?;
    }
    needs_table(
        s,
        Effect::Hydration,
        c.adiabatic.is_some(),
        "concrete.adiabatic",
    )
}

/// ρ, c and λ of `[table]`, each > 0.
fn thermal_properties(table: &str, m: &impl ThermalProperties) -> Check {
    positive(&format!("{table}.density_kg_m3"), m.density_kg_m3())?;
    positive(
        &format!("{table}.specific_heat_j_kgk"),
        m.specific_heat_j_kgk(),
    )?;
    positive(&format!("{table}.conductivity_w_mk"), m.conductivity_w_mk())
}

/// Optional tables: checked whenever present, required by their effects.
fn optional_tables(s: &Scene) -> Check {
    if let Some(rock) = &s.rock {
        rock_table(rock)?;
    }
    if let Some(p) = &s.pipes {
        pipes("pipes", p)?;
        // Zhu's fit of k(ξ), s(ξ) only holds for moderate ξ; the material
        // module knows the range and the layout rules.
        let (a, lambda) = (
            s.concrete_diffusivity_m2_per_day(),
            s.concrete.conductivity_w_mk,
        );
        if a.is_finite() && a > 0.0 && lambda > 0.0 {
            if let Err(message) = crate::material::ZhuPipe::try_new(p, a, lambda) {
                return Err(SceneError::invalid("pipes", format!("pipes: {message}")));
            }
        }
    }
    needs_table(s, Effect::PipeCooling, s.pipes.is_some(), "pipes")?;
    if let Some(a) = &s.air {
        air(a)?;
    }
    needs_table(s, Effect::Ambient, s.air.is_some(), "air")?;
    if let Some(r) = &s.reservoir {
        reservoir(r)?;
    }
    needs_table(
        s,
        Effect::ReservoirTemperature,
        s.reservoir.is_some(),
        "reservoir",
    )
}

/// `effect needs a [table] table, which is missing` when `effect` is on and
/// its table is not there.
fn needs_table(s: &Scene, effect: Effect, present: bool, table: &str) -> Check {
    if s.has(effect) && !present {
        return Err(SceneError::invalid(
            table,
            format!("effect `{effect}` needs a [{table}] table, which is missing"),
        ));
    }
    Ok(())
}

/// The step ladder and θ, and an end date after the epoch.
fn time(t: &TimeStepping, s: &Scene) -> Check {
    positive("time.first_step_days", t.first_step_days)?;
    finite("time.growth", t.growth)?;
    if t.growth < 1.0 {
        return Err(SceneError::invalid(
            "time.growth",
            format!("time.growth must be >= 1, got {}", t.growth),
        ));
    }
    finite("time.max_step_days", t.max_step_days)?;
    if t.max_step_days < t.first_step_days {
        return Err(SceneError::invalid(
            "time.max_step_days",
            format!(
                "time.max_step_days = {} must be >= time.first_step_days = {}",
                t.max_step_days, t.first_step_days
            ),
        ));
    }
    step_schedule(t)?;
    if !(1..=30).contains(&t.mechanics_max_step_days) {
        return Err(SceneError::invalid(
            "time.mechanics_max_step_days",
            format!(
                "time.mechanics_max_step_days must be a whole number of days in 1..=30, got {}",
                t.mechanics_max_step_days
            ),
        ));
    }
    if t.mechanics_merge_pours && t.mechanics_max_step_days == 1 {
        return Err(SceneError::invalid(
            "time.mechanics_merge_pours",
            "time.mechanics_merge_pours merges pours into mechanical steps of several days: \
             it needs time.mechanics_max_step_days above 1",
        ));
    }
    if t.mechanics_merge_groutings && t.mechanics_max_step_days == 1 {
        return Err(SceneError::invalid(
            "time.mechanics_merge_groutings",
            "time.mechanics_merge_groutings merges groutings into mechanical steps of several days: \
             it needs time.mechanics_max_step_days above 1",
        ));
    }
    if !(0.5..=1.0).contains(&t.theta) {
        return Err(SceneError::invalid(
            "time.theta",
            format!("time.theta must be in [0.5, 1], got {}", t.theta),
        ));
    }
    if let Some(end) = t.end_date {
        if end <= s.epoch.0 {
            return Err(SceneError::invalid(
                "time.end_date",
                format!("time.end_date = {end} must be after epoch {}", s.epoch),
            ));
        }
    }
    Ok(())
}

/// Positive steps, each rate ending after the one before it.
fn step_schedule(t: &TimeStepping) -> Check {
    let mut last = 0.0;
    for (i, r) in t.step_schedule.iter().enumerate() {
        let ok = r.step_days.is_finite()
            && r.step_days > 0.0
            && r.until_days.is_finite()
            && r.until_days > last;
        if !ok {
            return Err(SceneError::invalid(
                "time.step_schedule",
                format!(
                    "time.step_schedule entry {}: expected step_days > 0 and until_days > {last} (the entry before ends there), got step_days = {}, until_days = {}",
                    i + 1,
                    r.step_days,
                    r.until_days
                ),
            ));
        }
        last = r.until_days;
    }
    Ok(())
}

/// `n` if `total` = n·`unit` for a whole n ≥ 1 (relative tolerance 1e-9).
fn whole_multiple(total: f64, unit: f64) -> Option<u64> {
    let n = (total / unit).round();
    if !n.is_finite() || n < 1.0 {
        return None;
    }
    if (total - n * unit).abs() <= WHOLE_TOL * total.abs() {
        Some(n as u64)
    } else {
        None
    }
}

fn finite(key: &str, v: f64) -> Check {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{key} must be a finite number, got {v}"),
        ))
    }
}

fn positive(key: &str, v: f64) -> Check {
    finite(key, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{key} must be > 0, got {v}"),
        ))
    }
}

fn non_negative(key: &str, v: f64) -> Check {
    finite(key, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{key} must be >= 0, got {v}"),
        ))
    }
}

fn at_least_one(key: &str, v: u32) -> Check {
    if v >= 1 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{key} must be >= 1, got {v}"),
        ))
    }
}

/// `lo < v < hi` when `closed_hi` is false, `lo < v <= hi` otherwise.
fn in_range(key: &str, v: f64, lo: f64, hi: f64, closed_hi: bool) -> Check {
    finite(key, v)?;
    let ok = v > lo && if closed_hi { v <= hi } else { v < hi };
    if ok {
        Ok(())
    } else {
        let close = if closed_hi { ']' } else { ')' };
        Err(SceneError::invalid(
            key,
            format!("{key} must be in ({lo}, {hi}{close}, got {v}"),
        ))
    }
}

fn day_of_year(key: &str, v: f64) -> Check {
    finite(key, v)?;
    if (1.0..=366.0).contains(&v) {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{key} must be a day of the year in 1..=366, got {v}"),
        ))
    }
}

fn adiabatic(prefix: &str, rise: &AdiabaticRise) -> Check {
    let key = |f: &str| format!("{prefix}.{f}");
    let theta0 = match rise {
        AdiabaticRise::Exponential { theta0, m } => {
            positive(&key("m"), *m)?;
            *theta0
        }
        AdiabaticRise::Compound { theta0, a, b } => {
            positive(&key("a"), *a)?;
            in_range(&key("b"), *b, 0.0, 3.0, true)?;
            *theta0
        }
        AdiabaticRise::Hyperbolic { theta0, n } => {
            positive(&key("n"), *n)?;
            *theta0
        }
    };
    in_range(&key("theta0"), theta0, 0.0, 100.0, false)
}

fn pipes(prefix: &str, p: &PipeLayout) -> Check {
    let key = |f: &str| format!("{prefix}.{f}");
    positive(&key("spacing_horizontal_m"), p.spacing_horizontal_m)?;
    positive(&key("spacing_vertical_m"), p.spacing_vertical_m)?;
    positive(&key("length_m"), p.length_m)?;
    positive(&key("flow_l_per_min"), p.flow_l_per_min)?;
    positive(&key("outer_radius_m"), p.outer_radius_m)?;
    positive(&key("inner_radius_m"), p.inner_radius_m)?;
    if p.inner_radius_m >= p.outer_radius_m {
        return Err(SceneError::invalid(
            key("inner_radius_m"),
            format!(
                "{} = {} must be < {} = {}",
                key("inner_radius_m"),
                p.inner_radius_m,
                key("outer_radius_m"),
                p.outer_radius_m
            ),
        ));
    }
    positive(&key("wall_conductivity_w_mk"), p.wall_conductivity_w_mk)?;
    positive(&key("water_density"), p.water_density)?;
    positive(&key("water_specific_heat"), p.water_specific_heat)?;
    // Zhu's equivalent cooling cylinder: radius b = 0.5835·√(S1·S2) must
    // enclose the pipe.
    let b = 0.5835 * (p.spacing_horizontal_m * p.spacing_vertical_m).sqrt();
    if b <= p.outer_radius_m {
        return Err(SceneError::invalid(
            key("spacing_horizontal_m"),
            format!(
                "{prefix}: the equivalent cooling cylinder (radius 0.5835·√(spacing_horizontal_m·spacing_vertical_m) = {b:.4} m) must be wider than the pipe (outer_radius_m = {})",
                p.outer_radius_m
            ),
        ));
    }
    Ok(())
}

fn rock_table(r: &Rock) -> Check {
    thermal_properties("rock", r)?;
    finite("rock.initial_temp_c", r.initial_temp_c)?;
    finite("rock.gradient_c_per_m", r.gradient_c_per_m)
}

fn air(a: &Air) -> Check {
    finite("air.mean_c", a.mean_c)?;
    non_negative("air.amplitude_c", a.amplitude_c)?;
    day_of_year("air.warmest_day_of_year", a.warmest_day_of_year)?;
    positive("air.film_w_m2k", a.film_w_m2k)
}

fn reservoir(r: &Reservoir) -> Check {
    finite("reservoir.surface_mean_c", r.surface_mean_c)?;
    non_negative("reservoir.surface_amplitude_c", r.surface_amplitude_c)?;
    day_of_year("reservoir.warmest_day_of_year", r.warmest_day_of_year)?;
    finite("reservoir.bottom_temp_c", r.bottom_temp_c)?;
    non_negative("reservoir.decay_per_m", r.decay_per_m)
}

fn rock_needed(key: &str, depth: f64, s: &Scene) -> Check {
    if depth > 0.0 && s.rock.is_none() {
        return Err(SceneError::invalid(
            "rock",
            format!("{key} = {depth} needs a [rock] table, which is missing"),
        ));
    }
    Ok(())
}

fn blocks(g: &BlocksGeometry, s: &Scene) -> Check {
    at_least_one("geometry.n_blocks", g.n_blocks)?;
    positive("geometry.block_length_m", g.block_length_m)?;
    positive("geometry.thickness_m", g.thickness_m)?;
    at_least_one("geometry.n_lifts", g.n_lifts)?;
    at_least_one("geometry.elements_per_block", g.elements_per_block)?;
    at_least_one("geometry.elements_across", g.elements_across)?;
    at_least_one("geometry.layers_per_lift", g.layers_per_lift)?;
    non_negative("geometry.rock_depth_m", g.rock_depth_m)?;
    at_least_one("geometry.rock_layers", g.rock_layers)?;
    non_negative("geometry.rock_margin_m", g.rock_margin_m)?;
    at_least_one("geometry.rock_margin_elements", g.rock_margin_elements)?;
    grading_ratio(g.rock_grading_ratio)?;
    end_element("geometry.face_element_m", g.face_element_m)?;
    end_element("geometry.joint_element_m", g.joint_element_m)?;
    finite("geometry.base_elevation_m", g.base_elevation_m)?;
    rock_needed("geometry.rock_depth_m", g.rock_depth_m, s)
}

fn arch(g: &ArchGeometry, s: &Scene) -> Check {
    arch_blocks(g.n_blocks)?;
    positive("geometry.height_m", g.height_m)?;
    finite("geometry.base_elevation_m", g.base_elevation_m)?;
    positive("geometry.crest_radius_m", g.crest_radius_m)?;
    positive("geometry.base_radius_m", g.base_radius_m)?;
    if g.base_radius_m > g.crest_radius_m {
        return Err(SceneError::invalid(
            "geometry.base_radius_m",
            format!(
                "geometry.base_radius_m = {} must be <= geometry.crest_radius_m = {}",
                g.base_radius_m, g.crest_radius_m
            ),
        ));
    }
    in_range(
        "geometry.central_angle_deg",
        g.central_angle_deg,
        0.0,
        180.0,
        false,
    )?;
    positive("geometry.crest_thickness_m", g.crest_thickness_m)?;
    positive("geometry.base_thickness_m", g.base_thickness_m)?;
    if g.base_thickness_m < g.crest_thickness_m {
        return Err(SceneError::invalid(
            "geometry.base_thickness_m",
            format!(
                "geometry.base_thickness_m = {} must be >= geometry.crest_thickness_m = {}",
                g.base_thickness_m, g.crest_thickness_m
            ),
        ));
    }
    positive("geometry.thickness_exponent", g.thickness_exponent)?;
    finite("geometry.overhang_m", g.overhang_m)?;
    positive("geometry.valley_exponent", g.valley_exponent)?;
    in_range(
        "geometry.min_block_height_fraction",
        g.min_block_height_fraction,
        0.0,
        1.0,
        true,
    )?;
    arch_counts(&ArchCounts {
        elements_per_block: g.elements_per_block,
        elements_across: g.elements_across,
        rock_depth_m: g.rock_depth_m,
        rock_layers: g.rock_layers,
        rock_margin_m: g.rock_margin_m,
        rock_margin_elements: g.rock_margin_elements,
        rock_grading_ratio: g.rock_grading_ratio,
        face_element_m: g.face_element_m,
        joint_element_m: g.joint_element_m,
    })?;
    if whole_multiple(g.height_m, s.lifts.height_m).is_none() {
        return Err(SceneError::invalid(
            "geometry.height_m",
            format!(
                "geometry.height_m = {} is not a whole number of lifts (lifts.height_m = {})",
                g.height_m, s.lifts.height_m
            ),
        ));
    }
    if g.height_m < s.joints.zone_height_m {
        return Err(SceneError::invalid(
            "geometry.height_m",
            format!(
                "geometry.height_m = {} must be >= joints.zone_height_m = {}",
                g.height_m, s.joints.zone_height_m
            ),
        ));
    }
    rock_needed("geometry.rock_depth_m", g.rock_depth_m, s)
}

/// An arch has joints: at least two blocks.
fn arch_blocks(n_blocks: u32) -> Check {
    if n_blocks < 2 {
        return Err(SceneError::invalid(
            "geometry.n_blocks",
            format!("geometry.n_blocks must be >= 2 for an arch, got {n_blocks}"),
        ));
    }
    Ok(())
}

/// The element and rock counts both arch kinds have, under the same keys.
struct ArchCounts {
    elements_per_block: u32,
    elements_across: u32,
    rock_depth_m: f64,
    rock_layers: u32,
    rock_margin_m: f64,
    rock_margin_elements: u32,
    rock_grading_ratio: f64,
    face_element_m: Option<f64>,
    joint_element_m: Option<f64>,
}

fn arch_counts(c: &ArchCounts) -> Check {
    at_least_one("geometry.elements_per_block", c.elements_per_block)?;
    at_least_one("geometry.elements_across", c.elements_across)?;
    non_negative("geometry.rock_depth_m", c.rock_depth_m)?;
    at_least_one("geometry.rock_layers", c.rock_layers)?;
    non_negative("geometry.rock_margin_m", c.rock_margin_m)?;
    at_least_one("geometry.rock_margin_elements", c.rock_margin_elements)?;
    grading_ratio(c.rock_grading_ratio)?;
    end_element("geometry.face_element_m", c.face_element_m)?;
    end_element("geometry.joint_element_m", c.joint_element_m)
}

/// The scalar keys of an `arch_table` geometry (its CSV tables are checked
/// when [`Scene::load`] reads them).
fn arch_table(g: &ArchTableGeometry, s: &Scene) -> Check {
    arch_blocks(g.n_blocks)?;
    finite("geometry.base_elevation_m", g.base_elevation_m)?;
    finite("geometry.crest_elevation_m", g.crest_elevation_m)?;
    let height = g.crest_elevation_m - g.base_elevation_m;
    if height < s.joints.zone_height_m {
        return Err(SceneError::invalid(
            "geometry.crest_elevation_m",
            format!(
                "geometry.crest_elevation_m = {} must be at least joints.zone_height_m = {} above geometry.base_elevation_m = {}",
                g.crest_elevation_m, s.joints.zone_height_m, g.base_elevation_m
            ),
        ));
    }
    positive("geometry.crest_length_m", g.crest_length_m)?;
    in_range(
        "geometry.crest_left_length_m",
        g.crest_left_length_m / g.crest_length_m,
        0.0,
        1.0,
        false,
    )
    .map_err(|_| {
        SceneError::invalid(
            "geometry.crest_left_length_m",
            format!(
                "geometry.crest_left_length_m = {} must be in (0, geometry.crest_length_m = {})",
                g.crest_left_length_m, g.crest_length_m
            ),
        )
    })?;
    if !g.block_widths_m.is_empty() {
        let sum: f64 = g.block_widths_m.iter().sum();
        if g.block_widths_m.len() != g.n_blocks as usize
            || g.block_widths_m
                .iter()
                .any(|w| !(w.is_finite() && *w > 0.0))
            || (sum - g.crest_length_m).abs() > 1e-6 * g.crest_length_m
        {
            return Err(SceneError::invalid(
                "geometry.block_widths_m",
                format!(
                    "geometry.block_widths_m must be n_blocks = {} widths > 0 summing to geometry.crest_length_m = {}, got {} summing to {sum}",
                    g.n_blocks,
                    g.crest_length_m,
                    g.block_widths_m.len()
                ),
            ));
        }
    }
    positive("geometry.thickness_exponent", g.thickness_exponent)?;
    arch_counts(&ArchCounts {
        elements_per_block: g.elements_per_block,
        elements_across: g.elements_across,
        rock_depth_m: g.rock_depth_m,
        rock_layers: g.rock_layers,
        rock_margin_m: g.rock_margin_m,
        rock_margin_elements: g.rock_margin_elements,
        rock_grading_ratio: g.rock_grading_ratio,
        face_element_m: g.face_element_m,
        joint_element_m: g.joint_element_m,
    })?;
    rock_needed("geometry.rock_depth_m", g.rock_depth_m, s)
}

/// Mechanical inputs: required only by the mechanical effects, always
/// checked when present.
fn mechanical(s: &Scene) -> Check {
    let c = &s.concrete;
    let need = |what: &str, effect: &str| {
        SceneError::invalid(
            format!("concrete.{what}"),
            format!("effect `{effect}` needs concrete.{what}, which is missing"),
        )
    };
    if let Some(first) = s.effects.iter().find(|e| e.is_mechanical()) {
        if c.modulus.is_none() {
            return Err(need("modulus", first.name()));
        }
        if c.poisson.is_none() {
            return Err(need("poisson", first.name()));
        }
    }
    if s.has(Effect::ThermalStrain) && c.expansion_per_c.is_none() {
        return Err(need("expansion_per_c", "thermal_strain"));
    }
    if s.has(Effect::Creep) && c.creep.is_none() {
        return Err(need("creep", "creep"));
    }
    if s.has(Effect::Autogenous) && c.autogenous.is_none() {
        return Err(need("autogenous", "autogenous"));
    }
    if let Some(m) = &c.modulus {
        m.validate().map_err(|e| {
            SceneError::invalid("concrete.modulus", format!("concrete.modulus.{e}"))
        })?;
    }
    if let Some(nu) = c.poisson {
        poisson_ratio("concrete.poisson", nu)?;
    }
    if let Some(a) = c.expansion_per_c {
        finite("concrete.expansion_per_c", a)?;
        if !(0.0..1e-3).contains(&a) {
            return Err(SceneError::invalid(
                "concrete.expansion_per_c",
                format!("concrete.expansion_per_c must be in [0, 1e-3) 1/°C, got {a}"),
            ));
        }
    }
    if let Some(cr) = &c.creep {
        cr.validate()
            .map_err(|e| SceneError::invalid("concrete.creep", format!("concrete.creep: {e}")))?;
    }
    if let Some(g) = &c.autogenous {
        g.validate().map_err(|e| {
            SceneError::invalid("concrete.autogenous", format!("concrete.autogenous.{e}"))
        })?;
    }
    if let Some(r) = &s.rock {
        if s.any_mechanical() && r.modulus_pa.is_none() {
            return Err(SceneError::invalid(
                "rock.modulus_pa",
                "mechanical effects need rock.modulus_pa, which is missing",
            ));
        }
        if let Some(e) = r.modulus_pa {
            positive("rock.modulus_pa", e)?;
        }
        if let Some(nu) = r.poisson {
            poisson_ratio("rock.poisson", nu)?;
        }
        if let Some(a) = r.expansion_per_c {
            finite("rock.expansion_per_c", a)?;
        }
    }
    Ok(())
}

/// `geometry.face_element_m` or `joint_element_m` (`key`), where given:
/// positive (an end element longer than its share, t / count, leaves the
/// cells equal).
fn end_element(key: &str, size: Option<f64>) -> Check {
    match size {
        Some(s) => positive(key, s),
        None => Ok(()),
    }
}

/// `geometry.rock_grading_ratio` in [1, 3] (the generators' own limit).
fn grading_ratio(r: f64) -> Check {
    let key = "geometry.rock_grading_ratio";
    finite(key, r)?;
    if !(1.0..=3.0).contains(&r) {
        return Err(SceneError::invalid(
            key,
            format!("{key} must be in [1, 3] (1 = uniform rock), got {r}"),
        ));
    }
    Ok(())
}

/// `[boundary.<side>]`: finite temperatures; rollers only where the far
/// faces are plane and normal to x, y or z, which the arch's rock sides
/// are not (its upstream and downstream faces follow the rings, its
/// abutment faces the last joint planes).
fn boundary(s: &Scene) -> Check {
    for side in crate::mesh::FarSide::ALL {
        let face = s.boundary.side(side);
        if let Some(t) = face.temperature_c {
            finite(&format!("boundary.{side}.temperature_c"), t)?;
        }
        let arch = matches!(s.geometry, Geometry::Arch(_));
        if arch && side != crate::mesh::FarSide::Base && face.support == super::Support::Rollers {
            let key = format!("boundary.{side}.support");
            return Err(SceneError::invalid(
                &key,
                format!(
                    "{key} = \"rollers\" needs far faces normal to x, y or z, but the arch's \
                     {side} rock face is curved or oblique (use \"fixed\" or \"free\"; rollers \
                     hold on the base)"
                ),
            ));
        }
    }
    Ok(())
}

fn poisson_ratio(key: &str, nu: f64) -> Check {
    if !(nu.is_finite() && (0.0..0.5).contains(&nu)) {
        return Err(SceneError::invalid(
            key,
            format!("{key} must be in [0, 0.5), got {nu}"),
        ));
    }
    Ok(())
}
