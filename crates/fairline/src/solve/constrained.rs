//! The one constrained quadratic solve of the crate, in the spirit of
//! libigl's `min_quad_with_fixed` and PMP's constrained Cholesky: minimise
//! ½ xᵀA x − bᵀx over x with the entries of a fixed set given, i.e. solve
//!
//! A_ff x_f = b_f − A_fk x_k
//!
//! for the free unknowns f, the known (fixed) values x_k moved to the
//! right-hand side. A is a sparse symmetric matrix (positive definite on the
//! free block; positive semi-definite with enough fixed unknowns, e.g. a
//! Laplacian with one fixed vertex per component). The free block's pattern
//! and its symbolic Cholesky factorisation (fill-reducing ordering,
//! elimination tree, supernodes) are computed once in
//! [`ConstrainedSolver::analyse`]; every [`ConstrainedSolver::factor`] with
//! new values of the same pattern reuses them, and one factorisation solves
//! any number of right-hand sides (the x, y and z coordinates together with
//! [`ConstrainedSolver::solve_points`]).

use super::{CholeskyOptions, CholeskyOrdering, CholeskySolver, SolveError, nested_dissection};
use crate::Vec3;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use rayon::prelude::*;

/// Options of [`ConstrainedSolver::analyse`].
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct ConstrainedOptions {
    /// Positions of all n unknowns (e.g. mesh vertices): the free block is
    /// then ordered by [`nested_dissection`], which gives a cheaper factor
    /// on meshes than AMD; `None` uses AMD.
    pub points: Option<Vec<Vec3>>,
    /// Let the numeric factorisation use rayon inside large supernodes
    /// ([`CholeskyOptions::parallel`]).
    pub parallel: bool,
}

crate::control::setters!(ConstrainedOptions {
    points: Option<Vec<Vec3>>,
    parallel: bool,
});

/// Sparse Cholesky of the free block of a symmetric matrix with some
/// unknowns fixed; see the module documentation.
#[derive(Clone, Debug)]
pub struct ConstrainedSolver {
    /// Full index → index among the free unknowns (`usize::MAX`: fixed).
    free_index: Vec<usize>,
    /// Full indices of the free unknowns, ascending.
    free: Vec<usize>,
    /// Pattern of the full matrix A, to check `factor`.
    a_col_ptr: Vec<usize>,
    a_row_idx: Vec<usize>,
    /// The entries of the free columns in fixed rows (A_kf = A_fkᵀ): for
    /// free unknown r, `coupling[coupling_ptr[r]..coupling_ptr[r + 1]]`
    /// holds (entry of A, fixed row).
    coupling_ptr: Vec<usize>,
    coupling: Vec<(usize, usize)>,
    /// Their values at the last factorisation (`None`: not factored).
    coupling_values: Option<Vec<f64>>,
    /// Values of the lower A_ff, kept between factorisations (a buffer).
    free_values: Vec<f64>,
    /// Lower triangle of A_ff.
    pattern: SymbolicSparseColMat<usize>,
    /// Entry k of A goes to entry `to_free[k]` of the lower A_ff
    /// (`usize::MAX`: upper triangle or a fixed row or column).
    to_free: Vec<usize>,
    solver: Option<CholeskySolver>,
}

impl ConstrainedSolver {
    /// Symbolic analysis: the free block of the n × n pattern `a` with
    /// `fixed[i]` telling which unknowns are given. A is symmetric; the
    /// columns of the free unknowns must hold all their entries (both
    /// triangles; the columns of fixed unknowns are never read), rows sorted
    /// within each column. Needs no values, so it can run while they are
    /// computed.
    pub fn analyse(
        a: SymbolicSparseColMatRef<'_, usize>,
        fixed: &[bool],
        opts: &ConstrainedOptions,
    ) -> Result<Self, SolveError> {
        let n = a.nrows();
        if a.ncols() != n || fixed.len() != n {
            return Err(SolveError::Dimension(format!(
                "a constrained solve needs a square matrix and one flag per unknown, got {}×{} and {} flags",
                a.nrows(),
                a.ncols(),
                fixed.len()
            )));
        }
        let mut free_index = vec![usize::MAX; n];
        let mut free = Vec::new();
        for i in 0..n {
            if !fixed[i] {
                free_index[i] = free.len();
                free.push(i);
            }
        }
        let col_ptr_a = a.col_ptr();
        let row_idx_a = a.row_idx();
        let nnz = row_idx_a.len();
        let mut to_free = vec![usize::MAX; nnz];
        let mut coupling_ptr = Vec::with_capacity(free.len() + 1);
        let mut coupling = Vec::new();
        coupling_ptr.push(0usize);
        let mut col_ptr = Vec::with_capacity(free.len() + 1);
        let mut row_idx = Vec::with_capacity(nnz / 2 + free.len());
        col_ptr.push(0usize);
        for (c, &j) in free.iter().enumerate() {
            // rows sorted by full index are sorted by free index too
            for k in col_ptr_a[j]..col_ptr_a[j + 1] {
                let r = free_index[row_idx_a[k]];
                if r == usize::MAX {
                    coupling.push((k, row_idx_a[k]));
                } else if r >= c {
                    if row_idx.len() > col_ptr[c] && row_idx.last() == Some(&r) {
                        // a duplicate entry: its value is summed in `factor`
                        to_free[k] = row_idx.len() - 1;
                    } else {
                        to_free[k] = row_idx.len();
                        row_idx.push(r);
                    }
                }
            }
            col_ptr.push(row_idx.len());
            coupling_ptr.push(coupling.len());
        }
        let m = free.len();
        let pattern = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let solver = if m == 0 {
            None
        } else {
            let ordering = match &opts.points {
                Some(points) if points.len() == n => {
                    let p: Vec<Vec3> = free.iter().map(|&i| points[i]).collect();
                    CholeskyOrdering::Custom(nested_dissection(pattern.as_ref(), &p)?)
                }
                Some(points) => {
                    return Err(SolveError::Dimension(format!(
                        "{} points for {n} unknowns",
                        points.len()
                    )));
                }
                None => CholeskyOrdering::Amd,
            };
            let o = CholeskyOptions {
                ordering,
                parallel: opts.parallel,
            };
            Some(CholeskySolver::analyse(pattern.as_ref(), &o)?)
        };
        Ok(ConstrainedSolver {
            free_index,
            free,
            a_col_ptr: col_ptr_a.to_vec(),
            a_row_idx: row_idx_a.to_vec(),
            coupling_ptr,
            coupling,
            coupling_values: None,
            free_values: Vec::new(),
            pattern,
            to_free,
            solver,
        })
    }

    /// Numeric factorisation of A_ff for the values of `a` (the pattern
    /// given to [`ConstrainedSolver::analyse`]), reusing the symbolic
    /// analysis.
    pub fn factor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveError> {
        if a.symbolic().col_ptr() != self.a_col_ptr || a.symbolic().row_idx() != self.a_row_idx {
            return Err(SolveError::Dimension(
                "a constrained solve needs the pattern it was analysed with".into(),
            ));
        }
        let values = a.val();
        self.factor_with(|_, k| values[k])
    }

    /// Numeric factorisation of A_ff with the values of A given entry by
    /// entry: `value(j, k)` is entry k of the pattern given to
    /// [`ConstrainedSolver::analyse`], which lies in column j. Only the
    /// entries the solve needs are asked for, each once: the lower triangle
    /// of A_ff and the coupling A_kf of the free columns. So a method whose
    /// matrix changes every step (implicit smoothing) assembles and
    /// eliminates in one parallel pass over its entries, without building
    /// A; the buffers of the values are kept between factorisations.
    pub fn factor_with(
        &mut self,
        value: impl Fn(usize, usize) -> f64 + Sync,
    ) -> Result<(), SolveError> {
        self.coupling_values = None;
        let nnz = self.pattern.row_idx().len();
        let mut free_values = std::mem::take(&mut self.free_values);
        free_values.clear();
        free_values.resize(nnz, 0.0);
        let mut coupling_values = vec![0.0; self.coupling.len()];
        {
            // blocks of free columns: disjoint ranges of both value arrays
            const BLOCK: usize = 2048;
            let col_ptr = self.pattern.col_ptr();
            let m = self.free.len();
            let mut blocks = Vec::with_capacity(m / BLOCK + 1);
            let (mut fv, mut cv) = (&mut free_values[..], &mut coupling_values[..]);
            let mut c0 = 0;
            while c0 < m {
                let c1 = (c0 + BLOCK).min(m);
                let (a, rest) = fv.split_at_mut(col_ptr[c1] - col_ptr[c0]);
                let (b, rest_c) = cv.split_at_mut(self.coupling_ptr[c1] - self.coupling_ptr[c0]);
                blocks.push((c0, c1, a, b));
                (fv, cv) = (rest, rest_c);
                c0 = c1;
            }
            blocks.into_par_iter().for_each(|(c0, c1, fv, cv)| {
                let (f0, k0) = (col_ptr[c0], self.coupling_ptr[c0]);
                for c in c0..c1 {
                    let j = self.free[c];
                    for k in self.a_col_ptr[j]..self.a_col_ptr[j + 1] {
                        let t = self.to_free[k];
                        if t != usize::MAX {
                            fv[t - f0] += value(j, k);
                        }
                    }
                    for t in self.coupling_ptr[c]..self.coupling_ptr[c + 1] {
                        cv[t - k0] = value(j, self.coupling[t].0);
                    }
                }
            });
        }
        let result = match self.solver.as_mut() {
            Some(solver) => solver
                .factor_same_pattern(SparseColMatRef::new(self.pattern.as_ref(), &free_values)),
            None => Ok(()),
        };
        self.free_values = free_values;
        result?;
        self.coupling_values = Some(coupling_values);
        Ok(())
    }

    /// Full indices of the free unknowns, ascending.
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Number of unknowns n.
    pub fn dim(&self) -> usize {
        self.free_index.len()
    }

    /// Right-hand side of the free rows, b_f − A_fk x_k. A is symmetric,
    /// so A_fk is read from the free columns (A_kf), in parallel.
    fn reduced_rhs<T>(&self, b: &[T], x: &[T]) -> Result<Vec<T>, SolveError>
    where
        T: Copy + Send + Sync + std::ops::SubAssign + std::ops::Mul<f64, Output = T>,
    {
        let n = self.dim();
        if b.len() != n || x.len() != n {
            return Err(SolveError::Dimension(format!(
                "a constrained solve of {n} unknowns got {} right-hand-side and {} solution entries",
                b.len(),
                x.len()
            )));
        }
        let Some(values) = &self.coupling_values else {
            return Err(SolveError::Backend(
                "the constrained solve has been analysed but not factored".into(),
            ));
        };
        Ok(self
            .free
            .par_iter()
            .enumerate()
            .map(|(r, &i)| {
                let mut v = b[i];
                for t in self.coupling_ptr[r]..self.coupling_ptr[r + 1] {
                    v -= x[self.coupling[t].1] * values[t];
                }
                v
            })
            .collect())
    }

    /// Solves for points (three right-hand sides at once): `b` holds the
    /// right-hand side of every unknown (rows of fixed unknowns are
    /// ignored), `x` the given values of the fixed unknowns on entry and the
    /// solution at the free ones on return (the fixed entries unchanged).
    pub fn solve_points(&self, b: &[Vec3], x: &mut [Vec3]) -> Result<(), SolveError> {
        let mut rhs = self.reduced_rhs(b, x)?;
        if let Some(solver) = &self.solver {
            solver.solve_points(&mut rhs)?;
        }
        for (r, &i) in self.free.iter().enumerate() {
            x[i] = rhs[r];
        }
        Ok(())
    }

    /// As [`ConstrainedSolver::solve_points`] for one scalar right-hand
    /// side.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<(), SolveError> {
        let mut rhs = self.reduced_rhs(b, x)?;
        if let Some(solver) = &self.solver {
            solver.solve_in_place(&mut rhs)?;
        }
        for (r, &i) in self.free.iter().enumerate() {
            x[i] = rhs[r];
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::sparse_from_triplets;

    /// 1D Poisson problem −u'' = 0 on a path of n nodes with both ends
    /// fixed: the solution is the straight line between the end values; the
    /// same factorisation serves a second right-hand side and a refactored
    /// matrix equals a fresh analysis.
    #[test]
    fn fixed_ends_of_a_path_laplacian_give_the_straight_line() {
        let n = 40;
        let build = |shift: f64| {
            let mut t = Vec::new();
            for i in 0..n {
                let d = if i == 0 || i == n - 1 { 1.0 } else { 2.0 };
                t.push((i, i, d + shift));
                if i + 1 < n {
                    t.push((i, i + 1, -1.0));
                    t.push((i + 1, i, -1.0));
                }
            }
            sparse_from_triplets(n, n, &t).unwrap()
        };
        let a = build(0.0);
        let mut fixed = vec![false; n];
        fixed[0] = true;
        fixed[n - 1] = true;
        let mut s =
            ConstrainedSolver::analyse(a.symbolic(), &fixed, &ConstrainedOptions::default())
                .unwrap();
        let mut x = vec![0.0; n];
        assert!(s.solve(&vec![0.0; n], &mut x).is_err(), "not factored yet");
        s.factor(a.as_ref()).unwrap();
        x[0] = 1.0;
        x[n - 1] = 3.0;
        s.solve(&vec![0.0; n], &mut x).unwrap();
        for (i, v) in x.iter().enumerate() {
            let want = 1.0 + 2.0 * i as f64 / (n - 1) as f64;
            assert!((v - want).abs() < 1e-12, "{i}: {v} vs {want}");
        }
        // points: each coordinate its own line; rows of fixed unknowns in b
        // are ignored
        let mut p = vec![Vec3::ZERO; n];
        p[0] = Vec3::new(0.0, 1.0, -1.0);
        p[n - 1] = Vec3::new(1.0, 1.0, 2.0);
        let mut b = vec![Vec3::ZERO; n];
        b[0] = Vec3::splat(99.0);
        s.solve_points(&b, &mut p).unwrap();
        for (i, q) in p.iter().enumerate() {
            let t = i as f64 / (n - 1) as f64;
            let want = Vec3::new(t, 1.0, -1.0 + 3.0 * t);
            assert!(q.distance(want) < 1e-12, "{i}: {q} vs {want}");
        }
        // refactor with new values = a fresh analysis of them; a different
        // pattern is refused
        s.factor(build(0.5).as_ref()).unwrap();
        let mut fresh =
            ConstrainedSolver::analyse(a.symbolic(), &fixed, &ConstrainedOptions::default())
                .unwrap();
        fresh.factor(build(0.5).as_ref()).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let (mut y, mut z) = (x.clone(), x.clone());
        s.solve(&b, &mut y).unwrap();
        fresh.solve(&b, &mut z).unwrap();
        assert_eq!(y, z);
        assert_ne!(y, x);
        let other = sparse_from_triplets(n, n, &[(0, 0, 1.0)]).unwrap();
        assert!(s.factor(other.as_ref()).is_err());
        // nested dissection from points orders the free block: same answer
        let points: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
        let mut nd = ConstrainedSolver::analyse(
            a.symbolic(),
            &fixed,
            &ConstrainedOptions {
                points: Some(points),
                parallel: false,
            },
        )
        .unwrap();
        nd.factor(build(0.5).as_ref()).unwrap();
        let mut w = x.clone();
        nd.solve(&b, &mut w).unwrap();
        let d = w
            .iter()
            .zip(&y)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-12, "{d}");
        // nothing free: the given values come back untouched
        let mut all = ConstrainedSolver::analyse(
            a.symbolic(),
            &vec![true; n],
            &ConstrainedOptions::default(),
        )
        .unwrap();
        all.factor(a.as_ref()).unwrap();
        let mut v = b.clone();
        all.solve(&vec![0.0; n], &mut v).unwrap();
        assert_eq!(v, b);
        // without fixed unknowns the singular Laplacian is refused
        let mut none = ConstrainedSolver::analyse(
            a.symbolic(),
            &vec![false; n],
            &ConstrainedOptions::default(),
        )
        .unwrap();
        assert_eq!(
            none.factor(a.as_ref()).unwrap_err(),
            SolveError::NotPositiveDefinite
        );
    }
}
