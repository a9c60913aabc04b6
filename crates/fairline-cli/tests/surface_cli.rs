//! Command-line tests of B-spline surface highlight lines and
//! circular-highlight fairing (Nishiyama et al.): `highlight SURFACE.json`,
//! `fair-surface`, `convert` of IGES, on a dome-like bicubic surface with a
//! planted bump and on the real teapot and impeller.

mod common;
use common::*;

use fairline::Vec3;
use fairline::bspline::BSplineSurface;
use fairline::fair::endpoints_around;
use fairline::highlight::{CircularLight, SurfaceLight, surface_signed_distance};
use fairline::io::{read_surfaces_json, write_surfaces_json};

const CENTRE: [f64; 2] = DOME_BUMP_UV;

/// The bumped dome and the radii of nine concentric lights (centre
/// (0, 0, 3), axis z) whose lines cross the bump: ±20 % around the radius
/// the clean surface's normal line at the bump reaches.
fn dome() -> (BSplineSurface, Vec<f64>) {
    let clean = dome_surface(false);
    let q = clean.eval(CENTRE[0], CENTRE[1]);
    let n = clean.normal(CENTRE[0], CENTRE[1]).unwrap();
    let x = q + (3.0 - q.z) / n.z * n;
    let r0 = x.x.hypot(x.y);
    let radii = (0..9).map(|k| r0 * (0.8 + 0.05 * k as f64)).collect();
    (dome_surface(true), radii)
}

fn lights(radii: &[f64]) -> Vec<CircularLight> {
    radii
        .iter()
        .map(|&r| CircularLight::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z, r).unwrap())
        .collect()
}

fn list(v: &[f64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

#[test]
fn surface_highlight_writes_uv_and_points_on_the_zero_level() {
    let d = tmp("hl");
    let (surf, radii) = dome();
    let f = d.join("dome.json");
    write_surfaces_json(&f, std::slice::from_ref(&surf)).unwrap();
    let (out, png, svg, rep) = (
        d.join("lines.json"),
        d.join("lines.png"),
        d.join("uv.svg"),
        d.join("r.json"),
    );
    let o = run(&[
        "highlight",
        s(&f),
        "--circle-center",
        "0,0,3",
        "--circle-axis",
        "0,0,1",
        "--radii",
        &list(&radii),
        "--grid",
        "150",
        "--band",
        "0.01",
        "-o",
        s(&out),
        "--png",
        s(&png),
        "--svg",
        s(&svg),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json(&out);
    let lines = v["lines"].as_array().unwrap();
    assert!(lines.len() >= radii.len());
    let ls = lights(&radii);
    for l in lines {
        let r = l["radius"].as_f64().unwrap();
        let k = radii
            .iter()
            .position(|&x| x == r)
            .expect("radius of a given light");
        let light = SurfaceLight::Circular(ls[k]);
        let uv = l["uv"].as_array().unwrap();
        let pts = l["points"].as_array().unwrap();
        assert_eq!(uv.len(), pts.len());
        for (a, p) in uv.iter().zip(pts) {
            let (u, w) = (a[0].as_f64().unwrap(), a[1].as_f64().unwrap());
            let q = surf.eval(u, w);
            assert_eq!(q.x, p[0].as_f64().unwrap());
            assert!(surface_signed_distance(&surf, &light, u, w).unwrap().abs() <= 1e-9);
        }
    }
    assert!(!v["bands"]["lower"].as_array().unwrap().is_empty());
    let r = json(&rep);
    assert_eq!(r["command"], "highlight");
    assert!(r["time_s"].as_f64().unwrap() >= 0.0);
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<polyline"));
}

#[test]
fn fair_surface_end_to_end_leaves_the_outside_bit_identical() {
    let d = tmp("fair");
    let (surf, radii) = dome();
    let f = d.join("dome.json");
    write_surfaces_json(&f, std::slice::from_ref(&surf)).unwrap();
    let ls = lights(&radii);
    let ends = endpoints_around(&surf, &ls, CENTRE, 0.2, 200);
    assert!(ends.len() >= 3);
    let (lf, ef) = (d.join("lights.json"), d.join("ends.json"));
    std::fs::write(
        &lf,
        format!(
            r#"{{"center":[0,0,3],"axis":[0,0,1],"radii":[{}]}}"#,
            list(&radii)
        ),
    )
    .unwrap();
    std::fs::write(
        &ef,
        serde_json::to_string(&serde_json::json!({"endpoints": ends})).unwrap(),
    )
    .unwrap();
    let (out, rep, png, svg) = (
        d.join("out.json"),
        d.join("rep.json"),
        d.join("fair.png"),
        d.join("uv.svg"),
    );
    let o = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&ef),
        "-o",
        s(&out),
        "--report",
        s(&rep),
        "--png",
        s(&png),
        "--svg",
        s(&svg),
        "--max-iterations",
        "8",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // a truncation floor that is not a number is refused, nothing written
    let nan_out = d.join("nan.json");
    let bad = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&ef),
        "-o",
        s(&nan_out),
        "--min-truncation",
        "NaN",
    ]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
    assert!(String::from_utf8_lossy(&bad.stderr).contains("truncation"));
    assert!(!nan_out.exists());
    let r = json(&rep);
    for key in [
        "iterations",
        "converged",
        "modified_control_points",
        "residual_before",
        "residual_after",
        "time_s",
    ] {
        assert!(!r[key].is_null(), "report key {key}");
    }
    let (b, a) = (
        r["residual_before"]["mean"].as_f64().unwrap(),
        r["residual_after"]["mean"].as_f64().unwrap(),
    );
    assert!(a < b / 30.0, "mean |d_s| {b} -> {a}");
    assert!(r["iterations"].as_u64().unwrap() <= 8);
    assert!(
        ["epsilon", "stalled", "max_iterations", "zero_residual"]
            .contains(&r["stop"].as_str().unwrap())
    );
    let modified: Vec<(usize, usize)> = r["modified_indices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p[0].as_u64().unwrap() as usize,
                p[1].as_u64().unwrap() as usize,
            )
        })
        .collect();
    assert_eq!(
        modified.len(),
        r["modified_control_points"].as_u64().unwrap() as usize
    );
    let faired = read_surfaces_json(&out).unwrap().remove(0);
    let mut moved = 0;
    for i in 0..15 {
        for j in 0..15 {
            let (p, q) = (surf.control_point(i, j), faired.control_point(i, j));
            if modified.contains(&(i, j)) {
                moved += usize::from(p != q);
            } else {
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    q.to_array().map(f64::to_bits),
                    "({i},{j})"
                );
            }
        }
    }
    assert!(moved > 0);
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<circle"));
}

#[test]
fn fair_surface_bad_input_exits_2_without_output() {
    let d = tmp("bad");
    let (surf, radii) = dome();
    let f = d.join("dome.json");
    write_surfaces_json(&f, std::slice::from_ref(&surf)).unwrap();
    let lf = d.join("lights.json");
    std::fs::write(
        &lf,
        format!(
            r#"{{"center":[0,0,3],"axis":[0,0,1],"radii":[{}]}}"#,
            list(&radii)
        ),
    )
    .unwrap();
    let ef = d.join("ends.json");
    std::fs::write(
        &ef,
        r#"{"endpoints":[{"radius":7.5,"start":[0.6,0.3],"end":[0.8,0.4]}]}"#,
    )
    .unwrap();
    let out = d.join("out.json");
    let o = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&ef),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("radius 7.5"));
    assert!(!out.exists());
    // Malformed endpoints file: the error names the file.
    std::fs::write(&ef, r#"{"endpoints":[{"radius":1,"start":[0.6]}]}"#).unwrap();
    let o = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&ef),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("ends.json"));
    // Output over the input, wrong extensions, bad grid.
    let o = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&ef),
        "-o",
        s(&f),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&[
        "highlight",
        s(&f),
        "--circle-center",
        "0,0,3",
        "--circle-axis",
        "0,0,1",
        "--radii",
        "1",
        "-o",
        s(&d.join("l.obj")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&[
        "highlight",
        s(&f),
        "--radii",
        "1",
        "--circle-center",
        "0,0,3",
        "--circle-axis",
        "0,0,1",
        "--grid",
        "1",
        "-o",
        s(&d.join("l.json")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!d.join("l.json").exists());
    let o = run(&["fair-surface", "--help"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Example"));
}

#[test]
fn real_surfaces_teapot_and_impeller() {
    let Some(tp) = data("surfaces/teapot.json") else {
        return;
    };
    let d = tmp("real");
    let out = d.join("teapot-lines.json");
    let o = run(&[
        "highlight",
        s(&tp),
        "--circle-center",
        "0,-8,6",
        "--circle-axis",
        "0,1,-0.5",
        "--radii",
        "1,2,3",
        // on a file of many patches --grid counts points along the whole
        // part's diagonal (each patch gets its share, at least 12 a side)
        "--grid",
        "200",
        "-o",
        s(&out),
        "--png",
        s(&d.join("teapot.png")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json(&out);
    let lines = v["lines"].as_array().unwrap();
    assert!(lines.len() > 10);
    assert!(lines.iter().all(|l| l["surface"].as_u64().unwrap() < 32));
    let Some(ip) = data("surfaces/impeller.igs") else {
        return;
    };
    let js = d.join("impeller.json");
    let o = run(&["convert", s(&ip), s(&js)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let surfaces = read_surfaces_json(&js).unwrap();
    // 247 B-spline surfaces (128) and 30 surfaces of revolution (120)
    assert_eq!(surfaces.len(), 277);
    // Linear light array (defaults from the bounding box) on the impeller.
    let out = d.join("impeller-lines.json");
    let o = run(&[
        "highlight",
        s(&ip),
        "--grid",
        "40",
        "-o",
        s(&out),
        "--png",
        s(&d.join("impeller.png")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!json(&out)["lines"].as_array().unwrap().is_empty());
}

/// The default highlight output of a whole multi-patch part stays
/// proportionate. The impeller (247 trimmed faces) with default lights and
/// grid writes at most 50 MB and at most 100 kB per patch (the full
/// 200 × 200 grid on every face and up to 100 lights would make 404 MB); the
/// lines still cover most faces and carry their patch index.
#[test]
fn whole_part_default_highlight_output_is_proportionate() {
    let Some(ip) = data("surfaces/impeller.igs") else {
        return;
    };
    let d = tmp("proportionate");
    let out = d.join("impeller-lines.json");
    let report = d.join("report.json");
    ok(&run(&[
        "highlight",
        s(&ip),
        "-o",
        s(&out),
        "--report",
        s(&report),
    ]));
    let bytes = std::fs::metadata(&out).unwrap().len();
    let patches = 247;
    eprintln!(
        "impeller default highlight: {bytes} bytes, {} per patch",
        bytes / patches
    );
    assert!(bytes <= 50_000_000, "{bytes} bytes");
    assert!(
        bytes / patches <= 100_000,
        "{} bytes per patch",
        bytes / patches
    );
    let v = json(&out);
    let lines = v["lines"].as_array().unwrap();
    let mut faces: Vec<u64> = lines.iter().filter_map(|l| l["surface"].as_u64()).collect();
    assert_eq!(faces.len(), lines.len(), "every line names its patch");
    faces.sort_unstable();
    faces.dedup();
    eprintln!("lines on {} of {patches} faces", faces.len());
    assert!(
        faces.len() * 2 > patches as usize,
        "lines on {} faces",
        faces.len()
    );
}

/// The paper's method (Nishiyama et al. §3.3) that does not converge says
/// why and exits 1: a short stretch on the bumped dome has fewer samples at
/// the default spacing than moved control points, so its samples are
/// raised until the system is overdetermined (the report's Jacobian has at
/// least as many rows as columns); one iteration is not enough, and the
/// warning says so, on stderr and in the report, and the result is written
/// for inspection. `--damped-step` (μ of Eq. (3.13), default the paper's
/// 0.1) and `--damping` reach the solver: with `--damping off` no step is
/// damped, with `max-mean` (Eq. (3.12) as printed) on all nine stretches
/// some are; μ = 0 is refused.
#[test]
fn fair_surface_paper_method_that_does_not_converge_says_why_and_exits_1() {
    let d = tmp("fair-paper-stall");
    let (surf, radii) = dome();
    let f = d.join("dome.json");
    write_surfaces_json(&f, std::slice::from_ref(&surf)).unwrap();
    let ls = lights(&radii);
    let ends = endpoints_around(&surf, &ls, CENTRE, 0.2, 200);
    let mut short = ends[0];
    for k in 0..2 {
        short.end[k] = short.start[k] + 0.3 * (short.end[k] - short.start[k]);
    }
    let lf = d.join("lights.json");
    std::fs::write(
        &lf,
        format!(
            r#"{{"center":[0,0,3],"axis":[0,0,1],"radii":[{}]}}"#,
            list(&radii)
        ),
    )
    .unwrap();
    let write_ends = |name: &str, e: &[fairline::fair::EndpointPair]| {
        let p = d.join(name);
        std::fs::write(
            &p,
            serde_json::to_string(&serde_json::json!({ "endpoints": e })).unwrap(),
        )
        .unwrap();
        p
    };
    let (short_f, all_f) = (
        write_ends("ends-short.json", &[short]),
        write_ends("ends-all.json", &ends),
    );
    let fair = |ends: &std::path::Path, damped: &str, damping: &str, its: &str, name: &str| {
        let (out, rep) = (
            d.join(format!("{name}.json")),
            d.join(format!("{name}-r.json")),
        );
        let o = run(&[
            "fair-surface",
            s(&f),
            "--lights",
            s(&lf),
            "--endpoints",
            s(ends),
            "--method",
            "paper",
            "--damped-step",
            damped,
            "--damping",
            damping,
            "--max-iterations",
            its,
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ]);
        (o, out, rep)
    };
    let (o, out, rep) = fair(&short_f, "0.1", "residual", "1", "short");
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(out.exists(), "written for inspection");
    let r = json(&rep);
    assert_eq!(r["converged"], false);
    assert_eq!(r["stop"], "max_iterations");
    let (rows, cols) = (
        r["jacobian"]["rows"].as_u64().unwrap(),
        r["jacobian"]["cols"].as_u64().unwrap(),
    );
    assert!(rows >= cols, "{rows} x {cols}");
    assert_eq!(cols, r["modified_control_points"].as_u64().unwrap());
    // (the shortened end lies off the line and snaps onto it: a warning of
    // its own comes first)
    let warning = r["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .find(|w| w.contains("did not converge"))
        .unwrap_or_else(|| panic!("{r}"));
    for part in ["did not converge", "out of iterations: --max-iterations 1"] {
        assert!(warning.contains(part), "{part}: {warning}");
        assert!(e.contains(part), "{part}: {e}");
    }
    assert!(e.contains("written for inspection only"), "{e}");
    // μ and the damping rule reach Eq. (3.13)
    let steps = |rep: &std::path::Path| -> Vec<f64> {
        json(rep)["history"]
            .as_array()
            .unwrap()
            .iter()
            .map(|h| h["step"].as_f64().unwrap())
            .collect()
    };
    let (_, _, undamped) = fair(&all_f, "0.1", "off", "20", "undamped");
    let (_, _, damped) = fair(&all_f, "0.1", "max-mean", "20", "damped");
    assert!(steps(&undamped).iter().all(|&x| x == 1.0));
    assert!(steps(&damped).contains(&0.1), "{:?}", steps(&damped));
    let (o, out, _) = fair(&all_f, "0", "residual", "20", "zero");
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&d);
}
