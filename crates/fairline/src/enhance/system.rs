//! Assembly of the 8n × 3n least-squares system of Ji et al. Eq. (20) and of
//! its normal equations. Rows of a free vertex i (free index f), in this
//! order: two F_em rows (Eq. (17)–(18)), three F_sd rows (Eq. (6)), three
//! F_smo rows (Eq. (8)–(10)), one per coordinate. Unknown 3f + c is
//! coordinate c of free vertex f. Fixed neighbours go to the right-hand
//! side. Every structural entry is emitted even when its value is zero, so
//! the pattern depends only on the connectivity and the symbolic
//! factorisation can be reused across iterations.

use super::EnhanceError;
use crate::Vec3;
use crate::geom::PrincipalCurvatures;
use crate::mesh::SurfaceMesh;
use crate::solve::{SolveError, normal_matrix};
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

    pub fn ring(&self, f: usize) -> &[u32] {
        &self.ring[self.ring_ptr[f]..self.ring_ptr[f + 1]]
    }
}

/// The F_sd rows of every free vertex (Eq. (6)): the frame (T1, T2, N) of
/// the input at p, each scaled by √(λ c) with c = d|k| / (1 + d|k|) for the
/// tangents (d = 1 / max |k| over the free vertices) and c = 1 for N.
pub(super) struct DistanceModel {
    /// The three scaled frame vectors of each free vertex.
    pub rows: Vec<[Vec3; 3]>,
}

impl DistanceModel {
    pub fn new(curvature: &PrincipalCurvatures, layout: &Layout, lambda: f64) -> DistanceModel {
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
            .map(|&v| {
                let v = v as usize;
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
}

/// The least-squares system of one iteration: A (8n × 3n) by columns and
/// by rows, and the right-hand side Aᵀb + ε p of the regularised normal
/// equations (AᵀA + εI) x = Aᵀb + ε p.
pub(super) struct LeastSquares {
    /// A, compressed by column.
    pub a: SparseColMat<usize, f64>,
    /// Aᵀ, compressed by column (the rows of A).
    pub at: SparseColMat<usize, f64>,
    /// Aᵀb + ε p.
    pub rhs: Vec<f64>,
    /// ε.
    pub epsilon: f64,
}

impl LeastSquares {
    /// The regularised normal matrix AᵀA + εI (both triangles).
    pub fn normal_matrix(&self) -> Result<SparseColMat<usize, f64>, EnhanceError> {
        let mut matrix = normal_matrix(self.a.as_ref())?;
        let (symbolic, values) = matrix.parts_mut();
        for u in 0..symbolic.ncols() {
            let range = symbolic.col_range(u);
            let rows = &symbolic.row_idx()[range.clone()];
            match rows.binary_search(&u) {
                Ok(k) => values[range.start + k] += self.epsilon,
                Err(_) => {
                    return Err(
                        SolveError::Backend("normal matrix lacks a diagonal entry".into()).into(),
                    );
                }
            }
        }
        Ok(matrix)
    }
}

/// Rows of one chunk of free vertices: columns of Aᵀ.
struct Chunk {
    col_len: Vec<usize>,
    rows: Vec<usize>,
    vals: Vec<f64>,
    b: Vec<f64>,
}

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

/// Assembles the 8n × 3n matrix A and right-hand side b of Eq. (20) for the
/// current curvature (F_em, F_smo) and the fixed distance model (F_sd), and
/// returns it with the right-hand side of the regularised normal equations. `current` and `reference` are
/// normalised positions of all vertices; fixed vertices are read from
/// `current`, F_sd pulls toward `reference`.
pub(super) fn assemble(
    layout: &Layout,
    curvature: &PrincipalCurvatures,
    distance: &DistanceModel,
    current: &[Vec3],
    reference: &[Vec3],
    mu: f64,
    epsilon: f64,
) -> Result<LeastSquares, EnhanceError> {
    const CHUNK: usize = 2048;
    let nf = layout.free.len();
    let metrics = edge_metrics(curvature);
    let chunks: Vec<Chunk> = (0..nf.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let range = c * CHUNK..((c + 1) * CHUNK).min(nf);
            let mut chunk = Chunk {
                col_len: Vec::with_capacity(8 * range.len()),
                rows: Vec::new(),
                vals: Vec::new(),
                b: Vec::with_capacity(8 * range.len()),
            };
            // (free index, F_em coefficients for T1 and T2, F_smo coefficient)
            let mut entries: Vec<(u32, Vec3, Vec3, f64)> = Vec::new();
            for f in range {
                vertex_rows(
                    layout,
                    curvature,
                    &metrics,
                    distance,
                    current,
                    reference,
                    mu,
                    f,
                    &mut entries,
                    &mut chunk,
                );
            }
            chunk
        })
        .collect();

    let total: usize = chunks.iter().map(|c| c.rows.len()).sum();
    let mut col_ptr = Vec::with_capacity(8 * nf + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::with_capacity(total);
    let mut vals = Vec::with_capacity(total);
    let mut b = Vec::with_capacity(8 * nf);
    for c in chunks {
        for len in c.col_len {
            let last = *col_ptr.last().unwrap_or(&0);
            col_ptr.push(last + len);
        }
        row_idx.extend_from_slice(&c.rows);
        vals.extend_from_slice(&c.vals);
        b.extend_from_slice(&c.b);
    }
    let symbolic = SymbolicSparseColMat::new_checked(3 * nf, 8 * nf, col_ptr, None, row_idx);
    let at = SparseColMat::new(symbolic, vals);
    let a = at
        .as_ref()
        .transpose()
        .to_col_major()
        .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
    // Aᵀb, gathered per unknown, plus ε p
    let rhs: Vec<f64> = (0..3 * nf)
        .into_par_iter()
        .map(|u| {
            let rows = a.row_idx_of_col_raw(u);
            let v = a.val_of_col(u);
            let p = reference[layout.free[u / 3] as usize];
            rows.iter().zip(v).map(|(&r, x)| x * b[r]).sum::<f64>() + epsilon * p[u % 3]
        })
        .collect();
    Ok(LeastSquares {
        a,
        at,
        rhs,
        epsilon,
    })
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

/// Emits the eight rows (columns of Aᵀ) of free vertex `f`.
#[allow(clippy::too_many_arguments)]
fn vertex_rows(
    layout: &Layout,
    curvature: &PrincipalCurvatures,
    metrics: &[DMat3],
    distance: &DistanceModel,
    current: &[Vec3],
    reference: &[Vec3],
    mu: f64,
    f: usize,
    entries: &mut Vec<(u32, Vec3, Vec3, f64)>,
    out: &mut Chunk,
) {
    let i = layout.free[f] as usize;
    let ring = layout.ring(f);
    let deg = ring.len().max(1) as f64;
    let (t1, t2) = (curvature.d1[i], curvature.d2[i]);
    let (a1, a2) = absolute_curvatures(curvature, i);
    let w_smo = smoothness_weight(curvature, i, mu).sqrt();
    let s_ring = -w_smo / deg;
    // F_em: T_ikᵀ Σ_j (M_i + M_j)(v_i − v_j), with M_i T_ik = |k_ik| T_ik
    let mut ci = [Vec3::ZERO; 2];
    let mut b_em = [0.0; 2];
    let mut b_smo = Vec3::ZERO;
    entries.clear();
    for &j in ring {
        let mj = metrics[j as usize];
        let cj1 = -(a1 * t1 + mj * t1);
        let cj2 = -(a2 * t2 + mj * t2);
        ci[0] -= cj1;
        ci[1] -= cj2;
        let fj = layout.free_index[j as usize];
        if fj == NONE {
            let xj = current[j as usize];
            b_em[0] -= cj1.dot(xj);
            b_em[1] -= cj2.dot(xj);
            b_smo -= s_ring * xj;
        } else {
            entries.push((fj, cj1, cj2, s_ring));
        }
    }
    entries.push((f as u32, ci[0], ci[1], w_smo));
    entries.sort_unstable_by_key(|e| e.0);

    // two F_em rows
    for k in 0..2 {
        let mut len = 0;
        for e in entries.iter() {
            let c = if k == 0 { e.1 } else { e.2 };
            let base = 3 * e.0 as usize;
            out.rows.extend_from_slice(&[base, base + 1, base + 2]);
            out.vals.extend_from_slice(&[c.x, c.y, c.z]);
            len += 3;
        }
        out.col_len.push(len);
        out.b.push(b_em[k]);
    }
    // three F_sd rows: √(λc) Tᵀ v = √(λc) Tᵀ p
    let p = reference[i];
    for t in distance.rows[f] {
        out.rows.extend_from_slice(&[3 * f, 3 * f + 1, 3 * f + 2]);
        out.vals.extend_from_slice(&[t.x, t.y, t.z]);
        out.col_len.push(3);
        out.b.push(t.dot(p));
    }
    // three F_smo rows, one per coordinate
    for c in 0..3 {
        for e in entries.iter() {
            out.rows.push(3 * e.0 as usize + c);
            out.vals.push(e.3);
        }
        out.col_len.push(entries.len());
        out.b.push(b_smo[c]);
    }
}
