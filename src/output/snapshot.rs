//! VTU snapshots of the live mesh: temperature per node, block/lift/age per cell.

use std::io;
use std::path::Path;

use crate::mesh::{vtu, Part};
use crate::sim::Simulation;

pub fn write(path: &Path, sim: &Simulation<'_>) -> io::Result<()> {
    let mesh = sim.mesh;
    let live: Vec<u32> = match &sim.thermal {
        Some(th) => (0..mesh.elements.len() as u32)
            .filter(|&e| th.state.live[e as usize])
            .collect(),
        None => (0..mesh.elements.len() as u32).collect(),
    };
    let temperature = match &sim.thermal {
        Some(th) => th.nodal_field(mesh),
        None => vec![f64::NAN; mesh.nodes.len()],
    };
    let block: Vec<f64> = mesh
        .parts
        .iter()
        .map(|p| match p {
            Part::Concrete { block, .. } => *block as f64,
            Part::Rock => 0.0,
        })
        .collect();
    let lift: Vec<f64> = mesh
        .parts
        .iter()
        .map(|p| match p {
            Part::Concrete { lift, .. } => *lift as f64,
            Part::Rock => 0.0,
        })
        .collect();
    vtu::write_vtu(
        path,
        mesh,
        &[("temperature_c", temperature.as_slice())],
        &[("block", block.as_slice()), ("lift", lift.as_slice())],
        Some(&live),
    )
}
