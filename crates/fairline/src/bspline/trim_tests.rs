//! Trimmed surfaces against exact constructions: a plane with a circular
//! hole, a cylinder with a hole that is a disk on the developed cylinder, and
//! a rational torus cut along a curve whose area has a closed form (Bessel
//! J0). Areas from the trimmed tessellation and from the Gauss quadrature of
//! `|Su × Sv|` over it must agree with the exact values to 0.1 %.

use std::f64::consts::PI;

use super::tests::{full_circle, torus};
use super::*;
use crate::Vec3;

/// The nine-point rational circle of radius `r` around `c` as a trim curve,
/// counter-clockwise when `ccw`.
pub(crate) fn circle_curve(c: [f64; 2], r: f64, ccw: bool) -> TrimCurve {
    let (pts, w, knots) = full_circle();
    let mut pts: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| [c[0] + r * p[0], c[1] + r * p[1]])
        .collect();
    let mut w = w;
    if !ccw {
        pts.reverse();
        w.reverse();
    }
    TrimCurve::new(2, knots, pts, Some(w)).unwrap()
}

/// A closed degree-1 curve through `pts` (first point repeated at the end).
fn polyline_curve(pts: &[[f64; 2]]) -> TrimCurve {
    let mut p = pts.to_vec();
    p.push(pts[0]);
    let n = p.len();
    let mut knots = vec![0.0];
    knots.extend((0..n).map(|k| k as f64 / (n - 1) as f64));
    knots.push(1.0);
    TrimCurve::new(1, knots, p, None).unwrap()
}

/// Area of the 3-D triangles of a tessellation.
fn mesh_area(t: &Tessellation) -> f64 {
    t.triangles
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|k| t.positions[k as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// The parameter of the nine-point unit circle at angle `theta` in
/// `[0, 2π]`, by bisection on the evaluated circle (independent of any
/// closed form of the rational parameterisation).
fn circle_param(theta: f64) -> f64 {
    let (pts, w, knots) = full_circle();
    let c = TrimCurve::new(2, knots, pts, Some(w)).unwrap();
    let angle = |t: f64| {
        let p = c.eval(t);
        let a = p[1].atan2(p[0]);
        if a < 0.0 || (t > 0.5 && a == 0.0) {
            a + 2.0 * PI
        } else {
            a
        }
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if angle(mid) < theta {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Every triangle's centroid lies in the face (slivers of rounding size,
/// below 1e-12 of the domain's area, excepted).
fn assert_inside(s: &BSplineSurface, t: &Tessellation) {
    let (du, dv) = (s.domain_u(), s.domain_v());
    let domain_area = (du[1] - du[0]) * (dv[1] - dv[0]);
    for tri in &t.triangles {
        let [a, b, c] = tri.map(|k| t.uv[k as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        assert!(
            area > 0.0,
            "triangle {a:?} {b:?} {c:?} is not counter-clockwise"
        );
        let g = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
        assert!(
            area < 1e-12 * domain_area || s.contains_uv(g[0], g[1]),
            "triangle centroid {g:?} outside the face"
        );
    }
    assert!(t.positions.iter().all(|p| p.is_finite()));
    assert!(t.normals.iter().all(|n| n.is_finite()));
}

pub(crate) fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The flat square [0,2]² with a hole of radius 1/2 (area 4 − π/4), and a
/// disk of radius 0.7 as the outer loop (area 0.49 π).
#[test]
fn bspline_trim_plane_with_circular_hole_has_exact_area() {
    let net = vec![
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)],
        vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 2.0, 0.0)],
    ];
    let plane =
        BSplineSurface::new(1, 1, vec![0., 0., 2., 2.], vec![0., 0., 2., 2.], net, None).unwrap();
    let outer = TrimLoop::polygon(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]).unwrap();
    // The hole given counter-clockwise: orientation is normalised.
    let hole = TrimLoop {
        curves: vec![circle_curve([1.1, 0.93], 0.5, true)],
    };
    let s = plane.clone().with_trims(vec![outer, hole]).unwrap();
    let exact = 4.0 - PI * 0.25;
    let dom = s.trim().unwrap();
    assert!(
        rel(dom.parameter_area(), exact) < 1e-6,
        "{}",
        dom.parameter_area()
    );
    for n in [3, 8, 17, 50, 101] {
        let t = tessellate(&s, n, n);
        assert_inside(&s, &t);
        let a = mesh_area(&t);
        assert!(rel(a, exact) < 1e-5, "grid {n}: mesh area {a} vs {exact}");
        let q = trimmed_area(&s, n, n);
        assert!(rel(q, exact) < 1e-5, "grid {n}: quadrature {q} vs {exact}");
    }
    // The grid rule (Gauss–Legendre in whole cells split
    // at the knots) is within 1e-6 of the closed form on the 64 × 64 grid of
    // `info --area`, and no further from it than the former triangle rule
    // (every triangle by the 6-point rule, cells across knots).
    let (fast, slow) = (
        trimmed_area(&s, 64, 64),
        super::trimmed_area_by_triangles(&s, 64, 64),
    );
    eprintln!(
        "grid rule {fast} (error {:.2e}), triangle rule {slow} (error {:.2e})",
        rel(fast, exact),
        rel(slow, exact)
    );
    assert!(rel(fast, exact) < 1e-6, "{fast} vs {exact}");
    assert!(
        rel(fast, exact) <= rel(slow, exact) + 1e-12,
        "{fast} vs {slow}"
    );
    // Point classification against the exact circle (away from the edge).
    let mut rng = tests::Rng::new(7);
    for _ in 0..2000 {
        let (u, v) = (1.0 + rng.unit(), 1.0 + rng.unit());
        let d = (u - 1.1).hypot(v - 0.93);
        if (d - 0.5).abs() > 1e-4 {
            assert_eq!(s.contains_uv(u, v), d > 0.5, "({u}, {v})");
        }
    }
    assert!(!s.contains_uv(2.5, 1.0));
    // A disk as the outer loop, cut by many grid lines.
    let disk = plane
        .with_trims(vec![TrimLoop {
            curves: vec![circle_curve([0.95, 1.02], 0.7, false)],
        }])
        .unwrap();
    for n in [2, 5, 33, 64] {
        let t = tessellate(&disk, n, n);
        assert_inside(&disk, &t);
        assert!(
            rel(mesh_area(&t), 0.49 * PI) < 1e-5,
            "grid {n}: {}",
            mesh_area(&t)
        );
    }
    // A disk smaller than one cell: the loop lies in a single cell.
    let tiny = disk
        .clone()
        .with_trims(vec![TrimLoop {
            curves: vec![circle_curve([0.3, 0.4], 0.05, true)],
        }])
        .unwrap();
    let t = tessellate(&tiny, 3, 3);
    // Chords within δ = TRIM_FLATNESS × diagonal of a circle of radius r
    // lose less than 2δ/r of its area.
    let bound = 2.0 * TRIM_FLATNESS * 8f64.sqrt() / 0.05;
    assert!(rel(mesh_area(&t), 0.0025 * PI) < bound, "{}", mesh_area(&t));
    assert!(bound < 1e-3);
    // A hole inside one cell of a coarse grid (bridged into the cell).
    let holed = disk
        .with_trims(vec![
            TrimLoop::polygon(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]).unwrap(),
            TrimLoop {
                curves: vec![circle_curve([0.5, 0.45], 0.1, false)],
            },
        ])
        .unwrap();
    let t = tessellate(&holed, 3, 3);
    assert_inside(&holed, &t);
    assert!(
        rel(mesh_area(&t), 4.0 - 0.01 * PI) < 1e-5,
        "{}",
        mesh_area(&t)
    );
}

/// A rational cylinder (radius 2, height 3) with a hole that is a disk of
/// radius 0.9 on the developed cylinder: area 2πRH − π·0.81 (the cylinder
/// is developable, so the disk keeps its area).
#[test]
fn bspline_trim_cylinder_with_hole_has_exact_area() {
    let (r, h) = (2.0, 3.0);
    let (c, w, knots) = full_circle();
    let net: Vec<Vec<Vec3>> = c
        .iter()
        .map(|p| {
            vec![
                Vec3::new(r * p[0], r * p[1], 0.0),
                Vec3::new(r * p[0], r * p[1], h),
            ]
        })
        .collect();
    let weights: Vec<Vec<f64>> = w.iter().map(|&x| vec![x, x]).collect();
    let cyl = BSplineSurface::new(2, 1, knots, vec![0., 0., 1., 1.], net, Some(weights)).unwrap();
    let (theta_c, z_c, rho) = (1.3, 1.4, 0.9);
    let hole: Vec<[f64; 2]> = (0..1440)
        .map(|k| {
            let t = 2.0 * PI * k as f64 / 1440.0;
            let theta = theta_c + rho / r * t.cos();
            let z = z_c + rho * t.sin();
            [circle_param(theta), z / h]
        })
        .collect();
    // The hole's pre-image really is the developed disk.
    for p in hole.iter().step_by(97) {
        let q = cyl.eval(p[0], p[1]);
        let theta = q.y.atan2(q.x);
        let d = (r * (theta - theta_c)).hypot(q.z - z_c);
        assert!((d - rho).abs() < 1e-9, "{d}");
    }
    let outer = TrimLoop::polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap();
    let s = cyl
        .with_trims(vec![
            outer,
            TrimLoop {
                curves: vec![polyline_curve(&hole)],
            },
        ])
        .unwrap();
    let exact = 2.0 * PI * r * h - PI * rho * rho;
    for n in [16, 48, 97] {
        let q = trimmed_area(&s, n, n);
        assert!(rel(q, exact) < 1e-4, "grid {n}: quadrature {q} vs {exact}");
    }
    // The grid rule (Gauss–Legendre in whole cells split
    // at the knots) is within 1e-6 of the closed form on the 64 × 64 grid of
    // `info --area`, and no further from it than the former triangle rule
    // (every triangle by the 6-point rule, cells across knots).
    let (fast, slow) = (
        trimmed_area(&s, 64, 64),
        super::trimmed_area_by_triangles(&s, 64, 64),
    );
    eprintln!(
        "grid rule {fast} (error {:.2e}), triangle rule {slow} (error {:.2e})",
        rel(fast, exact),
        rel(slow, exact)
    );
    assert!(rel(fast, exact) < 1e-6, "{fast} vs {exact}");
    assert!(
        rel(fast, exact) <= rel(slow, exact) + 1e-12,
        "{fast} vs {slow}"
    );
    let t = tessellate(&s, 200, 40);
    assert_inside(&s, &t);
    let a = mesh_area(&t);
    assert!(rel(a, exact) < 1e-3, "mesh area {a} vs {exact}");
}

/// J0(x) by its power series.
fn bessel_j0(x: f64) -> f64 {
    let mut term = 1.0;
    let mut sum = 1.0;
    for k in 1..30 {
        term *= -(x * x / 4.0) / (k as f64 * k as f64);
        sum += term;
    }
    sum
}

/// A rational torus (R = 3, r = 1) cut to `0 ≤ θ ≤ π, 0 ≤ φ ≤ π/2 + sin(θ)/2`
/// (θ around the axis, φ around the tube): area
/// `r (R (π²/2 + 1) + r π J0(1/2))`.
#[test]
fn bspline_trim_torus_cut_by_a_curve_has_exact_area() {
    let (big, small) = (3.0, 1.0);
    let s = torus(big, small);
    let g = |theta: f64| PI / 2.0 + 0.5 * theta.sin();
    let mut pts = vec![[0.0, 0.0], [0.5, 0.0]];
    let n = 2000;
    for k in 0..=n {
        let theta = PI * (1.0 - k as f64 / n as f64);
        pts.push([circle_param(theta), circle_param(g(theta))]);
    }
    // (θ = π) is u = 0.5 exactly: the 9-point circle's knot.
    assert!((circle_param(PI) - 0.5).abs() < 1e-12);
    pts[2][0] = 0.5;
    pts.last_mut().unwrap()[0] = 0.0;
    let s = s
        .with_trims(vec![TrimLoop {
            curves: vec![polyline_curve(&pts)],
        }])
        .unwrap();
    let exact = small * (big * (PI * PI / 2.0 + 1.0) + small * PI * bessel_j0(0.5));
    for n in [9, 33, 65] {
        let q = trimmed_area(&s, n, n);
        assert!(rel(q, exact) < 1e-4, "grid {n}: quadrature {q} vs {exact}");
    }
    // The grid rule (Gauss–Legendre in whole cells split
    // at the knots) is within 1e-6 of the closed form on the 64 × 64 grid of
    // `info --area`, and no further from it than the former triangle rule
    // (every triangle by the 6-point rule, cells across knots).
    let (fast, slow) = (
        trimmed_area(&s, 64, 64),
        super::trimmed_area_by_triangles(&s, 64, 64),
    );
    eprintln!(
        "grid rule {fast} (error {:.2e}), triangle rule {slow} (error {:.2e})",
        rel(fast, exact),
        rel(slow, exact)
    );
    assert!(rel(fast, exact) < 1e-6, "{fast} vs {exact}");
    assert!(
        rel(fast, exact) <= rel(slow, exact) + 1e-12,
        "{fast} vs {slow}"
    );
    let t = tessellate(&s, 129, 129);
    assert_inside(&s, &t);
    let a = mesh_area(&t);
    assert!(rel(a, exact) < 1e-3, "mesh area {a} vs {exact}");
    // The face's 3-D points satisfy the cut.
    for p in t.positions.iter().step_by(37) {
        let theta = p.y.atan2(p.x);
        let rho = p.x.hypot(p.y) - big;
        let phi = p.z.atan2(rho);
        assert!((-1e-9..=PI + 1e-9).contains(&theta), "{theta}");
        assert!(phi >= -1e-6 && phi <= g(theta) + 1e-3, "{phi} {}", g(theta));
    }
}

/// Area of a face by the midpoint rule on an `m × m` grid of the whole
/// domain, counting only the cell centres inside the loops (even–odd count
/// of the loops' crossings of each row): independent of the trimmed
/// tessellation's clipping and of its quadrature.
pub(crate) fn midpoint_area(s: &BSplineSurface, m: usize) -> f64 {
    use rayon::prelude::*;
    let (du, dv) = (s.domain_u(), s.domain_v());
    let (hu, hv) = ((du[1] - du[0]) / m as f64, (dv[1] - dv[0]) / m as f64);
    let rows: Vec<f64> = (0..m)
        .into_par_iter()
        .map(|b| {
            let v = dv[0] + (b as f64 + 0.5) * hv;
            let xs = s.trim().map(|t| t.row_crossings(v));
            let mut sum = 0.0;
            for a in 0..m {
                let u = du[0] + (a as f64 + 0.5) * hu;
                let inside = xs
                    .as_ref()
                    .is_none_or(|xs| xs.partition_point(|&x| x < u) % 2 == 1);
                if inside {
                    let d = s.derivatives(u, v);
                    sum += d.su.cross(d.sv).length() * hu * hv;
                }
            }
            sum
        })
        .collect();
    rows.iter().sum()
}

/// Whether the triangles of `t` make a mesh (no edge of three faces).
fn builds_a_mesh(t: &Tessellation) -> Result<(), crate::MeshError> {
    crate::SurfaceMesh::new(t.positions.clone(), &t.triangles).map(|_| ())
}

/// A trimming loop through a point one ulp off a grid corner on the
/// domain's border (as featuretype.STEP's plane faces have, their loops
/// computed in floating point) must not become a second vertex beside the
/// corner: the clipped cell's ear clipping would make a sliver on the
/// corner's edge, shared by three faces, and the part could not be drawn
/// ("edge … is non-manifold"). Loop points within 1e-9 of a cell of a grid
/// line are moved onto it: the tessellation is a mesh on every grid, the
/// corner is one vertex, and the area is still the polygon's.
#[test]
fn a_loop_point_one_ulp_off_a_grid_corner_gives_a_manifold_tessellation() {
    let net = vec![
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
        vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0)],
    ];
    let plane =
        BSplineSurface::new(1, 1, vec![0., 0., 1., 1.], vec![0., 0., 1., 1.], net, None).unwrap();
    let below_half = f64::from_bits(0.5f64.to_bits() - 1);
    let corners = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, below_half],
        [0.6, 0.8],
        [0.0, 1.0],
    ];
    let s = plane
        .with_trims(vec![TrimLoop::polygon(&corners).unwrap()])
        .unwrap();
    let exact = 0.5 * polygon_signed_area2(&corners);
    for n in [3, 5, 9, 17, 33] {
        let t = tessellate(&s, n, n);
        builds_a_mesh(&t).unwrap_or_else(|e| panic!("grid {n}: {e}"));
        assert_inside(&s, &t);
        let near_corner =
            t.uv.iter()
                .filter(|p| (p[0] - 1.0).abs() < 1e-12 && (p[1] - 0.5).abs() < 1e-12)
                .count();
        assert_eq!(
            near_corner, 1,
            "grid {n}: the corner (1, 0.5) is one vertex"
        );
        let a = mesh_area(&t);
        assert!(rel(a, exact) < 1e-12, "grid {n}: area {a} vs {exact}");
    }
}

/// The real case: every face of trimesh's featuretype.STEP (SolidWorks,
/// 96 faces) tessellates into a mesh on the grids of a part picture and of
/// the light choice, for parts sampled with 10 to 320 points along the
/// diagonal (before: faces 4, 17, 31 and 61 failed on 40 of those grids).
#[test]
fn every_face_of_featuretype_step_tessellates_into_a_mesh() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/step/featuretype.STEP");
    let part: Vec<BSplineSurface> = crate::io::step::read_step(&path)
        .unwrap()
        .surfaces
        .into_iter()
        .map(|s| s.surface)
        .collect();
    assert_eq!(part.len(), 96);
    let diagonal = control_diagonal(&part);
    let mut failed = Vec::new();
    for n in (10..=320).step_by(3) {
        for (k, s) in part.iter().enumerate() {
            let [nu, nv] = patch_grid(s, diagonal, n);
            if let Err(e) = builds_a_mesh(&tessellate(s, nu, nv)) {
                failed.push(format!("n {n}, face {k}: {e}"));
            }
        }
    }
    assert!(
        failed.is_empty(),
        "{} failures: {:?}",
        failed.len(),
        &failed[..failed.len().min(5)]
    );
}

/// A part whose triangles have an edge of three faces is still made into a
/// mesh ([`part_mesh`]): the edge is cut open, the repeated triangle left
/// out, and every kept face keeps its patch.
#[test]
fn a_part_with_a_non_manifold_edge_is_made_into_a_mesh_with_its_patches() {
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.5, 1.0, 0.0),
        Vec3::new(0.5, -1.0, 0.0),
        Vec3::new(0.5, 0.0, 1.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(3.0, 1.0, 0.0),
    ];
    // faces 0, 1, 2 share the edge (0, 1); face 3 repeats face 0; face 4 is
    // a patch of its own
    let tris = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 2, 0], [5, 6, 7]];
    assert!(crate::SurfaceMesh::new(p.clone(), &tris).is_err());
    let (mesh, patch) = part_mesh(p, &tris, vec![0, 0, 1, 1, 2]).unwrap();
    assert_eq!(mesh.face_count(), 4, "the repeated triangle is left out");
    assert_eq!(patch, vec![0, 0, 1, 2]);
}

#[test]
fn trim_curve_second_derivative_gives_the_circle_curvature() {
    // On the rational circle of radius 2: c'' against differences of c',
    // and the curvature |c' × c''| / |c'|³ is 1/2 everywhere.
    let c = circle_curve([0.5, -0.25], 2.0, true);
    let [a, b] = c.domain();
    for i in 1..40 {
        let t = a + (b - a) * (i as f64 + 0.3) / 40.0;
        let (p, d1, d2) = c.eval_d2(t, false);
        assert_eq!((p, d1), c.eval_d1(t, false));
        let h = 1e-6;
        let (q0, q1) = (c.eval_d1(t - h, false).1, c.eval_d1(t + h, false).1);
        let fd = [(q1[0] - q0[0]) / (2.0 * h), (q1[1] - q0[1]) / (2.0 * h)];
        let err = (d2[0] - fd[0]).hypot(d2[1] - fd[1]);
        assert!(
            err < 1e-5 * (1.0 + d2[0].hypot(d2[1])),
            "t {t}: {d2:?} vs {fd:?}"
        );
        let speed = d1[0].hypot(d1[1]);
        let kappa = (d1[0] * d2[1] - d1[1] * d2[0]).abs() / speed.powi(3);
        assert!((kappa - 0.5).abs() < 1e-12, "t {t}: κ {kappa}");
    }
}

#[test]
fn trim_curve_derivative_matches_differences_and_takes_the_side_asked_for() {
    // A rational circle: the derivative against central differences
    // (step 1e-6, error O(h²) ≈ 1e-11 times the curvature terms), and
    // tangent to the circle.
    let c = circle_curve([0.5, -0.25], 2.0, true);
    let [a, b] = c.domain();
    for i in 1..40 {
        let t = a + (b - a) * (i as f64 + 0.3) / 40.0;
        let (p, d) = c.eval_d1(t, false);
        let e = c.eval(t);
        assert!((p[0] - e[0]).hypot(p[1] - e[1]) < 1e-14, "{p:?} vs {e:?}");
        let h = 1e-6;
        let (q0, q1) = (c.eval(t - h), c.eval(t + h));
        let fd = [(q1[0] - q0[0]) / (2.0 * h), (q1[1] - q0[1]) / (2.0 * h)];
        let err = (d[0] - fd[0]).hypot(d[1] - fd[1]);
        assert!(
            err < 1e-6 * (1.0 + d[0].hypot(d[1])),
            "t {t}: {d:?} vs {fd:?}"
        );
        let radial = [p[0] - 0.5, p[1] + 0.25];
        assert!((radial[0] * d[0] + radial[1] * d[1]).abs() < 1e-12 * d[0].hypot(d[1]) * 2.0);
    }
    // A polyline's corner: the derivative of the segment arriving with
    // `left`, of the one leaving without; the ends use their own segments.
    let l = TrimCurve::new(
        1,
        vec![0.0, 0.0, 1.0, 3.0, 3.0],
        vec![[0.0, 0.0], [2.0, 1.0], [2.0, 5.0]],
        None,
    )
    .unwrap();
    assert_eq!(l.eval_d1(1.0, true).1, [2.0, 1.0]);
    assert_eq!(l.eval_d1(1.0, false).1, [0.0, 2.0]);
    assert_eq!(l.eval_d1(0.0, true).1, [2.0, 1.0]);
    assert_eq!(l.eval_d1(3.0, false).1, [0.0, 2.0]);
    let corner = l.eval_d1(1.0, true).0;
    assert!((corner[0] - 2.0).abs() < 1e-15 && (corner[1] - 1.0).abs() < 1e-15);
}
