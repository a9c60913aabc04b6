//! Inputs a careless reader accepts silently and values a careless writer
//! writes as infinity. Each test states what a
//! careful reader does with the case (see the module docs of `io::*`).

use fairline::io::{
    MeshFormat, read_soup, read_soup_bytes, write_ply_with_vertex_properties, write_soup,
};
use fairline::{Soup, Vec3};

fn tmp(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!(
        "fairline-reader-defects-{tag}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn err(bytes: &[u8], format: MeshFormat, name: &str) -> String {
    match read_soup_bytes(bytes, format, name) {
        Ok(s) => panic!("{name} was accepted ({} vertices)", s.vertex_count()),
        Err(e) => e.to_string(),
    }
}

fn square() -> Soup {
    Soup::from_polygons(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        &[[0u32, 1, 2], [0, 2, 3]],
    )
}

#[test]
fn cr_only_obj_reads_every_line() {
    let text = "# old Mac\rv 0 0 0\rv 1 0 0\rv 1 1 0\rv 0 1 0\rf 1 2 3\rf 1 3 4\r";
    let soup = read_soup_bytes(text.as_bytes(), MeshFormat::Obj, "mac.obj").unwrap();
    assert_eq!(soup.vertex_count(), 4);
    assert_eq!(soup.face_count(), 2);
    assert_eq!(soup.positions[2], Vec3::new(1.0, 1.0, 0.0));
    // the same with a mix of endings, and OFF with lone CRs
    let mixed = "v 0 0 0\r\nv 1 0 0\rv 1 1 0\nf 1 2 3";
    let soup = read_soup_bytes(mixed.as_bytes(), MeshFormat::Obj, "mixed.obj").unwrap();
    assert_eq!((soup.vertex_count(), soup.face_count()), (3, 1));
    let off = "OFF\r3 1 0\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2\r";
    let soup = read_soup_bytes(off.as_bytes(), MeshFormat::Off, "mac.off").unwrap();
    assert_eq!((soup.vertex_count(), soup.face_count()), (3, 1));
}

#[test]
fn obj_without_vertices_is_refused_naming_the_file() {
    let e = err(b"foo 1 2 3\nbar baz\n", MeshFormat::Obj, "words.obj");
    assert!(e.starts_with("words.obj"), "{e}");
    assert!(e.contains("no vertices found"), "{e}");
    let e = err(b"# only a comment\nusemtl x\n", MeshFormat::Obj, "c.obj");
    assert!(e.contains("no vertices found"), "{e}");
}

#[test]
fn ascii_ply_values_must_fit_their_type() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let ok = format!("{head}0 0 0 255\n1 0 0 0\n0 1 0 7\n3 0 1 2\n");
    read_soup_bytes(ok.as_bytes(), MeshFormat::Ply, "ok.ply").unwrap();
    let bad = format!("{head}0 0 0 255\n1 0 0 300\n0 1 0 7\n3 0 1 2\n");
    let e = err(bad.as_bytes(), MeshFormat::Ply, "c.ply");
    assert!(e.starts_with("c.ply:12"), "{e}");
    assert!(
        e.contains("vertex 1") && e.contains("red") && e.contains("uchar"),
        "{e}"
    );
    let frac = format!("{head}0 0 0 1.5\n1 0 0 0\n0 1 0 7\n3 0 1 2\n");
    assert!(err(frac.as_bytes(), MeshFormat::Ply, "f.ply").contains("vertex 0"));
    let neg = format!("{head}0 0 0 -1\n1 0 0 0\n0 1 0 7\n3 0 1 2\n");
    assert!(err(neg.as_bytes(), MeshFormat::Ply, "n.ply").contains("red"));
    let big_float = format!("{head}0 0 1e39 1\n1 0 0 0\n0 1 0 7\n3 0 1 2\n");
    assert!(err(big_float.as_bytes(), MeshFormat::Ply, "b.ply").contains("property z"));
    // a list length beyond its uchar type, an index beyond int
    let long = format!("{head}0 0 0 1\n1 0 0 0\n0 1 0 7\n256 0 1 2\n");
    assert!(err(long.as_bytes(), MeshFormat::Ply, "l.ply").contains("face 0"));
    let wide = format!("{head}0 0 0 1\n1 0 0 0\n0 1 0 7\n3 0 1 4294967298\n");
    assert!(err(wide.as_bytes(), MeshFormat::Ply, "w.ply").contains("face 0"));
    // rows after the announced ones
    let extra = format!("{head}0 0 0 1\n1 0 0 0\n0 1 0 7\n3 0 1 2\n3 0 2 1\n");
    let e = err(extra.as_bytes(), MeshFormat::Ply, "x.ply");
    assert!(
        e.starts_with("x.ply:15") && e.contains("after the last element"),
        "{e}"
    );
    // trailing blank lines are fine
    let blank = format!("{head}0 0 0 1\n1 0 0 0\n0 1 0 7\n3 0 1 2\n\n \n");
    read_soup_bytes(blank.as_bytes(), MeshFormat::Ply, "blank.ply").unwrap();
}

fn binary_ply(big: bool) -> Vec<u8> {
    let enc = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!("ply\nformat {enc} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n").into_bytes();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            b.extend(if big {
                c.to_be_bytes()
            } else {
                c.to_le_bytes()
            });
        }
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend(if big {
            i.to_be_bytes()
        } else {
            i.to_le_bytes()
        });
    }
    b
}

#[test]
fn bytes_after_binary_ply_data_are_refused() {
    for big in [false, true] {
        let b = binary_ply(big);
        let end = b.len();
        read_soup_bytes(&b, MeshFormat::Ply, "ok.ply").unwrap();
        for tail in [&b"\n"[..], b"\r\n"] {
            let mut t = b.clone();
            t.extend_from_slice(tail);
            read_soup_bytes(&t, MeshFormat::Ply, "nl.ply").unwrap();
        }
        let mut t = b.clone();
        t.extend_from_slice(&[0, 0, 128, 63, 1, 2, 3]);
        let e = err(&t, MeshFormat::Ply, "t.ply");
        assert!(e.starts_with(&format!("t.ply: byte {end}")), "{e}");
        assert!(e.contains("7 bytes after"), "{e}");
    }
}

fn binary_stl(n_announced: u32, triangles: usize) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b.extend(n_announced.to_le_bytes());
    for t in 0..triangles {
        b.extend([0u8; 12]);
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., t as f32]] {
            for c in v {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

#[test]
fn bytes_after_binary_stl_data_are_refused() {
    read_soup_bytes(&binary_stl(2, 2), MeshFormat::Stl, "ok.stl").unwrap();
    let mut nl = binary_stl(2, 2);
    nl.push(b'\n');
    read_soup_bytes(&nl, MeshFormat::Stl, "nl.stl").unwrap();
    // three triangles stored, two announced: the third would be lost
    let e = err(&binary_stl(2, 3), MeshFormat::Stl, "t.stl");
    assert!(e.starts_with("t.stl: byte 184"), "{e}");
    assert!(e.contains("50 bytes after"), "{e}");
    // truncated: still refused naming the triangle
    let mut short = binary_stl(2, 2);
    short.truncate(150);
    assert!(err(&short, MeshFormat::Stl, "s.stl").contains("triangle 1"));
}

#[test]
fn lines_after_the_last_off_face_are_refused() {
    let ok = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# comment\n\n";
    read_soup_bytes(ok.as_bytes(), MeshFormat::Off, "ok.off").unwrap();
    let bad = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n";
    let e = err(bad.as_bytes(), MeshFormat::Off, "x.off");
    assert!(
        e.starts_with("x.off:7") && e.contains("after the last face"),
        "{e}"
    );
}

#[test]
fn stl_output_beyond_f32_range_is_refused_and_nothing_written() {
    let dir = tmp("stl-inf");
    let mut soup = square();
    soup.positions[2] = Vec3::new(1.0, 4e38, 0.0);
    let out = dir.join("big.stl");
    let e = write_soup(&out, &soup).unwrap_err().to_string();
    assert!(e.contains("big.stl") && e.contains("vertex 2"), "{e}");
    assert!(!out.exists(), "nothing may be written");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "no temporary file left"
    );
    // just inside the range: written, and read back finite and equal in f32
    soup.positions[2] = Vec3::new(1.0, f64::from(f32::MAX), 0.0);
    write_soup(&out, &soup).unwrap();
    let back = read_soup(&out).unwrap();
    assert!(back.positions.iter().all(|p| p.is_finite()));
    assert!(back.positions.iter().any(|p| p.y == f64::from(f32::MAX)));
    // PLY and OBJ keep f64 and take the large value exactly
    soup.positions[2] = Vec3::new(1.0, 4e38, 0.0);
    for ext in ["ply", "obj", "off"] {
        let p = dir.join(format!("big.{ext}"));
        write_soup(&p, &soup).unwrap();
        assert_eq!(read_soup(&p).unwrap().positions[2].y, 4e38);
    }
}

#[test]
fn ply_vertex_properties_must_be_finite() {
    let dir = tmp("ply-nan");
    let out = dir.join("k.ply");
    let k = [0.0, 1.0, f64::NAN, 2.0];
    let e = write_ply_with_vertex_properties(&out, &square(), &[("k", &k[..])])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("k.ply") && e.contains("vertex 2") && e.contains("\"k\""),
        "{e}"
    );
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------
// B-spline surfaces: weights (defect 11), file size (defect 9), the file named
// in every content error (defect 10)

fn surface_json(weight: &str) -> String {
    format!(
        r#"{{"degree_u":1,"degree_v":1,"knots_u":[0,0,1,1],"knots_v":[0,0,1,1],
        "control_points":[[[0,0,0],[0,1,0]],[[1,0,0],[1,1,1]]],
        "weights":[[1,1],[{weight},1]]}}"#
    )
}

#[test]
fn tiny_weights_are_refused_at_read_time_naming_the_weight_and_file() {
    use fairline::bspline::BSplineError;
    use fairline::io::{parse_surfaces_json, read_surfaces_json};
    let dir = tmp("weights");
    // sound weights (ratio 1e-6) are read and evaluate finitely
    let ok = parse_surfaces_json(&surface_json("1e-6")).unwrap();
    assert!(ok[0].eval(0.5, 0.5).is_finite());
    for w in ["1e-320", "1e-9", "2.2e-308"] {
        let path = dir.join("w.json");
        std::fs::write(&path, surface_json(w)).unwrap();
        let e = read_surfaces_json(&path).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("w.json"), "{text}");
        assert!(
            text.contains("surface 0") && text.contains("weight (1, 0)"),
            "{text}"
        );
        let inner = parse_surfaces_json(&surface_json(w)).unwrap_err();
        assert!(
            matches!(
                inner,
                fairline::io::SurfaceJsonError::Surface {
                    source: BSplineError::WeightRange { i: 1, j: 0, .. },
                    ..
                }
            ),
            "{inner:?}"
        );
    }
    // all weights equally tiny but subnormal: refused too
    let all = surface_json("1e-320")
        .replace("1,1],[", "1e-320,1e-320],[")
        .replace(",1]]}", ",1e-320]]}");
    assert!(parse_surfaces_json(&all).is_err());
}

#[test]
fn surface_json_over_the_size_limit_is_refused_before_reading() {
    use fairline::io::{MAX_SURFACE_JSON_BYTES, read_surfaces_json};
    let dir = tmp("json-size");
    let path = dir.join("huge.json");
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(MAX_SURFACE_JSON_BYTES + 1).unwrap(); // sparse: costs no disk
    let e = read_surfaces_json(&path).unwrap_err().to_string();
    assert!(e.contains("huge.json") && e.contains("refused"), "{e}");
    let _ = std::fs::remove_file(&path);
}

#[test]
fn surface_json_and_iges_content_errors_name_the_file() {
    use fairline::io::{read_iges, read_surfaces_json};
    let dir = tmp("named");
    let cases: [(&str, &str); 4] = [
        ("syntax.json", "{\"degree_u\": 3,"),
        ("layout.json", "[1, 2]"),
        (
            "field.json",
            r#"{"degree_u":1,"degree_v":1,"knots_u":[0,0,1,1],"knots_v":[0,0,1,1],"control_points":[[[0,0],[0,1,0]],[[1,0,0],[1,1,1]]]}"#,
        ),
        (
            "knots.json",
            r#"{"degree_u":1,"degree_v":1,"knots_u":[0,1,0,1],"knots_v":[0,0,1,1],"control_points":[[[0,0,0],[0,1,0]],[[1,0,0],[1,1,1]]]}"#,
        ),
    ];
    for (name, text) in cases {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        let e = read_surfaces_json(&p).unwrap_err().to_string();
        assert!(e.starts_with(p.to_str().unwrap()), "{e}");
    }
    for (name, text) in [
        ("short.igs", "garbage line\n"),
        ("letter.igs", &format!("{:<72}Z      1\n", "x")),
        ("entity.igs", &format!("{:<72}D      1\n", "     128")),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        let e = read_iges(&p).unwrap_err().to_string();
        assert!(e.starts_with(p.to_str().unwrap()), "{e}");
    }
}
