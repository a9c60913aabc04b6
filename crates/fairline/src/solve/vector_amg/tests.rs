//! Tests of the block AMG preconditioner: the block operator against its
//! scalar expansion, the hierarchy, and CG iterations on elasticity-like systems.

use super::operator::{Blocks, Scalars, symmetric_mul};
use super::*;
use crate::solve::pcg;

/// K = A ⊗ I₃ + S on a side × side grid: A the 4-neighbour graph
/// Laplacian with a Dirichlet term on the left column (a_ii + 1), S a
/// reaction `strength` · n nᵀ per node with n turning with the column
/// (as the normal of a cylinder turns around it), so the motion along
/// n is held by S and the two other directions by A alone.
fn grid(side: usize, strength: f64) -> VectorOperator {
    let node = |x: usize, y: usize| (y * side + x) as u32;
    let rows = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let mut row = Vec::new();
            let mut degree = 0.0;
            for (dx, dy) in [(0i64, -1i64), (-1, 0), (1, 0), (0, 1)] {
                let (u, v) = (x as i64 + dx, y as i64 + dy);
                if u >= 0 && v >= 0 && (u as usize) < side && (v as usize) < side {
                    row.push((node(u as usize, v as usize), -1.0, [0.0; 6]));
                    degree += 1.0;
                }
            }
            if x == 0 {
                degree += 1.0;
            }
            let angle = std::f64::consts::TAU * x as f64 / side as f64;
            let n = [angle.cos(), angle.sin(), 0.0];
            let s = [
                strength * n[0] * n[0],
                strength * n[1] * n[1],
                0.0,
                strength * n[0] * n[1],
                0.0,
                0.0,
            ];
            row.push((i as u32, degree, s));
            row.sort_by_key(|e| e.0);
            row
        })
        .collect();
    VectorOperator::from_rows(rows).unwrap()
}

fn dense(k: &VectorOperator) -> Vec<Vec<f64>> {
    let n = 3 * k.nodes();
    let m = k.to_faer().unwrap();
    let mut d = vec![vec![0.0; n]; n];
    for j in 0..n {
        for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
            d[i][j] = v;
        }
    }
    d
}

/// K x equals the dense matrix `d` times x, entry by entry.
fn assert_product_is_dense(k: &VectorOperator, d: &[Vec<f64>], x: &[f64]) {
    let n = x.len();
    let mut y = vec![0.0; n];
    k.mul_vec(x, &mut y);
    for i in 0..n {
        let e: f64 = (0..n).map(|j| d[i][j] * x[j]).sum();
        assert!(
            (y[i] - e).abs() <= 1e-12 * (1.0 + e.abs()),
            "{i}: {} vs {e}",
            y[i]
        );
    }
}

fn vector(n: usize, seed: f64) -> Vec<f64> {
    (0..n).map(|i| (seed * (i as f64 + 1.0)).sin()).collect()
}

/// The structured product equals the assembled matrix; the Galerkin
/// operator of the structure equals (P ⊗ I₃)ᵀ K (P ⊗ I₃) formed densely,
/// including its off-diagonal blocks, and its product is again that
/// matrix.
#[test]
fn structure_matches_the_assembled_matrices() {
    let k = grid(6, 2.0);
    let n = 3 * k.nodes();
    let d = dense(&k);
    let x = vector(n, 0.37);
    assert_product_is_dense(&k, &d, &x);
    // a smoothed prolongator of the scalar part from aggregates
    let aggregates = aggregate_nodes(&k.strength_norms(), 0.08);
    let count = aggregates.iter().map(|&a| a as usize + 1).max().unwrap();
    assert!(count < k.nodes() / 2, "{count} aggregates");
    let (t, _) = tentative(&aggregates, count, 1, &vec![1.0; k.nodes()], 1);
    let a = k.scalar();
    let (inverse, omega, _) = block_jacobi(&a, 1);
    let p = smooth_prolongator(&t, &a.matmul(&t), &inverse, 1, omega);
    let kc = k.galerkin(&p, &p.transpose()).unwrap();
    assert!(matches!(kc.s, Blocks::Full(_)));
    let dc = dense(&kc);
    let nc = 3 * count;
    // P ⊗ I₃ densely
    let mut pp = vec![vec![0.0; nc]; n];
    for i in 0..k.nodes() {
        let (idx, val) = p.row(i);
        for (&j, &v) in idx.iter().zip(val) {
            for c in 0..3 {
                pp[3 * i + c][3 * j as usize + c] = v;
            }
        }
    }
    let scale = d.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for r in 0..nc {
        for c in 0..nc {
            let mut e = 0.0;
            for i in 0..n {
                if pp[i][r] == 0.0 {
                    continue;
                }
                for j in 0..n {
                    e += pp[i][r] * d[i][j] * pp[j][c];
                }
            }
            assert!(
                (dc[r][c] - e).abs() <= 1e-12 * scale,
                "({r}, {c}): {} vs {e}",
                dc[r][c]
            );
        }
    }
    let xc = vector(nc, 0.91);
    let mut yc = vec![0.0; nc];
    kc.mul_vec(&xc, &mut yc);
    for r in 0..nc {
        let e: f64 = (0..nc).map(|c| dc[r][c] * xc[c]).sum();
        assert!((yc[r] - e).abs() <= 1e-11 * scale * (1.0 + e.abs()));
    }
}

/// Both storages of A with a diagonal S (unit off-diagonal values, as
/// the finest H; stored values) multiply like the assembled matrix, and one smoothing step equals x + ω D⁻¹(b − K x)
/// formed densely.
#[test]
fn every_storage_multiplies_and_smooths_like_the_matrix() {
    let unit = grid(5, 1.5);
    assert!(matches!(unit.a, Scalars::UnitOffDiagonal { .. }));
    // the same operator with A doubled: stored values
    let rows: Vec<Vec<(u32, f64, SymmetricBlock)>> = (0..unit.nodes())
        .map(|i| {
            (unit.ptr[i]..unit.ptr[i + 1])
                .map(|e| {
                    let (a, k) = unit.entry(i, e);
                    let s = [k[0] - a, k[1] - a, k[2] - a, k[3], k[4], k[5]];
                    (unit.idx[e], 2.0 * a, s)
                })
                .collect()
        })
        .collect();
    let general = VectorOperator::from_rows(rows).unwrap();
    assert!(matches!(general.a, Scalars::Entries(_)));
    assert!(matches!(general.s, Blocks::Diagonal(_)));
    for k in [&unit, &general] {
        let n = 3 * k.nodes();
        let d = dense(k);
        let (x, b) = (vector(n, 0.43), vector(n, 1.1));
        assert_product_is_dense(k, &d, &x);
        let (inverses, omega) = vector_jacobi(k, block_jacobi(&k.scalar(), 1).2);
        let mut smoothed = vec![0.0; n];
        k.smooth(&inverses, omega, &b, &x, &mut smoothed);
        for node in 0..k.nodes() {
            let r: Vec<f64> = (0..3)
                .map(|c| {
                    let row = 3 * node + c;
                    b[row] - (0..n).map(|j| d[row][j] * x[j]).sum::<f64>()
                })
                .collect();
            let z = symmetric_mul(&inverses[node], &r);
            for c in 0..3 {
                let e = x[3 * node + c] + omega * z[c];
                let got = smoothed[3 * node + c];
                assert!((got - e).abs() <= 1e-12 * (1.0 + e.abs()), "{got} vs {e}");
            }
        }
    }
}

/// Largest eigenvalue of the symmetric dense matrix `m`.
fn largest_eigenvalue(m: &[Vec<f64>]) -> f64 {
    let n = m.len();
    let dense = faer::Mat::from_fn(n, n, |i, j| m[i][j]);
    let values = dense.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    values[n - 1]
}

/// What lets the finest level skip its own power iterations: with S
/// block-diagonal, ρ(D⁻¹K) ≤ ρ(D_A⁻¹A) (dense eigenvalues of the
/// symmetric forms D^{-1/2} K D^{-1/2}), equal when S vanishes (and
/// here also with S of rank one per node: the two directions it leaves
/// free carry the top eigenvector).
#[test]
fn diagonal_reaction_does_not_raise_the_jacobi_spectral_radius() {
    for strength in [0.0, 0.3, 5.0] {
        let k = grid(6, strength);
        assert!(matches!(k.s, Blocks::Diagonal(_)));
        let (a, d) = (k.scalar(), dense(&k));
        let n = k.nodes();
        // D_A^{-1/2} A D_A^{-1/2}
        let a_diagonal: Vec<f64> = (0..n)
            .map(|i| {
                let (idx, val) = a.row(i);
                idx.iter()
                    .zip(val)
                    .find(|e| *e.0 as usize == i)
                    .unwrap()
                    .1
                    .sqrt()
            })
            .collect();
        let scaled_a: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let mut row = vec![0.0; n];
                let (idx, val) = a.row(i);
                for (&j, &v) in idx.iter().zip(val) {
                    row[j as usize] = v / (a_diagonal[i] * a_diagonal[j as usize]);
                }
                row
            })
            .collect();
        // D^{-1/2} K D^{-1/2} with the 3 × 3 diagonal blocks of K
        let roots: Vec<glam::DMat3> = (0..n)
            .map(|i| {
                let b = k.diagonal_block(i);
                let m = glam::DMat3::from_cols_array(&b).transpose();
                crate::solve::symmetric_function3(m, |x| 1.0 / x.sqrt())
            })
            .collect();
        let scaled_k: Vec<Vec<f64>> = (0..3 * n)
            .map(|r| {
                (0..3 * n)
                    .map(|c| {
                        let (ri, ci) = (r / 3, c / 3);
                        let mut v = 0.0;
                        for p in 0..3 {
                            for q in 0..3 {
                                v += roots[ri].col(p)[r % 3]
                                    * d[3 * ri + p][3 * ci + q]
                                    * roots[ci].col(c % 3)[q];
                            }
                        }
                        v
                    })
                    .collect()
            })
            .collect();
        let (rho_a, rho_k) = (largest_eigenvalue(&scaled_a), largest_eigenvalue(&scaled_k));
        assert!(rho_a > 1.0, "{rho_a}");
        if strength == 0.0 {
            assert!((rho_k - rho_a).abs() <= 1e-12, "{rho_k} vs {rho_a}");
        } else {
            assert!(rho_k <= rho_a + 1e-12, "S = {strength}: {rho_k} > {rho_a}");
        }
    }
}

fn solve(k: &VectorOperator, preconditioner: Option<&VectorAmg>) -> (usize, Vec<f64>) {
    let n = 3 * k.nodes();
    let rhs = vector(n, 0.61);
    let mut x = vec![0.0; n];
    let inverses = vector_jacobi(k, block_jacobi(&k.scalar(), 1).2).0;
    let report = pcg(
        |v: &[f64], out: &mut [f64]| k.mul_vec(v, out),
        |r: &[f64], z: &mut [f64]| match preconditioner {
            Some(p) => p.apply(r, z),
            None => scale_by_inverses(&inverses, 1.0, r, z),
        },
        &rhs,
        &mut x,
        1e-10,
        20_000,
    )
    .unwrap();
    assert!(report.converged, "{report:?}");
    (report.iterations, x)
}

/// Preconditioned by the V-cycle, conjugate gradients need about as
/// many iterations on a 96 × 96 grid as on a 24 × 24 one and far fewer
/// than with block Jacobi, and reach the direct solution.
#[test]
fn multigrid_iterations_do_not_grow_with_the_grid() {
    let mut counts = Vec::new();
    for side in [24, 48, 96] {
        let k = grid(side, 4.0);
        let amg = VectorAmg::new(
            k.clone(),
            &vec![1.0; k.nodes()],
            &VectorAmgOptions {
                smoothing_steps: 2,
                max_coarse_nodes: 50,
                ..VectorAmgOptions::default()
            },
        )
        .unwrap();
        assert!(amg.sizes().len() >= 3, "{:?}", amg.sizes());
        let (iterations, x) = solve(&k, Some(&amg));
        counts.push(iterations);
        if side == 24 {
            let (jacobi, _) = solve(&k, None);
            assert!(
                5 * iterations <= jacobi,
                "multigrid {iterations}, Jacobi {jacobi}"
            );
            let mut exact = vector(3 * k.nodes(), 0.61);
            CholeskySolver::new(k.to_faer().unwrap().as_ref())
                .unwrap()
                .solve_in_place(&mut exact)
                .unwrap();
            let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let diff = x
                .iter()
                .zip(&exact)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-7 * scale, "difference {diff}, scale {scale}");
        }
    }
    println!("vector multigrid iterations on 24², 48², 96² grids: {counts:?}");
    assert!(counts[2] <= counts[0] + counts[0] / 2 + 2, "{counts:?}");
}

/// The V-cycle is a symmetric positive-definite operator (conjugate
/// gradients need both).
#[test]
fn v_cycle_is_symmetric_positive_definite() {
    let k = grid(20, 3.0);
    let amg = VectorAmg::new(
        k.clone(),
        &vec![1.0; k.nodes()],
        &VectorAmgOptions {
            max_coarse_nodes: 30,
            ..VectorAmgOptions::default()
        },
    )
    .unwrap();
    let n = 3 * k.nodes();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (x, y) = (vector(n, 0.61), vector(n, 1.37));
    let (mut px, mut py) = (vec![0.0; n], vec![0.0; n]);
    amg.apply(&x, &mut px);
    amg.apply(&y, &mut py);
    let (a, b) = (dot(&y, &px), dot(&x, &py));
    assert!((a - b).abs() <= 1e-10 * a.abs().max(b.abs()), "{a} vs {b}");
    for seed in [0.61, 1.37, 2.9, 0.05] {
        let v = vector(n, seed);
        let mut pv = vec![0.0; n];
        amg.apply(&v, &mut pv);
        assert!(dot(&v, &pv) > 0.0);
    }
}

/// The cycle with smoothing before each coarse correction only and
/// the one with smoothing after it only are each other's transposes
/// (for 1 to 4 steps, an odd and an even count, over three levels),
/// neither is symmetric by itself, and their product Vᵀ V is positive
/// definite.
#[test]
fn one_sided_cycles_are_transposes() {
    let k = grid(20, 3.0);
    let n = 3 * k.nodes();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (x, y) = (vector(n, 0.61), vector(n, 1.37));
    for steps in 1..=4 {
        let amg = VectorAmg::new(
            k.clone(),
            &vec![1.0; k.nodes()],
            &VectorAmgOptions {
                smoothing_steps: steps,
                max_coarse_nodes: 30,
                ..VectorAmgOptions::default()
            },
        )
        .unwrap();
        assert!(amg.sizes().len() >= 3, "{:?}", amg.sizes());
        let mut v = vec![0.0; n];
        let mut w = vec![0.0; n];
        // ⟨y, V x⟩ = ⟨Vᵀ y, x⟩
        amg.apply_pre(&x, &mut v);
        amg.apply_post(&y, &mut w);
        let (a, b) = (dot(&y, &v), dot(&w, &x));
        assert!(
            (a - b).abs() <= 1e-10 * a.abs().max(b.abs()),
            "{steps}: {a} vs {b}"
        );
        // V alone is not symmetric: ⟨y, V x⟩ ≠ ⟨V y, x⟩
        let mut vy = vec![0.0; n];
        amg.apply_pre(&y, &mut vy);
        let c = dot(&vy, &x);
        assert!((a - c).abs() > 1e-6 * a.abs(), "{steps}: {a} vs {c}");
        // Vᵀ V x then ⟨x, Vᵀ V x⟩ = ‖V x‖² > 0
        let mut vtv = vec![0.0; n];
        amg.apply_post(&v, &mut vtv);
        let q = dot(&x, &vtv);
        assert!((q - dot(&v, &v)).abs() <= 1e-10 * q, "{steps}: {q}");
    }
}

/// Malformed operators are refused with an error, not a panic.
#[test]
fn malformed_operators_are_refused() {
    let block = [0.0; 6];
    // missing diagonal
    assert!(
        VectorOperator::from_rows(vec![vec![(1, -1.0, block)], vec![(1, 1.0, block)]]).is_err()
    );
    // column out of range, unsorted
    assert!(VectorOperator::from_rows(vec![vec![(0, 1.0, block), (5, -1.0, block)]]).is_err());
    assert!(
        VectorOperator::from_rows(vec![
            vec![(1, -1.0, block), (0, 2.0, block)],
            vec![(0, -1.0, block), (1, 2.0, block)]
        ])
        .is_err()
    );
    assert!(
        VectorOperator::with_diagonal_blocks(vec![0, 1], vec![0], vec![1.0, 2.0], vec![block])
            .is_err()
    );
    assert!(
        VectorOperator::with_diagonal_blocks(vec![0, 1], vec![1], vec![1.0], vec![block]).is_err()
    );
    let k = grid(4, 1.0);
    assert!(VectorAmg::new(k, &[1.0; 3], &VectorAmgOptions::default()).is_err());
}
