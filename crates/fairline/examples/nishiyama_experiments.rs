//! The three experiments of Nishiyama et al. §4 rebuilt — a dome-like 15×15,
//! a saddle-like 21×20 and a roof-panel-like 21×22 bicubic B-spline surface
//! on clamped uniform knots, each with a planted defect — faired with the
//! paper's solver (`SurfaceFairMethod::Paper`, with and without the damped
//! step of Eq. (3.12)–(3.13)) and the default regularised solver, printed
//! beside the paper's Table 1 (first fairing of each model).
//!
//! Columns: lights and iterations, the Jacobian's size, the time, mean
//! |d_s| at the targets before → after, the largest normal distance from
//! the defect-free surface over the knot box before → after, and the closed
//! pre-image loops the fairing made that the defective surface did not have.
//!
//! Run with `cargo run --release -p fairline --example nishiyama_experiments`.

use fairline::Vec3;
use fairline::bspline::{BSplineSurface, clamped_uniform_knots};
use fairline::fair::{
    PaperDamping, SurfaceFairMethod, SurfaceFairOptions, SurfaceFairReport, endpoints_around,
    fair_surface,
};
use fairline::highlight::{
    CircularLight, SurfaceHighlightOptions, SurfaceLight, surface_highlight_lines,
};
use std::time::Instant;

/// A bicubic surface on clamped uniform knots with its control points on
/// `z = h(x, y)` over `[-a, a] × [-b, b]`.
fn height_surface(
    nu: usize,
    nv: usize,
    a: f64,
    b: f64,
    h: impl Fn(f64, f64) -> f64,
) -> BSplineSurface {
    let net = (0..nu)
        .map(|i| {
            (0..nv)
                .map(|j| {
                    let x = -a + 2.0 * a * i as f64 / (nu - 1) as f64;
                    let y = -b + 2.0 * b * j as f64 / (nv - 1) as f64;
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
    .expect("a valid height surface")
}

/// One experiment: the defect-free surface, the defective one, the lights
/// and the disc of the parameter domain around the defect.
struct Experiment {
    name: &'static str,
    paper: &'static str,
    clean: BSplineSurface,
    defective: BSplineSurface,
    lights: Vec<CircularLight>,
    centre: [f64; 2],
    disc: f64,
}

/// The control point `(i, j)` moved by `dz` along z; `count` concentric
/// lights (centre `c`, axis z; the triple `(c, spread, count)`) with radii spread by ±`spread`/2 around the
/// one whose line passes over the defect.
fn experiment(
    name: &'static str,
    paper: &'static str,
    clean: BSplineSurface,
    (i, j, dz): (usize, usize, f64),
    (c, spread, count): (Vec3, f64, usize),
    disc: f64,
) -> Experiment {
    let mut defective = clean.clone();
    defective
        .set_control_point(i, j, clean.control_point(i, j) + Vec3::new(0.0, 0.0, dz))
        .expect("a finite control point");
    let greville = |k: &[f64], i: usize| (k[i + 1] + k[i + 2] + k[i + 3]) / 3.0;
    let centre = [greville(clean.knots_u(), i), greville(clean.knots_v(), j)];
    let q = clean.eval(centre[0], centre[1]);
    let n = clean.normal(centre[0], centre[1]).expect("a regular point");
    let x = q + (c.z - q.z) / n.z * n;
    let r0 = (x.x - c.x).hypot(x.y - c.y);
    let lights = (0..count)
        .map(|k| {
            let t = k as f64 / (count - 1) as f64 - 0.5;
            CircularLight::new(c, Vec3::Z, r0 * (1.0 + spread * t)).expect("a valid light")
        })
        .collect();
    Experiment {
        name,
        paper,
        clean,
        defective,
        lights,
        centre,
        disc,
    }
}

/// Largest |(S(u, v) − S₀(u, v)) · N₀(u, v)| over a 41 × 41 grid of the
/// knot box: how far `s` is from the defect-free surface `clean`.
fn distance_to_truth(s: &BSplineSurface, clean: &BSplineSurface, kb: [f64; 4]) -> f64 {
    let mut worst = 0.0f64;
    for a in 0..=40 {
        for b in 0..=40 {
            let u = kb[0] + (kb[1] - kb[0]) * a as f64 / 40.0;
            let v = kb[2] + (kb[3] - kb[2]) * b as f64 / 40.0;
            if let Some(n) = clean.normal(u, v) {
                worst = worst.max((s.eval(u, v) - clean.eval(u, v)).dot(n).abs());
            }
        }
    }
    worst
}

/// Closed pre-image polylines per light.
fn closed_loops(s: &BSplineSurface, lights: &[CircularLight], grid: usize) -> Vec<usize> {
    let ls: Vec<SurfaceLight> = lights.iter().map(|l| SurfaceLight::Circular(*l)).collect();
    let h = surface_highlight_lines(s, &ls, &SurfaceHighlightOptions::default().grid(grid));
    let mut out = vec![0; lights.len()];
    for l in h.lines.iter().filter(|l| l.closed && l.level == 0.0) {
        out[l.light] += 1;
    }
    out
}

fn row(e: &Experiment, label: &str, opts: &SurfaceFairOptions) {
    let endpoints = endpoints_around(&e.defective, &e.lights, e.centre, e.disc, opts.grid);
    let opts = opts
        .clone()
        .lights(e.lights.clone())
        .endpoints(endpoints.clone());
    let t0 = Instant::now();
    let out = match fair_surface(&e.defective, &opts) {
        Ok(o) => o,
        Err(err) => {
            println!("{:<8} {label:<22} failed: {err}", e.name);
            return;
        }
    };
    let time = t0.elapsed().as_secs_f64();
    let rep: &SurfaceFairReport = &out.report;
    let before = distance_to_truth(&e.defective, &e.clean, rep.knot_box);
    let after = distance_to_truth(&out.surfaces, &e.clean, rep.knot_box);
    let loops_before = closed_loops(&e.defective, &e.lights, opts.grid);
    let loops_after = closed_loops(&out.surfaces, &e.lights, opts.grid);
    let new_loops: usize = loops_before
        .iter()
        .zip(&loops_after)
        .map(|(b, a)| a.saturating_sub(*b))
        .sum();
    println!(
        "{:<8} {label:<22} {:>3} {:>3} {:>4}{} {:>4}×{:<4} {:>6.2} {:.2e} → {:.2e} {:.2e} → {:.2e} {:>3}",
        e.name,
        endpoints.len(),
        rep.iterations,
        format!("{:?}", rep.stop)
            .to_lowercase()
            .chars()
            .take(4)
            .collect::<String>(),
        if rep.converged { " " } else { "!" },
        rep.jacobian.rows,
        rep.jacobian.cols,
        time,
        rep.residual_before.mean,
        rep.residual_after.mean,
        before,
        after,
        new_loops
    );
    if std::env::args().any(|a| a == "--history") {
        for it in &rep.history {
            println!(
                "           max {:.3e} mean {:.3e} step {} rank {} trunc {:.0e} {:.0} ms",
                it.max_abs,
                it.mean_abs,
                it.step,
                it.rank,
                it.truncation,
                1e3 * it.time_s
            );
        }
    }
}

fn main() {
    let experiments = [
        experiment(
            "dome9",
            "(the tests' nine lights)",
            height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y)),
            (11, 7, 0.03),
            (Vec3::new(0.0, 0.0, 3.0), 0.4, 9),
            0.2,
        ),
        experiment(
            "dome",
            "12 lights, 5 iterations, 192×36, 0.95 s",
            height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y)),
            (11, 7, 0.03),
            (Vec3::new(0.0, 0.0, 3.0), 0.4, 12),
            0.2,
        ),
        experiment(
            "saddle",
            "11 lights, 4 iterations, 460×165, 6.32 s",
            height_surface(21, 20, 1.0, 1.0, |x, y| 0.35 * (x * x - y * y)),
            (6, 13, 0.02),
            (Vec3::new(0.0, 0.0, 2.0), 0.3, 11),
            0.16,
        ),
        experiment(
            "roof",
            "18 lights, 6 iterations, 273×108, 5.68 s",
            height_surface(21, 22, 1.5, 1.0, |x, y| {
                0.3 - 0.12 * x * x - 0.05 * y * y + 0.02 * x * y
            }),
            (8, 12, -0.015),
            (Vec3::new(2.0, 1.5, 2.5), 0.3, 18),
            0.2,
        ),
    ];
    let paper = SurfaceFairOptions::default().method(SurfaceFairMethod::Paper);
    let runs = [
        ("paper", paper.clone()),
        (
            "paper, Eq. 3.12 damping",
            paper.clone().damping(PaperDamping::MaxMean),
        ),
        ("paper, no damping", paper.damping(PaperDamping::Off)),
        ("regularised (default)", SurfaceFairOptions::default()),
    ];
    println!("Nishiyama et al. Table 1 (first fairing) beside fairline");
    println!(
        "(columns: stretches, iterations, stop (! = not converged), Jacobian, seconds, mean |d_s|, distance to the defect-free surface, new closed loops)"
    );
    for e in &experiments {
        println!("{:<8} {:<22} {}", e.name, "paper's Table 1", e.paper);
        for (label, opts) in &runs {
            row(e, label, opts);
        }
    }
}
