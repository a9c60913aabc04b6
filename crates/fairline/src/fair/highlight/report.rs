//! The report of highlight-line fairing: per iteration and for the run.

use super::least_change::LeastChange;
use super::options::FairMethod;
use crate::fair::desired::{DesiredLines, HighlightDeviation};
use crate::fair::region::MovableSet;
use crate::highlight::{HighlightLines, LightArray};
use serde::Serialize;

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

/// Report of [`fair_highlight_lines`](super::fair_highlight_lines). Serialises to the JSON report of
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
    /// Front ends warn and exit 1 (the result is not what was asked for).
    pub highlight_deviation_worse: bool,
    /// Desired lines of the input (§3.2).
    pub desired_lines: usize,
    /// Largest total displacement of a vertex (mesh units).
    pub max_displacement: f64,
    /// Mean edge length ē inside R.
    pub mean_edge_length: f64,
    /// Refits of the desired lines carried out ([`FairOptions::refits`](super::FairOptions::refits)).
    pub refits: usize,
    /// Share of the diffusion-flow state in the result
    /// ([`FairOptions::flow_share`](super::FairOptions::flow_share); 0 for the other methods).
    pub flow_share: f64,
    /// Iterations of the diffusion-flow run that gave that state (0 when
    /// none ran).
    pub flow_iterations: usize,
    /// True when least change ([`FairOptions::least_change`](super::FairOptions::least_change)(super::FairOptions::least_change)) kept the
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
