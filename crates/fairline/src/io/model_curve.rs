//! Model-space (3-D) curves, the writers' curve type: the 3-D edge curves
//! of STEP ([`crate::io::step`], made by its edge-curve fit) and highlight
//! lines as curves ([`crate::io::curve_fit`], written by
//! [`crate::io::iges_write::curves_to_iges`]).

use crate::Vec3;

/// A 3-D B-spline curve (NURBS when `weights` is given).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCurve {
    /// Degree.
    pub degree: usize,
    /// Knot vector (`points.len() + degree + 1` values).
    pub knots: Vec<f64>,
    /// Control points.
    pub points: Vec<Vec3>,
    /// Weights, when rational.
    pub weights: Option<Vec<f64>>,
    /// The curve is exactly what it stands for (an edge's `S(c(t))` up to
    /// rounding, or a polyline itself), not an approximation within a
    /// tolerance.
    pub exact: bool,
}
