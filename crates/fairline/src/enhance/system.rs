//! Assembly of the 8n × 3n least-squares system of Ji et al. Eq. (20) and of
//! its normal equations. Rows of a free vertex i (free index f), in this
//! order: two F_em rows (Eq. (17)–(18)), three F_sd rows (Eq. (6)), three
//! F_smo rows (Eq. (8)–(10)), one per coordinate. Unknown 3f + c is
//! coordinate c of free vertex f. Fixed neighbours go to the right-hand
//! side. Every structural entry is emitted even when its value is zero, so
//! the pattern depends only on the connectivity and the symbolic
//! factorisation can be reused across iterations.

use super::EnhanceError;
use super::boundary::BoundaryCurves;
use crate::Vec3;
use crate::geom::PrincipalCurvatures;
use crate::mesh::SurfaceMesh;
use crate::solve::{NormalEquations, SolveError, normal_matrix};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use glam::DMat3;
use rayon::prelude::*;

const NONE: u32 = u32::MAX;

/// Free vertices, their indices among the unknowns, and their one-rings.
pub(super) struct Layout {
    /// Vertex id of each free vertex.
    pub free: Vec<u32>,
    /// Free index of each vertex (`NONE` for fixed vertices).
    pub free_index: Vec<u32>,
    /// One-ring of free vertex f: `ring[ring_ptr[f]..ring_ptr[f + 1]]`.
    ring_ptr: Vec<usize>,
    ring: Vec<u32>,
}

impl Layout {
    pub fn new(mesh: &SurfaceMesh, is_fixed: &[bool]) -> Layout {
        let mut free = Vec::new();
        let mut free_index = vec![NONE; mesh.vertex_count()];
        for (i, &fixed) in is_fixed.iter().enumerate() {
            if !fixed {
                free_index[i] = free.len() as u32;
                free.push(i as u32);
            }
        }
        let rings: Vec<Vec<u32>> = free
            .par_iter()
            .map(|&v| mesh.one_ring(crate::VertexId(v)).map(|w| w.0).collect())
            .collect();
        let mut ring_ptr = Vec::with_capacity(free.len() + 1);
        ring_ptr.push(0);
        let mut ring = Vec::with_capacity(rings.iter().map(Vec::len).sum());
        for r in rings {
            ring.extend_from_slice(&r);
            ring_ptr.push(ring.len());
        }
        Layout {
            free,
            free_index,
            ring_ptr,
            ring,
        }
    }

    /// The free index of vertex `v`, `None` for a fixed vertex.
    pub fn free_of(&self, v: usize) -> Option<usize> {
        let f = *self.free_index.get(v)?;
        (f != NONE).then_some(f as usize)
    }

    pub fn ring(&self, f: usize) -> &[u32] {
        &self.ring[self.ring_ptr[f]..self.ring_ptr[f + 1]]
    }
}

/// The F_sd rows of every free vertex (Eq. (6)): the frame (T1, T2, N) of
/// the input at p, each scaled by √(λ c) with c = d|k| / (1 + d|k|) for the
/// tangents (d = 1 / max |k| over the free vertices) and c = 1 for N. A free
/// boundary vertex (module `boundary`) gets the rows of the squared
/// distance to its boundary curve instead: the frame (t, N × t, N) with t
/// the boundary tangent, c = d|κ| / (1 + d|κ|) along t (κ the curvature of
/// the boundary polyline) and c = 1 for the two directions normal to the
/// curve.
pub(super) struct DistanceModel {
    /// The three scaled frame vectors of each free vertex.
    pub rows: Vec<[Vec3; 3]>,
}

impl DistanceModel {
    pub fn new(
        curvature: &PrincipalCurvatures,
        layout: &Layout,
        boundary: &BoundaryCurves,
        lambda: f64,
    ) -> DistanceModel {
        Self::with_floor(curvature, layout, boundary, lambda, &[])
    }

    /// The model with the tangential coefficients c of free vertex `f`
    /// raised to at least `floor[f]` (an empty `floor`: none): the trust
    /// region of the flow's quality guard (module documentation of
    /// `enhance`, "Triangle quality").
    pub fn with_floor(
        curvature: &PrincipalCurvatures,
        layout: &Layout,
        boundary: &BoundaryCurves,
        lambda: f64,
        floor: &[f64],
    ) -> DistanceModel {
        let kmax = layout
            .free
            .iter()
            .map(|&v| {
                curvature.k1[v as usize]
                    .abs()
                    .max(curvature.k2[v as usize].abs())
            })
            .filter(|k| k.is_finite())
            .fold(0.0f64, f64::max);
        // d |k| = |k| / kmax, in [0, 1]; 0 everywhere on a flat mesh
        let coefficient = |k: f64| {
            if kmax > 0.0 && k.is_finite() {
                let dk = (k.abs() / kmax).min(1.0);
                dk / (1.0 + dk)
            } else {
                0.0
            }
        };
        let rows = layout
            .free
            .par_iter()
            .enumerate()
            .map(|(f, &v)| {
                let v = v as usize;
                let least = floor.get(f).copied().unwrap_or(0.0);
                let coefficient = |k: f64| coefficient(k).max(least);
                if let Some((t, kappa)) = boundary_frame(boundary, curvature, v) {
                    let n = curvature.normals[v];
                    return [
                        (lambda * coefficient(kappa)).sqrt() * t,
                        lambda.sqrt() * n.cross(t),
                        lambda.sqrt() * n,
                    ];
                }
                let c1 = coefficient(curvature.k1[v]);
                let c2 = coefficient(curvature.k2[v]);
                [
                    (lambda * c1).sqrt() * curvature.d1[v],
                    (lambda * c2).sqrt() * curvature.d2[v],
                    lambda.sqrt() * curvature.normals[v],
                ]
            })
            .collect();
        DistanceModel { rows }
    }

    /// Share of the free vertices with a tangential row whose weight λc is
    /// below [`super::SOFT_COEFFICIENT`] λ (rows built with this `lambda`).
    pub fn soft_share(&self, lambda: f64) -> f64 {
        if self.rows.is_empty() {
            return 0.0;
        }
        let limit = super::SOFT_COEFFICIENT * lambda;
        let soft = self
            .rows
            .iter()
            .filter(|r| r[0].length_squared().min(r[1].length_squared()) < limit)
            .count();
        soft as f64 / self.rows.len() as f64
    }
}

/// The unit tangent t of the boundary curve at boundary vertex `v`, made
/// perpendicular to the vertex normal, and the curvature of the boundary
/// polyline there; `None` off the boundary or where t is undefined.
pub(super) fn boundary_frame(
    boundary: &BoundaryCurves,
    curvature: &PrincipalCurvatures,
    v: usize,
) -> Option<(Vec3, f64)> {
    if !boundary.is_on(v) {
        return None;
    }
    let (t, kappa) = boundary.tangent_and_curvature(v);
    let n = curvature.normals[v];
    let t = (t - t.dot(n) * n).normalize_or_zero();
    (t != Vec3::ZERO).then_some((t, kappa))
}

/// The least-squares system of one iteration, stored by vertex (module
/// documentation): for free vertex f its entries `ptr[f]..ptr[f + 1]`, one
/// per free vertex of its closed one-ring (f included) in increasing free
/// index, each with the coefficients of the two F_em rows and of the F_smo
/// rows; its three F_sd rows; the right-hand side b of Eq. (20); and the
/// right-hand side Aᵀb + ε p of the regularised normal equations
/// (AᵀA + εI) x = Aᵀb + ε p. A is applied matrix-free (A x by rows, Aᵀ y
/// gathered with a copy of the coefficients in transposed order), which
/// moves less than half the memory of the assembled A and Aᵀ; the sparse A
/// is built only for the direct solver.
pub(super) struct LeastSquares {
    ptr: Vec<usize>,
    /// Free index of each entry.
    col: Vec<u32>,
    /// F_em coefficient vectors (rows 1 and 2) of each entry.
    em: Vec<[Vec3; 2]>,
    /// F_smo coefficient of each entry.
    smo: Vec<f64>,
    /// For entry e of g with column f: the coefficients of entry (f, g)
    /// (the column of A for g, read in g's order by Aᵀ y).
    em_mirror: Vec<[Vec3; 2]>,
    smo_mirror: Vec<f64>,
    /// F_sd rows of each free vertex.
    sd: Vec<[Vec3; 3]>,
    /// b of Eq. (20), eight rows per free vertex.
    b: Vec<f64>,
    /// Aᵀb + ε p.
    pub rhs: Vec<f64>,
    /// ε.
    pub epsilon: f64,
}

impl LeastSquares {
    /// y = A x (8 rows per free vertex), in parallel.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(8 * VERTICES)
            .enumerate()
            .for_each(|(c, y)| {
                for (k, y) in y.as_chunks_mut::<8>().0.iter_mut().enumerate() {
                    let f = c * VERTICES + k;
                    let (mut em, mut smo) = ([0.0; 2], Vec3::ZERO);
                    for e in self.ptr[f]..self.ptr[f + 1] {
                        let g = 3 * self.col[e] as usize;
                        let xg = Vec3::new(x[g], x[g + 1], x[g + 2]);
                        em[0] += self.em[e][0].dot(xg);
                        em[1] += self.em[e][1].dot(xg);
                        smo += self.smo[e] * xg;
                    }
                    let xf = Vec3::new(x[3 * f], x[3 * f + 1], x[3 * f + 2]);
                    let sd = self.sd[f];
                    *y = [
                        em[0],
                        em[1],
                        sd[0].dot(xf),
                        sd[1].dot(xf),
                        sd[2].dot(xf),
                        smo.x,
                        smo.y,
                        smo.z,
                    ];
                }
            });
    }

    /// x = Aᵀ y, gathered per free vertex in parallel.
    pub fn mul_transpose(&self, y: &[f64], x: &mut [f64]) {
        self.mul_transpose_shifted(y, None, x);
    }

    /// x = Aᵀ y + ε v for `shift` = Some((ε, v)) (x = Aᵀ y for None), in
    /// one pass.
    fn mul_transpose_shifted(&self, y: &[f64], shift: Option<(f64, &[f64])>, x: &mut [f64]) {
        x.par_chunks_mut(3 * VERTICES)
            .enumerate()
            .for_each(|(c, x)| {
                for (k, x) in x.as_chunks_mut::<3>().0.iter_mut().enumerate() {
                    let g = c * VERTICES + k;
                    let mut s = Vec3::ZERO;
                    for e in self.ptr[g]..self.ptr[g + 1] {
                        let f = self.col[e] as usize;
                        let yf = &y[8 * f..8 * f + 8];
                        let em = self.em_mirror[e];
                        s += em[0] * yf[0]
                            + em[1] * yf[1]
                            + self.smo_mirror[e] * Vec3::new(yf[5], yf[6], yf[7]);
                    }
                    let sd = self.sd[g];
                    let yg = &y[8 * g..8 * g + 8];
                    s += sd[0] * yg[2] + sd[1] * yg[3] + sd[2] * yg[4];
                    if let Some((epsilon, v)) = shift {
                        s += epsilon * Vec3::new(v[3 * g], v[3 * g + 1], v[3 * g + 2]);
                    }
                    *x = s.to_array();
                }
            });
    }

    /// out = (AᵀA + εI) v, with `scratch` of length 8n for A v.
    pub fn normal_product(&self, v: &[f64], out: &mut [f64], scratch: &mut [f64]) {
        self.mul(v, scratch);
        self.mul_transpose_shifted(scratch, Some((self.epsilon, v)), out);
    }

    /// The 3 × 3 diagonal blocks of AᵀA + εI, row-major per free vertex.
    pub fn diagonal_blocks(&self) -> Vec<f64> {
        let outer = |d: Vec3| DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        (0..self.sd.len())
            .into_par_iter()
            .flat_map_iter(|g| {
                let mut m = DMat3::from_diagonal(Vec3::splat(self.epsilon));
                for e in self.ptr[g]..self.ptr[g + 1] {
                    let em = self.em_mirror[e];
                    let smo = self.smo_mirror[e];
                    m += outer(em[0]) + outer(em[1]);
                    m += DMat3::from_diagonal(Vec3::splat(smo * smo));
                }
                for t in self.sd[g] {
                    m += outer(t);
                }
                // row-major (the block is symmetric)
                m.transpose().to_cols_array()
            })
            .collect()
    }

    /// The sparse A (8n × 3n) compressed by column; every structural entry
    /// is stored even when zero, so the pattern depends only on the
    /// connectivity.
    fn sparse(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        let nf = self.sd.len();
        let mut col_ptr = Vec::with_capacity(8 * nf + 1);
        col_ptr.push(0usize);
        let mut rows = Vec::with_capacity(2 * 3 * self.col.len() + 9 * nf + 3 * self.col.len());
        let mut vals = Vec::with_capacity(rows.capacity());
        // Aᵀ by columns = A by rows
        for f in 0..nf {
            let range = self.ptr[f]..self.ptr[f + 1];
            for k in 0..2 {
                for e in range.clone() {
                    let base = 3 * self.col[e] as usize;
                    rows.extend_from_slice(&[base, base + 1, base + 2]);
                    vals.extend_from_slice(&self.em[e][k].to_array());
                }
                col_ptr.push(rows.len());
            }
            for t in self.sd[f] {
                rows.extend_from_slice(&[3 * f, 3 * f + 1, 3 * f + 2]);
                vals.extend_from_slice(&t.to_array());
                col_ptr.push(rows.len());
            }
            for c in 0..3 {
                for e in range.clone() {
                    rows.push(3 * self.col[e] as usize + c);
                    vals.push(self.smo[e]);
                }
                col_ptr.push(rows.len());
            }
        }
        let symbolic = SymbolicSparseColMat::new_checked(3 * nf, 8 * nf, col_ptr, None, rows);
        SparseColMat::new(symbolic, vals)
            .as_ref()
            .transpose()
            .to_col_major()
            .map_err(|e| SolveError::Backend(format!("{e:?}")))
    }

    /// The regularised normal matrix AᵀA + εI (both triangles).
    pub fn normal_matrix(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        let mut matrix = normal_matrix(self.sparse()?.as_ref())?;
        let (symbolic, values) = matrix.parts_mut();
        for u in 0..symbolic.ncols() {
            let range = symbolic.col_range(u);
            let rows = &symbolic.row_idx()[range.clone()];
            match rows.binary_search(&u) {
                Ok(k) => values[range.start + k] += self.epsilon,
                Err(_) => {
                    return Err(SolveError::Backend(
                        "normal matrix lacks a diagonal entry".into(),
                    ));
                }
            }
        }
        Ok(matrix)
    }
}

/// Free vertices per parallel task of the matrix-free products.
const VERTICES: usize = 512;

/// The edge metric M_i = |k_i1| T_i1 T_i1ᵀ + |k_i2| T_i2 T_i2ᵀ of every
/// vertex (Ji et al. Eq. (2)).
fn edge_metrics(curvature: &PrincipalCurvatures) -> Vec<DMat3> {
    (0..curvature.k1.len())
        .into_par_iter()
        .map(|i| {
            let outer = |d: Vec3| DMat3::from_cols(d * d.x, d * d.y, d * d.z);
            let (a1, a2) = (curvature.k1[i].abs(), curvature.k2[i].abs());
            let m = outer(curvature.d1[i]) * a1 + outer(curvature.d2[i]) * a2;
            if m.is_finite() { m } else { DMat3::ZERO }
        })
        .collect()
}

/// Rows of Eq. (20) of one free vertex: its entries (column, F_em
/// coefficients, F_smo coefficient) and its eight right-hand sides.
type VertexRows = (Vec<(u32, [Vec3; 2], f64)>, [f64; 8]);

/// The normal equations of Eq. (20) as the staged solver of
/// [`crate::solve`] sees them.
impl NormalEquations for LeastSquares {
    fn rhs(&self) -> &[f64] {
        &self.rhs
    }
    fn apply(&self, v: &[f64], out: &mut [f64], scratch: &mut [f64]) {
        self.normal_product(v, out, scratch);
    }
    fn scratch_len(&self) -> usize {
        8 * self.sd.len()
    }
    fn diagonal_blocks(&self) -> Vec<f64> {
        LeastSquares::diagonal_blocks(self)
    }
    fn normal_matrix(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        LeastSquares::normal_matrix(self)
    }
}

/// Assembles the system of Eq. (20) for the current curvature (F_em,
/// F_smo) and the fixed distance model (F_sd), with the right-hand side of
/// the regularised normal equations. `current` and `reference` are
/// normalised positions of all vertices; fixed vertices are read from
/// `current`, F_sd pulls toward `reference`.
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble(
    layout: &Layout,
    curvature: &PrincipalCurvatures,
    boundary: &BoundaryCurves,
    distance: &DistanceModel,
    current: &[Vec3],
    reference: &[Vec3],
    mu: f64,
    epsilon: f64,
) -> Result<LeastSquares, EnhanceError> {
    let nf = layout.free.len();
    let metrics = edge_metrics(curvature);
    let rows: Vec<VertexRows> = (0..nf)
        .into_par_iter()
        .map(|f| {
            let rows = VertexInputs {
                layout,
                curvature,
                boundary,
                metrics: &metrics,
                distance,
                current,
                reference,
                mu,
            };
            rows.of(f)
        })
        .collect();
    let mut ptr = Vec::with_capacity(nf + 1);
    ptr.push(0usize);
    let total: usize = rows.iter().map(|r| r.0.len()).sum();
    let (mut col, mut em, mut smo) = (
        Vec::with_capacity(total),
        Vec::with_capacity(total),
        Vec::with_capacity(total),
    );
    let mut b = Vec::with_capacity(8 * nf);
    for (entries, rhs) in &rows {
        for &(g, c, s) in entries {
            col.push(g);
            em.push(c);
            smo.push(s);
        }
        ptr.push(col.len());
        b.extend_from_slice(rhs);
    }
    drop(rows);
    // the free-neighbour relation is symmetric: entry (f, g) has a mirror (g, f)
    let mirror: Vec<u32> = (0..nf)
        .into_par_iter()
        .flat_map_iter(|f| {
            let (ptr, col) = (&ptr, &col);
            (ptr[f]..ptr[f + 1]).map(move |e| {
                let g = col[e] as usize;
                let others = &col[ptr[g]..ptr[g + 1]];
                match others.binary_search(&(f as u32)) {
                    Ok(k) => (ptr[g] + k) as u32,
                    Err(_) => NONE,
                }
            })
        })
        .collect();
    if mirror.contains(&NONE) {
        return Err(SolveError::Backend("one-rings are not symmetric".into()).into());
    }
    let em_mirror = mirror.par_iter().map(|&m| em[m as usize]).collect();
    let smo_mirror = mirror.par_iter().map(|&m| smo[m as usize]).collect();
    let mut system = LeastSquares {
        ptr,
        col,
        em,
        smo,
        em_mirror,
        smo_mirror,
        sd: distance.rows.clone(),
        b,
        rhs: Vec::new(),
        epsilon,
    };
    // Aᵀb + ε p
    let mut rhs = vec![0.0; 3 * nf];
    system.mul_transpose(&system.b, &mut rhs);
    rhs.par_chunks_mut(3).enumerate().for_each(|(f, r)| {
        let p = reference[layout.free[f] as usize];
        for c in 0..3 {
            r[c] += epsilon * p[c];
        }
    });
    system.rhs = rhs;
    Ok(system)
}

/// |k_1|, |k_2| of vertex `i`, 0 where not finite.
fn absolute_curvatures(curvature: &PrincipalCurvatures, i: usize) -> (f64, f64) {
    let finite = |k: f64| if k.is_finite() { k.abs() } else { 0.0 };
    (finite(curvature.k1[i]), finite(curvature.k2[i]))
}

/// The weight μ μ_i of the F_smo rows of vertex `i` (their squared row
/// scale), μ_i = exp(−(|k_i1| + |k_i2|)) (Ji et al. Eq. (10)), curvature in
/// normalised units.
pub(super) fn smoothness_weight(curvature: &PrincipalCurvatures, i: usize, mu: f64) -> f64 {
    let (a1, a2) = absolute_curvatures(curvature, i);
    mu * (-(a1 + a2)).exp()
}

/// What the rows of a free vertex are built from (the arguments of
/// [`assemble`]).
struct VertexInputs<'a> {
    layout: &'a Layout,
    curvature: &'a PrincipalCurvatures,
    boundary: &'a BoundaryCurves,
    metrics: &'a [DMat3],
    distance: &'a DistanceModel,
    current: &'a [Vec3],
    reference: &'a [Vec3],
    mu: f64,
}

impl VertexInputs<'_> {
    /// The eight rows of free vertex `f` (two F_em, three F_sd, three F_smo):
    /// its entries in increasing free index (a neighbour listed twice sums)
    /// and the right-hand sides. A boundary vertex (module `boundary`) has
    /// one F_em row, along its boundary tangent t,
    /// tᵀ Σ_j (M_i + M_j)(v_i − v_j) = 0 (the second row is zero), and the
    /// F_smo rows of the Laplacian along the boundary, v_i − ½ (v_prev +
    /// v_next).
    fn of(&self, f: usize) -> VertexRows {
        let i = self.layout.free[f] as usize;
        let ring = self.layout.ring(f);
        let w_smo = smoothness_weight(self.curvature, i, self.mu).sqrt();
        // per neighbour: the two F_em coefficient vectors and the F_smo
        // coefficient
        let mut coefficients: Vec<(u32, [Vec3; 2], f64)> = Vec::with_capacity(ring.len());
        if let Some((t, _)) = boundary_frame(self.boundary, self.curvature, i) {
            let (prev, next) = self.boundary.neighbours(i);
            let mi = self.metrics[i];
            for &j in ring {
                let cj = -(mi * t + self.metrics[j as usize] * t);
                let s = if j == prev || j == next {
                    -0.5 * w_smo
                } else {
                    0.0
                };
                coefficients.push((j, [cj, Vec3::ZERO], s));
            }
        } else {
            let deg = ring.len().max(1) as f64;
            let (t1, t2) = (self.curvature.d1[i], self.curvature.d2[i]);
            let (a1, a2) = absolute_curvatures(self.curvature, i);
            let s_ring = -w_smo / deg;
            // F_em: T_ikᵀ Σ_j (M_i + M_j)(v_i − v_j), with M_i T_ik = |k_ik| T_ik
            for &j in ring {
                let mj = self.metrics[j as usize];
                let cj1 = -(a1 * t1 + mj * t1);
                let cj2 = -(a2 * t2 + mj * t2);
                coefficients.push((j, [cj1, cj2], s_ring));
            }
        }
        let mut ci = [Vec3::ZERO; 2];
        let mut b = [0.0; 8];
        let mut b_smo = Vec3::ZERO;
        let mut entries: Vec<(u32, [Vec3; 2], f64)> = Vec::with_capacity(ring.len() + 1);
        for (j, [cj1, cj2], s) in coefficients {
            ci[0] -= cj1;
            ci[1] -= cj2;
            let fj = self.layout.free_index[j as usize];
            if fj == NONE {
                let xj = self.current[j as usize];
                b[0] -= cj1.dot(xj);
                b[1] -= cj2.dot(xj);
                b_smo -= s * xj;
            } else {
                entries.push((fj, [cj1, cj2], s));
            }
        }
        entries.push((f as u32, ci, w_smo));
        entries.sort_unstable_by_key(|e| e.0);
        entries.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                kept.1[0] += later.1[0];
                kept.1[1] += later.1[1];
                kept.2 += later.2;
            }
            same
        });
        // F_sd rows: √(λc) Tᵀ v = √(λc) Tᵀ p
        let p = self.reference[i];
        for (k, t) in self.distance.rows[f].iter().enumerate() {
            b[2 + k] = t.dot(p);
        }
        b[5..8].copy_from_slice(&b_smo.to_array());
        (entries, b)
    }
}
