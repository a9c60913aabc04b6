//! Detection of the whole part: as many light arrays as it takes for every
//! face to be judged by one.
//!
//! The measure of [`detect_irregularities`] compares normals in every
//! direction at once (module documentation of `detect`, step 4), so the
//! direction of the lights does not hide any side of the part: a dent on
//! the underside of a torus scores as one on top (its distance L from the
//! light plane only raises its score). What leaves faces unjudged is the
//! scale: where the surface turns by more than
//! [`DetectOptions::max_turn`] within the smooth radius R = 1.5 s (step 6:
//! the tube of a torus whose radius is below R, ears, horns, tight
//! fillets), no cubic over R stands for it. [`detect_whole_part`] judges
//! those faces with arrays of half the spacing, then a quarter, … — the
//! same plane and direction — until every face is judged, or R reaches its
//! floor of five mean edges (a finer scale than the mesh resolves would
//! read its facets as defects), or [`MAX_FINER_ARRAYS`] arrays were added.
//! The regions a finer array finds where the coarser ones judged nothing
//! join the result; elsewhere the coarser array's judgement stands (its
//! noise floors were estimated over the whole part at its own scale).

use super::regions::area_share;
use super::sites::Scale;
use super::{
    DetectOptions, Detection, HighlightError, HighlightLines, IrregularRegion, LightArray,
    detect_irregularities,
};
use crate::geom;
use crate::mesh::{FaceId, SurfaceMesh};

/// Most arrays [`detect_whole_part`] adds to the given one (each halves the
/// spacing: down to 1/16 of it).
pub const MAX_FINER_ARRAYS: usize = 4;

/// Share of the part's area below which the unjudged rest is not looked at
/// again, and front ends do not lead their summary with it.
pub const NOT_JUDGED_SHARE: f64 = 0.005;

/// Detection of the whole part (module documentation): [`detect_irregularities`]
/// under `light`, then under arrays of half the spacing and less wherever
/// it judged nothing. The result is the first detection with the regions
/// the finer arrays found in faces no coarser array judged (each with its
/// [`IrregularRegion::spacing`]), ranked together by severity, their lines
/// and stretches, and [`Detection::not_judged_fraction`],
/// [`Detection::unjudged_faces`] and [`Detection::spacings`] of all arrays
/// together. Where the first array judges (almost) every face, the result
/// is that of [`detect_irregularities`]. Errors as
/// [`detect_irregularities`].
pub fn detect_whole_part(
    mesh: &SurfaceMesh,
    light: &LightArray,
    lines: &HighlightLines,
    options: &DetectOptions,
) -> Result<Detection, HighlightError> {
    let mut merged = detect_irregularities(mesh, light, lines, options)?;
    if merged.not_judged_fraction < NOT_JUDGED_SHARE {
        return Ok(merged);
    }
    let areas = geom::face_areas(mesh);
    let total: f64 = areas.iter().sum();
    let mut unjudged = vec![false; mesh.face_count()];
    for f in &merged.unjudged_faces {
        unjudged[f.idx()] = true;
    }
    let mut spacing = light.spacing();
    let mut radius = merged.smooth_radius;
    for _ in 0..MAX_FINER_ARRAYS {
        let finer = light.with_spacing(0.5 * spacing)?;
        // the smooth radius has a floor of five mean edges: past it a finer
        // array judges nothing new
        let finer_radius = Scale::new(mesh, &finer, options).smooth_radius;
        if !(finer_radius < 0.99 * radius) {
            break;
        }
        spacing = finer.spacing();
        radius = finer_radius;
        let det = detect_irregularities(mesh, &finer, lines, options)?;
        merged.spacings.push(spacing);
        for r in det
            .regions
            .iter()
            .filter(|r| mostly_in(r, &unjudged, &areas))
        {
            merge_region(&mut merged, &det, r);
        }
        let mut still = vec![false; mesh.face_count()];
        for f in &det.unjudged_faces {
            still[f.idx()] = true;
        }
        for (u, s) in unjudged.iter_mut().zip(&still) {
            *u &= *s;
        }
        let share = area_share(&faces_of(&unjudged), &areas, total);
        if share < NOT_JUDGED_SHARE {
            break;
        }
    }
    merged.unjudged_faces = faces_of(&unjudged);
    merged.not_judged_fraction = area_share(&merged.unjudged_faces, &areas, total);
    merged.regions.sort_by(|a, b| {
        b.severity
            .total_cmp(&a.severity)
            .then(b.score.total_cmp(&a.score))
            .then(a.faces.cmp(&b.faces))
    });
    merged.lines.sort_by_key(|l| l.line);
    let region_area: f64 = merged
        .regions
        .iter()
        .map(|r| r.area)
        .fold(0.0, |a, b| a + b);
    merged.flagged_area_fraction = if total > 0.0 {
        (region_area / total).clamp(0.0, 1.0)
    } else {
        0.0
    };
    Ok(merged)
}

/// The faces set in `mask`, ascending.
fn faces_of(mask: &[bool]) -> Vec<FaceId> {
    (0..mask.len())
        .filter(|&f| mask[f])
        .map(|f| FaceId(f as u32))
        .collect()
}

/// Whether more than half of the region's area lies in `unjudged`.
fn mostly_in(r: &IrregularRegion, unjudged: &[bool], areas: &[f64]) -> bool {
    let inside: f64 = r
        .faces
        .iter()
        .filter(|f| unjudged[f.idx()])
        .map(|f| areas[f.idx()])
        .sum();
    inside > 0.5 * r.area
}

/// Adds region `r` of the finer detection `det` to `merged`, with the
/// stretches of its lines that lie within it (by distance from its centre:
/// the stretches of `det` are cut at all of its regions).
fn merge_region(merged: &mut Detection, det: &Detection, r: &IrregularRegion) {
    merged.flagged_sites += r.flagged_sites;
    let extent = (r.area / std::f64::consts::PI).sqrt() * 2.0;
    for line in det
        .lines
        .iter()
        .filter(|l| r.lines.binary_search(&l.line).is_ok())
    {
        let stretches: Vec<Vec<crate::Vec3>> = line
            .stretches
            .iter()
            .filter(|s| {
                s.get(s.len() / 2)
                    .is_some_and(|p| (*p - r.center).length() <= extent)
            })
            .cloned()
            .collect();
        if stretches.is_empty() {
            continue;
        }
        match merged.lines.iter_mut().find(|l| l.line == line.line) {
            Some(l) => {
                l.score = l.score.max(r.score);
                l.stretches.extend(stretches);
            }
            None => {
                let mut l = line.clone();
                l.score = r.score;
                l.stretches = stretches;
                merged.lines.push(l);
            }
        }
    }
    merged.regions.push(r.clone());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::highlight::{HighlightOptions, UpAxis, highlight_lines};
    use crate::{Vec3, shapes};

    /// A torus whose tube (radius 1) is narrower than the default lights'
    /// smooth radius, with a dent planted on its underside, and the lights.
    fn torus(dent: f64) -> (SurfaceMesh, LightArray, HighlightLines) {
        let mut mesh = shapes::torus(6.0, 1.0, 380, 60);
        let centre = Vec3::new(6.0, 0.0, -1.0);
        for q in mesh.positions_mut() {
            let t = (*q - centre).length() / 0.4;
            if t < 1.0 {
                q.z += dent * (1.0 - t * t).powi(3);
            }
        }
        let light = LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap();
        let lines = highlight_lines(&mesh, &light, &HighlightOptions::default()).unwrap();
        (mesh, light, lines)
    }

    /// The default lights judge almost none of the tube (its turn within
    /// the smooth radius exceeds the limit), and the summary leads with it;
    /// the whole-part detection judges every face with finer arrays, finds
    /// the dent on the underside first, and flags nothing on the clean torus.
    #[test]
    fn finer_arrays_judge_the_whole_torus_and_find_a_dent_underneath() {
        let (clean, light, lines) = torus(0.0);
        let opts = DetectOptions::default();
        let one = detect_irregularities(&clean, &light, &lines, &opts).unwrap();
        assert!(one.not_judged_fraction > 0.3, "{}", one.not_judged_fraction);
        assert!(
            one.summary().starts_with("not judged: "),
            "{}",
            one.summary()
        );
        assert!(one.not_judged_warning().is_some());
        let whole = detect_whole_part(&clean, &light, &lines, &opts).unwrap();
        assert!(whole.spacings.len() >= 2, "{:?}", whole.spacings);
        assert!(whole.spacings[1] < light.spacing());
        assert!(
            whole.not_judged_fraction < NOT_JUDGED_SHARE,
            "{}",
            whole.not_judged_fraction
        );
        assert!(whole.regions.is_empty(), "{} regions", whole.regions.len());
        assert!(whole.summary().starts_with("0 region(s) flagged"));
        assert!(whole.not_judged_warning().is_none());

        let (dented, light, lines) = torus(0.02);
        let d = detect_whole_part(&dented, &light, &lines, &opts).unwrap();
        let best = d.regions.first().expect("the dent is found");
        assert!(
            (best.center - Vec3::new(6.0, 0.0, -1.0)).length() < 0.4,
            "{:?}",
            best.center
        );
        assert!(best.spacing < light.spacing());
    }
}
