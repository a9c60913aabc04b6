//! Input parsing through the `fairline` binary: polygon meshes whose
//! preferred quad diagonal is taken (triangulated, no panic), STL output
//! beyond f32 (refused, never written as inf), and a seeded
//! mutation fuzz of the JSON files commands take (lights, region, fixed
//! vertices, endpoints): never exit 101, exit 2 names an input file, and
//! nothing is written on failure.

mod common;
use common::*;
use std::time::{Duration, Instant};

/// Two quads around a valence-2 vertex whose shorter diagonal is the same
/// pair of vertices, and (with `closing`) a triangle that makes it an edge.
fn valence_two_obj(closing: bool) -> String {
    let mut s = String::from(
        "v -1 0 0\nv 0 0.1 0.05\nv 1 0 0\nv 0 3 0.3\nv 0 -3 0.2\nf 1 2 3 4\nf 3 2 1 5\n",
    );
    if closing {
        s.push_str("f 3 1 4\n");
    }
    s
}

#[test]
fn quads_sharing_their_preferred_diagonal_go_through_every_triangulating_command() {
    let d = tmp("valence2");
    for closing in [false, true] {
        let m = d.join(format!("quads{closing}.obj"));
        std::fs::write(&m, valence_two_obj(closing)).unwrap();
        let runs: [(&str, Vec<String>, &str); 4] = [
            ("curvature", vec!["-o".into()], "c.ply"),
            ("highlight", vec!["-o".into()], "l.json"),
            ("render", vec!["--png".into()], "r.png"),
            ("detect", vec!["-o".into()], "region.json"),
        ];
        for (cmd, flag, out) in runs {
            let out = d.join(format!("{closing}-{out}"));
            let mut args = vec![cmd, s(&m)];
            args.extend(flag.iter().map(String::as_str));
            args.push(s(&out));
            let o = run(&args);
            assert_ne!(o.status.code(), Some(101), "{cmd} panicked");
            ok(&o);
            assert!(out.exists(), "{cmd} wrote nothing");
        }
    }
}

#[test]
fn stl_output_beyond_f32_is_refused_with_exit_2_and_nothing_written() {
    let d = tmp("stlinf");
    let m = d.join("big.obj");
    std::fs::write(&m, "v 0 0 0\nv 1 0 0\nv 0 4e38 0\nf 1 2 3\n").unwrap();
    let out = d.join("big.stl");
    let o = run(&["convert", s(&m), s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("big.stl") && err.contains("vertex 2"), "{err}");
    assert!(!out.exists());
    // PLY keeps the value exactly
    let ply = d.join("big.ply");
    ok(&run(&["convert", s(&m), s(&ply)]));
    assert_eq!(fairline::io::read_soup(&ply).unwrap().positions[2].y, 4e38);
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const NASTY: &[&str] = &[
    "NaN",
    "1e999",
    "-1",
    "1e20",
    "4294967296",
    "-0",
    "null",
    "\"x\"",
    "[]",
    "{}",
    "true",
    "1.5",
    "0",
    "18446744073709551616",
];

fn mutate_json(seed: &str, rng: &mut Rng) -> Vec<u8> {
    let mut b = seed.as_bytes().to_vec();
    let at = rng.below(b.len());
    match rng.below(6) {
        0 => b[at] = rng.next() as u8,
        1 => b.truncate(at),
        2 | 3 => {
            // replace the number or word at `at`
            let is_tok = |c: &u8| c.is_ascii_alphanumeric() || b"+-.".contains(c);
            let start = b[..at]
                .iter()
                .rposition(|c| !is_tok(c))
                .map_or(0, |p| p + 1);
            let end = b[at..]
                .iter()
                .position(|c| !is_tok(c))
                .map_or(b.len(), |p| at + p);
            let r = NASTY[rng.below(NASTY.len())];
            b.splice(start..end, r.bytes());
        }
        4 => {
            let dup = b[at..].to_vec();
            b.extend(dup);
        }
        _ => b = Vec::new(),
    }
    b
}

/// A 6 × 6 height-field grid as OBJ text.
fn grid_obj() -> String {
    let n = 6;
    let mut s = String::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / 5.0, j as f64 / 5.0);
            s.push_str(&format!("v {x} {y} {}\n", 0.1 * (3.0 * x).sin() * y));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = j * n + i + 1;
            s.push_str(&format!(
                "f {} {} {}\nf {} {} {}\n",
                k,
                k + 1,
                k + n + 1,
                k,
                k + n + 1,
                k + n
            ));
        }
    }
    s
}

const BEZIER: &str = r#"{"degree_u":3,"degree_v":3,"knots_u":[0,0,0,0,1,1,1,1],"knots_v":[0,0,0,0,1,1,1,1],
"control_points":[[[0,0,0],[0,1,0.3],[0,2,0.3],[0,3,0]],[[1,0,0.3],[1,1,1],[1,2,1],[1,3,0.3]],
[[2,0,0.3],[2,1,1],[2,2,1],[2,3,0.3]],[[3,0,0],[3,1,0.3],[3,2,0.3],[3,3,0]]]}"#;

/// Fuzzes the JSON file `json_name` (content `seed`) of a command built by
/// `args(mesh, json, out)`.
fn fuzz_command(
    tag: &str,
    input: (&str, &str),
    json_name: &str,
    seed: &str,
    args: &dyn Fn(&str, &str, &str) -> Vec<String>,
    cases: usize,
    salt: u64,
) {
    let d = tmp(tag);
    let inp = d.join(input.0);
    std::fs::write(&inp, input.1).unwrap();
    let mut rng = Rng(0x243f_6a88_85a3_08d3 ^ salt);
    for case in 0..cases {
        let json = d.join(json_name);
        let bytes = if case == 0 {
            seed.as_bytes().to_vec()
        } else {
            mutate_json(seed, &mut rng)
        };
        std::fs::write(&json, &bytes).unwrap();
        let ext = if tag == "endpoints" { "json" } else { "obj" };
        let out = d.join(format!("out-{case}.{ext}"));
        let a = args(s(&inp), s(&json), s(&out));
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        let t = Instant::now();
        let o = run(&a);
        let took = t.elapsed();
        let err = String::from_utf8_lossy(&o.stderr);
        let text = String::from_utf8_lossy(&bytes);
        assert!(
            took < Duration::from_secs(60),
            "{tag}: took {took:?} on {text}"
        );
        let code = o.status.code();
        assert!(
            matches!(code, Some(0..=2)),
            "{tag}: exit {code:?} (101 is a panic) on {text}\n{err}"
        );
        if code == Some(2) {
            assert!(
                err.contains(json_name) || err.contains(input.0),
                "{tag}: exit 2 without naming the file, on {text}\n{err}"
            );
        }
        if code != Some(0) {
            assert!(
                !out.exists(),
                "{tag}: output written although it failed, on {text}"
            );
        }
    }
}

#[test]
fn fuzz_lights_region_fixed_and_endpoints_files() {
    let mesh = ("grid.obj", grid_obj());
    let lights =
        r#"{"plane_point":[0.5,0.5,3],"plane_normal":[0,0,1],"direction":[1,0,0],"spacing":0.1}"#;
    fuzz_command(
        "lights",
        (mesh.0, &mesh.1),
        "lights.json",
        lights,
        &|m, j, o| {
            ["highlight", m, "--lights", j, "-o", o]
                .map(String::from)
                .to_vec()
        },
        30,
        1,
    );
    fuzz_command(
        "region",
        (mesh.0, &mesh.1),
        "region.json",
        r#"{"faces":[20,21,22,23,30,31]}"#,
        &|m, j, o| {
            ["fair", m, "--region", j, "-o", o, "--max-iterations", "2"]
                .map(String::from)
                .to_vec()
        },
        30,
        2,
    );
    fuzz_command(
        "fixed",
        (mesh.0, &mesh.1),
        "fixed.json",
        r#"{"vertices":[0,1,2,14]}"#,
        &|m, j, o| {
            ["smooth", m, "--method", "laplace", "--fixed", j, "-o", o]
                .map(String::from)
                .to_vec()
        },
        30,
        3,
    );
    let d = tmp("endpoints-lights");
    let lf = d.join("circ.json");
    std::fs::write(
        &lf,
        r#"{"center":[1.5,1.5,3],"axis":[0,0,1],"radii":[0.8,1.0]}"#,
    )
    .unwrap();
    let lf = lf.to_str().unwrap().to_string();
    fuzz_command(
        "endpoints",
        ("patch.json", BEZIER),
        "ends.json",
        r#"{"endpoints":[{"radius":1.0,"start":[0.3,0.4],"end":[0.7,0.6]}]}"#,
        &|m, j, o| {
            [
                "fair-surface",
                m,
                "--lights",
                &lf,
                "--endpoints",
                j,
                "-o",
                o,
                "--max-iterations",
                "2",
            ]
            .map(String::from)
            .to_vec()
        },
        30,
        4,
    );
}
