//! JSON files of the commands: the `--report` of every command and the
//! reading and writing of JSON inputs and outputs.

use crate::error::bad_input;
use anyhow::{Context, Result};
use fairline_commands::{FrontEnd, Warning};
use serde_json::Value;
use std::path::Path;

/// A command's JSON report ([`fairline_commands::Report`]: `"command"`,
/// `"time_s"` of the computation only, the command's keys, `"warnings"`;
/// never `null`), whose warnings are also printed as `warning:` lines on
/// standard error when they arise. For the commands not yet run by the
/// command layer.
pub struct Report(fairline_commands::Report);

impl Report {
    /// A report for `command`.
    pub fn new(command: &str) -> Self {
        Report(fairline_commands::Report::new(command))
    }
    /// Prints the warnings recorded since there were `before`.
    fn print_since(&self, before: usize) {
        for w in &self.0.warnings()[before..] {
            crate::output::warn(w.message(FrontEnd::Cli));
        }
    }
    /// Sets a key (a non-finite value is left out with a warning).
    pub fn set(&mut self, key: &str, value: impl serde::Serialize) {
        let before = self.0.warnings().len();
        self.0.set(key, value);
        self.print_since(before);
    }
    /// Prints `warning: MSG` on standard error and records it under
    /// `"warnings"` in the report.
    pub fn warn(&mut self, msg: impl Into<String>) {
        let before = self.0.warnings().len();
        self.0.warn(Warning::Text(msg.into()));
        self.print_since(before);
    }
    /// Runs `f`, adding its wall time to the computation time.
    pub fn time<T>(&mut self, f: impl FnOnce() -> T) -> T {
        self.0.time(f)
    }
    /// The report as JSON.
    pub fn to_json(&self) -> Value {
        self.0.to_json()
    }
    /// Writes the report atomically when a path was given.
    pub fn write(&self, path: Option<&Path>) -> Result<()> {
        write_report(path, &self.0)
    }
}

/// Prints the warnings of a command's report as `warning:` lines.
pub fn print_warnings(report: &fairline_commands::Report) {
    for w in report.messages(FrontEnd::Cli) {
        crate::output::warn(w);
    }
}

/// Writes a command's report atomically when a path was given.
pub fn write_report(path: Option<&Path>, report: &fairline_commands::Report) -> Result<()> {
    if let Some(p) = path {
        // streamed: no copy of the report, no text of it in memory
        fairline::io::atomic_write(p, |w| {
            use std::io::Write;
            report
                .write_pretty(&mut *w)
                .map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })
        .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// Writes pretty JSON atomically.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    fairline::io::atomic_write(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Reads and parses a JSON file; errors name the file (and exit with 2).
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = fairline::io::read_input_file(path, fairline::io::MAX_INPUT_FILE_BYTES)
        .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
    serde_json::from_slice(&bytes).map_err(|e| bad_input(format!("{}: {e}", path.display())))
}
