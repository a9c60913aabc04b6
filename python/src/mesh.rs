//! `Mesh`: a mesh whose connectivity is built once (halfedges, split
//! non-manifold vertices, triangulation of polygons on first use) and kept
//! for every operator and command called on it. The methods compute what
//! the module functions of commands.rs compute from arrays, through the
//! same command-layer calls, so results are bit-identical; the pure-Python
//! class `fairline.Mesh` (python/fairline/__init__.py) subclasses it and turns
//! reports into dicts and matrices into scipy.sparse.

#![allow(clippy::too_many_arguments)]

use crate::commands::{
    CurvatureOut, curvature_arrays, curvature_settings, highlight_settings, run_curvature,
    run_smooth, smooth_settings, triangulated,
};
use crate::{Failure, Res, mesh_from, positions_array, soup_from};
use fairline::highlight::HighlightLines;
use fairline::mesh::VertexId;
use fairline::{SurfaceMesh, Vec3};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::{Arc, Mutex};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Mesh>()?;
    Ok(())
}

/// A mesh with its connectivity built once (see the module doc).
#[pyclass(subclass, frozen, module = "fairline._native")]
pub struct Mesh {
    mesh: Arc<SurfaceMesh>,
    /// The triangle mesh of a polygon mesh, made on first use (the mesh
    /// itself when it has triangles only).
    triangles: Arc<Mutex<Option<Arc<SurfaceMesh>>>>,
}

impl Mesh {
    /// The triangle mesh the highlight lines are drawn on.
    fn triangles(
        mesh: &Arc<SurfaceMesh>,
        cache: &Mutex<Option<Arc<SurfaceMesh>>>,
    ) -> Res<Arc<SurfaceMesh>> {
        if mesh.is_triangle_mesh() {
            return Ok(Arc::clone(mesh));
        }
        let mut slot = cache.lock().map_err(|_| {
            Failure::computation("the triangulation cache was poisoned by a failed run")
        })?;
        if let Some(t) = slot.as_ref() {
            return Ok(Arc::clone(t));
        }
        let t = Arc::new(triangulated(mesh)?.mesh);
        *slot = Some(Arc::clone(&t));
        Ok(t)
    }
}

/// Flat arrays of highlight lines: `points` (N, 3) of every line in turn,
/// `offsets` (L + 1,) so that line k is `points[offsets[k]:offsets[k+1]]`,
/// `index` (L,) the light index, `closed` (L,) and, for circular lights,
/// `radius` (L,).
fn line_arrays<'py>(
    py: Python<'py>,
    lines: &HighlightLines,
    radii: Option<&[f64]>,
) -> PyResult<Bound<'py, PyDict>> {
    let total: usize = lines.lines.iter().map(|l| l.points.len()).sum();
    let mut points: Vec<Vec3> = Vec::with_capacity(total);
    let mut offsets: Vec<i64> = Vec::with_capacity(lines.lines.len() + 1);
    let mut index = Vec::with_capacity(lines.lines.len());
    let mut closed = Vec::with_capacity(lines.lines.len());
    offsets.push(0);
    for l in &lines.lines {
        points.extend_from_slice(&l.points);
        offsets.push(points.len() as i64);
        index.push(l.index);
        closed.push(l.closed);
    }
    let d = PyDict::new(py);
    d.set_item("points", positions_array(py, &points))?;
    d.set_item("offsets", PyArray1::from_vec(py, offsets))?;
    d.set_item("index", PyArray1::from_vec(py, index))?;
    d.set_item("closed", PyArray1::from_vec(py, closed))?;
    if let Some(r) = radii {
        // a circular line's index is the position of its radius
        let radius: Option<Vec<f64>> = lines
            .lines
            .iter()
            .map(|l| {
                usize::try_from(l.index)
                    .ok()
                    .and_then(|k| r.get(k).copied())
            })
            .collect();
        if let Some(radius) = radius {
            d.set_item("radius", PyArray1::from_vec(py, radius))?;
        }
    }
    Ok(d)
}

/// A sparse matrix over the input's vertices, for scipy.sparse: either
/// compressed rows (`"csr"`, data, indices, indptr) or triplets (`"coo"`,
/// data, rows, cols) whose repeated entries are summed.
type SparseOut<'py> = (
    &'static str,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    usize,
);

#[pymethods]
impl Mesh {
    /// Builds the connectivity of (V, indices, offsets) with the GIL
    /// released; errors as the module functions name them.
    #[new]
    fn new(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        indices: PyReadonlyArray1<'_, u32>,
        offsets: PyReadonlyArray1<'_, u32>,
    ) -> PyResult<Self> {
        let soup = soup_from(&v, &indices, &offsets)?;
        let mesh = crate::compute(py, move |_| mesh_from(&soup))?;
        Ok(Mesh {
            mesh: Arc::new(mesh),
            triangles: Arc::new(Mutex::new(None)),
        })
    }

    /// Number of input vertices.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.mesh.original_vertex_count()
    }

    /// Number of faces.
    #[getter]
    fn face_count(&self) -> usize {
        self.mesh.face_count()
    }

    /// True when every face is a triangle.
    #[getter]
    fn is_triangle_mesh(&self) -> bool {
        self.mesh.is_triangle_mesh()
    }

    /// Area-weighted unit vertex normals (Yong et al. Eq. (3)), one row
    /// per input vertex; zero where no normal is defined.
    fn _vertex_normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let mesh = Arc::clone(&self.mesh);
        let n = crate::compute(py, move |_| {
            Ok(mesh
                .original_values(&fairline::geom::vertex_normals(&mesh))
                .to_vec())
        })?;
        Ok(positions_array(py, &n))
    }

    /// `curvature`'s (name, array) pairs and report.
    #[pyo3(signature = (method = "rusinkiewicz"))]
    fn _curvature<'py>(&self, py: Python<'py>, method: &str) -> PyResult<CurvatureOut<'py>> {
        let settings = curvature_settings(method)?;
        let mesh = Arc::clone(&self.mesh);
        let out = crate::compute(py, move |control| run_curvature(&mesh, &settings, control))?;
        Ok(curvature_arrays(py, &out))
    }

    /// The cotangent Laplacian (L_ij = ½ (cot α_ij + cot β_ij), L_ii = −Σ_j
    /// L_ij; Meyer et al. Eq. (8), libigl's `cotmatrix` convention) over
    /// the input's vertices; triangle meshes only.
    fn _cotangent_laplacian<'py>(&self, py: Python<'py>) -> PyResult<SparseOut<'py>> {
        if !self.mesh.is_triangle_mesh() {
            return Err(Failure::bad(
                "cotangent_laplacian needs a triangle mesh; this one has polygons (triangulate it first)",
            )
            .into());
        }
        let mesh = Arc::clone(&self.mesh);
        let (kind, data, a, b, n) = crate::compute(py, move |_| {
            let l = fairline::geom::cotangent_laplacian(&mesh);
            let n = mesh.original_vertex_count();
            let (col_ptr, row_idx) = (l.symbolic().col_ptr(), l.symbolic().row_idx());
            let values = l.val().to_vec();
            if mesh.vertex_count() == n {
                // symmetric: the compressed columns are the compressed rows
                let indices: Vec<i64> = row_idx.iter().map(|&r| r as i64).collect();
                let indptr: Vec<i64> = col_ptr.iter().map(|&c| c as i64).collect();
                return Ok(("csr", values, indices, indptr, n));
            }
            // split copies of non-manifold vertices are summed into the
            // input vertex they stand for
            let mut rows: Vec<i64> = Vec::with_capacity(values.len());
            let mut cols: Vec<i64> = Vec::with_capacity(values.len());
            for j in 0..mesh.vertex_count() {
                let cj = mesh.original_vertex(VertexId(j as u32)).idx() as i64;
                for &r in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                    rows.push(mesh.original_vertex(VertexId(r as u32)).idx() as i64);
                    cols.push(cj);
                }
            }
            Ok(("coo", values, rows, cols, n))
        })?;
        Ok((
            kind,
            PyArray1::from_vec(py, data),
            PyArray1::from_vec(py, a),
            PyArray1::from_vec(py, b),
            n,
        ))
    }

    /// Mixed Voronoi vertex areas (Meyer et al. 2003, §3.3), one per input
    /// vertex (split copies of a non-manifold vertex summed): the diagonal
    /// of the lumped mass matrix. They sum to the surface area.
    fn _vertex_areas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let mesh = Arc::clone(&self.mesh);
        let areas = crate::compute(py, move |_| {
            let a = fairline::geom::mixed_vertex_areas(&mesh);
            let n = mesh.original_vertex_count();
            let mut out = a[..n.min(a.len())].to_vec();
            for (v, &x) in a.iter().enumerate().skip(n) {
                out[mesh.original_vertex(VertexId(v as u32)).idx()] += x;
            }
            Ok(out)
        })?;
        Ok(PyArray1::from_vec(py, areas))
    }

    /// `smooth`'s new positions, report and stop sentence.
    #[pyo3(signature = (method = "taubin", weights = "uniform", exponent = -1.0,
        iterations = None, lambda_ = None, mu = None, pass_band = 0.1, time_step = 1.0,
        epsilon = None, max_work = None, fix_boundary = false, hierarchical_boundary = false,
        fixed = None, preserve_volume = false, tangential = false))]
    fn _smooth<'py>(
        &self,
        py: Python<'py>,
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
        let mesh = Arc::clone(&self.mesh);
        let (p, report, stopped) = crate::compute(py, move |control| {
            run_smooth(&mesh, settings, fixed, control)
        })?;
        Ok((positions_array(py, &p), report, stopped))
    }

    /// `highlight_lines` as flat arrays ([`line_arrays`]; with `band`,
    /// `band_radius`, `lower` and `upper` of the same shape) and the report.
    #[pyo3(signature = (direction = None, plane_normal = None, up = "auto",
        plane_point = None, spacing = None, lights = None, min_normal_cos = None,
        circle_center = None, circle_axis = None, radii = None, band = None))]
    fn _highlight_lines<'py>(
        &self,
        py: Python<'py>,
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
    ) -> PyResult<(Bound<'py, PyDict>, String)> {
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
        let mesh = Arc::clone(&self.mesh);
        let cache = Arc::clone(&self.triangles);
        let out = crate::compute(py, move |control| -> Res<_> {
            fairline_commands::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
            let triangles = Mesh::triangles(&mesh, &cache)?;
            Ok(fairline_commands::highlight::run(
                &triangles, &settings, control,
            )?)
        })?;
        let radii = out.radii.as_deref();
        let d = line_arrays(py, &out.lines, radii)?;
        if let Some(b) = &out.bands {
            d.set_item("band_radius", b.radius)?;
            d.set_item("lower", line_arrays(py, &b.lower, radii)?)?;
            d.set_item("upper", line_arrays(py, &b.upper, radii)?)?;
        }
        Ok((d, out.report.to_json().to_string()))
    }

    /// `highlight_lines` fitted as cubic B-spline curves within
    /// `tolerance` (the command's default for a mesh when `None`), written
    /// to `path` as IGES in `unit` (millimetres when `None`) when given;
    /// the curves ([`crate::curves::list`])
    /// and the report with its `curves` key.
    #[pyo3(signature = (tolerance = None, path = None, unit = None, direction = None, plane_normal = None,
        up = "auto", plane_point = None, spacing = None, lights = None, min_normal_cos = None,
        circle_center = None, circle_axis = None, radii = None))]
    fn _highlight_curves<'py>(
        &self,
        py: Python<'py>,
        tolerance: Option<f64>,
        path: Option<std::path::PathBuf>,
        unit: Option<String>,
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
    ) -> PyResult<(Bound<'py, pyo3::types::PyList>, String)> {
        crate::curves::check(tolerance, path.as_deref())?;
        let unit = crate::curves::unit(unit.as_deref())?;
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
            None,
        )?;
        let mesh = Arc::clone(&self.mesh);
        let cache = Arc::clone(&self.triangles);
        let (curves, report) = crate::compute(py, move |control| -> Res<_> {
            use fairline_commands::curves;
            fairline_commands::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
            let triangles = Mesh::triangles(&mesh, &cache)?;
            let out = fairline_commands::highlight::run(&triangles, &settings, control)?;
            let tol = curves::mesh_tolerance(tolerance, &triangles);
            crate::curves::fit_and_write(
                &curves::mesh_lines(&out.lines),
                tol,
                path.as_ref(),
                unit,
                out.report,
            )
        })?;
        Ok((crate::curves::list(py, &curves)?, report))
    }
}
