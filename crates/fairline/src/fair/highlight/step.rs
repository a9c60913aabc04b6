//! One iteration of Algorithm 2: the linearised energy of a mesh state,
//! the exact box-constrained step (Eq. (16)) with Levenberg–Marquardt
//! acceptance, and the loop that iterates it to Eq. (17).

use super::options::{FairMethod, FairOptions};
use super::report::IterationReport;
use crate::Vec3;
use crate::fair::FairError;
use crate::fair::desired::{DesiredLines, Tangents, across_tangents, desired_lines_with};
use crate::fair::region::MovableSet;
use crate::fair::system::{
    DiffNode, Frozen, NOT_MOVABLE, Residual, difference_energy_after, difference_residual,
    diffusion_residual, region_willmore, willmore_residual,
};
use crate::highlight::{HighlightLines, HighlightModel, LightArray};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{BoxQpOptions, box_qp, normal_matrix, sparse_from_triplets};

/// The linearised energy of one mesh state.
pub(super) struct Linearised {
    residual: Residual,
    objective: f64,
    desired: DesiredLines,
    f_fair: f64,
    f_diff: f64,
    diff_nodes: Vec<DiffNode>,
}

/// Smallest non-zero Levenberg–Marquardt damping, relative to the largest
/// diagonal entry of JᵀJ.
pub(super) const MIN_DAMPING: f64 = 1e-6;

/// Mean length of the edges inside R (both faces in R); edges touching R
/// when there is none.
pub(super) fn region_edge_length(mesh: &SurfaceMesh, set: &MovableSet) -> f64 {
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
pub(super) fn step_bounds(mesh: &SurfaceMesh, movable: &[VertexId]) -> Vec<f64> {
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
pub(super) fn solve_box(
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
/// the movable set: what [`fair_highlight_lines`](super::fair_highlight_lines) linearises and what a
/// step reaches.
pub(super) struct Energy<'a> {
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
    pub(super) fn new(
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

/// The state of Algorithm 2's iteration.
pub(super) struct Iterate {
    pub(super) history: Vec<IterationReport>,
    pub(super) converged: bool,
    /// Refits of the desired lines carried out.
    pub(super) refits: usize,
    /// The highlight lines of the current mesh.
    pub(super) lines: HighlightLines,
}

/// One Gauss–Newton step of Algorithm 2 inside the Eq. (16) box: moves the
/// movable vertices along their normals, updates the model and returns the
/// iteration's report, the positions before the step and ρ (reached over
/// predicted decrease).
pub(super) fn box_step(
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
pub(super) fn iterate(
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
