//! Face and vertex normals.

use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use rayon::prelude::*;

/// Unit normal and area of the triangle (a, b, c), counter-clockwise.
/// A degenerate triangle returns the zero vector and its (tiny) area.
#[inline]
pub fn triangle_normal_area(a: Vec3, b: Vec3, c: Vec3) -> (Vec3, f64) {
    let n = (b - a).cross(c - a);
    let len = n.length();
    let scale = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if len > super::DEGENERATE_RELATIVE_AREA * scale && len.is_finite() {
        (n / len, 0.5 * len)
    } else {
        (Vec3::ZERO, 0.5 * len.min(f64::MAX))
    }
}

/// Area vector of a face: half the Newell vector, i.e. area times unit
/// normal for planar polygons (the cross product for triangles).
#[inline]
pub(crate) fn face_area_vector(mesh: &SurfaceMesh, f: FaceId) -> Vec3 {
    face_area_vector_at(mesh, mesh.positions(), f)
}

/// [`face_area_vector`] with the vertices at `p` (one per vertex).
pub(crate) fn face_area_vector_at(mesh: &SurfaceMesh, p: &[Vec3], f: FaceId) -> Vec3 {
    let h0 = mesh.face_halfedge(f);
    let h1 = mesh.next(h0);
    let h2 = mesh.next(h1);
    if mesh.next(h2) == h0 {
        let [a, b, c] = mesh.triangle(f).map(|v| p[v.idx()]);
        return 0.5 * (b - a).cross(c - a);
    }
    // Newell: sum of cross products of consecutive vertices about the centroid.
    let mut centroid = Vec3::ZERO;
    let mut n = 0.0;
    for v in mesh.face_vertices(f) {
        centroid += p[v.idx()];
        n += 1.0;
    }
    centroid /= n;
    let mut s = Vec3::ZERO;
    for h in mesh.face_halfedges(f) {
        let a = p[mesh.from_vertex(h).idx()] - centroid;
        let b = p[mesh.to_vertex(h).idx()] - centroid;
        s += a.cross(b);
    }
    0.5 * s
}

/// Unit face normals (Newell normal for polygons); zero for degenerate faces.
pub fn face_normals(mesh: &SurfaceMesh) -> Vec<Vec3> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| face_area_vector(mesh, FaceId(f)).normalize_or_zero())
        .collect()
}

/// Area-weighted vertex normals, Yong et al. Eq. (3):
/// N_V = Σ A_T N_T / ‖Σ A_T N_T‖ over the faces T around V.
///
/// When the weighted sum vanishes (a vertex on a fold or only degenerate
/// faces) the unweighted sum of unit face normals is tried; if that vanishes
/// too, the normal is the zero vector. Isolated vertices get zero.
pub fn vertex_normals(mesh: &SurfaceMesh) -> Vec<Vec3> {
    vertex_normals_at(mesh, mesh.positions())
}

/// [`vertex_normals`] with the vertices at `positions` (one per vertex; a
/// geometry view: trial positions are evaluated without a copy of the mesh).
pub fn vertex_normals_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<Vec3> {
    let area_vectors: Vec<Vec3> = (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| face_area_vector_at(mesh, positions, FaceId(f)))
        .collect();
    (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| vertex_normal_from_area_vectors(mesh, VertexId(v), &area_vectors))
        .collect()
}

/// Area vectors of all faces (parallel): the weights A_T N_T of Yong et al.
/// Eq. (3).
pub(crate) fn face_area_vectors(mesh: &SurfaceMesh) -> Vec<Vec3> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| face_area_vector(mesh, FaceId(f)))
        .collect()
}

/// Entry `v` of [`vertex_normals`] from the face area vectors of
/// [`face_area_vectors`], for callers that fuse other per-vertex work into
/// the same pass (bit-identical).
#[inline]
pub(crate) fn vertex_normal_from_area_vectors(
    mesh: &SurfaceMesh,
    v: VertexId,
    area_vectors: &[Vec3],
) -> Vec3 {
    normal_from_area_vectors(mesh, v, |f| area_vectors[f.idx()])
}

/// The area-weighted normal of the single vertex `v`, Yong et al. Eq. (3);
/// bit-identical to entry `v` of [`vertex_normals`]. For incremental updates
/// after a few vertices moved (only the one-ring of a moved vertex changes).
pub fn vertex_normal(mesh: &SurfaceMesh, v: VertexId) -> Vec3 {
    normal_from_area_vectors(mesh, v, |f| face_area_vector(mesh, f))
}

/// Eq. (3) with the fallbacks of [`vertex_normals`], summing the face area
/// vectors given by `area` in circulation order.
#[inline]
fn normal_from_area_vectors(
    mesh: &SurfaceMesh,
    v: VertexId,
    area: impl Fn(FaceId) -> Vec3,
) -> Vec3 {
    let mut s = Vec3::ZERO;
    for f in mesh.vertex_faces(v) {
        s += area(f);
    }
    let n = s.normalize_or_zero();
    if n != Vec3::ZERO {
        return n;
    }
    let mut s = Vec3::ZERO;
    for f in mesh.vertex_faces(v) {
        s += area(f).normalize_or_zero();
    }
    s.normalize_or_zero()
}

/// Vertex normals with the weights of Max (1999), "Weights for computing
/// vertex normals from facet normals": N_V ∝ Σ (e1 × e2) / (|e1|² |e2|²)
/// over the corners at V, with e1, e2 the two edges leaving V in that
/// corner. Exact for vertices on a sphere, hence used by the curvature
/// estimators (as trimesh2 does). Falls back to [`vertex_normals`] where the
/// sum vanishes. Polygon corners are treated like triangle corners.
pub fn vertex_normals_max(mesh: &SurfaceMesh) -> Vec<Vec3> {
    vertex_normals_max_at(mesh, mesh.positions())
}

/// [`vertex_normals_max`] with the vertices at `positions` (one per vertex;
/// a geometry view).
pub fn vertex_normals_max_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<Vec3> {
    let p = positions;
    let fallback = std::sync::OnceLock::new();
    let out: Vec<Vec3> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let v = VertexId(v);
            let x = p[v.idx()];
            let mut s = Vec3::ZERO;
            for h in mesh.outgoing(v) {
                if mesh.is_boundary_halfedge(h) {
                    continue;
                }
                let e1 = p[mesh.to_vertex(h).idx()] - x;
                let e2 = p[mesh.from_vertex(mesh.prev(h)).idx()] - x;
                let d = e1.length_squared() * e2.length_squared();
                if d > 0.0 {
                    s += e1.cross(e2) / d;
                }
            }
            s.normalize_or_zero()
        })
        .collect();
    out.iter()
        .enumerate()
        .map(|(i, n)| {
            if *n != Vec3::ZERO || mesh.is_isolated(VertexId(i as u32)) {
                *n
            } else {
                fallback.get_or_init(|| vertex_normals_at(mesh, p))[i]
            }
        })
        .collect()
}
