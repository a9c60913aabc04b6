//! Benchmark of B-spline surface highlight lines and circular-highlight
//! fairing (Nishiyama et al.): the signed-distance field d_s on a 500 × 500
//! (u, v) grid of a bicubic 21 × 22 surface, contouring of its zero level,
//! and Gauss–Newton fairing iterations with a Jacobian of about the size of
//! the paper's largest (460 × 165). Prints medians.
//!
//! Run: `cargo bench -p fairline --bench bspline_surfaces`

mod common;

use fairline::Vec3;
use fairline::bspline::{BSplineSurface, clamped_uniform_knots};
use fairline::fair::{SurfaceFairOptions, endpoints_around, fair_surface};
use fairline::highlight::surface::{SurfaceHighlightOptions, contour_field, distance_field};
use fairline::highlight::{CircularLight, SurfaceLight};

fn height_surface(nu: usize, nv: usize, h: impl Fn(f64, f64) -> f64) -> BSplineSurface {
    let net = (0..nu)
        .map(|i| {
            (0..nv)
                .map(|j| {
                    let x = -1.0 + 2.0 * i as f64 / (nu - 1) as f64;
                    let y = -1.0 + 2.0 * j as f64 / (nv - 1) as f64;
                    Vec3::new(x, y, h(x, y))
                })
                .collect()
        })
        .collect();
    BSplineSurface::new(
        3,
        3,
        clamped_uniform_knots(nu, 3),
        clamped_uniform_knots(nv, 3),
        net,
        None,
    )
    .unwrap()
}

fn main() {
    let runs = common::runs(7);
    println!(
        "machine: {} threads (rayon); medians of {runs} runs",
        rayon::current_num_threads()
    );
    // 1. d_s field on a 500 x 500 grid of a bicubic 21 x 22 surface.
    let roof = height_surface(21, 22, |x, y| {
        0.3 - 0.12 * x * x - 0.05 * y * y + 0.02 * x * y
    });
    let light =
        SurfaceLight::Circular(CircularLight::new(Vec3::new(0.2, 0.1, 2.5), Vec3::Z, 1.0).unwrap());
    let t_field = common::median_secs(runs, || distance_field(&roof, &light, 500, 500));
    let field = distance_field(&roof, &light, 500, 500);
    let opts = SurfaceHighlightOptions::default().grid(500);
    let t_contour =
        common::median_secs(runs, || contour_field(&roof, &light, 0, &field, 0.0, &opts));
    let lines = contour_field(&roof, &light, 0, &field, 0.0, &opts);
    println!("{:<44} {:>10} {:>10}", "task", "size", "median ms");
    println!(
        "{:<44} {:>10} {:>10.1}",
        "d_s field, bicubic 21x22, 500x500 grid",
        "250000",
        t_field * 1e3
    );
    println!(
        "{:<44} {:>10} {:>10.1}",
        format!(
            "zero-level contour + refinement ({} pts)",
            lines.iter().map(|l| l.uv.len()).sum::<usize>()
        ),
        "500x500",
        t_contour * 1e3
    );
    // 2. Fairing: dome-like 15 x 15 surface with a bump, 9 lights.
    let mut dome = height_surface(15, 15, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let p = dome.control_point(11, 7);
    dome.set_control_point(11, 7, p + Vec3::new(0.0, 0.0, 0.03))
        .unwrap();
    let centre = [(9.0 + 10.0 + 11.0) / 36.0, 0.5];
    let lights: Vec<CircularLight> = (0..9)
        .map(|k| {
            let r = 1.95 * (0.8 + 0.05 * k as f64);
            CircularLight::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z, r).unwrap()
        })
        .collect();
    let fopts = SurfaceFairOptions::default().max_iterations(4);
    let ends = endpoints_around(&dome, &lights, centre, 0.2, fopts.grid);
    let fopts = fopts.lights(lights.clone()).endpoints(ends);
    let mut per_iter = Vec::new();
    let mut size = (0, 0, 0);
    let t_total = common::median_secs(runs, || {
        let rep = fair_surface(&dome, &fopts).unwrap().report;
        for it in &rep.history {
            per_iter.push(it.time_s);
            size = (it.rows, it.cols, rep.iterations);
        }
    });
    per_iter.sort_by(f64::total_cmp);
    let med = per_iter
        .get(per_iter.len() / 2)
        .copied()
        .unwrap_or(f64::NAN);
    println!(
        "{:<44} {:>10} {:>10.1}",
        "fairing iteration (Jacobian + SVD + step)",
        format!("{}x{}", size.0, size.1),
        med * 1e3
    );
    println!(
        "{:<44} {:>10} {:>10.1}",
        format!("fair_surface total ({} iterations, targets)", size.2),
        format!("{}x{}", size.0, size.1),
        t_total * 1e3
    );
}
