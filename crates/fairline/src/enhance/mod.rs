//! Feature enhancement by vertex flow (Ji, Liu, Wang & Wang 2011, "Feature
//! enhancement by vertex flow for 3D shapes", Computer-Aided Design &
//! Applications 8(5)): vertices of a triangle mesh slide over the surface
//! from flat regions toward ridges and valleys, so that a coarse mesh spends
//! its vertices where the curvature is.
//!
//! The new positions minimise, in the least-squares sense, Eq. (1)
//! F = F_em + λ F_sd + μ F_smo, a quadratic in the 3n coordinates:
//!
//! - **F_em** (§3.2, §4.1). With the edge metric M_i = |k_i1| T_i1 T_i1ᵀ +
//!   |k_i2| T_i2 T_i2ᵀ (Eq. (2)–(3), principal curvatures and directions by
//!   Rusinkiewicz 2004) the edge energy is f_em(e) = ½ e_ijᵀ (M_i + M_j) e_ij
//!   (Eq. (4)), whose gradient at v_i is Σ_j (M_i + M_j)(v_i − v_j). Only its
//!   tangential components are driven to zero (Eq. (13)–(19)): two rows per
//!   vertex, T_ikᵀ Σ_j (M_i + M_j)(v_i − v_j) = 0, k = 1, 2.
//! - **F_sd** (§3.3). The Pottmann–Hofer quadratic model of the squared
//!   distance to the input surface (Eq. (6)):
//!   h(v) = Σ_k d/(d + ρ_ik) [(v − p_i)·T_ik]² + [(v − p_i)·N_i]², with p_i
//!   the input position, ρ_ik = 1/|k_ik| and d the smallest principal radius
//!   over the free vertices, so the coefficient is d|k_ik| / (1 + d|k_ik|)
//!   (0 where k_ik = 0): three rows per vertex.
//! - **F_smo** (§3.4). The uniform Laplacian L(v_i) = v_i − (1/d_i) Σ_j v_j
//!   (Eq. (8)) weighted by μ_i = exp(−(|k_i1| + |k_i2|)) (Eq. (10)): three
//!   rows per vertex.
//!
//! The 8n × 3n system LX = b (Eq. (20), §4.3) is assembled once per
//! iteration in parallel and solved in the least-squares sense, i.e. its
//! normal equations (LᵀL + εI) X = Lᵀb + εp are solved (ε below), by one of the
//! solvers ([`EnhanceSolver`]) that give the same solution:
//!
//! - **Direct** ([`EnhanceSolver::Direct`]) — what §4.3 does ("we compute the Cholesky factorization
//!   for a 3n × 3n sparse matrix", TAUCS): [`crate::solve::normal_matrix`]
//!   and [`crate::solve::CholeskySolver`] (faer, AMD ordering, supernodal).
//!   LᵀL couples the three coordinates of each vertex with those of its
//!   whole 2-ring (the F_em rows mix x, y, z over the 1-ring; only the
//!   F_smo rows are per coordinate), so its factor fills in heavily:
//!   1.3 · 10⁷ nonzeros at 10k vertices, 2.2 · 10⁸ at 100k, 3.2 · 10⁹ (26 GB)
//!   at 1M; the factorisation takes 84–91 % of the time and 1M does not fit.
//! - **Conjugate gradients** — [`crate::solve::pcg_with`]:
//!   block-Jacobi (3 × 3 per vertex) preconditioned CG on the same normal
//!   equations, matrix-free: L is stored per vertex (the coefficients of
//!   its rows over its closed one-ring) and LᵀL v = Lᵀ(L v) is never
//!   formed; parallel and deterministic, warm-started at the current
//!   positions (the solution is within an edge length of them), stopped at
//!   a relative residual of [`CG_TOLERANCE`] = 10⁻¹², at which the result
//!   equals the Cholesky one to about 10⁻¹² of the bounding-box diagonal
//!   (tested to 10⁻⁸). Where the curvature pins the
//!   tangential motion (F_sd with d|k| > 0, F_em) CG converges in about 25
//!   iterations at any size (tori of 10k–1M vertices); where it does not —
//!   flat parts and the axial direction of cylindrical parts, where only
//!   the F_smo bi-Laplacian holds the tangential motion — the count grows
//!   with the size of those parts (rounded cube: 597 at 10k, about 1500 at
//!   100k; the real scan `spot`, 2.9k vertices: 730).
//! - **CG with the factored bi-Laplacian preconditioner**
//!   ([`EnhanceSolver::Amg`]): block Jacobi plus Vᵀ Q̂⁻¹ V ≈ H⁻¹ Q̂⁻¹ H⁻¹,
//!   where H Q̂ H models the F_smo and F_em rows as a weighted bi-Laplacian
//!   with per-vertex 3 × 3 weights and the F_sd rows as a reaction term,
//!   and H, a 1-ring vector Laplacian, is inverted approximately by a
//!   smoothed-aggregation multigrid cycle V and its transpose
//!   ([`crate::solve::VectorAmg`], Vaněk, Mandel & Brezina 1996); see
//!   `precondition.rs` for the derivation and the measured condition
//!   numbers. Its iteration count hardly grows with the mesh (rounded
//!   cube: 35 at 10k vertices, 33 at 100k, 41 at 1M; open cylinders of two
//!   lengths: 28 and 28, block Jacobi 631 on the shorter); an iteration
//!   costs about one symmetric V-cycle more than one of block Jacobi, and
//!   the setup about ten iterations. (An earlier multigrid on LᵀL itself
//!   cut the iterations only 8× and filled in on coarse levels: LᵀL is a
//!   fourth-order operator.)
//!
//! The default, [`EnhanceSolver::Auto`], chooses by the geometry: where
//! more than [`AUTO_SOFT_SHARE`] of the free vertices have a tangential
//! direction that F_sd leaves (nearly) free — flat and cylindrical parts —
//! it runs the factored preconditioner from the start; elsewhere it runs
//! block-Jacobi CG for at most [`AUTO_JACOBI_BUDGET`] iterations — enough
//! where the curvature holds the motion — giving up earlier when, checked
//! every [`AUTO_JACOBI_CHECK`] iterations, its rate predicts far more, and
//! continues from there with the factored preconditioner. The direct solve
//! is a last resort should that fail (up to [`AUTO_DIRECT_LIMIT`] free
//! vertices). Every CG result reaches the Cholesky one to 10⁻⁸ of the
//! bounding-box diagonal (tested).
//!
//! **Normalisations.** Eq. (5) and Eq. (7) average F_em over the edges and
//! F_sd over the vertices; fairline makes all three terms means over the
//! vertices, so that their balance (and the meaning of λ, μ) does not depend
//! on the mesh size: every row is a per-vertex residual and all rows carry
//! the same factor 1/√|V|, which cancels. (Taken literally, the gradient of
//! (1/|E|) Σ f_em shrinks like 1/|E| and the unnormalised Eq. (9) grows like
//! |V|, so F_smo alone would decide the result on large meshes.)
//!
//! **Units (scale and motion invariance).** The paper does not fix the units
//! of curvature, yet μ_i and the balance of the terms depend on them. All
//! computations run in normalised coordinates x' = (x − c) / ē, where c is
//! the centroid of the input vertices and ē the mean edge length of the
//! input; curvatures are then k' = k ē (the turning angle per edge), F_em
//! measures the sag of an edge in edge lengths (Appendix: f_em ≈ 8δ) and
//! F_sd squared distances in edge lengths. Every quantity is invariant
//! under translation, rotation and uniform scaling, so the result of a
//! transformed input is the transformed result (up to rounding).
//!
//! **Constraints and repair.** Isolated vertices, vertices without a
//! normal and the vertices listed in [`EnhanceOptions::fixed`] are not
//! unknowns; their output positions are the input values, bit for bit.
//! Boundary vertices slide along the boundary curve of the input (module
//! `boundary`: one F_em row along the boundary, the Pottmann–Hofer distance
//! to the curve, the Laplacian along the boundary, and after each solve
//! the projection onto the input boundary polyline, so that the output's
//! boundary vertices lie on the input's boundary as with the paper's fixed
//! boundary), so that a feature running into the boundary
//! is not pinned by a fixed vertex next to it; the corners of the boundary
//! curve (turning by more than [`FEATURE_ANGLE_DEG`]) stay bit for bit, and
//! with [`Projection::None`] (the paper's method) the whole boundary
//! stays. A tiny Tikhonov term ε‖v − p‖² (ε = 1e-10 in
//! normalised units) keeps the normal matrix positive definite when F_sd
//! leaves a tangential direction free. After each solve, triangles whose
//! normal turned against the input's (or collapsed), or whose quality fell
//! below [`QUALITY_FLOOR`] of the input's, are repaired by halving the steps
//! of their vertices, and after [`REPAIR_HALVINGS`] rounds by resetting
//! them, until no triangle is flipped or degraded (§5: "we rectify the
//! topological errors in the post-processing").
//!
//! **Projection onto the input surface** (module
//! `surface`). The paper keeps the vertices near the input only through the
//! quadratic distance model at their input positions, so a vertex sliding
//! over a curved part leaves it along the tangent plane, and F_smo pulls
//! curved parts inward: measured against known surfaces, the mesh ended
//! farther from the true shape than its input (rounded cube: Hausdorff
//! +45 %, RMS +117 %). After each solve (before the repair) every free
//! vertex is therefore moved along its input normal onto the input mesh
//! and lifted onto the Phong patch (α = ½) of the face it meets
//! ([`Projection::Smooth`], the default; [`Projection::Mesh`] stops on the
//! flat triangle, [`Projection::None`] is the paper's method). A vertex
//! that moved into the middle of a chord of a curved part lands on a
//! second-order fit of the surface instead of on the chord, so the denser
//! sampling of the features pays off: rounded cube Hausdorff −46 %, RMS
//! −37 %, filleted cylinder −21 % / −19 % (tests in `accuracy_tests`).
//! Sharp creases that the input cuts by a strip of chord faces are rebuilt
//! from their sides (module `crease`: flat sides, chord strips between
//! sides whose fits meet at more than [`FEATURE_ANGLE_DEG`], each side's
//! tangent plane, the nearest plane along the normal, points near the
//! intersection of two sides put onto it, and where three sides meet the
//! nearest vertex put onto their common point): sharp cube Hausdorff
//! −59 %, RMS −65 %, normal error near the edges 20.3° → 8.2° (without
//! the corners and with a 10° threshold per edge: −15 % / −27 %,
//! 12.1°; the Phong fit alone: −9 % / −10 %, 17.4°).
//!
//! **Triangle quality.** μ keeps the mean quality (the paper's Fig. 5),
//! but a single triangle can still invert or collapse where the vertices
//! crowd (a cow's ears and horns, small triangles next to large ones in
//! an artist mesh). The bound: no output triangle is flipped, and every
//! one keeps at least [`QUALITY_FLOOR`] (¼) of its input quality 2r/R. It
//! is kept in two steps. (1) The quality guard, a trust region in the
//! paper's own distance model: F_sd holds a vertex in its tangent
//! directions only with the weight c = d|k| / (1 + d|k|) ≤ ½ of Eq. (6)
//! (0 on flat and cylindrical directions), so nothing bounds its
//! tangential step there. Where the solved step would flip a triangle or
//! drop it below the floor, the tangential coefficients of its vertices
//! are raised to at least 1 (the weight of the normal direction), then
//! [`QUALITY_FLOOR_GROWTH`] times more in each further round, and the
//! system is solved again — at most [`QUALITY_ROUNDS`] times per iteration
//! (reported as `quality_resolves`) — so the neighbours adapt to the
//! shorter step in the same least-squares solution. With μ = 0 — the
//! paper's model without its quality term, whose flips Fig. 5 shows — the
//! guard is off. (2) What still flips or degrades after that is repaired
//! by halving the steps of its vertices (below; reported as
//! `flipped_triangles` / `degraded_triangles`).

//! **Iterations.** With `iterations > 1` curvature is recomputed on the
//! current mesh for F_em and F_smo, while F_sd keeps the input positions and
//! input frames as its distance reference.

#[cfg(test)]
mod accuracy_tests;
#[cfg(test)]
mod bitwise_tests;
#[cfg(test)]
pub(crate) use bitwise_tests::checksum as bitwise_checksum;
mod boundary;
mod crease;
mod junction;
mod precondition;
mod repair;
mod surface;
mod system;
#[cfg(test)]
mod tests;

use crate::geom::{
    PrincipalCurvatures, mean_edge_length, principal_curvatures_rusinkiewicz, triangle_qualities,
};
use crate::mesh::{MeshError, SurfaceMesh, VertexId};
pub use crate::solve::NormalSolver as EnhanceSolver;
pub use crate::solve::{AUTO_DIRECT_LIMIT, AUTO_JACOBI_BUDGET, AUTO_JACOBI_CHECK};
use crate::solve::{
    BlockJacobi, MultigridBuilder, Preconditioner, SolveError, StagedOptions, StagedSolver,
};
use crate::{Control, Output, Vec3};
pub use crease::{FEATURE_ANGLE_DEG, FLAT_SIDE_DEG, SNAP_DISTANCE};
pub use repair::QUALITY_FLOOR;
use serde::Serialize;
use std::time::Instant;
pub use surface::{CREASE_ANGLE_DEG, PHONG_ALPHA, Projection};
use thiserror::Error;

/// Solves the quality guard repeats at most per iteration, each with the
/// tangential distance coefficients raised at the vertices of the
/// triangles the last one would flip or drop below [`QUALITY_FLOOR`]
/// (module documentation, "Triangle quality").
pub const QUALITY_ROUNDS: usize = 3;

/// Factor by which the quality guard raises the floor under the
/// tangential distance coefficients of a vertex in each further round (the
/// first round lifts it to 1, the weight of the normal direction).
pub const QUALITY_FLOOR_GROWTH: f64 = 4.0;

/// Rounds of step halving for the vertices of flipped triangles before
/// their steps are reset to zero.
pub const REPAIR_HALVINGS: usize = 8;

/// Default relative residual at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-12;

/// Under [`EnhanceSolver::Auto`], block Jacobi is skipped when more than
/// this share of the free vertices have a tangential direction that the
/// distance term F_sd holds by less than [`SOFT_COEFFICIENT`] of its normal
/// weight (a principal curvature below 1 % of the largest: flat and
/// cylindrical parts), which only the F_smo bi-Laplacian holds.
pub const AUTO_SOFT_SHARE: f64 = 0.1;

/// The coefficient c = d|k| / (1 + d|k|) of Ji et al. Eq. (6) below which
/// a tangential direction counts as free for [`AUTO_SOFT_SHARE`].
pub const SOFT_COEFFICIENT: f64 = 0.01;

/// Default iteration limit of conjugate gradients.
pub const CG_MAX_ITERATIONS: usize = 5000;

/// Weight ε of the regularisation ε‖v − p‖² (normalised units).
const REGULARISATION: f64 = 1e-10;

/// Options of [`enhance_features`]; `Default` gives the paper's λ = 1,
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

/// Why [`enhance_features`] failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EnhanceError {
    /// The mesh is not a triangle mesh.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A fixed vertex does not exist.
    #[error("fixed vertex {vertex} does not exist; the mesh has {vertices} vertices")]
    FixedVertexOutOfRange {
        /// The offending index.
        vertex: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// The linear solve failed.
    #[error("vertex-flow solve failed: {0}")]
    Solve(#[from] SolveError),
    /// The caller cancelled the run ([`EnhanceOptions::control`]).
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
}

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

/// Wall-clock seconds spent in the phases of [`enhance_features`], summed
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

/// What [`enhance_features`] did; serialises to the JSON report of
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
    /// Triangles found below [`QUALITY_FLOOR`] of their input quality 2r/R
    /// (and not flipped) after the last solve of an iteration and repaired
    /// like flipped ones; summed over the iterations.
    pub degraded_triangles: usize,
    /// Vertices whose step was shortened or undone by the repair.
    pub backtracked_vertices: usize,
    /// Solves repeated by the quality guard (the distance model stiffened
    /// tangentially where the step would flip or degrade a triangle,
    /// [`QUALITY_ROUNDS`] per iteration at most); summed over the
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

/// Feature enhancement by vertex flow, Ji et al. 2011 Eq. (1)–(20): moves
/// the free vertices of a triangle mesh toward high-curvature regions by
/// minimising F_em + λ F_sd + μ F_smo in normalised coordinates (see the
/// module documentation for the normalisation, constraints and repair).
/// Returns the new positions (the connectivity is unchanged, the input is
/// not modified) and a report. Reports one progress step per iteration
/// through [`EnhanceOptions::control`] and stops there when cancelled.
///
/// Errors: non-triangle faces, λ ≤ 0, μ < 0, non-finite options, zero
/// iterations or bins, fixed vertices out of range, a failed factorisation,
/// conjugate gradients that did not converge ([`EnhanceSolver::Cg`],
/// [`EnhanceSolver::Amg`], or
/// [`EnhanceSolver::Auto`] above [`AUTO_DIRECT_LIMIT`] free vertices),
/// [`EnhanceError::Cancelled`].
pub fn enhance_features(
    mesh: &SurfaceMesh,
    options: &EnhanceOptions,
) -> Result<Output<EnhanceReport>, EnhanceError> {
    let start = Instant::now();
    validate(mesh, options)?;
    let mut timings = EnhanceTimings::default();
    let edge_length = mean_edge_length(mesh);
    let quality_before = QualityStats::of_mesh(mesh, options.histogram_bins);
    let unchanged = |mut timings: EnhanceTimings| {
        timings.total_s = start.elapsed().as_secs_f64();
        unchanged_output(mesh, options, quality_before.clone(), edge_length, timings)
    };
    if mesh.face_count() == 0 || !(edge_length > 0.0) || !edge_length.is_finite() {
        return Ok(unchanged(timings));
    }
    let problem = FlowProblem::new(mesh, options, edge_length, &mut timings)?;
    if problem.layout.free.is_empty() {
        return Ok(unchanged(timings));
    }
    let t = Instant::now();
    let input_surface = surface::InputSurface::new(mesh, &problem.reference);
    timings.repair_s += t.elapsed().as_secs_f64();
    let mut flow = Flow::new(&problem);
    let total = options.iterations as u64;
    for iteration in 0..options.iterations {
        options
            .control
            .step("iterations", iteration as u64, total)?;
        flow.iterate(&problem, &input_surface, iteration, &mut timings)?;
    }
    options.control.progress("iterations", total, total);
    let positions = problem.to_input_units(&flow.current);
    let mut output = flow.report(&problem, positions, quality_before)?;
    let solver = &flow.solver.stats;
    timings.assembly_s += solver.assembly_s;
    timings.factorisation_s += solver.factorisation_s;
    timings.solve_s += solver.solve_s;
    timings.total_s = start.elapsed().as_secs_f64();
    output.report.timings = timings;
    Ok(output)
}

/// The output of a run that moves nothing: the input positions and a
/// report of zero motion.
fn unchanged_output(
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

/// What stays fixed over the iterations of the vertex flow: the mesh in
/// normalised coordinates x' = (x − c) / ē, its input curvature, the
/// unknowns, the distance model F_sd and the input faces of the repair.
struct FlowProblem<'a> {
    mesh: &'a SurfaceMesh,
    options: &'a EnhanceOptions,
    /// c of the normalisation.
    centroid: Vec3,
    /// ē of the normalisation.
    edge_length: f64,
    /// Input positions, normalised.
    reference: Vec<Vec3>,
    /// The mesh at the normalised positions (curvature of later iterations
    /// is computed on a copy of it).
    normalised: SurfaceMesh,
    input_curvature: PrincipalCurvatures,
    layout: system::Layout,
    /// The boundary curves of the input (module `boundary`).
    boundary: boundary::BoundaryCurves,
    /// The free vertices off the boundary (projected onto the input
    /// surface) and on it (projected onto the boundary curve).
    interior_free: Vec<u32>,
    boundary_free: Vec<u32>,
    distance: system::DistanceModel,
    /// Share of the free vertices with a tangential direction F_sd leaves
    /// free ([`AUTO_SOFT_SHARE`]).
    soft_share: f64,
    input_faces: repair::InputFaces,
}

impl<'a> FlowProblem<'a> {
    /// Normalises the input, computes its curvature and finds the unknowns
    /// (free vertices: not a corner of the boundary, not pinned, not listed in
    /// [`EnhanceOptions::fixed`], with a normal and principal directions).
    fn new(
        mesh: &'a SurfaceMesh,
        options: &'a EnhanceOptions,
        edge_length: f64,
        timings: &mut EnhanceTimings,
    ) -> Result<FlowProblem<'a>, EnhanceError> {
        let input = mesh.positions();
        let n = mesh.vertex_count();
        let centroid = input.iter().copied().sum::<Vec3>() / n as f64;
        let reference: Vec<Vec3> = input
            .iter()
            .map(|&x| (x - centroid) / edge_length)
            .collect();
        let mut normalised = mesh.clone();
        normalised.set_positions(reference.clone())?;
        let t = Instant::now();
        let input_curvature = principal_curvatures_rusinkiewicz(&normalised);
        timings.curvature_s += t.elapsed().as_secs_f64();
        let boundary = boundary::BoundaryCurves::new(mesh, &reference);
        // boundary vertices slide along the boundary curve where there is a
        // projection to keep them on it (the paper's method keeps them)
        let sliding = options.projection != Projection::None;
        let mut is_fixed = vec![false; n];
        for v in mesh.vertices() {
            let i = v.idx();
            let stays_on_boundary = mesh.is_boundary_vertex(v)
                && (!sliding || !boundary.is_on(i) || boundary.is_corner(i));
            is_fixed[i] = stays_on_boundary
                || mesh.is_pinned(v)
                || input_curvature.normals[i] == Vec3::ZERO
                || input_curvature.d1[i] == Vec3::ZERO;
        }
        for v in &options.fixed {
            is_fixed[v.idx()] = true;
        }
        let layout = system::Layout::new(mesh, &is_fixed);
        let (boundary_free, interior_free): (Vec<u32>, Vec<u32>) = layout
            .free
            .iter()
            .copied()
            .partition(|&v| boundary.is_on(v as usize));
        let distance =
            system::DistanceModel::new(&input_curvature, &layout, &boundary, options.lambda);
        let soft_share = distance.soft_share(options.lambda);
        let input_faces = repair::InputFaces::of(&normalised);
        Ok(FlowProblem {
            mesh,
            options,
            centroid,
            edge_length,
            reference,
            normalised,
            input_curvature,
            layout,
            boundary,
            interior_free,
            boundary_free,
            distance,
            soft_share,
            input_faces,
        })
    }

    /// Normalised positions back in input units; fixed vertices keep their
    /// input bits (so does a free vertex whose result is not finite).
    fn to_input_units(&self, current: &[Vec3]) -> Vec<Vec3> {
        let mut positions = self.mesh.positions().to_vec();
        for &v in &self.layout.free {
            let v = v as usize;
            let x = self.centroid + current[v] * self.edge_length;
            if x.is_finite() {
                positions[v] = x;
            }
        }
        positions
    }
}

/// The state of the vertex flow between iterations.
struct Flow {
    /// Normalised positions.
    current: Vec<Vec3>,
    solver: StagedSolver,
    flipped_triangles: usize,
    degraded_triangles: usize,
    backtracked: Vec<bool>,
    /// Solves repeated by the quality guard.
    quality_resolves: usize,
}

impl Flow {
    fn new(problem: &FlowProblem<'_>) -> Flow {
        Flow {
            current: problem.reference.clone(),
            solver: StagedSolver::new(),
            flipped_triangles: 0,
            degraded_triangles: 0,
            backtracked: vec![false; problem.reference.len()],
            quality_resolves: 0,
        }
    }

    /// One iteration: curvature of the current mesh (the input's in the
    /// first), the system of Eq. (20), its least-squares solution
    /// ([`crate::solve::StagedSolver`]), the projection onto the input
    /// surface, the quality guard's re-solves and the repair of flipped or
    /// degraded triangles (module documentation, "Triangle quality").
    fn iterate(
        &mut self,
        problem: &FlowProblem<'_>,
        input_surface: &surface::InputSurface<'_>,
        iteration: usize,
        timings: &mut EnhanceTimings,
    ) -> Result<(), EnhanceError> {
        let options = problem.options;
        let layout = &problem.layout;
        let recomputed;
        let curvature = if iteration == 0 {
            &problem.input_curvature
        } else {
            let t = Instant::now();
            let mut work = problem.normalised.clone();
            work.set_positions(self.current.clone())?;
            recomputed = principal_curvatures_rusinkiewicz(&work);
            timings.curvature_s += t.elapsed().as_secs_f64();
            &recomputed
        };
        // the quality guard: where the step would flip a triangle or drop
        // it below the quality floor, the distance model of its vertices is
        // stiffened tangentially and the system solved again (warm-started
        // at the last solution)
        let mut stiffened: Option<system::DistanceModel> = None;
        let mut floor: Vec<f64> = Vec::new();
        let mut guess: Vec<f64> = layout
            .free
            .iter()
            .flat_map(|&v| self.current[v as usize].to_array())
            .collect();
        let mut round = 0;
        let target = loop {
            let distance = stiffened.as_ref().unwrap_or(&problem.distance);
            let (x, target) = self.solve_and_project(
                problem,
                input_surface,
                curvature,
                distance,
                guess,
                timings,
            )?;
            if round == QUALITY_ROUNDS || !(options.mu > 0.0) {
                break target;
            }
            let bad = repair::bad_face_vertices(problem.mesh, &problem.input_faces, &target);
            let bad: Vec<usize> = bad.into_iter().filter_map(|v| layout.free_of(v)).collect();
            if bad.is_empty() {
                break target;
            }
            if floor.is_empty() {
                floor = vec![0.0; layout.free.len()];
            }
            for f in bad {
                floor[f] = (QUALITY_FLOOR_GROWTH * floor[f]).max(1.0);
            }
            stiffened = Some(system::DistanceModel::with_floor(
                &problem.input_curvature,
                layout,
                &problem.boundary,
                options.lambda,
                &floor,
            ));
            self.quality_resolves += 1;
            guess = x;
            round += 1;
        };
        let mut target = target;
        let t = Instant::now();
        let outcome = repair::repair_flips(
            problem.mesh,
            &problem.input_faces,
            &problem.boundary,
            &self.current,
            &mut target,
        );
        self.flipped_triangles += outcome.flipped;
        self.degraded_triangles += outcome.degraded;
        for v in outcome.backtracked {
            self.backtracked[v] = true;
        }
        self.current = target;
        timings.repair_s += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// The system of Eq. (20) with the distance model `distance`,
    /// its least-squares solution from `guess` ([`crate::solve::StagedSolver`])
    /// and the projection of the free vertices onto the input surface (and
    /// boundary): the solution vector and the projected positions.
    fn solve_and_project(
        &mut self,
        problem: &FlowProblem<'_>,
        input_surface: &surface::InputSurface<'_>,
        curvature: &PrincipalCurvatures,
        distance: &system::DistanceModel,
        guess: Vec<f64>,
        timings: &mut EnhanceTimings,
    ) -> Result<(Vec<f64>, Vec<Vec3>), EnhanceError> {
        let options = problem.options;
        let layout = &problem.layout;
        let t = Instant::now();
        let system = system::assemble(
            layout,
            curvature,
            &problem.boundary,
            distance,
            &self.current,
            &problem.reference,
            options.mu,
            REGULARISATION,
        )?;
        timings.assembly_s += t.elapsed().as_secs_f64();
        // the factored bi-Laplacian preconditioner (needs μ > 0: with μ = 0
        // there is no smoothness model)
        let epsilon = system.epsilon;
        let build = |jacobi: BlockJacobi| -> Result<Box<dyn Preconditioner + '_>, SolveError> {
            Ok(Box::new(precondition::FactoredPreconditioner::new(
                layout, curvature, distance, jacobi, options.mu, epsilon,
            )?))
        };
        let multigrid: Option<&MultigridBuilder<'_>> = (options.mu > 0.0).then_some(&build);
        let x = self.solver.solve(
            &system,
            multigrid,
            guess,
            &StagedOptions {
                solver: options.solver,
                skip_jacobi: problem.soft_share > AUTO_SOFT_SHARE,
                tolerance: options.cg_tolerance,
                max_iterations: options.cg_max_iterations,
            },
        )?;
        let t = Instant::now();
        let mut target = self.current.clone();
        for (f, &v) in layout.free.iter().enumerate() {
            target[v as usize] = Vec3::new(x[3 * f], x[3 * f + 1], x[3 * f + 2]);
        }
        input_surface.project(&problem.interior_free, &mut target, options.projection);
        if options.projection != Projection::None {
            problem
                .boundary
                .project(&problem.boundary_free, &mut target);
        }
        timings.repair_s += t.elapsed().as_secs_f64();
        Ok((x, target))
    }

    /// The output: `positions` (input units) and the report of the run
    /// (timings are filled in by the caller).
    fn report(
        &self,
        problem: &FlowProblem<'_>,
        positions: Vec<Vec3>,
        quality_before: QualityStats,
    ) -> Result<Output<EnhanceReport>, EnhanceError> {
        let (mesh, options) = (problem.mesh, problem.options);
        let input = mesh.positions();
        let n = mesh.vertex_count();
        let (mut max_d, mut sum_d) = (0.0f64, 0.0);
        for (a, b) in positions.iter().zip(input) {
            let d = a.distance(*b);
            max_d = max_d.max(d);
            sum_d += d;
        }
        let (max_distance_to_input, mean_distance_to_input) =
            distance_to_input(mesh, &positions, &problem.layout.free);
        let mut out_mesh = mesh.clone();
        out_mesh.set_positions(positions.clone())?;
        let stats = &self.solver.stats;
        Ok(Output {
            report: EnhanceReport {
                vertices: n,
                free_vertices: problem.layout.free.len(),
                iterations: options.iterations,
                lambda: options.lambda,
                mu: options.mu,
                flipped_triangles: self.flipped_triangles,
                degraded_triangles: self.degraded_triangles,
                backtracked_vertices: self.backtracked.iter().filter(|b| **b).count(),
                quality_resolves: self.quality_resolves,
                quality_before,
                quality_after: QualityStats::of_mesh(&out_mesh, options.histogram_bins),
                max_displacement: max_d,
                mean_displacement: sum_d / n as f64,
                max_distance_to_input,
                mean_distance_to_input,
                edge_length: problem.edge_length,
                solver: options.solver,
                projection: options.projection,
                cg_iterations: stats.cg_iterations,
                cg_relative_residual: stats.cg_relative_residual,
                direct_fallbacks: stats.direct_fallbacks,
                timings: EnhanceTimings::default(),
            },
            positions,
        })
    }
}

/// Largest and mean distance of the `free` vertices at `positions` to the
/// input surface near them (the input faces are searched ring by ring
/// around the vertex's input position until a ring brings no nearer face,
/// at most [`surface::SEARCH_RINGS`] rings): an upper bound of the distance
/// to the whole input surface, which another part of the surface may come
/// nearer to.
fn distance_to_input(mesh: &SurfaceMesh, positions: &[Vec3], free: &[u32]) -> (f64, f64) {
    let queries: Vec<(u32, Vec3)> = free.iter().map(|&v| (v, positions[v as usize])).collect();
    let distances: Vec<f64> = surface::nearest_input_faces(mesh, mesh.positions(), &queries)
        .iter()
        .map(|n| n.map_or(0.0, |n| n.distance_squared.sqrt()))
        .collect();
    let max = distances.iter().copied().fold(0.0, f64::max);
    let mean = if distances.is_empty() {
        0.0
    } else {
        distances.iter().sum::<f64>() / distances.len() as f64
    };
    (max, mean)
}

fn validate(mesh: &SurfaceMesh, o: &EnhanceOptions) -> Result<(), EnhanceError> {
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
