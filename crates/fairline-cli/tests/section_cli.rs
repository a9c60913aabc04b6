//! `fairline section`: a sphere cut by a horizontal plane is one closed
//! circle whose curvature is 1/radius (within the curvature estimate's
//! error) and whose comb teeth are scale × curvature long; bad input exits
//! 2 with nothing written. Iso-curves of a B-spline cylinder have the
//! closed-form curvature 1/radius along its circles and none along its
//! rulings.

mod common;
use common::{json, ok, run, s, tmp};
use fairline::shapes;

#[test]
fn sphere_section_is_a_circle_with_comb_scale_over_radius() {
    let dir = tmp("section-sphere");
    let mesh = dir.join("sphere.obj");
    fairline::io::write_mesh(&mesh, &shapes::icosphere(2.0, 4)).unwrap();
    let (csv, obj, report) = (dir.join("s.csv"), dir.join("s.obj"), dir.join("s.json"));
    ok(&run(&[
        "section",
        s(&mesh),
        "--plane-point",
        "0,0,0.7",
        "--plane-normal",
        "0,0,1",
        "--count",
        "2",
        "--spacing",
        "-0.4",
        "--comb-scale",
        "0.5",
        "--csv",
        s(&csv),
        "--obj",
        s(&obj),
        "--report",
        s(&report),
    ]));
    let r = json(&report);
    let sections = r["sections"].as_array().unwrap();
    assert_eq!(sections.len(), 2);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut rows = 0;
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let (x, y, z, k) = (v[3], v[4], v[5], v[6]);
        let c = if v[0] == 0.0 { 0.7 } else { 0.3 };
        assert!((z - c).abs() < 1e-9, "{line}");
        let rho = (x * x + y * y).sqrt();
        let want = (4.0f64 - c * c).sqrt();
        assert!((rho - want).abs() < 0.01 * want, "{rho} vs {want}");
        assert!(
            (k * want - 1.0).abs() < 0.05,
            "curvature {k} at radius {want}"
        );
        let comb = (v[7] * v[7] + v[8] * v[8] + v[9] * v[9]).sqrt();
        assert!((comb - 0.5 * k).abs() < 1e-9, "comb {comb}");
        // outward: away from the axis
        assert!(v[7] * x + v[8] * y > 0.0, "{line}");
        rows += 1;
    }
    let mut points = 0;
    for sec in sections {
        let curves = sec["curves"].as_array().unwrap();
        assert_eq!(curves.len(), 1);
        assert_eq!(curves[0]["closed"], true);
        points += curves[0]["points"].as_u64().unwrap() as usize;
    }
    assert_eq!(rows, points);
    let obj_text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        obj_text.lines().filter(|l| l.starts_with("l ")).count(),
        2 + points
    );
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tmp("section-bad");
    let mesh = dir.join("sphere.obj");
    fairline::io::write_mesh(&mesh, &shapes::icosphere(1.0, 1)).unwrap();
    let csv = dir.join("s.csv");
    for args in [
        vec!["--plane-point", "0,0,0", "--plane-normal", "0,0,0"],
        vec![
            "--plane-point",
            "0,0,0",
            "--plane-normal",
            "0,0,1",
            "--count",
            "0",
        ],
    ] {
        let mut all = vec!["section", s(&mesh)];
        all.extend(args);
        all.extend(["--csv", s(&csv)]);
        let o = run(&all);
        assert_eq!(o.status.code(), Some(2), "{all:?}");
        assert!(!csv.exists());
    }
    let missing = dir.join("nope.obj");
    let o = run(&[
        "section",
        s(&missing),
        "--plane-point",
        "0,0,0",
        "--plane-normal",
        "0,0,1",
        "--csv",
        s(&csv),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nope.obj"));
    assert!(!csv.exists());
}

/// A quarter cylinder of radius 2 about the z axis, height 1: rational
/// quadratic circles in u, straight rulings in v.
const QUARTER_CYLINDER: &str = r#"{"surfaces":[{"degree_u":2,"degree_v":1,
"knots_u":[0,0,0,1,1,1],"knots_v":[0,0,1,1],
"control_points":[[[2,0,0],[2,0,1]],[[2,2,0],[2,2,1]],[[0,2,0],[0,2,1]]],
"weights":[[1,1],[0.7071067811865476,0.7071067811865476],[1,1]]}]}"#;

#[test]
fn iso_curves_of_a_cylinder_have_the_closed_form_combs() {
    let dir = tmp("section-iso");
    let part = dir.join("cylinder.json");
    std::fs::write(&part, QUARTER_CYLINDER).unwrap();
    let (csv, obj, report) = (dir.join("c.csv"), dir.join("c.obj"), dir.join("c.json"));
    let o = run(&[
        "section",
        s(&part),
        "--iso",
        "3",
        "--samples",
        "40",
        "--comb-scale",
        "0.5",
        "--csv",
        s(&csv),
        "--obj",
        s(&obj),
        "--report",
        s(&report),
    ]);
    ok(&o);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("6 iso-curve(s) of 240 points on 1 surface(s)"),
        "{stderr}"
    );
    let r = json(&report);
    assert_eq!(r["iso"]["curves"], 6);
    assert!((r["iso"]["max_curvature"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("surface,kind,value,curve,point,t,x,y,z,curvature,comb_x"));
    let mut rows = 0;
    for line in text.lines().skip(1) {
        let w: Vec<&str> = line.split(',').collect();
        let v: Vec<f64> = w.iter().map(|x| x.parse().unwrap_or(f64::NAN)).collect();
        let (x, y, k) = (v[6], v[7], v[9]);
        assert!((x.hypot(y) - 2.0).abs() < 1e-12, "on the cylinder: {line}");
        let comb = [v[10], v[11], v[12]];
        match w[1] {
            // u held: a ruling, straight
            "u" => assert!(k == 0.0 && comb == [0.0, 0.0, 0.0], "{line}"),
            // v held: a circle of radius 2, the comb outward, 0.5 × κ long
            "v" => {
                assert!((k - 0.5).abs() < 1e-12, "{line}");
                assert!((comb[0] - 0.125 * x).abs() < 1e-12, "{line}");
                assert!((comb[1] - 0.125 * y).abs() < 1e-12, "{line}");
                assert!(comb[2].abs() < 1e-12, "{line}");
            }
            other => panic!("kind {other}"),
        }
        rows += 1;
    }
    assert_eq!(rows, 240);
    let obj_text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        obj_text.lines().filter(|l| l.starts_with("l ")).count(),
        6 + 240
    );
}

/// `--png`: the part with its curves and combs; with the automatic scale
/// the teeth (magenta) show, with `--comb-scale 0` none do.
#[test]
fn iso_comb_picture_draws_the_teeth() {
    let dir = tmp("section-iso-png");
    let part = dir.join("cylinder.json");
    std::fs::write(&part, QUARTER_CYLINDER).unwrap();
    let magenta = |scale: Option<&str>| {
        let png = dir.join("combs.png");
        let mut args = vec!["section", s(&part), "--iso", "4", "--png", s(&png)];
        args.extend(["--size", "400x300"]);
        if let Some(c) = scale {
            args.extend(["--comb-scale", c]);
        }
        let o = run(&args);
        ok(&o);
        let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
        assert_eq!((img.width, img.height), (400, 300));
        let mut n = 0;
        for y in 0..img.height {
            for x in 0..img.width {
                let [r, g, b, _] = img.get(x, y).unwrap();
                if r as i32 > g as i32 + 60 && b as i32 > g as i32 + 30 {
                    n += 1;
                }
            }
        }
        n
    };
    let (auto, none) = (magenta(None), magenta(Some("0")));
    assert!(auto > 300, "teeth drawn: {auto} pixels");
    assert!(none < auto / 20, "no teeth at scale 0: {none} vs {auto}");
}

#[test]
fn iso_combs_refuse_meshes_and_bad_counts_and_write_nothing() {
    let dir = tmp("section-iso-bad");
    let mesh = dir.join("sphere.obj");
    fairline::io::write_mesh(&mesh, &shapes::icosphere(1.0, 1)).unwrap();
    let part = dir.join("cylinder.json");
    std::fs::write(&part, QUARTER_CYLINDER).unwrap();
    let csv = dir.join("c.csv");
    for (input, extra, says) in [
        (&mesh, vec!["--iso", "3"], "--iso is for B-spline surfaces"),
        (&part, vec!["--iso", "0"], "--iso 0"),
        (&part, vec!["--iso", "3", "--samples", "1"], "--samples 1"),
        (
            &part,
            vec!["--iso", "3", "--surface", "4"],
            "--surface 4 is out of range",
        ),
        (
            &part,
            vec!["--iso", "3", "--plane-point", "0,0,0"],
            "cannot be used with",
        ),
        (&part, vec!["--samples", "10"], "--iso"),
    ] {
        let mut all = vec!["section", s(input)];
        all.extend(extra);
        all.extend(["--csv", s(&csv)]);
        let o = run(&all);
        assert_eq!(o.status.code(), Some(2), "{all:?}");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(says), "{all:?}: {stderr}");
        assert!(!csv.exists());
    }
}
