//! Step (2): the Newton iteration that moves every free vertex along its
//! normal, with the Jacobian's sparsity and probe colouring, its finite
//! differences and the Levenberg–Marquardt step.

use super::curvature::{Eval, Evaluator, Unknowns};
use crate::Vec3;
use crate::smooth::SmoothError;
use crate::solve::{least_squares, sparse_from_triplets};

/// The vertices within `depth` rings of `start` (itself first).
pub(super) fn rings(nbrs: &[Vec<usize>], start: usize, depth: usize) -> Vec<usize> {
    let mut seen = vec![start];
    let mut frontier = vec![start];
    for _ in 0..depth {
        let mut next = Vec::new();
        for &a in &frontier {
            for &b in &nbrs[a] {
                if !seen.contains(&b) {
                    seen.push(b);
                    next.push(b);
                }
            }
        }
        frontier = next;
    }
    seen
}

/// Sparsity and probe colouring of the Newton Jacobian. The residual f_i of
/// a free vertex depends on the positions within two rings of it (H_i and
/// its normal on the one-ring, H_j of the neighbours on theirs, the
/// cotangent weights on the one-ring), so moving vertex k changes only the
/// rows of its two-ring: columns whose two-rings are disjoint (distance
/// above 4) are probed by one finite difference together. Returns the rows of
/// each column and the groups of columns probed together.
pub(super) fn jacobian_pattern(
    nbrs: &[Vec<usize>],
    u: &Unknowns,
) -> (Vec<Vec<usize>>, Vec<Vec<usize>>) {
    let index = &u.index;
    let support: Vec<Vec<usize>> = u
        .vertices
        .iter()
        .map(|&k| {
            let mut rows: Vec<usize> = rings(nbrs, k, 2)
                .into_iter()
                .filter_map(|i| (index[i] != usize::MAX).then_some(index[i]))
                .collect();
            rows.sort_unstable();
            rows
        })
        .collect();
    let mut colour = vec![usize::MAX; u.vertices.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (c, &k) in u.vertices.iter().enumerate() {
        let taken: Vec<usize> = rings(nbrs, k, 4)
            .into_iter()
            .filter(|&i| index[i] != usize::MAX)
            .map(|i| colour[index[i]])
            .filter(|&g| g != usize::MAX)
            .collect();
        let g = (0..).find(|g| !taken.contains(g)).unwrap_or(0);
        colour[c] = g;
        if g == groups.len() {
            groups.push(Vec::new());
        }
        groups[g].push(c);
    }
    (support, groups)
}

/// Step (2)'s Jacobian of the residuals Σ_j w_ij (H_i − H_j) in the offsets
/// t along the current normals, by coloured finite differences of the
/// whole evaluation (so it includes what a hand linearisation of Eq. (29)
/// freezes: the normals, the Moreton–Séquin fit weights, the cotangent
/// weights; with frozen terms the step was no descent direction on larger
/// patches). Triplets (row, column, value).
pub(super) fn finite_difference_jacobian(
    evaluator: &Evaluator,
    ev: &Eval,
    work: &[Vec3],
    support: &[Vec<usize>],
    groups: &[Vec<usize>],
    ebar: f64,
) -> Vec<(usize, usize, f64)> {
    let unknown = evaluator.unknown;
    let step = 1e-6 * ebar;
    let mut jac = Vec::new();
    let mut probe = work.to_vec();
    for group in groups {
        for &c in group {
            let i = unknown[c];
            probe[i] = work[i] + step * ev.normals[i];
        }
        let e = evaluator.evaluate(&probe);
        for &c in group {
            for &r in &support[c] {
                let v = (e.f[r] - ev.f[r]) / step;
                if v != 0.0 && v.is_finite() {
                    jac.push((r, c, v));
                }
            }
            let i = unknown[c];
            probe[i] = work[i];
        }
    }
    jac
}

/// Levenberg–Marquardt step min ‖J t + f‖² + δ‖t‖² with δ = `relative` ·
/// max_c ‖J e_c‖² (m unknowns). On a closed mesh without fixed vertices the
/// residuals sum to zero and moving along the normals of a rigid
/// translation or a scaling leaves Δ_B H unchanged, so J is rank deficient
/// and its normal equations singular; the damping picks the least-norm
/// step. On open patches the damped step also kept a 41×41 noisy cap from
/// stalling where the undamped Gauss–Newton steps ran into a region without
/// descent.
pub(super) fn damped_step(
    jac: &[(usize, usize, f64)],
    f: &[f64],
    m: usize,
    relative: f64,
) -> Result<Vec<f64>, SmoothError> {
    let mut colsq = vec![0.0f64; m];
    for &(_, c, v) in jac {
        colsq[c] += v * v;
    }
    let delta = relative * colsq.iter().fold(0.0f64, |a, b| a.max(*b));
    let d = if delta > 0.0 { delta.sqrt() } else { 1e-300 };
    let mut trip = jac.to_vec();
    trip.extend((0..m).map(|c| (m + c, c, d)));
    let mut rhs: Vec<f64> = f.iter().map(|x| -x).collect();
    rhs.resize(2 * m, 0.0);
    let jm = sparse_from_triplets(2 * m, m, &trip)?;
    Ok(least_squares(jm.as_ref(), std::slice::from_ref(&rhs))?
        .pop()
        .unwrap_or_default())
}

/// What one Newton iteration of step (2) found.
pub(super) enum NewtonOutcome {
    /// A step that lowers the merit: new positions, their evaluation and
    /// the size of the Newton step (max |t| / ē).
    Accepted(Vec<Vec3>, Eval, f64),
    /// The Newton step is below ε and lowers nothing: converged in place.
    BelowEpsilon,
    /// No attempt lowered the merit.
    NoDescent,
}

/// Step (2): every free vertex moves along its normal, all offsets at once,
/// by a Newton step on Σ_j w_ij (H_i − H_j) = 0 (Eq. (29)), |t_i| clamped to
/// half the mean length of its edges, kept only when it lowers the merit
/// (backtracking down to 1/64).
pub(super) fn newton_step(
    evaluator: &Evaluator,
    ev: &Eval,
    work: &[Vec3],
    jac: &[(usize, usize, f64)],
    any_floating: bool,
    ebar: f64,
    epsilon: f64,
) -> Result<NewtonOutcome, SmoothError> {
    let (unknown, nbrs) = (evaluator.unknown, evaluator.nbrs);
    let m = unknown.len();
    let p = work;
    let normals = &ev.normals;
    // the damped step first, the undamped one (unless the system is
    // known to be singular) when it finds no descent
    let undamped = if any_floating {
        None
    } else {
        let rhs: Vec<f64> = ev.f.iter().map(|x| -x).collect();
        let jm = sparse_from_triplets(m, m, jac)?;
        least_squares(jm.as_ref(), std::slice::from_ref(&rhs))
            .ok()
            .and_then(|mut t| t.pop())
    };
    // Attempts, in order: the lightly damped step (1e-12 relative, 1e-10
    // where a component floats), the undamped one, then
    // Levenberg–Marquardt steps with ever stronger damping. Far from
    // Δ_B H = 0 (the cow "Spot": ears, horns and legs) the Gauss–Newton
    // step, clamped to half an edge, often lowers the merit for no step
    // length down to 1/64, so the iteration would stop after one step;
    // a strongly damped step turns toward −Jᵀf, which lowers the merit
    // for a small enough length whenever f is not stationary.
    let light = if any_floating { 1e-10 } else { 1e-12 };
    let attempts: [Option<f64>; 6] = [
        Some(light),
        None,
        Some(1e-6),
        Some(1e-3),
        Some(1e-1),
        Some(10.0),
    ];
    // size of the lightly damped (Newton) step: the convergence measure,
    // whichever attempt is taken (a strongly damped step is short by
    // construction and says nothing about convergence)
    let mut newton_step = f64::INFINITY;
    for attempt in attempts {
        let newton = attempt.is_none_or(|relative| relative <= light);
        let t = match (attempt, &undamped) {
            (Some(relative), _) => damped_step(jac, &ev.f, m, relative)?,
            (None, Some(t)) => t.clone(),
            (None, None) => continue,
        };
        // clamp |t_i| to half the mean length of its edges
        let t: Vec<f64> = unknown
            .iter()
            .enumerate()
            .map(|(r, &i)| {
                let lmean = nbrs[i].iter().map(|&j| p[j].distance(p[i])).sum::<f64>()
                    / nbrs[i].len().max(1) as f64;
                let ti = t.get(r).copied().unwrap_or(0.0);
                if ti.is_finite() && normals[i] != Vec3::ZERO {
                    ti.clamp(-0.5 * lmean, 0.5 * lmean)
                } else {
                    0.0
                }
            })
            .collect();
        let tmax = t.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // backtracking on the merit ‖Σ_j w_ij (H_i − H_j)‖²: far from
        // the solution the linearisation can overshoot; halve the step
        // until the merit drops (a step that lowers it for no α ≥ 1/64
        // is not taken). A Newton step below ε means convergence: it is
        // taken when it lowers the merit (a merit at round-off level
        // cannot be lowered, and the mesh then stays where it is).
        if attempt == Some(light) {
            newton_step = tmax / ebar;
        }
        let small = newton && tmax / ebar < epsilon;
        let mut alpha = 1.0;
        let mut trial = work.to_vec();
        let found = loop {
            for (r, &i) in unknown.iter().enumerate() {
                trial[i] = p[i] + alpha * t[r] * normals[i];
            }
            let e = evaluator.evaluate(&trial);
            if e.merit < ev.merit {
                break Some(e);
            }
            if small || alpha < 1.0 / 64.0 {
                break None;
            }
            alpha *= 0.5;
        };
        if let Some(e) = found {
            let size = if newton {
                alpha * tmax / ebar
            } else {
                newton_step
            };
            return Ok(NewtonOutcome::Accepted(trial, e, size));
        }
        if small {
            return Ok(NewtonOutcome::BelowEpsilon);
        }
    }
    Ok(NewtonOutcome::NoDescent)
}
