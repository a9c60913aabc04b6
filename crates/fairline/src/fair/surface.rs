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
use crate::highlight::CircularLight;
use crate::highlight::surface::{SurfaceHighlightOptions, SurfaceLight};
use crate::{Cancelled, SurfaceOutput, Vec3};
use faer::Mat;
use rayon::prelude::*;
use std::time::Instant;
use thiserror::Error;

mod jacobian;
mod options;
mod paper;
mod regularised;
mod report;
mod targets;
mod waviness;

pub use options::{
    BoundaryControl, EndpointPair, Endpoints, PaperDamping, SurfaceFairMethod, SurfaceFairOptions,
};
pub use report::{FairIteration, FairStop, JacobianSize, Residual, SurfaceFairReport};
pub use targets::{TargetCurve, endpoints_around, target_curves};
pub use waviness::{
    Waviness, discrete_curvature, polyline_waviness, resample_polyline, self_crossings,
};

use jacobian::{Sample, residuals, sample_coeffs, stats};
use paper::solve_paper;
use targets::overdetermine;

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
///   Table 1 show; see [`control_directions`](jacobian::control_directions)). When the targets have
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

#[cfg(test)]
mod tests;
