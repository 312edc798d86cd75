//! Reading and writing mesh files by their extension, the error every mesh
//! file reader returns, and the checks both readers share.
//!
//! [`read_file`] reads `.msh` (Gmsh MSH 4.1, ASCII or binary, [`super::msh`])
//! and `.inp` (Abaqus / CalculiX, [`super::inp`]) into a [`RawMesh`].
//! Both readers collect what the file says into a [`Builder`], whose
//! [`Builder::finish`] applies the rules the formats share: node and element
//! numbers unique, every element's nodes defined, every node used by an
//! element, coordinates finite, groups resolved to indices. Nodes and
//! hexahedra come out ordered by their numbers in the file, so a file written
//! from a [`RawMesh`] numbered in order reads back equal to it.
//!
//! Verified by the unit tests of the two formats (one error per rule, the
//! messages' file and line) and by `tests/it/mesh_files.rs` (round trips of
//! the bundled scenes' meshes, truncated and byte-flipped files never panic).

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::Path;

use thiserror::Error;

use super::RawMesh;

/// Where in a mesh file something is: a 1-based line of a text file, or a
/// byte offset of a binary one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    Line(usize),
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "{l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// Everything that can go wrong reading or writing a mesh file.
///
/// Display forms: `dam.msh:12: expected a node number, found "x1"`,
/// `dam.msh:byte 4096: …` (binary MSH), `dam.inp: no 8-node hexahedra …`.
#[derive(Debug, Error)]
pub enum MeshFileError {
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// Something wrong at one place of the file.
    #[error("{file}:{at}: {message}")]
    At {
        file: String,
        at: Location,
        message: String,
    },
    /// Something wrong with the file as a whole (no place to point at).
    #[error("{file}: {message}")]
    File { file: String, message: String },
}

impl MeshFileError {
    pub(crate) fn file(file: &str, message: impl Into<String>) -> MeshFileError {
        MeshFileError::File {
            file: file.to_string(),
            message: message.into(),
        }
    }

    pub(crate) fn io(file: &Path) -> impl FnOnce(std::io::Error) -> MeshFileError + '_ {
        move |source| MeshFileError::Io {
            file: file.display().to_string(),
            source,
        }
    }
}

/// `text` quoted for a message, cut to at most ~120 characters.
pub(crate) fn quote(text: &str) -> String {
    const MAX: usize = 120;
    let mut s: String = text.chars().take(MAX).collect();
    if text.chars().nth(MAX).is_some() {
        s.push('…');
    }
    format!("{s:?}")
}

/// `1204` as `1,204` (counts in messages).
pub(crate) fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// How a reader's positions (`u64`) become [`Location`]s.
pub(crate) enum Positions<'a> {
    /// Positions are 1-based line numbers.
    Lines,
    /// Positions are byte offsets into this text; shown as its line numbers.
    TextOffsets(&'a [u8]),
    /// Positions are byte offsets into a binary file.
    Bytes,
}

impl Positions<'_> {
    pub(crate) fn at(&self, pos: u64) -> Location {
        match self {
            Positions::Lines => Location::Line(pos as usize),
            Positions::TextOffsets(text) => {
                let end = (pos as usize).min(text.len());
                Location::Line(1 + text[..end].iter().filter(|&&b| b == b'\n').count())
            }
            Positions::Bytes => Location::Byte(pos),
        }
    }
}

/// Volume elements other than 8-node hexahedra, counted by kind for one
/// error naming them all.
#[derive(Debug, Default)]
pub(crate) struct Unsupported {
    /// (kind in words singular, plural, the file's name of the type) → (count, first position).
    kinds: BTreeMap<(String, String, String), (usize, u64)>,
}

impl Unsupported {
    pub(crate) fn add(&mut self, singular: &str, plural: &str, name: &str, n: usize, pos: u64) {
        let e = self
            .kinds
            .entry((singular.into(), plural.into(), name.into()))
            .or_insert((0, pos));
        e.0 += n;
        e.1 = e.1.min(pos);
    }

    /// `only 8-node hexahedra are supported; found 1,204 4-node tetrahedra
    /// (type 4) and 12 6-node prisms (type 6)`, at the first of them.
    pub(crate) fn error(
        &self,
        file: &str,
        positions: &Positions,
        what: &str,
    ) -> Option<MeshFileError> {
        let first = self.kinds.values().map(|v| v.1).min()?;
        let mut parts: Vec<String> = self
            .kinds
            .iter()
            .map(|((one, many, name), (n, _))| {
                let word = if *n == 1 { one } else { many };
                format!("{} {word} ({name})", thousands(*n))
            })
            .collect();
        let last = parts.pop().unwrap_or_default();
        let list = if parts.is_empty() {
            last
        } else {
            format!("{} and {last}", parts.join(", "))
        };
        Some(MeshFileError::At {
            file: file.to_string(),
            at: positions.at(first),
            message: format!("only 8-node hexahedra {what}are supported; found {list}"),
        })
    }
}

/// A group as a file states it: member numbers (node or element numbers of
/// the file) with where each was listed.
#[derive(Debug, Default)]
pub(crate) struct RawGroup {
    pub members: Vec<(u64, u64)>,
}

/// What a reader found, by the file's numbers; [`Builder::finish`] checks
/// it and makes the [`RawMesh`].
pub(crate) struct Builder<'a> {
    pub file: String,
    pub positions: Positions<'a>,
    /// (number, xyz, position)
    nodes: Vec<(u64, [f64; 3], u64)>,
    node_at: HashMap<u64, u64>,
    /// (number, node numbers, position)
    hexes: Vec<(u64, [u64; 8], u64)>,
    hex_at: HashMap<u64, u64>,
    pub element_groups: BTreeMap<String, RawGroup>,
    pub node_groups: BTreeMap<String, RawGroup>,
    /// Elements that are not hexahedra (number → node numbers), ignored
    /// but for their nodes: a reader may turn a group of them into a node
    /// group; an element group listing them drops them.
    pub ignored_elements: HashMap<u64, Vec<u64>>,
}

impl<'a> Builder<'a> {
    pub(crate) fn new(file: &str, positions: Positions<'a>) -> Builder<'a> {
        Builder {
            file: file.to_string(),
            positions,
            nodes: Vec::new(),
            node_at: HashMap::new(),
            hexes: Vec::new(),
            hex_at: HashMap::new(),
            element_groups: BTreeMap::new(),
            node_groups: BTreeMap::new(),
            ignored_elements: Default::default(),
        }
    }

    /// An error at position `pos`.
    pub(crate) fn err(&self, pos: u64, message: impl Into<String>) -> MeshFileError {
        MeshFileError::At {
            file: self.file.clone(),
            at: self.positions.at(pos),
            message: message.into(),
        }
    }

    fn where_(&self, pos: u64) -> String {
        match self.positions.at(pos) {
            Location::Line(l) => format!("line {l}"),
            Location::Byte(b) => format!("byte {b}"),
        }
    }

    /// Node `id` at `xyz`, stated at `pos`.
    pub(crate) fn node(&mut self, id: u64, xyz: [f64; 3], pos: u64) -> Result<(), MeshFileError> {
        if let Some(&first) = self.node_at.get(&id) {
            let msg = format!(
                "node {id} is defined twice: {} and {}",
                self.where_(first),
                self.where_(pos)
            );
            return Err(self.err(pos, msg));
        }
        if let Some(c) = xyz.iter().position(|v| !v.is_finite()) {
            let axis = ["x", "y", "z"][c];
            return Err(self.err(
                pos,
                format!(
                    "node {id}: coordinate {axis} = {} is not a finite number",
                    xyz[c]
                ),
            ));
        }
        self.node_at.insert(id, pos);
        self.nodes.push((id, xyz, pos));
        Ok(())
    }

    /// Hexahedron `id` on node numbers `corners` (VTK order), stated at `pos`.
    pub(crate) fn hex(
        &mut self,
        id: u64,
        corners: [u64; 8],
        pos: u64,
    ) -> Result<(), MeshFileError> {
        if let Some(&first) = self.hex_at.get(&id) {
            let msg = format!(
                "element {id} is defined twice: {} and {}",
                self.where_(first),
                self.where_(pos)
            );
            return Err(self.err(pos, msg));
        }
        self.hex_at.insert(id, pos);
        self.hexes.push((id, corners, pos));
        Ok(())
    }

    pub(crate) fn is_hex(&self, id: u64) -> bool {
        self.hex_at.contains_key(&id)
    }

    /// The checked [`RawMesh`]: nodes and hexahedra sorted by number.
    pub(crate) fn finish(mut self) -> Result<RawMesh, MeshFileError> {
        if self.hexes.is_empty() {
            return Err(MeshFileError::file(
                &self.file,
                "no 8-node hexahedra in the file",
            ));
        }
        self.nodes.sort_by_key(|n| n.0);
        self.hexes.sort_by_key(|h| h.0);
        let node_index: HashMap<u64, u32> = self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| (n.0, i as u32))
            .collect();
        let elem_index: HashMap<u64, u32> = self
            .hexes
            .iter()
            .enumerate()
            .map(|(i, h)| (h.0, i as u32))
            .collect();
        let mut used = vec![false; self.nodes.len()];
        let mut hexes = Vec::with_capacity(self.hexes.len());
        for (id, corners, pos) in &self.hexes {
            let mut h = [0u32; 8];
            for (k, c) in corners.iter().enumerate() {
                let Some(&i) = node_index.get(c) else {
                    return Err(self.err(
                        *pos,
                        format!("element {id} uses node {c}, which is not defined"),
                    ));
                };
                used[i as usize] = true;
                h[k] = i;
            }
            hexes.push(h);
        }
        if let Some(i) = used.iter().position(|u| !u) {
            let (id, [x, y, z], pos) = self.nodes[i];
            return Err(self.err(
                pos,
                format!("node {id} at ({x}, {y}, {z}) is used by no element"),
            ));
        }
        let element_groups = self.resolve(&self.element_groups, &elem_index, "element")?;
        let node_groups = self.resolve(&self.node_groups, &node_index, "node")?;
        Ok(RawMesh {
            source: self.file.clone(),
            nodes: self.nodes.iter().map(|n| n.1).collect(),
            node_ids: self.nodes.iter().map(|n| n.0).collect(),
            hexes,
            elem_ids: self.hexes.iter().map(|h| h.0).collect(),
            element_groups,
            node_groups,
        })
    }

    /// Groups by indices, sorted, without repeats; a member the file never
    /// defined is an error (ignored non-hexahedral elements are dropped).
    fn resolve(
        &self,
        groups: &BTreeMap<String, RawGroup>,
        index: &HashMap<u64, u32>,
        what: &str,
    ) -> Result<BTreeMap<String, Vec<u32>>, MeshFileError> {
        let mut out = BTreeMap::new();
        for (name, g) in groups {
            let mut v = Vec::with_capacity(g.members.len());
            for &(id, pos) in &g.members {
                match index.get(&id) {
                    Some(&i) => v.push(i),
                    None if what == "element" && self.ignored_elements.contains_key(&id) => {}
                    None => {
                        return Err(self.err(
                            pos,
                            format!("group {name:?} lists {what} {id}, which is not defined"),
                        ));
                    }
                }
            }
            v.sort_unstable();
            v.dedup();
            out.insert(name.clone(), v);
        }
        Ok(out)
    }
}

/// The formats [`read_file`] and [`write_file`] know, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Gmsh MSH 4.1 (`.msh`).
    Msh,
    /// Abaqus / CalculiX input (`.inp`).
    Inp,
}

impl MeshFormat {
    /// The format of `path` by its extension (case-insensitive).
    pub fn of(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "msh" => Some(MeshFormat::Msh),
            "inp" => Some(MeshFormat::Inp),
            _ => None,
        }
    }
}

fn unknown_extension(path: &Path) -> MeshFileError {
    MeshFileError::file(
        &path.display().to_string(),
        "unknown mesh file extension: expected .msh (Gmsh MSH 4.1) or .inp (Abaqus/CalculiX)",
    )
}

/// Reads a `.msh` or `.inp` mesh file (by its extension) into a [`RawMesh`]
/// whose `source` is `path` as given.
pub fn read_file(path: &Path) -> Result<RawMesh, MeshFileError> {
    let format = MeshFormat::of(path).ok_or_else(|| unknown_extension(path))?;
    let bytes = std::fs::read(path).map_err(MeshFileError::io(path))?;
    let name = path.display().to_string();
    match format {
        MeshFormat::Msh => super::msh::read_msh(&bytes, &name),
        MeshFormat::Inp => super::inp::read_inp(&bytes, &name),
    }
}

/// Writes `raw` as `.msh` (MSH 4.1 ASCII) or `.inp` by the extension of `path`.
pub fn write_file(raw: &RawMesh, path: &Path) -> Result<(), MeshFileError> {
    match MeshFormat::of(path).ok_or_else(|| unknown_extension(path))? {
        MeshFormat::Msh => super::msh::write_msh(raw, path),
        MeshFormat::Inp => super::inp::write_inp(raw, path),
    }
}

/// Element-group signature of each hexahedron: the sorted names of the
/// groups holding it (writers make one volume per signature).
pub(crate) fn signatures(raw: &RawMesh) -> Vec<Vec<&str>> {
    let mut sig: Vec<Vec<&str>> = vec![Vec::new(); raw.hexes.len()];
    for (name, members) in &raw.element_groups {
        for &e in members {
            if let Some(s) = sig.get_mut(e as usize) {
                s.push(name.as_str());
            }
        }
    }
    sig
}

/// Refuses to write a mesh a reader would refuse: non-finite coordinates,
/// out-of-range indices, mismatched id lists.
pub(crate) fn check_writable(raw: &RawMesh, path: &Path) -> Result<(), MeshFileError> {
    let file = path.display().to_string();
    let bad = |m: String| Err(MeshFileError::file(&file, m));
    if raw.node_ids.len() != raw.nodes.len() || raw.elem_ids.len() != raw.hexes.len() {
        return bad("node_ids / elem_ids do not match nodes / hexes".into());
    }
    if let Some(i) = raw
        .nodes
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        return bad(format!(
            "node {} has a non-finite coordinate {:?}",
            raw.node_ids[i], raw.nodes[i]
        ));
    }
    let n = raw.nodes.len();
    if let Some(e) = raw
        .hexes
        .iter()
        .position(|h| h.iter().any(|&c| c as usize >= n))
    {
        return bad(format!(
            "element {} uses a node index out of range ({n} nodes)",
            raw.elem_ids[e]
        ));
    }
    for (name, g) in &raw.element_groups {
        if g.iter().any(|&e| e as usize >= raw.hexes.len()) {
            return bad(format!(
                "element group {name:?} holds an index out of range"
            ));
        }
    }
    for (name, g) in &raw.node_groups {
        if g.iter().any(|&i| i as usize >= n) {
            return bad(format!("node group {name:?} holds an index out of range"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_and_quote() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1204), "1,204");
        assert_eq!(thousands(1234567), "1,234,567");
        let long = "x".repeat(300);
        assert_eq!(quote(&long).chars().count(), 120 + 3);
        assert_eq!(quote("ab"), "\"ab\"");
    }

    #[test]
    fn text_offsets_are_lines() {
        let text = b"a\nbb\nccc\n";
        let p = Positions::TextOffsets(text);
        assert_eq!(p.at(0), Location::Line(1));
        assert_eq!(p.at(2), Location::Line(2));
        assert_eq!(p.at(5), Location::Line(3));
        assert_eq!(Positions::Bytes.at(7).to_string(), "byte 7");
    }
}
