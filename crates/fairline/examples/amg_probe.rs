use fairline::enhance::{EnhanceOptions, EnhanceSolver, enhance_features};
use fairline::shapes::{rounded_cube, torus};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = args[1].as_str();
    let n: usize = args[2].parse().unwrap();
    let solver = match args[3].as_str() {
        "amg" => EnhanceSolver::Amg,
        "cg" => EnhanceSolver::Cg,
        "direct" => EnhanceSolver::Direct,
        _ => EnhanceSolver::Auto,
    };
    let mesh = if shape == "cube" {
        rounded_cube(((n as f64 / 6.0).sqrt().round() as u32).max(2), 0.3)
    } else {
        let n_minor = ((n as f64 / 4.0).sqrt().round() as u32).max(3);
        let n_major = ((n as f64 / n_minor as f64).round() as u32).max(3);
        torus(1.0, 0.4, n_major, n_minor)
    };
    let t = Instant::now();
    let r = enhance_features(&mesh, &EnhanceOptions::default().solver(solver)).unwrap();
    println!(
        "{shape} {} {:?}: {:.3} s, iters {}, fallbacks {}, timings {:?}",
        mesh.vertex_count(),
        solver,
        t.elapsed().as_secs_f64(),
        r.report.cg_iterations,
        r.report.direct_fallbacks,
        r.report.timings
    );
}
