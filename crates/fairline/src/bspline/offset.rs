//! The offset of a B-spline surface as a B-spline surface: exact for a
//! plane, otherwise a bicubic interpolation of the exact offset refined
//! until it is within a tolerance ([`offset_surface`]).

use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::bspline::fit::{breaks, fit_bicubic};

/// An offset surface as a B-spline surface.
pub(crate) struct Offset {
    /// The surface, on the base surface's parameters.
    pub surface: BSplineSurface,
    /// `None`: exact; `Some(e)`: fitted, farthest from the exact offset by
    /// `e` at the points checked.
    pub deviation: Option<f64>,
}

/// `S(u, v) + d·N(u, v)` with `N = Su × Sv / |Su × Sv|` (the normal of a
/// nearby parameter at a degenerate point, [`BSplineSurface::normal`]).
fn exact(base: &BSplineSurface, d: f64, u: f64, v: f64) -> Result<Vec3, String> {
    let n = base
        .normal(u, v)
        .ok_or_else(|| format!("the base surface has no normal at ({u}, {v})"))?;
    Ok(base.eval(u, v) + d * n)
}

/// The offset of `base` by `d` along its normal (IGES 5.3 §4.20's
/// `S + d·N`), on `base`'s parameters:
///
/// - a plane (every control point within 1e-12 of the net's size of the
///   plane through the first, the normal the same at a grid of 9 × 9
///   points) is moved by `d·N`: exact;
/// - any other surface: the polynomial bicubic B-spline of
///   [`fit_bicubic`] on the base's distinct knots (triple where the base
///   is only C0) within `tolerance` of the exact offset.
///
/// Errors say why: no normal, or the tolerance not reached.
pub(crate) fn offset_surface(
    base: &BSplineSurface,
    d: f64,
    tolerance: f64,
) -> Result<Offset, String> {
    if !d.is_finite() {
        return Err(format!("the offset distance {d} is not a number"));
    }
    let (du, dv) = (base.domain_u(), base.domain_v());
    let (lo, hi) = base.control_bounding_box();
    let size = (hi - lo).length();
    if let Some(n) = plane_normal(base, size) {
        let mut s = base.clone();
        s.clear_trims();
        for i in 0..s.count_u() {
            for j in 0..s.count_v() {
                let p = s.control_point(i, j) + d * n;
                s.set_control_point(i, j, p).map_err(|e| e.to_string())?;
            }
        }
        return Ok(Offset {
            surface: s,
            deviation: None,
        });
    }
    let (bu, bv) = (
        breaks(base.knots_u(), base.degree_u(), du),
        breaks(base.knots_v(), base.degree_v(), dv),
    );
    let (surface, worst) = fit_bicubic(&bu, &bv, |u, v| exact(base, d, u, v), tolerance)?;
    Ok(Offset {
        surface,
        deviation: Some(worst),
    })
}

/// The unit normal of a planar surface (all control points on one plane,
/// the normal the same direction over a grid); `None` otherwise.
fn plane_normal(s: &BSplineSurface, size: f64) -> Option<Vec3> {
    let (du, dv) = (s.domain_u(), s.domain_v());
    let (cu, cv) = (0.5 * (du[0] + du[1]), 0.5 * (dv[0] + dv[1]));
    let n = s.normal(cu, cv)?;
    let p0 = s.control_points().first()?;
    if !s
        .control_points()
        .iter()
        .all(|p| (*p - *p0).dot(n).abs() <= 1e-12 * size)
    {
        return None;
    }
    for i in 0..=8 {
        for j in 0..=8 {
            let u = du[0] + (du[1] - du[0]) * i as f64 / 8.0;
            let v = dv[0] + (dv[1] - dv[0]) * j as f64 / 8.0;
            if !(s.normal(u, v)?.dot(n) >= 1.0 - 1e-12) {
                return None;
            }
        }
    }
    Some(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter of a cylinder of radius 2 (rational quadratic in u,
    /// linear in v, height 3).
    fn quarter_cylinder() -> BSplineSurface {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let ring = [(2.0, 0.0, 1.0), (2.0, 2.0, w), (0.0, 2.0, 1.0)];
        let mut pts = Vec::new();
        let mut ws = Vec::new();
        for &(x, y, wt) in &ring {
            for z in [0.0, 3.0] {
                pts.push(Vec3::new(x, y, z));
                ws.push(wt);
            }
        }
        BSplineSurface::from_flat(
            2,
            1,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            [3, 2],
            pts,
            Some(ws),
        )
        .unwrap()
    }

    #[test]
    fn the_offset_of_a_cylinder_is_within_its_tolerance_everywhere() {
        let s = quarter_cylinder();
        // the normal Su × Sv points outwards: d = 0.5 is radius 2.5
        let n = s.normal(0.5, 0.5).unwrap();
        assert!(n.dot(Vec3::new(1.0, 1.0, 0.0)) > 0.0);
        let tol = 1e-7;
        let o = offset_surface(&s, 0.5, tol).unwrap();
        let dev = o.deviation.unwrap();
        assert!(dev <= tol);
        let mut worst = 0.0_f64;
        for i in 0..=97 {
            for j in 0..=13 {
                let (u, v) = (i as f64 / 97.0, j as f64 / 13.0);
                let p = o.surface.eval(u, v);
                worst = worst.max((p.x.hypot(p.y) - 2.5).abs());
            }
        }
        assert!(worst <= 2.0 * tol, "{worst}");
    }

    #[test]
    fn the_offset_of_a_plane_is_exact() {
        let s = BSplineSurface::from_flat(
            1,
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            [2, 2],
            vec![
                Vec3::ZERO,
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(3.0, 2.0, 0.0),
            ],
            None,
        )
        .unwrap();
        let o = offset_surface(&s, 1.5, 1e-9).unwrap();
        assert!(o.deviation.is_none());
        let p = o.surface.eval(0.3, 0.7);
        assert!(p.distance(Vec3::new(0.9, 1.4, 1.5)) < 1e-15, "{p}");
        assert!(offset_surface(&s, f64::NAN, 1e-9).is_err());
    }
}
