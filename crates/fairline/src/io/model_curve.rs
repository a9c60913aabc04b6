//! Model-space (3-D) curves of trimming curves, for the writers: the image
//! `C(t) = S(c(t))` of a trim curve `c` on its surface `S`, as a B-spline
//! curve with the trim curve's own parameter `t`, so that a kernel reading
//! the file finds a 3-D edge curve that agrees with the p-curve (OCCT
//! builds its edges from both and rejects or re-approximates edges where
//! they disagree).
//!
//! - On an affine patch (degree 1 × 1, a parallelogram net, equal weights)
//!   `S` is an affine map and `C` is the trim curve's control polygon
//!   mapped by it, same knots and weights: exact.
//! - A straight trim segment along a parameter line (`u` or `v` constant) is
//!   the surface's isoparametric curve (the net's rows combined with the
//!   basis functions of the constant parameter, in homogeneous
//!   coordinates; Piegl & Tiller §3.4) reparametrised affinely to `t`:
//!   exact, of the surface's degree in the moving direction.
//! - Anything else: a C¹ piecewise cubic Hermite interpolant of `C(t)` and
//!   `C'(t) = S_u·u'(t) + S_v·v'(t)` at parameters bisected until the
//!   interpolant is within the tolerance of `C` at every piece's interior
//!   check points (Bézier pieces joined with triple knots).

use crate::Vec3;
use crate::bspline::basis::basis_funs;
use crate::bspline::{BSplineSurface, TrimCurve, find_span};

/// A 3-D B-spline curve (NURBS when `weights` is given).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCurve {
    /// Degree.
    pub degree: usize,
    /// Knot vector (`points.len() + degree + 1` values).
    pub knots: Vec<f64>,
    /// Control points.
    pub points: Vec<Vec3>,
    /// Weights, when rational.
    pub weights: Option<Vec<f64>>,
    /// The curve is exactly `S(c(t))` (up to rounding).
    pub exact: bool,
}

/// The distance within which a written 3-D curve follows its trim curve
/// where it is not exact: 1e-8 of the surface's control-net diagonal, at
/// most 5e-8 (half the 1e-7 distance accuracy the STEP writer declares).
pub fn model_tolerance(s: &BSplineSurface) -> f64 {
    let (lo, hi) = s.control_bounding_box();
    (1e-8 * (hi - lo).length()).min(5e-8)
}

/// Deepest bisection of one span of the trim curve (2^12 pieces).
const MAX_DEPTH: u32 = 12;

/// The 3-D curve of trim curve `c` on `s` (see the module docs); the
/// interpolated case stays within `tolerance` (model units) of `S(c(t))`
/// at its check points.
pub fn model_curve(s: &BSplineSurface, c: &TrimCurve, tolerance: f64) -> ModelCurve {
    if let Some(m) = affine_image(s, c) {
        return m;
    }
    if let Some(m) = iso_image(s, c) {
        return m;
    }
    hermite_image(s, c, tolerance)
}

/// `S` is affine: the image of the control polygon.
fn affine_image(s: &BSplineSurface, c: &TrimCurve) -> Option<ModelCurve> {
    if s.degree_u() != 1 || s.degree_v() != 1 || s.count_u() != 2 || s.count_v() != 2 {
        return None;
    }
    if let Some(w) = s.weights()
        && w.iter().any(|&x| x != w[0])
    {
        return None;
    }
    let (p00, p10, p01, p11) = (
        s.control_point(0, 0),
        s.control_point(1, 0),
        s.control_point(0, 1),
        s.control_point(1, 1),
    );
    let size = (p11 - p00).length().max((p10 - p01).length());
    if (p11 - p10 - p01 + p00).length() > 1e-14 * size.max(f64::MIN_POSITIVE) {
        return None;
    }
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    let (du, dv) = (u1 - u0, v1 - v0);
    if !(du > 0.0 && dv > 0.0) {
        return None;
    }
    let points = c
        .control_points()
        .iter()
        .map(|&[u, v]| p00 + (u - u0) / du * (p10 - p00) + (v - v0) / dv * (p01 - p00))
        .collect();
    Some(ModelCurve {
        degree: c.degree(),
        knots: c.knots().to_vec(),
        points,
        weights: c.weights().map(<[f64]>::to_vec),
        exact: true,
    })
}

/// A straight segment along `u` or `v`: the isoparametric curve.
fn iso_image(s: &BSplineSurface, c: &TrimCurve) -> Option<ModelCurve> {
    let pts = c.control_points();
    if c.degree() != 1 || pts.len() != 2 || c.weights().is_some() {
        return None;
    }
    let ([a, b], [t0, t1]) = ([pts[0], pts[1]], c.domain());
    // moving coordinate 0 (u) with v fixed, or 1 (v) with u fixed
    let moving = if a[1] == b[1] && a[0] != b[0] {
        0
    } else if a[0] == b[0] && a[1] != b[1] {
        1
    } else {
        return None;
    };
    let fixed = a[1 - moving];
    let (degree, knots, count, fixed_knots, fixed_degree, fixed_count) = if moving == 0 {
        (
            s.degree_u(),
            s.knots_u(),
            s.count_u(),
            s.knots_v(),
            s.degree_v(),
            s.count_v(),
        )
    } else {
        (
            s.degree_v(),
            s.knots_v(),
            s.count_v(),
            s.knots_u(),
            s.degree_u(),
            s.count_u(),
        )
    };
    let dom = if moving == 0 {
        s.domain_v()
    } else {
        s.domain_u()
    };
    let fixed = fixed.clamp(dom[0], dom[1]);
    let span = find_span(fixed_knots, fixed_degree, fixed_count, fixed);
    let mut n = [0.0; crate::bspline::MAX_ORDER];
    basis_funs(span, fixed, fixed_degree, fixed_knots, &mut n);
    let mut points = Vec::with_capacity(count);
    let mut weights = Vec::with_capacity(count);
    for i in 0..count {
        let (mut p, mut w) = (Vec3::ZERO, 0.0);
        for (r, nr) in n.iter().enumerate().take(fixed_degree + 1) {
            let j = span - fixed_degree + r;
            let (ij, jj) = if moving == 0 { (i, j) } else { (j, i) };
            let wt = s.weight(ij, jj);
            p += *nr * wt * s.control_point(ij, jj);
            w += nr * wt;
        }
        if !(w > 0.0 && w.is_finite()) {
            return None;
        }
        points.push(p / w);
        weights.push(w);
    }
    // t = t0 + (x − a)·(t1 − t0)/(b − a) along the moving coordinate x
    let (xa, xb) = (a[moving], b[moving]);
    let scale = (t1 - t0) / (xb - xa);
    let map = |x: f64| t0 + (x - xa) * scale;
    let (mut knots, mut points, mut weights): (Vec<f64>, Vec<Vec3>, Vec<f64>) =
        (knots.iter().map(|&k| map(k)).collect(), points, weights);
    if scale < 0.0 {
        knots.reverse();
        points.reverse();
        weights.reverse();
    }
    if !knots.windows(2).all(|w| w[0] <= w[1]) || !knots.iter().all(|k| k.is_finite()) {
        return None;
    }
    let rational = s.is_rational() && weights.iter().any(|&w| w != weights[0]);
    // the piece over the trim's own parameter range, so that the curve
    // ends where the edge does
    let piece = crate::io::step::nurbs::Nurbs3 {
        degree,
        knots,
        points,
        weights: rational.then_some(weights),
    }
    .between(t0, t1)?;
    Some(ModelCurve {
        degree: piece.degree,
        knots: piece.knots,
        points: piece.points,
        weights: piece.weights,
        exact: true,
    })
}

/// The piecewise cubic Hermite interpolant (see the module docs).
fn hermite_image(s: &BSplineSurface, c: &TrimCurve, tolerance: f64) -> ModelCurve {
    let [a, b] = c.domain();
    let eval = |t: f64| -> Vec3 {
        let [u, v] = c.eval(t);
        s.eval(u, v)
    };
    // C'(t): the trim curve's derivative by central differences clipped to
    // the piece [lo, hi] (pieces never straddle a knot, where the trim curve
    // may have a kink), chained with S_u, S_v.
    let deriv = |t: f64, lo: f64, hi: f64| -> Vec3 {
        let h = 1e-6 * (hi - lo).max(f64::MIN_POSITIVE);
        let (p0, p1) = ((t - h).max(lo), (t + h).min(hi));
        let (p, q) = (c.eval(p0), c.eval(p1));
        let dt = p1 - p0;
        if dt <= 0.0 {
            return Vec3::ZERO;
        }
        let [u, v] = c.eval(t);
        let d = s.derivatives(u, v);
        d.su * ((q[0] - p[0]) / dt) + d.sv * ((q[1] - p[1]) / dt)
    };
    let mut breaks: Vec<f64> = vec![a];
    let mut spans: Vec<f64> = c.knots().to_vec();
    spans.dedup();
    let spans: Vec<f64> = spans.into_iter().filter(|&k| k > a && k < b).collect();
    let mut ends = spans;
    ends.push(b);
    let mut start = a;
    for end in ends {
        let pieces = 2 * c.degree().max(1);
        for k in 0..pieces {
            let t0 = start + (end - start) * k as f64 / pieces as f64;
            let t1 = if k + 1 == pieces {
                end
            } else {
                start + (end - start) * (k + 1) as f64 / pieces as f64
            };
            refine(&eval, &deriv, t0, t1, tolerance, 0, &mut breaks);
        }
        start = end;
    }
    let mut knots = vec![a; 4];
    let mut points = Vec::with_capacity(3 * breaks.len());
    points.push(eval(a));
    for w in breaks.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        let h = t1 - t0;
        let (p0, p1) = (eval(t0), eval(t1));
        points.push(p0 + h / 3.0 * deriv(t0, t0, t1));
        points.push(p1 - h / 3.0 * deriv(t1, t0, t1));
        points.push(p1);
        knots.extend([t1; 3]);
    }
    knots.push(b);
    ModelCurve {
        degree: 3,
        knots,
        points,
        weights: None,
        exact: false,
    }
}

/// Appends the end parameters of the Hermite pieces over `[t0, t1]`,
/// bisecting while the cubic misses `C` by more than `tolerance` at `t`
/// ¼, ½, ¾ of the piece.
fn refine(
    eval: &impl Fn(f64) -> Vec3,
    deriv: &impl Fn(f64, f64, f64) -> Vec3,
    t0: f64,
    t1: f64,
    tolerance: f64,
    depth: u32,
    out: &mut Vec<f64>,
) {
    let h = t1 - t0;
    let (p0, p1, d0, d1) = (eval(t0), eval(t1), deriv(t0, t0, t1), deriv(t1, t0, t1));
    let bez = [p0, p0 + h / 3.0 * d0, p1 - h / 3.0 * d1, p1];
    let at = |x: f64| {
        let y = 1.0 - x;
        bez[0] * (y * y * y)
            + bez[1] * (3.0 * x * y * y)
            + bez[2] * (3.0 * x * x * y)
            + bez[3] * (x * x * x)
    };
    let miss = [0.25, 0.5, 0.75]
        .iter()
        .map(|&x| at(x).distance(eval(t0 + x * h)))
        .fold(0.0, f64::max);
    if depth < MAX_DEPTH && !(miss <= tolerance) {
        let tm = 0.5 * (t0 + t1);
        refine(eval, deriv, t0, tm, tolerance, depth + 1, out);
        refine(eval, deriv, tm, t1, tolerance, depth + 1, out);
    } else {
        out.push(t1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::TrimCurve;

    fn max_miss(s: &BSplineSurface, c: &TrimCurve, m: &ModelCurve) -> f64 {
        let n = crate::io::step::nurbs::Nurbs3 {
            degree: m.degree,
            knots: m.knots.clone(),
            points: m.points.clone(),
            weights: m.weights.clone(),
        };
        let [a, b] = c.domain();
        (0..=200)
            .map(|k| {
                let t = a + (b - a) * k as f64 / 200.0;
                let [u, v] = c.eval(t);
                n.eval(t).distance(s.eval(u, v))
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn model_curves_follow_their_pcurves() {
        let surfaces = crate::io::iges_write::tests::generated();
        let mut seen = [0usize; 2];
        for s in &surfaces {
            let (lo, hi) = s.control_bounding_box();
            let size = (hi - lo).length();
            for l in s.trims() {
                for c in &l.curves {
                    let m = model_curve(s, c, 1e-9 * size);
                    let miss = max_miss(s, c, &m);
                    assert!(miss <= 1e-8 * size, "miss {miss:e} exact {}", m.exact);
                    seen[usize::from(m.exact)] += 1;
                }
            }
            // the four sides of the domain: isoparametric, exact
            let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
            for (p, q) in [
                ([u0, v0], [u1, v0]),
                ([u1, v0], [u1, v1]),
                ([u1, v1], [u0, v1]),
                ([u0, v1], [u0, v0]),
            ] {
                let c = TrimCurve::line(p, q).unwrap();
                let m = model_curve(s, &c, 1e-9 * size);
                assert!(m.exact);
                assert!(max_miss(s, &c, &m) <= 1e-12 * size);
            }
        }
        assert!(seen[0] > 0, "no interpolated curve was tried");
    }
}
