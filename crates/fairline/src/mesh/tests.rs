//! Tests of mesh building, validation and topology queries.

use super::*;
use crate::Vec3;
use crate::shapes;

fn square_grid(n: u32) -> SurfaceMesh {
    shapes::quad_grid(n, n, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0)
}

fn pts(n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| Vec3::new(i as f64, (i * i % 7) as f64, 0.0))
        .collect()
}

#[test]
fn rejects_bad_faces_naming_the_element() {
    let e = SurfaceMesh::new(pts(3), &[[0u32, 1, 5]]).unwrap_err();
    assert_eq!(
        e,
        MeshError::IndexOutOfRange {
            face: 0,
            index: 5,
            vertices: 3
        }
    );
    assert!(e.to_string().contains("face 0"));
    let e = SurfaceMesh::new(pts(4), &[vec![0u32, 1, 2], vec![0, 1, 1]]).unwrap_err();
    assert_eq!(e, MeshError::RepeatedVertex { face: 1, vertex: 1 });
    let e = SurfaceMesh::new(pts(4), &[vec![0u32, 1]]).unwrap_err();
    assert_eq!(e, MeshError::FaceTooSmall { face: 0, size: 2 });
    let mut p = pts(3);
    p[2].y = f64::NAN;
    let e = SurfaceMesh::new(p, &[[0u32, 1, 2]]).unwrap_err();
    assert_eq!(e, MeshError::NonFiniteCoordinate { vertex: 2 });
}

/// Two closed tetrahedral cones touching at their apex, vertex 0 (no
/// boundary at the apex): a non-manifold vertex of two closed fans.
pub(crate) fn two_cones() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = vec![Vec3::ZERO];
    let mut faces = Vec::new();
    for side in [1.0, -1.0] {
        let base = p.len() as u32;
        for k in 0..3 {
            let a = k as f64 * 2.0;
            p.push(Vec3::new(a.cos(), a.sin(), side));
        }
        for k in 0..3u32 {
            let (a, b) = (base + k, base + (k + 1) % 3);
            faces.push(if side > 0.0 { [0, a, b] } else { [0, b, a] });
        }
        faces.push(if side > 0.0 {
            [base + 2, base + 1, base]
        } else {
            [base, base + 1, base + 2]
        });
    }
    (p, faces)
}

#[test]
fn rejects_non_manifold_edges() {
    // three triangles on edge (0, 1)
    let e = SurfaceMesh::new(pts(5), &[[0u32, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap_err();
    match e {
        MeshError::NonManifoldEdge {
            v0: 0,
            v1: 1,
            faces,
        } => assert_eq!(faces.len(), 3),
        other => panic!("{other:?}"),
    }
}

#[test]
fn non_manifold_vertices_are_split_per_fan_and_merged_back() {
    // bow tie: two triangles sharing only vertex 0 (two boundary fans)
    let faces = [[0u32, 1, 2], [0, 3, 4]];
    let m = SurfaceMesh::new(pts(5), &faces).unwrap();
    assert_eq!(m.vertex_count(), 6);
    assert_eq!(m.original_vertex_count(), 5);
    assert_eq!(m.split_vertex_count(), 1);
    assert_eq!(m.build_notes().vertex_copies, 1);
    assert_eq!(m.original_vertex(VertexId(5)), VertexId(0));
    assert!(m.is_pinned(VertexId(0)) && m.is_pinned(VertexId(5)));
    assert!(!m.is_pinned(VertexId(1)));
    // the first fan keeps vertex 0, the second uses the copy
    assert_eq!(m.triangle(FaceId(1)).iter().filter(|v| v.0 == 5).count(), 1);
    assert_eq!(m.valence(VertexId(0)), 2);
    assert_eq!(m.valence(VertexId(5)), 2);
    let soup = m.to_soup();
    assert_eq!(soup.positions, pts(5));
    assert_eq!(m.polygons(), vec![vec![0, 1, 2], vec![0, 3, 4]]);

    // two closed cones touching at the apex: the two copies are interior
    let (p, faces) = two_cones();
    let m = SurfaceMesh::new(p.clone(), &faces).unwrap();
    assert_eq!((m.vertex_count(), m.split_vertex_count()), (8, 1));
    assert!(m.is_closed());
    assert!(!m.is_boundary_vertex(VertexId(0)) && !m.is_boundary_vertex(VertexId(7)));
    assert!(m.is_pinned(VertexId(7)));
    assert_eq!(topology_summary(&m).components, 2);
    let soup = m.to_soup();
    assert_eq!(soup.positions.len(), 7);
    assert_eq!(
        soup.positions[0].to_array().map(f64::to_bits),
        p[0].to_array().map(f64::to_bits)
    );
    let want: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    let mut got = m.polygons();
    let mut want_sorted = want.clone();
    for f in got.iter_mut().chain(want_sorted.iter_mut()) {
        let k = f.iter().enumerate().min_by_key(|x| x.1).map_or(0, |x| x.0);
        f.rotate_left(k);
    }
    assert_eq!(got, want_sorted);
    // a triangulation keeps the split and the pins
    let t = triangulate(&m).unwrap();
    assert!(t.mesh.is_pinned(VertexId(7)));
    assert_eq!(t.mesh.to_soup().positions.len(), 7);

    // a vertex of three fans gets two copies, numbered in fan order
    let m = SurfaceMesh::new(pts(7), &[[0u32, 1, 2], [0, 3, 4], [5, 6, 0]]).unwrap();
    assert_eq!((m.vertex_count(), m.split_vertex_count()), (9, 1));
    assert_eq!(m.original_vertex(VertexId(7)), VertexId(0));
    assert_eq!(m.original_vertex(VertexId(8)), VertexId(0));
    assert_eq!(m.triangle(FaceId(2)).iter().filter(|v| v.0 == 8).count(), 1);
}

#[test]
fn moebius_strip_is_non_orientable() {
    let n = 12u32;
    let mut p = Vec::new();
    for i in 0..n {
        let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        for s in [-0.3, 0.3] {
            let w = s * (t / 2.0).cos();
            p.push(Vec3::new(
                (1.0 + w) * t.cos(),
                (1.0 + w) * t.sin(),
                s * (t / 2.0).sin(),
            ));
        }
    }
    let mut faces = Vec::new();
    for i in 0..n {
        let (a, b) = (2 * i, 2 * i + 1);
        let (c, d) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        faces.push([a, c, d, b]);
    }
    assert!(matches!(
        SurfaceMesh::new(p, &faces),
        Err(MeshError::NonOrientable { .. })
    ));
}

#[test]
fn inconsistent_orientation_is_repaired() {
    let m = shapes::icosphere(1.0, 1);
    let mut polys = m.polygons();
    polys[7].reverse();
    polys[30].reverse();
    let fixed = SurfaceMesh::new(m.positions().to_vec(), &polys).unwrap();
    assert_eq!(fixed.flipped_faces(), 2);
    assert!(crate::geom::volume(&fixed) > 0.0);
    assert_eq!(fixed.polygons()[7].len(), 3);
}

#[test]
fn one_ring_is_in_rotational_order() {
    let m = square_grid(3);
    let centre = VertexId(4);
    let ring: Vec<u32> = m.one_ring(centre).map(|v| v.0).collect();
    assert_eq!(ring.len(), 4);
    // consecutive neighbours share a face
    for k in 0..4 {
        let (a, b) = (VertexId(ring[k]), VertexId(ring[(k + 1) % 4]));
        let shared = m
            .vertex_faces(a)
            .any(|f| m.face_vertices(f).any(|v| v == b));
        assert!(shared, "{ring:?}");
    }
    assert!(!m.is_boundary_vertex(centre));
    assert_eq!(m.valence(VertexId(0)), 2);
    // boundary vertex ring starts at its boundary halfedge
    let h = m.vertex_halfedge(VertexId(1)).unwrap();
    assert!(m.is_boundary_halfedge(h));
}

#[test]
fn boundary_loops_components_and_genus() {
    let g = square_grid(5);
    let loops = boundary_loops(&g);
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].len(), 16);
    let t = topology_summary(&shapes::torus(3.0, 1.0, 12, 8));
    assert_eq!((t.genus, t.components, t.boundary_loops), (1, 1, 0));
    // two separate triangles and an isolated vertex
    let m = SurfaceMesh::new(pts(7), &[[0u32, 1, 2], [3, 4, 5]]).unwrap();
    let s = topology_summary(&m);
    assert_eq!(
        (s.components, s.isolated_vertices, s.boundary_loops),
        (2, 1, 2)
    );
    assert_eq!(s.euler_characteristic, 2);
    assert_eq!(components(&m).1, 3);
}

#[test]
fn triangulation_keeps_area_and_orientation() {
    let q = shapes::quad_grid(4, 3, (0.0, 3.0), (0.0, 2.0), |x, y| 0.1 * x * y);
    let t = triangulate(&q).unwrap();
    assert_eq!(t.mesh.face_count(), 2 * q.face_count());
    assert!(t.mesh.is_triangle_mesh());
    let a0 = crate::geom::surface_area(&q);
    let a1 = crate::geom::surface_area(&t.mesh);
    assert!((a0 - a1).abs() < 1e-2 * a0);
    // a non-convex L-shaped hexagon: ear clipping, area exactly 3
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(2.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 2.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    ];
    let m = SurfaceMesh::new(p, &[[0u32, 1, 2, 3, 4, 5]]).unwrap();
    let t = triangulate(&m).unwrap();
    assert_eq!(t.mesh.face_count(), 4);
    let n = crate::geom::face_normals(&t.mesh);
    assert!(
        n.iter().all(|n| n.z > 0.99),
        "all triangles keep the orientation"
    );
    assert!((crate::geom::surface_area(&t.mesh) - 3.0).abs() < 1e-12);
}

#[test]
fn structure_lines_of_grids() {
    // 6 × 4 vertex grid: 6 lines along y, 4 along x, corners end lines
    let g = shapes::quad_grid(6, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
    let lines = structure_lines(&g);
    assert_eq!(lines.len(), 10);
    let mut lens: Vec<usize> = lines.iter().map(|l| l.vertices.len()).collect();
    lens.sort();
    assert_eq!(lens, vec![4, 4, 4, 4, 4, 4, 6, 6, 6, 6]);
    assert!(lines.iter().all(|l| !l.closed));
    // every edge in exactly one line
    let edges: usize = lines.iter().map(|l| l.vertices.len() - 1).sum();
    assert_eq!(edges, g.edge_count());
    // a quad torus: all lines closed
    let (nu, nv) = (8u32, 5u32);
    let t = shapes::torus(2.0, 0.5, nu, nv);
    let p = t.positions().to_vec();
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let quads: Vec<[u32; 4]> = (0..nu)
        .flat_map(|i| (0..nv).map(move |j| (i, j)))
        .map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        .collect();
    let qt = SurfaceMesh::new(p, &quads).unwrap();
    let lines = structure_lines(&qt);
    assert_eq!(lines.len(), (nu + nv) as usize);
    assert!(lines.iter().all(|l| l.closed));
}
