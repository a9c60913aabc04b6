//! Vertex-flow feature enhancement (Ji et al. 2011) on tori of about 10k,
//! 100k and 1M vertices: median wall time of `enhance_features` (curvature
//! included) and the share of time spent in the sparse Cholesky
//! factorisation. `cargo bench -p fairline --bench enhance [-- SIZES]`, e.g.
//! `-- 10k 100k 1m` (default: 10k 100k; the 1M run needs tens of GB for the
//! Cholesky factor, see the report).

use fairline::enhance::{EnhanceOptions, enhance_features};
use fairline::shapes::torus;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let sizes: Vec<String> = if args.is_empty() {
        vec!["10k".into(), "100k".into()]
    } else {
        args
    };
    println!(
        "{:>9} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>7}",
        "vertices", "median_s", "curv_s", "assem_s", "factor_s", "solve_s", "repair_s", "factor%"
    );
    for s in sizes {
        let (nu, nv, reps) = match s.to_lowercase().as_str() {
            "10k" => (200, 50, 7),
            "100k" => (632, 158, 5),
            "1m" => (2000, 500, 3),
            other => {
                eprintln!("unknown size {other} (use 10k, 100k, 1m)");
                continue;
            }
        };
        let mesh = torus(1.0, 0.4, nu, nv);
        let options = EnhanceOptions::default();
        let mut runs = Vec::new();
        for _ in 0..reps {
            let t = Instant::now();
            let r = enhance_features(&mesh, &options).expect("enhance");
            runs.push((t.elapsed().as_secs_f64(), r.report.timings));
        }
        runs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (median, t) = &runs[runs.len() / 2];
        println!(
            "{:>9} {:>10.3} {:>10.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>6.1}%",
            mesh.vertex_count(),
            median,
            t.curvature_s,
            t.assembly_s,
            t.factorisation_s,
            t.solve_s,
            t.repair_s,
            100.0 * t.factorisation_s / median.max(1e-12)
        );
    }
}
