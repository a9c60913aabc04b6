//! Tests of structure-line fairing and fair polyline networks.

use super::*;
use crate::shapes;
use crate::smooth::{LaplaceOptions, TaubinOptions, laplace_smooth, taubin_smooth};
use crate::{Cancelled, Control};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Fairs `mesh` in place with the chosen solver (the tests compare meshes).
fn fair_in_place_with(
    mesh: &mut SurfaceMesh,
    options: &QuadFairOptions,
    method: Method,
) -> Result<QuadFairReport, QuadFairError> {
    let out = fair_structure_lines_with(mesh, options, method)?;
    mesh.set_positions(out.positions)?;
    Ok(out.report)
}

/// [`fair_in_place_with`] with the default solver choice.
fn fair_in_place(
    mesh: &mut SurfaceMesh,
    options: &QuadFairOptions,
) -> Result<QuadFairReport, QuadFairError> {
    let out = fair_structure_lines(mesh, options)?;
    mesh.set_positions(out.positions)?;
    Ok(out.report)
}

/// The one algorithm shape: the input is untouched, progress
/// comes once per iteration, and raising the cancel flag stops the run
/// with the Cancelled error (here after the first iteration).
#[test]
fn fairing_reports_progress_and_stops_when_cancelled() {
    let (_, zz) = zigzag_grid(16, 16, 0.2, |x, y| 0.3 * (x * x - y * y));
    let before = zz.positions().to_vec();
    let flag = Arc::new(AtomicBool::new(false));
    let raise = Arc::clone(&flag);
    let steps = Arc::new(std::sync::Mutex::new(Vec::new()));
    let seen = Arc::clone(&steps);
    let control = Control::new()
        .cancel_flag(Arc::clone(&flag))
        .on_progress(move |p| {
            if let Ok(mut v) = seen.lock() {
                v.push((p.stage, p.done, p.total));
            }
            if p.done >= 1 {
                raise.store(true, Ordering::Relaxed);
            }
        });
    let options = QuadFairOptions::default().iterations(3).control(control);
    assert_eq!(
        fair_structure_lines(&zz, &options),
        Err(QuadFairError::Cancelled(Cancelled))
    );
    assert_eq!(zz.positions(), &before[..]);
    let steps = steps.lock().map(|v| v.clone()).unwrap_or_default();
    assert_eq!(steps, vec![("iterations", 0, 3), ("iterations", 1, 3)]);
    // without cancelling: every iteration reports, then the end
    let all = Arc::new(std::sync::Mutex::new(0u64));
    let count = Arc::clone(&all);
    let control = Control::new().on_progress(move |_| {
        if let Ok(mut c) = count.lock() {
            *c += 1;
        }
    });
    let out = fair_structure_lines(&zz, &QuadFairOptions::default().control(control)).unwrap();
    assert_eq!(all.lock().map(|c| *c).unwrap_or(0), 4);
    assert_eq!(out.report.iterations, 3);
    assert_eq!(out.report.vertices, zz.vertex_count());
    assert_eq!(zz.positions(), &before[..]);
}

/// Quad grid of `truth` over [−1, 1]² with a planted zigzag: interior
/// vertices shifted alternately ±δ·h across the lines of constant i
/// (and, weaker, of constant j). Returns (truth mesh, zigzag mesh).
pub(crate) fn zigzag_grid(
    nx: u32,
    ny: u32,
    delta: f64,
    truth: impl Fn(f64, f64) -> f64,
) -> (SurfaceMesh, SurfaceMesh) {
    let t = shapes::quad_grid(nx, ny, (-1.0, 1.0), (-1.0, 1.0), &truth);
    let mut z = t.clone();
    let hx = 2.0 / (nx - 1) as f64;
    let hy = 2.0 / (ny - 1) as f64;
    for (k, p) in z.positions_mut().iter_mut().enumerate() {
        let (i, j) = (k as u32 % nx, k as u32 / nx);
        if i == 0 || j == 0 || i == nx - 1 || j == ny - 1 {
            continue;
        }
        let sx = if j % 2 == 0 { 1.0 } else { -1.0 };
        let sy = if i % 2 == 0 { 1.0 } else { -1.0 };
        let (x, y) = (p.x + sx * delta * hx, p.y + 0.5 * sy * delta * hy);
        *p = Vec3::new(x, y, truth(x, y));
    }
    (t, z)
}

fn mean_dist(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
    a.positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| p.distance(*q))
        .sum::<f64>()
        / a.vertex_count() as f64
}

fn boundary_drift(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
    a.vertices()
        .filter(|v| a.is_boundary_vertex(*v))
        .map(|v| a.position(v).distance(b.position(v)))
        .fold(0.0, f64::max)
}

#[test]
fn zigzag_structure_lines_are_straightened_closer_to_the_truth_than_laplace_and_taubin() {
    type Surface = Box<dyn Fn(f64, f64) -> f64>;
    let cases: Vec<(u32, u32, Surface)> = vec![
        (10, 10, Box::new(|x, y| 0.4 * (x * x - y * y))),
        (
            13,
            13,
            Box::new(|x, y| 0.3 * (1.5 * x).sin() * (1.0 + 0.5 * y * y) + 0.2 * x * y),
        ),
        (
            22,
            41,
            Box::new(|x, y| 0.5 * (1.0 - 0.3 * x * x) * (0.8 * y).cos()),
        ),
    ];
    for (nx, ny, f) in cases {
        let (truth, zz) = zigzag_grid(nx, ny, 0.2, &f);
        let mut ours = zz.clone();
        let r = fair_in_place(&mut ours, &QuadFairOptions::default()).unwrap();
        let mut lap = zz.clone();
        let out = laplace_smooth(&lap, &LaplaceOptions::default().iterations(10)).unwrap();
        lap.set_positions(out.positions).unwrap();
        let mut tau = zz.clone();
        let out = taubin_smooth(&tau, &TaubinOptions::default().iterations(10)).unwrap();
        tau.set_positions(out.positions).unwrap();
        let (e_l, e_t) = (structure_energy(&lap), structure_energy(&tau));
        let (d_ours, d_lap, d_tau) = (
            mean_dist(&ours, &truth),
            mean_dist(&lap, &truth),
            mean_dist(&tau, &truth),
        );
        let (b_ours, b_lap, b_tau) = (
            boundary_drift(&ours, &zz),
            boundary_drift(&lap, &zz),
            boundary_drift(&tau, &zz),
        );
        let what = format!(
            "{nx}×{ny}: E {:.3e}→{:.3e} (Laplace {e_l:.3e}, Taubin {e_t:.3e}); distance to truth {d_ours:.3e} (Laplace {d_lap:.3e}, Taubin {d_tau:.3e}, input {:.3e}); boundary drift {b_ours:.3e} ({b_lap:.3e}, {b_tau:.3e})",
            r.structure_energy_before,
            r.structure_energy_after,
            mean_dist(&zz, &truth)
        );
        // the zigzag is gone: Eq. (30) energy drops by more than 100×,
        // below that of Laplace and Taubin (at least as smooth) ...
        assert!(
            r.structure_energy_after < 0.01 * r.structure_energy_before,
            "{what}"
        );
        assert!(r.structure_energy_after < e_l.min(e_t), "{what}");
        // ... while moving toward the truth, closer than both, and
        // keeping the boundary where Laplace and Taubin pull it in
        assert!(
            d_ours < mean_dist(&zz, &truth) && d_ours < d_lap.min(d_tau),
            "{what}"
        );
        assert!(b_ours < 0.5 * b_lap.min(b_tau), "{what}");
        assert!(
            r.free_vertices > 0 && r.structure_lines == (nx + ny) as usize,
            "{what}"
        );
    }
}

/// The line-preconditioned conjugate gradients (used above
/// [`DIRECT_LIMIT`] free vertices) and Cholesky solve the same normal
/// equations: on a 60 × 60 zigzag grid with a few fixed vertices the
/// fairings agree to 1e-6 of the mean edge length at every vertex (the
/// stopping rule bounds the RMS error of each solve by 1e-7·ē), reach
/// the same Eq. (30) energy, keep the fixed vertices and corners
/// bit-identical, and the iteration is deterministic and does not
/// depend on where the mesh sits in space.
#[test]
fn iterative_and_cholesky_solves_give_the_same_fairing() {
    let (_, zz) = zigzag_grid(60, 60, 0.2, |x, y| 0.3 * (x * x - y * y) + 0.1 * x);
    let ebar = crate::geom::mean_edge_length(&zz);
    let fixed = [VertexId(61), VertexId(1234), VertexId(2000)];
    let o = QuadFairOptions {
        fixed: fixed.to_vec(),
        ..Default::default()
    };
    let mut direct = zz.clone();
    let rd = fair_in_place_with(&mut direct, &o, Method::Direct).unwrap();
    let mut it = zz.clone();
    let ri = fair_in_place_with(&mut it, &o, Method::Iterative).unwrap();
    let worst = max_distance(&direct, &it);
    assert!(
        worst <= 1e-6 * ebar,
        "iterative vs Cholesky: {worst:e} (ē = {ebar})"
    );
    assert_eq!(rd.free_vertices, ri.free_vertices);
    assert!(rd.free_vertices > 3000, "{rd:?}");
    assert!(ri.structure_energy_after < 0.01 * ri.structure_energy_before);
    assert!(
        (ri.structure_energy_after - rd.structure_energy_after).abs()
            <= 1e-4 * rd.structure_energy_after,
        "{ri:?} vs {rd:?}"
    );
    for v in fixed.into_iter().chain([0, 59, 3540, 3599].map(VertexId)) {
        assert_eq!(it.position(v), zz.position(v));
    }
    let mut again = zz.clone();
    fair_in_place_with(&mut again, &o, Method::Iterative).unwrap();
    assert_eq!(again.positions(), it.positions(), "deterministic");
    let shift = Vec3::new(1e4, -2e4, 3e4);
    let mut far = zz.clone();
    for p in far.positions_mut() {
        *p += shift;
    }
    fair_in_place_with(&mut far, &o, Method::Iterative).unwrap();
    for (p, q) in far.positions().iter().zip(it.positions()) {
        assert!((*p - shift).distance(*q) <= 1e-6 * ebar);
    }
}

/// The same agreement on a mesh whose structure lines cannot be split
/// into two families of non-crossing lines: three faces of a cube
/// meeting at an interior vertex of valence 3, with noise. Lines bend
/// around the cube edges and three kinds of lines cross pairwise, so the
/// preconditioner keeps some crossings within one family.
#[test]
fn iterative_solve_agrees_with_cholesky_around_an_irregular_vertex() {
    let n = 24u32;
    let mut index = std::collections::HashMap::new();
    let mut pos = Vec::new();
    let mut faces: Vec<[u32; 4]> = Vec::new();
    let mut state = 0x2545f4914f6cdd1du64;
    let mut vid = |l: [u32; 3], pos: &mut Vec<Vec3>| -> u32 {
        *index.entry(l).or_insert_with(|| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.3;
            let p = Vec3::new(l[0] as f64, l[1] as f64, l[2] as f64) / n as f64;
            pos.push(p + Vec3::splat(noise / n as f64));
            (pos.len() - 1) as u32
        })
    };
    for a in 0..n {
        for b in 0..n {
            let quads = [
                [[0, a, b], [0, a + 1, b], [0, a + 1, b + 1], [0, a, b + 1]],
                [[a, 0, b], [a, 0, b + 1], [a + 1, 0, b + 1], [a + 1, 0, b]],
                [[a, b, 0], [a + 1, b, 0], [a + 1, b + 1, 0], [a, b + 1, 0]],
            ];
            for q in quads {
                faces.push(q.map(|l| vid(l, &mut pos)));
            }
        }
    }
    let mesh = SurfaceMesh::new(pos, &faces).unwrap();
    assert_eq!(mesh.valence(VertexId(0)), 3);
    let ebar = crate::geom::mean_edge_length(&mesh);
    let o = QuadFairOptions::default();
    let mut direct = mesh.clone();
    let rd = fair_in_place_with(&mut direct, &o, Method::Direct).unwrap();
    let mut it = mesh.clone();
    fair_in_place_with(&mut it, &o, Method::Iterative).unwrap();
    assert!(rd.free_vertices > 100, "{rd:?}");
    let worst = max_distance(&direct, &it);
    assert!(
        worst <= 1e-6 * ebar,
        "iterative vs Cholesky: {worst:e} (ē = {ebar})"
    );
}

fn max_distance(a: &SurfaceMesh, b: &SurfaceMesh) -> f64 {
    a.positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

#[test]
fn corners_and_fixed_vertices_stay_bit_identical_and_the_weight_is_scale_invariant() {
    let (_, zz) = zigzag_grid(12, 12, 0.2, |x, y| 0.3 * x * y);
    let fixed = vec![VertexId(25), VertexId(40), VertexId(77)];
    let o = QuadFairOptions {
        fixed: fixed.clone(),
        ..Default::default()
    };
    let mut a = zz.clone();
    fair_in_place(&mut a, &o).unwrap();
    for v in fixed.iter().copied().chain([0, 11, 132, 143].map(VertexId)) {
        assert_eq!(a.position(v), zz.position(v));
    }
    assert!(
        a.positions()
            .iter()
            .zip(zz.positions())
            .any(|(p, q)| p != q)
    );
    // the same mesh scaled by 1000 gives the same result scaled by 1000
    let mut big = zz.clone();
    for p in big.positions_mut() {
        *p *= 1000.0;
    }
    fair_in_place(&mut big, &o).unwrap();
    for (p, q) in big.positions().iter().zip(a.positions()) {
        assert!((*p / 1000.0 - *q).length() < 1e-9, "{p} vs {q}");
    }
    // bad options and indices are errors
    let bad = QuadFairOptions {
        fixed: vec![VertexId(999)],
        ..Default::default()
    };
    assert!(matches!(
        fair_in_place(&mut a, &bad),
        Err(QuadFairError::FixedVertexOutOfRange { .. })
    ));
    let bad = QuadFairOptions {
        weight: f64::NAN,
        ..Default::default()
    };
    assert!(fair_in_place(&mut a, &bad).is_err());
}

#[test]
fn polyline_network_flattens_bumps_within_the_tolerance_cylinders() {
    // a plane z = 0 with a planted bump of height 0.3·ē: with h = 0.1·ē
    // the bump can only come down by h, and it does, exactly
    let mut m = shapes::quad_grid(9, 9, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
    let e = crate::geom::mean_edge_length(&m);
    m.positions_mut()[40].z = 0.3 * e;
    let z0: Vec<f64> = m.positions().iter().map(|p| p.z).collect();
    let o = PolylineNetworkOptions::default().per_vertex(Some(vec![0.1 * e; 81]));
    let out = fair_polyline_network(&m, &o).unwrap();
    let r = out.report;
    m.set_positions(out.positions).unwrap();
    assert!(r.energy_after < r.energy_before);
    for (p, z) in m.positions().iter().zip(&z0) {
        assert!((p.z - z).abs() <= 0.1 * e * (1.0 + 1e-12));
    }
    assert!(
        (m.positions()[40].z - 0.2 * e).abs() < 1e-9 * e,
        "{}",
        m.positions()[40].z
    );
    assert!(r.at_bound > 0);
    // a per-vertex tolerance of 0 keeps that height bit-identical
    let mut m2 = shapes::quad_grid(9, 9, (0.0, 1.0), (0.0, 1.0), |x, y| (3.0 * x).sin() * y);
    let zin: Vec<f64> = m2.positions().iter().map(|p| p.z).collect();
    let mut h = vec![0.05; 81];
    h[10] = 0.0;
    let o = PolylineNetworkOptions::default().per_vertex(Some(h));
    let out = fair_polyline_network(&m2, &o).unwrap();
    m2.set_positions(out.positions).unwrap();
    assert_eq!(m2.positions()[10].z, zin[10]);
}

/// Quad mesh of `truth` over [−1, 1]² whose rows have different lengths:
/// row j has `len(j)` vertices (non-increasing in j, a staircase boundary
/// with convex and reflex corners), interior vertices shifted like
/// [`zigzag_grid`]. Returns (truth mesh, zigzag mesh).
pub(crate) fn zigzag_staircase(
    nx: u32,
    ny: u32,
    len: impl Fn(u32) -> u32,
    delta: f64,
    truth: impl Fn(f64, f64) -> f64,
) -> (SurfaceMesh, SurfaceMesh) {
    let (hx, hy) = (2.0 / (nx - 1) as f64, 2.0 / (ny - 1) as f64);
    let mut id = vec![vec![u32::MAX; nx as usize]; ny as usize];
    let mut pos = Vec::new();
    for j in 0..ny {
        for i in 0..len(j).min(nx) {
            id[j as usize][i as usize] = pos.len() as u32;
            let (x, y) = (-1.0 + i as f64 * hx, -1.0 + j as f64 * hy);
            pos.push(Vec3::new(x, y, truth(x, y)));
        }
    }
    let mut faces = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..len(j).min(len(j + 1)).min(nx).saturating_sub(1) {
            let (i, j) = (i as usize, j as usize);
            faces.push([id[j][i], id[j][i + 1], id[j + 1][i + 1], id[j + 1][i]]);
        }
    }
    let t = SurfaceMesh::new(pos, &faces).expect("staircase mesh");
    let mut z = t.clone();
    for j in 0..ny as usize {
        for i in 0..nx as usize {
            let k = id[j][i];
            if k == u32::MAX || t.is_boundary_vertex(VertexId(k)) {
                continue;
            }
            let p = t.position(VertexId(k));
            let sx = if j % 2 == 0 { 1.0 } else { -1.0 };
            let sy = if i % 2 == 0 { 1.0 } else { -1.0 };
            let (x, y) = (p.x + sx * delta * hx, p.y + 0.5 * sy * delta * hy);
            z.positions_mut()[k as usize] = Vec3::new(x, y, truth(x, y));
        }
    }
    (t, z)
}

/// (max, RMS) distance of the vertices to the graph of `f`: the vertical
/// gap divided by √(1 + |∇f|²) (the closest-point distance up to terms of
/// second order in the gap; ∇f by central differences).
fn surface_distance(m: &SurfaceMesh, f: &dyn Fn(f64, f64) -> f64) -> (f64, f64) {
    let d: Vec<f64> = m
        .positions()
        .iter()
        .map(|p| {
            let e = 1e-6;
            let fx = (f(p.x + e, p.y) - f(p.x - e, p.y)) / (2.0 * e);
            let fy = (f(p.x, p.y + e) - f(p.x, p.y - e)) / (2.0 * e);
            (p.z - f(p.x, p.y)).abs() / (1.0 + fx * fx + fy * fy).sqrt()
        })
        .collect();
    let max = d.iter().fold(0.0f64, |a, b| a.max(*b));
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    (max, rms)
}

/// Turning angles (degrees) of the structure lines at their interior
/// points: (mean, max) of the angle between consecutive edges in space,
/// and (mean, max) of the geodesic part, the angle between the two edges
/// projected onto the tangent plane of the graph of `f`.
fn turning_angles(m: &SurfaceMesh, f: &dyn Fn(f64, f64) -> f64) -> [f64; 4] {
    let (space, geodesic) = turning_per_point(m, f);
    let stats = |x: &[f64]| {
        (
            x.iter().sum::<f64>() / x.len().max(1) as f64,
            x.iter().fold(0.0f64, |a, b| a.max(*b)),
        )
    };
    let (ms, xs) = stats(&space);
    let (mg, xg) = stats(&geodesic);
    [ms, xs, mg, xg]
}

/// (mean, max) over the interior points of the structure lines of
/// |turning angle of `m` − turning angle of `truth`| (degrees; the meshes
/// share their connectivity, so their lines correspond point by point): how
/// far the lines are from the smooth truth's lines, whether by zigzag, by a
/// wave or by flattening the surface.
fn turning_error(m: &SurfaceMesh, truth: &SurfaceMesh, f: &dyn Fn(f64, f64) -> f64) -> (f64, f64) {
    let (a, _) = turning_per_point(m, f);
    let (b, _) = turning_per_point(truth, f);
    let e: Vec<f64> = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).collect();
    (
        e.iter().sum::<f64>() / e.len().max(1) as f64,
        e.iter().fold(0.0f64, |s, x| s.max(*x)),
    )
}

/// Per interior point of every structure line: (space, geodesic) turning
/// angles in degrees, in line order.
fn turning_per_point(m: &SurfaceMesh, f: &dyn Fn(f64, f64) -> f64) -> (Vec<f64>, Vec<f64>) {
    let p = m.positions();
    let mut space = Vec::new();
    let mut geodesic = Vec::new();
    for l in structure_lines(m) {
        let v = &l.vertices;
        let k = v.len();
        let count = if l.closed { k } else { k.saturating_sub(2) };
        for i in 0..count {
            let (a, b, c) = (
                p[v[i].idx()],
                p[v[(i + 1) % k].idx()],
                p[v[(i + 2) % k].idx()],
            );
            let (e0, e1) = (b - a, c - b);
            space.push(e0.angle_between(e1).to_degrees());
            let e = 1e-6;
            let fx = (f(b.x + e, b.y) - f(b.x - e, b.y)) / (2.0 * e);
            let fy = (f(b.x, b.y + e) - f(b.x, b.y - e)) / (2.0 * e);
            let n = Vec3::new(-fx, -fy, 1.0).normalize();
            let (t0, t1) = (e0 - e0.dot(n) * n, e1 - e1.dot(n) * n);
            geodesic.push(t0.angle_between(t1).to_degrees());
        }
    }
    (space, geodesic)
}

type Height = Box<dyn Fn(f64, f64) -> f64>;

/// The generated cases of the structure-line evidence: (name, truth mesh,
/// zigzag mesh, height function).
fn structure_line_cases() -> Vec<(String, SurfaceMesh, SurfaceMesh, Height)> {
    let mut out: Vec<(String, SurfaceMesh, SurfaceMesh, Height)> = Vec::new();
    let grids: Vec<(u32, u32, &str, Height)> = vec![
        (16, 16, "saddle", Box::new(|x, y| 0.3 * (x * x - y * y))),
        (
            13,
            13,
            "free-form",
            Box::new(|x, y| 0.3 * (1.5 * x).sin() * (1.0 + 0.5 * y * y) + 0.2 * x * y),
        ),
        (
            22,
            41,
            "cosine roof",
            Box::new(|x, y| 0.5 * (1.0 - 0.3 * x * x) * (0.8 * y).cos()),
        ),
        (
            25,
            25,
            "bump",
            Box::new(|x, y| 0.4 * (-1.5 * (x * x + y * y)).exp()),
        ),
    ];
    for (nx, ny, name, f) in grids {
        let (t, z) = zigzag_grid(nx, ny, 0.2, &f);
        out.push((format!("{name} {nx}×{ny}"), t, z, f));
    }
    let f: Height = Box::new(|x, y| 0.35 * (1.2 * x).cos() * (1.0 + 0.4 * y) + 0.15 * x * y * y);
    let (t, z) = zigzag_staircase(21, 21, |j| 21 - 3 * (j / 4), 0.2, &f);
    out.push(("staircase 21 rows of 21…9".to_string(), t, z, f));
    out
}

/// Structure-line fairing without deformation. On zigzag
/// quad meshes of known smooth surfaces (a saddle, a free-form patch, a
/// cosine roof of 22 × 41 points, a Gaussian bump, and a staircase-shaped
/// patch whose rows have 21 down to 9 points), the default fairing — points
/// sliding along a fit of the input surface — against Taubin with 50
/// iterations (the baseline, with its defaults; also with the boundary
/// fixed, Taubin's best case):
/// - closer to the true surface than both Taubin variants (max and RMS);
/// - its lines closer to the truth's lines than Taubin 50 (mean and max of
///   the turning-angle error), and straighter (mean and max geodesic
///   turning, largest turning in space);
/// - the boundary bit-identical.
///
/// The thesis' method as printed (`on_surface: false`) leaves the surface
/// by 10–100× more. Per-vertex weights by deviation (`deviation_weights`,
/// the thesis' suggested extension) also beat Taubin 50 in all of these,
/// but not the one weight: their mean turning error is 1.1–7.4× the
/// default's, their largest distance −7 % to +60 %. Numbers: BENCHMARKS.md.
#[test]
fn zigzag_structure_lines_straighten_on_the_true_surface_better_than_taubin_50() {
    for (name, truth, zz, f) in structure_line_cases() {
        let taubin = |fix_boundary: bool| {
            let mut m = zz.clone();
            let o = TaubinOptions::default()
                .iterations(50)
                .fix_boundary(fix_boundary);
            let out = taubin_smooth(&m, &o).unwrap();
            m.set_positions(out.positions).unwrap();
            m
        };
        let (tau, tau_fixed) = (taubin(false), taubin(true));
        let mut ours = zz.clone();
        let r = fair_in_place(&mut ours, &QuadFairOptions::default()).unwrap();
        let mut thesis = zz.clone();
        fair_in_place(
            &mut thesis,
            &QuadFairOptions {
                on_surface: false,
                ..Default::default()
            },
        )
        .unwrap();
        let mut weighted = zz.clone();
        let rw = fair_in_place(
            &mut weighted,
            &QuadFairOptions::default().deviation_weights(true),
        )
        .unwrap();
        let measure = |m: &SurfaceMesh| {
            let (dmax, drms) = surface_distance(m, &*f);
            let [tmean, tmax, gmean, gmax] = turning_angles(m, &*f);
            let (emean, emax) = turning_error(m, &truth, &*f);
            [dmax, drms, emean, emax, tmean, tmax, gmean, gmax]
        };
        let rows = [
            ("input", measure(&zz)),
            ("Taubin 50", measure(&tau)),
            ("Taubin 50, boundary fixed", measure(&tau_fixed)),
            ("thesis (off surface)", measure(&thesis)),
            ("structure lines (default)", measure(&ours)),
            ("deviation weights", measure(&weighted)),
        ];
        eprintln!(
            "{name}: distance max / RMS | turning error mean / max ° | turning mean / max ° | geodesic mean / max °"
        );
        for (label, v) in &rows {
            eprintln!(
                "  {label:>26}: {:.2e} / {:.2e} | {:.3} / {:.2} | {:.3} / {:.2} | {:.3} / {:.2}",
                v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
            );
        }
        let (o, t, tf, th) = (rows[4].1, rows[1].1, rows[2].1, rows[3].1);
        let what = format!("{name}: ours {o:?}, Taubin 50 {t:?}, boundary fixed {tf:?}");
        // on the surface: closer than either Taubin (max and RMS), and far
        // closer than the thesis' penalty alone
        assert!(o[0] < t[0] && o[0] < tf[0], "max distance: {what}");
        assert!(o[1] < t[1] && o[1] < tf[1], "RMS distance: {what}");
        assert!(o[0] < 0.5 * th[0], "thesis {th:?}: {what}");
        // the lines: nearer the truth's than Taubin 50's, straighter along
        // the surface, and no larger turning anywhere
        assert!(o[2] < t[2] && o[3] < t[3], "turning error: {what}");
        assert!(o[6] < t[6] && o[7] < t[7], "geodesic turning: {what}");
        assert!(o[5] < t[5], "largest turning: {what}");
        // the zigzag is gone
        assert!(
            r.structure_energy_after < 0.01 * r.structure_energy_before,
            "{r:?}"
        );
        // per-vertex weights by deviation (the thesis' suggestion): also
        // closer to the surface and to the truth's lines than Taubin 50,
        // no larger geodesic turning, the zigzag gone
        let w = rows[5].1;
        let what_w = format!("{name}: deviation weights {w:?}, Taubin 50 {t:?}");
        assert!(w[0] < t[0] && w[1] < t[1], "distance: {what_w}");
        assert!(w[2] < t[2] && w[3] < t[3], "turning error: {what_w}");
        assert!(w[6] <= t[6] && w[7] < t[7], "geodesic turning: {what_w}");
        assert!(
            rw.structure_energy_after < 0.01 * rw.structure_energy_before,
            "{rw:?}"
        );
        // the boundary: bit-identical
        for v in zz.vertices().filter(|v| zz.is_boundary_vertex(*v)) {
            assert_eq!(ours.position(v), zz.position(v), "{name}: boundary {v:?}");
        }
    }
}
