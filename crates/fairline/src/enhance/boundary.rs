//! Boundary vertices that slide along the boundary curve of the input.
//!
//! Ji et al. fix the boundary ("For surfaces with boundaries, one needs to
//! fix mesh vertices on the boundaries and only subject other internal
//! vertices on optimization", §6). A fixed
//! boundary vertex pins the end of every feature that runs into it: where a crease
//! meets the boundary, the boundary edge across it keeps the input's chord
//! error and the rows of vertices next to it cannot reach the crease. So,
//! with a projection ([`super::Projection::Smooth`] or
//! [`super::Projection::Mesh`]), a boundary vertex is an unknown that may
//! move *along* the boundary curve only:
//!
//! 1. **Corners stay.** A boundary vertex where the boundary polyline turns
//!    by more than [`super::FEATURE_ANGLE_DEG`] is a corner of the
//!    boundary curve and stays fixed, unless one of its two boundary edges
//!    is a chord across a corner (step 2): then the corner of the curve is
//!    not a vertex of the input, and the vertex may slide toward it.
//! 2. **Chords across corners** (the one-dimensional counterpart of the
//!    chord strips of module `crease`): a boundary edge a → b whose two
//!    ends both turn the same way by more than
//!    [`super::FEATURE_ANGLE_DEG`], while the boundary is straight (within
//!    [`super::FLAT_SIDE_DEG`]) or turns the other way (another feature) at
//!    the vertices before a and after b, cuts a corner of the curve; the
//!    corner
//!    is rebuilt where the lines of the edges before a and after b meet (the
//!    boundary section of the crease that module `crease` rebuilds inside).
//! 3. **The rows of Eq. (20) of a boundary vertex** (module `system`): one
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
//! 4. **Projection onto the boundary curve** after each solve: the nearest
//!    point of the boundary polyline within [`super::surface::SEARCH_RINGS`]
//!    edges along the loop from the vertex (not past a corner), lifted onto
//!    the curve's Phong fit for [`super::Projection::Smooth`] — the Phong
//!    tessellation of Boubekeur & Alexa 2008 in one dimension: on the edge
//!    (a, b) at p = (1 − s) a + s b, p* = (1 − α) p + α ((1 − s) π_a(p) +
//!    s π_b(p)) with π the projection onto the tangent line at an end,
//!    α = ½, which reproduces a quadratic curve to second order — and on a
//!    chord across a corner onto the two segments to the rebuilt corner,
//!    onto the corner itself within [`super::SNAP_DISTANCE`] of the chord's
//!    length. Straight boundary parts stay straight (the tangent at a vertex
//!    of a straight part is its edges' direction, the lift vanishes).

use super::crease::{FEATURE_ANGLE_DEG, FLAT_SIDE_DEG, SNAP_DISTANCE};
use super::surface::{PHONG_ALPHA, SEARCH_RINGS};
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
    /// For the boundary edge from vertex a to `next[a]`: the corner of the
    /// curve that edge cuts (step 2 of the module documentation).
    chord_corner: Vec<Option<Vec3>>,
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

/// The point of the segment (a, b) nearest to x and its parameter s.
fn nearest_on_segment(x: Vec3, a: Vec3, b: Vec3) -> (Vec3, f64) {
    let e = b - a;
    let l2 = e.length_squared();
    let s = if l2 > 0.0 {
        ((x - a).dot(e) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + s * e, s)
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
                chord_corner: Vec::new(),
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
        // the axis each vertex turns about (its sign tells the way it turns)
        let axis: Vec<Vec3> = (0..n)
            .map(|v| {
                if !on(v) {
                    return Vec3::ZERO;
                }
                let p = positions[v];
                (p - positions[prev[v] as usize]).cross(positions[next[v] as usize] - p)
            })
            .collect();
        let (feature, flat) = (FEATURE_ANGLE_DEG.to_radians(), FLAT_SIDE_DEG.to_radians());
        let chord_corner: Vec<Option<Vec3>> = (0..n)
            .map(|a| {
                if !on(a) || corner[a] {
                    return None;
                }
                let b = next[a] as usize;
                let (before, after) = (prev[a] as usize, next[b] as usize);
                // both ends turn, the same way
                if corner[b] || turn[a] <= feature || turn[b] <= feature {
                    return None;
                }
                if !(axis[a].dot(axis[b]) > 0.0) || before == b || after == a {
                    return None;
                }
                // the curve is straight before a and after b, or turns the
                // other way there (another feature): not a sampled arc
                let apart = |u: usize, w: usize| turn[u] < flat || axis[u].dot(axis[w]) < 0.0;
                if !apart(before, a) || !apart(after, b) {
                    return None;
                }
                rebuilt_corner(
                    positions[before],
                    positions[a],
                    positions[b],
                    positions[after],
                )
            })
            .collect();
        for v in 0..n {
            if !on(v) {
                continue;
            }
            let p = prev[v] as usize;
            let degenerate =
                positions[v] == positions[p] || positions[v] == positions[next[v] as usize];
            let at_chord = chord_corner[v].is_some() || chord_corner[p].is_some();
            if degenerate || (turn[v] > feature && !at_chord) {
                corner[v] = true;
            }
        }
        BoundaryCurves {
            prev,
            next,
            corner,
            turn,
            chord_corner,
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

    /// The tangent of the boundary curve at vertex `v` used by the Phong lift
    /// of its edge towards `other`: the edge's own direction where the curve
    /// has a corner at `v` (a corner vertex, an end of a chord across a
    /// corner, a turn above the feature angle), else the direction from the
    /// previous to the next vertex.
    fn lift_tangent(&self, v: usize, other: usize) -> Vec3 {
        let own = (self.positions[other] - self.positions[v]).normalize_or_zero();
        let p = self.prev[v] as usize;
        let sharp = self.corner[v]
            || self.chord_corner[v].is_some()
            || self.chord_corner[p].is_some()
            || self.turn[v] > FEATURE_ANGLE_DEG.to_radians();
        if sharp {
            return own;
        }
        let t = (self.positions[self.next[v] as usize] - self.positions[p]).normalize_or_zero();
        if t == Vec3::ZERO { own } else { t }
    }

    /// The point of the boundary curve over the edge from `a` to its next
    /// vertex nearest to `x`, and its distance to `x` (before the lift):
    /// on the polyline for `smooth` false, else on the rebuilt corner or the
    /// curve's Phong fit (module documentation, step 4).
    fn edge_point(&self, a: usize, x: Vec3, smooth: bool) -> (Vec3, f64) {
        let b = self.next[a] as usize;
        let (pa, pb) = (self.positions[a], self.positions[b]);
        if smooth && let Some(c) = self.chord_corner[a] {
            let (q1, _) = nearest_on_segment(x, pa, c);
            let (q2, _) = nearest_on_segment(x, c, pb);
            let q = if x.distance(q1) <= x.distance(q2) {
                q1
            } else {
                q2
            };
            let q = if q.distance(c) <= SNAP_DISTANCE * pa.distance(pb) {
                c
            } else {
                q
            };
            return (q, x.distance(q));
        }
        let (p, s) = nearest_on_segment(x, pa, pb);
        let d = x.distance(p);
        if !smooth {
            return (p, d);
        }
        let (ta, tb) = (self.lift_tangent(a, b), self.lift_tangent(b, a));
        let on_line = |q: Vec3, t: Vec3| q + (p - q).dot(t) * t;
        let lifted = (1.0 - PHONG_ALPHA) * p
            + PHONG_ALPHA * ((1.0 - s) * on_line(pa, ta) + s * on_line(pb, tb));
        (if lifted.is_finite() { lifted } else { p }, d)
    }

    /// Moves each boundary vertex of `vertices` from its solved position in
    /// `positions` onto the boundary curve near its input position (module
    /// documentation, step 4; `smooth` false: onto the polyline).
    pub fn project(&self, vertices: &[u32], positions: &mut [Vec3], smooth: bool) {
        let moved: Vec<Vec3> = vertices
            .par_iter()
            .map(|&v| {
                let x = positions[v as usize];
                let mut best = (x, f64::INFINITY);
                let mut consider = |a: usize| {
                    let (q, d) = self.edge_point(a, x, smooth);
                    if d < best.1 {
                        best = (q, d);
                    }
                };
                // backward: the edges ending at v, its predecessor, ...
                let mut w = v as usize;
                for _ in 0..SEARCH_RINGS {
                    let p = self.prev[w] as usize;
                    consider(p);
                    if self.corner[p] || p == v as usize {
                        break;
                    }
                    w = p;
                }
                let mut w = v as usize;
                for _ in 0..SEARCH_RINGS {
                    consider(w);
                    let n = self.next[w] as usize;
                    if self.corner[n] || n == v as usize {
                        break;
                    }
                    w = n;
                }
                if best.0.is_finite() { best.0 } else { x }
            })
            .collect();
        for (&v, q) in vertices.iter().zip(moved) {
            positions[v as usize] = q;
        }
    }
}

/// The corner that a chord a → b cuts: where the line through `before`
/// and a meets the line through b and `after` (the midpoint of their
/// closest points), provided it lies ahead of a on the first line, behind b
/// on the second, within two chord lengths, and the lines nearly meet
/// (closer than a tenth of the chord).
fn rebuilt_corner(before: Vec3, a: Vec3, b: Vec3, after: Vec3) -> Option<Vec3> {
    let (u, w) = (
        (a - before).normalize_or_zero(),
        (after - b).normalize_or_zero(),
    );
    let chord = a.distance(b);
    if u == Vec3::ZERO || w == Vec3::ZERO || !(chord > 0.0) {
        return None;
    }
    // a + s u closest to b + r w
    let c = u.dot(w);
    let denominator = 1.0 - c * c;
    if !(denominator > 1e-9) {
        return None;
    }
    let d = a - b;
    let (du, dw) = (d.dot(u), d.dot(w));
    let s = (c * dw - du) / denominator;
    let r = (dw - c * du) / denominator;
    let (p, q) = (a + s * u, b + r * w);
    let ahead = s > 0.0 && s <= 2.0 * chord && r < 0.0 && -r <= 2.0 * chord;
    (ahead && p.distance(q) <= 0.1 * chord).then_some(0.5 * (p + q))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chord across a right-angled corner of a boundary is rebuilt at the
    /// corner; the vertices next to it may slide, a vertex on a real corner
    /// stays.
    #[test]
    fn chords_across_boundary_corners_are_rebuilt() {
        let c = rebuilt_corner(
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::new(-0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        )
        .unwrap();
        assert!(c.distance(Vec3::ZERO) < 1e-12, "{c}");
        // lines that meet behind the chord (a concave notch seen the wrong
        // way) give no corner
        assert!(
            rebuilt_corner(
                Vec3::new(-2.0, 0.0, 0.0),
                Vec3::new(-0.5, 0.0, 0.0),
                Vec3::new(0.0, -0.5, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
            )
            .is_none()
        );
    }
}
