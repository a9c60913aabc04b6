//! Triangulating polygon meshes whose preferred (shorter) quad diagonal is
//! already an edge, or is the diagonal another quad's split chose too
//! (a case where a naive triangulation panics in every command).

use fairline::geom::{CurvatureMethod, principal_curvatures, surface_area};
use fairline::mesh::{triangle_list, triangulate};
use fairline::{SurfaceMesh, Vec3, VertexId};

/// Two quads around a valence-2 vertex `v` (index 1): both quads' shorter
/// diagonal is a–b (0–2), so splitting both along it gives edge a–b four
/// triangles. With `closing_triangle`, triangle (b, a, x) also makes a–b an
/// existing edge of the mesh.
fn valence_two_quads(closing_triangle: bool) -> SurfaceMesh {
    let a = Vec3::new(-1.0, 0.0, 0.0);
    let v = Vec3::new(0.0, 0.1, 0.05);
    let b = Vec3::new(1.0, 0.0, 0.0);
    let x = Vec3::new(0.0, 3.0, 0.3);
    let y = Vec3::new(0.0, -3.0, 0.2);
    let mut faces: Vec<Vec<u32>> = vec![vec![0, 1, 2, 3], vec![2, 1, 0, 4]];
    if closing_triangle {
        faces.push(vec![2, 0, 3]);
    }
    SurfaceMesh::new(vec![a, v, b, x, y], &faces).unwrap()
}

/// Triangulates `mesh` (built by [`valence_two_quads`]) and checks the split.
fn check(mesh: &SurfaceMesh) {
    // the preferred diagonal really is a-b (0-2) in both quads
    let p = mesh.positions();
    assert!(p[0].distance(p[2]) < p[1].distance(p[3]));
    assert!(p[0].distance(p[2]) < p[1].distance(p[4]));
    let t = triangulate(mesh).expect("a valid polygon mesh triangulates");
    assert!(t.mesh.is_triangle_mesh());
    let quads = mesh.faces().filter(|&f| mesh.face_size(f) == 4).count();
    let tris = mesh.face_count() - quads;
    assert_eq!(t.mesh.face_count(), 2 * quads + tris);
    assert_eq!(t.source_face.len(), t.mesh.face_count());
    // the second quad is split along v-y (1-4), the only free diagonal; the
    // first along v-x (1-3) too when a-b is an edge of the closing triangle
    let expected: &[((u32, u32), usize)] = if mesh.face_count() == 3 {
        &[((1, 3), 0), ((1, 4), 1)]
    } else {
        &[((0, 2), 0), ((1, 4), 1)]
    };
    for &(pair, quad) in expected {
        let h = t.mesh.find_halfedge(VertexId(pair.0), VertexId(pair.1));
        assert!(h.is_some(), "quad {quad} split along {pair:?}");
    }
    // every edge has one or two triangles (SurfaceMesh::new checked it), and
    // the positions are untouched
    assert_eq!(t.mesh.positions(), mesh.positions());
    let area = surface_area(&t.mesh);
    assert!(area.is_finite() && area > 0.0);
    // the commands' next step runs
    let c = principal_curvatures(&t.mesh, CurvatureMethod::Rusinkiewicz);
    assert!(c.mean().iter().all(|h| h.is_finite()));
    // the drawing triangulation agrees
    assert_eq!(triangle_list(mesh).len(), t.mesh.face_count());
}

#[test]
fn shared_preferred_diagonal_of_two_quads_is_avoided() {
    check(&valence_two_quads(false));
}

#[test]
fn preferred_diagonal_that_is_already_an_edge_is_avoided() {
    check(&valence_two_quads(true));
}

#[test]
fn quad_grid_splits_along_the_shorter_diagonal() {
    // a sheared grid: the shorter diagonal of every cell is 0-2 (lower left to
    // upper right) and no diagonal is shared, so the split is unchanged
    let n = 5u32;
    let mut pos = Vec::new();
    for j in 0..n {
        for i in 0..n {
            pos.push(Vec3::new(i as f64 + 0.4 * j as f64, j as f64, 0.0));
        }
    }
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = j * n + i;
            faces.push(vec![k, k + 1, k + n + 1, k + n]);
        }
    }
    let m = SurfaceMesh::new(pos, &faces).unwrap();
    let t = triangulate(&m).unwrap();
    for q in &faces {
        // shorter diagonal: k+1 .. k+n (d² = 0.6² + 1) versus k .. k+n+1 (1.4² + 1)
        assert!(
            t.mesh
                .find_halfedge(VertexId(q[1]), VertexId(q[3]))
                .is_some()
        );
    }
    assert!((surface_area(&t.mesh) - 16.0).abs() < 1e-12);
}
