//! Wavefront OBJ: `v` and `f` statements; polygons are kept.
//!
//! Read: `v x y z [w] [r g b]` (only x y z are used), `f` with `v`,
//! `v/vt`, `v//vn` and `v/vt/vn` corners and negative (relative) indices,
//! `#` comments and `\` line continuations. Texture coordinates, normals,
//! lines, groups, objects, smoothing groups and materials are ignored.
//! Lines may end in `\n`, `\r\n` or a lone `\r` (old Mac files). A file
//! without any `v` statement is refused ("no vertices found") rather than
//! read as an empty mesh.
//! Write: `v` lines with Rust's shortest round-trip `{}` formatting, then
//! 1-based `f` lines.

use std::io::{self, Write};
use std::path::Path;

use super::text::{Lines, parse_f64, parse_i64, push_face, show, tokens, write_formatted};
use super::{IoError, Location, format_err};
use crate::Vec3;
use crate::mesh::Soup;

/// A face corner that refers to a vertex defined later in the file.
struct ForwardRef {
    face: usize,
    line: usize,
    index: u64,
}

struct Reader<'a> {
    path: &'a Path,
    soup: Soup,
    corners: Vec<u32>,
    forward: Vec<ForwardRef>,
}

/// Parses an OBJ file.
pub(super) fn read(bytes: &[u8], path: &Path) -> Result<Soup, IoError> {
    let mut r = Reader {
        path,
        soup: Soup::new(),
        corners: Vec::new(),
        forward: Vec::new(),
    };
    // a statement continued with `\` is collected here
    let mut joined: Vec<u8> = Vec::new();
    let mut joined_line = 0;
    for (ln, raw) in Lines::new(bytes, 1) {
        let line = match raw.iter().position(|&b| b == b'#') {
            Some(i) => &raw[..i],
            None => raw,
        };
        let trimmed = line.trim_ascii_end();
        if let [head @ .., b'\\'] = trimmed {
            if joined.is_empty() {
                joined_line = ln;
            }
            joined.extend_from_slice(head);
            joined.push(b' ');
            continue;
        }
        if joined.is_empty() {
            r.statement(ln, line)?;
        } else {
            joined.extend_from_slice(line);
            let stmt = std::mem::take(&mut joined);
            r.statement(joined_line, &stmt)?;
        }
    }
    if !joined.is_empty() {
        let stmt = std::mem::take(&mut joined);
        r.statement(joined_line, &stmt)?;
    }
    let nv = r.soup.vertex_count();
    if nv == 0 {
        // a file of only unknown (or only ignored) statements is not a mesh:
        // reading it as an empty one would hide a wrong file or format
        return Err(format_err(
            path,
            Location::File,
            "no vertices found (no 'v' statement): not an OBJ mesh",
        ));
    }
    if let Some(f) = r.forward.iter().find(|f| f.index >= nv as u64) {
        return Err(format_err(
            path,
            Location::Line(f.line),
            format!(
                "face {}: vertex index {} out of range ({nv} vertices)",
                f.face,
                f.index + 1
            ),
        ));
    }
    Ok(r.soup)
}

impl Reader<'_> {
    fn err(&self, line: usize, message: String) -> IoError {
        format_err(self.path, Location::Line(line), message)
    }

    fn statement(&mut self, ln: usize, line: &[u8]) -> Result<(), IoError> {
        let mut toks = tokens(line);
        let Some(keyword) = toks.next() else {
            return Ok(());
        };
        match keyword {
            b"v" => self.vertex(ln, toks),
            b"f" | b"fo" => self.face(ln, toks),
            _ => {
                let plausible = keyword[0].is_ascii_alphabetic()
                    && keyword
                        .iter()
                        .all(|b| b.is_ascii_alphanumeric() || *b == b'_');
                if plausible {
                    Ok(()) // vt, vn, l, o, g, s, usemtl, mtllib, ...
                } else {
                    Err(self.err(ln, format!("unrecognised statement '{}'", show(keyword))))
                }
            }
        }
    }

    fn vertex<'t>(
        &mut self,
        ln: usize,
        mut toks: impl Iterator<Item = &'t [u8]>,
    ) -> Result<(), IoError> {
        let v = self.soup.vertex_count();
        let mut xyz = [0.0; 3];
        for (k, c) in xyz.iter_mut().enumerate() {
            let Some(tok) = toks.next() else {
                return Err(self.err(ln, format!("vertex {v}: expected 3 coordinates, found {k}")));
            };
            *c = parse_f64(tok).ok_or_else(|| {
                self.err(
                    ln,
                    format!("vertex {v}: cannot read coordinate '{}'", show(tok)),
                )
            })?;
            if !c.is_finite() {
                return Err(self.err(
                    ln,
                    format!("vertex {v}: coordinate '{}' is not finite", show(tok)),
                ));
            }
        }
        if v >= u32::MAX as usize {
            return Err(self.err(ln, "too many vertices for 32-bit indices".into()));
        }
        self.soup.positions.push(Vec3::from_array(xyz));
        Ok(())
    }

    fn face<'t>(&mut self, ln: usize, toks: impl Iterator<Item = &'t [u8]>) -> Result<(), IoError> {
        let f = self.soup.face_count();
        let nv = self.soup.vertex_count() as i64;
        self.corners.clear();
        for tok in toks {
            let vpart = tok.split(|&b| b == b'/').next().unwrap_or(tok);
            let idx = parse_i64(vpart).ok_or_else(|| {
                self.err(
                    ln,
                    format!("face {f}: cannot read vertex index '{}'", show(tok)),
                )
            })?;
            let resolved = match idx {
                0 => {
                    return Err(self.err(
                        ln,
                        format!("face {f}: vertex index 0 is invalid (OBJ counts from 1)"),
                    ));
                }
                i if i < 0 => {
                    let r = nv + i;
                    if r < 0 {
                        return Err(self.err(
                            ln,
                            format!(
                                "face {f}: relative vertex index {i} is out of range ({nv} vertices so far)"
                            ),
                        ));
                    }
                    r
                }
                i => i - 1,
            };
            if resolved >= u32::MAX as i64 {
                return Err(self.err(ln, format!("face {f}: vertex index {idx} out of range")));
            }
            if resolved >= nv {
                self.forward.push(ForwardRef {
                    face: f,
                    line: ln,
                    index: resolved as u64,
                });
            }
            self.corners.push(resolved as u32);
        }
        if self.corners.len() < 3 {
            return Err(self.err(
                ln,
                format!(
                    "face {f}: has {} vertices; a face needs at least 3",
                    self.corners.len()
                ),
            ));
        }
        push_face(&mut self.soup, &self.corners).map_err(|m| self.err(ln, m.into()))
    }
}

/// Writes `v` lines (shortest round-trip formatting) and 1-based `f` lines.
pub(super) fn write(w: &mut impl Write, soup: &Soup) -> io::Result<()> {
    writeln!(w, "# written by fairline")?;
    write_formatted(w, soup.vertex_count(), |v, out| {
        let p = soup.positions[v];
        writeln!(out, "v {} {} {}", p.x, p.y, p.z)
    })?;
    write_formatted(w, soup.face_count(), |f, out| {
        out.push(b'f');
        for &i in soup.face(f) {
            write!(out, " {}", u64::from(i) + 1)?;
        }
        out.push(b'\n');
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Soup, IoError> {
        read(text.as_bytes(), Path::new("t.obj"))
    }

    fn err(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn reads_all_corner_forms_and_relative_indices() {
        let text = "# test\nmtllib a.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.2 0.1\n\
                    v 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\ng grp\ns off\nusemtl m\n\
                    f 1/1/1 2/2/1 3//1 4/1\nf -4 -3 -2\nl 1 2\n\n";
        let s = parse(text).unwrap();
        assert_eq!(s.vertex_count(), 4);
        assert_eq!(s.face_count(), 2);
        assert_eq!(s.face(0), &[0, 1, 2, 3]);
        assert_eq!(s.face(1), &[0, 1, 2]);
        assert_eq!(s.positions[1], Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn continuation_lines_crlf_and_trailing_comments() {
        let s = parse("v 0 0 0\r\nv 1 0 0 # x\r\nv 0 \\\r\n 1 0\r\nf 1 2 \\\n 3\r\n").unwrap();
        assert_eq!(s.vertex_count(), 3);
        assert_eq!(s.positions[2], Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(s.face(0), &[0, 1, 2]);
    }

    #[test]
    fn forward_references_are_allowed_when_defined_later() {
        let s = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(s.face(0), &[0, 1, 2]);
    }

    #[test]
    fn malformed_input_names_line_and_element() {
        let e = err("v 0 0 0\nv 1 2\n");
        assert_eq!(e, "t.obj:2: vertex 1: expected 3 coordinates, found 2");
        let e = err("v 0 0 0\nv 1 abc 2\n");
        assert!(
            e.starts_with("t.obj:2: vertex 1: cannot read coordinate 'abc'"),
            "{e}"
        );
        let e = err("v 0 0 0\nv 1 nan 2\n");
        assert!(
            e.starts_with("t.obj:2: vertex 1: coordinate 'nan' is not finite"),
            "{e}"
        );
        let e = err("v 0 0 0\nv 1 inf 2\n");
        assert!(e.contains("vertex 1"), "{e}");
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
        assert_eq!(
            e,
            "t.obj:5: face 1: vertex index 9 out of range (3 vertices)"
        );
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n");
        assert!(e.starts_with("t.obj:4: face 0: vertex index 0"), "{e}");
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n");
        assert!(
            e.starts_with("t.obj:4: face 0: relative vertex index -4"),
            "{e}"
        );
        let e = err("v 0 0 0\nv 1 0 0\nf 1 2\n");
        assert_eq!(
            e,
            "t.obj:3: face 0: has 2 vertices; a face needs at least 3"
        );
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n");
        assert!(
            e.starts_with("t.obj:4: face 0: cannot read vertex index 'x'"),
            "{e}"
        );
        let e = err("v 0 0 0\n\x01\x02garbage\n");
        assert!(e.starts_with("t.obj:2: unrecognised statement"), "{e}");
        let e = err("v 0 0 0\nf 1 2 99999999999999999999\n");
        assert!(
            e.starts_with("t.obj:2: face 0: cannot read vertex index"),
            "{e}"
        );
    }

    #[test]
    fn write_then_read_is_bit_exact_and_keeps_quads() {
        let positions = vec![
            Vec3::new(0.1, -0.0, 1e-300),
            Vec3::new(1.0 / 3.0, 2.0f64.sqrt(), -7.25e12),
            Vec3::new(f64::MIN_POSITIVE, f64::MAX, -f64::EPSILON),
            Vec3::new(0.3, 0.7, 5e-324),
            Vec3::new(-1.0, 2.0, 3.0),
        ];
        let soup = Soup::from_polygons(positions, &[vec![0u32, 1, 2, 3], vec![1, 4, 2]]);
        let mut out = Vec::new();
        write(&mut out, &soup).unwrap();
        let back = read(&out, Path::new("x.obj")).unwrap();
        assert_eq!(back.offsets, soup.offsets);
        assert_eq!(back.indices, soup.indices);
        for (a, b) in back.positions.iter().zip(&soup.positions) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
    }
}
