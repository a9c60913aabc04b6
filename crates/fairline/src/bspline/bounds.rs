//! The bounding box of a surface's face: its trimmed geometry, not its
//! control net.

use super::BSplineSurface;
use crate::Vec3;

/// Samples per parameter direction of [`face_bounding_box`]'s interior grid.
const GRID: usize = 64;

/// The axis-aligned box of the face of `s` (the trimmed region when it is
/// trimmed, else the whole surface), from the surface at the points of its
/// boundary — the trim loops as flattened for inside tests
/// ([`super::TrimmedDomain::polylines`], within [`super::TRIM_FLATNESS`] of
/// the domain's diagonal) or the four domain edges at 4·`GRID` points each
/// — and at a `GRID` × `GRID` grid of interior points inside the face. A
/// sampled box: it can miss a bulge of the surface between samples, by at
/// most the surface's deviation from its sample grid; it never includes
/// control points off the face (the control-point box is 1.4–2× the part
/// for analytic faces converted to NURBS). `None` when no sample lies on the
/// face or a sample is not finite.
pub fn face_bounding_box(s: &BSplineSurface) -> Option<(Vec3, Vec3)> {
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    let mut add = |p: Vec3| {
        lo = lo.min(p);
        hi = hi.max(p);
    };
    match s.trim() {
        Some(t) => {
            for l in t.polylines() {
                for &[u, v] in l {
                    add(s.eval(u, v));
                }
            }
        }
        None => {
            let n = 4 * GRID;
            for k in 0..=n {
                let f = k as f64 / n as f64;
                let (u, v) = (u0 + (u1 - u0) * f, v0 + (v1 - v0) * f);
                for p in [(u, v0), (u, v1), (u0, v), (u1, v)] {
                    add(s.eval(p.0, p.1));
                }
            }
        }
    }
    for i in 0..=GRID {
        for j in 0..=GRID {
            let u = u0 + (u1 - u0) * i as f64 / GRID as f64;
            let v = v0 + (v1 - v0) * j as f64 / GRID as f64;
            if s.contains_uv(u, v) {
                add(s.eval(u, v));
            }
        }
    }
    (lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::TrimLoop;

    #[test]
    fn face_box_of_a_trimmed_quarter_of_a_bilinear_patch() {
        let s = BSplineSurface::bezier(
            vec![
                vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0)],
                vec![Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.0, 4.0, 0.0)],
            ],
            None,
        )
        .unwrap();
        let (lo, hi) = face_bounding_box(&s).unwrap();
        assert!(
            lo.abs_diff_eq(Vec3::ZERO, 1e-12) && hi.abs_diff_eq(Vec3::new(4.0, 4.0, 0.0), 1e-12)
        );
        let t = s
            .with_trims(vec![
                TrimLoop::polygon(&[[0.25, 0.25], [0.5, 0.25], [0.5, 0.5], [0.25, 0.5]]).unwrap(),
            ])
            .unwrap();
        let (lo, hi) = face_bounding_box(&t).unwrap();
        assert!(lo.abs_diff_eq(Vec3::new(1.0, 1.0, 0.0), 1e-9), "{lo}");
        assert!(hi.abs_diff_eq(Vec3::new(2.0, 2.0, 0.0), 1e-9), "{hi}");
    }

    #[test]
    fn face_box_of_a_sphere_converted_to_nurbs_is_the_sphere_not_its_net() {
        // a quarter of a unit sphere's octant by exact revolution: the
        // control net reaches out to the corners of the unit cube
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let arc = [
            (Vec3::new(1.0, 0.0, 0.0), 1.0),
            (Vec3::new(1.0, 0.0, 1.0), w),
            (Vec3::new(0.0, 0.0, 1.0), 1.0),
        ];
        let net: Vec<Vec<Vec3>> = [(1.0, 0.0, 1.0), (1.0, 1.0, w), (0.0, 1.0, 1.0)]
            .iter()
            .map(|&(c, sn, _)| {
                arc.iter()
                    .map(|&(p, _)| Vec3::new(p.x * c, p.x * sn, p.z))
                    .collect()
            })
            .collect();
        let weights: Vec<Vec<f64>> = [1.0, w, 1.0]
            .iter()
            .map(|&a| arc.iter().map(|&(_, b)| a * b).collect())
            .collect();
        let s = BSplineSurface::bezier(net, Some(weights)).unwrap();
        let (lo, hi) = face_bounding_box(&s).unwrap();
        assert!(
            hi.max_element() <= 1.0 + 1e-12 && lo.min_element() >= -1e-12,
            "{lo} {hi}"
        );
        assert!((hi.x - 1.0).abs() < 1e-9 && (hi.z - 1.0).abs() < 1e-9);
        let (_, chi) = s.control_bounding_box();
        assert!(chi.x > 1.0 - 1e-12 && chi.y > 1.0 - 1e-12 && chi.z > 1.0 - 1e-12);
    }
}
