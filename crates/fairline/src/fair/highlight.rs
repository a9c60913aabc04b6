//! Highlight-line fairing of a triangle mesh, Yong et al. §3.3–3.7,
//! Algorithm 2, and the surface-diffusion-flow baseline the paper compares
//! against (Xu et al., ∂V/∂t = N Δ_B H).
//!
//! Each iteration: (1) freeze cotangents, areas and normals; (2) build the
//! desired lines of the current highlight lines ([`desired_lines`]);
//! (3) linearise F = ω1 f_fair + ω2 f_diff in the normal displacements x of
//! the movable vertices (module `system`: Willmore quadratic form,
//! Gauss–Newton of f_diff with the analytic sparse Jacobian of Eq. (13));
//! (4) minimise the quadratic under |x_i| ≤ ½ min adjacent edge length
//! (Eq. (16)) exactly with [`crate::solve::box_qp`]; (5) move V_i ← V_i +
//! x_i N_i and update the highlight model incrementally
//! ([`HighlightModel::update`]); stop when max|x_i| / ē < ε (Eq. (17), ē
//! the mean length of the edges inside R) or after N_max iterations.
//!
//! Step acceptance (beyond the paper, which has none): highlight lines react
//! to normals with a lever of the light plane's distance, so a full
//! Gauss–Newton step can overshoot. Each step is kept only when the energy
//! reached — Willmore energy with fresh areas and cotangents plus f_diff of
//! the same nodes and targets, the highlight distances re-evaluated without
//! linearisation (module `system`) — is below the energy at x = 0;
//! otherwise the vertices are put back and the step is recomputed with a
//! Levenberg–Marquardt damping term μ‖x‖² (μ grows ×10 on a rejection and
//! shrinks ×10 after a step that reached more than ¾ of the predicted
//! decrease). Rejected steps count as iterations and are reported.
//!
//! The quadratic Q = JᵀJ gets a ridge of 1e-12 × its largest diagonal entry
//! so that it is positive definite even where the frozen cotangent weights
//! leave a null direction (e.g. negative cotangents); this changes the
//! solution by a relative 1e-12 at most where Q was already definite.
//!
//! Methods: [`FairMethod::Paper`] is F = ω1 f_fair + ω2 f_diff exactly
//! (Yong et al. Eq. (15), Algorithm 2). [`FairMethod::Highlight`] (the
//! default) goes beyond the paper in four ways:
//!
//! 1. **Desired lines with clean end tangents** (module `end_tangents`):
//!    the tangents T0, T1 of the OGH curves of Eq. (5) are the directions
//!    of the highlight lines of a smooth cubic fitted to the vertices
//!    beyond the defect's footprint (outside R grown by one ring, within
//!    six edge lengths of Q0), continued to Q0. The paper fits them to the
//!    lines' outside parts, which carry the tail of the defect: on flat-ish
//!    panels (saddles) a small tilt of the normals moves a line by a lot.
//!    Optional refits ([`FairOptions::refits`], default 0): each time
//!    Eq. (17) is met, the tangents are refitted across the end nodes to
//!    the faired lines (module `desired`) and the iteration goes on;
//!    measured to throw the clean tangents' gain away (BENCHMARKS.md).
//! 2. **A share of the diffusion-flow state** ([`FairOptions::flow_share`],
//!    default ¼): the movable vertices end at (1 − s)·X_H + s·X_F, X_H the
//!    highlight result and X_F the stationary state of surface diffusion
//!    flow (Δ_B H = 0, the baseline below) on the same region from the same
//!    input. Both estimates leave a smooth residual of the defect, set by
//!    the tail of the defect in the fixed support rings: the highlight
//!    result follows desired curves through the end nodes in those rings,
//!    flow the biharmonic-like continuation of their positions and slopes;
//!    where one over- and the other under-corrects (the widest bumps), the
//!    combination is closer than either, and where the truth's mean
//!    curvature is far from harmonic (wavy panels) ¾ of the highlight
//!    result keeps most of its gain. Fixed weights, no selection rule:
//!    nothing is chosen per input.
//! 3. **Least change** ([`FairOptions::least_change`], default on): the
//!    blended result H' is kept only where it dominates the flow state F
//!    on the two counts visible without a truth — its lines are nearer the
//!    desired lines, and it changes the part less (RMS displacement of the
//!    movable vertices at least [`LEAST_CHANGE_MARGIN`] smaller) —
//!    otherwise F is the result ([`LeastChange`]). Both remove the defect;
//!    for a result R = T + E (T the truth, E its error) of an input
//!    T + D, |R − I|² = |D|² − 2⟨E, D⟩ + |E|², so of two results that
//!    remove D the one that moves the part less carries less error of its
//!    own, unless it left part of the defect in place — which the
//!    comparison of the lines with the desired lines catches. Measured on
//!    planted defects of real and generated parts that the flow share was
//!    not chosen on (docs/bench/detection.md), where H' was farther
//!    from the truth than F in 43 % of the cases and up to 7.7×.
//! 4. The optional curvature-Laplacian term ω3 f_lap, f_lap = D⁴
//!    ∫(Δ_B H)² dA over the movable vertices (D the region's bounding-box
//!    diagonal, so that ω3 does not depend on scale), default 0.
//!
//! Measured on 24 generated panels with a known truth (module `family`,
//! BENCHMARKS.md): the default ends closer to the truth than
//! diffusion flow in surface max/RMS and line max/RMS on every case, 2.1×
//! closer in surface max and 2.6× in line RMS on (geometric) average, and
//! on 32 held-out cases (other defect places and widths) as well; the
//! paper's energy alone loses 4 of the 24 (up to 1.67×). With
//! [`FairOptions::flow_share`] and `laplacian_weight` at 0 the default is
//! the paper's energy with the fitted end tangents.
//!
//! Shape: [`fair_highlight_lines`] takes the mesh and
//! [`FairOptions`] (region, lights, weights, stopping rule, refits and the
//! [`crate::Control`] that reports each iteration and can cancel) and
//! returns [`Output`]: the new positions and the serialisable
//! [`FairReport`] (the CLI's JSON report).
//!
//! The baseline (`FairMethod::DiffusionFlow`) replaces F by ‖Δ_B H‖² over
//! the movable vertices (area-weighted), linearised the same way: each step
//! is the implicit step of the flow with an infinite time step, i.e. a
//! Gauss–Newton step toward its stationary state Δ_B H = 0, inside the same
//! Eq. (16) box. Both methods move the same vertices along the same normals.

use super::FairError;
use super::desired::{
    DesiredLines, HighlightDeviation, Tangents, across_tangents, desired_lines_with,
};
use super::end_tangents::fitted_surface_tangents;
use super::region::{MovableSet, movable_vertices};
use super::system::{
    DiffNode, Frozen, NOT_MOVABLE, Residual, difference_energy_after, difference_residual,
    diffusion_residual, region_willmore, willmore_residual,
};
use crate::highlight::{
    HighlightLines, HighlightModel, HighlightOptions, LightArray, NodeId, UpAxis,
};
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::solve::{BoxQpOptions, box_qp, normal_matrix, sparse_from_triplets};
use crate::{Control, Output, Vec3};
use serde::Serialize;

/// Which energy the fairing minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FairMethod {
    /// Yong et al. Eq. (15) with desired lines whose end tangents come from
    /// a smooth fit beyond the defect's footprint (module `end_tangents`),
    /// a share of the diffusion-flow state ([`FairOptions::flow_share`]),
    /// the optional refits of the desired lines ([`FairOptions::refits`])
    /// and the optional curvature-Laplacian term ω3 f_lap
    /// ([`FairOptions::laplacian_weight`]); see the module documentation.
    #[default]
    Highlight,
    /// Yong et al. Eq. (15) exactly: ω1 f_fair + ω2 f_diff, whatever
    /// [`FairOptions::laplacian_weight`] says.
    Paper,
    /// Baseline: surface diffusion flow ∂V/∂t = N Δ_B H (Xu et al.) on the
    /// same movable vertices.
    DiffusionFlow,
    /// Membrane energy (Grüner thesis §3.1.2, Eq. (14)): ΔX = 0 on the
    /// movable vertices, the others held ([`super::energy_fairing`]); no
    /// lights are used and the vertices move freely (not along normals).
    Membrane,
    /// Thin-plate energy (Grüner §3.1.2, Eq. (13)): Δ²X = 0 on the movable
    /// vertices ([`super::energy_fairing`]).
    ThinPlate,
    /// Linearised variation of curvature, minimum variation surfaces
    /// (Grüner §3.1.3, Eq. (15)): Δ³X = 0 on the movable vertices
    /// ([`super::energy_fairing`]).
    Mvs,
}

impl FairMethod {
    /// The energy of an energy-functional method, `None` for the
    /// highlight-line methods.
    pub fn energy(self) -> Option<super::FairEnergy> {
        match self {
            FairMethod::Membrane => Some(super::FairEnergy::Membrane),
            FairMethod::ThinPlate => Some(super::FairEnergy::ThinPlate),
            FairMethod::Mvs => Some(super::FairEnergy::VariationOfCurvature),
            FairMethod::Highlight | FairMethod::Paper | FairMethod::DiffusionFlow => None,
        }
    }
}

/// Options of [`fair_highlight_lines`]: the region, the lights, the energy
/// and the stopping rule of Yong et al. Algorithm 2.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FairOptions {
    /// The region R to fair, as its faces (Yong et al. §3.1); must not be
    /// empty. Read a region file with [`crate::io::read_region`] and
    /// [`crate::io::RegionSpec::faces`].
    pub region: Vec<FaceId>,
    /// The linear light array whose highlight lines are faired; `None`: the
    /// default lights of `fairline highlight` for the mesh
    /// ([`LightArray::default_for_mesh`], up axis found from the part).
    pub light: Option<LightArray>,
    /// The energy to minimise (default [`FairMethod::Highlight`]).
    pub method: FairMethod,
    /// ω1, weight of f_fair (default 1, as in Yong et al. §4).
    pub fair_weight: f64,
    /// ω2, weight of f_diff (default 1, as in Yong et al. §4); f_diff is
    /// measured in light spacings per region diameter (module `system`).
    pub diff_weight: f64,
    /// ω3, weight of the curvature-Laplacian fairness term
    /// f_lap = D⁴ ∫(Δ_B H)² dA of [`FairMethod::Highlight`] (D the
    /// region's diameter): the energy whose zero is the stationary state of
    /// surface diffusion flow (Xu et al.). Default 0 (see the module
    /// documentation for the measured trade-off).
    pub laplacian_weight: f64,
    /// N_max, most iterations (default 50).
    pub max_iterations: usize,
    /// ε of Eq. (17) (default 1e-3).
    pub epsilon: f64,
    /// Refits of the desired lines ([`FairMethod::Highlight`] only,
    /// default 0): each time Eq. (17) is met, the tangents T0, T1 of the
    /// desired lines are refitted across their end nodes to the faired
    /// lines ([`super::desired::across_tangents`]) and the iteration goes
    /// on, this many times; 0 keeps the tangents of the smooth fit beyond
    /// the footprint ([`super::fitted_surface_tangents`]), which are closer
    /// to the truth's on the generated family (BENCHMARKS.md).
    pub refits: usize,
    /// Share of the surface-diffusion-flow state in the result of
    /// [`FairMethod::Highlight`] (default 0.25; 0 switches it off): the
    /// movable vertices end at (1 − s)·(highlight result) + s·(diffusion-flow
    /// result on the same region), see the module documentation.
    pub flow_share: f64,
    /// Least change ([`FairMethod::Highlight`] with a flow share only,
    /// default on): of the blended result and the diffusion-flow state,
    /// keep the one that moves the movable vertices less (RMS
    /// displacement); see the module documentation.
    pub least_change: bool,
    /// Options of the highlight line model.
    pub highlight: HighlightOptions,
    /// Progress (stage "iterations", once per iteration) and cancellation.
    pub control: Control,
}

impl Default for FairOptions {
    fn default() -> Self {
        FairOptions {
            region: Vec::new(),
            light: None,
            method: FairMethod::Highlight,
            fair_weight: 1.0,
            diff_weight: 1.0,
            laplacian_weight: 0.0,
            max_iterations: 50,
            epsilon: 1e-3,
            refits: DEFAULT_REFITS,
            flow_share: DEFAULT_FLOW_SHARE,
            least_change: true,
            highlight: HighlightOptions::default(),
            control: Control::default(),
        }
    }
}

impl FairOptions {
    /// Sets [`FairOptions::region`].
    pub fn region(mut self, faces: Vec<FaceId>) -> Self {
        self.region = faces;
        self
    }
    /// Sets [`FairOptions::light`].
    pub fn light(mut self, light: LightArray) -> Self {
        self.light = Some(light);
        self
    }
    /// Sets [`FairOptions::method`].
    pub fn method(mut self, m: FairMethod) -> Self {
        self.method = m;
        self
    }
    /// Sets ω1 and ω2.
    pub fn weights(mut self, fair: f64, diff: f64) -> Self {
        self.fair_weight = fair;
        self.diff_weight = diff;
        self
    }
    /// Sets [`FairOptions::fair_weight`] (ω1).
    pub fn fair_weight(mut self, w1: f64) -> Self {
        self.fair_weight = w1;
        self
    }
    /// Sets [`FairOptions::diff_weight`] (ω2).
    pub fn diff_weight(mut self, w2: f64) -> Self {
        self.diff_weight = w2;
        self
    }
    /// Sets [`FairOptions::laplacian_weight`] (ω3).
    pub fn laplacian_weight(mut self, w3: f64) -> Self {
        self.laplacian_weight = w3;
        self
    }
    /// Sets [`FairOptions::max_iterations`].
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets [`FairOptions::epsilon`].
    pub fn epsilon(mut self, e: f64) -> Self {
        self.epsilon = e;
        self
    }
    /// Sets [`FairOptions::refits`].
    pub fn refits(mut self, n: usize) -> Self {
        self.refits = n;
        self
    }
    /// Sets [`FairOptions::flow_share`].
    pub fn flow_share(mut self, s: f64) -> Self {
        self.flow_share = s;
        self
    }
    /// Sets [`FairOptions::least_change`].
    pub fn least_change(mut self, on: bool) -> Self {
        self.least_change = on;
        self
    }
    /// Sets [`FairOptions::highlight`].
    pub fn highlight(mut self, h: HighlightOptions) -> Self {
        self.highlight = h;
        self
    }
    /// Sets [`FairOptions::control`].
    pub fn control(mut self, c: Control) -> Self {
        self.control = c;
        self
    }
    fn check(&self) -> Result<(), FairError> {
        for (name, v) in [
            ("fair weight ω1", self.fair_weight),
            ("difference weight ω2", self.diff_weight),
            ("curvature-Laplacian weight ω3", self.laplacian_weight),
        ] {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(FairError::InvalidOption(format!(
                    "{name} must be a finite number ≥ 0, got {v}"
                )));
            }
        }
        if self.method != FairMethod::DiffusionFlow && self.fair_weight + self.diff_weight == 0.0 {
            return Err(FairError::InvalidOption(
                "at least one of the weights ω1, ω2 must be positive".into(),
            ));
        }
        if !(0.0..=1.0).contains(&self.flow_share) {
            return Err(FairError::InvalidOption(format!(
                "the diffusion-flow share must be a number in [0, 1], got {}",
                self.flow_share
            )));
        }
        if !(self.epsilon > 0.0) || !self.epsilon.is_finite() {
            return Err(FairError::InvalidOption(format!(
                "epsilon must be a positive number, got {}",
                self.epsilon
            )));
        }
        Ok(())
    }
}

/// What one iteration of Algorithm 2 did; energies at the start of the
/// iteration (x = 0). Serialises to one entry of the report's `history`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IterationReport {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// f_fair: Willmore energy Σ_{I_R} A_i H_i² of the region.
    pub f_fair: f64,
    /// f_diff: Σ (l_i/D) (ν_i·(Q_i − Q̃_i)/s)² (see module `system`).
    pub f_diff: f64,
    /// The minimised energy at x = 0: ω1 f_fair + ω2 f_diff (+ ω3 f_lap
    /// with [`FairMethod::Highlight`]), or ‖Δ_B H‖² for the baseline.
    pub objective: f64,
    /// The quadratic model's value at the QP solution.
    pub predicted: f64,
    /// The energy actually reached by the step.
    pub achieved: f64,
    /// Whether the step lowered the energy and was kept.
    pub accepted: bool,
    /// Levenberg–Marquardt damping used (relative to max diag JᵀJ).
    #[serde(skip)]
    pub damping: f64,
    /// max |x_i| (mesh units).
    pub max_step: f64,
    /// max |x_i| / ē, the quantity of Eq. (17).
    pub step_ratio: f64,
    /// Displacements at their Eq. (16) bound.
    pub active_bounds: usize,
    /// Projected-Newton iterations of the QP.
    #[serde(skip)]
    pub qp_iterations: usize,
    /// Inside highlight nodes with a target.
    pub target_nodes: usize,
    /// Runs of inside nodes without a desired line (§3.2).
    #[serde(skip)]
    pub skipped_runs: usize,
}

/// Report of [`fair_highlight_lines`]. Serialises to the JSON report of
/// `fairline fair --report` (and of the workbench and the Python package):
/// iterations, convergence, region sizes, the Willmore energy and the
/// highlight-line deviation (RMS and max) before and after, the largest
/// displacement and the per-iteration history. The fields marked "not in
/// the JSON" carry what pictures and checks need.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FairReport {
    /// Iterations run.
    pub iterations: usize,
    /// True when Eq. (17) stopped the iteration.
    pub converged: bool,
    /// Number of movable vertices (§3.1).
    pub movable_vertices: usize,
    /// Number of inside vertices I_R (§3.1).
    pub inside_vertices: usize,
    /// Number of faces in R.
    pub region_faces: usize,
    /// Willmore energy of the region before.
    pub willmore_before: f64,
    /// The same after fairing.
    pub willmore_after: f64,
    /// Length-weighted RMS distance of the inside highlight nodes from the
    /// desired curves, before (mesh units; [`HighlightDeviation::rms`]).
    pub highlight_deviation_before: f64,
    /// The same after fairing.
    pub highlight_deviation_after: f64,
    /// Largest distance of an inside highlight node from its desired curve,
    /// before.
    pub highlight_deviation_max_before: f64,
    /// The same after fairing.
    pub highlight_deviation_max_after: f64,
    /// True when fairing made the highlight lines worse: the RMS deviation
    /// after is larger than before ([`Self::highlight_deviation_before`]).
    /// Front ends warn and exit 1 (the result is not what was asked for);
    /// see [`super::regions_warnings`].
    pub highlight_deviation_worse: bool,
    /// Desired lines of the input (§3.2).
    pub desired_lines: usize,
    /// Largest total displacement of a vertex (mesh units).
    pub max_displacement: f64,
    /// Mean edge length ē inside R.
    pub mean_edge_length: f64,
    /// Refits of the desired lines carried out ([`FairOptions::refits`]).
    pub refits: usize,
    /// Share of the diffusion-flow state in the result
    /// ([`FairOptions::flow_share`]; 0 for the other methods).
    pub flow_share: f64,
    /// Iterations of the diffusion-flow run that gave that state (0 when
    /// none ran).
    pub flow_iterations: usize,
    /// True when least change ([`FairOptions::least_change`]) kept the
    /// diffusion-flow state whole (then `flow_share` is 1).
    pub kept_flow: bool,
    /// The four numbers least change compares (all 0 when no flow state
    /// was blended in); computed with least change off too, so that the
    /// report shows what it would have kept.
    pub least_change: LeastChange,
    /// Per-iteration energies.
    pub history: Vec<IterationReport>,
    /// The method that produced it (not in the JSON).
    #[serde(skip)]
    pub method: FairMethod,
    /// The lights the lines were computed with (not in the JSON).
    #[serde(skip)]
    pub light: LightArray,
    /// Deviation of the inside nodes from the desired curves, before, with
    /// the node count (not in the JSON).
    #[serde(skip)]
    pub deviation_before: HighlightDeviation,
    /// The same after fairing (not in the JSON).
    #[serde(skip)]
    pub deviation_after: HighlightDeviation,
    /// Region, inside and movable vertices (§3.1; not in the JSON).
    #[serde(skip)]
    pub region: MovableSet,
    /// Desired lines of the input, for pictures (not in the JSON).
    #[serde(skip)]
    pub desired_before: DesiredLines,
    /// Highlight lines before (not in the JSON).
    #[serde(skip)]
    pub lines_before: HighlightLines,
    /// Highlight lines after (not in the JSON).
    #[serde(skip)]
    pub lines_after: HighlightLines,
}

/// The linearised energy of one mesh state.
struct Linearised {
    residual: Residual,
    objective: f64,
    desired: DesiredLines,
    f_fair: f64,
    f_diff: f64,
    diff_nodes: Vec<DiffNode>,
}

/// Default [`FairOptions::refits`] (measured on the generated family: with
/// the fitted end tangents, refits lose
/// the widest saddle dent and cubic bump to diffusion flow).
pub const DEFAULT_REFITS: usize = 0;
/// Default [`FairOptions::flow_share`] (measured on the generated family:
/// without it the fitted end tangents
/// lose the widest cubic bump by 4 % in surface RMS).
pub const DEFAULT_FLOW_SHARE: f64 = 0.25;

/// Smallest non-zero Levenberg–Marquardt damping, relative to the largest
/// diagonal entry of JᵀJ.
const MIN_DAMPING: f64 = 1e-6;

/// Mean length of the edges inside R (both faces in R); edges touching R
/// when there is none.
fn region_edge_length(mesh: &SurfaceMesh, set: &MovableSet) -> f64 {
    let p = mesh.positions();
    let (mut inside, mut ni, mut touch, mut nt) = (0.0, 0usize, 0.0, 0usize);
    for e in mesh.edges() {
        let ins: Vec<bool> = (0..2)
            .map(|i| {
                mesh.face(mesh.edge_halfedge(e, i))
                    .is_some_and(|f| set.in_region[f.idx()])
            })
            .collect();
        if !(ins[0] || ins[1]) {
            continue;
        }
        let (a, b) = mesh.edge_vertices(e);
        let l = (p[a.idx()] - p[b.idx()]).length();
        touch += l;
        nt += 1;
        if ins[0] && ins[1] {
            inside += l;
            ni += 1;
        }
    }
    if ni > 0 {
        inside / ni as f64
    } else if nt > 0 {
        touch / nt as f64
    } else {
        0.0
    }
}

/// Eq. (16) bound ½ min adjacent edge length per movable vertex.
fn step_bounds(mesh: &SurfaceMesh, movable: &[VertexId]) -> Vec<f64> {
    let p = mesh.positions();
    movable
        .iter()
        .map(|&v| {
            let m = mesh
                .one_ring(v)
                .map(|w| (p[w.idx()] - p[v.idx()]).length())
                .fold(f64::INFINITY, f64::min);
            if m.is_finite() { 0.5 * m } else { 0.0 }
        })
        .collect()
}

/// Minimises ‖r0 + J x‖² under |x_i| ≤ bound_i (Eq. (16)); returns x,
/// the model value at x and the QP statistics.
fn solve_box(
    res: &Residual,
    bounds: &[f64],
    damping: f64,
) -> Result<(Vec<f64>, f64, usize, usize), FairError> {
    let n = bounds.len();
    let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
    let mut diag = vec![0.0; n];
    let mut c = vec![0.0; n];
    for (r, (row, &r0)) in res.rows.iter().zip(&res.r0).enumerate() {
        for &(col, v) in row {
            triplets.push((r, col as usize, v));
            diag[col as usize] += v * v;
            c[col as usize] += v * r0;
        }
    }
    let dmax = diag.iter().copied().fold(0.0, f64::max);
    let ridge = if dmax > 0.0 && dmax.is_finite() {
        1e-12 * dmax
    } else {
        1.0
    };
    let rows = res.rows.len();
    let lm = damping * dmax;
    for i in 0..n {
        triplets.push((rows + i, i, (ridge + lm).sqrt()));
    }
    let j = sparse_from_triplets(rows + n, n, &triplets)?;
    let q = normal_matrix(j.as_ref())?;
    let lower: Vec<f64> = bounds.iter().map(|b| -b).collect();
    let sol = box_qp(q.as_ref(), &c, &lower, bounds, &BoxQpOptions::default())?;
    // ‖r0 + Jx‖² = ‖r0‖² + 2(½ xᵀJᵀJx + cᵀx) − (ridge + damping)‖x‖²
    let xx: f64 = sol.x.iter().map(|v| v * v).sum();
    let predicted = res.energy() + 2.0 * sol.objective - (ridge + lm) * xx;
    Ok((sol.x, predicted, sol.active, sol.iterations))
}

/// The energy of one fairing (Eq. (15), its variants and the baseline) over
/// the movable set: what [`fair_highlight_lines`] linearises and what a
/// step reaches.
struct Energy<'a> {
    set: &'a MovableSet,
    /// Column of each movable vertex, [`NOT_MOVABLE`] for the others.
    col: Vec<u32>,
    method: FairMethod,
    w1: f64,
    w2: f64,
    /// ω3 (0 for the paper's method).
    w3: f64,
    /// f_diff unit D s² (module `system`).
    diff_unit: f64,
    /// The D² of f_lap's residual (D⁴ of the energy).
    curvature_laplacian_scale: f64,
}

impl<'a> Energy<'a> {
    /// The weights and units of `options` on the region `set` of `mesh`
    /// (positions of the input): D the bounding-box diagonal of the inside
    /// and movable vertices (at least ē).
    fn new(
        mesh: &SurfaceMesh,
        set: &'a MovableSet,
        light: &LightArray,
        ebar: f64,
        options: &FairOptions,
    ) -> Energy<'a> {
        let mut col = vec![NOT_MOVABLE; mesh.vertex_count()];
        for (k, v) in set.movable.iter().enumerate() {
            col[v.idx()] = k as u32;
        }
        let region_points: Vec<Vec3> = set
            .inside_vertices
            .iter()
            .chain(set.movable.iter())
            .map(|v| mesh.position(*v))
            .collect();
        let diameter = crate::mesh::bounding_box(&region_points)
            .map_or(0.0, |(lo, hi)| (hi - lo).length())
            .max(ebar);
        Energy {
            set,
            col,
            method: options.method,
            w1: options.fair_weight,
            w2: options.diff_weight,
            w3: match options.method {
                FairMethod::Paper => 0.0,
                _ => options.laplacian_weight,
            },
            diff_unit: diameter * light.spacing() * light.spacing(),
            curvature_laplacian_scale: diameter * diameter,
        }
    }

    /// The linearised energy of the current mesh (step 4 of Algorithm 2).
    fn linearise(
        &self,
        mesh: &SurfaceMesh,
        model: &HighlightModel,
        lines: &HighlightLines,
        tangents: &Tangents,
    ) -> Linearised {
        let (set, col) = (self.set, &self.col);
        let frozen = Frozen::new(mesh);
        let normals = model.normals();
        let desired = desired_lines_with(lines, |n| set.node_inside(mesh, n), tangents);
        let fair = willmore_residual(mesh, &frozen, normals, col, &set.inside_vertices);
        let lap = (self.w3 > 0.0 && self.method != FairMethod::DiffusionFlow)
            .then(|| diffusion_residual(mesh, &frozen, normals, col, &set.movable));
        let (diff, diff_nodes) =
            difference_residual(mesh, model, normals, col, &desired, self.diff_unit);
        let (f_fair, f_diff) = (fair.energy(), diff.energy());
        let residual = match self.method {
            FairMethod::Highlight | FairMethod::Paper => {
                let mut r = Residual::default();
                r.extend_scaled(fair, self.w1.sqrt());
                if let Some(lap) = lap {
                    r.extend_scaled(lap, self.w3.sqrt() * self.curvature_laplacian_scale);
                }
                r.extend_scaled(diff, self.w2.sqrt());
                r
            }
            // diffusion flow (the energy methods do not iterate)
            _ => diffusion_residual(mesh, &frozen, normals, col, &set.movable),
        };
        Linearised {
            objective: residual.energy(),
            residual,
            desired,
            f_fair,
            f_diff,
            diff_nodes,
        }
    }

    /// The energy reached after a step, with the targets `diff_nodes` of
    /// the iteration (fresh areas, cotangents and normals).
    fn reached(&self, mesh: &SurfaceMesh, model: &HighlightModel, diff_nodes: &[DiffNode]) -> f64 {
        let (set, col) = (self.set, &self.col);
        match self.method {
            FairMethod::Highlight | FairMethod::Paper => {
                let frozen = Frozen::new(mesh);
                let mut f_fair = self.w1 * region_willmore(mesh, &frozen, &set.inside_vertices);
                if self.w3 > 0.0 {
                    f_fair += self.w3
                        * diffusion_residual(mesh, &frozen, model.normals(), col, &set.movable)
                            .energy()
                        * self.curvature_laplacian_scale.powi(2);
                }
                f_fair + self.w2 * difference_energy_after(mesh, model, diff_nodes)
            }
            // diffusion flow (the energy methods do not iterate)
            _ => {
                let frozen = Frozen::new(mesh);
                diffusion_residual(mesh, &frozen, model.normals(), col, &set.movable).energy()
            }
        }
    }
}

/// The lights of `options`, or the default lights of the mesh.
fn lights_of(mesh: &SurfaceMesh, options: &FairOptions) -> Result<LightArray, FairError> {
    match options.light {
        Some(l) => Ok(l),
        None => LightArray::default_for_mesh(mesh, UpAxis::Auto).ok_or_else(|| {
            FairError::InvalidOption("the mesh has no finite vertex to place lights by".into())
        }),
    }
}

/// The state of Algorithm 2's iteration.
struct Iterate {
    history: Vec<IterationReport>,
    converged: bool,
    /// Refits of the desired lines carried out.
    refits: usize,
    /// The highlight lines of the current mesh.
    lines: HighlightLines,
}

/// One Gauss–Newton step of Algorithm 2 inside the Eq. (16) box: moves the
/// movable vertices along their normals, updates the model and returns the
/// iteration's report, the positions before the step and ρ (reached over
/// predicted decrease).
fn box_step(
    energy: &Energy,
    mesh: &mut SurfaceMesh,
    model: &mut HighlightModel,
    current: &Linearised,
    damping: f64,
    it: usize,
    ebar: f64,
) -> Result<(IterationReport, Vec<Vec3>, f64), FairError> {
    let set = energy.set;
    let normals = model.normals().to_vec();
    let bounds = step_bounds(mesh, &set.movable);
    let (x, predicted, active, qp_iterations) = solve_box(&current.residual, &bounds, damping)?;
    let max_step = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let old: Vec<Vec3> = set.movable.iter().map(|v| mesh.position(*v)).collect();
    let positions = mesh.positions_mut();
    for (k, v) in set.movable.iter().enumerate() {
        let np = old[k] + x[k] * normals[v.idx()];
        if np.is_finite() {
            positions[v.idx()] = np;
        }
    }
    model.update(mesh, &set.movable)?;
    // the energy reached, with the targets of this iteration
    let achieved = energy.reached(mesh, model, &current.diff_nodes);
    // Levenberg–Marquardt acceptance of the Gauss–Newton step
    let gain = current.objective - predicted;
    let rho = if gain > 0.0 {
        (current.objective - achieved) / gain
    } else {
        0.0
    };
    let accepted = achieved < current.objective && achieved.is_finite();
    let report = IterationReport {
        iteration: it,
        f_fair: current.f_fair,
        f_diff: current.f_diff,
        objective: current.objective,
        predicted,
        achieved,
        accepted,
        damping,
        max_step,
        step_ratio: max_step / ebar,
        active_bounds: active,
        qp_iterations,
        target_nodes: current.desired.lines.iter().map(|l| l.nodes.len()).sum(),
        skipped_runs: current.desired.skipped,
    };
    Ok((report, old, rho))
}

/// Algorithm 2's iteration with Levenberg–Marquardt step acceptance and
/// the refits of the desired lines ([`FairOptions::refits`]), until
/// Eq. (17) holds after the last refit or N_max iterations.
fn iterate(
    energy: &Energy,
    mesh: &mut SurfaceMesh,
    model: &mut HighlightModel,
    lines_before: &HighlightLines,
    ebar: f64,
    options: &FairOptions,
    initial_tangents: Tangents,
) -> Result<Iterate, FairError> {
    let set = energy.set;
    let mut history = Vec::new();
    let mut converged = false;
    let mut lines = lines_before.clone();
    let mut tangents = initial_tangents;
    let mut refits_left = match options.method {
        FairMethod::Highlight => options.refits,
        _ => 0,
    };
    let mut refits = 0;
    let mut current = energy.linearise(mesh, model, &lines, &tangents);
    let mut damping = 0.0;
    options.control.checkpoint()?;
    for it in 1..=options.max_iterations {
        let (report, old, rho) = box_step(energy, mesh, model, &current, damping, it, ebar)?;
        let (accepted, max_step) = (report.accepted, report.max_step);
        history.push(report);
        options
            .control
            .step("iterations", it as u64, options.max_iterations as u64)?;
        if accepted {
            lines = model.lines(mesh);
            current = energy.linearise(mesh, model, &lines, &tangents);
            if rho > 0.75 {
                damping *= 0.1;
                if damping < MIN_DAMPING {
                    damping = 0.0;
                }
            } else if rho < 0.25 {
                damping = (damping * 4.0).max(MIN_DAMPING);
            }
        } else {
            let positions = mesh.positions_mut();
            for (k, v) in set.movable.iter().enumerate() {
                positions[v.idx()] = old[k];
            }
            model.update(mesh, &set.movable)?;
            damping = (damping * 10.0).max(MIN_DAMPING);
        }
        if max_step / ebar < options.epsilon {
            if refits_left > 0 {
                // the desired lines refitted to the faired lines (module
                // `desired`), then on with the same stopping rule
                refits_left -= 1;
                refits += 1;
                tangents = across_tangents(&lines, |n| set.node_inside(mesh, n));
                current = energy.linearise(mesh, model, &lines, &tangents);
                damping = 0.0;
                continue;
            }
            converged = true;
            break;
        }
    }
    Ok(Iterate {
        history,
        converged,
        refits,
        lines,
    })
}

/// What least change ([`FairOptions::least_change`]) compares: the
/// blended highlight result H' = (1 − s)·H + s·F and the diffusion-flow
/// state F, each by the RMS displacement of the movable vertices from the
/// input (mesh units) and by the RMS distance of its highlight lines from
/// the desired lines of the highlight method (light spacings, as
/// [`FairReport::highlight_deviation_after`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LeastChange {
    /// RMS displacement of H'.
    pub displacement_highlight: f64,
    /// RMS displacement of F.
    pub displacement_flow: f64,
    /// Deviation of H' from the desired lines.
    pub deviation_highlight: f64,
    /// Deviation of F from the same desired lines.
    pub deviation_flow: f64,
}

impl LeastChange {
    /// H' is kept when it dominates F: nearer the desired lines, and a
    /// change of the part at least [`LEAST_CHANGE_MARGIN`] smaller (RMS
    /// displacement). Otherwise F, which has no desired lines to be wrong
    /// about, is kept.
    pub fn keeps_highlight(&self) -> bool {
        self.deviation_highlight < self.deviation_flow
            && self.displacement_highlight < (1.0 - LEAST_CHANGE_MARGIN) * self.displacement_flow
    }
}

/// The share by which the highlight result must move the movable vertices
/// less than the diffusion-flow state to be kept (RMS displacement): closer
/// than 1 % the two are the same change of the part.
pub const LEAST_CHANGE_MARGIN: f64 = 0.01;

/// RMS over `movable` of |p − start| (non-finite differences count 0).
fn rms_displacement(positions: &[Vec3], start: &[Vec3], movable: &[VertexId]) -> f64 {
    if movable.is_empty() {
        return 0.0;
    }
    let sum: f64 = movable
        .iter()
        .map(|v| {
            let d = positions[v.idx()] - start[v.idx()];
            if d.is_finite() {
                d.length_squared()
            } else {
                0.0
            }
        })
        .sum();
    (sum / movable.len() as f64).sqrt()
}

/// (1 − s)·highlight + s·flow on the movable vertices
/// ([`FairOptions::flow_share`]); the others are the input in both, so they
/// stay bit-identical. Returns the lines of the blended mesh.
fn blend_flow(
    mesh: &mut SurfaceMesh,
    model: &mut HighlightModel,
    set: &MovableSet,
    flow: &[Vec3],
    s: f64,
) -> Result<HighlightLines, FairError> {
    let positions = mesh.positions_mut();
    for v in &set.movable {
        let (h, f) = (positions[v.idx()], flow[v.idx()]);
        let np = if s >= 1.0 { f } else { h + s * (f - h) };
        if np.is_finite() {
            positions[v.idx()] = np;
        }
    }
    model.update(mesh, &set.movable)?;
    Ok(model.lines(mesh))
}

/// Fairs the region [`FairOptions::region`] of a triangle mesh with the
/// highlight lines of [`FairOptions::light`] (Yong et al. §3, Algorithm 2,
/// Eqs. (6)–(17); see the module documentation) and returns the new
/// positions with the [`FairReport`]. Only the movable vertices of §3.1
/// move, along their normals; every other vertex, every normal outside R and
/// every highlight node outside R stay bit-identical. Errors on non-triangle
/// meshes, invalid options or regions, with [`FairError::NoMovableVertex`]
/// (advice included) when the region is too small, and with
/// [`FairError::Cancelled`] when [`FairOptions::control`] asks to stop
/// (checked once per iteration).
pub fn fair_highlight_lines(
    mesh: &SurfaceMesh,
    options: &FairOptions,
) -> Result<Output<FairReport>, FairError> {
    options.check()?;
    mesh.require_triangles()?;
    if options.region.is_empty() {
        return Err(FairError::Region("the region has no face".into()));
    }
    let light = lights_of(mesh, options)?;
    // the diffusion-flow state of the same region, for the share of
    // [`FairOptions::flow_share`]
    let flow = if options.method == FairMethod::Highlight && options.flow_share > 0.0 {
        Some(fair_highlight_lines(
            mesh,
            &options
                .clone()
                .light(light)
                .method(FairMethod::DiffusionFlow),
        )?)
    } else {
        None
    };
    let mut mesh = mesh.clone();
    let mut model = HighlightModel::new(&mesh, light, options.highlight.clone())?;
    let lines_before = model.lines(&mesh);
    let nodes: Vec<NodeId> = lines_before
        .lines
        .iter()
        .flat_map(|l| l.nodes.iter().copied())
        .collect();
    let set = movable_vertices(&mesh, &options.region, &nodes)?;
    let ebar = region_edge_length(&mesh, &set);
    if !(ebar > 0.0) || !ebar.is_finite() {
        return Err(FairError::Region(
            "the region's edges have zero length".into(),
        ));
    }
    let start = mesh.positions().to_vec();
    let energy = Energy::new(&mesh, &set, &light, ebar, options);
    let initial_tangents = match options.method {
        FairMethod::Highlight => fitted_surface_tangents(
            &mesh,
            &set,
            model.normals(),
            &lines_before,
            &light,
            options.highlight.min_normal_cos,
            ebar,
        ),
        _ => Tangents::new(),
    };
    let desired_before = desired_lines_with(
        &lines_before,
        |n| set.node_inside(&mesh, n),
        &initial_tangents,
    );
    let deviation_before = desired_before.deviation();
    let willmore_before = region_willmore(&mesh, &Frozen::new(&mesh), &set.inside_vertices);
    let Iterate {
        history,
        converged,
        refits,
        mut lines,
    } = match options.method.energy() {
        Some(e) => {
            options.control.step("iterations", 0, 1)?;
            let fairing = super::energy_fairing(&mesh, &set.is_movable, e)?;
            let positions = mesh.positions_mut();
            for v in &set.movable {
                positions[v.idx()] = fairing[v.idx()];
            }
            model.update(&mesh, &set.movable)?;
            Iterate {
                history: Vec::new(),
                converged: true,
                refits: 0,
                lines: model.lines(&mesh),
            }
        }
        None => iterate(
            &energy,
            &mut mesh,
            &mut model,
            &lines_before,
            ebar,
            options,
            initial_tangents.clone(),
        )?,
    };
    // the flow share, then least change: the blended result is kept only
    // where it beats the flow state on both counts visible without a truth
    let mut share = 0.0;
    let mut choice = LeastChange::default();
    if let Some(flow) = &flow {
        share = options.flow_share;
        lines = blend_flow(&mut mesh, &mut model, &set, &flow.positions, share)?;
        {
            let inside = |n| set.node_inside(&mesh, n);
            choice = LeastChange {
                displacement_highlight: rms_displacement(mesh.positions(), &start, &set.movable),
                displacement_flow: rms_displacement(&flow.positions, &start, &set.movable),
                deviation_highlight: desired_lines_with(&lines, inside, &initial_tangents)
                    .deviation()
                    .rms,
                deviation_flow: desired_lines_with(
                    &flow.report.lines_after,
                    inside,
                    &initial_tangents,
                )
                .deviation()
                .rms,
            };
            if options.least_change && !choice.keeps_highlight() {
                share = 1.0;
                lines = blend_flow(&mut mesh, &mut model, &set, &flow.positions, share)?;
            }
        }
    }
    let desired_after =
        desired_lines_with(&lines, |n| set.node_inside(&mesh, n), &initial_tangents);
    let willmore_after = region_willmore(&mesh, &Frozen::new(&mesh), &set.inside_vertices);
    let max_displacement = mesh
        .positions()
        .iter()
        .zip(&start)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    let deviation_after = desired_after.deviation();
    let report = FairReport {
        iterations: history.len(),
        converged: converged && flow.as_ref().is_none_or(|f| f.report.converged),
        movable_vertices: set.movable.len(),
        inside_vertices: set.inside_vertices.len(),
        region_faces: set.in_region.iter().filter(|&&b| b).count(),
        willmore_before,
        willmore_after,
        highlight_deviation_before: deviation_before.rms,
        highlight_deviation_after: deviation_after.rms,
        highlight_deviation_max_before: deviation_before.max,
        highlight_deviation_max_after: deviation_after.max,
        highlight_deviation_worse: deviation_after.rms > deviation_before.rms,
        desired_lines: desired_before.lines.len(),
        max_displacement,
        mean_edge_length: ebar,
        refits,
        flow_share: share,
        flow_iterations: flow.as_ref().map_or(0, |f| f.report.iterations),
        kept_flow: flow.is_some() && share == 1.0,
        least_change: choice,
        history,
        method: options.method,
        light,
        deviation_before,
        deviation_after,
        region: set,
        desired_before,
        lines_before,
        lines_after: lines,
    };
    Ok(Output {
        positions: mesh.positions().to_vec(),
        report,
    })
}

/// The positions of `mesh` that differ from `reference` (same vertex
/// count), for checks and reports.
pub fn moved_vertices(mesh: &SurfaceMesh, reference: &[Vec3]) -> Vec<VertexId> {
    mesh.positions()
        .iter()
        .zip(reference)
        .enumerate()
        .filter(|(_, (a, b))| a.to_array().map(f64::to_bits) != b.to_array().map(f64::to_bits))
        .map(|(i, _)| VertexId(i as u32))
        .collect()
}

/// Grows a face region by `rings` rings of faces (faces sharing a vertex
/// with the region), e.g. to give a suggested region of
/// [`crate::highlight::detect_irregularities`] the two rings of margin
/// that movable vertices need (§3.1). Sorted, without duplicates.
pub fn grow_region(mesh: &SurfaceMesh, faces: &[FaceId], rings: usize) -> Vec<FaceId> {
    let mut inr = vec![false; mesh.face_count()];
    for f in faces {
        if f.idx() < inr.len() {
            inr[f.idx()] = true;
        }
    }
    for _ in 0..rings {
        let mut touch = vec![false; mesh.vertex_count()];
        for f in mesh.faces() {
            if inr[f.idx()] {
                for v in mesh.face_vertices(f) {
                    touch[v.idx()] = true;
                }
            }
        }
        for f in mesh.faces() {
            if mesh.face_vertices(f).any(|v| touch[v.idx()]) {
                inr[f.idx()] = true;
            }
        }
    }
    mesh.faces().filter(|f| inr[f.idx()]).collect()
}
