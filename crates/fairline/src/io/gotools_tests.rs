//! Tests of the GoTools reader: coefficient order, projective weights,
//! bounded surfaces, objects listed as unreadable, malformed files.

use super::*;

/// A bilinear-by-quadratic surface (2 × 3 coefficients, u fastest in
/// the file) whose control point (i, j) is (i, j, 10 i + j).
const PLAIN: &str = "200 1 0 0\n3 0\n2 2\n0 0 1 1\n3 2\n0 0 0.5 1 1\n\
    0 0 0\n1 0 10\n0 1 1\n1 1 11\n0 2 2\n1 2 12\n";

/// A quarter of the unit cylinder (rational quadratic in u, linear in
/// v, height 2), coefficients (w·x, w·y, w·z, w).
fn quarter_cylinder() -> String {
    let w = std::f64::consts::FRAC_1_SQRT_2;
    let mut s = String::from("200 1 0 0\n3 1\n3 3\n0 0 0 1 1 1\n2 2\n0 0 1 1\n");
    for z in [0.0, 2.0] {
        s.push_str(&format!("1 0 {z} 1\n"));
        s.push_str(&format!("{w} {w} {} {w}\n", z * w));
        s.push_str(&format!("0 1 {z} 1\n"));
    }
    s
}

#[test]
fn coefficients_run_u_fastest() {
    let imp = parse_gotools(PLAIN).unwrap();
    assert!(imp.unreadable.is_empty());
    let s = &imp.surfaces[0];
    assert_eq!((s.count_u(), s.count_v()), (2, 3));
    assert_eq!((s.degree_u(), s.degree_v()), (1, 1));
    assert_eq!(s.control_point(1, 2), Vec3::new(1.0, 2.0, 12.0));
    assert_eq!(s.control_point(0, 1), Vec3::new(0.0, 1.0, 1.0));
    assert_eq!(s.eval(1.0, 0.0), Vec3::new(1.0, 0.0, 10.0));
    assert_eq!(s.eval(0.0, 1.0), Vec3::new(0.0, 2.0, 2.0));
}

#[test]
fn rational_coefficients_are_projective() {
    let imp = parse_gotools(&quarter_cylinder()).unwrap();
    let s = &imp.surfaces[0];
    let w = std::f64::consts::FRAC_1_SQRT_2;
    assert_eq!(s.weight(1, 1), w);
    assert_eq!(s.control_point(1, 1), Vec3::new(1.0, 1.0, 2.0));
    for k in 0..=8 {
        let p = s.eval(k as f64 / 8.0, 0.25);
        assert!((p.x.hypot(p.y) - 1.0).abs() < 1e-14, "{p}");
        assert!((p.z - 0.5).abs() < 1e-14, "{p}");
    }
}

#[test]
fn bounded_surfaces_read_as_trimmed_and_other_objects_are_listed() {
    // a curve, the plain surface trimmed to the triangle
    // (0,0)-(1,0)-(0,1) by three linear parameter curves (one with a
    // space curve too), a plane (unknown layout: passed), the cylinder
    let line = |a: [f64; 2], b: [f64; 2]| {
        format!("2 0\n2 2\n0 0 1 1\n{} {}\n{} {}\n", a[0], a[1], b[0], b[1])
    };
    let mut t = String::from("100 1 0 0\n3 0\n2 2\n0 0 1 1\n0 0 0\n1 1 1\n\n");
    t.push_str("210 1 0 0\n200\n");
    t.push_str(PLAIN.strip_prefix("200 1 0 0\n").unwrap());
    t.push_str("1\n3 1e-6\n");
    t.push_str(&format!("1 100 0\n{}", line([0.0, 0.0], [1.0, 0.0])));
    t.push_str(&format!(
        "1 100 100\n{}3 0\n2 2\n0 0 1 1\n1 0 10\n0 2 2\n",
        line([1.0, 0.0], [0.0, 1.0])
    ));
    t.push_str(&format!("1 100 0\n{}", line([0.0, 1.0], [0.0, 0.0])));
    t.push_str("250 1 0 0\n3\n0 0 0\n0 0 1\n1 0 0\n0\n");
    t.push_str(&quarter_cylinder());
    let imp = parse_gotools(&t).unwrap();
    assert_eq!(imp.surfaces.len(), 2);
    let s = &imp.surfaces[0];
    assert!(s.is_trimmed());
    assert!(s.contains_uv(0.2, 0.2) && !s.contains_uv(0.8, 0.8));
    assert!(!imp.surfaces[1].is_trimmed());
    let listed: Vec<String> = imp.unreadable.iter().map(|u| u.to_string()).collect();
    assert_eq!(listed.len(), 2, "{listed:?}");
    assert!(listed[0].starts_with("object 1 (class 100 SplineCurve, line 1)"));
    assert!(
        listed[1].contains("object 3 (class 250 Plane"),
        "{listed:?}"
    );
}

#[test]
fn bounded_surfaces_without_parameter_curves_are_listed() {
    let mut t = String::from("210 1 0 0\n200\n");
    t.push_str(PLAIN.strip_prefix("200 1 0 0\n").unwrap());
    t.push_str("1\n1 1e-6\n0 0 100\n3 0\n2 2\n0 0 1 1\n0 0 0\n1 0 10\n");
    t.push_str(&quarter_cylinder());
    let imp = parse_gotools(&t).unwrap();
    assert_eq!(imp.surfaces.len(), 1);
    assert_eq!(imp.unreadable.len(), 1);
    assert!(
        imp.unreadable[0].reason.contains("no parameter curve"),
        "{:?}",
        imp.unreadable
    );
}

#[test]
fn malformed_files_are_refused_with_line_and_object() {
    let cases: &[(&str, &str)] = &[
        (
            "200 1 0 0\n3 0\n2 2\n0 0 1\n",
            "object 1 (class 200): the file ends before knot 3 of 4 in u",
        ),
        ("200 1 0 0\n3 0\n-2 2\n", "coefficient count in u -2"),
        ("200 1 0 0\n3 0\n99999999999 2\n", "more than the"),
        ("200 1 0 0\n3 0\n2 99999999999999999\n", "order in u"),
        ("200 1 0 0\n3 2\n", "rational flag 2"),
        (
            "200 1 0 0\n3 0\n2 2\n0 0 1 nan\n",
            "knot 3 of 4 in u: expected a finite number, found `nan`",
        ),
        (
            "200 1 0 0\n3 1\n2 2\n0 0 1 1\n2 2\n0 0 1 1\n1 0 0 0\n0 0 0 1\n0 0 0 1\n0 0 0 1\n",
            "coefficient 0 of 4: weight 0",
        ),
        (
            "200 1 0 0\n3 0\n2 2\n0 0 1 1\n2 2\n1 0 1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n",
            "object 1 (class 200)",
        ),
        ("x 1 0 0\n", "the class number: expected an integer"),
        ("200 1 0 -3\n", "auxiliary data count -3"),
    ];
    for (text, want) in cases {
        let err = parse_gotools(text).unwrap_err().to_string();
        assert!(err.contains(want), "{text:?}: {err}");
    }
    // every prefix of a valid file fails or reads, never panics
    let full = quarter_cylinder();
    for end in 0..full.len() {
        let _ = parse_gotools(&full[..end]);
    }
}

#[test]
fn reading_a_file_names_it() {
    let dir = std::env::temp_dir().join(format!("fairline-g2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.g2");
    std::fs::write(&p, "200 1 0 0\n3 0\n").unwrap();
    let err = read_gotools(&p).unwrap_err().to_string();
    assert!(err.starts_with(&p.display().to_string()), "{err}");
    std::fs::write(&p, PLAIN).unwrap();
    assert_eq!(read_gotools(&p).unwrap().surfaces.len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}
