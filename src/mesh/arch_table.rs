//! The `arch_table` generator: an arch dam given by its design tables, as a
//! site's drawings give it (issue 14, item 2), meshed like the parametric
//! [`super::arch`]: the same [`super::grid::BlockRow`], one element layer per
//! lift, joints, zones, margins and rock, through the shared
//! [`super::arch::node_positions`].
//!
//! # Inputs
//!
//! * `[geometry]` of the scene: `arch_type`, the elevations of the base and
//!   crest, the crest's reference-line length and where the crown lies on it
//!   (`crest_left_length_m`), the blocks (`n_blocks`, optional
//!   `block_widths_m` along the crest's reference line, from the left bank;
//!   equal widths when absent), the thickness law exponent and the element
//!   and rock counts of the `arch` generator ([`ArchTableGeometry`]).
//! * `table` (CSV, path relative to the scene's folder): one row per
//!   elevation, at increasing elevations, columns `elevation_m,
//!   crown_upstream_y_m, crown_downstream_y_m, thickness_left_abutment_m,
//!   thickness_right_abutment_m, radius_left_m, radius_right_m` and the
//!   type's coefficients (`outer_radius_{left,right}_m` and
//!   `central_half_angle_{left,right}_deg` for three-centred arches,
//!   `axis_ratio_{left,right}` for elliptical ones, `spiral_growth_{left,right}`
//!   for logarithmic spirals; another type's columns may be present, blank).
//!   Lines starting with `#` are comments. Values are linear in z between rows.
//! * `valley` (CSV): `crest_distance_m, foundation_elevation_m`, the
//!   foundation (abutment line) against the distance along the crest's
//!   reference line from its left end, increasing distances covering
//!   [0, crest length], elevations within [base, crest]; linear between rows.
//!
//! Both files are read by `Scene::load` (the scene module) into
//! [`ArchTableGeometry::tables`], so the scene kept in a run folder (and its
//! fingerprint) carries the tables themselves.
//!
//! # Plan geometry at elevation z
//!
//! Axes as in [`super`]: x along the dam axis, y downstream, the crown in the
//! plane x = 0; the table's y are measured from the reference axis (y = 0),
//! and the mesh is built in that local frame (no azimuth). The crown
//! cantilever gives y_u(z), y_d(z), the crown thickness T_c = y_d − y_u and
//! the **reference line**, the arch's centre line, through (0, y₀),
//! y₀ = (y_u + y_d)/2, tangent to x. Each half (left x < 0, right x > 0) is
//! a curve of the arch type with its own coefficients
//! ([`super::arch_curves`]), parametrised by its tangent angle φ (negative on
//! the left). The faces are the reference line offset by ∓T/2 along its
//! upstream normal n = (sin φ, −cos φ); a point at across fraction a is
//! C(φ) + (T/2 − a·T)·n. The thickness varies from the crown to the
//! abutment as T(φ) = T_c + (T_A − T_c)·min(1, |φ|/φ_A)^k (k =
//! `thickness_exponent`, default 1: linear in the angle), φ_A(z) the angle
//! where the reference line meets that side's abutment line at z (below),
//! T_A beyond it (in the rock of the grid). Where the arch is a point (the
//! valley's bottom at the base) φ_A is 0 and T = T_A: the table's base row
//! should then have T_A = T_c.
//!
//! # Joints, grid lines and the valley
//!
//! The crest's reference line (the row interpolated at the crest) carries
//! the blocks: block b spans crest distances [s_{b−1}, s_b] from the left
//! end, its `elements_per_block` grid lines at equal distances inside. Each
//! grid line i is given the tangent angle φ_i of its crest point, and keeps
//! it at every elevation: **joints keep their plan direction** (at z, the
//! joint is the normal of that elevation's reference line of direction φ_i).
//! This is the parametric arch's rule (a radial joint at angle φ through each
//! ring's own centre), so tables sampled from a parametric arch give its mesh
//! back; it keeps every element's plan corners in the order of the crest's,
//! and joint faces plane-by-lift. (Vertical joint planes, the crest normal
//! plane extended down, are not offered: on a curved lower ring they cut the
//! arch obliquely, which the structured grid would have to follow.)
//!
//! Block b is founded at the valley's elevation at its crest-centre distance,
//! rounded down to a zone boundary ([`super::arch::zone_floor`], as the
//! `arch` generator does); the abutment angle φ_A(z) of the thickness law is
//! that of the first crest distance, going out from the crown, where the
//! valley reaches z (the crest's end when it never does). Layers, margins
//! and rock are the `arch` generator's: the rock levels below the base use
//! the base row, the margins beyond the abutments follow the end tangents.
//!
//! # Verification
//!
//! `tests/it/arch_table.rs`: tables sampled from the parametric arch of
//! `models/demo_arch.toml` (circular, uniform thickness, its overhang,
//! valley and joints) give the mesh of [`super::generate_arch`] (nodes within
//! 1e-9 m, same elements, face pairs, zones); every curve type's crown
//! radius, tangent, arc length and tangent-angle parametrisation; every
//! type meshes with the table's crown faces and its abutment thickness T_A
//! at the crest's ends; table and valley errors with file:line:column; the
//! Xiaowan-like scene's mesh (gross dimensions, blocks and zones) against
//! its schedules.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::arch::{self, Across, ArchPlan, RowCounts};
use super::arch_curves::{ArchType, HalfArch, HalfCurve};
use super::geometry::{at_least, check, is_one, one, one_f, positive, two};
use super::grid::{self, Layers};
use super::{Mesh, MeshError};

pub use super::arch_table_read::{load_tables, ArchTableError};

/// An arch dam by design tables (`[geometry] kind = "arch_table"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArchTableGeometry {
    /// Type of the horizontal arches (`circular`, `three_centred`,
    /// `parabolic`, `elliptical`, `log_spiral`).
    pub arch_type: ArchType,
    /// CSV of the arch per elevation, relative to the scene file's folder.
    pub table: PathBuf,
    /// CSV of the valley (foundation against crest distance), relative to
    /// the scene file's folder.
    pub valley: PathBuf,
    /// Elevation of the deepest foundation \[m\].
    pub base_elevation_m: f64,
    /// Elevation of the crest \[m\].
    pub crest_elevation_m: f64,
    /// Number of blocks (≥ 2), from the left bank.
    pub n_blocks: u32,
    /// Length of the crest's reference line (centre line), abutment to
    /// abutment \[m\].
    pub crest_length_m: f64,
    /// Length of the crest's reference line from the left abutment to the
    /// crown \[m\] (the crown is at x = 0).
    pub crest_left_length_m: f64,
    /// Block widths along the crest's reference line, from the left bank
    /// \[m\]; their sum is `crest_length_m`. Empty: equal widths.
    #[serde(default)]
    pub block_widths_m: Vec<f64>,
    /// Exponent k of the thickness law T = T_c + (T_A − T_c)·(φ/φ_A)^k.
    #[serde(default = "one_f")]
    pub thickness_exponent: f64,
    /// Elements along the arc per block.
    pub elements_per_block: u32,
    /// Elements across the thickness.
    pub elements_across: u32,
    /// Thickness \[m\] of the element layer across at the upstream and
    /// downstream faces; the others grow by one ratio towards the middle of
    /// the section (`grid::graded_fractions`). Absent (default): equal
    /// elements across. Set to the grout stops' inset, the zone minimum is
    /// read on node rows and the faces' warm layer is resolved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub face_element_m: Option<f64>,
    /// Width \[m\] of the element along the block next to each transverse
    /// joint; the others grow by one ratio towards the block's middle
    /// (`grid::graded_fractions`; an arch's at the crest's reference line).
    /// Absent (default): equal elements along. The joints' faces cool and
    /// warm first, and the block's shortening near them is what opens the
    /// joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_element_m: Option<f64>,
    /// Rock depth below the deepest foundation \[m\].
    pub rock_depth_m: f64,
    /// Rock element layers below the deepest foundation.
    #[serde(default = "two")]
    pub rock_layers: u32,
    /// Rock margin upstream, downstream and beyond the abutments \[m\].
    pub rock_margin_m: f64,
    /// Rock elements across each margin.
    #[serde(default = "one")]
    pub rock_margin_elements: u32,
    /// Growth ratio of the rock cells away from the dam, in [1, 3]; 1
    /// (default) = uniform `rock_layers` and `rock_margin_elements`, above 1
    /// graded from the concrete cells' sizes (module doc of [`super::arch`]).
    #[serde(default = "one_f", skip_serializing_if = "is_one")]
    pub rock_grading_ratio: f64,
    /// The two tables as read by `Scene::load` (the scene module); never
    /// written in a scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tables: Option<ArchTables>,
}

/// The design tables of an [`ArchTableGeometry`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArchTables {
    /// The arch per elevation, at increasing elevations covering base..crest.
    pub rows: Vec<ArchRow>,
    /// (distance along the crest's reference line from its left end,
    /// foundation elevation), at increasing distances covering the crest.
    pub valley: Vec<[f64; 2]>,
}

/// One row of the arch table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArchRow {
    pub elevation_m: f64,
    /// y of the crown cantilever's upstream face.
    pub crown_upstream_y_m: f64,
    /// y of the crown cantilever's downstream face.
    pub crown_downstream_y_m: f64,
    pub thickness_left_abutment_m: f64,
    pub thickness_right_abutment_m: f64,
    pub left: HalfArch,
    pub right: HalfArch,
}

impl ArchRow {
    fn lerp(&self, o: &ArchRow, w: f64) -> ArchRow {
        // (1 − w)·a + w·b returns b exactly at w = 1: a row's own values at its elevation.
        let l = |a: f64, b: f64| (1.0 - w) * a + w * b;
        ArchRow {
            elevation_m: l(self.elevation_m, o.elevation_m),
            crown_upstream_y_m: l(self.crown_upstream_y_m, o.crown_upstream_y_m),
            crown_downstream_y_m: l(self.crown_downstream_y_m, o.crown_downstream_y_m),
            thickness_left_abutment_m: l(
                self.thickness_left_abutment_m,
                o.thickness_left_abutment_m,
            ),
            thickness_right_abutment_m: l(
                self.thickness_right_abutment_m,
                o.thickness_right_abutment_m,
            ),
            left: self.left.lerp(&o.left, w),
            right: self.right.lerp(&o.right, w),
        }
    }
}

impl ArchTables {
    /// The row at elevation `z`, linear between rows, clamped to the table.
    pub fn row_at(&self, z: f64) -> ArchRow {
        let rows = &self.rows;
        let last = rows.len() - 1;
        if z <= rows[0].elevation_m || last == 0 {
            return rows[0];
        }
        if z >= rows[last].elevation_m {
            return rows[last];
        }
        let i = rows
            .windows(2)
            .position(|w| z <= w[1].elevation_m)
            .unwrap_or(last - 1);
        let (a, b) = (&rows[i], &rows[i + 1]);
        a.lerp(b, (z - a.elevation_m) / (b.elevation_m - a.elevation_m))
    }

    /// The valley's foundation elevation at crest distance `s`, linear
    /// between rows, clamped to the table.
    pub fn valley_at(&self, s: f64) -> f64 {
        lerp_profile(&self.valley, s)
    }
}

fn lerp_profile(p: &[[f64; 2]], s: f64) -> f64 {
    let last = p.len() - 1;
    if s <= p[0][0] || last == 0 {
        return p[0][1];
    }
    if s >= p[last][0] {
        return p[last][1];
    }
    let i = p.windows(2).position(|w| s <= w[1][0]).unwrap_or(last - 1);
    let w = (s - p[i][0]) / (p[i + 1][0] - p[i][0]);
    (1.0 - w) * p[i][1] + w * p[i + 1][1]
}

/// The arch at one logical level (module doc, "Plan geometry").
#[derive(Debug, Clone, Copy)]
struct Level {
    /// y of the reference line at the crown.
    y0: f64,
    t_crown: f64,
    left: Side,
    right: Side,
    exponent: f64,
}

#[derive(Debug, Clone, Copy)]
struct Side {
    curve: HalfCurve,
    t_abutment: f64,
    /// |φ| where the reference line meets the abutment line.
    phi_abutment: f64,
}

impl Level {
    fn thickness(&self, side: &Side, phi: f64) -> f64 {
        let psi = if side.phi_abutment > 0.0 {
            (phi / side.phi_abutment).min(1.0)
        } else {
            1.0
        };
        self.t_crown + (side.t_abutment - self.t_crown) * psi.powf(self.exponent)
    }
}

impl ArchPlan for [Level] {
    fn plan_point(&self, k: usize, phi: f64, across: Across, ext: f64) -> [f64; 2] {
        let lv = &self[k];
        let (side, sign) = if phi < 0.0 {
            (&lv.left, -1.0)
        } else {
            (&lv.right, 1.0)
        };
        let a = phi.abs();
        let [px, py] = side.curve.point(a);
        let (cx, cy) = (sign * px, lv.y0 + py);
        let half = 0.5 * lv.thickness(side, a);
        let (s, c) = phi.sin_cos();
        // offset along the upstream normal (sin φ, −cos φ), plus +y downstream
        let (off, dy) = match across {
            Across::Upstream(d) => (half + d, 0.0),
            Across::Dam(f) => (half - f * 2.0 * half, 0.0),
            Across::Downstream(d) => (-half, d),
        };
        [cx + off * s + ext * c, cy - off * c + dy + ext * s]
    }

    fn thickness(&self, k: usize, phi: f64) -> f64 {
        let lv = &self[k];
        let side = if phi < 0.0 { &lv.left } else { &lv.right };
        lv.thickness(side, phi.abs())
    }
}

/// Build the mesh of an [`ArchTableGeometry`] whose tables are loaded, with
/// lifts of `lift_height` (m) and grouting zones of `zone_height` (m).
pub fn generate_arch_table(
    g: &ArchTableGeometry,
    lift_height: f64,
    zone_height: f64,
) -> Result<Mesh, MeshError> {
    let tables = g.tables.as_ref().ok_or_else(|| {
        MeshError::param(
            "table",
            "was not read (a scene read by Scene::load carries its tables)",
        )
    })?;
    let zone_lifts = check_params(g, lift_height, zone_height)?;
    let (base, crest) = (g.base_elevation_m, g.crest_elevation_m);
    let layer_z = arch::layer_boundaries(base, crest - base, lift_height)?;
    let n_layers = layer_z.len() - 1;
    let base_row = tables.row_at(base);
    let (row, rock) = arch::block_row(&RowCounts {
        n_blocks: g.n_blocks,
        elements_per_block: g.elements_per_block,
        elements_across: g.elements_across,
        rock_depth_m: g.rock_depth_m,
        rock_layers: g.rock_layers,
        rock_margin_m: g.rock_margin_m,
        rock_margin_elements: g.rock_margin_elements,
        rock_grading_ratio: g.rock_grading_ratio,
        face_element_m: g.face_element_m,
        joint_element_m: g.joint_element_m,
        first_cells_m: [
            g.crest_length_m / (g.n_blocks as f64 * g.elements_per_block as f64),
            (base_row.crown_downstream_y_m - base_row.crown_upstream_y_m)
                / g.elements_across as f64,
            lift_height,
        ],
        n_layers,
    })?;
    let zs = row.level_z(base, g.rock_depth_m, rock.below, &layer_z);
    let crest_row = tables.row_at(crest);
    let crest_curves = [
        HalfCurve {
            kind: g.arch_type,
            arch: crest_row.left,
        },
        HalfCurve {
            kind: g.arch_type,
            arch: crest_row.right,
        },
    ];
    let bounds = block_bounds(g);
    let along = grid_angles(g, &crest_curves, &bounds)?;
    let levels = zs
        .iter()
        .map(|&z| level(g, tables, &crest_curves, z))
        .collect::<Result<Vec<Level>, MeshError>>()?;
    let pos = arch::node_positions(
        levels.as_slice(),
        &row,
        &rock,
        &along,
        &zs,
        g.face_element_m,
    );
    let blocks = bounds
        .windows(2)
        .map(|w| {
            let zf = tables.valley_at(0.5 * (w[0] + w[1]));
            let b = arch::zone_floor(&layer_z, zf, zone_lifts);
            (b, n_layers as u32 - b)
        })
        .collect();
    let layers = Layers {
        z: layer_z,
        lift_height,
        zone_lifts,
        per_lift: 1,
        blocks,
    };
    row.build(pos, layers)
}

/// Checks the scene keys the generator relies on; returns the lifts per zone.
fn check_params(
    g: &ArchTableGeometry,
    lift_height: f64,
    zone_height: f64,
) -> Result<u32, MeshError> {
    at_least("n_blocks", g.n_blocks, 2)?;
    check(
        g.base_elevation_m.is_finite()
            && g.crest_elevation_m.is_finite()
            && g.crest_elevation_m > g.base_elevation_m,
        "crest_elevation_m",
        || {
            format!(
                "must be above base_elevation_m = {}, got {}",
                g.base_elevation_m, g.crest_elevation_m
            )
        },
    )?;
    positive("crest_length_m", g.crest_length_m)?;
    check(
        g.crest_left_length_m > 0.0 && g.crest_left_length_m < g.crest_length_m,
        "crest_left_length_m",
        || {
            format!(
                "must be in (0, crest_length_m = {}), got {}",
                g.crest_length_m, g.crest_left_length_m
            )
        },
    )?;
    if !g.block_widths_m.is_empty() {
        let sum: f64 = g.block_widths_m.iter().sum();
        check(
            g.block_widths_m.len() == g.n_blocks as usize
                && g.block_widths_m.iter().all(|w| w.is_finite() && *w > 0.0)
                && (sum - g.crest_length_m).abs() <= 1e-6 * g.crest_length_m,
            "block_widths_m",
            || {
                format!(
                    "must be n_blocks = {} widths > 0 summing to crest_length_m = {}, got {} summing to {sum}",
                    g.n_blocks,
                    g.crest_length_m,
                    g.block_widths_m.len()
                )
            },
        )?;
    }
    positive("thickness_exponent", g.thickness_exponent)?;
    grid::zone_lifts(lift_height, zone_height)
}

/// Crest distances of the block boundaries from the left end, `n_blocks + 1`.
fn block_bounds(g: &ArchTableGeometry) -> Vec<f64> {
    let n = g.n_blocks as usize;
    let mut bounds = Vec::with_capacity(n + 1);
    bounds.push(0.0);
    let mut s = 0.0;
    for b in 0..n {
        s += match g.block_widths_m.get(b) {
            Some(&w) => w,
            None => g.crest_length_m / n as f64,
        };
        bounds.push(s);
    }
    bounds
}

/// The tangent angle φ of every grid i-line of the dam: equal crest
/// distances inside each block, each turned into the angle of its crest
/// point (negative left of the crown).
fn grid_angles(
    g: &ArchTableGeometry,
    crest: &[HalfCurve; 2],
    bounds: &[f64],
) -> Result<Vec<f64>, MeshError> {
    let epb = g.elements_per_block as usize;
    let s_crown = g.crest_left_length_m;
    let mut along = Vec::with_capacity(bounds.len() * epb);
    for (b, w) in bounds.windows(2).enumerate() {
        let first = if b == 0 { 0 } else { 1 };
        let a = grid::graded_fractions(epb, w[1] - w[0], g.joint_element_m);
        for (e, f) in a.iter().enumerate().skip(first) {
            // uniform: the expression of the first version, bit for bit
            let s = match g.joint_element_m {
                None => w[0] + (w[1] - w[0]) * e as f64 / epb as f64,
                Some(_) => w[0] + (w[1] - w[0]) * f,
            };
            along.push(crest_angle(crest, s - s_crown)?);
        }
    }
    Ok(along)
}

/// Tangent angle of the crest point at signed distance `d` from the crown
/// (negative: left half).
fn crest_angle(crest: &[HalfCurve; 2], d: f64) -> Result<f64, MeshError> {
    let (curve, sign, key) = if d < 0.0 {
        (&crest[0], -1.0, "crest_left_length_m")
    } else {
        (&crest[1], 1.0, "crest_length_m")
    };
    curve
        .angle_at_length(d.abs())
        .map(|phi| sign * phi)
        .ok_or_else(|| {
            MeshError::param(
                key,
                format!(
                    "reaches {} m from the crown along the crest's {} reference line, beyond where it turns {:.0}° ({:.3} m)",
                    d.abs(),
                    curve.kind.name(),
                    super::arch_curves::MAX_ANGLE.to_degrees(),
                    curve.arc_length(super::arch_curves::MAX_ANGLE)
                ),
            )
        })
}

/// The arch at elevation `z` (clamped to base..crest); an error when its
/// crown thickness reaches the crown's diameter of curvature.
fn level(
    g: &ArchTableGeometry,
    tables: &ArchTables,
    crest: &[HalfCurve; 2],
    z: f64,
) -> Result<Level, MeshError> {
    let zc = z.clamp(g.base_elevation_m, g.crest_elevation_m);
    let r = tables.row_at(zc);
    let t_crown = r.crown_downstream_y_m - r.crown_upstream_y_m;
    for half in [&r.left, &r.right] {
        // also refuses NaN
        if 0.5 * t_crown >= half.radius_m || t_crown.is_nan() {
            return Err(MeshError::param(
                "table",
                format!(
                    "at z = {zc} m the crown thickness {t_crown} m is more than twice the crown radius {} m: the downstream face would fold",
                    half.radius_m
                ),
            ));
        }
    }
    let s_crown = g.crest_left_length_m;
    let abut = |dir: f64| -> Result<f64, MeshError> {
        let s = abutment_distance(&tables.valley, s_crown, g.crest_length_m, zc, dir);
        Ok(crest_angle(crest, s - s_crown)?.abs())
    };
    let side = |arch: HalfArch, t: f64, phi: f64| Side {
        curve: HalfCurve {
            kind: g.arch_type,
            arch,
        },
        t_abutment: t,
        phi_abutment: phi,
    };
    Ok(Level {
        y0: 0.5 * (r.crown_upstream_y_m + r.crown_downstream_y_m),
        t_crown,
        left: side(r.left, r.thickness_left_abutment_m, abut(-1.0)?),
        right: side(r.right, r.thickness_right_abutment_m, abut(1.0)?),
        exponent: g.thickness_exponent,
    })
}

/// The first crest distance, going from the crown at `s_crown` towards
/// `dir` (−1 left, +1 right), where the valley reaches elevation `z`; the
/// crest's end (0 or `length`) when it never does.
fn abutment_distance(valley: &[[f64; 2]], s_crown: f64, length: f64, z: f64, dir: f64) -> f64 {
    let end = if dir < 0.0 { 0.0 } else { length };
    let mut prev = [s_crown, lerp_profile(valley, s_crown)];
    if prev[1] >= z {
        return s_crown;
    }
    let beyond = |s: f64| (s - s_crown) * dir > 0.0;
    let mut points: Vec<[f64; 2]> = valley.iter().copied().filter(|p| beyond(p[0])).collect();
    if dir < 0.0 {
        points.reverse();
    }
    for p in points {
        if p[1] >= z {
            let s = prev[0] + (z - prev[1]) / (p[1] - prev[1]) * (p[0] - prev[0]);
            return if dir < 0.0 { s.max(end) } else { s.min(end) };
        }
        prev = p;
    }
    end
}
