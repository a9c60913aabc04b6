//! Continuity across the patch boundaries of the real parts in
//! ../shared/data/surfaces, with the defaults of
//! `fairline continuity` (position tolerance 1e-4 × the control points'
//! bounding-box diagonal, 0.5°, 5 % curvature). The numbers are those of
//! the table of docs/guide/inspect-cad.md, "Continuity across patch
//! boundaries", stated as bounds.
//!
//! Shared edges are found between the patches' boundaries: the sides of
//! untrimmed patches (the teapot), the trimming curves of trimmed ones (the
//! impeller).

#[path = "support/shared_data.rs"]
mod shared_data;

use fairline::bspline::BSplineSurface;
use fairline::bspline::continuity::{Boundary, ContinuityOptions, Seam, SeamClass, continuity};
use fairline::io::{read_iges, read_surfaces_json};

/// Edges per class (gap, G0, G1, G2) and the worst angle (degrees) and
/// relative curvature mismatch over the edges of each class.
fn summary<'a>(seams: impl IntoIterator<Item = &'a Seam>) -> ([usize; 4], [f64; 4], [f64; 4]) {
    let (mut n, mut angle, mut curvature) = ([0; 4], [0.0f64; 4], [0.0f64; 4]);
    for s in seams {
        let c = match s.class {
            SeamClass::Gap => 0,
            SeamClass::G0 => 1,
            SeamClass::G1 => 2,
            SeamClass::G2 => 3,
        };
        n[c] += 1;
        angle[c] = angle[c].max(s.g1_max_deg);
        curvature[c] = curvature[c].max(s.g2_max_relative);
    }
    (n, angle, curvature)
}

/// The Utah teapot's 32 bicubic Bézier patches: 76 shared edges; the
/// seams inside the body, lid, handle and spout are exact G1 or G2 joins
/// (angles and curvature mismatches at rounding level), the rim is a crease
/// (G0), and the handle and spout meet the body without shared edges
/// (gaps).
#[test]
fn continuity_of_the_teapot() {
    let Some(path) = shared_data::shared_data("surfaces/teapot.json") else {
        return;
    };
    let surfaces = read_surfaces_json(&path).unwrap();
    assert_eq!(surfaces.len(), 32);
    let r = continuity(&surfaces, &ContinuityOptions::default()).unwrap();
    let (n, angle, curvature) = summary(&r.seams);
    eprintln!(
        "teapot: {} edges, gap/G0/G1/G2 {n:?}, worst angle {angle:?}, worst curvature {curvature:?}",
        r.seams.len()
    );
    assert_eq!(r.seams.len(), 76);
    assert_eq!(r.degenerate_sides, 4);
    assert!(n[3] >= 30 && n[2] + n[3] >= 46, "{n:?}");
    assert!(n[1] <= 6 && n[0] <= 26, "{n:?}");
    // the G1 and G2 seams are exact joins
    assert!(angle[2] < 1e-9 && angle[3] < 1e-9, "{angle:?}");
    assert!(curvature[3] < 1e-9, "{curvature:?}");
    // the rim crease
    assert!(angle[1] > 100.0, "{angle:?}");
}

/// The impeller's 277 faces (247 B-spline, 30 of revolution), all
/// trimmed: their boundaries are their trimming curves, so the shared edges
/// are the seams of the trimmed faces — among them the blades' roots on
/// the hub (faces of revolution against B-spline faces). Before trims were
/// used (the untrimmed sides): 2096 edges, 831 gaps and 1061 G0 edges, most
/// of them sides meeting along trims.
#[test]
fn continuity_of_the_impeller() {
    let Some(path) = shared_data::shared_data("surfaces/impeller.igs") else {
        return;
    };
    let import = read_iges(&path).unwrap();
    let revolved: Vec<bool> = import
        .surfaces
        .iter()
        .map(|s| s.entity_type == 120)
        .collect();
    let surfaces: Vec<BSplineSurface> = import.surfaces.into_iter().map(|s| s.surface).collect();
    assert_eq!(surfaces.len(), 277);
    assert!(surfaces.iter().all(|s| s.is_trimmed()));
    let r = continuity(&surfaces, &ContinuityOptions::default()).unwrap();
    let (n, angle, curvature) = summary(&r.seams);
    // Seams between a face of revolution (the hub) and a B-spline face.
    let hub: Vec<&Seam> = r
        .seams
        .iter()
        .filter(|s| revolved[s.surfaces[0]] != revolved[s.surfaces[1]])
        .collect();
    let hub_closed = hub.iter().filter(|s| s.class != SeamClass::Gap).count();
    // Classes (gap, G0, G1, G2) of the dish–blade-root seams (a face of
    // revolution against a B-spline face) and of the dish–dish seams (two
    // faces of revolution), with the worst angle and curvature mismatch.
    let classes = |pick: &dyn Fn(&&Seam) -> bool| summary(r.seams.iter().filter(|s| pick(s)));
    let root = classes(&|s| revolved[s.surfaces[0]] != revolved[s.surfaces[1]]);
    let dish = classes(&|s| revolved[s.surfaces[0]] && revolved[s.surfaces[1]]);
    eprintln!(
        "impeller dish–blade-root seams: gap/G0/G1/G2 {:?}, worst angle {:?}, worst curvature {:?}",
        root.0, root.1, root.2
    );
    eprintln!(
        "impeller dish–dish seams: gap/G0/G1/G2 {:?}, worst angle {:?}, worst curvature {:?}",
        dish.0, dish.1, dish.2
    );
    // The blade roots stand on the dish without a fillet: every closed
    // dish–blade-root seam is a crease (G0, 45°–124°), none is G1 or G2.
    assert_eq!(root.0[2] + root.0[3], 0, "{:?}", root.0);
    assert!(root.0[1] >= 80, "{:?}", root.0);
    let smallest_root_crease = r
        .seams
        .iter()
        .filter(|s| revolved[s.surfaces[0]] != revolved[s.surfaces[1]] && s.class == SeamClass::G0)
        .map(|s| s.g1_max_deg)
        .fold(f64::INFINITY, f64::min);
    assert!(smallest_root_crease > 40.0, "{smallest_root_crease}");
    // The dish's own seams: exact G2 joins (19 measured) besides its
    // ridges and the gaps at its rim.
    assert!(dish.0[3] >= 15 && dish.0[2] == 0, "{:?}", dish.0);
    // The G1-but-not-G2 seams are all between B-spline faces (blade,
    // root and fillet patches): tangent within 0.3°, curvature jumping.
    assert!(
        r.seams
            .iter()
            .filter(|s| s.class == SeamClass::G1)
            .all(|s| !revolved[s.surfaces[0]] && !revolved[s.surfaces[1]])
    );
    eprintln!(
        "impeller: {} edges, gap/G0/G1/G2 {n:?}, worst angle {angle:?}, worst curvature {curvature:?}; hub–B-spline seams {} ({hub_closed} closed)",
        r.seams.len(),
        hub.len()
    );
    // every edge is a trimming curve against a trimming curve
    assert!(
        r.seams
            .iter()
            .all(|s| s.sides.iter().all(|b| matches!(b, Boundary::Trim(_))))
    );
    assert!(r.seams.len() >= 800, "{}", r.seams.len());
    assert!(n[2] >= 380 && n[3] >= 60, "{n:?}");
    assert!(n[0] <= 130, "{n:?}");
    assert!(angle[3] < 0.03, "{angle:?}");
    assert!(curvature[3] < 0.05, "{curvature:?}");
    // 128 measured, 84 of them closed (G0 or better)
    assert!(
        hub.len() >= 120 && hub_closed >= 80,
        "{} {hub_closed}",
        hub.len()
    );
    // every G0-or-better edge closes within the tolerance
    for s in &r.seams {
        if s.class != SeamClass::Gap {
            assert!(s.g0_max <= r.tolerance * (1.0 + 1e-9), "{}", s.g0_max);
        }
    }
}
