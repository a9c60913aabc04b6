//! Preconditioned conjugate gradients on the regularised normal equations
//! (AᵀA + εI) x = c of a sparse least-squares problem, matrix-free: the
//! product AᵀA v is computed as Aᵀ(A v) from A and Aᵀ (both compressed by
//! column, i.e. A by columns and by rows), so AᵀA — whose pattern is the
//! 2-ring of a mesh when the rows of A span 1-rings — is never formed. The
//! preconditioner is block Jacobi: the inverses of the diagonal blocks of
//! AᵀA + εI (e.g. 3 × 3 per vertex when the unknowns are its coordinates).
//! Both run on [`pcg`], preconditioned conjugate gradients for any symmetric
//! positive definite operator and preconditioner given as closures (e.g.
//! the line-block preconditioner of structure-line fairing).
//!
//! Every parallel loop writes disjoint outputs and every reduction sums
//! fixed-size chunks in a fixed order, so the result does not depend on the
//! number of threads or on scheduling.

use super::SolveError;
use faer::sparse::SparseColMatRef;
use rayon::prelude::*;

/// Restarts from the current iterate after the recurrence residual has
/// drifted below the tolerance while the true residual has not.
const MAX_RESTARTS: usize = 20;

/// Length of the chunks of the deterministic parallel reductions.
const CHUNK: usize = 4096;

/// Outcome of [`normal_equations_cg`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CgReport {
    /// Iterations performed.
    pub iterations: usize,
    /// Final relative residual ‖c − (AᵀA + εI) x‖ / ‖c‖.
    pub relative_residual: f64,
    /// Relative residual of the starting point.
    pub initial_relative_residual: f64,
    /// Whether the tolerance was reached.
    pub converged: bool,
}

/// Stopping rule of [`normal_equations_cg`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct CgOptions {
    /// Stop when ‖c − (AᵀA + εI) x‖ ≤ `tolerance` ‖c‖.
    pub tolerance: f64,
    /// Give up after this many iterations.
    pub max_iterations: usize,
    /// Size of the diagonal blocks of the block-Jacobi preconditioner
    /// (1 = Jacobi); the number of unknowns must be a multiple of it.
    pub block: usize,
    /// When not 0: every this many iterations from three times this many on,
    /// give up (not converged) when the mean reduction of the residual per
    /// iteration over the last this many predicts the tolerance only after
    /// twice `max_iterations` (the rate of a few iterations fluctuates) —
    /// for a cheap first attempt that a stronger preconditioner takes over.
    pub hopeless_after: usize,
}

impl Default for CgOptions {
    /// Relative residual 1e-10, at most 1000 iterations, Jacobi (blocks of
    /// 1), never given up early.
    fn default() -> Self {
        CgOptions {
            tolerance: 1e-10,
            max_iterations: 1000,
            block: 1,
            hopeless_after: 0,
        }
    }
}

crate::control::setters!(CgOptions {
    tolerance: f64,
    max_iterations: usize,
    block: usize,
    hopeless_after: usize,
});

/// A symmetric positive-definite approximation z = M⁻¹ r of the inverse of
/// the system matrix, applied once per conjugate-gradient iteration.
pub trait Preconditioner: Sync {
    /// z = M⁻¹ r (`z` is overwritten).
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// Solves (AᵀA + εI) x = `rhs` by block-Jacobi preconditioned conjugate
/// gradients, starting from the values in `x` (a warm start; its length is
/// the number of columns of A). `a` is A (m × n) and `at` is Aᵀ (n × m),
/// both compressed by column with sorted row indices.
///
/// Errors: inconsistent sizes, non-finite iterates. Not reaching the
/// tolerance is not an error: the report says so and `x` holds the last
/// iterate.
pub fn normal_equations_cg(
    a: SparseColMatRef<'_, usize, f64>,
    at: SparseColMatRef<'_, usize, f64>,
    epsilon: f64,
    rhs: &[f64],
    x: &mut [f64],
    options: &CgOptions,
) -> Result<CgReport, SolveError> {
    let (m, n) = (a.nrows(), a.ncols());
    let block = options.block.max(1);
    if at.nrows() != n || at.ncols() != m || rhs.len() != n || x.len() != n || n % block != 0 {
        return Err(SolveError::Dimension(format!(
            "CG on the normal equations: A {m}×{n}, Aᵀ {}×{}, right-hand side {}, start {}, block {block}",
            at.nrows(),
            at.ncols(),
            rhs.len(),
            x.len()
        )));
    }
    let preconditioner = BlockJacobi::new(a, epsilon, block);
    normal_equations_pcg(a, at, epsilon, rhs, x, options, &preconditioner)
}

/// Solves (AᵀA + εI) x = `rhs` by conjugate gradients preconditioned by
/// `preconditioner` (e.g. [`super::VectorAmg`]), otherwise as
/// [`normal_equations_cg`] (`options.block` is not used).
pub fn normal_equations_pcg(
    a: SparseColMatRef<'_, usize, f64>,
    at: SparseColMatRef<'_, usize, f64>,
    epsilon: f64,
    rhs: &[f64],
    x: &mut [f64],
    options: &CgOptions,
    preconditioner: &dyn Preconditioner,
) -> Result<CgReport, SolveError> {
    let (m, n) = (a.nrows(), a.ncols());
    if at.nrows() != n || at.ncols() != m || rhs.len() != n || x.len() != n {
        return Err(SolveError::Dimension(format!(
            "CG on the normal equations: A {m}×{n}, Aᵀ {}×{}, right-hand side {}, start {}",
            at.nrows(),
            at.ncols(),
            rhs.len(),
            x.len()
        )));
    }
    let mut scratch = vec![0.0; m];
    conjugate_gradients(
        |v: &[f64], out: &mut [f64]| normal_product(a, at, epsilon, v, out, &mut scratch),
        |r: &[f64], z: &mut [f64]| preconditioner.apply(r, z),
        rhs,
        x,
        options.tolerance,
        options.max_iterations,
        options.hopeless_after,
    )
}

/// Preconditioned conjugate gradients for S x = `rhs` with a symmetric
/// positive definite S given as the product `apply(v, out)`: out = S v, and a
/// symmetric positive definite preconditioner `precondition(r, z)`:
/// z ≈ S⁻¹ r, starting from the values in `x` (a warm start). Stops when the
/// true residual satisfies ‖rhs − S x‖ ≤ `tolerance` ‖rhs‖ (the recurrence
/// residual drifts from it, so CG is restarted from the current iterate when
/// the two disagree, at most 20 times); a zero right-hand side gives x = 0.
/// A non-positive curvature pᵀSp or rᵀz (an operator or preconditioner that
/// is not positive definite in floating point) also ends a cycle and
/// restarts from the true residual. Not reaching the tolerance within
/// `max_iterations` is reported, not an error; non-finite iterates are an
/// error. Every vector operation is a deterministic parallel loop, so the
/// result does not depend on the number of threads when `apply` and
/// `precondition` do not.
pub fn pcg(
    apply: impl FnMut(&[f64], &mut [f64]),
    precondition: impl FnMut(&[f64], &mut [f64]),
    rhs: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<CgReport, SolveError> {
    conjugate_gradients(apply, precondition, rhs, x, tolerance, max_iterations, 0)
}

/// [`pcg`] with the tolerance, iteration limit and early give-up rule of
/// `options` (`options.block` is not used).
pub fn pcg_with(
    apply: impl FnMut(&[f64], &mut [f64]),
    precondition: impl FnMut(&[f64], &mut [f64]),
    rhs: &[f64],
    x: &mut [f64],
    options: &CgOptions,
) -> Result<CgReport, SolveError> {
    conjugate_gradients(
        apply,
        precondition,
        rhs,
        x,
        options.tolerance,
        options.max_iterations,
        options.hopeless_after,
    )
}

fn conjugate_gradients(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&[f64], &mut [f64]),
    rhs: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    hopeless_after: usize,
) -> Result<CgReport, SolveError> {
    let n = rhs.len();
    if x.len() != n {
        return Err(SolveError::Dimension(format!(
            "CG: right-hand side {n}, start {}",
            x.len()
        )));
    }
    let norm_c = dot(rhs, rhs).sqrt();
    if !(norm_c > 0.0) {
        // c = 0: the solution is 0
        x.iter_mut().for_each(|v| *v = 0.0);
        return Ok(CgReport {
            iterations: 0,
            relative_residual: 0.0,
            initial_relative_residual: 0.0,
            converged: true,
        });
    }
    let target = tolerance * norm_c;
    let (mut r, mut z, mut p, mut q) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut iterations = 0;
    let mut restarts = 0;
    let mut initial_residual = None;
    let mut hopeless = false;
    let true_residual = loop {
        // true residual r = c − S x; the recurrence below drifts from it, so
        // convergence is confirmed on it and CG restarted from the current
        // iterate when the two disagree
        apply(x, &mut q);
        r.par_iter_mut()
            .zip(rhs.par_iter().zip(q.par_iter()))
            .for_each(|(r, (c, q))| *r = c - q);
        let true_residual = dot(&r, &r).sqrt();
        initial_residual.get_or_insert(true_residual);
        if !true_residual.is_finite() || !x.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFinite);
        }
        if true_residual <= target
            || iterations >= max_iterations
            || restarts >= MAX_RESTARTS
            || hopeless
        {
            break true_residual;
        }
        restarts += 1;
        precondition(&r, &mut z);
        p.copy_from_slice(&z);
        let mut rz = dot(&r, &z);
        let mut norm_r = true_residual;
        let mut checkpoint = (iterations, true_residual);
        while norm_r > target && iterations < max_iterations {
            apply(&p, &mut q);
            let pq = dot(&p, &q);
            if !(pq > 0.0) || !(rz > 0.0) {
                break;
            }
            let alpha = rz / pq;
            let norm_r_squared = step_and_norm(x, &mut r, &p, &q, alpha);
            precondition(&r, &mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            p.par_iter_mut()
                .zip(z.par_iter())
                .for_each(|(p, z)| *p = z + beta * *p);
            norm_r = norm_r_squared.sqrt();
            iterations += 1;
            if hopeless_after > 0 && iterations - checkpoint.0 == hopeless_after {
                // mean rate over the last stretch, extrapolated
                let rate = (norm_r / checkpoint.1).powf(1.0 / hopeless_after as f64);
                let needed = (target / norm_r).ln() / rate.ln();
                // the first two stretches are not judged: they hold the
                // quick decay of the stiffest components, or a stagnation,
                // on any mesh
                let judged = iterations >= 3 * hopeless_after;
                if judged
                    && (!(rate < 1.0)
                        || !(iterations as f64 + needed <= 2.0 * max_iterations as f64))
                {
                    hopeless = true;
                    break;
                }
                checkpoint = (iterations, norm_r);
            }
        }
    };
    Ok(CgReport {
        iterations,
        relative_residual: true_residual / norm_c,
        initial_relative_residual: initial_residual.unwrap_or(true_residual) / norm_c,
        converged: true_residual <= target,
    })
}

/// out = (AᵀA + εI) v, through t = A v (rows of A are the columns of Aᵀ).
fn normal_product(
    a: SparseColMatRef<'_, usize, f64>,
    at: SparseColMatRef<'_, usize, f64>,
    epsilon: f64,
    v: &[f64],
    out: &mut [f64],
    t: &mut [f64],
) {
    t.par_chunks_mut(CHUNK).enumerate().for_each(|(c, t)| {
        for (k, t) in t.iter_mut().enumerate() {
            let row = c * CHUNK + k;
            *t = at
                .row_idx_of_col_raw(row)
                .iter()
                .zip(at.val_of_col(row))
                .map(|(&u, a)| a * v[u])
                .sum();
        }
    });
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (k, o) in out.iter_mut().enumerate() {
            let u = c * CHUNK + k;
            let s: f64 = a
                .row_idx_of_col_raw(u)
                .iter()
                .zip(a.val_of_col(u))
                .map(|(&r, a)| a * t[r])
                .sum();
            *o = s + epsilon * v[u];
        }
    });
}

/// Deterministic parallel dot product.
/// x += α p and r −= α q in one pass, returning ‖r‖² of the new r (summed
/// like [`dot`]: the same bits as `dot(r, r)` afterwards).
fn step_and_norm(x: &mut [f64], r: &mut [f64], p: &[f64], q: &[f64], alpha: f64) -> f64 {
    x.par_chunks_mut(CHUNK)
        .zip(r.par_chunks_mut(CHUNK))
        .zip(p.par_chunks(CHUNK).zip(q.par_chunks(CHUNK)))
        .map(|((x, r), (p, q))| {
            let mut sum = 0.0;
            for (((x, r), p), q) in x.iter_mut().zip(r.iter_mut()).zip(p).zip(q) {
                *x += alpha * p;
                *r -= alpha * q;
                sum += *r * *r;
            }
            sum
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

pub(super) fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.par_chunks(CHUNK)
        .zip(y.par_chunks(CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(x, y)| x * y).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// The diagonal blocks of AᵀA + εI (`block` × `block`, row-major, one per
/// group of `block` consecutive unknowns), computed from the columns of A
/// (sorted row indices) in parallel.
pub fn normal_diagonal_blocks(
    a: SparseColMatRef<'_, usize, f64>,
    epsilon: f64,
    block: usize,
) -> Vec<f64> {
    let block = block.max(1);
    let nb = a.ncols() / block;
    let bb = block * block;
    let mut blocks = vec![0.0; nb * bb];
    blocks.par_chunks_mut(bb).enumerate().for_each(|(g, m)| {
        for i in 0..block {
            for j in 0..=i {
                let s = sparse_dot(a, g * block + i, g * block + j);
                m[i * block + j] = s;
                m[j * block + i] = s;
            }
            m[i * block + i] += epsilon;
        }
    });
    blocks
}

/// Block-Jacobi preconditioner: the inverses of symmetric diagonal blocks
/// (e.g. those of AᵀA + εI from [`normal_diagonal_blocks`]), row-major per
/// block.
#[derive(Clone, Debug)]
pub struct BlockJacobi {
    block: usize,
    inverses: Vec<f64>,
}

impl BlockJacobi {
    /// Block Jacobi of AᵀA + εI.
    pub fn new(a: SparseColMatRef<'_, usize, f64>, epsilon: f64, block: usize) -> BlockJacobi {
        BlockJacobi::from_blocks(normal_diagonal_blocks(a, epsilon, block), block)
    }

    /// Block Jacobi of the given `block` × `block` symmetric diagonal blocks
    /// (row-major, concatenated); a block that is not positive definite is
    /// replaced by the inverse of its positive diagonal entries.
    pub fn from_blocks(mut blocks: Vec<f64>, block: usize) -> BlockJacobi {
        let block = block.max(1);
        let bb = block * block;
        let mut inverses = vec![0.0; blocks.len()];
        inverses
            .par_chunks_mut(bb)
            .zip(blocks.par_chunks_mut(bb))
            .for_each(|(inv, m)| invert_spd(m, block, inv));
        BlockJacobi { block, inverses }
    }
}

impl Preconditioner for BlockJacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let b = self.block;
        z.par_chunks_mut(b * CHUNK)
            .zip(r.par_chunks(b * CHUNK))
            .zip(self.inverses.par_chunks(b * b * CHUNK))
            .for_each(|((z, r), inv)| {
                for ((z, r), inv) in z.chunks_mut(b).zip(r.chunks(b)).zip(inv.chunks(b * b)) {
                    for i in 0..b {
                        z[i] = (0..b).map(|j| inv[i * b + j] * r[j]).sum();
                    }
                }
            });
    }
}

/// Dot product of columns `i` and `j` of A (sorted row indices).
fn sparse_dot(a: SparseColMatRef<'_, usize, f64>, i: usize, j: usize) -> f64 {
    let (ri, vi) = (a.row_idx_of_col_raw(i), a.val_of_col(i));
    let (rj, vj) = (a.row_idx_of_col_raw(j), a.val_of_col(j));
    let (mut p, mut q, mut s) = (0, 0, 0.0);
    while p < ri.len() && q < rj.len() {
        match ri[p].cmp(&rj[q]) {
            std::cmp::Ordering::Less => p += 1,
            std::cmp::Ordering::Greater => q += 1,
            std::cmp::Ordering::Equal => {
                s += vi[p] * vj[q];
                p += 1;
                q += 1;
            }
        }
    }
    s
}

/// Inverse of the symmetric `b × b` matrix `m` by its Cholesky factor,
/// written to `inv`; a block that is not positive definite falls back to
/// the inverse of its diagonal (zero where the diagonal is not positive).
pub(super) fn invert_spd(m: &mut [f64], b: usize, inv: &mut [f64]) {
    // the diagonal of the input (for the fallback); blocks of up to 3 × 3
    // (the common case, once per vertex) stay on the stack
    let mut small = [0.0; 3];
    let mut large = Vec::new();
    let diagonal: &mut [f64] = if b <= 3 {
        &mut small[..b]
    } else {
        large.resize(b, 0.0);
        &mut large
    };
    for (i, d) in diagonal.iter_mut().enumerate() {
        *d = m[i * b + i];
    }
    let mut y_small = [0.0; 3];
    let mut y_large = Vec::new();
    // in-place Cholesky, lower triangle
    let mut ok = true;
    for j in 0..b {
        let d = m[j * b + j] - (0..j).map(|k| m[j * b + k] * m[j * b + k]).sum::<f64>();
        if !(d > 0.0) || !d.is_finite() {
            ok = false;
            break;
        }
        let d = d.sqrt();
        m[j * b + j] = d;
        for i in j + 1..b {
            let s = m[i * b + j] - (0..j).map(|k| m[i * b + k] * m[j * b + k]).sum::<f64>();
            m[i * b + j] = s / d;
        }
    }
    if ok {
        // columns of the inverse: solve L Lᵀ x = e_c
        for c in 0..b {
            let y: &mut [f64] = if b <= 3 {
                &mut y_small[..b]
            } else {
                y_large.clear();
                y_large.resize(b, 0.0);
                &mut y_large
            };
            for i in 0..b {
                let e = if i == c { 1.0 } else { 0.0 };
                y[i] = (e - (0..i).map(|k| m[i * b + k] * y[k]).sum::<f64>()) / m[i * b + i];
            }
            for i in (0..b).rev() {
                y[i] = (y[i] - (i + 1..b).map(|k| m[k * b + i] * y[k]).sum::<f64>()) / m[i * b + i];
            }
            for i in 0..b {
                inv[i * b + c] = y[i];
            }
        }
        if inv.iter().all(|v| v.is_finite()) {
            return;
        }
    }
    inv.iter_mut().for_each(|v| *v = 0.0);
    for i in 0..b {
        let d = diagonal[i];
        inv[i * b + i] = if d > 0.0 && d.is_finite() {
            1.0 / d
        } else {
            0.0
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{least_squares, sparse_from_triplets};

    /// An overdetermined system whose normal matrix is a 2D bi-Laplacian
    /// plus a weak diagonal (the hard case of vertex flow: smoothness rows
    /// and weak data rows): CG from a zero start reaches the Cholesky
    /// least-squares solution, with 3 × 3 blocks, deterministically.
    #[test]
    fn cg_reaches_the_cholesky_least_squares_solution() {
        let side = 12;
        let n = side * side * 3;
        let id = |i: usize, j: usize, c: usize| 3 * (i * side + j) + c;
        let mut t = Vec::new();
        let mut b = Vec::new();
        let mut row = 0;
        for i in 0..side {
            for j in 0..side {
                for c in 0..3 {
                    // Laplacian row, coupling the components a little
                    t.push((row, id(i, j, c), 4.0));
                    t.push((row, id(i, j, (c + 1) % 3), 0.3));
                    for (di, dj) in [(0i64, 1i64), (1, 0), (0, -1), (-1, 0)] {
                        let (a, bb) = (i as i64 + di, j as i64 + dj);
                        if a >= 0 && bb >= 0 && (a as usize) < side && (bb as usize) < side {
                            t.push((row, id(a as usize, bb as usize, c), -1.0));
                        }
                    }
                    b.push(((i * 7 + j * 3 + c) as f64 * 0.37).sin());
                    row += 1;
                    // weak data row
                    t.push((row, id(i, j, c), 0.05));
                    b.push(0.05 * (i as f64 - j as f64 + c as f64));
                    row += 1;
                }
            }
        }
        let a = sparse_from_triplets(row, n, &t).unwrap();
        let at = a.as_ref().transpose().to_col_major().unwrap();
        let exact = least_squares(a.as_ref(), std::slice::from_ref(&b)).unwrap();
        let rhs: Vec<f64> = (0..n)
            .map(|u| {
                let rows = a.row_idx_of_col_raw(u);
                rows.iter()
                    .zip(a.val_of_col(u))
                    .map(|(&r, v)| v * b[r])
                    .sum()
            })
            .collect();
        let options = CgOptions {
            tolerance: 1e-12,
            max_iterations: 2000,
            block: 3,
            hopeless_after: 0,
        };
        let mut x = vec![0.0; n];
        let r = normal_equations_cg(a.as_ref(), at.as_ref(), 0.0, &rhs, &mut x, &options).unwrap();
        assert!(r.converged && r.relative_residual <= 1e-12, "{r:?}");
        assert!(r.iterations > 10);
        let scale = exact[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (u, v) in exact[0].iter().zip(&x) {
            assert!((u - v).abs() <= 1e-9 * scale, "{u} vs {v}");
        }
        let mut again = vec![0.0; n];
        normal_equations_cg(a.as_ref(), at.as_ref(), 0.0, &rhs, &mut again, &options).unwrap();
        assert_eq!(again, x, "deterministic");
        // a wrong size is refused, a zero right-hand side gives zero
        let mut short = vec![0.0; n - 1];
        assert!(
            normal_equations_cg(a.as_ref(), at.as_ref(), 0.0, &rhs, &mut short, &options).is_err()
        );
        let mut z = vec![1.0; n];
        normal_equations_cg(
            a.as_ref(),
            at.as_ref(),
            0.0,
            &vec![0.0; n],
            &mut z,
            &options,
        )
        .unwrap();
        assert!(z.iter().all(|v| *v == 0.0));
    }
    /// `pcg` with a general operator and preconditioner: on the shifted 1D
    /// Laplacian S = tridiag(−1, 2 + σ, −1) the exact inverse as
    /// preconditioner (a tridiagonal solve) converges in one iteration, and
    /// the identity preconditioner reaches the same solution in more.
    #[test]
    fn pcg_with_an_exact_preconditioner_converges_in_one_step() {
        let (n, sigma) = (200, 0.01);
        let apply = |v: &[f64], out: &mut [f64]| {
            for i in 0..n {
                let l = if i > 0 { v[i - 1] } else { 0.0 };
                let r = if i + 1 < n { v[i + 1] } else { 0.0 };
                out[i] = (2.0 + sigma) * v[i] - l - r;
            }
        };
        // Thomas algorithm for S z = r
        let exact = |r: &[f64], z: &mut [f64]| {
            let mut c = vec![0.0; n];
            let mut d = vec![0.0; n];
            for i in 0..n {
                let m = 2.0 + sigma + if i > 0 { c[i - 1] } else { 0.0 };
                c[i] = -1.0 / m;
                d[i] = (r[i] + if i > 0 { d[i - 1] } else { 0.0 }) / m;
            }
            for i in (0..n).rev() {
                z[i] = d[i] - if i + 1 < n { c[i] * z[i + 1] } else { 0.0 };
            }
        };
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin() + 0.3).collect();
        let mut x = vec![0.0; n];
        let r = pcg(apply, exact, &rhs, &mut x, 1e-12, 100).unwrap();
        assert!(r.converged && r.iterations == 1, "{r:?}");
        let mut y = vec![0.0; n];
        let identity = |r: &[f64], z: &mut [f64]| z.copy_from_slice(r);
        let r = pcg(apply, identity, &rhs, &mut y, 1e-12, 1000).unwrap();
        assert!(r.converged && r.iterations > 10, "{r:?}");
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() <= 1e-8 * scale, "{a} vs {b}");
        }
        assert!(pcg(apply, identity, &rhs, &mut vec![0.0; n - 1], 1e-12, 10).is_err());
    }

    /// The give-up rule stops a hopeless run early and leaves a run alone
    /// that converges in time: on a 1D Laplacian of 2000 unknowns
    /// (condition number ~10⁶) plain CG cannot reach 10⁻¹⁰ in 40
    /// iterations and gives up at the 12th, 16th or 20th; on the same
    /// operator with a strong diagonal (condition number ~3) it converges,
    /// with the same iterations and result as without the rule.
    #[test]
    fn hopeless_runs_give_up_early() {
        let n = 2000;
        let run = |sigma: f64, hopeless_after: usize| {
            let apply = |v: &[f64], out: &mut [f64]| {
                for i in 0..n {
                    let l = if i > 0 { v[i - 1] } else { 0.0 };
                    let r = if i + 1 < n { v[i + 1] } else { 0.0 };
                    out[i] = (2.0 + sigma) * v[i] - l - r;
                }
            };
            let rhs: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin() + 1.0).collect();
            let mut x = vec![0.0; n];
            let options = CgOptions {
                tolerance: 1e-10,
                max_iterations: 40,
                block: 1,
                hopeless_after,
            };
            let report = pcg_with(apply, |r, z| z.copy_from_slice(r), &rhs, &mut x, &options);
            (report.unwrap(), x)
        };
        let (hard, _) = run(1e-6, 4);
        assert!(!hard.converged);
        assert!((12..=20).contains(&hard.iterations), "{hard:?}");
        let (easy, x) = run(2.0, 4);
        let (plain, y) = run(2.0, 0);
        assert!(easy.converged, "{easy:?}");
        assert_eq!(easy.iterations, plain.iterations);
        assert_eq!(x, y);
    }
}
