//! A minimal HTTP/1.1 server on std: one thread per connection (so an idle
//! keep-alive connection of the browser never starves another), requests
//! parsed by `httparse`, bodies by Content-Length, answers with
//! Content-Length. (tiny_http was tried first: its fixed pool of four
//! connection threads stalled the page for minutes while Chromium kept idle
//! keep-alive connections open.)

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// Largest header block read (bytes).
const MAX_HEAD: usize = 64 << 10;
/// Largest request body read (bytes).
pub const MAX_BODY: usize = 64 << 20;
/// Most connections served at once; more are closed at once.
const MAX_CONNECTIONS: usize = 64;
/// An idle keep-alive connection is closed after this long.
const IDLE: Duration = Duration::from_secs(60);

/// A request: method, URL (path and query), headers and body.
pub struct HttpRequest {
    pub method: String,
    pub url: String,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl HttpRequest {
    /// The value of header `name` (case-insensitive).
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// An answer: status, headers (without Content-Length and Connection), body.
pub struct HttpResponse {
    pub status: u16,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

/// Handles requests.
pub type Handler = Arc<dyn Fn(&HttpRequest) -> HttpResponse + Send + Sync>;

/// Serves connections of `listener` until the process ends.
pub fn serve(listener: TcpListener, handler: Handler) {
    let open = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        if open.load(Ordering::SeqCst) >= MAX_CONNECTIONS {
            continue; // dropped: closed
        }
        open.fetch_add(1, Ordering::SeqCst);
        let handler = Arc::clone(&handler);
        let open = Arc::clone(&open);
        std::thread::spawn(move || {
            connection(stream, &handler);
            open.fetch_sub(1, Ordering::SeqCst);
        });
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        409 => "Conflict",
        413 => "Payload Too Large",
        _ => "Error",
    }
}

fn write_response(stream: &mut TcpStream, r: &HttpResponse, close: bool) -> std::io::Result<()> {
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

fn error(status: u16, msg: &str) -> HttpResponse {
    HttpResponse {
        status,
        headers: vec![("Content-Type".into(), "text/plain; charset=utf-8".into())],
        body: msg.as_bytes().to_vec(),
    }
}

/// Serves the requests of one connection in turn.
fn connection(mut stream: TcpStream, handler: &Handler) {
    let _ = stream.set_read_timeout(Some(IDLE));
    let _ = stream.set_nodelay(true);
    let mut buf: Vec<u8> = Vec::new();
    loop {
        // read until the end of the header block
        let head_end = loop {
            if let Some(i) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
                break i + 4;
            }
            if buf.len() > MAX_HEAD {
                let _ = write_response(&mut stream, &error(400, "header too large"), true);
                return;
            }
            let mut chunk = [0u8; 16 << 10];
            match stream.read(&mut chunk) {
                Ok(0) | Err(_) => return,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
        };
        let mut headers = [httparse::EMPTY_HEADER; 64];
        let mut parsed = httparse::Request::new(&mut headers);
        let ok = matches!(
            parsed.parse(&buf[..head_end]),
            Ok(httparse::Status::Complete(_))
        );
        let (Some(method), Some(path), true) = (parsed.method, parsed.path, ok) else {
            let _ = write_response(&mut stream, &error(400, "malformed request"), true);
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
        if req.header("Transfer-Encoding").is_some() {
            let _ = write_response(
                &mut stream,
                &error(400, "chunked bodies are not accepted"),
                true,
            );
            return;
        }
        let length = match req
            .header("Content-Length")
            .map(|v| v.trim().parse::<usize>())
        {
            None => 0,
            Some(Ok(n)) if n <= MAX_BODY => n,
            Some(Ok(_)) => {
                let _ = write_response(&mut stream, &error(413, "request body too large"), true);
                return;
            }
            Some(Err(_)) => {
                let _ = write_response(&mut stream, &error(400, "bad Content-Length"), true);
                return;
            }
        };
        buf.drain(..head_end);
        while buf.len() < length {
            let mut chunk = vec![0u8; (length - buf.len()).min(1 << 20)];
            match stream.read(&mut chunk) {
                Ok(0) | Err(_) => return,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
        }
        req.body = buf.drain(..length).collect();
        let close = version == 0
            || req
                .header("Connection")
                .is_some_and(|c| c.to_ascii_lowercase().contains("close"));
        let resp = handler(&req);
        if write_response(&mut stream, &resp, close).is_err() || close {
            return;
        }
    }
}
