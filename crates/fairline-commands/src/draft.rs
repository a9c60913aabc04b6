//! `draft`: the draft angle of every face and vertex against a pull
//! direction and the share of the area with less than a minimum draft, as
//! every front end runs it ([`fairline::geom::draft_angles`]). Pictures
//! stay in the front ends.

use crate::error::CommandError;
use crate::report::Report;
use crate::warning::Warning;
use fairline::geom::{DraftAngles, DraftError, DraftShares, draft_angles};
use fairline::{Control, SurfaceMesh, Vec3};

/// The options of `draft` (default: pull +z, minimum angle 3°).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DraftSettings {
    /// The pull (demoulding) direction (need not be unit; not zero).
    pub pull: Vec3,
    /// The minimum draft angle, degrees (0 to 90).
    pub min_angle: f64,
}

/// The default minimum draft angle, degrees.
pub const DEFAULT_MIN_ANGLE: f64 = 3.0;

impl Default for DraftSettings {
    fn default() -> Self {
        DraftSettings {
            pull: Vec3::Z,
            min_angle: DEFAULT_MIN_ANGLE,
        }
    }
}

/// What `draft` gives.
#[derive(Clone, Debug)]
pub struct DraftOutcome {
    /// Face and vertex draft angles (degrees) and face areas.
    pub angles: DraftAngles,
    /// Per face: |draft| below the minimum angle.
    pub below: Vec<bool>,
    /// The shares of the area.
    pub shares: DraftShares,
    /// The JSON report: `pull`, `min_angle_deg`, `area`, `below_area`,
    /// `below_share`, `positive_share`, `negative_share`, `min_deg`,
    /// `max_deg`, `faces_below`.
    pub report: Report,
}

/// The draft angles of `mesh` against `settings.pull` (module
/// documentation). Errors: a zero or non-finite pull, a minimum angle
/// outside [0, 90] ([`CommandError::invalid`]), a mesh without faces.
pub fn run(
    mesh: &SurfaceMesh,
    settings: &DraftSettings,
    control: &Control,
) -> Result<DraftOutcome, CommandError> {
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    if !(settings.min_angle.is_finite() && (0.0..=90.0).contains(&settings.min_angle)) {
        return Err(CommandError::invalid(
            "min-angle",
            format!("{}; give 0 to 90 degrees", settings.min_angle),
        ));
    }
    if control.is_cancelled() {
        return Err(CommandError::cancelled());
    }
    let mut report = Report::new("draft");
    let angles = report
        .time(|| draft_angles(mesh, settings.pull))
        .map_err(|e| match e {
            DraftError::BadPull => {
                CommandError::invalid("pull", "must be a non-zero finite vector")
            }
        })?;
    let below: Vec<bool> = (0..mesh.face_count())
        .map(|f| angles.is_below(f, settings.min_angle))
        .collect();
    let shares = angles.shares(settings.min_angle);
    report.set("pull", angles.pull.to_array());
    report.set("min_angle_deg", settings.min_angle);
    report.set("area", shares.area);
    report.set("below_area", shares.below_area);
    report.set("below_share", shares.below);
    report.set("positive_share", shares.positive);
    report.set("negative_share", shares.negative);
    report.set("min_deg", shares.min_deg);
    report.set("max_deg", shares.max_deg);
    report.set("faces", mesh.face_count());
    report.set("faces_below", below.iter().filter(|b| **b).count());
    if shares.area <= 0.0 {
        report.warn(Warning::Text(
            "the surface has no area (every face is degenerate); the shares are 0".into(),
        ));
    }
    Ok(DraftOutcome {
        angles,
        below,
        shares,
        report,
    })
}

/// The edges between a face below the minimum draft and one that is not
/// (or the border of the mesh): the outline of the insufficient area, as
/// segments.
pub fn below_outline(mesh: &SurfaceMesh, below: &[bool]) -> Vec<[Vec3; 2]> {
    let is_below = |h| {
        mesh.face(h)
            .is_some_and(|f: fairline::mesh::FaceId| below.get(f.idx()).copied().unwrap_or(false))
    };
    mesh.edges()
        .filter(|&e| is_below(mesh.edge_halfedge(e, 0)) != is_below(mesh.edge_halfedge(e, 1)))
        .map(|e| {
            let (a, b) = mesh.edge_vertices(e);
            [mesh.position(a), mesh.position(b)]
        })
        .collect()
}

/// A one-line summary (the CLI's stderr line, the workbench's status).
pub fn summary(out: &DraftOutcome, min_angle: f64) -> String {
    let p = out.angles.pull;
    format!(
        "draft against ({:.3}, {:.3}, {:.3}): {:.2} % of the area below {min_angle}° ({} of {} faces), {:.2} % positive, {:.2} % negative; angles {:.2}° to {:.2}°",
        p.x,
        p.y,
        p.z,
        100.0 * out.shares.below,
        out.below.iter().filter(|b| **b).count(),
        out.below.len(),
        100.0 * out.shares.positive,
        100.0 * out.shares.negative,
        out.shares.min_deg,
        out.shares.max_deg
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use fairline::shapes;

    #[test]
    fn sphere_band_below_the_minimum_is_the_closed_form_share() {
        // on a sphere the area with |δ| < α is the band |z| < r sin α,
        // sin α of the area (Archimedes)
        let m = shapes::icosphere(1.0, 5);
        let s = DraftSettings {
            pull: Vec3::new(0.0, 0.0, 2.0),
            min_angle: 20.0,
        };
        let out = run(&m, &s, &Control::new()).unwrap();
        let want = 20f64.to_radians().sin();
        assert!(
            (out.shares.below - want).abs() < 0.01,
            "{}",
            out.shares.below
        );
        assert!((out.shares.positive - out.shares.negative).abs() < 0.01);
        let r = out.report.to_json();
        assert_eq!(r["min_angle_deg"], 20.0);
        assert!(summary(&out, 20.0).contains("% of the area below 20°"));
        let bad = DraftSettings {
            min_angle: 95.0,
            ..s
        };
        assert!(run(&m, &bad, &Control::new()).is_err());
        let zero = DraftSettings {
            pull: Vec3::ZERO,
            ..s
        };
        assert!(run(&m, &zero, &Control::new()).is_err());
    }
}
