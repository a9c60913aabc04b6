//! Vertex-flow feature enhancement (Ji et al. 2011) on tori (R = 1,
//! r = 0.4, n_major = 4 n_minor) and rounded cubes (radius 0.3, large flat
//! faces: the hard case of the iterative solvers) of about 10k and 100k
//! vertices: median wall
//! time of `enhance_features` (curvature, assembly, factorisation, solve and
//! flip repair: the whole computation of `fairline enhance` without file
//! input/output), the CPU time per run (all threads; the machine is shared,
//! so wall times depend on the load) and the phases of the median run with
//! the share of the linear solve (factorisation and triangular solves, or
//! conjugate gradients). Prints a Markdown table.
//!
//! Runs on a worker thread of rayon's pool, as the command does.
//!
//! Run: `cargo bench -p fairline --bench enhance`
//! (`FAIRLINE_BENCH_RUNS`, default 3, `FAIRLINE_BENCH_SIZES`, default
//! `10000,100000`, `FAIRLINE_BENCH_SOLVER`, `auto` (default), `cg`, `amg`
//! or `direct`, and `FAIRLINE_BENCH_SHAPES`, default `torus,cube`, override
//! runs, sizes, solver and shapes). One million vertices takes
//! about 3.3 GB with conjugate gradients; the direct solver does not fit a
//! 24 GiB machine there (the Cholesky factor of its 3M × 3M normal matrix
//! has 3.2 · 10⁹ nonzeros, 26 GB); see BENCHMARKS.md.

mod common;

use common::{cpu_ns, row, runs, sizes};
use fairline::enhance::{EnhanceOptions, EnhanceSolver, enhance_features};
use fairline::shapes::{rounded_cube, torus};
use std::time::Instant;

fn main() {
    // on a worker of rayon's pool, as `fairline` runs its commands
    rayon::scope(|_| bench());
}

fn bench() {
    let runs = runs(3).max(1);
    let solver = match std::env::var("FAIRLINE_BENCH_SOLVER").as_deref() {
        Ok("direct") => EnhanceSolver::Direct,
        Ok("cg") => EnhanceSolver::Cg,
        Ok("amg") => EnhanceSolver::Amg,
        _ => EnhanceSolver::Auto,
    };
    let shapes = std::env::var("FAIRLINE_BENCH_SHAPES").unwrap_or_else(|_| "torus,cube".into());
    let options = EnhanceOptions::default().solver(solver);
    row(&[
        "shape",
        "vertices",
        "solver",
        "median wall s",
        "CPU s per run",
        "curvature s",
        "assembly s",
        "factorisation s",
        "solve s (CG iterations)",
        "repair s",
        "other s",
        "solve share",
    ]
    .map(String::from));
    row(&["---"; 12].map(String::from));
    for (shape, n) in shapes
        .split(',')
        .flat_map(|s| sizes(&[10_000, 100_000]).into_iter().map(move |n| (s, n)))
    {
        let mesh = if shape == "cube" {
            rounded_cube(((n as f64 / 6.0).sqrt().round() as u32).max(2), 0.3)
        } else {
            let n_minor = ((n as f64 / 4.0).sqrt().round() as u32).max(3);
            let n_major = ((n as f64 / n_minor as f64).round() as u32).max(3);
            torus(1.0, 0.4, n_major, n_minor)
        };
        let c0 = cpu_ns();
        let mut results = Vec::new();
        for _ in 0..runs {
            let t = Instant::now();
            let r = enhance_features(&mesh, &options).expect("enhance");
            results.push((
                t.elapsed().as_secs_f64(),
                r.report.timings,
                r.report.cg_iterations,
            ));
        }
        let cpu = (cpu_ns() - c0) as f64 * 1e-9 / runs as f64;
        results.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (median, t, iterations) = &results[results.len() / 2];
        let f = |x: f64| format!("{x:.3}");
        row(&[
            shape.to_string(),
            mesh.vertex_count().to_string(),
            format!("{solver:?}").to_lowercase(),
            f(*median),
            f(cpu),
            f(t.curvature_s),
            f(t.assembly_s),
            f(t.factorisation_s),
            if *iterations > 0 {
                format!("{} ({iterations})", f(t.solve_s))
            } else {
                f(t.solve_s)
            },
            f(t.repair_s),
            f(t.total_s
                - t.curvature_s
                - t.assembly_s
                - t.factorisation_s
                - t.solve_s
                - t.repair_s),
            format!(
                "{:.0} %",
                100.0 * (t.factorisation_s + t.solve_s) / t.total_s.max(1e-12)
            ),
        ]);
    }
}
