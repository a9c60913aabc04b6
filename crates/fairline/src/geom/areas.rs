//! Face areas and vertex areas (barycentric and mixed Voronoi).

use super::normals::face_area_vector_at;
use crate::Vec3;
use crate::mesh::{FaceId, HalfedgeId, SurfaceMesh, VertexId};
use rayon::prelude::*;

/// Face areas (the magnitude of the Newell area vector for polygons).
pub fn face_areas(mesh: &SurfaceMesh) -> Vec<f64> {
    face_areas_at(mesh, mesh.positions())
}

/// [`face_areas`] with the vertices at `positions` (one per vertex; a
/// geometry view).
pub fn face_areas_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<f64> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| face_area_vector_at(mesh, positions, FaceId(f)).length())
        .collect()
}

/// Barycentric vertex areas, Yong et al. Eq. (7): A_i = ⅓ Σ A_T over the
/// triangles around vertex i (a polygon with n corners gives 1/n of its area
/// to each). They sum to the surface area.
pub fn barycentric_vertex_areas(mesh: &SurfaceMesh) -> Vec<f64> {
    barycentric_vertex_areas_at(mesh, mesh.positions())
}

/// [`barycentric_vertex_areas`] with the vertices at `positions` (one per
/// vertex; a geometry view).
pub fn barycentric_vertex_areas_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<f64> {
    let fa = face_areas_at(mesh, positions);
    let sizes: Vec<f64> = (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| mesh.face_size(FaceId(f)) as f64)
        .collect();
    (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            mesh.vertex_faces(VertexId(v))
                .map(|f| fa[f.idx()] / sizes[f.idx()])
                .sum()
        })
        .collect()
}

/// Mixed Voronoi area of the corner at `from_vertex(h)` in the face of `h`,
/// after Meyer, Desbrun, Schröder and Barr (2003), Fig. 4: the Voronoi area
/// ⅛(|PR|² cot Q + |PQ|² cot R) for non-obtuse triangles, half the triangle
/// area at an obtuse corner, a quarter at the other corners of an obtuse
/// triangle. Polygons that are not triangles give 1/n of their area per
/// corner; boundary halfedges and degenerate triangles give 0.
#[inline]
fn mixed_corner_area(mesh: &SurfaceMesh, p: &[Vec3], h: HalfedgeId) -> f64 {
    let Some(f) = mesh.face(h) else { return 0.0 };
    let h1 = mesh.next(h);
    let h2 = mesh.next(h1);
    if mesh.next(h2) != h {
        let n = mesh.face_size(f) as f64;
        return face_area_vector_at(mesh, p, f).length() / n;
    }
    let pp = p[mesh.from_vertex(h).idx()];
    let q = p[mesh.to_vertex(h).idx()];
    let r = p[mesh.to_vertex(h1).idx()];
    corner_area(pp, q, r)
}

/// Mixed area of corner P of triangle (P, Q, R); see [`mixed_corner_areas`].
#[inline]
pub(crate) fn corner_area(p: Vec3, q: Vec3, r: Vec3) -> f64 {
    let (pq, pr, qr) = (q - p, r - p, r - q);
    let cross = pq.cross(pr).length();
    let scale = pq.length_squared() + pr.length_squared() + qr.length_squared();
    if !(cross > super::DEGENERATE_RELATIVE_AREA * scale) {
        return 0.0;
    }
    let area = 0.5 * cross;
    let dp = pq.dot(pr);
    let dq = (-pq).dot(qr);
    let dr = (-pr).dot(-qr);
    if dp < 0.0 {
        0.5 * area
    } else if dq < 0.0 || dr < 0.0 {
        0.25 * area
    } else {
        // cot Q = dq / cross, cot R = dr / cross
        0.125 * (pr.length_squared() * dq + pq.length_squared() * dr) / cross
    }
}

/// Mixed corner areas of every face: entry `f` holds the areas of the
/// corners at `triangle(f)[0..3]` (for polygons, 1/n of the area at each of
/// the first three corners — use [`mixed_corner_areas`] for polygons).
pub(crate) fn triangle_corner_areas(mesh: &SurfaceMesh) -> Vec<[f64; 3]> {
    triangle_corner_areas_at(mesh, mesh.positions())
}

/// [`triangle_corner_areas`] with the vertices at `p`.
fn triangle_corner_areas_at(mesh: &SurfaceMesh, p: &[Vec3]) -> Vec<[f64; 3]> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| p[v.idx()]);
            [
                corner_area(a, b, c),
                corner_area(b, c, a),
                corner_area(c, a, b),
            ]
        })
        .collect()
}

/// Mixed corner areas per halfedge: entry `h` is the share of the face of
/// `h` that belongs to the vertex `from_vertex(h)` (0 on boundary halfedges).
/// The corner areas of a face sum to its area.
pub fn mixed_corner_areas(mesh: &SurfaceMesh) -> Vec<f64> {
    (0..mesh.halfedge_count() as u32)
        .into_par_iter()
        .map(|h| mixed_corner_area(mesh, mesh.positions(), HalfedgeId(h)))
        .collect()
}

/// Mixed Voronoi vertex areas of Meyer et al. (2003): the sum of the mixed
/// corner areas around each vertex. They sum to the surface area and are
/// never negative. Triangle corners are computed per face in parallel and
/// summed per vertex in face order (deterministic).
pub fn mixed_vertex_areas(mesh: &SurfaceMesh) -> Vec<f64> {
    mixed_vertex_areas_at(mesh, mesh.positions())
}

/// [`mixed_vertex_areas`] with the vertices at `positions` (one per vertex;
/// a geometry view over the mesh's connectivity, so a trial shape needs no
/// copy of the mesh).
pub fn mixed_vertex_areas_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<f64> {
    if !mesh.is_triangle_mesh() {
        return (0..mesh.vertex_count() as u32)
            .into_par_iter()
            .map(|v| {
                mesh.outgoing(VertexId(v))
                    .map(|h| mixed_corner_area(mesh, positions, h))
                    .sum()
            })
            .collect();
    }
    let corners = triangle_corner_areas_at(mesh, positions);
    let mut out = vec![0.0; mesh.vertex_count()];
    for (f, ca) in corners.iter().enumerate() {
        let t = mesh.triangle(FaceId(f as u32));
        for k in 0..3 {
            out[t[k].idx()] += ca[k];
        }
    }
    out
}
