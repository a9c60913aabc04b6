//! The shape tools of the workbench: plane sections with curvature combs
//! and the draft-angle map. The computations are the command layer's
//! ([`fairline_commands::section`], [`fairline_commands::draft`]); this
//! file parses requests and shapes answers.
//!
//! - `POST /api/doc/K/section` `{"point":[x,y,z], "normal":[x,y,z],
//!   "count"?: n, "spacing"?: s, "comb_scale"?: c}` (point relative to the
//!   document's `center`; defaults 1, 0, 1): the sections of the current
//!   state by `count` parallel planes `spacing` apart. Binary frame: the
//!   header lists `lines` (`start`, `count`, `closed`, `section`: the
//!   plane's index) into the points, `points` (their number),
//!   `max_curvature`, `report` (the command layer's `section` report),
//!   `summary` and `command`; the data are the points (minus `center`),
//!   then one comb vector −κ·m per point at scale 1 (the page scales them).
//! - `POST /api/doc/K/draft` `{"pull":[x,y,z], "min_angle"?: deg}`
//!   (default 3°): the draft angle of the current state against the pull
//!   direction. Binary frame: the header holds `report` (`below_share` …),
//!   `below` (the triangles with |draft| below the minimum), `range`
//!   (−90, 90), `summary` and `command`; then one f32 per vertex, the
//!   vertex draft angle in degrees.

use super::api::{Answer, Shared, bad, binary, lock, parse, vec_arg};
use super::frame::frame;
use fairline::{Control, Vec3};
use fairline_commands::FrontEnd;
use fairline_commands::draft::{self, DEFAULT_MIN_ANGLE, DraftSettings};
use fairline_commands::section::{self, SectionSettings, max_curvature};
use serde::Deserialize;
use serde_json::json;

fn one() -> usize {
    1
}

fn unit() -> f64 {
    1.0
}

fn default_min_angle() -> f64 {
    DEFAULT_MIN_ANGLE
}

#[derive(Deserialize)]
struct SectionRequest {
    point: [f64; 3],
    normal: [f64; 3],
    #[serde(default = "one")]
    count: usize,
    #[serde(default)]
    spacing: f64,
    #[serde(default = "unit")]
    comb_scale: f64,
}

/// `POST /api/doc/K/section` (module documentation).
pub fn section(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: SectionRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (mesh, center, file) = {
        let st = lock(shared);
        let d = &st.docs[k];
        (d.shared_tri_at(None), d.center, d.current_file())
    };
    let settings = SectionSettings {
        point: Vec3::from(req.point) + center,
        normal: Vec3::from(req.normal),
        count: req.count,
        spacing: req.spacing,
        comb_scale: req.comb_scale,
    };
    let out = match section::run(&mesh, &settings, &Control::new()) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let mut points: Vec<f32> = Vec::new();
    let mut combs: Vec<f32> = Vec::new();
    let mut lines = Vec::new();
    let mut kmax = 0.0f64;
    for (s, curves) in out.sections.iter().enumerate() {
        for c in curves {
            lines.push(json!({
                "start": points.len() / 3,
                "count": c.points.len(),
                "closed": c.closed,
                "section": s,
            }));
            for p in &c.points {
                let q = *p - center;
                points.extend([q.x as f32, q.y as f32, q.z as f32]);
            }
            for t in c.comb(1.0) {
                combs.extend([t.x as f32, t.y as f32, t.z as f32]);
            }
            kmax = kmax.max(max_curvature(c));
        }
    }
    let command = format!(
        "fairline section {file} --plane-point {} --plane-normal {} --count {} --spacing {} --comb-scale {} --obj sections.obj --report section.json",
        vec_arg(settings.point),
        vec_arg(settings.normal),
        settings.count,
        settings.spacing,
        settings.comb_scale
    );
    let mut summary = section::summary(&out, mesh.vertex_count());
    for w in out.report.messages(FrontEnd::Workbench) {
        summary.push_str(&format!("; warning: {w}"));
    }
    let header = json!({
        "lines": lines,
        "points": points.len() / 3,
        "max_curvature": kmax,
        "report": out.report.to_json(),
        "summary": summary,
        "command": command,
    });
    points.extend(combs);
    binary(frame(&header, &points))
}

#[derive(Deserialize)]
struct DraftRequest {
    pull: [f64; 3],
    #[serde(default = "default_min_angle")]
    min_angle: f64,
}

/// `POST /api/doc/K/draft` (module documentation).
pub fn draft(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: DraftRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (mesh, file) = {
        let st = lock(shared);
        let d = &st.docs[k];
        (d.shared_tri_at(None), d.current_file())
    };
    let settings = DraftSettings {
        pull: Vec3::from(req.pull),
        min_angle: req.min_angle,
    };
    let out = match draft::run(&mesh, &settings, &Control::new()) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let below: Vec<usize> = (0..out.below.len()).filter(|&f| out.below[f]).collect();
    let command = format!(
        "fairline draft {file} --pull {} --min-angle {} --png draft.png --report draft.json",
        vec_arg(settings.pull),
        settings.min_angle
    );
    let header = json!({
        "report": out.report.to_json(),
        "below": below,
        "range": {"lo": -90.0, "hi": 90.0},
        "summary": draft::summary(&out, settings.min_angle),
        "command": command,
    });
    let floats: Vec<f32> = out.angles.vertex_deg.iter().map(|&x| x as f32).collect();
    binary(frame(&header, &floats))
}
