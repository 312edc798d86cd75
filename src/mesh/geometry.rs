//! Parameters of the mesh generators, as they appear in a scene's `[geometry]` table.

use serde::{Deserialize, Serialize};

use super::MeshError;

/// Which generator builds the mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Geometry {
    Blocks(BlocksGeometry),
    Arch(ArchGeometry),
    /// An arch dam by design tables (CSV files beside the scene).
    ArchTable(super::arch_table::ArchTableGeometry),
    Mesh(MeshGeometry),
}

/// An analyst's mesh file (Gmsh MSH 4.1 or Abaqus/CalculiX `.inp`) with
/// element groups `block_<n>` and `rock` (see [`super::import`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshGeometry {
    /// The mesh file, relative to the scene file's folder.
    pub file: String,
    /// Set by `Scene::load`, never written by hand: where the file is and a
    /// digest of its bytes. A run folder's copy of the scene then finds the
    /// same file from anywhere (the TUI opens run folders), and the restart
    /// fingerprint, which hashes the scene, changes when the file does.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolved: Option<ResolvedFile>,
}

/// A mesh file found on disk when its scene was loaded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResolvedFile {
    /// The absolute path.
    pub path: String,
    /// FNV-1a of the file's bytes ([`crate::vocab::fnv1a`]).
    pub digest: u64,
}

impl MeshGeometry {
    /// Finds `file` relative to `dir` (the scene file's folder) and digests it.
    pub fn resolve(&mut self, dir: &std::path::Path) -> std::io::Result<()> {
        let path = std::path::absolute(dir.join(&self.file))?;
        let bytes = std::fs::read(&path)?;
        self.resolved = Some(ResolvedFile {
            path: path.display().to_string(),
            digest: crate::vocab::fnv1a(&bytes),
        });
        Ok(())
    }
}

/// N rectangular blocks in a row along x on a rock foundation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlocksGeometry {
    /// Number of blocks (≥ 1); joints = blocks − 1.
    pub n_blocks: u32,
    /// Length of each block along the axis (x) \[m\].
    pub block_length_m: f64,
    /// Thickness of the blocks in the stream direction (y) \[m\].
    pub thickness_m: f64,
    /// Number of lifts of every block.
    pub n_lifts: u32,
    /// Elements along x per block.
    pub elements_per_block: u32,
    /// Elements across the thickness (y).
    pub elements_across: u32,
    /// Element layers per lift (1 = one layer per lift).
    #[serde(default = "one")]
    pub layers_per_lift: u32,
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
    /// Rock depth under the blocks \[m\]; 0 = no rock (blocks on a rigid/adiabatic base).
    #[serde(default)]
    pub rock_depth_m: f64,
    /// Rock element layers.
    #[serde(default = "one")]
    pub rock_layers: u32,
    /// Rock margin beyond the blocks on every side \[m\] (0 = rock only under the blocks);
    /// needs `rock_depth_m > 0`. The margin's top is at the base elevation.
    #[serde(default)]
    pub rock_margin_m: f64,
    /// Rock elements across each margin (used when `rock_margin_m > 0`).
    #[serde(default = "one")]
    pub rock_margin_elements: u32,
    /// Growth ratio of the rock cells away from the dam, in [1, 3]; 1
    /// (default) = uniform `rock_layers` and `rock_margin_elements`, above 1
    /// the first cell is the size of the concrete cell it touches and the
    /// counts follow (module doc of [`super::blocks`]).
    #[serde(default = "one_f", skip_serializing_if = "is_one")]
    pub rock_grading_ratio: f64,
    /// Elevation of the block bases \[m\].
    #[serde(default)]
    pub base_elevation_m: f64,
}

/// A parametric double-curvature arch dam in a valley.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArchGeometry {
    /// Number of blocks (≥ 2), numbered from the left bank.
    pub n_blocks: u32,
    /// Structural height from the deepest foundation to the crest \[m\].
    pub height_m: f64,
    /// Elevation of the deepest foundation \[m\].
    #[serde(default)]
    pub base_elevation_m: f64,
    /// Radius of the upstream face at the crest \[m\].
    pub crest_radius_m: f64,
    /// Radius of the upstream face at the base \[m\] (smaller: plan curvature grows with depth).
    pub base_radius_m: f64,
    /// Central angle of the crest arch \[degrees\].
    pub central_angle_deg: f64,
    /// Crest thickness \[m\].
    pub crest_thickness_m: f64,
    /// Base thickness at the crown \[m\].
    pub base_thickness_m: f64,
    /// Exponent of the thickness law t(z) = t_c + (t_b − t_c)·((H − z)/H)^k.
    #[serde(default = "one_f")]
    pub thickness_exponent: f64,
    /// Crown-cantilever overhang: largest upstream offset of the upstream face \[m\]
    /// (reached at 2/3 of the height; zero at base and crest for the default shape).
    #[serde(default)]
    pub overhang_m: f64,
    /// Valley shape exponent v: block b, centred at f_b = (2b − 1 − N)/N along the
    /// crest (−1 left abutment, +1 right), is H·max(min_block_height_fraction,
    /// (1 − |f_b|^v)/(1 − f_min^v)) high (f_min = smallest |f_b|, so the central
    /// block(s) reach the base), its foundation rounded down to a zone boundary.
    #[serde(default = "two_f")]
    pub valley_exponent: f64,
    /// Lowest abutment block height as a fraction of H (the valley side blocks' height).
    #[serde(default = "min_block_fraction")]
    pub min_block_height_fraction: f64,
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
}

pub(super) fn one() -> u32 {
    1
}
pub(super) fn two() -> u32 {
    2
}
pub(super) fn one_f() -> f64 {
    1.0
}
pub(super) fn is_one(v: &f64) -> bool {
    *v == 1.0
}
fn two_f() -> f64 {
    2.0
}
fn min_block_fraction() -> f64 {
    0.3
}

/// `Err` naming `name` unless `ok`; the message is built only then.
pub(crate) fn check(ok: bool, name: &str, msg: impl FnOnce() -> String) -> Result<(), MeshError> {
    if ok {
        Ok(())
    } else {
        Err(MeshError::param(name, msg()))
    }
}

/// `name must be > 0, got v` unless v is finite and positive.
pub(crate) fn positive(name: &str, v: f64) -> Result<(), MeshError> {
    check(v.is_finite() && v > 0.0, name, || {
        format!("must be > 0, got {v}")
    })
}

/// `name must be >= 0, got v` unless v is finite and not negative.
pub(crate) fn non_negative(name: &str, v: f64) -> Result<(), MeshError> {
    check(v.is_finite() && v >= 0.0, name, || {
        format!("must be >= 0, got {v}")
    })
}

/// `name must be >= min, got v` for a count below `min`.
pub(crate) fn at_least(name: &str, v: u32, min: u32) -> Result<(), MeshError> {
    check(v >= min, name, || format!("must be >= {min}, got {v}"))
}
