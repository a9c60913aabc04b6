//! The mean-curvature field of the fairing: the Moreton–Séquin curvature
//! at a vertex, the unknowns, their evaluation over the mesh, and the
//! harmonic H̃ of step (1).

use crate::Vec3;
use crate::geom::{self, LaplaceWeights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::smooth::{Role, SmoothError};
use crate::solve::{ConstrainedOptions, ConstrainedSolver};

/// Moreton–Séquin mean curvature at `x` with normal `n` and neighbours `q`
/// (Eq. (28) and the least-squares fit of Euler's formula): H = Σ g_j κ̃_j,
/// linear in the normal curvatures κ̃_j = 2⟨q_j − x, n⟩ / |q_j − x|². Falls
/// back to the mean of κ̃ (g_j = 1/m) when the 3×3 normal matrix is singular.
pub(super) fn moreton_sequin(x: Vec3, n: Vec3, q: &[Vec3]) -> f64 {
    let m = q.len();
    let bx = n.any_orthonormal_vector();
    let by = n.cross(bx);
    let mut rows = Vec::with_capacity(m);
    let mut kappa = Vec::with_capacity(m);
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
    g.iter().zip(&kappa).map(|(a, b)| a * b).sum()
}

/// State of one outer iteration: normals (fixed G¹ normals at constrained
/// vertices), Moreton–Séquin fits, cotangent half-edge weights and the merit
/// Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices.
pub(super) struct Eval {
    pub(super) normals: Vec<Vec3>,
    pub(super) fits: Vec<Option<f64>>,
    pub(super) hw: Vec<f64>,
    /// Σ_j w_ij (H_i − H_j) per free vertex (the residual of Δ_B H = 0).
    pub(super) f: Vec<f64>,
    pub(super) merit: f64,
}

/// The free vertices (the unknowns of both second-order problems) and their
/// components, joined by free–free edges.
pub(super) struct Unknowns {
    /// Row of each vertex among the unknowns (`usize::MAX`: constrained).
    pub(super) index: Vec<usize>,
    /// Vertex of each unknown.
    pub(super) vertices: Vec<usize>,
    /// Component of each unknown.
    pub(super) component: Vec<usize>,
    /// Per component: it touches no constrained vertex (no Dirichlet data).
    pub(super) floating: Vec<bool>,
}

impl Unknowns {
    /// Numbers the free vertices and finds their components. A component
    /// that touches no constrained vertex — a closed mesh without fixed
    /// vertices — has no Dirichlet data: its harmonic functions are the
    /// constants, the Laplacian block is singular, and H̃ is the
    /// area-weighted mean of H over the component (the harmonic function
    /// nearest to H).
    pub(super) fn new(roles: &[Role], nbrs: &[Vec<usize>]) -> Unknowns {
        let n = roles.len();
        let mut index = vec![usize::MAX; n];
        let mut vertices = Vec::new();
        for i in 0..n {
            if roles[i] == Role::Free {
                index[i] = vertices.len();
                vertices.push(i);
            }
        }
        let m = vertices.len();
        let mut component = vec![usize::MAX; m];
        let mut floating: Vec<bool> = Vec::new();
        for start in 0..m {
            if component[start] != usize::MAX {
                continue;
            }
            let id = floating.len();
            let mut touches = false;
            component[start] = id;
            let mut stack = vec![vertices[start]];
            while let Some(i) = stack.pop() {
                for &j in &nbrs[i] {
                    let r = index[j];
                    if r == usize::MAX {
                        touches = true;
                    } else if component[r] == usize::MAX {
                        component[r] = id;
                        stack.push(j);
                    }
                }
            }
            floating.push(!touches);
        }
        Unknowns {
            index,
            vertices,
            component,
            floating,
        }
    }

    pub(super) fn any_floating(&self) -> bool {
        self.floating.iter().any(|f| *f)
    }

    /// The harmonic field's fixed values: constrained vertices and the free
    /// vertices of floating components.
    pub(super) fn field_fixed(&self) -> Vec<bool> {
        (0..self.index.len())
            .map(|i| self.index[i] == usize::MAX || self.floating[self.component[self.index[i]]])
            .collect()
    }
}

/// Evaluates the discrete Δ_B H of a position vector on the input's
/// connectivity (every geometry quantity through geom's `*_at(positions)`
/// views).
pub(super) struct Evaluator<'a> {
    pub(super) mesh: &'a SurfaceMesh,
    pub(super) roles: &'a [Role],
    /// G¹ normals of the constrained vertices.
    pub(super) normals0: &'a [Vec3],
    pub(super) nbrs: &'a [Vec<usize>],
    pub(super) unknown: &'a [usize],
    /// Evaluations so far (each one costs O(vertices)).
    pub(super) evaluations: std::cell::Cell<u64>,
}

impl Evaluator<'_> {
    pub(super) fn evaluate(&self, p: &[Vec3]) -> Eval {
        let (mesh, n) = (self.mesh, self.roles.len());
        self.evaluations.set(self.evaluations.get() + 1);
        let mut normals = geom::vertex_normals_max_at(mesh, p);
        for i in 0..n {
            if self.roles[i] != Role::Free {
                normals[i] = self.normals0[i];
            }
        }
        let fits: Vec<Option<f64>> = (0..n)
            .map(|i| {
                if self.nbrs[i].is_empty() || normals[i] == Vec3::ZERO {
                    return None;
                }
                let q: Vec<Vec3> = self.nbrs[i].iter().map(|&j| p[j]).collect();
                Some(moreton_sequin(p[i], normals[i], &q))
            })
            .collect();
        let hw = geom::halfedge_weights_at(mesh, p, LaplaceWeights::Cotangent);
        // merit: Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices
        let h_of = |i: usize| fits[i].unwrap_or(0.0);
        let f: Vec<f64> = self
            .unknown
            .iter()
            .map(|&i| {
                mesh.outgoing(VertexId(i as u32))
                    .map(|h| 2.0 * hw[h.idx()] * (h_of(i) - h_of(mesh.to_vertex(h).idx())))
                    .sum()
            })
            .collect();
        let merit = f.iter().map(|x| x * x).sum();
        Eval {
            normals,
            fits,
            hw,
            f,
            merit,
        }
    }
}

/// Step (1): the harmonic H̃, Σ_j w_ij (H̃_i − H̃_j) = 0 at the free
/// vertices (−L of geom's cotangent Laplacian, by the one constrained
/// solve, its symbolic factorisation kept in `solver`), Dirichlet values H
/// at the constrained vertices; a floating component takes the
/// area-weighted mean of its H as given value.
pub(super) fn harmonic_mean_curvature(
    mesh: &SurfaceMesh,
    work: &[Vec3],
    ev: &Eval,
    u: &Unknowns,
    field_fixed: &[bool],
    solver: &mut Option<ConstrainedSolver>,
) -> Result<Vec<f64>, SmoothError> {
    let n = mesh.vertex_count();
    let h_of = |i: usize| ev.fits[i].unwrap_or(0.0);
    let (index, component, floating) = (&u.index, &u.component, &u.floating);
    let mut float_mean = vec![(0.0, 0.0); floating.len()];
    if u.any_floating() {
        let area = geom::barycentric_vertex_areas_at(mesh, work);
        for (r, &i) in u.vertices.iter().enumerate() {
            if floating[component[r]] {
                let e = &mut float_mean[component[r]];
                e.0 += area[i] * h_of(i);
                e.1 += area[i];
            }
        }
    }
    let mut htilde: Vec<f64> = (0..n)
        .map(|i| match index[i] {
            usize::MAX => h_of(i),
            r if floating[component[r]] => {
                let (sum, total) = float_mean[component[r]];
                if total > 0.0 { sum / total } else { 0.0 }
            }
            _ => 0.0,
        })
        .collect();
    let mut a = geom::laplacian_from_weights(mesh, &ev.hw);
    let diagonal: Vec<Option<usize>> = {
        let (col_ptr, row_idx) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        (0..n)
            .map(|j| (col_ptr[j]..col_ptr[j + 1]).find(|&k| row_idx[k] == j))
            .collect()
    };
    let values = a.val_mut();
    for v in values.iter_mut() {
        *v *= -2.0;
    }
    // an isolated free vertex (all weights 0) keeps a solvable row
    for k in diagonal.into_iter().flatten() {
        values[k] = values[k].max(1e-300);
    }
    let harmonic = match solver.as_mut() {
        Some(s) => s,
        None => solver.insert(ConstrainedSolver::analyse(
            a.symbolic(),
            field_fixed,
            &ConstrainedOptions::default(),
        )?),
    };
    harmonic.factor(a.as_ref())?;
    harmonic.solve(&vec![0.0; n], &mut htilde)?;
    Ok(htilde)
}
