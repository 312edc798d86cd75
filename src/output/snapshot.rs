//! VTU snapshots of the live mesh, written from what the simulation hands
//! out ([`crate::sim::Snapshot`]).

use std::io;
use std::path::Path;

use crate::mesh::{vtu, Mesh};
use crate::sim::Snapshot;

pub fn write(path: &Path, mesh: &Mesh, snap: &Snapshot) -> io::Result<()> {
    let pf: Vec<(&str, &[f64])> = snap
        .point_fields
        .iter()
        .map(|(n, v)| (n.as_str(), v.as_slice()))
        .collect();
    let cf: Vec<(&str, &[f64])> = snap
        .cell_fields
        .iter()
        .map(|(n, v)| (n.as_str(), v.as_slice()))
        .collect();
    vtu::write_vtu(path, mesh, &pf, &cf, Some(&snap.live))
}
