//! The tensor-product (rational) B-spline surface and its differential
//! geometry (Piegl & Tiller A3.5, A3.6, A4.3, A4.4; do Carmo §3.3 for the
//! fundamental forms).

use std::ops::Range;

use glam::DVec4;
use rayon::prelude::*;

use super::basis::{BasisDerivs, MAX_DEGREE, MAX_ORDER, basis_funs, basis_funs_ders2, find_span};
use super::trim::{TrimError, TrimLoop, TrimmedDomain};
use super::{BSplineError, Direction};
use crate::Vec3;
use std::sync::Arc;

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

/// Position and partial derivatives up to second order at one parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceDerivatives {
    /// `S(u, v)`.
    pub point: Vec3,
    /// `∂S/∂u`.
    pub su: Vec3,
    /// `∂S/∂v`.
    pub sv: Vec3,
    /// `∂²S/∂u²`.
    pub suu: Vec3,
    /// `∂²S/∂u∂v`.
    pub suv: Vec3,
    /// `∂²S/∂v²`.
    pub svv: Vec3,
}

/// Curvature at a surface point, from the first and second fundamental forms.
///
/// Signs: positive where the surface bends away from `normal` (a sphere with
/// outward `Su × Sv` has `k1 = k2 = +1/r`). `k1 >= k2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Curvature {
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// Mean curvature `(k1 + k2) / 2`.
    pub mean: f64,
    /// Gaussian curvature `k1 * k2`.
    pub gauss: f64,
    /// Unit principal direction of `k1` (tangent to the surface).
    pub d1: Vec3,
    /// Unit principal direction of `k2`, `normal × d1`.
    pub d2: Vec3,
    /// Unit normal `Su × Sv / |Su × Sv|` used for the signs.
    pub normal: Vec3,
}

/// Which control points influence a parameter `(u, v)`: the knot spans
/// (Piegl & Tiller A2.1) and the index ranges `span - degree ..= span`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BasisSupport {
    /// Knot span index in u.
    pub span_u: usize,
    /// Knot span index in v.
    pub span_v: usize,
    /// Control point rows `i` with possibly non-zero `N_{i,p}(u)`.
    pub rows: Range<usize>,
    /// Control point columns `j` with possibly non-zero `N_{j,q}(v)`.
    pub cols: Range<usize>,
}

/// The non-zero basis functions and their first and second derivatives at a
/// parameter (Piegl & Tiller A2.3): `du[k][r]` is the k-th derivative of
/// `N_{span_u - p + r, p}(u)`, `dv[l][s]` likewise in v.
///
/// For a non-rational surface `∂^{k+l} S / ∂u^k ∂v^l = Σ du[k][r] dv[l][s] P_{rs}`,
/// so these are also the derivatives of `S` with respect to the control points.
#[derive(Clone, Debug)]
pub struct SurfaceBasis {
    /// Knot span index in u; rows `span_u - p ..= span_u`.
    pub span_u: usize,
    /// Knot span index in v; columns `span_v - q ..= span_v`.
    pub span_v: usize,
    /// Basis values and derivatives in u.
    pub du: BasisDerivs,
    /// Basis values and derivatives in v.
    pub dv: BasisDerivs,
}

/// Relative threshold below which `|Su × Sv|` counts as degenerate.
const DEGENERATE: f64 = 1e-10;

/// Parameter nudges (fractions of the domain width) tried for the normal at
/// a degenerate point before giving up (the normal's error grows like
/// ε / nudge, so the first nudge is tiny).
const NORMAL_NUDGES: [f64; 4] = [1e-7, 1e-5, 1e-3, 1e-2];

/// Curvature needs second derivatives against a well-conditioned frame: its
/// error grows like ε / ratio² where `ratio = |Su × Sv| / max(|Su|, |Sv|)²`.
/// Points with a ratio below this are treated as degenerate for curvature.
const CURVATURE_REGULAR: f64 = 1e-5;

/// Parameter nudges tried for curvature at a (nearly) degenerate point.
const CURVATURE_NUDGES: [f64; 3] = [1e-4, 1e-3, 1e-2];

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

    /// Knot span in u containing `u` (clamped), Piegl & Tiller A2.1.
    pub fn span_u(&self, u: f64) -> usize {
        let u = clamp_param(u, self.domain_u());
        find_span(&self.knots_u, self.degree_u, self.count_u, u)
    }

    /// Knot span in v containing `v` (clamped), Piegl & Tiller A2.1.
    pub fn span_v(&self, v: f64) -> usize {
        let v = clamp_param(v, self.domain_v());
        find_span(&self.knots_v, self.degree_v, self.count_v, v)
    }

    /// The control points that influence `S(u, v)`: rows `span_u - p ..= span_u`
    /// and columns `span_v - q ..= span_v` (Piegl & Tiller A2.1 and Eq. 2.4's
    /// local support). Some of them may have a zero basis value exactly at a knot.
    pub fn basis_support(&self, u: f64, v: f64) -> BasisSupport {
        let span_u = self.span_u(u);
        let span_v = self.span_v(v);
        BasisSupport {
            span_u,
            span_v,
            rows: span_u - self.degree_u..span_u + 1,
            cols: span_v - self.degree_v..span_v + 1,
        }
    }

    /// Indices `(i, j)` of the control points whose support
    /// `[knots_u[i], knots_u[i+p+1]] × [knots_v[j], knots_v[j+q+1]]` meets the
    /// parameter box `[u0, u1] × [v0, v1]` in a set of positive area, i.e.
    /// whose basis function is non-zero somewhere inside the box (the
    /// "control points that affect the bounding box" of Nishiyama et al. §3.2).
    /// The box is clamped to the domain; a box of zero width in a direction
    /// selects the basis functions non-zero at that parameter
    /// ([`BSplineSurface::basis_support`]). Row-major order.
    pub fn control_points_in_box(&self, u0: f64, u1: f64, v0: f64, v1: f64) -> Vec<(usize, usize)> {
        let rows = support_range(
            &self.knots_u,
            self.degree_u,
            self.count_u,
            self.domain_u(),
            u0,
            u1,
        );
        let cols = support_range(
            &self.knots_v,
            self.degree_v,
            self.count_v,
            self.domain_v(),
            v0,
            v1,
        );
        rows.flat_map(|i| cols.clone().map(move |j| (i, j)))
            .collect()
    }

    /// The non-zero basis functions and their derivatives up to second order
    /// at `(u, v)` (clamped), Piegl & Tiller A2.1 + A2.3.
    pub fn basis(&self, u: f64, v: f64) -> SurfaceBasis {
        let (span_u, du) = self.basis_u(u);
        let (span_v, dv) = self.basis_v(v);
        SurfaceBasis {
            span_u,
            span_v,
            du,
            dv,
        }
    }

    /// Knot span and basis derivatives (orders 0–2) in u at `u` (clamped).
    fn basis_u(&self, u: f64) -> (usize, BasisDerivs) {
        let u = clamp_param(u, self.domain_u());
        let span = find_span(&self.knots_u, self.degree_u, self.count_u, u);
        let mut d = [[0.0; MAX_ORDER]; 3];
        basis_funs_ders2(span, u, self.degree_u, &self.knots_u, &mut d);
        (span, d)
    }

    /// Knot span and basis derivatives (orders 0–2) in v at `v` (clamped).
    fn basis_v(&self, v: f64) -> (usize, BasisDerivs) {
        let v = clamp_param(v, self.domain_v());
        let span = find_span(&self.knots_v, self.degree_v, self.count_v, v);
        let mut d = [[0.0; MAX_ORDER]; 3];
        basis_funs_ders2(span, v, self.degree_v, &self.knots_v, &mut d);
        (span, d)
    }

    /// The surface point `S(u, v)` (parameters clamped to the domain):
    /// Piegl & Tiller A3.5 (`SurfacePoint`), or A4.3 for rational surfaces.
    pub fn eval(&self, u: f64, v: f64) -> Vec3 {
        let (u, v) = self.clamp_parameters(u, v);
        let (p, q) = (self.degree_u, self.degree_v);
        let span_u = find_span(&self.knots_u, p, self.count_u, u);
        let span_v = find_span(&self.knots_v, q, self.count_v, v);
        let mut nu = [0.0; MAX_ORDER];
        let mut nv = [0.0; MAX_ORDER];
        basis_funs(span_u, u, p, &self.knots_u, &mut nu);
        basis_funs(span_v, v, q, &self.knots_v, &mut nv);
        let (i0, j0) = (span_u - p, span_v - q);
        match &self.weights {
            None => {
                let mut s = Vec3::ZERO;
                for r in 0..=p {
                    let row = &self.points[self.index(i0 + r, j0)..][..=q];
                    let mut t = Vec3::ZERO;
                    for (c, &pt) in row.iter().enumerate() {
                        t += nv[c] * pt;
                    }
                    s += nu[r] * t;
                }
                s
            }
            Some(w) => {
                let mut s = DVec4::ZERO;
                for r in 0..=p {
                    let k = self.index(i0 + r, j0);
                    let row = &self.points[k..][..=q];
                    let wrow = &w[k..][..=q];
                    let mut t = DVec4::ZERO;
                    for c in 0..=q {
                        t += (nv[c] * wrow[c]) * row[c].extend(1.0);
                    }
                    s += nu[r] * t;
                }
                s.truncate() / s.w
            }
        }
    }

    /// Position and first and second partial derivatives at `(u, v)`
    /// (parameters clamped), analytic: Piegl & Tiller A3.6
    /// (`SurfaceDerivsAlgorithm1`) on the basis derivatives of A2.3 (computed
    /// by [`basis_funs_ders2`](super::basis::basis_funs_ders2)); for a
    /// rational surface the homogeneous derivatives `A^{(k,l)}, w^{(k,l)}` are
    /// combined by the quotient rule of A4.4 (`RatSurfaceDerivs`, Eq. 4.20).
    /// At a knot the derivatives are those of the span to the right (the
    /// last span at the domain end). No allocation.
    pub fn derivatives(&self, u: f64, v: f64) -> SurfaceDerivatives {
        let (span_u, du) = self.basis_u(u);
        let (span_v, dv) = self.basis_v(v);
        self.contract(span_u, &du, span_v, &dv)
    }

    /// The tensor-product sums of A3.6 (and the quotient rule of A4.4) for
    /// given basis derivatives in u and v.
    #[inline]
    fn contract(
        &self,
        span_u: usize,
        du: &BasisDerivs,
        span_v: usize,
        dv: &BasisDerivs,
    ) -> SurfaceDerivatives {
        let (p, q) = (self.degree_u, self.degree_v);
        let (i0, j0) = (span_u - p, span_v - q);
        match &self.weights {
            None => {
                // a[k][l] = Σ_r du[k][r] Σ_s dv[l][s] P_rs.
                let mut a = [Vec3::ZERO; 6];
                for r in 0..=p {
                    let row = &self.points[self.index(i0 + r, j0)..][..=q];
                    let (mut t0, mut t1, mut t2) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                    for (s, &pt) in row.iter().enumerate() {
                        t0 += dv[0][s] * pt;
                        t1 += dv[1][s] * pt;
                        t2 += dv[2][s] * pt;
                    }
                    let (n0, n1, n2) = (du[0][r], du[1][r], du[2][r]);
                    a[0] += n0 * t0;
                    a[1] += n1 * t0;
                    a[2] += n0 * t1;
                    a[3] += n2 * t0;
                    a[4] += n1 * t1;
                    a[5] += n0 * t2;
                }
                SurfaceDerivatives {
                    point: a[0],
                    su: a[1],
                    sv: a[2],
                    suu: a[3],
                    suv: a[4],
                    svv: a[5],
                }
            }
            Some(w) => {
                let mut a = [DVec4::ZERO; 6];
                for r in 0..=p {
                    let k = self.index(i0 + r, j0);
                    let row = &self.points[k..][..=q];
                    let wrow = &w[k..][..=q];
                    let (mut t0, mut t1, mut t2) = (DVec4::ZERO, DVec4::ZERO, DVec4::ZERO);
                    for s in 0..=q {
                        let pw = wrow[s] * row[s].extend(1.0);
                        t0 += dv[0][s] * pw;
                        t1 += dv[1][s] * pw;
                        t2 += dv[2][s] * pw;
                    }
                    let (n0, n1, n2) = (du[0][r], du[1][r], du[2][r]);
                    a[0] += n0 * t0;
                    a[1] += n1 * t0;
                    a[2] += n0 * t1;
                    a[3] += n2 * t0;
                    a[4] += n1 * t1;
                    a[5] += n0 * t2;
                }
                rational_derivatives(&a)
            }
        }
    }

    /// Derivatives at every grid point `(us[a], vs[b])`, row-major
    /// (`a * vs.len() + b`), equal to [`BSplineSurface::derivatives`] at each
    /// point. The basis derivatives (A2.1 + A2.3) are computed once per grid
    /// row and column, so each point costs only the sums of A3.6/A4.4.
    /// Parallel over points with rayon; deterministic.
    pub fn derivatives_grid(&self, us: &[f64], vs: &[f64]) -> Vec<SurfaceDerivatives> {
        let nv = vs.len();
        let bu: Vec<(usize, BasisDerivs)> = us.par_iter().map(|&u| self.basis_u(u)).collect();
        let bv: Vec<(usize, BasisDerivs)> = vs.par_iter().map(|&v| self.basis_v(v)).collect();
        (0..us.len() * nv)
            .into_par_iter()
            .with_min_len(256)
            .map(|k| {
                let (su, du) = &bu[k / nv];
                let (sv, dv) = &bv[k % nv];
                self.contract(*su, du, *sv, dv)
            })
            .collect()
    }

    /// `f(S, S_u, S_v)` at every grid point `(us[a], vs[b])`, row-major
    /// (`a * vs.len() + b`): position and first partial derivatives only,
    /// for fields that need the normal but no curvature (highlight lines).
    /// The basis functions (Piegl & Tiller A2.1 + A2.3) are computed once
    /// per grid row and column; each row then contracts the control net in
    /// u once — `T_j = Σ_r N_r(u) P_{i0+r, j}` and `T'_j = Σ_r N'_r(u) P_{i0+r, j}`
    /// for every column j (homogeneous `P^w` for a rational surface) — so a
    /// grid point costs only the (q+1)-term sums in v of A3.6 (and the
    /// quotient rule of A4.4). The values equal those of
    /// [`BSplineSurface::derivatives`] up to rounding. Parallel over rows
    /// with rayon; deterministic.
    pub fn map_grid_first<T: Send>(
        &self,
        us: &[f64],
        vs: &[f64],
        f: impl Fn(Vec3, Vec3, Vec3) -> T + Sync,
    ) -> Vec<T> {
        let (p, q) = (self.degree_u, self.degree_v);
        let nc = self.count_v;
        let bv: Vec<(usize, BasisDerivs)> = vs.iter().map(|&v| self.basis_v(v)).collect();
        us.par_iter()
            .flat_map_iter(|&u| {
                let (span_u, du) = self.basis_u(u);
                let i0 = span_u - p;
                // the net contracted in u: value and u-derivative per column
                let mut t0 = vec![DVec4::ZERO; nc];
                let mut t1 = vec![DVec4::ZERO; nc];
                for r in 0..=p {
                    let k = self.index(i0 + r, 0);
                    let row = &self.points[k..][..nc];
                    let (n0, n1) = (du[0][r], du[1][r]);
                    match &self.weights {
                        None => {
                            for (j, pt) in row.iter().enumerate() {
                                let pw = pt.extend(0.0);
                                t0[j] += n0 * pw;
                                t1[j] += n1 * pw;
                            }
                        }
                        Some(w) => {
                            for (j, (pt, &wj)) in row.iter().zip(&w[k..][..nc]).enumerate() {
                                let pw = wj * pt.extend(1.0);
                                t0[j] += n0 * pw;
                                t1[j] += n1 * pw;
                            }
                        }
                    }
                }
                let rational = self.weights.is_some();
                let f = &f;
                bv.iter().map(move |(span_v, dv)| {
                    let j0 = span_v - q;
                    let (mut a, mut au, mut av) = (DVec4::ZERO, DVec4::ZERO, DVec4::ZERO);
                    for s in 0..=q {
                        a += dv[0][s] * t0[j0 + s];
                        au += dv[0][s] * t1[j0 + s];
                        av += dv[1][s] * t0[j0 + s];
                    }
                    if rational {
                        let inv = 1.0 / a.w;
                        let s00 = a.truncate() * inv;
                        let su = (au.truncate() - au.w * s00) * inv;
                        let sv = (av.truncate() - av.w * s00) * inv;
                        f(s00, su, sv)
                    } else {
                        f(a.truncate(), au.truncate(), av.truncate())
                    }
                })
            })
            .collect()
    }

    /// Derivatives at `(u, v)`, or at the first of a few parameters nudged
    /// towards the domain centre (by the fractions `nudges` of the domain
    /// width) if the point is degenerate, i.e. `|Su × Sv| <= tol · max(|Su|, |Sv|)²`
    /// (a pole or a collapsed edge). `None` if every try is degenerate.
    fn regular_derivatives(
        &self,
        u: f64,
        v: f64,
        tol: f64,
        nudges: &[f64],
    ) -> Option<(SurfaceDerivatives, Vec3)> {
        let regular = |d: SurfaceDerivatives| {
            let n = d.su.cross(d.sv).length();
            let m = d.su.length_squared().max(d.sv.length_squared());
            if n > tol * m {
                d.normal().map(|nn| (d, nn))
            } else {
                None
            }
        };
        let (u, v) = self.clamp_parameters(u, v);
        if let Some(r) = regular(self.derivatives(u, v)) {
            return Some(r);
        }
        let ([a, b], [c, e]) = (self.domain_u(), self.domain_v());
        let (uc, vc) = self.domain_center();
        let su = if u <= uc { 1.0 } else { -1.0 };
        let sv = if v <= vc { 1.0 } else { -1.0 };
        nudges
            .iter()
            .find_map(|&t| regular(self.derivatives(u + su * t * (b - a), v + sv * t * (e - c))))
    }

    /// Unit normal `Su × Sv / |Su × Sv|` (Nishiyama et al. Eq. (2.4)). At a
    /// degenerate point (`|Su × Sv|` below 1e-10 of `max(|Su|, |Sv|)²`, e.g.
    /// a pole) the normal of a nearby parameter (nudged towards the domain
    /// centre) is returned; `None` only if that fails too. Never NaN.
    pub fn normal(&self, u: f64, v: f64) -> Option<Vec3> {
        self.regular_derivatives(u, v, DEGENERATE, &NORMAL_NUDGES)
            .map(|(_, n)| n)
    }

    /// Principal curvatures, directions, mean and Gaussian curvature at
    /// `(u, v)` from the first (`E, F, G`) and second (`L, M, N`) fundamental
    /// forms (see [`SurfaceDerivatives::curvature`]). Where the parametrisation
    /// is (nearly) degenerate, `|Su × Sv| <= 1e-5 · max(|Su|, |Sv|)²`, the
    /// curvature of a parameter nudged towards the domain centre by 1e-4,
    /// 1e-3 or 1e-2 of the domain width is returned instead (at a pole, the
    /// limit is approached to that distance); `None` if all are degenerate.
    pub fn principal_curvatures(&self, u: f64, v: f64) -> Option<Curvature> {
        self.regular_derivatives(u, v, CURVATURE_REGULAR, &CURVATURE_NUDGES)
            .and_then(|(d, _)| d.curvature())
    }

    /// Gaussian curvature `K = (LN - M²) / (EG - F²)` at `(u, v)`.
    pub fn gaussian_curvature(&self, u: f64, v: f64) -> Option<f64> {
        self.principal_curvatures(u, v).map(|c| c.gauss)
    }

    /// Mean curvature `H = -(EN - 2FM + GL) / (2 (EG - F²))` at `(u, v)`
    /// (positive on a sphere with outward `Su × Sv`).
    pub fn mean_curvature(&self, u: f64, v: f64) -> Option<f64> {
        self.principal_curvatures(u, v).map(|c| c.mean)
    }
}

/// Quotient rule for rational surface derivatives up to order 2
/// (Piegl & Tiller A4.4 / Eq. 4.20): `S^{(k,l)} = (A^{(k,l)} - Σ binomials ·
/// w^{(i,j)} S^{(k-i,l-j)}) / w`. Input order: (0,0), (1,0), (0,1), (2,0), (1,1), (0,2).
fn rational_derivatives(a: &[DVec4; 6]) -> SurfaceDerivatives {
    let w = a[0].w;
    let inv = 1.0 / w;
    let (w10, w01, w20, w11, w02) = (a[1].w, a[2].w, a[3].w, a[4].w, a[5].w);
    let s00 = a[0].truncate() * inv;
    let s10 = (a[1].truncate() - w10 * s00) * inv;
    let s01 = (a[2].truncate() - w01 * s00) * inv;
    let s20 = (a[3].truncate() - 2.0 * w10 * s10 - w20 * s00) * inv;
    let s11 = (a[4].truncate() - w10 * s01 - w01 * s10 - w11 * s00) * inv;
    let s02 = (a[5].truncate() - 2.0 * w01 * s01 - w02 * s00) * inv;
    SurfaceDerivatives {
        point: s00,
        su: s10,
        sv: s01,
        suu: s20,
        suv: s11,
        svv: s02,
    }
}

/// Indices of the basis functions of one direction non-zero somewhere inside
/// `[t0, t1]` (or at `t0` if the interval is a point).
fn support_range(
    knots: &[f64],
    degree: usize,
    count: usize,
    domain: [f64; 2],
    t0: f64,
    t1: f64,
) -> Range<usize> {
    let (mut a, mut b) = (clamp_param(t0, domain), clamp_param(t1, domain));
    if a > b {
        std::mem::swap(&mut a, &mut b);
    }
    if a == b {
        let span = find_span(knots, degree, count, a);
        return span - degree..span + 1;
    }
    // N_i is non-zero on (knots[i], knots[i+p+1]); overlap with (a, b).
    let first = (0..count).find(|&i| knots[i + degree + 1] > a);
    let last = (0..count).rev().find(|&i| knots[i] < b);
    match (first, last) {
        (Some(f), Some(l)) if f <= l => f..l + 1,
        _ => 0..0,
    }
}

/// Unit normal `Su × Sv / |Su × Sv|` (Nishiyama et al. Eq. (2.4)), or `None`
/// where `|Su × Sv|` is below 1e-10 · max(|Su|, |Sv|)² (degenerate
/// parametrisation) or not finite. See [`SurfaceDerivatives::normal`].
#[inline]
pub fn unit_normal(su: Vec3, sv: Vec3) -> Option<Vec3> {
    let n = su.cross(sv);
    let len = n.length();
    let m = su.length_squared().max(sv.length_squared());
    if len > DEGENERATE * m && len.is_finite() {
        Some(n / len)
    } else {
        None
    }
}

impl SurfaceDerivatives {
    /// Unit normal `Su × Sv / |Su × Sv|`, or `None` where `|Su × Sv|` is below
    /// 1e-10 · max(|Su|, |Sv|)² (degenerate parametrisation) or not finite.
    pub fn normal(&self) -> Option<Vec3> {
        unit_normal(self.su, self.sv)
    }

    /// Curvature from the fundamental forms (do Carmo §3.3):
    /// `E = Su·Su, F = Su·Sv, G = Sv·Sv`, `L = Suu·N, M = Suv·N, N = Svv·N`,
    /// with `K = (LN - M²)/(EG - F²)` and `H = -(EN - 2FM + GL)/(2(EG - F²))`.
    /// The minus sign makes curvature positive where the surface bends away
    /// from `N` (a sphere with outward normal has `+1/r`).
    ///
    /// Computed stably: the second fundamental form is expressed in the
    /// orthonormal tangent frame `e1 = Su/|Su|`, `e2 = N × e1` as the
    /// symmetric matrix `[[a, b], [b, c]]` (`a = -L/E`, …), whose eigenvalues
    /// `k1,2 = (a+c)/2 ± √(((a-c)/2)² + b²)` and eigenvectors (angle
    /// `½ atan2(2b, a - c)` from `e1`) are the principal curvatures and
    /// directions; this keeps full precision at umbilic points, where
    /// `H ± √(H² - K)` would lose half the digits. `None` at a degenerate point.
    pub fn curvature(&self) -> Option<Curvature> {
        let normal = self.normal()?;
        let e = self.su.dot(self.su);
        let f = self.su.dot(self.sv);
        let g = self.sv.dot(self.sv);
        let l = self.suu.dot(normal);
        let m = self.suv.dot(normal);
        let n = self.svv.dot(normal);
        let su_len = e.sqrt();
        let perp = g - f * f / e;
        if !(perp > 0.0 && su_len > 0.0) {
            return None;
        }
        // e1 = x1·(Su, Sv) with x1 = (1/|Su|, 0); e2 = (α, β)·(Su, Sv).
        let beta = 1.0 / perp.sqrt();
        let alpha = -f / e * beta;
        let a = -l / e;
        let b = -(alpha * l + beta * m) / su_len;
        let c = -(alpha * alpha * l + 2.0 * alpha * beta * m + beta * beta * n);
        let mean = 0.5 * (a + c);
        let half = (0.5 * (a - c)).hypot(b);
        let (k1, k2) = (mean + half, mean - half);
        let gauss = a * c - b * b;
        let e1 = self.su / su_len;
        let e2 = normal.cross(e1);
        let theta = 0.5 * (2.0 * b).atan2(a - c);
        let d1 = theta.cos() * e1 + theta.sin() * e2;
        let d2 = normal.cross(d1);
        let finite = [k1, k2, mean, gauss].iter().all(|x| x.is_finite()) && d1.is_finite();
        finite.then_some(Curvature {
            k1,
            k2,
            mean,
            gauss,
            d1,
            d2,
            normal,
        })
    }
}
