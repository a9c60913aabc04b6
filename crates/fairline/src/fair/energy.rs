//! Energy-functional fairing of a triangle-mesh region (Grüner thesis
//! §3.1.2–3.1.3): the free vertices are placed where a quadratic fairness
//! energy of the region is smallest, every other vertex held.
//!
//! The thesis gives up the parameter independence of the curvature
//! functionals (Eq. (12), (15)) and minimises energies of a parametrisation
//! X(u, v) instead, whose Euler–Lagrange equations are ΔᵏX = 0:
//!
//! - the membrane energy ½∫|X_u|² + |X_v|² (Eq. (14)): ΔX = 0;
//! - the thin-plate energy ½∫|X_uu|² + 2|X_uv|² + |X_vv|² (Eq. (13)):
//!   Δ²X = 0;
//! - the linearised variation of curvature (minimum variation surfaces,
//!   Eq. (15)): Δ³X = 0 (§3.1.3, last paragraph).
//!
//! Discretisation: Δ = M⁻¹L with the cotangent Laplacian L (Pinkall and
//! Polthier; [`crate::geom::cotangent_laplacian`]) and the mixed Voronoi
//! areas M (Meyer et al.; [`crate::geom::mixed_vertex_areas`]), taken on
//! the parameter domain: the mesh projected onto the plane of the region's
//! mean normal (the region seen from above, as a panel), or on the surface
//! itself where that projection folds a triangle over. The energies are
//! xᵀ(−L)x, xᵀ L M⁻¹ L x and xᵀ(−L M⁻¹ L M⁻¹ L)x, minimised with the other
//! vertices fixed by [`ConstrainedSolver`] (the free rows of ΔᵏX = 0; the
//! k rings of fixed vertices around the free ones are the boundary
//! conditions, C^{k−1} in the limit). Linear functions of the parameters
//! are reproduced exactly by every energy, quadratics by thin-plate and
//! MVS on regular grids; a planar region returns to its plane.

use super::FairError;
use crate::Vec3;
use crate::geom::{
    LaplaceWeights, halfedge_weights_at, laplacian_from_weights, mixed_vertex_areas_at,
};
use crate::mesh::SurfaceMesh;
use crate::solve::{ConstrainedOptions, ConstrainedSolver, SparseColMat, sparse_from_triplets};
use faer::Par;
use faer::sparse::linalg::matmul::sparse_sparse_matmul;

/// The fairness energy of [`energy_fairing`] (Grüner thesis §3.1.2–3.1.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FairEnergy {
    /// Membrane energy, Eq. (14): ΔX = 0.
    Membrane,
    /// Thin-plate energy, Eq. (13): Δ²X = 0.
    ThinPlate,
    /// Linearised variation of curvature (MVS, Eq. (15)): Δ³X = 0.
    VariationOfCurvature,
}

impl FairEnergy {
    /// k of ΔᵏX = 0.
    pub fn order(self) -> usize {
        match self {
            FairEnergy::Membrane => 1,
            FairEnergy::ThinPlate => 2,
            FairEnergy::VariationOfCurvature => 3,
        }
    }
}

/// The positions that minimise `energy` over the vertices with `free[v]`,
/// all others held at their place in `mesh` (see the module
/// documentation). Every free vertex needs a path of at most a few rings to
/// a fixed one (a region of a larger mesh); a system without fixed vertices
/// or with a singular free block is an error, never a NaN. Returns every
/// vertex's position (the fixed ones bit-identical).
pub fn energy_fairing(
    mesh: &SurfaceMesh,
    free: &[bool],
    energy: FairEnergy,
) -> Result<Vec<Vec3>, FairError> {
    mesh.require_triangles()?;
    let n = mesh.vertex_count();
    if free.len() != n {
        return Err(FairError::InvalidOption(format!(
            "{} free flags for {n} vertices",
            free.len()
        )));
    }
    let mut x = mesh.positions().to_vec();
    if !free.iter().any(|&f| f) {
        return Ok(x);
    }
    if free.iter().all(|&f| f) {
        return Err(FairError::NoMovableVertex(
            "energy fairing needs fixed vertices around the free ones".into(),
        ));
    }
    let k = energy.order();
    let domain = parameter_domain(mesh, free, k);
    let w = halfedge_weights_at(mesh, &domain, LaplaceWeights::Cotangent);
    let l = laplacian_from_weights(mesh, &w);
    let areas = mixed_vertex_areas_at(mesh, &domain);
    let mean_area = {
        let good: Vec<f64> = areas
            .iter()
            .copied()
            .filter(|a| *a > 0.0 && a.is_finite())
            .collect();
        if good.is_empty() {
            1.0
        } else {
            good.iter().sum::<f64>() / good.len() as f64
        }
    };
    // M^{-1/2}, guarded against empty or degenerate cells
    let inv_sqrt: Vec<f64> = areas
        .iter()
        .map(|&a| {
            let a = if a > 1e-12 * mean_area && a.is_finite() {
                a
            } else {
                mean_area
            };
            1.0 / a.sqrt()
        })
        .collect();
    let a = energy_matrix(&l, &inv_sqrt, k)?;
    let fixed: Vec<bool> = free.iter().map(|f| !f).collect();
    let mut solver = ConstrainedSolver::analyse(
        a.symbolic(),
        &fixed,
        &ConstrainedOptions::default().points(Some(x.clone())),
    )?;
    solver.factor(a.as_ref())?;
    let b = vec![Vec3::ZERO; n];
    solver.solve_points(&b, &mut x)?;
    if x.iter().any(|p| !p.is_finite()) {
        return Err(FairError::Solve(crate::solve::SolveError::Backend(
            "the energy's free block is singular".into(),
        )));
    }
    Ok(x)
}

/// The matrix of the discrete energy: −L (k = 1), L M⁻¹ L = BᵀB with
/// B = M^{-1/2} L (k = 2), Bᵀ(−M^{-1/2} L M^{-1/2})B (k = 3); symmetric,
/// both triangles stored, rows sorted.
fn energy_matrix(
    l: &SparseColMat<usize, f64>,
    inv_sqrt: &[f64],
    k: usize,
) -> Result<SparseColMat<usize, f64>, FairError> {
    let n = l.nrows();
    let entries = |m: &SparseColMat<usize, f64>, f: &dyn Fn(usize, usize, f64) -> f64| {
        let mut t = Vec::new();
        let m = m.as_ref();
        for c in 0..m.ncols() {
            for (r, v) in m.row_idx_of_col(c).zip(m.val_of_col(c)) {
                t.push((r, c, f(r, c, *v)));
            }
        }
        t
    };
    let rebuild = |t: &[(usize, usize, f64)]| -> Result<SparseColMat<usize, f64>, FairError> {
        Ok(sparse_from_triplets(n, n, t)?)
    };
    if k <= 1 {
        return rebuild(&entries(l, &|_, _, v| -v));
    }
    let b = rebuild(&entries(l, &|r, _, v| inv_sqrt[r] * v))?;
    let bt = rebuild(
        &entries(&b, &|_, _, v| v)
            .iter()
            .map(|&(r, c, v)| (c, r, v))
            .collect::<Vec<_>>(),
    )?;
    let backend = |e: faer::sparse::FaerError| {
        FairError::Solve(crate::solve::SolveError::Backend(format!("{e:?}")))
    };
    let inner = if k == 2 {
        b.clone()
    } else {
        let c = rebuild(&entries(l, &|r, c, v| -inv_sqrt[r] * v * inv_sqrt[c]))?;
        sparse_sparse_matmul(c.as_ref(), b.as_ref(), 1.0, Par::Seq).map_err(backend)?
    };
    let a = sparse_sparse_matmul(bt.as_ref(), inner.as_ref(), 1.0, Par::Seq).map_err(backend)?;
    // symmetrise what rounding left unsymmetric
    let mut t = entries(&a, &|_, _, v| 0.5 * v);
    let tt: Vec<(usize, usize, f64)> = t.iter().map(|&(r, c, v)| (c, r, v)).collect();
    t.extend(tt);
    rebuild(&t)
}

/// The parameter domain of the energies: every position projected onto
/// the plane through the origin normal to the area-weighted mean normal of
/// the fixed faces within k + 1 rings of the free vertices, when no face within k + 1 rings of
/// them folds over or degenerates there (relative area 1e-9); the positions
/// themselves otherwise.
fn parameter_domain(mesh: &SurfaceMesh, free: &[bool], k: usize) -> Vec<Vec3> {
    let p = mesh.positions();
    let n = mesh.vertex_count();
    // vertices within k + 1 rings of the free ones
    let mut near = free.to_vec();
    for _ in 0..=k {
        let mut next = near.clone();
        for v in mesh.vertices() {
            if near[v.idx()] {
                for u in mesh.one_ring(v) {
                    next[u.idx()] = true;
                }
            }
        }
        near = next;
    }
    let faces: Vec<[usize; 3]> = mesh
        .faces()
        .filter(|&f| mesh.face_vertices(f).any(|v| near[v.idx()]))
        .map(|f| mesh.triangle(f).map(|v| v.idx()))
        .collect();
    let cross = |t: &[usize; 3], q: &[Vec3]| (q[t[1]] - q[t[0]]).cross(q[t[2]] - q[t[0]]);
    // the plane of the fixed frame (faces without a free vertex), so that
    // the domain does not depend on where the defect put the free vertices
    let sum = |frame: bool| {
        faces
            .iter()
            .filter(|t| !frame || !t.iter().any(|&v| free[v]))
            .map(|t| cross(t, p))
            .filter(|c| c.is_finite())
            .fold(Vec3::ZERO, |a, c| a + c)
    };
    let mut normal = sum(true);
    if !(normal.length() > 0.0) {
        normal = sum(false);
    }
    if !(normal.length() > 0.0) || !normal.is_finite() {
        return p.to_vec();
    }
    let nz = normal.normalize();
    let projected: Vec<Vec3> = (0..n).map(|i| p[i] - p[i].dot(nz) * nz).collect();
    let total: f64 = faces.iter().map(|t| cross(t, p).length()).sum();
    let floor = 1e-9 * total / faces.len().max(1) as f64;
    let folds = faces
        .iter()
        .any(|t| !(cross(t, &projected).dot(nz) > floor));
    if folds { p.to_vec() } else { projected }
}

#[cfg(test)]
mod tests;
