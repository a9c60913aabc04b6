//! How a command fails: the exit status (DESIGN.md §4) and the marker of
//! errors that are the user's input being wrong.

/// Exit status for bad input or usage (DESIGN.md §4).
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit status for a failure of the computation.
pub const EXIT_FAILURE: i32 = 1;

/// Marks an error as the user's input being wrong (exit status 2).
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for BadInput {}

/// Some parts of a `fairline inspect` run could not be judged (exit
/// status 1; the report's rows say why).
#[derive(Debug)]
pub struct PartsFailed(pub u64);

impl std::fmt::Display for PartsFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} part(s) could not be judged; their rows in the report say why",
            self.0
        )
    }
}
impl std::error::Error for PartsFailed {}

/// An error that exits with status 2.
pub fn bad_input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(BadInput(msg.into()))
}

/// Exit status for an error — the one policy of every command
/// (docs/guide/conventions.md, "Exit status"):
///
/// - 1 when an output could not be written once the run was under way,
///   whatever its kind (mesh, picture, report, SVG, CSV, surface file):
///   the temporary file could not be made, written, synced or renamed
///   ([`fairline::io::write_failures`]); the inputs were good, the run
///   failed;
/// - else 2 when any cause is bad input or arguments (our marker — which
///   also covers an output path refused before any work: a missing or
///   unwritable folder, a directory, a hard-linked file —, a file-format
///   error, an invalid mesh, malformed JSON, a missing input file);
/// - 1 otherwise (the computation failed or did not give what was asked).
///
/// Either way nothing is written: the outputs are staged and put in place
/// only when the command succeeds.
pub fn exit_code(err: &anyhow::Error) -> i32 {
    if fairline::io::write_failures() > 0 {
        return EXIT_FAILURE;
    }
    for cause in err.chain() {
        if let Some(e) = cause.downcast_ref::<fairline_commands::CommandError>()
            && e.kind() == fairline_commands::ErrorKind::BadInput
        {
            return EXIT_BAD_INPUT;
        }
        if cause.is::<BadInput>()
            || cause.is::<fairline::io::IoError>()
            || cause.is::<fairline::MeshError>()
            || cause.is::<serde_json::Error>()
            || cause.is::<fairline::bspline::BSplineError>()
            || cause.is::<fairline::io::SurfaceJsonError>()
            || cause.is::<fairline::io::IgesError>()
            || cause.is::<fairline::io::step::StepError>()
            || cause.is::<fairline::io::surface_file::SurfaceFileError>()
        {
            return EXIT_BAD_INPUT;
        }
        if let Some(e) = cause.downcast_ref::<std::io::Error>()
            && matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::PermissionDenied
            )
        {
            return EXIT_BAD_INPUT;
        }
    }
    EXIT_FAILURE
}
