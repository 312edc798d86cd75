//! Mesh generators: counts, geometry, joints, zones, surfaces, errors, VTU.

use std::collections::{HashMap, HashSet};

use groutready::fem::quad4;
use groutready::mesh::geometry::{ArchGeometry, BlocksGeometry};
use groutready::mesh::{
    generate_arch, generate_blocks, hex_jacobian_det, hex_volume, write_pvd, write_vtu, Mesh,
    MeshError, Part, SurfaceKind, HEX_FACES,
};
use groutready::vocab::ZonePoint;

fn blocks_geom(n_blocks: u32) -> BlocksGeometry {
    BlocksGeometry {
        n_blocks,
        block_length_m: 20.0,
        thickness_m: 15.0,
        n_lifts: 3,
        elements_per_block: 2,
        elements_across: 2,
        layers_per_lift: 1,
        rock_depth_m: 0.0,
        rock_layers: 1,
        rock_margin_m: 0.0,
        rock_margin_elements: 1,
        rock_grading_ratio: 1.0,
        face_element_m: None,
        joint_element_m: None,
        base_elevation_m: 100.0,
    }
}

/// The demo-size arch of the brief.
fn demo_arch() -> ArchGeometry {
    ArchGeometry {
        n_blocks: 12,
        height_m: 150.0,
        base_elevation_m: 0.0,
        crest_radius_m: 160.0,
        base_radius_m: 90.0,
        central_angle_deg: 95.0,
        crest_thickness_m: 8.0,
        base_thickness_m: 35.0,
        thickness_exponent: 1.0,
        overhang_m: 6.0,
        valley_exponent: 2.0,
        min_block_height_fraction: 0.3,
        elements_per_block: 2,
        elements_across: 3,
        rock_depth_m: 60.0,
        rock_layers: 2,
        rock_margin_m: 60.0,
        rock_margin_elements: 1,
        rock_grading_ratio: 1.0,
        face_element_m: None,
        joint_element_m: None,
    }
}

/// Xiaowan-like: 43 blocks, 292 m (97.33 lifts of 3 m: the crest lift absorbs the rest).
fn large_arch() -> ArchGeometry {
    ArchGeometry {
        n_blocks: 43,
        height_m: 292.0,
        base_elevation_m: 953.0,
        crest_radius_m: 500.0,
        base_radius_m: 250.0,
        central_angle_deg: 100.0,
        crest_thickness_m: 12.0,
        base_thickness_m: 73.0,
        thickness_exponent: 1.2,
        overhang_m: 15.0,
        valley_exponent: 2.0,
        min_block_height_fraction: 0.25,
        elements_per_block: 3,
        elements_across: 6,
        rock_depth_m: 150.0,
        rock_layers: 3,
        rock_margin_m: 150.0,
        rock_margin_elements: 1,
        rock_grading_ratio: 1.0,
        face_element_m: None,
        joint_element_m: None,
    }
}

fn min_corner_jacobian(m: &Mesh) -> f64 {
    let corners = [-1.0, 1.0];
    let mut min = f64::INFINITY;
    for e in 0..m.elements.len() {
        let x = m.element_coords(e);
        for &a in &corners {
            for &b in &corners {
                for &c in &corners {
                    min = min.min(hex_jacobian_det(&x, a, b, c));
                }
            }
        }
    }
    min
}

fn concrete_volume(m: &Mesh) -> f64 {
    (0..m.elements.len())
        .filter(|&e| matches!(m.parts[e], Part::Concrete { .. }))
        .map(|e| hex_volume(&m.element_coords(e)))
        .sum()
}

/// Duplicated node pairs (a != b) named by the face pairs.
fn duplicated_pairs(m: &Mesh) -> HashSet<(u32, u32)> {
    let mut s = HashSet::new();
    for fp in &m.face_pairs {
        for k in 0..4 {
            if fp.nodes_a[k] != fp.nodes_b[k] {
                s.insert((fp.nodes_a[k], fp.nodes_b[k]));
            }
        }
    }
    s
}

/// thermal_dof merges exactly the joint duplicates: dof classes have one node,
/// or two coincident nodes that a face pair identifies.
fn check_thermal_dofs(m: &Mesh) {
    let dups = duplicated_pairs(m);
    assert_eq!(m.nodes.len() - m.n_thermal_dofs, dups.len());
    let mut by_dof: HashMap<u32, Vec<u32>> = HashMap::new();
    for (n, &d) in m.thermal_dof.iter().enumerate() {
        by_dof.entry(d).or_default().push(n as u32);
    }
    assert_eq!(by_dof.len(), m.n_thermal_dofs);
    for nodes in by_dof.values() {
        match nodes.as_slice() {
            [_] => {}
            [a, b] => {
                assert!(dups.contains(&(*a, *b)) || dups.contains(&(*b, *a)));
                assert_eq!(m.nodes[*a as usize], m.nodes[*b as usize]);
            }
            other => panic!("dof shared by {} nodes", other.len()),
        }
    }
}

/// Every element face is either shared with another element (same node set),
/// a joint face (one side of a face pair) or listed in `surfaces` — and only one.
fn check_surfaces_topology(m: &Mesh) {
    let mut count: HashMap<[u32; 4], usize> = HashMap::new();
    let key = |e: usize, f: usize| {
        let mut k: [u32; 4] = std::array::from_fn(|q| m.elements[e][HEX_FACES[f][q]]);
        k.sort_unstable();
        k
    };
    for e in 0..m.elements.len() {
        for f in 0..6 {
            *count.entry(key(e, f)).or_default() += 1;
        }
    }
    let mut joint_faces = HashSet::new();
    for fp in &m.face_pairs {
        joint_faces.insert((fp.elem_a as usize, 3usize));
        joint_faces.insert((fp.elem_b as usize, 5usize));
    }
    let surf: HashSet<(usize, usize)> = m
        .surfaces
        .iter()
        .map(|s| (s.elem as usize, s.face as usize))
        .collect();
    assert_eq!(surf.len(), m.surfaces.len(), "duplicate surface faces");
    for e in 0..m.elements.len() {
        for f in 0..6 {
            let once = count[&key(e, f)] == 1;
            let expected_boundary = once && !joint_faces.contains(&(e, f));
            assert_eq!(
                expected_boundary,
                surf.contains(&(e, f)),
                "element {e} face {f}: boundary {expected_boundary}"
            );
            if joint_faces.contains(&(e, f)) {
                assert!(once, "joint face shares its nodes with another element");
            }
        }
    }
}

/// Every joint holds whole zones: contiguous zones up to the crest, each with
/// `elements_across` pairs in every layer of its band.
fn check_whole_zones(m: &Mesh, elements_across: usize) {
    let per = m.zone_lifts * m.layers_per_lift;
    for j in 1..=m.joint_count() {
        let zones: Vec<_> = m.zones.iter().filter(|z| z.joint == j).collect();
        assert!(!zones.is_empty(), "joint {j} has no zones");
        let lowest = m.blocks[j as usize - 1]
            .base_layer
            .max(m.blocks[j as usize].base_layer);
        assert_eq!(lowest % per, 0, "joint {j} starts inside a zone");
        assert_eq!(zones[0].zone, lowest / per + 1);
        assert_eq!(zones.last().unwrap().zone, m.n_zones());
        for w in zones.windows(2) {
            assert_eq!(w[1].zone, w[0].zone + 1);
        }
        for z in zones {
            let band = m.zone_layers(z.zone);
            assert_eq!(z.pairs.len(), band.len() * elements_across);
            let layers: HashSet<u32> = z
                .pairs
                .iter()
                .map(|&p| m.face_pairs[p as usize].layer)
                .collect();
            assert_eq!(layers, band.clone().collect::<HashSet<u32>>());
            assert_eq!(z.z_bottom, m.layer_z[band.start as usize]);
            assert_eq!(z.z_top, m.layer_z[band.end as usize]);
            assert_eq!(m.zone_points_of(j, z.zone).len(), 3);
        }
    }
}

/// Zone points: on their pair's quad (from nodes_a and nodes_b alike), at the
/// zone's mid height, upstream/downstream on the joint's edges, centre midway.
fn check_zone_points(m: &Mesh) {
    assert_eq!(m.zone_points.len(), 3 * m.zones.len());
    for z in &m.zones {
        let pts = m.zone_points_of(z.joint, z.zone);
        let kinds: Vec<ZonePoint> = pts.iter().map(|p| p.point).collect();
        assert_eq!(
            kinds,
            [
                ZonePoint::Upstream,
                ZonePoint::Center,
                ZonePoint::Downstream
            ]
        );
        let zm = 0.5 * (z.z_bottom + z.z_top);
        for p in pts {
            let fp = &m.face_pairs[p.pair as usize];
            assert_eq!((fp.joint, fp.zone), (z.joint, z.zone));
            let w = quad4::shape([p.s, p.t]);
            for nodes in [fp.nodes_a, fp.nodes_b] {
                let mut q = [0.0; 3];
                for k in 0..4 {
                    for c in 0..3 {
                        q[c] += w[k] * m.nodes[nodes[k] as usize][c];
                    }
                }
                for c in 0..3 {
                    assert!((q[c] - p.xyz[c]).abs() < 1e-9, "{p:?}");
                }
            }
            assert!((p.xyz[2] - zm).abs() < 1e-9, "{p:?} not at mid-zone {zm}");
            let on_face = |face: u8| {
                m.surfaces
                    .iter()
                    .any(|s| s.elem == fp.elem_a && s.face == face)
            };
            match p.point {
                ZonePoint::Upstream => assert!(p.s == -1.0 && on_face(2)),
                ZonePoint::Downstream => assert!(p.s == 1.0 && on_face(4)),
                ZonePoint::Center => {}
                ZonePoint::Min => unreachable!("a zone site is a placed point"),
            }
        }
        let mid: Vec<f64> = (0..3)
            .map(|c| 0.5 * (pts[0].xyz[c] + pts[2].xyz[c]))
            .collect();
        for c in 0..3 {
            assert!(
                (pts[1].xyz[c] - mid[c]).abs() < 1e-9,
                "centre off mid-thickness"
            );
        }
    }
}

fn check_lift_index(m: &Mesh) {
    let mut seen = vec![false; m.elements.len()];
    for b in &m.blocks {
        let mut all = Vec::new();
        for lift in 1..=b.n_lifts {
            let els = m.elements_of_lift(b.block, lift);
            assert!(!els.is_empty());
            for &e in els {
                assert_eq!(
                    m.parts[e as usize],
                    Part::Concrete {
                        block: b.block,
                        lift
                    }
                );
                assert!(!seen[e as usize]);
                seen[e as usize] = true;
            }
            all.extend_from_slice(els);
        }
        assert_eq!(all, m.elements_of_block(b.block));
        assert!(m.elements_of_lift(b.block, b.n_lifts + 1).is_empty());
        assert!(m.elements_of_lift(b.block, 0).is_empty());
    }
    for (e, p) in m.parts.iter().enumerate() {
        assert_eq!(seen[e], matches!(p, Part::Concrete { .. }));
    }
    assert!(m.elements_of_lift(0, 1).is_empty());
    assert!(m.elements_of_block(m.blocks.len() as u32 + 1).is_empty());
}

fn check_all(m: &Mesh, elements_across: usize) {
    m.validate().expect("valid mesh");
    assert!(min_corner_jacobian(m) > 0.0);
    check_thermal_dofs(m);
    check_surfaces_topology(m);
    check_whole_zones(m, elements_across);
    check_zone_points(m);
    check_lift_index(m);
}

#[test]
fn two_blocks_without_rock_counts() {
    let g = blocks_geom(2);
    let m = generate_blocks(&g, 3.0, 9.0).unwrap();
    // logical nodes 5 x 3 x 4 = 60, the joint plane's 3 x 4 nodes duplicated
    assert_eq!(m.nodes.len(), 72);
    assert_eq!(m.n_thermal_dofs, 60);
    assert_eq!(duplicated_pairs(&m).len(), 12);
    assert_eq!(m.elements.len(), 4 * 2 * 3);
    assert!(m.parts.iter().all(|p| matches!(p, Part::Concrete { .. })));
    assert_eq!(m.face_pairs.len(), 2 * 3); // elements across x lifts
    assert_eq!(m.joint_count(), 1);
    assert_eq!(m.n_layers(), 3);
    assert_eq!(m.zone_lifts, 3);
    assert_eq!(m.zones.len(), 1);
    assert_eq!(m.layer_z, vec![100.0, 103.0, 106.0, 109.0]);
    assert_eq!(m.crest_z, 109.0);
    assert_eq!(m.blocks[1].foundation_z, 100.0);
    assert_eq!(m.elements_of_lift(1, 2).len(), 4);
    // surfaces: bottom Far 8, upstream Wet 12, downstream 12 + top 8 + ends 12 Ground
    let count = |k: SurfaceKind| m.surfaces.iter().filter(|s| s.kind == k).count();
    assert_eq!(count(SurfaceKind::Far), 8);
    assert_eq!(count(SurfaceKind::Wet), 12);
    assert_eq!(count(SurfaceKind::Ground), 32);
    for s in &m.surfaces {
        assert_eq!(s.kind == SurfaceKind::Wet, s.face == 2);
    }
    // face pairs: nodes_a on x = 20, upstream→downstream, bottom→top
    for fp in &m.face_pairs {
        for &n in &fp.nodes_a {
            assert_eq!(m.nodes[n as usize][0], 20.0);
        }
    }
    let pts = m.zone_points_of(1, 1);
    assert_eq!(pts[0].xyz, [20.0, 0.0, 104.5]);
    assert_eq!(pts[1].xyz, [20.0, 7.5, 104.5]);
    assert_eq!(pts[2].xyz, [20.0, 15.0, 104.5]);
    assert_eq!((pts[1].s, pts[1].t), (1.0, 0.0)); // 2 across: centre on an edge
    check_all(&m, 2);
    assert!((concrete_volume(&m) - 2.0 * 20.0 * 15.0 * 9.0).abs() < 1e-8);
}

#[test]
fn two_blocks_on_rock_share_foundation_nodes() {
    let mut g = blocks_geom(2);
    g.rock_depth_m = 10.0;
    g.rock_layers = 2;
    let m = generate_blocks(&g, 3.0, 9.0).unwrap();
    // logical 5 x 3 x 6 = 90; joint nodes touching rock (base row) are shared
    assert_eq!(m.n_thermal_dofs, 90);
    assert_eq!(m.nodes.len(), 90 + 9);
    assert_eq!(m.elements.len(), 24 + 16);
    assert_eq!(m.face_pairs.len(), 6);
    let bottom = &m.face_pairs[0];
    assert_eq!(bottom.layer, 0);
    assert_eq!(bottom.nodes_a[0], bottom.nodes_b[0]);
    assert_eq!(bottom.nodes_a[1], bottom.nodes_b[1]);
    assert_ne!(bottom.nodes_a[2], bottom.nodes_b[2]);
    check_all(&m, 2);

    g.rock_margin_m = 5.0;
    let m = generate_blocks(&g, 3.0, 9.0).unwrap();
    // rock nodes 7 x 5 x 3 + concrete levels 3 x (5 x 3) + 9 duplicates
    assert_eq!(m.nodes.len(), 105 + 45 + 9);
    assert_eq!(m.elements.len(), 6 * 4 * 2 + 24);
    let rock_vol: f64 = (0..m.elements.len())
        .filter(|&e| m.parts[e] == Part::Rock)
        .map(|e| hex_volume(&m.element_coords(e)))
        .sum();
    assert!((rock_vol - 50.0 * 25.0 * 10.0).abs() < 1e-8);
    // rock top upstream of the blocks is Wet, elsewhere Ground; bottom and sides Far
    let mut kinds = HashMap::new();
    for s in &m.surfaces {
        *kinds.entry(s.kind).or_insert(0) += 1;
    }
    // Far: bottom 6x4 + sides 2*(6+4)*2 = 64
    assert_eq!(kinds[&SurfaceKind::Far], 64);
    // Wet: rock top y<0 strip (6 cells) + concrete upstream faces (4 x 3)
    assert_eq!(kinds[&SurfaceKind::Wet], 6 + 12);
    check_all(&m, 2);
}

#[test]
fn blocks_volume_layers_and_zones() {
    let g = BlocksGeometry {
        n_blocks: 4,
        block_length_m: 15.0,
        thickness_m: 24.0,
        n_lifts: 10,
        elements_per_block: 3,
        elements_across: 4,
        layers_per_lift: 2,
        rock_depth_m: 30.0,
        rock_layers: 3,
        rock_margin_m: 20.0,
        rock_margin_elements: 2,
        rock_grading_ratio: 1.0,
        face_element_m: None,
        joint_element_m: None,
        base_elevation_m: 0.0,
    };
    let m = generate_blocks(&g, 1.5, 4.5).unwrap();
    let exact = 4.0 * 15.0 * 24.0 * 10.0 * 1.5;
    assert!((concrete_volume(&m) - exact).abs() < 1e-9 * exact);
    assert_eq!(m.n_layers(), 20);
    assert_eq!(m.layers_per_lift, 2);
    assert_eq!(m.n_zones(), 4); // 3 + 3 + 3 + 1 lifts: the crest zone is short
    assert_eq!(m.zone_layers(4), 18..20);
    assert_eq!(m.zone_of_layer(5), 1);
    assert_eq!(m.zone_of_layer(6), 2);
    assert_eq!(m.elements_of_lift(2, 4).len(), 2 * 3 * 4);
    assert_eq!(m.layer_of_lift(2, 4), Some(6));
    assert_eq!(m.joint_count(), 3);
    for j in 1..=3 {
        let n: usize = m
            .zones
            .iter()
            .filter(|z| z.joint == j)
            .map(|z| z.pairs.len())
            .sum();
        assert_eq!(n, 4 * 20);
    }
    check_all(&m, 4);
}

#[test]
fn demo_arch_is_valid() {
    let p = demo_arch();
    let m = generate_arch(&p, 3.0, 9.0).unwrap();
    println!(
        "demo arch: {} nodes, {} elements ({} concrete), {} thermal dofs, {} face pairs, {} zones",
        m.nodes.len(),
        m.elements.len(),
        m.parts.iter().filter(|p| **p != Part::Rock).count(),
        m.n_thermal_dofs,
        m.face_pairs.len(),
        m.zones.len()
    );
    assert!(min_corner_jacobian(&m) > 0.0);
    assert_eq!(m.blocks.len(), 12);
    assert_eq!(m.joint_count(), 11);
    assert_eq!(m.n_layers(), 50);
    assert_eq!(m.n_zones(), 17);
    assert_eq!(m.crest_z, 150.0);
    // valley: central blocks reach the base, abutment blocks are the shortest,
    // every foundation on a zone boundary, no block shorter than min fraction
    assert_eq!(m.blocks[5].base_layer, 0);
    assert_eq!(m.blocks[6].base_layer, 0);
    for b in &m.blocks {
        assert_eq!(b.base_layer % 3, 0);
        assert_eq!(b.n_lifts, 50 - b.base_layer);
        assert!(150.0 - b.foundation_z >= 0.3 * 150.0 - 1e-9);
        assert_eq!(
            m.blocks[11 - (b.block as usize - 1)].base_layer,
            b.base_layer
        ); // symmetric
    }
    assert!(m.blocks[0].base_layer > m.blocks[3].base_layer);
    // overhang: the crown's upstream face reaches ~6 m upstream near 2/3 H
    let y_min = (0..m.elements.len())
        .filter(|&e| m.parts[e] != Part::Rock)
        .flat_map(|e| m.element_coords(e))
        .filter(|p| p[0].abs() < 1e-9)
        .map(|p| p[1])
        .fold(f64::INFINITY, f64::min);
    assert!((-6.0..=-5.99).contains(&y_min), "crown overhang {y_min}");
    check_all(&m, 3);
    check_arch_zone_points_on_radial_planes(&m, &p);
}

/// `face_element_m`: at every elevation of every joint, whatever the
/// section's thickness there, the grid line next to each face lies exactly
/// that far in, and the cells grow towards the middle; the mesh stays valid.
#[test]
fn graded_across_puts_a_node_row_at_the_face_element() {
    let mut p = demo_arch();
    p.elements_across = 8;
    p.face_element_m = Some(1.0);
    let m = generate_arch(&p, 3.0, 9.0).unwrap();
    assert!(min_corner_jacobian(&m) > 0.0);
    check_all(&m, 8);
    let dist = |a: u32, b: u32| {
        let (x, y) = (m.nodes[a as usize], m.nodes[b as usize]);
        ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
    };
    let mut rows = 0;
    for z in &m.zones {
        let mut by_layer: HashMap<u32, Vec<&groutready::mesh::FacePair>> = HashMap::new();
        for &i in &z.pairs {
            let fp = &m.face_pairs[i as usize];
            by_layer.entry(fp.layer).or_default().push(fp);
        }
        for row in by_layer.values() {
            assert_eq!(row.len(), 8);
            // across widths of the row's quads, bottom edge (nodes 0 → 1)
            let w: Vec<f64> = row
                .iter()
                .map(|fp| dist(fp.nodes_a[0], fp.nodes_a[1]))
                .collect();
            let thickness: f64 = w.iter().sum();
            assert!(
                (w[0] - 1.0).abs() < 1e-9 && (w[7] - 1.0).abs() < 1e-9,
                "{w:?}"
            );
            if thickness > 8.0 + 1e-6 {
                assert!(w[1] > w[0] && w[3] > w[2] && w[6] > w[7], "{w:?}");
            }
            rows += 1;
        }
    }
    assert!(rows > 100);
    // the same grid without the key is the uniform one, node for node
    p.face_element_m = None;
    let uniform = generate_arch(&p, 3.0, 9.0).unwrap();
    assert_eq!(uniform.nodes.len(), m.nodes.len());
    assert_ne!(uniform.nodes, m.nodes);
}

/// `joint_element_m`: next to every joint (and abutment end) of every
/// block the element along is that wide, growing towards the block's
/// middle; with both gradings an arch stays valid.
#[test]
fn graded_along_puts_a_node_row_at_the_joint_element() {
    let mut p = blocks_geom(3);
    p.elements_per_block = 6;
    p.joint_element_m = Some(1.0);
    let m = generate_blocks(&p, 5.0, 5.0).unwrap();
    assert!(min_corner_jacobian(&m) > 0.0);
    let mut xs: Vec<f64> = m.nodes.iter().map(|n| n[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    assert_eq!(xs.len(), 3 * 6 + 1);
    for b in 0..3 {
        let w: Vec<f64> = (0..6).map(|e| xs[6 * b + e + 1] - xs[6 * b + e]).collect();
        assert!(
            (w[0] - 1.0).abs() < 1e-9 && (w[5] - 1.0).abs() < 1e-9,
            "{w:?}"
        );
        assert!(
            w[1] > w[0] && w[2] > w[1] && (w[2] - w[3]).abs() < 1e-9,
            "{w:?}"
        );
        assert!((xs[6 * b + 6] - 20.0 * (b + 1) as f64).abs() < 1e-9);
    }
    let mut a = demo_arch();
    a.elements_per_block = 4;
    a.elements_across = 6;
    a.joint_element_m = Some(2.0);
    a.face_element_m = Some(1.0);
    let m = generate_arch(&a, 3.0, 9.0).unwrap();
    assert!(min_corner_jacobian(&m) > 0.0);
    check_all(&m, 6);
    check_arch_zone_points_on_radial_planes(&m, &a);
}

/// Zone points lie on the radial joint plane φ_j through the centre of
/// curvature (0, y_c(z)), y_c = R(ζ) − overhang·g(ζ) (linear between levels).
fn check_arch_zone_points_on_radial_planes(m: &Mesh, p: &ArchGeometry) {
    let yc = |z: f64| {
        let zeta = (z - p.base_elevation_m) / p.height_m;
        let r = p.base_radius_m + (p.crest_radius_m - p.base_radius_m) * zeta;
        r - p.overhang_m * 6.75 * zeta * zeta * (1.0 - zeta)
    };
    let phi_total = p.central_angle_deg.to_radians();
    for zp in &m.zone_points {
        let phi = -0.5 * phi_total + phi_total * zp.joint as f64 / p.n_blocks as f64;
        let layer = m.face_pairs[zp.pair as usize].layer as usize;
        let (z0, z1) = (m.layer_z[layer], m.layer_z[layer + 1]);
        let w = 0.5 * (zp.t + 1.0);
        let c = (1.0 - w) * yc(z0) + w * yc(z1);
        let d = zp.xyz[0] * phi.cos() + (zp.xyz[1] - c) * phi.sin();
        assert!(
            d.abs() < 1e-8,
            "zone point {zp:?} is {d} m off its joint plane"
        );
    }
}

#[test]
fn large_arch_is_valid_and_over_100k_nodes() {
    let p = large_arch();
    let t0 = std::time::Instant::now();
    let m = generate_arch(&p, 3.0, 9.0).unwrap();
    let dt = t0.elapsed();
    println!(
        "large arch: {} nodes, {} elements ({} concrete), {} thermal dofs, {} face pairs, {} zones, {} layers; generated+validated in {:.2?}",
        m.nodes.len(),
        m.elements.len(),
        m.parts.iter().filter(|p| **p != Part::Rock).count(),
        m.n_thermal_dofs,
        m.face_pairs.len(),
        m.zones.len(),
        m.n_layers(),
        dt
    );
    assert!(m.nodes.len() >= 100_000);
    assert_eq!(m.n_layers(), 97);
    assert!((m.layer_z[97] - m.layer_z[96] - 4.0).abs() < 1e-9); // crest lift absorbs 1 m
    assert_eq!(m.crest_z, 953.0 + 292.0);
    assert!(min_corner_jacobian(&m) > 0.0);
    check_all(&m, 6);
    check_arch_zone_points_on_radial_planes(&m, &p);
}

#[test]
fn arch_variants_stay_valid() {
    // no margins, no rock depth, big overhang, steep valley, even counts
    let mut p = demo_arch();
    p.rock_margin_m = 0.0;
    p.rock_depth_m = 0.0;
    p.overhang_m = 25.0;
    p.valley_exponent = 0.7;
    p.elements_across = 4;
    p.elements_per_block = 1;
    p.n_blocks = 2;
    let m = generate_arch(&p, 3.0, 6.0).unwrap();
    check_all(&m, 4);
    check_arch_zone_points_on_radial_planes(&m, &p);
    // wide margins, several margin elements, thick base, exponent 2
    let mut p = demo_arch();
    p.rock_margin_m = 120.0;
    p.rock_margin_elements = 3;
    p.rock_layers = 4;
    p.thickness_exponent = 2.0;
    p.base_thickness_m = 60.0;
    p.central_angle_deg = 120.0;
    p.n_blocks = 9;
    let m = generate_arch(&p, 3.0, 9.0).unwrap();
    check_all(&m, 3);
    check_arch_zone_points_on_radial_planes(&m, &p);
    // surfaces: the rock upstream of the dam is Wet, its far faces Far
    assert!(m
        .surfaces
        .iter()
        .any(|s| s.kind == SurfaceKind::Wet && m.parts[s.elem as usize] == Part::Rock));
}

#[test]
fn bad_parameters_are_errors() {
    let mut g = blocks_geom(0);
    let e = generate_blocks(&g, 3.0, 9.0).unwrap_err();
    assert_eq!(e.to_string(), "n_blocks must be >= 1, got 0");
    assert!(matches!(e, MeshError::Param { ref param, .. } if param == "n_blocks"));
    g.n_blocks = 2;
    let e = generate_blocks(&g, 3.0, 10.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "zone_height_m must be a whole number of lifts (lift height 3 m), got 10"
    );
    let e = generate_blocks(&g, 0.0, 9.0).unwrap_err();
    assert_eq!(e.to_string(), "lift_height_m must be > 0, got 0");
    let e = generate_blocks(&g, 3.0, 1.5).unwrap_err();
    assert!(e
        .to_string()
        .starts_with("zone_height_m must be a whole number of lifts"));
    g.thickness_m = -1.0;
    assert_eq!(
        generate_blocks(&g, 3.0, 9.0).unwrap_err().to_string(),
        "thickness_m must be > 0, got -1"
    );
    g.thickness_m = 10.0;
    g.rock_margin_m = 5.0;
    assert!(generate_blocks(&g, 3.0, 9.0)
        .unwrap_err()
        .to_string()
        .starts_with("rock_margin_m must be 0 when rock_depth_m is 0"));
    g.rock_margin_m = 0.0;
    g.elements_across = 0;
    assert_eq!(
        generate_blocks(&g, 3.0, 9.0).unwrap_err().to_string(),
        "elements_across must be >= 1, got 0"
    );
    g.elements_across = 1;
    g.n_lifts = u32::MAX;
    g.elements_per_block = u32::MAX;
    assert!(matches!(
        generate_blocks(&g, 3.0, 9.0).unwrap_err(),
        MeshError::TooLarge { .. }
    ));

    // Indexable but beyond any machine (it aborted on a 17 GB allocation):
    // refused before anything is allocated, with the estimate.
    let mut p = demo_arch();
    p.elements_per_block = 100_000;
    let e = generate_arch(&p, 3.0, 9.0).unwrap_err();
    assert!(
        matches!(e, MeshError::TooMuchMemory { needed_gib, total_gib, .. } if needed_gib > total_gib),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("mesh too large for this machine: "),
        "{e}"
    );

    let mut p = demo_arch();
    p.n_blocks = 1;
    assert_eq!(
        generate_arch(&p, 3.0, 9.0).unwrap_err().to_string(),
        "n_blocks must be >= 2, got 1"
    );
    let mut p = demo_arch();
    p.central_angle_deg = 200.0;
    assert_eq!(
        generate_arch(&p, 3.0, 9.0).unwrap_err().to_string(),
        "central_angle_deg must be in (0, 180), got 200"
    );
    let mut p = demo_arch();
    p.base_thickness_m = 95.0;
    let e = generate_arch(&p, 3.0, 9.0).unwrap_err();
    assert!(
        matches!(e, MeshError::Param { ref param, .. } if param == "base_thickness_m"),
        "{e}"
    );
    let mut p = demo_arch();
    p.height_m = f64::NAN;
    assert_eq!(
        generate_arch(&p, 3.0, 9.0).unwrap_err().to_string(),
        "height_m must be > 0, got NaN"
    );
    let mut p = demo_arch();
    p.min_block_height_fraction = 0.0;
    assert!(generate_arch(&p, 3.0, 9.0).is_err());
    let p = demo_arch();
    assert_eq!(
        generate_arch(&p, 3.0, 7.5).unwrap_err().to_string(),
        "zone_height_m must be a whole number of lifts (lift height 3 m), got 7.5"
    );
}

#[test]
fn validate_catches_broken_meshes() {
    let m0 = generate_blocks(&blocks_geom(2), 3.0, 9.0).unwrap();
    // inverted element
    let mut m = m0.clone();
    m.elements[0].swap(0, 1);
    assert!(m.validate().is_err());
    // joint pair moved apart
    let mut m = m0.clone();
    let n = m.face_pairs[2].nodes_b[2] as usize;
    m.nodes[n][0] += 1e-6;
    assert!(matches!(m.validate(), Err(MeshError::Invalid(_))) || m.validate().is_err());
    // thermal dof merging two unrelated nodes
    let mut m = m0.clone();
    m.thermal_dof[0] = m.thermal_dof[1];
    assert!(m.validate().is_err());
    // duplicated joint node given its own thermal dof
    let mut m = m0.clone();
    let b = m.face_pairs[0].nodes_b[2] as usize;
    m.thermal_dof[b] = m.n_thermal_dofs as u32;
    m.n_thermal_dofs += 1;
    assert!(m.validate().is_err());
    m0.validate().unwrap();
}

// ---------- VTU ----------

fn b64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a') as u32 + 26,
            b'0'..=b'9' => (c - b'0') as u32 + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("bad base64 char {c}"),
        }
    };
    let bytes: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let mut out = Vec::new();
    for chunk in bytes.chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let mut n = 0u32;
        for &c in chunk {
            n = (n << 6) | if c == b'=' { 0 } else { val(c) };
        }
        let three = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&three[..3 - pad]);
    }
    out
}

/// (attributes text, decoded payload without the UInt64 header) of every DataArray.
fn data_arrays(xml: &str) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut rest = xml;
    while let Some(i) = rest.find("<DataArray") {
        rest = &rest[i..];
        let close = rest.find('>').unwrap();
        let attrs = rest[..close].to_string();
        let end = rest.find("</DataArray>").unwrap();
        let raw = b64_decode(&rest[close + 1..end]);
        let len = u64::from_le_bytes(raw[..8].try_into().unwrap()) as usize;
        assert_eq!(raw.len(), 8 + len, "header byte count");
        out.push((attrs, raw[8..].to_vec()));
        rest = &rest[end..];
    }
    out
}

#[test]
fn vtu_is_well_formed() {
    let m = generate_blocks(&blocks_geom(2), 3.0, 9.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.vtu");
    let temp: Vec<f64> = m.nodes.iter().map(|p| p[2]).collect();
    let disp: Vec<f64> = m.nodes.iter().flat_map(|p| [p[0], 0.0, 0.0]).collect();
    let age: Vec<f64> = (0..m.elements.len()).map(|e| e as f64).collect();
    let live: Vec<u32> = m
        .elements_of_lift(1, 1)
        .iter()
        .chain(m.elements_of_lift(2, 1))
        .copied()
        .collect();
    write_vtu(
        &path,
        &m,
        &[("temperature", &temp), ("displacement", &disp)],
        &[("age_d", &age)],
        Some(&live),
    )
    .unwrap();
    let xml = std::fs::read_to_string(&path).unwrap();
    assert!(xml.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
    assert!(xml.trim_end().ends_with("</VTKFile>"));
    assert!(xml.contains(&format!(
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        m.nodes.len(),
        live.len()
    )));
    for tag in [
        "UnstructuredGrid",
        "Piece",
        "PointData",
        "CellData",
        "Points",
        "Cells",
    ] {
        assert_eq!(
            xml.matches(&format!("<{tag}>")).count() + xml.matches(&format!("<{tag} ")).count(),
            1,
            "{tag}"
        );
        assert_eq!(xml.matches(&format!("</{tag}>")).count(), 1, "{tag}");
    }
    let arrays = data_arrays(&xml);
    let names: Vec<String> = arrays
        .iter()
        .map(|(a, _)| {
            a.split("Name=\"")
                .nth(1)
                .map_or("", |s| s.split('"').next().unwrap())
                .to_string()
        })
        .collect();
    assert_eq!(
        names,
        [
            "temperature",
            "displacement",
            "block",
            "lift",
            "age_d",
            "",
            "connectivity",
            "offsets",
            "types"
        ]
    );
    let f64s = |b: &[u8]| -> Vec<f64> {
        b.chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let i64s = |b: &[u8]| -> Vec<i64> {
        b.chunks(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    assert_eq!(f64s(&arrays[0].1), temp);
    assert!(arrays[1].0.contains("NumberOfComponents=\"3\""));
    assert_eq!(f64s(&arrays[1].1).len(), 3 * m.nodes.len());
    let gathered: Vec<f64> = live.iter().map(|&e| e as f64).collect();
    assert_eq!(f64s(&arrays[4].1), gathered);
    let pts = f64s(&arrays[5].1);
    assert_eq!(pts.len(), 3 * m.nodes.len());
    assert_eq!(&pts[3 * 7..3 * 8], &m.nodes[7]);
    let conn = i64s(&arrays[6].1);
    let want: Vec<i64> = live
        .iter()
        .flat_map(|&e| m.elements[e as usize].map(|n| n as i64))
        .collect();
    assert_eq!(conn, want);
    assert_eq!(
        i64s(&arrays[7].1),
        (1..=live.len() as i64).map(|i| 8 * i).collect::<Vec<_>>()
    );
    assert_eq!(arrays[8].1, vec![12u8; live.len()]);
    // no temporary file left behind
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

    // bad field lengths and names are errors, and leave no file
    let bad = dir.path().join("bad.vtu");
    assert!(write_vtu(&bad, &m, &[("t", &temp[1..])], &[], None).is_err());
    assert!(write_vtu(&bad, &m, &[("t", &temp), ("t", &temp)], &[], None).is_err());
    assert!(write_vtu(&bad, &m, &[], &[], Some(&[u32::MAX])).is_err());
    assert!(!bad.exists());

    // a caller's own `block` cell field (over all elements) replaces the built-in one
    let own = dir.path().join("own.vtu");
    let blk: Vec<f64> = vec![7.0; m.elements.len()];
    write_vtu(&own, &m, &[], &[("block", &blk)], Some(&live)).unwrap();
    let xml = std::fs::read_to_string(&own).unwrap();
    assert_eq!(xml.matches("Name=\"block\"").count(), 1);
    assert_eq!(xml.matches("Name=\"lift\"").count(), 1);
    let arrays = data_arrays(&xml);
    let blk_arr = arrays
        .iter()
        .find(|(a, _)| a.contains("Name=\"block\""))
        .unwrap();
    assert!(blk_arr.0.contains("Float64"));
    assert_eq!(f64s(&blk_arr.1), vec![7.0; live.len()]);

    let pvd = dir.path().join("series.pvd");
    write_pvd(&pvd, &[(0.0, "a.vtu".into()), (12.5, "b&c.vtu".into())]).unwrap();
    let s = std::fs::read_to_string(&pvd).unwrap();
    assert!(s.contains("<VTKFile type=\"Collection\""));
    assert!(s.contains("<DataSet timestep=\"12.5\" group=\"\" part=\"0\" file=\"b&amp;c.vtu\"/>"));
    assert_eq!(s.matches("<DataSet ").count(), 2);
}

/// Writes the demo arch with fields and checks it with meshio:
/// `cargo test --release --test mesh_generators -- --ignored vtu_meshio`
/// (needs `pip install meshio numpy`).
#[test]
#[ignore]
fn vtu_meshio_check() {
    let m = generate_arch(&demo_arch(), 3.0, 9.0).unwrap();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target-mesh/vtu_check");
    std::fs::create_dir_all(&dir).unwrap();
    let temp: Vec<f64> = m.nodes.iter().map(|p| 10.0 + p[2] / 10.0).collect();
    let disp: Vec<f64> = m
        .nodes
        .iter()
        .flat_map(|p| [p[0] * 1e-4, p[1] * 1e-4, 0.0])
        .collect();
    let vol: Vec<f64> = (0..m.elements.len())
        .map(|e| hex_volume(&m.element_coords(e)))
        .collect();
    let full = dir.join("demo_arch.vtu");
    write_vtu(
        &full,
        &m,
        &[("temperature", &temp), ("displacement", &disp)],
        &[("volume", &vol)],
        None,
    )
    .unwrap();
    let live: Vec<u32> = (1..=12)
        .flat_map(|b| m.elements_of_lift(b, 1).to_vec())
        .collect();
    let part = dir.join("demo_arch_live.vtu");
    write_vtu(
        &part,
        &m,
        &[("temperature", &temp)],
        &[("volume", &vol)],
        Some(&live),
    )
    .unwrap();
    write_pvd(
        dir.join("demo_arch.pvd"),
        &[
            (0.0, "demo_arch_live.vtu".into()),
            (1.0, "demo_arch.vtu".into()),
        ],
    )
    .unwrap();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtu_check.py");
    for (file, cells, pf) in [
        (
            &full,
            m.elements.len(),
            vec!["temperature", "displacement:3"],
        ),
        (&part, live.len(), vec!["temperature"]),
    ] {
        let mut cmd = std::process::Command::new("python3");
        cmd.arg(&script)
            .arg(file)
            .args(["--points", &m.nodes.len().to_string()])
            .args(["--cells", &cells.to_string()])
            .args(["--cell-field", "volume"]);
        for f in pf {
            cmd.args(["--point-field", f]);
        }
        let out = cmd.output().expect("python3");
        println!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            out.status.success(),
            "vtu_check.py failed on {}",
            file.display()
        );
    }
}

/// A failed pivot is reported at its node: where it is, the block and lift
/// of the elements around it and the joint it sits on.
#[test]
fn a_node_is_described_by_its_place() {
    let m = generate_blocks(&blocks_geom(2), 3.0, 9.0).unwrap();
    // The joint's top-lift face: its node on side a, at the crest.
    let pair = m.face_pairs.iter().max_by_key(|p| p.layer).unwrap();
    let node = pair.nodes_a[3];
    let [x, y, z] = m.nodes[node as usize];
    assert_eq!(
        m.describe_node(node),
        format!("node {node} at ({x:.1}, {y:.1}, {z:.1}) m, in block 1 lift 3, on joint 1")
    );
    assert_eq!(z, 109.0);
    // An interior node of the bottom lift, shared by lifts 1 and 2.
    let shared = (0..m.nodes.len() as u32)
        .find(|&n| m.nodes[n as usize][2] == 103.0 && m.describe_node(n).contains("block 2"))
        .unwrap();
    assert!(
        m.describe_node(shared)
            .ends_with("in block 2 lift 1 and block 2 lift 2")
            || m.describe_node(shared)
                .contains("in block 2 lift 1 and block 2 lift 2, on joint 1"),
        "{}",
        m.describe_node(shared)
    );
    let dof = m.thermal_dof[node as usize];
    let back = m.node_of_thermal_dof(dof).unwrap();
    assert_eq!(m.thermal_dof[back as usize], dof);
}
