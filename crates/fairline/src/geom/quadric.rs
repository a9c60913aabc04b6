//! Normal and mean curvature from a local quadric fit over the two-ring.
//!
//! Fan-based estimators (area- or Max-weighted normals, Moreton–Séquin
//! curvature) are exact only for a complete one-ring; at a boundary vertex
//! the half fan tilts the normal by O(h). Fitting the height function
//! z = a x² + b xy + c y² + d x + e y over the tangent plane to the two-ring
//! (Goldfeather and Interrante's quadric fit, as used by the fairing methods
//! of the Grüner thesis §3.3–3.4 for their fixed G¹ boundary normals) gives
//! the normal (−d, −e, 1) and the mean curvature of the graph at the vertex
//! with errors of the order of the third derivatives, one-sided or not.

use crate::Vec3;
use crate::mesh::{SurfaceMesh, VertexId};

/// Result of [`quadric_fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricFit {
    /// Unit normal, oriented like the face normals around the vertex.
    pub normal: Vec3,
    /// Mean curvature H = ½(k1 + k2), geom's sign convention: a sphere of
    /// radius r with outward normals gives +1/r.
    pub mean: f64,
}

/// Least-squares quadric fit at vertex `v` over its two-ring (two passes: the
/// second in the frame of the first pass' normal). `None` when the vertex has
/// fewer than five distinct neighbours within two rings, no initial normal
/// can be defined, or the 5×5 normal equations are singular.
pub fn quadric_fit(mesh: &SurfaceMesh, v: VertexId) -> Option<QuadricFit> {
    quadric_fit_rings(mesh, v, 2)
}

/// [`quadric_fit`] over the `rings`-ring of `v` (at least one ring). A
/// wider ring averages out noise in the vertex positions (the normal error
/// from noise of amplitude σ falls like σ / (R √N) for a fit over N points
/// within radius R) at the price of a bias of the order of the third and
/// fourth derivatives times R and R².
pub fn quadric_fit_rings(mesh: &SurfaceMesh, v: VertexId, rings: usize) -> Option<QuadricFit> {
    let patch = quadric_patch_rings(mesh, v, rings)?;
    Some(QuadricFit {
        normal: patch.normal(),
        mean: patch.mean(),
    })
}

/// The fitted height function of [`quadric_patch_rings`]: the graph
/// z = a u² + b uw + c w² + d u + e w over the plane through the vertex
/// `origin` spanned by `u_axis`, `w_axis`, heights along `axis` (the normal
/// of the first fitting pass). It interpolates the vertex and approximates
/// the surface around it with an error of the order of the third
/// derivatives times the cube of the distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricPatch {
    /// The vertex the patch is fitted at (height 0).
    pub origin: Vec3,
    /// First in-plane axis (unit).
    pub u_axis: Vec3,
    /// Second in-plane axis (unit, `axis × u_axis`).
    pub w_axis: Vec3,
    /// Height axis (unit).
    pub axis: Vec3,
    /// Coefficients [a, b, c, d, e] of the height function.
    pub coefficients: [f64; 5],
}

impl QuadricPatch {
    /// Height of the graph over the in-plane coordinates (u, w).
    pub fn height(&self, u: f64, w: f64) -> f64 {
        let [a, b, c, d, e] = self.coefficients;
        a * u * u + b * u * w + c * w * w + d * u + e * w
    }

    /// The point of the graph above or below `x` along [`Self::axis`]
    /// (same in-plane coordinates): `x` moved onto the patch.
    pub fn project(&self, x: Vec3) -> Vec3 {
        let r = x - self.origin;
        let (u, w) = (r.dot(self.u_axis), r.dot(self.w_axis));
        self.origin + u * self.u_axis + w * self.w_axis + self.height(u, w) * self.axis
    }

    /// Unit normal of the graph at the origin, (−d, −e, 1) in the frame.
    pub fn normal(&self) -> Vec3 {
        let [_, _, _, d, e] = self.coefficients;
        (self.axis - d * self.u_axis - e * self.w_axis).normalize_or_zero()
    }

    /// Mean curvature of the graph at the origin (geom's sign convention).
    pub fn mean(&self) -> f64 {
        let [a, b, c, d, e] = self.coefficients;
        let g = 1.0 + d * d + e * e;
        -((1.0 + e * e) * a - d * e * b + (1.0 + d * d) * c) / g.powf(1.5)
    }
}

/// The quadric fit of [`quadric_fit_rings`] as a surface patch: the height
/// function of the second pass, in the frame of the first pass' normal.
/// `None` in the cases listed at [`quadric_fit`].
pub fn quadric_patch_rings(mesh: &SurfaceMesh, v: VertexId, rings: usize) -> Option<QuadricPatch> {
    let p = mesh.positions();
    let x0 = p[v.idx()];
    let mut ring: Vec<u32> = vec![v.0];
    let mut frontier: Vec<u32> = vec![v.0];
    for _ in 0..rings.max(1) {
        let mut next = Vec::new();
        for &a in &frontier {
            for u in mesh.one_ring(VertexId(a)) {
                next.push(u.0);
            }
        }
        next.sort_unstable();
        next.dedup();
        next.retain(|u| ring.binary_search(u).is_err());
        ring.extend_from_slice(&next);
        ring.sort_unstable();
        frontier = next;
    }
    ring.retain(|&u| u != v.0 && p[u as usize] != x0);
    if ring.len() < 5 {
        return None;
    }
    let n0 = super::vertex_normal(mesh, v);
    if n0 == Vec3::ZERO {
        return None;
    }
    let mut n = n0;
    let mut patch = None;
    for _ in 0..2 {
        let bx = n.any_orthonormal_vector();
        let by = n.cross(bx);
        let mut ata = [[0.0f64; 5]; 5];
        let mut atb = [0.0f64; 5];
        let scale = ring
            .iter()
            .map(|&u| (p[u as usize] - x0).length())
            .fold(0.0, f64::max);
        if !(scale > 0.0) {
            return None;
        }
        for &u in &ring {
            let d = (p[u as usize] - x0) / scale;
            let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n));
            let row = [x * x, x * y, y * y, x, y];
            for i in 0..5 {
                for j in 0..5 {
                    ata[i][j] += row[i] * row[j];
                }
                atb[i] += row[i] * z;
            }
        }
        let s = solve5(ata, atb)?;
        // back to unscaled coordinates: second-order terms scale by 1/scale
        let here = QuadricPatch {
            origin: x0,
            u_axis: bx,
            w_axis: by,
            axis: n,
            coefficients: [s[0] / scale, s[1] / scale, s[2] / scale, s[3], s[4]],
        };
        let m = here.normal();
        if m == Vec3::ZERO || !here.mean().is_finite() {
            return None;
        }
        n = m;
        patch = Some(here);
    }
    patch
}

/// Gaussian elimination with partial pivoting; `None` when singular.
fn solve5(mut a: [[f64; 5]; 5], mut b: [f64; 5]) -> Option<[f64; 5]> {
    let norm = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(norm > 0.0) {
        return None;
    }
    for k in 0..5 {
        let piv = (k..5).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if !(a[piv][k].abs() > 1e-12 * norm) {
            return None;
        }
        a.swap(k, piv);
        b.swap(k, piv);
        for i in k + 1..5 {
            let f = a[i][k] / a[k][k];
            for j in k..5 {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; 5];
    for k in (0..5).rev() {
        let s: f64 = (k + 1..5).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn quadric_fit_is_accurate_at_the_boundary_of_a_sphere_cap() {
        // boundary vertices see half a fan; the fitted normal stays radial
        // and H ≈ 1/r where the fan-weighted normal is tilted by O(h)
        let r = 2.0;
        let cap = shapes::height_field(21, 21, (-0.8, 0.8), (-0.8, 0.8), |x, y| {
            (r * r - x * x - y * y).sqrt()
        });
        let mut worst_n: f64 = 0.0;
        let mut worst_h: f64 = 0.0;
        let mut worst_fan: f64 = 0.0;
        let fan = crate::geom::vertex_normals(&cap);
        for v in cap.vertices().filter(|v| cap.is_boundary_vertex(*v)) {
            let f = quadric_fit(&cap, v).expect("fit");
            let radial = cap.position(v).normalize();
            worst_n = worst_n.max(f.normal.angle_between(radial));
            worst_h = worst_h.max((f.mean - 1.0 / r).abs() * r);
            worst_fan = worst_fan.max(fan[v.idx()].angle_between(radial));
        }
        assert!(worst_n < 2e-3, "normal error {worst_n}");
        assert!(worst_h < 0.05, "relative H error {worst_h}");
        assert!(
            worst_fan > 10.0 * worst_n,
            "fan {worst_fan} vs fit {worst_n}"
        );
        // a plane: exact
        let pl = shapes::quad_grid(6, 6, (0.0, 1.0), (0.0, 1.0), |x, y| 0.3 * x - 0.2 * y);
        let f = quadric_fit(&pl, VertexId(0)).expect("fit");
        assert!(f.mean.abs() < 1e-12);
        assert!((f.normal - Vec3::new(-0.3, 0.2, 1.0).normalize()).length() < 1e-12);
    }
}
