//! Mesh files: Gmsh MSH 4.1 (ASCII, binary) and Abaqus/CalculiX `.inp`
//! read into a `RawMesh` and written from one, and `groutready mesh`.
//!
//! The Gmsh fixtures in `tests/fixtures/gmsh/` were written by Gmsh 4.8.4
//! from the `.geo` files beside them (`gmsh hex.geo -3 -format msh41
//! [-bin] -o …`, `-format msh22`, `-o hex.inp`): a 2 × 1 × 4 m bar of
//! 1 × 0.5 × 1 m hexahedra, 12 in the physical volume `block_1` and 4 in
//! the unnamed physical volume 7, and the physical surface `far` (z = 0).

use std::collections::BTreeMap;
use std::path::Path;

use groutready::mesh::import::{
    read_file, read_inp, read_msh, write_inp, write_msh, write_msh_binary, RawMesh,
};
use groutready::mesh::{quality, Mesh, Part};
use groutready::scene::Scene;

use crate::common::{bin, repo};

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(repo(&format!("tests/fixtures/gmsh/{name}"))).unwrap()
}

fn scene_mesh(model: &str) -> Mesh {
    let path = repo(&format!("models/{model}.toml"));
    let scene = Scene::load(&path).unwrap();
    groutready::app::build_mesh(&scene, model).unwrap()
}

fn msh_err(text: &str) -> String {
    read_msh(text.as_bytes(), "t.msh").unwrap_err().to_string()
}

fn inp_err(text: &str) -> String {
    read_inp(text.as_bytes(), "t.inp").unwrap_err().to_string()
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "{p:?} missing from: {msg}");
    }
}

#[test]
fn gmsh_ascii_file_reads_with_groups_and_vtk_corner_order() {
    let m = read_msh(&fixture("hex_ascii.msh"), "hex_ascii.msh").unwrap();
    assert_eq!((m.nodes.len(), m.hexes.len()), (45, 16));
    assert_eq!(m.element_groups["block_1"].len(), 12);
    // the unnamed physical volume is named by its tag
    assert_eq!(m.element_groups["7"].len(), 4);
    assert_eq!(m.element_groups.len(), 2);
    let far = &m.node_groups["far"];
    assert_eq!(far.len(), 9);
    assert!(far.iter().all(|&n| m.nodes[n as usize][2] == 0.0));
    // Every element is a 1 × 0.5 × 1 box: det J = 0.5 / 8 at every corner
    // only when Gmsh's corner order is read as VTK's.
    let j = quality::min_jacobian(&m.nodes, &m.hexes).unwrap();
    assert!((j.value - 0.0625).abs() < 1e-15, "{j:?}");
    for h in &m.hexes {
        let x: [[f64; 3]; 8] = std::array::from_fn(|k| m.nodes[h[k] as usize]);
        assert!((groutready::mesh::hex_volume(&x) - 0.5).abs() < 1e-14);
    }
    // nodes and elements in the order of their numbers
    assert!(m.node_ids.windows(2).all(|w| w[0] < w[1]));
    assert!(m.elem_ids.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn gmsh_binary_and_inp_exports_read_as_the_ascii_file() {
    let ascii = read_msh(&fixture("hex_ascii.msh"), "x").unwrap();
    let binary = read_msh(&fixture("hex_binary.msh"), "x").unwrap();
    assert_eq!(binary, ascii);
    // Gmsh's .inp: the same nodes and bricks; sets named after the physical
    // groups (and Gmsh's per-entity sets); the physical surface, written as
    // CPS4 elements, becomes the node group `far`.
    let inp = read_inp(&fixture("hex.inp"), "x").unwrap();
    assert_eq!(inp.nodes, ascii.nodes);
    assert_eq!(inp.node_ids, ascii.node_ids);
    assert_eq!(inp.hexes, ascii.hexes);
    assert_eq!(
        inp.element_groups["block_1"],
        ascii.element_groups["block_1"]
    );
    assert_eq!(
        inp.element_groups["PhysicalVolume7"],
        ascii.element_groups["7"]
    );
    assert_eq!(inp.node_groups["far"], ascii.node_groups["far"]);
}

#[test]
fn old_msh_and_other_volume_types_are_refused_in_words() {
    let e = read_msh(&fixture("hex_22.msh"), "old.msh")
        .unwrap_err()
        .to_string();
    assert_has(&e, &["old.msh:2:", "\"2.2\"", "-format msh41"]);
    let e = read_msh(&fixture("mixed.msh"), "mixed.msh")
        .unwrap_err()
        .to_string();
    assert_has(
        &e,
        &[
            "mixed.msh:",
            "only 8-node hexahedra (type 5) are supported; found 72 4-node tetrahedra (type 4)",
        ],
    );
    let text = "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,1,1\n6,1,1,0\n\
                *ELEMENT, TYPE=C3D4\n1, 1,2,3,4\n2, 2,3,4,5\n*Element, type=c3d6\n3, 1,2,3,4,5,6\n";
    assert_has(
        &inp_err(text),
        &["t.inp:9: only 8-node hexahedra (C3D8, C3D8R, C3D8I) are supported; found 2 4-node tetrahedra (C3D4) and 1 6-node prism (C3D6)"],
    );
}

/// A unit cube as an ASCII MSH 4.1 file, with `nodes` in place of its node section body.
fn cube_msh(nodes: &str, elements: &str) -> String {
    format!(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n{nodes}$EndNodes\n$Elements\n{elements}$EndElements\n"
    )
}

const CUBE_NODES: &str = "1 8 1 8\n3 1 0 8\n1\n2\n3\n4\n5\n6\n7\n8\n\
    0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n";
const CUBE_ELEMENTS: &str = "1 1 1 1\n3 1 5 1\n1 1 2 3 4 5 6 7 8\n";

#[test]
fn msh_errors_name_file_line_and_what_was_expected() {
    assert!(read_msh(cube_msh(CUBE_NODES, CUBE_ELEMENTS).as_bytes(), "t").is_ok());
    // a node number twice: both lines
    let dup = CUBE_NODES.replace("\n8\n0 0 0", "\n7\n0 0 0");
    assert_has(
        &msh_err(&cube_msh(&dup, CUBE_ELEMENTS)),
        &["t.msh:14: node 7 is defined twice: line 13 and line 14"],
    );
    // a non-finite coordinate, on the coordinate's line
    let nan = CUBE_NODES.replace("1 1 1\n", "1 nan 1\n");
    assert_has(
        &msh_err(&cube_msh(&nan, CUBE_ELEMENTS)),
        &["t.msh:21: node 7: coordinates (1, NaN, 1) are not all finite"],
    );
    // an undefined node
    let undef = CUBE_ELEMENTS.replace("7 8\n", "7 9\n");
    assert_has(
        &msh_err(&cube_msh(CUBE_NODES, &undef)),
        &["t.msh:27: element 1 uses node 9, which is not defined"],
    );
    // a node no element uses
    let extra = CUBE_NODES
        .replace("1 8 1 8\n3 1 0 8\n", "1 9 1 9\n3 1 0 9\n")
        .replace("8\n0 0 0", "8\n9\n0 0 0")
        + "2 2 2\n";
    assert_has(
        &msh_err(&cube_msh(&extra, CUBE_ELEMENTS)),
        &["node 9 at (2, 2, 2) is used by no element"],
    );
    // two elements with one number
    let two = "1 2 1 1\n3 1 5 2\n1 1 2 3 4 5 6 7 8\n1 1 2 3 4 5 6 7 8\n";
    assert_has(
        &msh_err(&cube_msh(CUBE_NODES, two)),
        &["t.msh:28: element 1 is defined twice: line 27 and line 28"],
    );
    // a word where a number belongs, quoted and cut
    let word = CUBE_NODES.replace("0 1 1\n", &format!("0 1 {}\n", "y".repeat(500)));
    let e = msh_err(&cube_msh(&word, CUBE_ELEMENTS));
    assert_has(
        &e,
        &[
            "t.msh:22: expected a node's z coordinate, found \"yyy",
            "…\"",
        ],
    );
    assert!(e.len() < 250, "{e}");
    // truncated inside the nodes
    let full = cube_msh(CUBE_NODES, CUBE_ELEMENTS);
    let cut = &full[..full.find("1 1 1\n").unwrap()];
    assert_has(&msh_err(cut), &["t.msh:6: the number of nodes in the block is 8, more than the rest of the file can hold (is it cut short?)"]);
    let cut = &full[..full.find("5 6 7 8\n").unwrap()];
    assert_has(
        &msh_err(cut),
        &["t.msh:27: expected an element's node tag, found the end of the file"],
    );
    // not an MSH file at all
    assert_has(
        &msh_err("solid cube\nfacet normal 0 0 1\n"),
        &["t.msh:1: not a Gmsh MSH file: expected `$MeshFormat` first, found \"solid\""],
    );
    assert_has(&msh_err(""), &["not a Gmsh MSH file", "an empty file"]);
    // an unknown section is skipped, a section without its end is not
    let with_data = full.clone() + "$NodeData\n1\n\"T\"\n$EndNodeData\n";
    assert!(read_msh(with_data.as_bytes(), "t").is_ok());
    assert_has(
        &msh_err(&(full + "$Periodic\n1\n")),
        &["section `$Periodic` has no `$EndPeriodic` line"],
    );
    // no hexahedra
    let no_hex = cube_msh("0 0 0 0\n", "0 0 0 0\n");
    assert_has(
        &msh_err(&no_hex),
        &["t.msh: no 8-node hexahedra in the file"],
    );
}

const CUBE_INP: &str = "** a unit cube\n*Node, nset=all_nodes\n1, 0, 0, 0\n2, 1., 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n\
    5, 0, 0, 1.0\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n*ELEMENT, TYPE=C3D8R,\n ELSET=Block_1\n1, 1, 2, 3, 4,\n 5, 6, 7, 8\n";

#[test]
fn inp_reads_sets_generate_continuations_and_case() {
    let text = format!(
        "{CUBE_INP}*MATERIAL, NAME=concrete\n*ELASTIC\n30e9, 0.2\n*elset, elset=BLOCK_1\n1\n\
         *ELSET, ELSET=both\nblock_1, 1\n*NSET, NSET=bottom, GENERATE\n1, 4, 1\n*nset, nset=odd, generate\n1, 7, 2\n\
         *ELEMENT, TYPE=S4R, ELSET=skin\n10, 1, 2, 3, 4\n*STEP\n*STATIC\n*END STEP\n"
    );
    let m = read_inp(text.as_bytes(), "t.inp").unwrap();
    assert_eq!(m.hexes, vec![[0, 1, 2, 3, 4, 5, 6, 7]]);
    assert_eq!(m.nodes[1], [1.0, 0.0, 0.0]);
    let groups: Vec<(&str, &[u32])> = m
        .element_groups
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_slice()))
        .collect();
    // one set under its first spelling; a set named in another set
    assert_eq!(groups, vec![("Block_1", &[0u32][..]), ("both", &[0][..])]);
    let nodes: BTreeMap<&str, Vec<u32>> = m
        .node_groups
        .iter()
        .map(|(k, v)| (k.as_str(), v.clone()))
        .collect();
    assert_eq!(nodes["all_nodes"], (0..8).collect::<Vec<u32>>());
    assert_eq!(nodes["bottom"], vec![0, 1, 2, 3]);
    assert_eq!(nodes["odd"], vec![0, 2, 4, 6]);
    // a set of shell elements only is a node group of their nodes
    assert_eq!(nodes["skin"], vec![0, 1, 2, 3]);
}

#[test]
fn inp_errors_name_file_line_and_what_was_expected() {
    let dup = CUBE_INP.replace("8, 0, 1, 1\n", "8, 0, 1, 1\n3, 5, 5, 5\n");
    assert_has(
        &inp_err(&dup),
        &["t.inp:11: node 3 is defined twice: line 5 and line 11"],
    );
    let two = format!("{CUBE_INP}1, 1, 2, 3, 4, 5, 6, 7, 8\n");
    assert_has(
        &inp_err(&two),
        &["t.inp:15: element 1 is defined twice: line 13 and line 15"],
    );
    let undef = CUBE_INP.replace(" 5, 6, 7, 8", " 5, 6, 7, 80");
    assert_has(
        &inp_err(&undef),
        &["t.inp:13: element 1 uses node 80, which is not defined"],
    );
    let unused = CUBE_INP.replace("8, 0, 1, 1\n", "8, 0, 1, 1\n17, 3, 4, 5.5\n");
    assert_has(
        &inp_err(&unused),
        &["t.inp:11: node 17 at (3, 4, 5.5) is used by no element"],
    );
    let inf = CUBE_INP.replace("6, 1, 0, 1", "6, 1, inf, 1");
    assert_has(
        &inp_err(&inf),
        &["t.inp:8: node 6: coordinate y = inf is not a finite number"],
    );
    let short = CUBE_INP.replace(" 5, 6, 7, 8\n", " 5, 6\n");
    assert_has(
        &inp_err(&short),
        &["t.inp:13: element 1 (C3D8R): expected 8 nodes, found 6"],
    );
    // truncated in the middle of a continued element line
    let cut = &CUBE_INP[..CUBE_INP.find(" 5, 6, 7, 8").unwrap()];
    assert_has(
        &inp_err(cut),
        &["t.inp:13: element 1 (C3D8R): expected 8 nodes, found 4"],
    );
    let word = CUBE_INP.replace("4, 0, 1, 0", "4, 0, one, 0");
    assert_has(
        &inp_err(&word),
        &["t.inp:6: expected a node line `number, x, y, z`, found \"4, 0, one, 0\""],
    );
    assert_has(
        &inp_err("<?xml version=\"1.0\"?>\n<VTKFile>\n"),
        &["t.inp:1: not an Abaqus/CalculiX input file"],
    );
    let inc = format!("*INCLUDE, INPUT=nodes.inp\n{CUBE_INP}");
    assert_has(
        &inp_err(&inc),
        &["t.inp:1: *INCLUDE is not supported: merge \"nodes.inp\" into this file"],
    );
    let set = format!("{CUBE_INP}*ELSET, ELSET=x\n1, 2\n");
    assert_has(
        &inp_err(&set),
        &["t.inp:16: group \"x\" lists element 2, which is not defined"],
    );
    let unknown_set = format!("{CUBE_INP}*ELSET, ELSET=x\nnowhere\n");
    assert_has(
        &inp_err(&unknown_set),
        &["t.inp:16: expected an element number or element set defined above, found \"nowhere\""],
    );
    let huge = format!("{CUBE_INP}*NSET, NSET=x, GENERATE\n1, 99999999999, 1\n");
    assert_has(
        &inp_err(&huge),
        &["t.inp:16: GENERATE range 1, 99999999999, 1"],
    );
    assert_has(
        &inp_err("*NODE\n1, 0, 0, 0\n"),
        &["t.inp: no 8-node hexahedra in the file"],
    );
}

/// `raw` written by `write` and read back by `read_file`.
fn round_trip(
    raw: &RawMesh,
    dir: &Path,
    name: &str,
    write: fn(&RawMesh, &Path) -> Result<(), groutready::mesh::import::MeshFileError>,
) -> RawMesh {
    let path = dir.join(name);
    write(raw, &path).unwrap();
    read_file(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn bundled_meshes_round_trip_bit_exact_through_msh_binary_msh_and_inp() {
    let tmp = tempfile::tempdir().unwrap();
    for model in ["small_dam_joints", "demo_arch"] {
        let mesh = scene_mesh(model);
        for (name, write) in [
            ("m.msh", write_msh as fn(&RawMesh, &Path) -> _),
            ("b.msh", write_msh_binary),
            ("m.inp", write_inp),
        ] {
            let source = tmp.path().join(name).display().to_string();
            let raw = RawMesh::from_mesh(&mesh, &source);
            let back = round_trip(&raw, tmp.path(), name, write);
            // bit-exact coordinates: `==` on f64 (and no NaN in a mesh)
            assert_eq!(back, raw, "{model} through {name}");
        }
    }
}

#[test]
fn node_groups_survive_msh_as_surfaces_and_inp_as_nsets() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = scene_mesh("small_dam_joints");
    let mut raw = RawMesh::from_mesh(&mesh, "x");
    let zmin = mesh
        .nodes
        .iter()
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    let bottom: Vec<u32> = (0..mesh.nodes.len() as u32)
        .filter(|&n| mesh.nodes[n as usize][2] == zmin)
        .collect();
    assert!(bottom.len() > 10);
    raw.node_groups.insert("far".into(), bottom.clone());
    raw.element_groups.insert(
        "all concrete".into(),
        (0..mesh.elements.len() as u32)
            .filter(|&e| matches!(mesh.parts[e as usize], Part::Concrete { .. }))
            .collect(),
    );
    for (name, write) in [
        ("g.msh", write_msh as fn(&RawMesh, &Path) -> _),
        ("g.bin.msh", write_msh_binary),
        ("g.inp", write_inp),
    ] {
        raw.source = tmp.path().join(name).display().to_string();
        let back = round_trip(&raw, tmp.path(), name, write);
        assert_eq!(back, raw, "{name}");
    }
}

/// A small deterministic generator for the damaged files.
fn lcg(state: &mut u64) -> u64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *state >> 33
}

#[test]
fn damaged_files_give_errors_never_panics() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = scene_mesh("small_dam_joints");
    let mut raw = RawMesh::from_mesh(&mesh, "x");
    raw.node_groups.insert("far".into(), vec![0, 1, 2, 3, 4, 5]);
    let mut files: Vec<(&str, Vec<u8>)> = Vec::new();
    for (name, write) in [
        ("a.msh", write_msh as fn(&RawMesh, &Path) -> _),
        ("b.msh", write_msh_binary),
        ("c.inp", write_inp),
    ] {
        let path = tmp.path().join(name);
        write(&raw, &path).unwrap();
        files.push((name, std::fs::read(&path).unwrap()));
    }
    files.push(("hex_binary.msh", fixture("hex_binary.msh")));
    files.push(("hex.inp", fixture("hex.inp")));
    let read = |name: &str, bytes: &[u8]| {
        if name.ends_with(".msh") {
            read_msh(bytes, name).map(|_| ())
        } else {
            read_inp(bytes, name).map(|_| ())
        }
    };
    let mut state = 7u64;
    let (mut ok, mut err) = (0, 0);
    for (name, bytes) in &files {
        let n = bytes.len();
        let mut cases: Vec<Vec<u8>> = (0..60).map(|k| bytes[..k * n / 60].to_vec()).collect();
        for _ in 0..300 {
            let mut b = bytes.clone();
            for _ in 0..1 + lcg(&mut state) % 4 {
                let i = lcg(&mut state) as usize % n;
                b[i] = match lcg(&mut state) % 3 {
                    0 => b[i] ^ (1 << (lcg(&mut state) % 8)),
                    1 => b"0123456789 \n$,-.e*"[lcg(&mut state) as usize % 18],
                    _ => lcg(&mut state) as u8,
                };
            }
            cases.push(b);
        }
        for (k, case) in cases.iter().enumerate() {
            let r = std::panic::catch_unwind(|| read(name, case));
            match r {
                Ok(Ok(())) => ok += 1,
                Ok(Err(e)) => {
                    assert!(e.to_string().starts_with(name), "{name} case {k}: {e}");
                    err += 1
                }
                Err(_) => panic!("{name}: case {k} panicked"),
            }
        }
    }
    assert!(err > 1000 && ok > 10, "{ok} read, {err} refused");
}

/// Decodes a VTU `DataArray` (base64 of an 8-byte length and the data).
fn vtu_array(xml: &str, name: &str) -> Vec<u8> {
    let start = xml
        .find(&format!("Name=\"{name}\""))
        .unwrap_or_else(|| panic!("no {name}"));
    let body = &xml[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    let mut bits = 0u32;
    let (mut acc, mut out) = (0u32, Vec::new());
    for c in body.trim().bytes().filter(|&c| c != b'=') {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            _ => 63,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    out[8..].to_vec()
}

fn f64s(b: &[u8]) -> Vec<f64> {
    b.chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn mesh_command_writes_vtu_msh_inp_and_prints_the_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = scene_mesh("small_dam_joints");
    let rock = mesh.parts.iter().filter(|p| **p == Part::Rock).count();
    let zones_of = |j: u32| mesh.zones.iter().filter(|z| z.joint == j).count();
    let lifts: Vec<u32> = mesh.blocks.iter().map(|b| b.n_lifts).collect();
    let expected = [
        format!(
            "blocks: {}, lifts per block {}–{}",
            mesh.blocks.len(),
            lifts.iter().min().unwrap(),
            lifts.iter().max().unwrap()
        ),
        format!(
            "joints: {}, grouting zones per joint {}–{}",
            mesh.blocks.len() - 1,
            zones_of(1),
            zones_of(4)
        ),
        format!(
            "elements: {} ({} concrete, {rock} rock)",
            mesh.elements.len(),
            mesh.elements.len() - rock
        ),
        format!("nodes: {}", mesh.nodes.len()),
        format!("thermal dofs: {}", mesh.n_thermal_dofs),
        format!("mechanical dofs: {} (3 per node)", 3 * mesh.nodes.len()),
        // 6 × 6 × 3 m concrete bricks: det J = 108 / 8 at every corner
        "smallest Jacobian determinant: 1.350000e1 m³".to_string(),
    ];
    assert_eq!((zones_of(1), zones_of(4)), (7, 7));
    for ext in ["vtu", "msh", "inp"] {
        let out = tmp.path().join(format!("small.{ext}"));
        let o = bin()
            .args(["mesh", "models/small_dam_joints.toml", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for line in &expected {
            assert!(stdout.contains(line.as_str()), "{line:?} not in:\n{stdout}");
        }
        assert!(
            stdout.contains("worst aspect ratio (longest / shortest edge): "),
            "{stdout}"
        );
        if ext == "vtu" {
            let xml = std::fs::read_to_string(&out).unwrap();
            assert!(xml.contains(&format!(
                "NumberOfPoints=\"{}\" NumberOfCells=\"{}\"",
                mesh.nodes.len(),
                mesh.elements.len()
            )));
            // zone: the elevation band of the element's centre, 0 for rock
            let zone = f64s(&vtu_array(&xml, "zone"));
            let band = mesh.zone_lifts as f64 * mesh.lift_height;
            for (e, z) in zone.iter().enumerate() {
                let zc = (0..8)
                    .map(|k| mesh.nodes[mesh.elements[e][k] as usize][2])
                    .sum::<f64>()
                    / 8.0;
                let want = match mesh.parts[e] {
                    Part::Rock => 0.0,
                    Part::Concrete { .. } => ((zc - mesh.layer_z[0]) / band).floor() + 1.0,
                };
                assert_eq!(*z, want, "element {e}");
            }
            // joint: the nodes of joint j's faces, at x = 18 j
            let joint = f64s(&vtu_array(&xml, "joint"));
            let on: Vec<usize> = (0..joint.len()).filter(|&n| joint[n] > 0.0).collect();
            assert!(!on.is_empty());
            for &n in &on {
                assert_eq!(mesh.nodes[n][0], 18.0 * joint[n], "node {n}");
            }
            let n_face_nodes: std::collections::BTreeSet<u32> = mesh
                .face_pairs
                .iter()
                .flat_map(|f| f.nodes_a.into_iter().chain(f.nodes_b))
                .collect();
            assert_eq!(on.len(), n_face_nodes.len());
        } else {
            let back = read_file(&out).unwrap();
            assert_eq!(back, RawMesh::from_mesh(&mesh, &back.source));
            assert!(back.source.ends_with(&format!("small.{ext}")));
        }
    }
    let o = bin()
        .args(["mesh", "models/small_dam_joints.toml", "--out"])
        .arg(tmp.path().join("m.stl"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_has(&err, &[".vtu", ".msh", ".inp", "m.stl"]);
}
