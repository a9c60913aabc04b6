//! Property tests: invariants of the discrete differential geometry and of
//! the file formats that must hold for every mesh, checked on randomly
//! perturbed spheres, height fields and meshes with collapsed (degenerate)
//! triangles.

use std::f64::consts::PI;

use fairline::geom::{self, LaplaceWeights};
use fairline::{SurfaceMesh, Vec3, shapes};
use proptest::prelude::*;

/// An icosphere whose vertices are moved radially and tangentially by
/// pseudo-random amounts of at most `amp` (deterministic in `seed`).
fn jittered_sphere(seed: u64, amp: f64) -> SurfaceMesh {
    let mut m = shapes::icosphere(1.0, 2);
    let mut s = seed | 1;
    let mut next = move || {
        // xorshift64*: reproducible without a dependency
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for p in m.positions_mut() {
        *p += Vec3::new(next(), next(), next()) * amp;
    }
    m
}

fn random_height_field(a: f64, b: f64, c: f64, n: u32) -> SurfaceMesh {
    shapes::height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), move |x, y| {
        a * (2.0 * x + b).sin() * (1.5 * y).cos() + c * x * y * y
    })
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Σ K_i A_i equals the total angle defect 2πχ exactly (Gauss–Bonnet),
    /// whatever the vertex positions, as long as the surface is a sphere.
    #[test]
    fn gauss_bonnet_holds_on_any_sphere(seed in any::<u64>(), amp in 0.0f64..0.15) {
        let m = jittered_sphere(seed, amp);
        let k = geom::gaussian_curvature(&m);
        let a = geom::mixed_vertex_areas(&m);
        let total: f64 = k.iter().zip(&a).map(|(k, a)| k * a).sum();
        prop_assert!((total - 4.0 * PI).abs() < 1e-9, "Σ K A = {total}");
    }

    /// Every Laplacian is symmetric with rows summing to zero.
    #[test]
    fn laplacians_symmetric_zero_row_sums(seed in any::<u64>(), amp in 0.0f64..0.15) {
        let m = jittered_sphere(seed, amp);
        for w in [
            LaplaceWeights::Uniform,
            LaplaceWeights::EdgeLength { exponent: -1.0 },
            LaplaceWeights::Cotangent,
        ] {
            let l = geom::laplacian(&m, w).to_dense();
            let n = m.vertex_count();
            for i in 0..n {
                let row: f64 = (0..n).map(|j| l[(i, j)]).sum();
                let scale: f64 = (0..n).map(|j| l[(i, j)].abs()).sum::<f64>().max(1.0);
                prop_assert!(row.abs() <= 1e-12 * scale, "{w:?} row {i} sums to {row}");
                for j in 0..n {
                    prop_assert_eq!(l[(i, j)], l[(j, i)]);
                }
            }
        }
    }

    /// Barycentric and mixed Voronoi vertex areas partition the surface
    /// area; mixed areas are never negative.
    #[test]
    fn vertex_areas_partition_the_surface(
        a in -0.5f64..0.5, b in -3.0f64..3.0, c in -0.5f64..0.5, n in 3u32..14,
    ) {
        let m = random_height_field(a, b, c, n);
        let total = geom::surface_area(&m);
        let bary: f64 = geom::barycentric_vertex_areas(&m).iter().sum();
        let mixed = geom::mixed_vertex_areas(&m);
        prop_assert!((bary - total).abs() <= 1e-12 * total);
        prop_assert!((mixed.iter().sum::<f64>() - total).abs() <= 1e-12 * total);
        prop_assert!(mixed.iter().all(|x| *x >= 0.0));
    }

    /// The enclosed volume does not change under translation and is positive
    /// for an outward-oriented sphere.
    #[test]
    fn volume_is_translation_invariant(
        seed in any::<u64>(), amp in 0.0f64..0.1,
        t in prop::array::uniform3(-10.0f64..10.0),
    ) {
        let m = jittered_sphere(seed, amp);
        let v0 = geom::volume(&m);
        let mut moved = m.clone();
        for p in moved.positions_mut() {
            *p += Vec3::from_array(t);
        }
        let v1 = geom::volume(&moved);
        prop_assert!(v0 > 0.0);
        prop_assert!((v0 - v1).abs() < 1e-10 * (1.0 + v0), "{v0} vs {v1}");
    }

    /// Collapsing vertices onto neighbours creates zero-area triangles;
    /// nothing computed from such a mesh may be NaN or infinite.
    #[test]
    fn degenerate_triangles_never_produce_nan(seed in any::<u64>(), collapses in 1usize..12) {
        let mut m = jittered_sphere(seed, 0.05);
        let n = m.vertex_count();
        let mut s = seed;
        for _ in 0..collapses {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let v = (s >> 33) as usize % n;
            let w = m.one_ring(fairline::VertexId(v as u32)).next().unwrap();
            let target = m.positions()[w.idx()];
            m.positions_mut()[v] = target;
        }
        let vec_finite = |v: &[Vec3]| v.iter().all(|p| p.is_finite());
        prop_assert!(vec_finite(&geom::vertex_normals(&m)));
        prop_assert!(vec_finite(&geom::vertex_normals_max(&m)));
        prop_assert!(vec_finite(&geom::mean_curvature_normals(&m)));
        prop_assert!(all_finite(&geom::mixed_vertex_areas(&m)));
        prop_assert!(all_finite(&geom::gaussian_curvature(&m)));
        prop_assert!(all_finite(&geom::cotangents(&m)));
        prop_assert!(all_finite(&geom::triangle_qualities(&m)));
        for pc in [
            geom::principal_curvatures_rusinkiewicz(&m),
            geom::principal_curvatures_meyer(&m),
        ] {
            prop_assert!(all_finite(&pc.k1) && all_finite(&pc.k2));
            prop_assert!(vec_finite(&pc.d1) && vec_finite(&pc.d2));
            prop_assert!(pc.k1.iter().zip(&pc.k2).all(|(a, b)| a >= b));
        }
        let l = geom::cotangent_laplacian(&m);
        prop_assert!(all_finite(l.val()));
    }

    /// Writing a mesh and reading it back gives the same faces and exactly
    /// the same coordinates, in every format that stores doubles or text.
    #[test]
    fn files_round_trip_exactly(seed in any::<u64>(), amp in 0.0f64..0.2) {
        let m = jittered_sphere(seed, amp);
        let dir = std::env::temp_dir().join(format!("fairline-prop-{}-{seed}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["obj", "ply", "off"] {
            let path = dir.join(format!("m.{ext}"));
            fairline::io::write_mesh(&path, &m).unwrap();
            let back = fairline::io::read_mesh(&path).unwrap();
            prop_assert_eq!(back.positions(), m.positions(), "{}", ext);
            prop_assert_eq!(back.to_soup().indices, m.to_soup().indices, "{}", ext);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
