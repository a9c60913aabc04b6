//! Routing and the handlers of the JSON API (documented in `view`).

use super::auth::{Guard, query_param};
use super::doc::Doc;
use super::frame::vec3_bytes;
use super::http::{HttpRequest, HttpResponse, Service};
use documents::{download, job_json, move_cursor, save, scalar, session};
use fairline::highlight::{HighlightModel, HighlightOptions, LightArray};
use fairline::{SurfaceMesh, Vec3};
use fairline_commands::Lights;
use jobs::start_job;
use lines::{outlines, surface_lines};
use regions::{detect, region, region_file};
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

mod documents;
mod jobs;
mod lines;
mod regions;

pub(super) use documents::{safe_file_name, step_bytes};

/// State shared by the worker threads.
pub struct Shared {
    pub state: Mutex<State>,
    pub guard: Guard,
    /// True once the documents are read: the server answers the page's
    /// files at once (so the browser loads the page while a large mesh is
    /// read) and holds API calls until then.
    loaded: Mutex<bool>,
    loaded_signal: Condvar,
}

impl Shared {
    /// The shared state of a server whose documents are still being read.
    pub fn new(save_dir: PathBuf, guard: Guard) -> Shared {
        Shared {
            state: Mutex::new(State::new(Vec::new(), save_dir)),
            guard,
            loaded: Mutex::new(false),
            loaded_signal: Condvar::new(),
        }
    }

    /// Hands over the documents read and lets the waiting API calls go.
    pub fn set_docs(&self, docs: Vec<Doc>, restore: Option<Value>) {
        {
            let mut st = lock(self);
            st.docs = docs;
            st.restore = restore;
        }
        *self.loaded.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.loaded_signal.notify_all();
    }

    /// Waits until the documents are read.
    fn wait_loaded(&self) {
        let mut loaded = self.loaded.lock().unwrap_or_else(|e| e.into_inner());
        while !*loaded {
            loaded = self
                .loaded_signal
                .wait(loaded)
                .unwrap_or_else(|e| e.into_inner());
        }
    }
}

/// Documents, the save folder and the current job.
pub struct State {
    pub(super) docs: Vec<Doc>,
    save_dir: PathBuf,
    job: Option<Job>,
    next_job: u64,
    model_cache: Option<ModelCache>,
    /// The page's view of the session file opened (`--session`).
    pub(super) restore: Option<Value>,
}

/// The last linear-light highlight model built (Yong et al. Algorithm 1):
/// the page asks for exact lines again with the same lights when only the
/// band changes, and for detection under the lights it just drew; at 450k
/// vertices the model is most of such a request. Keyed by the document,
/// its geometry (the step's positions, held so the pointer cannot be
/// reused) and the lights; the options are always the defaults.
struct ModelCache {
    doc: usize,
    positions: Arc<Vec<Vec3>>,
    light: LightArray,
    model: Arc<HighlightModel>,
}

/// The highlight model of document `doc` whose geometry is `mesh` (the
/// positions of one of its steps, `positions`) under `light` with default
/// options: the cached one when the key matches, else built (without the
/// workbench's lock held: other requests, cancel included, are answered
/// meanwhile) and cached. Returns the model and whether it came from the
/// cache.
fn cached_model(
    shared: &Shared,
    doc: usize,
    positions: &Arc<Vec<Vec3>>,
    mesh: &SurfaceMesh,
    light: LightArray,
) -> Result<(Arc<HighlightModel>, bool), fairline::highlight::HighlightError> {
    if let Some(c) = &lock(shared).model_cache
        && c.doc == doc
        && Arc::ptr_eq(&c.positions, positions)
        && c.light == light
    {
        return Ok((Arc::clone(&c.model), true));
    }
    let model = Arc::new(HighlightModel::new(
        mesh,
        light,
        HighlightOptions::default(),
    )?);
    lock(shared).model_cache = Some(ModelCache {
        doc,
        positions: Arc::clone(positions),
        light,
        model: Arc::clone(&model),
    });
    Ok((model, false))
}

/// A long computation running on its own thread.
struct Job {
    id: u64,
    doc: usize,
    label: String,
    /// running | cancelling (the flag is raised, the algorithm has not
    /// stopped yet) | done | failed | cancelled
    state: &'static str,
    progress: f64,
    /// The stage the library last reported ("iterations", "lights" …).
    stage: &'static str,
    message: String,
    report: Value,
    command: String,
    cancel: Arc<AtomicBool>,
    started: Instant,
}

impl State {
    pub fn new(docs: Vec<Doc>, save_dir: PathBuf) -> Self {
        State {
            docs,
            save_dir,
            job: None,
            next_job: 1,
            model_cache: None,
            restore: None,
        }
    }

    /// The folder saves go to.
    pub(super) fn save_dir(&self) -> &std::path::Path {
        &self.save_dir
    }
}

/// An answer: status, content type, body, extra headers.
pub(super) struct Answer {
    status: u16,
    content_type: &'static str,
    body: Vec<u8>,
    headers: Vec<(String, String)>,
}

pub(super) fn json_answer(v: &Value) -> Answer {
    Answer {
        status: 200,
        content_type: "application/json",
        body: v.to_string().into_bytes(),
        headers: Vec::new(),
    }
}

pub(super) fn binary(body: Vec<u8>) -> Answer {
    Answer {
        status: 200,
        content_type: "application/octet-stream",
        body,
        headers: Vec::new(),
    }
}

pub(super) fn error(status: u16, msg: impl Into<String>) -> Answer {
    Answer {
        status,
        content_type: "application/json",
        body: json!({"error": msg.into()}).to_string().into_bytes(),
        headers: Vec::new(),
    }
}

/// A bad request (400) from any error.
pub(super) fn bad(e: impl std::fmt::Display) -> Answer {
    error(400, e.to_string())
}

/// The workbench as the HTTP server sees it.
pub struct Api(pub Arc<Shared>);

impl Service for Api {
    fn admit(&self, req: &HttpRequest) -> Result<usize, HttpResponse> {
        match self.0.guard.check(req) {
            Err(why) => Err(respond(error(403, why))),
            Ok(()) => Ok(body_limit(req)),
        }
    }
    fn handle(&self, req: &HttpRequest) -> HttpResponse {
        handle(&self.0, req)
    }
}

/// The largest request body of an endpoint (bytes): none for GET, face
/// lists (4 to 10 bytes of JSON per triangle) for region and run calls,
/// lights for lines and detection, a few fields for the rest.
fn body_limit(req: &HttpRequest) -> usize {
    if req.method != "POST" {
        return 0;
    }
    let path = req.url.split('?').next().unwrap_or("");
    match path.rsplit('/').next().unwrap_or("") {
        "region" | "region-file" | "run" | "deviation" | "session-file" => 32 << 20,
        "lines" | "detect" | "surface-lines" => 256 << 10,
        _ => 4 << 10,
    }
}

/// Answers one request.
pub fn handle(shared: &Arc<Shared>, req: &HttpRequest) -> HttpResponse {
    let answer = match shared.guard.check(req) {
        Err(why) => error(403, why),
        Ok(()) => route(shared, req, &req.body),
    };
    respond(answer)
}

/// The HTTP answer of `answer`, with the headers every answer has.
fn respond(answer: Answer) -> HttpResponse {
    let mut headers = vec![
        ("Content-Type".to_string(), answer.content_type.to_string()),
        ("Cache-Control".to_string(), "no-store".to_string()),
        ("X-Content-Type-Options".to_string(), "nosniff".to_string()),
        (
            "Content-Security-Policy".to_string(),
            "default-src 'self'; img-src 'self' data: blob:; style-src 'self'; connect-src 'self'; frame-ancestors 'none'".to_string(),
        ),
    ];
    headers.extend(answer.headers);
    HttpResponse {
        status: answer.status,
        headers,
        body: answer.body,
    }
}

fn route(shared: &Arc<Shared>, req: &HttpRequest, body: &[u8]) -> Answer {
    let url = req.url.as_str();
    let path = url.split('?').next().unwrap_or("");
    let get = req.method == "GET";
    let post = req.method == "POST";
    if get && !path.starts_with("/api/") {
        return match super::assets::asset(path) {
            Some((ctype, bytes)) => {
                let mut a = Answer {
                    status: 200,
                    content_type: ctype,
                    body: bytes.to_vec(),
                    headers: Vec::new(),
                };
                if path == "/" || path == "/index.html" {
                    a.headers
                        .push(("Set-Cookie".into(), shared.guard.set_cookie()));
                }
                a
            }
            None => error(404, format!("no such page: {path}")),
        };
    }
    shared.wait_loaded();
    let parts: Vec<&str> = path.trim_start_matches("/api/").split('/').collect();
    match (get, post, parts.as_slice()) {
        (true, _, ["session"]) => json_answer(&session(&lock(shared))),
        (true, _, ["job"]) => json_answer(&job_json(&lock(shared))),
        (_, true, ["session-file"]) => super::session::save(shared, body),
        (_, true, ["job", "cancel"]) => {
            let mut st = lock(shared);
            if let Some(j) = st.job.as_mut()
                && j.state == "running"
            {
                // the library stops at its next checkpoint (Control); the
                // job turns `cancelled` when its thread has ended
                j.cancel.store(true, Ordering::SeqCst);
                j.state = "cancelling";
                j.message = "stopping; the result will be discarded".into();
            }
            json_answer(&job_json(&st))
        }
        (_, _, ["doc", k, rest @ ..]) => {
            let Ok(k) = k.parse::<usize>() else {
                return error(404, "bad document index");
            };
            if k >= lock(shared).docs.len() {
                return error(404, format!("no document {k}"));
            }
            let step = query_param(url, "step").and_then(|s| s.parse::<usize>().ok());
            match (get, post, rest) {
                (true, _, ["positions"]) => {
                    let st = lock(shared);
                    let d = &st.docs[k];
                    binary(vec3_bytes(&d.step(step).positions, d.center))
                }
                (true, _, ["normals"]) => {
                    let st = lock(shared);
                    binary(st.docs[k].normal_bytes(step).to_vec())
                }
                (true, _, ["indices"]) => binary(lock(shared).docs[k].index_bytes.clone()),
                (true, _, ["patches"]) => {
                    let st = lock(shared);
                    binary(
                        st.docs[k]
                            .patch_of_triangle
                            .iter()
                            .flat_map(|p| p.to_le_bytes())
                            .collect(),
                    )
                }
                (true, _, ["scalar", name]) => scalar(shared, k, name, step),
                (true, _, ["download"]) => download(shared, k, url),
                (_, true, ["lines"]) => lines::lines(shared, k, body),
                (_, true, ["lines-curves"]) => super::tools::lines_curves(shared, k, body),
                (true, _, ["outlines"]) => outlines(shared, k, step),
                (_, true, ["surface-lines"]) => surface_lines(shared, k, body),
                (_, true, ["detect"]) => detect(shared, k, body),
                (_, true, ["region"]) => region(shared, k, body),
                (_, true, ["region-file"]) => region_file(shared, k, body),
                (_, true, ["run"]) => start_job(shared, k, body),
                (_, true, ["undo"]) => move_cursor(shared, k, -1),
                (_, true, ["redo"]) => move_cursor(shared, k, 1),
                (_, true, ["save"]) => save(shared, k, body),
                (_, true, ["deviation"]) => super::tools::deviation(shared, k, body),
                (_, true, ["probe"]) => super::tools::probe(shared, k, body),
                (_, true, ["section"]) => super::shape::section(shared, k, body),
                (_, true, ["draft"]) => super::shape::draft(shared, k, body),
                (_, true, ["continuity"]) => super::surface_tools::continuity(shared, k, body),
                (true, _, ["control-net"]) => super::surface_tools::control_net(shared, k),
                (_, true, ["iso-combs"]) => super::surface_tools::iso_combs(shared, k, body),
                _ => error(404, format!("no such API call: {path}")),
            }
        }
        _ => error(404, format!("no such API call: {path}")),
    }
}

pub(super) fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, State> {
    shared
        .state
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub(super) fn parse<T: for<'de> Deserialize<'de>>(body: &[u8]) -> Result<T, Answer> {
    serde_json::from_slice(body).map_err(|e| bad(format!("request: {e}")))
}

pub(super) fn vec_arg(v: Vec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

/// The light options of a command for a linear light array.
pub(super) fn light_args(l: &LightArray) -> String {
    Lights::exactly(l)
        .args("lights.json")
        .trim_start()
        .to_string()
}
