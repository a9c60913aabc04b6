//! Trimming loops of a B-spline surface: closed loops of 2-D (rational)
//! B-spline curves in the parameter domain `(u, v)` (IGES 144/142, STEP
//! ADVANCED_FACE bounds; DESIGN.md §3 "Trimming" and §5 `"trims"`).
//!
//! The first loop is the outer boundary, the others are holes. Loops are
//! flattened once, when they are attached to a surface, into closed
//! polylines whose chords deviate from the curves by at most
//! [`TRIM_FLATNESS`] × the diagonal of the surface's parameter domain
//! (adaptive bisection of every knot span, Piegl & Tiller A2.1/A2.2/A4.1 for
//! the curve points). Everything downstream — the point-in-face test, the
//! trimmed tessellation, highlight-line clipping — works on these polylines.
//!
//! Inside means: inside the outer loop and inside no hole. Each loop's
//! inside is decided by its winding number being non-zero, so the test does
//! not depend on the orientation a file gave its loops; the stored polylines
//! are nevertheless re-oriented (outer counter-clockwise, holes clockwise)
//! so that the trimmed region is always on their left.

use super::basis::{BasisDerivs, MAX_DEGREE, MAX_ORDER, basis_funs, ders_basis_funs, find_span};
use thiserror::Error;

/// Largest deviation of a flattened trim polyline from its curves, as a
/// fraction of the parameter-domain diagonal `|(u1 - u0, v1 - v0)|`.
pub const TRIM_FLATNESS: f64 = 1e-6;

/// Deepest bisection of one knot span while flattening (2^14 chords).
const MAX_BISECTION_DEPTH: u32 = 14;

/// Why a trim curve or loop is invalid; names the loop and curve.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TrimError {
    /// A curve is malformed.
    #[error("trim loop {loop_index} curve {curve}: {message}")]
    Curve {
        /// Loop index (0 = outer).
        loop_index: usize,
        /// Curve index within the loop.
        curve: usize,
        /// What is wrong.
        message: String,
    },
    /// A loop does not bound an area.
    #[error("trim loop {loop_index}: {message}")]
    Loop {
        /// Loop index (0 = outer).
        loop_index: usize,
        /// What is wrong.
        message: String,
    },
}

/// A 2-D (rational) B-spline curve in the parameter domain of a surface:
/// `c(t) = Σ N_{i,p}(t) w_i P_i / Σ N_{i,p}(t) w_i` (Piegl & Tiller Eq. 4.1),
/// `P_i = [u, v]`, parameter domain `[knots[p], knots[n]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimCurve {
    degree: usize,
    knots: Vec<f64>,
    points: Vec<[f64; 2]>,
    weights: Option<Vec<f64>>,
}

impl TrimCurve {
    /// Builds a curve; checks the degree (`1..=MAX_DEGREE`), at least
    /// `degree + 1` finite control points, `points + degree + 1` finite,
    /// non-decreasing knots with a non-empty domain, and finite positive
    /// weights (one per point). The error message says which check failed.
    pub fn new(
        degree: usize,
        knots: Vec<f64>,
        points: Vec<[f64; 2]>,
        weights: Option<Vec<f64>>,
    ) -> Result<Self, String> {
        if degree == 0 || degree > MAX_DEGREE {
            return Err(format!("degree {degree} is outside 1..={MAX_DEGREE}"));
        }
        let n = points.len();
        if n < degree + 1 {
            return Err(format!(
                "{n} control points; degree {degree} needs at least {}",
                degree + 1
            ));
        }
        if knots.len() != n + degree + 1 {
            return Err(format!(
                "{} knots; {n} control points of degree {degree} need {}",
                knots.len(),
                n + degree + 1
            ));
        }
        if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
            return Err(format!("knot {i} is not finite"));
        }
        if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(format!("knots decrease at index {i}"));
        }
        if knots[n] - knots[degree] <= 0.0 || !(knots[n] - knots[degree]).is_finite() {
            return Err("the parameter domain is empty".into());
        }
        if let Some(i) = points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(format!("control point {i} is not finite"));
        }
        if let Some(w) = &weights {
            if w.len() != n {
                return Err(format!("{} weights for {n} control points", w.len()));
            }
            if let Some(i) = w.iter().position(|&w| !(w.is_finite() && w > 0.0)) {
                return Err(format!("weight {i} is {}; weights must be positive", w[i]));
            }
        }
        Ok(Self {
            degree,
            knots,
            points,
            weights,
        })
    }

    /// The straight segment from `a` to `b` (degree 1, knots `[0,0,1,1]`).
    pub fn line(a: [f64; 2], b: [f64; 2]) -> Result<Self, String> {
        Self::new(1, vec![0.0, 0.0, 1.0, 1.0], vec![a, b], None)
    }

    /// Degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Knot vector.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Control points `[u, v]`.
    pub fn control_points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// Weights, `None` for a polynomial curve.
    pub fn weights(&self) -> Option<&[f64]> {
        self.weights.as_deref()
    }

    /// The same curve traversed backwards: `c̃(t) = c(a + b − t)` over the
    /// same knot range `[a, b]` (knots mirrored, control points and weights
    /// in reverse order). Fails only where mirroring the knots in floating
    /// point leaves the domain empty (a domain at the rounding level of the
    /// knots' magnitude).
    pub fn reversed(&self) -> Result<Self, String> {
        let (a, b) = (self.knots[0], self.knots[self.knots.len() - 1]);
        Self::new(
            self.degree,
            self.knots.iter().rev().map(|x| a + b - x).collect(),
            self.points.iter().rev().copied().collect(),
            self.weights
                .as_ref()
                .map(|w| w.iter().rev().copied().collect()),
        )
    }

    /// Parameter domain `[knots[p], knots[n]]`.
    pub fn domain(&self) -> [f64; 2] {
        [self.knots[self.degree], self.knots[self.points.len()]]
    }

    /// The curve point at `t` (clamped to the domain; NaN gives the start),
    /// Piegl & Tiller A4.1 (A3.1 when polynomial).
    pub fn eval(&self, t: f64) -> [f64; 2] {
        let [a, b] = self.domain();
        let t = if t >= a { t.min(b) } else { a };
        let p = self.degree;
        let span = find_span(&self.knots, p, self.points.len(), t);
        let mut nb = [0.0; MAX_ORDER];
        basis_funs(span, t, p, &self.knots, &mut nb);
        let (mut x, mut y, mut w) = (0.0, 0.0, 0.0);
        for (r, &b) in nb.iter().enumerate().take(p + 1) {
            let i = span - p + r;
            let wi = self.weights.as_ref().map_or(1.0, |ws| ws[i]);
            x += b * wi * self.points[i][0];
            y += b * wi * self.points[i][1];
            w += b * wi;
        }
        if w > 0.0 && w.is_finite() {
            [x / w, y / w]
        } else {
            self.points[span - p]
        }
    }

    /// The curve point and first derivative `dc/dt` at `t` (clamped to the
    /// domain), Piegl & Tiller A3.2 on the basis derivatives of A2.3, and
    /// for a rational curve the quotient rule of Eq. 4.8
    /// (`c' = (A' − w' c) / w`). At a knot the derivative is the one of the
    /// span to the left when `left` (the curve arriving there), else of the
    /// span to the right; at the domain ends, of the end spans.
    pub fn eval_d1(&self, t: f64, left: bool) -> ([f64; 2], [f64; 2]) {
        let (c, d1, _) = self.eval_d2(t, left);
        (c, d1)
    }

    /// The curve point and its first and second derivatives at `t`, as
    /// [`TrimCurve::eval_d1`] (the same span at a knot), the second by the
    /// quotient rule of Piegl & Tiller Eq. 4.8 differentiated once more:
    /// `c'' = (A'' − 2w'c' − w''c) / w`. Zero derivatives where the weight
    /// vanishes.
    pub fn eval_d2(&self, t: f64, left: bool) -> ([f64; 2], [f64; 2], [f64; 2]) {
        let [a, b] = self.domain();
        let t = if t >= a { t.min(b) } else { a };
        let p = self.degree;
        let n = self.points.len();
        let mut span = find_span(&self.knots, p, n, t);
        if left {
            while span > p && self.knots[span] >= t {
                span -= 1;
            }
        }
        let mut d: BasisDerivs = [[0.0; MAX_ORDER]; 3];
        ders_basis_funs(span, t, p, 2, &self.knots, &mut d);
        let (mut x, mut dx, mut ddx) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
        for r in 0..=p {
            let i = span - p + r;
            let wi = self.weights.as_ref().map_or(1.0, |ws| ws[i]);
            let h = [wi * self.points[i][0], wi * self.points[i][1], wi];
            for k in 0..3 {
                x[k] += d[0][r] * h[k];
                dx[k] += d[1][r] * h[k];
                ddx[k] += d[2][r] * h[k];
            }
        }
        if !(x[2] > 0.0 && x[2].is_finite()) {
            return (self.eval(t), [0.0, 0.0], [0.0, 0.0]);
        }
        let w = x[2];
        let c = [x[0] / w, x[1] / w];
        let dc = [(dx[0] - dx[2] * c[0]) / w, (dx[1] - dx[2] * c[1]) / w];
        let ddc = [
            (ddx[0] - 2.0 * dx[2] * dc[0] - ddx[2] * c[0]) / w,
            (ddx[1] - 2.0 * dx[2] * dc[1] - ddx[2] * c[1]) / w,
        ];
        (c, dc, ddc)
    }

    /// Appends the flattened curve to `out` without its last point: every
    /// non-empty knot span is cut into `2·degree + 2` chords, each bisected
    /// until its midpoint lies within `tolerance` of the chord (at most
    /// 2^14 pieces per span). Degree-1 spans are exact chords.
    pub fn flatten_into(&self, tolerance: f64, out: &mut Vec<[f64; 2]>) {
        let [a, b] = self.domain();
        let p = self.degree;
        let n = self.points.len();
        let linear = p == 1;
        for s in p..n {
            let (t0, t1) = (self.knots[s].max(a), self.knots[s + 1].min(b));
            if t1 <= t0 {
                continue;
            }
            let pieces = if linear { 1 } else { 2 * p + 2 };
            for k in 0..pieces {
                let ta = t0 + (t1 - t0) * (k as f64 / pieces as f64);
                let tb = if k + 1 == pieces {
                    t1
                } else {
                    t0 + (t1 - t0) * ((k + 1) as f64 / pieces as f64)
                };
                let pa = self.eval(ta);
                out.push(pa);
                if !linear {
                    self.bisect(ta, tb, pa, self.eval(tb), tolerance, 0, out);
                }
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn bisect(
        &self,
        ta: f64,
        tb: f64,
        pa: [f64; 2],
        pb: [f64; 2],
        tolerance: f64,
        depth: u32,
        out: &mut Vec<[f64; 2]>,
    ) {
        let tm = 0.5 * (ta + tb);
        let pm = self.eval(tm);
        let dev = distance_to_segment(pm, pa, pb);
        if dev <= tolerance || depth >= MAX_BISECTION_DEPTH {
            return;
        }
        self.bisect(ta, tm, pa, pm, tolerance, depth + 1, out);
        out.push(pm);
        self.bisect(tm, tb, pm, pb, tolerance, depth + 1, out);
    }
}

/// Distance from `p` to the segment `a b`.
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
    (ex * ex + ey * ey).sqrt()
}

/// One closed trimming loop: curves joined end to start (a gap between
/// consecutive curves is closed by a straight chord).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimLoop {
    /// The curves in order.
    pub curves: Vec<TrimCurve>,
}

impl TrimLoop {
    /// A loop of straight segments through `corners` (closed back to the first).
    pub fn polygon(corners: &[[f64; 2]]) -> Result<Self, String> {
        let n = corners.len();
        let curves = (0..n)
            .map(|k| TrimCurve::line(corners[k], corners[(k + 1) % n]))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { curves })
    }
}

/// Twice the signed area of a closed polygon (positive counter-clockwise).
pub fn polygon_signed_area2(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let mut s = 0.0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        s += a[0] * b[1] - a[1] * b[0];
    }
    s
}

/// Winding number of the closed polygon `poly` around `p` (Sunday's
/// crossing-with-orientation rule; points exactly on an edge count on the
/// side the half-open rule puts them).
pub fn winding_number(poly: &[[f64; 2]], p: [f64; 2]) -> i32 {
    let n = poly.len();
    let mut w = 0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        let is_left = (b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1]);
        if a[1] <= p[1] {
            if b[1] > p[1] && is_left > 0.0 {
                w += 1;
            }
        } else if b[1] <= p[1] && is_left < 0.0 {
            w -= 1;
        }
    }
    w
}

/// The trimmed parameter domain of a surface: its loops and their
/// flattened, re-oriented polylines.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimmedDomain {
    loops: Vec<TrimLoop>,
    polylines: Vec<Vec<[f64; 2]>>,
    tolerance: f64,
}

impl TrimmedDomain {
    /// Flattens `loops` for a surface with parameter domain
    /// `[u0, u1] × [v0, v1]` (polyline points are clamped into it).
    /// Fails when there are no loops or a loop encloses no area.
    pub fn new(
        loops: Vec<TrimLoop>,
        domain_u: [f64; 2],
        domain_v: [f64; 2],
    ) -> Result<Self, TrimError> {
        if loops.is_empty() {
            return Err(TrimError::Loop {
                loop_index: 0,
                message: "no trimming loop given".into(),
            });
        }
        let diag = (domain_u[1] - domain_u[0]).hypot(domain_v[1] - domain_v[0]);
        let tolerance = TRIM_FLATNESS * diag;
        let mut polylines = Vec::with_capacity(loops.len());
        for (l, lp) in loops.iter().enumerate() {
            if lp.curves.is_empty() {
                return Err(TrimError::Loop {
                    loop_index: l,
                    message: "the loop has no curves".into(),
                });
            }
            let mut pts: Vec<[f64; 2]> = Vec::new();
            let n = lp.curves.len();
            for (k, c) in lp.curves.iter().enumerate() {
                c.flatten_into(tolerance, &mut pts);
                // A gap to the next curve's start (a degenerate edge at a
                // pole that the file leaves out, or a seam's two sides)
                // keeps this curve's end, so that the chord across the gap
                // runs from end to start, as the loop's contract says.
                let end = c.eval(c.domain()[1]);
                let next = &lp.curves[(k + 1) % n];
                let start = next.eval(next.domain()[0]);
                if (end[0] - start[0]).hypot(end[1] - start[1]) > tolerance {
                    pts.push(end);
                }
            }
            // The last curve's end closes the loop back to its start.
            for p in &mut pts {
                p[0] = p[0].clamp(domain_u[0], domain_u[1]);
                p[1] = p[1].clamp(domain_v[0], domain_v[1]);
            }
            pts.dedup();
            while pts.len() > 1 && pts.first() == pts.last() {
                pts.pop();
            }
            let area2 = polygon_signed_area2(&pts);
            if pts.len() < 3 || area2 == 0.0 || !area2.is_finite() {
                return Err(TrimError::Loop {
                    loop_index: l,
                    message: "the loop encloses no area".into(),
                });
            }
            let want_ccw = l == 0;
            if (area2 > 0.0) != want_ccw {
                pts.reverse();
            }
            polylines.push(pts);
        }
        Ok(Self {
            loops,
            polylines,
            tolerance,
        })
    }

    /// The loops as given (first outer, then holes).
    pub fn loops(&self) -> &[TrimLoop] {
        &self.loops
    }

    /// The flattened loops: outer counter-clockwise, holes clockwise, not
    /// repeating the first point at the end.
    pub fn polylines(&self) -> &[Vec<[f64; 2]>] {
        &self.polylines
    }

    /// The flattening tolerance used (parameter units).
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Whether `(u, v)` lies in the trimmed face: inside the outer loop and
    /// in no hole (winding numbers of the flattened loops).
    pub fn contains(&self, u: f64, v: f64) -> bool {
        let p = [u, v];
        let mut loops = self.polylines.iter();
        let Some(outer) = loops.next() else {
            return false;
        };
        winding_number(outer, p) != 0 && loops.all(|h| winding_number(h, p) == 0)
    }

    /// Signed area of the trimmed region in the parameter plane (outer minus
    /// holes), from the polylines (shoelace formula).
    pub fn parameter_area(&self) -> f64 {
        0.5 * self
            .polylines
            .iter()
            .map(|p| polygon_signed_area2(p))
            .sum::<f64>()
    }

    /// The u positions where the row `v = const` crosses the loops, sorted:
    /// between crossings 0–1, 2–3, … the row is inside (even–odd rule, the
    /// same half-open rule as [`winding_number`]).
    pub fn row_crossings(&self, v: f64) -> Vec<f64> {
        let mut xs = Vec::new();
        for poly in &self.polylines {
            let n = poly.len();
            for k in 0..n {
                let (a, b) = (poly[k], poly[(k + 1) % n]);
                if (a[1] <= v) != (b[1] <= v) {
                    let t = (v - a[1]) / (b[1] - a[1]);
                    xs.push(a[0] + t * (b[0] - a[0]));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        xs
    }
}

/// Whether `u` is inside according to sorted row crossings (even–odd).
pub(crate) fn inside_by_crossings(crossings: &[f64], u: f64) -> bool {
    crossings.partition_point(|&x| x < u) % 2 == 1
}
