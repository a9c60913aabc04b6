//! Command-line tests of `fairline highlight` and `fairline detect`.

mod common;
use common::*;

use std::fmt::Write as _;
use std::path::Path;

/// An n×n triangulated height field over [-2,2]² as OBJ text.
fn height_field_obj(n: usize, z: impl Fn(f64, f64) -> f64) -> String {
    let mut s = String::new();
    for j in 0..n {
        for i in 0..n {
            let x = -2.0 + 4.0 * i as f64 / (n - 1) as f64;
            let y = -2.0 + 4.0 * j as f64 / (n - 1) as f64;
            writeln!(s, "v {x} {y} {}", z(x, y)).unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = 1 + i + n * j;
            let (b, c, d) = (a + 1, a + 1 + n, a + n);
            writeln!(s, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
    s
}

#[test]
fn help_has_examples() {
    for cmd in ["highlight", "detect"] {
        let o = run(&[cmd, "--help"]);
        ok(&o);
        assert!(
            String::from_utf8_lossy(&o.stdout).contains("Example"),
            "{cmd}"
        );
    }
}

#[test]
fn plane_lines_at_known_positions_in_json_and_obj() {
    let d = tmp("plane");
    let mesh = d.join("plane.obj");
    std::fs::write(&mesh, height_field_obj(21, |_, _| 0.0)).unwrap();
    let out = d.join("lines.json");
    let rep = d.join("r.json");
    let lights = d.join("lights.json");
    std::fs::write(
        &lights,
        r#"{"plane_point":[0,0,3],"plane_normal":[0,0,1],"direction":[1,0,0],"spacing":0.5}"#,
    )
    .unwrap();
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--direction",
        "1,0,0",
        "--plane-normal",
        "0,0,1",
        "--plane-point",
        "0,0,3",
        "--spacing",
        "0.5",
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    ok(&o);
    let v = json(&out);
    let lines = v["lines"].as_array().unwrap();
    assert_eq!(lines.len(), 9, "lines at y = -2, -1.5, .., 2");
    for l in lines {
        let m = l["index"].as_i64().unwrap();
        assert_eq!(l["closed"], false);
        for p in l["points"].as_array().unwrap() {
            assert!((p[1].as_f64().unwrap() - 0.5 * m as f64).abs() < 1e-12);
        }
    }
    let r = json(&rep);
    assert_eq!(r["command"], "highlight");
    let png = d.join("lines.png");
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--lights",
        lights.to_str().unwrap(),
        "-o",
        d.join("l3.json").to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).is_ok());
    assert!(r["time_s"].as_f64().unwrap() >= 0.0);
    assert_eq!(r["lines"], 9);
    // OBJ output: one `l` per line
    let obj = d.join("lines.obj");
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--spacing",
        "0.5",
        "--plane-point",
        "0,0,3",
        "-o",
        obj.to_str().unwrap(),
    ]);
    ok(&o);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.lines().filter(|l| l.starts_with("l ")).count() >= 8);
    // same light from a file gives byte-identical output
    let out2 = d.join("lines2.json");
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--lights",
        lights.to_str().unwrap(),
        "-o",
        out2.to_str().unwrap(),
    ]);
    ok(&o);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&out2).unwrap());
}

#[test]
fn circular_lines_and_bands() {
    let d = tmp("circle");
    let mesh = d.join("plane.obj");
    std::fs::write(&mesh, height_field_obj(61, |_, _| 0.0)).unwrap();
    let out = d.join("c.json");
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--circle-center",
        "0,0,2",
        "--circle-axis",
        "0,0,1",
        "--radii",
        "0.5,1",
        "--band",
        "0.1",
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let v = json(&out);
    let lines = v["lines"].as_array().unwrap();
    assert_eq!(lines.len(), 2);
    for l in lines {
        assert_eq!(l["closed"], true);
        let r = l["radius"].as_f64().unwrap();
        for p in l["points"].as_array().unwrap() {
            let rr = p[0].as_f64().unwrap().hypot(p[1].as_f64().unwrap());
            assert!((rr - r).abs() < 5e-3, "{rr} vs {r}");
        }
    }
    assert_eq!(v["bands"]["radius"], 0.1);
    assert_eq!(v["bands"]["lower"].as_array().unwrap().len(), 2);
    assert_eq!(v["bands"]["upper"].as_array().unwrap().len(), 2);
}

#[test]
fn bad_input_exits_with_2_and_writes_nothing() {
    let d = tmp("bad");
    let mesh = d.join("plane.obj");
    std::fs::write(&mesh, height_field_obj(5, |_, _| 0.0)).unwrap();
    let out = d.join("x.json");
    let m = mesh.to_str().unwrap();
    let o_s = out.to_str().unwrap();
    for args in [
        vec!["highlight", m, "--spacing", "0", "-o", o_s],
        vec!["highlight", m, "--direction", "0,0,1", "-o", o_s],
        vec!["highlight", m, "-o", d.join("x.txt").to_str().unwrap()],
        vec![
            "highlight",
            d.join("missing.obj").to_str().unwrap(),
            "-o",
            o_s,
        ],
        vec!["highlight", m, "--circle-center", "0,0,1", "-o", o_s],
        vec![
            "highlight",
            m,
            "--circle-center",
            "0,0,1",
            "--circle-axis",
            "0,0,1",
            "--radii",
            "-1",
            "-o",
            o_s,
        ],
        vec!["highlight", m, "--band", "-2", "-o", o_s],
        vec!["highlight", m, "--curve-tolerance", "0.1", "-o", o_s],
        vec![
            "highlight",
            m,
            "--curve-tolerance",
            "-1",
            "-o",
            d.join("x.igs").to_str().unwrap(),
        ],
        vec!["detect", m, "-o", d.join("r.obj").to_str().unwrap()],
        vec!["detect", m, "--threshold", "0", "-o", o_s],
        vec![
            "detect",
            m,
            "-o",
            o_s,
            "--png",
            d.join("p.jpg").to_str().unwrap(),
        ],
        vec![
            "highlight",
            m,
            "-o",
            o_s,
            "--png",
            d.join("p.png").to_str().unwrap(),
            "--view",
            "0,0,0",
        ],
    ] {
        let o = run(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!out.exists(), "{args:?} wrote output");
        assert!(!d.join("x.igs").exists(), "{args:?} wrote output");
    }
    // never overwrites the input
    let o = run(&["highlight", m, "-o", m]);
    assert_ne!(o.status.code(), Some(0));
    assert!(std::fs::read_to_string(&mesh).unwrap().starts_with("v "));
}

#[test]
fn detect_finds_the_bump_and_not_a_clean_field() {
    let d = tmp("detect");
    let base = |x: f64, y: f64| 0.15 * (1.3 * x).sin() * (0.9 * y).cos();
    let (cx, cy, sg) = (0.4, -0.3, 0.12);
    let bump = move |x: f64, y: f64| {
        base(x, y) + 0.01 * (-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (sg * sg)).exp()
    };
    for (name, has_bump) in [("bump", true), ("clean", false)] {
        let mesh = d.join(format!("{name}.obj"));
        let text = if has_bump {
            height_field_obj(161, bump)
        } else {
            height_field_obj(161, base)
        };
        std::fs::write(&mesh, text).unwrap();
        let out = d.join(format!("{name}-region.json"));
        let rep = d.join(format!("{name}-report.json"));
        let png = d.join(format!("{name}.png"));
        let o = run(&[
            "detect",
            mesh.to_str().unwrap(),
            "--spacing",
            "0.1",
            "-o",
            out.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
            "--png",
            png.to_str().unwrap(),
        ]);
        ok(&o);
        // the picture shows dark lines, and red stretches only with the bump
        let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
        let dark = img
            .pixels
            .iter()
            .filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 90)
            .count();
        let red = img
            .pixels
            .iter()
            .filter(|p| p[0] > 200 && p[1] < 110 && p[2] < 80)
            .count();
        assert!(dark > 1000, "{name}: {dark} dark pixels");
        assert_eq!(red > 50, has_bump, "{name}: {red} red pixels");
        let faces = json(&out)["faces"].as_array().unwrap().len();
        let r = json(&rep);
        assert_eq!(r["command"], "detect");
        assert!(r["time_s"].is_number());
        let regions = r["regions"].as_array().unwrap();
        if has_bump {
            assert!(faces > 0 && !regions.is_empty());
            let c = &regions[0]["center"];
            let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
            assert!((x - cx).hypot(y - cy) < 2.0 * sg, "centre {c}");
            assert!(regions[0]["score"].as_f64().unwrap() > 0.0);
        } else {
            assert_eq!(faces, 0, "clean field flagged: {regions:?}");
        }
    }
}

#[test]
fn real_meshes() {
    for rel in [
        "meshes/bunny_npm.obj",
        "meshes/spot.ply",
        "meshes/bunny_zipper.ply",
        "meshes/bob_small.ply",
    ] {
        let Some(mesh) = data(rel) else { return };
        let d = tmp(&rel.replace('/', "-"));
        let out = d.join("lines.json");
        let o = run(&[
            "highlight",
            mesh.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        ok(&o);
        assert!(!json(&out)["lines"].as_array().unwrap().is_empty());
        let reg = d.join("region.json");
        let rep = d.join("r.json");
        let o = run(&[
            "detect",
            mesh.to_str().unwrap(),
            "-o",
            reg.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        ok(&o);
        assert!(json(&reg)["faces"].is_array());
        assert!(json(&rep)["regions"].is_array());
    }
}

/// Counts near-black line pixels and warning-red pixels of a picture.
fn dark_and_red(png: &Path) -> (usize, usize) {
    let img = fairline::render::Image::decode_png(&std::fs::read(png).unwrap()).unwrap();
    let dark = img
        .pixels
        .iter()
        .filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 90)
        .count();
    let red = img
        .pixels
        .iter()
        .filter(|p| p[0] > 200 && p[1] < 110 && p[2] < 80)
        .count();
    (dark, red)
}

#[test]
fn render_highlight_draws_lines_and_marks_the_bump_red() {
    let d = tmp("render");
    let base = |x: f64, y: f64| 0.15 * (1.3 * x).sin() * (0.9 * y).cos();
    let bump = move |x: f64, y: f64| {
        base(x, y) + 0.01 * (-((x - 0.4).powi(2) + (y + 0.3).powi(2)) / 0.0144).exp()
    };
    let mut clean_dark = 0;
    for (name, has_bump) in [("bump", true), ("clean", false)] {
        let mesh = d.join(format!("{name}.obj"));
        let text = if has_bump {
            height_field_obj(161, bump)
        } else {
            height_field_obj(161, base)
        };
        std::fs::write(&mesh, text).unwrap();
        let png = d.join(format!("{name}.png"));
        let rep = d.join(format!("{name}.json"));
        let o = run(&[
            "render",
            mesh.to_str().unwrap(),
            "--png",
            png.to_str().unwrap(),
            "--highlight",
            "--spacing",
            "0.1",
            "--size",
            "800x600",
            "--report",
            rep.to_str().unwrap(),
        ]);
        ok(&o);
        let (dark, red) = dark_and_red(&png);
        assert!(dark > 1000, "{name}: {dark} dark pixels");
        assert_eq!(red > 50, has_bump, "{name}: {red} red pixels");
        clean_dark = dark;
        let r = json(&rep);
        assert_eq!(r["command"], "render");
        assert_eq!(r["highlight"]["light"]["spacing"], 0.1);
        // 4 units across the light direction at spacing 0.1: ~40 lines
        let lines = r["highlight"]["lines"].as_u64().unwrap();
        assert!(lines >= 38, "{name}: {lines} lines");
        assert_eq!(r["highlight"]["regions"].as_u64().unwrap() > 0, has_bump);
    }
    // a plain render has no highlight lines: only the title is dark
    let png = d.join("plain.png");
    ok(&run(&[
        "render",
        d.join("clean.obj").to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--size",
        "800x600",
    ]));
    let (dark, red) = dark_and_red(&png);
    assert_eq!(red, 0);
    assert!(10 * dark < clean_dark, "{dark} vs {clean_dark}");
    // light options without --highlight are a usage error, nothing written
    let png = d.join("bad.png");
    let o = run(&[
        "render",
        d.join("clean.obj").to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--spacing",
        "0.1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!png.exists());
}

#[test]
fn circular_lights_from_a_json_file() {
    let d = tmp("circle-json");
    let mesh = d.join("plane.obj");
    std::fs::write(&mesh, height_field_obj(41, |_, _| 0.0)).unwrap();
    let lights = d.join("circles.json");
    std::fs::write(
        &lights,
        r#"{"center":[0,0,2],"axis":[0,0,1],"radii":[0.5,1]}"#,
    )
    .unwrap();
    let (a, b) = (d.join("a.json"), d.join("b.json"));
    ok(&run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--lights",
        lights.to_str().unwrap(),
        "-o",
        a.to_str().unwrap(),
    ]));
    ok(&run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--circle-center",
        "0,0,2",
        "--circle-axis",
        "0,0,1",
        "--radii",
        "0.5,1",
        "-o",
        b.to_str().unwrap(),
    ]));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let v = json(&a);
    assert_eq!(v["lines"].as_array().unwrap().len(), 2);
    assert_eq!(v["lines"][1]["radius"], 1.0);
    // circular lights make no sense to `detect`; empty radii are refused
    let out = d.join("r.json");
    let o = run(&[
        "detect",
        mesh.to_str().unwrap(),
        "--lights",
        lights.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("circular"));
    std::fs::write(&lights, r#"{"center":[0,0,2],"axis":[0,0,1],"radii":[]}"#).unwrap();
    let o = run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--lights",
        lights.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}

/// lego_open.ply is a flat outline in the plane y = 0 (y-up). The default
/// lights are chosen from the part (`--up auto`): they face it, so lines
/// appear (z-up lights above it would see it edge-on, Z·N = 0, and give
/// none), and on a plane the highlight distance
/// is linear in P, so every line is straight. Lights in a plane with normal
/// ±y give straight lines at z = A0.z − m·s (Z × H = −z).
#[test]
fn real_flat_outline_gives_straight_lines_with_default_lights() {
    let Some(mesh) = data("meshes/lego_open.ply") else {
        return;
    };
    let d = tmp("lego");
    let out = d.join("l.json");
    ok(&run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]));
    let lines = json(&out)["lines"].as_array().unwrap().clone();
    assert!(
        lines.len() >= 5,
        "{} lines with default lights",
        lines.len()
    );
    for l in &lines {
        let pts: Vec<[f64; 3]> = l["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| [0, 1, 2].map(|k| p[k].as_f64().unwrap()))
            .collect();
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let len = (ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]).sqrt();
        if len < 1e-9 {
            continue;
        }
        for p in &pts {
            let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
            let c = [
                ap[1] * ab[2] - ap[2] * ab[1],
                ap[2] * ab[0] - ap[0] * ab[2],
                ap[0] * ab[1] - ap[1] * ab[0],
            ];
            let dist = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() / len;
            assert!(
                dist < 1e-9,
                "line {}: point {p:?} off the straight line by {dist}",
                l["index"]
            );
        }
    }
    let rep = d.join("r.json");
    ok(&run(&[
        "highlight",
        mesh.to_str().unwrap(),
        "--plane-normal",
        "0,1,0",
        "--direction",
        "1,0,0",
        "--spacing",
        "0.05",
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]));
    let a0z = json(&rep)["light"]["array"]["plane_point"][2]
        .as_f64()
        .unwrap();
    let lines = json(&out)["lines"].as_array().unwrap().clone();
    // the outline spans z in [-0.5, 0.25]: 15 lights cross it
    let mut indices: Vec<i64> = lines.iter().map(|l| l["index"].as_i64().unwrap()).collect();
    indices.dedup();
    assert!(indices.len() >= 14, "{indices:?}");
    for l in &lines {
        let m = l["index"].as_f64().unwrap();
        for p in l["points"].as_array().unwrap() {
            let z = p[2].as_f64().unwrap();
            assert!((z - (a0z - 0.05 * m)).abs() < 1e-9, "line {m}: z {z}");
        }
    }
}

#[test]
fn non_manifold_real_meshes_are_refused_with_the_edge_named() {
    for rel in ["meshes/bunny_res4.ply", "meshes/elephant_nonmanifold.obj"] {
        let Some(mesh) = data(rel) else { return };
        let d = tmp(&rel.replace('/', "-"));
        let out = d.join("x.json");
        for cmd in ["highlight", "detect"] {
            let o = run(&[cmd, mesh.to_str().unwrap(), "-o", out.to_str().unwrap()]);
            assert_eq!(o.status.code(), Some(2), "{cmd} {rel}");
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                err.contains("non-manifold") && err.contains("edge ("),
                "{err}"
            );
            assert!(!out.exists());
        }
    }
}

/// The demo's highlight section: the planted dent is found (top region
/// centred on it within the dent's width) and the clean panel gets nothing.
#[test]
fn demo_finds_the_planted_dent() {
    let d = tmp("demo");
    let out = d.join("demo");
    let o = run(&["demo", "--out", out.to_str().unwrap(), "--size", "320x240"]);
    ok(&o);
    // a clean demo run has nothing to warn about (a value missing from the
    // report, e.g. the score of a region the clean hills do not have, is
    // left out rather than reported as not finite)
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("warning"), "{stderr}");
    let r = json(&out.join("report.json"));
    let s = &r["sections"]["Highlight lines and a planted dent"];
    assert!(s["regions"].as_u64().unwrap() >= 1, "{s}");
    assert!(
        s["top_region_centre_distance_from_dent"].as_f64().unwrap() < 0.16,
        "{s}"
    );
    assert_eq!(s["clean_panel_regions"], 0);
    for png in [
        "highlight-dent-lines.png",
        "highlight-dent-region.png",
        "highlight-clean-lines.png",
    ] {
        let (dark, _) = dark_and_red(&out.join(png));
        assert!(dark > 200, "{png}: {dark} dark pixels");
    }
    let (_, red) = dark_and_red(&out.join("highlight-dent-lines.png"));
    assert!(red > 20, "red stretches at the dent: {red}");
    // the detection section: strongly curved hills stay quiet, the same
    // hills with a bump of 0.1 % of the diagonal (σ = 0.1) get a region
    // centred on it, ranked first
    let c = &r["sections"]["Detection: quiet on curved shape, finds a small defect"];
    assert_eq!(c[0]["surface"], "clean hills", "{c}");
    assert_eq!(c[0]["regions"], 0, "{c}");
    assert!(c[1]["regions"].as_u64().unwrap() >= 1, "{c}");
    assert!(
        c[1]["top_region_centre_distance_from_bump"]
            .as_f64()
            .unwrap()
            < 0.1,
        "{c}"
    );
    for png in ["detect-curved-clean.png", "detect-curved-bump.png"] {
        let (dark, _) = dark_and_red(&out.join(png));
        assert!(dark > 200, "{png}: {dark} dark pixels");
    }
}

/// `-o LINES.igs`: one IGES entity 126 per line, a cubic with far fewer
/// control points than the line has points on a smooth bowl, named by its
/// light (`HLm` in the directory entry's label field), within the
/// tolerance the report gives; the JSON output of the same run has the
/// same lines.
#[test]
fn lines_as_iges_curves() {
    let d = tmp("curves");
    let mesh = d.join("bowl.obj");
    std::fs::write(&mesh, height_field_obj(61, |x, y| 0.1 * (x * x + y * y))).unwrap();
    let m = mesh.to_str().unwrap();
    let (igs, json, rep) = (d.join("lines.igs"), d.join("lines.json"), d.join("r.json"));
    ok(&run(&[
        "highlight",
        m,
        "-o",
        igs.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]));
    ok(&run(&["highlight", m, "-o", json.to_str().unwrap()]));
    let lines = common::json(&json)["lines"].as_array().unwrap().len();
    let r = common::json(&rep);
    let c = &r["curves"];
    assert_eq!(c["curves"].as_u64().unwrap() as usize, lines, "{c}");
    assert!(c["max_deviation"].as_f64().unwrap() <= c["tolerance"].as_f64().unwrap());
    assert!(
        c["control_points"].as_u64().unwrap() < c["points"].as_u64().unwrap() / 3,
        "{c}"
    );
    let text = std::fs::read_to_string(&igs).unwrap();
    let records: Vec<&str> = text.lines().collect();
    assert!(records.iter().all(|l| l.len() == 80), "80-column records");
    // directory entries: two records per entity, the second with the label
    let dir: Vec<&str> = records
        .iter()
        .copied()
        .filter(|l| &l[72..73] == "D")
        .collect();
    assert_eq!(dir.len(), 2 * lines);
    for pair in dir.chunks(2) {
        assert_eq!(pair[0][..8].trim(), "126");
        assert!(pair[1][56..64].trim().starts_with("HL"), "{}", pair[1]);
    }
}
