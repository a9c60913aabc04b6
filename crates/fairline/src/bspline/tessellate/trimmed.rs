//! Triangulation of a trimmed surface: the parameter grid clipped by the
//! trimming loops cell by cell, the loops refined where they cross grid
//! lines and split into chains per cell.

use rayon::prelude::*;

use super::polygon::clip_cell;
use super::{Tessellation, fill_missing_normals, grid_param};
use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::bspline::trim::{TrimmedDomain, inside_by_crossings};

/// A vertex of the trimmed tessellation before compaction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Vert {
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
pub(super) struct Chain {
    /// Vertex ids and their parameters, in loop order.
    pub(super) points: Vec<(Vert, [f64; 2])>,
    /// The loop closes inside the cell (the whole loop is this chain).
    pub(super) closed: bool,
}

/// How the trimmed face covers one grid cell.
pub(super) enum CellCover {
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
pub(super) struct ClippedGrid {
    pub(super) cells: Vec<CellCover>,
    pub(super) extra: Vec<[f64; 2]>,
}

pub(super) fn tessellate_trimmed(
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
pub(super) fn clip_grid(trim: &TrimmedDomain, us: &[f64], vs: &[f64]) -> ClippedGrid {
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
pub(super) fn perimeter(p: [f64; 2], [ul, uh, vl, vh]: [f64; 4]) -> f64 {
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
