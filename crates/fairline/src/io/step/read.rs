//! STEP geometry to trimmed B-spline surfaces (ISO 10303-42 geometry and
//! topology, as used by AP203, AP214 and AP242).
//!
//! Every `ADVANCED_FACE` (and `FACE_SURFACE`) becomes one surface:
//!
//! - `B_SPLINE_SURFACE_WITH_KNOTS` (rational: the complex instance with
//!   `RATIONAL_B_SPLINE_SURFACE`) is taken as it is. Its bounds become
//!   trimming loops from the edges' `PCURVE`s on this surface when present
//!   (a `DEFINITIONAL_REPRESENTATION` of a `LINE`, `CIRCLE`, `ELLIPSE` or
//!   B-spline curve in (u, v): lines, conic arcs and B-spline pieces
//!   exactly, see [`pcurve`]) that agree with the 3-D edge, otherwise from
//!   the edge curves sampled and projected onto the surface by Newton point
//!   inversion (Piegl & Tiller §6.1).
//! - `PLANE`, `CYLINDRICAL_SURFACE`, `CONICAL_SURFACE`, `SPHERICAL_SURFACE`,
//!   `TOROIDAL_SURFACE`, `SURFACE_OF_REVOLUTION` and
//!   `SURFACE_OF_LINEAR_EXTRUSION` are converted exactly to NURBS over the
//!   part of the surface the face's edges span (rational quadratic arcs of
//!   at most 90°, see [`super::nurbs`] and [`analytic`]). Their bounds are
//!   mapped into the NURBS parameters through the surface's natural
//!   coordinates (ISO 10303-42's (u, v): angles through [`ArcMap::param`]).
//!   An edge with a p-curve on the face's surface that agrees with its 3-D
//!   edge gets the p-curve mapped through that reparametrisation ([`pcurve`]:
//!   exact where the map is affine in the coordinates the p-curve varies in
//!   — any p-curve on a plane or an extrusion, lines along parameter lines
//!   of the others — else a dense polyline); otherwise the exact 3-D edge is
//!   used: exactly as rational curves on planes and as dense polylines
//!   through its natural coordinates on the other surfaces. A p-curve that
//!   disagrees with its edge is not used (counted in
//!   [`StepImport::trim_sources`] and named in a warning). Faces bounded
//!   without a seam edge — a
//!   cylinder between two full circles, a sphere cap or a cone bounded by
//!   one circle — are closed along a cut (and through the pole or apex on
//!   the face's side); their bounds come from the p-curves too when every
//!   edge has one that agrees, the face has no hole and every winding
//!   bound has a vertex on the cut (which then starts the NURBS's periodic
//!   coordinate, so that no p-curve crosses it), else from the 3-D edges;
//!   a sphere or torus face without loops is the whole surface.
//!
//! Orientation (ISO 10303-42 face, face_bound, oriented_edge): an
//! `ORIENTED_EDGE` with orientation `.F.` runs its `EDGE_CURVE` backwards,
//! an `EDGE_CURVE` with `same_sense .F.` runs against its curve, a
//! `FACE_BOUND` with orientation `.F.` reverses its loop; the face lies on
//! the side `n × t` of each loop (`t` its direction, `n` the face normal:
//! the surface normal, reversed when the face's `same_sense` is `.F.`).
//! Where the side matters — a face bounded by one loop winding around a
//! sphere or cone — it decides which part is the face; elsewhere loops are
//! taken by their winding numbers, whatever their orientation.
//!
//! Bounded B-spline surfaces that belong to no face (items of a
//! representation or a geometric set) are read untrimmed. Edge curves may
//! be `LINE`, `CIRCLE`, `ELLIPSE`, `B_SPLINE_CURVE_WITH_KNOTS` (rational
//! too), or a `SURFACE_CURVE`/`SEAM_CURVE` over one of them. Anything else
//! is refused with an error naming the entity `#id`. Coordinates stay in the
//! file's length unit, which is reported.

use std::collections::HashSet;
use std::f64::consts::{PI, TAU};

use super::StepError;
use super::nurbs::{ArcMap, Nurbs3, ellipse_arc};
use super::p21::{Exchange, Instance, Value};
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve};
use crate::io::units::LengthUnit;
use units::{collect_refs, distance_uncertainty};

/// One surface read from a STEP file.
#[derive(Clone, Debug, PartialEq)]
pub struct StepSurface {
    /// The surface, trimmed by its face's bounds.
    pub surface: BSplineSurface,
    /// `#id` of the face (or of the surface itself when it is in no face).
    pub entity: u64,
    /// `#id` of the underlying surface entity.
    pub surface_entity: u64,
    /// Its STEP type (`PLANE`, `B_SPLINE_SURFACE_WITH_KNOTS`, …).
    pub surface_type: String,
    /// The face's `same_sense`: false when the face's normal is opposite
    /// to the surface's `Su × Sv`.
    pub same_sense: bool,
}

/// The result of [`super::read_step`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepImport {
    /// Faces and free surfaces, in the order of their `#id`.
    pub surfaces: Vec<StepSurface>,
    /// The length unit of the file (first `LENGTH_UNIT`), if it names one.
    pub unit: Option<LengthUnit>,
    /// Where the faces' trimming curves came from, counted per edge of
    /// every face bound.
    pub trim_sources: TrimSources,
    /// What the reader did not take as the file says (p-curves that
    /// disagree with their 3-D edges); one line each.
    pub warnings: Vec<String>,
    /// The faces that could not be read (only when reading with
    /// `collect`, see [`super::read_step_with`]); none of them is in
    /// [`Self::surfaces`].
    pub unreadable: Vec<crate::io::unreadable::Unreadable>,
}

/// Where the trimming curves of a file's faces came from, counted per
/// oriented edge of the face bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct TrimSources {
    /// From the edge's p-curve on the face's surface (it agrees with the
    /// 3-D edge).
    pub pcurve: usize,
    /// From the 3-D edge: the edge has no p-curve on the face's surface,
    /// or the face is the whole converted surface, or the face's bounds
    /// wind around its surface and cannot all be taken from p-curves (a
    /// hole, a winding bound without a vertex on the cut, an edge without
    /// an agreeing p-curve).
    pub edge: usize,
    /// From the 3-D edge because its p-curves disagree with it by more
    /// than the tolerance (each named in [`StepImport::warnings`]).
    pub pcurve_rejected: usize,
}

mod analytic;
mod curves;
mod edges;
mod faces;
mod params;
mod pcurve;
mod units;

type R<T> = Result<T, StepError>;

struct Reader<'a> {
    ex: &'a Exchange,
    /// Radians per angle unit of the file.
    angle: f64,
    /// The file's distance uncertainty (0 when it states none).
    uncertainty: f64,
    /// Counts of [`StepImport::trim_sources`].
    sources: std::cell::Cell<TrimSources>,
    /// P-curves not used: (EDGE_CURVE #id, distance, tolerance).
    rejected: std::cell::RefCell<Vec<(u64, f64, f64)>>,
    /// Offset surfaces read as fitted B-splines, one warning each.
    fitted: std::cell::RefCell<Vec<String>>,
}

/// Reads the faces (and free bounded B-spline surfaces) of a parsed file.
pub(super) fn read(ex: &Exchange, collect: bool) -> R<StepImport> {
    let (unit, angle) = units::units(ex);
    let rd = Reader {
        ex,
        angle,
        uncertainty: distance_uncertainty(ex),
        sources: Default::default(),
        rejected: Default::default(),
        fitted: Default::default(),
    };
    let mut out = StepImport {
        unit,
        ..StepImport::default()
    };
    // Who refers to whom: surfaces referred to only by representations and
    // sets are free (not a face's, a p-curve's or a swept surface's basis).
    let mut bound_elsewhere: HashSet<u64> = HashSet::new();
    for i in ex.instances.values() {
        let container = i
            .parts
            .iter()
            .all(|(n, _)| n.contains("REPRESENTATION") || n.ends_with("SET"));
        if !container {
            for (_, p) in &i.parts {
                collect_refs(p, &mut bound_elsewhere);
            }
        }
    }
    let mut ids: Vec<u64> = ex.order.clone();
    ids.sort_unstable();
    for id in ids {
        let i = &ex.instances[&id];
        match i.type_name() {
            "ADVANCED_FACE" | "FACE_SURFACE" => match rd.face(i) {
                Ok(s) => out.surfaces.push(s),
                Err(e) if collect => out.unreadable.push(crate::io::unreadable::Unreadable {
                    entity: format!("#{id} {}", i.type_name()),
                    reason: e.to_string(),
                    estimated_area: None,
                }),
                Err(e) => return Err(e),
            },
            _ if i.is("B_SPLINE_SURFACE_WITH_KNOTS") && !bound_elsewhere.contains(&id) => {
                out.surfaces.push(StepSurface {
                    surface: rd.bspline_surface(i)?,
                    entity: id,
                    surface_entity: id,
                    surface_type: "B_SPLINE_SURFACE_WITH_KNOTS".into(),
                    same_sense: true,
                });
            }
            _ => {}
        }
    }
    out.trim_sources = rd.sources.get();
    out.warnings = rd.rejected_warning().into_iter().collect();
    out.warnings.extend(rd.fitted.take());
    Ok(out)
}

impl Reader<'_> {
    /// One warning naming the edges whose p-curves were not used.
    fn rejected_warning(&self) -> Option<String> {
        let r = self.rejected.borrow();
        let worst = r
            .iter()
            .max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))?;
        let ids: Vec<String> = r.iter().take(8).map(|x| format!("#{}", x.0)).collect();
        let largest = if worst.1.is_finite() {
            format!("{:.3e}", worst.1)
        } else {
            "off the surface's range".into()
        };
        Some(format!(
            "{} p-curve(s) disagree with their 3-D edges by more than the tolerance (EDGE_CURVE {}{}; largest {largest} at #{}, tolerance {:.1e}); those trims were computed from the 3-D edges",
            r.len(),
            ids.join(", "),
            if r.len() > ids.len() { ", …" } else { "" },
            worst.0,
            worst.2
        ))
    }
}

/// A degree-1 trim curve through `pts` (chord-length-free uniform knots).
pub(crate) fn polyline(pts: &[[f64; 2]]) -> Result<TrimCurve, String> {
    let mut p: Vec<[f64; 2]> = Vec::with_capacity(pts.len());
    for q in pts {
        if p.last() != Some(q) {
            p.push(*q);
        }
    }
    if p.len() < 2 {
        return Err("the edge has no length in the surface's parameters".into());
    }
    let n = p.len();
    let mut knots = vec![0.0];
    knots.extend((0..n).map(|k| k as f64 / (n - 1) as f64));
    knots.push(1.0);
    TrimCurve::new(1, knots, p, None)
}

/// The parameters of the point of `s` nearest to `q`: a grid search (or the
/// given guess), then Newton iterations on `Su·(S − q) = Sv·(S − q) = 0`
/// (Piegl & Tiller §6.1), clamped to the domain; a grid search again when
/// the guess leads astray.
pub(crate) fn invert_point(s: &BSplineSurface, q: Vec3, guess: Option<(f64, f64)>) -> (f64, f64) {
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    let grid = || {
        let n = 24;
        let mut best = (f64::INFINITY, (u0, v0));
        for i in 0..=n {
            for j in 0..=n {
                let u = u0 + (u1 - u0) * i as f64 / n as f64;
                let v = v0 + (v1 - v0) * j as f64 / n as f64;
                let d = s.eval(u, v).distance_squared(q);
                if d < best.0 {
                    best = (d, (u, v));
                }
            }
        }
        best.1
    };
    let newton = |(mut u, mut v): (f64, f64)| {
        for _ in 0..30 {
            let d = s.derivatives(u, v);
            let r = d.point - q;
            let f = d.su.dot(r);
            let g = d.sv.dot(r);
            let a = d.su.length_squared() + r.dot(d.suu);
            let b = d.su.dot(d.sv) + r.dot(d.suv);
            let c = d.sv.length_squared() + r.dot(d.svv);
            let det = a * c - b * b;
            if det.abs() <= 1e-300 || !det.is_finite() {
                break;
            }
            let du = (c * f - b * g) / det;
            let dv = (a * g - b * f) / det;
            let (nu, nv) = ((u - du).clamp(u0, u1), (v - dv).clamp(v0, v1));
            let moved = (nu - u).abs() + (nv - v).abs();
            (u, v) = (nu, nv);
            if moved <= 1e-15 * (1.0 + u.abs() + v.abs()) {
                break;
            }
        }
        (u, v)
    };
    let size = {
        let (a, b) = s.control_bounding_box();
        (b - a).length().max(1e-300)
    };
    if let Some(g) = guess {
        let r = newton(g);
        if s.eval(r.0, r.1).distance(q) <= 1e-7 * size {
            return r;
        }
    }
    newton(grid())
}
