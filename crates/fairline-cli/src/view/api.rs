//! Routing and the handlers of the JSON API (documented in `view`).

use super::auth::{Guard, query_param};
use super::doc::{Doc, Step, shell_word};
use super::frame::{frame, vec3_bytes};
use super::http::{HttpRequest, HttpResponse, Service};
use fairline::fair::{FairMethod, grow_region};
use fairline::geom::{CurvatureMethod, principal_curvatures};
use fairline::highlight::{
    CircularLight, CircularLights, HighlightLines, HighlightModel, HighlightOptions, LightArray,
    circular_highlight_bands, circular_highlight_lines,
};
use fairline::io::RegionSpec;
use fairline::mesh::{FaceId, VertexId};
use fairline::smooth::SmoothMethod;
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::detect::{DetectInput, DetectSettings, run_with_model as run_detect};
use fairline_commands::enhance::{self, EnhanceSettings};
use fairline_commands::fair::{self, FairInput, FairSettings};
use fairline_commands::fair_quad::{self, QuadSettings};
use fairline_commands::smooth::{self, SmoothSettings};
use fairline_commands::{Choice, CommandError, ErrorKind, FrontEnd, Lights, Subject, Weights};
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

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
                (_, true, ["lines"]) => lines(shared, k, body),
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

/// Summary statistics of a scalar for the legend: its extremes `min`,
/// `max`, the colour range `lo`, `hi` of the pictures' rule
/// ([`fairline::render::scalar_range`]; `signed` for the curvatures and
/// for a field with values of both signs), whether it is `signed` (a
/// diverging map centred on 0) and whether values lie beyond the range
/// (`clipped`).
fn scalar_range(v: &[f64], signed: Option<bool>) -> Value {
    let (min, max) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if min > max {
        return json!({"min": 0.0, "max": 0.0, "lo": -1.0, "hi": 1.0, "signed": true, "clipped": false});
    }
    let signed = signed.unwrap_or(min < 0.0 && max > 0.0);
    let (lo, hi) = fairline::render::scalar_range(v, signed);
    json!({
        "min": min,
        "max": max,
        "lo": lo,
        "hi": hi,
        "signed": signed,
        "clipped": fairline::render::clipped(v, (lo, hi)),
    })
}

fn session(st: &State) -> Value {
    let docs: Vec<Value> = st
        .docs
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let light = LightArray::default_for(d.bbox.0, d.bbox.1, None);
            let mut scalars = vec![
                json!({"name": "k1"}),
                json!({"name": "k2"}),
                json!({"name": "mean"}),
                json!({"name": "gauss"}),
            ];
            for (n, v) in &d.ply_scalars {
                let mut s = scalar_range(v, None);
                s["name"] = json!(n);
                scalars.push(s);
            }
            json!({
                "id": k,
                "name": d.name,
                "kind": if d.is_surface() { "surface" } else { "mesh" },
                "vertices": d.tri.vertex_count(),
                "triangles": d.tri.face_count(),
                "faces": d.input_mesh().face_count(),
                "quads": d.input_mesh().faces().filter(|&f| d.input_mesh().face_size(f) == 4).count(),
                "center": d.center.to_array(),
                "radius": d.radius,
                "bbox": [d.bbox.0.to_array(), d.bbox.1.to_array()],
                "view": d.view,
                // lines of the default spacing lie about spacing/ĝ apart
                "gradient_median": fairline::highlight::readable::distance_gradient_median(&d.tri, &light),
                "scalars": scalars,
                "grid": d.grid,
                "patches": d.history[0].surfaces.as_ref().map(|s| s.len()).unwrap_or(0),
                "light": light,
                "min_normal_cos": HighlightOptions::default().min_normal_cos,
                "load_s": d.load_s,
                "history": {
                    "cursor": d.cursor,
                    "steps": d.history.iter().map(|s| json!({"label": s.label, "command": s.command, "report": s.report})).collect::<Vec<_>>(),
                },
            })
        })
        .collect();
    json!({"docs": docs, "save_dir": st.save_dir.display().to_string(), "job": job_json(st), "restore": st.restore})
}

fn job_json(st: &State) -> Value {
    match &st.job {
        None => Value::Null,
        Some(j) => json!({
            "id": j.id,
            "doc": j.doc,
            "label": j.label,
            "state": j.state,
            "progress": j.progress,
            "stage": j.stage,
            "message": j.message,
            "report": j.report,
            "command": j.command,
            "elapsed_s": j.started.elapsed().as_secs_f64(),
        }),
    }
}

fn scalar(shared: &Shared, k: usize, name: &str, step: Option<usize>) -> Answer {
    let (mesh, ply) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let ply = d
            .ply_scalars
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone());
        (d.tri_at(step), ply)
    };
    let signed = ply.is_none().then_some(true);
    let values = match (name, ply) {
        (_, Some(v)) => v,
        ("k1" | "k2" | "mean" | "gauss", None) => {
            let c = principal_curvatures(&mesh, CurvatureMethod::Rusinkiewicz);
            match name {
                "k1" => c.k1,
                "k2" => c.k2,
                "mean" => c.mean(),
                _ => c.gauss(),
            }
        }
        _ => return error(404, format!("no scalar `{name}`")),
    };
    let range = scalar_range(&values, signed);
    let floats: Vec<f32> = values
        .iter()
        .map(|&x| if x.is_finite() { x as f32 } else { 0.0 })
        .collect();
    binary(frame(&range, &floats))
}

#[derive(Deserialize)]
struct LinesRequest {
    light: Option<LightArray>,
    circular: Option<CircularLights>,
    band: Option<f64>,
    #[serde(default)]
    step: Option<usize>,
}

/// Most circular lights one request may ask for: each is one pass over
/// the mesh (or the patch's grid) and one set of lines in the answer.
const MAX_RADII: usize = 256;
/// Most lights × grid nodes of one surface-lines request.
const MAX_SURFACE_NODES: usize = 16_000_000;

/// The circular lights of a request: at least one, at most [`MAX_RADII`].
fn circular_lights(c: &CircularLights) -> Result<Vec<CircularLight>, Answer> {
    if c.radii.len() > MAX_RADII {
        return Err(bad(format!(
            "{} radii asked for; at most {MAX_RADII} per request",
            c.radii.len()
        )));
    }
    match c.lights() {
        Ok(l) if !l.is_empty() => Ok(l),
        Ok(_) => Err(bad("circular lights need at least one radius")),
        Err(e) => Err(bad(e)),
    }
}

/// Lines into the header list and the float buffer.
fn push_lines(
    lines: &HighlightLines,
    center: Vec3,
    radii: Option<&[f64]>,
    meta: &mut Vec<Value>,
    floats: &mut Vec<f32>,
) {
    for l in &lines.lines {
        let start = floats.len() / 3;
        for p in &l.points {
            let q = *p - center;
            floats.extend([q.x as f32, q.y as f32, q.z as f32]);
        }
        let mut m =
            json!({"index": l.index, "closed": l.closed, "start": start, "count": l.points.len()});
        if let Some(r) = radii.and_then(|r| r.get(l.index as usize)) {
            m["radius"] = json!(r);
        }
        meta.push(m);
    }
}

fn lines(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: LinesRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (center, file, positions, mesh) = {
        let st = lock(shared);
        let d = &st.docs[k];
        (
            d.center,
            d.current_file(),
            Arc::clone(&d.step(req.step).positions),
            d.shared_tri_at(req.step),
        )
    };
    let mesh = mesh.as_ref();
    if let Some(b) = req.band
        && !(b > 0.0 && b.is_finite())
    {
        return bad("band must be a positive number");
    }
    let t = Instant::now();
    let mut stages: Vec<(&str, f64)> = Vec::new();
    let mut meta = Vec::new();
    let mut band_meta = Vec::new();
    let mut floats = Vec::new();
    let mut model_cached = false;
    let command;
    if let Some(c) = req.circular {
        let lights = match circular_lights(&c) {
            Ok(l) => l,
            Err(a) => return a,
        };
        let lines = match circular_highlight_lines(mesh, &lights, &HighlightOptions::default()) {
            Ok(l) => l,
            Err(e) => return bad(e),
        };
        push_lines(&lines, center, Some(&c.radii), &mut meta, &mut floats);
        if let Some(rho) = req.band {
            match circular_highlight_bands(mesh, &lights, rho, &HighlightOptions::default()) {
                Ok(b) => {
                    push_lines(
                        &b.lower,
                        center,
                        Some(&c.radii),
                        &mut band_meta,
                        &mut floats,
                    );
                    push_lines(
                        &b.upper,
                        center,
                        Some(&c.radii),
                        &mut band_meta,
                        &mut floats,
                    );
                }
                Err(e) => return bad(e),
            }
        }
        let radii: Vec<String> = c.radii.iter().map(|r| r.to_string()).collect();
        command = format!(
            "fairline highlight {file} --circle-center {} --circle-axis {} --radii {}{} -o lines.json",
            vec_arg(Vec3::from(c.center)),
            vec_arg(Vec3::from(c.axis)),
            radii.join(","),
            req.band.map(|b| format!(" --band {b}")).unwrap_or_default()
        );
    } else {
        let Some(light) = req.light else {
            return bad("give \"light\" or \"circular\"");
        };
        let model = match cached_model(shared, k, &positions, mesh, light) {
            Ok((m, hit)) => {
                model_cached = hit;
                m
            }
            Err(e) => return bad(e),
        };
        stages.push(("model", t.elapsed().as_secs_f64()));
        let lines = model.lines(mesh);
        stages.push(("chain", t.elapsed().as_secs_f64()));
        push_lines(&lines, center, None, &mut meta, &mut floats);
        stages.push(("encode", t.elapsed().as_secs_f64()));
        if let Some(rho) = req.band {
            match model.bands(mesh, rho) {
                Ok(b) => {
                    push_lines(&b.lower, center, None, &mut band_meta, &mut floats);
                    push_lines(&b.upper, center, None, &mut band_meta, &mut floats);
                }
                Err(e) => return bad(e),
            }
            stages.push(("bands", t.elapsed().as_secs_f64()));
        }
        command = format!(
            "fairline highlight {file} {}{} -o lines.json",
            light_args(&light),
            req.band.map(|b| format!(" --band {b}")).unwrap_or_default()
        );
    }
    // seconds of each stage (linear lights): the model (normals, distances,
    // segments; 0 when cached), chaining the segments into polylines, the
    // f32 encoding, the band boundaries (two more contours, when asked)
    let mut split = serde_json::Map::new();
    let mut last = 0.0;
    for (name, at) in stages {
        split.insert(name.into(), json!(at - last));
        last = at;
    }
    let header = json!({
        "lines": meta,
        "bands": band_meta,
        "time_s": t.elapsed().as_secs_f64(),
        "stages_s": split,
        "model_cached": model_cached,
        "command": command,
    });
    binary(frame(&header, &floats))
}

#[derive(Deserialize)]
struct DetectRequest {
    light: LightArray,
    threshold: Option<f64>,
    region_radius: Option<f64>,
    /// The history step to detect on (`None`: the current state), so that
    /// the page's "before" shows the detection of the state before.
    step: Option<usize>,
}

/// Detection under the page's lights: the command layer's `detect` on the
/// document's triangles with the lights given exactly (so its readable
/// lights are the page's and the cached model of those lights serves),
/// the detection of the whole part as `fairline detect` runs it.
fn detect(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: DetectRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (mesh, center, file, positions) = {
        let st = lock(shared);
        let d = &st.docs[k];
        (
            d.shared_tri_at(req.step),
            d.center,
            d.current_file(),
            Arc::clone(&d.step(req.step).positions),
        )
    };
    let mesh = mesh.as_ref();
    let defaults = DetectSettings::default();
    let settings = DetectSettings {
        lights: Lights::exactly(&req.light),
        threshold: req.threshold.unwrap_or(defaults.threshold),
        region_margin: req.region_radius.unwrap_or(defaults.region_margin),
        ..defaults
    };
    let t = Instant::now();
    let model = match cached_model(shared, k, &positions, mesh, req.light) {
        Ok((m, _)) => m,
        Err(e) => return bad(e),
    };
    let input = DetectInput {
        mesh,
        source: None,
        name: None,
    };
    let report = fairline_commands::Report::new("detect");
    let out = match run_detect(input, &settings, req.light, &model, report, &Control::new()) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let (lines, det) = (&out.lines, &out.detection);
    let elapsed = t.elapsed().as_secs_f64();
    let mut meta = Vec::new();
    let mut floats = Vec::new();
    push_lines(lines, center, None, &mut meta, &mut floats);
    let mut stretches = Vec::new();
    for l in &det.lines {
        for s in &l.stretches {
            let start = floats.len() / 3;
            for p in s {
                let q = *p - center;
                floats.extend([q.x as f32, q.y as f32, q.z as f32]);
            }
            stretches.push(json!({"line": l.line, "index": l.index, "score": l.score, "start": start, "count": s.len()}));
        }
    }
    let regions: Vec<Value> = det
        .regions
        .iter()
        .map(|r| {
            json!({
                "score": r.score,
                "threshold": r.threshold,
                "flat_spot": r.flat_spot,
                "severity": r.severity,
                "center": (r.center - center).to_array(),
                "faces": r.faces.iter().map(|f| f.0).collect::<Vec<_>>(),
                "lines": r.lines,
            })
        })
        .collect();
    let command = settings.command_line(&file, "region.json");
    let header = json!({
        "lines": meta,
        "bands": [],
        "stretches": stretches,
        "regions": regions,
        "report": out.report.to_json(),
        "sites": det.sites.len(),
        "shape_sites": det.shape_sites,
        "smooth_radius": det.smooth_radius,
        "time_s": elapsed,
        "command": command,
    });
    binary(frame(&header, &floats))
}

#[derive(Deserialize)]
struct RegionRequest {
    op: String,
    #[serde(default)]
    faces: Vec<u32>,
    #[serde(default)]
    rings: Option<usize>,
    center: Option<[f64; 3]>,
    radius: Option<f64>,
}

fn to_faces(mesh: &SurfaceMesh, faces: &[u32]) -> Vec<FaceId> {
    let mut f: Vec<FaceId> = faces
        .iter()
        .filter(|&&t| (t as usize) < mesh.face_count())
        .map(|&t| FaceId(t))
        .collect();
    f.sort_unstable();
    f.dedup();
    f
}

fn region(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: RegionRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (mesh, center) = {
        let st = lock(shared);
        (st.docs[k].tri_at(None), st.docs[k].center)
    };
    let faces = to_faces(&mesh, &req.faces);
    let rings = req.rings.unwrap_or(1).min(1000);
    let out: Vec<FaceId> = match req.op.as_str() {
        "grow" => grow_region(&mesh, &faces, rings),
        "shrink" => {
            // the complement grown by `rings` rings, complemented again
            let mut inside = vec![false; mesh.face_count()];
            for f in &faces {
                inside[f.idx()] = true;
            }
            let outside: Vec<FaceId> = mesh.faces().filter(|f| !inside[f.idx()]).collect();
            if outside.is_empty() {
                // a closed region with nothing outside: shrink from the
                // mesh boundary is impossible; leave it
                faces.clone()
            } else {
                let grown = grow_region(&mesh, &outside, rings);
                let mut out_grown = vec![false; mesh.face_count()];
                for f in &grown {
                    out_grown[f.idx()] = true;
                }
                faces
                    .iter()
                    .copied()
                    .filter(|f| !out_grown[f.idx()])
                    .collect()
            }
        }
        "sphere" => {
            let (Some(c), Some(r)) = (req.center, req.radius) else {
                return bad("sphere needs center and radius");
            };
            if !(r > 0.0 && r.is_finite() && c.iter().all(|x| x.is_finite())) {
                return bad("sphere needs a finite center and a positive radius");
            }
            let c = Vec3::from(c) + center;
            let spec = json!({"sphere": {"center": c.to_array(), "radius": r}}).to_string();
            match RegionSpec::from_json(&spec).and_then(|s| s.faces(&mesh)) {
                Ok(f) => f,
                Err(e) => return bad(e),
            }
        }
        other => {
            return bad(format!(
                "unknown region op `{other}` (grow, shrink, sphere)"
            ));
        }
    };
    json_answer(&json!({"faces": out.iter().map(|f| f.0).collect::<Vec<_>>()}))
}

/// Vertices all of whose faces are in the region.
fn inside_vertices(mesh: &SurfaceMesh, faces: &[FaceId]) -> Vec<bool> {
    let mut inr = vec![false; mesh.face_count()];
    for f in faces {
        inr[f.idx()] = true;
    }
    (0..mesh.vertex_count())
        .map(|v| {
            let mut any = false;
            for f in mesh.vertex_faces(VertexId(v as u32)) {
                if !inr[f.idx()] {
                    return false;
                }
                any = true;
            }
            any
        })
        .collect()
}

fn region_file(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    #[derive(Deserialize)]
    struct Req {
        faces: Vec<u32>,
    }
    let req: Req = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let st = lock(shared);
    let d = &st.docs[k];
    let faces = to_faces(&d.tri, &req.faces);
    let inside = inside_vertices(&d.tri, &faces);
    let fixed: Vec<u32> = (0..inside.len() as u32)
        .filter(|&v| !inside[v as usize])
        .collect();
    json_answer(&json!({
        "region": {"faces": d.input_faces(&req.faces)},
        "fixed": {"vertices": fixed},
    }))
}

#[derive(Deserialize, Default)]
#[serde(default)]
struct RunOptions {
    method: Option<String>,
    max_iterations: Option<usize>,
    epsilon: Option<f64>,
    iterations: Option<usize>,
    lambda: Option<f64>,
    mu: Option<f64>,
    weights: Option<String>,
    weight: Option<f64>,
}

#[derive(Deserialize)]
struct RunRequest {
    method: String,
    /// fair-surface: the patch, the circular lights and the endpoints
    /// `[{"radius","start":[u,v],"end":[u,v]}]` (DESIGN.md §5).
    #[serde(default)]
    patch: usize,
    circular: Option<CircularLights>,
    endpoints: Option<Value>,
    #[serde(default)]
    faces: Option<Vec<u32>>,
    light: Option<LightArray>,
    #[serde(default)]
    options: RunOptions,
}

/// What a finished job gives: new positions, report, command, label.
struct Outcome {
    positions: Vec<Vec3>,
    surfaces: Option<Arc<Vec<fairline::bspline::BSplineSurface>>>,
    report: Value,
    command: String,
    label: String,
}

fn start_job(shared: &Arc<Shared>, k: usize, body: &[u8]) -> Answer {
    let req: RunRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let mut st = lock(shared);
    if st
        .job
        .as_ref()
        .is_some_and(|j| matches!(j.state, "running" | "cancelling"))
    {
        return error(409, "a job is still running; wait for it or cancel it");
    }
    let d = &st.docs[k];
    if d.is_surface() != (req.method == "fair-surface") {
        return bad(if d.is_surface() {
            "this document is a B-spline surface: its method is fair-surface"
        } else {
            "fair-surface needs a B-spline surface document"
        });
    }
    let surface_input = d.current().surfaces.clone().map(|s| (s, d.grid));
    let tri = d.tri_at(None);
    let mesh = d.mesh_now();
    let file = d.current_file();
    let out = d.next_file();
    let id = st.next_job;
    st.next_job += 1;
    let cancel = Arc::new(AtomicBool::new(false));
    st.job = Some(Job {
        id,
        doc: k,
        label: req.method.clone(),
        state: "running",
        progress: 0.0,
        stage: "",
        message: format!("{} running", req.method),
        report: Value::Null,
        command: String::new(),
        cancel: Arc::clone(&cancel),
        started: Instant::now(),
    });
    drop(st);
    let ctx = JobContext {
        id,
        doc: k,
        cancel,
        progress: Arc::new(Mutex::new(JobProgress::default())),
    };
    let shared = Arc::clone(shared);
    std::thread::spawn(move || {
        let control = job_control(&ctx);
        let (tx, rx) = std::sync::mpsc::channel();
        let worker = std::thread::spawn(move || {
            let r = match surface_input {
                Some((surfaces, grid)) => {
                    run_fair_surface(&req, &surfaces, grid, &file, &out, &control)
                }
                None => run_method(&req, &tri, &mesh, &file, &out, &control),
            };
            let _ = tx.send(());
            r
        });
        // copy the progress into the job while it runs
        while rx
            .recv_timeout(std::time::Duration::from_millis(100))
            .is_err()
            && !worker.is_finished()
        {
            let p = *ctx.progress.lock().unwrap_or_else(|e| e.into_inner());
            let mut st = lock(&shared);
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
                && j.state == "running"
            {
                j.progress = p.fraction;
                j.stage = p.stage;
            }
        }
        let result = worker
            .join()
            .unwrap_or_else(|_| Err("the computation panicked".to_string()));
        finish_job(&shared, &ctx, result);
    });
    json_answer(&json!({"job": id}))
}

/// What the library last reported of a running job.
#[derive(Clone, Copy, Default)]
struct JobProgress {
    /// Fraction done, 0..1.
    fraction: f64,
    /// The stage ("iterations" …).
    stage: &'static str,
}

struct JobContext {
    id: u64,
    doc: usize,
    cancel: Arc<AtomicBool>,
    progress: Arc<Mutex<JobProgress>>,
}

/// The [`fairline::Control`] of a job: the job's cancel flag (raised by
/// `POST /api/job/cancel`, the library stops at its next
/// `control.step(..)`) and a progress callback writing the fraction done
/// into the job. Every job's options get it through their builder
/// `.control(..)` where the library's options have one.
fn job_control(ctx: &JobContext) -> Control {
    let progress = Arc::clone(&ctx.progress);
    Control::new()
        .cancel_flag(Arc::clone(&ctx.cancel))
        .on_progress(move |p| {
            let mut slot = progress.lock().unwrap_or_else(|e| e.into_inner());
            slot.stage = p.stage;
            if p.total > 0 {
                slot.fraction = (p.done as f64 / p.total as f64).clamp(0.0, 1.0);
            }
        })
}

fn finish_job(shared: &Shared, ctx: &JobContext, result: Result<Outcome, String>) {
    let mut st = lock(shared);
    let cancelled = ctx.cancel.load(Ordering::SeqCst);
    if cancelled {
        // stopped by the library (its Cancelled error) or finished after
        // the flag was raised: the result is thrown away either way
        if let Some(j) = st.job.as_mut()
            && j.id == ctx.id
        {
            j.state = "cancelled";
            j.message = match &result {
                Err(e) if e == "cancelled" => format!(
                    "{} cancelled after {:.2} s",
                    j.label,
                    j.started.elapsed().as_secs_f64()
                ),
                _ => format!("{} cancelled; its result was discarded", j.label),
            };
        }
        return;
    }
    match result {
        Ok(o) => {
            let d = &mut st.docs[ctx.doc];
            let surfaces = o.surfaces.or_else(|| d.current().surfaces.clone());
            d.push(Step::new(
                o.label.clone(),
                o.command.clone(),
                o.report.clone(),
                Arc::new(o.positions),
                surfaces,
            ));
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
            {
                j.state = "done";
                j.progress = 1.0;
                j.message = format!("{} done", o.label);
                j.report = o.report;
                j.command = o.command;
            }
        }
        Err(e) => {
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
            {
                j.state = "failed";
                j.message = e;
            }
        }
    }
}

/// Runs a mesh job: the command of the request with the job's `control`
/// (see [`job_control`]: progress and cancellation).
fn run_method(
    req: &RunRequest,
    tri: &SurfaceMesh,
    mesh: &SurfaceMesh,
    file: &str,
    out: &str,
    control: &Control,
) -> Result<Outcome, String> {
    let job = MeshJob {
        req,
        tri,
        mesh,
        file,
        out,
        control,
        faces: req.faces.as_ref().map(|f| to_faces(tri, f)),
    };
    match req.method.as_str() {
        "fair" => job.fair(),
        "smooth" => job.smooth(),
        "fair-quad" => job.fair_quad(),
        "enhance" => job.enhance(),
        other => Err(format!(
            "unknown method `{other}` (fair, smooth, fair-quad, enhance)"
        )),
    }
}

/// One mesh job of [`run_method`]: the request, the document's meshes
/// (`tri` triangulated, `mesh` as loaded), the file names the equivalent
/// command line uses, the job's control and the region's faces (of `tri`).
struct MeshJob<'j> {
    req: &'j RunRequest,
    tri: &'j SurfaceMesh,
    mesh: &'j SurfaceMesh,
    file: &'j str,
    out: &'j str,
    control: &'j Control,
    faces: Option<Vec<FaceId>>,
}

impl MeshJob<'_> {
    /// With a region: every vertex outside it is fixed (none without).
    fn fixed_outside(&self) -> Vec<VertexId> {
        match &self.faces {
            None => Vec::new(),
            Some(f) => {
                let inside = inside_vertices(self.tri, f);
                (0..inside.len() as u32)
                    .filter(|&v| !inside[v as usize])
                    .map(VertexId)
                    .collect()
            }
        }
    }

    /// Highlight-line fairing of the region: the `fair` command with the
    /// page's lights and options, detection before and after included.
    fn fair(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let faces = self
            .faces
            .as_ref()
            .ok_or("fairing needs a region (faces)")?;
        let light = self.req.light.ok_or("fairing needs the light array")?;
        let method = match o.method.as_deref() {
            Some(m) => FairMethod::parse(m).map_err(job_error)?,
            None => FairMethod::Highlight,
        };
        let d = FairSettings::default();
        let settings = FairSettings {
            lights: Lights::exactly(&light),
            method,
            max_iterations: o.max_iterations.unwrap_or(d.max_iterations),
            epsilon: o.epsilon.unwrap_or(d.epsilon),
            ..d
        };
        let input = FairInput {
            mesh: self.tri,
            region: Some(faces),
            name: Some(self.file),
        };
        let out = fair::run(input, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.mesh.positions().to_vec(),
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: format!("fair ({})", method.name()),
        })
    }

    /// One of the smoothing methods, outside the region fixed: the
    /// `smooth` command with the page's options (cotangent weights unless
    /// the page says otherwise; λ for Laplace smoothing only, Taubin's
    /// comes from the pass band).
    fn smooth(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let method =
            SmoothMethod::parse(o.method.as_deref().unwrap_or("taubin")).map_err(job_error)?;
        let weights = Weights::parse(o.weights.as_deref().unwrap_or("cotan")).map_err(job_error)?;
        let settings = SmoothSettings {
            method,
            weights,
            iterations: o.iterations,
            lambda: o.lambda.filter(|_| method == SmoothMethod::Laplace),
            fixed: self.fixed_outside(),
            ..SmoothSettings::default()
        };
        let out = smooth::run(self.mesh, &settings, self.control).map_err(job_error)?;
        // a run that stopped unconverged is not what was asked for: the
        // job fails with the reason, the document keeps its state (so a
        // save cannot write the unconverged result)
        if let Some(e) = out.stopped_error(fairline_commands::FrontEnd::Workbench) {
            return Err(job_error(e));
        }
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: format!("smooth ({})", method.name()),
        })
    }

    /// Structure-line fairing of a quad mesh, outside the region fixed:
    /// the `fair-quad` command with the page's weight and iterations.
    fn fair_quad(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let d = QuadSettings::default();
        let settings = QuadSettings {
            weight: o.weight.unwrap_or(d.weight),
            iterations: o.iterations.unwrap_or(d.iterations),
            fixed: self.fixed_outside(),
            ..d
        };
        let out = fair_quad::run(self.mesh, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: "fair-quad".into(),
        })
    }

    /// Feature enhancement by vertex flow, outside the region fixed: the
    /// `enhance` command with the page's λ, μ and iterations.
    fn enhance(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let d = EnhanceSettings::default();
        let settings = EnhanceSettings {
            lambda: o.lambda.unwrap_or(d.lambda),
            mu: o.mu.unwrap_or(d.mu),
            iterations: o.iterations.unwrap_or(d.iterations),
            fixed: self.fixed_outside(),
            ..d
        };
        let out = enhance::run(self.tri, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: "enhance".into(),
        })
    }
}

fn move_cursor(shared: &Shared, k: usize, by: i64) -> Answer {
    let mut st = lock(shared);
    let d = &mut st.docs[k];
    let next = d.cursor as i64 + by;
    if next < 0 || next >= d.history.len() as i64 {
        return error(
            409,
            if by < 0 {
                "nothing to undo"
            } else {
                "nothing to redo"
            },
        );
    }
    d.set_cursor(next as usize);
    json_answer(&json!({"cursor": d.cursor, "label": d.history[d.cursor].label}))
}

/// The current mesh (or surfaces) in a format, as bytes.
pub(super) fn current_bytes(d: &Doc, ext: &str) -> Result<Vec<u8>, String> {
    step_bytes(d, d.cursor, ext)
}

/// The state of step `n` of `d` (clamped to the history) as a file of
/// format `ext`: a mesh format, or JSON for surfaces.
pub(super) fn step_bytes(d: &Doc, n: usize, ext: &str) -> Result<Vec<u8>, String> {
    let step = d.step(Some(n));
    if ext == "json" {
        let Some(s) = &step.surfaces else {
            return Err("JSON is for surfaces; meshes download as obj, ply, off or stl".into());
        };
        return Ok(fairline::io::surfaces_to_json(s).into_bytes());
    }
    if !matches!(ext, "obj" | "ply" | "off" | "stl") {
        return Err(format!("unknown format `{ext}` (obj, ply, off, stl, json)"));
    }
    let mut mesh = d.input_mesh().clone();
    mesh.set_positions(step.positions.to_vec())
        .map_err(|e| e.to_string())?;
    let dir = std::env::temp_dir();
    let name = format!(
        "fairline-view-{}-{}.{ext}",
        std::process::id(),
        super::auth::new_token().map_err(|e| e.to_string())?
    );
    let path = dir.join(name);
    let r = fairline::io::write_mesh(&path, &mesh)
        .map_err(|e| e.to_string())
        .and_then(|_| std::fs::read(&path).map_err(|e| e.to_string()));
    let _ = std::fs::remove_file(&path);
    r
}

fn download(shared: &Shared, k: usize, url: &str) -> Answer {
    let st = lock(shared);
    let d = &st.docs[k];
    let ext = query_param(url, "format").unwrap_or_else(|| {
        if d.is_surface() {
            "json".into()
        } else {
            "ply".into()
        }
    });
    match current_bytes(d, &ext) {
        Ok(bytes) => {
            let mut a = binary(bytes);
            let stem = d
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "mesh".into());
            a.headers.push((
                "Content-Disposition".into(),
                format!(
                    "attachment; filename=\"{}-step{}.{ext}\"",
                    stem.replace(['"', '\\'], "_"),
                    d.cursor
                ),
            ));
            a
        }
        Err(e) => bad(e),
    }
}

/// A plain file name: no separator, not `.`/`..`, no leading dot, no
/// control characters, at most 200 bytes.
pub fn safe_file_name(name: &str) -> Result<&str, String> {
    let ok = !name.is_empty()
        && name.len() <= 200
        && !name.starts_with('.')
        && !name.contains(['/', '\\', ':', '\0'])
        && !name.chars().any(char::is_control);
    if ok {
        Ok(name)
    } else {
        Err(format!(
            "`{name}` is not a plain file name (no folders, no leading dot)"
        ))
    }
}

fn save(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    #[derive(Deserialize)]
    struct Req {
        name: String,
        /// Replace an existing file of that name (a regular file only).
        #[serde(default)]
        overwrite: bool,
    }
    let req: Req = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let name = match safe_file_name(&req.name) {
        Ok(n) => n,
        Err(e) => return bad(e),
    };
    let st = lock(shared);
    let d = &st.docs[k];
    let path = st.save_dir.join(name);
    for input in st.docs.iter().map(|d| &d.path) {
        if let Err(e) = fairline::io::ensure_distinct(input, &path) {
            return bad(e);
        }
    }
    let ext = std::path::Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    // the same policy as the CLI's outputs: an existing file is replaced
    // only when asked, never through a symbolic link (the write and its
    // rename stay in the save folder)
    match std::fs::symlink_metadata(&path) {
        Ok(m) if m.file_type().is_symlink() => {
            return bad(format!(
                "{name} in the save folder is a symbolic link; saves are not written through links"
            ));
        }
        Ok(_) if !req.overwrite => {
            return error(
                409,
                format!("{name} exists in the save folder; choose another name or overwrite it"),
            );
        }
        _ => {}
    }
    let bytes = match current_bytes(d, &ext) {
        Ok(b) => b,
        Err(e) => return bad(e),
    };
    match fairline::io::atomic_write_here(&path, |w| std::io::Write::write_all(w, &bytes)) {
        Ok(()) => json_answer(&json!({
            "path": path.display().to_string(),
            "bytes": bytes.len(),
            "command": format!("# saved step {} of {} as {}", d.cursor, d.name, shell_word(&path.display().to_string())),
        })),
        Err(e) => error(500, e.to_string()),
    }
}

/// Patch boundaries (one closed polyline per patch, from its tessellation
/// grid) and a label point per patch (its middle grid point).
fn outlines(shared: &Shared, k: usize, step: Option<usize>) -> Answer {
    let st = lock(shared);
    let d = &st.docs[k];
    let Some(surfaces) = &d.step(step).surfaces else {
        return bad("outlines are for B-spline surfaces");
    };
    let n = d.grid;
    let p = &d.step(step).positions;
    let mut floats = Vec::new();
    let mut meta = Vec::new();
    let mut labels = Vec::new();
    for s in 0..surfaces.len() {
        let base = s * n * n;
        let at =
            |a: usize, b: usize| p.get(base + a * n + b).copied().unwrap_or(Vec3::ZERO) - d.center;
        let mut ring: Vec<(usize, usize)> = Vec::new();
        ring.extend((0..n).map(|b| (0, b)));
        ring.extend((1..n).map(|a| (a, n - 1)));
        ring.extend((0..n - 1).rev().map(|b| (n - 1, b)));
        ring.extend((1..n - 1).rev().map(|a| (a, 0)));
        let start = floats.len() / 3;
        for (a, b) in &ring {
            let q = at(*a, *b);
            floats.extend([q.x as f32, q.y as f32, q.z as f32]);
        }
        meta.push(json!({"index": s, "closed": true, "start": start, "count": ring.len()}));
        labels.push(at(n / 2, n / 2).to_array());
    }
    binary(frame(&json!({"lines": meta, "labels": labels}), &floats))
}

#[derive(Deserialize)]
struct SurfaceLinesRequest {
    circular: CircularLights,
    #[serde(default)]
    patch: usize,
    grid: Option<usize>,
    band: Option<f64>,
}

/// Circular highlight line pre-images of one patch (Nishiyama et al. §2),
/// by the command layer's `surface_highlight` (so `report` is the report
/// of the answer's `command`): a frame with the 3-D points (minus the
/// centre), then the (u, v) points; each line has `radius`, `closed`,
/// `start`, `count` and `uv_start`.
fn surface_lines(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    use fairline_commands::highlight::HighlightLights;
    use fairline_commands::surface_highlight::{SurfaceHighlightSettings, run};
    let req: SurfaceLinesRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (surfaces, center, file) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let Some(s) = &d.current().surfaces else {
            return bad("surface lines are for B-spline surfaces");
        };
        if req.patch >= s.len() {
            return bad(format!(
                "no patch {} (the file holds {})",
                req.patch,
                s.len()
            ));
        }
        (Arc::clone(s), d.center, d.current_file())
    };
    let lights = match circular_lights(&req.circular) {
        Ok(l) => l,
        Err(a) => return a,
    };
    let grid = req.grid.unwrap_or(200).clamp(8, 2000);
    if lights.len() * grid * grid > MAX_SURFACE_NODES {
        return bad(format!(
            "{} lights on a {grid} × {grid} grid: more than {MAX_SURFACE_NODES} light × grid nodes; use fewer radii or a coarser grid",
            lights.len()
        ));
    }
    if let Some(b) = req.band
        && !(b > 0.0 && b.is_finite())
    {
        return bad("band must be a positive number");
    }
    let t = Instant::now();
    let settings = SurfaceHighlightSettings {
        lights: HighlightLights::Circular {
            spec: req.circular.clone(),
            from_lights: false,
        },
        grid,
        band: req.band,
        surface: Some(req.patch),
    };
    let out = match run(&surfaces, &settings, &Control::new(), &|| {}) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let (surface, h) = (&out.surfaces[0], &out.results[0].1.highlights);
    let elapsed = t.elapsed().as_secs_f64();
    let all: Vec<(&str, &fairline::highlight::SurfaceHighlightLine)> = h
        .lines
        .iter()
        .map(|l| ("line", l))
        .chain(h.band_lower.iter().map(|l| ("band", l)))
        .chain(h.band_upper.iter().map(|l| ("band", l)))
        .collect();
    let mut floats = Vec::new();
    let mut meta = Vec::new();
    for (kind, l) in &all {
        let start = floats.len() / 3;
        for p in &l.points {
            let q = *p - center;
            floats.extend([q.x as f32, q.y as f32, q.z as f32]);
        }
        meta.push(json!({"kind": kind, "light": l.light, "radius": l.radius, "level": l.level, "closed": l.closed, "start": start, "count": l.points.len()}));
    }
    let uv_base = floats.len();
    for (m, (_, l)) in meta.iter_mut().zip(&all) {
        m["uv_start"] = json!((floats.len() - uv_base) / 2);
        for uv in &l.uv {
            floats.extend([uv[0] as f32, uv[1] as f32]);
        }
    }
    let [u0, u1] = surface.domain_u();
    let [v0, v1] = surface.domain_v();
    let radii: Vec<String> = req.circular.radii.iter().map(|r| r.to_string()).collect();
    let header = json!({
        "lines": meta,
        "uv_offset": uv_base,
        "domain": [[u0, u1], [v0, v1]],
        "time_s": elapsed,
        "report": out.report.to_json(),
        "command": format!(
            "fairline highlight {file} --surface {} --circle-center {} --circle-axis {} --radii {} --grid {grid}{} -o lines.json --svg uv.svg",
            req.patch,
            vec_arg(Vec3::from(req.circular.center)),
            vec_arg(Vec3::from(req.circular.axis)),
            radii.join(","),
            req.band.map(|b| format!(" --band {b}")).unwrap_or_default()
        ),
    });
    binary(frame(&header, &floats))
}

/// Circular-highlight fairing of one patch (Nishiyama et al. §3): the
/// command layer's `fair_surface` with the page's lights and endpoints and
/// the library's defaults but for the iterations and ε; the patch is
/// replaced and re-tessellated.
fn run_fair_surface(
    req: &RunRequest,
    surfaces: &Arc<Vec<fairline::bspline::BSplineSurface>>,
    grid: usize,
    file: &str,
    out: &str,
    control: &Control,
) -> Result<Outcome, String> {
    use fairline::fair::Endpoints;
    use fairline_commands::fair_surface::{FairSurfaceInput, FairSurfaceSettings, run};
    let circular = req
        .circular
        .as_ref()
        .ok_or("fair-surface needs the circular lights")?;
    let ends: Endpoints =
        serde_json::from_value(json!({"endpoints": req.endpoints.clone().unwrap_or(Value::Null)}))
            .map_err(|e| format!("endpoints: {e}"))?;
    if req.patch >= surfaces.len() {
        return Err("no such patch".into());
    }
    let d = FairSurfaceSettings::default();
    let settings = FairSurfaceSettings {
        surface: req.patch,
        max_iterations: req.options.max_iterations.unwrap_or(d.max_iterations),
        epsilon: req.options.epsilon.unwrap_or(d.epsilon),
        ..d
    };
    let input = FairSurfaceInput {
        surfaces: surfaces.as_slice(),
        lights: Some(circular),
        endpoints: &ends.endpoints,
    };
    let faired = run(input, &settings, control).map_err(job_error)?;
    let (mesh, _) =
        super::doc::tessellate_all(&faired.surfaces, grid).map_err(|e| e.to_string())?;
    Ok(Outcome {
        positions: mesh.positions().to_vec(),
        surfaces: Some(Arc::new(faired.surfaces)),
        report: faired.report.to_json(),
        command: settings.command_line(file, out),
        label: format!("fair-surface (patch {})", req.patch),
    })
}

/// A failure of the command layer as the job's message: `cancelled` for a
/// cancelled run, else the message worded for the workbench, with the
/// region named when it is about the region.
fn job_error(e: CommandError) -> String {
    match (e.kind(), e.subject()) {
        (ErrorKind::Cancelled, _) => "cancelled".into(),
        (_, Some(Subject::Region)) => format!("region: {}", e.message(FrontEnd::Workbench)),
        (_, Some(Subject::Lights)) => format!("lights: {}", e.message(FrontEnd::Workbench)),
        _ => e.message(FrontEnd::Workbench),
    }
}
