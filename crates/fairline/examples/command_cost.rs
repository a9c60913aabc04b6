//! Inputs and in-process timings for the whole-command cost measurements of
//! BENCHMARKS.md.
//!
//! `cargo run --release -p fairline --example command_cost -- write DIR 450000,1000000`
//! writes `DIR/surface-N.ply` (binary PLY, the jittered wavy height field of
//! the benchmarks); `... -- time FILE [RUNS]` prints the median wall and
//! CPU seconds of the library steps a light command consists of: reading, building the
//! halfedge mesh, `inspect`, writing PLY/OBJ and curvature (the smoothing
//! commands report their own computation time in `--report`'s `time_s`).
//! Compare with the whole command (`scripts/command-cost`).
//! `... -- split-scan IN OUT N` writes the real scan IN split 4 × 4 twice
//! and cut to about N vertices (as the highlight benchmarks make it) to OUT
//! (binary PLY): a real scan at a production size.

#[path = "../benches/common.rs"]
mod common;

use std::time::Instant;

/// Median wall and CPU seconds (all threads) of `runs` calls, no warm-up
/// (a command runs once, cold).
fn median<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, f64) {
    let mut wall = Vec::new();
    let mut cpu = Vec::new();
    for _ in 0..runs.max(1) {
        let c0 = common::cpu_ns();
        let s = Instant::now();
        std::hint::black_box(f());
        wall.push(s.elapsed().as_secs_f64());
        cpu.push(common::cpu_ns().saturating_sub(c0) as f64 * 1e-9);
    }
    wall.sort_by(|a, b| a.total_cmp(b));
    cpu.sort_by(|a, b| a.total_cmp(b));
    (wall[wall.len() / 2], cpu[cpu.len() / 2])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("write") if args.len() == 3 => {
            let dir = std::path::Path::new(&args[1]);
            std::fs::create_dir_all(dir)?;
            for n in args[2].split(',').filter_map(|s| s.trim().parse().ok()) {
                let mesh = common::test_surface(n);
                let path = dir.join(format!("surface-{n}.ply"));
                fairline::io::write_mesh(&path, &mesh)?;
                println!(
                    "{}: {} vertices, {} faces",
                    path.display(),
                    mesh.vertex_count(),
                    mesh.face_count()
                );
            }
        }
        Some("time") if args.len() >= 2 => {
            let path = &args[1];
            let runs: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
            let soup = fairline::io::read_soup(path)?;
            let mesh = fairline::SurfaceMesh::from_soup(&soup)?;
            let dir = std::env::temp_dir().join(format!("command-cost-{}", std::process::id()));
            std::fs::create_dir_all(&dir)?;
            let rows: Vec<(&str, (f64, f64))> = vec![
                ("read_soup", median(runs, || fairline::io::read_soup(path))),
                ("read_mesh", median(runs, || fairline::io::read_mesh(path))),
                (
                    "SurfaceMesh::from_soup",
                    median(runs, || fairline::SurfaceMesh::from_soup(&soup)),
                ),
                (
                    "mesh::inspect",
                    median(runs, || fairline::mesh::inspect(&soup)),
                ),
                (
                    "write PLY",
                    median(runs, || {
                        fairline::io::write_mesh(dir.join("out.ply"), &mesh)
                    }),
                ),
                (
                    "write OBJ",
                    median(runs, || {
                        fairline::io::write_mesh(dir.join("out.obj"), &mesh)
                    }),
                ),
                (
                    "curvature (Rusinkiewicz)",
                    median(runs, || {
                        fairline::geom::principal_curvatures(
                            &mesh,
                            fairline::geom::CurvatureMethod::Rusinkiewicz,
                        )
                    }),
                ),
            ];
            let _ = std::fs::remove_dir_all(&dir);
            println!(
                "{path}: {} vertices, {} faces; median of {runs} runs",
                mesh.vertex_count(),
                mesh.face_count()
            );
            println!("| step | wall s | CPU s |\n| --- | --- | --- |");
            for (name, (wall, cpu)) in rows {
                println!("| {name} | {wall:.4} | {cpu:.4} |");
            }
        }
        Some("split-scan") if args.len() == 4 => {
            let scan = fairline::io::read_mesh(&args[1])?;
            let target: usize = args[3].parse()?;
            let mesh = common::cut_to(&common::split4(&scan, 2), target);
            fairline::io::write_mesh(&args[2], &mesh)?;
            println!(
                "{}: {} vertices, {} faces",
                args[2],
                mesh.vertex_count(),
                mesh.face_count()
            );
        }
        _ => {
            eprintln!(
                "usage: command_cost write DIR N[,N..] | command_cost time FILE [RUNS] | command_cost split-scan IN OUT N"
            );
            std::process::exit(2);
        }
    }
    Ok(())
}
