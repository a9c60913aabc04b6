//! Command-line tests of `fairline enhance`: report contract, fixed and
//! boundary vertices bit-identical in the written mesh, PNG, exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fairline"))
        .args(args)
        .output()
        .expect("run fairline")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fairline-enhance-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ridge() -> fairline::SurfaceMesh {
    fairline::shapes::height_field(15, 15, (-1.0, 1.0), (-1.0, 1.0), |x, _| {
        0.4 * (-(x / 0.2) * (x / 0.2)).exp()
    })
}

#[test]
fn enhance_writes_mesh_report_and_picture_and_keeps_constraints() {
    let d = tmp("ok");
    let input = d.join("ridge.obj");
    let mesh = ridge();
    fairline::io::write_mesh(&input, &mesh).unwrap();
    let fixed = d.join("fixed.json");
    std::fs::write(&fixed, r#"{"vertices":[40, 112]}"#).unwrap();
    let (out, rep, png) = (d.join("out.ply"), d.join("r.json"), d.join("p.png"));
    let o = run(&[
        "enhance",
        s(&input),
        "--lambda",
        "0.5",
        "--mu",
        "0.5",
        "--iterations",
        "2",
        "--fixed",
        s(&fixed),
        "-o",
        s(&out),
        "--report",
        s(&rep),
        "--png",
        s(&png),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
    assert_eq!(r["command"], "enhance");
    for key in [
        "time_s",
        "flipped_triangles",
        "quality_before",
        "quality_after",
        "max_displacement",
        "histogram_before",
        "histogram_after",
        "timings",
    ] {
        assert!(!r[key].is_null(), "report lacks {key}");
    }
    let hist: u64 = r["histogram_after"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(hist as usize, mesh.face_count());
    assert!(r["max_displacement"].as_f64().unwrap() > 0.0);
    assert!(r["quality_after"]["min"].as_f64().unwrap() > 0.0);

    let result = fairline::io::read_mesh(&out).unwrap();
    let (a, b) = (mesh.positions(), result.positions());
    let mut moved = 0;
    for v in mesh.vertices() {
        let same =
            a[v.idx()].to_array().map(f64::to_bits) == b[v.idx()].to_array().map(f64::to_bits);
        if mesh.is_boundary_vertex(v) || v.0 == 40 || v.0 == 112 {
            assert!(same, "vertex {} moved", v.0);
        } else if !same {
            moved += 1;
        }
    }
    assert!(moved > 50);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
}

#[test]
fn enhance_refuses_bad_input_with_status_2() {
    let d = tmp("bad");
    let input = d.join("ridge.obj");
    fairline::io::write_mesh(&input, &ridge()).unwrap();
    let out = d.join("out.obj");
    let o = run(&["enhance", s(&input), "--lambda", "0", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let fixed = d.join("fixed.json");
    std::fs::write(&fixed, r#"{"vertices":[100000]}"#).unwrap();
    let o = run(&["enhance", s(&input), "--fixed", s(&fixed), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::write(&fixed, r#"{"faces":[1]}"#).unwrap();
    let o = run(&["enhance", s(&input), "--fixed", s(&fixed), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let quads = d.join("quads.obj");
    let q = fairline::shapes::quad_grid(4, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
    fairline::io::write_mesh(&quads, &q).unwrap();
    let o = run(&["enhance", s(&quads), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["enhance", s(&input), "-o", s(&input)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists(), "no output after a failure");
    let o = run(&["enhance", "--help"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Example"));
}
