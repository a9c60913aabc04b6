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
use rayon::prelude::*;

/// The halfedge arrays without the boundary links.
pub(super) struct Halfedges {
    pub to: Vec<u32>,
    pub next: Vec<u32>,
    pub prev: Vec<u32>,
    pub face: Vec<u32>,
    pub face_halfedge: Vec<u32>,
}

/// "No element" in the index arrays.
pub(super) const NONE: u32 = u32::MAX;

/// Non-manifold vertices split by the builder, one copy per extra fan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct SplitVertices {
    /// Vertices of the input; copies are numbered from here on.
    pub original_vertices: usize,
    /// The input vertex of copy `original_vertices + j`, ascending.
    pub source: Vec<u32>,
    /// True for a split input vertex and for every copy.
    pub marked: Vec<bool>,
}

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
    /// Non-manifold vertices split when building; `None` for a manifold input.
    split: Option<SplitVertices>,
}

/// What the mesh builder did to the input besides building it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BuildNotes {
    /// Faces whose vertex order was reversed for a consistent orientation.
    pub flipped_faces: usize,
    /// Non-manifold input vertices (several fans of faces meeting) that were
    /// split, one copy per fan.
    pub split_vertices: usize,
    /// Copies added by that splitting (one per fan beyond the first).
    pub vertex_copies: usize,
}

impl SurfaceMesh {
    /// Builds a mesh from positions and polygons (triangles, quads, n-gons).
    pub fn new<F: AsRef<[u32]>>(positions: Vec<Vec3>, faces: &[F]) -> Result<Self, MeshError> {
        Self::from_owned_soup(Soup::from_polygons(positions, faces))
    }

    /// Assembles a mesh from the builder's arrays.
    pub(super) fn from_parts(
        mut positions: Vec<Vec3>,
        he: Halfedges,
        v_out: Vec<u32>,
        flipped_faces: usize,
        split: Option<SplitVertices>,
    ) -> Self {
        positions.shrink_to_fit();
        let Halfedges {
            to: he_to,
            next: he_next,
            prev: he_prev,
            face: he_face,
            face_halfedge: f_he,
        } = he;
        let is_triangle = |f: usize| {
            let h = f_he[f] as usize;
            he_next[he_next[he_next[h] as usize] as usize] as usize == h
        };
        let first_non_triangle = if f_he.len() >= 20_000 {
            (0..f_he.len())
                .into_par_iter()
                .find_first(|&f| !is_triangle(f))
        } else {
            (0..f_he.len()).find(|&f| !is_triangle(f))
        }
        .map(|f| f as u32);
        SurfaceMesh {
            positions,
            he_to,
            he_next,
            he_prev,
            he_face,
            v_out,
            f_he,
            flipped_faces,
            first_non_triangle,
            split,
        }
    }

    /// Gives this mesh (built from `source`'s positions with the same
    /// vertex indices, e.g. a triangulation) `source`'s split vertices.
    pub(super) fn inherit_split_vertices(&mut self, source: &SurfaceMesh) {
        self.split = source.split.clone();
    }

    /// What the builder changed: the number of faces it reversed.
    pub fn build_notes(&self) -> BuildNotes {
        BuildNotes {
            flipped_faces: self.flipped_faces,
            split_vertices: self.split_vertex_count(),
            vertex_copies: self.vertex_count() - self.original_vertex_count(),
        }
    }

    // ---- split non-manifold vertices ----------------------------------

    /// Number of vertices of the input the mesh was built from. Vertices
    /// `0..original_vertex_count()` are the input's, in its order; any after
    /// them are copies of split non-manifold vertices.
    pub fn original_vertex_count(&self) -> usize {
        self.split
            .as_ref()
            .map_or(self.positions.len(), |s| s.original_vertices)
    }

    /// Number of input vertices that were split because several fans of
    /// faces meet there.
    pub fn split_vertex_count(&self) -> usize {
        self.split.as_ref().map_or(0, |s| {
            let mut n = 0;
            let mut last = u32::MAX;
            for &v in &s.source {
                n += usize::from(v != last);
                last = v;
            }
            n
        })
    }

    /// The input vertex that `v` stands for: itself, or the vertex it is a
    /// split copy of.
    #[inline]
    pub fn original_vertex(&self, v: VertexId) -> VertexId {
        match &self.split {
            Some(s) if v.idx() >= s.original_vertices => {
                VertexId(s.source[v.idx() - s.original_vertices])
            }
            _ => v,
        }
    }

    /// True for a split non-manifold input vertex and for each of its copies.
    #[inline]
    pub fn is_split_vertex(&self, v: VertexId) -> bool {
        self.split
            .as_ref()
            .is_some_and(|s| s.marked.get(v.idx()).copied().unwrap_or(false))
    }

    /// True for vertices that no algorithm may move: isolated vertices and
    /// split non-manifold vertices with their copies (moving one fan's copy
    /// would tear the input vertex apart). Every algorithm treats them like
    /// fixed vertices, so their coordinates stay bit-identical.
    #[inline]
    pub fn is_pinned(&self, v: VertexId) -> bool {
        self.is_isolated(v) || self.is_split_vertex(v)
    }

    /// The first `original_vertex_count()` entries of a per-vertex array:
    /// the values of the input's vertices, in its order (a split vertex
    /// takes the value of the fan that kept its index).
    pub fn original_values<'a, T>(&self, values: &'a [T]) -> &'a [T] {
        &values[..self.original_vertex_count().min(values.len())]
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

    /// The polygons of the mesh as lists of input vertex indices (in the
    /// mesh's consistent orientation; split copies are replaced by the vertex
    /// they copy).
    pub fn polygons(&self) -> Vec<Vec<u32>> {
        self.faces()
            .map(|f| {
                let mut poly: Vec<u32> = self
                    .face_vertices(f)
                    .map(|v| self.original_vertex(v).0)
                    .collect();
                // start at the source of the stored halfedge for stable output
                poly.rotate_right(1);
                poly
            })
            .collect()
    }

    /// The mesh as a soup (positions and polygons) over the input's vertex
    /// list: split copies are merged back into the vertex they copy (they
    /// are pinned, so its position is bit-identical to the input's).
    pub fn to_soup(&self) -> Soup {
        let positions = self.original_values(&self.positions).to_vec();
        let mut soup = Soup {
            positions,
            offsets: Vec::with_capacity(self.face_count() + 1),
            indices: Vec::with_capacity(self.halfedge_count()),
        };
        soup.offsets.push(0);
        for f in self.faces() {
            // start at the source of the stored halfedge for stable output
            let h = self.face_halfedge(f);
            soup.indices
                .push(self.original_vertex(self.from_vertex(h)).0);
            let mut c = h;
            loop {
                let n = self.next(c);
                if n == h {
                    break;
                }
                soup.indices.push(self.original_vertex(self.to_vertex(c)).0);
                c = n;
            }
            soup.offsets.push(soup.indices.len() as u32);
        }
        soup
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
