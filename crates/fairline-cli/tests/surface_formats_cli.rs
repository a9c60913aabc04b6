//! Command-line tests of the B-spline surface formats fairline reads but
//! does not write (GoTools `.g2`, geomdl JSON): `info` reads them,
//! `convert` turns them into STEP or IGES keeping every number, objects
//! that are not read are named, and writing `.g2` is refused before
//! anything is read.

mod common;

use common::{json, ok, run, s, tmp};
use fairline::io::surface_file::read_surface_file;

/// A GoTools file: a rational quarter cylinder of radius 2 and height 3
/// (quadratic in u, linear in v; coefficients (w·x, w·y, w·z, w), u
/// running fastest) and a bilinear patch whose point (i, j) is
/// (10 + i, j, i·j).
fn part_g2() -> String {
    let w = std::f64::consts::FRAC_1_SQRT_2;
    let mut t = String::from("200 1 0 0\n3 1\n3 3\n0 0 0 1 1 1\n2 2\n0 0 1 1\n");
    for z in [0.0, 3.0] {
        t.push_str(&format!("2 0 {z} 1\n"));
        t.push_str(&format!("{} {} {} {w}\n", 2.0 * w, 2.0 * w, z * w));
        t.push_str(&format!("0 2 {z} 1\n"));
    }
    t.push_str("\n200 1 0 0\n3 0\n2 2\n0 0 1 1\n2 2\n0 0 1 1\n");
    t.push_str("10 0 0\n11 0 0\n10 1 0\n11 1 1\n");
    t
}

#[test]
fn gotools_files_are_read_and_converted_to_step() {
    let d = tmp("g2");
    let f = d.join("part.g2");
    std::fs::write(&f, part_g2()).unwrap();

    let o = run(&["info", "--json", s(&f)]);
    ok(&o);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["surfaces"], 2, "{info}");
    assert_eq!(info["rational"], 1, "{info}");
    assert_eq!(info["trimmed"], 0, "{info}");
    let bb = &info["bounding_box"];
    for (k, want) in [0.0, 0.0, 0.0, 11.0, 2.0, 3.0].into_iter().enumerate() {
        let got = bb[k / 3][k % 3].as_f64().unwrap();
        assert!((got - want).abs() < 1e-12, "{info}");
    }

    let out = d.join("part.step");
    let rep = d.join("convert.json");
    ok(&run(&["convert", s(&f), s(&out), "--report", s(&rep)]));
    assert_eq!(json(&rep)["surfaces"], 2);
    let back = read_surface_file(&out).unwrap();
    let orig = read_surface_file(&f).unwrap();
    assert_eq!(back.surfaces, orig.surfaces);
    let cyl = &back.surfaces[0];
    for k in 0..=6 {
        let p = cyl.eval(k as f64 / 6.0, 0.5);
        assert!((p.x.hypot(p.y) - 2.0).abs() < 1e-13, "{p}");
        assert!((p.z - 1.5).abs() < 1e-13, "{p}");
    }
    assert_eq!(
        back.surfaces[1].eval(1.0, 1.0),
        fairline::Vec3::new(11.0, 1.0, 1.0)
    );
}

#[test]
fn gotools_objects_not_read_are_named_and_g2_is_not_written() {
    let d = tmp("g2-unread");
    let f = d.join("part.g2");
    // a curve before the surfaces: listed, the part is incomplete
    let t = format!(
        "100 1 0 0\n3 0\n2 2\n0 0 1 1\n0 0 0\n1 1 1\n\n{}",
        part_g2()
    );
    std::fs::write(&f, t).unwrap();
    let o = run(&["info", "--json", s(&f)]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("object 1 (class 100 SplineCurve, line 1): a curve, not a surface"),
        "{err}"
    );
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["surfaces"], 2);
    assert_eq!(info["unreadable_faces"], 1);

    // writing .g2 is refused before reading (exit 2), nothing written
    let src = d.join("ok.g2");
    std::fs::write(&src, part_g2()).unwrap();
    let out = d.join("out.g2");
    let o = run(&["convert", s(&src), s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("does not write it"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());

    // a malformed file names the line and object
    let bad = d.join("bad.g2");
    std::fs::write(&bad, "200 1 0 0\n3 0\n2 2\n0 0 1\n").unwrap();
    let o = run(&["info", s(&bad)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.g2") && err.contains("object 1 (class 200)"),
        "{err}"
    );
}

/// The geomdl (NURBS-Python) file of the library's tests: a rational
/// quarter cylinder of radius 2 and height 3, and a bicubic.
fn geomdl_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fairline/tests/data/geomdl/cylinder_and_bicubic.json")
}

#[test]
fn geomdl_json_files_are_read_and_converted_to_iges() {
    let d = tmp("geomdl");
    let f = geomdl_file();
    let o = run(&["info", "--json", s(&f)]);
    ok(&o);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["surfaces"], 2, "{info}");
    assert_eq!(info["rational"], 1, "{info}");

    let out = d.join("part.igs");
    ok(&run(&["convert", s(&f), s(&out)]));
    let back = read_surface_file(&out).unwrap();
    assert_eq!(back.surfaces, read_surface_file(&f).unwrap().surfaces);
    // geomdl's evaluate_single at (0.3, 0.7) on the cylinder
    let p = back.surfaces[0].eval(0.3, 0.7);
    let want = [1.7947512999907453, 0.8825348555051692, 2.1];
    for (got, want) in p.to_array().into_iter().zip(want) {
        assert!((got - want).abs() < 1e-12, "{p}");
    }

    // a JSON file of neither schema says which it expected
    let bad = d.join("bad.json");
    std::fs::write(&bad, r#"{"nothing": 1}"#).unwrap();
    let o = run(&["info", s(&bad)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.json") && err.contains("geomdl"), "{err}");
}
