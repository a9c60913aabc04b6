//! Smoothed-aggregation multigrid (Vaněk, Mandel & Brezina 1996) for
//! symmetric positive-definite operators on three unknowns per node that
//! act alike on the three coordinates up to a local coupling:
//!
//!   K = A ⊗ I₃ + S,
//!
//! A a symmetric scalar matrix over the nodes (at the finest level a graph
//! Laplacian), S a symmetric block matrix with the pattern of A whose
//! blocks S_IJ are symmetric 3 × 3 (at the finest level a reaction term on
//! the diagonal only). Node I owns the unknowns 3I, 3I + 1, 3I + 2.
//!
//! The hierarchy keeps this structure. The tentative prolongator T_s comes
//! from one scalar near-null vector per node (constants: the translations
//! of every coordinate) and is smoothed with A alone,
//! P_s = (I − ω D_A⁻¹ A) T_s, so the prolongator of the three coordinates
//! is P = P_s ⊗ I₃ and the Galerkin coarse operator
//!
//!   Pᵀ K P = (P_sᵀ A P_s) ⊗ I₃ + P_sᵀ S P_s,   (P_sᵀ S P_s)_IJ = Σ_kl P_kI P_lJ S_kl,
//!
//! has the same form (its blocks are again symmetric, its pattern that of
//! P_sᵀ A P_s). Against the same method on the assembled 3n × 3n matrix
//! (3 × 3 blocks everywhere, as fairline had before) a stored coarse entry
//! is one index, one scalar and six block values instead of nine indices
//! and nine values, the prolongator has a ninth of the entries, the finest
//! level stores S on its diagonal only, and the setup multiplies scalar
//! matrices: on the 100k-vertex rounded cube of vertex flow a V-cycle took
//! 11.5 ms instead of about 40 and the setup 0.4 s instead of 1.3 s, in
//! fewer conjugate-gradient iterations. Aggregation, the tentative
//! prolongator and its smoothing are the shared steps of `amg.rs`.
//!
//! Apply: one symmetric V-cycle — ν damped block-Jacobi steps
//! x ← x + ω D⁻¹(b − K x), D the 3 × 3 diagonal blocks of K,
//! ω = 4 / (3 ρ̄) (ρ̄ as for the prolongator smoothing), before and ν
//! after the coarse correction, with restriction Pᵀ and prolongation P;
//! the coarsest level (at most [`VectorAmgOptions::max_coarse_nodes`]
//! nodes) is factored by [`super::CholeskySolver`]. The smoother is
//! convergent in the K norm (ω ρ(D⁻¹K) ≤ 4/3 < 2), pre- and post-smoothing
//! are adjoint and the coarsest solve is exact, so the V-cycle is a
//! symmetric positive-definite operator and a valid preconditioner for
//! conjugate gradients. The one-sided cycles [`VectorAmg::apply_pre`] (ν
//! steps before each coarse correction, none after) and
//! [`VectorAmg::apply_post`] (after only) are each other's transposes, so
//! a product Vᵀ W V with them is symmetric at the cost of one symmetric
//! cycle (vertex flow's factored preconditioner). Every parallel loop
//! writes disjoint rows and sums in a fixed order: the result does not
//! depend on the number of threads.
//!
//! Cost. Each smoothing step forms the residual row by row and updates
//! into a second vector (no stored residual, one pass instead of two), the
//! prolongation adds into that vector in the same pass, and the steps
//! alternate between the two vectors (starting in the one that makes the
//! result end in x, so no copy); the
//! finest H of vertex flow, a graph Laplacian, stores no off-diagonal
//! values (all −1); coarse levels store the whole block A_IJ I₃ + S_IJ
//! (one 3 × 3 product per entry), A beside it for the setup only. On the
//! 100k-vertex rounded cube a V-cycle went from 10.8 ms to 9.0 ms (best
//! of 40) with these.

use super::amg::{
    ROWS, RowAccumulator, aggregate_nodes, block_jacobi, jacobi_damping, power_iterations,
    smooth_prolongator, tentative,
};
use super::cg::{Preconditioner, invert_spd};
use super::{CholeskySolver, CsrMatrix, SolveError};
use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;
use std::sync::Mutex;

/// Nodes per chunk of the V-cycle's loops: small chunks balance the two
/// threads on small meshes (10k-vertex rounded cube: 0.20 s for the whole
/// command, 0.23 s with chunks of 1024).
const NODES: usize = 256;

/// Chunks of [`NODES`] nodes per parallel task at least: the coarse levels
/// are small, and waking a second thread for them costs more than it saves.
const MIN_TASK_CHUNKS: usize = 4;

/// Calls `f(i, out_i)` for every node i with its three entries of `out`,
/// in parallel over chunks of [`NODES`] nodes (each node written once).
fn for_each_node(out: &mut [f64], f: impl Fn(usize, &mut [f64; 3]) + Sync) {
    out.par_chunks_mut(3 * NODES)
        .enumerate()
        .with_min_len(MIN_TASK_CHUNKS)
        .for_each(|(c, out)| {
            // fixed-size entries: whole-array stores instead of a
            // slice copy (a call) per node
            for (k, out) in out.as_chunks_mut::<3>().0.iter_mut().enumerate() {
                f(c * NODES + k, out);
            }
        });
}

/// A symmetric 3 × 3 block as [xx, yy, zz, xy, xz, yz].
pub type SymmetricBlock = [f64; 6];

/// A symmetric block as a full 3 × 3 matrix, by rows.
#[inline]
fn full_block(s: &SymmetricBlock) -> [[f64; 3]; 3] {
    [[s[0], s[3], s[4]], [s[3], s[1], s[5]], [s[4], s[5], s[2]]]
}

#[inline(always)]
fn symmetric_mul(s: &SymmetricBlock, x: &[f64]) -> [f64; 3] {
    [
        s[0] * x[0] + s[3] * x[1] + s[4] * x[2],
        s[3] * x[0] + s[1] * x[1] + s[5] * x[2],
        s[4] * x[0] + s[5] * x[1] + s[2] * x[2],
    ]
}

/// The values of A in a [`VectorOperator`]: one per stored entry, or, for
/// a graph Laplacian (every off-diagonal entry −1, as H of vertex flow on
/// the finest level), the diagonal only — a third less memory to stream
/// per product.
#[derive(Clone, Debug, PartialEq)]
enum Scalars {
    Entries(Vec<f64>),
    UnitOffDiagonal { diagonal: Vec<f64> },
}

impl Scalars {
    /// The values `a` of the entries `ptr`, `idx`, stored as
    /// [`Scalars::UnitOffDiagonal`] when every off-diagonal one is −1.
    fn new(ptr: &[usize], idx: &[u32], a: Vec<f64>) -> Scalars {
        let n = ptr.len() - 1;
        let diagonal_of = |i: usize| (ptr[i]..ptr[i + 1]).find(|&e| idx[e] as usize == i);
        let unit = (0..n)
            .into_par_iter()
            .all(|i| (ptr[i]..ptr[i + 1]).all(|e| idx[e] as usize == i || a[e] == -1.0));
        if unit {
            Scalars::UnitOffDiagonal {
                diagonal: (0..n)
                    .into_par_iter()
                    .map(|i| diagonal_of(i).map_or(0.0, |e| a[e]))
                    .collect(),
            }
        } else {
            Scalars::Entries(a)
        }
    }
}

/// The blocks of a [`VectorOperator`]: S on the diagonal only (one S_II
/// per node), or the whole block K_IJ = A_IJ I₃ + S_IJ of every stored
/// entry (one symmetric 3 × 3 product per entry in the cycle; A is kept
/// beside it for the setup of the next level).
#[derive(Clone, Debug, PartialEq)]
enum Blocks {
    Diagonal(Vec<SymmetricBlock>),
    Full(Vec<SymmetricBlock>),
}

/// a I₃ + s.
#[inline]
fn shifted(a: f64, s: &SymmetricBlock) -> SymmetricBlock {
    [a + s[0], a + s[1], a + s[2], s[3], s[4], s[5]]
}

/// A symmetric operator K = A ⊗ I₃ + S on three unknowns per node, stored
/// by rows (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct VectorOperator {
    ptr: Vec<usize>,
    idx: Vec<u32>,
    a: Scalars,
    s: Blocks,
}

impl VectorOperator {
    /// The operator with, for each node I, the stored entries (J, A_IJ,
    /// S_IJ) of row I in strictly increasing J, the diagonal included. K
    /// must be symmetric: (J, A_JI, S_JI) = (I, A_IJ, S_IJ), blocks
    /// symmetric. When every off-diagonal block is zero only the diagonal
    /// blocks are kept.
    ///
    /// Errors: a column out of range, columns not increasing, a missing
    /// diagonal entry.
    pub fn from_rows(rows: Vec<Vec<(u32, f64, SymmetricBlock)>>) -> Result<Self, SolveError> {
        Self::from_entries(rows, false)
    }

    /// [`VectorOperator::from_rows`] with the blocks given as S_IJ
    /// (`whole` false) or as K_IJ = A_IJ I₃ + S_IJ (`whole` true).
    fn from_entries(
        rows: Vec<Vec<(u32, f64, SymmetricBlock)>>,
        whole: bool,
    ) -> Result<Self, SolveError> {
        let n = rows.len();
        if n >= u32::MAX as usize {
            return Err(SolveError::Dimension(format!("{n} nodes")));
        }
        for (i, row) in rows.iter().enumerate() {
            let increasing = row.windows(2).all(|w| w[0].0 < w[1].0);
            let in_range = row.iter().all(|e| (e.0 as usize) < n);
            let diagonal = row.iter().any(|e| e.0 as usize == i);
            if !increasing || !in_range || !diagonal {
                return Err(SolveError::Dimension(format!(
                    "vector operator row {i}: columns must increase, lie below {n} and include the diagonal"
                )));
            }
        }
        let reaction = |a: f64, b: &SymmetricBlock| {
            if whole {
                [b[0] - a, b[1] - a, b[2] - a, b[3], b[4], b[5]]
            } else {
                *b
            }
        };
        let diagonal_only = rows.iter().enumerate().all(|(i, row)| {
            row.iter()
                .all(|e| e.0 as usize == i || reaction(e.1, &e.2) == [0.0; 6])
        });
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0);
        let nnz: usize = rows.iter().map(Vec::len).sum();
        let mut idx = Vec::with_capacity(nnz);
        let mut a = Vec::with_capacity(nnz);
        let mut s = Vec::with_capacity(if diagonal_only { n } else { nnz });
        for (i, row) in rows.into_iter().enumerate() {
            for (j, v, b) in row {
                idx.push(j);
                a.push(v);
                if !diagonal_only {
                    s.push(if whole { b } else { shifted(v, &b) });
                } else if j as usize == i {
                    s.push(reaction(v, &b));
                }
            }
            ptr.push(idx.len());
        }
        Ok(VectorOperator {
            a: Scalars::new(&ptr, &idx, a),
            ptr,
            idx,
            s: if diagonal_only {
                Blocks::Diagonal(s)
            } else {
                Blocks::Full(s)
            },
        })
    }

    /// The operator A ⊗ I₃ + S with S block-diagonal: A by rows (`ptr`,
    /// columns `idx` strictly increasing per row and including the
    /// diagonal, values `a`) and the diagonal block of S of every node.
    /// A must be symmetric.
    ///
    /// Errors: inconsistent lengths, a column out of range, columns not
    /// increasing, a missing diagonal entry.
    pub fn with_diagonal_blocks(
        ptr: Vec<usize>,
        idx: Vec<u32>,
        a: Vec<f64>,
        s: Vec<SymmetricBlock>,
    ) -> Result<Self, SolveError> {
        let n = s.len();
        let consistent = ptr.len() == n + 1
            && ptr.first() == Some(&0)
            && ptr.windows(2).all(|w| w[0] <= w[1])
            && ptr[n] == idx.len()
            && idx.len() == a.len()
            && n < u32::MAX as usize;
        if !consistent {
            return Err(SolveError::Dimension(format!(
                "vector operator: {} row pointers, {} columns, {} values, {n} blocks",
                ptr.len(),
                idx.len(),
                a.len()
            )));
        }
        let bad = (0..n).into_par_iter().find_first(|&i| {
            let row = &idx[ptr[i]..ptr[i + 1]];
            !row.windows(2).all(|w| w[0] < w[1])
                || row.last().is_some_and(|&j| j as usize >= n)
                || row.binary_search(&(i as u32)).is_err()
        });
        if let Some(i) = bad {
            return Err(SolveError::Dimension(format!(
                "vector operator row {i}: columns must increase, lie below {n} and include the diagonal"
            )));
        }
        Ok(VectorOperator {
            a: Scalars::new(&ptr, &idx, a),
            ptr,
            idx,
            s: Blocks::Diagonal(s),
        })
    }

    /// Number of nodes (a third of the unknowns).
    pub fn nodes(&self) -> usize {
        self.ptr.len() - 1
    }

    /// Stored entries of A (blocks of K).
    pub fn entries(&self) -> usize {
        self.idx.len()
    }

    /// A_IJ of entry `e` of row `i`.
    #[inline]
    fn scalar_entry(&self, i: usize, e: usize) -> f64 {
        match &self.a {
            Scalars::Entries(a) => a[e],
            Scalars::UnitOffDiagonal { diagonal } if self.idx[e] as usize == i => diagonal[i],
            Scalars::UnitOffDiagonal { .. } => -1.0,
        }
    }

    /// Entry `e` of row `i` as (A_IJ, K_IJ = A_IJ I₃ + S_IJ).
    #[inline]
    fn entry(&self, i: usize, e: usize) -> (f64, SymmetricBlock) {
        let diagonal = self.idx[e] as usize == i;
        let a = self.scalar_entry(i, e);
        let k = match &self.s {
            Blocks::Full(k) => k[e],
            Blocks::Diagonal(s) if diagonal => shifted(a, &s[i]),
            Blocks::Diagonal(_) => shifted(a, &[0.0; 6]),
        };
        (a, k)
    }

    /// Row i of K applied to x: Σ_J (A_IJ x_J + S_IJ x_J).
    #[inline(always)]
    fn row_times(&self, i: usize, x: &[f64]) -> [f64; 3] {
        let mut y = [0.0; 3];
        let range = self.ptr[i]..self.ptr[i + 1];
        let xi = &x[3 * i..3 * i + 3];
        match (&self.a, &self.s) {
            (_, Blocks::Full(k)) => {
                for e in range {
                    let j = 3 * self.idx[e] as usize;
                    let t = symmetric_mul(&k[e], &x[j..j + 3]);
                    for c in 0..3 {
                        y[c] += t[c];
                    }
                }
            }
            (Scalars::Entries(a), Blocks::Diagonal(s)) => {
                for e in range {
                    let j = 3 * self.idx[e] as usize;
                    for c in 0..3 {
                        y[c] += a[e] * x[j + c];
                    }
                }
                let t = symmetric_mul(&s[i], xi);
                for c in 0..3 {
                    y[c] += t[c];
                }
            }
            (Scalars::UnitOffDiagonal { diagonal }, Blocks::Diagonal(s)) => {
                // −Σ over every stored entry (the diagonal one included,
                // hence a_II + 1 below): no branch per entry
                for e in range {
                    let j = 3 * self.idx[e] as usize;
                    for c in 0..3 {
                        y[c] -= x[j + c];
                    }
                }
                let t = symmetric_mul(&s[i], xi);
                for c in 0..3 {
                    y[c] += (diagonal[i] + 1.0) * xi[c] + t[c];
                }
            }
        }
        y
    }

    /// y = K x, in parallel.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        for_each_node(y, |i, y| {
            *y = self.row_times(i, x);
        });
    }

    /// One damped block-Jacobi step from `x` into `out`:
    /// out = x + ω D⁻¹ (b − K x), D⁻¹ the inverses of the diagonal blocks
    /// (the residual is formed row by row, never stored).
    fn smooth(
        &self,
        inverses: &[SymmetricBlock],
        omega: f64,
        b: &[f64],
        x: &[f64],
        out: &mut [f64],
    ) {
        for_each_node(out, |i, out| {
            let t = self.row_times(i, x);
            let r = [b[3 * i] - t[0], b[3 * i + 1] - t[1], b[3 * i + 2] - t[2]];
            let z = symmetric_mul(&inverses[i], &r);
            for c in 0..3 {
                out[c] = x[3 * i + c] + omega * z[c];
            }
        });
    }

    /// y = b − K x, in parallel.
    fn residual(&self, b: &[f64], x: &[f64], y: &mut [f64]) {
        for_each_node(y, |i, y| {
            let t = self.row_times(i, x);
            for r in 0..3 {
                y[r] = b[3 * i + r] - t[r];
            }
        });
    }

    /// The diagonal block A_II I₃ + S_II of node i (row-major 3 × 3).
    fn diagonal_block(&self, i: usize) -> [f64; 9] {
        let mut m = [0.0; 9];
        for e in self.ptr[i]..self.ptr[i + 1] {
            if self.idx[e] as usize == i {
                for (r, row) in full_block(&self.entry(i, e).1).iter().enumerate() {
                    m[3 * r..3 * r + 3].copy_from_slice(row);
                }
            }
        }
        m
    }

    /// The scalar matrix A.
    fn scalar(&self) -> CsrMatrix {
        let n = self.nodes();
        let val = match &self.a {
            Scalars::Entries(a) => a.clone(),
            Scalars::UnitOffDiagonal { .. } => (0..n)
                .into_par_iter()
                .flat_map_iter(|i| (self.ptr[i]..self.ptr[i + 1]).map(move |e| self.entry(i, e).0))
                .collect(),
        };
        CsrMatrix {
            nrows: n,
            ncols: n,
            ptr: self.ptr.clone(),
            idx: self.idx.clone(),
            val,
        }
    }

    /// Per node, (J, ‖A_IJ I₃ + S_IJ‖²_F) over its stored entries.
    fn strength_norms(&self) -> Vec<Vec<(u32, f64)>> {
        (0..self.nodes())
            .into_par_iter()
            .map(|i| {
                (self.ptr[i]..self.ptr[i + 1])
                    .map(|e| {
                        let k = self.entry(i, e).1;
                        let diagonal = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                        let off = 2.0 * (k[3] * k[3] + k[4] * k[4] + k[5] * k[5]);
                        (self.idx[e], diagonal + off)
                    })
                    .collect()
            })
            .collect()
    }

    /// The Galerkin operator (P ⊗ I₃)ᵀ K (P ⊗ I₃) for the scalar
    /// prolongator `p` (with its transpose `pt`), symmetrised; a node whose
    /// row vanishes (a zero column of `p`) gets a unit diagonal.
    ///
    /// With S on the diagonal only, Pᵀ A P and Pᵀ S P are summed apart:
    /// an off-diagonal entry of K adds one scalar per coarse pair instead
    /// of seven values.
    fn galerkin(&self, p: &CsrMatrix, pt: &CsrMatrix) -> Result<VectorOperator, SolveError> {
        let nc = p.ncols;
        type Row = Vec<(u32, f64, SymmetricBlock)>;
        // a few tasks per thread also on small coarse levels (each with an
        // accumulator as long as a coarse row)
        let per_task = nc
            .div_ceil(4 * rayon::current_num_threads())
            .clamp(16, ROWS);
        let reaction_only = matches!(self.s, Blocks::Diagonal(_));
        let rows: Vec<Row> = (0..nc.div_ceil(per_task))
            .into_par_iter()
            .flat_map_iter(|c| {
                // column sums of (A, K) for Full, (A, S) for Diagonal
                let mut acc = RowAccumulator::<7>::new(nc);
                let mut out: Vec<Row> = Vec::new();
                for ci in c * per_task..((c + 1) * per_task).min(nc) {
                    let (ki, kv) = pt.row(ci);
                    for (&k, &pk) in ki.iter().zip(kv) {
                        let k = k as usize;
                        for e in self.ptr[k]..self.ptr[k + 1] {
                            let l = self.idx[e] as usize;
                            let (li, lv) = p.row(l);
                            let (a, s) = match &self.s {
                                Blocks::Full(blocks) => (self.scalar_entry(k, e), blocks[e]),
                                Blocks::Diagonal(blocks) if l == k => {
                                    (self.scalar_entry(k, e), blocks[k])
                                }
                                Blocks::Diagonal(_) => {
                                    let a = self.scalar_entry(k, e);
                                    for (&j, &pl) in li.iter().zip(lv) {
                                        acc.add_first(j, pk * pl * a);
                                    }
                                    continue;
                                }
                            };
                            for (&j, &pl) in li.iter().zip(lv) {
                                let w = pk * pl;
                                acc.add_vector(
                                    j,
                                    [
                                        w * a,
                                        w * s[0],
                                        w * s[1],
                                        w * s[2],
                                        w * s[3],
                                        w * s[4],
                                        w * s[5],
                                    ],
                                );
                            }
                        }
                    }
                    let mut row = Vec::new();
                    acc.flush_with(|j, v| {
                        let s = [v[1], v[2], v[3], v[4], v[5], v[6]];
                        row.push((j, v[0], if reaction_only { shifted(v[0], &s) } else { s }));
                    });
                    out.push(row);
                }
                out
            })
            .collect();
        // symmetrise: average (I, J) and (J, I) (equal up to rounding)
        let rows: Vec<Row> = rows
            .par_iter()
            .enumerate()
            .map(|(i, row)| {
                let mut out: Row = row
                    .iter()
                    .map(|&(j, a, s)| {
                        let other = &rows[j as usize];
                        match other.binary_search_by_key(&(i as u32), |e| e.0) {
                            Ok(q) => {
                                let (_, b, t) = other[q];
                                let mut m = [0.0; 6];
                                for r in 0..6 {
                                    m[r] = 0.5 * (s[r] + t[r]);
                                }
                                (j, 0.5 * (a + b), m)
                            }
                            Err(_) => (j, a, s),
                        }
                    })
                    .collect();
                let vanishes = out.iter().all(|e| e.1 == 0.0 && e.2 == [0.0; 6]);
                if vanishes || !out.iter().any(|e| e.0 as usize == i) {
                    out.retain(|e| e.0 as usize != i);
                    let at = out.partition_point(|e| (e.0 as usize) < i);
                    let a = if vanishes { 1.0 } else { 0.0 };
                    out.insert(at, (i as u32, a, shifted(a, &[0.0; 6])));
                }
                out
            })
            .collect();
        VectorOperator::from_entries(rows, true)
    }

    /// The assembled 3n × 3n matrix (both triangles).
    fn to_faer(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        let mut t = Vec::with_capacity(9 * self.entries());
        for i in 0..self.nodes() {
            for e in self.ptr[i]..self.ptr[i + 1] {
                let j = self.idx[e] as usize;
                let m = full_block(&self.entry(i, e).1);
                for (r, row) in m.iter().enumerate() {
                    for (c, &v) in row.iter().enumerate() {
                        if v != 0.0 {
                            t.push(Triplet::new(3 * i + r, 3 * j + c, v));
                        }
                    }
                }
            }
        }
        let n = 3 * self.nodes();
        SparseColMat::try_new_from_triplets(n, n, &t)
            .map_err(|e| SolveError::Backend(format!("{e:?}")))
    }
}

/// Options of [`VectorAmg::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct VectorAmgOptions {
    /// Damped block-Jacobi steps before and after each coarse correction.
    pub smoothing_steps: usize,
    /// Factor the level directly once it has at most this many nodes.
    pub max_coarse_nodes: usize,
    /// Largest number of levels.
    pub max_levels: usize,
    /// Strength threshold θ of the aggregation: nodes I, J are aggregated
    /// together only when ‖K_IJ‖ ≥ θ √(‖K_II‖ ‖K_JJ‖) (Frobenius norms).
    pub strength: f64,
}

impl Default for VectorAmgOptions {
    fn default() -> Self {
        VectorAmgOptions {
            smoothing_steps: 1,
            max_coarse_nodes: 150,
            max_levels: 10,
            strength: 0.08,
        }
    }
}

crate::control::setters!(VectorAmgOptions {
    smoothing_steps: usize,
    max_coarse_nodes: usize,
    max_levels: usize,
    strength: f64,
});

struct Level {
    k: VectorOperator,
    /// Inverses of the diagonal blocks of K (symmetric).
    inverses: Vec<SymmetricBlock>,
    omega: f64,
    /// Scalar prolongator from the next coarser level and its transpose.
    p: CsrMatrix,
    pt: CsrMatrix,
}

/// A smoothed-aggregation multigrid V-cycle for K = A ⊗ I₃ + S, a
/// symmetric positive-definite preconditioner of K (module documentation).
pub struct VectorAmg {
    levels: Vec<Level>,
    coarse: CholeskySolver,
    smoothing_steps: usize,
    workspace: Mutex<Vec<[Vec<f64>; 4]>>,
}

impl VectorAmg {
    /// Builds the hierarchy for the symmetric positive-definite `k` with
    /// the scalar near-null vector `nullspace` (one value per node; ones
    /// for the translations).
    ///
    /// Errors: a near-null vector of the wrong length, a coarsest operator
    /// that is not positive definite (K was not).
    pub fn new(
        k: VectorOperator,
        nullspace: &[f64],
        options: &VectorAmgOptions,
    ) -> Result<VectorAmg, SolveError> {
        if nullspace.len() != k.nodes() {
            return Err(SolveError::Dimension(format!(
                "vector multigrid: {} nodes, near-null vector of length {}",
                k.nodes(),
                nullspace.len()
            )));
        }
        let mut levels = Vec::new();
        let mut k = k;
        let mut b = nullspace.to_vec();
        loop {
            let n = k.nodes();
            if n <= options.max_coarse_nodes || levels.len() + 1 >= options.max_levels {
                break;
            }
            let aggregates = aggregate_nodes(&k.strength_norms(), options.strength);
            let count = aggregates
                .iter()
                .map(|&a| a as usize + 1)
                .max()
                .unwrap_or(0);
            if count >= n {
                break;
            }
            let (t, coarse_b) = tentative(&aggregates, count, 1, &b, 1);
            let a = k.scalar();
            let (a_inverse, a_omega, a_power) = block_jacobi(&a, 1);
            let p = smooth_prolongator(&t, &a.matmul(&t), &a_inverse, 1, a_omega);
            let pt = p.transpose();
            let kc = k.galerkin(&p, &pt)?;
            let (inverses, omega) = vector_jacobi(&k, a_power);
            levels.push(Level {
                k,
                inverses,
                omega,
                p,
                pt,
            });
            k = kc;
            b = coarse_b;
        }
        let coarse = CholeskySolver::new(k.to_faer()?.as_ref())?;
        let mut amg = VectorAmg {
            levels,
            coarse,
            smoothing_steps: options.smoothing_steps.max(1),
            workspace: Mutex::new(Vec::new()),
        };
        amg.workspace = Mutex::new(amg.new_workspace());
        Ok(amg)
    }

    /// Nodes and stored entries per level, finest first (the last level is
    /// factored).
    pub fn sizes(&self) -> Vec<(usize, usize)> {
        let mut s: Vec<(usize, usize)> = self
            .levels
            .iter()
            .map(|l| (l.k.nodes(), l.k.entries()))
            .collect();
        s.push((self.coarse.dim() / 3, self.coarse.factor_len()));
        s
    }

    /// Scratch vectors of every level: the other iterate of the smoothing
    /// steps, the residual, the coarse residual, the coarse correction.
    fn new_workspace(&self) -> Vec<[Vec<f64>; 4]> {
        self.levels
            .iter()
            .map(|l| {
                let (n, nc) = (3 * l.k.nodes(), 3 * l.p.ncols);
                [vec![0.0; n], vec![0.0; n], vec![0.0; nc], vec![0.0; nc]]
            })
            .collect()
    }

    /// x = V-cycle applied to b from `level` down, with `pre` smoothing
    /// steps before the coarse correction and `post` after, on every
    /// level. The steps alternate between x and a scratch vector, which
    /// one holds the iterate first is chosen so that the result ends in x
    /// without a copy.
    fn cycle(
        &self,
        level: usize,
        b: &[f64],
        x: &mut [f64],
        workspace: &mut [[Vec<f64>; 4]],
        (pre, post): (usize, usize),
    ) {
        if level == self.levels.len() {
            x.copy_from_slice(b);
            if self.coarse.solve_in_place(x).is_err() {
                x.iter_mut().for_each(|v| *v = 0.0);
            }
            return;
        }
        let l = &self.levels[level];
        let Some(([other, r, rc, xc], deeper)) = workspace.split_first_mut() else {
            return;
        };
        // steps that move the iterate to the other vector: pre − 1
        // smoothing steps, the prolongation, post smoothing steps
        let moves = pre.saturating_sub(1) + 1 + post;
        let (mut current, mut next): (&mut [f64], &mut [f64]) = if moves % 2 == 0 {
            (x, other)
        } else {
            (other, x)
        };
        if pre > 0 {
            // pre-smoothing from x = 0: the first step is x = ω D⁻¹ b
            scale_by_inverses(&l.inverses, l.omega, b, current);
            for _ in 1..pre {
                l.k.smooth(&l.inverses, l.omega, b, current, next);
                std::mem::swap(&mut current, &mut next);
            }
            l.k.residual(b, current, r);
            mul_coordinates(&l.pt, r, rc);
        } else {
            // x = 0: the residual is b
            mul_coordinates(&l.pt, b, rc);
        }
        self.cycle(level + 1, rc, xc, deeper, (pre, post));
        prolong_add(&l.p, xc, (pre > 0).then_some(&*current), next);
        std::mem::swap(&mut current, &mut next);
        for _ in 0..post {
            l.k.smooth(&l.inverses, l.omega, b, current, next);
            std::mem::swap(&mut current, &mut next);
        }
    }

    /// Runs `cycle` from the finest level with the shared scratch vectors
    /// (no page faults on fresh memory each cycle); a concurrent call gets
    /// its own.
    fn run(&self, r: &[f64], z: &mut [f64], steps: (usize, usize)) {
        match self.workspace.try_lock() {
            Ok(mut workspace) => self.cycle(0, r, z, &mut workspace, steps),
            Err(_) => self.cycle(0, r, z, &mut self.new_workspace(), steps),
        }
    }

    /// The V-cycle with ν smoothing steps before each coarse correction
    /// and none after, V_pre; [`VectorAmg::apply_post`] is its transpose,
    /// so V_preᵀ W V_pre is symmetric positive semi-definite for every
    /// symmetric positive semi-definite W, at the cost of one symmetric
    /// V-cycle. (With T = I − ω D⁻¹K and Z = Σ_{i<ν} Tⁱ ω D⁻¹, Z is
    /// symmetric and I − Z K = T^ν, so V_pre = Z + P V_pre,c Pᵀ (I − K Z)
    /// has the transpose Z + T^ν P V_pre,cᵀ Pᵀ, the cycle with ν steps after
    /// each coarse correction only, by induction over the levels.)
    pub fn apply_pre(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (self.smoothing_steps, 0));
    }

    /// The transpose of [`VectorAmg::apply_pre`]: ν smoothing steps after
    /// each coarse correction and none before.
    pub fn apply_post(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (0, self.smoothing_steps));
    }
}

impl Preconditioner for VectorAmg {
    /// The symmetric V-cycle: ν steps before and ν after each coarse
    /// correction.
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (self.smoothing_steps, self.smoothing_steps));
    }
}

/// y = (M ⊗ I₃) x for a scalar matrix M on interleaved coordinates.
fn mul_coordinates(m: &CsrMatrix, x: &[f64], y: &mut [f64]) {
    for_each_node(y, |i, y| {
        let (idx, val) = m.row(i);
        let mut s = [0.0; 3];
        for (&j, &v) in idx.iter().zip(val) {
            let j = 3 * j as usize;
            for r in 0..3 {
                s[r] += v * x[j + r];
            }
        }
        *y = s;
    });
}

/// out = base + (M ⊗ I₃) x for a scalar matrix M on interleaved
/// coordinates (the prolongation of a coarse correction, added; base 0
/// when None).
fn prolong_add(m: &CsrMatrix, x: &[f64], base: Option<&[f64]>, out: &mut [f64]) {
    for_each_node(out, |i, out| {
        let (idx, val) = m.row(i);
        let mut s = base.map_or([0.0; 3], |b| [b[3 * i], b[3 * i + 1], b[3 * i + 2]]);
        for (&j, &v) in idx.iter().zip(val) {
            let j = 3 * j as usize;
            for r in 0..3 {
                s[r] += v * x[j + r];
            }
        }
        *out = s;
    });
}

/// x = ω D⁻¹ r, D⁻¹ the symmetric inverses of the 3 × 3 diagonal blocks.
fn scale_by_inverses(inverses: &[SymmetricBlock], omega: f64, r: &[f64], x: &mut [f64]) {
    x.par_chunks_mut(3 * NODES)
        .zip(r.par_chunks(3 * NODES))
        .zip(inverses.par_chunks(NODES))
        .with_min_len(MIN_TASK_CHUNKS)
        .for_each(|((x, r), inv)| {
            for ((x, r), m) in x.chunks_mut(3).zip(r.chunks(3)).zip(inv) {
                let z = symmetric_mul(m, r);
                for i in 0..3 {
                    x[i] = omega * z[i];
                }
            }
        });
}

/// Inverses of the diagonal blocks of K and the smoother's damping
/// 4 / (3 ρ̄), ρ̄ the smaller of the largest absolute row sum of D⁻¹K and
/// 1.1 times a power-iteration estimate of ρ(D⁻¹K), given `scalar_power`,
/// that estimate of ρ(D_A⁻¹A).
///
/// When S is block-diagonal (the finest level of vertex flow) that of A
/// serves: D = D_A ⊗ I₃ + S, and for every x
/// xᵀKx / xᵀDx = (xᵀ(A ⊗ I₃)x + xᵀSx) / (xᵀ(D_A ⊗ I₃)x + xᵀSx)
/// ≤ max(ρ(D_A⁻¹A), 1) = ρ(D_A⁻¹A) (S ⪰ 0; the mean eigenvalue of D_A⁻¹A
/// is 1), so ρ(D⁻¹K) ≤ ρ(D_A⁻¹A) — fifteen products with K saved.
fn vector_jacobi(k: &VectorOperator, scalar_power: f64) -> (Vec<SymmetricBlock>, f64) {
    let n = k.nodes();
    let inverses: Vec<SymmetricBlock> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut m = k.diagonal_block(i);
            let mut inv = [0.0; 9];
            invert_spd(&mut m, 3, &mut inv);
            // symmetric up to rounding: average the two triangles
            let mean = |r: usize, c: usize| 0.5 * (inv[3 * r + c] + inv[3 * c + r]);
            [inv[0], inv[4], inv[8], mean(0, 1), mean(0, 2), mean(1, 2)]
        })
        .collect();
    let gershgorin = (0..n)
        .into_par_iter()
        .map(|i| {
            let inv = full_block(&inverses[i]);
            let mut sums = [0.0f64; 3];
            for e in k.ptr[i]..k.ptr[i + 1] {
                let m = full_block(&k.entry(i, e).1);
                for (r, sum) in sums.iter_mut().enumerate() {
                    for c in 0..3 {
                        let v: f64 = (0..3).map(|l| inv[r][l] * m[l][c]).sum();
                        *sum += v.abs();
                    }
                }
            }
            sums.into_iter().fold(0.0f64, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    let power = if matches!(k.s, Blocks::Diagonal(_)) {
        scalar_power.max(1.0)
    } else {
        let mut y = vec![0.0; 3 * n];
        power_iterations(3 * n, |x, z| {
            k.mul_vec(x, &mut y);
            scale_by_inverses(&inverses, 1.0, &y, z);
        })
    };
    (inverses, jacobi_damping(gershgorin, power))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::pcg;

    /// K = A ⊗ I₃ + S on a side × side grid: A the 4-neighbour graph
    /// Laplacian with a Dirichlet term on the left column (a_ii + 1), S a
    /// reaction `strength` · n nᵀ per node with n turning with the column
    /// (as the normal of a cylinder turns around it), so the motion along
    /// n is held by S and the two other directions by A alone.
    fn grid(side: usize, strength: f64) -> VectorOperator {
        let node = |x: usize, y: usize| (y * side + x) as u32;
        let rows = (0..side * side)
            .map(|i| {
                let (x, y) = (i % side, i / side);
                let mut row = Vec::new();
                let mut degree = 0.0;
                for (dx, dy) in [(0i64, -1i64), (-1, 0), (1, 0), (0, 1)] {
                    let (u, v) = (x as i64 + dx, y as i64 + dy);
                    if u >= 0 && v >= 0 && (u as usize) < side && (v as usize) < side {
                        row.push((node(u as usize, v as usize), -1.0, [0.0; 6]));
                        degree += 1.0;
                    }
                }
                if x == 0 {
                    degree += 1.0;
                }
                let angle = std::f64::consts::TAU * x as f64 / side as f64;
                let n = [angle.cos(), angle.sin(), 0.0];
                let s = [
                    strength * n[0] * n[0],
                    strength * n[1] * n[1],
                    0.0,
                    strength * n[0] * n[1],
                    0.0,
                    0.0,
                ];
                row.push((i as u32, degree, s));
                row.sort_by_key(|e| e.0);
                row
            })
            .collect();
        VectorOperator::from_rows(rows).unwrap()
    }

    fn dense(k: &VectorOperator) -> Vec<Vec<f64>> {
        let n = 3 * k.nodes();
        let m = k.to_faer().unwrap();
        let mut d = vec![vec![0.0; n]; n];
        for j in 0..n {
            for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
                d[i][j] = v;
            }
        }
        d
    }

    /// K x equals the dense matrix `d` times x, entry by entry.
    fn assert_product_is_dense(k: &VectorOperator, d: &[Vec<f64>], x: &[f64]) {
        let n = x.len();
        let mut y = vec![0.0; n];
        k.mul_vec(x, &mut y);
        for i in 0..n {
            let e: f64 = (0..n).map(|j| d[i][j] * x[j]).sum();
            assert!(
                (y[i] - e).abs() <= 1e-12 * (1.0 + e.abs()),
                "{i}: {} vs {e}",
                y[i]
            );
        }
    }

    fn vector(n: usize, seed: f64) -> Vec<f64> {
        (0..n).map(|i| (seed * (i as f64 + 1.0)).sin()).collect()
    }

    /// The structured product equals the assembled matrix; the Galerkin
    /// operator of the structure equals (P ⊗ I₃)ᵀ K (P ⊗ I₃) formed densely,
    /// including its off-diagonal blocks, and its product is again that
    /// matrix.
    #[test]
    fn structure_matches_the_assembled_matrices() {
        let k = grid(6, 2.0);
        let n = 3 * k.nodes();
        let d = dense(&k);
        let x = vector(n, 0.37);
        assert_product_is_dense(&k, &d, &x);
        // a smoothed prolongator of the scalar part from aggregates
        let aggregates = aggregate_nodes(&k.strength_norms(), 0.08);
        let count = aggregates.iter().map(|&a| a as usize + 1).max().unwrap();
        assert!(count < k.nodes() / 2, "{count} aggregates");
        let (t, _) = tentative(&aggregates, count, 1, &vec![1.0; k.nodes()], 1);
        let a = k.scalar();
        let (inverse, omega, _) = block_jacobi(&a, 1);
        let p = smooth_prolongator(&t, &a.matmul(&t), &inverse, 1, omega);
        let kc = k.galerkin(&p, &p.transpose()).unwrap();
        assert!(matches!(kc.s, Blocks::Full(_)));
        let dc = dense(&kc);
        let nc = 3 * count;
        // P ⊗ I₃ densely
        let mut pp = vec![vec![0.0; nc]; n];
        for i in 0..k.nodes() {
            let (idx, val) = p.row(i);
            for (&j, &v) in idx.iter().zip(val) {
                for c in 0..3 {
                    pp[3 * i + c][3 * j as usize + c] = v;
                }
            }
        }
        let scale = d.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for r in 0..nc {
            for c in 0..nc {
                let mut e = 0.0;
                for i in 0..n {
                    if pp[i][r] == 0.0 {
                        continue;
                    }
                    for j in 0..n {
                        e += pp[i][r] * d[i][j] * pp[j][c];
                    }
                }
                assert!(
                    (dc[r][c] - e).abs() <= 1e-12 * scale,
                    "({r}, {c}): {} vs {e}",
                    dc[r][c]
                );
            }
        }
        let xc = vector(nc, 0.91);
        let mut yc = vec![0.0; nc];
        kc.mul_vec(&xc, &mut yc);
        for r in 0..nc {
            let e: f64 = (0..nc).map(|c| dc[r][c] * xc[c]).sum();
            assert!((yc[r] - e).abs() <= 1e-11 * scale * (1.0 + e.abs()));
        }
    }

    /// Both storages of A with a diagonal S (unit off-diagonal values, as
    /// the finest H; stored values) multiply like the assembled matrix, and one smoothing step equals x + ω D⁻¹(b − K x)
    /// formed densely.
    #[test]
    fn every_storage_multiplies_and_smooths_like_the_matrix() {
        let unit = grid(5, 1.5);
        assert!(matches!(unit.a, Scalars::UnitOffDiagonal { .. }));
        // the same operator with A doubled: stored values
        let rows: Vec<Vec<(u32, f64, SymmetricBlock)>> = (0..unit.nodes())
            .map(|i| {
                (unit.ptr[i]..unit.ptr[i + 1])
                    .map(|e| {
                        let (a, k) = unit.entry(i, e);
                        let s = [k[0] - a, k[1] - a, k[2] - a, k[3], k[4], k[5]];
                        (unit.idx[e], 2.0 * a, s)
                    })
                    .collect()
            })
            .collect();
        let general = VectorOperator::from_rows(rows).unwrap();
        assert!(matches!(general.a, Scalars::Entries(_)));
        assert!(matches!(general.s, Blocks::Diagonal(_)));
        for k in [&unit, &general] {
            let n = 3 * k.nodes();
            let d = dense(k);
            let (x, b) = (vector(n, 0.43), vector(n, 1.1));
            assert_product_is_dense(k, &d, &x);
            let (inverses, omega) = vector_jacobi(k, block_jacobi(&k.scalar(), 1).2);
            let mut smoothed = vec![0.0; n];
            k.smooth(&inverses, omega, &b, &x, &mut smoothed);
            for node in 0..k.nodes() {
                let r: Vec<f64> = (0..3)
                    .map(|c| {
                        let row = 3 * node + c;
                        b[row] - (0..n).map(|j| d[row][j] * x[j]).sum::<f64>()
                    })
                    .collect();
                let z = symmetric_mul(&inverses[node], &r);
                for c in 0..3 {
                    let e = x[3 * node + c] + omega * z[c];
                    let got = smoothed[3 * node + c];
                    assert!((got - e).abs() <= 1e-12 * (1.0 + e.abs()), "{got} vs {e}");
                }
            }
        }
    }

    /// Largest eigenvalue of the symmetric dense matrix `m`.
    fn largest_eigenvalue(m: &[Vec<f64>]) -> f64 {
        let n = m.len();
        let dense = faer::Mat::from_fn(n, n, |i, j| m[i][j]);
        let values = dense.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        values[n - 1]
    }

    /// What lets the finest level skip its own power iterations: with S
    /// block-diagonal, ρ(D⁻¹K) ≤ ρ(D_A⁻¹A) (dense eigenvalues of the
    /// symmetric forms D^{-1/2} K D^{-1/2}), equal when S vanishes (and
    /// here also with S of rank one per node: the two directions it leaves
    /// free carry the top eigenvector).
    #[test]
    fn diagonal_reaction_does_not_raise_the_jacobi_spectral_radius() {
        for strength in [0.0, 0.3, 5.0] {
            let k = grid(6, strength);
            assert!(matches!(k.s, Blocks::Diagonal(_)));
            let (a, d) = (k.scalar(), dense(&k));
            let n = k.nodes();
            // D_A^{-1/2} A D_A^{-1/2}
            let a_diagonal: Vec<f64> = (0..n)
                .map(|i| {
                    let (idx, val) = a.row(i);
                    idx.iter()
                        .zip(val)
                        .find(|e| *e.0 as usize == i)
                        .unwrap()
                        .1
                        .sqrt()
                })
                .collect();
            let scaled_a: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    let mut row = vec![0.0; n];
                    let (idx, val) = a.row(i);
                    for (&j, &v) in idx.iter().zip(val) {
                        row[j as usize] = v / (a_diagonal[i] * a_diagonal[j as usize]);
                    }
                    row
                })
                .collect();
            // D^{-1/2} K D^{-1/2} with the 3 × 3 diagonal blocks of K
            let roots: Vec<glam::DMat3> = (0..n)
                .map(|i| {
                    let b = k.diagonal_block(i);
                    let m = glam::DMat3::from_cols_array(&b).transpose();
                    crate::solve::symmetric_function3(m, |x| 1.0 / x.sqrt())
                })
                .collect();
            let scaled_k: Vec<Vec<f64>> = (0..3 * n)
                .map(|r| {
                    (0..3 * n)
                        .map(|c| {
                            let (ri, ci) = (r / 3, c / 3);
                            let mut v = 0.0;
                            for p in 0..3 {
                                for q in 0..3 {
                                    v += roots[ri].col(p)[r % 3]
                                        * d[3 * ri + p][3 * ci + q]
                                        * roots[ci].col(c % 3)[q];
                                }
                            }
                            v
                        })
                        .collect()
                })
                .collect();
            let (rho_a, rho_k) = (largest_eigenvalue(&scaled_a), largest_eigenvalue(&scaled_k));
            assert!(rho_a > 1.0, "{rho_a}");
            if strength == 0.0 {
                assert!((rho_k - rho_a).abs() <= 1e-12, "{rho_k} vs {rho_a}");
            } else {
                assert!(rho_k <= rho_a + 1e-12, "S = {strength}: {rho_k} > {rho_a}");
            }
        }
    }

    fn solve(k: &VectorOperator, preconditioner: Option<&VectorAmg>) -> (usize, Vec<f64>) {
        let n = 3 * k.nodes();
        let rhs = vector(n, 0.61);
        let mut x = vec![0.0; n];
        let inverses = vector_jacobi(k, block_jacobi(&k.scalar(), 1).2).0;
        let report = pcg(
            |v: &[f64], out: &mut [f64]| k.mul_vec(v, out),
            |r: &[f64], z: &mut [f64]| match preconditioner {
                Some(p) => p.apply(r, z),
                None => scale_by_inverses(&inverses, 1.0, r, z),
            },
            &rhs,
            &mut x,
            1e-10,
            20_000,
        )
        .unwrap();
        assert!(report.converged, "{report:?}");
        (report.iterations, x)
    }

    /// Preconditioned by the V-cycle, conjugate gradients need about as
    /// many iterations on a 96 × 96 grid as on a 24 × 24 one and far fewer
    /// than with block Jacobi, and reach the direct solution.
    #[test]
    fn multigrid_iterations_do_not_grow_with_the_grid() {
        let mut counts = Vec::new();
        for side in [24, 48, 96] {
            let k = grid(side, 4.0);
            let amg = VectorAmg::new(
                k.clone(),
                &vec![1.0; k.nodes()],
                &VectorAmgOptions {
                    smoothing_steps: 2,
                    max_coarse_nodes: 50,
                    ..VectorAmgOptions::default()
                },
            )
            .unwrap();
            assert!(amg.sizes().len() >= 3, "{:?}", amg.sizes());
            let (iterations, x) = solve(&k, Some(&amg));
            counts.push(iterations);
            if side == 24 {
                let (jacobi, _) = solve(&k, None);
                assert!(
                    5 * iterations <= jacobi,
                    "multigrid {iterations}, Jacobi {jacobi}"
                );
                let mut exact = vector(3 * k.nodes(), 0.61);
                CholeskySolver::new(k.to_faer().unwrap().as_ref())
                    .unwrap()
                    .solve_in_place(&mut exact)
                    .unwrap();
                let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let diff = x
                    .iter()
                    .zip(&exact)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                assert!(diff <= 1e-7 * scale, "difference {diff}, scale {scale}");
            }
        }
        println!("vector multigrid iterations on 24², 48², 96² grids: {counts:?}");
        assert!(counts[2] <= counts[0] + counts[0] / 2 + 2, "{counts:?}");
    }

    /// The V-cycle is a symmetric positive-definite operator (conjugate
    /// gradients need both).
    #[test]
    fn v_cycle_is_symmetric_positive_definite() {
        let k = grid(20, 3.0);
        let amg = VectorAmg::new(
            k.clone(),
            &vec![1.0; k.nodes()],
            &VectorAmgOptions {
                max_coarse_nodes: 30,
                ..VectorAmgOptions::default()
            },
        )
        .unwrap();
        let n = 3 * k.nodes();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (x, y) = (vector(n, 0.61), vector(n, 1.37));
        let (mut px, mut py) = (vec![0.0; n], vec![0.0; n]);
        amg.apply(&x, &mut px);
        amg.apply(&y, &mut py);
        let (a, b) = (dot(&y, &px), dot(&x, &py));
        assert!((a - b).abs() <= 1e-10 * a.abs().max(b.abs()), "{a} vs {b}");
        for seed in [0.61, 1.37, 2.9, 0.05] {
            let v = vector(n, seed);
            let mut pv = vec![0.0; n];
            amg.apply(&v, &mut pv);
            assert!(dot(&v, &pv) > 0.0);
        }
    }

    /// The cycle with smoothing before each coarse correction only and
    /// the one with smoothing after it only are each other's transposes
    /// (for 1 to 4 steps, an odd and an even count, over three levels),
    /// neither is symmetric by itself, and their product Vᵀ V is positive
    /// definite.
    #[test]
    fn one_sided_cycles_are_transposes() {
        let k = grid(20, 3.0);
        let n = 3 * k.nodes();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (x, y) = (vector(n, 0.61), vector(n, 1.37));
        for steps in 1..=4 {
            let amg = VectorAmg::new(
                k.clone(),
                &vec![1.0; k.nodes()],
                &VectorAmgOptions {
                    smoothing_steps: steps,
                    max_coarse_nodes: 30,
                    ..VectorAmgOptions::default()
                },
            )
            .unwrap();
            assert!(amg.sizes().len() >= 3, "{:?}", amg.sizes());
            let mut v = vec![0.0; n];
            let mut w = vec![0.0; n];
            // ⟨y, V x⟩ = ⟨Vᵀ y, x⟩
            amg.apply_pre(&x, &mut v);
            amg.apply_post(&y, &mut w);
            let (a, b) = (dot(&y, &v), dot(&w, &x));
            assert!(
                (a - b).abs() <= 1e-10 * a.abs().max(b.abs()),
                "{steps}: {a} vs {b}"
            );
            // V alone is not symmetric: ⟨y, V x⟩ ≠ ⟨V y, x⟩
            let mut vy = vec![0.0; n];
            amg.apply_pre(&y, &mut vy);
            let c = dot(&vy, &x);
            assert!((a - c).abs() > 1e-6 * a.abs(), "{steps}: {a} vs {c}");
            // Vᵀ V x then ⟨x, Vᵀ V x⟩ = ‖V x‖² > 0
            let mut vtv = vec![0.0; n];
            amg.apply_post(&v, &mut vtv);
            let q = dot(&x, &vtv);
            assert!((q - dot(&v, &v)).abs() <= 1e-10 * q, "{steps}: {q}");
        }
    }

    /// Malformed operators are refused with an error, not a panic.
    #[test]
    fn malformed_operators_are_refused() {
        let block = [0.0; 6];
        // missing diagonal
        assert!(
            VectorOperator::from_rows(vec![vec![(1, -1.0, block)], vec![(1, 1.0, block)]]).is_err()
        );
        // column out of range, unsorted
        assert!(VectorOperator::from_rows(vec![vec![(0, 1.0, block), (5, -1.0, block)]]).is_err());
        assert!(
            VectorOperator::from_rows(vec![
                vec![(1, -1.0, block), (0, 2.0, block)],
                vec![(0, -1.0, block), (1, 2.0, block)]
            ])
            .is_err()
        );
        assert!(
            VectorOperator::with_diagonal_blocks(vec![0, 1], vec![0], vec![1.0, 2.0], vec![block])
                .is_err()
        );
        assert!(
            VectorOperator::with_diagonal_blocks(vec![0, 1], vec![1], vec![1.0], vec![block])
                .is_err()
        );
        let k = grid(4, 1.0);
        assert!(VectorAmg::new(k, &[1.0; 3], &VectorAmgOptions::default()).is_err());
    }
}
