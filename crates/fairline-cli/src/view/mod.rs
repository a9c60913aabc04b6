//! `fairline view`: the workbench, a local browser app over the library.
//!
//! The command reads the files named on the command line, starts an HTTP
//! server bound to 127.0.0.1 only, prints the page URL with a random access
//! token as the first line of standard output, opens the browser (unless
//! `--no-open`) and serves until interrupted. The page (crates/fairline-cli/web,
//! embedded in the binary) is a client of the JSON API below; the only
//! computation in JavaScript is shading. The browser is opened on a small
//! redirect page (0600, removed after a minute), so that the token never
//! appears on a command line.
//!
//! # Security
//! - The listener is bound to 127.0.0.1.
//! - Every request must carry the token: as the `token` query parameter
//!   (the page URL), the `X-Fairline-Token` header (API calls of the page),
//!   or, for GET requests only, the `fairline_PORT` cookie the page response
//!   sets (`HttpOnly; SameSite=Strict`, so that the page's ES module imports
//!   load). Anything else gets 403, the page included.
//! - The `Host` header must be `127.0.0.1:PORT` or `localhost:PORT` (DNS
//!   rebinding), an `Origin` header, when present, `http://127.0.0.1:PORT`
//!   or `http://localhost:PORT`, and `Sec-Fetch-Site: cross-site` is refused
//!   (cross-site requests). POST requests need the header token (the query
//!   parameter is for GET only): a form of
//!   another site cannot set it, and no CORS header is ever sent.
//! - The token is checked on the request line and headers before any body
//!   byte is read; bodies are bounded per endpoint; request heads and bodies
//!   have deadlines; connections without the token share a small pool of
//!   their own (the limits are documented in `http`). Circular lights are
//!   at most 256 per request; lines and detection compute without the
//!   workbench's lock, so cancel and other calls are answered meanwhile.
//! - Only the files named on the command line are read; saves go to
//!   `--save-dir` (default: the current folder) under a plain file name (no
//!   separator, no `..`), atomically, never over an input file.
//!
//! # API (all paths under `/api`, all JSON unless said otherwise)
//! - `GET /api/session`: the open documents `docs[k]` with `name`, `kind`
//!   (`mesh` | `surface`), `vertices`, `triangles`, `center` (positions in
//!   binary buffers are relative to it), `radius`, `bbox`, `scalars`
//!   (names with `min`, `max`, `lo`, `hi` = 2nd/98th percentiles),
//!   `patches`, `light` (the default linear light array of DESIGN.md §5),
//!   `min_normal_cos`, `history` (`cursor`, `steps` with `label`, `command`);
//!   plus `save_dir` and `job`.
//! - `GET /api/doc/K/positions[?step=N]`, `.../normals[?step=N]`:
//!   little-endian f32 triples per vertex (positions minus `center`;
//!   normals = the library's area-weighted vertex normals, Yong et al.
//!   Eq. (3), computed once per step, for the opening step while the file
//!   is read); `step` selects a history step (default the current one).
//! - `GET /api/doc/K/indices`: u32 triples per triangle.
//! - `GET /api/doc/K/patches`: u32 patch index per triangle (surfaces).
//! - `GET /api/doc/K/scalar/NAME`: f32 per vertex (`k1 k2 mean gauss` by
//!   Rusinkiewicz's method, or a PLY vertex property of the input).
//! - `POST /api/doc/K/lines` `{"light":LIGHT}` or
//!   `{"circular":{"center","axis","radii"}}`, optional `"band":rho`: the
//!   library's exact highlight polylines. Binary frame: u32 length of a JSON
//!   header, the header, padding to 4 bytes, then f32 points (minus
//!   `center`); the header lists `lines` (`index`, `closed`, `start`,
//!   `count` into the points), `bands`, `time_s`, `stages_s` (linear
//!   lights: seconds of `model`, `chain`, `encode`, and `bands` when a band
//!   was asked for), `model_cached` (linear lights: the highlight model
//!   of the last request was reused — same document state and lights — so
//!   `model` is about 0) and `command`. Detection reuses that model too.
//! - `POST /api/doc/K/detect` `{"light":LIGHT, "threshold"?, "region_radius"?}`:
//!   the same frame; the header adds `stretches` (irregular stretches,
//!   `start`, `count`, `score`), the ranked `regions` (`score`, `center`,
//!   `faces` as triangle indices) and `report`: the command layer's
//!   `detect` report, the one `command` (its `fairline detect` line)
//!   writes.
//! - `POST /api/doc/K/region` `{"faces":[..], "op":"grow"|"shrink", "rings":n}`
//!   or `{"op":"sphere","center":[x,y,z],"radius":r}`: a triangle set.
//! - `POST /api/doc/K/region-file` `{"faces":[..]}`: the region JSON of
//!   DESIGN.md §5 in the input file's face indices, and `fixed`: the fixed
//!   vertices file (every vertex not inside the region).
//! - `POST /api/doc/K/run` `{"method":M, "faces"?, "light"?, "options"?}`
//!   with M one of `fair` (options `method`
//!   highlight|paper|diffusion-flow|membrane|thin-plate|mvs,
//!   `max_iterations`, `epsilon`), `smooth` (options `method`, `iterations`,
//!   `lambda`, `weights`), `fair-quad` (`weight`, `iterations`), `enhance`
//!   (`lambda`, `mu`, `iterations`): starts a job on a thread; answers
//!   `{"job":id}`. With `faces`, only the vertices inside the region move.
//! - `GET /api/job`: `{"id","state":"running"|"cancelling"|"done"|"failed"|"cancelled",
//!   "progress":0..1,"stage","message","report","command"}`.
//!   `POST /api/job/cancel` raises the job's cancel flag: the job's
//!   [`fairline::Control`] (in the options of every library call that takes
//!   one) stops the algorithm at its next checkpoint; the job is
//!   `cancelling` until its thread has ended, then `cancelled`, and its
//!   result is thrown away. Progress comes from the same `Control`
//!   (`stage`, done/total).
//! - The server answers the page's files as soon as the URL is printed;
//!   API calls wait until the files named on the command line are read
//!   (`GET /api/session` gives `load_s` per document: `read`, `prepare`,
//!   `total` seconds).
//! - `POST /api/doc/K/undo`, `POST /api/doc/K/redo`: move in the history.
//! - `GET /api/doc/K/download?format=obj|ply|off|stl|json`: the current mesh
//!   (or surfaces as JSON) as a file.
//! - `POST /api/doc/K/save` `{"name":"file.obj"}`: writes the current mesh
//!   (or surfaces .json) into the save folder, atomically.
//! - `POST /api/doc/K/deviation`, `POST /api/doc/K/probe`: the evaluation
//!   tools, documented in `tools`.
//! - `POST /api/doc/K/section`, `POST /api/doc/K/draft`: plane sections
//!   with curvature combs and the draft-angle map, documented in `shape`.
//! - `POST /api/session-file`: saves the session (files, view, marks,
//!   history positions) as JSON, documented in `session`; `GET
//!   /api/session` gives the page's part of an opened session as
//!   `restore`.
//! - `POST /api/doc/K/continuity`, `GET /api/doc/K/control-net`: the
//!   continuity of patch boundaries and the control net of surface
//!   documents, documented in `surface_tools`.

mod api;
mod assets;
mod auth;
mod doc;
mod frame;
mod http;
mod session;
mod shape;
mod surface_tools;
mod tools;

use crate::error::bad_input;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

/// Opens meshes (.obj .ply .off .stl) or B-spline surfaces (.json .igs
/// .iges .step .stp) in the browser: exact highlight shading on the GPU, the
/// library's highlight lines and detected irregularities, marking a region
/// and fairing or smoothing it, with undo/redo and the equivalent command
/// for each step. Prints the page URL (with its access token) as the first
/// line of standard output and serves until interrupted (Ctrl-C).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline view fairline-demo/dented-panel.obj\n  fairline view fairline-demo/dented-roof.obj fairline-demo/dented-roof-faired.obj --no-open\n  fairline view fairline-demo/bspline-panel-dented.json --port 8765 --save-dir out\n  fairline view --session out/panel-session.json"
)]
pub struct Args {
    /// Mesh or surface to open.
    #[arg(required_unless_present = "session")]
    pub file: Option<PathBuf>,
    /// A second mesh or surface shown beside the first.
    pub file2: Option<PathBuf>,
    /// Port on 127.0.0.1 (default: a free one).
    #[arg(long)]
    pub port: Option<u16>,
    /// Do not open the browser; only print the URL.
    #[arg(long)]
    pub no_open: bool,
    /// Folder where the page may save files (default: the current folder).
    #[arg(long, value_name = "DIR")]
    pub save_dir: Option<PathBuf>,
    /// Grid points per direction and patch when tessellating surfaces.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub grid: usize,
    /// A session file saved from the page (its files, view, lights, marks
    /// and history positions) to open instead of FILE.
    #[arg(long, value_name = "SESSION.json", conflicts_with_all = ["file", "file2"])]
    pub session: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let save_dir = match &args.save_dir {
        Some(d) => d.clone(),
        None => std::env::current_dir().context("the current folder")?,
    };
    if !save_dir.is_dir() {
        return Err(bad_input(format!(
            "--save-dir {}: not a folder",
            save_dir.display()
        )));
    }
    if !(2..=1024).contains(&args.grid) {
        return Err(bad_input("--grid must be between 2 and 1024"));
    }
    // the files must be readable before the URL is printed; they are read
    // after it, so that the browser starts while a large mesh loads (its
    // requests wait in the listen queue until the server answers)
    let session = match &args.session {
        Some(p) => Some(session::read(p)?),
        None => None,
    };
    let session_dir = args
        .session
        .as_ref()
        .and_then(|p| p.parent().map(std::path::Path::to_path_buf))
        .unwrap_or_default();
    let files: Vec<PathBuf> = match &session {
        Some(s) => s
            .files
            .iter()
            .map(|f| session::resolve(&session_dir, f))
            .collect(),
        None => args
            .file
            .iter()
            .chain(args.file2.as_ref())
            .cloned()
            .collect(),
    };
    let grid = session.as_ref().and_then(|s| s.grid).unwrap_or(args.grid);
    if !(2..=1024).contains(&grid) {
        return Err(bad_input("--grid must be between 2 and 1024"));
    }
    for f in &files {
        fairline::io::require_regular_file(f)
            .and_then(|()| std::fs::File::open(f))
            .map_err(|e| bad_input(format!("{}: {e}", f.display())))?;
    }
    let token = auth::new_token()?;
    let listener = std::net::TcpListener::bind(("127.0.0.1", args.port.unwrap_or(0)))
        .with_context(|| format!("cannot listen on 127.0.0.1:{}", args.port.unwrap_or(0)))?;
    let port = listener.local_addr()?.port();
    let url = format!("http://127.0.0.1:{port}/?token={token}");
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{url}")?;
        out.flush()?;
    }
    if !args.no_open {
        open_browser(&url);
    }
    // serve at once: the page and its modules load (and WebGL starts) while
    // the files are read; API calls wait until they are
    let shared = Arc::new(api::Shared::new(
        save_dir.clone(),
        auth::Guard::new(token, port),
    ));
    let state = Arc::clone(&shared);
    let service: Arc<dyn http::Service> = Arc::new(api::Api(state));
    let server = std::thread::spawn(move || http::serve(listener, service));
    let mut docs = Vec::new();
    for f in &files {
        docs.push(doc::Doc::open(f, grid)?);
    }
    if let Some(s) = &session {
        for (d, entry) in docs.iter_mut().zip(&s.documents) {
            if let Some(w) = session::restore(d, entry, &session_dir) {
                eprintln!("warning: {w}");
            }
        }
    }
    let names: Vec<String> = docs.iter().map(|d| d.name.clone()).collect();
    let load_s: f64 = docs.iter().filter_map(|d| d.load_s["total"].as_f64()).sum();
    shared.set_docs(docs, session.map(|s| s.view));
    eprintln!(
        "fairline view: serving {} on 127.0.0.1:{port} (read in {load_s:.2} s; saves go to {}); Ctrl-C to stop",
        names.join(" and "),
        save_dir.display()
    );
    server
        .join()
        .map_err(|_| anyhow::anyhow!("the HTTP server stopped"))?;
    Ok(())
}

/// Opens `url` in the browser without putting its token on a command line
/// (where `ps` would show it to every local user): the opener (xdg-open,
/// `open` on macOS) gets the path of a small page, readable by the owner
/// only (0600), that redirects to `url`; the page is removed after
/// [`REDIRECT_LIFETIME`]. Failure is a warning.
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    let page = match redirect_page(url) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("warning: could not open a browser ({e}); open the URL above by hand");
            return;
        }
    };
    match std::process::Command::new(opener)
        .arg(&page)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
    {
        Ok(_) => {
            std::thread::spawn(move || {
                std::thread::sleep(REDIRECT_LIFETIME);
                let _ = std::fs::remove_file(&page);
            });
        }
        Err(e) => {
            let _ = std::fs::remove_file(&page);
            eprintln!(
                "warning: could not open a browser ({opener}: {e}); open the URL above by hand"
            )
        }
    }
}

/// How long the redirect page of [`open_browser`] stays on disk.
const REDIRECT_LIFETIME: std::time::Duration = std::time::Duration::from_secs(60);

/// Writes the redirect page to `url` as a new file, mode 0600, in the
/// temporary folder; its path.
fn redirect_page(url: &str) -> std::io::Result<PathBuf> {
    let mut bytes = [0u8; 8];
    getrandom::fill(&mut bytes).map_err(|e| std::io::Error::other(e.to_string()))?;
    let tag: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    let path =
        std::env::temp_dir().join(format!("fairline-view-{}-{tag}.html", std::process::id()));
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.mode(0o600);
    }
    let mut f = options.open(&path)?;
    // the URL is ours (host, port, hex token): nothing to escape
    writeln!(
        f,
        "<!doctype html><meta charset=\"utf-8\"><meta http-equiv=\"refresh\" content=\"0;url={url}\"><title>fairline view</title><a href=\"{url}\">Open the fairline workbench</a>"
    )?;
    f.sync_all()?;
    Ok(path)
}
