//! Shared command-line plumbing: exit codes, input errors, reports,
//! progress bars, parsing of vectors and sizes.

use anyhow::{Context, Result};
use fairline::Vec3;
use serde_json::{Map, Value, json};
use std::io::IsTerminal;
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
            || cause.is::<fairline::bspline::SurfaceJsonError>()
            || cause.is::<fairline::bspline::IgesError>()
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

/// A JSON report: `"command"`, `"time_s"` (computation only) and the keys
/// each command adds.
pub struct Report {
    map: Map<String, Value>,
    compute: std::time::Duration,
}

impl Report {
    /// A report for `command`.
    pub fn new(command: &str) -> Self {
        let mut map = Map::new();
        map.insert("command".into(), json!(command));
        Report {
            map,
            compute: std::time::Duration::ZERO,
        }
    }
    /// Sets a key.
    pub fn set(&mut self, key: &str, value: impl serde::Serialize) {
        self.map.insert(
            key.into(),
            serde_json::to_value(value).unwrap_or(Value::Null),
        );
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

/// Refuses to write `output` over `input`.
pub fn check_output(input: &Path, output: &Path) -> Result<()> {
    fairline::io::ensure_distinct(input, output)?;
    Ok(())
}

/// A progress bar on stderr when stderr is a terminal; hidden otherwise.
pub fn progress(len: u64, message: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg:<24} [{bar:32}] {pos}/{len} ({elapsed})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(message.to_string());
    bar
}

/// A spinner for work of unknown length; hidden when not on a terminal.
pub fn spinner(message: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}
