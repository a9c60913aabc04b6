//! The evaluation tools of the workbench: deviation between states or
//! documents, and the point probe. Computations are the library's and the
//! command layer's; this file parses requests and shapes answers.
//!
//! - `POST /api/doc/K/deviation` `{"against": "original" | "previous" |
//!   {"doc": J}, "faces"?: [..], "show"?: "signed" | "broad" | "local"}`:
//!   the signed deviation (or its broad or local part) of document K's
//!   current state from its opening state, from the step before the
//!   current one, or from document J's current state
//!   ([`fairline_commands::deviation`]). Binary frame: the header holds
//!   the report (`method`, `units`, `all`, and with `faces`
//!   `inside_region` / `outside_region`: the statistics inside the marked
//!   triangles' vertices and outside them; `broad`, `local` and
//!   `broad_wavelength`: the parts split by wavelength), `range` (`lo`,
//!   `hi`: the colour range ±max |d| of the part shown, centred on 0),
//!   `summary` and `command`; then one f32 per vertex of document K: the
//!   part shown.
//! - `POST /api/doc/K/probe` `{"face": f, "point"?: [x,y,z], "light"?}` (point
//!   relative to the document's `center`, default the triangle's
//!   centroid): the point of triangle `f` closest to `point`, the
//!   interpolated unit normal, the principal curvatures `k1 ≥ k2`
//!   (Rusinkiewicz's estimate at the vertices, interpolated
//!   barycentrically), their radii (`null` where |k| < 1e-12: flat),
//!   `mean` and `gauss`. Positions in the answer are absolute. With
//!   `"light"` (a linear light array) also `highlight`: the highlight
//!   distance d of Yong et al. Eq. (1) at the vertices (their area-weighted
//!   normals, Eq. (3), as the lines are drawn), interpolated as the
//!   lines are drawn (`distance`), the light `spacing` and `light` = d / s
//!   (an integer on a highlight line, between two lights elsewhere);
//!   `null` where a corner's normal is nearly parallel to the light plane.

use super::api::{Answer, Shared, bad, binary, error, json_answer, lock, parse};
use super::doc::{Doc, shell_word};
use super::frame::frame;
use fairline::geom::{
    CurvatureMethod, PrincipalCurvatures, closest_point_on_triangle, principal_curvatures,
};
use fairline::mesh::FaceId;
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::deviation::{self, DeviationSettings};
use serde::Deserialize;
use serde_json::{Value, json};
use std::sync::{Arc, Mutex};

#[derive(Deserialize)]
#[serde(untagged)]
enum Against {
    Named(String),
    Doc { doc: usize },
}

#[derive(Deserialize)]
struct DeviationRequest {
    against: Against,
    #[serde(default)]
    faces: Option<Vec<u32>>,
    #[serde(default)]
    show: Option<String>,
}

/// `POST /api/doc/K/deviation` (module documentation).
pub fn deviation(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: DeviationRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let show = req.show.as_deref().unwrap_or("signed");
    if !matches!(show, "signed" | "broad" | "local") {
        return bad(format!(
            "show: `{show}`; give \"signed\", \"broad\" or \"local\""
        ));
    }
    // a surface reference is measured against exactly (its surfaces, the
    // start grid its document's), as the command does
    let (reference, surfaces, measured, measured_surfaces, command) = {
        let st = lock(shared);
        let docs = &st.docs;
        let d = &docs[k];
        let (owner, step) = match &req.against {
            Against::Named(n) if n == "original" => (d, Some(0)),
            Against::Named(n) if n == "previous" => (d, Some(d.cursor.saturating_sub(1))),
            Against::Named(n) => {
                return bad(format!(
                    "against: `{n}`; give \"original\", \"previous\" or {{\"doc\": J}}"
                ));
            }
            Against::Doc { doc } => match docs.get(*doc) {
                Some(o) => (o, None),
                None => return error(404, format!("no document {doc}")),
            },
        };
        let ref_file = match step {
            Some(n) => file_at(owner, n),
            None => owner.current_file(),
        };
        let surfaces = owner.step(step).surfaces.clone().map(|s| (s, owner.grid));
        let region = if req.faces.as_ref().is_some_and(|f| !f.is_empty()) {
            " --region region.json"
        } else {
            ""
        };
        let grid = if d.is_surface() {
            format!(" --grid {}", d.grid)
        } else {
            String::new()
        };
        let show_option = if show == "signed" {
            String::new()
        } else {
            format!(" --show {show}")
        };
        let command = format!(
            "fairline deviation {ref_file} {}{grid}{region}{show_option} --png deviation.png --report deviation.json",
            d.current_file()
        );
        (
            owner.shared_tri_at(step),
            surfaces,
            d.shared_tri_at(None),
            d.step(None).surfaces.clone(),
            command,
        )
    };
    let faces: Option<Vec<FaceId>> = req
        .faces
        .as_ref()
        .filter(|f| !f.is_empty())
        .map(|f| f.iter().map(|&i| FaceId(i)).collect());
    let settings = DeviationSettings::default();
    let out = match (&surfaces, &measured_surfaces) {
        // both states B-spline surfaces: the peak between the vertices too
        (Some((s, grid)), Some(m)) => deviation::run_between_surfaces(
            s,
            *grid,
            m,
            &measured,
            faces.as_deref(),
            &settings,
            &Control::new(),
        ),
        (Some((s, grid)), None) => deviation::run_on_surfaces(
            s,
            *grid,
            &measured,
            faces.as_deref(),
            &settings,
            &Control::new(),
        ),
        (None, _) => deviation::run(
            &reference,
            &measured,
            faces.as_deref(),
            &settings,
            &Control::new(),
        ),
    };
    let out = match out {
        Ok(o) => o,
        Err(e) => return bad(e.message(fairline_commands::FrontEnd::Workbench)),
    };
    let (values, stats) = match show {
        "broad" => (&out.split.broad, &out.broad),
        "local" => (&out.split.local, &out.local),
        _ => (&out.deviation.signed, &out.all),
    };
    // the whole range, as the histogram: a fairing moves few vertices,
    // and a percentile would saturate all of them
    let m = stats.max_abs.max(1e-12);
    let mut header = out.report.to_json();
    header["range"] = json!({"lo": -m, "hi": m});
    header["summary"] = json!(deviation::summary(&out));
    header["command"] = json!(command);
    let floats: Vec<f32> = values.iter().map(|&x| x as f32).collect();
    binary(frame(&header, &floats))
}

/// The file name of step `n` of `d` as the commands call it: the input
/// file for step 0, else the output name a command would give it.
fn file_at(d: &Doc, n: usize) -> String {
    if n == 0 {
        return shell_word(&d.path.display().to_string());
    }
    let stem = d
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let ext = if d.is_surface() {
        "json".to_string()
    } else {
        d.path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_else(|| "ply".into())
    };
    shell_word(&format!("{stem}-step{n}.{ext}"))
}

#[derive(Deserialize)]
struct ProbeRequest {
    face: u32,
    #[serde(default)]
    point: Option<[f64; 3]>,
    #[serde(default)]
    light: Option<fairline::highlight::LightArray>,
}

/// The principal curvatures of the last state probed: a probe is a click,
/// and clicks come in series on one state.
struct CurvatureCache {
    doc: usize,
    mesh: Arc<SurfaceMesh>,
    curvatures: Arc<PrincipalCurvatures>,
}

static CURVATURE_CACHE: Mutex<Option<CurvatureCache>> = Mutex::new(None);

fn curvatures_of(doc: usize, mesh: &Arc<SurfaceMesh>) -> Arc<PrincipalCurvatures> {
    let mut cache = CURVATURE_CACHE.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(c) = cache.as_ref()
        && c.doc == doc
        && Arc::ptr_eq(&c.mesh, mesh)
    {
        return Arc::clone(&c.curvatures);
    }
    let curvatures = Arc::new(principal_curvatures(mesh, CurvatureMethod::Rusinkiewicz));
    *cache = Some(CurvatureCache {
        doc,
        mesh: Arc::clone(mesh),
        curvatures: Arc::clone(&curvatures),
    });
    curvatures
}

/// `1/k`, or `None` for |k| < 1e-12 (flat in that direction).
fn radius(k: f64) -> Option<f64> {
    (k.abs() >= 1e-12 && k.is_finite()).then(|| 1.0 / k)
}

/// `POST /api/doc/K/probe` (module documentation).
pub fn probe(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    let req: ProbeRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let (mesh, center) = {
        let st = lock(shared);
        let d = &st.docs[k];
        (d.shared_tri_at(None), d.center)
    };
    if req.face as usize >= mesh.face_count() {
        return bad(format!(
            "face {} out of range (the mesh has {} triangles)",
            req.face,
            mesh.face_count()
        ));
    }
    let c = curvatures_of(k, &mesh);
    let t = mesh.triangle(FaceId(req.face));
    let p = t.map(|v| mesh.position(v));
    let target = match req.point {
        Some(q) if q.iter().all(|x| x.is_finite()) => Vec3::from(q) + center,
        Some(_) => return bad("point must be finite"),
        None => (p[0] + p[1] + p[2]) / 3.0,
    };
    let w = closest_point_on_triangle(target, p[0], p[1], p[2]);
    let at = w[0] * p[0] + w[1] * p[1] + w[2] * p[2];
    let lerp = |v: &[f64]| -> f64 {
        let x = w[0] * v[t[0].idx()] + w[1] * v[t[1].idx()] + w[2] * v[t[2].idx()];
        if x.is_finite() { x } else { 0.0 }
    };
    let n = (w[0] * c.normals[t[0].idx()]
        + w[1] * c.normals[t[1].idx()]
        + w[2] * c.normals[t[2].idx()])
    .normalize_or_zero();
    let (k1, k2) = (lerp(&c.k1), lerp(&c.k2));
    let (k1, k2) = (k1.max(k2), k1.min(k2));
    let mut answer: Value = json!({
        "face": req.face,
        "point": at.to_array(),
        "normal": n.to_array(),
        "k1": k1,
        "k2": k2,
        "r1": radius(k1),
        "r2": radius(k2),
        "mean": 0.5 * (k1 + k2),
        "gauss": k1 * k2,
        "method": "rusinkiewicz",
    });
    if let Some(light) = req.light {
        let min_cos = fairline::highlight::HighlightOptions::default().min_normal_cos;
        let d: Option<Vec<f64>> = t
            .iter()
            .map(|v| {
                let n = fairline::geom::vertex_normal(&mesh, *v);
                light.highlight_distance(mesh.position(*v), n, min_cos)
            })
            .collect();
        answer["highlight"] = match d {
            Some(d) => {
                let at = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
                json!({"distance": at, "spacing": light.spacing(), "light": at / light.spacing()})
            }
            None => Value::Null,
        };
    }
    json_answer(&answer)
}

#[derive(Deserialize)]
struct CurvesRequest {
    light: Option<fairline::highlight::LightArray>,
    circular: Option<fairline::highlight::CircularLights>,
    /// The history step (`None`: the current state).
    step: Option<usize>,
    /// The largest distance from a curve to its line (`None`: the
    /// command's default for a mesh).
    tolerance: Option<f64>,
}

/// `POST /api/doc/K/lines-curves` `{"light"|"circular", "step"?,
/// "tolerance"?}`: the highlight lines of the lights given, as cubic
/// B-spline curves in an IGES file (`fairline highlight FILE -o LINES.igs`,
/// the command layer's [`fairline_commands::curves`]): on a mesh the lines
/// of the drawn mesh, on a surface document the surfaces' exact lines
/// (every patch, the command's grid), in the file's length unit. Answers
/// `name` (the file name offered), `iges` (the file's text), `curves` (the
/// report's `curves` key) and `command`.
pub fn lines_curves(shared: &Shared, k: usize, body: &[u8]) -> Answer {
    use fairline_commands::curves;
    use fairline_commands::highlight::{self, HighlightLights, HighlightSettings};
    let req: CurvesRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    if let Some(t) = req.tolerance
        && !(t > 0.0 && t.is_finite())
    {
        return bad(format!("tolerance must be a positive number, got {t}"));
    }
    let (mesh, surfaces, unit, file, stem) = {
        let st = lock(shared);
        let d = &st.docs[k];
        let stem = d
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().replace(['"', '\\', '/'], "_"))
            .unwrap_or_else(|| "part".into());
        (
            d.shared_tri_at(req.step),
            d.step(req.step).surfaces.clone(),
            d.unit.clone(),
            d.current_file(),
            stem,
        )
    };
    let (lights, args) = match (req.light, req.circular) {
        (Some(l), _) => (
            HighlightLights::Linear(fairline_commands::Lights::exactly(&l)),
            super::api::light_args(&l),
        ),
        (None, Some(c)) => {
            let radii: Vec<String> = c.radii.iter().map(|r| r.to_string()).collect();
            let args = format!(
                "--circle-center {} --circle-axis {} --radii {}",
                super::api::vec_arg(Vec3::from(c.center)),
                super::api::vec_arg(Vec3::from(c.axis)),
                radii.join(",")
            );
            (
                HighlightLights::Circular {
                    spec: c,
                    from_lights: false,
                },
                args,
            )
        }
        (None, None) => return bad("give \"light\" or \"circular\""),
    };
    let fitted = match &surfaces {
        Some(surfaces) => {
            use fairline_commands::surface_highlight::{SurfaceHighlightSettings, run};
            // the command's defaults: every patch, its grid
            let settings = SurfaceHighlightSettings {
                lights,
                ..SurfaceHighlightSettings::default()
            };
            let out = match run(surfaces, &settings, &Control::new(), &|| {}) {
                Ok(o) => o,
                Err(e) => return bad(e.message(fairline_commands::FrontEnd::Workbench)),
            };
            let tol = curves::surface_tolerance(req.tolerance, surfaces);
            curves::fit(&curves::surface_lines(&out.results), tol)
        }
        None => {
            let settings = HighlightSettings { lights, band: None };
            let out = match highlight::run(&mesh, &settings, &Control::new()) {
                Ok(o) => o,
                Err(e) => return bad(e.to_string()),
            };
            let tol = curves::mesh_tolerance(req.tolerance, &mesh);
            curves::fit(&curves::mesh_lines(&out.lines), tol)
        }
    };
    let mut options = fairline::io::iges_write::IgesWriteOptions::default();
    if let Some(u) = unit.filter(|_| surfaces.is_some()) {
        options = options.unit(u);
    }
    let text = match fairline::io::iges_write::curves_to_iges(&fitted.curves, &options) {
        Ok(t) => t,
        Err(e) => return error(500, e),
    };
    let tolerance_arg = req
        .tolerance
        .map(|t| format!(" --curve-tolerance {t}"))
        .unwrap_or_default();
    let answer = json!({
        "name": format!("{stem}-lines.igs"),
        "iges": text,
        "curves": fitted.summary,
        "command": format!("fairline highlight {file} {args}{tolerance_arg} -o lines.igs"),
    });
    json_answer(&answer)
}
