//! What detection reports: the sites, the regions, the lines crossing them
//! and the whole-mesh numbers, with the summaries front ends print.

use super::NOT_JUDGED_SHARE;
use super::grid::Grid;
use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use rayon::prelude::*;
use serde::Serialize;

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
    /// The flat-spot measure at this site ([module documentation](super), step 8):
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
    /// Position of the line in the [`HighlightLines`](crate::highlight::HighlightLines) given.
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
    /// Light spacing s of the array that judged the region (mesh units):
    /// the given array's, or a finer one of
    /// [`detect_whole_part`](super::detect_whole_part) where the given
    /// array judged nothing.
    pub spacing: f64,
}

/// Result of [`detect_irregularities`](super::detect_irregularities): the
/// regions, the lines crossing
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
    /// [`DetectOptions::max_turn`](super::DetectOptions::max_turn) within
    /// the smooth radius (shape finer
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
    /// off ([module documentation](super), step 8).
    pub flat_spot_floor: f64,
    /// The curvature noise: the median over the judged sites of the
    /// curvature change the smoothing makes, |κ_s − κ|·R (dimensionless).
    pub curvature_noise: f64,
    /// Side of the cubes that hold one site each (mesh units): every
    /// vertex with a normal has a site within √3 times this distance.
    #[serde(skip)]
    pub site_cell: f64,
    /// Share of the part's area (0–1) that no light array judged: faces
    /// whose nearest site has no score (shape finer than the measure's
    /// scale, no fit), the mesh border left out ([`Self::shape_faces`]).
    /// A front end's summary begins with it when it is not 0
    /// ([`Self::summary`]): "0 regions" there does not mean "clean".
    pub not_judged_fraction: f64,
    /// Light spacings of the arrays that judged the part, the given one
    /// first ([`detect_whole_part`](super::detect_whole_part) adds finer ones where it judged
    /// nothing; one entry for [`detect_irregularities`](super::detect_irregularities)).
    pub spacings: Vec<f64>,
    /// The faces of [`Self::not_judged_fraction`], ascending.
    #[serde(skip)]
    pub unjudged_faces: Vec<FaceId>,
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

    /// The one-line summary of a detection, as every front end prints it:
    /// first, where at least [`NOT_JUDGED_SHARE`] of the part was not
    /// judged, "not judged: 94 % of the part" (so that "0 regions" is
    /// never read as "clean" where nothing was looked at), then the number
    /// of regions.
    pub fn summary(&self) -> String {
        let regions = format!("{} region(s) flagged", self.regions.len());
        match self.not_judged_percent() {
            Some(p) => format!("not judged: {p} of the part; {regions}"),
            None => regions,
        }
    }

    /// The not-judged share as front ends print it ("94 %", "< 1 %"), or
    /// `None` below [`NOT_JUDGED_SHARE`].
    fn not_judged_percent(&self) -> Option<String> {
        let f = self.not_judged_fraction;
        if !(f >= NOT_JUDGED_SHARE) {
            return None;
        }
        let p = 100.0 * f;
        Some(if p < 1.0 {
            "< 1 %".to_string()
        } else {
            format!("{p:.0} %")
        })
    }

    /// The warning for reports where a share of the part was not judged
    /// (see [`Self::summary`]); `None` below [`NOT_JUDGED_SHARE`].
    pub fn not_judged_warning(&self) -> Option<String> {
        let p = self.not_judged_percent()?;
        let finest = self.spacings.iter().copied().fold(f64::INFINITY, f64::min);
        Some(format!(
            "not judged: {p} of the part: the surface there turns by more than the measure allows within its smooth radius even with light spacing {finest:.4} (the finest the mesh resolves: the radius is five mean edges at least), or no fit was possible; no region there means nothing was looked at, not that it is clean"
        ))
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

    /// The faces no light array judged ([`Self::unjudged_faces`],
    /// ascending). For one array: those whose centroid's nearest site has no
    /// score and is not on the mesh border — [`Detection::shape_sites`], and the
    /// rare site with no fit. A picture shows them so that "no region" is
    /// not read as "no defect" where nothing was looked at. The border,
    /// which the measure never judges ([module documentation](super), step 3), is
    /// left out, as are faces with no site within two site cells (there
    /// are none on the mesh [`detect_irregularities`](super::detect_irregularities) ran on).
    pub fn shape_faces(&self, _mesh: &SurfaceMesh) -> Vec<FaceId> {
        self.unjudged_faces.clone()
    }

    /// The faces whose centroid's nearest site is not judged and not on the
    /// border (see [`Self::shape_faces`]). A face with no site within two
    /// site cells of its centroid (faces larger than the site spacing on a
    /// coarse mesh) takes the nearest site among its own corners; a face
    /// with neither was looked at by no site and is not judged either.
    pub(super) fn nearest_unjudged_faces(&self, mesh: &SurfaceMesh) -> Vec<FaceId> {
        let shape = |s: &Site| s.score.is_none() && !mesh.is_boundary_vertex(s.vertex);
        if !self.sites.iter().any(shape) || !(self.site_cell > 0.0) {
            return Vec::new();
        }
        let mut site_of = vec![u32::MAX; mesh.vertex_count()];
        for (i, s) in self.sites.iter().enumerate() {
            if let Some(slot) = site_of.get_mut(s.vertex.idx()) {
                *slot = i as u32;
            }
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
                let nearest = nearest.filter(|&(d, _)| d <= reach * reach).or_else(|| {
                    // no site near the centroid: the nearest corner site
                    [a, b, c]
                        .iter()
                        .filter_map(|v| {
                            let i = site_of[v.idx()];
                            (i != u32::MAX).then(|| {
                                (
                                    (self.sites[i as usize].position - centroid).length_squared(),
                                    i,
                                )
                            })
                        })
                        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                });
                match nearest {
                    Some((_, i)) => shape(&self.sites[i as usize]).then_some(face),
                    None => Some(face),
                }
            })
            .collect()
    }
}
