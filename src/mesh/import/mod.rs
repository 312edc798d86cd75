//! Meshes from outside: an analyst's hexahedral mesh of the dam (Gmsh MSH 4.1,
//! Abaqus/CalculiX `.inp`) read into a [`RawMesh`] (what the file says:
//! nodes, 8-node hexahedra, named groups), then turned into a dam [`Mesh`]
//! (blocks, lifts, joints, zones, zone points, surfaces) by [`dam`].
//!
//! The two steps are separate so that each file format only has to produce
//! a [`RawMesh`], and the dam's rules (joints found as faces shared by two
//! blocks, lifts as element layers by elevation, …) are written once.
//!
//! # Conventions of a [`RawMesh`]
//!
//! * Hexahedra are in the VTK / Gmsh / Abaqus C3D8 corner order (the three
//!   agree: corners 0–3 the bottom face, 4–7 the top, see
//!   `docs/ARCHITECTURE.md`); their orientation is not yet the dam's (the
//!   dam step re-orders each element's corners).
//! * `node_ids` and `elem_ids` are the numbers the file gave (for messages);
//!   every index stored elsewhere is 0-based into `nodes` / `hexes`.
//! * Element groups come from Gmsh physical groups of dimension 3 or Abaqus
//!   `*ELSET`s (and `*ELEMENT, ELSET=`); node groups from Gmsh physical groups
//!   of dimension 2 (the nodes of their faces) or `*NSET`s. The dam step
//!   reads the parts `block_<n>` and `rock`, the optional lifts
//!   `block_<n>_lift_<m>`, and the optional surface overrides `far`, `air`,
//!   `upstream` (a boundary face belongs to a node group when its four
//!   corners do).

pub mod dam;
pub mod file;
pub mod inp;
pub mod msh;

pub use file::{read_file, write_file, MeshFileError, MeshFormat};
pub use inp::{read_inp, write_inp};
pub use msh::{read_msh, write_msh, write_msh_binary};

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{Mesh, Part};

/// What a mesh file says, before any dam rule is applied.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RawMesh {
    /// The file it came from, as the user named it (for messages).
    pub source: String,
    pub nodes: Vec<[f64; 3]>,
    /// The file's number of each node, parallel to `nodes`.
    pub node_ids: Vec<u64>,
    /// 8-node hexahedra, corners as indices into `nodes` (VTK order).
    pub hexes: Vec<[u32; 8]>,
    /// The file's number of each hexahedron, parallel to `hexes`.
    pub elem_ids: Vec<u64>,
    /// Named element groups: name → indices into `hexes`, sorted, no repeats.
    pub element_groups: BTreeMap<String, Vec<u32>>,
    /// Named node groups: name → indices into `nodes`, sorted, no repeats.
    pub node_groups: BTreeMap<String, Vec<u32>>,
}

impl RawMesh {
    /// The raw form of a dam mesh (what `groutready mesh` writes): its nodes
    /// and hexahedra in order, numbered from 1, with the element groups
    /// `block_<n>` and `rock` (the latter only when there is rock).
    pub fn from_mesh(mesh: &Mesh, source: &str) -> RawMesh {
        let mut element_groups: BTreeMap<String, Vec<u32>> = BTreeMap::new();
        for (e, part) in mesh.parts.iter().enumerate() {
            let name = match part {
                Part::Concrete { block, .. } => format!("block_{block}"),
                Part::Rock => "rock".to_string(),
            };
            element_groups.entry(name).or_default().push(e as u32);
        }
        RawMesh {
            source: source.to_string(),
            nodes: mesh.nodes.clone(),
            node_ids: (1..=mesh.nodes.len() as u64).collect(),
            hexes: mesh.elements.clone(),
            elem_ids: (1..=mesh.elements.len() as u64).collect(),
            element_groups,
            node_groups: BTreeMap::new(),
        }
    }
}
