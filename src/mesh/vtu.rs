//! VTK XML output for ParaView: `.vtu` unstructured grids and `.pvd` time series.
//!
//! Files are VTK XML version 1.0, little endian, `header_type="UInt64"`,
//! inline base64 `binary` data arrays (uncompressed: one base64 block holding
//! the 8-byte byte count followed by the data). Points are `Float64` xyz,
//! connectivity and offsets `Int64`, cell types `UInt8` (12 = hexahedron).
//! Every cell also carries two `Int32` arrays, `block` and `lift` (0 for rock),
//! unless the caller passes cell fields of those names.
//! Files are written atomically: a temporary file in the same folder, then a
//! rename.

use std::fmt::Write as _;
use std::fs;
use std::io::{self, Write};
use std::path::Path;

use super::{Mesh, Part};

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 (RFC 4648, with padding).
pub fn base64_encode(data: &[u8]) -> String {
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        out.push(B64[(n >> 18) as usize & 63] as char);
        out.push(B64[(n >> 12) as usize & 63] as char);
        out.push(if chunk.len() > 1 {
            B64[(n >> 6) as usize & 63] as char
        } else {
            '='
        });
        out.push(if chunk.len() > 2 {
            B64[n as usize & 63] as char
        } else {
            '='
        });
    }
    out
}

fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            _ => o.push(c),
        }
    }
    o
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Write `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| invalid(format!("{} is not a file path", path.display())))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// One `<DataArray>` element with base64 binary content.
fn data_array(out: &mut String, ty: &str, name: Option<&str>, comps: usize, bytes: &[u8]) {
    let mut blob = Vec::with_capacity(8 + bytes.len());
    blob.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    blob.extend_from_slice(bytes);
    let _ = write!(out, "        <DataArray type=\"{ty}\"");
    if let Some(n) = name {
        let _ = write!(out, " Name=\"{}\"", xml_escape(n));
    }
    if comps != 1 {
        // scalars omit it (default 1), so readers such as meshio give 1-D arrays
        let _ = write!(out, " NumberOfComponents=\"{comps}\"");
    }
    let _ = writeln!(
        out,
        " format=\"binary\">\n          {}\n        </DataArray>",
        base64_encode(&blob)
    );
}

fn f64_bytes<I: IntoIterator<Item = f64>>(it: I) -> Vec<u8> {
    it.into_iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Components of a field of `len` values over `n` entities: 1 (scalar) or 3 (vector).
fn components(name: &str, len: usize, n: usize, what: &str) -> io::Result<usize> {
    if len == n {
        Ok(1)
    } else if len == 3 * n && n > 0 {
        Ok(3)
    } else {
        Err(invalid(format!(
            "field {name:?} has {len} values for {n} {what} (expected {n} or {})",
            3 * n
        )))
    }
}

/// Write `mesh` as a `.vtu` file.
///
/// * `point_fields`: per node, `nodes.len()` values (scalar) or `3·nodes.len()`
///   (xyz vectors, node-major).
/// * `cell_fields`: scalar or 3-vector per cell. Without `cells`: per
///   element. With a subset `cells`: either over all elements
///   (`elements.len()` or `3·elements.len()` values, gathered onto the
///   subset; this reading wins when both fit) or per written cell, in the
///   order of `cells`.
/// * `cells`: the elements to write (e.g. only live ones); `None` = all.
///   All nodes are always written (unused points are valid VTK).
///
/// Field names must be unique within points and within cells. The cell arrays
/// `block` and `lift` (`Int32`, 0 for rock) are added unless `cell_fields`
/// has fields of those names.
pub fn write_vtu(
    path: impl AsRef<Path>,
    mesh: &Mesh,
    point_fields: &[(&str, &[f64])],
    cell_fields: &[(&str, &[f64])],
    cells: Option<&[u32]>,
) -> io::Result<()> {
    let ne = mesh.elements.len();
    let all: Vec<u32>;
    let cells: &[u32] = match cells {
        Some(c) => c,
        None => {
            all = (0..ne as u32).collect();
            &all
        }
    };
    if let Some(&bad) = cells.iter().find(|&&e| e as usize >= ne) {
        return Err(invalid(format!("cell {bad} out of range ({ne} elements)")));
    }
    for group in [point_fields, cell_fields] {
        for (i, (name, _)) in group.iter().enumerate() {
            if group[..i].iter().any(|(n, _)| n == name) {
                return Err(invalid(format!("duplicate field name {name:?}")));
            }
        }
    }

    let n_nodes = mesh.nodes.len();
    let nc = cells.len();
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    out.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n_nodes}\" NumberOfCells=\"{nc}\">"
    );
    out.push_str("      <PointData>\n");
    for (name, vals) in point_fields {
        let comps = components(name, vals.len(), n_nodes, "points")?;
        data_array(
            &mut out,
            "Float64",
            Some(name),
            comps,
            &f64_bytes(vals.iter().copied()),
        );
    }
    out.push_str("      </PointData>\n");
    cell_data(&mut out, mesh, cell_fields, cells)?;
    geometry(&mut out, mesh, cells);
    out.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path.as_ref(), out.as_bytes())
}

/// The `<CellData>` of the written `cells`: `block` and `lift` unless the
/// caller has fields of those names, then the caller's fields, gathered onto
/// the subset when they are given over all elements.
fn cell_data(
    out: &mut String,
    mesh: &Mesh,
    cell_fields: &[(&str, &[f64])],
    cells: &[u32],
) -> io::Result<()> {
    let ne = mesh.elements.len();
    let nc = cells.len();
    let subset = nc != ne || cells.iter().enumerate().any(|(i, &e)| i as u32 != e);
    let caller_has = |n: &str| cell_fields.iter().any(|(name, _)| *name == n);
    out.push_str("      <CellData>\n");
    let (blocks, lifts): (Vec<i32>, Vec<i32>) = cells
        .iter()
        .map(|&e| match mesh.parts[e as usize] {
            Part::Concrete { block, lift } => (block as i32, lift as i32),
            Part::Rock => (0, 0),
        })
        .unzip();
    for (name, vals) in [("block", &blocks), ("lift", &lifts)] {
        if !caller_has(name) {
            let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
            data_array(out, "Int32", Some(name), 1, &bytes);
        }
    }
    for (name, vals) in cell_fields {
        let per_element = subset && (vals.len() == ne || vals.len() == 3 * ne);
        let (comps, gathered): (usize, Vec<f64>) = if per_element {
            // a field over all elements, gathered onto the written subset
            let c = vals.len() / ne;
            let g = cells
                .iter()
                .flat_map(|&el| (0..c).map(move |k| vals[el as usize * c + k]))
                .collect();
            (c, g)
        } else {
            (components(name, vals.len(), nc, "cells")?, vals.to_vec())
        };
        data_array(out, "Float64", Some(name), comps, &f64_bytes(gathered));
    }
    out.push_str("      </CellData>\n");
    Ok(())
}

/// `<Points>` (every node) and `<Cells>` (the written hexahedra).
fn geometry(out: &mut String, mesh: &Mesh, cells: &[u32]) {
    out.push_str("      <Points>\n");
    data_array(
        out,
        "Float64",
        None,
        3,
        &f64_bytes(mesh.nodes.iter().flat_map(|p| p.iter().copied())),
    );
    out.push_str("      </Points>\n");

    out.push_str("      <Cells>\n");
    let conn: Vec<u8> = cells
        .iter()
        .flat_map(|&e| mesh.elements[e as usize].iter().map(|&n| n as i64))
        .flat_map(|v| v.to_le_bytes())
        .collect();
    data_array(out, "Int64", Some("connectivity"), 1, &conn);
    let offsets: Vec<u8> = (1..=cells.len() as i64)
        .flat_map(|i| (8 * i).to_le_bytes())
        .collect();
    data_array(out, "Int64", Some("offsets"), 1, &offsets);
    data_array(out, "UInt8", Some("types"), 1, &vec![12u8; cells.len()]);
    out.push_str("      </Cells>\n");
}

/// Write a ParaView collection (`.pvd`) listing `(time [day], file)` entries;
/// file names are written as given (relative to the `.pvd` file's folder).
pub fn write_pvd(path: impl AsRef<Path>, entries: &[(f64, String)]) -> io::Result<()> {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <Collection>\n");
    for (t, file) in entries {
        if !t.is_finite() {
            return Err(invalid(format!("time {t} of {file:?} is not finite")));
        }
        let _ = writeln!(
            out,
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{}\"/>",
            xml_escape(file)
        );
    }
    out.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path.as_ref(), out.as_bytes())
}
