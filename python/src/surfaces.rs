//! B-spline surfaces: `read_surfaces`, `write_surfaces`,
//! `surface_highlight_lines`, `fair_surface`.
//!
//! Surfaces cross into Python as the JSON of DESIGN.md §5 (fairline's
//! surface file format, numbers printed exactly), which the Python layer
//! turns into dictionaries; so reading, writing and every function keep the
//! library's one definition of that format.

#![allow(clippy::too_many_arguments)]

use crate::commands::{LightOptions, bad_choice, highlight_error, vec3};
use crate::{Failure, Res};
use fairline::bspline::BSplineSurface;
use fairline::highlight::surface_highlight_lines_json;
use fairline::highlight::{
    CircularLight, CircularLights, PartLights, PatchHighlights, SurfaceHighlightOptions,
    part_highlight_lines,
};
use fairline::io::{parse_surfaces_json, surfaces_to_json};
use fairline_commands::{Report, Warning};
use pyo3::prelude::*;
use serde_json::json;
use std::path::PathBuf;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_surfaces, m)?)?;
    m.add_function(wrap_pyfunction!(write_surfaces, m)?)?;
    m.add_function(wrap_pyfunction!(surface_highlight_lines, m)?)?;
    m.add_function(wrap_pyfunction!(fair_surface, m)?)?;
    Ok(())
}

/// All surfaces of a .json, .igs/.iges or .step/.stp file (the CLI's
/// `surface::load_surfaces`, through `fairline::io::surface_file`), errors
/// naming the file.
fn load_surfaces(
    path: &std::path::Path,
    skip_unreadable: bool,
) -> Res<(Vec<BSplineSurface>, Vec<String>)> {
    let named = |msg: String| {
        let shown = path.display().to_string();
        if msg.contains(&shown) {
            msg
        } else {
            format!("{shown}: {msg}")
        }
    };
    let file = fairline::io::surface_file::read_surface_file(path)
        .map_err(|e| file_failure(&e, named(e.to_string())))?;
    let mut warnings = Vec::new();
    if let Some(summary) = file.unreadable_summary(UNREADABLE_NAMED, None) {
        if file.surfaces.is_empty() {
            return Err(Failure::bad(format!(
                "{}: no face could be read: {summary}",
                path.display()
            )));
        }
        if !skip_unreadable {
            return Err(Failure::bad(format!(
                "{}: {summary}; the part is incomplete (pass skip_unreadable=True to go on without them)",
                path.display()
            )));
        }
        warnings.push(format!(
            "{}: {summary} (left out: skip_unreadable=True)",
            path.display()
        ));
    }
    if file.surfaces.is_empty() {
        return Err(Failure::bad(format!(
            "{}: the file holds no B-spline surface",
            path.display()
        )));
    }
    warnings.extend(
        file.warnings
            .iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
    Ok((file.surfaces, warnings))
}

/// How many unreadable faces a message names (as the CLI's).
const UNREADABLE_NAMED: usize = 5;

/// A file that the operating system could not open is a `File` failure,
/// anything else about its content bad input.
fn file_failure(e: &(dyn std::error::Error + 'static), message: String) -> Failure {
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(c) = cause {
        if c.downcast_ref::<std::io::Error>().is_some() {
            return Failure {
                kind: crate::Kind::File,
                message,
            };
        }
        cause = c.source();
    }
    Failure::bad(message)
}

/// Surfaces from the JSON text the Python layer hands over.
fn parse(text: &str, what: &str) -> Res<Vec<BSplineSurface>> {
    parse_surfaces_json(text).map_err(|e| Failure::bad(format!("{what}: {e}")))
}

/// Reads a surface file; returns `{"surfaces":[...]}` JSON text.
#[pyfunction]
#[pyo3(signature = (path, skip_unreadable = false))]
fn read_surfaces(
    py: Python<'_>,
    path: PathBuf,
    skip_unreadable: bool,
) -> PyResult<(String, Vec<String>)> {
    let (surfaces, warnings) = crate::compute(py, move |_| load_surfaces(&path, skip_unreadable))?;
    Ok((surfaces_to_json(&surfaces), warnings))
}

/// Writes surfaces (JSON text) atomically, as .json, .igs/.iges or
/// .step/.stp by the extension (`fairline::io::surface_file`).
#[pyfunction]
fn write_surfaces(py: Python<'_>, path: PathBuf, surfaces: String) -> PyResult<()> {
    if fairline::io::surface_file::SurfaceFormat::from_path(&path).is_none() {
        return Err(Failure::bad(format!(
            "{}: surfaces are written as .json, .igs/.iges or .step/.stp",
            path.display()
        ))
        .into());
    }
    let surfaces = parse(&surfaces, "surfaces")?;
    crate::compute(py, move |_| {
        fairline::io::surface_file::write_surface_file(&path, &surfaces, None)
            .map_err(|e| file_failure(&e, e.to_string()))
    })?;
    Ok(())
}

/// `fairline highlight SURFACES.json` (crates/fairline-cli/src/
/// surface_highlight.rs): the lines document and the report.
#[pyfunction]
#[pyo3(signature = (surfaces, circle_center = None, circle_axis = None, radii = None, band = None,
    grid = 200, surface = None, direction = None, plane_normal = None, up = "auto",
    plane_point = None, spacing = None, lights = None, min_normal_cos = None, circular = false))]
fn surface_highlight_lines(
    py: Python<'_>,
    surfaces: String,
    circle_center: Option<[f64; 3]>,
    circle_axis: Option<[f64; 3]>,
    radii: Option<Vec<f64>>,
    band: Option<f64>,
    grid: usize,
    surface: Option<usize>,
    direction: Option<[f64; 3]>,
    plane_normal: Option<[f64; 3]>,
    up: &str,
    plane_point: Option<[f64; 3]>,
    spacing: Option<f64>,
    lights: Option<String>,
    min_normal_cos: Option<f64>,
    circular: bool,
) -> PyResult<(String, String)> {
    if !(2..=4000).contains(&grid) {
        return Err(Failure::bad(format!("grid must be between 2 and 4000, got {grid}")).into());
    }
    if let Some(b) = band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(Failure::bad(format!("band must be a positive number, got {b}")).into());
    }
    let given = [
        circle_center.is_some(),
        circle_axis.is_some(),
        radii.is_some(),
    ];
    if given.iter().any(|&b| b) && !given.iter().all(|&b| b) {
        return Err(Failure::bad(
            "circular lights need circle_center, circle_axis and radii together",
        )
        .into());
    }
    let light = LightOptions::new(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
    )?;
    let circle_center = vec3("circle_center", circle_center)?;
    let circle_axis = vec3("circle_axis", circle_axis)?;
    let all = parse(&surfaces, "surfaces")?;
    let out = crate::compute(py, move |_control| -> Res<_> {
        if all.is_empty() {
            return Err(Failure::bad("surfaces: no B-spline surface given"));
        }
        let all_surfaces = all.clone();
        let chosen: Vec<(usize, BSplineSurface)> = match surface {
            Some(k) => {
                let s = all.get(k).cloned().ok_or_else(|| {
                    Failure::bad(format!(
                        "surface {k} is out of range (the file holds {} surfaces)",
                        all.len()
                    ))
                })?;
                vec![(k, s)]
            }
            None => all.into_iter().enumerate().collect(),
        };
        let surfaces: Vec<BSplineSurface> = chosen.iter().map(|(_, s)| s.clone()).collect();
        let mut report = Report::new("highlight");
        report.set("surfaces", chosen.len());
        report.set("grid", grid);
        let opts = SurfaceHighlightOptions::default().grid(grid).band(band);
        // as the CLI: given, from a circular `lights` dictionary, or derived
        // from the whole part (`circular`)
        let spec = if let (Some(c), Some(t), Some(radii)) = (circle_center, circle_axis, radii) {
            Some((
                CircularLights {
                    center: c.to_array(),
                    axis: t.to_array(),
                    radii,
                },
                false,
            ))
        } else if let Some(spec) = light.circular()? {
            Some((spec, false))
        } else if circular {
            let spec = fairline::highlight::default_circular_lights(
                &all_surfaces,
                light.up_vector(),
                fairline::highlight::DEFAULT_CIRCULAR_RADII,
            )
            .ok_or_else(|| {
                Failure::bad(
                    "cannot derive circular lights: the part has no area with a defined normal",
                )
            })?;
            Some((spec, true))
        } else {
            None
        };
        let circular = if let Some((spec, derived)) = spec {
            let lights = spec.lights().map_err(highlight_error)?;
            if lights.is_empty() {
                return Err(Failure::bad("circular lights need at least one radius"));
            }
            let mut l = json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
            if derived {
                l["derived"] = json!(true);
            }
            report.set("light", l);
            Some(lights)
        } else {
            None
        };
        let array = match circular {
            Some(_) => None,
            None => {
                let a = light.part_light_array(&surfaces)?;
                report.set("light", json!({"kind": "linear", "array": a}));
                Some(a)
            }
        };
        let min_cos = light.min_normal_cos();
        let part_lights = match (circular, array) {
            (Some(c), _) => PartLights::Circular(c),
            (None, Some(array)) => PartLights::Linear {
                array,
                min_cos,
                max_lights: fairline::highlight::surface::DEFAULT_MAX_LIGHTS,
            },
            (None, None) => PartLights::Circular(Vec::new()),
        };
        let patches = report.time(|| part_highlight_lines(&surfaces, &part_lights, &opts, &|| {}));
        let results: Vec<(usize, &PatchHighlights)> = chosen
            .iter()
            .zip(&patches)
            .map(|((k, _), p)| (*k, p))
            .collect();
        // the CLI's lines document (`fairline::io::surface_highlight_lines_json`)
        let (doc, counts) = surface_highlight_lines_json(&results, band);
        let line_count = counts.lines;
        report.set("lines", counts.lines);
        report.set("closed_lines", counts.closed_lines);
        report.set("points", counts.points);
        if line_count == 0 {
            report.warn(Warning::Text("no highlight line pre-image was found on the surface; try other radii, --circle-center or --circle-axis".into()));
        }
        Ok((doc.to_string(), report.to_json().to_string()))
    })?;
    Ok(out)
}

/// `fairline fair-surface` (crates/fairline-cli/src/fair_surface.rs): all
/// surfaces with surface `surface` faired (JSON text) and the report.
/// `lights` and `endpoints` are the JSON texts of the CLI's files.
#[pyfunction]
#[pyo3(signature = (surfaces, lights, endpoints, surface = 0, max_iterations = None,
    epsilon = None, truncation = None, min_truncation = None, sample_spacing = None, grid = None,
    method = "regularised", boundary = "fixed", keep_weight = None, fairness_weight = None,
    damped_step = None))]
fn fair_surface(
    py: Python<'_>,
    surfaces: String,
    lights: String,
    endpoints: String,
    surface: usize,
    max_iterations: Option<usize>,
    epsilon: Option<f64>,
    truncation: Option<f64>,
    min_truncation: Option<f64>,
    sample_spacing: Option<f64>,
    grid: Option<usize>,
    method: &str,
    boundary: &str,
    keep_weight: Option<f64>,
    fairness_weight: Option<f64>,
    damped_step: Option<f64>,
) -> PyResult<(String, String)> {
    use fairline::fair::{
        BoundaryControl, Endpoints, SurfaceFairError, SurfaceFairMethod, SurfaceFairOptions,
        fair_surface as library_fair_surface,
    };
    let method = match method {
        "regularised" => SurfaceFairMethod::Regularised,
        "paper" => SurfaceFairMethod::Paper,
        other => return Err(bad_choice("method", other, &["regularised", "paper"]).into()),
    };
    let boundary = match boundary {
        "fixed" => BoundaryControl::Fixed,
        "tangent" => BoundaryControl::FixedWithTangents,
        "free" => BoundaryControl::Free,
        other => {
            return Err(bad_choice("boundary", other, &["fixed", "tangent", "free"]).into());
        }
    };
    let mut all = parse(&surfaces, "surfaces")?;
    if surface >= all.len() {
        return Err(Failure::bad(format!(
            "surface {surface} is out of range (the file holds {} surfaces)",
            all.len()
        ))
        .into());
    }
    let spec: CircularLights =
        serde_json::from_str(&lights).map_err(|e| Failure::bad(format!("lights: {e}")))?;
    let lights: Vec<CircularLight> = spec
        .lights()
        .map_err(|e| Failure::bad(format!("lights: {e}")))?;
    let ends: Endpoints =
        serde_json::from_str(&endpoints).map_err(|e| Failure::bad(format!("endpoints: {e}")))?;
    let d = SurfaceFairOptions::default();
    let truncation = truncation.unwrap_or(d.truncation);
    let min_truncation = min_truncation.unwrap_or(d.min_truncation);
    let opts = SurfaceFairOptions::default()
        .lights(lights)
        .endpoints(ends.endpoints)
        .grid(grid.unwrap_or(d.grid))
        .sample_spacing(sample_spacing.unwrap_or(d.sample_spacing))
        .truncation(truncation)
        // as the CLI: a larger floor is taken as `truncation`; NaN is left
        // for the library's option check to refuse
        .min_truncation(if min_truncation > truncation {
            truncation
        } else {
            min_truncation
        })
        .epsilon(epsilon.unwrap_or(d.epsilon))
        .max_iterations(max_iterations.unwrap_or(d.max_iterations))
        .method(method)
        .boundary(boundary)
        .keep_weight(keep_weight.unwrap_or(d.keep_weight))
        .fairness_weight(fairness_weight.unwrap_or(d.fairness_weight))
        .damped_step(damped_step.unwrap_or(d.damped_step));
    let out = crate::compute(py, move |control| -> Res<_> {
        let input = all[surface].clone();
        let mut report = Report::new("fair-surface");
        let opts = opts.control(control.clone());
        let out = report
            .time(|| library_fair_surface(&input, &opts))
            .map_err(|e| match e {
                SurfaceFairError::Svd | SurfaceFairError::Surface(_) => {
                    Failure::computation(e.to_string())
                }
                SurfaceFairError::NothingToMove(_) => {
                    Failure::bad(format!("{e} (boundary=\"free\")"))
                }
                other => Failure::bad(other.to_string()),
            })?;
        let (faired, rep) = (out.surfaces, out.report);
        // the library's report carries the command's keys (as the CLI)
        if let Ok(serde_json::Value::Object(fields)) = serde_json::to_value(&rep) {
            for (key, value) in fields {
                report.set(&key, value);
            }
        }
        all[surface] = faired;
        if let Some(w) = fairline_commands::fair_surface::not_converged_warning(&rep) {
            report.warn(Warning::Text(w));
        }
        if rep.residual_after.max > rep.residual_before.max {
            report.warn(Warning::Text(format!(
                "the largest highlight residual got worse: {:.4e} before, {:.4e} after",
                rep.residual_before.max, rep.residual_after.max
            )));
        }
        Ok((surfaces_to_json(&all), report.to_json().to_string()))
    })?;
    Ok(out)
}
