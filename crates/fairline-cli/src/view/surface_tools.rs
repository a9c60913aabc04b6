//! The B-spline tools of the workbench: the continuity of the patch
//! boundaries drawn on the part, the control net and the curvature combs
//! of the isoparametric curves. The continuity is
//! the command layer's ([`fairline_commands::continuity`]); this file
//! parses requests and shapes answers. Both need a surface document.
//!
//! - `POST /api/doc/K/continuity` `{"tolerance"?, "angle_tolerance"?,
//!   "curvature_tolerance"?}` (the CLI's options; defaults the CLI's): the
//!   G0 / G1 / G2 class of every shared patch edge of the current state.
//!   Binary frame: the header is the command layer's report (`edges` with
//!   `surfaces`, `sides`, `class`, `g0_max`, `g1_max_deg`,
//!   `g2_max_relative`, `worst`, …, each with `start`, `count` into the
//!   points; `classes`, `tolerance`), plus `summary` and `command`; the data
//!   are the sample points along each edge (minus `center`).
//! - `GET /api/doc/K/control-net`: the control points of every patch of
//!   the current state. Binary frame: the header lists `patches`
//!   (`index`, `count_u`, `count_v`, `start`: the first point), `points`
//!   (their number) and `segments` (the number of control-net edges); the
//!   data are the points (minus `center`, row by row along v), then the
//!   net's edges as point pairs (rows along u and along v).
//! - `POST /api/doc/K/iso-combs` `{"count"?, "samples"?, "surface"?}`
//!   (defaults `fairline section --iso`'s: 5, 200, every patch): the
//!   isoparametric curves of the current state with their exact curvature
//!   (the command layer's [`fairline_commands::section::iso`]). Binary
//!   frame as the plane sections': the header lists `lines` (`start`,
//!   `count`, `closed`, `surface`, `kind`, `value`), `points`,
//!   `max_curvature`, `curvature_median` (the median curvature of the
//!   curved points, for a comb length that the sharp places of a part do
//!   not shrink), `report`, `summary` and `command`; the data are the
//!   points (minus `center`), then one comb vector −κ·m per point at scale
//!   1.

use super::api::{Answer, Shared, bad, binary, lock, parse};
use super::frame::frame;
use fairline::{Control, Vec3};
use fairline_commands::FrontEnd;
use fairline_commands::continuity::{self, ContinuitySettings};
use serde::Deserialize;
use serde_json::json;

#[derive(Deserialize, Default)]
struct ContinuityRequest {
    #[serde(default)]
    tolerance: Option<f64>,
    #[serde(default)]
    angle_tolerance: Option<f64>,
    #[serde(default)]
    curvature_tolerance: Option<f64>,
}

/// `POST /api/doc/K/continuity` (module documentation).
pub fn continuity(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: ContinuityRequest = if body.iter().all(|b| b.is_ascii_whitespace()) {
        ContinuityRequest::default()
    } else {
        match parse(body) {
            Ok(r) => r,
            Err(a) => return a,
        }
    };
    let (surfaces, center, file) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let Some(s) = d.current().surfaces.clone() else {
            return bad("continuity is for B-spline surfaces (open a .json, .igs or .step file)");
        };
        (s, d.center, d.current_file())
    };
    let mut settings = ContinuitySettings {
        tolerance: req.tolerance,
        ..Default::default()
    };
    if let Some(a) = req.angle_tolerance {
        settings.angle_tolerance = a;
    }
    if let Some(c) = req.curvature_tolerance {
        settings.curvature_tolerance = c;
    }
    let finite = [settings.angle_tolerance, settings.curvature_tolerance]
        .iter()
        .chain(settings.tolerance.as_ref())
        .all(|x| x.is_finite() && *x >= 0.0);
    if !finite {
        return bad("the tolerances must be finite and not negative");
    }
    let out = match continuity::run(&surfaces, &settings, &Control::new()) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let mut header = out.report.to_json();
    let mut floats: Vec<f32> = Vec::new();
    if let Some(edges) = header["edges"].as_array_mut() {
        for (e, seam) in edges.iter_mut().zip(&out.result.seams) {
            e["start"] = json!(floats.len() / 3);
            e["count"] = json!(seam.points.len());
            for p in &seam.points {
                let q = *p - center;
                floats.extend([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
    }
    let mut command = format!("fairline continuity {file}");
    if let Some(t) = settings.tolerance {
        command.push_str(&format!(" --tolerance {t}"));
    }
    command.push_str(&format!(
        " --angle-tolerance {} --curvature-tolerance {} --png continuity.png --report continuity.json",
        settings.angle_tolerance, settings.curvature_tolerance
    ));
    header["summary"] = json!(continuity::summary(&out, surfaces.len(), &settings));
    header["command"] = json!(command);
    binary(frame(&header, &floats))
}

/// `GET /api/doc/K/control-net` (module documentation).
pub fn control_net(shared: &Shared, k: usize) -> Answer {
    let (surfaces, center) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let Some(s) = d.current().surfaces.clone() else {
            return bad("the control net is for B-spline surfaces");
        };
        (s, d.center)
    };
    let push = |out: &mut Vec<f32>, p: Vec3| {
        let q = p - center;
        out.extend([q.x as f32, q.y as f32, q.z as f32]);
    };
    let (mut points, mut segments) = (Vec::new(), Vec::new());
    let mut patches = Vec::new();
    for (index, s) in surfaces.iter().enumerate() {
        let (nu, nv) = (s.count_u(), s.count_v());
        patches
            .push(json!({"index": index, "count_u": nu, "count_v": nv, "start": points.len() / 3}));
        for i in 0..nu {
            for j in 0..nv {
                push(&mut points, s.control_point(i, j));
                if j + 1 < nv {
                    push(&mut segments, s.control_point(i, j));
                    push(&mut segments, s.control_point(i, j + 1));
                }
                if i + 1 < nu {
                    push(&mut segments, s.control_point(i, j));
                    push(&mut segments, s.control_point(i + 1, j));
                }
            }
        }
    }
    let header = json!({
        "patches": patches,
        "points": points.len() / 3,
        "segments": segments.len() / 6,
    });
    points.extend(segments);
    binary(frame(&header, &points))
}

#[derive(Deserialize)]
struct IsoRequest {
    #[serde(default)]
    count: Option<usize>,
    #[serde(default)]
    samples: Option<usize>,
    #[serde(default)]
    surface: Option<usize>,
}

/// `POST /api/doc/K/iso-combs` (module documentation).
pub fn iso_combs(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    use fairline_commands::section::{self, IsoSettings, max_curvature};
    let req: IsoRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (surfaces, center, file) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let Some(s) = d.current().surfaces.clone() else {
            return bad("iso-curve combs are for B-spline surfaces");
        };
        (s, d.center, d.current_file())
    };
    let defaults = IsoSettings::default();
    let settings = IsoSettings {
        count: req.count.unwrap_or(defaults.count),
        samples: req.samples.unwrap_or(defaults.samples),
        surface: req.surface,
        comb_scale: 1.0,
    };
    let out = match section::iso(&surfaces, &settings, &Control::new()) {
        Ok(o) => o,
        Err(e) => return bad(e.message(FrontEnd::Workbench)),
    };
    let mut points: Vec<f32> = Vec::new();
    let mut combs: Vec<f32> = Vec::new();
    let mut lines = Vec::new();
    let mut kmax = 0.0f64;
    let mut all: Vec<f64> = Vec::new();
    for (surface, c) in &out.curves {
        lines.push(json!({
            "start": points.len() / 3,
            "count": c.curve.points.len(),
            "closed": false,
            "surface": surface,
            "kind": c.kind_name(),
            "value": c.kind_value(),
        }));
        for p in &c.curve.points {
            let q = *p - center;
            points.extend([q.x as f32, q.y as f32, q.z as f32]);
        }
        for t in c.curve.comb(1.0) {
            combs.extend([t.x as f32, t.y as f32, t.z as f32]);
        }
        kmax = kmax.max(max_curvature(&c.curve));
        all.extend_from_slice(&c.curve.curvature);
    }
    // the median of the curved points' curvature (straight rulings left out)
    all.retain(|&k| k > 0.0);
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(0.0);
    let mut command = format!(
        "fairline section {file} --iso {} --samples {}",
        settings.count, settings.samples
    );
    if let Some(s) = settings.surface {
        command.push_str(&format!(" --surface {s}"));
    }
    command.push_str(" --obj combs.obj --report combs.json");
    let mut summary = section::iso_summary(&out);
    for w in out.report.messages(FrontEnd::Workbench) {
        summary.push_str(&format!("; warning: {w}"));
    }
    let header = json!({
        "lines": lines,
        "points": points.len() / 3,
        "max_curvature": kmax,
        "curvature_median": median,
        "report": out.report.to_json(),
        "summary": summary,
        "command": command,
    });
    points.extend(combs);
    binary(frame(&header, &points))
}
