//! Defect detection and regions: detected defects, a region grown from the
//! faces picked, and regions read from a file.

use std::sync::Arc;
use std::time::Instant;

use fairline::fair::grow_region;
use fairline::highlight::LightArray;
use fairline::io::RegionSpec;
use fairline::mesh::{FaceId, VertexId};
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::detect::{DetectInput, DetectSettings, run_with_model as run_detect};
use fairline_commands::{FrontEnd, Lights};
use serde::Deserialize;
use serde_json::{Value, json};

use super::lines::push_lines;
use super::{Answer, Shared, bad, binary, cached_model, json_answer, lock, parse};
use crate::view::frame::frame;

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
pub(super) fn detect(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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

pub(super) fn to_faces(mesh: &SurfaceMesh, faces: &[u32]) -> Vec<FaceId> {
    let mut f: Vec<FaceId> = faces
        .iter()
        .filter(|&&t| (t as usize) < mesh.face_count())
        .map(|&t| FaceId(t))
        .collect();
    f.sort_unstable();
    f.dedup();
    f
}

pub(super) fn region(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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
pub(super) fn inside_vertices(mesh: &SurfaceMesh, faces: &[FaceId]) -> Vec<bool> {
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

pub(super) fn region_file(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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
