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
//!
//! With `rock_grading_ratio` r > 1 the rock is graded instead: each margin
//! and the rock below are cut into cells growing geometrically by r away
//! from the dam, the first as large as the concrete cell it touches at most
//! (L / `elements_per_block` beyond the abutments, thickness /
//! `elements_across` upstream and downstream, the lift height /
//! `layers_per_lift` below), their count per direction the least that
//! reaches the margin with that first cell ([`grid::Spacing::graded`]); the
//! counts `rock_layers` and `rock_margin_elements` are then not used.

use super::geometry::{at_least, non_negative, positive, BlocksGeometry};
use super::grid::{self, BlockRow, Layers, Margins, Spacing};
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
    let dz = lift_height / p.layers_per_lift as f64;
    let rock = RockSpacing::of(p, dz);
    let row = BlockRow {
        n_blocks: p.n_blocks,
        elements_per_block: p.elements_per_block,
        elements_across: p.elements_across,
        margin: Margins {
            left: rock.along.count,
            right: rock.along.count,
            upstream: rock.across.count,
            downstream: rock.across.count,
        },
        rock_layers: if has_rock { rock.below.count } else { 0 },
        layers: p.n_lifts as u64 * p.layers_per_lift as u64,
        rock_beyond_abutments: false,
    };
    row.size()?;
    let layer_z: Vec<f64> = (0..=row.layers as usize)
        .map(|l| p.base_elevation_m + l as f64 * dz)
        .collect();
    let pos = node_positions(p, &row, &rock, &layer_z);
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
    grid::grading_ratio(p.rock_grading_ratio)?;
    grid::end_element("face_element_m", p.face_element_m)?;
    grid::end_element("joint_element_m", p.joint_element_m)?;
    Ok(zone_lifts)
}

/// The rock cells of the three directions: margins along x (beyond the
/// abutments) and y (upstream, downstream), layers below.
struct RockSpacing {
    along: Spacing,
    across: Spacing,
    below: Spacing,
}

impl RockSpacing {
    /// Uniform counts of the scene at ratio 1, graded from the concrete
    /// cells' sizes (`dz` the concrete layer height) above it; no margin
    /// without rock or with a zero margin.
    fn of(p: &BlocksGeometry, dz: f64) -> RockSpacing {
        let has_rock = p.rock_depth_m > 0.0;
        let margin = if has_rock { p.rock_margin_m } else { 0.0 };
        let r = p.rock_grading_ratio;
        let side = |count: u32, first: f64| {
            if margin <= 0.0 {
                Spacing::uniform(0, 0.0)
            } else if r == 1.0 {
                Spacing::uniform(count as usize, margin)
            } else {
                Spacing::graded(margin, first, r)
            }
        };
        RockSpacing {
            along: side(
                p.rock_margin_elements,
                p.block_length_m / p.elements_per_block as f64,
            ),
            across: side(
                p.rock_margin_elements,
                p.thickness_m / p.elements_across as f64,
            ),
            below: if r == 1.0 || !has_rock {
                Spacing::uniform(p.rock_layers as usize, p.rock_depth_m)
            } else {
                Spacing::graded(p.rock_depth_m, dz, r)
            },
        }
    }
}

/// Grid nodes on the axis-aligned lines of [`axis`], i fastest.
fn node_positions(
    p: &BlocksGeometry,
    row: &BlockRow,
    rock: &RockSpacing,
    layer_z: &[f64],
) -> Vec<[f64; 3]> {
    let epb = p.elements_per_block as usize;
    let na = p.elements_across as usize;
    let length = p.n_blocks as f64 * p.block_length_m;
    let mut xs = axis(
        &rock.along,
        p.n_blocks as usize * epb,
        p.block_length_m,
        epb,
        length,
    );
    if p.joint_element_m.is_some() {
        let m = rock.along.count;
        let a = grid::graded_fractions(epb, p.block_length_m, p.joint_element_m);
        for b in 0..p.n_blocks as usize {
            let x0 = b as f64 * p.block_length_m;
            for (e, f) in a.iter().enumerate().skip(1).take(epb - 1) {
                xs[m + b * epb + e] = x0 + f * p.block_length_m;
            }
        }
    }
    let mut ys = axis(&rock.across, na, p.thickness_m, na, p.thickness_m);
    if p.face_element_m.is_some() {
        let m = rock.across.count;
        let a = grid::graded_fractions(na, p.thickness_m, p.face_element_m);
        for (y, f) in ys[m..=m + na].iter_mut().zip(a) {
            *y = f * p.thickness_m;
        }
    }
    let zs = row.level_z(p.base_elevation_m, p.rock_depth_m, rock.below, layer_z);
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

/// Grid lines along x or y: the margin's cells before 0, `n` cells of
/// `len / per` each, the margin's cells beyond `end` (uniform margins by
/// the expressions of the first version, so their meshes stay bit-identical).
fn axis(margin: &Spacing, n: usize, len: f64, per: usize, end: f64) -> Vec<f64> {
    let (m, width) = (margin.count, margin.length);
    (0..=n + 2 * m)
        .map(|i| {
            if i < m && margin.ratio == 1.0 {
                -width + width * i as f64 / m as f64
            } else if i < m {
                -margin.distance(m - i)
            } else if i <= m + n {
                (i - m) as f64 * len / per as f64
            } else if margin.ratio == 1.0 {
                end + width * (i - m - n) as f64 / m as f64
            } else {
                end + margin.distance(i - m - n)
            }
        })
        .collect()
}
