//! Contouring of the signed distance field: marching squares on the
//! `(u, v)` grid, chaining of the cell segments into polylines, clipping to
//! the trims, and refinement of every point onto the true level along its
//! grid edge.

use super::{
    DistanceField, FieldSample, SurfaceHighlightLine, SurfaceHighlightOptions, SurfaceLight,
    surface_signed_distance,
};
use crate::bspline::BSplineSurface;
use crate::highlight::contour;
use rayon::prelude::*;

/// A grid edge: horizontal (along u) from `(a, b)` to `(a + 1, b)`, or
/// vertical (along v) from `(a, b)` to `(a, b + 1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GridEdge {
    U(usize, usize),
    V(usize, usize),
}

/// The level `level` of a sampled field as polylines in `(u, v)` (marching
/// squares) mapped to 3D:
///
/// - a grid edge carries a contour point when both ends are defined, lie on
///   the same branch (branch angles less than 90° apart) and on different
///   sides of the level (a value equal to the level counts as above);
/// - a cell whose four corners and edges are all valid contributes one
///   segment per pair of crossed edges; with four crossed edges (a saddle)
///   the value at the cell centre (mean of the corners) decides: the
///   segments cut off the corners on the other side of the level than the
///   centre, the same rule in every cell (consistent, no crossings);
/// - segments are chained through shared edges into open or closed lines;
/// - each point is refined along its grid edge by the Illinois variant of
///   regula falsi on the exact field until |d_s − level| ≤ `opts.tolerance`
///   (or `opts.max_refine_steps`); if the field becomes undefined inside
///   the edge, or the refinement finds no zero (the sign change is a jump
///   of d_s, e.g. where the nearest root of the quartic switches), the
///   point is dropped and its line split there.
pub fn contour_field(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    light_index: usize,
    field: &DistanceField,
    level: f64,
    opts: &SurfaceHighlightOptions,
) -> Vec<SurfaceHighlightLine> {
    let (nu, nv) = (field.us.len(), field.vs.len());
    if nu < 2 || nv < 2 || field.samples.len() != nu * nv {
        return Vec::new();
    }
    let edges = GridEdges { nu, nv };
    let segments = cell_segments(field, &edges, light, level, opts);
    if segments.is_empty() {
        return Vec::new();
    }
    let (nodes, chains) = chain_segments(&segments);
    // Refine every node onto the level along its grid edge; a crossing that
    // is a jump of the field (no zero inside the edge) is dropped.
    let refined: Vec<Option<[f64; 2]>> = nodes
        .par_iter()
        .map(|&id| {
            let ((a0, b0), (a1, b1)) = edges.ends(edges.edge(id));
            let p0 = [field.us[a0], field.vs[b0]];
            let p1 = [field.us[a1], field.vs[b1]];
            let f0 = field.samples[a0 * nv + b0].map_or(0.0, |s| s.value) - level;
            let f1 = field.samples[a1 * nv + b1].map_or(0.0, |s| s.value) - level;
            refine_on_edge(surface, light, level, p0, p1, f0, f1, opts)
        })
        .collect();
    let mut pieces = split_at_dropped_points(chains, &refined);
    if surface.is_trimmed() {
        pieces = clip_to_trims(surface, pieces);
    }
    pieces
        .into_iter()
        .filter(|(_, uv)| uv.len() >= 2)
        .map(|(closed, uv)| {
            let points = uv.iter().map(|&[u, v]| surface.eval(u, v)).collect();
            SurfaceHighlightLine {
                light: light_index,
                radius: light.radius(),
                level,
                closed,
                uv,
                points,
            }
        })
        .collect()
}

/// The edges of an `nu × nv` grid and their ids: `U(a, b)` → `a * nv + b`,
/// `V(a, b)` → `(nu − 1) nv + a (nv − 1) + b`.
#[derive(Clone, Copy, Debug)]
struct GridEdges {
    nu: usize,
    nv: usize,
}

impl GridEdges {
    /// The id of an edge.
    fn id(&self, e: GridEdge) -> usize {
        let n_u_edges = (self.nu - 1) * self.nv;
        match e {
            GridEdge::U(a, b) => a * self.nv + b,
            GridEdge::V(a, b) => n_u_edges + a * (self.nv - 1) + b,
        }
    }
    /// The edge of an id.
    fn edge(&self, id: usize) -> GridEdge {
        let n_u_edges = (self.nu - 1) * self.nv;
        if id < n_u_edges {
            GridEdge::U(id / self.nv, id % self.nv)
        } else {
            let k = id - n_u_edges;
            GridEdge::V(k / (self.nv - 1), k % (self.nv - 1))
        }
    }
    /// The grid points at the ends of an edge.
    fn ends(&self, e: GridEdge) -> ((usize, usize), (usize, usize)) {
        match e {
            GridEdge::U(a, b) => ((a, b), (a + 1, b)),
            GridEdge::V(a, b) => ((a, b), (a, b + 1)),
        }
    }
}

/// Marching squares on the level `level` of `field` (the rules of
/// [`contour_field`]): the segments of every cell as pairs of edge ids, in
/// cell order (parallel over cell rows, deterministic).
fn cell_segments(
    field: &DistanceField,
    edges: &GridEdges,
    light: &SurfaceLight,
    level: f64,
    opts: &SurfaceHighlightOptions,
) -> Vec<[usize; 2]> {
    let (nu, nv) = (edges.nu, edges.nv);
    let at = |a: usize, b: usize| field.samples[a * nv + b];
    // Linear lights: a cell crossed by more than `max_lines_per_cell`
    // levels holds lines finer than the grid (near silhouettes, where d_P
    // runs off as Z·N → 0); it is skipped by the rule the mesh model skips
    // triangles with (`HighlightOptions::max_lines_per_face`).
    let max_cell_levels = match light {
        SurfaceLight::Linear { array, .. } if opts.max_lines_per_cell > 0 => {
            Some((array.spacing(), i64::from(opts.max_lines_per_cell)))
        }
        _ => None,
    };
    (0..nu - 1)
        .into_par_iter()
        .flat_map_iter(|a| {
            let mut segs = Vec::new();
            for b in 0..nv - 1 {
                let [Some(c0), Some(c1), Some(c2), Some(c3)] =
                    [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]
                else {
                    continue;
                };
                cell_segment(
                    [c0, c1, c2, c3],
                    [a, b],
                    edges,
                    level,
                    max_cell_levels,
                    &mut segs,
                );
            }
            segs
        })
        .collect()
}

/// The segments of cell `(a, b)` with corner samples `c` (counter-clockwise
/// from `(a, b)`), appended to `segs`; see [`contour_field`].
fn cell_segment(
    c: [FieldSample; 4],
    [a, b]: [usize; 2],
    edges: &GridEdges,
    level: f64,
    max_cell_levels: Option<(f64, i64)>,
    segs: &mut Vec<[usize; 2]>,
) {
    let above = |s: FieldSample| s.value >= level;
    let same_branch = |x: FieldSample, y: FieldSample| (x.branch - y.branch).cos() > 0.0;
    // Cheap tests first: most cells are not crossed by the level.
    let side = c.map(above);
    if side.iter().all(|&x| x == side[0]) {
        return;
    }
    if let Some((spacing, most)) = max_cell_levels {
        let (lo, hi) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                (l.min(s.value), h.max(s.value))
            });
        // the levels of this field are m·s − shift: count them
        // as the mesh does (`contour::too_many_levels`)
        if contour::too_many_levels(lo, hi, spacing, level.rem_euclid(spacing), most) {
            return;
        }
    }
    if !(same_branch(c[0], c[1])
        && same_branch(c[1], c[2])
        && same_branch(c[2], c[3])
        && same_branch(c[3], c[0]))
    {
        return;
    }
    // Cell edges in order: bottom (c0-c1), right (c1-c2), top (c3-c2), left (c0-c3).
    let cell_edges = [
        GridEdge::U(a, b),
        GridEdge::V(a + 1, b),
        GridEdge::U(a, b + 1),
        GridEdge::V(a, b),
    ];
    let cut: Vec<usize> = (0..4).filter(|&k| side[k] != side[(k + 1) % 4]).collect();
    match cut.len() {
        2 => segs.push([edges.id(cell_edges[cut[0]]), edges.id(cell_edges[cut[1]])]),
        4 => {
            let centre = 0.25 * (c[0].value + c[1].value + c[2].value + c[3].value);
            let centre_above = centre >= level;
            // Corner k touches edges k-1 (previous) and k.
            for k in 0..4 {
                if side[k] != centre_above {
                    segs.push([edges.id(cell_edges[(k + 3) % 4]), edges.id(cell_edges[k])]);
                }
            }
        }
        _ => {}
    }
}

/// Chains segments (pairs of edge ids; every edge has at most two) through
/// their shared edges: the sorted edge ids (the nodes) and the chains as
/// (closed, node positions), open chains first (from their ends), then the
/// loops.
fn chain_segments(segments: &[[usize; 2]]) -> (Vec<usize>, Vec<(bool, Vec<usize>)>) {
    let mut nodes: Vec<usize> = segments.iter().flatten().copied().collect();
    nodes.sort_unstable();
    nodes.dedup();
    let index_of = |id: usize| nodes.binary_search(&id).unwrap_or(0);
    let mut adj: Vec<[usize; 2]> = vec![[usize::MAX; 2]; nodes.len()];
    for s in segments {
        let (x, y) = (index_of(s[0]), index_of(s[1]));
        for (p, q) in [(x, y), (y, x)] {
            if adj[p][0] == usize::MAX {
                adj[p][0] = q;
            } else if adj[p][1] == usize::MAX {
                adj[p][1] = q;
            }
        }
    }
    let degree = |p: usize| adj[p].iter().filter(|&&q| q != usize::MAX).count();
    let mut used = vec![false; nodes.len()];
    let mut chains: Vec<(bool, Vec<usize>)> = Vec::new();
    let walk = |start: usize, used: &mut Vec<bool>| -> (bool, Vec<usize>) {
        let mut chain = vec![start];
        used[start] = true;
        let mut prev = usize::MAX;
        let mut cur = start;
        loop {
            let next = adj[cur]
                .iter()
                .copied()
                .find(|&q| q != usize::MAX && q != prev && !used[q]);
            match next {
                Some(q) => {
                    used[q] = true;
                    chain.push(q);
                    prev = cur;
                    cur = q;
                }
                None => {
                    let closed = chain.len() > 2 && adj[cur].contains(&start);
                    return (closed, chain);
                }
            }
        }
    };
    for p in 0..nodes.len() {
        if !used[p] && degree(p) <= 1 {
            let c = walk(p, &mut used);
            chains.push((false, c.1));
        }
    }
    for p in 0..nodes.len() {
        if !used[p] {
            chains.push(walk(p, &mut used));
        }
    }
    (nodes, chains)
}

/// The chains as polylines of refined points, each split where a point was
/// dropped (`None`; a loop is opened at its first dropped point).
fn split_at_dropped_points(
    chains: Vec<(bool, Vec<usize>)>,
    refined: &[Option<[f64; 2]>],
) -> Vec<(bool, Vec<[f64; 2]>)> {
    let mut pieces: Vec<(bool, Vec<[f64; 2]>)> = Vec::new();
    for (closed, chain) in chains {
        if chain.iter().all(|&p| refined[p].is_some()) {
            pieces.push((closed, chain.iter().filter_map(|&p| refined[p]).collect()));
            continue;
        }
        let n = chain.len();
        let shift = if closed {
            chain
                .iter()
                .position(|&p| refined[p].is_none())
                .unwrap_or(0)
        } else {
            0
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        for k in 0..n {
            match refined[chain[(shift + k) % n]] {
                Some(p) => run.push(p),
                None => pieces.push((false, std::mem::take(&mut run))),
            }
        }
        pieces.push((false, run));
    }
    pieces
}

/// Keeps the parts of `(closed, uv)` polylines that lie in the trimmed face
/// ([`BSplineSurface::contains_uv`]): a polyline is cut where it leaves the
/// face, the cut point found by bisection (40 steps) on the segment between
/// the inside and the outside point, so lines end on the trimming loop.
fn clip_to_trims(
    surface: &BSplineSurface,
    pieces: Vec<(bool, Vec<[f64; 2]>)>,
) -> Vec<(bool, Vec<[f64; 2]>)> {
    let boundary = |inside: [f64; 2], outside: [f64; 2]| {
        let (mut a, mut b) = (inside, outside);
        for _ in 0..40 {
            let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            if surface.contains_uv(m[0], m[1]) {
                a = m;
            } else {
                b = m;
            }
        }
        a
    };
    let mut out = Vec::new();
    for (closed, uv) in pieces {
        let inside: Vec<bool> = uv.iter().map(|p| surface.contains_uv(p[0], p[1])).collect();
        if inside.iter().all(|&x| x) {
            out.push((closed, uv));
            continue;
        }
        let n = uv.len();
        // Start a loop at an outside point so that runs do not wrap.
        let (shift, count) = if closed {
            (inside.iter().position(|&x| !x).unwrap_or(0), n + 1)
        } else {
            (0, n)
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        for k in 0..count {
            let i = (shift + k) % n;
            if inside[i] {
                if run.is_empty() && k > 0 {
                    let prev = (shift + k - 1) % n;
                    run.push(boundary(uv[i], uv[prev]));
                }
                run.push(uv[i]);
            } else if !run.is_empty() {
                let prev = (shift + k + n - 1) % n;
                run.push(boundary(uv[prev], uv[i]));
                out.push((false, std::mem::take(&mut run)));
            }
        }
        if !run.is_empty() {
            out.push((false, run));
        }
    }
    out
}

/// The point of the segment `p0 → p1` where the field equals `level`, with
/// `f0 = field(p0) − level` and `f1 = field(p1) − level` of opposite signs:
/// Illinois regula falsi on the exact field (safeguarded by the bracket).
/// `None` when the sign change is a jump of the field rather than a zero
/// (the best |f| found stays above 1e-6 of the end values and above the
/// tolerance).
#[allow(clippy::too_many_arguments)]
fn refine_on_edge(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    level: f64,
    p0: [f64; 2],
    p1: [f64; 2],
    f0: f64,
    f1: f64,
    opts: &SurfaceHighlightOptions,
) -> Option<[f64; 2]> {
    let lerp = |t: f64| [p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])];
    let linear_t = |fa: f64, fb: f64, ta: f64, tb: f64| {
        let den = fa - fb;
        if den != 0.0 && den.is_finite() {
            (ta + fa * (tb - ta) / den).clamp(ta.min(tb), ta.max(tb))
        } else {
            0.5 * (ta + tb)
        }
    };
    if f0 == 0.0 {
        return Some(p0);
    }
    if f1 == 0.0 {
        return Some(p1);
    }
    let (mut ta, mut fa, mut tb, mut fb) = (0.0, f0, 1.0, f1);
    let mut best = (linear_t(fa, fb, ta, tb), f64::INFINITY);
    let mut side = 0i8;
    for _ in 0..opts.max_refine_steps {
        let t = linear_t(fa, fb, ta, tb);
        let [u, v] = lerp(t);
        let Some(ft) = surface_signed_distance(surface, light, u, v).map(|d| d - level) else {
            // Undefined inside the edge: no reliable zero there.
            return None;
        };
        if ft.abs() < best.1 {
            best = (t, ft.abs());
        }
        if ft.abs() <= opts.tolerance || (tb - ta).abs() < 1e-15 {
            break;
        }
        if (ft < 0.0) == (fa < 0.0) {
            ta = t;
            fa = ft;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            tb = t;
            fb = ft;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    // A true zero brings |f| down to the tolerance (or to rounding level on
    // a collapsed bracket); a jump leaves it near the jump's size.
    let accept = best.1 <= opts.tolerance.max(1e-6 * f0.abs().max(f1.abs()));
    accept.then(|| lerp(best.0))
}
