//! End tangents of the desired highlight lines from a smooth surface fitted
//! beyond the defect's footprint (beyond the paper).
//!
//! Yong et al. §3.2 ask for desired curves that are "the highlight lines
//! the surface would have without the irregularity": between the nodes Q0
//! and Q1 just outside R they interpolate the line and its direction
//! (the OGH curve of Eq. (5)). The paper estimates the direction T0 at Q0
//! from the line's own course outside R ([`super::desired`]). A defect
//! does not stop at the region's border: its tail tilts the normals of the
//! first rings outside R by a little, and a highlight line moves across by
//! the normal's tilt divided by the curvature, so on a flat-ish panel
//! (a saddle) a tilt of 1e-4 moves the line near Q0 by several 1e-4, while
//! it is clean a few edges farther out. A line that leaves R nearly
//! tangentially runs along that band for a long stretch, so its outside
//! course carries the tail into T0 however the nodes are picked.
//!
//! Here the direction is that of the highlight line of a smooth surface
//! fitted to the vertices *beyond* the footprint — outside R grown by
//! [`FOOTPRINT_RINGS`] rings, within [`FIT_RADIUS`] mean edge lengths of
//! Q0 — and continued to Q0: a weighted least-squares cubic height field
//! z(x, y) over the tangent plane at Q0 (weights (1 − r²/ρ²)², as in the
//! fine fit of [`crate::highlight::detect_irregularities`]). At the point
//! of the fit above Q0, with the fit's normal N(x, y) = (−z_x, −z_y, 1)/|·|,
//! the highlight distance d(x, y) of Eq. (1) has the level line through it
//! in the direction orthogonal to ∇d in the tangent plane:
//! T ∝ (−d_y) S_x + d_x S_y, S the fitted graph (∇d by central
//! differences of the exact polynomial). That is the direction the clean
//! surface's line has at Q0 to within the cubic's truncation over a few
//! edges. T is oriented like the paper's estimate (or like Q1 − Q0 when
//! that is zero), and only its direction enters the OGH curve. Vertices
//! whose normal is more than 60° from the frame's are left out (no height
//! field there). Where the fit has too few points (mesh boundary, tiny
//! mesh), is singular, the highlight distance is undefined, or the fit
//! turns the paper's direction by more than 20° (the tail's correction is
//! under 2° on every generated panel; more means the cubic does not
//! represent the surface: features, noise, coarse meshes), the paper's
//! estimate is kept.
//!
//! Why the fit and not the lines: on the truth of the generated family
//! (module `family`), the paper's energy with tangents fitted to the
//! *truth's* lines beats surface diffusion flow on all 24 cases in all four
//! measures (BENCHMARKS.md), so clean directions at Q0 are what
//! the paper's desired curves need. A Gaussian tail's slope falls by e
//! every σ²/r (under one edge at the border of the family's regions), so
//! one ring beyond R it is several times smaller than at the border and
//! two rings beyond it an order of magnitude; a cubic over six edges
//! represents every smooth panel there. Measured
//! against the exact direction of the truth's line at each end node
//! (test `fitted_end_tangents_follow_the_truths_lines`): within 0.06° on
//! the quadratic, cubic and saddle panels, 5–100× closer than the paper's
//! estimate (up to 0.31°); on the wavy panels, which no cubic over six
//! edges follows exactly, within 1.7° (the paper's: within 1.8°). The
//! footprint (one ring), the radius (six edges) and the flow share of the
//! default were chosen on the family and checked on 32 held-out cases
//! (BENCHMARKS.md).

use super::desired::{Run, Tangents, fitted_tangent, for_each_run, part};
use super::region::MovableSet;
use crate::Vec3;
use crate::highlight::{HighlightLines, LightArray, NodeId};
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::solve::{height_monomials, solve_spd};
use std::collections::BTreeSet;

/// Rings of faces around R that the fit leaves out (the defect's tail).
pub const FOOTPRINT_RINGS: usize = 1;
/// Radius ρ of the fit around Q0, in mean edge lengths of R.
pub const FIT_RADIUS: f64 = 6.0;
/// Smallest cosine between a fitted vertex's normal and the frame's
/// normal: beyond 60° the surface is no height field over the tangent
/// plane at Q0 (a fold, a crease, the far side of a thin part).
const MIN_FRAME_COS: f64 = 0.5;
/// Largest angle (radians, 20°) between the fitted direction and the
/// paper's estimate: the fit corrects the tilt of a defect's tail (under
/// 2° on every generated panel); a larger disagreement means the cubic
/// does not represent the surface there (features, noise, a coarse mesh),
/// and the paper's estimate is kept.
const MAX_CORRECTION: f64 = 0.35;

/// A height field z(x, y) = Σ c_k m_k(x, y) over the plane through
/// `origin` spanned by `bx`, `by`, heights along `n0`, coordinates scaled
/// by `scale`.
struct HeightFit {
    origin: Vec3,
    bx: Vec3,
    by: Vec3,
    n0: Vec3,
    scale: f64,
    c: [f64; 10],
}

impl HeightFit {
    /// Point and unit normal of the graph at (x, y) (scaled coordinates).
    fn point_normal(&self, x: f64, y: f64) -> (Vec3, Vec3) {
        let c = &self.c;
        let z = height_monomials::<10>(x, y)
            .iter()
            .zip(c)
            .map(|(m, k)| m * k)
            .sum::<f64>();
        let zx = c[1]
            + 2.0 * c[3] * x
            + c[4] * y
            + 3.0 * c[6] * x * x
            + 2.0 * c[7] * x * y
            + c[8] * y * y;
        let zy = c[2]
            + c[4] * x
            + 2.0 * c[5] * y
            + c[7] * x * x
            + 2.0 * c[8] * x * y
            + 3.0 * c[9] * y * y;
        let p = self.origin + self.scale * (x * self.bx + y * self.by + z * self.n0);
        let n = (self.n0 - zx * self.bx - zy * self.by).normalize_or_zero();
        (p, n)
    }

    /// Unit direction of the level line of the highlight distance through
    /// the graph's point at the origin, or `None` where d is undefined or
    /// its gradient vanishes.
    fn level_direction(&self, light: &LightArray, min_cos: f64) -> Option<Vec3> {
        let h = 1e-4;
        let d = |x: f64, y: f64| {
            let (p, n) = self.point_normal(x, y);
            light.highlight_distance(p, n, min_cos)
        };
        let dx = (d(h, 0.0)? - d(-h, 0.0)?) / (2.0 * h);
        let dy = (d(0.0, h)? - d(0.0, -h)?) / (2.0 * h);
        let (p0, _) = self.point_normal(0.0, 0.0);
        let sx = (self.point_normal(h, 0.0).0 - self.point_normal(-h, 0.0).0) / (2.0 * h);
        let sy = (self.point_normal(0.0, h).0 - self.point_normal(0.0, -h).0) / (2.0 * h);
        let t = (-dy * sx + dx * sy).normalize_or_zero();
        (p0.is_finite() && t != Vec3::ZERO && t.is_finite()).then_some(t)
    }
}

/// Weighted least-squares height field over `pts` around `q` (unit normal
/// `n0`, radius `rho`): cubic with at least 14 points, else quadric with
/// at least 10; `None` with fewer points or a singular fit.
fn fit_height(q: Vec3, n0: Vec3, pts: &[Vec3], rho: f64) -> Option<HeightFit> {
    let bx = n0.any_orthonormal_vector();
    let by = n0.cross(bx);
    let rows: Vec<([f64; 10], f64, f64)> = pts
        .iter()
        .filter_map(|&p| {
            let d = (p - q) / rho;
            let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n0));
            let w = (1.0 - x * x - y * y).max(0.0).powi(2);
            (w > 0.0).then(|| (height_monomials::<10>(x, y), z, w))
        })
        .collect();
    let c = if rows.len() >= 14 {
        solve_weighted::<10>(&rows)
    } else {
        None
    };
    let c = match c {
        Some(c) => c,
        None if rows.len() >= 10 => {
            let c6 = solve_weighted::<6>(&rows)?;
            let mut c = [0.0; 10];
            c[..6].copy_from_slice(&c6);
            c
        }
        None => return None,
    };
    Some(HeightFit {
        origin: q,
        bx,
        by,
        n0,
        scale: rho,
        c,
    })
}

/// Normal equations of the weighted fit with the first N monomials.
fn solve_weighted<const N: usize>(rows: &[([f64; 10], f64, f64)]) -> Option<[f64; N]> {
    let mut ata = [[0.0f64; N]; N];
    let mut atb = [0.0f64; N];
    for (m, z, w) in rows {
        for i in 0..N {
            for j in i..N {
                ata[i][j] += w * m[i] * m[j];
            }
            atb[i] += w * m[i] * z;
        }
    }
    solve_spd(&ata, &atb)
}

/// Per vertex: within the footprint (a vertex of a face of R grown by
/// `rings` rings).
fn footprint(mesh: &SurfaceMesh, set: &MovableSet, rings: usize) -> Vec<bool> {
    let faces: Vec<FaceId> = mesh
        .faces()
        .filter(|f| set.in_region.get(f.idx()).copied().unwrap_or(false))
        .collect();
    let mut near = vec![false; mesh.vertex_count()];
    for f in super::grow_region(mesh, &faces, rings) {
        for v in mesh.face_vertices(f) {
            near[v.idx()] = true;
        }
    }
    near
}

/// The vertices of the node's edge (or the node's vertex).
fn node_vertices(mesh: &SurfaceMesh, node: NodeId) -> Vec<VertexId> {
    match node {
        NodeId::Edge(e, _) => {
            let (a, b) = mesh.edge_vertices(e);
            vec![a, b]
        }
        NodeId::Vertex(v, _) => vec![v],
    }
}

/// What the fit at one end node needs.
struct EndFit<'a> {
    mesh: &'a SurfaceMesh,
    /// Vertex normals of the mesh (Eq. (3)).
    normals: &'a [Vec3],
    /// Per vertex: within the footprint ([`footprint`]).
    near: &'a [bool],
    light: &'a LightArray,
    min_cos: f64,
    /// Radius ρ of the fit (mesh units).
    rho: f64,
}

impl EndFit<'_> {
    /// The vertices outside the footprint within distance ρ of `q` whose
    /// normals are within 60° of `n0`, reached through the mesh from the
    /// node's vertices.
    fn points(&self, node: NodeId, q: Vec3, n0: Vec3) -> Vec<Vec3> {
        let (mesh, p) = (self.mesh, self.mesh.positions());
        let mut stack: Vec<VertexId> = node_vertices(mesh, node);
        let mut seen: BTreeSet<u32> = stack.iter().map(|v| v.0).collect();
        let mut out = Vec::new();
        while let Some(v) = stack.pop() {
            let normal = self.normals.get(v.idx()).copied().unwrap_or(Vec3::ZERO);
            if !self.near[v.idx()] && p[v.idx()].is_finite() && normal.dot(n0) >= MIN_FRAME_COS {
                out.push(p[v.idx()]);
            }
            for u in mesh.one_ring(v) {
                if (p[u.idx()] - q).length() <= self.rho && seen.insert(u.0) {
                    stack.push(u);
                }
            }
        }
        out
    }

    /// The fitted direction at the end node `node` (position `q`),
    /// oriented like the paper's estimate `paper` (or like `fallback` when
    /// that is zero); the paper's estimate when the fit fails or turns the
    /// direction by more than [`MAX_CORRECTION`].
    fn tangent(&self, (node, q): (NodeId, Vec3), paper: Vec3, fallback: Vec3) -> Vec3 {
        let n0 = node_vertices(self.mesh, node)
            .iter()
            .map(|v| self.normals.get(v.idx()).copied().unwrap_or(Vec3::ZERO))
            .fold(Vec3::ZERO, |a, b| a + b)
            .normalize_or_zero();
        if n0 == Vec3::ZERO || !q.is_finite() {
            return paper;
        }
        let pts = self.points(node, q, n0);
        let Some(t) = fit_height(q, n0, &pts, self.rho)
            .and_then(|f| f.level_direction(self.light, self.min_cos))
        else {
            return paper;
        };
        let reference = if paper != Vec3::ZERO { paper } else { fallback };
        let t = if t.dot(reference) < 0.0 { -t } else { t };
        if paper != Vec3::ZERO && t.angle_between(paper) > MAX_CORRECTION {
            return paper;
        }
        t
    }
}

/// Tangents T0, T1 of every desired line of `lines` (the runs of the nodes
/// inside R, §3.2) from the smooth fit beyond the footprint (module
/// documentation), to be used by [`super::desired_lines_with`];
/// `normals` are the mesh's vertex normals (Eq. (3)), `ebar` the mean edge
/// length inside R (the fit's radius is [`FIT_RADIUS`] · ē).
pub fn fitted_surface_tangents(
    mesh: &SurfaceMesh,
    set: &MovableSet,
    normals: &[Vec3],
    lines: &HighlightLines,
    light: &LightArray,
    min_cos: f64,
    ebar: f64,
) -> Tangents {
    let near = footprint(mesh, set, FOOTPRINT_RINGS);
    let fit = EndFit {
        mesh,
        normals,
        near: &near,
        light,
        min_cos,
        rho: FIT_RADIUS * ebar,
    };
    let mut out = Tangents::new();
    for_each_run(
        lines,
        |n| set.node_inside(mesh, n),
        |run| {
            let Run { seq, ins, a, b, .. } = *run;
            let (q0, q1) = (seq[a - 1], seq[b]);
            // the paper's estimate (module `desired`), for the orientation
            // and where the fit fails
            let reach = 0.5 * (q1.1 - q0.1).length();
            let (p0, s0) = part(seq, ins, false, a - 1, -1, reach, 3);
            let (p1, s1) = part(seq, ins, false, b, 1, reach, 3);
            let chord = q1.1 - q0.1;
            let t = (
                fit.tangent(q0, fitted_tangent(q0.1, &p0, &s0), chord),
                fit.tangent(q1, fitted_tangent(q1.1, &p1, &s1), chord),
            );
            if t.0.is_finite() && t.1.is_finite() {
                out.insert((q0.0, q1.0), t);
            }
        },
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fair::{desired_lines, movable_vertices};
    use crate::highlight::{HighlightModel, HighlightOptions};
    use crate::io::RegionSpec;
    use crate::shapes;

    /// Where nothing lies beyond the footprint (the region is the whole
    /// panel; its lines end on the mesh boundary) the fit has no point and every
    /// tangent is the paper's outside estimate, bit for bit; with the
    /// region in the middle the fit replaces them (and stays within 20°).
    #[test]
    fn without_points_beyond_the_footprint_the_papers_tangents_are_kept() {
        let mesh = shapes::height_field(21, 21, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
            0.1 * x * x - 0.05 * y * y + 0.01 * (-(x * x + y * y) / 0.02).exp()
        });
        let light = LightArray::new(
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(0.0, 0.15, 1.0),
            Vec3::X,
            0.05,
        )
        .unwrap();
        let model = HighlightModel::new(&mesh, light, HighlightOptions::default()).unwrap();
        let lines = model.lines(&mesh);
        let nodes: Vec<NodeId> = lines.lines.iter().flat_map(|l| l.nodes.clone()).collect();
        let middle = RegionSpec::Sphere {
            center: Vec3::new(0.0, 0.0, 0.01),
            radius: 0.5,
        }
        .faces(&mesh)
        .unwrap();
        for (faces, same) in [(mesh.faces().collect::<Vec<_>>(), true), (middle, false)] {
            let set = movable_vertices(&mesh, &faces, &nodes).unwrap();
            let inside = |n| set.node_inside(&mesh, n);
            let fitted =
                fitted_surface_tangents(&mesh, &set, model.normals(), &lines, &light, 0.1, 0.1);
            let paper = desired_lines(&lines, inside);
            assert!(!paper.lines.is_empty());
            let mut changed = 0;
            for l in &paper.lines {
                let t = fitted[&l.ends];
                if same {
                    assert_eq!(t, l.tangents);
                } else {
                    for (a, b) in [(t.0, l.tangents.0), (t.1, l.tangents.1)] {
                        assert!(a.is_finite() && a.angle_between(b) <= MAX_CORRECTION);
                        changed += usize::from(a != b);
                    }
                }
            }
            assert!(same || changed > 0, "no tangent fitted");
        }
    }
}
