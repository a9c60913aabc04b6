//! Evidence for the vertex flow: density moves toward high curvature, the
//! surface stays close to the input, no flips, constraints are exact, the
//! result is invariant to scale and rigid motion, and λ and μ have the
//! effects reported by Ji et al. (§5, Fig. 4 and 5).

use super::*;
use crate::geom::face_normals;
use crate::shapes;

/// |k1| + |k2| of the torus (R, r) about z at the tube angle of `p`.
fn torus_curvature(big_r: f64, r: f64, p: Vec3) -> f64 {
    let rho = (p.x * p.x + p.y * p.y).sqrt();
    let v = p.z.atan2(rho - big_r);
    1.0 / r + v.cos().abs() / (big_r + r * v.cos())
}

/// Cube [-1, 1]³ with edges and corners rounded to `radius`, from an n × n
/// grid per side: the flat parts are exact, the rounded parts are the offset
/// of the inner box [-a, a]³, a = 1 − radius.
pub(super) fn rounded_cube(n: u32, radius: f64) -> SurfaceMesh {
    use std::collections::HashMap;
    let a = 1.0 - radius;
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut pos = Vec::new();
    let mut faces = Vec::new();
    let mut vertex = |l: [u32; 3], pos: &mut Vec<Vec3>| -> u32 {
        *index.entry(l).or_insert_with(|| {
            let p = Vec3::new(l[0] as f64, l[1] as f64, l[2] as f64) * (2.0 / n as f64) - Vec3::ONE;
            let q = p.clamp(Vec3::splat(-a), Vec3::splat(a));
            pos.push(q + radius * (p - q).normalize());
            (pos.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        for side in [0, n] {
            let (mut b, mut c) = ((axis + 1) % 3, (axis + 2) % 3);
            if side == 0 {
                std::mem::swap(&mut b, &mut c);
            }
            let at = |u: u32, v: u32| {
                let mut l = [0; 3];
                l[axis] = side;
                l[b] = u;
                l[c] = v;
                l
            };
            for u in 0..n {
                for v in 0..n {
                    let q = [
                        vertex(at(u, v), &mut pos),
                        vertex(at(u + 1, v), &mut pos),
                        vertex(at(u + 1, v + 1), &mut pos),
                        vertex(at(u, v + 1), &mut pos),
                    ];
                    if (u + v) % 2 == 0 {
                        faces.push([q[0], q[1], q[2]]);
                        faces.push([q[0], q[2], q[3]]);
                    } else {
                        faces.push([q[0], q[1], q[3]]);
                        faces.push([q[1], q[2], q[3]]);
                    }
                }
            }
        }
    }
    SurfaceMesh::new(pos, &faces).expect("rounded cube is manifold")
}

/// Mean distance of points of [`rounded_cube`] to its rounded part (0 for
/// points in it, else the distance within the flat face to its border).
fn mean_feature_distance(pos: &[Vec3], radius: f64) -> f64 {
    let a = 1.0 - radius;
    let d: f64 = pos
        .iter()
        .map(|p| {
            let c = p.abs().to_array();
            let out = c.iter().filter(|x| **x > a).count();
            if out >= 2 {
                0.0
            } else {
                c.iter()
                    .filter(|x| **x <= a)
                    .map(|x| a - x)
                    .fold(f64::INFINITY, f64::min)
            }
        })
        .sum();
    d / pos.len() as f64
}

/// Closest-point distance from `p` to triangle (a, b, c) (Ericson,
/// Real-Time Collision Detection §5.1.5).
fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return p.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return p.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = va + vb + vc;
    if !(denom.abs() > 0.0) {
        return p.distance(a).min(p.distance(b)).min(p.distance(c));
    }
    p.distance(a + ab * (vb / denom) + ac * (vc / denom))
}

/// Largest distance from the points to the surface of `input` (brute force).
fn max_distance_to_surface(input: &SurfaceMesh, points: &[Vec3]) -> f64 {
    let p = input.positions();
    points
        .iter()
        .map(|&x| {
            input
                .faces()
                .map(|f| {
                    let [a, b, c] = input.triangle(f).map(|v| p[v.idx()]);
                    point_triangle_distance(x, a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// Faces of `mesh` whose normal at `positions` is not positively aligned
/// with the input normal.
fn count_flips(mesh: &SurfaceMesh, positions: &[Vec3]) -> usize {
    let n0 = face_normals(mesh);
    let mut out = mesh.clone();
    out.set_positions(positions.to_vec()).unwrap();
    let n1 = face_normals(&out);
    (0..mesh.face_count())
        .filter(|&f| n0[f] != Vec3::ZERO && !(n0[f].dot(n1[f]) > 0.0))
        .count()
}

#[test]
fn torus_vertices_move_toward_higher_curvature() {
    let (big_r, r) = (1.0, 0.6);
    let m = shapes::torus(big_r, r, 48, 24);
    let mean_k = |pos: &[Vec3]| {
        pos.iter()
            .map(|&p| torus_curvature(big_r, r, p))
            .sum::<f64>()
            / pos.len() as f64
    };
    let before = mean_k(m.positions());
    let mut gains = Vec::new();
    for lambda in [10.0, 1.0, 0.2] {
        let out = enhance_features(&m, &EnhanceOptions::default().lambda(lambda)).unwrap();
        let gain = mean_k(&out.positions) - before;
        assert!(gain > 0.0, "λ = {lambda}: mean |k1|+|k2| did not increase");
        assert_eq!(count_flips(&m, &out.positions), 0);
        gains.push(gain);
    }
    // Fig. 4: smaller λ, stronger effect
    assert!(gains[0] < gains[1] && gains[1] < gains[2], "{gains:?}");
}

#[test]
fn rounded_cube_vertices_flow_to_the_rounded_edges_and_stay_on_the_surface() {
    let radius = 0.3;
    let m = rounded_cube(12, radius);
    let before = mean_feature_distance(m.positions(), radius);
    let out = enhance_features(&m, &EnhanceOptions::default()).unwrap();
    let after = mean_feature_distance(&out.positions, radius);
    let e = out.report.edge_length;
    let deviation = max_distance_to_surface(&m, &out.positions);
    println!(
        "feature distance {before:.4} -> {after:.4}, max deviation {:.3} ē",
        deviation / e
    );
    assert!(after < 0.9 * before, "{before} -> {after}");
    assert!(
        deviation < 0.2 * e,
        "max distance to input {}",
        deviation / e
    );
    assert!(out.report.max_displacement > 0.3 * e);
    assert_eq!(count_flips(&m, &out.positions), 0);
    // the flat parts stay flat: every moved point is on the cube's surface
    // to within the deviation measured above
    let r = &out.report;
    assert_eq!(
        r.quality_before.histogram.iter().sum::<usize>(),
        m.face_count()
    );
    assert_eq!(
        r.quality_after.histogram.iter().sum::<usize>(),
        m.face_count()
    );
    assert!(r.timings.total_s >= r.timings.factorisation_s);
}

#[test]
fn smaller_lambda_enhances_more_and_larger_mu_gives_better_triangles() {
    let radius = 0.3;
    let m = rounded_cube(12, radius);
    let feature = |o: EnhanceOptions| {
        let out = enhance_features(&m, &o).unwrap();
        (mean_feature_distance(&out.positions, radius), out)
    };
    // Fig. 4: features become more prominent as λ decreases
    let (d10, _) = feature(EnhanceOptions::default().lambda(10.0));
    let (d1, _) = feature(EnhanceOptions::default().lambda(1.0));
    let (d02, _) = feature(EnhanceOptions::default().lambda(0.2));
    assert!(d02 < d1 && d1 < d10, "{d02} {d1} {d10}");
    // Fig. 5: larger μ, better triangle quality; μ = 0 flips triangles,
    // which the repair undoes
    let (_, mu0) = feature(EnhanceOptions::default().mu(0.0));
    let (_, mu2) = feature(EnhanceOptions::default().mu(2.0));
    let (q0, q2) = (&mu0.report.quality_after, &mu2.report.quality_after);
    assert!(q0.mean < q2.mean && q0.min < q2.min, "{q0:?} {q2:?}");
    assert!(mu0.report.flipped_triangles > 0);
    assert!(mu0.report.backtracked_vertices > 0);
    assert_eq!(count_flips(&m, &mu0.positions), 0);
}

#[test]
fn boundary_and_fixed_vertices_are_bit_identical() {
    // a rounded ridge along y: vertices should gather toward x = 0
    let m = shapes::height_field(21, 21, (-1.0, 1.0), (-1.0, 1.0), |x, _| {
        0.4 * (-(x / 0.2) * (x / 0.2)).exp()
    });
    let fixed = vec![VertexId(5 + 21 * 10), VertexId(10 + 21 * 3)];
    let o = EnhanceOptions::default().lambda(0.5).fixed(fixed.clone());
    let out = enhance_features(&m, &o).unwrap();
    let input = m.positions();
    for v in m.vertices() {
        if m.is_boundary_vertex(v) || fixed.contains(&v) {
            let (a, b) = (input[v.idx()], out.positions[v.idx()]);
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
    }
    assert_eq!(
        out.report.free_vertices,
        m.vertex_count() - 80 - fixed.len()
    );
    let interior: Vec<VertexId> = m.vertices().filter(|&v| !m.is_boundary_vertex(v)).collect();
    let spread = |p: &[Vec3]| interior.iter().map(|v| p[v.idx()].x.abs()).sum::<f64>();
    assert!(
        spread(&out.positions) < spread(input),
        "vertices move toward the ridge"
    );
    assert_eq!(count_flips(&m, &out.positions), 0);
}

#[test]
fn result_is_invariant_to_scale_and_rigid_motion() {
    let m = rounded_cube(8, 0.4);
    let o = EnhanceOptions::default().iterations(2);
    let base = enhance_features(&m, &o).unwrap();
    let rotation = glam::DQuat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let shift = Vec3::new(1.0e3, -250.0, 3.5e4);
    for scale in [1.0, 1000.0, 1e-3] {
        let map = |p: Vec3| rotation * (scale * p) + shift;
        let mut t = m.clone();
        t.set_positions(m.positions().iter().map(|&p| map(p)).collect())
            .unwrap();
        let out = enhance_features(&t, &o).unwrap();
        let e = base.report.edge_length;
        for (a, b) in base.positions.iter().zip(&out.positions) {
            let d = map(*a).distance(*b) / (scale * e);
            assert!(d < 1e-6, "scale {scale}: relative difference {d}");
        }
        assert_eq!(out.report.flipped_triangles, base.report.flipped_triangles);
        let rel =
            (out.report.max_displacement / (scale * base.report.max_displacement) - 1.0).abs();
        assert!(rel < 1e-6);
    }
}

#[test]
fn invalid_input_is_refused_and_trivial_input_is_returned_unchanged() {
    let m = rounded_cube(4, 0.3);
    for o in [
        EnhanceOptions::default().lambda(0.0),
        EnhanceOptions::default().lambda(f64::NAN),
        EnhanceOptions::default().mu(-1.0),
        EnhanceOptions::default().iterations(0),
        EnhanceOptions::default().histogram_bins(0),
    ] {
        assert!(matches!(
            enhance_features(&m, &o),
            Err(EnhanceError::InvalidOption(_))
        ));
    }
    let o = EnhanceOptions::default().fixed(vec![VertexId(10_000)]);
    assert!(matches!(
        enhance_features(&m, &o),
        Err(EnhanceError::FixedVertexOutOfRange { .. })
    ));
    let quads = shapes::quad_grid(4, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
    assert!(matches!(
        enhance_features(&quads, &EnhanceOptions::default()),
        Err(EnhanceError::Mesh(_))
    ));
    // a plane has no curvature: nothing moves, nothing is NaN
    let plane = shapes::plane(6);
    let out = enhance_features(&plane, &EnhanceOptions::default()).unwrap();
    for (a, b) in plane.positions().iter().zip(&out.positions) {
        assert!(a.distance(*b) < 1e-9);
    }
    // every vertex fixed
    let all: Vec<VertexId> = m.vertices().collect();
    let out = enhance_features(&m, &EnhanceOptions::default().fixed(all)).unwrap();
    assert_eq!(out.positions, m.positions());
    assert_eq!(out.report.free_vertices, 0);
}
