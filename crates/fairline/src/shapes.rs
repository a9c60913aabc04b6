//! Procedural surfaces with known geometry, for tests, benchmarks and the
//! demo: spheres, cylinders, tori, planes, height fields and quad grids.
//! All are oriented with outward (or +z) normals.

use crate::Vec3;
use crate::mesh::SurfaceMesh;
use std::f64::consts::PI;

fn build<F: AsRef<[u32]>>(positions: Vec<Vec3>, faces: &[F]) -> SurfaceMesh {
    SurfaceMesh::new(positions, faces).expect("procedural meshes are manifold")
}

/// Icosphere of the given radius: an icosahedron subdivided `subdivisions`
/// times (each step ×4 faces), vertices projected to the sphere. Closed,
/// 10·4^s + 2 vertices, near-uniform triangles.
pub fn icosphere(radius: f64, subdivisions: u32) -> SurfaceMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for &[a, b, c] in &faces {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let pos = pos.into_iter().map(|p| p * radius).collect();
    build(pos, &faces)
}

/// UV sphere with `n_lon` segments around and `n_lat` rings (poles are
/// single vertices). Closed.
pub fn uv_sphere(radius: f64, n_lon: u32, n_lat: u32) -> SurfaceMesh {
    let (n_lon, n_lat) = (n_lon.max(3), n_lat.max(2));
    let mut pos = vec![Vec3::new(0.0, 0.0, radius)];
    for i in 1..n_lat {
        let th = PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = 2.0 * PI * j as f64 / n_lon as f64;
            pos.push(radius * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    pos.push(Vec3::new(0.0, 0.0, -radius));
    let south = (pos.len() - 1) as u32;
    let ring = |i: u32, j: u32| 1 + (i - 1) * n_lon + (j % n_lon);
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for j in 0..n_lon {
        faces.push(vec![0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            faces.push(vec![ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            faces.push(vec![ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    for j in 0..n_lon {
        faces.push(vec![ring(n_lat - 1, j), south, ring(n_lat - 1, j + 1)]);
    }
    build(pos, &faces)
}

/// Torus about the z axis with major radius `big_r` and tube radius `r`,
/// `n_major` × `n_minor` vertices, triangulated. Closed, genus 1.
pub fn torus(big_r: f64, r: f64, n_major: u32, n_minor: u32) -> SurfaceMesh {
    let (nu, nv) = (n_major.max(3), n_minor.max(3));
    let mut pos = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let u = 2.0 * PI * i as f64 / nu as f64;
        for j in 0..nv {
            let v = 2.0 * PI * j as f64 / nv as f64;
            let rr = big_r + r * v.cos();
            pos.push(Vec3::new(rr * u.cos(), rr * u.sin(), r * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut faces = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    build(pos, &faces)
}

/// Open cylinder of the given radius about the z axis, from z = 0 to
/// `height`, with `n_around` vertices per ring and `n_along` rings,
/// triangulated, outward normals.
pub fn cylinder(radius: f64, height: f64, n_around: u32, n_along: u32) -> SurfaceMesh {
    let (na, nz) = (n_around.max(3), n_along.max(2));
    let mut pos = Vec::new();
    for k in 0..nz {
        let z = height * k as f64 / (nz - 1) as f64;
        for j in 0..na {
            let ph = 2.0 * PI * j as f64 / na as f64;
            pos.push(Vec3::new(radius * ph.cos(), radius * ph.sin(), z));
        }
    }
    let id = |k: u32, j: u32| k * na + (j % na);
    let mut faces = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..na {
            // alternate the diagonal so the mesh has no preferred direction
            if (j + k) % 2 == 0 {
                faces.push([id(k, j), id(k, j + 1), id(k + 1, j + 1)]);
                faces.push([id(k, j), id(k + 1, j + 1), id(k + 1, j)]);
            } else {
                faces.push([id(k, j), id(k, j + 1), id(k + 1, j)]);
                faces.push([id(k, j + 1), id(k + 1, j + 1), id(k + 1, j)]);
            }
        }
    }
    build(pos, &faces)
}

/// Positions of an `nx` × `ny` grid over [x0, x1] × [y0, y1] with
/// z = height(x, y); index i + nx·j.
fn grid_positions(
    nx: u32,
    ny: u32,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    height: &dyn Fn(f64, f64) -> f64,
) -> Vec<Vec3> {
    let mut pos = Vec::with_capacity((nx * ny) as usize);
    for j in 0..ny {
        let y = y0 + (y1 - y0) * j as f64 / (ny - 1) as f64;
        for i in 0..nx {
            let x = x0 + (x1 - x0) * i as f64 / (nx - 1) as f64;
            pos.push(Vec3::new(x, y, height(x, y)));
        }
    }
    pos
}

/// Triangulated height field z = height(x, y) on an `nx` × `ny` vertex grid
/// over [x0, x1] × [y0, y1]; normals point to +z. Diagonals alternate
/// (a "criss-cross" free pattern) so there is no preferred direction.
pub fn height_field(
    nx: u32,
    ny: u32,
    xr: (f64, f64),
    yr: (f64, f64),
    height: impl Fn(f64, f64) -> f64,
) -> SurfaceMesh {
    let (nx, ny) = (nx.max(2), ny.max(2));
    let pos = grid_positions(nx, ny, xr, yr, &height);
    let id = |i: u32, j: u32| i + nx * j;
    let mut faces = Vec::with_capacity(2 * ((nx - 1) * (ny - 1)) as usize);
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            if (i + j) % 2 == 0 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                faces.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                faces.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    build(pos, &faces)
}

/// Quad grid z = height(x, y) with `nx` × `ny` vertices (quads, +z normals).
pub fn quad_grid(
    nx: u32,
    ny: u32,
    xr: (f64, f64),
    yr: (f64, f64),
    height: impl Fn(f64, f64) -> f64,
) -> SurfaceMesh {
    let (nx, ny) = (nx.max(2), ny.max(2));
    let pos = grid_positions(nx, ny, xr, yr, &height);
    let id = |i: u32, j: u32| i + nx * j;
    let mut faces = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    build(pos, &faces)
}

/// Flat square [−1, 1]² in the z = 0 plane, triangulated, n × n vertices.
pub fn plane(n: u32) -> SurfaceMesh {
    height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), |_, _| 0.0)
}

/// Cube [-1, 1]³ with its edges and corners rounded to `radius` (clamped to
/// [0, 1]), from an `n` × `n` grid per side (`n` ≥ 1), triangulated with
/// alternating diagonals. The flat parts are exact; the rounded parts lie on
/// the offset by `radius` of the inner box [-a, a]³, a = 1 − radius, so the
/// principal curvatures there are 1/radius and 0 (edges) or 1/radius twice
/// (corners). Closed, genus 0, 6n² + 2 vertices. A surface with sharp
/// features for vertex flow (Ji et al. 2011), whose vertices sit evenly
/// over flat and curved parts.
pub fn rounded_cube(n: u32, radius: f64) -> SurfaceMesh {
    use std::collections::HashMap;
    let n = n.max(1);
    let radius = if radius.is_finite() {
        radius.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let a = 1.0 - radius;
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut pos = Vec::new();
    let mut faces = Vec::new();
    let mut vertex = |l: [u32; 3], pos: &mut Vec<Vec3>| -> u32 {
        *index.entry(l).or_insert_with(|| {
            let p = Vec3::new(l[0] as f64, l[1] as f64, l[2] as f64) * (2.0 / n as f64) - Vec3::ONE;
            let q = p.clamp(Vec3::splat(-a), Vec3::splat(a));
            // p − q is at least 1 − a = radius long on the rounded part
            let d = p - q;
            let len = d.length();
            pos.push(if len > 0.0 { q + d * (radius / len) } else { p });
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
    build(pos, &faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::topology_summary;

    #[test]
    fn topology_of_generated_shapes() {
        let s = topology_summary(&icosphere(1.0, 2));
        assert_eq!(
            (s.vertices, s.faces, s.genus, s.boundary_loops),
            (162, 320, 0, 0)
        );
        let t = topology_summary(&torus(2.0, 0.5, 24, 12));
        assert_eq!((t.euler_characteristic, t.genus), (0, 1));
        let c = topology_summary(&cylinder(1.0, 2.0, 16, 5));
        assert_eq!((c.boundary_loops, c.genus, c.components), (2, 0, 1));
        let q = quad_grid(5, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
        assert!(q.is_quad_mesh());
        assert_eq!(topology_summary(&q).boundary_loops, 1);
        let u = uv_sphere(1.0, 12, 8);
        assert_eq!(topology_summary(&u).genus, 0);
        assert!(u.is_closed());
    }

    #[test]
    fn rounded_cube_is_closed_with_flat_faces_and_round_edges() {
        let (n, radius) = (6, 0.3);
        let m = rounded_cube(n, radius);
        assert_eq!(m.vertex_count() as u32, 6 * n * n + 2);
        assert!(m.is_closed());
        assert_eq!(topology_summary(&m).genus, 0);
        let a = 1.0 - radius;
        for &p in m.positions() {
            // distance to the inner box is exactly the radius
            let q = p.clamp(Vec3::splat(-a), Vec3::splat(a));
            assert!((p.distance(q) - radius).abs() < 1e-12, "{p}");
            assert!(p.abs().max_element() <= 1.0 + 1e-12);
        }
    }
}
