//! The G¹ boundary condition: the normals of the constrained vertices,
//! given or estimated from the boundary curve's tangents.

use super::SchneiderKobbeltOptions;
use crate::Vec3;
use crate::geom;
use crate::mesh::{SurfaceMesh, VertexId};
use crate::smooth::{Role, SmoothError};

/// G¹ normals of the constrained vertices: given in `opts.normals`, else a
/// quadric fit over the input's `normal_fit_rings` rings (a boundary vertex
/// sees only half a fan, which tilts fan normals by O(h)), else the vertex
/// normal; an estimated normal of a boundary vertex is then made
/// perpendicular to the boundary curve ([`perpendicular_to_boundary`]).
/// The fit's error along the curve is not noise the fairing can average
/// out: with the boundary positions fixed it contradicts them, and the
/// Moreton–Séquin estimate of H at the boundary (Eq. (28)), the Dirichlet
/// data of H̃, then bends the first rings to honour it — on noisy sphere
/// caps the largest error sat there, most at the patch corners
/// (BENCHMARKS.md). Free vertices get their vertex normal
/// (replaced every iteration).
pub(super) fn g1_normals(
    mesh: &SurfaceMesh,
    roles: &[Role],
    opts: &SchneiderKobbeltOptions,
    ebar: f64,
) -> Result<Vec<Vec3>, SmoothError> {
    let n = mesh.vertex_count();
    let fit_rings = opts.normal_fit_rings.unwrap_or_else(|| {
        let (lo, hi) = mesh.positions().iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let rings = 0.15 * (hi - lo).length() / ebar;
        if rings.is_finite() {
            (rings.ceil() as usize).clamp(2, 12)
        } else {
            2
        }
    });
    let mut normals0 = geom::vertex_normals_max(mesh);
    for i in 0..n {
        let v = VertexId(i as u32);
        if roles[i] != Role::Free
            && mesh.is_boundary_vertex(v)
            && let Some(f) = geom::quadric_fit_rings(mesh, v, fit_rings)
        {
            normals0[i] = f.normal;
        }
    }
    for (i, tangents) in boundary_tangents(mesh) {
        if roles[i] != Role::Free {
            normals0[i] = perpendicular_to_boundary(normals0[i], tangents);
        }
    }
    for &(v, nv) in &opts.normals {
        let i = v.idx();
        if i >= n {
            return Err(SmoothError::InvalidOption(format!(
                "normal given for vertex {i}, the mesh has {n}"
            )));
        }
        let l = nv.length();
        if !(l > 0.0) || !l.is_finite() {
            return Err(SmoothError::InvalidOption(format!(
                "normal of vertex {i} is zero or not finite"
            )));
        }
        normals0[i] = nv / l;
    }
    Ok(normals0)
}

/// Tangents of the boundary curve at a boundary vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum BoundaryTangents {
    /// A smooth point: the tangent of the parabola through the vertex and
    /// its two neighbours along the boundary.
    Smooth(Vec3),
    /// A kink (the one-sided tangents differ by more than
    /// [`KINK_ANGLE_DEG`]): the incoming and the outgoing one-sided tangents.
    Kink(Vec3, Vec3),
}

/// Angle between the one-sided tangents of the boundary curve above which a
/// boundary vertex is a kink (a corner of the patch) rather than a smooth
/// point of the curve.
pub(super) const KINK_ANGLE_DEG: f64 = 30.0;

/// Derivative at `x` (chord parameter 0) of the parabola through `x`, `a`
/// (at distance h1 along the curve) and `b` (h2 beyond `a`); second order
/// for any spacing. `None` when two points coincide.
pub(super) fn one_sided_tangent(x: Vec3, a: Vec3, b: Vec3) -> Option<Vec3> {
    let (h1, h2) = (x.distance(a), a.distance(b));
    if !(h1 > 0.0 && h2 > 0.0) {
        return None;
    }
    let t = -(2.0 * h1 + h2) / (h1 * (h1 + h2)) * x + (h1 + h2) / (h1 * h2) * a
        - h1 / (h2 * (h1 + h2)) * b;
    let t = t.normalize_or_zero();
    (t != Vec3::ZERO && t.is_finite()).then_some(t)
}

/// The tangents of the boundary curves at their vertices (vertex index,
/// tangents), from the boundary polylines: at a smooth point the tangent of
/// the parabola through the previous, the vertex and the next point
/// (chord-length parameter; second order for any spacing), at a kink both
/// one-sided parabola tangents. Loops of fewer than five vertices and
/// coincident points give nothing.
pub(super) fn boundary_tangents(mesh: &SurfaceMesh) -> Vec<(usize, BoundaryTangents)> {
    let mut out = Vec::new();
    for lp in crate::mesh::boundary_loops(mesh) {
        let k = lp.len();
        if k < 5 {
            continue;
        }
        // the loop's vertices in order: vertex j is where half-edge j starts
        let p: Vec<Vec3> = lp
            .iter()
            .map(|h| mesh.position(mesh.from_vertex(*h)))
            .collect();
        for j in 0..k {
            let at = |d: isize| p[(j as isize + d).rem_euclid(k as isize) as usize];
            let (x, prev, next) = (at(0), at(-1), at(1));
            let (Some(back), Some(ahead)) = (
                one_sided_tangent(x, prev, at(-2)),
                one_sided_tangent(x, next, at(2)),
            ) else {
                continue;
            };
            // back points backwards along the curve, ahead forwards
            let turn = (-back).angle_between(ahead);
            let tangents = if turn.to_degrees() > KINK_ANGLE_DEG {
                BoundaryTangents::Kink(-back, ahead)
            } else {
                let (h1, h2) = (x.distance(prev), x.distance(next));
                // derivative at x of the parabola through prev, x, next
                let t = (h2 * h2 * (x - prev) + h1 * h1 * (next - x)) / (h1 * h2 * (h1 + h2));
                let t = t.normalize_or_zero();
                if t == Vec3::ZERO || !t.is_finite() {
                    continue;
                }
                BoundaryTangents::Smooth(t)
            };
            out.push((mesh.from_vertex(lp[j]).idx(), tangents));
        }
    }
    out
}

/// The unit vector nearest to the estimated normal `n` that is
/// perpendicular to the boundary curve: a surface through the boundary
/// curve has its normal perpendicular to the curve's tangent (at a kink, to
/// both one-sided tangents), so G¹ data with a component along the curve
/// contradict the fixed boundary positions. `n` where the projection
/// vanishes.
pub(super) fn perpendicular_to_boundary(n: Vec3, tangents: BoundaryTangents) -> Vec3 {
    let m = match tangents {
        BoundaryTangents::Smooth(t) => n - n.dot(t) * t,
        BoundaryTangents::Kink(a, b) => {
            let c = a.cross(b).normalize_or_zero();
            c * c.dot(n).signum()
        }
    };
    let m = m.normalize_or_zero();
    if m == Vec3::ZERO || !m.is_finite() {
        n
    } else {
        m
    }
}
