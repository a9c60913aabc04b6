//! Bound-constrained convex quadratic programming:
//! min ½ xᵀQx + cᵀx subject to l ≤ x ≤ u, with sparse symmetric positive
//! (semi-)definite Q. Projected Newton method of Bertsekas (1982): the
//! variables at a bound whose gradient pushes outward are held fixed, a
//! Newton step is taken on the others by a sparse Cholesky factorisation
//! (the pattern of Q is kept, so the symbolic analysis is reused), followed
//! by an Armijo search along the projection arc. Once the active set is
//! identified the full Newton step is exact, so the result satisfies the KKT
//! conditions to rounding error.

use super::{CholeskySolver, SolveError};
use faer::sparse::{SparseColMat, SparseColMatRef};

/// Options of [`solve_box_qp`].
#[derive(Clone, Debug, PartialEq)]
pub struct BoxQpOptions {
    /// Stop when ‖x − P(x − ∇f)‖∞ ≤ tolerance · max(1, ‖c‖∞).
    pub tolerance: f64,
    /// Upper bound on Newton iterations.
    pub max_iterations: usize,
}

impl Default for BoxQpOptions {
    fn default() -> Self {
        BoxQpOptions {
            tolerance: 1e-12,
            max_iterations: 200,
        }
    }
}

/// Result of [`solve_box_qp`].
#[derive(Clone, Debug, PartialEq)]
pub struct BoxQpSolution {
    /// The minimiser.
    pub x: Vec<f64>,
    /// Objective ½ xᵀQx + cᵀx at `x`.
    pub objective: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Whether the projected-gradient criterion was met.
    pub converged: bool,
    /// Variables at their lower bound.
    pub at_lower: usize,
    /// Variables at their upper bound.
    pub at_upper: usize,
}

fn mul(q: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; x.len()];
    for j in 0..q.ncols() {
        for (&i, &v) in q.row_idx_of_col_raw(j).iter().zip(q.val_of_col(j)) {
            y[i] += v * x[j];
        }
    }
    y
}

fn objective(q: SparseColMatRef<'_, usize, f64>, c: &[f64], x: &[f64]) -> f64 {
    let qx = mul(q, x);
    x.iter()
        .zip(&qx)
        .zip(c)
        .map(|((x, qx), c)| 0.5 * x * qx + c * x)
        .sum()
}

/// Solves min ½ xᵀQx + cᵀx s.t. `lower` ≤ x ≤ `upper` (bounds may be
/// ±∞). Q is given with both triangles. `x0` is an optional start (projected
/// onto the box). A positive semi-definite Q is handled by a small diagonal
/// shift of the Newton system when its factorisation fails.
pub fn solve_box_qp(
    q: SparseColMatRef<'_, usize, f64>,
    c: &[f64],
    lower: &[f64],
    upper: &[f64],
    x0: Option<&[f64]>,
    opts: &BoxQpOptions,
) -> Result<BoxQpSolution, SolveError> {
    let n = c.len();
    if q.nrows() != n || q.ncols() != n || lower.len() != n || upper.len() != n {
        return Err(SolveError::Dimension("box QP sizes".into()));
    }
    if lower.iter().zip(upper).any(|(l, u)| !(l <= u)) {
        return Err(SolveError::Dimension("a lower bound exceeds its upper bound".into()));
    }
    let proj = |i: usize, v: f64| v.max(lower[i]).min(upper[i]);
    let mut x: Vec<f64> = match x0 {
        Some(s) if s.len() == n => (0..n).map(|i| proj(i, s[i])).collect(),
        _ => (0..n)
            .map(|i| proj(i, if lower[i].is_finite() || upper[i].is_finite() {
                0.0f64.max(lower[i]).min(upper[i])
            } else {
                0.0
            }))
            .collect(),
    };
    let scale = c.iter().fold(1.0f64, |a, v| a.max(v.abs()));
    let tol = opts.tolerance * scale;
    // pattern with every diagonal entry present, values filled per iteration
    let mut trip = Vec::new();
    let mut maxdiag: f64 = 0.0;
    for j in 0..n {
        trip.push((j, j, 0.0));
        for (&i, &v) in q.row_idx_of_col_raw(j).iter().zip(q.val_of_col(j)) {
            if i >= j {
                trip.push((i, j, v));
            }
            if i == j {
                maxdiag = maxdiag.max(v.abs());
            }
        }
    }
    let base = super::sparse_from_triplets(n, n, &trip)?;
    let mut solver: Option<CholeskySolver> = None;
    let mut iterations = 0;
    let mut converged = false;
    let mut f = objective(q, c, &x);
    while iterations < opts.max_iterations {
        let mut g = mul(q, &x);
        for i in 0..n {
            g[i] += c[i];
        }
        let pg = (0..n)
            .map(|i| (x[i] - proj(i, x[i] - g[i])).abs())
            .fold(0.0, f64::max);
        if pg <= tol {
            converged = true;
            break;
        }
        iterations += 1;
        // binding set: at (or within eps of) a bound with the gradient pointing out
        let eps = pg.min(1e-8 * scale);
        let bound: Vec<bool> = (0..n)
            .map(|i| {
                (x[i] <= lower[i] + eps && g[i] > 0.0) || (x[i] >= upper[i] - eps && g[i] < 0.0)
            })
            .collect();
        let mut d = vec![0.0; n];
        let mut shift = 0.0;
        loop {
            let mut vals = base.val().to_vec();
            let sym = base.symbolic();
            for j in 0..n {
                let r = sym.col_range(j);
                for k in r {
                    let i = sym.row_idx()[k];
                    vals[k] = if bound[i] || bound[j] {
                        if i == j { 1.0 } else { 0.0 }
                    } else if i == j {
                        vals[k] + shift
                    } else {
                        vals[k]
                    };
                }
            }
            let a = SparseColMat::new(sym.to_owned().map_err(|e| SolveError::Backend(format!("{e:?}")))?, vals);
            let ok = match solver.as_mut() {
                Some(s) => s.refactor(a.as_ref()).is_ok(),
                None => match CholeskySolver::new(a.as_ref()) {
                    Ok(s) => {
                        solver = Some(s);
                        true
                    }
                    Err(_) => false,
                },
            };
            if ok {
                for i in 0..n {
                    d[i] = if bound[i] { 0.0 } else { -g[i] };
                }
                if solver.as_ref().expect("ok").solve_in_place(&mut d).is_ok() {
                    break;
                }
            }
            shift = if shift == 0.0 { 1e-12 * maxdiag.max(1.0) } else { shift * 100.0 };
            if shift > 1e6 * maxdiag.max(1.0) {
                return Err(SolveError::NotPositiveDefinite);
            }
        }
        // Armijo search along the projection arc
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..60 {
            let xn: Vec<f64> = (0..n).map(|i| proj(i, x[i] + alpha * d[i])).collect();
            let fn_ = objective(q, c, &xn);
            let dec: f64 = (0..n)
                .map(|i| {
                    if bound[i] {
                        g[i] * (x[i] - xn[i])
                    } else {
                        -alpha * g[i] * d[i]
                    }
                })
                .sum();
            if fn_ <= f - 1e-4 * dec.max(0.0) || fn_ < f {
                x = xn;
                f = fn_;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    let at_lower = (0..n).filter(|&i| x[i] <= lower[i]).count();
    let at_upper = (0..n).filter(|&i| x[i] >= upper[i]).count();
    Ok(BoxQpSolution {
        objective: f,
        x,
        iterations,
        converged,
        at_lower,
        at_upper,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::sparse_from_triplets;

    /// Tiny deterministic generator (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Dense solve by Gaussian elimination (test helper).
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
            if a[p][k].abs() < 1e-14 {
                return None;
            }
            a.swap(k, p);
            b.swap(k, p);
            for i in k + 1..n {
                let m = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= m * a[k][j];
                }
                b[i] -= m * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
            x[k] = (b[k] - s) / a[k][k];
        }
        Some(x)
    }

    #[test]
    fn box_qp_matches_brute_force_enumeration_of_active_sets() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        for trial in 0..40 {
            let n = 2 + trial % 5;
            // Q = BᵀB + 0.1 I, sparse-ish B
            let b: Vec<Vec<f64>> = (0..n)
                .map(|_| (0..n).map(|_| if rng.next() > 0.0 { rng.next() } else { 0.0 }).collect())
                .collect();
            let mut qd = vec![vec![0.0; n]; n];
            for i in 0..n {
                for j in 0..n {
                    qd[i][j] = (0..n).map(|k| b[k][i] * b[k][j]).sum::<f64>();
                }
                qd[i][i] += 0.1;
            }
            let c: Vec<f64> = (0..n).map(|_| 2.0 * rng.next()).collect();
            let lo: Vec<f64> = (0..n).map(|_| -0.5 + 0.4 * rng.next()).collect();
            let up: Vec<f64> = lo.iter().map(|l| l + 0.2 + 0.5 * rng.next().abs()).collect();
            let mut t = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    if qd[i][j] != 0.0 {
                        t.push((i, j, qd[i][j]));
                    }
                }
            }
            let q = sparse_from_triplets(n, n, &t).unwrap();
            let sol = solve_box_qp(q.as_ref(), &c, &lo, &up, None, &BoxQpOptions::default())
                .unwrap();
            assert!(sol.converged, "trial {trial}");
            // brute force: every assignment lower / upper / free
            let obj = |x: &[f64]| -> f64 {
                (0..n)
                    .map(|i| 0.5 * x[i] * (0..n).map(|j| qd[i][j] * x[j]).sum::<f64>() + c[i] * x[i])
                    .sum()
            };
            let mut best = f64::INFINITY;
            let mut best_x = vec![];
            for code in 0..3usize.pow(n as u32) {
                let mut state = vec![0; n];
                let mut k = code;
                for s in state.iter_mut() {
                    *s = k % 3;
                    k /= 3;
                }
                let free: Vec<usize> = (0..n).filter(|&i| state[i] == 2).collect();
                let mut x: Vec<f64> = (0..n)
                    .map(|i| match state[i] {
                        0 => lo[i],
                        1 => up[i],
                        _ => 0.0,
                    })
                    .collect();
                if !free.is_empty() {
                    let a: Vec<Vec<f64>> =
                        free.iter().map(|&i| free.iter().map(|&j| qd[i][j]).collect()).collect();
                    let r: Vec<f64> = free
                        .iter()
                        .map(|&i| {
                            -c[i] - (0..n)
                                .filter(|j| state[*j] != 2)
                                .map(|j| qd[i][j] * x[j])
                                .sum::<f64>()
                        })
                        .collect();
                    let Some(s) = dense_solve(a, r) else { continue };
                    for (k, &i) in free.iter().enumerate() {
                        x[i] = s[k];
                    }
                }
                if (0..n).all(|i| x[i] >= lo[i] - 1e-12 && x[i] <= up[i] + 1e-12) {
                    let o = obj(&x);
                    if o < best {
                        best = o;
                        best_x = x;
                    }
                }
            }
            for i in 0..n {
                assert!((sol.x[i] - best_x[i]).abs() < 1e-9, "trial {trial}: {:?} vs {best_x:?}", sol.x);
            }
            assert!((sol.objective - best).abs() < 1e-10);
        }
    }

    #[test]
    fn box_qp_refuses_inconsistent_bounds() {
        let q = sparse_from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap();
        assert!(solve_box_qp(q.as_ref(), &[0.0], &[1.0], &[0.0], None, &BoxQpOptions::default()).is_err());
    }
}
