//! Face and vertex normals.

use crate::Vec3;
use crate::mesh::{FaceId, HalfedgeId, SurfaceMesh, VertexId};
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
    let area_vectors = face_area_vectors_at(mesh, positions);
    let mut normals = vec![Vec3::ZERO; mesh.vertex_count()];
    normals
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| vertex_normals_into(mesh, &area_vectors, c * CHUNK, out));
    normals
}

/// Elements per parallel task of the whole-mesh passes.
const CHUNK: usize = 4096;

/// Elements whose memory loads are issued together (see [`gather_triangles`]).
pub(crate) const BATCH: usize = 64;

/// Area vectors of all faces (parallel): the weights A_T N_T of Yong et al.
/// Eq. (3).
pub(crate) fn face_area_vectors(mesh: &SurfaceMesh) -> Vec<Vec3> {
    face_area_vectors_at(mesh, mesh.positions())
}

/// [`face_area_vectors`] with the vertices at `p` (one per vertex).
fn face_area_vectors_at(mesh: &SurfaceMesh, p: &[Vec3]) -> Vec<Vec3> {
    if !mesh.is_triangle_mesh() {
        return (0..mesh.face_count() as u32)
            .into_par_iter()
            .map(|f| face_area_vector_at(mesh, p, FaceId(f)))
            .collect();
    }
    let mut out = vec![Vec3::ZERO; mesh.face_count()];
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (b, block) in out.chunks_mut(BATCH).enumerate() {
            let f0 = c * CHUNK + b * BATCH;
            let n = block.len();
            let mut halfedges = [[0u32; 3]; BATCH];
            let mut tri = [[0u32; 3]; BATCH];
            gather_triangles(mesh, f0, &mut halfedges[..n], &mut tri[..n]);
            for (a, t) in block.iter_mut().zip(&tri) {
                // face_area_vector_at's triangle branch: the same operands
                let [a0, b0, c0] = t.map(|v| p[v as usize]);
                *a = 0.5 * (b0 - a0).cross(c0 - a0);
            }
        }
    });
    out
}

/// The halfedges (the stored one first, then in order) and the vertices
/// (as [`SurfaceMesh::triangle`] gives them: the targets of those
/// halfedges) of triangles `f0..f0 + tri.len()`, gathered stage by stage
/// over the batch: the loads of one stage are independent of each other,
/// so the processor overlaps their cache misses (on a scan, neighbouring
/// faces and their halfedges lie far apart in memory, and one face at a
/// time waits for each of its dependent loads in turn). The mesh must be
/// all triangles; at most [`BATCH`] faces.
#[inline]
pub(crate) fn gather_triangles(
    mesh: &SurfaceMesh,
    f0: usize,
    halfedges: &mut [[u32; 3]],
    tri: &mut [[u32; 3]],
) {
    for (i, h) in halfedges.iter_mut().enumerate() {
        h[0] = mesh.face_halfedge(FaceId((f0 + i) as u32)).0;
    }
    for h in halfedges.iter_mut() {
        h[1] = mesh.next(HalfedgeId(h[0])).0;
    }
    for h in halfedges.iter_mut() {
        h[2] = mesh.next(HalfedgeId(h[1])).0;
    }
    for (t, h) in tri.iter_mut().zip(halfedges.iter()) {
        *t = h.map(|h| mesh.to_vertex(HalfedgeId(h)).0);
    }
}

/// Entries `v0..v0 + out.len()` of [`vertex_normals`] from the face area
/// vectors of [`face_area_vectors`], bit-identical to
/// [`vertex_normal_from_area_vectors`]: the circulations of a batch of
/// vertices advance in lockstep, one step of every vertex after the other,
/// so that their dependent loads (halfedge, face, area vector) overlap;
/// each vertex still sums its faces in its own circulation order.
pub(crate) fn vertex_normals_into(
    mesh: &SurfaceMesh,
    area_vectors: &[Vec3],
    v0: usize,
    out: &mut [Vec3],
) {
    for (b, block) in out.chunks_mut(BATCH).enumerate() {
        let first = v0 + b * BATCH;
        let mut start = [0u32; BATCH];
        let mut current = [0u32; BATCH];
        let mut sum = [Vec3::ZERO; BATCH];
        let mut active = [0u8; BATCH];
        let mut m = 0;
        for i in 0..block.len() {
            if let Some(h) = mesh.vertex_halfedge(VertexId((first + i) as u32)) {
                (start[i], current[i]) = (h.0, h.0);
                active[m] = i as u8;
                m += 1;
            }
        }
        while m > 0 {
            let mut kept = 0;
            for j in 0..m {
                let i = active[j] as usize;
                let h = HalfedgeId(current[i]);
                if let Some(f) = mesh.face(h) {
                    sum[i] += area_vectors[f.idx()];
                }
                // kept without a branch: whether the circulation goes on
                // is known only when its load arrives, and a mispredicted
                // branch would wait for it
                let next = mesh.cw_rotated(h).0;
                current[i] = next;
                active[kept] = i as u8;
                kept += usize::from(next != start[i]);
            }
            m = kept;
        }
        for (i, n) in block.iter_mut().enumerate() {
            *n = sum[i].normalize_or_zero();
            if *n == Vec3::ZERO {
                // the rare fallbacks, one vertex at a time
                *n = vertex_normal_from_area_vectors(
                    mesh,
                    VertexId((first + i) as u32),
                    area_vectors,
                );
            }
        }
    }
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
