//! The part of a grouting zone inside its grout stops, where the deciding
//! aperture is read.
//!
//! # Definition
//!
//! A zone is sealed by grout stops (water stops) embedded in the joint near
//! the dam's upstream and downstream faces; the grout fills the joint between
//! them. Two readings of "inside the grout stops" (`[joints]
//! grout_stop_inset_m`):
//!
//! * **at a physical inset** (`grout_stop_inset_m = d`): the zone's deciding
//!   aperture (`ZonePoint::Min`) is the minimum of the finite-element
//!   aperture field over the zone's joint area at distance ≥ d from both
//!   faces, the distance measured along the joint face from its upstream
//!   (or downstream) edge. The quantity does not depend on the mesh, and
//!   converges as the mesh resolves the faces' thermal boundary layer;
//! * **one node in** (the key absent, the default): the minimum over the
//!   zone's joint nodes off the dam's faces. The nearest of them sits one
//!   element width from a face, so the point read moves with the mesh
//!   across the thickness. `groutready study accuracy` measured what that
//!   costs (README, "Accuracy and presets"): on the small dam successive
//!   meshes across differ by about 0.7 mm. It stays the default because
//!   today's meshes (3–7 m elements across) do not resolve the face layer
//!   at a 1 m inset either: read there, the field is mostly the face node's,
//!   and the demo's and small dam's zones all read below 0.5 mm on dates
//!   their sites grouted. Elements graded toward the faces are what makes the
//!   physical inset both converged and affordable.
//!
//! # Discretisation
//!
//! The joint faces of every mesh kind (blocks, arch, arch_table, imported)
//! are structured: a zone's face pairs lie in element layers, ordered from
//! upstream to downstream in each layer ([`crate::mesh::Zone::pairs`]), so
//! each layer's top and bottom edges are *node rows* from the upstream edge
//! to the downstream edge. On a row the aperture is linear in the arc length
//! between neighbouring nodes (the quad's edges are straight, the field
//! bilinear). The samples of a row at distances d from its upstream end,
//! row length L:
//!
//! * its nodes with `inset ≤ d ≤ L − inset`, and
//! * the field on the two inset lines, d = inset and d = L − inset, linearly
//!   interpolated between the two nodes that straddle it;
//! * when the row is shorter than two insets (`L < 2·inset`), the grout
//!   stops would overlap: the row's centre, d = L/2, alone (documented in the
//!   README's `[joints]` table).
//!
//! The bilinear field on a quad attains its minimum over a rectangle of its
//! reference coordinates at the rectangle's corners, so where the inset
//! line crosses a layer at one reference coordinate s (a layer of constant
//! thickness, every generated block mesh) these samples give the exact
//! minimum of the FE field over the area. Where the thickness changes
//! within a layer (arch faces) the inset line is slanted in (s, t); the
//! samples then give the minimum over the node rows, which is what the
//! joint points resolve anyway.
//!
//! Rows shared by two zones belong to the zone that owns their joint points
//! (the zone below, [`super::joints::build_points`]); a row on the rock
//! (its nodes shared by the two blocks, no joint point) has no sample, as a
//! point there carries no contact. A zone without any sample (no row of
//! its own) keeps its joint points as samples.
//!
//! # Verification
//!
//! `tests/it/joint_grout_stops.rs`: two blocks opened by a prescribed
//! separation linear across the thickness; the zone minimum equals the
//! closed form at the inset to 1e-9 relative for two meshes across (the
//! quantity does not move with the mesh), a section thinner than two insets
//! reads its centre, and the unit tests below check the row sampling; the
//! default (one node in) reads the field one element from the face, a
//! different value on each mesh.

use std::collections::{HashMap, HashSet};

use crate::fem::hex8::FACES;
use crate::mesh::{Mesh, SurfaceKind};

use super::joints::JointPoint;

/// One place where the zone minimum is sought: a joint point, or the field
/// interpolated between two neighbouring joint points of a node row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopSample {
    /// joint point indices (the second is unused when its weight is 0)
    pub points: [u32; 2],
    /// the linear weights of `points` (sum 1)
    pub weights: [f64; 2],
}

impl StopSample {
    fn at(point: u32) -> StopSample {
        StopSample {
            points: [point, point],
            weights: [1.0, 0.0],
        }
    }
}

/// The samples of every zone (see the module docs), keyed by (joint, zone):
/// at `inset` from the faces, or one node in from them when None.
pub fn inside_grout_stops(
    mesh: &Mesh,
    points: &[JointPoint],
    inset: Option<f64>,
) -> HashMap<(u32, u32), Vec<StopSample>> {
    match inset {
        Some(inset) => at_inset(mesh, points, inset),
        None => one_node_in(mesh, points),
    }
}

/// The joint points of each zone off the dam's outer faces (not the far
/// faces of the rock). A zone with no such point (one element across) keeps
/// all of its points.
fn one_node_in(mesh: &Mesh, points: &[JointPoint]) -> HashMap<(u32, u32), Vec<StopSample>> {
    let mut on_face = vec![false; mesh.nodes.len()];
    for f in mesh.surfaces.iter().filter(|f| f.kind != SurfaceKind::Far) {
        let conn = &mesh.elements[f.elem as usize];
        for &k in &FACES[f.face as usize] {
            on_face[conn[k] as usize] = true;
        }
    }
    let mut all: HashMap<(u32, u32), Vec<StopSample>> = HashMap::new();
    let mut inner: HashMap<(u32, u32), Vec<StopSample>> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        let sample = StopSample::at(i as u32);
        all.entry((p.joint, p.zone)).or_default().push(sample);
        if !on_face[p.a as usize] {
            inner.entry((p.joint, p.zone)).or_default().push(sample);
        }
    }
    all.extend(inner);
    all
}

/// The samples at a physical inset (see the module docs).
fn at_inset(
    mesh: &Mesh,
    points: &[JointPoint],
    inset: f64,
) -> HashMap<(u32, u32), Vec<StopSample>> {
    let point_of_a: HashMap<u32, u32> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (p.a, i as u32))
        .collect();
    let mut out: HashMap<(u32, u32), Vec<StopSample>> = HashMap::new();
    for zone in &mesh.zones {
        let key = (zone.joint, zone.zone);
        let mut seen: HashSet<Vec<u32>> = HashSet::new();
        let mut samples = Vec::new();
        for row in node_rows(mesh, &zone.pairs) {
            if !seen.insert(row.clone()) {
                continue;
            }
            // a node of the row that is not a joint point of this zone (on
            // the rock, or the zone below's) has no sample of this zone
            let own: Vec<Option<u32>> = row
                .iter()
                .map(|n| {
                    point_of_a
                        .get(n)
                        .copied()
                        .filter(|&p| (points[p as usize].joint, points[p as usize].zone) == key)
                })
                .collect();
            let xyz: Vec<[f64; 3]> = row.iter().map(|&n| mesh.nodes[n as usize]).collect();
            for (k, w) in row_samples(&arc_lengths(&xyz), inset) {
                match (own[k], w[1] > 0.0) {
                    (Some(p), false) => samples.push(StopSample::at(p)),
                    (Some(p), true) => {
                        if let Some(q) = own[k + 1] {
                            samples.push(StopSample {
                                points: [p, q],
                                weights: w,
                            });
                        }
                    }
                    (None, _) => {}
                }
            }
        }
        if samples.is_empty() {
            samples = (0..points.len() as u32)
                .filter(|&p| (points[p as usize].joint, points[p as usize].zone) == key)
                .map(StopSample::at)
                .collect();
        }
        out.insert(key, samples);
    }
    out
}

/// The node rows (side-a nodes, upstream to downstream) of a zone's face
/// pairs: the bottom and top edge of each run of adjacent pairs of a layer.
pub fn node_rows(mesh: &Mesh, pairs: &[u32]) -> Vec<Vec<u32>> {
    let mut rows = Vec::new();
    let mut run: Vec<[u32; 4]> = Vec::new();
    let mut layer = u32::MAX;
    let mut flush = |run: &mut Vec<[u32; 4]>| {
        if let Some(first) = run.first() {
            let bottom = std::iter::once(first[0]).chain(run.iter().map(|q| q[1]));
            let top = std::iter::once(first[3]).chain(run.iter().map(|q| q[2]));
            rows.push(bottom.collect());
            rows.push(top.collect());
        }
        run.clear();
    };
    for &p in pairs {
        let fp = &mesh.face_pairs[p as usize];
        // a new layer, or a pair not adjacent to the last one, starts a row
        let adjacent = run.last().is_some_and(|q| q[1] == fp.nodes_a[0]);
        if fp.layer != layer || !adjacent {
            flush(&mut run);
            layer = fp.layer;
        }
        run.push(fp.nodes_a);
    }
    flush(&mut run);
    rows
}

/// Distance of each point from the first along the polyline through them.
fn arc_lengths(xyz: &[[f64; 3]]) -> Vec<f64> {
    let mut d = Vec::with_capacity(xyz.len());
    let mut s = 0.0;
    for (k, p) in xyz.iter().enumerate() {
        if k > 0 {
            let q = xyz[k - 1];
            s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        }
        d.push(s);
    }
    d
}

/// The samples of a row of nodes at arc lengths `d` (increasing from 0):
/// (k, [w_k, w_k+1]), the field at node k weighted with node k + 1 (`w[1] =
/// 0` for the node alone). See the module docs.
fn row_samples(d: &[f64], inset: f64) -> Vec<(usize, [f64; 2])> {
    let Some(&length) = d.last() else {
        return Vec::new();
    };
    let lines = if length >= 2.0 * inset {
        vec![inset, length - inset]
    } else {
        vec![0.5 * length]
    };
    let (lo, hi) = (lines[0], lines[lines.len() - 1]);
    let mut out: Vec<(usize, [f64; 2])> = (0..d.len())
        .filter(|&k| d[k] > lo && d[k] < hi)
        .map(|k| (k, [1.0, 0.0]))
        .collect();
    for x in lines {
        // the node at or below x; x = length is node n − 1 alone
        let k = d.partition_point(|&v| v <= x).saturating_sub(1);
        if k + 1 >= d.len() || d[k] == x {
            out.push((k, [1.0, 0.0]));
        } else {
            let w = (x - d[k]) / (d[k + 1] - d[k]);
            out.push((k, [1.0 - w, w]));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value of a sampled row field `f` at its samples.
    fn values(d: &[f64], f: impl Fn(f64) -> f64, inset: f64) -> Vec<f64> {
        row_samples(d, inset)
            .into_iter()
            .map(|(k, w)| w[0] * f(d[k]) + if w[1] > 0.0 { w[1] * f(d[k + 1]) } else { 0.0 })
            .collect()
    }

    #[test]
    fn inset_lines_interpolate_the_straddling_nodes() {
        let d = [0.0, 3.0, 6.0, 9.0, 12.0];
        let s = row_samples(&d, 1.0);
        // nodes 1..=3 inside, then the two inset lines
        assert_eq!(s.len(), 5);
        for ((k, w), (k_want, w1)) in [s[3], s[4]]
            .into_iter()
            .zip([(0, 1.0 / 3.0), (3, 2.0 / 3.0)])
        {
            assert_eq!(k, k_want);
            assert!(
                (w[0] - (1.0 - w1)).abs() < 1e-15 && (w[1] - w1).abs() < 1e-15,
                "{w:?}"
            );
        }
        // a linear field is read exactly at the lines
        let v = values(&d, |x| 0.1 * x + 2.0, 1.0);
        let min = v.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((min - 2.1).abs() < 1e-15);
    }

    #[test]
    fn a_line_on_a_node_is_the_node_and_a_thin_row_its_centre() {
        let d = [0.0, 1.0, 2.0, 3.0];
        let s = row_samples(&d, 1.0);
        assert_eq!(s, vec![(1, [1.0, 0.0]), (2, [1.0, 0.0])]);
        // 1.5 m thick, inset 1 m: the centre only
        assert_eq!(row_samples(&[0.0, 1.5], 1.0), vec![(0, [0.5, 0.5])]);
        // inset 0: every node, the faces included
        assert_eq!(row_samples(&[0.0, 2.0], 0.0).len(), 2);
    }

    #[test]
    fn arc_length_follows_the_row() {
        let d = arc_lengths(&[[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 2.0]]);
        assert_eq!(d, vec![0.0, 5.0, 7.0]);
    }
}
