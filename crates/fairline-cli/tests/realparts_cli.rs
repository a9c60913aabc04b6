//! What `detect` says where it could not judge, and `render --range`, on
//! the real meshes of ../shared/data.

mod common;
use common::{data, json, ok, run, s, tmp};

/// `detect` on Spot (whose ears, horns and legs turn faster than the
/// measure's scale on this coarse mesh): the one-line summary begins with
/// the share of the part not judged, the report has it as a number and as
/// a warning, and the picture's title says it too (not tested here: pixels).
#[test]
fn detect_summary_leads_with_what_was_not_judged() {
    let Some(mesh) = data("meshes/spot.ply") else {
        return;
    };
    let dir = tmp("realparts-detect");
    let rep = dir.join("detect.json");
    let o = run(&[
        "detect",
        s(&mesh),
        "-o",
        s(&dir.join("region.json")),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    let r = json(&rep);
    let share = r["not_judged_fraction"].as_f64().unwrap();
    assert!(share > 0.005 && share < 1.0, "{r}");
    let summary = err
        .lines()
        .find(|l| l.starts_with("fairline detect: "))
        .unwrap_or_else(|| panic!("{err}"));
    let lead = format!(
        "fairline detect: not judged: {:.0} % of the part; ",
        100.0 * share
    );
    assert!(summary.starts_with(&lead), "{summary}");
    let warnings = r["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains("not judged: "))),
        "{r}"
    );
    assert!(
        r["spacings"].as_array().is_some_and(|a| !a.is_empty()),
        "{r}"
    );
}

/// `render --range` sets the curvature map's range; without `--scalar` it
/// is refused with exit status 2 and nothing written.
#[test]
fn render_range_needs_a_scalar_and_is_used() {
    let Some(mesh) = data("meshes/bob_small.ply") else {
        return;
    };
    let dir = tmp("realparts-render");
    let png = dir.join("mean.png");
    let o = run(&["render", s(&mesh), "--png", s(&png), "--range", "-2,2"]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(!png.exists());
    let o = run(&[
        "render",
        s(&mesh),
        "--png",
        s(&png),
        "--scalar",
        "mean",
        "--range",
        "-2,2",
        "--size",
        "320x240",
    ]);
    ok(&o);
    assert!(png.exists());
    let o = run(&[
        "render",
        s(&mesh),
        "--png",
        s(&png),
        "--scalar",
        "mean",
        "--range",
        "2,-2",
    ]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
}
