//! Smoothing and structure-line fairing timings (issue 5 targets on this
//! 2-core machine): Taubin, uniform weights, 10 iterations (20 steps) on a
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
                let mut m = mesh.clone();
                taubin_smooth(&mut m, &TaubinOptions::default()).expect("taubin")
            });
            println!(
                "{:>10} {:>28} {:>10.3}",
                mesh.vertex_count(),
                "taubin 10 it (20 steps)",
                t
            );
        }
        if wanted("implicit") {
            let mut cpu = Vec::new();
            let t = common::median_secs(runs, || {
                let mut m = mesh.clone();
                let c0 = common::cpu_ns();
                let r = implicit_smooth(&mut m, &ImplicitOptions::default()).expect("implicit");
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
    // the options that were the default before session 17 (the thesis'
    // penalty alone, deviation halved)
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
