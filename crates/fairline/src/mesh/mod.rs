//! Meshes: the halfedge [`SurfaceMesh`], the connectivity-free [`Soup`],
//! topology queries, triangulation of polygons, structure lines of quad
//! meshes, and the repair of dirty face lists.

mod build;
mod inspect;
mod repair;
mod soup;
mod surface_mesh;
mod topology;
mod union_find;

pub use inspect::{BoundingBox, MeshInfo, Stats, inspect};
pub use repair::{
    RemovalReason, RemovedFace, RepairError, RepairOptions, RepairReport, Repaired, SplitEdge,
    SplitVertex, repair,
};
pub use soup::{Soup, bounding_box};
pub use surface_mesh::{BuildNotes, FaceHalfedges, Outgoing, SurfaceMesh};
pub use topology::{
    StructureLine, TopologySummary, Triangulation, boundary_loops, components, structure_lines,
    topology_summary, triangle_list, triangulate,
};
pub(crate) use union_find::{find as union_find_root, union as union_find_join};

use thiserror::Error;

/// Relative threshold below which a face counts as degenerate: its double
/// area is at most `DEGENERATE_RELATIVE_AREA` times the sum of its squared
/// edge lengths. Defined here, with the meshes, because their inspection
/// counts degenerate faces; `geom`'s areas and normals use the same value
/// (re-exported as `geom::DEGENERATE_RELATIVE_AREA`).
pub const DEGENERATE_RELATIVE_AREA: f64 = 1e-14;

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
        pub struct $name(pub u32);
        impl $name {
            /// The index as `usize`.
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }
        impl From<$name> for usize {
            #[inline]
            fn from(id: $name) -> usize {
                id.0 as usize
            }
        }
    };
}

id_type!(
    /// Index of a vertex.
    VertexId
);
id_type!(
    /// Index of a face.
    FaceId
);
id_type!(
    /// Index of an edge (edge `e` owns halfedges `2e` and `2e + 1`).
    EdgeId
);
id_type!(
    /// Index of a halfedge.
    HalfedgeId
);

/// Why a face list could not be made into a [`SurfaceMesh`], naming the element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Face index.
        face: usize,
        /// The offending vertex index.
        index: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// A face has fewer than three vertices.
    #[error("face {face} has {size} vertices; a face needs at least 3")]
    FaceTooSmall {
        /// Face index.
        face: usize,
        /// Its number of vertices.
        size: usize,
    },
    /// A face lists the same vertex twice.
    #[error("face {face} uses vertex {vertex} more than once")]
    RepeatedVertex {
        /// Face index.
        face: usize,
        /// The repeated vertex.
        vertex: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a coordinate that is NaN or infinite")]
    NonFiniteCoordinate {
        /// Vertex index.
        vertex: usize,
    },
    /// An edge is shared by more than two faces.
    #[error("edge ({v0}, {v1}) is non-manifold: it is shared by faces {faces:?}")]
    NonManifoldEdge {
        /// First vertex.
        v0: usize,
        /// Second vertex.
        v1: usize,
        /// The faces that share it.
        faces: Vec<usize>,
    },
    /// A vertex where several fans of faces meet.
    #[error("vertex {vertex} is non-manifold: its faces form more than one fan")]
    NonManifoldVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// The faces of a component cannot be oriented consistently.
    #[error(
        "face {face} cannot be oriented consistently with its neighbours (non-orientable surface)"
    )]
    NonOrientable {
        /// A face where the conflict was found.
        face: usize,
    },
    /// An algorithm needs triangles.
    #[error("face {face} has {size} vertices; this operation needs a triangle mesh")]
    NotTriangle {
        /// Face index.
        face: usize,
        /// Its number of vertices.
        size: usize,
    },
    /// An algorithm needs quads.
    #[error("face {face} has {size} vertices; this operation needs a quad mesh")]
    NotQuad {
        /// Face index.
        face: usize,
        /// Its number of vertices.
        size: usize,
    },
    /// A position array of the wrong length.
    #[error("expected {expected} positions, got {got}")]
    PositionCount {
        /// Expected count.
        expected: usize,
        /// Given count.
        got: usize,
    },
    /// Every split of a polygon into triangles would repeat an edge that the
    /// mesh (or the split of another polygon) already has.
    #[error(
        "face {face} cannot be split into triangles: every diagonal of it is already an edge of the mesh"
    )]
    NoTriangulation {
        /// Face index.
        face: usize,
    },
    /// The mesh does not fit 32-bit indices.
    #[error("mesh too large for 32-bit indices")]
    TooLarge,
}

#[cfg(test)]
mod tests;
