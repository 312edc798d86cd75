//! mesh::import::dam: a RawMesh → the dam Mesh. Generated meshes come back
//! field for field; shuffled, re-oriented and joint-merged copies give the
//! same dam; malformed meshes give their exact messages.

use std::collections::BTreeMap;
use std::path::Path;

use groutready::fem::hex8::NODES;
use groutready::mesh::geometry::BlocksGeometry;
use groutready::mesh::import::{dam, RawMesh};
use groutready::mesh::{generate_blocks, Mesh, Part, SurfaceKind, HEX_FACES};
use groutready::scene::Scene;

/// A model scene's generated mesh with its lift and zone heights.
fn generated(scene: &str) -> (Mesh, f64, f64) {
    let path = format!("{}/models/{scene}", env!("CARGO_MANIFEST_DIR"));
    let s = Scene::load(Path::new(&path)).unwrap();
    let m = groutready::app::build_mesh(&s, &path).unwrap();
    (m, s.lifts.height_m, s.joints.zone_height_m)
}

fn assert_same(got: &Mesh, want: &Mesh) {
    assert_eq!(got.nodes, want.nodes);
    assert_eq!(got.elements, want.elements);
    assert_eq!(got.parts, want.parts);
    assert_eq!(got.thermal_dof, want.thermal_dof);
    assert_eq!(got.n_thermal_dofs, want.n_thermal_dofs);
    assert_eq!(got.layer_z, want.layer_z);
    assert_eq!(got.lift_height, want.lift_height);
    assert_eq!(got.zone_lifts, want.zone_lifts);
    assert_eq!(got.layers_per_lift, want.layers_per_lift);
    assert_eq!(got.blocks, want.blocks);
    assert_eq!(got.face_pairs, want.face_pairs);
    assert_eq!(got.zones, want.zones);
    assert_eq!(got.zone_points, want.zone_points);
    // Same order too: both list boundary faces element by element, face by face.
    assert_eq!(got.surfaces, want.surfaces);
    assert_eq!(got.crest_z, want.crest_z);
    assert_eq!(got.upstream_normal_hint, want.upstream_normal_hint);
}

#[test]
fn generated_meshes_round_trip() {
    for scene in ["small_dam_joints.toml", "demo_arch.toml", "two_blocks.toml"] {
        let (m, lift, zone) = generated(scene);
        let back = dam::build(&RawMesh::from_mesh(&m, "x"), lift, zone).unwrap();
        assert_same(&back, &m);
    }
}

/// A file's mirrored corner order (left-handed elements) is re-ordered, not refused.
#[test]
fn mirrored_elements_are_reflected() {
    let (m, lift, zone) = generated("two_blocks.toml");
    let mut raw = RawMesh::from_mesh(&m, "x");
    for h in &mut raw.hexes {
        *h = [h[4], h[5], h[6], h[7], h[0], h[1], h[2], h[3]];
    }
    assert_same(&dam::build(&raw, lift, zone).unwrap(), &m);
}

/// A tiny LCG: the tests' fixed randomness.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as usize
    }
    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, self.below(i + 1));
        }
    }
}

/// The 24 proper rotations of the reference cube as corner maps: corner c
/// of the rotated element is corner `r[c]` of the original.
fn rotations() -> Vec<[usize; 8]> {
    let mut out = Vec::new();
    for axes in [
        [0, 1, 2],
        [1, 2, 0],
        [2, 0, 1],
        [0, 2, 1],
        [1, 0, 2],
        [2, 1, 0],
    ] {
        let parity = if axes[0] == 0 && axes[1] == 1
            || axes[0] == 1 && axes[1] == 2
            || axes[0] == 2 && axes[1] == 0
        {
            1.0
        } else {
            -1.0
        };
        for bits in 0..8 {
            let signs: [f64; 3] = [0, 1, 2].map(|k| if bits >> k & 1 == 1 { -1.0 } else { 1.0 });
            if parity * signs[0] * signs[1] * signs[2] < 0.0 {
                continue;
            }
            out.push(std::array::from_fn(|c| {
                let mut old = [0.0; 3];
                for k in 0..3 {
                    old[axes[k]] = signs[k] * NODES[c][k];
                }
                NODES.iter().position(|r| *r == old).unwrap()
            }));
        }
    }
    assert_eq!(out.len(), 24);
    out
}

/// `m` as a file might say it: joint copies merged into one node, nodes and
/// elements shuffled, every element's corners rotated.
fn as_a_file_says(m: &Mesh, seed: u64) -> RawMesh {
    let mut rng = Lcg(seed);
    // The first node of each thermal dof stands for its joint copies.
    let mut first_of_dof = vec![u32::MAX; m.n_thermal_dofs];
    let mut keep = Vec::new();
    for (n, &d) in m.thermal_dof.iter().enumerate() {
        if first_of_dof[d as usize] == u32::MAX {
            first_of_dof[d as usize] = n as u32;
            keep.push(n as u32);
        }
    }
    rng.shuffle(&mut keep);
    let mut new_of_dof = vec![0u32; m.n_thermal_dofs];
    for (i, &n) in keep.iter().enumerate() {
        new_of_dof[m.thermal_dof[n as usize] as usize] = i as u32;
    }
    let mut order: Vec<usize> = (0..m.elements.len()).collect();
    rng.shuffle(&mut order);
    let rots = rotations();
    let hexes: Vec<[u32; 8]> = order
        .iter()
        .map(|&e| {
            let r = rots[rng.below(24)];
            r.map(|c| new_of_dof[m.thermal_dof[m.elements[e][c] as usize] as usize])
        })
        .collect();
    let mut element_groups: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    for (i, &e) in order.iter().enumerate() {
        let name = match m.parts[e] {
            Part::Concrete { block, .. } => format!("block_{block}"),
            Part::Rock => "rock".to_string(),
        };
        element_groups.entry(name).or_default().push(i as u32);
    }
    RawMesh {
        source: "shuffled".to_string(),
        nodes: keep.iter().map(|&n| m.nodes[n as usize]).collect(),
        node_ids: (1..=keep.len() as u64).map(|i| 10 * i).collect(),
        hexes,
        elem_ids: (1..=order.len() as u64).collect(),
        element_groups,
        node_groups: BTreeMap::new(),
    }
}

/// Coordinates as exact bits (the builds move no coordinate).
fn bits(p: [f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

/// (joint, zone, layer, nodes_a's points, nodes_b's points) of a face pair.
type PairKey = (u32, u32, u32, Vec<[u64; 3]>, Vec<[u64; 3]>);

fn face_pair_set(m: &Mesh) -> Vec<PairKey> {
    let mut v: Vec<_> = m
        .face_pairs
        .iter()
        .map(|fp| {
            let a = fp
                .nodes_a
                .iter()
                .map(|&n| bits(m.nodes[n as usize]))
                .collect();
            let b = fp
                .nodes_b
                .iter()
                .map(|&n| bits(m.nodes[n as usize]))
                .collect();
            (fp.joint, fp.zone, fp.layer, a, b)
        })
        .collect();
    v.sort();
    v
}

fn surface_set(m: &Mesh) -> Vec<(Vec<[u64; 3]>, String)> {
    let mut v: Vec<_> = m
        .surfaces
        .iter()
        .map(|s| {
            let el = m.elements[s.elem as usize];
            let mut corners: Vec<[u64; 3]> = HEX_FACES[s.face as usize]
                .iter()
                .map(|&c| bits(m.nodes[el[c] as usize]))
                .collect();
            corners.sort();
            (corners, format!("{:?}", s.kind))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn a_file_s_differences_give_the_same_dam() {
    for (scene, seed) in [
        ("small_dam_joints.toml", 7),
        ("demo_arch.toml", 11),
        ("two_blocks.toml", 3),
    ] {
        let (m, lift, zone) = generated(scene);
        let raw = as_a_file_says(&m, seed);
        assert!(
            raw.nodes.len() < m.nodes.len(),
            "{scene}: joint copies merged"
        );
        let got = dam::build(&raw, lift, zone).unwrap();
        crate::joint_grout_stops::assert_full_rows(&got, scene);
        assert_eq!(
            got.nodes.len(),
            m.nodes.len(),
            "{scene}: joint copies restored"
        );
        assert_eq!(got.n_thermal_dofs, m.n_thermal_dofs);
        assert_eq!(got.layer_z, m.layer_z);
        assert_eq!(got.layers_per_lift, m.layers_per_lift);
        assert_eq!(got.blocks, m.blocks);
        assert_eq!(
            face_pair_set(&got),
            face_pair_set(&m),
            "{scene}: face pairs"
        );
        let zone_key =
            |z: &groutready::mesh::Zone| (z.joint, z.zone, z.z_bottom, z.z_top, z.pairs.len());
        assert_eq!(
            got.zones.iter().map(zone_key).collect::<Vec<_>>(),
            m.zones.iter().map(zone_key).collect::<Vec<_>>()
        );
        let point_key =
            |p: &groutready::mesh::ZoneSite| (p.joint, p.zone, p.point, p.s, p.t, bits(p.xyz));
        assert_eq!(
            got.zone_points.iter().map(point_key).collect::<Vec<_>>(),
            m.zone_points.iter().map(point_key).collect::<Vec<_>>()
        );
        assert_eq!(surface_set(&got), surface_set(&m), "{scene}: surfaces");
        // Each element is the generator's, corner for corner, wherever it went.
        let corners = |m: &Mesh, e: usize| m.elements[e].map(|n| bits(m.nodes[n as usize]));
        let mut want: Vec<_> = (0..m.elements.len())
            .map(|e| (corners(&m, e), m.parts[e]))
            .collect();
        let mut have: Vec<_> = (0..got.elements.len())
            .map(|e| (corners(&got, e), got.parts[e]))
            .collect();
        want.sort_by_key(|a| a.0);
        have.sort_by_key(|a| a.0);
        assert!(want == have, "{scene}: elements and parts");
    }
}

/// Named lifts that agree build; one element in the wrong lift is named.
#[test]
fn named_lifts_are_checked() {
    let (m, lift, zone) = generated("two_blocks.toml");
    let mut raw = RawMesh::from_mesh(&m, "two.msh");
    for (e, p) in m.parts.iter().enumerate() {
        if let Part::Concrete { block, lift } = p {
            raw.element_groups
                .entry(format!("block_{block}_lift_{lift}"))
                .or_default()
                .push(e as u32);
        }
    }
    assert_same(&dam::build(&raw, lift, zone).unwrap(), &m);
    let moved = raw
        .element_groups
        .get_mut("block_1_lift_1")
        .unwrap()
        .remove(0);
    raw.element_groups
        .get_mut("block_1_lift_2")
        .unwrap()
        .insert(0, moved);
    assert_eq!(
        dam::build(&raw, lift, zone).unwrap_err().to_string(),
        "two.msh: element 1: is in block_1_lift_2 but lies in lift 1 of block 1 (z = 0.000 … 3.000 m)"
    );
}

/// Node groups `far` and `air` override the kind of the faces they hold.
#[test]
fn node_groups_override_surface_kinds() {
    let (m, lift, zone) = generated("two_blocks.toml");
    let mut raw = RawMesh::from_mesh(&m, "x");
    let on = |pred: &dyn Fn([f64; 3]) -> bool| -> Vec<u32> {
        (0..m.nodes.len() as u32)
            .filter(|&n| pred(m.nodes[n as usize]))
            .collect()
    };
    raw.node_groups
        .insert("far".into(), on(&|p| p[1] == 0.0 && p[2] <= 9.0));
    raw.node_groups.insert("air".into(), on(&|p| p[2] == 0.0));
    let got = dam::build(&raw, lift, zone).unwrap();
    assert_eq!(got.surfaces.len(), m.surfaces.len());
    for (g, w) in got.surfaces.iter().zip(&m.surfaces) {
        let el = m.elements[g.elem as usize];
        let zs: Vec<f64> = HEX_FACES[g.face as usize]
            .iter()
            .map(|&c| m.nodes[el[c] as usize][2])
            .collect();
        let want = match (g.face, zs.iter().cloned().fold(0.0, f64::max)) {
            (2, top) if top <= 9.0 => SurfaceKind::Far,
            (0, _) => SurfaceKind::Ground,
            _ => w.kind,
        };
        assert_eq!((g.elem, g.face, g.kind), (w.elem, w.face, want));
    }
}

/// A scene may name a mesh file instead of a generator.
#[test]
fn a_mesh_scene_validates() {
    let s = crate::common::scene("", "kind = \"mesh\"\nfile = \"dam.msh\"", "");
    match &s.geometry {
        groutready::mesh::geometry::Geometry::Mesh(g) => assert_eq!(g.file, "dam.msh"),
        other => panic!("mesh geometry expected, got {other:?}"),
    }
    let text = "kind = \"mesh\"\nfile = \"dam.msh\"\nn_blocks = 3";
    let err = std::panic::catch_unwind(|| crate::common::scene("", text, "")).unwrap_err();
    let msg = err.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(msg.contains("n_blocks"), "{msg}");
}

// ---- malformed meshes ----

/// The two blocks of models/two_blocks.toml (no rock, 4 × 2 elements per layer, 6 layers).
fn two_blocks() -> RawMesh {
    RawMesh::from_mesh(&generated("two_blocks.toml").0, "two.msh")
}

fn error(raw: &RawMesh) -> String {
    dam::build(raw, 3.0, 9.0).unwrap_err().to_string()
}

fn block(n_blocks: u32, elements_across: u32, n_lifts: u32, lift: f64) -> Mesh {
    let g = BlocksGeometry {
        n_blocks,
        block_length_m: 20.0,
        thickness_m: 10.0,
        n_lifts,
        elements_per_block: 2,
        elements_across,
        layers_per_lift: 1,
        rock_depth_m: 0.0,
        rock_layers: 1,
        rock_margin_m: 0.0,
        rock_margin_elements: 1,
        rock_grading_ratio: 1.0,
        face_element_m: None,
        joint_element_m: None,
        base_elevation_m: 0.0,
    };
    generate_blocks(&g, lift, 3.0 * lift).unwrap()
}

/// Block 1 = `a`, block 2 = `b` moved by `shift`, as one file.
fn side_by_side(a: &Mesh, b: &Mesh, shift: [f64; 3]) -> RawMesh {
    let mut raw = RawMesh::from_mesh(a, "pair.inp");
    let off = raw.nodes.len() as u32;
    raw.nodes.extend(
        b.nodes
            .iter()
            .map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]),
    );
    let first = raw.hexes.len() as u32;
    raw.hexes
        .extend(b.elements.iter().map(|h| h.map(|n| n + off)));
    raw.node_ids = (1..=raw.nodes.len() as u64).collect();
    raw.elem_ids = (1..=raw.hexes.len() as u64).collect();
    raw.element_groups
        .insert("block_2".into(), (first..raw.hexes.len() as u32).collect());
    raw
}

#[test]
fn an_inverted_element_is_named() {
    let mut raw = two_blocks();
    // Its top face twisted into a bow tie.
    raw.hexes[0].swap(6, 7);
    assert_eq!(
        error(&raw),
        "two.msh: element 1: (block 1) is inverted or degenerate: its Jacobian determinant is -9.375e0 m³ at its \
         corner node 41 (0.000, 5.000, 3.000) m in every corner order (its corners must bound a convex hexahedron)"
    );
}

#[test]
fn a_collapsed_element_is_named() {
    let mut raw = two_blocks();
    let h = raw.hexes[3];
    raw.hexes[3] = [h[0], h[1], h[2], h[3], h[0], h[1], h[2], h[3]];
    assert_eq!(
        error(&raw),
        "two.msh: element 4: (block 1) is inverted or degenerate: its Jacobian determinant is 0.000e0 m³ at its \
         corner node 4 (15.000, 0.000, 0.000) m in every corner order (its corners must bound a convex hexahedron)"
    );
}

#[test]
fn a_non_conforming_joint_is_found() {
    let raw = side_by_side(&block(1, 2, 6, 3.0), &block(1, 4, 6, 3.0), [20.0, 0.0, 0.0]);
    assert_eq!(
        error(&raw),
        "pair.inp: non-conforming joint between block 1 and block 2: the face of element 2 (block 1) centred at \
         (20.000, 2.500, 1.500) m lies on the face of element 25 (block 2) but does not match it node for node"
    );
}

#[test]
fn layers_that_do_not_make_lifts_are_named() {
    let raw = two_blocks();
    assert_eq!(
        dam::build(&raw, 4.0, 8.0).unwrap_err().to_string(),
        "two.msh: block 1: its layers do not make lifts of 4 m from its foundation at z = 0.000 m: no layer \
         boundary at z = 4.000 m (the nearest are z = 3.000 and 6.000 m)"
    );
}

#[test]
fn blocks_whose_levels_do_not_line_up_are_named() {
    // Block 2 (lifts of 2 m) stands 1 m beside block 1 (lifts of 3 m).
    let raw = side_by_side(&block(1, 2, 6, 3.0), &block(1, 2, 9, 2.0), [21.0, 0.0, 0.0]);
    assert_eq!(
        error(&raw),
        "pair.inp: element 1: (block 1) spans z = 0.000 … 3.000 m across the level z = 2.000 m of element 25 \
         (block 2): element layers must line up across the whole dam"
    );
}

#[test]
fn a_floating_block_is_named() {
    let mut raw = two_blocks();
    let mut moved = vec![false; raw.nodes.len()];
    for &e in &raw.element_groups["block_2"] {
        for &n in &raw.hexes[e as usize] {
            moved[n as usize] = true;
        }
    }
    for (p, _) in raw.nodes.iter_mut().zip(&moved).filter(|(_, &m)| m) {
        p[0] += 1.0;
        p[2] += 9.0;
    }
    assert_eq!(
        error(&raw),
        "two.msh: block 2: is floating: its element 5 at (23.500, 2.500, 10.500) m shares no face, directly or \
         through other blocks, with the lowest concrete level (z = 0.000 m)"
    );
}

#[test]
fn an_element_in_no_part_is_named() {
    let mut raw = two_blocks();
    // Element index 5 is block 2's second element of the first layer.
    raw.element_groups
        .get_mut("block_2")
        .unwrap()
        .retain(|&e| e != 5);
    assert_eq!(
        error(&raw),
        "two.msh: element 6: is in no part: every element must be in one element group block_<n> or rock"
    );
}

#[test]
fn an_element_in_two_parts_is_named() {
    let mut raw = two_blocks();
    let b1 = raw.element_groups.get_mut("block_1").unwrap();
    b1.push(5);
    b1.sort_unstable();
    assert_eq!(
        error(&raw),
        "two.msh: element 6: is in two parts, block_1 and block_2 (an element is in one block_<n> or in rock)"
    );
}

#[test]
fn a_gap_in_block_numbers_is_named() {
    let mut raw = two_blocks();
    let b2 = raw.element_groups.remove("block_2").unwrap();
    raw.element_groups.insert("block_3".into(), b2);
    assert_eq!(
        error(&raw),
        "two.msh: block numbers have a gap: block_2 is missing (found block_1, block_3); blocks are numbered 1, \
         2, … from the left bank"
    );
    raw.element_groups.clear();
    raw.element_groups
        .insert("concrete".into(), (0..raw.hexes.len() as u32).collect());
    assert_eq!(
        error(&raw),
        "two.msh: no element group block_<n>: the dam's blocks must be element groups block_1, block_2, … from \
         the left bank (groups found: concrete)"
    );
}

#[test]
fn blocks_numbered_from_the_right_bank_are_refused() {
    let mut raw = two_blocks();
    let b1 = raw.element_groups.remove("block_1").unwrap();
    let b2 = raw.element_groups.insert("block_2".into(), b1).unwrap();
    raw.element_groups.insert("block_1".into(), b2);
    assert_eq!(
        error(&raw),
        "two.msh: the blocks run from the right bank to the left: number them block_1, block_2, … from the left \
         bank (on the left looking downstream, along +y; z up)"
    );
}

#[test]
fn blocks_1_and_3_touching_are_named() {
    let mut raw = RawMesh::from_mesh(&block(3, 2, 6, 3.0), "three.msh");
    let b2 = raw.element_groups.remove("block_2").unwrap();
    let b3 = raw.element_groups.insert("block_3".into(), b2).unwrap();
    raw.element_groups.insert("block_2".into(), b3);
    assert_eq!(
        error(&raw),
        "three.msh: blocks 1 and 3 touch at node 3 (20.000, 0.000, 0.000) m: only neighbouring blocks j and j + 1 \
         may meet"
    );
}

#[test]
fn a_face_that_is_not_level_is_named() {
    let mut raw = two_blocks();
    let corner = raw
        .nodes
        .iter()
        .position(|p| *p == [0.0, 0.0, 18.0])
        .unwrap();
    raw.nodes[corner][2] += 0.5;
    assert_eq!(
        error(&raw),
        "two.msh: element 81: (block 1) its top face is not level: its corners lie at z = 18.500, 18.000, 18.000, \
         18.000 m (concrete element layers must be horizontal, to 1.8e-5 m)"
    );
}

#[test]
fn a_foundation_off_a_zone_boundary_is_named() {
    // Block 2 founded one lift higher, on a step of block 1's side.
    let a = block(1, 2, 6, 3.0);
    let b = block(1, 2, 5, 3.0);
    let raw = side_by_side(&a, &b, [20.0, 0.0, 3.0]);
    assert_eq!(
        error(&raw),
        "pair.inp: block 2: its foundation at z = 3.000 m is not on a zone boundary: zones are bands of 3 lifts \
         from the lowest concrete level z = 0.000 m; the nearest boundaries are z = 0.000 and 9.000 m"
    );
}

/// Build times of the demo and the Xiaowan-like arch, from shuffled,
/// re-oriented, joint-merged files
/// (`cargo test --release --test it -- --ignored build_time --nocapture`).
#[test]
#[ignore]
fn build_time_of_the_demo() {
    for scene in ["demo_arch.toml", "xiaowan_like.toml"] {
        let (m, lift, zone) = generated(scene);
        let raw = as_a_file_says(&m, 5);
        let t = std::time::Instant::now();
        let got = dam::build(&raw, lift, zone).unwrap();
        println!(
            "{scene}: {} elements, {} nodes: built in {:.3} s",
            got.elements.len(),
            got.nodes.len(),
            t.elapsed().as_secs_f64()
        );
        assert_eq!(face_pair_set(&got), face_pair_set(&m));
    }
}
