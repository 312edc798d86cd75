//! Placeholder: a RawMesh to a dam Mesh (being written).
