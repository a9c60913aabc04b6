//! The lines file of `fairline highlight` (`-o`): JSON or OBJ polylines,
//! or IGES curves ([`fairline_commands::curves`]), chosen by extension;
//! for meshes and surface files alike.

use crate::error::bad_input;
use anyhow::Result;
use fairline::highlight::{HighlightBands, HighlightLines};
use std::path::Path;

/// Output format of polylines.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum LinesFormat {
    /// JSON of DESIGN.md §4.
    Json,
    /// Wavefront OBJ `l` elements.
    Obj,
    /// B-spline curves in IGES ([`fairline_commands::curves`]).
    Iges,
}

/// The format of `path` from its extension.
pub fn lines_format(path: &Path) -> Result<LinesFormat> {
    crate::output::require_extension("-o", path, &["json", "obj", "igs", "iges"])?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    Ok(match ext.as_str() {
        "obj" => LinesFormat::Obj,
        "igs" | "iges" => LinesFormat::Iges,
        _ => LinesFormat::Json,
    })
}

/// Refuses a `--curve-tolerance` that is not a positive number.
pub fn check_curve_tolerance(t: Option<f64>) -> Result<()> {
    match t {
        Some(t) if !(t > 0.0 && t.is_finite()) => Err(bad_input(format!(
            "--curve-tolerance must be a positive number, got {t}"
        ))),
        _ => Ok(()),
    }
}

/// Writes `lines` as B-spline curves of IGES entities 126 within `tol` in
/// `unit`; returns the report's `curves` key.
pub fn write_curves(
    path: &Path,
    lines: &[fairline_commands::curves::LinePolyline<'_>],
    tol: f64,
    unit: Option<&fairline::io::units::LengthUnit>,
) -> Result<serde_json::Value> {
    let out = fairline_commands::curves::fit(lines, tol);
    let mut options = fairline::io::iges_write::IgesWriteOptions::default();
    if let Some(u) = unit {
        options = options.unit(u.clone());
    }
    fairline::io::iges_write::write_curves_iges(path, &out.curves, &options)?;
    let left_out = out.summary["left_out"].as_u64().unwrap_or(0);
    if left_out > 0 {
        crate::output::warn(format!(
            "{left_out} line(s) of fewer than two distinct points are not written as curves"
        ));
    }
    Ok(out.summary)
}

/// Writes lines (and bands) atomically in the format of `path`'s
/// extension ([`fairline::highlight::highlight_lines_json`],
/// [`fairline::highlight::highlight_lines_obj`]).
pub fn write_lines(
    path: &Path,
    lines: &HighlightLines,
    bands: Option<&HighlightBands>,
    radii: Option<&[f64]>,
) -> Result<()> {
    match lines_format(path)? {
        LinesFormat::Iges => Err(anyhow::anyhow!(
            "{}: curves are written by write_curves",
            path.display()
        )),
        LinesFormat::Json => crate::common::write_json(
            path,
            &fairline::highlight::highlight_lines_json(lines, bands, radii),
        ),
        LinesFormat::Obj => {
            let text = fairline::highlight::highlight_lines_obj(lines, bands);
            fairline::io::atomic_write(path, |w| {
                use std::io::Write;
                w.write_all(text.as_bytes())
            })?;
            Ok(())
        }
    }
}
