//! Benchmark of the highlight line model (Yong et al. Algorithm 1): normals,
//! distances, nodes and polylines on smooth height fields of about 112k,
//! 450k and 900k vertices. Prints median wall times over several runs.
//!
//! Run: `cargo bench -p fairline --bench highlight`

use fairline::Vec3;
use fairline::geom;
use fairline::highlight::{HighlightModel, HighlightOptions, LightArray};
use fairline::shapes;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let runs = 11;
    println!("highlight model (normals + distances + nodes + polylines), median of {runs} runs");
    println!(
        "{:>10} {:>10} {:>12} {:>12} {:>12} {:>8} {:>8}",
        "vertices", "faces", "normals ms", "model ms", "total ms", "lines", "nodes"
    );
    for n in [335u32, 670, 948] {
        let mesh = shapes::height_field(n, n, (-2.0, 2.0), (-2.0, 2.0), |x, y| {
            0.3 * (1.3 * x).sin() * (0.9 * y).cos() + 0.1 * (x * y).cos()
        });
        let light =
            LightArray::default_for(Vec3::new(-2.0, -2.0, -0.4), Vec3::new(2.0, 2.0, 0.4), None);
        let opts = HighlightOptions::default();
        let mut t_norm = Vec::new();
        let mut t_model = Vec::new();
        let mut t_total = Vec::new();
        let mut counts = (0, 0);
        for _ in 0..runs {
            let t0 = Instant::now();
            let normals = geom::vertex_normals(&mesh);
            t_norm.push(t0.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(normals);
            let t0 = Instant::now();
            let model = HighlightModel::new(&mesh, light, opts).expect("triangle mesh");
            let t1 = Instant::now();
            let lines = model.lines(&mesh);
            let t2 = Instant::now();
            t_model.push((t1 - t0).as_secs_f64() * 1e3);
            t_total.push((t2 - t0).as_secs_f64() * 1e3);
            counts = (lines.lines.len(), lines.node_count());
        }
        println!(
            "{:>10} {:>10} {:>12.2} {:>12.2} {:>12.2} {:>8} {:>8}",
            mesh.vertex_count(),
            mesh.face_count(),
            median(t_norm),
            median(t_model),
            median(t_total),
            counts.0,
            counts.1
        );
    }
}
