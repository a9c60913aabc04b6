//! The linear least-squares solve of one iteration of structure-line
//! fairing: sparse Cholesky of the normal equations, or conjugate gradients
//! preconditioned with banded per-line blocks.

use super::QuadFairError;
use crate::Vec3;
use crate::mesh::StructureLine;
use crate::solve::{BandedBlocks, CholeskySolver, SolveError, sandwich_pcg};
use rayon::prelude::*;

/// Largest number of free vertices solved by sparse Cholesky. The normal
/// matrix couples each vertex with the vertices up to three steps away along
/// both of its structure lines, so the Cholesky factor of a large grid fills
/// in heavily (1M unknowns: gigabytes, tens of seconds), while the
/// line-preconditioned conjugate gradients need a few dozen passes over N.
pub(crate) const DIRECT_LIMIT: usize = 20_000;

/// Accuracy ε of the iterative solve in units of the mean edge length ē:
/// the root mean square error of the computed displacements is at most ε·ē
/// (see [`System::solve_iterative`]).
const ITERATIVE_ACCURACY: f64 = 1e-7;

/// Shifts of the sandwich preconditioner P₁⁻¹P₂⁻¹P₁⁻¹ of
/// [`System::solve_iterative`], P_f = c_f I + K_f, in units of √(ωλ): the
/// values that minimise the condition number max/min over μ₁, μ₂ ∈ [0, λ]
/// of (ω + μ₁ + μ₂)/((c₁ + μ₁)²(c₂ + μ₂)) at ω = λ/1600 (the default
/// weight on a regular grid), found by a grid search.
const OUTER_SHIFT: f64 = 4.6;
/// See [`OUTER_SHIFT`].
const INNER_SHIFT: f64 = 1.22;

/// Iteration cap of the iterative solve; beyond it the solve falls back to
/// Cholesky.
const ITERATIVE_MAX_ITERATIONS: usize = 1_000;

/// The linear least-squares problem of one iteration: minimise
/// Σ_runs ‖A_r x‖² + ω‖x − p⁰‖² over the free points (fixed points enter A_r x
/// with their current positions), A_r the Eq. (32) row of run r.
pub(super) struct System<'a> {
    pub(super) runs: &'a [[u32; 4]],
    pub(super) coef: &'a [[f64; 4]],
    /// vertex → (run, slot) incidence, CSR
    pub(super) off: &'a [u32],
    pub(super) inc: &'a [(u32, u8)],
    /// vertex → unknown index (u32::MAX when fixed)
    pub(super) index: &'a [u32],
    pub(super) unknowns: &'a [usize],
    /// penalty weight ω_i of Eq. (34) per vertex (scaled by ē⁻²)
    pub(super) omega: &'a [f64],
    /// mean edge length of the input
    pub(super) ebar: f64,
    pub(super) p0: &'a [Vec3],
    pub(super) cur: &'a [Vec3],
}

impl System<'_> {
    /// Assembles ωI + AᵀA over the free points (lower triangle, by column,
    /// in parallel) and solves by sparse Cholesky with three right-hand
    /// sides; the symbolic analysis is reused while the free set is the same.
    pub(super) fn solve_direct(
        &self,
        solver: &mut Option<(Vec<usize>, CholeskySolver)>,
    ) -> Result<Vec<Vec3>, QuadFairError> {
        let (runs, coef, index, cur, omega) =
            (self.runs, self.coef, self.index, self.cur, self.omega);
        let cols: Vec<(Vec<(usize, f64)>, Vec3)> = self
            .unknowns
            .par_iter()
            .map(|&j| {
                let mut e: Vec<(usize, f64)> = Vec::with_capacity(32);
                let mut rhs = omega[j] * self.p0[j];
                e.push((index[j] as usize, omega[j]));
                for &(ri, s) in &self.inc[self.off[j] as usize..self.off[j + 1] as usize] {
                    let r = &runs[ri as usize];
                    let c = &coef[ri as usize];
                    let aj = c[s as usize];
                    for t in 0..4 {
                        let k = r[t] as usize;
                        if index[k] != u32::MAX {
                            if index[k] >= index[j] {
                                e.push((index[k] as usize, aj * c[t]));
                            }
                        } else {
                            rhs -= aj * c[t] * cur[k];
                        }
                    }
                }
                e.sort_unstable_by_key(|x| x.0);
                let mut merged: Vec<(usize, f64)> = Vec::with_capacity(e.len());
                for (r, v) in e {
                    match merged.last_mut() {
                        Some(last) if last.0 == r => last.1 += v,
                        _ => merged.push((r, v)),
                    }
                }
                (merged, rhs)
            })
            .collect();
        let m = self.unknowns.len();
        let mut col_ptr = Vec::with_capacity(m + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        let mut rhs = vec![vec![0.0; m]; 3];
        for (c, (entries, b)) in cols.iter().enumerate() {
            for &(r, v) in entries {
                row_idx.push(r);
                vals.push(v);
            }
            col_ptr.push(row_idx.len());
            rhs[0][c] = b.x;
            rhs[1][c] = b.y;
            rhs[2][c] = b.z;
        }
        let sym = faer::sparse::SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let a = faer::sparse::SparseColMat::new(sym, vals);
        let reuse = match solver.as_mut() {
            Some((u, s)) if u.as_slice() == self.unknowns => s.refactor(a.as_ref()).is_ok(),
            _ => false,
        };
        if !reuse {
            *solver = Some((self.unknowns.to_vec(), CholeskySolver::new(a.as_ref())?));
        }
        if let Some((_, s)) = solver.as_ref() {
            s.solve_columns(&mut rhs)?;
        }
        Ok((0..m)
            .map(|c| Vec3::new(rhs[0][c], rhs[1][c], rhs[2][c]))
            .collect())
    }

    /// Solves the same normal equations N d = c, N = ωI + AᵀA, iteratively
    /// for the displacement d from the current positions x (warm start
    /// d = 0; c = ω(p⁰ − x) − Aᵀ(A x), A x over all points of a run, so the
    /// stopping test does not depend on where the mesh sits in space).
    ///
    /// The structure lines are split into two families (lines that cross get
    /// different families where the mesh allows, see [`line_families`]),
    /// N = ωI + K₁ + K₂ with K_f the Eq. (32) terms of the runs of family f.
    /// Along one line K_f is banded (a run spans four consecutive points),
    /// so P_f = c_f I + K_f is factored line by line ([`line_blocks`], [`BandedBlocks`]). The
    /// alternating-direction product P₁P₂ ≈ N (Peaceman–Rachford) is not
    /// symmetric when K₁ and K₂ do not commute (short lines around fixed
    /// points, scattered free sets), and its symmetrised inverse need not be
    /// positive definite, so the preconditioner is the sandwich
    /// M⁻¹ = P₁⁻¹P₂⁻¹P₁⁻¹ (three banded solves), symmetric positive definite
    /// for any mesh, and the solver is conjugate gradients ([`pcg`]) on the
    /// stacked x, y, z coordinates (the three systems share N). On a regular
    /// grid, where K₁ and K₂ commute with eigenvalues in [0, λ] (λ ≈ 16/ē²:
    /// the Eq. (32) row is half the third difference), the shifts
    /// c₁ = [`OUTER_SHIFT`]·√(ωλ) and c₂ = [`INNER_SHIFT`]·√(ωλ) minimise
    /// the condition number of M⁻¹N: about 48 at the default weight instead
    /// of about 3,200 for N itself. N is applied matrix-free as ωv + Aᵀ(Av).
    ///
    /// Stopping rule: ‖c − N d‖ ≤ ω·ε·ē·√(3m) with ε = [`ITERATIVE_ACCURACY`]
    /// and m free points. Since N ⪰ ωI, ‖d − d*‖ ≤ ‖c − N d‖/ω, so the root
    /// mean square error of the displacements is at most ε·ē whatever the
    /// mesh's size, scale or position. `None` if the iteration does not
    /// reach it (the caller then factors N).
    pub(super) fn solve_iterative(
        &self,
        lines: &Lines<'_>,
    ) -> Result<Option<Vec<Vec3>>, QuadFairError> {
        let (runs, coef, index, cur, omega) =
            (self.runs, self.coef, self.index, self.cur, self.omega);
        let m = self.unknowns.len();
        let incident = |j: usize| &self.inc[self.off[j] as usize..self.off[j + 1] as usize];
        let residual: Vec<Vec3> = runs
            .par_iter()
            .zip(coef.par_iter())
            .with_min_len(4096)
            .map(|(r, c)| (0..4).map(|t| c[t] * cur[r[t] as usize]).sum())
            .collect();
        let mut rhs = vec![0.0; 3 * m];
        rhs.par_chunks_mut(3)
            .zip(self.unknowns.par_iter())
            .with_min_len(4096)
            .for_each(|(b, &j)| {
                let g: Vec3 = incident(j)
                    .iter()
                    .map(|&(ri, s)| coef[ri as usize][s as usize] * residual[ri as usize])
                    .sum();
                b.copy_from_slice(&(omega[j] * (self.p0[j] - cur[j]) - g).to_array());
            });
        drop(residual);
        // √(ωλ), λ ≈ half the mean Gershgorin bound of K₁ + K₂ over
        // the unknowns: Σ_j Σ_{runs ∋ j} |a_j| Σ_{free t} |a_t| = Σ_runs S²
        // with S = Σ_{free t} |a_t|
        let gersh: f64 = runs
            .par_iter()
            .zip(coef.par_iter())
            .with_min_len(4096)
            .map(|(r, c)| {
                let s: f64 = (0..4)
                    .filter(|&t| index[r[t] as usize] != u32::MAX)
                    .map(|t| c[t].abs())
                    .sum();
                s * s
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        // the smallest weight over the unknowns: N ⪰ ω_min I
        let omega_min = self
            .unknowns
            .iter()
            .map(|&j| omega[j])
            .fold(f64::INFINITY, f64::min);
        let scale = (2.0 * omega_min * gersh / m as f64 / 4.0)
            .sqrt()
            .max(omega_min);
        let (Some(p1), Some(p2)) = (
            line_blocks(self, lines, 0, OUTER_SHIFT * scale),
            line_blocks(self, lines, 1, INNER_SHIFT * scale),
        ) else {
            return Ok(None);
        };
        // per run the unknowns of its points (u32::MAX: fixed), and per
        // incidence of a vertex its coefficient, so that the product below
        // streams over arrays instead of looking them up
        let local: Vec<[u32; 4]> = runs
            .par_iter()
            .with_min_len(4096)
            .map(|r| r.map(|v| index[v as usize]))
            .collect();
        let inc_coef: Vec<f64> = self
            .inc
            .par_iter()
            .with_min_len(4096)
            .map(|&(ri, s)| coef[ri as usize][s as usize])
            .collect();
        let mut av = vec![Vec3::ZERO; runs.len()];
        // out = ωv + Aᵀ(Av) on interleaved x, y, z
        let apply = |v: &[f64], out: &mut [f64]| {
            av.par_iter_mut()
                .zip(local.par_iter().zip(coef.par_iter()))
                .with_min_len(4096)
                .for_each(|(o, (r, c))| {
                    let mut s = Vec3::ZERO;
                    for t in 0..4 {
                        if r[t] != u32::MAX {
                            let u = 3 * r[t] as usize;
                            s += c[t] * Vec3::new(v[u], v[u + 1], v[u + 2]);
                        }
                    }
                    *o = s;
                });
            let av: &Vec<Vec3> = &av;
            out.par_chunks_mut(3)
                .zip(v.par_chunks(3))
                .zip(self.unknowns.par_iter())
                .with_min_len(4096)
                .for_each(|((o, v), &j)| {
                    let (a, b) = (self.off[j] as usize, self.off[j + 1] as usize);
                    let mut g = Vec3::ZERO;
                    for (&(ri, _), &c) in self.inc[a..b].iter().zip(&inc_coef[a..b]) {
                        g += c * av[ri as usize];
                    }
                    o[0] = omega[j] * v[0] + g.x;
                    o[1] = omega[j] * v[1] + g.y;
                    o[2] = omega[j] * v[2] + g.z;
                });
        };
        // stop at ‖c − N d‖ ≤ ω_min·ε·ē·√(3m): since N ⪰ ω_min I, the error of d then
        // has a root mean square of at most ε·ē per coordinate
        let norm_c = rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        let tolerance = if norm_c > 0.0 {
            omega_min * ITERATIVE_ACCURACY * self.ebar * ((3 * m) as f64).sqrt() / norm_c
        } else {
            0.0
        };
        let mut d = vec![0.0; 3 * m];
        // z = M⁻¹ r = P₁⁻¹P₂⁻¹P₁⁻¹ r, P_f = c_f I + K_f
        let report = match sandwich_pcg(
            apply,
            &p1,
            &p2,
            &rhs,
            &mut d,
            tolerance,
            ITERATIVE_MAX_ITERATIONS,
        ) {
            Ok(r) => r,
            Err(SolveError::NonFinite) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        if !report.converged {
            return Ok(None);
        }
        Ok(Some(
            self.unknowns
                .iter()
                .enumerate()
                .map(|(i, &j)| cur[j] + Vec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]))
                .collect(),
        ))
    }
}

/// The structure lines with their runs and families.
pub(super) struct Lines<'a> {
    pub(super) lines: &'a [StructureLine],
    /// runs of line l: `line_runs[run_start[l]..run_start[l + 1]]`
    pub(super) run_start: &'a [usize],
    pub(super) line_runs: &'a [u32],
    /// family (0 or 1) of every line
    pub(super) family: &'a [u8],
}

/// c_f I + K_f of one family f, factored line by line
/// ([`BandedBlocks`]): every unknown belongs to the block of the first line
/// of family f through it (or to a block of its own), and the block of a
/// line holds the Eq. (32) terms of the runs of that line among the
/// unknowns it owns, in line order. A run spans four consecutive points, so
/// a block is a banded matrix of bandwidth 3 (dropping points keeps
/// neighbours within 3 places); a run that would break the band (wrapping
/// around a closed line, or meeting a point owned by another line twice) is
/// left out whole. Every block is then a shifted sum of positive
/// semi-definite run terms, hence positive definite. `None` if a block is
/// not numerically positive definite.
fn line_blocks(sys: &System<'_>, lines: &Lines<'_>, f: u8, shift: f64) -> Option<BandedBlocks> {
    let (index, m) = (sys.index, sys.unknowns.len());
    let mut placed = vec![false; m];
    let mut order: Vec<u32> = Vec::with_capacity(m);
    let mut block_start = vec![0usize];
    let mut block_line = Vec::new();
    for (li, l) in lines.lines.iter().enumerate() {
        if lines.family[li] != f {
            continue;
        }
        for v in &l.vertices {
            let u = index[v.idx()];
            if u != u32::MAX && !placed[u as usize] {
                placed[u as usize] = true;
                order.push(u);
            }
        }
        if order.len() > *block_start.last().unwrap_or(&0) {
            block_start.push(order.len());
            block_line.push(li as u32);
        }
    }
    for u in 0..m {
        if !placed[u] {
            placed[u] = true;
            order.push(u as u32);
            block_start.push(order.len());
            block_line.push(u32::MAX);
        }
    }
    // position of every unknown in `order`
    let mut place = vec![u32::MAX; m];
    for (i, &u) in order.iter().enumerate() {
        place[u as usize] = i as u32;
    }
    let starts = block_start.clone();
    BandedBlocks::new(order, block_start, shift, |b, band| {
        let (li, start) = (block_line[b], starts[b]);
        if li == u32::MAX {
            return;
        }
        let li = li as usize;
        for &ri in &lines.line_runs[lines.run_start[li]..lines.run_start[li + 1]] {
            let ri = ri as usize;
            let (r, c) = (&sys.runs[ri], &sys.coef[ri]);
            // local positions of the run's points in this block
            let mut at = [usize::MAX; 4];
            let mut fits = true;
            for t in 0..4 {
                let u = index[r[t] as usize];
                if u != u32::MAX {
                    let p = place[u as usize] as usize;
                    if p >= start && p < start + band.len() {
                        at[t] = p - start;
                    }
                }
            }
            for t in 0..4 {
                for w in 0..4 {
                    if at[t] != usize::MAX && at[w] != usize::MAX && at[t].abs_diff(at[w]) > 3 {
                        fits = false;
                    }
                }
            }
            if !fits {
                continue;
            }
            for t in 0..4 {
                for w in 0..4 {
                    if at[t] != usize::MAX && at[w] != usize::MAX && at[t] >= at[w] {
                        band[at[t]][at[t] - at[w]] += c[t] * c[w];
                    }
                }
            }
        }
    })
}

/// Splits the structure lines into two families: breadth-first over the
/// lines, a line gets the other family than the line it was reached from
/// through a shared point. On a grid-like mesh every crossing joins lines of
/// different families; where the line graph has odd cycles (around irregular
/// points) some crossings stay within one family, which only weakens the
/// preconditioner of [`System::solve_iterative`].
pub(super) fn line_families(lines: &[StructureLine], n: usize) -> Vec<u8> {
    let mut off = vec![0usize; n + 1];
    for l in lines {
        for v in &l.vertices {
            off[v.idx() + 1] += 1;
        }
    }
    for i in 0..n {
        off[i + 1] += off[i];
    }
    let mut through = vec![0u32; off[n]];
    let mut fill = off.clone();
    for (li, l) in lines.iter().enumerate() {
        for v in &l.vertices {
            through[fill[v.idx()]] = li as u32;
            fill[v.idx()] += 1;
        }
    }
    let mut family = vec![u8::MAX; lines.len()];
    let mut queue = std::collections::VecDeque::new();
    for start in 0..lines.len() {
        if family[start] != u8::MAX {
            continue;
        }
        family[start] = 0;
        queue.push_back(start);
        while let Some(l) = queue.pop_front() {
            for v in &lines[l].vertices {
                for &o in &through[off[v.idx()]..off[v.idx() + 1]] {
                    if family[o as usize] == u8::MAX {
                        family[o as usize] = 1 - family[l];
                        queue.push_back(o as usize);
                    }
                }
            }
        }
    }
    family
}
