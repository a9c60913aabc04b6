//! The 3-D curve of a trim curve on its surface, `C(t) = S(c(t))` with the
//! trim curve's own parameter `t`, as a B-spline curve for an exchange file's
//! edge (what a kernel builds faces from and checks the p-curve against):
//!
//! - **exact** where the composition is a B-spline curve: on an affine
//!   surface (one bilinear span whose control points form a parallelogram,
//!   the plane of a planar face) the trim curve's control points mapped by
//!   the surface (same knots and weights); along an isoparametric line (the
//!   trim curve polynomial, one coordinate constant, the other linear in
//!   `t`) the surface's iso-curve, cut to the edge by knot insertion
//!   (Piegl & Tiller A5.1) and reparametrised affinely onto `t`;
//! - otherwise **fitted**: a cubic B-spline through `C` and `C'` at
//!   breakpoints (cubic Hermite pieces, C1 where a piece was bisected, C0 at
//!   the trim curve's knots), every piece bisected until `C` at 8 interior
//!   samples is within the tolerance (at most [`MAX_DEPTH`] bisections). The
//!   largest sampled distance is returned so the writer can state it.
//!
//! The curves are [`ModelCurve`]s, the writers' 3-D curve type. An iso
//! edge is any polynomial trim curve linear along the line, cut to the
//! edge; a fitted curve is C1 inside the trim curve's knot spans, and the
//! fit is bounded below by the rounding of the surface's points and above
//! by [`MAX_PIECES`].

use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, find_span};
use crate::io::model_curve::ModelCurve;

/// Deepest bisection of one trim-curve knot span while fitting.
pub(crate) const MAX_DEPTH: u32 = 40;

/// Most cubic pieces of one fitted curve: past it no piece is bisected
/// (the distance reached is still returned).
pub(crate) const MAX_PIECES: usize = 1 << 16;

/// The point of a 3-D (rational) B-spline curve at `t` (clamped to the
/// domain), Piegl & Tiller A4.1.
pub(crate) fn curve_point(c: &ModelCurve, t: f64) -> Vec3 {
    let p = c.degree;
    let n = c.points.len();
    let t = t.clamp(c.knots[p], c.knots[n]);
    let span = find_span(&c.knots, p, n, t);
    let mut nb = [0.0; crate::bspline::MAX_ORDER];
    crate::bspline::basis::basis_funs(span, t, p, &c.knots, &mut nb);
    let (mut a, mut w) = (Vec3::ZERO, 0.0);
    for (r, &b) in nb.iter().enumerate().take(p + 1) {
        let i = span - p + r;
        let wi = c.weights.as_ref().map_or(1.0, |ws| ws[i]);
        a += c.points[i] * (b * wi);
        w += b * wi;
    }
    a / w
}

/// How an edge curve was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// The trim curve mapped by an affine surface.
    Affine,
    /// A cut of an iso-curve of the surface.
    Iso,
    /// Cubic Hermite pieces within the tolerance.
    Fitted,
}

/// The 3-D curve of `c` on `s` (see the module documentation), how it was
/// made and the largest distance from `S(c(t))` at the fitting samples (0
/// when exact). `tolerance` (a length) bounds the fit; a non-positive one
/// fits to [`MAX_DEPTH`] (and never below 1e-13 of the surface's largest
/// coordinate, the rounding of its points); a fit stops at [`MAX_PIECES`].
pub(crate) fn edge_curve(
    s: &BSplineSurface,
    c: &TrimCurve,
    tolerance: f64,
) -> (ModelCurve, Kind, f64) {
    if let Some(curve) = affine(s, c) {
        return (curve, Kind::Affine, 0.0);
    }
    if let Some(curve) = iso(s, c) {
        return (curve, Kind::Iso, 0.0);
    }
    let (curve, dev) = fitted(s, c, tolerance);
    (curve, Kind::Fitted, dev)
}

/// `S(u, v) = O + (u − u0)/(u1 − u0)·A + (v − v0)/(v1 − v0)·B` when `s` is
/// one bilinear polynomial span on a parallelogram (the difference of the
/// diagonals exactly zero, or within 1e-15 of the net's size).
fn affine(s: &BSplineSurface, c: &TrimCurve) -> Option<ModelCurve> {
    if s.degree_u() != 1 || s.degree_v() != 1 || s.count_u() != 2 || s.count_v() != 2 {
        return None;
    }
    if let Some(w) = s.weights()
        && w.iter().any(|&x| x.to_bits() != w[0].to_bits())
    {
        return None;
    }
    let (p00, p10, p01, p11) = (
        s.control_point(0, 0),
        s.control_point(1, 0),
        s.control_point(0, 1),
        s.control_point(1, 1),
    );
    let size = (p10 - p00).length() + (p01 - p00).length();
    if (p11 - p10 - p01 + p00).length() > 1e-15 * size {
        return None;
    }
    let [u0, u1] = s.domain_u();
    let [v0, v1] = s.domain_v();
    let (a, b) = (p10 - p00, p01 - p00);
    let points = c
        .control_points()
        .iter()
        .map(|&[u, v]| p00 + a * ((u - u0) / (u1 - u0)) + b * ((v - v0) / (v1 - v0)))
        .collect();
    Some(ModelCurve {
        degree: c.degree(),
        knots: c.knots().to_vec(),
        points,
        weights: c.weights().map(<[f64]>::to_vec),
        exact: true,
    })
}

/// `x(t) = a·t + b` when coordinate `k` of the polynomial curve `c` is
/// linear (its coefficients lie on a line over the Greville abscissae, the
/// B-spline's linear precision, within 1e-13 of their size).
fn linear(c: &TrimCurve, k: usize) -> Option<(f64, f64)> {
    if c.weights().is_some() {
        return None;
    }
    let p = c.degree();
    let kn = c.knots();
    let pts = c.control_points();
    let g = |i: usize| kn[i + 1..=i + p].iter().sum::<f64>() / p as f64;
    let n = pts.len();
    let (g0, g1) = (g(0), g(n - 1));
    if g1 <= g0 {
        return None;
    }
    let a = (pts[n - 1][k] - pts[0][k]) / (g1 - g0);
    let b = pts[0][k] - a * g0;
    let scale = pts.iter().map(|q| q[k].abs()).fold(0.0, f64::max) + (a * (g1 - g0)).abs();
    (0..n)
        .all(|i| (pts[i][k] - (a * g(i) + b)).abs() <= 1e-13 * scale)
        .then_some((a, b))
}

/// The cut of the surface's iso-curve that `c` traces, when `c` is
/// isoparametric (see the module documentation).
fn iso(s: &BSplineSurface, c: &TrimCurve) -> Option<ModelCurve> {
    let pts = c.control_points();
    for fixed in 0..2 {
        let x0 = pts[0][fixed];
        if pts.iter().any(|q| q[fixed].to_bits() != x0.to_bits()) {
            continue;
        }
        let run = 1 - fixed;
        let (a, b) = linear(c, run)?;
        if a == 0.0 {
            return None;
        }
        let (degree, knots, net) = iso_net(s, fixed, x0);
        let [t0, t1] = c.domain();
        let (wa, wb) = (a * t0 + b, a * t1 + b);
        let (lo, hi) = if wa < wb { (wa, wb) } else { (wb, wa) };
        let [d0, d1] = [knots[degree], knots[net.len()]];
        if !(lo >= d0 && hi <= d1 && lo < hi) {
            return None;
        }
        let (mut knots, mut net) = cut(degree, knots, net, lo, hi)?;
        // t = (x − b) / a onto the trim curve's parameter, ends exact.
        let m = knots.len();
        let mut tk: Vec<f64> = knots.iter().map(|&x| (x - b) / a).collect();
        if a < 0.0 {
            tk.reverse();
            net.reverse();
        }
        for (i, k) in tk.iter_mut().enumerate() {
            if i <= degree {
                *k = t0;
            } else if i >= m - degree - 1 {
                *k = t1;
            } else {
                *k = k.clamp(t0, t1);
            }
        }
        for i in 1..m {
            if tk[i] < tk[i - 1] {
                tk[i] = tk[i - 1];
            }
        }
        knots = tk;
        let rational = net.iter().any(|h| h[3].to_bits() != 1f64.to_bits());
        let points = net
            .iter()
            .map(|h| Vec3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]))
            .collect();
        let curve = ModelCurve {
            degree,
            knots,
            points,
            weights: rational.then(|| net.iter().map(|h| h[3]).collect()),
            exact: true,
        };
        // A check of the construction (an unclamped surface's end, say):
        // the cut agrees with S(c(t)) to rounding, or the edge is fitted.
        let size = curve
            .points
            .iter()
            .map(|q| q.abs().max_element())
            .fold(0.0, f64::max);
        let agrees = (0..=16).all(|i| {
            let t = t0 + (t1 - t0) * i as f64 / 16.0;
            let [u, v] = c.eval(t);
            curve_point(&curve, t).distance(s.eval(u, v)) <= 1e-11 * size.max(f64::MIN_POSITIVE)
        });
        return agrees.then_some(curve);
    }
    None
}

/// The homogeneous control net `[w·P, w]` of the iso-curve of `s` with
/// coordinate `fixed` (0: u, 1: v) at `x`, with its degree and knots.
fn iso_net(s: &BSplineSurface, fixed: usize, x: f64) -> (usize, Vec<f64>, Vec<[f64; 4]>) {
    let (p, kn, n, q, other, m) = if fixed == 0 {
        (
            s.degree_u(),
            s.knots_u(),
            s.count_u(),
            s.degree_v(),
            s.knots_v(),
            s.count_v(),
        )
    } else {
        (
            s.degree_v(),
            s.knots_v(),
            s.count_v(),
            s.degree_u(),
            s.knots_u(),
            s.count_u(),
        )
    };
    let span = find_span(kn, p, n, x);
    let mut nb = [0.0; crate::bspline::MAX_ORDER];
    crate::bspline::basis::basis_funs(span, x, p, kn, &mut nb);
    let net = (0..m)
        .map(|j| {
            let mut h = [0.0; 4];
            for (r, &bf) in nb.iter().enumerate().take(p + 1) {
                let i = span - p + r;
                let (ii, jj) = if fixed == 0 { (i, j) } else { (j, i) };
                let w = s.weight(ii, jj);
                let pt = s.control_point(ii, jj);
                h[0] += bf * w * pt.x;
                h[1] += bf * w * pt.y;
                h[2] += bf * w * pt.z;
                h[3] += bf * w;
            }
            h
        })
        .collect();
    (q, other.to_vec(), net)
}

/// Inserts `x` once (Boehm, Piegl & Tiller A5.1 with r = 1) into the curve
/// of `degree`, `knots` and homogeneous `net`. Requires
/// `knots[degree] <= x < knots[net.len()]`.
fn insert(degree: usize, knots: &mut Vec<f64>, net: &mut Vec<[f64; 4]>, x: f64) {
    let p = degree;
    let n = net.len();
    let k = find_span(knots, p, n, x);
    let s = knots.iter().filter(|&&y| y == x).count();
    let mut q = Vec::with_capacity(n + 1);
    for i in 0..=n {
        if i + p <= k {
            q.push(net[i]);
        } else if i + s > k {
            q.push(net[i - 1]);
        } else {
            let al = (x - knots[i]) / (knots[i + p] - knots[i]);
            let (a, b) = (net[i], net[i - 1]);
            q.push([
                al * a[0] + (1.0 - al) * b[0],
                al * a[1] + (1.0 - al) * b[1],
                al * a[2] + (1.0 - al) * b[2],
                al * a[3] + (1.0 - al) * b[3],
            ]);
        }
    }
    knots.insert(k + 1, x);
    *net = q;
}

/// The piece of the curve over `[lo, hi]` (inside its domain, `lo < hi`):
/// both ends inserted to multiplicity `degree`, the knots clamped there.
fn cut(
    degree: usize,
    mut knots: Vec<f64>,
    mut net: Vec<[f64; 4]>,
    lo: f64,
    hi: f64,
) -> Option<(Vec<f64>, Vec<[f64; 4]>)> {
    let p = degree;
    for x in [lo, hi] {
        let end = knots[net.len()];
        if x >= end {
            continue;
        }
        while knots.iter().filter(|&&y| y == x).count() < p {
            insert(p, &mut knots, &mut net, x);
        }
    }
    // C(lo) = P[k − p] with k the last knot index at lo (at or after the
    // domain start); C(hi) = P[m − 1] with m the first knot index at hi.
    let n = net.len();
    let k = (p..n).rev().find(|&i| knots[i] <= lo)?;
    let m = (k + 1..=n).find(|&i| knots[i] >= hi)?;
    if k < p || m < k + 1 || m - 1 < k - p {
        return None;
    }
    let pts = net[k - p..m].to_vec();
    let mut kn = vec![lo; p + 1];
    kn.extend_from_slice(&knots[k + 1..m]);
    kn.extend(std::iter::repeat_n(hi, p + 1));
    (kn.len() == pts.len() + p + 1).then_some((kn, pts))
}

/// `S(c(t))` and its derivative in `t` (the trim curve's derivative from
/// the side `left` says).
fn composite(s: &BSplineSurface, c: &TrimCurve, t: f64, left: bool) -> (Vec3, Vec3) {
    let ([u, v], [du, dv]) = c.eval_d1(t, left);
    let d = s.derivatives(u, v);
    (d.point, d.su * du + d.sv * dv)
}

/// One cubic piece `[t0, t1]` in Bézier form.
struct Piece {
    t1: f64,
    bez: [Vec3; 4],
    /// The piece ends at a trim-curve knot (C0 join to the next).
    corner: bool,
}

fn bezier(b: &[Vec3; 4], x: f64) -> Vec3 {
    let y = 1.0 - x;
    b[0] * (y * y * y) + b[1] * (3.0 * x * y * y) + b[2] * (3.0 * x * x * y) + b[3] * (x * x * x)
}

/// Hermite pieces from `(t0, P0, D0)` to `(t1, P1, D1)`, bisected until
/// within `tol`; appends them to `out` and returns the largest sampled
/// distance.
#[allow(clippy::too_many_arguments)]
fn fit_span(
    s: &BSplineSurface,
    c: &TrimCurve,
    (t0, p0, d0): (f64, Vec3, Vec3),
    (t1, p1, d1): (f64, Vec3, Vec3),
    tol: f64,
    depth: u32,
    corner: bool,
    out: &mut Vec<Piece>,
) -> f64 {
    let h = t1 - t0;
    let bez = [p0, p0 + d0 * (h / 3.0), p1 - d1 * (h / 3.0), p1];
    let mut err = 0.0f64;
    for k in 1..=8 {
        // Samples off the bisection points, so that the halves are
        // checked where this piece was not.
        let x = (k as f64 - 0.37) / 8.0 + 0.02;
        let [u, v] = c.eval(t0 + h * x);
        err = err.max(bezier(&bez, x).distance(s.eval(u, v)));
    }
    if !(err > tol) || depth >= MAX_DEPTH || out.len() >= MAX_PIECES || !err.is_finite() {
        out.push(Piece { t1, bez, corner });
        return if err.is_finite() { err } else { f64::INFINITY };
    }
    let tm = t0 + 0.5 * h;
    let (pm, dm) = composite(s, c, tm, false);
    let a = fit_span(s, c, (t0, p0, d0), (tm, pm, dm), tol, depth + 1, false, out);
    let b = fit_span(
        s,
        c,
        (tm, pm, dm),
        (t1, p1, d1),
        tol,
        depth + 1,
        corner,
        out,
    );
    a.max(b)
}

/// The fitted cubic (see the module documentation) and its largest sampled
/// distance from `S(c(t))`.
fn fitted(s: &BSplineSurface, c: &TrimCurve, tol: f64) -> (ModelCurve, f64) {
    // Not below the rounding of the surface's coordinates.
    let (lo, hi) = s.control_bounding_box();
    let tol = tol.max(1e-13 * lo.abs().max(hi.abs()).max_element());
    let [t0, t1] = c.domain();
    let mut breaks = vec![t0];
    for &k in c.knots() {
        if k > *breaks.last().unwrap_or(&t0) && k < t1 {
            breaks.push(k);
        }
    }
    breaks.push(t1);
    let mut pieces = Vec::new();
    let mut dev = 0.0f64;
    for w in breaks.windows(2) {
        let (p0, d0) = composite(s, c, w[0], false);
        let (p1, d1) = composite(s, c, w[1], true);
        dev = dev.max(fit_span(
            s,
            c,
            (w[0], p0, d0),
            (w[1], p1, d1),
            tol,
            0,
            true,
            &mut pieces,
        ));
    }
    let mut knots = vec![t0; 4];
    let mut points = pieces.first().map(|p| p.bez.to_vec()).unwrap_or_default();
    for w in pieces.windows(2) {
        let (prev, next) = (&w[0], &w[1]);
        if prev.corner {
            knots.extend([prev.t1; 3]);
        } else {
            knots.extend([prev.t1; 2]);
            points.pop();
        }
        points.extend_from_slice(&next.bez[1..]);
    }
    knots.extend([t1; 4]);
    (
        ModelCurve {
            degree: 3,
            knots,
            points,
            weights: None,
            exact: false,
        },
        dev,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::{TrimCurve, TrimLoop};

    /// Largest distance of the curve from `S(c(t))` at 2001 parameters.
    fn distance(s: &BSplineSurface, c: &TrimCurve, e: &ModelCurve) -> f64 {
        let [t0, t1] = c.domain();
        assert_eq!(e.knots[0], t0);
        assert_eq!(*e.knots.last().unwrap(), t1);
        assert_eq!(e.knots.len(), e.points.len() + e.degree + 1);
        (0..=2000)
            .map(|i| {
                let t = t0 + (t1 - t0) * i as f64 / 2000.0;
                let [u, v] = c.eval(t);
                curve_point(e, t).distance(s.eval(u, v))
            })
            .fold(0.0, f64::max)
    }

    /// A rational biquadratic patch: a quarter of a cylinder of radius 10
    /// (u around, v along the axis, cubic in v with a bulge).
    fn rational_patch() -> BSplineSurface {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let ring = [(10.0, 0.0, 1.0), (10.0, 10.0, h), (0.0, 10.0, 1.0)];
        let mut pts = Vec::new();
        let mut ws = Vec::new();
        for &(x, y, w) in &ring {
            let mut row = Vec::new();
            for (j, z) in [0.0, 3.0, 7.0, 12.0].iter().enumerate() {
                let bulge = if j == 1 || j == 2 { 1.3 } else { 1.0 };
                row.push(Vec3::new(x * bulge, y * bulge, *z));
            }
            pts.push(row);
            ws.push(vec![w; 4]);
        }
        BSplineSurface::new(
            2,
            3,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0],
            pts,
            Some(ws),
        )
        .unwrap()
    }

    #[test]
    fn iso_edges_are_the_surface_iso_curves_exactly() {
        let s = rational_patch();
        // u = 0.3 from v = 1.7 down to v = 0.2 (reversed, cut inside), and
        // v = 0.5 over the whole of u.
        for c in [
            TrimCurve::new(
                1,
                vec![5.0, 5.0, 8.0, 8.0],
                vec![[0.3, 1.7], [0.3, 0.2]],
                None,
            )
            .unwrap(),
            TrimCurve::line([0.0, 0.5], [1.0, 0.5]).unwrap(),
            TrimCurve::line([1.0, 2.0], [1.0, 0.0]).unwrap(),
        ] {
            let (e, kind, dev) = edge_curve(&s, &c, 1e-9);
            assert_eq!(kind, Kind::Iso);
            assert_eq!(dev, 0.0);
            let d = distance(&s, &c, &e);
            assert!(d < 1e-12, "{d}");
        }
    }

    #[test]
    fn planar_edges_map_the_trim_curve_exactly() {
        let s = BSplineSurface::new(
            1,
            1,
            vec![0.0, 0.0, 2.0, 2.0],
            vec![-1.0, -1.0, 1.0, 1.0],
            vec![
                vec![Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 4.0, 1.0)],
                vec![Vec3::new(6.0, 1.0, 3.0), Vec3::new(6.0, 5.0, 3.0)],
            ],
            None,
        )
        .unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let arc = TrimCurve::new(
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![[1.5, 0.0], [1.5, 0.5], [1.0, 0.5]],
            Some(vec![1.0, h, 1.0]),
        )
        .unwrap();
        let (e, kind, _) = edge_curve(&s, &arc, 1e-9);
        assert_eq!(kind, Kind::Affine);
        assert!(e.weights.is_some());
        assert!(distance(&s, &arc, &e) < 1e-13);
    }

    #[test]
    fn fitted_edges_are_within_the_tolerance_and_fail_without_fitting() {
        let s = rational_patch();
        // A rational cubic wave across the patch with a C0 corner (a
        // double knot of a quadratic) in the middle.
        let c = TrimCurve::new(
            2,
            vec![0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0],
            vec![[0.05, 0.1], [0.5, 0.2], [0.4, 1.0], [0.9, 1.2], [0.95, 1.9]],
            Some(vec![1.0, 2.0, 1.0, 0.5, 1.0]),
        )
        .unwrap();
        for tol in [1e-4, 1e-7, 1e-10] {
            let (e, kind, dev) = edge_curve(&s, &c, tol);
            assert_eq!(kind, Kind::Fitted);
            assert!(dev <= tol, "{dev} > {tol}");
            let d = distance(&s, &c, &e);
            // Dense samples, not only the fit's: within twice the tolerance.
            assert!(d <= 2.0 * tol, "tolerance {tol}: {d}");
        }
        // The fit is not trivially exact: a coarse tolerance leaves a
        // measurable distance that a finer one removes.
        let (coarse, _, _) = edge_curve(&s, &c, 1e-2);
        assert!(distance(&s, &c, &coarse) > 1e-6);
        let loops = TrimLoop { curves: vec![c] };
        assert_eq!(loops.curves.len(), 1);
    }

    #[test]
    fn fits_far_from_the_origin_stop_at_the_rounding_of_the_points() {
        // The patch moved 1e9 away: a tolerance of 1e-12 is below the
        // rounding of its points (about 1e-7); the fit stops there instead
        // of bisecting every piece to the deepest level.
        let s0 = rational_patch();
        let far = Vec3::splat(1e9);
        let net: Vec<Vec<Vec3>> = (0..s0.count_u())
            .map(|i| {
                (0..s0.count_v())
                    .map(|j| s0.control_point(i, j) + far)
                    .collect()
            })
            .collect();
        let w: Vec<Vec<f64>> = (0..s0.count_u())
            .map(|i| (0..s0.count_v()).map(|j| s0.weight(i, j)).collect())
            .collect();
        let s = BSplineSurface::new(
            2,
            3,
            s0.knots_u().to_vec(),
            s0.knots_v().to_vec(),
            net,
            Some(w),
        )
        .unwrap();
        let c = TrimCurve::new(
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![[0.1, 0.1], [0.5, 1.9], [0.9, 0.3]],
            None,
        )
        .unwrap();
        let (e, kind, dev) = edge_curve(&s, &c, 1e-12);
        assert_eq!(kind, Kind::Fitted);
        assert!(e.points.len() < 2000, "{} points", e.points.len());
        assert!(dev < 1e-3, "{dev}");
    }
}
