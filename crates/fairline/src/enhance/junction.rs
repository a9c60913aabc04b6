//! Vertex normals where a flat or gently curved part meets a fillet
//! tangentially.
//!
//! The corner normals of the Phong lift (module `surface`) are area-weighted
//! means of the normals of the faces around a vertex. On a smooth surface the
//! faces on either side of the vertex tilt by about the same angle the
//! opposite way, and the mean is the normal. Where a plane (or a cylinder
//! wall, straight across the junction) meets a fillet of curvature κ
//! tangentially (G¹ but not G²: a flat–fillet or fillet–wall junction of a
//! CAD part), the faces on the flat side carry the normal while those on the
//! fillet side turn by about κℓ/2 over an edge ℓ, and the mean tilts by
//! about κℓ/4: the flat's Phong patch is bent by the tilt and the fillet's is
//! bent too little (measured on the filleted cylinder of the accuracy tests:
//! the true normals at the junction vertices alone lower its RMS distance to
//! the true surface from −19 % to −28 % of the input's).
//!
//! The model of such a junction: a height field over the tangent plane at the
//! vertex, z = g·x + ½ xᵀ H± x, with one tangent plane (g) and one normal
//! curvature along the junction line (H±'s entry along the line) shared by
//! both sides, and a second fundamental form of its own on each side of a
//! line through the vertex (H+ and H− differ across the line). It is fitted
//! by least squares to the vertices of the 2-ring, for each line through the
//! vertex along one of its edges, and compared with the single osculating
//! quadric z = g·x + ½ xᵀ H x; where the Bayesian information criterion
//! (Schwarz 1978) prefers the split model — it has two more parameters, so
//! its residual must fall by the factor n^(−2/n) for n points — the vertex
//! takes the split model's normal (−g, 1). On a smooth surface the single
//! quadric fits (the mean normal is kept); at a junction each side's
//! quadric is exact on its own side and the tangent plane they share is the
//! surface's.
//!
//! A limitation: with two rows of vertices on a side, a curvature that jumps
//! at the line cannot be told from one that changes linearly across it (a
//! cubic z = k y³ is fitted exactly by the split model too, whose slope at
//! the vertex is then off by 2kℓ² where the mean's is off by kℓ²); both are
//! second-order errors, where the mean's error at a junction is first-order.

use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::solve::solve_spd;

/// Fewest vertices of the 2-ring for the split fit (seven parameters).
const MIN_POINTS: usize = 10;

/// Relative size of rounding errors in the fits: residuals below it (times
/// the size of the coordinates) count as zero, so that the choice between
/// the models does not depend on rounding (the result stays invariant to
/// rigid motion and scale on exactly flat or quadric parts).
const ROUNDING: f64 = 1e-9;

/// Two spokes whose directions have a dot product below −this lie on one
/// line through the vertex (the split fit along it is done once).
const SAME_LINE: f64 = 1.0 - 1e-12;

/// Split fits whose residuals differ by less than this share of the single
/// quadric's residual are equally good (module documentation).
const TIE: f64 = 1e-6;

/// Faces around a vertex whose normals agree to this (1 − cos) are coplanar:
/// the vertex lies on a plane and keeps its normal (flat faces stay flat).
const COPLANAR: f64 = 1e-12;

/// The normal of the split-quadric model at `v` (module documentation)
/// where the information criterion prefers it to the single quadric;
/// `None` elsewhere (and for boundary vertices, whose fan is one-sided).
/// `normal` is the vertex's current unit normal (the frame of the fit).
pub(super) fn junction_normal(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    corner_normals: &[[Vec3; 3]],
    separate: &[bool],
    v: VertexId,
    normal: Vec3,
) -> Option<Vec3> {
    if normal == Vec3::ZERO || mesh.is_boundary_vertex(v) {
        return None;
    }
    let origin = positions[v.idx()];
    let (t1, t2) = normal.any_orthonormal_pair();
    let local = |u: VertexId| {
        let d = positions[u.idx()] - origin;
        Vec3::new(d.dot(t1), d.dot(t2), d.dot(normal))
    };
    let spokes: Vec<Vec3> = mesh.one_ring(v).map(local).collect();
    let points: Vec<Vec3> = smooth_two_ring(mesh, corner_normals, separate, v)
        .into_iter()
        .map(local)
        .filter(|p| p.is_finite())
        .collect();
    let n = points.len();
    if n < MIN_POINTS {
        return None;
    }
    // rounding: residuals below this are zero (coordinates of size `scale`)
    let scale = points.iter().map(|p| p.length_squared()).sum::<f64>() / n as f64;
    let rounding = n as f64 * ROUNDING * ROUNDING * scale;
    let single = quadric_residual(&points)?;
    if !(single > rounding) {
        // the single quadric fits: no junction
        return None;
    }
    // one line per pair of opposite spokes (the same line, the same fit)
    let mut lines: Vec<glam::DVec2> = Vec::with_capacity(spokes.len());
    for s in &spokes {
        let along = glam::DVec2::new(s.x, s.y).normalize_or_zero();
        if along != glam::DVec2::ZERO && !lines.iter().any(|l| l.dot(along) < -SAME_LINE) {
            lines.push(along);
        }
    }
    let fits: Vec<(f64, glam::DVec2)> = lines
        .iter()
        .filter_map(|&along| split_fit(&points, along))
        .collect();
    let split = fits.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
    if !split.is_finite() {
        return None;
    }
    // lines that fit equally well (a symmetric fan: rounding would pick one)
    // share the choice: their gradients are averaged
    let tie = split + TIE * single;
    let tied: Vec<glam::DVec2> = fits.iter().filter(|f| f.0 <= tie).map(|f| f.1).collect();
    let g = tied.iter().sum::<glam::DVec2>() / tied.len() as f64;
    let split = split.max(rounding);
    let prefers_split = n as f64 * (split / single).ln() + 2.0 * (n as f64).ln() < 0.0;
    if !prefers_split {
        return None;
    }
    let fitted = (normal - g.x * t1 - g.y * t2).normalize_or_zero();
    (fitted != Vec3::ZERO && fitted.is_finite() && fitted.dot(normal) > 0.0).then_some(fitted)
}

/// The vertices of the 2-ring of `v` reached without crossing a crease:
/// those of the faces around each neighbour u that are in the smoothing
/// group of v's faces at u (equal corner normals at u) and are no chord
/// face (`separate`); `v` itself left out.
fn smooth_two_ring(
    mesh: &SurfaceMesh,
    corner_normals: &[[Vec3; 3]],
    separate: &[bool],
    v: VertexId,
) -> Vec<VertexId> {
    let corner = |f: FaceId, u: VertexId| {
        let k = mesh.triangle(f).iter().position(|&w| w == u)?;
        Some(corner_normals[f.idx()][k])
    };
    let mut ring = Vec::new();
    for f in mesh.vertex_faces(v) {
        for u in mesh.triangle(f) {
            if u == v {
                continue;
            }
            let Some(group) = corner(f, u) else { continue };
            for g in mesh.vertex_faces(u) {
                if !separate[g.idx()] && corner(g, u) == Some(group) {
                    ring.extend(mesh.triangle(g));
                }
            }
        }
    }
    ring.sort_unstable_by_key(|u| u.0);
    ring.dedup();
    ring.retain(|&u| u != v);
    ring
}

/// Residual sum of squares of the osculating quadric z = g·x + ½ xᵀHx
/// (five parameters, through the origin) fitted to `points`.
fn quadric_residual(points: &[Vec3]) -> Option<f64> {
    let basis = |p: &Vec3| [p.x, p.y, p.x * p.x, p.x * p.y, p.y * p.y];
    let c = least_squares::<5>(points, basis)?;
    Some(
        points
            .iter()
            .map(|p| {
                let m = basis(p);
                let z: f64 = (0..5).map(|k| c[k] * m[k]).sum();
                (p.z - z).powi(2)
            })
            .sum(),
    )
}

/// The split-quadric model across the line through the origin along the
/// unit tangent direction `along` (module documentation): its residual sum
/// of squares and its gradient g in the frame of `points`.
fn split_fit(points: &[Vec3], along: glam::DVec2) -> Option<(f64, glam::DVec2)> {
    let across = along.perp();
    // coordinates (p along the line, q across it); the side by the sign of q
    let basis = |pt: &Vec3| {
        let x = glam::DVec2::new(pt.x, pt.y);
        let (p, q) = (x.dot(along), x.dot(across));
        let (minus, plus) = if q < 0.0 { (1.0, 0.0) } else { (0.0, 1.0) };
        [
            p,
            q,
            p * p,
            minus * p * q,
            minus * q * q,
            plus * p * q,
            plus * q * q,
        ]
    };
    let c = least_squares::<7>(points, basis)?;
    let residual = points
        .iter()
        .map(|pt| {
            let m = basis(pt);
            let z: f64 = (0..7).map(|k| c[k] * m[k]).sum();
            (pt.z - z).powi(2)
        })
        .sum();
    Some((residual, c[0] * along + c[1] * across))
}

/// The least-squares coefficients of z ≈ Σ c_k basis(p)_k over `points`
/// (normal equations, [`solve_spd`]); `None` for a rank-deficient fit.
fn least_squares<const N: usize>(
    points: &[Vec3],
    basis: impl Fn(&Vec3) -> [f64; N],
) -> Option<[f64; N]> {
    let mut a = [[0.0; N]; N];
    let mut b = [0.0; N];
    for p in points {
        let m = basis(p);
        for i in 0..N {
            for j in i..N {
                a[i][j] += m[i] * m[j];
            }
            b[i] += m[i] * p.z;
        }
    }
    solve_spd(&a, &b)
}

/// Replaces the corner normals of each interior vertex whose faces form one
/// smoothing group (none of them a chord face, `separate`) and are not all
/// coplanar (unit `face_normals`) by its [`junction_normal`] where there is
/// one.
pub(super) fn refine_corner_normals(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    face_normals: &[Vec3],
    corner_normals: &mut [[Vec3; 3]],
    separate: &[bool],
) {
    use rayon::prelude::*;
    let corner_of = |f: FaceId, v: VertexId| {
        let k = mesh.triangle(f).iter().position(|&u| u == v)?;
        Some(corner_normals[f.idx()][k])
    };
    let fitted: Vec<(u32, Vec3)> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .filter_map(|v| {
            let v = VertexId(v);
            let mut shared: Option<Vec3> = None;
            let mut fan_normal: Option<Vec3> = None;
            let mut planar = true;
            for f in mesh.vertex_faces(v) {
                let n = face_normals[f.idx()];
                match fan_normal {
                    None => fan_normal = Some(n),
                    Some(m) => planar &= n.dot(m) >= 1.0 - COPLANAR,
                }
                let n = corner_of(f, v)?;
                if separate[f.idx()] || shared.is_some_and(|s| s != n) {
                    return None;
                }
                shared = Some(n);
            }
            if planar {
                return None;
            }
            junction_normal(mesh, positions, corner_normals, separate, v, shared?).map(|n| (v.0, n))
        })
        .collect();
    for (v, n) in fitted {
        let v = VertexId(v);
        for f in mesh.vertex_faces(v) {
            if let Some(k) = mesh.triangle(f).iter().position(|&u| u == v) {
                corner_normals[f.idx()][k] = n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{face_normals, vertex_normals};
    use crate::shapes::height_field;

    /// The corner normals of a mesh without creases: the vertex normals.
    fn corners(mesh: &SurfaceMesh) -> Vec<[Vec3; 3]> {
        let normals = vertex_normals(mesh);
        mesh.faces()
            .map(|f| mesh.triangle(f).map(|v| normals[v.idx()]))
            .collect()
    }

    /// The angle (degrees) between the mean normal and z, and between the
    /// junction normal and z, at the centre vertex of a 7 × 7 height field
    /// over [−1.5, 1.5]² (spacing ½).
    fn at_centre(height: impl Fn(f64, f64) -> f64) -> (f64, Option<f64>) {
        let mesh = height_field(7, 7, (-1.5, 1.5), (-1.5, 1.5), height);
        let normals = corners(&mesh);
        let separate = vec![false; mesh.face_count()];
        let centre = VertexId(3 + 7 * 3);
        let mean = vertex_normals(&mesh)[centre.idx()];
        let angle = |n: Vec3| n.dot(Vec3::Z).clamp(-1.0, 1.0).acos().to_degrees();
        let fitted = junction_normal(&mesh, mesh.positions(), &normals, &separate, centre, mean);
        (angle(mean), fitted.map(angle))
    }

    /// A plane meeting a circular fillet (radius 2, over edges of ½)
    /// tangentially at the vertex: the true normal is z; the mean of the
    /// faces tilts by about κℓ/4 (3.6°) toward the fillet, the junction fit
    /// (one tangent plane, a quadric of its own on each side) is within 1.2°
    /// (the quadric's error on the circle's quartic term).
    #[test]
    fn a_flat_meeting_a_fillet_tangentially_takes_the_flats_normal() {
        let r = 2.0;
        let (mean, fitted) = at_centre(|_, y| {
            if y <= 0.0 {
                0.0
            } else {
                r - (r * r - y * y).sqrt()
            }
        });
        let fitted = fitted.expect("the split model is preferred at a junction");
        assert!(mean > 3.0, "mean {mean}°");
        assert!(fitted < 1.2, "fitted {fitted}° (mean {mean}°)");
    }

    /// On a smooth quadric (a paraboloid, the true normal z at the centre)
    /// the single quadric fits and the mean normal is kept, or the fit is
    /// as good as the mean.
    #[test]
    fn a_smooth_quadric_keeps_its_normal() {
        let (mean, fitted) = at_centre(|x, y| 0.2 * x * x + 0.3 * y * y);
        assert!(mean < 1e-9, "mean {mean}°");
        if let Some(fitted) = fitted {
            assert!(fitted < 1e-6, "fitted {fitted}°");
        }
    }

    /// Corner normals of a plane, and of a vertex whose faces are coplanar
    /// beside a fillet, are not changed (flat faces stay exactly flat).
    #[test]
    fn coplanar_fans_keep_their_corner_normals() {
        let mesh = height_field(9, 9, (-2.0, 2.0), (-2.0, 2.0), |_, y| {
            if y <= 0.5 { 0.0 } else { (y - 0.5).powi(2) }
        });
        let before = corners(&mesh);
        let mut after = before.clone();
        refine_corner_normals(
            &mesh,
            mesh.positions(),
            &face_normals(&mesh),
            &mut after,
            &vec![false; mesh.face_count()],
        );
        let mut changed = 0;
        for f in mesh.faces() {
            for (k, v) in mesh.triangle(f).into_iter().enumerate() {
                let p = mesh.positions()[v.idx()];
                if p.y <= 0.0 {
                    assert_eq!(after[f.idx()][k], before[f.idx()][k], "{p}");
                }
                changed += usize::from(after[f.idx()][k] != before[f.idx()][k]);
            }
        }
        // the vertices on the junction line y = ½ take the fitted normal
        assert!(changed > 0);
    }
}
