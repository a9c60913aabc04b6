//! Cotangents, edge weights and Laplacian matrices.
//!
//! Sign convention (as libigl's `cotmatrix`): `L[i][j] = w_ij` for each
//! neighbour j and `L[i][i] = −Σ_j w_ij`, so `(L x)_i = Σ_j w_ij (x_j − x_i)`;
//! L is symmetric negative semi-definite for positive weights and constants
//! lie in its null space. Divide row i by a vertex area to get the
//! Laplace–Beltrami operator.

use super::COTANGENT_LIMIT;
use crate::Vec3;
use crate::mesh::{HalfedgeId, SurfaceMesh, VertexId};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

/// Edge weights of a Laplacian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LaplaceWeights {
    /// w_ij = 1 (umbrella operator); any polygon mesh.
    Uniform,
    /// w_ij = |x_j − x_i|^exponent (Fujiwara for exponent −1); any polygon
    /// mesh. Zero-length edges get weight 0.
    EdgeLength {
        /// The power of the edge length (−1 in the Grüner thesis §3.2.2).
        exponent: f64,
    },
    /// w_ij = ½ (cot α_ij + cot β_ij) (Pinkall–Polthier, Desbrun et al.);
    /// triangle meshes (polygon faces contribute nothing).
    Cotangent,
}

/// Cotangent of the angle opposite each halfedge within its triangle (the
/// angle at `to_vertex(next(h))`), per halfedge. Boundary halfedges,
/// non-triangle faces and degenerate triangles give 0; magnitudes are clamped
/// to [`COTANGENT_LIMIT`]. Computed as cot θ = (a·b) / |a × b|.
pub fn cotangents(mesh: &SurfaceMesh) -> Vec<f64> {
    cotangents_at(mesh, mesh.positions())
}

/// [`cotangents`] with the vertices at `positions` (one per vertex) instead
/// of the mesh's own: a geometry view over the mesh's connectivity, so a
/// trial shape needs no copy of the mesh.
pub fn cotangents_at(mesh: &SurfaceMesh, positions: &[Vec3]) -> Vec<f64> {
    let p = positions;
    (0..mesh.halfedge_count() as u32)
        .into_par_iter()
        .map(|h| {
            let h = HalfedgeId(h);
            if mesh.is_boundary_halfedge(h) {
                return 0.0;
            }
            let h1 = mesh.next(h);
            if mesh.next(mesh.next(h1)) != h {
                return 0.0;
            }
            let a = p[mesh.from_vertex(h).idx()];
            let b = p[mesh.to_vertex(h).idx()];
            let c = p[mesh.to_vertex(h1).idx()];
            cotangent(a - c, b - c)
        })
        .collect()
}

/// cot of the angle between `u` and `v`, guarded: 0 when the vectors are
/// (nearly) parallel or zero, clamped to ±[`COTANGENT_LIMIT`].
#[inline]
pub(crate) fn cotangent(u: glam::DVec3, v: glam::DVec3) -> f64 {
    let cross = u.cross(v).length();
    let scale = u.length_squared() + v.length_squared();
    if !(cross > super::DEGENERATE_RELATIVE_AREA * scale) {
        return 0.0;
    }
    (u.dot(v) / cross).clamp(-COTANGENT_LIMIT, COTANGENT_LIMIT)
}

/// Weight of every halfedge for the given scheme: entry `h` is w_ij for
/// i = from_vertex(h), j = to_vertex(h). Both halfedges of an edge carry the
/// same weight, so the Laplacian is symmetric.
pub fn halfedge_weights(mesh: &SurfaceMesh, weights: LaplaceWeights) -> Vec<f64> {
    halfedge_weights_at(mesh, mesh.positions(), weights)
}

/// [`halfedge_weights`] with the vertices at `positions` (one per vertex;
/// a geometry view, see [`cotangents_at`]).
pub fn halfedge_weights_at(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    weights: LaplaceWeights,
) -> Vec<f64> {
    match weights {
        LaplaceWeights::Uniform => vec![1.0; mesh.halfedge_count()],
        LaplaceWeights::EdgeLength { exponent } => {
            let p = positions;
            (0..mesh.halfedge_count() as u32)
                .into_par_iter()
                .map(|h| {
                    let h = HalfedgeId(h);
                    let l = p[mesh.from_vertex(h).idx()].distance(p[mesh.to_vertex(h).idx()]);
                    if l > 0.0 {
                        let w = l.powf(exponent);
                        if w.is_finite() { w } else { 0.0 }
                    } else {
                        0.0
                    }
                })
                .collect()
        }
        LaplaceWeights::Cotangent => {
            let cot = cotangents_at(mesh, positions);
            (0..mesh.halfedge_count())
                .into_par_iter()
                .map(|h| 0.5 * (cot[h] + cot[h ^ 1]))
                .collect()
        }
    }
}

/// Assembles the n × n Laplacian for per-halfedge weights (see the module
/// doc for the sign convention). Columns are built per vertex in parallel,
/// rows sorted; the pattern is that of the vertex adjacency plus the diagonal.
pub fn laplacian_from_weights(mesh: &SurfaceMesh, w: &[f64]) -> SparseColMat<usize, f64> {
    let n = mesh.vertex_count();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut total = 0usize;
    for v in mesh.vertices() {
        total += mesh.valence(v) + 1;
        col_ptr.push(total);
    }
    let mut row_idx = vec![0usize; total];
    let mut values = vec![0f64; total];
    // split the buffers into per-column slices and fill them in parallel
    let mut rows: Vec<&mut [usize]> = Vec::with_capacity(n);
    let mut vals: Vec<&mut [f64]> = Vec::with_capacity(n);
    {
        let (mut r, mut x) = (&mut row_idx[..], &mut values[..]);
        for v in 0..n {
            let len = col_ptr[v + 1] - col_ptr[v];
            let (a, rest_r) = r.split_at_mut(len);
            let (b, rest_x) = x.split_at_mut(len);
            rows.push(a);
            vals.push(b);
            r = rest_r;
            x = rest_x;
        }
    }
    rows.into_par_iter()
        .zip(vals.into_par_iter())
        .enumerate()
        .for_each(|(v, (r, x))| {
            let mut entries: smallvec_like::Small = smallvec_like::Small::new();
            let mut diag = 0.0;
            for h in mesh.outgoing(VertexId(v as u32)) {
                let wij = w[h.idx()];
                entries.push((mesh.to_vertex(h).idx(), wij));
                diag -= wij;
            }
            entries.push((v, diag));
            entries.sort();
            for (k, &(row, val)) in entries.as_slice().iter().enumerate() {
                r[k] = row;
                x[k] = val;
            }
        });
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// The pattern of the Laplacian of [`laplacian_from_weights`] (vertex
/// adjacency plus the diagonal, rows sorted within each column) and, for
/// every stored entry, where its value comes from: so a method whose weights
/// change every step (implicit smoothing) computes the entries it needs
/// straight from the halfedge weights, without assembling the matrix.
#[derive(Clone, Debug)]
pub struct LaplacianPattern {
    /// The n × n pattern (both triangles and the diagonal).
    pub symbolic: SymbolicSparseColMat<usize>,
    /// Per entry: the halfedge from the column's vertex to the row's vertex,
    /// or [`LaplacianPattern::DIAGONAL`].
    pub source: Vec<u32>,
}

impl LaplacianPattern {
    /// The source of a diagonal entry.
    pub const DIAGONAL: u32 = u32::MAX;

    /// The pattern of `mesh`'s Laplacian.
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let n = mesh.vertex_count();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::with_capacity(mesh.halfedge_count() + n);
        let mut source = Vec::with_capacity(mesh.halfedge_count() + n);
        let mut column: Vec<(usize, u32)> = Vec::new();
        for v in mesh.vertices() {
            column.clear();
            column.extend(mesh.outgoing(v).map(|h| (mesh.to_vertex(h).idx(), h.0)));
            column.push((v.idx(), Self::DIAGONAL));
            column.sort_unstable_by_key(|e| e.0);
            row_idx.extend(column.iter().map(|e| e.0));
            source.extend(column.iter().map(|e| e.1));
            col_ptr.push(row_idx.len());
        }
        LaplacianPattern {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            source,
        }
    }

    /// Entry k (in the column of vertex j) of the Laplacian for the
    /// halfedge weights `w`: w_ij off the diagonal, −Σ_j w_ij (summed in the
    /// order of [`SurfaceMesh::outgoing`], as [`laplacian_from_weights`]
    /// does) on it.
    #[inline]
    pub fn entry(&self, mesh: &SurfaceMesh, w: &[f64], j: usize, k: usize) -> f64 {
        match self.source[k] {
            Self::DIAGONAL => {
                let mut diag = 0.0;
                for h in mesh.outgoing(VertexId(j as u32)) {
                    diag -= w[h.idx()];
                }
                diag
            }
            h => w[h as usize],
        }
    }
}

/// Laplacian with the given weights.
pub fn laplacian(mesh: &SurfaceMesh, weights: LaplaceWeights) -> SparseColMat<usize, f64> {
    laplacian_from_weights(mesh, &halfedge_weights(mesh, weights))
}

/// Uniform (umbrella) Laplacian: L_ij = 1 for neighbours, L_ii = −valence.
pub fn uniform_laplacian(mesh: &SurfaceMesh) -> SparseColMat<usize, f64> {
    laplacian(mesh, LaplaceWeights::Uniform)
}

/// Edge-length Laplacian L_ij = |x_j − x_i|^exponent (Grüner thesis §3.2.2;
/// exponent −1 is Fujiwara's scale-dependent umbrella).
pub fn edge_length_laplacian(mesh: &SurfaceMesh, exponent: f64) -> SparseColMat<usize, f64> {
    laplacian(mesh, LaplaceWeights::EdgeLength { exponent })
}

/// Cotangent Laplacian L_ij = ½ (cot α_ij + cot β_ij) (Pinkall–Polthier 1993;
/// Meyer et al. 2003 Eq. (8)); not divided by areas.
pub fn cotangent_laplacian(mesh: &SurfaceMesh) -> SparseColMat<usize, f64> {
    laplacian(mesh, LaplaceWeights::Cotangent)
}

/// A tiny inline vector for one column (valence rarely exceeds 15), so
/// assembly allocates nothing per vertex in the common case.
mod smallvec_like {
    pub(super) struct Small {
        inline: [(usize, f64); 16],
        len: usize,
        heap: Vec<(usize, f64)>,
    }
    impl Small {
        pub(super) fn new() -> Self {
            Small {
                inline: [(0, 0.0); 16],
                len: 0,
                heap: Vec::new(),
            }
        }
        pub(super) fn push(&mut self, e: (usize, f64)) {
            if self.heap.is_empty() && self.len < 16 {
                self.inline[self.len] = e;
                self.len += 1;
            } else {
                if self.heap.is_empty() {
                    self.heap.extend_from_slice(&self.inline[..self.len]);
                }
                self.heap.push(e);
            }
        }
        pub(super) fn as_slice(&self) -> &[(usize, f64)] {
            if self.heap.is_empty() {
                &self.inline[..self.len]
            } else {
                &self.heap
            }
        }
        pub(super) fn sort(&mut self) {
            if self.heap.is_empty() {
                self.inline[..self.len].sort_unstable_by_key(|e| e.0);
            } else {
                self.heap.sort_unstable_by_key(|e| e.0);
            }
        }
    }
}
