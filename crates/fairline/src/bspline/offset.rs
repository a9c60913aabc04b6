//! The offset of a B-spline surface as a B-spline surface: exact for a
//! plane, otherwise a bicubic interpolation of the exact offset refined
//! until it is within a tolerance ([`offset_surface`]).

use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::bspline::basis::{MAX_ORDER, basis_funs, find_span};

/// Most control points per direction of a fitted offset.
const MAX_FIT_POINTS: usize = 400;

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
/// - any other surface: a polynomial bicubic B-spline interpolating the
///   exact offset at the Greville points of its knots (the base's distinct
///   knots, triple where the base is only C0, each span cut into equal
///   pieces), the pieces doubled until the fit is within `tolerance` of
///   the exact offset at the midpoints between the interpolation points
///   (the deviation returned is the largest there), at most
///   [`MAX_FIT_POINTS`] control points per direction.
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
    let mut pieces = 2;
    loop {
        let (ku, kv) = (fit_knots(&bu, pieces), fit_knots(&bv, pieces));
        let (nu, nv) = (ku.len() - 4, kv.len() - 4);
        if nu > MAX_FIT_POINTS || nv > MAX_FIT_POINTS {
            return Err(format!(
                "a bicubic fit of the offset with {MAX_FIT_POINTS} control points per direction is not within {tolerance:.3e}"
            ));
        }
        let (gu, gv) = (greville(&ku), greville(&kv));
        let mut values = Vec::with_capacity(nu * nv);
        for &u in &gu {
            for &v in &gv {
                values.push(exact(base, d, u, v)?);
            }
        }
        solve_rows(&ku, &gu, &mut values, nv)?;
        transpose(&mut values, nu, nv);
        solve_rows(&kv, &gv, &mut values, nu)?;
        transpose(&mut values, nv, nu);
        let fit = BSplineSurface::from_flat(3, 3, ku, kv, [nu, nv], values, None)
            .map_err(|e| e.to_string())?;
        let mut worst = 0.0_f64;
        let mids = |g: &[f64]| -> Vec<f64> { g.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect() };
        for &u in mids(&gu).iter().chain(&gu) {
            for &v in mids(&gv).iter().chain(&gv) {
                worst = worst.max(fit.eval(u, v).distance(exact(base, d, u, v)?));
            }
        }
        if !worst.is_finite() {
            return Err("the fitted offset is not finite".into());
        }
        if worst <= tolerance {
            return Ok(Offset {
                surface: fit,
                deviation: Some(worst),
            });
        }
        pieces *= 2;
    }
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

/// The distinct knots of `[a, b]` and whether the surface is only C0
/// there (multiplicity at least the degree).
fn breaks(knots: &[f64], degree: usize, [a, b]: [f64; 2]) -> Vec<(f64, bool)> {
    let mut out = vec![(a, true)];
    for &k in knots.iter().filter(|&&k| k > a && k < b) {
        match out.last_mut() {
            Some(last) if last.0 == k => {}
            _ => {
                let m = knots.iter().filter(|&&x| x == k).count();
                out.push((k, m >= degree));
            }
        }
    }
    out.push((b, true));
    out
}

/// A clamped cubic knot vector: each span between `breaks` cut into
/// `pieces` equal pieces, a break where the base is C0 triple.
fn fit_knots(breaks: &[(f64, bool)], pieces: usize) -> Vec<f64> {
    let (a, b) = (breaks[0].0, breaks[breaks.len() - 1].0);
    let mut k = vec![a; 4];
    for (i, w) in breaks.windows(2).enumerate() {
        if i > 0 {
            let (t, c0) = w[0];
            k.extend(std::iter::repeat_n(t, if c0 { 3 } else { 1 }));
        }
        for s in 1..pieces {
            k.push(w[0].0 + (w[1].0 - w[0].0) * s as f64 / pieces as f64);
        }
    }
    k.extend([b; 4]);
    k
}

/// Greville abscissae of a cubic knot vector.
fn greville(k: &[f64]) -> Vec<f64> {
    (0..k.len() - 4)
        .map(|i| (k[i + 1] + k[i + 2] + k[i + 3]) / 3.0)
        .collect()
}

/// Transposes a row-major `rows × cols` grid in place.
fn transpose(values: &mut Vec<Vec3>, rows: usize, cols: usize) {
    let mut t = Vec::with_capacity(values.len());
    for j in 0..cols {
        for i in 0..rows {
            t.push(values[i * cols + j]);
        }
    }
    *values = t;
}

/// Replaces the grid's rows (`n = nodes.len()` rows of `cols` values,
/// row-major) by the control points of the cubic B-splines on `knots`
/// interpolating each column at `nodes`: the collocation matrix is banded
/// (half-width 3 at Greville points) and totally positive, so Gaussian
/// elimination without pivoting is stable (de Boor, 1976).
fn solve_rows(
    knots: &[f64],
    nodes: &[f64],
    values: &mut [Vec3],
    cols: usize,
) -> Result<(), String> {
    let n = nodes.len();
    const W: usize = 4;
    let mut a = vec![0.0; n * n];
    let mut b = [0.0; MAX_ORDER];
    for (r, &t) in nodes.iter().enumerate() {
        let span = find_span(knots, 3, n, t);
        basis_funs(span, t, 3, knots, &mut b);
        for (q, &x) in b.iter().enumerate().take(4) {
            a[r * n + span - 3 + q] = x;
        }
    }
    for c in 0..n {
        let pivot = a[c * n + c];
        if !(pivot.abs() > 1e-300) {
            return Err("the interpolation of the offset is singular".into());
        }
        for r in c + 1..(c + W + 1).min(n) {
            let f = a[r * n + c] / pivot;
            if f == 0.0 {
                continue;
            }
            for x in c..(c + W + 1).min(n) {
                a[r * n + x] -= f * a[c * n + x];
            }
            for j in 0..cols {
                let v = values[c * cols + j];
                values[r * cols + j] -= f * v;
            }
        }
    }
    for c in (0..n).rev() {
        for x in c + 1..(c + W + 1).min(n) {
            let f = a[c * n + x];
            if f != 0.0 {
                for j in 0..cols {
                    let v = values[x * cols + j];
                    values[c * cols + j] -= f * v;
                }
            }
        }
        let pivot = a[c * n + c];
        for j in 0..cols {
            values[c * cols + j] /= pivot;
        }
    }
    Ok(())
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
