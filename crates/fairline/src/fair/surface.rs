//! Circular-highlight fairing of B-spline surfaces (Nishiyama et al. §3).
//!
//! The user marks, on the pre-image of each circular highlight line, the two
//! endpoints of an irregular stretch. Between them a smooth *target curve*
//! is built in the parameter domain (cubic Hermite, Eq. (3.1)–(3.3)), sampled
//! at n(i) points (Eq. (3.4)–(3.5)), and the control points whose support
//! meets the knot-span bounding box of all endpoints are moved by
//! Gauss–Newton on d_s(u_ij, v_ij) = 0 (Eq. (3.6)–(3.9)) with a truncated
//! SVD, a damped step when the residual grows (Eq. (3.12)–(3.13)) and the
//! stopping rule of Eq. (3.14).
//!
//! Everything outside the selected control points is left bit-identical: the
//! other control points are never written, so the surface is unchanged
//! wherever no selected basis function is non-zero.
//!
//! Assumes a regular parametrisation (Nishiyama et al. §3.1) and a
//! non-degenerate normal along the target curves; samples where d_s is
//! undefined are left out and counted.

use crate::bspline::{BSplineError, BSplineSurface};
use crate::curves::CubicHermite;
use crate::highlight::CircularLight;
use crate::highlight::surface::{
    SurfaceHighlightLine, SurfaceHighlightOptions, SurfaceLight, contour_field, distance_field,
};
use crate::{Cancelled, Control, SurfaceOutput, Vec3};
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;
use thiserror::Error;

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

/// Options of [`fair_surface`]: the lights and the stretches to fair, and
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

/// The solver of [`fair_surface`].
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

/// Why fairing could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SurfaceFairError {
    /// An option or an endpoint is out of range.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// No light of the endpoint's radius was given.
    #[error("endpoint {index}: no circular light of radius {radius}")]
    NoLight {
        /// Position in the endpoints list.
        index: usize,
        /// The radius asked for.
        radius: f64,
    },
    /// The light of that radius draws no highlight line on the surface.
    #[error("endpoint {index}: the light of radius {radius} has no highlight line on the surface")]
    NoPreImage {
        /// Position in the endpoints list.
        index: usize,
        /// The radius.
        radius: f64,
    },
    /// No sample of any target curve has a defined d_s.
    #[error("no target sample has a defined signed distance")]
    NoSamples,
    /// The SVD did not converge.
    #[error("singular value decomposition failed")]
    Svd,
    /// Every control point over the stretches is on the patch boundary and
    /// held by [`SurfaceFairOptions::boundary`].
    #[error(
        "all {0} control points over the stretches lie on the patch boundary, which is held fixed (free it to move them)"
    )]
    NothingToMove(usize),
    /// Writing a control point failed (non-finite update).
    #[error(transparent)]
    Surface(#[from] BSplineError),
    /// Stopped through [`SurfaceFairOptions::control`].
    #[error("cancelled")]
    Cancelled(#[from] Cancelled),
}

/// The smooth target of one stretch (Nishiyama et al. §3.2–3.3). In the
/// JSON report: radius, endpoints, tangents and the number of samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetCurve {
    /// Position of the stretch in the endpoints list.
    #[serde(skip)]
    pub index: usize,
    /// Position of its light in [`SurfaceFairOptions::lights`].
    #[serde(skip)]
    pub light: usize,
    /// Radius of that light.
    pub radius: f64,
    /// Endpoint e¹ snapped onto the pre-image.
    pub start: [f64; 2],
    /// Endpoint e² snapped onto the pre-image.
    pub end: [f64; 2],
    /// Tangent t¹ of Eq. (3.1) (direction from the Bézier fit, length Eq. (3.3)).
    pub tangent_start: [f64; 2],
    /// Tangent t² of Eq. (3.1).
    pub tangent_end: [f64; 2],
    /// The sample parameters h_i(t_j) of Eq. (3.4), n(i) of Eq. (3.5)
    /// (their number in the JSON report).
    #[serde(serialize_with = "serialize_count")]
    pub samples: Vec<[f64; 2]>,
    /// The pre-image polyline the endpoints were snapped to (u, v).
    #[serde(skip)]
    pub pre_image: Vec<[f64; 2]>,
    /// The stretch of that polyline between e¹ and e² (the part the target
    /// replaces), from e¹ to e².
    #[serde(skip)]
    pub stretch: Vec<[f64; 2]>,
    /// How far (in u, v) each given endpoint was from where it snapped:
    /// a large value means the point was not on a line of that radius
    /// (all of them: [`SurfaceFairReport::snap_distances`]).
    #[serde(skip)]
    pub snap_distance: [f64; 2],
}

/// Serialises a list as its length.
fn serialize_count<S: serde::Serializer, T>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(v.len() as u64)
}

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

/// One Gauss–Newton iteration of [`fair_surface`].
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

/// Why [`fair_surface`] stopped.
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

/// What [`fair_surface`] did; its fields are the keys of the JSON report
/// of `fairline fair-surface`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceFairReport {
    /// The targets.
    pub targets: Vec<TargetCurve>,
    /// The solver used.
    pub method: SurfaceFairMethod,
    /// The boundary rule used ([`SurfaceFairOptions::boundary`]).
    pub boundary: BoundaryControl,
    /// How many control points moved (`modified_indices.len()`).
    pub modified_control_points: usize,
    /// Control points moved, `(i, j)`, row-major.
    pub modified_indices: Vec<(usize, usize)>,
    /// Control points over the knot box that stayed fixed because they lie
    /// on the patch boundary ([`SurfaceFairOptions::boundary`]), row-major.
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

/// The light of each endpoint pair: the one whose radius matches within
/// 1e-9 (relative).
fn light_of(lights: &[CircularLight], radius: f64) -> Option<usize> {
    lights
        .iter()
        .position(|l| (l.radius() - radius).abs() <= 1e-9 * l.radius().max(1.0))
}

/// A pre-image polyline with cumulative arc length (in `(u, v)`).
struct Arc<'a> {
    pts: &'a [[f64; 2]],
    closed: bool,
    /// `cum[k]` arc length at point k; for closed lines one extra entry
    /// (back to point 0).
    cum: Vec<f64>,
}

fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

impl<'a> Arc<'a> {
    fn new(line: &'a SurfaceHighlightLine) -> Self {
        let pts = &line.uv[..];
        let mut cum = vec![0.0];
        let n = pts.len();
        let segs = if line.closed { n } else { n.saturating_sub(1) };
        for k in 0..segs {
            let d = dist2(pts[k], pts[(k + 1) % n]).sqrt();
            cum.push(cum[k] + d);
        }
        Arc {
            pts,
            closed: line.closed,
            cum,
        }
    }
    fn length(&self) -> f64 {
        *self.cum.last().unwrap_or(&0.0)
    }
    /// Nearest point: (squared distance, arc position, point).
    fn nearest(&self, p: [f64; 2]) -> (f64, f64, [f64; 2]) {
        let n = self.pts.len();
        let mut best = (f64::INFINITY, 0.0, self.pts[0]);
        if n == 1 {
            return (dist2(self.pts[0], p), 0.0, self.pts[0]);
        }
        for k in 0..self.cum.len() - 1 {
            let (a, b) = (self.pts[k], self.pts[(k + 1) % n]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let l2 = ab[0] * ab[0] + ab[1] * ab[1];
            let t = if l2 > 0.0 {
                (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = [a[0] + t * ab[0], a[1] + t * ab[1]];
            let d = dist2(p, q);
            if d < best.0 {
                best = (d, self.cum[k] + t * (self.cum[k + 1] - self.cum[k]), q);
            }
        }
        best
    }
    /// The polyline from arc position `s1` to `s2` travelling in direction
    /// `dir` (±1; wrapping on closed lines): the two end points and the
    /// vertices between them.
    fn between(&self, s1: f64, s2: f64, dir: f64) -> Vec<[f64; 2]> {
        let len = self.length();
        let n = self.pts.len();
        let mut out = vec![self.at(s1)];
        if !(len > 0.0) || n < 2 {
            return out;
        }
        let span = if self.closed {
            (dir * (s2 - s1)).rem_euclid(len)
        } else {
            (s2 - s1).abs()
        };
        // vertices k with arc position strictly inside the travelled span
        let mut inner: Vec<(f64, [f64; 2])> = (0..self.cum.len() - 1)
            .filter_map(|k| {
                let d = if self.closed {
                    (dir * (self.cum[k] - s1)).rem_euclid(len)
                } else {
                    dir * (self.cum[k] - s1)
                };
                (d > 0.0 && d < span).then_some((d, self.pts[k % n]))
            })
            .collect();
        inner.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.extend(inner.into_iter().map(|(_, p)| p));
        out.push(self.at(s2));
        out
    }
    /// The point at arc position `s` (wrapped on closed lines, clamped on
    /// open ones).
    fn at(&self, s: f64) -> [f64; 2] {
        let len = self.length();
        let n = self.pts.len();
        if len <= 0.0 || n < 2 {
            return self.pts[0];
        }
        let s = if self.closed {
            s.rem_euclid(len)
        } else {
            s.clamp(0.0, len)
        };
        let k = match self.cum.binary_search_by(|c| c.total_cmp(&s)) {
            Ok(k) => k.min(self.cum.len() - 2),
            Err(k) => k.saturating_sub(1).min(self.cum.len() - 2),
        };
        let (a, b) = (self.pts[k], self.pts[(k + 1) % n]);
        let d = self.cum[k + 1] - self.cum[k];
        let t = if d > 0.0 {
            ((s - self.cum[k]) / d).clamp(0.0, 1.0)
        } else {
            0.0
        };
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
    }
}

/// Direction of travel at an endpoint from the cubic through four points of
/// the regular part (Nishiyama et al. §3.2, Fig. 4(b)): `q[0]` is the
/// endpoint and `q[1..4]` go away from the stretch at equal arc steps. The
/// interpolating cubic at t = 0, 1/3, 2/3, 1 has derivative
/// (−11 q0 + 18 q1 − 9 q2 + 2 q3) / 2 at q0 (pointing away from the stretch).
fn outward_direction(q: [[f64; 2]; 4]) -> Option<[f64; 2]> {
    let d = [
        0.5 * (-11.0 * q[0][0] + 18.0 * q[1][0] - 9.0 * q[2][0] + 2.0 * q[3][0]),
        0.5 * (-11.0 * q[0][1] + 18.0 * q[1][1] - 9.0 * q[2][1] + 2.0 * q[3][1]),
    ];
    let l = d[0].hypot(d[1]);
    (l > 0.0 && l.is_finite()).then(|| [d[0] / l, d[1] / l])
}

/// Target curves of Nishiyama et al. §3.2–3.3 for each endpoint pair:
///
/// 1. the pre-images of every light used are contoured on an
///    `opts.grid`² grid ([`crate::highlight::surface`]);
/// 2. the start is snapped to the nearest point of its radius' pre-image,
///    and the end to the nearest point of the same polyline;
/// 3. the stretch runs from e¹ to e² along the polyline (on closed lines the
///    shorter way); four points of the regular part on each side, spaced by
///    |e¹ − e²|/3 of arc length (less where an open line ends), give the
///    tangent directions through a cubic fit; their lengths are |e¹ − e²|
///    (Eq. (3.3));
/// 4. the cubic Hermite curve of Eq. (3.1)–(3.2) is sampled at
///    n(i) = 2 + ⌊|e¹ − e²| / s⌋ equally spaced parameters (Eq. (3.4)–(3.5)),
///    s = `opts.sample_spacing` × domain diagonal, clamped to the domain.
///
/// (Eq. (3.2) of the paper lists the Hermite basis with H₁ and H₂ swapped
/// relative to Eq. (3.1); [`CubicHermite`] uses the standard assignment.)
pub fn target_curves(
    surface: &BSplineSurface,
    opts: &SurfaceFairOptions,
) -> Result<Vec<TargetCurve>, SurfaceFairError> {
    check_options(opts)?;
    let (lights, endpoints) = (&opts.lights[..], &opts.endpoints[..]);
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let diag = (du[1] - du[0]).hypot(dv[1] - dv[0]);
    let s = opts.sample_spacing * diag;
    // Pre-images of the lights used (once per light).
    let mut used: Vec<usize> = Vec::new();
    let mut light_index = Vec::with_capacity(endpoints.len());
    for (k, e) in endpoints.iter().enumerate() {
        let finite = e.start.iter().chain(&e.end).all(|x| x.is_finite());
        if !(e.radius > 0.0 && e.radius.is_finite() && finite) {
            return Err(SurfaceFairError::Invalid(format!(
                "endpoint {k}: radius must be positive and coordinates finite"
            )));
        }
        let l = light_of(lights, e.radius).ok_or(SurfaceFairError::NoLight {
            index: k,
            radius: e.radius,
        })?;
        light_index.push(l);
        if !used.contains(&l) {
            used.push(l);
        }
    }
    let hopts = SurfaceHighlightOptions::default().grid(opts.grid);
    let pre_images: Vec<(usize, Vec<SurfaceHighlightLine>)> = used
        .par_iter()
        .map(|&l| {
            let light = SurfaceLight::Circular(lights[l]);
            let field = distance_field(surface, &light, opts.grid, opts.grid);
            (l, contour_field(surface, &light, l, &field, 0.0, &hopts))
        })
        .collect();
    let mut out = Vec::with_capacity(endpoints.len());
    for (k, e) in endpoints.iter().enumerate() {
        let l = light_index[k];
        let lines = &pre_images
            .iter()
            .find(|(x, _)| *x == l)
            .map(|(_, v)| v)
            .ok_or(SurfaceFairError::NoPreImage {
                index: k,
                radius: e.radius,
            })?;
        let arcs: Vec<Arc> = lines
            .iter()
            .filter(|x| x.uv.len() >= 2)
            .map(Arc::new)
            .collect();
        let start = surface_clamp(surface, e.start);
        let end = surface_clamp(surface, e.end);
        let (arc, (_, s1, e1)) = arcs
            .iter()
            .map(|a| (a, a.nearest(start)))
            .min_by(|x, y| x.1.0.total_cmp(&y.1.0))
            .ok_or(SurfaceFairError::NoPreImage {
                index: k,
                radius: e.radius,
            })?;
        let (_, s2, e2) = arc.nearest(end);
        let chord = dist2(e1, e2).sqrt();
        if !(chord > 1e-9 * diag) {
            return Err(SurfaceFairError::Invalid(format!(
                "endpoint {k}: start and end snap to the same point of the highlight line"
            )));
        }
        let len = arc.length();
        // Direction of travel along the arc from e1 to e2.
        let dir = if arc.closed {
            if (s2 - s1).rem_euclid(len) <= 0.5 * len {
                1.0
            } else {
                -1.0
            }
        } else if s2 >= s1 {
            1.0
        } else {
            -1.0
        };
        let h = chord / 3.0;
        let side = |s0: f64, away: f64| -> Option<[f64; 2]> {
            // Arc available beyond s0 in direction `away`.
            let avail = if arc.closed {
                f64::INFINITY
            } else if away > 0.0 {
                len - s0
            } else {
                s0
            };
            let step = h.min(avail / 3.0);
            if !(step > 1e-12 * diag) {
                return None;
            }
            let q = [0.0, 1.0, 2.0, 3.0].map(|m| arc.at(s0 + away * m * step));
            outward_direction(q)
        };
        let stretch = arc.between(s1, s2, dir);
        let chord_dir = [(e2[0] - e1[0]) / chord, (e2[1] - e1[1]) / chord];
        let t1 = side(s1, -dir).map_or(chord_dir, |d| [-d[0], -d[1]]);
        let t2 = side(s2, dir).unwrap_or(chord_dir);
        let hermite = CubicHermite {
            p0: Vec3::new(e1[0], e1[1], 0.0),
            p1: Vec3::new(e2[0], e2[1], 0.0),
            v0: Vec3::new(t1[0], t1[1], 0.0) * chord,
            v1: Vec3::new(t2[0], t2[1], 0.0) * chord,
        };
        let n = 2 + if s > 0.0 {
            ((chord / s).floor() as usize).min(100_000)
        } else {
            0
        };
        let samples = (0..n)
            .map(|j| {
                let p = hermite.point(j as f64 / (n - 1) as f64);
                surface_clamp(surface, [p.x, p.y])
            })
            .collect();
        out.push(TargetCurve {
            index: k,
            light: l,
            radius: lights[l].radius(),
            start: e1,
            end: e2,
            tangent_start: [t1[0] * chord, t1[1] * chord],
            tangent_end: [t2[0] * chord, t2[1] * chord],
            samples,
            pre_image: arc.pts.to_vec(),
            stretch,
            snap_distance: [dist2(e.start, e1).sqrt(), dist2(e.end, e2).sqrt()],
        });
    }
    Ok(out)
}

/// Raises the samples n(i) of every target by a common whole factor k
/// (spacing s/k of Eq. (3.5); the old samples stay among the new) until
/// there are at least as many samples as `unknowns`: Nishiyama et al. §3.3
/// choose n(i) "such that the linear system is always an overdetermined
/// system". At most 64 times as many samples.
fn overdetermine(surface: &BSplineSurface, targets: &mut [TargetCurve], unknowns: usize) {
    let rows: usize = targets.iter().map(|t| t.samples.len()).sum();
    if rows == 0 || rows >= unknowns {
        return;
    }
    let k = unknowns.div_ceil(rows).clamp(2, 64);
    for t in targets.iter_mut() {
        let hermite = CubicHermite {
            p0: Vec3::new(t.start[0], t.start[1], 0.0),
            p1: Vec3::new(t.end[0], t.end[1], 0.0),
            v0: Vec3::new(t.tangent_start[0], t.tangent_start[1], 0.0),
            v1: Vec3::new(t.tangent_end[0], t.tangent_end[1], 0.0),
        };
        let n = (t.samples.len().max(2) - 1) * k + 1;
        t.samples = (0..n)
            .map(|j| {
                let p = hermite.point(j as f64 / (n - 1) as f64);
                surface_clamp(surface, [p.x, p.y])
            })
            .collect();
    }
}

fn surface_clamp(surface: &BSplineSurface, p: [f64; 2]) -> [f64; 2] {
    let (u, v) = surface.clamp_parameters(p[0], p[1]);
    [u, v]
}

fn check_options(o: &SurfaceFairOptions) -> Result<(), SurfaceFairError> {
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

/// The knot-span bounding box of points (Nishiyama et al. §3.2, Fig. 4(c)):
/// the smallest box with knot-valued sides that encloses them.
pub fn knot_box(surface: &BSplineSurface, points: &[[f64; 2]]) -> [f64; 4] {
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let (mut u0, mut u1, mut v0, mut v1) = (du[1], du[0], dv[1], dv[0]);
    for p in points {
        u0 = u0.min(p[0]);
        u1 = u1.max(p[0]);
        v0 = v0.min(p[1]);
        v1 = v1.max(p[1]);
    }
    let down = |knots: &[f64], x: f64, lo: f64| {
        knots
            .iter()
            .copied()
            .filter(|&k| k <= x && k >= lo)
            .fold(lo, f64::max)
    };
    let up = |knots: &[f64], x: f64, hi: f64| {
        knots
            .iter()
            .copied()
            .filter(|&k| k >= x && k <= hi)
            .fold(hi, f64::min)
    };
    [
        down(surface.knots_u(), u0, du[0]),
        up(surface.knots_u(), u1, du[1]),
        down(surface.knots_v(), v0, dv[0]),
        up(surface.knots_v(), v1, dv[1]),
    ]
}

/// A sample of a target curve with its light and the derivatives of the
/// surface (and its first partials) with respect to the selected control
/// points: S, S_u, S_v are linear in the control points with coefficients
/// R, ∂R/∂u, ∂R/∂v of the (rational) basis.
struct Sample {
    uv: [f64; 2],
    light: usize,
    /// (column base = 3 × selected index, R, R_u, R_v).
    coeffs: Vec<(usize, f64, f64, f64)>,
}

/// Rational basis R_ij and its first partials at `(u, v)` for the control
/// points in `column` (flat index → selected index), Piegl & Tiller Eq. (4.2)
/// differentiated: R = N w / W, R_u = (N_u w W − N w W_u) / W².
fn sample_coeffs(
    surface: &BSplineSurface,
    column: &[Option<usize>],
    u: f64,
    v: f64,
) -> Vec<(usize, f64, f64, f64)> {
    let b = surface.basis(u, v);
    let (p, q) = (surface.degree_u(), surface.degree_v());
    let (i0, j0) = (b.span_u - p, b.span_v - q);
    let w = |r: usize, s: usize| surface.weight(i0 + r, j0 + s);
    let (mut ww, mut wu, mut wv) = (0.0, 0.0, 0.0);
    if surface.is_rational() {
        for r in 0..=p {
            for s in 0..=q {
                let wt = w(r, s);
                ww += b.du[0][r] * b.dv[0][s] * wt;
                wu += b.du[1][r] * b.dv[0][s] * wt;
                wv += b.du[0][r] * b.dv[1][s] * wt;
            }
        }
    } else {
        ww = 1.0;
    }
    let mut out = Vec::new();
    if !(ww > 0.0 && ww.is_finite()) {
        return out;
    }
    for r in 0..=p {
        for s in 0..=q {
            let Some(col) = column[surface.index(i0 + r, j0 + s)] else {
                continue;
            };
            let wt = if surface.is_rational() { w(r, s) } else { 1.0 };
            let n = b.du[0][r] * b.dv[0][s] * wt;
            let nu = b.du[1][r] * b.dv[0][s] * wt;
            let nv = b.du[0][r] * b.dv[1][s] * wt;
            let rr = n / ww;
            let ru = (nu * ww - n * wu) / (ww * ww);
            let rv = (nv * ww - n * wv) / (ww * ww);
            if rr != 0.0 || ru != 0.0 || rv != 0.0 {
                out.push((3 * col, rr, ru, rv));
            }
        }
    }
    out
}

/// d_s of Eq. (2.18) at every sample; `None` where undefined.
fn residuals(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
) -> Vec<Option<f64>> {
    samples
        .par_iter()
        .with_min_len(16)
        .map(|s| {
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            lights[s.light].signed_distance(d.point, d.normal()?)
        })
        .collect()
}

/// (max, mean) |d_s|; infinite if any sample is undefined.
fn stats(r: &[Option<f64>]) -> (f64, f64) {
    if r.is_empty() {
        return (0.0, 0.0);
    }
    let mut max = 0.0f64;
    let mut sum = 0.0;
    for x in r {
        match x {
            Some(x) => {
                max = max.max(x.abs());
                sum += x.abs();
            }
            None => return (f64::INFINITY, f64::INFINITY),
        }
    }
    (max, sum / r.len() as f64)
}

/// The Jacobian ∂d_s/∂r of Eq. (3.9) by the forward differences of
/// Eq. (3.10), re-evaluating only the samples each column affects: moving
/// component a of control point P by Δw moves S, S_u, S_v of a sample by
/// (R, R_u, R_v)·Δw along axis a, exactly, so only the normal and the
/// quartic of Eq. (2.15) are recomputed. Parallel over samples; one sparse
/// row (column, value) per sample, empty where d_s is undefined.
fn jacobian_rows(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    f: &[Option<f64>],
    dw: f64,
) -> Vec<Vec<(usize, f64)>> {
    samples
        .par_iter()
        .zip(f.par_iter())
        .with_min_len(8)
        .map(|(s, &f0)| {
            let mut e = Vec::with_capacity(3 * s.coeffs.len());
            let Some(f0) = f0 else { return e };
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            let light = &lights[s.light];
            for &(c, r, ru, rv) in &s.coeffs {
                for a in 0..3 {
                    let mut ax = Vec3::ZERO;
                    ax[a] = dw;
                    let q = d.point + r * ax;
                    let n = (d.su + ru * ax).cross(d.sv + rv * ax);
                    let g = light.signed_distance(q, n).map_or(0.0, |fd| (fd - f0) / dw);
                    if g.is_finite() {
                        e.push((c + a, g));
                    }
                }
            }
            e
        })
        .collect()
}

/// The Jacobian of Eq. (3.9)–(3.10) with one unknown per selected control
/// point, its displacement along `dirs[k]` (Nishiyama et al. §3.3: "the
/// selected components of the control points"), by forward differences
/// re-evaluating only the samples each column affects (as
/// [`jacobian_rows`]). Samples × `dirs.len()`.
fn jacobian_along(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    f: &[Option<f64>],
    dirs: &[Vec3],
    dw: f64,
) -> Mat<f64> {
    let entries: Vec<Vec<(usize, f64)>> = samples
        .par_iter()
        .zip(f.par_iter())
        .with_min_len(8)
        .map(|(s, &f0)| {
            let mut e = Vec::with_capacity(s.coeffs.len());
            let Some(f0) = f0 else { return e };
            let d = surface.derivatives(s.uv[0], s.uv[1]);
            let light = &lights[s.light];
            for &(c, r, ru, rv) in &s.coeffs {
                let k = c / 3;
                let ax = dw * dirs[k];
                let q = d.point + r * ax;
                let n = (d.su + ru * ax).cross(d.sv + rv * ax);
                let g = light.signed_distance(q, n).map_or(0.0, |fd| (fd - f0) / dw);
                if g.is_finite() {
                    e.push((k, g));
                }
            }
            e
        })
        .collect();
    let mut j = Mat::<f64>::zeros(samples.len(), dirs.len());
    for (row, e) in entries.iter().enumerate() {
        for &(c, g) in e {
            j[(row, c)] = g;
        }
    }
    j
}

/// The direction every selected control point moves in with
/// [`SurfaceFairMethod::Paper`]: the coordinate axis (x, y or z) closest to
/// the mean unit normal of the surface at the samples (+z when that mean is
/// undefined). Nishiyama et al. §3.3 solve for "the selected components of
/// the control points", and the Jacobians of their Table 1 have one column
/// per moved control point (36 for the dome's 6 × 6), i.e. one coordinate
/// each: the height of a panel seen from above. Measured on the rebuilt
/// dome, saddle and roof it ends closer to the defect-free surface than the
/// normal at each point's Greville abscissae (normal deviation 2.4e-3 vs
/// 3.0e-3, 1.8e-3 vs 1.8e-3, 7.9e-4 vs 9.8e-4), and than three unknowns
/// per point on the dome and the saddle.
fn control_directions(
    surface: &BSplineSurface,
    selected: &[(usize, usize)],
    samples: &[Sample],
) -> Vec<Vec3> {
    let mean = samples
        .iter()
        .filter_map(|s| surface.normal(s.uv[0], s.uv[1]))
        .filter(|n| n.is_finite())
        .fold(Vec3::ZERO, |a, n| a + n);
    let a = mean.abs();
    let axis = if !(a.length() > 0.0) || (a.z >= a.x && a.z >= a.y) {
        Vec3::Z
    } else if a.y >= a.x {
        Vec3::Y
    } else {
        Vec3::X
    };
    vec![axis; selected.len()]
}

/// Σ (F + J Δr)²: the sum of squares the linearisation of Eq. (3.8)
/// predicts after the step Δr.
fn predicted_sum_of_squares(j: &Mat<f64>, f: &[f64], dr: &[f64]) -> f64 {
    (0..j.nrows())
        .map(|r| {
            let lin: f64 = (0..j.ncols()).map(|c| j[(r, c)] * dr[c]).sum();
            (f[r] + lin).powi(2)
        })
        .sum()
}

/// The thin SVD J = U S Vᵀ of the Jacobian, computed once per iteration
/// and reused for every truncation level tried.
struct JacobianSvd {
    u: Mat<f64>,
    s: Vec<f64>,
    v: Mat<f64>,
}

fn jacobian_svd(j: &Mat<f64>) -> Result<JacobianSvd, SurfaceFairError> {
    let svd = j.thin_svd().map_err(|_| SurfaceFairError::Svd)?;
    let sv = svd.S().column_vector();
    Ok(JacobianSvd {
        u: svd.U().to_owned(),
        s: (0..sv.nrows()).map(|i| sv[i]).collect(),
        v: svd.V().to_owned(),
    })
}

/// Least-squares solution of J Δr = −F by the truncated SVD (Nishiyama et
/// al. §3.3): singular values below `truncation` × the largest are set to
/// zero. Returns (Δr, rank).
fn truncated_svd_solve(svd: &JacobianSvd, f: &[f64], truncation: f64) -> (Vec<f64>, usize) {
    let (u, v) = (&svd.u, &svd.v);
    let smax = svd.s.iter().copied().fold(0.0f64, f64::max);
    let mut dr = vec![0.0; v.nrows()];
    if !(smax > 0.0 && smax.is_finite()) {
        return (dr, 0);
    }
    let mut rank = 0;
    for (i, &si) in svd.s.iter().enumerate() {
        if !(si >= truncation * smax && si > 0.0) {
            continue;
        }
        rank += 1;
        let mut utf = 0.0;
        for r in 0..u.nrows() {
            utf += u[(r, i)] * f[r];
        }
        let c = -utf / si;
        for (col, x) in dr.iter_mut().enumerate() {
            *x += c * v[(col, i)];
        }
    }
    (dr, rank)
}

/// Moves selected control point k by `mu · dr[k]` along `dirs[k]`.
fn apply_along(
    surface: &mut BSplineSurface,
    base: &[Vec3],
    selected: &[(usize, usize)],
    dirs: &[Vec3],
    dr: &[f64],
    mu: f64,
) -> Result<(), SurfaceFairError> {
    for (k, &(i, j)) in selected.iter().enumerate() {
        surface.set_control_point(i, j, base[k] + (mu * dr[k]) * dirs[k])?;
    }
    Ok(())
}

/// Moves the selected control points by `mu · dr`.
fn apply(
    surface: &mut BSplineSurface,
    base: &[Vec3],
    selected: &[(usize, usize)],
    dr: &[f64],
    mu: f64,
) -> Result<(), SurfaceFairError> {
    for (k, &(i, j)) in selected.iter().enumerate() {
        let d = Vec3::new(dr[3 * k], dr[3 * k + 1], dr[3 * k + 2]);
        surface.set_control_point(i, j, base[k] + mu * d)?;
    }
    Ok(())
}

/// Whether control point (i, j) is held by the boundary rule.
fn on_held_boundary(surface: &BSplineSurface, rule: BoundaryControl, i: usize, j: usize) -> bool {
    let rows = match rule {
        BoundaryControl::Free => return false,
        BoundaryControl::Fixed => 1,
        BoundaryControl::FixedWithTangents => 2,
    };
    let (nu, nv) = (surface.count_u(), surface.count_v());
    i < rows || j < rows || i + rows >= nu || j + rows >= nv
}

/// What a solver hands back to [`fair_surface`].
struct Solved {
    surface: BSplineSurface,
    iterations: Vec<FairIteration>,
    converged: bool,
    stop: FairStop,
    after: (f64, f64),
    keep_samples: usize,
}

/// Circular-highlight fairing of a B-spline surface, Nishiyama et al. §3:
/// targets by [`target_curves`]; the control points whose support meets
/// the knot-span bounding box of all endpoints ([`knot_box`],
/// [`BSplineSurface::control_points_in_box`]), less those on the patch
/// boundary held by `opts.boundary` (by default the outermost row on every
/// side, so the boundary curves and the seams stay closed), are the
/// unknowns r. Then, by `opts.method`:
///
/// - [`SurfaceFairMethod::Paper`]: Gauss–Newton on d_s(u_ij, v_ij) = 0
///   (Eq. (3.6)–(3.9)). The unknowns are "the selected components of the
///   control points" (§3.3): one per moved control point, the coordinate
///   closest to the surface normal (as the Jacobian sizes of the paper's
///   Table 1 show; see [`control_directions`]). When the targets have
///   fewer samples than unknowns, n(i) is raised until the system is
///   overdetermined, as §3.3 prescribes. The Jacobian is that of
///   Eq. (3.10) (Δw relative to the control net size), solved by the
///   truncated SVD: the paper's 5 % first; when that step is not accepted
///   or gains less than a halving of mean |d_s|, the truncation is lowered
///   tenfold within the same iteration (same SVD) down to
///   `opts.min_truncation`, and the best accepted step is taken — so no
///   iteration is spent on a step the next level beats. Full step
///   R + Δr (Eq. (3.11)), or R + μΔr (Eq. (3.13)) when no full step is
///   accepted: by default a step is accepted when it lowers Σ d_s²;
///   [`PaperDamping::MaxMean`]: when it lowers max and mean |d_s|
///   (Eq. (3.12) as printed). Stops (converged) when the best step by
///   Σ d_s² does not lower mean |d_s| (the least-squares floor in the
///   paper's measure; the step is not taken), when |mean⁽ᵖ⁺¹⁾ − mean⁽ᵖ⁾| / mean⁽ᵖ⁾
///   < ε (Eq. (3.14), read with the absolute value: as printed it holds
///   after every step that lowers the mean) or when the step at the finest
///   truncation would lower Σ d_s² by less than ε relative (the
///   least-squares problem is solved), when the residual vanishes, when
///   not even a damped step is accepted ([`FairStop::Stalled`], not
///   converged), or after `opts.max_iterations` (not converged).
/// - [`SurfaceFairMethod::Regularised`]: Levenberg–Marquardt on the
///   objective of [`regularised`] (targets + weak targets on every other line
///   crossing the moved region + thin-plate energy of the displacement),
///   stopping when its relative decrease falls below ε.
///
/// The lights and stretches are `opts.lights` and `opts.endpoints`; each
/// iteration is one step of `opts.control` (stage `"iterations"`), which
/// can stop the run with [`SurfaceFairError::Cancelled`]. Returns the
/// faired surface (control points outside the selection bit-identical; the
/// input is not modified) and the report.
pub fn fair_surface(
    surface: &BSplineSurface,
    opts: &SurfaceFairOptions,
) -> Result<SurfaceOutput<BSplineSurface, SurfaceFairReport>, SurfaceFairError> {
    if opts.endpoints.is_empty() {
        return Err(SurfaceFairError::Invalid("no endpoints given".into()));
    }
    let lights = &opts.lights[..];
    let mut targets = target_curves(surface, opts)?;
    let ends: Vec<[f64; 2]> = targets.iter().flat_map(|t| [t.start, t.end]).collect();
    let kb = knot_box(surface, &ends);
    type ControlIndices = Vec<(usize, usize)>;
    let (held, selected): (ControlIndices, ControlIndices) = surface
        .control_points_in_box(kb[0], kb[1], kb[2], kb[3])
        .into_iter()
        .partition(|&(i, j)| on_held_boundary(surface, opts.boundary, i, j));
    if selected.is_empty() {
        return Err(SurfaceFairError::NothingToMove(held.len()));
    }
    let unknowns = match opts.method {
        SurfaceFairMethod::Paper => selected.len(),
        SurfaceFairMethod::Regularised => 3 * selected.len(),
    };
    if opts.method == SurfaceFairMethod::Paper {
        overdetermine(surface, &mut targets, unknowns);
    }
    let mut column = vec![None; surface.count_u() * surface.count_v()];
    for (k, &(i, j)) in selected.iter().enumerate() {
        column[surface.index(i, j)] = Some(k);
    }
    // Samples with a defined d_s on the input surface.
    let all: Vec<Sample> = targets
        .iter()
        .flat_map(|t| {
            t.samples.iter().map(|&uv| Sample {
                uv,
                light: t.light,
                coeffs: Vec::new(),
            })
        })
        .collect();
    let f_all = residuals(surface, lights, &all);
    let mut samples: Vec<Sample> = all
        .into_iter()
        .zip(&f_all)
        .filter(|(_, f)| f.is_some())
        .map(|(s, _)| s)
        .collect();
    let undefined_samples = f_all.len() - samples.len();
    if samples.is_empty() {
        return Err(SurfaceFairError::NoSamples);
    }
    samples
        .par_iter_mut()
        .for_each(|s| s.coeffs = sample_coeffs(surface, &column, s.uv[0], s.uv[1]));
    let (lo, hi) = surface.control_bounding_box();
    let size = (hi - lo).length().max(f64::MIN_POSITIVE);
    let dw = opts.fd_step * size;
    let tiny = 1e-14 * size;
    let before = stats(&residuals(surface, lights, &samples));
    let solved = match opts.method {
        SurfaceFairMethod::Paper => {
            solve_paper(surface, lights, &samples, &selected, opts, dw, tiny)?
        }
        SurfaceFairMethod::Regularised => regularised::solve(
            &regularised::Problem {
                surface,
                lights,
                targets: &targets,
                samples: &samples,
                selected: &selected,
                column: &column,
                dw,
                tiny,
            },
            opts,
        )?,
    };
    let current = solved.surface;
    let max_displacement = selected
        .iter()
        .map(|&(i, j)| (current.control_point(i, j) - surface.control_point(i, j)).length())
        .fold(0.0, f64::max);
    let snap_distances = targets.iter().map(|t| t.snap_distance).collect();
    Ok(SurfaceOutput {
        surfaces: current,
        report: SurfaceFairReport {
            targets,
            method: opts.method,
            boundary: opts.boundary,
            modified_control_points: selected.len(),
            jacobian: JacobianSize {
                rows: samples.len(),
                cols: unknowns,
            },
            modified_indices: selected,
            held_boundary_points: held,
            keep_samples: solved.keep_samples,
            snap_distances,
            knot_box: kb,
            undefined_samples,
            residual_before: before.into(),
            residual_after: solved.after.into(),
            iterations: solved.iterations.len(),
            history: solved.iterations,
            converged: solved.converged,
            stop: solved.stop,
            max_displacement,
        },
    })
}

/// The paper's solver (Nishiyama et al. §3.3), see [`fair_surface`].
fn solve_paper(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    selected: &[(usize, usize)],
    opts: &SurfaceFairOptions,
    dw: f64,
    tiny: f64,
) -> Result<Solved, SurfaceFairError> {
    let dirs = control_directions(surface, selected, samples);
    let cols = dirs.len();
    let mut current = surface.clone();
    let mut f = residuals(&current, lights, samples);
    let mut now = stats(&f);
    let mut iterations = Vec::new();
    let mut converged = now.1 <= tiny;
    let mut stop = if converged {
        FairStop::ZeroResidual
    } else {
        FairStop::MaxIterations
    };
    let levels = truncation_levels(opts.truncation, opts.min_truncation);
    let mut trunc = opts.truncation;
    while !converged && iterations.len() < opts.max_iterations && cols > 0 {
        opts.control.step(
            "iterations",
            iterations.len() as u64,
            opts.max_iterations as u64,
        )?;
        let t0 = Instant::now();
        let base: Vec<Vec3> = selected
            .iter()
            .map(|&(i, j)| current.control_point(i, j))
            .collect();
        let j = jacobian_along(&current, lights, samples, &f, &dirs, dw);
        let fv: Vec<f64> = f.iter().map(|x| x.unwrap_or(0.0)).collect();
        let ss_now: f64 = fv.iter().map(|x| x * x).sum();
        let svd = jacobian_svd(&j)?;
        // Eq. (3.14) on the linear model: when even the finest truncation
        // would change the sum of squares by less than ε (relative), the
        // least-squares problem is solved and another step only shuffles
        // the residual.
        let (finest, _) = truncated_svd_solve(&svd, &fv, opts.min_truncation.min(trunc));
        if !finest.iter().all(|x| x.is_finite()) {
            stop = FairStop::NonFiniteStep;
            break;
        }
        if ss_now - predicted_sum_of_squares(&j, &fv, &finest) <= opts.epsilon * ss_now {
            converged = true;
            stop = FairStop::Epsilon;
            break;
        }
        // The full step of Eq. (3.11) at the current truncation; when it is
        // not accepted or gains less than a halving of mean |d_s|, the
        // truncation is lowered tenfold (same SVD, same iteration) down to
        // the floor. The best accepted full step is taken (the coarser
        // levels, tried in earlier iterations, compete as well); when no
        // full step is accepted, the damped step of Eq. (3.13) at the
        // finest level, then at the coarser ones.
        let try_step = |t: f64, mu: f64| -> Result<Option<Candidate>, SurfaceFairError> {
            let (dr, rank) = truncated_svd_solve(&svd, &fv, t);
            if !dr.iter().all(|x| x.is_finite()) {
                return Ok(None);
            }
            let mut trial = current.clone();
            apply_along(&mut trial, &base, selected, &dirs, &dr, mu)?;
            let ft = residuals(&trial, lights, samples);
            let c = Candidate {
                st: stats(&ft),
                ss: sum_of_squares(&ft),
                surface: trial,
                f: ft,
                step: mu,
                rank,
                truncation: t,
            };
            let ok = match opts.damping {
                // Eq. (3.12) as printed
                PaperDamping::MaxMean => c.st.0 < now.0 && c.st.1 < now.1,
                PaperDamping::Residual => c.ss < ss_now,
                PaperDamping::Off => c.ss.is_finite(),
            };
            Ok(ok.then_some(c))
        };
        let better = |c: &Candidate, a: &Option<Candidate>| {
            a.as_ref().is_none_or(|a| match opts.damping {
                PaperDamping::MaxMean => c.st.1 < a.st.1,
                _ => c.ss < a.ss,
            })
        };
        let mut accepted: Option<Candidate> = None;
        loop {
            if let Some(c) = try_step(trunc, 1.0)? {
                let halved = c.st.1 <= 0.5 * now.1;
                if better(&c, &accepted) {
                    accepted = Some(c);
                }
                if halved {
                    break;
                }
            }
            if trunc <= opts.min_truncation || opts.damping == PaperDamping::Off {
                break;
            }
            trunc = (0.1 * trunc).max(opts.min_truncation);
        }
        if accepted.is_none() {
            for &t in levels.iter().rev().filter(|&&t| t > trunc) {
                if let Some(c) = try_step(t, 1.0)?
                    && better(&c, &accepted)
                {
                    accepted = Some(c);
                }
            }
        }
        if accepted.is_none() {
            for &t in levels.iter().rev() {
                if let Some(c) = try_step(t, opts.damped_step)? {
                    accepted = Some(c);
                    break;
                }
            }
        }
        let Some(c) = accepted else {
            // Not even a damped step helps: keep the current surface.
            stop = FairStop::Stalled;
            break;
        };
        if opts.damping == PaperDamping::Residual && c.st.1 >= now.1 {
            // The best step lowers Σ d_s² but not mean |d_s|: Eq. (3.12)
            // no longer sees convergence, the least-squares floor is
            // reached (Eq. (3.14)); keep the current surface.
            converged = true;
            stop = FairStop::Epsilon;
            break;
        }
        let rel = (now.1 - c.st.1).abs() / now.1;
        current = c.surface;
        f = c.f;
        now = c.st;
        let objective = mean_square(&f);
        iterations.push(FairIteration {
            max_abs: now.0,
            mean_abs: now.1,
            step: c.step,
            rows: samples.len(),
            cols,
            rank: c.rank,
            truncation: c.truncation,
            objective,
            damping: 0.0,
            time_s: t0.elapsed().as_secs_f64(),
        });
        if now.1 <= tiny {
            converged = true;
            stop = FairStop::ZeroResidual;
        } else if rel < opts.epsilon {
            // Eq. (3.14)
            converged = true;
            stop = FairStop::Epsilon;
        }
    }
    Ok(Solved {
        surface: current,
        iterations,
        converged,
        stop,
        after: now,
        keep_samples: 0,
    })
}

/// One trial step of [`solve_paper`]: the surface it gives and its
/// residuals.
struct Candidate {
    surface: BSplineSurface,
    f: Vec<Option<f64>>,
    /// (max, mean) |d_s|.
    st: (f64, f64),
    /// Σ d_s².
    ss: f64,
    step: f64,
    rank: usize,
    truncation: f64,
}

/// The truncation levels [`solve_paper`] tries at every iteration: the
/// paper's `first` (5 %), lowered tenfold down to `floor` (which ends the
/// list); `first` alone when `floor ≥ first`.
fn truncation_levels(first: f64, floor: f64) -> Vec<f64> {
    let mut out = vec![first];
    let mut t = first;
    while t > floor && out.len() < 16 {
        t = (0.1 * t).max(floor);
        out.push(t);
    }
    out
}

/// Σ d_s² (infinite if any is undefined).
fn sum_of_squares(r: &[Option<f64>]) -> f64 {
    r.iter().map(|x| x.map_or(f64::INFINITY, |x| x * x)).sum()
}

/// Mean of d_s² (infinite if any is undefined; 0 for none).
fn mean_square(r: &[Option<f64>]) -> f64 {
    if r.is_empty() {
        return 0.0;
    }
    let mut sum = 0.0;
    for x in r {
        match x {
            Some(x) => sum += x * x,
            None => return f64::INFINITY,
        }
    }
    sum / r.len() as f64
}

/// Endpoint pairs around a disc of the parameter domain: for every pre-image
/// of every light (zero level on a `grid`² grid) and every maximal run of its
/// points inside the disc of centre `center` and radius `radius` (in
/// `(u, v)`), the pair (last point before, first point after) the run — the
/// "two endpoints bounding the local irregularity" a user would click
/// (Nishiyama et al. Fig. 3). Runs that reach an open end of a line are
/// skipped (no regular part on that side).
pub fn endpoints_around(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    center: [f64; 2],
    radius: f64,
    grid: usize,
) -> Vec<EndpointPair> {
    let hopts = SurfaceHighlightOptions::default().grid(grid);
    let mut out = Vec::new();
    if !(radius > 0.0) {
        return out;
    }
    for (k, light) in lights.iter().enumerate() {
        let sl = SurfaceLight::Circular(*light);
        let field = distance_field(surface, &sl, grid, grid);
        for line in contour_field(surface, &sl, k, &field, 0.0, &hopts) {
            let n = line.uv.len();
            if n < 3 {
                continue;
            }
            let inside: Vec<bool> = line
                .uv
                .iter()
                .map(|&p| dist2(p, center) <= radius * radius)
                .collect();
            if inside.iter().all(|&b| b) || !inside.iter().any(|&b| b) {
                continue;
            }
            // Start scanning at an outside point so runs do not wrap.
            let first_out = if line.closed {
                inside.iter().position(|&b| !b).unwrap_or(0)
            } else {
                0
            };
            let m = if line.closed { n } else { n - first_out };
            let idx = |t: usize| (first_out + t) % n;
            let mut t = 0;
            while t < m {
                if inside[idx(t)] {
                    let s = t;
                    while t < m && inside[idx(t)] {
                        t += 1;
                    }
                    if !line.closed && (s == 0 || t >= m) {
                        continue; // reaches an open end
                    }
                    out.push(EndpointPair {
                        radius: light.radius(),
                        start: line.uv[idx(s - 1)],
                        end: line.uv[idx(t)],
                    });
                } else {
                    t += 1;
                }
            }
        }
    }
    out
}

mod regularised;
mod waviness;

pub use waviness::{
    Waviness, discrete_curvature, polyline_waviness, resample_polyline, self_crossings,
};

#[cfg(test)]
mod tests;
