//! The target samples, their signed distances d_s and the Jacobian of d_s
//! with respect to the selected control points (Nishiyama et al.
//! Eq. (3.6)–(3.10)).

use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::highlight::CircularLight;
use faer::Mat;
use rayon::prelude::*;

/// A sample of a target curve with its light and the derivatives of the
/// surface (and its first partials) with respect to the selected control
/// points: S, S_u, S_v are linear in the control points with coefficients
/// R, ∂R/∂u, ∂R/∂v of the (rational) basis.
pub(super) struct Sample {
    pub(super) uv: [f64; 2],
    pub(super) light: usize,
    /// (column base = 3 × selected index, R, R_u, R_v).
    pub(super) coeffs: Vec<(usize, f64, f64, f64)>,
}

/// Rational basis R_ij and its first partials at `(u, v)` for the control
/// points in `column` (flat index → selected index), Piegl & Tiller Eq. (4.2)
/// differentiated: R = N w / W, R_u = (N_u w W − N w W_u) / W².
pub(super) fn sample_coeffs(
    surface: &BSplineSurface,
    column: &[Option<usize>],
    u: f64,
    v: f64,
) -> Vec<(usize, f64, f64, f64)> {
    let b = surface.basis(u, v);
    let (p, q) = (surface.degree_u(), surface.degree_v());
    let (i0, j0) = (b.span_u - p, b.span_v - q);
    let w = |r: usize, s: usize| surface.weight(i0 + r, j0 + s);
    let (mut ww, mut wu, mut wv) = (0.0, 0.0, 0.0);
    if surface.is_rational() {
        for r in 0..=p {
            for s in 0..=q {
                let wt = w(r, s);
                ww += b.du[0][r] * b.dv[0][s] * wt;
                wu += b.du[1][r] * b.dv[0][s] * wt;
                wv += b.du[0][r] * b.dv[1][s] * wt;
            }
        }
    } else {
        ww = 1.0;
    }
    let mut out = Vec::new();
    if !(ww > 0.0 && ww.is_finite()) {
        return out;
    }
    for r in 0..=p {
        for s in 0..=q {
            let Some(col) = column[surface.index(i0 + r, j0 + s)] else {
                continue;
            };
            let wt = if surface.is_rational() { w(r, s) } else { 1.0 };
            let n = b.du[0][r] * b.dv[0][s] * wt;
            let nu = b.du[1][r] * b.dv[0][s] * wt;
            let nv = b.du[0][r] * b.dv[1][s] * wt;
            let rr = n / ww;
            let ru = (nu * ww - n * wu) / (ww * ww);
            let rv = (nv * ww - n * wv) / (ww * ww);
            if rr != 0.0 || ru != 0.0 || rv != 0.0 {
                out.push((3 * col, rr, ru, rv));
            }
        }
    }
    out
}

/// d_s of Eq. (2.18) at every sample; `None` where undefined.
pub(super) fn residuals(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
) -> Vec<Option<f64>> {
    samples
        .par_iter()
        .with_min_len(16)
        .map(|s| {
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            lights[s.light].signed_distance(d.point, d.normal()?)
        })
        .collect()
}

/// (max, mean) |d_s|; infinite if any sample is undefined.
pub(super) fn stats(r: &[Option<f64>]) -> (f64, f64) {
    if r.is_empty() {
        return (0.0, 0.0);
    }
    let mut max = 0.0f64;
    let mut sum = 0.0;
    for x in r {
        match x {
            Some(x) => {
                max = max.max(x.abs());
                sum += x.abs();
            }
            None => return (f64::INFINITY, f64::INFINITY),
        }
    }
    (max, sum / r.len() as f64)
}

/// The Jacobian ∂d_s/∂r of Eq. (3.9) by the forward differences of
/// Eq. (3.10), re-evaluating only the samples each column affects: moving
/// component a of control point P by Δw moves S, S_u, S_v of a sample by
/// (R, R_u, R_v)·Δw along axis a, exactly, so only the normal and the
/// quartic of Eq. (2.15) are recomputed. Parallel over samples; one sparse
/// row (column, value) per sample, empty where d_s is undefined.
pub(super) fn jacobian_rows(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    f: &[Option<f64>],
    dw: f64,
) -> Vec<Vec<(usize, f64)>> {
    samples
        .par_iter()
        .zip(f.par_iter())
        .with_min_len(8)
        .map(|(s, &f0)| {
            let mut e = Vec::with_capacity(3 * s.coeffs.len());
            let Some(f0) = f0 else { return e };
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            let light = &lights[s.light];
            for &(c, r, ru, rv) in &s.coeffs {
                for a in 0..3 {
                    let mut ax = Vec3::ZERO;
                    ax[a] = dw;
                    let q = d.point + r * ax;
                    let n = (d.su + ru * ax).cross(d.sv + rv * ax);
                    let g = light.signed_distance(q, n).map_or(0.0, |fd| (fd - f0) / dw);
                    if g.is_finite() {
                        e.push((c + a, g));
                    }
                }
            }
            e
        })
        .collect()
}

/// The Jacobian of Eq. (3.9)–(3.10) with one unknown per selected control
/// point, its displacement along `dirs[k]` (Nishiyama et al. §3.3: "the
/// selected components of the control points"), by forward differences
/// re-evaluating only the samples each column affects (as
/// [`jacobian_rows`]). Samples × `dirs.len()`.
pub(super) fn jacobian_along(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    f: &[Option<f64>],
    dirs: &[Vec3],
    dw: f64,
) -> Mat<f64> {
    let entries: Vec<Vec<(usize, f64)>> = samples
        .par_iter()
        .zip(f.par_iter())
        .with_min_len(8)
        .map(|(s, &f0)| {
            let mut e = Vec::with_capacity(s.coeffs.len());
            let Some(f0) = f0 else { return e };
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            let light = &lights[s.light];
            for &(c, r, ru, rv) in &s.coeffs {
                let k = c / 3;
                let ax = dw * dirs[k];
                let q = d.point + r * ax;
                let n = (d.su + ru * ax).cross(d.sv + rv * ax);
                let g = light.signed_distance(q, n).map_or(0.0, |fd| (fd - f0) / dw);
                if g.is_finite() {
                    e.push((k, g));
                }
            }
            e
        })
        .collect();
    let mut j = Mat::<f64>::zeros(samples.len(), dirs.len());
    for (row, e) in entries.iter().enumerate() {
        for &(c, g) in e {
            j[(row, c)] = g;
        }
    }
    j
}

/// The direction every selected control point moves in with
/// [`SurfaceFairMethod::Paper`](super::SurfaceFairMethod::Paper): the
/// coordinate axis (x, y or z) closest to
/// the mean unit normal of the surface at the samples (+z when that mean is
/// undefined). Nishiyama et al. §3.3 solve for "the selected components of
/// the control points", and the Jacobians of their Table 1 have one column
/// per moved control point (36 for the dome's 6 × 6), i.e. one coordinate
/// each: the height of a panel seen from above. Measured on the rebuilt
/// dome, saddle and roof it ends closer to the defect-free surface than the
/// normal at each point's Greville abscissae (normal deviation 2.4e-3 vs
/// 3.0e-3, 1.8e-3 vs 1.8e-3, 7.9e-4 vs 9.8e-4), and than three unknowns
/// per point on the dome and the saddle.
pub(super) fn control_directions(
    surface: &BSplineSurface,
    selected: &[(usize, usize)],
    samples: &[Sample],
) -> Vec<Vec3> {
    let mean = samples
        .iter()
        .filter_map(|s| surface.normal(s.uv[0], s.uv[1]))
        .filter(|n| n.is_finite())
        .fold(Vec3::ZERO, |a, n| a + n);
    let a = mean.abs();
    let axis = if !(a.length() > 0.0) || (a.z >= a.x && a.z >= a.y) {
        Vec3::Z
    } else if a.y >= a.x {
        Vec3::Y
    } else {
        Vec3::X
    };
    vec![axis; selected.len()]
}
