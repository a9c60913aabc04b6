//! The geometry operators on the real meshes of ../shared/data/meshes:
//! invariants that hold on any valid mesh (Gauss–Bonnet, area sums, zero
//! row sums, finite curvature), checked on scans and artist meshes.

use fairline::geom;
use fairline::mesh::topology_summary;
use std::f64::consts::PI;
use std::path::PathBuf;

#[path = "support/shared_data.rs"]
mod shared_data;

fn data(rel: &str) -> Option<PathBuf> {
    shared_data::shared_data(rel)
}

#[test]
fn closed_real_meshes_satisfy_gauss_bonnet_and_have_outward_volume() {
    for (file, genus) in [
        ("meshes/spot.ply", 0),
        ("meshes/bob_small.ply", 1),
        ("meshes/bunny_npm.obj", 0),
    ] {
        let Some(path) = data(file) else { return };
        let mesh = fairline::io::read_mesh(&path).unwrap();
        let t = topology_summary(&mesh);
        assert_eq!(t.genus, genus, "{file}");
        assert_eq!(t.boundary_loops, 0, "{file}");
        let k = geom::gaussian_curvature(&mesh);
        let a = geom::mixed_vertex_areas(&mesh);
        let total: f64 = k.iter().zip(&a).map(|(k, a)| k * a).sum();
        let chi = 2.0 - 2.0 * genus as f64;
        assert!((total - 2.0 * PI * chi).abs() < 1e-8, "{file}: {total}");
        assert!(geom::volume(&mesh) > 0.0, "{file}: outward orientation");
        let area = geom::surface_area(&mesh);
        assert!((a.iter().sum::<f64>() - area).abs() < 1e-9 * area);
    }
}

#[test]
fn curvature_and_laplacians_on_real_meshes_are_finite() {
    for file in [
        "meshes/spot.ply",
        "meshes/bob_small.ply",
        "meshes/bunny_npm.obj",
        "meshes/lego_open.ply",
        "meshes/bunny_zipper.ply",
    ] {
        let Some(path) = data(file) else { return };
        let mesh = fairline::io::read_mesh(&path).unwrap();
        for method in [
            geom::CurvatureMethod::Rusinkiewicz,
            geom::CurvatureMethod::Meyer,
        ] {
            let c = geom::principal_curvatures(&mesh, method);
            assert!(c.k1.iter().chain(&c.k2).all(|x| x.is_finite()), "{file}");
            assert!(c.k1.iter().zip(&c.k2).all(|(a, b)| a >= b));
            assert!(c.d1.iter().all(|d| d.is_finite()));
        }
        let l = geom::cotangent_laplacian(&mesh);
        assert!(l.val().iter().all(|x| x.is_finite()));
        // rows sum to zero
        let ones = vec![1.0; mesh.vertex_count()];
        let r = l.as_ref() * faer::col::ColRef::from_slice(&ones);
        let scale = l.val().iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(
            (0..mesh.vertex_count()).all(|i| r[i].abs() <= 1e-9 * scale),
            "{file}"
        );
        let q = geom::triangle_qualities(&mesh);
        assert!(q.iter().all(|q| (0.0..=1.0).contains(q)));
    }
}
