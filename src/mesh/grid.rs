//! Shared builder: a structured logical grid of classified cells → [`Mesh`].
//!
//! Node (i, j, k) has index `i + (ni+1)·(j + (nj+1)·k)`, cell (i, j, k)
//! `i + ni·(j + nj·k)`. Cells are void, rock, or concrete of (block, global
//! layer). Joint duplication, face pairs, zones, zone points, surfaces and
//! thermal dofs all follow from the classification (see the module docs of
//! [`super`]).

use std::collections::HashMap;
use std::sync::OnceLock;

use crate::vocab::ZonePoint;

use super::{BlockInfo, FacePair, Mesh, MeshError, Part, SurfaceFace, SurfaceKind, Zone, ZoneSite};

/// Largest node/element count a mesh may have (indices are `u32`).
pub(crate) const MAX_ENTITIES: u64 = u32::MAX as u64 / 2;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Cell {
    Void,
    Rock,
    Concrete { block: u32, layer: u32 },
}

pub(crate) struct Grid {
    pub ni: usize,
    pub nj: usize,
    pub nk: usize,
    /// Node positions, `(ni+1)(nj+1)(nk+1)`.
    pub pos: Vec<[f64; 3]>,
    /// Cell classes, `ni·nj·nk`.
    pub cells: Vec<Cell>,
    /// Concrete cells across are `j ∈ [j0, j1)`; cells with `j < j0` are upstream.
    pub j0: usize,
    pub j1: usize,
    pub layer_z: Vec<f64>,
    pub lift_height: f64,
    pub zone_lifts: u32,
    pub layers_per_lift: u32,
    /// Per block (index block − 1): (base_layer, n_lifts).
    pub block_layers: Vec<(u32, u32)>,
}

/// Check that a grid of this size can be indexed; call before allocating it.
pub(crate) fn check_size(ni: usize, nj: usize, nk: usize) -> Result<(), MeshError> {
    let nodes = (ni as u64 + 1)
        .saturating_mul(nj as u64 + 1)
        .saturating_mul(nk as u64 + 1);
    let elements = (ni as u64)
        .saturating_mul(nj as u64)
        .saturating_mul(nk as u64);
    // Duplicated joint nodes at most double the node count.
    if nodes.saturating_mul(2) > MAX_ENTITIES || elements > MAX_ENTITIES {
        return Err(MeshError::TooLarge {
            nodes,
            elements,
            limit: MAX_ENTITIES,
        });
    }
    Ok(())
}

impl Grid {
    fn node(&self, i: usize, j: usize, k: usize) -> usize {
        i + (self.ni + 1) * (j + (self.nj + 1) * k)
    }
    fn cell_index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.ni * (j + self.nj * k)
    }
    fn cell(&self, i: isize, j: isize, k: isize) -> Cell {
        if i < 0 || j < 0 || k < 0 {
            return Cell::Void;
        }
        let (i, j, k) = (i as usize, j as usize, k as usize);
        if i >= self.ni || j >= self.nj || k >= self.nk {
            return Cell::Void;
        }
        self.cells[self.cell_index(i, j, k)]
    }
    fn inside(&self, i: isize, j: isize, k: isize) -> bool {
        i >= 0
            && j >= 0
            && k >= 0
            && (i as usize) < self.ni
            && (j as usize) < self.nj
            && (k as usize) < self.nk
    }
}

/// Build the mesh and validate it.
pub(crate) fn build(g: Grid) -> Result<Mesh, MeshError> {
    let bug = |m: String| MeshError::Invalid(format!("generator: {m}"));
    let (ni, nj, nk) = (g.ni, g.nj, g.nk);
    let nn = (ni + 1) * (nj + 1) * (nk + 1);
    debug_assert_eq!(g.pos.len(), nn);
    debug_assert_eq!(g.cells.len(), ni * nj * nk);
    let n_layers = g.layer_z.len() - 1;
    let lpl = g.layers_per_lift;

    // 1. Node classification: used, duplicated (joint node away from rock).
    let mut used = vec![false; nn];
    let mut dup = vec![false; nn];
    for k in 0..=nk {
        for j in 0..=nj {
            for i in 0..=ni {
                let n = g.node(i, j, k);
                let mut any = false;
                let mut rock = false;
                let mut left: Option<u32> = None;
                let mut right: Option<u32> = None;
                for dk in 0..2isize {
                    for dj in 0..2isize {
                        for di in 0..2isize {
                            let c = g.cell(
                                i as isize - 1 + di,
                                j as isize - 1 + dj,
                                k as isize - 1 + dk,
                            );
                            match c {
                                Cell::Void => {}
                                Cell::Rock => {
                                    any = true;
                                    rock = true;
                                }
                                Cell::Concrete { block, .. } => {
                                    any = true;
                                    let side = if di == 0 { &mut left } else { &mut right };
                                    match *side {
                                        None => *side = Some(block),
                                        Some(b) if b == block => {}
                                        Some(_) => {
                                            return Err(bug(format!(
                                                "two blocks on one side of node ({i},{j},{k})"
                                            )))
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
                used[n] = any;
                if let (Some(l), Some(r)) = (left, right) {
                    if l != r {
                        if r != l + 1 {
                            return Err(bug(format!(
                                "blocks {l} and {r} meet at node ({i},{j},{k})"
                            )));
                        }
                        dup[n] = !rock;
                    }
                }
            }
        }
    }

    // 2. Mesh nodes and thermal dofs.
    let mut id_a = vec![u32::MAX; nn];
    let mut id_b = vec![u32::MAX; nn];
    let mut nodes = Vec::new();
    let mut thermal_dof = Vec::new();
    let mut n_dofs: u32 = 0;
    for n in 0..nn {
        if !used[n] {
            continue;
        }
        id_a[n] = nodes.len() as u32;
        nodes.push(g.pos[n]);
        thermal_dof.push(n_dofs);
        id_b[n] = id_a[n];
        if dup[n] {
            id_b[n] = nodes.len() as u32;
            nodes.push(g.pos[n]);
            thermal_dof.push(n_dofs);
        }
        n_dofs += 1;
    }

    // 3. Elements and parts.
    let mut elements: Vec<[u32; 8]> = Vec::new();
    let mut parts: Vec<Part> = Vec::new();
    let mut cell_elem = vec![u32::MAX; ni * nj * nk];
    for k in 0..nk {
        for j in 0..nj {
            for i in 0..ni {
                let c = g.cells[g.cell_index(i, j, k)];
                let part = match c {
                    Cell::Void => continue,
                    Cell::Rock => Part::Rock,
                    Cell::Concrete { block, layer } => {
                        let (base, n_lifts) = *g
                            .block_layers
                            .get((block as usize).wrapping_sub(1))
                            .ok_or_else(|| bug(format!("unknown block {block}")))?;
                        if layer < base || (layer - base) / lpl >= n_lifts {
                            return Err(bug(format!("layer {layer} outside block {block}")));
                        }
                        Part::Concrete {
                            block,
                            lift: (layer - base) / lpl + 1,
                        }
                    }
                };
                // corners in VTK order; nodes on the cell's low-i side use copy B
                let corner = |di: usize, dj: usize, dk: usize| {
                    let n = g.node(i + di, j + dj, k + dk);
                    if di == 0 {
                        id_b[n]
                    } else {
                        id_a[n]
                    }
                };
                cell_elem[g.cell_index(i, j, k)] = elements.len() as u32;
                elements.push([
                    corner(0, 0, 0),
                    corner(1, 0, 0),
                    corner(1, 1, 0),
                    corner(0, 1, 0),
                    corner(0, 0, 1),
                    corner(1, 0, 1),
                    corner(1, 1, 1),
                    corner(0, 1, 1),
                ]);
                parts.push(part);
            }
        }
    }

    // 4. Face pairs, sorted by (joint, layer, j).
    let zone_layers = (g.zone_lifts as u64 * lpl as u64).min(u32::MAX as u64) as usize;
    let mut keyed: Vec<(u32, u32, usize, u32, u32)> = Vec::new(); // joint, layer, j, ea, eb
    for k in 0..nk {
        for j in 0..nj {
            for i in 1..ni {
                let l = g.cells[g.cell_index(i - 1, j, k)];
                let r = g.cells[g.cell_index(i, j, k)];
                if let (
                    Cell::Concrete { block: bl, layer },
                    Cell::Concrete {
                        block: br,
                        layer: lr,
                    },
                ) = (l, r)
                {
                    if bl == br {
                        continue;
                    }
                    if br != bl + 1 || layer != lr {
                        return Err(bug(format!("bad joint face at cell ({i},{j},{k})")));
                    }
                    keyed.push((
                        bl,
                        layer,
                        j,
                        cell_elem[g.cell_index(i - 1, j, k)],
                        cell_elem[g.cell_index(i, j, k)],
                    ));
                }
            }
        }
    }
    keyed.sort_unstable_by_key(|x| (x.0, x.1, x.2));
    let mut face_pairs = Vec::with_capacity(keyed.len());
    let mut pair_at: HashMap<(u32, u32, usize), u32> = HashMap::new();
    for &(joint, layer, j, ea, eb) in &keyed {
        let a = elements[ea as usize];
        let b = elements[eb as usize];
        pair_at.insert((joint, layer, j), face_pairs.len() as u32);
        face_pairs.push(FacePair {
            joint,
            zone: layer / zone_layers as u32 + 1,
            layer,
            elem_a: ea,
            elem_b: eb,
            nodes_a: [a[1], a[2], a[6], a[5]],
            nodes_b: [b[0], b[3], b[7], b[4]],
        });
    }

    // 5. Zones and zone points.
    let mut zones: Vec<Zone> = Vec::new();
    for (p, fp) in face_pairs.iter().enumerate() {
        match zones.last_mut() {
            Some(z) if z.joint == fp.joint && z.zone == fp.zone => z.pairs.push(p as u32),
            _ => {
                let first = (fp.zone as usize - 1) * zone_layers;
                let end = (fp.zone as usize * zone_layers).min(n_layers);
                zones.push(Zone {
                    joint: fp.joint,
                    zone: fp.zone,
                    z_bottom: g.layer_z[first],
                    z_top: g.layer_z[end],
                    pairs: vec![p as u32],
                });
            }
        }
    }
    let n_across = g.j1 - g.j0;
    let mut zone_points = Vec::with_capacity(zones.len() * 3);
    for z in &zones {
        let zm = 0.5 * (z.z_bottom + z.z_top);
        let first = (z.zone as usize - 1) * zone_layers;
        let end = (z.zone as usize * zone_layers).min(n_layers);
        let scale = 1e-12 * (1.0 + zm.abs());
        let layer = (first..end)
            .find(|&l| g.layer_z[l + 1] >= zm - scale)
            .unwrap_or(end - 1);
        let (z0, z1) = (g.layer_z[layer], g.layer_z[layer + 1]);
        let t = (2.0 * (zm - z0) / (z1 - z0) - 1.0).clamp(-1.0, 1.0);
        let center = if n_across % 2 == 1 {
            (g.j0 + n_across / 2, 0.0)
        } else {
            (g.j0 + n_across / 2 - 1, 1.0)
        };
        for (point, (j, s)) in [
            (ZonePoint::Upstream, (g.j0, -1.0)),
            (ZonePoint::Center, center),
            (ZonePoint::Downstream, (g.j1 - 1, 1.0)),
        ] {
            let pair = *pair_at.get(&(z.joint, layer as u32, j)).ok_or_else(|| {
                bug(format!(
                    "no face pair for joint {} zone {} at layer {layer}, across {j}",
                    z.joint, z.zone
                ))
            })?;
            let fp = &face_pairs[pair as usize];
            let w = super::quad_shape(s, t);
            let mut xyz = [0.0; 3];
            for (q, &node) in fp.nodes_a.iter().enumerate() {
                for c in 0..3 {
                    xyz[c] += w[q] * nodes[node as usize][c];
                }
            }
            zone_points.push(ZoneSite {
                joint: z.joint,
                zone: z.zone,
                point,
                pair,
                s,
                t,
                xyz,
            });
        }
    }

    // 6. Surfaces.
    const DIRS: [(isize, isize, isize); 6] = [
        (0, 0, -1),
        (0, 0, 1),
        (0, -1, 0),
        (1, 0, 0),
        (0, 1, 0),
        (-1, 0, 0),
    ];
    let mut surfaces = Vec::new();
    for k in 0..nk {
        for j in 0..nj {
            for i in 0..ni {
                let c = g.cells[g.cell_index(i, j, k)];
                if c == Cell::Void {
                    continue;
                }
                let elem = cell_elem[g.cell_index(i, j, k)];
                for (face, &(di, dj, dk)) in DIRS.iter().enumerate() {
                    let (a, b, cc) = (i as isize + di, j as isize + dj, k as isize + dk);
                    if g.cell(a, b, cc) != Cell::Void {
                        continue;
                    }
                    let outside = !g.inside(a, b, cc);
                    let kind = match c {
                        Cell::Rock => {
                            if outside && face != 1 {
                                SurfaceKind::Far
                            } else if j < g.j0 {
                                SurfaceKind::Wet
                            } else {
                                SurfaceKind::Ground
                            }
                        }
                        _ => {
                            if outside && face == 0 {
                                SurfaceKind::Far
                            } else if face == 2 {
                                SurfaceKind::Wet
                            } else {
                                SurfaceKind::Ground
                            }
                        }
                    };
                    surfaces.push(SurfaceFace {
                        elem,
                        face: face as u8,
                        kind,
                    });
                }
            }
        }
    }

    let blocks = g
        .block_layers
        .iter()
        .enumerate()
        .map(|(b, &(base, n_lifts))| BlockInfo {
            block: b as u32 + 1,
            n_lifts,
            base_layer: base,
            foundation_z: g.layer_z[base as usize],
        })
        .collect();

    let mesh = Mesh {
        nodes,
        elements,
        parts,
        thermal_dof,
        n_thermal_dofs: n_dofs as usize,
        crest_z: *g.layer_z.last().unwrap_or(&0.0),
        layer_z: g.layer_z,
        lift_height: g.lift_height,
        zone_lifts: g.zone_lifts,
        layers_per_lift: lpl,
        blocks,
        face_pairs,
        zones,
        zone_points,
        surfaces,
        upstream_normal_hint: [0.0, -1.0, 0.0],
        index: OnceLock::new(),
    };
    mesh.validate()?;
    Ok(mesh)
}

/// Lifts per zone from the two heights; the error names `zone_height_m`.
pub(crate) fn zone_lifts(lift_height: f64, zone_height: f64) -> Result<u32, MeshError> {
    if !(lift_height.is_finite() && lift_height > 0.0) {
        return Err(MeshError::param(
            "lift_height_m",
            format!("must be > 0, got {lift_height}"),
        ));
    }
    if !(zone_height.is_finite() && zone_height > 0.0) {
        return Err(MeshError::param(
            "zone_height_m",
            format!("must be > 0, got {zone_height}"),
        ));
    }
    let r = zone_height / lift_height;
    let n = r.round();
    if n < 1.0 || (r - n).abs() > 1e-9 * r.max(1.0) || n > u32::MAX as f64 / 4.0 {
        return Err(MeshError::param(
            "zone_height_m",
            format!(
                "must be a whole number of lifts (lift height {lift_height} m), got {zone_height}"
            ),
        ));
    }
    Ok(n as u32)
}
