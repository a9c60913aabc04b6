//! Curves of edges as NURBS: lines, circles and ellipses (exact rational
//! arcs over the part an edge uses), B-spline curves, and the parameter of a
//! vertex on a curve.

use std::f64::consts::TAU;

use super::{R, Reader};
use crate::Vec3;
use crate::bspline::TrimCurve;
use crate::io::step::nurbs::{ArcMap, Nurbs3, ellipse_arc};
use crate::io::step::p21::{Instance, Value};

/// The map from natural coordinates of an analytic face to the parameters
/// of its NURBS, per coordinate: through the rational arcs' parameter
/// ([`ArcMap::param`]) or unchanged.
#[derive(Clone, Copy, Debug)]
pub(super) struct ToUv(pub(super) [Option<ArcMap>; 2]);

impl ToUv {
    pub(super) fn at(&self, a: f64, b: f64) -> [f64; 2] {
        let f = |m: &Option<ArcMap>, x: f64| m.as_ref().map_or(x, |m| m.param(x));
        [f(&self.0[0], a), f(&self.0[1], b)]
    }
}

/// A 3-D (or 2-D, `z = 0`) curve of the file.
#[derive(Clone, Debug)]
pub(super) enum Curve {
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
    pub(super) fn eval(&self, t: f64) -> Vec3 {
        match self {
            Curve::Line { p, d } => *p + t * *d,
            Curve::Conic { c, x, y, rx, ry } => *c + rx * t.cos() * *x + ry * t.sin() * *y,
            Curve::Spline(n) => n.eval(t),
        }
    }

    /// The parameter of the curve point nearest to `q` (closed forms for
    /// lines and conics, sampling and golden-section refinement otherwise),
    /// measured by `dist`.
    pub(super) fn param_of(&self, q: Vec3) -> f64 {
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
    pub(super) fn conic_arc(&self, [t0, t1]: [f64; 2]) -> Option<Nurbs3> {
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
pub(super) fn conic_range(t0: f64, t1: f64, closed: bool, forward: bool) -> [f64; 2] {
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
pub(super) fn nearest_param(a: f64, b: f64, samples: usize, f: impl Fn(f64) -> f64) -> f64 {
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
pub(super) fn vertex_param(n: &Nurbs3, q: Vec3) -> f64 {
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

impl<'a> Reader<'a> {
    /// A curve entity as a [`Curve`].
    pub(super) fn curve(&self, i: &'a Instance) -> R<Curve> {
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
    pub(super) fn knots(&self, i: &Instance, mults: &[Value], values: &[Value]) -> R<Vec<f64>> {
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
}
