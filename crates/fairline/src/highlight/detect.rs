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
//!    `detect_flat_spot.rs`. The wide dent on Spot's flank (radius 0.3,
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

use super::{HighlightError, HighlightLines, LightArray, NodeId};
use crate::geom;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::solve::{height_monomials, solve_spd};
use crate::{Control, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Wavelength of the smoothing the flat-spot measure compares with, in
/// smooth radii R (module documentation, step 8).
pub const FLAT_SPOT_WAVELENGTH: f64 = 4.0;

/// A small multiplicative hasher for integer cell keys (the default SipHash
/// dominated the neighbour queries); not for untrusted keys, which these
/// are not.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

type Cell = (i64, i64, i64);
type CellMap = HashMap<Cell, Vec<u32>, BuildHasherDefault<CellHasher>>;

/// A uniform grid of points for radius queries.
struct Grid {
    size: f64,
    cells: CellMap,
}

impl Grid {
    fn cell(size: f64, x: Vec3) -> Cell {
        let c = (x / size).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    }
    fn new(size: f64, points: impl Iterator<Item = (u32, Vec3)>) -> Self {
        let mut cells: CellMap = HashMap::default();
        for (i, p) in points {
            cells.entry(Self::cell(size, p)).or_default().push(i);
        }
        Grid { size, cells }
    }
    /// Calls `f` with every stored index in the 27 cells around `x`
    /// (a superset of the points within `size` of `x`).
    fn around(&self, x: Vec3, mut f: impl FnMut(u32)) {
        let (i, j, k) = Self::cell(self.size, x);
        for di in -1..=1 {
            for dj in -1..=1 {
                for dk in -1..=1 {
                    let c = (
                        i.saturating_add(di),
                        j.saturating_add(dj),
                        k.saturating_add(dk),
                    );
                    if let Some(v) = self.cells.get(&c) {
                        for &p in v {
                            f(p);
                        }
                    }
                }
            }
        }
    }
}

/// Options of [`detect_irregularities`]; lengths in light spacings s.
/// Build them with `DetectOptions::default()` and the setters.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct DetectOptions {
    /// Flag sites whose score (highlight displacement in tenths of a
    /// spacing, see the module documentation) exceeds this (default 1).
    pub threshold: f64,
    /// Radius R of the smooth (cubic) fit, in spacings (default 1.5): defects
    /// up to about this lateral size are found; shape at larger scales is
    /// taken as intended.
    pub smooth_radius: f64,
    /// Radius of the fine (quadric) fit, in spacings (default 0.25; at
    /// least 2.5 mean edge lengths are used).
    pub fine_radius: f64,
    /// Distance between sites, in spacings (default 0.25).
    pub site_spacing: f64,
    /// Faces within this distance of a flagged site go into a region, in
    /// spacings (default 1); scaled up with R on meshes too coarse for the
    /// spacing (module documentation, Regions).
    pub region_margin: f64,
    /// The threshold is raised to this many times the median site score,
    /// the score noise of a scan (default 4; 0 turns it off).
    pub noise_factor: f64,
    /// The threshold at each site is raised to this many times the normal
    /// error that the site's own facets explain on this mesh (default 10;
    /// 0 turns it off): the discretisation floor of the module
    /// documentation, step 7.
    pub discretisation_factor: f64,
    /// Largest angle (radians, default 1) by which the surface normals
    /// within the smooth radius R may turn away from a site's normal for
    /// the site to be judged. Where they turn by more (κ·R ≳ 1: ears, horns,
    /// creases, fillets tighter than R) no cubic over R can stand for the
    /// intended surface: the shape there is finer than the scale of the
    /// measure, so it is counted as shape ([`Detection::shape_sites`]) and
    /// not judged. A defect of the kind the measure is for turns the
    /// normal by a few degrees at most (a 0.1 %-of-diagonal bump a spacing
    /// wide: about 1°).
    pub max_turn: f64,
    /// The flat-spot measure's noise factor (default 4; 0 turns the measure
    /// off): a site's area-median relative curvature drop is judged where
    /// the smoothed surface's curvature exceeds this many times the mesh's
    /// curvature noise, and flagged above max(0.5, this many times its 90th
    /// percentile over the mesh) (module documentation, step 8).
    pub flat_spot_factor: f64,
    /// Progress (stage "detect", one step per stage of the measure) and
    /// cancellation.
    pub control: Control,
}

impl Default for DetectOptions {
    fn default() -> Self {
        DetectOptions {
            threshold: 1.0,
            smooth_radius: 1.5,
            fine_radius: 0.25,
            site_spacing: 0.25,
            region_margin: 1.0,
            noise_factor: 4.0,
            discretisation_factor: 10.0,
            max_turn: 1.0,
            flat_spot_factor: 4.0,
            control: Control::default(),
        }
    }
}

impl DetectOptions {
    /// Sets the score threshold.
    pub fn threshold(mut self, t: f64) -> Self {
        self.threshold = t;
        self
    }
    /// Sets the smooth-fit radius (spacings).
    pub fn smooth_radius(mut self, r: f64) -> Self {
        self.smooth_radius = r;
        self
    }
    /// Sets the fine-fit radius (spacings).
    pub fn fine_radius(mut self, r: f64) -> Self {
        self.fine_radius = r;
        self
    }
    /// Sets the distance between sites (spacings).
    pub fn site_spacing(mut self, d: f64) -> Self {
        self.site_spacing = d;
        self
    }
    /// Sets the region margin (spacings).
    pub fn region_margin(mut self, r: f64) -> Self {
        self.region_margin = r;
        self
    }
    /// Sets the noise factor (0: no noise floor).
    pub fn noise_factor(mut self, k: f64) -> Self {
        self.noise_factor = k;
        self
    }
    /// Sets the discretisation factor (0: no discretisation floor).
    pub fn discretisation_factor(mut self, k: f64) -> Self {
        self.discretisation_factor = k;
        self
    }
    /// Sets the largest normal turn within the smooth radius at which a
    /// site is judged (radians).
    pub fn max_turn(mut self, a: f64) -> Self {
        self.max_turn = a;
        self
    }
    /// Sets the flat-spot measure's noise factor (0: no flat-spot measure).
    pub fn flat_spot_factor(mut self, k: f64) -> Self {
        self.flat_spot_factor = k;
        self
    }
    /// Sets the progress callback and cancel flag.
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }

    /// Every length and factor must be positive and finite (the noise
    /// factor may be 0).
    fn validate(&self) -> Result<(), HighlightError> {
        for (name, v) in [
            ("threshold", self.threshold),
            ("smooth_radius", self.smooth_radius),
            ("fine_radius", self.fine_radius),
            ("site_spacing", self.site_spacing),
            ("region_margin", self.region_margin),
            ("max_turn", self.max_turn),
        ] {
            if !(v > 0.0) || !v.is_finite() {
                return Err(HighlightError::InvalidOption(format!(
                    "{name} must be positive, got {v}"
                )));
            }
        }
        for (name, v) in [
            ("noise_factor", self.noise_factor),
            ("discretisation_factor", self.discretisation_factor),
            ("flat_spot_factor", self.flat_spot_factor),
        ] {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(HighlightError::InvalidOption(format!(
                    "{name} must be non-negative, got {v}"
                )));
            }
        }
        Ok(())
    }
}

/// One site of the measure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// The vertex the site sits on.
    pub vertex: VertexId,
    /// Denoised position p̂ from the fine fit (mesh units).
    pub position: Vec3,
    /// Score θ·L/(0.1·s) (dimensionless); `None` when not judged.
    pub score: Option<f64>,
    /// Facet angle δ at the site: the mean angle between the normals of
    /// neighbouring faces within the fine radius (radians), the turn of
    /// the normal that the mesh resolves per edge.
    pub facet_angle: f64,
    /// The threshold applied at this site: the largest of the threshold,
    /// the scan-noise floor and the discretisation floor (see the module
    /// documentation).
    pub threshold: f64,
    /// The flat-spot measure at this site (module documentation, step 8):
    /// the median relative curvature drop against the smoothed surface
    /// over the sites within 0.35 R (dimensionless; 1 = flat where the
    /// smooth surface curves), 0 where the smoothed surface's curvature is
    /// not resolved above the mesh's curvature noise; `None` when not
    /// judged.
    pub flat_spot: Option<f64>,
}

/// Highlight lines crossing the suggested regions (for pictures and
/// reports).
#[derive(Clone, Debug, PartialEq)]
pub struct LineFairness {
    /// Position of the line in the [`HighlightLines`] given.
    pub line: usize,
    /// Its light index m.
    pub index: i64,
    /// Its length (mesh units).
    pub length: f64,
    /// Largest score of a region the line crosses (0 when none).
    pub score: f64,
    /// The stretches of the line inside regions, as polylines.
    pub stretches: Vec<Vec<Vec3>>,
}

/// A suggested fairing region: a connected face set (DESIGN.md §5 region)
/// without holes.
#[derive(Clone, Debug, PartialEq)]
pub struct IrregularRegion {
    /// Faces, ascending.
    pub faces: Vec<FaceId>,
    /// Largest score of the flagged sites inside (the normal measure; below
    /// its threshold when only the flat-spot measure flagged the region).
    pub score: f64,
    /// The threshold applied at the site of that score ([`Site::threshold`]).
    pub threshold: f64,
    /// Largest flat-spot value of the sites inside flagged by the
    /// flat-spot measure ([`Site::flat_spot`]; 0 when none).
    pub flat_spot: f64,
    /// How many times the region's strongest flagged site exceeds the
    /// threshold of the measure that flagged it: the larger of score over
    /// its site's threshold and flat spot over the flat-spot floor (> 1;
    /// regions are ranked by it).
    pub severity: f64,
    /// Centre of the flagged sites inside (mesh units), weighted by score
    /// (by flat-spot value where only the flat-spot measure flagged).
    pub center: Vec3,
    /// Area of the faces (mesh units²).
    pub area: f64,
    /// Number of flagged sites inside.
    pub flagged_sites: usize,
    /// Lines (positions in the input) crossing the region.
    pub lines: Vec<usize>,
}

/// Result of [`detect_irregularities`]: the regions, the lines crossing
/// them and the sites, and the numbers of the measure. It serialises to
/// the report of `fairline detect` (the numbers; `sites` as their count;
/// regions and lines are written by the front end, which maps faces to
/// its input).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Detection {
    /// Regions by decreasing severity.
    #[serde(skip)]
    pub regions: Vec<IrregularRegion>,
    /// Lines crossing regions (only those), in line order.
    #[serde(skip)]
    pub lines: Vec<LineFairness>,
    /// Every site, judged or not.
    #[serde(serialize_with = "serialize_count")]
    pub sites: Vec<Site>,
    /// Number of judged sites.
    pub judged_sites: usize,
    /// Number of sites not judged because the surface turns by more than
    /// [`DetectOptions::max_turn`] within the smooth radius (shape finer
    /// than the measure's scale: ears, horns, creases).
    pub shape_sites: usize,
    /// Number of flagged sites.
    pub flagged_sites: usize,
    /// The threshold applied to the whole mesh: max(threshold,
    /// noise_factor × median score); sites with large facet angles may
    /// have a higher one ([`Site::threshold`]).
    pub threshold: f64,
    /// Median site score (the score noise; dimensionless).
    pub median_score: f64,
    /// Median weighted RMS residual of the fine fits (mesh units): the
    /// sampling noise of the surface.
    pub noise_level: f64,
    /// Median facet angle of the judged sites (radians): how far the
    /// mesh's normals turn from one face to the next.
    pub facet_angle: f64,
    /// Discretisation level: the median, over the judged sites, of the
    /// normal error θ over the facet angle δ (dimensionless): the part of
    /// the faceting that the fits leave as normal error on this mesh.
    pub discretisation_level: f64,
    /// Number of sites above the threshold whose normal error the mesh's
    /// facets explain (below the discretisation floor), not flagged.
    pub discretisation_sites: usize,
    /// Area of all regions over the mesh area (0–1).
    pub flagged_area_fraction: f64,
    /// Fine-fit radius used (mesh units).
    pub fine_radius: f64,
    /// Smooth-fit radius used (mesh units).
    pub smooth_radius: f64,
    /// Number of sites flagged by the flat-spot measure (some may also be
    /// flagged by the normal measure; [`Self::flagged_sites`] counts them
    /// once).
    pub flat_spot_sites: usize,
    /// The flat-spot floor: max(0.5, flat_spot_factor × the 90th
    /// percentile of the sites' flat-spot values); 0 when the measure is
    /// off (module documentation, step 8).
    pub flat_spot_floor: f64,
    /// The curvature noise: the median over the judged sites of the
    /// curvature change the smoothing makes, |κ_s − κ|·R (dimensionless).
    pub curvature_noise: f64,
    /// Side of the cubes that hold one site each (mesh units): every
    /// vertex with a normal has a site within √3 times this distance.
    #[serde(skip)]
    pub site_cell: f64,
}

fn serialize_count<S: serde::Serializer, T>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(v.len() as u64)
}

impl Detection {
    /// All region faces (union, ascending): the region JSON `{"faces":[..]}`.
    pub fn all_faces(&self) -> Vec<FaceId> {
        let mut f: Vec<FaceId> = self
            .regions
            .iter()
            .flat_map(|r| r.faces.iter().copied())
            .collect();
        f.sort_unstable();
        f.dedup();
        f
    }
    /// The largest region score (0 when nothing was flagged).
    pub fn max_score(&self) -> f64 {
        self.regions.iter().map(|r| r.score).fold(0.0, f64::max)
    }

    /// What flagged the best region, for titles and summaries: "score S"
    /// where the normal measure flagged it, "flat spot F (floor G)" where
    /// only the flat-spot measure did; `None` when nothing was flagged.
    pub fn best_summary(&self) -> Option<String> {
        let best = self.regions.first()?;
        Some(if best.score > best.threshold || best.flat_spot <= 0.0 {
            format!("score {:.1}", best.score)
        } else {
            format!(
                "flat spot {:.2} (floor {:.2})",
                best.flat_spot, self.flat_spot_floor
            )
        })
    }

    /// The faces the measure did not judge as shape finer than its scale
    /// (ascending): those whose centroid's nearest site has no score and
    /// is not on the mesh border — [`Detection::shape_sites`], and the
    /// rare site with no fit. A picture shows them so that "no region" is
    /// not read as "no defect" where nothing was looked at. The border,
    /// which the measure never judges (module documentation, step 3), is
    /// left out, as are faces with no site within two site cells (there
    /// are none on the mesh [`detect_irregularities`] ran on).
    pub fn shape_faces(&self, mesh: &SurfaceMesh) -> Vec<FaceId> {
        let shape = |s: &Site| s.score.is_none() && !mesh.is_boundary_vertex(s.vertex);
        if !self.sites.iter().any(shape) || !(self.site_cell > 0.0) {
            return Vec::new();
        }
        let reach = 2.0 * self.site_cell;
        let grid = Grid::new(
            reach,
            self.sites
                .iter()
                .enumerate()
                .map(|(i, s)| (i as u32, s.position)),
        );
        let p = mesh.positions();
        (0..mesh.face_count())
            .into_par_iter()
            .filter_map(|f| {
                let face = FaceId(f as u32);
                let [a, b, c] = mesh.triangle(face);
                let centroid = (p[a.idx()] + p[b.idx()] + p[c.idx()]) / 3.0;
                let mut nearest: Option<(f64, u32)> = None;
                grid.around(centroid, |i| {
                    let d = (self.sites[i as usize].position - centroid).length_squared();
                    // ties to the lower index: independent of the grid's order
                    if nearest.is_none_or(|(e, j)| d < e || (d == e && i < j)) {
                        nearest = Some((d, i));
                    }
                });
                nearest
                    .filter(|&(d, i)| d <= reach * reach && shape(&self.sites[i as usize]))
                    .map(|_| face)
            })
            .collect()
    }
}

/// Orthonormal tangent frame (bx, by) of a unit normal.
fn frame(n: Vec3) -> (Vec3, Vec3) {
    let bx = n.any_orthonormal_vector();
    (bx, n.cross(bx))
}

/// Fine fit: weighted least-squares height field (N = 10: cubic, N = 6:
/// quadric) over the neighbours in the frame of `n0`, coordinates scaled by
/// r, weights (1 − ρ²)². Returns the denoised position, normal and
/// weighted RMS residual (mesh units); `None` with fewer than N + 4 points.
fn fine_fit<const N: usize>(p0: Vec3, n0: Vec3, pts: &[Vec3], r: f64) -> Option<(Vec3, Vec3, f64)> {
    let (bx, by) = frame(n0);
    let mut ata = [[0.0f64; N]; N];
    let mut atb = [0.0f64; N];
    let mut wsum = 0.0;
    let mut rows: Vec<([f64; N], f64, f64)> = Vec::with_capacity(pts.len());
    for &q in pts {
        let d = (q - p0) / r;
        let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n0));
        let w = (1.0 - x * x - y * y).max(0.0).powi(2);
        if w <= 0.0 {
            continue;
        }
        let row = height_monomials::<N>(x, y);
        for i in 0..N {
            for j in i..N {
                ata[i][j] += w * row[i] * row[j];
            }
            atb[i] += w * row[i] * z;
        }
        wsum += w;
        rows.push((row, z, w));
    }
    if rows.len() < N + 4 {
        return None;
    }
    let c = solve_spd(&ata, &atb)?;
    let mut res = 0.0;
    for (row, z, w) in &rows {
        let f: f64 = row.iter().zip(&c).map(|(a, b)| a * b).sum();
        res += w * (z - f) * (z - f);
    }
    let rms = if wsum > 0.0 {
        (res / wsum).sqrt() * r
    } else {
        0.0
    };
    let n = (n0 - c[1] * bx - c[2] * by).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    Some((p0 + c[0] * r * n0, n, rms))
}

/// Coarse fit: IRLS cubic height field through the neighbour sites'
/// positions and normals (frame of `n0` at `p0`, scaled by `r`); returns
/// the fit's unit normal at the origin. `floor` is the smallest robust
/// scale of the slope residuals (radians).
fn smooth_normal(p0: Vec3, n0: Vec3, nb: &[(Vec3, Vec3)], r: f64, floor: f64) -> Option<Vec3> {
    smooth_normal_with_hole(p0, n0, nb, r, floor, HOLE)
}

/// [`smooth_normal`] leaving out the sites within `hole` smooth radii.
fn smooth_normal_with_hole(
    p0: Vec3,
    n0: Vec3,
    nb: &[(Vec3, Vec3)],
    r: f64,
    floor: f64,
    hole: f64,
) -> Option<Vec3> {
    let (bx, by) = frame(n0);
    struct Row {
        x: f64,
        y: f64,
        z: f64,
        gx: f64,
        gy: f64,
        w: f64,
    }
    let mut all_rows: Vec<Row> = Vec::with_capacity(nb.len());
    for &(q, nq) in nb {
        let d = (q - p0) / r;
        let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n0));
        let rr = x * x + y * y;
        let w = (1.0 - rr).max(0.0).powi(2);
        let nz = nq.dot(n0);
        if w <= 0.0 || nz < 0.3 {
            continue;
        }
        all_rows.push(Row {
            x,
            y,
            z,
            gx: -nq.dot(bx) / nz,
            gy: -nq.dot(by) / nz,
            w,
        });
    }
    // one-sided neighbourhood (mesh boundary): a cubic fitted on one side
    // of the site errs more at the site, so the fit shrinks to 0.6 R there
    // and keeps the sites near the judged one; elsewhere it leaves them out
    let mut rows: Vec<Row> = Vec::with_capacity(all_rows.len());
    let wsum: f64 = all_rows.iter().map(|r| r.w).sum();
    if wsum > 0.0 {
        let cx = all_rows.iter().map(|r| r.w * r.x).sum::<f64>() / wsum;
        let cy = all_rows.iter().map(|r| r.w * r.y).sum::<f64>() / wsum;
        if cx.hypot(cy) > BOUNDARY_OFFSET {
            let k = BOUNDARY_SHRINK;
            rows = all_rows;
            rows.retain(|r| r.x * r.x + r.y * r.y < k * k);
            for r in &mut rows {
                (r.x, r.y, r.z) = (r.x / k, r.y / k, r.z / k);
                r.w = (1.0 - r.x * r.x - r.y * r.y).max(0.0).powi(2);
            }
        } else {
            rows = all_rows;
            rows.retain(|r| r.x * r.x + r.y * r.y >= hole * hole);
        }
    }
    if rows.len() < 12 {
        return None;
    }
    let basis = |x: f64, y: f64| -> ([f64; 10], [f64; 10], [f64; 10]) {
        (
            height_monomials(x, y),
            [
                0.0,
                1.0,
                0.0,
                2.0 * x,
                y,
                0.0,
                3.0 * x * x,
                2.0 * x * y,
                y * y,
                0.0,
            ],
            [
                0.0,
                0.0,
                1.0,
                0.0,
                x,
                2.0 * y,
                0.0,
                x * x,
                2.0 * x * y,
                3.0 * y * y,
            ],
        )
    };
    let mut robust = vec![1.0f64; rows.len()];
    let mut coef = [0.0f64; 10];
    for pass in 0..3 {
        let mut ata = [[0.0f64; 10]; 10];
        let mut atb = [0.0f64; 10];
        for (row, &rw) in rows.iter().zip(&robust) {
            let w = row.w * rw;
            if w <= 0.0 {
                continue;
            }
            let (v, dx, dy) = basis(row.x, row.y);
            for i in 0..10 {
                for j in i..10 {
                    ata[i][j] += w * (v[i] * v[j] + dx[i] * dx[j] + dy[i] * dy[j]);
                }
                atb[i] += w * (v[i] * row.z + dx[i] * row.gx + dy[i] * row.gy);
            }
        }
        coef = solve_spd(&ata, &atb)?;
        if pass == 2 {
            break;
        }
        // slope residuals and their robust scale
        let res: Vec<f64> = rows
            .iter()
            .map(|row| {
                let (_, dx, dy) = basis(row.x, row.y);
                let fx: f64 = dx.iter().zip(&coef).map(|(a, b)| a * b).sum();
                let fy: f64 = dy.iter().zip(&coef).map(|(a, b)| a * b).sum();
                ((fx - row.gx).powi(2) + (fy - row.gy).powi(2)).sqrt()
            })
            .collect();
        let mut sorted = res.clone();
        sorted.sort_by(f64::total_cmp);
        let med = sorted[sorted.len() / 2];
        let scale = (1.4826 * med).max(floor);
        let c = 4.685 * scale;
        for (rw, e) in robust.iter_mut().zip(&res) {
            let u = e / c;
            *rw = if u < 1.0 { (1.0 - u * u).powi(2) } else { 0.0 };
        }
    }
    let n = (n0 - coef[1] * bx - coef[2] * by).normalize_or_zero();
    (n != Vec3::ZERO).then_some(n)
}

/// Weighted centroid offset of a neighbourhood (in smooth radii) above
/// which the site counts as near a boundary.
const BOUNDARY_OFFSET: f64 = 0.05;
/// The smooth fit leaves out the sites within this many smooth radii of
/// the site it judges, so a defect there does not bend the fit toward
/// itself (the fit interpolates across the hole).
const HOLE: f64 = 0.35;
/// Radius of the smooth fit near a boundary, in smooth radii.
const BOUNDARY_SHRINK: f64 = 0.6;

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

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
    let detection = detect_irregularities(mesh, light, &lines, &options)?;
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
    Ok(Detection {
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
    })
}

/// Whether the normal measure flags a site (its score above its threshold).
fn normal_flagged(site: &Site) -> bool {
    site.score.is_some_and(|sc| sc > site.threshold)
}

/// The lengths of the measure on one mesh (mesh units).
struct Scale {
    /// Light spacing s.
    spacing: f64,
    /// Fine-fit radius r_f = max(fine_radius·s, 2.5 h).
    fine_radius: f64,
    /// Smooth-fit radius R = max(smooth_radius·s, 2 r_f).
    smooth_radius: f64,
    /// Side of the cubes that hold one site each.
    site_cell: f64,
}

impl Scale {
    /// How many times R exceeds `smooth_radius`·s (1 unless the mesh is
    /// coarse against the spacing and R was raised to 2 r_f).
    fn coarsening(&self, o: &DetectOptions) -> f64 {
        let nominal = o.smooth_radius * self.spacing;
        if nominal > 0.0 && self.smooth_radius.is_finite() {
            (self.smooth_radius / nominal).max(1.0)
        } else {
            1.0
        }
    }

    fn new(mesh: &SurfaceMesh, light: &LightArray, o: &DetectOptions) -> Self {
        let s = light.spacing();
        let h = geom::mean_edge_length(mesh);
        let h = if h > 0.0 && h.is_finite() { h } else { s };
        let fine_radius = (o.fine_radius * s).max(2.5 * h);
        Scale {
            spacing: s,
            fine_radius,
            smooth_radius: (o.smooth_radius * s).max(2.0 * fine_radius),
            site_cell: o.site_spacing * s,
        }
    }
}

/// Sites: the lowest-index vertex (with a normal) of each cube of side
/// `cell`, ascending.
fn site_vertices(p: &[Vec3], normals: &[Vec3], cell: f64) -> Vec<u32> {
    let mut site_of_cell: HashMap<Cell, u32, BuildHasherDefault<CellHasher>> = HashMap::default();
    for (i, &q) in p.iter().enumerate() {
        if normals[i] == Vec3::ZERO || !q.is_finite() {
            continue;
        }
        site_of_cell.entry(Grid::cell(cell, q)).or_insert(i as u32);
    }
    let mut site_vertices: Vec<u32> = site_of_cell.into_values().collect();
    site_vertices.sort_unstable();
    site_vertices
}

/// Per vertex, the mean angle between the normals of the two faces of
/// each interior edge around it (radians; 0 where there is none): how far
/// the piecewise-flat mesh turns its normal from one face to the next
/// (about κ·h on a smooth surface of curvature κ sampled at edge length h).
fn vertex_facet_angles(mesh: &SurfaceMesh) -> Vec<f64> {
    let face_normals = geom::face_normals(mesh);
    let mut sum = vec![0.0f64; mesh.vertex_count()];
    let mut count = vec![0u32; mesh.vertex_count()];
    for e in mesh.edges() {
        let (Some(f), Some(g)) = (
            mesh.face(mesh.edge_halfedge(e, 0)),
            mesh.face(mesh.edge_halfedge(e, 1)),
        ) else {
            continue;
        };
        let (nf, ng) = (face_normals[f.idx()], face_normals[g.idx()]);
        if nf == Vec3::ZERO || ng == Vec3::ZERO {
            continue;
        }
        let angle = nf.dot(ng).clamp(-1.0, 1.0).acos();
        let (a, b) = mesh.edge_vertices(e);
        for v in [a, b] {
            sum[v.idx()] += angle;
            count[v.idx()] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
        .collect()
}

/// What the fine fit says at a site.
#[derive(Clone, Copy, Debug)]
struct FineFit {
    /// Denoised position p̂.
    position: Vec3,
    /// Its unit normal n̂.
    normal: Vec3,
    /// Weighted RMS residual (mesh units; NaN when no fit was possible).
    residual: f64,
    /// Mean facet angle of the vertices within the fine radius (radians).
    facet_angle: f64,
}

/// Fine fits at every site (step 2 of the module documentation): a cubic
/// over r_f, over a radius grown to hold 20 vertices where there are too
/// few (boundaries, corners), else a quadric; `None` where no finite fit
/// exists.
fn fine_fits(
    p: &[Vec3],
    normals: &[Vec3],
    facets: &[f64],
    site_vertices: &[u32],
    scale: &Scale,
) -> Vec<Option<FineFit>> {
    let fine_r = scale.fine_radius;
    let fine_cell = 1.6 * fine_r;
    let vgrid = Grid::new(fine_cell, p.iter().enumerate().map(|(i, &q)| (i as u32, q)));
    site_vertices
        .par_iter()
        .map(|&v| {
            let (p0, n0) = (p[v as usize], normals[v as usize]);
            // candidates within 1.6 r_f (the grid cell is 1.6 r_f)
            let mut near: Vec<(f64, Vec3)> = Vec::new();
            let (mut facet_sum, mut facet_count) = (0.0, 0usize);
            vgrid.around(p0, |u| {
                let q = p[u as usize];
                let d2 = (q - p0).length_squared();
                if d2 < fine_cell * fine_cell && normals[u as usize].dot(n0) > 0.5 {
                    near.push((d2, q));
                    if d2 < fine_r * fine_r {
                        facet_sum += facets[u as usize];
                        facet_count += 1;
                    }
                }
            });
            let facet_angle = if facet_count > 0 {
                facet_sum / facet_count as f64
            } else {
                facets[v as usize]
            };
            let within = |r: f64| -> Vec<Vec3> {
                near.iter()
                    .filter(|(d2, _)| *d2 < r * r)
                    .map(|x| x.1)
                    .collect()
            };
            let pts = within(fine_r);
            let fit = if pts.len() >= 20 {
                fine_fit::<10>(p0, n0, &pts, fine_r)
            } else {
                let mut d2: Vec<f64> = near.iter().map(|x| x.0).collect();
                d2.sort_by(f64::total_cmp);
                let r = d2
                    .get(19)
                    .map_or(fine_cell, |d| d.sqrt() * 1.05)
                    .min(fine_cell);
                fine_fit::<10>(p0, n0, &within(r), r)
            };
            fit.or_else(|| fine_fit::<6>(p0, n0, &pts, fine_r))
                .or(Some((p0, n0, f64::NAN)))
                .filter(|(q, n, _)| q.is_finite() && n.is_finite())
                .map(|(position, normal, residual)| FineFit {
                    position,
                    normal,
                    residual,
                    facet_angle,
                })
        })
        .collect()
}

/// The judgement of one site.
#[derive(Clone, Copy, Debug)]
struct Judgement {
    /// Score θ/θ₀ (`None`: not judged).
    score: Option<f64>,
    /// θ₀ = 0.1·s/L: the normal error of score 1 at this site (radians).
    unit_angle: f64,
    /// Not judged because the surface turns by more than `max_turn`
    /// within R (shape finer than the measure).
    shape: bool,
}

/// Coarse fits and scores (steps 3, 4 and 6 of the module documentation).
fn judge_sites(
    mesh: &SurfaceMesh,
    light: &LightArray,
    site_vertices: &[u32],
    fine: &[Option<FineFit>],
    scale: &Scale,
    o: &DetectOptions,
) -> Vec<Judgement> {
    let s = scale.spacing;
    let smooth_r = scale.smooth_radius;
    let z = light.plane_normal();
    let a0 = light.plane_point();
    let sgrid = Grid::new(
        smooth_r,
        fine.iter()
            .enumerate()
            .filter_map(|(i, f)| f.map(|f| (i as u32, f.position))),
    );
    let min_turn_cos = o.max_turn.min(std::f64::consts::PI).cos();
    (0..site_vertices.len())
        .into_par_iter()
        .map(|i| {
            let not_judged = Judgement {
                score: None,
                unit_angle: 0.0,
                shape: false,
            };
            if mesh.is_boundary_vertex(VertexId(site_vertices[i])) {
                return not_judged;
            }
            let Some(FineFit {
                position: pi,
                normal: ni,
                ..
            }) = fine[i]
            else {
                return not_judged;
            };
            let dist = (a0 - pi).dot(z).abs().max(s);
            let theta0 = 0.1 * s / dist;
            let mut nb = Vec::new();
            let mut least_cos = 1.0f64;
            sgrid.around(pi, |j| {
                if let Some(f) = fine[j as usize]
                    && (f.position - pi).length_squared() < smooth_r * smooth_r
                {
                    let c = f.normal.dot(ni);
                    least_cos = least_cos.min(c);
                    if c > 0.3 {
                        nb.push((f.position, f.normal));
                    }
                }
            });
            if least_cos < min_turn_cos {
                return Judgement {
                    shape: true,
                    ..not_judged
                };
            }
            let score = smooth_normal(pi, ni, &nb, smooth_r, 0.5 * theta0).and_then(|ns| {
                let theta = ni.dot(ns).clamp(-1.0, 1.0).acos();
                let score = theta / theta0;
                score.is_finite().then_some(score)
            });
            Judgement {
                score,
                unit_angle: theta0,
                shape: false,
            }
        })
        .collect()
}

/// The noise floors of the measure (steps 5 and 7 of the module
/// documentation).
struct NoiseFloors {
    /// max(threshold, noise_factor × median score).
    threshold: f64,
    /// `discretisation_factor` × discretisation level.
    facet_factor: f64,
    judged_sites: usize,
    median_score: f64,
    noise_level: f64,
    facet_angle: f64,
    discretisation_level: f64,
}

impl NoiseFloors {
    fn estimate(judgements: &[Judgement], fine: &[Option<FineFit>], o: &DetectOptions) -> Self {
        let judged: Vec<f64> = judgements.iter().filter_map(|j| j.score).collect();
        let judged_sites = judged.len();
        let median_score = median(judged);
        let noise_level = median(
            fine.iter()
                .flatten()
                .map(|f| f.residual)
                .filter(|r| r.is_finite())
                .collect(),
        );
        // normal error over facet angle at the judged sites with facets
        let mut ratios = Vec::new();
        let mut facets = Vec::new();
        for (j, f) in judgements.iter().zip(fine) {
            if let (Some(score), Some(f)) = (j.score, f) {
                facets.push(f.facet_angle);
                if f.facet_angle > 0.0 {
                    let ratio = score * j.unit_angle / f.facet_angle;
                    if ratio.is_finite() {
                        ratios.push(ratio);
                    }
                }
            }
        }
        let discretisation_level = median(ratios);
        NoiseFloors {
            threshold: o.threshold.max(o.noise_factor * median_score),
            facet_factor: o.discretisation_factor * discretisation_level,
            judged_sites,
            median_score,
            noise_level,
            facet_angle: median(facets),
            discretisation_level,
        }
    }

    /// The threshold at one site: the mesh's, raised to the normal error
    /// the site's facets explain (in score units, δ·factor/θ₀).
    fn at(&self, j: &Judgement, f: Option<&FineFit>) -> f64 {
        match (j.score, f) {
            (Some(_), Some(f)) if j.unit_angle > 0.0 => {
                let facet = self.facet_factor * f.facet_angle / j.unit_angle;
                if facet.is_finite() {
                    self.threshold.max(facet)
                } else {
                    self.threshold
                }
            }
            _ => self.threshold,
        }
    }
}

/// Faces whose centroid lies within `margin` of a flagged site, and the
/// faces around the flagged sites' vertices.
fn faces_near_sites(
    mesh: &SurfaceMesh,
    sites: &[Site],
    flagged: &[usize],
    margin: f64,
) -> Vec<bool> {
    let p = mesh.positions();
    let nf = mesh.face_count();
    let fgrid = Grid::new(
        margin,
        flagged.iter().map(|&i| (i as u32, sites[i].position)),
    );
    let centroid = |f: FaceId| {
        let [a, b, c] = mesh.triangle(f);
        (p[a.idx()] + p[b.idx()] + p[c.idx()]) / 3.0
    };
    let mut in_region: Vec<bool> = if flagged.is_empty() {
        vec![false; nf]
    } else {
        (0..nf)
            .into_par_iter()
            .map(|f| {
                let c = centroid(FaceId(f as u32));
                let mut hit = false;
                fgrid.around(c, |i| {
                    hit |= (sites[i as usize].position - c).length_squared() <= margin * margin;
                });
                hit
            })
            .collect()
    };
    for &i in flagged {
        for f in mesh.vertex_faces(sites[i].vertex) {
            in_region[f.idx()] = true;
        }
    }
    in_region
}

/// The connected components of the region faces (as unscored regions) and
/// each face's component (`u32::MAX` outside).
fn connected_regions(
    mesh: &SurfaceMesh,
    in_region: &[bool],
    areas: &[f64],
) -> (Vec<IrregularRegion>, Vec<u32>) {
    let nf = mesh.face_count();
    let mut comp = vec![u32::MAX; nf];
    let mut regions: Vec<IrregularRegion> = Vec::new();
    for f0 in 0..nf {
        if !in_region[f0] || comp[f0] != u32::MAX {
            continue;
        }
        let id = regions.len() as u32;
        let mut faces = Vec::new();
        let mut stack = vec![FaceId(f0 as u32)];
        comp[f0] = id;
        while let Some(f) = stack.pop() {
            faces.push(f);
            for hh in mesh.face_halfedges(f) {
                if let Some(g) = mesh.face(mesh.opposite(hh))
                    && in_region[g.idx()]
                    && comp[g.idx()] == u32::MAX
                {
                    comp[g.idx()] = id;
                    stack.push(g);
                }
            }
        }
        faces.sort_unstable();
        let area = faces.iter().map(|f| areas[f.idx()]).sum();
        regions.push(IrregularRegion {
            faces,
            score: 0.0,
            threshold: 0.0,
            flat_spot: 0.0,
            severity: 0.0,
            center: Vec3::ZERO,
            area,
            flagged_sites: 0,
            lines: Vec::new(),
        });
    }
    (regions, comp)
}

/// Each region's score (largest flagged score inside), flat spot,
/// severity, centre (score-weighted; flat-spot-weighted where only the
/// flat-spot measure flagged) and number of flagged sites. `flat_floor` is
/// the flat-spot floor.
fn score_regions(
    mesh: &SurfaceMesh,
    sites: &[Site],
    flagged: &[usize],
    flat_floor: f64,
    component: &[u32],
    regions: &mut [IrregularRegion],
) {
    // per region and measure (normal, flat spot): the weighted sum of
    // positions, the weight, and the best score with its threshold
    #[derive(Clone, Copy, Default)]
    struct Tally {
        sum: Vec3,
        weight: f64,
        best: Option<(f64, f64)>,
    }
    let mut tallies = vec![[Tally::default(); 2]; regions.len()];
    for &i in flagged {
        let Some(f) = mesh.vertex_faces(sites[i].vertex).next() else {
            continue;
        };
        let r = component[f.idx()];
        if r == u32::MAX {
            continue;
        }
        let (site, r) = (&sites[i], r as usize);
        let sc = site.score.unwrap_or(0.0);
        let flat = site.flat_spot.unwrap_or(0.0);
        let by_flat = flat_floor > 0.0 && flat > flat_floor;
        let region = &mut regions[r];
        for (k, flagged_by, weight, severity) in [
            (0, normal_flagged(site), sc, sc / site.threshold),
            (
                1,
                by_flat,
                flat,
                if by_flat { flat / flat_floor } else { 0.0 },
            ),
        ] {
            if !flagged_by || !severity.is_finite() {
                continue;
            }
            let t = &mut tallies[r][k];
            t.sum += weight * site.position;
            t.weight += weight;
            if t.best.is_none_or(|(b, _)| sc > b) {
                t.best = Some((sc, site.threshold));
            }
            region.severity = region.severity.max(severity);
            if k == 1 {
                region.flat_spot = region.flat_spot.max(flat);
            }
        }
        region.flagged_sites += 1;
    }
    for (region, t) in regions.iter_mut().zip(&tallies) {
        // the normal measure's numbers where it flagged, else the flat spot's
        if let Some(t) = t.iter().find(|t| t.weight > 0.0) {
            region.center = t.sum / t.weight;
            (region.score, region.threshold) = t.best.unwrap_or((0.0, 0.0));
        }
    }
}

/// The stretches of the highlight lines inside the regions; records in
/// each region the lines crossing it.
fn lines_crossing_regions(
    mesh: &SurfaceMesh,
    lines: &HighlightLines,
    in_region: &[bool],
    component: &[u32],
    regions: &mut [IrregularRegion],
) -> Vec<LineFairness> {
    let node_region = |nd: NodeId| -> Option<u32> {
        let f = match nd {
            NodeId::Edge(e, _) => [0, 1].iter().find_map(|&k| {
                mesh.face(mesh.edge_halfedge(e, k))
                    .filter(|f| in_region[f.idx()])
            }),
            NodeId::Vertex(v, _) => mesh.vertex_faces(v).find(|f| in_region[f.idx()]),
        }?;
        Some(component[f.idx()])
    };
    let mut line_out: Vec<LineFairness> = Vec::new();
    for (li, line) in lines.lines.iter().enumerate() {
        let mut stretches: Vec<Vec<Vec3>> = Vec::new();
        let mut current: Vec<Vec3> = Vec::new();
        let mut score: f64 = 0.0;
        for (&nd, &q) in line.nodes.iter().zip(&line.points) {
            match node_region(nd) {
                Some(r) if (r as usize) < regions.len() => {
                    current.push(q);
                    score = score.max(regions[r as usize].score);
                    if !regions[r as usize].lines.contains(&li) {
                        regions[r as usize].lines.push(li);
                    }
                }
                _ => {
                    if current.len() > 1 {
                        stretches.push(std::mem::take(&mut current));
                    }
                    current.clear();
                }
            }
        }
        if current.len() > 1 {
            stretches.push(current);
        }
        if !stretches.is_empty() {
            let length = line.points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
            line_out.push(LineFairness {
                line: li,
                index: line.index,
                length,
                score,
                stretches,
            });
        }
    }
    line_out
}

/// Fills the holes of a face set: complement components that touch no mesh
/// boundary, are not the largest complement component and are smaller than
/// the set itself are added to it.
fn fill_holes(mesh: &SurfaceMesh, in_region: &mut [bool]) {
    let nf = mesh.face_count();
    let region_faces = in_region.iter().filter(|&&b| b).count();
    if region_faces == 0 {
        return;
    }
    let mut comp = vec![u32::MAX; nf];
    let mut parts: Vec<(Vec<FaceId>, bool)> = Vec::new();
    for f0 in 0..nf {
        if in_region[f0] || comp[f0] != u32::MAX {
            continue;
        }
        let id = parts.len() as u32;
        let mut faces = Vec::new();
        let mut boundary = false;
        let mut stack = vec![FaceId(f0 as u32)];
        comp[f0] = id;
        while let Some(f) = stack.pop() {
            faces.push(f);
            for hh in mesh.face_halfedges(f) {
                match mesh.face(mesh.opposite(hh)) {
                    Some(g) => {
                        if !in_region[g.idx()] && comp[g.idx()] == u32::MAX {
                            comp[g.idx()] = id;
                            stack.push(g);
                        }
                    }
                    None => boundary = true,
                }
            }
        }
        parts.push((faces, boundary));
    }
    let largest = parts
        .iter()
        .enumerate()
        .max_by_key(|(i, (f, _))| (f.len(), std::cmp::Reverse(*i)))
        .map(|(i, _)| i);
    for (i, (faces, boundary)) in parts.iter().enumerate() {
        if Some(i) == largest || *boundary || faces.len() >= region_faces {
            continue;
        }
        for f in faces {
            in_region[f.idx()] = true;
        }
    }
}

/// The flat-spot measure (module documentation, step 8).
#[path = "detect_flat_spot.rs"]
mod flat_spot;

/// The wider-scale comparisons measured for wide dents on coarse meshes
/// (README, Default lights on real meshes): a table
/// printer, not a check.
#[cfg(test)]
#[path = "detect_wide_table.rs"]
mod wide_table;

/// The loops and flat spots measured for the wide flank dent on Spot
/// (README, Default lights on real meshes): table
/// printers, not checks.
#[cfg(test)]
#[path = "detect_loops_table.rs"]
mod loops_table;

/// The smoothed-mesh comparison of the highlight distance's extrema for
/// the wide flank dent on Spot: a table printer, not a check.
#[cfg(test)]
#[path = "detect_smoothed_table.rs"]
mod smoothed_table;
