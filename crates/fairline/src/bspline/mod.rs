//! B-spline surfaces: evaluation, derivatives, normals, curvature,
//! trimming loops and tessellation. Their files (surface JSON, IGES, STEP)
//! are read and written in [`crate::io`]; this module imports nothing from
//! it.
//!
//! The surfaces are the tensor-product (rational) B-spline surfaces of
//! Nishiyama et al. §2, Eq. (2.2): `r(u, v) = Σ_i Σ_j N_{i,p}(u) N_{j,q}(v) P_ij`,
//! or its rational form with weights `w_ij`. All algorithms follow
//! Piegl & Tiller, *The NURBS Book* (2nd ed.):
//!
//! - knot span search A2.1, basis functions A2.2, basis derivatives A2.3
//!   ([`basis`]);
//! - surface point A3.5 / A4.3, surface derivatives A3.6, rational surface
//!   derivatives A4.4 ([`BSplineSurface`]), also on whole parameter grids
//!   ([`BSplineSurface::derivatives_grid`], [`tessellate`]);
//! - normals and curvature from the first and second fundamental forms;
//!   isoparametric curves with exact curvature combs ([`iso_curves`]);
//! - point inversion A6.1 and the exact deviation of points from a part
//!   ([`closest_point_on_surface`], [`surface_deviation`]);
//! - local support (Piegl & Tiller Eq. 2.4, property P2.1):
//!   [`BSplineSurface::basis_support`], [`BSplineSurface::control_points_in_box`];
//!
//! Evaluation never allocates: the basis functions live in stack buffers
//! sized for [`MAX_DEGREE`].
//!
//! Knot vectors may be clamped or unclamped; the parameter domain is
//! `[knots[p], knots[n]]` for `n` control points of degree `p`, and
//! parameters outside it are clamped to it (NaN to the domain start). Degrees
//! up to [`MAX_DEGREE`] (15) are supported.
//!
//! Sign convention for curvature (as everywhere in fairline): the normal is
//! `N = Su × Sv / |Su × Sv|`, and a normal section curving *away* from `N`
//! (towards the inside) has positive curvature. A sphere whose `Su × Sv`
//! points outward has `k1 = k2 = +1/r`, `H = +1/r`, `K = 1/r²`.

pub mod basis;
mod bounds;
pub mod continuity;
pub(crate) mod fit;
mod iso;
pub(crate) mod offset;
mod project;
mod surface;
mod tessellate;
#[cfg(test)]
pub(crate) mod tests;
mod trim;
#[cfg(test)]
pub(crate) mod trim_tests;

pub use basis::{MAX_DEGREE, MAX_ORDER, clamped_uniform_knots, find_span};
pub use bounds::face_bounding_box;
pub use iso::{IsoCurve, curve_curvature, iso_curve, iso_curves};
pub use project::{
    DeviationPeak, PointDeviation, SurfaceReference, closest_point_on_surface, deviation_peak,
    surface_deviation,
};
pub use surface::{
    BSplineSurface, BasisSupport, Curvature, MIN_WEIGHT_RATIO, SurfaceBasis, SurfaceDerivatives,
    unit_normal,
};
#[cfg(test)]
pub(crate) use tessellate::trimmed_area_by_triangles;
pub use tessellate::{
    MIN_PATCH_GRID, Tessellation, control_diagonal, part_mesh, patch_grid, tessellate,
    tessellate_part, tessellate_part_with, trimmed_area,
};
pub(crate) use trim::inside_by_crossings;
pub use trim::{
    TRIM_FLATNESS, TrimCurve, TrimError, TrimLoop, TrimmedDomain, polygon_signed_area2,
    winding_number,
};

use std::fmt;
use thiserror::Error;

/// A parameter direction of a tensor-product surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// The first parameter `u` (control point index `i`).
    U,
    /// The second parameter `v` (control point index `j`).
    V,
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::U => "u",
            Direction::V => "v",
        })
    }
}

/// Why a [`BSplineSurface`] could not be built, naming the offending entry.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum BSplineError {
    /// Degree 0 surfaces are not supported.
    #[error("degree in {direction} is 0; the degree must be at least 1")]
    DegreeZero {
        /// Direction.
        direction: Direction,
    },
    /// The degree exceeds [`MAX_DEGREE`].
    #[error("degree in {direction} is {degree}; at most {max} is supported")]
    DegreeTooHigh {
        /// Direction.
        direction: Direction,
        /// The degree given.
        degree: usize,
        /// [`MAX_DEGREE`].
        max: usize,
    },
    /// The control net has no rows or no columns.
    #[error("the control net is empty")]
    EmptyControlNet,
    /// A row of the control net has a different length from row 0.
    #[error("control net row {row} has {found} points, row 0 has {expected}")]
    RaggedControlNet {
        /// Row index `i`.
        row: usize,
        /// Length of row 0.
        expected: usize,
        /// Length of this row.
        found: usize,
    },
    /// The flat control point list does not hold `count_u * count_v` points.
    #[error("expected {expected} control points ({count_u} x {count_v}), found {found}")]
    ControlPointCount {
        /// Points along u.
        count_u: usize,
        /// Points along v.
        count_v: usize,
        /// `count_u * count_v`.
        expected: usize,
        /// Points given.
        found: usize,
    },
    /// Too few control points for the degree.
    #[error("{count} control points in {direction}; degree {degree} needs at least {needed}")]
    TooFewControlPoints {
        /// Direction.
        direction: Direction,
        /// Points given in that direction.
        count: usize,
        /// Degree in that direction.
        degree: usize,
        /// `degree + 1`.
        needed: usize,
    },
    /// The knot vector length is not `count + degree + 1`.
    #[error(
        "knot vector in {direction} has {found} knots; {count} control points of degree {degree} need {expected}"
    )]
    KnotCount {
        /// Direction.
        direction: Direction,
        /// Knots given.
        found: usize,
        /// `count + degree + 1`.
        expected: usize,
        /// Control points in that direction.
        count: usize,
        /// Degree in that direction.
        degree: usize,
    },
    /// A knot is NaN or infinite.
    #[error("knot {index} in {direction} is not finite")]
    NonFiniteKnot {
        /// Direction.
        direction: Direction,
        /// Knot index.
        index: usize,
    },
    /// The knots span a range too large to subtract in f64 (`last - first`
    /// overflows), which would make the basis functions NaN.
    #[error("knot vector in {direction} spans a range too large for f64 arithmetic")]
    KnotRangeOverflow {
        /// Direction.
        direction: Direction,
    },
    /// The knot vector decreases.
    #[error("knot vector in {direction} decreases at index {index} ({previous} > {value})")]
    KnotDecreasing {
        /// Direction.
        direction: Direction,
        /// Index of the knot smaller than its predecessor.
        index: usize,
        /// `knots[index - 1]`.
        previous: f64,
        /// `knots[index]`.
        value: f64,
    },
    /// A knot value repeats too often (more than `p + 1` times, or more than
    /// `p` times inside the domain).
    #[error(
        "knot {value} in {direction} (from index {index}) has multiplicity {multiplicity}; at most {max} allowed there"
    )]
    KnotMultiplicity {
        /// Direction.
        direction: Direction,
        /// Index of the first occurrence.
        index: usize,
        /// The repeated knot value.
        value: f64,
        /// How often it occurs.
        multiplicity: usize,
        /// The allowed maximum.
        max: usize,
    },
    /// The domain `[knots[p], knots[n]]` has zero length.
    #[error("parameter domain in {direction} is empty: [{start}, {end}]")]
    EmptyDomain {
        /// Direction.
        direction: Direction,
        /// `knots[p]`.
        start: f64,
        /// `knots[n]`.
        end: f64,
    },
    /// A control point has a NaN or infinite coordinate.
    #[error("control point ({i}, {j}) is not finite")]
    NonFiniteControlPoint {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
    },
    /// The weights do not have the shape of the control net.
    #[error("weights: {message}")]
    WeightShape {
        /// What is wrong (which row, how many entries).
        message: String,
    },
    /// A weight is NaN or infinite.
    #[error("weight ({i}, {j}) is not finite")]
    NonFiniteWeight {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
    },
    /// A weight is zero or negative.
    #[error("weight ({i}, {j}) is {weight}; weights must be positive")]
    NonPositiveWeight {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
        /// The weight.
        weight: f64,
    },
    /// A weight so much smaller than the largest weight (or so small in
    /// itself: subnormal) that rational evaluation loses all precision or
    /// overflows; see [`MIN_WEIGHT_RATIO`].
    #[error(
        "weight ({i}, {j}) is {weight:e}, below 1e-8 times the largest weight {largest:e} (or subnormal): the surface cannot be evaluated reliably"
    )]
    WeightRange {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
        /// The weight.
        weight: f64,
        /// The largest weight of the surface.
        largest: f64,
    },
    /// A control point index is out of range.
    #[error("control point index ({i}, {j}) is outside the {count_u} x {count_v} net")]
    IndexOutOfRange {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
        /// Points along u.
        count_u: usize,
        /// Points along v.
        count_v: usize,
    },
}
