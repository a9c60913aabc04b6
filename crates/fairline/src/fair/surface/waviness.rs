//! How wavy a planar polyline is: the measures by which fairing of B-spline
//! surfaces is judged to keep the highlight lines it does not target fair.
//! They work on the (u, v) pre-images of highlight
//! lines, which are planar curves, so curvature has a sign and inflections
//! are defined.
//!
//! Contoured polylines have a vertex on every grid edge they cross; their
//! discrete curvature at that resolution is dominated by the contouring
//! error. Every measure therefore first resamples the polyline at a uniform
//! arc-length `spacing` chosen by the caller (a few grid cells).

/// Waviness of one planar polyline, resampled at a uniform arc-length
/// spacing h: signed curvature κ_k = 2 sin(φ_k / 2) / h at each interior
/// sample (φ_k the turning angle, the curvature of the circle through the
/// three samples when they are h apart), and its variation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Waviness {
    /// Length of the polyline (units of its coordinates).
    pub length: f64,
    /// Total variation of the curvature Σ |κ_{k+1} − κ_k| (1 / length
    /// units): a straight line and a circle have 0, each wiggle adds twice
    /// its curvature amplitude.
    pub curvature_variation: f64,
    /// Largest |κ| (1 / length units).
    pub max_curvature: f64,
    /// Sign changes of κ among the samples with |κ| above the caller's
    /// threshold (samples below it are skipped, so contouring noise on a
    /// nearly straight stretch does not count).
    pub inflections: usize,
    /// Pairs of non-adjacent segments that cross (a line that crosses
    /// itself makes a loop).
    pub self_crossings: usize,
}

/// Points at arc-length spacing ≈ `spacing` along the polyline (first and
/// last point kept on open lines; the spacing is adjusted so that the
/// length is a whole number of steps). Closed lines are treated as
/// returning to their first point, which is not repeated.
pub fn resample_polyline(points: &[[f64; 2]], closed: bool, spacing: f64) -> Vec<[f64; 2]> {
    let n = points.len();
    if n < 2 || !(spacing > 0.0 && spacing.is_finite()) {
        return points.to_vec();
    }
    let segs = if closed { n } else { n - 1 };
    let mut cum = Vec::with_capacity(segs + 1);
    cum.push(0.0);
    for k in 0..segs {
        let (a, b) = (points[k], points[(k + 1) % n]);
        cum.push(cum[k] + (b[0] - a[0]).hypot(b[1] - a[1]));
    }
    let len = cum[segs];
    if !(len > 0.0 && len.is_finite()) {
        return points[..1].to_vec();
    }
    let steps = ((len / spacing).round() as usize).clamp(1, 10_000_000);
    let h = len / steps as f64;
    let count = if closed { steps } else { steps + 1 };
    let mut out = Vec::with_capacity(count);
    let mut seg = 0;
    for m in 0..count {
        let s = (m as f64 * h).min(len);
        while seg + 1 < segs && cum[seg + 1] < s {
            seg += 1;
        }
        let (a, b) = (points[seg], points[(seg + 1) % n]);
        let d = cum[seg + 1] - cum[seg];
        let t = if d > 0.0 {
            ((s - cum[seg]) / d).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
    }
    out
}

/// Signed discrete curvature at the interior samples of a uniformly
/// resampled polyline (all of them on closed lines): 2 sin(φ/2) / h with φ
/// the signed turning angle (counter-clockwise positive) and h the mean of
/// the two adjacent segment lengths. Segments of zero length give 0.
pub fn discrete_curvature(samples: &[[f64; 2]], closed: bool) -> Vec<f64> {
    let n = samples.len();
    if n < 3 {
        return Vec::new();
    }
    let range: Box<dyn Iterator<Item = usize>> = if closed {
        Box::new(0..n)
    } else {
        Box::new(1..n - 1)
    };
    range
        .map(|k| {
            let a = samples[(k + n - 1) % n];
            let b = samples[k];
            let c = samples[(k + 1) % n];
            let e1 = [b[0] - a[0], b[1] - a[1]];
            let e2 = [c[0] - b[0], c[1] - b[1]];
            let (l1, l2) = (e1[0].hypot(e1[1]), e2[0].hypot(e2[1]));
            let h = 0.5 * (l1 + l2);
            if !(l1 > 0.0 && l2 > 0.0 && h > 0.0) {
                return 0.0;
            }
            let cross = e1[0] * e2[1] - e1[1] * e2[0];
            let dot = e1[0] * e2[0] + e1[1] * e2[1];
            let phi = cross.atan2(dot);
            let k = 2.0 * (0.5 * phi).sin() / h;
            if k.is_finite() { k } else { 0.0 }
        })
        .collect()
}

/// Number of pairs of non-adjacent segments of the polyline that properly
/// cross (O(n²) on the given points: pass a resampled line).
pub fn self_crossings(points: &[[f64; 2]], closed: bool) -> usize {
    let n = points.len();
    if n < 4 {
        return 0;
    }
    let segs = if closed { n } else { n - 1 };
    let seg = |k: usize| (points[k], points[(k + 1) % n]);
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let mut count = 0;
    for i in 0..segs {
        let (a, b) = seg(i);
        for j in i + 2..segs {
            if closed && i == 0 && j == segs - 1 {
                continue; // adjacent through the closing point
            }
            let (c, d) = seg(j);
            let (o1, o2) = (orient(a, b, c), orient(a, b, d));
            let (o3, o4) = (orient(c, d, a), orient(c, d, b));
            if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
                count += 1;
            }
        }
    }
    count
}

/// The [`Waviness`] of a planar polyline resampled at arc-length `spacing`;
/// inflections count sign changes of κ among samples with
/// |κ| ≥ `inflection_threshold`.
pub fn polyline_waviness(
    points: &[[f64; 2]],
    closed: bool,
    spacing: f64,
    inflection_threshold: f64,
) -> Waviness {
    let r = resample_polyline(points, closed, spacing);
    let length = {
        let n = points.len();
        let segs = if closed { n } else { n.saturating_sub(1) };
        (0..segs)
            .map(|k| {
                let (a, b) = (points[k], points[(k + 1) % n]);
                (b[0] - a[0]).hypot(b[1] - a[1])
            })
            .sum()
    };
    let kappa = discrete_curvature(&r, closed);
    let m = kappa.len();
    let mut tv = 0.0;
    let pairs = if closed { m } else { m.saturating_sub(1) };
    for k in 0..pairs {
        tv += (kappa[(k + 1) % m] - kappa[k]).abs();
    }
    let max_curvature = kappa.iter().fold(0.0f64, |a, k| a.max(k.abs()));
    let significant: Vec<f64> = kappa
        .iter()
        .copied()
        .filter(|k| k.abs() >= inflection_threshold)
        .collect();
    let mut inflections = significant
        .windows(2)
        .filter(|w| (w[0] > 0.0) != (w[1] > 0.0))
        .count();
    if closed && significant.len() >= 2 {
        let (first, last) = (significant[0], significant[significant.len() - 1]);
        if (first > 0.0) != (last > 0.0) {
            inflections += 1;
        }
    }
    Waviness {
        length,
        curvature_variation: tv,
        max_curvature,
        inflections,
        self_crossings: self_crossings(&r, closed),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn circle(r: f64, n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let t = 2.0 * PI * k as f64 / n as f64;
                [r * t.cos(), r * t.sin()]
            })
            .collect()
    }

    #[test]
    fn waviness_of_a_circle_is_its_constant_curvature() {
        let w = polyline_waviness(&circle(0.5, 20_000), true, 0.01, 0.1);
        assert!((w.length - PI).abs() < 1e-5, "{}", w.length);
        assert!((w.max_curvature - 2.0).abs() < 1e-3, "{}", w.max_curvature);
        // The resampled points lie on the 20 000-gon's chords (sagitta
        // 6e-9): 2 sagitta / h² = 1.2e-4 of curvature noise per sample,
        // summed over 314 samples.
        assert!(w.curvature_variation < 0.05, "{}", w.curvature_variation);
        assert_eq!(w.inflections, 0);
        assert_eq!(w.self_crossings, 0);
    }

    #[test]
    fn waviness_of_a_sine_counts_its_inflections_and_variation() {
        // y = a sin(x) on [0, 4π]: curvature −a sin x / (1 + a² cos² x)^1.5,
        // 3 interior zeros with a sign change; TV = Σ |κ| swings = 8 a for
        // the four half-waves peaking at |κ| = a (at x = π/2 + kπ) and
        // starting / ending at 0.
        let a = 0.2;
        let pts: Vec<[f64; 2]> = (0..=20_000)
            .map(|k| {
                let x = 4.0 * PI * k as f64 / 20_000.0;
                [x, a * x.sin()]
            })
            .collect();
        let w = polyline_waviness(&pts, false, 0.005, 0.01);
        assert_eq!(w.inflections, 3);
        assert!((w.max_curvature - a).abs() < 1e-3, "{}", w.max_curvature);
        assert!(
            (w.curvature_variation - 8.0 * a).abs() < 0.01,
            "{}",
            w.curvature_variation
        );
        // A straight line: nothing.
        let line: Vec<[f64; 2]> = (0..100).map(|k| [k as f64 * 0.01, 0.3]).collect();
        let w = polyline_waviness(&line, false, 0.02, 1e-6);
        assert_eq!(w.inflections, 0);
        assert!(w.curvature_variation < 1e-9);
    }

    #[test]
    fn waviness_finds_a_loop() {
        // A curve that crosses itself once (a limaçon with an inner loop
        // r = 0.5 + cos t crosses itself at the pole once).
        let pts: Vec<[f64; 2]> = (0..4000)
            .map(|k| {
                let t = 2.0 * PI * k as f64 / 4000.0;
                let r = 0.5 + t.cos();
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        let w = polyline_waviness(&pts, true, 0.01, 0.1);
        assert_eq!(w.self_crossings, 1);
        assert_eq!(
            polyline_waviness(&circle(1.0, 500), true, 0.01, 0.1).self_crossings,
            0
        );
    }

    #[test]
    fn waviness_survives_degenerate_input() {
        assert_eq!(polyline_waviness(&[], false, 0.1, 0.1), Waviness::default());
        let w = polyline_waviness(&[[0.0, 0.0]; 5], true, 0.1, 0.1);
        assert_eq!(w.curvature_variation, 0.0);
        let w = polyline_waviness(&[[0.0, 0.0], [1.0, 0.0]], false, 0.0, 0.1);
        assert!(w.length == 1.0 && w.curvature_variation == 0.0);
    }
}
