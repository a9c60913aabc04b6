//! Every command that reads a file, given a bad one (truncated or garbled
//! OBJ/PLY/OFF/STL, bad STEP/IGES/surface JSON, bad side files, a missing
//! file, a directory), exits 2 with the file named and writes nothing; the
//! exit status of an output that cannot be written is one policy for
//! every kind of output (docs/guide/conventions.md, "Exit status").

mod common;
use common::{ok, run, s, tmp};
use std::path::{Path, PathBuf};

/// A 6 × 6 wavy height field as OBJ text (a good mesh).
fn wavy_obj(n: usize) -> String {
    let mut t = String::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            t.push_str(&format!("v {x} {y} {}\n", 0.1 * (6.0 * x).sin() * y));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            t.push_str(&format!(
                "f {a} {} {}\nf {a} {} {}\n",
                a + 1,
                a + n + 1,
                a + n + 1,
                a + n
            ));
        }
    }
    t
}

/// A bad file: its name, its bytes (`None`: missing; `Some(None)`: made a
/// directory), and whether every command refuses it: a file that parses
/// but is no valid mesh is counted by `info`, converted by `convert` (a
/// face list is converted as it is) and fixed by `repair` when it has
/// faces; every other command refuses it.
struct Bad {
    name: &'static str,
    bytes: Option<Option<Vec<u8>>>,
    unparseable: bool,
}

fn bad(name: &'static str, text: &str, unparseable: bool) -> Bad {
    Bad {
        name,
        bytes: Some(Some(text.as_bytes().to_vec())),
        unparseable,
    }
}

/// Whether `command` accepts the parseable but invalid file `b` (see
/// [`Bad`]).
fn accepts(command: &str, b: &Bad) -> bool {
    // lights that draw no line: `highlight` says so in a warning
    if b.name == "far-side.json" {
        return command == "highlight";
    }
    !b.unparseable
        && (command == "info"
            || command == "convert"
            || (command == "repair" && b.name != "nofaces.obj"))
}

fn binary_stl_truncated() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&10u32.to_le_bytes());
    b.extend_from_slice(&[1u8; 60]);
    b
}

fn binary_ply_truncated() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    b.extend_from_slice(&[0u8; 13]);
    b
}

fn garbage(len: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

fn mesh_corpus() -> Vec<Bad> {
    vec![
        bad("truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n", true),
        Bad {
            name: "garbled.obj",
            bytes: Some(Some(garbage(300, 7))),
            unparseable: true,
        },
        bad("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", true),
        bad("letters.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", true),
        bad(
            "header.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n0\n",
            true,
        ),
        Bad {
            name: "body.ply",
            bytes: Some(Some(binary_ply_truncated())),
            unparseable: true,
        },
        bad("counts.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n", true),
        bad("words.off", "OFF\nfour two zero\n", true),
        Bad {
            name: "short.stl",
            bytes: Some(Some(binary_stl_truncated())),
            unparseable: true,
        },
        bad(
            "ascii.stl",
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\nendloop\n",
            true,
        ),
        bad("empty.obj", "", true),
        Bad {
            name: "missing.obj",
            bytes: None,
            unparseable: true,
        },
        Bad {
            name: "folder.ply",
            bytes: Some(None),
            unparseable: true,
        },
        bad("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", false),
        bad(
            "nonmanifold.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            false,
        ),
    ]
}

fn surface_corpus() -> Vec<Bad> {
    vec![
        bad("cut.json", "{\"surfaces\": [", true),
        bad("wrong.json", "{\"degree_u\": \"three\"}", true),
        bad(
            "knots.json",
            "{\"degree_u\":3,\"degree_v\":3,\"knots_u\":[0,1],\"knots_v\":[0,1],\"control_points\":[[[0,0,0]]]}",
            true,
        ),
        bad(
            "garbage.step",
            "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=GARBAGE(;\nENDSEC;\nEND-ISO-10303-21;\n",
            true,
        ),
        bad("empty.stp", "", true),
        bad(
            "garbage.igs",
            "this is not an IGES file at all, just words\nand more words\n",
            true,
        ),
        Bad {
            name: "noise.iges",
            bytes: Some(Some(garbage(800, 11))),
            unparseable: true,
        },
        Bad {
            name: "missing.json",
            bytes: None,
            unparseable: true,
        },
        Bad {
            name: "folder.step",
            bytes: Some(None),
            unparseable: true,
        },
    ]
}

/// Bad side files (regions, fixed vertices, lights, endpoints, lines).
fn side_corpus() -> Vec<Bad> {
    vec![
        bad("cut-side.json", "{\"faces\": [1, 2", true),
        bad(
            "strings-side.json",
            "{\"faces\": [\"a\"], \"vertices\": [\"b\"]}",
            true,
        ),
        bad("number-side.json", "42", true),
        // well-formed endpoints of a radius no light can have
        bad(
            "negative-side.json",
            r#"{"endpoints":[{"radius":-1,"start":[0.3,0.4],"end":[0.6,0.5]}]}"#,
            true,
        ),
        // well-formed circular lights whose lines miss the surface
        bad(
            "far-side.json",
            r#"{"center":[0,1e9,3],"axis":[0,1,0],"radii":[1.0]}"#,
            true,
        ),
        Bad {
            name: "missing-side.json",
            bytes: None,
            unparseable: true,
        },
        Bad {
            name: "folder-side.json",
            bytes: Some(None),
            unparseable: true,
        },
    ]
}

/// Puts `b` in `dir` and returns its path.
fn place(dir: &Path, b: &Bad) -> PathBuf {
    let p = dir.join(b.name);
    match &b.bytes {
        None => {}
        Some(None) => std::fs::create_dir_all(&p).unwrap(),
        Some(Some(bytes)) => std::fs::write(&p, bytes).unwrap(),
    }
    p
}

/// Runs `args`, then checks exit status 2, the file `name` in the error
/// and an empty `out` folder; returns a description of what failed.
fn refused(args: &[String], name: &str, out: &Path) -> Option<String> {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = run(&a);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let written: Vec<_> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    for e in std::fs::read_dir(out).unwrap() {
        let _ = std::fs::remove_file(e.unwrap().path());
    }
    let mut problems = Vec::new();
    if o.status.code() != Some(2) {
        problems.push(format!("exit {:?}", o.status.code()));
    }
    if !err.contains(name) {
        problems.push(format!("{name} not named"));
    }
    if err.contains("panicked") {
        problems.push("panic".into());
    }
    if !written.is_empty() {
        problems.push(format!("wrote {written:?}"));
    }
    (!problems.is_empty()).then(|| format!("{a:?}: {}: {}", problems.join(", "), err.trim()))
}

fn owned(args: &[&str]) -> Vec<String> {
    args.iter().map(|a| a.to_string()).collect()
}

#[test]
fn every_command_refuses_every_bad_file_naming_it_and_writes_nothing() {
    let d = tmp("reliability-corpus");
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let o = |name: &str| out.join(name).to_string_lossy().to_string();
    let good = d.join("good.obj");
    std::fs::write(&good, wavy_obj(6)).unwrap();
    let g = s(&good).to_string();
    let quads = d.join("quads.obj");
    let mut quad_text = String::new();
    for j in 0..5 {
        for i in 0..5 {
            quad_text.push_str(&format!("v {i} {j} {}\n", 0.1 * ((i * j) % 3) as f64));
        }
    }
    for j in 0..4 {
        for i in 0..4 {
            let a = j * 5 + i + 1;
            quad_text.push_str(&format!("f {a} {} {} {}\n", a + 1, a + 6, a + 5));
        }
    }
    std::fs::write(&quads, quad_text).unwrap();
    let q = s(&quads).to_string();
    let surface = d.join("dome.json");
    fairline::io::write_surfaces_json(&surface, &[common::dome_surface(true)]).unwrap();
    let sf = s(&surface).to_string();
    let lights = d.join("lights.json");
    std::fs::write(
        &lights,
        r#"{"center":[0,0,3],"axis":[0,0,1],"radii":[2.5,2.7]}"#,
    )
    .unwrap();
    let ends = d.join("ends.json");
    std::fs::write(
        &ends,
        r#"{"endpoints":[{"radius":2.5,"start":[0.6,0.3],"end":[0.8,0.4]}]}"#,
    )
    .unwrap();
    let (lf, ef) = (s(&lights).to_string(), s(&ends).to_string());

    // the commands that read a mesh, with the mesh's place as {}
    let mesh_commands: Vec<Vec<String>> = vec![
        owned(&["info", "{}", "--report", &o("r.json")]),
        owned(&["convert", "{}", &o("c.ply"), "--report", &o("r.json")]),
        owned(&["curvature", "{}", "-o", &o("k.ply")]),
        owned(&["highlight", "{}", "-o", &o("l.json"), "--png", &o("l.png")]),
        owned(&["detect", "{}", "-o", &o("d.json"), "--report", &o("r.json")]),
        owned(&["enhance", "{}", "-o", &o("e.obj")]),
        owned(&["fair", "{}", "--auto", "-o", &o("f.obj")]),
        owned(&["render", "{}", "--png", &o("p.png")]),
        owned(&["smooth", "{}", "-o", &o("s.obj"), "--report", &o("r.json")]),
        owned(&["fair-quad", "{}", "-o", &o("q.obj")]),
        owned(&["repair", "{}", &o("rep.ply")]),
    ];
    let surface_commands: Vec<Vec<String>> = vec![
        owned(&["info", "{}", "--report", &o("r.json")]),
        owned(&["convert", "{}", &o("c.json")]),
        owned(&["convert", "{}", &o("c.obj")]),
        owned(&[
            "highlight",
            "{}",
            "--circle-center",
            "0,0,3",
            "--circle-axis",
            "0,0,1",
            "--radii",
            "2.5",
            "-o",
            &o("l.json"),
        ]),
        owned(&["render", "{}", "--png", &o("p.png")]),
        owned(&["continuity", "{}", "--report", &o("r.json")]),
        owned(&[
            "fair-surface",
            "{}",
            "--lights",
            &lf,
            "--endpoints",
            &ef,
            "-o",
            &o("fs.json"),
        ]),
    ];
    // the commands that read a side file, with its place as {}
    let side_commands: Vec<Vec<String>> = vec![
        owned(&["fair", &g, "--region", "{}", "-o", &o("f.obj")]),
        owned(&["smooth", &g, "--fixed", "{}", "-o", &o("s.obj")]),
        owned(&["enhance", &g, "--fixed", "{}", "-o", &o("e.obj")]),
        owned(&["fair-quad", &q, "--fixed", "{}", "-o", &o("q.obj")]),
        owned(&["highlight", &g, "--lights", "{}", "-o", &o("l.json")]),
        owned(&["detect", &g, "--lights", "{}", "-o", &o("d.json")]),
        owned(&[
            "render",
            &g,
            "--highlight",
            "--lights",
            "{}",
            "--png",
            &o("p.png"),
        ]),
        owned(&[
            "fair-surface",
            &sf,
            "--lights",
            "{}",
            "--endpoints",
            &ef,
            "-o",
            &o("fs.json"),
        ]),
        owned(&[
            "fair-surface",
            &sf,
            "--lights",
            &lf,
            "--endpoints",
            "{}",
            "-o",
            &o("fs.json"),
        ]),
        owned(&[
            "fair-surface",
            &sf,
            "--lights",
            &lf,
            "--lines",
            "{}",
            "--from",
            "0:0.3",
            "--to",
            "0:0.6",
            "-o",
            &o("fs.json"),
        ]),
    ];
    let mut failures = Vec::new();
    let mut runs = 0;
    for (corpus, commands) in [
        (mesh_corpus(), &mesh_commands),
        (surface_corpus(), &surface_commands),
        (side_corpus(), &side_commands),
    ] {
        for b in &corpus {
            let path = place(&d, b);
            for cmd in commands.iter() {
                if accepts(&cmd[0], b) {
                    continue;
                }
                let args: Vec<String> = cmd
                    .iter()
                    .map(|a| {
                        if a == "{}" {
                            s(&path).to_string()
                        } else {
                            a.clone()
                        }
                    })
                    .collect();
                runs += 1;
                if let Some(f) = refused(&args, b.name, &out) {
                    failures.push(f);
                }
            }
        }
    }
    assert!(runs > 200, "{runs} runs");
    assert!(
        failures.is_empty(),
        "{} of {runs} runs failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Runs `fairline args` with writes to files limited to `limit_bytes`
/// (RLIMIT_FSIZE through the shell's `ulimit -f`, SIGXFSZ ignored, so a
/// write past it fails with EFBIG, as on a full disk): an output that
/// cannot be written once the run is under way.
#[cfg(unix)]
fn run_with_file_size_limit(args: &[&str]) -> std::process::Output {
    std::process::Command::new("bash")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 0; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_fairline"))
        .args(args)
        .output()
        .unwrap()
}

/// The one exit-status policy for outputs, whatever their kind: an output
/// refused before any work (its folder missing or not writable) is a bad
/// argument, exit 2; an output that cannot be written once the run is
/// under way is a failed run, exit 1. Either way nothing is written.
#[cfg(unix)]
#[test]
fn outputs_that_cannot_be_written_exit_alike_whatever_their_kind() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp("reliability-outputs");
    let mesh = d.join("in.obj");
    std::fs::write(&mesh, wavy_obj(8)).unwrap();
    let m = s(&mesh).to_string();
    let surface = d.join("dome.json");
    fairline::io::write_surfaces_json(&surface, &[common::dome_surface(true)]).unwrap();
    let sf = s(&surface).to_string();
    // a folder nobody may write to: mode 0555, or, for a user whom modes
    // do not stop (root), a folder of a file system that makes no files
    let locked = d.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let locked = if std::fs::write(locked.join("probe"), "x").is_ok() {
        PathBuf::from("/sys")
    } else {
        locked
    };
    let missing = d.join("missing");
    // (kind, arguments before the output, the output's option, file name)
    let kinds: Vec<(&str, Vec<String>, &str, &str)> = vec![
        ("mesh", owned(&["smooth", &m, "-o"]), "-o", "out.obj"),
        ("PNG", owned(&["render", &m, "--png"]), "--png", "out.png"),
        (
            "report",
            owned(&["info", &m, "--report"]),
            "--report",
            "r.json",
        ),
        (
            "SVG",
            owned(&[
                "highlight",
                &sf,
                "--circle-center",
                "0,0,3",
                "--circle-axis",
                "0,0,1",
                "--radii",
                "2.5,2.7",
                "-o",
                &d.join("lines.json").to_string_lossy(),
                "--svg",
            ]),
            "--svg",
            "uv.svg",
        ),
        ("surface", owned(&["convert", &sf]), "", "out.igs"),
    ];
    let mut seen = Vec::new();
    for (kind, before, option, name) in &kinds {
        for (folder, why) in [(&missing, "missing"), (&locked, "read-only")] {
            let out = folder.join(name);
            let mut args: Vec<String> = before.clone();
            args.push(s(&out).to_string());
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = run(&a);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!out.exists(), "{kind} in a {why} folder: written");
            assert!(
                err.contains(name),
                "{kind} ({option}) in a {why} folder: {err}"
            );
            seen.push((format!("{kind}, {why} folder"), o.status.code()));
        }
        // a write that fails under way: files limited to 0 bytes
        let out = d.join(name);
        let mut args: Vec<String> = before.clone();
        args.push(s(&out).to_string());
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run_with_file_size_limit(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            o.status.code(),
            Some(1),
            "{kind}: an output that cannot be written under way: {err}"
        );
        // the error names the file that could not be written: this one,
        // or an output the command writes before it
        assert!(
            err.contains(name) || err.contains("lines.json"),
            "{kind}: {err}"
        );
        assert!(!out.exists(), "{kind}: written");
        let temps: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        assert!(temps.is_empty(), "{kind}: left {temps:?}");
    }
    // refused before any work: the same status for every kind
    for (what, code) in &seen {
        assert_eq!(*code, Some(2), "{what}: {seen:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A replaced output keeps its mode; an output with other hard links is
/// refused before any work (exit 2, the file and its number of links
/// named, nothing written, both names keep their content).
#[cfg(unix)]
#[test]
fn hard_linked_outputs_are_refused_naming_the_links() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp("reliability-links");
    let input = d.join("in.obj");
    std::fs::write(&input, wavy_obj(6)).unwrap();
    let out = d.join("out.obj");
    std::fs::write(&out, "old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
    ok(&run(&["smooth", s(&input), "-o", s(&out)]));
    let meta = std::fs::metadata(&out).unwrap();
    assert_eq!(meta.permissions().mode() & 0o777, 0o600);
    assert!(meta.len() > 3);
    let linked = d.join("linked.obj");
    let other = d.join("other.obj");
    std::fs::write(&linked, "old").unwrap();
    std::fs::hard_link(&linked, &other).unwrap();
    let report = d.join("r.json");
    let o = run(&[
        "smooth",
        s(&input),
        "--report",
        s(&report),
        "-o",
        s(&linked),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("linked.obj") && err.contains("has 2 hard links") && err.contains("break"),
        "{err}"
    );
    assert!(!report.exists());
    assert_eq!(std::fs::read_to_string(&linked).unwrap(), "old");
    assert_eq!(std::fs::read_to_string(&other).unwrap(), "old");
    let _ = std::fs::remove_dir_all(&d);
}
