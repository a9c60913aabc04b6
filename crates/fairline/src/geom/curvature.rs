//! Curvature: mean-curvature normals, Gaussian curvature, principal
//! curvatures and directions (Rusinkiewicz 2004; Meyer et al. 2003).
//!
//! Sign convention: with outward normals a sphere of radius r has
//! k1 = k2 = H = +1/r. Principal curvatures are ordered signed, k1 ≥ k2.

use super::areas::{mixed_corner_areas, triangle_corner_areas};
use super::laplace::{LaplaceWeights, halfedge_weights};
use super::measures::angle_between;
use super::normals::{vertex_normals, vertex_normals_max};
use crate::mesh::{FaceId, MeshError, Stats, SurfaceMesh, VertexId};
use crate::{Control, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use thiserror::Error;

/// Which estimator of principal curvatures to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CurvatureMethod {
    /// Per-face shape-operator fit averaged into vertex frames
    /// (Rusinkiewicz 2004). Robust, gives directions directly.
    #[default]
    Rusinkiewicz,
    /// From the mean-curvature normal and the angle defect (Meyer et al. 2003).
    Meyer,
}

/// Per-vertex principal curvatures, directions and the normals used.
#[derive(Clone, Debug, Default)]
pub struct PrincipalCurvatures {
    /// Larger principal curvature (signed).
    pub k1: Vec<f64>,
    /// Smaller principal curvature (signed), k2 ≤ k1.
    pub k2: Vec<f64>,
    /// Unit direction of k1, tangent to the surface.
    pub d1: Vec<Vec3>,
    /// Unit direction of k2 (n × d1).
    pub d2: Vec<Vec3>,
    /// Unit vertex normals the estimate was made with (Max 1999 weights for
    /// Rusinkiewicz, area weights of Yong et al. Eq. (3) for Meyer).
    pub normals: Vec<Vec3>,
}

impl PrincipalCurvatures {
    /// Mean curvature H = (k1 + k2) / 2 per vertex.
    pub fn mean(&self) -> Vec<f64> {
        self.k1
            .iter()
            .zip(&self.k2)
            .map(|(a, b)| 0.5 * (a + b))
            .collect()
    }
    /// Gaussian curvature K = k1 k2 per vertex.
    pub fn gauss(&self) -> Vec<f64> {
        self.k1.iter().zip(&self.k2).map(|(a, b)| a * b).collect()
    }
}

/// Options of [`curvature`].
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct CurvatureOptions {
    /// The estimator (default Rusinkiewicz 2004).
    pub method: CurvatureMethod,
    /// Progress callback and cancel flag (stage `"curvature"`: one step
    /// before and one after the estimate; the estimate itself is one
    /// parallel pass).
    pub control: Control,
}

impl CurvatureOptions {
    /// Sets [`CurvatureOptions::method`].
    pub fn method(mut self, method: CurvatureMethod) -> Self {
        self.method = method;
        self
    }
    /// Sets [`CurvatureOptions::control`].
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }
}

/// Why [`curvature`] could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CurvatureError {
    /// The polygons of the mesh could not be triangulated.
    #[error("triangulating its polygons: {0}")]
    Mesh(#[from] MeshError),
    /// The caller's [`Control`] asked to stop.
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
}

/// What [`curvature`] did: the JSON of `fairline curvature --report`
/// (besides `"command"` and `"time_s"`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CurvatureReport {
    /// The estimator used.
    pub method: CurvatureMethod,
    /// Vertices of the input as read (a non-manifold vertex split into
    /// fans counts once, [`SurfaceMesh::original_vertex_count`]).
    pub vertices: usize,
    /// Whether polygons were triangulated first.
    pub triangulated: bool,
    /// Range of k1 over the vertices (finite values).
    pub k1: Stats,
    /// Range of k2.
    pub k2: Stats,
    /// Range of the mean curvature H = (k1 + k2)/2.
    pub mean: Stats,
    /// Range of the Gaussian curvature K = k1·k2.
    pub gauss: Stats,
}

/// What [`curvature`] returns. Curvature is a measurement, not a change of
/// the shape: instead of new positions (the [`crate::Output`] of the other
/// algorithms) it carries per-vertex fields, one value per vertex of the
/// mesh in vertex order, and the report.
#[derive(Clone, Debug)]
pub struct CurvatureOutput {
    /// Principal curvatures, directions and the normals used.
    pub fields: PrincipalCurvatures,
    /// Mean curvature H = (k1 + k2)/2 per vertex.
    pub mean: Vec<f64>,
    /// Gaussian curvature K = k1·k2 per vertex.
    pub gauss: Vec<f64>,
    /// What was computed.
    pub report: CurvatureReport,
}

/// Per-vertex curvature of a mesh, the algorithm of `fairline curvature`:
/// principal curvatures and directions by the chosen estimator
/// ([`principal_curvatures`]: Rusinkiewicz 2004 or Meyer et al. 2003),
/// mean and Gaussian curvature, and their ranges. Polygon meshes are
/// triangulated first (vertices unchanged, so the fields are per input
/// vertex). Errors only when the polygons cannot be triangulated or the
/// control asks to stop ([`CurvatureError::Cancelled`]).
pub fn curvature(
    mesh: &SurfaceMesh,
    options: &CurvatureOptions,
) -> Result<CurvatureOutput, CurvatureError> {
    options.control.step("curvature", 0, 1)?;
    let triangulated = !mesh.is_triangle_mesh();
    let fields = if triangulated {
        let t = crate::mesh::triangulate(mesh)?;
        principal_curvatures(&t.mesh, options.method)
    } else {
        principal_curvatures(mesh, options.method)
    };
    options.control.step("curvature", 1, 1)?;
    let mean = fields.mean();
    let gauss = fields.gauss();
    let report = CurvatureReport {
        method: options.method,
        vertices: mesh.original_vertex_count(),
        triangulated,
        k1: Stats::of(fields.k1.iter().copied()),
        k2: Stats::of(fields.k2.iter().copied()),
        mean: Stats::of(mean.iter().copied()),
        gauss: Stats::of(gauss.iter().copied()),
    };
    Ok(CurvatureOutput {
        fields,
        mean,
        gauss,
        report,
    })
}

/// Principal curvatures by the chosen method.
pub fn principal_curvatures(mesh: &SurfaceMesh, method: CurvatureMethod) -> PrincipalCurvatures {
    match method {
        CurvatureMethod::Rusinkiewicz => principal_curvatures_rusinkiewicz(mesh),
        CurvatureMethod::Meyer => principal_curvatures_meyer(mesh),
    }
}

/// Mean-curvature normals K_i = (1 / (2 A_i)) Σ_j (cot α_ij + cot β_ij)(x_i − x_j)
/// = 2 H_i n_i (Meyer et al. 2003 Eq. (8), with A_i the mixed area). Yong et
/// al. Eq. (8) writes the same operator with the barycentric area and without
/// the ½, i.e. a multiple of this one. Boundary vertices and vertices of zero
/// area get the zero vector. Triangle meshes.
pub fn mean_curvature_normals(mesh: &SurfaceMesh) -> Vec<Vec3> {
    let w = halfedge_weights(mesh, LaplaceWeights::Cotangent);
    let corner = mixed_corner_areas(mesh);
    let p = mesh.positions();
    (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let v = VertexId(v);
            if mesh.is_boundary_vertex(v) {
                return Vec3::ZERO;
            }
            let xi = p[v.idx()];
            let mut s = Vec3::ZERO;
            let mut area = 0.0;
            for h in mesh.outgoing(v) {
                s += w[h.idx()] * (xi - p[mesh.to_vertex(h).idx()]);
                area += corner[h.idx()];
            }
            if area > 0.0 { s / area } else { Vec3::ZERO }
        })
        .collect()
}

/// Mean curvature H_i = ½ K_i · N_i from the mean-curvature normal and the
/// area-weighted vertex normal (positive on a sphere with outward normals).
/// Boundary vertices get 0.
pub fn mean_curvature(mesh: &SurfaceMesh) -> Vec<f64> {
    let k = mean_curvature_normals(mesh);
    let n = vertex_normals(mesh);
    k.iter().zip(&n).map(|(k, n)| 0.5 * k.dot(*n)).collect()
}

/// Gaussian curvature by the angle defect over the mixed area (Meyer et al.
/// 2003 Eq. (9)): K_i = (2π − Σ θ_j) / A_i for interior vertices and
/// (π − Σ θ_j) / A_i on the boundary. Zero area gives 0.
pub fn gaussian_curvature(mesh: &SurfaceMesh) -> Vec<f64> {
    let corner = mixed_corner_areas(mesh);
    let p = mesh.positions();
    (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let v = VertexId(v);
            if mesh.is_isolated(v) {
                return 0.0;
            }
            let xi = p[v.idx()];
            let mut angle = 0.0;
            let mut area = 0.0;
            for h in mesh.outgoing(v) {
                if mesh.is_boundary_halfedge(h) {
                    continue;
                }
                let a = p[mesh.to_vertex(h).idx()] - xi;
                let b = p[mesh.from_vertex(mesh.prev(h)).idx()] - xi;
                angle += angle_between(a, b);
                area += corner[h.idx()];
            }
            let full = if mesh.is_boundary_vertex(v) {
                PI
            } else {
                2.0 * PI
            };
            if area > 0.0 {
                (full - angle) / area
            } else {
                0.0
            }
        })
        .collect()
}

/// An orthonormal tangent frame at a vertex: the first edge projected into
/// the tangent plane, and n × that. Zero vectors when n is zero.
fn vertex_frame(mesh: &SurfaceMesh, v: VertexId, n: Vec3) -> (Vec3, Vec3) {
    if n == Vec3::ZERO {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let p = mesh.positions();
    let mut u = Vec3::ZERO;
    for h in mesh.outgoing(v) {
        let e = p[mesh.to_vertex(h).idx()] - p[v.idx()];
        u = (e - e.dot(n) * n).normalize_or_zero();
        if u != Vec3::ZERO {
            break;
        }
    }
    if u == Vec3::ZERO {
        u = n.any_orthonormal_vector();
    }
    (u, n.cross(u))
}

/// Eigen-decomposition of the symmetric 2×2 tensor [[a, b], [b, c]]:
/// returns (λ1 ≥ λ2, (cos θ, sin θ) of the λ1 eigenvector).
#[inline]
fn eigen_sym2(a: f64, b: f64, c: f64) -> (f64, f64, f64, f64) {
    let m = 0.5 * (a + c);
    let d = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    (m + d, m - d, theta.cos(), theta.sin())
}

/// Rotates the frame (u, v) about u × v × n so that it becomes perpendicular
/// to `n` (trimesh2's `rot_coord_sys`, Rusinkiewicz 2004 §3).
#[inline]
fn rotate_frame(u: Vec3, v: Vec3, n: Vec3) -> (Vec3, Vec3) {
    let old_n = u.cross(v);
    let ndot = old_n.dot(n);
    if ndot <= -1.0 + 1e-12 {
        return (-u, -v);
    }
    let perp_old = n - ndot * old_n;
    let dperp = (old_n + n) / (1.0 + ndot);
    (u - dperp * u.dot(perp_old), v - dperp * v.dot(perp_old))
}

/// Principal curvatures and directions by Rusinkiewicz (2004), "Estimating
/// curvatures and their derivatives on triangle meshes":
/// per face, a frame (t along the first edge, b = n × t) and a 3×3
/// least-squares fit of the shape operator S (with dn = S e) to the normal
/// differences along the three edges (§3, Eq. (4)); each face tensor is
/// rotated into the frame of each of its vertices and averaged with the
/// mixed Voronoi corner areas as weights (§4); the averaged 2×2 tensor is
/// diagonalised. Vertex normals use the weights of Max (1999), exact on
/// spheres, as trimesh2 does. Degenerate faces and singular fits are skipped.
/// Triangle meshes; non-triangle faces are ignored.
pub fn principal_curvatures_rusinkiewicz(mesh: &SurfaceMesh) -> PrincipalCurvatures {
    let normals = vertex_normals_max(mesh);
    let corner = triangle_corner_areas(mesh);
    let p = mesh.positions();
    // Per-face tensor (ku, kuv, kv) in frame (t, b); None when degenerate.
    let face_tensors: Vec<Option<(Vec3, Vec3, [f64; 3])>> = (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            let f = FaceId(f);
            let h0 = mesh.face_halfedge(f);
            let h1 = mesh.next(h0);
            let h2 = mesh.next(h1);
            if mesh.next(h2) != h0 {
                return None;
            }
            let vs = [mesh.to_vertex(h0), mesh.to_vertex(h1), mesh.to_vertex(h2)];
            let x = vs.map(|v| p[v.idx()]);
            let nv = vs.map(|v| normals[v.idx()]);
            // edge j is opposite vertex j
            let e = [x[2] - x[1], x[0] - x[2], x[1] - x[0]];
            let dn = [nv[2] - nv[1], nv[0] - nv[2], nv[1] - nv[0]];
            let t = e[0].normalize_or_zero();
            let n = e[0].cross(e[1]).normalize_or_zero();
            if t == Vec3::ZERO || n == Vec3::ZERO {
                return None;
            }
            let b = n.cross(t);
            let (mut w00, mut w01, mut w22) = (0.0, 0.0, 0.0);
            let mut m = [0.0; 3];
            for j in 0..3 {
                let u = e[j].dot(t);
                let v = e[j].dot(b);
                w00 += u * u;
                w01 += u * v;
                w22 += v * v;
                let dnu = dn[j].dot(t);
                let dnv = dn[j].dot(b);
                m[0] += dnu * u;
                m[1] += dnu * v + dnv * u;
                m[2] += dnv * v;
            }
            let w11 = w00 + w22;
            let w12 = w01;
            let k = solve3([[w00, w01, 0.0], [w01, w11, w12], [0.0, w12, w22]], m)?;
            if !k.iter().all(|v| v.is_finite()) {
                return None;
            }
            Some((t, b, k))
        })
        .collect();
    let results: Vec<(f64, f64, Vec3, Vec3)> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let v = VertexId(v);
            let n = normals[v.idx()];
            let (pu, pv) = vertex_frame(mesh, v, n);
            if pu == Vec3::ZERO {
                return (0.0, 0.0, Vec3::ZERO, Vec3::ZERO);
            }
            let (mut a, mut bb, mut c, mut wsum) = (0.0, 0.0, 0.0, 0.0);
            for h in mesh.outgoing(v) {
                let Some(f) = mesh.face(h) else { continue };
                let Some((t, b, k)) = face_tensors[f.idx()] else {
                    continue;
                };
                let tri = mesh.triangle(f);
                let k_at = if tri[0] == v {
                    0
                } else if tri[1] == v {
                    1
                } else {
                    2
                };
                let wt = corner[f.idx()][k_at];
                if !(wt > 0.0) {
                    continue;
                }
                // rotate the vertex frame into the face plane, then project
                let (ru, rv) = rotate_frame(pu, pv, t.cross(b));
                let (u1, v1) = (ru.dot(t), ru.dot(b));
                let (u2, v2) = (rv.dot(t), rv.dot(b));
                let ku = k[0] * u1 * u1 + k[1] * 2.0 * u1 * v1 + k[2] * v1 * v1;
                let kuv = k[0] * u1 * u2 + k[1] * (u1 * v2 + u2 * v1) + k[2] * v1 * v2;
                let kv = k[0] * u2 * u2 + k[1] * 2.0 * u2 * v2 + k[2] * v2 * v2;
                a += wt * ku;
                bb += wt * kuv;
                c += wt * kv;
                wsum += wt;
            }
            if !(wsum > 0.0) {
                return (0.0, 0.0, pu, pv);
            }
            let (k1, k2, cs, sn) = eigen_sym2(a / wsum, bb / wsum, c / wsum);
            let d1 = (cs * pu + sn * pv).normalize_or_zero();
            let d2 = n.cross(d1);
            (k1, k2, d1, d2)
        })
        .collect();
    unzip(results, normals)
}

fn unzip(results: Vec<(f64, f64, Vec3, Vec3)>, normals: Vec<Vec3>) -> PrincipalCurvatures {
    let mut out = PrincipalCurvatures {
        k1: Vec::with_capacity(results.len()),
        k2: Vec::with_capacity(results.len()),
        d1: Vec::with_capacity(results.len()),
        d2: Vec::with_capacity(results.len()),
        normals,
    };
    for (k1, k2, d1, d2) in results {
        out.k1.push(k1);
        out.k2.push(k2);
        out.d1.push(d1);
        out.d2.push(d2);
    }
    out
}

/// Principal curvatures from H and K (Meyer et al. 2003 §4–5):
/// k1,2 = H ± √max(H² − K, 0), with H from [`mean_curvature`] and K from
/// [`gaussian_curvature`]. Directions: eigenvectors of the 2×2 tensor fitted
/// by least squares to the normal curvatures of the incident edges,
/// κ_ij = 2 (x_i − x_j)·n_i / |x_i − x_j|² (Meyer et al. §5.3, without the
/// eigenvalue constraint); the eigenvalues are those from H and K. Boundary
/// vertices have no mean-curvature normal and get k1 = k2 = 0.
pub fn principal_curvatures_meyer(mesh: &SurfaceMesh) -> PrincipalCurvatures {
    let normals = vertex_normals(mesh);
    let kn = mean_curvature_normals(mesh);
    let gauss = gaussian_curvature(mesh);
    let p = mesh.positions();
    let results: Vec<(f64, f64, Vec3, Vec3)> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let v = VertexId(v);
            let n = normals[v.idx()];
            let (pu, pv) = vertex_frame(mesh, v, n);
            if pu == Vec3::ZERO || mesh.is_boundary_vertex(v) {
                return (0.0, 0.0, pu, pv);
            }
            let h = 0.5 * kn[v.idx()].dot(n);
            let disc = (h * h - gauss[v.idx()]).max(0.0).sqrt();
            let (k1, k2) = (h + disc, h - disc);
            // least-squares fit of κ = a u² + 2 b u v + c v²
            let xi = p[v.idx()];
            let mut ata = [[0.0f64; 3]; 3];
            let mut atb = [0.0f64; 3];
            for he in mesh.outgoing(v) {
                let d = p[mesh.to_vertex(he).idx()] - xi;
                let l2 = d.length_squared();
                let t = (d - d.dot(n) * n).normalize_or_zero();
                if !(l2 > 0.0) || t == Vec3::ZERO {
                    continue;
                }
                let kappa = -2.0 * d.dot(n) / l2;
                let (u, w) = (t.dot(pu), t.dot(pv));
                let row = [u * u, 2.0 * u * w, w * w];
                for r in 0..3 {
                    for s in 0..3 {
                        ata[r][s] += row[r] * row[s];
                    }
                    atb[r] += row[r] * kappa;
                }
            }
            let (cs, sn) = match solve3(ata, atb) {
                Some([a, b, c]) => {
                    let (_, _, cs, sn) = eigen_sym2(a, b, c);
                    (cs, sn)
                }
                None => (1.0, 0.0),
            };
            let d1 = (cs * pu + sn * pv).normalize_or_zero();
            let d2 = n.cross(d1);
            (k1, k2, d1, d2)
        })
        .collect();
    unzip(results, normals)
}

/// Solves a 3×3 system by Cramer's rule; `None` when (nearly) singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(a);
    let scale: f64 = a.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
    if !(d.abs() > 1e-12 * scale * scale * scale) {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = a;
        for r in 0..3 {
            m[r][k] = b[r];
        }
        *xk = det3(m) / d;
    }
    Some(x)
}
