//! Session files of the workbench: which files are open, the page's view
//! (camera, lights, marks, active document) and each document's history
//! position, as JSON, saved from the page and opened with
//! `fairline view --session FILE`.
//!
//! - `POST /api/session-file` `{"name": "NAME.json", "view": {...}}`
//!   writes the session into the save folder (atomically; an existing
//!   session file of that name is replaced, an input file or a link
//!   never). Every step of every document after the opening one, the
//!   redo tail included, is written beside it as `STEM-docK-stepN.EXT`
//!   (the input's mesh format; surfaces as JSON) and named in the session,
//!   so a reopened session has the whole history — undo, redo, each step's
//!   label, command and report — at the saved position. Answers `path`,
//!   `states` (the state files written) and `command`.
//!
//! The format (`"fairline_session": 1`): `files` (absolute paths),
//! `grid`, `documents[k]` with `cursor`, `steps` (`label`, `command`,
//! `report` and `state` of each step: the state file relative to the
//! session file's folder, null for the opening step) and `state` (the
//! current step's file), and `view`: what the page restores (opaque to the
//! server: camera, controls, marks, and `tools`, the evaluation overlays
//! shown — sections with their picked point, the deviation or draft map,
//! iso combs — which the page computes again). A session whose steps name no state files (written by an
//! earlier fairline) reopens with two steps: as opened and `state`.

use super::api::{
    Answer, Shared, bad, error, json_answer, lock, parse, safe_file_name, step_bytes,
};
use super::doc::{Doc, Step, shell_word, tessellate_all};
use crate::error::bad_input;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The version of the session format written and read.
pub const FORMAT: u32 = 1;

/// A session file.
#[derive(Serialize, Deserialize, Debug, Clone)]
pub struct SessionFile {
    /// The format version ([`FORMAT`]).
    pub fairline_session: u32,
    /// The files opened (one or two).
    pub files: Vec<PathBuf>,
    /// The tessellation grid of surface documents.
    #[serde(default)]
    pub grid: Option<usize>,
    /// Per file: its history position.
    #[serde(default)]
    pub documents: Vec<SessionDoc>,
    /// What the page restores: camera, lights, marks, active document.
    #[serde(default)]
    pub view: Value,
}

/// The history position of one document.
#[derive(Serialize, Deserialize, Debug, Clone, Default)]
pub struct SessionDoc {
    /// The current step when the session was saved.
    pub cursor: usize,
    /// Label, command, report and state file of each step.
    #[serde(default)]
    pub steps: Vec<Value>,
    /// The current state's file (relative to the session file's folder),
    /// `None` at the opening step.
    #[serde(default)]
    pub state: Option<PathBuf>,
}

/// Reads a session file; errors are bad input naming the file.
pub fn read(path: &Path) -> Result<SessionFile> {
    let text =
        std::fs::read_to_string(path).map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
    let s: SessionFile = serde_json::from_str(&text)
        .map_err(|e| bad_input(format!("{}: not a fairline session: {e}", path.display())))?;
    if s.fairline_session != FORMAT {
        return Err(bad_input(format!(
            "{}: session format {} (this fairline reads format {FORMAT})",
            path.display(),
            s.fairline_session
        )));
    }
    if s.files.is_empty() || s.files.len() > 2 {
        return Err(bad_input(format!(
            "{}: a session names one or two files, not {}",
            path.display(),
            s.files.len()
        )));
    }
    Ok(s)
}

/// `path` as given, or relative to `base` when it is relative.
pub fn resolve(base: &Path, path: &Path) -> PathBuf {
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        base.join(path)
    }
}

/// Reads one saved state: the positions of `doc`'s drawn mesh and, for a
/// surface document, the surfaces.
fn load_state(
    doc: &Doc,
    path: &Path,
) -> Result<(
    Vec<fairline::Vec3>,
    Option<Vec<fairline::bspline::BSplineSurface>>,
)> {
    let (positions, surfaces) = if doc.is_surface() {
        let s = crate::surface::load_surfaces(path)?;
        let (mesh, _) = tessellate_all(&s, doc.grid)?;
        (mesh.positions().to_vec(), Some(s))
    } else {
        (fairline::io::read_mesh(path)?.positions().to_vec(), None)
    };
    if positions.len() != doc.tri.vertex_count() {
        anyhow::bail!(
            "{} vertices, but {} has {}",
            positions.len(),
            doc.name,
            doc.tri.vertex_count()
        );
    }
    Ok((positions, surfaces))
}

/// Rebuilds `doc`'s history from `entry` (state files relative to `base`)
/// and moves to the saved position. Returns a warning when a state cannot
/// be restored: the history then ends before it.
pub fn restore(doc: &mut Doc, entry: &SessionDoc, base: &Path) -> Option<String> {
    let per_step = entry.steps.len() > 1
        && entry.steps[1..]
            .iter()
            .all(|s| s["state"].as_str().is_some());
    // (state file, label, command, report) of each step after the opening
    let saved: Vec<(PathBuf, String, String, Value)> = if per_step {
        entry.steps[1..]
            .iter()
            .map(|s| {
                (
                    resolve(base, Path::new(s["state"].as_str().unwrap_or_default())),
                    s["label"].as_str().unwrap_or("step").to_string(),
                    s["command"].as_str().unwrap_or("").to_string(),
                    s["report"].clone(),
                )
            })
            .collect()
    } else {
        let state = entry.state.as_ref()?;
        let path = resolve(base, state);
        let last = entry.steps.last().cloned().unwrap_or(Value::Null);
        vec![(
            path.clone(),
            format!(
                "{} (restored, step {} of the session)",
                last["label"].as_str().unwrap_or("step"),
                entry.cursor
            ),
            last["command"].as_str().unwrap_or("").to_string(),
            json!({"command": "session", "state": path.display().to_string(), "history": entry.steps}),
        )]
    };
    let cursor = if per_step { entry.cursor } else { 1 };
    for (path, label, command, report) in saved {
        match load_state(doc, &path) {
            Ok((positions, surfaces)) => doc.push(Step::new(
                label,
                command,
                report,
                Arc::new(positions),
                surfaces.map(Arc::new),
            )),
            Err(e) => {
                let kept = doc.history.len();
                doc.set_cursor(cursor.min(kept - 1));
                return Some(format!(
                    "{}: the saved state was not restored ({e:#}); {} keeps {kept} of its steps",
                    path.display(),
                    doc.name
                ));
            }
        }
    }
    doc.set_cursor(cursor);
    None
}

#[derive(Deserialize)]
struct SaveRequest {
    name: String,
    #[serde(default)]
    view: Value,
}

/// The extension of a document's state file.
fn state_ext(d: &Doc) -> String {
    if d.is_surface() {
        return "json".into();
    }
    d.path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .filter(|e| matches!(e.as_str(), "obj" | "ply" | "off" | "stl"))
        .unwrap_or_else(|| "ply".into())
}

/// Writes `bytes` to `path` in the save folder: atomically, never over an
/// input file or through a link.
fn write_in_save_dir(docs: &[Doc], path: &Path, bytes: &[u8]) -> Result<(), Answer> {
    for input in docs.iter().map(|d| &d.path) {
        if let Err(e) = fairline::io::ensure_distinct(input, path) {
            return Err(bad(e));
        }
    }
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(bad(format!(
            "{} is a symbolic link; saves are not written through links",
            path.display()
        )));
    }
    fairline::io::atomic_write_here(path, |w| std::io::Write::write_all(w, bytes))
        .map_err(|e| error(500, e.to_string()))
}

/// `POST /api/session-file` (module documentation).
pub fn save(shared: &Shared, body: &[u8]) -> Answer {
    let req: SaveRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let name = match safe_file_name(&req.name) {
        Ok(n) if n.to_ascii_lowercase().ends_with(".json") => n,
        Ok(n) => return bad(format!("{n}: a session file name ends in .json")),
        Err(e) => return bad(e),
    };
    let st = lock(shared);
    let dir = st.save_dir().to_path_buf();
    let path = dir.join(name);
    let stem = name[..name.len() - 5].to_string();
    let mut documents = Vec::new();
    let mut states = Vec::new();
    for (k, d) in st.docs.iter().enumerate() {
        let ext = state_ext(d);
        let mut steps = Vec::new();
        for (n, step) in d.history.iter().enumerate() {
            let file = if n == 0 {
                None
            } else {
                let file = format!("{stem}-doc{k}-step{n}.{ext}");
                let bytes = match step_bytes(d, n, &ext) {
                    Ok(b) => b,
                    Err(e) => return bad(e),
                };
                if let Err(a) = write_in_save_dir(&st.docs, &dir.join(&file), &bytes) {
                    return a;
                }
                states.push(dir.join(&file).display().to_string());
                Some(file)
            };
            steps.push(json!({
                "label": step.label,
                "command": step.command,
                "report": step.report,
                "state": file,
            }));
        }
        let state = steps[d.cursor]["state"].as_str().map(PathBuf::from);
        documents.push(SessionDoc {
            cursor: d.cursor,
            steps,
            state,
        });
    }
    let files = st
        .docs
        .iter()
        .map(|d| std::fs::canonicalize(&d.path).unwrap_or_else(|_| d.path.clone()))
        .collect();
    let session = SessionFile {
        fairline_session: FORMAT,
        files,
        grid: st.docs.first().map(|d| d.grid),
        documents,
        view: req.view,
    };
    let text = match serde_json::to_string_pretty(&session) {
        Ok(t) => t + "\n",
        Err(e) => return error(500, e.to_string()),
    };
    if let Err(a) = write_in_save_dir(&st.docs, &path, text.as_bytes()) {
        return a;
    }
    json_answer(&json!({
        "path": path.display().to_string(),
        "states": states,
        "command": format!("fairline view --session {}", shell_word(&path.display().to_string())),
    }))
}
