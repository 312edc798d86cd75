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

use super::geometry::BlocksGeometry;
use super::grid::{self, Cell, Grid};
use super::{Mesh, MeshError};

fn positive(name: &str, v: f64) -> Result<(), MeshError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(MeshError::param(name, format!("must be > 0, got {v}")))
    }
}

fn non_negative(name: &str, v: f64) -> Result<(), MeshError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(MeshError::param(name, format!("must be >= 0, got {v}")))
    }
}

fn at_least_one(name: &str, v: u32) -> Result<(), MeshError> {
    if v >= 1 {
        Ok(())
    } else {
        Err(MeshError::param(name, format!("must be >= 1, got {v}")))
    }
}

/// Build the mesh of [`BlocksGeometry`] with lifts of `lift_height` (m) and
/// grouting zones of `zone_height` (m) (a whole number of lifts).
pub fn generate_blocks(
    p: &BlocksGeometry,
    lift_height: f64,
    zone_height: f64,
) -> Result<Mesh, MeshError> {
    at_least_one("n_blocks", p.n_blocks)?;
    positive("block_length_m", p.block_length_m)?;
    positive("thickness_m", p.thickness_m)?;
    at_least_one("n_lifts", p.n_lifts)?;
    at_least_one("elements_per_block", p.elements_per_block)?;
    at_least_one("elements_across", p.elements_across)?;
    at_least_one("layers_per_lift", p.layers_per_lift)?;
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
        at_least_one("rock_layers", p.rock_layers)?;
    } else if p.rock_margin_m > 0.0 {
        return Err(MeshError::param(
            "rock_margin_m",
            format!(
                "must be 0 when rock_depth_m is 0 (no rock), got {}",
                p.rock_margin_m
            ),
        ));
    }
    let has_margin = has_rock && p.rock_margin_m > 0.0;
    if has_margin {
        at_least_one("rock_margin_elements", p.rock_margin_elements)?;
    }

    let m = if has_margin {
        p.rock_margin_elements as usize
    } else {
        0
    };
    let rl = if has_rock { p.rock_layers as usize } else { 0 };
    let epb = p.elements_per_block as usize;
    let na = p.elements_across as usize;
    let lpl = p.layers_per_lift as usize;
    let n_layers_u64 = p.n_lifts as u64 * lpl as u64;
    let ni = (p.n_blocks as u64)
        .saturating_mul(epb as u64)
        .saturating_add(2 * m as u64);
    let nj = na as u64 + 2 * m as u64;
    let nk = n_layers_u64 + rl as u64;
    if ni > u32::MAX as u64 || nj > u32::MAX as u64 || nk > u32::MAX as u64 {
        return Err(MeshError::TooLarge {
            nodes: u64::MAX,
            elements: u64::MAX,
            limit: grid::MAX_ENTITIES,
        });
    }
    let (ni, nj, nk) = (ni as usize, nj as usize, nk as usize);
    grid::check_size(ni, nj, nk)?;
    let n_layers = n_layers_u64 as usize;
    let nb_cells = p.n_blocks as usize * epb;

    let base = p.base_elevation_m;
    let dz = lift_height / lpl as f64;
    let layer_z: Vec<f64> = (0..=n_layers).map(|l| base + l as f64 * dz).collect();

    let margin = p.rock_margin_m;
    let xs: Vec<f64> = (0..=ni)
        .map(|i| {
            if i < m {
                -margin + margin * i as f64 / m as f64
            } else if i <= m + nb_cells {
                (i - m) as f64 * p.block_length_m / epb as f64
            } else {
                p.n_blocks as f64 * p.block_length_m + margin * (i - m - nb_cells) as f64 / m as f64
            }
        })
        .collect();
    let ys: Vec<f64> = (0..=nj)
        .map(|j| {
            if j < m {
                -margin + margin * j as f64 / m as f64
            } else if j <= m + na {
                (j - m) as f64 * p.thickness_m / na as f64
            } else {
                p.thickness_m + margin * (j - m - na) as f64 / m as f64
            }
        })
        .collect();
    let zs: Vec<f64> = (0..=nk)
        .map(|k| {
            if k < rl {
                base - p.rock_depth_m + p.rock_depth_m * k as f64 / rl as f64
            } else {
                layer_z[k - rl]
            }
        })
        .collect();

    let mut pos = Vec::with_capacity((ni + 1) * (nj + 1) * (nk + 1));
    for &z in &zs {
        for &y in &ys {
            for &x in &xs {
                pos.push([x, y, z]);
            }
        }
    }
    let mut cells = Vec::with_capacity(ni * nj * nk);
    for k in 0..nk {
        for j in 0..nj {
            for i in 0..ni {
                let c = if k < rl {
                    Cell::Rock
                } else if i >= m && i < m + nb_cells && j >= m && j < m + na {
                    Cell::Concrete {
                        block: ((i - m) / epb) as u32 + 1,
                        layer: (k - rl) as u32,
                    }
                } else {
                    Cell::Void
                };
                cells.push(c);
            }
        }
    }

    grid::build(Grid {
        ni,
        nj,
        nk,
        pos,
        cells,
        j0: m,
        j1: m + na,
        layer_z,
        lift_height,
        zone_lifts,
        layers_per_lift: p.layers_per_lift,
        block_layers: vec![(0, p.n_lifts); p.n_blocks as usize],
    })
}
