//! The output policy of every command and what commands say on the
//! terminal: outputs checked
//! against inputs and each other before any work, special files refused,
//! no temporary file left on SIGINT/SIGTERM, a closed pipe ends quietly,
//! reports without null, a summary and warnings on standard error.

mod common;
use common::{json, ok, run, s, tmp};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Stdio;

/// An n × n grid of triangles over a wavy height field, as OBJ text.
fn wavy_obj(n: usize) -> String {
    let mut t = String::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let z = 0.1 * (6.0 * x).sin() * (5.0 * y).cos();
            writeln!(t, "v {x} {y} {z}").unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n, a + n + 1);
            writeln!(t, "f {a} {b} {d}\nf {a} {d} {c}").unwrap();
        }
    }
    t
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The names of the files in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn temp_files(dir: &Path) -> Vec<String> {
    names(dir)
        .into_iter()
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// A folder with `in.obj` (wavy grid), a B-spline surface, lights,
/// endpoints and a fixed-vertex file.
fn setup(tag: &str) -> PathBuf {
    let d = tmp(tag);
    std::fs::write(d.join("in.obj"), wavy_obj(12)).unwrap();
    std::fs::write(d.join("fixed.json"), r#"{"vertices":[0,1]}"#).unwrap();
    std::fs::write(
        d.join("lights.json"),
        r#"{"plane_point":[0.5,0.5,3],"plane_normal":[0,0,1],"direction":[0,1,0],"spacing":0.1}"#,
    )
    .unwrap();
    d
}

#[test]
fn an_output_naming_an_input_is_refused_by_every_command_and_nothing_is_written() {
    let d = setup("clash");
    let input = d.join("in.obj");
    let original = std::fs::read(&input).unwrap();
    let (i, o, png) = (s(&input), d.join("o.obj"), d.join("p.png"));
    let dotted = format!("{}/./in.obj", d.display());
    let lights = d.join("lights.json");
    let fixed = d.join("fixed.json");
    let cases: Vec<Vec<&str>> = vec![
        vec!["smooth", i, "-o", s(&o), "--report", i],
        vec!["smooth", i, "-o", s(&o), "--report", &dotted],
        vec!["smooth", i, "-o", s(&o), "--png", i],
        vec!["fair-quad", i, "-o", s(&o), "--report", i],
        vec!["curvature", i, "-o", "x.ply", "--report", i],
        vec!["info", i, "--report", i],
        vec!["render", i, "--png", s(&png), "--report", i],
        vec!["detect", i, "-o", "r.json", "--report", i],
        vec!["convert", i, s(&o), "--report", i],
        vec!["highlight", i, "-o", "l.json", "--report", i],
        vec!["enhance", i, "-o", s(&o), "--report", i],
        vec!["fair", i, "--auto", "-o", s(&o), "--report", i],
        // files read besides the mesh are inputs too
        vec!["highlight", i, "--lights", s(&lights), "-o", s(&lights)],
        vec!["detect", i, "--lights", s(&lights), "-o", s(&lights)],
        vec![
            "smooth",
            i,
            "--fixed",
            s(&fixed),
            "-o",
            s(&o),
            "--report",
            s(&fixed),
        ],
        vec![
            "enhance",
            i,
            "--fixed",
            s(&fixed),
            "-o",
            s(&o),
            "--report",
            s(&fixed),
        ],
    ];
    let before = names(&d);
    for args in cases {
        // relative outputs are resolved in the test folder
        let out = run_in(&d, &args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        let e = stderr(&out);
        assert!(e.contains("refusing to write"), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
        assert_eq!(names(&d), before, "{args:?} wrote something");
        assert_eq!(std::fs::read(&input).unwrap(), original);
        assert!(
            std::fs::read_to_string(&lights)
                .unwrap()
                .contains("spacing")
        );
    }
}

fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    common::bin().current_dir(dir).args(args).output().unwrap()
}

#[test]
fn fair_surface_refuses_to_write_over_its_lights_endpoints_or_surface() {
    let d = tmp("surface-clash");
    let (surface, lights, ends) = (d.join("s.json"), d.join("lights.json"), d.join("ends.json"));
    std::fs::write(&surface, "{}").unwrap();
    std::fs::write(&lights, r#"{"center":[0,0,3],"axis":[0,0,1],"radii":[1]}"#).unwrap();
    std::fs::write(&ends, r#"{"endpoints":[]}"#).unwrap();
    for (flag, target) in [
        ("-o", &lights),
        ("-o", &ends),
        ("--report", &surface),
        ("--report", &ends),
    ] {
        let mut args = vec![
            "fair-surface",
            s(&surface),
            "--lights",
            s(&lights),
            "--endpoints",
            s(&ends),
        ];
        if flag == "-o" {
            args.extend(["-o", s(target)]);
        } else {
            args.extend(["-o", "out.json", "--report", s(target)]);
        }
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("refusing to write"), "{}", stderr(&o));
    }
    assert_eq!(names(&d), ["ends.json", "lights.json", "s.json"]);
}

#[test]
fn two_outputs_with_one_path_are_refused() {
    let d = setup("two-outputs");
    let i = d.join("in.obj");
    let o = d.join("o.obj");
    let alias = d.join("sub/../o.obj");
    std::fs::create_dir(d.join("sub")).unwrap();
    for args in [
        vec!["smooth", s(&i), "-o", s(&o), "--report", s(&o)],
        vec!["smooth", s(&i), "-o", s(&o), "--report", s(&alias)],
        vec!["convert", s(&i), s(&o), "--report", s(&o)],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(stderr(&out).contains("same file"), "{}", stderr(&out));
        assert!(!o.exists());
    }
}

#[test]
fn a_missing_report_folder_is_found_before_any_output_is_written() {
    // defect 5: `smooth -o ok.obj --report missing-dir/r.json` left ok.obj
    let d = setup("partial");
    let i = d.join("in.obj");
    let ok_obj = d.join("ok.obj");
    let r = d.join("missing-dir/r.json");
    let png = d.join("missing-dir/p.png");
    for args in [
        vec!["smooth", s(&i), "-o", s(&ok_obj), "--report", s(&r)],
        vec!["curvature", s(&i), "-o", "ok.ply", "--report", s(&r)],
        vec!["convert", s(&i), s(&ok_obj), "--report", s(&r)],
        vec!["highlight", s(&i), "-o", "ok.json", "--report", s(&r)],
        vec!["detect", s(&i), "-o", "ok.json", "--png", s(&png)],
    ] {
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("missing-dir"), "{}", stderr(&o));
        assert_eq!(
            names(&d),
            ["fixed.json", "in.obj", "lights.json"],
            "{args:?}"
        );
    }
}

#[cfg(unix)]
#[test]
fn special_files_and_folders_are_never_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let d = setup("special");
    let i = d.join("in.obj");
    let fifo = d.join("pipe.json");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    let have_fifo = made.map(|s| s.success()).unwrap_or(false);
    let folder = d.join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    let mut cases = vec![
        vec!["smooth", s(&i), "-o", "o.obj", "--report", "/dev/null"],
        vec!["convert", s(&i), "/dev/null"],
        vec!["convert", s(&i), "/dev/stdout"],
        vec!["convert", s(&i), "-"],
        vec!["convert", s(&i), s(&folder)],
        vec!["info", s(&i), "--report", "/dev/null"],
    ];
    if have_fifo {
        cases.push(vec!["smooth", s(&i), "-o", "o.obj", "--report", s(&fifo)]);
    }
    for args in cases {
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!d.join("o.obj").exists());
    }
    let null = std::fs::metadata("/dev/null").unwrap();
    assert!(null.file_type().is_char_device());
    assert!(folder.is_dir());
    if have_fifo {
        assert!(
            std::fs::symlink_metadata(&fifo)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }
}

#[cfg(unix)]
#[test]
fn convert_refuses_its_input_under_another_name() {
    let d = setup("convert-same");
    let i = d.join("in.obj");
    let original = std::fs::read(&i).unwrap();
    std::os::unix::fs::symlink(&i, d.join("sym.obj")).unwrap();
    std::fs::hard_link(&i, d.join("hard.obj")).unwrap();
    for out in ["./in.obj", "sym.obj", "hard.obj", "../convert-same/in.obj"] {
        let out = if out.starts_with("../") {
            format!("../{}/in.obj", d.file_name().unwrap().to_string_lossy())
        } else {
            out.to_string()
        };
        let o = run_in(&d, &["convert", "in.obj", &out]);
        assert_eq!(o.status.code(), Some(2), "{out}: {}", stderr(&o));
        assert_eq!(std::fs::read(&i).unwrap(), original, "{out}");
    }
    // a symbolic link to another file is written through: the link stays
    std::fs::write(d.join("target.off"), "old").unwrap();
    std::os::unix::fs::symlink(d.join("target.off"), d.join("link.off")).unwrap();
    ok(&run_in(&d, &["convert", "in.obj", "link.off"]));
    assert!(
        std::fs::symlink_metadata(d.join("link.off"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        std::fs::read_to_string(d.join("target.off"))
            .unwrap()
            .starts_with("OFF")
    );
}

/// A grid of n × n vertices as ASCII OFF.
fn big_off(path: &Path, n: usize) {
    let mut t = String::with_capacity(n * n * 40);
    writeln!(t, "OFF\n{} {} 0", n * n, 2 * (n - 1) * (n - 1)).unwrap();
    for j in 0..n {
        for i in 0..n {
            writeln!(
                t,
                "{} {} {}",
                i as f64 * 0.37,
                j as f64 * 0.41,
                ((i * j) % 7) as f64 * 0.13
            )
            .unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            writeln!(
                t,
                "3 {} {} {}\n3 {} {} {}",
                a,
                a + 1,
                a + n + 1,
                a,
                a + n + 1,
                a + n
            )
            .unwrap();
        }
    }
    std::fs::write(path, t).unwrap();
}

/// Sends `signal` to the `fairline convert` of a large mesh while it
/// writes its output (its temporary file exists), and checks that it
/// exits with 128 + the signal number and leaves no temporary file and
/// no output.
#[cfg(unix)]
fn interrupted_while_writing(signal: &str, code: i32) {
    let d = tmp(&format!("signal-{signal}"));
    let mut n = 700;
    for attempt in 0..6 {
        let input = d.join("big.off");
        big_off(&input, n);
        let out = d.join("out.obj");
        let mut child = common::bin()
            .args(["convert", s(&input), s(&out)])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        let mut sent = false;
        while start.elapsed().as_secs() < 120 {
            if child.try_wait().unwrap().is_some() {
                break;
            }
            if temp_files(&d).iter().any(|n| n.starts_with(".out.obj.")) {
                let status = std::process::Command::new("kill")
                    .args(["-s", signal, &child.id().to_string()])
                    .status()
                    .unwrap();
                assert!(status.success());
                sent = true;
                break;
            }
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        let o = child.wait_with_output().unwrap();
        assert!(
            temp_files(&d).is_empty(),
            "{signal}: temporary files left: {:?}",
            names(&d)
        );
        if sent && o.status.code() == Some(code) {
            assert!(!out.exists(), "{signal}: an interrupted output was written");
            assert!(stderr(&o).contains("temporary file"), "{}", stderr(&o));
            return;
        }
        // the write finished before the signal arrived: a larger mesh
        let _ = std::fs::remove_file(&out);
        n = n * 3 / 2;
        eprintln!("attempt {attempt}: the write finished first; trying {n} × {n}");
    }
    panic!("{signal}: never caught the write in progress");
}

#[cfg(unix)]
#[test]
fn sigint_and_sigterm_remove_temporary_files() {
    interrupted_while_writing("INT", 130);
    interrupted_while_writing("TERM", 143);
}

#[test]
fn a_closed_standard_output_ends_quietly() {
    // defect 7: `fairline info X | head -1` panicked
    let d = setup("pipe");
    for extra in [None, Some("--json")] {
        let mut cmd = common::bin();
        cmd.arg("info").arg(d.join("in.obj"));
        if let Some(e) = extra {
            cmd.arg(e);
        }
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader goes away before any output
        let o = child.wait_with_output().unwrap();
        let e = stderr(&o);
        assert!(!e.contains("panicked"), "{e}");
        assert_eq!(o.status.code(), Some(0), "{e}");
    }
}

#[test]
fn reports_never_contain_null_and_say_what_was_left_out() {
    // defect 8: a tetrahedron of edge 1e150 has a volume of about 1e449,
    // beyond f64; serde_json would write it as null
    let d = tmp("null");
    let m = d.join("huge.obj");
    std::fs::write(
        &m,
        "v 0 0 0\nv 1e150 0 0\nv 0 1e150 0\nv 0 0 1e150\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let r = d.join("r.json");
    let o = run(&[
        "smooth",
        s(&m),
        "--method",
        "laplace",
        "-o",
        s(&d.join("o.obj")),
        "--report",
        s(&r),
    ]);
    ok(&o);
    let text = std::fs::read_to_string(&r).unwrap();
    assert!(!text.contains("null"), "{text}");
    let e = stderr(&o);
    assert!(
        e.contains("warning: report value `volume_before` is not a finite number; left out"),
        "{e}"
    );
    let v = json(&r);
    assert!(v.get("volume_before").is_none());
    assert!(v["max_displacement"].as_f64().unwrap() > 1e148);
    assert_eq!(v["warnings"].as_array().unwrap().len(), 2);
    assert_eq!(v["vertices"], 4);
    // a non-manifold mesh has no genus: the key is left out, not null
    let nm = d.join("nm.obj");
    std::fs::write(
        &nm,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let o = run(&["info", s(&nm), "--json", "--report", s(&r)]);
    ok(&o);
    assert!(!std::fs::read_to_string(&r).unwrap().contains("null"));
    assert!(!String::from_utf8_lossy(&o.stdout).contains("null"));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

#[test]
fn every_command_ends_with_a_summary_line_naming_its_outputs() {
    let d = setup("summary");
    let i = d.join("in.obj");
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        ("info", vec!["info", s(&i)], "12x12"),
        ("convert", vec!["convert", s(&i), "c.off"], "c.off"),
        (
            "curvature",
            vec!["curvature", s(&i), "-o", "k.ply"],
            "k.ply",
        ),
        (
            "smooth",
            vec!["smooth", s(&i), "-o", "s.obj", "--report", "s.json"],
            "s.obj, s.json",
        ),
        (
            "highlight",
            vec!["highlight", s(&i), "-o", "h.json"],
            "h.json",
        ),
        ("detect", vec!["detect", s(&i), "-o", "d.json"], "d.json"),
        ("render", vec!["render", s(&i), "--png", "r.png"], "r.png"),
        ("enhance", vec!["enhance", s(&i), "-o", "e.obj"], "e.obj"),
    ];
    for (cmd, args, wrote) in cases {
        let o = run_in(&d, &args);
        ok(&o);
        let e = stderr(&o);
        let line = e
            .lines()
            .find(|l| l.starts_with(&format!("fairline {cmd}: ")))
            .unwrap_or_else(|| panic!("{cmd}: no summary in {e:?}"));
        assert!(line.contains(" s"), "{line}");
        if cmd != "info" {
            assert!(line.ends_with(&format!("; wrote {wrote}")), "{line}");
        }
    }
}

#[test]
fn non_convergence_and_worse_measures_are_warned_about() {
    let d = setup("warn");
    let i = d.join("in.obj");
    // spring smoothing cut off after one sweep
    let o = run_in(
        &d,
        &[
            "smooth",
            s(&i),
            "--method",
            "spring",
            "--iterations",
            "1",
            "-o",
            "s.obj",
            "--report",
            "r.json",
        ],
    );
    ok(&o);
    let e = stderr(&o);
    assert!(
        e.contains("warning: spring did not converge in 1 iteration(s)"),
        "{e}"
    );
    assert!(e.contains("not converged"), "{e}");
    let r = json(&d.join("r.json"));
    assert_eq!(r["converged"], false);
    assert!(
        r["warnings"][0]
            .as_str()
            .unwrap()
            .contains("did not converge")
    );
    // a fixed number of Laplace steps: nothing to warn about
    let o = run_in(&d, &["smooth", s(&i), "--method", "laplace", "-o", "s.obj"]);
    ok(&o);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    // report values are spelled like the option values
    let o = run_in(
        &d,
        &[
            "smooth",
            s(&i),
            "--method",
            "schneider-kobbelt",
            "--iterations",
            "2",
            "-o",
            "s.obj",
            "--report",
            "r.json",
        ],
    );
    // (cut off after two sweeps it did not converge: exit 1, the reason in
    // the report)
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let r = json(&d.join("r.json"));
    assert_eq!(r["method"], "schneider-kobbelt");
    assert_eq!(r["stop_reason"], "max_iterations");
}

#[test]
fn demo_never_writes_into_a_folder_it_did_not_make() {
    let d = tmp("demo-folder");
    std::fs::write(d.join("precious.png"), "mine").unwrap();
    let o = run(&["demo", "--out", s(&d), "--size", "64x48"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not empty"), "{}", stderr(&o));
    assert_eq!(names(&d), ["precious.png"]);
    assert_eq!(
        std::fs::read_to_string(d.join("precious.png")).unwrap(),
        "mine"
    );
    // a file given as the folder
    let o = run(&["demo", "--out", s(&d.join("precious.png"))]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn errors_reading_inputs_name_the_file() {
    let d = setup("names");
    let i = d.join("in.obj");
    let bad = d.join("bad-file.json");
    std::fs::write(&bad, "{\"oops\": ").unwrap();
    let bad_obj = d.join("bad-mesh.obj");
    std::fs::write(&bad_obj, "v 0 0 0\nv 1 0\nf 1 2 3\n").unwrap();
    let lights = d.join("lights.json");
    let zero_axis = d.join("zero-axis.json");
    std::fs::write(
        &zero_axis,
        r#"{"center":[0,0,1],"axis":[0,0,0],"radii":[1]}"#,
    )
    .unwrap();
    let bad_igs = d.join("bad-surface.igs");
    std::fs::write(&bad_igs, "not an iges file\n").unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["smooth", s(&i), "--fixed", s(&bad), "-o", "o.obj"],
            "bad-file.json",
        ),
        (
            vec!["enhance", s(&i), "--fixed", s(&bad), "-o", "o.obj"],
            "bad-file.json",
        ),
        (
            vec!["highlight", s(&i), "--lights", s(&bad), "-o", "h.json"],
            "bad-file.json",
        ),
        (
            vec!["fair", s(&i), "--region", s(&bad), "-o", "o.obj"],
            "bad-file.json",
        ),
        (vec!["info", s(&bad_obj)], "bad-mesh.obj"),
        (vec!["smooth", s(&bad_obj), "-o", "o.obj"], "bad-mesh.obj"),
        (vec!["convert", s(&bad), "o.obj"], "bad-file.json"),
        (vec!["convert", s(&bad_igs), "o.json"], "bad-surface.igs"),
        (vec!["render", s(&bad), "--png", "p.png"], "bad-file.json"),
        (
            vec![
                "fair-surface",
                s(&bad),
                "--lights",
                s(&lights),
                "--endpoints",
                s(&bad),
                "-o",
                "o.json",
            ],
            "bad-file.json",
        ),
    ];
    for (args, file) in cases {
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains(file),
            "{args:?}: the error does not name {file}: {e}"
        );
        assert!(!e.contains("panicked"), "{e}");
    }
}

/// A replaced output keeps its permissions; one with other hard links is
/// refused (a rename would leave the other names with the old content).
#[cfg(unix)]
#[test]
fn replaced_outputs_keep_their_mode_and_hard_links_are_refused() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp("outputs-mode");
    let input = dir.join("in.obj");
    std::fs::write(&input, wavy_obj(6)).unwrap();
    let out = dir.join("out.ply");
    std::fs::write(&out, "old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
    ok(&run(&["convert", s(&input), s(&out)]));
    let meta = std::fs::metadata(&out).unwrap();
    assert_eq!(meta.permissions().mode() & 0o777, 0o600);
    assert!(meta.len() > 3);
    let linked = dir.join("linked.ply");
    let other = dir.join("other-name.ply");
    std::fs::write(&linked, "old").unwrap();
    std::fs::hard_link(&linked, &other).unwrap();
    let o = run(&["convert", s(&input), s(&linked)]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("hard links") && err.contains("linked.ply"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&linked).unwrap(), "old");
    assert_eq!(std::fs::read_to_string(&other).unwrap(), "old");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `fairline` in `dir` with `args`, killing it after `secs` seconds
/// (a run that waits on a FIFO must fail the test, not hang it).
fn run_in_bounded(dir: &Path, args: &[&str], secs: u64) -> std::process::Output {
    let mut child = common::bin()
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed().as_secs() >= secs {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("{args:?}: still running after {secs} s: {}", stderr(&o));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// An input that is not a regular file — a device that never ends
/// (`/dev/zero`, `/dev/urandom` under a mesh name), a FIFO (opening it
/// would wait for a writer), a directory — is refused before it is opened:
/// exit status 2, the file named, nothing written, promptly.
#[cfg(unix)]
#[test]
fn inputs_that_are_not_regular_files_are_refused_unread() {
    let d = setup("special-inputs");
    let i = d.join("in.obj");
    let zero = d.join("zero.stl");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let random = d.join("random.ply");
    std::os::unix::fs::symlink("/dev/urandom", &random).unwrap();
    let fifo_mesh = d.join("pipe.obj");
    let fifo_json = d.join("pipe.json");
    for f in [&fifo_mesh, &fifo_json] {
        let made = std::process::Command::new("mkfifo").arg(f).status();
        assert!(made.unwrap().success(), "mkfifo {}", f.display());
    }
    let folder = d.join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    let zero_json = d.join("zero.json");
    std::os::unix::fs::symlink("/dev/zero", &zero_json).unwrap();
    let cases: Vec<(Vec<&str>, &Path, &str)> = vec![
        (vec!["info", s(&zero)], &zero, "is a device"),
        (
            vec!["smooth", s(&zero), "-o", "o.obj"],
            &zero,
            "is a device",
        ),
        (
            vec!["curvature", s(&random), "-o", "o.ply"],
            &random,
            "is a device",
        ),
        (
            vec!["info", s(&fifo_mesh)],
            &fifo_mesh,
            "is a FIFO (named pipe)",
        ),
        (
            vec!["convert", s(&fifo_mesh), "o.obj"],
            &fifo_mesh,
            "is a FIFO (named pipe)",
        ),
        (vec!["info", s(&folder)], &folder, "is a directory"),
        (
            vec!["fair", s(&i), "--region", s(&fifo_json), "-o", "o.obj"],
            &fifo_json,
            "is a FIFO (named pipe)",
        ),
        (
            vec!["smooth", s(&i), "--fixed", s(&zero_json), "-o", "o.obj"],
            &zero_json,
            "is a device",
        ),
        (vec!["info", s(&zero_json)], &zero_json, "is a device"),
        (
            vec!["render", s(&zero_json), "--png", "p.png"],
            &zero_json,
            "is a device",
        ),
    ];
    for (args, file, what) in cases {
        let o = run_in_bounded(&d, &args, 30);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains(&format!(
                "error: {}: {what}, not a regular file",
                file.display()
            )),
            "{args:?}: {e}"
        );
        assert!(!e.contains("panicked"), "{e}");
        for out in ["o.obj", "o.ply", "p.png"] {
            assert!(!d.join(out).exists(), "{args:?} wrote {out}");
        }
    }
}

/// Writes `text` as `name` in `dir` and returns its path.
fn put(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A mesh without faces — no vertex at all, or vertices only — gives
/// every command but `info` exit status 2 and a message naming the file,
/// and writes nothing; `info` counts it and says it holds no surface.
#[test]
fn meshes_without_faces_are_refused_by_every_command_and_counted_by_info() {
    let d = setup("no-faces");
    let empty_ply = put(
        &d,
        "empty.ply",
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty double x\nproperty double y\nproperty double z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
    );
    let empty_off = put(&d, "empty.off", "OFF\n0 0 0\n");
    let empty_stl = put(&d, "empty.stl", "solid nothing\nendsolid nothing\n");
    let points = put(&d, "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let commands: Vec<Vec<&str>> = vec![
        vec!["smooth", "-o", "o.obj", "--report", "r.json"],
        vec!["fair", "--auto", "-o", "o.obj", "--report", "r.json"],
        vec!["detect", "-o", "r.json"],
        vec!["highlight", "-o", "o.json"],
        vec!["curvature", "-o", "o.ply"],
        vec!["render", "--png", "p.png"],
        vec!["enhance", "-o", "o.obj"],
        vec!["fair-quad", "-o", "o.obj"],
    ];
    for mesh in [&empty_ply, &empty_off, &empty_stl, &points] {
        let none = mesh != &points;
        let mut runs: Vec<Vec<&str>> = commands
            .iter()
            .map(|c| {
                let mut args = vec![c[0], s(mesh)];
                args.extend_from_slice(&c[1..]);
                args
            })
            .collect();
        runs.push(vec!["repair", s(mesh), "o.obj", "--report", "r.json"]);
        for args in runs {
            let o = run_in(&d, &args);
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
            let said = if none {
                "the mesh is empty (no vertex, no face): there is no surface to work on"
            } else {
                "the mesh has no faces, only 3 vertices: there is no surface to work on"
            };
            assert!(
                e.contains(&format!("error: {}: {said}", mesh.display())),
                "{args:?}: {e}"
            );
            assert!(!e.contains("panicked"), "{e}");
            assert!(temp_files(&d).is_empty(), "{args:?}: {:?}", names(&d));
            for out in ["o.obj", "o.ply", "o.json", "r.json", "p.png"] {
                assert!(!d.join(out).exists(), "{args:?} wrote {out}");
            }
        }
        // info: the counts, no made-up box, edge lengths or genus, and a
        // warning that there is no surface
        let o = run_in(&d, &["info", s(mesh), "--json", "--report", "r.json"]);
        ok(&o);
        let e = stderr(&o);
        assert!(
            e.contains(&format!("warning: {}: the file ", mesh.display())),
            "{e}"
        );
        assert!(e.contains("0 faces, no surface"), "{e}");
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["faces"], 0, "{j}");
        assert_eq!(j["vertices"], if none { 0 } else { 3 }, "{j}");
        assert!(j.get("edge_length").is_none(), "{j}");
        assert!(j.get("genus").is_none(), "{j}");
        assert_eq!(j.get("bbox").is_none(), none, "{j}");
        let r = json(&d.join("r.json"));
        assert!(
            r["warnings"][0].as_str().unwrap().contains("the file "),
            "{r}"
        );
        std::fs::remove_file(d.join("r.json")).unwrap();
    }
}

/// With standard error not a terminal (a pipe here), a long run prints a
/// line of progress now and then — never a bar redrawn in place — and a
/// quick one prints none. The interval is shortened for the test through
/// the environment.
#[test]
fn progress_off_a_terminal_is_a_line_now_and_then() {
    let d = tmp("progress-lines");
    let big = put(&d, "big.obj", &wavy_obj(150));
    let o = common::bin()
        .current_dir(&d)
        .env("FAIRLINE_PROGRESS_INTERVAL_MS", "20")
        .args(["smooth", s(&big), "--iterations", "400", "-o", "o.obj"])
        .output()
        .unwrap();
    ok(&o);
    let e = stderr(&o);
    let lines: Vec<&str> = e
        .lines()
        .filter(|l| l.starts_with("progress: smoothing, "))
        .collect();
    assert!(!lines.is_empty(), "no progress line: {e}");
    assert!(lines.iter().all(|l| l.ends_with(" s elapsed")), "{e}");
    assert!(!e.contains('\r') && !e.contains('\x1b'), "a bar: {e:?}");
    // the summary comes after the last progress line
    assert!(
        e.trim_end()
            .lines()
            .last()
            .unwrap()
            .starts_with("fairline smooth: "),
        "{e}"
    );
    // a quick run, at the usual interval: no progress line
    let small = put(&d, "small.obj", &wavy_obj(12));
    let o = run_in(&d, &["smooth", s(&small), "-o", "o.obj"]);
    ok(&o);
    assert!(!stderr(&o).contains("progress:"), "{}", stderr(&o));
}

/// A command's outputs are written all or none: when a later output
/// cannot be written (here the picture, over a file-size limit the mesh
/// is under), the mesh written before it is not put in place either, an
/// older file at its path keeps its content, and no temporary file stays.
#[cfg(unix)]
#[test]
fn outputs_are_written_all_or_none() {
    let d = setup("all-or-none");
    let i = d.join("in.obj");
    let args = [
        "smooth",
        s(&i),
        "-o",
        "s.obj",
        "--png",
        "p.png",
        "--report",
        "r.json",
    ];
    ok(&run_in(&d, &args));
    let mesh = std::fs::metadata(d.join("s.obj")).unwrap().len();
    let png = std::fs::metadata(d.join("p.png")).unwrap().len();
    // a limit in blocks the mesh is under and the picture over, whether
    // the shell counts blocks of 512 or of 1024 bytes
    let blocks = mesh / 512 + 1;
    assert!(1024 * blocks < png, "mesh {mesh} B, picture {png} B");
    for f in ["p.png", "r.json"] {
        std::fs::remove_file(d.join(f)).unwrap();
    }
    std::fs::write(d.join("s.obj"), "older\n").unwrap();
    let o = std::process::Command::new("sh")
        .current_dir(&d)
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f {blocks}; exec \"$0\" \"$@\""
        ))
        .arg(env!("CARGO_BIN_EXE_fairline"))
        .args(&args[..])
        .output()
        .unwrap();
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(e.contains("p.png"), "{e}");
    assert!(e.contains("not put in place; nothing written"), "{e}");
    assert_eq!(std::fs::read_to_string(d.join("s.obj")).unwrap(), "older\n");
    assert!(!d.join("p.png").exists() && !d.join("r.json").exists());
    assert!(temp_files(&d).is_empty(), "{:?}", names(&d));
}
