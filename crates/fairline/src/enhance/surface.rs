//! The input surface as the place the vertices flow on.
//!
//! Ji et al. keep the vertices near the input only through the quadratic
//! Pottmann–Hofer model of the squared distance at each vertex's *input*
//! position (Eq. (6)): a vertex that slides tangentially moves along the
//! tangent plane at its old place and leaves a curved surface by about
//! k t²/2 after a slide t; the curvature-weighted Laplacian F_smo
//! (Eq. (8)–(10)) also pulls curved parts inward. Measured on meshes of
//! known surfaces, the distance to the true surface then *rose* 10–35 %
//! although the vertices gathered on the features. So after each solve
//! every free vertex is put back onto the surface the input mesh stands for
//! ([`Projection`]):
//!
//! 1. the point where the line through it along its input vertex normal
//!    meets the input triangle mesh (the nearest such point, searched ring by
//!    ring around the vertex's own input position, [`search_rings`], so that
//!    a vertex never jumps to another sheet across a thin part; where the
//!    line meets no face nearby, the nearest point of the mesh). Unlike the
//!    nearest point, which jumps between the two sides of a ridge for a
//!    vertex just inside it, this point moves continuously with the vertex
//!    (the direct and the iterative solvers, equal to 10⁻¹², give equal
//!    results); then
//! 2. for [`Projection::Smooth`], lifted onto the Phong tessellation of that
//!    input triangle (Boubekeur & Alexa 2008, "Phong Tessellation", Eq. (2)
//!    –(3)): with the point p = Σ wᵢ vᵢ of the triangle and the projections
//!    πᵢ(p) = p − ((p − vᵢ)·nᵢ) nᵢ onto the tangent planes of its corners,
//!    p* = (1 − α) p + α Σ wᵢ πᵢ(p). With α = ½ the patch reproduces a
//!    quadratic height field to second order (for z = xᵀAx the lift is
//!    2α (Q(x) − Σ wᵢ Q(xᵢ))), so a vertex that moved into the middle of a
//!    chord of a curved part lands on the curved surface, not on the chord:
//!    the error of the chord (the sag ℓ²k/8) becomes O(ℓ⁴).
//!
//! Corner normals nᵢ are area-weighted means of the normals of the faces
//! around vᵢ that turn by less than [`CREASE_ANGLE_DEG`] from the face
//! itself (a face on one side of a sharp crease does not take the normals
//! of the other side), so flat faces stay exactly flat (every corner normal
//! of a face whose neighbours are coplanar is its own normal, and the lift
//! vanishes), and the corners of a crease keep the planes of their sides.
//! Where a flat or gently curved part meets a fillet tangentially, the mean
//! tilts toward the fillet; there the vertex takes the normal of a
//! two-sided quadric fit of its 2-ring instead (module `junction`).

use super::crease::{
    CreaseCorner, SidePlanes, chord_faces, crease_corners, crease_point, snap_to_corners,
};
use crate::Vec3;
use crate::geom::{closest_point_on_triangle, triangle_normal_area};
use crate::mesh::{FaceId, SurfaceMesh, VertexId, union_find_join, union_find_root};
use rayon::prelude::*;
use serde::Serialize;

/// Where the vertices are put after each solve of the vertex flow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Nowhere: the solution of Eq. (20) as published (Ji et al. 2011); the
    /// vertices leave curved surfaces while they slide.
    None,
    /// Onto the closest point of the input triangle mesh (near the vertex's
    /// input position): on the surface the input shows, chords included.
    Mesh,
    /// Onto the Phong tessellation (α = ½) of the input triangle met along
    /// the vertex's input normal, with crease-aware corner normals: between
    /// the input's vertices the point lands on a smooth fit of the surface
    /// instead of on the chord (module documentation); on the chord faces
    /// of an under-sampled sharp crease, onto the crease rebuilt from the
    /// planes of its sides (module `crease`).
    #[default]
    Smooth,
}

/// Faces around a vertex whose normals turn by more than this angle (in
/// degrees) from a face's normal do not contribute to that face's corner
/// normal there: a sharp crease (a cube's edges turn by 90°) keeps its two
/// planes, while the chords of a rounded edge sampled by two or more
/// triangles across (each turning by at most 45°) are smoothed over.
pub const CREASE_ANGLE_DEG: f64 = 50.0;

/// Shape factor α of the Phong tessellation: ½ reproduces quadratic
/// surfaces to second order (module documentation).
pub const PHONG_ALPHA: f64 = 0.5;

/// Rings of input faces searched at most around a vertex's input position.
pub const SEARCH_RINGS: usize = 16;

/// A point of the input mesh found by [`search_rings`]: its face, the
/// barycentric coordinates in that face and its score (the squared distance
/// for [`nearest_input_faces`], the distance along the line for the
/// projection).
#[derive(Clone, Copy, Debug)]
pub(super) struct Nearest {
    pub face: FaceId,
    pub weights: [f64; 3],
    pub distance_squared: f64,
}

/// For each query, the input face with the smallest score near the query's
/// vertex: the faces are searched ring by ring around the vertex (its
/// incident faces, then those of its one-ring, ...) until a ring brings no
/// better face (at most [`SEARCH_RINGS`] rings). `score(query, face)` gives
/// the face's score and the barycentric coordinates of its point, or `None`
/// where the face does not qualify. Parallel and deterministic; ties keep
/// the face found first.
fn search_rings<S>(mesh: &SurfaceMesh, starts: &[u32], score: S) -> Vec<Option<Nearest>>
where
    S: Fn(usize, FaceId) -> Option<(f64, [f64; 3])> + Sync,
{
    // a few chunks per thread; each marks the faces and vertices it has
    // seen with the index of the query being searched (no clearing)
    let chunk = starts
        .len()
        .div_ceil(4 * rayon::current_num_threads())
        .max(256);
    starts
        .par_chunks(chunk)
        .enumerate()
        .flat_map_iter(|(c, starts)| {
            let mut face_mark = vec![u32::MAX; mesh.face_count()];
            let mut vertex_mark = vec![u32::MAX; mesh.vertex_count()];
            let (mut frontier, mut next) = (Vec::new(), Vec::new());
            let mut out = Vec::with_capacity(starts.len());
            for (k, &v) in starts.iter().enumerate() {
                let query = c * chunk + k;
                let k = k as u32;
                let mut best: Option<Nearest> = None;
                let value = |b: &Option<Nearest>| b.map_or(f64::INFINITY, |b| b.distance_squared);
                vertex_mark[v as usize] = k;
                frontier.clear();
                frontier.push(VertexId(v));
                for _ in 0..SEARCH_RINGS {
                    let mut ring_best: Option<Nearest> = None;
                    next.clear();
                    for &w in &frontier {
                        for f in mesh.vertex_faces(w) {
                            if std::mem::replace(&mut face_mark[f.idx()], k) == k {
                                continue;
                            }
                            if let Some((d, weights)) = score(query, f)
                                && d < value(&ring_best)
                            {
                                ring_best = Some(Nearest {
                                    face: f,
                                    weights,
                                    distance_squared: d,
                                });
                            }
                        }
                        for u in mesh.one_ring(w) {
                            if std::mem::replace(&mut vertex_mark[u.idx()], k) != k {
                                next.push(u);
                            }
                        }
                    }
                    if value(&ring_best) < value(&best) {
                        best = ring_best;
                    } else if best.is_some() {
                        break;
                    }
                    if next.is_empty() {
                        break;
                    }
                    std::mem::swap(&mut frontier, &mut next);
                }
                out.push(best);
            }
            out
        })
        .collect()
}

/// For each `(vertex, point)` pair, the nearest point of the triangle mesh
/// `mesh` at `positions` to `point`, searched ring by ring around `vertex`
/// ([`search_rings`]); `None` for a vertex without faces. An upper bound of
/// the distance to the whole mesh, which another part of the surface
/// (across a thin part) may come nearer to.
pub(super) fn nearest_input_faces(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    queries: &[(u32, Vec3)],
) -> Vec<Option<Nearest>> {
    let starts: Vec<u32> = queries.iter().map(|q| q.0).collect();
    search_rings(mesh, &starts, |q, f| {
        let x = queries[q].1;
        let t = mesh.triangle(f).map(|u| positions[u.idx()]);
        let b = closest_point_on_triangle(x, t[0], t[1], t[2]);
        Some((
            x.distance_squared(b[0] * t[0] + b[1] * t[1] + b[2] * t[2]),
            b,
        ))
    })
}

/// Where the line x + t d meets the triangle (a, b, c) (Möller & Trumbore
/// 1997), edges included to a relative tolerance so that a line through an
/// edge meets both faces: |t| and the barycentric coordinates; `None` for a
/// line parallel to the triangle or passing beside it.
fn line_triangle(x: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<(f64, [f64; 3])> {
    const EDGE_TOLERANCE: f64 = 1e-9;
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if !(det.abs() > 1e-12 * e1.length() * e2.length()) {
        return None;
    }
    let inv = 1.0 / det;
    let s = x - a;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let t = e2.dot(q) * inv;
    let inside = u >= -EDGE_TOLERANCE && v >= -EDGE_TOLERANCE && u + v <= 1.0 + EDGE_TOLERANCE;
    if !(inside && t.is_finite()) {
        return None;
    }
    let w = [(1.0 - u - v).max(0.0), u.max(0.0), v.max(0.0)];
    let sum = w[0] + w[1] + w[2];
    Some((t.abs(), w.map(|w| w / sum)))
}

/// Unit normal at each corner of each triangle: the area-weighted mean of
/// the normals of the faces in the corner's smoothing group — the faces
/// around the vertex reached from the corner's face across edges whose
/// dihedral angle is below [`CREASE_ANGLE_DEG`] (found by joining the two
/// corners at each end of every such edge, union–find). All faces of a
/// group share one normal at the vertex, so the Phong patches of two faces
/// meet along their common edge unless it is a crease (a point whose
/// nearest input point lies on an edge gets the same lift from either
/// face); without creases the corner normal is the area-weighted vertex
/// normal. Faces marked in `separate` (the chord faces of under-sampled
/// creases, module `crease`) are not joined to faces that are not, so the
/// sides of a crease keep their own normals up to it. Degenerate faces get
/// zero normals (no lift).
fn corner_normals(
    mesh: &SurfaceMesh,
    face_normals: &[(Vec3, f64)],
    separate: &[bool],
) -> Vec<[Vec3; 3]> {
    let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
    let nf = mesh.face_count();
    let triangles: Vec<[VertexId; 3]> = (0..nf as u32).map(|f| mesh.triangle(FaceId(f))).collect();
    let corner = |f: FaceId, v: VertexId| -> Option<u32> {
        let k = triangles[f.idx()].iter().position(|&u| u == v)?;
        Some(3 * f.0 + k as u32)
    };
    let mut parent: Vec<u32> = (0..3 * nf as u32).collect();
    for h in mesh.halfedges() {
        let o = mesh.opposite(h);
        // each interior edge once
        if h.0 > o.0 {
            continue;
        }
        let (Some(f1), Some(f2)) = (mesh.face(h), mesh.face(o)) else {
            continue;
        };
        let (n1, n2) = (face_normals[f1.idx()].0, face_normals[f2.idx()].0);
        if n1 == Vec3::ZERO
            || n2 == Vec3::ZERO
            || n1.dot(n2) < cos_crease
            || separate[f1.idx()] != separate[f2.idx()]
        {
            continue;
        }
        for v in [mesh.from_vertex(h), mesh.to_vertex(h)] {
            if let (Some(a), Some(b)) = (corner(f1, v), corner(f2, v)) {
                union_find_join(&mut parent, a, b);
            }
        }
    }
    let roots: Vec<u32> = (0..3 * nf as u32)
        .map(|c| union_find_root(&mut parent, c))
        .collect();
    let mut sums = vec![Vec3::ZERO; 3 * nf];
    for (c, &r) in roots.iter().enumerate() {
        let (n, area) = face_normals[c / 3];
        sums[r as usize] += area * n;
    }
    (0..nf)
        .map(|f| {
            let own = face_normals[f].0;
            std::array::from_fn(|k| {
                if own == Vec3::ZERO {
                    return Vec3::ZERO;
                }
                let n = sums[roots[3 * f + k] as usize].normalize_or_zero();
                if n == Vec3::ZERO { own } else { n }
            })
        })
        .collect()
}

/// The input surface of the vertex flow: the input mesh at its (normalised)
/// positions with the crease-aware corner normals of its faces.
pub(super) struct InputSurface<'a> {
    mesh: &'a SurfaceMesh,
    positions: &'a [Vec3],
    /// Unit normal at each corner of each face (zero for degenerate faces).
    corner_normals: Vec<[Vec3; 3]>,
    /// Area-weighted unit normal of each vertex (zero where undefined).
    vertex_normals: Vec<Vec3>,
    /// The side planes of the chord faces of under-sampled sharp creases
    /// (module `crease`); `None` for every other face.
    chords: Vec<Option<SidePlanes>>,
    /// The points where three sides of under-sampled creases meet (module
    /// `crease`, step 6).
    corners: Vec<CreaseCorner>,
}

impl<'a> InputSurface<'a> {
    /// The surface of the triangle mesh `mesh` at `positions`.
    pub fn new(mesh: &'a SurfaceMesh, positions: &'a [Vec3]) -> InputSurface<'a> {
        let face_normals: Vec<(Vec3, f64)> = (0..mesh.face_count() as u32)
            .into_par_iter()
            .map(|f| {
                let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| positions[v.idx()]);
                triangle_normal_area(a, b, c)
            })
            .collect();
        let chords = chord_faces(mesh, &face_normals);
        let corners = crease_corners(mesh, positions, &chords);
        let separate: Vec<bool> = chords.iter().map(Option::is_some).collect();
        let mut corner_normals = corner_normals(mesh, &face_normals, &separate);
        let unit: Vec<Vec3> = face_normals.iter().map(|n| n.0).collect();
        super::junction::refine_corner_normals(
            mesh,
            positions,
            &unit,
            &mut corner_normals,
            &separate,
        );
        let vertex_normals = (0..mesh.vertex_count() as u32)
            .into_par_iter()
            .map(|v| {
                mesh.vertex_faces(VertexId(v))
                    .map(|f| face_normals[f.idx()].1 * face_normals[f.idx()].0)
                    .sum::<Vec3>()
                    .normalize_or_zero()
            })
            .collect();
        InputSurface {
            mesh,
            positions,
            corner_normals,
            vertex_normals,
            chords,
            corners,
        }
    }

    /// The point of face `face` at barycentric coordinates `w` on the flat
    /// triangle ([`Projection::Mesh`]), or for [`Projection::Smooth`] on the
    /// crease rebuilt from its sides where the face is a chord of an
    /// under-sampled sharp crease (module `crease`), else on its Phong patch
    /// (module documentation).
    pub fn point(&self, face: FaceId, w: [f64; 3], projection: Projection) -> Vec3 {
        let t = self.mesh.triangle(face).map(|u| self.positions[u.idx()]);
        let p = w[0] * t[0] + w[1] * t[1] + w[2] * t[2];
        if projection != Projection::Smooth {
            return p;
        }
        if let Some(q) = self.chords[face.idx()]
            .as_ref()
            .and_then(|planes| crease_point(t, planes, w))
        {
            return q;
        }
        let n = self.corner_normals[face.idx()];
        let mut lift = Vec3::ZERO;
        for k in 0..3 {
            lift -= w[k] * (p - t[k]).dot(n[k]) * n[k];
        }
        let q = p + PHONG_ALPHA * lift;
        if q.is_finite() { q } else { p }
    }

    /// Moves each free vertex `v` of `positions` onto the input surface near
    /// its input position (module documentation); `None` leaves them.
    pub fn project(&self, free: &[u32], positions: &mut [Vec3], projection: Projection) {
        if projection == Projection::None {
            return;
        }
        // along the vertex's input normal: the point moves continuously with
        // the vertex (the nearest point jumps between the two sides of a
        // ridge for a vertex just inside it)
        let hits = search_rings(self.mesh, free, |q, f| {
            let v = free[q] as usize;
            let d = self.vertex_normals[v];
            if d == Vec3::ZERO {
                return None;
            }
            let t = self.mesh.triangle(f).map(|u| self.positions[u.idx()]);
            line_triangle(positions[v], d, t[0], t[1], t[2])
        });
        // where the line meets no face near the vertex (a boundary, a fold):
        // the nearest point
        let missed: Vec<(u32, Vec3)> = free
            .iter()
            .zip(&hits)
            .filter(|(_, h)| h.is_none())
            .map(|(&v, _)| (v, positions[v as usize]))
            .collect();
        let mut nearest = nearest_input_faces(self.mesh, self.positions, &missed).into_iter();
        let found: Vec<Option<Nearest>> = hits
            .into_iter()
            .map(|h| h.or_else(|| nearest.next().flatten()))
            .collect();
        let moved: Vec<Option<Vec3>> = found
            .par_iter()
            .map(|n| n.map(|n| self.point(n.face, n.weights, projection)))
            .collect();
        for (&v, q) in free.iter().zip(moved) {
            if let Some(q) = q {
                positions[v as usize] = q;
            }
        }
        if projection == Projection::Smooth && !self.corners.is_empty() {
            let mut is_free = vec![false; positions.len()];
            for &v in free {
                is_free[v as usize] = true;
            }
            snap_to_corners(self.mesh, &self.corners, &is_free, positions);
        }
    }
}
