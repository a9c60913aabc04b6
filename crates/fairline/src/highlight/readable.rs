//! Line density of a linear light array on a part, and the readable
//! drawing of its highlight lines (beyond Yong et al., who draw every line:
//! on round parts the lines of Eq. (1) crowd toward the silhouette, where
//! d_P = ((P − A0) × N)·H / (Z·N) runs off like tan of the normal's angle
//! to Z, and a picture shows them as black hatching and broken pieces).
//!
//! Two quantities, both from the per-vertex highlight distances d_P:
//!
//! - the **distance gradient** |∇d| of the piecewise-linear interpolant of
//!   d_P on each triangle: neighbouring lines (levels m·s and (m+1)·s) lie
//!   s/|∇d| apart on the surface. A flat panel facing the lights has
//!   |∇d| = 1 (d_P is the position across the lights); a part of curvature
//!   κ at distance L from the light plane has |∇d| ≈ 1 + L·κ/cos²θ;
//! - the **readable drawing**: the lines cut where their separation
//!   s/|∇d| falls below [`Readability::min_separation`] (denser than the
//!   picture resolves) and pieces shorter than
//!   [`Readability::min_length`] left out. This changes only what is
//!   drawn; the lines themselves (the data, `HighlightModel::lines`) are
//!   untouched.

use super::{HighlightLine, HighlightLines, LightArray, NodeId};
use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh};
use rayon::prelude::*;

/// |∇d| of the linear interpolant of the per-vertex values `d` on each
/// triangle (mesh units per mesh unit, i.e. dimensionless); `None` where a
/// vertex has no highlight distance (`branch` 0), the branches (sides of
/// the light plane the normal points to) differ, or the triangle is
/// degenerate.
///
/// For a triangle (a, b, c) with area vector n = (b − a) × (c − a):
/// ∇d = ((d_b − d_a)·(n × (a − c)) + (d_c − d_a)·(n × (b − a))) / |n|²
/// — the gradient of the linear function with those vertex values.
pub fn face_distance_gradients(mesh: &SurfaceMesh, d: &[f64], branch: &[i8]) -> Vec<Option<f64>> {
    let p = mesh.positions();
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| v.idx());
            if branch[a] == 0 || branch[a] != branch[b] || branch[a] != branch[c] {
                return None;
            }
            let (e1, e2) = (p[b] - p[a], p[c] - p[a]);
            let n = e1.cross(e2);
            let n2 = n.length_squared();
            if !(n2 > 0.0) || !n2.is_finite() {
                return None;
            }
            let g = ((d[b] - d[a]) * n.cross(-e2) + (d[c] - d[a]) * n.cross(e1)) / n2;
            let g = g.length();
            g.is_finite().then_some(g)
        })
        .collect()
}

/// Most triangles [`sampled_median_distance_gradient`] evaluates by
/// default: a larger mesh is sampled (see [`sample_faces`]),
/// which keeps choosing the readable lights of a 450k-vertex part to a few
/// milliseconds; the median of |∇d| over tens of thousands of triangles
/// spread over the whole part is the median of all of them to far better
/// than the rounding of k = round(ĝ/3) needs.
pub(crate) const GRADIENT_SAMPLE_FACES: usize = 32_768;

/// The area-weighted median ĝ of |∇d_P| under `light` (model units of d
/// per unit of length: lines of spacing s lie about s/ĝ apart on the
/// part), estimated on at most 32 768 triangles spread over the part;
/// `None` when no triangle has a gradient. What a viewer needs to choose
/// a spacing whose lines lie a given number of pixels apart.
pub fn distance_gradient_median(mesh: &SurfaceMesh, light: &LightArray) -> Option<f64> {
    sampled_median_distance_gradient(mesh, light, GRADIENT_SAMPLE_FACES)
}

/// The area-weighted median ĝ of |∇d| (see [`face_distance_gradients`])
/// under `light`, estimated on at most `budget` triangles picked by
/// [`sample_faces`] (all of them when F ≤ budget),
/// with d_P evaluated only at their vertices (normals of Yong et al.
/// Eq. (3), bit-identical to [`crate::geom::vertex_normals`]). `None` when
/// no sampled triangle has a gradient.
pub(crate) fn sampled_median_distance_gradient(
    mesh: &SurfaceMesh,
    light: &LightArray,
    budget: usize,
) -> Option<f64> {
    let min_cos = super::HighlightOptions::default().min_normal_cos;
    let p = mesh.positions();
    let faces = sample_faces(mesh.face_count(), budget);
    let v: Vec<(f64, f64)> = faces
        .par_iter()
        .filter_map(|&f| {
            let [a, b, c] = mesh.triangle(FaceId(f));
            let [(da, ba), (db, bb), (dc, bc)] = [a, b, c].map(|v| {
                let n = crate::geom::vertex_normal(mesh, v);
                super::light::vertex_distance(light, p[v.idx()], n, min_cos)
            });
            if ba == 0 || ba != bb || ba != bc {
                return None;
            }
            let (e1, e2) = (p[b.idx()] - p[a.idx()], p[c.idx()] - p[a.idx()]);
            let n = e1.cross(e2);
            let n2 = n.length_squared();
            if !(n2 > 0.0) || !n2.is_finite() {
                return None;
            }
            let g = ((db - da) * n.cross(-e2) + (dc - da) * n.cross(e1)) / n2;
            let g = g.length();
            let area = 0.5 * n2.sqrt();
            (g.is_finite() && area.is_finite()).then_some((g, area))
        })
        .collect();
    weighted_median(v)
}

/// At most `budget` face indices out of `nf`, sorted: all of them when
/// `nf ≤ budget`, otherwise the Weyl sequence ⌊frac((k + ½)/φ) · nf⌋,
/// k = 0 … budget − 1 (φ the golden ratio). A regular stride aliases with
/// the rows and columns of structured meshes (a cylinder's every k-th
/// triangle can fall on one side of every quad); the golden-ratio sequence
/// spreads the sample evenly over any face order. Deterministic.
pub(crate) fn sample_faces(nf: usize, budget: usize) -> Vec<u32> {
    let budget = budget.max(1);
    if nf <= budget {
        return (0..nf as u32).collect();
    }
    let step = (5f64.sqrt() - 1.0) / 2.0; // 1/φ
    let mut faces: Vec<u32> = (0..budget)
        .map(|k| {
            let x = ((k as f64 + 0.5) * step).fract();
            ((x * nf as f64) as usize).min(nf - 1) as u32
        })
        .collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// The area-weighted median of |∇d| over the triangles that have one
/// (see [`face_distance_gradients`]); `None` when none has.
#[cfg(test)]
pub(crate) fn median_distance_gradient(
    mesh: &SurfaceMesh,
    d: &[f64],
    branch: &[i8],
) -> Option<f64> {
    let g = face_distance_gradients(mesh, d, branch);
    let areas = crate::geom::face_areas(mesh);
    let v: Vec<(f64, f64)> = g
        .iter()
        .zip(&areas)
        .filter_map(|(g, &a)| g.filter(|_| a > 0.0 && a.is_finite()).map(|g| (g, a)))
        .collect();
    weighted_median(v)
}

/// The weighted median of (value, weight) pairs; `None` for none.
fn weighted_median(mut v: Vec<(f64, f64)>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|x, y| x.0.total_cmp(&y.0));
    let total: f64 = v.iter().map(|x| x.1).sum();
    let mut acc = 0.0;
    for (g, a) in &v {
        acc += a;
        if acc >= 0.5 * total {
            return Some(*g);
        }
    }
    v.last().map(|x| x.0)
}

/// What a picture of highlight lines can show (mesh units): lines closer
/// together than `min_separation` are not drawn, nor pieces shorter than
/// `min_length`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readability {
    /// Smallest separation s/|∇d| between neighbouring lines that is drawn.
    pub min_separation: f64,
    /// Shortest piece that is drawn.
    pub min_length: f64,
}

/// Separation limit as a fraction of the part's width across the lights:
/// about 6 px on a picture where the part spans 900 px.
const MIN_SEPARATION_OF_WIDTH: f64 = 1.0 / 150.0;
/// Shortest drawn piece as a fraction of the part's width (30 px at
/// 900 px).
const MIN_LENGTH_OF_WIDTH: f64 = 1.0 / 30.0;

impl Readability {
    /// Limits for a picture of the whole part: `min_separation` = width/150
    /// and `min_length` = width/30, with width the part's extent along the
    /// light array's across direction Z × H (its bounding-box diagonal when
    /// that is zero).
    pub fn for_part(mesh: &SurfaceMesh, light: &LightArray) -> Self {
        let width = part_width(mesh.positions(), light.across());
        Readability {
            min_separation: width * MIN_SEPARATION_OF_WIDTH,
            min_length: width * MIN_LENGTH_OF_WIDTH,
        }
    }
}

/// Extent of the finite points along the unit vector `across` (their
/// bounding-box diagonal when that is zero; 1 for no finite point).
pub fn part_width(points: &[Vec3], across: Vec3) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for q in points.iter().filter(|q| q.is_finite()) {
        let t = q.dot(across);
        lo = lo.min(t);
        hi = hi.max(t);
    }
    let width = hi - lo;
    if width > 0.0 && width.is_finite() {
        return width;
    }
    match crate::mesh::bounding_box(points) {
        Some((a, b)) if (b - a).length() > 0.0 && (b - a).length().is_finite() => (b - a).length(),
        _ => 1.0,
    }
}

/// The readable drawing of `lines` (see the module documentation): each
/// line is cut at the nodes where the local separation `spacing`/|∇d| is
/// below `r.min_separation` (|∇d| at a vertex: the area-weighted mean over
/// the triangles around it that have one; at an edge node the larger of
/// its two vertices; a vertex without any gradient counts as unreadable), and the pieces shorter than
/// `r.min_length` are left out. Pieces keep their light index.
pub(crate) fn readable_lines(
    mesh: &SurfaceMesh,
    d: &[f64],
    branch: &[i8],
    spacing: f64,
    lines: &HighlightLines,
    r: &Readability,
) -> HighlightLines {
    let g = face_distance_gradients(mesh, d, branch);
    let areas = crate::geom::face_areas(mesh);
    let vertex_gradient: Vec<f64> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let (mut sum, mut weight) = (0.0, 0.0);
            for f in mesh.vertex_faces(crate::mesh::VertexId(v)) {
                if let Some(x) = g[f.idx()] {
                    sum += areas[f.idx()] * x;
                    weight += areas[f.idx()];
                }
            }
            if weight > 0.0 {
                sum / weight
            } else {
                f64::INFINITY
            }
        })
        .collect();
    // the largest gradient |∇d| at which lines are still drawn
    let max_gradient = if r.min_separation > 0.0 {
        spacing / r.min_separation
    } else {
        f64::INFINITY
    };
    let readable = |n: NodeId| -> bool {
        let gn = match n {
            NodeId::Vertex(v, _) => vertex_gradient[v.idx()],
            NodeId::Edge(e, _) => {
                let (a, b) = mesh.edge_vertices(e);
                vertex_gradient[a.idx()].max(vertex_gradient[b.idx()])
            }
        };
        gn <= max_gradient
    };
    let mut out = Vec::new();
    for line in &lines.lines {
        let keep: Vec<bool> = line.nodes.iter().map(|&n| readable(n)).collect();
        let len = line.points.len();
        if keep.iter().all(|&k| k) {
            if polyline_length(&line.points, line.closed) >= r.min_length {
                out.push(line.clone());
            }
            continue;
        }
        // walk from a cut node (for a loop) or from the start (open line)
        let start = if line.closed {
            keep.iter().position(|&k| !k).unwrap_or(0)
        } else {
            0
        };
        let steps = if line.closed { len + 1 } else { len };
        let mut piece = HighlightLine {
            index: line.index,
            closed: false,
            points: Vec::new(),
            nodes: Vec::new(),
        };
        let flush = |piece: &mut HighlightLine, out: &mut Vec<HighlightLine>| {
            if piece.points.len() >= 2 && polyline_length(&piece.points, false) >= r.min_length {
                out.push(piece.clone());
            }
            piece.points.clear();
            piece.nodes.clear();
        };
        for k in 0..steps {
            let i = (start + k) % len;
            if keep[i] {
                piece.points.push(line.points[i]);
                piece.nodes.push(line.nodes[i]);
            } else {
                flush(&mut piece, &mut out);
            }
        }
        flush(&mut piece, &mut out);
    }
    HighlightLines { lines: out }
}

/// Length of a polyline (with its closing segment when `closed`).
pub fn polyline_length(points: &[Vec3], closed: bool) -> f64 {
    let open: f64 = points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
    match (closed, points.first(), points.last()) {
        (true, Some(a), Some(b)) if points.len() > 2 => open + (*a - *b).length(),
        _ => open,
    }
}

/// How fragmented a set of lines is, in numbers a test or a warning can
/// state: pieces, distinct lights, pieces per light and the median piece
/// length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineStats {
    /// Number of polylines.
    pub pieces: usize,
    /// Number of distinct light indices among them.
    pub lights: usize,
    /// `pieces / lights` (0 without lines).
    pub pieces_per_light: f64,
    /// Median polyline length (mesh units; 0 without lines).
    pub median_length: f64,
    /// Total length of all polylines (mesh units).
    pub total_length: f64,
    /// Length-weighted median piece length ("N50"): the pieces at least
    /// this long hold half of the total length (mesh units; 0 without
    /// lines). Unlike the plain median it is not pulled down by many tiny
    /// closed loops around the bumps of a scan.
    pub n50_length: f64,
}

impl LineStats {
    /// The statistics of `lines`.
    pub fn of(lines: &HighlightLines) -> Self {
        let mut lengths: Vec<f64> = lines
            .lines
            .iter()
            .map(|l| polyline_length(&l.points, l.closed))
            .collect();
        lengths.sort_by(f64::total_cmp);
        let mut idx: Vec<i64> = lines.lines.iter().map(|l| l.index).collect();
        idx.sort_unstable();
        idx.dedup();
        let pieces = lines.lines.len();
        let total_length: f64 = lengths.iter().sum();
        let mut acc = 0.0;
        let mut n50_length = 0.0;
        for &l in lengths.iter().rev() {
            acc += l;
            if acc >= 0.5 * total_length {
                n50_length = l;
                break;
            }
        }
        LineStats {
            pieces,
            lights: idx.len(),
            pieces_per_light: if idx.is_empty() {
                0.0
            } else {
                pieces as f64 / idx.len() as f64
            },
            median_length: lengths.get(pieces / 2).copied().unwrap_or(0.0),
            total_length,
            n50_length,
        }
    }
}

/// The readable spacing of a light array on a part (the lines the
/// picture resolves).
impl LightArray {
    /// How many spacings of `self` apart the lines must be drawn to be
    /// readable on `mesh`: k = max(1, round(ĝ/3)), with ĝ the area-weighted
    /// median of the highlight-distance gradient |∇d| over the lit triangles
    /// (neighbouring lines lie s/|∇d| apart on the surface, see
    /// [`super::readable`]). The lines of the array with spacing k·s and the
    /// same light 0 are exactly the lines of `self` whose index is a
    /// multiple of k.
    ///
    /// With the default spacing s = w/20 (w the part's width across the
    /// lights) this keeps the median line separation at about w/60 or more:
    /// a panel facing the lights has ĝ ≈ 1–3 and keeps k = 1 (about 20
    /// lights across); on a round part d_P grows like the tangent of the
    /// normal's angle to Z (ĝ of 15–30 on the figures in ../shared/data),
    /// and without thinning the lines would lie w/300–w/600 apart, below
    /// what a picture resolves, and break into hatching.
    ///
    /// ĝ is estimated on at most 32 768 triangles spread over the part
    /// (every k-th in face order; all of them on smaller meshes).
    pub fn readable_multiple(&self, mesh: &SurfaceMesh) -> u32 {
        self.readable_multiple_sampled(mesh, GRADIENT_SAMPLE_FACES)
    }

    /// [`Self::readable_multiple`] with ĝ estimated on at most `budget`
    /// triangles.
    pub(crate) fn readable_multiple_sampled(&self, mesh: &SurfaceMesh, budget: usize) -> u32 {
        match sampled_median_distance_gradient(mesh, self, budget) {
            Some(g) if g.is_finite() && g > 0.0 => (g / 3.0).round().clamp(1.0, 1000.0) as u32,
            _ => 1,
        }
    }
}
