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
use super::nurbs::{ArcMap, Nurbs3, arc, ellipse_arc, revolve};
use super::p21::{Exchange, Instance, Value};
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::units::LengthUnit;

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
mod pcurve;

use pcurve::{PcurveMap, PcurveUse};

type R<T> = Result<T, StepError>;

/// The map from natural coordinates of an analytic face to the parameters
/// of its NURBS, per coordinate: through the rational arcs' parameter
/// ([`ArcMap::param`]) or unchanged.
#[derive(Clone, Copy, Debug)]
struct ToUv([Option<ArcMap>; 2]);

impl ToUv {
    fn at(&self, a: f64, b: f64) -> [f64; 2] {
        let f = |m: &Option<ArcMap>, x: f64| m.as_ref().map_or(x, |m| m.param(x));
        [f(&self.0[0], a), f(&self.0[1], b)]
    }
}

/// A 3-D (or 2-D, `z = 0`) curve of the file.
#[derive(Clone, Debug)]
enum Curve {
    /// `p + t·d`.
    Line { p: Vec3, d: Vec3 },
    /// `c + rx·cos t·x + ry·sin t·y` (circle when `rx == ry`).
    Conic {
        c: Vec3,
        x: Vec3,
        y: Vec3,
        rx: f64,
        ry: f64,
    },
    /// A B-spline curve.
    Spline(Nurbs3),
}

impl Curve {
    fn eval(&self, t: f64) -> Vec3 {
        match self {
            Curve::Line { p, d } => *p + t * *d,
            Curve::Conic { c, x, y, rx, ry } => *c + rx * t.cos() * *x + ry * t.sin() * *y,
            Curve::Spline(n) => n.eval(t),
        }
    }

    /// The parameter of the curve point nearest to `q` (closed forms for
    /// lines and conics, sampling and golden-section refinement otherwise),
    /// measured by `dist`.
    fn param_of(&self, q: Vec3) -> f64 {
        match self {
            Curve::Line { p, d } => {
                let l2 = d.length_squared();
                if l2 > 0.0 { (q - *p).dot(*d) / l2 } else { 0.0 }
            }
            Curve::Conic { c, x, y, rx, ry } => {
                let r = q - *c;
                (r.dot(*y) / ry).atan2(r.dot(*x) / rx)
            }
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                nearest_param(a, b, 64 * n.points.len().max(4), |t| n.eval(t).distance(q))
            }
        }
    }
}

impl Curve {
    /// The arc of a conic over the parameters `[t0, t1]` (either way
    /// round) as an exact rational NURBS in that direction (Piegl & Tiller
    /// A7.1); `None` for other curves.
    fn conic_arc(&self, [t0, t1]: [f64; 2]) -> Option<Nurbs3> {
        let Curve::Conic { c, x, y, rx, ry } = self else {
            return None;
        };
        let map = ArcMap::new(t0.min(t1), t0.max(t1), 1.0);
        let a = ellipse_arc(*c, *x, *y, *rx, *ry, &map);
        Some(if t1 < t0 { a.reversed() } else { a })
    }
}

/// The traversal parameters of an edge on a conic from the parameters
/// `t0`, `t1` of its start and end (each in one turn): a whole turn from
/// `t0` for a closed edge, else `t1` moved by whole turns so that the arc
/// runs forward (the conic's direction) or backward from `t0`.
fn conic_range(t0: f64, t1: f64, closed: bool, forward: bool) -> [f64; 2] {
    let mut t1 = t1;
    if closed {
        t1 = if forward { t0 + TAU } else { t0 - TAU };
    } else if forward {
        while t1 <= t0 {
            t1 += TAU;
        }
    } else {
        while t1 >= t0 {
            t1 -= TAU;
        }
    }
    [t0, t1]
}

/// The `t ∈ [a, b]` minimising `f`: the best of `samples + 1` equally spaced
/// samples, refined by golden-section search on its two neighbouring
/// intervals.
fn nearest_param(a: f64, b: f64, samples: usize, f: impl Fn(f64) -> f64) -> f64 {
    let n = samples.clamp(8, 20_000);
    let at = |k: usize| a + (b - a) * k as f64 / n as f64;
    let best = (0..=n)
        .map(|k| (k, f(at(k))))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map_or(0, |x| x.0);
    let (mut lo, mut hi) = (at(best.saturating_sub(1)), at((best + 1).min(n)));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let m1 = hi - g * (hi - lo);
        let m2 = lo + g * (hi - lo);
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    0.5 * (lo + hi)
}

/// The parameter of an edge's vertex `q` on its B-spline curve `n`: the
/// end of the curve's domain where `q` lies on the curve's end point (to
/// 1e-9 of the curve's size) and the curve's two end points are apart —
/// where writers put an edge's vertices — else the nearest point of the
/// curve ([`Curve::param_of`], a dense search).
fn vertex_param(n: &Nurbs3, q: Vec3) -> f64 {
    let [a, b] = n.domain();
    let (pa, pb) = (n.eval(a), n.eval(b));
    let (lo, hi) = n
        .points
        .iter()
        .fold((q, q), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let close = 1e-9 * (hi - lo).length();
    if pa.distance(pb) > 2.0 * close {
        if pa.distance(q) <= close {
            return a;
        }
        if pb.distance(q) <= close {
            return b;
        }
    }
    nearest_param(a, b, 64 * n.points.len().max(4), |t| n.eval(t).distance(q))
}

/// An oriented edge of a face bound, as a piece of a curve.
struct EdgeUse {
    /// `#id` of the EDGE_CURVE.
    edge: u64,
    /// Its curve (a SURFACE_CURVE resolved to its 3-D curve).
    curve: Curve,
    /// The instance the curve came from (for p-curves).
    curve_entity: u64,
    /// Start and end points in traversal order.
    start: Vec3,
    end: Vec3,
    /// Start and end vertices are the same.
    closed: bool,
    /// Traversal runs along the curve's parameter direction.
    forward: bool,
}

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

impl<'a> Reader<'a> {
    fn get(&self, id: u64, from: &Instance) -> R<&'a Instance> {
        self.ex
            .instances
            .get(&id)
            .ok_or_else(|| self.err(from, format!("refers to #{id}, which is not defined")))
    }

    fn err(&self, i: &Instance, message: String) -> StepError {
        StepError::Entity {
            id: i.id,
            line: i.line,
            message: format!("{}: {message}", i.type_name()),
        }
    }

    /// The parameters of a simple instance of one of `types`.
    fn params(&self, i: &'a Instance, types: &[&str]) -> R<&'a [Value]> {
        match i.parts.as_slice() {
            [(n, p)] if types.contains(&n.as_str()) => Ok(p),
            _ => Err(self.err(i, format!("expected {}", types.join(" or ")))),
        }
    }

    fn at<'v>(&self, i: &Instance, p: &'v [Value], k: usize) -> R<&'v Value> {
        p.get(k).ok_or_else(|| {
            self.err(
                i,
                format!("has {} parameters, needs at least {}", p.len(), k + 1),
            )
        })
    }

    fn num(&self, i: &Instance, p: &[Value], k: usize) -> R<f64> {
        self.at(i, p, k)?
            .number()
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.err(i, format!("parameter {k} is not a number")))
    }

    fn int(&self, i: &Instance, p: &[Value], k: usize) -> R<usize> {
        let x = self.num(i, p, k)?;
        if x >= 0.0 && x.fract() == 0.0 && x < 1e9 {
            Ok(x as usize)
        } else {
            Err(self.err(i, format!("parameter {k} is not a count ({x})")))
        }
    }

    fn refer(&self, i: &'a Instance, p: &[Value], k: usize) -> R<&'a Instance> {
        match self.at(i, p, k)? {
            Value::Ref(id) => self.get(*id, i),
            _ => Err(self.err(i, format!("parameter {k} is not an entity reference"))),
        }
    }

    fn list<'v>(&self, i: &Instance, p: &'v [Value], k: usize) -> R<&'v [Value]> {
        match self.at(i, p, k)? {
            Value::List(l) => Ok(l),
            _ => Err(self.err(i, format!("parameter {k} is not a list"))),
        }
    }

    fn flag(&self, i: &Instance, p: &[Value], k: usize) -> R<bool> {
        match self.at(i, p, k)? {
            Value::Enum(e) if e == "T" => Ok(true),
            Value::Enum(e) if e == "F" => Ok(false),
            _ => Err(self.err(i, format!("parameter {k} is not .T. or .F."))),
        }
    }

    fn numbers(&self, i: &Instance, l: &[Value]) -> R<Vec<f64>> {
        l.iter()
            .map(|v| {
                v.number()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.err(i, "a list holds something other than numbers".into()))
            })
            .collect()
    }

    fn refs(&self, i: &'a Instance, l: &[Value]) -> R<Vec<&'a Instance>> {
        l.iter()
            .map(|v| match v {
                Value::Ref(id) => self.get(*id, i),
                _ => Err(self.err(
                    i,
                    "a list holds something other than entity references".into(),
                )),
            })
            .collect()
    }

    /// CARTESIAN_POINT (2-D points get `z = 0`).
    fn point(&self, i: &'a Instance) -> R<Vec3> {
        let p = self.params(i, &["CARTESIAN_POINT"])?;
        let c = self.numbers(i, self.list(i, p, 1)?)?;
        match c.as_slice() {
            [x, y] => Ok(Vec3::new(*x, *y, 0.0)),
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.err(i, format!("{} coordinates", c.len()))),
        }
    }

    /// DIRECTION, normalised.
    fn direction(&self, i: &'a Instance) -> R<Vec3> {
        let p = self.params(i, &["DIRECTION"])?;
        let c = self.numbers(i, self.list(i, p, 1)?)?;
        let d = match c.as_slice() {
            [x, y] => Vec3::new(*x, *y, 0.0),
            [x, y, z] => Vec3::new(*x, *y, *z),
            _ => return Err(self.err(i, format!("{} components", c.len()))),
        };
        let l = d.length();
        if l > 0.0 && l.is_finite() {
            Ok(d / l)
        } else {
            Err(self.err(i, "the direction has no length".into()))
        }
    }

    /// AXIS2_PLACEMENT_3D / _2D: origin and the axes x, y, z.
    fn placement(&self, i: &'a Instance) -> R<(Vec3, Vec3, Vec3, Vec3)> {
        let p = self.params(i, &["AXIS2_PLACEMENT_3D", "AXIS2_PLACEMENT_2D"])?;
        let o = self.point(self.refer(i, p, 1)?)?;
        let opt_dir = |k: usize| -> R<Option<Vec3>> {
            match p.get(k) {
                Some(Value::Ref(_)) => Ok(Some(self.direction(self.refer(i, p, k)?)?)),
                _ => Ok(None),
            }
        };
        let (z, xr) = if i.type_name() == "AXIS2_PLACEMENT_2D" {
            (Vec3::Z, opt_dir(2)?)
        } else {
            (opt_dir(2)?.unwrap_or(Vec3::Z), opt_dir(3)?)
        };
        let xr = xr.unwrap_or_else(|| if z.x.abs() < 0.9 { Vec3::X } else { Vec3::Y });
        let x = xr - xr.dot(z) * z;
        let l = x.length();
        if l <= 1e-12 || !l.is_finite() {
            return Err(self.err(i, "the reference direction is parallel to the axis".into()));
        }
        let x = x / l;
        Ok((o, x, z.cross(x), z))
    }

    /// A curve entity as a [`Curve`].
    fn curve(&self, i: &'a Instance) -> R<Curve> {
        match i.type_name() {
            "LINE" => {
                let p = self.params(i, &["LINE"])?;
                let o = self.point(self.refer(i, p, 1)?)?;
                let v = self.refer(i, p, 2)?;
                let vp = self.params(v, &["VECTOR"])?;
                let d = self.direction(self.refer(v, vp, 1)?)? * self.num(v, vp, 2)?;
                Ok(Curve::Line { p: o, d })
            }
            "CIRCLE" | "ELLIPSE" => {
                let p = self.params(i, &["CIRCLE", "ELLIPSE"])?;
                let (c, x, y, _) = self.placement(self.refer(i, p, 1)?)?;
                let rx = self.num(i, p, 2)?;
                let ry = if i.type_name() == "ELLIPSE" { self.num(i, p, 3)? } else { rx };
                if rx <= 0.0 || ry <= 0.0 {
                    return Err(self.err(i, "the radius is not positive".into()));
                }
                Ok(Curve::Conic { c, x, y, rx, ry })
            }
            "SURFACE_CURVE" | "SEAM_CURVE" => {
                // Resolved iteratively: a file may chain (or cycle) them.
                let mut c = i;
                for _ in 0..16 {
                    let p = self.params(c, &["SURFACE_CURVE", "SEAM_CURVE"])?;
                    let next = self.refer(c, p, 1)?;
                    if !matches!(next.type_name(), "SURFACE_CURVE" | "SEAM_CURVE") {
                        return self.curve(next);
                    }
                    c = next;
                }
                Err(self.err(i, "surface curves nest too deeply".into()))
            }
            "HYPERBOLA" | "PARABOLA" => self.open_conic(i),
            _ if i.is("B_SPLINE_CURVE_WITH_KNOTS") => Ok(Curve::Spline(self.bspline_curve(i)?)),
            t => Err(self.err(
                i,
                format!("curve type {t} is not supported (LINE, CIRCLE, ELLIPSE, HYPERBOLA, PARABOLA, B_SPLINE_CURVE_WITH_KNOTS, SURFACE_CURVE are)"),
            )),
        }
    }

    /// A `HYPERBOLA` (`c + a·cosh t·x + b·sinh t·y`, ISO 10303-42
    /// §4.4.14) or `PARABOLA` (`c + f·t²·x + 2f·t·y`, §4.4.15) as an exact
    /// rational quadratic B-spline over the parameters of the file's
    /// vertices that lie on it (an open conic is unbounded; its edges end
    /// at vertices): the parabola as one Bézier arc whose parameter is `t`;
    /// the hyperbola as arcs of at most 1 in `t`, each with its middle
    /// control point at the tangents' intersection `c + (a·cosh tm·x +
    /// b·sinh tm·y) / cosh δ` and weight `cosh δ` (`tm`, `δ` the arc's mid
    /// parameter and half span; the hyperbolic analogue of Piegl & Tiller
    /// A7.1), parameter equal to `t` at the arc joints.
    fn open_conic(&self, i: &'a Instance) -> R<Curve> {
        let hyperbola = i.type_name() == "HYPERBOLA";
        let p = self.params(i, &["HYPERBOLA", "PARABOLA"])?;
        let (c, x, y, _) = self.placement(self.refer(i, p, 1)?)?;
        let a = self.num(i, p, 2)?;
        let b = if hyperbola { self.num(i, p, 3)? } else { a };
        if !(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite()) {
            return Err(self.err(i, "the semi-axes or focal distance are not positive".into()));
        }
        let eval = |t: f64| -> Vec3 {
            if hyperbola {
                c + a * t.cosh() * x + b * t.sinh() * y
            } else {
                c + a * t * t * x + 2.0 * a * t * y
            }
        };
        let inverse = |q: Vec3| -> f64 {
            let r = q - c;
            if hyperbola {
                (r.dot(y) / b).asinh()
            } else {
                r.dot(y) / (2.0 * a)
            }
        };
        // the parameters of the vertices on the curve
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in self.ex.instances.values() {
            if v.type_name() != "VERTEX_POINT" {
                continue;
            }
            let Ok(vp) = self.params(v, &["VERTEX_POINT"]) else {
                continue;
            };
            let Ok(q) = self.refer(v, vp, 1).and_then(|pt| self.point(pt)) else {
                continue;
            };
            let t = inverse(q);
            let tol = 1e-7 * (1.0 + (q - c).length() + a + b);
            if t.is_finite() && eval(t).distance(q) <= tol.max(self.uncertainty) {
                lo = lo.min(t);
                hi = hi.max(t);
            }
        }
        if !(hi > lo) {
            return Err(self.err(
                i,
                "no two vertices of the file lie on this open conic: its extent is unknown".into(),
            ));
        }
        let arcs = if hyperbola {
            ((hi - lo).ceil() as usize).clamp(1, 64)
        } else {
            1
        };
        let d = (hi - lo) / arcs as f64;
        let mut knots = vec![lo; 3];
        let mut points = vec![eval(lo)];
        let mut weights = vec![1.0];
        for k in 0..arcs {
            let (t0, t1) = (lo + k as f64 * d, lo + (k + 1) as f64 * d);
            let (tm, h) = (0.5 * (t0 + t1), 0.5 * d);
            if hyperbola {
                points.push(c + (a * tm.cosh() * x + b * tm.sinh() * y) / h.cosh());
                weights.push(h.cosh());
            } else {
                points.push(c + a * t0 * t1 * x + a * (t0 + t1) * y);
                weights.push(1.0);
            }
            points.push(eval(t1));
            weights.push(1.0);
            if k + 1 < arcs {
                knots.extend([t1, t1]);
            }
        }
        knots.extend([hi; 3]);
        Ok(Curve::Spline(Nurbs3 {
            degree: 2,
            knots,
            points,
            weights: hyperbola.then_some(weights),
        }))
    }

    /// Knots from distinct values and multiplicities.
    fn knots(&self, i: &Instance, mults: &[Value], values: &[Value]) -> R<Vec<f64>> {
        let m = self.numbers(i, mults)?;
        let v = self.numbers(i, values)?;
        if m.len() != v.len() {
            return Err(self.err(
                i,
                format!("{} multiplicities for {} knots", m.len(), v.len()),
            ));
        }
        let mut out = Vec::new();
        for (&m, &k) in m.iter().zip(&v) {
            if !(m >= 1.0 && m.fract() == 0.0 && m <= 64.0) {
                return Err(self.err(i, format!("knot multiplicity {m}")));
            }
            out.extend(std::iter::repeat_n(k, m as usize));
        }
        Ok(out)
    }

    /// B_SPLINE_CURVE_WITH_KNOTS, simple or complex (with
    /// RATIONAL_B_SPLINE_CURVE).
    fn bspline_curve(&self, i: &'a Instance) -> R<Nurbs3> {
        let (head, tail): (&[Value], &[Value]) = match i.part("B_SPLINE_CURVE") {
            Some(h) => (h, i.part("B_SPLINE_CURVE_WITH_KNOTS").unwrap_or(&[])),
            None => {
                let p = self.params(i, &["B_SPLINE_CURVE_WITH_KNOTS"])?;
                (p.get(1..6).unwrap_or(&[]), p.get(6..).unwrap_or(&[]))
            }
        };
        let degree = self.int(i, head, 0)?;
        let pts = self
            .refs(i, self.list(i, head, 1)?)?
            .into_iter()
            .map(|p| self.point(p))
            .collect::<R<Vec<_>>>()?;
        let knots = self.knots(i, self.list(i, tail, 0)?, self.list(i, tail, 1)?)?;
        let weights = match i.part("RATIONAL_B_SPLINE_CURVE") {
            Some(w) => Some(self.numbers(i, self.list(i, w, 0)?)?),
            None => None,
        };
        let c = TrimCurve::new(
            degree,
            knots.clone(),
            pts.iter().map(|p| [p.x, p.y]).collect(),
            weights.clone(),
        )
        .map_err(|m| self.err(i, m))?;
        // Validated above (degree, knot count, weights) so that evaluation
        // cannot fail.
        drop(c);
        Ok(Nurbs3 {
            degree,
            knots,
            points: pts,
            weights,
        })
    }

    /// B_SPLINE_SURFACE_WITH_KNOTS, simple or complex (with
    /// RATIONAL_B_SPLINE_SURFACE).
    fn bspline_surface(&self, i: &'a Instance) -> R<BSplineSurface> {
        let (head, tail): (&[Value], &[Value]) = match i.part("B_SPLINE_SURFACE") {
            Some(h) => (h, i.part("B_SPLINE_SURFACE_WITH_KNOTS").unwrap_or(&[])),
            None => {
                let p = self.params(i, &["B_SPLINE_SURFACE_WITH_KNOTS"])?;
                (p.get(1..8).unwrap_or(&[]), p.get(8..).unwrap_or(&[]))
            }
        };
        let (du, dv) = (self.int(i, head, 0)?, self.int(i, head, 1)?);
        let rows = self.list(i, head, 2)?;
        let mut points = Vec::new();
        let mut count_v = None;
        for row in rows {
            let Value::List(r) = row else {
                return Err(self.err(i, "control points are not a list of lists".into()));
            };
            if *count_v.get_or_insert(r.len()) != r.len() {
                return Err(self.err(i, "control point rows differ in length".into()));
            }
            for p in self.refs(i, r)? {
                points.push(self.point(p)?);
            }
        }
        let ku = self.knots(i, self.list(i, tail, 0)?, self.list(i, tail, 2)?)?;
        let kv = self.knots(i, self.list(i, tail, 1)?, self.list(i, tail, 3)?)?;
        let weights = match i.part("RATIONAL_B_SPLINE_SURFACE") {
            Some(w) => {
                let mut out = Vec::new();
                for row in self.list(i, w, 0)? {
                    let Value::List(r) = row else {
                        return Err(self.err(i, "weights are not a list of lists".into()));
                    };
                    out.extend(self.numbers(i, r)?);
                }
                Some(out)
            }
            None => None,
        };
        BSplineSurface::from_flat(
            du,
            dv,
            ku,
            kv,
            [rows.len(), count_v.unwrap_or(0)],
            points,
            weights,
        )
        .map_err(|e| self.err(i, e.to_string()))
    }

    /// The edges of one FACE_BOUND's EDGE_LOOP (None for a VERTEX_LOOP).
    fn bound_edges(&self, bound: &'a Instance) -> R<Option<(bool, Vec<EdgeUse>)>> {
        let p = self.params(bound, &["FACE_OUTER_BOUND", "FACE_BOUND"])?;
        let outer = bound.type_name() == "FACE_OUTER_BOUND";
        let lp = self.refer(bound, p, 1)?;
        let sense = self.flag(bound, p, 2)?;
        if lp.type_name() == "VERTEX_LOOP" {
            return Ok(None);
        }
        let lpp = self.params(lp, &["EDGE_LOOP"])?;
        let mut edges = Vec::new();
        for oe in self.refs(lp, self.list(lp, lpp, 1)?)? {
            let op = self.params(oe, &["ORIENTED_EDGE"])?;
            let ec = self.refer(oe, op, 3)?;
            let orientation = self.flag(oe, op, 4)?;
            let ep = self.params(ec, &["EDGE_CURVE"])?;
            let vertex = |k: usize| -> R<(u64, Vec3)> {
                let v = self.refer(ec, ep, k)?;
                let vp = self.params(v, &["VERTEX_POINT"])?;
                Ok((v.id, self.point(self.refer(v, vp, 1)?)?))
            };
            let (v1, v2) = (vertex(1)?, vertex(2)?);
            let ci = self.refer(ec, ep, 3)?;
            let curve = self.curve(ci)?;
            let same = self.flag(ec, ep, 4)?;
            let (start, end) = if orientation { (v1, v2) } else { (v2, v1) };
            edges.push(EdgeUse {
                edge: ec.id,
                curve,
                curve_entity: ci.id,
                start: start.1,
                end: end.1,
                closed: v1.0 == v2.0 || v1.1 == v2.1,
                forward: same == orientation,
            });
        }
        if !sense {
            edges.reverse();
            for e in &mut edges {
                std::mem::swap(&mut e.start, &mut e.end);
                e.forward = !e.forward;
            }
        }
        Ok(Some((outer, edges)))
    }

    /// The traversal parameters `[t_start, t_end]` of an edge on its curve.
    fn edge_range(&self, e: &EdgeUse) -> [f64; 2] {
        match &e.curve {
            Curve::Line { .. } => [e.curve.param_of(e.start), e.curve.param_of(e.end)],
            Curve::Conic { .. } => conic_range(
                e.curve.param_of(e.start),
                e.curve.param_of(e.end),
                e.closed,
                e.forward,
            ),
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                if e.closed {
                    if e.forward { [a, b] } else { [b, a] }
                } else {
                    [vertex_param(n, e.start), vertex_param(n, e.end)]
                }
            }
        }
    }

    /// The edge as an exact NURBS curve in traversal order where one
    /// exists (lines, conic arcs, whole B-spline curves), else `None`.
    fn edge_nurbs(&self, e: &EdgeUse) -> Option<Nurbs3> {
        let [t0, t1] = self.edge_range(e);
        match &e.curve {
            Curve::Line { .. } => Some(Nurbs3::segment(
                e.curve.eval(t0),
                e.curve.eval(t1),
                0.0,
                1.0,
            )),
            Curve::Conic { .. } => e.curve.conic_arc([t0, t1]),
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                let tol = 1e-9 * (b - a);
                if (t0 - a).abs() <= tol && (t1 - b).abs() <= tol {
                    Some(n.clone())
                } else if (t0 - b).abs() <= tol && (t1 - a).abs() <= tol {
                    Some(n.reversed())
                } else {
                    None
                }
            }
        }
    }

    /// Dense points along an edge in traversal order (both ends included).
    fn edge_points(&self, e: &EdgeUse) -> Vec<Vec3> {
        self.edge_samples(e).into_iter().map(|(_, q)| q).collect()
    }

    /// [`Self::edge_points`] with their curve parameters.
    fn edge_samples(&self, e: &EdgeUse) -> Vec<(f64, Vec3)> {
        let [t0, t1] = self.edge_range(e);
        let n = match &e.curve {
            Curve::Line { .. } => 32,
            Curve::Conic { .. } => ((t1 - t0).abs().to_degrees() * 2.0).ceil() as usize,
            Curve::Spline(s) => 16 * s.points.len() * s.degree,
        }
        .clamp(8, 4000);
        (0..=n)
            .map(|k| {
                let t = t0 + (t1 - t0) * k as f64 / n as f64;
                (t, e.curve.eval(t))
            })
            .collect()
    }
}

/// Reads the faces (and free bounded B-spline surfaces) of a parsed file.
pub(super) fn read(ex: &Exchange, collect: bool) -> R<StepImport> {
    let (unit, angle) = units(ex);
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

impl<'a> Reader<'a> {
    /// An `OFFSET_SURFACE` (ISO 10303-42 §4.4.14) whose basis, through
    /// nested offsets, is a B-spline surface: the exact offset S + d·N on
    /// the basis's parameters, as a plane moved exactly or a bicubic
    /// B-spline fitted within 1e-7 of the basis's size
    /// ([`crate::bspline::offset::offset_surface`]), the fit named in the
    /// warnings. `None` for any other surface.
    fn offset_of_bspline(&self, si: &'a Instance) -> R<Option<BSplineSurface>> {
        let (mut basis, mut d) = (si, 0.0);
        for _ in 0..8 {
            if !basis.is("OFFSET_SURFACE") {
                break;
            }
            let p = self.params(basis, &["OFFSET_SURFACE"])?;
            d += self.num(basis, p, 2)?;
            basis = self.refer(basis, p, 1)?;
        }
        if !si.is("OFFSET_SURFACE") || !basis.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            return Ok(None);
        }
        let s = self.bspline_surface(basis)?;
        let (lo, hi) = s.control_bounding_box();
        let tolerance = 1e-7 * ((hi - lo).length() + 2.0 * d.abs());
        let o = crate::bspline::offset::offset_surface(&s, d, tolerance)
            .map_err(|m| self.err(si, format!("the offset surface: {m}")))?;
        if let Some(e) = o.deviation {
            self.fitted.borrow_mut().push(format!(
                "#{} OFFSET_SURFACE: the offset surface is approximated by a bicubic B-spline within {tolerance:.1e} (largest deviation found {e:.1e})",
                si.id
            ));
        }
        Ok(Some(o.surface))
    }
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

/// For each edge of a loop with several agreeing p-curves (a seam), the
/// index of the one to use (0: the first); `None` for the others. Every
/// edge takes the candidate whose start lies nearest to the previous
/// edge's end, starting from each candidate of the first such edge in
/// turn; the start with the smallest total gap around the loop wins.
fn seam_choice(found: &[(PcurveUse, Vec<TrimCurve>)]) -> Vec<Option<usize>> {
    let n = found.len();
    let cands: Vec<Vec<&TrimCurve>> = found
        .iter()
        .map(|(u, o)| match u {
            PcurveUse::Used(c) => std::iter::once(c).chain(o.iter()).collect(),
            _ => Vec::new(),
        })
        .collect();
    let Some(first) = cands.iter().position(|c| c.len() > 1) else {
        return cands.iter().map(|c| (!c.is_empty()).then_some(0)).collect();
    };
    let ends = |c: &TrimCurve| {
        let [a, b] = c.domain();
        (c.eval(a), c.eval(b))
    };
    let gap = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let mut best: Option<(f64, Vec<Option<usize>>)> = None;
    for start in 0..cands[first].len() {
        let mut pick: Vec<Option<usize>> = vec![None; n];
        pick[first] = Some(start);
        let mut prev_end = Some(ends(cands[first][start]).1);
        for step in 1..n {
            let k = (first + step) % n;
            let c = &cands[k];
            if c.is_empty() {
                prev_end = None;
                continue;
            }
            let j = match prev_end {
                Some(p) if c.len() > 1 => (0..c.len())
                    .min_by(|&x, &y| gap(p, ends(c[x]).0).total_cmp(&gap(p, ends(c[y]).0)))
                    .unwrap_or(0),
                _ => 0,
            };
            pick[k] = Some(j);
            prev_end = Some(ends(c[j]).1);
        }
        let mut total = 0.0;
        for k in 0..n {
            let next = (k + 1) % n;
            if let (Some(a), Some(b)) = (pick[k], pick[next]) {
                total += gap(ends(cands[k][a]).1, ends(cands[next][b]).0);
            }
        }
        if best.as_ref().is_none_or(|b| total < b.0) {
            best = Some((total, pick));
        }
    }
    best.map(|b| b.1).unwrap_or_else(|| vec![None; n])
}

/// The file's distance uncertainty (the first positive
/// `UNCERTAINTY_MEASURE_WITH_UNIT` value, in the file's length unit), 0
/// when it states none.
fn distance_uncertainty(ex: &Exchange) -> f64 {
    let mut ids: Vec<u64> = ex.order.clone();
    ids.sort_unstable();
    ids.iter()
        .filter_map(|id| ex.instances[id].part("UNCERTAINTY_MEASURE_WITH_UNIT"))
        .filter_map(|p| p.first().and_then(Value::number))
        .find(|x| x.is_finite() && *x > 0.0)
        .unwrap_or(0.0)
}

fn collect_refs(v: &[Value], out: &mut HashSet<u64>) {
    for x in v {
        match x {
            Value::Ref(id) => {
                out.insert(*id);
            }
            Value::List(l) => collect_refs(l, out),
            Value::Typed(_, b) => collect_refs(std::slice::from_ref(b), out),
            _ => {}
        }
    }
}

/// The file's length unit and radians per plane-angle unit (1 when
/// absent): the units a GLOBAL_UNIT_ASSIGNED_CONTEXT assigns, else the first
/// LENGTH_UNIT / PLANE_ANGLE_UNIT instances.
fn units(ex: &Exchange) -> (Option<LengthUnit>, f64) {
    let mut ids: Vec<u64> = ex.order.clone();
    ids.sort_unstable();
    let mut candidates: Vec<&Instance> = Vec::new();
    for id in &ids {
        if let Some(Value::List(l)) = ex.instances[id]
            .part("GLOBAL_UNIT_ASSIGNED_CONTEXT")
            .and_then(|p| p.first())
        {
            for v in l {
                if let Value::Ref(u) = v
                    && let Some(i) = ex.instances.get(u)
                {
                    candidates.push(i);
                }
            }
        }
    }
    candidates.extend(ids.iter().map(|id| &ex.instances[id]));
    let mut length = None;
    let mut angle = None;
    for i in candidates {
        if length.is_none() && i.is("LENGTH_UNIT") {
            length = unit_size(ex, i, 0).map(|m| {
                let named = LengthUnit::from_iges_name(&unit_name(i))
                    .filter(|u| (u.metres - m).abs() <= 1e-9 * m);
                named.unwrap_or(LengthUnit {
                    name: unit_name(i),
                    metres: m,
                })
            });
        }
        if angle.is_none() && i.is("PLANE_ANGLE_UNIT") {
            angle = unit_size(ex, i, 0);
        }
    }
    (length, angle.filter(|a| *a > 0.0).unwrap_or(1.0))
}

/// Metres (or radians) per unit of an SI_UNIT or CONVERSION_BASED_UNIT.
fn unit_size(ex: &Exchange, i: &Instance, depth: usize) -> Option<f64> {
    if depth > 8 {
        return None;
    }
    if let Some(si) = i.part("SI_UNIT") {
        let prefix = match si.first() {
            Some(Value::Enum(p)) => match p.as_str() {
                "MILLI" => 1e-3,
                "CENTI" => 1e-2,
                "DECI" => 1e-1,
                "KILO" => 1e3,
                "MICRO" => 1e-6,
                "NANO" => 1e-9,
                _ => return None,
            },
            _ => 1.0,
        };
        return Some(prefix);
    }
    if let Some(cb) = i.part("CONVERSION_BASED_UNIT") {
        let Some(Value::Ref(m)) = cb.get(1) else {
            return None;
        };
        let m = ex.instances.get(m)?;
        let (_, p) = m
            .parts
            .iter()
            .find(|(n, _)| n.contains("MEASURE_WITH_UNIT"))?;
        let factor = p.first()?.number()?;
        let Some(Value::Ref(u)) = p.get(1) else {
            return None;
        };
        let base = unit_size(ex, ex.instances.get(u)?, depth + 1)?;
        return Some(factor * base).filter(|x| x.is_finite() && *x > 0.0);
    }
    None
}

fn unit_name(i: &Instance) -> String {
    if let Some(cb) = i.part("CONVERSION_BASED_UNIT")
        && let Some(Value::Text(t)) = cb.first()
    {
        return t.to_ascii_uppercase();
    }
    match i.part("SI_UNIT") {
        Some([Value::Enum(p), Value::Enum(_)]) if p == "MILLI" => "MM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "CENTI" => "CM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "KILO" => "KM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "MICRO" => "UM".into(),
        _ => "M".into(),
    }
}

impl<'a> Reader<'a> {
    fn face(&self, f: &'a Instance) -> R<StepSurface> {
        let p = self.params(f, &["ADVANCED_FACE", "FACE_SURFACE"])?;
        let bounds = self.refs(f, self.list(f, p, 1)?)?;
        let si = self.refer(f, p, 2)?;
        let same_sense = self.flag(f, p, 3)?;
        let mut loops: Vec<(bool, Vec<EdgeUse>)> = Vec::new();
        for b in bounds {
            if let Some(l) = self.bound_edges(b)? {
                loops.push(l);
            }
        }
        // The outer bound first (FACE_OUTER_BOUND, else decided later by area).
        loops.sort_by_key(|l| !l.0);
        let surface = if si.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            let s = self.bspline_surface(si)?;
            let trims = loops
                .iter()
                .map(|(_, edges)| self.bspline_loop(&s, si.id, edges))
                .collect::<R<Vec<_>>>()?;
            self.attach(f, s, trims, loops.first().is_some_and(|l| l.0))?
        } else if let Some(s) = self.offset_of_bspline(si)? {
            // on the basis's parameters: its p-curves trim the offset
            let trims = loops
                .iter()
                .map(|(_, edges)| self.bspline_loop(&s, si.id, edges))
                .collect::<R<Vec<_>>>()?;
            self.attach(f, s, trims, loops.first().is_some_and(|l| l.0))?
        } else {
            self.analytic_face(f, si, &loops, same_sense)?
        };
        Ok(StepSurface {
            surface,
            entity: f.id,
            surface_entity: si.id,
            surface_type: si.type_name().to_string(),
            same_sense,
        })
    }

    /// Attaches loops; when no loop was marked outer, the one enclosing the
    /// largest parameter area goes first.
    fn attach(
        &self,
        f: &Instance,
        s: BSplineSurface,
        mut trims: Vec<TrimLoop>,
        outer_known: bool,
    ) -> R<BSplineSurface> {
        if trims.is_empty() {
            return Ok(s);
        }
        if !outer_known && trims.len() > 1 {
            let area = |l: &TrimLoop| {
                let mut pts = Vec::new();
                for c in &l.curves {
                    c.flatten_into(1e-6, &mut pts);
                }
                crate::bspline::polygon_signed_area2(&pts).abs()
            };
            let k = (0..trims.len())
                .max_by(|&a, &b| area(&trims[a]).total_cmp(&area(&trims[b])))
                .unwrap_or(0);
            trims.swap(0, k);
        }
        s.with_trims(trims).map_err(|e| self.err(f, e.to_string()))
    }

    /// A loop on a B-spline surface: p-curves on it when the edges have
    /// them, else the edge points projected onto the surface.
    ///
    /// A seam edge (a SEAM_CURVE with two p-curves that both agree with
    /// the edge, as on a surface closed in u or v) takes the p-curve that
    /// continues the loop: the choice that leaves the smallest total gap
    /// between consecutive curves' ends and starts, so that a seam used
    /// twice runs once along each side of the parameter domain.
    fn bspline_loop(&self, s: &BSplineSurface, sid: u64, edges: &[EdgeUse]) -> R<TrimLoop> {
        let mut curves = Vec::with_capacity(edges.len());
        let mut guess = None;
        let mut found = Vec::with_capacity(edges.len());
        for e in edges {
            found.push(self.pcurve_trims(s, sid, e, &PcurveMap::IDENTITY, None, true)?);
        }
        let choice = seam_choice(&found);
        for ((e, (use_, others)), pick) in edges.iter().zip(found).zip(choice) {
            let use_ = match (use_, pick) {
                (PcurveUse::Used(_), Some(k)) if k > 0 => {
                    PcurveUse::Used(others.into_iter().nth(k - 1).expect("seam choice"))
                }
                (u, _) => u,
            };
            if let Some(c) = self.count_trim(e, use_) {
                curves.push(c);
                continue;
            }
            let pts: Vec<[f64; 2]> = self
                .edge_points(e)
                .into_iter()
                .map(|q| {
                    let uv = invert_point(s, q, guess);
                    guess = Some(uv);
                    [uv.0, uv.1]
                })
                .collect();
            curves.push(polyline(&pts).map_err(|m| self.err(&self.ex.instances[&e.edge], m))?);
        }
        Ok(TrimLoop { curves })
    }

    /// Counts where an edge's trim curve came from and returns the
    /// p-curve's when it is used.
    fn count_trim(&self, e: &EdgeUse, found: PcurveUse) -> Option<TrimCurve> {
        let mut n = self.sources.get();
        let out = match found {
            PcurveUse::Used(c) => {
                n.pcurve += 1;
                Some(c)
            }
            PcurveUse::Absent => {
                n.edge += 1;
                None
            }
            PcurveUse::Rejected {
                distance,
                tolerance,
            } => {
                n.pcurve_rejected += 1;
                self.rejected
                    .borrow_mut()
                    .push((e.edge, distance, tolerance));
                None
            }
        };
        self.sources.set(n);
        out
    }

    /// Counts edges whose trims come from the 3-D edges without looking
    /// at p-curves.
    fn count_edges(&self, edges: usize) {
        let mut n = self.sources.get();
        n.edge += edges;
        self.sources.set(n);
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
