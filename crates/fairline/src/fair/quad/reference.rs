//! The input surface of structure-line fairing as a smooth reference: the
//! points slide along it instead of leaving it.
//!
//! The input quad mesh is only a sampling of the surface the user means; its
//! flat faces lie inside a convex surface by about κh²/8, which is as large
//! as the deviations the fairing should avoid. The reference is therefore a
//! blend of local quadric fits ([`geom::quadric_patch_rings`], the height
//! function z = a u² + b uw + c w² + d u + e w over the two-ring of every
//! input vertex, interpolating the vertex): a point near input vertex v is
//! moved onto each fit of v and of its one-ring along that fit's axis, and
//! the results are averaged with Gaussian weights exp(−|x − p_j|²/σ²),
//! σ = ½ × the mean length of the edges at v. Each fit approximates the
//! surface to the third order in the distance, and the weights vary
//! smoothly, so the projection adds no kinks of its own.

use crate::Vec3;
use crate::geom::{self, QuadricPatch};
use crate::mesh::{SurfaceMesh, VertexId};
use std::sync::OnceLock;

/// Rings of the quadric fits (two: the smallest ring with more than five
/// neighbours around a regular quad vertex, so the fit follows the
/// surface's own curvature as closely as the sampling allows).
const FIT_RINGS: usize = 2;

/// Largest number of steps of the walk to the nearest input vertex.
const WALK_STEPS: usize = 64;

/// The input surface, fitted lazily (only around the points that move).
pub(super) struct ReferenceSurface<'a> {
    input: &'a SurfaceMesh,
    patches: Vec<OnceLock<Option<QuadricPatch>>>,
}

impl<'a> ReferenceSurface<'a> {
    pub(super) fn new(input: &'a SurfaceMesh) -> Self {
        ReferenceSurface {
            input,
            patches: (0..input.vertex_count()).map(|_| OnceLock::new()).collect(),
        }
    }

    fn patch(&self, v: usize) -> Option<&QuadricPatch> {
        self.patches[v]
            .get_or_init(|| geom::quadric_patch_rings(self.input, VertexId(v as u32), FIT_RINGS))
            .as_ref()
    }

    /// The input vertex nearest to `x`, by a greedy walk over the input
    /// connectivity from `start` (points move by a fraction of an edge per
    /// iteration, so the walk takes a step or two).
    fn nearest(&self, start: usize, x: Vec3) -> usize {
        let p = self.input.positions();
        let mut best = start;
        let mut d = p[best].distance_squared(x);
        for _ in 0..WALK_STEPS {
            let mut moved = false;
            for u in self.input.one_ring(VertexId(best as u32)) {
                let du = p[u.idx()].distance_squared(x);
                if du < d {
                    (best, d) = (u.idx(), du);
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        best
    }

    /// `x` moved onto the reference surface near input vertex `start` (the
    /// blend described in the module documentation); `x` itself where no
    /// fit exists (fewer than five distinct neighbours, degenerate faces).
    pub(super) fn project(&self, start: usize, x: Vec3) -> Vec3 {
        let p = self.input.positions();
        let v = self.nearest(start, x);
        let ring: Vec<usize> = std::iter::once(v)
            .chain(self.input.one_ring(VertexId(v as u32)).map(|u| u.idx()))
            .collect();
        let spacing = ring[1..].iter().map(|&u| p[u].distance(p[v])).sum::<f64>()
            / (ring.len() - 1).max(1) as f64;
        let sigma2 = (0.5 * spacing).powi(2);
        if !(sigma2 > 0.0) {
            return x;
        }
        // weights relative to the nearest vertex's, so that they cannot all
        // underflow however far x is
        let d0 = p[v].distance_squared(x);
        let mut sum = Vec3::ZERO;
        let mut total = 0.0;
        for &u in &ring {
            if let Some(patch) = self.patch(u) {
                let w = (-(p[u].distance_squared(x) - d0) / sigma2).exp();
                let q = patch.project(x);
                if w > 0.0 && q.is_finite() {
                    sum += w * q;
                    total += w;
                }
            }
        }
        if total > 0.0 { sum / total } else { x }
    }
}
