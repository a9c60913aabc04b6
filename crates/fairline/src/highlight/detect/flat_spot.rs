//! The flat-spot measure of detection (module documentation of
//! [`super`], step 8): where the surface's curvature drops against the
//! surface smoothed at a few smooth radii, over an area of several sites.
//!
//! The normal measure compares each site with a cubic over R; a dent or a
//! flat spot wider than about R bends that cubic with it and is not seen
//! (a 0.3-wide, 2 %-deep dent on the flank of the 2.9k-vertex Spot, with
//! R = 0.24: docs/guide/inspect-mesh.md). What such a defect
//! does to the surface is to take away its curvature: a flank that curves
//! one way goes flat or turns the other way over the defect's area, while
//! the surface smoothed at a wavelength of a few R — the intended shape at
//! that scale — keeps curving. The measure, per judged site:
//!
//! 1. **Smoothed surface.** The mesh is smoothed by Taubin's λ|μ filter
//!    (Taubin 1995, uniform weights, boundary fixed, 60 iterations) with
//!    its pass band at the wavelength ℓ = 4 R: k_PB = (π h / ℓ)², h the
//!    mean edge (the uniform Laplacian's eigenvalue of a wave of length ℓ
//!    on a regular mesh is about (π h / ℓ)²). Shape at longer wavelengths
//!    stays; a defect up to about 2 R across is mostly removed.
//! 2. **Curvature tensors** (Rusinkiewicz 2004) of the input and of the
//!    smoothed mesh are averaged over the vertices within the footprint
//!    max(2 h, r_f) of the site (those facing the site: normals within
//!    60°).
//! 3. **Relative curvature drop** in the smoothed surface's most curved
//!    direction t at the site: ρ = (κ_s(t) − κ(t)) / κ_s(t). ρ = 0 where
//!    the surface curves as its smooth version does, 1 where it is flat,
//!    above 1 where it curves the other way; it does not depend on scale.
//!    Cylinders, tori and every smooth shape keep ρ near 0 (the smoothing
//!    changes curvature only at wavelengths below ℓ).
//! 4. **Over an area.** A flat spot is an area, not a point: the value of
//!    a site is the median of ρ over the judged sites within 0.35 R of it,
//!    which takes away single sites where a scan's roughness makes the
//!    curvature jump.
//! 5. **Where curvature is resolved.** ρ divides by κ_s, so it is judged
//!    only where the smoothed surface curves clearly above the mesh's
//!    curvature noise: the median of |κ_s|·R over the same area must exceed
//!    `flat_spot_factor` × the *curvature noise*, the median over the
//!    judged sites of |κ_s − κ|·R (a scan's roughness, an artist mesh's
//!    faceting). On a nearly flat surface a flat spot is no defect of its
//!    own (a dent there turns the normals and the normal measure sees it).
//! 6. **Floor.** A site is flagged when its value exceeds
//!    max(0.5, `flat_spot_factor` × the 90th percentile of |value| over
//!    the judged sites): the curvature must fall at least by half, and
//!    stand out of what the mesh shows everywhere.
//!
//! Measured (BENCHMARKS.md): the wide dent on Spot 0.94 against
//! its floor 0.54 (the narrow one 0.75 against 0.57); clean Spot at most
//! 0.37, bunny_npm 0.20, the raw bunny scan 0.69 against its floor 0.95;
//! every generated family (saddles, sin·sin hills, panels, domes,
//! cylinders, tori, 5k and 50k vertices) at most 0.05. The values do not
//! move much with the choices: the wavelength 3 or 4 R, the area 0.3–0.45
//! R, the factor 3 or 4 all separate the dent from every clean mesh.
//!
//! Reach. Sixty Taubin iterations smooth a wavelength of 4 R when R is
//! about five mean edges — the meshes too coarse for the spacing, where R
//! is raised to 2 r_f and defects a spacing or two wide
//! can be wider than R: the case this measure is for. On finer meshes the
//! filter reaches less far (its attenuation per iteration falls with
//! (h/ℓ)⁴), so the smoothed surface keeps wide dents and the measure stays
//! quiet there; R is 1.5 spacings on such meshes and the normal measure
//! covers defects up to that size (measured: a dent 2 spacings wide on the
//! 5k-vertex panel is flagged by the normal measure, not by this one).

use super::FLAT_SPOT_WAVELENGTH as WAVELENGTH;
use super::fits::frame;
use super::grid::Grid;
use super::noise::median;
use super::report::Site;
use crate::Vec3;
use crate::geom;
use crate::mesh::SurfaceMesh;
use crate::smooth::{TaubinOptions, taubin_smooth};
use rayon::prelude::*;

/// Taubin iterations of the smoothing (step 1).
const ITERATIONS: usize = 60;
/// Radius of the area over which a site's value is the median, in smooth
/// radii (step 4).
const AREA: f64 = 0.35;
/// The least value flagged: the curvature falls at least by half (step 6).
const LEAST_DROP: f64 = 0.5;

/// What the flat-spot measure says about a mesh.
pub(super) struct FlatSpots {
    /// Per site: the area median of the relative curvature drop, 0 where
    /// the curvature is not resolved; `None` where the site is not judged.
    pub values: Vec<Option<f64>>,
    /// The floor of step 6 (0 when the measure is off).
    pub floor: f64,
    /// Median |κ_s − κ|·R over the judged sites (dimensionless).
    pub curvature_noise: f64,
}

impl FlatSpots {
    /// The measure switched off or impossible: nothing judged.
    fn none(n: usize) -> Self {
        FlatSpots {
            values: vec![None; n],
            floor: 0.0,
            curvature_noise: 0.0,
        }
    }

    /// Whether site `i` is flagged.
    pub fn flagged(&self, i: usize) -> bool {
        self.floor > 0.0 && self.values[i].is_some_and(|v| v > self.floor)
    }
}

/// The measure at the `sites` judged by the normal measure (those with a
/// score); `factor` is [`super::DetectOptions::flat_spot_factor`] (0: off).
pub(super) fn flat_spots(
    mesh: &SurfaceMesh,
    sites: &[Site],
    smooth_radius: f64,
    fine_radius: f64,
    factor: f64,
) -> FlatSpots {
    let judged: Vec<usize> = (0..sites.len())
        .filter(|&i| sites[i].score.is_some())
        .collect();
    if factor <= 0.0 || judged.is_empty() || !(smooth_radius > 0.0) {
        return FlatSpots::none(sites.len());
    }
    let h = geom::mean_edge_length(mesh);
    let foot = (2.0 * h).max(fine_radius);
    let Some(smooth) = smoothed(mesh, h, WAVELENGTH * smooth_radius) else {
        return FlatSpots::none(sites.len());
    };
    let drops = curvature_drops(mesh, &smooth, sites, &judged, foot);
    let r = smooth_radius;
    let curvature_noise = median(
        drops
            .iter()
            .flatten()
            .map(|d| (d.smooth - d.input).abs() * r)
            .collect(),
    );
    // step 4 and 5: the median over the area, where curvature is resolved
    let p = mesh.positions();
    let area = AREA * r;
    let grid = Grid::new(
        area,
        judged
            .iter()
            .filter(|&&i| drops[i].is_some())
            .map(|&i| (i as u32, p[sites[i].vertex.idx()])),
    );
    let gate = factor * curvature_noise;
    let values: Vec<Option<f64>> = (0..sites.len())
        .into_par_iter()
        .map(|i| {
            drops[i]?;
            let q = p[sites[i].vertex.idx()];
            let (mut rel, mut curved) = (Vec::new(), Vec::new());
            grid.around(q, |j| {
                let j = j as usize;
                if let Some(d) = drops[j]
                    && (p[sites[j].vertex.idx()] - q).length_squared() < area * area
                {
                    rel.push(d.relative());
                    curved.push(d.smooth.abs() * r);
                }
            });
            Some(if median(curved) > gate {
                median(rel)
            } else {
                0.0
            })
        })
        .collect();
    let mut magnitudes: Vec<f64> = values.iter().flatten().map(|v| v.abs()).collect();
    magnitudes.sort_by(f64::total_cmp);
    let p90 = magnitudes
        .get(magnitudes.len() * 9 / 10)
        .copied()
        .unwrap_or(0.0);
    FlatSpots {
        values,
        floor: LEAST_DROP.max(factor * p90),
        curvature_noise,
    }
}

/// The mesh's positions smoothed by Taubin's filter with its pass band at
/// `wavelength` (step 1); `None` when the filter refuses the mesh.
fn smoothed(mesh: &SurfaceMesh, h: f64, wavelength: f64) -> Option<SurfaceMesh> {
    if !(h > 0.0) || !(wavelength > 0.0) {
        return None;
    }
    let k_pb = (std::f64::consts::PI * h / wavelength)
        .powi(2)
        .clamp(1e-4, 0.5);
    let out = taubin_smooth(
        mesh,
        &TaubinOptions::default()
            .pass_band(k_pb)
            .iterations(ITERATIONS)
            .fix_boundary(true),
    )
    .ok()?;
    if !out.positions.iter().all(|q| q.is_finite()) {
        return None;
    }
    let mut m = mesh.clone();
    m.positions_mut().copy_from_slice(&out.positions);
    Some(m)
}

/// The footprint-averaged curvatures of one site in the smoothed surface's
/// most curved direction.
#[derive(Clone, Copy, Debug)]
pub(super) struct Drop {
    /// κ_s(t) of the smoothed surface.
    pub smooth: f64,
    /// κ(t) of the input.
    pub input: f64,
}

impl Drop {
    /// ρ = (κ_s − κ)/κ_s (0 where κ_s vanishes).
    pub fn relative(&self) -> f64 {
        if self.smooth.abs() > f64::EPSILON {
            (self.smooth - self.input) / self.smooth
        } else {
            0.0
        }
    }
}

/// Steps 2 and 3 at the judged sites (`None` elsewhere and where no vertex
/// of the footprint has a finite curvature).
pub(super) fn curvature_drops(
    mesh: &SurfaceMesh,
    smooth: &SurfaceMesh,
    sites: &[Site],
    judged: &[usize],
    foot: f64,
) -> Vec<Option<Drop>> {
    let method = geom::CurvatureMethod::Rusinkiewicz;
    let (pc, ps) = (
        geom::principal_curvatures(mesh, method),
        geom::principal_curvatures(smooth, method),
    );
    let p = mesh.positions();
    let tensor = |c: &geom::PrincipalCurvatures, v: usize| {
        outer(c.d1[v]) * c.k1[v] + outer(c.d2[v]) * c.k2[v]
    };
    let grid = Grid::new(foot, p.iter().enumerate().map(|(i, &q)| (i as u32, q)));
    let mut is_judged = vec![false; sites.len()];
    for &i in judged {
        is_judged[i] = true;
    }
    (0..sites.len())
        .into_par_iter()
        .map(|i| {
            if !is_judged[i] {
                return None;
            }
            let v = sites[i].vertex.idx();
            let (q0, n0) = (p[v], ps.normals[v]);
            let (mut t0, mut t1, mut count) = (glam::DMat3::ZERO, glam::DMat3::ZERO, 0usize);
            grid.around(q0, |u| {
                let u = u as usize;
                if (p[u] - q0).length_squared() < foot * foot
                    && pc.k1[u].is_finite()
                    && pc.k2[u].is_finite()
                    && ps.k1[u].is_finite()
                    && ps.k2[u].is_finite()
                    && ps.normals[u].dot(n0) > 0.5
                {
                    t0 += tensor(&pc, u);
                    t1 += tensor(&ps, u);
                    count += 1;
                }
            });
            if count == 0 || n0 == Vec3::ZERO {
                return None;
            }
            let w = 1.0 / count as f64;
            let (smooth, input) = most_curved_direction(n0, &(t1 * w), &(t0 * w));
            (smooth.is_finite() && input.is_finite()).then_some(Drop { smooth, input })
        })
        .collect()
}

fn outer(a: Vec3) -> glam::DMat3 {
    glam::DMat3::from_cols(a * a.x, a * a.y, a * a.z)
}

/// The normal curvature of `reference` (a curvature tensor, 3×3) in its
/// most curved tangent direction t at the normal `n0` (36 directions over
/// half a turn), and that of `tensor` in the same direction:
/// (κ_reference(t), κ_tensor(t)).
pub(super) fn most_curved_direction(
    n0: Vec3,
    reference: &glam::DMat3,
    tensor: &glam::DMat3,
) -> (f64, f64) {
    let (bx, by) = frame(n0);
    let k = |m: &glam::DMat3, t: Vec3| t.dot(*m * t);
    let (mut best_t, mut best_k) = (bx, 0.0f64);
    for i in 0..36 {
        let a = i as f64 * std::f64::consts::PI / 36.0;
        let t = a.cos() * bx + a.sin() * by;
        if k(reference, t).abs() > best_k.abs() {
            (best_t, best_k) = (t, k(reference, t));
        }
    }
    (best_k, k(tensor, best_t))
}
