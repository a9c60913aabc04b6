//! `smooth`: the classic smoothing family (Grüner thesis ch. 3) with its
//! shared constraints, as every front end runs it.

use crate::error::CommandError;
use crate::names::{Choice, Weights};
use crate::report::Report;
use crate::warning::{FrontEnd, Warning};
use crate::words::{push_changed, push_given, push_switch};
use fairline::mesh::VertexId;
use fairline::smooth::{SmoothMethod, SmoothOptions, SmoothReport, StopReason, smooth};
use fairline::{Control, SurfaceMesh};

/// The options of `smooth` (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothSettings {
    /// The method.
    pub method: SmoothMethod,
    /// Laplacian weights (laplace, taubin).
    pub weights: Weights,
    /// Exponent of the edge-length weights.
    pub exponent: f64,
    /// Iterations (`None`: the method's default).
    pub iterations: Option<usize>,
    /// λ.
    pub lambda: Option<f64>,
    /// μ (taubin).
    pub mu: Option<f64>,
    /// Taubin pass band.
    pub pass_band: f64,
    /// Implicit time step (units of the squared mean edge length).
    pub time_step: f64,
    /// Convergence threshold (spring, schneider-kobbelt).
    pub epsilon: Option<f64>,
    /// Most work, in evaluations of Δ_B H at a vertex (schneider-kobbelt;
    /// `None`: the library's default).
    pub max_work: Option<u64>,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Smooth the boundary as curves first.
    pub hierarchical_boundary: bool,
    /// Vertices that never move.
    pub fixed: Vec<VertexId>,
    /// Keep the enclosed volume (closed meshes).
    pub preserve_volume: bool,
    /// Move vertices only in their tangent planes.
    pub tangential: bool,
}

impl Default for SmoothSettings {
    fn default() -> Self {
        SmoothSettings {
            method: SmoothMethod::Taubin,
            weights: Weights::Uniform,
            exponent: -1.0,
            iterations: None,
            lambda: None,
            mu: None,
            pass_band: 0.1,
            time_step: 1.0,
            epsilon: None,
            max_work: None,
            fix_boundary: false,
            hierarchical_boundary: false,
            fixed: Vec::new(),
            preserve_volume: false,
            tangential: false,
        }
    }
}

impl SmoothSettings {
    /// Refuses non-finite numbers and zero iterations (naming the option).
    pub fn check(&self) -> Result<(), CommandError> {
        for (name, v) in [
            ("lambda", self.lambda),
            ("mu", self.mu),
            ("pass-band", Some(self.pass_band)),
            ("time-step", Some(self.time_step)),
            ("epsilon", self.epsilon),
            ("exponent", Some(self.exponent)),
        ] {
            if v.is_some_and(|x| !x.is_finite()) {
                return Err(CommandError::invalid(name, "must be finite"));
            }
        }
        if self.iterations == Some(0) {
            return Err(CommandError::invalid("iterations", "must be at least 1"));
        }
        if self.max_work == Some(0) {
            return Err(CommandError::invalid("max-work", "must be at least 1"));
        }
        Ok(())
    }

    /// The `fairline smooth` command line of these settings on the file
    /// `input`, writing `output` (shell words); fixed vertices are read
    /// from `fixed.json`.
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = SmoothSettings::default();
        let mut c = format!("fairline smooth {input} --method {}", self.method.name());
        if self.weights != d.weights {
            c.push_str(&format!(" --weights {}", self.weights.name()));
        }
        push_changed(&mut c, "exponent", self.exponent, d.exponent);
        push_given(&mut c, "iterations", self.iterations);
        push_given(&mut c, "lambda", self.lambda);
        push_given(&mut c, "mu", self.mu);
        push_changed(&mut c, "pass-band", self.pass_band, d.pass_band);
        push_changed(&mut c, "time-step", self.time_step, d.time_step);
        push_given(&mut c, "epsilon", self.epsilon);
        push_given(&mut c, "max-work", self.max_work);
        push_switch(&mut c, "fix-boundary", self.fix_boundary);
        push_switch(&mut c, "hierarchical-boundary", self.hierarchical_boundary);
        if !self.fixed.is_empty() {
            c.push_str(" --fixed fixed.json");
        }
        push_switch(&mut c, "preserve-volume", self.preserve_volume);
        push_switch(&mut c, "tangential", self.tangential);
        c.push_str(&format!(" -o {output}"));
        c
    }

    /// The library's options.
    pub fn options(&self) -> SmoothOptions {
        SmoothOptions::default()
            .method(self.method)
            .weights(self.weights.laplace(self.exponent))
            .lambda(self.lambda)
            .mu(self.mu)
            .pass_band(self.pass_band)
            .time_step(self.time_step)
            .epsilon(self.epsilon)
            .iterations(self.iterations)
            .max_work(self.max_work)
            .fixed(self.fixed.clone())
            .fix_boundary(self.fix_boundary)
            .hierarchical_boundary(self.hierarchical_boundary)
            .preserve_volume(self.preserve_volume)
            .tangential_only(self.tangential)
    }
}

/// What `smooth` gives: the new positions, the library's report and the
/// JSON report. A method with a stopping rule of its own that stopped for
/// another reason ([`SmoothOutcome::stopped_unconverged`]) did not give
/// what was asked for: front ends say so as a failure of the computation
/// (the CLI exits 1 after writing the result for inspection).
#[derive(Clone, Debug)]
pub struct SmoothOutcome {
    /// The method that ran.
    pub method: SmoothMethod,
    /// The smoothed positions of the input's vertices.
    pub positions: Vec<fairline::Vec3>,
    /// What the method did.
    pub result: SmoothReport,
    /// The JSON report.
    pub report: Report,
}

impl SmoothOutcome {
    /// Why the method stopped, when it has a stopping rule of its own
    /// (Schneider–Kobbelt) and stopped without meeting it.
    pub fn stopped_unconverged(&self) -> Option<StopReason> {
        self.result
            .stop_reason
            .filter(|r| *r != StopReason::Converged)
    }

    /// The error of a run that stopped unconverged
    /// ([`SmoothOutcome::stopped_unconverged`]), worded once for every
    /// front end: `schneider-kobbelt stopped unconverged (stagnated) after
    /// 12 iteration(s): the residual stagnated …; try …`. A failure of the
    /// computation (CLI exit status 1, Python `FairlineComputationError`,
    /// a failed workbench job); `None` when the run gave what was asked.
    pub fn stopped_error(&self, front_end: FrontEnd) -> Option<CommandError> {
        let reason = self.stopped_unconverged()?;
        Some(CommandError::computation(crate::warning::smooth_stopped(
            self.method.name(),
            self.result.iterations,
            reason,
            true,
            front_end,
        )))
    }
}

/// Smooths `mesh` with `settings`; progress and cancellation through
/// `control`.
pub fn run(
    mesh: &SurfaceMesh,
    settings: &SmoothSettings,
    control: &Control,
) -> Result<SmoothOutcome, CommandError> {
    settings.check()?;
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    let options = settings.options().control(control.clone());
    let mut report = Report::new("smooth");
    let out = report.time(|| smooth(mesh, &options))?;
    let r = out.report;
    report.set("method", settings.method.name());
    report.set("vertices", mesh.vertex_count());
    report.set_fields(&r);
    for w in smooth_warnings(mesh, &options, &r) {
        report.warn(w);
    }
    Ok(SmoothOutcome {
        method: settings.method,
        positions: out.positions,
        result: r,
        report,
    })
}

/// What smoothing `input` into `report` with `options` warns about: the
/// method did not converge; Schneider–Kobbelt ran on a closed mesh with no
/// fixed vertex, where Δ_B H = 0 has no boundary data and its solutions are
/// the surfaces of constant mean curvature.
pub fn smooth_warnings(
    input: &SurfaceMesh,
    options: &SmoothOptions,
    report: &SmoothReport,
) -> Vec<Warning> {
    let mut warnings = Vec::new();
    let method = options.method.name();
    match report.stop_reason {
        Some(StopReason::Converged) => {}
        Some(reason) if reason != StopReason::MaxIterations => {
            warnings.push(Warning::SmoothStopped {
                method,
                iterations: report.iterations,
                reason,
            })
        }
        _ if !report.converged => warnings.push(Warning::SmoothNotConverged {
            method,
            iterations: report.iterations,
        }),
        _ => {}
    }
    let unanchored = options.method == SmoothMethod::SchneiderKobbelt
        && input.is_closed()
        && options.fixed.is_empty();
    if unanchored {
        warnings.push(Warning::Unanchored);
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warning::FrontEnd;
    use fairline::shapes;

    fn noisy_sphere() -> SurfaceMesh {
        let mut m = shapes::icosphere(1.0, 2);
        for (i, p) in m.positions_mut().iter_mut().enumerate() {
            *p *= 1.0 + 0.02 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
        }
        m
    }

    #[test]
    fn warnings_name_the_method_and_the_unanchored_closed_mesh() {
        let mesh = noisy_sphere();
        let sk = SmoothOptions::default()
            .method(SmoothMethod::SchneiderKobbelt)
            .iterations(Some(1));
        let out = smooth(&mesh, &sk).unwrap();
        let w: Vec<String> = smooth_warnings(&mesh, &sk, &out.report)
            .iter()
            .map(|w| w.message(FrontEnd::Cli))
            .collect();
        assert!(!out.report.converged);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(
            w[0],
            "schneider-kobbelt did not converge in 1 iteration(s); try more --iterations or a larger --epsilon"
        );
        assert!(w[1].starts_with("schneider-kobbelt on a closed mesh without --fixed vertices"));
        // anchored by a fixed vertex, or not Schneider–Kobbelt: no such warning
        let anchored = sk.clone().fixed(vec![VertexId(0)]);
        let out = smooth(&mesh, &anchored).unwrap();
        assert_eq!(smooth_warnings(&mesh, &anchored, &out.report).len(), 1);
        let taubin = SmoothOptions::default();
        let out = smooth(&mesh, &taubin).unwrap();
        assert!(out.report.converged);
        assert!(smooth_warnings(&mesh, &taubin, &out.report).is_empty());
    }

    /// A Schneider–Kobbelt run cut off by its work bound warns with the
    /// reason and the option to raise, in each front end's words, and is
    /// a run that stopped unconverged; with the default bound it runs.
    #[test]
    fn a_run_stopped_by_its_work_bound_says_so_and_names_the_option() {
        let mesh = noisy_sphere();
        let settings = SmoothSettings {
            method: SmoothMethod::SchneiderKobbelt,
            max_work: Some(1),
            fixed: vec![VertexId(0)],
            ..SmoothSettings::default()
        };
        let out = run(&mesh, &settings, &Control::new()).unwrap();
        assert_eq!(out.stopped_unconverged(), Some(StopReason::WorkLimit));
        let w = smooth_warnings(&mesh, &settings.options(), &out.result);
        assert_eq!(w.len(), 1, "{w:?}");
        let cli = w[0].message(FrontEnd::Cli);
        assert!(
            cli.starts_with("schneider-kobbelt stopped unconverged after 0 iteration(s): the next iteration would have exceeded the work bound (--max-work); raise --max-work"),
            "{cli}"
        );
        assert!(w[0].message(FrontEnd::Python).contains("raise max_work"));
        assert_eq!(out.report.to_json()["stop_reason"], "work_limit");
        // the error every front end raises names the reason in its words
        let e = out.stopped_error(FrontEnd::Python).unwrap();
        assert_eq!(e.kind(), crate::ErrorKind::Computation);
        let text = e.message(FrontEnd::Python);
        assert!(
            text.starts_with(
                "schneider-kobbelt stopped unconverged (work_limit) after 0 iteration(s)"
            ) && text.contains("raise max_work"),
            "{text}"
        );
        // the default bound lets it run its sweeps
        let bounded = SmoothSettings {
            max_work: None,
            ..settings
        };
        let out = run(&mesh, &bounded, &Control::new()).unwrap();
        assert!(out.result.iterations > 0, "{:?}", out.result);
        assert_ne!(out.result.stop_reason, Some(StopReason::WorkLimit));
        if out.stopped_unconverged().is_none() {
            assert!(out.stopped_error(FrontEnd::Cli).is_none());
        }
    }

    #[test]
    fn the_command_line_names_what_differs_from_the_defaults() {
        let s = SmoothSettings {
            method: SmoothMethod::Laplace,
            weights: Weights::Cotan,
            iterations: Some(3),
            lambda: Some(0.25),
            fixed: vec![VertexId(1)],
            ..SmoothSettings::default()
        };
        assert_eq!(
            s.command_line("in.obj", "out.obj"),
            "fairline smooth in.obj --method laplace --weights cotan --iterations 3 --lambda 0.25 --fixed fixed.json -o out.obj"
        );
    }
}
