//! Sparse Cholesky (LLᵀ) with the symbolic analysis kept for refactoring
//! matrices of the same pattern, as PMP's and libigl's `min_quad_with_fixed`
//! do: assemble once, analyse once, refactor and solve many times.

use super::SolveError;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::matmul::sparse_sparse_matmul;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, Triplet};
use faer::{Mat, Par, Side};

/// Sparse Cholesky factorisation of a symmetric positive-definite matrix.
/// The symbolic factorisation (fill-reducing ordering, elimination tree) is
/// computed once in [`CholeskySolver::new`] and reused by
/// [`CholeskySolver::refactor`] when only the values change.
#[derive(Clone, Debug)]
pub struct CholeskySolver {
    symbolic: faer::sparse::linalg::solvers::SymbolicLlt<usize>,
    pattern: SymbolicSparseColMat<usize>,
    llt: faer::sparse::linalg::solvers::Llt<usize, f64>,
}

impl CholeskySolver {
    /// Analyses and factors `a` (the full symmetric matrix or its lower
    /// triangle; only the lower triangle is read).
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Result<Self, SolveError> {
        if a.nrows() != a.ncols() {
            return Err(SolveError::Dimension(format!(
                "Cholesky needs a square matrix, got {}×{}",
                a.nrows(),
                a.ncols()
            )));
        }
        let symbolic =
            faer::sparse::linalg::solvers::SymbolicLlt::try_new(a.symbolic(), Side::Lower)
                .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
        let llt = faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(
            symbolic.clone(),
            a,
            Side::Lower,
        )
        .map_err(llt_error)?;
        Ok(CholeskySolver {
            symbolic,
            pattern: a
                .symbolic()
                .to_owned()
                .map_err(|e| SolveError::Backend(format!("{e:?}")))?,
            llt,
        })
    }

    /// Refactors a matrix with the same sparsity pattern as the one given to
    /// [`CholeskySolver::new`], reusing the symbolic analysis.
    pub fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveError> {
        if a.symbolic().col_ptr() != self.pattern.col_ptr()
            || a.symbolic().row_idx() != self.pattern.row_idx()
        {
            return Err(SolveError::Dimension(
                "refactor needs the same sparsity pattern".into(),
            ));
        }
        self.llt = faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            a,
            Side::Lower,
        )
        .map_err(llt_error)?;
        Ok(())
    }

    /// Order of the matrix.
    pub fn dim(&self) -> usize {
        self.pattern.nrows()
    }

    /// Solves A x = b for one right-hand side, in place.
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<(), SolveError> {
        let n = self.dim();
        if b.len() != n {
            return Err(SolveError::Dimension(format!(
                "right-hand side has {} entries, matrix has order {n}",
                b.len()
            )));
        }
        let mut m = Mat::<f64>::from_fn(n, 1, |i, _| b[i]);
        self.llt.solve_in_place(m.as_mut());
        for (i, x) in b.iter_mut().enumerate() {
            *x = m[(i, 0)];
        }
        if b.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFinite)
        }
    }

    /// Solves A X = B for several right-hand sides (e.g. x, y, z
    /// coordinates), each a slice of length n, in place.
    pub fn solve_columns(&self, columns: &mut [Vec<f64>]) -> Result<(), SolveError> {
        let n = self.dim();
        if columns.iter().any(|c| c.len() != n) {
            return Err(SolveError::Dimension("right-hand side length".into()));
        }
        let mut m = Mat::<f64>::from_fn(n, columns.len(), |i, j| columns[j][i]);
        self.llt.solve_in_place(m.as_mut());
        for (j, c) in columns.iter_mut().enumerate() {
            for (i, x) in c.iter_mut().enumerate() {
                *x = m[(i, j)];
            }
        }
        if columns.iter().flatten().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFinite)
        }
    }
}

/// A failed numeric factorisation: not positive definite, or out of memory
/// (the factor of a large system may not fit) and other faer failures.
fn llt_error(e: faer::sparse::linalg::LltError) -> SolveError {
    match e {
        faer::sparse::linalg::LltError::Numeric(_) => SolveError::NotPositiveDefinite,
        faer::sparse::linalg::LltError::Generic(e) => SolveError::Backend(format!("{e:?}")),
    }
}

/// Assembles a sparse matrix from (row, column, value) triplets; duplicate
/// entries are summed.
pub fn sparse_from_triplets(
    nrows: usize,
    ncols: usize,
    triplets: &[(usize, usize, f64)],
) -> Result<SparseColMat<usize, f64>, SolveError> {
    if let Some(t) = triplets.iter().find(|t| t.0 >= nrows || t.1 >= ncols) {
        return Err(SolveError::Dimension(format!(
            "entry ({}, {}) outside a {nrows}×{ncols} matrix",
            t.0, t.1
        )));
    }
    let t: Vec<Triplet<usize, usize, f64>> = triplets
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    SparseColMat::try_new_from_triplets(nrows, ncols, &t)
        .map_err(|e| SolveError::Backend(format!("{e:?}")))
}

/// The normal matrix AᵀA of a sparse least-squares problem (symmetric,
/// positive semi-definite).
pub fn normal_matrix(
    a: SparseColMatRef<'_, usize, f64>,
) -> Result<SparseColMat<usize, f64>, SolveError> {
    let at = a
        .transpose()
        .to_col_major()
        .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
    sparse_sparse_matmul(at.as_ref(), a, 1.0, Par::rayon(0))
        .map_err(|e| SolveError::Backend(format!("{e:?}")))
}

/// Least-squares solution of A x ≈ b for each column of `rhs` (each of
/// length `a.nrows()`), by a sparse Cholesky factorisation of the normal
/// equations AᵀA x = Aᵀb. A must have full column rank.
pub fn least_squares(
    a: SparseColMatRef<'_, usize, f64>,
    rhs: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, SolveError> {
    if rhs.iter().any(|b| b.len() != a.nrows()) {
        return Err(SolveError::Dimension("right-hand side length".into()));
    }
    let ata = normal_matrix(a)?;
    let solver = CholeskySolver::new(ata.as_ref())?;
    let mut cols: Vec<Vec<f64>> = rhs
        .iter()
        .map(|b| {
            let mut atb = vec![0.0; a.ncols()];
            for j in 0..a.ncols() {
                let rows = a.row_idx_of_col_raw(j);
                let vals = a.val_of_col(j);
                atb[j] = rows.iter().zip(vals).map(|(&r, v)| v * b[r]).sum();
            }
            atb
        })
        .collect();
    solver.solve_columns(&mut cols)?;
    Ok(cols)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_and_refactors_with_the_same_pattern() {
        // 1D Poisson matrix plus identity
        let n = 50;
        let build = |shift: f64| {
            let mut t = Vec::new();
            for i in 0..n {
                t.push((i, i, 2.0 + shift));
                if i + 1 < n {
                    t.push((i, i + 1, -1.0));
                    t.push((i + 1, i, -1.0));
                }
            }
            sparse_from_triplets(n, n, &t).unwrap()
        };
        let a = build(1.0);
        let mut s = CholeskySolver::new(a.as_ref()).unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| {
                let mut v = 3.0 * x_true[i];
                if i > 0 {
                    v -= x_true[i - 1];
                }
                if i + 1 < n {
                    v -= x_true[i + 1];
                }
                v
            })
            .collect();
        let mut x = b.clone();
        s.solve_in_place(&mut x).unwrap();
        for i in 0..n {
            assert!((x[i] - x_true[i]).abs() < 1e-12);
        }
        s.refactor(build(2.0).as_ref()).unwrap();
        let mut y = b;
        s.solve_in_place(&mut y).unwrap();
        assert!((y[0] - x[0]).abs() > 1e-3, "refactored values are used");
        // a matrix that is not positive definite is refused
        let bad = sparse_from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, -1.0)]).unwrap();
        assert_eq!(
            CholeskySolver::new(bad.as_ref()).unwrap_err(),
            SolveError::NotPositiveDefinite
        );
    }

    #[test]
    fn least_squares_fits_a_line() {
        // fit y = 2 x + 1 through noisy-free samples: exact
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut t = Vec::new();
        for (i, x) in xs.iter().enumerate() {
            t.push((i, 0, *x));
            t.push((i, 1, 1.0));
        }
        let a = sparse_from_triplets(5, 2, &t).unwrap();
        let b: Vec<f64> = xs.iter().map(|x| 2.0 * x + 1.0).collect();
        let sol = least_squares(a.as_ref(), &[b]).unwrap();
        assert!((sol[0][0] - 2.0).abs() < 1e-12 && (sol[0][1] - 1.0).abs() < 1e-12);
    }
}
