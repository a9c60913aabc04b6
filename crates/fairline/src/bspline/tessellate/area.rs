//! The area of a trimmed surface: Gauss quadrature on the cells inside the
//! trims, Dunavant's rule on the triangles of the clipped cells.

use rayon::prelude::*;

use super::grid_param;
use super::trimmed::{CellCover, Vert, clip_grid};
use crate::bspline::BSplineSurface;

/// Area of the trimmed surface (model units²): `∫∫ |Su × Sv| du dv`
/// over the trimmed region of the parameter plane, on the `nu × nv` grid of
/// [`tessellate`](super::tessellate): a grid cell wholly inside the face is integrated with the
/// 3 × 3 Gauss–Legendre rule (degree 5 in each direction) on each piece of
/// the cell between knots (the integrand is smooth only between knots), its
/// nodes evaluated together over the whole grid by
/// [`BSplineSurface::map_grid_first`] (basis functions once per node row and
/// column); a cell the trimming loops cut is split as in [`tessellate`](super::tessellate) and
/// its (u, v) triangles integrated with the 6-point degree-4 Gauss rule on
/// the triangle (Dunavant 1985). Independent of the 3-D triangle areas, it
/// converges to the exact area as the trim flattening tolerance
/// ([`crate::bspline::TRIM_FLATNESS`]) and the curvature of `|Su × Sv|` allow.
/// Deterministic (fixed summation order).
pub fn trimmed_area(surface: &BSplineSurface, nu: usize, nv: usize) -> f64 {
    let nu = nu.clamp(2, 65535);
    let nv = nv.clamp(2, 65535);
    let ([u0, u1], [v0, v1]) = (surface.domain_u(), surface.domain_v());
    let us: Vec<f64> = (0..nu).map(|a| grid_param(u0, u1, a, nu)).collect();
    let vs: Vec<f64> = (0..nv).map(|b| grid_param(v0, v1, b, nv)).collect();
    let (cells_u, cells_v) = (nu - 1, nv - 1);
    let clipped = surface.trim().map(|t| clip_grid(t, &us, &vs));
    let whole = |c: usize| match &clipped {
        None => true,
        Some(g) => matches!(g.cells[c], CellCover::Whole),
    };
    // Gauss–Legendre nodes of every cell, the cell split at the knots
    // inside it (the integrand is smooth between knots only).
    let (gu, wu, start_u) = cell_nodes(&us, surface.knots_u());
    let (gv, wv, start_v) = cell_nodes(&vs, surface.knots_v());
    let any_whole = (0..cells_u * cells_v).any(whole);
    let jac: Vec<f64> = if any_whole {
        surface.map_grid_first(&gu, &gv, |_, su, sv| su.cross(sv).length())
    } else {
        Vec::new()
    };
    let ng = gv.len();
    let whole_sum: Vec<f64> = (0..cells_u)
        .into_par_iter()
        .map(|a| {
            let mut row = 0.0;
            for b in 0..cells_v {
                if !whole(a * cells_v + b) {
                    continue;
                }
                let mut cell = 0.0;
                for i in start_u[a]..start_u[a + 1] {
                    let mut col = 0.0;
                    for j in start_v[b]..start_v[b + 1] {
                        col += wv[j] * jac[i * ng + j];
                    }
                    cell += wu[i] * col;
                }
                row += cell;
            }
            row
        })
        .collect();
    let mut area: f64 = whole_sum.iter().sum();
    if let Some(g) = &clipped {
        let at = |v: Vert| match v {
            Vert::Grid(k) => [us[k / nv], vs[k % nv]],
            Vert::Extra(k) => g.extra[k],
        };
        let cut: Vec<f64> = g
            .cells
            .par_iter()
            .map(|cover| match cover {
                CellCover::Cut(tris) => {
                    tris.iter().map(|t| dunavant_area(surface, t.map(at))).sum()
                }
                _ => 0.0,
            })
            .collect();
        area += cut.iter().sum::<f64>();
    }
    area
}

/// The 3-point Gauss–Legendre nodes and weights (including the interval
/// length) of every cell `[ts[a], ts[a + 1]]`, the cell split at the
/// distinct knots strictly inside it; cell `a`'s nodes are
/// `start[a]..start[a + 1]`.
fn cell_nodes(ts: &[f64], knots: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
    let h = 0.5 * 0.6f64.sqrt();
    let nodes = [0.5 - h, 0.5, 0.5 + h];
    let weights = [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0];
    let (mut at, mut w, mut start) = (Vec::new(), Vec::new(), vec![0]);
    for cell in ts.windows(2) {
        let (t0, t1) = (cell[0], cell[1]);
        let mut cuts = vec![t0];
        for &k in knots {
            if k > t0 && k < t1 && cuts.last().is_some_and(|&c| k > c) {
                cuts.push(k);
            }
        }
        cuts.push(t1);
        for piece in cuts.windows(2) {
            let len = piece[1] - piece[0];
            for (x, wx) in nodes.iter().zip(&weights) {
                at.push(piece[0] + x * len);
                w.push(wx * len);
            }
        }
        start.push(at.len());
    }
    (at, w, start)
}

/// `∫∫ |Su × Sv| du dv` over one (u, v) triangle by the 6-point degree-4
/// Gauss rule on the triangle (Dunavant 1985).
fn dunavant_area(surface: &BSplineSurface, [a, b, c]: [[f64; 2]; 3]) -> f64 {
    const W: [f64; 2] = [0.223_381_589_678_011, 0.109_951_743_655_322];
    const A: [f64; 2] = [0.445_948_490_915_965, 0.091_576_213_509_771];
    let jac = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    let mut sum = 0.0;
    for (&w, &l) in W.iter().zip(&A) {
        let m = 1.0 - 2.0 * l;
        for bary in [[m, l, l], [l, m, l], [l, l, m]] {
            let u = bary[0] * a[0] + bary[1] * b[0] + bary[2] * c[0];
            let v = bary[0] * a[1] + bary[1] * b[1] + bary[2] * c[1];
            let d = surface.derivatives(u, v);
            sum += w * d.su.cross(d.sv).length();
        }
    }
    0.5 * jac * sum
}

/// The former [`trimmed_area`] (every triangle of the tessellation by the
/// 6-point rule), kept to check the faster one against.
#[cfg(test)]
pub(crate) fn trimmed_area_by_triangles(surface: &BSplineSurface, nu: usize, nv: usize) -> f64 {
    let t = super::tessellate(surface, nu, nv);
    let parts: Vec<f64> = t
        .triangles
        .par_iter()
        .map(|tri| dunavant_area(surface, tri.map(|k| t.uv[k as usize])))
        .collect();
    parts.iter().sum()
}
