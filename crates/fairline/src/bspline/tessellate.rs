//! Triangulation of a B-spline surface on a uniform parameter grid.

use rayon::prelude::*;

use super::BSplineSurface;
use crate::Vec3;

/// A triangle mesh sampled from a surface on a uniform `(u, v)` grid.
///
/// Vertex `a * nv + b` sits at `(u_a, v_b)` with `u_a = u0 + a (u1 - u0) / (nu - 1)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tessellation {
    /// Surface points `S(u_a, v_b)`.
    pub positions: Vec<Vec3>,
    /// Unit normals `Su × Sv / |Su × Sv|` (nearby-parameter fallback at
    /// degenerate points, then the average of the adjacent triangle normals;
    /// zero only if all of that fails). Never NaN.
    pub normals: Vec<Vec3>,
    /// Parameters `[u, v]` of each vertex.
    pub uv: Vec<[f64; 2]>,
    /// Triangles, counter-clockwise seen from the side `Su × Sv` points to.
    pub triangles: Vec<[u32; 3]>,
}

/// Samples `surface` on a uniform grid of `nu × nv` vertices spanning its
/// whole domain (values below 2 are raised to 2, values above 65535 lowered
/// to 65535 so that vertex indices fit in `u32`) and splits every grid cell
/// into two triangles oriented consistently with `Su × Sv`: cell corners
/// `a=(i,j), b=(i+1,j), c=(i+1,j+1), d=(i,j+1)` give `[a,b,c]` and `[a,c,d]`.
///
/// Points and normals come from [`BSplineSurface::derivatives`] (Piegl &
/// Tiller A3.6/A4.4); rows are evaluated in parallel with rayon and the
/// output is deterministic.
pub fn tessellate(surface: &BSplineSurface, nu: usize, nv: usize) -> Tessellation {
    let nu = nu.clamp(2, 65535);
    let nv = nv.clamp(2, 65535);
    let [u0, u1] = surface.domain_u();
    let [v0, v1] = surface.domain_v();
    let param = |t0: f64, t1: f64, k: usize, n: usize| {
        if k + 1 == n {
            t1
        } else {
            t0 + (t1 - t0) * (k as f64 / (n - 1) as f64)
        }
    };
    let count = nu * nv;
    let us: Vec<f64> = (0..nu).map(|a| param(u0, u1, a, nu)).collect();
    let vs: Vec<f64> = (0..nv).map(|b| param(v0, v1, b, nv)).collect();
    let derivs = surface.derivatives_grid(&us, &vs);
    let uv: Vec<[f64; 2]> = (0..count).map(|k| [us[k / nv], vs[k % nv]]).collect();
    let positions: Vec<Vec3> = derivs.iter().map(|d| d.point).collect();
    let mut normals: Vec<Vec3> = derivs
        .par_iter()
        .zip(uv.par_iter())
        .map(|(d, &[u, v])| {
            d.normal()
                .or_else(|| surface.normal(u, v))
                .unwrap_or(Vec3::ZERO)
        })
        .collect();
    let idx = |a: usize, b: usize| (a * nv + b) as u32;
    let mut triangles = Vec::with_capacity(2 * (nu - 1) * (nv - 1));
    for a in 0..nu - 1 {
        for b in 0..nv - 1 {
            let (p, q, r, s) = (idx(a, b), idx(a + 1, b), idx(a + 1, b + 1), idx(a, b + 1));
            triangles.push([p, q, r]);
            triangles.push([p, r, s]);
        }
    }
    // Last resort for normals: area-weighted average of adjacent triangles.
    if normals.contains(&Vec3::ZERO) {
        let mut acc = vec![Vec3::ZERO; count];
        for t in &triangles {
            let [p, q, r] = t.map(|k| positions[k as usize]);
            let n = (q - p).cross(r - p);
            for &k in t {
                acc[k as usize] += n;
            }
        }
        for (n, a) in normals.iter_mut().zip(&acc) {
            if *n == Vec3::ZERO {
                let m = a.normalize_or_zero();
                *n = if m.is_finite() { m } else { Vec3::ZERO };
            }
        }
    }
    Tessellation {
        positions,
        normals,
        uv,
        triangles,
    }
}
