//! A bicubic B-spline surface standing for a surface known only by its
//! points (an offset, a ruled surface of equal arc length): interpolation
//! at the Greville points of a knot vector refined until within a
//! tolerance ([`fit_bicubic`]).

use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::bspline::basis::{MAX_ORDER, basis_funs, find_span};

/// Most control points per direction of a fitted surface.
pub(crate) const MAX_FIT_POINTS: usize = 400;

/// The polynomial bicubic B-spline interpolating `exact(u, v)` at the
/// Greville points of its knots — the distinct `breaks` of each direction
/// (triple where flagged C0), each span cut into equal pieces — the pieces
/// doubled until the fit is within `tolerance` of `exact` at the
/// interpolation points and the midpoints between them, at most
/// [`MAX_FIT_POINTS`] control points per direction. Returns the surface
/// and the largest deviation found; errors say why (`exact` failing, the
/// tolerance not reached, a result not finite).
pub(crate) fn fit_bicubic(
    bu: &[(f64, bool)],
    bv: &[(f64, bool)],
    exact: impl Fn(f64, f64) -> Result<Vec3, String>,
    tolerance: f64,
) -> Result<(BSplineSurface, f64), String> {
    let mut pieces = 2;
    loop {
        let (ku, kv) = (fit_knots(bu, pieces), fit_knots(bv, pieces));
        let (nu, nv) = (ku.len() - 4, kv.len() - 4);
        if nu > MAX_FIT_POINTS || nv > MAX_FIT_POINTS {
            return Err(format!(
                "a bicubic fit with {MAX_FIT_POINTS} control points per direction is not within {tolerance:.3e}"
            ));
        }
        let (gu, gv) = (greville(&ku), greville(&kv));
        let mut values = Vec::with_capacity(nu * nv);
        for &u in &gu {
            for &v in &gv {
                values.push(exact(u, v)?);
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
                worst = worst.max(fit.eval(u, v).distance(exact(u, v)?));
            }
        }
        if !worst.is_finite() {
            return Err("the fitted surface is not finite".into());
        }
        if worst <= tolerance {
            return Ok((fit, worst));
        }
        pieces *= 2;
    }
}

/// The distinct knots of `[a, b]` and whether the surface is only C0
/// there (multiplicity at least the degree).
pub(crate) fn breaks(knots: &[f64], degree: usize, [a, b]: [f64; 2]) -> Vec<(f64, bool)> {
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
            return Err("the interpolation is singular".into());
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
