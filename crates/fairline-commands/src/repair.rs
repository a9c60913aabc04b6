//! `repair`: a dirty face list made into a mesh every command accepts, as
//! every front end runs it.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use fairline::mesh::{RepairError, RepairOptions, Repaired, repair};
use fairline::{Control, Soup};

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
