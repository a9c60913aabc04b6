//! `Soup`: positions plus a flat polygon list, with no connectivity.
//!
//! Every reader produces a `Soup`; `SurfaceMesh::from_soup` then builds the
//! halfedge structure and refuses what is not a manifold. `info` analyses a
//! `Soup` directly so that broken files can still be described.

use crate::Vec3;

/// Positions and polygons as read from a file: no connectivity, no checks.
///
/// Faces are stored flat: face `f` is `indices[offsets[f]..offsets[f + 1]]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Soup {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Start of each face in `indices`, plus one final entry (`faces + 1` long).
    pub offsets: Vec<u32>,
    /// Vertex indices of all faces, concatenated.
    pub indices: Vec<u32>,
}

impl Soup {
    /// An empty soup.
    pub fn new() -> Self {
        Soup {
            positions: Vec::new(),
            offsets: vec![0],
            indices: Vec::new(),
        }
    }

    /// A soup from positions and a list of polygons.
    pub fn from_polygons<F: AsRef<[u32]>>(positions: Vec<Vec3>, faces: &[F]) -> Self {
        let mut soup = Soup {
            positions,
            offsets: Vec::with_capacity(faces.len() + 1),
            indices: Vec::new(),
        };
        soup.offsets.push(0);
        for f in faces {
            soup.push_face(f.as_ref());
        }
        soup
    }

    /// Appends one polygon.
    pub fn push_face(&mut self, face: &[u32]) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.indices.extend_from_slice(face);
        self.offsets.push(self.indices.len() as u32);
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The vertex indices of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }

    /// Iterator over all faces.
    pub fn faces(&self) -> impl Iterator<Item = &[u32]> + '_ {
        (0..self.face_count()).map(move |f| self.face(f))
    }

    /// True when every face is a triangle.
    pub fn is_triangle_soup(&self) -> bool {
        self.offsets.windows(2).all(|w| w[1] - w[0] == 3)
    }

    /// Axis-aligned bounding box `(min, max)` of the finite positions, or
    /// `None` when there are none.
    pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> {
        bounding_box(&self.positions)
    }
}

/// Axis-aligned bounding box `(min, max)` of the finite points, or `None`.
pub fn bounding_box(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let mut it = points.iter().filter(|p| p.is_finite());
    let first = *it.next()?;
    let (mut lo, mut hi) = (first, first);
    for p in it {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    Some((lo, hi))
}
