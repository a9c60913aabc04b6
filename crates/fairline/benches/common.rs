//! Timing helpers shared by the benchmark binaries (harness = false): each
//! benchmark runs a closure several times and prints the median.

#![allow(dead_code)]

use std::time::Instant;

/// Median wall time in seconds of `runs` calls of `f` (after one warm-up).
pub fn median_secs<T>(runs: usize, mut f: impl FnMut() -> T) -> f64 {
    std::hint::black_box(f());
    let mut t: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let s = Instant::now();
            std::hint::black_box(f());
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(|a, b| a.total_cmp(b));
    t[t.len() / 2]
}

/// Number of runs from `FAIRLINE_BENCH_RUNS` (default `default`).
pub fn runs(default: usize) -> usize {
    std::env::var("FAIRLINE_BENCH_RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Sizes (vertex counts) from `FAIRLINE_BENCH_SIZES`, e.g. `10000,100000`.
pub fn sizes(default: &[usize]) -> Vec<usize> {
    std::env::var("FAIRLINE_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

/// A smooth, irregularly triangulated test surface with about `n` vertices:
/// a wavy height field whose vertices are jittered in the plane so that the
/// triangles are not all alike (closer to a scanned mesh than a clean grid).
pub fn test_surface(n: usize) -> fairline::SurfaceMesh {
    let side = (n as f64).sqrt().round().max(2.0) as u32;
    let mut m = fairline::shapes::height_field(side, side, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.25 * (3.0 * x).sin() * (2.0 * y).cos() + 0.1 * x * y
    });
    let h = 2.0 / (side - 1) as f64;
    let mut state = 0x9e3779b97f4a7c15u64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let boundary: Vec<bool> = m.vertices().map(|v| m.is_boundary_vertex(v)).collect();
    for (i, p) in m.positions_mut().iter_mut().enumerate() {
        if !boundary[i] {
            p.x += 0.3 * h * rnd();
            p.y += 0.3 * h * rnd();
            p.z = 0.25 * (3.0 * p.x).sin() * (2.0 * p.y).cos() + 0.1 * p.x * p.y;
        }
    }
    m
}

/// Prints one row of a Markdown table.
pub fn row(cells: &[String]) {
    println!("| {} |", cells.join(" | "));
}

/// CPU time (ns) used so far by all threads of this process (Linux
/// /proc/self/task/*/schedstat; 0 elsewhere). The machine is shared, so
/// wall times depend on the load; CPU time much less.
pub fn cpu_ns() -> u64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    dir.filter_map(|t| t.ok())
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Medians over `runs` calls of `f` (after one warm-up) of the wall time and
/// of the CPU time of all threads, both in seconds. On a loaded machine the
/// CPU time divided by the thread count estimates the idle-machine wall time.
pub fn median_wall_cpu<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, f64) {
    std::hint::black_box(f());
    let mut wall = Vec::new();
    let mut cpu = Vec::new();
    for _ in 0..runs.max(1) {
        let c0 = cpu_ns();
        let s = Instant::now();
        std::hint::black_box(f());
        wall.push(s.elapsed().as_secs_f64());
        cpu.push((cpu_ns().saturating_sub(c0)) as f64 * 1e-9);
    }
    wall.sort_by(|a, b| a.total_cmp(b));
    cpu.sort_by(|a, b| a.total_cmp(b));
    (wall[wall.len() / 2], cpu[cpu.len() / 2])
}
