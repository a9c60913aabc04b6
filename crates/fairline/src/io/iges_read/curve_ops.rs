//! Exact operations on NURBS curves that the IGES surface conversions need
//! ([`super::surfaces`]): affine reparametrisation, Bézier decomposition,
//! degree elevation (Piegl & Tiller §5.5, segment by segment in homogeneous
//! coordinates), making two curves compatible (same degree and knots,
//! Piegl & Tiller §10.3) and joining curves end to start. None of them
//! changes the curve's points: every result traces the same curve.

use super::{Nurbs3, Vec3};

/// A control point in homogeneous coordinates `(w·x, w·y, w·z, w)`.
type Homogeneous = [f64; 4];

fn homogeneous(c: &Nurbs3) -> Vec<Homogeneous> {
    c.points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let w = c.weights.as_ref().map_or(1.0, |ws| ws[i]);
            [w * p.x, w * p.y, w * p.z, w]
        })
        .collect()
}

/// The curve of `degree` and `knots` whose homogeneous control points are
/// `h`; `None` when a weight is not positive and finite.
fn from_homogeneous(
    degree: usize,
    knots: Vec<f64>,
    h: &[Homogeneous],
    rational: bool,
) -> Option<Nurbs3> {
    let mut points = Vec::with_capacity(h.len());
    let mut weights = Vec::with_capacity(h.len());
    for q in h {
        if !(q[3] > 0.0 && q[3].is_finite()) {
            return None;
        }
        let p = Vec3::new(q[0], q[1], q[2]) / q[3];
        if !p.is_finite() {
            return None;
        }
        points.push(p);
        weights.push(q[3]);
    }
    Some(Nurbs3 {
        degree,
        knots,
        points,
        weights: rational.then_some(weights),
    })
}

/// The distinct knot values strictly inside the curve's domain.
fn interior_breaks(c: &Nurbs3) -> Vec<f64> {
    let [a, b] = c.domain();
    let mut out: Vec<f64> = c
        .knots
        .iter()
        .copied()
        .filter(|&k| k > a && k < b)
        .collect();
    out.dedup();
    out
}

/// The curve with its domain mapped linearly onto `[a, b]` (`a < b`);
/// `None` when its own domain is empty or not finite.
pub(super) fn reparametrised(c: &Nurbs3, a: f64, b: f64) -> Option<Nurbs3> {
    let [t0, t1] = c.domain();
    let w = t1 - t0;
    if !(w > 0.0 && w.is_finite() && b > a) {
        return None;
    }
    let s = (b - a) / w;
    let knots = c
        .knots
        .iter()
        .map(|&k| {
            if k == t0 {
                a
            } else if k == t1 {
                b
            } else {
                a + (k - t0) * s
            }
        })
        .collect();
    Some(Nurbs3 { knots, ..c.clone() })
}

/// The curve clamped to its domain with every interior knot raised to
/// multiplicity `degree` (Piegl & Tiller A5.1): its Bézier segments, point
/// `s·degree` to `(s+1)·degree` each. `None` for a degree-0 curve, a knot
/// of multiplicity above the degree inside the domain, or a failed
/// insertion.
fn bezier_form(c: &Nurbs3) -> Option<Nurbs3> {
    if c.degree == 0 {
        return None;
    }
    let [a, b] = c.domain();
    let mut c = c.between(a, b)?;
    for t in interior_breaks(&c) {
        c = c.with_knot(t)?;
    }
    let p = c.degree;
    let segments = interior_breaks(&c).len() + 1;
    (c.points.len() == segments * p + 1).then_some(c)
}

/// A Bézier segment of one degree higher (Piegl & Tiller Eq. 5.36).
fn elevate_once(b: &[Homogeneous]) -> Vec<Homogeneous> {
    let n = b.len() - 1;
    (0..=n + 1)
        .map(|i| {
            let a = i as f64 / (n + 1) as f64;
            std::array::from_fn(|c| {
                let lo = if i > 0 { a * b[i - 1][c] } else { 0.0 };
                let hi = if i <= n { (1.0 - a) * b[i][c] } else { 0.0 };
                lo + hi
            })
        })
        .collect()
}

/// The curve in Bézier form raised to degree `q` (at least its own):
/// each segment elevated exactly, the segments joined with knots of
/// multiplicity `q`.
pub(super) fn elevated(c: &Nurbs3, q: usize) -> Option<Nurbs3> {
    let c = bezier_form(c)?;
    let p = c.degree;
    if q <= p {
        return Some(c);
    }
    let [a, b] = c.domain();
    let breaks = interior_breaks(&c);
    let h = homogeneous(&c);
    let mut out = vec![h[0]];
    for s in 0..=breaks.len() {
        let mut seg = h[s * p..=s * p + p].to_vec();
        for _ in p..q {
            seg = elevate_once(&seg);
        }
        out.extend_from_slice(&seg[1..]);
    }
    let mut knots = vec![a; q + 1];
    for &t in &breaks {
        knots.extend(std::iter::repeat_n(t, q));
    }
    knots.extend(std::iter::repeat_n(b, q + 1));
    from_homogeneous(q, knots, &out, c.weights.is_some())
}

/// Two curves on `[0, 1]` of one degree and one knot vector tracing the
/// given curves (each reparametrised linearly onto `[0, 1]`, elevated to
/// the higher degree, each other's knots inserted).
pub(super) fn compatible(a: &Nurbs3, b: &Nurbs3) -> Option<(Nurbs3, Nurbs3)> {
    let q = a.degree.max(b.degree);
    let mut a = reparametrised(&elevated(a, q)?, 0.0, 1.0)?;
    let mut b = reparametrised(&elevated(b, q)?, 0.0, 1.0)?;
    let (ka, kb) = (interior_breaks(&a), interior_breaks(&b));
    for t in kb.iter().filter(|t| !ka.contains(t)) {
        a = a.with_knot(*t)?;
    }
    for t in ka.iter().filter(|t| !kb.contains(t)) {
        b = b.with_knot(*t)?;
    }
    (a.knots == b.knots && a.points.len() == b.points.len()).then_some((a, b))
}

/// Curves joined end to start into one, of their highest degree: each
/// keeps the length of its parameter range, shifted to follow the previous
/// one's, the joints are knots of multiplicity equal to the degree (C0),
/// each curve's weights are scaled (which does not change it) to meet the
/// previous one's at the joint. `None` when a curve does not start within
/// `gap` of where the previous one ends.
pub(super) fn joined(curves: &[Nurbs3], gap: f64) -> Option<Nurbs3> {
    let q = curves.iter().map(|c| c.degree).max()?;
    let rational = curves.iter().any(|c| c.weights.is_some());
    let mut knots = Vec::new();
    let mut h: Vec<Homogeneous> = Vec::new();
    let mut end = 0.0;
    let mut last_point = None;
    for (i, c) in curves.iter().enumerate() {
        let e = elevated(c, q)?;
        let [a, b] = e.domain();
        let e = if i == 0 {
            e
        } else {
            reparametrised(&e, end, end + (b - a))?
        };
        let [a, b] = e.domain();
        let mut hc = homogeneous(&e);
        if let Some(prev) = last_point {
            let first: Vec3 = e.points[0];
            if !(first.distance(prev) <= gap) {
                return None;
            }
            let s = h.last().map_or(1.0, |l: &Homogeneous| l[3]) / hc[0][3];
            for x in &mut hc {
                x.iter_mut().for_each(|v| *v *= s);
            }
            h.extend_from_slice(&hc[1..]);
        } else {
            knots.extend(std::iter::repeat_n(a, q + 1));
            h.extend_from_slice(&hc);
        }
        knots.extend(e.knots.iter().copied().filter(|&k| k > a && k < b));
        knots.extend(std::iter::repeat_n(b, q));
        end = b;
        last_point = e.points.last().copied();
    }
    knots.push(end);
    from_homogeneous(q, knots, &h, rational)
}

/// The cubic `Σ c_k s^k`, `s ∈ [0, h]`, as its four Bézier control values
/// (power basis to Bernstein basis).
pub(super) fn power_to_bezier(c: [f64; 4], h: f64) -> [f64; 4] {
    let a = [c[0], c[1] * h, c[2] * h * h, c[3] * h * h * h];
    [
        a[0],
        a[0] + a[1] / 3.0,
        a[0] + 2.0 * a[1] / 3.0 + a[2] / 3.0,
        a[0] + a[1] + a[2] + a[3],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Nurbs3 {
        Nurbs3 {
            degree: 2,
            knots: vec![1.0, 1.0, 1.0, 1.5, 2.5, 3.0, 3.0, 3.0],
            points: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 2.0, 0.5),
                Vec3::new(2.0, -1.0, 1.0),
                Vec3::new(3.0, 1.0, 0.0),
                Vec3::new(4.0, 0.5, -1.0),
            ],
            weights: Some(vec![1.0, 0.6, 1.3, 0.8, 1.0]),
        }
    }

    fn same_curve(a: &Nurbs3, b: &Nurbs3) -> f64 {
        let ([a0, a1], [b0, b1]) = (a.domain(), b.domain());
        (0..=200)
            .map(|i| {
                let x = i as f64 / 200.0;
                a.eval(a0 + x * (a1 - a0))
                    .distance(b.eval(b0 + x * (b1 - b0)))
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn elevation_and_compatibility_keep_the_curve() {
        let c = sample();
        for q in 2..6 {
            let e = elevated(&c, q).unwrap();
            assert_eq!(e.degree, q);
            assert!(same_curve(&c, &e) < 1e-13, "degree {q}");
        }
        let line = Nurbs3::segment(Vec3::ZERO, Vec3::new(0.0, 0.0, 5.0), 0.0, 1.0);
        let (a, b) = compatible(&c, &line).unwrap();
        assert_eq!(a.knots, b.knots);
        assert_eq!(a.domain(), [0.0, 1.0]);
        assert!(same_curve(&c, &a) < 1e-13);
        assert!(same_curve(&line, &b) < 1e-13);
    }

    #[test]
    fn joined_curves_pass_through_each_piece() {
        let c = sample();
        let l = Nurbs3::segment(
            Vec3::new(4.0, 0.5, -1.0),
            Vec3::new(6.0, 0.0, 0.0),
            0.0,
            2.0,
        );
        let j = joined(&[c.clone(), l.clone()], 1e-12).unwrap();
        assert_eq!(j.domain(), [1.0, 5.0]);
        for i in 0..=50 {
            let x = i as f64 / 50.0;
            assert!(j.eval(1.0 + 2.0 * x).distance(c.eval(1.0 + 2.0 * x)) < 1e-13);
            assert!(j.eval(3.0 + 2.0 * x).distance(l.eval(2.0 * x)) < 1e-13);
        }
        let far = Nurbs3::segment(Vec3::ONE, Vec3::new(2.0, 1.0, 1.0), 0.0, 1.0);
        assert!(joined(&[c, far], 1e-9).is_none());
    }

    #[test]
    fn a_cubic_in_power_form_is_its_bezier_segment() {
        let c = [0.5, -1.0, 2.0, 0.75];
        let h = 1.7;
        let b = power_to_bezier(c, h);
        for i in 0..=10 {
            let x = i as f64 / 10.0;
            let s = x * h;
            let want = c[0] + c[1] * s + c[2] * s * s + c[3] * s * s * s;
            let y = 1.0 - x;
            let got = y * y * y * b[0]
                + 3.0 * x * y * y * b[1]
                + 3.0 * x * x * y * b[2]
                + x * x * x * b[3];
            assert!((got - want).abs() < 1e-13);
        }
    }
}
