//! Vertex-flow feature enhancement (Ji et al. 2011) on tori (R = 1,
//! r = 0.4, n_major = 4 n_minor) of about 10k and 100k vertices: median wall
//! time of `enhance_features` (curvature, assembly, factorisation, solve and
//! flip repair: the whole computation of `fairline enhance` without file
//! input/output), the CPU time per run (all threads; the machine is shared,
//! so wall times depend on the load) and the phases of the median run with
//! the share of the sparse Cholesky factorisation. Prints a Markdown table.
//!
//! Run: `cargo bench -p fairline --bench enhance`
//! (`FAIRLINE_BENCH_RUNS`, default 3, and `FAIRLINE_BENCH_SIZES`, default
//! `10000,100000`, override runs and sizes). One million vertices does not
//! fit a 24 GiB machine: the Cholesky factor of its 3M × 3M normal matrix
//! (3 × 3 blocks over the 2-ring of each vertex) has 3.2 · 10⁹ nonzeros
//! (26 GB) after the AMD ordering; see BENCHMARKS.md.

mod common;

use common::{cpu_ns, row, runs, sizes};
use fairline::enhance::{EnhanceOptions, enhance_features};
use fairline::shapes::torus;
use std::time::Instant;

fn main() {
    let runs = runs(3).max(1);
    let options = EnhanceOptions::default();
    row(&[
        "vertices",
        "median wall s",
        "CPU s per run",
        "curvature s",
        "assembly s",
        "factorisation s",
        "solve s",
        "repair s",
        "factorisation share",
    ]
    .map(String::from));
    row(&["---"; 9].map(String::from));
    for n in sizes(&[10_000, 100_000]) {
        let n_minor = ((n as f64 / 4.0).sqrt().round() as u32).max(3);
        let n_major = ((n as f64 / n_minor as f64).round() as u32).max(3);
        let mesh = torus(1.0, 0.4, n_major, n_minor);
        let c0 = cpu_ns();
        let mut results = Vec::new();
        for _ in 0..runs {
            let t = Instant::now();
            let r = enhance_features(&mesh, &options).expect("enhance");
            results.push((t.elapsed().as_secs_f64(), r.report.timings));
        }
        let cpu = (cpu_ns() - c0) as f64 * 1e-9 / runs as f64;
        results.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (median, t) = &results[results.len() / 2];
        let f = |x: f64| format!("{x:.3}");
        row(&[
            mesh.vertex_count().to_string(),
            f(*median),
            f(cpu),
            f(t.curvature_s),
            f(t.assembly_s),
            f(t.factorisation_s),
            f(t.solve_s),
            f(t.repair_s),
            format!("{:.0} %", 100.0 * t.factorisation_s / t.total_s.max(1e-12)),
        ]);
    }
}
