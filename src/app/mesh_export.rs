//! What `groutready mesh` does, as a library call: build a scene's mesh,
//! write it by the extension of the output file (`.vtu` for ParaView with
//! the cell arrays `block`, `lift`, `zone` and the point array `joint`;
//! `.msh` Gmsh MSH 4.1 ASCII; `.inp` Abaqus/CalculiX, both through
//! [`RawMesh::from_mesh`]) and summarise its size and element quality.
//!
//! Verified by `tests/it/mesh_files.rs`: the command on the small dam, its
//! summary's figures counted again from the mesh, the files read back.

use std::fmt;
use std::path::Path;

use crate::mesh::import::{self, MeshFileError, RawMesh};
use crate::mesh::quality::{self, Worst};
use crate::mesh::{Mesh, Part};
use crate::scene::Scene;

use super::AppError;

/// The files `groutready mesh` writes, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshOut {
    Vtu,
    Msh,
    Inp,
}

impl MeshOut {
    /// What an output file's extension must be, for messages.
    pub const EXPECTED: &'static str =
        ".vtu (ParaView), .msh (Gmsh MSH 4.1) or .inp (Abaqus/CalculiX)";

    /// The format of `path` by its extension (case-insensitive).
    pub fn of(path: &Path) -> Option<MeshOut> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "vtu" => Some(MeshOut::Vtu),
            "msh" => Some(MeshOut::Msh),
            "inp" => Some(MeshOut::Inp),
            _ => None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum MeshCommandError {
    #[error(transparent)]
    App(#[from] AppError),
    #[error(transparent)]
    File(#[from] MeshFileError),
    #[error("{0}: unknown mesh file extension: expected {ext}", ext = MeshOut::EXPECTED)]
    Extension(String),
}

/// The size and quality of a dam mesh, as `groutready mesh` prints it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSummary {
    pub blocks: usize,
    /// Lifts per block, smallest and largest.
    pub lifts: (u32, u32),
    pub joints: u32,
    /// Grouting zones per joint, smallest and largest.
    pub zones_per_joint: (usize, usize),
    pub concrete_elements: usize,
    pub rock_elements: usize,
    pub nodes: usize,
    pub thermal_dofs: usize,
    /// 3 × nodes.
    pub mechanical_dofs: usize,
    pub min_jacobian: Option<Worst>,
    pub worst_aspect: Option<Worst>,
    /// Where the two worst elements are (`block 4 lift 7`, `the rock`).
    pub jacobian_part: String,
    pub aspect_part: String,
}

fn part_of(mesh: &Mesh, w: Option<Worst>) -> String {
    match w.and_then(|w| mesh.parts.get(w.element)) {
        Some(Part::Concrete { block, lift }) => format!("block {block} lift {lift}"),
        Some(Part::Rock) => "the rock".into(),
        None => String::new(),
    }
}

fn min_max<T: Copy + Ord + Default>(it: impl Iterator<Item = T>) -> (T, T) {
    it.fold(None, |acc: Option<(T, T)>, v| {
        Some(acc.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
    })
    .unwrap_or_default()
}

impl MeshSummary {
    pub fn of(mesh: &Mesh) -> MeshSummary {
        let joints = mesh.joint_count();
        let zones_per_joint =
            min_max((1..=joints).map(|j| mesh.zones.iter().filter(|z| z.joint == j).count()));
        let rock = mesh
            .parts
            .iter()
            .filter(|p| matches!(p, Part::Rock))
            .count();
        let min_jacobian = quality::min_jacobian(&mesh.nodes, &mesh.elements);
        let worst_aspect = quality::worst_aspect(&mesh.nodes, &mesh.elements);
        MeshSummary {
            blocks: mesh.blocks.len(),
            lifts: min_max(mesh.blocks.iter().map(|b| b.n_lifts)),
            joints,
            zones_per_joint,
            concrete_elements: mesh.elements.len() - rock,
            rock_elements: rock,
            nodes: mesh.nodes.len(),
            thermal_dofs: mesh.n_thermal_dofs,
            mechanical_dofs: 3 * mesh.nodes.len(),
            jacobian_part: part_of(mesh, min_jacobian),
            aspect_part: part_of(mesh, worst_aspect),
            min_jacobian,
            worst_aspect,
        }
    }
}

/// `element 124 (ParaView cell 123, block 4 lift 7)`: the number in the
/// `.msh` / `.inp` files, the 0-based cell of the `.vtu`.
fn element_words(e: usize, part: &str) -> String {
    format!("element {} (ParaView cell {e}, {part})", e + 1)
}

impl fmt::Display for MeshSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "blocks: {}, lifts per block {}–{}",
            self.blocks, self.lifts.0, self.lifts.1
        )?;
        let (z0, z1) = self.zones_per_joint;
        writeln!(
            f,
            "joints: {}, grouting zones per joint {z0}–{z1}",
            self.joints
        )?;
        writeln!(
            f,
            "elements: {} ({} concrete, {} rock)",
            self.concrete_elements + self.rock_elements,
            self.concrete_elements,
            self.rock_elements
        )?;
        writeln!(f, "nodes: {}", self.nodes)?;
        writeln!(f, "thermal dofs: {}", self.thermal_dofs)?;
        writeln!(f, "mechanical dofs: {} (3 per node)", self.mechanical_dofs)?;
        if let Some(w) = self.min_jacobian {
            writeln!(
                f,
                "smallest Jacobian determinant: {:.6e} m³ at corner {} of {}",
                w.value,
                w.corner,
                element_words(w.element, &self.jacobian_part)
            )?;
        }
        if let Some(w) = self.worst_aspect {
            writeln!(
                f,
                "worst aspect ratio (longest / shortest edge): {:.3} in {}",
                w.value,
                element_words(w.element, &self.aspect_part)
            )?;
        }
        Ok(())
    }
}

/// Per element, the grouting zone of its lift (0 for rock).
pub fn zone_of_elements(mesh: &Mesh) -> Vec<u32> {
    mesh.parts
        .iter()
        .map(|p| match *p {
            Part::Concrete { block, lift } => mesh
                .layer_of_lift(block, lift)
                .map_or(0, |layer| mesh.zone_of_layer(layer)),
            Part::Rock => 0,
        })
        .collect()
}

/// Per node, the joint whose face pairs hold it (0 for none).
pub fn joint_of_nodes(mesh: &Mesh) -> Vec<u32> {
    let mut joint = vec![0u32; mesh.nodes.len()];
    for fp in &mesh.face_pairs {
        for &n in fp.nodes_a.iter().chain(&fp.nodes_b) {
            joint[n as usize] = fp.joint;
        }
    }
    joint
}

/// Writes `mesh` to `path` in the format of its extension; `source` names
/// the scene in the `.msh` / `.inp` files.
pub fn write_mesh(mesh: &Mesh, path: &Path, source: &str) -> Result<MeshOut, MeshCommandError> {
    let format =
        MeshOut::of(path).ok_or_else(|| MeshCommandError::Extension(path.display().to_string()))?;
    match format {
        MeshOut::Vtu => {
            let as_f64 = |v: Vec<u32>| v.into_iter().map(f64::from).collect::<Vec<f64>>();
            let zone = as_f64(zone_of_elements(mesh));
            let joint = as_f64(joint_of_nodes(mesh));
            crate::mesh::vtu::write_vtu(path, mesh, &[("joint", &joint)], &[("zone", &zone)], None)
                .map_err(MeshFileError::io(path))?;
        }
        MeshOut::Msh => import::write_msh(&RawMesh::from_mesh(mesh, source), path)?,
        MeshOut::Inp => import::write_inp(&RawMesh::from_mesh(mesh, source), path)?,
    }
    Ok(format)
}

/// `groutready mesh SCENE --out FILE`: builds the scene's mesh, writes it
/// and returns its summary. The extension is checked before the mesh is built.
pub fn mesh(scene_path: &Path, out: &Path) -> Result<MeshSummary, MeshCommandError> {
    if MeshOut::of(out).is_none() {
        return Err(MeshCommandError::Extension(out.display().to_string()));
    }
    let scene = Scene::load(scene_path).map_err(AppError::from)?;
    let source = scene_path.display().to_string();
    let mesh = super::build_mesh(&scene, &source)?;
    write_mesh(&mesh, out, &source)?;
    Ok(MeshSummary::of(&mesh))
}
