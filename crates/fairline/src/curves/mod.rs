//! Curves used to design desired highlight lines: cubic Hermite segments,
//! the optimized geometric Hermite (OGH) curve of Yong & Cheng (2004) as
//! written in Yong et al. Eq. (5), arc-length tables, and polyline
//! utilities (chord-length parametrisation, Yong et al. §3.5).

use crate::Vec3;

/// A cubic Hermite segment
/// H(t) = (2t+1)(t−1)² P0 + (−2t+3)t² P1 + (1−t)²t V0 + (t−1)t² V1,
/// t ∈ [0, 1], with H(0) = P0, H(1) = P1, H'(0) = V0, H'(1) = V1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicHermite {
    /// Start point.
    pub p0: Vec3,
    /// End point.
    pub p1: Vec3,
    /// Derivative at t = 0.
    pub v0: Vec3,
    /// Derivative at t = 1.
    pub v1: Vec3,
}

impl CubicHermite {
    /// The point H(t).
    pub fn point(&self, t: f64) -> Vec3 {
        let s = t - 1.0;
        (2.0 * t + 1.0) * s * s * self.p0
            + (-2.0 * t + 3.0) * t * t * self.p1
            + s * s * t * self.v0
            + s * t * t * self.v1
    }
    /// The derivative H'(t).
    pub fn derivative(&self, t: f64) -> Vec3 {
        (6.0 * t * t - 6.0 * t) * (self.p0 - self.p1)
            + (3.0 * t * t - 4.0 * t + 1.0) * self.v0
            + (3.0 * t * t - 2.0 * t) * self.v1
    }
    /// Strain energy ∫₀¹ ‖H''(t)‖² dt (closed form).
    pub fn strain_energy(&self) -> f64 {
        // H'' = (12t−6)(P0−P1) + (6t−4)V0 + (6t−2)V1; integrals of products.
        let d = self.p0 - self.p1;
        12.0 * d.length_squared()
            + 4.0 * self.v0.length_squared()
            + 4.0 * self.v1.length_squared()
            + 2.0 * 2.0 * self.v0.dot(self.v1)
            + 2.0 * 6.0 * d.dot(self.v0)
            + 2.0 * 6.0 * d.dot(self.v1)
    }
}

/// How an OGH curve was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OghKind {
    /// The unconstrained optimum of Eq. (5): both magnitudes a0, a1 > 0
    /// (tangent directions preserved).
    Optimal,
    /// Eq. (5) gave a0 ≤ 0 or a1 ≤ 0 (the tangent-preserving condition
    /// failed): the strain energy was minimised under a0, a1 ≥ δ with
    /// δ = 0.1 ‖Q1 − Q0‖ instead (an exact two-variable box problem).
    Constrained,
    /// A tangent was zero or not finite (the Eq. (5) denominator
    /// 4T0²T1² − (T0·T1)² vanishes): the straight segment Q0→Q1 is used.
    Straight,
    /// The magnitudes a0, a1 > 0 were fitted to points the curve should
    /// pass near (the refitted desired lines of highlight-line fairing),
    /// not taken from Eq. (5).
    Fitted,
}

/// An optimized geometric Hermite curve (Yong et al. Eq. (5)): the cubic
/// through Q0, Q1 with tangent directions T0, T1 and magnitudes a0, a1 that
/// minimise the strain energy ∫‖H''‖².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OghCurve {
    /// The cubic, with v0 = a0 T0 and v1 = a1 T1.
    pub hermite: CubicHermite,
    /// The magnitudes (a0, a1).
    pub magnitudes: (f64, f64),
    /// Which branch produced it.
    pub kind: OghKind,
}

/// Builds the OGH curve of Yong et al. Eq. (5) between `q0` and `q1` with
/// tangent directions `t0`, `t1` (any length; only direction and the
/// formula's own scaling matter). Never fails: the degenerate cases use the
/// documented fallbacks of [`OghKind`]. The denominator of Eq. (5) is
/// ≥ 3 T0²T1² by Cauchy–Schwarz, so it vanishes only with a zero tangent.
pub fn ogh_curve(q0: Vec3, t0: Vec3, q1: Vec3, t1: Vec3) -> OghCurve {
    let d = q1 - q0;
    let chord = d.length();
    let straight = |q0: Vec3, q1: Vec3| OghCurve {
        hermite: CubicHermite {
            p0: q0,
            p1: q1,
            v0: q1 - q0,
            v1: q1 - q0,
        },
        magnitudes: (chord, chord),
        kind: OghKind::Straight,
    };
    let (t0, t1) = (t0.normalize_or_zero(), t1.normalize_or_zero());
    if t0 == Vec3::ZERO || t1 == Vec3::ZERO || !d.is_finite() {
        return straight(q0, q1);
    }
    let (t00, t11, t01) = (1.0, 1.0, t0.dot(t1));
    let den = 4.0 * t00 * t11 - t01 * t01;
    if !(den > 1e-12) {
        return straight(q0, q1);
    }
    let (dt0, dt1) = (d.dot(t0), d.dot(t1));
    let a0 = (6.0 * dt0 * t11 - 3.0 * dt1 * t01) / den;
    let a1 = (6.0 * dt1 * t00 - 3.0 * dt0 * t01) / den;
    let make = |a0: f64, a1: f64, kind| OghCurve {
        hermite: CubicHermite {
            p0: q0,
            p1: q1,
            v0: a0 * t0,
            v1: a1 * t1,
        },
        magnitudes: (a0, a1),
        kind,
    };
    if a0 > 0.0 && a1 > 0.0 {
        return make(a0, a1, OghKind::Optimal);
    }
    if !(chord > 0.0) {
        return straight(q0, q1);
    }
    // Energy E(a0, a1) is a convex quadratic with normal equations
    // 2a0 + t01 a1 = 3 dt0, t01 a0 + 2a1 = 3 dt1 (unit tangents). Minimise
    // over a0, a1 ≥ δ: the optimum has one or both magnitudes at δ.
    let delta = 0.1 * chord;
    let mut best: Option<(f64, f64, f64)> = None;
    let mut consider = |a0: f64, a1: f64| {
        if a0 >= delta && a1 >= delta {
            let e = make(a0, a1, OghKind::Constrained).hermite.strain_energy();
            if best.is_none_or(|b| e < b.2) {
                best = Some((a0, a1, e));
            }
        }
    };
    consider(delta, ((3.0 * dt1 - t01 * delta) / 2.0).max(delta));
    consider(((3.0 * dt0 - t01 * delta) / 2.0).max(delta), delta);
    consider(delta, delta);
    let (a0, a1, _) = best.unwrap_or((delta, delta, 0.0));
    make(a0, a1, OghKind::Constrained)
}

/// Cumulative normalised chord-length parameters of a polyline (Yong et al.
/// §3.5): c_0 = 0, c_i = Σ_{j≤i} ‖P_j − P_{j−1}‖ / total, c_last = 1. A
/// polyline of zero length gets uniform parameters.
pub fn chord_parameters(points: &[Vec3]) -> Vec<f64> {
    let n = points.len();
    if n == 0 {
        return Vec::new();
    }
    let mut c = Vec::with_capacity(n);
    c.push(0.0);
    let mut acc = 0.0;
    for w in points.windows(2) {
        acc += (w[1] - w[0]).length();
        c.push(acc);
    }
    if acc > 0.0 && acc.is_finite() {
        for v in &mut c {
            *v /= acc;
        }
        c[n - 1] = 1.0;
    } else if n > 1 {
        for (i, v) in c.iter_mut().enumerate() {
            *v = i as f64 / (n - 1) as f64;
        }
    }
    c
}

/// Length of a polyline.
pub fn polyline_length(points: &[Vec3]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).length()).sum()
}

/// Arc-length table of a parametric curve c(t), t ∈ [0, 1], sampled at
/// `samples + 1` uniform parameters; maps normalised arc length s ∈ [0, 1]
/// to points (the reparametrisation H̃(s) of Yong et al. §3.5).
#[derive(Clone, Debug, PartialEq)]
pub struct ArcLengthTable {
    points: Vec<Vec3>,
    params: Vec<f64>,
    length: f64,
}

impl ArcLengthTable {
    /// Samples `curve` at `samples` (≥ 1) uniform steps.
    pub fn new(curve: impl Fn(f64) -> Vec3, samples: usize) -> Self {
        let samples = samples.max(1);
        let points: Vec<Vec3> = (0..=samples)
            .map(|i| curve(i as f64 / samples as f64))
            .collect();
        let length = polyline_length(&points);
        let params = chord_parameters(&points);
        ArcLengthTable {
            points,
            params,
            length,
        }
    }
    /// Total (polygonal) arc length.
    pub fn length(&self) -> f64 {
        self.length
    }
    /// The point at normalised arc length `s` (clamped to [0, 1]).
    pub fn point(&self, s: f64) -> Vec3 {
        polyline_point(&self.points, &self.params, s)
    }
}

/// Point of a polyline at parameter `s` given the polyline's increasing
/// parameters (e.g. from [`chord_parameters`]); linear between vertices,
/// clamped to the ends.
pub fn polyline_point(points: &[Vec3], params: &[f64], s: f64) -> Vec3 {
    let n = points.len().min(params.len());
    if n == 0 {
        return Vec3::ZERO;
    }
    if !(s > params[0]) {
        return points[0];
    }
    if s >= params[n - 1] {
        return points[n - 1];
    }
    let k = params[..n].partition_point(|&p| p <= s).clamp(1, n - 1);
    let (a, b) = (params[k - 1], params[k]);
    let w = if b > a { (s - a) / (b - a) } else { 0.0 };
    points[k - 1].lerp(points[k], w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_interpolates_ends_and_derivatives() {
        let h = CubicHermite {
            p0: Vec3::new(0.0, 0.0, 0.0),
            p1: Vec3::new(1.0, 2.0, 0.5),
            v0: Vec3::new(1.0, 0.0, 0.0),
            v1: Vec3::new(0.0, 1.0, 1.0),
        };
        assert!((h.point(0.0) - h.p0).length() < 1e-15);
        assert!((h.point(1.0) - h.p1).length() < 1e-15);
        assert!((h.derivative(0.0) - h.v0).length() < 1e-14);
        assert!((h.derivative(1.0) - h.v1).length() < 1e-14);
        // derivative against central differences
        let e = 1e-6;
        let fd = (h.point(0.3 + e) - h.point(0.3 - e)) / (2.0 * e);
        assert!((fd - h.derivative(0.3)).length() < 1e-8);
    }

    #[test]
    fn ogh_minimises_strain_energy_and_reproduces_lines() {
        // Collinear data: the optimum is the straight line at uniform speed.
        let q0 = Vec3::ZERO;
        let q1 = Vec3::new(3.0, 0.0, 0.0);
        let c = ogh_curve(q0, Vec3::X, q1, Vec3::X);
        assert_eq!(c.kind, OghKind::Optimal);
        assert!((c.magnitudes.0 - 3.0).abs() < 1e-12 && (c.magnitudes.1 - 3.0).abs() < 1e-12);
        assert!((c.hermite.point(0.5) - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-12);
        // Optimality: perturbing the magnitudes raises the strain energy.
        let t0 = Vec3::new(1.0, 1.0, 0.0).normalize();
        let t1 = Vec3::new(1.0, -0.5, 0.2).normalize();
        let q1 = Vec3::new(2.0, 0.5, 0.1);
        let c = ogh_curve(q0, t0, q1, t1);
        assert_eq!(c.kind, OghKind::Optimal);
        let e0 = c.hermite.strain_energy();
        for (da, db) in [(0.01, 0.0), (-0.01, 0.0), (0.0, 0.01), (0.0, -0.01)] {
            let mut h = c.hermite;
            h.v0 = (c.magnitudes.0 + da) * t0;
            h.v1 = (c.magnitudes.1 + db) * t1;
            assert!(h.strain_energy() > e0);
        }
        // Closed-form energy against quadrature.
        let n = 2000;
        let num: f64 = (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) / n as f64;
                let e = 1e-4;
                let dd = (c.hermite.point(t + e) - 2.0 * c.hermite.point(t)
                    + c.hermite.point(t - e))
                    / (e * e);
                dd.length_squared() / n as f64
            })
            .sum();
        assert!((num - e0).abs() < 1e-3 * e0.max(1.0));
    }

    #[test]
    fn ogh_fallbacks_keep_tangent_direction() {
        // Tangents pointing backwards: Eq. (5) gives negative magnitudes.
        let c = ogh_curve(Vec3::ZERO, -Vec3::X, Vec3::X, -Vec3::X);
        assert_eq!(c.kind, OghKind::Constrained);
        assert!(c.magnitudes.0 > 0.0 && c.magnitudes.1 > 0.0);
        let c = ogh_curve(Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::X);
        assert_eq!(c.kind, OghKind::Straight);
        assert!((c.hermite.point(0.25) - Vec3::new(0.25, 0.0, 0.0)).length() < 1e-12);
        let c = ogh_curve(Vec3::ZERO, Vec3::X, Vec3::ZERO, Vec3::Y);
        assert!(c.hermite.point(0.5).is_finite());
    }

    #[test]
    fn arc_length_and_chord_parameters() {
        let pts = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 3.0, 0.0)];
        assert_eq!(chord_parameters(&pts), vec![0.0, 0.25, 1.0]);
        assert_eq!(polyline_length(&pts), 4.0);
        let p = polyline_point(&pts, &chord_parameters(&pts), 0.5);
        assert!((p - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
        assert_eq!(chord_parameters(&[Vec3::ONE, Vec3::ONE]), vec![0.0, 1.0]);
        // Arc length of a quarter circle, evaluated at half length.
        let t = ArcLengthTable::new(
            |t| {
                let a = t * t * std::f64::consts::FRAC_PI_2;
                Vec3::new(a.cos(), a.sin(), 0.0)
            },
            4000,
        );
        assert!((t.length() - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
        let m = t.point(0.5);
        let a = std::f64::consts::FRAC_PI_4;
        assert!((m - Vec3::new(a.cos(), a.sin(), 0.0)).length() < 1e-5);
    }
}
