//! Regularised circular-highlight fairing (beyond Nishiyama et al.;
//! DESIGN.md §3).
//!
//! The paper solves J Δr = −F for the selected targets only, with a
//! truncated SVD. With few targets the system is underdetermined (more
//! control components than samples) and every direction the targets do not
//! see is left to the truncation: the other highlight lines over the moved
//! control points drift and get wavier. Here the unknown displacement x of
//! the free control points minimises
//!
//! Φ(x) = (1/N_t) Σ_t d_s(u_t, v_t)²
//!      + (κ/N_k) Σ_k (d_s(u_k, v_k) − d_s⁰(u_k, v_k))²
//!      + λ Σ_stencils |Δ² x|²
//!
//! - t: the samples of the Hermite targets (the paper's Eq. (3.4));
//! - k: weak targets, samples of the current pre-images of *every* light
//!   (all radii) inside the support of the free control points, except the
//!   stretches being replaced; d_s⁰ is their value on the input surface, so
//!   the lines are held where they are (κ = `keep_weight`);
//! - Δ² x: the second differences of the displacement over the control net
//!   in u, in v and mixed (×√2), a discrete thin-plate energy; fixed control
//!   points have zero displacement. λ = φ · (mean diagonal of the target
//!   term's Gauss–Newton matrix) / (mean diagonal of the stencil matrix),
//!   φ = `fairness_weight`, fixed at the first iteration. This term alone
//!   makes the normal matrix positive definite (every free point is in a
//!   stencil with a fixed neighbour), so the problem is well posed however
//!   few the targets.
//!
//! Minimised by Levenberg–Marquardt: (A + μ diag A) δ = −g with the
//! Gauss–Newton A = Jᵀ W J + λ DᵀD (the Jacobian of Eq. (3.10), rows of both
//! target kinds) and g the gradient; a step is taken only if Φ decreases
//! (μ / 5 then), otherwise μ × 8 and retried up to 12 times. It stops when
//! the relative decrease of Φ of an accepted step is below ε (the analogue
//! of Eq. (3.14)) — that alone is `converged` — or when Φ vanishes.

use super::jacobian::jacobian_rows;
use super::paper::{apply, mean_square};
use super::targets::dist2;
use super::*;
use crate::highlight::surface::{contour_field, distance_field};
use faer::Side;
use faer::linalg::solvers::Solve;

/// The fixed data of one regularised fairing.
pub(super) struct Problem<'a> {
    pub surface: &'a BSplineSurface,
    pub lights: &'a [CircularLight],
    pub targets: &'a [TargetCurve],
    /// Target samples with their basis coefficients.
    pub samples: &'a [Sample],
    /// The free control points (unknowns, row-major).
    pub selected: &'a [(usize, usize)],
    /// Flat control point index → position in `selected`.
    pub column: &'a [Option<usize>],
    /// Finite-difference step (surface units).
    pub dw: f64,
    /// A residual below this is zero (surface units).
    pub tiny: f64,
}

/// Distance from `p` to the polyline `line` (open).
fn distance_to_polyline(p: [f64; 2], line: &[[f64; 2]]) -> f64 {
    match line.len() {
        0 => f64::INFINITY,
        1 => dist2(p, line[0]).sqrt(),
        _ => line
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let ab = [b[0] - a[0], b[1] - a[1]];
                let l2 = ab[0] * ab[0] + ab[1] * ab[1];
                let t = if l2 > 0.0 {
                    (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                dist2(p, [a[0] + t * ab[0], a[1] + t * ab[1]])
            })
            .fold(f64::INFINITY, f64::min)
            .sqrt(),
    }
}

/// The parameter box where a free control point's basis function is
/// non-zero: the union of their supports' bounding box.
fn influence_box(p: &Problem) -> [f64; 4] {
    let s = p.surface;
    let (pu, pv) = (s.degree_u(), s.degree_v());
    let imin = p.selected.iter().map(|x| x.0).min().unwrap_or(0);
    let imax = p.selected.iter().map(|x| x.0).max().unwrap_or(0);
    let jmin = p.selected.iter().map(|x| x.1).min().unwrap_or(0);
    let jmax = p.selected.iter().map(|x| x.1).max().unwrap_or(0);
    let (ku, kv) = (s.knots_u(), s.knots_v());
    [
        ku[imin],
        ku[(imax + pu + 1).min(ku.len() - 1)],
        kv[jmin],
        kv[(jmax + pv + 1).min(kv.len() - 1)],
    ]
}

/// Weak-target samples: every light's pre-image on the input surface,
/// resampled at twice the target spacing, inside the influence box, away
/// from (more than 1.5 grid cells) the stretches of the same light that the
/// targets replace, where some free basis function is non-zero and d_s is
/// defined. Returns the samples and their d_s⁰.
fn keep_samples(p: &Problem, opts: &SurfaceFairOptions) -> (Vec<Sample>, Vec<f64>) {
    let s = p.surface;
    let (du, dv) = (s.domain_u(), s.domain_v());
    let diag = (du[1] - du[0]).hypot(dv[1] - dv[0]);
    let spacing = 2.0 * opts.sample_spacing * diag;
    let cell = (du[1] - du[0]).max(dv[1] - dv[0]) / (opts.grid - 1) as f64;
    let b = influence_box(p);
    let hopts = SurfaceHighlightOptions::default().grid(opts.grid);
    let per_light: Vec<Vec<Sample>> = p
        .lights
        .par_iter()
        .enumerate()
        .map(|(l, light)| {
            let sl = SurfaceLight::Circular(*light);
            let field = distance_field(s, &sl, opts.grid, opts.grid);
            let stretches: Vec<&[[f64; 2]]> = p
                .targets
                .iter()
                .filter(|t| t.light == l)
                .map(|t| &t.stretch[..])
                .collect();
            let mut out = Vec::new();
            for line in contour_field(s, &sl, l, &field, 0.0, &hopts) {
                for uv in resample_polyline(&line.uv, line.closed, spacing) {
                    let inside = uv[0] > b[0] && uv[0] < b[1] && uv[1] > b[2] && uv[1] < b[3];
                    if !inside
                        || stretches
                            .iter()
                            .any(|st| distance_to_polyline(uv, st) < 1.5 * cell)
                    {
                        continue;
                    }
                    let coeffs = sample_coeffs(s, p.column, uv[0], uv[1]);
                    if !coeffs.is_empty() {
                        out.push(Sample {
                            uv,
                            light: l,
                            coeffs,
                        });
                    }
                }
            }
            out
        })
        .collect();
    let all: Vec<Sample> = per_light.into_iter().flatten().collect();
    let f0 = residuals(s, p.lights, &all);
    all.into_iter()
        .zip(f0)
        .filter_map(|(smp, f)| f.map(|f| (smp, f)))
        .unzip()
}

/// The second-difference stencils of the control net restricted to the
/// free points (fixed points contribute zero displacement): (position in
/// `selected`, coefficient) lists, one per stencil that touches a free
/// point.
fn stencils(p: &Problem) -> Vec<Vec<(usize, f64)>> {
    let s = p.surface;
    let (nu, nv) = (s.count_u(), s.count_v());
    let col = |i: usize, j: usize| p.column[s.index(i, j)];
    let mut out = Vec::new();
    let mut push = |terms: &[(usize, usize, f64)]| {
        let st: Vec<(usize, f64)> = terms
            .iter()
            .filter_map(|&(i, j, c)| col(i, j).map(|k| (k, c)))
            .collect();
        if !st.is_empty() {
            out.push(st);
        }
    };
    let r2 = std::f64::consts::SQRT_2;
    for i in 0..nu {
        for j in 0..nv {
            if i >= 1 && i + 1 < nu {
                push(&[(i - 1, j, 1.0), (i, j, -2.0), (i + 1, j, 1.0)]);
            }
            if j >= 1 && j + 1 < nv {
                push(&[(i, j - 1, 1.0), (i, j, -2.0), (i, j + 1, 1.0)]);
            }
            if i + 1 < nu && j + 1 < nv {
                push(&[
                    (i, j, r2),
                    (i + 1, j, -r2),
                    (i, j + 1, -r2),
                    (i + 1, j + 1, r2),
                ]);
            }
        }
    }
    out
}

/// Φ's parts at a surface: (target mean square, keep mean square ×κ,
/// fairness λ|Δ²x|²) and the target residuals; `None` if some d_s is
/// undefined.
struct Evaluation {
    ft: Vec<Option<f64>>,
    fk: Vec<f64>,
    phi: f64,
}

fn evaluate(
    p: &Problem,
    trial: &BSplineSurface,
    keep: &[Sample],
    keep_f0: &[f64],
    fairness: &dyn Fn(&BSplineSurface) -> f64,
    kappa: f64,
) -> Option<Evaluation> {
    let ft = residuals(trial, p.lights, p.samples);
    let target = mean_square(&ft);
    if !target.is_finite() {
        return None;
    }
    let fk_opt = residuals(trial, p.lights, keep);
    let mut fk = Vec::with_capacity(keep.len());
    for (f, f0) in fk_opt.iter().zip(keep_f0) {
        fk.push((*f)? - f0);
    }
    let keep_term = if fk.is_empty() {
        0.0
    } else {
        kappa * fk.iter().map(|x| x * x).sum::<f64>() / fk.len() as f64
    };
    let phi = target + keep_term + fairness(trial);
    phi.is_finite().then_some(Evaluation { ft, fk, phi })
}

/// Adds w Σ rowᵀ row to `a` and w Σ row r to `g`.
fn accumulate(
    a: &mut Mat<f64>,
    g: &mut [f64],
    rows: &[Vec<(usize, f64)>],
    r: &dyn Fn(usize) -> f64,
    w: f64,
) {
    for (k, row) in rows.iter().enumerate() {
        let rk = r(k);
        for &(c1, v1) in row {
            g[c1] += w * v1 * rk;
            for &(c2, v2) in row {
                a[(c1, c2)] += w * v1 * v2;
            }
        }
    }
}

/// Checks the weights of the regularised method.
fn check_weights(opts: &SurfaceFairOptions) -> Result<(), SurfaceFairError> {
    if !(opts.keep_weight >= 0.0 && opts.keep_weight.is_finite()) {
        return Err(SurfaceFairError::Invalid(
            "keep weight must be finite and not negative".into(),
        ));
    }
    if !(opts.fairness_weight > 0.0 && opts.fairness_weight.is_finite()) {
        return Err(SurfaceFairError::Invalid(
            "fairness weight must be positive and finite".into(),
        ));
    }
    Ok(())
}

/// The thin-plate term Σ_stencils |Δ² x|² of the free control points'
/// displacement x from the input.
struct ThinPlate<'a> {
    selected: &'a [(usize, usize)],
    stencil: Vec<Vec<(usize, f64)>>,
    /// M = DᵀD over the free points (the same for each component), n × n
    /// row-major.
    m: Vec<f64>,
    trace_m: f64,
    /// The free control points of the input.
    origin: Vec<Vec3>,
}

impl<'a> ThinPlate<'a> {
    fn new(p: &Problem<'a>) -> ThinPlate<'a> {
        let n = p.selected.len();
        let stencil = stencils(p);
        let mut m = vec![0.0; n * n];
        for st in &stencil {
            for &(a, ca) in st {
                for &(b, cb) in st {
                    m[a * n + b] += ca * cb;
                }
            }
        }
        let trace_m: f64 = (0..n).map(|a| m[a * n + a]).sum();
        let origin: Vec<Vec3> = p
            .selected
            .iter()
            .map(|&(i, j)| p.surface.control_point(i, j))
            .collect();
        ThinPlate {
            selected: p.selected,
            stencil,
            m,
            trace_m,
            origin,
        }
    }

    fn displacement(&self, s: &BSplineSurface) -> Vec<Vec3> {
        self.selected
            .iter()
            .zip(&self.origin)
            .map(|(&(i, j), o)| s.control_point(i, j) - *o)
            .collect()
    }

    fn energy(&self, x: &[Vec3]) -> f64 {
        self.stencil
            .iter()
            .map(|st| {
                let mut d = Vec3::ZERO;
                for &(k, c) in st {
                    d += c * x[k];
                }
                d.length_squared()
            })
            .sum()
    }

    /// λ Σ |Δ² x|² of a surface (0 for λ = 0).
    fn weighted(&self, lambda: f64) -> impl Fn(&BSplineSurface) -> f64 + '_ {
        move |s: &BSplineSurface| -> f64 {
            if lambda == 0.0 {
                0.0
            } else {
                lambda * self.energy(&self.displacement(s))
            }
        }
    }
}

/// The Gauss–Newton system of one iteration.
struct GaussNewton {
    a: Mat<f64>,
    g: Vec<f64>,
    /// Largest diagonal entry of A.
    max_diag: f64,
    /// The fairness weight λ.
    lambda: f64,
}

/// One regularised fairing: the problem, its weak targets and thin-plate
/// term, and the weights of Φ's parts.
struct Regularised<'a> {
    p: &'a Problem<'a>,
    opts: &'a SurfaceFairOptions,
    keep: Vec<Sample>,
    keep_f0: Vec<f64>,
    thin_plate: ThinPlate<'a>,
    /// Weight of a target sample, 1/N_t.
    wt: f64,
    /// Weight of a weak-target sample, κ/N_k.
    wk: f64,
}

impl<'a> Regularised<'a> {
    fn new(p: &'a Problem<'a>, opts: &'a SurfaceFairOptions) -> Regularised<'a> {
        let (keep, keep_f0) = keep_samples(p, opts);
        let thin_plate = ThinPlate::new(p);
        let (nt, nk) = (p.samples.len() as f64, keep.len().max(1) as f64);
        Regularised {
            p,
            opts,
            keep,
            keep_f0,
            thin_plate,
            wt: 1.0 / nt,
            wk: opts.keep_weight / nk,
        }
    }

    /// Φ of `surface` with fairness weight λ.
    fn evaluate(&self, surface: &BSplineSurface, lambda: f64) -> Option<Evaluation> {
        evaluate(
            self.p,
            surface,
            &self.keep,
            &self.keep_f0,
            &self.thin_plate.weighted(lambda),
            self.opts.keep_weight,
        )
    }

    /// The Gauss–Newton matrix A = Jᵀ W J + λ DᵀD and gradient g of Φ at
    /// `current` (halved: Φ = Σ w r²). `lambda` `None` (first iteration)
    /// fixes λ = φ · (mean diagonal of the target term) / (mean diagonal of
    /// the stencil matrix).
    fn gauss_newton(
        &self,
        current: &BSplineSurface,
        eval: &Evaluation,
        lambda: Option<f64>,
    ) -> GaussNewton {
        let (p, tp) = (self.p, &self.thin_plate);
        let n = p.selected.len();
        let cols = 3 * n;
        let ft: Vec<Option<f64>> = eval.ft.clone();
        // The finite differences start from d_s itself, not from the
        // residual d_s − d_s⁰.
        let dk: Vec<Option<f64>> = eval
            .fk
            .iter()
            .zip(&self.keep_f0)
            .map(|(&x, f0)| Some(x + f0))
            .collect();
        let jt = jacobian_rows(current, p.lights, p.samples, &ft, p.dw);
        let jk = jacobian_rows(current, p.lights, &self.keep, &dk, p.dw);
        let mut a = Mat::<f64>::zeros(cols, cols);
        let mut g = vec![0.0; cols];
        accumulate(&mut a, &mut g, &jt, &|k| ft[k].unwrap_or(0.0), self.wt);
        let lambda = lambda.unwrap_or_else(|| {
            let trace_t: f64 = (0..cols).map(|c| a[(c, c)]).sum();
            if tp.trace_m > 0.0 && trace_t > 0.0 {
                self.opts.fairness_weight * (trace_t / cols as f64) / (tp.trace_m / n as f64)
            } else {
                self.opts.fairness_weight
            }
        });
        accumulate(&mut a, &mut g, &jk, &|k| eval.fk[k], self.wk);
        let x = tp.displacement(current);
        for r in 0..n {
            for c in 0..n {
                let mv = lambda * tp.m[r * n + c];
                if mv == 0.0 {
                    continue;
                }
                for ax in 0..3 {
                    a[(3 * r + ax, 3 * c + ax)] += mv;
                    g[3 * r + ax] += mv * x[c][ax];
                }
            }
        }
        let max_diag = (0..cols).map(|c| a[(c, c)]).fold(0.0f64, f64::max);
        GaussNewton {
            a,
            g,
            max_diag,
            lambda,
        }
    }

    /// Levenberg–Marquardt: (A + μ diag A) δ = −g, taken only if Φ falls
    /// below `phi` (μ × 8 and retried up to 12 times otherwise). Returns the
    /// new surface and its evaluation, `None` when no try lowered Φ.
    fn damped_step(
        &self,
        current: &BSplineSurface,
        normal: &GaussNewton,
        phi: f64,
        mu: &mut f64,
    ) -> Result<Option<(BSplineSurface, Evaluation)>, SurfaceFairError> {
        let p = self.p;
        let (a, g, max_diag, lambda) = (&normal.a, &normal.g, normal.max_diag, normal.lambda);
        let cols = g.len();
        let base: Vec<Vec3> = p
            .selected
            .iter()
            .map(|&(i, j)| current.control_point(i, j))
            .collect();
        for _ in 0..12 {
            let mut damped = a.clone();
            for c in 0..cols {
                damped[(c, c)] += *mu * (a[(c, c)] + 1e-12 * max_diag);
            }
            let Ok(llt) = damped.llt(Side::Lower) else {
                *mu *= 8.0;
                continue;
            };
            let rhs = Mat::<f64>::from_fn(cols, 1, |r, _| -g[r]);
            let sol = llt.solve(&rhs);
            let dr: Vec<f64> = (0..cols).map(|r| sol[(r, 0)]).collect();
            if !dr.iter().all(|v| v.is_finite()) {
                *mu *= 8.0;
                continue;
            }
            let mut trial = current.clone();
            apply(&mut trial, &base, p.selected, &dr, 1.0)?;
            match self.evaluate(&trial, lambda) {
                Some(e) if e.phi < phi => return Ok(Some((trial, e))),
                _ => *mu *= 8.0,
            }
        }
        Ok(None)
    }
}

/// See the module documentation.
pub(super) fn solve(p: &Problem, opts: &SurfaceFairOptions) -> Result<Solved, SurfaceFairError> {
    check_weights(opts)?;
    let cols = 3 * p.selected.len();
    let problem = Regularised::new(p, opts);
    let mut lambda = None;
    let mut current = p.surface.clone();
    let mut eval = problem
        .evaluate(&current, 0.0)
        .ok_or(SurfaceFairError::NoSamples)?;
    let mut iterations = Vec::new();
    let mut mu = 1e-3;
    let mut converged = eval.phi <= p.tiny * p.tiny;
    let mut stop = if converged {
        FairStop::ZeroResidual
    } else {
        FairStop::MaxIterations
    };
    while !converged && iterations.len() < opts.max_iterations {
        opts.control.step(
            "iterations",
            iterations.len() as u64,
            opts.max_iterations as u64,
        )?;
        let t0 = Instant::now();
        let normal = problem.gauss_newton(&current, &eval, lambda);
        let max_diag = normal.max_diag;
        if !(max_diag > 0.0 && max_diag.is_finite()) {
            stop = FairStop::NonFiniteStep;
            break;
        }
        if lambda.is_none() {
            // Φ with this λ (λ was 0 before the first iteration)
            eval.phi += problem.thin_plate.weighted(normal.lambda)(&current);
        }
        lambda = Some(normal.lambda);
        let Some((trial, e)) = problem.damped_step(&current, &normal, eval.phi, &mut mu)? else {
            stop = FairStop::Stalled;
            break;
        };
        let rel = (eval.phi - e.phi) / eval.phi;
        current = trial;
        eval = e;
        let st = stats(&eval.ft);
        iterations.push(FairIteration {
            max_abs: st.0,
            mean_abs: st.1,
            step: 1.0,
            rows: p.samples.len() + problem.keep.len() + problem.thin_plate.stencil.len(),
            cols,
            rank: cols,
            truncation: 0.0,
            objective: eval.phi,
            damping: mu,
            time_s: t0.elapsed().as_secs_f64(),
        });
        mu = (mu / 5.0).max(1e-12);
        if eval.phi <= p.tiny * p.tiny {
            converged = true;
            stop = FairStop::ZeroResidual;
        } else if rel < opts.epsilon {
            converged = true;
            stop = FairStop::Epsilon;
        }
    }
    Ok(Solved {
        after: stats(&eval.ft),
        surface: current,
        iterations,
        converged,
        stop,
        keep_samples: problem.keep.len(),
    })
}
