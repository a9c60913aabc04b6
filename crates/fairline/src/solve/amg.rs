//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996,
//! "Algebraic multigrid by smoothed aggregation for second and fourth order
//! elliptic problems", Computing 56) as a preconditioner of conjugate
//! gradients for a sparse symmetric positive-definite matrix K with a block
//! structure (b unknowns per node, e.g. the three coordinates of a vertex).
//!
//! Setup, per level:
//! 1. **Aggregation** of the nodes over the graph of K (node i and j are
//!    neighbours when the block K_ij is stored): greedy, in node order —
//!    a node all of whose neighbours are free becomes the root of an
//!    aggregate holding it and its neighbours; left-over nodes join the
//!    aggregate of a neighbour; the rest form aggregates with their free
//!    neighbours. Weak couplings are dropped ([`AmgOptions::strength`]).
//!    Deterministic.
//! 2. **Tentative prolongator** T: per aggregate, the near-null-space
//!    vectors B restricted to its unknowns, orthonormalised (modified
//!    Gram–Schmidt, twice); B_a = Q_a R_a gives the columns Q_a of T and the
//!    coarse near-null space R_a. A vector that is (numerically) dependent
//!    on the previous ones on an aggregate gives a zero column, i.e. an idle
//!    coarse unknown with a unit diagonal.
//! 3. **Prolongator smoothing** P = (I − ω D⁻¹K) T with D the block
//!    diagonal of K and ω = 4 / (3 ρ̄), ρ̄ an estimate of ρ(D⁻¹K): the
//!    smaller of the largest absolute row sum of D⁻¹K (a Gershgorin bound)
//!    and 1.1 times the estimate of 15 power iterations.
//! 4. **Galerkin coarse matrix** K_c = Pᵀ K P (symmetrised), until the
//!    coarse matrix is small; the coarsest is factored by
//!    [`super::CholeskySolver`].
//!
//! Apply: one symmetric V-cycle — ν damped block-Jacobi steps
//! x ← x + ω D⁻¹(b − K x) before and ν after the coarse correction, with
//! restriction Pᵀ and prolongation P. The smoother is convergent in the K
//! norm (ω ρ(D⁻¹K) ≤ 4/3 < 2), pre- and post-smoothing are adjoint and the
//! coarsest solve is exact, so the V-cycle is a symmetric positive-definite
//! operator and a valid preconditioner for conjugate gradients.
//!
//! Every parallel loop writes disjoint rows, sums in a fixed order, so the
//! result does not depend on the number of threads.

use super::cg::{Preconditioner, invert_spd};
use super::{CholeskySolver, SolveError};
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use rayon::prelude::*;

/// Rows per parallel task.
pub(super) const ROWS: usize = 1024;

/// A sparse matrix compressed by row with 32-bit column indices.
#[derive(Clone, Debug, PartialEq)]
pub struct CsrMatrix {
    pub(super) nrows: usize,
    pub(super) ncols: usize,
    pub(super) ptr: Vec<usize>,
    pub(super) idx: Vec<u32>,
    pub(super) val: Vec<f64>,
}

impl CsrMatrix {
    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.idx.len()
    }

    pub(super) fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.ptr[i]..self.ptr[i + 1];
        (&self.idx[r.clone()], &self.val[r])
    }

    /// The symmetric matrix K given compressed by column (both triangles
    /// stored); for a symmetric matrix its columns are its rows.
    pub fn from_symmetric(k: SparseColMatRef<'_, usize, f64>) -> Result<CsrMatrix, SolveError> {
        if k.nrows() != k.ncols() || k.nrows() >= u32::MAX as usize {
            return Err(SolveError::Dimension(format!(
                "multigrid needs a square matrix, got {}×{}",
                k.nrows(),
                k.ncols()
            )));
        }
        let n = k.ncols();
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0);
        let mut idx = Vec::with_capacity(k.compute_nnz());
        let mut val = Vec::with_capacity(k.compute_nnz());
        for j in 0..n {
            idx.extend(k.row_idx_of_col_raw(j).iter().map(|&i| i as u32));
            val.extend_from_slice(k.val_of_col(j));
            ptr.push(idx.len());
        }
        Ok(CsrMatrix {
            nrows: n,
            ncols: n,
            ptr,
            idx,
            val,
        })
    }

    /// The regularised normal matrix AᵀA + εI of a least-squares problem,
    /// from A and Aᵀ compressed by column: row u is Σ_r A_ru (row r of A),
    /// gathered in parallel (Gustavson's algorithm), columns sorted.
    pub fn normal(
        a: SparseColMatRef<'_, usize, f64>,
        at: SparseColMatRef<'_, usize, f64>,
        epsilon: f64,
    ) -> Result<CsrMatrix, SolveError> {
        let (m, n) = (a.nrows(), a.ncols());
        if at.nrows() != n || at.ncols() != m || n >= u32::MAX as usize {
            return Err(SolveError::Dimension(format!(
                "normal matrix: A {m}×{n}, Aᵀ {}×{}",
                at.nrows(),
                at.ncols()
            )));
        }
        let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..n.div_ceil(ROWS))
            .into_par_iter()
            .map(|c| {
                let rows = c * ROWS..((c + 1) * ROWS).min(n);
                let mut row = RowAccumulator::<1>::new(n);
                let (mut len, mut idx, mut val) = (Vec::new(), Vec::new(), Vec::new());
                for u in rows {
                    for (&r, &w) in a.row_idx_of_col_raw(u).iter().zip(a.val_of_col(u)) {
                        for (&v, &x) in at.row_idx_of_col_raw(r).iter().zip(at.val_of_col(r)) {
                            row.add(v as u32, w * x);
                        }
                    }
                    row.add(u as u32, epsilon);
                    len.push(row.flush(&mut idx, &mut val));
                }
                (len, idx, val)
            })
            .collect();
        Ok(CsrMatrix::concat(n, n, chunks))
    }

    fn concat(nrows: usize, ncols: usize, chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)>) -> Self {
        let total: usize = chunks.iter().map(|c| c.1.len()).sum();
        let mut ptr = Vec::with_capacity(nrows + 1);
        ptr.push(0);
        let mut idx = Vec::with_capacity(total);
        let mut val = Vec::with_capacity(total);
        for (len, i, v) in chunks {
            for l in len {
                ptr.push(ptr[ptr.len() - 1] + l);
            }
            idx.extend_from_slice(&i);
            val.extend_from_slice(&v);
        }
        CsrMatrix {
            nrows,
            ncols,
            ptr,
            idx,
            val,
        }
    }

    /// y = M x, in parallel.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(ROWS).enumerate().for_each(|(c, y)| {
            for (k, y) in y.iter_mut().enumerate() {
                let (idx, val) = self.row(c * ROWS + k);
                *y = idx.iter().zip(val).map(|(&j, v)| v * x[j as usize]).sum();
            }
        });
    }

    /// y = b − M x, in parallel.
    pub(super) fn residual(&self, b: &[f64], x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(ROWS).enumerate().for_each(|(c, y)| {
            for (k, y) in y.iter_mut().enumerate() {
                let i = c * ROWS + k;
                let (idx, val) = self.row(i);
                *y = b[i]
                    - idx
                        .iter()
                        .zip(val)
                        .map(|(&j, v)| v * x[j as usize])
                        .sum::<f64>();
            }
        });
    }

    /// Mᵀ (entries of each row in increasing column order).
    pub fn transpose(&self) -> CsrMatrix {
        let mut count = vec![0usize; self.ncols + 1];
        for &j in &self.idx {
            count[j as usize + 1] += 1;
        }
        for j in 0..self.ncols {
            count[j + 1] += count[j];
        }
        let ptr = count.clone();
        let mut next = count;
        let mut idx = vec![0u32; self.nnz()];
        let mut val = vec![0.0; self.nnz()];
        for i in 0..self.nrows {
            let (ri, rv) = self.row(i);
            for (&j, &v) in ri.iter().zip(rv) {
                let p = next[j as usize];
                idx[p] = i as u32;
                val[p] = v;
                next[j as usize] += 1;
            }
        }
        CsrMatrix {
            nrows: self.ncols,
            ncols: self.nrows,
            ptr,
            idx,
            val,
        }
    }

    /// M B, in parallel by rows (Gustavson), columns sorted.
    pub fn matmul(&self, b: &CsrMatrix) -> CsrMatrix {
        let n = b.ncols;
        let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..self.nrows.div_ceil(ROWS))
            .into_par_iter()
            .map(|c| {
                let rows = c * ROWS..((c + 1) * ROWS).min(self.nrows);
                let mut row = RowAccumulator::<1>::new(n);
                let (mut len, mut idx, mut val) = (Vec::new(), Vec::new(), Vec::new());
                for i in rows {
                    let (ri, rv) = self.row(i);
                    for (&k, &w) in ri.iter().zip(rv) {
                        let (bi, bv) = b.row(k as usize);
                        for (&j, &x) in bi.iter().zip(bv) {
                            row.add(j, w * x);
                        }
                    }
                    len.push(row.flush(&mut idx, &mut val));
                }
                (len, idx, val)
            })
            .collect();
        CsrMatrix::concat(self.nrows, n, chunks)
    }

    fn to_faer(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        // a symmetric matrix: its rows are its columns
        let t: Vec<Triplet<usize, usize, f64>> = (0..self.nrows)
            .flat_map(|i| {
                let (ri, rv) = self.row(i);
                ri.iter()
                    .zip(rv)
                    .map(move |(&j, &v)| Triplet::new(j as usize, i, v))
            })
            .collect();
        SparseColMat::try_new_from_triplets(self.ncols, self.nrows, &t)
            .map_err(|e| SolveError::Backend(format!("{e:?}")))
    }
}

/// Options of [`Amg::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmgOptions {
    /// Unknowns per node of the finest level (3 for vertex coordinates).
    pub block: usize,
    /// Damped block-Jacobi steps before and after each coarse correction.
    pub smoothing_steps: usize,
    /// Factor the level directly once it has at most this many unknowns.
    pub max_coarse: usize,
    /// Largest number of levels.
    pub max_levels: usize,
    /// Strength threshold θ: nodes i, j are aggregated together only when
    /// ‖K_ij‖ ≥ θ √(‖K_ii‖ ‖K_jj‖) (Frobenius norms of the blocks). The
    /// default 0.08 drops the weak couplings of a normal matrix AᵀA whose
    /// rows span mesh 1-rings (most 2-ring entries), so the finest
    /// aggregates are about 1-rings rather than 2-rings.
    pub strength: f64,
}

impl Default for AmgOptions {
    fn default() -> Self {
        AmgOptions {
            block: 3,
            smoothing_steps: 1,
            max_coarse: 2000,
            max_levels: 10,
            strength: 0.08,
        }
    }
}

/// One level of the hierarchy: its matrix, block-diagonal inverses, the
/// smoother's damping, and the prolongator to it from the next coarser
/// level (with its transpose).
struct Level {
    k: CsrMatrix,
    block: usize,
    inverses: Vec<f64>,
    omega: f64,
    p: CsrMatrix,
    pt: CsrMatrix,
}

/// A smoothed-aggregation multigrid V-cycle, a symmetric positive-definite
/// preconditioner of K (module documentation).
pub struct Amg {
    levels: Vec<Level>,
    coarse: CholeskySolver,
    smoothing_steps: usize,
}

/// Sizes of the levels of an [`Amg`] hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct AmgStats {
    /// Unknowns per level, finest first (the last is factored).
    pub unknowns: Vec<usize>,
    /// Stored entries per level.
    pub nonzeros: Vec<usize>,
}

impl Amg {
    /// Builds the hierarchy for the symmetric positive-definite `k` (both
    /// triangles stored) with near-null-space vectors `nullspace` (each of
    /// length `k.nrows()`; e.g. the rigid translations and the linear
    /// fields of a displacement).
    ///
    /// Errors: inconsistent sizes, a coarse matrix that is not positive
    /// definite (K was not).
    pub fn new(
        k: CsrMatrix,
        nullspace: &[Vec<f64>],
        options: &AmgOptions,
    ) -> Result<Amg, SolveError> {
        let block = options.block.max(1);
        let n = k.nrows();
        if k.ncols() != n
            || !n.is_multiple_of(block)
            || nullspace.is_empty()
            || nullspace.iter().any(|b| b.len() != n)
        {
            return Err(SolveError::Dimension(format!(
                "multigrid: matrix {}×{}, block {block}, {} near-null-space vectors of lengths {:?}",
                k.nrows(),
                k.ncols(),
                nullspace.len(),
                nullspace.iter().map(Vec::len).collect::<Vec<_>>()
            )));
        }
        let nk = nullspace.len();
        // near-null space by rows: b[i * nk + j] = nullspace[j][i]
        let mut b: Vec<f64> = (0..n * nk).map(|t| nullspace[t % nk][t / nk]).collect();
        let mut levels = Vec::new();
        let mut k = k;
        let mut block = block;
        loop {
            let size = k.nrows();
            let (inverses, omega) = block_jacobi(&k, block);
            if size <= options.max_coarse || levels.len() + 1 >= options.max_levels {
                break;
            }
            let aggregates = aggregate(&k, block, options.strength);
            let count = aggregates
                .iter()
                .map(|&a| a as usize + 1)
                .max()
                .unwrap_or(0);
            if count * nk >= size {
                // no reduction: stop coarsening
                break;
            }
            let (t, coarse_b) = tentative(&aggregates, count, block, &b, nk);
            // P = (I − ω D⁻¹ K) T
            let kt = k.matmul(&t);
            let p = smooth_prolongator(&t, &kt, &inverses, block, omega);
            let pt = p.transpose();
            let kc = symmetrise_with_unit_idle(pt.matmul(&k.matmul(&p)));
            levels.push(Level {
                k,
                block,
                inverses,
                omega,
                p,
                pt,
            });
            k = kc;
            block = nk;
            b = coarse_b;
        }
        let coarse = CholeskySolver::new(k.to_faer()?.as_ref())?;
        Ok(Amg {
            levels,
            coarse,
            smoothing_steps: options.smoothing_steps.max(1),
        })
    }

    /// Sizes of the hierarchy.
    pub fn stats(&self) -> AmgStats {
        let mut unknowns: Vec<usize> = self.levels.iter().map(|l| l.k.nrows()).collect();
        let mut nonzeros: Vec<usize> = self.levels.iter().map(|l| l.k.nnz()).collect();
        unknowns.push(self.coarse.dim());
        nonzeros.push(0);
        AmgStats { unknowns, nonzeros }
    }

    fn cycle(&self, level: usize, b: &[f64], x: &mut [f64]) {
        if level == self.levels.len() {
            x.copy_from_slice(b);
            if self.coarse.solve_in_place(x).is_err() {
                x.iter_mut().for_each(|v| *v = 0.0);
            }
            return;
        }
        let l = &self.levels[level];
        let n = b.len();
        let mut r = vec![0.0; n];
        // pre-smoothing from x = 0
        block_apply(&l.inverses, l.block, l.omega, b, x, false);
        for _ in 1..self.smoothing_steps {
            l.k.residual(b, x, &mut r);
            block_apply(&l.inverses, l.block, l.omega, &r, x, true);
        }
        l.k.residual(b, x, &mut r);
        let mut rc = vec![0.0; l.pt.nrows()];
        l.pt.mul_vec(&r, &mut rc);
        let mut xc = vec![0.0; rc.len()];
        self.cycle(level + 1, &rc, &mut xc);
        l.p.mul_vec(&xc, &mut r);
        x.par_iter_mut()
            .zip(r.par_iter())
            .for_each(|(x, c)| *x += c);
        for _ in 0..self.smoothing_steps {
            l.k.residual(b, x, &mut r);
            block_apply(&l.inverses, l.block, l.omega, &r, x, true);
        }
    }
}

impl Preconditioner for Amg {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.cycle(0, r, z);
    }
}

/// Inverses of the diagonal blocks of K (row-major per block) and the
/// smoother's damping 4 / (3 ρ̄), ρ̄ the largest absolute row sum of D⁻¹K.
pub(super) fn block_jacobi(k: &CsrMatrix, block: usize) -> (Vec<f64>, f64) {
    let nb = k.nrows() / block;
    let bb = block * block;
    let mut inverses = vec![0.0; nb * bb];
    let bounds: Vec<f64> = inverses
        .par_chunks_mut(bb)
        .enumerate()
        .map(|(g, inv)| {
            let mut m = vec![0.0; bb];
            for i in 0..block {
                let (ri, rv) = k.row(g * block + i);
                for (&j, &v) in ri.iter().zip(rv) {
                    let j = j as usize;
                    if j >= g * block && j < (g + 1) * block {
                        m[i * block + j - g * block] = v;
                    }
                }
            }
            // symmetrise the block (rounding)
            for i in 0..block {
                for j in 0..i {
                    let s = 0.5 * (m[i * block + j] + m[j * block + i]);
                    m[i * block + j] = s;
                    m[j * block + i] = s;
                }
            }
            invert_spd(&mut m, block, inv);
            // row sums of |D_g⁻¹ K_g,:|: accumulate per column
            let mut bound = 0.0f64;
            let rows: Vec<(&[u32], &[f64])> = (0..block).map(|i| k.row(g * block + i)).collect();
            for i in 0..block {
                let mut s = 0.0;
                // (D⁻¹ K)_{i, j} = Σ_l inv[i, l] K[l, j]; the rows of the
                // block share most columns but not necessarily all
                let mut merged: Vec<(u32, f64)> = Vec::new();
                for (l, (ri, rv)) in rows.iter().enumerate() {
                    let w = inv[i * block + l];
                    merged.extend(ri.iter().zip(rv.iter()).map(|(&j, &v)| (j, w * v)));
                }
                merged.sort_unstable_by_key(|e| e.0);
                let mut p = 0;
                while p < merged.len() {
                    let j = merged[p].0;
                    let mut t = 0.0;
                    while p < merged.len() && merged[p].0 == j {
                        t += merged[p].1;
                        p += 1;
                    }
                    s += t.abs();
                }
                bound = bound.max(s);
            }
            bound
        })
        .collect();
    let gershgorin = bounds.iter().copied().fold(0.0f64, f64::max);
    let power = power_estimate(k, &inverses, block);
    let rho = gershgorin.min(1.1 * power);
    let omega = if rho > 0.0 && rho.is_finite() {
        4.0 / (3.0 * rho)
    } else {
        1.0
    };
    (inverses, omega)
}

/// Estimate of ρ(D⁻¹K) by power iterations from a fixed start vector.
fn power_estimate(k: &CsrMatrix, inverses: &[f64], block: usize) -> f64 {
    let n = k.nrows();
    let mut x: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * ((i as f64 * 0.618_033_988_75).fract() - 0.5))
        .collect();
    let mut y = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut rho = 0.0;
    for _ in 0..POWER_ITERATIONS {
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0) || !norm.is_finite() {
            return f64::INFINITY;
        }
        x.iter_mut().for_each(|v| *v /= norm);
        k.mul_vec(&x, &mut y);
        block_apply(inverses, block, 1.0, &y, &mut z, false);
        rho = z.iter().map(|v| v * v).sum::<f64>().sqrt();
        std::mem::swap(&mut x, &mut z);
    }
    rho
}

/// Power iterations of the spectral radius estimate.
pub(super) const POWER_ITERATIONS: usize = 15;

/// x = ω D⁻¹ r (or x += ω D⁻¹ r when `add`), in parallel.
pub(super) fn block_apply(
    inverses: &[f64],
    block: usize,
    omega: f64,
    r: &[f64],
    x: &mut [f64],
    add: bool,
) {
    let b = block;
    x.par_chunks_mut(b * 256)
        .zip(r.par_chunks(b * 256))
        .zip(inverses.par_chunks(b * b * 256))
        .for_each(|((x, r), inv)| {
            for ((x, r), inv) in x.chunks_mut(b).zip(r.chunks(b)).zip(inv.chunks(b * b)) {
                for i in 0..b {
                    let z: f64 = (0..b).map(|j| inv[i * b + j] * r[j]).sum();
                    if add {
                        x[i] += omega * z;
                    } else {
                        x[i] = omega * z;
                    }
                }
            }
        });
}

/// Aggregate index of every node (module documentation, step 1).
fn aggregate(k: &CsrMatrix, block: usize, theta: f64) -> Vec<u32> {
    let nb = k.nrows() / block;
    // node graph: neighbours of node g are the nodes of the columns of its rows
    // squared Frobenius norms of the blocks K_gh of each block row
    let norms: Vec<Vec<(u32, f64)>> = (0..nb)
        .into_par_iter()
        .map(|g| {
            let mut v: Vec<(u32, f64)> = (0..block)
                .flat_map(|i| {
                    let (ri, rv) = k.row(g * block + i);
                    ri.iter().zip(rv).map(|(&j, &x)| (j / block as u32, x * x))
                })
                .collect();
            v.sort_by_key(|e| e.0);
            let mut out: Vec<(u32, f64)> = Vec::with_capacity(v.len() / block);
            for (h, x) in v {
                match out.last_mut() {
                    Some(last) if last.0 == h => last.1 += x,
                    _ => out.push((h, x)),
                }
            }
            out
        })
        .collect();
    aggregate_nodes(&norms, theta)
}

/// Aggregates of the nodes of a graph given, per node, its stored blocks
/// as (node, squared Frobenius norm), sorted by node (module
/// documentation, step 1): couplings weaker than `theta` are dropped.
pub(super) fn aggregate_nodes(norms: &[Vec<(u32, f64)>], theta: f64) -> Vec<u32> {
    const FREE: u32 = u32::MAX;
    let nb = norms.len();
    let diagonal: Vec<f64> = norms
        .iter()
        .enumerate()
        .map(|(g, row)| {
            row.iter()
                .find(|e| e.0 as usize == g)
                .map(|e| e.1.sqrt())
                .unwrap_or(0.0)
        })
        .collect();
    let neighbours: Vec<Vec<u32>> = norms
        .par_iter()
        .enumerate()
        .map(|(g, row)| {
            row.iter()
                .filter(|e| {
                    e.0 as usize != g
                        && e.1.sqrt() >= theta * (diagonal[g] * diagonal[e.0 as usize]).sqrt()
                })
                .map(|e| e.0)
                .collect()
        })
        .collect();
    let mut agg = vec![FREE; nb];
    let mut count = 0u32;
    // phase 1: roots whose neighbourhood is free
    for g in 0..nb {
        if agg[g] == FREE && neighbours[g].iter().all(|&h| agg[h as usize] == FREE) {
            agg[g] = count;
            for &h in &neighbours[g] {
                agg[h as usize] = count;
            }
            count += 1;
        }
    }
    // phase 2: join a neighbouring aggregate of phase 1
    let first = agg.clone();
    for g in 0..nb {
        if agg[g] == FREE
            && let Some(&h) = neighbours[g].iter().find(|&&h| first[h as usize] != FREE)
        {
            agg[g] = first[h as usize];
        }
    }
    // phase 3: the rest, with their free neighbours
    for g in 0..nb {
        if agg[g] == FREE {
            agg[g] = count;
            for &h in &neighbours[g] {
                if agg[h as usize] == FREE {
                    agg[h as usize] = count;
                }
            }
            count += 1;
        }
    }
    agg
}

/// Tentative prolongator (n × count·nk) and coarse near-null space (by
/// rows), by a QR factorisation of the near-null space on each aggregate.
pub(super) fn tentative(
    aggregates: &[u32],
    count: usize,
    block: usize,
    b: &[f64],
    nk: usize,
) -> (CsrMatrix, Vec<f64>) {
    let nb = aggregates.len();
    let n = nb * block;
    // nodes of each aggregate
    let mut start = vec![0usize; count + 1];
    for &a in aggregates {
        start[a as usize + 1] += 1;
    }
    for a in 0..count {
        start[a + 1] += start[a];
    }
    let mut members = vec![0u32; nb];
    let mut next = start.clone();
    for (g, &a) in aggregates.iter().enumerate() {
        members[next[a as usize]] = g as u32;
        next[a as usize] += 1;
    }
    // per aggregate: Q (rows of its unknowns × nk) and R (nk × nk)
    let factors: Vec<(Vec<f64>, Vec<f64>)> = (0..count)
        .into_par_iter()
        .map(|a| {
            let nodes = &members[start[a]..start[a + 1]];
            let rows = nodes.len() * block;
            // column-major copy of B on the aggregate
            let mut q = vec![0.0; rows * nk];
            for (t, &g) in nodes.iter().enumerate() {
                for i in 0..block {
                    let u = g as usize * block + i;
                    for j in 0..nk {
                        q[j * rows + t * block + i] = b[u * nk + j];
                    }
                }
            }
            let mut r = vec![0.0; nk * nk];
            for j in 0..nk {
                let norm0 = q[j * rows..(j + 1) * rows]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt();
                for _ in 0..2 {
                    for l in 0..j {
                        let d: f64 = (0..rows).map(|s| q[l * rows + s] * q[j * rows + s]).sum();
                        r[l * nk + j] += d;
                        for s in 0..rows {
                            q[j * rows + s] -= d * q[l * rows + s];
                        }
                    }
                }
                let norm = q[j * rows..(j + 1) * rows]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt();
                if norm > 1e-10 * norm0 && norm > 0.0 && norm.is_finite() {
                    r[j * nk + j] = norm;
                    q[j * rows..(j + 1) * rows]
                        .iter_mut()
                        .for_each(|v| *v /= norm);
                } else {
                    // dependent on the previous columns here: idle coarse unknown
                    q[j * rows..(j + 1) * rows]
                        .iter_mut()
                        .for_each(|v| *v = 0.0);
                }
            }
            (q, r)
        })
        .collect();
    // T by rows: node g in aggregate a at position t
    let mut position = vec![0usize; nb];
    for a in 0..count {
        for (t, &g) in members[start[a]..start[a + 1]].iter().enumerate() {
            position[g as usize] = t;
        }
    }
    let mut ptr = Vec::with_capacity(n + 1);
    ptr.push(0);
    let mut idx = Vec::with_capacity(n * nk);
    let mut val = Vec::with_capacity(n * nk);
    for g in 0..nb {
        let a = aggregates[g] as usize;
        let (q, _) = &factors[a];
        let rows = (start[a + 1] - start[a]) * block;
        for i in 0..block {
            let s = position[g] * block + i;
            for j in 0..nk {
                let v = q[j * rows + s];
                if v != 0.0 {
                    idx.push((a * nk + j) as u32);
                    val.push(v);
                }
            }
            ptr.push(idx.len());
        }
    }
    let t = CsrMatrix {
        nrows: n,
        ncols: count * nk,
        ptr,
        idx,
        val,
    };
    let mut coarse_b = vec![0.0; count * nk * nk];
    for (a, (_, r)) in factors.iter().enumerate() {
        coarse_b[a * nk * nk..(a + 1) * nk * nk].copy_from_slice(r);
    }
    (t, coarse_b)
}

/// P = T − ω D⁻¹ (K T), row block by row block.
pub(super) fn smooth_prolongator(
    t: &CsrMatrix,
    kt: &CsrMatrix,
    inverses: &[f64],
    block: usize,
    omega: f64,
) -> CsrMatrix {
    let nb = t.nrows / block;
    let ncols = t.ncols;
    let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..nb.div_ceil(ROWS))
        .into_par_iter()
        .map(|c| {
            let nodes = c * ROWS..((c + 1) * ROWS).min(nb);
            let mut row = RowAccumulator::<1>::new(ncols);
            let (mut len, mut idx, mut val) = (Vec::new(), Vec::new(), Vec::new());
            for g in nodes {
                let inv = &inverses[g * block * block..(g + 1) * block * block];
                for i in 0..block {
                    let (ti, tv) = t.row(g * block + i);
                    for (&j, &v) in ti.iter().zip(tv) {
                        row.add(j, v);
                    }
                    for l in 0..block {
                        let w = -omega * inv[i * block + l];
                        let (ki, kv) = kt.row(g * block + l);
                        for (&j, &v) in ki.iter().zip(kv) {
                            row.add(j, w * v);
                        }
                    }
                    len.push(row.flush(&mut idx, &mut val));
                }
            }
            (len, idx, val)
        })
        .collect();
    CsrMatrix::concat(t.nrows, ncols, chunks)
}

/// (K + Kᵀ) / 2 for a structurally symmetric K, with a unit diagonal on
/// idle unknowns (empty rows, from zero columns of the prolongator).
fn symmetrise_with_unit_idle(k: CsrMatrix) -> CsrMatrix {
    let kt = k.transpose();
    let n = k.nrows;
    let rows: Vec<(Vec<u32>, Vec<f64>)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (ai, av) = k.row(i);
            let (bi, bv) = kt.row(i);
            let (mut p, mut q) = (0, 0);
            let (mut idx, mut val) = (Vec::new(), Vec::new());
            while p < ai.len() || q < bi.len() {
                let (j, v) = if q >= bi.len() || (p < ai.len() && ai[p] < bi[q]) {
                    p += 1;
                    (ai[p - 1], 0.5 * av[p - 1])
                } else if p >= ai.len() || bi[q] < ai[p] {
                    q += 1;
                    (bi[q - 1], 0.5 * bv[q - 1])
                } else {
                    p += 1;
                    q += 1;
                    (ai[p - 1], 0.5 * (av[p - 1] + bv[q - 1]))
                };
                idx.push(j);
                val.push(v);
            }
            let diagonal = idx
                .iter()
                .position(|&j| j as usize == i)
                .map(|p| val[p])
                .unwrap_or(0.0);
            if !(diagonal > 0.0) {
                // idle unknown (its row is zero): a unit diagonal
                if idx.iter().zip(&val).all(|(_, v)| *v == 0.0) {
                    idx = vec![i as u32];
                    val = vec![1.0];
                }
            }
            (idx, val)
        })
        .collect();
    let mut ptr = Vec::with_capacity(n + 1);
    ptr.push(0);
    let mut idx = Vec::new();
    let mut val = Vec::new();
    for (i, v) in rows {
        idx.extend_from_slice(&i);
        val.extend_from_slice(&v);
        ptr.push(idx.len());
    }
    CsrMatrix {
        nrows: n,
        ncols: n,
        ptr,
        idx,
        val,
    }
}

/// A dense scatter accumulator for one sparse row at a time (Gustavson's
/// sparse product) with values in ℝ^W: `add_vector` sums into column j,
/// `flush_with` hands the touched columns in increasing order with their
/// sums to a closure and resets, returning how many there were.
pub(super) struct RowAccumulator<const W: usize = 1> {
    acc: Vec<[f64; W]>,
    mark: Vec<bool>,
    touched: Vec<u32>,
}

impl<const W: usize> RowAccumulator<W> {
    pub(super) fn new(ncols: usize) -> Self {
        RowAccumulator {
            acc: vec![[0.0; W]; ncols],
            mark: vec![false; ncols],
            touched: Vec::new(),
        }
    }

    #[inline]
    pub(super) fn add_vector(&mut self, j: u32, v: [f64; W]) {
        let k = j as usize;
        if !self.mark[k] {
            self.mark[k] = true;
            self.touched.push(j);
        }
        for (a, v) in self.acc[k].iter_mut().zip(v) {
            *a += v;
        }
    }

    pub(super) fn flush_with(&mut self, mut f: impl FnMut(u32, [f64; W])) -> usize {
        self.touched.sort_unstable();
        for &j in &self.touched {
            f(j, self.acc[j as usize]);
            self.acc[j as usize] = [0.0; W];
            self.mark[j as usize] = false;
        }
        let n = self.touched.len();
        self.touched.clear();
        n
    }
}

impl RowAccumulator<1> {
    #[inline]
    fn add(&mut self, j: u32, v: f64) {
        self.add_vector(j, [v]);
    }

    fn flush(&mut self, idx: &mut Vec<u32>, val: &mut Vec<f64>) -> usize {
        self.flush_with(|j, v| {
            idx.push(j);
            val.push(v[0]);
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{
        CgOptions, least_squares, normal_equations_cg, normal_equations_pcg, sparse_from_triplets,
    };

    /// Rows of a grid operator: `laplace` = uniform Laplacian rows (K =
    /// bi-Laplacian), else edge differences (K = graph Laplacian); plus a
    /// weak diagonal `delta` row per unknown on the first column of nodes.
    fn grid(side: usize, laplace: bool, delta: f64) -> SparseColMat<usize, f64> {
        let id = |i: usize, j: usize| i * side + j;
        let mut t = Vec::new();
        let mut row = 0;
        for i in 0..side {
            for j in 0..side {
                if laplace {
                    let mut nb = Vec::new();
                    for (di, dj) in [(0i64, 1i64), (1, 0), (0, -1), (-1, 0)] {
                        let (a, b) = (i as i64 + di, j as i64 + dj);
                        if a >= 0 && b >= 0 && (a as usize) < side && (b as usize) < side {
                            nb.push(id(a as usize, b as usize));
                        }
                    }
                    t.push((row, id(i, j), 1.0));
                    for &n in &nb {
                        t.push((row, n, -1.0 / nb.len() as f64));
                    }
                    row += 1;
                } else {
                    if j + 1 < side {
                        t.push((row, id(i, j), 1.0));
                        t.push((row, id(i, j + 1), -1.0));
                        row += 1;
                    }
                    if i + 1 < side {
                        t.push((row, id(i, j), 1.0));
                        t.push((row, id(i + 1, j), -1.0));
                        row += 1;
                    }
                }
                if j == 0 || (laplace && i == 0) {
                    t.push((row, id(i, j), delta));
                    row += 1;
                }
            }
        }
        sparse_from_triplets(row, side * side, &t).unwrap()
    }

    /// Iterations and solution of PCG with AMG and with Jacobi on the
    /// least-squares problem of `grid(side, laplace, delta)`.
    fn solve_grid(side: usize, laplace: bool, nullspace: usize) -> (usize, usize, f64) {
        let a = grid(side, laplace, 0.1);
        let at = a.as_ref().transpose().to_col_major().unwrap();
        let n = side * side;
        let k = CsrMatrix::normal(a.as_ref(), at.as_ref(), 0.0).unwrap();
        let mut ns = vec![vec![1.0; n]];
        if nullspace == 3 {
            ns.push((0..n).map(|u| (u % side) as f64).collect());
            ns.push((0..n).map(|u| (u / side) as f64).collect());
        }
        let b: Vec<f64> = (0..a.nrows())
            .map(|r| ((r * 7) as f64 * 0.37).sin())
            .collect();
        let rhs: Vec<f64> = (0..n)
            .map(|u| {
                a.row_idx_of_col_raw(u)
                    .iter()
                    .zip(a.val_of_col(u))
                    .map(|(&r, v)| v * b[r])
                    .sum()
            })
            .collect();
        let options = CgOptions {
            tolerance: 1e-12,
            max_iterations: 100_000,
            block: 1,
            hopeless_after: 0,
        };
        let mut x = vec![0.0; n];
        let jacobi =
            normal_equations_cg(a.as_ref(), at.as_ref(), 0.0, &rhs, &mut x, &options).unwrap();
        let amg = Amg::new(
            k,
            &ns,
            &AmgOptions {
                block: 1,
                // a multilevel hierarchy at every size (not one direct solve)
                max_coarse: 64,
                ..AmgOptions::default()
            },
        )
        .unwrap();
        assert!(amg.stats().unknowns.len() >= 3, "{:?}", amg.stats());
        let mut y = vec![0.0; n];
        let r = normal_equations_pcg(a.as_ref(), at.as_ref(), 0.0, &rhs, &mut y, &options, &amg)
            .unwrap();
        assert!(r.converged && jacobi.converged, "{r:?} {jacobi:?}");
        let exact = least_squares(a.as_ref(), std::slice::from_ref(&b)).unwrap();
        let scale = exact[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = exact[0]
            .iter()
            .zip(&y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max);
        (r.iterations, jacobi.iterations, diff / scale)
    }

    /// Graph Laplacian of a square grid plus a weak shift on one side (a
    /// 2-D Poisson problem): PCG with the multigrid V-cycle reaches the
    /// Cholesky solution to 1e-9 in a handful of iterations that barely
    /// grow from a 32² to a 128² grid, while Jacobi PCG needs many times
    /// more and grows with the grid (a wrong prolongator or a
    /// non-symmetric cycle would break both).
    #[test]
    fn multigrid_iterations_do_not_grow_with_the_grid() {
        let (small, small_jacobi, e1) = solve_grid(32, false, 1);
        let (large, large_jacobi, e2) = solve_grid(128, false, 1);
        println!(
            "32²: AMG {small}, Jacobi {small_jacobi}; 128²: AMG {large}, Jacobi {large_jacobi}"
        );
        assert!(e1 <= 1e-9 && e2 <= 1e-9, "{e1:e} {e2:e}");
        assert!(5 * small < small_jacobi && 10 * large < large_jacobi);
        assert!(large <= small + small / 2 + 2, "{small} → {large}");
        assert!(large_jacobi > 2 * small_jacobi);
    }

    /// The same for the bi-Laplacian (uniform-Laplacian rows, the F_smo
    /// part of vertex flow) with the linear functions in the near-null
    /// space (Vaněk, Mandel & Brezina's condition for fourth-order
    /// problems): far fewer iterations than Jacobi, same solution.
    #[test]
    fn multigrid_preconditions_the_bi_laplacian() {
        let (amg, jacobi, e) = solve_grid(48, true, 3);
        println!("bi-Laplacian 48²: AMG {amg}, Jacobi {jacobi}");
        assert!(e <= 1e-9, "{e:e}");
        assert!(10 * amg < jacobi, "{amg} vs {jacobi}");
    }

    /// Sizes are checked.
    #[test]
    fn multigrid_refuses_inconsistent_sizes() {
        let a = grid(8, false, 0.1);
        let at = a.as_ref().transpose().to_col_major().unwrap();
        let k = CsrMatrix::normal(a.as_ref(), at.as_ref(), 0.0).unwrap();
        assert!(
            Amg::new(
                k.clone(),
                &[vec![1.0; 63]],
                &AmgOptions {
                    block: 1,
                    ..AmgOptions::default()
                }
            )
            .is_err()
        );
        assert!(
            Amg::new(
                k.clone(),
                &[],
                &AmgOptions {
                    block: 1,
                    ..AmgOptions::default()
                }
            )
            .is_err()
        );
        assert!(
            Amg::new(k, &[vec![1.0; 64]], &AmgOptions::default()).is_err(),
            "64 is not a multiple of 3"
        );
    }
}
