//! Smoothing and structure-line fairing timings (with their speed targets
//! on a 2-core machine): Taubin, uniform weights, 10 iterations (20 steps) on a
//! 450k-vertex triangle mesh (target ≤ 0.15 s); one implicit step on the same
//! mesh (≤ 1.5 s); structure-line fairing of a 1M-vertex zigzag quad grid
//! (≤ 10 s). `cargo bench -p fairline --bench smooth`; sizes via
//! `FAIRLINE_BENCH_SIZES=450000`, runs via `FAIRLINE_BENCH_RUNS`, tasks via
//! `FAIRLINE_BENCH_TASKS` (comma-separated: taubin, implicit, fair; default
//! all). The implicit step also reports the median CPU time of all threads
//! (the machine is shared, so wall times depend on the load).

mod common;

use fairline::Vec3;
use fairline::fair::{QuadFairOptions, fair_structure_lines};
use fairline::smooth::{ImplicitOptions, TaubinOptions, implicit_smooth, taubin_smooth};

/// One default implicit step (nothing fixed) assembled directly, without
/// the constrained solve: the lower pattern straight from the one-rings,
/// values filled per column, nested-dissection ordering from the
/// positions, sequential LLᵀ. Here only to compare the two in one process
/// (task `implicit-ab`).
fn direct_implicit_step(mesh: &fairline::SurfaceMesh) -> Vec<Vec3> {
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
    use fairline::geom::{self, LaplaceWeights};
    use fairline::solve::{CholeskyOptions, CholeskyOrdering, CholeskySolver, nested_dissection};
    let n = mesh.vertex_count();
    let p = mesh.positions();
    let e = geom::mean_edge_length(mesh);
    let t = e * e;
    let mut col_ptr = vec![0usize];
    let mut row_idx = Vec::new();
    for v in mesh.vertices() {
        row_idx.push(v.idx());
        let start = row_idx.len();
        row_idx.extend(
            mesh.outgoing(v)
                .map(|h| mesh.to_vertex(h).idx())
                .filter(|&r| r > v.idx()),
        );
        row_idx[start..].sort_unstable();
        col_ptr.push(row_idx.len());
    }
    let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    let order = nested_dissection(pattern.as_ref(), p).expect("ordering");
    let opts = CholeskyOptions::default()
        .ordering(CholeskyOrdering::Custom(order))
        .parallel(false);
    let mut solver = CholeskySolver::analyse(pattern.as_ref(), &opts).expect("analyse");
    let hw = geom::halfedge_weights(mesh, LaplaceWeights::Cotangent);
    let mass = geom::mixed_vertex_areas(mesh);
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let mut values = vec![0.0; ri.len()];
    let mut rhs = Vec::with_capacity(n);
    for v in mesh.vertices() {
        let c = v.idx();
        let mut diag = mass[c];
        for h in mesh.outgoing(v) {
            let w = hw[h.idx()];
            diag += t * w;
            let r = mesh.to_vertex(h).idx();
            if r > c
                && let Ok(k) = ri[cp[c] + 1..cp[c + 1]].binary_search(&r)
            {
                values[cp[c] + 1 + k] -= t * w;
            }
        }
        values[cp[c]] = diag;
        rhs.push(mass[c] * p[c]);
    }
    solver
        .refactor(SparseColMatRef::new(pattern.as_ref(), &values))
        .expect("factor");
    solver.solve_points(&mut rhs).expect("solve");
    rhs
}

/// Whether `task` is selected by `FAIRLINE_BENCH_TASKS` (all by default).
fn wanted(task: &str) -> bool {
    std::env::var("FAIRLINE_BENCH_TASKS")
        .map(|s| s.split(',').any(|t| t.trim() == task))
        .unwrap_or(true)
}

fn main() {
    let runs = common::runs(3);
    println!("{:>10} {:>28} {:>10}", "vertices", "task", "median_s");
    for n in common::sizes(&[450_000]) {
        let mesh = common::test_surface(n);
        if wanted("taubin") {
            let t = common::median_secs(runs, || {
                taubin_smooth(&mesh, &TaubinOptions::default()).expect("taubin")
            });
            println!(
                "{:>10} {:>28} {:>10.3}",
                mesh.vertex_count(),
                "taubin 10 it (20 steps)",
                t
            );
        }
        if wanted("implicit-ab") {
            // the one constrained solve against the direct assembly, runs
            // interleaved so that both see the same load
            let o = ImplicitOptions::default();
            let (mut new, mut old) = (Vec::new(), Vec::new());
            let mut diff = 0.0f64;
            for _ in 0..runs {
                let t = std::time::Instant::now();
                let a = implicit_smooth(&mesh, &o).expect("implicit");
                new.push(t.elapsed().as_secs_f64());
                let t = std::time::Instant::now();
                let b = direct_implicit_step(&mesh);
                old.push(t.elapsed().as_secs_f64());
                for (p, q) in a.positions.iter().zip(&b) {
                    diff = diff.max(p.distance(*q));
                }
            }
            new.sort_by(|a, b| a.total_cmp(b));
            old.sort_by(|a, b| a.total_cmp(b));
            println!(
                "{:>10} {:>28} {:>10.3}   (direct assembly {:.3} s, max difference {:.2e} = {:.2e} mean edges)",
                mesh.vertex_count(),
                "implicit 1 step (one solve)",
                new[new.len() / 2],
                old[old.len() / 2],
                diff,
                diff / fairline::geom::mean_edge_length(&mesh)
            );
        }
        if wanted("implicit") {
            let mut cpu = Vec::new();
            let t = common::median_secs(runs, || {
                let c0 = common::cpu_ns();
                let r = implicit_smooth(&mesh, &ImplicitOptions::default()).expect("implicit");
                cpu.push((common::cpu_ns() - c0) as f64 * 1e-9);
                r
            });
            cpu.sort_by(|a, b| a.total_cmp(b));
            println!(
                "{:>10} {:>28} {:>10.3}   (cpu median {:.3} s)",
                mesh.vertex_count(),
                "implicit 1 step",
                t,
                cpu[cpu.len() / 2]
            );
        }
    }
    if !wanted("fair") {
        return;
    }
    // 1M-vertex quad grid with a planted zigzag
    let side = 1000u32;
    let mut quads = fairline::shapes::quad_grid(side, side, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.3 * (x * x - y * y)
    });
    let h = 2.0 / (side - 1) as f64;
    for (k, p) in quads.positions_mut().iter_mut().enumerate() {
        let (i, j) = (k as u32 % side, k as u32 / side);
        if i > 0 && j > 0 && i < side - 1 && j < side - 1 {
            let x = p.x + if j % 2 == 0 { 0.2 * h } else { -0.2 * h };
            *p = Vec3::new(x, p.y, 0.3 * (x * x - p.y * p.y));
        }
    }
    // the default (points on the input surface, deviation factor 0.1) and
    // the thesis' method as printed (its penalty alone, off the surface,
    // deviation halved)
    let before = QuadFairOptions::default()
        .on_surface(false)
        .deviation_factor(0.5);
    for (label, opts) in [
        ("structure-line fairing", QuadFairOptions::default()),
        ("  (off surface, factor 0.5)", before),
    ] {
        let t = common::median_secs(runs.min(2), || {
            fair_structure_lines(&quads, &opts).expect("fair")
        });
        println!("{:>10} {:>28} {:>10.3}", quads.vertex_count(), label, t);
    }
}
