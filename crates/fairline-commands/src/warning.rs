//! What a command warns about, as structured values, and how each front
//! end words them: the CLI names its options `--grow 2`, the Python package
//! its keywords `grow=2`, the workbench its controls.

use fairline::fair::{FairStop, SurfaceFairMethod};
use fairline::smooth::{
    DEFAULT_MAX_WORK, DIVERGENCE_FACTOR, STAGNATION_DECREASE, STAGNATION_WINDOW, StopReason,
};
use serde::Serialize;

/// The front end a message is worded for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrontEnd {
    /// `fairline COMMAND --option value`.
    Cli,
    /// The Python package's keyword arguments `option=value`.
    Python,
    /// The workbench's controls (named as on the page).
    Workbench,
}

impl FrontEnd {
    /// The name of option `name` (the CLI's long name without `--`, e.g.
    /// `max-iterations`) in this front end.
    pub fn option(self, name: &str) -> String {
        match self {
            FrontEnd::Cli => format!("--{name}"),
            FrontEnd::Python if name == "lambda" => "lambda_".into(),
            FrontEnd::Python => name.replace('-', "_"),
            FrontEnd::Workbench => name.replace('-', " "),
        }
    }

    /// Option `name` set to `value`: `--grow 2`, `grow=2`, `grow 2`.
    pub fn setting(self, name: &str, value: &str) -> String {
        match self {
            FrontEnd::Cli => format!("--{name} {value}"),
            FrontEnd::Python if value.parse::<f64>().is_ok() => {
                format!("{}={value}", self.option(name))
            }
            FrontEnd::Python => format!("{}={value:?}", self.option(name)),
            FrontEnd::Workbench => format!("{} {value}", self.option(name)),
        }
    }

    /// A switch turned on: `--auto`, `auto=True`, `auto`.
    pub fn switch(self, name: &str) -> String {
        match self {
            FrontEnd::Python => format!("{}=True", self.option(name)),
            _ => self.option(name),
        }
    }
}

/// What detection still flags on a faired mesh, as `detect` on the output
/// would report it ([`Warning::RemainingDefect`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RemainingDefect {
    /// Regions detection flags on the result.
    pub regions: usize,
    /// How many of them share a face with the faired region.
    pub overlapping: usize,
    /// Whether the best one does.
    pub best_inside: bool,
    /// The best region's score and the threshold at its site.
    pub score: f64,
    /// The threshold at the best region's site.
    pub threshold: f64,
    /// The best region's flat-spot value (0 when none) and the floor.
    pub flat_spot: f64,
    /// The flat-spot floor of the detection.
    pub flat_spot_floor: f64,
    /// The best region's centre.
    pub center: [f64; 3],
    /// Detection score inside the faired region before and after.
    pub score_before: f64,
    /// Detection score inside the faired region after.
    pub score_after: f64,
}

/// A warning of a command: something the user should hear about (a run
/// that did not converge, a measure made worse, a value left out of the
/// report). Worded by [`Warning::message`].
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Warning {
    /// A report value is not a finite number and was left out.
    NotFinite { key: String },
    /// A report value could not be serialised.
    ReportValueUnwritable { key: String, error: String },
    /// A report could not be serialised.
    ReportUnwritable { error: String },
    /// `fair`: there were `regions` regions to fair, but none was faired.
    NothingFaired { regions: usize },
    /// `fair`: a region did not converge within the iterations allowed.
    FairNotConverged { max_iterations: usize },
    /// `fair`: the highlight-line deviation got worse.
    DeviationWorse {
        before: f64,
        after: f64,
        score_before: f64,
        score_after: f64,
    },
    /// `fair`: detection on the result still flags a defect; `input` is
    /// the name of the input the front end says it about.
    RemainingDefect {
        input: Option<String>,
        defect: RemainingDefect,
    },
    /// `smooth`: the method did not converge.
    SmoothNotConverged {
        method: &'static str,
        iterations: usize,
    },
    /// `smooth`: the method stopped before converging for `reason` (not
    /// the most iterations: that is [`Warning::SmoothNotConverged`]).
    SmoothStopped {
        method: &'static str,
        iterations: usize,
        reason: StopReason,
    },
    /// `smooth`: Schneider–Kobbelt on a closed mesh with nothing fixed.
    Unanchored,
    /// `fair-quad`: the Eq. (30) structure-line energy got worse.
    QuadEnergyWorse { before: f64, after: f64 },
    /// `fair-quad --method network`: the structure-line energy (Eq. (30))
    /// rose; the network lowers the heights' bending, not the lines'
    /// turning.
    NetworkStructureWorse { before: f64, after: f64 },
    /// `enhance`: triangles flipped in a solved step and were repaired.
    TrianglesFlipped { count: usize },
    /// `fair-surface`: endpoint `index` (its start, or its end) lay
    /// `distance` from the nearest line of its light's radius, more than
    /// `fraction` of the parameter domain's `diagonal`, and was snapped
    /// there.
    EndpointSnappedFar {
        index: usize,
        fraction: f64,
        start: bool,
        given: [f64; 2],
        snapped: [f64; 2],
        distance: f64,
        radius: f64,
        diagonal: f64,
    },
    /// `fair-surface`: the iteration stopped without converging;
    /// `equations` target samples against `unknowns` coordinates.
    SurfaceFairNotConverged {
        method: SurfaceFairMethod,
        stop: FairStop,
        iterations: usize,
        equations: usize,
        unknowns: usize,
    },
    /// `fair-surface`: the largest highlight residual grew.
    HighlightResidualWorse { before: f64, after: f64 },
    /// `detect`: no highlight line crosses the mesh, so nothing could be
    /// detected.
    NoLineToDetectOn,
    /// `highlight`: no highlight line crosses the mesh.
    NoLineCrossesTheMesh,
    /// `highlight` on surfaces: no pre-image of a highlight line was found.
    NoPreImage,
    /// A sentence that names no option (a library report's, or a
    /// command's not yet in this layer).
    Text(String),
}

impl Warning {
    /// The warning as a sentence with `front_end`'s option names.
    pub fn message(&self, front_end: FrontEnd) -> String {
        let o = |name: &str| front_end.option(name);
        match self {
            Warning::NotFinite { key } => {
                format!("report value `{key}` is not a finite number; left out of the report")
            }
            Warning::ReportValueUnwritable { key, error } => {
                format!("report value `{key}` could not be written ({error}); left out")
            }
            Warning::ReportUnwritable { error } => format!("report could not be written ({error})"),
            Warning::NothingFaired { regions } => {
                let which = match regions {
                    1 => "the region to fair has no vertex".to_string(),
                    n => format!("none of the {n} regions to fair has a vertex"),
                };
                format!(
                    "no region was faired: {which} free to move (see skipped_regions in the report); the output is the input unchanged"
                )
            }
            Warning::FairNotConverged { max_iterations } => format!(
                "fairing did not converge within {}; try more iterations or a larger region ({}, {})",
                front_end.setting("max-iterations", &max_iterations.to_string()),
                o("grow"),
                o("auto")
            ),
            Warning::DeviationWorse {
                before,
                after,
                score_before,
                score_after,
            } => format!(
                "the highlight-line deviation (distance of the lines inside the region from their own smoothed curves) got worse: {before:.4e} before, {after:.4e} after; the detection score (as `detect` measures it, same lights) went {score_before:.2} -> {score_after:.2}"
            ),
            Warning::RemainingDefect { input, defect } => {
                let text = remaining_defect(defect, front_end);
                match input {
                    Some(name) => format!("{name}: {text}"),
                    None => text,
                }
            }
            Warning::SmoothNotConverged { method, iterations } => format!(
                "{method} did not converge in {iterations} iteration(s); try more {} or a larger {}",
                o("iterations"),
                o("epsilon")
            ),
            Warning::SmoothStopped {
                method,
                iterations,
                reason,
            } => smooth_stopped(method, *iterations, *reason, false, front_end),
            Warning::Unanchored => format!(
                "schneider-kobbelt on a closed mesh without {} vertices: nothing holds the shape, \
                 and Δ_B H = 0 pulls it toward constant mean curvature (a sphere-like blob), erasing \
                 features such as ears or legs; fix the vertices that must stay ({}) to keep them",
                o("fixed"),
                o("fixed")
            ),
            Warning::QuadEnergyWorse { before, after } => format!(
                "the structure-line energy got worse: {before:.4e} before, {after:.4e} after; try a larger {}",
                o("weight")
            ),
            Warning::NetworkStructureWorse { before, after } => format!(
                "the structure-line energy got worse: {before:.4e} before, {after:.4e} after; the network method lowers the bending of the heights within their tolerance cylinders, not the turning of the lines (the default {} straightens structure lines)",
                o("method")
            ),
            Warning::TrianglesFlipped { count } => format!(
                "{count} triangle(s) flipped their orientation in the solved step and were repaired by shortening their vertices' steps; try a smaller {} or fewer {}",
                o("lambda"),
                o("iterations")
            ),
            Warning::EndpointSnappedFar {
                index,
                fraction,
                start,
                given: p,
                snapped: q,
                distance,
                radius,
                diagonal,
            } => format!(
                "endpoint {index} {}: ({:.4}, {:.4}) lies {distance:.4} from the nearest line of radius {radius} (more than {} % of the domain diagonal {diagonal:.4}) and was snapped to ({:.4}, {:.4}); was it read off another line?",
                if *start { "start" } else { "end" },
                p[0],
                p[1],
                100.0 * fraction,
                q[0],
                q[1]
            ),
            Warning::SurfaceFairNotConverged {
                method,
                stop,
                iterations,
                equations,
                unknowns,
            } => surface_not_converged(
                *method,
                *stop,
                *iterations,
                (*equations, *unknowns),
                front_end,
            ),
            Warning::HighlightResidualWorse { before, after } => format!(
                "the largest highlight residual got worse: {before:.4e} before, {after:.4e} after"
            ),
            Warning::NoLineToDetectOn => format!(
                "no highlight line crosses the mesh, so nothing could be detected; try other light options ({}, {}, {})",
                o("plane-normal"),
                o("direction"),
                o("spacing")
            ),
            Warning::NoLineCrossesTheMesh => format!(
                "no highlight line crosses the mesh; try other light options ({}, {}, {})",
                o("plane-normal"),
                o("direction"),
                o("spacing")
            ),
            Warning::NoPreImage => format!(
                "no highlight line pre-image was found on the surface; try other radii, {} or {}",
                o("circle-center"),
                o("circle-axis")
            ),
            Warning::Text(text) => text.clone(),
        }
    }
}

/// The sentence of a `fair-surface` run that did not converge: the reason
/// it stopped, the system's size (`rows` equations, `cols` unknowns) when
/// it is underdetermined, what to try.
fn surface_not_converged(
    method: SurfaceFairMethod,
    stop: FairStop,
    iterations: usize,
    (rows, cols): (usize, usize),
    front_end: FrontEnd,
) -> String {
    let o = |name: &str| front_end.option(name);
    let objective = match method {
        SurfaceFairMethod::Paper => "the residual d_s",
        SurfaceFairMethod::Regularised => "the objective",
    };
    let why = match stop {
        FairStop::Stalled => format!(
            "stalled: {objective} stopped decreasing (neither the full nor the damped step lowered it at the finest truncation)"
        ),
        FairStop::MaxIterations => format!(
            "out of iterations: {} ran without meeting the stopping rule",
            front_end.setting("max-iterations", &iterations.to_string())
        ),
        FairStop::NonFiniteStep => {
            "the step was not finite; the last finite surface is kept".to_string()
        }
        FairStop::Epsilon | FairStop::ZeroResidual => "the stopping rule did not hold".to_string(),
    };
    let underdetermined = if rows < cols {
        format!(
            "; underdetermined: {rows} equations (target samples) for {cols} unknowns, so the targets do not fix the control points"
        )
    } else {
        String::new()
    };
    let try_this = match method {
        SurfaceFairMethod::Paper => format!(
            "try {} (well posed whatever the number of targets), more or longer stretches, a smaller {}, or {}",
            front_end.setting("method", "regularised"),
            o("sample-spacing"),
            o("max-iterations")
        ),
        SurfaceFairMethod::Regularised => {
            format!("try {} or other endpoints", o("max-iterations"))
        }
    };
    format!(
        "fairing did not converge after {iterations} iteration(s): {why}{underdetermined}; {try_this}"
    )
}

/// Why a smoothing run stopped unconverged, and what to try.
/// The sentence of a run that stopped without meeting its stopping rule:
/// why and what to try; `tagged` adds the reason's report name
/// (`stop_reason`) after "unconverged", as the error of the run says it.
pub(crate) fn smooth_stopped(
    method: &str,
    iterations: usize,
    reason: StopReason,
    tagged: bool,
    front_end: FrontEnd,
) -> String {
    let o = |name: &str| front_end.option(name);
    let why = match reason {
        StopReason::Stagnated => format!(
            "the residual stagnated (it fell by less than {:.0} % over the last {STAGNATION_WINDOW} iterations)",
            100.0 * STAGNATION_DECREASE
        ),
        StopReason::Diverged => format!(
            "the residual diverged (it grew beyond {DIVERGENCE_FACTOR} times its smallest value)"
        ),
        StopReason::NoDescent => "no step lowered the residual".to_string(),
        StopReason::WorkLimit => format!(
            "the next iteration would have exceeded the work bound ({})",
            o("max-work")
        ),
        StopReason::MaxIterations => "it ran the most iterations allowed".to_string(),
        StopReason::Converged => "it converged".to_string(),
    };
    let try_this = match reason {
        StopReason::WorkLimit => format!(
            "raise {} (default {DEFAULT_MAX_WORK}), smooth fewer vertices ({} the others), or use another {} (taubin, implicit)",
            o("max-work"),
            o("fixed"),
            o("method")
        ),
        StopReason::MaxIterations => {
            format!("try more {} or a larger {}", o("iterations"), o("epsilon"))
        }
        _ => format!(
            "fix the vertices that must stay ({}), try a larger {}, or another {} (taubin, implicit)",
            o("fixed"),
            o("epsilon"),
            o("method")
        ),
    };
    let tag = if tagged {
        format!(" ({})", reason.name())
    } else {
        String::new()
    };
    format!("{method} stopped unconverged{tag} after {iterations} iteration(s): {why}; {try_this}")
}

/// The remaining-defect sentence: what `detect` on the result flags, where,
/// and what to do.
fn remaining_defect(d: &RemainingDefect, front_end: FrontEnd) -> String {
    let place = if d.best_inside {
        "inside the faired region"
    } else {
        "outside the faired region"
    };
    let advice = if d.overlapping == 0 {
        match front_end {
            FrontEnd::Cli => {
                "fair it too (`fairline detect` on the result writes its region, or use --auto)"
                    .to_string()
            }
            _ => format!(
                "fair it too (detect on the result gives its region, or use {})",
                front_end.switch("auto")
            ),
        }
    } else if d.score_after > d.score_before {
        format!(
            "the detection score inside the region got worse; try a larger region ({}) or {}",
            front_end.setting("grow", "2"),
            front_end.setting("method", "diffusion-flow")
        )
    } else {
        format!("try {} or more iterations", front_end.setting("grow", "2"))
    };
    let what = if d.score > d.threshold || d.flat_spot <= 0.0 {
        format!(
            "the best scoring {:.2} (threshold {:.2} there)",
            d.score, d.threshold
        )
    } else {
        format!(
            "the best a flat spot {:.2} (floor {:.2})",
            d.flat_spot, d.flat_spot_floor
        )
    };
    let c = d.center;
    format!(
        "a defect remains: detect on the result flags {} region(s) ({} overlapping the faired region), {what} at [{:.4}, {:.4}, {:.4}], {place}; detection score inside the faired region {:.2} -> {:.2}; {advice}",
        d.regions, d.overlapping, c[0], c[1], c[2], d.score_before, d.score_after,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_front_end_names_its_own_options() {
        let w = Warning::FairNotConverged { max_iterations: 2 };
        assert_eq!(
            w.message(FrontEnd::Cli),
            "fairing did not converge within --max-iterations 2; try more iterations or a larger region (--grow, --auto)"
        );
        assert_eq!(
            w.message(FrontEnd::Python),
            "fairing did not converge within max_iterations=2; try more iterations or a larger region (grow, auto)"
        );
        assert_eq!(FrontEnd::Python.option("lambda"), "lambda_");
        assert_eq!(
            FrontEnd::Python.setting("method", "diffusion-flow"),
            "method=\"diffusion-flow\""
        );
        assert_eq!(
            Warning::NothingFaired { regions: 1 }.message(FrontEnd::Cli),
            "no region was faired: the region to fair has no vertex free to move (see skipped_regions in the report); the output is the input unchanged"
        );
    }
}
