//! Structure-line fairing of quad meshes (Grüner thesis chapter 4,
//! Eq. (30)–(34), algorithm of §4.1) and fair polyline networks with
//! tolerance cylinders (§3.1.1 after Hofer et al.).
//!
//! A structure line is a chain of vertices running straight through regular
//! vertices ([`crate::mesh::structure_lines`]). It is fair when, for every
//! four consecutive points, the unit edge directions satisfy
//! ½(v̂_{i−1} + v̂_{i+1}) − v̂_i ≈ 0 (Eq. (30)). Fixing the edge lengths at
//! those of the current polygon makes the residual linear (Eq. (32)); a
//! penalty ω‖p − p⁰‖² keeps the shape (Eq. (34)). x, y and z decouple, so
//! every iteration is one sparse least-squares problem with three
//! right-hand sides, solved by sparse Cholesky of its normal equations up to
//! [`DIRECT_LIMIT`] free points and above that by conjugate gradients
//! preconditioned with banded per-line blocks (no fill-in, no symbolic
//! analysis when the free set changes between iterations).
//!
//! Fairing without deformation: the penalty of Eq. (34)
//! holds every direction alike, so the solve straightens the lines partly
//! by cutting across the surface (measured: 5e-3 from the true surface,
//! farther than Taubin). By default ([`QuadFairOptions::on_surface`]) the
//! free points are moved back onto a smooth fit of the input surface after
//! every solve (`reference.rs`): they slide along the surface while the
//! lines straighten, the normal direction is held exactly and the penalty
//! acts along the surface only. On the generated zigzag grids of the tests
//! the result stays 10⁻⁴–10⁻⁶ from the true surface (Taubin 50: 10⁻³–10⁻²)
//! with the boundary bit-identical.

mod network;
mod reference;
mod solver;

pub use network::{PolylineNetworkOptions, PolylineNetworkReport, fair_polyline_network};
use reference::ReferenceSurface;
pub(crate) use solver::DIRECT_LIMIT;
use solver::{Lines, System, line_families};

use crate::geom;
use crate::mesh::{MeshError, StructureLine, SurfaceMesh, VertexId, structure_lines};
use crate::solve::{CholeskySolver, SolveError};
use crate::{Control, Output, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

/// Why structure-line fairing failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum QuadFairError {
    /// Mesh problem.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A linear solve failed.
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A fixed vertex does not exist.
    #[error("fixed vertex {vertex} does not exist (the mesh has {count} vertices)")]
    FixedVertexOutOfRange {
        /// The offending index.
        vertex: usize,
        /// Number of vertices.
        count: usize,
    },
    /// The caller cancelled the run ([`QuadFairOptions::control`]).
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
}

/// Options of [`fair_structure_lines`]; build with
/// `QuadFairOptions::default()` and the setters
/// (`.weight(0.1).fix_boundary(true)`).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct QuadFairOptions {
    /// Penalty weight ω of Eq. (34), scale-invariant: the penalty actually
    /// used is (ω / ē²)‖p − p⁰‖² with ē the mean edge length of the input,
    /// because the residual of Eq. (32) is dimensionless while ‖p − p⁰‖² is
    /// a squared length. With this scaling a value behaves the same on a
    /// mesh of any size. Default 0.01 (the zigzag grids of the tests: larger
    /// keeps more of the input, smaller straightens more).
    pub weight: f64,
    /// Deviation parameter: a run of four points whose Eq. (30) deviation
    /// ‖½(v̂_{i−1} + v̂_{i+1}) − v̂_i‖ exceeds it marks its two middle points
    /// "need to be faired"; all other points are fixed. Default 0.1.
    pub deviation: f64,
    /// The deviation is multiplied by this factor after every iteration
    /// (the thesis halves it). Default 0.1: with halving, the last of three
    /// iterations still fixes every run below 0.025 (about 1.4°), and the
    /// kinks between fixed and freed points stay as a low-frequency wave
    /// (measured on the zigzag grids of the tests: largest geodesic turning
    /// 3.0–4.9° with 0.5, 1.9–3.0° with 0.1).
    pub deviation_factor: f64,
    /// Iterations (each reclassifies and re-linearises). Default 3.
    pub iterations: usize,
    /// Keep all boundary vertices fixed. Corners (boundary vertices of
    /// valence ≤ 2) are always fixed.
    pub fix_boundary: bool,
    /// Further vertices that never move.
    pub fixed: Vec<VertexId>,
    /// Keep the points on the input surface (default): after every solve
    /// the free points are moved onto a smooth fit of the input surface
    /// (blended local quadric fits, see `reference.rs`), so they slide
    /// along the surface while the lines straighten, and the penalty of
    /// Eq. (34) only holds them back along the surface. `false` is the
    /// thesis' method as printed: the points may leave the surface (lines
    /// straighten by cutting across it).
    pub on_surface: bool,
    /// Per-vertex weights by deviation (Grüner §4.2: "each vertex gets its
    /// own weight dependent on the value of the deviation of three
    /// consecutive vectors"): a free point whose largest Eq. (30)
    /// deviation d_i exceeds the iteration's deviation parameter δ gets
    /// ω_i = ω·δ / d_i, so the worse a zigzag the less it is held to its
    /// input; ω elsewhere. Default off (one ω for all, as printed).
    pub deviation_weights: bool,
    /// Progress (one step per iteration) and cancellation.
    pub control: Control,
}

impl Default for QuadFairOptions {
    fn default() -> Self {
        QuadFairOptions {
            weight: 0.01,
            deviation: 0.1,
            deviation_factor: 0.1,
            iterations: 3,
            fix_boundary: false,
            fixed: Vec::new(),
            on_surface: true,
            deviation_weights: false,
            control: Control::default(),
        }
    }
}

impl QuadFairOptions {
    /// Sets the penalty weight ω.
    pub fn weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// Sets the deviation parameter.
    pub fn deviation(mut self, deviation: f64) -> Self {
        self.deviation = deviation;
        self
    }
    /// Sets the factor the deviation is multiplied by after each iteration.
    pub fn deviation_factor(mut self, factor: f64) -> Self {
        self.deviation_factor = factor;
        self
    }
    /// Sets the number of iterations.
    pub fn iterations(mut self, iterations: usize) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets whether the whole boundary stays fixed.
    pub fn fix_boundary(mut self, fix_boundary: bool) -> Self {
        self.fix_boundary = fix_boundary;
        self
    }
    /// Sets the vertices that never move.
    pub fn fixed(mut self, fixed: Vec<VertexId>) -> Self {
        self.fixed = fixed;
        self
    }
    /// Sets whether the points stay on the input surface.
    pub fn on_surface(mut self, on_surface: bool) -> Self {
        self.on_surface = on_surface;
        self
    }
    /// Sets [`QuadFairOptions::deviation_weights`].
    pub fn deviation_weights(mut self, on: bool) -> Self {
        self.deviation_weights = on;
        self
    }
    /// Sets the progress callback and cancel flag.
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }
}

/// What [`fair_structure_lines`] did; serialises to the JSON report of
/// `fairline fair-quad` (the CLI adds its timing keys).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct QuadFairReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of structure lines traced.
    pub structure_lines: usize,
    /// Vertices that were free in at least one iteration.
    pub free_vertices: usize,
    /// Eq. (30) energy (unit direction vectors) before fairing.
    pub structure_energy_before: f64,
    /// Eq. (30) energy after fairing.
    pub structure_energy_after: f64,
    /// Largest distance a vertex moved.
    pub max_displacement: f64,
    /// Iterations performed.
    pub iterations: usize,
}

/// Runs of four consecutive vertices of all lines (closed lines wrap), with
/// the index of the line of each run.
fn runs(lines: &[StructureLine]) -> (Vec<[u32; 4]>, Vec<u32>) {
    let mut out = Vec::new();
    let mut line_of = Vec::new();
    for (li, l) in lines.iter().enumerate() {
        let v = &l.vertices;
        let n = v.len();
        if l.closed {
            if n >= 4 {
                for i in 0..n {
                    out.push([v[i].0, v[(i + 1) % n].0, v[(i + 2) % n].0, v[(i + 3) % n].0]);
                }
            }
        } else if n >= 4 {
            for i in 0..n - 3 {
                out.push([v[i].0, v[i + 1].0, v[i + 2].0, v[i + 3].0]);
            }
        }
        line_of.resize(out.len(), li as u32);
    }
    (out, line_of)
}

/// Eq. (30) deviation vector of a run; zero-length edges contribute 0.
#[inline]
fn run_deviation(p: &[Vec3], r: &[u32; 4]) -> Vec3 {
    let d = |a: u32, b: u32| (p[b as usize] - p[a as usize]).normalize_or_zero();
    0.5 * (d(r[0], r[1]) + d(r[2], r[3])) - d(r[1], r[2])
}

/// The Eq. (30) energy Σ ‖½(v̂_{i−1} + v̂_{i+1}) − v̂_i‖² over every run of
/// four consecutive points of every structure line of `mesh`.
pub fn structure_energy(mesh: &SurfaceMesh) -> f64 {
    let (r, _) = runs(&structure_lines(mesh));
    energy_of(mesh.positions(), &r)
}

fn energy_of(p: &[Vec3], runs: &[[u32; 4]]) -> f64 {
    let parts: Vec<f64> = runs
        .par_iter()
        .with_min_len(4096)
        .map(|r| run_deviation(p, r).length_squared())
        .collect();
    parts.iter().sum()
}

/// Structure-line fairing (Grüner thesis §4.1). Per iteration: classify the
/// points by the deviation parameter, build for every run of four points the
/// linear residual of Eq. (32) with the lengths l of the current polygon
/// (coefficients −1/(2l₀), 1/(2l₀) + 1/l₁, −1/l₁ − 1/(2l₂), 1/(2l₂)),
/// minimise Σ‖A_i x + b_i‖² + (ω/ē²) Σ‖p − p⁰‖² over the free points
/// (Eq. (34)) by a sparse Cholesky factorisation of the normal equations
/// (above [`DIRECT_LIMIT`] free points by line-block conjugate gradients,
/// [`crate::solve::sandwich_pcg`]), move the free points onto the input
/// surface (unless [`QuadFairOptions::on_surface`] is off), then shrink the
/// deviation by `deviation_factor`. A boundary point is freed only by a run
/// above the initial deviation (a zigzag of the boundary line itself), never
/// by the shrunken one, which would eventually flag the natural turning of a
/// curved boundary. Fixed points keep bit-identical coordinates. Works on
/// any mesh whose structure lines are traced by [`structure_lines`] (quad
/// meshes in practice). The input is not modified; one progress step per
/// iteration goes to [`QuadFairOptions::control`], which can cancel the run
/// ([`QuadFairError::Cancelled`]).
pub fn fair_structure_lines(
    mesh: &SurfaceMesh,
    options: &QuadFairOptions,
) -> Result<Output<QuadFairReport>, QuadFairError> {
    fair_structure_lines_with(mesh, options, Method::Auto)
}

/// How the normal equations (ωI + AᵀA) x = c of one iteration are solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Method {
    /// [`Method::Direct`] up to [`DIRECT_LIMIT`] free vertices, else
    /// [`Method::Iterative`].
    Auto,
    /// Sparse Cholesky of the assembled normal matrix.
    #[cfg_attr(not(test), allow(dead_code))] // the tests compare the two
    Direct,
    /// Conjugate gradients preconditioned with per-line banded blocks only:
    /// not converging is an error (Auto falls back to Cholesky).
    #[cfg_attr(not(test), allow(dead_code))]
    Iterative,
}

/// The runs of four points of all structure lines and their incidences.
struct RunIndex {
    /// Runs in the order of their middle points.
    runs: Vec<[u32; 4]>,
    /// vertex → (run, slot) incidence, CSR: `inc[off[v]..off[v + 1]]`.
    off: Vec<u32>,
    inc: Vec<(u32, u8)>,
    /// Runs of line l: `line_runs[run_start[l]..run_start[l + 1]]`.
    run_start: Vec<usize>,
    line_runs: Vec<u32>,
}

impl RunIndex {
    fn new(lines: &[StructureLine], n: usize) -> RunIndex {
        let (runs, line_of) = {
            let (runs, line_of) = runs(lines);
            // runs in the order of their middle points, so that the runs
            // through a vertex sit close together in memory whichever line
            // they belong to (the iterative solve streams over them)
            let mut perm: Vec<u32> = (0..runs.len() as u32).collect();
            perm.par_sort_unstable_by_key(|&i| (runs[i as usize][1], runs[i as usize][2], i));
            (
                perm.iter().map(|&i| runs[i as usize]).collect::<Vec<_>>(),
                perm.iter()
                    .map(|&i| line_of[i as usize])
                    .collect::<Vec<_>>(),
            )
        };
        let mut off = vec![0u32; n + 1];
        for r in &runs {
            for &v in r {
                off[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            off[i + 1] += off[i];
        }
        let mut inc = vec![(0u32, 0u8); off[n] as usize];
        let mut fill = off.clone();
        for (ri, r) in runs.iter().enumerate() {
            for (s, &v) in r.iter().enumerate() {
                inc[fill[v as usize] as usize] = (ri as u32, s as u8);
                fill[v as usize] += 1;
            }
        }
        let mut run_start = vec![0usize; lines.len() + 1];
        for &l in &line_of {
            run_start[l as usize + 1] += 1;
        }
        for l in 0..lines.len() {
            run_start[l + 1] += run_start[l];
        }
        let mut line_runs = vec![0u32; runs.len()];
        let mut fill = run_start.clone();
        for (ri, &l) in line_of.iter().enumerate() {
            line_runs[fill[l as usize]] = ri as u32;
            fill[l as usize] += 1;
        }
        RunIndex {
            runs,
            off,
            inc,
            run_start,
            line_runs,
        }
    }
}

/// Vertices that never move: pinned ones, corners (boundary vertices of
/// valence ≤ 2), the whole boundary with [`QuadFairOptions::fix_boundary`],
/// and [`QuadFairOptions::fixed`].
fn hard_fixed_vertices(
    mesh: &SurfaceMesh,
    opts: &QuadFairOptions,
) -> Result<Vec<bool>, QuadFairError> {
    let n = mesh.vertex_count();
    let mut hard_fixed = vec![false; n];
    for v in mesh.vertices() {
        let b = mesh.is_boundary_vertex(v);
        if mesh.is_pinned(v) || (b && (opts.fix_boundary || mesh.valence(v) <= 2)) {
            hard_fixed[v.idx()] = true;
        }
    }
    for v in &opts.fixed {
        if v.idx() >= n {
            return Err(QuadFairError::FixedVertexOutOfRange {
                vertex: v.idx(),
                count: n,
            });
        }
        hard_fixed[v.idx()] = true;
    }
    Ok(hard_fixed)
}

/// The points a run above `deviation` frees (its two middle points; a
/// boundary point only when the run is above the initial deviation, a real
/// zigzag of the boundary line, because the shrinking deviation eventually
/// flags the natural turning of any curved boundary, and boundaries are
/// meant to stay).
fn classify(
    runs: &[[u32; 4]],
    cur: &[Vec3],
    deviation: f64,
    initial_deviation: f64,
    boundary: &[bool],
) -> (Vec<bool>, Vec<f64>) {
    let deviations: Vec<f64> = runs
        .par_iter()
        .with_min_len(4096)
        .map(|r| run_deviation(cur, r).length())
        .collect();
    let mut free = vec![false; cur.len()];
    let mut largest = vec![0.0f64; cur.len()];
    for (r, &d) in runs.iter().zip(&deviations) {
        for &v in &r[1..3] {
            largest[v as usize] = largest[v as usize].max(d);
        }
        if d > deviation {
            for &v in &r[1..3] {
                if d > initial_deviation || !boundary[v as usize] {
                    free[v as usize] = true;
                }
            }
        }
    }
    (free, largest)
}

/// Penalty weight ω_i of every vertex: `omega`, or with
/// [`QuadFairOptions::deviation_weights`] ω·δ / d_i where the vertex's
/// largest run deviation d_i exceeds the deviation parameter δ.
fn vertex_weights(omega: f64, by_deviation: bool, deviation: f64, largest: &[f64]) -> Vec<f64> {
    largest
        .iter()
        .map(|&d| {
            if by_deviation && d > deviation && deviation > 0.0 {
                omega * (deviation / d)
            } else {
                omega
            }
        })
        .collect()
}

/// Eq. (32) coefficients of every run from the current polygon.
fn run_coefficients(runs: &[[u32; 4]], cur: &[Vec3]) -> Vec<[f64; 4]> {
    runs.par_iter()
        .with_min_len(4096)
        .map(|r| {
            let l = |a: u32, b: u32| cur[a as usize].distance(cur[b as usize]);
            let inv = |x: f64| if x > 0.0 { 1.0 / x } else { 0.0 };
            let (a0, a1, a2) = (inv(l(r[0], r[1])), inv(l(r[1], r[2])), inv(l(r[2], r[3])));
            [-0.5 * a0, 0.5 * a0 + a1, -a1 - 0.5 * a2, 0.5 * a2]
        })
        .collect()
}

/// [`fair_structure_lines`] with a chosen linear solver (tests compare them).
pub(crate) fn fair_structure_lines_with(
    mesh: &SurfaceMesh,
    opts: &QuadFairOptions,
    method: Method,
) -> Result<Output<QuadFairReport>, QuadFairError> {
    if !(opts.weight > 0.0) || !opts.weight.is_finite() {
        return Err(QuadFairError::InvalidOption(
            "weight must be positive".into(),
        ));
    }
    if !(opts.deviation >= 0.0) || !(opts.deviation_factor > 0.0) {
        return Err(QuadFairError::InvalidOption(
            "deviation must be ≥ 0 and its factor > 0".into(),
        ));
    }
    let n = mesh.vertex_count();
    let boundary: Vec<bool> = mesh
        .vertices()
        .map(|v| mesh.is_boundary_vertex(v))
        .collect();
    let hard_fixed = hard_fixed_vertices(mesh, opts)?;
    let lines = structure_lines(mesh);
    let index_of_runs = RunIndex::new(&lines, n);
    let runs = &index_of_runs.runs;
    let p0 = mesh.positions().to_vec();
    let ebar = geom::mean_edge_length(mesh);
    let e_before = energy_of(&p0, runs);
    let mut report = QuadFairReport {
        vertices: n,
        structure_lines: lines.len(),
        structure_energy_before: e_before,
        structure_energy_after: e_before,
        ..Default::default()
    };
    if !(ebar > 0.0) || runs.is_empty() {
        return Ok(Output {
            positions: p0,
            report,
        });
    }
    let omega = opts.weight / (ebar * ebar);
    let line_family = line_families(&lines, n);
    let line_set = Lines {
        lines: &lines,
        run_start: &index_of_runs.run_start,
        line_runs: &index_of_runs.line_runs,
        family: &line_family,
    };
    let reference = opts.on_surface.then(|| ReferenceSurface::new(mesh));
    let mut cur = p0.clone();
    let mut ever_free = vec![false; n];
    let mut deviation = opts.deviation;
    let mut solver: Option<(Vec<usize>, CholeskySolver)> = None;
    let total = opts.iterations as u64;
    for iteration in 0..opts.iterations {
        opts.control.step("iterations", iteration as u64, total)?;
        report.iterations += 1;
        let (free, largest) = classify(runs, &cur, deviation, opts.deviation, &boundary);
        let weights = vertex_weights(omega, opts.deviation_weights, deviation, &largest);
        let mut index = vec![u32::MAX; n];
        let mut unknowns = Vec::new();
        for i in 0..n {
            if free[i] && !hard_fixed[i] {
                index[i] = unknowns.len() as u32;
                unknowns.push(i);
                ever_free[i] = true;
            }
        }
        deviation *= opts.deviation_factor;
        if unknowns.is_empty() {
            continue;
        }
        let coef = run_coefficients(runs, &cur);
        let system = System {
            runs,
            coef: &coef,
            off: &index_of_runs.off,
            inc: &index_of_runs.inc,
            index: &index,
            unknowns: &unknowns,
            omega: &weights,
            ebar,
            p0: &p0,
            cur: &cur,
        };
        let iterative = match method {
            Method::Auto => unknowns.len() > DIRECT_LIMIT,
            Method::Direct => false,
            Method::Iterative => true,
        };
        let solved = if iterative {
            system.solve_iterative(&line_set)?
        } else {
            None
        };
        let new_positions = match solved {
            Some(x) => x,
            None if method == Method::Iterative => {
                return Err(QuadFairError::Solve(SolveError::Backend(
                    "line-preconditioned conjugate gradients did not converge".into(),
                )));
            }
            None => system.solve_direct(&mut solver)?,
        };
        let new_positions: Vec<Vec3> = match &reference {
            Some(surface) => unknowns
                .par_iter()
                .zip(new_positions.into_par_iter())
                .map(|(&i, p)| surface.project(i, p))
                .collect(),
            None => new_positions,
        };
        for (&i, p) in unknowns.iter().zip(new_positions) {
            if p.is_finite() {
                cur[i] = p;
            }
        }
    }
    opts.control.progress("iterations", total, total);
    report.free_vertices = ever_free.iter().filter(|&&b| b).count();
    report.structure_energy_after = energy_of(&cur, runs);
    report.max_displacement = cur
        .iter()
        .zip(&p0)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    Ok(Output {
        positions: cur,
        report,
    })
}

#[cfg(test)]
mod bitwise_tests;
#[cfg(test)]
mod tests;
