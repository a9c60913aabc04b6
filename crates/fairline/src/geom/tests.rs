//! Closed-form and property tests of the differential-geometry operators.

use super::*;
use crate::Vec3;
use crate::mesh::{SurfaceMesh, VertexId};
use crate::shapes;
use std::f64::consts::PI;

fn max_abs_err(values: &[f64], truth: impl Fn(usize) -> f64, keep: impl Fn(usize) -> bool) -> f64 {
    values
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(i, v)| (v - truth(i)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn sphere_principal_curvatures_converge_to_one_over_r() {
    let r = 2.0;
    let mut last = f64::INFINITY;
    for sub in [2, 3, 4] {
        let m = shapes::icosphere(r, sub);
        for method in [CurvatureMethod::Rusinkiewicz, CurvatureMethod::Meyer] {
            let c = principal_curvatures(&m, method);
            let e1 = max_abs_err(&c.k1, |_| 1.0 / r, |_| true);
            let e2 = max_abs_err(&c.k2, |_| 1.0 / r, |_| true);
            // relative error under 6% already at 162 vertices
            assert!(e1.max(e2) * r < 0.06, "sub {sub} {method:?}: {e1} {e2}");
            assert!(c.k1.iter().zip(&c.k2).all(|(a, b)| a >= b));
        }
        let c = principal_curvatures_rusinkiewicz(&m);
        let e = max_abs_err(&c.mean(), |_| 1.0 / r, |_| true);
        assert!(
            e <= last + 1e-12,
            "error must not grow with resolution: {e} > {last}"
        );
        last = e;
    }
    assert!(
        last * r < 0.01,
        "at 2562 vertices the mean curvature is within 1%: {last}"
    );
    // outward normals on the sphere
    let m = shapes::icosphere(r, 3);
    let n = vertex_normals(&m);
    let nm = vertex_normals_max(&m);
    for v in m.vertices() {
        let p = m.position(v);
        assert!(n[v.idx()].dot(p / r) > 0.999);
        // Max's weights are exact for points on a sphere
        assert!((nm[v.idx()] - p / r).length() < 1e-12);
    }
}

#[test]
fn sphere_mean_and_gaussian_curvature_and_willmore() {
    let r = 0.5;
    let m = shapes::icosphere(r, 4);
    let h = mean_curvature(&m);
    let k = gaussian_curvature(&m);
    assert!(max_abs_err(&h, |_| 1.0 / r, |_| true) * r < 0.01);
    assert!(max_abs_err(&k, |_| 1.0 / (r * r), |_| true) * r * r < 0.02);
    // Willmore energy of a round sphere is 4π, whatever its radius
    let w = willmore_energy(&m);
    assert!((w - 4.0 * PI).abs() < 0.02 * 4.0 * PI, "{w}");
}

#[test]
fn gauss_bonnet_holds_exactly_for_angle_defects() {
    for (m, chi) in [
        (shapes::icosphere(1.3, 2), 2.0),
        (shapes::torus(2.0, 0.7, 20, 11), 0.0),
    ] {
        let k = gaussian_curvature(&m);
        let a = mixed_vertex_areas(&m);
        let total: f64 = k.iter().zip(&a).map(|(k, a)| k * a).sum();
        assert!((total - 2.0 * PI * chi).abs() < 1e-9, "{total}");
    }
}

#[test]
fn cylinder_curvature_is_one_over_r_across_and_zero_along() {
    let r = 1.5;
    let m = shapes::cylinder(r, 4.0, 64, 30);
    let c = principal_curvatures_rusinkiewicz(&m);
    let interior = |i: usize| !m.is_boundary_vertex(VertexId(i as u32));
    assert!(max_abs_err(&c.k1, |_| 1.0 / r, interior) * r < 0.02);
    assert!(max_abs_err(&c.k2, |_| 0.0, interior) * r < 0.02);
    for v in m.vertices().filter(|v| interior(v.idx())) {
        // the zero-curvature direction runs along the axis
        assert!(c.d2[v.idx()].z.abs() > 0.99, "{:?}", c.d2[v.idx()]);
        assert!(c.d1[v.idx()].z.abs() < 0.1);
    }
}

#[test]
fn torus_principal_curvatures_match_closed_form() {
    let (big_r, r) = (2.0, 0.5);
    let m = shapes::torus(big_r, r, 120, 40);
    let truth_k2 = |i: usize| {
        let p = m.position(VertexId(i as u32));
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let cos_v = (rho - big_r) / r;
        cos_v / (big_r + r * cos_v)
    };
    for method in [CurvatureMethod::Rusinkiewicz, CurvatureMethod::Meyer] {
        let c = principal_curvatures(&m, method);
        let e1 = max_abs_err(&c.k1, |_| 1.0 / r, |_| true);
        let e2 = max_abs_err(&c.k2, truth_k2, |_| true);
        assert!(e1 < 0.05 && e2 < 0.05, "{method:?}: {e1} {e2}");
    }
}

#[test]
fn plane_has_zero_curvature() {
    let m = shapes::plane(12);
    let c = principal_curvatures_rusinkiewicz(&m);
    assert!(c.k1.iter().chain(&c.k2).all(|k| k.abs() < 1e-12));
    let k = gaussian_curvature(&m);
    let interior = |i: usize| !m.is_boundary_vertex(VertexId(i as u32));
    assert!(max_abs_err(&k, |_| 0.0, interior) < 1e-9);
    assert!(mean_curvature(&m).iter().all(|h| h.abs() < 1e-12));
}

fn wavy(n: u32) -> SurfaceMesh {
    shapes::height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.2 * (3.0 * x).sin() * (2.0 * y).cos() + 0.05 * x * y
    })
}

#[test]
fn laplacians_are_symmetric_with_zero_row_sums() {
    let m = wavy(15);
    for w in [
        LaplaceWeights::Uniform,
        LaplaceWeights::EdgeLength { exponent: -1.0 },
        LaplaceWeights::Cotangent,
    ] {
        let l = laplacian(&m, w).to_dense();
        let n = m.vertex_count();
        for i in 0..n {
            let row: f64 = (0..n).map(|j| l[(i, j)]).sum();
            assert!(row.abs() < 1e-12, "{w:?} row {i} sums to {row}");
            for j in 0..n {
                assert_eq!(l[(i, j)], l[(j, i)]);
            }
        }
    }
}

#[test]
fn cotangent_laplacian_reproduces_linear_functions_inside() {
    // Σ_j w_ij (x_j − x_i) = 0 for interior vertices of a planar mesh
    let m = shapes::height_field(9, 7, (0.0, 2.0), (0.0, 1.0), |_, _| 0.0);
    let l = cotangent_laplacian(&m);
    let x: Vec<f64> = m
        .positions()
        .iter()
        .map(|p| 3.0 * p.x - 2.0 * p.y)
        .collect();
    let lx = l.as_ref() * faer::col::ColRef::from_slice(&x);
    for v in m.vertices() {
        if !m.is_boundary_vertex(v) {
            assert!(lx[v.idx()].abs() < 1e-12);
        }
    }
}

#[test]
fn vertex_areas_sum_to_surface_area() {
    for m in [
        wavy(13),
        shapes::torus(2.0, 0.4, 16, 9),
        shapes::icosphere(1.0, 2),
    ] {
        let total = surface_area(&m);
        let bary: f64 = barycentric_vertex_areas(&m).iter().sum();
        let mixed = mixed_vertex_areas(&m);
        assert!((bary - total).abs() < 1e-12 * total);
        assert!((mixed.iter().sum::<f64>() - total).abs() < 1e-12 * total);
        assert!(mixed.iter().all(|a| *a >= 0.0));
        let fa: f64 = face_areas(&m).iter().sum();
        assert!((fa - total).abs() < 1e-12 * total);
    }
}

#[test]
fn volume_of_sphere_and_cube() {
    let m = shapes::icosphere(2.0, 5);
    let v = volume(&m);
    assert!((v - 4.0 / 3.0 * PI * 8.0).abs() / v < 2e-3, "{v}");
    // unit cube from quads: exact
    let p: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    let q = [
        [0u32, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let cube = SurfaceMesh::new(p, &q).unwrap();
    assert!((volume(&cube) - 1.0).abs() < 1e-15);
    assert!((surface_area(&cube) - 6.0).abs() < 1e-15);
}

#[test]
fn triangle_quality_extremes() {
    let a = Vec3::ZERO;
    let b = Vec3::X;
    let c = Vec3::new(0.5, 3f64.sqrt() / 2.0, 0.0);
    assert!((triangle_quality(a, b, c) - 1.0).abs() < 1e-12);
    assert_eq!(triangle_quality(a, b, 2.0 * b), 0.0);
    assert_eq!(triangle_quality(a, a, a), 0.0);
    let q = triangle_quality(a, b, Vec3::new(0.5, 0.1, 0.0));
    assert!(q > 0.0 && q < 0.5);
}

#[test]
fn degenerate_triangles_produce_no_nan() {
    // a fan whose middle triangle has collapsed onto a line, plus a zero-area sliver
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1e-300, 0.0),
    ];
    let f = [[0u32, 1, 3], [1, 2, 3], [0, 4, 1], [1, 4, 2], [0, 1, 5]];
    let Ok(m) = SurfaceMesh::new(p, &f[..4]) else {
        panic!()
    };
    let m2 = SurfaceMesh::new(
        vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X, Vec3::Y],
        &[[0u32, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let _ = f[4];
    for mesh in [m, m2] {
        let all: Vec<f64> = [
            gaussian_curvature(&mesh),
            mean_curvature(&mesh),
            mixed_vertex_areas(&mesh),
            cotangents(&mesh),
            triangle_qualities(&mesh),
            principal_curvatures_rusinkiewicz(&mesh).k1,
            principal_curvatures_meyer(&mesh).k2,
        ]
        .concat();
        assert!(all.iter().all(|x| x.is_finite()));
        assert!(vertex_normals(&mesh).iter().all(|n| n.is_finite()));
        assert!(
            laplacian(&mesh, LaplaceWeights::Cotangent)
                .val()
                .iter()
                .all(|x| x.is_finite())
        );
    }
}

#[test]
fn curvature_is_scale_covariant() {
    let m = shapes::torus(2.0, 0.6, 30, 14);
    let mut big = m.clone();
    for p in big.positions_mut() {
        *p *= 1000.0;
    }
    let a = principal_curvatures_rusinkiewicz(&m);
    let b = principal_curvatures_rusinkiewicz(&big);
    for i in 0..a.k1.len() {
        assert!((a.k1[i] - 1000.0 * b.k1[i]).abs() < 1e-9 * a.k1[i].abs().max(1.0));
    }
}

/// A copy of `mesh` (triangles or polygons) with its vertices and faces in
/// a scrambled order, as a scan's are: neighbours far apart in memory.
pub(crate) fn scrambled(mesh: &SurfaceMesh, seed: u64) -> SurfaceMesh {
    let mut state = seed | 1;
    let mut next = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    let nv = mesh.vertex_count();
    let mut order: Vec<usize> = (0..nv).collect();
    for i in (1..nv).rev() {
        order.swap(i, next(i + 1));
    }
    let mut new_id = vec![0u32; nv];
    for (k, &v) in order.iter().enumerate() {
        new_id[v] = k as u32;
    }
    let positions: Vec<Vec3> = order.iter().map(|&v| mesh.positions()[v]).collect();
    let mut faces: Vec<Vec<u32>> = mesh
        .faces()
        .map(|f| mesh.face_vertices(f).map(|v| new_id[v.idx()]).collect())
        .collect();
    for i in (1..faces.len()).rev() {
        faces.swap(i, next(i + 1));
    }
    SurfaceMesh::new(positions, &faces).unwrap()
}

#[test]
fn whole_mesh_normals_equal_the_single_vertex_normal_bit_for_bit() {
    // vertex_normals gathers the faces of a batch and walks the vertex
    // circulations of a batch in lockstep; vertex_normal takes one vertex
    // at a time. Scrambled order (a scan's), a boundary (faces left out),
    // degenerate faces (collapsed vertices), an isolated vertex, a
    // triangle of zero area on its own (the fallbacks) and a quad mesh.
    let torus = scrambled(&shapes::torus(2.0, 0.7, 90, 40), 7);
    let mut positions = torus.positions().to_vec();
    positions[5] = positions[torus.one_ring(VertexId(5)).next().unwrap().idx()];
    let base = positions.len() as u32;
    positions.extend([Vec3::new(9.0, 9.0, 9.0); 4]);
    let mut faces: Vec<[u32; 3]> = torus
        .faces()
        .map(|f| torus.triangle(f).map(|v| v.0))
        .filter(|t| !t.iter().any(|&v| v % 97 == 3))
        .collect();
    faces.push([base, base + 1, base + 2]); // zero area; base + 3 is isolated
    let mesh = SurfaceMesh::new(positions, &faces).unwrap();
    let quads = scrambled(
        &shapes::quad_grid(40, 30, (-1.0, 1.0), (-1.0, 1.0), |x, y| x * x - 0.5 * y),
        11,
    );
    for m in [&mesh, &quads] {
        let all = vertex_normals(m);
        for v in m.vertices() {
            let one = vertex_normal(m, v);
            assert_eq!(
                all[v.idx()].to_array().map(f64::to_bits),
                one.to_array().map(f64::to_bits),
                "vertex {v:?}"
            );
        }
    }
    assert_eq!(vertex_normals(&mesh)[base as usize + 3], Vec3::ZERO);
    assert_eq!(vertex_normals(&mesh)[base as usize], Vec3::ZERO);
}
