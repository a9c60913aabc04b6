//! Triangulation of a B-spline surface on a uniform parameter grid.

use rayon::prelude::*;

use super::BSplineSurface;
use super::trim::{TrimmedDomain, inside_by_crossings, winding_number};
use crate::Vec3;

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

/// A vertex of the trimmed tessellation before compaction.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Vert {
    /// Grid vertex `a * nv + b`.
    Grid(usize),
    /// Extra vertex (a trimming polyline point) with its index.
    Extra(usize),
}

/// The cell `[0, n-2]` whose interval `[ts[k], ts[k+1]]` holds `t`.
fn cell_of(ts: &[f64], t: f64) -> usize {
    ts.partition_point(|&x| x <= t)
        .saturating_sub(1)
        .min(ts.len() - 2)
}

/// A piece of a trimming polyline inside one grid cell.
struct Chain {
    /// Vertex ids and their parameters, in loop order.
    points: Vec<(Vert, [f64; 2])>,
    /// The loop closes inside the cell (the whole loop is this chain).
    closed: bool,
}

/// How the trimmed face covers one grid cell.
enum CellCover {
    /// Not at all.
    Outside,
    /// Wholly (two triangles `[a,b,c]`, `[a,c,d]` of the cell corners).
    Whole,
    /// In part: the triangles of the clipped region.
    Cut(Vec<[Vert; 3]>),
}

/// The trimmed region over the grid `us × vs`: the cover of every cell
/// (cell `(a, b)` at `a * (nv - 1) + b`) and the extra vertices (trimming
/// polyline points) the cut cells' triangles use.
struct ClippedGrid {
    cells: Vec<CellCover>,
    extra: Vec<[f64; 2]>,
}

fn tessellate_trimmed(
    surface: &BSplineSurface,
    trim: &TrimmedDomain,
    nu: usize,
    nv: usize,
) -> Tessellation {
    let [u0, u1] = surface.domain_u();
    let [v0, v1] = surface.domain_v();
    let us: Vec<f64> = (0..nu).map(|a| grid_param(u0, u1, a, nu)).collect();
    let vs: Vec<f64> = (0..nv).map(|b| grid_param(v0, v1, b, nv)).collect();
    let ClippedGrid { cells, extra } = clip_grid(trim, &us, &vs);
    let cells_v = nv - 1;
    let g = |i: usize, j: usize| Vert::Grid(i * nv + j);
    let tris_per_cell: Vec<Vec<[Vert; 3]>> = cells
        .into_iter()
        .enumerate()
        .map(|(c, cover)| match cover {
            CellCover::Outside => Vec::new(),
            CellCover::Whole => {
                let (a, b) = (c / cells_v, c % cells_v);
                let (p, q, r, s) = (g(a, b), g(a + 1, b), g(a + 1, b + 1), g(a, b + 1));
                vec![[p, q, r], [p, r, s]]
            }
            CellCover::Cut(t) => t,
        })
        .collect();
    build_trimmed(surface, &us, &vs, &extra, &tris_per_cell)
}

/// Clips the grid `us × vs` (each at least 2 long, increasing) to the
/// trimming loops: steps 1–2 of [`tessellate_trimmed`].
fn clip_grid(trim: &TrimmedDomain, us: &[f64], vs: &[f64]) -> ClippedGrid {
    let (nu, nv) = (us.len(), vs.len());
    let (u0, u1) = (us[0], us[nu - 1]);
    let (v0, v1) = (vs[0], vs[nv - 1]);
    let cells_u = nu - 1;
    let cells_v = nv - 1;
    let cell_w = (u1 - u0) / cells_u as f64;
    let cell_h = (v1 - v0) / cells_v as f64;
    let nudge = 1e-7 * cell_w.min(cell_h);

    // 1. Refine the loops at every grid line; assign each piece to a cell.
    let mut extra: Vec<[f64; 2]> = Vec::new();
    let mut chains: Vec<Vec<Chain>> = (0..cells_u * cells_v).map(|_| Vec::new()).collect();
    for poly in trim.polylines() {
        let pts = refine_at_grid_lines(poly, us, vs, cell_w, cell_h);
        if pts.len() < 3 {
            continue;
        }
        let ids = loop_vertex_ids(&pts, us, vs, &mut extra);
        let cell = piece_cells(&pts, us, vs, nudge);
        split_into_cell_chains(&pts, &ids, &cell, &mut chains);
    }

    // 2. Triangles: whole cells by the inside test of their centre, cut
    //    cells by clipping.
    let cells = cell_covers(trim, us, vs, &chains);
    ClippedGrid { cells, extra }
}

/// Distance (as a fraction of a grid cell's side) within which a trimming
/// polyline point or a cut is moved onto a grid line. Far below the
/// flattening tolerance and the `nudge` of [`piece_cells`] (1e-7 of a cell),
/// far above the rounding of loops computed in floating point: a loop point
/// one ulp off a grid corner (featuretype.STEP's plane faces, whose trims
/// run along the domain's border) would otherwise become a second vertex
/// beside the corner, and the clipped cell's ear clipping made a sliver on
/// the corner's edge that a third face shared (a non-manifold edge).
const GRID_SNAP: f64 = 1e-9;

/// `p` with each coordinate within [`GRID_SNAP`] of a cell side from a
/// grid line of `us` (resp. `vs`) moved onto it.
fn snap_to_grid_lines(mut p: [f64; 2], us: &[f64], vs: &[f64], cell: [f64; 2]) -> [f64; 2] {
    for (axis, ts) in [us, vs].into_iter().enumerate() {
        let k = cell_of(ts, p[axis]);
        for &t in &ts[k..(k + 2).min(ts.len())] {
            if (p[axis] - t).abs() <= GRID_SNAP * cell[axis] {
                p[axis] = t;
            }
        }
    }
    p
}

/// The closed polyline `poly` with its points snapped onto the grid lines
/// of `us × vs` near them ([`snap_to_grid_lines`]) and a point added
/// wherever it crosses a grid line (snapped too), without repeated points
/// and without the closing repetition of the first point.
fn refine_at_grid_lines(
    poly: &[[f64; 2]],
    us: &[f64],
    vs: &[f64],
    cell_w: f64,
    cell_h: f64,
) -> Vec<[f64; 2]> {
    let snap = |p: [f64; 2]| snap_to_grid_lines(p, us, vs, [cell_w, cell_h]);
    let snapped: Vec<[f64; 2]> = poly.iter().map(|&p| snap(p)).collect();
    let mut pts: Vec<[f64; 2]> = Vec::with_capacity(poly.len() * 2);
    let n = snapped.len();
    for k in 0..n {
        let (a, b) = (snapped[k], snapped[(k + 1) % n]);
        if pts.last() != Some(&a) {
            pts.push(a);
        }
        let mut cuts: Vec<(f64, [f64; 2])> = Vec::new();
        let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
        let first = us.partition_point(|&x| x <= lo);
        for &x in us[first..].iter().take_while(|&&x| x < hi) {
            let t = (x - a[0]) / (b[0] - a[0]);
            cuts.push((t, [x, a[1] + t * (b[1] - a[1])]));
        }
        let (lo, hi) = (a[1].min(b[1]), a[1].max(b[1]));
        let first = vs.partition_point(|&y| y <= lo);
        for &y in vs[first..].iter().take_while(|&&y| y < hi) {
            let t = (y - a[1]) / (b[1] - a[1]);
            cuts.push((t, [a[0] + t * (b[0] - a[0]), y]));
        }
        cuts.sort_by(|p, q| p.0.total_cmp(&q.0));
        for (t, p) in cuts {
            if !(t > 0.0 && t < 1.0) {
                continue;
            }
            // A cut next to a grid corner lands on it.
            let p = snap(p);
            if pts.last() != Some(&p) && p != b {
                pts.push(p);
            }
        }
    }
    while pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    pts
}

/// The vertex of each loop point: a point on a grid corner is that grid
/// vertex, any other a new extra vertex (appended to `extra`).
fn loop_vertex_ids(
    pts: &[[f64; 2]],
    us: &[f64],
    vs: &[f64],
    extra: &mut Vec<[f64; 2]>,
) -> Vec<Vert> {
    let nv = vs.len();
    pts.iter()
        .map(|&p| {
            let a = us.binary_search_by(|x| x.total_cmp(&p[0]));
            let b = vs.binary_search_by(|y| y.total_cmp(&p[1]));
            match (a, b) {
                (Ok(a), Ok(b)) => Vert::Grid(a * nv + b),
                _ => {
                    extra.push(p);
                    Vert::Extra(extra.len() - 1)
                }
            }
        })
        .collect()
}

/// The cell (`a * (nv - 1) + b`) of each piece k → k+1 of a refined loop:
/// the cell of its midpoint nudged by `nudge` to its left (the trimmed
/// region lies left of every oriented loop).
fn piece_cells(pts: &[[f64; 2]], us: &[f64], vs: &[f64], nudge: f64) -> Vec<usize> {
    let cells_v = vs.len() - 1;
    let m = pts.len();
    (0..m)
        .map(|k| {
            let (a, b) = (pts[k], pts[(k + 1) % m]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = dx.hypot(dy);
            let (nx, ny) = if len > 0.0 {
                (-dy / len, dx / len)
            } else {
                (0.0, 0.0)
            };
            let mx = 0.5 * (a[0] + b[0]) + nudge * nx;
            let my = 0.5 * (a[1] + b[1]) + nudge * ny;
            cell_of(us, mx) * cells_v + cell_of(vs, my)
        })
        .collect()
}

/// Cuts a refined loop into the chains of consecutive pieces that lie in
/// one cell and adds each to its cell's list (a loop inside one cell is one
/// closed chain).
fn split_into_cell_chains(
    pts: &[[f64; 2]],
    ids: &[Vert],
    cell: &[usize],
    chains: &mut [Vec<Chain>],
) {
    let m = pts.len();
    let Some(start) = (0..m).find(|&k| cell[k] != cell[(k + m - 1) % m]) else {
        // The whole loop lies in one cell.
        chains[cell[0]].push(Chain {
            points: (0..m).map(|k| (ids[k], pts[k])).collect(),
            closed: true,
        });
        return;
    };
    let mut k = start;
    loop {
        let c = cell[k];
        let mut points = vec![(ids[k], pts[k])];
        while cell[k] == c {
            k = (k + 1) % m;
            points.push((ids[k], pts[k]));
            if k == start {
                break;
            }
        }
        chains[c].push(Chain {
            points,
            closed: false,
        });
        if k == start {
            break;
        }
    }
}

/// How the trimmed face covers each cell: a cell no loop enters is whole or
/// outside by the inside test of its centre, a cell with chains is clipped
/// ([`clip_cell`]).
fn cell_covers(
    trim: &TrimmedDomain,
    us: &[f64],
    vs: &[f64],
    chains: &[Vec<Chain>],
) -> Vec<CellCover> {
    let (nu, nv) = (us.len(), vs.len());
    let (cells_u, cells_v) = (nu - 1, nv - 1);
    let rows_inside: Vec<Vec<bool>> = (0..cells_v)
        .into_par_iter()
        .map(|b| {
            let vc = 0.5 * (vs[b] + vs[b + 1]);
            let xs = trim.row_crossings(vc);
            (0..cells_u)
                .map(|a| inside_by_crossings(&xs, 0.5 * (us[a] + us[a + 1])))
                .collect()
        })
        .collect();
    (0..cells_u * cells_v)
        .into_par_iter()
        .map(|c| {
            let (a, b) = (c / cells_v, c % cells_v);
            let g = |i: usize, j: usize| Vert::Grid(i * nv + j);
            if chains[c].is_empty() {
                if rows_inside[b][a] {
                    CellCover::Whole
                } else {
                    CellCover::Outside
                }
            } else {
                let rect = [us[a], us[a + 1], vs[b], vs[b + 1]];
                let corners = [
                    (g(a, b), [us[a], vs[b]]),
                    (g(a + 1, b), [us[a + 1], vs[b]]),
                    (g(a + 1, b + 1), [us[a + 1], vs[b + 1]]),
                    (g(a, b + 1), [us[a], vs[b + 1]]),
                ];
                CellCover::Cut(clip_cell(&chains[c], rect, &corners, |p| {
                    trim.contains(p[0], p[1])
                }))
            }
        })
        .collect()
}

/// Step 3 of [`tessellate_trimmed`]: compacts the vertices of the cells'
/// triangles and evaluates them.
fn build_trimmed(
    surface: &BSplineSurface,
    us: &[f64],
    vs: &[f64],
    extra: &[[f64; 2]],
    tris_per_cell: &[Vec<[Vert; 3]>],
) -> Tessellation {
    let (nu, nv) = (us.len(), vs.len());
    // 3. Compact the vertices and evaluate them.
    let mut map_grid = vec![u32::MAX; nu * nv];
    let mut map_extra = vec![u32::MAX; extra.len()];
    let mut uv: Vec<[f64; 2]> = Vec::new();
    for t in tris_per_cell.iter().flatten() {
        for v in t {
            if let Vert::Grid(k) = *v {
                map_grid[k] = 0;
            }
        }
    }
    for (k, m) in map_grid.iter_mut().enumerate() {
        if *m == 0 {
            *m = uv.len() as u32;
            uv.push([us[k / nv], vs[k % nv]]);
        }
    }
    let mut triangles = Vec::new();
    for t in tris_per_cell.iter().flatten() {
        let tri = t.map(|v| match v {
            Vert::Grid(k) => map_grid[k],
            Vert::Extra(k) => {
                if map_extra[k] == u32::MAX {
                    map_extra[k] = uv.len() as u32;
                    uv.push(extra[k]);
                }
                map_extra[k]
            }
        });
        if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
            triangles.push(tri);
        }
    }
    let derivs: Vec<(Vec3, Vec3)> = uv
        .par_iter()
        .map(|&[u, v]| {
            let d = surface.derivatives(u, v);
            let n = d
                .normal()
                .or_else(|| surface.normal(u, v))
                .unwrap_or(Vec3::ZERO);
            (d.point, n)
        })
        .collect();
    let positions: Vec<Vec3> = derivs.iter().map(|d| d.0).collect();
    let mut normals: Vec<Vec3> = derivs.iter().map(|d| d.1).collect();
    fill_missing_normals(&positions, &triangles, &mut normals);
    Tessellation {
        positions,
        normals,
        uv,
        triangles,
    }
}

/// Position of a point of the cell boundary along its counter-clockwise
/// perimeter, in `[0, 4)`: bottom `[0,1)`, right `[1,2)`, top `[2,3)`,
/// left `[3,4)`. A point off the boundary is projected to the nearest side.
fn perimeter(p: [f64; 2], [ul, uh, vl, vh]: [f64; 4]) -> f64 {
    let (w, h) = (
        (uh - ul).max(f64::MIN_POSITIVE),
        (vh - vl).max(f64::MIN_POSITIVE),
    );
    let d = [p[1] - vl, uh - p[0], vh - p[1], p[0] - ul];
    let side = (0..4)
        .min_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs()))
        .unwrap_or(0);
    let f = match side {
        0 => (p[0] - ul) / w,
        1 => (p[1] - vl) / h,
        2 => (uh - p[0]) / w,
        _ => (vh - p[1]) / h,
    };
    (side as f64 + f.clamp(0.0, 1.0)).rem_euclid(4.0)
}

/// The triangles of the trimmed region inside one grid cell `rect =
/// [u_lo, u_hi, v_lo, v_hi]`, from the pieces of the loops that cross it.
/// Open chains enter and leave through the cell boundary with the region on
/// their left: after a chain leaves, the boundary is walked counter-clockwise
/// (taking the corners passed) to the next entering chain, until the polygon
/// closes. Closed chains are whole loops: an outer loop is a polygon of its
/// own, a hole is bridged into the polygon that holds it.
fn clip_cell(
    chains: &[Chain],
    rect: [f64; 4],
    corners: &[(Vert, [f64; 2]); 4],
    inside: impl Fn([f64; 2]) -> bool,
) -> Vec<[Vert; 3]> {
    type Poly = Vec<(Vert, [f64; 2])>;
    let open: Vec<&Chain> = chains.iter().filter(|c| !c.closed).collect();
    let mut polys: Vec<Poly> = Vec::new();
    let mut holes: Vec<Poly> = Vec::new();
    for c in chains.iter().filter(|c| c.closed) {
        let pts: Vec<[f64; 2]> = c.points.iter().map(|p| p.1).collect();
        if super::trim::polygon_signed_area2(&pts) > 0.0 {
            polys.push(c.points.clone());
        } else {
            holes.push(c.points.clone());
        }
    }
    if open.is_empty() {
        // Only whole loops inside the cell: the cell itself is a polygon
        // when its corner lies in the face (then the loops are holes).
        if inside(corners[0].1) {
            polys.push(corners.to_vec());
        }
    } else {
        let entry: Vec<f64> = open
            .iter()
            .map(|c| perimeter(c.points[0].1, rect))
            .collect();
        let exit: Vec<f64> = open
            .iter()
            .map(|c| perimeter(c.points[c.points.len() - 1].1, rect))
            .collect();
        let mut used = vec![false; open.len()];
        for first in 0..open.len() {
            if used[first] {
                continue;
            }
            let mut poly: Poly = Vec::new();
            let mut cur = first;
            for _ in 0..=open.len() {
                used[cur] = true;
                let pts = &open[cur].points;
                poly.extend_from_slice(pts);
                let s = exit[cur];
                // The next chain entering counter-clockwise from here.
                let dist = |e: f64| {
                    let d = (e - s).rem_euclid(4.0);
                    if d.is_finite() { d } else { 0.0 }
                };
                let next = (0..open.len())
                    .filter(|&k| !used[k] || k == first)
                    .min_by(|&i, &j| dist(entry[i]).total_cmp(&dist(entry[j])));
                let Some(next) = next else { break };
                let d = dist(entry[next]);
                let mut cs: Vec<(f64, usize)> = (0..4)
                    .map(|k| (dist(k as f64), k))
                    .filter(|&(dc, _)| dc > 0.0 && dc < d)
                    .collect();
                cs.sort_by(|x, y| x.0.total_cmp(&y.0));
                for (_, k) in cs {
                    poly.push(corners[k]);
                }
                if next == first {
                    break;
                }
                cur = next;
            }
            // Drop repeated consecutive vertices (chain ends meet).
            poly.dedup_by(|a, b| a.0 == b.0);
            while poly.len() > 1 && poly.first().map(|p| p.0) == poly.last().map(|p| p.0) {
                poly.pop();
            }
            if poly.len() >= 3 {
                polys.push(poly);
            }
        }
    }
    for hole in holes {
        let probe = hole[0].1;
        let holder = polys.iter().position(|p| {
            let pts: Vec<[f64; 2]> = p.iter().map(|q| q.1).collect();
            winding_number(&pts, probe) != 0
        });
        if let Some(k) = holder {
            let merged = bridge_hole(&polys[k], &hole);
            polys[k] = merged;
        }
    }
    let mut out = Vec::new();
    for p in &polys {
        ear_clip(p, &mut out);
    }
    out
}

/// Whether the open segments `a b` and `c d` cross (touching at shared
/// endpoints does not count).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    if a == c || a == d || b == c || b == d {
        return false;
    }
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    (o1 > 0.0) != (o2 > 0.0) && (o3 > 0.0) != (o4 > 0.0) && o1 != 0.0 && o2 != 0.0
}

/// Joins a clockwise hole to a counter-clockwise polygon through a bridge
/// from the hole's leftmost vertex to the nearest polygon vertex it sees.
fn bridge_hole(poly: &[(Vert, [f64; 2])], hole: &[(Vert, [f64; 2])]) -> Vec<(Vert, [f64; 2])> {
    let hi = (0..hole.len())
        .min_by(|&i, &j| hole[i].1[0].total_cmp(&hole[j].1[0]))
        .unwrap_or(0);
    let h = hole[hi].1;
    let edges_ok = |p: [f64; 2]| {
        let all = [poly, hole];
        all.iter().all(|ring| {
            (0..ring.len()).all(|k| {
                let (a, b) = (ring[k].1, ring[(k + 1) % ring.len()].1);
                !segments_cross(h, p, a, b)
            })
        })
    };
    let mut order: Vec<usize> = (0..poly.len()).collect();
    let d2 = |p: [f64; 2]| (p[0] - h[0]).powi(2) + (p[1] - h[1]).powi(2);
    order.sort_by(|&i, &j| d2(poly[i].1).total_cmp(&d2(poly[j].1)));
    let pi = order
        .iter()
        .copied()
        .find(|&i| edges_ok(poly[i].1))
        .unwrap_or(order[0]);
    let mut out = Vec::with_capacity(poly.len() + hole.len() + 2);
    out.extend_from_slice(&poly[..=pi]);
    out.extend_from_slice(&hole[hi..]);
    out.extend_from_slice(&hole[..=hi]);
    out.extend_from_slice(&poly[pi..]);
    out
}

/// Ear clipping of a simple counter-clockwise polygon (bridged holes
/// allowed) into triangles appended to `out`. Ears are strictly convex
/// corners with no other vertex inside or on them; when none is left (a
/// degenerate remainder), the flattest corner is cut off.
fn ear_clip(poly: &[(Vert, [f64; 2])], out: &mut Vec<[Vert; 3]>) {
    let mut idx: Vec<usize> = (0..poly.len()).collect();
    let p = |k: usize| poly[k].1;
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let in_tri = |q: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0
    };
    let mut guard = 0usize;
    while idx.len() > 3 && guard < 4 * poly.len() * poly.len() + 16 {
        guard += 1;
        let n = idx.len();
        let mut cut = None;
        for k in 0..n {
            let (ia, ib, ic) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
            let (a, b, c) = (p(ia), p(ib), p(ic));
            if cross(a, b, c) <= 0.0 {
                continue;
            }
            let blocked = idx.iter().any(|&j| {
                j != ia
                    && j != ib
                    && j != ic
                    && poly[j].1 != a
                    && poly[j].1 != b
                    && poly[j].1 != c
                    && in_tri(poly[j].1, a, b, c)
            });
            if !blocked {
                cut = Some(k);
                break;
            }
        }
        let k = cut.unwrap_or_else(|| {
            (0..n)
                .min_by(|&i, &j| {
                    let f = |k: usize| {
                        cross(p(idx[(k + n - 1) % n]), p(idx[k]), p(idx[(k + 1) % n])).abs()
                    };
                    f(i).total_cmp(&f(j))
                })
                .unwrap_or(0)
        });
        let (ia, ib, ic) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
        if cross(p(ia), p(ib), p(ic)) > 0.0 {
            out.push([poly[ia].0, poly[ib].0, poly[ic].0]);
        }
        idx.remove(k);
    }
    if idx.len() == 3 {
        let (a, b, c) = (idx[0], idx[1], idx[2]);
        if cross(p(a), p(b), p(c)) > 0.0 {
            out.push([poly[a].0, poly[b].0, poly[c].0]);
        }
    }
}

/// Area of the trimmed surface (model units²): `∫∫ |Su × Sv| du dv`
/// over the trimmed region of the parameter plane, on the `nu × nv` grid of
/// [`tessellate`]: a grid cell wholly inside the face is integrated with the
/// 3 × 3 Gauss–Legendre rule (degree 5 in each direction) on each piece of
/// the cell between knots (the integrand is smooth only between knots), its
/// nodes evaluated together over the whole grid by
/// [`BSplineSurface::map_grid_first`] (basis functions once per node row and
/// column); a cell the trimming loops cut is split as in [`tessellate`] and
/// its (u, v) triangles integrated with the 6-point degree-4 Gauss rule on
/// the triangle (Dunavant 1985). Independent of the 3-D triangle areas, it
/// converges to the exact area as the trim flattening tolerance
/// ([`super::TRIM_FLATNESS`]) and the curvature of `|Su × Sv|` allow.
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
    let t = tessellate(surface, nu, nv);
    let parts: Vec<f64> = t
        .triangles
        .par_iter()
        .map(|tri| dunavant_area(surface, tri.map(|k| t.uv[k as usize])))
        .collect();
    parts.iter().sum()
}
