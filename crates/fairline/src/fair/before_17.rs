//! The highlight-line fairing code path as it was before the one algorithm
//! shape of issue #17 (`fair_highlight_lines(mesh, light, faces, options)
//! -> FairResult`), kept for the test that the converted function gives the
//! same positions and report bit for bit. Test-only.

#![allow(dead_code)]

use super::FairError;
use super::desired::{DesiredLines, HighlightDeviation, desired_lines};
use super::highlight::{FairMethod, IterationReport};
use super::region::{MovableSet, movable_vertices};
use super::system::{
    DiffNode, Frozen, NOT_MOVABLE, Residual, difference_energy_after, difference_residual,
    diffusion_residual, region_willmore, willmore_residual,
};
use crate::Vec3;
use crate::highlight::{HighlightLines, HighlightModel, HighlightOptions, LightArray, NodeId};
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::solve::{BoxQpOptions, box_qp, normal_matrix, sparse_from_triplets};

/// Options of [`fair_highlight_lines`].
#[derive(Clone, Debug, PartialEq)]
pub struct FairOptions {
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
    /// Options of the highlight line model.
    pub highlight: HighlightOptions,
}

impl Default for FairOptions {
    fn default() -> Self {
        FairOptions {
            method: FairMethod::Highlight,
            fair_weight: 1.0,
            diff_weight: 1.0,
            laplacian_weight: 0.0,
            max_iterations: 50,
            epsilon: 1e-3,
            highlight: HighlightOptions::default(),
        }
    }
}

impl FairOptions {
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
    /// Sets [`FairOptions::highlight`].
    pub fn highlight(mut self, h: HighlightOptions) -> Self {
        self.highlight = h;
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
        if !(self.epsilon > 0.0) || !self.epsilon.is_finite() {
            return Err(FairError::InvalidOption(format!(
                "epsilon must be a positive number, got {}",
                self.epsilon
            )));
        }
        Ok(())
    }
}

/// Result of [`fair_highlight_lines`].
#[derive(Clone, Debug)]
pub struct FairResult {
    /// The method that produced it.
    pub method: FairMethod,
    /// The faired mesh (same connectivity; only movable vertices moved).
    pub mesh: SurfaceMesh,
    /// Region, inside and movable vertices (§3.1).
    pub region: MovableSet,
    /// Iterations run.
    pub iterations: usize,
    /// True when Eq. (17) stopped the iteration.
    pub converged: bool,
    /// Willmore energy of the region before and after.
    pub willmore_before: f64,
    /// See `willmore_before`.
    pub willmore_after: f64,
    /// Distance of the inside highlight nodes from the desired curves,
    /// before.
    pub deviation_before: HighlightDeviation,
    /// The same after fairing.
    pub deviation_after: HighlightDeviation,
    /// Largest total displacement of a vertex (mesh units).
    pub max_displacement: f64,
    /// Mean edge length ē inside R.
    pub mean_edge_length: f64,
    /// Desired lines of the input (for pictures).
    pub desired_before: DesiredLines,
    /// Highlight lines before and after.
    pub lines_before: HighlightLines,
    /// See `lines_before`.
    pub lines_after: HighlightLines,
    /// Per-iteration energies.
    pub history: Vec<IterationReport>,
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

/// Fairs the face region `faces` of a triangle mesh with the highlight
/// lines of `light` (Yong et al. Algorithm 2; see the module
/// documentation). Only the movable vertices of §3.1 move, along their
/// normals; every other vertex, every normal outside R and every highlight
/// node outside R stay bit-identical. Errors on non-triangle meshes,
/// invalid options or regions, and with [`FairError::NoMovableVertex`]
/// (advice included) when the region is too small.
pub fn fair_highlight_lines(
    mesh: &SurfaceMesh,
    light: &LightArray,
    faces: &[FaceId],
    options: &FairOptions,
) -> Result<FairResult, FairError> {
    fair_highlight_lines_with(mesh, light, faces, options, &mut |_| {})
}

/// [`fair_highlight_lines`] calling `on_iteration` after every iteration
/// (for progress display).
pub fn fair_highlight_lines_with(
    mesh: &SurfaceMesh,
    light: &LightArray,
    faces: &[FaceId],
    options: &FairOptions,
    on_iteration: &mut dyn FnMut(&IterationReport),
) -> Result<FairResult, FairError> {
    options.check()?;
    mesh.require_triangles()?;
    let mut mesh = mesh.clone();
    let mut model = HighlightModel::new(&mesh, *light, options.highlight.clone())?;
    let lines_before = model.lines(&mesh);
    let nodes: Vec<NodeId> = lines_before
        .lines
        .iter()
        .flat_map(|l| l.nodes.iter().copied())
        .collect();
    let set = movable_vertices(&mesh, faces, &nodes)?;
    let mut col = vec![NOT_MOVABLE; mesh.vertex_count()];
    for (k, v) in set.movable.iter().enumerate() {
        col[v.idx()] = k as u32;
    }
    let ebar = region_edge_length(&mesh, &set);
    if !(ebar > 0.0) || !ebar.is_finite() {
        return Err(FairError::Region(
            "the region's edges have zero length".into(),
        ));
    }
    let start = mesh.positions().to_vec();
    // f_diff unit D s² (module `system`): D the region's bounding-box diagonal
    let region_points: Vec<Vec3> = set
        .inside_vertices
        .iter()
        .chain(set.movable.iter())
        .map(|v| start[v.idx()])
        .collect();
    let diameter = crate::mesh::bounding_box(&region_points)
        .map_or(0.0, |(lo, hi)| (hi - lo).length())
        .max(ebar);
    let diff_unit = diameter * light.spacing() * light.spacing();
    let inside_node = |m: &SurfaceMesh, n: NodeId| set.node_inside(m, n);
    let w3 = match options.method {
        FairMethod::Paper => 0.0,
        _ => options.laplacian_weight,
    };
    // the D⁴ of f_lap, as a residual scale
    let curvature_laplacian_scale = diameter * diameter;
    let desired_before = desired_lines(&lines_before, |n| inside_node(&mesh, n));
    let deviation_before = desired_before.deviation();
    let willmore_before = region_willmore(&mesh, &Frozen::new(&mesh), &set.inside_vertices);
    let (w1, w2) = (options.fair_weight, options.diff_weight);
    // the linearised energy of the current mesh (steps 4 of Algorithm 2)
    let linearise = |mesh: &SurfaceMesh, model: &HighlightModel, lines: &HighlightLines| {
        let frozen = Frozen::new(mesh);
        let normals = model.normals();
        let desired = desired_lines(lines, |n| set.node_inside(mesh, n));
        let fair = willmore_residual(mesh, &frozen, normals, &col, &set.inside_vertices);
        let lap = (w3 > 0.0 && options.method != FairMethod::DiffusionFlow)
            .then(|| diffusion_residual(mesh, &frozen, normals, &col, &set.movable));
        let (diff, diff_nodes) =
            difference_residual(mesh, model, normals, &col, &desired, diff_unit);
        let (f_fair, f_diff) = (fair.energy(), diff.energy());
        let residual = match options.method {
            FairMethod::Highlight | FairMethod::Paper => {
                let mut r = Residual::default();
                r.extend_scaled(fair, w1.sqrt());
                if let Some(lap) = lap {
                    r.extend_scaled(lap, w3.sqrt() * curvature_laplacian_scale);
                }
                r.extend_scaled(diff, w2.sqrt());
                r
            }
            FairMethod::DiffusionFlow => {
                diffusion_residual(mesh, &frozen, normals, &col, &set.movable)
            }
        };
        Linearised {
            objective: residual.energy(),
            residual,
            desired,
            f_fair,
            f_diff,
            diff_nodes,
        }
    };
    let mut history = Vec::new();
    let mut converged = false;
    let mut lines = lines_before.clone();
    let mut current = linearise(&mesh, &model, &lines);
    let mut damping = 0.0;
    for it in 1..=options.max_iterations {
        let normals = model.normals().to_vec();
        let bounds = step_bounds(&mesh, &set.movable);
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
        model.update(&mesh, &set.movable)?;
        // the energy reached, with the targets of this iteration
        let achieved = match options.method {
            FairMethod::Highlight | FairMethod::Paper => {
                let frozen = Frozen::new(&mesh);
                let mut f_fair = w1 * region_willmore(&mesh, &frozen, &set.inside_vertices);
                if w3 > 0.0 {
                    f_fair += w3
                        * diffusion_residual(&mesh, &frozen, model.normals(), &col, &set.movable)
                            .energy()
                        * curvature_laplacian_scale.powi(2);
                }
                f_fair + w2 * difference_energy_after(&mesh, &model, &current.diff_nodes)
            }
            FairMethod::DiffusionFlow => {
                let frozen = Frozen::new(&mesh);
                diffusion_residual(&mesh, &frozen, model.normals(), &col, &set.movable).energy()
            }
        };
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
        on_iteration(&report);
        history.push(report);
        if accepted {
            lines = model.lines(&mesh);
            current = linearise(&mesh, &model, &lines);
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
            model.update(&mesh, &set.movable)?;
            damping = (damping * 10.0).max(MIN_DAMPING);
        }
        if max_step / ebar < options.epsilon {
            converged = true;
            break;
        }
    }
    let desired_after = desired_lines(&lines, |n| inside_node(&mesh, n));
    let willmore_after = region_willmore(&mesh, &Frozen::new(&mesh), &set.inside_vertices);
    let max_displacement = mesh
        .positions()
        .iter()
        .zip(&start)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    Ok(FairResult {
        method: options.method,
        iterations: history.len(),
        converged,
        willmore_before,
        willmore_after,
        deviation_before,
        deviation_after: desired_after.deviation(),
        max_displacement,
        mean_edge_length: ebar,
        desired_before,
        lines_before,
        lines_after: lines,
        history,
        region: set,
        mesh,
    })
}

impl FairResult {
    /// The report of one fairing run as JSON, the keys of `fairline fair
    /// --report` (and of the workbench's and the Python package's reports):
    /// iterations, convergence, region sizes, the Willmore energy and the
    /// highlight-line deviation (RMS and max) before and after, the largest
    /// displacement and the per-iteration history (Yong et al. Algorithm 2).
    pub fn report_json(&self) -> serde_json::Value {
        let r = self;
        serde_json::json!({
            "iterations": r.iterations,
            "converged": r.converged,
            "movable_vertices": r.region.movable.len(),
            "inside_vertices": r.region.inside_vertices.len(),
            "region_faces": r.region.in_region.iter().filter(|&&b| b).count(),
            "willmore_before": r.willmore_before,
            "willmore_after": r.willmore_after,
            "highlight_deviation_before": r.deviation_before.rms,
            "highlight_deviation_after": r.deviation_after.rms,
            "highlight_deviation_max_before": r.deviation_before.max,
            "highlight_deviation_max_after": r.deviation_after.max,
            "desired_lines": r.desired_before.lines.len(),
            "max_displacement": r.max_displacement,
            "mean_edge_length": r.mean_edge_length,
            "history": r.history.iter().map(|h| serde_json::json!({
                "iteration": h.iteration,
                "f_fair": h.f_fair,
                "f_diff": h.f_diff,
                "objective": h.objective,
                "predicted": h.predicted,
                "achieved": h.achieved,
                "accepted": h.accepted,
                "max_step": h.max_step,
                "step_ratio": h.step_ratio,
                "active_bounds": h.active_bounds,
                "target_nodes": h.target_nodes,
            })).collect::<Vec<_>>(),
        })
    }
}
