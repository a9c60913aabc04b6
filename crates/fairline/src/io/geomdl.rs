//! The JSON format of geomdl (NURBS-Python 5, `exchange.export_json`):
//! `{"shape": {"type": "surface", "count": n, "data": [surface, …]}}`, each
//! surface `{"type": "spline", "rational", "dimension", "degree_u",
//! "degree_v", "knotvector_u", "knotvector_v", "size_u", "size_v",
//! "control_points": {"points": [[x, y, z], …], "weights": [w, …]}}`.
//!
//! After geomdl's `_exchange.export_dict_surf` / `import_dict_surf`: the
//! points are Cartesian (not multiplied by their weight), u-major —
//! control point (i, j) at `j + size_v · i`, fairline's own order — and
//! `weights`, when present, makes the surface rational. Dimension 3 is
//! read; dimension 2 in the plane z = 0.
//!
//! A surface with `trims` is trimmed by them ([`trims`]: holes and kept
//! areas, geomdl's sense): one face per kept area.
//!
//! Not read, and listed in [`GeomdlImport::unreadable`]: shapes that are
//! not surfaces (`"type": "curve"` or `"volume"`), entries that are not
//! `"spline"`, and surfaces whose trims do not make faces (a trim that does
//! not close, kept areas inside one another, a trim curve of a type geomdl
//! does not define).

use serde_json::{Map, Value};
use thiserror::Error;

use super::unreadable::Unreadable;
use crate::Vec3;
use crate::bspline::{BSplineError, BSplineSurface};

mod trims;

/// Why a geomdl document could not be read (the surface JSON reader wraps
/// it with the file's name).
#[derive(Debug, Error)]
pub enum GeomdlError {
    /// `shape` or its `type` or `data` is missing or malformed.
    #[error("geomdl JSON: {0}")]
    Layout(String),
    /// A field of an entry of `shape.data` is missing or malformed.
    #[error("surface {surface}: field `{field}`: {message}")]
    Field {
        /// Index of the entry in `shape.data`.
        surface: usize,
        /// The field, with indices.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The fields are well formed but do not make a valid surface.
    #[error("surface {surface}: {source}")]
    Surface {
        /// Index of the entry in `shape.data`.
        surface: usize,
        /// The validation error.
        source: BSplineError,
    },
}

fn field_error(surface: usize, field: &str, message: &str) -> GeomdlError {
    GeomdlError::Field {
        surface,
        field: field.to_string(),
        message: message.to_string(),
    }
}

/// The surfaces of a geomdl JSON document.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GeomdlImport {
    /// Every spline surface, in file order.
    pub surfaces: Vec<BSplineSurface>,
    /// Every entry of `shape.data` not read, and why.
    pub unreadable: Vec<Unreadable>,
}

/// Whether a JSON document's top level is geomdl's (it has `shape`).
pub fn is_geomdl(top: &Map<String, Value>) -> bool {
    top.contains_key("shape")
}

/// Reads the surfaces of a geomdl document's top-level object; errors name
/// the entry of `shape.data` (`surface k`, from 0) and the field.
pub fn parse_geomdl(top: &Map<String, Value>) -> Result<GeomdlImport, GeomdlError> {
    let layout = |m: &str| GeomdlError::Layout(m.to_string());
    let Some(Value::Object(shape)) = top.get("shape") else {
        return Err(layout("`shape` is not an object"));
    };
    let kind = match shape.get("type") {
        Some(Value::String(t)) => t.as_str(),
        _ => return Err(layout("`shape.type` is missing or not a string")),
    };
    let Some(Value::Array(data)) = shape.get("data") else {
        return Err(layout("`shape.data` is missing or not an array"));
    };
    let mut out = GeomdlImport::default();
    for (k, item) in data.iter().enumerate() {
        let unread = |reason: String| Unreadable {
            entity: format!("geomdl shape.data[{k}]"),
            reason,
            estimated_area: None,
        };
        if kind != "surface" {
            out.unreadable
                .push(unread(format!("a {kind}, not a surface")));
            continue;
        }
        let Value::Object(o) = item else {
            return Err(field_error(k, "", "the surface is not an object"));
        };
        match o.get("type") {
            None | Some(Value::Null) => {}
            Some(Value::String(t)) if t == "spline" => {}
            Some(t) => {
                out.unreadable.push(unread(format!(
                    "a surface of type {t}; only \"spline\" surfaces are read"
                )));
                continue;
            }
        }
        let surface = surface(k, o)?;
        match trims::face_loops(k, o, &surface)? {
            Ok(None) => out.surfaces.push(surface),
            Ok(Some(faces)) => {
                for loops in faces {
                    match surface.clone().with_trims(loops) {
                        Ok(face) => out.surfaces.push(face),
                        Err(e) => out.unreadable.push(unread(format!(
                            "a trimmed surface whose trims make no face: {e}"
                        ))),
                    }
                }
            }
            Err(reason) => out
                .unreadable
                .push(unread(format!("a trimmed surface not read: {reason}"))),
        }
    }
    Ok(out)
}

/// A non-negative integer field.
fn count(k: usize, o: &Map<String, Value>, name: &str) -> Result<usize, GeomdlError> {
    o.get(name)
        .ok_or_else(|| field_error(k, name, "missing"))?
        .as_u64()
        .and_then(|d| usize::try_from(d).ok())
        .ok_or_else(|| field_error(k, name, "expected a non-negative integer"))
}

/// An array of numbers.
fn numbers(k: usize, name: &str, v: Option<&Value>) -> Result<Vec<f64>, GeomdlError> {
    let Some(Value::Array(a)) = v else {
        return Err(field_error(k, name, "missing or not an array of numbers"));
    };
    a.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64()
                .ok_or_else(|| field_error(k, &format!("{name}[{i}]"), "expected a number"))
        })
        .collect()
}

/// One `"spline"` surface entry.
fn surface(k: usize, o: &Map<String, Value>) -> Result<BSplineSurface, GeomdlError> {
    let degree_u = count(k, o, "degree_u")?;
    let degree_v = count(k, o, "degree_v")?;
    let size_u = count(k, o, "size_u")?;
    let size_v = count(k, o, "size_v")?;
    let knots_u = numbers(k, "knotvector_u", o.get("knotvector_u"))?;
    let knots_v = numbers(k, "knotvector_v", o.get("knotvector_v"))?;
    let Some(Value::Object(cp)) = o.get("control_points") else {
        return Err(field_error(
            k,
            "control_points",
            "missing or not an object with `points`",
        ));
    };
    let Some(Value::Array(pts)) = cp.get("points") else {
        return Err(field_error(
            k,
            "control_points.points",
            "missing or not an array of points",
        ));
    };
    if size_u.checked_mul(size_v) != Some(pts.len()) {
        return Err(field_error(
            k,
            "control_points.points",
            &format!(
                "{} points, size_u × size_v = {size_u} × {size_v} expected",
                pts.len()
            ),
        ));
    }
    let dimension = match o.get("dimension") {
        None | Some(Value::Null) => 3,
        Some(_) => count(k, o, "dimension")?,
    };
    if dimension != 2 && dimension != 3 {
        return Err(field_error(
            k,
            "dimension",
            &format!("{dimension}; only 2 and 3 are read"),
        ));
    }
    let mut points = Vec::with_capacity(pts.len());
    for (i, p) in pts.iter().enumerate() {
        let name = format!("control_points.points[{i}]");
        let c = numbers(k, &name, Some(p))?;
        if c.len() != dimension {
            return Err(field_error(
                k,
                &name,
                &format!("{} coordinates, dimension {dimension}", c.len()),
            ));
        }
        points.push(Vec3::new(c[0], c[1], c.get(2).copied().unwrap_or(0.0)));
    }
    let weights = match cp.get("weights") {
        None | Some(Value::Null) => None,
        w => Some(numbers(k, "control_points.weights", w)?),
    };
    if weights.is_none() && o.get("rational") == Some(&Value::Bool(true)) {
        return Err(field_error(
            k,
            "control_points.weights",
            "missing for a rational surface",
        ));
    }
    BSplineSurface::from_flat(
        degree_u,
        degree_v,
        knots_u,
        knots_v,
        [size_u, size_v],
        points,
        weights,
    )
    .map_err(|source| GeomdlError::Surface { surface: k, source })
}

#[cfg(test)]
mod tests {
    use super::super::surface_json::parse_surface_json_any;

    const BILINEAR: &str = r#"{"type": "spline", "degree_u": 1, "degree_v": 1,
        "knotvector_u": [0, 0, 1, 1], "knotvector_v": [0, 0, 1, 1],
        "size_u": 2, "size_v": 2,
        "control_points": {"points": [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 1]]}}"#;

    /// The bilinear surface with `"trims": {"data": trims}`.
    fn with_trims(trims: &str) -> String {
        BILINEAR.replace(
            "\"size_u\"",
            &format!("\"trims\": {{\"count\": 1, \"data\": {trims}}}, \"size_u\""),
        )
    }

    /// A polyline trim through `points` with geomdl's sense.
    fn polyline(points: &[[f64; 2]], reversed: u8) -> String {
        let pts: Vec<String> = points
            .iter()
            .map(|p| format!("[{}, {}]", p[0], p[1]))
            .collect();
        format!(
            r#"{{"type": "freeform", "points": [{}], "reversed": {reversed}}}"#,
            pts.join(", ")
        )
    }

    fn doc(kind: &str, items: &[&str]) -> String {
        format!(
            r#"{{"shape": {{"type": "{kind}", "count": {}, "data": [{}]}}}}"#,
            items.len(),
            items.join(",")
        )
    }

    #[test]
    fn points_are_u_major() {
        let imp = parse_surface_json_any(&doc("surface", &[BILINEAR])).unwrap();
        let s = &imp.surfaces[0];
        assert_eq!(s.eval(1.0, 0.0).to_array(), [1.0, 0.0, 0.0]);
        assert_eq!(s.eval(0.0, 1.0).to_array(), [0.0, 1.0, 0.0]);
        assert_eq!(s.eval(1.0, 1.0).to_array(), [1.0, 1.0, 1.0]);
    }

    #[test]
    fn shapes_not_read_are_listed() {
        let trimmed = with_trims(r#"[{"type": "analytic"}]"#);
        let freeform = r#"{"type": "freeform", "points": []}"#;
        let imp = parse_surface_json_any(&doc("surface", &[BILINEAR, &trimmed, freeform])).unwrap();
        assert_eq!(imp.surfaces.len(), 1);
        let listed: Vec<String> = imp.unreadable.iter().map(|u| u.to_string()).collect();
        assert_eq!(listed.len(), 2);
        assert!(
            listed[0].contains(
                "shape.data[1]: a trimmed surface not read: trim 0 is of type \"analytic\""
            ),
            "{listed:?}"
        );
        assert!(
            listed[1].contains("shape.data[2]: a surface of type"),
            "{listed:?}"
        );
        let curves = parse_surface_json_any(&doc("curve", &["{}"])).unwrap();
        assert!(
            curves.unreadable[0]
                .reason
                .contains("a curve, not a surface")
        );
        // the strict reader refuses what it cannot read
        let err = super::super::surface_json::parse_surfaces_json(&doc("curve", &["{}"]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("a curve, not a surface"), "{err}");
    }

    #[test]
    fn malformed_entries_name_the_surface_and_field() {
        let cases = [
            (
                BILINEAR.replace("\"size_u\": 2", "\"size_u\": 3"),
                "surface 0: field `control_points.points`: 4 points, size_u × size_v = 3 × 2 expected",
            ),
            (
                BILINEAR.replace(
                    "[0, 0, 1, 1], \"knotvector_v\"",
                    "[0, 0, 1], \"knotvector_v\"",
                ),
                "surface 0:",
            ),
            (
                BILINEAR.replace("[1, 1, 1]", "[1, 1]"),
                "field `control_points.points[3]`: 2 coordinates, dimension 3",
            ),
            (
                BILINEAR.replace("\"degree_u\": 1", "\"degree_u\": -1"),
                "field `degree_u`",
            ),
            (
                BILINEAR.replace(
                    "\"type\": \"spline\",",
                    "\"type\": \"spline\", \"rational\": true,",
                ),
                "field `control_points.weights`: missing",
            ),
            (
                BILINEAR.replace("]]}", "]], \"weights\": [1, 1, 1, -1]}"),
                "surface 0:",
            ),
            (
                BILINEAR.replace("\"size_u\": 2", "\"size_u\": 18446744073709551615"),
                "size_u × size_v",
            ),
        ];
        for (item, want) in &cases {
            let err = parse_surface_json_any(&doc("surface", &[item]))
                .unwrap_err()
                .to_string();
            assert!(err.contains(want), "{item}: {err}");
        }
        for bad in [
            r#"{"shape": 1}"#,
            r#"{"shape": {"type": "surface"}}"#,
            r#"{"shape": {"data": []}}"#,
        ] {
            let err = parse_surface_json_any(bad).unwrap_err().to_string();
            assert!(err.contains("geomdl JSON"), "{bad}: {err}");
        }
        let err = parse_surface_json_any(r#"{"nothing": 1}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("`shape` (geomdl JSON)"), "{err}");
    }

    #[test]
    fn trims_are_fractions_of_the_knot_range() {
        // knots [0, 0, 10, 10] in u: geomdl reads the trim's 0.5 as u = 5
        let surface = with_trims(&format!(
            "[{}]",
            polyline(
                &[
                    [0.25, 0.25],
                    [0.75, 0.25],
                    [0.75, 0.75],
                    [0.25, 0.75],
                    [0.25, 0.25]
                ],
                0
            )
        ))
        .replace(
            "\"knotvector_u\": [0, 0, 1, 1]",
            "\"knotvector_u\": [0, 0, 10, 10]",
        );
        let imp = parse_surface_json_any(&doc("surface", &[&surface])).unwrap();
        let trim = imp.surfaces[0].trim().unwrap();
        assert_eq!(trim.loops().len(), 2, "the domain and one hole");
        assert!(trim.contains(1.0, 0.5) && !trim.contains(5.0, 0.5));
        assert!((trim.parameter_area() - (10.0 - 2.5)).abs() < 1e-12);
    }

    #[test]
    fn trims_that_make_no_face_are_listed() {
        let square = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8], [0.2, 0.2]];
        let open = with_trims(&format!("[{}]", polyline(&square[..4], 0)));
        let nested = with_trims(&format!(
            "[{}, {}]",
            polyline(&square, 1),
            polyline(&[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.4]], 1)
        ));
        let imp = parse_surface_json_any(&doc("surface", &[&open, &nested, BILINEAR])).unwrap();
        assert_eq!(imp.surfaces.len(), 1);
        let listed: Vec<String> = imp.unreadable.iter().map(|u| u.to_string()).collect();
        assert!(
            listed[0].contains("shape.data[0]") && listed[0].contains("trim 0 does not close"),
            "{listed:?}"
        );
        assert!(
            listed[1].contains("shape.data[1]") && listed[1].contains("overlap"),
            "{listed:?}"
        );
    }

    #[test]
    fn malformed_trims_name_the_field() {
        let cases = [
            (
                r#"[{"type": "freeform", "points": [[0, 0, 1], [1, 1, 1]]}]"#,
                "field `trims.data[0].points[0]`: 3 coordinates",
            ),
            (
                r#"[{"type": "freeform", "points": [[0, 0]]}]"#,
                "field `trims.data[0].points`: 1 points",
            ),
            (
                r#"[{"type": "spline", "degree": 1, "knotvector": [0, 1], "control_points": {"points": [[0, 0], [1, 1]]}}]"#,
                "field `trims.data[0]`: 2 knots",
            ),
            (r#"[{"type": "container"}]"#, "field `trims.data[0].data`"),
            (
                r#"[{"type": "freeform", "points": [[0, 0], [1, 0], [0, 0]], "reversed": 2}]"#,
                "field `trims.data[0].reversed`",
            ),
            (r#"[3]"#, "field `trims.data[0]`: not an object"),
        ];
        for (trims, want) in cases {
            let err = parse_surface_json_any(&doc("surface", &[&with_trims(trims)]))
                .unwrap_err()
                .to_string();
            assert!(err.contains(want), "{trims}: {err}");
        }
    }
}
