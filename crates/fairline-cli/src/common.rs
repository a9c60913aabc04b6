//! JSON files of the commands: the `--report` of every command and the
//! reading and writing of JSON inputs and outputs.

use crate::error::bad_input;
use anyhow::{Context, Result};
use serde_json::{Map, Value, json};
use std::path::Path;
use std::time::Instant;

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
