//! Command-line tests of `fairline continuity`: a constructed pair of
//! patches with a known kink, bad input, and the real teapot.

mod common;
use common::*;

use fairline::Vec3;
use fairline::bspline::BSplineSurface;
use fairline::io::write_surfaces_json;

/// A plane z = 0 Bézier patch over [x0, x0 + 1] × [0, 1] whose row next to
/// u = 0 is lifted by `lift` (a kink of atan(3 lift) at that side).
fn patch(x0: f64, lift: f64) -> BSplineSurface {
    let net = (0..4)
        .map(|i| {
            (0..4)
                .map(|j| {
                    let z = if i == 1 { lift } else { 0.0 };
                    Vec3::new(x0 + i as f64 / 3.0, j as f64 / 3.0, z)
                })
                .collect()
        })
        .collect();
    BSplineSurface::bezier(net, None).unwrap()
}

#[test]
fn continuity_cli_reports_a_known_kink() {
    let dir = tmp("continuity-kink");
    let input = dir.join("pair.json");
    write_surfaces_json(&input, &[patch(0.0, 0.0), patch(1.0, 0.01)]).unwrap();
    let (rep, png) = (dir.join("r.json"), dir.join("c.png"));
    let o = run(&[
        "continuity",
        s(&input),
        "--report",
        s(&rep),
        "--png",
        s(&png),
    ]);
    ok(&o);
    let r = json(&rep);
    assert_eq!(r["command"], "continuity");
    assert!(r["time_s"].as_f64().unwrap() >= 0.0);
    let edges = r["edges"].as_array().unwrap();
    assert_eq!(edges.len(), 1);
    let e = &edges[0];
    assert_eq!(e["surfaces"], serde_json::json!([0, 1]));
    assert_eq!(e["class"], "G0");
    let want = (0.03f64).atan().to_degrees();
    assert!((e["g1_max_deg"].as_f64().unwrap() - want).abs() < 1e-9);
    assert!(e["g0_max"].as_f64().unwrap() < 1e-12);
    assert!(e["g2_max"].as_f64().unwrap().is_finite());
    let worst = e["worst"].as_array().unwrap();
    assert_eq!(worst.len(), 3);
    assert!(
        (worst[0].as_f64().unwrap() - 1.0).abs() < 1e-12,
        "the worst point is on the seam x = 1"
    );
    assert_eq!(r["classes"]["G0"], 1);
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // A looser angle tolerance: G1 (B bends back to z = 0 across the seam,
    // A is flat: the curvature differs, so not G2).
    let o = run(&[
        "continuity",
        s(&input),
        "--angle-tolerance",
        "5",
        "--report",
        s(&rep),
    ]);
    ok(&o);
    assert_eq!(json(&rep)["edges"][0]["class"], "G1");
}

#[test]
fn continuity_cli_bad_input_exits_2() {
    let dir = tmp("continuity-bad");
    let o = run(&["continuity", s(&dir.join("missing.json"))]);
    assert_eq!(o.status.code(), Some(2));
    let input = dir.join("one.json");
    write_surfaces_json(&input, &[patch(0.0, 0.0)]).unwrap();
    let o = run(&["continuity", s(&input), "--tolerance", "-1"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&["continuity", s(&input), "--png", s(&dir.join("x.jpg"))]);
    assert_eq!(o.status.code(), Some(2));
}

/// The shared data file, or a failure under CI (a loud skip otherwise).
fn required(rel: &str) -> Option<std::path::PathBuf> {
    let p = data(rel);
    if p.is_none() && std::env::var_os("CI").is_some() {
        panic!("../shared/data/{rel} is missing and CI is set");
    }
    p
}

#[test]
fn continuity_cli_teapot_seams() {
    let Some(teapot) = required("surfaces/teapot.json") else {
        return;
    };
    let dir = tmp("continuity-teapot");
    let (rep, png) = (dir.join("r.json"), dir.join("c.png"));
    let o = run(&[
        "continuity",
        s(&teapot),
        "--report",
        s(&rep),
        "--png",
        s(&png),
    ]);
    ok(&o);
    eprintln!("{}", String::from_utf8_lossy(&o.stderr));
    let r = json(&rep);
    let edges = r["edges"].as_array().unwrap();
    eprintln!("{}", serde_json::to_string(&r["classes"]).unwrap());
    // The body, lid, rim and bottom are surfaces of revolution cut into
    // quadrant patches that join smoothly: dozens of G1 / G2 seams.
    let smooth = edges
        .iter()
        .filter(|e| e["class"] == "G1" || e["class"] == "G2")
        .count();
    assert!(smooth >= 30, "{smooth} smooth seams");
    let c = &r["classes"];
    let total: u64 = ["gap", "G0", "G1", "G2"]
        .iter()
        .map(|k| c[*k].as_u64().unwrap())
        .sum();
    assert_eq!(total as usize, edges.len());
    let matching = r["match_distance"].as_f64().unwrap();
    for e in edges {
        assert!(e["g0_max"].as_f64().unwrap() <= matching * (1.0 + 1e-9));
        assert!(
            e["worst"]
                .as_array()
                .unwrap()
                .iter()
                .all(|x| x.as_f64().unwrap().is_finite())
        );
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}
