//! Command-line tests of `fairline enhance`: report contract, fixed
//! vertices bit-identical and boundary vertices on the boundary in the
//! written mesh, PNG, exit codes.

mod common;
use common::*;

use std::path::Path;

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
        "max_distance_to_input",
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
        let (p, q) = (a[v.idx()], b[v.idx()]);
        if v.0 == 40 || v.0 == 112 {
            assert!(same, "vertex {} moved", v.0);
        } else if mesh.is_boundary_vertex(v) {
            // boundary vertices slide along the boundary only
            if (p.x.abs() - 1.0).abs() < 1e-12 {
                assert!(
                    (q.x - p.x).abs() < 1e-12 && (q.z - p.z).abs() < 1e-12,
                    "{p} -> {q}"
                );
            } else {
                assert!((q.y - p.y).abs() < 1e-12, "{p} -> {q}");
            }
        } else if !same {
            moved += 1;
        }
    }
    assert!(moved > 50);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
}

/// Runs `fairline enhance` with `args` and the outputs of folder `d`, and
/// checks status 2, a message naming `names`, and that nothing was written.
fn refused(d: &Path, args: &[&str], names: &str) {
    let (out, rep, png) = (d.join("out.obj"), d.join("r.json"), d.join("p.png"));
    let mut all = vec!["enhance"];
    all.extend_from_slice(args);
    let has = |flag: &str| args.contains(&flag);
    if !has("-o") {
        all.extend_from_slice(&["-o", s(&out)]);
    }
    if !has("--report") {
        all.extend_from_slice(&["--report", s(&rep)]);
    }
    if !has("--png") {
        all.extend_from_slice(&["--png", s(&png)]);
    }
    let o = run(&all);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(names),
        "{args:?}: message `{err}` lacks `{names}`"
    );
    for p in [&out, &rep, &png] {
        assert!(
            !p.exists(),
            "{args:?}: {} written after a failure",
            p.display()
        );
    }
}

#[test]
fn enhance_refuses_bad_input_with_status_2_and_writes_nothing() {
    let d = tmp("bad");
    let input = d.join("ridge.obj");
    fairline::io::write_mesh(&input, &ridge()).unwrap();
    let i = s(&input);
    // options out of range
    refused(&d, &[i, "--lambda", "0"], "lambda");
    refused(&d, &[i, "--lambda", "NaN"], "lambda");
    refused(&d, &[i, "--mu=-1"], "mu");
    refused(&d, &[i, "--iterations", "0"], "iterations");
    refused(&d, &[i, "--lambda", "abc"], "lambda");
    refused(&d, &[i, "--solver", "lu"], "solver");
    // fixed-vertex files: index out of range, wrong key, broken JSON
    let fixed = d.join("fixed.json");
    std::fs::write(&fixed, r#"{"vertices":[100000]}"#).unwrap();
    refused(&d, &[i, "--fixed", s(&fixed)], "fixed.json");
    refused(&d, &[i, "--fixed", s(&fixed)], "100000");
    std::fs::write(&fixed, r#"{"faces":[1]}"#).unwrap();
    refused(&d, &[i, "--fixed", s(&fixed)], "fixed.json");
    std::fs::write(&fixed, r#"{"vertices":[1, -2]}"#).unwrap();
    refused(&d, &[i, "--fixed", s(&fixed)], "fixed.json");
    std::fs::write(&fixed, r#"{"vertices":[1,"#).unwrap();
    refused(&d, &[i, "--fixed", s(&fixed)], "fixed.json");
    refused(&d, &[i, "--fixed", s(&d.join("none.json"))], "none.json");
    // meshes: quads, missing file, broken file
    let quads = d.join("quads.obj");
    let q = fairline::shapes::quad_grid(4, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
    fairline::io::write_mesh(&quads, &q).unwrap();
    refused(&d, &[s(&quads)], "triangle");
    refused(&d, &[s(&d.join("missing.obj"))], "missing.obj");
    let broken = d.join("broken.obj");
    std::fs::write(&broken, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    refused(&d, &[s(&broken)], "broken.obj");
    // outputs: over the input, wrong picture type, missing folder
    refused(&d, &[i, "-o", i], "ridge.obj");
    refused(&d, &[i, "--png", s(&d.join("p.jpg"))], "p.jpg");
    let nowhere = d.join("no-such-folder").join("out.obj");
    refused(&d, &[i, "-o", s(&nowhere)], "no-such-folder");
    let nowhere = d.join("no-such-folder").join("r.json");
    refused(&d, &[i, "--report", s(&nowhere)], "no-such-folder");
    let o = run(&["enhance", "--help"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Example"));
}

/// The coarse real mesh "Bob" (250 vertices, genus 1) from the shared data:
/// the command runs, keeps the connectivity, moves vertices by less than an
/// edge length, reports no unrepaired flips and improves the worst triangle
/// (μ = 0.5 evens out the sliver triangles of this scan-like mesh).
#[test]
fn enhance_runs_on_a_real_coarse_mesh() {
    let Some(input) = data("meshes/bob_small.ply") else {
        return;
    };
    let d = tmp("bob");
    let (out, rep) = (d.join("bob.ply"), d.join("r.json"));
    let o = run(&[
        "enhance",
        s(&input),
        "--lambda",
        "0.5",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
    let mesh = fairline::io::read_mesh(&input).unwrap();
    let result = fairline::io::read_mesh(&out).unwrap();
    assert_eq!(result.face_count(), mesh.face_count());
    assert_eq!(r["vertices"].as_u64(), Some(mesh.vertex_count() as u64));
    let e = r["edge_length"].as_f64().unwrap();
    let max_d = r["max_displacement"].as_f64().unwrap();
    assert!(
        max_d > 0.1 * e && max_d < e,
        "max displacement {max_d} vs edge {e}"
    );
    let measured = mesh
        .positions()
        .iter()
        .zip(result.positions())
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!((measured - max_d).abs() <= 1e-12 * e.max(1.0));
    let (q0, q1) = (
        r["quality_before"]["min"].as_f64().unwrap(),
        r["quality_after"]["min"].as_f64().unwrap(),
    );
    assert!(q1 > q0, "min quality {q0} -> {q1}");
    // no triangle of the output points against its input orientation
    let n0 = fairline::geom::face_normals(&mesh);
    let n1 = fairline::geom::face_normals(&result);
    assert!(n0.iter().zip(&n1).all(|(a, b)| a.dot(*b) > 0.0));
}

/// `fairline demo` has a vertex-flow section: its picture is written and
/// linked, and its numbers show vertices moving onto the rounded edges of
/// the cube.
#[test]
fn demo_has_a_vertex_flow_section() {
    let d = tmp("demo");
    let out = d.join("demo");
    let o = run(&["demo", "--out", s(&out), "--size", "320x240"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let v = &r["sections"]["Vertex flow"];
    let before = v["share_on_rounded_edges_before"].as_f64().unwrap();
    let after = v["share_on_rounded_edges_after"].as_f64().unwrap();
    assert!(
        after > before + 0.1,
        "share on the rounded edges {before} -> {after}"
    );
    assert_eq!(v["flipped_triangles"].as_u64(), Some(0));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("vertex-flow.png"));
    let png = std::fs::read(out.join("vertex-flow.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
}

/// `--solver direct`, `cg` and `amg` write the same mesh to 1e-8 of the
/// bounding-box diagonal (the same least-squares solution), and the report
/// says which solver ran and how many CG iterations it took.
#[test]
fn enhance_solvers_agree_from_the_command_line() {
    let d = tmp("solvers");
    let input = d.join("cube.obj");
    fairline::io::write_mesh(&input, &fairline::shapes::rounded_cube(10, 0.3)).unwrap();
    let mut outputs = Vec::new();
    for solver in ["direct", "cg", "amg", "auto"] {
        let (out, rep) = (
            d.join(format!("{solver}.ply")),
            d.join(format!("{solver}.json")),
        );
        let o = run(&[
            "enhance",
            s(&input),
            "--solver",
            solver,
            "-o",
            s(&out),
            "--report",
            s(&rep),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
        assert_eq!(r["solver"], solver);
        let iterations = r["cg_iterations"].as_u64().unwrap();
        assert_eq!(
            iterations == 0,
            solver == "direct",
            "{solver}: {iterations}"
        );
        outputs.push(fairline::io::read_mesh(&out).unwrap());
    }
    let p = outputs[0].positions();
    let (lo, hi) = p.iter().fold(
        (
            fairline::Vec3::splat(f64::INFINITY),
            fairline::Vec3::splat(f64::NEG_INFINITY),
        ),
        |(lo, hi), q| (lo.min(*q), hi.max(*q)),
    );
    for other in &outputs[1..] {
        let diff = p
            .iter()
            .zip(other.positions())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        assert!(diff <= 1e-8 * lo.distance(hi), "difference {diff}");
    }
    let input_mesh = fairline::io::read_mesh(&input).unwrap();
    let moved = input_mesh
        .positions()
        .iter()
        .zip(p)
        .filter(|(a, b)| a.distance(**b) > 1e-3)
        .count();
    assert!(moved > 100, "{moved} vertices moved");
}

/// Largest distance of the boundary vertices of `output` from the boundary
/// polyline of `input` (same connectivity), over the bounding-box diagonal
/// of `input`.
fn boundary_offset(input: &fairline::SurfaceMesh, output: &fairline::SurfaceMesh) -> f64 {
    let p = input.positions();
    let edges: Vec<_> = fairline::mesh::boundary_loops(input)
        .iter()
        .flatten()
        .map(|&h| (p[input.from_vertex(h).idx()], p[input.to_vertex(h).idx()]))
        .collect();
    assert!(!edges.is_empty(), "an open mesh");
    let (lo, hi) = fairline::mesh::bounding_box(p).unwrap();
    let worst = input
        .vertices()
        .filter(|&v| input.is_boundary_vertex(v))
        .map(|v| {
            let x = output.position(v);
            edges
                .iter()
                .map(|&(a, b)| {
                    let e = b - a;
                    let s = ((x - a).dot(e) / e.length_squared().max(f64::MIN_POSITIVE))
                        .clamp(0.0, 1.0);
                    x.distance(a + s * e)
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    worst / lo.distance(hi)
}

/// The written boundary vertices lie on the input's boundary polyline to
/// 1e-12 of the diagonal, with every --projection, on a noisy generated
/// open patch and on the real open outline lego_open.ply, while some of
/// them slid along it (--projection none keeps them).
#[test]
fn enhance_keeps_boundary_vertices_on_the_input_boundary_polyline() {
    let d = tmp("boundary");
    let mut patch = fairline::shapes::height_field(21, 21, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.5 * (x * x - 0.5 * y * y) + 0.3 * (-(x / 0.25) * (x / 0.25)).exp()
    });
    let noise = |i: usize, k: usize| ((i * 7919 + k * 104729) % 41) as f64 / 20.0 - 1.0;
    for (i, p) in patch.positions_mut().iter_mut().enumerate() {
        *p += 0.01 * fairline::Vec3::new(noise(i, 1), noise(i, 2), noise(i, 3));
    }
    let generated = d.join("patch.obj");
    fairline::io::write_mesh(&generated, &patch).unwrap();
    let mut inputs = vec![(generated, "patch")];
    if let Some(lego) = data("meshes/lego_open.ply") {
        inputs.push((lego, "lego_open"));
    }
    for (input, name) in inputs {
        let mesh = fairline::io::read_mesh(&input).unwrap();
        for projection in ["smooth", "mesh", "none"] {
            let out = d.join(format!("{name}-{projection}.obj"));
            let o = run(&[
                "enhance",
                s(&input),
                "--projection",
                projection,
                "-o",
                s(&out),
            ]);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let result = fairline::io::read_mesh(&out).unwrap();
            let off = boundary_offset(&mesh, &result);
            let slid = mesh
                .vertices()
                .filter(|&v| mesh.is_boundary_vertex(v) && mesh.position(v) != result.position(v))
                .count();
            eprintln!(
                "{name} --projection {projection}: {slid} boundary vertices slid, {off:.3e} × diagonal off the input boundary"
            );
            assert!(off <= 1e-12, "{name} {projection}: {off}");
            assert_eq!(
                slid == 0,
                projection == "none",
                "{name} {projection}: {slid}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
