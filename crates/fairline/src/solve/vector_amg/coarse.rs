//! What the hierarchy needs of a block operator: the scalar matrix and the
//! strength of its connections, the Galerkin product PᵀKP of the next
//! level, and the coarsest level as a faer matrix for the direct solve.

use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;

use super::operator::{Blocks, Scalars, SymmetricBlock, VectorOperator, full_block, shifted};
use crate::solve::amg::{ROWS, RowAccumulator};
use crate::solve::{CsrMatrix, SolveError};

impl VectorOperator {
    /// The scalar matrix A.
    pub(super) fn scalar(&self) -> CsrMatrix {
        let n = self.nodes();
        let val = match &self.a {
            Scalars::Entries(a) => a.clone(),
            Scalars::UnitOffDiagonal { .. } => (0..n)
                .into_par_iter()
                .flat_map_iter(|i| (self.ptr[i]..self.ptr[i + 1]).map(move |e| self.entry(i, e).0))
                .collect(),
        };
        CsrMatrix {
            nrows: n,
            ncols: n,
            ptr: self.ptr.clone(),
            idx: self.idx.clone(),
            val,
        }
    }

    /// Per node, (J, ‖A_IJ I₃ + S_IJ‖²_F) over its stored entries.
    pub(super) fn strength_norms(&self) -> Vec<Vec<(u32, f64)>> {
        (0..self.nodes())
            .into_par_iter()
            .map(|i| {
                (self.ptr[i]..self.ptr[i + 1])
                    .map(|e| {
                        let k = self.entry(i, e).1;
                        let diagonal = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                        let off = 2.0 * (k[3] * k[3] + k[4] * k[4] + k[5] * k[5]);
                        (self.idx[e], diagonal + off)
                    })
                    .collect()
            })
            .collect()
    }

    /// The Galerkin operator (P ⊗ I₃)ᵀ K (P ⊗ I₃) for the scalar
    /// prolongator `p` (with its transpose `pt`), symmetrised; a node whose
    /// row vanishes (a zero column of `p`) gets a unit diagonal.
    ///
    /// With S on the diagonal only, Pᵀ A P and Pᵀ S P are summed apart:
    /// an off-diagonal entry of K adds one scalar per coarse pair instead
    /// of seven values.
    pub(super) fn galerkin(
        &self,
        p: &CsrMatrix,
        pt: &CsrMatrix,
    ) -> Result<VectorOperator, SolveError> {
        let nc = p.ncols;
        type Row = Vec<(u32, f64, SymmetricBlock)>;
        // a few tasks per thread also on small coarse levels (each with an
        // accumulator as long as a coarse row)
        let per_task = nc
            .div_ceil(4 * rayon::current_num_threads())
            .clamp(16, ROWS);
        let reaction_only = matches!(self.s, Blocks::Diagonal(_));
        let rows: Vec<Row> = (0..nc.div_ceil(per_task))
            .into_par_iter()
            .flat_map_iter(|c| {
                // column sums of (A, K) for Full, (A, S) for Diagonal
                let mut acc = RowAccumulator::<7>::new(nc);
                let mut out: Vec<Row> = Vec::new();
                for ci in c * per_task..((c + 1) * per_task).min(nc) {
                    let (ki, kv) = pt.row(ci);
                    for (&k, &pk) in ki.iter().zip(kv) {
                        let k = k as usize;
                        for e in self.ptr[k]..self.ptr[k + 1] {
                            let l = self.idx[e] as usize;
                            let (li, lv) = p.row(l);
                            let (a, s) = match &self.s {
                                Blocks::Full(blocks) => (self.scalar_entry(k, e), blocks[e]),
                                Blocks::Diagonal(blocks) if l == k => {
                                    (self.scalar_entry(k, e), blocks[k])
                                }
                                Blocks::Diagonal(_) => {
                                    let a = self.scalar_entry(k, e);
                                    for (&j, &pl) in li.iter().zip(lv) {
                                        acc.add_first(j, pk * pl * a);
                                    }
                                    continue;
                                }
                            };
                            for (&j, &pl) in li.iter().zip(lv) {
                                let w = pk * pl;
                                acc.add_vector(
                                    j,
                                    [
                                        w * a,
                                        w * s[0],
                                        w * s[1],
                                        w * s[2],
                                        w * s[3],
                                        w * s[4],
                                        w * s[5],
                                    ],
                                );
                            }
                        }
                    }
                    let mut row = Vec::new();
                    acc.flush_with(|j, v| {
                        let s = [v[1], v[2], v[3], v[4], v[5], v[6]];
                        row.push((j, v[0], if reaction_only { shifted(v[0], &s) } else { s }));
                    });
                    out.push(row);
                }
                out
            })
            .collect();
        // symmetrise: average (I, J) and (J, I) (equal up to rounding)
        let rows: Vec<Row> = rows
            .par_iter()
            .enumerate()
            .map(|(i, row)| {
                let mut out: Row = row
                    .iter()
                    .map(|&(j, a, s)| {
                        let other = &rows[j as usize];
                        match other.binary_search_by_key(&(i as u32), |e| e.0) {
                            Ok(q) => {
                                let (_, b, t) = other[q];
                                let mut m = [0.0; 6];
                                for r in 0..6 {
                                    m[r] = 0.5 * (s[r] + t[r]);
                                }
                                (j, 0.5 * (a + b), m)
                            }
                            Err(_) => (j, a, s),
                        }
                    })
                    .collect();
                let vanishes = out.iter().all(|e| e.1 == 0.0 && e.2 == [0.0; 6]);
                if vanishes || !out.iter().any(|e| e.0 as usize == i) {
                    out.retain(|e| e.0 as usize != i);
                    let at = out.partition_point(|e| (e.0 as usize) < i);
                    let a = if vanishes { 1.0 } else { 0.0 };
                    out.insert(at, (i as u32, a, shifted(a, &[0.0; 6])));
                }
                out
            })
            .collect();
        VectorOperator::from_entries(rows, true)
    }

    /// The assembled 3n × 3n matrix (both triangles).
    pub(super) fn to_faer(&self) -> Result<SparseColMat<usize, f64>, SolveError> {
        let mut t = Vec::with_capacity(9 * self.entries());
        for i in 0..self.nodes() {
            for e in self.ptr[i]..self.ptr[i + 1] {
                let j = self.idx[e] as usize;
                let m = full_block(&self.entry(i, e).1);
                for (r, row) in m.iter().enumerate() {
                    for (c, &v) in row.iter().enumerate() {
                        if v != 0.0 {
                            t.push(Triplet::new(3 * i + r, 3 * j + c, v));
                        }
                    }
                }
            }
        }
        let n = 3 * self.nodes();
        SparseColMat::try_new_from_triplets(n, n, &t)
            .map_err(|e| SolveError::Backend(format!("{e:?}")))
    }
}
