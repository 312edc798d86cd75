//! Hex8 meshes of dams: generators, joints, grouting zones, VTU output.

pub mod geometry;
