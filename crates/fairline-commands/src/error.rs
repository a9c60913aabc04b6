//! How a command fails: a handful of kinds that every front end maps the
//! same way (the CLI to its exit status, Python to its exception classes,
//! the workbench to its HTTP status and job state), and the one place the
//! library's error types are sorted into them.

use crate::warning::FrontEnd;
use fairline::MeshError;
use fairline::enhance::EnhanceError;
use fairline::fair::{FairError, QuadFairError};
use fairline::highlight::HighlightError;
use fairline::smooth::SmoothError;

/// The kind of a failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The input or the options are wrong: CLI exit status 2, Python
    /// `FairlineError` (a ValueError), HTTP 400.
    BadInput,
    /// The computation failed: CLI exit status 1, Python
    /// `FairlineComputationError` (a RuntimeError).
    Computation,
    /// The caller cancelled the run through its [`fairline::Control`].
    Cancelled,
    /// The operating system could not read or write a file: CLI exit
    /// status 1 (2 when it does not exist), Python `FairlineFileError`.
    Io,
}

/// The input an error is about; the front end names it (the CLI by its
/// path, Python by its argument).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subject {
    /// The input mesh.
    Input,
    /// The region to work in.
    Region,
    /// The lights given (a lights file).
    Lights,
    /// The stretches of highlight lines to fair (an endpoints file).
    Endpoints,
}

/// What the user can do about an error, worded by each front end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hint {
    /// Enlarge the region or grow it by two rings.
    GrowRegion,
    /// Set option `.0` to `.1` (said in parentheses after the message).
    Setting(&'static str, &'static str),
}

/// A command's failure: its kind, its message, and what it is about.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandError {
    kind: ErrorKind,
    message: String,
    option: Option<&'static str>,
    subject: Option<Subject>,
    hint: Option<Hint>,
}

impl CommandError {
    fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        CommandError {
            kind,
            message: message.into(),
            option: None,
            subject: None,
            hint: None,
        }
    }
    /// The input or options are wrong.
    pub fn bad_input(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::BadInput, message)
    }
    /// The computation failed.
    pub fn computation(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Computation, message)
    }
    /// The run was cancelled.
    pub fn cancelled() -> Self {
        Self::new(ErrorKind::Cancelled, "cancelled")
    }
    /// Option `option` (the CLI's long name without `--`) has a bad value:
    /// `problem` says what is wrong ("must be finite").
    pub fn invalid(option: &'static str, problem: impl Into<String>) -> Self {
        CommandError {
            option: Some(option),
            ..Self::bad_input(problem)
        }
    }
    /// The same error, said to be about `subject`.
    pub fn about(mut self, subject: Subject) -> Self {
        self.subject = Some(subject);
        self
    }
    /// The same error, naming the setting of option `option` (the CLI's
    /// long name) to `value` that avoids it: "… (--boundary free)".
    pub fn with_setting(mut self, option: &'static str, value: &'static str) -> Self {
        self.hint = Some(Hint::Setting(option, value));
        self
    }
    /// The kind.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }
    /// What the error is about, when it is about one input.
    pub fn subject(&self) -> Option<Subject> {
        self.subject
    }
    /// The message with `front_end`'s option names (without the name of
    /// the subject, which the front end puts in front).
    pub fn message(&self, front_end: FrontEnd) -> String {
        let mut text = match self.option {
            Some(o) => format!("{} {}", front_end.option(o), self.message),
            None => self.message.clone(),
        };
        match self.hint {
            Some(Hint::GrowRegion) => text.push_str(&format!(
                "; a vertex can move only when every face around it and around its neighbours is in the region: enlarge the region or pass {}",
                front_end.setting("grow", "2")
            )),
            Some(Hint::Setting(option, value)) => {
                text.push_str(&format!(" ({})", front_end.setting(option, value)))
            }
            None => {}
        }
        text
    }
}

impl std::fmt::Display for CommandError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message(FrontEnd::Cli))
    }
}

impl std::error::Error for CommandError {}

/// The error and its causes joined by ": ", leaving out a cause whose text
/// the message already ends with (library errors often include their
/// source in their own text).
pub fn chain_text(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !msg.ends_with(&text) {
            msg.push_str(": ");
            msg.push_str(&text);
        }
        cause = c.source();
    }
    msg
}

impl From<HighlightError> for CommandError {
    /// Every highlight error is about the input (lights, options, mesh).
    fn from(e: HighlightError) -> Self {
        match e {
            HighlightError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::bad_input(e.to_string()),
        }
    }
}

impl From<MeshError> for CommandError {
    fn from(e: MeshError) -> Self {
        CommandError::bad_input(e.to_string())
    }
}

impl From<FairError> for CommandError {
    /// A failed solve is the computation's; a region without a movable
    /// vertex says how to enlarge it; every other error is the input's.
    fn from(e: FairError) -> Self {
        match e {
            FairError::Solve(_) => CommandError::computation(chain_text(&e)),
            FairError::Cancelled(_) => CommandError::cancelled(),
            FairError::NoMovableVertex(msg) => CommandError {
                hint: Some(Hint::GrowRegion),
                ..CommandError::bad_input(msg)
            },
            e => CommandError::bad_input(e.to_string()),
        }
    }
}

impl From<SmoothError> for CommandError {
    fn from(e: SmoothError) -> Self {
        match e {
            SmoothError::Solve(_) | SmoothError::Diverged(_) => {
                CommandError::computation(chain_text(&e))
            }
            SmoothError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::bad_input(e.to_string()),
        }
    }
}

impl From<QuadFairError> for CommandError {
    fn from(e: QuadFairError) -> Self {
        match e {
            QuadFairError::Solve(_) => CommandError::computation(chain_text(&e)),
            QuadFairError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::bad_input(e.to_string()),
        }
    }
}

impl From<EnhanceError> for CommandError {
    /// A fixed vertex beyond the mesh names the valid range; a failed solve
    /// is the computation's.
    fn from(e: EnhanceError) -> Self {
        match e {
            EnhanceError::FixedVertexOutOfRange { vertex, vertices } => {
                CommandError::bad_input(format!(
                    "fixed vertex {vertex} does not exist; the mesh has {vertices} vertices (0 to {})",
                    vertices.saturating_sub(1)
                ))
            }
            e @ EnhanceError::InvalidOption(_) => CommandError::bad_input(e.to_string()),
            EnhanceError::Cancelled(_) => CommandError::cancelled(),
            e => CommandError::computation(format!("vertex flow: {}", chain_text(&e))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_without_movable_vertices_says_how_to_enlarge_it() {
        let e = CommandError::from(FairError::NoMovableVertex("the region is too thin".into()));
        assert_eq!(
            e.message(FrontEnd::Cli),
            "the region is too thin; a vertex can move only when every face around it and around its neighbours is in the region: enlarge the region or pass --grow 2"
        );
        assert!(e.message(FrontEnd::Python).ends_with("or pass grow=2"));
        assert_eq!(e.kind(), ErrorKind::BadInput);
        let other = FairError::InvalidOption("epsilon".into());
        let text = other.to_string();
        assert_eq!(CommandError::from(other).message(FrontEnd::Cli), text);
        let bad = CommandError::invalid("lambda", "must be finite");
        assert_eq!(bad.message(FrontEnd::Cli), "--lambda must be finite");
        assert_eq!(bad.message(FrontEnd::Python), "lambda_ must be finite");
    }
}
