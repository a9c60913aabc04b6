//! `fair-surface`: circular-highlight fairing of one B-spline surface of a
//! part (Nishiyama et al. §3) — the light policy (the circular lights
//! given, or derived from the whole part), the fairing, the JSON report and
//! its warnings — as the CLI, the Python package and the workbench all run
//! it. Reading the files (surfaces, lights, endpoints, line ids resolved on
//! a lines document) and drawing pictures stay in the front ends.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use crate::words::push_changed;
use fairline::Control;
use fairline::bspline::BSplineSurface;
use fairline::fair::{
    BoundaryControl, EndpointPair, PaperDamping, SurfaceFairError, SurfaceFairMethod,
    SurfaceFairOptions, SurfaceFairReport, fair_surface,
};
use fairline::highlight::{
    CircularLight, CircularLights, DEFAULT_CIRCULAR_RADII, default_circular_lights,
};
use serde_json::json;

/// Most distance, as a fraction of the parameter domain's diagonal, at
/// which an endpoint given as (u, v) may lie from the line it snaps to
/// without a warning ([`Warning::EndpointSnappedFar`]).
pub const SNAP_WARNING_FRACTION: f64 = 0.02;

/// The options of `fair-surface` (defaults: the CLI's, which are the
/// library's [`SurfaceFairOptions`] defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct FairSurfaceSettings {
    /// Which surface of the part to fair.
    pub surface: usize,
    /// Most iterations.
    pub max_iterations: usize,
    /// ε of the stopping rule, Eq. (3.14).
    pub epsilon: f64,
    /// Singular values below this fraction of the largest are dropped.
    pub truncation: f64,
    /// Floor the truncation is lowered to (a larger value is taken as
    /// `truncation`).
    pub min_truncation: f64,
    /// Step factor μ of the damped step, Eq. (3.13).
    pub damped_step: f64,
    /// When the paper's solver damps a step (Eq. (3.12)–(3.13)).
    pub damping: PaperDamping,
    /// Target sample spacing as a fraction of the domain diagonal.
    pub sample_spacing: f64,
    /// Grid points per direction for the pre-images.
    pub grid: usize,
    /// The solver.
    pub method: SurfaceFairMethod,
    /// Which boundary control points may move.
    pub boundary: BoundaryControl,
    /// Weight of the weak targets holding the other lines (regularised).
    pub keep_weight: f64,
    /// Weight of the thin-plate energy of the displacement (regularised).
    pub fairness_weight: f64,
}

impl Default for FairSurfaceSettings {
    fn default() -> Self {
        let d = SurfaceFairOptions::default();
        FairSurfaceSettings {
            surface: 0,
            max_iterations: d.max_iterations,
            epsilon: d.epsilon,
            truncation: d.truncation,
            min_truncation: d.min_truncation,
            damped_step: d.damped_step,
            damping: d.damping,
            sample_spacing: d.sample_spacing,
            grid: d.grid,
            method: SurfaceFairMethod::Regularised,
            boundary: BoundaryControl::Fixed,
            keep_weight: d.keep_weight,
            fairness_weight: d.fairness_weight,
        }
    }
}

/// The CLI's name of a solver (`--method`).
pub fn method_name(m: SurfaceFairMethod) -> &'static str {
    match m {
        SurfaceFairMethod::Regularised => "regularised",
        SurfaceFairMethod::Paper => "paper",
    }
}

/// The CLI's name of a boundary rule (`--boundary`).
pub fn boundary_name(b: BoundaryControl) -> &'static str {
    match b {
        BoundaryControl::Fixed => "fixed",
        BoundaryControl::FixedWithTangents => "tangent",
        BoundaryControl::Free => "free",
    }
}

impl FairSurfaceSettings {
    /// The `fairline fair-surface` command line of these settings on the
    /// file `input` with the lights file `lights.json` and the endpoints
    /// file `endpoints.json`, writing `output` (shell words); only what
    /// differs from the defaults besides `--surface`.
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = FairSurfaceSettings::default();
        let mut c = format!(
            "fairline fair-surface {input} --surface {} --lights lights.json --endpoints endpoints.json",
            self.surface
        );
        push_changed(
            &mut c,
            "max-iterations",
            self.max_iterations,
            d.max_iterations,
        );
        push_changed(&mut c, "epsilon", self.epsilon, d.epsilon);
        push_changed(&mut c, "truncation", self.truncation, d.truncation);
        push_changed(
            &mut c,
            "min-truncation",
            self.min_truncation,
            d.min_truncation,
        );
        push_changed(&mut c, "damped-step", self.damped_step, d.damped_step);
        if self.damping != d.damping {
            c.push_str(&format!(" --damping {}", self.damping.name()));
        }
        push_changed(
            &mut c,
            "sample-spacing",
            self.sample_spacing,
            d.sample_spacing,
        );
        push_changed(&mut c, "grid", self.grid, d.grid);
        if self.method != d.method {
            c.push_str(&format!(" --method {}", method_name(self.method)));
        }
        if self.boundary != d.boundary {
            c.push_str(&format!(" --boundary {}", boundary_name(self.boundary)));
        }
        push_changed(&mut c, "keep-weight", self.keep_weight, d.keep_weight);
        push_changed(
            &mut c,
            "fairness-weight",
            self.fairness_weight,
            d.fairness_weight,
        );
        c.push_str(&format!(" -o {output}"));
        c
    }

    /// The library's options with `lights` and `endpoints`.
    pub fn options(
        &self,
        lights: &[CircularLight],
        endpoints: &[EndpointPair],
    ) -> SurfaceFairOptions {
        SurfaceFairOptions::default()
            .lights(lights.to_vec())
            .endpoints(endpoints.to_vec())
            .grid(self.grid)
            .sample_spacing(self.sample_spacing)
            .truncation(self.truncation)
            // a larger floor is taken as the truncation; NaN is left for
            // the library's option check to refuse (f64::min would hide it)
            .min_truncation(if self.min_truncation > self.truncation {
                self.truncation
            } else {
                self.min_truncation
            })
            .epsilon(self.epsilon)
            .damped_step(self.damped_step)
            .damping(self.damping)
            .max_iterations(self.max_iterations)
            .method(self.method)
            .boundary(self.boundary)
            .keep_weight(self.keep_weight)
            .fairness_weight(self.fairness_weight)
    }
}

/// What `fair-surface` works on: every surface of the part, the circular
/// lights (`None`: derived from the whole part, as `highlight --circular`)
/// and the endpoint pairs of the stretches to fair, in (u, v).
#[derive(Clone, Copy, Debug)]
pub struct FairSurfaceInput<'a> {
    /// The surfaces of the part.
    pub surfaces: &'a [BSplineSurface],
    /// The circular lights given.
    pub lights: Option<&'a CircularLights>,
    /// The stretches to fair.
    pub endpoints: &'a [EndpointPair],
}

/// What `fair-surface` gives.
#[derive(Clone, Debug)]
pub struct FairSurfaceOutcome {
    /// Every surface of the part, the faired one in its place.
    pub surfaces: Vec<BSplineSurface>,
    /// The lights the fairing worked with.
    pub lights: Vec<CircularLight>,
    /// The lights derived from the part when none were given (front ends
    /// show them so that they can be saved and reused).
    pub derived: Option<CircularLights>,
    /// What the fairing did.
    pub result: SurfaceFairReport,
    /// The JSON report.
    pub report: Report,
}

impl FairSurfaceOutcome {
    /// Whether the paper's method, which promises the targets, stopped
    /// without converging: the result is for inspection only (the CLI
    /// exits 1 after writing it).
    pub fn paper_unconverged(&self) -> bool {
        !self.result.converged && self.result.method == SurfaceFairMethod::Paper
    }
}

/// Refuses a surface index beyond the part (about the input, naming the
/// option `surface`).
pub fn check_surface(surface: usize, count: usize) -> Result<(), CommandError> {
    if surface < count {
        return Ok(());
    }
    Err(CommandError::invalid(
        "surface",
        format!("{surface} is out of range (the file holds {count} surfaces)"),
    )
    .about(Subject::Input))
}

/// The circular lights of a run: those given, or derived from the whole
/// part; with the derived specification.
pub fn circular_lights(
    surfaces: &[BSplineSurface],
    given: Option<&CircularLights>,
) -> Result<(Vec<CircularLight>, Option<CircularLights>), CommandError> {
    match given {
        Some(spec) => {
            let lights = spec
                .lights()
                .map_err(|e| CommandError::bad_input(e.to_string()).about(Subject::Lights))?;
            Ok((lights, None))
        }
        None => {
            let spec = default_circular_lights(surfaces, None, DEFAULT_CIRCULAR_RADII).ok_or_else(
                || {
                    CommandError::bad_input(
                        "cannot derive circular lights: the part has no area with a defined normal",
                    )
                },
            )?;
            let lights = spec
                .lights()
                .map_err(|e| CommandError::bad_input(e.to_string()))?;
            Ok((lights, Some(spec)))
        }
    }
}

impl From<SurfaceFairError> for CommandError {
    /// A failed decomposition or a non-finite update is the computation's;
    /// every control point held says how to free them; the rest is the
    /// input's.
    fn from(e: SurfaceFairError) -> Self {
        match e {
            SurfaceFairError::Svd | SurfaceFairError::Surface(_) => {
                CommandError::computation(crate::chain_text(&e))
            }
            SurfaceFairError::Cancelled(_) => CommandError::cancelled(),
            SurfaceFairError::NothingToMove(_) => {
                CommandError::bad_input(e.to_string()).with_setting("boundary", "free")
            }
            SurfaceFairError::Invalid(ref m) if m.contains("endpoint") => {
                CommandError::bad_input(e.to_string()).about(Subject::Endpoints)
            }
            SurfaceFairError::NoLight { .. } | SurfaceFairError::NoPreImage { .. } => {
                CommandError::bad_input(e.to_string()).about(Subject::Endpoints)
            }
            other => CommandError::bad_input(other.to_string()),
        }
    }
}

/// Fairs surface `settings.surface` of `input`; progress and cancellation
/// through `control`.
pub fn run(
    input: FairSurfaceInput<'_>,
    settings: &FairSurfaceSettings,
    control: &Control,
) -> Result<FairSurfaceOutcome, CommandError> {
    check_surface(settings.surface, input.surfaces.len())?;
    let (lights, derived) = circular_lights(input.surfaces, input.lights)?;
    let options = settings
        .options(&lights, input.endpoints)
        .control(control.clone());
    let surface = &input.surfaces[settings.surface];
    let mut report = Report::new("fair-surface");
    let out = report.time(|| fair_surface(surface, &options))?;
    let result = out.report;
    if let Some(spec) = &derived {
        report.set(
            "light",
            json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii, "derived": true}),
        );
    }
    // the library's report carries the command's keys
    report.set_fields(&result);
    for w in fair_surface_warnings(surface, input.endpoints, &result) {
        report.warn(w);
    }
    let mut surfaces = input.surfaces.to_vec();
    surfaces[settings.surface] = out.surfaces;
    Ok(FairSurfaceOutcome {
        surfaces,
        lights,
        derived,
        result,
        report,
    })
}

/// What a run warns about: endpoints that snapped far from where they were
/// given (more than [`SNAP_WARNING_FRACTION`] of the parameter domain's
/// diagonal: probably read off another line), a run that did not converge,
/// a largest residual that grew.
pub fn fair_surface_warnings(
    input: &BSplineSurface,
    endpoints: &[EndpointPair],
    rep: &SurfaceFairReport,
) -> Vec<Warning> {
    let (du, dv) = (input.domain_u(), input.domain_v());
    let diagonal = (du[1] - du[0]).hypot(dv[1] - dv[0]);
    let mut warnings = Vec::new();
    for t in &rep.targets {
        for (k, d) in t.snap_distance.iter().enumerate() {
            if *d > SNAP_WARNING_FRACTION * diagonal {
                let given = endpoints[t.index];
                warnings.push(Warning::EndpointSnappedFar {
                    index: t.index,
                    fraction: SNAP_WARNING_FRACTION,
                    start: k == 0,
                    given: if k == 0 { given.start } else { given.end },
                    snapped: if k == 0 { t.start } else { t.end },
                    distance: *d,
                    radius: t.radius,
                    diagonal,
                });
            }
        }
    }
    if !rep.converged {
        warnings.push(Warning::SurfaceFairNotConverged {
            method: rep.method,
            stop: rep.stop,
            iterations: rep.iterations,
            equations: rep.jacobian.rows,
            unknowns: rep.jacobian.cols,
        });
    }
    if rep.residual_after.max > rep.residual_before.max {
        warnings.push(Warning::HighlightResidualWorse {
            before: rep.residual_before.max,
            after: rep.residual_after.max,
        });
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_names_what_differs_from_the_defaults() {
        let s = FairSurfaceSettings {
            surface: 2,
            max_iterations: 3,
            method: SurfaceFairMethod::Paper,
            boundary: BoundaryControl::Free,
            damping: PaperDamping::MaxMean,
            ..FairSurfaceSettings::default()
        };
        assert_eq!(
            s.command_line("in.json", "out.json"),
            "fairline fair-surface in.json --surface 2 --lights lights.json --endpoints endpoints.json --max-iterations 3 --damping max-mean --method paper --boundary free -o out.json"
        );
    }

    #[test]
    fn a_surface_beyond_the_part_names_the_option() {
        let e = check_surface(3, 2).unwrap_err();
        assert_eq!(
            e.message(crate::FrontEnd::Cli),
            "--surface 3 is out of range (the file holds 2 surfaces)"
        );
        assert_eq!(
            e.message(crate::FrontEnd::Python),
            "surface 3 is out of range (the file holds 2 surfaces)"
        );
        assert!(check_surface(1, 2).is_ok());
    }
}
