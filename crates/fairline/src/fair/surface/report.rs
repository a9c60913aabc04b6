//! What fairing reports: the residuals before and after, the Jacobian's
//! size, each iteration and why the iteration stopped.

use super::{BoundaryControl, SurfaceFairMethod, TargetCurve};
use serde::Serialize;

/// Largest and mean |d_s| over the target samples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Residual {
    /// max |d_s|.
    pub max: f64,
    /// mean |d_s|.
    pub mean: f64,
}

impl From<(f64, f64)> for Residual {
    fn from((max, mean): (f64, f64)) -> Self {
        Residual { max, mean }
    }
}

/// Size of the targets' Jacobian (Eq. (3.10)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct JacobianSize {
    /// Target samples with a defined d_s.
    pub rows: usize,
    /// Unknowns: one per moved control point (one coordinate) with
    /// [`SurfaceFairMethod::Paper`], three (x, y, z) with
    /// [`SurfaceFairMethod::Regularised`].
    pub cols: usize,
}

/// One Gauss–Newton iteration of [`fair_surface`](super::fair_surface).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FairIteration {
    /// max |d_s| over the samples after the step.
    pub max_abs: f64,
    /// mean |d_s| over the samples after the step.
    pub mean_abs: f64,
    /// Step factor μ used (1, or the damped step of Eq. (3.13)).
    pub step: f64,
    /// Jacobian rows (samples).
    pub rows: usize,
    /// Jacobian columns (unknowns: one per moved control point with
    /// [`SurfaceFairMethod::Paper`], three with the regularised solver).
    pub cols: usize,
    /// Singular values kept by the truncation.
    pub rank: usize,
    /// The truncation used (fraction of the largest singular value;
    /// [`SurfaceFairMethod::Paper`] only, 0 otherwise).
    pub truncation: f64,
    /// The objective after the step: mean d_s² at the targets (plus the weak
    /// targets and the fairness energy with [`SurfaceFairMethod::Regularised`]).
    pub objective: f64,
    /// Levenberg–Marquardt damping of the accepted step (0 for the paper's
    /// method).
    pub damping: f64,
    /// Wall time of the iteration (s).
    pub time_s: f64,
}

/// Why [`fair_surface`](super::fair_surface) stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FairStop {
    /// The relative change of mean |d_s| fell below ε (Eq. (3.14)); with
    /// [`SurfaceFairMethod::Regularised`], the relative decrease of the
    /// objective did.
    Epsilon,
    /// mean |d_s| vanished (below 1e-14 of the control net size).
    ZeroResidual,
    /// Neither the full nor the damped step lowered mean |d_s| (the
    /// objective with [`SurfaceFairMethod::Regularised`], after raising the
    /// damping 12 times): not converged.
    Stalled,
    /// `max_iterations` reached.
    MaxIterations,
    /// The step was not finite (the previous surface is kept).
    NonFiniteStep,
}

/// What [`fair_surface`](super::fair_surface) did; its fields are the keys of the JSON report
/// of `fairline fair-surface`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceFairReport {
    /// The targets.
    pub targets: Vec<TargetCurve>,
    /// The solver used.
    pub method: SurfaceFairMethod,
    /// The boundary rule used
    /// ([`SurfaceFairOptions::boundary`](super::SurfaceFairOptions::boundary)).
    pub boundary: BoundaryControl,
    /// How many control points moved (`modified_indices.len()`).
    pub modified_control_points: usize,
    /// Control points moved, `(i, j)`, row-major.
    pub modified_indices: Vec<(usize, usize)>,
    /// Control points over the knot box that stayed fixed because they lie
    /// on the patch boundary
    /// ([`SurfaceFairOptions::boundary`](super::SurfaceFairOptions::boundary)),
    /// row-major.
    pub held_boundary_points: Vec<(usize, usize)>,
    /// Weak-target samples on the other lines
    /// ([`SurfaceFairMethod::Regularised`]; 0 otherwise).
    pub keep_samples: usize,
    /// How far (in u, v) each given endpoint was from where it snapped
    /// (start, end), per stretch ([`TargetCurve::snap_distance`]).
    pub snap_distances: Vec<[f64; 2]>,
    /// Knot-span bounding box `[u0, u1, v0, v1]` of the endpoints.
    pub knot_box: [f64; 4],
    /// Size of the targets' Jacobian.
    pub jacobian: JacobianSize,
    /// Samples left out because d_s is undefined there.
    pub undefined_samples: usize,
    /// |d_s| at the samples before fairing.
    pub residual_before: Residual,
    /// |d_s| at the samples after fairing.
    pub residual_after: Residual,
    /// How many iterations ran (`history.len()`).
    pub iterations: usize,
    /// Per-iteration record.
    pub history: Vec<FairIteration>,
    /// Whether the stop test held: Eq. (3.14) (the objective's relative
    /// decrease below ε with [`SurfaceFairMethod::Regularised`]) or a
    /// vanishing residual. False when stalled or out of iterations.
    pub converged: bool,
    /// Why the iteration stopped.
    pub stop: FairStop,
    /// Largest control point displacement (surface units).
    pub max_displacement: f64,
}
