//! Detection and repair of flipped and collapsing triangles after a
//! vertex-flow solve (Ji et al. §5: "we rectify the topological errors in
//! the post-processing if triangle flips occur"), and the quality bound:
//! no triangle ends with a quality 2r/R below [`QUALITY_FLOOR`] times its
//! input quality.

use super::REPAIR_HALVINGS;
use super::boundary::BoundaryCurves;
use crate::Vec3;
use crate::geom::{triangle_normal_area, triangle_quality};
use crate::mesh::{FaceId, SurfaceMesh};
use rayon::prelude::*;

/// Unit normal of every face at `positions` (zero for degenerate faces);
/// faces of `mesh` are triangles.
pub(super) fn normals_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<Vec3> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| positions[v.idx()]);
            triangle_normal_area(a, b, c).0
        })
        .collect()
}

/// Share of its input quality 2r/R below which a triangle counts as
/// collapsing and its vertices' steps are shortened like those of a flipped
/// one: every output triangle keeps at least a quarter of its input quality
/// (the documented bound of the flow's triangle quality; the paper relies on
/// μ alone, which keeps the mean but lets single triangles collapse to
/// slivers).
pub const QUALITY_FLOOR: f64 = 0.25;

/// The input of the repair: normal and quality of every input face.
pub(super) struct InputFaces {
    normals: Vec<Vec3>,
    qualities: Vec<f64>,
}

impl InputFaces {
    /// Unit face normals and qualities of the (normalised) input mesh.
    pub fn of(mesh: &SurfaceMesh) -> InputFaces {
        let p = mesh.positions();
        InputFaces {
            normals: normals_at(mesh, p),
            qualities: (0..mesh.face_count() as u32)
                .into_par_iter()
                .map(|f| {
                    let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| p[v.idx()]);
                    triangle_quality(a, b, c)
                })
                .collect(),
        }
    }
}

/// Whether face `f` at `positions` is flipped (its normal against, or
/// perpendicular to, its input normal, or collapsed), and whether it fell
/// below [`QUALITY_FLOOR`] of its input quality. Faces degenerate in the
/// input are never flagged.
fn face_state(mesh: &SurfaceMesh, input: &InputFaces, positions: &[Vec3], f: u32) -> (bool, bool) {
    let n0 = input.normals[f as usize];
    if n0 == Vec3::ZERO {
        return (false, false);
    }
    let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| positions[v.idx()]);
    let n = triangle_normal_area(a, b, c).0;
    let flipped = !(n.dot(n0) > 0.0);
    let degraded = triangle_quality(a, b, c) < QUALITY_FLOOR * input.qualities[f as usize];
    (flipped, degraded)
}

/// Faces flipped or below the quality floor at `positions`, and how many of
/// them are flipped.
fn bad_faces(mesh: &SurfaceMesh, input: &InputFaces, positions: &[Vec3]) -> (Vec<u32>, usize) {
    let states: Vec<(u32, bool)> = (0..mesh.face_count() as u32)
        .into_par_iter()
        .filter_map(|f| {
            let (flipped, degraded) = face_state(mesh, input, positions, f);
            (flipped || degraded).then_some((f, flipped))
        })
        .collect();
    let flipped = states.iter().filter(|s| s.1).count();
    (states.into_iter().map(|s| s.0).collect(), flipped)
}

/// The vertices (sorted, each once) of the faces flipped or below the
/// quality floor at `positions`: where the quality guard of the flow lifts
/// μ_i before the repair.
pub(super) fn bad_face_vertices(
    mesh: &SurfaceMesh,
    input: &InputFaces,
    positions: &[Vec3],
) -> Vec<usize> {
    let mut vertices: Vec<usize> = bad_faces(mesh, input, positions)
        .0
        .into_iter()
        .flat_map(|f| mesh.triangle(FaceId(f)).map(|v| v.idx()))
        .collect();
    vertices.sort_unstable();
    vertices.dedup();
    vertices
}

/// What [`repair_flips`] did.
pub(super) struct RepairOutcome {
    /// Faces flipped before the repair.
    pub flipped: usize,
    /// Faces not flipped but below the quality floor before the repair.
    pub degraded: usize,
    /// Vertices whose step was shortened or undone.
    pub backtracked: Vec<usize>,
}

/// Repairs flipped and collapsing faces of `target` (the solution of a step
/// that started at `start`, where no face is either): the steps of the
/// vertices of such faces are halved, [`REPAIR_HALVINGS`] times at most,
/// then reset to zero, until no face is flipped or below the quality floor.
/// A halved step of a boundary vertex that slides along the boundary is
/// projected back onto the input boundary polyline (`boundary`; the
/// midpoint of two points of a polyline need not lie on it).
/// Terminates: a face whose vertices are all back at `start` is neither,
/// and every round moves at least one vertex back.
pub(super) fn repair_flips(
    mesh: &SurfaceMesh,
    input: &InputFaces,
    boundary: &BoundaryCurves,
    start: &[Vec3],
    target: &mut [Vec3],
) -> RepairOutcome {
    let (mut flagged, flipped) = bad_faces(mesh, input, target);
    let degraded = flagged.len() - flipped;
    let mut backtracked = vec![false; target.len()];
    let mut touched = vec![false; target.len()];
    let mut round = 0;
    while !flagged.is_empty() {
        let mut changed = false;
        touched.iter_mut().for_each(|t| *t = false);
        for &f in &flagged {
            for v in mesh.triangle(FaceId(f)) {
                let v = v.idx();
                if touched[v] || target[v] == start[v] {
                    continue;
                }
                touched[v] = true;
                backtracked[v] = true;
                changed = true;
                target[v] = if round < REPAIR_HALVINGS {
                    let halved = start[v] + 0.5 * (target[v] - start[v]);
                    if boundary.is_on(v) {
                        boundary.nearest(v, halved)
                    } else {
                        halved
                    }
                } else {
                    start[v]
                };
            }
        }
        if !changed {
            break;
        }
        round += 1;
        flagged = bad_faces(mesh, input, target).0;
    }
    RepairOutcome {
        flipped,
        degraded,
        backtracked: (0..backtracked.len()).filter(|&v| backtracked[v]).collect(),
    }
}
