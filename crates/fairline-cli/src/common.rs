//! Shared command-line plumbing: exit codes, input errors, reports,
//! progress bars, parsing of vectors and sizes.

use anyhow::{Context, Result};
use fairline::Vec3;
use serde_json::{Map, Value, json};
use std::path::Path;
use std::time::Instant;

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

/// An error that exits with status 2.
pub fn bad_input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(BadInput(msg.into()))
}

/// Exit status for an error: 2 when any cause is bad input (our marker, a
/// file-format error, an invalid mesh, malformed JSON, a missing file), 1
/// otherwise.
pub fn exit_code(err: &anyhow::Error) -> i32 {
    for cause in err.chain() {
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

/// Parses `X,Y,Z` into a vector.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got `{s}`"));
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .parse::<f64>()
            .map_err(|_| format!("`{p}` is not a number in `{s}`"))?;
        if !v[k].is_finite() {
            return Err(format!("`{p}` is not finite in `{s}`"));
        }
    }
    Ok(Vec3::from_array(v))
}

/// Parses a comma-separated list of numbers.
pub fn parse_list(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|p| {
            let v = p
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("`{p}` is not a number"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("`{p}` is not finite"))
            }
        })
        .collect()
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in `{s}`"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in `{s}`"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "image size `{s}` must be between 1 and 16384 pixels"
        ));
    }
    Ok((w, h))
}

/// A JSON report: `"command"`, `"time_s"` (computation only), the keys
/// each command adds, and `"warnings"` when a command warned.
///
/// A report never contains `null`: a value that does not serialise to a
/// finite number (serde_json turns NaN and ±inf into `null`) is left out of
/// its object, or written as the string `"not finite"` inside an array,
/// with a `warning:` line naming the key. A command that has a value that
/// may legitimately be absent leaves the key out itself.
pub struct Report {
    map: Map<String, Value>,
    compute: std::time::Duration,
    warnings: Vec<String>,
}

impl Report {
    /// A report for `command`.
    pub fn new(command: &str) -> Self {
        let mut map = Map::new();
        map.insert("command".into(), json!(command));
        Report {
            map,
            compute: std::time::Duration::ZERO,
            warnings: Vec::new(),
        }
    }
    /// Sets a key (see the type's documentation for non-finite values).
    pub fn set(&mut self, key: &str, value: impl serde::Serialize) {
        let value = match serde_json::to_value(value) {
            Ok(v) => v,
            Err(e) => {
                self.warn(format!(
                    "report value `{key}` could not be written ({e}); left out"
                ));
                return;
            }
        };
        let mut dropped = Vec::new();
        if let Some(v) = finite_only(key, value, &mut dropped) {
            self.map.insert(key.into(), v);
        }
        for path in dropped {
            self.warn(format!(
                "report value `{path}` is not a finite number; left out of the report"
            ));
        }
    }

    /// Sets every field of `fields` (a struct that serialises to an object,
    /// e.g. a library report) as a key, like [`Report::set`].
    pub fn set_fields(&mut self, fields: impl serde::Serialize) {
        match serde_json::to_value(fields) {
            Ok(Value::Object(map)) => {
                for (key, value) in map {
                    self.set(&key, value);
                }
            }
            Ok(other) => self.set("value", other),
            Err(e) => self.warn(format!("report could not be written ({e})")),
        }
    }
    /// Prints `warning: MSG` on standard error and records it under
    /// `"warnings"` in the report.
    pub fn warn(&mut self, msg: impl Into<String>) {
        let msg = msg.into();
        crate::output::warn(&msg);
        self.warnings.push(msg);
    }
    /// Runs `f`, adding its wall time to the computation time.
    pub fn time<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.compute += t.elapsed();
        out
    }
    /// The report as JSON.
    pub fn to_json(&self) -> Value {
        let mut m = self.map.clone();
        m.insert("time_s".into(), json!(self.compute.as_secs_f64()));
        if !self.warnings.is_empty() {
            m.insert("warnings".into(), json!(self.warnings));
        }
        Value::Object(m)
    }
    /// Writes the report atomically when a path was given.
    pub fn write(&self, path: Option<&Path>) -> Result<()> {
        if let Some(p) = path {
            write_json(p, &self.to_json())?;
        }
        Ok(())
    }
}

/// `value` without its `null`s: dropped from objects, replaced by the
/// string `"not finite"` in arrays; the path of each (`key.sub[3]`) is
/// pushed to `dropped`. `None` when `value` itself is `null`.
pub fn finite_only(path: &str, value: Value, dropped: &mut Vec<String>) -> Option<Value> {
    match value {
        Value::Null => {
            dropped.push(path.to_string());
            None
        }
        Value::Object(m) => Some(Value::Object(
            m.into_iter()
                .filter_map(|(k, v)| {
                    let sub = format!("{path}.{k}");
                    finite_only(&sub, v, dropped).map(|v| (k, v))
                })
                .collect(),
        )),
        Value::Array(a) => Some(Value::Array(
            a.into_iter()
                .enumerate()
                .map(|(i, v)| {
                    let sub = format!("{path}[{i}]");
                    finite_only(&sub, v, dropped).unwrap_or_else(|| json!("not finite"))
                })
                .collect(),
        )),
        other => Some(other),
    }
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
    let text =
        std::fs::read_to_string(path).map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| bad_input(format!("{}: {e}", path.display())))
}

/// Refuses to write `output` over `input`: the policy of
/// [`crate::output::Job`] for a command with one input and one output
/// (prefer declaring every input and output on a `Job`). Kept for commands
/// written against the older helper.
#[allow(dead_code)]
pub fn check_output(input: &Path, output: &Path) -> Result<()> {
    crate::output::Job::new("fairline")
        .input(input)
        .output("output", output)
        .check()?;
    Ok(())
}

pub use crate::output::{progress, spinner};
