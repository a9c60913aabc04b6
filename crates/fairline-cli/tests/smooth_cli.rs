//! Command-line tests of `fairline smooth` and `fairline fair-quad`.

mod common;
use common::*;

use std::fmt::Write as _;
use std::path::Path;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn read_obj_vertices(p: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// n×n quad grid of a saddle with a planted zigzag across the lines.
fn zigzag_quads(n: usize) -> String {
    let mut out = String::new();
    let h = 2.0 / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let mut x = -1.0 + h * i as f64;
            let y = -1.0 + h * j as f64;
            if i > 0 && j > 0 && i < n - 1 && j < n - 1 {
                x += if j % 2 == 0 { 0.2 * h } else { -0.2 * h };
            }
            writeln!(out, "v {x} {y} {}", 0.4 * (x * x - y * y)).unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            writeln!(out, "f {} {} {} {}", a, a + 1, a + 1 + n, a + n).unwrap();
        }
    }
    out
}

#[test]
fn fair_quad_straightens_a_zigzag_grid_keeps_fixed_vertices_and_writes_a_picture() {
    let d = tmp("fq");
    let input = d.join("zz.obj");
    std::fs::write(&input, zigzag_quads(10)).unwrap();
    std::fs::write(d.join("fixed.json"), r#"{"vertices":[33,56]}"#).unwrap();
    let out = d.join("out.obj");
    let rep = d.join("r.json");
    let png = d.join("cmp.png");
    let o = run(&[
        "fair-quad",
        s(&input),
        "-o",
        s(&out),
        "--fixed",
        s(&d.join("fixed.json")),
        "--report",
        s(&rep),
        "--png",
        s(&png),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = json(&rep);
    for k in [
        "command",
        "time_s",
        "structure_lines",
        "free_vertices",
        "structure_energy_before",
        "structure_energy_after",
        "max_displacement",
    ] {
        assert!(r.get(k).is_some(), "missing {k}");
    }
    assert_eq!(r["structure_lines"], 20);
    let (e0, e1) = (
        r["structure_energy_before"].as_f64().unwrap(),
        r["structure_energy_after"].as_f64().unwrap(),
    );
    assert!(e1 < 0.01 * e0, "{e0} → {e1}");
    let a = read_obj_vertices(&input);
    let b = read_obj_vertices(&out);
    for v in [33, 56, 0, 9, 90, 99] {
        assert_eq!(a[v], b[v], "vertex {v}");
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // the thesis' method as printed (points may leave the surface) is a
    // different result
    let off = d.join("off.obj");
    let o = run(&["fair-quad", s(&input), "-o", s(&off), "--off-surface"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_ne!(read_obj_vertices(&off), b);
}

/// n×n quad grid of a saddle with a height zigzag (±a) across the lines.
fn height_zigzag_quads(n: usize, a: f64) -> String {
    let mut out = String::new();
    let h = 2.0 / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (-1.0 + h * i as f64, -1.0 + h * j as f64);
            let inner = i > 0 && j > 0 && i < n - 1 && j < n - 1;
            let dz = if inner && (i + j) % 2 == 0 {
                a * h
            } else {
                0.0
            };
            writeln!(out, "v {x} {y} {}", 0.4 * (x * x - y * y) + dz).unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            writeln!(out, "f {} {} {} {}", a, a + 1, a + 1 + n, a + n).unwrap();
        }
    }
    out
}

/// `fair-quad --method network` (Grüner §3.1.1): only the heights move,
/// each by at most the tolerance h·ē; the network's bending energy falls;
/// fixed and (with --fix-boundary) boundary vertices stay bit-identical.
#[test]
fn fair_quad_network_moves_heights_within_their_tolerance_cylinders() {
    let d = tmp("fq-network");
    let input = d.join("zz.obj");
    std::fs::write(&input, height_zigzag_quads(10, 0.3)).unwrap();
    std::fs::write(d.join("fixed.json"), r#"{"vertices":[44]}"#).unwrap();
    let out = d.join("out.obj");
    let rep = d.join("r.json");
    let o = run(&[
        "fair-quad",
        s(&input),
        "--method",
        "network",
        "--tolerance",
        "0.2",
        "--fix-boundary",
        "--fixed",
        s(&d.join("fixed.json")),
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&rep);
    assert_eq!(r["method"], "network");
    let (e0, e1) = (
        r["network_energy_before"].as_f64().unwrap(),
        r["network_energy_after"].as_f64().unwrap(),
    );
    assert!(e1 < 0.5 * e0, "{e0} → {e1}");
    assert!(r["at_bound"].as_u64().unwrap() > 0);
    // the structure-line energy is another measure: where it rose, the
    // report and stderr say so
    let rose = r["structure_energy_after"].as_f64().unwrap()
        > r["structure_energy_before"].as_f64().unwrap();
    let warned = r["warnings"].as_array().is_some_and(|w| {
        w.iter().any(|m| {
            m.as_str()
                .unwrap_or("")
                .contains("structure-line energy got worse")
        })
    });
    assert_eq!(rose, warned, "{r}");
    assert_eq!(rose, stderr(&o).contains("structure-line energy got worse"));
    let (a, b) = (read_obj_vertices(&input), read_obj_vertices(&out));
    let ebar = 2.0 / 9.0; // the grid spacing; slopes make edges up to 1.5× longer
    for (v, (p, q)) in a.iter().zip(&b).enumerate() {
        assert_eq!(p[0].to_bits(), q[0].to_bits());
        assert_eq!(p[1].to_bits(), q[1].to_bits());
        assert!((p[2] - q[2]).abs() <= 0.2 * 1.5 * ebar, "vertex {v}");
        let (i, j) = (v % 10, v / 10);
        if v == 44 || i == 0 || j == 0 || i == 9 || j == 9 {
            assert_eq!(p[2].to_bits(), q[2].to_bits(), "vertex {v}");
        }
    }
    // a tolerance of 0 holds everything
    let o = run(&[
        "fair-quad",
        s(&input),
        "--method",
        "network",
        "--tolerance",
        "0",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read_obj_vertices(&out), a);
    let o = run(&[
        "fair-quad",
        s(&input),
        "--method",
        "network",
        "--tolerance",
        "-1",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn smooth_methods_run_from_the_command_line_with_their_report_keys() {
    let d = tmp("methods");
    let input = d.join("zz.obj");
    std::fs::write(&input, zigzag_quads(8)).unwrap();
    // triangle-only methods get the triangulated grid
    let tri = d.join("tri.obj");
    assert!(run(&["convert", s(&input), s(&tri)]).status.success());
    let mut t = String::new();
    for l in std::fs::read_to_string(&input).unwrap().lines() {
        if let Some(f) = l.strip_prefix("f ") {
            let v: Vec<&str> = f.split_whitespace().collect();
            writeln!(
                t,
                "f {} {} {}\nf {} {} {}",
                v[0], v[1], v[2], v[0], v[2], v[3]
            )
            .unwrap();
        } else {
            writeln!(t, "{l}").unwrap();
        }
    }
    std::fs::write(&tri, t).unwrap();
    for (method, mesh, extra) in [
        ("laplace", &input, vec!["--weights", "edge"]),
        ("taubin", &input, vec!["--pass-band", "0.1"]),
        ("implicit", &tri, vec!["--time-step", "2", "--fix-boundary"]),
        ("spring", &input, vec![]),
        ("schneider-kobbelt", &tri, vec!["--iterations", "5"]),
    ] {
        let out = d.join(format!("{method}.obj"));
        let rep = d.join(format!("{method}.json"));
        let mut args = vec![
            "smooth",
            s(mesh),
            "--method",
            method,
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ];
        args.extend(extra);
        let o = run(&args);
        assert!(
            o.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let r = json(&rep);
        for k in [
            "command",
            "time_s",
            "iterations",
            "volume_before",
            "volume_after",
            "max_displacement",
        ] {
            assert!(r.get(k).is_some(), "{method}: missing {k}");
        }
        assert!(
            r["max_displacement"].as_f64().unwrap() > 0.0,
            "{method} moved nothing"
        );
        if method == "taubin" {
            let (l, m) = (r["lambda"].as_f64().unwrap(), r["mu"].as_f64().unwrap());
            assert!((1.0 / l + 1.0 / m - 0.1).abs() < 1e-12);
            assert_eq!(r["transfer"].as_array().unwrap().len(), 21);
        }
    }
}

#[test]
fn smooth_preserves_volume_of_a_real_closed_mesh() {
    let Some(spot) = data("meshes/spot.ply") else {
        return;
    };
    let d = tmp("vol");
    let out = d.join("spot.ply");
    let rep = d.join("r.json");
    let o = run(&[
        "smooth",
        s(&spot),
        "--method",
        "laplace",
        "--iterations",
        "20",
        "--preserve-volume",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = json(&rep);
    let (v0, v1) = (
        r["volume_before"].as_f64().unwrap(),
        r["volume_after"].as_f64().unwrap(),
    );
    assert!(((v1 - v0) / v0).abs() < 1e-9, "{v0} {v1}");
    // without it Laplace shrinks the real mesh
    let o = run(&[
        "smooth",
        s(&spot),
        "--method",
        "laplace",
        "--iterations",
        "20",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success());
    let r = json(&rep);
    assert!(r["volume_after"].as_f64().unwrap() < 0.99 * r["volume_before"].as_f64().unwrap());
}

/// Above 20,000 free vertices `fair-quad` solves each iteration by
/// line-preconditioned conjugate gradients instead of Cholesky: on a
/// 160 × 160 zigzag grid the structure lines are still straightened (Eq. (30)
/// energy down more than 100×) and fixed vertices and corners are written
/// back bit-identical.
#[test]
fn fair_quad_on_a_large_grid_takes_the_iterative_path() {
    let n = 160;
    let d = tmp("fq-large");
    let input = d.join("zz.obj");
    std::fs::write(&input, zigzag_quads(n)).unwrap();
    std::fs::write(d.join("fixed.json"), r#"{"vertices":[1000,12345]}"#).unwrap();
    let out = d.join("out.obj");
    let rep = d.join("r.json");
    let o = run(&[
        "fair-quad",
        s(&input),
        "-o",
        s(&out),
        "--fixed",
        s(&d.join("fixed.json")),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = json(&rep);
    assert!(r["free_vertices"].as_u64().unwrap() > 20_000, "{r}");
    let (e0, e1) = (
        r["structure_energy_before"].as_f64().unwrap(),
        r["structure_energy_after"].as_f64().unwrap(),
    );
    assert!(e1 < 0.01 * e0, "{e0} → {e1}");
    let a = read_obj_vertices(&input);
    let b = read_obj_vertices(&out);
    assert_eq!(a.len(), b.len());
    assert!(b.iter().flatten().all(|x| x.is_finite()));
    for v in [1000, 12345, 0, n - 1, n * (n - 1), n * n - 1] {
        assert_eq!(a[v], b[v], "vertex {v}");
    }
}

#[test]
fn fair_quad_on_the_real_quad_meshes() {
    for f in ["quads/quadmesh.obj", "quads/hypar.obj"] {
        let Some(p) = data(f) else { return };
        let d = tmp("real");
        let out = d.join("out.obj");
        let rep = d.join("r.json");
        let o = run(&[
            "fair-quad",
            s(&p),
            "--deviation",
            "0.005",
            "--fix-boundary",
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ]);
        assert!(
            o.status.success(),
            "{f}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let r = json(&rep);
        let (e0, e1) = (
            r["structure_energy_before"].as_f64().unwrap(),
            r["structure_energy_after"].as_f64().unwrap(),
        );
        assert!(e1 <= e0, "{f}: {e0} → {e1}");
        assert!(r["structure_lines"].as_u64().unwrap() >= 18, "{f}");
        // same vertex count, finite coordinates
        let a = read_obj_vertices(&p);
        let b = read_obj_vertices(&out);
        assert_eq!(a.len(), b.len());
        assert!(b.iter().flatten().all(|x| x.is_finite()));
    }
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let d = tmp("bad");
    let input = d.join("zz.obj");
    std::fs::write(&input, zigzag_quads(6)).unwrap();
    let out = d.join("out.obj");
    let bad_fixed = d.join("fixed.json");
    std::fs::write(&bad_fixed, r#"{"vertices":[1, 500]}"#).unwrap();
    let garbage = d.join("garbage.json");
    std::fs::write(&garbage, "{not json").unwrap();
    let broken = d.join("broken.obj");
    std::fs::write(&broken, "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    let missing = d.join("missing.obj");
    let cases: Vec<Vec<&str>> = vec![
        vec!["smooth", s(&input), "-o", s(&out), "--fixed", s(&bad_fixed)],
        vec!["smooth", s(&input), "-o", s(&out), "--fixed", s(&garbage)],
        vec!["smooth", s(&input), "-o", s(&out), "--method", "implicit"],
        vec![
            "smooth",
            s(&input),
            "-o",
            s(&out),
            "--method",
            "laplace",
            "--weights",
            "cotan",
        ],
        vec!["smooth", s(&input), "-o", s(&out), "--preserve-volume"],
        vec![
            "smooth",
            s(&input),
            "-o",
            s(&out),
            "--method",
            "taubin",
            "--pass-band",
            "1.5",
        ],
        vec!["smooth", s(&input), "-o", s(&out), "--lambda", "inf"],
        vec!["smooth", s(&input), "-o", s(&out), "--iterations", "0"],
        vec!["smooth", s(&input), "-o", s(&input)],
        vec!["smooth", s(&broken), "-o", s(&out)],
        vec!["smooth", s(&missing), "-o", s(&out)],
        vec!["smooth", s(&input), "-o", s(&out), "--method", "nope"],
        vec!["fair-quad", s(&input), "-o", s(&out), "--weight", "-1"],
        vec![
            "fair-quad",
            s(&input),
            "-o",
            s(&out),
            "--deviation-factor",
            "0",
        ],
        vec![
            "fair-quad",
            s(&input),
            "-o",
            s(&out),
            "--fixed",
            s(&bad_fixed),
        ],
        vec!["fair-quad", s(&broken), "-o", s(&out)],
    ];
    for args in cases {
        let o = run(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            !String::from_utf8_lossy(&o.stderr).trim().is_empty(),
            "{args:?}: no message"
        );
        assert!(!out.exists(), "{args:?} wrote output");
    }
    // a triangle mesh has no quads for fair-quad
    let tri = d.join("tri.obj");
    std::fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = run(&["fair-quad", s(&tri), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("quad"));
    for cmd in ["smooth", "fair-quad"] {
        let o = run(&[cmd, "--help"]);
        assert!(o.status.success() && String::from_utf8_lossy(&o.stdout).contains("Example"));
    }
}

/// An unstable step is a failure (exit 1, nothing written), never
/// "converged" with coordinates near 1e306.
#[test]
fn a_diverging_smoothing_exits_1_and_writes_nothing() {
    let dir = tmp("smooth-diverged");
    let mut text = String::new();
    let n = 8;
    for j in 0..n {
        for i in 0..n {
            let _ = writeln!(text, "v {i} {j} {}", ((i * 7 + j * 3) % 5) as f64 * 0.1);
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            let _ = writeln!(
                text,
                "f {a} {} {}\nf {a} {} {}",
                a + 1,
                a + n + 1,
                a + n + 1,
                a + n
            );
        }
    }
    let input = dir.join("grid.obj");
    std::fs::write(&input, text).unwrap();
    for lambda in ["1e308", "1e6"] {
        let out = dir.join("out.obj");
        let report = dir.join("r.json");
        let o = run(&[
            "smooth",
            s(&input),
            "--method",
            "laplace",
            "--weights",
            "cotan",
            "--lambda",
            lambda,
            "-o",
            s(&out),
            "--report",
            s(&report),
        ]);
        assert_eq!(
            o.status.code(),
            Some(1),
            "lambda {lambda}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(String::from_utf8_lossy(&o.stderr).contains("diverged"));
        assert!(!out.exists() && !report.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Schneider–Kobbelt on closed meshes from the command line: a noisy
/// sphere converges (exit 0, `stop_reason` "converged"); a noisy torus and
/// the cow "Spot" (nothing fixed, so nothing anchors Δ_B H = 0) stop
/// unconverged within seconds, exit 1 with the reason on stderr and in
/// the report, the result written for inspection.
#[test]
fn schneider_kobbelt_on_closed_meshes_converges_or_exits_1_with_its_reason() {
    let d = tmp("sk-closed");
    let mut sphere = fairline::shapes::icosphere(1.0, 3);
    for (i, p) in sphere.positions_mut().iter_mut().enumerate() {
        *p *= 1.0 + 0.02 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
    }
    let mut torus = fairline::shapes::torus(1.0, 0.4, 48, 16);
    for (i, p) in torus.positions_mut().iter_mut().enumerate() {
        let w = |k: usize| ((i * 7919 + k * 104729) % 17) as f64 / 8.0 - 1.0;
        *p += 0.01 * fairline::Vec3::new(w(1), w(2), w(3));
    }
    let (sphere_path, torus_path) = (d.join("sphere.obj"), d.join("torus.obj"));
    fairline::io::write_mesh(&sphere_path, &sphere).unwrap();
    fairline::io::write_mesh(&torus_path, &torus).unwrap();
    let smooth = |input: &Path, name: &str| {
        let (out, rep) = (
            d.join(format!("{name}-smooth.obj")),
            d.join(format!("{name}.json")),
        );
        let t = std::time::Instant::now();
        let o = run(&[
            "smooth",
            s(input),
            "--method",
            "schneider-kobbelt",
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ]);
        let seconds = t.elapsed().as_secs_f64();
        eprintln!("{name}: exit {:?} in {seconds:.1} s", o.status.code());
        assert!(out.exists(), "{name}: {}", stderr(&o));
        (o, json(&rep), seconds)
    };
    let (o, r, _) = smooth(&sphere_path, "sphere");
    ok(&o);
    assert_eq!(r["stop_reason"], "converged", "{r}");
    assert_eq!(r["converged"], true);
    let mut closed = vec![(torus_path, "torus")];
    if let Some(spot) = data("meshes/spot.ply") {
        closed.push((spot, "spot"));
    }
    for (path, name) in closed {
        let (o, r, seconds) = smooth(&path, name);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {e}");
        let reason = r["stop_reason"].as_str().unwrap().to_string();
        assert!(
            [
                "stagnated",
                "diverged",
                "no_descent",
                "work_limit",
                "max_iterations"
            ]
            .contains(&reason.as_str()),
            "{name}: {r}"
        );
        assert_eq!(r["converged"], false);
        assert!(
            e.contains("stopped unconverged") && e.contains(&format!("({reason})")),
            "{name}: {e}"
        );
        assert!(
            r["warnings"][0]
                .as_str()
                .unwrap()
                .contains("stopped unconverged"),
            "{name}: {r}"
        );
        assert!(seconds < 60.0, "{name}: {seconds} s");
    }
    let _ = std::fs::remove_dir_all(&d);
}
