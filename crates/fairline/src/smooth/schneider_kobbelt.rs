//! Fair surfaces with G¹ boundary conditions by Δ_B H = 0 (Schneider and
//! Kobbelt; Grüner thesis §3.4, Eq. (25)–(29)).

use super::{Constraints, Role, SmoothError, SmoothReport, max_distance, roles};
use crate::Vec3;
use crate::geom::{self, LaplaceWeights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{CholeskySolver, sparse_from_triplets};

/// Options of [`schneider_kobbelt`].
#[derive(Clone, Debug, PartialEq)]
pub struct SchneiderKobbeltOptions {
    /// Upper bound on the outer iterations M_k → M_{k+1}.
    pub max_iterations: usize,
    /// Stop when the largest normal move divided by the mean edge length is
    /// below ε.
    pub epsilon: f64,
    /// Further fixed vertices. The boundary vertices and their normals are
    /// always fixed (the G¹ boundary condition).
    pub constraints: Constraints,
}

impl Default for SchneiderKobbeltOptions {
    fn default() -> Self {
        SchneiderKobbeltOptions {
            max_iterations: 50,
            epsilon: 1e-5,
            constraints: Constraints::default(),
        }
    }
}

/// Moreton–Séquin mean curvature at `x` with normal `n` and neighbours `q`
/// (Eq. (28) and the least-squares fit of Euler's formula), returned as
/// (H, g) with H = g·κ̃ linear in the normal curvatures κ̃_j; also returns the
/// squared distances |q_j − x|². Falls back to the mean of κ̃ (g_j = 1/m)
/// when the 3×3 normal matrix is singular.
fn moreton_sequin(x: Vec3, n: Vec3, q: &[Vec3]) -> (f64, Vec<f64>, Vec<f64>) {
    let m = q.len();
    let bx = n.any_orthonormal_vector();
    let by = n.cross(bx);
    let mut rows = Vec::with_capacity(m);
    let mut kappa = Vec::with_capacity(m);
    let mut d2 = Vec::with_capacity(m);
    for &qj in q {
        let d = qj - x;
        let l2 = d.length_squared();
        let t = d - d.dot(n) * n;
        let (tx, ty) = (t.dot(bx), t.dot(by));
        let tl = (tx * tx + ty * ty).sqrt();
        let (tx, ty) = if tl > 0.0 {
            (tx / tl, ty / tl)
        } else {
            (0.0, 0.0)
        };
        rows.push([tx * tx, tx * ty, ty * ty]);
        kappa.push(if l2 > 0.0 { 2.0 * d.dot(n) / l2 } else { 0.0 });
        d2.push(l2);
    }
    let mut ata = glam::DMat3::ZERO;
    for r in &rows {
        let v = glam::DVec3::from_array(*r);
        ata += glam::DMat3::from_cols(v * r[0], v * r[1], v * r[2]);
    }
    let det = ata.determinant();
    let g: Vec<f64> = if det.abs() > 1e-10 && m >= 3 {
        let inv = ata.inverse();
        // H = ½ (x0 + x2), x = (AᵀA)⁻¹ Aᵀ κ̃  ⇒  g_j = ½ (e0 + e2)ᵀ (AᵀA)⁻¹ a_j
        let sel = inv.transpose() * glam::DVec3::new(0.5, 0.0, 0.5);
        rows.iter()
            .map(|r| sel.dot(glam::DVec3::from_array(*r)))
            .collect()
    } else if m > 0 {
        vec![1.0 / m as f64; m]
    } else {
        Vec::new()
    };
    let h = g.iter().zip(&kappa).map(|(a, b)| a * b).sum();
    (h, g, d2)
}

/// Schneider–Kobbelt fairing of a triangle mesh with fixed boundary
/// vertices and normals: per iteration (1) solve the discrete Dirichlet
/// problem Σ_j (cot α_j + cot β_j)(H̃_i − H̃_j) = 0 for the inner vertices
/// (Eq. (26)–(27), boundary values H from the input mesh, sparse Cholesky,
/// symbolic factorisation reused), (2) move each inner vertex along its
/// normal by the t that makes its linearised Moreton–Séquin mean curvature
/// equal H̃ (Eq. (29)), a Jacobi step damped by ½; |t| is limited to half
/// the mean length of its edges.
/// Iterates until max |t| / ē < ε.
pub fn schneider_kobbelt(
    mesh: &mut SurfaceMesh,
    opts: &SchneiderKobbeltOptions,
) -> Result<SmoothReport, SmoothError> {
    mesh.require_triangles()?;
    let mut c = opts.constraints.clone();
    c.fix_boundary = true;
    c.preserve_volume = false;
    let roles = roles(mesh, &c)?;
    let n = mesh.vertex_count();
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let ebar = geom::mean_edge_length(mesh);
    let nbrs: Vec<Vec<usize>> = mesh
        .vertices()
        .map(|v| mesh.one_ring(v).map(|u| u.idx()).collect())
        .collect();
    let mut normals0 = geom::vertex_normals_max(mesh);
    // Fixed mean curvature values at the constrained vertices. A boundary
    // vertex sees only half a fan, which tilts fan normals by O(h) and spoils
    // the Moreton–Séquin fit, so its G¹ data (normal and H) come from a
    // quadric fit over the two-ring ([`geom::quadric_fit`]; sign flipped to
    // the Moreton–Séquin convention κ̃ = 2⟨d, n⟩/|d|²).
    let h_fixed: Vec<f64> = (0..n)
        .map(|i| {
            let v = VertexId(i as u32);
            if roles[i] != Role::Free
                && mesh.is_boundary_vertex(v)
                && let Some(f) = geom::quadric_fit(mesh, v)
            {
                normals0[i] = f.normal;
                return -f.mean;
            }
            let q: Vec<Vec3> = nbrs[i].iter().map(|&j| input[j]).collect();
            moreton_sequin(input[i], normals0[i], &q).0
        })
        .collect();
    let mut index = vec![usize::MAX; n];
    let mut unknown = Vec::new();
    for i in 0..n {
        if roles[i] == Role::Free {
            index[i] = unknown.len();
            unknown.push(i);
        }
    }
    let mut work = mesh.clone();
    let mut solver: Option<CholeskySolver> = None;
    let mut iterations = 0;
    let mut converged = unknown.is_empty() || !(ebar > 0.0);
    while !converged && iterations < opts.max_iterations {
        iterations += 1;
        let p = work.positions().to_vec();
        let mut normals = geom::vertex_normals_max(&work);
        for i in 0..n {
            if roles[i] != Role::Free {
                normals[i] = normals0[i];
            }
        }
        // (1) harmonic H̃ with Dirichlet values at fixed vertices
        let hw = geom::halfedge_weights(&work, LaplaceWeights::Cotangent);
        let m = unknown.len();
        let mut trip = Vec::new();
        let mut rhs = vec![0.0; m];
        for (r, &i) in unknown.iter().enumerate() {
            let mut diag = 0.0;
            for h in work.outgoing(VertexId(i as u32)) {
                let j = work.to_vertex(h).idx();
                let w = 2.0 * hw[h.idx()];
                diag += w;
                let cidx = index[j];
                if cidx == usize::MAX {
                    rhs[r] += w * h_fixed[j];
                } else if cidx > r {
                    trip.push((cidx, r, -w));
                }
            }
            trip.push((r, r, diag.max(1e-300)));
        }
        let a = sparse_from_triplets(m, m, &trip)?;
        let ok = solver
            .as_mut()
            .is_some_and(|s| s.refactor(a.as_ref()).is_ok());
        if !ok {
            solver = Some(CholeskySolver::new(a.as_ref())?);
        }
        solver.as_ref().expect("set").solve_in_place(&mut rhs)?;
        // (2) move along the normal so that H(q + t n) = H̃ (Jacobi step,
        // damped by ½: a full step overshoots the checkerboard mode)
        let mut worst: f64 = 0.0;
        let mut next = p.clone();
        for (r, &i) in unknown.iter().enumerate() {
            let ni = normals[i];
            if ni == Vec3::ZERO || nbrs[i].is_empty() {
                continue;
            }
            let q: Vec<Vec3> = nbrs[i].iter().map(|&j| p[j]).collect();
            let (h, g, d2) = moreton_sequin(p[i], ni, &q);
            // κ̃_j(t) ≈ κ̃_j − 2t/|d_j|²  ⇒  H(t) = H − 2t Σ g_j/|d_j|²
            let slope: f64 = g
                .iter()
                .zip(&d2)
                .map(|(g, d)| if *d > 0.0 { 2.0 * g / d } else { 0.0 })
                .sum();
            if !(slope.abs() > 1e-300) {
                continue;
            }
            let lmean = q.iter().map(|x| x.distance(p[i])).sum::<f64>() / q.len() as f64;
            let t = (0.5 * (h - rhs[r]) / slope).clamp(-0.5 * lmean, 0.5 * lmean);
            if t.is_finite() {
                next[i] = p[i] + t * ni;
                worst = worst.max(t.abs() / ebar);
            }
        }
        work.positions_mut().copy_from_slice(&next);
        if worst < opts.epsilon {
            converged = true;
        }
    }
    let cur = work.positions().to_vec();
    let max_displacement = max_distance(&cur, &input);
    mesh.set_positions(cur)?;
    Ok(SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume(mesh),
        max_displacement,
        converged,
    })
}
