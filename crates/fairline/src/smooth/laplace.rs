//! Laplace smoothing (Grüner thesis §3.2.2, Eq. (16)–(18)), Taubin λ|μ
//! smoothing (§3.2.3, Eq. (19)) and implicit backward-Euler smoothing
//! (Desbrun et al. 1999), with the constraints of §3.2.4.
//!
//! Explicit steps are Jacobi updates x'_i = x_i + s Σ_j ω_ij (x_j − x_i) with
//! weights normalised to sum 1 over the neighbourhood (Eq. (17)); they run in
//! parallel over CSR neighbour arrays and are deterministic.

use super::{
    Constraints, Neighbourhoods, Role, SmoothError, SmoothReport, max_distance, restore_volume,
    roles, setters,
};
use crate::geom::{self, LaplaceWeights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{ConstrainedOptions, ConstrainedSolver, sparse_from_triplets};
use crate::{Control, Output, Vec3};
use faer::sparse::{SparseColMat, SymbolicSparseColMatRef};
use rayon::prelude::*;

/// Options of [`laplace_smooth`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct LaplaceOptions {
    /// Edge weights: uniform, edge length to a power (exponent −1 by
    /// default, §3.2.5) or cotangent (Desbrun; triangle meshes only).
    /// Geometry-dependent weights are recomputed before every step.
    pub weights: LaplaceWeights,
    /// Scale factor λ of Eq. (18), 0 < λ < 1.
    pub lambda: f64,
    /// Number of steps.
    pub iterations: usize,
    /// Vertices that never move (empty neighbourhoods, Taubin's
    /// interpolatory constraint, Grüner §3.2.4); bit-identical in the output.
    pub fixed: Vec<VertexId>,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Hierarchical labels: boundary vertices get the higher label, so the
    /// boundary is smoothed as a set of curves (each boundary vertex sees
    /// only its two neighbours along the boundary polyline) and the interior
    /// follows. Ignored when `fix_boundary` is set.
    pub hierarchical_boundary: bool,
    /// Rescale about the centroid after every step so the enclosed volume
    /// equals the input volume (Desbrun et al., β = (V0/Vn)^(1/3)); closed
    /// meshes only. With fixed vertices only the free vertices are scaled
    /// (the scale is then found by a secant iteration). Relative error ≤ 1e-9.
    pub preserve_volume: bool,
    /// Move vertices only within the tangent plane of their input normal
    /// (the normal component of every displacement is removed).
    pub tangential_only: bool,
    /// Progress callback and cancel flag (one step per iteration).
    pub control: Control,
}

impl Default for LaplaceOptions {
    fn default() -> Self {
        LaplaceOptions {
            weights: LaplaceWeights::Uniform,
            lambda: 0.5,
            iterations: 10,
            fixed: Vec::new(),
            fix_boundary: false,
            hierarchical_boundary: false,
            preserve_volume: false,
            tangential_only: false,
            control: Control::default(),
        }
    }
}

setters!(LaplaceOptions {
    weights: LaplaceWeights,
    lambda: f64,
    iterations: usize,
        fixed: Vec<VertexId>,
        fix_boundary: bool,
        hierarchical_boundary: bool,
        preserve_volume: bool,
        tangential_only: bool,
        control: Control,
});

impl LaplaceOptions {
    /// The constraints of §3.2.4 as the methods use them.
    fn constraints(&self) -> Constraints {
        Constraints {
            fixed: self.fixed.clone(),
            fix_boundary: self.fix_boundary,
            hierarchical_boundary: self.hierarchical_boundary,
            preserve_volume: self.preserve_volume,
            tangential_only: self.tangential_only,
        }
    }
}

/// Options of [`taubin_smooth`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
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
    /// Vertices that never move (empty neighbourhoods, Taubin's
    /// interpolatory constraint, Grüner §3.2.4); bit-identical in the output.
    pub fixed: Vec<VertexId>,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Hierarchical labels: boundary vertices get the higher label, so the
    /// boundary is smoothed as a set of curves (each boundary vertex sees
    /// only its two neighbours along the boundary polyline) and the interior
    /// follows. Ignored when `fix_boundary` is set.
    pub hierarchical_boundary: bool,
    /// Rescale about the centroid after every step so the enclosed volume
    /// equals the input volume (Desbrun et al., β = (V0/Vn)^(1/3)); closed
    /// meshes only. With fixed vertices only the free vertices are scaled
    /// (the scale is then found by a secant iteration). Relative error ≤ 1e-9.
    pub preserve_volume: bool,
    /// Move vertices only within the tangent plane of their input normal
    /// (the normal component of every displacement is removed).
    pub tangential_only: bool,
    /// Progress callback and cancel flag (one step per iteration).
    pub control: Control,
}

impl Default for TaubinOptions {
    fn default() -> Self {
        TaubinOptions {
            weights: LaplaceWeights::Uniform,
            lambda: None,
            mu: None,
            pass_band: 0.1,
            iterations: 10,
            fixed: Vec::new(),
            fix_boundary: false,
            hierarchical_boundary: false,
            preserve_volume: false,
            tangential_only: false,
            control: Control::default(),
        }
    }
}

setters!(TaubinOptions {
    weights: LaplaceWeights,
    lambda: Option<f64>,
    mu: Option<f64>,
    pass_band: f64,
    iterations: usize,
        fixed: Vec<VertexId>,
        fix_boundary: bool,
        hierarchical_boundary: bool,
        preserve_volume: bool,
        tangential_only: bool,
        control: Control,
});

impl TaubinOptions {
    /// The constraints of §3.2.4 as the methods use them.
    fn constraints(&self) -> Constraints {
        Constraints {
            fixed: self.fixed.clone(),
            fix_boundary: self.fix_boundary,
            hierarchical_boundary: self.hierarchical_boundary,
            preserve_volume: self.preserve_volume,
            tangential_only: self.tangential_only,
        }
    }
}

/// The scale factors of a Taubin filter and its transfer function
/// f(k) = (1 − λk)(1 − μk) (Grüner §3.2.3). Serialises as `lambda`, `mu`,
/// `pass_band` and `transfer` ([`TaubinParameters::transfer_samples`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaubinParameters {
    /// Positive scale factor.
    pub lambda: f64,
    /// Negative scale factor.
    pub mu: f64,
    /// Pass-band frequency 1/λ + 1/μ (Eq. (19)).
    pub pass_band: f64,
}

impl serde::Serialize for TaubinParameters {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut s = serializer.serialize_struct("TaubinParameters", 4)?;
        s.serialize_field("lambda", &self.lambda)?;
        s.serialize_field("mu", &self.mu)?;
        s.serialize_field("pass_band", &self.pass_band)?;
        s.serialize_field("transfer", &self.transfer_samples())?;
        s.end()
    }
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
#[non_exhaustive]
pub struct ImplicitOptions {
    /// Time step in units of the squared mean edge length of the input, so
    /// the result does not depend on the scale of the mesh (default 1).
    pub time_step: f64,
    /// Number of backward-Euler steps.
    pub iterations: usize,
    /// Vertices that never move (empty neighbourhoods, Taubin's
    /// interpolatory constraint, Grüner §3.2.4); bit-identical in the output.
    pub fixed: Vec<VertexId>,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Hierarchical labels: boundary vertices get the higher label, so the
    /// boundary is smoothed as a set of curves (each boundary vertex sees
    /// only its two neighbours along the boundary polyline) and the interior
    /// follows. Ignored when `fix_boundary` is set.
    pub hierarchical_boundary: bool,
    /// Rescale about the centroid after every step so the enclosed volume
    /// equals the input volume (Desbrun et al., β = (V0/Vn)^(1/3)); closed
    /// meshes only. With fixed vertices only the free vertices are scaled
    /// (the scale is then found by a secant iteration). Relative error ≤ 1e-9.
    pub preserve_volume: bool,
    /// Move vertices only within the tangent plane of their input normal
    /// (the normal component of every displacement is removed).
    pub tangential_only: bool,
    /// Progress callback and cancel flag (one step per iteration).
    pub control: Control,
}

impl Default for ImplicitOptions {
    fn default() -> Self {
        ImplicitOptions {
            time_step: 1.0,
            iterations: 1,
            fixed: Vec::new(),
            fix_boundary: false,
            hierarchical_boundary: false,
            preserve_volume: false,
            tangential_only: false,
            control: Control::default(),
        }
    }
}

setters!(ImplicitOptions {
    time_step: f64,
    iterations: usize,
        fixed: Vec<VertexId>,
        fix_boundary: bool,
        hierarchical_boundary: bool,
        preserve_volume: bool,
        tangential_only: bool,
        control: Control,
});

impl ImplicitOptions {
    /// The constraints of §3.2.4 as the methods use them.
    fn constraints(&self) -> Constraints {
        Constraints {
            fixed: self.fixed.clone(),
            fix_boundary: self.fix_boundary,
            hierarchical_boundary: self.hierarchical_boundary,
            preserve_volume: self.preserve_volume,
            tangential_only: self.tangential_only,
        }
    }
}

/// Normalised weights per neighbourhood entry (Eq. (17)); `None` for uniform.
fn normalised_weights(
    mesh: &SurfaceMesh,
    positions: &[Vec3],
    nb: &Neighbourhoods,
    weights: LaplaceWeights,
) -> Option<Vec<f64>> {
    if weights == LaplaceWeights::Uniform {
        return None;
    }
    let hw = geom::halfedge_weights_at(mesh, positions, weights);
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
    mesh: &SurfaceMesh,
    weights: LaplaceWeights,
    scales: &[f64],
    iterations: usize,
    c: &Constraints,
    control: &Control,
) -> Result<Output<SmoothReport>, SmoothError> {
    check_weights(mesh, weights)?;
    let roles = roles(mesh, c)?;
    let nb = Neighbourhoods::new(mesh, &roles);
    let normals = c.tangential_only.then(|| geom::vertex_normals(mesh));
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let mut cur = input.clone();
    let mut next = input.clone();
    for iteration in 0..iterations {
        control.step("iterations", iteration as u64, iterations as u64)?;
        for &s in scales {
            // geometry-dependent weights at the current positions
            let w = normalised_weights(mesh, &cur, &nb, weights);
            explicit_step(&cur, &mut next, &nb, w.as_deref(), s, normals.as_deref());
            std::mem::swap(&mut cur, &mut next);
            if c.preserve_volume {
                restore_volume(mesh, &mut cur, &roles, v0)?;
            }
        }
    }
    finish(mesh, cur, &input, v0, iterations)
}

/// The output of an explicit or implicit run: the report of the new
/// positions `cur` of `mesh` (an error when they are not finite).
fn finish(
    mesh: &SurfaceMesh,
    cur: Vec<Vec3>,
    input: &[Vec3],
    v0: f64,
    iterations: usize,
) -> Result<Output<SmoothReport>, SmoothError> {
    if cur.iter().any(|p| !p.is_finite()) {
        return Err(SmoothError::InvalidOption(
            "smoothing diverged (non-finite positions); reduce the scale factors".into(),
        ));
    }
    let max_displacement = max_distance(&cur, input);
    let report = SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume_at(mesh, &cur),
        max_displacement,
        converged: true,
        residual: None,
        stop_reason: None,
        taubin: None,
    };
    Ok(Output {
        positions: cur,
        report,
    })
}

/// Laplace smoothing, Grüner thesis Eq. (18): `iterations` steps
/// x'_i = x_i + λ Δx_i with the normalised Laplacian of Eq. (16)–(17).
/// Works on triangle, quad and polygon meshes (the one-ring of the polygon
/// mesh); cotangent weights need triangles ([`crate::MeshError::NotTriangle`]).
pub fn laplace_smooth(
    mesh: &SurfaceMesh,
    opts: &LaplaceOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    if !opts.lambda.is_finite() {
        return Err(SmoothError::InvalidOption("λ must be finite".into()));
    }
    run_explicit(
        mesh,
        opts.weights,
        &[opts.lambda],
        opts.iterations,
        &opts.constraints(),
        &opts.control,
    )
}

/// Taubin λ|μ smoothing (Grüner §3.2.3): each iteration is a Laplace step
/// with λ > 0 followed by one with μ < −λ; transfer function
/// f(k) = (1 − λk)(1 − μk) per iteration. The parameters used are in the
/// report's `taubin` field.
pub fn taubin_smooth(
    mesh: &SurfaceMesh,
    opts: &TaubinOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    let p = TaubinParameters::from_options(opts)?;
    let mut out = run_explicit(
        mesh,
        opts.weights,
        &[p.lambda, p.mu],
        opts.iterations,
        &opts.constraints(),
        &opts.control,
    )?;
    out.report.taubin = Some(p);
    Ok(out)
}

/// Entry k (in column j) of the backward-Euler matrix M − tL of Desbrun
/// et al. on the pattern of `lap` ([`geom::LaplacianPattern`]): −t L_ij off
/// the diagonal, m_j − t L_jj = m_j + t Σ w on it (as (L_jj · −t) + m_j, the
/// order of operations of the former assembled matrix, so results are
/// bit-identical to it).
#[inline]
fn backward_euler_entry(
    mesh: &SurfaceMesh,
    lap: &geom::LaplacianPattern,
    w: &[f64],
    mass: &[f64],
    t: f64,
    j: usize,
    k: usize,
) -> f64 {
    let l = lap.entry(mesh, w, j, k) * -t;
    if lap.source[k] == geom::LaplacianPattern::DIAGONAL {
        l + mass[j]
    } else {
        l
    }
}

/// The 1D backward-Euler system of the boundary curves (hierarchical
/// labels): for every vertex with role `BoundaryCurve`, weights ē/l to its
/// boundary neighbours and mass ē(l₋ + l₊)/2, at the positions `p`; the
/// other columns hold their diagonal only (those vertices are fixed in this
/// solve).
fn curve_matrix(
    p: &[Vec3],
    roles: &[Role],
    nb: &Neighbourhoods,
    ebar: f64,
    t: f64,
) -> Result<(SparseColMat<usize, f64>, Vec<f64>), SmoothError> {
    let n = p.len();
    let mut triplets = Vec::new();
    let mut mass = vec![0.0; n];
    for i in 0..n {
        if roles[i] != Role::BoundaryCurve {
            triplets.push((i, i, 1.0));
            continue;
        }
        let mut diag = 0.0;
        let mut length = 0.0;
        for k in nb.off[i] as usize..nb.off[i + 1] as usize {
            let j = nb.nbr[k] as usize;
            let l = p[i].distance(p[j]);
            length += l;
            let w = if l > 0.0 { ebar / l } else { 0.0 };
            diag += t * w;
            triplets.push((j, i, -t * w));
        }
        mass[i] = 0.5 * ebar * length;
        triplets.push((i, i, mass[i] + diag));
    }
    Ok((sparse_from_triplets(n, n, &triplets)?, mass))
}

/// Solves one backward-Euler system A x' = M x for the free vertices of
/// `solver` (the others keep their positions in `cur`), A given entry by
/// entry (`value(j, k)`, entry k of the pattern `pattern`, in column j; one
/// pass assembles and eliminates, [`ConstrainedSolver::factor_with`]).
/// Re-analyses once with an ordering from the current positions when the
/// factorisation fails (with large steps and obtuse triangles M − tL can be
/// near indefinite and the pivots depend on the order, as for a fresh
/// solver).
fn backward_euler_step(
    solver: &mut ConstrainedSolver,
    pattern: SymbolicSparseColMatRef<'_, usize>,
    value: impl Fn(usize, usize) -> f64 + Sync,
    mass: &[f64],
    fixed: &[bool],
    cur: &mut [Vec3],
) -> Result<(), SmoothError> {
    if let Err(e) = solver.factor_with(&value) {
        let opts = ConstrainedOptions {
            points: Some(cur.to_vec()),
            parallel: false,
        };
        let mut fresh = ConstrainedSolver::analyse(pattern, fixed, &opts)?;
        if fresh.factor_with(&value).is_err() {
            return Err(e.into());
        }
        *solver = fresh;
    }
    let rhs: Vec<Vec3> = mass
        .par_iter()
        .zip(cur.par_iter())
        .map(|(m, p)| *m * *p)
        .collect();
    solver.solve_points(&rhs, cur)?;
    Ok(())
}

/// Implicit smoothing (Desbrun et al. 1999): per step solve
/// (M − tL) x' = M x with the cotangent Laplacian L of
/// [`geom::laplacian_from_weights`] (weights ½(cot α + cot β), recomputed per
/// step at the current positions, [`geom::halfedge_weights_at`]) and the
/// mixed Voronoi mass M ([`geom::mixed_vertex_areas_at`]), by the one
/// constrained solve of [`crate::solve::ConstrainedSolver`]: fixed vertices
/// are Dirichlet values moved to the right-hand side, the free block is
/// ordered by nested dissection and its symbolic analysis is reused across
/// steps. t = `time_step` · ē² (ē the input mean edge length). With
/// hierarchical labels the boundary is first smoothed as curves by the 1D
/// analogue (weights ē/l, mass ē(l₋ + l₊)/2). Triangle meshes.
pub fn implicit_smooth(
    mesh: &SurfaceMesh,
    opts: &ImplicitOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    mesh.require_triangles()?;
    if !(opts.time_step > 0.0) || !opts.time_step.is_finite() {
        return Err(SmoothError::InvalidOption(
            "time step must be positive".into(),
        ));
    }
    let c = &opts.constraints();
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
    let inner_fixed: Vec<bool> = roles.iter().map(|r| *r != Role::Free).collect();
    let curve_fixed: Vec<bool> = roles.iter().map(|r| *r != Role::BoundaryCurve).collect();
    let has_curve = curve_fixed.iter().any(|f| !f);
    // the symbolic analysis of the free vertices' system needs only the
    // Laplacian's pattern and the input positions: run it alongside the
    // first step's cotangent weights and mixed areas
    let (analysed, first) = rayon::join(
        || {
            let lap = geom::LaplacianPattern::new(mesh);
            let opts = ConstrainedOptions {
                points: Some(input.clone()),
                // faer's rayon-parallel supernodal kernels made the 450k
                // step slower on 2 cores (1.6 s vs 1.2 s wall, measured)
                parallel: false,
            };
            ConstrainedSolver::analyse(lap.symbolic.as_ref(), &inner_fixed, &opts)
                .map(|solver| (solver, lap))
        },
        || {
            rayon::join(
                || geom::halfedge_weights(mesh, LaplaceWeights::Cotangent),
                || geom::mixed_vertex_areas(mesh),
            )
        },
    );
    let (mut inner, lap) = analysed?;
    let mut first = Some(first);
    let mut curve: Option<ConstrainedSolver> = None;
    let mut cur = input.clone();
    for step in 0..opts.iterations {
        opts.control
            .step("iterations", step as u64, opts.iterations as u64)?;
        let before = cur.clone();
        if has_curve {
            let (a, mass) = curve_matrix(&before, &roles, &nb, ebar, t)?;
            let solver = match curve.as_mut() {
                Some(s) => s,
                None => curve.insert(ConstrainedSolver::analyse(
                    a.symbolic(),
                    &curve_fixed,
                    &ConstrainedOptions {
                        points: Some(before.clone()),
                        parallel: false,
                    },
                )?),
            };
            let values = a.val();
            backward_euler_step(
                solver,
                a.symbolic(),
                |_, k| values[k],
                &mass,
                &curve_fixed,
                &mut cur,
            )?;
        }
        let (hw, mass) = match first.take() {
            Some(wm) => wm,
            None => rayon::join(
                || geom::halfedge_weights_at(mesh, &before, LaplaceWeights::Cotangent),
                || geom::mixed_vertex_areas_at(mesh, &before),
            ),
        };
        backward_euler_step(
            &mut inner,
            lap.symbolic.as_ref(),
            |j, k| backward_euler_entry(mesh, &lap, &hw, &mass, t, j, k),
            &mass,
            &inner_fixed,
            &mut cur,
        )?;
        if let Some(nrm) = &normals {
            for i in 0..n {
                let d = cur[i] - before[i];
                if d != Vec3::ZERO {
                    cur[i] = before[i] + (d - d.dot(nrm[i]) * nrm[i]);
                }
            }
        }
        if c.preserve_volume {
            restore_volume(mesh, &mut cur, &roles, v0)?;
        }
    }
    finish(mesh, cur, &input, v0, opts.iterations)
}
