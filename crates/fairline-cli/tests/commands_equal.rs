//! The commands run by the workbench are the CLI's: for each command the
//! workbench runs (fair, smooth, fair-quad, enhance, fair-surface), the
//! job's equivalent
//! command line, run by the CLI, writes the bytes the workbench serves and
//! the report the workbench shows (every key but the computation times);
//! the workbench's detection and its surface pre-images give the reports
//! of their `fairline detect` and `fairline highlight` command lines.

mod common;
use common::{bin, s, tmp};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// A running `fairline view` on one mesh.
struct Server {
    child: Child,
    port: u16,
    token: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Server {
    fn start(mesh: &Path, dir: &Path) -> Server {
        let mut child = bin()
            .args(["view", s(mesh), "--no-open", "--save-dir", s(dir)])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start fairline view");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line.trim().to_string();
        let rest = url.strip_prefix("http://127.0.0.1:").expect("the URL");
        let port = rest.split('/').next().unwrap().parse().unwrap();
        let token = url.split("token=").nth(1).unwrap().to_string();
        Server { child, port, token }
    }

    /// One request; the status and the body.
    fn call(&self, method: &str, path: &str, body: Option<&Value>) -> (u16, Vec<u8>) {
        let body = body.map(|b| b.to_string()).unwrap_or_default();
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        let req = format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\nX-Fairline-Token: {}\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
            self.port,
            self.token,
            body.len()
        );
        stream.write_all(req.as_bytes()).unwrap();
        let mut resp = Vec::new();
        stream.read_to_end(&mut resp).unwrap();
        let split = resp.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
        let head = String::from_utf8_lossy(&resp[..split]).to_ascii_lowercase();
        let status = head.split(' ').nth(1).unwrap().parse().unwrap();
        let mut out = resp[split + 4..].to_vec();
        if head.contains("transfer-encoding: chunked") {
            out = dechunk(&out);
        }
        (status, out)
    }

    fn json(&self, path: &str, body: Option<&Value>) -> Value {
        let (st, b) = self.call(if body.is_some() { "POST" } else { "GET" }, path, body);
        assert_eq!(st, 200, "{path}: {}", String::from_utf8_lossy(&b));
        serde_json::from_slice(&b).unwrap()
    }

    /// Runs a job and waits for it; the finished job.
    fn job(&self, request: &Value) -> Value {
        self.json("/api/doc/0/run", Some(request));
        let t = Instant::now();
        loop {
            let j = self.json("/api/job", None);
            if j["state"] != "running" && j["state"] != "cancelling" {
                assert_eq!(j["state"], "done", "{j}");
                return j;
            }
            assert!(t.elapsed() < Duration::from_secs(120), "job did not finish");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let nl = b.windows(2).position(|w| w == b"\r\n").unwrap();
        let n = usize::from_str_radix(std::str::from_utf8(&b[..nl]).unwrap().trim(), 16).unwrap();
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[nl + 2..nl + 2 + n]);
        b = &b[nl + 2 + n + 2..];
    }
}

/// A wavy panel with a dent at (0.5, −0.4), n × n vertices over [−2, 2]²,
/// as triangles (or quads with `quads`), with a small zigzag in the grid
/// so that quad fairing has structure lines to straighten.
fn panel(path: &Path, n: usize, quads: bool) {
    let mut text = String::new();
    let h = |x: f64, y: f64| {
        0.15 * (1.3 * x).sin() * (0.9 * y).cos()
            - 0.01 * (-((x - 0.5).powi(2) + (y + 0.4).powi(2)) / (0.16f64 * 0.16)).exp()
    };
    let step = 4.0 / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let inner = i > 0 && j > 0 && i < n - 1 && j < n - 1;
            let wiggle = if inner && j % 2 == 0 {
                0.15 * step
            } else {
                0.0
            };
            let x = -2.0 + step * i as f64 + wiggle;
            let y = -2.0 + step * j as f64;
            text.push_str(&format!("v {x} {y} {}\n", h(x, y)));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            if quads {
                text.push_str(&format!("f {a} {b} {c} {d}\n"));
            } else {
                text.push_str(&format!("f {a} {b} {c}\nf {a} {c} {d}\n"));
            }
        }
    }
    std::fs::write(path, text).unwrap();
}

/// The report without its computation times (`time_s` at any depth:
/// fair-surface's history has one per iteration; the stage timings of
/// `enhance`).
fn without_time(mut v: Value) -> Value {
    match &mut v {
        Value::Object(m) => {
            m.remove("time_s");
            m.remove("timings");
            for x in m.values_mut() {
                *x = without_time(x.take());
            }
        }
        Value::Array(a) => {
            for x in a.iter_mut() {
                *x = without_time(x.take());
            }
        }
        _ => {}
    }
    v
}

/// Runs the job `request` on the server, then its equivalent command line
/// with the CLI in `dir` (the region and fixed files the workbench gives
/// for the job's faces), and asserts the same output bytes and report.
fn same_as_cli(srv: &Server, dir: &Path, request: Value) {
    let faces = request["faces"].clone();
    let files = srv.json("/api/doc/0/region-file", Some(&json!({"faces": faces})));
    std::fs::write(dir.join("region.json"), files["region"].to_string()).unwrap();
    std::fs::write(dir.join("fixed.json"), files["fixed"].to_string()).unwrap();
    let job = srv.job(&request);
    same_job_as_cli(srv, dir, &job);
}

/// Runs the equivalent command line of the finished `job` with the CLI in
/// `dir` (which holds the files the command line names) and asserts the
/// same output bytes and report; undoes the job.
fn same_job_as_cli(srv: &Server, dir: &Path, job: &Value) {
    let command = job["command"].as_str().unwrap().to_string();
    let words: Vec<&str> = command.split(' ').collect();
    assert_eq!(words[0], "fairline", "{command}");
    let out_name = words[words.iter().position(|w| *w == "-o").unwrap() + 1];
    let o = bin()
        .current_dir(dir)
        .args(&words[1..])
        .args(["--report", "report.json"])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{command}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let ext = Path::new(out_name).extension().unwrap().to_str().unwrap();
    let (st, served) = srv.call("GET", &format!("/api/doc/0/download?format={ext}"), None);
    assert_eq!(st, 200);
    let written = std::fs::read(dir.join(out_name)).unwrap();
    assert!(
        served == written,
        "{command}: the workbench's result differs"
    );
    let report = common::json(&dir.join("report.json"));
    assert_eq!(
        without_time(job["report"].clone()),
        without_time(report),
        "{command}"
    );
    srv.json("/api/doc/0/undo", Some(&json!({})));
}

/// The faces within `radius` of `point` (as the page's sphere tool).
fn sphere_faces(srv: &Server, point: [f64; 3], radius: f64) -> Value {
    let session = srv.json("/api/session", None);
    let c: Vec<f64> = serde_json::from_value(session["docs"][0]["center"].clone()).unwrap();
    let center = [point[0] - c[0], point[1] - c[1], point[2] - c[2]];
    let r = srv.json(
        "/api/doc/0/region",
        Some(&json!({"op": "sphere", "center": center, "radius": radius})),
    );
    r["faces"].clone()
}

#[test]
fn the_workbench_runs_the_clis_fair_smooth_and_enhance() {
    let dir = tmp("commands-equal");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 41, false);
    let srv = Server::start(&mesh, &dir);
    let faces = sphere_faces(&srv, [0.5, -0.4, 0.0], 0.6);
    let light =
        json!({"plane_point":[0,0,6],"plane_normal":[0,0,1],"direction":[1,0,0],"spacing":0.1});
    same_as_cli(
        &srv,
        &dir,
        json!({"method": "fair", "faces": faces, "light": light,
               "options": {"method": "highlight", "max_iterations": 4}}),
    );
    same_as_cli(
        &srv,
        &dir,
        json!({"method": "fair", "faces": faces, "light": light,
               "options": {"method": "diffusion-flow", "max_iterations": 3}}),
    );
    for options in [
        json!({"method": "taubin", "iterations": 5}),
        json!({"method": "laplace", "weights": "uniform", "lambda": 0.3, "iterations": 2}),
        json!({"method": "implicit"}),
    ] {
        same_as_cli(
            &srv,
            &dir,
            json!({"method": "smooth", "faces": faces, "options": options}),
        );
    }
    same_as_cli(
        &srv,
        &dir,
        json!({"method": "enhance", "faces": faces, "options": {"lambda": 0.8, "mu": 0.5}}),
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_workbench_runs_the_clis_fair_quad() {
    let dir = tmp("commands-equal-quad");
    let mesh = dir.join("quads.obj");
    panel(&mesh, 13, true);
    let srv = Server::start(&mesh, &dir);
    let faces = sphere_faces(&srv, [0.0, 0.0, 0.0], 1.2);
    same_as_cli(
        &srv,
        &dir,
        json!({"method": "fair-quad", "faces": faces, "options": {"weight": 0.02, "iterations": 2}}),
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_workbench_runs_the_clis_fair_surface() {
    let dir = tmp("commands-equal-surface");
    let o = bin()
        .current_dir(&dir)
        .args(["demo", "--out", "demo"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let demo = dir.join("demo");
    let panel = dir.join("panel.json");
    std::fs::copy(demo.join("bspline-panel-dented.json"), &panel).unwrap();
    let lights = common::json(&demo.join("bspline-panel-lights.json"));
    let ends = common::json(&demo.join("bspline-panel-endpoints.json"));
    std::fs::write(dir.join("lights.json"), lights.to_string()).unwrap();
    std::fs::write(dir.join("endpoints.json"), ends.to_string()).unwrap();
    let srv = Server::start(&panel, &dir);
    // the pre-images the page draws: the report of their command line
    let (st, b) = srv.call(
        "POST",
        "/api/doc/0/surface-lines",
        Some(&json!({"circular": lights, "patch": 0, "grid": 120, "band": 0.05})),
    );
    assert_eq!(st, 200, "{}", String::from_utf8_lossy(&b));
    let header = frame_header(&b);
    let report = cli_report(&dir, header["command"].as_str().unwrap());
    assert!(report["lines"].as_u64().unwrap() > 0, "{report}");
    assert_eq!(without_time(header["report"].clone()), without_time(report));
    for options in [json!({"max_iterations": 3}), json!({})] {
        let job = srv.job(
            &json!({"method": "fair-surface", "patch": 0, "circular": lights,
            "endpoints": ends["endpoints"], "options": options}),
        );
        assert!(job["report"]["modified_control_points"].as_u64().unwrap() > 0);
        same_job_as_cli(&srv, &dir, &job);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs the CLI command line `command` in `dir` with `--report
/// report.json`; the report.
fn cli_report(dir: &Path, command: &str) -> Value {
    let words: Vec<&str> = command.split(' ').collect();
    assert_eq!(words[0], "fairline", "{command}");
    let o = bin()
        .current_dir(dir)
        .args(&words[1..])
        .args(["--report", "report.json"])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{command}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    common::json(&dir.join("report.json"))
}

/// The JSON header of a binary frame answer.
fn frame_header(b: &[u8]) -> Value {
    let len = u32::from_le_bytes(b[..4].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[4..4 + len]).unwrap()
}

#[test]
fn the_workbench_detects_as_the_cli() {
    let dir = tmp("commands-equal-detect");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 41, false);
    let srv = Server::start(&mesh, &dir);
    let light =
        json!({"plane_point":[0,0,6],"plane_normal":[0,0,1],"direction":[1,0,0],"spacing":0.1});
    for request in [
        json!({"light": light}),
        json!({"light": light, "threshold": 1.5, "region_radius": 0.5}),
    ] {
        let (st, b) = srv.call("POST", "/api/doc/0/detect", Some(&request));
        assert_eq!(st, 200, "{}", String::from_utf8_lossy(&b));
        let header = frame_header(&b);
        let command = header["command"].as_str().unwrap();
        assert!(command.starts_with("fairline detect "), "{command}");
        let report = cli_report(&dir, command);
        assert!(
            !report["regions"].as_array().unwrap().is_empty(),
            "{report}"
        );
        assert_eq!(
            without_time(header["report"].clone()),
            without_time(report.clone()),
            "{command}"
        );
        let regions = header["regions"].as_array().unwrap();
        assert_eq!(regions.len(), report["regions"].as_array().unwrap().len());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
