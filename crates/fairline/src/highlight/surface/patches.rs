//! Highlight lines of a whole part: the lights of every patch and the lines
//! of each patch on its own grid.

use super::lights::linear_lights;
use super::{SurfaceHighlightOptions, SurfaceHighlights, SurfaceLight, surface_highlight_lines};
use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::highlight::light::{CircularLight, LightArray};
use rayon::prelude::*;

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
