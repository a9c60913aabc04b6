//! The shared real data (`../shared/data/` beside the checkout) for tests:
//! the one helper every test that needs it goes through.
//!
//! When a file is missing, a test must not pass silently: with the
//! environment variable `CI` set (to anything but empty, `0` or `false`) the
//! helper panics, so the test fails; otherwise it prints a loud message on
//! standard error and returns `None`, and the test returns early.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::{Path, PathBuf};

/// The folder `../shared/data` beside the checkout.
pub fn shared_data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}

/// Whether the tests run under continuous integration (`CI` set).
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// `../shared/data/<rel>` when it exists; otherwise fails the test under CI
/// and says loudly that the test checked nothing elsewhere.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    let p = shared_data_dir().join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        !under_ci(),
        "{} is missing and CI is set: a test that needs ../shared/data must fail, not skip",
        p.display()
    );
    eprintln!(
        "\n********\n* SKIPPED: {} not found; this test checked NOTHING.\n* Put the shared data beside the checkout (set CI=1 to make this a failure).\n********\n",
        p.display()
    );
    None
}
