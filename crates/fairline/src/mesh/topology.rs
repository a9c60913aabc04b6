//! Topology queries over a [`SurfaceMesh`]: boundary loops, connected
//! components, Euler characteristic and genus, triangulation of polygons and
//! structure lines of quad meshes.

use super::{FaceId, HalfedgeId, MeshError, SurfaceMesh, VertexId};
use crate::Vec3;
use std::collections::HashSet;

/// Boundary loops as sequences of boundary halfedges (each loop in order).
pub fn boundary_loops(mesh: &SurfaceMesh) -> Vec<Vec<HalfedgeId>> {
    let mut seen = vec![false; mesh.halfedge_count()];
    let mut loops = Vec::new();
    for h in mesh.halfedges() {
        if seen[h.idx()] || !mesh.is_boundary_halfedge(h) {
            continue;
        }
        let mut lp = Vec::new();
        let mut c = h;
        while !seen[c.idx()] {
            seen[c.idx()] = true;
            lp.push(c);
            c = mesh.next(c);
        }
        loops.push(lp);
    }
    loops
}

/// Connected components: a label per vertex (isolated vertices get their own
/// component) and the number of components. Labels are numbered in order of
/// each component's smallest vertex. Union–find over the edge array (one
/// sequential pass, no circulation).
pub fn components(mesh: &SurfaceMesh) -> (Vec<u32>, usize) {
    let n = mesh.vertex_count();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for e in mesh.edges() {
        let (a, b) = mesh.edge_vertices(e);
        super::union_find::union(&mut parent, a.0, b.0);
    }
    // roots are the smallest vertex of their component (union keeps the
    // smaller root), so labels follow the first vertex of each component
    let mut label = vec![u32::MAX; n];
    let mut count = 0u32;
    for v in 0..n {
        let r = super::union_find::find(&mut parent, v as u32) as usize;
        if label[r] == u32::MAX {
            label[r] = count;
            count += 1;
        }
        label[v] = label[r];
    }
    (label, count as usize)
}

/// Counts that describe a mesh's topology.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct TopologySummary {
    /// Number of vertices (isolated ones included).
    pub vertices: usize,
    /// Number of edges.
    pub edges: usize,
    /// Number of faces.
    pub faces: usize,
    /// Number of boundary edges.
    pub boundary_edges: usize,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Connected components (isolated vertices excluded).
    pub components: usize,
    /// Isolated vertices (no face).
    pub isolated_vertices: usize,
    /// Euler characteristic V − E + F (isolated vertices excluded).
    pub euler_characteristic: i64,
    /// Sum over components of the genus g from χ = 2 − 2g − b.
    pub genus: i64,
}

/// Euler characteristic, genus and friends. Genus is computed per component
/// from χ_c = 2 − 2g_c − b_c and summed.
pub fn topology_summary(mesh: &SurfaceMesh) -> TopologySummary {
    let (label, ncomp) = components(mesh);
    let loops = boundary_loops(mesh);
    let mut v_c = vec![0i64; ncomp];
    let mut e_c = vec![0i64; ncomp];
    let mut f_c = vec![0i64; ncomp];
    let mut b_c = vec![0i64; ncomp];
    let mut isolated = 0usize;
    let mut is_iso_comp = vec![false; ncomp];
    for v in mesh.vertices() {
        if mesh.is_isolated(v) {
            isolated += 1;
            is_iso_comp[label[v.idx()] as usize] = true;
        } else {
            v_c[label[v.idx()] as usize] += 1;
        }
    }
    for e in mesh.edges() {
        let (a, _) = mesh.edge_vertices(e);
        e_c[label[a.idx()] as usize] += 1;
    }
    for f in mesh.faces() {
        let v = mesh.to_vertex(mesh.face_halfedge(f));
        f_c[label[v.idx()] as usize] += 1;
    }
    for lp in &loops {
        let v = mesh.to_vertex(lp[0]);
        b_c[label[v.idx()] as usize] += 1;
    }
    let mut genus = 0i64;
    let mut chi_total = 0i64;
    let mut comps = 0usize;
    for c in 0..ncomp {
        if is_iso_comp[c] {
            continue;
        }
        comps += 1;
        let chi = v_c[c] - e_c[c] + f_c[c];
        chi_total += chi;
        genus += ((2 - chi - b_c[c]) / 2).max(0);
    }
    TopologySummary {
        vertices: mesh.vertex_count(),
        edges: mesh.edge_count(),
        faces: mesh.face_count(),
        boundary_edges: mesh.edges().filter(|&e| mesh.is_boundary_edge(e)).count(),
        boundary_loops: loops.len(),
        components: comps,
        isolated_vertices: isolated,
        euler_characteristic: chi_total,
        genus,
    }
}

/// A triangulated copy of a polygon mesh and where each triangle came from.
#[derive(Clone, Debug)]
pub struct Triangulation {
    /// The triangle mesh (same vertices, same indices).
    pub mesh: SurfaceMesh,
    /// For each triangle, the polygon of the input it belongs to.
    pub source_face: Vec<FaceId>,
}

/// Triangulates every polygon. Triangles are kept; quads are split along the
/// shorter diagonal; larger polygons are ear-clipped in the plane of their
/// Newell normal (a fan from the first vertex if ear clipping gets stuck on a
/// self-intersecting polygon). Vertex indices are unchanged.
/// Split non-manifold vertices stay split and pinned in the triangulation.
///
/// A diagonal that is already an edge of the mesh, or that another polygon's
/// split already added, would give an edge of three or four triangles (a
/// valence-2 vertex between two quads, T-junction quads); such a split is
/// replaced by the other diagonal of a quad, or by a fan from another corner
/// of a larger polygon, whose diagonals are all new edges.
///
/// # Errors
/// [`MeshError::NoTriangulation`] naming the polygon when every such split
/// would duplicate an edge (every diagonal of it is already an edge).
pub fn triangulate(mesh: &SurfaceMesh) -> Result<Triangulation, MeshError> {
    let (tris, source) = split_polygons(mesh, true)?;
    let mut triangles = SurfaceMesh::new(mesh.positions().to_vec(), &tris)?;
    triangles.inherit_split_vertices(mesh);
    Ok(Triangulation {
        mesh: triangles,
        source_face: source,
    })
}

/// The triangles of every polygon for drawing only: the same splits as
/// [`triangulate`] where those exist, otherwise the preferred split even if it
/// duplicates an edge (a picture does not need a manifold triangle list).
pub fn triangle_list(mesh: &SurfaceMesh) -> Vec<[u32; 3]> {
    match split_polygons(mesh, true) {
        Ok((tris, _)) => tris,
        Err(_) => split_polygons(mesh, false)
            .map(|(tris, _)| tris)
            .unwrap_or_default(),
    }
}

/// Splits every polygon into triangles; with `avoid_duplicates`, no diagonal
/// is an existing edge or a diagonal already added (see [`triangulate`]).
fn split_polygons(
    mesh: &SurfaceMesh,
    avoid_duplicates: bool,
) -> Result<(Vec<[u32; 3]>, Vec<FaceId>), MeshError> {
    let p = mesh.positions();
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(mesh.face_count() * 2);
    let mut source = Vec::with_capacity(mesh.face_count() * 2);
    let mut poly = Vec::new();
    // diagonals added so far, as (smaller, larger) vertex index
    let mut added: HashSet<(u32, u32)> = HashSet::new();
    let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
    for f in mesh.faces() {
        poly.clear();
        poly.extend(mesh.face_vertices(f).map(|v| v.0));
        let first = tris.len();
        match poly.len() {
            3 => tris.push([poly[0], poly[1], poly[2]]),
            4 => {
                let d02 = p[poly[0] as usize].distance_squared(p[poly[2] as usize]);
                let d13 = p[poly[1] as usize].distance_squared(p[poly[3] as usize]);
                let split_at = |k: usize, tris: &mut Vec<[u32; 3]>| {
                    let [a, b, c, d] = [0, 1, 2, 3].map(|i| poly[(i + k) % 4]);
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                };
                split_at(if d02 <= d13 { 0 } else { 1 }, &mut tris);
            }
            _ => ear_clip(p, &poly, &mut tris),
        }
        if avoid_duplicates && poly.len() > 3 {
            let is_free = |tris: &[[u32; 3]], added: &HashSet<(u32, u32)>| {
                polygon_diagonals(&poly, tris).all(|(a, b)| {
                    !added.contains(&key(a, b))
                        && mesh.find_halfedge(VertexId(a), VertexId(b)).is_none()
                })
            };
            if !is_free(&tris[first..], &added) {
                // fans from each corner in turn (for a quad: the other diagonal)
                let mut found = false;
                for k in 0..poly.len() {
                    tris.truncate(first);
                    for i in 1..poly.len() - 1 {
                        let at = |j: usize| poly[(j + k) % poly.len()];
                        tris.push([at(0), at(i), at(i + 1)]);
                    }
                    if is_free(&tris[first..], &added) {
                        found = true;
                        break;
                    }
                }
                if !found {
                    return Err(MeshError::NoTriangulation { face: f.idx() });
                }
            }
            for (a, b) in polygon_diagonals(&poly, &tris[first..]) {
                added.insert(key(a, b));
            }
        }
        source.resize(tris.len(), f);
    }
    Ok((tris, source))
}

/// The edges of `tris` (the triangles of one polygon) that are not sides of
/// `poly`: the diagonals the split adds (each reported once per triangle side).
fn polygon_diagonals<'a>(
    poly: &'a [u32],
    tris: &'a [[u32; 3]],
) -> impl Iterator<Item = (u32, u32)> + 'a {
    let n = poly.len();
    let is_side = move |a: u32, b: u32| {
        (0..n).any(|i| {
            let (u, v) = (poly[i], poly[(i + 1) % n]);
            (u == a && v == b) || (u == b && v == a)
        })
    };
    tris.iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(move |&(a, b)| !is_side(a, b))
}

fn ear_clip(p: &[Vec3], poly: &[u32], out: &mut Vec<[u32; 3]>) {
    // Newell normal and a 2D frame in its plane.
    let mut n = Vec3::ZERO;
    for i in 0..poly.len() {
        let a = p[poly[i] as usize];
        let b = p[poly[(i + 1) % poly.len()] as usize];
        n += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let len = n.length();
    if !(len > 0.0) {
        fan(poly, out);
        return;
    }
    let n = n / len;
    let u = n.any_orthonormal_vector();
    let w = n.cross(u);
    let q: Vec<(f64, f64)> = poly
        .iter()
        .map(|&i| (p[i as usize].dot(u), p[i as usize].dot(w)))
        .collect();
    let mut idx: Vec<usize> = (0..poly.len()).collect();
    let cross = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    let mut guard = 0;
    while idx.len() > 3 && guard < 4 * poly.len() * poly.len() {
        guard += 1;
        let m = idx.len();
        let mut clipped = false;
        for k in 0..m {
            let (ia, ib, ic) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (a, b, c) = (q[ia], q[ib], q[ic]);
            if cross(a, b, c) <= 0.0 {
                continue; // reflex or degenerate corner
            }
            let inside = idx.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let x = q[j];
                cross(a, b, x) >= 0.0 && cross(b, c, x) >= 0.0 && cross(c, a, x) >= 0.0
            });
            if inside {
                continue;
            }
            out.push([poly[ia], poly[ib], poly[ic]]);
            idx.remove(k);
            clipped = true;
            break;
        }
        if !clipped {
            break;
        }
    }
    if idx.len() == 3 {
        out.push([poly[idx[0]], poly[idx[1]], poly[idx[2]]]);
    } else {
        let rest: Vec<u32> = idx.iter().map(|&i| poly[i]).collect();
        fan(&rest, out);
    }
}

fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for i in 1..poly.len() - 1 {
        out.push([poly[0], poly[i], poly[i + 1]]);
    }
}

/// A structure line of a quad mesh: a chain of vertices that runs straight
/// through regular vertices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StructureLine {
    /// The vertices in order. For a closed line the first vertex is not repeated.
    pub vertices: Vec<VertexId>,
    /// True when the line closes on itself.
    pub closed: bool,
}

/// Whether a line arriving at `v` by halfedge `h` (ending at `v`) continues,
/// and along which outgoing halfedge. Straight continuation exists through
/// interior vertices of valence 4 (the outgoing halfedge two steps around from
/// the one we came along) and through boundary vertices of valence 3 when
/// arriving along a boundary edge (continue along the other boundary edge).
fn straight_continuation(mesh: &SurfaceMesh, h: HalfedgeId) -> Option<HalfedgeId> {
    let v = mesh.to_vertex(h);
    let back = mesh.opposite(h);
    let valence = mesh.valence(v);
    if !mesh.is_boundary_vertex(v) {
        if valence == 4 {
            return Some(mesh.cw_rotated(mesh.cw_rotated(back)));
        }
        return None;
    }
    if valence == 3 && mesh.is_boundary_edge(mesh.edge(h)) {
        // the outgoing boundary-edge halfedges of v are the stored boundary
        // halfedge and the opposite of the incoming boundary halfedge
        let out_b = mesh.vertex_halfedge(v)?;
        let in_b_opp = mesh.ccw_rotated(out_b);
        let other = if back == out_b { in_b_opp } else { out_b };
        if other == back {
            return None;
        }
        return Some(other);
    }
    None
}

/// Traces the structure lines of a (quad-dominant) mesh: maximal chains of
/// edges that pass straight through regular vertices (valence 4 inside,
/// valence 3 on the boundary along the boundary). Every edge belongs to
/// exactly one line. Lines start and end at irregular vertices, corners or
/// boundary vertices; lines that meet only regular vertices close on
/// themselves.
pub fn structure_lines(mesh: &SurfaceMesh) -> Vec<StructureLine> {
    let mut used = vec![false; mesh.edge_count()];
    let mut lines = Vec::new();
    let trace = |start: HalfedgeId, used: &mut Vec<bool>| -> StructureLine {
        let mut verts = vec![mesh.from_vertex(start)];
        let mut h = start;
        let mut closed = false;
        loop {
            used[mesh.edge(h).idx()] = true;
            let v = mesh.to_vertex(h);
            match straight_continuation(mesh, h) {
                Some(n) if n == start => {
                    closed = true;
                    break;
                }
                Some(n) if !used[mesh.edge(n).idx()] => {
                    verts.push(v);
                    h = n;
                }
                _ => {
                    verts.push(v);
                    break;
                }
            }
        }
        StructureLine {
            vertices: verts,
            closed,
        }
    };
    // Open lines: start wherever the line cannot be continued backwards.
    for h in mesh.halfedges() {
        if used[mesh.edge(h).idx()] || mesh.is_isolated(mesh.from_vertex(h)) {
            continue;
        }
        let back = mesh.opposite(h);
        if straight_continuation(mesh, back).is_some() {
            continue;
        }
        lines.push(trace(h, &mut used));
    }
    // Whatever is left runs through regular vertices only: closed loops.
    for h in mesh.halfedges() {
        if used[mesh.edge(h).idx()] {
            continue;
        }
        lines.push(trace(h, &mut used));
    }
    lines
}
