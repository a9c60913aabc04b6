//! Reports with the keys and rules of the CLI's `--report` (README
//! "Outputs and safety"): `"command"`, `"time_s"` (computation only), the
//! command's keys, `"warnings"` when it warned; never `null` (a non-finite
//! value is left out with a warning naming it, or written as the string
//! `"not finite"` inside an array).
//!
//! This mirrors `crates/fairline-cli/src/common.rs` `Report` without its
//! printing (the Python layer turns warnings into `warnings.warn`). Once the
//! library's reports derive `Serialize` (issue #17 item 1) both can share
//! one definition in the library.

use serde_json::{Map, Value, json};
use std::time::{Duration, Instant};

pub struct Report {
    map: Map<String, Value>,
    compute: Duration,
    warnings: Vec<String>,
}

impl Report {
    pub fn new(command: &str) -> Self {
        let mut map = Map::new();
        map.insert("command".into(), json!(command));
        Report {
            map,
            compute: Duration::ZERO,
            warnings: Vec::new(),
        }
    }

    /// Sets a key; non-finite numbers are left out with a warning.
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

    /// Sets every field of `fields` (a library report) as a key.
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

    /// Records a warning (listed under `"warnings"`).
    pub fn warn(&mut self, msg: impl Into<String>) {
        self.warnings.push(msg.into());
    }

    /// Runs `f`, adding its wall time to the computation time.
    pub fn time<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.compute += t.elapsed();
        out
    }

    /// The report as JSON text.
    pub fn to_json(&self) -> String {
        let mut m = self.map.clone();
        m.insert("time_s".into(), json!(self.compute.as_secs_f64()));
        if !self.warnings.is_empty() {
            m.insert("warnings".into(), json!(self.warnings));
        }
        Value::Object(m).to_string()
    }
}

/// `value` without its `null`s (see the module documentation).
fn finite_only(path: &str, value: Value, dropped: &mut Vec<String>) -> Option<Value> {
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
