//! The `arch` generator: a parametric double-curvature arch dam in a valley.
//!
//! # Shape
//!
//! With H the height, `base` the deepest foundation, crest = base + H and
//! ζ = (z − base)/H ∈ [0, 1]:
//!
//! * upstream-face radius R(ζ) = R_b + (R_c − R_b)·ζ;
//! * thickness t(ζ) = t_c + (t_b − t_c)·(1 − ζ)^k (k = `thickness_exponent`);
//! * overhang bump g(ζ) = 27/4·ζ²·(1 − ζ): g(0) = g(1) = 0, g′(0) = 0 (the
//!   upstream face leaves the foundation vertically), maximum g(2/3) = 1;
//! * the horizontal arch ring at ζ has its centre of curvature downstream at
//!   (0, y_c(ζ)), y_c = R(ζ) − overhang·g(ζ): the crown's upstream face is at
//!   y = −overhang·g(ζ) (the whole ring leans upstream by that amount);
//! * a point at angle φ (0 at the crown, positive towards the right bank) and
//!   across fraction a ∈ [0, 1] (0 upstream face, 1 downstream face) is
//!   (r sin φ, y_c − r cos φ, z) with r = R − a·t; the downstream face has
//!   radius R − t (must stay > 0).
//!
//! Blocks are equal angular sectors of the central angle Φ: block b spans
//! φ ∈ [−Φ/2 + (b−1)Φ/N, −Φ/2 + bΦ/N]. Joint planes are radial (φ = const),
//! so the duplicated joint nodes pair exactly.
//!
//! # Valley
//!
//! Block b's centre lies at f_b = (2b − 1 − N)/N along the crest (−1 left
//! abutment, +1 right). Its height is
//! h_b = H·max(m, (1 − |f_b|^v)/(1 − f_min^v)) (v = `valley_exponent`,
//! m = `min_block_height_fraction`, f_min = the smallest |f_b|, so the
//! central block(s) reach the base); its foundation crest − h_b is then
//! rounded **down** to a zone boundary (zones are bands of `zone_lifts` lifts
//! from the base), so every joint holds whole zones. Concrete layers are
//! global: layer l spans [base + l·lift, base + (l+1)·lift]; when H is not a
//! whole number of lifts the crest layer absorbs the remainder (it is between
//! 0.5 and 1.5 lifts high).
//!
//! # Rock
//!
//! The logical grid is i along the arc (`rock_margin_elements` beyond each
//! abutment, `elements_per_block` per block), j across (margin upstream,
//! `elements_across`, margin downstream), k up (`rock_layers` over
//! `rock_depth_m` below the base, then one layer per lift up to the crest).
//! Rock fills: everything below the base; under each block up to its
//! foundation (upstream and downstream margins too: the valley floor there is
//! the block's foundation level); beyond the abutments up to the crest. Where
//! a block is founded lower than its neighbour, its side face below the
//! neighbour's foundation touches rock (shared nodes, no joint).
//! Margin nodes: upstream radially (r = R + u·margin), downstream along +y
//! (the downstream face point + u·margin·ŷ, which avoids the centre of
//! curvature when the margin is wider than R − t), beyond the abutments along
//! the crest tangent of the last joint plane (± u·margin·(cos φ, sin φ)).
//! Rock below the base uses the base ring.
//!
//! With `rock_grading_ratio` r > 1 the margins and the rock below are
//! graded ([`grid::Spacing::graded`]): cells growing by r away from the dam,
//! the first at most as large as the concrete cell next to it — the crest
//! ring's element along the arc at mid-thickness ((R_c − t_c/2)·Φ/n, n the
//! elements along the whole arc) beyond the abutments, the base thickness
//! over `elements_across` upstream and downstream, and the lift height
//! below — their count per direction the least that reaches the margin (or
//! the depth); `rock_layers` and `rock_margin_elements` are then not used.
//! Which far face of this rock faces which side is
//! [`super::far::DamFrame::face_reading`]'s rule.
//!
//! Since every node of a level k has
//! the same z, each hex's corner Jacobian is Δz times the signed area of its
//! plan corner, positive for all these maps while Φ < 180° and R − t > 0.
//!
//! The layout (levels, margins, rock, zone rounding, node placement) is
//! shared with [`super::arch_table`]: [`block_row`], [`layer_boundaries`],
//! [`zone_floor`] and [`node_positions`] over an [`ArchPlan`], the plan
//! point of a level at an along-parameter (here φ) and across position.

use super::geometry::{at_least, check, non_negative, positive, ArchGeometry};
use super::grid::{self, BlockRow, Layers, Margins, Spacing};
use super::{Mesh, MeshError};

/// The arch's ring at one elevation.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ring {
    /// Upstream-face radius.
    r_up: f64,
    /// Thickness.
    t: f64,
    /// y of the centre of curvature.
    yc: f64,
}

/// Overhang bump g(ζ) = 27/4·ζ²(1 − ζ), clamped to ζ ∈ [0, 1].
pub fn overhang_bump(zeta: f64) -> f64 {
    let z = zeta.clamp(0.0, 1.0);
    6.75 * z * z * (1.0 - z)
}

fn ring(p: &ArchGeometry, z: f64) -> Ring {
    let h = p.height_m;
    let zeta = ((z - p.base_elevation_m) / h).clamp(0.0, 1.0);
    let r_up = p.base_radius_m + (p.crest_radius_m - p.base_radius_m) * zeta;
    let t = p.crest_thickness_m
        + (p.base_thickness_m - p.crest_thickness_m) * (1.0 - zeta).powf(p.thickness_exponent);
    let yc = r_up - p.overhang_m * overhang_bump(zeta);
    Ring { r_up, t, yc }
}

/// Foundation layer (global layer index, on a zone boundary) of every block.
fn foundation_layers(p: &ArchGeometry, layer_z: &[f64], zone_lifts: u32) -> Vec<u32> {
    let n = p.n_blocks as f64;
    let v = p.valley_exponent;
    let fs: Vec<f64> = (1..=p.n_blocks)
        .map(|b| ((2 * b) as f64 - 1.0 - n) / n)
        .collect();
    let f_min = fs.iter().fold(f64::INFINITY, |m, f| m.min(f.abs()));
    let norm = 1.0 - f_min.powf(v);
    let h = p.height_m;
    let crest = p.base_elevation_m + h;
    fs.iter()
        .map(|f| {
            let shape = if norm > 0.0 {
                (1.0 - f.abs().powf(v)) / norm
            } else {
                1.0
            };
            let zf = crest - h * shape.max(p.min_block_height_fraction).min(1.0);
            zone_floor(layer_z, zf, zone_lifts)
        })
        .collect()
}

/// The highest zone boundary (a global layer index) at or below elevation
/// `zf`, the lowest when `zf` is below the base: a block founded there
/// holds whole zones.
pub(super) fn zone_floor(layer_z: &[f64], zf: f64, zone_lifts: u32) -> u32 {
    let n_layers = layer_z.len() - 1;
    let h = layer_z[n_layers] - layer_z[0];
    let tol = 1e-9 * (1.0 + h);
    let mut base = 0usize;
    let mut l = 0usize;
    while l < n_layers {
        if layer_z[l] <= zf + tol {
            base = l;
        }
        l += zone_lifts as usize;
    }
    base as u32
}

/// Build the arch mesh of [`ArchGeometry`] with lifts of `lift_height` (m) and
/// grouting zones of `zone_height` (m) (a whole number of lifts).
pub fn generate_arch(
    p: &ArchGeometry,
    lift_height: f64,
    zone_height: f64,
) -> Result<Mesh, MeshError> {
    let zone_lifts = check_params(p, lift_height, zone_height)?;
    let layer_z = layer_boundaries(p.base_elevation_m, p.height_m, lift_height)?;
    let n_layers = layer_z.len() - 1;
    let (row, rock) = block_row(&RowCounts {
        n_blocks: p.n_blocks,
        elements_per_block: p.elements_per_block,
        elements_across: p.elements_across,
        rock_depth_m: p.rock_depth_m,
        rock_layers: p.rock_layers,
        rock_margin_m: p.rock_margin_m,
        rock_margin_elements: p.rock_margin_elements,
        rock_grading_ratio: p.rock_grading_ratio,
        face_element_m: p.face_element_m,
        joint_element_m: p.joint_element_m,
        first_cells_m: [
            (p.crest_radius_m - 0.5 * p.crest_thickness_m) * p.central_angle_deg.to_radians()
                / (p.n_blocks as f64 * p.elements_per_block as f64),
            p.base_thickness_m / p.elements_across as f64,
            lift_height,
        ],
        n_layers,
    })?;
    let zs = row.level_z(p.base_elevation_m, p.rock_depth_m, rock.below, &layer_z);
    let rings = rings(p, &zs)?;
    let phi_total = p.central_angle_deg.to_radians();
    let nd = p.n_blocks as usize * p.elements_per_block as usize;
    let epb = p.elements_per_block as usize;
    // the joint element is measured on the crest's centre line
    let crest_block =
        (p.crest_radius_m - 0.5 * p.crest_thickness_m) * phi_total / p.n_blocks as f64;
    let a = grid::graded_fractions(epb, crest_block, p.joint_element_m);
    let along: Vec<f64> = (0..=nd)
        .map(|i| match p.joint_element_m {
            None => -0.5 * phi_total + phi_total * i as f64 / nd as f64,
            Some(_) => {
                let (b, e) = (i / epb, i % epb);
                -0.5 * phi_total + phi_total * (b as f64 + a[e]) / p.n_blocks as f64
            }
        })
        .collect();
    let pos = node_positions(rings.as_slice(), &row, &rock, &along, &zs, p.face_element_m);
    let blocks = foundation_layers(p, &layer_z, zone_lifts)
        .into_iter()
        .map(|b| (b, n_layers as u32 - b))
        .collect();
    let layers = Layers {
        z: layer_z,
        lift_height,
        zone_lifts,
        per_lift: 1,
        blocks,
    };
    row.build(pos, layers)
}

/// The cell counts of an arch's [`BlockRow`] (both arch generators).
pub(super) struct RowCounts {
    pub n_blocks: u32,
    pub elements_per_block: u32,
    pub elements_across: u32,
    pub rock_depth_m: f64,
    pub rock_layers: u32,
    pub rock_margin_m: f64,
    pub rock_margin_elements: u32,
    /// Growth of the rock cells away from the dam (1: the uniform counts).
    pub rock_grading_ratio: f64,
    /// The concrete's face element across (None: equal elements across).
    pub face_element_m: Option<f64>,
    /// The element along next to each joint (None: equal elements along).
    pub joint_element_m: Option<f64>,
    /// The concrete cells the graded rock starts from \[m\]: along the arc
    /// (beyond the abutments), across (upstream and downstream), and the
    /// lift height (below).
    pub first_cells_m: [f64; 3],
    /// Concrete element layers (one per lift).
    pub n_layers: usize,
}

/// The grid of an arch and the spacing of its rock, its counts checked
/// first (both arch generators' keys of the same names).
pub(super) fn block_row(c: &RowCounts) -> Result<(BlockRow, RockSpacing), MeshError> {
    at_least("elements_per_block", c.elements_per_block, 1)?;
    at_least("elements_across", c.elements_across, 1)?;
    non_negative("rock_depth_m", c.rock_depth_m)?;
    non_negative("rock_margin_m", c.rock_margin_m)?;
    if c.rock_depth_m > 0.0 {
        at_least("rock_layers", c.rock_layers, 1)?;
    }
    if c.rock_margin_m > 0.0 {
        at_least("rock_margin_elements", c.rock_margin_elements, 1)?;
    }
    grid::grading_ratio(c.rock_grading_ratio)?;
    grid::end_element("face_element_m", c.face_element_m)?;
    grid::end_element("joint_element_m", c.joint_element_m)?;
    let rock = RockSpacing::of(c);
    let row = BlockRow {
        n_blocks: c.n_blocks,
        elements_per_block: c.elements_per_block,
        elements_across: c.elements_across,
        margin: Margins {
            left: rock.along.count,
            right: rock.along.count,
            upstream: rock.across.count,
            downstream: rock.across.count,
        },
        rock_layers: rock.below.count,
        layers: c.n_layers as u64,
        rock_beyond_abutments: true,
    };
    row.size()?;
    Ok((row, rock))
}

/// Checks every parameter in scene order; returns the lifts per zone.
fn check_params(p: &ArchGeometry, lift_height: f64, zone_height: f64) -> Result<u32, MeshError> {
    at_least("n_blocks", p.n_blocks, 2)?;
    positive("height_m", p.height_m)?;
    check(p.base_elevation_m.is_finite(), "base_elevation_m", || {
        format!("must be finite, got {}", p.base_elevation_m)
    })?;
    positive("crest_radius_m", p.crest_radius_m)?;
    positive("base_radius_m", p.base_radius_m)?;
    check(
        p.central_angle_deg.is_finite() && p.central_angle_deg > 0.0 && p.central_angle_deg < 180.0,
        "central_angle_deg",
        || format!("must be in (0, 180), got {}", p.central_angle_deg),
    )?;
    positive("crest_thickness_m", p.crest_thickness_m)?;
    positive("base_thickness_m", p.base_thickness_m)?;
    positive("thickness_exponent", p.thickness_exponent)?;
    check(p.overhang_m.is_finite(), "overhang_m", || {
        format!("must be finite, got {}", p.overhang_m)
    })?;
    positive("valley_exponent", p.valley_exponent)?;
    check(
        p.min_block_height_fraction.is_finite()
            && p.min_block_height_fraction > 0.0
            && p.min_block_height_fraction <= 1.0,
        "min_block_height_fraction",
        || format!("must be in (0, 1], got {}", p.min_block_height_fraction),
    )?;
    grid::zone_lifts(lift_height, zone_height)
}

/// The rock cells of the three directions: margins along the arc (beyond
/// the abutments) and across (upstream, downstream), layers below.
pub(super) struct RockSpacing {
    pub along: Spacing,
    pub across: Spacing,
    pub below: Spacing,
}

impl RockSpacing {
    /// The scene's uniform counts at ratio 1; above it graded from the sizes
    /// of the concrete cells next to the rock (module doc, "Rock").
    fn of(c: &RowCounts) -> RockSpacing {
        let r = c.rock_grading_ratio;
        let margin = c.rock_margin_m;
        let [first_along, first_across, first_below] = c.first_cells_m;
        let side = |first: f64| {
            if margin <= 0.0 {
                Spacing::uniform(0, 0.0)
            } else if r == 1.0 {
                Spacing::uniform(c.rock_margin_elements as usize, margin)
            } else {
                Spacing::graded(margin, first, r)
            }
        };
        RockSpacing {
            along: side(first_along),
            across: side(first_across),
            below: if c.rock_depth_m <= 0.0 {
                Spacing::uniform(0, 0.0)
            } else if r == 1.0 {
                Spacing::uniform(c.rock_layers as usize, c.rock_depth_m)
            } else {
                Spacing::graded(c.rock_depth_m, first_below, r)
            },
        }
    }
}

/// Concrete layer boundaries from `base` over the height `h`: one layer per
/// lift, the crest layer absorbing the remainder of the height.
pub(super) fn layer_boundaries(base: f64, h: f64, lift_height: f64) -> Result<Vec<f64>, MeshError> {
    let ratio = h / lift_height;
    check(ratio < 1e6, "height_m", || {
        format!("is more than a million lifts ({h} m with {lift_height} m lifts)")
    })?;
    let n_layers = (ratio.round() as usize).max(1);
    let mut layer_z: Vec<f64> = (0..n_layers)
        .map(|l| base + l as f64 * lift_height)
        .collect();
    layer_z.push(base + h);
    Ok(layer_z)
}

/// The ring of every logical level `zs`; an error when the downstream face
/// would reach the centre of curvature.
fn rings(p: &ArchGeometry, zs: &[f64]) -> Result<Vec<Ring>, MeshError> {
    let rings: Vec<Ring> = zs.iter().map(|&z| ring(p, z)).collect();
    for (k, r) in rings.iter().enumerate() {
        let rd = r.r_up - r.t;
        // also rejects NaN
        if rd.partial_cmp(&(1e-6 * r.r_up)) != Some(std::cmp::Ordering::Greater) {
            return Err(MeshError::param(
                "base_thickness_m",
                format!(
                    "leaves no room for the arch: at z = {} the thickness {} m reaches the upstream radius {} m \
                     (thickness must stay below the radius)",
                    zs[k], r.t, r.r_up
                ),
            ));
        }
    }
    Ok(rings)
}

/// Where a grid line j lies across the dam (module doc, "Rock").
#[derive(Debug, Clone, Copy)]
pub(super) enum Across {
    /// This far \[m\] beyond the upstream face, along its outward normal.
    Upstream(f64),
    /// Fraction a ∈ [0, 1] of the way from the upstream to the downstream face.
    Dam(f64),
    /// This far \[m\] beyond the downstream face, along +y.
    Downstream(f64),
}

/// An arch's plan shape at each logical level: what [`node_positions`]
/// needs from a generator.
pub(super) trait ArchPlan {
    /// Plan point (x, y) at level `k`, along-parameter `u` (a grid i-line of
    /// the dam; for both arch generators the angle φ of its normal) and
    /// across position `across`, moved `ext` metres along the arch's tangent
    /// at `u` (towards increasing `u`; the rock beyond the abutments).
    fn plan_point(&self, k: usize, u: f64, across: Across, ext: f64) -> [f64; 2];

    /// The dam's thickness at level `k` and along-parameter `u` \[m\], as
    /// [`Across::Dam`] measures it (the cells across are graded on it).
    fn thickness(&self, k: usize, u: f64) -> f64;
}

impl ArchPlan for [Ring] {
    fn plan_point(&self, k: usize, phi: f64, across: Across, ext: f64) -> [f64; 2] {
        let rg = self[k];
        let (r, dy) = match across {
            Across::Upstream(d) => (rg.r_up + d, 0.0),
            Across::Dam(a) => (rg.r_up - rg.t * a, 0.0),
            Across::Downstream(d) => (rg.r_up - rg.t, d),
        };
        let (s, c) = phi.sin_cos();
        [r * s + ext * c, rg.yc - r * c + dy + ext * s]
    }

    fn thickness(&self, k: usize, _phi: f64) -> f64 {
        self[k].t
    }
}

/// Grid nodes (i fastest) of the levels `zs`: the dam's i-lines at the
/// along-parameters `along` (`n_blocks·elements_per_block + 1` of them),
/// across it from the upstream to the downstream face, the upstream margin
/// along the face's normal, the downstream one along +y, the margins beyond
/// the abutments along the end tangents (module doc, "Rock"); the dam's
/// cells across equal, or graded from a `face` element at both faces on the
/// local thickness ([`grid::graded_fractions`]).
pub(super) fn node_positions(
    plan: &(impl ArchPlan + ?Sized),
    row: &BlockRow,
    rock: &RockSpacing,
    along_u: &[f64],
    zs: &[f64],
    face: Option<f64>,
) -> Vec<[f64; 3]> {
    let (ma, mc) = (rock.along.count, rock.across.count);
    let na = row.elements_across as usize;
    let nd = along_u.len() - 1;
    let (ni, nj) = (nd + 2 * ma, na + 2 * mc);
    // Per i: (along-parameter, extension along the tangent).
    let along: Vec<(f64, f64)> = (0..=ni)
        .map(|i| {
            if i < ma {
                (along_u[0], -rock.along.distance(ma - i))
            } else if i > ma + nd {
                (along_u[nd], rock.along.distance(i - ma - nd))
            } else {
                (along_u[i - ma], 0.0)
            }
        })
        .collect();

    let mut pos = Vec::with_capacity((ni + 1) * (nj + 1) * zs.len());
    for (k, &z) in zs.iter().enumerate() {
        // the fractions across of every i-line of this level
        let fractions: Vec<Vec<f64>> = along
            .iter()
            .map(|&(u, _)| grid::graded_fractions(na, plan.thickness(k, u), face))
            .collect();
        for j in 0..=nj {
            for (i, &(u, ext)) in along.iter().enumerate() {
                let across = if j < mc {
                    Across::Upstream(rock.across.distance(mc - j))
                } else if j <= mc + na {
                    Across::Dam(fractions[i][j - mc])
                } else {
                    Across::Downstream(rock.across.distance(j - mc - na))
                };
                let [x, y] = plan.plan_point(k, u, across, ext);
                pos.push([x, y, z]);
            }
        }
    }
    pos
}
