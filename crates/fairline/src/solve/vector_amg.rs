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
//! ([`super::Amg`]) a stored coarse entry is one index, one scalar and six
//! block values instead of nine indices and nine values, the prolongator
//! has a ninth of the entries, the finest level stores S on its diagonal
//! only, and the setup multiplies scalar matrices. Aggregation, the
//! tentative prolongator and its smoothing are those of [`super::Amg`]
//! (shared functions); the smoother is damped block Jacobi with the 3 × 3
//! diagonal blocks of K, ω = 4 / (3 ρ̄), so the V-cycle is symmetric
//! positive definite (see [`super::Amg`]).

use super::amg::{
    POWER_ITERATIONS, ROWS, RowAccumulator, aggregate_nodes, block_jacobi, smooth_prolongator,
    tentative,
};
use super::cg::{Preconditioner, invert_spd};
use super::{CholeskySolver, CsrMatrix, SolveError};
use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;

/// A symmetric 3 × 3 block as [xx, yy, zz, xy, xz, yz].
pub type SymmetricBlock = [f64; 6];

#[inline]
fn symmetric_mul(s: &SymmetricBlock, x: &[f64]) -> [f64; 3] {
    [
        s[0] * x[0] + s[3] * x[1] + s[4] * x[2],
        s[3] * x[0] + s[1] * x[1] + s[5] * x[2],
        s[4] * x[0] + s[5] * x[1] + s[2] * x[2],
    ]
}

/// The blocks S of a [`VectorOperator`]: on the diagonal only (one per
/// node) or one per stored entry of A.
#[derive(Clone, Debug, PartialEq)]
enum Blocks {
    Diagonal(Vec<SymmetricBlock>),
    Full(Vec<SymmetricBlock>),
}

/// A symmetric operator K = A ⊗ I₃ + S on three unknowns per node, stored
/// by rows (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct VectorOperator {
    ptr: Vec<usize>,
    idx: Vec<u32>,
    a: Vec<f64>,
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
        let diagonal_only = rows
            .iter()
            .enumerate()
            .all(|(i, row)| row.iter().all(|e| e.0 as usize == i || e.2 == [0.0; 6]));
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
                if !diagonal_only || j as usize == i {
                    s.push(b);
                }
            }
            ptr.push(idx.len());
        }
        Ok(VectorOperator {
            ptr,
            idx,
            a,
            s: if diagonal_only {
                Blocks::Diagonal(s)
            } else {
                Blocks::Full(s)
            },
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

    /// Entry `e` of row `i` as (A_IJ, S_IJ).
    #[inline]
    fn entry(&self, i: usize, e: usize) -> (f64, SymmetricBlock) {
        let s = match &self.s {
            Blocks::Full(s) => s[e],
            Blocks::Diagonal(s) if self.idx[e] as usize == i => s[i],
            Blocks::Diagonal(_) => [0.0; 6],
        };
        (self.a[e], s)
    }

    /// Row i of K applied to x: Σ_J (A_IJ x_J + S_IJ x_J).
    #[inline]
    fn row_times(&self, i: usize, x: &[f64]) -> [f64; 3] {
        let mut y = [0.0; 3];
        let range = self.ptr[i]..self.ptr[i + 1];
        match &self.s {
            Blocks::Full(s) => {
                for e in range {
                    let j = 3 * self.idx[e] as usize;
                    let xj = &x[j..j + 3];
                    let t = symmetric_mul(&s[e], xj);
                    for c in 0..3 {
                        y[c] += self.a[e] * xj[c] + t[c];
                    }
                }
            }
            Blocks::Diagonal(s) => {
                for e in range {
                    let j = 3 * self.idx[e] as usize;
                    for c in 0..3 {
                        y[c] += self.a[e] * x[j + c];
                    }
                }
                let t = symmetric_mul(&s[i], &x[3 * i..3 * i + 3]);
                for c in 0..3 {
                    y[c] += t[c];
                }
            }
        }
        y
    }

    /// y = K x, in parallel.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(3 * ROWS).enumerate().for_each(|(c, y)| {
            for (k, y) in y.chunks_mut(3).enumerate() {
                y.copy_from_slice(&self.row_times(c * ROWS + k, x));
            }
        });
    }

    /// y = b − K x, in parallel.
    fn residual(&self, b: &[f64], x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(3 * ROWS).enumerate().for_each(|(c, y)| {
            for (k, y) in y.chunks_mut(3).enumerate() {
                let i = c * ROWS + k;
                let t = self.row_times(i, x);
                for r in 0..3 {
                    y[r] = b[3 * i + r] - t[r];
                }
            }
        });
    }

    /// The diagonal block A_II I₃ + S_II of node i (row-major 3 × 3).
    fn diagonal_block(&self, i: usize) -> [f64; 9] {
        let mut m = [0.0; 9];
        for e in self.ptr[i]..self.ptr[i + 1] {
            if self.idx[e] as usize == i {
                let (a, s) = self.entry(i, e);
                m = [
                    a + s[0],
                    s[3],
                    s[4],
                    s[3],
                    a + s[1],
                    s[5],
                    s[4],
                    s[5],
                    a + s[2],
                ];
            }
        }
        m
    }

    /// The scalar matrix A.
    fn scalar(&self) -> CsrMatrix {
        let n = self.nodes();
        CsrMatrix {
            nrows: n,
            ncols: n,
            ptr: self.ptr.clone(),
            idx: self.idx.clone(),
            val: self.a.clone(),
        }
    }

    /// Per node, (J, ‖A_IJ I₃ + S_IJ‖²_F) over its stored entries.
    fn strength_norms(&self) -> Vec<Vec<(u32, f64)>> {
        (0..self.nodes())
            .into_par_iter()
            .map(|i| {
                (self.ptr[i]..self.ptr[i + 1])
                    .map(|e| {
                        let (a, s) = self.entry(i, e);
                        let diagonal = (a + s[0]).powi(2) + (a + s[1]).powi(2) + (a + s[2]).powi(2);
                        let off = 2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
                        (self.idx[e], diagonal + off)
                    })
                    .collect()
            })
            .collect()
    }

    /// The Galerkin operator (P ⊗ I₃)ᵀ K (P ⊗ I₃) for the scalar
    /// prolongator `p` (with its transpose `pt`), symmetrised; a node whose
    /// row vanishes (a zero column of `p`) gets a unit diagonal.
    fn galerkin(&self, p: &CsrMatrix, pt: &CsrMatrix) -> VectorOperator {
        let nc = p.ncols;
        type Row = Vec<(u32, f64, SymmetricBlock)>;
        let rows: Vec<Row> = (0..nc.div_ceil(ROWS))
            .into_par_iter()
            .flat_map_iter(|c| {
                let mut acc = RowAccumulator::<7>::new(nc);
                let mut out: Vec<Row> = Vec::new();
                for ci in c * ROWS..((c + 1) * ROWS).min(nc) {
                    let (ki, kv) = pt.row(ci);
                    for (&k, &pk) in ki.iter().zip(kv) {
                        let k = k as usize;
                        for e in self.ptr[k]..self.ptr[k + 1] {
                            let (a, s) = self.entry(k, e);
                            let (li, lv) = p.row(self.idx[e] as usize);
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
                        row.push((j, v[0], [v[1], v[2], v[3], v[4], v[5], v[6]]));
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
                    out.insert(at, (i as u32, if vanishes { 1.0 } else { 0.0 }, [0.0; 6]));
                }
                out
            })
            .collect();
        VectorOperator::from_rows(rows).expect("Galerkin rows are sorted and hold the diagonal")
    }

    /// The assembled 3n × 3n matrix (both triangles).
    fn to_faer(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        let mut t = Vec::with_capacity(9 * self.entries());
        for i in 0..self.nodes() {
            for e in self.ptr[i]..self.ptr[i + 1] {
                let j = self.idx[e] as usize;
                let (a, s) = self.entry(i, e);
                let m = [
                    [a + s[0], s[3], s[4]],
                    [s[3], a + s[1], s[5]],
                    [s[4], s[5], a + s[2]],
                ];
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

struct Level {
    k: VectorOperator,
    inverses: Vec<[f64; 9]>,
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
            let (a_inverse, a_omega) = block_jacobi(&a, 1);
            let p = smooth_prolongator(&t, &a.matmul(&t), &a_inverse, 1, a_omega);
            let pt = p.transpose();
            let kc = k.galerkin(&p, &pt);
            let (inverses, omega) = vector_jacobi(&k);
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
        Ok(VectorAmg {
            levels,
            coarse,
            smoothing_steps: options.smoothing_steps.max(1),
        })
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

    fn cycle(&self, level: usize, b: &[f64], x: &mut [f64]) {
        if level == self.levels.len() {
            x.copy_from_slice(b);
            if self.coarse.solve_in_place(x).is_err() {
                x.iter_mut().for_each(|v| *v = 0.0);
            }
            return;
        }
        let l = &self.levels[level];
        let mut r = vec![0.0; b.len()];
        // pre-smoothing from x = 0
        jacobi_step(&l.inverses, l.omega, b, x, false);
        for _ in 1..self.smoothing_steps {
            l.k.residual(b, x, &mut r);
            jacobi_step(&l.inverses, l.omega, &r, x, true);
        }
        l.k.residual(b, x, &mut r);
        let mut rc = vec![0.0; 3 * l.pt.nrows];
        mul_coordinates(&l.pt, &r, &mut rc);
        let mut xc = vec![0.0; rc.len()];
        self.cycle(level + 1, &rc, &mut xc);
        mul_coordinates(&l.p, &xc, &mut r);
        x.par_iter_mut()
            .zip(r.par_iter())
            .for_each(|(x, c)| *x += c);
        for _ in 0..self.smoothing_steps {
            l.k.residual(b, x, &mut r);
            jacobi_step(&l.inverses, l.omega, &r, x, true);
        }
    }
}

impl Preconditioner for VectorAmg {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.cycle(0, r, z);
    }
}

/// y = (M ⊗ I₃) x for a scalar matrix M on interleaved coordinates.
fn mul_coordinates(m: &CsrMatrix, x: &[f64], y: &mut [f64]) {
    y.par_chunks_mut(3 * ROWS).enumerate().for_each(|(c, y)| {
        for (k, y) in y.chunks_mut(3).enumerate() {
            let (idx, val) = m.row(c * ROWS + k);
            let mut s = [0.0; 3];
            for (&j, &v) in idx.iter().zip(val) {
                let j = 3 * j as usize;
                for r in 0..3 {
                    s[r] += v * x[j + r];
                }
            }
            y.copy_from_slice(&s);
        }
    });
}

/// x = ω D⁻¹ r (or x += ω D⁻¹ r when `add`), D the 3 × 3 diagonal blocks.
fn jacobi_step(inverses: &[[f64; 9]], omega: f64, r: &[f64], x: &mut [f64], add: bool) {
    x.par_chunks_mut(3 * ROWS)
        .zip(r.par_chunks(3 * ROWS))
        .zip(inverses.par_chunks(ROWS))
        .for_each(|((x, r), inv)| {
            for ((x, r), m) in x.chunks_mut(3).zip(r.chunks(3)).zip(inv) {
                for i in 0..3 {
                    let z = m[3 * i] * r[0] + m[3 * i + 1] * r[1] + m[3 * i + 2] * r[2];
                    if add {
                        x[i] += omega * z;
                    } else {
                        x[i] = omega * z;
                    }
                }
            }
        });
}

/// Inverses of the diagonal blocks of K and the smoother's damping
/// 4 / (3 ρ̄), ρ̄ the smaller of the largest absolute row sum of D⁻¹K and
/// 1.1 times a power-iteration estimate of ρ(D⁻¹K).
fn vector_jacobi(k: &VectorOperator) -> (Vec<[f64; 9]>, f64) {
    let n = k.nodes();
    let inverses: Vec<[f64; 9]> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut m = k.diagonal_block(i);
            let mut inv = [0.0; 9];
            invert_spd(&mut m, 3, &mut inv);
            inv
        })
        .collect();
    let gershgorin = (0..n)
        .into_par_iter()
        .map(|i| {
            let inv = &inverses[i];
            let mut sums = [0.0f64; 3];
            for e in k.ptr[i]..k.ptr[i + 1] {
                let (a, s) = k.entry(i, e);
                let m = [
                    [a + s[0], s[3], s[4]],
                    [s[3], a + s[1], s[5]],
                    [s[4], s[5], a + s[2]],
                ];
                for (r, sum) in sums.iter_mut().enumerate() {
                    for c in 0..3 {
                        let v: f64 = (0..3).map(|l| inv[3 * r + l] * m[l][c]).sum();
                        *sum += v.abs();
                    }
                }
            }
            sums.into_iter().fold(0.0f64, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    // power iterations on D⁻¹K from a fixed start vector
    let mut x: Vec<f64> = (0..3 * n)
        .map(|i| 1.0 + 0.5 * ((i as f64 * 0.618_033_988_75).fract() - 0.5))
        .collect();
    let (mut y, mut z) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    let mut power = 0.0;
    for _ in 0..POWER_ITERATIONS {
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0) || !norm.is_finite() {
            power = f64::INFINITY;
            break;
        }
        x.iter_mut().for_each(|v| *v /= norm);
        k.mul_vec(&x, &mut y);
        jacobi_step(&inverses, 1.0, &y, &mut z, false);
        power = z.iter().map(|v| v * v).sum::<f64>().sqrt();
        std::mem::swap(&mut x, &mut z);
    }
    let rho = gershgorin.min(1.1 * power);
    let omega = if rho > 0.0 && rho.is_finite() {
        4.0 / (3.0 * rho)
    } else {
        1.0
    };
    (inverses, omega)
}
