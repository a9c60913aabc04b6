//! Timing helpers shared by the benchmark binaries (harness = false): each
//! benchmark runs a closure several times and prints the median.

#![allow(dead_code)]

use fairline::SurfaceMesh;
use fairline::mesh::bounding_box;
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

/// Each triangle split into four at its edge midpoints (a shared midpoint
/// per edge), `times` times: a real scan at a larger vertex count, with
/// the scan's own shape and irregular sampling.
pub fn split4(mesh: &SurfaceMesh, times: u32) -> SurfaceMesh {
    let mut m = mesh.clone();
    for _ in 0..times {
        let mut pos = m.positions().to_vec();
        let mut mid = std::collections::HashMap::new();
        let mut faces: Vec<[u32; 3]> = Vec::with_capacity(4 * m.face_count());
        for f in m.faces() {
            let t = m.triangle(f).map(|v| v.0);
            let mut e = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                e[k] = *mid.entry(key).or_insert_with(|| {
                    pos.push(0.5 * (pos[a as usize] + pos[b as usize]));
                    (pos.len() - 1) as u32
                });
            }
            faces.push([t[0], e[0], e[2]]);
            faces.push([t[1], e[1], e[0]]);
            faces.push([t[2], e[2], e[1]]);
            faces.push([e[0], e[1], e[2]]);
        }
        m = SurfaceMesh::new(pos, &faces).expect("split mesh");
    }
    m
}

/// The part of `mesh` below a plane across its longest bounding-box axis,
/// placed so that about `target` vertices remain: a real scan cut to a
/// given size, with the scan's own vertex and face order (kept vertices
/// and faces in their input order).
pub fn cut_to(mesh: &SurfaceMesh, target: usize) -> SurfaceMesh {
    let p = mesh.positions();
    let (lo, hi) = bounding_box(p).expect("vertices");
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mut coord: Vec<f64> = p.iter().map(|q| q[axis]).collect();
    let k = target.min(coord.len() - 1);
    let (_, &mut cut, _) = coord.select_nth_unstable_by(k, f64::total_cmp);
    let keep: Vec<bool> = p.iter().map(|q| q[axis] < cut).collect();
    let mut id = vec![u32::MAX; p.len()];
    let mut pos = Vec::new();
    for (i, q) in p.iter().enumerate() {
        if keep[i] {
            id[i] = pos.len() as u32;
            pos.push(*q);
        }
    }
    let faces: Vec<[u32; 3]> = mesh
        .faces()
        .map(|f| mesh.triangle(f).map(|v| v.0))
        .filter(|t| t.iter().all(|&v| keep[v as usize]))
        .map(|t| t.map(|v| id[v as usize]))
        .collect();
    // vertices of no kept face would be isolated: drop them too
    let mut used = vec![false; pos.len()];
    for t in &faces {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut id2 = vec![u32::MAX; pos.len()];
    let mut pos2 = Vec::new();
    for (i, q) in pos.iter().enumerate() {
        if used[i] {
            id2[i] = pos2.len() as u32;
            pos2.push(*q);
        }
    }
    let faces: Vec<[u32; 3]> = faces.iter().map(|t| t.map(|v| id2[v as usize])).collect();
    SurfaceMesh::new(pos2, &faces).expect("cut mesh")
}
