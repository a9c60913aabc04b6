//! The tensor-product (rational) B-spline surface and its differential
//! geometry (Piegl & Tiller A3.5, A3.6, A4.3, A4.4; do Carmo §3.3 for the
//! fundamental forms).

use std::sync::Arc;

use super::basis::MAX_DEGREE;
use super::trim::{TrimError, TrimLoop, TrimmedDomain};
use super::{BSplineError, Direction};
use crate::Vec3;

mod evaluation;

pub use evaluation::{BasisSupport, Curvature, SurfaceBasis, SurfaceDerivatives, unit_normal};

/// A tensor-product B-spline surface of degrees `(p, q)`, non-rational or
/// rational (NURBS), with clamped or unclamped knot vectors.
///
/// Control point `P_ij` (`i` along u, `j` along v) is stored flat, row-major:
/// index `i * count_v + j`. The fields are private so that the invariants
/// checked by the constructors (see [`BSplineError`]) always hold.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineSurface {
    degree_u: usize,
    degree_v: usize,
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    count_u: usize,
    count_v: usize,
    points: Vec<Vec3>,
    weights: Option<Vec<f64>>,
    /// Trimming loops (shared between clones; `None` = the whole domain).
    trim: Option<Arc<TrimmedDomain>>,
}

/// The smallest weight allowed relative to the largest one of a surface.
///
/// The rational surface `S = Σ N w P / Σ N w` and its derivatives divide by
/// `W = Σ N w ≥ min w` while the numerators scale with `max w`; rounding
/// errors therefore grow like `(max w / min w) · ε`. At the bound 1e-8 that
/// keeps about eight correct digits (2e-8 relative); a weight of 1e-320 next
/// to weights of 1 makes evaluation overflow to infinity or NaN, which later
/// steps would blame on a vertex instead of on the weight.
pub const MIN_WEIGHT_RATIO: f64 = 1e-8;

/// Checks weights (row-major, `count_v` per row): finite, positive, normal
/// (not subnormal) and within [`MIN_WEIGHT_RATIO`] of the largest.
fn check_weights(w: &[f64], count_v: usize) -> Result<(), BSplineError> {
    let at = |k: usize| (k / count_v.max(1), k % count_v.max(1));
    for (k, &weight) in w.iter().enumerate() {
        let (i, j) = at(k);
        if !weight.is_finite() {
            return Err(BSplineError::NonFiniteWeight { i, j });
        }
        if weight <= 0.0 {
            return Err(BSplineError::NonPositiveWeight { i, j, weight });
        }
    }
    let largest = w.iter().copied().fold(0.0, f64::max);
    let floor = (largest * MIN_WEIGHT_RATIO).max(f64::MIN_POSITIVE);
    if let Some(k) = w.iter().position(|&weight| weight < floor) {
        let (i, j) = at(k);
        return Err(BSplineError::WeightRange {
            i,
            j,
            weight: w[k],
            largest,
        });
    }
    Ok(())
}

fn check_degree(direction: Direction, degree: usize) -> Result<(), BSplineError> {
    if degree == 0 {
        return Err(BSplineError::DegreeZero { direction });
    }
    if degree > MAX_DEGREE {
        return Err(BSplineError::DegreeTooHigh {
            direction,
            degree,
            max: MAX_DEGREE,
        });
    }
    Ok(())
}

/// Checks one knot vector against its degree and control point count.
fn check_knots(
    direction: Direction,
    degree: usize,
    count: usize,
    knots: &[f64],
) -> Result<(), BSplineError> {
    let p = degree;
    if count < p + 1 {
        return Err(BSplineError::TooFewControlPoints {
            direction,
            count,
            degree,
            needed: p + 1,
        });
    }
    if knots.len() != count + p + 1 {
        return Err(BSplineError::KnotCount {
            direction,
            found: knots.len(),
            expected: count + p + 1,
            count,
            degree,
        });
    }
    if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
        return Err(BSplineError::NonFiniteKnot { direction, index });
    }
    if !(knots[knots.len() - 1] - knots[0]).is_finite() {
        return Err(BSplineError::KnotRangeOverflow { direction });
    }
    for index in 1..knots.len() {
        if knots[index] < knots[index - 1] {
            return Err(BSplineError::KnotDecreasing {
                direction,
                index,
                previous: knots[index - 1],
                value: knots[index],
            });
        }
    }
    let (start, end) = (knots[p], knots[count]);
    let mut index = 0;
    while index < knots.len() {
        let value = knots[index];
        let mut m = 1;
        while index + m < knots.len() && knots[index + m] == value {
            m += 1;
        }
        let max = if value > start && value < end {
            p
        } else {
            p + 1
        };
        if m > max {
            return Err(BSplineError::KnotMultiplicity {
                direction,
                index,
                value,
                multiplicity: m,
                max,
            });
        }
        index += m;
    }
    if start >= end {
        return Err(BSplineError::EmptyDomain {
            direction,
            start,
            end,
        });
    }
    Ok(())
}

/// Clamps `t` to `[a, b]`; NaN goes to `a`.
#[inline]
fn clamp_param(t: f64, [a, b]: [f64; 2]) -> f64 {
    if t >= a {
        if t <= b { t } else { b }
    } else {
        a
    }
}

impl BSplineSurface {
    /// Builds a surface from a nested control net `control_points[i][j]`
    /// (`i` along u, `j` along v) and optional weights of the same shape.
    ///
    /// Checks (each failure names the offending row, index or direction):
    /// degrees in `1..=MAX_DEGREE`; a rectangular, non-empty net; at least
    /// `p + 1` points per direction; `knots.len() == n + p + 1`; finite,
    /// non-decreasing knots; multiplicity ≤ `p + 1` (≤ `p` strictly inside
    /// the domain); a non-empty domain `[knots[p], knots[n]]`; finite
    /// control points; finite, positive weights no smaller than
    /// [`MIN_WEIGHT_RATIO`] times the largest (see [`BSplineError::WeightRange`]).
    pub fn new(
        degree_u: usize,
        degree_v: usize,
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        control_points: Vec<Vec<Vec3>>,
        weights: Option<Vec<Vec<f64>>>,
    ) -> Result<Self, BSplineError> {
        let count_u = control_points.len();
        let count_v = control_points.first().map_or(0, Vec::len);
        if count_u == 0 || count_v == 0 {
            return Err(BSplineError::EmptyControlNet);
        }
        for (row, r) in control_points.iter().enumerate() {
            if r.len() != count_v {
                return Err(BSplineError::RaggedControlNet {
                    row,
                    expected: count_v,
                    found: r.len(),
                });
            }
        }
        let flat_weights = match weights {
            None => None,
            Some(w) => {
                if w.len() != count_u {
                    return Err(BSplineError::WeightShape {
                        message: format!("{} rows, the control net has {count_u}", w.len()),
                    });
                }
                for (row, r) in w.iter().enumerate() {
                    if r.len() != count_v {
                        return Err(BSplineError::WeightShape {
                            message: format!(
                                "row {row} has {} weights, the control net has {count_v}",
                                r.len()
                            ),
                        });
                    }
                }
                Some(w.into_iter().flatten().collect())
            }
        };
        let points = control_points.into_iter().flatten().collect();
        Self::from_flat(
            degree_u,
            degree_v,
            knots_u,
            knots_v,
            [count_u, count_v],
            points,
            flat_weights,
        )
    }

    /// Builds a surface from a flat row-major control net (`P_ij` at
    /// `i * count_v + j`) of `counts = [count_u, count_v]` points and optional
    /// flat weights. Same checks as [`BSplineSurface::new`].
    pub fn from_flat(
        degree_u: usize,
        degree_v: usize,
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        counts: [usize; 2],
        points: Vec<Vec3>,
        weights: Option<Vec<f64>>,
    ) -> Result<Self, BSplineError> {
        let [count_u, count_v] = counts;
        check_degree(Direction::U, degree_u)?;
        check_degree(Direction::V, degree_v)?;
        if count_u == 0 || count_v == 0 {
            return Err(BSplineError::EmptyControlNet);
        }
        if count_u.checked_mul(count_v) != Some(points.len()) {
            return Err(BSplineError::ControlPointCount {
                count_u,
                count_v,
                expected: count_u.saturating_mul(count_v),
                found: points.len(),
            });
        }
        check_knots(Direction::U, degree_u, count_u, &knots_u)?;
        check_knots(Direction::V, degree_v, count_v, &knots_v)?;
        if let Some(k) = points.iter().position(|p| !p.is_finite()) {
            return Err(BSplineError::NonFiniteControlPoint {
                i: k / count_v,
                j: k % count_v,
            });
        }
        if let Some(w) = &weights {
            if w.len() != points.len() {
                return Err(BSplineError::WeightShape {
                    message: format!("{} weights for {} control points", w.len(), points.len()),
                });
            }
            check_weights(w, count_v)?;
        }
        Ok(BSplineSurface {
            degree_u,
            degree_v,
            knots_u,
            knots_v,
            count_u,
            count_v,
            points,
            weights,
            trim: None,
        })
    }

    /// A Bézier patch (clamped knots `[0,…,0,1,…,1]`) of degrees
    /// `(rows - 1, columns - 1)` from a nested net and optional weights.
    pub fn bezier(
        control_points: Vec<Vec<Vec3>>,
        weights: Option<Vec<Vec<f64>>>,
    ) -> Result<Self, BSplineError> {
        let nu = control_points.len();
        let nv = control_points.first().map_or(0, Vec::len);
        let clamped = |n: usize| {
            let mut k = vec![0.0; n];
            k.extend(std::iter::repeat_n(1.0, n));
            k
        };
        Self::new(
            nu.saturating_sub(1),
            nv.saturating_sub(1),
            clamped(nu),
            clamped(nv),
            control_points,
            weights,
        )
    }

    /// Degree `p` in u.
    pub fn degree_u(&self) -> usize {
        self.degree_u
    }

    /// Degree `q` in v.
    pub fn degree_v(&self) -> usize {
        self.degree_v
    }

    /// Knot vector in u (`count_u + p + 1` entries).
    pub fn knots_u(&self) -> &[f64] {
        &self.knots_u
    }

    /// Knot vector in v (`count_v + q + 1` entries).
    pub fn knots_v(&self) -> &[f64] {
        &self.knots_v
    }

    /// Number of control points along u (rows `i`).
    pub fn count_u(&self) -> usize {
        self.count_u
    }

    /// Number of control points along v (columns `j`).
    pub fn count_v(&self) -> usize {
        self.count_v
    }

    /// All control points, row-major (`P_ij` at `i * count_v + j`).
    pub fn control_points(&self) -> &[Vec3] {
        &self.points
    }

    /// Flat index `i * count_v + j` of control point `(i, j)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.count_v + j
    }

    /// Control point `P_ij`. Panics if `(i, j)` is outside the net.
    pub fn control_point(&self, i: usize, j: usize) -> Vec3 {
        assert!(i < self.count_u && j < self.count_v);
        self.points[self.index(i, j)]
    }

    /// Weights, row-major like the control points; `None` if non-rational.
    pub fn weights(&self) -> Option<&[f64]> {
        self.weights.as_deref()
    }

    /// Weight `w_ij` (1 for a non-rational surface). Panics if out of range.
    pub fn weight(&self, i: usize, j: usize) -> f64 {
        assert!(i < self.count_u && j < self.count_v);
        self.weights.as_ref().map_or(1.0, |w| w[self.index(i, j)])
    }

    /// Whether the surface has weights (is a NURBS surface).
    pub fn is_rational(&self) -> bool {
        self.weights.is_some()
    }

    fn check_index(&self, i: usize, j: usize) -> Result<usize, BSplineError> {
        if i >= self.count_u || j >= self.count_v {
            return Err(BSplineError::IndexOutOfRange {
                i,
                j,
                count_u: self.count_u,
                count_v: self.count_v,
            });
        }
        Ok(self.index(i, j))
    }

    /// Moves control point `P_ij`; refuses non-finite positions and
    /// out-of-range indices.
    pub fn set_control_point(&mut self, i: usize, j: usize, p: Vec3) -> Result<(), BSplineError> {
        let k = self.check_index(i, j)?;
        if !p.is_finite() {
            return Err(BSplineError::NonFiniteControlPoint { i, j });
        }
        self.points[k] = p;
        Ok(())
    }

    /// Sets weight `w_ij`, making the surface rational (all other weights 1)
    /// if it was not; refuses weights that [`BSplineSurface::new`] refuses.
    pub fn set_weight(&mut self, i: usize, j: usize, weight: f64) -> Result<(), BSplineError> {
        let k = self.check_index(i, j)?;
        let n = self.points.len();
        let mut w = self.weights.clone().unwrap_or_else(|| vec![1.0; n]);
        w[k] = weight;
        check_weights(&w, self.count_v)?;
        self.weights = Some(w);
        Ok(())
    }

    /// Parameter domain in u: `[knots_u[p], knots_u[count_u]]`.
    pub fn domain_u(&self) -> [f64; 2] {
        [self.knots_u[self.degree_u], self.knots_u[self.count_u]]
    }

    /// Parameter domain in v: `[knots_v[q], knots_v[count_v]]`.
    pub fn domain_v(&self) -> [f64; 2] {
        [self.knots_v[self.degree_v], self.knots_v[self.count_v]]
    }

    /// Attaches trimming loops (first the outer boundary, then holes; see
    /// [`TrimmedDomain`]), replacing any previous ones. The loops are
    /// flattened once here (tolerance [`super::TRIM_FLATNESS`] × domain
    /// diagonal). Control points, knots and weights are untouched.
    pub fn set_trims(&mut self, loops: Vec<TrimLoop>) -> Result<(), TrimError> {
        let domain = TrimmedDomain::new(loops, self.domain_u(), self.domain_v())?;
        self.trim = Some(Arc::new(domain));
        Ok(())
    }

    /// The surface with trimming loops attached; see [`Self::set_trims`].
    pub fn with_trims(mut self, loops: Vec<TrimLoop>) -> Result<Self, TrimError> {
        self.set_trims(loops)?;
        Ok(self)
    }

    /// Removes the trimming loops (the whole domain becomes the face).
    pub fn clear_trims(&mut self) {
        self.trim = None;
    }

    /// The trimmed domain, `None` for an untrimmed surface.
    pub fn trim(&self) -> Option<&TrimmedDomain> {
        self.trim.as_deref()
    }

    /// The trimming loops (empty for an untrimmed surface).
    pub fn trims(&self) -> &[TrimLoop] {
        self.trim.as_deref().map_or(&[], TrimmedDomain::loops)
    }

    /// Whether trimming loops are attached.
    pub fn is_trimmed(&self) -> bool {
        self.trim.is_some()
    }

    /// Whether `(u, v)` belongs to the face: inside the parameter domain
    /// and, for a trimmed surface, inside the trimming loops
    /// ([`TrimmedDomain::contains`]).
    pub fn contains_uv(&self, u: f64, v: f64) -> bool {
        let [a, b] = self.domain_u();
        let [c, d] = self.domain_v();
        if !(u >= a && u <= b && v >= c && v <= d) {
            return false;
        }
        match self.trim.as_deref() {
            None => true,
            Some(t) => t.contains(u, v),
        }
    }

    /// The centre of the parameter domain.
    pub fn domain_center(&self) -> (f64, f64) {
        let [a, b] = self.domain_u();
        let [c, d] = self.domain_v();
        (0.5 * (a + b), 0.5 * (c + d))
    }

    /// `(u, v)` clamped to the domain (NaN goes to the domain start).
    pub fn clamp_parameters(&self, u: f64, v: f64) -> (f64, f64) {
        (
            clamp_param(u, self.domain_u()),
            clamp_param(v, self.domain_v()),
        )
    }

    /// Axis-aligned bounding box `(min, max)` of the control points; it
    /// contains the surface (convex hull property, positive weights).
    pub fn control_bounding_box(&self) -> (Vec3, Vec3) {
        self.points.iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }
}
