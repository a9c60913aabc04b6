//! Detection and repair of flipped triangles after a vertex-flow solve
//! (Ji et al. §5: "we rectify the topological errors in the post-processing
//! if triangle flips occur").

use super::REPAIR_HALVINGS;
use crate::Vec3;
use crate::geom::triangle_normal_area;
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

/// Unit face normals of the (normalised) input mesh.
pub(super) fn face_normals_of(mesh: &SurfaceMesh) -> Vec<Vec3> {
    normals_at(mesh, mesh.positions())
}

/// Faces whose normal at `positions` points against (or is perpendicular
/// to) their input normal, or which collapsed. Faces degenerate in the input
/// are never flagged.
pub(super) fn flipped_faces(
    mesh: &SurfaceMesh,
    input_normals: &[Vec3],
    positions: &[Vec3],
) -> Vec<u32> {
    (0..mesh.face_count() as u32)
        .into_par_iter()
        .filter(|&f| {
            let n0 = input_normals[f as usize];
            if n0 == Vec3::ZERO {
                return false;
            }
            let [a, b, c] = mesh.triangle(FaceId(f)).map(|v| positions[v.idx()]);
            let n = triangle_normal_area(a, b, c).0;
            !(n.dot(n0) > 0.0)
        })
        .collect()
}

/// What [`repair_flips`] did.
pub(super) struct RepairOutcome {
    /// Faces flipped before the repair.
    pub flipped: usize,
    /// Vertices whose step was shortened or undone.
    pub backtracked: Vec<usize>,
}

/// Repairs flipped faces of `target` (the solution of a step that started at
/// the flip-free `start`): the steps of the vertices of flipped faces are
/// halved, [`REPAIR_HALVINGS`] times at most, then reset to zero, until no
/// face is flipped. Terminates: a face whose vertices are all back at
/// `start` is not flipped, and every round moves at least one vertex back.
pub(super) fn repair_flips(
    mesh: &SurfaceMesh,
    input_normals: &[Vec3],
    start: &[Vec3],
    target: &mut [Vec3],
) -> RepairOutcome {
    let mut flagged = flipped_faces(mesh, input_normals, target);
    let flipped = flagged.len();
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
                    start[v] + 0.5 * (target[v] - start[v])
                } else {
                    start[v]
                };
            }
        }
        if !changed {
            break;
        }
        round += 1;
        flagged = flipped_faces(mesh, input_normals, target);
    }
    RepairOutcome {
        flipped,
        backtracked: (0..backtracked.len()).filter(|&v| backtracked[v]).collect(),
    }
}
