//! `SurfaceMesh`: an oriented 2-manifold polygon mesh with halfedge
//! connectivity, in the manner of PMP and OpenMesh.
//!
//! Halfedges come in pairs: edge `e` owns halfedges `2e` and `2e + 1`, so the
//! opposite of halfedge `h` is `h ^ 1`. Boundary halfedges have no face and
//! are linked into boundary loops. The outgoing halfedge stored for a boundary
//! vertex is its boundary halfedge, so circulating from it visits the whole fan.

use super::soup::Soup;
use super::{EdgeId, FaceId, HalfedgeId, MeshError, VertexId};
use crate::Vec3;

const NONE: u32 = u32::MAX;

/// Polygon mesh with halfedge connectivity. Built from a face list by
/// [`SurfaceMesh::new`] or [`SurfaceMesh::from_soup`], which reject
/// non-manifold and non-orientable input with an error naming the element.
#[derive(Clone, Debug)]
pub struct SurfaceMesh {
    positions: Vec<Vec3>,
    /// Target vertex of each halfedge.
    he_to: Vec<u32>,
    he_next: Vec<u32>,
    he_prev: Vec<u32>,
    /// Face of each halfedge (`NONE` on the boundary).
    he_face: Vec<u32>,
    /// One outgoing halfedge per vertex; the boundary one for boundary
    /// vertices; `NONE` for isolated vertices.
    v_out: Vec<u32>,
    /// One halfedge of each face.
    f_he: Vec<u32>,
    /// Number of faces whose orientation was reversed to make it consistent.
    flipped_faces: usize,
    /// The first face that is not a triangle (topology never changes after
    /// construction, so the triangle checks of every algorithm are O(1)).
    first_non_triangle: Option<u32>,
}

/// What the mesh builder did to the input besides building it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BuildNotes {
    /// Faces whose vertex order was reversed for a consistent orientation.
    pub flipped_faces: usize,
}

impl SurfaceMesh {
    /// Builds a mesh from positions and polygons (triangles, quads, n-gons).
    pub fn new<F: AsRef<[u32]>>(positions: Vec<Vec3>, faces: &[F]) -> Result<Self, MeshError> {
        let soup = Soup::from_polygons(positions, faces);
        Self::from_soup(&soup)
    }

    /// Builds a mesh from a soup.
    ///
    /// Rejects: indices out of range, faces with fewer than three vertices or
    /// a repeated vertex, non-finite coordinates, edges shared by more than
    /// two faces, vertices whose faces form more than one fan, and components
    /// whose faces cannot be oriented consistently (Möbius strips). Faces
    /// whose orientation disagrees with their component's first face are
    /// reversed (see [`SurfaceMesh::flipped_faces`]).
    pub fn from_soup(soup: &Soup) -> Result<Self, MeshError> {
        let nv = soup.positions.len();
        let nf = soup.face_count();
        if nv >= NONE as usize / 2 || soup.indices.len() >= NONE as usize / 2 {
            return Err(MeshError::TooLarge);
        }
        for (v, p) in soup.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(MeshError::NonFiniteCoordinate { vertex: v });
            }
        }
        for f in 0..nf {
            let face = soup.face(f);
            if face.len() < 3 {
                return Err(MeshError::FaceTooSmall {
                    face: f,
                    size: face.len(),
                });
            }
            for (i, &a) in face.iter().enumerate() {
                if a as usize >= nv {
                    return Err(MeshError::IndexOutOfRange {
                        face: f,
                        index: a as usize,
                        vertices: nv,
                    });
                }
                if face[..i].contains(&a) {
                    return Err(MeshError::RepeatedVertex {
                        face: f,
                        vertex: a as usize,
                    });
                }
            }
        }

        // Undirected edges: group corners by their smaller vertex (CSR).
        let corners = soup.indices.len();
        let mut count = vec![0u32; nv + 1];
        for f in 0..nf {
            let face = soup.face(f);
            for i in 0..face.len() {
                let (a, b) = (face[i], face[(i + 1) % face.len()]);
                count[a.min(b) as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            count[i + 1] += count[i];
        }
        // entry: (hi, face, corner index into soup.indices, forward = lo->hi)
        let mut entries: Vec<(u32, u32, u32, bool)> = vec![(0, 0, 0, false); corners];
        let mut fill = count.clone();
        for f in 0..nf {
            let start = soup.offsets[f];
            let face = soup.face(f);
            for i in 0..face.len() {
                let (a, b) = (face[i], face[(i + 1) % face.len()]);
                let lo = a.min(b) as usize;
                entries[fill[lo] as usize] = (a.max(b), f as u32, start + i as u32, a < b);
                fill[lo] += 1;
            }
        }
        // Edge id of every corner (the edge from corner i to corner i+1).
        let mut corner_edge = vec![0u32; corners];
        let mut edge_lo_hi: Vec<(u32, u32)> = Vec::with_capacity(corners / 2 + 1);
        // For each edge: up to two (face, forward) incidences.
        let mut edge_faces: Vec<[(u32, bool); 2]> = Vec::with_capacity(corners / 2 + 1);
        for lo in 0..nv {
            let group = &mut entries[count[lo] as usize..count[lo + 1] as usize];
            group.sort_unstable_by_key(|e| (e.0, e.1));
            let mut i = 0;
            while i < group.len() {
                let hi = group[i].0;
                let mut j = i;
                while j < group.len() && group[j].0 == hi {
                    j += 1;
                }
                if j - i > 2 {
                    return Err(MeshError::NonManifoldEdge {
                        v0: lo,
                        v1: hi as usize,
                        faces: group[i..j].iter().map(|e| e.1 as usize).collect(),
                    });
                }
                if j - i == 2 && group[i].1 == group[i + 1].1 {
                    // the same face uses the edge twice (a face that folds back)
                    return Err(MeshError::NonManifoldEdge {
                        v0: lo,
                        v1: hi as usize,
                        faces: vec![group[i].1 as usize, group[i + 1].1 as usize],
                    });
                }
                let e = edge_lo_hi.len() as u32;
                edge_lo_hi.push((lo as u32, hi));
                let mut inc = [(NONE, false); 2];
                for (k, g) in group[i..j].iter().enumerate() {
                    corner_edge[g.2 as usize] = e;
                    inc[k] = (g.1, g.3);
                }
                edge_faces.push(inc);
                i = j;
            }
        }
        let ne = edge_lo_hi.len();

        // Consistent orientation by breadth-first search over faces.
        let mut flip: Vec<u8> = vec![2; nf]; // 2 = unvisited
        let mut queue = Vec::new();
        let mut flipped_faces = 0usize;
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
                    let inc = edge_faces[corner_edge[c] as usize];
                    if inc[1].0 == NONE {
                        continue;
                    }
                    let (me, other) = if inc[0].0 as usize == f {
                        (inc[0], inc[1])
                    } else {
                        (inc[1], inc[0])
                    };
                    let g = other.0 as usize;
                    // Consistent when the two faces traverse the edge in
                    // opposite directions after flipping.
                    let want = if me.1 == other.1 {
                        1 - flip[f]
                    } else {
                        flip[f]
                    };
                    if flip[g] == 2 {
                        flip[g] = want;
                        if want == 1 {
                            flipped_faces += 1;
                        }
                        queue.push(g as u32);
                    } else if flip[g] != want {
                        return Err(MeshError::NonOrientable { face: g });
                    }
                }
            }
        }

        // Halfedges: edge e owns 2e (lo -> hi) and 2e + 1 (hi -> lo).
        let nh = 2 * ne;
        let mut he_to = vec![0u32; nh];
        for (e, &(lo, hi)) in edge_lo_hi.iter().enumerate() {
            he_to[2 * e] = hi;
            he_to[2 * e + 1] = lo;
        }
        let mut he_next = vec![NONE; nh];
        let mut he_prev = vec![NONE; nh];
        let mut he_face = vec![NONE; nh];
        let mut f_he = vec![NONE; nf];
        let mut face_hes: Vec<u32> = Vec::new();
        for f in 0..nf {
            let (s, t) = (soup.offsets[f] as usize, soup.offsets[f + 1] as usize);
            let n = t - s;
            face_hes.clear();
            for k in 0..n {
                // walk the face in its (possibly flipped) order
                let (a, c) = if flip[f] == 1 {
                    // reversed order: edge from corner s+k+1 to corner s+k
                    let c = s + (n - 1 - k);
                    let a = soup.indices[s + (c - s + 1) % n];
                    (a, c)
                } else {
                    (soup.indices[s + k], s + k)
                };
                let e = corner_edge[c] as usize;
                let h = if edge_lo_hi[e].0 == a {
                    2 * e
                } else {
                    2 * e + 1
                };
                if he_face[h] != NONE {
                    // cannot happen after orientation unless two faces share a
                    // directed edge, which orientation would have reported
                    return Err(MeshError::NonOrientable { face: f });
                }
                he_face[h] = f as u32;
                face_hes.push(h as u32);
            }
            for k in 0..n {
                let h = face_hes[k] as usize;
                let hn = face_hes[(k + 1) % n];
                he_next[h] = hn;
                he_prev[hn as usize] = h as u32;
            }
            f_he[f] = face_hes[0];
        }

        // Boundary halfedges: at most one outgoing per vertex.
        let mut v_out = vec![NONE; nv];
        let mut boundary_out = vec![NONE; nv];
        for h in 0..nh {
            if he_face[h] == NONE {
                let from = he_to[h ^ 1] as usize;
                if boundary_out[from] != NONE {
                    return Err(MeshError::NonManifoldVertex { vertex: from });
                }
                boundary_out[from] = h as u32;
            }
        }
        for h in 0..nh {
            if he_face[h] == NONE {
                let to = he_to[h] as usize;
                let n = boundary_out[to];
                he_next[h] = n;
                he_prev[n as usize] = h as u32;
            }
            let from = he_to[h ^ 1] as usize;
            if v_out[from] == NONE {
                v_out[from] = h as u32;
            }
        }
        for v in 0..nv {
            if boundary_out[v] != NONE {
                v_out[v] = boundary_out[v];
            }
        }
        let mut mesh = SurfaceMesh {
            positions: soup.positions.clone(),
            he_to,
            he_next,
            he_prev,
            he_face,
            v_out,
            f_he,
            flipped_faces,
            first_non_triangle: None,
        };
        mesh.first_non_triangle = (0..mesh.f_he.len() as u32).find(|&f| {
            let h = mesh.f_he[f as usize] as usize;
            mesh.he_next[mesh.he_next[mesh.he_next[h] as usize] as usize] as usize != h
        });

        // Every vertex must be a single fan: circulating from its stored
        // halfedge must reach all of its outgoing halfedges.
        let mut valence = vec![0u32; nv];
        for h in 0..nh {
            valence[mesh.he_to[h ^ 1] as usize] += 1;
        }
        for v in 0..nv {
            if mesh.v_out[v] == NONE {
                continue;
            }
            let mut n = 0u32;
            let start = mesh.v_out[v];
            let mut h = start;
            loop {
                n += 1;
                h = mesh.he_next[(h ^ 1) as usize];
                if h == start || n > valence[v] {
                    break;
                }
            }
            if n != valence[v] {
                return Err(MeshError::NonManifoldVertex { vertex: v });
            }
        }
        mesh.positions.shrink_to_fit();
        Ok(mesh)
    }

    /// What the builder changed: the number of faces it reversed.
    pub fn build_notes(&self) -> BuildNotes {
        BuildNotes {
            flipped_faces: self.flipped_faces,
        }
    }

    /// Number of faces whose orientation was reversed when building.
    pub fn flipped_faces(&self) -> usize {
        self.flipped_faces
    }

    // ---- sizes -------------------------------------------------------

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.f_he.len()
    }
    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.he_to.len() / 2
    }
    /// Number of halfedges (twice the edges).
    pub fn halfedge_count(&self) -> usize {
        self.he_to.len()
    }

    /// Iterator over vertex ids.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = VertexId> + use<> {
        (0..self.vertex_count() as u32).map(VertexId)
    }
    /// Iterator over face ids.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = FaceId> + use<> {
        (0..self.face_count() as u32).map(FaceId)
    }
    /// Iterator over edge ids.
    pub fn edges(&self) -> impl ExactSizeIterator<Item = EdgeId> + use<> {
        (0..self.edge_count() as u32).map(EdgeId)
    }
    /// Iterator over halfedge ids.
    pub fn halfedges(&self) -> impl ExactSizeIterator<Item = HalfedgeId> + use<> {
        (0..self.halfedge_count() as u32).map(HalfedgeId)
    }

    // ---- geometry ----------------------------------------------------

    /// All vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }
    /// Mutable vertex positions (connectivity is unaffected).
    pub fn positions_mut(&mut self) -> &mut [Vec3] {
        &mut self.positions
    }
    /// Replaces all positions; returns an error when the count differs.
    pub fn set_positions(&mut self, positions: Vec<Vec3>) -> Result<(), MeshError> {
        if positions.len() != self.positions.len() {
            return Err(MeshError::PositionCount {
                expected: self.positions.len(),
                got: positions.len(),
            });
        }
        self.positions = positions;
        Ok(())
    }
    /// Position of vertex `v`.
    #[inline]
    pub fn position(&self, v: VertexId) -> Vec3 {
        self.positions[v.idx()]
    }

    // ---- halfedge navigation ----------------------------------------

    /// Target vertex of `h`.
    #[inline]
    pub fn to_vertex(&self, h: HalfedgeId) -> VertexId {
        VertexId(self.he_to[h.idx()])
    }
    /// Source vertex of `h`.
    #[inline]
    pub fn from_vertex(&self, h: HalfedgeId) -> VertexId {
        VertexId(self.he_to[h.idx() ^ 1])
    }
    /// Next halfedge in the face (or boundary loop).
    #[inline]
    pub fn next(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.he_next[h.idx()])
    }
    /// Previous halfedge in the face (or boundary loop).
    #[inline]
    pub fn prev(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.he_prev[h.idx()])
    }
    /// The opposite halfedge.
    #[inline]
    pub fn opposite(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(h.0 ^ 1)
    }
    /// Face of `h`, `None` on the boundary.
    #[inline]
    pub fn face(&self, h: HalfedgeId) -> Option<FaceId> {
        let f = self.he_face[h.idx()];
        (f != NONE).then_some(FaceId(f))
    }
    /// Edge of `h`.
    #[inline]
    pub fn edge(&self, h: HalfedgeId) -> EdgeId {
        EdgeId(h.0 >> 1)
    }
    /// Halfedge `i` (0 or 1) of edge `e`; halfedge 0 runs from the smaller to
    /// the larger vertex index.
    #[inline]
    pub fn edge_halfedge(&self, e: EdgeId, i: u32) -> HalfedgeId {
        HalfedgeId(2 * e.0 + (i & 1))
    }
    /// The two vertices of edge `e` (smaller index first).
    #[inline]
    pub fn edge_vertices(&self, e: EdgeId) -> (VertexId, VertexId) {
        let h = HalfedgeId(2 * e.0);
        (self.from_vertex(h), self.to_vertex(h))
    }
    /// One halfedge of face `f`.
    #[inline]
    pub fn face_halfedge(&self, f: FaceId) -> HalfedgeId {
        HalfedgeId(self.f_he[f.idx()])
    }
    /// The stored outgoing halfedge of `v` (its boundary halfedge if `v` is on
    /// the boundary); `None` for isolated vertices.
    #[inline]
    pub fn vertex_halfedge(&self, v: VertexId) -> Option<HalfedgeId> {
        let h = self.v_out[v.idx()];
        (h != NONE).then_some(HalfedgeId(h))
    }
    /// The next outgoing halfedge of the same vertex, clockwise:
    /// `next(opposite(h))`.
    #[inline]
    pub fn cw_rotated(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.he_next[(h.0 ^ 1) as usize])
    }
    /// The next outgoing halfedge of the same vertex, counter-clockwise:
    /// `opposite(prev(h))`.
    #[inline]
    pub fn ccw_rotated(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.he_prev[h.idx()] ^ 1)
    }

    // ---- boundary tests ---------------------------------------------

    /// True when `h` has no face.
    #[inline]
    pub fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        self.he_face[h.idx()] == NONE
    }
    /// True when one of the halfedges of `e` has no face.
    #[inline]
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.he_face[2 * e.idx()] == NONE || self.he_face[2 * e.idx() + 1] == NONE
    }
    /// True when `v` lies on the boundary (isolated vertices count as boundary).
    #[inline]
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.v_out[v.idx()];
        h == NONE || self.he_face[h as usize] == NONE
    }
    /// True when `v` has no incident face.
    #[inline]
    pub fn is_isolated(&self, v: VertexId) -> bool {
        self.v_out[v.idx()] == NONE
    }
    /// True when `f` has a boundary edge.
    pub fn is_boundary_face(&self, f: FaceId) -> bool {
        self.face_halfedges(f)
            .any(|h| self.is_boundary_halfedge(self.opposite(h)))
    }
    /// True when the mesh has no boundary edge.
    pub fn is_closed(&self) -> bool {
        self.he_face.iter().all(|&f| f != NONE)
    }

    // ---- circulators --------------------------------------------------

    /// Outgoing halfedges of `v`, clockwise, starting at the stored one
    /// (the boundary halfedge for boundary vertices).
    pub fn outgoing(&self, v: VertexId) -> Outgoing<'_> {
        let start = self.v_out[v.idx()];
        Outgoing {
            mesh: self,
            start,
            current: start,
            done: start == NONE,
        }
    }
    /// The one-ring of `v`: neighbouring vertices in circulation order.
    pub fn one_ring(&self, v: VertexId) -> impl Iterator<Item = VertexId> + '_ {
        self.outgoing(v).map(move |h| self.to_vertex(h))
    }
    /// Faces around `v` in circulation order.
    pub fn vertex_faces(&self, v: VertexId) -> impl Iterator<Item = FaceId> + '_ {
        self.outgoing(v).filter_map(move |h| self.face(h))
    }
    /// Number of edges at `v`.
    pub fn valence(&self, v: VertexId) -> usize {
        self.outgoing(v).count()
    }
    /// Halfedges of face `f` in order.
    pub fn face_halfedges(&self, f: FaceId) -> FaceHalfedges<'_> {
        let start = self.f_he[f.idx()];
        FaceHalfedges {
            mesh: self,
            start,
            current: start,
            done: false,
        }
    }
    /// Vertices of face `f` in order (the target of each face halfedge,
    /// starting with the target of the stored halfedge).
    pub fn face_vertices(&self, f: FaceId) -> impl Iterator<Item = VertexId> + '_ {
        self.face_halfedges(f).map(move |h| self.to_vertex(h))
    }
    /// Number of vertices of face `f`.
    pub fn face_size(&self, f: FaceId) -> usize {
        self.face_halfedges(f).count()
    }
    /// Vertex indices of the triangle `f` (which must be a triangle).
    #[inline]
    pub fn triangle(&self, f: FaceId) -> [VertexId; 3] {
        let h0 = self.f_he[f.idx()] as usize;
        let h1 = self.he_next[h0] as usize;
        let h2 = self.he_next[h1] as usize;
        [
            VertexId(self.he_to[h0]),
            VertexId(self.he_to[h1]),
            VertexId(self.he_to[h2]),
        ]
    }
    /// True when every face is a triangle.
    pub fn is_triangle_mesh(&self) -> bool {
        self.first_non_triangle.is_none()
    }
    /// True when every face is a quad.
    pub fn is_quad_mesh(&self) -> bool {
        self.faces().all(|f| self.face_size(f) == 4)
    }
    /// Returns an error naming the first non-triangle face, for
    /// triangle-only algorithms.
    pub fn require_triangles(&self) -> Result<(), MeshError> {
        match self.first_non_triangle {
            None => Ok(()),
            Some(f) => Err(MeshError::NotTriangle {
                face: f as usize,
                size: self.face_size(FaceId(f)),
            }),
        }
    }

    /// The polygons of the mesh as vertex-index lists (in the mesh's
    /// consistent orientation).
    pub fn polygons(&self) -> Vec<Vec<u32>> {
        self.faces()
            .map(|f| {
                let mut poly: Vec<u32> = self.face_vertices(f).map(|v| v.0).collect();
                // start at the source of the stored halfedge for stable output
                poly.rotate_right(1);
                poly
            })
            .collect()
    }

    /// The mesh as a soup (positions and polygons).
    pub fn to_soup(&self) -> Soup {
        Soup::from_polygons(self.positions.clone(), &self.polygons())
    }

    /// Halfedge from `a` to `b`, if the edge exists.
    pub fn find_halfedge(&self, a: VertexId, b: VertexId) -> Option<HalfedgeId> {
        self.outgoing(a).find(|&h| self.to_vertex(h) == b)
    }
}

/// Clockwise circulator over the outgoing halfedges of a vertex.
pub struct Outgoing<'a> {
    mesh: &'a SurfaceMesh,
    start: u32,
    current: u32,
    done: bool,
}

impl Iterator for Outgoing<'_> {
    type Item = HalfedgeId;
    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.done {
            return None;
        }
        let h = self.current;
        self.current = self.mesh.he_next[(h ^ 1) as usize];
        if self.current == self.start {
            self.done = true;
        }
        Some(HalfedgeId(h))
    }
}

/// Iterator over the halfedges of a face.
pub struct FaceHalfedges<'a> {
    mesh: &'a SurfaceMesh,
    start: u32,
    current: u32,
    done: bool,
}

impl Iterator for FaceHalfedges<'_> {
    type Item = HalfedgeId;
    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.done {
            return None;
        }
        let h = self.current;
        self.current = self.mesh.he_next[h as usize];
        if self.current == self.start {
            self.done = true;
        }
        Some(HalfedgeId(h))
    }
}
