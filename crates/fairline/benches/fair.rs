//! Benchmark of highlight-line fairing (Yong et al. Algorithm 2): a bump in
//! a region of about 500, 2,000 and 8,000 movable vertices of a
//! 100k-vertex height field. Prints the median time of the set-up (model,
//! movable set, desired lines) and of one iteration (linearisation, box QP,
//! incremental model update, step check). It runs the paper's method
//! (`FairMethod::Paper`): the default method's iterations cost the same;
//! it adds one smooth fit per desired-line end in the set-up (its end
//! tangents) and one diffusion-flow run.
//!
//! Run: `cargo bench -p fairline --bench fair`

use fairline::Vec3;
use fairline::fair::{FairMethod, FairOptions, fair_highlight_lines};
use fairline::highlight::LightArray;
use fairline::io::RegionSpec;
use fairline::shapes;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let runs = 5;
    let n = 317u32; // 100,489 vertices
    let mesh = shapes::height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.05 * x * x + 0.02 * (-(x * x + y * y) / (2.0 * 0.05 * 0.05)).exp()
    });
    let light = LightArray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, Vec3::X, 0.02).unwrap();
    println!(
        "highlight-line fairing on a {}-vertex height field, median of {runs} runs",
        mesh.vertex_count()
    );
    println!(
        "{:>8} {:>9} {:>10} {:>14} {:>11}",
        "radius", "movable", "setup ms", "iteration ms", "iterations"
    );
    for radius in [0.09, 0.16, 0.31] {
        let faces = RegionSpec::Sphere {
            center: Vec3::ZERO,
            radius,
        }
        .faces(&mesh)
        .unwrap();
        let (mut t1, mut t3) = (Vec::new(), Vec::new());
        let mut movable = 0;
        let mut iters = 0;
        for _ in 0..runs {
            let t = Instant::now();
            let options = FairOptions::default()
                .method(FairMethod::Paper)
                .region(faces.clone())
                .light(light);
            let r = fair_highlight_lines(&mesh, &options.clone().max_iterations(1))
                .unwrap()
                .report;
            t1.push(t.elapsed().as_secs_f64() * 1e3);
            movable = r.movable_vertices;
            let t = Instant::now();
            let r = fair_highlight_lines(&mesh, &options.max_iterations(3))
                .unwrap()
                .report;
            t3.push(t.elapsed().as_secs_f64() * 1e3);
            iters = r.iterations;
        }
        let (m1, m3) = (median(t1), median(t3));
        let per = if iters > 1 {
            (m3 - m1) / (iters - 1) as f64
        } else {
            m1
        };
        println!(
            "{radius:>8} {movable:>9} {:>10.0} {per:>14.0} {iters:>11}",
            m1 - per
        );
    }
}
