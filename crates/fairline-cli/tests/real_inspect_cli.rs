//! Inspection with no options on the real meshes of ../shared/data (issue
//! #18): `highlight` draws readable lines without a fragment warning,
//! `detect` explains what it leaves as shape, and `fair`'s report measures
//! what `detect` shows, with detect's own threshold.

mod common;
use common::{data, json, ok, run, s, tmp};

/// `highlight` with no light options on every clean real mesh: lines drawn,
/// no "fragmented" or "no line" warning, and the report's drawn lines hold
/// half of their length in pieces at least 0.15 of the part's width long.
#[test]
fn highlight_defaults_on_real_meshes_draw_readable_lines_without_warning() {
    let dir = tmp("real-highlight");
    for rel in [
        "meshes/spot.ply",
        "meshes/bunny_npm.obj",
        "meshes/bob_small.ply",
        "meshes/lego_open.ply",
    ] {
        let Some(mesh) = data(rel) else { return };
        let out = dir.join("lines.json");
        let png = dir.join("lines.png");
        let rep = dir.join("report.json");
        let o = run(&[
            "highlight",
            s(&mesh),
            "-o",
            s(&out),
            "--png",
            s(&png),
            "--size",
            "400x300",
            "--report",
            s(&rep),
        ]);
        ok(&o);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("warning"), "{rel}: {err}");
        let r = json(&rep);
        let drawn = &r["drawn"];
        assert!(drawn["lights"].as_u64().unwrap() >= 6, "{rel}: {drawn}");
        assert!(
            drawn["n50_length_over_width"].as_f64().unwrap() >= 0.15,
            "{rel}: {drawn}"
        );
        let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
        assert_eq!((img.width, img.height), (400, 300), "{rel}");
    }
}

/// `detect` on Spot: the ears, horns and legs are counted as shape finer
/// than the measure's scale and said so on the terminal and in the report.
#[test]
fn detect_on_spot_reports_small_features_as_shape() {
    let Some(mesh) = data("meshes/spot.ply") else {
        return;
    };
    let dir = tmp("real-detect");
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
    let shape = r["shape_sites"].as_u64().unwrap();
    assert!(shape > 0, "{r}");
    assert!(
        err.contains("shape finer than the measure's scale"),
        "{err}"
    );
    assert!(
        shape + r["judged_sites"].as_u64().unwrap() <= r["sites"].as_u64().unwrap(),
        "{r}"
    );
}

/// `fair --auto` on a real scan: the report's detection scores are measured
/// as `detect` measures them (same lights, and `detect`'s threshold for
/// this mesh, raised above the scan's noise), the score inside the regions
/// goes down, and when the highlight deviation (a different quantity) rises
/// the warning names the detection score beside it.
#[test]
fn fair_report_on_a_real_scan_measures_what_detect_shows() {
    let Some(mesh) = data("meshes/spot.ply") else {
        return;
    };
    let dir = tmp("real-fair");
    let det = dir.join("detect.json");
    ok(&run(&[
        "detect",
        s(&mesh),
        "-o",
        s(&dir.join("region.json")),
        "--report",
        s(&det),
    ]));
    let rep = dir.join("fair.json");
    let o = run(&[
        "fair",
        s(&mesh),
        "--auto",
        "-o",
        s(&dir.join("faired.obj")),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let d = json(&det);
    let f = json(&rep);
    assert_eq!(f["light"], d["light"], "same lights as detect");
    assert_eq!(f["detect_threshold"], d["threshold"], "detect's threshold");
    let (before, after) = (
        f["detect_score_before"].as_f64().unwrap(),
        f["detect_score_after"].as_f64().unwrap(),
    );
    assert!(
        (before - d["regions"][0]["score"].as_f64().unwrap()).abs() < 1e-9,
        "the score before is detect's best region score: {before} vs {}",
        d["regions"][0]["score"]
    );
    assert!(after < before, "{before} -> {after}");
    let err = String::from_utf8_lossy(&o.stderr);
    if f["highlight_deviation_after"].as_f64() > f["highlight_deviation_before"].as_f64() {
        assert!(err.contains("the detection score"), "{err}");
    }
    assert!(
        err.contains(&format!("detection score {before:.2} → {after:.2}")),
        "{err}"
    );
}
