//! Building blocks of smoothed-aggregation algebraic multigrid (Vaněk,
//! Mandel & Brezina 1996, "Algebraic multigrid by smoothed aggregation for
//! second and fourth order elliptic problems", Computing 56), used by
//! [`super::VectorAmg`]: a row-compressed sparse matrix with 32-bit indices
//! and its products, and the three setup steps of a level for a matrix K
//! with b unknowns per node:
//!
//! 1. **Aggregation** of the nodes over the graph of K (node i and j are
//!    neighbours when the block K_ij is stored): greedy, in node order —
//!    a node all of whose neighbours are free becomes the root of an
//!    aggregate holding it and its neighbours; left-over nodes join the
//!    aggregate of a neighbour; the rest form aggregates with their free
//!    neighbours. Weak couplings (‖K_ij‖ < θ √(‖K_ii‖ ‖K_jj‖)) are
//!    dropped. Deterministic.
//! 2. **Tentative prolongator** T: per aggregate, the near-null-space
//!    vectors B restricted to its unknowns, orthonormalised (modified
//!    Gram–Schmidt, twice); B_a = Q_a R_a gives the columns Q_a of T and the
//!    coarse near-null space R_a. A vector that is (numerically) dependent
//!    on the previous ones on an aggregate gives a zero column.
//! 3. **Prolongator smoothing** P = (I − ω D⁻¹K) T with D the block
//!    diagonal of K and ω = 4 / (3 ρ̄), ρ̄ an estimate of ρ(D⁻¹K): the
//!    smaller of the largest absolute row sum of D⁻¹K (a Gershgorin bound)
//!    and 1.1 times the estimate of 15 power iterations.
//!
//! Every parallel loop writes disjoint rows, sums in a fixed order, so the
//! result does not depend on the number of threads.

use super::cg::{dot, invert_spd};
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
}

/// Inverses of the diagonal blocks of K (row-major per block), the
/// smoother's damping 4 / (3 ρ̄) ([`jacobi_damping`]) and the power
/// estimate of ρ(D⁻¹K) it used.
pub(super) fn block_jacobi(k: &CsrMatrix, block: usize) -> (Vec<f64>, f64, f64) {
    if block == 1 {
        return point_jacobi(k);
    }
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
    (inverses, jacobi_damping(gershgorin, power), power)
}

/// [`block_jacobi`] with 1 × 1 blocks: 1 / K_ii (0 where not positive)
/// and the damping from the row sums Σ_j |K_ij| / K_ii.
fn point_jacobi(k: &CsrMatrix) -> (Vec<f64>, f64, f64) {
    let (inverses, bounds): (Vec<f64>, Vec<f64>) = (0..k.nrows())
        .into_par_iter()
        .map(|i| {
            let (ri, rv) = k.row(i);
            let d: f64 = ri
                .iter()
                .zip(rv)
                .filter(|(j, _)| **j as usize == i)
                .map(|(_, v)| v)
                .sum();
            let inverse = if d > 0.0 && d.is_finite() {
                1.0 / d
            } else {
                0.0
            };
            let sum: f64 = rv.iter().map(|v| v.abs()).sum();
            (inverse, inverse * sum)
        })
        .unzip();
    let gershgorin = bounds.iter().copied().fold(0.0f64, f64::max);
    let power = power_estimate(k, &inverses, 1);
    (inverses, jacobi_damping(gershgorin, power), power)
}

/// Estimate of ρ(D⁻¹K) by power iterations from a fixed start vector.
fn power_estimate(k: &CsrMatrix, inverses: &[f64], block: usize) -> f64 {
    let mut y = vec![0.0; k.nrows()];
    power_iterations(k.nrows(), |x, z| {
        k.mul_vec(x, &mut y);
        block_apply(inverses, block, 1.0, &y, z, false);
    })
}

/// Estimate of the spectral radius of the operator `apply(x, z)`: z = M x
/// on vectors of length `n`, by [`POWER_ITERATIONS`] power iterations from
/// a fixed start vector; infinite when an iterate vanishes or overflows.
pub(super) fn power_iterations(n: usize, mut apply: impl FnMut(&[f64], &mut [f64])) -> f64 {
    let mut x: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * ((i as f64 * 0.618_033_988_75).fract() - 0.5))
        .collect();
    let mut z = vec![0.0; n];
    let mut rho = 0.0;
    let mut norm = dot(&x, &x).sqrt();
    for _ in 0..POWER_ITERATIONS {
        if !(norm > 0.0) || !norm.is_finite() {
            return f64::INFINITY;
        }
        x.par_iter_mut().for_each(|v| *v /= norm);
        apply(&x, &mut z);
        // ‖z‖ is the estimate and the next normalisation
        norm = dot(&z, &z).sqrt();
        rho = norm;
        std::mem::swap(&mut x, &mut z);
    }
    rho
}

/// The damping 4 / (3 ρ̄) of a Jacobi smoother, ρ̄ the smaller of the
/// Gershgorin bound and 1.1 times the power estimate of ρ(D⁻¹K) (1 when
/// neither is usable).
pub(super) fn jacobi_damping(gershgorin: f64, power: f64) -> f64 {
    let rho = gershgorin.min(1.1 * power);
    if rho > 0.0 && rho.is_finite() {
        4.0 / (3.0 * rho)
    } else {
        1.0
    }
}

/// Power iterations of the spectral radius estimate.
const POWER_ITERATIONS: usize = 15;

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

    /// Adds `v` to the first component of column j only.
    #[inline]
    pub(super) fn add_first(&mut self, j: u32, v: f64) {
        let k = j as usize;
        if !self.mark[k] {
            self.mark[k] = true;
            self.touched.push(j);
        }
        self.acc[k][0] += v;
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
