//! Block-diagonal preconditioners whose blocks are symmetric positive
//! definite banded matrices of bandwidth 3, for three interleaved
//! right-hand sides (x, y, z), and the conjugate gradients preconditioned by
//! a sandwich of two of them: the line-block solver of structure-line
//! fairing (Grüner thesis ch. 4; `crate::fair::fair_structure_lines`),
//! where a block is one structure line and a run of four consecutive
//! points couples unknowns at most three places apart.
//!
//! A banded block costs O(length) to factor ([`banded_cholesky`]) and to
//! solve ([`banded_solve`]); there is no fill-in and no symbolic analysis,
//! so the preconditioner is rebuilt cheaply whenever the set of unknowns
//! changes.

use super::{CgReport, SolveError, pcg};
use rayon::prelude::*;

/// Unknowns per group of consecutive blocks solved by one task.
const GROUP_SIZE: usize = 4096;

/// A block-diagonal matrix of banded symmetric positive definite blocks
/// (bandwidth 3) over a permutation of the unknowns, in factored form.
pub struct BandedBlocks {
    /// unknowns in block order
    order: Vec<u32>,
    /// position of every unknown in `order`
    place: Vec<u32>,
    /// banded Cholesky factor: row i holds L(i, i) (its reciprocal),
    /// L(i, i−1), L(i, i−2), L(i, i−3)
    factor: Vec<[f64; 4]>,
    /// block boundaries in `order`
    block_start: Vec<usize>,
    /// groups of consecutive blocks of similar total length (parallel work)
    group_start: Vec<usize>,
}

impl BandedBlocks {
    /// Factors the blocks: `order` lists every unknown once, in block order;
    /// block b holds `order[block_start[b]..block_start[b + 1]]`
    /// (`block_start` starts at 0 and ends at the number of unknowns). The
    /// band of every block starts as `shift`·I (row i: M(i, i), M(i, i−1),
    /// M(i, i−2), M(i, i−3)) and `fill(b, band)` adds the block's entries
    /// (all blocks in parallel). `None` if a block is not numerically
    /// positive definite or the layout is inconsistent.
    pub fn new(
        order: Vec<u32>,
        block_start: Vec<usize>,
        shift: f64,
        fill: impl Fn(usize, &mut [[f64; 4]]) + Sync,
    ) -> Option<BandedBlocks> {
        let m = order.len();
        if block_start.first() != Some(&0) || block_start.last() != Some(&m) {
            return None;
        }
        let mut place = vec![u32::MAX; m];
        for (i, &u) in order.iter().enumerate() {
            let slot = place.get_mut(u as usize)?;
            if *slot != u32::MAX {
                return None;
            }
            *slot = i as u32;
        }
        let blocks = block_start.len() - 1;
        let mut factor = vec![[shift, 0.0, 0.0, 0.0]; m];
        let mut slices: Vec<&mut [[f64; 4]]> = Vec::with_capacity(blocks);
        let mut rest: &mut [[f64; 4]] = &mut factor;
        for b in 0..blocks {
            let (head, tail) = rest.split_at_mut(block_start[b + 1].checked_sub(block_start[b])?);
            slices.push(head);
            rest = tail;
        }
        let ok = slices.into_par_iter().enumerate().all(|(b, band)| {
            fill(b, band);
            banded_cholesky(band)
        });
        if !ok {
            return None;
        }
        let mut group_start = vec![0usize];
        for &s in &block_start[1..] {
            if s - group_start.last().copied().unwrap_or(0) >= GROUP_SIZE || s == m {
                group_start.push(s);
            }
        }
        group_start.dedup();
        Some(BandedBlocks {
            order,
            place,
            factor,
            block_start,
            group_start,
        })
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// z = scale · M⁻¹ r on interleaved x, y, z, or z += scale · M⁻¹ r when
    /// `add`. `y` is scratch space.
    pub fn solve(&self, r: &[f64], z: &mut [f64], scale: f64, add: bool, y: &mut Vec<f64>) {
        // gather into block order, solve the blocks, scatter back
        y.resize(r.len(), 0.0);
        y.par_chunks_mut(3)
            .zip(self.order.par_iter())
            .with_min_len(4096)
            .for_each(|(y, &u)| {
                let u = 3 * u as usize;
                y.copy_from_slice(&r[u..u + 3]);
            });
        let mut chunks: Vec<(&mut [f64], usize)> = Vec::with_capacity(self.group_start.len());
        let mut rest: &mut [f64] = y;
        for g in self.group_start.windows(2) {
            let (head, tail) = rest.split_at_mut(3 * (g[1] - g[0]));
            chunks.push((head, g[0]));
            rest = tail;
        }
        chunks.into_par_iter().for_each(|(y, start)| {
            let first = self.block_start.partition_point(|&s| s < start);
            let mut b = first;
            while b + 1 < self.block_start.len() && self.block_start[b] < start + y.len() / 3 {
                let (s0, s1) = (self.block_start[b], self.block_start[b + 1]);
                banded_solve(
                    &self.factor[s0..s1],
                    &mut y[3 * (s0 - start)..3 * (s1 - start)],
                );
                b += 1;
            }
        });
        z.par_chunks_mut(3)
            .zip(self.place.par_iter())
            .with_min_len(4096)
            .for_each(|(z, &p)| {
                let p = 3 * p as usize;
                if add {
                    z[0] += scale * y[p];
                    z[1] += scale * y[p + 1];
                    z[2] += scale * y[p + 2];
                } else {
                    z[0] = scale * y[p];
                    z[1] = scale * y[p + 1];
                    z[2] = scale * y[p + 2];
                }
            });
    }
}

/// Conjugate gradients ([`pcg`]) for N x = b on interleaved x, y, z
/// (`apply` computes N v), preconditioned by the sandwich
/// M⁻¹ = P₁⁻¹P₂⁻¹P₁⁻¹ of two banded block matrices: symmetric positive
/// definite whenever P₁ and P₂ are, even where they do not commute (the
/// alternating-direction product P₁P₂ of Peaceman–Rachford need not be).
/// `x` is the start and the result.
pub fn sandwich_pcg(
    apply: impl FnMut(&[f64], &mut [f64]),
    outer: &BandedBlocks,
    inner: &BandedBlocks,
    rhs: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<CgReport, SolveError> {
    let n = 3 * outer.len();
    if inner.len() != outer.len() || rhs.len() != n || x.len() != n {
        return Err(SolveError::Dimension(format!(
            "banded blocks of {} and {} unknowns, right-hand side {}, start {}",
            outer.len(),
            inner.len(),
            rhs.len(),
            x.len()
        )));
    }
    let (mut a, mut b, mut y) = (vec![0.0; n], vec![0.0; n], Vec::new());
    let precondition = |r: &[f64], z: &mut [f64]| {
        outer.solve(r, &mut a, 1.0, false, &mut y);
        inner.solve(&a, &mut b, 1.0, false, &mut y);
        outer.solve(&b, z, 1.0, false, &mut y);
    };
    pcg(apply, precondition, rhs, x, tolerance, max_iterations)
}

/// In-place Cholesky factor of a symmetric banded matrix of bandwidth 3
/// (row i: M(i, i), M(i, i−1), M(i, i−2), M(i, i−3)); row i of the result
/// holds 1/L(i, i), L(i, i−1), L(i, i−2), L(i, i−3). False if a pivot is
/// not positive.
pub fn banded_cholesky(band: &mut [[f64; 4]]) -> bool {
    for i in 0..band.len() {
        for d in (1..=3.min(i)).rev() {
            let j = i - d;
            // L(i, j) = (M(i, j) − Σ_{k<j} L(i, k) L(j, k)) / L(j, j)
            let mut s = band[i][d];
            for k in (i.saturating_sub(3))..j {
                s -= band[i][i - k] * band[j][j - k];
            }
            band[i][d] = s * band[j][0];
        }
        let mut s = band[i][0];
        for d in 1..=3.min(i) {
            s -= band[i][d] * band[i][d];
        }
        if !(s > 0.0) || !s.is_finite() {
            return false;
        }
        band[i][0] = 1.0 / s.sqrt();
    }
    true
}

/// Solves L Lᵀ y = b in place for three interleaved right-hand sides; `l`
/// is the factor of [`banded_cholesky`] (reciprocal diagonal; the entries of
/// the first rows that reach before row 0 are zero).
pub fn banded_solve(l: &[[f64; 4]], y: &mut [f64]) {
    // forward: L w = b, keeping w_{i−1}, w_{i−2}, w_{i−3}
    let (mut w1, mut w2, mut w3) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    for (li, yi) in l.iter().zip(y.chunks_exact_mut(3)) {
        let mut s = [0.0; 3];
        for c in 0..3 {
            s[c] = (yi[c] - li[1] * w1[c] - li[2] * w2[c] - li[3] * w3[c]) * li[0];
        }
        yi.copy_from_slice(&s);
        (w3, w2, w1) = (w2, w1, s);
    }
    // backward: Lᵀ y = w, keeping y_{i+1..i+3} and the rows L(i+d, ·)
    let (mut y1, mut y2, mut y3) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    let (mut r1, mut r2, mut r3) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
    for (li, yi) in l.iter().zip(y.chunks_exact_mut(3)).rev() {
        let mut s = [0.0; 3];
        for c in 0..3 {
            s[c] = (yi[c] - r1[1] * y1[c] - r2[2] * y2[c] - r3[3] * y3[c]) * li[0];
        }
        yi.copy_from_slice(&s);
        (y3, y2, y1) = (y2, y1, s);
        (r3, r2, r1) = (r2, r1, *li);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense M x for a banded matrix given by rows (M(i, i), M(i, i−1) …).
    fn band_times(band: &[[f64; 4]], x: &[f64]) -> Vec<f64> {
        let n = band.len();
        let mut y = vec![0.0; 3 * n];
        for i in 0..n {
            for d in 0..=3.min(i) {
                let j = i - d;
                for c in 0..3 {
                    y[3 * i + c] += band[i][d] * x[3 * j + c];
                    if d > 0 {
                        y[3 * j + c] += band[i][d] * x[3 * i + c];
                    }
                }
            }
        }
        y
    }

    /// A positive definite band: the sum of run terms aaᵀ of four
    /// consecutive points plus a shift (how structure-line fairing fills it).
    fn run_band(n: usize, shift: f64) -> Vec<[f64; 4]> {
        let mut band = vec![[shift, 0.0, 0.0, 0.0]; n];
        for s in 0..n.saturating_sub(3) {
            let a = [-0.5, 1.5 + 0.1 * s as f64, -1.5, 0.5];
            for t in 0..4 {
                for w in 0..=t {
                    band[s + t][t - w] += a[t] * a[w];
                }
            }
        }
        band
    }

    #[test]
    fn banded_cholesky_solves_the_band_and_refuses_an_indefinite_one() {
        let band = run_band(40, 0.01);
        let mut factor = band.clone();
        assert!(banded_cholesky(&mut factor));
        let x: Vec<f64> = (0..120).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        let mut y = band_times(&band, &x);
        banded_solve(&factor, &mut y);
        let err = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-8, "{err}");
        let mut bad = run_band(10, -1.0);
        assert!(!banded_cholesky(&mut bad));
    }

    #[test]
    fn banded_blocks_solve_every_block_through_the_permutation() {
        // two blocks over a shuffled order of 9 unknowns
        let order = vec![4, 0, 7, 2, 8, 1, 6, 3, 5];
        let blocks = BandedBlocks::new(order.clone(), vec![0, 5, 9], 0.5, |b, band| {
            let extra = run_band(band.len(), 0.0);
            for (row, e) in band.iter_mut().zip(&extra) {
                for d in 0..4 {
                    row[d] += (1.0 + b as f64) * e[d];
                }
            }
        })
        .expect("positive definite");
        assert_eq!(blocks.len(), 9);
        let r: Vec<f64> = (0..27).map(|k| (k as f64 * 0.37).sin()).collect();
        let mut z = vec![0.0; 27];
        let mut y = Vec::new();
        blocks.solve(&r, &mut z, 2.0, false, &mut y);
        // check block by block: M_b (z/2 gathered) = r gathered
        let (zr, rr) = (&z, &r);
        for (b, range) in [(0usize, 0..5), (1, 5..9)] {
            let mut band = run_band(range.len(), 0.0);
            for row in band.iter_mut() {
                for v in row.iter_mut() {
                    *v *= 1.0 + b as f64;
                }
                row[0] += 0.5;
            }
            let zg: Vec<f64> = order[range.clone()]
                .iter()
                .flat_map(|&u| (0..3).map(move |c| 0.5 * zr[3 * u as usize + c]))
                .collect();
            let rg: Vec<f64> = order[range]
                .iter()
                .flat_map(|&u| (0..3).map(move |c| rr[3 * u as usize + c]))
                .collect();
            let mz = band_times(&band, &zg);
            let err = mz
                .iter()
                .zip(&rg)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "block {b}: {err}");
        }
        // inconsistent layouts are refused
        assert!(BandedBlocks::new(vec![0, 0], vec![0, 2], 1.0, |_, _| {}).is_none());
        assert!(BandedBlocks::new(vec![0, 1], vec![0, 1], 1.0, |_, _| {}).is_none());
    }
}
