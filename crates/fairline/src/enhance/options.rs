//! The options of feature enhancement, with their setters and validation.

use super::{CG_MAX_ITERATIONS, CG_TOLERANCE, EnhanceError, EnhanceSolver, Projection};
use crate::Control;
use crate::mesh::{SurfaceMesh, VertexId};

/// Options of [`enhance_features`](super::enhance_features); `Default` gives the paper's λ = 1,
/// μ = 0.5 and one iteration. Build with `EnhanceOptions::default()` and
/// the setters (`.lambda(0.5).iterations(2)`).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct EnhanceOptions {
    /// λ, weight of the squared-distance term F_sd (Eq. (1)). Smaller values
    /// allow more deviation from the input and give stronger features. > 0.
    pub lambda: f64,
    /// μ, weight of the fairness term F_smo (Eq. (1)). Larger values give
    /// better-shaped triangles. ≥ 0.
    pub mu: f64,
    /// Number of solves; curvature is recomputed on the current mesh before
    /// each one after the first (F_sd keeps the input as reference). ≥ 1.
    pub iterations: usize,
    /// Vertices that must not move (in addition to the corners of the
    /// boundary; the other boundary vertices slide along the boundary).
    pub fixed: Vec<VertexId>,
    /// Number of bins of the triangle-quality histograms over [0, 1]. ≥ 1.
    pub histogram_bins: usize,
    /// How the least-squares system of Eq. (20) is solved.
    pub solver: EnhanceSolver,
    /// Conjugate gradients stop when the residual of the normal equations
    /// is at most this fraction of their right-hand side. In (0, 1).
    pub cg_tolerance: f64,
    /// Conjugate gradients fail after this many iterations. ≥ 1.
    pub cg_max_iterations: usize,
    /// Where the free vertices are put after each solve: onto a smooth fit
    /// of the input surface (the default), onto the input mesh, or nowhere
    /// (the paper's method).
    pub projection: Projection,
    /// Progress (one step per iteration) and cancellation.
    pub control: Control,
}

impl Default for EnhanceOptions {
    fn default() -> Self {
        EnhanceOptions {
            lambda: 1.0,
            mu: 0.5,
            iterations: 1,
            fixed: Vec::new(),
            histogram_bins: 10,
            solver: EnhanceSolver::Auto,
            cg_tolerance: CG_TOLERANCE,
            cg_max_iterations: CG_MAX_ITERATIONS,
            projection: Projection::Smooth,
            control: Control::default(),
        }
    }
}

impl EnhanceOptions {
    /// Sets λ.
    pub fn lambda(mut self, lambda: f64) -> Self {
        self.lambda = lambda;
        self
    }
    /// Sets μ.
    pub fn mu(mut self, mu: f64) -> Self {
        self.mu = mu;
        self
    }
    /// Sets the number of iterations.
    pub fn iterations(mut self, iterations: usize) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the fixed vertices.
    pub fn fixed(mut self, fixed: Vec<VertexId>) -> Self {
        self.fixed = fixed;
        self
    }
    /// Sets the solver.
    pub fn solver(mut self, solver: EnhanceSolver) -> Self {
        self.solver = solver;
        self
    }
    /// Sets where the vertices are put after each solve.
    pub fn projection(mut self, projection: Projection) -> Self {
        self.projection = projection;
        self
    }
    /// Sets the number of histogram bins.
    pub fn histogram_bins(mut self, bins: usize) -> Self {
        self.histogram_bins = bins;
        self
    }
    /// Sets the relative residual at which conjugate gradients stop.
    pub fn cg_tolerance(mut self, tolerance: f64) -> Self {
        self.cg_tolerance = tolerance;
        self
    }
    /// Sets the iteration limit of conjugate gradients.
    pub fn cg_max_iterations(mut self, iterations: usize) -> Self {
        self.cg_max_iterations = iterations;
        self
    }
    /// Sets the progress callback and cancel flag.
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }
}

pub(super) fn validate(mesh: &SurfaceMesh, o: &EnhanceOptions) -> Result<(), EnhanceError> {
    mesh.require_triangles()?;
    if !(o.lambda > 0.0) || !o.lambda.is_finite() {
        return Err(EnhanceError::InvalidOption(format!(
            "lambda must be positive and finite, got {}",
            o.lambda
        )));
    }
    if !(o.mu >= 0.0) || !o.mu.is_finite() {
        return Err(EnhanceError::InvalidOption(format!(
            "mu must be non-negative and finite, got {}",
            o.mu
        )));
    }
    if o.iterations == 0 {
        return Err(EnhanceError::InvalidOption(
            "iterations must be at least 1".into(),
        ));
    }
    if o.histogram_bins == 0 {
        return Err(EnhanceError::InvalidOption(
            "histogram_bins must be at least 1".into(),
        ));
    }
    if let Some(v) = o.fixed.iter().find(|v| v.idx() >= mesh.vertex_count()) {
        return Err(EnhanceError::FixedVertexOutOfRange {
            vertex: v.idx(),
            vertices: mesh.vertex_count(),
        });
    }
    Ok(())
}
