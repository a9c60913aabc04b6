//! B-spline surfaces: `read_surfaces`, `write_surfaces`,
//! `surface_highlight_lines`, `surface_highlight_curves`,
//! `surface_iso_curves`, `fair_surface`.
//!
//! Surfaces cross into Python as the JSON of DESIGN.md §5 (fairline's
//! surface file format, numbers printed exactly), which the Python layer
//! turns into dictionaries; so reading, writing and every function keep the
//! library's one definition of that format.

#![allow(clippy::too_many_arguments)]

use crate::commands::{LightOptions, bad_choice, vec3};
use crate::{Failure, Res};
use fairline::bspline::BSplineSurface;
use fairline::highlight::CircularLights;
use fairline::io::{parse_surfaces_json, surfaces_to_json};
use fairline_commands::highlight::HighlightLights;
use fairline_commands::surface_highlight::SurfaceHighlightSettings;
use pyo3::prelude::*;
use std::path::PathBuf;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_surfaces, m)?)?;
    m.add_function(wrap_pyfunction!(write_surfaces, m)?)?;
    m.add_function(wrap_pyfunction!(surface_highlight_lines, m)?)?;
    m.add_function(wrap_pyfunction!(surface_highlight_curves, m)?)?;
    m.add_function(wrap_pyfunction!(surface_iso_curves, m)?)?;
    m.add_function(wrap_pyfunction!(fair_surface, m)?)?;
    Ok(())
}

/// All surfaces of a .json, .igs/.iges, .step/.stp or .g2 file (the CLI's
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
    if !fairline::io::surface_file::SurfaceFormat::from_path(&path)
        .is_some_and(fairline::io::surface_file::SurfaceFormat::is_writable)
    {
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

/// The settings of `surface_highlight_lines` and
/// `surface_highlight_curves` from the package's arguments: circular
/// lights given, from a circular `lights` dictionary or derived from the
/// whole part (`circular`), else linear lights, as the CLI chooses them.
fn surface_settings(
    circle_center: Option<[f64; 3]>,
    circle_axis: Option<[f64; 3]>,
    radii: Option<Vec<f64>>,
    band: Option<f64>,
    grid: usize,
    surface: Option<usize>,
    light: LightOptions,
    circular: bool,
) -> Res<SurfaceHighlightSettings> {
    if !(2..=4000).contains(&grid) {
        return Err(Failure::bad(format!(
            "grid must be between 2 and 4000, got {grid}"
        )));
    }
    if let Some(b) = band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(Failure::bad(format!(
            "band must be a positive number, got {b}"
        )));
    }
    let given = [
        circle_center.is_some(),
        circle_axis.is_some(),
        radii.is_some(),
    ];
    if given.iter().any(|&b| b) && !given.iter().all(|&b| b) {
        return Err(Failure::bad(
            "circular lights need circle_center, circle_axis and radii together",
        ));
    }
    let circle_center = vec3("circle_center", circle_center)?;
    let circle_axis = vec3("circle_axis", circle_axis)?;
    let lights = if let (Some(c), Some(t), Some(radii)) = (circle_center, circle_axis, radii) {
        HighlightLights::Circular {
            spec: CircularLights {
                center: c.to_array(),
                axis: t.to_array(),
                radii,
            },
            from_lights: false,
        }
    } else if let Some(spec) = light.circular()? {
        HighlightLights::Circular {
            spec,
            from_lights: true,
        }
    } else if circular {
        HighlightLights::DerivedCircular {
            up: light.up_vector(),
        }
    } else {
        HighlightLights::Linear(light.lights()?)
    };
    Ok(SurfaceHighlightSettings {
        lights,
        grid,
        band,
        surface,
    })
}

/// `fairline highlight SURFACES.json`: the command layer's
/// `surface_highlight`; the lines document and the report.
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
    let light = LightOptions::new(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
    )?;
    let settings = surface_settings(
        circle_center,
        circle_axis,
        radii,
        band,
        grid,
        surface,
        light,
        circular,
    )?;
    let all = parse(&surfaces, "surfaces")?;
    let out = crate::compute(py, move |control| -> Res<_> {
        if all.is_empty() {
            return Err(Failure::bad("surfaces: no B-spline surface given"));
        }
        let out = fairline_commands::surface_highlight::run(&all, &settings, control, &|| {})?;
        Ok((out.document.to_string(), out.report.to_json().to_string()))
    })?;
    Ok(out)
}

/// `fairline highlight SURFACES.json -o LINES.igs`: the surfaces' exact
/// lines (level 0) fitted as cubic B-spline curves within `tolerance`
/// (the command's default when `None`), written to `path` as IGES in
/// `unit` when given; the curves ([`crate::curves::list`]) and the report
/// with its `curves` key.
#[pyfunction]
#[pyo3(signature = (surfaces, tolerance = None, path = None, unit = None, circle_center = None,
    circle_axis = None, radii = None, grid = 200, surface = None, direction = None,
    plane_normal = None, up = "auto", plane_point = None, spacing = None, lights = None,
    min_normal_cos = None, circular = false))]
fn surface_highlight_curves<'py>(
    py: Python<'py>,
    surfaces: String,
    tolerance: Option<f64>,
    path: Option<PathBuf>,
    unit: Option<String>,
    circle_center: Option<[f64; 3]>,
    circle_axis: Option<[f64; 3]>,
    radii: Option<Vec<f64>>,
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
) -> PyResult<(Bound<'py, pyo3::types::PyList>, String)> {
    crate::curves::check(tolerance, path.as_deref())?;
    let unit = crate::curves::unit(unit.as_deref())?;
    let light = LightOptions::new(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
    )?;
    let settings = surface_settings(
        circle_center,
        circle_axis,
        radii,
        None,
        grid,
        surface,
        light,
        circular,
    )?;
    let all = parse(&surfaces, "surfaces")?;
    let (curves, report) = crate::compute(py, move |control| -> Res<_> {
        use fairline_commands::curves;
        if all.is_empty() {
            return Err(Failure::bad("surfaces: no B-spline surface given"));
        }
        let out = fairline_commands::surface_highlight::run(&all, &settings, control, &|| {})?;
        let tol = curves::surface_tolerance(tolerance, &all);
        crate::curves::fit_and_write(
            &curves::surface_lines(&out.results),
            tol,
            path.as_ref(),
            unit,
            out.report,
        )
    })?;
    Ok((crate::curves::list(py, &curves)?, report))
}

/// `fairline section SURFACES --iso N`: isoparametric curves with their
/// exact curvature combs as flat arrays — a dict of `points` (n, 3),
/// `params` (n,), `curvature` (n,), `comb` (n, 3), per curve `offsets`
/// (curves + 1,), `surface`, `kind` (0: u held, 1: v held, 2: an edge of a trimmed face) and `value` (the held
/// parameter, or the edge's trimming loop) —
/// and the report.
#[pyfunction]
#[pyo3(signature = (surfaces, count = 5, samples = 200, surface = None, comb_scale = 1.0))]
fn surface_iso_curves<'py>(
    py: Python<'py>,
    surfaces: String,
    count: usize,
    samples: usize,
    surface: Option<usize>,
    comb_scale: f64,
) -> PyResult<(Bound<'py, pyo3::types::PyDict>, String)> {
    use fairline_commands::section::{IsoSettings, iso};
    let settings = IsoSettings {
        count,
        samples,
        surface,
        comb_scale,
    };
    let all = parse(&surfaces, "surfaces")?;
    let (out, report) = crate::compute(py, move |control| -> Res<_> {
        if all.is_empty() {
            return Err(Failure::bad("surfaces: no B-spline surface given"));
        }
        let out = iso(&all, &settings, control)?;
        let report = out.report.to_json().to_string();
        Ok((out.curves, report))
    })?;
    let (mut points, mut params, mut curvature, mut comb) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut offsets, mut index, mut kind, mut value) =
        (vec![0i64], Vec::new(), Vec::new(), Vec::new());
    for (k, c) in &out {
        points.extend_from_slice(&c.curve.points);
        params.extend_from_slice(&c.params);
        curvature.extend_from_slice(&c.curve.curvature);
        comb.extend(c.curve.comb(comb_scale));
        offsets.push(points.len() as i64);
        index.push(*k as i64);
        kind.push(match c.kind_name() {
            "u" => 0i64,
            "v" => 1,
            _ => 2,
        });
        value.push(c.kind_value());
    }
    let d = pyo3::types::PyDict::new(py);
    d.set_item("points", crate::positions_array(py, &points))?;
    d.set_item("params", numpy::PyArray1::from_vec(py, params))?;
    d.set_item("curvature", numpy::PyArray1::from_vec(py, curvature))?;
    d.set_item("comb", crate::positions_array(py, &comb))?;
    d.set_item("offsets", numpy::PyArray1::from_vec(py, offsets))?;
    d.set_item("surface", numpy::PyArray1::from_vec(py, index))?;
    d.set_item("kind", numpy::PyArray1::from_vec(py, kind))?;
    d.set_item("value", numpy::PyArray1::from_vec(py, value))?;
    Ok((d, report))
}

/// `fairline fair-surface`: the command layer's `fair_surface`; all
/// surfaces with surface `surface` faired (JSON text) and the report.
/// `lights` and `endpoints` are the JSON texts of the CLI's files.
#[pyfunction]
#[pyo3(signature = (surfaces, lights, endpoints, surface = 0, max_iterations = None,
    epsilon = None, truncation = None, min_truncation = None, sample_spacing = None, grid = None,
    method = "regularised", boundary = "fixed", keep_weight = None, fairness_weight = None,
    damped_step = None, damping = "residual"))]
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
    damping: &str,
) -> PyResult<(String, String)> {
    use fairline::fair::{BoundaryControl, Endpoints, PaperDamping, SurfaceFairMethod};
    let names: Vec<&str> = PaperDamping::ALL.iter().map(|d| d.name()).collect();
    let damping =
        PaperDamping::from_name(damping).ok_or_else(|| bad_choice("damping", damping, &names))?;
    use fairline_commands::fair_surface::{FairSurfaceInput, FairSurfaceSettings, run};
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
    let all = parse(&surfaces, "surfaces")?;
    fairline_commands::fair_surface::check_surface(surface, all.len()).map_err(Failure::from)?;
    let spec: CircularLights =
        serde_json::from_str(&lights).map_err(|e| Failure::bad(format!("lights: {e}")))?;
    let ends: Endpoints =
        serde_json::from_str(&endpoints).map_err(|e| Failure::bad(format!("endpoints: {e}")))?;
    let d = FairSurfaceSettings::default();
    let settings = FairSurfaceSettings {
        surface,
        max_iterations: max_iterations.unwrap_or(d.max_iterations),
        epsilon: epsilon.unwrap_or(d.epsilon),
        truncation: truncation.unwrap_or(d.truncation),
        min_truncation: min_truncation.unwrap_or(d.min_truncation),
        damped_step: damped_step.unwrap_or(d.damped_step),
        damping,
        sample_spacing: sample_spacing.unwrap_or(d.sample_spacing),
        grid: grid.unwrap_or(d.grid),
        method,
        boundary,
        keep_weight: keep_weight.unwrap_or(d.keep_weight),
        fairness_weight: fairness_weight.unwrap_or(d.fairness_weight),
    };
    let out = crate::compute(py, move |control| -> Res<_> {
        let input = FairSurfaceInput {
            surfaces: &all,
            lights: Some(&spec),
            endpoints: &ends.endpoints,
        };
        let out = run(input, &settings, control)?;
        Ok((
            surfaces_to_json(&out.surfaces),
            out.report.to_json().to_string(),
        ))
    })?;
    Ok(out)
}
