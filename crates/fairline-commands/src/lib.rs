//! The commands of fairline as one layer: each command a user runs —
//! `fair`, `smooth`, … — is a function here,
//! `run(inputs, &settings, &Control) -> Result<Outcome, CommandError>`,
//! that the CLI, the Python package and the workbench all call. A front end
//! only parses its own options into the settings, calls, and presents the
//! outcome; reading and writing files and drawing pictures stay in the
//! front ends.
//!
//! What is here once for every front end:
//! - the light options and the readable-light policy ([`Lights`]);
//! - the names of methods, weights, solvers and projections ([`Choice`]);
//! - the kinds of failure and how the library's errors map into them
//!   ([`CommandError`], [`ErrorKind`]);
//! - warnings and notes as structured values, worded by each front end in
//!   its own option names ([`Warning`], [`Note`], [`FrontEnd`]);
//! - the JSON report ([`Report`]), the same document in every front end;
//! - the equivalent command line of a command's settings
//!   (`Settings::command_line`), so that what the workbench shows is what
//!   the CLI runs.

#![forbid(unsafe_code)]

pub mod continuity;
pub mod curvature;
pub mod curves;
pub mod detect;
pub mod deviation;
pub mod draft;
pub mod enhance;
pub mod error;
pub mod fair;
pub mod fair_quad;
pub mod fair_surface;
pub mod highlight;
pub mod info;
pub mod lights;
pub mod names;
pub mod regions;
pub mod repair;
pub mod report;
pub mod section;
pub mod smooth;
pub mod surface_highlight;
pub mod warning;
mod words;

pub use error::{CommandError, ErrorKind, Subject, chain_text};
pub use lights::Lights;
pub use names::{Choice, Named, Weights};
pub use report::{Report, finite_only};
pub use warning::{FrontEnd, Warning};

/// Refuses a mesh of `faces` faces and `vertices` vertices that has no
/// face: it holds no surface for a command to work on (only `info` counts
/// such a file). The error is about the input ([`Subject::Input`]).
pub fn require_faces(faces: usize, vertices: usize) -> Result<(), CommandError> {
    if faces > 0 {
        return Ok(());
    }
    let what = match vertices {
        0 => "is empty (no vertex, no face)".to_string(),
        1 => "has no faces, only 1 vertex".to_string(),
        n => format!("has no faces, only {n} vertices"),
    };
    Err(
        CommandError::bad_input(format!("the mesh {what}: there is no surface to work on"))
            .about(Subject::Input),
    )
}

/// What a command says on the way (not a warning: nothing went wrong),
/// worded by each front end ([`Note::message`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// `fair --auto` found nothing to fair.
    NothingDetected,
    /// `fair --auto`: detected region `region` (1-based, with its score)
    /// grown by `rings` rings of faces.
    AutoRegionGrown {
        region: usize,
        score: f64,
        rings: usize,
        from: usize,
        to: usize,
    },
    /// A region grown by `rings` rings of faces (`fair --grow`).
    RegionGrown {
        rings: usize,
        from: usize,
        to: usize,
    },
}

impl Note {
    /// The note worded for `front_end`; `input` names the input.
    pub fn message(&self, front_end: FrontEnd, input: Option<&str>) -> String {
        match self {
            Note::NothingDetected => {
                let text = format!(
                    "{} found no defect above the detection threshold; nothing to fair",
                    front_end.switch("auto")
                );
                match input {
                    Some(name) => format!("{name}: {text}"),
                    None => text,
                }
            }
            Note::AutoRegionGrown {
                region,
                score,
                rings,
                from,
                to,
            } => format!(
                "{}: region {region} (score {score:.1}) grown by {rings} rings of faces: {from} -> {to} faces",
                front_end.switch("auto")
            ),
            Note::RegionGrown { rings, from, to } => {
                format!("region grown by {rings} rings of faces: {from} -> {to} faces")
            }
        }
    }
}
