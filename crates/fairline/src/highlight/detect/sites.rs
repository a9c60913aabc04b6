//! Site scores: the lengths of the measure on one mesh, the choice of
//! sites, their fine fits and the coarse fits that judge them (steps 1–4
//! and 6 of the module documentation of [`super`]).

use super::fits::{fine_fit, smooth_normal};
use super::grid::{Cell, CellHasher, Grid};
use super::options::DetectOptions;
use crate::Vec3;
use crate::geom;
use crate::highlight::LightArray;
use crate::mesh::{SurfaceMesh, VertexId};
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

/// The lengths of the measure on one mesh (mesh units).
pub(super) struct Scale {
    /// Light spacing s.
    pub(super) spacing: f64,
    /// Fine-fit radius r_f = max(fine_radius·s, 2.5 h).
    pub(super) fine_radius: f64,
    /// Smooth-fit radius R = max(smooth_radius·s, 2 r_f).
    pub(super) smooth_radius: f64,
    /// Side of the cubes that hold one site each.
    pub(super) site_cell: f64,
}

impl Scale {
    /// How many times R exceeds `smooth_radius`·s (1 unless the mesh is
    /// coarse against the spacing and R was raised to 2 r_f).
    pub(super) fn coarsening(&self, o: &DetectOptions) -> f64 {
        let nominal = o.smooth_radius * self.spacing;
        if nominal > 0.0 && self.smooth_radius.is_finite() {
            (self.smooth_radius / nominal).max(1.0)
        } else {
            1.0
        }
    }

    pub(super) fn new(mesh: &SurfaceMesh, light: &LightArray, o: &DetectOptions) -> Self {
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
pub(super) fn site_vertices(p: &[Vec3], normals: &[Vec3], cell: f64) -> Vec<u32> {
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
pub(super) fn vertex_facet_angles(mesh: &SurfaceMesh) -> Vec<f64> {
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
pub(super) struct FineFit {
    /// Denoised position p̂.
    pub(super) position: Vec3,
    /// Its unit normal n̂.
    pub(super) normal: Vec3,
    /// Weighted RMS residual (mesh units; NaN when no fit was possible).
    pub(super) residual: f64,
    /// Mean facet angle of the vertices within the fine radius (radians).
    pub(super) facet_angle: f64,
}

/// Fine fits at every site (step 2 of the [module documentation](super)): a cubic
/// over r_f, over a radius grown to hold 20 vertices where there are too
/// few (boundaries, corners), else a quadric; `None` where no finite fit
/// exists.
pub(super) fn fine_fits(
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
pub(super) struct Judgement {
    /// Score θ/θ₀ (`None`: not judged).
    pub(super) score: Option<f64>,
    /// θ₀ = 0.1·s/L: the normal error of score 1 at this site (radians).
    pub(super) unit_angle: f64,
    /// Not judged because the surface turns by more than `max_turn`
    /// within R (shape finer than the measure).
    pub(super) shape: bool,
}

/// Coarse fits and scores (steps 3, 4 and 6 of the [module documentation](super)).
pub(super) fn judge_sites(
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
