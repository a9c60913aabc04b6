//! `section`: plane sections of a triangle mesh (a surface's tessellation)
//! with the curvature of each section point, and isoparametric curves of
//! B-spline surfaces with their exact curvature (`--iso`), as every front
//! end runs them.
//! Writing the CSV and OBJ files stays in the CLI.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use fairline::bspline::{BSplineSurface, IsoCurve, iso_curves};
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

/// Most iso-curves per direction and surface of one run.
pub const MAX_ISO_COUNT: usize = 1000;
/// Most samples along one iso-curve.
pub const MAX_ISO_SAMPLES: usize = 100_000;
/// Most iso-curve samples of one run (memory stays bounded whatever the
/// counts asked for).
pub const MAX_ISO_POINTS: usize = 20_000_000;

/// The options of `section --iso`: isoparametric curves of B-spline
/// surfaces with their exact curvature combs (defaults: 5 per direction,
/// 200 samples each, every surface, comb scale 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoSettings {
    /// Iso-curves per direction and surface, ends of the domain (the patch
    /// edges) included (1 to [`MAX_ISO_COUNT`]; 1: the middle one).
    pub count: usize,
    /// Even samples along each curve, the interior knots added (2 to
    /// [`MAX_ISO_SAMPLES`]).
    pub samples: usize,
    /// The one surface to comb (`None`: all).
    pub surface: Option<usize>,
    /// Length of a comb tooth per unit curvature (reported).
    pub comb_scale: f64,
}

impl Default for IsoSettings {
    fn default() -> Self {
        IsoSettings {
            count: 5,
            samples: 200,
            surface: None,
            comb_scale: 1.0,
        }
    }
}

/// What `section --iso` gives: each curve with the index of its surface,
/// and the JSON report.
#[derive(Clone, Debug)]
pub struct IsoOutcome {
    /// `(surface index, piece of an iso-curve)`, surfaces in order, u-held
    /// curves first on each.
    pub curves: Vec<(usize, IsoCurve)>,
    /// The JSON report: `iso` (`count`, `samples`, `comb_scale`,
    /// `surfaces`, `curves`, `max_curvature`) and per curve `surface`,
    /// `kind` (`u`, `v`: the parameter held; `trim`: an edge of a trimmed
    /// face), `value` (the held parameter, or the edge's loop), `points`, `length`, `max_curvature`.
    pub report: Report,
}

/// The isoparametric curves of `surfaces` with their curvature combs
/// ([`fairline::bspline::iso_curves`]: exact curvature from the surface
/// derivatives; on trimmed faces the pieces inside the face). Errors: a
/// count, sample number, comb scale or surface index out of range
/// ([`CommandError::invalid`]).
pub fn iso(
    surfaces: &[BSplineSurface],
    settings: &IsoSettings,
    control: &Control,
) -> Result<IsoOutcome, CommandError> {
    let s = settings;
    if s.count == 0 || s.count > MAX_ISO_COUNT {
        return Err(CommandError::invalid(
            "iso",
            format!(
                "{}; give 1 to {MAX_ISO_COUNT} curves per direction",
                s.count
            ),
        ));
    }
    if !(2..=MAX_ISO_SAMPLES).contains(&s.samples) {
        return Err(CommandError::invalid(
            "samples",
            format!("{}; give 2 to {MAX_ISO_SAMPLES}", s.samples),
        ));
    }
    if !s.comb_scale.is_finite() {
        return Err(CommandError::invalid("comb-scale", "must be finite"));
    }
    if let Some(k) = s.surface
        && k >= surfaces.len()
    {
        return Err(CommandError::invalid(
            "surface",
            format!(
                "{k} is out of range (the file holds {} surfaces)",
                surfaces.len()
            ),
        ));
    }
    let chosen: Vec<usize> = match s.surface {
        Some(k) => vec![k],
        None => (0..surfaces.len()).collect(),
    };
    // the iso-curves' samples (trim edges come on top, as many per curve)
    let planned = chosen.len() as f64 * 2.0 * s.count as f64 * s.samples as f64;
    if planned > MAX_ISO_POINTS as f64 {
        return Err(CommandError::invalid(
            "samples",
            format!(
                "{}: {} surfaces × 2 × {} curves × {} samples is more than {MAX_ISO_POINTS} points; give fewer curves or samples, or one --surface",
                s.samples,
                chosen.len(),
                s.count,
                s.samples
            ),
        ));
    }
    let mut report = Report::new("section");
    let mut curves = Vec::new();
    report.time(|| -> Result<(), CommandError> {
        for (done, &k) in chosen.iter().enumerate() {
            control
                .step("surfaces", done as u64, chosen.len() as u64)
                .map_err(|_| CommandError::cancelled())?;
            curves.extend(
                iso_curves(&surfaces[k], s.count, s.samples)
                    .into_iter()
                    .map(|c| (k, c)),
            );
        }
        Ok(())
    })?;
    let kmax = curves
        .iter()
        .map(|(_, c)| max_curvature(&c.curve))
        .fold(0.0, f64::max);
    let listed: Vec<serde_json::Value> = curves
        .iter()
        .map(|(k, c)| {
            serde_json::json!({
                "surface": k,
                "kind": c.kind_name(),
                "value": c.kind_value(),
                "points": c.curve.points.len(),
                "length": c.curve.length(),
                "max_curvature": max_curvature(&c.curve),
            })
        })
        .collect();
    report.set(
        "iso",
        serde_json::json!({
            "count": s.count,
            "samples": s.samples,
            "comb_scale": s.comb_scale,
            "surfaces": chosen.len(),
            "curves": curves.len(),
            "max_curvature": kmax,
        }),
    );
    report.set("curves", listed);
    if curves.is_empty() {
        report.warn(Warning::Text(
            "no iso-curve lies on the faces (every sample is trimmed away)".into(),
        ));
    }
    Ok(IsoOutcome { curves, report })
}

/// A one-line summary of `section --iso`.
pub fn iso_summary(out: &IsoOutcome) -> String {
    let points: usize = out.curves.iter().map(|(_, c)| c.curve.points.len()).sum();
    let surfaces = out.report.to_json()["iso"]["surfaces"]
        .as_u64()
        .unwrap_or(0);
    let kmax = out
        .curves
        .iter()
        .map(|(_, c)| max_curvature(&c.curve))
        .fold(0.0, f64::max);
    format!(
        "{} iso-curve(s) of {points} points on {surfaces} surface(s); largest curvature {kmax:.3e}",
        out.curves.len()
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

    #[test]
    fn iso_curves_of_a_flat_patch_are_straight_and_bad_settings_are_named() {
        let plane = fairline::bspline::BSplineSurface::new(
            1,
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            vec![
                vec![Vec3::ZERO, Vec3::Y],
                vec![Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
            ],
            None,
        )
        .unwrap();
        let surfaces = vec![plane.clone(), plane];
        let out = iso(&surfaces, &IsoSettings::default(), &Control::new()).unwrap();
        // 5 per direction on each of the two surfaces
        assert_eq!(out.curves.len(), 20);
        let r = out.report.to_json();
        assert_eq!(r["iso"]["curves"], 20);
        assert_eq!(r["iso"]["max_curvature"], 0.0);
        assert_eq!(r["curves"][0]["kind"], "u");
        assert_eq!(r["curves"][0]["length"], 1.0);
        assert!(iso_summary(&out).starts_with("20 iso-curve(s) of 4000 points on 2 surface(s)"));
        let one = IsoSettings {
            surface: Some(1),
            count: 1,
            ..Default::default()
        };
        let out = iso(&surfaces, &one, &Control::new()).unwrap();
        assert!(
            out.curves
                .iter()
                .all(|(k, c)| *k == 1 && c.kind_value() == 0.5)
        );
        for (bad, option) in [
            (
                IsoSettings {
                    count: 0,
                    ..Default::default()
                },
                "iso",
            ),
            (
                IsoSettings {
                    samples: 1,
                    ..Default::default()
                },
                "samples",
            ),
            (
                IsoSettings {
                    surface: Some(2),
                    ..Default::default()
                },
                "surface",
            ),
            (
                IsoSettings {
                    comb_scale: f64::NAN,
                    ..Default::default()
                },
                "comb-scale",
            ),
            (
                IsoSettings {
                    count: 1000,
                    samples: 100_000,
                    ..Default::default()
                },
                "samples",
            ),
        ] {
            let e = iso(&surfaces, &bad, &Control::new()).unwrap_err();
            assert!(
                e.message(crate::FrontEnd::Cli)
                    .contains(&format!("--{option}")),
                "{}",
                e.message(crate::FrontEnd::Cli)
            );
        }
    }
}
