//! Exact NURBS forms of the STEP curves and surfaces (ISO 10303-42 §4.4):
//! lines, circles and ellipses as rational quadratic arcs (Piegl & Tiller
//! A7.1), and the surfaces of revolution of a profile (Piegl & Tiller A8.1)
//! that give cylinders, cones, spheres, tori and general surfaces of
//! revolution; linear extrusions as ruled surfaces (Piegl & Tiller §8.3).

use crate::Vec3;
use crate::bspline::basis::{MAX_ORDER, basis_funs, find_span};

/// A (rational) B-spline curve in 3-D (2-D curves have `z = 0`).
#[derive(Clone, Debug, PartialEq)]
pub struct Nurbs3 {
    /// Degree.
    pub degree: usize,
    /// Knot vector (`points + degree + 1` knots).
    pub knots: Vec<f64>,
    /// Control points.
    pub points: Vec<Vec3>,
    /// Weights, `None` when polynomial.
    pub weights: Option<Vec<f64>>,
}

impl Nurbs3 {
    /// Parameter domain `[knots[p], knots[n]]`.
    pub fn domain(&self) -> [f64; 2] {
        [self.knots[self.degree], self.knots[self.points.len()]]
    }

    /// The curve point at `t` (clamped to the domain), Piegl & Tiller A4.1.
    pub fn eval(&self, t: f64) -> Vec3 {
        let [a, b] = self.domain();
        let t = if t >= a { t.min(b) } else { a };
        let p = self.degree;
        let span = find_span(&self.knots, p, self.points.len(), t);
        let mut nb = [0.0; MAX_ORDER];
        basis_funs(span, t, p, &self.knots, &mut nb);
        let (mut q, mut w) = (Vec3::ZERO, 0.0);
        for (r, &b) in nb.iter().enumerate().take(p + 1) {
            let i = span - p + r;
            let wi = self.weights.as_ref().map_or(1.0, |ws| ws[i]);
            q += b * wi * self.points[i];
            w += b * wi;
        }
        if w > 0.0 && w.is_finite() {
            q / w
        } else {
            self.points[span - p]
        }
    }

    /// The same curve traversed backwards (knots mirrored, points reversed).
    pub fn reversed(&self) -> Nurbs3 {
        let (a, b) = (self.knots[0], self.knots[self.knots.len() - 1]);
        Nurbs3 {
            degree: self.degree,
            knots: self.knots.iter().rev().map(|k| a + b - k).collect(),
            points: self.points.iter().rev().copied().collect(),
            weights: self
                .weights
                .as_ref()
                .map(|w| w.iter().rev().copied().collect()),
        }
    }

    /// The piece of the curve over `[t0, t1]` (either way round: a
    /// reversed piece when `t1 < t0`) as an exact NURBS: both ends inserted
    /// as knots of multiplicity `degree` (Piegl & Tiller A5.1) and the
    /// control points between them kept (Piegl & Tiller §5.3, curve
    /// splitting). Ends within 1e-12 of the domain width of a knot are
    /// snapped to it. `None` when the piece is empty or leaves the domain.
    pub fn between(&self, t0: f64, t1: f64) -> Option<Nurbs3> {
        if t1 < t0 {
            return self.between(t1, t0).map(|c| c.reversed());
        }
        let [a, b] = self.domain();
        let eps = 1e-12 * (b - a);
        if !(t0 >= a - eps && t1 <= b + eps && t1 - t0 > eps) {
            return None;
        }
        let snap = |t: f64| {
            self.knots
                .iter()
                .copied()
                .find(|k| (k - t).abs() <= eps)
                .unwrap_or(t)
                .clamp(a, b)
        };
        let (t0, t1) = (snap(t0), snap(t1));
        let c = self.with_knot(t0)?.with_knot(t1)?;
        let p = c.degree;
        // C(t0) = P[last index of t0 − p], C(t1) = P[first index of t1 − 1].
        let la = c.knots.iter().rposition(|&k| k == t0)?;
        let fb = c.knots.iter().position(|&k| k == t1)?;
        if la < p || fb <= la || fb > c.points.len() {
            return None;
        }
        let (i0, i1) = (la - p, fb - 1);
        let mut knots = vec![t0; p + 1];
        knots.extend_from_slice(&c.knots[la + 1..fb]);
        knots.extend(std::iter::repeat_n(t1, p + 1));
        Some(Nurbs3 {
            degree: p,
            knots,
            points: c.points[i0..=i1].to_vec(),
            weights: c.weights.as_ref().map(|w| w[i0..=i1].to_vec()),
        })
    }

    /// The same curve with the knot `t` inserted until its multiplicity is
    /// at least the degree (Piegl & Tiller A5.1, in homogeneous
    /// coordinates, so exact for rational curves too). `None` when `t` is
    /// not inside the knot vector's usable range.
    pub(crate) fn with_knot(&self, t: f64) -> Option<Nurbs3> {
        let p = self.degree;
        let n = self.points.len();
        let s = self.knots.iter().filter(|&&k| k == t).count();
        if s >= p {
            return Some(self.clone());
        }
        let r = p - s;
        // The span k: knots[k] <= t < knots[k + 1].
        let k = self.knots.iter().rposition(|&x| x <= t)?;
        if k < p || k >= n {
            return None;
        }
        let w = |i: usize| self.weights.as_ref().map_or(1.0, |ws| ws[i]);
        let pw: Vec<[f64; 4]> = (0..n)
            .map(|i| {
                let q = self.points[i] * w(i);
                [q.x, q.y, q.z, w(i)]
            })
            .collect();
        let lerp = |x: [f64; 4], y: [f64; 4], alpha: f64| {
            std::array::from_fn(|c| alpha * y[c] + (1.0 - alpha) * x[c])
        };
        let mut knots = Vec::with_capacity(self.knots.len() + r);
        knots.extend_from_slice(&self.knots[..=k]);
        knots.extend(std::iter::repeat_n(t, r));
        knots.extend_from_slice(&self.knots[k + 1..]);
        let mut qw = vec![[0.0; 4]; n + r];
        qw[..=k - p].copy_from_slice(&pw[..=k - p]);
        qw[k - s + r..n + r].copy_from_slice(&pw[k - s..n]);
        let mut rw: Vec<[f64; 4]> = (0..=p - s).map(|i| pw[k - p + i]).collect();
        let mut l = k - p;
        for j in 1..=r {
            l = k - p + j;
            for i in 0..=p - j - s {
                let den = self.knots[i + k + 1] - self.knots[l + i];
                if den <= 0.0 {
                    return None;
                }
                rw[i] = lerp(rw[i], rw[i + 1], (t - self.knots[l + i]) / den);
            }
            qw[l] = rw[0];
            qw[k + r - j - s] = rw[p - j - s];
        }
        if l + 1 < k - s {
            qw[l + 1..k - s].copy_from_slice(&rw[1..k - s - l]);
        }
        let rational = self.weights.is_some();
        let mut points = Vec::with_capacity(n + r);
        let mut weights = Vec::with_capacity(n + r);
        for q in &qw {
            if !(q[3] > 0.0 && q[3].is_finite()) {
                return None;
            }
            points.push(Vec3::new(q[0], q[1], q[2]) / q[3]);
            weights.push(q[3]);
        }
        Some(Nurbs3 {
            degree: p,
            knots,
            points,
            weights: rational.then_some(weights),
        })
    }

    /// The straight segment from `a` to `b`, parameter `[t0, t1]`.
    pub fn segment(a: Vec3, b: Vec3, t0: f64, t1: f64) -> Nurbs3 {
        Nurbs3 {
            degree: 1,
            knots: vec![t0, t0, t1, t1],
            points: vec![a, b],
            weights: None,
        }
    }
}

/// Equal rational quadratic arcs covering the angles `[start, start +
/// sweep]` (`sweep` may be negative), each at most 90°, with the curve
/// parameter proportional to the arc index: arc `k` spans `[scale·(start +
/// k·d), scale·(start + (k+1)·d)]`, `d = sweep / arcs` (Piegl & Tiller A7.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcMap {
    /// First angle (radians).
    pub start: f64,
    /// Signed sweep (radians).
    pub sweep: f64,
    /// Number of arcs.
    pub arcs: usize,
    /// Parameter units per radian.
    pub scale: f64,
}

impl ArcMap {
    /// Arcs of at most 90° over `[a0, a1]` (`a1 > a0`), parameter `scale`
    /// per radian.
    pub fn new(a0: f64, a1: f64, scale: f64) -> Self {
        let sweep = a1 - a0;
        let arcs =
            ((sweep.abs() / std::f64::consts::FRAC_PI_2 - 1e-9).ceil() as usize).clamp(1, 64);
        Self {
            start: a0,
            sweep,
            arcs,
            scale,
        }
    }

    fn step(&self) -> f64 {
        self.sweep / self.arcs as f64
    }

    /// The knot vector (degree 2, double interior knots).
    pub fn knots(&self) -> Vec<f64> {
        let d = self.step();
        let at = |k: usize| self.scale * (self.start + k as f64 * d);
        let mut k = vec![at(0); 3];
        for i in 1..self.arcs {
            k.push(at(i));
            k.push(at(i));
        }
        k.extend([at(self.arcs); 3]);
        k
    }

    /// The `2·arcs + 1` control angles and their weights: the arc ends
    /// (weight 1) and the arc middles, whose control point lies at radius
    /// `1 / cos(d/2)` (weight `cos(d/2)`).
    pub fn controls(&self) -> Vec<(f64, f64, f64)> {
        let d = self.step();
        let w = (0.5 * d).cos();
        let mut out = vec![(self.start, 1.0, 1.0)];
        for k in 0..self.arcs {
            let a = self.start + k as f64 * d;
            out.push((a + 0.5 * d, 1.0 / w, w));
            out.push((a + d, 1.0, 1.0));
        }
        out
    }

    /// The curve parameter of the point at angle `a` (in the swept range):
    /// within an arc of half-angle `h`, `tan(ψ/2) = tan(h/2)·(2s − 1)` with
    /// `ψ` the angle from the arc's middle and `s ∈ [0, 1]` the arc's local
    /// parameter.
    pub fn param(&self, a: f64) -> f64 {
        let d = self.step();
        if d == 0.0 {
            return self.scale * self.start;
        }
        let x = ((a - self.start) / d).clamp(0.0, self.arcs as f64);
        let k = (x.floor() as usize).min(self.arcs - 1);
        let mid = self.start + (k as f64 + 0.5) * d;
        let h = 0.5 * d;
        let s = 0.5 * ((0.5 * (a - mid)).tan() / (0.5 * h).tan() + 1.0);
        self.scale * (self.start + (k as f64 + s.clamp(0.0, 1.0)) * d)
    }
}

/// The arc of radius `r` in the plane of `(x, y)` around `c` through the
/// angles of `map`: points `c + r(cos a·x + sin a·y)`.
pub fn arc(c: Vec3, x: Vec3, y: Vec3, r: f64, map: &ArcMap) -> Nurbs3 {
    ellipse_arc(c, x, y, r, r, map)
}

/// The elliptic arc `c + rx·cos a·x + ry·sin a·y` (an affine image of the
/// circle, so the same weights hold).
pub fn ellipse_arc(c: Vec3, x: Vec3, y: Vec3, rx: f64, ry: f64, map: &ArcMap) -> Nurbs3 {
    let ctl = map.controls();
    Nurbs3 {
        degree: 2,
        knots: map.knots(),
        points: ctl
            .iter()
            .map(|&(a, f, _)| c + f * (rx * a.cos() * x + ry * a.sin() * y))
            .collect(),
        weights: Some(ctl.iter().map(|&(_, _, w)| w).collect()),
    }
}

/// The surface swept by rotating `profile` about the axis through `c` along
/// the unit `z`, through the angles of `map` measured from the profile's own
/// position (Piegl & Tiller A8.1): `u` is the angle direction, `v` the
/// profile's parameter. Control points `P_ij` are laid out `i` along u.
pub fn revolve(
    c: Vec3,
    z: Vec3,
    profile: &Nurbs3,
    map: &ArcMap,
) -> (Vec<f64>, Vec<Vec3>, Vec<f64>) {
    let ctl = map.controls();
    let nv = profile.points.len();
    let mut points = Vec::with_capacity(ctl.len() * nv);
    let mut weights = Vec::with_capacity(ctl.len() * nv);
    for &(a, f, w) in &ctl {
        let (s, co) = a.sin_cos();
        for (j, &p) in profile.points.iter().enumerate() {
            let d = p - c;
            let h = d.dot(z);
            let rho = d - h * z;
            let rot = co * rho + s * z.cross(rho);
            points.push(c + h * z + f * rot);
            weights.push(w * profile.weights.as_ref().map_or(1.0, |ws| ws[j]));
        }
    }
    (map.knots(), points, weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_piece_between_two_parameters_is_the_same_curve_there() {
        // A rational cubic with interior knots (one double), split at
        // parameters inside spans, on knots and at the ends, both ways.
        let points: Vec<Vec3> = (0..7)
            .map(|i| {
                let t = i as f64;
                Vec3::new(t, (0.7 * t).sin() * 2.0, 0.3 * t * t)
            })
            .collect();
        let c = Nurbs3 {
            degree: 3,
            knots: vec![0.0, 0.0, 0.0, 0.0, 0.4, 1.1, 1.1, 2.0, 2.0, 2.0, 2.0],
            points,
            weights: Some(vec![1.0, 0.7, 1.4, 0.9, 1.2, 0.8, 1.0]),
        };
        for &(t0, t1) in &[
            (0.13, 1.7),
            (0.4, 1.1),
            (0.0, 2.0),
            (0.0, 0.05),
            (1.1, 2.0),
            (1.9, 0.2),
            (0.7, 0.71),
        ] {
            let piece = c.between(t0, t1).unwrap();
            let [a, b] = piece.domain();
            // (reversing mirrors the knots: a + b − k, exact to rounding)
            assert!((a - t0.min(t1)).abs() < 1e-15 && (b - t0.max(t1)).abs() < 1e-15);
            for k in 0..=50 {
                let s = a + (b - a) * k as f64 / 50.0;
                // The original parameter of piece parameter s.
                let t = if t1 < t0 { t0 + t1 - s } else { s };
                let d = piece.eval(s).distance(c.eval(t));
                assert!(d < 1e-12, "[{t0}, {t1}] at {s}: {d:e}");
            }
            assert!(piece.eval(a).distance(c.eval(t0)) < 1e-12);
            assert!(piece.eval(b).distance(c.eval(t1)) < 1e-12);
        }
        assert!(c.between(0.5, 0.5).is_none());
        assert!(c.between(-1.0, 0.5).is_none());
    }

    #[test]
    fn step_arcs_are_exact_circles_and_param_inverts_the_angle() {
        for &(a0, a1) in &[(0.0, 2.0 * PI), (-0.3, 1.0), (1.0, 1.2), (0.5, 0.5 + 3.0)] {
            let map = ArcMap::new(a0, a1, 2.5);
            let c = arc(Vec3::ZERO, Vec3::X, Vec3::Y, 3.0, &map);
            let [t0, t1] = c.domain();
            for k in 0..=200 {
                let t = t0 + (t1 - t0) * k as f64 / 200.0;
                let p = c.eval(t);
                assert!((p.length() - 3.0).abs() < 1e-12, "{p:?}");
                // The angle nearest to a rough estimate (the parameter is
                // nearly proportional to the angle).
                let guess = t / 2.5;
                let mut a = p.y.atan2(p.x);
                a += 2.0 * PI * ((guess - a) / (2.0 * PI)).round();
                assert!((map.param(a) - t).abs() < 1e-9 * (1.0 + t.abs()), "{a} {t}");
            }
            assert!((c.eval(t1) - Vec3::new(3.0 * a1.cos(), 3.0 * a1.sin(), 0.0)).length() < 1e-12);
        }
    }
}
