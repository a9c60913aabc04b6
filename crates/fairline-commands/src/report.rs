//! The JSON report of a command: the `--report` file of the CLI, the
//! report dictionary of the Python package and the report panel of the
//! workbench, one definition for all three.
//!
//! A report holds `"command"`, `"time_s"` (computation only), the keys the
//! command adds (often every field of an algorithm's `Serialize` report,
//! [`Report::set_fields`]) and `"warnings"` when the command warned. It
//! never holds `null`: a value that does not serialise to a finite number
//! (serde_json turns NaN and ±inf into `null`) is left out of its object,
//! or written as the string `"not finite"` inside an array, with a warning
//! naming the key. The warnings are structured values ([`Warning`]); the
//! JSON lists them worded with the CLI's option names, the same document in
//! every front end, and a front end shows them its own way
//! ([`Warning::message`]).

use crate::warning::{FrontEnd, Warning};
use serde_json::{Map, Value, json};
use std::time::{Duration, Instant};

/// A command's JSON report under construction; see the module documentation.
#[derive(Clone, Debug)]
pub struct Report {
    map: Map<String, Value>,
    compute: Duration,
    warnings: Vec<Warning>,
}

impl Report {
    /// A report for `command`.
    pub fn new(command: &str) -> Self {
        let mut map = Map::new();
        map.insert("command".into(), json!(command));
        Report {
            map,
            compute: Duration::ZERO,
            warnings: Vec::new(),
        }
    }

    /// Sets a key (non-finite numbers are left out with a warning).
    pub fn set(&mut self, key: &str, value: impl serde::Serialize) {
        let value = match serde_json::to_value(value) {
            Ok(v) => v,
            Err(e) => {
                self.warn(Warning::ReportValueUnwritable {
                    key: key.into(),
                    error: e.to_string(),
                });
                return;
            }
        };
        self.insert(key, value);
    }

    /// Sets `key` to `value` without its non-finite numbers (in place).
    fn insert(&mut self, key: &str, mut value: Value) {
        let mut dropped = Vec::new();
        if prune(&mut key.to_string(), &mut value, &mut dropped) {
            self.map.insert(key.into(), value);
        }
        for path in dropped {
            self.warn(Warning::NotFinite { key: path });
        }
    }

    /// Sets every field of `fields` (a struct that serialises to an object,
    /// e.g. a library report) as a key, like [`Report::set`].
    pub fn set_fields(&mut self, fields: impl serde::Serialize) {
        match serde_json::to_value(fields) {
            Ok(Value::Object(map)) => {
                for (key, value) in map {
                    self.insert(&key, value);
                }
            }
            Ok(other) => self.set("value", other),
            Err(e) => self.warn(Warning::ReportUnwritable {
                error: e.to_string(),
            }),
        }
    }

    /// Records a warning (listed under `"warnings"`).
    pub fn warn(&mut self, warning: Warning) {
        self.warnings.push(warning);
    }

    /// The warnings so far, oldest first.
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The warnings worded for `front_end`, oldest first.
    pub fn messages(&self, front_end: FrontEnd) -> Vec<String> {
        self.warnings.iter().map(|w| w.message(front_end)).collect()
    }

    /// Adds `seconds` to the computation time (work timed elsewhere).
    pub fn add_time(&mut self, seconds: f64) {
        if seconds.is_finite() && seconds > 0.0 {
            self.compute += Duration::from_secs_f64(seconds);
        }
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
            m.insert("warnings".into(), json!(self.messages(FrontEnd::Cli)));
        }
        Value::Object(m)
    }
}

impl Report {
    /// Writes [`JsonReport::to_json`] as pretty JSON into `w` without
    /// copying the report (a repair report lists millions of faces); the
    /// same text as `serde_json::to_writer_pretty(w, &self.to_json())`.
    pub fn write_pretty(&self, w: impl std::io::Write) -> serde_json::Result<()> {
        serde_json::to_writer_pretty(w, &Whole(self))
    }
}

/// A [`JsonReport`] serialised as [`JsonReport::to_json`] would be.
struct Whole<'a>(&'a Report);

impl serde::Serialize for Whole<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let r = self.0;
        let time = json!(r.compute.as_secs_f64());
        let warnings = json!(r.messages(FrontEnd::Cli));
        let mut entries: Vec<(&str, &Value)> = r
            .map
            .iter()
            .filter(|(k, _)| k.as_str() != "time_s" && k.as_str() != "warnings")
            .map(|(k, v)| (k.as_str(), v))
            .collect();
        entries.push(("time_s", &time));
        if !r.warnings.is_empty() {
            entries.push(("warnings", &warnings));
        }
        // the key order of the map (`to_json`'s)
        entries.sort_by(|a, b| a.0.cmp(b.0));
        let mut m = s.serialize_map(Some(entries.len()))?;
        for (k, v) in entries {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// `value` without its `null`s: dropped from objects, replaced by the
/// string `"not finite"` in arrays; the path of each (`key.sub[3]`) is
/// pushed to `dropped`. `None` when `value` itself is `null`.
pub fn finite_only(path: &str, mut value: Value, dropped: &mut Vec<String>) -> Option<Value> {
    prune(&mut path.to_string(), &mut value, dropped).then_some(value)
}

/// [`finite_only`] in place (no copy of a large report): whether `value`
/// is kept; `path` is the path of `value` and is restored on return.
fn prune(path: &mut String, value: &mut Value, dropped: &mut Vec<String>) -> bool {
    use std::fmt::Write;
    match value {
        Value::Null => {
            dropped.push(path.clone());
            false
        }
        Value::Object(m) => {
            m.retain(|k, v| {
                let len = path.len();
                path.push('.');
                path.push_str(k);
                let keep = prune(path, v, dropped);
                path.truncate(len);
                keep
            });
            true
        }
        Value::Array(a) => {
            for (i, v) in a.iter_mut().enumerate() {
                let len = path.len();
                let _ = write!(path, "[{i}]");
                if !prune(path, v, dropped) {
                    *v = json!("not finite");
                }
                path.truncate(len);
            }
            true
        }
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_are_left_out_with_a_warning_naming_them() {
        let mut r = Report::new("smooth");
        r.set("iterations", 3);
        r.set("bad", f64::NAN);
        r.set("nested", json!({"a": 1.0, "b": null, "c": [1.0, null]}));
        #[derive(serde::Serialize)]
        struct Fields {
            energy: f64,
            inf: f64,
        }
        r.set_fields(Fields {
            energy: 0.5,
            inf: f64::INFINITY,
        });
        let j = r.to_json();
        assert_eq!(j["command"], "smooth");
        assert_eq!(j["iterations"], 3);
        assert!(j.get("bad").is_none());
        assert_eq!(j["nested"], json!({"a": 1.0, "c": [1.0, "not finite"]}));
        assert_eq!(j["energy"], 0.5);
        assert!(j.get("inf").is_none());
        assert!(j["time_s"].as_f64().is_some_and(|t| t >= 0.0));
        let w = r.messages(FrontEnd::Cli);
        assert_eq!(w.len(), 4, "{w:?}");
        assert!(w[0].contains("`bad`"));
        assert!(w[1].contains("`nested.b`"));
        assert!(w[2].contains("`nested.c[1]`"));
        assert!(w[3].contains("`inf`"));
        assert_eq!(j["warnings"].as_array().map(Vec::len), Some(4));
        assert!(!j.to_string().contains("null"));
        let mut streamed = Vec::new();
        r.write_pretty(&mut streamed).unwrap();
        assert_eq!(
            String::from_utf8(streamed).unwrap(),
            serde_json::to_string_pretty(&j).unwrap()
        );
    }
}
