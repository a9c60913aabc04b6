//! Scalar measures: edge lengths, angles, triangle quality, Willmore energy,
//! surface area and enclosed volume.

use super::normals::face_area_vector;
use crate::Vec3;
use crate::mesh::{EdgeId, FaceId, HalfedgeId, SurfaceMesh};
use rayon::prelude::*;

/// Length of every edge.
pub fn edge_lengths(mesh: &SurfaceMesh) -> Vec<f64> {
    let p = mesh.positions();
    (0..mesh.edge_count() as u32)
        .into_par_iter()
        .map(|e| {
            let (a, b) = mesh.edge_vertices(EdgeId(e));
            p[a.idx()].distance(p[b.idx()])
        })
        .collect()
}

/// Mean edge length (0 for a mesh without edges).
pub fn mean_edge_length(mesh: &SurfaceMesh) -> f64 {
    let l = edge_lengths(mesh);
    if l.is_empty() {
        0.0
    } else {
        l.iter().sum::<f64>() / l.len() as f64
    }
}

/// Interior angle (radians) at the corner `from_vertex(h)` of the face of
/// `h`, per halfedge; 0 on boundary halfedges and at zero-length edges.
pub fn corner_angles(mesh: &SurfaceMesh) -> Vec<f64> {
    let p = mesh.positions();
    (0..mesh.halfedge_count() as u32)
        .into_par_iter()
        .map(|h| {
            let h = HalfedgeId(h);
            if mesh.is_boundary_halfedge(h) {
                return 0.0;
            }
            let v = p[mesh.from_vertex(h).idx()];
            let a = p[mesh.to_vertex(h).idx()] - v;
            let b = p[mesh.from_vertex(mesh.prev(h)).idx()] - v;
            angle_between(a, b)
        })
        .collect()
}

/// Angle between two vectors in [0, π], robust (atan2 form); 0 when either
/// vector is zero.
#[inline]
pub(crate) fn angle_between(a: Vec3, b: Vec3) -> f64 {
    let c = a.cross(b).length();
    let d = a.dot(b);
    if c == 0.0 && d == 0.0 {
        0.0
    } else {
        c.atan2(d)
    }
}

/// Barycentric coordinates (summing to 1, all ≥ 0) of the point of triangle
/// (a, b, c) closest to `p` (Ericson, Real-Time Collision Detection,
/// §5.1.5, Voronoi regions of the vertices and edges). A degenerate
/// triangle gives the closest of its vertices or edge points; never NaN for
/// finite input.
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
        let t = d1 / (d1 - d3);
        return [1.0 - t, t, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
        let t = d2 / (d2 - d6);
        return [1.0 - t, 0.0, t];
    }
    let va = d3 * d6 - d5 * d4;
    let (e, f) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e >= 0.0 && f >= 0.0 && e + f > 0.0 {
        let t = e / (e + f);
        return [0.0, 1.0 - t, t];
    }
    let denom = va + vb + vc;
    if !(denom.abs() > 0.0) || !denom.is_finite() {
        // degenerate: the best of the three vertices
        let d = [p.distance(a), p.distance(b), p.distance(c)];
        let k = (0..3).min_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap_or(0);
        let mut w = [0.0; 3];
        w[k] = 1.0;
        return w;
    }
    let (v, w) = (vb / denom, vc / denom);
    [1.0 - v - w, v, w]
}

/// Triangle quality 2r/R (inradius over circumradius, times 2): 1 for an
/// equilateral triangle, 0 for a degenerate one. Computed as
/// 16 A² / (a b c (a + b + c)).
#[inline]
pub fn triangle_quality(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let (la, lb, lc) = (b.distance(c), c.distance(a), a.distance(b));
    let area = 0.5 * (b - a).cross(c - a).length();
    let denom = la * lb * lc * (la + lb + lc);
    if !(denom > 0.0) || !denom.is_finite() {
        return 0.0;
    }
    (16.0 * area * area / denom).clamp(0.0, 1.0)
}

/// Quality 2r/R of every face (a triangle mesh is expected; polygons are
/// rated by their first three vertices).
pub fn triangle_qualities(mesh: &SurfaceMesh) -> Vec<f64> {
    let p = mesh.positions();
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| p[v.idx()]);
            triangle_quality(a, b, c)
        })
        .collect()
}

/// Total surface area.
pub fn surface_area(mesh: &SurfaceMesh) -> f64 {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| face_area_vector(mesh, FaceId(f)).length())
        .sum()
}

/// Signed volume enclosed by a closed mesh, by the divergence theorem:
/// V = ⅙ Σ p0 · (p1 × p2) over the triangles of a fan of each face, taken
/// about the centroid of the vertices for numerical accuracy. Positive for
/// outward orientation. For an open mesh this is the volume of the cone
/// from the centroid and has no intrinsic meaning.
pub fn volume(mesh: &SurfaceMesh) -> f64 {
    volume_at(mesh, mesh.positions())
}

/// [`volume`] of the mesh's faces with the vertices at `positions` (one per
/// vertex; a geometry view, so a trial shape needs no copy of the mesh).
/// 0 when the count does not match the mesh.
pub fn volume_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> f64 {
    let p = positions;
    if p.is_empty() || p.len() != mesh.vertex_count() {
        return 0.0;
    }
    let c = p.iter().copied().sum::<Vec3>() / p.len() as f64;
    let parts: Vec<f64> = (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            // the fan of triangles (v0, v_i, v_i+1), without a list per face
            let mut verts = mesh.face_vertices(FaceId(f)).map(|v| p[v.idx()] - c);
            let (Some(first), Some(mut prev)) = (verts.next(), verts.next()) else {
                return 0.0;
            };
            let mut s = 0.0;
            for v in verts {
                s += first.dot(prev.cross(v));
                prev = v;
            }
            s
        })
        .collect();
    // sequential sum of a fixed order keeps the result deterministic
    parts.iter().sum::<f64>() / 6.0
}

/// Discrete Willmore energy W = Σ_i H_i² A_i with H the mean curvature of
/// [`super::mean_curvature`] and A the mixed vertex areas (the discretisation
/// of ∫ H² dA used by Yong et al. Eq. (6)). Boundary vertices are excluded.
pub fn willmore_energy(mesh: &SurfaceMesh) -> f64 {
    let areas = super::mixed_vertex_areas(mesh);
    let h = super::mean_curvature(mesh);
    let parts: Vec<f64> = mesh
        .vertices()
        .map(|v| {
            if mesh.is_boundary_vertex(v) {
                0.0
            } else {
                h[v.idx()] * h[v.idx()] * areas[v.idx()]
            }
        })
        .collect();
    parts.iter().sum()
}

#[cfg(test)]
mod closest_point_tests {
    use super::*;

    #[test]
    fn closest_point_on_triangle_in_every_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let at = |w: [f64; 3]| w[0] * a + w[1] * b + w[2] * c;
        let cases = [
            (Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.25, 0.25, 0.0)),
            (Vec3::new(-1.0, -1.0, 0.5), a),
            (Vec3::new(3.0, -0.5, 0.0), b),
            (Vec3::new(-0.2, 4.0, 1.0), c),
            (Vec3::new(0.5, -2.0, 0.0), Vec3::new(0.5, 0.0, 0.0)),
            (Vec3::new(-3.0, 0.5, 0.0), Vec3::new(0.0, 0.5, 0.0)),
            (Vec3::new(1.0, 1.0, -1.0), Vec3::new(0.5, 0.5, 0.0)),
        ];
        for (p, q) in cases {
            let w = closest_point_on_triangle(p, a, b, c);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            assert!(w.iter().all(|x| *x >= 0.0));
            assert!(at(w).distance(q) < 1e-15, "{p}: {} vs {q}", at(w));
        }
        // degenerate triangles give a finite answer on the triangle
        for (a, b, c) in [(a, a, a), (a, b, 2.0 * b), (b, b, c)] {
            let w = closest_point_on_triangle(Vec3::new(0.3, 0.7, 0.2), a, b, c);
            assert!(w.iter().all(|x| x.is_finite()));
        }
    }
}
