//! Gmsh MSH 4.1 meshes, ASCII and binary: [`read_msh`] into a [`RawMesh`],
//! [`write_msh`] (ASCII) and [`write_msh_binary`] from one.
//!
//! # Reading
//!
//! Sections `$MeshFormat` (version 4.1 only: older files are refused with
//! the `gmsh -format msh41` that re-exports them), `$PhysicalNames`,
//! `$Entities`, `$Nodes`, `$Elements`; any other section (`$Periodic`,
//! `$NodeData`, …) is skipped to its `$End…` line. In a binary file the
//! integer `1` after the format line gives the byte order; `int` is 4 bytes,
//! `size_t` the file's data size (4 or 8), doubles 8.
//!
//! * Element blocks of dimension 3: 8-node hexahedra (type 5, corner order
//!   = VTK's) go into the element groups named by the physical groups of
//!   their volume entity (`$PhysicalNames`; an unnamed group is named by its
//!   tag number). Any other volume type is an error naming every type found
//!   in words with its count.
//! * Element blocks of dimension 2 (any type): all their nodes go into the
//!   node groups of their surface entity's physical groups.
//! * Points and lines (dimensions 0, 1) are ignored.
//!
//! Every count read from the file is checked against the bytes left before
//! anything is allocated for it, so no input makes the reader panic or run
//! out of memory (the fuzz-style test in `tests/it/mesh_files.rs`).
//!
//! # Writing
//!
//! One volume entity per distinct set of element groups holding an element
//! (one per group when the groups partition the elements, as for
//! [`RawMesh::from_mesh`]), each with those groups as physical tags, so the
//! groups survive a read. A node group is written as a physical surface of
//! the boundary quadrangles whose four corners are all in the group; a node
//! group's nodes on no such face do not survive the round trip. All nodes
//! sit in one node block on the first volume entity. Coordinates are
//! written with Rust's shortest round-trip formatting, so an ASCII round
//! trip is bit-exact; the tests read back the bundled scenes' meshes equal.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::file::{
    check_writable, quote, signatures, Builder, MeshFileError, Positions, Unsupported,
};
use super::RawMesh;
use crate::mesh::HEX_FACES;

/// Dimension, node count and names (singular, plural) of a Gmsh element type.
fn element_type(t: i64) -> Option<(u8, usize, &'static str, &'static str)> {
    Some(match t {
        1 => (1, 2, "2-node line", "2-node lines"),
        2 => (2, 3, "3-node triangle", "3-node triangles"),
        3 => (2, 4, "4-node quadrangle", "4-node quadrangles"),
        4 => (3, 4, "4-node tetrahedron", "4-node tetrahedra"),
        5 => (3, 8, "8-node hexahedron", "8-node hexahedra"),
        6 => (3, 6, "6-node prism", "6-node prisms"),
        7 => (3, 5, "5-node pyramid", "5-node pyramids"),
        8 => (1, 3, "3-node line", "3-node lines"),
        9 => (2, 6, "6-node triangle", "6-node triangles"),
        10 => (2, 9, "9-node quadrangle", "9-node quadrangles"),
        11 => (3, 10, "10-node tetrahedron", "10-node tetrahedra"),
        12 => (3, 27, "27-node hexahedron", "27-node hexahedra"),
        13 => (3, 18, "18-node prism", "18-node prisms"),
        14 => (3, 14, "14-node pyramid", "14-node pyramids"),
        15 => (0, 1, "point", "points"),
        16 => (2, 8, "8-node quadrangle", "8-node quadrangles"),
        17 => (3, 20, "20-node hexahedron", "20-node hexahedra"),
        18 => (3, 15, "15-node prism", "15-node prisms"),
        19 => (3, 13, "13-node pyramid", "13-node pyramids"),
        20 => (2, 9, "9-node triangle", "9-node triangles"),
        21 => (2, 10, "10-node triangle", "10-node triangles"),
        26 => (1, 4, "4-node line", "4-node lines"),
        27 => (1, 5, "5-node line", "5-node lines"),
        28 => (1, 6, "6-node line", "6-node lines"),
        29 => (3, 20, "20-node tetrahedron", "20-node tetrahedra"),
        92 => (3, 64, "64-node hexahedron", "64-node hexahedra"),
        93 => (3, 125, "125-node hexahedron", "125-node hexahedra"),
        _ => return None,
    })
}

/// Reads through an MSH file: whitespace-separated tokens in ASCII
/// sections, fixed-size values in binary ones.
struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    binary: bool,
    big_endian: bool,
    size_t: usize,
    file: &'a str,
}

type Res<T> = Result<T, MeshFileError>;

impl<'a> Cursor<'a> {
    fn positions(&self) -> Positions<'a> {
        if self.binary {
            Positions::Bytes
        } else {
            Positions::TextOffsets(self.data)
        }
    }

    fn err(&self, pos: usize, message: impl Into<String>) -> MeshFileError {
        MeshFileError::At {
            file: self.file.to_string(),
            at: self.positions().at(pos as u64),
            message: message.into(),
        }
    }

    fn skip_ws(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next whitespace-separated token, or `None` at the end of the file.
    fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.data[start..self.pos]))
    }

    fn expect_token(&mut self, what: &str) -> Res<(usize, String)> {
        match self.token() {
            Some((p, t)) => Ok((p, String::from_utf8_lossy(t).into_owned())),
            None => Err(self.err(
                self.data.len(),
                format!("expected {what}, found the end of the file"),
            )),
        }
    }

    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Res<(usize, T)> {
        let (p, t) = self.expect_token(what)?;
        match t.parse::<T>() {
            Ok(v) => Ok((p, v)),
            Err(_) => Err(self.err(p, format!("expected {what}, found {}", quote(&t)))),
        }
    }

    fn bytes(&mut self, n: usize, what: &str) -> Res<(usize, &'a [u8])> {
        let start = self.pos;
        if self.data.len() - start < n {
            return Err(self.err(start, format!("expected {what}, found the end of the file")));
        }
        self.pos += n;
        Ok((start, &self.data[start..start + n]))
    }

    fn uint_bytes(&self, b: &[u8]) -> u64 {
        let mut v: u64 = 0;
        let mut push = |x: u8| v = (v << 8) | u64::from(x);
        if self.big_endian {
            b.iter().for_each(|&x| push(x));
        } else {
            b.iter().rev().for_each(|&x| push(x));
        }
        v
    }

    fn int(&mut self, what: &str) -> Res<(usize, i64)> {
        if !self.binary {
            return self.parse(what);
        }
        let (p, b) = self.bytes(4, what)?;
        Ok((p, i64::from(self.uint_bytes(b) as u32 as i32)))
    }

    fn size(&mut self, what: &str) -> Res<(usize, u64)> {
        if !self.binary {
            return self.parse(what);
        }
        let (p, b) = self.bytes(self.size_t, what)?;
        Ok((p, self.uint_bytes(b)))
    }

    fn float(&mut self, what: &str) -> Res<(usize, f64)> {
        if !self.binary {
            return self.parse(what);
        }
        let (p, b) = self.bytes(8, what)?;
        Ok((p, f64::from_bits(self.uint_bytes(b))))
    }

    /// A count of items each taking at least `min_bytes`: refused when the
    /// file is too short to hold them (a damaged count must not allocate).
    fn count(&mut self, what: &str, min_bytes: usize) -> Res<usize> {
        let (p, n) = self.size(what)?;
        let left = (self.data.len() - self.pos) as u64;
        if n > left / min_bytes.max(1) as u64 {
            return Err(self.err(
                p,
                format!(
                    "{what} is {n}, more than the rest of the file can hold (is it cut short?)"
                ),
            ));
        }
        Ok(n as usize)
    }

    /// A count in an ASCII or binary section: items of `ascii` bytes at
    /// least (a digit and a space) or `binary` bytes.
    fn count_of(&mut self, what: &str, ascii: usize, binary: usize) -> Res<usize> {
        let min = if self.binary { binary } else { ascii };
        self.count(what, min)
    }

    /// The end of a section's header line, where binary data starts.
    fn end_of_line(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.data.len());
    }

    /// The tokens left on the current line (ASCII elements of unknown type).
    fn rest_of_line(&mut self) -> usize {
        let mut n = 0;
        loop {
            while self.pos < self.data.len() && matches!(self.data[self.pos], b' ' | b'\t' | b'\r')
            {
                self.pos += 1;
            }
            if self.pos >= self.data.len() || self.data[self.pos] == b'\n' {
                return n;
            }
            self.token();
            n += 1;
        }
    }

    fn expect_end(&mut self, section: &str) -> Res<()> {
        let want = format!("$End{section}");
        let (p, t) = self.expect_token(&format!("`{want}`"))?;
        if t != want {
            return Err(self.err(p, format!("expected `{want}`, found {}", quote(&t))));
        }
        Ok(())
    }

    /// Skips an unknown section to the line after its `$End…`.
    fn skip_section(&mut self, name: &str, at: usize) -> Res<()> {
        let end = format!("\n$End{name}");
        let hay = &self.data[self.pos..];
        match hay.windows(end.len()).position(|w| w == end.as_bytes()) {
            Some(i) => {
                self.pos += i + end.len();
                Ok(())
            }
            None => Err(self.err(at, format!("section `${name}` has no `$End{name}` line"))),
        }
    }
}

/// Physical names and the physical tags of each entity, for the groups.
#[derive(Default)]
struct Physical {
    names: HashMap<(i64, i64), String>,
    /// (dim, entity tag) → physical tags
    entities: HashMap<(i64, i64), Vec<i64>>,
}

impl Physical {
    fn groups_of(&self, dim: i64, entity: i64) -> Vec<String> {
        let tags = self
            .entities
            .get(&(dim, entity.wrapping_abs()))
            .map(Vec::as_slice)
            .unwrap_or(&[]);
        tags.iter()
            .map(|&p| {
                self.names
                    .get(&(dim, p.wrapping_abs()))
                    .cloned()
                    .unwrap_or_else(|| p.wrapping_abs().to_string())
            })
            .collect()
    }
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary); `file` names it in messages
/// and becomes the mesh's `source`.
pub fn read_msh(data: &[u8], file: &str) -> Result<RawMesh, MeshFileError> {
    let mut c = Cursor {
        data,
        pos: 0,
        binary: false,
        big_endian: false,
        size_t: 8,
        file,
    };
    mesh_format(&mut c)?;
    let mut b = Builder::new(file, c.positions());
    let mut phys = Physical::default();
    let mut unsupported = Unsupported::default();
    while let Some((at, t)) = c.token() {
        let name = String::from_utf8_lossy(t).into_owned();
        let Some(section) = name.strip_prefix('$') else {
            return Err(c.err(
                at,
                format!(
                    "expected a section such as `$Nodes`, found {}",
                    quote(&name)
                ),
            ));
        };
        match section {
            "PhysicalNames" => physical_names(&mut c, &mut phys)?,
            "Entities" => entities(&mut c, &mut phys)?,
            "Nodes" => nodes(&mut c, &mut b)?,
            "Elements" => elements(&mut c, &mut b, &phys, &mut unsupported)?,
            "MeshFormat" => return Err(c.err(at, "a second `$MeshFormat` section")),
            _ => {
                c.skip_section(section, at)?;
                continue;
            }
        }
        c.expect_end(section)?;
    }
    if let Some(e) = unsupported.error(file, &c.positions(), "(type 5) ") {
        return Err(e);
    }
    // A named physical group is a group even when it holds nothing.
    for ((dim, _), name) in &phys.names {
        match dim {
            3 => drop(b.element_groups.entry(name.clone()).or_default()),
            2 => drop(b.node_groups.entry(name.clone()).or_default()),
            _ => {}
        }
    }
    b.finish()
}

/// `$MeshFormat`: version 4.1, ASCII or binary, data size, byte order.
fn mesh_format(c: &mut Cursor) -> Res<()> {
    let first = c.token();
    let found = first.map(|(_, t)| String::from_utf8_lossy(t).into_owned());
    match found.as_deref() {
        Some("$MeshFormat") => {}
        Some("$NOD") | Some("$NOE") => {
            return Err(c.err(0, "this is an MSH 1 file; only MSH 4.1 is read: re-export it with `gmsh FILE -3 -format msh41 -o FILE.msh` (or File > Export, Version 4 ASCII)"));
        }
        other => {
            let f = other.map(quote).unwrap_or_else(|| "an empty file".into());
            return Err(c.err(
                0,
                format!("not a Gmsh MSH file: expected `$MeshFormat` first, found {f}"),
            ));
        }
    }
    let (p, version) = c.expect_token("the MSH version")?;
    if version != "4.1" {
        return Err(c.err(p, format!("MSH version {} is not supported, only 4.1: re-export the mesh with `gmsh FILE -3 -format msh41 -o FILE.msh` (or File > Export, Version 4)", quote(&version))));
    }
    let (p, kind) = c.parse::<i64>("the file type (0 ASCII, 1 binary)")?;
    c.binary = match kind {
        0 => false,
        1 => true,
        _ => {
            return Err(c.err(
                p,
                format!("expected the file type 0 (ASCII) or 1 (binary), found {kind}"),
            ))
        }
    };
    let (p, size) = c.parse::<usize>("the data size")?;
    if size != 4 && size != 8 {
        return Err(c.err(p, format!("expected the data size 8 (or 4), found {size}")));
    }
    c.size_t = size;
    if c.binary {
        c.end_of_line();
        let (p, one) = c.bytes(4, "the binary integer 1 (byte order)")?;
        if one == [1, 0, 0, 0] {
            c.big_endian = false;
        } else if one == [0, 0, 0, 1] {
            c.big_endian = true;
        } else {
            return Err(c.err(p, format!("expected the binary integer 1 that gives the byte order, found the bytes {one:?}")));
        }
    }
    c.expect_end("MeshFormat")
}

/// `$PhysicalNames` (ASCII in both kinds of file): `dim tag "name"` lines.
fn physical_names(c: &mut Cursor, phys: &mut Physical) -> Res<()> {
    let binary = std::mem::replace(&mut c.binary, false);
    let result = (|| {
        let n = c.count("the number of physical names", 6)?;
        for _ in 0..n {
            let (_, dim) = c.parse::<i64>("a physical group's dimension")?;
            let (_, tag) = c.parse::<i64>("a physical group's tag")?;
            c.skip_ws();
            let start = c.pos;
            if c.data.get(c.pos) != Some(&b'"') {
                let (p, t) = c.expect_token("a quoted physical name")?;
                return Err(c.err(
                    p,
                    format!("expected a quoted physical name, found {}", quote(&t)),
                ));
            }
            let rest = &c.data[start + 1..];
            let Some(len) = rest.iter().position(|&b| b == b'"' || b == b'\n') else {
                return Err(c.err(start, "a physical name without its closing quote"));
            };
            if rest[len] != b'"' {
                return Err(c.err(start, "a physical name without its closing quote"));
            }
            let name = String::from_utf8_lossy(&rest[..len]).into_owned();
            c.pos = start + 1 + len + 1;
            phys.names.insert((dim, tag), name);
        }
        Ok(())
    })();
    c.binary = binary;
    result
}

/// `$Entities`: each entity's physical tags.
fn entities(c: &mut Cursor, phys: &mut Physical) -> Res<()> {
    start_data(c);
    let mut counts = [0usize; 4];
    for (d, n) in counts.iter_mut().enumerate() {
        *n = c.count_of(&format!("the number of entities of dimension {d}"), 2, 4)?;
    }
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let (_, tag) = c.int("an entity tag")?;
            let n_coords = if dim == 0 { 3 } else { 6 };
            for _ in 0..n_coords {
                c.float("an entity's bounding box coordinate")?;
            }
            let n_phys = c.count_of("the number of physical tags", 2, 4)?;
            let mut tags = Vec::with_capacity(n_phys);
            for _ in 0..n_phys {
                tags.push(c.int("a physical tag")?.1);
            }
            if dim > 0 {
                let n_bound = c.count_of("the number of bounding entities", 2, 4)?;
                for _ in 0..n_bound {
                    c.int("a bounding entity tag")?;
                }
            }
            phys.entities.insert((dim as i64, tag), tags);
        }
    }
    Ok(())
}

/// Starts a section's data: binary data begins after the header line.
fn start_data(c: &mut Cursor) {
    if c.binary {
        c.end_of_line();
    }
}

/// `$Nodes`: blocks of node tags then their coordinates.
fn nodes(c: &mut Cursor, b: &mut Builder) -> Res<()> {
    start_data(c);
    let blocks = c.count_of("the number of node blocks", 8, 8 + c.size_t)?;
    for _ in 0..3 {
        c.size("the node count and tag range")?;
    }
    for _ in 0..blocks {
        let (_, dim) = c.int("a node block's entity dimension")?;
        c.int("a node block's entity tag")?;
        let (p, parametric) = c.int("a node block's parametric flag (0 or 1)")?;
        if !(0..=1).contains(&parametric) || !(0..=3).contains(&dim) {
            return Err(c.err(p, format!("expected an entity dimension 0–3 and a parametric flag 0 or 1, found {dim} and {parametric}")));
        }
        let n = c.count_of("the number of nodes in the block", 8, c.size_t + 24)?;
        let mut tags = Vec::with_capacity(n);
        for _ in 0..n {
            tags.push(c.size("a node tag")?);
        }
        let extra = if parametric == 1 { dim as usize } else { 0 };
        for (tp, tag) in tags {
            let (cp, x) = c.float("a node's x coordinate")?;
            let y = c.float("a node's y coordinate")?.1;
            let z = c.float("a node's z coordinate")?.1;
            for _ in 0..extra {
                c.float("a node's parametric coordinate")?;
            }
            if ![x, y, z].iter().all(|v| v.is_finite()) {
                return Err(c.err(
                    cp,
                    format!("node {tag}: coordinates ({x}, {y}, {z}) are not all finite numbers"),
                ));
            }
            b.node(tag, [x, y, z], tp as u64)?;
        }
    }
    Ok(())
}

/// `$Elements`: hexahedra into element groups, surface elements' nodes
/// into node groups, other volume types counted for the error.
fn elements(
    c: &mut Cursor,
    b: &mut Builder,
    phys: &Physical,
    unsupported: &mut Unsupported,
) -> Res<()> {
    start_data(c);
    let blocks = c.count_of("the number of element blocks", 8, 12 + c.size_t)?;
    for _ in 0..3 {
        c.size("the element count and tag range")?;
    }
    for _ in 0..blocks {
        let (_, dim) = c.int("an element block's entity dimension")?;
        let (_, entity) = c.int("an element block's entity tag")?;
        let (tp, ty) = c.int("an element type")?;
        let known = element_type(ty);
        let n = c.count_of("the number of elements in the block", 2, c.size_t * 2)?;
        if c.binary && known.is_none() {
            return Err(c.err(tp, format!("unknown element type {ty}")));
        }
        let groups = phys.groups_of(dim, entity);
        if dim == 3 && ty != 5 {
            let (one, many) = known.map(|k| (k.2, k.3)).unwrap_or(("element", "elements"));
            unsupported.add(one, many, &format!("type {ty}"), n, tp as u64);
        }
        for _ in 0..n {
            let (ep, tag) = c.size("an element tag")?;
            let corners = element_nodes(c, known.map(|k| k.1))?;
            if dim == 3 && ty == 5 {
                let hex: [u64; 8] = std::array::from_fn(|k| corners[k]);
                b.hex(tag, hex, ep as u64)?;
                for g in &groups {
                    b.element_groups
                        .entry(g.clone())
                        .or_default()
                        .members
                        .push((tag, ep as u64));
                }
            } else if dim == 2 {
                for g in &groups {
                    let members = &mut b.node_groups.entry(g.clone()).or_default().members;
                    members.extend(corners.iter().map(|&n| (n, ep as u64)));
                }
            }
        }
    }
    Ok(())
}

/// An element's node tags: `n` of them, or (ASCII, type unknown) the rest of the line.
fn element_nodes(c: &mut Cursor, n: Option<usize>) -> Res<Vec<u64>> {
    let Some(n) = n else {
        let start = c.pos;
        let k = c.rest_of_line();
        c.pos = start;
        return (0..k)
            .map(|_| c.size("an element's node tag").map(|v| v.1))
            .collect();
    };
    (0..n)
        .map(|_| c.size("an element's node tag").map(|v| v.1))
        .collect()
}

/// Numbers of an MSH file being written: text tokens or binary values.
struct Out {
    buf: Vec<u8>,
    binary: bool,
}

impl Out {
    fn text(&mut self, s: &str) {
        self.buf.extend_from_slice(s.as_bytes());
    }
    fn int(&mut self, v: i32) {
        if self.binary {
            self.buf.extend_from_slice(&v.to_le_bytes());
        } else {
            self.text(&format!("{v} "));
        }
    }
    fn size(&mut self, v: u64) {
        if self.binary {
            self.buf.extend_from_slice(&v.to_le_bytes());
        } else {
            self.text(&format!("{v} "));
        }
    }
    fn float(&mut self, v: f64) {
        if self.binary {
            self.buf.extend_from_slice(&v.to_le_bytes());
        } else {
            // `{:?}` is the shortest text that reads back to the same bits
            self.text(&format!("{v:?} "));
        }
    }
    /// Ends a record: a newline in ASCII (in place of the last space).
    fn end(&mut self) {
        if !self.binary {
            if self.buf.last() == Some(&b' ') {
                self.buf.pop();
            }
            self.buf.push(b'\n');
        }
    }
    fn section(&mut self, name: &str) {
        self.text(&format!("${name}\n"));
    }
    fn end_section(&mut self, name: &str) {
        if self.binary {
            self.buf.push(b'\n');
        }
        self.text(&format!("$End{name}\n"));
    }
}

/// One entity being written: its dimension-specific tag, physical tags and elements.
struct Entity {
    phys: Vec<i32>,
    /// hexahedra (indices) for volumes, quads (node indices) for surfaces
    cells: Vec<Vec<u32>>,
}

/// Writes `raw` as an ASCII MSH 4.1 file, atomically.
pub fn write_msh(raw: &RawMesh, path: &Path) -> Result<(), MeshFileError> {
    write(raw, path, false)
}

/// Writes `raw` as a binary (little-endian) MSH 4.1 file, atomically.
pub fn write_msh_binary(raw: &RawMesh, path: &Path) -> Result<(), MeshFileError> {
    write(raw, path, true)
}

fn write(raw: &RawMesh, path: &Path, binary: bool) -> Result<(), MeshFileError> {
    check_writable(raw, path)?;
    let (volumes, surfaces) = plan_entities(raw);
    let mut o = Out {
        buf: Vec::new(),
        binary,
    };
    o.section("MeshFormat");
    o.text(if binary { "4.1 1 8\n" } else { "4.1 0 8\n" });
    if binary {
        o.buf.extend_from_slice(&1i32.to_le_bytes());
        o.buf.push(b'\n');
    }
    o.text("$EndMeshFormat\n");
    physical_names_out(&mut o, raw, &surfaces);
    entities_out(&mut o, raw, &volumes, &surfaces);
    nodes_out(&mut o, raw, !volumes.is_empty());
    elements_out(&mut o, raw, &volumes, &surfaces);
    crate::mesh::vtu::write_atomic(path, &o.buf).map_err(MeshFileError::io(path))
}

/// Volume entities (one per set of element groups) and surface entities
/// (one per node group with boundary faces, tagged by its node-group index + 1).
fn plan_entities(raw: &RawMesh) -> (Vec<Entity>, Vec<(i32, Entity)>) {
    let group_tag: HashMap<&str, i32> = raw
        .element_groups
        .keys()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i as i32 + 1))
        .collect();
    let mut by_sig: BTreeMap<Vec<&str>, Vec<Vec<u32>>> = BTreeMap::new();
    for (e, sig) in signatures(raw).into_iter().enumerate() {
        by_sig.entry(sig).or_default().push(vec![e as u32]);
    }
    let volumes = by_sig
        .into_iter()
        .map(|(sig, cells)| Entity {
            phys: sig.iter().map(|n| group_tag[n]).collect(),
            cells,
        })
        .collect();
    let mut surfaces = Vec::new();
    if !raw.node_groups.is_empty() {
        let faces = boundary_faces(raw);
        for (i, nodes) in raw.node_groups.values().enumerate() {
            let mut member = vec![false; raw.nodes.len()];
            nodes.iter().for_each(|&n| member[n as usize] = true);
            let cells: Vec<Vec<u32>> = faces
                .iter()
                .filter(|q| q.iter().all(|&n| member[n as usize]))
                .map(|q| q.to_vec())
                .collect();
            if !cells.is_empty() {
                surfaces.push((
                    i as i32 + 1,
                    Entity {
                        phys: vec![i as i32 + 1],
                        cells,
                    },
                ));
            }
        }
    }
    (volumes, surfaces)
}

/// Faces of the hexahedra used by one element only, outward, in element order.
fn boundary_faces(raw: &RawMesh) -> Vec<[u32; 4]> {
    let mut count: HashMap<[u32; 4], u32> = HashMap::new();
    let quad = |h: &[u32; 8], f: &[usize; 4]| -> [u32; 4] { std::array::from_fn(|k| h[f[k]]) };
    let key = |mut q: [u32; 4]| {
        q.sort_unstable();
        q
    };
    for h in &raw.hexes {
        for f in &HEX_FACES {
            *count.entry(key(quad(h, f))).or_default() += 1;
        }
    }
    raw.hexes
        .iter()
        .flat_map(|h| HEX_FACES.iter().map(move |f| quad(h, f)))
        .filter(|q| count[&key(*q)] == 1)
        .collect()
}

fn physical_names_out(o: &mut Out, raw: &RawMesh, surfaces: &[(i32, Entity)]) {
    let node_names: Vec<&String> = raw.node_groups.keys().collect();
    o.section("PhysicalNames");
    o.text(&format!("{}\n", raw.element_groups.len() + surfaces.len()));
    for (i, name) in raw.element_groups.keys().enumerate() {
        o.text(&format!("3 {} \"{}\"\n", i + 1, name.replace('"', "'")));
    }
    for (tag, _) in surfaces {
        let name = node_names[*tag as usize - 1];
        o.text(&format!("2 {tag} \"{}\"\n", name.replace('"', "'")));
    }
    o.text("$EndPhysicalNames\n");
}

/// Bounding box of a set of nodes.
fn bbox<'a>(raw: &RawMesh, nodes: impl Iterator<Item = &'a u32>) -> [f64; 6] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for &n in nodes {
        for (k, &v) in raw.nodes[n as usize].iter().enumerate() {
            b[k] = b[k].min(v);
            b[k + 3] = b[k + 3].max(v);
        }
    }
    b
}

fn entities_out(o: &mut Out, raw: &RawMesh, volumes: &[Entity], surfaces: &[(i32, Entity)]) {
    o.section("Entities");
    for n in [0, 0, surfaces.len(), volumes.len()] {
        o.size(n as u64);
    }
    o.end();
    let entity = |o: &mut Out, tag: i32, e: &Entity, nodes: Vec<u32>| {
        o.int(tag);
        bbox(raw, nodes.iter()).iter().for_each(|&v| o.float(v));
        o.size(e.phys.len() as u64);
        e.phys.iter().for_each(|&p| o.int(p));
        o.size(0);
        o.end();
    };
    for (tag, s) in surfaces {
        entity(o, *tag, s, s.cells.concat());
    }
    for (i, v) in volumes.iter().enumerate() {
        let nodes = v
            .cells
            .iter()
            .flat_map(|c| raw.hexes[c[0] as usize])
            .collect();
        entity(o, i as i32 + 1, v, nodes);
    }
    o.end_section("Entities");
}

fn nodes_out(o: &mut Out, raw: &RawMesh, has_volume: bool) {
    o.section("Nodes");
    let n = if has_volume { raw.nodes.len() } else { 0 };
    let ids = &raw.node_ids[..n];
    o.size(u64::from(n > 0));
    o.size(n as u64);
    o.size(ids.iter().copied().min().unwrap_or(0));
    o.size(ids.iter().copied().max().unwrap_or(0));
    o.end();
    if n > 0 {
        for v in [3, 1, 0] {
            o.int(v);
        }
        o.size(n as u64);
        o.end();
        for &id in ids {
            o.size(id);
            o.end();
        }
        for p in &raw.nodes {
            p.iter().for_each(|&v| o.float(v));
            o.end();
        }
    }
    o.end_section("Nodes");
}

fn elements_out(o: &mut Out, raw: &RawMesh, volumes: &[Entity], surfaces: &[(i32, Entity)]) {
    o.section("Elements");
    let n_quads: usize = surfaces.iter().map(|s| s.1.cells.len()).sum();
    let first_quad = raw.elem_ids.iter().copied().max().unwrap_or(0) + 1;
    let min_tag = raw.elem_ids.iter().copied().min().unwrap_or(first_quad);
    let total = raw.hexes.len() + n_quads;
    o.size((volumes.len() + surfaces.len()) as u64);
    o.size(total as u64);
    o.size(if total > 0 { min_tag } else { 0 });
    o.size(if total > 0 {
        first_quad + n_quads as u64 - 1
    } else {
        0
    });
    o.end();
    let mut next = first_quad;
    for (tag, s) in surfaces {
        for v in [2, *tag, 3] {
            o.int(v);
        }
        o.size(s.cells.len() as u64);
        o.end();
        for q in &s.cells {
            o.size(next);
            next += 1;
            q.iter().for_each(|&n| o.size(raw.node_ids[n as usize]));
            o.end();
        }
    }
    for (i, v) in volumes.iter().enumerate() {
        for x in [3, i as i32 + 1, 5] {
            o.int(x);
        }
        o.size(v.cells.len() as u64);
        o.end();
        for c in &v.cells {
            let e = c[0] as usize;
            o.size(raw.elem_ids[e]);
            raw.hexes[e]
                .iter()
                .for_each(|&n| o.size(raw.node_ids[n as usize]));
            o.end();
        }
    }
    o.end_section("Elements");
}
