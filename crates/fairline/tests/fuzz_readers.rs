//! Seeded, deterministic mutation fuzzing of every reader: OBJ, PLY
//! (ascii, binary little- and big-endian), OFF, STL (ascii
//! and binary), surface JSON (fairline's and geomdl's), IGES, STEP and
//! GoTools. Valid seed files are mutated (byte and
//! bit flips, truncation, duplicated / deleted / swapped lines, huge numbers,
//! NaN text, negative counts, random keywords, line-ending changes) by a
//! xorshift generator with a fixed seed, so every run tries the same inputs.
//!
//! Asserted for every input: no panic (`catch_unwind`), no hang (each read
//! under a time bound), an error names the file; for meshes that read, the
//! mesh builds or is refused with a typed error, and polygon meshes
//! triangulate or are refused (never a panic). The files of `tests/corpus/`
//! (inputs that once failed) run every time.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fairline::bspline::BSplineSurface;
use fairline::io::{MeshFormat, read_soup_bytes, write_soup};
use fairline::io::{
    parse_iges, parse_surfaces_json, read_iges, read_surfaces_json, surfaces_to_json,
};
use fairline::mesh::triangulate;
use fairline::{Soup, SurfaceMesh, Vec3};

/// A reader under test: the bytes and the file name for errors.
type Reader = dyn Fn(&[u8], &str) -> Result<(), String>;

/// Mutated inputs per seed file.
const CASES: usize = 20_000;
/// The longest one read may take (tiny files: microseconds normally).
const MAX_READ: Duration = Duration::from_secs(2);

/// xorshift64* (Vigna): small, fast and deterministic.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const NASTY: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e999",
    "-1e999",
    "1e-320",
    "-1",
    "0",
    "-0",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "99999999999999999999999",
    "-2147483649",
    "300",
    "1.5",
    "",
    "x",
    "0x10",
    "1e308",
    "3.4e39",
];
const KEYWORDS: &[&str] = &[
    "#1",
    "$",
    ".T.",
    "(",
    ")",
    "'",
    "/*",
    "CIRCLE",
    "B_SPLINE_CURVE_WITH_KNOTS",
    "ENDSEC;",
    "v",
    "f",
    "vt",
    "vn",
    "o",
    "g",
    "l",
    "s",
    "usemtl",
    "facet",
    "vertex",
    "endfacet",
    "solid",
    "endsolid",
    "element",
    "property",
    "end_header",
    "format",
    "list",
    "OFF",
    "ply",
    "comment",
    "#",
    "\\",
    "{",
    "}",
    "[",
    "]",
    ",",
    "\"surfaces\"",
    "null",
];

/// One mutation of `seed`.
fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    let rounds = 1 + rng.below(3);
    for _ in 0..rounds {
        if b.is_empty() {
            b.extend_from_slice(KEYWORDS[rng.below(KEYWORDS.len())].as_bytes());
            continue;
        }
        let at = rng.below(b.len());
        match rng.below(12) {
            0 => b[at] = rng.next() as u8,
            1 => b[at] ^= 1 << rng.below(8),
            2 => b.truncate(at),
            3 | 4 => {
                // replace a token (a number, usually) by a nasty one
                let start = b[..at]
                    .iter()
                    .rposition(|c| !c.is_ascii_alphanumeric() && !b"+-.".contains(c))
                    .map_or(0, |p| p + 1);
                let end = b[at..]
                    .iter()
                    .position(|c| !c.is_ascii_alphanumeric() && !b"+-.".contains(c))
                    .map_or(b.len(), |p| at + p);
                let s = NASTY[rng.below(NASTY.len())].as_bytes();
                b.splice(start..end, s.iter().copied());
            }
            5 | 6 => {
                // duplicate, delete or swap lines
                let lines: Vec<&[u8]> = b.split_inclusive(|&c| c == b'\n').collect();
                let n = lines.len();
                let (i, j) = (rng.below(n), rng.below(n));
                let mut out: Vec<Vec<u8>> = lines.iter().map(|l| l.to_vec()).collect();
                match rng.below(3) {
                    0 => out.insert(i, out[i].clone()),
                    1 => {
                        out.remove(i);
                    }
                    _ => out.swap(i, j),
                }
                b = out.concat();
            }
            7 => {
                let k = KEYWORDS[rng.below(KEYWORDS.len())];
                let ins = format!("{k} {} {}\n", NASTY[rng.below(NASTY.len())], rng.below(9));
                let at = b[..at]
                    .iter()
                    .rposition(|&c| c == b'\n')
                    .map_or(0, |p| p + 1);
                b.splice(at..at, ins.bytes());
            }
            8 => {
                let n = 1 + rng.below(16);
                let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                b.splice(at..at, junk);
            }
            9 => {
                // line endings: all CR, all CRLF
                let lf_to = if rng.below(2) == 0 {
                    &b"\r"[..]
                } else {
                    b"\r\n"
                };
                b = b
                    .iter()
                    .flat_map(|&c| if c == b'\n' { lf_to.to_vec() } else { vec![c] })
                    .collect();
            }
            10 => {
                // append garbage after the data
                b.extend_from_within(..at.min(64));
            }
            _ => {
                // a binary u32 count overwritten by a huge or zero value
                let v = [0u32, 1, u32::MAX, 0x7fff_ffff, rng.next() as u32][rng.below(5)];
                if b.len() >= at + 4 {
                    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
                }
            }
        }
    }
    b
}

/// Reads `bytes` as `format` with `read`, checking no panic, the time bound
/// and, on error, that the message starts with the file's name.
fn check_one(name: &str, bytes: &[u8], read: &Reader) -> bool {
    let t = Instant::now();
    let r = catch_unwind(AssertUnwindSafe(|| read(bytes, name)));
    let took = t.elapsed();
    let show = || String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).into_owned();
    let accepted = matches!(r, Ok(Ok(())));
    match r {
        Err(_) => panic!("{name}: the reader panicked on:\n{}", show()),
        Ok(Err(msg)) => assert!(
            msg.starts_with(name),
            "{name}: the error does not name the file: {msg}"
        ),
        Ok(Ok(())) => {}
    }
    assert!(
        took < MAX_READ,
        "{name}: reading took {took:?} on:\n{}",
        show()
    );
    accepted
}

/// A mesh reader through soup, mesh and triangulation.
fn read_mesh_bytes(format: MeshFormat) -> impl Fn(&[u8], &str) -> Result<(), String> {
    move |bytes, name| {
        let soup = read_soup_bytes(bytes, format, name).map_err(|e| e.to_string())?;
        assert!(
            soup.positions.iter().all(|p| p.is_finite()),
            "{name}: non-finite vertex read"
        );
        if let Ok(mesh) = SurfaceMesh::from_soup(&soup)
            && !mesh.is_triangle_mesh()
            && let Ok(t) = triangulate(&mesh)
        {
            assert_eq!(t.source_face.len(), t.mesh.face_count());
        }
        Ok(())
    }
}

fn read_json_bytes(bytes: &[u8], name: &str) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    parse_surfaces_json(&text)
        .map(|s| {
            for s in s {
                let [u0, u1] = s.domain_u();
                let [v0, v1] = s.domain_v();
                let p = s.eval(0.5 * (u0 + u1), 0.5 * (v0 + v1));
                assert!(
                    p.is_finite(),
                    "{name}: a surface that validates evaluates to {p}"
                );
            }
        })
        .map_err(|e| format!("{name}: {e}"))
}

fn read_iges_bytes(bytes: &[u8], name: &str) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    parse_iges(&text)
        .map(|_| ())
        .map_err(|e| format!("{name}: {e}"))
}

fn read_step_bytes(bytes: &[u8], name: &str) -> Result<(), String> {
    fairline::io::step::parse_step_bytes(bytes)
        .map(|imp| {
            for s in imp.surfaces {
                let (u, v) = s.surface.domain_center();
                let p = s.surface.eval(u, v);
                assert!(
                    p.is_finite(),
                    "{name}: a surface that reads evaluates to {p}"
                );
            }
        })
        .map_err(|e| format!("{name}: {e}"))
}

fn fuzz(name: &str, seed: &[u8], salt: u64, read: &Reader) {
    // the seed itself is valid
    read(seed, name).unwrap_or_else(|e| panic!("seed {name} does not read: {e}"));
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ salt.wrapping_mul(0xff51_afd7_ed55_8ccd));
    let start = Instant::now();
    let mut accepted = 0;
    for _ in 0..CASES {
        let m = mutate(seed, &mut rng);
        accepted += usize::from(check_one(name, &m, read));
    }
    eprintln!(
        "{name}: {CASES} mutations in {:?}, {accepted} read, {} refused",
        start.elapsed(),
        CASES - accepted
    );
    // the mutations must exercise both outcomes to be worth anything
    assert!(
        accepted > 0 && accepted < CASES,
        "{name}: {accepted} of {CASES} read"
    );
}

fn seed_soup() -> Soup {
    // a quad strip with a valence-2 vertex pair and a triangle, in 3D
    Soup::from_polygons(
        vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.1, 0.05),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 3.0, 0.3),
            Vec3::new(0.0, -3.0, 0.2),
            Vec3::new(2.0, 1.0, 0.1),
        ],
        &[vec![0u32, 1, 2, 3], vec![2, 1, 0, 4], vec![2, 5, 3]],
    )
}

fn written(ext: &str) -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!("fairline-fuzz-seed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("seed.{ext}"));
    write_soup(&p, &seed_soup()).unwrap();
    std::fs::read(&p).unwrap()
}

fn ply_text(encoding: &str) -> Vec<u8> {
    let s = seed_soup();
    let mut b = format!(
        "ply\nformat {encoding} 1.0\ncomment fuzz seed\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        s.vertex_count(),
        s.face_count()
    )
    .into_bytes();
    let big = encoding == "binary_big_endian";
    for p in &s.positions {
        for c in p.to_array() {
            if encoding == "ascii" {
                b.extend(format!("{c} ").bytes());
            } else if big {
                b.extend((c as f32).to_be_bytes());
            } else {
                b.extend((c as f32).to_le_bytes());
            }
        }
        if encoding == "ascii" {
            b.extend(b"200\n");
        } else {
            b.push(200);
        }
    }
    for f in s.faces() {
        if encoding == "ascii" {
            let idx: Vec<String> = f.iter().map(|i| i.to_string()).collect();
            b.extend(format!("{} {}\n", f.len(), idx.join(" ")).bytes());
        } else {
            b.push(f.len() as u8);
            for &i in f {
                b.extend(if big {
                    (i as i32).to_be_bytes()
                } else {
                    (i as i32).to_le_bytes()
                });
            }
        }
    }
    b
}

#[test]
fn fuzz_obj() {
    let mut seed = written("obj");
    seed.extend_from_slice(b"# comment\nvt 0.5 0.5\nvn 0 0 1\ng group\nf -6/1/1 -5//1 -4\n");
    fuzz("seed.obj", &seed, 1, &read_mesh_bytes(MeshFormat::Obj));
}

#[test]
fn fuzz_off() {
    fuzz(
        "seed.off",
        &written("off"),
        2,
        &read_mesh_bytes(MeshFormat::Off),
    );
}

#[test]
fn fuzz_ply_ascii() {
    fuzz(
        "seed.ply",
        &ply_text("ascii"),
        3,
        &read_mesh_bytes(MeshFormat::Ply),
    );
}

#[test]
fn fuzz_ply_binary_little_endian() {
    let r = read_mesh_bytes(MeshFormat::Ply);
    fuzz("le.ply", &ply_text("binary_little_endian"), 4, &r);
    // the writer's own output (double coordinates)
    fuzz("written.ply", &written("ply"), 5, &r);
}

#[test]
fn fuzz_ply_binary_big_endian() {
    fuzz(
        "be.ply",
        &ply_text("binary_big_endian"),
        6,
        &read_mesh_bytes(MeshFormat::Ply),
    );
}

#[test]
fn fuzz_stl_binary_and_ascii() {
    let r = read_mesh_bytes(MeshFormat::Stl);
    fuzz("seed.stl", &written("stl"), 7, &r);
    let ascii = b"solid t\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\nfacet normal 0 0 1\n outer loop\n  vertex 1 0 0\n  vertex 1 1 0\n  vertex 0 1 0\n endloop\nendfacet\nendsolid t\n";
    fuzz("ascii.stl", ascii, 8, &r);
}

fn seed_surface(rational: bool) -> BSplineSurface {
    let net: Vec<Vec<Vec3>> = (0..4)
        .map(|i| {
            (0..3)
                .map(|j| Vec3::new(i as f64, j as f64, 0.1 * (i * j) as f64))
                .collect()
        })
        .collect();
    let w = rational.then(|| vec![vec![1.0, 0.5, 2.0]; 4]);
    BSplineSurface::new(
        2,
        2,
        vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0],
        vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        net,
        w,
    )
    .unwrap()
}

#[test]
fn fuzz_surface_json() {
    let text = surfaces_to_json(&[seed_surface(false), seed_surface(true)]);
    fuzz("seed.json", text.as_bytes(), 9, &read_json_bytes);
}

/// A fixed-format IGES file of one bilinear entity 128 (the record layout of
/// IGES 5.3: 72 columns, the section letter in column 73).
fn iges_seed() -> Vec<u8> {
    let mut s = String::new();
    s.push_str(&format!("{:<72}S{:>7}\n", "fuzz seed", 1));
    let global = "1H,,1H;,4Hfuzz,8Hfuzz.igs,3Hgen,3Hver,32,308,15,308,15,4Hfuzz,1.,2,2HMM,1,0.1,15H20240101.000000,1E-8,100.,1Ha,1Hb,11,0,15H20240101.000000;";
    let g: Vec<char> = global.chars().collect();
    for (k, c) in g.chunks(72).enumerate() {
        let c: String = c.iter().collect();
        s.push_str(&format!("{c:<72}G{:>7}\n", k + 1));
    }
    let data = "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,1.,1.,1.,0.,1.,0.,1.;";
    let chunks: Vec<String> = data
        .chars()
        .collect::<Vec<_>>()
        .chunks(64)
        .map(|c| c.iter().collect())
        .collect();
    s.push_str(&format!(
        "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}\n",
        128, 1, 0, 0, 0, 0, 0, 0, "00000000", 1
    ));
    s.push_str(&format!(
        "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}\n",
        128,
        0,
        0,
        chunks.len(),
        0,
        "",
        "",
        "",
        0,
        2
    ));
    for (k, c) in chunks.iter().enumerate() {
        s.push_str(&format!("{c:<64} {:>7}P{:>7}\n", 1, k + 1));
    }
    s.push_str(&format!(
        "{:<72}T{:>7}\n",
        "S      1G      2D      2P      2", 1
    ));
    s.into_bytes()
}

#[test]
fn fuzz_iges() {
    let seed = iges_seed();
    let imp = parse_iges(std::str::from_utf8(&seed).unwrap()).unwrap();
    assert_eq!(imp.surfaces.len(), 1, "the seed holds one surface");
    fuzz("seed.igs", &seed, 10, &read_iges_bytes);
}

/// STEP: a hand-written file of analytic faces (a plane with a hole, a half
/// cylinder: lines, circles, vertex and edge orientation) and a written one
/// (rational B-spline face with p-curves, an untrimmed surface, units).
#[test]
fn fuzz_step() {
    let analytic = include_bytes!("corpus/step/ok-plane-hole-half-cylinder.step");
    fuzz("seed.step", analytic, 11, &read_step_bytes);
    let trimmed = seed_surface(true)
        .with_trims(vec![
            fairline::bspline::TrimLoop::polygon(&[[0.1, 0.1], [0.9, 0.2], [0.5, 0.9]]).unwrap(),
        ])
        .unwrap();
    let written = fairline::io::step::surfaces_to_step(
        &[trimmed, seed_surface(false)],
        &fairline::io::step::StepWriteOptions::default(),
    )
    .unwrap();
    let imp = fairline::io::step::parse_step(&written).unwrap();
    assert_eq!(imp.surfaces.len(), 2, "the seed holds two surfaces");
    fuzz("written.step", written.as_bytes(), 12, &read_step_bytes);
}

fn read_surface_text(
    parse: fn(&str) -> Result<Vec<BSplineSurface>, String>,
) -> impl Fn(&[u8], &str) -> Result<(), String> {
    move |bytes, name| {
        let text = String::from_utf8_lossy(bytes);
        let surfaces = parse(&text).map_err(|e| format!("{name}: {e}"))?;
        for s in surfaces {
            let (u, v) = s.domain_center();
            let p = s.eval(u, v);
            assert!(
                p.is_finite(),
                "{name}: a surface that reads evaluates to {p}"
            );
        }
        Ok(())
    }
}

/// GoTools: a spline surface, a bounded one over it with linear parameter
/// curves, a curve (listed) and a rational surface.
#[test]
fn fuzz_gotools() {
    let surface = "3 0\n2 2\n0 0 1 1\n3 2\n0 0 0.5 1 1\n0 0 0\n1 0 1\n0 1 1\n1 1 2\n0 2 2\n1 2 3\n";
    let line = |a: &str, b: &str| format!("1 100 0\n2 0\n2 2\n0 0 1 1\n{a}\n{b}\n");
    let mut seed = format!("200 1 0 0\n{surface}\n210 1 0 0\n200\n{surface}1\n3 1e-6\n");
    seed.push_str(&line("0 0", "1 0"));
    seed.push_str(&line("1 0", "0 1"));
    seed.push_str(&line("0 1", "0 0"));
    seed.push_str("100 1 0 0\n3 0\n2 2\n0 0 1 1\n0 0 0\n1 1 1\n");
    seed.push_str("200 1 0 0\n3 1\n2 2\n0 0 1 1\n2 2\n0 0 1 1\n");
    seed.push_str("1 0 0 1\n1 0 0 0.5\n0 1 0 1\n1 1 1 2\n");
    let imp = fairline::io::parse_gotools(&seed).unwrap();
    assert_eq!((imp.surfaces.len(), imp.unreadable.len()), (3, 1));
    let read = read_surface_text(|t| {
        fairline::io::parse_gotools(t)
            .map(|i| i.surfaces)
            .map_err(|e| e.to_string())
    });
    fuzz("seed.g2", seed.as_bytes(), 13, &read);
}

/// geomdl JSON: the file geomdl wrote for the library's tests.
#[test]
fn fuzz_geomdl_json() {
    let seed = include_bytes!("data/geomdl/cylinder_and_bicubic.json");
    let read = read_surface_text(|t| {
        fairline::io::parse_surface_json_any(t)
            .map(|i| i.surfaces)
            .map_err(|e| e.to_string())
    });
    fuzz("geomdl.json", seed, 14, &read);
}

/// The inputs that once failed (`tests/corpus/<what>/<file>`), read through
/// the file-opening functions so the file name check covers them too. Each
/// file's expected outcome is in its name: `ok-*` must read, `err-*` must be
/// refused naming the file; `mesh-ok-*` must also build and triangulate.
#[test]
fn corpus_of_once_failing_inputs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    let mut files: Vec<PathBuf> = walk(&root);
    files.sort();
    assert!(
        files.len() >= 8,
        "the corpus is missing ({} files)",
        files.len()
    );
    for p in files {
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        let path = p.to_str().unwrap().to_string();
        let r = catch_unwind(AssertUnwindSafe(|| -> Result<(), String> {
            match ext {
                "json" => read_surfaces_json(&p)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
                "igs" | "iges" => read_iges(&p).map(|_| ()).map_err(|e| e.to_string()),
                "step" | "stp" => fairline::io::step::read_step(&p)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
                _ => {
                    let soup = fairline::io::read_soup(&p).map_err(|e| e.to_string())?;
                    if name.starts_with("mesh-ok") {
                        let mesh = SurfaceMesh::from_soup(&soup).map_err(|e| e.to_string())?;
                        triangulate(&mesh).map_err(|e| format!("{path}: {e}"))?;
                    }
                    Ok(())
                }
            }
        }));
        match r {
            Err(_) => panic!("{path}: panicked"),
            Ok(Ok(())) => assert!(!name.starts_with("err-"), "{path}: accepted"),
            Ok(Err(e)) => {
                assert!(!name.contains("ok-"), "{path}: refused: {e}");
                assert!(
                    e.starts_with(&path),
                    "{path}: the error does not name the file: {e}"
                );
            }
        }
    }
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}
