//! Circular-highlight fairing on surfaces built like the paper's examples
//! (Nishiyama et al. §4: a dome-like 15×15, a saddle-like 21×20 and a
//! roof-panel-like 21×22 bicubic surface on clamped uniform knots), each with
//! a planted bump: the residual at the targets drops by orders of magnitude
//! within the paper's iteration counts, everything outside the selected
//! control points is bit-identical, and the highlight lines and the surface
//! move back towards the clean surface's.

use super::targets::{Arc, dist2};
use super::*;
use crate::Control;
use crate::bspline::clamped_uniform_knots;
use crate::highlight::surface::SurfaceHighlightLine;

/// [`fair_surface`] with `lights` and `endpoints` set on `opts`, as the
/// pair (faired surface, report).
fn fair(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    endpoints: &[EndpointPair],
    opts: &SurfaceFairOptions,
) -> Result<(BSplineSurface, SurfaceFairReport), SurfaceFairError> {
    let opts = opts
        .clone()
        .lights(lights.to_vec())
        .endpoints(endpoints.to_vec());
    fair_surface(surface, &opts).map(|out| (out.surfaces, out.report))
}

/// A bicubic surface on clamped uniform knots whose control points sit on
/// the height field `z = h(x, y)` over `[-a, a] × [-b, b]`.
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
    .unwrap()
}

/// The surface with control point (i, j) raised by `dz`.
fn with_bump(s: &BSplineSurface, i: usize, j: usize, dz: f64) -> BSplineSurface {
    let mut d = s.clone();
    d.set_control_point(i, j, s.control_point(i, j) + Vec3::new(0.0, 0.0, dz))
        .unwrap();
    d
}

/// The radius of the circle (centre `c`, axis +z) that the normal line of
/// `s` at `(u, v)` meets: the normal line's horizontal distance from the
/// axis at the circle's height.
fn radius_through(s: &BSplineSurface, c: Vec3, u: f64, v: f64) -> f64 {
    let q = s.eval(u, v);
    let n = s.normal(u, v).unwrap();
    let x = q + (c.z - q.z) / n.z * n;
    (x.x - c.x).hypot(x.y - c.y)
}

/// Greville abscissa of control point k (its "centre" in the domain).
fn greville(knots: &[f64], k: usize) -> f64 {
    (knots[k + 1] + knots[k + 2] + knots[k + 3]) / 3.0
}

struct Case {
    clean: BSplineSurface,
    bumped: BSplineSurface,
    lights: Vec<CircularLight>,
    centre: [f64; 2],
    disc: f64,
}

fn case(
    clean: BSplineSurface,
    bump: (usize, usize, f64),
    light_c: Vec3,
    spread: f64,
    count: usize,
    disc: f64,
) -> Case {
    let bumped = with_bump(&clean, bump.0, bump.1, bump.2);
    let centre = [
        greville(clean.knots_u(), bump.0),
        greville(clean.knots_v(), bump.1),
    ];
    let r0 = radius_through(&clean, light_c, centre[0], centre[1]);
    let lights = (0..count)
        .map(|k| {
            let t = k as f64 / (count - 1) as f64 - 0.5;
            CircularLight::new(light_c, Vec3::Z, r0 * (1.0 + spread * t)).unwrap()
        })
        .collect();
    Case {
        clean,
        bumped,
        lights,
        centre,
        disc,
    }
}

/// Largest distance (in u, v) from the points of `lines` inside the disc to
/// the nearest point of the reference pre-images of the same light.
fn deviation(
    lines: &[SurfaceHighlightLine],
    reference: &[SurfaceHighlightLine],
    centre: [f64; 2],
    disc: f64,
) -> f64 {
    let mut worst = 0.0f64;
    for l in lines {
        let refs: Vec<Arc> = reference
            .iter()
            .filter(|r| r.light == l.light && r.uv.len() >= 2)
            .map(Arc::new)
            .collect();
        for &p in &l.uv {
            if dist2(p, centre) > disc * disc {
                continue;
            }
            let d = refs
                .iter()
                .map(|a| a.nearest(p).0)
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            worst = worst.max(d);
        }
    }
    worst
}

fn pre_images(
    s: &BSplineSurface,
    lights: &[CircularLight],
    grid: usize,
) -> Vec<SurfaceHighlightLine> {
    let ls: Vec<SurfaceLight> = lights.iter().map(|l| SurfaceLight::Circular(*l)).collect();
    crate::highlight::surface_highlight_lines(
        s,
        &ls,
        &SurfaceHighlightOptions::default().grid(grid),
    )
    .lines
}

/// Per light: (Σ total variation of curvature, Σ inflections, Σ self
/// crossings, closed polylines) of its pre-images, resampled every four
/// grid cells; inflections count sign changes among |κ| ≥ 0.5 (a radius of
/// two domains: contouring noise on straight stretches stays below it).
fn light_waviness(
    lines: &[SurfaceHighlightLine],
    count: usize,
    grid: usize,
) -> Vec<(f64, usize, usize, usize)> {
    let spacing = 4.0 / (grid - 1) as f64;
    let mut out = vec![(0.0, 0, 0, 0); count];
    for l in lines {
        let w = polyline_waviness(&l.uv, l.closed, spacing, 0.5);
        let o = &mut out[l.light];
        o.0 += w.curvature_variation;
        o.1 += w.inflections;
        o.2 += w.self_crossings;
        o.3 += usize::from(l.closed);
    }
    out
}

/// Every light's lines are at most as wavy after as before: total
/// variation of curvature not higher, no new inflection, crossing or closed
/// loop. Returns (Σ TV before, Σ TV after).
fn assert_no_line_wavier(
    before: &[SurfaceHighlightLine],
    after: &[SurfaceHighlightLine],
    count: usize,
    grid: usize,
    name: &str,
) -> (f64, f64) {
    let (wb, wa) = (
        light_waviness(before, count, grid),
        light_waviness(after, count, grid),
    );
    let mut sums = (0.0, 0.0);
    for (l, (b, a)) in wb.iter().zip(&wa).enumerate() {
        sums.0 += b.0;
        sums.1 += a.0;
        assert!(
            a.0 <= b.0,
            "{name}: light {l}: curvature variation {} -> {}",
            b.0,
            a.0
        );
        assert!(
            a.1 <= b.1,
            "{name}: light {l}: inflections {} -> {}",
            b.1,
            a.1
        );
        assert!(
            a.2 <= b.2,
            "{name}: light {l}: self crossings {} -> {}",
            b.2,
            a.2
        );
        assert!(
            a.3 <= b.3,
            "{name}: light {l}: closed loops {} -> {}",
            b.3,
            a.3
        );
    }
    sums
}

/// The lights whose worst per-light TV rose with the paper's solver (for
/// the record), as (count, largest relative rise).
fn tv_rises(
    before: &[SurfaceHighlightLine],
    after: &[SurfaceHighlightLine],
    count: usize,
    grid: usize,
) -> (usize, f64) {
    let (wb, wa) = (
        light_waviness(before, count, grid),
        light_waviness(after, count, grid),
    );
    let mut worst = (0, 0.0f64);
    for (b, a) in wb.iter().zip(&wa) {
        if a.0 > b.0 {
            worst.0 += 1;
            worst.1 = worst.1.max(a.0 / b.0.max(f64::MIN_POSITIVE) - 1.0);
        }
    }
    worst
}

/// Runs the whole check on one case and returns the report: the default
/// (regularised) solver on all stretches around the defect and on the
/// stretches of every other light only.
/// The faired surface equals the bumped one bit for bit at every sample of
/// a 61 × 61 (u, v) grid whose basis support meets no moved control point,
/// and more than a third of the samples are such.
fn assert_bit_identical_outside_support(
    c: &Case,
    rep: &SurfaceFairReport,
    faired: &BSplineSurface,
    name: &str,
) {
    let n = 61;
    let mut outside = 0;
    for a in 0..n {
        for bb in 0..n {
            let (u, v) = (a as f64 / (n - 1) as f64, bb as f64 / (n - 1) as f64);
            let sup = c.bumped.basis_support(u, v);
            let touches = rep
                .modified_indices
                .iter()
                .any(|&(i, j)| sup.rows.contains(&i) && sup.cols.contains(&j));
            if !touches {
                outside += 1;
                let (p, q) = (c.bumped.eval(u, v), faired.eval(u, v));
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    q.to_array().map(f64::to_bits)
                );
            }
        }
    }
    assert!(
        outside > n * n / 3,
        "{name}: only {outside} samples outside the support"
    );
}

fn check_case(c: &Case, drop: f64, closer: f64, name: &str) -> SurfaceFairReport {
    let opts = SurfaceFairOptions::default();
    let endpoints = endpoints_around(&c.bumped, &c.lights, c.centre, c.disc, opts.grid);
    assert!(
        endpoints.len() >= 3,
        "{name}: {} stretches",
        endpoints.len()
    );
    let (faired, rep) = fair(&c.bumped, &c.lights, &endpoints, &opts).unwrap();
    let (b, a) = (
        (rep.residual_before.max, rep.residual_before.mean),
        (rep.residual_after.max, rep.residual_after.mean),
    );
    let per_iteration = rep.history.iter().map(|i| i.time_s).fold(0.0, f64::max);
    eprintln!(
        "{name}: {} stretches, {} target + {} weak samples, {} unknowns, {} held on the boundary, {} iterations ({:?}, slowest {:.1} ms), mean |d_s| {:.3e} -> {:.3e}, max {:.3e} -> {:.3e}",
        endpoints.len(),
        rep.targets.iter().map(|t| t.samples.len()).sum::<usize>(),
        rep.keep_samples,
        3 * rep.modified_indices.len(),
        rep.held_boundary_points.len(),
        rep.history.len(),
        rep.stop,
        1e3 * per_iteration,
        b.1,
        a.1,
        b.0,
        a.0
    );
    for it in &rep.history {
        eprintln!(
            "{name}:   objective {:.6e} mean {:.3e} damping {:.1e} {:.1} ms",
            it.objective,
            it.mean_abs,
            it.damping,
            1e3 * it.time_s
        );
    }
    assert_eq!(rep.method, SurfaceFairMethod::Regularised);
    // Converged by its stop test, within the paper's 4–8 iterations.
    assert!(rep.converged, "{name}: stopped by {:?}", rep.stop);
    assert_eq!(rep.stop, FairStop::Epsilon);
    assert!(
        rep.history.len() <= 8,
        "{name}: {} iterations",
        rep.history.len()
    );
    let last = rep.history.last().unwrap();
    let prev = if rep.history.len() >= 2 {
        rep.history[rep.history.len() - 2].objective
    } else {
        f64::INFINITY
    };
    assert!((prev - last.objective) / prev < opts.epsilon || rep.history.len() == 1);
    for w in rep.history.windows(2) {
        assert!(w[1].objective < w[0].objective);
    }
    // The targets are reached: mean |d_s| drops by `drop` (two orders of
    // magnitude and more), max by 20, and further than with the paper's
    // fixed 5 % truncation. (The regularised solver stops at the
    // compromise with the weak targets and the thin-plate energy: its
    // residual is 2–5 times that of the paper's solver with the truncation
    // lowered to 1e-3, which makes the other lines wavier.)
    assert!(a.1 <= b.1 / drop, "{name}: mean {} -> {}", b.1, a.1);
    let fixed5 = SurfaceFairOptions {
        method: SurfaceFairMethod::Paper,
        min_truncation: opts.truncation,
        ..opts.clone()
    };
    let (_, rep5) = fair(&c.bumped, &c.lights, &endpoints, &fixed5).unwrap();
    eprintln!(
        "{name}: paper's fixed 5 % truncation: mean |d_s| {:.3e} after {} iterations",
        rep5.residual_after.mean,
        rep5.history.len()
    );
    assert!(
        a.1 < rep5.residual_after.mean,
        "{name}: no better than the 5 % rule"
    );
    assert!(a.0 <= b.0 / 20.0, "{name}: max {} -> {}", b.0, a.0);
    // Control points outside the selection — the boundary rows among them —
    // bit-identical.
    let sel: std::collections::HashSet<(usize, usize)> =
        rep.modified_indices.iter().copied().collect();
    let (nu, nv) = (c.bumped.count_u(), c.bumped.count_v());
    for i in 0..nu {
        for j in 0..nv {
            let (p, q) = (c.bumped.control_point(i, j), faired.control_point(i, j));
            let boundary = i == 0 || j == 0 || i + 1 == nu || j + 1 == nv;
            assert!(!(boundary && sel.contains(&(i, j))));
            if !sel.contains(&(i, j)) {
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    q.to_array().map(f64::to_bits)
                );
            }
        }
    }
    assert!(rep.max_displacement > 0.0);
    // The surface outside the selected points' support: bit-identical.
    assert_bit_identical_outside_support(c, &rep, &faired, name);
    // Highlight lines inside the disc move back towards the clean ones.
    let clean_lines = pre_images(&c.clean, &c.lights, opts.grid);
    let bumped_lines = pre_images(&c.bumped, &c.lights, opts.grid);
    let faired_lines = pre_images(&faired, &c.lights, opts.grid);
    let before = deviation(&bumped_lines, &clean_lines, c.centre, c.disc);
    let after = deviation(&faired_lines, &clean_lines, c.centre, c.disc);
    eprintln!("{name}: pre-image deviation from the clean surface {before:.3e} -> {after:.3e}");
    assert!(
        after < 0.4 * before,
        "{name}: deviation {before} -> {after}"
    );
    // No line of any light gets wavier.
    let tv = assert_no_line_wavier(
        &bumped_lines,
        &faired_lines,
        c.lights.len(),
        opts.grid,
        name,
    );
    eprintln!(
        "{name}: total variation of curvature, all lights: {:.3} -> {:.3}",
        tv.0, tv.1
    );
    // And the surface itself: normal deviation from the clean surface.
    let kb = rep.knot_box;
    let mut dev = (0.0f64, 0.0f64);
    for a in 0..=40 {
        for bb in 0..=40 {
            let u = kb[0] + (kb[1] - kb[0]) * a as f64 / 40.0;
            let v = kb[2] + (kb[3] - kb[2]) * bb as f64 / 40.0;
            let p0 = c.clean.eval(u, v);
            let nn = c.clean.normal(u, v).unwrap();
            dev.0 = dev.0.max((c.bumped.eval(u, v) - p0).dot(nn).abs());
            dev.1 = dev.1.max((faired.eval(u, v) - p0).dot(nn).abs());
        }
    }
    eprintln!(
        "{name}: normal deviation from the clean surface {:.3e} -> {:.3e}",
        dev.0, dev.1
    );
    assert!(
        dev.1 < closer * dev.0,
        "{name}: surface deviation {} -> {}",
        dev.0,
        dev.1
    );
    // The paper's solver on the same stretches, for the record.
    let paper = SurfaceFairOptions {
        method: SurfaceFairMethod::Paper,
        ..opts.clone()
    };
    let (pf, prep) = fair(&c.bumped, &c.lights, &endpoints, &paper).unwrap();
    let rises = tv_rises(
        &bumped_lines,
        &pre_images(&pf, &c.lights, opts.grid),
        c.lights.len(),
        opts.grid,
    );
    eprintln!(
        "{name}: paper's solver: {} iterations ({:?}), mean |d_s| {:.3e}; {} lights with a higher curvature variation (worst +{:.0} %)",
        prep.history.len(),
        prep.stop,
        prep.residual_after.mean,
        rises.0,
        100.0 * rises.1
    );
    // Only every other light's stretches selected: the lines left out cross
    // the moved region with their kinks and must not get wavier either.
    let half: Vec<EndpointPair> = endpoints
        .iter()
        .filter(|e| {
            c.lights
                .iter()
                .position(|l| l.radius() == e.radius)
                .is_some_and(|k| k % 2 == 0)
        })
        .copied()
        .collect();
    assert!(!half.is_empty() && half.len() < endpoints.len());
    let (hf, hrep) = fair(&c.bumped, &c.lights, &half, &opts).unwrap();
    assert!(
        hrep.converged && hrep.history.len() <= 8,
        "{name}: half: {:?} after {}",
        hrep.stop,
        hrep.history.len()
    );
    // Two orders of magnitude: the kinked lines left out are held by the
    // weak targets and pull against the selected ones.
    assert!(
        hrep.residual_after.mean <= hrep.residual_before.mean / 50.0,
        "{name}: half: mean {:?} -> {:?}",
        hrep.residual_before,
        hrep.residual_after
    );
    let tv = assert_no_line_wavier(
        &bumped_lines,
        &pre_images(&hf, &c.lights, opts.grid),
        c.lights.len(),
        opts.grid,
        name,
    );
    let (hp, _) = fair(&c.bumped, &c.lights, &half, &paper).unwrap();
    let rises = tv_rises(
        &bumped_lines,
        &pre_images(&hp, &c.lights, opts.grid),
        c.lights.len(),
        opts.grid,
    );
    eprintln!(
        "{name}: every other light: {} iterations, mean |d_s| {:.3e} -> {:.3e}, TV {:.3} -> {:.3}; paper's solver: {} lights wavier (worst +{:.0} %)",
        hrep.history.len(),
        hrep.residual_before.mean,
        hrep.residual_after.mean,
        tv.0,
        tv.1,
        rises.0,
        100.0 * rises.1
    );
    rep
}

/// The guarantees of the paper's method (`--method paper`), with its own
/// thresholds:
/// the regularised default trades some target residual for keeping every
/// other line fair (see `check_case`), the paper's method keeps these.
fn check_case_paper(
    c: &Case,
    max_iterations: usize,
    drop: f64,
    gain: f64,
    name: &str,
) -> SurfaceFairReport {
    let opts = SurfaceFairOptions {
        max_iterations,
        method: SurfaceFairMethod::Paper,
        boundary: BoundaryControl::Free,
        ..Default::default()
    };
    let endpoints = endpoints_around(&c.bumped, &c.lights, c.centre, c.disc, opts.grid);
    assert!(
        endpoints.len() >= 3,
        "{name}: {} stretches",
        endpoints.len()
    );
    let (faired, rep) = fair(&c.bumped, &c.lights, &endpoints, &opts).unwrap();
    let (b, a) = (
        (rep.residual_before.max, rep.residual_before.mean),
        (rep.residual_after.max, rep.residual_after.mean),
    );
    eprintln!(
        "{name}: {} stretches, {}x{} Jacobian, {} iterations, mean |d_s| {:.3e} -> {:.3e}, max {:.3e} -> {:.3e}",
        endpoints.len(),
        rep.history.first().map_or(0, |i| i.rows),
        rep.history.first().map_or(0, |i| i.cols),
        rep.history.len(),
        b.1,
        a.1,
        b.0,
        a.0
    );
    // Within the paper's iteration counts (at most 8) the mean residual at
    // the targets drops by `drop` (two to three orders of magnitude). With
    // the paper's fixed 5 % truncation it stalls after ~1.5 orders (the
    // residual left lies in the dropped singular directions); the
    // truncation is lowered to 1e-3 as progress slows. What remains is the
    // least-squares floor: the Hermite targets are not exactly highlight
    // lines of any surface the selected control points can reach (more
    // samples than unknowns, one coordinate per moved point).
    assert!(a.1 <= b.1 / drop, "{name}: mean {} -> {}", b.1, a.1);
    // the fixed 5 % rule of the paper, for comparison: stalls higher (its
    // mean |d_s| at least 1/`gain` times ours)
    let fixed = SurfaceFairOptions {
        min_truncation: opts.truncation,
        ..opts.clone()
    };
    let (_, rep5) = fair(&c.bumped, &c.lights, &endpoints, &fixed).unwrap();
    eprintln!(
        "{name}: fixed 5 % truncation: mean |d_s| {:.3e} after {} iterations",
        rep5.residual_after.mean,
        rep5.history.len()
    );
    assert!(
        a.1 < gain * rep5.residual_after.mean,
        "{name}: no gain over 5 %"
    );
    assert!(a.0 <= b.0 / 20.0, "{name}: max {} -> {}", b.0, a.0);
    assert!(rep.history.len() <= max_iterations);
    assert!(rep.converged, "{name}: stopped by {:?}", rep.stop);
    // one unknown per moved control point (one coordinate), more
    // samples than unknowns
    assert_eq!(rep.jacobian.cols, rep.modified_indices.len());
    assert!(rep.jacobian.rows >= rep.jacobian.cols);
    // every accepted step lowers Σ d_s², what the least-squares step
    // minimises (the default damping rule), and mean |d_s|
    for w in rep.history.windows(2) {
        assert!(w[1].objective < w[0].objective);
        assert!(w[1].mean_abs < w[0].mean_abs);
    }
    // Control points outside the selection: bit-identical.
    let sel: std::collections::HashSet<(usize, usize)> =
        rep.modified_indices.iter().copied().collect();
    for i in 0..c.bumped.count_u() {
        for j in 0..c.bumped.count_v() {
            let (p, q) = (c.bumped.control_point(i, j), faired.control_point(i, j));
            if !sel.contains(&(i, j)) {
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    q.to_array().map(f64::to_bits)
                );
            }
        }
    }
    assert!(rep.max_displacement > 0.0);
    // The surface outside the selected points' support: bit-identical.
    assert_bit_identical_outside_support(c, &rep, &faired, name);
    // Highlight lines inside the disc move back towards the clean ones.
    let clean_lines = pre_images(&c.clean, &c.lights, opts.grid);
    let before = deviation(
        &pre_images(&c.bumped, &c.lights, opts.grid),
        &clean_lines,
        c.centre,
        c.disc,
    );
    let after = deviation(
        &pre_images(&faired, &c.lights, opts.grid),
        &clean_lines,
        c.centre,
        c.disc,
    );
    eprintln!("{name}: pre-image deviation from the clean surface {before:.3e} -> {after:.3e}");
    assert!(
        after < 0.4 * before,
        "{name}: deviation {before} -> {after}"
    );
    // And the surface itself: normal deviation from the clean surface.
    let kb = rep.knot_box;
    let mut dev = (0.0f64, 0.0f64);
    for a in 0..=40 {
        for bb in 0..=40 {
            let u = kb[0] + (kb[1] - kb[0]) * a as f64 / 40.0;
            let v = kb[2] + (kb[3] - kb[2]) * bb as f64 / 40.0;
            let p0 = c.clean.eval(u, v);
            let nn = c.clean.normal(u, v).unwrap();
            dev.0 = dev.0.max((c.bumped.eval(u, v) - p0).dot(nn).abs());
            dev.1 = dev.1.max((faired.eval(u, v) - p0).dot(nn).abs());
        }
    }
    eprintln!(
        "{name}: normal deviation from the clean surface {:.3e} -> {:.3e}",
        dev.0, dev.1
    );
    assert!(
        dev.1 < 0.5 * dev.0,
        "{name}: surface deviation {} -> {}",
        dev.0,
        dev.1
    );
    rep
}

#[test]
fn fair_paper_method_keeps_its_guarantees_on_dome_saddle_and_roof() {
    let clean = height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let c = case(clean, (11, 7, 0.03), Vec3::new(0.0, 0.0, 3.0), 0.4, 9, 0.2);
    // The paper gives no residual, only iterations (Table 1: 5 for the
    // dome's first fairing, 4 for the saddle's, 6 for the roof's; measured
    // 4, 5 and 4). On the dome the target residual drops 90× (not 100×):
    // with one coordinate per control point, as the paper's Jacobian sizes
    // show, the least-squares floor is higher than with three (113×), since
    // the tangential moves only reparametrise the surface under the
    // parameter-space targets; the surface itself ends closer to the
    // defect-free one (normal deviation 2.4e-3 vs 3.3e-3 with three). With
    // one coordinate the paper's fixed 5 % truncation gets closer to the
    // floor as well (8.8e-4 vs 9.3e-4), so the lowered truncation gains
    // 1.7× over it on the dome (not 2×).
    check_case_paper(&c, 8, 90.0, 0.6, "dome (paper)");
    let clean = height_surface(21, 20, 1.0, 1.0, |x, y| 0.35 * (x * x - y * y));
    let c = case(clean, (6, 13, 0.02), Vec3::new(0.0, 0.0, 2.0), 0.3, 9, 0.16);
    check_case_paper(&c, 8, 500.0, 0.5, "saddle (paper)");
    let clean = height_surface(21, 22, 1.5, 1.0, |x, y| {
        0.3 - 0.12 * x * x - 0.05 * y * y + 0.02 * x * y
    });
    let c = case(
        clean,
        (8, 12, -0.015),
        Vec3::new(2.0, 1.5, 2.5),
        0.3,
        11,
        0.2,
    );
    check_case_paper(&c, 8, 300.0, 0.5, "roof (paper)");
}

/// The paper's solver converges on the dome within the paper's iteration
/// counts (Table 1: 5 and 8) with the default damping rule and with none;
/// the damping of Eq. (3.12) as printed damps nearly every step near the
/// least-squares floor and needs more. An underdetermined target set (one
/// short stretch) gets more samples until there are as many as unknowns.
#[test]
fn fair_paper_method_converges_on_the_dome_and_says_how_it_damped() {
    let clean = height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let c = case(clean, (11, 7, 0.03), Vec3::new(0.0, 0.0, 3.0), 0.4, 9, 0.2);
    let base = SurfaceFairOptions::default().method(SurfaceFairMethod::Paper);
    let endpoints = endpoints_around(&c.bumped, &c.lights, c.centre, c.disc, base.grid);
    let mut counts = Vec::new();
    for damping in PaperDamping::ALL {
        assert_eq!(PaperDamping::from_name(damping.name()), Some(damping));
        let (_, rep) = fair(
            &c.bumped,
            &c.lights,
            &endpoints,
            &base.clone().damping(damping),
        )
        .unwrap();
        eprintln!(
            "dome, damping {}: {} iterations ({:?}), mean |d_s| {:.3e} -> {:.3e}",
            damping.name(),
            rep.iterations,
            rep.stop,
            rep.residual_before.mean,
            rep.residual_after.mean
        );
        assert!(
            rep.residual_after.mean < rep.residual_before.mean / 50.0,
            "{damping:?}"
        );
        let damped = rep.history.iter().filter(|i| i.step < 1.0).count();
        match damping {
            PaperDamping::Off => assert_eq!(damped, 0),
            PaperDamping::MaxMean => assert!(damped > 0),
            PaperDamping::Residual => {}
        }
        counts.push((damping, rep.converged, rep.iterations));
    }
    assert!(counts[0].1 && counts[0].2 <= 8, "{counts:?}");
    assert!(counts[2].1 && counts[2].2 <= 8, "{counts:?}");
    assert!(counts[1].2 > counts[0].2, "{counts:?}");
    // one short stretch: fewer samples than moved control points at the
    // default spacing
    let mut short = endpoints[0];
    for k in 0..2 {
        short.end[k] = short.start[k] + 0.3 * (short.end[k] - short.start[k]);
    }
    let (_, rep) = fair(&c.bumped, &c.lights, &[short], &base).unwrap();
    let spaced = base.clone().lights(c.lights.clone()).endpoints(vec![short]);
    let at_default: usize = target_curves(&c.bumped, &spaced)
        .unwrap()
        .iter()
        .map(|t| t.samples.len())
        .sum();
    assert!(at_default < rep.jacobian.cols, "{at_default}");
    assert!(rep.jacobian.rows >= rep.jacobian.cols, "{:?}", rep.jacobian);
    assert!(rep.residual_after.mean < rep.residual_before.mean);
}

#[test]
fn fair_dome_15x15_removes_a_planted_bump() {
    let clean = height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let c = case(clean, (11, 7, 0.03), Vec3::new(0.0, 0.0, 3.0), 0.4, 9, 0.2);
    // The thin-plate energy resists the one-point correction most on the
    // dome: 0.61 of the defect's normal deviation is left (with the
    // paper's solver, 0.27, which lets other lines drift).
    let rep = check_case(&c, 80.0, 0.7, "dome");
    // The selected control points are exactly those whose support meets
    // the knot box of the endpoints.
    let kb = rep.knot_box;
    for k in kb {
        assert!(c.bumped.knots_u().contains(&k) || c.bumped.knots_v().contains(&k));
    }
    let mut all = rep.modified_indices.clone();
    all.extend(&rep.held_boundary_points);
    all.sort();
    assert_eq!(
        all,
        c.bumped.control_points_in_box(kb[0], kb[1], kb[2], kb[3])
    );
}

#[test]
fn fair_saddle_21x20_removes_a_planted_bump() {
    let clean = height_surface(21, 20, 1.0, 1.0, |x, y| 0.35 * (x * x - y * y));
    let c = case(clean, (6, 13, 0.02), Vec3::new(0.0, 0.0, 2.0), 0.3, 9, 0.16);
    check_case(&c, 300.0, 0.5, "saddle");
}

#[test]
fn fair_roof_panel_21x22_removes_a_planted_dent() {
    let clean = height_surface(21, 22, 1.5, 1.0, |x, y| {
        0.3 - 0.12 * x * x - 0.05 * y * y + 0.02 * x * y
    });
    let c = case(
        clean,
        (8, 12, -0.015),
        Vec3::new(2.0, 1.5, 2.5),
        0.3,
        11,
        0.2,
    );
    check_case(&c, 200.0, 0.5, "roof");
}

#[test]
fn fair_targets_follow_a_circle_on_a_plane() {
    // A linearly parametrised plane: the pre-image of a circular light with
    // a vertical axis is a circle; the Hermite target between two of its
    // points (tangents from the regular part, lengths = chord, Eq. (3.3))
    // stays close to the arc, with n = 2 + ⌊chord / s⌋ samples.
    let xs = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0];
    let net = (0..4)
        .map(|i| (0..4).map(|j| Vec3::new(xs[i], xs[j], 0.0)).collect())
        .collect();
    let clean = BSplineSurface::bezier(net, None).unwrap();
    let light = CircularLight::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, 0.6).unwrap();
    let to_uv = |x: f64, y: f64| [(x + 1.0) / 2.0, (y + 1.0) / 2.0];
    let (a0, a1) = (0.2f64, 1.2f64);
    let e = EndpointPair {
        radius: 0.6,
        start: to_uv(0.6 * a0.cos() + 0.003, 0.6 * a0.sin()),
        end: to_uv(0.6 * a1.cos(), 0.6 * a1.sin() - 0.002),
    };
    let opts = SurfaceFairOptions::default();
    let t = target_curves(&clean, &opts.clone().lights(vec![light]).endpoints(vec![e])).unwrap();
    assert_eq!(t.len(), 1);
    let t = &t[0];
    let chord = dist2(t.start, t.end).sqrt();
    assert_eq!(
        t.samples.len(),
        2 + (chord / (opts.sample_spacing * 2f64.sqrt())).floor() as usize
    );
    // Snapped onto the pre-image polyline of the circle of radius 0.3 (in
    // u, v): its vertices are on the circle, its chords (at most a grid
    // diagonal, 0.0071, long) within the sagitta l²/(8r) < 2.2e-5 of it.
    for p in [t.start, t.end] {
        let r = (p[0] - 0.5).hypot(p[1] - 0.5);
        assert!(r <= 0.3 + 1e-9 && r > 0.3 - 2.2e-5, "{r}");
    }
    // Tangent lengths = chord; directions = the circle's (counter-clockwise).
    for (p, tan) in [(t.start, t.tangent_start), (t.end, t.tangent_end)] {
        assert!((tan[0].hypot(tan[1]) - chord).abs() < 1e-12);
        let radial = [p[0] - 0.5, p[1] - 0.5];
        let ccw = [-radial[1], radial[0]];
        let cos = (tan[0] * ccw[0] + tan[1] * ccw[1]) / (chord * 0.3);
        assert!(cos > 0.9999, "tangent direction cos {cos}");
    }
    // The Hermite curve of a 1-radian arc with chord-length tangents stays
    // within 1.5 % of the radius from the circle.
    for p in &t.samples {
        let r = (p[0] - 0.5).hypot(p[1] - 0.5);
        assert!((r - 0.3).abs() < 0.015 * 0.3, "sample radius {r}");
    }
    assert_eq!(t.samples[0], t.start);
    // A clean surface with targets near its pre-image: fairing only needs
    // to absorb the Hermite approximation error.
    let (faired, rep) = fair(&clean, &[light], &[e], &opts).unwrap();
    assert!(rep.residual_after.mean < rep.residual_before.mean);
    assert!(faired.control_points().iter().all(|p| p.is_finite()));
}

#[test]
fn fair_bad_input_is_reported() {
    let s = height_surface(6, 6, 1.0, 1.0, |x, y| 0.1 * x * y);
    let light = CircularLight::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, 0.5).unwrap();
    let opts = SurfaceFairOptions::default();
    assert!(matches!(
        fair(&s, &[light], &[], &opts),
        Err(SurfaceFairError::Invalid(_))
    ));
    let e = EndpointPair {
        radius: 0.7,
        start: [0.2, 0.2],
        end: [0.8, 0.8],
    };
    assert!(matches!(
        fair(&s, &[light], &[e], &opts),
        Err(SurfaceFairError::NoLight { index: 0, .. })
    ));
    let e = EndpointPair {
        radius: 0.5,
        start: [f64::NAN, 0.2],
        end: [0.8, 0.8],
    };
    assert!(matches!(
        fair(&s, &[light], &[e], &opts),
        Err(SurfaceFairError::Invalid(_))
    ));
    // A light whose circle no normal line reaches: no pre-image.
    let far = CircularLight::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, 50.0).unwrap();
    let e = EndpointPair {
        radius: 50.0,
        start: [0.2, 0.2],
        end: [0.8, 0.8],
    };
    assert!(matches!(
        fair(&s, &[far], &[e], &opts),
        Err(SurfaceFairError::NoPreImage { .. })
    ));
    let bad = SurfaceFairOptions {
        truncation: 1.5,
        ..opts.clone()
    };
    let e = EndpointPair {
        radius: 0.5,
        start: [0.2, 0.2],
        end: [0.8, 0.8],
    };
    assert!(matches!(
        fair(&s, &[light], &[e], &bad),
        Err(SurfaceFairError::Invalid(_))
    ));
}

#[test]
fn fair_knot_box_snaps_outward_to_knots() {
    let s = height_surface(15, 15, 1.0, 1.0, |_, _| 0.0);
    let kb = knot_box(&s, &[[0.30, 0.52], [0.41, 0.6]]);
    let h = 1.0 / 12.0;
    assert!((kb[0] - 3.0 * h).abs() < 1e-15 && (kb[1] - 5.0 * h).abs() < 1e-15);
    assert!((kb[2] - 6.0 * h).abs() < 1e-15 && (kb[3] - 8.0 * h).abs() < 1e-15);
}

/// FNV-1a over the bits of every control point of `s` and of the report's
/// residuals and iteration objectives: a fingerprint of a fairing result.
fn fingerprint(s: &BSplineSurface, residual_after: [f64; 2], objectives: &[f64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for b in x.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for i in 0..s.count_u() {
        for j in 0..s.count_v() {
            let p = s.control_point(i, j);
            eat(p.x);
            eat(p.y);
            eat(p.z);
        }
    }
    residual_after.into_iter().for_each(&mut eat);
    objectives.iter().copied().for_each(&mut eat);
    h
}

/// `fair_surface(surface, options)` gives bit for bit the recorded
/// fingerprints of a reference implementation on the dome
/// case (both solvers); the input surface is untouched.
#[test]
fn fair_surface_is_bit_identical_to_the_recorded_reference() {
    let clean = height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let c = case(clean, (11, 7, 0.03), Vec3::new(0.0, 0.0, 3.0), 0.4, 9, 0.2);
    let recorded = [
        (SurfaceFairMethod::Regularised, 0x7541_3e89_b3a5_edd4_u64, 6),
        (SurfaceFairMethod::Paper, 0x129f_60c5_df05_5c76_u64, 4),
    ];
    for (method, expected, iterations) in recorded {
        let base = SurfaceFairOptions::default().method(method);
        let endpoints = endpoints_around(&c.bumped, &c.lights, c.centre, c.disc, base.grid);
        let input = c.bumped.clone();
        let opts = base.lights(c.lights.clone()).endpoints(endpoints);
        let out = fair_surface(&input, &opts).unwrap();
        assert_eq!(input, c.bumped);
        let rep = &out.report;
        let obj: Vec<f64> = rep.history.iter().map(|i| i.objective).collect();
        let after = [rep.residual_after.max, rep.residual_after.mean];
        assert_eq!(rep.iterations, iterations, "{method:?}");
        assert_eq!(
            fingerprint(&out.surfaces, after, &obj),
            expected,
            "{method:?}"
        );
        // the report's keys are the CLI's
        let v = serde_json::to_value(rep).unwrap();
        for key in [
            "method",
            "boundary",
            "held_boundary_points",
            "keep_samples",
            "snap_distances",
            "iterations",
            "converged",
            "stop",
            "modified_control_points",
            "modified_indices",
            "residual_before",
            "residual_after",
            "history",
            "jacobian",
            "undefined_samples",
            "knot_box",
            "max_displacement",
            "targets",
        ] {
            assert!(v.get(key).is_some(), "{key} missing: {v}");
        }
        assert_eq!(v["iterations"], iterations);
        assert_eq!(v["residual_after"]["mean"], rep.residual_after.mean);
        assert_eq!(v["targets"][0]["samples"], rep.targets[0].samples.len());
        assert_eq!(v["modified_indices"][0][1], rep.modified_indices[0].1);
    }
}

/// Raising the cancel flag stops the run at its next iteration with
/// `Cancelled`; the progress callback sees one step per iteration.
#[test]
fn fair_surface_cancels_and_reports_progress() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let clean = height_surface(15, 15, 1.0, 1.0, |x, y| 0.8 - 0.4 * (x * x + y * y));
    let c = case(clean, (11, 7, 0.03), Vec3::new(0.0, 0.0, 3.0), 0.4, 9, 0.2);
    let endpoints = endpoints_around(&c.bumped, &c.lights, c.centre, c.disc, 200);
    let flag = Arc::new(AtomicBool::new(false));
    let steps = Arc::new(AtomicUsize::new(0));
    let (f, n) = (Arc::clone(&flag), Arc::clone(&steps));
    // cancel once the second iteration starts
    let control = Control::new()
        .cancel_flag(Arc::clone(&flag))
        .on_progress(move |p| {
            assert_eq!(p.stage, "iterations");
            if n.fetch_add(1, Ordering::Relaxed) == 1 {
                f.store(true, Ordering::Relaxed);
            }
        });
    for method in [SurfaceFairMethod::Regularised, SurfaceFairMethod::Paper] {
        flag.store(false, Ordering::Relaxed);
        steps.store(0, Ordering::Relaxed);
        let opts = SurfaceFairOptions::default()
            .method(method)
            .lights(c.lights.clone())
            .endpoints(endpoints.clone())
            .control(control.clone());
        let r = fair_surface(&c.bumped, &opts);
        assert!(
            matches!(r, Err(SurfaceFairError::Cancelled(Cancelled))),
            "{method:?}: {r:?}"
        );
        assert_eq!(steps.load(Ordering::Relaxed), 2, "{method:?}");
        // raised before the run: cancelled before the first iteration
        flag.store(true, Ordering::Relaxed);
        let r = fair_surface(
            &c.bumped,
            &opts
                .clone()
                .control(Control::new().cancel_flag(Arc::clone(&flag))),
        );
        assert!(matches!(r, Err(SurfaceFairError::Cancelled(_))));
        // without a flag the same options run to the end
        assert!(fair_surface(&c.bumped, &opts.control(Control::new())).is_ok());
    }
}
