//! Command-line tests of the foundation commands: info, convert, curvature,
//! render, demo; exit codes and atomic, non-overwriting outputs.

mod common;
use common::*;

use std::path::Path;

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

const TETRA_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

#[test]
fn help_has_examples_for_every_command() {
    for cmd in ["info", "convert", "curvature", "render", "demo"] {
        let o = run(&[cmd, "--help"]);
        assert!(o.status.success(), "{cmd}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("Example"), "{cmd} --help has no example");
    }
    let o = run(&["no-such-command"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn info_reports_contract_keys_and_defects() {
    let d = tmp("info");
    let f = d.join("tetra.obj");
    write(&f, TETRA_OBJ);
    let o = run(&["info", f.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "vertices",
        "faces",
        "face_sizes",
        "edges",
        "boundary_edges",
        "boundary_loops",
        "non_manifold_edges",
        "components",
        "genus",
        "degenerate_faces",
        "bbox",
        "edge_length",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["vertices"], 4);
    assert_eq!(v["edges"], 6);
    assert_eq!(v["genus"], 0);
    // a non-manifold file is reported, not refused
    let nm = d.join("nm.obj");
    write(
        &nm,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    );
    let o = run(&["info", nm.to_str().unwrap(), "--json"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["non_manifold_edges"], 1);
    assert_eq!(v["genus"], serde_json::Value::Null);
    if let Some(p) = data("meshes/bunny_res4.ply") {
        let o = run(&["info", p.to_str().unwrap(), "--json"]);
        assert!(o.status.success());
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["vertices"], 453);
        assert!(v["non_manifold_edges"].as_u64().unwrap() > 0);
    }
}

#[test]
fn bad_input_exits_with_2_and_names_the_problem() {
    let d = tmp("bad");
    let f = d.join("broken.obj");
    write(&f, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let out = d.join("out.ply");
    let o = run(&[
        "curvature",
        f.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("broken.obj"), "{err}");
    assert!(!out.exists(), "no partial output");
    // missing file
    let o = run(&["info", d.join("missing.ply").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    // garbage PLY
    let g = d.join("garbage.ply");
    write(
        &g,
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n",
    );
    let o = run(&["info", g.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    // bad vector syntax is a usage error
    let o = run(&[
        "render",
        f.to_str().unwrap(),
        "--png",
        "x.png",
        "--view",
        "1,2",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn convert_keeps_quads_and_refuses_to_overwrite_the_input() {
    let d = tmp("convert");
    let f = d.join("quad.obj");
    write(
        &f,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.1 0.2 0.30000000000000004\nf 1 2 3 4\nf 1 4 5\n",
    );
    for ext in ["ply", "off", "obj"] {
        let out = d.join(format!("quad-out.{ext}"));
        let o = run(&["convert", f.to_str().unwrap(), out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o = run(&["info", out.to_str().unwrap(), "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["face_sizes"]["4"], 1, "{ext}");
        assert_eq!(
            v["bbox"]["max"][2], 0.30000000000000004,
            "{ext}: exact coordinates"
        );
    }
    let before = std::fs::read(&f).unwrap();
    let o = run(&["convert", f.to_str().unwrap(), f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&f).unwrap(), before);
}

#[test]
fn curvature_of_a_sphere_file_is_one_over_r() {
    let d = tmp("curv");
    let mesh = fairline::shapes::icosphere(2.0, 3);
    let f = d.join("sphere.obj");
    fairline::io::write_mesh(&f, &mesh).unwrap();
    let out = d.join("k.ply");
    let rep = d.join("r.json");
    let o = run(&[
        "curvature",
        f.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (soup, props) = fairline::io::read_ply_vertex_properties(&out).unwrap();
    assert_eq!(soup.vertex_count(), mesh.vertex_count());
    let names: Vec<&str> = props.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "nx", "ny", "nz", "k1", "k2", "mean", "gauss", "d1x", "d1y", "d1z", "d2x", "d2y", "d2z"
        ]
    );
    let bytes = std::fs::read(&out).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]);
    let order: Vec<&str> = header
        .lines()
        .take_while(|l| !l.starts_with("end_header"))
        .filter_map(|l| l.strip_prefix("property double "))
        .collect();
    assert_eq!(
        &order[..4],
        ["x", "y", "z", "nx"],
        "x y z come first, as doubles"
    );
    let k1 = &props[3].1;
    assert!(k1.iter().all(|k| (k - 0.5).abs() < 1e-6));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(rep).unwrap()).unwrap();
    assert_eq!(r["command"], "curvature");
    assert!(r["time_s"].as_f64().unwrap() >= 0.0);
    // meyer too
    let o = run(&[
        "curvature",
        f.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--method",
        "meyer",
    ]);
    assert!(o.status.success());
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let d = tmp("render");
    let f = d.join("torus.ply");
    fairline::io::write_mesh(&f, &fairline::shapes::torus(1.0, 0.3, 40, 16)).unwrap();
    let png = d.join("t.png");
    let o = run(&[
        "render",
        f.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--scalar",
        "gauss",
        "--size",
        "320x200",
        "--view",
        "0,-1,-1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = fairline::render::Image::decode_png(&std::fs::read(&png).unwrap()).unwrap();
    assert_eq!((img.width, img.height), (320, 200));
}

#[test]
fn demo_writes_pictures_report_and_index() {
    let d = tmp("demo");
    let out = d.join("demo");
    let o = run(&["demo", "--out", out.to_str().unwrap(), "--size", "320x240"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["command"], "demo");
    let err = r["sections"]["Sphere"]["rusinkiewicz_max_abs_error_k1"]
        .as_f64()
        .unwrap();
    assert!(err < 1e-6, "sphere curvature error {err}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for img in [
        "sphere-mean-curvature.png",
        "torus-gauss.png",
        "quad-structure-lines.png",
    ] {
        assert!(html.contains(img));
        assert!(out.join(img).exists());
    }
}
