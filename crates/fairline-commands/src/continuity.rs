//! `continuity`: G0 / G1 / G2 across the shared boundaries of a set of
//! B-spline patches, and its JSON report, as every front end runs it.
//! Reading the file and drawing the picture stay in the front ends.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use fairline::Control;
use fairline::bspline::BSplineSurface;
use fairline::bspline::continuity::{ContinuityOptions, ContinuityReport, continuity};

/// The options of `continuity` (defaults: the CLI's, which are the
/// library's [`ContinuityOptions`] defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct ContinuitySettings {
    /// Largest gap of a G0 seam (`None`: from the part's size).
    pub tolerance: Option<f64>,
    /// Largest normal angle of a G1 seam, in degrees.
    pub angle_tolerance: f64,
    /// Largest relative curvature jump of a G2 seam.
    pub curvature_tolerance: f64,
    /// Distance within which boundaries are matched (`None`: from the
    /// tolerance).
    pub match_distance: Option<f64>,
    /// Samples per shared edge.
    pub samples: usize,
}

impl Default for ContinuitySettings {
    fn default() -> Self {
        let d = ContinuityOptions::default();
        ContinuitySettings {
            tolerance: None,
            angle_tolerance: d.angle_tolerance_deg,
            curvature_tolerance: d.curvature_tolerance,
            match_distance: None,
            samples: d.samples,
        }
    }
}

impl ContinuitySettings {
    /// The library's options.
    pub fn options(&self) -> ContinuityOptions {
        ContinuityOptions::default()
            .tolerance(self.tolerance)
            .angle_tolerance_deg(self.angle_tolerance)
            .curvature_tolerance(self.curvature_tolerance)
            .match_distance(self.match_distance)
            .samples(self.samples)
    }
}

/// What `continuity` gives: the library's report of the seams and the JSON
/// report.
#[derive(Clone, Debug)]
pub struct ContinuityOutcome {
    /// The seams, their classes and the tolerance used.
    pub result: ContinuityReport,
    /// The JSON report.
    pub report: Report,
}

/// Classifies the seams of `surfaces`; the computation takes no control.
/// A failure is about the input ([`Subject::Input`]).
pub fn run(
    surfaces: &[BSplineSurface],
    settings: &ContinuitySettings,
    control: &Control,
) -> Result<ContinuityOutcome, CommandError> {
    let _ = control;
    let mut report = Report::new("continuity");
    let result = report
        .time(|| continuity(surfaces, &settings.options()))
        .map_err(|e| CommandError::bad_input(e.to_string()).about(Subject::Input))?;
    report.set_fields(&result);
    report.set("surfaces", surfaces.len());
    report.set("angle_tolerance_deg", settings.angle_tolerance);
    report.set("curvature_tolerance", settings.curvature_tolerance);
    Ok(ContinuityOutcome { result, report })
}

/// A one-line summary of an outcome over `surfaces` patches: the counts
/// per class, the tolerances and the skipped degenerate pieces (the CLI's
/// stderr line after the file name, the workbench's status).
pub fn summary(out: &ContinuityOutcome, surfaces: usize, settings: &ContinuitySettings) -> String {
    use fairline::bspline::continuity::SeamClass;
    let r = &out.result;
    let classes = [SeamClass::Gap, SeamClass::G0, SeamClass::G1, SeamClass::G2];
    format!(
        "{surfaces} patches, {} shared edges: {}; tolerance {:.3e}, {}°, {} % curvature{}",
        r.seams.len(),
        classes
            .iter()
            .map(|c| format!("{} {}", r.classes.get(*c), c.name()))
            .collect::<Vec<_>>()
            .join(", "),
        r.tolerance,
        settings.angle_tolerance,
        100.0 * settings.curvature_tolerance,
        if r.degenerate_sides > 0 {
            format!(
                "; {} boundary pieces shorter than the matching distance (poles, slivers) skipped",
                r.degenerate_sides
            )
        } else {
            String::new()
        }
    )
}
