//! Fairing regions and movable vertices, Yong et al. §3.1 (the region file
//! is read by [`crate::io::read_region`]).
//!
//! A region R is a set of faces. A vertex is *inside* R when all its faces
//! are in R (mesh-boundary vertices are never inside: their Willmore term
//! and normal are one-sided); an edge is inside when both its faces are in
//! R. The support vertices of a vertex are itself and its one-ring (Eq. (3));
//! those of a highlight node on edge (V1, V2) are V1, V2 and their supports
//! (Eq. (4)). *Movable* vertices are the inside vertices that support no
//! outside vertex and no outside node, so moving them changes no normal,
//! position or highlight node outside R, exactly.
//!
//! An outside node lies on an outside edge, which has a face outside R, so
//! both of its end vertices are outside vertices; a node's supports are its
//! end vertices' supports. Hence "supports no outside node" adds nothing to
//! "supports no outside vertex": movable = inside vertices whose one-ring
//! holds only inside vertices. [`movable_vertices`] checks both anyway.

use super::FairError;
use crate::Vec3;
use crate::highlight::NodeId;
use crate::mesh::{EdgeId, FaceId, SurfaceMesh, VertexId};

/// Region R with its inside elements and movable vertices (Yong et al.
/// §3.1).
#[derive(Clone, Debug, PartialEq)]
pub struct MovableSet {
    /// Per face: in R.
    pub in_region: Vec<bool>,
    /// Per vertex: inside R (all faces in R, not on the mesh boundary).
    pub inside: Vec<bool>,
    /// Per vertex: movable.
    pub is_movable: Vec<bool>,
    /// The movable vertices, sorted.
    pub movable: Vec<VertexId>,
    /// The inside vertices I_R of Eq. (6), sorted.
    pub inside_vertices: Vec<VertexId>,
}

impl MovableSet {
    /// True when edge `e` is inside R (both faces in R).
    pub fn edge_inside(&self, mesh: &SurfaceMesh, e: EdgeId) -> bool {
        (0..2).all(|i| {
            mesh.face(mesh.edge_halfedge(e, i))
                .is_some_and(|f| self.in_region[f.idx()])
        })
    }

    /// True when the highlight node lies inside R (on an inside edge, or
    /// on an inside vertex).
    pub fn node_inside(&self, mesh: &SurfaceMesh, node: NodeId) -> bool {
        match node {
            NodeId::Edge(e, _) => self.edge_inside(mesh, e),
            NodeId::Vertex(v, _) => self.inside[v.idx()],
        }
    }

    /// The boundary of R as segments (edges with exactly one face in R, or
    /// a face in R on the mesh boundary), for drawing.
    pub fn outline(&self, mesh: &SurfaceMesh) -> Vec<(Vec3, Vec3)> {
        let p = mesh.positions();
        mesh.edges()
            .filter(|&e| {
                let a = mesh
                    .face(mesh.edge_halfedge(e, 0))
                    .is_some_and(|f| self.in_region[f.idx()]);
                let b = mesh
                    .face(mesh.edge_halfedge(e, 1))
                    .is_some_and(|f| self.in_region[f.idx()]);
                a != b
            })
            .map(|e| {
                let (u, v) = mesh.edge_vertices(e);
                (p[u.idx()], p[v.idx()])
            })
            .collect()
    }
}

/// Inside and movable vertices of the face region `faces` (Yong et al.
/// §3.1; see the module documentation). `nodes` are the current highlight
/// nodes; a node outside R blocks its support vertices. Errors on an
/// out-of-range face and, with advice on enlarging the region, when no
/// vertex is movable.
pub fn movable_vertices(
    mesh: &SurfaceMesh,
    faces: &[FaceId],
    nodes: &[NodeId],
) -> Result<MovableSet, FairError> {
    let nf = mesh.face_count();
    let nv = mesh.vertex_count();
    let mut in_region = vec![false; nf];
    for &f in faces {
        if f.idx() >= nf {
            return Err(FairError::Region(format!(
                "face {} out of range (the mesh has {nf} faces)",
                f.0
            )));
        }
        in_region[f.idx()] = true;
    }
    let inside: Vec<bool> = mesh
        .vertices()
        .map(|v| {
            !mesh.is_pinned(v)
                && !mesh.is_boundary_vertex(v)
                && mesh.vertex_faces(v).all(|f| in_region[f.idx()])
        })
        .collect();
    // Supports of outside vertices: the vertex and its one-ring (Eq. (3)).
    let mut blocked = vec![false; nv];
    let block_support = |v: VertexId, blocked: &mut Vec<bool>| {
        blocked[v.idx()] = true;
        for w in mesh.one_ring(v) {
            blocked[w.idx()] = true;
        }
    };
    for v in mesh.vertices() {
        if !inside[v.idx()] {
            block_support(v, &mut blocked);
        }
    }
    let partial = MovableSet {
        in_region,
        inside,
        is_movable: Vec::new(),
        movable: Vec::new(),
        inside_vertices: Vec::new(),
    };
    // Supports of outside nodes: the edge's ends and their supports (Eq. (4)).
    for &n in nodes {
        if partial.node_inside(mesh, n) {
            continue;
        }
        match n {
            NodeId::Edge(e, _) => {
                let (a, b) = mesh.edge_vertices(e);
                block_support(a, &mut blocked);
                block_support(b, &mut blocked);
            }
            NodeId::Vertex(v, _) => block_support(v, &mut blocked),
        }
    }
    let MovableSet {
        in_region, inside, ..
    } = partial;
    let is_movable: Vec<bool> = (0..nv).map(|i| inside[i] && !blocked[i]).collect();
    let movable: Vec<VertexId> = (0..nv as u32)
        .filter(|&i| is_movable[i as usize])
        .map(VertexId)
        .collect();
    let inside_vertices: Vec<VertexId> = (0..nv as u32)
        .filter(|&i| inside[i as usize])
        .map(VertexId)
        .collect();
    if movable.is_empty() {
        return Err(FairError::NoMovableVertex(format!(
            "the region has {} faces and {} inside vertices, but every inside vertex is in the \
             one-ring of a vertex outside the region. Enlarge the region by at least two rings of \
             faces around the part to be faired (e.g. a larger sphere radius or more faces)",
            faces.len(),
            inside_vertices.len()
        )));
    }
    Ok(MovableSet {
        in_region,
        inside,
        is_movable,
        movable,
        inside_vertices,
    })
}
