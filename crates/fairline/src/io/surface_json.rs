//! The B-spline surface JSON format of DESIGN.md §5:
//! `{"degree_u":3,"degree_v":3,"knots_u":[...],"knots_v":[...],
//! "control_points":[[[x,y,z],...],...]}` with optional `"weights"` of the
//! control net's shape and optional `"trims"` (closed loops of 2-D B-spline
//! curves in (u, v), the first the outer boundary, the rest holes; each curve
//! `{"degree","knots","control_points":[[u,v],...],"weights"?}`); a file holds
//! one surface or `{"surfaces":[...]}`. A file whose top level has `shape`
//! is geomdl's JSON instead ([`super::geomdl`]).
//!
//! Numbers are written as the shortest decimal that reads back to the same
//! f64 and read exactly (serde_json `float_roundtrip`), so a round trip is
//! bit-exact. Files are written atomically (temporary file + rename).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};
use thiserror::Error;

use super::geomdl::{GeomdlError, GeomdlImport, is_geomdl, parse_geomdl};
use crate::Vec3;
use crate::bspline::{BSplineError, BSplineSurface, TrimCurve, TrimLoop};

/// Why a surface JSON file could not be read or written.
#[derive(Debug, Error)]
pub enum SurfaceJsonError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The error of [`super::atomic_write`].
        source: super::IoError,
    },
    /// The text is not JSON (the message carries line and column).
    #[error("invalid JSON: {0}")]
    Syntax(String),
    /// The top level is neither a surface object nor `{"surfaces": [...]}`
    /// nor geomdl's `{"shape": ...}`, or a geomdl entry is not read.
    #[error(
        "expected a surface object, {{\"surfaces\": [...]}} or geomdl's {{\"shape\": ...}}: {0}"
    )]
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
    /// The file is larger than [`MAX_SURFACE_JSON_BYTES`].
    #[error(
        "{}: {size} bytes; surface JSON files over {max} bytes are refused (reading one holds it in memory several times over)",
        path.display()
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size in bytes.
        size: u64,
        /// The limit, [`MAX_SURFACE_JSON_BYTES`].
        max: u64,
    },
    /// An error of the content of a file, with the file's name.
    #[error("{}: {error}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it (surface, field, JSON line and column).
        error: Box<SurfaceJsonError>,
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

/// The largest surface JSON file [`read_surfaces_json`] reads: 32 MiB.
///
/// The parser holds the text and a tree of its values: measured, a file of
/// one-digit control points peaks at about 23 bytes of memory per byte of
/// text (a 32 MiB file at 0.76 GB; a 200 MB file peaked at 5.1 GB before
/// this limit). 32 MiB holds a net of about half a million control points at
/// full precision, far beyond real CAD surfaces.
pub const MAX_SURFACE_JSON_BYTES: u64 = 32 << 20;

/// Reads every surface of a JSON file (DESIGN.md §5, or geomdl's JSON,
/// see [`super::geomdl`]): a single surface gives a list of one. Errors
/// name the file, the surface index and the field; a geomdl entry that is
/// not read (see [`read_surface_json_file`]) is an error here. Files over
/// [`MAX_SURFACE_JSON_BYTES`] are refused before being read.
pub fn read_surfaces_json(path: impl AsRef<Path>) -> Result<Vec<BSplineSurface>, SurfaceJsonError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_surfaces_json(&text).map_err(|error| in_file(path, error))
}

/// The surfaces of a JSON file of either schema (fairline's, DESIGN.md §5,
/// or geomdl's, told apart by its top-level `shape`), with the geomdl
/// entries that are not read listed rather than refused.
pub fn read_surface_json_file(path: impl AsRef<Path>) -> Result<GeomdlImport, SurfaceJsonError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_surface_json_any(&text).map_err(|error| in_file(path, error))
}

fn in_file(path: &Path, error: SurfaceJsonError) -> SurfaceJsonError {
    SurfaceJsonError::InFile {
        path: path.to_path_buf(),
        error: Box::new(error),
    }
}

/// The text of a JSON file, refused over [`MAX_SURFACE_JSON_BYTES`].
fn read_text(path: &Path) -> Result<String, SurfaceJsonError> {
    use std::io::Read;
    let read_err = |source| SurfaceJsonError::Read {
        path: path.to_path_buf(),
        source,
    };
    let too_large = |size| SurfaceJsonError::TooLarge {
        path: path.to_path_buf(),
        size,
        max: MAX_SURFACE_JSON_BYTES,
    };
    super::require_regular_file(path).map_err(read_err)?;
    let file = fs::File::open(path).map_err(read_err)?;
    let size = file.metadata().map_err(read_err)?.len();
    if size > MAX_SURFACE_JSON_BYTES {
        return Err(too_large(size));
    }
    // read at most one byte past the limit, in case the file grows meanwhile
    let mut text = String::new();
    file.take(MAX_SURFACE_JSON_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(read_err)?;
    if text.len() as u64 > MAX_SURFACE_JSON_BYTES {
        return Err(too_large(text.len() as u64));
    }
    Ok(text)
}

/// Parses surfaces from JSON text; see [`read_surfaces_json`].
pub fn parse_surfaces_json(text: &str) -> Result<Vec<BSplineSurface>, SurfaceJsonError> {
    let imp = parse_surface_json_any(text)?;
    if let Some(u) = imp.unreadable.first() {
        return Err(SurfaceJsonError::Layout(u.to_string()));
    }
    Ok(imp.surfaces)
}

/// Parses JSON text of either schema; see [`read_surface_json_file`].
pub fn parse_surface_json_any(text: &str) -> Result<GeomdlImport, SurfaceJsonError> {
    let value: Value =
        serde_json::from_str(text).map_err(|e| SurfaceJsonError::Syntax(e.to_string()))?;
    let Value::Object(obj) = value else {
        return Err(SurfaceJsonError::Layout(
            "the top level is not an object".into(),
        ));
    };
    if is_geomdl(&obj) {
        return parse_geomdl(&obj).map_err(|e| match e {
            GeomdlError::Layout(m) => SurfaceJsonError::Layout(format!("geomdl JSON: {m}")),
            GeomdlError::Field {
                surface,
                field,
                message,
            } => SurfaceJsonError::Field {
                surface,
                field,
                message,
            },
            GeomdlError::Surface { surface, source } => {
                SurfaceJsonError::Surface { surface, source }
            }
        });
    }
    let surfaces = if let Some(list) = obj.get("surfaces") {
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
            .collect::<Result<Vec<_>, _>>()?
    } else if obj.contains_key("degree_u") || obj.contains_key("control_points") {
        vec![surface_from_object(0, &obj)?]
    } else {
        return Err(SurfaceJsonError::Layout(
            "neither `surfaces` nor `control_points` (fairline surface JSON) nor `shape` (geomdl JSON) found".into(),
        ));
    };
    Ok(GeomdlImport {
        surfaces,
        unreadable: Vec::new(),
    })
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
    fn rows<'a>(k: usize, name: &str, v: &'a Value) -> Result<&'a [Value], SurfaceJsonError> {
        match v {
            Value::Array(a) => Ok(a),
            _ => Err(field_error(k, name, "expected an array of rows")),
        }
    }
    let degree_u = degree("degree_u")?;
    let degree_v = degree("degree_v")?;
    let knots_u = numbers("knots_u", get("knots_u")?)?;
    let knots_v = numbers("knots_v", get("knots_v")?)?;
    let mut net = Vec::new();
    for (i, row) in rows(k, "control_points", get("control_points")?)?
        .iter()
        .enumerate()
    {
        let name = format!("control_points[{i}]");
        let mut r = Vec::new();
        for (j, p) in rows(k, &name, row)?.iter().enumerate() {
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
            for (i, row) in rows(k, "weights", w)?.iter().enumerate() {
                out.push(numbers(&format!("weights[{i}]"), row)?);
            }
            Some(out)
        }
    };
    let surface = BSplineSurface::new(degree_u, degree_v, knots_u, knots_v, net, weights)
        .map_err(|source| SurfaceJsonError::Surface { surface: k, source })?;
    match o.get("trims") {
        None | Some(Value::Null) => Ok(surface),
        Some(t) => {
            let loops = trims_from_value(k, t)?;
            surface
                .with_trims(loops)
                .map_err(|e| field_error(k, "trims", &e.to_string()))
        }
    }
}

/// `"trims": [[curve, ...], ...]`, each curve
/// `{"degree","knots","control_points":[[u,v],...],"weights"?}`.
fn trims_from_value(k: usize, t: &Value) -> Result<Vec<TrimLoop>, SurfaceJsonError> {
    let Value::Array(loops) = t else {
        return Err(field_error(k, "trims", "expected an array of loops"));
    };
    let mut out = Vec::with_capacity(loops.len());
    for (l, lp) in loops.iter().enumerate() {
        let Value::Array(curves) = lp else {
            return Err(field_error(
                k,
                &format!("trims[{l}]"),
                "expected an array of curves",
            ));
        };
        let mut cs = Vec::with_capacity(curves.len());
        for (c, cv) in curves.iter().enumerate() {
            let name = format!("trims[{l}][{c}]");
            let Value::Object(co) = cv else {
                return Err(field_error(k, &name, "expected a curve object"));
            };
            let get = |f: &str| {
                co.get(f)
                    .ok_or_else(|| field_error(k, &format!("{name}.{f}"), "missing"))
            };
            let nums = |f: &str, v: &Value| -> Result<Vec<f64>, SurfaceJsonError> {
                let Value::Array(a) = v else {
                    return Err(field_error(
                        k,
                        &format!("{name}.{f}"),
                        "expected an array of numbers",
                    ));
                };
                a.iter()
                    .enumerate()
                    .map(|(i, x)| {
                        x.as_f64().ok_or_else(|| {
                            field_error(k, &format!("{name}.{f}[{i}]"), "expected a number")
                        })
                    })
                    .collect()
            };
            let degree = get("degree")?
                .as_u64()
                .and_then(|d| usize::try_from(d).ok())
                .ok_or_else(|| {
                    field_error(
                        k,
                        &format!("{name}.degree"),
                        "expected a non-negative integer",
                    )
                })?;
            let knots = nums("knots", get("knots")?)?;
            let Value::Array(pts) = get("control_points")? else {
                return Err(field_error(
                    k,
                    &format!("{name}.control_points"),
                    "expected an array of [u, v] points",
                ));
            };
            let mut points = Vec::with_capacity(pts.len());
            for (i, p) in pts.iter().enumerate() {
                let f = format!("control_points[{i}]");
                let uv = nums(&f, p)?;
                if uv.len() != 2 {
                    return Err(field_error(
                        k,
                        &format!("{name}.{f}"),
                        &format!("expected 2 coordinates, found {}", uv.len()),
                    ));
                }
                points.push([uv[0], uv[1]]);
            }
            let weights = match co.get("weights") {
                None | Some(Value::Null) => None,
                Some(w) => Some(nums("weights", w)?),
            };
            let curve = TrimCurve::new(degree, knots, points, weights)
                .map_err(|m| field_error(k, &name, &m))?;
            cs.push(curve);
        }
        out.push(TrimLoop { curves: cs });
    }
    Ok(out)
}

fn trims_value(s: &BSplineSurface) -> Value {
    let loops: Vec<Value> = s
        .trims()
        .iter()
        .map(|l| {
            let curves: Vec<Value> = l
                .curves
                .iter()
                .map(|c| {
                    let mut o = Map::new();
                    o.insert("degree".into(), Value::from(c.degree()));
                    o.insert("knots".into(), Value::from(c.knots().to_vec()));
                    let pts: Vec<Value> = c
                        .control_points()
                        .iter()
                        .map(|p| Value::from(p.to_vec()))
                        .collect();
                    o.insert("control_points".into(), Value::from(pts));
                    if let Some(w) = c.weights() {
                        o.insert("weights".into(), Value::from(w.to_vec()));
                    }
                    Value::Object(o)
                })
                .collect();
            Value::from(curves)
        })
        .collect();
    Value::from(loops)
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
    if s.is_trimmed() {
        o.insert("trims".into(), trims_value(s));
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

/// Writes `bytes` through [`super::atomic_write`] (temporary file in the
/// same directory, synced, then renamed; nothing is left behind on failure).
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SurfaceJsonError> {
    super::atomic_write(path, |w| w.write_all(bytes)).map_err(|e| SurfaceJsonError::Write {
        path: path.to_path_buf(),
        source: e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::TrimLoop;
    use crate::bspline::tests::{Rng, torus};
    use crate::bspline::trim_tests::circle_curve;

    fn random_surface(rng: &mut Rng, rational: bool) -> BSplineSurface {
        let (nu, nv) = (5, 4);
        let net: Vec<Vec<Vec3>> = (0..nu)
            .map(|_| (0..nv).map(|_| 1e3 * rng.vec3()).collect())
            .collect();
        let weights = rational.then(|| {
            (0..nu)
                .map(|_| (0..nv).map(|_| 0.1 + rng.unit()).collect())
                .collect()
        });
        let k = rng.unit();
        BSplineSurface::new(
            3,
            2,
            vec![0.0, 0.0, 0.0, 0.0, 0.1 + 0.8 * k, 1.0, 1.0, 1.0, 1.0],
            vec![-1.0, -0.5, 0.1 * k, 1.0 / 3.0, 2.0, 2.5, 3.0],
            net,
            weights,
        )
        .unwrap()
    }

    fn temp_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("fairline-bspline-{name}-{}", std::process::id()));
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn bspline_json_round_trip_is_bit_exact() {
        let mut rng = Rng::new(42);
        let surfaces = vec![
            random_surface(&mut rng, false),
            random_surface(&mut rng, true),
        ];
        let text = surfaces_to_json(&surfaces);
        let back = parse_surfaces_json(&text).unwrap();
        assert_eq!(back, surfaces);
        for (a, b) in back.iter().zip(&surfaces) {
            for (p, q) in a.control_points().iter().zip(b.control_points()) {
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    q.to_array().map(f64::to_bits)
                );
            }
        }
        assert_eq!(surfaces_to_json(&back), text);
        // A single surface object reads as a list of one.
        let one = surface_to_json(&surfaces[1]);
        assert!(one.starts_with("{\"control_points\""));
        assert_eq!(
            parse_surfaces_json(&one).unwrap(),
            vec![surfaces[1].clone()]
        );
        // Through files, atomically, leaving no temporary file behind.
        let dir = temp_dir("roundtrip");
        let path = dir.join("surfaces.json");
        write_surfaces_json(&path, &surfaces).unwrap();
        write_surface_json(dir.join("one.json"), &surfaces[0]).unwrap();
        assert_eq!(read_surfaces_json(&path).unwrap(), surfaces);
        assert_eq!(
            read_surfaces_json(dir.join("one.json")).unwrap(),
            vec![surfaces[0].clone()]
        );
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bspline_json_errors_name_surface_and_field() {
        let good = r#"{"degree_u":1,"degree_v":1,"knots_u":[0,0,1,1],"knots_v":[0,0,1,1],
            "control_points":[[[0,0,0],[0,1,0]],[[1,0,0],[1,1,0.5]]]}"#;
        assert_eq!(parse_surfaces_json(good).unwrap().len(), 1);
        let list = |second: &str| format!("{{\"surfaces\":[{good},{second}]}}");
        let err = |text: &str| parse_surfaces_json(text).unwrap_err().to_string();
        assert_eq!(
            err(&list(&good.replace("\"degree_u\":1,", ""))),
            "surface 1: field `degree_u`: missing"
        );
        assert_eq!(
            err(&list(&good.replace("\"degree_u\":1", "\"degree_u\":-1"))),
            "surface 1: field `degree_u`: expected a non-negative integer"
        );
        assert_eq!(
            err(&list(&good.replace("[1,1,0.5]", "[1,1]"))),
            "surface 1: field `control_points[1][1]`: expected 3 coordinates, found 2"
        );
        assert_eq!(
            err(&list(&good.replace("[1,1,0.5]", "[1,\"a\",0.5]"))),
            "surface 1: field `control_points[1][1][1]`: expected a number"
        );
        assert_eq!(
            err(&list(
                &good.replace("\"knots_v\":[0,0,1,1]", "\"knots_v\":[0,1,0,1]")
            )),
            "surface 1: knot vector in v decreases at index 2 (1 > 0)"
        );
        assert_eq!(
            err(&list(&good.replace("}", ",\"weights\":[[1,1],[1]]}"))),
            "surface 1: weights: row 1 has 1 weights, the control net has 2"
        );
        assert_eq!(
            err(&list(&good.replace("}", ",\"weights\":[[1,1],[1,0]]}"))),
            "surface 1: weight (1, 1) is 0; weights must be positive"
        );
        assert!(err("{\"surfaces\": 3}").contains("not an array"));
        assert!(err("[1,2]").contains("not an object"));
        assert!(err("{\"degree_u\": 1,").starts_with("invalid JSON"));
        assert!(
            read_surfaces_json("/nonexistent/x.json")
                .unwrap_err()
                .to_string()
                .starts_with("cannot read /nonexistent/x.json")
        );
        // A failed write leaves nothing behind.
        let dir = temp_dir("failed-write");
        let target = dir.join("sub-directory-as-target");
        fs::create_dir_all(&target).unwrap();
        assert!(write_surfaces_json(&target, &[]).is_err());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bspline_teapot_json_loads() {
        let Some(path) = crate::shared_data::shared_data("surfaces/teapot.json") else {
            return;
        };
        let surfaces = read_surfaces_json(path).unwrap();
        assert_eq!(surfaces.len(), 32);
        for s in &surfaces {
            assert_eq!((s.degree_u(), s.degree_v()), (3, 3));
            assert_eq!((s.count_u(), s.count_v()), (4, 4));
            assert!(!s.is_rational());
            let t = crate::bspline::tessellate(s, 9, 9);
            assert!(t.positions.iter().all(|p| p.is_finite()));
            // Degenerate patch corners (spout tip, lid pole) still get normals.
            for n in &t.normals {
                assert!(n.is_finite());
                assert!((n.length() - 1.0).abs() < 1e-9, "{n:?}");
            }
        }
        // Round trip of a real file is bit-exact.
        let again = parse_surfaces_json(&surfaces_to_json(&surfaces)).unwrap();
        assert_eq!(again, surfaces);
    }

    /// Trims survive the JSON round trip bit for bit; untrimmed surfaces write
    /// no `"trims"` key; malformed trims are errors naming the field.
    #[test]
    fn surface_json_trims_round_trip_and_errors() {
        let s = torus(3.0, 1.0)
            .with_trims(vec![
                TrimLoop::polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap(),
                TrimLoop {
                    curves: vec![circle_curve([0.3, 0.6], 0.1 + 1e-17, false)],
                },
            ])
            .unwrap();
        let text = surface_to_json(&s);
        let back = parse_surfaces_json(&text).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!(back[0], s);
        assert_eq!(surface_to_json(&back[0]), text);
        let plain = torus(3.0, 1.0);
        assert!(!surface_to_json(&plain).contains("trims"));
        let bad = text.replacen("\"degree\":2", "\"degree\":0", 1);
        let e = parse_surfaces_json(&bad).unwrap_err().to_string();
        assert!(e.contains("trims[1][0]") && e.contains("degree"), "{e}");
        let empty = text.replacen("\"trims\":[", "\"trims\":[[],", 1);
        let e = parse_surfaces_json(&empty).unwrap_err().to_string();
        assert!(e.contains("trim loop 0"), "{e}");
    }
}
