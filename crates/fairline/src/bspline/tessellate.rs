//! Triangulation of a B-spline surface on a uniform parameter grid.

use rayon::prelude::*;

use super::BSplineSurface;
use crate::Vec3;
use trimmed::tessellate_trimmed;

mod area;
mod polygon;
mod trimmed;

pub use area::trimmed_area;
#[cfg(test)]
pub(crate) use area::trimmed_area_by_triangles;

/// A triangle mesh sampled from a surface on a uniform `(u, v)` grid.
///
/// Untrimmed surfaces: vertex `a * nv + b` sits at `(u_a, v_b)` with
/// `u_a = u0 + a (u1 - u0) / (nu - 1)`. Trimmed surfaces: only the grid
/// vertices used by a triangle are kept (in grid order), followed by the
/// points of the trimming polylines; `uv` gives every vertex's parameters.
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
///
/// A trimmed surface ([`BSplineSurface::trim`]) is clipped to its loops:
/// grid cells wholly inside the face keep their two triangles, cells wholly
/// outside are dropped, and each cell the loops cross is cut along the
/// trimming polylines (refined at every grid line they cross, so that
/// neighbouring cells share their cut points) and the pieces inside are
/// ear-clipped. The triangles cover the trimmed region of the parameter
/// plane up to the flattening tolerance of the loops, so the mesh area
/// converges to the trimmed surface area as the grid is refined.
pub fn tessellate(surface: &BSplineSurface, nu: usize, nv: usize) -> Tessellation {
    let nu = nu.clamp(2, 65535);
    let nv = nv.clamp(2, 65535);
    if let Some(trim) = surface.trim() {
        return tessellate_trimmed(surface, trim, nu, nv);
    }
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
    fill_missing_normals(&positions, &triangles, &mut normals);
    Tessellation {
        positions,
        normals,
        uv,
        triangles,
    }
}

/// Fewest grid points per direction a patch of a part gets.
pub const MIN_PATCH_GRID: usize = 12;

/// The (u, v) grid of one patch of a part whose bounding-box diagonal is
/// `part_diagonal`, for a part grid of `grid` points per diagonal: each
/// direction gets points in proportion to the length of the control polygon
/// along it (the longest row or column, an upper bound of the iso-curves'
/// length), so that grid points lie about `part_diagonal / grid` apart in
/// space on every patch, between [`MIN_PATCH_GRID`] and `grid`. A part of
/// many small faces then costs about as much as one surface of its size,
/// not `grid²` samples per face.
pub fn patch_grid(surface: &BSplineSurface, part_diagonal: f64, grid: usize) -> [usize; 2] {
    let (nu, nv) = (surface.count_u(), surface.count_v());
    let p = |i: usize, j: usize| surface.control_point(i, j);
    let len_u = (0..nv)
        .map(|j| {
            (1..nu)
                .map(|i| (p(i, j) - p(i - 1, j)).length())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    let len_v = (0..nu)
        .map(|i| {
            (1..nv)
                .map(|j| (p(i, j) - p(i, j - 1)).length())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    let lo = MIN_PATCH_GRID.min(grid);
    let count = |len: f64| {
        if part_diagonal > 0.0 && len.is_finite() {
            ((grid as f64 * len / part_diagonal).ceil() as usize).clamp(lo, grid)
        } else {
            grid
        }
    };
    [count(len_u), count(len_v)]
}

/// Every surface of a part tessellated on the grid `grid(s)` (in parallel,
/// merged in input order) into one triangle mesh, with the patch (index
/// into `surfaces`) of every face. The patches are not welded to each
/// other (each keeps its own vertices), so a mesh the builder refuses can
/// only come from one patch's tessellation; then the triangles are made
/// into a mesh as `fairline repair` would ([`part_mesh`]).
pub fn tessellate_part_with(
    surfaces: &[BSplineSurface],
    grid: impl Fn(&BSplineSurface) -> [usize; 2] + Sync,
) -> Result<(crate::SurfaceMesh, Vec<u32>), crate::MeshError> {
    let pieces: Vec<_> = surfaces
        .par_iter()
        .map(|s| {
            let [nu, nv] = grid(s);
            tessellate(s, nu, nv)
        })
        .collect();
    let mut positions = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut patch: Vec<u32> = Vec::new();
    for (k, t) in pieces.into_iter().enumerate() {
        let base = positions.len() as u32;
        positions.extend(t.positions);
        triangles.extend(t.triangles.iter().map(|tri| tri.map(|i| i + base)));
        patch.resize(triangles.len(), k as u32);
    }
    part_mesh(positions, &triangles, patch)
}

/// The mesh of a part's triangles with the patch of every face: the
/// triangles as they are when [`crate::SurfaceMesh::new`] takes them;
/// otherwise (an edge of three or more faces, e.g. a sliver of a clipped
/// cell, or faces that cannot be oriented alike) the mesh of
/// [`crate::mesh::repair`]: such an edge is cut open (its first two faces
/// stay joined), repeated and zero-area triangles are left out, and
/// vertices where several fans meet are split — a picture or a light choice
/// of the part loses nothing it could show. The patches follow the faces
/// kept. Fails only on non-finite positions.
pub fn part_mesh(
    positions: Vec<Vec3>,
    triangles: &[[u32; 3]],
    patch: Vec<u32>,
) -> Result<(crate::SurfaceMesh, Vec<u32>), crate::MeshError> {
    let soup = crate::Soup::from_polygons(positions, triangles);
    let refused = match crate::SurfaceMesh::from_soup(&soup) {
        Ok(m) => return Ok((m, patch)),
        Err(e) => e,
    };
    let repaired = match crate::mesh::repair(&soup, &crate::mesh::RepairOptions::default()) {
        Ok(r) => r,
        Err(crate::mesh::RepairError::Mesh(e)) => return Err(e),
        // not raised: the default options have no cancel flag
        Err(crate::mesh::RepairError::Cancelled(_)) => return Err(refused),
    };
    let mut removed = vec![false; triangles.len()];
    for r in &repaired.report.removed_faces {
        if let Some(x) = removed.get_mut(r.face) {
            *x = true;
        }
    }
    let kept: Vec<u32> = patch
        .iter()
        .zip(&removed)
        .filter(|&(_, &r)| !r)
        .map(|(&p, _)| p)
        .collect();
    let mesh = crate::SurfaceMesh::from_owned_soup(repaired.soup)?;
    Ok((mesh, kept))
}

/// A part tessellated for a picture (or for choosing its lights): one
/// surface `n` × `n`; several, each on its [`patch_grid`] (about `n`
/// samples along the part's diagonal, small faces get few), so that a part
/// of hundreds of faces costs about as much as one surface of its size.
/// With the patch of every face.
pub fn tessellate_part(
    surfaces: &[BSplineSurface],
    n: usize,
) -> Result<(crate::SurfaceMesh, Vec<u32>), crate::MeshError> {
    if surfaces.len() <= 1 {
        return tessellate_part_with(surfaces, |_| [n, n]);
    }
    let diagonal = control_diagonal(surfaces);
    tessellate_part_with(surfaces, |s| patch_grid(s, diagonal, n))
}

/// The diagonal of the bounding box of the control points of all
/// `surfaces` (a bound of the part's size that needs no evaluation).
pub fn control_diagonal(surfaces: &[BSplineSurface]) -> f64 {
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for s in surfaces {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    (hi - lo).length()
}

/// Last resort for normals: area-weighted average of adjacent triangles.
fn fill_missing_normals(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut [Vec3]) {
    let count = positions.len();
    if normals.contains(&Vec3::ZERO) {
        let mut acc = vec![Vec3::ZERO; count];
        for t in triangles {
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
}

/// Grid parameter `k` of `n` on `[t0, t1]`, the last one exactly `t1`.
fn grid_param(t0: f64, t1: f64, k: usize, n: usize) -> f64 {
    if k + 1 == n {
        t1
    } else {
        t0 + (t1 - t0) * (k as f64 / (n - 1) as f64)
    }
}
