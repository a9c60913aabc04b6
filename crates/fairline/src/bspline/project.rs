//! Closest points on B-spline surfaces and the exact deviation of points
//! from a part of surfaces.
//!
//! Point inversion (Piegl & Tiller §6.1, Eq. 6.3–6.6): the foot `S(u, v)`
//! of the perpendicular from `P` solves `f = S_u · r = 0`, `g = S_v · r = 0`
//! with `r = S(u, v) − P`; Newton's step solves
//! `[[|S_u|² + r·S_uu, S_u·S_v + r·S_uv], [S_u·S_v + r·S_uv, |S_v|² + r·S_vv]] δ = −[f, g]`,
//! each iterate clamped to the domain (a foot outside it ends on its
//! boundary).
//!
//! The deviation of points from a part ([`surface_deviation`]) starts each
//! point at the closest point of the part's tessellation (trimmed faces
//! tessellated inside their trims) and refines it by point inversion on
//! that triangle's surface; the refined foot is kept when it lies on the
//! face (inside its trims) and within the triangle's size of the
//! tessellation's closest point, otherwise the tessellation's closest
//! point stands (counted). The sign
//! is that of `(P − S) · N`, `N = S_u × S_v` normalised.

use super::{BSplineSurface, tessellate, unit_normal};
use crate::Vec3;
use crate::geom::{Deviation, DeviationError, DeviationMethod, TriangleGrid};
use rayon::prelude::*;

/// Most Newton steps of one point inversion.
const MAX_STEPS: usize = 30;

/// The closest point of `surface` to `p` by point inversion from `(u0, v0)`
/// (module documentation): the parameters and the point. Newton's step
/// where the Hessian of the squared distance is positive definite, else
/// steepest descent; each step halved until the distance does not grow.
/// Stops when a step moves less than 1e-15 of the domain's size, no
/// halving helps, or after [`MAX_STEPS`] steps; never leaves the domain.
pub fn closest_point_on_surface(
    surface: &BSplineSurface,
    p: Vec3,
    u0: f64,
    v0: f64,
) -> (f64, f64, Vec3) {
    let (mut u, mut v) = surface.clamp_parameters(u0, v0);
    let [a, b] = surface.domain_u();
    let [c, d] = surface.domain_v();
    let size = (b - a).abs().max((d - c).abs());
    for _ in 0..MAX_STEPS {
        let s = surface.derivatives(u, v);
        let r = s.point - p;
        let f = s.su.dot(r);
        let g = s.sv.dot(r);
        let j11 = s.su.length_squared() + r.dot(s.suu);
        let j12 = s.su.dot(s.sv) + r.dot(s.suv);
        let j22 = s.sv.length_squared() + r.dot(s.svv);
        let det = j11 * j22 - j12 * j12;
        let scale = (j11.abs() + j12.abs()) * (j12.abs() + j22.abs());
        // Newton where the Hessian is positive definite (a minimum ahead),
        // else steepest descent scaled by the first fundamental form
        let (du, dv) = if det > 1e-14 * scale && j11 > 0.0 && det.is_finite() {
            ((-f * j22 + g * j12) / det, (-g * j11 + f * j12) / det)
        } else {
            let e = s.su.length_squared() + s.sv.length_squared();
            if !(e > 1e-300) {
                break;
            }
            (-f / e, -g / e)
        };
        if !(du.is_finite() && dv.is_finite()) {
            break;
        }
        // halve the step until the distance does not grow
        let d0 = r.length_squared();
        let mut step = 1.0;
        let mut next = None;
        while step > 1e-6 {
            let (nu, nv) = surface.clamp_parameters(u + step * du, v + step * dv);
            if (surface.eval(nu, nv) - p).length_squared() <= d0 {
                next = Some((nu, nv));
                break;
            }
            step *= 0.5;
        }
        let Some((nu, nv)) = next else { break };
        let moved = (nu - u).abs().max((nv - v).abs());
        u = nu;
        v = nv;
        if moved <= 1e-15 * size {
            break;
        }
    }
    (u, v, surface.eval(u, v))
}

/// Signed distance of every point of `points` from the part `surfaces`
/// (module documentation), each surface tessellated `grid` × `grid` for the
/// start. `unrefined` counts the points whose foot could not be refined on
/// a face (their value is the tessellation's), `unmatched` those with no
/// finite value (set to 0). Fails when the tessellations hold no usable
/// triangle.
pub fn surface_deviation(
    surfaces: &[BSplineSurface],
    points: &[Vec3],
    grid: usize,
) -> Result<Deviation, DeviationError> {
    let pieces: Vec<_> = surfaces
        .par_iter()
        .map(|s| tessellate(s, grid, grid))
        .collect();
    let (mut positions, mut uv, mut triangles, mut patch) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, t) in pieces.into_iter().enumerate() {
        let base = positions.len() as u32;
        positions.extend(t.positions);
        uv.extend(t.uv);
        for tri in t.triangles {
            triangles.push(tri.map(|i| i + base));
            patch.push(k);
        }
    }
    let tgrid = TriangleGrid::new(&positions, &triangles);
    if tgrid.is_empty() {
        return Err(DeviationError::EmptyReference);
    }
    let measured: Vec<Option<(f64, f64, bool)>> = points
        .par_iter()
        .map(|&p| {
            let c = tgrid.closest(p)?;
            let t = triangles[c.triangle];
            let s = &surfaces[patch[c.triangle]];
            let w = c.barycentric;
            let at = |i: usize| {
                w[0] * uv[t[0] as usize][i]
                    + w[1] * uv[t[1] as usize][i]
                    + w[2] * uv[t[2] as usize][i]
            };
            let (u, v, q) = closest_point_on_surface(s, p, at(0), at(1));
            let exact = q.distance(p);
            // a foot found from this triangle lies within its size of the
            // triangle's closest point (a chord is within it of its arc)
            let q3 = t.map(|i| positions[i as usize]);
            let size = q3[0]
                .distance(q3[1])
                .max(q3[1].distance(q3[2]))
                .max(q3[2].distance(q3[0]));
            // on the face; or, at a trim boundary the tessellation follows,
            // where the foot has not moved off its start
            let start = (at(0), at(1));
            let [u0, u1] = s.domain_u();
            let [v0, v1] = s.domain_v();
            let stayed = (u - start.0).abs() + (v - start.1).abs()
                <= 1e-9 * ((u1 - u0).abs() + (v1 - v0).abs());
            let (foot, uv_foot, dist, refined) = if (s.contains_uv(u, v) || stayed)
                && exact <= c.distance + size
                && exact.is_finite()
            {
                (q, (u, v), exact, true)
            } else {
                (c.point, (at(0), at(1)), c.distance, false)
            };
            let d = s.derivatives(uv_foot.0, uv_foot.1);
            let side = match unit_normal(d.su, d.sv) {
                Some(n) => (p - foot).dot(n),
                None => {
                    let q = t.map(|i| positions[i as usize]);
                    (p - foot).dot((q[1] - q[0]).cross(q[2] - q[0]))
                }
            };
            let signed = if side < 0.0 { -dist } else { dist };
            (signed.is_finite() && dist.is_finite()).then_some((signed, dist, refined))
        })
        .collect();
    let unmatched = measured.iter().filter(|m| m.is_none()).count();
    let unrefined = measured
        .iter()
        .filter(|m| matches!(m, Some((_, _, false))))
        .count();
    let (signed, distance) = measured
        .into_iter()
        .map(|m| m.map_or((0.0, 0.0), |(s, d, _)| (s, d)))
        .unzip();
    Ok(Deviation {
        method: DeviationMethod::SurfacePoint,
        signed,
        distance,
        unmatched,
        unrefined,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter cylinder of radius r about the z axis, height 1.
    fn quarter_cylinder(r: f64) -> BSplineSurface {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let ring = [
            (Vec3::new(r, 0.0, 0.0), 1.0),
            (Vec3::new(r, r, 0.0), w),
            (Vec3::new(0.0, r, 0.0), 1.0),
        ];
        BSplineSurface::new(
            2,
            1,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            ring.iter()
                .map(|(p, _)| vec![*p, *p + Vec3::new(0.0, 0.0, 1.0)])
                .collect(),
            Some(ring.iter().map(|(_, w)| vec![*w, *w]).collect()),
        )
        .unwrap()
    }

    #[test]
    fn points_off_a_cylinder_are_their_radial_distance_away_exactly() {
        let s = quarter_cylinder(2.0);
        // points at radius 2 ± h, angles inside the quarter, heights inside
        let mut points = Vec::new();
        let mut want = Vec::new();
        for i in 0..20 {
            let a = 0.05 + 1.4 * i as f64 / 19.0;
            let h = 0.1 * ((i as f64) - 9.5) / 9.5;
            points.push(Vec3::new(
                (2.0 + h) * a.cos(),
                (2.0 + h) * a.sin(),
                0.05 * i as f64,
            ));
            want.push(h);
        }
        let coarse = surface_deviation(std::slice::from_ref(&s), &points, 6).unwrap();
        assert_eq!(coarse.method, DeviationMethod::SurfacePoint);
        assert_eq!((coarse.unmatched, coarse.unrefined), (0, 0));
        for (got, h) in coarse.signed.iter().zip(&want) {
            // the cylinder's normal points outward: farther out is positive
            assert!((got - h).abs() < 1e-12, "{got} vs {h}");
        }
        // the tessellation alone is off by the chord error of a 6 × 6 grid
        let mesh = crate::bspline::tessellate(&s, 6, 6);
        let m = crate::SurfaceMesh::new(mesh.positions, &mesh.triangles).unwrap();
        let tess = crate::geom::closest_point_deviation(&m, &points).unwrap();
        let worst = tess
            .signed
            .iter()
            .zip(&want)
            .map(|(g, h)| (g - h).abs())
            .fold(0.0, f64::max);
        assert!(
            worst > 1e-3,
            "the chord error the projection removes: {worst}"
        );
    }

    #[test]
    fn the_foot_stays_in_the_domain_and_inversion_reaches_its_point() {
        let s = quarter_cylinder(1.0);
        let (u, v, q) = closest_point_on_surface(&s, s.eval(0.3, 0.7), 0.9, 0.1);
        assert!(
            (u - 0.3).abs() < 1e-12 && (v - 0.7).abs() < 1e-12,
            "{u} {v}"
        );
        assert!(q.distance(s.eval(0.3, 0.7)) < 1e-14);
        // beyond the end of the quarter: the foot on the domain's edge
        let (u, _, _) = closest_point_on_surface(&s, Vec3::new(-1.0, 0.5, 0.5), 0.5, 0.5);
        assert_eq!(u, 1.0);
        // no NaN from a point on the axis (every foot equally near)
        let (u, v, q) = closest_point_on_surface(&s, Vec3::new(0.0, 0.0, 0.5), 0.5, 0.5);
        assert!(u.is_finite() && v.is_finite() && q.is_finite());
    }
}
