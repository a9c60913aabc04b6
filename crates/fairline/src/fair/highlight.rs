//! Highlight-line fairing of a triangle mesh, Yong et al. §3.3–3.7,
//! Algorithm 2, and the surface-diffusion-flow baseline the paper compares
//! against (Xu et al., ∂V/∂t = N Δ_B H).
//!
//! Each iteration: (1) freeze cotangents, areas and normals; (2) build the
//! desired lines of the current highlight lines (module `desired`);
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
use super::desired::{Tangents, desired_lines_with};
use super::end_tangents::fitted_surface_tangents;
use super::region::movable_vertices;
use super::system::{Frozen, region_willmore};
use crate::highlight::{HighlightModel, LightArray, NodeId, UpAxis};
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::{Output, Vec3};

mod least_change;
mod options;
mod report;
mod step;

pub use least_change::{LEAST_CHANGE_MARGIN, LeastChange};
use least_change::{blend_flow, rms_displacement};
pub use options::{DEFAULT_FLOW_SHARE, DEFAULT_REFITS, FairMethod, FairOptions};
pub use report::{FairReport, IterationReport};
use step::{Energy, Iterate, iterate, region_edge_length};

/// The lights of `options`, or the default lights of the mesh.
fn lights_of(mesh: &SurfaceMesh, options: &FairOptions) -> Result<LightArray, FairError> {
    match options.light {
        Some(l) => Ok(l),
        None => LightArray::default_for_mesh(mesh, UpAxis::Auto).ok_or_else(|| {
            FairError::InvalidOption("the mesh has no finite vertex to place lights by".into())
        }),
    }
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
