//! `repair`: a dirty face list made into a mesh every command accepts, as
//! every front end runs it.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::{FrontEnd, Warning};
use fairline::mesh::{RepairError, RepairOptions, Repaired, repair};
use fairline::{Control, MeshError, Soup};
use std::path::{Path, PathBuf};

/// What to do about a face list that is not a mesh every command accepts
/// (a non-manifold edge or vertex, a non-orientable surface, a repeated
/// vertex in a face, a face of fewer than three vertices): run `repair`
/// and use its result, in `front_end`'s words — the CLI names the file
/// `file` and the repaired file; Python names `fairline.repair`. `None`
/// for errors repair does not fix.
pub fn repair_hint(error: &MeshError, front_end: FrontEnd, file: Option<&Path>) -> Option<String> {
    use fairline::MeshError as M;
    if !matches!(
        error,
        M::NonManifoldEdge { .. }
            | M::NonManifoldVertex { .. }
            | M::NonOrientable { .. }
            | M::RepeatedVertex { .. }
            | M::FaceTooSmall { .. }
    ) {
        return None;
    }
    Some(match (front_end, file) {
        (FrontEnd::Cli, Some(path)) => format!(
            "run `fairline repair {} {}` and use the repaired mesh",
            path.display(),
            repaired_name(path).display()
        ),
        (FrontEnd::Cli, None) => {
            "run `fairline repair` on the file and use the repaired mesh".to_string()
        }
        (FrontEnd::Python, _) => {
            "run `V, F, report = fairline.repair(V, F)` and use the repaired mesh".to_string()
        }
        (FrontEnd::Workbench, _) => {
            "repair the mesh (`fairline repair`) and load the repaired one".to_string()
        }
    })
}

/// `name-repaired.ext` in the current folder (the input's folder may be
/// read-only).
fn repaired_name(path: &Path) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh");
    let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("ply");
    PathBuf::from(format!("{stem}-repaired.{ext}"))
}

/// What `repair` gives: the repaired face list and what was changed, and
/// the JSON report.
#[derive(Clone, Debug)]
pub struct RepairOutcome {
    /// The repaired positions and faces, with the library's report.
    pub repaired: Repaired,
    /// The JSON report.
    pub report: Report,
}

/// Repairs `soup`.
pub fn run(soup: &Soup, control: &Control) -> Result<RepairOutcome, CommandError> {
    crate::require_faces(soup.face_count(), soup.vertex_count())?;
    let mut report = Report::new("repair");
    let options = RepairOptions::default().control(control.clone());
    let repaired = report
        .time(|| repair(soup, &options))
        .map_err(|e| match e {
            RepairError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::bad_input(format!("cannot repair: {e}")).about(Subject::Input),
        })?;
    if repaired.soup.face_count() == 0 {
        return Err(CommandError::bad_input(format!(
            "cannot repair: every one of its {} faces was removed (invalid, duplicate or of zero area); no surface is left",
            soup.face_count()
        ))
        .about(Subject::Input));
    }
    let r = &repaired.report;
    report.set_fields(r);
    for w in r.warnings() {
        report.warn(Warning::Text(w));
    }
    Ok(RepairOutcome { repaired, report })
}
