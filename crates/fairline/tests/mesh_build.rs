//! The halfedge builder (`SurfaceMesh::from_soup`) gives exactly the
//! connectivity of the reference builder: every halfedge's target, next,
//! previous and face, every vertex's outgoing and every face's halfedge,
//! the reversed faces and the split non-manifold vertices, hashed, against
//! fingerprints recorded with the builder of commit 85564a7. Inputs: the
//! shapes the demo draws from, dirty meshes (faces reversed, vertices shuffled, bow ties and cones
//! touching at a tip, isolated vertices, polygons), meshes large enough for
//! the builder's parallel paths, and the real meshes of ../shared/data.

#[path = "support/shared_data.rs"]
mod shared_data;

use fairline::mesh::Soup;
use fairline::{SurfaceMesh, Vec3, shapes};

/// FNV-1a over 64-bit words.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// A hash of everything the builder decides, or of its error message.
fn fingerprint(soup: &Soup) -> u64 {
    let mut h = Fnv::new();
    match SurfaceMesh::from_soup(soup) {
        Err(e) => {
            for b in e.to_string().bytes() {
                h.word(u64::from(b));
            }
        }
        Ok(m) => {
            let none = u64::MAX;
            h.word(m.vertex_count() as u64);
            h.word(m.halfedge_count() as u64);
            h.word(m.face_count() as u64);
            for hh in m.halfedges() {
                h.word(u64::from(m.to_vertex(hh).0));
                h.word(u64::from(m.next(hh).0));
                h.word(u64::from(m.prev(hh).0));
                h.word(m.face(hh).map_or(none, |f| u64::from(f.0)));
            }
            for v in m.vertices() {
                h.word(m.vertex_halfedge(v).map_or(none, |x| u64::from(x.0)));
                h.word(u64::from(m.original_vertex(v).0));
                h.word(u64::from(m.is_pinned(v)));
            }
            for f in m.faces() {
                h.word(u64::from(m.face_halfedge(f).0));
            }
            let notes = m.build_notes();
            h.word(notes.flipped_faces as u64);
            h.word(notes.split_vertices as u64);
            h.word(notes.vertex_copies as u64);
            h.word(u64::from(m.is_triangle_mesh()));
            // the merged-back soup is the input's vertex list, bit for bit
            let back = m.to_soup();
            assert_eq!(back.positions.len(), soup.positions.len());
            for (a, b) in back.positions.iter().zip(&soup.positions) {
                assert_eq!(
                    a.to_array().map(f64::to_bits),
                    b.to_array().map(f64::to_bits)
                );
            }
            for &i in &back.indices {
                h.word(u64::from(i));
            }
        }
    }
    h.0
}

/// A deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// `soup` with its vertices renumbered by a random permutation, its faces
/// shuffled, every face rotated, and about every third face of the second
/// half of the faces reversed (so orientation has to be repaired).
fn scrambled(soup: &Soup, seed: u64) -> Soup {
    let mut rng = Rng(seed);
    let nv = soup.vertex_count();
    let mut perm: Vec<u32> = (0..nv as u32).collect();
    for i in (1..nv).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    let mut positions = vec![Vec3::ZERO; nv];
    for (v, &p) in perm.iter().enumerate() {
        positions[p as usize] = soup.positions[v];
    }
    let mut faces: Vec<Vec<u32>> = soup
        .faces()
        .map(|f| f.iter().map(|&v| perm[v as usize]).collect())
        .collect();
    for i in (1..faces.len()).rev() {
        let j = rng.below(i + 1);
        faces.swap(i, j);
    }
    let half = faces.len() / 2;
    for (k, f) in faces.iter_mut().enumerate() {
        let r = rng.below(f.len());
        f.rotate_left(r);
        if k >= half && rng.below(3) == 0 {
            f.reverse();
        }
    }
    Soup::from_polygons(positions, &faces)
}

/// Faces of a mesh that touch only at vertices: several fans at one vertex.
fn dirty_soups() -> Vec<(&'static str, Soup)> {
    let p = |n: usize| -> Vec<Vec3> {
        (0..n)
            .map(|i| Vec3::new(i as f64, ((i * i) % 7) as f64, (i % 3) as f64))
            .collect()
    };
    // two closed cones touching at their tip (vertex 0)
    let mut cone_p = vec![Vec3::ZERO];
    let mut cone_f: Vec<[u32; 3]> = Vec::new();
    for side in [1.0, -1.0] {
        let base = cone_p.len() as u32;
        for k in 0..3 {
            let a = k as f64 * 2.0;
            cone_p.push(Vec3::new(a.cos(), a.sin(), side));
        }
        for k in 0..3u32 {
            let (a, b) = (base + k, base + (k + 1) % 3);
            cone_f.push(if side > 0.0 { [0, a, b] } else { [0, b, a] });
        }
        cone_f.push(if side > 0.0 {
            [base + 2, base + 1, base]
        } else {
            [base, base + 1, base + 2]
        });
    }
    // a grid of quads whose diagonal corners touch: a chain of bow ties
    let mut bows: Vec<[u32; 3]> = Vec::new();
    for k in 0..20u32 {
        let c = 2 * k;
        bows.push([c, c + 1, c + 2]);
    }
    vec![
        (
            "bow tie",
            Soup::from_polygons(p(5), &[[0u32, 1, 2], [0, 3, 4]]),
        ),
        ("two cones", Soup::from_polygons(cone_p, &cone_f)),
        ("chain of bow ties", Soup::from_polygons(p(41), &bows)),
        (
            "isolated vertices and mixed polygons",
            Soup::from_polygons(
                p(12),
                &[
                    vec![0u32, 1, 2, 3],
                    vec![3, 2, 4],
                    vec![2, 1, 5, 6, 4],
                    vec![8, 9, 10],
                ],
            ),
        ),
        (
            "inconsistent orientation",
            Soup::from_polygons(p(4), &[[0u32, 1, 2], [0, 1, 3]]),
        ),
        (
            "non-manifold edge (refused)",
            Soup::from_polygons(p(5), &[[0u32, 1, 2], [1, 0, 3], [0, 1, 4]]),
        ),
        (
            "Moebius strip (refused)",
            Soup::from_polygons(
                p(6),
                &[
                    [0u32, 1, 3],
                    [1, 4, 3],
                    [1, 2, 4],
                    [2, 5, 4],
                    [2, 3, 5],
                    [3, 0, 5],
                ],
            ),
        ),
    ]
}

/// The test inputs, by name.
fn cases() -> Vec<(String, Soup)> {
    let mut out: Vec<(String, Soup)> = vec![
        ("icosphere 3".into(), shapes::icosphere(1.0, 3).to_soup()),
        ("uv sphere".into(), shapes::uv_sphere(1.0, 24, 12).to_soup()),
        ("torus".into(), shapes::torus(2.0, 0.5, 30, 12).to_soup()),
        (
            "cylinder".into(),
            shapes::cylinder(1.0, 2.0, 20, 6).to_soup(),
        ),
        (
            "rounded cube".into(),
            shapes::rounded_cube(6, 0.3).to_soup(),
        ),
        (
            "quad grid".into(),
            shapes::quad_grid(9, 7, (0.0, 1.0), (0.0, 1.0), |x, y| x * y).to_soup(),
        ),
    ];
    // large enough for the parallel steps (≥ 20,000 faces)
    let big = shapes::height_field(140, 120, (-1.0, 1.0), (-1.0, 1.0), |x, y| x * y).to_soup();
    out.push(("height field 140x120".into(), big.clone()));
    out.push(("height field scrambled".into(), scrambled(&big, 7)));
    let ball = shapes::icosphere(1.0, 6).to_soup();
    out.push(("icosphere 6 scrambled".into(), scrambled(&ball, 11)));
    for (name, soup) in dirty_soups() {
        out.push((format!("{name} scrambled"), scrambled(&soup, 3)));
        out.push((name.to_string(), soup));
    }
    out
}

/// Fingerprints of [`cases`] under the builder of commit 85564a7.
const EXPECTED: &[(&str, u64)] = &[
    ("icosphere 3", 0xef8e8077bb7c987b),
    ("uv sphere", 0x87723762ee983567),
    ("torus", 0xa437e869fd176d2a),
    ("cylinder", 0x29ab63a0753b2491),
    ("rounded cube", 0xa1cda585f23e02c3),
    ("quad grid", 0xe467948ba75effb8),
    ("height field 140x120", 0xd4a36fe361c2a247),
    ("height field scrambled", 0xa41cb4e3b1f9736c),
    ("icosphere 6 scrambled", 0x82d7a82445604a9e),
    ("bow tie scrambled", 0x6febe39d28720ba5),
    ("bow tie", 0xbe87cc1e6dd7f1c6),
    ("two cones scrambled", 0xbdb7d65ad6dedf60),
    ("two cones", 0x5cb0fc00c0c01896),
    ("chain of bow ties scrambled", 0x9b011c1ab5eaf5a6),
    ("chain of bow ties", 0x1b5c535e4ed99bd7),
    (
        "isolated vertices and mixed polygons scrambled",
        0xecff66dce34b3933,
    ),
    ("isolated vertices and mixed polygons", 0x438fdec7ec3243cf),
    ("inconsistent orientation scrambled", 0xf37d8314e420cbe1),
    ("inconsistent orientation", 0x7a75cc2083b6c2e4),
    ("non-manifold edge (refused) scrambled", 0x5e920c6124a642f4),
    ("non-manifold edge (refused)", 0xc2be503b55ae4390),
    ("Moebius strip (refused) scrambled", 0x3f9565bc00cbcefb),
    ("Moebius strip (refused)", 0x3f9565bc00cbcefb),
];

#[test]
fn builder_connectivity_equals_the_recorded_one() {
    let got: Vec<(String, u64)> = cases()
        .into_iter()
        .map(|(name, soup)| {
            let f = fingerprint(&soup);
            (name, f)
        })
        .collect();
    let table: String = got
        .iter()
        .map(|(n, f)| format!("    ({n:?}, 0x{f:016x}),\n"))
        .collect();
    assert_eq!(got.len(), EXPECTED.len(), "fingerprints now:\n{table}");
    for ((name, f), (ename, ef)) in got.iter().zip(EXPECTED) {
        assert_eq!(name, ename);
        assert_eq!(
            f, ef,
            "{name}: connectivity changed; fingerprints now:\n{table}"
        );
    }
}

/// The real meshes: scans with holes, a non-manifold elephant (vertices
/// split per fan), quads; fingerprints under the builder of commit 85564a7.
const EXPECTED_REAL: &[(&str, u64)] = &[
    ("meshes/bob_small.ply", 0x8cf765694a579c7b),
    ("meshes/bunny_npm.obj", 0x87cfb3272d741c3b),
    ("meshes/bunny_res4.ply", 0xbd2a8493a66e561a),
    ("meshes/bunny_zipper.ply", 0xec8c29377619ee69),
    ("meshes/elephant_nonmanifold.obj", 0x499a2235b9b0ff4a),
    ("meshes/lego_open.ply", 0xbeb7492f6f70adec),
    ("meshes/spot.ply", 0x7e409af0e8da192e),
    ("quads/hypar.obj", 0x0b46fee1aa785432),
    ("quads/quadmesh.obj", 0x377a561e409b8dbb),
];

#[test]
fn builder_connectivity_on_real_meshes_equals_the_recorded_one() {
    let mut got = Vec::new();
    for &(rel, _) in EXPECTED_REAL {
        let Some(path) = shared_data::shared_data(rel) else {
            return;
        };
        let soup = fairline::io::read_soup(&path).expect("read");
        got.push(fingerprint(&soup));
    }
    let table: String = EXPECTED_REAL
        .iter()
        .zip(&got)
        .map(|((rel, _), f)| format!("    ({rel:?}, 0x{f:016x}),\n"))
        .collect();
    for ((rel, expected), f) in EXPECTED_REAL.iter().zip(&got) {
        assert_eq!(
            f, expected,
            "{rel}: connectivity changed; fingerprints now:\n{table}"
        );
    }
}

/// The inputs exercise what the fingerprints are meant to cover: splitting
/// of non-manifold vertices, reversed faces in the parallel paths, refusals.
#[test]
fn the_inputs_cover_splitting_flipping_and_refusals() {
    let cases = cases();
    let get = |name: &str| {
        let soup = &cases.iter().find(|(n, _)| n == name).expect("case").1;
        SurfaceMesh::from_soup(soup)
    };
    let notes = |name: &str| get(name).expect("builds").build_notes();
    assert_eq!(notes("bow tie").split_vertices, 1);
    assert_eq!(notes("two cones").split_vertices, 1);
    assert_eq!(notes("chain of bow ties").split_vertices, 19);
    assert_eq!(notes("inconsistent orientation").flipped_faces, 1);
    let big = get("height field scrambled").expect("builds");
    assert!(big.face_count() >= 20_000 && big.build_notes().flipped_faces > 1000);
    assert!(notes("icosphere 6 scrambled").flipped_faces > 1000);
    assert_eq!(
        notes("isolated vertices and mixed polygons").split_vertices,
        0
    );
    assert!(matches!(
        get("non-manifold edge (refused)"),
        Err(fairline::MeshError::NonManifoldEdge { .. })
    ));
    assert!(matches!(
        get("Moebius strip (refused)"),
        Err(fairline::MeshError::NonOrientable { .. })
    ));
}
