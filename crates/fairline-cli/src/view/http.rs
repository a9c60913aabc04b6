//! A minimal HTTP/1.1 server on std for the local workbench: one thread per
//! connection, requests parsed by `httparse`, bodies by Content-Length,
//! answers with Content-Length. (tiny_http was tried first: its fixed pool
//! of four connection threads stalled the page for minutes while Chromium
//! kept idle keep-alive connections open.)
//!
//! # Limits (no local process without the token can starve or flood it)
//! - A request's head is checked by [`Service::admit`] (token, host,
//!   origin) **before any body byte is read**; a refused request is answered
//!   and its connection closed, its body never read. The admitted body size
//!   is per endpoint (`admit` returns it); a larger Content-Length is 413.
//! - Framing is unambiguous or refused (400): one Content-Length of plain
//!   digits, no Transfer-Encoding, no duplicated Host, Origin or token
//!   header.
//! - Deadlines: a connection that has not sent a complete request head
//!   [`HEAD_DEADLINE`] after it opened (or after the first byte of a later
//!   request) is closed; a body must arrive within [`BODY_DEADLINE`]; an
//!   idle keep-alive connection is closed after [`IDLE`]; a client that does
//!   not read its answer for [`WRITE_DEADLINE`] is dropped.
//! - The pool: at most [`MAX_CONNECTIONS`] connections, of which at most
//!   [`MAX_UNPROVEN`] have not yet made an admitted request. Every client
//!   of a loopback server has the address 127.0.0.1, so the per-client
//!   cap is per proof of the token: connections without it share their own
//!   small pool, in which a newcomer evicts the oldest that has been open
//!   for [`HEAD_GRACE`] (younger ones keep their place, and the newcomer
//!   is admitted beside them while the whole pool has room); when the whole pool
//!   is full, a newcomer evicts the oldest connection that is waiting for a
//!   request (never one whose request is being served). A client with the
//!   token therefore always gets a connection, and its request head (one
//!   packet) is admitted at once.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Largest header block read (bytes).
const MAX_HEAD: usize = 32 << 10;
/// Most connections served at once.
pub const MAX_CONNECTIONS: usize = 64;
/// Most connections that have not yet made an admitted request.
pub const MAX_UNPROVEN: usize = 16;
/// Time an unproven connection keeps its place among the
/// [`MAX_UNPROVEN`] against newcomers (a request head is one packet: a
/// client that has not sent it by then is slow or idle).
pub const HEAD_GRACE: Duration = Duration::from_secs(1);
/// Time from a connection's opening (or a later request's first byte) to
/// the end of the request head.
pub const HEAD_DEADLINE: Duration = Duration::from_secs(5);
/// Time for a request body to arrive once its head is admitted.
pub const BODY_DEADLINE: Duration = Duration::from_secs(30);
/// An idle keep-alive connection is closed after this long.
pub const IDLE: Duration = Duration::from_secs(30);
/// Time a client may take to read an answer.
pub const WRITE_DEADLINE: Duration = Duration::from_secs(30);

/// A request: method, URL (path and query), headers and body.
pub struct HttpRequest {
    pub method: String,
    pub url: String,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl HttpRequest {
    /// The value of header `name` (case-insensitive; the first one).
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }

    fn header_count(&self, name: &str) -> usize {
        self.headers
            .iter()
            .filter(|(k, _)| k.eq_ignore_ascii_case(name))
            .count()
    }
}

/// An answer: status, headers (without Content-Length and Connection), body.
pub struct HttpResponse {
    pub status: u16,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

/// What the server serves.
pub trait Service: Send + Sync + 'static {
    /// Checks a request whose head is read and whose body is not (`body`
    /// is empty): the largest body accepted for it, or the refusal answer.
    fn admit(&self, req: &HttpRequest) -> Result<usize, HttpResponse>;
    /// Answers an admitted request with its body read.
    fn handle(&self, req: &HttpRequest) -> HttpResponse;
}

/// One open connection as the pool sees it.
struct Slot {
    id: u64,
    /// A handle to shut the socket down when the connection is evicted.
    stream: TcpStream,
    /// Has made an admitted request.
    proven: bool,
    /// Waiting for (the head of) a request, so it may be evicted.
    waiting: bool,
    /// When it opened or last finished a request.
    since: Instant,
}

/// The open connections.
#[derive(Default)]
struct Pool {
    slots: Mutex<(u64, Vec<Slot>)>,
}

impl Pool {
    fn lock(&self) -> std::sync::MutexGuard<'_, (u64, Vec<Slot>)> {
        self.slots.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Makes room for and registers a new connection; `None` when every
    /// connection is busy serving a request.
    fn enter(&self, stream: &TcpStream) -> Option<u64> {
        let handle = stream.try_clone().ok()?;
        let mut g = self.lock();
        let unproven = g.1.iter().filter(|s| !s.proven).count();
        if unproven >= MAX_UNPROVEN {
            // only one that had time to send its head: a client with the
            // token is not evicted by a burst of newcomers before its
            // connection's thread has read the head it sent at once
            let now = Instant::now();
            evict_oldest(&mut g.1, |s| {
                !s.proven && s.waiting && now.duration_since(s.since) >= HEAD_GRACE
            });
        }
        if g.1.len() >= MAX_CONNECTIONS && !evict_oldest(&mut g.1, |s| s.waiting) {
            return None;
        }
        g.0 += 1;
        let id = g.0;
        g.1.push(Slot {
            id,
            stream: handle,
            proven: false,
            waiting: true,
            since: Instant::now(),
        });
        Some(id)
    }

    fn set(&self, id: u64, proven: bool, waiting: bool) {
        let mut g = self.lock();
        if let Some(s) = g.1.iter_mut().find(|s| s.id == id) {
            s.proven |= proven;
            s.waiting = waiting;
            if waiting {
                s.since = Instant::now();
            }
        }
    }

    fn leave(&self, id: u64) {
        self.lock().1.retain(|s| s.id != id);
    }
}

/// Shuts down and forgets the oldest slot that `may`; whether one was.
fn evict_oldest(slots: &mut Vec<Slot>, may: impl Fn(&Slot) -> bool) -> bool {
    let Some(i) = slots
        .iter()
        .enumerate()
        .filter(|(_, s)| may(s))
        .min_by_key(|(_, s)| s.since)
        .map(|(i, _)| i)
    else {
        return false;
    };
    let s = slots.swap_remove(i);
    let _ = s.stream.shutdown(Shutdown::Both);
    true
}

/// Serves connections of `listener` until the process ends.
pub fn serve(listener: TcpListener, service: Arc<dyn Service>) {
    let pool = Arc::new(Pool::default());
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        let Some(id) = pool.enter(&stream) else {
            let mut stream = stream;
            let _ = write_response(&mut stream, &error(503, "server busy"), true);
            continue; // closed
        };
        let service = Arc::clone(&service);
        let in_pool = Arc::clone(&pool);
        let spawned = std::thread::Builder::new()
            .name("http".into())
            .spawn(move || {
                connection(stream, id, &in_pool, service.as_ref());
                in_pool.leave(id);
            });
        if spawned.is_err() {
            // no thread: the stream went with the closure and is closed
            pool.leave(id);
        }
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        408 => "Request Timeout",
        409 => "Conflict",
        413 => "Payload Too Large",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        _ => "Error",
    }
}

fn write_response(stream: &mut TcpStream, r: &HttpResponse, close: bool) -> std::io::Result<()> {
    let _ = stream.set_write_timeout(Some(WRITE_DEADLINE));
    let mut head = format!("HTTP/1.1 {} {}\r\n", r.status, reason(r.status));
    for (k, v) in &r.headers {
        if k.contains(['\r', '\n']) || v.contains(['\r', '\n']) {
            continue;
        }
        head.push_str(&format!("{k}: {v}\r\n"));
    }
    head.push_str(&format!(
        "Content-Length: {}\r\nConnection: {}\r\n\r\n",
        r.body.len(),
        if close { "close" } else { "keep-alive" }
    ));
    stream.write_all(head.as_bytes())?;
    stream.write_all(&r.body)?;
    stream.flush()
}

/// A plain-text answer.
pub fn error(status: u16, msg: &str) -> HttpResponse {
    HttpResponse {
        status,
        headers: vec![("Content-Type".into(), "text/plain; charset=utf-8".into())],
        body: msg.as_bytes().to_vec(),
    }
}

/// Answers `r` and closes the connection without reading what the client
/// still sends (a short, bounded drain lets the answer reach the client
/// before the close resets the connection).
fn refuse(stream: &mut TcpStream, r: &HttpResponse) {
    if write_response(stream, r, true).is_err() {
        return;
    }
    let _ = stream.shutdown(Shutdown::Write);
    let until = Instant::now() + Duration::from_millis(200);
    let mut sink = [0u8; 8 << 10];
    let mut drained = 0usize;
    while drained < (1 << 20) {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            break;
        }
        match stream.read(&mut sink) {
            Ok(0) | Err(_) => break,
            Ok(n) => drained += n,
        }
    }
}

/// Reads into `buf` until it holds `want` bytes or `deadline` passes;
/// whether it got them.
fn read_until(stream: &mut TcpStream, buf: &mut Vec<u8>, want: usize, deadline: Instant) -> bool {
    while buf.len() < want {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return false;
        }
        let mut chunk = [0u8; 16 << 10];
        let n = (want - buf.len()).min(chunk.len());
        match stream.read(&mut chunk[..n]) {
            Ok(0) | Err(_) => return false,
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
        }
    }
    true
}

/// Reads a request head (through the blank line) into `buf`; the end of
/// the head in `buf`, or `None` when the client closed, timed out (both
/// silently) or sent too much (answered).
fn read_head(
    stream: &mut TcpStream,
    buf: &mut Vec<u8>,
    proven: bool,
    opened: Instant,
) -> Option<usize> {
    // a new connection has HEAD_DEADLINE from its opening; a kept-alive
    // one may idle for IDLE, then has HEAD_DEADLINE from the first byte
    let mut deadline = if proven && buf.is_empty() {
        Instant::now() + IDLE
    } else {
        opened + HEAD_DEADLINE
    };
    let mut started = !buf.is_empty();
    loop {
        if let Some(i) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            return Some(i + 4);
        }
        if buf.len() > MAX_HEAD {
            refuse(stream, &error(431, "request header too large"));
            return None;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return None;
        }
        let mut chunk = [0u8; 4 << 10];
        match stream.read(&mut chunk) {
            Ok(0) | Err(_) => return None,
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
        }
        if !started {
            started = true;
            deadline = Instant::now() + HEAD_DEADLINE;
        }
    }
}

/// The body length a head declares, or why its framing is refused.
fn body_length(req: &HttpRequest) -> Result<usize, &'static str> {
    if req.header_count("Transfer-Encoding") > 0 {
        return Err("Transfer-Encoding is not accepted (send a Content-Length)");
    }
    for name in ["Content-Length", "Host", "Origin", "X-Fairline-Token"] {
        if req.header_count(name) > 1 {
            return Err("a framing or security header is repeated");
        }
    }
    match req.header("Content-Length").map(str::trim) {
        None => Ok(0),
        Some(v) if !v.is_empty() && v.len() <= 12 && v.bytes().all(|b| b.is_ascii_digit()) => {
            v.parse().map_err(|_| "bad Content-Length")
        }
        Some(_) => Err("bad Content-Length"),
    }
}

/// Serves the requests of one connection in turn.
fn connection(mut stream: TcpStream, id: u64, pool: &Pool, service: &dyn Service) {
    let _ = stream.set_nodelay(true);
    let mut buf: Vec<u8> = Vec::new();
    let mut proven = false;
    let mut opened = Instant::now();
    loop {
        let Some(head_end) = read_head(&mut stream, &mut buf, proven, opened) else {
            return;
        };
        pool.set(id, false, false);
        let mut headers = [httparse::EMPTY_HEADER; 64];
        let mut parsed = httparse::Request::new(&mut headers);
        let ok = matches!(
            parsed.parse(&buf[..head_end]),
            Ok(httparse::Status::Complete(_))
        );
        let (Some(method), Some(path), true) = (parsed.method, parsed.path, ok) else {
            refuse(&mut stream, &error(400, "malformed request"));
            return;
        };
        let version = parsed.version.unwrap_or(1);
        let mut req = HttpRequest {
            method: method.to_string(),
            url: path.to_string(),
            headers: parsed
                .headers
                .iter()
                .map(|h| {
                    (
                        h.name.to_string(),
                        String::from_utf8_lossy(h.value).into_owned(),
                    )
                })
                .collect(),
            body: Vec::new(),
        };
        let length = match body_length(&req) {
            Ok(n) => n,
            Err(why) => {
                refuse(&mut stream, &error(400, why));
                return;
            }
        };
        // the token and the endpoint's body limit, before the body
        let limit = match service.admit(&req) {
            Ok(limit) => limit,
            Err(answer) => {
                refuse(&mut stream, &answer);
                return;
            }
        };
        if length > limit {
            refuse(
                &mut stream,
                &error(
                    413,
                    &format!("request body too large ({length} bytes; at most {limit} here)"),
                ),
            );
            return;
        }
        proven = true;
        pool.set(id, true, false);
        buf.drain(..head_end);
        if !read_until(
            &mut stream,
            &mut buf,
            length,
            Instant::now() + BODY_DEADLINE,
        ) {
            return;
        }
        req.body = buf.drain(..length).collect();
        let close = version == 0
            || req
                .header("Connection")
                .is_some_and(|c| c.to_ascii_lowercase().contains("close"));
        let resp = service.handle(&req);
        if write_response(&mut stream, &resp, close).is_err() || close {
            return;
        }
        pool.set(id, true, true);
        opened = Instant::now();
    }
}
