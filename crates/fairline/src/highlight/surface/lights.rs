//! The lights drawn on a surface by default: the linear lights whose lines
//! the grid resolves, and the circular lights spread over the surface's
//! extent.

use super::{SurfaceHighlightOptions, SurfaceLight, distance_field, patch_grid};
use crate::Vec3;
use crate::bspline::{BSplineSurface, unit_normal};
use crate::highlight::light::LightArray;
use crate::highlight::{contour, light};
use rayon::prelude::*;

/// The lights m of a linear light array whose highlight lines can appear
/// on the surface (Yong et al. Eq. (1)–(2)): d_P is sampled on an `n × n`
/// grid and light m is kept when its level m·s crosses at least one grid
/// cell that [`contour_field`](super::contour_field) contours — all four corners defined (|Z·N| ≥
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
            if spacing <= 0.0 || contour::too_many_levels(lo, hi, spacing, 0.0, max_levels) {
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
) -> Option<light::CircularLights> {
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
) -> Option<light::CircularLights> {
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
) -> Option<light::CircularLights> {
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
    Some(light::CircularLights {
        center: centre.to_array(),
        axis: t.to_array(),
        radii,
    })
}
