//! What feature enhancement reports: triangle quality before and after,
//! displacements, solver statistics and timings.

use super::{EnhanceOptions, EnhanceSolver, Projection};
use crate::Output;
use crate::geom::triangle_qualities;
use crate::mesh::SurfaceMesh;
use serde::Serialize;

/// Statistics of the triangle quality 2r/R (1 equilateral, 0 degenerate;
/// Ji et al. §5, Pébay & Baker).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QualityStats {
    /// Smallest quality.
    pub min: f64,
    /// Mean quality.
    pub mean: f64,
    /// Face counts in equal bins over [0, 1] (the last bin includes 1).
    pub histogram: Vec<usize>,
}

impl QualityStats {
    /// Statistics of the qualities of all faces of `mesh` with `bins` bins.
    pub fn of_mesh(mesh: &SurfaceMesh, bins: usize) -> QualityStats {
        let q = triangle_qualities(mesh);
        let bins = bins.max(1);
        let mut histogram = vec![0usize; bins];
        for &x in &q {
            let b = ((x * bins as f64) as usize).min(bins - 1);
            histogram[b] += 1;
        }
        let min = q.iter().copied().fold(f64::INFINITY, f64::min);
        QualityStats {
            min: if min.is_finite() { min } else { 0.0 },
            mean: if q.is_empty() {
                0.0
            } else {
                q.iter().sum::<f64>() / q.len() as f64
            },
            histogram,
        }
    }
}

/// Wall-clock seconds spent in the phases of [`enhance_features`](super::enhance_features), summed
/// over the iterations.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EnhanceTimings {
    /// Principal curvatures (Rusinkiewicz).
    pub curvature_s: f64,
    /// Rows of Eq. (20) (and the normal matrix, for the direct solver).
    pub assembly_s: f64,
    /// Sparse Cholesky factorisation (symbolic analysis included; 0 when
    /// conjugate gradients solved the system).
    pub factorisation_s: f64,
    /// Conjugate gradients and the triangular solves of the direct solver.
    pub solve_s: f64,
    /// Projection onto the input surface ([`Projection`]), flip detection
    /// and repair.
    pub repair_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// What [`enhance_features`](super::enhance_features) did; serialises to the JSON report of
/// `fairline enhance` (the CLI adds `histogram_before`/`histogram_after`
/// and its own timing keys).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnhanceReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Vertices that were free to move (3 unknowns each).
    pub free_vertices: usize,
    /// Solves performed.
    pub iterations: usize,
    /// λ of the run ([`EnhanceOptions::lambda`]).
    pub lambda: f64,
    /// μ of the run ([`EnhanceOptions::mu`]).
    pub mu: f64,
    /// Triangles found flipped (normal against the input's, or collapsed)
    /// after the last solve of an iteration (after the quality guard's
    /// re-solves) and repaired; summed over the iterations. No output
    /// triangle is flipped.
    pub flipped_triangles: usize,
    /// Triangles found below [`QUALITY_FLOOR`](super::QUALITY_FLOOR) of their input quality 2r/R
    /// (and not flipped) after the last solve of an iteration and repaired
    /// like flipped ones; summed over the iterations.
    pub degraded_triangles: usize,
    /// Vertices whose step was shortened or undone by the repair.
    pub backtracked_vertices: usize,
    /// Solves repeated by the quality guard (the distance model stiffened
    /// tangentially where the step would flip or degrade a triangle,
    /// [`QUALITY_ROUNDS`](super::QUALITY_ROUNDS) per iteration at most); summed over the
    /// iterations.
    pub quality_resolves: usize,
    /// Triangle quality of the input.
    pub quality_before: QualityStats,
    /// Triangle quality of the output.
    pub quality_after: QualityStats,
    /// Largest vertex displacement, in input units.
    pub max_displacement: f64,
    /// Mean vertex displacement, in input units.
    pub mean_displacement: f64,
    /// Largest distance of a free vertex to the input surface around it, in
    /// input units: input faces are searched ring by ring from the vertex's
    /// input position until a ring brings no nearer face. It bounds the
    /// distance to the whole input surface from above (another part of the
    /// surface, e.g. across a thin part, may be nearer).
    pub max_distance_to_input: f64,
    /// Mean of the same distance over the free vertices, in input units.
    pub mean_distance_to_input: f64,
    /// The length unit ē (mean input edge length) of the normalisation.
    pub edge_length: f64,
    /// The solver used.
    pub solver: EnhanceSolver,
    /// Where the vertices were put after each solve.
    pub projection: Projection,
    /// Conjugate-gradient iterations, summed over the solves (0 for the
    /// direct solver).
    pub cg_iterations: usize,
    /// Largest final relative residual of the normal equations over the
    /// conjugate-gradient solves that converged (0 for the direct solver).
    pub cg_relative_residual: f64,
    /// Solves of [`EnhanceSolver::Auto`] that fell back to the direct
    /// solver because conjugate gradients had not converged in their budget.
    pub direct_fallbacks: usize,
    /// Timings.
    pub timings: EnhanceTimings,
}

impl EnhanceReport {
    /// What a front end warns about after the run, as plain sentences (the
    /// CLI prints them as `warning:` lines, every front end lists them in
    /// its report): triangles flipped their orientation and were repaired.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if self.flipped_triangles > 0 {
            warnings.push(format!(
                "{} triangle(s) flipped their orientation in the solved step and were repaired by shortening their vertices' steps; try a smaller --lambda or fewer --iterations",
                self.flipped_triangles
            ));
        }
        warnings
    }
}

/// The output of a run that moves nothing: the input positions and a
/// report of zero motion.
pub(super) fn unchanged_output(
    mesh: &SurfaceMesh,
    options: &EnhanceOptions,
    quality_before: QualityStats,
    edge_length: f64,
    timings: EnhanceTimings,
) -> Output<EnhanceReport> {
    Output {
        positions: mesh.positions().to_vec(),
        report: EnhanceReport {
            vertices: mesh.vertex_count(),
            free_vertices: 0,
            iterations: 0,
            lambda: options.lambda,
            mu: options.mu,
            flipped_triangles: 0,
            degraded_triangles: 0,
            backtracked_vertices: 0,
            quality_resolves: 0,
            quality_after: quality_before.clone(),
            quality_before,
            max_displacement: 0.0,
            mean_displacement: 0.0,
            max_distance_to_input: 0.0,
            mean_distance_to_input: 0.0,
            edge_length: if edge_length.is_finite() {
                edge_length
            } else {
                0.0
            },
            solver: options.solver,
            projection: options.projection,
            cg_iterations: 0,
            cg_relative_residual: 0.0,
            direct_fallbacks: 0,
            timings,
        },
    }
}
