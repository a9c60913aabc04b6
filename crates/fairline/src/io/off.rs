//! Geomview OFF: `OFF`, `COFF`, `NOFF`, `CNOFF` (and `ST` prefixes).
//!
//! Read: the header keyword (the counts may follow it on the same line),
//! `vertices faces [edges]`, one vertex per line (`x y z`, further values
//! such as normals and colours ignored), one face per line
//! (`n i1 .. in [colour]`), `#` comments and blank lines anywhere.
//! Polygons are kept. Lines beyond the announced counts are refused (they
//! mean the counts are wrong). Write: plain `OFF` with `{}`-formatted coordinates.

use std::io::{self, Write};
use std::path::Path;

use super::text::{
    Lines, capped_capacity, parse_f64, parse_i64, push_face, show, tokens, write_formatted,
};
use super::{IoError, Location, format_err};
use crate::Vec3;
use crate::mesh::Soup;

/// True for `OFF` optionally prefixed by `ST`, `C`, `N` in that order.
fn is_off_keyword(tok: &[u8]) -> bool {
    let t = tok.strip_prefix(b"ST").unwrap_or(tok);
    let t = t.strip_prefix(b"C").unwrap_or(t);
    let t = t.strip_prefix(b"N").unwrap_or(t);
    t == b"OFF"
}

/// Parses an OFF file.
pub(super) fn read(bytes: &[u8], path: &Path) -> Result<Soup, IoError> {
    let err = |ln: usize, m: String| format_err(path, Location::Line(ln), m);
    let mut lines = Lines::new(bytes, 1).filter_map(|(ln, raw)| {
        let line = match raw.iter().position(|&b| b == b'#') {
            Some(i) => &raw[..i],
            None => raw,
        };
        (!line.trim_ascii().is_empty()).then_some((ln, line))
    });
    let mut last_line = 1;
    // header keyword, possibly followed by the counts
    let mut counts: Vec<&[u8]> = Vec::new();
    let mut count_line = 0;
    if let Some((ln, line)) = lines.next() {
        last_line = ln;
        let mut t = tokens(line);
        let first = t.next().unwrap_or_default();
        if is_off_keyword(first) {
            counts.extend(t);
        } else if parse_i64(first).is_some() {
            counts.push(first);
            counts.extend(t);
        } else {
            return Err(err(
                ln,
                format!("not an OFF file: unknown header '{}'", show(first)),
            ));
        }
        count_line = ln;
    }
    if counts.is_empty() {
        match lines.next() {
            Some((ln, line)) => {
                counts.extend(tokens(line));
                count_line = ln;
                last_line = ln;
            }
            None => return Err(err(last_line, "missing vertex and face counts".into())),
        }
    }
    if counts.len() < 2 {
        return Err(err(
            count_line,
            format!(
                "expected vertex, face and edge counts, found {} values",
                counts.len()
            ),
        ));
    }
    let parse_count = |tok: &[u8], what: &str| {
        parse_i64(tok)
            .filter(|&n| (0..u32::MAX as i64).contains(&n))
            .map(|n| n as usize)
            .ok_or_else(|| {
                err(
                    count_line,
                    format!("cannot read {what} count '{}'", show(tok)),
                )
            })
    };
    let nv = parse_count(counts[0], "vertex")?;
    let nf = parse_count(counts[1], "face")?;
    let mut soup = Soup::new();
    soup.positions.reserve(capped_capacity(nv, bytes.len(), 6));
    soup.offsets.reserve(capped_capacity(nf, bytes.len(), 8));
    for v in 0..nv {
        let Some((ln, line)) = lines.next() else {
            return Err(err(
                last_line,
                format!("vertex {v}: unexpected end of file (the header announces {nv} vertices)"),
            ));
        };
        last_line = ln;
        let p = vertex_line(line).map_err(|m| err(ln, format!("vertex {v}: {m}")))?;
        soup.positions.push(p);
    }
    let mut corners = Vec::new();
    for f in 0..nf {
        let Some((ln, line)) = lines.next() else {
            return Err(err(
                last_line,
                format!("face {f}: unexpected end of file (the header announces {nf} faces)"),
            ));
        };
        last_line = ln;
        face_line(line, nv, &mut corners).map_err(|m| err(ln, format!("face {f}: {m}")))?;
        push_face(&mut soup, &corners).map_err(|m| err(ln, format!("face {f}: {m}")))?;
    }
    // lines beyond the header's counts would be lost silently
    if let Some((ln, _)) = lines.next() {
        return Err(err(
            ln,
            format!("data after the last face (the header announces {nv} vertices and {nf} faces)"),
        ));
    }
    Ok(soup)
}

/// The position on a vertex line (`x y z`, further values ignored).
fn vertex_line(line: &[u8]) -> Result<Vec3, String> {
    let mut t = tokens(line);
    let mut xyz = [0.0; 3];
    for (k, c) in xyz.iter_mut().enumerate() {
        let Some(tok) = t.next() else {
            return Err(format!("expected 3 coordinates, found {k}"));
        };
        *c = parse_f64(tok).ok_or_else(|| format!("cannot read coordinate '{}'", show(tok)))?;
        if !c.is_finite() {
            return Err(format!("coordinate '{}' is not finite", show(tok)));
        }
    }
    Ok(Vec3::from_array(xyz))
}

/// The vertex indices of a face line (`n i1 .. in [colour]`) into
/// `corners`, checked against the `nv` vertices.
fn face_line(line: &[u8], nv: usize, corners: &mut Vec<u32>) -> Result<(), String> {
    let mut t = tokens(line);
    let first = t.next().unwrap_or_default();
    let n = parse_i64(first)
        .filter(|&n| n >= 0)
        .ok_or_else(|| format!("cannot read vertex count '{}'", show(first)))?;
    if n < 3 {
        return Err(format!("has {n} vertices; a face needs at least 3"));
    }
    corners.clear();
    for k in 0..n {
        let Some(tok) = t.next() else {
            return Err(format!("expected {n} vertex indices, found {k}"));
        };
        let i =
            parse_i64(tok).ok_or_else(|| format!("cannot read vertex index '{}'", show(tok)))?;
        if i < 0 || i as u64 >= nv as u64 {
            return Err(format!("vertex index {i} out of range ({nv} vertices)"));
        }
        corners.push(i as u32);
    }
    Ok(())
}

/// Writes a plain OFF file with `{}`-formatted coordinates.
pub(super) fn write(w: &mut impl Write, soup: &Soup) -> io::Result<()> {
    writeln!(w, "OFF")?;
    writeln!(w, "{} {} 0", soup.vertex_count(), soup.face_count())?;
    write_formatted(w, soup.vertex_count(), |v, out| {
        let p = soup.positions[v];
        writeln!(out, "{} {} {}", p.x, p.y, p.z)
    })?;
    write_formatted(w, soup.face_count(), |f, out| {
        let face = soup.face(f);
        write!(out, "{}", face.len())?;
        for &i in face {
            write!(out, " {i}")?;
        }
        out.push(b'\n');
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Soup, IoError> {
        read(text.as_bytes(), Path::new("t.off"))
    }

    fn err(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn header_variants_comments_colours_and_quads() {
        let body =
            "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3 255 0 0\n3 0 2 3\n";
        for head in [
            "OFF\n4 2 0\n",
            "COFF 4 2 5\n",
            "NOFF\n# comment\n\n4 2\n",
            "CNOFF\r\n4 2 0\r\n",
            "4 2 0\n",
        ] {
            let s = parse(&format!("# leading comment\n{head}{body}")).unwrap();
            assert_eq!(s.vertex_count(), 4, "{head}");
            assert_eq!(s.face(0), &[0, 1, 2, 3]);
            assert_eq!(s.face(1), &[0, 2, 3]);
            assert_eq!(s.positions[2], Vec3::new(1.0, 1.0, 0.0));
        }
    }

    #[test]
    fn malformed_input_names_line_and_element() {
        assert_eq!(
            err("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
            "t.off:4: vertex 1: expected 3 coordinates, found 2"
        );
        assert!(
            err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 NaN 0\n3 0 1 2\n")
                .starts_with("t.off:5: vertex 2: coordinate 'NaN' is not finite")
        );
        assert!(
            err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
                .starts_with("t.off:6: face 0: vertex index 3 out of range (3 vertices)")
        );
        assert_eq!(
            err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
            "t.off:6: face 0: has 2 vertices; a face needs at least 3"
        );
        assert_eq!(
            err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"),
            "t.off:6: face 0: expected 4 vertex indices, found 3"
        );
        assert!(
            err("OFF\n3 1 0\n0 0 0\n1 0 zz\n0 1 0\n3 0 1 2\n")
                .starts_with("t.off:4: vertex 1: cannot read coordinate 'zz'")
        );
        assert!(
            err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 q 2\n")
                .starts_with("t.off:6: face 0: cannot read vertex index 'q'")
        );
        assert!(
            err("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
                .starts_with("t.off:6: face 1: unexpected end of file")
        );
        assert!(
            err("OFF\n3000000000 1 0\n0 0 0\n")
                .starts_with("t.off:3: vertex 1: unexpected end of file")
        );
        assert!(err("OFF\n-3 1 0\n").starts_with("t.off:2: cannot read vertex count '-3'"));
        assert!(err("OFF\n3\n").starts_with("t.off:2: expected vertex, face and edge counts"));
        assert!(err("PLY\n3 1 0\n").starts_with("t.off:1: not an OFF file"));
        assert!(err("OFF\n").contains("missing vertex and face counts"));
    }

    #[test]
    fn write_then_read_is_bit_exact() {
        let positions = vec![
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.0 / 3.0, -2.0 / 7.0, 1e-17),
            Vec3::new(123456.789, -0.0, 5e-324),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        let soup = Soup::from_polygons(positions, &[vec![0u32, 1, 2, 3], vec![0, 2, 3]]);
        let mut out = Vec::new();
        write(&mut out, &soup).unwrap();
        let back = read(&out, Path::new("x.off")).unwrap();
        assert_eq!(back.indices, soup.indices);
        assert_eq!(back.offsets, soup.offsets);
        for (a, b) in back.positions.iter().zip(&soup.positions) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
    }
}
