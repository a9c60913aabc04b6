//! The documents' state as the page reads it, per-vertex scalars, the step
//! cursor, and the current or a past step's mesh downloaded or saved.

use fairline::geom::{CurvatureMethod, principal_curvatures};
use fairline::highlight::{HighlightOptions, LightArray};
use serde::Deserialize;
use serde_json::{Value, json};

use super::{Answer, Shared, State, bad, binary, error, json_answer, lock, parse};
use crate::view::auth::query_param;
use crate::view::doc::{Doc, shell_word};
use crate::view::frame::frame;

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

pub(super) fn session(st: &State) -> Value {
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

pub(super) fn job_json(st: &State) -> Value {
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

pub(super) fn scalar(shared: &Shared, k: usize, name: &str, step: Option<usize>) -> Answer {
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

pub(super) fn move_cursor(shared: &Shared, k: usize, by: i64) -> Answer {
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
pub(in crate::view) fn step_bytes(d: &Doc, n: usize, ext: &str) -> Result<Vec<u8>, String> {
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
        crate::view::auth::new_token().map_err(|e| e.to_string())?
    );
    let path = dir.join(name);
    let r = fairline::io::write_mesh(&path, &mesh)
        .map_err(|e| e.to_string())
        .and_then(|_| std::fs::read(&path).map_err(|e| e.to_string()));
    let _ = std::fs::remove_file(&path);
    r
}

pub(super) fn download(shared: &Shared, k: usize, url: &str) -> Answer {
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

pub(super) fn save(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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
