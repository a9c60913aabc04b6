//! `fair-surface`'s wording shared by the front ends (the command itself
//! is still assembled by each front end).

use fairline::fair::{FairStop, SurfaceFairMethod, SurfaceFairReport};

/// The sentence of a run that did not converge: the reason it stopped,
/// the system's size when it is underdetermined, what to try; `None` when
/// it converged.
pub fn not_converged_warning(rep: &SurfaceFairReport) -> Option<String> {
    if rep.converged {
        return None;
    }
    let objective = match rep.method {
        SurfaceFairMethod::Paper => "mean |d_s|",
        SurfaceFairMethod::Regularised => "the objective",
    };
    let why = match rep.stop {
        FairStop::Stalled => format!(
            "stalled: {objective} stopped decreasing (neither the full nor the damped step lowered it at the finest truncation)"
        ),
        FairStop::MaxIterations => format!(
            "out of iterations: --max-iterations {} ran without meeting the stopping rule",
            rep.iterations
        ),
        FairStop::NonFiniteStep => {
            "the step was not finite; the last finite surface is kept".to_string()
        }
        FairStop::Epsilon | FairStop::ZeroResidual => "the stopping rule did not hold".to_string(),
    };
    let (rows, cols) = (rep.jacobian.rows, rep.jacobian.cols);
    let underdetermined = if rows < cols {
        format!(
            "; underdetermined: {rows} equations (target samples) for {cols} unknowns (3 per moved control point), so the targets do not fix the control points"
        )
    } else {
        String::new()
    };
    let try_this = match rep.method {
        SurfaceFairMethod::Paper => {
            "try --method regularised (well posed whatever the number of targets), more or longer stretches, a smaller --sample-spacing, or --max-iterations"
        }
        SurfaceFairMethod::Regularised => "try --max-iterations or other endpoints",
    };
    Some(format!(
        "fairing did not converge after {} iteration(s): {why}{underdetermined}; {try_this}",
        rep.iterations
    ))
}
