//! Dirty meshes on the command line: non-manifold vertices accepted by every
//! command (split per fan, pinned, merged back bit-identical), `fairline
//! repair`, and the hint every refusal of dirty input ends with.

mod common;
use common::*;

use fairline::Vec3;
use fairline::mesh::Soup;
use std::path::{Path, PathBuf};

/// A file of ../shared/data: fails when it is missing and `CI` is set, says
/// so loudly (and returns `None`) otherwise.
fn shared(rel: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "{} is missing and CI is set: the real-data tests cannot run",
        p.display()
    );
    eprintln!(
        "\n*** SKIPPED: {} not found; this test needs ../shared/data ***\n",
        p.display()
    );
    None
}

fn bits(p: &[Vec3]) -> Vec<[u64; 3]> {
    p.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
}

fn faces(soup: &Soup) -> Vec<Vec<u32>> {
    soup.faces().map(<[u32]>::to_vec).collect()
}

/// Two bumpy spheres touching at one shared vertex (index 0, the top of the
/// lower sphere and the bottom of the upper one): a non-manifold vertex where
/// two closed fans meet. Every other vertex is pushed off the sphere a little
/// so that the smoothing methods have something to do.
fn touching_spheres() -> Soup {
    let s = fairline::shapes::icosphere(1.0, 3).to_soup();
    let top = (0..s.positions.len())
        .max_by(|&a, &b| s.positions[a].z.total_cmp(&s.positions[b].z))
        .unwrap() as u32;
    let n = s.positions.len() as u32;
    // lower sphere: its top vertex becomes vertex 0
    let lower = |v: u32| {
        if v == top {
            0
        } else if v == 0 {
            top
        } else {
            v
        }
    };
    let mut positions = vec![Vec3::ZERO; 2 * n as usize - 1];
    for v in 0..n {
        positions[lower(v) as usize] = s.positions[v as usize];
    }
    // upper sphere: mirrored through the plane of the shared vertex
    let z0 = s.positions[top as usize].z;
    let upper = |v: u32| {
        if v == top {
            0
        } else {
            n + v - u32::from(v > top)
        }
    };
    for v in 0..n {
        let p = s.positions[v as usize];
        positions[upper(v) as usize] = Vec3::new(p.x, p.y, 2.0 * z0 - p.z);
    }
    for (i, p) in positions.iter_mut().enumerate().skip(1) {
        let wobble = 1.0 + 0.03 * ((i * 7919) % 13) as f64 / 13.0;
        let c = Vec3::new(0.0, 0.0, if p.z > z0 { 2.0 * z0 } else { 0.0 });
        *p = c + (*p - c) * wobble;
    }
    let mut polys: Vec<Vec<u32>> = Vec::new();
    for f in s.faces() {
        polys.push(f.iter().map(|&v| lower(v)).collect());
    }
    for f in s.faces() {
        // mirrored: reverse to keep the outward orientation
        polys.push(f.iter().rev().map(|&v| upper(v)).collect());
    }
    Soup::from_polygons(positions, &polys)
}

#[test]
fn a_non_manifold_vertex_goes_through_every_command_and_comes_back_bit_identical() {
    let dir = tmp("nm-vertex");
    let input = dir.join("spheres.obj");
    let soup = touching_spheres();
    fairline::io::write_soup(&input, &soup).unwrap();
    // the file really has a vertex of two fans
    let info = run(&["info", s(&input), "--json"]);
    ok(&info);
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(info["non_manifold_vertices"], 1);
    assert_eq!(info["manifold"], true);

    let region = dir.join("region.json");
    std::fs::write(
        &region,
        r#"{"sphere":{"center":[0.0,0.0,1.0],"radius":0.6}}"#,
    )
    .unwrap();
    let runs: Vec<(&str, Vec<String>, bool)> = vec![
        ("convert", vec!["convert".into(), s(&input).into()], false),
        (
            "taubin",
            vec![
                "smooth".into(),
                s(&input).into(),
                "--method".into(),
                "taubin".into(),
            ],
            true,
        ),
        (
            "laplace",
            vec![
                "smooth".into(),
                s(&input).into(),
                "--method".into(),
                "laplace".into(),
            ],
            true,
        ),
        (
            "implicit",
            vec![
                "smooth".into(),
                s(&input).into(),
                "--method".into(),
                "implicit".into(),
            ],
            true,
        ),
        ("enhance", vec!["enhance".into(), s(&input).into()], true),
        (
            "fair",
            vec![
                "fair".into(),
                s(&input).into(),
                "--region".into(),
                s(&region).into(),
            ],
            true,
        ),
    ];
    for (name, mut args, moves) in runs {
        let out = dir.join(format!("{name}.obj"));
        if name == "convert" {
            args.push(s(&out).into());
        } else {
            args.push("-o".into());
            args.push(s(&out).into());
        }
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&argv);
        ok(&o);
        let stderr = String::from_utf8_lossy(&o.stderr);
        if name != "convert" {
            assert!(
                stderr.contains("1 non-manifold vertices split"),
                "{name}: {stderr}"
            );
        }
        let back = fairline::io::read_soup(&out).unwrap();
        assert_eq!(back.positions.len(), soup.positions.len(), "{name}");
        assert_eq!(faces(&back), faces(&soup), "{name}: faces and their order");
        assert_eq!(
            back.positions[0].to_array().map(f64::to_bits),
            soup.positions[0].to_array().map(f64::to_bits),
            "{name}: the split vertex moved"
        );
        let moved = back
            .positions
            .iter()
            .zip(&soup.positions)
            .filter(|(a, b)| a != b)
            .count();
        if moves {
            assert!(moved > 0, "{name} moved nothing");
        } else {
            assert_eq!(bits(&back.positions), bits(&soup.positions), "{name}");
        }
    }

    // curvature: one row per input vertex
    let c = dir.join("curvature.ply");
    ok(&run(&["curvature", s(&input), "-o", s(&c)]));
    let (pos, props) = fairline::io::read_ply_vertex_properties(&c).unwrap();
    assert_eq!(pos.positions.len(), soup.positions.len());
    assert!(props.iter().all(|(_, v)| v.len() == soup.positions.len()));

    // detect and highlight lines: accepted, output written
    let r = dir.join("detected.json");
    ok(&run(&["detect", s(&input), "-o", s(&r)]));
    assert!(json(&r).is_object());
}

#[test]
fn repair_of_a_clean_mesh_writes_the_same_bytes_as_convert() {
    let dir = tmp("repair-identity");
    let input = dir.join("torus.obj");
    fairline::io::write_mesh(&input, &fairline::shapes::torus(2.0, 0.7, 24, 12)).unwrap();
    let mut inputs = vec![input];
    if let Some(p) = shared("meshes/spot.ply") {
        inputs.push(p);
    }
    if let Some(p) = shared("meshes/lego_open.ply") {
        inputs.push(p);
    }
    for (k, input) in inputs.iter().enumerate() {
        let ext = input.extension().unwrap().to_str().unwrap();
        let (a, b) = (
            dir.join(format!("c{k}.{ext}")),
            dir.join(format!("r{k}.{ext}")),
        );
        let report = dir.join(format!("r{k}.json"));
        ok(&run(&["convert", s(input), s(&a)]));
        let o = run(&["repair", s(input), s(&b), "--report", s(&report)]);
        ok(&o);
        assert!(String::from_utf8_lossy(&o.stderr).contains("nothing to repair"));
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{input:?}"
        );
        let r = json(&report);
        assert_eq!(r["command"], "repair");
        assert_eq!(r["removed_faces"].as_array().unwrap().len(), 0);
        assert_eq!(r["manifold"], true);
    }
}

#[test]
fn dirty_input_is_refused_with_a_hint_and_repair_fixes_it() {
    let dir = tmp("repair-hint");
    // a square with a fin on its diagonal (a non-manifold edge), a duplicate
    // face and an unreferenced vertex
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.5, 0.5, 1.0),
        Vec3::new(5.0, 5.0, 5.0),
    ];
    let soup = Soup::from_polygons(p.clone(), &[[0u32, 1, 2], [0, 2, 3], [0, 2, 4], [1, 2, 0]]);
    let input = dir.join("fin.obj");
    fairline::io::write_soup(&input, &soup).unwrap();
    let o = run(&["curvature", s(&input), "-o", s(&dir.join("c.ply"))]);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("non-manifold"), "{stderr}");
    assert!(
        stderr.contains(&format!("fairline repair {}", input.display())),
        "{stderr}"
    );
    let fixed = dir.join("fin-repaired.obj");
    let report = dir.join("repair.json");
    ok(&run(&[
        "repair",
        s(&input),
        s(&fixed),
        "--report",
        s(&report),
    ]));
    let r = json(&report);
    assert_eq!(r["removed_faces"][0]["face"], 3);
    assert_eq!(r["removed_faces"][0]["reason"], "duplicate");
    assert_eq!(r["removed_vertices"], serde_json::json!([5]));
    assert_eq!(r["manifold"], true);
    let back = fairline::io::read_soup(&fixed).unwrap();
    assert_eq!(bits(&back.positions[..5]), bits(&p[..5]));
    ok(&run(&["curvature", s(&fixed), "-o", s(&dir.join("c.ply"))]));
    // the repair never overwrites its input
    let o = run(&["repair", s(&input), s(&input)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(fairline::io::read_soup(&input).unwrap(), soup);
}

#[test]
fn the_dirty_real_meshes_go_through_repair_and_then_every_command() {
    let dir = tmp("repair-real");
    for name in ["meshes/bunny_res4.ply", "meshes/elephant_nonmanifold.obj"] {
        let Some(input) = shared(name) else {
            return;
        };
        let stem = input.file_stem().unwrap().to_str().unwrap().to_string();
        let fixed = dir.join(format!("{stem}.ply"));
        let report = dir.join(format!("{stem}-repair.json"));
        let o = run(&["curvature", s(&input), "-o", s(&dir.join("refused.ply"))]);
        assert_eq!(o.status.code(), Some(2), "{name} was not dirty");
        assert!(String::from_utf8_lossy(&o.stderr).contains("hint: run `fairline repair"));
        ok(&run(&[
            "repair",
            s(&input),
            s(&fixed),
            "--report",
            s(&report),
        ]));
        let r = json(&report);
        assert_eq!(r["manifold"], true, "{name}: {}", r["remaining_problem"]);
        let original = fairline::io::read_soup(&input).unwrap();
        let repaired = fairline::io::read_soup(&fixed).unwrap();
        // every kept vertex bit-identical, as vertex_source says
        let source: Vec<usize> = match r["vertex_source"].as_array() {
            Some(a) if !a.is_empty() => a.iter().map(|v| v.as_u64().unwrap() as usize).collect(),
            _ => (0..original.positions.len()).collect(),
        };
        assert_eq!(source.len(), repaired.positions.len());
        for (i, &v) in source.iter().enumerate() {
            assert_eq!(
                repaired.positions[i].to_array().map(f64::to_bits),
                original.positions[v].to_array().map(f64::to_bits)
            );
        }
        for (cmd, extra) in [
            ("curvature", vec![]),
            ("detect", vec![]),
            ("smooth", vec!["--method", "taubin"]),
            ("enhance", vec![]),
        ] {
            let ext = match cmd {
                "detect" => "json",
                "curvature" => "ply",
                _ => "obj",
            };
            let out = dir.join(format!("{stem}-{cmd}.{ext}"));
            let mut args = vec![cmd, s(&fixed)];
            args.extend(extra);
            args.extend(["-o", s(&out)]);
            let o = run(&args);
            ok(&o);
            assert!(out.exists(), "{name}: {cmd} wrote nothing");
        }
    }
}

/// One triangle repeated 200,000 times: `info` and `repair` take time and
/// memory linear in the faces. (A pairwise comparison of the faces around a
/// vertex, as `info` once made, takes about an hour here: 31 s at 20,000.)
#[test]
fn one_triangle_repeated_many_times_costs_linear_time() {
    let dir = tmp("repair-duplicates");
    let n = 200_000;
    let mesh = dir.join("dup.obj");
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    text.push_str(&"f 1 2 3\n".repeat(n));
    std::fs::write(&mesh, text).unwrap();
    let t = std::time::Instant::now();
    let o = run(&["info", s(&mesh), "--json"]);
    let info_s = t.elapsed().as_secs_f64();
    ok(&o);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["faces"], n);
    assert_eq!(j["manifold"], false);
    let t = std::time::Instant::now();
    let out = dir.join("one.obj");
    let report = dir.join("r.json");
    let o = run(&["repair", s(&mesh), s(&out), "--report", s(&report)]);
    let repair_s = t.elapsed().as_secs_f64();
    ok(&o);
    let r = json(&report);
    assert_eq!(r["faces_after"], 1);
    assert_eq!(r["removed_faces"].as_array().map(Vec::len), Some(n - 1));
    assert!(
        info_s < 20.0 && repair_s < 20.0,
        "info {info_s:.1} s, repair {repair_s:.1} s for {n} duplicates"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
