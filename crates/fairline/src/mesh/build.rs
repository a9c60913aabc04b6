//! Building a [`SurfaceMesh`] from a [`Soup`], in named steps:
//!
//! 1. [`validate`]: indices in range, faces of ≥ 3 distinct vertices, finite
//!    coordinates (parallel; the first offending element is named).
//! 2. [`match_edges`]: undirected edges by a counting sort of the corners on
//!    their smaller vertex, then a sort of each (small) group on the larger
//!    vertex; no hashing. Edges of more than two faces are refused.
//! 3. [`orient`]: a breadth-first search over faces that reverses faces
//!    disagreeing with their component's first face.
//! 4. [`link_faces`] and [`link_boundary`]: the halfedge arrays.
//! 5. [`find_fans`]: every vertex must be one fan of faces; where several fans
//!    meet (two cones touching at a tip, a bow tie), the builder splits the
//!    vertex, one copy per fan ([`split_fans`]), and builds again. Copies are
//!    appended after the input vertices and remembered, so that output merges
//!    them back bit-identical (as PMP and OpenMesh do when reading such files).

use super::MeshError;
use super::soup::Soup;
use super::surface_mesh::{Halfedges, NONE, SplitVertices, SurfaceMesh};
use super::union_find::{find, union};
use rayon::prelude::*;

/// Below this many faces the parallel steps run sequentially.
const PARALLEL_FACES: usize = 20_000;

/// Step 1: refuses out-of-range indices, faces with fewer than three
/// vertices or a repeated vertex, and non-finite coordinates, naming the
/// first offending face or vertex.
pub(super) fn validate(soup: &Soup) -> Result<(), MeshError> {
    let nv = soup.positions.len();
    if nv >= NONE as usize / 2 || soup.indices.len() >= NONE as usize / 2 {
        return Err(MeshError::TooLarge);
    }
    let bad_vertex = if nv >= PARALLEL_FACES {
        soup.positions.par_iter().position_first(|p| !p.is_finite())
    } else {
        soup.positions.iter().position(|p| !p.is_finite())
    };
    if let Some(v) = bad_vertex {
        return Err(MeshError::NonFiniteCoordinate { vertex: v });
    }
    let check = |f: usize| -> Option<MeshError> {
        let face = soup.face(f);
        if face.len() < 3 {
            return Some(MeshError::FaceTooSmall {
                face: f,
                size: face.len(),
            });
        }
        for (i, &a) in face.iter().enumerate() {
            if a as usize >= nv {
                return Some(MeshError::IndexOutOfRange {
                    face: f,
                    index: a as usize,
                    vertices: nv,
                });
            }
            if face[..i].contains(&a) {
                return Some(MeshError::RepeatedVertex {
                    face: f,
                    vertex: a as usize,
                });
            }
        }
        None
    };
    let nf = soup.face_count();
    let first = if nf >= PARALLEL_FACES {
        (0..nf).into_par_iter().find_map_first(check)
    } else {
        (0..nf).find_map(check)
    };
    match first {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The undirected edges of a soup and which corners use them.
///
/// Corner `c` is position `c` of `soup.indices`; "the edge of corner `c`"
/// runs from its vertex to the next vertex of its face.
pub(super) struct EdgeTable {
    /// Edge of every corner.
    pub corner_edge: Vec<u32>,
    /// Face of every corner.
    pub corner_face: Vec<u32>,
    /// The two vertices of every edge, smaller first.
    pub lo_hi: Vec<(u32, u32)>,
    /// Up to two incidences of every edge; `NONE` when absent.
    pub incidences: Vec<Incidence>,
}

/// The faces on one edge as (face, corner) pairs.
pub(super) type Incidence = [(u32, u32); 2];

/// A chunk of vertex groups and its ranges of the edge arrays.
type EdgeChunk<'a> = (usize, &'a mut [(u32, u32)], &'a mut [Incidence]);

/// Step 2: matches the corners of all faces into undirected edges. Edges are
/// numbered by (smaller vertex, larger vertex), so the numbering depends only
/// on the face list. Refuses an edge used by more than two faces, or twice by
/// one face.
pub(super) fn match_edges(soup: &Soup) -> Result<EdgeTable, MeshError> {
    let nv = soup.positions.len();
    let nf = soup.face_count();
    let corners = soup.indices.len();
    // Counting sort of the corners on the smaller vertex of their edge.
    let mut start = vec![0u32; nv + 1];
    let mut corner_face = vec![0u32; corners];
    for f in 0..nf {
        let (s, t) = (soup.offsets[f] as usize, soup.offsets[f + 1] as usize);
        let face = &soup.indices[s..t];
        for i in 0..face.len() {
            let (a, b) = (face[i], face[if i + 1 == face.len() { 0 } else { i + 1 }]);
            start[a.min(b) as usize + 1] += 1;
            corner_face[s + i] = f as u32;
        }
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    // entry: (larger vertex, corner); corners ascend within a group, and so
    // do their faces.
    let mut entries: Vec<(u32, u32)> = vec![(0, 0); corners];
    let mut fill = start.clone();
    for f in 0..nf {
        let (s, t) = (soup.offsets[f] as usize, soup.offsets[f + 1] as usize);
        let face = &soup.indices[s..t];
        for i in 0..face.len() {
            let (a, b) = (face[i], face[if i + 1 == face.len() { 0 } else { i + 1 }]);
            let lo = a.min(b) as usize;
            entries[fill[lo] as usize] = (a.max(b), (s + i) as u32);
            fill[lo] += 1;
        }
    }
    drop(fill);
    // Each group (corners of one smaller vertex) is sorted on the larger
    // vertex and counted, in parallel over chunks of whole groups; then the
    // edges of each chunk are written into its own range of the edge arrays.
    let chunks = group_chunks(&start, nf >= PARALLEL_FACES);
    let mut slices: Vec<&mut [(u32, u32)]> = Vec::with_capacity(chunks.len());
    let mut rest: &mut [(u32, u32)] = &mut entries;
    for w in chunks.windows(2) {
        let len = (start[w[1]] - start[w[0]]) as usize;
        let (head, tail) = rest.split_at_mut(len);
        slices.push(head);
        rest = tail;
    }
    let count_chunk = |(k, slice): (usize, &mut [(u32, u32)])| -> Result<usize, MeshError> {
        let base = start[chunks[k]];
        let mut edges = 0;
        for lo in chunks[k]..chunks[k + 1] {
            let group = &mut slice[(start[lo] - base) as usize..(start[lo + 1] - base) as usize];
            if group.len() > 1 {
                // corners ascend within a group, so this is stable on them
                group.sort_unstable();
            }
            let mut i = 0;
            while i < group.len() {
                let hi = group[i].0;
                let mut j = i + 1;
                while j < group.len() && group[j].0 == hi {
                    j += 1;
                }
                let face_of = |k: usize| corner_face[group[k].1 as usize];
                if j - i > 2 || (j - i == 2 && face_of(i) == face_of(i + 1)) {
                    return Err(MeshError::NonManifoldEdge {
                        v0: lo,
                        v1: hi as usize,
                        faces: (i..j).map(|k| face_of(k) as usize).collect(),
                    });
                }
                edges += 1;
                i = j;
            }
        }
        Ok(edges)
    };
    let counts: Vec<Result<usize, MeshError>> = if chunks.len() > 2 {
        slices
            .into_par_iter()
            .enumerate()
            .map(count_chunk)
            .collect()
    } else {
        slices.into_iter().enumerate().map(count_chunk).collect()
    };
    let mut edge_start = Vec::with_capacity(counts.len() + 1);
    edge_start.push(0usize);
    for c in counts {
        let n = c?;
        edge_start.push(edge_start[edge_start.len() - 1] + n);
    }
    let ne = edge_start[edge_start.len() - 1];
    let mut lo_hi: Vec<(u32, u32)> = vec![(0, 0); ne];
    let mut incidences: Vec<Incidence> = vec![[(NONE, NONE); 2]; ne];
    let mut parts: Vec<EdgeChunk> = Vec::new();
    let (mut lh, mut inc): (&mut [(u32, u32)], &mut [Incidence]) = (&mut lo_hi, &mut incidences);
    for k in 0..edge_start.len() - 1 {
        let len = edge_start[k + 1] - edge_start[k];
        let (a, b) = lh.split_at_mut(len);
        let (c, d) = inc.split_at_mut(len);
        parts.push((k, a, c));
        lh = b;
        inc = d;
    }
    let fill_chunk = |(k, lo_hi, incidences): EdgeChunk| {
        let mut e = 0;
        for lo in chunks[k]..chunks[k + 1] {
            let group = &entries[start[lo] as usize..start[lo + 1] as usize];
            let mut i = 0;
            while i < group.len() {
                let hi = group[i].0;
                lo_hi[e] = (lo as u32, hi);
                incidences[e][0] = (corner_face[group[i].1 as usize], group[i].1);
                if i + 1 < group.len() && group[i + 1].0 == hi {
                    incidences[e][1] = (corner_face[group[i + 1].1 as usize], group[i + 1].1);
                    i += 2;
                } else {
                    i += 1;
                }
                e += 1;
            }
        }
    };
    if chunks.len() > 2 {
        parts.into_par_iter().for_each(fill_chunk);
    } else {
        parts.into_iter().for_each(fill_chunk);
    }
    drop(entries);
    let mut corner_edge = vec![0u32; corners];
    for (e, inc) in incidences.iter().enumerate() {
        corner_edge[inc[0].1 as usize] = e as u32;
        if inc[1].1 != NONE {
            corner_edge[inc[1].1 as usize] = e as u32;
        }
    }
    Ok(EdgeTable {
        corner_edge,
        corner_face,
        lo_hi,
        incidences,
    })
}

/// Boundaries of chunks of whole vertex groups (vertex indices, first 0,
/// last `nv`) with about equal numbers of corners: one chunk when
/// sequential.
fn group_chunks(start: &[u32], parallel: bool) -> Vec<usize> {
    let nv = start.len() - 1;
    let total = start[nv] as usize;
    let pieces = if parallel { 64 } else { 1 };
    let mut bounds = vec![0usize];
    for k in 1..pieces {
        let target = (total * k / pieces) as u32;
        let v = start.partition_point(|&s| s < target).min(nv);
        if v > bounds[bounds.len() - 1] {
            bounds.push(v);
        }
    }
    if bounds[bounds.len() - 1] < nv || bounds.len() == 1 {
        bounds.push(nv);
    }
    bounds
}

/// Step 3: which faces to reverse so that every interior edge is traversed
/// in opposite directions by its two faces (breadth-first over faces, the
/// first face of each component keeps its order). Returns the flags (1 =
/// reverse) and how many faces are reversed; refuses a component that cannot
/// be oriented (Möbius strip), naming a face of the conflict.
pub(super) fn orient(soup: &Soup, edges: &EdgeTable) -> Result<(Vec<u8>, usize), MeshError> {
    let nf = soup.face_count();
    if consistently_oriented(soup, edges) {
        // the search would keep every face as it is
        return Ok((vec![0; nf], 0));
    }
    let mut flip: Vec<u8> = vec![2; nf]; // 2 = unvisited
    let mut queue = Vec::new();
    let mut flipped = 0usize;
    for seed in 0..nf {
        if flip[seed] != 2 {
            continue;
        }
        flip[seed] = 0;
        queue.clear();
        queue.push(seed as u32);
        while let Some(f) = queue.pop() {
            let f = f as usize;
            let (s, t) = (soup.offsets[f] as usize, soup.offsets[f + 1] as usize);
            for c in s..t {
                let e = edges.corner_edge[c] as usize;
                let inc = edges.incidences[e];
                if inc[1].0 == NONE {
                    continue;
                }
                let (me, other) = if inc[0].1 as usize == c {
                    (inc[0], inc[1])
                } else {
                    (inc[1], inc[0])
                };
                let g = other.0 as usize;
                let lo = edges.lo_hi[e].0;
                let forward = |corner: u32| soup.indices[corner as usize] == lo;
                // Consistent when the two faces traverse the edge in opposite
                // directions after flipping.
                let want = if forward(me.1) == forward(other.1) {
                    1 - flip[f]
                } else {
                    flip[f]
                };
                if flip[g] == 2 {
                    flip[g] = want;
                    flipped += want as usize;
                    queue.push(g as u32);
                } else if flip[g] != want {
                    return Err(MeshError::NonOrientable { face: g });
                }
            }
        }
    }
    Ok((flip, flipped))
}

/// True when the two faces of every interior edge traverse it in opposite
/// directions (the usual input): then [`orient`] reverses nothing, and its
/// sequential search is skipped for this parallel check.
fn consistently_oriented(soup: &Soup, edges: &EdgeTable) -> bool {
    let consistent = |e: usize| {
        let [(_, c), (g, d)] = edges.incidences[e];
        let lo = edges.lo_hi[e].0;
        g == NONE || (soup.indices[c as usize] == lo) != (soup.indices[d as usize] == lo)
    };
    let ne = edges.incidences.len();
    if ne >= PARALLEL_FACES {
        (0..ne).into_par_iter().all(consistent)
    } else {
        (0..ne).all(consistent)
    }
}

/// One halfedge's entries of the arrays `to`, `next`, `prev` and `face`, as
/// zipped iterators hand them out.
type LinkSlots<'a> = (((&'a mut u32, &'a mut u32), &'a mut u32), &'a mut u32);

/// Step 4a: the halfedges of every face, in the face's (possibly reversed)
/// order. Edge `e` owns halfedges `2e` (smaller → larger vertex) and `2e + 1`.
///
/// Every halfedge is found from its own edge's corners (a gather, parallel
/// over halfedges): corner `c` stands for the halfedge of the edge from
/// corner `c` to the next corner of its face, walked in the face's order
/// (from the next corner back to `c` when the face is reversed).
pub(super) fn link_faces(
    soup: &Soup,
    edges: &EdgeTable,
    flip: &[u8],
) -> Result<Halfedges, MeshError> {
    let nf = soup.face_count();
    let nh = 2 * edges.lo_hi.len();
    let parallel = nf >= PARALLEL_FACES;
    let face_range = |f: usize| (soup.offsets[f] as usize, soup.offsets[f + 1] as usize);
    // the corners after and before corner `c` of face `f`
    let after = |c: usize, (s, t): (usize, usize)| if c + 1 == t { s } else { c + 1 };
    let before = |c: usize, (s, t): (usize, usize)| if c == s { t - 1 } else { c - 1 };
    let half_of = |c: usize| -> u32 {
        let f = edges.corner_face[c] as usize;
        let c1 = after(c, face_range(f));
        let from = if flip[f] == 1 {
            soup.indices[c1]
        } else {
            soup.indices[c]
        };
        let e = edges.corner_edge[c];
        if edges.lo_hi[e as usize].0 == from {
            2 * e
        } else {
            2 * e + 1
        }
    };
    let corners = soup.indices.len();
    let corner_half: Vec<u32> = if parallel {
        (0..corners).into_par_iter().map(half_of).collect()
    } else {
        (0..corners).map(half_of).collect()
    };
    // the (face, corner) of halfedge h: the incidence of its edge whose
    // corner stands for it
    let owner = |h: usize| -> Option<(usize, usize)> {
        edges.incidences[h / 2]
            .iter()
            .find(|&&(f, c)| f != NONE && corner_half[c as usize] as usize == h)
            .map(|&(f, c)| (f as usize, c as usize))
    };
    // two faces that walk one edge in the same direction: orientation
    // reports this first, so only reachable through an inconsistent table;
    // named as the face order meets it (the later face of the first pair)
    let conflict = |e: usize| -> Option<usize> {
        let [(f, c), (g, d)] = edges.incidences[e];
        (g != NONE && corner_half[c as usize] == corner_half[d as usize]).then(|| f.max(g) as usize)
    };
    let ne = edges.lo_hi.len();
    let first_conflict = if parallel {
        (0..ne).into_par_iter().filter_map(conflict).min()
    } else {
        (0..ne).filter_map(conflict).min()
    };
    if let Some(face) = first_conflict {
        return Err(MeshError::NonOrientable { face });
    }
    let mut to = vec![0u32; nh];
    let mut next = vec![NONE; nh];
    let mut prev = vec![NONE; nh];
    let mut face = vec![NONE; nh];
    let link = |(h, (((to, next), prev), face)): (usize, LinkSlots)| {
        let (lo, hi) = edges.lo_hi[h / 2];
        *to = if h % 2 == 0 { hi } else { lo };
        if let Some((f, c)) = owner(h) {
            let range = face_range(f);
            let (n, p) = if flip[f] == 1 {
                (before(c, range), after(c, range))
            } else {
                (after(c, range), before(c, range))
            };
            *next = corner_half[n];
            *prev = corner_half[p];
            *face = f as u32;
        }
    };
    if parallel {
        to.par_iter_mut()
            .zip(next.par_iter_mut())
            .zip(prev.par_iter_mut())
            .zip(face.par_iter_mut())
            .enumerate()
            .for_each(link);
    } else {
        to.iter_mut()
            .zip(next.iter_mut())
            .zip(prev.iter_mut())
            .zip(face.iter_mut())
            .enumerate()
            .for_each(link);
    }
    // a face's first halfedge: that of its first corner, or of its last
    // when it is reversed
    let first = |f: usize| {
        let (s, t) = face_range(f);
        if flip[f] == 1 {
            corner_half[t - 1]
        } else {
            corner_half[s]
        }
    };
    let face_halfedge: Vec<u32> = if parallel {
        (0..nf).into_par_iter().map(first).collect()
    } else {
        (0..nf).map(first).collect()
    };
    Ok(Halfedges {
        to,
        next,
        prev,
        face,
        face_halfedge,
    })
}

/// Step 4b: links the boundary halfedges into loops and picks each vertex's
/// outgoing halfedge (its boundary halfedge on the boundary). Returns the
/// outgoing halfedges, or `None` when a vertex has two outgoing boundary
/// halfedges (several fans meet there): then the error names that vertex.
pub(super) fn link_boundary(nv: usize, he: &mut Halfedges) -> Result<Vec<u32>, usize> {
    let nh = he.to.len();
    let mut v_out = vec![NONE; nv];
    let mut boundary_out = vec![NONE; nv];
    for h in 0..nh {
        if he.face[h] == NONE {
            let from = he.to[h ^ 1] as usize;
            if boundary_out[from] != NONE {
                return Err(from);
            }
            boundary_out[from] = h as u32;
        }
    }
    for h in 0..nh {
        if he.face[h] == NONE {
            let n = boundary_out[he.to[h] as usize];
            he.next[h] = n;
            he.prev[n as usize] = h as u32;
        }
        let from = he.to[h ^ 1] as usize;
        if v_out[from] == NONE {
            v_out[from] = h as u32;
        }
    }
    for v in 0..nv {
        if boundary_out[v] != NONE {
            v_out[v] = boundary_out[v];
        }
    }
    Ok(v_out)
}

/// Step 5: the first vertex that is not a single fan (circulating from its
/// stored halfedge does not reach all of its outgoing halfedges), if any.
pub(super) fn first_multi_fan_vertex(he: &Halfedges, v_out: &[u32]) -> Option<usize> {
    let nv = v_out.len();
    let mut valence = vec![0u32; nv];
    for &from in he.to.iter().skip(1).step_by(2) {
        valence[from as usize] += 1;
    }
    for &to in he.to.iter().step_by(2) {
        valence[to as usize] += 1;
    }
    let one_fan = |v: usize| {
        let start = v_out[v];
        if start == NONE {
            return true;
        }
        let mut n = 0u32;
        let mut h = start;
        loop {
            n += 1;
            h = he.next[(h ^ 1) as usize];
            if h == start || n > valence[v] {
                break;
            }
        }
        n == valence[v]
    };
    if nv >= PARALLEL_FACES {
        (0..nv).into_par_iter().find_first(|&v| !one_fan(v))
    } else {
        (0..nv).find(|&v| !one_fan(v))
    }
}

/// Splits every vertex where several fans of faces meet: corners of a vertex
/// are joined when their faces share an edge at that vertex; the fan holding
/// the vertex's first corner keeps the vertex, every other fan gets a copy
/// appended after the input vertices (in order of vertex, then first corner).
/// Returns the rewritten soup and the original vertex of every copy, or
/// `None` when nothing needs splitting.
pub(super) fn split_fans(soup: &Soup, edges: &EdgeTable) -> Option<(Soup, Vec<u32>)> {
    let corners = soup.indices.len();
    let nv = soup.positions.len();
    let mut parent: Vec<u32> = (0..corners as u32).collect();
    // the corner after `c` in its face
    let next_corner = |c: u32, f: u32| -> u32 {
        let t = soup.offsets[f as usize + 1];
        if c + 1 == t {
            soup.offsets[f as usize]
        } else {
            c + 1
        }
    };
    for inc in &edges.incidences {
        let [(f, c), (g, d)] = *inc;
        if g == NONE {
            continue;
        }
        let (c1, d1) = (next_corner(c, f), next_corner(d, g));
        if soup.indices[c as usize] == soup.indices[d as usize] {
            union(&mut parent, c, d);
            union(&mut parent, c1, d1);
        } else {
            union(&mut parent, c, d1);
            union(&mut parent, c1, d);
        }
    }
    // The fan of the smallest corner of each vertex keeps the vertex.
    let mut keeper = vec![NONE; nv];
    for c in 0..corners as u32 {
        let v = soup.indices[c as usize] as usize;
        if keeper[v] == NONE {
            keeper[v] = find(&mut parent, c);
        }
    }
    // Copies for the other fans: (vertex, root) in order of first corner
    // within each vertex, vertices ascending.
    let mut others: Vec<(u32, u32, u32)> = Vec::new(); // (vertex, first corner, root)
    let mut seen_root = vec![false; corners];
    for c in 0..corners as u32 {
        let v = soup.indices[c as usize];
        let r = find(&mut parent, c);
        if r != keeper[v as usize] && !seen_root[r as usize] {
            seen_root[r as usize] = true;
            others.push((v, c, r));
        }
    }
    if others.is_empty() {
        return None;
    }
    others.sort_unstable();
    let mut copy_of_root = vec![NONE; corners];
    let mut source = Vec::with_capacity(others.len());
    let mut positions = soup.positions.clone();
    for &(v, _, r) in &others {
        copy_of_root[r as usize] = (nv + source.len()) as u32;
        source.push(v);
        positions.push(soup.positions[v as usize]);
    }
    let mut indices = soup.indices.clone();
    for (c, index) in indices.iter_mut().enumerate() {
        let copy = copy_of_root[find(&mut parent, c as u32) as usize];
        if copy != NONE {
            *index = copy;
        }
    }
    Some((
        Soup {
            positions,
            offsets: soup.offsets.clone(),
            indices,
        },
        source,
    ))
}

/// Builds the halfedge mesh of a soup whose vertices may be non-manifold;
/// see the module documentation.
pub(super) fn build(soup: &Soup) -> Result<SurfaceMesh, MeshError> {
    build_with_flips(soup).map(|(mesh, _)| mesh)
}

/// [`build`] of a soup that is given away: its positions become the mesh's
/// without a copy.
pub(super) fn build_owned(soup: Soup) -> Result<SurfaceMesh, MeshError> {
    Ok(match build_steps(&soup)? {
        Built::Input {
            he, v_out, flipped, ..
        } => SurfaceMesh::from_parts(soup.positions, he, v_out, flipped, None),
        Built::Split { mesh, .. } => mesh,
    })
}

/// [`build`], also returning which faces were reversed (1) for a consistent
/// orientation.
pub(super) fn build_with_flips(soup: &Soup) -> Result<(SurfaceMesh, Vec<u8>), MeshError> {
    Ok(match build_steps(soup)? {
        Built::Input {
            he,
            v_out,
            flipped,
            flip,
        } => {
            let positions = soup.positions.clone();
            let mesh = SurfaceMesh::from_parts(positions, he, v_out, flipped, None);
            (mesh, flip)
        }
        Built::Split { mesh, flip } => (mesh, flip),
    })
}

/// What the steps make of a soup.
enum Built {
    /// Connectivity over the input's vertices, as they are.
    Input {
        he: Halfedges,
        v_out: Vec<u32>,
        flipped: usize,
        flip: Vec<u8>,
    },
    /// Non-manifold vertices were split: a mesh with its own positions.
    Split { mesh: SurfaceMesh, flip: Vec<u8> },
}

/// Steps 1 to 5 of the module documentation.
fn build_steps(soup: &Soup) -> Result<Built, MeshError> {
    validate(soup)?;
    let edges = match_edges(soup)?;
    let (flip, flipped) = orient(soup, &edges)?;
    let mut he = link_faces(soup, &edges, &flip)?;
    let bad_vertex = match link_boundary(soup.positions.len(), &mut he) {
        Ok(v_out) => match first_multi_fan_vertex(&he, &v_out) {
            None => {
                return Ok(Built::Input {
                    he,
                    v_out,
                    flipped,
                    flip,
                });
            }
            Some(v) => v,
        },
        Err(v) => v,
    };
    // Several fans meet at some vertex: split it, one copy per fan.
    let refused = MeshError::NonManifoldVertex { vertex: bad_vertex };
    let (split, source) = split_fans(soup, &edges).ok_or(refused.clone())?;
    drop(edges);
    let nv = soup.positions.len();
    let edges = match_edges(&split)?;
    let (flip, flipped) = orient(&split, &edges)?;
    let mut he = link_faces(&split, &edges, &flip)?;
    let v_out = link_boundary(split.positions.len(), &mut he).map_err(|_| refused.clone())?;
    if first_multi_fan_vertex(&he, &v_out).is_some() {
        return Err(refused);
    }
    let mut marked = vec![false; split.positions.len()];
    for (j, &v) in source.iter().enumerate() {
        marked[v as usize] = true;
        marked[nv + j] = true;
    }
    let mesh = SurfaceMesh::from_parts(
        split.positions,
        he,
        v_out,
        flipped,
        Some(SplitVertices {
            original_vertices: nv,
            source,
            marked,
        }),
    );
    Ok(Built::Split { mesh, flip })
}

impl SurfaceMesh {
    /// Builds a mesh from a soup (see [`super::build`] for the steps).
    ///
    /// Rejects: indices out of range, faces with fewer than three vertices or
    /// a repeated vertex, non-finite coordinates, edges shared by more than
    /// two faces, and components whose faces cannot be oriented consistently
    /// (Möbius strips). Faces whose orientation disagrees with their
    /// component's first face are reversed (see [`SurfaceMesh::flipped_faces`]).
    ///
    /// A vertex where several fans of faces meet (a non-manifold vertex) is
    /// split, one copy per fan: the fan with the vertex's first corner keeps
    /// the index, the others get copies appended after the input vertices.
    /// The original and its copies are pinned ([`SurfaceMesh::is_pinned`]):
    /// no algorithm moves them, so [`SurfaceMesh::to_soup`] can merge the
    /// copies back and write the input's vertex list bit-identical.
    pub fn from_soup(soup: &Soup) -> Result<Self, MeshError> {
        build(soup)
    }

    /// [`SurfaceMesh::from_soup`] of a soup the caller no longer needs: its
    /// positions become the mesh's without a copy (what the mesh readers
    /// do). The same mesh, bit for bit.
    pub fn from_owned_soup(soup: Soup) -> Result<Self, MeshError> {
        build_owned(soup)
    }
}
