//! Dense symmetric 3 × 3 matrices: eigendecomposition by cyclic Jacobi
//! rotations (Golub & Van Loan, "Matrix Computations", §8.5) and functions
//! of a matrix through it (square roots, inverses of per-vertex tensors).

use crate::{Mat3, Vec3};
use glam::{DMat3, DVec3};

/// Eigenvalues and orthonormal eigenvectors (the columns of the matrix,
/// in the order of the values) of the symmetric part of `m`. Non-finite
/// input gives non-finite output.
pub fn symmetric_eigen3(m: Mat3) -> (Vec3, Mat3) {
    let mut a = [[0.0f64; 3]; 3];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = 0.5 * (m.col(j)[i] + m.col(i)[j]);
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if !(off > 1e-36 * diag) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // rotation that annihilates a[p][q]
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let values = DVec3::new(a[0][0], a[1][1], a[2][2]);
    let vectors = DMat3::from_cols(
        DVec3::new(v[0][0], v[1][0], v[2][0]),
        DVec3::new(v[0][1], v[1][1], v[2][1]),
        DVec3::new(v[0][2], v[1][2], v[2][2]),
    );
    (values, vectors)
}

/// f(S) = V diag(f(λ)) Vᵀ for the symmetric part S of `m`.
pub fn symmetric_function3(m: Mat3, f: impl Fn(f64) -> f64) -> Mat3 {
    let (values, vectors) = symmetric_eigen3(m);
    function_of_eigen3(values, vectors, f)
}

/// f(M) = V f(Λ) Vᵀ from the eigenvalues Λ and orthonormal eigenvectors V
/// (columns) of a symmetric M, as returned by [`symmetric_eigen3`]: several
/// functions of one matrix for one decomposition.
pub fn function_of_eigen3(values: Vec3, vectors: Mat3, f: impl Fn(f64) -> f64) -> Mat3 {
    let scaled = DMat3::from_cols(
        vectors.x_axis * f(values.x),
        vectors.y_axis * f(values.y),
        vectors.z_axis * f(values.z),
    );
    scaled * vectors.transpose()
}

/// The first N of the bivariate monomials 1, x, y, x², xy, y², x³, x²y,
/// xy², y³: the basis of the small least-squares height fits
/// z(x, y) = Σ c_k m_k(x, y) (N = 6: quadric, N = 10: cubic) solved by
/// [`solve_spd`]. N ≤ 10.
pub fn height_monomials<const N: usize>(x: f64, y: f64) -> [f64; N] {
    let all = [
        1.0,
        x,
        y,
        x * x,
        x * y,
        y * y,
        x * x * x,
        x * x * y,
        x * y * y,
        y * y * y,
    ];
    let mut out = [0.0; N];
    out.copy_from_slice(&all[..N]);
    out
}

/// Solves the dense symmetric positive definite system A x = b of a small
/// least-squares fit (normal equations, N ≤ ~10) by Cholesky factorisation
/// (Golub & Van Loan §4.2). Only the upper triangle of `a` (i ≤ j) is read.
/// `None` when a pivot falls below 1e-12 times the largest diagonal entry
/// (rank-deficient fit) or the input is not finite.
pub fn solve_spd<const N: usize>(a: &[[f64; N]; N], b: &[f64; N]) -> Option<[f64; N]> {
    let scale = (0..N).map(|i| a[i][i]).fold(0.0f64, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return None;
    }
    // lower factor L with A = L Lᵀ
    let mut l = [[0.0f64; N]; N];
    for j in 0..N {
        let mut d = a[j][j];
        for k in 0..j {
            d -= l[j][k] * l[j][k];
        }
        if !(d > 1e-12 * scale) {
            return None;
        }
        let djj = d.sqrt();
        l[j][j] = djj;
        for i in j + 1..N {
            let mut s = a[j][i];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s / djj;
        }
    }
    let mut y = [0.0f64; N];
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0f64; N];
    for i in (0..N).rev() {
        let mut s = y[i];
        for k in i + 1..N {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DMat3, b: DMat3, tol: f64) -> bool {
        (0..3).all(|j| (a.col(j) - b.col(j)).abs().max_element() <= tol)
    }

    #[test]
    fn eigen_reconstructs_and_is_orthonormal() {
        let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let m = r * DMat3::from_diagonal(DVec3::new(5.0, -1.0, 1e-9)) * r.transpose();
        let (l, v) = symmetric_eigen3(m);
        let back = v * DMat3::from_diagonal(l) * v.transpose();
        assert!(close(back, m, 1e-13), "{back} vs {m}");
        assert!(close(v.transpose() * v, DMat3::IDENTITY, 1e-14));
        let mut sorted = l.to_array();
        sorted.sort_by(f64::total_cmp);
        assert!((sorted[0] + 1.0).abs() < 1e-13 && (sorted[2] - 5.0).abs() < 1e-13);
        // repeated eigenvalues and a diagonal input
        let (l, _) = symmetric_eigen3(DMat3::from_diagonal(DVec3::new(2.0, 2.0, 3.0)));
        assert_eq!(l, DVec3::new(2.0, 2.0, 3.0));
    }

    #[test]
    fn square_root_squares_back() {
        let r = DMat3::from_axis_angle(DVec3::new(-1.0, 0.5, 2.0).normalize(), 1.3);
        let m = r * DMat3::from_diagonal(DVec3::new(4.0, 0.25, 9.0)) * r.transpose();
        let s = symmetric_function3(m, f64::sqrt);
        assert!(close(s * s, m, 1e-12));
        let inv = symmetric_function3(m, |x| 1.0 / x);
        assert!(close(inv * m, DMat3::IDENTITY, 1e-12));
    }
}
