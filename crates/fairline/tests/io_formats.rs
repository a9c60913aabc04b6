//! Mesh file formats end to end: the real meshes of `../shared/data`, round
//! trips through files on disk, and mutated/truncated files (no panic).

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use fairline::io::{
    IoError, MeshFormat, read_mesh, read_ply_vertex_properties, read_soup, read_soup_bytes,
    write_mesh, write_ply_with_vertex_properties, write_soup,
};
use fairline::{Soup, Vec3};

#[path = "support/shared_data.rs"]
mod shared_data;

fn data_dir() -> Option<PathBuf> {
    shared_data::shared_data("")
}

fn temp_dir(tag: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let dir =
        std::env::temp_dir().join(format!("fairline-io-test-{tag}-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn bits(s: &Soup) -> Vec<[u64; 3]> {
    s.positions
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

const EXPECTED: [(&str, usize, usize); 9] = [
    ("meshes/bunny_npm.obj", 1839, 3674),
    ("meshes/bunny_zipper.ply", 35947, 69451),
    ("meshes/bunny_res4.ply", 453, 948),
    ("meshes/spot.ply", 2930, 5856),
    ("meshes/bob_small.ply", 250, 500),
    ("meshes/lego_open.ply", 1649, 3072),
    ("meshes/elephant_nonmanifold.obj", 623, 1148),
    ("quads/quadmesh.obj", 100, 81),
    ("quads/hypar.obj", 81, 64),
];

#[test]
fn reads_every_shared_mesh_with_the_documented_counts() {
    let Some(dir) = data_dir() else { return };
    for (file, nv, nf) in EXPECTED {
        let soup = read_soup(dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(soup.vertex_count(), nv, "{file}");
        assert_eq!(soup.face_count(), nf, "{file}");
        if file.starts_with("quads/") {
            assert!(soup.faces().all(|f| f.len() == 4), "{file}");
        } else {
            assert!(soup.is_triangle_soup(), "{file}");
        }
    }
    // the listed files are all the meshes there are
    for sub in ["meshes", "quads"] {
        for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
            let name = format!("{sub}/{}", entry.unwrap().file_name().to_string_lossy());
            if MeshFormat::from_path(&name).is_ok() {
                assert!(EXPECTED.iter().any(|e| e.0 == name), "unlisted {name}");
            }
        }
    }
}

#[test]
fn manifold_shared_meshes_build_surface_meshes() {
    let Some(dir) = data_dir() else { return };
    for file in [
        "meshes/bunny_npm.obj",
        "meshes/spot.ply",
        "meshes/bob_small.ply",
        "quads/hypar.obj",
    ] {
        let mesh = read_mesh(dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        assert!(mesh.vertex_count() > 0, "{file}");
    }
    // a non-manifold file gives a mesh error naming the file
    let e = read_mesh(dir.join("meshes/bunny_res4.ply")).unwrap_err();
    assert!(matches!(e, IoError::Mesh { .. }), "{e}");
    assert!(e.to_string().contains("bunny_res4.ply"), "{e}");
}

#[test]
fn ascii_ply_extra_vertex_properties_are_readable() {
    let Some(dir) = data_dir() else { return };
    let (soup, props) = read_ply_vertex_properties(dir.join("meshes/bunny_res4.ply")).unwrap();
    assert_eq!(soup.vertex_count(), 453);
    let names: Vec<&str> = props.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["confidence", "intensity"]);
    assert_eq!(props[0].1.len(), 453);
    assert_eq!(props[1].1[0], 0.5);
}

#[test]
fn every_format_round_trips_through_files() {
    let dir = temp_dir("roundtrip");
    let positions: Vec<Vec3> = (0..12)
        .map(|i| {
            let t = i as f64;
            Vec3::new(
                (t * 0.7).sin() / 3.0,
                (t * 1.3).cos() * 1e5,
                t.sqrt() - 1e-9,
            )
        })
        .collect();
    let faces = vec![
        vec![0u32, 1, 2, 3],
        vec![3, 2, 4],
        vec![4, 5, 6, 7, 8],
        vec![8, 9, 10, 11],
    ];
    let soup = Soup::from_polygons(positions, &faces);
    for ext in ["obj", "off", "ply", "OBJ", "Ply"] {
        let path = dir.join(format!("m.{ext}"));
        write_soup(&path, &soup).unwrap();
        let back = read_soup(&path).unwrap();
        assert_eq!(bits(&back), bits(&soup), "{ext}");
        assert_eq!(back.offsets, soup.offsets, "{ext}");
        assert_eq!(back.indices, soup.indices, "{ext}");
    }
    // STL: f32, triangles, welded vertices
    let path = dir.join("m.stl");
    write_soup(&path, &soup).unwrap();
    let back = read_soup(&path).unwrap();
    assert_eq!(back.vertex_count(), 12);
    assert_eq!(back.face_count(), 2 + 1 + 3 + 2);
    for (a, b) in back.positions.iter().zip(&soup.positions) {
        assert_eq!(*a, b.as_vec3().as_dvec3());
    }
    // vertex properties
    let k: Vec<f64> = (0..12).map(|i| 1.0 / (i as f64 + 0.5)).collect();
    let h: Vec<f64> = (0..12).map(|i| -(i as f64)).collect();
    let path = dir.join("props.ply");
    write_ply_with_vertex_properties(&path, &soup, &[("k1", &k), ("mean", &h)]).unwrap();
    let (back, props) = read_ply_vertex_properties(&path).unwrap();
    assert_eq!(bits(&back), bits(&soup));
    assert_eq!(props, vec![("k1".to_string(), k), ("mean".to_string(), h)]);
    // no temporary files left behind
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn shared_meshes_round_trip_bit_exactly() {
    let Some(data) = data_dir() else { return };
    let dir = temp_dir("shared");
    for file in [
        "meshes/spot.ply",
        "quads/quadmesh.obj",
        "meshes/bunny_npm.obj",
    ] {
        let soup = read_soup(data.join(file)).unwrap();
        for ext in ["obj", "ply", "off"] {
            let out = dir.join(format!("out.{ext}"));
            write_soup(&out, &soup).unwrap();
            let back = read_soup(&out).unwrap();
            assert_eq!(bits(&back), bits(&soup), "{file} -> {ext}");
            assert_eq!(back.indices, soup.indices, "{file} -> {ext}");
        }
        if soup.is_triangle_soup() {
            let out = dir.join("out.stl");
            write_soup(&out, &soup).unwrap();
            let back = read_soup(&out).unwrap();
            assert_eq!(back.face_count(), soup.face_count(), "{file}");
        }
    }
    let mesh = read_mesh(data.join("meshes/bob_small.ply")).unwrap();
    let out = dir.join("bob.obj");
    write_mesh(&out, &mesh).unwrap();
    assert_eq!(read_mesh(&out).unwrap().face_count(), 500);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_name_the_file() {
    let e = read_soup("/nonexistent/dir/m.obj").unwrap_err();
    assert!(matches!(e, IoError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/dir/m.obj"), "{e}");
    let e = read_soup("m.txt").unwrap_err();
    assert!(e.to_string().contains("m.txt"), "{e}");
    let e = read_soup_bytes(b"v 1 2\n", MeshFormat::Obj, "bunny.obj").unwrap_err();
    assert_eq!(
        e.to_string(),
        "bunny.obj:1: vertex 0: expected 3 coordinates, found 2"
    );
}

/// A deterministic pseudo-random sequence (xorshift).
fn rng(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

fn sample_files() -> Vec<(MeshFormat, Vec<u8>)> {
    let soup = Soup::from_polygons(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 0.5, 1.0),
        ],
        &[
            vec![3u32, 2, 1, 0],
            vec![0, 1, 4],
            vec![1, 2, 4],
            vec![2, 3, 4],
            vec![3, 0, 4],
        ],
    );
    let dir = temp_dir("fuzz");
    let mut files = Vec::new();
    for format in [
        MeshFormat::Obj,
        MeshFormat::Ply,
        MeshFormat::Off,
        MeshFormat::Stl,
    ] {
        let path = dir.join(format!("s.{}", format.extension()));
        write_soup(&path, &soup).unwrap();
        files.push((format, std::fs::read(&path).unwrap()));
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let ascii_ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nproperty list uchar int tags\nelement face 1\n\
        property list uchar int vertex_indices\nelement edge 1\nproperty int a\nend_header\n\
        0 0 0 1 7\n1 0 0 0\n0 1 0 2 1 2\n3 0 1 2\n5\n";
    files.push((MeshFormat::Ply, ascii_ply.as_bytes().to_vec()));
    let ascii_stl = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
        vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    files.push((MeshFormat::Stl, ascii_stl.as_bytes().to_vec()));
    if let Some(dir) = data_dir() {
        for f in ["meshes/bob_small.ply", "quads/hypar.obj"] {
            let path = dir.join(f);
            files.push((
                MeshFormat::from_path(&path).unwrap(),
                std::fs::read(path).unwrap(),
            ));
        }
    }
    files
}

#[test]
fn truncated_and_mutated_files_never_panic() {
    let mut next = rng(0x5eed);
    let nasty: [&[u8]; 8] = [
        b"\xff",
        b"\0",
        b"-",
        b"nan",
        b"1e999",
        b" 4294967295 ",
        b"\n",
        b"99999999999999999999",
    ];
    for (format, bytes) in sample_files() {
        // every truncation (strided for larger files)
        let step = (bytes.len() / 400).max(1);
        for cut in (0..bytes.len()).step_by(step) {
            let _ = read_soup_bytes(&bytes[..cut], format, "cut");
        }
        // random byte flips and splices
        for _ in 0..400 {
            let mut m = bytes.clone();
            let at = (next() as usize) % m.len();
            match next() % 3 {
                0 => m[at] = next() as u8,
                1 => {
                    let s = nasty[(next() % nasty.len() as u64) as usize];
                    m.splice(at..at, s.iter().copied());
                }
                _ => {
                    let end = (at + (next() % 16) as usize).min(m.len());
                    m.drain(at..end);
                }
            }
            if let Ok(soup) = read_soup_bytes(&m, format, "mutated") {
                // whatever is accepted is consistent
                let nv = soup.vertex_count();
                assert!(soup.indices.iter().all(|&i| (i as usize) < nv));
                assert!(soup.positions.iter().all(|p| p.is_finite()));
                assert!(soup.faces().all(|f| f.len() >= 3));
            }
        }
    }
}

/// Reading a 17 MB binary PLY (450k vertices, 900k triangles) takes at most
/// 0.2 s in release builds. Run with
/// `cargo test --release -p fairline --test io_formats -- --ignored`.
#[test]
#[ignore = "timing; run in release"]
fn large_binary_ply_reads_fast() {
    let n: i32 = 671; // 671² ≈ 450k vertices, 2·670² ≈ 898k triangles
    let mut body = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for c in [i as f32, j as f32, ((i * j) % 7) as f32] {
                body.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let mut faces = 0;
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let v = i * n + j;
            for t in [[v, v + 1, v + n], [v + 1, v + n + 1, v + n]] {
                body.push(3);
                for k in t {
                    body.extend_from_slice(&k.to_le_bytes());
                }
                faces += 1;
            }
        }
    }
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n",
        n * n
    );
    let dir = temp_dir("large");
    let path = dir.join("large.ply");
    std::fs::write(&path, [header.as_bytes(), &body].concat()).unwrap();
    let start = std::time::Instant::now();
    let soup = read_soup(&path).unwrap();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "read {} bytes, {} vertices, {} faces in {secs:.3} s",
        header.len() + body.len(),
        soup.vertex_count(),
        soup.face_count()
    );
    assert_eq!(soup.face_count(), faces);
    std::fs::remove_dir_all(&dir).unwrap();
    if !cfg!(debug_assertions) {
        assert!(secs <= 0.2, "{secs} s");
    }
}
