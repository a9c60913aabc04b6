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

mod lights;
mod marching;
mod part;
mod patches;

pub use lights::{
    DEFAULT_CIRCULAR_RADII, default_circular_lights, default_circular_lights_for_mesh,
    linear_lights,
};
pub use marching::contour_field;
pub use part::{
    LIGHT_CHOICE_SAMPLES, best_covered_lights, linear_distance_gradient,
    linear_separation_on_screen, part_light_array, part_view, readable_surface_lines,
    readable_surface_lines_in_view,
};
pub use patches::{
    DEFAULT_MAX_LIGHTS, MIN_PATCH_GRID, PartLights, PatchHighlights, part_highlight_lines,
    patch_grid,
};

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

#[cfg(test)]
mod tests;
