//! Spring model of Yamada et al. (Grüner thesis §3.3, Eq. (20)–(24)).

use super::{Constraints, Role, SmoothError, SmoothReport, max_distance, roles, setters};
use crate::geom;
use crate::mesh::{SurfaceMesh, VertexId};
use crate::{Control, Output, Vec3};

/// Options of [`spring_smooth`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SpringOptions {
    /// Stop when the largest displacement of a sweep divided by the mean
    /// length of that vertex's edges is below ε.
    pub epsilon: f64,
    /// Upper bound on the number of Gauss–Seidel sweeps.
    pub max_iterations: usize,
    /// Positional constraints: vertices that never move (bit-identical in
    /// the output). Boundary vertices are always fixed, as Yamada et al.
    /// require positional constraints on the boundary nodes.
    pub fixed: Vec<VertexId>,
    /// Normal constraints (Grüner §3.3): these vertices use the given
    /// normal (normalised) instead of the estimated one. Boundary vertices
    /// not listed get a normal from a quadric fit over the input two-ring.
    pub normals: Vec<(VertexId, Vec3)>,
    /// Relative stopping rule: stop once the root-mean-square displacement
    /// of a sweep (relative to each vertex's mean edge length) is more than
    /// `stall_ratio` times that of the sweep before, from the third sweep
    /// on. The spring iteration damps the high-frequency modes (noise) by a
    /// large factor per sweep and the low-frequency ones (legs, horns, the
    /// shape itself) by a factor near one; when the sweeps stop shrinking
    /// fast, the noise is gone and further sweeps only erode features.
    /// `None` keeps only the absolute rule `epsilon`.
    pub stall_ratio: Option<f64>,
    /// Progress callback and cancel flag (one step per sweep).
    pub control: Control,
}

/// Default of [`SpringOptions::stall_ratio`].
pub const STALL_RATIO: f64 = 0.8;

impl Default for SpringOptions {
    fn default() -> Self {
        SpringOptions {
            epsilon: 1e-4,
            max_iterations: 200,
            fixed: Vec::new(),
            normals: Vec::new(),
            stall_ratio: Some(STALL_RATIO),
            control: Control::default(),
        }
    }
}

setters!(SpringOptions {
    epsilon: f64,
    max_iterations: usize,
    fixed: Vec<VertexId>,
    normals: Vec<(VertexId, Vec3)>,
    stall_ratio: Option<f64>,
    control: Control,
});

/// Spring-model fairing: each free node moves by the inverse-length
/// weighted average (Eq. (24)) of the spring displacements
/// dp_ij = ⟨p_j − p_i, n_i + n_j⟩ / (1 + ⟨n_i, n_j⟩) n_i (Eq. (23), n_j
/// reversed when ⟨n_i, n_j⟩ < 0) plus the tangential part of the uniform
/// Laplacian dp_u,i. Gauss–Seidel: each sweep updates nodes in index order
/// using the latest positions (normals are recomputed per sweep, by
/// [`geom::vertex_normals`]). Any polygon mesh.
///
/// Stopping: `epsilon` on the largest relative sweep displacement (Yamada
/// et al.'s convergence) or, by default, the relative rule of
/// [`SpringOptions::stall_ratio`] — on the cow "Spot" the fixed count of
/// 200 sweeps moved vertices by 4.7 mean edge lengths (legs and horns
/// eroded), the relative rule stops after 4 sweeps with 1.5 mean edge
/// lengths and the volume within 0.2 %. `converged` is true when either
/// rule stopped the iteration.
pub fn spring_smooth(
    mesh: &SurfaceMesh,
    opts: &SpringOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    let c = Constraints {
        fixed: opts.fixed.clone(),
        fix_boundary: true,
        ..Constraints::default()
    };
    let roles = roles(mesh, &c)?;
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let mut work = mesh.clone();
    let mut iterations = 0;
    let mut converged = false;
    let nbrs: Vec<Vec<usize>> = mesh
        .vertices()
        .map(|v| mesh.one_ring(v).map(|u| u.idx()).collect())
        .collect();
    // Normal constraint at the boundary (Grüner §3.3): a boundary node sees
    // half a fan, whose averaged normal is tilted by O(h) and would bend the
    // whole patch; its normal is taken once from a quadric fit over the
    // two-ring of the input ([`geom::quadric_fit`]).
    let n = mesh.vertex_count();
    let mut given = vec![None; n];
    for &(v, nrm) in &opts.normals {
        if v.idx() >= n {
            return Err(SmoothError::FixedVertexOutOfRange {
                vertex: v.idx(),
                count: n,
            });
        }
        let u = nrm.normalize_or_zero();
        if u == Vec3::ZERO || !u.is_finite() {
            return Err(SmoothError::InvalidOption(format!(
                "normal constraint of vertex {} is not a direction",
                v.idx()
            )));
        }
        given[v.idx()] = Some(u);
    }
    let boundary_normals: Vec<(usize, Vec3)> = mesh
        .vertices()
        .filter_map(|v| match given[v.idx()] {
            Some(u) => Some((v.idx(), u)),
            None if roles[v.idx()] == Role::Fixed && mesh.is_boundary_vertex(v) => {
                geom::quadric_fit(mesh, v).map(|f| (v.idx(), f.normal))
            }
            None => None,
        })
        .collect();
    if let Some(r) = opts.stall_ratio
        && !(r > 0.0 && r < 1.0)
    {
        return Err(SmoothError::InvalidOption(format!(
            "spring stall ratio must lie in (0, 1), got {r}"
        )));
    }
    let mut previous_rms = f64::INFINITY;
    while iterations < opts.max_iterations {
        opts.control
            .step("iterations", iterations as u64, opts.max_iterations as u64)?;
        iterations += 1;
        let mut normals = geom::vertex_normals_max(&work);
        for &(i, nrm) in &boundary_normals {
            normals[i] = nrm;
        }
        let p = work.positions_mut();
        let mut worst: f64 = 0.0;
        let (mut sum_sq, mut moved) = (0.0, 0usize);
        for i in 0..p.len() {
            if roles[i] != Role::Free || nbrs[i].is_empty() {
                continue;
            }
            let ni = normals[i];
            if ni == Vec3::ZERO {
                continue;
            }
            let x = p[i];
            let (mut sw, mut sd, mut lap, mut lsum) = (0.0, 0.0, Vec3::ZERO, 0.0);
            for &j in &nbrs[i] {
                let d = p[j] - x;
                let l = d.length();
                lap += p[j];
                lsum += l;
                if !(l > 0.0) {
                    continue;
                }
                let mut nj = normals[j];
                if nj.dot(ni) < 0.0 {
                    nj = -nj;
                }
                let den = 1.0 + ni.dot(nj);
                if !(den > 1e-12) {
                    continue;
                }
                let w = 1.0 / l;
                sw += w;
                sd += w * d.dot(ni + nj) / den;
            }
            let m = nbrs[i].len() as f64;
            let u0 = lap / m - x;
            let du = u0 - u0.dot(ni) * ni;
            let dn = if sw > 0.0 { sd / sw } else { 0.0 };
            let disp = dn * ni + du;
            let mean_l = lsum / m;
            if disp.is_finite() {
                p[i] = x + disp;
                if mean_l > 0.0 {
                    let rel = disp.length() / mean_l;
                    worst = worst.max(rel);
                    sum_sq += rel * rel;
                    moved += 1;
                }
            }
        }
        if worst < opts.epsilon {
            converged = true;
            break;
        }
        let rms = (sum_sq / moved.max(1) as f64).sqrt();
        if let Some(r) = opts.stall_ratio
            && iterations >= 3
            && rms > r * previous_rms
        {
            converged = true;
            break;
        }
        previous_rms = rms;
    }
    let cur = work.positions().to_vec();
    let max_displacement = max_distance(&cur, &input);
    let report = SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume_at(mesh, &cur),
        max_displacement,
        converged,
        residual: None,
        stop_reason: None,
        taubin: None,
    };
    Ok(Output {
        positions: cur,
        report,
    })
}
