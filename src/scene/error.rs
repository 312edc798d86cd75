//! Errors of scene loading: I/O, TOML syntax/schema (with file:line:column),
//! and validation (naming the dotted key).

use std::fmt;
use std::ops::Range;
use std::path::PathBuf;

use serde::Deserialize;
use thiserror::Error;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::mesh::arch_table::{ArchTableError, ArchTableGeometry};
use crate::mesh::geometry::{ArchGeometry, BlocksGeometry};

/// Everything that can go wrong while loading a scene file.
///
/// Display forms:
/// - `models/x.toml: cannot read the scene file: No such file or directory (os error 2)`
/// - `models/x.toml:12:1: unknown key `conductivty` in [concrete], expected one of ...`
/// - `models/x.toml: concrete.conductivity_w_mk must be > 0, got -2.1`
#[derive(Debug, Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// TOML syntax error or a value that does not fit the schema
    /// (unknown key, wrong type, missing table, misspelled effect, bad date).
    #[error("{}", fmt_parse(origin, *position, message))]
    Parse {
        /// File name (or the origin name given to [`super::Scene::from_toml_str`]).
        origin: String,
        /// 1-based (line, column) of the offending text, when it has one.
        position: Option<(usize, usize)>,
        message: String,
    },
    /// A value that parsed but is out of range or inconsistent with another.
    #[error("{}", fmt_invalid(origin.as_deref(), *position, message))]
    Invalid {
        /// File name; `None` when [`super::Scene::validate`] is called on a scene
        /// that did not come from a file.
        origin: Option<String>,
        /// 1-based (line, column) of the key's value in the file (of the
        /// nearest table that exists when the key itself is missing).
        position: Option<(usize, usize)>,
        /// Dotted key of the offending value, e.g. `concrete.conductivity_w_mk`.
        key: String,
        /// Full message, starting with the key.
        message: String,
    },
    /// A CSV table of the geometry (`arch_table`'s `table` or `valley`).
    #[error(transparent)]
    Table(#[from] ArchTableError),
}

fn fmt_parse(origin: &str, position: Option<(usize, usize)>, message: &str) -> String {
    match position {
        Some((line, col)) => format!("{origin}:{line}:{col}: {message}"),
        None => format!("{origin}: {message}"),
    }
}

fn fmt_invalid(origin: Option<&str>, position: Option<(usize, usize)>, message: &str) -> String {
    match (origin, position) {
        (Some(o), Some((line, col))) => format!("{o}:{line}:{col}: {message}"),
        (Some(o), None) => format!("{o}: {message}"),
        (None, _) => message.to_string(),
    }
}

impl SceneError {
    /// A validation error about `key`; `message` is the full text, starting with the key.
    pub(crate) fn invalid(key: impl Into<String>, message: impl fmt::Display) -> SceneError {
        SceneError::Invalid {
            origin: None,
            position: None,
            key: key.into(),
            message: message.to_string(),
        }
    }

    /// Attach the file name to a validation error that has none.
    pub fn with_origin(self, name: &str) -> SceneError {
        match self {
            SceneError::Invalid {
                origin: None,
                position,
                key,
                message,
            } => SceneError::Invalid {
                origin: Some(name.to_string()),
                position,
                key,
                message,
            },
            other => other,
        }
    }

    /// Attach the line and column of the key a validation error is about,
    /// found in the scene's `text`.
    pub(crate) fn located(self, text: &str) -> SceneError {
        match self {
            SceneError::Invalid {
                origin,
                position: None,
                key,
                message,
            } => SceneError::Invalid {
                origin,
                position: key_offset(text, &key).map(|at| line_col(text, at)),
                key,
                message,
            },
            other => other,
        }
    }

    /// The dotted key a validation error is about.
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// 1-based line and column (in characters) of byte offset `at` in `text`.
pub(crate) fn line_col(text: &str, at: usize) -> (usize, usize) {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    let col = text[line_start..at].chars().count() + 1;
    (line, col)
}

/// Tables a scene must have, reported as `missing table [x]`.
const REQUIRED_TABLES: [&str; 4] = ["geometry", "lifts", "joints", "concrete"];

/// Turn a toml/serde error into a [`SceneError::Parse`] that names the file,
/// the line and column, and the key (or table) involved.
pub(crate) fn from_toml_error(text: &str, origin: &str, err: toml::de::Error) -> SceneError {
    let doc = DeTable::parse(text).ok();
    let mut err = err;
    if let Some(doc) = &doc {
        if let Some(better) = refine_geometry_error(text, doc, &err) {
            err = better;
        }
    }
    let raw = err.message().trim().to_string();
    let span = err.span();
    let Some(doc) = doc else {
        // Syntax error: toml's own message and position.
        return SceneError::Parse {
            origin: origin.to_string(),
            position: span.map(|s| line_col(text, s.start)),
            message: raw,
        };
    };
    let span = span.unwrap_or(0..0);
    let located = locate(doc.get_ref(), &span);

    if let Some(rest) = raw.strip_prefix("unknown field `") {
        if let Some((field, tail)) = rest.split_once('`') {
            let (table, pos) = match &located {
                Some(Located::Key(path)) => (path[..path.len() - 1].to_vec(), span.start),
                Some(Located::Table(path)) => {
                    // The error points at the table header: find the key itself.
                    let at = table_at(doc.get_ref(), path)
                        .and_then(|t| key_span(t, field))
                        .map(|s| s.start)
                        .unwrap_or(span.start);
                    (path.clone(), at)
                }
                _ => (Vec::new(), span.start),
            };
            return SceneError::Parse {
                origin: origin.to_string(),
                position: Some(line_col(text, pos)),
                message: format!("unknown key `{field}` {}{tail}", in_table(&table)),
            };
        }
    }
    if let Some(rest) = raw.strip_prefix("missing field `") {
        if let Some((field, _)) = rest.split_once('`') {
            let table = match &located {
                Some(Located::Table(path)) | Some(Located::Value(path)) => path.clone(),
                _ => Vec::new(),
            };
            if table.is_empty() {
                let message = if REQUIRED_TABLES.contains(&field) {
                    format!("missing table [{field}]")
                } else {
                    format!("missing key `{field}` at the top level")
                };
                return SceneError::Parse {
                    origin: origin.to_string(),
                    position: None,
                    message,
                };
            }
            return SceneError::Parse {
                origin: origin.to_string(),
                position: Some(line_col(text, span.start)),
                message: format!("missing key `{field}` {}", in_table(&table)),
            };
        }
    }
    let message = match &located {
        Some(Located::Value(path)) | Some(Located::Table(path)) if !path.is_empty() => {
            format!("{}: {raw}", path.join("."))
        }
        _ => raw,
    };
    SceneError::Parse {
        origin: origin.to_string(),
        position: Some(line_col(text, span.start)),
        message,
    }
}

fn in_table(path: &[String]) -> String {
    if path.is_empty() {
        "at the top level".to_string()
    } else {
        format!("in [{}]", path.join("."))
    }
}

/// What an error span points at.
enum Located {
    /// A key; the path includes the key.
    Key(Vec<String>),
    /// A table (its header); the path of the table.
    Table(Vec<String>),
    /// A value (or an element of an array value); the path of its key.
    Value(Vec<String>),
}

fn locate(table: &DeTable<'_>, span: &Range<usize>) -> Option<Located> {
    locate_in(table, span, &mut Vec::new())
}

fn locate_in(table: &DeTable<'_>, span: &Range<usize>, path: &mut Vec<String>) -> Option<Located> {
    for (k, v) in table.iter() {
        path.push(k.get_ref().to_string());
        if k.span() == *span {
            return Some(Located::Key(path.clone()));
        }
        if v.span() == *span {
            return Some(match v.get_ref() {
                DeValue::Table(_) => Located::Table(path.clone()),
                _ => Located::Value(path.clone()),
            });
        }
        match v.get_ref() {
            DeValue::Table(t) => {
                if let Some(found) = locate_in(t, span, path) {
                    return Some(found);
                }
            }
            DeValue::Array(items) => {
                for item in items.iter() {
                    if item.span() == *span {
                        return Some(Located::Value(path.clone()));
                    }
                    if let DeValue::Table(t) = item.get_ref() {
                        if let Some(found) = locate_in(t, span, path) {
                            return Some(found);
                        }
                    }
                }
            }
            _ => {}
        }
        path.pop();
    }
    None
}

/// Byte offset of the dotted `key` (`concrete.conductivity_w_mk`,
/// `output.snapshots[2]`) in the scene text: its value when it is a plain
/// value, its name when it is a table, the nearest existing table's name
/// when it is missing.
fn key_offset(text: &str, key: &str) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut found = None;
    for name in key.split('.') {
        let name = name.split('[').next().unwrap_or(name);
        let (Some(value), Some(span)) = (entry(table, name), key_span(table, name)) else {
            break;
        };
        match value.get_ref() {
            DeValue::Table(inner) => {
                found = Some(span.start);
                table = inner;
            }
            _ => return Some(value.span().start),
        }
    }
    found
}

fn table_at<'a, 'i>(root: &'a DeTable<'i>, path: &[String]) -> Option<&'a DeTable<'i>> {
    let mut t = root;
    for name in path {
        let v = entry(t, name)?;
        match v.get_ref() {
            DeValue::Table(inner) => t = inner,
            _ => return None,
        }
    }
    Some(t)
}

fn entry<'a, 'i>(table: &'a DeTable<'i>, name: &str) -> Option<&'a Spanned<DeValue<'i>>> {
    table
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == name)
        .map(|(_, v)| v)
}

fn key_span(table: &DeTable<'_>, name: &str) -> Option<Range<usize>> {
    table
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == name)
        .map(|(k, _)| k.span())
}

/// `[geometry]` is an internally tagged enum: serde buffers it, and its errors
/// lose their position (they point at the `[geometry]` header and do not name
/// the key). Re-read the geometry table alone, in a copy of the text where
/// everything else is blanked (byte offsets unchanged), into the variant its
/// `kind` names, and return that error instead.
fn refine_geometry_error(
    text: &str,
    doc: &Spanned<DeTable<'_>>,
    err: &toml::de::Error,
) -> Option<toml::de::Error> {
    let span = err.span()?;
    let geometry = entry(doc.get_ref(), "geometry")?;
    if geometry.span() != span {
        return None;
    }
    let DeValue::Table(table) = geometry.get_ref() else {
        return None;
    };
    // Only a `[geometry]` header table (not an inline or dotted one) can be cut out.
    if !text.get(span.clone())?.trim_start().starts_with('[') {
        return None;
    }
    let kind = entry(table, "kind")?.get_ref().as_str()?.to_string();

    let mut keep = vec![false; text.len()];
    keep[span.clone()].iter_mut().for_each(|b| *b = true);
    for (k, v) in table.iter() {
        if k.get_ref().as_ref() == "kind" {
            continue;
        }
        let (start, end) = (k.span().start, v.span().end);
        if start > end || end > text.len() {
            return None;
        }
        keep[start..end].iter_mut().for_each(|b| *b = true);
    }
    let blanked: Vec<u8> = text
        .bytes()
        .zip(&keep)
        .map(|(b, &k)| {
            if k || b == b'\n' || b == b'\r' {
                b
            } else {
                b' '
            }
        })
        .collect();
    // Blanking whole characters only (all bytes of a multi-byte char are
    // inside or outside the same range), so this stays valid UTF-8.
    let blanked = String::from_utf8(blanked).ok()?;

    #[derive(Deserialize)]
    struct Only<T> {
        #[allow(dead_code)]
        geometry: T,
    }
    let result = match kind.as_str() {
        "blocks" => toml::from_str::<Only<BlocksGeometry>>(&blanked).map(|_| ()),
        "arch" => toml::from_str::<Only<ArchGeometry>>(&blanked).map(|_| ()),
        "arch_table" => toml::from_str::<Only<ArchTableGeometry>>(&blanked).map(|_| ()),
        _ => return None,
    };
    result.err()
}
