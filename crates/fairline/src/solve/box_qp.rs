//! Bound-constrained convex quadratic programming
//!
//! minimise ½ xᵀQx + cᵀx subject to l ≤ x ≤ u, Q sparse symmetric positive
//! definite: the problem of Yong et al. Eq. (16).
//!
//! Method: projected Newton with an active set (Bertsekas 1982, in the exact
//! form for quadratics). At each iterate the *binding* set holds the
//! variables at a bound whose gradient pushes outward; the remaining (free)
//! variables take the Newton step of the reduced problem, solved exactly by
//! a sparse Cholesky factorisation of Q_FF ([`CholeskySolver`]). Free
//! variables at a bound whose Newton step would leave the box are moved to
//! the binding set and the step recomputed, so the projected path is a
//! descent path; a projected Armijo search then takes the step. When a full
//! step is taken without touching a new bound, the iterate is the exact
//! minimiser over its face, and the loop stops once the KKT conditions hold
//! (gradient zero on free variables, with the right sign on bound ones).

use super::{CholeskySolver, SolveError, sparse_from_triplets};
use faer::sparse::SparseColMatRef;

/// Options of [`box_qp`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct BoxQpOptions {
    /// Most projected Newton iterations (default 200).
    pub max_iterations: usize,
    /// KKT tolerance relative to max(1, ‖c‖∞, ‖Q‖ scale) (default 1e-10).
    pub tolerance: f64,
}

impl Default for BoxQpOptions {
    fn default() -> Self {
        BoxQpOptions {
            max_iterations: 200,
            tolerance: 1e-10,
        }
    }
}

impl BoxQpOptions {
    /// Sets [`BoxQpOptions::max_iterations`].
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets [`BoxQpOptions::tolerance`].
    pub fn tolerance(mut self, t: f64) -> Self {
        self.tolerance = t;
        self
    }
}

/// Result of [`box_qp`].
#[derive(Clone, Debug, PartialEq)]
pub struct BoxQpSolution {
    /// The minimiser (inside the box).
    pub x: Vec<f64>,
    /// ½ xᵀQx + cᵀx at `x`.
    pub objective: f64,
    /// Projected Newton iterations used.
    pub iterations: usize,
    /// Number of variables at a bound at the solution.
    pub active: usize,
    /// True when the KKT conditions hold to the tolerance.
    pub converged: bool,
}

/// Symmetric matrix as per-column (row, value) lists, both triangles.
struct SymMatrix {
    cols: Vec<Vec<(usize, f64)>>,
}

impl SymMatrix {
    fn from_faer(q: SparseColMatRef<'_, usize, f64>) -> Self {
        let n = q.ncols();
        let sym = q.symbolic();
        let rows = sym.row_idx();
        let vals = q.val();
        let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for j in 0..n {
            for k in sym.col_range(j) {
                let i = rows[k];
                cols[j].push((i, vals[k]));
            }
        }
        SymMatrix { cols }
    }
    fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for (j, col) in self.cols.iter().enumerate() {
            let xj = x[j];
            if xj == 0.0 {
                continue;
            }
            for &(i, v) in col {
                y[i] += v * xj;
            }
        }
        y
    }
}

fn objective(q: &SymMatrix, c: &[f64], x: &[f64]) -> f64 {
    let qx = q.mul(x);
    x.iter()
        .zip(&qx)
        .zip(c)
        .map(|((&xi, &qi), &ci)| 0.5 * xi * qi + ci * xi)
        .sum()
}

/// Solves min ½ xᵀQx + cᵀx subject to `lower ≤ x ≤ upper` (Yong et al.
/// Eq. (16)) exactly by projected Newton with an active set (see the module
/// documentation). `q` is the full symmetric matrix (both triangles) and must
/// be positive definite; bounds may be ±∞ but need `lower ≤ upper`.
/// Errors on mismatched sizes, crossed or NaN bounds, non-finite data, or
/// when a reduced matrix is not positive definite.
pub fn box_qp(
    q: SparseColMatRef<'_, usize, f64>,
    c: &[f64],
    lower: &[f64],
    upper: &[f64],
    options: &BoxQpOptions,
) -> Result<BoxQpSolution, SolveError> {
    let n = c.len();
    if q.nrows() != n || q.ncols() != n || lower.len() != n || upper.len() != n {
        return Err(SolveError::Dimension(format!(
            "box QP: Q is {}×{}, c has {}, bounds {} and {}",
            q.nrows(),
            q.ncols(),
            n,
            lower.len(),
            upper.len()
        )));
    }
    if let Some(i) = (0..n).find(|&i| !(lower[i] <= upper[i])) {
        return Err(SolveError::Dimension(format!(
            "box QP: bounds of variable {i} are crossed or NaN ({} > {})",
            lower[i], upper[i]
        )));
    }
    if c.iter().any(|v| !v.is_finite()) || q.val().iter().any(|v| !v.is_finite()) {
        return Err(SolveError::NonFinite);
    }
    let qm = SymMatrix::from_faer(q);
    let scale = 1.0
        + c.iter().fold(0.0f64, |a, &v| a.max(v.abs()))
        + q.val().iter().fold(0.0f64, |a, &v| a.max(v.abs()));
    let tol = options.tolerance * scale;
    let project = |x: &mut [f64]| {
        for i in 0..n {
            x[i] = x[i].clamp(lower[i], upper[i]);
        }
    };
    let mut x = vec![0.0; n];
    project(&mut x);
    let mut iterations = 0;
    let mut converged = false;
    // 0 = free, -1 at lower, +1 at upper (binding)
    let mut state = vec![0i8; n];
    while iterations < options.max_iterations {
        iterations += 1;
        let g: Vec<f64> = qm.mul(&x).iter().zip(c).map(|(a, b)| a + b).collect();
        for i in 0..n {
            state[i] = if x[i] <= lower[i] && g[i] > 0.0 {
                -1
            } else if x[i] >= upper[i] && g[i] < 0.0 {
                1
            } else {
                0
            };
        }
        // KKT check: gradient vanishes on free variables.
        let kkt = (0..n)
            .filter(|&i| state[i] == 0)
            .fold(0.0f64, |a, i| a.max(g[i].abs()));
        if kkt <= tol {
            converged = true;
            break;
        }
        // Newton step on the free set; grow the binding set while the step
        // would push a variable sitting at a bound out of the box.
        let d = loop {
            let free: Vec<usize> = (0..n).filter(|&i| state[i] == 0).collect();
            let d = reduced_newton(&qm, &g, &free, n)?;
            let mut grew = false;
            for &i in &free {
                if (x[i] <= lower[i] && d[i] < 0.0) || (x[i] >= upper[i] && d[i] > 0.0) {
                    state[i] = if x[i] <= lower[i] { -1 } else { 1 };
                    grew = true;
                }
            }
            if !grew {
                break d;
            }
        };
        let f0 = objective(&qm, c, &x);
        let mut t = 1.0;
        let mut accepted = None;
        for _ in 0..60 {
            let mut y: Vec<f64> = x.iter().zip(&d).map(|(a, b)| a + t * b).collect();
            project(&mut y);
            let decrease: f64 = g
                .iter()
                .zip(y.iter().zip(&x))
                .map(|(gi, (a, b))| gi * (a - b))
                .sum();
            let f = objective(&qm, c, &y);
            if f <= f0 + 1e-4 * decrease {
                accepted = Some(y);
                break;
            }
            t *= 0.5;
        }
        match accepted {
            Some(y) => {
                let moved = y.iter().zip(&x).any(|(a, b)| a != b);
                x = y;
                if !moved {
                    // No progress possible at floating-point resolution.
                    break;
                }
            }
            None => break,
        }
    }
    if !converged {
        // Final check after the last step.
        let g: Vec<f64> = qm.mul(&x).iter().zip(c).map(|(a, b)| a + b).collect();
        converged = (0..n).all(|i| {
            let at_lower = x[i] <= lower[i] && g[i] > 0.0;
            let at_upper = x[i] >= upper[i] && g[i] < 0.0;
            at_lower || at_upper || g[i].abs() <= tol
        });
    }
    let active = (0..n)
        .filter(|&i| x[i] <= lower[i] || x[i] >= upper[i])
        .count();
    Ok(BoxQpSolution {
        objective: objective(&qm, c, &x),
        x,
        iterations,
        active,
        converged,
    })
}

/// Newton direction −Q_FF⁻¹ g_F on the free variables, zero elsewhere.
fn reduced_newton(
    q: &SymMatrix,
    g: &[f64],
    free: &[usize],
    n: usize,
) -> Result<Vec<f64>, SolveError> {
    let mut d = vec![0.0; n];
    if free.is_empty() {
        return Ok(d);
    }
    let mut local = vec![usize::MAX; n];
    for (k, &i) in free.iter().enumerate() {
        local[i] = k;
    }
    let mut triplets = Vec::new();
    for (kj, &j) in free.iter().enumerate() {
        for &(i, v) in &q.cols[j] {
            let ki = local[i];
            if ki != usize::MAX && ki >= kj {
                triplets.push((ki, kj, v));
            }
        }
    }
    let m = sparse_from_triplets(free.len(), free.len(), &triplets)?;
    let chol = CholeskySolver::new(m.as_ref())?;
    let mut rhs: Vec<f64> = free.iter().map(|&i| -g[i]).collect();
    chol.solve_in_place(&mut rhs)?;
    for (k, &i) in free.iter().enumerate() {
        d[i] = rhs[k];
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::sparse_from_triplets;

    /// Tiny deterministic generator (xorshift) so the test needs no crate.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    fn dense_solve(a: &mut [Vec<f64>], b: &mut [f64]) -> bool {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
                .unwrap();
            if a[p][k].abs() < 1e-14 {
                return false;
            }
            a.swap(k, p);
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                b[i] -= f * b[k];
            }
        }
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k][j] * b[j]).sum();
            b[k] = (b[k] - s) / a[k][k];
        }
        true
    }

    /// Minimum over all 3^n assignments (lower / upper / free) of the
    /// feasible face minimisers: the global minimum of a convex QP.
    fn brute_force(q: &[Vec<f64>], c: &[f64], l: &[f64], u: &[f64]) -> (Vec<f64>, f64) {
        let n = c.len();
        let mut best = (vec![], f64::INFINITY);
        for code in 0..3usize.pow(n as u32) {
            let mut s = vec![0; n];
            let mut k = code;
            for si in s.iter_mut() {
                *si = k % 3;
                k /= 3;
            }
            let mut x = vec![0.0; n];
            for i in 0..n {
                x[i] = match s[i] {
                    0 => l[i],
                    1 => u[i],
                    _ => 0.0,
                };
            }
            let free: Vec<usize> = (0..n).filter(|&i| s[i] == 2).collect();
            let mut a: Vec<Vec<f64>> = free
                .iter()
                .map(|&i| free.iter().map(|&j| q[i][j]).collect())
                .collect();
            let mut b: Vec<f64> = free
                .iter()
                .map(|&i| {
                    -c[i]
                        - (0..n)
                            .filter(|&j| s[j] != 2)
                            .map(|j| q[i][j] * x[j])
                            .sum::<f64>()
                })
                .collect();
            if !dense_solve(&mut a, &mut b) {
                continue;
            }
            for (k, &i) in free.iter().enumerate() {
                x[i] = b[k];
            }
            if (0..n).any(|i| x[i] < l[i] - 1e-12 || x[i] > u[i] + 1e-12) {
                continue;
            }
            let f: f64 = (0..n)
                .map(|i| 0.5 * x[i] * (0..n).map(|j| q[i][j] * x[j]).sum::<f64>() + c[i] * x[i])
                .sum();
            if f < best.1 {
                best = (x, f);
            }
        }
        best
    }

    #[test]
    fn box_qp_matches_brute_force_on_random_problems() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        for trial in 0..300 {
            let n = 1 + trial % 7;
            // Q = BᵀB + δI with a sparse-ish B.
            let b: Vec<Vec<f64>> = (0..n + 1)
                .map(|_| {
                    (0..n)
                        .map(|_| if rng.next() > -0.3 { rng.next() } else { 0.0 })
                        .collect()
                })
                .collect();
            let mut q = vec![vec![0.0; n]; n];
            for i in 0..n {
                for j in 0..n {
                    q[i][j] = (0..n + 1).map(|k| b[k][i] * b[k][j]).sum::<f64>();
                }
                q[i][i] += 0.05;
            }
            let c: Vec<f64> = (0..n).map(|_| 3.0 * rng.next()).collect();
            let l: Vec<f64> = (0..n).map(|_| -0.2 - rng.next().abs()).collect();
            let u: Vec<f64> = (0..n).map(|_| 0.1 + rng.next().abs()).collect();
            let mut trip = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    if q[i][j] != 0.0 {
                        trip.push((i, j, q[i][j]));
                    }
                }
            }
            let qs = sparse_from_triplets(n, n, &trip).unwrap();
            let sol = box_qp(qs.as_ref(), &c, &l, &u, &BoxQpOptions::default()).unwrap();
            let (xb, fb) = brute_force(&q, &c, &l, &u);
            assert!(sol.converged, "trial {trial}");
            for i in 0..n {
                assert!(sol.x[i] >= l[i] && sol.x[i] <= u[i]);
                assert!(
                    (sol.x[i] - xb[i]).abs() < 1e-8,
                    "trial {trial}: {:?} vs {:?}",
                    sol.x,
                    xb
                );
            }
            assert!((sol.objective - fb).abs() < 1e-9 * (1.0 + fb.abs()));
        }
    }

    #[test]
    fn box_qp_unconstrained_interior_solution_and_errors() {
        // Q = diag(2, 4), c = (-2, -4): minimiser (1, 1) inside the box.
        let q = sparse_from_triplets(2, 2, &[(0, 0, 2.0), (1, 1, 4.0)]).unwrap();
        let s = box_qp(
            q.as_ref(),
            &[-2.0, -4.0],
            &[-5.0, -5.0],
            &[5.0, 5.0],
            &BoxQpOptions::default(),
        )
        .unwrap();
        // exact up to the rounding of the Cholesky factor (√2·√2 ≠ 2 in f64)
        for xi in &s.x {
            assert!((xi - 1.0).abs() <= 4.0 * f64::EPSILON, "{:?}", s.x);
        }
        assert_eq!(s.active, 0);
        // Crossed bounds and size mismatch are errors.
        assert!(
            box_qp(
                q.as_ref(),
                &[0.0, 0.0],
                &[1.0, 0.0],
                &[0.0, 1.0],
                &BoxQpOptions::default()
            )
            .is_err()
        );
        assert!(box_qp(q.as_ref(), &[0.0], &[0.0], &[0.0], &BoxQpOptions::default()).is_err());
        // Indefinite Q is reported.
        let bad = sparse_from_triplets(2, 2, &[(0, 0, -1.0), (1, 1, 1.0)]).unwrap();
        assert!(
            box_qp(
                bad.as_ref(),
                &[1.0, 1.0],
                &[-1.0, -1.0],
                &[1.0, 1.0],
                &BoxQpOptions::default()
            )
            .is_err()
        );
    }
}
