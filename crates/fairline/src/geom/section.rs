//! Plane sections of a triangle mesh and their curvature combs.
//!
//! A section is the intersection of the mesh with the plane
//! `(x − point) · n = 0`: polylines through the points where edges cross
//! the plane (linear interpolation of the signed distances along the
//! edge), chained across the triangles. A vertex on the plane counts as
//! above it (distance ≥ 0), so each triangle is crossed by 0 or 2 of its
//! edges, each crossing on an edge interior or at a vertex on the plane.
//! A vertex on the plane is one point of the section however many of its
//! edges cross there; a triangle whose two crossings are the same vertex
//! only touches the plane and links nothing.
//!
//! The curvature of the section curve at a point comes from the surface
//! (Meusnier's theorem): with `S` the shape operator of the library's
//! principal curvatures ([`principal_curvatures_rusinkiewicz`]: k1, k2 and
//! their directions, interpolated along the crossed edge as the tensor
//! k1·d1d1ᵀ + k2·d2d2ᵀ), `t` the curve's unit tangent (from its
//! neighbours), `n` the surface normal and `m` the unit in-plane normal of
//! the curve (plane normal × t), the normal curvature κ_n = tᵀ S t gives the
//! curvature vector `K = −κ_n / (m·n) · m` (a sphere of radius r with
//! outward normals has κ_n = 1/r; its section at distance d from the centre
//! gets |K| = 1/√(r² − d²)). Where the plane nearly touches the surface
//! (|m·n| < 0.05) the circle through the point and its two neighbours is
//! used instead, κ = 2|(q − p) × (r − q)| / (a·b·c). The comb vector is
//! `−scale · K`: it stands on the convex side, as in CAD systems. The ends
//! of an open curve take the tangent of their one neighbour.

use super::curvature::{PrincipalCurvatures, principal_curvatures_rusinkiewicz};
use crate::Vec3;
use crate::mesh::{EdgeId, SurfaceMesh};
use glam::DMat3;
use std::collections::HashMap;

/// One polyline of a plane section.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionCurve {
    /// Points on the plane, in order along the curve.
    pub points: Vec<Vec3>,
    /// Whether the last point connects to the first.
    pub closed: bool,
    /// Curvature of the polyline at each point (≥ 0, finite).
    pub curvature: Vec<f64>,
    /// Unit vector from each point towards its centre of curvature (zero
    /// where the curvature is 0).
    pub towards_center: Vec<Vec3>,
}

impl SectionCurve {
    /// The comb vector at each point: `−scale · κ · m` (module documentation).
    pub fn comb(&self, scale: f64) -> Vec<Vec3> {
        self.curvature
            .iter()
            .zip(&self.towards_center)
            .map(|(k, m)| -scale * *k * *m)
            .collect()
    }

    /// The length of the polyline.
    pub fn length(&self) -> f64 {
        let n = self.points.len();
        let open: f64 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        if self.closed && n > 1 {
            open + self.points[n - 1].distance(self.points[0])
        } else {
            open
        }
    }
}

/// The section of the triangle mesh `mesh` by the plane through `point`
/// with normal `normal` (need not be unit; a zero or non-finite normal
/// gives no curve). Polygon faces are skipped: triangulate first.
pub fn plane_section(mesh: &SurfaceMesh, point: Vec3, normal: Vec3) -> Vec<SectionCurve> {
    section_with(
        mesh,
        &principal_curvatures_rusinkiewicz(mesh),
        point,
        normal,
    )
}

/// [`plane_section`] with the principal curvatures of `mesh` given.
fn section_with(
    mesh: &SurfaceMesh,
    pc: &PrincipalCurvatures,
    point: Vec3,
    normal: Vec3,
) -> Vec<SectionCurve> {
    let n = normal.normalize_or_zero();
    if n == Vec3::ZERO || !point.is_finite() {
        return Vec::new();
    }
    let s: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|p| (*p - point).dot(n))
        .collect();
    // the crossing of each crossed edge, and the point it stands for: a
    // vertex on the plane once, however many of its edges cross there
    let mut crossing: HashMap<EdgeId, usize> = HashMap::new();
    let mut on_plane: HashMap<usize, usize> = HashMap::new();
    let mut points: Vec<Vec3> = Vec::new();
    // the surface normal and shape operator at each crossing
    let mut frames: Vec<(Vec3, DMat3)> = Vec::new();
    let shape = |v: usize| {
        let (d1, d2) = (pc.d1[v], pc.d2[v]);
        let outer = |d: Vec3| DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        pc.k1[v] * outer(d1) + pc.k2[v] * outer(d2)
    };
    for e in mesh.edges() {
        let (a, b) = mesh.edge_vertices(e);
        let (sa, sb) = (s[a.idx()], s[b.idx()]);
        if !(sa.is_finite() && sb.is_finite()) || (sa >= 0.0) == (sb >= 0.0) {
            continue;
        }
        let t = sa / (sa - sb); // sa and sb differ in sign: sa − sb ≠ 0
        let (pa, pb) = (mesh.position(a), mesh.position(b));
        let t = t.clamp(0.0, 1.0);
        let at_vertex = if sa == 0.0 {
            Some(a.idx())
        } else if sb == 0.0 {
            Some(b.idx())
        } else {
            None
        };
        if let Some(v) = at_vertex {
            if let Some(&i) = on_plane.get(&v) {
                crossing.insert(e, i);
                continue;
            }
            on_plane.insert(v, points.len());
        }
        crossing.insert(e, points.len());
        points.push(pa + t * (pb - pa));
        let nrm = ((1.0 - t) * pc.normals[a.idx()] + t * pc.normals[b.idx()]).normalize_or_zero();
        frames.push((nrm, (1.0 - t) * shape(a.idx()) + t * shape(b.idx())));
    }
    // each crossed triangle links its two crossings
    let mut links: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    for f in mesh.faces() {
        if mesh.face_size(f) != 3 {
            continue;
        }
        let hit: Vec<usize> = mesh
            .face_halfedges(f)
            .filter_map(|h| crossing.get(&mesh.edge(h)).copied())
            .collect();
        if let [a, b] = hit[..]
            && a != b
        {
            // an edge in the plane is shared by two crossed triangles
            if !links[a].contains(&b) {
                links[a].push(b);
                links[b].push(a);
            }
        }
    }
    let extent = crate::mesh::bounding_box(mesh.positions())
        .map(|(lo, hi)| (hi - lo).length())
        .unwrap_or(1.0);
    let mut used = vec![false; points.len()];
    let mut curves = Vec::new();
    // open chains start at a crossing with one link, then the loops
    let starts: Vec<usize> = (0..points.len())
        .filter(|&i| links[i].len() == 1)
        .chain(0..points.len())
        .collect();
    for start in starts {
        if used[start] || links[start].is_empty() {
            continue;
        }
        let mut chain = vec![start];
        used[start] = true;
        let mut cur = start;
        let closed;
        loop {
            match links[cur].iter().copied().find(|&j| !used[j]) {
                Some(j) => {
                    used[j] = true;
                    chain.push(j);
                    cur = j;
                }
                None => {
                    closed = chain.len() > 2 && links[cur].contains(&start);
                    break;
                }
            }
        }
        let pts: Vec<Vec3> = chain.iter().map(|&i| points[i]).collect();
        let fr: Vec<(Vec3, DMat3)> = chain.iter().map(|&i| frames[i]).collect();
        curves.push(curve_with_curvature(pts, &fr, n, closed, extent));
    }
    curves
}

/// `count` parallel sections `spacing` apart, the first through `point`
/// (count at least 1); sections in order, each a list of curves.
pub fn parallel_sections(
    mesh: &SurfaceMesh,
    point: Vec3,
    normal: Vec3,
    count: usize,
    spacing: f64,
) -> Vec<Vec<SectionCurve>> {
    let n = normal.normalize_or_zero();
    let step = if spacing.is_finite() { spacing } else { 0.0 };
    let pc = principal_curvatures_rusinkiewicz(mesh);
    (0..count.max(1))
        .map(|k| section_with(mesh, &pc, point + (k as f64 * step) * n, normal))
        .collect()
}

/// The curve of `points` with its curvature (module documentation);
/// `frames`: the surface normal and shape operator at each point, `plane`
/// the unit plane normal.
fn curve_with_curvature(
    points: Vec<Vec3>,
    frames: &[(Vec3, DMat3)],
    plane: Vec3,
    closed: bool,
    extent: f64,
) -> SectionCurve {
    let n = points.len();
    let tiny = 1e-12 * extent.max(f64::MIN_POSITIVE);
    let mut curvature = vec![0.0; n];
    let mut towards = vec![Vec3::ZERO; n];
    if n < 2 {
        return SectionCurve {
            points,
            closed,
            curvature,
            towards_center: towards,
        };
    }
    for i in 0..n {
        let (prev, next) = if closed {
            ((i + n - 1) % n, (i + 1) % n)
        } else {
            (i.saturating_sub(1), (i + 1).min(n - 1))
        };
        let t = (points[next] - points[prev]).normalize_or_zero();
        if t == Vec3::ZERO {
            continue;
        }
        let m = plane.cross(t).normalize_or_zero();
        let (nrm, s) = frames[i];
        let mn = m.dot(nrm);
        let k_vec = if mn.abs() >= 0.05 {
            let tt = (t - t.dot(nrm) * nrm).normalize_or_zero();
            let kn = tt.dot(s * tt);
            (-kn / mn) * m
        } else if prev != i && next != i {
            // the plane nearly touches the surface: the circle through
            // the point and its neighbours
            let (p, q, r) = (points[prev], points[i], points[next]);
            let (a, b, c) = (q.distance(r), p.distance(r), p.distance(q));
            if a < tiny || b < tiny || c < tiny {
                continue;
            }
            let cross = (q - p).cross(r - q);
            let k = 2.0 * cross.length() / (a * b * c);
            k * cross.cross(r - p).normalize_or_zero()
        } else {
            continue;
        };
        let k = k_vec.length();
        if k.is_finite() && k > 0.0 {
            curvature[i] = k;
            towards[i] = k_vec / k;
        }
    }
    SectionCurve {
        points,
        closed,
        curvature,
        towards_center: towards,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// A plane z = c cuts a sphere of radius r in a circle of radius
    /// ρ = √(r² − c²): the section's points lie on it (to the chordal
    /// error), its curvature is 1/ρ (Meusnier: 1/r over cos), its comb
    /// scale/ρ long, pointing away from the axis.
    #[test]
    fn sphere_section_is_a_circle_of_known_radius() {
        let (r, c) = (2.0, 0.7);
        let m = shapes::icosphere(r, 4);
        let curves = plane_section(&m, Vec3::new(0.0, 0.0, c), Vec3::Z);
        assert_eq!(curves.len(), 1);
        let cv = &curves[0];
        assert!(cv.closed);
        let rho = (r * r - c * c).sqrt();
        for p in &cv.points {
            let x = p.truncate().length();
            assert!((x - rho).abs() < 0.005 * rho, "{x} vs {rho}");
            assert!((p.z - c).abs() < 1e-12);
        }
        let mean = cv.curvature.iter().sum::<f64>() / cv.curvature.len() as f64;
        assert!(
            (mean * rho - 1.0).abs() < 0.01,
            "mean curvature {mean}, 1/rho {}",
            1.0 / rho
        );
        for k in &cv.curvature {
            assert!((k * rho - 1.0).abs() < 0.05, "{k} vs {}", 1.0 / rho);
        }
        let comb = cv.comb(0.5);
        for ((v, p), k) in comb.iter().zip(&cv.points).zip(&cv.curvature) {
            assert!((v.length() - 0.5 * k).abs() < 1e-12);
            assert!(v.truncate().dot(p.truncate()) > 0.0, "comb points outward");
        }
        let l = cv.length();
        assert!((l - 2.0 * std::f64::consts::PI * rho).abs() < 0.01 * l);
    }

    /// The plane through the equator of an icosphere holds vertices and
    /// whole edges of the mesh: each vertex is one point of the curve, and
    /// the curvature is 1/r at every point (no zero teeth where a vertex's
    /// edges would give repeated points).
    #[test]
    fn a_plane_through_vertices_gives_each_vertex_once() {
        let r = 2.0;
        let m = shapes::icosphere(r, 4);
        let on_equator = m.positions().iter().filter(|p| p.z.abs() < 1e-12).count();
        assert!(on_equator > 8, "the icosphere has vertices on its equator");
        let curves = plane_section(&m, Vec3::ZERO, Vec3::Z);
        assert_eq!(curves.len(), 1, "{curves:?}");
        let cv = &curves[0];
        assert!(cv.closed);
        let n = cv.points.len();
        for i in 0..n {
            let d = cv.points[i].distance(cv.points[(i + 1) % n]);
            assert!(d > 1e-9, "repeated point {i} of {n}");
        }
        for k in &cv.curvature {
            assert!((k * r - 1.0).abs() < 0.05, "{k} vs {}", 1.0 / r);
        }
        let l = cv.length();
        assert!((l - 2.0 * std::f64::consts::PI * r).abs() < 0.01 * l);
    }

    #[test]
    fn cylinder_cut_along_its_axis_gives_two_straight_lines() {
        let m = shapes::cylinder(1.0, 2.0, 32, 8);
        let curves = plane_section(&m, Vec3::new(0.013, 0.0, 0.0), Vec3::X);
        assert_eq!(curves.len(), 2, "{curves:?}");
        for cv in &curves {
            assert!(!cv.closed);
            assert!(cv.curvature.iter().all(|k| k.abs() < 1e-9));
        }
        // no plane, no curve; a plane beside the mesh, none either
        assert!(plane_section(&m, Vec3::ZERO, Vec3::ZERO).is_empty());
        assert!(plane_section(&m, Vec3::new(5.0, 0.0, 0.0), Vec3::X).is_empty());
        let stack = parallel_sections(&m, Vec3::new(0.0, 0.0, 0.1), Vec3::Z, 3, 0.5);
        assert_eq!(stack.len(), 3);
        assert!(stack.iter().all(|s| s.len() == 1 && s[0].closed));
    }
}
