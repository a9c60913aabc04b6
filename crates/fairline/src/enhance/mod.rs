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
mod flow;
mod junction;
mod options;
mod precondition;
mod repair;
mod report;
mod surface;
mod system;
#[cfg(test)]
mod tests;

use crate::Output;
use crate::geom::mean_edge_length;
use crate::mesh::{MeshError, SurfaceMesh};
pub use crate::solve::NormalSolver as EnhanceSolver;
use crate::solve::SolveError;
pub use crate::solve::{AUTO_DIRECT_LIMIT, AUTO_JACOBI_BUDGET, AUTO_JACOBI_CHECK};
pub use crease::{FEATURE_ANGLE_DEG, FLAT_SIDE_DEG, SNAP_DISTANCE};
pub use repair::QUALITY_FLOOR;
use std::time::Instant;
pub use surface::{CREASE_ANGLE_DEG, PHONG_ALPHA, Projection};
use thiserror::Error;

pub use options::EnhanceOptions;
pub use report::{EnhanceReport, EnhanceTimings, QualityStats};

use flow::{Flow, FlowProblem};
use options::validate;
use report::unchanged_output;

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
