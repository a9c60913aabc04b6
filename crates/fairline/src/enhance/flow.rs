//! The vertex flow: what stays fixed over the iterations (the normalised
//! mesh, its constraints and the reference surface) and the state that
//! each iteration moves, solves and projects.

use super::{
    AUTO_SOFT_SHARE, EnhanceError, EnhanceOptions, EnhanceReport, EnhanceTimings, Projection,
    QUALITY_FLOOR_GROWTH, QUALITY_ROUNDS, QualityStats,
};
use super::{boundary, precondition, repair, surface, system};
use crate::geom::{PrincipalCurvatures, principal_curvatures_rusinkiewicz};
use crate::mesh::SurfaceMesh;
use crate::solve::{
    BlockJacobi, MultigridBuilder, Preconditioner, SolveError, StagedOptions, StagedSolver,
};
use crate::{Output, Vec3};
use std::time::Instant;

/// Weight ε of the regularisation ε‖v − p‖² (normalised units).
const REGULARISATION: f64 = 1e-10;

/// What stays fixed over the iterations of the vertex flow: the mesh in
/// normalised coordinates x' = (x − c) / ē, its input curvature, the
/// unknowns, the distance model F_sd and the input faces of the repair.
pub(super) struct FlowProblem<'a> {
    pub(super) mesh: &'a SurfaceMesh,
    pub(super) options: &'a EnhanceOptions,
    /// c of the normalisation.
    pub(super) centroid: Vec3,
    /// ē of the normalisation.
    pub(super) edge_length: f64,
    /// Input positions, normalised.
    pub(super) reference: Vec<Vec3>,
    /// The mesh at the normalised positions (curvature of later iterations
    /// is computed on a copy of it).
    pub(super) normalised: SurfaceMesh,
    pub(super) input_curvature: PrincipalCurvatures,
    pub(super) layout: system::Layout,
    /// The boundary curves of the input (module `boundary`).
    pub(super) boundary: boundary::BoundaryCurves,
    /// The free vertices off the boundary (projected onto the input
    /// surface) and on it (projected onto the boundary curve).
    pub(super) interior_free: Vec<u32>,
    pub(super) boundary_free: Vec<u32>,
    pub(super) distance: system::DistanceModel,
    /// Share of the free vertices with a tangential direction F_sd leaves
    /// free ([`AUTO_SOFT_SHARE`]).
    pub(super) soft_share: f64,
    pub(super) input_faces: repair::InputFaces,
}

impl<'a> FlowProblem<'a> {
    /// Normalises the input, computes its curvature and finds the unknowns
    /// (free vertices: not a corner of the boundary, not pinned, not listed in
    /// [`EnhanceOptions::fixed`], with a normal and principal directions).
    pub(super) fn new(
        mesh: &'a SurfaceMesh,
        options: &'a EnhanceOptions,
        edge_length: f64,
        timings: &mut EnhanceTimings,
    ) -> Result<FlowProblem<'a>, EnhanceError> {
        let input = mesh.positions();
        let n = mesh.vertex_count();
        let centroid = input.iter().copied().sum::<Vec3>() / n as f64;
        let reference: Vec<Vec3> = input
            .iter()
            .map(|&x| (x - centroid) / edge_length)
            .collect();
        let mut normalised = mesh.clone();
        normalised.set_positions(reference.clone())?;
        let t = Instant::now();
        let input_curvature = principal_curvatures_rusinkiewicz(&normalised);
        timings.curvature_s += t.elapsed().as_secs_f64();
        let boundary = boundary::BoundaryCurves::new(mesh, &reference);
        // boundary vertices slide along the boundary curve where there is a
        // projection to keep them on it (the paper's method keeps them)
        let sliding = options.projection != Projection::None;
        let mut is_fixed = vec![false; n];
        for v in mesh.vertices() {
            let i = v.idx();
            let stays_on_boundary = mesh.is_boundary_vertex(v)
                && (!sliding || !boundary.is_on(i) || boundary.is_corner(i));
            is_fixed[i] = stays_on_boundary
                || mesh.is_pinned(v)
                || input_curvature.normals[i] == Vec3::ZERO
                || input_curvature.d1[i] == Vec3::ZERO;
        }
        for v in &options.fixed {
            is_fixed[v.idx()] = true;
        }
        let layout = system::Layout::new(mesh, &is_fixed);
        let (boundary_free, interior_free): (Vec<u32>, Vec<u32>) = layout
            .free
            .iter()
            .copied()
            .partition(|&v| boundary.is_on(v as usize));
        let distance =
            system::DistanceModel::new(&input_curvature, &layout, &boundary, options.lambda);
        let soft_share = distance.soft_share(options.lambda);
        let input_faces = repair::InputFaces::of(&normalised);
        Ok(FlowProblem {
            mesh,
            options,
            centroid,
            edge_length,
            reference,
            normalised,
            input_curvature,
            layout,
            boundary,
            interior_free,
            boundary_free,
            distance,
            soft_share,
            input_faces,
        })
    }

    /// Normalised positions back in input units; fixed vertices keep their
    /// input bits (so does a free vertex whose result is not finite).
    pub(super) fn to_input_units(&self, current: &[Vec3]) -> Vec<Vec3> {
        let mut positions = self.mesh.positions().to_vec();
        for &v in &self.layout.free {
            let v = v as usize;
            let x = self.centroid + current[v] * self.edge_length;
            if x.is_finite() {
                positions[v] = x;
            }
        }
        positions
    }
}

/// The state of the vertex flow between iterations.
pub(super) struct Flow {
    /// Normalised positions.
    pub(super) current: Vec<Vec3>,
    pub(super) solver: StagedSolver,
    pub(super) flipped_triangles: usize,
    pub(super) degraded_triangles: usize,
    pub(super) backtracked: Vec<bool>,
    /// Solves repeated by the quality guard.
    pub(super) quality_resolves: usize,
}

impl Flow {
    pub(super) fn new(problem: &FlowProblem<'_>) -> Flow {
        Flow {
            current: problem.reference.clone(),
            solver: StagedSolver::new(),
            flipped_triangles: 0,
            degraded_triangles: 0,
            backtracked: vec![false; problem.reference.len()],
            quality_resolves: 0,
        }
    }

    /// One iteration: curvature of the current mesh (the input's in the
    /// first), the system of Eq. (20), its least-squares solution
    /// ([`crate::solve::StagedSolver`]), the projection onto the input
    /// surface, the quality guard's re-solves and the repair of flipped or
    /// degraded triangles (module documentation, "Triangle quality").
    pub(super) fn iterate(
        &mut self,
        problem: &FlowProblem<'_>,
        input_surface: &surface::InputSurface<'_>,
        iteration: usize,
        timings: &mut EnhanceTimings,
    ) -> Result<(), EnhanceError> {
        let options = problem.options;
        let layout = &problem.layout;
        let recomputed;
        let curvature = if iteration == 0 {
            &problem.input_curvature
        } else {
            let t = Instant::now();
            let mut work = problem.normalised.clone();
            work.set_positions(self.current.clone())?;
            recomputed = principal_curvatures_rusinkiewicz(&work);
            timings.curvature_s += t.elapsed().as_secs_f64();
            &recomputed
        };
        // the quality guard: where the step would flip a triangle or drop
        // it below the quality floor, the distance model of its vertices is
        // stiffened tangentially and the system solved again (warm-started
        // at the last solution)
        let mut stiffened: Option<system::DistanceModel> = None;
        let mut floor: Vec<f64> = Vec::new();
        let mut guess: Vec<f64> = layout
            .free
            .iter()
            .flat_map(|&v| self.current[v as usize].to_array())
            .collect();
        let mut round = 0;
        let target = loop {
            let distance = stiffened.as_ref().unwrap_or(&problem.distance);
            let (x, target) = self.solve_and_project(
                problem,
                input_surface,
                curvature,
                distance,
                guess,
                timings,
            )?;
            if round == QUALITY_ROUNDS || !(options.mu > 0.0) {
                break target;
            }
            let bad = repair::bad_face_vertices(problem.mesh, &problem.input_faces, &target);
            let bad: Vec<usize> = bad.into_iter().filter_map(|v| layout.free_of(v)).collect();
            if bad.is_empty() {
                break target;
            }
            if floor.is_empty() {
                floor = vec![0.0; layout.free.len()];
            }
            for f in bad {
                floor[f] = (QUALITY_FLOOR_GROWTH * floor[f]).max(1.0);
            }
            stiffened = Some(system::DistanceModel::with_floor(
                &problem.input_curvature,
                layout,
                &problem.boundary,
                options.lambda,
                &floor,
            ));
            self.quality_resolves += 1;
            guess = x;
            round += 1;
        };
        let mut target = target;
        let t = Instant::now();
        let outcome = repair::repair_flips(
            problem.mesh,
            &problem.input_faces,
            &problem.boundary,
            &self.current,
            &mut target,
        );
        self.flipped_triangles += outcome.flipped;
        self.degraded_triangles += outcome.degraded;
        for v in outcome.backtracked {
            self.backtracked[v] = true;
        }
        self.current = target;
        timings.repair_s += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// The system of Eq. (20) with the distance model `distance`,
    /// its least-squares solution from `guess` ([`crate::solve::StagedSolver`])
    /// and the projection of the free vertices onto the input surface (and
    /// boundary): the solution vector and the projected positions.
    pub(super) fn solve_and_project(
        &mut self,
        problem: &FlowProblem<'_>,
        input_surface: &surface::InputSurface<'_>,
        curvature: &PrincipalCurvatures,
        distance: &system::DistanceModel,
        guess: Vec<f64>,
        timings: &mut EnhanceTimings,
    ) -> Result<(Vec<f64>, Vec<Vec3>), EnhanceError> {
        let options = problem.options;
        let layout = &problem.layout;
        let t = Instant::now();
        let system = system::assemble(
            layout,
            curvature,
            &problem.boundary,
            distance,
            &self.current,
            &problem.reference,
            options.mu,
            REGULARISATION,
        )?;
        timings.assembly_s += t.elapsed().as_secs_f64();
        // the factored bi-Laplacian preconditioner (needs μ > 0: with μ = 0
        // there is no smoothness model)
        let epsilon = system.epsilon;
        let build = |jacobi: BlockJacobi| -> Result<Box<dyn Preconditioner + '_>, SolveError> {
            Ok(Box::new(precondition::FactoredPreconditioner::new(
                layout, curvature, distance, jacobi, options.mu, epsilon,
            )?))
        };
        let multigrid: Option<&MultigridBuilder<'_>> = (options.mu > 0.0).then_some(&build);
        let x = self.solver.solve(
            &system,
            multigrid,
            guess,
            &StagedOptions {
                solver: options.solver,
                skip_jacobi: problem.soft_share > AUTO_SOFT_SHARE,
                tolerance: options.cg_tolerance,
                max_iterations: options.cg_max_iterations,
            },
        )?;
        let t = Instant::now();
        let mut target = self.current.clone();
        for (f, &v) in layout.free.iter().enumerate() {
            target[v as usize] = Vec3::new(x[3 * f], x[3 * f + 1], x[3 * f + 2]);
        }
        input_surface.project(&problem.interior_free, &mut target, options.projection);
        if options.projection != Projection::None {
            problem
                .boundary
                .project(&problem.boundary_free, &mut target);
        }
        timings.repair_s += t.elapsed().as_secs_f64();
        Ok((x, target))
    }

    /// The output: `positions` (input units) and the report of the run
    /// (timings are filled in by the caller).
    pub(super) fn report(
        &self,
        problem: &FlowProblem<'_>,
        positions: Vec<Vec3>,
        quality_before: QualityStats,
    ) -> Result<Output<EnhanceReport>, EnhanceError> {
        let (mesh, options) = (problem.mesh, problem.options);
        let input = mesh.positions();
        let n = mesh.vertex_count();
        let (mut max_d, mut sum_d) = (0.0f64, 0.0);
        for (a, b) in positions.iter().zip(input) {
            let d = a.distance(*b);
            max_d = max_d.max(d);
            sum_d += d;
        }
        let (max_distance_to_input, mean_distance_to_input) =
            distance_to_input(mesh, &positions, &problem.layout.free);
        let mut out_mesh = mesh.clone();
        out_mesh.set_positions(positions.clone())?;
        let stats = &self.solver.stats;
        Ok(Output {
            report: EnhanceReport {
                vertices: n,
                free_vertices: problem.layout.free.len(),
                iterations: options.iterations,
                lambda: options.lambda,
                mu: options.mu,
                flipped_triangles: self.flipped_triangles,
                degraded_triangles: self.degraded_triangles,
                backtracked_vertices: self.backtracked.iter().filter(|b| **b).count(),
                quality_resolves: self.quality_resolves,
                quality_before,
                quality_after: QualityStats::of_mesh(&out_mesh, options.histogram_bins),
                max_displacement: max_d,
                mean_displacement: sum_d / n as f64,
                max_distance_to_input,
                mean_distance_to_input,
                edge_length: problem.edge_length,
                solver: options.solver,
                projection: options.projection,
                cg_iterations: stats.cg_iterations,
                cg_relative_residual: stats.cg_relative_residual,
                direct_fallbacks: stats.direct_fallbacks,
                timings: EnhanceTimings::default(),
            },
            positions,
        })
    }
}

/// Largest and mean distance of the `free` vertices at `positions` to the
/// input surface near them (the input faces are searched ring by ring
/// around the vertex's input position until a ring brings no nearer face,
/// at most [`surface::SEARCH_RINGS`] rings): an upper bound of the distance
/// to the whole input surface, which another part of the surface may come
/// nearer to.
pub(super) fn distance_to_input(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    free: &[u32],
) -> (f64, f64) {
    let queries: Vec<(u32, Vec3)> = free.iter().map(|&v| (v, positions[v as usize])).collect();
    let distances: Vec<f64> = surface::nearest_input_faces(mesh, mesh.positions(), &queries)
        .iter()
        .map(|n| n.map_or(0.0, |n| n.distance_squared.sqrt()))
        .collect();
    let max = distances.iter().copied().fold(0.0, f64::max);
    let mean = if distances.is_empty() {
        0.0
    } else {
        distances.iter().sum::<f64>() / distances.len() as f64
    };
    (max, mean)
}
