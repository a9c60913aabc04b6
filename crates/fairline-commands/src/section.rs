//! `section`: plane sections of a triangle mesh (a surface's tessellation)
//! with the curvature of each section point, as every front end runs them.
//! Writing the CSV and OBJ files stays in the CLI.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use fairline::geom::{SectionCurve, parallel_sections};
use fairline::{Control, SurfaceMesh, Vec3};

/// Most planes of one run.
pub const MAX_COUNT: usize = 10_000;

/// The options of `section` (default: one plane through the origin,
/// normal +z, comb scale 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionSettings {
    /// A point of the first plane.
    pub point: Vec3,
    /// The planes' normal (need not be unit; not zero).
    pub normal: Vec3,
    /// Number of parallel planes (1 to [`MAX_COUNT`]).
    pub count: usize,
    /// Distance between neighbouring planes along the normal.
    pub spacing: f64,
    /// Length of a comb tooth per unit curvature (reported; the teeth are
    /// [`SectionCurve::comb`] of it).
    pub comb_scale: f64,
}

impl Default for SectionSettings {
    fn default() -> Self {
        SectionSettings {
            point: Vec3::ZERO,
            normal: Vec3::Z,
            count: 1,
            spacing: 0.0,
            comb_scale: 1.0,
        }
    }
}

/// What `section` gives: the curves of each plane and the JSON report.
#[derive(Clone, Debug)]
pub struct SectionOutcome {
    /// `sections[k]`: the curves of plane k (at `point + k·spacing·n̂`).
    pub sections: Vec<Vec<SectionCurve>>,
    /// The JSON report: per plane its `offset` and curves (`points`,
    /// `closed`, `length`, `max_curvature`), `comb_scale`.
    pub report: Report,
}

impl SectionOutcome {
    /// Number of curves over every plane.
    pub fn curve_count(&self) -> usize {
        self.sections.iter().map(Vec::len).sum()
    }
}

/// Cuts the triangle mesh `mesh` with the planes of `settings`. Errors: a
/// zero or non-finite normal, a count out of range, a non-finite spacing
/// or comb scale ([`CommandError::invalid`]); a mesh without faces or with
/// polygons (about the input).
pub fn run(
    mesh: &SurfaceMesh,
    settings: &SectionSettings,
    control: &Control,
) -> Result<SectionOutcome, CommandError> {
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    let s = settings;
    if !s.normal.is_finite() || s.normal.length() < 1e-300 {
        return Err(CommandError::invalid(
            "plane-normal",
            "must be a non-zero finite vector",
        ));
    }
    if !s.point.is_finite() {
        return Err(CommandError::invalid("plane-point", "must be finite"));
    }
    if s.count == 0 || s.count > MAX_COUNT {
        return Err(CommandError::invalid(
            "count",
            format!("{}; give 1 to {MAX_COUNT}", s.count),
        ));
    }
    if !s.spacing.is_finite() || !s.comb_scale.is_finite() {
        return Err(CommandError::invalid(
            "spacing",
            "the spacing and the comb scale must be finite",
        ));
    }
    if !mesh.is_triangle_mesh() {
        return Err(
            CommandError::bad_input("sections need a triangle mesh; triangulate first")
                .about(Subject::Input),
        );
    }
    if control.is_cancelled() {
        return Err(CommandError::cancelled());
    }
    let mut report = Report::new("section");
    let sections = report.time(|| parallel_sections(mesh, s.point, s.normal, s.count, s.spacing));
    let summary: Vec<serde_json::Value> = sections
        .iter()
        .enumerate()
        .map(|(k, curves)| {
            serde_json::json!({
                "section": k,
                "offset": k as f64 * s.spacing,
                "curves": curves.iter().map(|c| serde_json::json!({
                    "points": c.points.len(),
                    "closed": c.closed,
                    "length": c.length(),
                    "max_curvature": max_curvature(c),
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    report.set("sections", summary);
    report.set("comb_scale", s.comb_scale);
    let mut out = SectionOutcome { sections, report };
    if out.curve_count() == 0 {
        out.report.warn(Warning::Text(
            "no plane crosses the surface; check the plane point and normal".into(),
        ));
    }
    Ok(out)
}

/// The largest curvature of a curve (0 for none).
pub fn max_curvature(c: &SectionCurve) -> f64 {
    c.curvature.iter().copied().fold(0.0, f64::max)
}

/// A one-line summary (the CLI's stderr line, the workbench's status).
pub fn summary(out: &SectionOutcome, vertices: usize) -> String {
    let points: usize = out.sections.iter().flatten().map(|c| c.points.len()).sum();
    let kmax = out
        .sections
        .iter()
        .flatten()
        .map(max_curvature)
        .fold(0.0, f64::max);
    format!(
        "{} section(s), {} curve(s) of {points} points on {vertices} vertices; largest curvature {kmax:.3e}",
        out.sections.len(),
        out.curve_count(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use fairline::shapes;

    #[test]
    fn sphere_sections_are_circles_of_the_closed_form_curvature() {
        let m = shapes::icosphere(2.0, 5);
        // off the equator, where the icosphere has vertices on the plane
        let settings = SectionSettings {
            point: Vec3::new(0.0, 0.0, 0.1),
            count: 2,
            spacing: 1.0,
            ..Default::default()
        };
        let out = run(&m, &settings, &Control::new()).unwrap();
        assert_eq!(out.sections.len(), 2);
        // planes z = 0.1 and 1.1: circles of curvature 1/√(4 − z²)
        for (k, z) in [(0, 0.1f64), (1, 1.1)] {
            let want = 1.0 / (4.0 - z * z).sqrt();
            let c = &out.sections[k][0];
            assert!(c.closed);
            let mean = c.curvature.iter().sum::<f64>() / c.curvature.len() as f64;
            assert!((mean - want).abs() < 0.02 * want, "{mean} vs {want}");
        }
        let r = out.report.to_json();
        assert_eq!(r["sections"][1]["offset"], 1.0);
        assert!(summary(&out, m.vertex_count()).starts_with("2 section(s), 2 curve(s)"));
        let none = SectionSettings {
            point: Vec3::new(0.0, 0.0, 5.0),
            ..Default::default()
        };
        let out = run(&m, &none, &Control::new()).unwrap();
        assert_eq!(out.curve_count(), 0);
        assert_eq!(out.report.warnings().len(), 1);
        let zero = SectionSettings {
            normal: Vec3::ZERO,
            ..Default::default()
        };
        assert!(run(&m, &zero, &Control::new()).is_err());
    }
}
