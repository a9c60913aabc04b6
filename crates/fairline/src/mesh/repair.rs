//! Repair of dirty face lists (`fairline repair`): what real scans bring
//! (non-manifold edges and vertices, duplicate and zero-area faces,
//! unreferenced vertices, inconsistent orientation) turned into a face list
//! [`SurfaceMesh`](super::SurfaceMesh) accepts, with a report of every change.
//!
//! Every vertex that is kept keeps its coordinates bit-identical and its
//! order; removed vertices close the gaps (the report lists them, and
//! [`RepairReport::vertex_source`] maps every output vertex to its input
//! vertex); copies made by splitting are appended at the end. Kept faces keep
//! their order and their first vertex (a reversed face runs `v0, vn-1, …, v1`).

use super::inspect::polygon_area;
use super::soup::Soup;
use super::union_find::{find, union};
use super::{MeshError, SurfaceMesh};
use crate::control::{Cancelled, Control};
use serde::Serialize;
use std::collections::HashMap;
use thiserror::Error;

const NONE: u32 = u32::MAX;

/// Why a face was removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RemovalReason {
    /// It refers to a vertex that does not exist.
    InvalidIndex,
    /// It has fewer than three vertices.
    TooFewVertices,
    /// It has fewer than three distinct vertices, or uses a vertex twice
    /// other than consecutively.
    RepeatedVertex,
    /// Its area is zero relative to its edge lengths
    /// ([`super::DEGENERATE_RELATIVE_AREA`]).
    ZeroArea,
    /// It has the same vertex set as an earlier face.
    Duplicate,
    /// It is a third (or later) face on an edge that splitting could not
    /// separate.
    NonManifoldEdge,
}

/// One removed face.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RemovedFace {
    /// Index of the face in the input.
    pub face: usize,
    /// Why it was removed.
    pub reason: RemovalReason,
    /// For a duplicate: the earlier face it repeats.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duplicate_of: Option<usize>,
}

/// A non-manifold edge that was cut apart.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SplitEdge {
    /// Its two input vertices (smaller first).
    pub vertices: [usize; 2],
    /// The input faces on it; the first two stay joined across it when they
    /// are oppositely oriented (else the first two), the others are cut off.
    pub faces: Vec<usize>,
}

/// A vertex where several fans of faces met, split into one vertex per fan.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SplitVertex {
    /// The input vertex (its fan with the first face keeps it).
    pub vertex: usize,
    /// Output indices of the copies, one per further fan.
    pub copies: Vec<usize>,
}

/// Exactly what [`repair`] changed. Face indices are input indices; vertex
/// indices are input indices unless said otherwise.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RepairReport {
    /// Input vertices.
    pub vertices_before: usize,
    /// Input faces.
    pub faces_before: usize,
    /// Output vertices.
    pub vertices_after: usize,
    /// Output faces.
    pub faces_after: usize,
    /// Faces removed, with the reason.
    pub removed_faces: Vec<RemovedFace>,
    /// Faces that listed a vertex twice in a row and were kept with the
    /// repetition removed.
    pub collapsed_faces: Vec<usize>,
    /// Vertices used by no (remaining) face, removed.
    pub removed_vertices: Vec<usize>,
    /// Non-manifold edges cut apart.
    pub split_edges: Vec<SplitEdge>,
    /// Non-manifold vertices split, one vertex per fan.
    pub split_vertices: Vec<SplitVertex>,
    /// Faces whose vertex order was reversed for a consistent orientation.
    pub flipped_faces: Vec<usize>,
    /// Faces where the orientation could not be made consistent (a
    /// non-orientable component, e.g. a Möbius strip); left as they are.
    pub orientation_conflicts: Vec<usize>,
    /// Input vertex of every output vertex; empty when the vertex list is
    /// unchanged (output vertex i is input vertex i).
    pub vertex_source: Vec<u32>,
    /// True when the output is a valid oriented manifold (every fairline
    /// command accepts it).
    pub manifold: bool,
    /// Why the output is still refused, when it is (left out of the
    /// serialised report when there is none: reports never hold `null`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub remaining_problem: Option<String>,
}

impl RepairReport {
    /// True when the output equals the input.
    pub fn unchanged(&self) -> bool {
        self.removed_faces.is_empty()
            && self.collapsed_faces.is_empty()
            && self.removed_vertices.is_empty()
            && self.split_edges.is_empty()
            && self.split_vertices.is_empty()
            && self.flipped_faces.is_empty()
    }

    /// What a front end warns about after the repair, as plain sentences
    /// (the CLI prints them as `warning:` lines, every front end lists them
    /// in its report): faces that could not be oriented consistently, and
    /// why the output is still not a manifold.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if !self.orientation_conflicts.is_empty() {
            warnings.push(format!(
                "{} faces could not be oriented consistently (non-orientable surface); left as they are",
                self.orientation_conflicts.len()
            ));
        }
        if let Some(problem) = &self.remaining_problem {
            warnings.push(format!("the output is still not a manifold: {problem}"));
        }
        warnings
    }
}

/// What [`repair`] returns: the repaired face list (vertices may be
/// removed or split, so it is a new [`Soup`], not new positions of the
/// input's vertices) and what was changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Repaired {
    /// The repaired positions and faces.
    pub soup: Soup,
    /// What was changed.
    pub report: RepairReport,
}

/// Options of [`repair`] (the crate's one shape, [`crate::control`]).
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct RepairOptions {
    /// Progress callback and cancel flag: one step per stage ("steps": the
    /// faces cleaned; edges cut, faces oriented and vertices split; the
    /// vertices compacted; the result checked).
    pub control: Control,
}

crate::control::setters!(RepairOptions { control: Control });

/// Why [`repair`] gave no result.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RepairError {
    /// The face list holds what cannot be repaired without inventing
    /// geometry: non-finite coordinates, more than 32-bit indices.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The caller raised the cancel flag of [`RepairOptions::control`].
    #[error("cancelled")]
    Cancelled(#[from] Cancelled),
}

/// Stages of [`repair`] reported to [`RepairOptions::control`].
const REPAIR_STEPS: u64 = 4;

/// Repairs a face list so that [`SurfaceMesh::from_soup`] accepts it:
///
/// 1. faces with an invalid index or fewer than three vertices are removed;
///    a vertex repeated in a row is collapsed (else the face is removed);
/// 2. zero-area faces and faces with the vertex set of an earlier face are
///    removed;
/// 3. non-manifold edges are cut: of the faces on such an edge, the first
///    stays joined with the first later one that runs the edge the other
///    way (else the second), the rest are cut off;
/// 4. faces are reversed to agree with their neighbours (breadth-first
///    over joined edges, each component's first face keeps its order);
///    conflicts (non-orientable components) are reported, not changed;
/// 5. every vertex where several fans of faces meet is split, one vertex
///    per fan, copies appended after the input vertices;
/// 6. vertices no face uses are removed.
///
/// If an edge still carries more than two faces after cutting (faces joined
/// around both of its vertices some other way), its extra faces are removed
/// and the steps from 3 on run again.
///
/// Refuses only what cannot be repaired without inventing geometry:
/// non-finite coordinates and meshes beyond 32-bit indices.
///
/// The input is a [`Soup`], not a [`SurfaceMesh`]: a mesh cannot hold what
/// this repairs. It is never modified. Reports one progress step per stage
/// through [`RepairOptions::control`] and stops there when cancelled
/// ([`RepairError::Cancelled`]).
pub fn repair(soup: &Soup, options: &RepairOptions) -> Result<Repaired, RepairError> {
    let control = &options.control;
    let nv = soup.vertex_count();
    if nv >= NONE as usize / 2 || soup.indices.len() >= NONE as usize / 2 {
        return Err(MeshError::TooLarge.into());
    }
    if let Some(v) = soup.positions.iter().position(|p| !p.is_finite()) {
        return Err(MeshError::NonFiniteCoordinate { vertex: v }.into());
    }
    control.checkpoint()?;
    let mut report = RepairReport {
        vertices_before: nv,
        faces_before: soup.face_count(),
        ..RepairReport::default()
    };
    // Steps 1 and 2: a clean list of candidate faces (input index, vertices).
    let mut faces = clean_faces(soup, &mut report);
    control.step("steps", 1, REPAIR_STEPS)?;

    // Steps 3 to 5, again after removing faces an edge cannot hold.
    let (out_faces, copies) = loop {
        let attempt = cut_orient_split(nv, &faces);
        if attempt.excess.is_empty() {
            report.split_edges = attempt.split_edges;
            report.flipped_faces = attempt.flipped;
            report.orientation_conflicts = attempt.conflicts;
            break (attempt.faces, attempt.copies);
        }
        let excess: std::collections::HashSet<usize> = attempt.excess.iter().copied().collect();
        faces.retain(|(f, _)| !excess.contains(f));
        for f in attempt.excess {
            report.removed_faces.push(RemovedFace {
                face: f,
                reason: RemovalReason::NonManifoldEdge,
                duplicate_of: None,
            });
        }
        control.checkpoint()?;
    };
    report.removed_faces.sort_by_key(|r| r.face);
    control.step("steps", 2, REPAIR_STEPS)?;

    // Step 6: drop unreferenced input vertices; copies follow the kept ones.
    let out = compact_vertices(soup, &out_faces, &copies, &mut report);
    control.step("steps", 3, REPAIR_STEPS)?;
    match SurfaceMesh::from_soup(&out) {
        Ok(_) => report.manifold = true,
        Err(e) => report.remaining_problem = Some(e.to_string()),
    }
    control.progress("steps", REPAIR_STEPS, REPAIR_STEPS);
    Ok(Repaired { soup: out, report })
}

/// Steps 1 and 2 of [`repair`]: the candidate faces (input index, vertices)
/// after removing invalid, collapsed-to-nothing, zero-area and duplicate
/// faces (recorded in `report`) and collapsing repeated corners.
fn clean_faces(soup: &Soup, report: &mut RepairReport) -> Vec<(usize, Vec<u32>)> {
    let nv = soup.vertex_count();
    let mut faces: Vec<(usize, Vec<u32>)> = Vec::with_capacity(soup.face_count());
    for (f, face) in soup.faces().enumerate() {
        let remove = |report: &mut RepairReport, reason| {
            report.removed_faces.push(RemovedFace {
                face: f,
                reason,
                duplicate_of: None,
            })
        };
        if face.iter().any(|&i| i as usize >= nv) {
            remove(report, RemovalReason::InvalidIndex);
            continue;
        }
        if face.len() < 3 {
            remove(report, RemovalReason::TooFewVertices);
            continue;
        }
        let mut poly: Vec<u32> = Vec::with_capacity(face.len());
        for &v in face {
            if poly.last() != Some(&v) {
                poly.push(v);
            }
        }
        while poly.len() > 1 && poly.first() == poly.last() {
            poly.pop();
        }
        let distinct = poly.iter().enumerate().all(|(k, a)| !poly[..k].contains(a));
        if poly.len() < 3 || !distinct {
            remove(report, RemovalReason::RepeatedVertex);
            continue;
        }
        if polygon_area(&soup.positions, &poly).1 {
            remove(report, RemovalReason::ZeroArea);
            continue;
        }
        if poly.len() != face.len() {
            report.collapsed_faces.push(f);
        }
        faces.push((f, poly));
    }
    let mut first_with: HashMap<Vec<u32>, usize> = HashMap::with_capacity(faces.len());
    faces.retain(|(f, poly)| {
        let mut key = poly.clone();
        key.sort_unstable();
        match first_with.get(&key) {
            Some(&earlier) => {
                report.removed_faces.push(RemovedFace {
                    face: *f,
                    reason: RemovalReason::Duplicate,
                    duplicate_of: Some(earlier),
                });
                false
            }
            None => {
                first_with.insert(key, *f);
                true
            }
        }
    });
    faces
}

/// Step 6 of [`repair`]: the output soup without unreferenced input
/// vertices, the copies of split vertices after the kept ones; records the
/// removed vertices, the split vertices, the sizes and the vertex sources
/// in `report`.
fn compact_vertices(
    soup: &Soup,
    out_faces: &[(usize, Vec<u32>)],
    copies: &[u32],
    report: &mut RepairReport,
) -> Soup {
    let nv = soup.vertex_count();
    let total = nv + copies.len();
    let mut used = vec![false; total];
    for (_, poly) in out_faces {
        for &v in poly {
            used[v as usize] = true;
        }
    }
    let mut new_index = vec![NONE; total];
    let mut source: Vec<u32> = Vec::with_capacity(total);
    for v in 0..nv {
        if used[v] {
            new_index[v] = source.len() as u32;
            source.push(v as u32);
        } else {
            report.removed_vertices.push(v);
        }
    }
    for (j, &v) in copies.iter().enumerate() {
        new_index[nv + j] = source.len() as u32;
        source.push(v);
    }
    let mut by_vertex: Vec<SplitVertex> = Vec::new();
    for (j, &v) in copies.iter().enumerate() {
        let out = new_index[nv + j] as usize;
        match by_vertex.last_mut() {
            Some(s) if s.vertex == v as usize => s.copies.push(out),
            _ => by_vertex.push(SplitVertex {
                vertex: v as usize,
                copies: vec![out],
            }),
        }
    }
    report.split_vertices = by_vertex;
    let positions = source.iter().map(|&v| soup.positions[v as usize]).collect();
    let mut out = Soup {
        positions,
        offsets: Vec::with_capacity(out_faces.len() + 1),
        indices: Vec::with_capacity(soup.indices.len()),
    };
    out.offsets.push(0);
    for (_, poly) in out_faces {
        out.indices
            .extend(poly.iter().map(|&v| new_index[v as usize]));
        out.offsets.push(out.indices.len() as u32);
    }
    report.vertices_after = out.vertex_count();
    report.faces_after = out.face_count();
    if source.len() != nv || report.removed_vertices.len() + copies.len() > 0 {
        report.vertex_source = source;
    }
    out
}

/// What one pass of steps 3 to 5 produced.
struct Pass {
    /// (input face, vertices) with copies numbered from `nv` on.
    faces: Vec<(usize, Vec<u32>)>,
    /// Input vertex of each copy `nv + j`.
    copies: Vec<u32>,
    split_edges: Vec<SplitEdge>,
    flipped: Vec<usize>,
    conflicts: Vec<usize>,
    /// Input faces to remove before trying again (empty when done).
    excess: Vec<usize>,
}

/// Corners of the faces of `faces`: corner `c` of face `k` runs from
/// `vertex[c]` to the next vertex of that face.
struct Corners {
    vertex: Vec<u32>,
    face: Vec<u32>,
    start: Vec<u32>,
}

impl Corners {
    fn new(faces: &[(usize, Vec<u32>)]) -> Corners {
        let mut c = Corners {
            vertex: Vec::new(),
            face: Vec::new(),
            start: vec![0],
        };
        for (k, (_, poly)) in faces.iter().enumerate() {
            c.vertex.extend_from_slice(poly);
            c.face.extend(std::iter::repeat_n(k as u32, poly.len()));
            c.start.push(c.vertex.len() as u32);
        }
        c
    }
    fn next(&self, c: u32) -> u32 {
        let k = self.face[c as usize] as usize;
        if c + 1 == self.start[k + 1] {
            self.start[k]
        } else {
            c + 1
        }
    }
    /// Edges as groups of corners: (smaller vertex, larger vertex, corner),
    /// sorted.
    fn edge_groups(&self) -> Vec<(u32, u32, u32)> {
        let mut e: Vec<(u32, u32, u32)> = (0..self.vertex.len() as u32)
            .map(|c| {
                let (a, b) = (self.vertex[c as usize], self.vertex[self.next(c) as usize]);
                (a.min(b), a.max(b), c)
            })
            .collect();
        e.sort_unstable();
        e
    }
}

fn cut_orient_split(nv: usize, faces: &[(usize, Vec<u32>)]) -> Pass {
    let corners = Corners::new(faces);
    let nc = corners.vertex.len();
    let groups = corners.edge_groups();
    // Step 3: which corners are joined across their edge.
    let mut mate = vec![NONE; nc];
    let mut split_edges = Vec::new();
    let mut i = 0;
    while i < groups.len() {
        let mut j = i + 1;
        while j < groups.len() && groups[j].0 == groups[i].0 && groups[j].1 == groups[i].1 {
            j += 1;
        }
        let group = &groups[i..j];
        let c0 = group[0].2;
        let pair = match group.len() {
            1 => None,
            2 => Some(group[1].2),
            _ => {
                let dir = |c: u32| corners.vertex[c as usize] == group[0].0;
                let opposite = group[1..].iter().find(|g| dir(g.2) != dir(c0));
                let mut input_faces: Vec<usize> = group
                    .iter()
                    .map(|g| faces[corners.face[g.2 as usize] as usize].0)
                    .collect();
                input_faces.sort_unstable();
                split_edges.push(SplitEdge {
                    vertices: [group[0].0 as usize, group[0].1 as usize],
                    faces: input_faces,
                });
                Some(opposite.unwrap_or(&group[1]).2)
            }
        };
        if let Some(d) = pair {
            mate[c0 as usize] = d;
            mate[d as usize] = c0;
        }
        i = j;
    }
    // Step 4: orientation by breadth-first search over joined edges.
    let nf = faces.len();
    let (flip, conflict) = orient_by_mates(&corners, &mate, nf);
    // Step 5: fans of corners around each vertex, joined across mates.
    let mut parent: Vec<u32> = (0..nc as u32).collect();
    for c in 0..nc as u32 {
        let d = mate[c as usize];
        if d == NONE || d < c {
            continue;
        }
        let (c1, d1) = (corners.next(c), corners.next(d));
        if corners.vertex[c as usize] == corners.vertex[d as usize] {
            union(&mut parent, c, d);
            union(&mut parent, c1, d1);
        } else {
            union(&mut parent, c, d1);
            union(&mut parent, c1, d);
        }
    }
    let mut keeper = vec![NONE; nv];
    let mut others: Vec<(u32, u32)> = Vec::new(); // (vertex, root) in corner order
    let mut seen = vec![false; nc];
    for c in 0..nc as u32 {
        let v = corners.vertex[c as usize] as usize;
        let r = find(&mut parent, c);
        if keeper[v] == NONE {
            keeper[v] = r;
            seen[r as usize] = true;
        } else if !seen[r as usize] {
            seen[r as usize] = true;
            others.push((v as u32, r));
        }
    }
    others.sort_by_key(|&(v, _)| v); // stable: fans of a vertex in corner order
    let mut copy_of_root = vec![NONE; nc];
    let mut copies = Vec::with_capacity(others.len());
    for &(v, r) in &others {
        copy_of_root[r as usize] = (nv + copies.len()) as u32;
        copies.push(v);
    }
    let mut out = Vec::with_capacity(nf);
    let mut flipped = Vec::new();
    for (k, (f, _)) in faces.iter().enumerate() {
        let mut poly: Vec<u32> = (corners.start[k]..corners.start[k + 1])
            .map(|c| {
                let copy = copy_of_root[find(&mut parent, c) as usize];
                if copy == NONE {
                    corners.vertex[c as usize]
                } else {
                    copy
                }
            })
            .collect();
        if flip[k] == 1 {
            poly[1..].reverse();
            flipped.push(*f);
        }
        out.push((*f, poly));
    }
    // An edge that still has more than two faces: remove the extra faces.
    let again = Corners::new(&out);
    let groups = again.edge_groups();
    let mut excess = Vec::new();
    let mut i = 0;
    while i < groups.len() {
        let mut j = i + 1;
        while j < groups.len() && groups[j].0 == groups[i].0 && groups[j].1 == groups[i].1 {
            j += 1;
        }
        for g in &groups[(i + 2).min(j)..j] {
            excess.push(out[again.face[g.2 as usize] as usize].0);
        }
        i = j;
    }
    excess.sort_unstable();
    excess.dedup();
    let conflicts = (0..nf)
        .filter(|&k| conflict[k])
        .map(|k| faces[k].0)
        .collect();
    Pass {
        faces: out,
        copies,
        split_edges,
        flipped,
        conflicts,
        excess,
    }
}

/// Step 4 of [`repair`]: which of the `nf` faces to reverse (1) so that
/// joined corners (`mate`) traverse their edge in opposite directions,
/// breadth-first from the first face of each component, and the faces
/// where that conflicts with an earlier choice (non-orientable parts).
fn orient_by_mates(corners: &Corners, mate: &[u32], nf: usize) -> (Vec<u8>, Vec<bool>) {
    let mut flip: Vec<u8> = vec![2; nf];
    let mut conflict = vec![false; nf];
    let mut queue = Vec::new();
    for seed in 0..nf {
        if flip[seed] != 2 {
            continue;
        }
        flip[seed] = 0;
        queue.push(seed as u32);
        while let Some(f) = queue.pop() {
            let f = f as usize;
            for c in corners.start[f]..corners.start[f + 1] {
                let d = mate[c as usize];
                if d == NONE {
                    continue;
                }
                let g = corners.face[d as usize] as usize;
                let same_direction = corners.vertex[c as usize] == corners.vertex[d as usize];
                let want = if same_direction { 1 - flip[f] } else { flip[f] };
                if flip[g] == 2 {
                    flip[g] = want;
                    queue.push(g as u32);
                } else if flip[g] != want {
                    conflict[g] = true;
                }
            }
        }
    }
    (flip, conflict)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;
    use crate::shapes;

    fn bits(p: &[Vec3]) -> Vec<[u64; 3]> {
        p.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
    }

    fn square() -> Vec<Vec3> {
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn a_clean_mesh_is_left_exactly_as_it_is() {
        for m in [
            shapes::icosphere(1.0, 2),
            shapes::torus(2.0, 0.5, 12, 8),
            shapes::quad_grid(5, 4, (0.0, 1.0), (0.0, 1.0), |x, y| x * y),
        ] {
            let soup = m.to_soup();
            let r = repair(&soup, &RepairOptions::default()).unwrap();
            assert!(r.report.unchanged(), "{:?}", r.report);
            assert!(r.report.manifold);
            assert!(r.report.vertex_source.is_empty());
            assert_eq!(r.soup, soup);
        }
    }

    #[test]
    fn duplicate_zero_area_and_invalid_faces_are_removed_and_vertices_renumbered() {
        let mut p = square();
        p.push(Vec3::new(0.5, 0.0, 0.0)); // 4: on edge (0, 1)
        p.push(Vec3::new(7.0, 7.0, 7.0)); // 5: used only by removed faces
        p.push(Vec3::new(0.5, 0.5, 1.0)); // 6
        let mut soup = Soup::from_polygons(
            p.clone(),
            &[
                vec![0u32, 1, 2],
                vec![0, 2, 3],
                vec![2, 0, 1],    // 2: duplicate of 0 (other start)
                vec![0, 4, 1],    // 3: zero area
                vec![5, 5, 2],    // 4: two distinct vertices
                vec![3, 3, 2, 6], // 5: collapsed to (3, 2, 6)
                vec![0, 9, 1],    // 6: invalid index
            ],
        );
        soup.push_face(&[1, 2]); // 7: too few vertices
        let r = repair(&soup, &RepairOptions::default()).unwrap();
        let reasons: Vec<(usize, RemovalReason)> = r
            .report
            .removed_faces
            .iter()
            .map(|f| (f.face, f.reason))
            .collect();
        assert_eq!(
            reasons,
            vec![
                (2, RemovalReason::Duplicate),
                (3, RemovalReason::ZeroArea),
                (4, RemovalReason::RepeatedVertex),
                (6, RemovalReason::InvalidIndex),
                (7, RemovalReason::TooFewVertices),
            ]
        );
        assert_eq!(r.report.removed_faces[0].duplicate_of, Some(0));
        assert_eq!(r.report.collapsed_faces, vec![5]);
        assert_eq!(r.report.removed_vertices, vec![4, 5]);
        assert_eq!(r.report.vertex_source, vec![0, 1, 2, 3, 6]);
        // kept vertices bit-identical and in order; faces renumbered
        let kept: Vec<Vec3> = [0, 1, 2, 3, 6].iter().map(|&i| p[i]).collect();
        assert_eq!(bits(&r.soup.positions), bits(&kept));
        let faces: Vec<Vec<u32>> = r.soup.faces().map(<[u32]>::to_vec).collect();
        assert_eq!(faces, vec![vec![0, 1, 2], vec![0, 2, 3], vec![3, 2, 4]]);
        assert!(r.report.manifold);
        assert_eq!((r.report.vertices_after, r.report.faces_after), (5, 3));
    }

    #[test]
    fn non_manifold_edges_are_cut_and_the_surface_keeps_its_sheet() {
        // a flat square (two triangles) with a fin standing on its diagonal
        let mut p = square();
        p.push(Vec3::new(0.5, 0.5, 1.0));
        let soup = Soup::from_polygons(p, &[[0u32, 1, 2], [0, 2, 3], [0, 2, 4]]);
        assert!(matches!(
            SurfaceMesh::from_soup(&soup),
            Err(MeshError::NonManifoldEdge { .. })
        ));
        let r = repair(&soup, &RepairOptions::default()).unwrap();
        assert_eq!(
            r.report.split_edges,
            vec![SplitEdge {
                vertices: [0, 2],
                faces: vec![0, 1, 2]
            }]
        );
        // faces 0 and 1 run the diagonal in opposite directions and stay
        // joined; the fin gets copies of 0 and 2
        assert_eq!(r.report.split_vertices.len(), 2);
        assert_eq!(r.report.vertex_source, vec![0, 1, 2, 3, 4, 0, 2]);
        let faces: Vec<Vec<u32>> = r.soup.faces().map(<[u32]>::to_vec).collect();
        assert_eq!(faces, vec![vec![0, 1, 2], vec![0, 2, 3], vec![5, 6, 4]]);
        let m = SurfaceMesh::from_soup(&r.soup).unwrap();
        assert_eq!(super::super::topology_summary(&m).components, 2);
        assert!(r.report.manifold);
    }

    #[test]
    fn non_manifold_vertices_are_split_into_appended_copies() {
        let (p, faces) = super::super::tests::two_cones();
        let soup = Soup::from_polygons(p.clone(), &faces);
        let r = repair(&soup, &RepairOptions::default()).unwrap();
        assert_eq!(
            r.report.split_vertices,
            vec![SplitVertex {
                vertex: 0,
                copies: vec![7]
            }]
        );
        assert!(r.report.split_edges.is_empty() && r.report.removed_faces.is_empty());
        assert_eq!(r.soup.positions.len(), 8);
        assert_eq!(bits(&r.soup.positions[..7]), bits(&p));
        assert_eq!(r.soup.positions[7].to_array(), p[0].to_array());
        // the second cone's faces use the copy, nothing else changed
        for (k, face) in r.soup.faces().enumerate() {
            let want: Vec<u32> = faces[k]
                .iter()
                .map(|&v| if v == 0 && k >= 4 { 7 } else { v })
                .collect();
            assert_eq!(face, &want[..]);
        }
        let m = SurfaceMesh::from_soup(&r.soup).unwrap();
        assert_eq!(m.split_vertex_count(), 0);
    }

    #[test]
    fn orientation_is_made_consistent_and_moebius_strips_are_reported() {
        let m = shapes::icosphere(1.0, 1);
        let mut soup = m.to_soup();
        let mut polys: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
        polys[7].reverse();
        polys[30].reverse();
        let reversed = polys.clone();
        soup = Soup::from_polygons(soup.positions, &polys);
        let r = repair(&soup, &RepairOptions::default()).unwrap();
        assert_eq!(r.report.flipped_faces, vec![7, 30]);
        assert!(r.report.orientation_conflicts.is_empty());
        for (k, face) in r.soup.faces().enumerate() {
            let mut want = reversed[k].clone();
            if k == 7 || k == 30 {
                want[1..].reverse();
            }
            assert_eq!(face, &want[..]);
        }
        let fixed = SurfaceMesh::from_soup(&r.soup).unwrap();
        assert_eq!(fixed.flipped_faces(), 0);
        assert!(crate::geom::volume(&fixed) > 0.0);

        // a Möbius strip of 12 quads cannot be oriented: reported, not hidden
        let n = 12u32;
        let mut p = Vec::new();
        for i in 0..n {
            let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            for s in [-0.3, 0.3] {
                let w = s * (t / 2.0).cos();
                p.push(Vec3::new(
                    (1.0 + w) * t.cos(),
                    (1.0 + w) * t.sin(),
                    s * (t / 2.0).sin(),
                ));
            }
        }
        let faces: Vec<[u32; 4]> = (0..n)
            .map(|i| {
                let (c, d) = if i + 1 < n {
                    (2 * i + 2, 2 * i + 3)
                } else {
                    (1, 0)
                };
                [2 * i, c, d, 2 * i + 1]
            })
            .collect();
        let r = repair(&Soup::from_polygons(p, &faces), &RepairOptions::default()).unwrap();
        assert!(!r.report.orientation_conflicts.is_empty());
        assert!(!r.report.manifold);
        assert!(
            r.report
                .remaining_problem
                .as_deref()
                .is_some_and(|e| e.contains("oriented"))
        );
    }

    #[test]
    fn non_finite_coordinates_are_refused() {
        let mut p = square();
        p[2].z = f64::NAN;
        let e = repair(
            &Soup::from_polygons(p, &[[0u32, 1, 2]]),
            &RepairOptions::default(),
        )
        .unwrap_err();
        assert_eq!(
            e,
            RepairError::Mesh(MeshError::NonFiniteCoordinate { vertex: 2 })
        );
        assert_eq!(
            e.to_string(),
            MeshError::NonFiniteCoordinate { vertex: 2 }.to_string()
        );
    }
}
