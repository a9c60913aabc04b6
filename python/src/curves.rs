//! Highlight lines as B-spline curves (`fairline.highlight_curves`,
//! `fairline.surface_highlight_curves`, `Mesh.highlight_curves`): the
//! command layer's [`fairline_commands::curves`] fit, the curves handed to
//! Python as dicts of numpy arrays and, when a path is given, written as
//! an IGES file of entities 126 as `fairline highlight -o LINES.igs` writes
//! it.

use crate::{Failure, Res, positions_array};
use fairline::io::iges_write::{IgesWriteOptions, NamedCurve, write_curves_iges};
use fairline::io::units::LengthUnit;
use fairline_commands::curves::{LinePolyline, fit};
use fairline_commands::report::Report;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};

/// Refuses a tolerance that is not a positive number and a path whose
/// extension is not `.igs`/`.iges` (before anything is computed).
pub(crate) fn check(tolerance: Option<f64>, path: Option<&Path>) -> Res<()> {
    if let Some(t) = tolerance
        && !(t > 0.0 && t.is_finite())
    {
        return Err(Failure::bad(format!(
            "tolerance must be a positive number, got {t}"
        )));
    }
    if let Some(p) = path {
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if ext != "igs" && ext != "iges" {
            return Err(Failure::bad(format!(
                "{}: curves are written as .igs or .iges",
                p.display()
            )));
        }
    }
    Ok(())
}

/// The length unit named by `name` (an IGES unit name: `MM`, `IN`, `M`,
/// `CM`, `FT`, …; case-insensitive); `None` for millimetres.
pub(crate) fn unit(name: Option<&str>) -> Res<Option<LengthUnit>> {
    match name {
        None => Ok(None),
        Some(n) => LengthUnit::from_iges_name(n).map(Some).ok_or_else(|| {
            Failure::bad(format!(
                "unit must be an IGES unit name (MM, CM, M, IN, FT, …), got {n:?}"
            ))
        }),
    }
}

/// Fits `lines` within `tolerance`, writes the curves atomically as IGES
/// in `unit` (millimetres when none) when `path` is given, and sets the
/// report's `curves` key: the curves and the report's JSON text.
pub(crate) fn fit_and_write(
    lines: &[LinePolyline<'_>],
    tolerance: f64,
    path: Option<&PathBuf>,
    unit: Option<LengthUnit>,
    mut report: Report,
) -> Res<(Vec<NamedCurve>, String)> {
    let fitted = fit(lines, tolerance);
    if let Some(path) = path {
        let mut options = IgesWriteOptions::default();
        if let Some(u) = unit {
            options = options.unit(u);
        }
        write_curves_iges(path, &fitted.curves, &options).map_err(Failure::from)?;
    }
    report.set("curves", fitted.summary);
    Ok((fitted.curves, report.to_json().to_string()))
}

/// The curves as a list of dicts: `label` (the IGES label, `HLm` or
/// `PkLj`), `number` (its subscript), `degree`, `knots` (float64),
/// `points` ((k, 3) float64 control points) and `weights` when rational.
pub(crate) fn list<'py>(py: Python<'py>, curves: &[NamedCurve]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for c in curves {
        let d = PyDict::new(py);
        d.set_item("label", &c.label)?;
        d.set_item("number", c.number)?;
        d.set_item("degree", c.curve.degree)?;
        d.set_item("knots", PyArray1::from_slice(py, &c.curve.knots))?;
        d.set_item("points", positions_array(py, &c.curve.points))?;
        if let Some(w) = &c.curve.weights {
            d.set_item("weights", PyArray1::from_slice(py, w))?;
        }
        out.append(d)?;
    }
    Ok(out)
}
