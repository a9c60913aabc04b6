//! Highlight lines as B-spline curves for CAD systems (`highlight -o
//! LINES.igs`, the workbench's "lines as curves", Python's
//! `fairline.highlight_curves`): each line fitted by a cubic B-spline
//! within a tolerance ([`fairline::io::curve_fit::fit_polyline`]) and
//! named for the light it belongs to, ready for an IGES file of entities
//! 126 ([`fairline::io::iges_write::curves_to_iges`]).
//!
//! Names: a line of a mesh under light `m` is `HLm` (its subscript counts
//! the pieces of that light's line); a line of patch `k` of a surface
//! file under its light `j` is `PkLj` (circular lights: `j` the radius'
//! index). Band boundaries are not written.

use fairline::Vec3;
use fairline::bspline::BSplineSurface;
use fairline::highlight::HighlightLines;
use fairline::highlight::surface::PatchHighlights;
use fairline::io::curve_fit::fit_polyline;
use fairline::io::iges_write::NamedCurve;
use serde_json::json;
use std::collections::HashMap;

/// The tolerance used when none is given: 1e-4 of the part's bounding-box
/// diagonal (0.1 mm on a part of one metre).
pub const DEFAULT_RELATIVE_TOLERANCE: f64 = 1e-4;

/// One polyline to be written as a curve.
#[derive(Clone, Debug)]
pub struct LinePolyline<'a> {
    /// The label (at most 8 characters).
    pub label: String,
    /// The points in order.
    pub points: &'a [Vec3],
    /// Whether the last point joins the first.
    pub closed: bool,
}

/// The curves and what fitting them gave.
#[derive(Clone, Debug)]
pub struct CurvesOutcome {
    /// The named curves, in the order of the lines.
    pub curves: Vec<NamedCurve>,
    /// `curves`, `points` (of the polylines), `control_points`,
    /// `tolerance`, `max_deviation`, `polylines` (lines kept as degree-1
    /// curves because no cubic within the tolerance was shorter) and
    /// `left_out` (lines of fewer than two distinct points): the report's
    /// `curves` key.
    pub summary: serde_json::Value,
}

/// The polylines of a mesh's highlight lines, named `HLm`.
pub fn mesh_lines(lines: &HighlightLines) -> Vec<LinePolyline<'_>> {
    lines
        .lines
        .iter()
        .map(|l| LinePolyline {
            label: format!("HL{}", l.index),
            points: &l.points,
            closed: l.closed,
        })
        .collect()
}

/// The polylines of surface highlight lines (level 0 only), named `PkLj`.
pub fn surface_lines(results: &[(usize, PatchHighlights)]) -> Vec<LinePolyline<'_>> {
    results
        .iter()
        .flat_map(|(k, patch)| {
            patch
                .highlights
                .lines
                .iter()
                .filter(|l| l.level == 0.0)
                .map(move |l| LinePolyline {
                    label: format!("P{k}L{}", l.light),
                    points: &l.points,
                    closed: l.closed,
                })
        })
        .collect()
}

/// The share of a mesh's mean edge length below which its lines are not
/// followed: a mesh's highlight line bends at every edge it crosses, by an
/// amount of the order of the mesh's own accuracy, not of the surface.
pub const MESH_EDGE_SHARE: f64 = 0.1;

/// The tolerance for a part of bounding-box diagonal `diagonal`: `given`
/// when it is a positive number, else [`DEFAULT_RELATIVE_TOLERANCE`] of the
/// diagonal.
pub fn tolerance(given: Option<f64>, diagonal: f64) -> f64 {
    match given {
        Some(t) if t.is_finite() && t > 0.0 => t,
        _ => DEFAULT_RELATIVE_TOLERANCE * diagonal.max(0.0),
    }
}

/// The bounding-box diagonal of the faces of `surfaces` (trimmed geometry,
/// [`fairline::bspline::face_bounding_box`]; the control net's box where a
/// face has none); 0 for no surface.
pub fn surfaces_diagonal(surfaces: &[BSplineSurface]) -> f64 {
    let mut lo = Vec3::splat(f64::INFINITY);
    let mut hi = Vec3::splat(f64::NEG_INFINITY);
    for s in surfaces {
        let (a, b) =
            fairline::bspline::face_bounding_box(s).unwrap_or_else(|| s.control_bounding_box());
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let d = (hi - lo).length();
    if d.is_finite() { d } else { 0.0 }
}

/// The tolerance for the lines of surfaces: `given`, else
/// [`DEFAULT_RELATIVE_TOLERANCE`] of the part's diagonal
/// ([`surfaces_diagonal`]).
pub fn surface_tolerance(given: Option<f64>, surfaces: &[BSplineSurface]) -> f64 {
    match given {
        Some(t) if t.is_finite() && t > 0.0 => t,
        _ => tolerance(None, surfaces_diagonal(surfaces)),
    }
}

/// The tolerance for the lines of a triangle mesh: `given`, else the larger
/// of [`tolerance`]'s default and [`MESH_EDGE_SHARE`] of the mean edge
/// length.
pub fn mesh_tolerance(given: Option<f64>, mesh: &fairline::SurfaceMesh) -> f64 {
    let diagonal =
        fairline::mesh::bounding_box(mesh.positions()).map_or(0.0, |(lo, hi)| (hi - lo).length());
    let edge = fairline::geom::mean_edge_length(mesh);
    match given {
        Some(t) if t.is_finite() && t > 0.0 => t,
        _ => tolerance(None, diagonal).max(if edge.is_finite() {
            MESH_EDGE_SHARE * edge
        } else {
            0.0
        }),
    }
}

/// Fits every line within `tolerance` (module documentation); lines of
/// fewer than two distinct points are left out and counted.
pub fn fit(lines: &[LinePolyline<'_>], tolerance: f64) -> CurvesOutcome {
    let mut curves = Vec::with_capacity(lines.len());
    let mut pieces: HashMap<&str, usize> = HashMap::new();
    let (mut points, mut control, mut polylines, mut skipped) = (0, 0, 0, 0);
    let mut worst = 0.0_f64;
    for l in lines {
        points += l.points.len();
        let Some(f) = fit_polyline(l.points, l.closed, tolerance) else {
            skipped += 1;
            continue;
        };
        let n = pieces.entry(l.label.as_str()).or_insert(0);
        *n += 1;
        control += f.curve.points.len();
        polylines += usize::from(f.curve.degree == 1 && f.curve.points.len() > 2);
        worst = worst.max(f.max_deviation);
        curves.push(NamedCurve {
            curve: f.curve,
            label: l.label.clone(),
            number: *n,
        });
    }
    let summary = json!({
        "curves": curves.len(),
        "points": points,
        "control_points": control,
        "tolerance": tolerance,
        "max_deviation": worst,
        "polylines": polylines,
        "left_out": skipped,
    });
    CurvesOutcome { curves, summary }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_fitted_named_and_counted() {
        let circle: Vec<Vec3> = (0..400)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / 400.0;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let dot = [Vec3::ONE];
        let lines = [
            LinePolyline {
                label: "HL3".into(),
                points: &circle,
                closed: true,
            },
            LinePolyline {
                label: "HL3".into(),
                points: &circle[..100],
                closed: false,
            },
            LinePolyline {
                label: "HL4".into(),
                points: &dot,
                closed: false,
            },
        ];
        let out = fit(&lines, tolerance(None, 2.0));
        assert_eq!(out.curves.len(), 2);
        assert_eq!(
            (out.curves[0].number, out.curves[1].number),
            (1, 2),
            "two pieces of light 3"
        );
        let r = &out.summary;
        assert_eq!(r["left_out"], 1);
        assert_eq!(r["tolerance"], 2e-4);
        assert!(r["max_deviation"].as_f64().unwrap() <= 2e-4);
        assert!(r["control_points"].as_u64().unwrap() < 100);
        assert_eq!(tolerance(Some(0.5), 2.0), 0.5);
        assert_eq!(tolerance(Some(-1.0), 2.0), 2e-4);
    }
}
