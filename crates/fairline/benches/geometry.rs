//! Foundation benchmarks: reading a binary PLY, normals, cotangent
//! Laplacian, mixed Voronoi areas and principal curvatures, on meshes of
//! about 10k, 100k, 450k and 1M vertices. Prints a Markdown table of medians.
//!
//! `cargo bench -p fairline --bench geometry`
//! (`FAIRLINE_BENCH_SIZES=10000,100000` and `FAIRLINE_BENCH_RUNS=5` adjust it).

mod common;

use common::{median_wall_cpu, row, runs, sizes, test_surface};
use fairline::geom;

/// "wall (cpu)" of a median pair.
fn cell((wall, cpu): (f64, f64)) -> String {
    format!("{wall:.4} ({cpu:.4})")
}

fn main() {
    let runs = runs(7);
    println!(
        "threads: {}, runs per cell: {runs}; each cell: median wall seconds (median CPU seconds of all threads)\n",
        rayon::current_num_threads()
    );
    row(&[
        "vertices".into(),
        "faces".into(),
        "read binary PLY".into(),
        "PLY MB".into(),
        "build halfedges".into(),
        "vertex normals".into(),
        "cotangent Laplacian".into(),
        "mixed areas".into(),
        "principal curvatures".into(),
    ]);
    row(&vec!["---".to_string(); 9]);
    let dir = std::env::temp_dir().join(format!("fairline-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for n in sizes(&[10_000, 100_000, 450_000, 1_000_000]) {
        let mesh = test_surface(n);
        let soup = mesh.to_soup();
        let path = dir.join(format!("surface-{n}.ply"));
        fairline::io::write_ply_with_vertex_properties(&path, &soup, &[]).expect("write ply");
        let mb = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0) as f64 / 1e6;
        let t_read = median_wall_cpu(runs, || fairline::io::read_soup(&path).expect("read"));
        let t_build = median_wall_cpu(runs, || {
            fairline::SurfaceMesh::from_soup(&soup).expect("mesh")
        });
        let t_normals = median_wall_cpu(runs, || geom::vertex_normals(&mesh));
        let t_cot = median_wall_cpu(runs, || geom::cotangent_laplacian(&mesh));
        let t_areas = median_wall_cpu(runs, || geom::mixed_vertex_areas(&mesh));
        let t_curv = median_wall_cpu(runs, || geom::principal_curvatures_rusinkiewicz(&mesh));
        row(&[
            mesh.vertex_count().to_string(),
            mesh.face_count().to_string(),
            cell(t_read),
            format!("{mb:.1}"),
            cell(t_build),
            cell(t_normals),
            cell(t_cot),
            cell(t_areas),
            cell(t_curv),
        ]);
        let _ = std::fs::remove_file(&path);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
