//! The paper's solver (Nishiyama et al. §3.3): Gauss–Newton on the
//! signed distances with a truncated SVD, lowered truncation levels and
//! damped steps.

use super::jacobian::{Sample, control_directions, jacobian_along, residuals, stats};
use super::{FairIteration, FairStop, PaperDamping, Solved, SurfaceFairError, SurfaceFairOptions};
use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::highlight::CircularLight;
use faer::Mat;
use std::time::Instant;

/// Σ (F + J Δr)²: the sum of squares the linearisation of Eq. (3.8)
/// predicts after the step Δr.
pub(super) fn predicted_sum_of_squares(j: &Mat<f64>, f: &[f64], dr: &[f64]) -> f64 {
    (0..j.nrows())
        .map(|r| {
            let lin: f64 = (0..j.ncols()).map(|c| j[(r, c)] * dr[c]).sum();
            (f[r] + lin).powi(2)
        })
        .sum()
}

/// The thin SVD J = U S Vᵀ of the Jacobian, computed once per iteration
/// and reused for every truncation level tried.
pub(super) struct JacobianSvd {
    u: Mat<f64>,
    s: Vec<f64>,
    v: Mat<f64>,
}

pub(super) fn jacobian_svd(j: &Mat<f64>) -> Result<JacobianSvd, SurfaceFairError> {
    let svd = j.thin_svd().map_err(|_| SurfaceFairError::Svd)?;
    let sv = svd.S().column_vector();
    Ok(JacobianSvd {
        u: svd.U().to_owned(),
        s: (0..sv.nrows()).map(|i| sv[i]).collect(),
        v: svd.V().to_owned(),
    })
}

/// Least-squares solution of J Δr = −F by the truncated SVD (Nishiyama et
/// al. §3.3): singular values below `truncation` × the largest are set to
/// zero. Returns (Δr, rank).
pub(super) fn truncated_svd_solve(
    svd: &JacobianSvd,
    f: &[f64],
    truncation: f64,
) -> (Vec<f64>, usize) {
    let (u, v) = (&svd.u, &svd.v);
    let smax = svd.s.iter().copied().fold(0.0f64, f64::max);
    let mut dr = vec![0.0; v.nrows()];
    if !(smax > 0.0 && smax.is_finite()) {
        return (dr, 0);
    }
    let mut rank = 0;
    for (i, &si) in svd.s.iter().enumerate() {
        if !(si >= truncation * smax && si > 0.0) {
            continue;
        }
        rank += 1;
        let mut utf = 0.0;
        for r in 0..u.nrows() {
            utf += u[(r, i)] * f[r];
        }
        let c = -utf / si;
        for (col, x) in dr.iter_mut().enumerate() {
            *x += c * v[(col, i)];
        }
    }
    (dr, rank)
}

/// Moves selected control point k by `mu · dr[k]` along `dirs[k]`.
pub(super) fn apply_along(
    surface: &mut BSplineSurface,
    base: &[Vec3],
    selected: &[(usize, usize)],
    dirs: &[Vec3],
    dr: &[f64],
    mu: f64,
) -> Result<(), SurfaceFairError> {
    for (k, &(i, j)) in selected.iter().enumerate() {
        surface.set_control_point(i, j, base[k] + (mu * dr[k]) * dirs[k])?;
    }
    Ok(())
}

/// Moves the selected control points by `mu · dr`.
pub(super) fn apply(
    surface: &mut BSplineSurface,
    base: &[Vec3],
    selected: &[(usize, usize)],
    dr: &[f64],
    mu: f64,
) -> Result<(), SurfaceFairError> {
    for (k, &(i, j)) in selected.iter().enumerate() {
        let d = Vec3::new(dr[3 * k], dr[3 * k + 1], dr[3 * k + 2]);
        surface.set_control_point(i, j, base[k] + mu * d)?;
    }
    Ok(())
}

/// The paper's solver (Nishiyama et al. §3.3), see [`fair_surface`](super::fair_surface).
pub(super) fn solve_paper(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    samples: &[Sample],
    selected: &[(usize, usize)],
    opts: &SurfaceFairOptions,
    dw: f64,
    tiny: f64,
) -> Result<Solved, SurfaceFairError> {
    let dirs = control_directions(surface, selected, samples);
    let cols = dirs.len();
    let mut current = surface.clone();
    let mut f = residuals(&current, lights, samples);
    let mut now = stats(&f);
    let mut iterations = Vec::new();
    let mut converged = now.1 <= tiny;
    let mut stop = if converged {
        FairStop::ZeroResidual
    } else {
        FairStop::MaxIterations
    };
    let levels = truncation_levels(opts.truncation, opts.min_truncation);
    let mut trunc = opts.truncation;
    while !converged && iterations.len() < opts.max_iterations && cols > 0 {
        opts.control.step(
            "iterations",
            iterations.len() as u64,
            opts.max_iterations as u64,
        )?;
        let t0 = Instant::now();
        let base: Vec<Vec3> = selected
            .iter()
            .map(|&(i, j)| current.control_point(i, j))
            .collect();
        let j = jacobian_along(&current, lights, samples, &f, &dirs, dw);
        let fv: Vec<f64> = f.iter().map(|x| x.unwrap_or(0.0)).collect();
        let ss_now: f64 = fv.iter().map(|x| x * x).sum();
        let svd = jacobian_svd(&j)?;
        // Eq. (3.14) on the linear model: when even the finest truncation
        // would change the sum of squares by less than ε (relative), the
        // least-squares problem is solved and another step only shuffles
        // the residual.
        let (finest, _) = truncated_svd_solve(&svd, &fv, opts.min_truncation.min(trunc));
        if !finest.iter().all(|x| x.is_finite()) {
            stop = FairStop::NonFiniteStep;
            break;
        }
        if ss_now - predicted_sum_of_squares(&j, &fv, &finest) <= opts.epsilon * ss_now {
            converged = true;
            stop = FairStop::Epsilon;
            break;
        }
        // The full step of Eq. (3.11) at the current truncation; when it is
        // not accepted or gains less than a halving of mean |d_s|, the
        // truncation is lowered tenfold (same SVD, same iteration) down to
        // the floor. The best accepted full step is taken (the coarser
        // levels, tried in earlier iterations, compete as well); when no
        // full step is accepted, the damped step of Eq. (3.13) at the
        // finest level, then at the coarser ones.
        let try_step = |t: f64, mu: f64| -> Result<Option<Candidate>, SurfaceFairError> {
            let (dr, rank) = truncated_svd_solve(&svd, &fv, t);
            if !dr.iter().all(|x| x.is_finite()) {
                return Ok(None);
            }
            let mut trial = current.clone();
            apply_along(&mut trial, &base, selected, &dirs, &dr, mu)?;
            let ft = residuals(&trial, lights, samples);
            let c = Candidate {
                st: stats(&ft),
                ss: sum_of_squares(&ft),
                surface: trial,
                f: ft,
                step: mu,
                rank,
                truncation: t,
            };
            let ok = match opts.damping {
                // Eq. (3.12) as printed
                PaperDamping::MaxMean => c.st.0 < now.0 && c.st.1 < now.1,
                PaperDamping::Residual => c.ss < ss_now,
                PaperDamping::Off => c.ss.is_finite(),
            };
            Ok(ok.then_some(c))
        };
        let better = |c: &Candidate, a: &Option<Candidate>| {
            a.as_ref().is_none_or(|a| match opts.damping {
                PaperDamping::MaxMean => c.st.1 < a.st.1,
                _ => c.ss < a.ss,
            })
        };
        let mut accepted: Option<Candidate> = None;
        loop {
            if let Some(c) = try_step(trunc, 1.0)? {
                let halved = c.st.1 <= 0.5 * now.1;
                if better(&c, &accepted) {
                    accepted = Some(c);
                }
                if halved {
                    break;
                }
            }
            if trunc <= opts.min_truncation || opts.damping == PaperDamping::Off {
                break;
            }
            trunc = (0.1 * trunc).max(opts.min_truncation);
        }
        if accepted.is_none() {
            for &t in levels.iter().rev().filter(|&&t| t > trunc) {
                if let Some(c) = try_step(t, 1.0)?
                    && better(&c, &accepted)
                {
                    accepted = Some(c);
                }
            }
        }
        if accepted.is_none() {
            for &t in levels.iter().rev() {
                if let Some(c) = try_step(t, opts.damped_step)? {
                    accepted = Some(c);
                    break;
                }
            }
        }
        let Some(c) = accepted else {
            // Not even a damped step helps: keep the current surface.
            stop = FairStop::Stalled;
            break;
        };
        if opts.damping == PaperDamping::Residual && c.st.1 >= now.1 {
            // The best step lowers Σ d_s² but not mean |d_s|: Eq. (3.12)
            // no longer sees convergence, the least-squares floor is
            // reached (Eq. (3.14)); keep the current surface.
            converged = true;
            stop = FairStop::Epsilon;
            break;
        }
        let rel = (now.1 - c.st.1).abs() / now.1;
        current = c.surface;
        f = c.f;
        now = c.st;
        let objective = mean_square(&f);
        iterations.push(FairIteration {
            max_abs: now.0,
            mean_abs: now.1,
            step: c.step,
            rows: samples.len(),
            cols,
            rank: c.rank,
            truncation: c.truncation,
            objective,
            damping: 0.0,
            time_s: t0.elapsed().as_secs_f64(),
        });
        if now.1 <= tiny {
            converged = true;
            stop = FairStop::ZeroResidual;
        } else if rel < opts.epsilon {
            // Eq. (3.14)
            converged = true;
            stop = FairStop::Epsilon;
        }
    }
    Ok(Solved {
        surface: current,
        iterations,
        converged,
        stop,
        after: now,
        keep_samples: 0,
    })
}

/// One trial step of [`solve_paper`]: the surface it gives and its
/// residuals.
pub(super) struct Candidate {
    surface: BSplineSurface,
    f: Vec<Option<f64>>,
    /// (max, mean) |d_s|.
    st: (f64, f64),
    /// Σ d_s².
    ss: f64,
    step: f64,
    rank: usize,
    truncation: f64,
}

/// The truncation levels [`solve_paper`] tries at every iteration: the
/// paper's `first` (5 %), lowered tenfold down to `floor` (which ends the
/// list); `first` alone when `floor ≥ first`.
pub(super) fn truncation_levels(first: f64, floor: f64) -> Vec<f64> {
    let mut out = vec![first];
    let mut t = first;
    while t > floor && out.len() < 16 {
        t = (0.1 * t).max(floor);
        out.push(t);
    }
    out
}

/// Σ d_s² (infinite if any is undefined).
pub(super) fn sum_of_squares(r: &[Option<f64>]) -> f64 {
    r.iter().map(|x| x.map_or(f64::INFINITY, |x| x * x)).sum()
}

/// Mean of d_s² (infinite if any is undefined; 0 for none).
pub(super) fn mean_square(r: &[Option<f64>]) -> f64 {
    if r.is_empty() {
        return 0.0;
    }
    let mut sum = 0.0;
    for x in r {
        match x {
            Some(x) => sum += x * x,
            None => return f64::INFINITY,
        }
    }
    sum / r.len() as f64
}
