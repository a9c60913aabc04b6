//! Smoothed-aggregation multigrid (Vaněk, Mandel & Brezina 1996) for
//! symmetric positive-definite operators on three unknowns per node that
//! act alike on the three coordinates up to a local coupling:
//!
//!   K = A ⊗ I₃ + S,
//!
//! A a symmetric scalar matrix over the nodes (at the finest level a graph
//! Laplacian), S a symmetric block matrix with the pattern of A whose
//! blocks S_IJ are symmetric 3 × 3 (at the finest level a reaction term on
//! the diagonal only). Node I owns the unknowns 3I, 3I + 1, 3I + 2.
//!
//! The hierarchy keeps this structure. The tentative prolongator T_s comes
//! from one scalar near-null vector per node (constants: the translations
//! of every coordinate) and is smoothed with A alone,
//! P_s = (I − ω D_A⁻¹ A) T_s, so the prolongator of the three coordinates
//! is P = P_s ⊗ I₃ and the Galerkin coarse operator
//!
//!   Pᵀ K P = (P_sᵀ A P_s) ⊗ I₃ + P_sᵀ S P_s,   (P_sᵀ S P_s)_IJ = Σ_kl P_kI P_lJ S_kl,
//!
//! has the same form (its blocks are again symmetric, its pattern that of
//! P_sᵀ A P_s). Against the same method on the assembled 3n × 3n matrix
//! (3 × 3 blocks everywhere, as fairline had before) a stored coarse entry
//! is one index, one scalar and six block values instead of nine indices
//! and nine values, the prolongator has a ninth of the entries, the finest
//! level stores S on its diagonal only, and the setup multiplies scalar
//! matrices: on the 100k-vertex rounded cube of vertex flow a V-cycle took
//! 11.5 ms instead of about 40 and the setup 0.4 s instead of 1.3 s, in
//! fewer conjugate-gradient iterations. Aggregation, the tentative
//! prolongator and its smoothing are the shared steps of `amg.rs`.
//!
//! Apply: one symmetric V-cycle — ν damped block-Jacobi steps
//! x ← x + ω D⁻¹(b − K x), D the 3 × 3 diagonal blocks of K,
//! ω = 4 / (3 ρ̄) (ρ̄ as for the prolongator smoothing), before and ν
//! after the coarse correction, with restriction Pᵀ and prolongation P;
//! the coarsest level (at most [`VectorAmgOptions::max_coarse_nodes`]
//! nodes) is factored by [`super::CholeskySolver`]. The smoother is
//! convergent in the K norm (ω ρ(D⁻¹K) ≤ 4/3 < 2), pre- and post-smoothing
//! are adjoint and the coarsest solve is exact, so the V-cycle is a
//! symmetric positive-definite operator and a valid preconditioner for
//! conjugate gradients. The one-sided cycles [`VectorAmg::apply_pre`] (ν
//! steps before each coarse correction, none after) and
//! [`VectorAmg::apply_post`] (after only) are each other's transposes, so
//! a product Vᵀ W V with them is symmetric at the cost of one symmetric
//! cycle (vertex flow's factored preconditioner). Every parallel loop
//! writes disjoint rows and sums in a fixed order: the result does not
//! depend on the number of threads.
//!
//! Cost. Each smoothing step forms the residual row by row and updates
//! into a second vector (no stored residual, one pass instead of two), the
//! prolongation adds into that vector in the same pass, and the steps
//! alternate between the two vectors (starting in the one that makes the
//! result end in x, so no copy); the
//! finest H of vertex flow, a graph Laplacian, stores no off-diagonal
//! values (all −1); coarse levels store the whole block A_IJ I₃ + S_IJ
//! (one 3 × 3 product per entry), A beside it for the setup only. On the
//! 100k-vertex rounded cube a V-cycle went from 10.8 ms to 9.0 ms (best
//! of 40) with these.

use std::sync::Mutex;

use rayon::prelude::*;

use super::amg::{
    aggregate_nodes, block_jacobi, jacobi_damping, power_iterations, smooth_prolongator, tentative,
};
use super::cg::{Preconditioner, invert_spd};
use super::{CholeskySolver, CsrMatrix, SolveError};
use operator::{Blocks, MIN_TASK_CHUNKS, NODES, for_each_node, full_block, symmetric_mul};

mod coarse;
mod operator;
#[cfg(test)]
mod tests;

pub use operator::{SymmetricBlock, VectorOperator};

/// Options of [`VectorAmg::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct VectorAmgOptions {
    /// Damped block-Jacobi steps before and after each coarse correction.
    pub smoothing_steps: usize,
    /// Factor the level directly once it has at most this many nodes.
    pub max_coarse_nodes: usize,
    /// Largest number of levels.
    pub max_levels: usize,
    /// Strength threshold θ of the aggregation: nodes I, J are aggregated
    /// together only when ‖K_IJ‖ ≥ θ √(‖K_II‖ ‖K_JJ‖) (Frobenius norms).
    pub strength: f64,
}

impl Default for VectorAmgOptions {
    fn default() -> Self {
        VectorAmgOptions {
            smoothing_steps: 1,
            max_coarse_nodes: 150,
            max_levels: 10,
            strength: 0.08,
        }
    }
}

crate::control::setters!(VectorAmgOptions {
    smoothing_steps: usize,
    max_coarse_nodes: usize,
    max_levels: usize,
    strength: f64,
});

struct Level {
    k: VectorOperator,
    /// Inverses of the diagonal blocks of K (symmetric).
    inverses: Vec<SymmetricBlock>,
    omega: f64,
    /// Scalar prolongator from the next coarser level and its transpose.
    p: CsrMatrix,
    pt: CsrMatrix,
}

/// A smoothed-aggregation multigrid V-cycle for K = A ⊗ I₃ + S, a
/// symmetric positive-definite preconditioner of K (module documentation).
pub struct VectorAmg {
    levels: Vec<Level>,
    coarse: CholeskySolver,
    smoothing_steps: usize,
    workspace: Mutex<Vec<[Vec<f64>; 4]>>,
}

impl VectorAmg {
    /// Builds the hierarchy for the symmetric positive-definite `k` with
    /// the scalar near-null vector `nullspace` (one value per node; ones
    /// for the translations).
    ///
    /// Errors: a near-null vector of the wrong length, a coarsest operator
    /// that is not positive definite (K was not).
    pub fn new(
        k: VectorOperator,
        nullspace: &[f64],
        options: &VectorAmgOptions,
    ) -> Result<VectorAmg, SolveError> {
        if nullspace.len() != k.nodes() {
            return Err(SolveError::Dimension(format!(
                "vector multigrid: {} nodes, near-null vector of length {}",
                k.nodes(),
                nullspace.len()
            )));
        }
        let mut levels = Vec::new();
        let mut k = k;
        let mut b = nullspace.to_vec();
        loop {
            let n = k.nodes();
            if n <= options.max_coarse_nodes || levels.len() + 1 >= options.max_levels {
                break;
            }
            let aggregates = aggregate_nodes(&k.strength_norms(), options.strength);
            let count = aggregates
                .iter()
                .map(|&a| a as usize + 1)
                .max()
                .unwrap_or(0);
            if count >= n {
                break;
            }
            let (t, coarse_b) = tentative(&aggregates, count, 1, &b, 1);
            let a = k.scalar();
            let (a_inverse, a_omega, a_power) = block_jacobi(&a, 1);
            let p = smooth_prolongator(&t, &a.matmul(&t), &a_inverse, 1, a_omega);
            let pt = p.transpose();
            let kc = k.galerkin(&p, &pt)?;
            let (inverses, omega) = vector_jacobi(&k, a_power);
            levels.push(Level {
                k,
                inverses,
                omega,
                p,
                pt,
            });
            k = kc;
            b = coarse_b;
        }
        let coarse = CholeskySolver::new(k.to_faer()?.as_ref())?;
        let mut amg = VectorAmg {
            levels,
            coarse,
            smoothing_steps: options.smoothing_steps.max(1),
            workspace: Mutex::new(Vec::new()),
        };
        amg.workspace = Mutex::new(amg.new_workspace());
        Ok(amg)
    }

    /// Nodes and stored entries per level, finest first (the last level is
    /// factored).
    pub fn sizes(&self) -> Vec<(usize, usize)> {
        let mut s: Vec<(usize, usize)> = self
            .levels
            .iter()
            .map(|l| (l.k.nodes(), l.k.entries()))
            .collect();
        s.push((self.coarse.dim() / 3, self.coarse.factor_len()));
        s
    }

    /// Scratch vectors of every level: the other iterate of the smoothing
    /// steps, the residual, the coarse residual, the coarse correction.
    fn new_workspace(&self) -> Vec<[Vec<f64>; 4]> {
        self.levels
            .iter()
            .map(|l| {
                let (n, nc) = (3 * l.k.nodes(), 3 * l.p.ncols);
                [vec![0.0; n], vec![0.0; n], vec![0.0; nc], vec![0.0; nc]]
            })
            .collect()
    }

    /// x = V-cycle applied to b from `level` down, with `pre` smoothing
    /// steps before the coarse correction and `post` after, on every
    /// level. The steps alternate between x and a scratch vector, which
    /// one holds the iterate first is chosen so that the result ends in x
    /// without a copy.
    fn cycle(
        &self,
        level: usize,
        b: &[f64],
        x: &mut [f64],
        workspace: &mut [[Vec<f64>; 4]],
        (pre, post): (usize, usize),
    ) {
        if level == self.levels.len() {
            x.copy_from_slice(b);
            if self.coarse.solve_in_place(x).is_err() {
                x.iter_mut().for_each(|v| *v = 0.0);
            }
            return;
        }
        let l = &self.levels[level];
        let Some(([other, r, rc, xc], deeper)) = workspace.split_first_mut() else {
            return;
        };
        // steps that move the iterate to the other vector: pre − 1
        // smoothing steps, the prolongation, post smoothing steps
        let moves = pre.saturating_sub(1) + 1 + post;
        let (mut current, mut next): (&mut [f64], &mut [f64]) = if moves % 2 == 0 {
            (x, other)
        } else {
            (other, x)
        };
        if pre > 0 {
            // pre-smoothing from x = 0: the first step is x = ω D⁻¹ b
            scale_by_inverses(&l.inverses, l.omega, b, current);
            for _ in 1..pre {
                l.k.smooth(&l.inverses, l.omega, b, current, next);
                std::mem::swap(&mut current, &mut next);
            }
            l.k.residual(b, current, r);
            mul_coordinates(&l.pt, r, rc);
        } else {
            // x = 0: the residual is b
            mul_coordinates(&l.pt, b, rc);
        }
        self.cycle(level + 1, rc, xc, deeper, (pre, post));
        prolong_add(&l.p, xc, (pre > 0).then_some(&*current), next);
        std::mem::swap(&mut current, &mut next);
        for _ in 0..post {
            l.k.smooth(&l.inverses, l.omega, b, current, next);
            std::mem::swap(&mut current, &mut next);
        }
    }

    /// Runs `cycle` from the finest level with the shared scratch vectors
    /// (no page faults on fresh memory each cycle); a concurrent call gets
    /// its own.
    fn run(&self, r: &[f64], z: &mut [f64], steps: (usize, usize)) {
        match self.workspace.try_lock() {
            Ok(mut workspace) => self.cycle(0, r, z, &mut workspace, steps),
            Err(_) => self.cycle(0, r, z, &mut self.new_workspace(), steps),
        }
    }

    /// The V-cycle with ν smoothing steps before each coarse correction
    /// and none after, V_pre; [`VectorAmg::apply_post`] is its transpose,
    /// so V_preᵀ W V_pre is symmetric positive semi-definite for every
    /// symmetric positive semi-definite W, at the cost of one symmetric
    /// V-cycle. (With T = I − ω D⁻¹K and Z = Σ_{i<ν} Tⁱ ω D⁻¹, Z is
    /// symmetric and I − Z K = T^ν, so V_pre = Z + P V_pre,c Pᵀ (I − K Z)
    /// has the transpose Z + T^ν P V_pre,cᵀ Pᵀ, the cycle with ν steps after
    /// each coarse correction only, by induction over the levels.)
    pub fn apply_pre(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (self.smoothing_steps, 0));
    }

    /// The transpose of [`VectorAmg::apply_pre`]: ν smoothing steps after
    /// each coarse correction and none before.
    pub fn apply_post(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (0, self.smoothing_steps));
    }
}

impl Preconditioner for VectorAmg {
    /// The symmetric V-cycle: ν steps before and ν after each coarse
    /// correction.
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.run(r, z, (self.smoothing_steps, self.smoothing_steps));
    }
}

/// y = (M ⊗ I₃) x for a scalar matrix M on interleaved coordinates.
fn mul_coordinates(m: &CsrMatrix, x: &[f64], y: &mut [f64]) {
    for_each_node(y, |i, y| {
        let (idx, val) = m.row(i);
        let mut s = [0.0; 3];
        for (&j, &v) in idx.iter().zip(val) {
            let j = 3 * j as usize;
            for r in 0..3 {
                s[r] += v * x[j + r];
            }
        }
        *y = s;
    });
}

/// out = base + (M ⊗ I₃) x for a scalar matrix M on interleaved
/// coordinates (the prolongation of a coarse correction, added; base 0
/// when None).
fn prolong_add(m: &CsrMatrix, x: &[f64], base: Option<&[f64]>, out: &mut [f64]) {
    for_each_node(out, |i, out| {
        let (idx, val) = m.row(i);
        let mut s = base.map_or([0.0; 3], |b| [b[3 * i], b[3 * i + 1], b[3 * i + 2]]);
        for (&j, &v) in idx.iter().zip(val) {
            let j = 3 * j as usize;
            for r in 0..3 {
                s[r] += v * x[j + r];
            }
        }
        *out = s;
    });
}

/// x = ω D⁻¹ r, D⁻¹ the symmetric inverses of the 3 × 3 diagonal blocks.
fn scale_by_inverses(inverses: &[SymmetricBlock], omega: f64, r: &[f64], x: &mut [f64]) {
    x.par_chunks_mut(3 * NODES)
        .zip(r.par_chunks(3 * NODES))
        .zip(inverses.par_chunks(NODES))
        .with_min_len(MIN_TASK_CHUNKS)
        .for_each(|((x, r), inv)| {
            for ((x, r), m) in x.chunks_mut(3).zip(r.chunks(3)).zip(inv) {
                let z = symmetric_mul(m, r);
                for i in 0..3 {
                    x[i] = omega * z[i];
                }
            }
        });
}

/// Inverses of the diagonal blocks of K and the smoother's damping
/// 4 / (3 ρ̄), ρ̄ the smaller of the largest absolute row sum of D⁻¹K and
/// 1.1 times a power-iteration estimate of ρ(D⁻¹K), given `scalar_power`,
/// that estimate of ρ(D_A⁻¹A).
///
/// When S is block-diagonal (the finest level of vertex flow) that of A
/// serves: D = D_A ⊗ I₃ + S, and for every x
/// xᵀKx / xᵀDx = (xᵀ(A ⊗ I₃)x + xᵀSx) / (xᵀ(D_A ⊗ I₃)x + xᵀSx)
/// ≤ max(ρ(D_A⁻¹A), 1) = ρ(D_A⁻¹A) (S ⪰ 0; the mean eigenvalue of D_A⁻¹A
/// is 1), so ρ(D⁻¹K) ≤ ρ(D_A⁻¹A) — fifteen products with K saved.
fn vector_jacobi(k: &VectorOperator, scalar_power: f64) -> (Vec<SymmetricBlock>, f64) {
    let n = k.nodes();
    let inverses: Vec<SymmetricBlock> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut m = k.diagonal_block(i);
            let mut inv = [0.0; 9];
            invert_spd(&mut m, 3, &mut inv);
            // symmetric up to rounding: average the two triangles
            let mean = |r: usize, c: usize| 0.5 * (inv[3 * r + c] + inv[3 * c + r]);
            [inv[0], inv[4], inv[8], mean(0, 1), mean(0, 2), mean(1, 2)]
        })
        .collect();
    let gershgorin = (0..n)
        .into_par_iter()
        .map(|i| {
            let inv = full_block(&inverses[i]);
            let mut sums = [0.0f64; 3];
            for e in k.ptr[i]..k.ptr[i + 1] {
                let m = full_block(&k.entry(i, e).1);
                for (r, sum) in sums.iter_mut().enumerate() {
                    for c in 0..3 {
                        let v: f64 = (0..3).map(|l| inv[r][l] * m[l][c]).sum();
                        *sum += v.abs();
                    }
                }
            }
            sums.into_iter().fold(0.0f64, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    let power = if matches!(k.s, Blocks::Diagonal(_)) {
        scalar_power.max(1.0)
    } else {
        let mut y = vec![0.0; 3 * n];
        power_iterations(3 * n, |x, z| {
            k.mul_vec(x, &mut y);
            scale_by_inverses(&inverses, 1.0, &y, z);
        })
    };
    (inverses, jacobi_damping(gershgorin, power))
}
