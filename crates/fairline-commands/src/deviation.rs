//! `deviation`: the signed distance, per vertex of a measured mesh, to a
//! reference (the state before fairing, or another file), and its
//! statistics — over the whole surface and, given a region, inside it (the
//! intended motion) and outside it (side effects, about 0 for fairing);
//! and split by wavelength ([`fairline::geom::split_by_wavelength`]) into
//! its broad part (what moved whole neighbourhoods: an offset, a drift,
//! the shrinkage of a smoothing — side effects of a repair) and its local
//! part (what moved a few vertices against their neighbours: the noise or
//! the defect a repair is meant to remove).

use crate::error::{CommandError, Subject};
use crate::report::Report;
use fairline::bspline::{BSplineSurface, DeviationPeak, SurfaceReference, deviation_peak};
use fairline::geom::{
    Deviation, DeviationError, DeviationStats, WavelengthSplit, deviation, deviation_stats,
    split_by_wavelength,
};
use fairline::mesh::FaceId;
use fairline::{Control, SurfaceMesh};

/// Most tessellation points of B-spline surfaces measured against or
/// measured (surfaces × grid²): memory stays bounded whatever the grid
/// asked for.
pub const MAX_GRID_POINTS: usize = 20_000_000;

/// Refuses a tessellation grid out of 2..=1024, or one that would give
/// `surfaces` × `grid`² more than [`MAX_GRID_POINTS`] points.
pub fn check_grid(surfaces: usize, grid: usize) -> Result<(), CommandError> {
    if !(2..=1024).contains(&grid) {
        return Err(CommandError::invalid(
            "grid",
            format!("{grid}; give 2 to 1024"),
        ));
    }
    let points = surfaces as f64 * (grid * grid) as f64;
    if points > MAX_GRID_POINTS as f64 {
        return Err(CommandError::invalid(
            "grid",
            format!(
                "{grid}: {surfaces} surfaces × {grid}² is more than {MAX_GRID_POINTS} points; give a smaller grid"
            ),
        ));
    }
    Ok(())
}

/// Bins of the histogram in the report (default).
pub const DEFAULT_BINS: usize = 41;

/// The wavelength of the broad/local split, in mean edge lengths of the
/// measured mesh, when none is given: noise (one to a few edges) is local,
/// the shape is broad.
pub const DEFAULT_BROAD_WAVELENGTH_EDGES: f64 = 10.0;

/// The options of `deviation` (default: the CLI's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviationSettings {
    /// Histogram bins (at least 1).
    pub bins: usize,
    /// The wavelength (model units) that splits the deviation into its
    /// broad and local parts; `None`: [`DEFAULT_BROAD_WAVELENGTH_EDGES`]
    /// mean edge lengths of the measured mesh.
    pub broad_wavelength: Option<f64>,
}

impl Default for DeviationSettings {
    fn default() -> Self {
        DeviationSettings {
            bins: DEFAULT_BINS,
            broad_wavelength: None,
        }
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
    /// The signed deviation split by wavelength into broad and local parts.
    pub split: WavelengthSplit,
    /// Statistics of the broad part (waves longer than the split's).
    pub broad: DeviationStats,
    /// Statistics of the local part.
    pub local: DeviationStats,
    /// Where measured B-spline surfaces lie farthest from reference
    /// surfaces, searched between the sample points
    /// ([`fairline::bspline::deviation_peak`]; [`run_between_surfaces`]).
    pub peak: Option<DeviationPeak>,
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
/// tessellation. Errors as [`run`]'s, and a grid refused by
/// [`check_grid`].
pub fn run_on_surfaces(
    reference: &[BSplineSurface],
    grid: usize,
    measured: &SurfaceMesh,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    control: &Control,
) -> Result<DeviationOutcome, CommandError> {
    on_surfaces(reference, grid, measured, None, region, settings, control)
}

/// [`run_on_surfaces`] where the measured state is B-spline surfaces too
/// (`measured` their tessellation, whose vertices give the per-vertex
/// values): adds the largest deviation of the measured surfaces found
/// between the samples ([`fairline::bspline::deviation_peak`]; report key
/// `peak`), since a maximum taken at tessellation vertices alone can miss
/// the true one.
pub fn run_between_surfaces(
    reference: &[BSplineSurface],
    grid: usize,
    measured_surfaces: &[BSplineSurface],
    measured: &SurfaceMesh,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    control: &Control,
) -> Result<DeviationOutcome, CommandError> {
    check_grid(measured_surfaces.len(), grid)?;
    on_surfaces(
        reference,
        grid,
        measured,
        Some(measured_surfaces),
        region,
        settings,
        control,
    )
}

fn on_surfaces(
    reference: &[BSplineSurface],
    grid: usize,
    measured: &SurfaceMesh,
    measured_surfaces: Option<&[BSplineSurface]>,
    region: Option<&[FaceId]>,
    settings: &DeviationSettings,
    control: &Control,
) -> Result<DeviationOutcome, CommandError> {
    crate::require_faces(measured.face_count(), measured.original_vertex_count())?;
    check(settings, control)?;
    check_grid(reference.len(), grid)?;
    let mut report = Report::new("deviation");
    let (dev, peak) = report
        .time(|| -> Result<_, DeviationError> {
            let target = SurfaceReference::new(reference, grid)?;
            let dev = target.deviations(measured.positions());
            let peak = measured_surfaces.and_then(|m| deviation_peak(&target, m, grid));
            Ok((dev, peak))
        })
        .map_err(reference_error)?;
    if control.is_cancelled() {
        return Err(CommandError::cancelled());
    }
    let mut out = finish(dev, measured, region, settings, report)?;
    if let Some(p) = peak {
        out.report.set(
            "peak",
            serde_json::json!({
                "deviation": p.signed,
                "abs": p.signed.abs(),
                "face": p.face,
                "u": p.u,
                "v": p.v,
                "point": p.point.to_array(),
                "sampled_max": p.sampled,
                "vertices_max": out.all.max_abs,
            }),
        );
    }
    out.peak = peak;
    Ok(out)
}

/// The bins and the cancel flag, checked before any work.
fn check(settings: &DeviationSettings, control: &Control) -> Result<(), CommandError> {
    if let Some(w) = settings.broad_wavelength
        && !(w.is_finite() && w > 0.0)
    {
        return Err(CommandError::invalid(
            "broad-wavelength",
            format!("{w}; give a positive length"),
        ));
    }
    if settings.bins == 0 || settings.bins > 10_000 {
        return Err(CommandError::invalid(
            "bins",
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
    let wavelength = settings.broad_wavelength.unwrap_or_else(|| {
        DEFAULT_BROAD_WAVELENGTH_EDGES * fairline::geom::mean_edge_length(measured)
    });
    let split = report.time(|| split_by_wavelength(measured, &dev.signed, wavelength));
    let broad = deviation_stats(&split.broad, settings.bins);
    let local = deviation_stats(&split.local, settings.bins);
    report.set("broad_wavelength", split.wavelength);
    report.set("broad_converged", split.converged);
    report.set("broad", &broad);
    report.set("local", &local);
    Ok(DeviationOutcome {
        deviation: dev,
        all,
        inside,
        outside,
        in_region,
        split,
        broad,
        local,
        peak: None,
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
    s.push_str(&format!(
        "; broad (waves over {:.3e}) max {:.3e} mean {:+.3e}, local max {:.3e}",
        out.split.wavelength, out.broad.max_abs, out.broad.mean, out.local.max_abs
    ));
    if !out.split.converged {
        s.push_str(" (the broad/local split did not converge: its parts are approximate)");
    }
    if let Some(p) = &out.peak {
        s.push_str(&format!(
            "; between the vertices the surfaces reach max |d| {:.3e} (surface {} at u {:.6}, v {:.6})",
            p.signed.abs(),
            p.face,
            p.u,
            p.v
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use fairline::shapes;

    #[test]
    fn an_offset_is_broad_motion_and_a_spike_is_local() {
        let m = shapes::plane(41);
        let mut moved = m.clone();
        let spike = 20 * 41 + 20;
        for (i, p) in moved.positions_mut().iter_mut().enumerate() {
            p.z += 0.01 + if i == spike { 0.02 } else { 0.0 };
        }
        let out = run(
            &m,
            &moved,
            None,
            &DeviationSettings::default(),
            &Control::new(),
        )
        .unwrap();
        // the default wavelength: ten mean edges
        let edge = fairline::geom::mean_edge_length(&moved);
        assert!((out.split.wavelength - 10.0 * edge).abs() < 1e-12);
        // ten edges: the spike (two edges wide) is local
        let settings = DeviationSettings {
            broad_wavelength: Some(0.5),
            ..DeviationSettings::default()
        };
        let out = run(&m, &moved, None, &settings, &Control::new()).unwrap();
        assert!(out.split.converged);
        assert!((out.broad.mean - 0.01).abs() < 1e-4);
        assert!(out.local.max_abs > 0.015 && out.split.local[spike] > 0.015);
        let far = out
            .split
            .local
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != spike);
        assert!(far.map(|(_, l)| l.abs()).fold(0.0, f64::max) < 0.005);
        let r = out.report.to_json();
        assert!(r["broad"]["rms"].as_f64().unwrap() > 0.0099);
        assert_eq!(r["broad_converged"], true);
        assert!(summary(&out).contains("broad (waves over 5.000e-1) max"));
        let bad = DeviationSettings {
            broad_wavelength: Some(-1.0),
            ..DeviationSettings::default()
        };
        assert!(run(&m, &moved, None, &bad, &Control::new()).is_err());
    }

    /// Smoothing a noisy unit sphere: the shrinkage of Laplace smoothing
    /// is broad motion (about uniform, inward), the noise it removes is
    /// local; Taubin smoothing removes the same noise with a small fraction
    /// of the broad motion.
    #[test]
    fn smoothing_shrinkage_is_broad_and_the_noise_removed_is_local() {
        use crate::smooth::{SmoothSettings, run as smooth};
        use fairline::smooth::SmoothMethod;
        let clean = shapes::icosphere(1.0, 4);
        let mut noisy = clean.clone();
        let mut state = 12345u64;
        let noise: Vec<f64> = (0..noisy.vertex_count())
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02
            })
            .collect();
        for (p, e) in noisy.positions_mut().iter_mut().zip(&noise) {
            *p *= 1.0 + e;
        }
        let split = |method| {
            let settings = SmoothSettings {
                method,
                ..SmoothSettings::default()
            };
            let out = smooth(&noisy, &settings, &Control::new()).unwrap();
            let mut after = noisy.clone();
            after.positions_mut().copy_from_slice(&out.positions);
            run(
                &noisy,
                &after,
                None,
                &DeviationSettings::default(),
                &Control::new(),
            )
            .unwrap()
        };
        let laplace = split(SmoothMethod::Laplace);
        let taubin = split(SmoothMethod::Taubin);
        // Laplace: the sphere shrinks (broad, inward, nearly uniform)
        assert!(laplace.broad.mean < -0.01, "{}", laplace.broad.mean);
        assert!(laplace.broad.p95_abs < 1.5 * laplace.broad.mean.abs());
        // both remove the noise (local, about its rms 0.0058)
        for out in [&laplace, &taubin] {
            assert!(
                out.local.rms > 0.004 && out.local.rms < 0.008,
                "{}",
                out.local.rms
            );
        }
        // Taubin keeps the shape: a tenth of Laplace's broad motion (ten
        // edges of the sphere: 0.77)
        assert!(
            taubin.broad.rms < 0.1 * laplace.broad.rms,
            "{} {}",
            taubin.broad.rms,
            laplace.broad.rms
        );
    }

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
