//! The detect → fair → detect loop, end to end on the
//! command line: a panel with a known smooth truth and a planted dent.

mod common;
use common::*;

use fairline::{SurfaceMesh, Vec3};
use std::path::Path;

/// A crowned car-roof-like panel over [−1, 1]² (the smooth truth).
fn panel(x: f64, y: f64) -> f64 {
    0.3 * (1.0 - 0.45 * x * x - 0.25 * y * y) + 0.05 * x * x * x - 0.03 * x * y * y
}

/// The planted dent: 0.006 deep (0.2 % of the bounding-box diagonal),
/// Gaussian of width 0.1 (one light spacing) at (0.3, −0.2).
fn dent(x: f64, y: f64) -> f64 {
    -0.006 * (-((x - 0.3).powi(2) + (y + 0.2).powi(2)) / 0.01).exp()
}

fn write(dir: &Path, name: &str, f: impl Fn(f64, f64) -> f64) -> std::path::PathBuf {
    let m = fairline::shapes::height_field(101, 101, (-1.0, 1.0), (-1.0, 1.0), f);
    let p = dir.join(name);
    fairline::io::write_mesh(&p, &m).unwrap();
    p
}

fn bits(m: &SurfaceMesh) -> Vec<[u64; 3]> {
    m.positions()
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn detect_then_fair_then_detect_removes_a_planted_dent() {
    let d = tmp("detect-loop");
    let dented = write(&d, "dented.obj", |x, y| panel(x, y) + dent(x, y));
    let (region, rep1) = (d.join("region.json"), d.join("det1.json"));
    ok(&run(&[
        "detect",
        s(&dented),
        "-o",
        s(&region),
        "--report",
        s(&rep1),
    ]));
    let r1 = json(&rep1);
    let regions = r1["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 1, "{r1}");
    let c = &regions[0]["center"];
    let c = Vec3::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap(), 0.0);
    assert!((c - Vec3::new(0.3, -0.2, 0.0)).length() < 0.05, "{c}");
    // the region file goes to fair as it is
    let (faired, rep2) = (d.join("faired.obj"), d.join("fair.json"));
    let o = run(&[
        "fair",
        s(&dented),
        "--region",
        s(&region),
        "-o",
        s(&faired),
        "--report",
        s(&rep2),
    ]);
    ok(&o);
    let r2 = json(&rep2);
    assert_eq!(r2["converged"], true, "{r2}");
    let before = r2["detect_score_before"].as_f64().unwrap();
    let after = r2["detect_score_after"].as_f64().unwrap();
    assert!(before > 1.0 && after < 1.0, "{before} -> {after}");
    // detect again: nothing
    let (region2, rep3) = (d.join("region2.json"), d.join("det2.json"));
    ok(&run(&[
        "detect",
        s(&faired),
        "-o",
        s(&region2),
        "--report",
        s(&rep3),
    ]));
    let r3 = json(&rep3);
    assert_eq!(r3["regions"].as_array().unwrap().len(), 0, "{r3}");
    // detect is quiet on the result, and so is fair's warning
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("a defect remains"), "{err}");
    assert_eq!(r2["detect_regions_after"], 0, "{r2}");
    // inside the region the surface is ≥ 20× closer to the truth; outside
    // bit-identical
    let a = fairline::io::read_mesh(&dented).unwrap();
    let b = fairline::io::read_mesh(&faired).unwrap();
    let faces: Vec<u32> = serde_json::from_value(json(&region)["faces"].clone()).unwrap();
    let mut inside = vec![false; a.vertex_count()];
    for f in faces {
        for v in a.face_vertices(fairline::mesh::FaceId(f)) {
            inside[v.idx()] = true;
        }
    }
    let err = |m: &SurfaceMesh| -> f64 {
        m.positions()
            .iter()
            .zip(&inside)
            .filter(|(_, i)| **i)
            .map(|(p, _)| (p.z - panel(p.x, p.y)).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let (e0, e1) = (err(&a), err(&b));
    assert!(e1 * 20.0 <= e0, "distance to the truth {e0} -> {e1}");
    let (ba, bb) = (bits(&a), bits(&b));
    for (v, (x, y)) in ba.iter().zip(&bb).enumerate() {
        if !inside[v] {
            assert_eq!(x, y, "vertex {v} outside the region moved");
        }
    }
}

#[test]
fn a_region_too_small_to_move_is_refused_with_advice_and_grow_fixes_it() {
    let d = tmp("detect-grow");
    let dented = write(&d, "dented.obj", |x, y| panel(x, y) + dent(x, y));
    let region = d.join("tiny.json");
    std::fs::write(
        &region,
        r#"{"sphere":{"center":[0.3,-0.2,0.28],"radius":0.025}}"#,
    )
    .unwrap();
    let out = d.join("out.obj");
    let o = run(&["fair", s(&dented), "--region", s(&region), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--grow"), "{err}");
    assert!(!out.exists());
    ok(&run(&[
        "fair",
        s(&dented),
        "--region",
        s(&region),
        "--grow",
        "6",
        "-o",
        s(&out),
    ]));
    assert!(out.exists());
}

#[test]
fn clean_panel_has_no_region() {
    let d = tmp("detect-clean");
    let clean = write(&d, "clean.obj", panel);
    let (region, rep) = (d.join("region.json"), d.join("det.json"));
    ok(&run(&[
        "detect",
        s(&clean),
        "-o",
        s(&region),
        "--report",
        s(&rep),
    ]));
    let r = json(&rep);
    assert_eq!(r["regions"].as_array().unwrap().len(), 0, "{r}");
    assert_eq!(json(&region)["faces"].as_array().unwrap().len(), 0);
}

/// fair's "a defect remains" warning says what `detect` on the result says,
/// every site with its own threshold: fairing only the best region of a
/// panel with two dents leaves the second, weaker one, which `detect` on
/// the result flags; the warning fires, names it (outside the faired
/// region, its score and threshold) and says what to do. Before, the
/// warning compared only the best site inside the faired region with the
/// threshold there, and stayed silent.
#[test]
fn the_remaining_defect_warning_says_what_detect_on_the_result_says() {
    let d = tmp("detect-second");
    // a second dent, half as deep, at (−0.45, 0.45)
    let second =
        |x: f64, y: f64| -0.003 * (-((x + 0.45).powi(2) + (y - 0.45).powi(2)) / 0.01).exp();
    let dented = write(&d, "two-dents.obj", |x, y| {
        panel(x, y) + dent(x, y) + second(x, y)
    });
    let (region, rep1) = (d.join("region.json"), d.join("det1.json"));
    ok(&run(&[
        "detect",
        s(&dented),
        "--max-regions",
        "1",
        "-o",
        s(&region),
        "--report",
        s(&rep1),
    ]));
    let r1 = json(&rep1);
    assert_eq!(r1["regions"].as_array().unwrap().len(), 1, "{r1}");
    let (faired, rep2) = (d.join("faired.obj"), d.join("fair.json"));
    let o = run(&[
        "fair",
        s(&dented),
        "--region",
        s(&region),
        "-o",
        s(&faired),
        "--report",
        s(&rep2),
    ]);
    ok(&o);
    let r2 = json(&rep2);
    // inside the faired region detection is quiet
    let threshold = r2["detect_threshold"].as_f64().unwrap();
    assert!(
        r2["detect_score_after"].as_f64().unwrap() <= threshold,
        "{r2}"
    );
    // what detect says on the result
    let rep3 = d.join("det2.json");
    ok(&run(&[
        "detect",
        s(&faired),
        "-o",
        s(&d.join("region2.json")),
        "--report",
        s(&rep3),
    ]));
    let r3 = json(&rep3);
    let regions = r3["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 1, "the second dent remains: {r3}");
    let c = &regions[0]["center"];
    let c = Vec3::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap(), 0.0);
    assert!((c - Vec3::new(-0.45, 0.45, 0.0)).length() < 0.05, "{c}");
    // and fair's warning says the same
    assert_eq!(r2["detect_regions_after"], 1, "{r2}");
    let err = String::from_utf8_lossy(&o.stderr);
    let score = regions[0]["score"].as_f64().unwrap();
    assert!(
        err.contains(&format!(
            "a defect remains: detect on the result flags 1 region(s) (0 overlapping the faired region), the best scoring {score:.2}"
        )),
        "{err}"
    );
    assert!(err.contains("outside the faired region"), "{err}");
    let warnings: Vec<String> = serde_json::from_value(r2["warnings"].clone()).unwrap_or_default();
    assert!(
        warnings.iter().any(|w| w.contains("a defect remains")),
        "{warnings:?}"
    );
}

/// `fair --auto` on the smooth panel: detection finds nothing, which is
/// what was asked (exit status 0), and the run says so — the summary line
/// begins "nothing to fair", the report says `nothing_to_fair` and claims
/// no convergence, the picture asked for shows the input's lines and says
/// nothing was faired — and the output is the input, bit for bit. On the dented panel the same run fairs and says so.
#[test]
fn fair_auto_with_nothing_to_fair_says_so_and_claims_nothing() {
    let d = tmp("auto-nothing");
    let clean = write(&d, "clean.obj", panel);
    let (out, rep, png) = (d.join("out.obj"), d.join("r.json"), d.join("p.png"));
    let o = run(&[
        "fair",
        s(&clean),
        "--auto",
        "-o",
        s(&out),
        "--report",
        s(&rep),
        "--png",
        s(&png),
    ]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    let summary = err
        .lines()
        .find(|l| l.starts_with("fairline fair: "))
        .unwrap_or_else(|| panic!("no summary: {err}"));
    assert!(
        summary.starts_with(
            "fairline fair: nothing to fair (--auto found no defect above the detection threshold"
        ),
        "{summary}"
    );
    assert!(
        !err.contains("region(s) faired") && !err.contains("converged"),
        "{err}"
    );
    assert!(!err.contains("warning:"), "{err}");
    let r = json(&rep);
    assert_eq!(r["nothing_to_fair"], true, "{r}");
    assert_eq!(r["regions"], 0, "{r}");
    assert!(r.get("converged").is_none(), "{r}");
    let picture = std::fs::read(&png).expect("the --png asked for is written");
    assert!(picture.starts_with(b"\x89PNG"), "not a PNG");
    let (a, b) = (
        fairline::io::read_mesh(&clean).unwrap(),
        fairline::io::read_mesh(&out).unwrap(),
    );
    assert_eq!(bits(&a), bits(&b));
    // with a dent there is something to fair, and the report says so
    let dented = write(&d, "dented.obj", |x, y| panel(x, y) + dent(x, y));
    let o = run(&[
        "fair",
        s(&dented),
        "--auto",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("fairline fair: 1 region(s) faired, converged"),
        "{err}"
    );
    let r = json(&rep);
    assert_eq!(r["nothing_to_fair"], false, "{r}");
    assert_eq!(r["converged"], true, "{r}");
}
