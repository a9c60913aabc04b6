//! The regions of the `fair` and `detect` commands: the margins around
//! detected regions, the regions `fair --auto` fairs in turn, the one
//! report of a run over several regions and what it warns about. The
//! fairing itself is [`fairline::fair::fair_highlight_lines`] (Yong et al.
//! §3).

use crate::warning::Warning;
use fairline::fair::{FairReport, grow_region};
use fairline::highlight::{
    DetectOptions, Detection, HighlightError, HighlightModel, HighlightOptions, LightArray,
    detect_whole_part,
};
use fairline::mesh::{FaceId, SurfaceMesh};
use serde::Serialize;
use serde_json::{Map, Value, json};

/// Rings of faces added around the union of the detected regions in the
/// region `fairline detect` writes: a vertex moves under fairing only when
/// all faces around it and around its neighbours are in the region (Yong
/// et al. §3.1), so two rings make every vertex of a detected region
/// movable.
pub const SUPPORT_RINGS: usize = 2;

/// Rings of faces `fairline fair --auto` adds around each detected region
/// before fairing it.
pub const AUTO_RINGS: usize = 4;

/// The regions `fairline fair --auto` fairs: the irregular regions that
/// detection of the whole part (default [`DetectOptions`],
/// [`detect_whole_part`]) finds on the highlight lines of `light`, best
/// first, each grown by [`AUTO_RINGS`]; with the detection.
pub fn detect_regions_to_fair(
    mesh: &SurfaceMesh,
    light: LightArray,
    options: HighlightOptions,
) -> Result<(Detection, Vec<Vec<FaceId>>), HighlightError> {
    let model = HighlightModel::new(mesh, light, options)?;
    let lines = model.lines(mesh);
    let detection = detect_whole_part(mesh, &light, &lines, &DetectOptions::default())?;
    let grown = detection
        .regions
        .iter()
        .map(|r| grow_region(mesh, &r.faces, AUTO_RINGS))
        .collect();
    Ok((detection, grown))
}

/// Every face of the regions, sorted, without repeats.
pub fn regions_union(regions: &[Vec<FaceId>]) -> Vec<FaceId> {
    let mut all: Vec<FaceId> = regions.iter().flatten().copied().collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// Faces of `faces` as faces of the input mesh, sorted and without
/// repeats: `source[f]` is the input face of face `f` when the mesh was
/// triangulated from polygons (`None`: the mesh is the input).
pub fn input_faces(faces: &[FaceId], source: Option<&[FaceId]>) -> Vec<u32> {
    let mut out: Vec<u32> = match source {
        Some(src) => faces.iter().map(|f| src[f.idx()].0).collect(),
        None => faces.iter().map(|f| f.0).collect(),
    };
    out.sort_unstable();
    out.dedup();
    out
}

/// The region a detection suggests for fairing: the union of its regions
/// grown by [`SUPPORT_RINGS`], as input faces ([`input_faces`]).
pub fn suggested_region(
    mesh: &SurfaceMesh,
    detection: &Detection,
    source: Option<&[FaceId]>,
) -> Vec<u32> {
    input_faces(
        &grow_region(mesh, &detection.all_faces(), SUPPORT_RINGS),
        source,
    )
}

/// One detected region as the report of `fairline detect` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DetectedRegionEntry {
    /// Largest score of the flagged sites inside
    /// ([`crate::highlight::IrregularRegion::score`]).
    pub score: f64,
    /// The threshold at the site of that score.
    pub threshold: f64,
    /// Largest flat-spot value of the sites the flat-spot measure flagged
    /// inside (0 when none).
    pub flat_spot: f64,
    /// How many times the strongest flagged site exceeds its measure's
    /// threshold (regions are ranked by it).
    pub severity: f64,
    /// Number of input faces of the region (without the support rings).
    pub faces: usize,
    /// Area of the region (mesh units²).
    pub area: f64,
    /// Score-weighted centre of the flagged sites inside.
    pub center: [f64; 3],
    /// Flagged sites inside.
    pub flagged_sites: usize,
    /// Lines crossing the region.
    pub lines: Vec<usize>,
}

/// The report entries of the regions of `detection`, best first
/// (`source` as for [`input_faces`]).
pub fn detected_region_entries(
    detection: &Detection,
    source: Option<&[FaceId]>,
) -> Vec<DetectedRegionEntry> {
    detection
        .regions
        .iter()
        .map(|r| DetectedRegionEntry {
            score: r.score,
            threshold: r.threshold,
            flat_spot: r.flat_spot,
            severity: r.severity,
            faces: input_faces(&r.faces, source).len(),
            area: r.area,
            center: r.center.to_array(),
            flagged_sites: r.flagged_sites,
            lines: r.lines.clone(),
        })
        .collect()
}

/// The report keys of fairing `results` (one report per faired region, in
/// order): a single region's report as it is; otherwise the run summed up
/// — iterations, movable vertices and Willmore energies summed, converged
/// when every region converged (left out when there is none), the highlight deviations their largest,
/// `max_displacement` the largest move of a vertex over the whole run
/// (`max_displacement`, measured by the caller) — with every region's
/// report under `per_region`.
pub fn regions_report(results: &[FairReport], max_displacement: f64) -> Map<String, Value> {
    let results: Vec<Value> = results
        .iter()
        .map(|r| serde_json::to_value(r).unwrap_or(Value::Null))
        .collect();
    let mut keys = Map::new();
    if let [Value::Object(one)] = results.as_slice() {
        return one.clone();
    }
    let sum = |key: &str| -> f64 { results.iter().filter_map(|r| r[key].as_f64()).sum() };
    keys.insert("iterations".into(), json!(sum("iterations") as u64));
    // with no region faired nothing converged: the key is left out
    if !results.is_empty() {
        keys.insert("converged".into(), json!(all_converged(&results)));
    }
    keys.insert(
        "movable_vertices".into(),
        json!(sum("movable_vertices") as u64),
    );
    keys.insert("willmore_before".into(), json!(sum("willmore_before")));
    keys.insert("willmore_after".into(), json!(sum("willmore_after")));
    for key in ["highlight_deviation_before", "highlight_deviation_after"] {
        keys.insert(key.into(), json!(largest(&results, key)));
    }
    keys.insert(
        "highlight_deviation_worse".into(),
        json!(
            results
                .iter()
                .any(|r| r["highlight_deviation_worse"] == json!(true))
        ),
    );
    keys.insert("max_displacement".into(), json!(max_displacement));
    keys.insert("per_region".into(), Value::Array(results));
    keys
}

/// Whether every report says it converged.
fn all_converged(results: &[Value]) -> bool {
    results.iter().all(|r| r["converged"] == json!(true))
}

/// The largest value of `key` over the reports (0 when none has one).
fn largest(results: &[Value], key: &str) -> f64 {
    results
        .iter()
        .filter_map(|r| r[key].as_f64())
        .fold(0.0, f64::max)
}

/// Whether fairing made the highlight lines of any region worse
/// ([`FairReport::highlight_deviation_worse`], or the largest deviation
/// over the regions grew).
pub fn regions_made_worse(results: &[FairReport]) -> bool {
    let (before, after) = regions_deviation(results);
    after > before || results.iter().any(|r| r.highlight_deviation_worse)
}

/// Whether the result of fairing is not what was asked for, so that front
/// ends exit 1 (after the warnings of [`regions_warnings`]): the
/// highlight-line deviation got worse ([`regions_made_worse`]) and
/// detection does not confirm that the defect is gone — inside the faired
/// regions, the detection score after fairing is above its threshold or
/// the flat-spot value above its floor (a floor of 0 means the flat-spot
/// measure is off). Where detection confirms the removal, a grown
/// deviation is a warning only: the lines around the removed defect
/// moved, which that measure reads as change.
pub fn fairing_made_worse(
    results: &[FairReport],
    (score_after, threshold): (f64, f64),
    (flat_after, flat_floor): (f64, f64),
) -> bool {
    let removed = score_after <= threshold && (flat_floor <= 0.0 || flat_after <= flat_floor);
    regions_made_worse(results) && !removed
}

/// The highlight-line deviation of the faired regions, before and after
/// (the largest over the regions; 0 when none was faired).
pub fn regions_deviation(results: &[FairReport]) -> (f64, f64) {
    let results: Vec<Value> = results
        .iter()
        .filter_map(|r| serde_json::to_value(r).ok())
        .collect();
    (
        largest(&results, "highlight_deviation_before"),
        largest(&results, "highlight_deviation_after"),
    )
}

/// What fairing `results` of `attempted` regions with at most
/// `max_iterations` iterations per region warns about: there were regions
/// but none was faired (none to fair is no warning); a region did not
/// converge;
/// the highlight-line deviation got worse (with the detection score inside
/// the regions before and after, `detection_scores`, as `detect` measures
/// it).
pub fn regions_warnings(
    results: &[FairReport],
    attempted: usize,
    max_iterations: usize,
    detection_scores: (f64, f64),
) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if results.is_empty() && attempted > 0 {
        warnings.push(Warning::NothingFaired { regions: attempted });
    }
    if !results.iter().all(|r| r.converged) {
        warnings.push(Warning::FairNotConverged { max_iterations });
    }
    let (before, after) = regions_deviation(results);
    let (score_before, score_after) = detection_scores;
    if regions_made_worse(results) {
        warnings.push(Warning::DeviationWorse {
            before,
            after,
            score_before,
            score_after,
        });
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warning::FrontEnd;
    use fairline::fair::{FairMethod, FairOptions, fair_highlight_lines};
    use fairline::mesh::bounding_box;
    use fairline::{Vec3, shapes};

    /// Two small bumps (at x = ∓0.5) on a crowned panel, their regions,
    /// the lights.
    fn two_bumps() -> (SurfaceMesh, Vec<Vec<FaceId>>, LightArray) {
        let mesh = shapes::height_field(121, 91, (-1.0, 1.0), (-0.75, 0.75), |x, y| {
            let bump = |cx: f64| 0.003 * (-((x - cx).powi(2) + y * y) / (0.1 * 0.1)).exp();
            0.3 * (1.0 - 0.45 * x * x - 0.25 * y * y) + bump(-0.5) + bump(0.5)
        });
        let region = |cx: f64| {
            fairline::io::RegionSpec::Sphere {
                center: Vec3::new(cx, 0.0, 0.0),
                radius: 0.35,
            }
            .faces(&mesh)
            .unwrap()
        };
        let regions = vec![region(-0.5), region(0.5)];
        let (lo, hi) = bounding_box(mesh.positions()).unwrap();
        (mesh, regions, LightArray::default_for(lo, hi, None))
    }

    fn fair_in_turn(
        mesh: &SurfaceMesh,
        regions: &[Vec<FaceId>],
        options: &FairOptions,
    ) -> Vec<FairReport> {
        let mut current = mesh.clone();
        regions
            .iter()
            .map(|faces| {
                let out =
                    fair_highlight_lines(&current, &options.clone().region(faces.clone())).unwrap();
                current.set_positions(out.positions).unwrap();
                out.report
            })
            .collect()
    }

    #[test]
    fn one_region_reports_itself_and_several_are_summed_up() {
        let (mesh, regions, light) = two_bumps();
        let options = FairOptions::default()
            .light(light)
            .method(FairMethod::DiffusionFlow)
            .max_iterations(2)
            .epsilon(1e-14);
        let reports = fair_in_turn(&mesh, &regions, &options);
        // one region: its own keys, exactly
        let one = regions_report(&reports[..1], 0.5);
        assert_eq!(
            Value::Object(one),
            serde_json::to_value(&reports[0]).unwrap()
        );
        // two: sums, maxima, the caller's displacement, each region's report
        let both = regions_report(&reports, 0.25);
        let (a, b) = (&reports[0], &reports[1]);
        assert_eq!(both["iterations"], json!(a.iterations + b.iterations));
        assert_eq!(
            both["movable_vertices"],
            json!(a.movable_vertices + b.movable_vertices)
        );
        assert_eq!(
            both["willmore_before"],
            json!(a.willmore_before + b.willmore_before)
        );
        assert_eq!(
            both["highlight_deviation_after"],
            json!(a.highlight_deviation_after.max(b.highlight_deviation_after))
        );
        assert_eq!(both["converged"], json!(a.converged && b.converged));
        assert_eq!(both["max_displacement"], json!(0.25));
        assert_eq!(both["per_region"].as_array().map(Vec::len), Some(2));
        assert_eq!(
            regions_deviation(&reports),
            (
                a.highlight_deviation_before
                    .max(b.highlight_deviation_before),
                a.highlight_deviation_after.max(b.highlight_deviation_after)
            )
        );
        // 2 iterations of diffusion flow do not reach ε = 1e-14: said once
        assert!(!a.converged);
        let w: Vec<String> = regions_warnings(&reports, reports.len(), 2, (1.0, 0.5))
            .iter()
            .map(|w| w.message(FrontEnd::Cli))
            .collect();
        assert_eq!(
            w[0],
            "fairing did not converge within --max-iterations 2; try more iterations or a larger region (--grow, --auto)"
        );
        assert!(w.iter().all(|s| !s.starts_with("no region was faired")));
        // regions but none faired: said, and nothing else
        let none: Vec<String> = regions_warnings(&[], 2, 3, (0.0, 0.0))
            .iter()
            .map(|w| w.message(FrontEnd::Cli))
            .collect();
        assert_eq!(
            none,
            vec![
                "no region was faired: none of the 2 regions to fair has a vertex free to move (see skipped_regions in the report); the output is the input unchanged"
            ]
        );
        // no region to fair: nothing went wrong, no warning, no claim of
        // convergence
        assert!(regions_warnings(&[], 0, 3, (0.0, 0.0)).is_empty());
        assert!(regions_report(&[], 0.0).get("converged").is_none());
    }

    /// A region whose highlight deviation grew is flagged in its report and
    /// in the run's, the warning names the numbers, and front ends learn
    /// that the result is not as asked (exit 1); one that improved is not.
    #[test]
    fn a_worse_highlight_deviation_is_flagged_and_warned_about() {
        let (mesh, regions, light) = two_bumps();
        let options = FairOptions::default().light(light).max_iterations(3);
        let mut reports = fair_in_turn(&mesh, &regions, &options);
        for r in &reports {
            assert_eq!(
                r.highlight_deviation_worse,
                r.highlight_deviation_after > r.highlight_deviation_before
            );
            assert!(!r.highlight_deviation_worse, "{r:?}");
        }
        assert!(!regions_made_worse(&reports));
        assert!(
            regions_warnings(&reports, reports.len(), 3, (2.0, 0.5))
                .iter()
                .all(|w| !matches!(w, Warning::DeviationWorse { .. }))
        );
        assert_eq!(
            regions_report(&reports, 0.1)["highlight_deviation_worse"],
            json!(false)
        );
        // the second region made worse
        let b = &mut reports[1];
        b.highlight_deviation_after = 3.0 * b.highlight_deviation_before;
        b.highlight_deviation_worse = true;
        assert!(regions_made_worse(&reports));
        assert_eq!(
            regions_report(&reports, 0.1)["highlight_deviation_worse"],
            json!(true)
        );
        // exit 1 unless detection confirms the defect is gone
        assert!(fairing_made_worse(&reports, (2.5, 1.0), (0.0, 0.5)));
        assert!(fairing_made_worse(&reports, (0.5, 1.0), (0.8, 0.5)));
        assert!(!fairing_made_worse(&reports, (0.5, 1.0), (0.2, 0.5)));
        reports[1].highlight_deviation_worse = false;
        reports[1].highlight_deviation_after = 0.5 * reports[1].highlight_deviation_before;
        assert!(!fairing_made_worse(&reports, (2.5, 1.0), (0.0, 0.5)));
        reports[1].highlight_deviation_after = 3.0 * reports[1].highlight_deviation_before;
        reports[1].highlight_deviation_worse = true;
        let w: Vec<String> = regions_warnings(&reports, reports.len(), 3, (2.0, 2.5))
            .iter()
            .map(|w| w.message(FrontEnd::Cli))
            .collect();
        assert!(
            w.iter()
                .any(|s| s.contains("got worse") && s.contains("2.00 -> 2.50")),
            "{w:?}"
        );
    }

    #[test]
    fn detected_regions_are_grown_and_mapped_to_the_input_faces() {
        let (mesh, _, light) = two_bumps();
        let (det, grown) =
            detect_regions_to_fair(&mesh, light, HighlightOptions::default()).unwrap();
        assert_eq!(det.regions.len(), grown.len());
        assert!(!det.regions.is_empty(), "two bumps are defects");
        for (r, g) in det.regions.iter().zip(&grown) {
            assert_eq!(g, &grow_region(&mesh, &r.faces, AUTO_RINGS));
            assert!(g.len() > r.faces.len());
        }
        let union = regions_union(&grown);
        assert!(union.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(
            union.len(),
            grown
                .iter()
                .flatten()
                .collect::<std::collections::BTreeSet<_>>()
                .len()
        );
        // triangles of quads (two per quad) map to their quad, sorted,
        // without repeats
        let source: Vec<FaceId> = (0..mesh.face_count() as u32)
            .map(|f| FaceId(f / 2))
            .collect();
        let faces = [FaceId(5), FaceId(0), FaceId(3), FaceId(1)];
        assert_eq!(input_faces(&faces, Some(&source)), vec![0, 1, 2]);
        assert_eq!(input_faces(&faces, None), vec![0, 1, 3, 5]);
        let suggested = suggested_region(&mesh, &det, None);
        assert_eq!(
            suggested,
            input_faces(&grow_region(&mesh, &det.all_faces(), SUPPORT_RINGS), None)
        );
        let entries = detected_region_entries(&det, None);
        assert_eq!(entries.len(), det.regions.len());
        assert_eq!(entries[0].faces, det.regions[0].faces.len());
        assert_eq!(entries[0].score, det.regions[0].score);
    }
}
