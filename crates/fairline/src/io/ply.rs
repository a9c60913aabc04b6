//! Stanford PLY: ascii, binary little-endian and binary big-endian.
//!
//! Read: elements in any order, properties in any order and of any scalar
//! type (`char`/`int8` ... `double`/`float64`), list properties anywhere
//! (skipped unless they are the face's `vertex_indices` / `vertex_index`),
//! unknown elements (edges, materials, ...) skipped, `comment` and
//! `obj_info` lines, CRLF line endings (the header: `\n` or `\r\n` only, as
//! binary data follows it). Polygons are kept. Binary bodies are
//! parsed by slicing the bytes in memory; every header count is checked
//! against the bytes that remain before anything is allocated.
//! Refused rather than converted or ignored: an ascii value that does not fit
//! its declared type (a `uchar` of 300, an `int` of 1.5, a `float` beyond
//! ±3.4e38), rows after the last announced element (ascii), and bytes after
//! the end of the binary data (only a final line ending is tolerated).
//! Write: binary little-endian, `double x y z` plus optional extra double
//! vertex properties, faces as `list uchar int vertex_indices` (`uint` count
//! when a face has more than 255 vertices).

use std::io::{self, Write};
use std::path::Path;

use super::{IoError, Location, VertexProperties as Extra, format_err};
use crate::mesh::Soup;
use ascii::read_ascii;
use binary::read_binary;
use header::{Element, Encoding, Kind, Role, parse_header};

mod ascii;
mod binary;
mod header;
#[cfg(test)]
mod tests;

/// Everything the body readers need besides the bytes.
struct Plan {
    roles: Vec<Role>,
    /// Index of x, y, z in the vertex element.
    xyz: [usize; 3],
    /// Index of the index list in the face element.
    face_list: usize,
    /// Number of vertices announced by the header.
    nv: usize,
    /// Collect the other scalar vertex properties.
    collect: bool,
}

/// Parses a PLY file; with `collect`, also returns the scalar vertex
/// properties other than x, y, z.
pub(super) fn read(bytes: &[u8], path: &Path, collect: bool) -> Result<(Soup, Extra), IoError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(format_err(path, Location::File, "empty file"));
    }
    let header = parse_header(bytes, path)?;
    let herr = |line: usize, m: String| format_err(path, Location::Line(line), m);
    let mut roles = vec![Role::Skip; header.elements.len()];
    let vi = header.elements.iter().position(|e| e.name == "vertex");
    let fi = header.elements.iter().position(|e| e.name == "face");
    let Some(vi) = vi else {
        return Err(herr(
            header.lines,
            "the header declares no vertex element".into(),
        ));
    };
    roles[vi] = Role::Vertex;
    let ve = &header.elements[vi];
    let mut xyz = [0; 3];
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        xyz[k] = match ve.prop(name) {
            Some(i) if matches!(ve.props[i].kind, Kind::Scalar(_)) => i,
            Some(_) => return Err(herr(ve.line, format!("vertex property {name} is a list"))),
            None => {
                return Err(herr(
                    ve.line,
                    format!("element vertex has no property {name}"),
                ));
            }
        };
    }
    let mut face_list = 0;
    if let Some(fi) = fi {
        let fe = &header.elements[fi];
        let list = fe
            .prop("vertex_indices")
            .or_else(|| fe.prop("vertex_index"));
        match list {
            Some(i) if matches!(fe.props[i].kind, Kind::List { .. }) => {
                face_list = i;
                roles[fi] = Role::Face;
            }
            Some(_) => {
                return Err(herr(
                    fe.line,
                    "face property vertex_indices is not a list".into(),
                ));
            }
            None if fe.count == 0 => {}
            None => {
                return Err(herr(
                    fe.line,
                    "element face has no list property vertex_indices".into(),
                ));
            }
        }
    }
    let plan = Plan {
        roles,
        xyz,
        face_list,
        nv: ve.count,
        collect,
    };
    match header.encoding {
        Encoding::Ascii => read_ascii(bytes, path, &header, &plan),
        Encoding::Little => read_binary(bytes, path, &header, &plan, false),
        Encoding::Big => read_binary(bytes, path, &header, &plan, true),
    }
}

/// The extra vertex properties to collect: (property index, name).
fn extra_props(el: &Element, plan: &Plan) -> Vec<usize> {
    if !plan.collect {
        return Vec::new();
    }
    el.props
        .iter()
        .enumerate()
        .filter(|(i, p)| matches!(p.kind, Kind::Scalar(_)) && !plan.xyz.contains(i))
        .map(|(i, _)| i)
        .collect()
}

/// Writes a binary little-endian PLY with double coordinates, the extra
/// double vertex properties, and the faces.
pub(super) fn write(w: &mut impl Write, soup: &Soup, props: &[(&str, &[f64])]) -> io::Result<()> {
    let wide = soup.faces().any(|f| f.len() > 255);
    let count_ty = if wide { "uint" } else { "uchar" };
    let index_ty = if soup.vertex_count() > i32::MAX as usize {
        "uint"
    } else {
        "int"
    };
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by fairline\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\n",
        soup.vertex_count()
    )?;
    for (name, _) in props {
        writeln!(w, "property double {name}")?;
    }
    write!(
        w,
        "element face {}\nproperty list {count_ty} {index_ty} vertex_indices\nend_header\n",
        soup.face_count()
    )?;
    let mut row = Vec::with_capacity(8 * (3 + props.len()));
    for (v, p) in soup.positions.iter().enumerate() {
        row.clear();
        for c in p.to_array() {
            row.extend_from_slice(&c.to_le_bytes());
        }
        for (_, values) in props {
            row.extend_from_slice(&values.get(v).copied().unwrap_or(0.0).to_le_bytes());
        }
        w.write_all(&row)?;
    }
    for face in soup.faces() {
        row.clear();
        if wide {
            row.extend_from_slice(&(face.len() as u32).to_le_bytes());
        } else {
            row.push(face.len() as u8);
        }
        for &i in face {
            row.extend_from_slice(&i.to_le_bytes());
        }
        w.write_all(&row)?;
    }
    Ok(())
}
