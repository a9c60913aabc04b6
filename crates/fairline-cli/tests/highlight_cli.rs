//! Command-line tests of `fairline highlight` and `fairline detect`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fairline"))
        .args(args)
        .output()
        .expect("run fairline")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fairline-hl-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn data(rel: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!("skipped: ../shared/data not found");
        None
    }
}

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

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "status {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
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
    let lights = d.join("lights.json");
    std::fs::write(
        &lights,
        r#"{"plane_point":[0,0,3],"plane_normal":[0,0,1],"direction":[1,0,0],"spacing":0.5}"#,
    )
    .unwrap();
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
        vec!["detect", m, "-o", d.join("r.obj").to_str().unwrap()],
        vec!["detect", m, "--threshold", "0", "-o", o_s],
    ] {
        let o = run(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!out.exists(), "{args:?} wrote output");
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
        let o = run(&[
            "detect",
            mesh.to_str().unwrap(),
            "--spacing",
            "0.1",
            "-o",
            out.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        ok(&o);
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
    for rel in ["meshes/bunny_npm.obj", "meshes/spot.ply"] {
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
