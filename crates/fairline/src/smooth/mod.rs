//! The classic smoothing family of the Grüner thesis, chapter 3: Laplace
//! smoothing (§3.2.2), Taubin λ|μ smoothing (§3.2.3), implicit (backward
//! Euler) smoothing of Desbrun et al., the constraints of §3.2.4 (fixed
//! vertices by empty neighbourhoods, fixed boundary, hierarchical labels,
//! volume preservation by rescaling, tangent-plane motion), the spring model
//! of Yamada et al. (§3.3) and the Δ_B H = 0 construction of Schneider and
//! Kobbelt (§3.4).
//!
//! Every function has the crate's one shape ([`crate::control`]): it takes
//! the mesh by reference and an options struct (`Default`, a builder setter
//! per field, `#[non_exhaustive]`) and returns
//! `Result<Output<SmoothReport>, SmoothError>` with the new positions; the
//! input is never modified. Vertices that are constrained keep their exact
//! (bit-identical) coordinates. Fixed vertices are `fixed: Vec<VertexId>`
//! in every options struct; the other constraints of §3.2.4 are boolean
//! fields of the methods they apply to. Every iteration calls
//! `control.step("iterations", k, total)`, so a run can be watched and
//! cancelled ([`SmoothError::Cancelled`]).

mod laplace;
mod method;
mod schneider_kobbelt;
mod spring;

pub use laplace::{
    ImplicitOptions, LaplaceOptions, TaubinOptions, TaubinParameters, implicit_smooth,
    laplace_smooth, taubin_lambda_for_pass_band, taubin_smooth,
};
pub use method::{SmoothMethod, SmoothOptions, smooth};
pub use schneider_kobbelt::{
    DEFAULT_MAX_WORK, DIVERGENCE_FACTOR, STAGNATION_DECREASE, STAGNATION_WINDOW,
    SchneiderKobbeltOptions, schneider_kobbelt,
};
pub use spring::{SpringOptions, spring_smooth};

use crate::Vec3;
use crate::mesh::{MeshError, SurfaceMesh, VertexId};
use crate::solve::SolveError;
use serde::Serialize;
use thiserror::Error;

/// The crate's builder-setter macro, for the options structs of this module.
pub(crate) use crate::control::setters;

/// Why a smoothing run failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SmoothError {
    /// The mesh does not suit the method (e.g. cotangent weights on quads).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A linear solve failed.
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A fixed-vertex index is out of range.
    #[error("fixed vertex {vertex} does not exist (the mesh has {count} vertices)")]
    FixedVertexOutOfRange {
        /// The offending index.
        vertex: usize,
        /// Number of vertices.
        count: usize,
    },
    /// Volume preservation was asked for an open mesh.
    #[error("volume preservation needs a closed mesh")]
    NotClosed,
    /// The caller raised the cancel flag of the options' [`crate::Control`].
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
    /// The result is not a surface: a position is not finite, or vertices
    /// moved far more than the mesh's size (an unstable step, e.g. a
    /// Laplace λ far above 1). No result is given.
    #[error("the smoothing diverged: {0}")]
    Diverged(String),
}

/// How far (in bounding-box diagonals of the input) a vertex may move
/// before a smoothing result counts as diverged: smoothing shrinks and
/// flattens, so even heavy smoothing moves vertices less than one diagonal.
pub const DIVERGED_DISPLACEMENT: f64 = 10.0;

/// `out` when its positions are finite and no vertex moved more than
/// [`DIVERGED_DISPLACEMENT`] diagonals of `input`; else
/// [`SmoothError::Diverged`] saying which vertex and how far.
pub fn check_diverged<R>(
    input: &SurfaceMesh,
    out: crate::Output<R>,
) -> Result<crate::Output<R>, SmoothError> {
    if let Some(v) = out.positions.iter().position(|p| !p.is_finite()) {
        return Err(SmoothError::Diverged(format!(
            "vertex {v} has a non-finite position; no result (use a smaller step, e.g. lambda ≤ 1)"
        )));
    }
    let diagonal = crate::mesh::bounding_box(input.positions())
        .map(|(lo, hi)| lo.distance(hi))
        .unwrap_or(0.0);
    let (mut worst, mut at) = (0.0f64, 0usize);
    for (v, (p, q)) in input.positions().iter().zip(&out.positions).enumerate() {
        let d = p.distance(*q);
        if d > worst {
            (worst, at) = (d, v);
        }
    }
    if !worst.is_finite() || (diagonal > 0.0 && worst > DIVERGED_DISPLACEMENT * diagonal) {
        return Err(SmoothError::Diverged(format!(
            "vertex {at} moved {worst:.3e}, {:.1e} times the mesh's diagonal; no result (use a smaller step, e.g. lambda ≤ 1)",
            worst / diagonal
        )));
    }
    Ok(out)
}

/// Constraints of Grüner thesis §3.2.4, shared by every smoothing method;
/// the options structs carry them as their own fields (`fixed`,
/// `fix_boundary`, …) and hand them to the methods in this form.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Constraints {
    /// Vertices that never move (empty neighbourhoods, Taubin's interpolatory
    /// constraint). Their coordinates stay bit-identical.
    pub fixed: Vec<VertexId>,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Hierarchical labels: boundary vertices get the higher label, so the
    /// boundary is smoothed as a set of curves (each boundary vertex sees only
    /// its two neighbours along the boundary polyline) and the interior follows.
    /// Ignored when `fix_boundary` is set.
    pub hierarchical_boundary: bool,
    /// Rescale about the centroid after every step so the enclosed volume
    /// equals the input volume (Desbrun et al., β = (V0/Vn)^(1/3)); closed
    /// meshes only. With fixed vertices only the free vertices are scaled
    /// (the scale is then found by a secant iteration). Relative error ≤ 1e-9.
    pub preserve_volume: bool,
    /// Move vertices only within the tangent plane of their input normal
    /// (the normal component of every displacement is removed).
    pub tangential_only: bool,
}

/// What a smoothing run did. Serialises to the keys of the JSON report of
/// `fairline smooth --report` (`residual` only when there is one; Taubin's
/// `lambda`, `mu`, `pass_band` and `transfer` only for Taubin).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SmoothReport {
    /// Iterations performed (a Taubin iteration is a λ step and a μ step).
    pub iterations: usize,
    /// Whether an iterative method met its stopping criterion.
    pub converged: bool,
    /// Enclosed volume before (meaningful for closed meshes only).
    pub volume_before: f64,
    /// Enclosed volume after.
    pub volume_after: f64,
    /// Largest distance a vertex moved from its input position.
    pub max_displacement: f64,
    /// Final residual of an iterative method that has one (Schneider–Kobbelt:
    /// max |H_i − H̃_i| · ē over the free vertices, dimensionless); `None`
    /// for the others.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// Why an iterative method with a stopping rule of its own stopped
    /// (Schneider–Kobbelt); `None` for the others.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop_reason: Option<StopReason>,
    /// The scale factors Taubin smoothing used (`None` for the other
    /// methods); serialised flat as `lambda`, `mu`, `pass_band` and the
    /// `transfer` samples.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub taubin: Option<TaubinParameters>,
}

/// Why an iterative smoothing stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The stopping criterion held.
    Converged,
    /// The most sweeps allowed ran.
    MaxIterations,
    /// The merit fell by less than a set fraction over a window of sweeps.
    Stagnated,
    /// No step length lowered the merit.
    NoDescent,
    /// The residual grew far beyond the smallest one seen.
    Diverged,
    /// The next sweep would have exceeded the work bound.
    WorkLimit,
}

impl StopReason {
    /// The name in the JSON report (`stop_reason`).
    pub fn name(self) -> &'static str {
        match self {
            StopReason::Converged => "converged",
            StopReason::MaxIterations => "max_iterations",
            StopReason::Stagnated => "stagnated",
            StopReason::NoDescent => "no_descent",
            StopReason::Diverged => "diverged",
            StopReason::WorkLimit => "work_limit",
        }
    }
}

/// Per-vertex role derived from [`Constraints`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    Fixed,
    /// Boundary vertex smoothed along the boundary polyline only.
    BoundaryCurve,
    Free,
}

pub(crate) fn roles(mesh: &SurfaceMesh, c: &Constraints) -> Result<Vec<Role>, SmoothError> {
    let n = mesh.vertex_count();
    let mut r = vec![Role::Free; n];
    for v in mesh.vertices() {
        if mesh.is_pinned(v) {
            r[v.idx()] = Role::Fixed;
        } else if mesh.is_boundary_vertex(v) {
            if c.fix_boundary {
                r[v.idx()] = Role::Fixed;
            } else if c.hierarchical_boundary {
                r[v.idx()] = Role::BoundaryCurve;
            }
        }
    }
    for v in &c.fixed {
        if v.idx() >= n {
            return Err(SmoothError::FixedVertexOutOfRange {
                vertex: v.idx(),
                count: n,
            });
        }
        r[v.idx()] = Role::Fixed;
    }
    if c.preserve_volume && !mesh.is_closed() {
        return Err(SmoothError::NotClosed);
    }
    Ok(r)
}

/// Neighbourhood structure in CSR form: for vertex i, neighbours
/// `nbr[off[i]..off[i+1]]` with halfedge ids `he[..]` (for weights).
/// Fixed vertices have empty neighbourhoods; boundary-curve vertices see only
/// their boundary neighbours (Grüner thesis §3.2.4, hierarchical labels).
pub(crate) struct Neighbourhoods {
    pub off: Vec<u32>,
    pub nbr: Vec<u32>,
    pub he: Vec<u32>,
}

impl Neighbourhoods {
    pub(crate) fn new(mesh: &SurfaceMesh, roles: &[Role]) -> Self {
        let n = mesh.vertex_count();
        let mut off = Vec::with_capacity(n + 1);
        let mut nbr = Vec::with_capacity(mesh.halfedge_count());
        let mut he = Vec::with_capacity(mesh.halfedge_count());
        off.push(0u32);
        for v in mesh.vertices() {
            match roles[v.idx()] {
                Role::Fixed => {}
                Role::Free => {
                    for h in mesh.outgoing(v) {
                        nbr.push(mesh.to_vertex(h).0);
                        he.push(h.0);
                    }
                }
                Role::BoundaryCurve => {
                    for h in mesh.outgoing(v) {
                        if mesh.is_boundary_edge(mesh.edge(h)) {
                            nbr.push(mesh.to_vertex(h).0);
                            he.push(h.0);
                        }
                    }
                }
            }
            off.push(nbr.len() as u32);
        }
        Neighbourhoods { off, nbr, he }
    }
}

/// Largest distance between corresponding points.
pub(crate) fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.distance(*y))
        .fold(0.0, f64::max)
}

/// Restores the volume `v0` by scaling the non-fixed vertices about the
/// centroid of all vertices (Desbrun et al. 1999; Grüner §3.2.3). `work`
/// holds the current positions of the vertices of `mesh`. Exact cube root
/// when nothing is fixed; a safeguarded secant iteration on the scale
/// otherwise.
pub(crate) fn restore_volume(
    mesh: &SurfaceMesh,
    work: &mut [Vec3],
    roles: &[Role],
    v0: f64,
) -> Result<(), SmoothError> {
    let vol = crate::geom::volume_at(mesh, work);
    if !(vol.abs() > 0.0) || !(v0.abs() > 0.0) || !vol.is_finite() {
        return Ok(());
    }
    let base: Vec<Vec3> = work.to_vec();
    let c = base.iter().copied().sum::<Vec3>() / base.len().max(1) as f64;
    let apply = |work: &mut [Vec3], s: f64| {
        for (i, p) in work.iter_mut().enumerate() {
            if roles[i] != Role::Fixed {
                *p = c + s * (base[i] - c);
            }
        }
    };
    let ratio = v0 / vol;
    if !(ratio > 0.0) {
        return Ok(());
    }
    let mut s1 = ratio.cbrt();
    apply(work, s1);
    if roles.iter().all(|r| *r != Role::Fixed) {
        return Ok(());
    }
    // secant on g(s) = V(s) - v0, starting from s = 1 and the cube-root guess
    let mut s0 = 1.0;
    let mut g0 = vol - v0;
    let mut g1 = crate::geom::volume_at(mesh, work) - v0;
    for _ in 0..60 {
        if (g1 / v0).abs() <= 1e-12 {
            return Ok(());
        }
        let d = g1 - g0;
        if !(d.abs() > 0.0) {
            break;
        }
        let s2 = s1 - g1 * (s1 - s0) / d;
        if !s2.is_finite() || !(s2 > 0.0) {
            break;
        }
        s0 = s1;
        g0 = g1;
        s1 = s2;
        apply(work, s1);
        g1 = crate::geom::volume_at(mesh, work) - v0;
    }
    if (g1 / v0).abs() > 1e-9 {
        return Err(SmoothError::InvalidOption(
            "volume cannot be restored by scaling the free vertices".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
