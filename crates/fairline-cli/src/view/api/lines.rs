//! Highlight lines: the lines and bands of a mesh under linear and circular
//! lights, the outlines of a step, and the highlight lines of B-spline surfaces.

use std::sync::Arc;
use std::time::Instant;

use fairline::highlight::{
    CircularLight, CircularLights, HighlightLines, HighlightOptions, LightArray,
    circular_highlight_bands, circular_highlight_lines,
};
use fairline::{Control, Vec3};
use fairline_commands::FrontEnd;
use serde::Deserialize;
use serde_json::{Value, json};

use super::{Answer, Shared, bad, binary, cached_model, light_args, lock, parse, vec_arg};
use crate::view::frame::frame;

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
pub(super) fn push_lines(
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

pub(super) fn lines(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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

/// Patch boundaries (one closed polyline per patch, from its tessellation
/// grid) and a label point per patch (its middle grid point).
pub(super) fn outlines(shared: &Shared, k: usize, step: Option<usize>) -> Answer {
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
pub(super) fn surface_lines(shared: &Shared, k: usize, body: &[u8]) -> Answer {
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
