//! Fair surfaces with G¹ boundary conditions by Δ_B H = 0 (Schneider and
//! Kobbelt; Grüner thesis §3.4, Eq. (25)–(29)).

use super::{Constraints, SmoothError, SmoothReport, StopReason, max_distance, roles, setters};
use crate::geom;
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::ConstrainedSolver;
use crate::{Control, Output, Vec3};

mod boundary;
mod curvature;
mod newton;

use boundary::g1_normals;
use curvature::{Evaluator, Unknowns, harmonic_mean_curvature};
use newton::{NewtonOutcome, finite_difference_jacobian, jacobian_pattern, newton_step};

/// Options of [`schneider_kobbelt`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SchneiderKobbeltOptions {
    /// Upper bound on the outer iterations M_k → M_{k+1}.
    pub max_iterations: usize,
    /// Stop when the largest normal move divided by the mean edge length is
    /// below ε.
    pub epsilon: f64,
    /// Further fixed vertices (bit-identical in the output). The boundary
    /// vertices and their normals are always fixed (the G¹ boundary
    /// condition).
    pub fixed: Vec<VertexId>,
    /// G¹ normals of constrained vertices (normalised). Constrained
    /// boundary vertices not listed get the normal of a quadric fit over
    /// their input `normal_fit_rings`-ring ([`geom::quadric_fit_rings`]),
    /// falling back to the vertex normal, made perpendicular to the
    /// boundary curve (its tangent, or both one-sided tangents at a
    /// corner): a surface through the fixed boundary cannot have a normal
    /// with a component along it. Given normals are taken as they are.
    pub normals: Vec<(VertexId, Vec3)>,
    /// Rings of the quadric fit ([`geom::quadric_fit_rings`]) that
    /// estimates the G¹ normals not given in `normals`; `None` chooses them
    /// from the mesh: a fit radius of 0.15 × the bounding-box diagonal,
    /// i.e. ⌈0.15 · diagonal / ē⌉ rings, within 2..=12. A boundary vertex
    /// sees half a disc, so a two-ring fit on a noisy mesh tilts the normal
    /// by about σ/h (0.2 rad for noise of 0.2 edge lengths) and Δ_B H = 0
    /// then bends the whole patch to honour it; wider rings average the
    /// noise out but add the bias of the unmodelled higher-order terms.
    /// Where the true normals are known, pass them in `normals`: with exact
    /// normals the method is exact on a sphere cap.
    pub normal_fit_rings: Option<usize>,
    /// Most work, in evaluations of Δ_B H at one vertex (a sweep costs
    /// about (probe groups of the Jacobian + line-search trials) ×
    /// vertices): a sweep that would take the total beyond it is not
    /// started ([`StopReason::WorkLimit`]).
    pub max_work: u64,
    /// Progress callback and cancel flag (one step per outer iteration).
    pub control: Control,
}

/// Sweeps over which the merit must fall by [`STAGNATION_DECREASE`].
pub const STAGNATION_WINDOW: usize = 5;
/// Least relative decrease of the merit over [`STAGNATION_WINDOW`] sweeps
/// before the iteration counts as stagnated: 10 % in five sweeps is a
/// linear rate of 2 % a sweep, which would need hundreds of sweeps to
/// converge. (A noisy 41² sphere cap crawls at 5 % a sweep for 17 sweeps
/// before the Newton steps take over; the cow "Spot" falls to 1 % a sweep
/// after 25 sweeps and stays there.)
pub const STAGNATION_DECREASE: f64 = 0.1;
/// A residual max |H − H̃|·ē this many times the smallest one so far
/// counts as diverged (the merit falls at every accepted step, the
/// largest residual may rise for a sweep: 1.4× on the 41² cap).
pub const DIVERGENCE_FACTOR: f64 = 4.0;
/// Default of [`SchneiderKobbeltOptions::max_work`]: 10⁷ evaluations of
/// Δ_B H at a vertex, about ten seconds (a sweep over 2,930 vertices costs
/// about 1.5·10⁵, one over 36,000 about 1.5·10⁶).
pub const DEFAULT_MAX_WORK: u64 = 10_000_000;

impl Default for SchneiderKobbeltOptions {
    fn default() -> Self {
        SchneiderKobbeltOptions {
            max_iterations: 50,
            epsilon: 1e-5,
            fixed: Vec::new(),
            normals: Vec::new(),
            normal_fit_rings: None,
            max_work: DEFAULT_MAX_WORK,
            control: Control::default(),
        }
    }
}

setters!(SchneiderKobbeltOptions {
    max_iterations: usize,
    epsilon: f64,
    fixed: Vec<VertexId>,
    normals: Vec<(VertexId, Vec3)>,
    normal_fit_rings: Option<usize>,
    max_work: u64,
    control: Control,
});

/// Why [`schneider_kobbelt`] stopped watching its sweeps: the merit
/// history over the last [`STAGNATION_WINDOW`] sweeps, the smallest
/// residual so far and the work done.
struct Progress {
    vertices: u64,
    /// Probe groups of the Jacobian: the evaluations of a sweep at least.
    groups: u64,
    max_work: u64,
    merits: Vec<f64>,
    best_residual: f64,
    /// Evaluations at the start of the last sweep and how many it took.
    last_start: u64,
    last_cost: u64,
    /// Vertex evaluations so far (evaluations × vertices).
    work: u64,
}

impl Progress {
    fn new(vertices: usize, groups: usize, max_work: u64) -> Progress {
        Progress {
            vertices: vertices as u64,
            groups: groups as u64,
            max_work,
            merits: Vec::new(),
            best_residual: f64::INFINITY,
            last_start: 0,
            last_cost: 0,
            work: 0,
        }
    }

    /// Called at the head of every sweep with the current merit, residual
    /// and evaluation count: why to stop, if the sweeps stagnated, diverged
    /// or the next sweep would exceed the work bound.
    fn stop(&mut self, merit: f64, residual: f64, evaluations: u64) -> Option<StopReason> {
        self.last_cost = evaluations - self.last_start;
        self.last_start = evaluations;
        self.work = evaluations.saturating_mul(self.vertices);
        self.merits.push(merit);
        if !residual.is_finite() || residual > DIVERGENCE_FACTOR * self.best_residual {
            return Some(StopReason::Diverged);
        }
        self.best_residual = self.best_residual.min(residual);
        let k = self.merits.len();
        if k > STAGNATION_WINDOW {
            let before = self.merits[k - 1 - STAGNATION_WINDOW];
            if merit > (1.0 - STAGNATION_DECREASE) * before {
                return Some(StopReason::Stagnated);
            }
        }
        let sweep = self.last_cost.max(self.groups + 1);
        let next = self
            .work
            .saturating_add(sweep.saturating_mul(self.vertices));
        (next > self.max_work).then_some(StopReason::WorkLimit)
    }
}

/// Schneider–Kobbelt fairing of a triangle mesh with G¹ boundary (fixed
/// boundary vertices and normals; Grüner §3.4). The fourth-order Δ_B H = 0
/// is factorised into two nested second-order problems per outer iteration
/// M_k → M_{k+1}:
///
/// 1. H̃ solves the discrete Dirichlet problem Σ_j (cot α_j + cot β_j)
///    (H̃_i − H̃_j) = 0 at the free vertices (Eq. (26)–(27), sparse Cholesky,
///    symbolic factorisation reused), with boundary values H_b given by the
///    Moreton–Séquin estimate (Eq. (28) and the Euler-formula fit) at each
///    constrained vertex with its *fixed* G¹ normal and its current
///    neighbours — this is where the normal condition enters;
/// 2. every free vertex moves along its normal, q_i + t_i n_i, so that its
///    Moreton–Séquin mean curvature equals H̃_i (Eq. (29)). Moving q_j
///    changes κ̃_j at q_i by the same order as moving q_i, and the normals,
///    fit weights and cotangent weights move too, so the t_i are solved
///    together: one Newton step on the residuals Σ_j w_ij (H_i − H_j) of the
///    free vertices, with the Jacobian by finite differences of the whole
///    evaluation, coloured so that vertices more than four rings apart are
///    probed together (a residual depends on its two-ring only), and solved
///    by sparse least squares (`solve::least_squares`). |t_i| is limited to
///    half the mean length of its edges. (A vertex-by-vertex update converges
///    like Jacobi on a Laplacian; a hand linearisation that freezes normals
///    and weights gave no descent direction on a 61×61 dented roof.)
///
/// Closed meshes and meshes constrained only by fixed vertices: a free
/// component that touches no constrained vertex has no Dirichlet data for
/// H̃; its harmonic functions are the constants and H̃ is the area-weighted
/// mean of H there. The Newton system is then rank deficient (a rigid
/// motion or a scaling along the normals keeps Δ_B H = 0) and is solved with
/// a Levenberg–Marquardt damping of 1e-10 relative (the least-norm step); a
/// noisy closed sphere converges back onto a sphere.
///
/// Iterates until max |t| / ē < ε (ē the input mean edge length), or until
/// the Newton step itself is below ε (the mesh already satisfies
/// Δ_B H = 0 to round-off, e.g. a perfect sphere: converged, 0 iterations); the report
/// gives the accepted iterations and the final residual max |H − H̃| · ē.
/// A step is accepted only if it lowers the merit Σ_i (Σ_j w_ij (H_i − H_j))²;
/// when no step length down to 1/64 does, the iteration stops unconverged
/// instead of drifting ([`StopReason::NoDescent`]). It also stops
/// unconverged, with the reason in the report's `stop_reason`, when the
/// merit fell by less than [`STAGNATION_DECREASE`] over the last
/// [`STAGNATION_WINDOW`] sweeps ([`StopReason::Stagnated`]), when the
/// residual grew beyond [`DIVERGENCE_FACTOR`] times its smallest value
/// ([`StopReason::Diverged`]), when the next sweep would take the work
/// beyond `opts.max_work` ([`StopReason::WorkLimit`]) or after
/// `opts.max_iterations` sweeps ([`StopReason::MaxIterations`]).
pub fn schneider_kobbelt(
    mesh: &SurfaceMesh,
    opts: &SchneiderKobbeltOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    mesh.require_triangles()?;
    let c = Constraints {
        fixed: opts.fixed.clone(),
        fix_boundary: true,
        ..Constraints::default()
    };
    let roles = roles(mesh, &c)?;
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let ebar = geom::mean_edge_length(mesh);
    let nbrs: Vec<Vec<usize>> = mesh
        .vertices()
        .map(|v| mesh.one_ring(v).map(|u| u.idx()).collect())
        .collect();
    let normals0 = g1_normals(mesh, &roles, opts, ebar)?;
    let unknowns = Unknowns::new(&roles, &nbrs);
    let m = unknowns.vertices.len();
    let any_floating = unknowns.any_floating();
    let field_fixed = unknowns.field_fixed();
    let evaluator = Evaluator {
        mesh,
        roles: &roles,
        normals0: &normals0,
        nbrs: &nbrs,
        unknown: &unknowns.vertices,
        evaluations: std::cell::Cell::new(0),
    };
    let (support, groups) = jacobian_pattern(&nbrs, &unknowns);
    // current positions (the connectivity is the input's)
    let mut work: Vec<Vec3> = input.clone();
    let mut solver: Option<ConstrainedSolver> = None;
    let mut iterations = 0;
    let mut converged = m == 0 || !(ebar > 0.0);
    let mut stop = if converged {
        StopReason::Converged
    } else {
        StopReason::MaxIterations
    };
    let mut residual = 0.0;
    let mut last_step = f64::INFINITY;
    let mut ev = evaluator.evaluate(&work);
    let mut progress = Progress::new(mesh.vertex_count(), groups.len(), opts.max_work);
    while !converged {
        opts.control
            .step("iterations", iterations as u64, opts.max_iterations as u64)?;
        let htilde =
            harmonic_mean_curvature(mesh, &work, &ev, &unknowns, &field_fixed, &mut solver)?;
        let h_of = |i: usize| ev.fits[i].unwrap_or(0.0);
        residual = unknowns
            .vertices
            .iter()
            .map(|&i| htilde[i] - h_of(i))
            .fold(0.0f64, |a, r| a.max(r.abs()))
            * ebar;
        if last_step < opts.epsilon {
            converged = true;
            stop = StopReason::Converged;
            break;
        }
        if iterations >= opts.max_iterations {
            break;
        }
        if let Some(reason) = progress.stop(ev.merit, residual, evaluator.evaluations.get()) {
            stop = reason;
            break;
        }
        let jac = finite_difference_jacobian(&evaluator, &ev, &work, &support, &groups, ebar);
        match newton_step(
            &evaluator,
            &ev,
            &work,
            &jac,
            any_floating,
            ebar,
            opts.epsilon,
        )? {
            NewtonOutcome::Accepted(trial, e, worst) => {
                iterations += 1;
                work = trial;
                ev = e;
                last_step = worst;
            }
            // the loop head computes the final residual and stops
            NewtonOutcome::BelowEpsilon => last_step = 0.0,
            NewtonOutcome::NoDescent => {
                stop = StopReason::NoDescent;
                break;
            }
        }
    }
    let report = SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume_at(mesh, &work),
        max_displacement: max_distance(&work, &input),
        converged,
        residual: Some(residual),
        stop_reason: Some(stop),
        taubin: None,
    };
    Ok(Output {
        positions: work,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stopping rules on given merit and residual sequences: a merit
    /// that falls by less than [`STAGNATION_DECREASE`] over
    /// [`STAGNATION_WINDOW`] sweeps stagnates (by more it goes on), a
    /// residual beyond [`DIVERGENCE_FACTOR`] times its smallest value
    /// diverges, a non-finite one too, and a sweep that would pass the work
    /// bound is not started.
    #[test]
    fn sweeps_stop_when_they_stagnate_diverge_or_would_exceed_the_work() {
        let unbounded = || Progress::new(10, 3, u64::MAX);
        // 3 % a sweep: 14 % over five sweeps, goes on
        let mut p = unbounded();
        for k in 0..40 {
            assert_eq!(p.stop(0.97f64.powi(k), 1.0, 5 * k as u64 + 1), None, "{k}");
        }
        // 1 % a sweep: stagnated once five sweeps are seen
        let mut p = unbounded();
        let stops: Vec<Option<StopReason>> = (0..7)
            .map(|k| p.stop(0.99f64.powi(k), 1.0, 5 * k as u64 + 1))
            .collect();
        assert_eq!(stops[..5], [None; 5]);
        assert_eq!(stops[5], Some(StopReason::Stagnated));
        // the residual: up to the factor goes on, beyond it diverges
        let mut p = unbounded();
        assert_eq!(p.stop(1.0, 1.0, 1), None);
        assert_eq!(p.stop(0.5, DIVERGENCE_FACTOR, 6), None);
        assert_eq!(
            p.stop(0.25, 1.01 * DIVERGENCE_FACTOR, 11),
            Some(StopReason::Diverged)
        );
        let mut p = unbounded();
        assert_eq!(p.stop(1.0, f64::NAN, 1), Some(StopReason::Diverged));
        // work: 10 vertices, sweeps of 5 evaluations; a bound of 200 allows
        // the sweeps to 150 evaluations × vertices, not the next
        let mut p = Progress::new(10, 3, 200);
        assert_eq!(p.stop(1.0, 1.0, 1), None); // next: (3 + 1) × 10 = 40
        assert_eq!(p.stop(0.5, 1.0, 6), None); // 60 + 50
        assert_eq!(p.stop(0.25, 1.0, 11), None); // 110 + 50
        assert_eq!(p.stop(0.125, 1.0, 16), Some(StopReason::WorkLimit)); // 160 + 50
    }
}
