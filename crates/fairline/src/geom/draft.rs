//! Draft angles of a surface against a pull (demoulding) direction.
//!
//! The draft angle of a surface element with unit normal `n` against the
//! unit pull direction `d` is the angle between the element's tangent
//! plane and `d`:
//!
//! `δ = asin(n · d)` (degrees, in [−90°, 90°]),
//!
//! i.e. 90° minus the angle between `n` and `d`. A face with δ > 0 faces
//! the pull direction and releases from the mould half that moves along
//! `d`; δ < 0 faces away (it belongs to the opposite half, or is an
//! undercut); |δ| below the minimum draft angle of the process is
//! insufficient draft for either half (walls parallel to `d` have δ = 0).
//! A cone of half-angle α about `d` (apex towards `d`) has δ = α on its
//! mantle, a cylinder about `d` has δ = 0.
//!
//! Face values use the unit face normals, vertex values the area-weighted
//! vertex normals ([`vertex_normals`], Yong et al. Eq. (3)); degenerate
//! faces and vertices without a normal get δ = 0 and count as area 0.

use super::areas::face_areas;
use super::normals::{face_normals, vertex_normals};
use crate::Vec3;
use crate::mesh::SurfaceMesh;

/// The draft angles of a mesh ([`draft_angles`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DraftAngles {
    /// The unit pull direction used.
    pub pull: Vec3,
    /// Draft angle of each face, degrees in [−90, 90].
    pub face_deg: Vec<f64>,
    /// Draft angle at each vertex (from its area-weighted normal), degrees.
    pub vertex_deg: Vec<f64>,
    /// Area of each face (the weights of [`DraftAngles::shares`]).
    pub face_area: Vec<f64>,
}

/// Shares of the surface area by draft ([`DraftAngles::shares`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DraftShares {
    /// Total area of the faces.
    pub area: f64,
    /// Area with |δ| < the minimum angle (insufficient draft).
    pub below_area: f64,
    /// `below_area / area` (0 for a surface of no area).
    pub below: f64,
    /// Share of area with δ ≥ the minimum angle.
    pub positive: f64,
    /// Share of area with δ ≤ −the minimum angle.
    pub negative: f64,
    /// Smallest face draft angle, degrees (0 without faces).
    pub min_deg: f64,
    /// Largest face draft angle, degrees (0 without faces).
    pub max_deg: f64,
}

/// Errors of [`draft_angles`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DraftError {
    /// The pull direction is zero or not finite.
    #[error("the pull direction must be a non-zero finite vector")]
    BadPull,
}

/// `asin(n · d)` in degrees; 0 for a zero normal.
fn draft_of(n: Vec3, d: Vec3) -> f64 {
    if n == Vec3::ZERO {
        return 0.0;
    }
    n.dot(d).clamp(-1.0, 1.0).asin().to_degrees()
}

/// The draft angle of every face and vertex of `mesh` against `pull` (need
/// not be unit), module documentation.
pub fn draft_angles(mesh: &SurfaceMesh, pull: Vec3) -> Result<DraftAngles, DraftError> {
    let d = pull.normalize_or_zero();
    if !pull.is_finite() || d == Vec3::ZERO {
        return Err(DraftError::BadPull);
    }
    let face_deg = face_normals(mesh).iter().map(|&n| draft_of(n, d)).collect();
    let vertex_deg = vertex_normals(mesh)
        .iter()
        .map(|&n| draft_of(n, d))
        .collect();
    let face_area = face_areas(mesh)
        .into_iter()
        .map(|a| if a.is_finite() { a } else { 0.0 })
        .collect();
    Ok(DraftAngles {
        pull: d,
        face_deg,
        vertex_deg,
        face_area,
    })
}

impl DraftAngles {
    /// Whether face `f` has insufficient draft: |δ| < `min_deg`.
    pub fn is_below(&self, f: usize, min_deg: f64) -> bool {
        self.face_deg[f].abs() < min_deg
    }

    /// The shares of area with insufficient, positive and negative draft
    /// against the minimum angle `min_deg` (degrees).
    pub fn shares(&self, min_deg: f64) -> DraftShares {
        let (mut area, mut below, mut pos, mut neg) = (0.0, 0.0, 0.0, 0.0);
        for (&a, &dg) in self.face_area.iter().zip(&self.face_deg) {
            area += a;
            if dg.abs() < min_deg {
                below += a;
            } else if dg > 0.0 {
                pos += a;
            } else {
                neg += a;
            }
        }
        let share = |x: f64| if area > 0.0 { x / area } else { 0.0 };
        let fold = |f: fn(f64, f64) -> f64, init: f64| {
            let v = self.face_deg.iter().copied().fold(init, f);
            if v.is_finite() { v } else { 0.0 }
        };
        DraftShares {
            area,
            below_area: below,
            below: share(below),
            positive: share(pos),
            negative: share(neg),
            min_deg: fold(f64::min, f64::INFINITY),
            max_deg: fold(f64::max, f64::NEG_INFINITY),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// An open cone about +z, apex up, half-angle `alpha` (radians),
    /// `n` segments around and `m` rings along.
    fn cone(alpha: f64, n: u32, m: u32) -> SurfaceMesh {
        let h = 1.0;
        let r0 = h * alpha.tan();
        let mut p = Vec::new();
        for j in 0..m {
            let t = j as f64 / m as f64; // 0 at the base
            let r = r0 * (1.0 - t);
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                p.push(Vec3::new(r * a.cos(), r * a.sin(), t * h));
            }
        }
        let apex = p.len() as u32;
        p.push(Vec3::new(0.0, 0.0, h));
        let mut f = Vec::new();
        for j in 0..m - 1 {
            for i in 0..n {
                let a = j * n + i;
                let b = j * n + (i + 1) % n;
                f.push([a, b, b + n]);
                f.push([a, b + n, a + n]);
            }
        }
        for i in 0..n {
            let a = (m - 1) * n + i;
            let b = (m - 1) * n + (i + 1) % n;
            f.push([a, b, apex]);
        }
        SurfaceMesh::new(p, &f).unwrap()
    }

    #[test]
    fn cone_mantle_has_its_half_angle_as_draft() {
        for deg in [2.0f64, 10.0, 30.0] {
            let m = cone(deg.to_radians(), 64, 6);
            let d = draft_angles(&m, Vec3::Z).unwrap();
            // every face lies in the plane through the apex and a chord of
            // the base circle: a cone of half-angle atan(tan α cos(π/64))
            let exact = (deg.to_radians().tan() * (std::f64::consts::PI / 64.0).cos())
                .atan()
                .to_degrees();
            for &a in &d.face_deg {
                assert!((a - exact).abs() < 1e-9, "{a} vs {exact}");
            }
            // the vertex normals average neighbouring faces: within 0.05°
            for &a in &d.vertex_deg[..64] {
                assert!((a - deg).abs() < 0.05, "{a} vs {deg}");
            }
            let s = d.shares(deg + 1.0);
            assert!((s.below - 1.0).abs() < 1e-12);
            let s = d.shares(deg - 1.0);
            assert_eq!(s.below, 0.0);
            assert!((s.positive - 1.0).abs() < 1e-12);
            // pulled the other way the mantle is negative draft
            let s = draft_angles(&m, -Vec3::Z).unwrap().shares(deg - 1.0);
            assert!((s.negative - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn cylinder_walls_have_zero_draft() {
        let m = shapes::cylinder(1.0, 2.0, 48, 8);
        let d = draft_angles(&m, Vec3::new(0.0, 0.0, 3.0)).unwrap();
        assert_eq!(d.pull, Vec3::Z);
        // the open tube is all wall
        assert!(d.face_deg.iter().all(|a| a.abs() < 1e-9));
        assert!(d.vertex_deg.iter().all(|a| a.abs() < 1e-9));
        let s = d.shares(3.0);
        assert!((s.below - 1.0).abs() < 1e-12);
        assert!((s.area - 2.0 * std::f64::consts::PI * 2.0).abs() < 0.05);
        // a sideways pull sees the walls from 90° to -90°
        let side = draft_angles(&m, Vec3::X).unwrap();
        assert!(side.face_deg.iter().any(|&a| a > 80.0));
        assert!(side.face_deg.iter().any(|&a| a < -80.0));
    }

    #[test]
    fn bad_pull_is_refused() {
        let m = shapes::plane(3);
        assert_eq!(draft_angles(&m, Vec3::ZERO), Err(DraftError::BadPull));
        assert_eq!(
            draft_angles(&m, Vec3::new(f64::NAN, 0.0, 1.0)),
            Err(DraftError::BadPull)
        );
    }
}
