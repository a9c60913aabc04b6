//! `fairline deviation`: closed-form distances between concentric spheres,
//! the split of the statistics inside and outside a region, the picture,
//! the CSV, and the refusal of bad input (exit 2, the file named, nothing
//! written); a B-spline reference measured exactly (points off a rational
//! cylinder at their radial distance).

mod common;
use common::{json, ok, run, s, tmp};
use fairline::shapes;

#[test]
fn concentric_spheres_deviate_by_their_radius_difference() {
    let dir = tmp("deviation-spheres");
    let (a, b) = (dir.join("inner.obj"), dir.join("outer.ply"));
    fairline::io::write_mesh(&a, &shapes::icosphere(1.0, 4)).unwrap();
    fairline::io::write_mesh(&b, &shapes::uv_sphere(1.2, 64, 32)).unwrap();
    let (png, csv, report) = (dir.join("d.png"), dir.join("d.csv"), dir.join("d.json"));
    let out = run(&[
        "deviation",
        s(&a),
        s(&b),
        "--png",
        s(&png),
        "--csv",
        s(&csv),
        "--report",
        s(&report),
        "--size",
        "400x300",
    ]);
    ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("fairline deviation:"), "{stderr}");
    let r = json(&report);
    assert_eq!(r["method"], "closest-point");
    // the inner sphere's tessellation lies within 2e-3 of radius 1
    let all = &r["all"];
    assert!((all["min"].as_f64().unwrap() - 0.2).abs() < 3e-3, "{all}");
    assert!((all["max"].as_f64().unwrap() - 0.2).abs() < 3e-3, "{all}");
    assert!((all["rms"].as_f64().unwrap() - 0.2).abs() < 3e-3, "{all}");
    let counts: usize = all["histogram"]["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap() as usize)
        .sum();
    assert_eq!(counts, r["vertices"].as_u64().unwrap() as usize);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("vertex,x,y,z,signed,distance,in_region,broad,local\n"));
    assert_eq!(
        text.lines().count(),
        1 + r["vertices"].as_u64().unwrap() as usize
    );
    let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
    assert_eq!((img.width, img.height), (400, 300));
}

#[test]
fn region_splits_intended_motion_from_side_effects() {
    let dir = tmp("deviation-region");
    let before = shapes::plane(21);
    let mut after = before.clone();
    // lift the vertices of the first 40 triangles
    let region: Vec<u32> = (0..40).collect();
    let mut lifted = vec![false; before.vertex_count()];
    for &f in &region {
        for v in before.face_vertices(fairline::FaceId(f)) {
            lifted[v.idx()] = true;
        }
    }
    for (p, l) in after.positions_mut().iter_mut().zip(&lifted) {
        if *l {
            p.z += 0.03;
        }
    }
    let (a, b, reg) = (
        dir.join("a.obj"),
        dir.join("b.obj"),
        dir.join("region.json"),
    );
    fairline::io::write_mesh(&a, &before).unwrap();
    fairline::io::write_mesh(&b, &after).unwrap();
    std::fs::write(&reg, serde_json::json!({ "faces": region }).to_string()).unwrap();
    let report = dir.join("r.json");
    ok(&run(&[
        "deviation",
        s(&a),
        s(&b),
        "--region",
        s(&reg),
        "--report",
        s(&report),
    ]));
    let r = json(&report);
    assert_eq!(r["method"], "displacement");
    assert!((r["inside_region"]["max_abs"].as_f64().unwrap() - 0.03).abs() < 1e-9);
    assert_eq!(r["outside_region"]["max_abs"].as_f64().unwrap(), 0.0);
    assert!(r["inside_region"]["count"].as_u64().unwrap() > 0);
}

/// A shift of the whole plane plus a one-vertex spike: `--show broad`
/// colours the shift, `--show local` the spike; the CSV's `broad` and
/// `local` add up to `signed`.
#[test]
fn broad_and_local_parts_are_shown_and_written() {
    let dir = tmp("deviation-broad");
    let before = shapes::plane(41);
    let mut after = before.clone();
    let spike = 20 * 41 + 20;
    for (i, p) in after.positions_mut().iter_mut().enumerate() {
        p.z += 0.01 + if i == spike { 0.02 } else { 0.0 };
    }
    let (a, b) = (dir.join("a.obj"), dir.join("b.obj"));
    fairline::io::write_mesh(&a, &before).unwrap();
    fairline::io::write_mesh(&b, &after).unwrap();
    let (csv, report) = (dir.join("d.csv"), dir.join("r.json"));
    let mut pictures = Vec::new();
    for show in ["broad", "local"] {
        let png = dir.join(format!("{show}.png"));
        let out = run(&[
            "deviation",
            s(&a),
            s(&b),
            "--broad-wavelength",
            "0.5",
            "--show",
            show,
            "--png",
            s(&png),
            "--csv",
            s(&csv),
            "--report",
            s(&report),
            "--size",
            "400x400",
        ]);
        ok(&out);
        assert!(String::from_utf8_lossy(&out.stderr).contains("broad (waves over 5.000e-1)"));
        let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
        assert_eq!((img.width, img.height), (400, 400));
        pictures.push(img);
    }
    // the two parts are two different fields on the part
    assert!(pictures[0] != pictures[1]);
    let text = std::fs::read_to_string(&csv).unwrap();
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        assert!((f[7] + f[8] - f[4]).abs() < 1e-12, "{line}");
    }
    let r = json(&report);
    assert_eq!(r["broad_wavelength"], 0.5);
    assert!((r["broad"]["mean"].as_f64().unwrap() - 0.01).abs() < 1e-4);
    assert!(r["local"]["max_abs"].as_f64().unwrap() > 0.015);
    let bad = run(&["deviation", s(&a), s(&b), "--broad-wavelength", "0"]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}

#[test]
fn bad_inputs_exit_2_naming_the_file_and_write_nothing() {
    let dir = tmp("deviation-bad");
    let good = dir.join("good.obj");
    fairline::io::write_mesh(&good, &shapes::icosphere(1.0, 1)).unwrap();
    let missing = dir.join("missing.obj");
    let report = dir.join("r.json");
    let o = run(&["deviation", s(&good), s(&missing), "--report", s(&report)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.obj"));
    assert!(!report.exists());
    // a file with vertices but no face
    let empty = dir.join("points.obj");
    std::fs::write(&empty, "v 0 0 0\nv 1 0 0\n").unwrap();
    let o = run(&["deviation", s(&empty), s(&good), "--report", s(&report)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("points.obj"));
    assert!(!report.exists());
    // a region face out of range names the region file
    let reg = dir.join("region.json");
    std::fs::write(&reg, r#"{"faces":[100000]}"#).unwrap();
    let o = run(&[
        "deviation",
        s(&good),
        s(&good),
        "--region",
        s(&reg),
        "--report",
        s(&report),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("region.json"));
    assert!(!report.exists());
    // a wrong picture extension
    let o = run(&[
        "deviation",
        s(&good),
        s(&good),
        "--png",
        s(&dir.join("d.jpg")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let help = run(&["deviation", "--help"]);
    ok(&help);
    assert!(String::from_utf8_lossy(&help.stdout).contains("fairline deviation fairline-demo/"));
}

/// A quarter cylinder of radius 2 about the z axis, height 1, as exact
/// rational B-spline surface JSON.
const QUARTER_CYLINDER: &str = r#"{"surfaces":[{"degree_u":2,"degree_v":1,
"knots_u":[0,0,0,1,1,1],"knots_v":[0,0,1,1],
"control_points":[[[2,0,0],[2,0,1]],[[2,2,0],[2,2,1]],[[0,2,0],[0,2,1]]],
"weights":[[1,1],[0.7071067811865476,0.7071067811865476],[1,1]]}]}"#;

/// The plane z = 0 over [−1, 2]² and the surface (u, v, 3u(1 − u)²) over
/// the unit square, whose height peaks at u = 1/3 (4/9): on a grid of 8
/// points per direction the vertices sit at u = k/7 and miss it.
const FLOOR: &str = r#"{"surfaces":[{"degree_u":1,"degree_v":1,"knots_u":[0,0,1,1],"knots_v":[0,0,1,1],
"control_points":[[[-1,-1,0],[-1,2,0]],[[2,-1,0],[2,2,0]]]}]}"#;
const HUMP: &str = r#"{"surfaces":[{"degree_u":3,"degree_v":1,"knots_u":[0,0,0,0,1,1,1,1],"knots_v":[0,0,1,1],
"control_points":[[[0,0,0],[0,1,0]],[[0.3333333333333333,0,1],[0.3333333333333333,1,1]],
[[0.6666666666666666,0,0],[0.6666666666666666,1,0]],[[1,0,0],[1,1,0]]]}]}"#;

#[test]
fn between_two_surface_files_the_peak_is_searched_between_the_vertices() {
    let dir = tmp("deviation-peak");
    let (floor, hump) = (dir.join("floor.json"), dir.join("hump.json"));
    std::fs::write(&floor, FLOOR).unwrap();
    std::fs::write(&hump, HUMP).unwrap();
    let report = dir.join("d.json");
    let out = run(&[
        "deviation",
        s(&floor),
        s(&hump),
        "--grid",
        "8",
        "--report",
        s(&report),
    ]);
    ok(&out);
    let r = json(&report);
    let at = |u: f64| 3.0 * u * (1.0 - u) * (1.0 - u);
    let vertices = r["all"]["max_abs"].as_f64().unwrap();
    assert!((vertices - at(2.0 / 7.0)).abs() < 1e-12, "{r}");
    let peak = &r["peak"];
    assert!(
        (peak["abs"].as_f64().unwrap() - 4.0 / 9.0).abs() < 1e-12,
        "{r}"
    );
    assert!(
        (peak["u"].as_f64().unwrap() - 1.0 / 3.0).abs() < 1e-5,
        "{r}"
    );
    assert_eq!(peak["vertices_max"], r["all"]["max_abs"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("between the vertices the surfaces reach max |d| 4.444e-1"),
        "{stderr}"
    );
    // a mesh measured against surfaces has no peak: its vertices are all
    let mesh = dir.join("hump.obj");
    ok(&run(&["convert", s(&hump), s(&mesh)]));
    ok(&run(&[
        "deviation",
        s(&floor),
        s(&mesh),
        "--report",
        s(&report),
    ]));
    assert!(json(&report).get("peak").is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_surface_reference_is_measured_exactly_not_through_its_tessellation() {
    let dir = tmp("deviation-surface");
    let part = dir.join("cylinder.json");
    std::fs::write(&part, QUARTER_CYLINDER).unwrap();
    // points at radius 2.1 and 1.95 over the quarter: +0.1 and −0.05 away
    let mut text = String::new();
    let mut want = Vec::new();
    for i in 0..12 {
        for j in 0..4 {
            let a = 0.05 + 1.45 * i as f64 / 11.0;
            let r = if (i + j) % 2 == 0 { 2.1 } else { 1.95 };
            text.push_str(&format!(
                "v {} {} {}\n",
                r * a.cos(),
                r * a.sin(),
                0.3 * j as f64
            ));
            want.push(r - 2.0);
        }
    }
    for i in 0..11 {
        for j in 0..3 {
            let k = 4 * i + j + 1;
            text.push_str(&format!(
                "f {} {} {}\nf {} {} {}\n",
                k,
                k + 4,
                k + 5,
                k,
                k + 5,
                k + 1
            ));
        }
    }
    let points = dir.join("points.obj");
    std::fs::write(&points, text).unwrap();
    let (csv, report) = (dir.join("d.csv"), dir.join("d.json"));
    ok(&run(&[
        "deviation",
        s(&part),
        s(&points),
        "--grid",
        "4",
        "--csv",
        s(&csv),
        "--report",
        s(&report),
    ]));
    let r = json(&report);
    assert_eq!(r["method"], "surface-point");
    assert_eq!(r["unrefined"], 0);
    let rows = std::fs::read_to_string(&csv).unwrap();
    for (line, want) in rows.lines().skip(1).zip(&want) {
        let signed: f64 = line.split(',').nth(4).unwrap().parse().unwrap();
        // exact to rounding although a 4 × 4 tessellation is 3 % off
        assert!((signed - want).abs() < 1e-12, "{line}: want {want}");
    }
    // a surface file against itself: zero to rounding
    ok(&run(&[
        "deviation",
        s(&part),
        s(&part),
        "--report",
        s(&report),
    ]));
    assert!(json(&report)["all"]["max_abs"].as_f64().unwrap() < 1e-13);
    // a grid that would tessellate 30 surfaces into 30 × 1000² points is
    // refused before any work, on either side, naming the counts
    let one = QUARTER_CYLINDER
        .strip_prefix(r#"{"surfaces":["#)
        .and_then(|t| t.strip_suffix("]}"))
        .unwrap();
    let many = dir.join("many.json");
    let thirty = vec![one; 30].join(",");
    std::fs::write(&many, format!(r#"{{"surfaces":[{thirty}]}}"#)).unwrap();
    for (before, after) in [(&many, &points), (&points, &many)] {
        let out = run(&[
            "deviation",
            s(before),
            s(after),
            "--grid",
            "1000",
            "--report",
            s(&dir.join("refused.json")),
        ]);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("30 surfaces × 1000² is more than 20000000 points"),
            "{err}"
        );
        assert!(!dir.join("refused.json").exists());
    }
}
