//! Helpers shared by the command-line tests: run the `fairline` binary, a
//! fresh temporary directory per test, the shared real data, JSON reports.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `fairline` binary built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fairline"))
}

/// Runs `fairline` with `args` and returns its status and output.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run fairline")
}

/// A fresh, empty temporary directory unique to this test process and
/// `name`.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fairline-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[path = "../../../fairline/tests/support/shared_data.rs"]
mod shared_data;

/// A file of the shared real data (`../shared/data/` beside the checkout);
/// when it is missing the test fails under CI and says loudly that it
/// checked nothing otherwise (see `shared_data.rs`).
pub fn data(rel: &str) -> Option<PathBuf> {
    shared_data::shared_data(rel)
}

/// The JSON document in `path`.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Asserts that the command succeeded, showing its standard error if not.
pub fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "status {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `p` as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
