//! Abaqus / CalculiX input files (`.inp`): [`read_inp`] into a [`RawMesh`],
//! [`write_inp`] from one.
//!
//! # Reading
//!
//! A flat input file (CalculiX style; Abaqus parts and instances are not
//! resolved). Keywords are case-insensitive, `**` starts a comment line, a
//! keyword line ending with a comma continues on the next line, and so does
//! an element's data line (elements with many nodes span lines).
//!
//! * `*NODE` (optionally `NSET=`): `number, x, y, z` (a missing coordinate
//!   is 0, as in Abaqus).
//! * `*ELEMENT, TYPE=C3D8` (and the other 8-node bricks: `C3D8R`, `C3D8I`,
//!   `C3D8H`, `DC3D8`, …; `ELSET=` puts them in a group). Other solid types
//!   (`C3D4`, `C3D10`, `C3D6`, `C3D20`, …) are an error naming each type in
//!   words with its count. Elements that are not solids (shells, membranes,
//!   beams, springs) are ignored but for their nodes: a set holding only such
//!   elements becomes a node group (Gmsh's `.inp` export writes a physical
//!   surface as a set of `CPS4`), and other sets drop them.
//! * `*ELSET, ELSET=name` and `*NSET, NSET=name`: numbers, names of sets
//!   defined before, or with `GENERATE` `first, last[, step]`. Set names are
//!   case-insensitive (as in Abaqus); a set keeps its first spelling.
//! * `*INCLUDE` is refused (merge the included file); every other keyword
//!   (materials, steps, …) is skipped with its data lines.
//!
//! # Writing
//!
//! `*NODE`, one `*ELEMENT, TYPE=C3D8` block in element order, an `*ELSET`
//! per element group and an `*NSET` per node group (16 numbers a line);
//! coordinates in Rust's shortest round-trip form, so a round trip is
//! bit-exact. Verified by the unit tests below (one per rule and error) and
//! the round trips of `tests/it/mesh_files.rs`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use super::file::{check_writable, quote, Builder, MeshFileError, Positions, Unsupported};
use super::RawMesh;

/// What an `*ELEMENT` block's `TYPE=` holds.
#[derive(Debug, Clone)]
enum ElemKind {
    /// An 8-node brick.
    Hex,
    /// A solid element of another shape: (singular, plural, nodes).
    Unsupported(String, String, usize),
    /// Not a solid: ignored.
    Ignored,
}

/// `C3D8R` → Hex, `C3D4` → 4-node tetrahedra, `S4R` → ignored.
fn element_kind(ty: &str) -> ElemKind {
    let t = ty.to_ascii_uppercase();
    let body = ["DCC3D", "DC3D", "C3D"]
        .iter()
        .find_map(|p| t.strip_prefix(p));
    let Some(body) = body else {
        return ElemKind::Ignored;
    };
    let digits: String = body.chars().take_while(char::is_ascii_digit).collect();
    let n: usize = digits.parse().unwrap_or(0);
    let (one, many) = match n {
        8 => return ElemKind::Hex,
        4 | 10 => ("tetrahedron", "tetrahedra"),
        6 | 15 => ("prism", "prisms"),
        5 | 13 => ("pyramid", "pyramids"),
        20 | 27 => ("hexahedron", "hexahedra"),
        _ => ("solid element", "solid elements"),
    };
    ElemKind::Unsupported(format!("{n}-node {one}"), format!("{n}-node {many}"), n)
}

/// The data lines a keyword governs.
enum Block {
    Node {
        nset: Option<String>,
    },
    Element {
        kind: ElemKind,
        ty: String,
        elset: Option<String>,
    },
    Set {
        nodes: bool,
        name: String,
        generate: bool,
    },
    Skip,
}

/// A keyword line: its name (upper case, spaces collapsed) and parameters
/// (upper-case keys; values as written, quotes removed).
struct Keyword {
    name: String,
    params: Vec<(String, Option<String>)>,
}

impl Keyword {
    fn parse(text: &str) -> Keyword {
        let mut parts = text.trim_start_matches('*').split(',');
        let name = parts
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_ascii_uppercase();
        let params = parts
            .filter(|p| !p.trim().is_empty())
            .map(|p| match p.split_once('=') {
                Some((k, v)) => (
                    k.trim().to_ascii_uppercase(),
                    Some(v.trim().trim_matches('"').to_string()),
                ),
                None => (p.trim().to_ascii_uppercase(), None),
            })
            .collect();
        Keyword { name, params }
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v.as_deref())
    }

    fn has(&self, key: &str) -> bool {
        self.params.iter().any(|(k, _)| k == key)
    }
}

/// The reader's state between lines.
struct Reader<'a> {
    b: Builder<'a>,
    unsupported: Unsupported,
    /// lower-case set name → the spelling it was first given (elsets, nsets)
    elset_names: HashMap<String, String>,
    nset_names: HashMap<String, String>,
    /// an element record continued on the next line
    pending: Option<Pending>,
}

/// Reads an Abaqus / CalculiX input file; `file` names it in messages and
/// becomes the mesh's `source`.
pub fn read_inp(data: &[u8], file: &str) -> Result<RawMesh, MeshFileError> {
    let text = String::from_utf8_lossy(data);
    let mut r = Reader {
        b: Builder::new(file, Positions::Lines),
        unsupported: Unsupported::default(),
        elset_names: HashMap::new(),
        nset_names: HashMap::new(),
        pending: None,
    };
    let mut block: Option<Block> = None;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    while let Some((ln, line)) = lines.next() {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with("**") {
            continue;
        }
        if trimmed.starts_with('*') {
            r.end_record()?;
            let mut kw_text = trimmed.to_string();
            while kw_text.ends_with(',') {
                match lines.next() {
                    Some((_, more)) => kw_text.push_str(more.trim()),
                    None => break,
                }
            }
            block = Some(r.keyword(&Keyword::parse(&kw_text), ln)?);
            continue;
        }
        match &block {
            None => {
                return Err(r.b.err(ln as u64, format!("not an Abaqus/CalculiX input file: expected a keyword line starting with `*`, found {}", quote(trimmed))));
            }
            Some(Block::Skip) => {}
            Some(Block::Node { nset }) => r.node_line(trimmed, ln, nset.clone())?,
            Some(Block::Element { kind, ty, elset }) => {
                let (kind, ty, elset) = (kind.clone(), ty.clone(), elset.clone());
                r.element_line(trimmed, ln, &kind, &ty, elset.as_deref())?;
            }
            Some(Block::Set {
                nodes,
                name,
                generate,
            }) => {
                let (nodes, name, generate) = (*nodes, name.clone(), *generate);
                r.set_line(trimmed, ln, nodes, &name, generate)?;
            }
        }
    }
    r.end_record()?;
    r.surface_sets_to_node_groups();
    if let Some(e) = r
        .unsupported
        .error(file, &Positions::Lines, "(C3D8, C3D8R, C3D8I) ")
    {
        return Err(e);
    }
    r.b.finish()
}

/// The fields of a data line, trimmed; a trailing comma gives no field.
fn fields(line: &str) -> Vec<String> {
    let mut f: Vec<String> = line.split(',').map(|s| s.trim().to_string()).collect();
    if f.last().is_some_and(String::is_empty) {
        f.pop();
    }
    f
}

/// An Abaqus number (`1.`, `1.5E3`, Fortran's `1.5D3`); an empty field is 0.
fn number(s: &str) -> Option<f64> {
    if s.is_empty() {
        return Some(0.0);
    }
    s.replace(['D', 'd'], "E").parse().ok()
}

/// Set members of `GENERATE` lines beyond this many are refused (a damaged
/// range must not take the machine's memory).
const MAX_GENERATED: u64 = 50_000_000;

impl Reader<'_> {
    /// Starts the block of keyword `kw` (line `ln`).
    fn keyword(&mut self, kw: &Keyword, ln: usize) -> Result<Block, MeshFileError> {
        let at = ln as u64;
        let set_param = |key: &str| -> Result<String, MeshFileError> {
            match kw.get(key) {
                Some(v) if !v.is_empty() => Ok(v.to_string()),
                _ => Err(self.b.err(at, format!("*{} needs {key}=name", kw.name))),
            }
        };
        Ok(match kw.name.as_str() {
            "INCLUDE" => {
                let input = kw.get("INPUT").unwrap_or("?");
                return Err(self.b.err(
                    at,
                    format!(
                        "*INCLUDE is not supported: merge {} into this file",
                        quote(input)
                    ),
                ));
            }
            "NODE" => {
                if let Some(sys) = kw.get("SYSTEM").filter(|s| !s.eq_ignore_ascii_case("R")) {
                    return Err(self.b.err(at, format!("*NODE, SYSTEM={sys}: only rectangular coordinates (SYSTEM=R) are supported")));
                }
                let nset = kw.get("NSET").map(|n| self.set_name(true, n));
                Block::Node { nset }
            }
            "ELEMENT" => {
                let Some(ty) = kw.get("TYPE") else {
                    return Err(self
                        .b
                        .err(at, "*ELEMENT needs TYPE= (C3D8, C3D8R or C3D8I)"));
                };
                let elset = kw.get("ELSET").map(|n| self.set_name(false, n));
                Block::Element {
                    kind: element_kind(ty),
                    ty: ty.to_ascii_uppercase(),
                    elset,
                }
            }
            "ELSET" | "NSET" => {
                let nodes = kw.name == "NSET";
                if nodes && kw.has("ELSET") {
                    return Err(self.b.err(
                        at,
                        "*NSET, ELSET=: nodes of an element set are not supported; list the nodes",
                    ));
                }
                let name = set_param(&kw.name)?;
                let name = self.set_name(nodes, &name);
                Block::Set {
                    nodes,
                    name,
                    generate: kw.has("GENERATE"),
                }
            }
            _ => Block::Skip,
        })
    }

    /// The set's name as first spelled, its group created.
    fn set_name(&mut self, nodes: bool, name: &str) -> String {
        let names = if nodes {
            &mut self.nset_names
        } else {
            &mut self.elset_names
        };
        let name = names
            .entry(name.to_lowercase())
            .or_insert_with(|| name.to_string())
            .clone();
        let groups = if nodes {
            &mut self.b.node_groups
        } else {
            &mut self.b.element_groups
        };
        groups.entry(name.clone()).or_default();
        name
    }

    fn node_line(
        &mut self,
        line: &str,
        ln: usize,
        nset: Option<String>,
    ) -> Result<(), MeshFileError> {
        let f = fields(line);
        let at = ln as u64;
        let id = f.first().and_then(|s| s.parse::<u64>().ok());
        let coords: Vec<Option<f64>> = (1..4)
            .map(|k| number(f.get(k).map_or("", |s| s.as_str())))
            .collect();
        let (Some(id), [Some(x), Some(y), Some(z)]) = (id, coords.as_slice()) else {
            return Err(self.b.err(
                at,
                format!(
                    "expected a node line `number, x, y, z`, found {}",
                    quote(line)
                ),
            ));
        };
        self.b.node(id, [*x, *y, *z], at)?;
        if let Some(set) = nset {
            self.b
                .node_groups
                .entry(set)
                .or_default()
                .members
                .push((id, at));
        }
        Ok(())
    }

    fn element_line(
        &mut self,
        line: &str,
        ln: usize,
        kind: &ElemKind,
        ty: &str,
        elset: Option<&str>,
    ) -> Result<(), MeshFileError> {
        let mut rec = self.pending.take().unwrap_or_else(|| Pending {
            first: ln,
            fields: Vec::new(),
            kind: kind.clone(),
            ty: ty.to_string(),
            elset: elset.map(str::to_string),
        });
        rec.fields.extend(fields(line));
        let complete = match rec.want() {
            Some(w) => rec.fields.len() >= w || !line.ends_with(','),
            None => !line.ends_with(','),
        };
        if complete {
            self.element_record(rec)
        } else {
            self.pending = Some(rec);
            Ok(())
        }
    }

    /// An element record cut short by a keyword or the end of the file.
    fn end_record(&mut self) -> Result<(), MeshFileError> {
        match self.pending.take() {
            Some(rec) => self.element_record(rec),
            None => Ok(()),
        }
    }

    fn element_record(&mut self, rec: Pending) -> Result<(), MeshFileError> {
        let at = rec.first as u64;
        let Some(id) = rec.fields.first().and_then(|s| s.parse::<u64>().ok()) else {
            let found = rec.fields.join(", ");
            return Err(self.b.err(
                at,
                format!(
                    "expected an element line `number, node, node, …`, found {}",
                    quote(&found)
                ),
            ));
        };
        let nodes: Vec<u64> = rec.fields[1..]
            .iter()
            .map(|s| s.parse::<u64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                self.b.err(
                    at,
                    format!(
                        "element {id}: expected node numbers, found {}",
                        quote(&rec.fields[1..].join(", "))
                    ),
                )
            })?;
        if let Some(w) = rec.want() {
            if nodes.len() != w - 1 {
                return Err(self.b.err(
                    at,
                    format!(
                        "element {id} ({}): expected {} nodes, found {}",
                        rec.ty,
                        w - 1,
                        nodes.len()
                    ),
                ));
            }
        }
        match &rec.kind {
            ElemKind::Hex => self.b.hex(id, std::array::from_fn(|k| nodes[k]), at)?,
            ElemKind::Unsupported(one, many, _) => {
                self.unsupported.add(one, many, &rec.ty, 1, at);
                return Ok(());
            }
            ElemKind::Ignored => drop(self.b.ignored_elements.insert(id, nodes)),
        }
        if let Some(set) = rec.elset {
            let group = self.b.element_groups.entry(set).or_default();
            group.members.push((id, at));
        }
        Ok(())
    }

    /// An element set of surface (or other non-solid) elements only is a
    /// node group of their nodes, as a Gmsh physical surface is (Gmsh's own
    /// `.inp` export writes physical surfaces so, as `CPS4` sets).
    fn surface_sets_to_node_groups(&mut self) {
        let names: Vec<String> = self
            .b
            .element_groups
            .iter()
            .filter(|(_, g)| {
                !g.members.is_empty()
                    && g.members.iter().all(|(id, _)| !self.b.is_hex(*id))
                    && g.members
                        .iter()
                        .any(|(id, _)| self.b.ignored_elements.contains_key(id))
            })
            .map(|(n, _)| n.clone())
            .collect();
        for name in names {
            let Some(g) = self.b.element_groups.remove(&name) else {
                continue;
            };
            let mut nodes = Vec::new();
            for (id, at) in g.members {
                if let Some(ns) = self.b.ignored_elements.get(&id) {
                    nodes.extend(ns.iter().map(|&n| (n, at)));
                }
            }
            self.b
                .node_groups
                .entry(name)
                .or_default()
                .members
                .extend(nodes);
        }
    }

    /// A data line of `*ELSET` / `*NSET`: numbers, set names, or a `GENERATE` range.
    fn set_line(
        &mut self,
        line: &str,
        ln: usize,
        nodes: bool,
        name: &str,
        generate: bool,
    ) -> Result<(), MeshFileError> {
        let at = ln as u64;
        let f = fields(line);
        let mut members: Vec<(u64, u64)> = Vec::new();
        if generate {
            let v: Vec<Option<u64>> = f.iter().map(|s| s.parse().ok()).collect();
            let (first, last, step) = match v.as_slice() {
                [Some(a), Some(b)] => (*a, *b, 1),
                [Some(a), Some(b), Some(c)] => (*a, *b, *c),
                _ => {
                    return Err(self.b.err(
                        at,
                        format!(
                            "expected `first, last[, step]` (GENERATE), found {}",
                            quote(line)
                        ),
                    ))
                }
            };
            if step == 0 || last < first || (last - first) / step >= MAX_GENERATED {
                return Err(self.b.err(at, format!("GENERATE range {first}, {last}, {step}: expected first <= last, a step >= 1 and at most {MAX_GENERATED} members")));
            }
            members.extend((first..=last).step_by(step as usize).map(|i| (i, at)));
        } else {
            for s in f.iter().filter(|s| !s.is_empty()) {
                if let Ok(i) = s.parse::<u64>() {
                    members.push((i, at));
                    continue;
                }
                let names = if nodes {
                    &self.nset_names
                } else {
                    &self.elset_names
                };
                let groups = if nodes {
                    &self.b.node_groups
                } else {
                    &self.b.element_groups
                };
                let Some(g) = names
                    .get(&s.trim_matches('"').to_lowercase())
                    .and_then(|n| groups.get(n))
                else {
                    let what = if nodes {
                        "node number or node set"
                    } else {
                        "element number or element set"
                    };
                    return Err(self.b.err(
                        at,
                        format!("expected an {what} defined above, found {}", quote(s)),
                    ));
                };
                members.extend(g.members.iter().copied());
            }
        }
        let groups = if nodes {
            &mut self.b.node_groups
        } else {
            &mut self.b.element_groups
        };
        groups
            .entry(name.to_string())
            .or_default()
            .members
            .extend(members);
        Ok(())
    }
}

/// An element record being read (it may span lines).
struct Pending {
    first: usize,
    fields: Vec<String>,
    kind: ElemKind,
    ty: String,
    elset: Option<String>,
}

impl Pending {
    /// Fields of a complete record (number + nodes), when the type says.
    fn want(&self) -> Option<usize> {
        match &self.kind {
            ElemKind::Hex => Some(9),
            ElemKind::Unsupported(_, _, n) if *n > 0 => Some(n + 1),
            _ => None,
        }
    }
}

/// A set name as written: quoted when it is not a plain word.
fn set_name_out(name: &str) -> String {
    if name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
        && !name.is_empty()
    {
        name.to_string()
    } else {
        format!("\"{}\"", name.replace('"', "'"))
    }
}

/// Numbers 16 to a line (Abaqus's limit for set data lines).
fn number_lines(out: &mut String, ids: impl Iterator<Item = u64>) {
    let ids: Vec<u64> = ids.collect();
    for chunk in ids.chunks(16) {
        let line: Vec<String> = chunk.iter().map(u64::to_string).collect();
        let _ = writeln!(out, "{}", line.join(", "));
    }
}

/// Writes `raw` as an Abaqus / CalculiX input file, atomically.
pub fn write_inp(raw: &RawMesh, path: &Path) -> Result<(), MeshFileError> {
    check_writable(raw, path)?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "** written by groutready from {}",
        raw.source.replace(['\n', '\r'], " ")
    );
    out.push_str("*NODE\n");
    for (id, p) in raw.node_ids.iter().zip(&raw.nodes) {
        let _ = writeln!(out, "{id}, {:?}, {:?}, {:?}", p[0], p[1], p[2]);
    }
    if !raw.hexes.is_empty() {
        out.push_str("*ELEMENT, TYPE=C3D8\n");
        for (id, h) in raw.elem_ids.iter().zip(&raw.hexes) {
            let nodes: Vec<String> = h
                .iter()
                .map(|&n| raw.node_ids[n as usize].to_string())
                .collect();
            let _ = writeln!(out, "{id}, {}", nodes.join(", "));
        }
    }
    for (name, members) in &raw.element_groups {
        let _ = writeln!(out, "*ELSET, ELSET={}", set_name_out(name));
        number_lines(&mut out, members.iter().map(|&e| raw.elem_ids[e as usize]));
    }
    for (name, members) in &raw.node_groups {
        let _ = writeln!(out, "*NSET, NSET={}", set_name_out(name));
        number_lines(&mut out, members.iter().map(|&n| raw.node_ids[n as usize]));
    }
    crate::mesh::vtu::write_atomic(path, out.as_bytes()).map_err(MeshFileError::io(path))
}
