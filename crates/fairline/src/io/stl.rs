//! STL, ascii and binary.
//!
//! Read: a file is binary when its size is exactly `84 + 50·n` for the
//! triangle count `n` stored at byte 80 (a binary header may well begin with
//! `solid`); otherwise it is ascii when it begins with `solid` and looks like
//! text (its tokens separated by any whitespace, line breaks optional),
//! else a binary file whose size does not match its count: a
//! truncated one is refused naming the first missing triangle, and bytes
//! after the announced triangles are refused too (only a final line ending
//! is tolerated), since they mean the count is wrong and data would be lost. STL stores every triangle
//! with its own corners, so vertices are welded by exact position (bit
//! pattern, `-0.0` counted as `0.0`). Facet normals are ignored.
//! Write: binary, polygons split into triangle fans, facet normals computed
//! from the f64 positions, coordinates rounded to f32.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::io::{self, Write};
use std::path::Path;

use super::text::{Lines, parse_f64, push_face, show, tokens, trailing_bytes};
use super::{IoError, Location, format_err};
use crate::Vec3;
use crate::mesh::Soup;

/// A fast hasher for position keys (three u64 bit patterns).
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }

    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

/// Welds corners to vertices by exact position.
struct Welder {
    map: HashMap<(u64, u64, u64), u32, BuildHasherDefault<KeyHasher>>,
    positions: Vec<Vec3>,
}

impl Welder {
    fn with_capacity(n: usize) -> Self {
        Welder {
            map: HashMap::with_capacity_and_hasher(n, Default::default()),
            positions: Vec::with_capacity(n),
        }
    }

    /// The vertex at `p` (finite), created if new.
    fn vertex(&mut self, p: Vec3) -> Result<u32, &'static str> {
        // -0.0 == 0.0, so this maps both zeros to +0.0
        let bits = |c: f64| if c == 0.0 { 0u64 } else { c.to_bits() };
        let key = (bits(p.x), bits(p.y), bits(p.z));
        let n = self.positions.len();
        if let Some(&v) = self.map.get(&key) {
            return Ok(v);
        }
        if n >= u32::MAX as usize {
            return Err("too many vertices for 32-bit indices");
        }
        self.map.insert(key, n as u32);
        self.positions.push(p);
        Ok(n as u32)
    }
}

/// Parses an STL file (ascii or binary).
pub(super) fn read(bytes: &[u8], path: &Path) -> Result<Soup, IoError> {
    let announced = bytes
        .get(80..84)
        .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])));
    let binary_size = announced.map(|n| 84 + 50 * n);
    if binary_size == Some(bytes.len() as u64) {
        return read_binary(bytes, path);
    }
    let head = &bytes[..bytes.len().min(512)];
    if bytes.trim_ascii_start().starts_with(b"solid") && !head.contains(&0) {
        return read_ascii(bytes, path);
    }
    match binary_size {
        None => Err(format_err(
            path,
            Location::File,
            format!(
                "not an ascii STL and too short ({} bytes) for a binary STL, which has at least 84",
                bytes.len()
            ),
        )),
        Some(_) => read_binary(bytes, path),
    }
}

fn read_binary(bytes: &[u8], path: &Path) -> Result<Soup, IoError> {
    let err = |at: usize, m: String| format_err(path, Location::Byte(at), m);
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let have = (bytes.len() - 84) / 50;
    if have < n {
        return Err(err(
            84 + 50 * have,
            format!(
                "triangle {have}: file ends inside the triangle list: the header announces {n} triangles ({} bytes), the file has {} bytes (truncated file?)",
                84 + 50 * n as u64,
                bytes.len()
            ),
        ));
    }
    trailing_bytes(bytes, 84 + 50 * n, path)?;
    let mut welder = Welder::with_capacity(n / 2 + 3);
    let mut soup = Soup::new();
    soup.offsets.reserve_exact(n);
    soup.indices.reserve_exact(3 * n);
    let f32_at =
        |b: &[u8], o: usize| f64::from(f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]));
    for (t, rec) in bytes[84..84 + 50 * n].chunks_exact(50).enumerate() {
        let at = 84 + 50 * t;
        let mut tri = [0u32; 3];
        for (k, v) in tri.iter_mut().enumerate() {
            let o = 12 + 12 * k;
            let p = Vec3::new(f32_at(rec, o), f32_at(rec, o + 4), f32_at(rec, o + 8));
            if !p.is_finite() {
                return Err(err(
                    at,
                    format!("triangle {t}: coordinate is not finite ({p})"),
                ));
            }
            *v = welder
                .vertex(p)
                .map_err(|m| err(at, format!("triangle {t}: {m}")))?;
        }
        push_face(&mut soup, &tri).map_err(|m| err(at, format!("triangle {t}: {m}")))?;
    }
    soup.positions = welder.positions;
    Ok(soup)
}

/// The words of the ascii STL grammar; a coordinate or a normal component
/// is never one of them.
const KEYWORDS: [&[u8]; 9] = [
    b"solid",
    b"endsolid",
    b"facet",
    b"normal",
    b"outer",
    b"loop",
    b"vertex",
    b"endloop",
    b"endfacet",
];

fn is_keyword(tok: &[u8]) -> bool {
    KEYWORDS.contains(&tok)
}

/// Reads ascii STL as a stream of whitespace-separated tokens, so that line
/// breaks are optional (a whole file on one line reads the same). A solid's
/// name is the rest of its `solid` line up to a `facet` or `endsolid` on
/// that line; the name after `endsolid` ends likewise before a `solid`.
fn read_ascii(bytes: &[u8], path: &Path) -> Result<Soup, IoError> {
    let err = |ln: usize, m: String| format_err(path, Location::Line(ln), m);
    let mut welder = Welder::with_capacity(0);
    let mut soup = Soup::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut facet = 0usize;
    let mut open: Option<usize> = None; // line of the open `facet`
    let mut last_line = 1;
    let mut toks = Lines::new(bytes, 1)
        .flat_map(|(ln, line)| tokens(line).map(move |t| (ln, t)))
        .peekable();
    while let Some((ln, keyword)) = toks.next() {
        last_line = ln;
        match keyword {
            b"solid" | b"endsolid" => {
                // the name: the rest of the line, up to what may follow it
                // there when the file is written without line breaks
                let next: &[u8] = if keyword == b"solid" {
                    b"facet"
                } else {
                    b"solid"
                };
                while toks
                    .next_if(|&(l, t)| l == ln && t != next && t != b"endsolid")
                    .is_some()
                {}
            }
            b"facet" => {
                if open.is_some() {
                    return Err(err(ln, format!("facet {facet}: 'facet' before 'endfacet'")));
                }
                open = Some(ln);
                corners.clear();
                if toks.next_if(|&(_, t)| t == b"normal").is_some() {
                    // the normal is ignored; its components are skipped
                    for _ in 0..3 {
                        toks.next_if(|&(_, t)| !is_keyword(t));
                    }
                }
            }
            b"outer" => {
                if toks.next_if(|&(_, t)| t == b"loop").is_none() {
                    return Err(err(ln, format!("facet {facet}: 'outer' without 'loop'")));
                }
            }
            b"endloop" => {}
            b"vertex" => {
                if open.is_none() {
                    return Err(err(ln, format!("facet {facet}: 'vertex' outside a facet")));
                }
                let mut xyz = [0.0; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let Some((_, tok)) = toks.next_if(|&(_, t)| !is_keyword(t)) else {
                        return Err(err(
                            ln,
                            format!("facet {facet}: expected 3 coordinates, found {k}"),
                        ));
                    };
                    *c = parse_f64(tok).ok_or_else(|| {
                        err(
                            ln,
                            format!("facet {facet}: cannot read coordinate '{}'", show(tok)),
                        )
                    })?;
                    if !c.is_finite() {
                        return Err(err(
                            ln,
                            format!("facet {facet}: coordinate '{}' is not finite", show(tok)),
                        ));
                    }
                }
                let v = welder
                    .vertex(Vec3::from_array(xyz))
                    .map_err(|m| err(ln, format!("facet {facet}: {m}")))?;
                corners.push(v);
            }
            b"endfacet" => {
                if open.take().is_none() {
                    return Err(err(
                        ln,
                        format!("facet {facet}: 'endfacet' without 'facet'"),
                    ));
                }
                if corners.len() < 3 {
                    return Err(err(
                        ln,
                        format!(
                            "facet {facet}: has {} vertices; a facet needs at least 3",
                            corners.len()
                        ),
                    ));
                }
                push_face(&mut soup, &corners)
                    .map_err(|m| err(ln, format!("facet {facet}: {m}")))?;
                facet += 1;
            }
            _ => {
                return Err(err(ln, format!("unexpected '{}'", show(keyword))));
            }
        }
    }
    if open.is_some() {
        return Err(err(
            last_line,
            format!("facet {facet}: file ends inside the facet"),
        ));
    }
    soup.positions = welder.positions;
    Ok(soup)
}

/// Number of triangles the writer produces (fans of the polygons).
pub(super) fn triangle_count(soup: &Soup) -> usize {
    soup.faces().map(|f| f.len().saturating_sub(2)).sum()
}

/// Writes a binary STL: polygons as triangle fans, unit facet normals (zero
/// for degenerate triangles), f32 coordinates. The triangle count must fit
/// in u32 (checked by the caller).
pub(super) fn write(w: &mut impl Write, soup: &Soup) -> io::Result<()> {
    let mut header = [b' '; 80];
    let title = b"binary STL written by fairline";
    header[..title.len()].copy_from_slice(title);
    w.write_all(&header)?;
    w.write_all(&(triangle_count(soup) as u32).to_le_bytes())?;
    let mut rec = [0u8; 50];
    for face in soup.faces() {
        for k in 1..face.len().saturating_sub(1) {
            let tri = [face[0], face[k], face[k + 1]].map(|i| soup.positions[i as usize]);
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
            for (j, p) in std::iter::once(n).chain(tri).enumerate() {
                for (c, x) in p.to_array().into_iter().enumerate() {
                    let o = 12 * j + 4 * c;
                    rec[o..o + 4].copy_from_slice(&(x as f32).to_le_bytes());
                }
            }
            w.write_all(&rec)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(bytes: &[u8]) -> Result<Soup, IoError> {
        read(bytes, Path::new("t.stl"))
    }

    const ASCII: &str = "solid square\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\r\n  outer loop\n   vertex -0 0 0\n   vertex 1 1 0\n   vertex 0 1 -0.0\n  endloop\n endfacet\nendsolid square\n";

    #[test]
    fn ascii_welds_by_exact_position_with_signed_zero() {
        let s = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(s.vertex_count(), 4);
        assert_eq!(s.face_count(), 2);
        assert_eq!(s.face(1), &[0, 2, 3]);
    }

    #[test]
    fn binary_round_trip_welds_and_triangulates() {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 0.5, 1.0),
        ];
        let soup = Soup::from_polygons(
            positions.clone(),
            &[
                vec![3u32, 2, 1, 0],
                vec![0, 1, 4],
                vec![1, 2, 4],
                vec![2, 3, 4],
                vec![3, 0, 4],
            ],
        );
        let mut out = Vec::new();
        write(&mut out, &soup).unwrap();
        assert_eq!(out.len(), 84 + 50 * 6);
        let back = parse(&out).unwrap();
        assert_eq!(back.vertex_count(), 5);
        assert_eq!(back.face_count(), 6);
        // the first triangle's normal points down (-z)
        let nz = f32::from_le_bytes([out[92], out[93], out[94], out[95]]);
        assert_eq!(nz, -1.0);
        // welded vertices are shared between the fan triangles
        assert_eq!(back.face(0)[0], back.face(1)[0]);
        // size-based detection wins over a header that begins with "solid"
        let mut solid = out.clone();
        solid[..5].copy_from_slice(b"solid");
        solid[5..80].fill(b' ');
        assert_eq!(parse(&solid).unwrap().face_count(), 6);
    }

    #[test]
    fn malformed_binary_names_the_triangle() {
        let soup = Soup::from_polygons(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            &[[0u32, 1, 2], [0, 2, 3]],
        );
        let mut out = Vec::new();
        write(&mut out, &soup).unwrap();
        let e = parse(&out[..84 + 70]).unwrap_err().to_string();
        assert!(
            e.starts_with("t.stl: byte 134: triangle 1: file ends inside"),
            "{e}"
        );
        let mut bad = out.clone();
        bad[84 + 50 + 16..84 + 50 + 20].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let e = parse(&bad).unwrap_err().to_string();
        assert!(
            e.starts_with("t.stl: byte 134: triangle 1: coordinate is not finite"),
            "{e}"
        );
        let mut huge = out.clone();
        huge[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(&huge).unwrap_err().to_string();
        assert!(
            e.contains("the header announces 4294967295 triangles"),
            "{e}"
        );
        let e = parse(&out[..50]).unwrap_err().to_string();
        assert!(e.contains("too short"), "{e}");
        for cut in 0..out.len() {
            let _ = parse(&out[..cut]);
        }
    }

    #[test]
    fn ascii_on_one_line_reads_as_with_line_breaks() {
        let one_line = ASCII.split_ascii_whitespace().collect::<Vec<_>>().join(" ");
        assert!(!one_line.contains('\n'));
        let lines = parse(ASCII.as_bytes()).unwrap();
        let flat = parse(one_line.as_bytes()).unwrap();
        assert_eq!(flat.face_count(), 2);
        assert_eq!(flat.positions, lines.positions);
        assert_eq!(flat.indices, lines.indices);
        assert_eq!(flat.offsets, lines.offsets);
        // two solids, names of several words, no line break anywhere
        let two = format!("{one_line} {}", one_line.replace("square", "second part"));
        let two = parse(two.as_bytes()).unwrap();
        assert_eq!(two.face_count(), 4);
        assert_eq!(two.vertex_count(), 4);
        // a vertex short of a coordinate is still named, not read past
        let e = parse(
            one_line
                .replacen("vertex 1 0 0", "vertex 1 0", 1)
                .as_bytes(),
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "t.stl:1: facet 0: expected 3 coordinates, found 2");
        let e = parse(one_line.replacen("endloop", "endloop 7", 1).as_bytes())
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.stl:1: unexpected '7'");
    }

    #[test]
    fn malformed_ascii_names_line_and_facet() {
        let e = |s: &str| parse(s.as_bytes()).unwrap_err().to_string();
        let bad = ASCII.replace("vertex 1 0 0", "vertex 1 0");
        assert_eq!(e(&bad), "t.stl:5: facet 0: expected 3 coordinates, found 2");
        let bad = ASCII.replace("vertex 0 1 -0.0", "vertex 0 1 nan");
        assert!(e(&bad).starts_with("t.stl:13: facet 1: coordinate 'nan' is not finite"));
        let bad = ASCII.replace("vertex 0 1 -0.0", "vertex 0 1 zz");
        assert!(e(&bad).starts_with("t.stl:13: facet 1: cannot read coordinate 'zz'"));
        let bad = ASCII.replace("   vertex 0 1 -0.0\n", "");
        assert!(
            e(&bad).starts_with("t.stl:14: facet 1: has 2 vertices"),
            "{}",
            e(&bad)
        );
        let bad = ASCII.replace("endloop", "endlop");
        assert!(e(&bad).starts_with("t.stl:7: unexpected 'endlop'"));
        let cut = &ASCII[..ASCII.rfind("  endloop").unwrap()];
        assert!(e(cut).contains("file ends inside the facet"));
    }
}
