//! The `blocks` generator: N rectangular blocks in a row on a rock foundation.
//!
//! Block *b* occupies x ∈ [(b−1)·L, b·L], y ∈ [0, thickness] (y = 0 is the
//! upstream face), z ∈ [base, base + n_lifts·lift_height]. With
//! `rock_depth_m > 0` rock fills z ∈ [base − depth, base] under the blocks and,
//! with `rock_margin_m > 0`, `rock_margin_m` beyond them on every side
//! (x < 0, x > N·L, y < 0, y > thickness); its top is at the base elevation.
//! Elements: `elements_per_block` along x per block, `elements_across` along y,
//! `layers_per_lift` per lift, `rock_layers` in the rock, `rock_margin_elements`
//! across each margin. Joints are the planes x = b·L, b = 1..N−1.

use super::geometry::{at_least, non_negative, positive, BlocksGeometry};
use super::grid::{self, BlockRow, Layers};
use super::{Mesh, MeshError};

/// Build the mesh of [`BlocksGeometry`] with lifts of `lift_height` (m) and
/// grouting zones of `zone_height` (m) (a whole number of lifts).
pub fn generate_blocks(
    p: &BlocksGeometry,
    lift_height: f64,
    zone_height: f64,
) -> Result<Mesh, MeshError> {
    let zone_lifts = check_params(p, lift_height, zone_height)?;
    let has_rock = p.rock_depth_m > 0.0;
    let row = BlockRow {
        n_blocks: p.n_blocks,
        elements_per_block: p.elements_per_block,
        elements_across: p.elements_across,
        margin: if has_rock && p.rock_margin_m > 0.0 {
            p.rock_margin_elements as usize
        } else {
            0
        },
        rock_layers: if has_rock { p.rock_layers as usize } else { 0 },
        layers: p.n_lifts as u64 * p.layers_per_lift as u64,
        rock_beyond_abutments: false,
    };
    row.size()?;
    let dz = lift_height / p.layers_per_lift as f64;
    let layer_z: Vec<f64> = (0..=row.layers as usize)
        .map(|l| p.base_elevation_m + l as f64 * dz)
        .collect();
    let pos = node_positions(p, &row, &layer_z);
    let layers = Layers {
        z: layer_z,
        lift_height,
        zone_lifts,
        per_lift: p.layers_per_lift,
        blocks: vec![(0, p.n_lifts); p.n_blocks as usize],
    };
    row.build(pos, layers)
}

/// Checks every parameter in scene order; returns the lifts per zone.
fn check_params(p: &BlocksGeometry, lift_height: f64, zone_height: f64) -> Result<u32, MeshError> {
    at_least("n_blocks", p.n_blocks, 1)?;
    positive("block_length_m", p.block_length_m)?;
    positive("thickness_m", p.thickness_m)?;
    at_least("n_lifts", p.n_lifts, 1)?;
    at_least("elements_per_block", p.elements_per_block, 1)?;
    at_least("elements_across", p.elements_across, 1)?;
    at_least("layers_per_lift", p.layers_per_lift, 1)?;
    non_negative("rock_depth_m", p.rock_depth_m)?;
    non_negative("rock_margin_m", p.rock_margin_m)?;
    if !p.base_elevation_m.is_finite() {
        return Err(MeshError::param(
            "base_elevation_m",
            format!("must be finite, got {}", p.base_elevation_m),
        ));
    }
    let zone_lifts = grid::zone_lifts(lift_height, zone_height)?;
    let has_rock = p.rock_depth_m > 0.0;
    if has_rock {
        at_least("rock_layers", p.rock_layers, 1)?;
    } else if p.rock_margin_m > 0.0 {
        return Err(MeshError::param(
            "rock_margin_m",
            format!(
                "must be 0 when rock_depth_m is 0 (no rock), got {}",
                p.rock_margin_m
            ),
        ));
    }
    if has_rock && p.rock_margin_m > 0.0 {
        at_least("rock_margin_elements", p.rock_margin_elements, 1)?;
    }
    Ok(zone_lifts)
}

/// Grid nodes on the axis-aligned lines of [`axis`], i fastest.
fn node_positions(p: &BlocksGeometry, row: &BlockRow, layer_z: &[f64]) -> Vec<[f64; 3]> {
    let (m, margin) = (row.margin, p.rock_margin_m);
    let epb = p.elements_per_block as usize;
    let na = p.elements_across as usize;
    let length = p.n_blocks as f64 * p.block_length_m;
    let xs = axis(
        m,
        margin,
        p.n_blocks as usize * epb,
        p.block_length_m,
        epb,
        length,
    );
    let ys = axis(m, margin, na, p.thickness_m, na, p.thickness_m);
    let zs = row.level_z(p.base_elevation_m, p.rock_depth_m, layer_z);
    let mut pos = Vec::with_capacity(xs.len() * ys.len() * zs.len());
    for &z in &zs {
        for &y in &ys {
            for &x in &xs {
                pos.push([x, y, z]);
            }
        }
    }
    pos
}

/// Grid lines along x or y: `m` margin cells over `margin` before 0, `n`
/// cells of `len / per` each, `m` margin cells beyond `end`.
fn axis(m: usize, margin: f64, n: usize, len: f64, per: usize, end: f64) -> Vec<f64> {
    (0..=n + 2 * m)
        .map(|i| {
            if i < m {
                -margin + margin * i as f64 / m as f64
            } else if i <= m + n {
                (i - m) as f64 * len / per as f64
            } else {
                end + margin * (i - m - n) as f64 / m as f64
            }
        })
        .collect()
}
