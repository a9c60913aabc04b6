//! Tests of surface evaluation against closed forms: de Casteljau on Bézier
//! patches, exact rational sphere and torus patches, unclamped uniform
//! B-splines, plus validation, support helpers and tessellation.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use super::*;
use crate::Vec3;

/// A small deterministic generator (xorshift64*), values in [-1, 1).
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub(crate) fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
        x as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    pub(crate) fn unit(&mut self) -> f64 {
        0.5 * (self.next() + 1.0)
    }
    pub(crate) fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

fn random_net(rng: &mut Rng, nu: usize, nv: usize) -> Vec<Vec<Vec3>> {
    (0..nu)
        .map(|i| {
            (0..nv)
                .map(|j| Vec3::new(i as f64, j as f64, 0.0) + 0.4 * rng.vec3())
                .collect()
        })
        .collect()
}

/// De Casteljau evaluation of a Bézier curve of homogeneous points.
fn casteljau(points: &[glam::DVec4], t: f64) -> glam::DVec4 {
    let mut b = points.to_vec();
    for r in 1..b.len() {
        for k in 0..b.len() - r {
            b[k] = (1.0 - t) * b[k] + t * b[k + 1];
        }
    }
    b[0]
}

/// De Casteljau on a tensor-product net of homogeneous points.
fn casteljau_surface(net: &[Vec<glam::DVec4>], u: f64, v: f64) -> glam::DVec4 {
    let rows: Vec<glam::DVec4> = net.iter().map(|row| casteljau(row, v)).collect();
    casteljau(&rows, u)
}

/// Forward differences of a net (the hodograph control points), scaled by
/// the degree: the Bézier derivative in u (`du = true`) or v.
fn hodograph(net: &[Vec<glam::DVec4>], du: bool) -> Vec<Vec<glam::DVec4>> {
    if du {
        let p = (net.len() - 1) as f64;
        (0..net.len() - 1)
            .map(|i| {
                (0..net[i].len())
                    .map(|j| p * (net[i + 1][j] - net[i][j]))
                    .collect()
            })
            .collect()
    } else {
        net.iter()
            .map(|row| {
                let q = (row.len() - 1) as f64;
                (0..row.len() - 1)
                    .map(|j| q * (row[j + 1] - row[j]))
                    .collect()
            })
            .collect()
    }
}

/// Homogeneous derivative A^{(k,l)} of a Bézier patch by hodographs.
fn bezier_homogeneous_derivative(
    net: &[Vec<glam::DVec4>],
    k: usize,
    l: usize,
    u: f64,
    v: f64,
) -> glam::DVec4 {
    let mut n = net.to_vec();
    for _ in 0..k {
        if n.len() < 2 {
            return glam::DVec4::ZERO;
        }
        n = hodograph(&n, true);
    }
    for _ in 0..l {
        if n[0].len() < 2 {
            return glam::DVec4::ZERO;
        }
        n = hodograph(&n, false);
    }
    casteljau_surface(&n, u, v)
}

fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
    (a - b).length() <= tol * (1.0 + b.length())
}

fn central_differences(s: &BSplineSurface, u: f64, v: f64, h: f64) -> SurfaceDerivatives {
    // Richardson extrapolation of central differences: O(h⁴).
    let f = |a: f64, b: f64| s.eval(a, b);
    let cd = |h: f64| SurfaceDerivatives {
        point: f(u, v),
        su: (f(u + h, v) - f(u - h, v)) / (2.0 * h),
        sv: (f(u, v + h) - f(u, v - h)) / (2.0 * h),
        suu: (f(u + h, v) - 2.0 * f(u, v) + f(u - h, v)) / (h * h),
        suv: (f(u + h, v + h) - f(u + h, v - h) - f(u - h, v + h) + f(u - h, v - h))
            / (4.0 * h * h),
        svv: (f(u, v + h) - 2.0 * f(u, v) + f(u, v - h)) / (h * h),
    };
    let (a, b) = (cd(h), cd(0.5 * h));
    let r = |x: Vec3, y: Vec3| (4.0 * y - x) / 3.0;
    SurfaceDerivatives {
        point: a.point,
        su: r(a.su, b.su),
        sv: r(a.sv, b.sv),
        suu: r(a.suu, b.suu),
        suv: r(a.suv, b.suv),
        svv: r(a.svv, b.svv),
    }
}

fn assert_derivatives_close(a: &SurfaceDerivatives, b: &SurfaceDerivatives, tol1: f64, tol2: f64) {
    assert!(close(a.point, b.point, tol1), "point {a:?} vs {b:?}");
    assert!(close(a.su, b.su, tol1), "su {:?} vs {:?}", a.su, b.su);
    assert!(close(a.sv, b.sv, tol1), "sv {:?} vs {:?}", a.sv, b.sv);
    assert!(close(a.suu, b.suu, tol2), "suu {:?} vs {:?}", a.suu, b.suu);
    assert!(close(a.suv, b.suv, tol2), "suv {:?} vs {:?}", a.suv, b.suv);
    assert!(close(a.svv, b.svv, tol2), "svv {:?} vs {:?}", a.svv, b.svv);
}

#[test]
fn bspline_bezier_patches_match_de_casteljau() {
    let mut rng = Rng::new(7);
    for &(p, q, rational) in &[
        (3, 2, false),
        (2, 3, false),
        (1, 1, false),
        (4, 4, false),
        (1, 5, false),
        (3, 2, true),
        (2, 2, true),
        (5, 3, true),
    ] {
        for _ in 0..3 {
            let net = random_net(&mut rng, p + 1, q + 1);
            let weights: Option<Vec<Vec<f64>>> = rational.then(|| {
                (0..=p)
                    .map(|_| (0..=q).map(|_| 0.3 + 1.5 * rng.unit()).collect())
                    .collect()
            });
            let hom: Vec<Vec<glam::DVec4>> = net
                .iter()
                .enumerate()
                .map(|(i, row)| {
                    row.iter()
                        .enumerate()
                        .map(|(j, pt)| {
                            let w = weights.as_ref().map_or(1.0, |w| w[i][j]);
                            (w * *pt).extend(w)
                        })
                        .collect()
                })
                .collect();
            let s = BSplineSurface::bezier(net, weights).unwrap();
            assert_eq!((s.degree_u(), s.degree_v()), (p, q));
            for _ in 0..20 {
                let (u, v) = (rng.unit(), rng.unit());
                let a = |k, l| bezier_homogeneous_derivative(&hom, k, l, u, v);
                // Quotient rule on the de Casteljau homogeneous derivatives.
                let (a00, a10, a01) = (a(0, 0), a(1, 0), a(0, 1));
                let (a20, a11, a02) = (a(2, 0), a(1, 1), a(0, 2));
                let w = a00.w;
                let s00 = a00.truncate() / w;
                let s10 = (a10.truncate() - a10.w * s00) / w;
                let s01 = (a01.truncate() - a01.w * s00) / w;
                let reference = SurfaceDerivatives {
                    point: s00,
                    su: s10,
                    sv: s01,
                    suu: (a20.truncate() - 2.0 * a10.w * s10 - a20.w * s00) / w,
                    suv: (a11.truncate() - a10.w * s01 - a01.w * s10 - a11.w * s00) / w,
                    svv: (a02.truncate() - 2.0 * a01.w * s01 - a02.w * s00) / w,
                };
                let d = s.derivatives(u, v);
                assert_derivatives_close(&d, &reference, 1e-12, 1e-11);
                assert!(close(s.eval(u, v), reference.point, 1e-13));
                // Central differences, away from the domain boundary.
                let (uc, vc) = (0.05 + 0.9 * u, 0.05 + 0.9 * v);
                let fd = central_differences(&s, uc, vc, 1e-3);
                assert_derivatives_close(&s.derivatives(uc, vc), &fd, 1e-7, 1e-4);
            }
        }
    }
}

#[test]
fn bspline_nonuniform_spline_matches_central_differences_across_knots() {
    let mut rng = Rng::new(11);
    let knots_u = vec![0.0, 0.0, 0.0, 0.0, 0.2, 0.45, 0.45, 0.7, 1.0, 1.0, 1.0, 1.0];
    let knots_v = vec![-1.0, -1.0, -1.0, 0.0, 0.5, 2.0, 2.0, 2.0];
    let net = random_net(&mut rng, 8, 5);
    let weights: Vec<Vec<f64>> = (0..8)
        .map(|_| (0..5).map(|_| 0.5 + rng.unit()).collect())
        .collect();
    for w in [None, Some(weights)] {
        let s =
            BSplineSurface::new(3, 2, knots_u.clone(), knots_v.clone(), net.clone(), w).unwrap();
        for _ in 0..100 {
            let u = 0.01 + 0.98 * rng.unit();
            let v = -0.97 + 2.94 * rng.unit();
            // Skip points within h of a knot (derivatives jump there).
            let near = |t: f64, k: &[f64]| k.iter().any(|&x| (x - t).abs() < 2e-4);
            if near(u, &knots_u) || near(v, &knots_v) {
                continue;
            }
            let fd = central_differences(&s, u, v, 1e-4);
            assert_derivatives_close(&s.derivatives(u, v), &fd, 1e-7, 1e-4);
            assert!(close(s.derivatives(u, v).point, s.eval(u, v), 1e-14));
        }
    }
}

/// Quarter circle (rational quadratic) control points and weights.
fn quarter_circle() -> ([[f64; 2]; 3], [f64; 3]) {
    (
        [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        [1.0, FRAC_1_SQRT_2, 1.0],
    )
}

/// Full circle: nine rational quadratic control points, knots with double
/// interior knots (Piegl & Tiller Ex. 7.2).
pub(crate) fn full_circle() -> (Vec<[f64; 2]>, Vec<f64>, Vec<f64>) {
    let pts = vec![
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [-1.0, 1.0],
        [-1.0, 0.0],
        [-1.0, -1.0],
        [0.0, -1.0],
        [1.0, -1.0],
        [1.0, 0.0],
    ];
    let w = (0..9)
        .map(|k| if k % 2 == 1 { FRAC_1_SQRT_2 } else { 1.0 })
        .collect();
    let knots = vec![
        0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
    ];
    (pts, w, knots)
}

/// Sphere octant of radius `r`: u along the equator (x towards y), v from
/// the equator up to the north pole, so `Su × Sv` points outward.
pub(crate) fn sphere_octant(r: f64) -> BSplineSurface {
    let (c, w) = quarter_circle();
    let mut net = Vec::new();
    let mut weights = Vec::new();
    for i in 0..3 {
        let (mut row, mut wrow) = (Vec::new(), Vec::new());
        for j in 0..3 {
            // Meridian (rho, z) = c[j]; longitude direction c[i].
            row.push(r * Vec3::new(c[j][0] * c[i][0], c[j][0] * c[i][1], c[j][1]));
            wrow.push(w[i] * w[j]);
        }
        net.push(row);
        weights.push(wrow);
    }
    BSplineSurface::bezier(net, Some(weights)).unwrap()
}

#[test]
fn bspline_rational_sphere_patch_is_exact() {
    let r = 2.5;
    let s = sphere_octant(r);
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        let (u, v) = (rng.unit(), 0.98 * rng.unit());
        let d = s.derivatives(u, v);
        assert!((d.point.length() - r).abs() < 1e-12, "{}", d.point.length());
        let n = s.normal(u, v).unwrap();
        assert!((n - d.point / r).length() < 1e-12);
        let c = s.principal_curvatures(u, v).unwrap();
        assert!((c.k1 - 1.0 / r).abs() < 1e-10, "k1 {}", c.k1);
        assert!((c.k2 - 1.0 / r).abs() < 1e-10, "k2 {}", c.k2);
        assert!((c.mean - 1.0 / r).abs() < 1e-10);
        assert!((c.gauss - 1.0 / (r * r)).abs() < 1e-10);
        assert!((s.mean_curvature(u, v).unwrap() - 1.0 / r).abs() < 1e-10);
        assert!((s.gaussian_curvature(u, v).unwrap() - 1.0 / (r * r)).abs() < 1e-10);
        assert!(c.d1.dot(n).abs() < 1e-9 && c.d2.dot(n).abs() < 1e-9);
    }
    // The north pole (v = 1) is degenerate (Su = 0): the normal falls back
    // to a nearby parameter and is still (almost) +z, never NaN.
    let d = s.derivatives(0.3, 1.0);
    assert!(d.normal().is_none());
    let n = s.normal(0.3, 1.0).unwrap();
    assert!(n.is_finite() && (n - Vec3::Z).length() < 1e-5, "{n:?}");
    let c = s.principal_curvatures(0.3, 1.0).unwrap();
    assert!((c.k1 - 1.0 / r).abs() < 1e-7 && (c.k2 - 1.0 / r).abs() < 1e-7);
}

/// Full torus: u around the z axis, v around the tube starting at the outer
/// equator going up; `Su × Sv` points outward.
pub(crate) fn torus(big: f64, small: f64) -> BSplineSurface {
    let (c, w, knots) = full_circle();
    let mut net = Vec::new();
    let mut weights = Vec::new();
    for i in 0..9 {
        let (mut row, mut wrow) = (Vec::new(), Vec::new());
        for j in 0..9 {
            let rho = big + small * c[j][0];
            row.push(Vec3::new(rho * c[i][0], rho * c[i][1], small * c[j][1]));
            wrow.push(w[i] * w[j]);
        }
        net.push(row);
        weights.push(wrow);
    }
    BSplineSurface::new(2, 2, knots.clone(), knots, net, Some(weights)).unwrap()
}

#[test]
fn bspline_rational_torus_is_exact_with_known_curvature() {
    let (big, small) = (3.0, 1.0);
    let s = torus(big, small);
    let mut rng = Rng::new(5);
    for k in 0..400 {
        // Include the knots (double interior knots) themselves.
        let (u, v) = if k < 25 {
            ((k / 5) as f64 * 0.25, (k % 5) as f64 * 0.25)
        } else {
            (rng.unit(), rng.unit())
        };
        let p = s.eval(u, v);
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let dist = ((rho - big).powi(2) + p.z * p.z).sqrt();
        assert!((dist - small).abs() < 1e-12, "distance {dist}");
        let c = s.principal_curvatures(u, v).unwrap();
        let phi = p.z.atan2(rho - big);
        let k_meridian = 1.0 / small;
        let k_parallel = phi.cos() / (big + small * phi.cos());
        let (e1, e2) = (k_meridian.max(k_parallel), k_meridian.min(k_parallel));
        assert!((c.k1 - e1).abs() < 1e-9, "k1 {} vs {e1}", c.k1);
        assert!((c.k2 - e2).abs() < 1e-9, "k2 {} vs {e2}", c.k2);
        // Outward normal.
        let centre = Vec3::new(p.x, p.y, 0.0) * (big / rho);
        assert!(c.normal.dot((p - centre) / small) > 1.0 - 1e-10);
    }
    // Closed: the seam matches.
    for t in [0.0, 0.3, 0.77] {
        assert!((s.eval(0.0, t) - s.eval(1.0, t)).length() < 1e-14);
        assert!((s.eval(t, 0.0) - s.eval(t, 1.0)).length() < 1e-14);
    }
}

/// Uniform cubic B-spline basis on one span and its derivatives.
fn uniform_cubic(t: f64) -> [[f64; 4]; 3] {
    let s = 1.0 - t;
    [
        [
            s * s * s / 6.0,
            (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
            t * t * t / 6.0,
        ],
        [
            -s * s / 2.0,
            (3.0 * t * t - 4.0 * t) / 2.0,
            (-3.0 * t * t + 2.0 * t + 1.0) / 2.0,
            t * t / 2.0,
        ],
        [s, 3.0 * t - 2.0, -3.0 * t + 1.0, t],
    ]
}

#[test]
fn bspline_unclamped_uniform_cubic_matches_closed_form() {
    let mut rng = Rng::new(13);
    let (nu, nv) = (7, 6);
    let net = random_net(&mut rng, nu, nv);
    let knots = |n: usize| (0..n + 4).map(|k| k as f64 - 2.0).collect::<Vec<f64>>();
    let s = BSplineSurface::new(3, 3, knots(nu), knots(nv), net.clone(), None).unwrap();
    assert_eq!(s.domain_u(), [1.0, nu as f64 - 2.0]);
    assert_eq!(s.domain_v(), [1.0, nv as f64 - 2.0]);
    for k in 0..300 {
        let u = 1.0 + (nu as f64 - 3.0) * if k == 0 { 1.0 } else { rng.unit() };
        let v = 1.0 + (nv as f64 - 3.0) * if k == 0 { 1.0 } else { rng.unit() };
        // Span index: the control points are net[a..a+4] with a = floor(u) - 1.
        let (a, b) = (
            ((u - 1.0).floor() as usize).min(nu - 4),
            ((v - 1.0).floor() as usize).min(nv - 4),
        );
        let (bu, bv) = (
            uniform_cubic(u - 1.0 - a as f64),
            uniform_cubic(v - 1.0 - b as f64),
        );
        let sum = |k: usize, l: usize| {
            let mut acc = Vec3::ZERO;
            for r in 0..4 {
                for c in 0..4 {
                    acc += bu[k][r] * bv[l][c] * net[a + r][b + c];
                }
            }
            acc
        };
        let reference = SurfaceDerivatives {
            point: sum(0, 0),
            su: sum(1, 0),
            sv: sum(0, 1),
            suu: sum(2, 0),
            suv: sum(1, 1),
            svv: sum(0, 2),
        };
        assert_derivatives_close(&s.derivatives(u, v), &reference, 1e-13, 1e-12);
    }
}

#[test]
fn bspline_parameters_are_clamped_to_the_domain() {
    let s = sphere_octant(1.0);
    assert_eq!(s.eval(-3.0, 0.5), s.eval(0.0, 0.5));
    assert_eq!(s.eval(0.5, 7.0), s.eval(0.5, 1.0));
    assert_eq!(s.eval(f64::NAN, 0.5), s.eval(0.0, 0.5));
    assert_eq!(s.eval(f64::INFINITY, 0.5), s.eval(1.0, 0.5));
    assert_eq!(s.derivatives(2.0, 0.5), s.derivatives(1.0, 0.5));
    assert!(s.eval(f64::NAN, f64::NAN).is_finite());
    assert!(s.normal(f64::NAN, f64::NEG_INFINITY).unwrap().is_finite());
}

#[test]
fn bspline_support_helpers() {
    let knots_u = vec![0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0, 3.0];
    let knots_v = vec![0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0];
    let net = random_net(&mut Rng::new(1), 6, 4);
    let s = BSplineSurface::new(3, 2, knots_u, knots_v, net, None).unwrap();
    let b = s.basis_support(1.5, 0.5);
    assert_eq!((b.span_u, b.span_v), (4, 2));
    assert_eq!((b.rows, b.cols), (1..5, 0..3));
    let b = s.basis_support(3.0, 2.0);
    assert_eq!((b.rows, b.cols), (2..6, 1..4));
    // Only N_{i,3} with support meeting (1.2, 1.8): i = 1..=4.
    let ids = s.control_points_in_box(1.2, 1.8, 0.1, 0.2);
    let rows: Vec<usize> = ids.iter().map(|&(i, _)| i).collect();
    assert_eq!(ids.len(), 4 * 3);
    assert_eq!(rows.first(), Some(&1));
    assert_eq!(rows.last(), Some(&4));
    // A box whose edges are knots: (1, 2) x (0, 1).
    let ids = s.control_points_in_box(1.0, 2.0, 0.0, 1.0);
    assert_eq!(ids.first(), Some(&(1, 0)));
    assert_eq!(ids.last(), Some(&(4, 2)));
    assert_eq!(ids.len(), 4 * 3);
    // A degenerate box is the support at that point.
    let ids = s.control_points_in_box(1.5, 1.5, 0.5, 0.5);
    assert_eq!(ids.len(), 4 * 3);
    // Everything: the whole domain.
    assert_eq!(s.control_points_in_box(-1.0, 9.0, -1.0, 9.0).len(), 24);
    // The basis values reproduce the surface.
    let sb = s.basis(1.5, 0.5);
    let mut p = Vec3::ZERO;
    for r in 0..=3 {
        for c in 0..=2 {
            p += sb.du[0][r] * sb.dv[0][c] * s.control_point(sb.span_u - 3 + r, sb.span_v - 2 + c);
        }
    }
    assert!((p - s.eval(1.5, 0.5)).length() < 1e-14);
}

#[test]
fn bspline_setters_keep_the_surface_valid() {
    let mut s = sphere_octant(1.0);
    assert_eq!(
        s.set_control_point(3, 0, Vec3::ZERO),
        Err(BSplineError::IndexOutOfRange {
            i: 3,
            j: 0,
            count_u: 3,
            count_v: 3
        })
    );
    assert_eq!(
        s.set_control_point(1, 2, Vec3::new(f64::NAN, 0.0, 0.0)),
        Err(BSplineError::NonFiniteControlPoint { i: 1, j: 2 })
    );
    assert!(matches!(
        s.set_weight(0, 0, -1.0),
        Err(BSplineError::NonPositiveWeight { i: 0, j: 0, .. })
    ));
    s.set_control_point(1, 1, Vec3::ONE).unwrap();
    assert_eq!(s.control_point(1, 1), Vec3::ONE);
    let mut b = BSplineSurface::bezier(random_net(&mut Rng::new(2), 2, 2), None).unwrap();
    assert!(!b.is_rational());
    b.set_weight(1, 1, 2.0).unwrap();
    assert!(b.is_rational());
    assert_eq!(b.weights().unwrap(), &[1.0, 1.0, 1.0, 2.0]);
}

#[test]
fn bspline_validation_errors_name_the_problem() {
    use BSplineError as E;
    use Direction::{U, V};
    let net = |nu: usize, nv: usize| random_net(&mut Rng::new(9), nu, nv);
    let k4 = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
    let k3 = vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
    let mk = |du, dv, ku: Vec<f64>, kv: Vec<f64>, n, w| BSplineSurface::new(du, dv, ku, kv, n, w);
    assert_eq!(
        mk(0, 2, vec![0.0, 1.0], k3.clone(), net(1, 3), None),
        Err(E::DegreeZero { direction: U })
    );
    assert!(matches!(
        mk(3, 16, k4.clone(), k4.clone(), net(4, 4), None),
        Err(E::DegreeTooHigh {
            direction: V,
            degree: 16,
            ..
        })
    ));
    assert_eq!(
        mk(3, 3, k4.clone(), k4.clone(), vec![], None),
        Err(E::EmptyControlNet)
    );
    let mut ragged = net(4, 4);
    ragged[2].pop();
    assert_eq!(
        mk(3, 3, k4.clone(), k4.clone(), ragged, None),
        Err(E::RaggedControlNet {
            row: 2,
            expected: 4,
            found: 3
        })
    );
    assert!(matches!(
        mk(3, 2, k4.clone(), vec![0.0, 0.0, 1.0, 1.0], net(4, 2), None),
        Err(E::TooFewControlPoints {
            direction: V,
            count: 2,
            needed: 3,
            ..
        })
    ));
    assert!(matches!(
        mk(3, 2, k4.clone(), k4.clone(), net(4, 3), None),
        Err(E::KnotCount {
            direction: V,
            found: 8,
            expected: 6,
            ..
        })
    ));
    let mut bad = k4.clone();
    bad[5] = f64::NAN;
    assert_eq!(
        mk(3, 2, bad, k3.clone(), net(4, 3), None),
        Err(E::NonFiniteKnot {
            direction: U,
            index: 5
        })
    );
    assert!(matches!(
        mk(
            2,
            2,
            k3.clone(),
            vec![0.0, 0.0, 0.0, 1.0, 0.5, 1.0],
            net(3, 3),
            None
        ),
        Err(E::KnotDecreasing {
            direction: V,
            index: 4,
            ..
        })
    ));
    assert_eq!(
        mk(
            1,
            2,
            vec![-1e308, -1e308, 1e308, 1e308],
            k3.clone(),
            net(2, 3),
            None
        ),
        Err(E::KnotRangeOverflow { direction: U })
    );
    // Interior multiplicity 3 > p = 2.
    assert!(matches!(
        mk(
            2,
            2,
            vec![0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0],
            k3.clone(),
            net(6, 3),
            None
        ),
        Err(E::KnotMultiplicity {
            direction: U,
            index: 3,
            multiplicity: 3,
            max: 2,
            ..
        })
    ));
    // End multiplicity 4 > p + 1 = 3.
    assert!(matches!(
        mk(
            2,
            2,
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            k3.clone(),
            net(4, 3),
            None
        ),
        Err(E::KnotMultiplicity {
            direction: U,
            index: 0,
            multiplicity: 4,
            max: 3,
            ..
        })
    ));
    // Unclamped with an empty domain.
    assert!(matches!(
        mk(1, 2, vec![0.0, 1.0, 1.0, 2.0], k3.clone(), net(2, 3), None),
        Err(E::EmptyDomain { direction: U, .. })
    ));
    let mut nan_net = net(3, 3);
    nan_net[1][2].y = f64::INFINITY;
    assert_eq!(
        mk(2, 2, k3.clone(), k3.clone(), nan_net, None),
        Err(E::NonFiniteControlPoint { i: 1, j: 2 })
    );
    let w = |f: &dyn Fn(usize, usize) -> f64| -> Option<Vec<Vec<f64>>> {
        Some((0..3).map(|i| (0..3).map(|j| f(i, j)).collect()).collect())
    };
    assert_eq!(
        mk(
            2,
            2,
            k3.clone(),
            k3.clone(),
            net(3, 3),
            w(&|i, j| if (i, j) == (2, 0) { 0.0 } else { 1.0 })
        ),
        Err(E::NonPositiveWeight {
            i: 2,
            j: 0,
            weight: 0.0
        })
    );
    assert_eq!(
        mk(
            2,
            2,
            k3.clone(),
            k3.clone(),
            net(3, 3),
            w(&|i, _| if i == 1 { f64::NAN } else { 1.0 })
        ),
        Err(E::NonFiniteWeight { i: 1, j: 0 })
    );
    let mut short = w(&|_, _| 1.0).unwrap();
    short[1].pop();
    let err = mk(2, 2, k3.clone(), k3.clone(), net(3, 3), Some(short)).unwrap_err();
    assert!(err.to_string().contains("row 1"), "{err}");
    let two_rows = Some(vec![vec![1.0; 3]; 2]);
    let err = mk(2, 2, k3.clone(), k3.clone(), net(3, 3), two_rows).unwrap_err();
    assert_eq!(err.to_string(), "weights: 2 rows, the control net has 3");
    let err = BSplineSurface::from_flat(
        2,
        2,
        k3.clone(),
        k3.clone(),
        [3, 3],
        vec![Vec3::ZERO; 9],
        Some(vec![1.0; 8]),
    )
    .unwrap_err();
    assert!(matches!(err, E::WeightShape { .. }), "{err}");
    assert!(matches!(
        BSplineSurface::from_flat(
            2,
            2,
            k3.clone(),
            k3.clone(),
            [3, 3],
            vec![Vec3::ZERO; 8],
            None
        ),
        Err(E::ControlPointCount {
            expected: 9,
            found: 8,
            ..
        })
    ));
    // Messages name the direction and index.
    let e = E::KnotDecreasing {
        direction: V,
        index: 4,
        previous: 1.0,
        value: 0.5,
    };
    assert_eq!(
        e.to_string(),
        "knot vector in v decreases at index 4 (1 > 0.5)"
    );
}

#[test]
fn bspline_tessellation_is_oriented_and_deterministic() {
    let s = sphere_octant(2.0);
    let t = tessellate(&s, 12, 9);
    assert_eq!(t.positions.len(), 12 * 9);
    assert_eq!(t.normals.len(), 12 * 9);
    assert_eq!(t.triangles.len(), 2 * 11 * 8);
    assert_eq!(t.uv[0], [0.0, 0.0]);
    assert_eq!(t.uv[12 * 9 - 1], [1.0, 1.0]);
    for n in &t.normals {
        assert!((n.length() - 1.0).abs() < 1e-12);
    }
    for tri in &t.triangles {
        let [a, b, c] = tri.map(|k| t.positions[k as usize]);
        let n = (b - a).cross(c - a);
        if n.length() > 1e-12 {
            // Outward on the sphere, agreeing with Su × Sv.
            assert!(n.dot(a + b + c) > 0.0);
            assert!(n.dot(t.normals[tri[0] as usize]) > 0.0);
        }
    }
    assert_eq!(t, tessellate(&s, 12, 9));
    let tiny = tessellate(&s, 0, 1);
    assert_eq!(tiny.positions.len(), 4);
}

#[test]
fn bspline_derivatives_grid_matches_pointwise() {
    let s = torus(2.0, 0.5);
    let us = [0.0, 0.1, 0.5, 1.0];
    let vs = [0.2, 0.9, 1.0];
    let g = s.derivatives_grid(&us, &vs);
    for (a, &u) in us.iter().enumerate() {
        for (b, &v) in vs.iter().enumerate() {
            assert_eq!(g[a * 3 + b], s.derivatives(u, v));
        }
    }
}

/// The row-contracted first-derivative grid equals pointwise evaluation on
/// a rational torus (exact surface of revolution, weights ≠ 1, knots with
/// interior multiplicity) and a non-rational random net, including the
/// domain ends and knot values.
#[test]
fn bspline_map_grid_first_matches_pointwise() {
    let mut rng = Rng::new(5);
    let net = random_net(&mut rng, 7, 6);
    let plain = BSplineSurface::new(
        3,
        2,
        clamped_uniform_knots(7, 3),
        clamped_uniform_knots(6, 2),
        net,
        None,
    )
    .unwrap();
    for s in [torus(2.0, 0.5), plain] {
        let [a, b] = s.domain_u();
        let [c, d] = s.domain_v();
        let us: Vec<f64> = (0..=16).map(|k| a + (b - a) * k as f64 / 16.0).collect();
        let vs: Vec<f64> = (0..=12).map(|k| c + (d - c) * k as f64 / 12.0).collect();
        let g = s.map_grid_first(&us, &vs, |p, su, sv| (p, su, sv));
        assert_eq!(g.len(), us.len() * vs.len());
        for (ia, &u) in us.iter().enumerate() {
            for (ib, &v) in vs.iter().enumerate() {
                let want = s.derivatives(u, v);
                let (p, su, sv) = g[ia * vs.len() + ib];
                let scale = 1.0 + want.su.length() + want.sv.length();
                assert!((p - want.point).length() < 1e-13 * scale, "S at ({u}, {v})");
                assert!((su - want.su).length() < 1e-12 * scale, "Su at ({u}, {v})");
                assert!((sv - want.sv).length() < 1e-12 * scale, "Sv at ({u}, {v})");
            }
        }
    }
}

#[test]
#[ignore = "timing; run with cargo test --release -- --ignored"]
fn bspline_grid_evaluation_speed() {
    let mut rng = Rng::new(21);
    let net = random_net(&mut rng, 21, 22);
    let knots = |n: usize| {
        let mut k = vec![0.0; 4];
        k.extend((1..n - 3).map(|i| i as f64));
        k.extend([(n - 3) as f64; 4]);
        k
    };
    let s = BSplineSurface::new(3, 3, knots(21), knots(22), net, None).unwrap();
    let [a, b] = s.domain_u();
    let [c, d] = s.domain_v();
    let us: Vec<f64> = (0..500).map(|k| a + (b - a) * k as f64 / 499.0).collect();
    let vs: Vec<f64> = (0..500).map(|k| c + (d - c) * k as f64 / 499.0).collect();
    let _ = s.derivatives_grid(&us, &vs);
    let t = std::time::Instant::now();
    let g = s.derivatives_grid(&us, &vs);
    let dt = t.elapsed().as_secs_f64();
    eprintln!("500x500 grid, points + 1st + 2nd derivatives: {dt:.4} s");
    assert_eq!(g.len(), 250_000);
    assert!(dt < 0.05, "{dt} s");
}

#[test]
fn bspline_sphere_circle_helpers_sanity() {
    // Guards the fixtures: the full circle passes through (cos, sin) at 1/8.
    let (c, _, _) = full_circle();
    assert_eq!(c.len(), 9);
    let s = torus(3.0, 1.0);
    let p = s.eval(0.125, 0.0);
    let a = PI / 4.0;
    assert!((p - Vec3::new(4.0 * a.cos(), 4.0 * a.sin(), 0.0)).length() < 1e-12);
}
