//! Polylines as B-spline curves, for CAD systems: the way highlight lines
//! leave fairline as curves, the way Alias' "highlights to curves" and NX's
//! highlight-line output give them.
//!
//! [`fit_polyline`] fits a clamped cubic B-spline curve to a polyline by
//! least squares (Piegl & Tiller, *The NURBS Book*, §9.4.1): the ends are
//! interpolated, the data points get chord-length parameters, and knots are
//! inserted where the curve misses the polyline, at the median data
//! parameter of each failing span (so every span keeps data on both sides,
//! the Schoenberg–Whitney condition of a unique fit), until every data
//! point is within the tolerance, and the curve's middle of every segment
//! within the tolerance of the span from the chord's middle to the middle
//! of the cubic through the four points around it (where the line's
//! middle lies; a wave between the points leaves both). The normal equations are banded (bandwidth 3 with the small
//! second-difference term that keeps a span without data well posed) and
//! solved by a banded Cholesky factorisation: the cost is linear in the
//! number of points per round, and the rounds are few (each halves the
//! failing spans). Where no cubic within the tolerance has fewer control
//! points than the polyline has points, the cubic through every point
//! (knots by averaging) is tried; where that too misses the tolerance
//! between the points, and for polylines of fewer than four points, the
//! polyline itself is returned as a degree-1 B-spline curve (exact). Points
//! within a tenth of the tolerance of the previous one are dropped first.

use super::model_curve::ModelCurve;
use crate::Vec3;
use crate::bspline::basis::{MAX_ORDER, basis_funs};
use crate::bspline::find_span;

/// A fitted curve and how far it strays from the polyline.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedCurve {
    /// The curve (not rational; `exact` is false unless it is the
    /// polyline itself).
    pub curve: ModelCurve,
    /// The largest distance from the curve to the data points and of the
    /// segments' middles (module documentation): at most the tolerance; 0
    /// for the polyline itself.
    pub max_deviation: f64,
}

/// Rounds of knot insertion before the polyline is returned instead.
const MAX_ROUNDS: usize = 40;

/// The cubic B-spline curve through the ends of `points` within
/// `tolerance` of the polyline (module documentation); a closed polyline
/// (`closed`, last point joined to the first) gives a curve that starts and
/// ends at its first point. Repeated consecutive points are dropped. `None`
/// when fewer than two distinct finite points remain. A non-finite or
/// non-positive tolerance is taken as 0 (the polyline comes back exactly).
pub fn fit_polyline(points: &[Vec3], closed: bool, tolerance: f64) -> Option<FittedCurve> {
    let tol = if tolerance.is_finite() && tolerance > 0.0 {
        tolerance
    } else {
        0.0
    };
    let mut pts: Vec<Vec3> = Vec::with_capacity(points.len() + 1);
    let scale = points
        .iter()
        .filter(|p| p.is_finite())
        .fold(0.0_f64, |m, p| m.max(p.abs().max_element()));
    let same = 1e-12 * scale.max(f64::MIN_POSITIVE);
    // points within a tenth of the tolerance of the last one kept are
    // dropped (the last point of the line always kept): they change the
    // polyline by less than that, and near-coincident points (a line
    // crossing an edge next to a vertex) would make the fit wave
    let close = same.max(0.1 * tol);
    for (k, &p) in points.iter().enumerate() {
        if !p.is_finite() {
            return None;
        }
        let last = k + 1 == points.len();
        match pts.last() {
            None => pts.push(p),
            Some(q) if q.distance(p) > close => pts.push(p),
            Some(q) if last && q.distance(p) > same => {
                if pts.len() > 1 {
                    pts.pop();
                }
                pts.push(p);
            }
            _ => {}
        }
    }
    if closed && pts.len() > 2 && pts[0].distance(pts[pts.len() - 1]) > same {
        pts.push(pts[0]);
    }
    if pts.len() < 2 {
        return None;
    }
    let mut t = Vec::with_capacity(pts.len());
    let mut acc = 0.0;
    t.push(0.0);
    for w in pts.windows(2) {
        acc += w[0].distance(w[1]);
        t.push(acc);
    }
    if !(acc > 0.0) {
        return None;
    }
    for x in &mut t {
        *x /= acc;
    }
    let last = t.len() - 1;
    t[last] = 1.0;
    let n = pts.len();
    let degree = 3.min(n - 1);
    if degree < 3 || tol == 0.0 {
        return Some(polyline(&pts, &t));
    }
    let mut inner: Vec<f64> = Vec::new();
    for _ in 0..MAX_ROUNDS {
        // as many control points as data points: the interpolating cubic,
        // knots by averaging (Piegl & Tiller Eq. (9.8))
        let interpolating = inner.len() + degree + 1 >= n;
        if interpolating {
            inner = (1..n - degree)
                .map(|j| t[j..j + degree].iter().sum::<f64>() / degree as f64)
                .collect();
        }
        let mut knots = vec![0.0; degree + 1];
        knots.extend_from_slice(&inner);
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        let Some(ctrl) = least_squares(&pts, &t, &knots, degree) else {
            break;
        };
        let curve = ModelCurve {
            degree,
            knots,
            points: ctrl,
            weights: None,
            exact: false,
        };
        // the largest miss per span
        let spans = inner.len() + 1;
        let mut miss = vec![0.0_f64; spans];
        let span_of = |u: f64| inner.partition_point(|&k| k <= u).min(spans - 1);
        let mut worst = 0.0_f64;
        for i in 0..n {
            let d = eval(&curve, t[i]).distance(pts[i]);
            let s = span_of(t[i]);
            miss[s] = miss[s].max(d);
            worst = worst.max(d);
            if i + 1 < n {
                let um = 0.5 * (t[i] + t[i + 1]);
                // the line's middle lies between the chord's middle and
                // the estimate through the neighbouring points
                let chord = 0.5 * (pts[i] + pts[i + 1]);
                let d = segment_distance(eval(&curve, um), chord, midpoint(&pts, &t, i));
                let s = span_of(um);
                miss[s] = miss[s].max(d);
                worst = worst.max(d);
            }
        }
        if !worst.is_finite() {
            break;
        }
        if worst <= tol {
            return Some(FittedCurve {
                curve,
                max_deviation: worst,
            });
        }
        if interpolating {
            break;
        }
        // a knot at the median data parameter of each failing span
        let mut bounds = vec![0.0];
        bounds.extend_from_slice(&inner);
        bounds.push(1.0);
        let mut added = Vec::new();
        for s in 0..spans {
            if miss[s] <= tol {
                continue;
            }
            let (a, b) = (bounds[s], bounds[s + 1]);
            let lo = t.partition_point(|&x| x <= a);
            let hi = t.partition_point(|&x| x < b);
            let k = if hi > lo {
                t[(lo + hi) / 2]
            } else {
                0.5 * (a + b)
            };
            if k > a && k < b {
                added.push(k);
            }
        }
        if added.is_empty() {
            break;
        }
        inner.extend(added);
        inner.sort_by(f64::total_cmp);
    }
    Some(polyline(&pts, &t))
}

/// The polyline as a degree-1 B-spline curve with knots at its parameters.
fn polyline(pts: &[Vec3], t: &[f64]) -> FittedCurve {
    let mut knots = Vec::with_capacity(t.len() + 2);
    knots.push(0.0);
    knots.extend_from_slice(t);
    knots.push(1.0);
    FittedCurve {
        curve: ModelCurve {
            degree: 1,
            knots,
            points: pts.to_vec(),
            weights: None,
            exact: true,
        },
        max_deviation: 0.0,
    }
}

/// The point of a non-rational `curve` at `u`.
pub fn eval(curve: &ModelCurve, u: f64) -> Vec3 {
    let p = curve.degree;
    let count = curve.points.len();
    let span = find_span(&curve.knots, p, count, u);
    let mut nb = [0.0; MAX_ORDER];
    basis_funs(span, u, p, &curve.knots, &mut nb);
    let mut c = Vec3::ZERO;
    for (j, b) in nb.iter().enumerate().take(p + 1) {
        c += *b * curve.points[span - p + j];
    }
    c
}

/// The distance from `q` to the segment `a b`.
fn segment_distance(q: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let s = if l2 > 0.0 {
        ((q - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + s * ab)
}

/// The line's estimated middle between points `i` and `i + 1` of the
/// polyline: the cubic through the four points around the segment (three
/// at an end) in their chord-length parameters `t`, at the middle
/// parameter (a chord's middle misses a curved line by its sagitta, which
/// a faithful curve must not be blamed for).
fn midpoint(pts: &[Vec3], t: &[f64], i: usize) -> Vec3 {
    let n = pts.len();
    let lo = i.saturating_sub(1);
    let hi = (i + 2).min(n - 1);
    let um = 0.5 * (t[i] + t[i + 1]);
    let mut q = Vec3::ZERO;
    for a in lo..=hi {
        let mut w = 1.0;
        for b in lo..=hi {
            if b != a {
                let d = t[a] - t[b];
                // chord-length parameters of distinct points differ
                if d == 0.0 {
                    return 0.5 * (pts[i] + pts[i + 1]);
                }
                w *= (um - t[b]) / d;
            }
        }
        q += w * pts[a];
    }
    if q.is_finite() {
        q
    } else {
        0.5 * (pts[i] + pts[i + 1])
    }
}

/// The least-squares control points for `knots` with the end points
/// interpolated (Piegl & Tiller Eq. (9.63)–(9.67)), plus a second-difference
/// term 1e-9 × the largest diagonal entry that keeps spans without data
/// well posed. `None` when the banded factorisation fails.
fn least_squares(pts: &[Vec3], t: &[f64], knots: &[f64], degree: usize) -> Option<Vec<Vec3>> {
    let count = knots.len() - degree - 1;
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    // unknowns: control points 1..count-1, index j-1
    let m = count - 2;
    const BAND: usize = 3;
    // lower band: a[i][d] = A(i, i-d)
    let mut a = vec![[0.0_f64; BAND + 1]; m];
    let mut rhs = vec![Vec3::ZERO; m];
    let mut nb = [0.0; MAX_ORDER];
    for (i, &u) in t.iter().enumerate().skip(1).take(pts.len() - 2) {
        let span = find_span(knots, degree, count, u);
        basis_funs(span, u, degree, knots, &mut nb);
        let mut r = pts[i];
        for (k, &b) in nb.iter().enumerate().take(degree + 1) {
            let j = span - degree + k;
            if j == 0 {
                r -= b * first;
            } else if j == count - 1 {
                r -= b * last;
            }
        }
        for (k, &bk) in nb.iter().enumerate().take(degree + 1) {
            let jk = span - degree + k;
            if jk == 0 || jk == count - 1 {
                continue;
            }
            rhs[jk - 1] += bk * r;
            for (l, &bl) in nb.iter().enumerate().take(k + 1) {
                let jl = span - degree + l;
                if jl == 0 || jl == count - 1 {
                    continue;
                }
                a[jk - 1][jk - jl] += bk * bl;
            }
        }
    }
    let diag = a.iter().map(|r| r[0]).fold(0.0_f64, f64::max);
    let lambda = 1e-9 * diag.max(f64::MIN_POSITIVE);
    // λ Σ |P_{j-1} − 2 P_j + P_{j+1}|² over all control points, the fixed
    // ends moved to the right-hand side
    let mut all = vec![Vec3::ZERO; count];
    all[0] = first;
    all[count - 1] = last;
    for c in 1..count - 1 {
        let stencil = [(c - 1, 1.0), (c, -2.0), (c + 1, 1.0)];
        for &(j, wj) in &stencil {
            if j == 0 || j == count - 1 {
                continue;
            }
            for &(k, wk) in &stencil {
                if k == 0 || k == count - 1 {
                    rhs[j - 1] -= lambda * wj * wk * all[k];
                } else if k <= j {
                    a[j - 1][j - k] += lambda * wj * wk;
                }
            }
        }
    }
    let x = banded_cholesky_solve(&mut a, &rhs)?;
    let mut out = Vec::with_capacity(count);
    out.push(first);
    out.extend(x);
    out.push(last);
    Some(out)
}

/// Solves `A x = b` for the symmetric positive definite banded `A` given by
/// its lower band (`a[i][d] = A(i, i−d)`), factorised in place. `None`
/// when a pivot is not positive.
fn banded_cholesky_solve<const B1: usize>(a: &mut [[f64; B1]], b: &[Vec3]) -> Option<Vec<Vec3>> {
    let band = B1 - 1;
    let m = a.len();
    for j in 0..m {
        let mut s = a[j][0];
        for k in j.saturating_sub(band)..j {
            s -= a[j][j - k] * a[j][j - k];
        }
        if !(s > 0.0) || !s.is_finite() {
            return None;
        }
        let d = s.sqrt();
        a[j][0] = d;
        for i in j + 1..m.min(j + band + 1) {
            let mut s = a[i][i - j];
            for k in i.saturating_sub(band)..j {
                s -= a[i][i - k] * a[j][j - k];
            }
            a[i][i - j] = s / d;
        }
    }
    let mut y = vec![Vec3::ZERO; m];
    for i in 0..m {
        let mut s = b[i];
        for k in i.saturating_sub(band)..i {
            s -= a[i][i - k] * y[k];
        }
        y[i] = s / a[i][0];
    }
    for i in (0..m).rev() {
        let mut s = y[i];
        for k in i + 1..m.min(i + band + 1) {
            s -= a[k][k - i] * y[k];
        }
        y[i] = s / a[i][0];
    }
    Some(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                Vec3::new(r * a.cos(), r * a.sin(), 0.1 * a.sin())
            })
            .collect()
    }

    /// A dense polyline of a smooth closed curve: a few dozen control
    /// points within the tolerance, ends at the first point, every data
    /// point within the tolerance.
    #[test]
    fn a_dense_smooth_loop_becomes_a_short_cubic_within_the_tolerance() {
        let pts = circle(2000, 3.0);
        let tol = 1e-4;
        let f = fit_polyline(&pts, true, tol).unwrap();
        assert_eq!(f.curve.degree, 3);
        assert!(f.max_deviation <= tol, "{}", f.max_deviation);
        assert!(
            f.curve.points.len() < 80,
            "{} control points",
            f.curve.points.len()
        );
        assert_eq!(f.curve.points[0], pts[0]);
        assert_eq!(*f.curve.points.last().unwrap(), pts[0]);
        let mut t = vec![0.0];
        for k in 1..=pts.len() {
            t.push(t[k - 1] + pts[k - 1].distance(pts[k % pts.len()]));
        }
        for (i, p) in pts.iter().enumerate() {
            // at its chord-length parameter
            assert!(eval(&f.curve, t[i] / t[pts.len()]).distance(*p) <= tol);
        }
        assert_eq!(
            f.curve.knots.len(),
            f.curve.points.len() + 4,
            "clamped cubic knot vector"
        );
    }

    /// A line with a corner keeps the corner within the tolerance (many
    /// knots near it); a tolerance of 0 gives the polyline itself.
    #[test]
    fn corners_get_knots_and_zero_tolerance_gives_the_polyline() {
        let mut pts: Vec<Vec3> = (0..=100)
            .map(|i| Vec3::new(i as f64 / 100.0, 0.0, 0.0))
            .collect();
        pts.extend((1..=100).map(|i| Vec3::new(1.0, i as f64 / 100.0, 0.0)));
        let f = fit_polyline(&pts, false, 5e-3).unwrap();
        assert_eq!(f.curve.degree, 3);
        assert!(f.max_deviation <= 5e-3, "{}", f.max_deviation);
        assert!(f.curve.points.len() < pts.len());
        let exact = fit_polyline(&pts, false, 0.0).unwrap();
        assert_eq!(exact.curve.degree, 1);
        assert!(exact.curve.exact);
        assert_eq!(exact.curve.points, pts);
        assert_eq!(exact.max_deviation, 0.0);
        // a zigzag no cubic follows within the tolerance: the polyline
        let zig: Vec<Vec3> = (0..9)
            .map(|i| Vec3::new(i as f64, (i % 2) as f64, 0.0))
            .collect();
        let f = fit_polyline(&zig, false, 1e-3).unwrap();
        assert_eq!((f.curve.degree, f.max_deviation), (1, 0.0));
        assert_eq!(f.curve.points, zig);
    }

    /// A short polyline of a smooth curve (six points of a quarter circle,
    /// chords 1.2 % of the radius off the arc): a cubic, through its points
    /// within the tolerance.
    #[test]
    fn a_short_smooth_polyline_becomes_a_cubic() {
        let pts: Vec<Vec3> = (0..6)
            .map(|i| {
                let a = std::f64::consts::FRAC_PI_2 * i as f64 / 5.0;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let tol = 5e-3;
        let f = fit_polyline(&pts, false, tol).unwrap();
        assert_eq!(f.curve.degree, 3);
        assert!(f.max_deviation <= tol);
        for (i, p) in pts.iter().enumerate() {
            let q = eval(&f.curve, i as f64 / 5.0);
            assert!(q.distance(*p) <= tol, "{q} vs {p}");
        }
    }

    /// Degenerate input: nothing from a point, the two-point polyline as a
    /// line, repeated points dropped, no NaN from non-finite input.
    #[test]
    fn degenerate_polylines_give_no_curve_or_a_line() {
        assert!(fit_polyline(&[], false, 1e-3).is_none());
        assert!(fit_polyline(&[Vec3::ONE; 5], false, 1e-3).is_none());
        assert!(fit_polyline(&[Vec3::ZERO, Vec3::new(f64::NAN, 0.0, 0.0)], false, 1e-3).is_none());
        let f = fit_polyline(&[Vec3::ZERO, Vec3::ZERO, Vec3::X], false, 1e-3).unwrap();
        assert_eq!(f.curve.degree, 1);
        assert_eq!(f.curve.points, vec![Vec3::ZERO, Vec3::X]);
    }
}
