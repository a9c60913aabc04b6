//! A per-vertex field split by wavelength into its broad and local parts:
//! what moved a whole neighbourhood (an offset, a drift, the shrinkage of a
//! smoothing) and what moved a few vertices against their neighbours (the
//! noise or the defect a repair removes).
//!
//! The broad part is one implicit heat step of the field,
//! `(M − t L) b = M f` (M the barycentric vertex areas, L the cotangent
//! Laplacian of [`super::cotangent_laplacian`], negative semi-definite,
//! Desbrun et al. 1999 §4), whose response to a wave of wavelength λ' is
//! `1 / (1 + t (2π/λ')²)`: with `t = (λ/2π)²` waves longer than λ keep more
//! than half their height in `b`, shorter ones fall into the local part
//! `f − b`. The step has no boundary condition (natural, zero normal
//! derivative), so a constant field is all broad and the area-weighted
//! mean of `f` equals that of `b`.
//!
//! The step is solved by sparse Cholesky up to [`DIRECT_LIMIT`] vertices —
//! the tessellations of CAD parts (slivers, poles, 64 × 64 grids on thin
//! faces) condition it so badly that conjugate gradients take thousands of
//! iterations (the impeller's 828,651 vertices: 45 s, against a few
//! seconds factored) — and by Jacobi-preconditioned conjugate gradients to
//! 1e-9 beyond that, or where the factorisation fails.

use super::{COTANGENT_LIMIT, LaplaceWeights, barycentric_vertex_areas, halfedge_weights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{CholeskySolver, pcg, sparse_from_triplets};
use rayon::prelude::*;

/// The two parts of a field: `broad[i] + local[i] = values[i]` to rounding.
#[derive(Clone, Debug, PartialEq)]
pub struct WavelengthSplit {
    /// The part of wavelengths longer than the split's, per vertex.
    pub broad: Vec<f64>,
    /// The rest, per vertex.
    pub local: Vec<f64>,
    /// The wavelength of the split (model units).
    pub wavelength: f64,
    /// Whether the heat step's solve reached its tolerance (1e-9 relative
    /// residual); when it did not, `broad` is the last iterate (finite).
    pub converged: bool,
}

/// Most vertices whose heat step is factored (module documentation).
pub const DIRECT_LIMIT: usize = 1_500_000;

/// Splits `values` (one per vertex of `mesh`) at `wavelength` (module
/// documentation). Polygon faces are split into triangles (the vertices
/// stay); vertices of no face, and every vertex when `wavelength` is not a
/// positive finite length or the mesh has no area, keep their whole value
/// as broad. Non-finite values are taken as 0. Cost: linear in the mesh per
/// conjugate-gradient iteration (Jacobi-preconditioned; the iterations grow
/// with the wavelength over the edge length).
///
/// # Panics
/// If `values.len()` differs from the vertex count.
pub fn split_by_wavelength(mesh: &SurfaceMesh, values: &[f64], wavelength: f64) -> WavelengthSplit {
    assert_eq!(values.len(), mesh.vertex_count(), "one value per vertex");
    let f: Vec<f64> = values
        .iter()
        .map(|v| if v.is_finite() { *v } else { 0.0 })
        .collect();
    let whole = |converged| WavelengthSplit {
        broad: f.clone(),
        local: vec![0.0; f.len()],
        wavelength,
        converged,
    };
    if !(wavelength.is_finite() && wavelength > 0.0) || f.is_empty() {
        return whole(true);
    }
    let triangulated;
    let tri = if mesh.is_triangle_mesh() {
        mesh
    } else {
        match crate::mesh::triangulate(mesh) {
            Ok(t) => {
                triangulated = t.mesh;
                &triangulated
            }
            Err(_) => return whole(true),
        }
    };
    let area = barycentric_vertex_areas(tri);
    let total: f64 = area.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        return whole(true);
    }
    // a vertex of no area is pinned to its value by a mass of 1e-9 of the
    // mean (its row of L is empty or tiny)
    let floor = 1e-9 * total / area.len() as f64;
    let mass: Vec<f64> = area.iter().map(|a| a.max(floor)).collect();
    let t = (wavelength / std::f64::consts::TAU).powi(2);
    let w = halfedge_weights(tri, LaplaceWeights::Cotangent);
    // compressed neighbour lists: (neighbour, t·w_ij) per vertex
    let n = tri.vertex_count();
    let mut start = Vec::with_capacity(n + 1);
    let mut nbr: Vec<(u32, f64)> = Vec::with_capacity(tri.halfedge_count());
    start.push(0usize);
    for v in 0..n {
        for h in tri.outgoing(VertexId(v as u32)) {
            let wij = w[h.idx()].clamp(-COTANGENT_LIMIT, COTANGENT_LIMIT);
            if wij != 0.0 {
                nbr.push((tri.to_vertex(h).idx() as u32, t * wij));
            }
        }
        start.push(nbr.len());
    }
    let diag: Vec<f64> = (0..n)
        .map(|i| {
            let s: f64 = nbr[start[i]..start[i + 1]].iter().map(|e| e.1).sum();
            mass[i] + s
        })
        .collect();
    let apply = |x: &[f64], y: &mut [f64]| {
        y.par_iter_mut().enumerate().for_each(|(i, yi)| {
            let mut s = diag[i] * x[i];
            for &(j, tw) in &nbr[start[i]..start[i + 1]] {
                s -= tw * x[j as usize];
            }
            *yi = s;
        });
    };
    let precondition = |r: &[f64], z: &mut [f64]| {
        z.par_iter_mut().enumerate().for_each(|(i, zi)| {
            let d = diag[i].max(mass[i]);
            *zi = r[i] / d;
        });
    };
    let rhs: Vec<f64> = f.iter().zip(&mass).map(|(v, m)| v * m).collect();
    let direct = || -> Option<Vec<f64>> {
        if n > DIRECT_LIMIT {
            return None;
        }
        let mut entries = Vec::with_capacity(n + nbr.len());
        for i in 0..n {
            entries.push((i, i, diag[i]));
            for &(j, tw) in &nbr[start[i]..start[i + 1]] {
                entries.push((i, j as usize, -tw));
            }
        }
        let a = sparse_from_triplets(n, n, &entries).ok()?;
        let solver = CholeskySolver::new(a.as_ref()).ok()?;
        let mut x = rhs.clone();
        solver.solve_in_place(&mut x).ok()?;
        x.iter().all(|v| v.is_finite()).then_some(x)
    };
    let (broad, converged) = match direct() {
        Some(b) => (b, true),
        None => {
            let mut broad = f.clone();
            match pcg(apply, precondition, &rhs, &mut broad, 1e-9, 5000) {
                Ok(report) => (broad, report.converged),
                Err(_) => return whole(false),
            }
        }
    };
    if broad.iter().any(|b| !b.is_finite()) {
        return whole(false);
    }
    let local = f.iter().zip(&broad).map(|(v, b)| v - b).collect();
    WavelengthSplit {
        broad,
        local,
        wavelength,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{plane, quad_grid};

    /// cos(2π (x + 1) / λ') on [−1, 1]² with 4/λ' whole has zero normal
    /// derivative on the border: an eigenfunction of the Neumann Laplacian,
    /// so the heat step scales it by 1 / (1 + (λ/λ')²).
    fn wave(mesh: &SurfaceMesh, period: f64) -> Vec<f64> {
        mesh.positions()
            .iter()
            .map(|p| (std::f64::consts::TAU * (p.x + 1.0) / period).cos())
            .collect()
    }

    #[test]
    fn a_wave_keeps_the_heat_steps_share_in_the_broad_part() {
        let mesh = plane(121);
        let f = wave(&mesh, 1.0);
        for (lambda, expected) in [(1.0, 0.5), (0.5, 0.8), (2.0, 0.2)] {
            let s = split_by_wavelength(&mesh, &f, lambda);
            assert!(s.converged);
            // the ratio broad / f at the crests (|f| = 1)
            let mut worst: f64 = 0.0;
            for (b, v) in s.broad.iter().zip(&f) {
                if v.abs() > 0.99 {
                    worst = worst.max((b / v - expected).abs());
                }
            }
            assert!(worst < 0.01, "λ {lambda}: broad/f off by {worst}");
            for ((b, l), v) in s.broad.iter().zip(&s.local).zip(&f) {
                assert!((b + l - v).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn a_constant_is_all_broad_and_the_mean_is_kept() {
        let mesh = crate::shapes::icosphere(1.0, 3);
        let s = split_by_wavelength(&mesh, &vec![-0.25; mesh.vertex_count()], 0.4);
        assert!(s.broad.iter().all(|b| (b + 0.25).abs() < 1e-9));
        assert!(s.local.iter().all(|l| l.abs() < 1e-9));
        // a spike: its area-weighted mean survives, spread over the sphere
        let mut f = vec![0.0; mesh.vertex_count()];
        f[7] = 1.0;
        let s = split_by_wavelength(&mesh, &f, 1.0);
        let a = barycentric_vertex_areas(&mesh);
        let mean = |x: &[f64]| x.iter().zip(&a).map(|(x, a)| x * a).sum::<f64>();
        // to the solve's tolerance (1e-9 of the right-hand side's norm)
        assert!((mean(&s.broad) - mean(&f)).abs() < 1e-7 * mean(&f));
        assert!(s.broad[7] < 0.5 && s.local[7] > 0.5);
    }

    #[test]
    fn quads_are_split_like_their_triangles_and_bad_input_keeps_the_field() {
        let quads = quad_grid(31, 31, (-1.0, 1.0), (-1.0, 1.0), |_, _| 0.0);
        let f = wave(&quads, 2.0);
        let s = split_by_wavelength(&quads, &f, 1.0);
        assert!(s.converged);
        let crest = f.iter().position(|v| (v - 1.0).abs() < 1e-12).unwrap();
        assert!((s.broad[crest] - 0.8).abs() < 0.02, "{}", s.broad[crest]);
        for lambda in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let s = split_by_wavelength(&quads, &f, lambda);
            assert_eq!(s.broad, f);
            assert!(s.local.iter().all(|l| *l == 0.0));
        }
        let mut g = f.clone();
        g[3] = f64::NAN;
        let s = split_by_wavelength(&quads, &g, 1.0);
        assert!(s.broad.iter().chain(&s.local).all(|x| x.is_finite()));
    }
}
