//! Sharp creases that the input under-samples, and the surface the vertex
//! flow puts its vertices on there.
//!
//! A coarse mesh sampled without regard to a sharp crease cuts it by a
//! strip of *chord* faces: their vertices lie on the two sides, the faces
//! themselves on neither, and the crease lies outside (convex) or inside
//! (concave) the strip. A smooth fit through the strip (the Phong patch of
//! [`super::surface`]) rounds the crease, so a vertex that flows toward it
//! cannot reach it. Here the crease is rebuilt from the sides instead:
//!
//! 1. **Bent edges**: interior input edges whose two faces' normals
//!    differ by more than [`FLAT_SIDE_DEG`] (the bound within which a side
//!    counts as flat, step 3); a vertex on one is a *feature vertex*.
//! 2. **Patches**: the faces joined across the other edges (union–find).
//!    A patch every vertex of which is a feature vertex — it has no vertex
//!    inside it, a strip at most one face wide — is a *chord strip*; every
//!    other patch is a *side*, and so is a flat strip one face wide
//!    between a concave and a convex crease (the fandisk-like part's 45°
//!    slope): a chord strip that touches no side and whose concave and
//!    convex borders lie apart ([`strips_between_creases`]); its plane is
//!    its own. The crease is judged by the sides, not by
//!    the chord's turning (step 3): a chord that cuts a crease unevenly
//!    turns by most of its dihedral angle at one edge and by little at the
//!    other (the fandisk-like part's 45° convex crease: 36° and 9°), so a
//!    threshold on the faces' turning at each edge alone misses it.
//! 3. **Chord faces**: a face of a chord strip each of whose corners
//!    touches a side. At each corner, each side touching it gives a plane
//!    through the corner, normal to the area-weighted mean normal of that
//!    side's faces at the corner — the tangent plane of that side there —
//!    provided the side is flat near the corner: its faces within two rings
//!    turn by less than [`FLAT_SIDE_DEG`] from that normal. Where a corner
//!    touches no side, or a side that bends (a rounded feature sampled by
//!    two or more strips: the neighbouring strips are strips too, or the
//!    flank of the fillet bends away from the plane), the face is no chord
//!    face and keeps the smooth fit: the rounding there is real. The
//!    sides at the face must meet at a clear dihedral angle — two of its
//!    side normals differ by more than [`FEATURE_ANGLE_DEG`] — else the
//!    strip is a gentle bend and keeps the smooth fit.
//! 4. **The crease surface over a chord face**: a point p of the face moves
//!    along the interpolated side normal d onto the nearest of the corner
//!    planes (the smallest |t| with p + t d on a plane). At a convex crease
//!    the chord lies inside every side's half-space and the first plane met
//!    going outward is the surface; at a concave one it lies outside all of
//!    them and the first plane met going inward is the surface; on the edge
//!    a chord face shares with a side, t = 0, so the crease surface meets
//!    the side without a gap. Where the planes disagree about the side the
//!    point is on (t of both signs: a crease that is neither convex nor
//!    concave across the face), where the line runs nearly parallel to a
//!    plane, or where the move would exceed the face's longest edge, the
//!    face's smooth fit is used.
//! 5. **On the crease**: a point that lands within [`SNAP_DISTANCE`] of the
//!    face's longest edge from the line where its plane meets the plane of
//!    another side (the intersection of the side fits) is put onto that
//!    line, so the vertices that the flow gathers at a crease sit on it and
//!    the mesh's edges between them follow it.
//! 6. **At a corner**: where the planes of a chord face belong to three
//!    sides (a corner of a box, where three creases meet), the surface has
//!    a vertex at the intersection point of the three side fits — the
//!    minimum of the Pottmann–Hofer squared distance (Ji et al. Eq. (6))
//!    to the three planes, which the flow's distance model at a vertex
//!    near it approaches. A chord strip cuts the corner off, and a vertex
//!    projected onto any one chord face lands on at most two of the
//!    planes, so after each projection the free vertex nearest that point
//!    (within the chord face's longest edge) is put onto it
//!    ([`crease_corners`], [`snap_to_corners`]).
//!
//! The feature threshold, 10° between the sides' fits, lies below the
//! dihedral turn of the creases the flow is to sharpen and above the turn
//! per edge of the smooth parts of a mesh that resolves them (a cylinder
//! of radius r with edges of length ℓ turns by ℓ/r, 9° at 40 edges around,
//! about half that across an edge of the triangulation). It is applied to
//! the sides' normals, not to each edge of the chord: a chord that cuts a
//! crease unevenly (the crease nearer one row) turns by most of the
//! dihedral angle at one of its borders and by little at the other, below
//! any per-edge threshold that the smooth parts pass (step 2). A rounded
//! feature that one strip spans (a fillet of radius ≤ the edge length,
//! between flat sides) is rebuilt as a crease: the error is then the
//! fillet's own sag, which the input's chord has too. Faces next to a
//! chord face do not average their corner normals with it
//! ([`super::surface`]), so the sides stay flat up to the crease. On the
//! shapes of `accuracy_tests`: 188 chord faces on the sharp cube and 100
//! on the fandisk-like part (all near a crease; 104 and 25 with the 10°
//! threshold on each edge; 50 before its slope strip counted as a side),
//! none on the rounded cube and the filleted cylinder, whose results are
//! unchanged bit for bit. The fandisk-like part's slope between its
//! concave and its convex crease is one strip of faces wide: as a chord
//! strip it left both chords next to it without a side at one border, so
//! neither crease was rebuilt (normal error near the features 6.74°
//! against the input's 6.51°); as a side, 6.29°. Telling such strips from
//! chords by the sense of their bends alone (a chord bends the
//! same way at both borders), which also took patches of one or two faces
//! on coarsely sampled curved parts (the rounded cube's corners, whose
//! bends change their sense at a vertex) and the cubes' twisted chord
//! strips (which touch sides) for sides (rounded cube Hausdorff +48 %,
//! sharp cube −14 % instead of −59 %); [`strips_between_creases`] adds
//! the two conditions that exclude them.

use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh, VertexId, union_find_join, union_find_root};
use std::collections::HashMap;

/// Sides whose fitted normals differ by more than this angle (in degrees)
/// meet at a crease (module documentation, steps 3, 5 and 6).
pub const FEATURE_ANGLE_DEG: f64 = 10.0;

/// A side is used as a plane at a corner only where its faces within two
/// rings of the corner turn by less than this angle (in degrees) from its
/// mean normal there (module documentation, step 3).
pub const FLAT_SIDE_DEG: f64 = 5.0;

/// The line p + t d is used against a corner plane only where it meets the
/// plane at an angle whose cosine |d · n| is at least this.
const MIN_INCIDENCE: f64 = 0.2;

/// A point of the crease surface closer to the crease line than this share
/// of its face's longest edge is put onto the line (module documentation,
/// step 5).
pub const SNAP_DISTANCE: f64 = 0.25;

/// The tangent planes of the sides at the corners of a chord face: for
/// each corner, the unit normals of the sides touching it (the planes pass
/// through the corner).
#[derive(Clone, Debug, Default)]
pub(super) struct SidePlanes(pub [Vec<Vec3>; 3]);

/// For each face of `mesh` with unit normals and areas `face_normals`, the
/// side planes at its corners if it is a chord face of an under-sampled
/// crease (module documentation, steps 1–3), else `None`.
pub(super) fn chord_faces(
    mesh: &SurfaceMesh,
    face_normals: &[(Vec3, f64)],
) -> Vec<Option<SidePlanes>> {
    let nf = mesh.face_count();
    let cos_split = FLAT_SIDE_DEG.to_radians().cos();
    let cos_feature = FEATURE_ANGLE_DEG.to_radians().cos();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    let mut feature_vertex = vec![false; mesh.vertex_count()];
    for h in mesh.halfedges() {
        let o = mesh.opposite(h);
        // each interior edge once
        if h.0 > o.0 {
            continue;
        }
        let (Some(f1), Some(f2)) = (mesh.face(h), mesh.face(o)) else {
            continue;
        };
        let (n1, n2) = (face_normals[f1.idx()].0, face_normals[f2.idx()].0);
        if n1 == Vec3::ZERO || n2 == Vec3::ZERO {
            continue;
        }
        if n1.dot(n2) < cos_split {
            feature_vertex[mesh.from_vertex(h).idx()] = true;
            feature_vertex[mesh.to_vertex(h).idx()] = true;
        } else {
            union_find_join(&mut parent, f1.0, f2.0);
        }
    }
    let patch: Vec<u32> = (0..nf as u32)
        .map(|f| union_find_root(&mut parent, f))
        .collect();
    let triangles: Vec<[VertexId; 3]> = (0..nf as u32).map(|f| mesh.triangle(FaceId(f))).collect();
    // a patch is a chord strip when none of its vertices is inside it;
    // degenerate faces belong to no side
    let mut strip = vec![true; nf];
    for f in 0..nf {
        if face_normals[f].0 == Vec3::ZERO || triangles[f].iter().any(|v| !feature_vertex[v.idx()])
        {
            strip[patch[f] as usize] = false;
        }
    }
    for root in strips_between_creases(mesh, face_normals, &patch, &strip) {
        strip[root as usize] = false;
    }
    let is_side =
        |g: FaceId| face_normals[g.idx()].0 != Vec3::ZERO && !strip[patch[g.idx()] as usize];
    (0..nf)
        .map(|f| {
            if face_normals[f].0 == Vec3::ZERO || !strip[patch[f] as usize] {
                return None;
            }
            let mut planes = SidePlanes::default();
            for (k, &v) in triangles[f].iter().enumerate() {
                // area-weighted normal sums of the sides around v, by patch
                let mut sides: Vec<(u32, Vec3)> = Vec::new();
                for g in mesh.vertex_faces(v).filter(|&g| is_side(g)) {
                    let (n, area) = face_normals[g.idx()];
                    let id = patch[g.idx()];
                    match sides.iter_mut().find(|s| s.0 == id) {
                        Some(s) => s.1 += area * n,
                        None => sides.push((id, area * n)),
                    }
                }
                for (id, sum) in sides {
                    let n = sum.normalize_or_zero();
                    if n == Vec3::ZERO || !flat_near(mesh, face_normals, &patch, id, v, n) {
                        return None;
                    }
                    planes.0[k].push(n);
                }
                if planes.0[k].is_empty() {
                    return None;
                }
            }
            // the sides' fits must meet at a clear dihedral angle
            let normals: Vec<Vec3> = planes.0.iter().flatten().copied().collect();
            let crease = normals
                .iter()
                .enumerate()
                .any(|(i, a)| normals[i + 1..].iter().any(|b| a.dot(*b) < cos_feature));
            crease.then_some(planes)
        })
        .collect()
}

/// The chord-strip patches (roots in `patch`, flagged in `strip`) that are
/// flat strips one face wide between a concave and a convex crease — a side
/// of its own (module documentation, step 2): a patch that
///
/// - touches no side (no face of a side shares a vertex with it): a chord
///   of one crease has the crease's two sides at its borders, while the
///   fandisk-like part's 45° slope, sampled by one strip between the
///   chords of its two creases, touches only those chords;
/// - bends opposite ways at its borders (the neighbour across one bent
///   edge rises above the patch's plane — concave — and across another
///   falls below it — convex): the faces of a chord, and the middle strip
///   of a fillet sampled by several strips, bend the same way at both
///   borders;
/// - is flat: each of its faces turns by less than [`FLAT_SIDE_DEG`] from
///   its area-weighted mean normal.
///
/// Its plane is then the plane of its own faces, the Pottmann–Hofer
/// tangent plane of the side (Ji et al. Eq. (6)) fitted from the strip
/// itself, and the chords on either side are rebuilt between it and their
/// outer sides (steps 3–5).
fn strips_between_creases(
    mesh: &SurfaceMesh,
    face_normals: &[(Vec3, f64)],
    patch: &[u32],
    strip: &[bool],
) -> Vec<u32> {
    let nf = face_normals.len();
    let in_strip = |f: usize| face_normals[f].0 != Vec3::ZERO && strip[patch[f] as usize];
    let is_side =
        |g: FaceId| face_normals[g.idx()].0 != Vec3::ZERO && !strip[patch[g.idx()] as usize];
    let (mut touches_side, mut concave, mut convex) =
        (vec![false; nf], vec![false; nf], vec![false; nf]);
    let mut mean = vec![Vec3::ZERO; nf];
    for f in (0..nf).filter(|&f| in_strip(f)) {
        let root = patch[f] as usize;
        mean[root] += face_normals[f].1 * face_normals[f].0;
        let touches = mesh
            .triangle(FaceId(f as u32))
            .iter()
            .any(|&v| mesh.vertex_faces(v).any(is_side));
        touches_side[root] |= touches;
    }
    // the senses of the bends at each vertex of a strip, per strip:
    // bit 0 concave, bit 1 convex
    let mut senses: HashMap<(u32, u32), u8> = HashMap::new();
    for h in mesh.halfedges() {
        let (Some(f), Some(g)) = (mesh.face(h), mesh.face(mesh.opposite(h))) else {
            continue;
        };
        // faces of different patches meet at a bent edge (step 1)
        if !in_strip(f.idx())
            || patch[f.idx()] == patch[g.idx()]
            || face_normals[g.idx()].0 == Vec3::ZERO
        {
            continue;
        }
        let root = patch[f.idx()] as usize;
        // the mesh's own positions: the sense of a bend is unchanged by the
        // flow's normalisation (a translation and a uniform scaling)
        let from = mesh.positions()[mesh.from_vertex(h).idx()];
        let apex = mesh.positions()[mesh.to_vertex(mesh.next(mesh.opposite(h))).idx()];
        let rise = face_normals[f.idx()].0.dot(apex - from);
        concave[root] |= rise > 0.0;
        convex[root] |= rise < 0.0;
        let sense = if rise > 0.0 {
            1
        } else if rise < 0.0 {
            2
        } else {
            0
        };
        for v in [mesh.from_vertex(h), mesh.to_vertex(h)] {
            *senses.entry((root as u32, v.0)).or_default() |= sense;
        }
    }
    // the concave and the convex border of a strip between two creases do
    // not meet (they are apart, joined by the mesh's boundary or not at
    // all); on a curved surface sampled coarsely, the bends of a patch of
    // one or two faces change their sense at a vertex
    let mut borders_apart = vec![true; nf];
    for (&(root, _), &bits) in &senses {
        if bits == 3 {
            borders_apart[root as usize] = false;
        }
    }
    let cos_flat = FLAT_SIDE_DEG.to_radians().cos();
    let mut flat = vec![true; nf];
    for f in (0..nf).filter(|&f| in_strip(f)) {
        let root = patch[f] as usize;
        let n = mean[root].normalize_or_zero();
        flat[root] &= n != Vec3::ZERO && face_normals[f].0.dot(n) >= cos_flat;
    }
    (0..nf)
        .filter(|&r| in_strip(r) && patch[r] as usize == r)
        .filter(|&r| !touches_side[r] && concave[r] && convex[r] && borders_apart[r] && flat[r])
        .map(|r| r as u32)
        .collect()
}

/// Whether the faces of patch `id` around the one-ring of `v` (its faces
/// within two rings) all turn by less than [`FLAT_SIDE_DEG`] from `n`.
fn flat_near(
    mesh: &SurfaceMesh,
    face_normals: &[(Vec3, f64)],
    patch: &[u32],
    id: u32,
    v: VertexId,
    n: Vec3,
) -> bool {
    let cos_flat = FLAT_SIDE_DEG.to_radians().cos();
    std::iter::once(v).chain(mesh.one_ring(v)).all(|u| {
        mesh.vertex_faces(u)
            .filter(|g| patch[g.idx()] == id)
            .all(|g| face_normals[g.idx()].0.dot(n) >= cos_flat)
    })
}

/// The point of the crease surface over the chord face with corners `t`
/// and side planes `planes` at barycentric coordinates `w` (module
/// documentation, step 4); `None` where the face's smooth fit is to be used.
pub(super) fn crease_point(t: [Vec3; 3], planes: &SidePlanes, w: [f64; 3]) -> Option<Vec3> {
    let p = w[0] * t[0] + w[1] * t[1] + w[2] * t[2];
    let mut d = Vec3::ZERO;
    for k in 0..3 {
        let corner: Vec3 = planes.0[k].iter().copied().sum();
        d += w[k] * corner.normalize_or_zero();
    }
    let d = d.normalize_or_zero();
    if d == Vec3::ZERO {
        return None;
    }
    let reach = (0..3)
        .map(|k| t[k].distance(t[(k + 1) % 3]))
        .fold(0.0, f64::max);
    let (mut nearest, mut below, mut above) = (f64::INFINITY, false, false);
    let mut plane = (Vec3::ZERO, Vec3::ZERO);
    for k in 0..3 {
        for &n in &planes.0[k] {
            let incidence = d.dot(n);
            if incidence.abs() < MIN_INCIDENCE {
                continue;
            }
            let s = (t[k] - p).dot(n) / incidence;
            // a point on the plane (to rounding) is on both of its sides
            let tiny = 1e-12 * reach;
            below |= s > tiny;
            above |= s < -tiny;
            if s.abs() < nearest.abs() {
                nearest = s;
                plane = (t[k], n);
            }
        }
    }
    if (below && above) || !(nearest.abs() <= reach) {
        return None;
    }
    let q = p + nearest * d;
    let q = snap_to_crease(q, plane, t, planes, SNAP_DISTANCE * reach);
    q.is_finite().then_some(q)
}

/// `q` (on the plane `on` = (point, unit normal)) moved onto the line where
/// that plane meets the nearest other corner plane of a different side
/// (their normals apart by more than [`FEATURE_ANGLE_DEG`]), when that line
/// is within `radius` of `q`; else `q`.
fn snap_to_crease(
    q: Vec3,
    on: (Vec3, Vec3),
    t: [Vec3; 3],
    planes: &SidePlanes,
    radius: f64,
) -> Vec3 {
    let cos_feature = FEATURE_ANGLE_DEG.to_radians().cos();
    let n_a = on.1;
    let mut best: Option<(f64, Vec3)> = None;
    for k in 0..3 {
        for &n_b in &planes.0[k] {
            let c = n_a.dot(n_b);
            if c >= cos_feature {
                continue;
            }
            // the point of the line {x·n_a = q·n_a, (x − t_k)·n_b = 0}
            // nearest to q: q − β (n_b − c n_a) / (1 − c²) with β the
            // distance of q from the plane b (q is on plane a)
            let beta = (q - t[k]).dot(n_b);
            let sine2 = 1.0 - c * c;
            if !(sine2 > 1e-12) {
                continue;
            }
            let shift = -beta * (n_b - c * n_a) / sine2;
            let distance = shift.length();
            if distance <= radius && best.is_none_or(|b| distance < b.0) {
                best = Some((distance, q + shift));
            }
        }
    }
    best.map_or(q, |b| b.1)
}

/// A point where three sides of under-sampled creases meet (module
/// documentation, step 6): the intersection of their tangent planes, the
/// vertices of the chord face it was found on and the face's longest edge.
#[derive(Clone, Debug)]
pub(super) struct CreaseCorner {
    pub point: Vec3,
    pub face_vertices: [VertexId; 3],
    pub reach: f64,
}

/// The corners of the under-sampled creases of `mesh` at `positions`, one
/// per corner (module documentation, step 6): on each chord face of
/// `chords` whose corner planes belong to three sides (normals apart by
/// more than [`FEATURE_ANGLE_DEG`] pairwise) meeting at a well-defined
/// point (|n₁ · (n₂ × n₃)| ≥ [`MIN_INCIDENCE`]) no farther from the face's
/// centroid than its longest edge; a point within that distance of a
/// corner found on an earlier face is the same corner.
pub(super) fn crease_corners(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    chords: &[Option<SidePlanes>],
) -> Vec<CreaseCorner> {
    let cos_feature = FEATURE_ANGLE_DEG.to_radians().cos();
    let mut corners: Vec<CreaseCorner> = Vec::new();
    for (f, planes) in chords.iter().enumerate() {
        let Some(planes) = planes else { continue };
        let face_vertices = mesh.triangle(FaceId(f as u32));
        let t = face_vertices.map(|v| positions[v.idx()]);
        // the distinct side planes (point, unit normal) of the face
        let mut distinct: Vec<(Vec3, Vec3)> = Vec::new();
        for k in 0..3 {
            for &n in &planes.0[k] {
                if distinct.iter().all(|d| d.1.dot(n) < cos_feature) {
                    distinct.push((t[k], n));
                }
            }
        }
        if distinct.len() < 3 {
            continue;
        }
        let reach = (0..3)
            .map(|k| t[k].distance(t[(k + 1) % 3]))
            .fold(0.0, f64::max);
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        let Some(point) = three_plane_point(&distinct, centroid, reach) else {
            continue;
        };
        if corners.iter().any(|c| c.point.distance(point) <= reach) {
            continue;
        }
        corners.push(CreaseCorner {
            point,
            face_vertices,
            reach,
        });
    }
    corners
}

/// The intersection point of three of the `planes` (point, unit normal),
/// the one nearest `centre` among the triples whose normals are
/// independent (|n₁ · (n₂ × n₃)| ≥ [`MIN_INCIDENCE`]), if within `reach`
/// of `centre`: the minimum of the Pottmann–Hofer squared distance
/// Σᵢ ((x − pᵢ) · nᵢ)² to the three planes (Ji et al. Eq. (6) with the
/// sides' fits), solved by Cramer's rule.
fn three_plane_point(planes: &[(Vec3, Vec3)], centre: Vec3, reach: f64) -> Option<Vec3> {
    let mut best: Option<(f64, Vec3)> = None;
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for l in j + 1..planes.len() {
                let (a, b, c) = (planes[i], planes[j], planes[l]);
                let det = a.1.dot(b.1.cross(c.1));
                if !(det.abs() >= MIN_INCIDENCE) {
                    continue;
                }
                let x = (a.1.dot(a.0) * b.1.cross(c.1)
                    + b.1.dot(b.0) * c.1.cross(a.1)
                    + c.1.dot(c.0) * a.1.cross(b.1))
                    / det;
                let d = x.distance(centre);
                if x.is_finite() && d <= reach && best.is_none_or(|b| d < b.0) {
                    best = Some((d, x));
                }
            }
        }
    }
    best.map(|b| b.1)
}

/// Puts, for each of `corners`, the free vertex nearest to it (of those
/// with a face within one ring of the corner's chord face, `is_free`)
/// onto it, when that vertex's position in `positions` is within the
/// corner's reach and no other corner took it (module documentation,
/// step 6).
pub(super) fn snap_to_corners(
    mesh: &SurfaceMesh,
    corners: &[CreaseCorner],
    is_free: &[bool],
    positions: &mut [Vec3],
) {
    let mut taken = vec![false; positions.len()];
    for corner in corners {
        let mut best: Option<(f64, usize)> = None;
        for &v in &corner.face_vertices {
            for u in std::iter::once(v).chain(mesh.one_ring(v)) {
                let u = u.idx();
                if !is_free[u] || taken[u] {
                    continue;
                }
                let d = positions[u].distance(corner.point);
                if d <= corner.reach && best.is_none_or(|b| d < b.0) {
                    best = Some((d, u));
                }
            }
        }
        if let Some((_, u)) = best {
            taken[u] = true;
            positions[u] = corner.point;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A roof y = −|x| (convex, 90°) and a valley y = |x| (concave) cut by a
    /// chord: the crease point of every point of the chord lies on the true
    /// surface, the chord's ends stay where they are.
    #[test]
    fn crease_points_of_a_chord_lie_on_the_crease_surface() {
        for convex in [true, false] {
            let s = if convex { -1.0 } else { 1.0 };
            // corners: two on the left side (x < 0), one on the right
            let t = [
                Vec3::new(-0.3, s * 0.3, 0.0),
                Vec3::new(-0.3, s * 0.3, 1.0),
                Vec3::new(0.5, s * 0.5, 0.5),
            ];
            // outward normals of the two sides (the solid below the roof /
            // below the valley)
            let left = Vec3::new(s, 1.0, 0.0).normalize();
            let right = Vec3::new(-s, 1.0, 0.0).normalize();
            let planes = SidePlanes([vec![left], vec![left], vec![right]]);
            for (a, b) in [(0.5, 0.2), (0.1, 0.1), (0.3, 0.6), (0.0, 0.0), (0.5, 0.5)] {
                let w = [1.0 - a - b, a, b];
                let q = crease_point(t, &planes, w).unwrap();
                let on = s * q.x.abs();
                assert!((q.y - on).abs() < 1e-12, "{convex} {w:?}: {q}");
            }
            // a corner stays where it is
            let q = crease_point(t, &planes, [1.0, 0.0, 0.0]).unwrap();
            assert!(q.distance(t[0]) < 1e-12);
        }
    }

    /// The corner of three planes is their common point (the minimum of
    /// the Pottmann–Hofer distance to them), found only within reach and
    /// only for independent normals.
    #[test]
    fn three_planes_meet_at_the_box_corner() {
        let planes = [
            (Vec3::new(1.0, 0.3, -0.2), Vec3::X),
            (Vec3::new(0.2, 1.0, 0.7), Vec3::Y),
            (Vec3::new(-0.4, 0.1, 1.0), Vec3::Z),
        ];
        let c = three_plane_point(&planes, Vec3::new(0.8, 0.8, 0.8), 1.0).unwrap();
        assert!(c.distance(Vec3::ONE) < 1e-12, "{c}");
        assert!(three_plane_point(&planes, Vec3::ZERO, 1.0).is_none());
        // two parallel planes and one across: no corner
        let slab = [planes[0], (Vec3::new(-1.0, 0.0, 0.0), Vec3::X), planes[2]];
        assert!(three_plane_point(&slab, Vec3::ZERO, 10.0).is_none());
    }

    /// Rows of 3 vertices along z through the (x, y) profile points `xy`,
    /// joined by strips of two triangles between consecutive rows.
    fn extruded(xy: &[(f64, f64)]) -> SurfaceMesh {
        let mut pos = Vec::new();
        for &(x, y) in xy {
            for z in 0..3 {
                pos.push(Vec3::new(x, y, z as f64));
            }
        }
        let mut faces = Vec::new();
        for i in 0..xy.len() as u32 - 1 {
            for j in 0..2 {
                let (a, b) = (3 * i + j, 3 * (i + 1) + j);
                faces.push([a, a + 1, b]);
                faces.push([a + 1, b + 1, b]);
            }
        }
        SurfaceMesh::new(pos, &faces).unwrap()
    }

    fn unit_face_normals(mesh: &SurfaceMesh) -> Vec<(Vec3, f64)> {
        (0..mesh.face_count() as u32)
            .map(|f| {
                let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| mesh.positions()[v.idx()]);
                crate::geom::triangle_normal_area(a, b, c)
            })
            .collect()
    }

    /// A step sampled like the fandisk-like part's slope: a flat (y = 0), a
    /// concave crease at the origin, a 45° slope sampled by ONE strip of
    /// faces, a convex crease at (0.35, 0.35) and a flat top. The slope's
    /// strip has no vertex inside it, yet it is a side (it touches no side
    /// and bends concave at one border, convex at the other): both chords
    /// are found with the slope's plane as their inner side, the slope is
    /// no chord, and every crease point of the chords lies on the step.
    /// Without the slope as a side neither chord has sides at both borders.
    #[test]
    fn a_strip_one_face_wide_between_two_creases_is_a_side() {
        let xy = [
            (-1.5, 0.0),
            (-1.0, 0.0),
            (-0.5, 0.0),
            (0.1, 0.1),
            (0.25, 0.25),
            (0.45, 0.35),
            (0.95, 0.35),
            (1.45, 0.35),
        ];
        let mesh = extruded(&xy);
        let chords = chord_faces(&mesh, &unit_face_normals(&mesh));
        for (f, c) in chords.iter().enumerate() {
            // strips 2 (x −0.5 → 0.1) and 4 (0.25 → 0.45): faces 8..12, 16..20
            let chord = (8..12).contains(&f) || (16..20).contains(&f);
            assert_eq!(c.is_some(), chord, "face {f}");
        }
        // the step y = min(max(x, 0), 0.35): distance of (x, y) from it
        let off_step = |q: Vec3| {
            let pieces = [
                ((-2.0, 0.0), (0.0, 0.0)),
                ((0.0, 0.0), (0.35, 0.35)),
                ((0.35, 0.35), (2.0, 0.35)),
            ];
            pieces
                .iter()
                .map(|&((ax, ay), (bx, by))| {
                    let (a, b) = (Vec3::new(ax, ay, q.z), Vec3::new(bx, by, q.z));
                    let t = ((q - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                    q.distance(a + t * (b - a))
                })
                .fold(f64::INFINITY, f64::min)
        };
        for f in (8..12).chain(16..20) {
            let planes = chords[f].as_ref().unwrap();
            let t = mesh
                .triangle(FaceId(f as u32))
                .map(|v| mesh.positions()[v.idx()]);
            for (a, b) in [(0.5, 0.2), (0.1, 0.1), (0.3, 0.6), (0.2, 0.3), (0.5, 0.5)] {
                let q = crease_point(t, planes, [1.0 - a - b, a, b]).unwrap();
                assert!(off_step(q) < 1e-12, "face {f} ({a}, {b}): {q}");
            }
        }
        // a rounded edge sampled by four strips, each bending the same way
        // (concave) at both borders: the two middle strips touch no side
        // either, but they are no sides, so nothing is rebuilt
        let rounded = extruded(&[
            (-1.5, 0.0),
            (-1.0, 0.0),
            (-0.5, 0.0),
            (0.0, 0.1),
            (0.3, 0.3),
            (0.5, 0.6),
            (0.6, 1.0),
            (0.6, 1.5),
            (0.6, 2.0),
        ]);
        let chords = chord_faces(&rounded, &unit_face_normals(&rounded));
        assert!(chords.iter().all(Option::is_none));
    }

    /// A chord across a crease of a generated mesh is found, the flat faces
    /// are not: a folded strip of faces (two flat sides of 2 × 4 faces at
    /// 90°, joined by one strip of chord faces).
    #[test]
    fn the_chord_strip_of_a_folded_sheet_is_found() {
        // rows of 3 vertices along z at x positions on the roof y = −|x|
        let xs = [-1.5, -1.0, -0.5, 0.3, 0.8, 1.3];
        let roof: Vec<(f64, f64)> = xs.iter().map(|&x| (x, -f64::abs(x))).collect();
        let mesh = extruded(&roof);
        let normals: Vec<(Vec3, f64)> = (0..mesh.face_count() as u32)
            .map(|f| {
                let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| mesh.positions()[v.idx()]);
                crate::geom::triangle_normal_area(a, b, c)
            })
            .collect();
        let chords = chord_faces(&mesh, &normals);
        for (f, c) in chords.iter().enumerate() {
            // faces 8..12 join the rows at x = −0.5 and x = 0.3
            assert_eq!(c.is_some(), (8..12).contains(&f), "face {f}");
        }
    }
}
