//! Highlight lines of B-spline surfaces in the parameter domain (Nishiyama
//! et al. §2, last two paragraphs): the signed distance d_s of Eq. (2.18)
//! sampled on a `(u, v)` grid, its zero level (and the band levels ±ρ)
//! contoured by marching squares into pre-image polylines, every contour
//! point refined onto the true level along its grid edge, and the lines
//! mapped to 3D by evaluating the surface.
//!
//! Assumes a regular parametrisation (Nishiyama et al. §2: "well
//! conditioned"); where the normal is undefined, d_s is undefined and no
//! line is drawn through that grid cell. d_s changes sign where the nearest
//! point of the circle jumps (Eq. (2.18) measures along N × L̇), and a
//! linear light's distance jumps through infinity where Z·N = 0; grid edges
//! across such a jump carry no contour point (as on meshes, DESIGN.md §3).

use super::light::{CircularLight, LightArray};
use crate::Vec3;
use crate::bspline::{BSplineSurface, SurfaceDerivatives, unit_normal};
use rayon::prelude::*;

/// A light whose highlight lines are drawn on a B-spline surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceLight {
    /// A circular light (Nishiyama et al. Eq. (2.1)); field d_s of Eq. (2.18).
    Circular(CircularLight),
    /// Light `index` m of a linear light array (Yong et al. Eq. (1)–(2),
    /// sign of DESIGN.md §3); field d_P − m·s.
    Linear {
        /// The array.
        array: LightArray,
        /// The light index m.
        index: i64,
        /// Smallest |Z·N| at which the distance is defined.
        min_cos: f64,
    },
}

/// A light's field value at one surface point: the distance and a *branch
/// angle*. Two samples belong to the same continuous piece of the field when
/// their branch angles differ by less than 90° (the angle θ of the nearest
/// circle point for circular lights; 0 or π by the sign of Z·N for linear
/// lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSample {
    /// Signed distance (surface units).
    pub value: f64,
    /// Branch angle (radians).
    pub branch: f64,
}

impl SurfaceLight {
    /// The field at a surface point `q` with unit normal `normal`: d_s of
    /// Nishiyama et al. Eq. (2.18) via [`CircularLight::approach`], or the
    /// highlight distance of [`LightArray::highlight_distance`] minus m·s.
    /// `None` where undefined.
    #[inline]
    pub fn sample(&self, q: Vec3, normal: Vec3) -> Option<FieldSample> {
        match self {
            SurfaceLight::Circular(c) => c.approach(q, normal).map(|a| FieldSample {
                value: a.signed_distance,
                branch: a.theta,
            }),
            SurfaceLight::Linear {
                array,
                index,
                min_cos,
            } => {
                let d = array.highlight_distance(q, normal, *min_cos)?;
                let zn = array.plane_normal().dot(normal);
                Some(FieldSample {
                    value: d - *index as f64 * array.spacing(),
                    branch: if zn >= 0.0 { 0.0 } else { std::f64::consts::PI },
                })
            }
        }
    }

    /// The field at surface derivatives `d` (normal of Eq. (2.4)).
    #[inline]
    pub fn sample_derivatives(&self, d: &SurfaceDerivatives) -> Option<FieldSample> {
        self.sample(d.point, d.normal()?)
    }

    /// The radius R of a circular light, `None` for a linear one.
    pub fn radius(&self) -> Option<f64> {
        match self {
            SurfaceLight::Circular(c) => Some(c.radius()),
            SurfaceLight::Linear { .. } => None,
        }
    }
}

/// The signed distance d_s(u, v) of Nishiyama et al. Eq. (2.18) (or the
/// linear-light distance) at one parameter; `None` where undefined.
pub fn surface_signed_distance(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    u: f64,
    v: f64,
) -> Option<f64> {
    light
        .sample_derivatives(&surface.derivatives(u, v))
        .map(|s| s.value)
}

/// A light's field sampled on a tensor grid of parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceField {
    /// Grid parameters in u (increasing).
    pub us: Vec<f64>,
    /// Grid parameters in v (increasing).
    pub vs: Vec<f64>,
    /// Samples, row-major: `samples[a * vs.len() + b]` at `(us[a], vs[b])`;
    /// `None` where the field is undefined.
    pub samples: Vec<Option<FieldSample>>,
}

impl DistanceField {
    /// The field value at grid point `(a, b)`.
    pub fn value(&self, a: usize, b: usize) -> Option<f64> {
        self.samples[a * self.vs.len() + b].map(|s| s.value)
    }
}

/// `n` parameters spread uniformly over `[t0, t1]`, ending exactly at `t1`.
pub(crate) fn uniform_params([t0, t1]: [f64; 2], n: usize) -> Vec<f64> {
    let n = n.max(2);
    (0..n)
        .map(|k| {
            if k + 1 == n {
                t1
            } else {
                t0 + (t1 - t0) * (k as f64 / (n - 1) as f64)
            }
        })
        .collect()
}

/// The field of `light` on the `nu × nv` uniform grid over the whole
/// parameter domain (each count at least 2). Points and first derivatives
/// come from [`BSplineSurface::map_grid_first`] (basis functions once per
/// grid row and column, the net contracted in u once per row), the normal
/// from Eq. (2.4), and the quartic of Eq. (2.15)–(2.16) is solved per grid
/// point without allocation; parallel over rows. Deterministic.
pub fn distance_field(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    nu: usize,
    nv: usize,
) -> DistanceField {
    let us = uniform_params(surface.domain_u(), nu);
    let vs = uniform_params(surface.domain_v(), nv);
    let samples =
        surface.map_grid_first(&us, &vs, |p, su, sv| light.sample(p, unit_normal(su, sv)?));
    DistanceField { us, vs, samples }
}

/// The lights m of a linear light array whose highlight lines can appear
/// on the surface (Yong et al. Eq. (1)–(2)): d_P is sampled on an `n × n`
/// grid and light m is kept when its level m·s crosses at least one grid
/// cell that [`contour_field`] contours — all four corners defined (|Z·N| ≥
/// `min_cos`), on one side of the light plane, and crossed by at most
/// [`SurfaceHighlightOptions::max_lines_per_cell`] (default) levels counted
/// by the mesh model's rule (`contour::too_many_levels`), so that cells
/// near silhouettes, where d_P runs off to infinity, do not decide which
/// lights are drawn, and the same lights are drawn as on the tessellated
/// surface. When more than
/// `max_lights` lights qualify, the `max_lights` consecutive ones crossing
/// the most cells are kept (the lights of the bulk of the surface, not the
/// middle of a range stretched by outliers). Empty when no cell qualifies.
pub fn linear_lights(
    surface: &BSplineSurface,
    array: LightArray,
    min_cos: f64,
    n: usize,
    max_lights: usize,
) -> Vec<SurfaceLight> {
    let probe = SurfaceLight::Linear {
        array,
        index: 0,
        min_cos,
    };
    let field = distance_field(surface, &probe, n, n);
    let spacing = array.spacing();
    let max_levels = i64::from(SurfaceHighlightOptions::default().max_lines_per_cell.max(1));
    let (nu, nv) = (field.us.len(), field.vs.len());
    let at = |a: usize, b: usize| field.samples[a * nv + b];
    // Cells crossed per light m, counted in one pass over the cells.
    let mut crossed: std::collections::BTreeMap<i64, usize> = std::collections::BTreeMap::new();
    for a in 0..nu.saturating_sub(1) {
        for b in 0..nv.saturating_sub(1) {
            let [Some(c0), Some(c1), Some(c2), Some(c3)] =
                [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]
            else {
                continue;
            };
            let c = [c0, c1, c2, c3];
            if c.iter().any(|x| x.branch != c0.branch) {
                continue;
            }
            let (lo, hi) = c
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                    (l.min(s.value), h.max(s.value))
                });
            if spacing <= 0.0 || super::contour::too_many_levels(lo, hi, spacing, 0.0, max_levels) {
                continue;
            }
            // Levels m·s with lo < m·s ≤ hi (a value equal to the level
            // counts as above, as in contour_field).
            let (m0, m1) = (
                (lo / spacing).floor() as i64 + 1,
                (hi / spacing).floor() as i64,
            );
            for m in m0..=m1 {
                *crossed.entry(m).or_insert(0) += 1;
            }
        }
    }
    if crossed.is_empty() || max_lights == 0 {
        return Vec::new();
    }
    let (first, last) = match (crossed.keys().next(), crossed.keys().next_back()) {
        (Some(&f), Some(&l)) => (f, l),
        _ => return Vec::new(),
    };
    let (mut m0, mut m1) = (first, last);
    if (last - first + 1) as usize > max_lights {
        // The window of max_lights consecutive lights crossing most cells
        // (the first such window: deterministic).
        let count = |m: i64| crossed.get(&m).copied().unwrap_or(0);
        let w = max_lights as i64;
        let mut sum: usize = (first..first + w).map(count).sum();
        let (mut best, mut best_start) = (sum, first);
        for start in first + 1..=last - w + 1 {
            sum = sum + count(start + w - 1) - count(start - 1);
            if sum > best {
                best = sum;
                best_start = start;
            }
        }
        m0 = best_start;
        m1 = best_start + w - 1;
    }
    (m0..=m1)
        .filter(|m| crossed.contains_key(m))
        .map(|index| SurfaceLight::Linear {
            array,
            index,
            min_cos,
        })
        .collect()
}

/// Options of [`surface_highlight_lines`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct SurfaceHighlightOptions {
    /// Grid points in u (≥ 2).
    pub grid_u: usize,
    /// Grid points in v (≥ 2).
    pub grid_v: usize,
    /// Band radius ρ: when set, the levels ±ρ are contoured too
    /// (Nishiyama et al. §2, "circular highlight band").
    pub band: Option<f64>,
    /// Absolute tolerance on |d_s − level| for refined contour points.
    pub tolerance: f64,
    /// Most refinement steps per contour point.
    pub max_refine_steps: usize,
    /// Linear lights: most lines one grid cell may be crossed by (default
    /// 4, counted as `HighlightOptions::max_lines_per_face` on mesh
    /// triangles: `ceil(hi/s) − floor(lo/s) ≤ 4 + 2`); a cell crossed by
    /// more is skipped, its lines being finer than the grid (this happens
    /// only near silhouettes). 0: no limit.
    pub max_lines_per_cell: u32,
}

crate::control::setters!(SurfaceHighlightOptions {
    grid_u: usize,
    grid_v: usize,
    tolerance: f64,
    max_refine_steps: usize,
});

impl Default for SurfaceHighlightOptions {
    fn default() -> Self {
        SurfaceHighlightOptions {
            grid_u: 200,
            grid_v: 200,
            band: None,
            tolerance: 1e-11,
            max_refine_steps: 80,
            max_lines_per_cell: 4,
        }
    }
}

impl SurfaceHighlightOptions {
    /// Sets both grid sizes.
    pub fn grid(mut self, n: usize) -> Self {
        self.grid_u = n;
        self.grid_v = n;
        self
    }
    /// Sets the band radius ρ.
    pub fn band(mut self, rho: Option<f64>) -> Self {
        self.band = rho;
        self
    }
    /// Sets [`SurfaceHighlightOptions::max_lines_per_cell`].
    pub fn max_lines_per_cell(mut self, n: u32) -> Self {
        self.max_lines_per_cell = n;
        self
    }
}

/// One pre-image polyline of a highlight line (or band boundary) and its
/// image on the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceHighlightLine {
    /// Position of the light in the input slice.
    pub light: usize,
    /// Radius R of the circular light (`None` for linear lights).
    pub radius: Option<f64>,
    /// Contoured level: 0 for the highlight line, ±ρ for band boundaries.
    pub level: f64,
    /// True when the polyline is a loop (the first point is not repeated).
    pub closed: bool,
    /// Parameters `[u, v]` of the points, each on a grid edge, refined so
    /// that |d_s − level| ≤ the tolerance where the field allows.
    pub uv: Vec<[f64; 2]>,
    /// Surface points `S(u, v)`.
    pub points: Vec<Vec3>,
}

/// All highlight lines of a surface: the zero levels and, with a band, the
/// ±ρ levels. Sorted by light, then by first grid edge (deterministic).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceHighlights {
    /// Zero-level pre-images (the highlight lines).
    pub lines: Vec<SurfaceHighlightLine>,
    /// Level −ρ (empty without a band).
    pub band_lower: Vec<SurfaceHighlightLine>,
    /// Level +ρ (empty without a band).
    pub band_upper: Vec<SurfaceHighlightLine>,
}

/// Circular (or linear) highlight lines of a B-spline surface (Nishiyama et
/// al. §2): for each light, d_s of Eq. (2.18) on the grid of `opts`, its
/// zero level by [`contour_field`], and with `opts.band = Some(ρ)` the band
/// boundaries d_s = ±ρ. Consecutive lights of one linear array share one
/// sampled field d_P (light m is its level m·s).
pub fn surface_highlight_lines(
    surface: &BSplineSurface,
    lights: &[SurfaceLight],
    opts: &SurfaceHighlightOptions,
) -> SurfaceHighlights {
    let mut out = SurfaceHighlights::default();
    // Lights of one linear array share d_P: its field is sampled once and
    // light m is the level m·s of it.
    let mut cache: Option<(SurfaceLight, DistanceField)> = None;
    for (k, light) in lights.iter().enumerate() {
        let (base, shift) = match *light {
            SurfaceLight::Linear {
                array,
                index,
                min_cos,
            } => (
                SurfaceLight::Linear {
                    array,
                    index: 0,
                    min_cos,
                },
                index as f64 * array.spacing(),
            ),
            SurfaceLight::Circular(_) => (*light, 0.0),
        };
        if !matches!(&cache, Some((l, _)) if *l == base) {
            cache = Some((
                base,
                distance_field(surface, &base, opts.grid_u, opts.grid_v),
            ));
        }
        let Some((_, field)) = &cache else {
            continue;
        };
        let level_set = |level: f64| {
            let mut ls = contour_field(surface, &base, k, field, shift + level, opts);
            for l in &mut ls {
                l.level = level;
                l.radius = light.radius();
            }
            ls
        };
        out.lines.extend(level_set(0.0));
        if let Some(rho) = opts.band.filter(|r| *r > 0.0 && r.is_finite()) {
            out.band_lower.extend(level_set(-rho));
            out.band_upper.extend(level_set(rho));
        }
    }
    out
}

/// Radii of [`default_circular_lights`] unless told otherwise.
pub const DEFAULT_CIRCULAR_RADII: usize = 10;

/// Circular lights derived from a part, for a user who
/// has none: the axis t is `axis` when given, else the area-weighted mean
/// normal `Σ N dA / Σ dA` of the part when its length is at least 0.2 (an
/// open panel or a shell facing one way), else +z (a closed body, whose
/// mean normal vanishes); the centre A lies on the axis through the
/// area-weighted centroid c, half a bounding-box diagonal above the part's
/// highest point along t. A circle of radius R lights the points whose
/// normal line meets the circle's plane at distance R from A (Nishiyama et
/// al. Eq. (2.8)–(2.10) with d_s = 0), so the `count` radii are spread
/// evenly between the 5 % and 95 % area quantiles of that distance over the
/// part (points with |N·t| < 0.1 left out): the lines span the part.
///
/// The part is sampled at the midpoints of a grid of at most 32 × 32 cells
/// per patch ([`patch_grid`] with 32 points along the part's diagonal),
/// dA = |S_u × S_v| Δu Δv (Nishiyama et al. Eq. (2.4)), cells outside the
/// trims left out. `None` when the part has no area or no usable normal.
pub fn default_circular_lights(
    surfaces: &[BSplineSurface],
    axis: Option<Vec3>,
    count: usize,
) -> Option<super::light::CircularLights> {
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for s in surfaces {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diagonal = (hi - lo).length();
    if !(diagonal > 0.0 && diagonal.is_finite()) || count == 0 {
        return None;
    }
    // (point, unit normal, area) at the cell midpoints of every patch.
    let samples: Vec<(Vec3, Vec3, f64)> = surfaces
        .par_iter()
        .flat_map_iter(|s| {
            let [nu, nv] = patch_grid(s, diagonal, 32).map(|n| n.saturating_sub(1).max(1));
            let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
            let (du, dv) = ((u1 - u0) / nu as f64, (v1 - v0) / nv as f64);
            let us: Vec<f64> = (0..nu).map(|a| u0 + (a as f64 + 0.5) * du).collect();
            let vs: Vec<f64> = (0..nv).map(|b| v0 + (b as f64 + 0.5) * dv).collect();
            let inside: Vec<bool> = match s.trim() {
                Some(t) => vs
                    .iter()
                    .flat_map(|&v| {
                        let xs = t.row_crossings(v);
                        us.iter()
                            .map(|&u| crate::bspline::inside_by_crossings(&xs, u))
                            .collect::<Vec<_>>()
                    })
                    .collect(),
                None => vec![true; nu * nv],
            };
            let cell = (du * dv).abs();
            let grid = s.map_grid_first(&us, &vs, |p, su, sv| {
                let n = su.cross(sv);
                let area = n.length() * cell;
                unit_normal(su, sv).map(|unit| (p, unit, area))
            });
            // grid is row-major over (u, v); `inside` is v-major.
            grid.into_iter()
                .enumerate()
                .filter_map(move |(k, x)| {
                    let (a, b) = (k / nv, k % nv);
                    if inside[b * nu + a] { x } else { None }
                })
                .filter(|(p, n, w)| p.is_finite() && n.is_finite() && w.is_finite() && *w > 0.0)
                .collect::<Vec<_>>()
        })
        .collect();
    circular_lights_over(&samples, diagonal, axis, count)
}

/// Default circular lights for a triangle mesh: as
/// [`default_circular_lights`], sampled at the triangle centroids with the
/// triangle normals and areas (polygons are not sampled).
pub fn default_circular_lights_for_mesh(
    mesh: &crate::SurfaceMesh,
    axis: Option<Vec3>,
    count: usize,
) -> Option<super::light::CircularLights> {
    let (lo, hi) = crate::mesh::bounding_box(mesh.positions())?;
    let samples: Vec<(Vec3, Vec3, f64)> = mesh
        .faces()
        .filter(|&f| mesh.face_size(f) == 3)
        .filter_map(|f| {
            let [a, b, c] = mesh.triangle(f).map(|v| mesh.position(v));
            let n = (b - a).cross(c - a);
            let area = 0.5 * n.length();
            let unit = n.try_normalize()?;
            Some(((a + b + c) / 3.0, unit, area))
        })
        .collect();
    circular_lights_over(&samples, (hi - lo).length(), axis, count)
}

/// The lights of [`default_circular_lights`] from area samples
/// (point, unit normal, area) of a part whose bounding-box diagonal is
/// `diagonal`.
fn circular_lights_over(
    samples: &[(Vec3, Vec3, f64)],
    diagonal: f64,
    axis: Option<Vec3>,
    count: usize,
) -> Option<super::light::CircularLights> {
    if !(diagonal > 0.0 && diagonal.is_finite()) || count == 0 {
        return None;
    }
    let total: f64 = samples.iter().map(|s| s.2).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mean_normal = samples.iter().fold(Vec3::ZERO, |acc, s| acc + s.2 * s.1) / total;
    let centroid = samples.iter().fold(Vec3::ZERO, |acc, s| acc + s.2 * s.0) / total;
    let t = match axis.and_then(|a| a.try_normalize()) {
        Some(a) => a,
        None if mean_normal.length() >= 0.2 => mean_normal.try_normalize()?,
        None => Vec3::Z,
    };
    let top = samples
        .iter()
        .map(|s| (s.0 - centroid).dot(t))
        .fold(f64::NEG_INFINITY, f64::max);
    let centre = centroid + (top + 0.5 * diagonal) * t;
    // Where each normal line meets the plane through A perpendicular to t.
    let mut dist: Vec<(f64, f64)> = samples
        .iter()
        .filter_map(|&(q, n, w)| {
            let nt = n.dot(t);
            if nt.abs() < 0.1 {
                return None;
            }
            let x = q + ((centre - q).dot(t) / nt) * n;
            let r = (x - centre).length();
            r.is_finite().then_some((r, w))
        })
        .collect();
    if dist.is_empty() {
        return None;
    }
    dist.sort_by(|a, b| a.0.total_cmp(&b.0));
    let weight: f64 = dist.iter().map(|d| d.1).sum();
    let quantile = |f: f64| {
        let mut acc = 0.0;
        for &(r, w) in &dist {
            acc += w;
            if acc >= f * weight {
                return r;
            }
        }
        dist[dist.len() - 1].0
    };
    let (r0, r1) = (quantile(0.05), quantile(0.95));
    let (r0, r1) = if r1 - r0 > 1e-6 * diagonal {
        (r0, r1)
    } else {
        // One radius for the whole part (a sphere seen from its centre):
        // rings around it.
        (0.5 * r0.max(0.05 * diagonal), 1.5 * r0.max(0.05 * diagonal))
    };
    let radii: Vec<f64> = (0..count)
        .map(|k| {
            if count == 1 {
                0.5 * (r0 + r1)
            } else {
                r0 + (r1 - r0) * k as f64 / (count - 1) as f64
            }
        })
        .map(|r| r.max(1e-9 * diagonal))
        .collect();
    Some(super::light::CircularLights {
        center: centre.to_array(),
        axis: t.to_array(),
        radii,
    })
}

/// The lights of a whole part (a file of many patches), Nishiyama et al.
/// §2 (circular) or Yong et al. Eq. (1)–(2) (linear).
#[derive(Clone, Debug, PartialEq)]
pub enum PartLights {
    /// The same circular lights on every patch.
    Circular(Vec<CircularLight>),
    /// One linear light array; each patch draws the lights of
    /// [`linear_lights`] (at most `max_lights`).
    Linear {
        /// The array.
        array: LightArray,
        /// Smallest |Z·N| at which the distance is defined.
        min_cos: f64,
        /// Most lights per patch.
        max_lights: usize,
    },
}

/// The highlight lines of one patch of a part.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchHighlights {
    /// The lights drawn on this patch (`SurfaceHighlightLine::light`
    /// indexes this list).
    pub lights: Vec<SurfaceLight>,
    /// The grid (u, v) the field was sampled on.
    pub grid: [usize; 2],
    /// The lines.
    pub highlights: SurfaceHighlights,
}

/// Most linear lights drawn per patch by default (a bound against
/// pathological inputs; the lights drawn are those whose lines the grid
/// resolves, see [`linear_lights`]).
pub const DEFAULT_MAX_LIGHTS: usize = 1000;

pub use crate::bspline::{MIN_PATCH_GRID, patch_grid};

/// Highlight lines of every patch of a part, in one run:
/// for a single surface exactly [`surface_highlight_lines`] with `opts`;
/// for several, each patch on its own [`patch_grid`] (the part's diagonal
/// from the control points of all patches, `opts.grid_u` points along it),
/// parallel over patches, results in input order (deterministic).
/// `on_patch` is called once per finished patch (progress).
pub fn part_highlight_lines(
    surfaces: &[BSplineSurface],
    lights: &PartLights,
    opts: &SurfaceHighlightOptions,
    on_patch: &(dyn Fn() + Sync),
) -> Vec<PatchHighlights> {
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for s in surfaces {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diagonal = (hi - lo).length();
    let single = surfaces.len() == 1;
    surfaces
        .par_iter()
        .map(|s| {
            let grid = if single {
                [opts.grid_u, opts.grid_v]
            } else {
                patch_grid(s, diagonal, opts.grid_u.max(opts.grid_v))
            };
            let patch_opts = SurfaceHighlightOptions {
                grid_u: grid[0],
                grid_v: grid[1],
                ..*opts
            };
            let patch_lights: Vec<SurfaceLight> = match lights {
                PartLights::Circular(c) => c.iter().map(|l| SurfaceLight::Circular(*l)).collect(),
                PartLights::Linear {
                    array,
                    min_cos,
                    max_lights,
                } => {
                    let n = if single {
                        opts.grid_u.min(400)
                    } else {
                        grid[0].max(grid[1]).min(400)
                    };
                    linear_lights(s, *array, *min_cos, n, *max_lights)
                }
            };
            let highlights = surface_highlight_lines(s, &patch_lights, &patch_opts);
            on_patch();
            PatchHighlights {
                lights: patch_lights,
                grid,
                highlights,
            }
        })
        .collect()
}

/// A grid edge: horizontal (along u) from `(a, b)` to `(a + 1, b)`, or
/// vertical (along v) from `(a, b)` to `(a, b + 1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GridEdge {
    U(usize, usize),
    V(usize, usize),
}

/// The level `level` of a sampled field as polylines in `(u, v)` (marching
/// squares) mapped to 3D:
///
/// - a grid edge carries a contour point when both ends are defined, lie on
///   the same branch (branch angles less than 90° apart) and on different
///   sides of the level (a value equal to the level counts as above);
/// - a cell whose four corners and edges are all valid contributes one
///   segment per pair of crossed edges; with four crossed edges (a saddle)
///   the value at the cell centre (mean of the corners) decides: the
///   segments cut off the corners on the other side of the level than the
///   centre, the same rule in every cell (consistent, no crossings);
/// - segments are chained through shared edges into open or closed lines;
/// - each point is refined along its grid edge by the Illinois variant of
///   regula falsi on the exact field until |d_s − level| ≤ `opts.tolerance`
///   (or `opts.max_refine_steps`); if the field becomes undefined inside
///   the edge, or the refinement finds no zero (the sign change is a jump
///   of d_s, e.g. where the nearest root of the quartic switches), the
///   point is dropped and its line split there.
pub fn contour_field(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    light_index: usize,
    field: &DistanceField,
    level: f64,
    opts: &SurfaceHighlightOptions,
) -> Vec<SurfaceHighlightLine> {
    let (nu, nv) = (field.us.len(), field.vs.len());
    if nu < 2 || nv < 2 || field.samples.len() != nu * nv {
        return Vec::new();
    }
    let edges = GridEdges { nu, nv };
    let segments = cell_segments(field, &edges, light, level, opts);
    if segments.is_empty() {
        return Vec::new();
    }
    let (nodes, chains) = chain_segments(&segments);
    // Refine every node onto the level along its grid edge; a crossing that
    // is a jump of the field (no zero inside the edge) is dropped.
    let refined: Vec<Option<[f64; 2]>> = nodes
        .par_iter()
        .map(|&id| {
            let ((a0, b0), (a1, b1)) = edges.ends(edges.edge(id));
            let p0 = [field.us[a0], field.vs[b0]];
            let p1 = [field.us[a1], field.vs[b1]];
            let f0 = field.samples[a0 * nv + b0].map_or(0.0, |s| s.value) - level;
            let f1 = field.samples[a1 * nv + b1].map_or(0.0, |s| s.value) - level;
            refine_on_edge(surface, light, level, p0, p1, f0, f1, opts)
        })
        .collect();
    let mut pieces = split_at_dropped_points(chains, &refined);
    if surface.is_trimmed() {
        pieces = clip_to_trims(surface, pieces);
    }
    pieces
        .into_iter()
        .filter(|(_, uv)| uv.len() >= 2)
        .map(|(closed, uv)| {
            let points = uv.iter().map(|&[u, v]| surface.eval(u, v)).collect();
            SurfaceHighlightLine {
                light: light_index,
                radius: light.radius(),
                level,
                closed,
                uv,
                points,
            }
        })
        .collect()
}

/// The edges of an `nu × nv` grid and their ids: `U(a, b)` → `a * nv + b`,
/// `V(a, b)` → `(nu − 1) nv + a (nv − 1) + b`.
#[derive(Clone, Copy, Debug)]
struct GridEdges {
    nu: usize,
    nv: usize,
}

impl GridEdges {
    /// The id of an edge.
    fn id(&self, e: GridEdge) -> usize {
        let n_u_edges = (self.nu - 1) * self.nv;
        match e {
            GridEdge::U(a, b) => a * self.nv + b,
            GridEdge::V(a, b) => n_u_edges + a * (self.nv - 1) + b,
        }
    }
    /// The edge of an id.
    fn edge(&self, id: usize) -> GridEdge {
        let n_u_edges = (self.nu - 1) * self.nv;
        if id < n_u_edges {
            GridEdge::U(id / self.nv, id % self.nv)
        } else {
            let k = id - n_u_edges;
            GridEdge::V(k / (self.nv - 1), k % (self.nv - 1))
        }
    }
    /// The grid points at the ends of an edge.
    fn ends(&self, e: GridEdge) -> ((usize, usize), (usize, usize)) {
        match e {
            GridEdge::U(a, b) => ((a, b), (a + 1, b)),
            GridEdge::V(a, b) => ((a, b), (a, b + 1)),
        }
    }
}

/// Marching squares on the level `level` of `field` (the rules of
/// [`contour_field`]): the segments of every cell as pairs of edge ids, in
/// cell order (parallel over cell rows, deterministic).
fn cell_segments(
    field: &DistanceField,
    edges: &GridEdges,
    light: &SurfaceLight,
    level: f64,
    opts: &SurfaceHighlightOptions,
) -> Vec<[usize; 2]> {
    let (nu, nv) = (edges.nu, edges.nv);
    let at = |a: usize, b: usize| field.samples[a * nv + b];
    // Linear lights: a cell crossed by more than `max_lines_per_cell`
    // levels holds lines finer than the grid (near silhouettes, where d_P
    // runs off as Z·N → 0); it is skipped by the rule the mesh model skips
    // triangles with (`HighlightOptions::max_lines_per_face`).
    let max_cell_levels = match light {
        SurfaceLight::Linear { array, .. } if opts.max_lines_per_cell > 0 => {
            Some((array.spacing(), i64::from(opts.max_lines_per_cell)))
        }
        _ => None,
    };
    (0..nu - 1)
        .into_par_iter()
        .flat_map_iter(|a| {
            let mut segs = Vec::new();
            for b in 0..nv - 1 {
                let [Some(c0), Some(c1), Some(c2), Some(c3)] =
                    [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]
                else {
                    continue;
                };
                cell_segment(
                    [c0, c1, c2, c3],
                    [a, b],
                    edges,
                    level,
                    max_cell_levels,
                    &mut segs,
                );
            }
            segs
        })
        .collect()
}

/// The segments of cell `(a, b)` with corner samples `c` (counter-clockwise
/// from `(a, b)`), appended to `segs`; see [`contour_field`].
fn cell_segment(
    c: [FieldSample; 4],
    [a, b]: [usize; 2],
    edges: &GridEdges,
    level: f64,
    max_cell_levels: Option<(f64, i64)>,
    segs: &mut Vec<[usize; 2]>,
) {
    let above = |s: FieldSample| s.value >= level;
    let same_branch = |x: FieldSample, y: FieldSample| (x.branch - y.branch).cos() > 0.0;
    // Cheap tests first: most cells are not crossed by the level.
    let side = c.map(above);
    if side.iter().all(|&x| x == side[0]) {
        return;
    }
    if let Some((spacing, most)) = max_cell_levels {
        let (lo, hi) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                (l.min(s.value), h.max(s.value))
            });
        // the levels of this field are m·s − shift: count them
        // as the mesh does (`contour::too_many_levels`)
        if super::contour::too_many_levels(lo, hi, spacing, level.rem_euclid(spacing), most) {
            return;
        }
    }
    if !(same_branch(c[0], c[1])
        && same_branch(c[1], c[2])
        && same_branch(c[2], c[3])
        && same_branch(c[3], c[0]))
    {
        return;
    }
    // Cell edges in order: bottom (c0-c1), right (c1-c2), top (c3-c2), left (c0-c3).
    let cell_edges = [
        GridEdge::U(a, b),
        GridEdge::V(a + 1, b),
        GridEdge::U(a, b + 1),
        GridEdge::V(a, b),
    ];
    let cut: Vec<usize> = (0..4).filter(|&k| side[k] != side[(k + 1) % 4]).collect();
    match cut.len() {
        2 => segs.push([edges.id(cell_edges[cut[0]]), edges.id(cell_edges[cut[1]])]),
        4 => {
            let centre = 0.25 * (c[0].value + c[1].value + c[2].value + c[3].value);
            let centre_above = centre >= level;
            // Corner k touches edges k-1 (previous) and k.
            for k in 0..4 {
                if side[k] != centre_above {
                    segs.push([edges.id(cell_edges[(k + 3) % 4]), edges.id(cell_edges[k])]);
                }
            }
        }
        _ => {}
    }
}

/// Chains segments (pairs of edge ids; every edge has at most two) through
/// their shared edges: the sorted edge ids (the nodes) and the chains as
/// (closed, node positions), open chains first (from their ends), then the
/// loops.
fn chain_segments(segments: &[[usize; 2]]) -> (Vec<usize>, Vec<(bool, Vec<usize>)>) {
    let mut nodes: Vec<usize> = segments.iter().flatten().copied().collect();
    nodes.sort_unstable();
    nodes.dedup();
    let index_of = |id: usize| nodes.binary_search(&id).unwrap_or(0);
    let mut adj: Vec<[usize; 2]> = vec![[usize::MAX; 2]; nodes.len()];
    for s in segments {
        let (x, y) = (index_of(s[0]), index_of(s[1]));
        for (p, q) in [(x, y), (y, x)] {
            if adj[p][0] == usize::MAX {
                adj[p][0] = q;
            } else if adj[p][1] == usize::MAX {
                adj[p][1] = q;
            }
        }
    }
    let degree = |p: usize| adj[p].iter().filter(|&&q| q != usize::MAX).count();
    let mut used = vec![false; nodes.len()];
    let mut chains: Vec<(bool, Vec<usize>)> = Vec::new();
    let walk = |start: usize, used: &mut Vec<bool>| -> (bool, Vec<usize>) {
        let mut chain = vec![start];
        used[start] = true;
        let mut prev = usize::MAX;
        let mut cur = start;
        loop {
            let next = adj[cur]
                .iter()
                .copied()
                .find(|&q| q != usize::MAX && q != prev && !used[q]);
            match next {
                Some(q) => {
                    used[q] = true;
                    chain.push(q);
                    prev = cur;
                    cur = q;
                }
                None => {
                    let closed = chain.len() > 2 && adj[cur].contains(&start);
                    return (closed, chain);
                }
            }
        }
    };
    for p in 0..nodes.len() {
        if !used[p] && degree(p) <= 1 {
            let c = walk(p, &mut used);
            chains.push((false, c.1));
        }
    }
    for p in 0..nodes.len() {
        if !used[p] {
            chains.push(walk(p, &mut used));
        }
    }
    (nodes, chains)
}

/// The chains as polylines of refined points, each split where a point was
/// dropped (`None`; a loop is opened at its first dropped point).
fn split_at_dropped_points(
    chains: Vec<(bool, Vec<usize>)>,
    refined: &[Option<[f64; 2]>],
) -> Vec<(bool, Vec<[f64; 2]>)> {
    let mut pieces: Vec<(bool, Vec<[f64; 2]>)> = Vec::new();
    for (closed, chain) in chains {
        if chain.iter().all(|&p| refined[p].is_some()) {
            pieces.push((closed, chain.iter().filter_map(|&p| refined[p]).collect()));
            continue;
        }
        let n = chain.len();
        let shift = if closed {
            chain
                .iter()
                .position(|&p| refined[p].is_none())
                .unwrap_or(0)
        } else {
            0
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        for k in 0..n {
            match refined[chain[(shift + k) % n]] {
                Some(p) => run.push(p),
                None => pieces.push((false, std::mem::take(&mut run))),
            }
        }
        pieces.push((false, run));
    }
    pieces
}

/// Keeps the parts of `(closed, uv)` polylines that lie in the trimmed face
/// ([`BSplineSurface::contains_uv`]): a polyline is cut where it leaves the
/// face, the cut point found by bisection (40 steps) on the segment between
/// the inside and the outside point, so lines end on the trimming loop.
fn clip_to_trims(
    surface: &BSplineSurface,
    pieces: Vec<(bool, Vec<[f64; 2]>)>,
) -> Vec<(bool, Vec<[f64; 2]>)> {
    let boundary = |inside: [f64; 2], outside: [f64; 2]| {
        let (mut a, mut b) = (inside, outside);
        for _ in 0..40 {
            let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            if surface.contains_uv(m[0], m[1]) {
                a = m;
            } else {
                b = m;
            }
        }
        a
    };
    let mut out = Vec::new();
    for (closed, uv) in pieces {
        let inside: Vec<bool> = uv.iter().map(|p| surface.contains_uv(p[0], p[1])).collect();
        if inside.iter().all(|&x| x) {
            out.push((closed, uv));
            continue;
        }
        let n = uv.len();
        // Start a loop at an outside point so that runs do not wrap.
        let (shift, count) = if closed {
            (inside.iter().position(|&x| !x).unwrap_or(0), n + 1)
        } else {
            (0, n)
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        for k in 0..count {
            let i = (shift + k) % n;
            if inside[i] {
                if run.is_empty() && k > 0 {
                    let prev = (shift + k - 1) % n;
                    run.push(boundary(uv[i], uv[prev]));
                }
                run.push(uv[i]);
            } else if !run.is_empty() {
                let prev = (shift + k + n - 1) % n;
                run.push(boundary(uv[prev], uv[i]));
                out.push((false, std::mem::take(&mut run)));
            }
        }
        if !run.is_empty() {
            out.push((false, run));
        }
    }
    out
}

/// The point of the segment `p0 → p1` where the field equals `level`, with
/// `f0 = field(p0) − level` and `f1 = field(p1) − level` of opposite signs:
/// Illinois regula falsi on the exact field (safeguarded by the bracket).
/// `None` when the sign change is a jump of the field rather than a zero
/// (the best |f| found stays above 1e-6 of the end values and above the
/// tolerance).
#[allow(clippy::too_many_arguments)]
fn refine_on_edge(
    surface: &BSplineSurface,
    light: &SurfaceLight,
    level: f64,
    p0: [f64; 2],
    p1: [f64; 2],
    f0: f64,
    f1: f64,
    opts: &SurfaceHighlightOptions,
) -> Option<[f64; 2]> {
    let lerp = |t: f64| [p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])];
    let linear_t = |fa: f64, fb: f64, ta: f64, tb: f64| {
        let den = fa - fb;
        if den != 0.0 && den.is_finite() {
            (ta + fa * (tb - ta) / den).clamp(ta.min(tb), ta.max(tb))
        } else {
            0.5 * (ta + tb)
        }
    };
    if f0 == 0.0 {
        return Some(p0);
    }
    if f1 == 0.0 {
        return Some(p1);
    }
    let (mut ta, mut fa, mut tb, mut fb) = (0.0, f0, 1.0, f1);
    let mut best = (linear_t(fa, fb, ta, tb), f64::INFINITY);
    let mut side = 0i8;
    for _ in 0..opts.max_refine_steps {
        let t = linear_t(fa, fb, ta, tb);
        let [u, v] = lerp(t);
        let Some(ft) = surface_signed_distance(surface, light, u, v).map(|d| d - level) else {
            // Undefined inside the edge: no reliable zero there.
            return None;
        };
        if ft.abs() < best.1 {
            best = (t, ft.abs());
        }
        if ft.abs() <= opts.tolerance || (tb - ta).abs() < 1e-15 {
            break;
        }
        if (ft < 0.0) == (fa < 0.0) {
            ta = t;
            fa = ft;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            tb = t;
            fb = ft;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    // A true zero brings |f| down to the tolerance (or to rounding level on
    // a collapsed bracket); a jump leaves it near the jump's size.
    let accept = best.1 <= opts.tolerance.max(1e-6 * f0.abs().max(f1.abs()));
    accept.then(|| lerp(best.0))
}

mod part;
pub use part::{
    LIGHT_CHOICE_SAMPLES, best_covered_lights, linear_distance_gradient,
    linear_separation_on_screen, part_light_array, part_view, readable_surface_lines,
    readable_surface_lines_in_view,
};

#[cfg(test)]
mod tests;
