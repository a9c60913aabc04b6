//! The options of circular-highlight fairing: the endpoint pairs, the
//! method, the paper's damping and truncation, the boundary rule, and their
//! validation.

use super::SurfaceFairError;
use crate::Control;
use crate::highlight::CircularLight;
use serde::{Deserialize, Serialize};

/// One irregular stretch to fair: the radius of its light and the two
/// endpoints in the parameter domain, DESIGN.md §5
/// `{"radius":r,"start":[u,v],"end":[u,v]}`. Each endpoint is snapped to the
/// nearest point of that radius' pre-image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndpointPair {
    /// Radius R of the circular light whose highlight line this is.
    pub radius: f64,
    /// First endpoint e¹ (u, v).
    pub start: [f64; 2],
    /// Second endpoint e² (u, v).
    pub end: [f64; 2],
}

/// The endpoints file of DESIGN.md §5: `{"endpoints":[...]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Endpoints {
    /// The stretches to fair.
    pub endpoints: Vec<EndpointPair>,
}

/// Options of [`fair_surface`](super::fair_surface): the lights and the stretches to fair, and
/// the solver's settings. Lengths of the paper that assume its units
/// (s = 50, Δw = 1e-4) are expressed relative to the surface (DESIGN.md §3).
/// Build with [`SurfaceFairOptions::default`] and the builder setters.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SurfaceFairOptions {
    /// The circular lights (Nishiyama et al. Eq. (2.1)); each endpoint pair
    /// names one by its radius.
    pub lights: Vec<CircularLight>,
    /// The irregular stretches to fair, one endpoint pair each.
    pub endpoints: Vec<EndpointPair>,
    /// Grid points per direction for the pre-images the endpoints snap to.
    pub grid: usize,
    /// Sample spacing s of Eq. (3.5) as a fraction of the parameter domain's
    /// diagonal.
    pub sample_spacing: f64,
    /// Finite-difference step Δw of Eq. (3.10) as a fraction of the control
    /// net's bounding-box diagonal.
    pub fd_step: f64,
    /// Singular values below this fraction of the largest are dropped
    /// (Nishiyama et al. §3.3: 5 %) — at first; see `min_truncation`.
    pub truncation: f64,
    /// Floor of the truncation. The 5 % truncation keeps the first steps
    /// stable but leaves the residual in the dropped singular directions
    /// untouched, so with it alone the residual stalls after ~1.5 orders of
    /// magnitude. Whenever a step is not accepted or mean |d_s| falls by
    /// less than half, the truncation is divided by 10 within the same
    /// iteration (the same SVD is reused) down to this floor, and the best
    /// accepted step is taken. Equal to `truncation` for the paper's fixed
    /// rule.
    pub min_truncation: f64,
    /// Step factor μ of Eq. (3.13) used when a step is damped (0.1).
    pub damped_step: f64,
    /// When the paper's solver damps a step ([`SurfaceFairMethod::Paper`]
    /// only).
    pub damping: PaperDamping,
    /// ε of the stopping rule Eq. (3.14) (1e-4).
    pub epsilon: f64,
    /// Most Gauss–Newton iterations.
    pub max_iterations: usize,
    /// The solver: the paper's truncated SVD, or the regularised
    /// Levenberg–Marquardt that also keeps the other lines (default).
    pub method: SurfaceFairMethod,
    /// Which control points on the patch boundary may move.
    pub boundary: BoundaryControl,
    /// Weight κ of the weak targets that hold the other highlight lines
    /// (all lights, outside the selected stretches) where they are, relative
    /// to the selected targets (each group's sum of squares is divided by its
    /// number of samples). [`SurfaceFairMethod::Regularised`] only.
    pub keep_weight: f64,
    /// Weight φ of the fairness energy on the control displacement
    /// (second differences of the displacement of the control net, a
    /// discrete thin-plate energy), relative to the mean diagonal of the
    /// targets' Gauss–Newton matrix over the mean diagonal of the
    /// second-difference matrix (so it does not depend on the surface's
    /// scale). [`SurfaceFairMethod::Regularised`] only.
    pub fairness_weight: f64,
    /// Progress (one step per iteration) and cancellation.
    pub control: Control,
}

impl SurfaceFairOptions {
    /// Sets [`Self::lights`].
    pub fn lights(mut self, v: Vec<CircularLight>) -> Self {
        self.lights = v;
        self
    }
    /// Sets [`Self::endpoints`].
    pub fn endpoints(mut self, v: Vec<EndpointPair>) -> Self {
        self.endpoints = v;
        self
    }
    /// Sets [`Self::grid`].
    pub fn grid(mut self, v: usize) -> Self {
        self.grid = v;
        self
    }
    /// Sets [`Self::sample_spacing`].
    pub fn sample_spacing(mut self, v: f64) -> Self {
        self.sample_spacing = v;
        self
    }
    /// Sets [`Self::fd_step`].
    pub fn fd_step(mut self, v: f64) -> Self {
        self.fd_step = v;
        self
    }
    /// Sets [`Self::truncation`].
    pub fn truncation(mut self, v: f64) -> Self {
        self.truncation = v;
        self
    }
    /// Sets [`Self::min_truncation`].
    pub fn min_truncation(mut self, v: f64) -> Self {
        self.min_truncation = v;
        self
    }
    /// Sets [`Self::damped_step`].
    pub fn damped_step(mut self, v: f64) -> Self {
        self.damped_step = v;
        self
    }
    /// Sets [`Self::damping`].
    pub fn damping(mut self, v: PaperDamping) -> Self {
        self.damping = v;
        self
    }
    /// Sets [`Self::epsilon`].
    pub fn epsilon(mut self, v: f64) -> Self {
        self.epsilon = v;
        self
    }
    /// Sets [`Self::max_iterations`].
    pub fn max_iterations(mut self, v: usize) -> Self {
        self.max_iterations = v;
        self
    }
    /// Sets [`Self::method`].
    pub fn method(mut self, v: SurfaceFairMethod) -> Self {
        self.method = v;
        self
    }
    /// Sets [`Self::boundary`].
    pub fn boundary(mut self, v: BoundaryControl) -> Self {
        self.boundary = v;
        self
    }
    /// Sets [`Self::keep_weight`].
    pub fn keep_weight(mut self, v: f64) -> Self {
        self.keep_weight = v;
        self
    }
    /// Sets [`Self::fairness_weight`].
    pub fn fairness_weight(mut self, v: f64) -> Self {
        self.fairness_weight = v;
        self
    }
    /// Sets [`Self::control`].
    pub fn control(mut self, v: Control) -> Self {
        self.control = v;
        self
    }
}

/// The solver of [`fair_surface`](super::fair_surface).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceFairMethod {
    /// Nishiyama et al. §3.3: Gauss–Newton with a truncated SVD (lowered
    /// from 5 % as progress slows, see
    /// [`SurfaceFairOptions::min_truncation`]) on the selected targets
    /// only, one unknown per moved control point (one coordinate, the axis
    /// closest to the surface normal).
    Paper,
    /// Beyond the paper: Levenberg–Marquardt on the
    /// selected targets plus weak targets at the current pre-images of all
    /// other lines crossing the moved region plus a fairness energy on the
    /// control displacement; well posed whatever the number of targets.
    Regularised,
}

/// When [`SurfaceFairMethod::Paper`] takes the damped step R + μΔr of
/// Nishiyama et al. Eq. (3.13) instead of the full step of Eq. (3.11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PaperDamping {
    /// When the full step raises the sum of squares Σ d_s² — the quantity
    /// the least-squares step of Eq. (3.9) minimises (default). Near the
    /// least-squares floor a full step lowers Σ d_s² while the largest
    /// |d_s| may rise a little; Eq. (3.12) as printed then damps every step
    /// and the iteration creeps by μ per step.
    #[default]
    Residual,
    /// Eq. (3.12) as printed: when the full step raises max |d_s| or mean
    /// |d_s|.
    MaxMean,
    /// Never: the regular Newton step of Eq. (3.11).
    Off,
}

impl PaperDamping {
    /// Every rule, in the order of the CLI's `--damping` list.
    pub const ALL: [PaperDamping; 3] = [
        PaperDamping::Residual,
        PaperDamping::MaxMean,
        PaperDamping::Off,
    ];

    /// The rule's name: the CLI's `--damping` value.
    pub fn name(self) -> &'static str {
        match self {
            PaperDamping::Residual => "residual",
            PaperDamping::MaxMean => "max-mean",
            PaperDamping::Off => "off",
        }
    }

    /// The rule named `name` ([`PaperDamping::name`]), if there is one.
    pub fn from_name(name: &str) -> Option<PaperDamping> {
        PaperDamping::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Which control points on the boundary of the patch may move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryControl {
    /// Boundary control points move like any other.
    Free,
    /// The outermost row of control points on all four sides stays fixed:
    /// the boundary curves, hence the seams with any neighbour (G0), are
    /// unchanged (default).
    Fixed,
    /// The two outermost rows stay fixed: boundary curves and the
    /// cross-boundary tangents, hence G1 seams with an unchanged neighbour,
    /// are kept.
    FixedWithTangents,
}

impl Default for SurfaceFairOptions {
    fn default() -> Self {
        SurfaceFairOptions {
            lights: Vec::new(),
            endpoints: Vec::new(),
            grid: 200,
            sample_spacing: 0.005,
            fd_step: 1e-7,
            truncation: 0.05,
            min_truncation: 1e-3,
            damped_step: 0.1,
            damping: PaperDamping::Residual,
            epsilon: 1e-4,
            max_iterations: 20,
            method: SurfaceFairMethod::Regularised,
            boundary: BoundaryControl::Fixed,
            keep_weight: 0.01,
            fairness_weight: 3e-3,
            control: Control::default(),
        }
    }
}

pub(super) fn check_options(o: &SurfaceFairOptions) -> Result<(), SurfaceFairError> {
    let bad = |m: &str| Err(SurfaceFairError::Invalid(m.to_string()));
    if o.grid < 3 || o.grid > 10_000 {
        return bad("grid must be between 3 and 10000");
    }
    if !(o.sample_spacing > 0.0 && o.sample_spacing.is_finite()) {
        return bad("sample spacing must be positive");
    }
    if !(o.fd_step > 0.0 && o.fd_step < 1.0) {
        return bad("finite-difference step must be in (0, 1)");
    }
    if !(o.truncation >= 0.0 && o.truncation < 1.0) {
        return bad("truncation must be in [0, 1)");
    }
    if !(o.min_truncation >= 0.0 && o.min_truncation <= o.truncation) {
        return bad("minimum truncation must be in [0, truncation]");
    }
    if !(o.damped_step > 0.0 && o.damped_step <= 1.0) {
        return bad("damped step must be in (0, 1]");
    }
    if !(o.epsilon > 0.0 && o.epsilon.is_finite()) {
        return bad("epsilon must be positive");
    }
    Ok(())
}
