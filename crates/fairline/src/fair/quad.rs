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

use crate::Vec3;
use crate::geom;
use crate::mesh::{MeshError, StructureLine, SurfaceMesh, VertexId, structure_lines};
use crate::solve::{BoxQpOptions, CholeskySolver, SolveError, box_qp, pcg, sparse_from_triplets};
use rayon::prelude::*;
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
}

/// Options of [`fair_structure_lines`].
#[derive(Clone, Debug, PartialEq)]
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
    /// (the thesis halves it). Default 0.5.
    pub deviation_factor: f64,
    /// Iterations (each reclassifies and re-linearises). Default 3.
    pub iterations: usize,
    /// Keep all boundary vertices fixed. Corners (boundary vertices of
    /// valence ≤ 2) are always fixed.
    pub fix_boundary: bool,
    /// Further vertices that never move.
    pub fixed: Vec<VertexId>,
}

impl Default for QuadFairOptions {
    fn default() -> Self {
        QuadFairOptions {
            weight: 0.01,
            deviation: 0.1,
            deviation_factor: 0.5,
            iterations: 3,
            fix_boundary: false,
            fixed: Vec::new(),
        }
    }
}

/// What [`fair_structure_lines`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QuadFairReport {
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
/// (Eq. (34)) by a sparse Cholesky factorisation of the normal equations,
/// then shrink the deviation by `deviation_factor`. Fixed points keep
/// bit-identical coordinates. Works on any mesh whose structure lines are
/// traced by [`structure_lines`] (quad meshes in practice).
pub fn fair_structure_lines(
    mesh: &mut SurfaceMesh,
    opts: &QuadFairOptions,
) -> Result<QuadFairReport, QuadFairError> {
    fair_structure_lines_with(mesh, opts, Method::Auto)
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

/// Largest number of free vertices solved by sparse Cholesky. The normal
/// matrix couples each vertex with the vertices up to three steps away along
/// both of its structure lines, so the Cholesky factor of a large grid fills
/// in heavily (1M unknowns: gigabytes, tens of seconds), while the
/// line-preconditioned conjugate gradients need a few dozen passes over N.
pub(crate) const DIRECT_LIMIT: usize = 20_000;

/// Accuracy ε of the iterative solve in units of the mean edge length ē:
/// the root mean square error of the computed displacements is at most ε·ē
/// (see [`System::solve_iterative`]).
const ITERATIVE_ACCURACY: f64 = 1e-7;

/// Shifts of the sandwich preconditioner P₁⁻¹P₂⁻¹P₁⁻¹ of
/// [`System::solve_iterative`], P_f = c_f I + K_f, in units of √(ωλ): the
/// values that minimise the condition number max/min over μ₁, μ₂ ∈ [0, λ]
/// of (ω + μ₁ + μ₂)/((c₁ + μ₁)²(c₂ + μ₂)) at ω = λ/1600 (the default
/// weight on a regular grid), found by a grid search.
const OUTER_SHIFT: f64 = 4.6;
/// See [`OUTER_SHIFT`].
const INNER_SHIFT: f64 = 1.22;

/// Iteration cap of the iterative solve; beyond it the solve falls back to
/// Cholesky.
const ITERATIVE_MAX_ITERATIONS: usize = 1_000;

/// The linear least-squares problem of one iteration: minimise
/// Σ_runs ‖A_r x‖² + ω‖x − p⁰‖² over the free points (fixed points enter A_r x
/// with their current positions), A_r the Eq. (32) row of run r.
struct System<'a> {
    runs: &'a [[u32; 4]],
    coef: &'a [[f64; 4]],
    /// vertex → (run, slot) incidence, CSR
    off: &'a [u32],
    inc: &'a [(u32, u8)],
    /// vertex → unknown index (u32::MAX when fixed)
    index: &'a [u32],
    unknowns: &'a [usize],
    omega: f64,
    /// mean edge length of the input
    ebar: f64,
    p0: &'a [Vec3],
    cur: &'a [Vec3],
}

impl System<'_> {
    /// Assembles ωI + AᵀA over the free points (lower triangle, by column,
    /// in parallel) and solves by sparse Cholesky with three right-hand
    /// sides; the symbolic analysis is reused while the free set is the same.
    fn solve_direct(
        &self,
        solver: &mut Option<(Vec<usize>, CholeskySolver)>,
    ) -> Result<Vec<Vec3>, QuadFairError> {
        let (runs, coef, index, cur, omega) =
            (self.runs, self.coef, self.index, self.cur, self.omega);
        let cols: Vec<(Vec<(usize, f64)>, Vec3)> = self
            .unknowns
            .par_iter()
            .map(|&j| {
                let mut e: Vec<(usize, f64)> = Vec::with_capacity(32);
                let mut rhs = omega * self.p0[j];
                e.push((index[j] as usize, omega));
                for &(ri, s) in &self.inc[self.off[j] as usize..self.off[j + 1] as usize] {
                    let r = &runs[ri as usize];
                    let c = &coef[ri as usize];
                    let aj = c[s as usize];
                    for t in 0..4 {
                        let k = r[t] as usize;
                        if index[k] != u32::MAX {
                            if index[k] >= index[j] {
                                e.push((index[k] as usize, aj * c[t]));
                            }
                        } else {
                            rhs -= aj * c[t] * cur[k];
                        }
                    }
                }
                e.sort_unstable_by_key(|x| x.0);
                let mut merged: Vec<(usize, f64)> = Vec::with_capacity(e.len());
                for (r, v) in e {
                    match merged.last_mut() {
                        Some(last) if last.0 == r => last.1 += v,
                        _ => merged.push((r, v)),
                    }
                }
                (merged, rhs)
            })
            .collect();
        let m = self.unknowns.len();
        let mut col_ptr = Vec::with_capacity(m + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        let mut rhs = vec![vec![0.0; m]; 3];
        for (c, (entries, b)) in cols.iter().enumerate() {
            for &(r, v) in entries {
                row_idx.push(r);
                vals.push(v);
            }
            col_ptr.push(row_idx.len());
            rhs[0][c] = b.x;
            rhs[1][c] = b.y;
            rhs[2][c] = b.z;
        }
        let sym = faer::sparse::SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let a = faer::sparse::SparseColMat::new(sym, vals);
        let reuse = match solver.as_mut() {
            Some((u, s)) if u.as_slice() == self.unknowns => s.refactor(a.as_ref()).is_ok(),
            _ => false,
        };
        if !reuse {
            *solver = Some((self.unknowns.to_vec(), CholeskySolver::new(a.as_ref())?));
        }
        if let Some((_, s)) = solver.as_ref() {
            s.solve_columns(&mut rhs)?;
        }
        Ok((0..m)
            .map(|c| Vec3::new(rhs[0][c], rhs[1][c], rhs[2][c]))
            .collect())
    }

    /// Solves the same normal equations N d = c, N = ωI + AᵀA, iteratively
    /// for the displacement d from the current positions x (warm start
    /// d = 0; c = ω(p⁰ − x) − Aᵀ(A x), A x over all points of a run, so the
    /// stopping test does not depend on where the mesh sits in space).
    ///
    /// The structure lines are split into two families (lines that cross get
    /// different families where the mesh allows, see [`line_families`]),
    /// N = ωI + K₁ + K₂ with K_f the Eq. (32) terms of the runs of family f.
    /// Along one line K_f is banded (a run spans four consecutive points),
    /// so P_f = c_f I + K_f is factored line by line ([`LineBlocks`]). The
    /// alternating-direction product P₁P₂ ≈ N (Peaceman–Rachford) is not
    /// symmetric when K₁ and K₂ do not commute (short lines around fixed
    /// points, scattered free sets), and its symmetrised inverse need not be
    /// positive definite, so the preconditioner is the sandwich
    /// M⁻¹ = P₁⁻¹P₂⁻¹P₁⁻¹ (three banded solves), symmetric positive definite
    /// for any mesh, and the solver is conjugate gradients ([`pcg`]) on the
    /// stacked x, y, z coordinates (the three systems share N). On a regular
    /// grid, where K₁ and K₂ commute with eigenvalues in [0, λ] (λ ≈ 16/ē²:
    /// the Eq. (32) row is half the third difference), the shifts
    /// c₁ = [`OUTER_SHIFT`]·√(ωλ) and c₂ = [`INNER_SHIFT`]·√(ωλ) minimise
    /// the condition number of M⁻¹N: about 48 at the default weight instead
    /// of about 3,200 for N itself. N is applied matrix-free as ωv + Aᵀ(Av).
    ///
    /// Stopping rule: ‖c − N d‖ ≤ ω·ε·ē·√(3m) with ε = [`ITERATIVE_ACCURACY`]
    /// and m free points. Since N ⪰ ωI, ‖d − d*‖ ≤ ‖c − N d‖/ω, so the root
    /// mean square error of the displacements is at most ε·ē whatever the
    /// mesh's size, scale or position. `None` if the iteration does not
    /// reach it (the caller then factors N).
    fn solve_iterative(&self, lines: &Lines<'_>) -> Result<Option<Vec<Vec3>>, QuadFairError> {
        let (runs, coef, index, cur, omega) =
            (self.runs, self.coef, self.index, self.cur, self.omega);
        let m = self.unknowns.len();
        let incident = |j: usize| &self.inc[self.off[j] as usize..self.off[j + 1] as usize];
        let residual: Vec<Vec3> = runs
            .par_iter()
            .zip(coef.par_iter())
            .with_min_len(4096)
            .map(|(r, c)| (0..4).map(|t| c[t] * cur[r[t] as usize]).sum())
            .collect();
        let mut rhs = vec![0.0; 3 * m];
        rhs.par_chunks_mut(3)
            .zip(self.unknowns.par_iter())
            .with_min_len(4096)
            .for_each(|(b, &j)| {
                let g: Vec3 = incident(j)
                    .iter()
                    .map(|&(ri, s)| coef[ri as usize][s as usize] * residual[ri as usize])
                    .sum();
                b.copy_from_slice(&(omega * (self.p0[j] - cur[j]) - g).to_array());
            });
        drop(residual);
        // √(ωλ), λ ≈ half the mean Gershgorin bound of K₁ + K₂ over
        // the unknowns: Σ_j Σ_{runs ∋ j} |a_j| Σ_{free t} |a_t| = Σ_runs S²
        // with S = Σ_{free t} |a_t|
        let gersh: f64 = runs
            .par_iter()
            .zip(coef.par_iter())
            .with_min_len(4096)
            .map(|(r, c)| {
                let s: f64 = (0..4)
                    .filter(|&t| index[r[t] as usize] != u32::MAX)
                    .map(|t| c[t].abs())
                    .sum();
                s * s
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        let scale = (2.0 * omega * gersh / m as f64 / 4.0).sqrt().max(omega);
        let (Some(p1), Some(p2)) = (
            LineBlocks::new(self, lines, 0, OUTER_SHIFT * scale),
            LineBlocks::new(self, lines, 1, INNER_SHIFT * scale),
        ) else {
            return Ok(None);
        };
        // per run the unknowns of its points (u32::MAX: fixed), and per
        // incidence of a vertex its coefficient, so that the product below
        // streams over arrays instead of looking them up
        let local: Vec<[u32; 4]> = runs
            .par_iter()
            .with_min_len(4096)
            .map(|r| r.map(|v| index[v as usize]))
            .collect();
        let inc_coef: Vec<f64> = self
            .inc
            .par_iter()
            .with_min_len(4096)
            .map(|&(ri, s)| coef[ri as usize][s as usize])
            .collect();
        let mut av = vec![Vec3::ZERO; runs.len()];
        // out = ωv + Aᵀ(Av) on interleaved x, y, z
        let apply = |v: &[f64], out: &mut [f64]| {
            av.par_iter_mut()
                .zip(local.par_iter().zip(coef.par_iter()))
                .with_min_len(4096)
                .for_each(|(o, (r, c))| {
                    let mut s = Vec3::ZERO;
                    for t in 0..4 {
                        if r[t] != u32::MAX {
                            let u = 3 * r[t] as usize;
                            s += c[t] * Vec3::new(v[u], v[u + 1], v[u + 2]);
                        }
                    }
                    *o = s;
                });
            let av: &Vec<Vec3> = &av;
            out.par_chunks_mut(3)
                .zip(v.par_chunks(3))
                .zip(self.unknowns.par_iter())
                .with_min_len(4096)
                .for_each(|((o, v), &j)| {
                    let (a, b) = (self.off[j] as usize, self.off[j + 1] as usize);
                    let mut g = Vec3::ZERO;
                    for (&(ri, _), &c) in self.inc[a..b].iter().zip(&inc_coef[a..b]) {
                        g += c * av[ri as usize];
                    }
                    o[0] = omega * v[0] + g.x;
                    o[1] = omega * v[1] + g.y;
                    o[2] = omega * v[2] + g.z;
                });
        };
        // z = M⁻¹ r = P₁⁻¹P₂⁻¹P₁⁻¹ r, P_f = c_f I + K_f
        let (mut a, mut b, mut y) = (vec![0.0; 3 * m], vec![0.0; 3 * m], Vec::new());
        let precondition = |r: &[f64], z: &mut [f64]| {
            p1.solve(r, &mut a, 1.0, false, &mut y);
            p2.solve(&a, &mut b, 1.0, false, &mut y);
            p1.solve(&b, z, 1.0, false, &mut y);
        };
        // stop at ‖c − N d‖ ≤ ω·ε·ē·√(3m): since N ⪰ ωI, the error of d then
        // has a root mean square of at most ε·ē per coordinate
        let norm_c = rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        let tolerance = if norm_c > 0.0 {
            omega * ITERATIVE_ACCURACY * self.ebar * ((3 * m) as f64).sqrt() / norm_c
        } else {
            0.0
        };
        let mut d = vec![0.0; 3 * m];
        let report = match pcg(
            apply,
            precondition,
            &rhs,
            &mut d,
            tolerance,
            ITERATIVE_MAX_ITERATIONS,
        ) {
            Ok(r) => r,
            Err(SolveError::NonFinite) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        if !report.converged {
            return Ok(None);
        }
        Ok(Some(
            self.unknowns
                .iter()
                .enumerate()
                .map(|(i, &j)| cur[j] + Vec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]))
                .collect(),
        ))
    }
}

/// The structure lines with their runs and families.
struct Lines<'a> {
    lines: &'a [StructureLine],
    /// runs of line l: `line_runs[run_start[l]..run_start[l + 1]]`
    run_start: &'a [usize],
    line_runs: &'a [u32],
    /// family (0 or 1) of every line
    family: &'a [u8],
}

/// c_f I + K_f of one family f, factored line by line: every unknown belongs
/// to the block of the first line of family f through it (or to a block of
/// its own), and the block of a line holds the Eq. (32) terms of the runs
/// of that line among the unknowns it owns, in line order. A run spans four
/// consecutive points, so a block is a banded matrix of bandwidth 3
/// (dropping points keeps neighbours within 3 places); a run that would
/// break the band (wrapping around a closed line, or meeting a point owned
/// by another line twice) is left out whole. Every block is then a shifted
/// sum of positive semi-definite run terms, hence positive definite, and its
/// banded Cholesky factor costs O(length).
struct LineBlocks {
    /// unknowns in block order
    order: Vec<u32>,
    /// position of every unknown in `order`
    place: Vec<u32>,
    /// banded Cholesky factor: row i holds L(i, i), L(i, i−1), L(i, i−2),
    /// L(i, i−3)
    factor: Vec<[f64; 4]>,
    /// block boundaries in `order`
    block_start: Vec<usize>,
    /// groups of consecutive blocks of similar total length (parallel work)
    group_start: Vec<usize>,
}

impl LineBlocks {
    /// `None` if a block is not numerically positive definite.
    fn new(sys: &System<'_>, lines: &Lines<'_>, f: u8, shift: f64) -> Option<LineBlocks> {
        let (index, m) = (sys.index, sys.unknowns.len());
        let mut place = vec![u32::MAX; m];
        let mut order: Vec<u32> = Vec::with_capacity(m);
        let mut block_start = vec![0usize];
        let mut block_line = Vec::new();
        for (li, l) in lines.lines.iter().enumerate() {
            if lines.family[li] != f {
                continue;
            }
            for v in &l.vertices {
                let u = index[v.idx()];
                if u != u32::MAX && place[u as usize] == u32::MAX {
                    place[u as usize] = order.len() as u32;
                    order.push(u);
                }
            }
            if order.len() > *block_start.last().unwrap_or(&0) {
                block_start.push(order.len());
                block_line.push(li as u32);
            }
        }
        for u in 0..m {
            if place[u] == u32::MAX {
                place[u] = order.len() as u32;
                order.push(u as u32);
                block_start.push(order.len());
                block_line.push(u32::MAX);
            }
        }
        // band of c_f I + K_f, then its factor, block by block in parallel
        let mut factor = vec![[shift, 0.0, 0.0, 0.0]; m];
        let mut slices: Vec<&mut [[f64; 4]]> = Vec::with_capacity(block_line.len());
        let mut rest: &mut [[f64; 4]] = &mut factor;
        for b in 0..block_line.len() {
            let (head, tail) = rest.split_at_mut(block_start[b + 1] - block_start[b]);
            slices.push(head);
            rest = tail;
        }
        let ok = slices
            .into_par_iter()
            .zip(block_line.par_iter())
            .zip(block_start.par_iter())
            .all(|((band, &li), &start)| {
                if li != u32::MAX {
                    let li = li as usize;
                    for &ri in &lines.line_runs[lines.run_start[li]..lines.run_start[li + 1]] {
                        let ri = ri as usize;
                        let (r, c) = (&sys.runs[ri], &sys.coef[ri]);
                        // local positions of the run's points in this block
                        let mut at = [usize::MAX; 4];
                        let mut fits = true;
                        for t in 0..4 {
                            let u = index[r[t] as usize];
                            if u != u32::MAX {
                                let p = place[u as usize] as usize;
                                if p >= start && p < start + band.len() {
                                    at[t] = p - start;
                                }
                            }
                        }
                        for t in 0..4 {
                            for w in 0..4 {
                                if at[t] != usize::MAX
                                    && at[w] != usize::MAX
                                    && at[t].abs_diff(at[w]) > 3
                                {
                                    fits = false;
                                }
                            }
                        }
                        if !fits {
                            continue;
                        }
                        for t in 0..4 {
                            for w in 0..4 {
                                if at[t] != usize::MAX && at[w] != usize::MAX && at[t] >= at[w] {
                                    band[at[t]][at[t] - at[w]] += c[t] * c[w];
                                }
                            }
                        }
                    }
                }
                banded_cholesky(band)
            });
        if !ok {
            return None;
        }
        // groups of about 4096 unknowns
        let mut group_start = vec![0usize];
        for &s in &block_start[1..] {
            if s - group_start.last().copied().unwrap_or(0) >= 4096 || s == m {
                group_start.push(s);
            }
        }
        group_start.dedup();
        Some(LineBlocks {
            order,
            place,
            factor,
            block_start,
            group_start,
        })
    }

    /// z = scale · (c_f I + K_f)⁻¹ r on interleaved x, y, z, or
    /// z += scale · (c_f I + K_f)⁻¹ r when `add`.
    /// `y` is scratch space.
    fn solve(&self, r: &[f64], z: &mut [f64], scale: f64, add: bool, y: &mut Vec<f64>) {
        // gather into block order, solve the blocks, scatter back
        y.resize(r.len(), 0.0);
        y.par_chunks_mut(3)
            .zip(self.order.par_iter())
            .with_min_len(4096)
            .for_each(|(y, &u)| {
                let u = 3 * u as usize;
                y.copy_from_slice(&r[u..u + 3]);
            });
        let mut chunks: Vec<(&mut [f64], usize)> = Vec::with_capacity(self.group_start.len());
        let mut rest: &mut [f64] = y;
        for g in self.group_start.windows(2) {
            let (head, tail) = rest.split_at_mut(3 * (g[1] - g[0]));
            chunks.push((head, g[0]));
            rest = tail;
        }
        chunks.into_par_iter().for_each(|(y, start)| {
            let first = self.block_start.partition_point(|&s| s < start);
            let mut b = first;
            while b + 1 < self.block_start.len() && self.block_start[b] < start + y.len() / 3 {
                let (s0, s1) = (self.block_start[b], self.block_start[b + 1]);
                banded_solve(
                    &self.factor[s0..s1],
                    &mut y[3 * (s0 - start)..3 * (s1 - start)],
                );
                b += 1;
            }
        });
        z.par_chunks_mut(3)
            .zip(self.place.par_iter())
            .with_min_len(4096)
            .for_each(|(z, &p)| {
                let p = 3 * p as usize;
                if add {
                    z[0] += scale * y[p];
                    z[1] += scale * y[p + 1];
                    z[2] += scale * y[p + 2];
                } else {
                    z[0] = scale * y[p];
                    z[1] = scale * y[p + 1];
                    z[2] = scale * y[p + 2];
                }
            });
    }
}

/// In-place Cholesky factor of a symmetric banded matrix of bandwidth 3
/// (row i: M(i, i), M(i, i−1), M(i, i−2), M(i, i−3)); false if a pivot is
/// not positive.
fn banded_cholesky(band: &mut [[f64; 4]]) -> bool {
    for i in 0..band.len() {
        for d in (1..=3.min(i)).rev() {
            let j = i - d;
            // L(i, j) = (M(i, j) − Σ_{k<j} L(i, k) L(j, k)) / L(j, j)
            let mut s = band[i][d];
            for k in (i.saturating_sub(3))..j {
                s -= band[i][i - k] * band[j][j - k];
            }
            band[i][d] = s * band[j][0];
        }
        let mut s = band[i][0];
        for d in 1..=3.min(i) {
            s -= band[i][d] * band[i][d];
        }
        if !(s > 0.0) || !s.is_finite() {
            return false;
        }
        band[i][0] = 1.0 / s.sqrt();
    }
    true
}

/// Solves L Lᵀ y = b in place for three interleaved right-hand sides; `l`
/// is the factor of [`banded_cholesky`] (reciprocal diagonal; the entries of
/// the first rows that reach before row 0 are zero).
fn banded_solve(l: &[[f64; 4]], y: &mut [f64]) {
    // forward: L w = b, keeping w_{i−1}, w_{i−2}, w_{i−3}
    let (mut w1, mut w2, mut w3) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    for (li, yi) in l.iter().zip(y.chunks_exact_mut(3)) {
        let mut s = [0.0; 3];
        for c in 0..3 {
            s[c] = (yi[c] - li[1] * w1[c] - li[2] * w2[c] - li[3] * w3[c]) * li[0];
        }
        yi.copy_from_slice(&s);
        (w3, w2, w1) = (w2, w1, s);
    }
    // backward: Lᵀ y = w, keeping y_{i+1..i+3} and the rows L(i+d, ·)
    let (mut y1, mut y2, mut y3) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    let (mut r1, mut r2, mut r3) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
    for (li, yi) in l.iter().zip(y.chunks_exact_mut(3)).rev() {
        let mut s = [0.0; 3];
        for c in 0..3 {
            s[c] = (yi[c] - r1[1] * y1[c] - r2[2] * y2[c] - r3[3] * y3[c]) * li[0];
        }
        yi.copy_from_slice(&s);
        (y3, y2, y1) = (y2, y1, s);
        (r3, r2, r1) = (r2, r1, *li);
    }
}

/// Splits the structure lines into two families: breadth-first over the
/// lines, a line gets the other family than the line it was reached from
/// through a shared point. On a grid-like mesh every crossing joins lines of
/// different families; where the line graph has odd cycles (around irregular
/// points) some crossings stay within one family, which only weakens the
/// preconditioner of [`System::solve_iterative`].
fn line_families(lines: &[StructureLine], n: usize) -> Vec<u8> {
    let mut off = vec![0usize; n + 1];
    for l in lines {
        for v in &l.vertices {
            off[v.idx() + 1] += 1;
        }
    }
    for i in 0..n {
        off[i + 1] += off[i];
    }
    let mut through = vec![0u32; off[n]];
    let mut fill = off.clone();
    for (li, l) in lines.iter().enumerate() {
        for v in &l.vertices {
            through[fill[v.idx()]] = li as u32;
            fill[v.idx()] += 1;
        }
    }
    let mut family = vec![u8::MAX; lines.len()];
    let mut queue = std::collections::VecDeque::new();
    for start in 0..lines.len() {
        if family[start] != u8::MAX {
            continue;
        }
        family[start] = 0;
        queue.push_back(start);
        while let Some(l) = queue.pop_front() {
            for v in &lines[l].vertices {
                for &o in &through[off[v.idx()]..off[v.idx() + 1]] {
                    if family[o as usize] == u8::MAX {
                        family[o as usize] = 1 - family[l];
                        queue.push_back(o as usize);
                    }
                }
            }
        }
    }
    family
}

/// [`fair_structure_lines`] with a chosen linear solver (tests compare them).
pub(crate) fn fair_structure_lines_with(
    mesh: &mut SurfaceMesh,
    opts: &QuadFairOptions,
    method: Method,
) -> Result<QuadFairReport, QuadFairError> {
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
    let lines = structure_lines(mesh);
    let (runs, line_of) = {
        let (runs, line_of) = runs(&lines);
        // runs in the order of their middle points, so that the runs through
        // a vertex sit close together in memory whichever line they belong
        // to (the iterative solve streams over them)
        let mut perm: Vec<u32> = (0..runs.len() as u32).collect();
        perm.par_sort_unstable_by_key(|&i| (runs[i as usize][1], runs[i as usize][2], i));
        (
            perm.iter().map(|&i| runs[i as usize]).collect::<Vec<_>>(),
            perm.iter()
                .map(|&i| line_of[i as usize])
                .collect::<Vec<_>>(),
        )
    };
    // vertex → (run, slot) incidence in CSR form
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
    let p0 = mesh.positions().to_vec();
    let ebar = geom::mean_edge_length(mesh);
    let e_before = energy_of(&p0, &runs);
    let mut report = QuadFairReport {
        structure_lines: lines.len(),
        structure_energy_before: e_before,
        structure_energy_after: e_before,
        ..Default::default()
    };
    if !(ebar > 0.0) || runs.is_empty() {
        return Ok(report);
    }
    let omega = opts.weight / (ebar * ebar);
    let line_family = line_families(&lines, n);
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
    let line_set = Lines {
        lines: &lines,
        run_start: &run_start,
        line_runs: &line_runs,
        family: &line_family,
    };
    let mut cur = p0.clone();
    let mut ever_free = vec![false; n];
    let mut deviation = opts.deviation;
    let mut solver: Option<(Vec<usize>, CholeskySolver)> = None;
    for _ in 0..opts.iterations {
        report.iterations += 1;
        // classification
        let flagged: Vec<bool> = runs
            .par_iter()
            .with_min_len(4096)
            .map(|r| run_deviation(&cur, r).length() > deviation)
            .collect();
        let mut free = vec![false; n];
        for (r, _) in runs.iter().zip(&flagged).filter(|(_, f)| **f) {
            free[r[1] as usize] = true;
            free[r[2] as usize] = true;
        }
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
        // Eq. (32) coefficients from the current polygon
        let coef: Vec<[f64; 4]> = runs
            .par_iter()
            .with_min_len(4096)
            .map(|r| {
                let l = |a: u32, b: u32| cur[a as usize].distance(cur[b as usize]);
                let inv = |x: f64| if x > 0.0 { 1.0 / x } else { 0.0 };
                let (a0, a1, a2) = (inv(l(r[0], r[1])), inv(l(r[1], r[2])), inv(l(r[2], r[3])));
                [-0.5 * a0, 0.5 * a0 + a1, -a1 - 0.5 * a2, 0.5 * a2]
            })
            .collect();
        let system = System {
            runs: &runs,
            coef: &coef,
            off: &off,
            inc: &inc,
            index: &index,
            unknowns: &unknowns,
            omega,
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
        for (&i, p) in unknowns.iter().zip(new_positions) {
            if p.is_finite() {
                cur[i] = p;
            }
        }
    }
    report.free_vertices = ever_free.iter().filter(|&&b| b).count();
    report.structure_energy_after = energy_of(&cur, &runs);
    report.max_displacement = cur
        .iter()
        .zip(&p0)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    mesh.set_positions(cur)?;
    Ok(report)
}

/// Options of [`fair_polyline_network`].
#[derive(Clone, Debug, PartialEq)]
pub struct PolylineNetworkOptions {
    /// Half height h of every tolerance cylinder, in units of the mean edge
    /// length (so |z − z⁰| ≤ h·ē). Default 0.1.
    pub tolerance: f64,
    /// Optional per-vertex half heights (absolute, overriding `tolerance`);
    /// 0 fixes a vertex.
    pub per_vertex: Option<Vec<f64>>,
}

impl Default for PolylineNetworkOptions {
    fn default() -> Self {
        PolylineNetworkOptions {
            tolerance: 0.1,
            per_vertex: None,
        }
    }
}

/// What [`fair_polyline_network`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolylineNetworkReport {
    /// Height-only bending energy Σ (z_{k−1} − 2z_k + z_{k+1})² before.
    pub energy_before: f64,
    /// The same after.
    pub energy_after: f64,
    /// Vertices that ended on the top or bottom of their cylinder.
    pub at_bound: usize,
    /// QP iterations.
    pub iterations: usize,
}

/// Fair polyline network with tolerance cylinders (Grüner thesis §3.1.1,
/// Hofer et al.): only the heights z move; minimise the height-only bending
/// energy E = Σ over structure lines of Σ_k (z_{k−1} − 2z_k + z_{k+1})²
/// (the z part of Eq. (11)) subject to |z − z⁰| ≤ h, a convex
/// bound-constrained QP solved exactly by [`box_qp`] in the displacement
/// d = z − z⁰ (so the solver starts at the input).
///
/// E is only positive semi-definite (heights bilinear in the grid indices
/// cost nothing), so a proximal term ε‖d‖² with ε = 1e-9·max diag(Q) is
/// added: it makes the problem strictly convex and picks, among the
/// minimisers of E, the one closest to the input; its effect on E is of
/// relative order 1e-9.
pub fn fair_polyline_network(
    mesh: &mut SurfaceMesh,
    opts: &PolylineNetworkOptions,
) -> Result<PolylineNetworkReport, QuadFairError> {
    let n = mesh.vertex_count();
    let ebar = geom::mean_edge_length(mesh);
    if !(opts.tolerance >= 0.0) || !opts.tolerance.is_finite() {
        return Err(QuadFairError::InvalidOption(
            "tolerance must be finite and ≥ 0".into(),
        ));
    }
    let h: Vec<f64> = match &opts.per_vertex {
        Some(v) if v.len() == n => v.clone(),
        Some(v) => {
            return Err(QuadFairError::InvalidOption(format!(
                "{} per-vertex tolerances for {n} vertices",
                v.len()
            )));
        }
        None => vec![opts.tolerance * ebar; n],
    };
    if h.iter().any(|x| !(*x >= 0.0) || !x.is_finite()) {
        return Err(QuadFairError::InvalidOption(
            "tolerances must be finite and ≥ 0".into(),
        ));
    }
    let z0: Vec<f64> = mesh.positions().iter().map(|p| p.z).collect();
    let mut trip = Vec::new();
    let mut triples = Vec::new();
    for l in structure_lines(mesh) {
        let v = &l.vertices;
        let m = v.len();
        let count = if l.closed { m } else { m.saturating_sub(2) };
        for i in 0..count {
            let t = [v[i].idx(), v[(i + 1) % m].idx(), v[(i + 2) % m].idx()];
            triples.push(t);
            let c = [1.0, -2.0, 1.0];
            for a in 0..3 {
                for b in 0..3 {
                    trip.push((t[a], t[b], 2.0 * c[a] * c[b]));
                }
            }
        }
    }
    let energy = |z: &[f64]| -> f64 {
        triples
            .iter()
            .map(|t| (z[t[0]] - 2.0 * z[t[1]] + z[t[2]]).powi(2))
            .sum()
    };
    let e0 = energy(&z0);
    if triples.is_empty() || n == 0 {
        return Ok(PolylineNetworkReport {
            energy_before: e0,
            energy_after: e0,
            ..Default::default()
        });
    }
    // Q of E(z) = ½ zᵀQz (both triangles), plus the proximal diagonal
    let mut diag = vec![0.0f64; n];
    for &(i, j, v) in &trip {
        if i == j {
            diag[i] += v;
        }
    }
    let eps = 1e-9 * diag.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-300);
    for (i, d) in diag.iter().enumerate() {
        trip.push((i, i, if *d > 0.0 { eps } else { 1.0 }));
    }
    let q = sparse_from_triplets(n, n, &trip)?;
    // E(z⁰ + d) = ½ dᵀQd + (Qz⁰)ᵀd + const (proximal term only on d)
    let mut c = vec![0.0; n];
    for t in &triples {
        let r = 2.0 * (z0[t[0]] - 2.0 * z0[t[1]] + z0[t[2]]);
        c[t[0]] += r;
        c[t[1]] -= 2.0 * r;
        c[t[2]] += r;
    }
    let lo: Vec<f64> = h.iter().map(|x| -x).collect();
    let sol = box_qp(q.as_ref(), &c, &lo, &h, &BoxQpOptions::default())?;
    let z: Vec<f64> = (0..n)
        .map(|i| {
            let d = sol.x[i].clamp(-h[i], h[i]);
            if d.is_finite() { z0[i] + d } else { z0[i] }
        })
        .collect();
    let report = PolylineNetworkReport {
        energy_before: e0,
        energy_after: energy(&z),
        at_bound: (0..n)
            .filter(|&i| h[i] > 0.0 && sol.x[i].abs() >= h[i])
            .count(),
        iterations: sol.iterations,
    };
    for (p, zi) in mesh.positions_mut().iter_mut().zip(&z) {
        p.z = *zi;
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use crate::smooth::{LaplaceOptions, TaubinOptions, laplace_smooth, taubin_smooth};

    /// Quad grid of `truth` over [−1, 1]² with a planted zigzag: interior
    /// vertices shifted alternately ±δ·h across the lines of constant i
    /// (and, weaker, of constant j). Returns (truth mesh, zigzag mesh).
    pub(crate) fn zigzag_grid(
        nx: u32,
        ny: u32,
        delta: f64,
        truth: impl Fn(f64, f64) -> f64,
    ) -> (SurfaceMesh, SurfaceMesh) {
        let t = shapes::quad_grid(nx, ny, (-1.0, 1.0), (-1.0, 1.0), &truth);
        let mut z = t.clone();
        let hx = 2.0 / (nx - 1) as f64;
        let hy = 2.0 / (ny - 1) as f64;
        for (k, p) in z.positions_mut().iter_mut().enumerate() {
            let (i, j) = (k as u32 % nx, k as u32 / nx);
            if i == 0 || j == 0 || i == nx - 1 || j == ny - 1 {
                continue;
            }
            let sx = if j % 2 == 0 { 1.0 } else { -1.0 };
            let sy = if i % 2 == 0 { 1.0 } else { -1.0 };
            let (x, y) = (p.x + sx * delta * hx, p.y + 0.5 * sy * delta * hy);
            *p = Vec3::new(x, y, truth(x, y));
        }
        (t, z)
    }

    fn mean_dist(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
        a.positions()
            .iter()
            .zip(b.positions())
            .map(|(p, q)| p.distance(*q))
            .sum::<f64>()
            / a.vertex_count() as f64
    }

    fn boundary_drift(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
        a.vertices()
            .filter(|v| a.is_boundary_vertex(*v))
            .map(|v| a.position(v).distance(b.position(v)))
            .fold(0.0, f64::max)
    }

    #[test]
    fn zigzag_structure_lines_are_straightened_closer_to_the_truth_than_laplace_and_taubin() {
        type Surface = Box<dyn Fn(f64, f64) -> f64>;
        let cases: Vec<(u32, u32, Surface)> = vec![
            (10, 10, Box::new(|x, y| 0.4 * (x * x - y * y))),
            (
                13,
                13,
                Box::new(|x, y| 0.3 * (1.5 * x).sin() * (1.0 + 0.5 * y * y) + 0.2 * x * y),
            ),
            (
                22,
                41,
                Box::new(|x, y| 0.5 * (1.0 - 0.3 * x * x) * (0.8 * y).cos()),
            ),
        ];
        for (nx, ny, f) in cases {
            let (truth, zz) = zigzag_grid(nx, ny, 0.2, &f);
            let mut ours = zz.clone();
            let r = fair_structure_lines(&mut ours, &QuadFairOptions::default()).unwrap();
            let mut lap = zz.clone();
            laplace_smooth(
                &mut lap,
                &LaplaceOptions {
                    iterations: 10,
                    ..Default::default()
                },
            )
            .unwrap();
            let mut tau = zz.clone();
            taubin_smooth(
                &mut tau,
                &TaubinOptions {
                    iterations: 10,
                    ..Default::default()
                },
            )
            .unwrap();
            let (e_l, e_t) = (structure_energy(&lap), structure_energy(&tau));
            let (d_ours, d_lap, d_tau) = (
                mean_dist(&ours, &truth),
                mean_dist(&lap, &truth),
                mean_dist(&tau, &truth),
            );
            let (b_ours, b_lap, b_tau) = (
                boundary_drift(&ours, &zz),
                boundary_drift(&lap, &zz),
                boundary_drift(&tau, &zz),
            );
            let what = format!(
                "{nx}×{ny}: E {:.3e}→{:.3e} (Laplace {e_l:.3e}, Taubin {e_t:.3e}); distance to truth {d_ours:.3e} (Laplace {d_lap:.3e}, Taubin {d_tau:.3e}, input {:.3e}); boundary drift {b_ours:.3e} ({b_lap:.3e}, {b_tau:.3e})",
                r.structure_energy_before,
                r.structure_energy_after,
                mean_dist(&zz, &truth)
            );
            // the zigzag is gone: Eq. (30) energy drops by more than 100×,
            // below that of Laplace and Taubin (at least as smooth) ...
            assert!(
                r.structure_energy_after < 0.01 * r.structure_energy_before,
                "{what}"
            );
            assert!(r.structure_energy_after < e_l.min(e_t), "{what}");
            // ... while moving toward the truth, closer than both, and
            // keeping the boundary where Laplace and Taubin pull it in
            assert!(
                d_ours < mean_dist(&zz, &truth) && d_ours < d_lap.min(d_tau),
                "{what}"
            );
            assert!(b_ours < 0.5 * b_lap.min(b_tau), "{what}");
            assert!(
                r.free_vertices > 0 && r.structure_lines == (nx + ny) as usize,
                "{what}"
            );
        }
    }

    /// The line-preconditioned conjugate gradients (used above
    /// [`DIRECT_LIMIT`] free vertices) and Cholesky solve the same normal
    /// equations: on a 60 × 60 zigzag grid with a few fixed vertices the
    /// fairings agree to 1e-6 of the mean edge length at every vertex (the
    /// stopping rule bounds the RMS error of each solve by 1e-7·ē), reach
    /// the same Eq. (30) energy, keep the fixed vertices and corners
    /// bit-identical, and the iteration is deterministic and does not
    /// depend on where the mesh sits in space.
    #[test]
    fn iterative_and_cholesky_solves_give_the_same_fairing() {
        let (_, zz) = zigzag_grid(60, 60, 0.2, |x, y| 0.3 * (x * x - y * y) + 0.1 * x);
        let ebar = crate::geom::mean_edge_length(&zz);
        let fixed = [VertexId(61), VertexId(1234), VertexId(2000)];
        let o = QuadFairOptions {
            fixed: fixed.to_vec(),
            ..Default::default()
        };
        let mut direct = zz.clone();
        let rd = fair_structure_lines_with(&mut direct, &o, Method::Direct).unwrap();
        let mut it = zz.clone();
        let ri = fair_structure_lines_with(&mut it, &o, Method::Iterative).unwrap();
        let worst = max_distance(&direct, &it);
        assert!(
            worst <= 1e-6 * ebar,
            "iterative vs Cholesky: {worst:e} (ē = {ebar})"
        );
        assert_eq!(rd.free_vertices, ri.free_vertices);
        assert!(rd.free_vertices > 3000, "{rd:?}");
        assert!(ri.structure_energy_after < 0.01 * ri.structure_energy_before);
        assert!(
            (ri.structure_energy_after - rd.structure_energy_after).abs()
                <= 1e-4 * rd.structure_energy_after,
            "{ri:?} vs {rd:?}"
        );
        for v in fixed.into_iter().chain([0, 59, 3540, 3599].map(VertexId)) {
            assert_eq!(it.position(v), zz.position(v));
        }
        let mut again = zz.clone();
        fair_structure_lines_with(&mut again, &o, Method::Iterative).unwrap();
        assert_eq!(again.positions(), it.positions(), "deterministic");
        let shift = Vec3::new(1e4, -2e4, 3e4);
        let mut far = zz.clone();
        for p in far.positions_mut() {
            *p += shift;
        }
        fair_structure_lines_with(&mut far, &o, Method::Iterative).unwrap();
        for (p, q) in far.positions().iter().zip(it.positions()) {
            assert!((*p - shift).distance(*q) <= 1e-6 * ebar);
        }
    }

    /// The same agreement on a mesh whose structure lines cannot be split
    /// into two families of non-crossing lines: three faces of a cube
    /// meeting at an interior vertex of valence 3, with noise. Lines bend
    /// around the cube edges and three kinds of lines cross pairwise, so the
    /// preconditioner keeps some crossings within one family.
    #[test]
    fn iterative_solve_agrees_with_cholesky_around_an_irregular_vertex() {
        let n = 24u32;
        let mut index = std::collections::HashMap::new();
        let mut pos = Vec::new();
        let mut faces: Vec<[u32; 4]> = Vec::new();
        let mut state = 0x2545f4914f6cdd1du64;
        let mut vid = |l: [u32; 3], pos: &mut Vec<Vec3>| -> u32 {
            *index.entry(l).or_insert_with(|| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.3;
                let p = Vec3::new(l[0] as f64, l[1] as f64, l[2] as f64) / n as f64;
                pos.push(p + Vec3::splat(noise / n as f64));
                (pos.len() - 1) as u32
            })
        };
        for a in 0..n {
            for b in 0..n {
                let quads = [
                    [[0, a, b], [0, a + 1, b], [0, a + 1, b + 1], [0, a, b + 1]],
                    [[a, 0, b], [a, 0, b + 1], [a + 1, 0, b + 1], [a + 1, 0, b]],
                    [[a, b, 0], [a + 1, b, 0], [a + 1, b + 1, 0], [a, b + 1, 0]],
                ];
                for q in quads {
                    faces.push(q.map(|l| vid(l, &mut pos)));
                }
            }
        }
        let mesh = SurfaceMesh::new(pos, &faces).unwrap();
        assert_eq!(mesh.valence(VertexId(0)), 3);
        let ebar = crate::geom::mean_edge_length(&mesh);
        let o = QuadFairOptions::default();
        let mut direct = mesh.clone();
        let rd = fair_structure_lines_with(&mut direct, &o, Method::Direct).unwrap();
        let mut it = mesh.clone();
        fair_structure_lines_with(&mut it, &o, Method::Iterative).unwrap();
        assert!(rd.free_vertices > 100, "{rd:?}");
        let worst = max_distance(&direct, &it);
        assert!(
            worst <= 1e-6 * ebar,
            "iterative vs Cholesky: {worst:e} (ē = {ebar})"
        );
    }

    fn max_distance(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
        a.positions()
            .iter()
            .zip(b.positions())
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max)
    }

    #[test]
    fn corners_and_fixed_vertices_stay_bit_identical_and_the_weight_is_scale_invariant() {
        let (_, zz) = zigzag_grid(12, 12, 0.2, |x, y| 0.3 * x * y);
        let fixed = vec![VertexId(25), VertexId(40), VertexId(77)];
        let o = QuadFairOptions {
            fixed: fixed.clone(),
            ..Default::default()
        };
        let mut a = zz.clone();
        fair_structure_lines(&mut a, &o).unwrap();
        for v in fixed.iter().copied().chain([0, 11, 132, 143].map(VertexId)) {
            assert_eq!(a.position(v), zz.position(v));
        }
        assert!(
            a.positions()
                .iter()
                .zip(zz.positions())
                .any(|(p, q)| p != q)
        );
        // the same mesh scaled by 1000 gives the same result scaled by 1000
        let mut big = zz.clone();
        for p in big.positions_mut() {
            *p *= 1000.0;
        }
        fair_structure_lines(&mut big, &o).unwrap();
        for (p, q) in big.positions().iter().zip(a.positions()) {
            assert!((*p / 1000.0 - *q).length() < 1e-9, "{p} vs {q}");
        }
        // bad options and indices are errors
        let bad = QuadFairOptions {
            fixed: vec![VertexId(999)],
            ..Default::default()
        };
        assert!(matches!(
            fair_structure_lines(&mut a, &bad),
            Err(QuadFairError::FixedVertexOutOfRange { .. })
        ));
        let bad = QuadFairOptions {
            weight: f64::NAN,
            ..Default::default()
        };
        assert!(fair_structure_lines(&mut a, &bad).is_err());
    }

    #[test]
    fn polyline_network_flattens_bumps_within_the_tolerance_cylinders() {
        // a plane z = 0 with a planted bump of height 0.3·ē: with h = 0.1·ē
        // the bump can only come down by h, and it does, exactly
        let mut m = shapes::quad_grid(9, 9, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
        let e = crate::geom::mean_edge_length(&m);
        m.positions_mut()[40].z = 0.3 * e;
        let z0: Vec<f64> = m.positions().iter().map(|p| p.z).collect();
        let o = PolylineNetworkOptions {
            per_vertex: Some(vec![0.1 * e; 81]),
            ..Default::default()
        };
        let r = fair_polyline_network(&mut m, &o).unwrap();
        assert!(r.energy_after < r.energy_before);
        for (p, z) in m.positions().iter().zip(&z0) {
            assert!((p.z - z).abs() <= 0.1 * e * (1.0 + 1e-12));
        }
        assert!(
            (m.positions()[40].z - 0.2 * e).abs() < 1e-9 * e,
            "{}",
            m.positions()[40].z
        );
        assert!(r.at_bound > 0);
        // a per-vertex tolerance of 0 keeps that height bit-identical
        let mut m2 = shapes::quad_grid(9, 9, (0.0, 1.0), (0.0, 1.0), |x, y| (3.0 * x).sin() * y);
        let zin: Vec<f64> = m2.positions().iter().map(|p| p.z).collect();
        let mut h = vec![0.05; 81];
        h[10] = 0.0;
        let o = PolylineNetworkOptions {
            per_vertex: Some(h),
            ..Default::default()
        };
        fair_polyline_network(&mut m2, &o).unwrap();
        assert_eq!(m2.positions()[10].z, zin[10]);
    }
}
