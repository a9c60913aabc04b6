//! geomdl's trim curves (`"trims"` of a surface entry) as trimming loops.
//!
//! geomdl 5 (`_exchange.import_dict_surf`, `tessellate.TrimTessellate`,
//! `trimming`): `"trims": {"count": n, "data": [trim, …]}`, each trim a
//! closed curve in the surface's parameter plane, of type
//!
//! - `"spline"`: `degree`, `knotvector`, `control_points.points` (Cartesian
//!   `[u, v]`) and optional `control_points.weights`;
//! - `"freeform"`: `points`, a polyline;
//! - `"container"`: `data`, a list of `"spline"` and `"freeform"` curves
//!   joined end to start;
//!
//! with an optional sense `"reversed"`: 0 (geomdl's default) trims the area
//! the curve encloses away — a hole — and 1 keeps it — an outer boundary.
//! The face is the union of the kept areas (the whole domain where no trim
//! is reversed) less the holes.
//!
//! geomdl normalises every knot vector to `[0, 1]` when it reads a file, so
//! a trim's coordinates are fractions of the surface's knot range:
//! `u = k₀ + t·(k_last − k₀)`. The map is affine, so the trim's control
//! points are mapped and its weights kept.

use serde_json::{Map, Value};

use super::{GeomdlError, count, field_error, numbers};
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop, winding_number};

/// Largest gap between consecutive curves of a trim, and between a trim's
/// end and its start, as a fraction of the parameter domain's diagonal
/// (geomdl's own tolerance is 1e-7 in its normalised domain).
const CLOSURE: f64 = 1e-6;

/// The loops of each face a trimmed surface entry makes (outer first, then
/// holes), `None` where the entry has no trims.
pub(super) type FaceLoops = Option<Vec<Vec<TrimLoop>>>;

/// One trim: its curves in order and whether its inside is kept.
struct Trim {
    curves: Vec<TrimCurve>,
    keeps_inside: bool,
}

/// The trimming loops of the faces a surface entry stands for: one list of
/// loops (outer first, then holes) per face, or `Ok(None)` where the entry
/// has no trims. Malformed fields are errors naming the field
/// (`trims.data[i]…`); trims that are well formed but do not make faces
/// (a curve that does not close, kept areas that overlap, a curve type
/// geomdl does not define) give `Err` with the reason in the outer
/// `Ok`, and the entry is listed as not read.
pub(super) fn face_loops(
    k: usize,
    o: &Map<String, Value>,
    surface: &BSplineSurface,
) -> Result<Result<FaceLoops, String>, GeomdlError> {
    let data = match o.get("trims") {
        None | Some(Value::Null) => return Ok(Ok(None)),
        Some(Value::Object(t)) => match t.get("data") {
            Some(Value::Array(d)) => d,
            None | Some(Value::Null) => return Ok(Ok(None)),
            Some(_) => return Err(field_error(k, "trims.data", "not an array of curves")),
        },
        Some(_) => return Err(field_error(k, "trims", "not an object with `data`")),
    };
    if data.is_empty() {
        return Ok(Ok(None));
    }
    let (u, v) = (surface.domain_u(), surface.domain_v());
    let ku = knot_range(surface.knots_u());
    let kv = knot_range(surface.knots_v());
    let to_domain = |p: [f64; 2]| {
        [
            ku[0] + p[0] * (ku[1] - ku[0]),
            kv[0] + p[1] * (kv[1] - kv[0]),
        ]
    };
    let diag = (u[1] - u[0]).hypot(v[1] - v[0]);
    let mut trims = Vec::with_capacity(data.len());
    for (i, t) in data.iter().enumerate() {
        let name = format!("trims.data[{i}]");
        let Value::Object(t) = t else {
            return Err(field_error(k, &name, "not an object"));
        };
        let kind = match t.get("type") {
            Some(Value::String(s)) => s.as_str(),
            _ => {
                return Err(field_error(
                    k,
                    &format!("{name}.type"),
                    "missing or not a string",
                ));
            }
        };
        let mut curves = Vec::new();
        match kind {
            "spline" | "freeform" => curves.push(curve(k, &name, kind, t, &to_domain)?),
            "container" => {
                let Some(Value::Array(parts)) = t.get("data") else {
                    return Err(field_error(
                        k,
                        &format!("{name}.data"),
                        "missing or not an array of curves",
                    ));
                };
                for (j, c) in parts.iter().enumerate() {
                    let cname = format!("{name}.data[{j}]");
                    let Value::Object(c) = c else {
                        return Err(field_error(k, &cname, "not an object"));
                    };
                    match c.get("type") {
                        Some(Value::String(s)) if s == "spline" || s == "freeform" => {
                            curves.push(curve(k, &cname, s, c, &to_domain)?);
                        }
                        _ => {
                            return Ok(Err(format!(
                                "trim {i} curve {j} is neither a \"spline\" nor a \"freeform\" curve"
                            )));
                        }
                    }
                }
                if curves.is_empty() {
                    return Ok(Err(format!("trim {i} is an empty container")));
                }
            }
            other => {
                return Ok(Err(format!(
                    "trim {i} is of type \"{other}\"; geomdl's trims are \"spline\", \"freeform\" or \"container\""
                )));
            }
        }
        let keeps_inside = match t.get("reversed") {
            None | Some(Value::Null) => false,
            Some(Value::Bool(b)) => *b,
            Some(x) => match x.as_f64() {
                Some(0.0) => false,
                Some(1.0) => true,
                _ => {
                    return Err(field_error(
                        k,
                        &format!("{name}.reversed"),
                        "expected 0, 1, true or false",
                    ));
                }
            },
        };
        let curves = match chain(curves, CLOSURE * diag) {
            Ok(c) => c,
            Err(gap) => {
                return Ok(Err(format!(
                    "trim {i} does not close: {gap}, more than {CLOSURE:e} of the parameter domain's diagonal"
                )));
            }
        };
        trims.push(Trim {
            curves,
            keeps_inside,
        });
    }
    Ok(faces(trims, u, v))
}

/// `[first, last]` knot: the range geomdl normalises to `[0, 1]`.
fn knot_range(knots: &[f64]) -> [f64; 2] {
    match (knots.first(), knots.last()) {
        (Some(&a), Some(&b)) => [a, b],
        _ => [0.0, 1.0],
    }
}

/// One `"spline"` or `"freeform"` trim curve, mapped to the surface's
/// parameter domain.
fn curve(
    k: usize,
    name: &str,
    kind: &str,
    c: &Map<String, Value>,
    to_domain: &dyn Fn([f64; 2]) -> [f64; 2],
) -> Result<TrimCurve, GeomdlError> {
    let (points_field, points) = if kind == "freeform" {
        (format!("{name}.points"), c.get("points"))
    } else {
        let Some(Value::Object(cp)) = c.get("control_points") else {
            return Err(field_error(
                k,
                &format!("{name}.control_points"),
                "missing or not an object with `points`",
            ));
        };
        (format!("{name}.control_points.points"), cp.get("points"))
    };
    let Some(Value::Array(points)) = points else {
        return Err(field_error(
            k,
            &points_field,
            "missing or not an array of points",
        ));
    };
    let mut uv = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let pname = format!("{points_field}[{i}]");
        let x = numbers(k, &pname, Some(p))?;
        match x.as_slice() {
            [a, b] => uv.push(to_domain([*a, *b])),
            [a, b, z] if *z == 0.0 => uv.push(to_domain([*a, *b])),
            _ => {
                return Err(field_error(
                    k,
                    &pname,
                    &format!(
                        "{} coordinates; a trim curve lies in the parameter plane ([u, v], or [u, v, 0])",
                        x.len()
                    ),
                ));
            }
        }
    }
    let made = if kind == "freeform" {
        let n = uv.len();
        if n < 2 {
            return Err(field_error(
                k,
                &points_field,
                &format!("{n} points; a polyline needs at least 2"),
            ));
        }
        // A polyline: degree 1, one knot per point, ends repeated.
        let knots = std::iter::once(0.0)
            .chain((0..n).map(|i| i as f64))
            .chain(std::iter::once((n - 1) as f64))
            .collect();
        TrimCurve::new(1, knots, uv, None)
    } else {
        let degree = count(k, c, "degree").map_err(|_| {
            field_error(
                k,
                &format!("{name}.degree"),
                "expected a non-negative integer",
            )
        })?;
        let knots = numbers(k, &format!("{name}.knotvector"), c.get("knotvector"))?;
        let weights = match c.get("control_points").and_then(|cp| cp.get("weights")) {
            None | Some(Value::Null) => None,
            w => Some(numbers(k, &format!("{name}.control_points.weights"), w)?),
        };
        TrimCurve::new(degree, knots, uv, weights)
    };
    made.map_err(|message| field_error(k, name, &message))
}

/// The curves of one trim joined end to start: a curve whose end, not its
/// start, meets the previous curve's end is traversed backwards (as
/// geomdl's `trimming.fix_multi_trim_curves` does). Fails with the gap
/// where two curves do not meet or the last does not return to the first.
fn chain(mut curves: Vec<TrimCurve>, tolerance: f64) -> Result<Vec<TrimCurve>, String> {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let start = |c: &TrimCurve| c.eval(c.domain()[0]);
    let end = |c: &TrimCurve| c.eval(c.domain()[1]);
    if curves.len() > 1 {
        // The first curve runs towards the second.
        let (s0, e0) = (start(&curves[0]), end(&curves[0]));
        let (s1, e1) = (start(&curves[1]), end(&curves[1]));
        if dist(s0, s1).min(dist(s0, e1)) < dist(e0, s1).min(dist(e0, e1)) {
            curves[0] = curves[0].reversed()?;
        }
        for j in 1..curves.len() {
            let at = end(&curves[j - 1]);
            if dist(end(&curves[j]), at) < dist(start(&curves[j]), at) {
                curves[j] = curves[j].reversed()?;
            }
            let gap = dist(start(&curves[j]), at);
            if gap > tolerance {
                return Err(format!(
                    "curve {j} starts {gap:.3e} from the end of curve {}",
                    j - 1
                ));
            }
        }
    }
    let (Some(first), Some(last)) = (curves.first(), curves.last()) else {
        return Err("no curves".into());
    };
    let gap = dist(start(first), end(last));
    if gap > tolerance {
        return Err(format!("its ends are {gap:.3e} apart"));
    }
    Ok(curves)
}

/// The faces the trims make on the domain `u × v`: one per kept area (the
/// whole domain where none is kept), each with the holes whose curves lie
/// inside it. Kept areas inside one another are refused: geomdl keeps
/// their union, which is not a face of one outer loop.
fn faces(trims: Vec<Trim>, u: [f64; 2], v: [f64; 2]) -> Result<FaceLoops, String> {
    let probe = |t: &Trim| t.curves[0].eval(t.curves[0].domain()[0]);
    let polygon = |t: &Trim| {
        let mut p = Vec::new();
        for c in &t.curves {
            c.flatten_into(1e-9 * (u[1] - u[0]).hypot(v[1] - v[0]), &mut p);
        }
        p
    };
    let (outers, holes): (Vec<Trim>, Vec<Trim>) = trims.into_iter().partition(|t| t.keeps_inside);
    let outer_loops: Vec<(Vec<[f64; 2]>, TrimLoop)> = if outers.is_empty() {
        let corners = [[u[0], v[0]], [u[1], v[0]], [u[1], v[1]], [u[0], v[1]]];
        vec![(corners.to_vec(), TrimLoop::polygon(&corners)?)]
    } else {
        outers
            .into_iter()
            .map(|t| (polygon(&t), TrimLoop { curves: t.curves }))
            .collect()
    };
    for (a, (poly_a, _)) in outer_loops.iter().enumerate() {
        for (b, (_, loop_b)) in outer_loops.iter().enumerate() {
            let c = &loop_b.curves[0];
            if a != b && winding_number(poly_a, c.eval(c.domain()[0])) != 0 {
                return Err(format!(
                    "the kept areas of two reversed trims overlap (trim {b}'s curve starts inside trim {a}'s)"
                ));
            }
        }
    }
    let hole_probes: Vec<[f64; 2]> = holes.iter().map(probe).collect();
    let mut holes: Vec<Option<TrimLoop>> = holes
        .into_iter()
        .map(|t| Some(TrimLoop { curves: t.curves }))
        .collect();
    let mut out = Vec::with_capacity(outer_loops.len());
    for (poly, outer) in outer_loops {
        let mut loops = vec![outer];
        for (h, p) in holes.iter_mut().zip(&hole_probes) {
            if winding_number(&poly, *p) != 0
                && let Some(hole) = h.take()
            {
                loops.push(hole);
            }
        }
        out.push(loops);
    }
    Ok(Some(out))
}
