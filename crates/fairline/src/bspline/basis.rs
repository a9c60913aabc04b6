//! B-spline basis functions and their derivatives.
//!
//! Implements Piegl & Tiller, *The NURBS Book* (2nd ed.), Algorithm A2.1
//! (`FindSpan`), A2.2 (`BasisFuns`) and A2.3 (`DersBasisFuns`), restricted to
//! derivatives of order ≤ 2 and working on fixed-size stack buffers so that an
//! evaluation never allocates.
//!
//! Conventions: `knots` has `count + degree + 1` entries, `count` is the number
//! of control points in that direction, and the parameter domain is
//! `[knots[degree], knots[count]]`. The knot vector may be clamped or unclamped.

/// Largest supported degree in either direction (the size of the stack buffers).
pub const MAX_DEGREE: usize = 15;

/// `MAX_DEGREE + 1`: the largest number of non-zero basis functions at a parameter.
pub const MAX_ORDER: usize = MAX_DEGREE + 1;

/// Basis function values and derivatives up to second order on one knot span:
/// `ders[k][r]` is the k-th derivative of `N_{span - degree + r, degree}`.
pub type BasisDerivs = [[f64; MAX_ORDER]; 3];

/// The clamped uniform knot vector of `count` control points of degree
/// `degree` on `[0, 1]`: `degree + 1` zeros, `count - degree - 1` equally
/// spaced interior knots, `degree + 1` ones (Piegl & Tiller Eq. 2.13 with
/// uniform interior knots). Empty when `count <= degree`.
pub fn clamped_uniform_knots(count: usize, degree: usize) -> Vec<f64> {
    if count <= degree {
        return Vec::new();
    }
    let spans = count - degree;
    (0..count + degree + 1)
        .map(|k| {
            if k <= degree {
                0.0
            } else if k >= count {
                1.0
            } else {
                (k - degree) as f64 / spans as f64
            }
        })
        .collect()
}

/// The knot span index `k` with `knots[k] <= u < knots[k + 1]` and
/// `degree <= k < count` (Piegl & Tiller A2.1, `FindSpan`, binary search).
///
/// `u` at or beyond the domain end `knots[count]` returns the last non-empty
/// span, so that the surface is evaluated up to and including its end;
/// `u` at or below `knots[degree]` returns the first non-empty span.
/// Requires a valid knot vector with a non-empty domain (as checked by
/// [`BSplineSurface`](super::BSplineSurface)); `u` must not be NaN.
pub fn find_span(knots: &[f64], degree: usize, count: usize, u: f64) -> usize {
    let p = degree;
    let n = count;
    if u >= knots[n] {
        let mut k = n - 1;
        while k > p && knots[k] >= knots[n] {
            k -= 1;
        }
        return k;
    }
    // Invariant: knots[low] <= u < knots[high].
    let mut low = p;
    let mut high = n;
    if u < knots[low] {
        // Below the domain start: use the first non-empty span.
        while knots[low + 1] <= knots[p] {
            low += 1;
        }
        return low;
    }
    while high - low > 1 {
        let mid = (low + high) / 2;
        if u < knots[mid] {
            high = mid;
        } else {
            low = mid;
        }
    }
    low
}

/// The `degree + 1` non-zero basis functions `N_{span-degree..=span, degree}(u)`
/// written to `out[0..=degree]` (Piegl & Tiller A2.2, `BasisFuns`).
///
/// `span` must come from [`find_span`]; `degree <= MAX_DEGREE`.
pub fn basis_funs(span: usize, u: f64, degree: usize, knots: &[f64], out: &mut [f64; MAX_ORDER]) {
    let p = degree;
    let mut left = [0.0; MAX_ORDER];
    let mut right = [0.0; MAX_ORDER];
    out[0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = out[r] / (right[r + 1] + left[j - r]);
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
}

/// The non-zero basis functions and their derivatives up to order `n <= 2`
/// (Piegl & Tiller A2.3, `DersBasisFuns`): `ders[k][r]` is the k-th derivative
/// of `N_{span-degree+r, degree}(u)`. Rows `k > min(n, degree)` are set to 0.
///
/// `span` must come from [`find_span`]; `degree <= MAX_DEGREE`.
pub fn ders_basis_funs(
    span: usize,
    u: f64,
    degree: usize,
    n: usize,
    knots: &[f64],
    ders: &mut BasisDerivs,
) {
    let p = degree;
    let n = n.min(2).min(p);
    // ndu[j][r] (r <= j): knot differences; ndu[r][j] (r <= j): basis values.
    let mut ndu = [[0.0f64; MAX_ORDER]; MAX_ORDER];
    let mut left = [0.0f64; MAX_ORDER];
    let mut right = [0.0f64; MAX_ORDER];
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for row in ders.iter_mut() {
        row[..=p].fill(0.0);
    }
    for j in 0..=p {
        ders[0][j] = ndu[j][p];
    }
    let pi = p as isize;
    let mut a = [[0.0f64; MAX_ORDER]; 2];
    for r in 0..=pi {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=n as isize {
            let mut d = 0.0;
            let rk = r - k;
            let pk = pi - k;
            let pk1 = (pk + 1) as usize;
            if r >= k {
                a[s2][0] = a[s1][0] / ndu[pk1][rk as usize];
                d = a[s2][0] * ndu[rk as usize][pk as usize];
            }
            let j1 = if rk >= -1 { 1 } else { -rk };
            let j2 = if r - 1 <= pk { k - 1 } else { pi - r };
            for j in j1..=j2 {
                let ju = j as usize;
                let idx = (rk + j) as usize;
                a[s2][ju] = (a[s1][ju] - a[s1][ju - 1]) / ndu[pk1][idx];
                d += a[s2][ju] * ndu[idx][pk as usize];
            }
            if r <= pk {
                let ku = k as usize;
                a[s2][ku] = -a[s1][ku - 1] / ndu[pk1][r as usize];
                d += a[s2][ku] * ndu[r as usize][pk as usize];
            }
            ders[k as usize][r as usize] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut factor = p as f64;
    for k in 1..=n {
        for v in ders[k][..=p].iter_mut() {
            *v *= factor;
        }
        factor *= (p - k) as f64;
    }
}

/// Derivative of the degree-`d` basis functions on knot span `span`, in
/// place: on entry `x[r'] = X_{span-d+1+r', d-1}` (values or derivatives of
/// the degree `d - 1` functions, `d` entries), on exit `x[r]` is the
/// derivative of `N_{span-d+r, d}` (`d + 1` entries), by Piegl & Tiller
/// Eq. (2.9):
/// `N'_{i,d} = d (N_{i,d-1} / (u_{i+d} - u_i) - N_{i+1,d-1} / (u_{i+d+1} - u_{i+1}))`.
/// Every denominator used spans the non-empty knot span, so none is zero.
#[inline(always)]
fn differentiate(span: usize, d: usize, knots: &[f64], x: &mut [f64; MAX_ORDER]) {
    let df = d as f64;
    // prev = x[r-1] / (u_{span+r} - u_{span-d+r}), the first term of N'_{span-d+r}.
    let mut prev = 0.0;
    for r in 0..d {
        let t = x[r] / (knots[span + r + 1] - knots[span + r + 1 - d]);
        x[r] = df * (prev - t);
        prev = t;
    }
    x[d] = df * prev;
}

/// The non-zero basis functions and their first and second derivatives,
/// like [`ders_basis_funs`] with `n = 2` (same output layout, rows beyond the
/// degree zero), but cheaper and with no scratch buffers: the triangular
/// table of A2.2 is run once, keeping its degree `p-1` and `p-2` rows in
/// `ders[1]` and `ders[2]`, and the derivatives follow from the derivative
/// formula Eq. (2.9) applied in place once and twice — the same quantities
/// A2.3 computes through its `a[k][j]` coefficients. This is the evaluation
/// hot path; it is cross-checked against A2.3 in the tests.
pub fn basis_funs_ders2(span: usize, u: f64, degree: usize, knots: &[f64], ders: &mut BasisDerivs) {
    let p = degree;
    let [n, d1, d2] = ders;
    n[0] = 1.0;
    if p == 1 {
        d1[0] = 1.0;
    } else if p == 2 {
        d2[0] = 1.0;
    }
    for j in 1..=p {
        // left[k] = u - knots[span + 1 - k], right[k] = knots[span + k] - u.
        let mut saved = 0.0;
        for r in 0..j {
            let right = knots[span + r + 1] - u;
            let left = u - knots[span + 1 + r - j];
            let temp = n[r] / (right + left);
            n[r] = saved + right * temp;
            saved = left * temp;
        }
        n[j] = saved;
        if j + 2 == p {
            d2[..=j].copy_from_slice(&n[..=j]);
        } else if j + 1 == p {
            d1[..=j].copy_from_slice(&n[..=j]);
        }
    }
    if p >= 2 {
        // Derivatives of the degree p-1 functions, then of degree p.
        differentiate(span, p - 1, knots, d2);
        differentiate(span, p, knots, d2);
    } else {
        d2[..=p].fill(0.0);
    }
    differentiate(span, p, knots, d1);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cox–de Boor recursion, the definition (Piegl & Tiller Eq. 2.5).
    fn cox_de_boor(i: usize, p: usize, knots: &[f64], u: f64) -> f64 {
        if p == 0 {
            return if knots[i] <= u && u < knots[i + 1] {
                1.0
            } else {
                0.0
            };
        }
        let mut v = 0.0;
        let d1 = knots[i + p] - knots[i];
        if d1 > 0.0 {
            v += (u - knots[i]) / d1 * cox_de_boor(i, p - 1, knots, u);
        }
        let d2 = knots[i + p + 1] - knots[i + 1];
        if d2 > 0.0 {
            v += (knots[i + p + 1] - u) / d2 * cox_de_boor(i + 1, p - 1, knots, u);
        }
        v
    }

    #[test]
    fn bspline_find_span_handles_ends_and_repeated_knots() {
        let knots = [0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 3.0, 4.0, 4.0, 4.0];
        let (p, n) = (2, 7);
        assert_eq!(find_span(&knots, p, n, 0.0), 2);
        assert_eq!(find_span(&knots, p, n, 0.5), 2);
        assert_eq!(find_span(&knots, p, n, 1.0), 3);
        assert_eq!(find_span(&knots, p, n, 2.0), 5);
        assert_eq!(find_span(&knots, p, n, 3.999), 6);
        assert_eq!(find_span(&knots, p, n, 4.0), 6);
        assert_eq!(find_span(&knots, p, n, 5.0), 6);
        // Unclamped with a repeated knot at the domain start.
        let knots = [0.0, 1.0, 1.0, 1.0, 2.0, 3.0, 4.0];
        assert_eq!(find_span(&knots, 2, 4, 1.0), 3);
        assert_eq!(find_span(&knots, 2, 4, 0.5), 3);
        assert_eq!(find_span(&knots, 2, 4, 2.0), 3);
    }

    #[test]
    fn bspline_basis_matches_cox_de_boor_and_partition_of_unity() {
        let knots = [0.0, 0.0, 0.0, 0.0, 0.3, 0.5, 0.5, 0.8, 1.0, 1.0, 1.0, 1.0];
        let (p, n) = (3, 8);
        for step in 0..200 {
            let u = step as f64 / 200.0;
            let span = find_span(&knots, p, n, u);
            let mut out = [0.0; MAX_ORDER];
            basis_funs(span, u, p, &knots, &mut out);
            let mut ders = [[0.0; MAX_ORDER]; 3];
            ders_basis_funs(span, u, p, 2, &knots, &mut ders);
            let mut fast = [[0.0; MAX_ORDER]; 3];
            basis_funs_ders2(span, u, p, &knots, &mut fast);
            for k in 0..3 {
                for r in 0..=p {
                    let scale = 1.0 + ders[k][r].abs();
                    assert!((fast[k][r] - ders[k][r]).abs() < 1e-12 * scale, "{k} {r}");
                }
            }
            let sum: f64 = out[..=p].iter().sum();
            assert!((sum - 1.0).abs() < 1e-14);
            let dsum: f64 = ders[1][..=p].iter().sum();
            assert!(dsum.abs() < 1e-12);
            for r in 0..=p {
                let reference = cox_de_boor(span - p + r, p, &knots, u);
                assert!((out[r] - reference).abs() < 1e-14);
                assert!((ders[0][r] - reference).abs() < 1e-14);
                // Derivatives against central differences inside the span.
                let h = 1e-6;
                if u - h > knots[span] && u + h < knots[span + 1] {
                    let f = |x: f64| cox_de_boor(span - p + r, p, &knots, x);
                    let d1 = (f(u + h) - f(u - h)) / (2.0 * h);
                    let d2 = (f(u + h) - 2.0 * f(u) + f(u - h)) / (h * h);
                    assert!((ders[1][r] - d1).abs() < 1e-6, "{} vs {}", ders[1][r], d1);
                    assert!((ders[2][r] - d2).abs() < 1e-2, "{} vs {}", ders[2][r], d2);
                }
            }
        }
    }

    #[test]
    fn bspline_fast_derivatives_match_a2_3_for_all_degrees() {
        let mut x = 0.123_f64;
        let mut next = || {
            x = (x * 7919.0 + 0.31).fract();
            x
        };
        for p in 1..=MAX_DEGREE {
            let count = p + 4;
            let mut knots = vec![0.0; p + 1];
            let mut t = 0.0;
            for k in 0..count - p - 1 {
                // A double knot in the middle, random spacing elsewhere.
                if k != 1 {
                    t += 0.2 + next();
                }
                knots.push(t);
            }
            let end = t + 0.5;
            knots.extend(std::iter::repeat_n(end, p + 1));
            for step in 0..=50 {
                let u = end * step as f64 / 50.0;
                let span = find_span(&knots, p, count, u);
                let mut a = [[0.0; MAX_ORDER]; 3];
                let mut b = [[0.0; MAX_ORDER]; 3];
                ders_basis_funs(span, u, p, 2, &knots, &mut a);
                basis_funs_ders2(span, u, p, &knots, &mut b);
                for k in 0..3 {
                    let scale = a[k][..=p].iter().fold(1.0f64, |m, v| m.max(v.abs()));
                    for r in 0..=p {
                        assert!(
                            (a[k][r] - b[k][r]).abs() <= 1e-11 * scale,
                            "p {p} k {k} r {r}: {} vs {}",
                            a[k][r],
                            b[k][r]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn bspline_linear_basis_has_zero_second_derivative() {
        let knots = [0.0, 0.0, 0.5, 1.0, 1.0];
        let span = find_span(&knots, 1, 3, 0.25);
        let mut ders = [[7.0; MAX_ORDER]; 3];
        ders_basis_funs(span, 0.25, 1, 2, &knots, &mut ders);
        assert_eq!(&ders[0][..2], &[0.5, 0.5]);
        assert_eq!(&ders[1][..2], &[-2.0, 2.0]);
        assert_eq!(&ders[2][..2], &[0.0, 0.0]);
        let mut fast = [[7.0; MAX_ORDER]; 3];
        basis_funs_ders2(span, 0.25, 1, &knots, &mut fast);
        assert_eq!(&fast[0][..2], &[0.5, 0.5]);
        assert_eq!(&fast[1][..2], &[-2.0, 2.0]);
        assert_eq!(&fast[2][..2], &[0.0, 0.0]);
    }
}
