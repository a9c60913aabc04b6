//! Boundary vertices that slide along the boundary polyline of the input.
//!
//! Ji et al. fix the boundary ("For surfaces with boundaries, one needs to
//! fix mesh vertices on the boundaries and only subject other internal
//! vertices on optimization", §6). A fixed boundary vertex pins the end of
//! every feature that runs into it, so, with a projection
//! ([`super::Projection::Smooth`] or [`super::Projection::Mesh`]), a
//! boundary vertex is an unknown that may move *along* the input boundary
//! polyline only — the boundary of the output lies on that of the input
//! (to rounding), as with the paper's fixed boundary:
//!
//! 1. **Corners stay.** A boundary vertex where the boundary polyline turns
//!    by more than [`super::FEATURE_ANGLE_DEG`] is a corner of the
//!    boundary curve and stays fixed (sliding past it would cut the corner).
//! 2. **The rows of Eq. (20) of a boundary vertex** (module `system`): one
//!    F_em row along the boundary tangent t (the tangential component of the
//!    edge-energy gradient along the only direction the vertex may move);
//!    the F_sd rows of the Pottmann–Hofer squared distance to a *curve*
//!    (the curve's counterpart of Eq. (6)): weight d|κ| / (1 + d|κ|) along t
//!    with κ the curvature of the boundary polyline (turning angle over the
//!    mean length of the two edges) and weight 1 along the two directions
//!    normal to the curve (the surface normal and the conormal n × t); and
//!    the F_smo rows of the Laplacian along the boundary, v − ½ (v_prev +
//!    v_next), which evens out the spacing along the curve without pulling
//!    the boundary inward.
//! 3. **Projection onto the boundary polyline** after each solve and after
//!    each halving of a step by the repair of flipped triangles: the nearest
//!    point of the input boundary polyline within
//!    [`super::surface::SEARCH_RINGS`] edges along the loop from the vertex
//!    (not past a corner). Every projection mode does the same: a smooth
//!    fit of the curve (the Phong lift the interior gets) would leave the
//!    input's boundary by up to 1e-3 of the bounding-box diagonal on a range
//!    scan, where the boundary is where the scan ends, not a sampled curve.

use super::crease::FEATURE_ANGLE_DEG;
use super::surface::SEARCH_RINGS;
use crate::Vec3;
use crate::mesh::{SurfaceMesh, boundary_loops};
use rayon::prelude::*;

const NONE: u32 = u32::MAX;

/// The boundary curves of the input mesh (normalised positions) as the
/// vertex flow sees them (module documentation).
pub(super) struct BoundaryCurves {
    /// Previous and next vertex along the boundary loop of each vertex
    /// (`NONE` off the boundary).
    prev: Vec<u32>,
    next: Vec<u32>,
    /// Boundary vertices that stay: corners of the curve, vertices met
    /// twice by the boundary loops, vertices of loops shorter than four
    /// edges or next to degenerate edges.
    corner: Vec<bool>,
    /// Turning angle of the boundary polyline at each boundary vertex
    /// (radians).
    turn: Vec<f64>,
    /// The boundary vertices' positions (the input, normalised).
    positions: Vec<Vec3>,
}

/// Angle between two vectors (radians); π for a zero vector.
fn angle(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.normalize_or_zero(), b.normalize_or_zero());
    if a == Vec3::ZERO || b == Vec3::ZERO {
        return std::f64::consts::PI;
    }
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// The point of the segment (a, b) nearest to x.
fn nearest_on_segment(x: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let e = b - a;
    let l2 = e.length_squared();
    let s = if l2 > 0.0 {
        ((x - a).dot(e) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + s * e
}

impl BoundaryCurves {
    /// The boundary loops of `mesh` at the normalised input `positions`.
    pub fn new(mesh: &SurfaceMesh, positions: &[Vec3]) -> BoundaryCurves {
        let loops = boundary_loops(mesh);
        if loops.is_empty() {
            // a closed mesh: nothing to store
            return BoundaryCurves {
                prev: Vec::new(),
                next: Vec::new(),
                corner: Vec::new(),
                turn: Vec::new(),
                positions: Vec::new(),
            };
        }
        let n = mesh.vertex_count();
        let (mut prev, mut next) = (vec![NONE; n], vec![NONE; n]);
        let mut corner = vec![false; n];
        for lp in loops {
            for &h in &lp {
                let (a, b) = (mesh.from_vertex(h).idx(), mesh.to_vertex(h).idx());
                if next[a] != NONE || prev[b] != NONE || lp.len() < 4 {
                    corner[a] = true;
                    corner[b] = true;
                }
                next[a] = b as u32;
                prev[b] = a as u32;
            }
        }
        let on = |v: usize| next[v] != NONE && prev[v] != NONE;
        let turn: Vec<f64> = (0..n)
            .map(|v| {
                if !on(v) {
                    return 0.0;
                }
                let p = positions[v];
                angle(
                    p - positions[prev[v] as usize],
                    positions[next[v] as usize] - p,
                )
            })
            .collect();
        let feature = FEATURE_ANGLE_DEG.to_radians();
        for v in 0..n {
            if !on(v) {
                continue;
            }
            let degenerate = positions[v] == positions[prev[v] as usize]
                || positions[v] == positions[next[v] as usize];
            if degenerate || turn[v] > feature {
                corner[v] = true;
            }
        }
        BoundaryCurves {
            prev,
            next,
            corner,
            turn,
            positions: positions.to_vec(),
        }
    }

    /// Whether `v` lies on a boundary loop.
    pub fn is_on(&self, v: usize) -> bool {
        self.next.get(v).is_some_and(|&w| w != NONE) && self.prev[v] != NONE
    }

    /// Whether the boundary vertex `v` stays (a corner of the curve).
    pub fn is_corner(&self, v: usize) -> bool {
        self.corner.get(v).copied().unwrap_or(false)
    }

    /// The previous and next vertex of boundary vertex `v` along its loop.
    pub fn neighbours(&self, v: usize) -> (u32, u32) {
        (self.prev[v], self.next[v])
    }

    /// The direction of the boundary at vertex `v` (unit; from the previous
    /// to the next vertex) and the curvature of the polyline there (turning
    /// angle over the mean length of its two edges, normalised units).
    pub fn tangent_and_curvature(&self, v: usize) -> (Vec3, f64) {
        let (a, b) = (
            self.positions[self.prev[v] as usize],
            self.positions[self.next[v] as usize],
        );
        let p = self.positions[v];
        let length = 0.5 * (p.distance(a) + p.distance(b));
        let curvature = if length > 0.0 {
            self.turn[v] / length
        } else {
            0.0
        };
        ((b - a).normalize_or_zero(), curvature)
    }

    /// The point of the input boundary polyline nearest to `x` among the
    /// edges within [`SEARCH_RINGS`] edges along the loop from boundary
    /// vertex `v` (not past a corner); `x` when `x` is not finite.
    pub fn nearest(&self, v: usize, x: Vec3) -> Vec3 {
        let mut best = (x, f64::INFINITY);
        let mut consider = |a: usize| {
            let b = self.next[a] as usize;
            let q = nearest_on_segment(x, self.positions[a], self.positions[b]);
            let d = x.distance(q);
            if d < best.1 {
                best = (q, d);
            }
        };
        // backward: the edges ending at v, its predecessor, ...
        let mut w = v;
        for _ in 0..SEARCH_RINGS {
            let p = self.prev[w] as usize;
            consider(p);
            if self.corner[p] || p == v {
                break;
            }
            w = p;
        }
        let mut w = v;
        for _ in 0..SEARCH_RINGS {
            consider(w);
            let n = self.next[w] as usize;
            if self.corner[n] || n == v {
                break;
            }
            w = n;
        }
        if best.0.is_finite() { best.0 } else { x }
    }

    /// Moves each boundary vertex of `vertices` from its solved position in
    /// `positions` onto the input boundary polyline near its input position
    /// (module documentation, step 4).
    pub fn project(&self, vertices: &[u32], positions: &mut [Vec3]) {
        let moved: Vec<Vec3> = vertices
            .par_iter()
            .map(|&v| self.nearest(v as usize, positions[v as usize]))
            .collect();
        for (&v, q) in vertices.iter().zip(moved) {
            positions[v as usize] = q;
        }
    }
}
