//! The B-spline surface JSON format of DESIGN.md §5:
//! `{"degree_u":3,"degree_v":3,"knots_u":[...],"knots_v":[...],
//! "control_points":[[[x,y,z],...],...]}` with optional `"weights"` of the
//! control net's shape; a file holds one surface or `{"surfaces":[...]}`.
//!
//! Numbers are written as the shortest decimal that reads back to the same
//! f64 and read exactly (serde_json `float_roundtrip`), so a round trip is
//! bit-exact. Files are written atomically (temporary file + rename).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde_json::{Map, Value};
use thiserror::Error;

use super::{BSplineError, BSplineSurface};
use crate::Vec3;

/// Why a surface JSON file could not be read or written.
#[derive(Debug, Error)]
pub enum SurfaceJsonError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The text is not JSON (the message carries line and column).
    #[error("invalid JSON: {0}")]
    Syntax(String),
    /// The top level is neither a surface object nor `{"surfaces": [...]}`.
    #[error("expected a surface object or {{\"surfaces\": [...]}}: {0}")]
    Layout(String),
    /// A field of a surface is missing or has the wrong type or shape.
    #[error("surface {surface}: field `{field}`: {message}")]
    Field {
        /// Index of the surface in the file (0 for a single surface).
        surface: usize,
        /// The field, with indices (e.g. `control_points[2][1]`).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The fields are well formed but do not make a valid surface.
    #[error("surface {surface}: {source}")]
    Surface {
        /// Index of the surface in the file.
        surface: usize,
        /// The validation error.
        source: BSplineError,
    },
}

/// Reads every surface of a JSON file (DESIGN.md §5): a single surface gives
/// a list of one. Errors name the surface index and field.
pub fn read_surfaces_json(path: impl AsRef<Path>) -> Result<Vec<BSplineSurface>, SurfaceJsonError> {
    let path = path.as_ref();
    let text = fs::read_to_string(path).map_err(|source| SurfaceJsonError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_surfaces_json(&text)
}

/// Parses surfaces from JSON text; see [`read_surfaces_json`].
pub fn parse_surfaces_json(text: &str) -> Result<Vec<BSplineSurface>, SurfaceJsonError> {
    let value: Value =
        serde_json::from_str(text).map_err(|e| SurfaceJsonError::Syntax(e.to_string()))?;
    let Value::Object(obj) = value else {
        return Err(SurfaceJsonError::Layout(
            "the top level is not an object".into(),
        ));
    };
    if let Some(list) = obj.get("surfaces") {
        let Value::Array(list) = list else {
            return Err(SurfaceJsonError::Layout(
                "`surfaces` is not an array".into(),
            ));
        };
        list.iter()
            .enumerate()
            .map(|(k, s)| match s {
                Value::Object(o) => surface_from_object(k, o),
                _ => Err(field_error(k, "", "the surface is not an object")),
            })
            .collect()
    } else if obj.contains_key("degree_u") || obj.contains_key("control_points") {
        Ok(vec![surface_from_object(0, &obj)?])
    } else {
        Err(SurfaceJsonError::Layout(
            "neither `surfaces` nor `control_points` found".into(),
        ))
    }
}

fn field_error(surface: usize, field: &str, message: &str) -> SurfaceJsonError {
    SurfaceJsonError::Field {
        surface,
        field: field.to_string(),
        message: message.to_string(),
    }
}

fn surface_from_object(
    k: usize,
    o: &Map<String, Value>,
) -> Result<BSplineSurface, SurfaceJsonError> {
    let get = |name: &str| o.get(name).ok_or_else(|| field_error(k, name, "missing"));
    let degree = |name: &str| -> Result<usize, SurfaceJsonError> {
        get(name)?
            .as_u64()
            .and_then(|d| usize::try_from(d).ok())
            .ok_or_else(|| field_error(k, name, "expected a non-negative integer"))
    };
    let numbers = |name: &str, v: &Value| -> Result<Vec<f64>, SurfaceJsonError> {
        let Value::Array(a) = v else {
            return Err(field_error(k, name, "expected an array of numbers"));
        };
        a.iter()
            .enumerate()
            .map(|(i, x)| {
                x.as_f64()
                    .ok_or_else(|| field_error(k, &format!("{name}[{i}]"), "expected a number"))
            })
            .collect()
    };
    let rows = |name: &str, v: &Value| -> Result<Vec<Value>, SurfaceJsonError> {
        match v {
            Value::Array(a) => Ok(a.clone()),
            _ => Err(field_error(k, name, "expected an array of rows")),
        }
    };
    let degree_u = degree("degree_u")?;
    let degree_v = degree("degree_v")?;
    let knots_u = numbers("knots_u", get("knots_u")?)?;
    let knots_v = numbers("knots_v", get("knots_v")?)?;
    let mut net = Vec::new();
    for (i, row) in rows("control_points", get("control_points")?)?
        .iter()
        .enumerate()
    {
        let name = format!("control_points[{i}]");
        let mut r = Vec::new();
        for (j, p) in rows(&name, row)?.iter().enumerate() {
            let name = format!("control_points[{i}][{j}]");
            let xyz = numbers(&name, p)?;
            if xyz.len() != 3 {
                return Err(field_error(
                    k,
                    &name,
                    &format!("expected 3 coordinates, found {}", xyz.len()),
                ));
            }
            r.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
        }
        net.push(r);
    }
    let weights = match o.get("weights") {
        None | Some(Value::Null) => None,
        Some(w) => {
            let mut out = Vec::new();
            for (i, row) in rows("weights", w)?.iter().enumerate() {
                out.push(numbers(&format!("weights[{i}]"), row)?);
            }
            Some(out)
        }
    };
    BSplineSurface::new(degree_u, degree_v, knots_u, knots_v, net, weights)
        .map_err(|source| SurfaceJsonError::Surface { surface: k, source })
}

fn surface_value(s: &BSplineSurface) -> Value {
    let nv = s.count_v();
    let pts = s.control_points();
    let net: Vec<Value> = pts
        .chunks(nv)
        .map(|row| {
            Value::from(
                row.iter()
                    .map(|p| Value::from(p.to_array().to_vec()))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let mut o = Map::new();
    o.insert("degree_u".into(), Value::from(s.degree_u()));
    o.insert("degree_v".into(), Value::from(s.degree_v()));
    o.insert("knots_u".into(), Value::from(s.knots_u().to_vec()));
    o.insert("knots_v".into(), Value::from(s.knots_v().to_vec()));
    o.insert("control_points".into(), Value::from(net));
    if let Some(w) = s.weights() {
        let rows: Vec<Value> = w.chunks(nv).map(|r| Value::from(r.to_vec())).collect();
        o.insert("weights".into(), Value::from(rows));
    }
    Value::Object(o)
}

/// One surface as JSON text (DESIGN.md §5), numbers printed exactly.
pub fn surface_to_json(surface: &BSplineSurface) -> String {
    let mut s = surface_value(surface).to_string();
    s.push('\n');
    s
}

/// A list of surfaces as `{"surfaces":[...]}`, numbers printed exactly.
pub fn surfaces_to_json(surfaces: &[BSplineSurface]) -> String {
    let list: Vec<Value> = surfaces.iter().map(surface_value).collect();
    let mut o = Map::new();
    o.insert("surfaces".into(), Value::from(list));
    let mut s = Value::Object(o).to_string();
    s.push('\n');
    s
}

/// Writes one surface to `path` atomically (temporary file in the same
/// directory, then rename).
pub fn write_surface_json(
    path: impl AsRef<Path>,
    surface: &BSplineSurface,
) -> Result<(), SurfaceJsonError> {
    write_atomic(path.as_ref(), surface_to_json(surface).as_bytes())
}

/// Writes `{"surfaces":[...]}` to `path` atomically.
pub fn write_surfaces_json(
    path: impl AsRef<Path>,
    surfaces: &[BSplineSurface],
) -> Result<(), SurfaceJsonError> {
    write_atomic(path.as_ref(), surfaces_to_json(surfaces).as_bytes())
}

/// Writes `bytes` to a temporary file next to `path`, syncs it and renames it
/// over `path`; on failure the temporary file is removed and `path` untouched.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SurfaceJsonError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let err = |source| SurfaceJsonError::Write {
        path: path.to_path_buf(),
        source,
    };
    let name = path
        .file_name()
        .ok_or_else(|| err(std::io::Error::other("the path has no file name")))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = dir.join(format!(
        ".{}.{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(err(e));
    }
    Ok(())
}
