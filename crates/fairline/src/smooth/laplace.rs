//! Laplace smoothing (Grüner thesis §3.2.2, Eq. (16)–(18)), Taubin λ|μ
//! smoothing (§3.2.3, Eq. (19)) and implicit backward-Euler smoothing
//! (Desbrun et al. 1999), with the constraints of §3.2.4.
//!
//! Explicit steps are Jacobi updates x'_i = x_i + s Σ_j ω_ij (x_j − x_i) with
//! weights normalised to sum 1 over the neighbourhood (Eq. (17)); they run in
//! parallel over CSR neighbour arrays and are deterministic.

use super::{
    Constraints, Neighbourhoods, Role, SmoothError, SmoothReport, max_distance, restore_volume,
    roles,
};
use crate::Vec3;
use crate::geom::{self, LaplaceWeights};
use crate::mesh::SurfaceMesh;
use crate::solve::{CholeskyOptions, CholeskyOrdering, CholeskySolver, nested_dissection};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use rayon::prelude::*;

/// Options of [`laplace_smooth`].
#[derive(Clone, Debug, PartialEq)]
pub struct LaplaceOptions {
    /// Edge weights: uniform, edge length to a power (exponent −1 by
    /// default, §3.2.5) or cotangent (Desbrun; triangle meshes only).
    /// Geometry-dependent weights are recomputed before every step.
    pub weights: LaplaceWeights,
    /// Scale factor λ of Eq. (18), 0 < λ < 1.
    pub lambda: f64,
    /// Number of steps.
    pub iterations: usize,
    /// Constraints (§3.2.4).
    pub constraints: Constraints,
}

impl Default for LaplaceOptions {
    fn default() -> Self {
        LaplaceOptions {
            weights: LaplaceWeights::Uniform,
            lambda: 0.5,
            iterations: 10,
            constraints: Constraints::default(),
        }
    }
}

/// Options of [`taubin_smooth`].
#[derive(Clone, Debug, PartialEq)]
pub struct TaubinOptions {
    /// Edge weights (see [`LaplaceOptions::weights`]).
    pub weights: LaplaceWeights,
    /// Positive scale factor λ; `None` chooses it from the pass band by the
    /// rule f(1) = −f(2) ([`taubin_lambda_for_pass_band`]).
    pub lambda: Option<f64>,
    /// Negative scale factor μ; `None` derives it from the pass band,
    /// 1/λ + 1/μ = k_PB (Eq. (19)).
    pub mu: Option<f64>,
    /// Pass-band frequency k_PB (0 < k_PB < 1; default 0.1).
    pub pass_band: f64,
    /// Iterations; each is one λ step followed by one μ step.
    pub iterations: usize,
    /// Constraints (§3.2.4).
    pub constraints: Constraints,
}

impl Default for TaubinOptions {
    fn default() -> Self {
        TaubinOptions {
            weights: LaplaceWeights::Uniform,
            lambda: None,
            mu: None,
            pass_band: 0.1,
            iterations: 10,
            constraints: Constraints::default(),
        }
    }
}

/// The scale factors of a Taubin filter and its transfer function
/// f(k) = (1 − λk)(1 − μk) (Grüner §3.2.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaubinParameters {
    /// Positive scale factor.
    pub lambda: f64,
    /// Negative scale factor.
    pub mu: f64,
    /// Pass-band frequency 1/λ + 1/μ (Eq. (19)).
    pub pass_band: f64,
}

impl TaubinParameters {
    /// Transfer function of one iteration, f(k) = (1 − λk)(1 − μk).
    pub fn transfer(&self, k: f64) -> f64 {
        (1.0 - self.lambda * k) * (1.0 - self.mu * k)
    }

    /// Samples (k, f(k)) at k = 0, 0.1, …, 2 (the spectrum of the normalised
    /// operator K = I − W lies in [0, 2]).
    pub fn transfer_samples(&self) -> Vec<(f64, f64)> {
        (0..=20)
            .map(|i| {
                let k = i as f64 * 0.1;
                (k, self.transfer(k))
            })
            .collect()
    }

    /// Resolves λ and μ from the options (Eq. (19) and the f(1) = −f(2) rule).
    pub fn from_options(o: &TaubinOptions) -> Result<Self, SmoothError> {
        let (lambda, mu) = match (o.lambda, o.mu) {
            (Some(l), Some(m)) => (l, m),
            (Some(l), None) => {
                // 1/μ = k_PB − 1/λ
                let inv = o.pass_band - 1.0 / l;
                if !(inv < 0.0) {
                    return Err(SmoothError::InvalidOption(format!(
                        "λ = {l} and k_PB = {} give no negative μ (need k_PB < 1/λ)",
                        o.pass_band
                    )));
                }
                (l, 1.0 / inv)
            }
            (None, Some(m)) => {
                let inv = o.pass_band - 1.0 / m;
                if !(inv > 0.0) {
                    return Err(SmoothError::InvalidOption(format!(
                        "μ = {m} and k_PB = {} give no positive λ",
                        o.pass_band
                    )));
                }
                (1.0 / inv, m)
            }
            (None, None) => taubin_lambda_for_pass_band(o.pass_band)?,
        };
        if !(lambda > 0.0) || !(mu < -lambda) || !lambda.is_finite() || !mu.is_finite() {
            return Err(SmoothError::InvalidOption(format!(
                "Taubin needs 0 < λ < −μ, got λ = {lambda}, μ = {mu}"
            )));
        }
        Ok(TaubinParameters {
            lambda,
            mu,
            pass_band: 1.0 / lambda + 1.0 / mu,
        })
    }
}

/// λ and μ for the pass band k_PB (0 < k_PB < 1) chosen by Taubin's rule
/// f(1) = −f(2) (Grüner §3.2.3): with s = λ + μ and p = λμ the rule gives
/// 2 − 3s + 5p = 0 and Eq. (19) gives s = k_PB p, so p = 2 / (3k_PB − 5) and
/// λ, μ are the positive and negative roots of t² − s t + p.
/// For k_PB = 0.1: λ ≈ 0.6307, μ ≈ −0.6732.
pub fn taubin_lambda_for_pass_band(k_pb: f64) -> Result<(f64, f64), SmoothError> {
    if !(k_pb > 0.0 && k_pb < 1.0) {
        return Err(SmoothError::InvalidOption(format!(
            "pass band must lie in (0, 1), got {k_pb}"
        )));
    }
    let p = 2.0 / (3.0 * k_pb - 5.0);
    let s = k_pb * p;
    let disc = (s * s - 4.0 * p).sqrt();
    Ok((0.5 * (s + disc), 0.5 * (s - disc)))
}

/// Options of [`implicit_smooth`].
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitOptions {
    /// Time step in units of the squared mean edge length of the input, so
    /// the result does not depend on the scale of the mesh (default 1).
    pub time_step: f64,
    /// Number of backward-Euler steps.
    pub iterations: usize,
    /// Constraints (§3.2.4).
    pub constraints: Constraints,
}

impl Default for ImplicitOptions {
    fn default() -> Self {
        ImplicitOptions {
            time_step: 1.0,
            iterations: 1,
            constraints: Constraints::default(),
        }
    }
}

/// Normalised weights per neighbourhood entry (Eq. (17)); `None` for uniform.
fn normalised_weights(
    mesh: &SurfaceMesh,
    nb: &Neighbourhoods,
    weights: LaplaceWeights,
) -> Option<Vec<f64>> {
    if weights == LaplaceWeights::Uniform {
        return None;
    }
    let hw = geom::halfedge_weights(mesh, weights);
    let n = nb.off.len() - 1;
    let per_vertex: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let r = nb.off[i] as usize..nb.off[i + 1] as usize;
            let w: Vec<f64> = nb.he[r].iter().map(|&h| hw[h as usize]).collect();
            let s: f64 = w.iter().sum();
            if s > 0.0 && s.is_finite() {
                w.iter().map(|x| x / s).collect()
            } else {
                vec![0.0; w.len()]
            }
        })
        .collect();
    Some(per_vertex.concat())
}

/// One explicit step x' = x + s Δx into `out` (Jacobi, parallel).
fn explicit_step(
    cur: &[Vec3],
    out: &mut [Vec3],
    nb: &Neighbourhoods,
    w: Option<&[f64]>,
    s: f64,
    normals: Option<&[Vec3]>,
) {
    out.par_iter_mut()
        .with_min_len(4096)
        .enumerate()
        .for_each(|(i, o)| {
            let (a, b) = (nb.off[i] as usize, nb.off[i + 1] as usize);
            let x = cur[i];
            if a == b {
                *o = x;
                return;
            }
            let mut d = Vec3::ZERO;
            match w {
                None => {
                    for &j in &nb.nbr[a..b] {
                        d += cur[j as usize];
                    }
                    d = d / (b - a) as f64 - x;
                }
                Some(w) => {
                    for k in a..b {
                        d += w[k] * (cur[nb.nbr[k] as usize] - x);
                    }
                }
            }
            if let Some(n) = normals {
                d -= d.dot(n[i]) * n[i];
            }
            *o = x + s * d;
        });
}

fn check_weights(mesh: &SurfaceMesh, w: LaplaceWeights) -> Result<(), SmoothError> {
    if w == LaplaceWeights::Cotangent {
        mesh.require_triangles()?;
    }
    Ok(())
}

/// Runs explicit steps with the given scale factors in turn.
fn run_explicit(
    mesh: &mut SurfaceMesh,
    weights: LaplaceWeights,
    scales: &[f64],
    iterations: usize,
    c: &Constraints,
) -> Result<SmoothReport, SmoothError> {
    check_weights(mesh, weights)?;
    let roles = roles(mesh, c)?;
    let nb = Neighbourhoods::new(mesh, &roles);
    let normals = c.tangential_only.then(|| geom::vertex_normals(mesh));
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let needs_sync = weights != LaplaceWeights::Uniform || c.preserve_volume;
    // a copy of the mesh is only needed to recompute weights or volumes
    let mut work = needs_sync.then(|| mesh.clone());
    let mut cur = input.clone();
    let mut next = input.clone();
    for _ in 0..iterations {
        for &s in scales {
            let w = match work.as_mut() {
                Some(wm) => {
                    wm.positions_mut().copy_from_slice(&cur);
                    normalised_weights(wm, &nb, weights)
                }
                None => None,
            };
            explicit_step(&cur, &mut next, &nb, w.as_deref(), s, normals.as_deref());
            std::mem::swap(&mut cur, &mut next);
            if let (true, Some(wm)) = (c.preserve_volume, work.as_mut()) {
                wm.positions_mut().copy_from_slice(&cur);
                restore_volume(wm, &roles, v0)?;
                cur.copy_from_slice(wm.positions());
            }
        }
    }
    finish(mesh, cur, &input, v0, iterations)
}

fn finish(
    mesh: &mut SurfaceMesh,
    cur: Vec<Vec3>,
    input: &[Vec3],
    v0: f64,
    iterations: usize,
) -> Result<SmoothReport, SmoothError> {
    if cur.iter().any(|p| !p.is_finite()) {
        return Err(SmoothError::InvalidOption(
            "smoothing diverged (non-finite positions); reduce the scale factors".into(),
        ));
    }
    let max_displacement = max_distance(&cur, input);
    mesh.set_positions(cur)?;
    Ok(SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume(mesh),
        max_displacement,
        converged: true,
        residual: None,
    })
}

/// Laplace smoothing, Grüner thesis Eq. (18): `iterations` steps
/// x'_i = x_i + λ Δx_i with the normalised Laplacian of Eq. (16)–(17).
/// Works on triangle, quad and polygon meshes (the one-ring of the polygon
/// mesh); cotangent weights need triangles ([`crate::MeshError::NotTriangle`]).
pub fn laplace_smooth(
    mesh: &mut SurfaceMesh,
    opts: &LaplaceOptions,
) -> Result<SmoothReport, SmoothError> {
    if !opts.lambda.is_finite() {
        return Err(SmoothError::InvalidOption("λ must be finite".into()));
    }
    run_explicit(
        mesh,
        opts.weights,
        &[opts.lambda],
        opts.iterations,
        &opts.constraints,
    )
}

/// Taubin λ|μ smoothing (Grüner §3.2.3): each iteration is a Laplace step
/// with λ > 0 followed by one with μ < −λ; transfer function
/// f(k) = (1 − λk)(1 − μk) per iteration. Returns the report and the
/// parameters used.
pub fn taubin_smooth(
    mesh: &mut SurfaceMesh,
    opts: &TaubinOptions,
) -> Result<(SmoothReport, TaubinParameters), SmoothError> {
    let p = TaubinParameters::from_options(opts)?;
    let r = run_explicit(
        mesh,
        opts.weights,
        &[p.lambda, p.mu],
        opts.iterations,
        &opts.constraints,
    )?;
    Ok((r, p))
}

/// One backward-Euler system over the `unknown` vertices: rows
/// (m_i + t Σ_j w_ij) x'_i − t Σ_{j unknown} w_ij x'_j = m_i x_i + t Σ_{j known} w_ij x_j.
///
/// The lower-triangular pattern is built once from the one-ring adjacency
/// (column c holds row c, then the unknown neighbours r > c in ascending
/// order); each step only refills the values, in parallel per column block,
/// and refactors with the symbolic analysis (nested-dissection ordering,
/// computed from the positions at the first step) kept.
struct Stage {
    index: Vec<usize>,
    unknowns: Vec<usize>,
    pattern: SymbolicSparseColMat<usize>,
    solver: Option<CholeskySolver>,
}

/// Columns per parallel task when filling matrix values.
const COLUMN_BLOCK: usize = 4096;

impl Stage {
    fn new(
        is_unknown: impl Fn(usize) -> bool,
        n: usize,
        nb: &Neighbourhoods,
    ) -> Result<Self, SmoothError> {
        let mut index = vec![usize::MAX; n];
        let mut unknowns = Vec::new();
        for i in 0..n {
            if is_unknown(i) {
                index[i] = unknowns.len();
                unknowns.push(i);
            }
        }
        let m = unknowns.len();
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::with_capacity(m + nb.nbr.len() / 2);
        col_ptr.push(0usize);
        for (c, &i) in unknowns.iter().enumerate() {
            row_idx.push(c);
            let start = row_idx.len();
            for &j in &nb.nbr[nb.off[i] as usize..nb.off[i + 1] as usize] {
                let r = index[j as usize];
                if r != usize::MAX && r > c {
                    row_idx.push(r);
                }
            }
            row_idx[start..].sort_unstable();
            // a neighbour listed twice gets one entry (values are summed)
            let mut w = start;
            for k in start..row_idx.len() {
                if w == start || row_idx[w - 1] != row_idx[k] {
                    row_idx[w] = row_idx[k];
                    w += 1;
                }
            }
            row_idx.truncate(w);
            col_ptr.push(row_idx.len());
        }
        let pattern = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        Ok(Stage {
            index,
            unknowns,
            pattern,
            solver: None,
        })
    }

    /// Symbolic analysis of the pattern: nested-dissection ordering from the
    /// positions `cur` of the unknowns, then faer's symbolic Cholesky. Needs
    /// no matrix values, so it can run while they are computed.
    fn analyse(&mut self, cur: &[Vec3]) -> Result<(), SmoothError> {
        if self.unknowns.is_empty() {
            return Ok(());
        }
        let points: Vec<Vec3> = self.unknowns.iter().map(|&i| cur[i]).collect();
        let order = nested_dissection(self.pattern.as_ref(), &points)?;
        let opts = CholeskyOptions {
            ordering: CholeskyOrdering::Custom(order),
            // faer's rayon-parallel supernodal kernels made the 450k step
            // slower on 2 cores (1.6 s vs 1.2 s wall, BENCHMARKS.md)
            parallel: false,
        };
        self.solver = Some(CholeskySolver::analyse(self.pattern.as_ref(), &opts)?);
        Ok(())
    }

    /// `weight(i, k)` is w_ij for unknown vertex i and its neighbourhood
    /// entry k (j = `nb.nbr[k]`); `mass[i]` the diagonal.
    fn solve(
        &mut self,
        cur: &mut [Vec3],
        mass: &[f64],
        t: f64,
        nb: &Neighbourhoods,
        weight: &(dyn Fn(usize, usize) -> f64 + Sync),
    ) -> Result<(), SmoothError> {
        let m = self.unknowns.len();
        if m == 0 {
            return Ok(());
        }
        if self.solver.is_none() {
            self.analyse(cur)?;
        }
        let col_ptr = self.pattern.col_ptr();
        let row_idx = self.pattern.row_idx();
        let mut values = vec![0.0; row_idx.len()];
        // split the values into blocks of whole columns
        let mut blocks: Vec<(usize, &mut [f64])> = Vec::with_capacity(m / COLUMN_BLOCK + 1);
        let mut rest = values.as_mut_slice();
        for c0 in (0..m).step_by(COLUMN_BLOCK) {
            let c1 = (c0 + COLUMN_BLOCK).min(m);
            let (head, tail) = rest.split_at_mut(col_ptr[c1] - col_ptr[c0]);
            blocks.push((c0, head));
            rest = tail;
        }
        let (index, unknowns) = (&self.index, &self.unknowns);
        let src: &[Vec3] = cur;
        let rhs_blocks: Vec<Vec<Vec3>> = blocks
            .into_par_iter()
            .map(|(c0, vals)| {
                let c1 = (c0 + COLUMN_BLOCK).min(m);
                let base = col_ptr[c0];
                let mut rhs = Vec::with_capacity(c1 - c0);
                for c in c0..c1 {
                    let i = unknowns[c];
                    let (a, b) = (col_ptr[c] - base, col_ptr[c + 1] - base);
                    let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                    let mut diag = mass[i];
                    let mut bi = mass[i] * src[i];
                    for k in nb.off[i] as usize..nb.off[i + 1] as usize {
                        let j = nb.nbr[k] as usize;
                        let w = weight(i, k);
                        diag += t * w;
                        let r = index[j];
                        if r == usize::MAX {
                            bi += t * w * src[j];
                        } else if r > c {
                            // rows[0] is the diagonal; the rest is sorted
                            if let Ok(p) = rows[1..].binary_search(&r) {
                                vals[a + 1 + p] -= t * w;
                            }
                        }
                    }
                    vals[a] = diag;
                    debug_assert!(b > a);
                    rhs.push(bi);
                }
                rhs
            })
            .collect();
        let mut rhs = rhs_blocks.concat();
        let a = SparseColMatRef::new(self.pattern.as_ref(), &values);
        let solver = self.solver.as_mut().expect("analysed above");
        if let Err(e) = solver.refactor(a) {
            // With large steps and obtuse triangles M − tL can be near
            // indefinite and the pivots depend on the order: retry once with
            // an ordering from the current positions (as a fresh solver would)
            let points: Vec<Vec3> = self.unknowns.iter().map(|&i| src[i]).collect();
            let order = nested_dissection(self.pattern.as_ref(), &points)?;
            let opts = CholeskyOptions {
                ordering: CholeskyOrdering::Custom(order),
                parallel: false,
            };
            match CholeskySolver::with_options(a, &opts) {
                Ok(fresh) => *solver = fresh,
                Err(_) => return Err(e.into()),
            }
        }
        solver.solve_points(&mut rhs)?;
        for (r, &i) in self.unknowns.iter().enumerate() {
            cur[i] = rhs[r];
        }
        Ok(())
    }
}

/// Implicit smoothing (Desbrun et al. 1999): per step solve
/// (M − tL) x' = M x with the cotangent Laplacian L (weights
/// ½(cot α + cot β), recomputed per step) and the mixed Voronoi mass M, by a
/// sparse Cholesky factorisation (nested-dissection ordering) whose symbolic
/// analysis is reused across steps. t = `time_step` · ē² (ē the input mean edge length). Fixed vertices
/// are Dirichlet values; with hierarchical labels the boundary is first
/// smoothed as curves by the 1D analogue (weights ē/l, mass ē(l₋ + l₊)/2).
/// Triangle meshes.
pub fn implicit_smooth(
    mesh: &mut SurfaceMesh,
    opts: &ImplicitOptions,
) -> Result<SmoothReport, SmoothError> {
    mesh.require_triangles()?;
    if !(opts.time_step > 0.0) || !opts.time_step.is_finite() {
        return Err(SmoothError::InvalidOption(
            "time step must be positive".into(),
        ));
    }
    let c = &opts.constraints;
    let roles = roles(mesh, c)?;
    let nb = Neighbourhoods::new(mesh, &roles);
    let normals = c.tangential_only.then(|| geom::vertex_normals(mesh));
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let ebar = geom::mean_edge_length(mesh);
    if !(ebar > 0.0) {
        return finish(mesh, input.clone(), &input, v0, 0);
    }
    let t = opts.time_step * ebar * ebar;
    let n = mesh.vertex_count();
    let mut curve = Stage::new(|i| roles[i] == Role::BoundaryCurve, n, &nb)?;
    let mut inner = Stage::new(|i| roles[i] == Role::Free, n, &nb)?;
    // the mesh itself carries the positions of each step (weights, areas,
    // volume); on failure its input positions are restored
    // the symbolic analysis of the free vertices' system needs only its
    // pattern and the input positions: run it alongside the first step's
    // cotangent weights and mixed areas (the mesh still holds the input)
    let (analysed, wm) = {
        let m: &SurfaceMesh = mesh;
        rayon::join(
            || inner.analyse(&input),
            || {
                rayon::join(
                    || geom::halfedge_weights(m, LaplaceWeights::Cotangent),
                    || geom::mixed_vertex_areas(m),
                )
            },
        )
    };
    analysed?;
    let mut first = Some(wm);
    let mut run = |mesh: &mut SurfaceMesh| -> Result<Vec<Vec3>, SmoothError> {
        let mut cur = input.clone();
        for step in 0..opts.iterations {
            let before = cur.clone();
            if step > 0 {
                mesh.positions_mut().copy_from_slice(&before);
            }
            if !curve.unknowns.is_empty() {
                let p = &before;
                let length = |i: usize, k: usize| p[i].distance(p[nb.nbr[k] as usize]);
                let weight = |i: usize, k: usize| {
                    let l = length(i, k);
                    if l > 0.0 { ebar / l } else { 0.0 }
                };
                let mass: Vec<f64> = (0..n)
                    .into_par_iter()
                    .map(|i| {
                        let s: f64 = (nb.off[i] as usize..nb.off[i + 1] as usize)
                            .map(|k| length(i, k))
                            .sum();
                        0.5 * ebar * s
                    })
                    .collect();
                curve.solve(&mut cur, &mass, t, &nb, &weight)?;
            }
            let (hw, mass) = match first.take() {
                Some(wm) => wm,
                None => rayon::join(
                    || geom::halfedge_weights(mesh, LaplaceWeights::Cotangent),
                    || geom::mixed_vertex_areas(mesh),
                ),
            };
            let weight = |_: usize, k: usize| hw[nb.he[k] as usize];
            inner.solve(&mut cur, &mass, t, &nb, &weight)?;
            if let Some(nrm) = &normals {
                for i in 0..n {
                    let d = cur[i] - before[i];
                    if d != Vec3::ZERO {
                        cur[i] = before[i] + (d - d.dot(nrm[i]) * nrm[i]);
                    }
                }
            }
            if c.preserve_volume {
                mesh.positions_mut().copy_from_slice(&cur);
                restore_volume(mesh, &roles, v0)?;
                cur.copy_from_slice(mesh.positions());
            }
        }
        Ok(cur)
    };
    let cur = match run(mesh) {
        Ok(cur) => cur,
        Err(e) => {
            mesh.positions_mut().copy_from_slice(&input);
            return Err(e);
        }
    };
    finish(mesh, cur, &input, v0, opts.iterations)
}
