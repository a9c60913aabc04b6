//! Default lights and detection on every real mesh of ../shared/data/meshes:
//! the lines a user sees with no options are readable and not
//! fragmented, and detection gives stable, explainable results.
//!
//! "Unfragmented" in numbers, for the drawn (readable) lines: at least 6
//! lights show, and half of the drawn length lies in pieces at least 0.15
//! of the part's width across the lights long (N50, the length-weighted
//! median piece length; the plain median and pieces per light are printed
//! too, but a scan's many small closed loops around its real bumps pull
//! those down without making the long lines any less readable). The same
//! numbers for the detail lights (the spacing of detection, drawn as they
//! are) are printed beside them: what the defaults gave before.

use fairline::SurfaceMesh;
use fairline::highlight::readable::part_width;
use fairline::highlight::{
    DetectOptions, HighlightModel, HighlightOptions, LightArray, LineStats, Readability, UpAxis,
    detect_irregularities,
};

#[path = "support/shared_data.rs"]
mod shared_data;

/// Every mesh of ../shared/data/meshes, read as the commands read them;
/// the two dirty ones go through `repair` first, as the CLI's hint says.
const MESHES: [&str; 7] = [
    "meshes/bob_small.ply",
    "meshes/bunny_npm.obj",
    "meshes/bunny_res4.ply",
    "meshes/bunny_zipper.ply",
    "meshes/elephant_nonmanifold.obj",
    "meshes/lego_open.ply",
    "meshes/spot.ply",
];

fn load(rel: &str) -> Option<SurfaceMesh> {
    let path = shared_data::shared_data(rel)?;
    if let Ok(mesh) = fairline::io::read_mesh(&path) {
        return Some(mesh);
    }
    let soup = fairline::io::read_soup(&path).unwrap();
    let repaired = fairline::mesh::repair(&soup, &Default::default()).unwrap();
    Some(SurfaceMesh::from_soup(&repaired.soup).unwrap())
}

struct Drawn {
    stats: LineStats,
    all: LineStats,
    width: f64,
    spacing: f64,
}

fn drawn(mesh: &SurfaceMesh, light: LightArray) -> Drawn {
    let model = HighlightModel::new(mesh, light, HighlightOptions::default()).unwrap();
    let lines = model.lines(mesh);
    let shown = model.readable_lines(mesh, &lines, &Readability::for_part(mesh, &light));
    Drawn {
        stats: LineStats::of(&shown),
        all: LineStats::of(&lines),
        width: part_width(mesh.positions(), light.across()),
        spacing: light.spacing(),
    }
}

fn describe(d: &Drawn) -> String {
    format!(
        "spacing {:.4} (width/{:.1}): drawn {} pieces on {} lights ({:.2}/light), N50 {:.3} and median {:.3} of width, total {:.2} widths; computed {} pieces on {} lights, N50 {:.3} of width",
        d.spacing,
        d.width / d.spacing,
        d.stats.pieces,
        d.stats.lights,
        d.stats.pieces_per_light,
        d.stats.n50_length / d.width,
        d.stats.median_length / d.width,
        d.stats.total_length / d.width,
        d.all.pieces,
        d.all.lights,
        d.all.n50_length / d.width,
    )
}

#[test]
fn default_lights_give_readable_unfragmented_lines_on_every_real_mesh() {
    for rel in MESHES {
        let Some(mesh) = load(rel) else { return };
        let light = LightArray::readable_for_mesh(&mesh, UpAxis::Auto).unwrap();
        let d = drawn(&mesh, light);
        // the detail lights (the scale of detection), drawn as they are,
        // for comparison: on round parts these are the fragments of old
        let detail = drawn(
            &mesh,
            LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap(),
        );
        println!("{rel}: {}", describe(&d));
        println!("  detail lights: {}", describe(&detail));
        assert!(
            d.stats.lights >= 6,
            "{rel}: too few lines: {}",
            describe(&d)
        );
        assert!(
            d.stats.n50_length >= 0.15 * d.width,
            "{rel}: fragmented: {}",
            describe(&d)
        );
    }
}

#[test]
fn detection_on_real_meshes_is_stable_and_leaves_small_features_as_shape() {
    for rel in MESHES {
        let Some(mesh) = load(rel) else { return };
        let light = LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap();
        let lines = HighlightModel::new(&mesh, light, HighlightOptions::default())
            .unwrap()
            .lines(&mesh);
        let opts = DetectOptions::default();
        let d = detect_irregularities(&mesh, &light, &lines, &opts).unwrap();
        println!(
            "{rel}: {} regions, flagged {:.4} of the area, best score {:.1}, threshold {:.1}, median score {:.2}, sites {} judged / {} shape / {}",
            d.regions.len(),
            d.flagged_area_fraction,
            d.max_score(),
            d.threshold,
            d.median_score,
            d.judged_sites,
            d.shape_sites,
            d.sites.len()
        );
        for r in d.regions.iter().take(5) {
            println!(
                "  score {:.1} at {:.3?}, area {:.4}",
                r.score, r.center, r.area
            );
        }
        println!(
            "  facet angle {:.2}°, discretisation level {:.3}, {} sites within their discretisation floor",
            d.facet_angle.to_degrees(),
            d.discretisation_level,
            d.discretisation_sites
        );
        // explainable: every site is judged, counted as shape finer than
        // the measure's scale, or on a boundary / without a fit; on the
        // coarse figures (250–623 vertices: bob, bunny_res4, elephant) the
        // smooth radius (at least five mean edge lengths) spans their legs,
        // ears and trunks, so everything is shape; on spot and bunny_npm
        // the junctions modelled with few edges (head and body, leg and
        // belly) score above the noise-raised threshold but within their
        // discretisation floor (module documentation of `detect`, step 7)
        // and are counted as such. None of these meshes has a defect that
        // stands out: no region on any of them (docs/guide/inspect-mesh.md,
        // "Default lights on real meshes").
        assert!(d.judged_sites + d.shape_sites <= d.sites.len(), "{rel}");
        assert!(d.regions.is_empty(), "{rel}: {} regions", d.regions.len());
        assert_eq!(d.flagged_area_fraction, 0.0, "{rel}");
        if rel.ends_with("spot.ply") || rel.ends_with("bunny_npm.obj") {
            assert!(d.discretisation_sites > 0, "{rel}: explained");
            assert!(d.discretisation_level > 0.0, "{rel}");
        }
        // stable: the same input gives the same result
        let again = detect_irregularities(&mesh, &light, &lines, &opts).unwrap();
        assert_eq!(d, again, "{rel}");
    }
}

/// A checksum of every site's score and denoised position, in site order.
fn site_checksum(d: &fairline::highlight::Detection) -> u64 {
    let mut h: u64 = 0;
    for (i, s) in d.sites.iter().enumerate() {
        let b = s.score.map_or(7u64, f64::to_bits);
        h = h.rotate_left(7) ^ b.wrapping_mul(i as u64 + 1) ^ s.position.x.to_bits();
    }
    h
}

/// The measure of `detect_irregularities` is pinned: the site scores and
/// positions, and with the noise floors off (both factors 0) the regions,
/// equal bit for bit the recorded checksums and scores below (same
/// lights). The region scores are those of the region margin that grows
/// with R on meshes coarse against the spacing (fewer, larger regions
/// around the same sites).
#[test]
fn detection_scores_equal_the_recorded_ones() {
    type Recorded = (&'static str, u64, &'static [f64]);
    let recorded: [Recorded; 3] = [
        (
            "meshes/spot.ply",
            7160788985567650308,
            // the region margin grows with R on meshes this coarse
            // (R = 3.8 × 1.5 s here), and the flagged sites make three
            // regions: the top three scores
            &[34.64891592583728, 29.557044101557654, 28.683151199758438],
        ),
        (
            "meshes/bunny_npm.obj",
            2465209405891117502,
            // one region, with the margin grown with R
            &[117.79797013972217],
        ),
        ("meshes/lego_open.ply", 10212499764174956624, &[]),
    ];
    for (rel, checksum, scores) in recorded {
        let Some(mesh) = load(rel) else { return };
        let light = LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap();
        let lines = HighlightModel::new(&mesh, light, HighlightOptions::default())
            .unwrap()
            .lines(&mesh);
        let opts = DetectOptions::default()
            .noise_factor(0.0)
            .discretisation_factor(0.0);
        let d = detect_irregularities(&mesh, &light, &lines, &opts).unwrap();
        assert_eq!(site_checksum(&d), checksum, "{rel}");
        let got: Vec<f64> = d.regions.iter().map(|r| r.score).collect();
        assert_eq!(got, scores, "{rel}");
        // the default floors change what is flagged, never the scores
        let d = detect_irregularities(&mesh, &light, &lines, &DetectOptions::default()).unwrap();
        assert_eq!(site_checksum(&d), checksum, "{rel}");
    }
}
