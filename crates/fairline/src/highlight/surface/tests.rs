//! Highlight lines of B-spline surfaces against closed forms: circles on a
//! plane under a circular light, latitude circles on an exact rational
//! sphere with the light on its axis, straight lines on a plane under a
//! linear light; every refined contour point on the true zero level; real
//! surfaces (teapot JSON, impeller IGES).

use super::*;
use crate::bspline::tests::sphere_octant;
use crate::bspline::{BSplineSurface, read_iges, read_surfaces_json};
use crate::highlight::{CircularLight, LightArray};

/// The plane z = 0 over [-2, 2]² as a bicubic Bézier patch (non-uniform
/// inner control points so the parametrisation is not linear).
fn plane() -> BSplineSurface {
    let xs = [-2.0, -0.9, 0.4, 2.0];
    let net = (0..4)
        .map(|i| (0..4).map(|j| Vec3::new(xs[i], xs[j], 0.0)).collect())
        .collect();
    BSplineSurface::bezier(net, None).unwrap()
}

fn data(path: &str) -> Option<std::path::PathBuf> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/surfaces")
        .join(path);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: ../shared/data not found");
        None
    }
}

#[test]
fn surface_circular_lines_on_a_plane_are_circles() {
    let s = plane();
    let c = Vec3::new(0.3, -0.2, 1.5);
    let light = SurfaceLight::Circular(CircularLight::new(c, Vec3::Z, 1.0).unwrap());
    let h = surface_highlight_lines(&s, &[light], &SurfaceHighlightOptions::default().grid(120));
    assert_eq!(h.lines.len(), 1, "one closed circle");
    let l = &h.lines[0];
    assert!(l.closed);
    assert!(l.points.len() > 100);
    for (p, uv) in l.points.iter().zip(&l.uv) {
        // The normal line is vertical: d_s = 0 exactly on the circle of
        // radius R around the light's axis.
        let r = (p.x - c.x).hypot(p.y - c.y);
        assert!((r - 1.0).abs() < 1e-9, "radius {r}");
        let d = surface_signed_distance(&s, &light, uv[0], uv[1]).unwrap();
        assert!(d.abs() <= 1e-9, "|d_s| = {d}");
        assert_eq!(*p, s.eval(uv[0], uv[1]));
    }
}

#[test]
fn surface_circular_lines_on_a_sphere_are_latitudes() {
    let r = 2.0;
    let s = sphere_octant(r);
    let (h, big_r) = (3.0, 1.5);
    let light = CircularLight::new(Vec3::new(0.0, 0.0, h), Vec3::Z, big_r).unwrap();
    let lights = [SurfaceLight::Circular(light)];
    let opts = SurfaceHighlightOptions::default()
        .grid(150)
        .band(Some(0.05));
    let out = surface_highlight_lines(&s, &lights, &opts);
    assert_eq!(out.lines.len(), 1);
    let l = &out.lines[0];
    assert!(
        !l.closed,
        "an octant holds a quarter of the latitude circle"
    );
    // Normal lines pass through the centre: they meet the circle where the
    // polar direction is that of (R, h).
    let cos_polar = h / big_r.hypot(h);
    for (p, uv) in l.points.iter().zip(&l.uv) {
        assert!((p.z / p.length() - cos_polar).abs() < 1e-9, "{p}");
        assert!(
            surface_signed_distance(&s, &lights[0], uv[0], uv[1])
                .unwrap()
                .abs()
                <= 1e-9
        );
    }
    // The quarter circle spans the octant: from the xz plane to the yz plane.
    let (a, b) = (l.points[0], *l.points.last().unwrap());
    assert!(a.x.abs().min(a.y.abs()) < 1e-9 && b.x.abs().min(b.y.abs()) < 1e-9);
    // Bands: one line each side, on the levels ±ρ, at different latitudes.
    assert_eq!(out.band_lower.len(), 1);
    assert_eq!(out.band_upper.len(), 1);
    for (band, level) in [(&out.band_lower, -0.05), (&out.band_upper, 0.05)] {
        for uv in &band[0].uv {
            let d = surface_signed_distance(&s, &lights[0], uv[0], uv[1]).unwrap();
            assert!((d - level).abs() <= 1e-9, "{d} vs {level}");
        }
    }
    let z = |ls: &[SurfaceHighlightLine]| ls[0].points[0].z / ls[0].points[0].length();
    assert!((z(&out.band_lower) - z(&out.band_upper)).abs() > 1e-3);
}

#[test]
fn surface_linear_lines_on_a_plane_are_straight_and_spaced() {
    let s = plane();
    let array = LightArray::new(Vec3::new(0.0, 0.0, 4.0), Vec3::Z, Vec3::X, 0.5).unwrap();
    let lights: Vec<SurfaceLight> = (-3..=3)
        .map(|m| SurfaceLight::Linear {
            array,
            index: m,
            min_cos: 0.05,
        })
        .collect();
    let out = surface_highlight_lines(&s, &lights, &SurfaceHighlightOptions::default().grid(60));
    assert_eq!(out.lines.len(), 7);
    for l in &out.lines {
        let m = l.light as f64 - 3.0;
        for p in &l.points {
            // Vertical normals: the light is seen straight up; the line of
            // light m is y = A0.y + m s (sign of Yong et al. Eq. (1) as
            // corrected in DESIGN.md §3, checked against the library).
            let d = array.highlight_distance(*p, Vec3::Z, 0.05).unwrap();
            assert!((d - m * 0.5).abs() < 1e-9);
            assert!((p.y.abs() - (m * 0.5).abs()).abs() < 1e-9, "{p} m {m}");
        }
    }
}

#[test]
fn surface_lines_are_deterministic_and_undefined_cells_are_skipped() {
    let s = sphere_octant(1.0);
    // Light on the axis through the pole: the pole's normal line is the
    // axis, where d_s is undefined; no NaN may appear anywhere.
    let light =
        SurfaceLight::Circular(CircularLight::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, 0.3).unwrap());
    let opts = SurfaceHighlightOptions::default().grid(80);
    let a = surface_highlight_lines(&s, &[light], &opts);
    let b = surface_highlight_lines(&s, &[light], &opts);
    assert_eq!(a, b);
    assert!(!a.lines.is_empty());
    for l in &a.lines {
        assert!(l.points.iter().all(|p| p.is_finite()));
        assert!(l.uv.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
    }
    let f = distance_field(&s, &light, 2, 2);
    assert_eq!(f.samples.len(), 4);
}

#[test]
fn surface_lines_on_the_teapot_and_the_impeller() {
    let Some(tp) = data("teapot.json") else {
        return;
    };
    let teapot = read_surfaces_json(&tp).unwrap();
    let light =
        SurfaceLight::Circular(CircularLight::new(Vec3::new(0.0, 0.0, 6.0), Vec3::Z, 3.0).unwrap());
    let opts = SurfaceHighlightOptions::default().grid(60);
    let (mut total, mut worst) = (0, Vec::new());
    for patch in &teapot {
        let out = surface_highlight_lines(patch, &[light], &opts);
        for l in &out.lines {
            total += l.uv.len();
            for uv in &l.uv {
                let d = surface_signed_distance(patch, &light, uv[0], uv[1]).unwrap();
                worst.push(d.abs());
            }
        }
    }
    worst.sort_by(f64::total_cmp);
    assert!(total > 200, "teapot lines: {total} points");
    let q = |f: f64| worst[((worst.len() - 1) as f64 * f) as usize];
    eprintln!(
        "teapot |d_s| at contour points: median {:e}, 99% {:e}, max {:e}",
        q(0.5),
        q(0.99),
        q(1.0)
    );
    assert!(
        q(1.0) <= 1e-9,
        "teapot |d_s| quantiles {:e} {:e} {:e}",
        q(0.5),
        q(0.99),
        q(1.0)
    );
    let Some(ip) = data("impeller.igs") else {
        return;
    };
    let imp = read_iges(&ip).unwrap();
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for s in &imp.surfaces {
        let (a, b) = s.surface.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diag = (hi - lo).length();
    let centre = 0.5 * (lo + hi);
    let light = SurfaceLight::Circular(
        CircularLight::new(centre + 0.8 * diag * Vec3::Z, Vec3::Z, 0.3 * diag).unwrap(),
    );
    let mut lines = 0;
    for s in imp.surfaces.iter().take(60) {
        let out = surface_highlight_lines(
            &s.surface,
            &[light],
            &SurfaceHighlightOptions::default().grid(40),
        );
        for l in &out.lines {
            assert!(l.points.iter().all(|p| p.is_finite()));
        }
        lines += out.lines.len();
    }
    assert!(lines > 0, "impeller: no highlight lines");
}

#[test]
fn scratch_teapot_far() {
    let Some(tp) = data("teapot.json") else { return; };
    let teapot = read_surfaces_json(&tp).unwrap();
    for (cz, rad) in [(40.0, 20.0), (60.0, 30.0), (100.0, 25.0), (30.0, 25.0)] {
        let light = CircularLight::new(Vec3::new(0.5, 0.3, cz), Vec3::new(0.1, 0.2, 1.0), rad).unwrap();
        let (mut flips, mut nones, mut tot) = (0, 0, 0);
        for patch in &teapot {
            let f = distance_field(patch, &SurfaceLight::Circular(light), 200, 200);
            let _ = &f;
            let [u0, u1] = patch.domain_u();
            let [v0, v1] = patch.domain_v();
            for i in 0..40 {
                let u = u0 + (u1 - u0) * (i as f64 + 0.5) / 40.0;
                let mut prev: Option<(f64, f64)> = None;
                for j in 0..=400 {
                    let v = v0 + (v1 - v0) * j as f64 / 400.0;
                    let d = patch.derivatives(u, v);
                    tot += 1;
                    let a = light.approach(d.point, d.normal().unwrap_or(Vec3::ZERO));
                    match a {
                        None => { nones += 1; if nones < 5 { println!("none at {u} {v}"); } prev = None; }
                        Some(a) => {
                            if let Some((pd, pt)) = prev {
                                if (a.theta - pt).cos() > 0.99 && pd * a.signed_distance < 0.0 && pd.abs() > 0.5 {
                                    flips += 1;
                                    if flips < 5 { println!("flip {pd} -> {} th {pt} {}", a.signed_distance, a.theta); }
                                }
                            }
                            prev = Some((a.signed_distance, a.theta));
                        }
                    }
                }
            }
        }
        println!("light cz={cz} r={rad}: flips {flips} nones {nones} of {tot}");
    }
}

/// min over θ of the distance between the circle point L(θ) and the line
/// Q + τN, by dense sampling of θ refined by golden-section search: the
/// ground truth for the nearest stationary point of Eq. (2.15).
fn brute_min_distance(light: &CircularLight, q: Vec3, n: Vec3) -> f64 {
    let n = n.normalize();
    let dist = |t: f64| (light.point(t) - q).cross(n).length();
    let m = 3600;
    let step = std::f64::consts::TAU / m as f64;
    let k = (0..m)
        .min_by(|&i, &j| dist(i as f64 * step).total_cmp(&dist(j as f64 * step)))
        .unwrap();
    let (mut a, mut b) = ((k as f64 - 1.0) * step, (k as f64 + 1.0) * step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let (x1, x2) = (b - g * (b - a), a + g * (b - a));
        if dist(x1) < dist(x2) {
            b = x2;
        } else {
            a = x1;
        }
    }
    dist(0.5 * (a + b))
}

/// Distant lights on the teapot (|ε| ≫ R, nearly merged quartic roots):
/// every sample's |d_s| is the global minimum distance between the normal
/// line and the circle, and d_s along parameter lines has no sign flip while
/// the nearest circle point θ moves continuously (both were broken when the
/// quartic coefficients of Eq. (2.16) were formed about Q instead of the
/// line point nearest the centre).
#[test]
fn teapot_distant_light_distance_is_global_minimum_and_continuous() {
    let Some(tp) = data("teapot.json") else {
        return;
    };
    let teapot = read_surfaces_json(&tp).unwrap();
    for (cz, rad) in [(40.0, 20.0), (60.0, 30.0), (100.0, 25.0)] {
        let light =
            CircularLight::new(Vec3::new(0.5, 0.3, cz), Vec3::new(0.1, 0.2, 1.0), rad).unwrap();
        let (mut flips, mut worst) = (0, 0.0f64);
        for patch in &teapot {
            let [u0, u1] = patch.domain_u();
            let [v0, v1] = patch.domain_v();
            for i in 0..12 {
                let u = u0 + (u1 - u0) * (i as f64 + 0.5) / 12.0;
                let mut prev: Option<(f64, f64)> = None;
                for j in 0..=200 {
                    let v = v0 + (v1 - v0) * (j as f64 + 0.5) / 201.0;
                    let d = patch.derivatives(u, v);
                    let Some(nrm) = d.normal() else {
                        prev = None;
                        continue;
                    };
                    let a = light.approach(d.point, nrm).expect("defined off the axis");
                    if j % 10 == 0 {
                        let truth = brute_min_distance(&light, d.point, nrm);
                        worst = worst.max((a.signed_distance.abs() - truth).abs());
                    }
                    if let Some((pd, pt)) = prev
                        && (a.theta - pt).cos() > 0.99
                        && pd * a.signed_distance < 0.0
                        && (pd - a.signed_distance).abs() > 0.5
                    {
                        flips += 1;
                    }
                    prev = Some((a.signed_distance, a.theta));
                }
            }
        }
        assert!(worst < 1e-7, "light z={cz}: |d_s| off the true minimum by {worst:e}");
        assert_eq!(flips, 0, "light z={cz}: spurious sign flips of d_s");
    }
}
