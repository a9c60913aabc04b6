//! Isoparametric curves of a B-spline surface with their exact curvature
//! combs: the curves CAD systems comb to judge a surface along its
//! parameter lines and at its patch edges (the iso-curves at the ends of
//! the domain).
//!
//! The curve with `u = u₀` held is `C(t) = S(u₀, t)`, so `C' = S_v` and
//! `C'' = S_vv` (with `v = v₀` held, `S_u` and `S_uu`), from the surface
//! derivatives of Piegl & Tiller A3.6 / A4.4 ([`BSplineSurface::derivatives`]).
//! Its curvature is `κ = |C' × C''| / |C'|³` and its principal normal `m`
//! the unit part of `C''` across `C'` (towards the centre of curvature);
//! the comb tooth is `−scale · κ · m`, on the convex side, as for plane
//! sections ([`crate::geom::SectionCurve::comb`]). Where `|C'|` vanishes (a
//! pole) or the curve is straight, `κ = 0` and `m = 0`.
//!
//! Samples: `samples` parameters evenly spaced over the domain and every
//! interior knot (where the curvature of a low-degree surface may jump).
//! On a trimmed face only the pieces inside the face are kept
//! ([`BSplineSurface::contains_uv`]), split where the curve leaves it.
//!
//! The edges of a trimmed face are its trimming curves `c(t) = (u, v)`,
//! mapped onto the surface: `C = S(c(t))`, with
//! `C' = S_u u' + S_v v'` and
//! `C'' = S_uu u'² + 2 S_uv u'v' + S_vv v'² + S_u u'' + S_v v''`
//! ([`TrimCurve::eval_d2`](super::TrimCurve::eval_d2)), sampled in the same
//! way over each curve's domain. The edges of an untrimmed patch are the
//! iso-curves at the ends of its domain.

use super::{BSplineSurface, Direction};
use crate::Vec3;
use crate::geom::SectionCurve;

/// Which curve on the surface an [`IsoCurve`] is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IsoKind {
    /// An isoparametric curve: `fixed` held at `value` (`U`: the curve
    /// `S(value, t)` runs along v).
    Held {
        /// The parameter held.
        fixed: Direction,
        /// Its value.
        value: f64,
    },
    /// Curve `curve` of trimming loop `loop_index`, mapped onto the surface:
    /// an edge of a trimmed face.
    TrimEdge {
        /// The loop (0: the first loop of the face).
        loop_index: usize,
        /// The curve within the loop.
        curve: usize,
    },
}

/// One piece of an isoparametric curve or of a trimmed face's edge, with
/// its curvature.
#[derive(Clone, Debug, PartialEq)]
pub struct IsoCurve {
    /// Which curve it is.
    pub kind: IsoKind,
    /// The running parameter at each point (the iso-curve's free surface
    /// parameter, or the trimming curve's parameter).
    pub params: Vec<f64>,
    /// Points, curvature and the unit vector towards the centre of
    /// curvature at each sample (never closed).
    pub curve: SectionCurve,
}

/// The curvature `κ = |C' × C''| / |C'|³` of a curve with derivatives `d1`,
/// `d2`, and the unit vector towards its centre of curvature; `(0, 0)`
/// where `|C'|` or the bending vanishes (to rounding).
pub fn curve_curvature(d1: Vec3, d2: Vec3) -> (f64, Vec3) {
    let speed2 = d1.length_squared();
    if !(speed2 > 1e-300) || !d2.is_finite() {
        return (0.0, Vec3::ZERO);
    }
    let across = d2 - d1 * (d1.dot(d2) / speed2);
    let len = across.length();
    // bending below rounding of the second derivative: a straight curve
    if !(len > 1e-14 * d2.length().max(1e-300)) {
        return (0.0, Vec3::ZERO);
    }
    let kappa = d1.cross(d2).length() / (speed2 * speed2.sqrt());
    if kappa.is_finite() {
        (kappa, across / len)
    } else {
        (0.0, Vec3::ZERO)
    }
}

/// The parameters of `samples` (at least 2) even steps over `[a, b]` and
/// every knot strictly inside, sorted, without repeats.
fn sample_params(knots: &[f64], [a, b]: [f64; 2], samples: usize) -> Vec<f64> {
    let n = samples.max(2);
    let mut t: Vec<f64> = (0..n)
        .map(|k| {
            if k + 1 == n {
                b
            } else {
                a + (b - a) * k as f64 / (n - 1) as f64
            }
        })
        .collect();
    t.extend(knots.iter().copied().filter(|&k| k > a && k < b));
    t.sort_by(f64::total_cmp);
    let span = (b - a).abs().max(f64::MIN_POSITIVE);
    t.dedup_by(|x, y| (*x - *y).abs() <= 1e-12 * span);
    t
}

/// The isoparametric curve of `surface` with `fixed` held at `value`
/// (clamped to the domain), sampled as the module documentation says:
/// one piece on an untrimmed surface, the pieces inside the face on a
/// trimmed one (none when the curve misses the face).
pub fn iso_curve(
    surface: &BSplineSurface,
    fixed: Direction,
    value: f64,
    samples: usize,
) -> Vec<IsoCurve> {
    let (domain, knots) = match fixed {
        Direction::U => (surface.domain_v(), surface.knots_v()),
        Direction::V => (surface.domain_u(), surface.knots_u()),
    };
    let held = match fixed {
        Direction::U => surface.clamp_parameters(value, domain[0]).0,
        Direction::V => surface.clamp_parameters(domain[0], value).1,
    };
    let uv = |t: f64| match fixed {
        Direction::U => (held, t),
        Direction::V => (t, held),
    };
    let mut pieces = Vec::new();
    let mut current: Option<IsoCurve> = None;
    for t in sample_params(knots, domain, samples) {
        let (u, v) = uv(t);
        if !surface.contains_uv(u, v) {
            pieces.extend(current.take());
            continue;
        }
        let d = surface.derivatives(u, v);
        let (d1, d2) = match fixed {
            Direction::U => (d.sv, d.svv),
            Direction::V => (d.su, d.suu),
        };
        if !d.point.is_finite() {
            pieces.extend(current.take());
            continue;
        }
        let (kappa, m) = curve_curvature(d1, d2);
        let c = current.get_or_insert_with(|| IsoCurve {
            kind: IsoKind::Held { fixed, value: held },
            params: Vec::new(),
            curve: SectionCurve {
                points: Vec::new(),
                closed: false,
                curvature: Vec::new(),
                towards_center: Vec::new(),
            },
        });
        c.params.push(t);
        c.curve.points.push(d.point);
        c.curve.curvature.push(kappa);
        c.curve.towards_center.push(m);
    }
    pieces.extend(current);
    pieces.retain(|c| c.params.len() >= 2);
    pieces
}

/// The edges of a trimmed face: every curve of every trimming loop mapped
/// onto the surface (module documentation), each sampled with `samples`
/// parameters plus its interior knots; none for an untrimmed surface.
pub fn trim_edges(surface: &BSplineSurface, samples: usize) -> Vec<IsoCurve> {
    let mut out = Vec::new();
    for (l, lp) in surface.trims().iter().enumerate() {
        for (k, tc) in lp.curves.iter().enumerate() {
            let mut c = IsoCurve {
                kind: IsoKind::TrimEdge {
                    loop_index: l,
                    curve: k,
                },
                params: Vec::new(),
                curve: SectionCurve {
                    points: Vec::new(),
                    closed: false,
                    curvature: Vec::new(),
                    towards_center: Vec::new(),
                },
            };
            let ts = sample_params(tc.knots(), tc.domain(), samples);
            let last = ts.len().saturating_sub(1);
            for (i, &t) in ts.iter().enumerate() {
                // at a knot, the span the curve arrives from (the last
                // sample takes the last span)
                let (uv, d1, d2) = tc.eval_d2(t, i == last);
                let (u, v) = surface.clamp_parameters(uv[0], uv[1]);
                let d = surface.derivatives(u, v);
                if !d.point.is_finite() {
                    continue;
                }
                let c1 = d.su * d1[0] + d.sv * d1[1];
                let c2 = d.suu * (d1[0] * d1[0])
                    + d.suv * (2.0 * d1[0] * d1[1])
                    + d.svv * (d1[1] * d1[1])
                    + d.su * d2[0]
                    + d.sv * d2[1];
                let (kappa, m) = curve_curvature(c1, c2);
                c.params.push(t);
                c.curve.points.push(d.point);
                c.curve.curvature.push(kappa);
                c.curve.towards_center.push(m);
            }
            if c.params.len() >= 2 {
                out.push(c);
            }
        }
    }
    out
}

/// `count` isoparametric curves per direction of `surface`: for each held
/// parameter, `count` values evenly spaced over its domain, ends included
/// (the patch edges of an untrimmed surface; one value, the middle, when
/// `count` is 1); u-held curves first; then, on a trimmed face, its edges
/// ([`trim_edges`]). Each curve sampled with `samples` parameters
/// ([`iso_curve`]).
pub fn iso_curves(surface: &BSplineSurface, count: usize, samples: usize) -> Vec<IsoCurve> {
    let mut out = Vec::new();
    for fixed in [Direction::U, Direction::V] {
        let [a, b] = match fixed {
            Direction::U => surface.domain_u(),
            Direction::V => surface.domain_v(),
        };
        for k in 0..count {
            let value = if count == 1 {
                0.5 * (a + b)
            } else if k + 1 == count {
                b
            } else {
                a + (b - a) * k as f64 / (count - 1) as f64
            };
            out.extend(iso_curve(surface, fixed, value, samples));
        }
    }
    out.extend(trim_edges(surface, samples));
    out
}

impl IsoCurve {
    /// The held parameter and its value, `None` for a trimmed face's edge.
    pub fn held(&self) -> Option<(Direction, f64)> {
        match self.kind {
            IsoKind::Held { fixed, value } => Some((fixed, value)),
            IsoKind::TrimEdge { .. } => None,
        }
    }

    /// `u` or `v` (the parameter held), or `trim` (an edge of a trimmed
    /// face): the curve's kind as the files and reports name it.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            IsoKind::Held {
                fixed: Direction::U,
                ..
            } => "u",
            IsoKind::Held {
                fixed: Direction::V,
                ..
            } => "v",
            IsoKind::TrimEdge { .. } => "trim",
        }
    }

    /// The held parameter's value, or for an edge the index of its
    /// trimming loop.
    pub fn kind_value(&self) -> f64 {
        match self.kind {
            IsoKind::Held { value, .. } => value,
            IsoKind::TrimEdge { loop_index, .. } => loop_index as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::clamped_uniform_knots;

    /// A quarter cylinder of radius r about the z axis as a rational
    /// quadratic in u (exact circle) and linear in v (height h).
    fn quarter_cylinder(r: f64, h: f64) -> BSplineSurface {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let ring = [
            (Vec3::new(r, 0.0, 0.0), 1.0),
            (Vec3::new(r, r, 0.0), w),
            (Vec3::new(0.0, r, 0.0), 1.0),
        ];
        let points = ring
            .iter()
            .map(|(p, _)| vec![*p, *p + Vec3::new(0.0, 0.0, h)])
            .collect();
        let weights = ring.iter().map(|(_, w)| vec![*w, *w]).collect();
        BSplineSurface::new(
            2,
            1,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            points,
            Some(weights),
        )
        .unwrap()
    }

    #[test]
    fn circles_of_a_cylinder_have_curvature_one_over_r_towards_the_axis() {
        let r = 2.5;
        let s = quarter_cylinder(r, 1.0);
        // v held: the circle of radius r at height v·h
        let curves = iso_curve(&s, Direction::V, 0.3, 50);
        assert_eq!(curves.len(), 1);
        let c = &curves[0];
        assert!(c.params.len() >= 50);
        for ((p, k), m) in c
            .curve
            .points
            .iter()
            .zip(&c.curve.curvature)
            .zip(&c.curve.towards_center)
        {
            assert!((k - 1.0 / r).abs() < 1e-12, "κ {k}");
            // towards the axis: −(x, y, 0)/r
            let want = -Vec3::new(p.x, p.y, 0.0) / r;
            assert!((*m - want).length() < 1e-12, "{m} vs {want}");
            assert!((p.z - 0.3).abs() < 1e-12);
        }
        // the comb stands outside the cylinder: p + comb is farther out
        let comb = c.curve.comb(1.0);
        for (p, t) in c.curve.points.iter().zip(&comb) {
            let q = *p + *t;
            assert!((q.x.hypot(q.y) - (r + 1.0 / r)).abs() < 1e-12);
        }
        // u held: a straight ruling, no curvature
        for c in iso_curve(&s, Direction::U, 0.4, 20) {
            assert!(c.curve.curvature.iter().all(|&k| k == 0.0));
            assert!(c.curve.towards_center.iter().all(|m| *m == Vec3::ZERO));
        }
    }

    #[test]
    fn a_parabola_has_the_closed_form_curvature_and_knots_are_sampled() {
        // z = x² over [−1, 1] × [0, 1]: a quadratic Bézier in u with
        // control points (x, z) = (−1, 1), (0, −1), (1, 1), linear in v
        let knots_u = vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let points = [(-1.0, 1.0), (0.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, z)| vec![Vec3::new(x, 0.0, z), Vec3::new(x, 1.0, z)])
            .collect();
        let s =
            BSplineSurface::new(2, 1, knots_u, clamped_uniform_knots(2, 1), points, None).unwrap();
        let c = &iso_curve(&s, Direction::V, 0.5, 41)[0];
        for (p, k) in c.curve.points.iter().zip(&c.curve.curvature) {
            let want = 2.0 / (1.0 + 4.0 * p.x * p.x).powf(1.5);
            assert!((k - want).abs() < 1e-12, "x {}: {k} vs {want}", p.x);
        }
        assert!(sample_params(&[0.0, 0.0, 0.3, 1.0, 1.0], [0.0, 1.0], 3).contains(&0.3));
    }

    #[test]
    fn a_grid_of_iso_curves_includes_the_patch_edges_and_respects_trims() {
        let s = quarter_cylinder(1.0, 1.0);
        let all = iso_curves(&s, 3, 10);
        assert_eq!(all.len(), 6);
        let values: Vec<f64> = all.iter().map(|c| c.kind_value()).collect();
        assert_eq!(values, vec![0.0, 0.5, 1.0, 0.0, 0.5, 1.0]);
        // a trim keeping u < 0.5 cuts the v-held curves in half and drops
        // the u-held curve at u = 1
        use crate::bspline::TrimLoop;
        let half = TrimLoop::polygon(&[[0.0, 0.0], [0.5, 0.0], [0.5, 1.0], [0.0, 1.0]]).unwrap();
        let t = s.clone().with_trims(vec![half]).unwrap();
        let trimmed = iso_curves(&t, 3, 41);
        let held: Vec<&IsoCurve> = trimmed.iter().filter(|c| c.held().is_some()).collect();
        assert!(held.iter().all(|c| c.params.iter().all(|&p| {
            let u = match c.held() {
                Some((Direction::U, value)) => value,
                _ => p,
            };
            u <= 0.5 + 1e-12
        })));
        assert!(!held.iter().any(|c| c.held() == Some((Direction::U, 1.0))));
        // the face's four edges follow: on the cylinder the two straight
        // ones (u = 0, 0.5) and the two arcs (v = 0, 1) of curvature 1
        let edges: Vec<&IsoCurve> = trimmed.iter().filter(|c| c.kind_name() == "trim").collect();
        assert_eq!(edges.len(), 4);
        for e in &edges {
            let k = &e.curve.curvature;
            let arc = k.iter().all(|&k| (k - 1.0).abs() < 1e-12);
            let straight = k.iter().all(|&k| k.abs() < 1e-9);
            assert!(arc || straight, "{:?}", e.kind);
            assert!(
                e.curve
                    .points
                    .iter()
                    .all(|p| (p.x.hypot(p.y) - 1.0).abs() < 1e-12)
            );
        }
        assert_eq!(
            edges.iter().filter(|e| e.curve.curvature[0] > 0.5).count(),
            2
        );
        // no NaN anywhere, even at a degenerate input
        for c in &trimmed {
            assert!(c.curve.points.iter().all(|p| p.is_finite()));
            assert!(c.curve.curvature.iter().all(|k| k.is_finite()));
        }
    }

    #[test]
    fn degenerate_derivatives_give_zero_curvature() {
        assert_eq!(curve_curvature(Vec3::ZERO, Vec3::X), (0.0, Vec3::ZERO));
        assert_eq!(curve_curvature(Vec3::X, Vec3::X * 3.0), (0.0, Vec3::ZERO));
        assert_eq!(
            curve_curvature(Vec3::X, Vec3::splat(f64::NAN)),
            (0.0, Vec3::ZERO)
        );
    }
}
