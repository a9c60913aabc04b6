//! Command-line tests of `fairline fair` (Yong et al. §3, Algorithm 2).

mod common;
use common::*;

use fairline::{SurfaceMesh, Vec3};
use std::path::{Path, PathBuf};

/// A gently curved panel with a planted bump at the origin.
fn bump_panel(dir: &Path) -> PathBuf {
    let mesh = fairline::shapes::height_field(41, 41, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.03 * x * x + 0.03 * (-(x * x + y * y) / (2.0 * 0.12 * 0.12)).exp()
    });
    let p = dir.join("bump.obj");
    fairline::io::write_mesh(&p, &mesh).unwrap();
    p
}

fn bits(m: &SurfaceMesh) -> Vec<[u64; 3]> {
    m.positions()
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn fair_removes_a_bump_and_touches_nothing_outside() {
    let d = tmp("bump");
    let mesh = bump_panel(&d);
    let region = d.join("region.json");
    std::fs::write(&region, r#"{"sphere":{"center":[0,0,0],"radius":0.5}}"#).unwrap();
    let (out, png, rep) = (d.join("out.obj"), d.join("fair.png"), d.join("rep.json"));
    let o = run(&[
        "fair",
        s(&mesh),
        "--region",
        s(&region),
        "-o",
        s(&out),
        "--png",
        s(&png),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let r = json(&rep);
    for key in [
        "command",
        "time_s",
        "iterations",
        "converged",
        "movable_vertices",
        "willmore_before",
        "willmore_after",
        "highlight_deviation_before",
        "highlight_deviation_after",
        "max_displacement",
        "history",
    ] {
        assert!(r.get(key).is_some(), "report misses {key}");
    }
    assert_eq!(r["command"], "fair");
    assert_eq!(r["converged"], true);
    let f = |k: &str| r[k].as_f64().unwrap();
    assert!(f("willmore_after") < 0.1 * f("willmore_before"));
    assert!(f("highlight_deviation_after") < 0.05 * f("highlight_deviation_before"));
    assert_eq!(
        r["history"].as_array().unwrap().len() as u64,
        r["iterations"].as_u64().unwrap()
    );
    // only the movable vertices moved; the rest is bit-identical in the file
    let (a, b) = (
        fairline::io::read_mesh(&mesh).unwrap(),
        fairline::io::read_mesh(&out).unwrap(),
    );
    let (ba, bb) = (bits(&a), bits(&b));
    let moved = ba.iter().zip(&bb).filter(|(x, y)| x != y).count();
    assert!(moved > 0 && moved as u64 <= r["movable_vertices"].as_u64().unwrap());
    for (v, (x, y)) in ba.iter().zip(&bb).enumerate() {
        if x != y {
            assert!(
                a.positions()[v].length() < 0.5,
                "vertex {v} outside the region moved"
            );
        }
    }
    // the bump is gone: the region is back on z = 0.03 x² within a small fraction
    let err = b
        .positions()
        .iter()
        .map(|p| (p.z - 0.03 * p.x * p.x).abs())
        .fold(0.0, f64::max);
    assert!(
        err < 0.03 / 20.0,
        "largest distance to the smooth panel {err}"
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);

    // the baseline runs on the same region and is worse on the highlight lines
    let (out2, rep2) = (d.join("flow.obj"), d.join("flow.json"));
    ok(&run(&[
        "fair",
        s(&mesh),
        "--region",
        s(&region),
        "-o",
        s(&out2),
        "--method",
        "diffusion-flow",
        "--report",
        s(&rep2),
    ]));
    let r2 = json(&rep2);
    assert_eq!(r2["method"], "diffusion-flow");
    // least change: on this bump the highlight result does not dominate
    // the flow state, so the default is the flow state, bit for bit, and
    // the report says so with the numbers it compared
    assert_eq!(r["kept_flow"], true, "{}", r["least_change"]);
    assert_eq!(r["flow_share"], 1.0);
    let lc = &r["least_change"];
    for key in [
        "displacement_highlight",
        "displacement_flow",
        "deviation_highlight",
        "deviation_flow",
    ] {
        assert!(lc[key].as_f64().unwrap() > 0.0, "{lc}");
    }
    let flow_mesh = fairline::io::read_mesh(&out2).unwrap();
    assert!(
        bits(&flow_mesh) == bb,
        "the default differs from the flow state"
    );

    // --no-least-change keeps the highlight-line result: a different
    // surface, with the same four numbers in its report
    let (out3, rep3) = (d.join("highlight.obj"), d.join("highlight.json"));
    let o = run(&[
        "fair",
        s(&mesh),
        "--region",
        s(&region),
        "-o",
        s(&out3),
        "--no-least-change",
        "--report",
        s(&rep3),
    ]);
    ok(&o);
    let r3 = json(&rep3);
    assert_eq!(r3["kept_flow"], false);
    assert_eq!(r3["flow_share"], 0.25);
    assert_eq!(r3["least_change"], r["least_change"]);
    let highlight_mesh = fairline::io::read_mesh(&out3).unwrap();
    assert!(bits(&highlight_mesh) != bb);
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("least change"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `--method membrane|thin-plate|mvs` (Grüner §3.1.2–3.1.3): the energy
/// methods remove the bump from the region, no vertex outside it moves,
/// and the report names the method.
#[test]
fn energy_methods_fair_the_region_and_touch_nothing_outside() {
    let d = tmp("energy");
    let mesh = bump_panel(&d);
    let region = d.join("region.json");
    std::fs::write(&region, r#"{"sphere":{"center":[0,0,0],"radius":0.5}}"#).unwrap();
    let a = fairline::io::read_mesh(&mesh).unwrap();
    for method in ["membrane", "thin-plate", "mvs"] {
        let (out, rep) = (
            d.join(format!("{method}.obj")),
            d.join(format!("{method}.json")),
        );
        ok(&run(&[
            "fair",
            s(&mesh),
            "--region",
            s(&region),
            "--method",
            method,
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ]));
        let r = json(&rep);
        assert_eq!(r["method"], method);
        assert_eq!(r["converged"], true);
        let b = fairline::io::read_mesh(&out).unwrap();
        for (v, (x, y)) in bits(&a).iter().zip(&bits(&b)).enumerate() {
            if x != y {
                assert!(
                    a.positions()[v].length() < 0.5,
                    "{method}: vertex {v} moved"
                );
            }
        }
        let err = b
            .positions()
            .iter()
            .map(|p| (p.z - 0.03 * p.x * p.x).abs())
            .fold(0.0, f64::max);
        assert!(
            err < 0.03 / 5.0,
            "{method}: largest distance to the panel {err}"
        );
    }
}

#[test]
fn auto_detects_and_fairs() {
    let d = tmp("auto");
    let mesh = bump_panel(&d);
    let (out, rep) = (d.join("out.ply"), d.join("rep.json"));
    ok(&run(&[
        "fair",
        s(&mesh),
        "--auto",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]));
    let r = json(&rep);
    assert!(r["detected_regions"].as_u64().unwrap() >= 1, "{r}");
    assert!(r["regions"].as_u64().unwrap() >= 1);
    assert!(r["willmore_after"].as_f64().unwrap() < 0.2 * r["willmore_before"].as_f64().unwrap());
    assert!(out.exists());
}

#[test]
fn bad_regions_exit_with_2_and_write_nothing() {
    let d = tmp("bad");
    let mesh = bump_panel(&d);
    let out = d.join("out.obj");
    let cases: Vec<(&str, &str)> = vec![
        ("tiny", r#"{"sphere":{"center":[0,0,0],"radius":0.08}}"#),
        ("empty", r#"{"sphere":{"center":[5,5,5],"radius":0.1}}"#),
        ("range", r#"{"faces":[0,999999]}"#),
        ("garbage", "{faces"),
        ("none", "{}"),
    ];
    for (name, text) in cases {
        let region = d.join(format!("{name}.json"));
        std::fs::write(&region, text).unwrap();
        let o = run(&["fair", s(&mesh), "--region", s(&region), "-o", s(&out)]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!out.exists(), "{name}: output written");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("region") || err.contains("movable"),
            "{name}: {err}"
        );
        if name == "tiny" {
            assert!(err.contains("Enlarge"), "{err}");
        }
    }
    // never over the input; options checked
    let region = d.join("ok.json");
    std::fs::write(&region, r#"{"sphere":{"center":[0,0,0],"radius":0.5}}"#).unwrap();
    let o = run(&["fair", s(&mesh), "--region", s(&region), "-o", s(&mesh)]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&[
        "fair",
        s(&mesh),
        "--region",
        s(&region),
        "-o",
        s(&out),
        "--epsilon",
        "-1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
    let o = run(&["fair", "--help"]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Example"));
}

/// Real data: a bump planted on the back of Crane's "Spot" (a real, closed
/// scan-like mesh), faired in a sphere region; everything outside stays
/// bit-identical and the region's energies drop.
#[test]
fn real_mesh_spot_back() {
    let Some(p) = data("meshes/spot.ply") else {
        return;
    };
    let d = tmp("spot");
    let mut mesh = fairline::io::read_mesh(&p).unwrap();
    // the highest vertex of the back (y up, body along z)
    let c = mesh
        .positions()
        .iter()
        .copied()
        .filter(|q| q.x.abs() < 0.05 && q.z > 0.0 && q.z < 0.3)
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    let normals = fairline::geom::vertex_normals(&mesh);
    for (q, n) in mesh.positions_mut().iter_mut().zip(&normals) {
        let r2 = (*q - c).length_squared();
        *q += 0.015 * (-r2 / (2.0 * 0.07 * 0.07)).exp() * *n;
    }
    let input = d.join("spot-bump.ply");
    fairline::io::write_mesh(&input, &mesh).unwrap();
    let region = d.join("region.json");
    std::fs::write(
        &region,
        format!(
            r#"{{"sphere":{{"center":[{},{},{}],"radius":0.35}}}}"#,
            c.x, c.y, c.z
        ),
    )
    .unwrap();
    let (out, rep) = (d.join("out.ply"), d.join("rep.json"));
    ok(&run(&[
        "fair",
        s(&input),
        "--region",
        s(&region),
        "--plane-normal",
        "0,1,0",
        "--direction",
        "0,0,1",
        "--plane-point",
        "0,1.2,0.1",
        "--spacing",
        "0.06",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]));
    let r = json(&rep);
    let f = |k: &str| r[k].as_f64().unwrap();
    assert!(r["movable_vertices"].as_u64().unwrap() > 20, "{r}");
    // Spot is coarse for its curvature: its highlight lines are fragmented
    // and only a few cross the region whole, so the claims are modest
    assert!(r["desired_lines"].as_u64().unwrap() > 0, "{r}");
    assert!(f("willmore_after") < 0.7 * f("willmore_before"), "{r}");
    assert!(
        f("highlight_deviation_after") < f("highlight_deviation_before"),
        "{r}"
    );
    let b = fairline::io::read_mesh(&out).unwrap();
    let moved: Vec<usize> = bits(&mesh)
        .iter()
        .zip(bits(&b))
        .enumerate()
        .filter(|(_, (x, y))| **x != *y)
        .map(|(i, _)| i)
        .collect();
    assert!(!moved.is_empty());
    for i in moved {
        assert!(
            (mesh.positions()[i] - c).length() < 0.35,
            "vertex {i} outside the region moved"
        );
    }
    let _ = Vec3::ZERO;
}

/// Dark (line-ink) pixels of a picture.
fn dark_pixels(png: &Path) -> usize {
    let img = fairline::render::Image::decode_png(&std::fs::read(png).unwrap()).unwrap();
    img.pixels
        .iter()
        .filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 90)
        .count()
}

/// On a round part `fair` fairs and draws the readable lines — every k-th
/// light of detection's array, the lines `highlight` and `detect` show
/// with the default lights (at the detail spacing the lines lie a fraction
/// of an edge apart on this coarse mesh, triangles crossed by more than
/// four of them carry none, the picture would be hatched fragments and
/// highlight-line fairing would not converge). The report keeps
/// detection's lights under "light" and the fairing lights, k > 1 times
/// their spacing, under "fairing_light"; fairing converges and the picture
/// shows lines. The part: Spot with a dent planted on its flank, which
/// `--auto` finds and fairs (clean Spot has nothing to fair).
#[test]
fn fair_picture_on_a_round_part_draws_the_readable_lines() {
    let Some(clean) = data("meshes/spot.ply") else {
        return;
    };
    let d = tmp("spot-picture");
    let (p, _) = dented_spot(&clean, &d, 0.15);
    let (out_a, png_a, rep_a) = (d.join("a.ply"), d.join("a.png"), d.join("a.json"));
    ok(&run(&[
        "fair",
        s(&p),
        "--auto",
        "-o",
        s(&out_a),
        "--png",
        s(&png_a),
        "--report",
        s(&rep_a),
    ]));
    let rep = json(&rep_a);
    assert!(
        rep["regions"].as_u64().unwrap() >= 1,
        "the dent is faired: {rep}"
    );
    let spacing = rep["light"]["spacing"].as_f64().unwrap();
    let fairing = rep["fairing_light"]["spacing"].as_f64().unwrap();
    let k = fairing / spacing;
    assert!(k > 1.5 && (k - k.round()).abs() < 1e-9, "{rep}");
    assert_eq!(rep["converged"], true, "{rep}");
    let readable = dark_pixels(&png_a);
    assert!(
        readable > 500,
        "the readable picture shows lines: {readable}"
    );
}
