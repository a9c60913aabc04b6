//! Mesh commands: `read_mesh`, `write_mesh`, `curvature`, `deviation`,
//! `section`, `draft`, `highlight_lines`,
//! `detect`, `fair`, `smooth`, `fair_quad`, `enhance`, `repair`.
//!
//! Each runs one command: `curvature`, `detect`, `fair`, `smooth`,
//! `fair_quad`, `enhance`, `repair` and `highlight_lines` through the
//! command layer (`fairline_commands`), as the CLI and the workbench do.
//! What the CLI does with files (reading the mesh, writing outputs,
//! pictures) is left out: arrays come in and go out.

#![allow(clippy::too_many_arguments)]

use crate::{Failure, Res, SoupArrays, mesh_from, positions_array, soup_arrays, soup_from};
use fairline::enhance::{EnhanceSolver, Projection};
use fairline::fair::FairMethod;
use fairline::geom::CurvatureMethod;
use fairline::highlight::{CircularLights, HighlightOptions, LightArray, UpAxis};
use fairline::io::RegionSpec;
use fairline::mesh::{FaceId, VertexId};
use fairline::smooth::SmoothMethod;
use fairline::{SurfaceMesh, Vec3};
use fairline_commands::curvature::CurvatureSettings;
use fairline_commands::detect::{DetectInput, DetectSettings};
use fairline_commands::enhance::EnhanceSettings;
use fairline_commands::fair::{FairInput, FairSettings};
use fairline_commands::fair_quad::{QuadMethod, QuadSettings};
use fairline_commands::highlight::{HighlightLights, HighlightSettings};
use fairline_commands::smooth::SmoothSettings;
use fairline_commands::{Choice, FrontEnd, Lights, Weights};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use serde_json::Value;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(curvature, m)?)?;
    m.add_function(wrap_pyfunction!(deviation, m)?)?;
    m.add_function(wrap_pyfunction!(surface_deviation, m)?)?;
    m.add_function(wrap_pyfunction!(section, m)?)?;
    m.add_function(wrap_pyfunction!(draft, m)?)?;
    m.add_function(wrap_pyfunction!(smooth, m)?)?;
    m.add_function(wrap_pyfunction!(fair_quad, m)?)?;
    m.add_function(wrap_pyfunction!(enhance, m)?)?;
    m.add_function(wrap_pyfunction!(repair, m)?)?;
    m.add_function(wrap_pyfunction!(highlight_lines, m)?)?;
    m.add_function(wrap_pyfunction!(detect, m)?)?;
    m.add_function(wrap_pyfunction!(fair, m)?)?;
    Ok(())
}

type V<'py> = PyReadonlyArray2<'py, f64>;
type Idx<'py> = PyReadonlyArray1<'py, u32>;

/// Reads a mesh file as positions and faces (no connectivity checks, so
/// dirty files can be read and repaired); errors name the file and line as
/// the CLI's do.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<SoupArrays<'py>> {
    let soup = crate::compute(py, move |_| {
        fairline::io::read_soup(&path).map_err(Failure::from)
    })?;
    Ok(soup_arrays(py, &soup))
}

/// Writes a mesh file atomically (format by extension).
#[pyfunction]
fn write_mesh(
    py: Python<'_>,
    path: std::path::PathBuf,
    v: V<'_>,
    indices: Idx<'_>,
    offsets: Idx<'_>,
) -> PyResult<()> {
    let soup = soup_from(&v, &indices, &offsets)?;
    crate::compute(py, move |_| {
        fairline::io::write_soup(&path, &soup).map_err(Failure::from)
    })?;
    Ok(())
}

/// Per-vertex curvature: (name, array) pairs — `normals`, `d1`, `d2` as
/// (n, 3), `k1`, `k2`, `mean`, `gauss` as (n,) — plus the report.
pub(crate) type CurvatureOut<'py> = (Vec<(&'static str, Bound<'py, PyAny>)>, String);

/// `fairline curvature` (crates/fairline-cli/src/curvature.rs): the
/// values of the columns the CLI writes to its PLY, one row per input
/// vertex.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, method = "rusinkiewicz"))]
fn curvature<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    method: &str,
) -> PyResult<CurvatureOut<'py>> {
    let settings = curvature_settings(method)?;
    let soup = soup_from(&v, &indices, &offsets)?;
    let out = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        run_curvature(&mesh, &settings, control)
    })?;
    Ok(curvature_arrays(py, &out))
}

/// The curvature settings of a method name.
pub(crate) fn curvature_settings(method: &str) -> Res<CurvatureSettings> {
    Ok(CurvatureSettings {
        method: CurvatureMethod::parse(method).map_err(Failure::from)?,
    })
}

/// What `curvature` computed, one row per input vertex, and the report.
pub(crate) struct CurvatureRows {
    output: fairline::geom::CurvatureOutput,
    rows: usize,
    report: String,
}

/// The command layer's `curvature` on a built mesh.
pub(crate) fn run_curvature(
    mesh: &SurfaceMesh,
    settings: &CurvatureSettings,
    control: &fairline::Control,
) -> Res<CurvatureRows> {
    let out = fairline_commands::curvature::run(mesh, settings, control)?;
    // one row per input vertex, as the CLI writes them (a split
    // non-manifold vertex takes the values of the fan that kept its index)
    let rows = mesh.original_vertex_count();
    let report = out.report.to_json().to_string();
    Ok(CurvatureRows {
        output: out.output,
        rows,
        report,
    })
}

/// The (name, array) pairs and the report of a curvature result.
pub(crate) fn curvature_arrays<'py>(py: Python<'py>, out: &CurvatureRows) -> CurvatureOut<'py> {
    let n = out.rows;
    let (c, mean, gauss) = (&out.output.fields, &out.output.mean, &out.output.gauss);
    let rows = |v: &[Vec3]| positions_array(py, &v[..n.min(v.len())]).into_any();
    let col = |v: &[f64]| PyArray1::from_slice(py, &v[..n.min(v.len())]).into_any();
    let values = vec![
        ("normals", rows(&c.normals)),
        ("k1", col(&c.k1)),
        ("k2", col(&c.k2)),
        ("mean", col(mean)),
        ("gauss", col(gauss)),
        ("d1", rows(&c.d1)),
        ("d2", rows(&c.d2)),
    ];
    (values, out.report.clone())
}

/// Per-vertex deviation: the signed and unsigned arrays (n,), the
/// in-region flags (n,) (all false without a region), the broad and local
/// parts (n,), and the report.
type DeviationOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    String,
);

/// A deviation's per-input-vertex values (signed, distance, in region,
/// broad, local) and the report's JSON text.
type DeviationValues = (Vec<f64>, Vec<f64>, Vec<bool>, Vec<f64>, Vec<f64>, String);

/// A deviation's signed and unsigned values, region flags and broad and
/// local parts, one per input vertex (`n`: the input's vertex count, as
/// the CLI's CSV), and the report's JSON text.
fn per_input_vertex(
    out: &fairline_commands::deviation::DeviationOutcome,
    n: usize,
) -> DeviationValues {
    let cut = |v: &[f64]| v[..n.min(v.len())].to_vec();
    let mut inside = out.in_region.clone();
    inside.resize(n, false);
    (
        cut(&out.deviation.signed),
        cut(&out.deviation.distance),
        inside,
        cut(&out.split.broad),
        cut(&out.split.local),
        out.report.to_json().to_string(),
    )
}

/// [`per_input_vertex`]'s values as numpy arrays.
fn deviation_out(py: Python<'_>, values: DeviationValues) -> DeviationOut<'_> {
    let (signed, distance, inside, broad, local, report) = values;
    (
        PyArray1::from_vec(py, signed),
        PyArray1::from_vec(py, distance),
        PyArray1::from_vec(py, inside),
        PyArray1::from_vec(py, broad),
        PyArray1::from_vec(py, local),
        report,
    )
}

/// `fairline deviation SURFACES MESH`: the exact signed distance of every
/// vertex of a mesh from B-spline surfaces (JSON text), through the
/// command layer's `run_on_surfaces`; `grid`: the start tessellation.
#[pyfunction]
#[pyo3(signature = (surfaces, v1, indices1, offsets1, grid = 64, region = None, bins = 41, broad_wavelength = None))]
fn surface_deviation<'py>(
    py: Python<'py>,
    surfaces: String,
    v1: V<'py>,
    indices1: Idx<'py>,
    offsets1: Idx<'py>,
    grid: usize,
    region: Option<Vec<u32>>,
    bins: usize,
    broad_wavelength: Option<f64>,
) -> PyResult<DeviationOut<'py>> {
    let reference = fairline::io::parse_surfaces_json(&surfaces)
        .map_err(|e| Failure::bad(format!("surfaces: {e}")))?;
    let after = soup_from(&v1, &indices1, &offsets1)?;
    let settings = fairline_commands::deviation::DeviationSettings {
        bins,
        broad_wavelength,
    };
    let values = crate::compute(py, move |control| -> Res<_> {
        if reference.is_empty() {
            return Err(Failure::bad("surfaces: no B-spline surface given"));
        }
        let after = mesh_from(&after)?;
        let faces: Option<Vec<FaceId>> = region.map(|r| r.into_iter().map(FaceId).collect());
        let out = fairline_commands::deviation::run_on_surfaces(
            &reference,
            grid,
            &after,
            faces.as_deref(),
            &settings,
            control,
        )?;
        Ok(per_input_vertex(&out, after.original_vertex_count()))
    })?;
    Ok(deviation_out(py, values))
}

/// `fairline deviation` (crates/fairline-cli/src/deviation.rs): the
/// signed deviation of the second mesh from the first, per vertex of the
/// second, through the command layer; `region`: faces of the second mesh.
#[pyfunction]
#[pyo3(signature = (v0, indices0, offsets0, v1, indices1, offsets1, region = None, bins = 41, broad_wavelength = None))]
fn deviation<'py>(
    py: Python<'py>,
    v0: V<'py>,
    indices0: Idx<'py>,
    offsets0: Idx<'py>,
    v1: V<'py>,
    indices1: Idx<'py>,
    offsets1: Idx<'py>,
    region: Option<Vec<u32>>,
    bins: usize,
    broad_wavelength: Option<f64>,
) -> PyResult<DeviationOut<'py>> {
    let before = soup_from(&v0, &indices0, &offsets0)?;
    let after = soup_from(&v1, &indices1, &offsets1)?;
    let settings = fairline_commands::deviation::DeviationSettings {
        bins,
        broad_wavelength,
    };
    let values = crate::compute(py, move |control| -> Res<_> {
        let before = mesh_from(&before)?;
        let after = mesh_from(&after)?;
        let faces: Option<Vec<FaceId>> = region.map(|r| r.into_iter().map(FaceId).collect());
        let out = fairline_commands::deviation::run(
            &before,
            &after,
            faces.as_deref(),
            &settings,
            control,
        )?;
        Ok(per_input_vertex(&out, after.original_vertex_count()))
    })?;
    Ok(deviation_out(py, values))
}

/// Plane sections as flat arrays: points (n, 3), curvature (n,), comb
/// vectors (n, 3) at the comb scale, curve offsets (curves + 1,) into the
/// points, closed flags and plane index per curve, and the report.
type SectionOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<u32>>,
    String,
);

/// `fairline section` (crates/fairline-cli/src/section.rs) through the
/// command layer: polygons are triangulated first.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, point, normal, count = 1, spacing = 0.0, comb_scale = 1.0))]
fn section<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    point: [f64; 3],
    normal: [f64; 3],
    count: usize,
    spacing: f64,
    comb_scale: f64,
) -> PyResult<SectionOut<'py>> {
    let soup = soup_from(&v, &indices, &offsets)?;
    let settings = fairline_commands::section::SectionSettings {
        point: Vec3::from(point),
        normal: Vec3::from(normal),
        count,
        spacing,
        comb_scale,
    };
    let (points, curvature, comb, starts, closed, plane, report) =
        crate::compute(py, move |control| -> Res<_> {
            let mesh = mesh_from(&soup)?;
            let mesh = if mesh.is_triangle_mesh() {
                mesh
            } else {
                fairline::mesh::triangulate(&mesh)
                    .map_err(|e| Failure::bad(e.to_string()))?
                    .mesh
            };
            let out = fairline_commands::section::run(&mesh, &settings, control)?;
            let (mut points, mut curvature, mut comb) = (Vec::new(), Vec::new(), Vec::new());
            let (mut starts, mut closed, mut plane) = (vec![0u32], Vec::new(), Vec::new());
            for (k, curves) in out.sections.iter().enumerate() {
                for c in curves {
                    points.extend_from_slice(&c.points);
                    curvature.extend_from_slice(&c.curvature);
                    comb.extend(c.comb(settings.comb_scale));
                    starts.push(points.len() as u32);
                    closed.push(c.closed);
                    plane.push(k as u32);
                }
            }
            Ok((
                points,
                curvature,
                comb,
                starts,
                closed,
                plane,
                out.report.to_json().to_string(),
            ))
        })?;
    Ok((
        positions_array(py, &points),
        PyArray1::from_vec(py, curvature),
        positions_array(py, &comb),
        PyArray1::from_vec(py, starts),
        PyArray1::from_vec(py, closed),
        PyArray1::from_vec(py, plane),
        report,
    ))
}

/// Draft angles: per input vertex (n,), per face of the mesh as given
/// (m,), the below-minimum flag per face (m,), and the report.
type DraftOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<bool>>,
    String,
);

/// `fairline draft` (crates/fairline-cli/src/draft.rs) through the
/// command layer.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, pull, min_angle = 3.0))]
fn draft<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    pull: [f64; 3],
    min_angle: f64,
) -> PyResult<DraftOut<'py>> {
    let soup = soup_from(&v, &indices, &offsets)?;
    let settings = fairline_commands::draft::DraftSettings {
        pull: Vec3::from(pull),
        min_angle,
    };
    let (vertex, face, below, report) = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        let out = fairline_commands::draft::run(&mesh, &settings, control)?;
        // one value per input vertex (a split non-manifold vertex keeps
        // the value of the fan that kept its index)
        let n = mesh.original_vertex_count();
        let mut vertex = out.angles.vertex_deg.clone();
        vertex.truncate(n);
        Ok((
            vertex,
            out.angles.face_deg.clone(),
            out.below.clone(),
            out.report.to_json().to_string(),
        ))
    })?;
    Ok((
        PyArray1::from_vec(py, vertex),
        PyArray1::from_vec(py, face),
        PyArray1::from_vec(py, below),
        report,
    ))
}

/// `option must be one of a, b; got x`.
pub(crate) fn bad_choice(option: &str, got: &str, allowed: &[&str]) -> Failure {
    Failure::bad(format!(
        "{option} must be one of {}; got {got:?}",
        allowed.join(", ")
    ))
}

/// Fixed vertices given as indices: each must be a vertex of `mesh` (the
/// check and message of the CLI's `--fixed` file, with `fixed[k]` for
/// `vertices[k]`).
fn fixed_vertices(fixed: &[i64], count: usize) -> Res<Vec<VertexId>> {
    fixed
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            if v < 0 || v as u64 >= count as u64 {
                Err(Failure::bad(format!(
                    "fixed[{k}] = {v} is not a vertex (the mesh has {count})"
                )))
            } else {
                Ok(VertexId(v as u32))
            }
        })
        .collect()
}

/// New positions and the report.
type PositionsOut<'py> = (Bound<'py, PyArray2<f64>>, String);

/// `fairline smooth`: the command layer's `smooth`.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, method = "taubin", weights = "uniform", exponent = -1.0,
    iterations = None, lambda_ = None, mu = None, pass_band = 0.1, time_step = 1.0, epsilon = None,
    max_work = None, fix_boundary = false, hierarchical_boundary = false, fixed = None,
    preserve_volume = false, tangential = false))]
fn smooth<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    method: &str,
    weights: &str,
    exponent: f64,
    iterations: Option<usize>,
    lambda_: Option<f64>,
    mu: Option<f64>,
    pass_band: f64,
    time_step: f64,
    epsilon: Option<f64>,
    max_work: Option<u64>,
    fix_boundary: bool,
    hierarchical_boundary: bool,
    fixed: Option<Vec<i64>>,
    preserve_volume: bool,
    tangential: bool,
) -> PyResult<(Bound<'py, PyArray2<f64>>, String, Option<String>)> {
    let settings = smooth_settings(
        method,
        weights,
        exponent,
        iterations,
        lambda_,
        mu,
        pass_band,
        time_step,
        epsilon,
        max_work,
        fix_boundary,
        hierarchical_boundary,
        preserve_volume,
        tangential,
    )?;
    let soup = soup_from(&v, &indices, &offsets)?;
    let (p, report, stopped) = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        run_smooth(&mesh, settings, fixed, control)
    })?;
    Ok((positions_array(py, &p), report, stopped))
}

/// The settings of `smooth` from the package's arguments (checked; fixed
/// vertices are set by [`run_smooth`], which knows the mesh).
pub(crate) fn smooth_settings(
    method: &str,
    weights: &str,
    exponent: f64,
    iterations: Option<usize>,
    lambda_: Option<f64>,
    mu: Option<f64>,
    pass_band: f64,
    time_step: f64,
    epsilon: Option<f64>,
    max_work: Option<u64>,
    fix_boundary: bool,
    hierarchical_boundary: bool,
    preserve_volume: bool,
    tangential: bool,
) -> Res<SmoothSettings> {
    let settings = SmoothSettings {
        method: SmoothMethod::parse(method).map_err(Failure::from)?,
        weights: Weights::parse(weights).map_err(Failure::from)?,
        exponent,
        iterations,
        lambda: lambda_,
        mu,
        pass_band,
        time_step,
        epsilon,
        max_work,
        fix_boundary,
        hierarchical_boundary,
        fixed: Vec::new(),
        preserve_volume,
        tangential,
    };
    settings.check().map_err(Failure::from)?;
    Ok(settings)
}

/// The command layer's `smooth` on a built mesh: the new positions (one
/// per input vertex), the report, and for a run that stopped unconverged
/// the sentence of the error the package raises
/// (FairlineNotConvergedError, with the result).
pub(crate) fn run_smooth(
    mesh: &SurfaceMesh,
    mut settings: SmoothSettings,
    fixed: Option<Vec<i64>>,
    control: &fairline::Control,
) -> Res<(Vec<Vec3>, String, Option<String>)> {
    settings.fixed = fixed_vertices(fixed.as_deref().unwrap_or(&[]), mesh.vertex_count())?;
    let out = fairline_commands::smooth::run(mesh, &settings, control)?;
    let stopped = out
        .stopped_error(FrontEnd::Python)
        .map(|e| e.message(FrontEnd::Python));
    Ok((
        mesh.original_values(&out.positions).to_vec(),
        out.report.to_json().to_string(),
        stopped,
    ))
}

/// The positions the CLI writes: the input's vertex list (split copies of
/// non-manifold vertices merged back; they are pinned, so bit-identical).
fn output_positions(mesh: &SurfaceMesh) -> Vec<Vec3> {
    mesh.original_values(mesh.positions()).to_vec()
}

/// `fairline fair-quad`: the command layer's `fair-quad`.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, weight = 0.01, deviation = 0.1, deviation_factor = 0.1,
    iterations = 3, fix_boundary = false, fixed = None, off_surface = false,
    method = "structure-lines", tolerance = 0.1, deviation_weights = false))]
#[allow(clippy::too_many_arguments)]
fn fair_quad<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    weight: f64,
    deviation: f64,
    deviation_factor: f64,
    iterations: usize,
    fix_boundary: bool,
    fixed: Option<Vec<i64>>,
    off_surface: bool,
    method: &str,
    tolerance: f64,
    deviation_weights: bool,
) -> PyResult<PositionsOut<'py>> {
    let method = QuadMethod::parse(method).map_err(Failure::from)?;
    let mut settings = QuadSettings {
        method,
        tolerance,
        weight,
        deviation,
        deviation_factor,
        iterations,
        fix_boundary,
        fixed: Vec::new(),
        off_surface,
        deviation_weights,
    };
    settings.check().map_err(Failure::from)?;
    let soup = soup_from(&v, &indices, &offsets)?;
    let (p, report) = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        settings.fixed = fixed_vertices(fixed.as_deref().unwrap_or(&[]), mesh.vertex_count())?;
        let out = fairline_commands::fair_quad::run(&mesh, &settings, control)?;
        Ok((
            mesh.original_values(&out.positions).to_vec(),
            out.report.to_json().to_string(),
        ))
    })?;
    Ok((positions_array(py, &p), report))
}

/// `fairline enhance`: the command layer's `enhance`.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, lambda_ = 1.0, mu = 0.5, iterations = 1,
    solver = "auto", fixed = None, projection = "smooth"))]
fn enhance<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    lambda_: f64,
    mu: f64,
    iterations: usize,
    solver: &str,
    fixed: Option<Vec<i64>>,
    projection: &str,
) -> PyResult<PositionsOut<'py>> {
    let projection = Projection::parse(projection).map_err(Failure::from)?;
    let solver = EnhanceSolver::parse(solver).map_err(Failure::from)?;
    let soup = soup_from(&v, &indices, &offsets)?;
    let (p, report) = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        let mut fixed_ids = Vec::new();
        for (k, &f) in fixed.as_deref().unwrap_or(&[]).iter().enumerate() {
            // the library names a vertex beyond the mesh; a negative or
            // too-large index cannot even be a vertex id
            if f < 0 || f > u32::MAX as i64 {
                return Err(Failure::bad(format!(
                    "fixed[{k}] = {f} is not a vertex (the mesh has {})",
                    mesh.vertex_count()
                )));
            }
            fixed_ids.push(VertexId(f as u32));
        }
        let settings = EnhanceSettings {
            lambda: lambda_,
            mu,
            iterations,
            solver,
            projection,
            fixed: fixed_ids,
        };
        let out = fairline_commands::enhance::run(&mesh, &settings, control)?;
        Ok((
            mesh.original_values(&out.positions).to_vec(),
            out.report.to_json().to_string(),
        ))
    })?;
    Ok((positions_array(py, &p), report))
}

/// `fairline repair` (crates/fairline-cli/src/repair.rs): the repaired
/// soup and the report.
#[pyfunction]
fn repair<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
) -> PyResult<(SoupArrays<'py>, String)> {
    let soup = soup_from(&v, &indices, &offsets)?;
    let (out, report) = crate::compute(py, move |control| -> Res<_> {
        let out = fairline_commands::repair::run(&soup, control)?;
        Ok((out.repaired.soup, out.report.to_json().to_string()))
    })?;
    Ok((soup_arrays(py, &out), report))
}

// ---- highlight lines -------------------------------------------------

/// The light options shared by `highlight_lines`, `detect` and `fair`
/// (the CLI's `LightArgs`, crates/fairline-cli/src/args.rs).
pub(crate) struct LightOptions {
    direction: Option<Vec3>,
    plane_normal: Option<Vec3>,
    up: UpAxis,
    plane_point: Option<Vec3>,
    spacing: Option<f64>,
    /// The `lights` dictionary as JSON text.
    lights: Option<Value>,
    min_normal_cos: Option<f64>,
}

pub(crate) fn vec3(name: &str, v: Option<[f64; 3]>) -> Res<Option<Vec3>> {
    match v {
        Some(a) if a.iter().any(|x| !x.is_finite()) => Err(Failure::bad(format!(
            "{name} must be three finite numbers, got {a:?}"
        ))),
        Some(a) => Ok(Some(Vec3::from_array(a))),
        None => Ok(None),
    }
}

impl LightOptions {
    pub(crate) fn new(
        direction: Option<[f64; 3]>,
        plane_normal: Option<[f64; 3]>,
        up: &str,
        plane_point: Option<[f64; 3]>,
        spacing: Option<f64>,
        lights: Option<String>,
        min_normal_cos: Option<f64>,
    ) -> Res<Self> {
        let up = UpAxis::parse(up)?;
        let lights = match lights {
            Some(text) => Some(
                serde_json::from_str::<Value>(&text)
                    .map_err(|e| Failure::bad(format!("lights: {e}")))?,
            ),
            None => None,
        };
        if lights.is_some()
            && (direction.is_some()
                || plane_normal.is_some()
                || plane_point.is_some()
                || spacing.is_some())
        {
            return Err(Failure::bad(
                "lights cannot be given together with direction, plane_normal, plane_point or spacing",
            ));
        }
        Ok(LightOptions {
            direction: vec3("direction", direction)?,
            plane_normal: vec3("plane_normal", plane_normal)?,
            up,
            plane_point: vec3("plane_point", plane_point)?,
            spacing,
            lights,
            min_normal_cos,
        })
    }

    /// The circular lights of the `lights` dictionary when it has the
    /// circular form (recognised by its "center" key).
    pub(crate) fn circular(&self) -> Res<Option<CircularLights>> {
        match &self.lights {
            Some(v) if v.get("center").is_some() => serde_json::from_value(v.clone())
                .map(Some)
                .map_err(|e| Failure::bad(format!("lights: {e}"))),
            _ => Ok(None),
        }
    }

    /// The lights as the command layer takes them, with `given` as the
    /// whole array.
    fn fields(&self, given: Option<LightArray>) -> Lights {
        Lights {
            direction: self.direction,
            plane_normal: self.plane_normal,
            up: self.up,
            plane_point: self.plane_point,
            spacing: self.spacing,
            given,
            min_normal_cos: self.min_normal_cos(),
        }
    }

    /// The `lights` dictionary as a linear light array, if given.
    fn given(&self) -> Res<Option<LightArray>> {
        match &self.lights {
            Some(v) => serde_json::from_value(v.clone())
                .map(Some)
                .map_err(|e| Failure::bad(format!("lights: {e}"))),
            None => Ok(None),
        }
    }

    /// The lights of a command that needs a linear light array (a circular
    /// `lights` dictionary is refused).
    pub(crate) fn lights(&self) -> Res<Lights> {
        if self
            .lights
            .as_ref()
            .is_some_and(|v| v.get("center").is_some())
        {
            return Err(Failure::bad(
                "lights: circular lights are drawn by `highlight_lines` only; this function needs a linear light array {\"plane_point\",\"plane_normal\",\"direction\",\"spacing\"}",
            ));
        }
        Ok(self.fields(self.given()?))
    }

    /// The `up` axis as a vector (`None` for auto).
    pub(crate) fn up_vector(&self) -> Option<Vec3> {
        self.up.vector()
    }

    /// `min_normal_cos`, or the library's default as the CLI's.
    pub(crate) fn min_normal_cos(&self) -> f64 {
        self.min_normal_cos
            .unwrap_or(HighlightOptions::default().min_normal_cos)
    }
}

/// The mesh, triangulated when it has polygons, and for each triangle the
/// input face it came from (the CLI's `read_triangles`).
fn triangles(soup: &fairline::Soup) -> Res<(SurfaceMesh, Option<Vec<FaceId>>)> {
    fairline_commands::require_faces(soup.face_count(), soup.vertex_count())?;
    let mesh = mesh_from(soup)?;
    if mesh.is_triangle_mesh() {
        Ok((mesh, None))
    } else {
        let t = triangulated(&mesh)?;
        Ok((t.mesh, Some(t.source_face)))
    }
}

/// The triangles of a polygon mesh (vertices unchanged).
pub(crate) fn triangulated(mesh: &SurfaceMesh) -> Res<fairline::mesh::Triangulation> {
    fairline::mesh::triangulate(mesh)
        .map_err(|e| Failure::bad(format!("triangulating its polygons: {e}")))
}

/// `fairline highlight` on a mesh: the command layer's `highlight`; the
/// lines document (as the CLI's JSON output) and the report.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, direction = None, plane_normal = None, up = "auto",
    plane_point = None, spacing = None, lights = None, min_normal_cos = None,
    circle_center = None, circle_axis = None, radii = None, band = None))]
fn highlight_lines(
    py: Python<'_>,
    v: V<'_>,
    indices: Idx<'_>,
    offsets: Idx<'_>,
    direction: Option<[f64; 3]>,
    plane_normal: Option<[f64; 3]>,
    up: &str,
    plane_point: Option<[f64; 3]>,
    spacing: Option<f64>,
    lights: Option<String>,
    min_normal_cos: Option<f64>,
    circle_center: Option<[f64; 3]>,
    circle_axis: Option<[f64; 3]>,
    radii: Option<Vec<f64>>,
    band: Option<f64>,
) -> PyResult<(String, String)> {
    let settings = highlight_settings(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
        circle_center,
        circle_axis,
        radii,
        band,
    )?;
    let soup = soup_from(&v, &indices, &offsets)?;
    let out = crate::compute(py, move |control| -> Res<_> {
        let (mesh, _) = triangles(&soup)?;
        let out = fairline_commands::highlight::run(&mesh, &settings, control)?;
        let document = fairline_commands::highlight::lines_document(&out);
        Ok((document.to_string(), out.report.to_json().to_string()))
    })?;
    Ok(out)
}

/// The settings of `highlight_lines` from the package's arguments: linear
/// lights, or circular ones given by `circle_center`/`circle_axis`/`radii`
/// or by a circular `lights` dictionary.
pub(crate) fn highlight_settings(
    direction: Option<[f64; 3]>,
    plane_normal: Option<[f64; 3]>,
    up: &str,
    plane_point: Option<[f64; 3]>,
    spacing: Option<f64>,
    lights: Option<String>,
    min_normal_cos: Option<f64>,
    circle_center: Option<[f64; 3]>,
    circle_axis: Option<[f64; 3]>,
    radii: Option<Vec<f64>>,
    band: Option<f64>,
) -> Res<HighlightSettings> {
    let light = LightOptions::new(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
    )?;
    let circle_given = [
        circle_center.is_some(),
        circle_axis.is_some(),
        radii.is_some(),
    ];
    if circle_given.iter().any(|&b| b) && !circle_given.iter().all(|&b| b) {
        return Err(Failure::bad(
            "circular lights need circle_center, circle_axis and radii together",
        ));
    }
    if circle_given[0] && light.lights.is_some() {
        return Err(Failure::bad(
            "circle_center cannot be given together with lights",
        ));
    }
    if let Some(r) = &radii
        && r.iter().any(|x| !x.is_finite())
    {
        return Err(Failure::bad("radii must be finite numbers"));
    }
    if let Some(b) = band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(Failure::bad(format!(
            "band must be a positive number, got {b}"
        )));
    }
    let circle_center = vec3("circle_center", circle_center)?;
    let circle_axis = vec3("circle_axis", circle_axis)?;
    let lights = match (circle_center, circle_axis, radii) {
        (Some(c), Some(t), Some(radii)) => HighlightLights::Circular {
            spec: CircularLights {
                center: c.to_array(),
                axis: t.to_array(),
                radii,
            },
            from_lights: false,
        },
        _ => match light.circular()? {
            Some(spec) => HighlightLights::Circular {
                spec,
                from_lights: true,
            },
            None => HighlightLights::Linear(light.lights()?),
        },
    };
    Ok(HighlightSettings { lights, band })
}

/// `fairline detect`: the command layer's `detect`; the region's faces
/// (as the CLI's `-o` JSON `faces`) and the report.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, direction = None, plane_normal = None, up = "auto",
    plane_point = None, spacing = None, lights = None, min_normal_cos = None,
    threshold = None, smooth_radius = None, region_margin = None, max_regions = None))]
fn detect<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    direction: Option<[f64; 3]>,
    plane_normal: Option<[f64; 3]>,
    up: &str,
    plane_point: Option<[f64; 3]>,
    spacing: Option<f64>,
    lights: Option<String>,
    min_normal_cos: Option<f64>,
    threshold: Option<f64>,
    smooth_radius: Option<f64>,
    region_margin: Option<f64>,
    max_regions: Option<usize>,
) -> PyResult<(Bound<'py, PyArray1<u32>>, String)> {
    let light = LightOptions::new(
        direction,
        plane_normal,
        up,
        plane_point,
        spacing,
        lights,
        min_normal_cos,
    )?;
    let d = DetectSettings::default();
    let settings = DetectSettings {
        lights: light.lights()?,
        threshold: threshold.unwrap_or(d.threshold),
        smooth_radius: smooth_radius.unwrap_or(d.smooth_radius),
        region_margin: region_margin.unwrap_or(d.region_margin),
        max_regions,
    };
    let soup = soup_from(&v, &indices, &offsets)?;
    let (faces, report) = crate::compute(py, move |control| -> Res<_> {
        let (mesh, source) = triangles(&soup)?;
        let input = DetectInput {
            mesh: &mesh,
            source: source.as_deref(),
            name: None,
        };
        let out = fairline_commands::detect::run(input, &settings, control)?;
        Ok((out.region, out.report.to_json().to_string()))
    })?;
    Ok((PyArray1::from_vec(py, faces), report))
}

/// `fairline fair`: the command layer's `fair`; new positions and the
/// report. `region` is region JSON text ({"faces"}, {"vertices"} or
/// {"sphere"}); `auto` detects the regions instead.
#[pyfunction]
#[pyo3(signature = (v, indices, offsets, region = None, auto = false, grow = 0,
    direction = None, plane_normal = None, up = "auto", plane_point = None, spacing = None,
    lights = None, min_normal_cos = None, max_iterations = None, epsilon = None,
    method = "highlight", fair_weight = None, diff_weight = None, laplacian_weight = None,
    least_change = true))]
fn fair<'py>(
    py: Python<'py>,
    v: V<'py>,
    indices: Idx<'py>,
    offsets: Idx<'py>,
    region: Option<String>,
    auto: bool,
    grow: usize,
    direction: Option<[f64; 3]>,
    plane_normal: Option<[f64; 3]>,
    up: &str,
    plane_point: Option<[f64; 3]>,
    spacing: Option<f64>,
    lights: Option<String>,
    min_normal_cos: Option<f64>,
    max_iterations: Option<usize>,
    epsilon: Option<f64>,
    method: &str,
    fair_weight: Option<f64>,
    diff_weight: Option<f64>,
    laplacian_weight: Option<f64>,
    least_change: bool,
) -> PyResult<PositionsOut<'py>> {
    let method = FairMethod::parse(method).map_err(Failure::from)?;
    match (&region, auto) {
        (Some(_), true) => {
            return Err(Failure::bad("region and auto=True cannot be given together").into());
        }
        (None, false) => {
            return Err(Failure::bad("give a region, or auto=True to detect the regions").into());
        }
        _ => {}
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
    let d = FairSettings::default();
    let settings = FairSettings {
        auto,
        grow,
        lights: light.lights()?,
        max_iterations: max_iterations.unwrap_or(d.max_iterations),
        epsilon: epsilon.unwrap_or(d.epsilon),
        method,
        fair_weight: fair_weight.unwrap_or(d.fair_weight),
        diff_weight: diff_weight.unwrap_or(d.diff_weight),
        laplacian_weight: laplacian_weight.unwrap_or(d.laplacian_weight),
        least_change,
    };
    let soup = soup_from(&v, &indices, &offsets)?;
    let out = crate::compute(py, move |control| -> Res<_> {
        let mesh = mesh_from(&soup)?;
        let faces = match &region {
            Some(text) => {
                let spec = RegionSpec::from_json(text)
                    .map_err(|e| Failure::bad(format!("region: {e}")))?;
                Some(
                    spec.faces(&mesh)
                        .map_err(|e| Failure::bad(format!("region: {e}")))?,
                )
            }
            None => None,
        };
        let input = FairInput {
            mesh: &mesh,
            region: faces.as_deref(),
            name: None,
        };
        let out = fairline_commands::fair::run(input, &settings, control)?;
        Ok((
            output_positions(&out.mesh),
            out.report.to_json().to_string(),
        ))
    })?;
    Ok((positions_array(py, &out.0), out.1))
}
