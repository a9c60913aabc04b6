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
//!   at 1M; the factorisation was 84–91 % of the time and 1M did not fit.
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
//! **Constraints and repair.** Boundary vertices, isolated vertices,
//! vertices without a normal and the vertices listed in
//! [`EnhanceOptions::fixed`] are not unknowns; their output positions are the
//! input values, bit for bit. A tiny Tikhonov term ε‖v − p‖² (ε = 1e-10 in
//! normalised units) keeps the normal matrix positive definite when F_sd
//! leaves a tangential direction free. After each solve, triangles whose
//! normal turned against the input's (or collapsed), or whose quality fell
//! below [`QUALITY_FLOOR`] of the input's, are repaired by halving the steps
//! of their vertices, and after [`REPAIR_HALVINGS`] rounds by resetting
//! them, until no triangle is flipped or degraded (§5: "we rectify the
//! topological errors in the post-processing").
//!
//! **Projection onto the input surface** (issue #21 item 2; module
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
//! Sharp creases are not reconstructed (the fit rounds them).
//!
//! **Triangle quality.** μ keeps the mean quality (the paper's Fig. 5);
//! the repair also shortens the steps of the vertices of any triangle whose
//! quality 2r/R falls below [`QUALITY_FLOOR`] (¼) of its input quality, so
//! no triangle collapses to a sliver: every output triangle keeps at least
//! a quarter of its input quality (reported as `degraded_triangles`).
//!
//! **Iterations.** With `iterations > 1` curvature is recomputed on the
//! current mesh for F_em and F_smo, while F_sd keeps the input positions and
//! input frames as its distance reference.

#[cfg(test)]
mod accuracy_tests;
#[cfg(test)]
mod bitwise_tests;
#[cfg(test)]
pub(crate) use bitwise_tests::checksum as bitwise_checksum;
mod precondition;
mod repair;
mod surface;
mod system;
#[cfg(test)]
mod tests;

use crate::Vec3;
use crate::geom::{mean_edge_length, principal_curvatures_rusinkiewicz, triangle_qualities};
use crate::mesh::{MeshError, SurfaceMesh, VertexId};
use crate::solve::{
    BlockJacobi, CgOptions, CgReport, CholeskySolver, Preconditioner, SolveError, pcg_with,
};
pub use repair::QUALITY_FLOOR;
use serde::Serialize;
use std::time::Instant;
pub use surface::{CREASE_ANGLE_DEG, PHONG_ALPHA, Projection};
use thiserror::Error;

/// Rounds of step halving for the vertices of flipped triangles before
/// their steps are reset to zero.
pub const REPAIR_HALVINGS: usize = 8;

/// Default relative residual at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-12;

/// Iterations of block-Jacobi conjugate gradients under
/// [`EnhanceSolver::Auto`] before they switch to the multigrid-preconditioned
/// ones: where the curvature holds every tangential direction (tori of 10k
/// to 1M vertices) block Jacobi converges in about 25 iterations, each
/// cheaper than a preconditioned one and without a setup; where it does not
/// (flat or cylindrical parts) it would need hundreds to thousands.
pub const AUTO_JACOBI_BUDGET: usize = 40;

/// Under [`EnhanceSolver::Auto`], block Jacobi is skipped when more than
/// this share of the free vertices have a tangential direction that the
/// distance term F_sd holds by less than [`SOFT_COEFFICIENT`] of its normal
/// weight (a principal curvature below 1 % of the largest: flat and
/// cylindrical parts), which only the F_smo bi-Laplacian holds.
pub const AUTO_SOFT_SHARE: f64 = 0.1;

/// The coefficient c = d|k| / (1 + d|k|) of Ji et al. Eq. (6) below which
/// a tangential direction counts as free for [`AUTO_SOFT_SHARE`].
pub const SOFT_COEFFICIENT: f64 = 0.01;

/// Under [`EnhanceSolver::Auto`], block-Jacobi conjugate gradients give up
/// early when, every this many iterations, their mean rate over the last
/// ones predicts more than [`AUTO_JACOBI_BUDGET`] iterations
/// ([`CgOptions::hopeless_after`]).
pub const AUTO_JACOBI_CHECK: usize = 4;

/// Largest number of free vertices for which [`EnhanceSolver::Auto`] falls
/// back to the direct solver when conjugate gradients fail: the Cholesky
/// factor of 300k vertices takes about 6 GB; beyond, it does not fit a
/// typical machine.
pub const AUTO_DIRECT_LIMIT: usize = 300_000;

/// Default iteration limit of conjugate gradients.
pub const CG_MAX_ITERATIONS: usize = 5000;

/// Weight ε of the regularisation ε‖v − p‖² (normalised units).
const REGULARISATION: f64 = 1e-10;

/// Options of [`enhance_features`]; `Default` gives the paper's λ = 1,
/// μ = 0.5 and one iteration.
#[derive(Clone, Debug, PartialEq)]
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
    /// Vertices that must not move (in addition to the boundary).
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
}

/// Solver of the least-squares system of Eq. (20); both compute the same
/// least-squares solution (to the tolerance of conjugate gradients).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EnhanceSolver {
    /// [`EnhanceSolver::Amg`] on meshes with large flat or cylindrical
    /// parts ([`AUTO_SOFT_SHARE`]); elsewhere block-Jacobi conjugate
    /// gradients for at most [`AUTO_JACOBI_BUDGET`] iterations (fewer when
    /// their progress predicts far more), then, from where they stopped,
    /// conjugate gradients preconditioned as [`EnhanceSolver::Amg`] up to
    /// [`EnhanceOptions::cg_max_iterations`], then (should they fail, and
    /// for n ≤ [`AUTO_DIRECT_LIMIT`] free vertices) the direct solver.
    Auto,
    /// Sparse Cholesky factorisation of the normal matrix AᵀA + εI.
    Direct,
    /// Block-Jacobi preconditioned conjugate gradients on the normal
    /// equations, matrix-free, warm-started at the current positions.
    Cg,
    /// Conjugate gradients preconditioned by block Jacobi plus the factored
    /// bi-Laplacian model H Q̂ H of the smoothness and edge-metric rows,
    /// with smoothed-aggregation multigrid cycles for H (module
    /// documentation), warm-started at the current positions, up to
    /// [`EnhanceOptions::cg_max_iterations`]; an error if they do not
    /// converge. The iteration count hardly grows with the mesh, also on
    /// flat and cylindrical parts. Needs μ > 0 (with μ = 0 it is block
    /// Jacobi).
    Amg,
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

/// What [`enhance_features`] did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnhanceReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Vertices that were free to move (3 unknowns each).
    pub free_vertices: usize,
    /// Solves performed.
    pub iterations: usize,
    /// Triangles found flipped (normal against the input's, or collapsed)
    /// after a solve and repaired; summed over the iterations.
    pub flipped_triangles: usize,
    /// Triangles found below [`QUALITY_FLOOR`] of their input quality 2r/R
    /// (and not flipped) after a solve and repaired like flipped ones; summed
    /// over the iterations.
    pub degraded_triangles: usize,
    /// Vertices whose step was shortened or undone by the repair.
    pub backtracked_vertices: usize,
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

/// Output of [`enhance_features`].
#[derive(Clone, Debug)]
pub struct Enhanced {
    /// New vertex positions (fixed vertices bit-identical to the input).
    pub positions: Vec<Vec3>,
    /// Report.
    pub report: EnhanceReport,
}

/// Feature enhancement by vertex flow, Ji et al. 2011 Eq. (1)–(20): moves
/// the free vertices of a triangle mesh toward high-curvature regions by
/// minimising F_em + λ F_sd + μ F_smo in normalised coordinates (see the
/// module documentation for the normalisation, constraints and repair).
/// Returns the new positions (the connectivity is unchanged) and a report.
///
/// Errors: non-triangle faces, λ ≤ 0, μ < 0, non-finite options, zero
/// iterations or bins, fixed vertices out of range, a failed factorisation,
/// conjugate gradients that did not converge ([`EnhanceSolver::Cg`],
/// [`EnhanceSolver::Amg`], or
/// [`EnhanceSolver::Auto`] above [`AUTO_DIRECT_LIMIT`] free vertices).
pub fn enhance_features(
    mesh: &SurfaceMesh,
    options: &EnhanceOptions,
) -> Result<Enhanced, EnhanceError> {
    let start = Instant::now();
    validate(mesh, options)?;
    let n = mesh.vertex_count();
    let input = mesh.positions();
    let bins = options.histogram_bins;
    let quality_before = QualityStats::of_mesh(mesh, bins);
    let edge_length = mean_edge_length(mesh);
    let mut timings = EnhanceTimings::default();
    let unchanged = |timings: EnhanceTimings, free: usize| Enhanced {
        positions: input.to_vec(),
        report: EnhanceReport {
            vertices: n,
            free_vertices: free,
            iterations: 0,
            flipped_triangles: 0,
            degraded_triangles: 0,
            backtracked_vertices: 0,
            quality_before: quality_before.clone(),
            quality_after: quality_before.clone(),
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
    };
    if mesh.face_count() == 0 || !(edge_length > 0.0) || !edge_length.is_finite() {
        return Ok(unchanged(timings, 0));
    }

    // Normalised copy of the mesh: x' = (x − c) / ē.
    let centroid = input.iter().copied().sum::<Vec3>() / n as f64;
    let reference: Vec<Vec3> = input
        .iter()
        .map(|&x| (x - centroid) / edge_length)
        .collect();
    let mut work = mesh.clone();
    work.set_positions(reference.clone())?;

    let t = Instant::now();
    let input_curvature = principal_curvatures_rusinkiewicz(&work);
    timings.curvature_s += t.elapsed().as_secs_f64();

    let mut is_fixed = vec![false; n];
    for v in mesh.vertices() {
        let i = v.idx();
        is_fixed[i] = mesh.is_boundary_vertex(v)
            || mesh.is_pinned(v)
            || input_curvature.normals[i] == Vec3::ZERO
            || input_curvature.d1[i] == Vec3::ZERO;
    }
    for v in &options.fixed {
        is_fixed[v.idx()] = true;
    }
    let layout = system::Layout::new(mesh, &is_fixed);
    if layout.free.is_empty() {
        timings.total_s = start.elapsed().as_secs_f64();
        return Ok(unchanged(timings, 0));
    }
    let distance = system::DistanceModel::new(&input_curvature, &layout, options.lambda);
    let soft_share = distance.soft_share(options.lambda);
    let input_faces = repair::InputFaces::of(&work);
    let t = Instant::now();
    let input_surface = surface::InputSurface::new(mesh, &reference);
    timings.repair_s += t.elapsed().as_secs_f64();

    let mut current = reference.clone();
    let mut solver: Option<CholeskySolver> = None;
    let mut flipped_triangles = 0;
    let mut degraded_triangles = 0;
    let (mut cg_iterations, mut cg_residual) = (0usize, 0.0f64);
    let mut direct_fallbacks = 0;
    let mut backtracked = vec![false; n];
    for iteration in 0..options.iterations {
        let curvature = if iteration == 0 {
            input_curvature.clone()
        } else {
            let t = Instant::now();
            work.set_positions(current.clone())?;
            let c = principal_curvatures_rusinkiewicz(&work);
            timings.curvature_s += t.elapsed().as_secs_f64();
            c
        };
        let t = Instant::now();
        let system = system::assemble(
            &layout,
            &curvature,
            &distance,
            &current,
            &reference,
            options.mu,
            REGULARISATION,
        )?;
        timings.assembly_s += t.elapsed().as_secs_f64();

        let nf = layout.free.len();
        let mut guess: Vec<f64> = layout
            .free
            .iter()
            .flat_map(|&v| current[v as usize].to_array())
            .collect();
        let cg = |max_iterations: usize, hopeless_after: usize| CgOptions {
            tolerance: options.cg_tolerance,
            max_iterations,
            block: 3,
            hopeless_after,
        };
        let not_converged = |r: &CgReport| {
            EnhanceError::Solve(SolveError::Backend(format!(
                "conjugate gradients did not reach the relative residual {:e} in {} iterations ({:e}); \
                 try the direct solver",
                options.cg_tolerance, r.iterations, r.relative_residual
            )))
        };
        let mut x = None;
        // block-Jacobi CG: alone (Cg) or as the cheap first attempt (Auto)
        // (μ = 0 leaves no smoothness model for the multigrid preconditioner)
        let jacobi_only = options.solver == EnhanceSolver::Cg
            || (options.solver == EnhanceSolver::Amg && options.mu == 0.0);
        let jacobi_budget = match options.solver {
            _ if jacobi_only => options.cg_max_iterations,
            // many vertices with a free tangential direction: block Jacobi
            // would only lose time before the multigrid takes over
            EnhanceSolver::Auto if options.mu > 0.0 && soft_share > AUTO_SOFT_SHARE => 0,
            EnhanceSolver::Auto => AUTO_JACOBI_BUDGET.min(options.cg_max_iterations),
            _ => 0,
        };
        // one CG run from `guess`: block Jacobi (`None`) or the given
        // preconditioner; counts its iterations, time and residual
        let mut cg_seconds = 0.0;
        let jacobi = BlockJacobi::from_blocks(system.diagonal_blocks(), 3);
        let mut scratch = vec![0.0; 8 * nf];
        let mut run_cg = |guess: &mut [f64],
                          budget: usize,
                          hopeless_after: usize,
                          preconditioner: &dyn Preconditioner|
         -> Result<CgReport, EnhanceError> {
            let t = Instant::now();
            let r = pcg_with(
                |v: &[f64], out: &mut [f64]| system.normal_product(v, out, &mut scratch),
                |r: &[f64], z: &mut [f64]| preconditioner.apply(r, z),
                &system.rhs,
                guess,
                &cg(budget, hopeless_after),
            )?;
            cg_iterations += r.iterations;
            cg_seconds += t.elapsed().as_secs_f64();
            if r.converged {
                cg_residual = cg_residual.max(r.relative_residual);
            }
            Ok(r)
        };
        if jacobi_budget > 0 {
            let hopeless_after = if jacobi_only { 0 } else { AUTO_JACOBI_CHECK };
            let r = run_cg(&mut guess, jacobi_budget, hopeless_after, &jacobi)?;
            if r.converged {
                x = Some(guess.clone());
            } else if jacobi_only {
                return Err(not_converged(&r));
            }
        }
        // CG preconditioned by the factored bi-Laplacian model, warm-started
        // where block Jacobi stopped
        let multigrid = matches!(options.solver, EnhanceSolver::Amg | EnhanceSolver::Auto);
        if x.is_none() && multigrid && options.mu > 0.0 {
            let t = Instant::now();
            let built = precondition::FactoredPreconditioner::new(
                &layout,
                &curvature,
                &distance,
                jacobi.clone(),
                options.mu,
                system.epsilon,
            );
            timings.factorisation_s += t.elapsed().as_secs_f64();
            match built {
                Ok(preconditioner) => {
                    let r = run_cg(&mut guess, options.cg_max_iterations, 0, &preconditioner)?;
                    if r.converged {
                        x = Some(guess.clone());
                    } else if options.solver == EnhanceSolver::Amg || nf > AUTO_DIRECT_LIMIT {
                        return Err(not_converged(&r));
                    }
                }
                // auto: a degenerate model (e.g. a multigrid level that is
                // not positive definite) leaves the direct solve
                Err(e) if options.solver == EnhanceSolver::Amg || nf > AUTO_DIRECT_LIMIT => {
                    return Err(e.into());
                }
                Err(_) => {}
            }
        }
        if x.is_none() && options.solver == EnhanceSolver::Auto && nf > AUTO_DIRECT_LIMIT {
            // μ = 0: no smoothness model to precondition with; block-Jacobi
            // CG continues (the direct factor does not fit)
            let r = run_cg(&mut guess, options.cg_max_iterations, 0, &jacobi)?;
            if !r.converged {
                return Err(not_converged(&r));
            }
            x = Some(guess.clone());
        }
        timings.solve_s += cg_seconds;
        let attempted_cg = jacobi_budget > 0 || multigrid;
        let x = match x {
            Some(x) => x,
            None => {
                if attempted_cg {
                    direct_fallbacks += 1;
                }
                let t = Instant::now();
                let matrix = system.normal_matrix()?;
                timings.assembly_s += t.elapsed().as_secs_f64();
                let t = Instant::now();
                let refactored = match solver.as_mut() {
                    Some(s) => s.refactor(matrix.as_ref()).is_ok(),
                    None => false,
                };
                if !refactored {
                    solver = Some(CholeskySolver::new(matrix.as_ref())?);
                }
                timings.factorisation_s += t.elapsed().as_secs_f64();
                let t = Instant::now();
                let mut x = system.rhs;
                if let Some(s) = solver.as_ref() {
                    s.solve_in_place(&mut x)?;
                }
                timings.solve_s += t.elapsed().as_secs_f64();
                x
            }
        };

        let t = Instant::now();
        let mut target = current.clone();
        for (f, &v) in layout.free.iter().enumerate() {
            target[v as usize] = Vec3::new(x[3 * f], x[3 * f + 1], x[3 * f + 2]);
        }
        input_surface.project(&layout.free, &mut target, options.projection);
        let outcome = repair::repair_flips(mesh, &input_faces, &current, &mut target);
        flipped_triangles += outcome.flipped;
        degraded_triangles += outcome.degraded;
        for v in outcome.backtracked {
            backtracked[v] = true;
        }
        current = target;
        timings.repair_s += t.elapsed().as_secs_f64();
    }

    // Back to input units; fixed vertices keep their input bits.
    let mut positions = input.to_vec();
    for &v in &layout.free {
        let v = v as usize;
        let x = centroid + current[v] * edge_length;
        if x.is_finite() {
            positions[v] = x;
        }
    }
    let (mut max_d, mut sum_d) = (0.0f64, 0.0);
    for (a, b) in positions.iter().zip(input) {
        let d = a.distance(*b);
        max_d = max_d.max(d);
        sum_d += d;
    }
    let (max_distance_to_input, mean_distance_to_input) =
        distance_to_input(mesh, &positions, &layout.free);
    let mut out_mesh = mesh.clone();
    out_mesh.set_positions(positions.clone())?;
    timings.total_s = start.elapsed().as_secs_f64();
    Ok(Enhanced {
        positions,
        report: EnhanceReport {
            vertices: n,
            free_vertices: layout.free.len(),
            iterations: options.iterations,
            flipped_triangles,
            degraded_triangles,
            backtracked_vertices: backtracked.iter().filter(|b| **b).count(),
            quality_before,
            quality_after: QualityStats::of_mesh(&out_mesh, bins),
            max_displacement: max_d,
            mean_displacement: sum_d / n as f64,
            max_distance_to_input,
            mean_distance_to_input,
            edge_length,
            solver: options.solver,
            projection: options.projection,
            cg_iterations,
            cg_relative_residual: cg_residual,
            direct_fallbacks,
            timings,
        },
    })
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
