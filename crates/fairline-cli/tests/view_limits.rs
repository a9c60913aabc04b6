//! `fairline view` under hostile local clients (loopback only, bounded
//! loops): slow and idle connections, floods of oversized requests without
//! the token, ambiguous framing, the query token on POST, oversized and long
//! authenticated requests, and the token kept off the opener's command
//! line. Throughout, an authenticated request is answered within a second
//! and the server's resident memory stays under 200 MB.

mod common;
use common::{bin, s, tmp};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The tests of this file measure the server's answer times under load
/// they make themselves; run side by side on two cores they would measure
/// each other. Each takes this lock for its whole run.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn exclusive() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

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
    let url = line.trim();
    let port = url["http://127.0.0.1:".len()..]
        .split('/')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let token = url.split("token=").nth(1).unwrap().to_string();
    Server { child, port, token }
}

/// A grid panel of n × n vertices as OBJ.
fn panel(path: &Path, n: usize) {
    let mut t = String::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            t.push_str(&format!(
                "v {x} {y} {}\n",
                0.1 * (3.0 * x).sin() * (2.0 * y).cos()
            ));
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
    std::fs::write(path, t).unwrap();
}

/// Sends `raw` and reads the answer until the server closes (or 60 s);
/// the status line's code (0 when nothing came back) and the whole answer.
fn exchange(port: u16, raw: &[u8]) -> (u16, String) {
    let mut c = TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let _ = c.write_all(raw);
    let mut out = Vec::new();
    let _ = c.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).to_string();
    let code = text
        .split(' ')
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (code, text)
}

impl Server {
    fn head(&self, method: &str, path: &str, extra: &str, length: usize) -> String {
        format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\nContent-Length: {length}\r\n{extra}\r\n",
            self.port
        )
    }
    fn auth(&self) -> String {
        format!("X-Fairline-Token: {}\r\n", self.token)
    }
    /// An authenticated GET; its status and how long it took.
    fn timed_get(&self, path: &str) -> (u16, Duration) {
        let t = Instant::now();
        let (code, _) = exchange(
            self.port,
            self.head("GET", path, &self.auth(), 0).as_bytes(),
        );
        (code, t.elapsed())
    }
    fn post(&self, path: &str, body: &str) -> (u16, String) {
        let mut raw = self
            .head("POST", path, &self.auth(), body.len())
            .into_bytes();
        raw.extend_from_slice(body.as_bytes());
        exchange(self.port, &raw)
    }
    /// Resident memory of the server (MB).
    fn rss_mb(&self) -> f64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id()))
            .unwrap_or_default();
        status
            .lines()
            .find(|l| l.starts_with("VmRSS:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|k| k.parse::<f64>().ok())
            .map_or(0.0, |kb| kb / 1024.0)
    }
    /// Polls an authenticated request every 100 ms while `busy` is set;
    /// returns the slowest answer, failures and the largest RSS seen.
    fn watch(&self, busy: &AtomicBool) -> (Duration, Vec<u16>, f64) {
        let (mut slowest, mut failed, mut rss) = (Duration::ZERO, Vec::new(), 0.0f64);
        while busy.load(Ordering::SeqCst) {
            let (code, took) = self.timed_get("/api/job");
            if code != 200 {
                failed.push(code);
            }
            slowest = slowest.max(took);
            rss = rss.max(self.rss_mb());
            std::thread::sleep(Duration::from_millis(100));
        }
        (slowest, failed, rss)
    }
}

fn ready(srv: &Server) {
    let t = Instant::now();
    while srv.timed_get("/api/session").0 != 200 {
        assert!(t.elapsed() < Duration::from_secs(30), "server not ready");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn token_is_checked_before_the_body_and_bodies_are_bounded() {
    let _one = exclusive();
    let dir = tmp("limits-body");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let srv = Arc::new(start(&mesh, &dir));
    ready(&srv);
    // a 60 MiB POST without the token is refused on its head alone: the
    // answer comes before any body byte is sent
    let (code, _) = exchange(
        srv.port,
        srv.head("POST", "/api/doc/0/run", "", 60 << 20).as_bytes(),
    );
    assert_eq!(code, 403);
    // with the token, bodies are bounded per endpoint
    let (code, text) = exchange(
        srv.port,
        srv.head("POST", "/api/doc/0/undo", &srv.auth(), 1 << 20)
            .as_bytes(),
    );
    assert_eq!(code, 413, "{text}");
    let (code, _) = exchange(
        srv.port,
        srv.head("GET", "/api/session", &srv.auth(), 100).as_bytes(),
    );
    assert_eq!(code, 413);
    let (code, _) = exchange(
        srv.port,
        srv.head("POST", "/api/doc/0/run", &srv.auth(), 60 << 20)
            .as_bytes(),
    );
    assert_eq!(code, 413);
    // a flood: 32 clients each sending 4 unauthenticated 60 MiB POSTs and
    // pushing up to 4 MiB of body each time
    let busy = Arc::new(AtomicBool::new(true));
    let flood: Vec<_> = (0..32)
        .map(|_| {
            let head = srv.head("POST", "/api/doc/0/run", "", 60 << 20);
            let port = srv.port;
            std::thread::spawn(move || {
                let chunk = vec![b'x'; 256 << 10];
                for _ in 0..4 {
                    let Ok(mut c) = TcpStream::connect(("127.0.0.1", port)) else {
                        continue;
                    };
                    let _ = c.set_write_timeout(Some(Duration::from_secs(2)));
                    let _ = c.write_all(head.as_bytes());
                    for _ in 0..16 {
                        if c.write_all(&chunk).is_err() {
                            break;
                        }
                    }
                }
            })
        })
        .collect();
    let watcher = {
        let (srv, busy) = (Arc::clone(&srv), Arc::clone(&busy));
        std::thread::spawn(move || srv.watch(&busy))
    };
    for f in flood {
        f.join().unwrap();
    }
    busy.store(false, Ordering::SeqCst);
    let (slowest, failed, rss) = watcher.join().unwrap();
    assert!(
        failed.is_empty(),
        "authenticated requests failed: {failed:?}"
    );
    assert!(
        slowest < Duration::from_secs(1),
        "slowest answer {slowest:?}"
    );
    assert!(rss < 200.0, "server RSS {rss:.0} MB");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn slow_and_idle_connections_do_not_starve_an_authenticated_client() {
    let _one = exclusive();
    let dir = tmp("limits-slow");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let srv = Arc::new(start(&mesh, &dir));
    ready(&srv);
    let busy = Arc::new(AtomicBool::new(true));
    let port = srv.port;
    // 100 idle connections, then 80 slowloris clients each trickling a
    // request head one byte every 200 ms for 7 s (reconnecting when dropped)
    let idle: Vec<TcpStream> = (0..100)
        .filter_map(|_| TcpStream::connect(("127.0.0.1", port)).ok())
        .collect();
    let dropped_after = Arc::new(std::sync::Mutex::new(Vec::new()));
    let slow: Vec<_> = (0..80)
        .map(|_| {
            let busy = Arc::clone(&busy);
            let dropped_after = Arc::clone(&dropped_after);
            std::thread::spawn(move || {
                let head = format!("GET /api/session HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n");
                let end = Instant::now() + Duration::from_secs(7);
                while Instant::now() < end && busy.load(Ordering::SeqCst) {
                    let Ok(mut c) = TcpStream::connect(("127.0.0.1", port)) else {
                        std::thread::sleep(Duration::from_millis(100));
                        continue;
                    };
                    let opened = Instant::now();
                    for b in head.bytes().cycle() {
                        if Instant::now() >= end || c.write_all(&[b]).is_err() {
                            break;
                        }
                        std::thread::sleep(Duration::from_millis(200));
                    }
                    if Instant::now() < end {
                        dropped_after.lock().unwrap().push(opened.elapsed());
                    }
                }
            })
        })
        .collect();
    let watcher = {
        let (srv, busy) = (Arc::clone(&srv), Arc::clone(&busy));
        std::thread::spawn(move || srv.watch(&busy))
    };
    for t in slow {
        t.join().unwrap();
    }
    busy.store(false, Ordering::SeqCst);
    let (slowest, failed, rss) = watcher.join().unwrap();
    drop(idle);
    assert!(
        failed.is_empty(),
        "authenticated requests failed: {failed:?}"
    );
    assert!(
        slowest < Duration::from_secs(1),
        "slowest answer {slowest:?}"
    );
    assert!(rss < 200.0, "server RSS {rss:.0} MB");
    // slow clients were dropped (a head must be complete 5 s after opening)
    let dropped = dropped_after.lock().unwrap();
    assert!(!dropped.is_empty(), "no slow client was dropped");
    assert!(
        dropped.iter().all(|d| *d < Duration::from_secs(6)),
        "a slow client was kept {:?}",
        dropped.iter().max()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ambiguous_framing_is_refused() {
    let _one = exclusive();
    let dir = tmp("limits-framing");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let srv = start(&mesh, &dir);
    ready(&srv);
    let (p, t) = (srv.port, srv.token.as_str());
    let smuggled = format!(
        "GET /api/session HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\n\r\n"
    );
    let cases = [
        // two Content-Length headers (the first would win: the rest of the
        // body would be read as a second request)
        format!(
            "POST /api/doc/0/undo HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nContent-Length: 0\r\nContent-Length: {}\r\n\r\n{smuggled}",
            smuggled.len()
        ),
        format!(
            "POST /api/doc/0/undo HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nContent-Length: 2\r\nContent-Length: 2\r\n\r\n{{}}"
        ),
        // Content-Length with Transfer-Encoding
        format!(
            "POST /api/doc/0/undo HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nContent-Length: 5\r\nTransfer-Encoding: chunked\r\n\r\n0\r\n\r\n{smuggled}"
        ),
        format!(
            "POST /api/doc/0/undo HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{{}}\r\n0\r\n\r\n"
        ),
        // a signed or padded length
        format!(
            "POST /api/doc/0/undo HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nContent-Length: +2\r\n\r\n{{}}"
        ),
        // two Host or token headers
        format!(
            "GET /api/session HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nHost: evil.example\r\nX-Fairline-Token: {t}\r\n\r\n"
        ),
        format!(
            "GET /api/session HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-Fairline-Token: {t}\r\nX-Fairline-Token: x\r\n\r\n"
        ),
    ];
    for raw in &cases {
        let (code, text) = exchange(p, raw.as_bytes());
        assert_eq!(code, 400, "{raw:?} → {text}");
        assert_eq!(
            text.matches("HTTP/1.1 ").count(),
            1,
            "one answer only: {text}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_query_token_is_for_get_only() {
    let _one = exclusive();
    let dir = tmp("limits-query");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let srv = start(&mesh, &dir);
    ready(&srv);
    let path = format!("/api/doc/0/undo?token={}", srv.token);
    let (code, _) = exchange(
        srv.port,
        srv.head("POST", &path, "", 2)
            .replace("\r\n\r\n", "\r\n\r\n{}")
            .as_bytes(),
    );
    assert_eq!(code, 403);
    // with the header: admitted (nothing to undo yet: 409)
    assert_eq!(srv.post("/api/doc/0/undo", "{}").0, 409);
    let (code, _) = exchange(
        srv.port,
        srv.head("GET", &format!("/api/session?token={}", srv.token), "", 0)
            .as_bytes(),
    );
    assert_eq!(code, 200);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn huge_light_requests_are_refused_and_long_ones_leave_the_server_answering() {
    let _one = exclusive();
    let dir = tmp("limits-lines");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 70);
    let srv = Arc::new(start(&mesh, &dir));
    ready(&srv);
    let radii = |n: usize| -> String {
        (0..n)
            .map(|i| format!("{}", 0.05 + 0.5 * i as f64 / n as f64))
            .collect::<Vec<_>>()
            .join(",")
    };
    let body = |n: usize| {
        format!(
            r#"{{"circular":{{"center":[0.5,0.5,2],"axis":[1,0,0],"radii":[{}]}},"band":0.01}}"#,
            radii(n)
        )
    };
    let t = Instant::now();
    let (code, text) = srv.post("/api/doc/0/lines", &body(20_000));
    assert_eq!(code, 400, "{text}");
    assert!(text.contains("at most 256"), "{text}");
    assert!(t.elapsed() < Duration::from_secs(2));
    // the largest request allowed runs while other calls are answered
    let busy = Arc::new(AtomicBool::new(true));
    let watcher = {
        let (srv, busy) = (Arc::clone(&srv), Arc::clone(&busy));
        std::thread::spawn(move || srv.watch(&busy))
    };
    let started = Instant::now();
    let (code, text) = srv.post("/api/doc/0/lines", &body(256));
    let took = started.elapsed();
    busy.store(false, Ordering::SeqCst);
    let (slowest, failed, rss) = watcher.join().unwrap();
    assert_eq!(code, 200, "{}", &text[..text.len().min(300)]);
    eprintln!(
        "256 circular lights with bands: {took:?}, slowest other answer {slowest:?}, RSS {rss:.0} MB"
    );
    assert!(failed.is_empty(), "{failed:?}");
    assert!(
        slowest < Duration::from_secs(1),
        "slowest answer {slowest:?} while lines took {took:?}"
    );
    assert!(rss < 200.0, "server RSS {rss:.0} MB");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The opener gets the path of a 0600 redirect page, never the token.
#[cfg(unix)]
#[test]
fn the_browser_is_opened_without_the_token_on_a_command_line() {
    let _one = exclusive();
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp("limits-open");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let fake = dir.join("bin");
    std::fs::create_dir_all(&fake).unwrap();
    let record = dir.join("record");
    let script = format!(
        "#!/bin/sh\nprintf '%s\\n' \"$@\" > {r}.args\nstat -c %a \"$1\" > {r}.mode\ncat \"$1\" > {r}.page\n",
        r = s(&record)
    );
    for name in ["xdg-open", "open"] {
        let p = fake.join(name);
        std::fs::write(&p, &script).unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let path = format!("{}:{}", s(&fake), std::env::var("PATH").unwrap_or_default());
    let mut child = bin()
        .args(["view", s(&mesh), "--save-dir", s(&dir)])
        .env("PATH", path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let token = line.trim().split("token=").nth(1).unwrap().to_string();
    let page = dir.join("record.page");
    let t = Instant::now();
    while !std::fs::read_to_string(&page).is_ok_and(|p| p.contains("</a>")) {
        assert!(t.elapsed() < Duration::from_secs(20), "opener not run");
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    let args = std::fs::read_to_string(dir.join("record.args")).unwrap();
    assert!(!args.contains(&token), "token on the command line: {args}");
    assert_eq!(
        std::fs::read_to_string(dir.join("record.mode"))
            .unwrap()
            .trim(),
        "600"
    );
    assert!(
        std::fs::read_to_string(&page)
            .unwrap()
            .contains(line.trim())
    );
    let _ = std::fs::remove_file(args.trim());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Saves stay in the save folder: an existing name is replaced only when
/// asked, a symbolic link is never written through.
#[cfg(unix)]
#[test]
fn saves_are_confined_to_the_save_folder() {
    let _one = exclusive();
    let dir = tmp("limits-save");
    let mesh = dir.join("panel.obj");
    panel(&mesh, 11);
    let saves = dir.join("saves");
    std::fs::create_dir_all(&saves).unwrap();
    let outside = dir.join("outside.txt");
    std::fs::write(&outside, "keep me").unwrap();
    std::os::unix::fs::symlink(&outside, saves.join("link.obj")).unwrap();
    let srv = start(&mesh, &saves);
    ready(&srv);
    assert_eq!(srv.post("/api/doc/0/save", r#"{"name":"a.obj"}"#).0, 200);
    std::fs::write(saves.join("a.obj"), "mine").unwrap();
    let (code, text) = srv.post("/api/doc/0/save", r#"{"name":"a.obj"}"#);
    assert_eq!(code, 409, "{text}");
    assert_eq!(
        std::fs::read_to_string(saves.join("a.obj")).unwrap(),
        "mine"
    );
    let (code, _) = srv.post("/api/doc/0/save", r#"{"name":"a.obj","overwrite":true}"#);
    assert_eq!(code, 200);
    assert_ne!(
        std::fs::read_to_string(saves.join("a.obj")).unwrap(),
        "mine"
    );
    for body in [
        r#"{"name":"link.obj"}"#,
        r#"{"name":"link.obj","overwrite":true}"#,
    ] {
        let (code, text) = srv.post("/api/doc/0/save", body);
        assert_eq!(code, 400, "{text}");
        assert!(text.contains("symbolic link"), "{text}");
    }
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep me");
    assert!(
        std::fs::symlink_metadata(saves.join("link.obj"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
