//! Real roots of polynomials of degree ≤ 4, used for the quartic of
//! Nishiyama et al. Eq. (2.15)–(2.16).
//!
//! Method: root isolation by critical points. The real roots of p' (found
//! recursively down to the closed-form quadratic) split the real line into
//! intervals on which p is monotone; each interval whose end values differ
//! in sign holds exactly one root, found by safeguarded Newton–bisection to
//! full precision. A critical point where |p| is within rounding of zero is
//! a (near-)double root. Every root is finally polished by Newton steps on
//! the original polynomial (kept only when they reduce |p|). Unlike Ferrari's
//! closed form this loses no accuracy on near-double roots or on
//! coefficients of very different magnitude.

/// Relative size below which a leading coefficient counts as zero (the
/// degree drops: quartic → cubic → quadratic → linear).
const LEADING_TOLERANCE: f64 = 1e-14;

/// Horner evaluation of p(x) = Σ c[i] x^i and of the bound Σ |c[i]| |x|^i
/// on its rounding error.
#[inline]
fn eval(c: &[f64], x: f64) -> (f64, f64) {
    let mut p = 0.0;
    let mut m = 0.0;
    let ax = x.abs();
    for &ci in c.iter().rev() {
        p = p * x + ci;
        m = m * ax + ci.abs();
    }
    (p, m)
}

#[inline]
fn eval_d(c: &[f64], x: f64) -> (f64, f64) {
    let mut p = 0.0;
    let mut d = 0.0;
    for &ci in c.iter().rev() {
        d = d * x + p;
        p = p * x + ci;
    }
    (p, d)
}

/// All distinct real roots of the quartic c4 x⁴ + c3 x³ + c2 x² + c1 x + c0,
/// ascending (Nishiyama et al. Eq. (2.15)). A vanishing leading coefficient
/// lowers the degree; the zero polynomial and non-finite coefficients give
/// no roots. A double root is reported once.
pub fn quartic_roots(c4: f64, c3: f64, c2: f64, c1: f64, c0: f64) -> Vec<f64> {
    real_roots(&[c0, c1, c2, c3, c4])
}

/// All distinct real roots of p(x) = Σ coeffs[i] xⁱ (ascending order of
/// powers, any degree; meant for degree ≤ 4), sorted ascending. Leading
/// coefficients below 1e-14 of the largest coefficient are dropped (their
/// roots would lie beyond 1e14 relative to the others). The zero polynomial
/// and non-finite coefficients give no roots.
pub fn real_roots(coeffs: &[f64]) -> Vec<f64> {
    if coeffs.iter().any(|c| !c.is_finite()) {
        return Vec::new();
    }
    let scale = coeffs.iter().fold(0.0f64, |a, c| a.max(c.abs()));
    if !(scale > 0.0) {
        return Vec::new();
    }
    let c: Vec<f64> = coeffs.iter().map(|x| x / scale).collect();
    let mut deg = c.len() - 1;
    // Drop a leading coefficient that is zero, or so small that the root it
    // adds (about −c[deg−1]/c[deg]) lies beyond 1e14 times the size of the
    // other roots (Fujiwara bound of the reduced polynomial).
    while deg > 0 {
        if c[deg] == 0.0 {
            deg -= 1;
            continue;
        }
        if deg >= 2 && c[deg - 1] != 0.0 {
            let rest = fujiwara(&c[..deg]);
            if (c[deg] * rest).abs() <= LEADING_TOLERANCE * c[deg - 1].abs() {
                deg -= 1;
                continue;
            }
        }
        break;
    }
    let c = &c[..=deg];
    let mut roots = roots_normalised(c);
    // Newton polish on the (normalised) polynomial.
    for r in roots.iter_mut() {
        for _ in 0..3 {
            let (p, d) = eval_d(c, *r);
            if p == 0.0 || d == 0.0 || !d.is_finite() {
                break;
            }
            let x = *r - p / d;
            if x.is_finite() && eval(c, x).0.abs() < p.abs() {
                *r = x;
            } else {
                break;
            }
        }
    }
    roots.sort_by(f64::total_cmp);
    roots.dedup_by(|a, b| (*a - *b).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()));
    roots
}

/// Roots of a polynomial whose leading coefficient is non-zero.
fn roots_normalised(c: &[f64]) -> Vec<f64> {
    let deg = c.len() - 1;
    match deg {
        0 => Vec::new(),
        1 => {
            let x = -c[0] / c[1];
            if x.is_finite() { vec![x] } else { Vec::new() }
        }
        2 => quadratic(c[2], c[1], c[0]),
        _ => {
            // critical points: roots of p'
            let dc: Vec<f64> = (1..=deg).map(|i| i as f64 * c[i]).collect();
            let mut crit = roots_normalised(&dc);
            crit.sort_by(f64::total_cmp);
            let bound = 1.01 * fujiwara(c);
            if !(bound > 0.0) || !bound.is_finite() {
                // p = c_n xⁿ (all lower coefficients zero): the root 0
                return vec![0.0];
            }
            let mut pts = Vec::with_capacity(crit.len() + 2);
            pts.push(-bound);
            pts.extend(crit.iter().copied().filter(|x| x.abs() < bound));
            pts.push(bound);
            let mut roots = Vec::new();
            for w in pts.windows(2) {
                let (a, b) = (w[0], w[1]);
                if !(b > a) {
                    continue;
                }
                let (pa, _) = eval(c, a);
                let (pb, _) = eval(c, b);
                if pa == 0.0 {
                    roots.push(a);
                }
                if pa * pb < 0.0 {
                    roots.push(bracketed(c, a, b, pa));
                }
            }
            if let Some(&last) = pts.last()
                && eval(c, last).0 == 0.0
            {
                roots.push(last);
            }
            // (near-)double roots: critical points where p is within rounding of 0
            for &x in &crit {
                let (p, m) = eval(c, x);
                if p.abs() <= 64.0 * f64::EPSILON * m {
                    roots.push(x);
                }
            }
            roots
        }
    }
}

/// Fujiwara's bound on the moduli of the roots of Σ c[i] xⁱ (c[n] ≠ 0):
/// 2·max_k |c[n−k]/c[n]|^(1/k) (the constant term's share halved).
fn fujiwara(c: &[f64]) -> f64 {
    let n = c.len() - 1;
    let lead = c[n];
    let mut b = 0.0f64;
    for k in 1..=n {
        let mut r = (c[n - k] / lead).abs();
        if k == n {
            r *= 0.5;
        }
        b = b.max(r.powf(1.0 / k as f64));
    }
    2.0 * b
}

/// Numerically stable quadratic formula; a discriminant within rounding of
/// zero gives the double root.
fn quadratic(a: f64, b: f64, c: f64) -> Vec<f64> {
    let disc = b * b - 4.0 * a * c;
    let tol = 8.0 * f64::EPSILON * (b * b + (4.0 * a * c).abs());
    if disc < -tol {
        return Vec::new();
    }
    if disc.abs() <= tol {
        let x = -b / (2.0 * a);
        return if x.is_finite() { vec![x] } else { Vec::new() };
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let mut out = Vec::with_capacity(2);
    let x1 = q / a;
    if x1.is_finite() {
        out.push(x1);
    }
    if q != 0.0 {
        let x2 = c / q;
        if x2.is_finite() {
            out.push(x2);
        }
    }
    out
}

/// The single root of a monotone p on [a, b] with p(a)·p(b) < 0:
/// Newton steps kept inside the shrinking bracket, bisection otherwise.
fn bracketed(c: &[f64], mut a: f64, mut b: f64, pa: f64) -> f64 {
    let sa = pa.signum();
    let mut x = 0.5 * (a + b);
    for _ in 0..200 {
        let (p, d) = eval_d(c, x);
        if p == 0.0 {
            return x;
        }
        if p.signum() == sa {
            a = x;
        } else {
            b = x;
        }
        let newton = x - p / d;
        let next = if newton > a && newton < b && newton.is_finite() {
            newton
        } else {
            0.5 * (a + b)
        };
        if next == x || b - a <= 2.0 * f64::EPSILON * a.abs().max(b.abs()) {
            return next;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Coefficients (ascending) of lead·Π (x − r).
    fn from_roots(lead: f64, roots: &[f64]) -> Vec<f64> {
        let mut c = vec![lead];
        for &r in roots {
            let mut n = vec![0.0; c.len() + 1];
            for (i, &ci) in c.iter().enumerate() {
                n[i + 1] += ci;
                n[i] -= r * ci;
            }
            c = n;
        }
        c
    }

    fn assert_roots(got: &[f64], want: &[f64], tol: f64) {
        assert_eq!(got.len(), want.len(), "got {got:?}, want {want:?}");
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g - w).abs() <= tol * (1.0 + w.abs()),
                "got {got:?}, want {want:?}"
            );
        }
    }

    #[test]
    fn simple_quartic_roots() {
        let c = from_roots(2.0, &[-3.0, -0.5, 1.0, 7.0]);
        assert_roots(&real_roots(&c), &[-3.0, -0.5, 1.0, 7.0], 1e-13);
        let q = quartic_roots(c[4], c[3], c[2], c[1], c[0]);
        assert_roots(&q, &[-3.0, -0.5, 1.0, 7.0], 1e-13);
    }

    #[test]
    fn quartic_with_complex_pair() {
        // (x² + 1)(x − 2)(x + 5)
        let c = from_roots(1.0, &[2.0, -5.0]);
        let mut p = vec![0.0; 5];
        for (i, &ci) in c.iter().enumerate() {
            p[i] += ci;
            p[i + 2] += ci;
        }
        assert_roots(&real_roots(&p), &[-5.0, 2.0], 1e-13);
        // x⁴ + 1: no real root
        assert!(quartic_roots(1.0, 0.0, 0.0, 0.0, 1.0).is_empty());
    }

    #[test]
    fn near_double_and_double_roots() {
        let c = from_roots(1.0, &[1.0, 1.0 + 1e-6, 3.0, -2.0]);
        assert_roots(&real_roots(&c), &[-2.0, 1.0, 1.0 + 1e-6, 3.0], 1e-8);
        // the two close roots are separated
        let r = real_roots(&c);
        assert_eq!(r.len(), 4, "{r:?}");
        assert!((r[2] - r[1] - 1e-6).abs() < 1e-8, "{r:?}");
        assert!(real_roots(&c).iter().all(|&x| eval(&c, x).0.abs() < 1e-12));
        // exact double root reported once
        let c = from_roots(1.0, &[0.5, 0.5, -1.0, 4.0]);
        assert_roots(&real_roots(&c), &[-1.0, 0.5, 4.0], 1e-7);
        // two double roots
        let c = from_roots(3.0, &[2.0, 2.0, -1.0, -1.0]);
        assert_roots(&real_roots(&c), &[-1.0, 2.0], 1e-7);
        // quadruple root
        let c = from_roots(1.0, &[1.5, 1.5, 1.5, 1.5]);
        let r = real_roots(&c);
        assert!(
            !r.is_empty() && r.iter().all(|x| (x - 1.5).abs() < 1e-3),
            "{r:?}"
        );
    }

    #[test]
    fn degree_drops() {
        // cubic (leading 0)
        let c = from_roots(1.0, &[-1.0, 0.25, 2.0]);
        assert_roots(
            &quartic_roots(0.0, c[3], c[2], c[1], c[0]),
            &[-1.0, 0.25, 2.0],
            1e-13,
        );
        // quadratic, linear, constant, zero
        assert_roots(&quartic_roots(0.0, 0.0, 1.0, -3.0, 2.0), &[1.0, 2.0], 1e-14);
        assert_roots(&quartic_roots(0.0, 0.0, 0.0, 2.0, -1.0), &[0.5], 1e-15);
        assert!(quartic_roots(0.0, 0.0, 0.0, 0.0, 3.0).is_empty());
        assert!(quartic_roots(0.0, 0.0, 0.0, 0.0, 0.0).is_empty());
        assert!(quartic_roots(f64::NAN, 1.0, 0.0, 0.0, 0.0).is_empty());
        // tiny leading coefficient: the huge root is dropped, the rest kept
        assert_roots(
            &quartic_roots(1e-20, 0.0, 1.0, -3.0, 2.0),
            &[1.0, 2.0],
            1e-12,
        );
    }

    #[test]
    fn wide_coefficient_ranges() {
        for &s in &[1e-6, 1e-3, 1.0, 1e3, 1e6] {
            let roots = [-2.0 * s, -1e-3 * s, 0.7 * s, 5.0 * s];
            let c = from_roots(0.3, &roots);
            assert_roots(&real_roots(&c), &roots, 1e-9);
        }
        // roots of very different magnitude
        let roots = [-1e4, 1e-4, 1.0, 1e3];
        assert_roots(&real_roots(&from_roots(1.0, &roots)), &roots, 1e-9);
    }

    #[test]
    fn random_quartics_roundtrip() {
        // deterministic pseudo-random roots; residuals stay at rounding level
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
        };
        for _ in 0..500 {
            let mut r = [rnd(), rnd(), rnd(), rnd()];
            r.sort_by(f64::total_cmp);
            if r.windows(2).any(|w| w[1] - w[0] < 1e-3) {
                continue;
            }
            let c = from_roots(rnd(), &r);
            if c[4].abs() < 1e-3 {
                continue;
            }
            assert_roots(&real_roots(&c), &r, 1e-8);
        }
    }
}
#[cfg(test)]
mod scratch {
    use super::*;
    fn from_roots(lead: f64, roots: &[f64]) -> Vec<f64> {
        let mut c = vec![lead];
        for &r in roots {
            let mut n = vec![0.0; c.len() + 1];
            for (i, &ci) in c.iter().enumerate() {
                n[i + 1] += ci;
                n[i] -= r * ci;
            }
            c = n;
        }
        c
    }
    #[test]
    fn scratch_near_double() {
        let mut fails = 0;
        for &s in &[1e-3, 1.0, 25.0, 1e3, 1e5] {
            for &gap in &[1e-2, 1e-4, 1e-6, 1e-7, 1e-8] {
                for &(o1, o2) in &[(3.0, -2.0), (1.2, -0.3), (50.0, 0.5)] {
                    let r = [s, s * (1.0 + gap), s * o1, s * o2];
                    let c = from_roots(0.7, &r);
                    let got = real_roots(&c);
                    if got.len() < 3 { fails += 1; println!("s={s} gap={gap} o=({o1},{o2}) got {got:?}"); }
                }
            }
        }
        println!("fails {fails}");
    }
}
