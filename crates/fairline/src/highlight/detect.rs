//! Detection of surface defects that disturb highlight lines, and their
//! conversion into suggested fairing regions (beyond Yong et al.: §3.1
//! leaves the choice of the irregular region R to the user; this module
//! proposes one).
//!
//! # The measure: the surface against its own smooth version
//!
//! A highlight line is displaced where the surface normal differs from the
//! normal the "intended" smooth surface would have there (Yong et al.
//! Eq. (1): d_P depends on the normal N_P). The lines themselves are not
//! judged node by node: where |∇d| is small (summits, saddles) the O(h)
//! error of vertex normals becomes large node jitter along the line that a
//! curvature test on polylines reads as wiggles, more so on finer meshes
//! (DESIGN.md §3, last note on Yong et al.). Instead the normals are
//! compared at two scales:
//!
//! 1. **Sites.** One vertex per cube of side `site_spacing`·s (default s/4,
//!    s the light spacing); the sites cover the surface evenly whatever the
//!    triangle size.
//! 2. **Fine scale — what the surface is.** At each site a weighted
//!    least-squares quadric height field over the vertices within
//!    r_f = max(`fine_radius`·s, 2.5 h) (h the mean edge length) gives the
//!    site's denoised position p̂ and normal n̂. A fit instead of the vertex
//!    normal makes the measure independent of the triangulation (vertex
//!    normals carry an O(h) error on irregular meshes); its weighted RMS
//!    residual is the local noise of the sampling.
//! 3. **Coarse scale — what the surface should be.** Around each site, a
//!    cubic height field over the tangent plane is fitted to the positions
//!    *and* normals of the sites within R = `smooth_radius`·s (default
//!    1.5 s), leaving out those within 0.35 R of the judged site (the fit
//!    interpolates across the hole, so a defect there does not bend it
//!    toward itself), by iteratively reweighted least squares (Tukey
//!    biweight on the normal residuals, three passes), so a defect's slope
//!    does not bend the smooth fit either. Smooth shape — strong curvature,
//!    saddles, cylinders, tori — is a cubic to within the fit's truncation
//!    error O(|∇³n|·R⁴) and is not reported; a bump, dent, flat spot,
//!    ripple or kink of lateral size up to about R is not a cubic and is.
//!    Where the neighbourhood is one-sided (near a mesh boundary: its
//!    weighted centroid lies more than 0.05 R from the site) the fit keeps
//!    the near sites and shrinks to 0.6 R, since a one-sided cubic errs
//!    more at its edge; mesh-boundary vertices themselves are not judged.
//! 4. **Score.** θ = angle between the fine normal n̂ and the coarse fit's
//!    normal at the site; L = distance of p̂ from the light plane (at least
//!    s). A normal error θ displaces the highlight line of a light array at
//!    distance L, seen head on, by about L·θ; the score is that displacement
//!    in tenths of a spacing:
//!
//!    **score = θ·L / (0.1·s)** — a score of 1 means the highlight line is
//!    displaced by one tenth of the light spacing against the line the
//!    smooth surface would show. The score does not depend on the light
//!    direction H: the normal error is compared in every direction at once,
//!    which is what a set of light arrays rotated about Z would show.
//! 5. **Noise.** The noise level is the median fine-fit residual (mesh
//!    units, reported), and the score noise the median site score. A site
//!    is flagged when its score exceeds max(`threshold`, `noise_factor` ×
//!    median score) (defaults 1 and 4): on a clean model the median score
//!    is far below 1 and the threshold is 1; on a noisy scan the threshold
//!    rises above the noise and only what stands out of it is flagged.
//! 6. **Shape finer than the scale.** The measure assumes the intended
//!    surface is smooth at the scale R. Where the normals within R turn by
//!    more than `max_turn` (default 1 rad, κ·R ≳ 1) from the site's normal
//!    — the ears and horns of a figure, a crease, a fillet or a thin wall
//!    narrower than R — no cubic over R stands for it, and the fit's misfit
//!    would be read as a defect of enormous score. Such sites are shape, not
//!    defects at this scale: they are not judged and are counted apart
//!    ([`Detection::shape_sites`]). A denser array (smaller spacing) judges
//!    them at their own scale.
//! 7. **Discretisation.** A coarse mesh is a faceted surface: its normal
//!    turns by the facet angle δ ≈ κ·h from one face to the next (κ the
//!    curvature, h the edge length), and where the artist modelled strong
//!    but smooth shape with few edges — the junctions of head and body, of
//!    leg and belly — the surface between the vertices is not known to
//!    better than a fraction of δ. The fits turn part of that into normal
//!    error: θ grows with δ over the whole mesh. The measure estimates that
//!    part per mesh, as it estimates a scan's noise: the *discretisation
//!    level* α = median over the judged sites of θ/δ (δ the mean facet
//!    angle within the fine radius, [`Site::facet_angle`]), and raises the
//!    threshold at each site to `discretisation_factor`·α·δ/θ₀ (default
//!    factor 10, in score units): a site is flagged only where its normal
//!    error stands far above what its own facets explain. The factor is
//!    larger than the noise factor of a scan because this error is not
//!    spread evenly: it gathers where curvature changes within a few
//!    edges. Measured on the artist meshes of ../shared/data (spot,
//!    bunny_npm; and the bunny scan), θ/δ reaches 4.6–7.4 times its median
//!    at those junctions, while a planted 0.1 %-of-diagonal defect on a
//!    mesh that resolves it stands 10⁴ times above its mesh's median (its
//!    own facets turn by a small fraction of a degree): on such meshes the
//!    floor stays far below the threshold and changes nothing. Sites above
//!    the mesh's threshold but below their discretisation floor are
//!    counted ([`Detection::discretisation_sites`]).
//! 8. **Flat spots wider than R.** A dent or flat spot wider than about R
//!    bends the cubic of step 3 with it and scores low. What it does to
//!    the surface is to take away its curvature over its area, while the
//!    surface smoothed at a wavelength of 4 R ([`FLAT_SPOT_WAVELENGTH`])
//!    keeps curving. The second measure ([`Site::flat_spot`]) is the
//!    relative drop of curvature (κ_s − κ)/κ_s in the smoothed surface's
//!    most curved direction (1: flat, above 1: curving the other way),
//!    the median over the sites within 0.35 R, judged where the smoothed
//!    surface's curvature stands above `flat_spot_factor` times the mesh's
//!    curvature noise ([`Detection::curvature_noise`]) and flagged above
//!    max(0.5, `flat_spot_factor` × its 90th percentile over the mesh)
//!    ([`Detection::flat_spot_floor`]); details and measurements in
//!    `detect/flat_spot.rs`. The wide dent on Spot's flank (radius 0.3,
//!    2 % of the diagonal deep, R = 0.24) scores 0.94 against its floor
//!    0.54; clean Spot, bunny_npm, the bunny scan and every generated
//!    family stay below their floors.
//!
//! # Regions
//!
//! The faces whose centroid lies within `region_margin`·s (default 1 s)
//! of a flagged site are united — the margin scaled by R/(`smooth_radius`·s)
//! where the mesh is too coarse for the spacing and R was raised to 2 r_f
//! (step 2): the defects found are then up to about that larger R across,
//! and a margin of one spacing would leave most of a defect's footprint
//! outside its region (on Spot, R is 3.8 times 1.5 s; the margin of a
//! 0.3-wide dent on its flank goes from 0.063 to 0.159). Each connected
//! component, with the holes
//! it encloses filled (a bump's summit has the smooth normal, its flanks
//! do not), is a suggested region. Sites flagged by the flat-spot measure
//! (step 8) add their faces in the same way, except where they lie in a
//! region the normal measure's sites already make: those sites sit on a
//! defect's flanks and outline it, and a flat spot at its centre is the
//! same defect. A region's score is the largest score of the flagged sites
//! inside, its flat spot the largest flat-spot value, and its severity how
//! many times its strongest site exceeds the threshold (or floor) of the
//! measure that flagged it; regions are ranked by severity. Sites where no fit is possible (fewer
//! sites than coefficients inside R, normals turning by more than 72°) are
//! not judged and counted in the result.

mod fits;
/// The flat-spot measure (module documentation, step 8).
mod flat_spot;
mod grid;
mod noise;
mod options;
mod regions;
mod report;
mod sites;
mod whole;

pub use options::DetectOptions;
pub use report::{Detection, IrregularRegion, LineFairness, Site};
pub use whole::{MAX_FINER_ARRAYS, NOT_JUDGED_SHARE, detect_whole_part};

use super::{HighlightError, HighlightLines, LightArray};
use crate::geom;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use noise::NoiseFloors;
use regions::{
    area_share, connected_regions, faces_near_sites, fill_holes, lines_crossing_regions,
    normal_flagged, score_regions,
};
use sites::{Scale, fine_fits, judge_sites, site_vertices, vertex_facet_angles};

/// Wavelength of the smoothing the flat-spot measure compares with, in
/// smooth radii R (module documentation, step 8).
pub const FLAT_SPOT_WAVELENGTH: f64 = 4.0;

/// What `fairline detect` says about a mesh, with the best site inside a
/// face region: the measure of `fair`'s report before and after fairing
/// and of its warning, so that they say what `detect` on the result would
/// say (same lights, default [`DetectOptions`], every site with its own
/// threshold).
#[derive(Clone, Debug, PartialEq)]
pub struct RegionDetection {
    /// The detection of the whole mesh.
    pub detection: Detection,
    /// Largest score at the sites on the vertices of the region's faces (0
    /// when none is judged).
    pub score: f64,
    /// The threshold detection applied at that site (the mesh's threshold
    /// when none is judged).
    pub threshold: f64,
    /// Largest flat-spot value ([`Site::flat_spot`]) at the sites on the
    /// vertices of the region's faces (0 when none is judged); flagged
    /// above [`Detection::flat_spot_floor`].
    pub flat_spot: f64,
    /// Per region of [`Self::detection`]: whether it shares a face with
    /// the given face region.
    pub overlaps: Vec<bool>,
}

/// Detection with the default [`DetectOptions`] under `light` (the
/// highlight lines computed with `highlight`), as `fairline detect` runs
/// it, and its best site inside the face region `faces` (see
/// [`RegionDetection`]). Faces out of range are ignored.
pub fn detect_region(
    mesh: &SurfaceMesh,
    light: &LightArray,
    highlight: super::HighlightOptions,
    faces: &[FaceId],
) -> Result<RegionDetection, HighlightError> {
    let options = DetectOptions::default();
    let model = super::HighlightModel::new(mesh, *light, highlight)?;
    let lines = model.lines(mesh);
    let detection = detect_whole_part(mesh, light, &lines, &options)?;
    let mut in_faces = vec![false; mesh.face_count()];
    let mut inside = vec![false; mesh.vertex_count()];
    for f in faces {
        if f.idx() < mesh.face_count() {
            in_faces[f.idx()] = true;
            for v in mesh.face_vertices(*f) {
                inside[v.idx()] = true;
            }
        }
    }
    let (score, threshold) = detection
        .sites
        .iter()
        .filter(|s| inside[s.vertex.idx()])
        .filter_map(|s| s.score.map(|sc| (sc, s.threshold)))
        .fold(
            (0.0, detection.threshold),
            |a, b| if b.0 > a.0 { b } else { a },
        );
    let flat_spot = detection
        .sites
        .iter()
        .filter(|s| inside[s.vertex.idx()])
        .filter_map(|s| s.flat_spot)
        .fold(0.0, f64::max);
    let overlaps = detection
        .regions
        .iter()
        .map(|r| r.faces.iter().any(|f| in_faces[f.idx()]))
        .collect();
    Ok(RegionDetection {
        detection,
        score,
        threshold,
        flat_spot,
        overlaps,
    })
}

/// Finds surface defects that displace the highlight lines of `light` and
/// turns them into suggested fairing regions (see the module documentation
/// for the measure, its score, its noise floors and defaults). `lines` are
/// the highlight lines of `light` on `mesh` (used only to report which
/// lines cross each region). The mesh is not changed and no positions are
/// returned: detection only reads the surface and the lines given.
/// Errors on non-triangle meshes, invalid options, and
/// [`HighlightError::Cancelled`] when `options.control` asks to stop
/// (checked between the stages: sites, fine fits, smooth fits, regions).
pub fn detect_irregularities(
    mesh: &SurfaceMesh,
    light: &LightArray,
    lines: &HighlightLines,
    options: &DetectOptions,
) -> Result<Detection, HighlightError> {
    mesh.require_triangles()?;
    options.validate()?;
    let control = &options.control;
    const STAGES: u64 = 5;
    let scale = Scale::new(mesh, light, options);
    let normals = geom::vertex_normals(mesh);
    let site_vertices = site_vertices(mesh.positions(), &normals, scale.site_cell);
    control.step("detect", 1, STAGES)?;
    let facets = vertex_facet_angles(mesh);
    let fine = fine_fits(mesh.positions(), &normals, &facets, &site_vertices, &scale);
    control.step("detect", 2, STAGES)?;
    let judgements = judge_sites(mesh, light, &site_vertices, &fine, &scale, options);
    control.step("detect", 3, STAGES)?;
    let shape_sites = judgements.iter().filter(|j| j.shape).count();
    let floors = NoiseFloors::estimate(&judgements, &fine, options);
    let mut sites: Vec<Site> = site_vertices
        .iter()
        .zip(&fine)
        .zip(&judgements)
        .map(|((&v, f), j)| Site {
            vertex: VertexId(v),
            position: f.map_or(mesh.positions()[v as usize], |f| f.position),
            score: j.score,
            facet_angle: f.map_or(0.0, |f| f.facet_angle),
            threshold: floors.at(j, f.as_ref()),
            flat_spot: None,
        })
        .collect();
    let flat = flat_spot::flat_spots(
        mesh,
        &sites,
        scale.smooth_radius,
        scale.fine_radius,
        options.flat_spot_factor,
    );
    for (site, v) in sites.iter_mut().zip(&flat.values) {
        site.flat_spot = *v;
    }
    control.step("detect", 4, STAGES)?;
    let flagged: Vec<usize> = (0..sites.len())
        .filter(|&i| normal_flagged(&sites[i]) || flat.flagged(i))
        .collect();
    let flat_spot_sites = (0..sites.len()).filter(|&i| flat.flagged(i)).count();
    let discretisation_sites = sites
        .iter()
        .filter(|s| {
            s.score
                .is_some_and(|sc| sc > floors.threshold && sc <= s.threshold)
        })
        .count();
    let margin =
        (options.region_margin * scale.spacing * scale.coarsening(options)).max(scale.site_cell);
    // the normal measure's flagged sites lie where the normals deviate,
    // on a defect's flanks, and outline it; a flat spot at the centre of
    // a defect they outline is the same defect and leaves its region as
    // it is, while flat spots elsewhere make regions of their own
    let by_normal: Vec<usize> = flagged
        .iter()
        .copied()
        .filter(|&i| normal_flagged(&sites[i]))
        .collect();
    let mut in_region = faces_near_sites(mesh, &sites, &by_normal, margin);
    let flat_elsewhere: Vec<usize> = flagged
        .iter()
        .copied()
        .filter(|&i| {
            !normal_flagged(&sites[i])
                && !mesh
                    .vertex_faces(sites[i].vertex)
                    .any(|f| in_region[f.idx()])
        })
        .collect();
    for (f, near) in faces_near_sites(mesh, &sites, &flat_elsewhere, margin)
        .into_iter()
        .enumerate()
    {
        in_region[f] |= near;
    }
    fill_holes(mesh, &mut in_region);
    let areas = geom::face_areas(mesh);
    let total_area: f64 = areas.iter().sum();
    let (mut regions, component) = connected_regions(mesh, &in_region, &areas);
    score_regions(mesh, &sites, &flagged, flat.floor, &component, &mut regions);
    let line_out = lines_crossing_regions(mesh, lines, &in_region, &component, &mut regions);
    control.step("detect", 5, STAGES)?;
    regions.retain(|r| r.severity > 0.0);
    for r in &mut regions {
        r.lines.sort_unstable();
        r.spacing = scale.spacing;
    }
    regions.sort_by(|a, b| {
        b.severity
            .total_cmp(&a.severity)
            .then(b.score.total_cmp(&a.score))
            .then(a.faces.cmp(&b.faces))
    });
    // a fold from +0.0 (an empty `sum` of f64 is −0.0, which reports print)
    let region_area: f64 = regions.iter().map(|r| r.area).fold(0.0, |a, b| a + b);
    let flagged_area_fraction = if total_area > 0.0 {
        (region_area / total_area).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut detection = Detection {
        regions,
        lines: line_out,
        flagged_sites: flagged.len(),
        sites,
        judged_sites: floors.judged_sites,
        shape_sites,
        threshold: floors.threshold,
        median_score: floors.median_score,
        noise_level: floors.noise_level,
        facet_angle: floors.facet_angle,
        discretisation_level: floors.discretisation_level,
        discretisation_sites,
        flagged_area_fraction,
        fine_radius: scale.fine_radius,
        smooth_radius: scale.smooth_radius,
        flat_spot_sites,
        flat_spot_floor: flat.floor,
        curvature_noise: flat.curvature_noise,
        site_cell: scale.site_cell,
        not_judged_fraction: 0.0,
        spacings: vec![scale.spacing],
        unjudged_faces: Vec::new(),
    };
    detection.unjudged_faces = detection.nearest_unjudged_faces(mesh);
    detection.not_judged_fraction = area_share(&detection.unjudged_faces, &areas, total_area);
    Ok(detection)
}
