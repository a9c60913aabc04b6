//! Fair surfaces with G¹ boundary conditions by Δ_B H = 0 (Schneider and
//! Kobbelt; Grüner thesis §3.4, Eq. (25)–(29)).

use super::{Constraints, Role, SmoothError, SmoothReport, max_distance, roles};
use crate::Vec3;
use crate::geom::{self, LaplaceWeights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{CholeskySolver, least_squares, sparse_from_triplets};

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
    /// G¹ normals of constrained vertices (normalised). Constrained
    /// vertices not listed get the normal of a quadric fit over the input
    /// two-ring ([`geom::quadric_fit`]), falling back to the vertex normal.
    pub normals: Vec<(VertexId, Vec3)>,
}

impl Default for SchneiderKobbeltOptions {
    fn default() -> Self {
        SchneiderKobbeltOptions {
            max_iterations: 50,
            epsilon: 1e-5,
            constraints: Constraints::default(),
            normals: Vec::new(),
        }
    }
}

/// Moreton–Séquin mean curvature at `x` with normal `n` and neighbours `q`
/// (Eq. (28) and the least-squares fit of Euler's formula), returned as
/// (H, g, d2, κ̃) with H = g·κ̃ linear in the normal curvatures κ̃_j, d2 the
/// squared distances |q_j − x|². Falls back to the mean of κ̃ (g_j = 1/m)
/// when the 3×3 normal matrix is singular.
fn moreton_sequin(x: Vec3, n: Vec3, q: &[Vec3]) -> MsFit {
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
    MsFit { h, g, d2, kappa }
}

/// State of one outer iteration: normals (fixed G¹ normals at constrained
/// vertices), Moreton–Séquin fits, cotangent half-edge weights and the merit
/// Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices.
struct Eval {
    normals: Vec<Vec3>,
    fits: Vec<Option<MsFit>>,
    hw: Vec<f64>,
    merit: f64,
}

/// Moreton–Séquin estimate at one vertex: H = Σ g_j κ̃_j.
struct MsFit {
    h: f64,
    g: Vec<f64>,
    d2: Vec<f64>,
    kappa: Vec<f64>,
}

/// Schneider–Kobbelt fairing of a triangle mesh with G¹ boundary (fixed
/// boundary vertices and normals; Grüner §3.4). The fourth-order Δ_B H = 0
/// is factorised into two nested second-order problems per outer iteration
/// M_k → M_{k+1}:
///
/// 1. H̃ solves the discrete Dirichlet problem Σ_j (cot α_j + cot β_j)
///    (H̃_i − H̃_j) = 0 at the free vertices (Eq. (26)–(27), sparse Cholesky,
///    symbolic factorisation reused), with boundary values H_b given by the
///    Moreton–Séquin estimate (Eq. (28) and the Euler-formula fit) at each
///    constrained vertex with its *fixed* G¹ normal and its current
///    neighbours — this is where the normal condition enters;
/// 2. every free vertex moves along its normal, q_i + t_i n_i, so that its
///    Moreton–Séquin mean curvature equals H̃_i (Eq. (29)). The linearisation
///    of Eq. (28) in t couples each vertex with its neighbours (moving q_j
///    changes κ̃_j at q_i by the same order as moving q_i), so the t_i are
///    solved together from the sparse linearised system J t = H̃ − H (least
///    squares, `solve::least_squares`) — a Newton step; the vertex-by-vertex
///    (Jacobi) update of the linearisation converges like Jacobi on a
///    Laplacian, i.e. in O(n) iterations, and was too slow on small patches.
///    |t_i| is limited to half the mean length of its edges.
///
/// Iterates until max |t| / ē < ε (ē the input mean edge length); the report
/// gives the accepted iterations and the final residual max |H − H̃| · ē.
/// A step is accepted only if it lowers the merit Σ_i (Σ_j w_ij (H_i − H_j))²;
/// when no step length down to 1/64 does (the linearisation freezes the
/// normals and cotangent weights, which is poor on larger patches such as a
/// 61×61 dented roof), the iteration stops unconverged instead of drifting.
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
    // G¹ normals of the constrained vertices: given, else a quadric fit over
    // the input two-ring (a boundary vertex sees only half a fan, which tilts
    // fan normals by O(h)), else the vertex normal
    let mut normals0 = geom::vertex_normals_max(mesh);
    for i in 0..n {
        let v = VertexId(i as u32);
        if roles[i] != Role::Free
            && mesh.is_boundary_vertex(v)
            && let Some(f) = geom::quadric_fit(mesh, v)
        {
            normals0[i] = f.normal;
        }
    }
    for &(v, nv) in &opts.normals {
        let i = v.idx();
        if i >= n {
            return Err(SmoothError::InvalidOption(format!(
                "normal given for vertex {i}, the mesh has {n}"
            )));
        }
        let l = nv.length();
        if !(l > 0.0) || !l.is_finite() {
            return Err(SmoothError::InvalidOption(format!(
                "normal of vertex {i} is zero or not finite"
            )));
        }
        normals0[i] = nv / l;
    }
    let mut index = vec![usize::MAX; n];
    let mut unknown = Vec::new();
    for i in 0..n {
        if roles[i] == Role::Free {
            index[i] = unknown.len();
            unknown.push(i);
        }
    }
    let m = unknown.len();
    let mut work = mesh.clone();
    let mut solver: Option<CholeskySolver> = None;
    let mut iterations = 0;
    let mut converged = m == 0 || !(ebar > 0.0);
    let mut residual = 0.0;
    let mut last_step = f64::INFINITY;
    let evaluate = |work: &SurfaceMesh| -> Eval {
        let p = work.positions();
        let mut normals = geom::vertex_normals_max(work);
        for i in 0..n {
            if roles[i] != Role::Free {
                normals[i] = normals0[i];
            }
        }
        let fits: Vec<Option<MsFit>> = (0..n)
            .map(|i| {
                if nbrs[i].is_empty() || normals[i] == Vec3::ZERO {
                    return None;
                }
                let q: Vec<Vec3> = nbrs[i].iter().map(|&j| p[j]).collect();
                Some(moreton_sequin(p[i], normals[i], &q))
            })
            .collect();
        let hw = geom::halfedge_weights(work, LaplaceWeights::Cotangent);
        // merit: Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices
        let h_of = |i: usize| fits[i].as_ref().map_or(0.0, |f| f.h);
        let merit = unknown
            .iter()
            .map(|&i| {
                let f: f64 = work
                    .outgoing(VertexId(i as u32))
                    .map(|h| 2.0 * hw[h.idx()] * (h_of(i) - h_of(work.to_vertex(h).idx())))
                    .sum();
                f * f
            })
            .sum();
        Eval {
            normals,
            fits,
            hw,
            merit,
        }
    };
    let mut ev = evaluate(&work);
    while !converged {
        let p = work.positions().to_vec();
        let Eval {
            normals, fits, hw, ..
        } = &ev;
        let h_of = |i: usize| fits[i].as_ref().map_or(0.0, |f| f.h);
        // (1) harmonic H̃ with Dirichlet values at the constrained vertices
        let mut trip = Vec::new();
        let mut htilde = vec![0.0; m];
        for (r, &i) in unknown.iter().enumerate() {
            let mut diag = 0.0;
            for h in work.outgoing(VertexId(i as u32)) {
                let j = work.to_vertex(h).idx();
                let w = 2.0 * hw[h.idx()];
                diag += w;
                let cidx = index[j];
                if cidx == usize::MAX {
                    htilde[r] += w * h_of(j);
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
        solver.as_ref().expect("set").solve_in_place(&mut htilde)?;
        let res: Vec<f64> = unknown
            .iter()
            .enumerate()
            .map(|(r, &i)| htilde[r] - h_of(i))
            .collect();
        residual = res.iter().fold(0.0f64, |a, r| a.max(r.abs())) * ebar;
        if last_step < opts.epsilon {
            converged = true;
            break;
        }
        if iterations >= opts.max_iterations {
            break;
        }
        // (2) linearised Eq. (29) for all free vertices at once. With
        // κ̃_j = 2a/L, a = ⟨d_j, n_i⟩, L = |d_j|², d_j = q_j − q_i:
        // ∂κ̃_j/∂t_i = (−2 + 2κ̃_j a)/L, ∂κ̃_j/∂t_j = (2⟨n_j, n_i⟩ − 2κ̃_j⟨d_j, n_j⟩)/L.
        // Rows of ∂H/∂t for every vertex (constrained ones too: their H, the
        // Dirichlet data of H̃, moves with their free neighbours).
        let dh: Vec<Vec<(usize, f64)>> = (0..n)
            .map(|i| {
                let mut row = Vec::new();
                let Some(f) = &fits[i] else {
                    return row;
                };
                let ni = normals[i];
                let mut diag = 0.0;
                for (k, &j) in nbrs[i].iter().enumerate() {
                    let l = f.d2[k];
                    if !(l > 0.0) {
                        continue;
                    }
                    let d = p[j] - p[i];
                    diag += f.g[k] * (-2.0 + 2.0 * f.kappa[k] * d.dot(ni)) / l;
                    let cj = index[j];
                    if cj != usize::MAX {
                        let nj = normals[j];
                        let v = f.g[k] * (2.0 * nj.dot(ni) - 2.0 * f.kappa[k] * d.dot(nj)) / l;
                        if v.is_finite() {
                            row.push((cj, v));
                        }
                    }
                }
                if index[i] != usize::MAX && diag.is_finite() {
                    row.push((index[i], diag));
                }
                row
            })
            .collect();
        // Newton step for Σ_j w_ij (H_i − H_j) = 0 at the free vertices
        // (equivalently H = H̃ with H̃'s boundary data moving along):
        // Σ_j w_ij (∂H_i − ∂H_j) t = −Σ_j w_ij (H_i − H_j)
        let mut jac = Vec::new();
        let mut rhs = vec![0.0; m];
        for (r, &i) in unknown.iter().enumerate() {
            for h in work.outgoing(VertexId(i as u32)) {
                let j = work.to_vertex(h).idx();
                let w = 2.0 * hw[h.idx()];
                rhs[r] -= w * (h_of(i) - h_of(j));
                for &(c, v) in &dh[i] {
                    jac.push((r, c, w * v));
                }
                for &(c, v) in &dh[j] {
                    jac.push((r, c, -w * v));
                }
            }
        }
        let jm = sparse_from_triplets(m, m, &jac)?;
        let t = least_squares(jm.as_ref(), std::slice::from_ref(&rhs))?
            .pop()
            .unwrap_or_default();
        // clamp |t_i| to half the mean length of its edges
        let t: Vec<f64> = unknown
            .iter()
            .enumerate()
            .map(|(r, &i)| {
                let lmean = nbrs[i].iter().map(|&j| p[j].distance(p[i])).sum::<f64>()
                    / nbrs[i].len().max(1) as f64;
                let ti = t.get(r).copied().unwrap_or(0.0);
                if ti.is_finite() && normals[i] != Vec3::ZERO {
                    ti.clamp(-0.5 * lmean, 0.5 * lmean)
                } else {
                    0.0
                }
            })
            .collect();
        let tmax = t.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // backtracking on the merit ‖Σ_j w_ij (H_i − H_j)‖²: far from the
        // solution the linearisation (normals and fit weights frozen) can
        // overshoot; halve the step until the merit drops
        // (a step that lowers it for no α ≥ 1/64 is not taken: the iteration
        // has stalled and ends unconverged rather than drift uphill)
        let mut alpha = 1.0;
        let mut trial = work.clone();
        let next_ev = loop {
            for (r, &i) in unknown.iter().enumerate() {
                trial.positions_mut()[i] = p[i] + alpha * t[r] * normals[i];
            }
            let e = evaluate(&trial);
            if e.merit < ev.merit {
                break Some(e);
            }
            if alpha < 1.0 / 64.0 {
                break None;
            }
            alpha *= 0.5;
        };
        let Some(next_ev) = next_ev else {
            break;
        };
        iterations += 1;
        let worst = alpha * tmax / ebar;
        work = trial;
        ev = next_ev;
        last_step = worst;
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
        residual: Some(residual),
    })
}
