//! `curvature`: per-vertex principal curvatures, directions, mean and
//! Gaussian curvature, as every front end runs it.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use fairline::geom::{
    CurvatureError, CurvatureMethod, CurvatureOptions, CurvatureOutput, curvature,
};
use fairline::{Control, SurfaceMesh};

/// The options of `curvature` (default: the CLI's).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurvatureSettings {
    /// The estimator.
    pub method: CurvatureMethod,
}

/// What `curvature` gives: the library's output (one value per vertex of
/// the mesh) and the JSON report.
#[derive(Clone, Debug)]
pub struct CurvatureOutcome {
    /// Principal curvatures, directions, normals, mean and Gaussian
    /// curvature.
    pub output: CurvatureOutput,
    /// The JSON report.
    pub report: Report,
}

/// The curvature of `mesh` (polygons are triangulated first).
pub fn run(
    mesh: &SurfaceMesh,
    settings: &CurvatureSettings,
    control: &Control,
) -> Result<CurvatureOutcome, CommandError> {
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    let mut report = Report::new("curvature");
    let options = CurvatureOptions::default()
        .method(settings.method)
        .control(control.clone());
    let output = report
        .time(|| curvature(mesh, &options))
        .map_err(|e| match e {
            CurvatureError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::bad_input(e.to_string()).about(Subject::Input),
        })?;
    report.set_fields(&output.report);
    Ok(CurvatureOutcome { output, report })
}
