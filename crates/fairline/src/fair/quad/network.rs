//! Fair polyline networks with tolerance cylinders (Grüner thesis §3.1.1
//! after Hofer et al.).

use super::QuadFairError;
use crate::geom;
use crate::mesh::{SurfaceMesh, structure_lines};
use crate::solve::{BoxQpOptions, box_qp, sparse_from_triplets};
use crate::{Control, Output};
use serde::Serialize;

/// Options of [`fair_polyline_network`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PolylineNetworkOptions {
    /// Half height h of every tolerance cylinder, in units of the mean edge
    /// length (so |z − z⁰| ≤ h·ē). Default 0.1.
    pub tolerance: f64,
    /// Optional per-vertex half heights (absolute, overriding `tolerance`);
    /// 0 fixes a vertex.
    pub per_vertex: Option<Vec<f64>>,
    /// Progress callback and cancel flag (stage `"network"`: one step
    /// before assembling the QP and one before solving it).
    pub control: Control,
}

impl Default for PolylineNetworkOptions {
    fn default() -> Self {
        PolylineNetworkOptions {
            tolerance: 0.1,
            per_vertex: None,
            control: Control::default(),
        }
    }
}

impl PolylineNetworkOptions {
    /// Sets [`PolylineNetworkOptions::tolerance`].
    pub fn tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Sets [`PolylineNetworkOptions::per_vertex`].
    pub fn per_vertex(mut self, per_vertex: Option<Vec<f64>>) -> Self {
        self.per_vertex = per_vertex;
        self
    }
    /// Sets [`PolylineNetworkOptions::control`].
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }
}

/// What [`fair_polyline_network`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PolylineNetworkReport {
    /// Height-only bending energy Σ (z_{k−1} − 2z_k + z_{k+1})² before.
    pub energy_before: f64,
    /// The same after.
    pub energy_after: f64,
    /// Vertices that ended on the top or bottom of their cylinder.
    pub at_bound: usize,
    /// QP iterations.
    pub iterations: usize,
}

/// Fair polyline network with tolerance cylinders (Grüner thesis §3.1.1,
/// Hofer et al.): only the heights z move; minimise the height-only bending
/// energy E = Σ over structure lines of Σ_k (z_{k−1} − 2z_k + z_{k+1})²
/// (the z part of Eq. (11)) subject to |z − z⁰| ≤ h, a convex
/// bound-constrained QP solved exactly by [`box_qp`] in the displacement
/// d = z − z⁰ (so the solver starts at the input).
///
/// E is only positive semi-definite (heights bilinear in the grid indices
/// cost nothing), so a proximal term ε‖d‖² with ε = 1e-9·max diag(Q) is
/// added: it makes the problem strictly convex and picks, among the
/// minimisers of E, the one closest to the input; its effect on E is of
/// relative order 1e-9.
///
/// Returns the new positions (only z changes) and the report; the input is
/// untouched.
pub fn fair_polyline_network(
    mesh: &SurfaceMesh,
    opts: &PolylineNetworkOptions,
) -> Result<Output<PolylineNetworkReport>, QuadFairError> {
    opts.control.step("network", 0, 2)?;
    let n = mesh.vertex_count();
    let ebar = geom::mean_edge_length(mesh);
    if !(opts.tolerance >= 0.0) || !opts.tolerance.is_finite() {
        return Err(QuadFairError::InvalidOption(
            "tolerance must be finite and ≥ 0".into(),
        ));
    }
    let h: Vec<f64> = match &opts.per_vertex {
        Some(v) if v.len() == n => v.clone(),
        Some(v) => {
            return Err(QuadFairError::InvalidOption(format!(
                "{} per-vertex tolerances for {n} vertices",
                v.len()
            )));
        }
        None => vec![opts.tolerance * ebar; n],
    };
    if h.iter().any(|x| !(*x >= 0.0) || !x.is_finite()) {
        return Err(QuadFairError::InvalidOption(
            "tolerances must be finite and ≥ 0".into(),
        ));
    }
    let z0: Vec<f64> = mesh.positions().iter().map(|p| p.z).collect();
    let mut trip = Vec::new();
    let mut triples = Vec::new();
    for l in structure_lines(mesh) {
        let v = &l.vertices;
        let m = v.len();
        let count = if l.closed { m } else { m.saturating_sub(2) };
        for i in 0..count {
            let t = [v[i].idx(), v[(i + 1) % m].idx(), v[(i + 2) % m].idx()];
            triples.push(t);
            let c = [1.0, -2.0, 1.0];
            for a in 0..3 {
                for b in 0..3 {
                    trip.push((t[a], t[b], 2.0 * c[a] * c[b]));
                }
            }
        }
    }
    let energy = |z: &[f64]| -> f64 {
        triples
            .iter()
            .map(|t| (z[t[0]] - 2.0 * z[t[1]] + z[t[2]]).powi(2))
            .sum()
    };
    let e0 = energy(&z0);
    if triples.is_empty() || n == 0 {
        return Ok(Output {
            positions: mesh.positions().to_vec(),
            report: PolylineNetworkReport {
                energy_before: e0,
                energy_after: e0,
                ..Default::default()
            },
        });
    }
    // Q of E(z) = ½ zᵀQz (both triangles), plus the proximal diagonal
    let mut diag = vec![0.0f64; n];
    for &(i, j, v) in &trip {
        if i == j {
            diag[i] += v;
        }
    }
    let eps = 1e-9 * diag.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-300);
    for (i, d) in diag.iter().enumerate() {
        trip.push((i, i, if *d > 0.0 { eps } else { 1.0 }));
    }
    let q = sparse_from_triplets(n, n, &trip)?;
    // E(z⁰ + d) = ½ dᵀQd + (Qz⁰)ᵀd + const (proximal term only on d)
    let mut c = vec![0.0; n];
    for t in &triples {
        let r = 2.0 * (z0[t[0]] - 2.0 * z0[t[1]] + z0[t[2]]);
        c[t[0]] += r;
        c[t[1]] -= 2.0 * r;
        c[t[2]] += r;
    }
    let lo: Vec<f64> = h.iter().map(|x| -x).collect();
    opts.control.step("network", 1, 2)?;
    let sol = box_qp(q.as_ref(), &c, &lo, &h, &BoxQpOptions::default())?;
    let z: Vec<f64> = (0..n)
        .map(|i| {
            let d = sol.x[i].clamp(-h[i], h[i]);
            if d.is_finite() { z0[i] + d } else { z0[i] }
        })
        .collect();
    let report = PolylineNetworkReport {
        energy_before: e0,
        energy_after: energy(&z),
        at_bound: (0..n)
            .filter(|&i| h[i] > 0.0 && sol.x[i].abs() >= h[i])
            .count(),
        iterations: sol.iterations,
    };
    let positions = mesh
        .positions()
        .iter()
        .zip(&z)
        .map(|(p, zi)| crate::Vec3::new(p.x, p.y, *zi))
        .collect();
    Ok(Output { positions, report })
}
