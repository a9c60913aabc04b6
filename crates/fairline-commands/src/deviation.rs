//! `deviation`: the signed distance, per vertex of a measured mesh, to a
//! reference (the state before fairing, or another file), and its
//! statistics — over the whole surface and, given a region, inside it (the
//! intended motion) and outside it (side effects, about 0 for fairing).

use crate::error::{CommandError, Subject};
use crate::report::Report;
use fairline::bspline::{BSplineSurface, surface_deviation};
use fairline::geom::{Deviation, DeviationError, DeviationStats, deviation, deviation_stats};
use fairline::mesh::FaceId;
use fairline::{Control, SurfaceMesh};

/// Bins of the histogram in the report (default).
pub const DEFAULT_BINS: usize = 41;

/// The options of `deviation` (default: the CLI's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviationSettings {
    /// Histogram bins (at least 1).
    pub bins: usize,
}

impl Default for DeviationSettings {
    fn default() -> Self {
        DeviationSettings { bins: DEFAULT_BINS }
    }
}

/// What `deviation` gives: the per-vertex values and the JSON report.
#[derive(Clone, Debug)]
pub struct DeviationOutcome {
    /// Signed and unsigned deviation per vertex of the measured mesh.
    pub deviation: Deviation,
    /// Statistics of the signed deviation over every vertex.
    pub all: DeviationStats,
    /// Inside the region (its faces' vertices), when one was given.
    pub inside: Option<DeviationStats>,
    /// Outside the region, when one was given.
    pub outside: Option<DeviationStats>,
    /// Per vertex of the measured mesh: inside the region (empty without one).
    pub in_region: Vec<bool>,
    /// The JSON report.
    pub report: Report,
}

/// The deviation of `measured` from `reference` (polygon references are
/// triangulated first; their vertices stay). `region`: faces of
/// `measured` whose vertices count as "inside" for the split statistics.
/// Errors: an empty mesh or an empty reference (about the input,
/// [`Subject::Input`]; the front end names which file), a face of the
/// region out of range ([`Subject::Region`]).
pub fn run(
    reference: &SurfaceMesh,
    measured: &SurfaceMesh,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    control: &Control,
) -> Result<DeviationOutcome, CommandError> {
    crate::require_faces(reference.face_count(), reference.original_vertex_count())?;
    crate::require_faces(measured.face_count(), measured.original_vertex_count())?;
    check(settings, control)?;
    let mut report = Report::new("deviation");
    let triangulated;
    let reference = if reference.is_triangle_mesh() {
        reference
    } else {
        triangulated = fairline::mesh::triangulate(reference)
            .map_err(|e| CommandError::bad_input(e.to_string()).about(Subject::Input))?
            .mesh;
        &triangulated
    };
    let dev = report
        .time(|| deviation(reference, measured))
        .map_err(reference_error)?;
    finish(dev, measured, region, settings, report)
}

/// A reference that gives nothing to measure against (about the input).
fn reference_error(e: DeviationError) -> CommandError {
    match e {
        DeviationError::NotTriangles | DeviationError::EmptyReference => {
            CommandError::bad_input(e.to_string()).about(Subject::Input)
        }
    }
}

/// The deviation of `measured` (a surface file's tessellation, or a mesh)
/// from the B-spline surfaces `reference` themselves: the exact distance to
/// the closest point of the surfaces ([`fairline::bspline::surface_deviation`],
/// started from their tessellation `grid` × `grid` per surface), not to a
/// tessellation. Errors as [`run`]'s, and a grid out of 2..=1024.
pub fn run_on_surfaces(
    reference: &[BSplineSurface],
    grid: usize,
    measured: &SurfaceMesh,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    control: &Control,
) -> Result<DeviationOutcome, CommandError> {
    crate::require_faces(measured.face_count(), measured.original_vertex_count())?;
    check(settings, control)?;
    if !(2..=1024).contains(&grid) {
        return Err(CommandError::invalid(
            "grid",
            format!("{grid}; give 2 to 1024"),
        ));
    }
    let mut report = Report::new("deviation");
    let dev = report
        .time(|| surface_deviation(reference, measured.positions(), grid))
        .map_err(reference_error)?;
    finish(dev, measured, region, settings, report)
}

/// The bins and the cancel flag, checked before any work.
fn check(settings: &DeviationSettings, control: &Control) -> Result<(), CommandError> {
    if settings.bins == 0 || settings.bins > 10_000 {
        return Err(CommandError::invalid(
            "--bins",
            format!("{} bins; give 1 to 10000", settings.bins),
        ));
    }
    if control.is_cancelled() {
        return Err(CommandError::cancelled());
    }
    Ok(())
}

/// The statistics (all, inside and outside the region) and the report of
/// a measured deviation.
fn finish(
    dev: Deviation,
    measured: &SurfaceMesh,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    mut report: Report,
) -> Result<DeviationOutcome, CommandError> {
    let all = deviation_stats(&dev.signed, settings.bins);
    let mut in_region = Vec::new();
    let (mut inside, mut outside) = (None, None);
    if let Some(faces) = region {
        let nf = measured.face_count();
        if let Some(bad) = faces.iter().find(|f| f.idx() >= nf) {
            return Err(CommandError::bad_input(format!(
                "face {} out of range (the mesh has {nf} faces)",
                bad.idx()
            ))
            .about(Subject::Region));
        }
        in_region = vec![false; measured.vertex_count()];
        for &f in faces {
            for v in measured.face_vertices(f) {
                in_region[v.idx()] = true;
            }
        }
        let pick = |want: bool| -> Vec<f64> {
            dev.signed
                .iter()
                .zip(&in_region)
                .filter(|(_, r)| **r == want)
                .map(|(s, _)| *s)
                .collect()
        };
        inside = Some(deviation_stats(&pick(true), settings.bins));
        outside = Some(deviation_stats(&pick(false), settings.bins));
    }
    report.set("method", dev.method);
    report.set("units", "model units (the length unit of the files)");
    report.set("vertices", measured.vertex_count());
    report.set("unmatched", dev.unmatched);
    if dev.method == fairline::geom::DeviationMethod::SurfacePoint {
        report.set("unrefined", dev.unrefined);
    }
    report.set("all", &all);
    if let (Some(i), Some(o)) = (&inside, &outside) {
        report.set("inside_region", i);
        report.set("outside_region", o);
    }
    Ok(DeviationOutcome {
        deviation: dev,
        all,
        inside,
        outside,
        in_region,
        report,
    })
}

/// A one-line summary of an outcome (the CLI's stderr line, the
/// workbench's status).
pub fn summary(out: &DeviationOutcome) -> String {
    let mut s = format!(
        "deviation of {} vertices ({}): max |d| {:.3e}, mean {:+.3e}, rms {:.3e}, 95% within {:.3e}",
        out.all.count,
        match out.deviation.method {
            fairline::geom::DeviationMethod::Displacement => "vertex displacement",
            fairline::geom::DeviationMethod::ClosestPoint => "closest point",
            fairline::geom::DeviationMethod::SurfacePoint => "closest point on the surfaces",
        },
        out.all.max_abs,
        out.all.mean,
        out.all.rms,
        out.all.p95_abs
    );
    if let (Some(i), Some(o)) = (&out.inside, &out.outside) {
        s.push_str(&format!(
            "; inside the region max {:.3e} ({} vertices), outside max {:.3e} ({} vertices)",
            i.max_abs, i.count, o.max_abs, o.count
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use fairline::shapes;

    #[test]
    fn region_splits_motion_inside_from_outside() {
        let m = shapes::plane(11);
        let mut moved = m.clone();
        let region: Vec<FaceId> = m.faces().take(10).collect();
        let mut inside = vec![false; m.vertex_count()];
        for &f in &region {
            for v in m.face_vertices(f) {
                inside[v.idx()] = true;
            }
        }
        for (p, i) in moved.positions_mut().iter_mut().zip(&inside) {
            if *i {
                p.z += 0.05;
            }
        }
        let out = run(
            &m,
            &moved,
            Some(&region),
            &DeviationSettings::default(),
            &Control::new(),
        )
        .unwrap();
        assert!((out.inside.as_ref().unwrap().max_abs - 0.05).abs() < 1e-12);
        assert_eq!(out.outside.as_ref().unwrap().max_abs, 0.0);
        let r = out.report.to_json();
        assert_eq!(r["method"], "displacement");
        assert!(r["outside_region"]["rms"].as_f64() == Some(0.0));
        assert!(summary(&out).contains("outside max 0.000e0"));
        let bad = [FaceId(100_000)];
        let e = run(
            &m,
            &moved,
            Some(&bad),
            &DeviationSettings::default(),
            &Control::new(),
        );
        assert_eq!(e.unwrap_err().subject(), Some(Subject::Region));
    }
}
