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

use super::text::{
    Lines, capped_capacity, parse_f64, parse_i64, push_face, show, tokens, trailing_bytes,
};
use super::{IoError, Location, VertexProperties as Extra, format_err};
use crate::Vec3;
use crate::mesh::Soup;

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Whether a value read from ascii text can be stored in this type: an
    /// integer within the type's range for the integer types, a value within
    /// ±`f32::MAX` for `float` (NaN and infinity are left to the callers,
    /// which refuse them for coordinates). A `uchar` of 300 or an `int` of
    /// 1.5 is a broken file, not a value to convert silently.
    fn holds(self, v: f64) -> bool {
        let int_in = |lo: f64, hi: f64| v.fract() == 0.0 && (lo..=hi).contains(&v);
        match self {
            Scalar::I8 => int_in(i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => int_in(0.0, u8::MAX.into()),
            Scalar::I16 => int_in(i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => int_in(0.0, u16::MAX.into()),
            Scalar::I32 => int_in(i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => int_in(0.0, u32::MAX.into()),
            Scalar::F32 => !v.is_finite() || v.abs() <= f64::from(f32::MAX),
            Scalar::F64 => true,
        }
    }

    /// The type's name as written in PLY headers.
    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// The value at the start of `b`, which holds at least `self.size()`
    /// bytes (checked by the caller).
    #[inline(always)]
    fn get(self, b: &[u8], big: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:literal) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(rd!(i16, 2)),
            Scalar::U16 => f64::from(rd!(u16, 2)),
            Scalar::I32 => f64::from(rd!(i32, 4)),
            Scalar::U32 => f64::from(rd!(u32, 4)),
            Scalar::F32 => f64::from(rd!(f32, 4)),
            Scalar::F64 => rd!(f64, 8),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    /// Header line that declared the element.
    line: usize,
}

impl Element {
    /// Bytes of one row when it has no list property.
    fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0, |acc, p| match p.kind {
            Kind::Scalar(s) => Some(acc + s.size()),
            Kind::List { .. } => None,
        })
    }

    /// The fewest bytes one row can take (lists empty).
    fn min_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }

    fn prop(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of header lines (the body starts on the next line).
    lines: usize,
}

/// What a reader does with an element.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Vertex,
    Face,
    Skip,
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
    let err = |line: usize, m: String| format_err(path, Location::Line(line), m);
    let mut lines = Lines::lf_only(bytes, 1);
    match lines.next() {
        Some((_, l)) if l.trim_ascii() == b"ply" => {}
        _ => {
            return Err(err(
                1,
                "not a PLY file (the first line is not 'ply')".into(),
            ));
        }
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut last_line = 1;
    for (ln, raw) in lines.by_ref() {
        last_line = ln;
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(err(ln, "header line is not text".into()));
        };
        let mut t = line.split_ascii_whitespace();
        let Some(keyword) = t.next() else { continue };
        match keyword {
            "comment" | "obj_info" => {}
            "format" => {
                let name = t.next().unwrap_or("");
                encoding = Some(match name {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    _ => {
                        return Err(err(
                            ln,
                            format!("unknown PLY format '{}'", show(name.as_bytes())),
                        ));
                    }
                });
            }
            "element" => {
                let (Some(name), Some(count)) = (t.next(), t.next()) else {
                    return Err(err(ln, "element line needs a name and a count".into()));
                };
                let count: usize = count.parse().map_err(|_| {
                    err(
                        ln,
                        format!(
                            "element {name}: cannot read count '{}'",
                            show(count.as_bytes())
                        ),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: ln,
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(ln, "property before any element".into()));
                };
                let words: Vec<&str> = t.collect();
                let ty = |w: &str| {
                    Scalar::parse(w).ok_or_else(|| {
                        err(
                            ln,
                            format!("unknown property type '{}'", show(w.as_bytes())),
                        )
                    })
                };
                let (kind, name) = match words.as_slice() {
                    ["list", count, item, name] => {
                        let count = ty(count)?;
                        if !count.is_integer() {
                            return Err(err(ln, "list length type must be an integer type".into()));
                        }
                        (
                            Kind::List {
                                count,
                                item: ty(item)?,
                            },
                            name,
                        )
                    }
                    [t, name] if *t != "list" => (Kind::Scalar(ty(t)?), name),
                    _ => {
                        return Err(err(
                            ln,
                            format!("malformed property line '{}'", show(line.as_bytes())),
                        ));
                    }
                };
                el.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => {
                let Some(encoding) = encoding else {
                    return Err(err(ln, "the header has no format line".into()));
                };
                if let Some(el) = elements.iter().find(|e| e.props.is_empty() && e.count > 0) {
                    return Err(err(
                        el.line,
                        format!("element {} has no properties", el.name),
                    ));
                }
                return Ok(Header {
                    encoding,
                    elements,
                    body_start: bytes.len() - lines.remaining(),
                    lines: ln,
                });
            }
            _ => {
                return Err(err(
                    ln,
                    format!("unexpected header line '{}'", show(line.as_bytes())),
                ));
            }
        }
    }
    Err(err(last_line, "the header has no end_header line".into()))
}

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

/// The binary body: every element in header order, each by its role.
fn read_binary(
    bytes: &[u8],
    path: &Path,
    header: &Header,
    plan: &Plan,
    big: bool,
) -> Result<(Soup, Extra), IoError> {
    let mut body = BinaryBody {
        bytes,
        path,
        big,
        pos: header.body_start,
    };
    let mut soup = Soup::new();
    let mut extra: Extra = Vec::new();
    for (el, &role) in header.elements.iter().zip(&plan.roles) {
        let remaining = bytes.len() - body.pos;
        let min = el.min_size();
        if min.checked_mul(el.count).is_none_or(|n| n > remaining) {
            return Err(body.err(
                body.pos,
                format!(
                    "element {}: the header announces {} rows of at least {min} bytes, but only {remaining} bytes remain (truncated file?)",
                    el.name, el.count
                ),
            ));
        }
        match role {
            Role::Vertex => extra = body.vertices(el, plan, &mut soup)?,
            Role::Face => body.faces(el, plan, &mut soup)?,
            Role::Skip => body.skip(el)?,
        }
    }
    trailing_bytes(bytes, body.pos, path)?;
    Ok((soup, extra))
}

/// A binary PLY body being read: the bytes, the byte order and the position
/// of the next row.
struct BinaryBody<'a> {
    bytes: &'a [u8],
    path: &'a Path,
    big: bool,
    pos: usize,
}

impl BinaryBody<'_> {
    /// An error at byte `at`.
    fn err(&self, at: usize, m: String) -> IoError {
        format_err(self.path, Location::Byte(at), m)
    }

    /// The error of a row `i` of element `what` starting at `at` that the
    /// file ends inside.
    fn eof(&self, at: usize, what: &str, i: usize) -> IoError {
        self.err(
            at,
            format!("{what} {i}: file ends inside the element (truncated file?)"),
        )
    }

    /// The vertex element: positions into `soup`, and the extra scalar
    /// properties when the plan collects them. Rows without lists (the
    /// usual case) are sliced at fixed offsets.
    fn vertices(&mut self, el: &Element, plan: &Plan, soup: &mut Soup) -> Result<Extra, IoError> {
        let (bytes, big) = (self.bytes, self.big);
        let cols = extra_props(el, plan);
        let mut extra: Extra = cols
            .iter()
            .map(|&c| (el.props[c].name.clone(), Vec::with_capacity(el.count)))
            .collect();
        soup.positions.reserve_exact(el.count);
        let tys: Vec<Scalar> = el
            .props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) | Kind::List { count: s, .. } => s,
            })
            .collect();
        let Some(stride) = el.fixed_size() else {
            return self.vertices_with_lists(el, plan, soup, cols, extra);
        };
        let mut offs = Vec::with_capacity(el.props.len());
        let mut o = 0;
        for t in &tys {
            offs.push(o);
            o += t.size();
        }
        let [ix, iy, iz] = plan.xyz;
        let (tx, ty, tz) = (tys[ix], tys[iy], tys[iz]);
        let (ox, oy, oz) = (offs[ix], offs[iy], offs[iz]);
        let pos = self.pos;
        let body = &bytes[pos..pos + stride * el.count];
        for (i, row) in body.chunks_exact(stride).enumerate() {
            let p = Vec3::new(
                tx.get(&row[ox..], big),
                ty.get(&row[oy..], big),
                tz.get(&row[oz..], big),
            );
            if !p.is_finite() {
                return Err(self.err(
                    pos + i * stride,
                    format!("vertex {i}: coordinate is not finite ({p})"),
                ));
            }
            soup.positions.push(p);
            for (k, &c) in cols.iter().enumerate() {
                extra[k].1.push(tys[c].get(&row[offs[c]..], big));
            }
        }
        self.pos += stride * el.count;
        Ok(extra)
    }

    /// The vertex element when its rows hold list properties (skipped):
    /// every row is walked property by property.
    fn vertices_with_lists(
        &mut self,
        el: &Element,
        plan: &Plan,
        soup: &mut Soup,
        cols: Vec<usize>,
        mut extra: Extra,
    ) -> Result<Extra, IoError> {
        let (bytes, big) = (self.bytes, self.big);
        let mut vals = vec![0.0; el.props.len()];
        for i in 0..el.count {
            let start = self.pos;
            for (j, prop) in el.props.iter().enumerate() {
                match prop.kind {
                    Kind::Scalar(s) => {
                        let b = bytes
                            .get(self.pos..self.pos + s.size())
                            .ok_or_else(|| self.eof(start, "vertex", i))?;
                        vals[j] = s.get(b, big);
                        self.pos += s.size();
                    }
                    Kind::List { count, item } => {
                        self.pos = skip_list(bytes, self.pos, count, item, big)
                            .ok_or_else(|| self.eof(start, "vertex", i))?;
                    }
                }
            }
            let p = Vec3::new(vals[plan.xyz[0]], vals[plan.xyz[1]], vals[plan.xyz[2]]);
            if !p.is_finite() {
                return Err(self.err(start, format!("vertex {i}: coordinate is not finite ({p})")));
            }
            soup.positions.push(p);
            for (k, &c) in cols.iter().enumerate() {
                extra[k].1.push(vals[c]);
            }
        }
        Ok(extra)
    }

    /// The face element: the vertex index list of every row into `soup`
    /// (indices checked against the vertex count), other properties skipped.
    fn faces(&mut self, el: &Element, plan: &Plan, soup: &mut Soup) -> Result<(), IoError> {
        let (bytes, big) = (self.bytes, self.big);
        soup.offsets.reserve_exact(el.count);
        if let [
            Property {
                kind:
                    Kind::List {
                        count: Scalar::U8,
                        item: item @ (Scalar::I32 | Scalar::U32),
                    },
                ..
            },
        ] = el.props.as_slice()
        {
            return self.faces_uchar_int(el.count, *item == Scalar::I32, plan.nv, soup);
        }
        let nv = plan.nv as f64;
        let mut corners: Vec<u32> = Vec::new();
        for f in 0..el.count {
            let start = self.pos;
            for (j, prop) in el.props.iter().enumerate() {
                match prop.kind {
                    Kind::Scalar(s) => {
                        if self.pos + s.size() > bytes.len() {
                            return Err(self.eof(start, "face", f));
                        }
                        self.pos += s.size();
                    }
                    Kind::List { count, item } if j == plan.face_list => {
                        let b = bytes
                            .get(self.pos..self.pos + count.size())
                            .ok_or_else(|| self.eof(start, "face", f))?;
                        let n = count.get(b, big);
                        self.pos += count.size();
                        if n < 3.0 {
                            return Err(self.err(
                                start,
                                format!("face {f}: has {n} vertices; a face needs at least 3"),
                            ));
                        }
                        let n = n as usize;
                        let len = n
                            .checked_mul(item.size())
                            .ok_or_else(|| self.eof(start, "face", f))?;
                        let items = bytes
                            .get(self.pos..)
                            .and_then(|r| r.get(..len))
                            .ok_or_else(|| self.eof(start, "face", f))?;
                        corners.clear();
                        for b in items.chunks_exact(item.size()) {
                            let v = item.get(b, big);
                            if !(v >= 0.0 && v < nv && v.fract() == 0.0) {
                                return Err(self.err(
                                    start,
                                    format!(
                                        "face {f}: vertex index {v} out of range ({} vertices)",
                                        plan.nv
                                    ),
                                ));
                            }
                            corners.push(v as u32);
                        }
                        self.pos += len;
                        push_face(soup, &corners)
                            .map_err(|m| self.err(start, format!("face {f}: {m}")))?;
                    }
                    Kind::List { count, item } => {
                        self.pos = skip_list(bytes, self.pos, count, item, big)
                            .ok_or_else(|| self.eof(start, "face", f))?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The usual face element, `list uchar int vertex_indices` (or `uint`)
    /// and nothing else, read straight from the bytes: the same checks and
    /// messages as [`Self::faces`] without converting every index to `f64`.
    fn faces_uchar_int(
        &mut self,
        count: usize,
        signed: bool,
        nv: usize,
        soup: &mut Soup,
    ) -> Result<(), IoError> {
        let (bytes, big) = (self.bytes, self.big);
        let mut corners: Vec<u32> = Vec::with_capacity(8);
        for f in 0..count {
            let start = self.pos;
            let n = usize::from(*bytes.get(start).ok_or_else(|| self.eof(start, "face", f))?);
            if n < 3 {
                return Err(self.err(
                    start,
                    format!("face {f}: has {n} vertices; a face needs at least 3"),
                ));
            }
            let items = bytes
                .get(start + 1..start + 1 + 4 * n)
                .ok_or_else(|| self.eof(start, "face", f))?;
            corners.clear();
            for b in items.chunks_exact(4) {
                let raw = [b[0], b[1], b[2], b[3]];
                let v = match (signed, big) {
                    (true, false) => i64::from(i32::from_le_bytes(raw)),
                    (true, true) => i64::from(i32::from_be_bytes(raw)),
                    (false, false) => i64::from(u32::from_le_bytes(raw)),
                    (false, true) => i64::from(u32::from_be_bytes(raw)),
                };
                if v < 0 || v as u64 >= nv as u64 {
                    return Err(self.err(
                        start,
                        format!("face {f}: vertex index {v} out of range ({nv} vertices)"),
                    ));
                }
                corners.push(v as u32);
            }
            self.pos = start + 1 + 4 * n;
            push_face(soup, &corners).map_err(|m| self.err(start, format!("face {f}: {m}")))?;
        }
        Ok(())
    }

    /// An element the reader does not use (edges, materials, ...).
    fn skip(&mut self, el: &Element) -> Result<(), IoError> {
        if let Some(stride) = el.fixed_size() {
            self.pos += stride * el.count;
            return Ok(());
        }
        for i in 0..el.count {
            let start = self.pos;
            for prop in &el.props {
                self.pos = match prop.kind {
                    Kind::Scalar(s) => Some(self.pos + s.size()).filter(|&p| p <= self.bytes.len()),
                    Kind::List { count, item } => {
                        skip_list(self.bytes, self.pos, count, item, self.big)
                    }
                }
                .ok_or_else(|| self.eof(start, &el.name, i))?;
            }
        }
        Ok(())
    }
}

/// The position after a list property starting at `pos`, or `None` when the
/// file ends inside it or its length is negative.
#[inline]
fn skip_list(bytes: &[u8], pos: usize, count: Scalar, item: Scalar, big: bool) -> Option<usize> {
    let n = count.get(bytes.get(pos..pos + count.size())?, big);
    if n < 0.0 {
        return None;
    }
    let end = (pos + count.size()).checked_add((n as usize).checked_mul(item.size())?)?;
    (end <= bytes.len()).then_some(end)
}

/// The ascii body: every element in header order, one row per line.
fn read_ascii(
    bytes: &[u8],
    path: &Path,
    header: &Header,
    plan: &Plan,
) -> Result<(Soup, Extra), IoError> {
    let mut soup = Soup::new();
    let mut extra: Extra = Vec::new();
    let mut lines = Lines::new(&bytes[header.body_start..], header.lines + 1);
    let mut last_line = header.lines;
    let mut toks: Vec<&[u8]> = Vec::new();
    let mut vals: Vec<f64> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    for (el, &role) in header.elements.iter().zip(&plan.roles) {
        let what = match role {
            Role::Vertex => "vertex",
            Role::Face => "face",
            Role::Skip => el.name.as_str(),
        };
        let cols = if role == Role::Vertex {
            extra_props(el, plan)
        } else {
            Vec::new()
        };
        let cap = capped_capacity(el.count, lines.remaining(), 2 * el.props.len());
        match role {
            Role::Vertex => {
                soup.positions.reserve(cap);
                extra = cols
                    .iter()
                    .map(|&c| (el.props[c].name.clone(), Vec::with_capacity(cap)))
                    .collect();
            }
            Role::Face => soup.offsets.reserve(cap),
            Role::Skip => {}
        }
        vals.clear();
        vals.resize(el.props.len(), 0.0);
        for i in 0..el.count {
            let (ln, line) = loop {
                match lines.next() {
                    Some((ln, l)) if l.trim_ascii().is_empty() => last_line = ln,
                    Some(x) => break x,
                    None => {
                        return Err(format_err(
                            path,
                            Location::Line(last_line),
                            format!(
                                "{what} {i}: unexpected end of file (the header announces {} rows of element {})",
                                el.count, el.name
                            ),
                        ));
                    }
                }
            };
            last_line = ln;
            let err = |m: String| format_err(path, Location::Line(ln), format!("{what} {i}: {m}"));
            toks.clear();
            toks.extend(tokens(line));
            let face_list = (role == Role::Face).then_some(plan.face_list);
            let k = ascii_row(
                el,
                &toks,
                face_list,
                plan.nv,
                &mut vals,
                &mut corners,
                &mut soup,
            )
            .map_err(err)?;
            if k < toks.len() {
                return Err(err(format!("expected {k} values, found {}", toks.len())));
            }
            if role == Role::Vertex {
                let p = Vec3::new(vals[plan.xyz[0]], vals[plan.xyz[1]], vals[plan.xyz[2]]);
                if !p.is_finite() {
                    return Err(err(format!("coordinate is not finite ({p})")));
                }
                soup.positions.push(p);
                for (c, &col) in cols.iter().enumerate() {
                    extra[c].1.push(vals[col]);
                }
            }
        }
    }
    // rows beyond the header's counts would be lost silently
    if let Some((ln, _)) = lines.find(|(_, l)| !l.trim_ascii().is_empty()) {
        return Err(format_err(
            path,
            Location::Line(ln),
            "data after the last element (the header's counts announce fewer rows)",
        ));
    }
    Ok((soup, extra))
}

/// Parses one ascii row (`toks`) of element `el`: scalar values into
/// `vals` (by property), and, when `face_list` names the face's index
/// list, its vertex indices (checked against the `nv` vertices) as a face
/// of `soup`; other lists are checked and skipped. Returns the number of
/// tokens used, or the message of the first problem.
fn ascii_row(
    el: &Element,
    toks: &[&[u8]],
    face_list: Option<usize>,
    nv: usize,
    vals: &mut [f64],
    corners: &mut Vec<u32>,
    soup: &mut Soup,
) -> Result<usize, String> {
    let mut k = 0;
    for (j, prop) in el.props.iter().enumerate() {
        let rest = el.props.len() - j - 1;
        let Some(tok) = toks.get(k) else {
            return Err(format!(
                "expected {} values, found {}",
                k + 1 + rest,
                toks.len()
            ));
        };
        match prop.kind {
            Kind::Scalar(s) => {
                let v = parse_f64(tok).ok_or_else(|| {
                    format!(
                        "cannot read '{}' as property {} ({})",
                        show(tok),
                        prop.name,
                        s.name()
                    )
                })?;
                if !s.holds(v) {
                    return Err(format!(
                        "value '{}' of property {} does not fit its type {}",
                        show(tok),
                        prop.name,
                        s.name()
                    ));
                }
                vals[j] = v;
                k += 1;
            }
            Kind::List { count, item } => {
                let n = parse_i64(tok)
                    .filter(|&n| n >= 0 && count.holds(n as f64))
                    .ok_or_else(|| {
                        format!(
                            "cannot read list length '{}' of property {} ({})",
                            show(tok),
                            prop.name,
                            count.name()
                        )
                    })?;
                let need = (n as u64).saturating_add((k + 1 + rest) as u64);
                if need > toks.len() as u64 {
                    return Err(format!("expected {need} values, found {}", toks.len()));
                }
                let n = n as usize;
                let items = &toks[k + 1..k + 1 + n];
                if face_list == Some(j) {
                    if n < 3 {
                        return Err(format!("has {n} vertices; a face needs at least 3"));
                    }
                    corners.clear();
                    for tok in items {
                        let v = parse_i64(tok)
                            .filter(|&v| item.holds(v as f64))
                            .ok_or_else(|| {
                                format!(
                                    "cannot read vertex index '{}' ({})",
                                    show(tok),
                                    item.name()
                                )
                            })?;
                        if v < 0 || v as u64 >= nv as u64 {
                            return Err(format!("vertex index {v} out of range ({nv} vertices)"));
                        }
                        corners.push(v as u32);
                    }
                    push_face(soup, corners).map_err(String::from)?;
                } else if let Some(tok) = items
                    .iter()
                    .find(|t| parse_f64(t).is_none_or(|v| !item.holds(v)))
                {
                    return Err(format!(
                        "cannot read '{}' in list {} as {}",
                        show(tok),
                        prop.name,
                        item.name()
                    ));
                }
                k += 1 + n;
            }
        }
    }
    Ok(k)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(bytes: &[u8]) -> Result<Soup, IoError> {
        read(bytes, Path::new("t.ply"), false).map(|(s, _)| s)
    }

    fn err(bytes: &[u8]) -> String {
        parse(bytes).unwrap_err().to_string()
    }

    /// A tiny byte writer for binary test files.
    struct Bin {
        out: Vec<u8>,
        big: bool,
    }

    impl Bin {
        fn new(header: &str, big: bool) -> Self {
            Bin {
                out: header.as_bytes().to_vec(),
                big,
            }
        }
        fn f32(&mut self, v: f32) -> &mut Self {
            let b = if self.big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            self.out.extend_from_slice(&b);
            self
        }
        fn f64(&mut self, v: f64) -> &mut Self {
            let b = if self.big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            self.out.extend_from_slice(&b);
            self
        }
        fn i32(&mut self, v: i32) -> &mut Self {
            let b = if self.big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            self.out.extend_from_slice(&b);
            self
        }
        fn u16(&mut self, v: u16) -> &mut Self {
            let b = if self.big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            self.out.extend_from_slice(&b);
            self
        }
        fn u8(&mut self, v: u8) -> &mut Self {
            self.out.push(v);
            self
        }
    }

    const ASCII: &str = "ply\r\nformat ascii 1.0\r\ncomment hello\r\nobj_info made by hand\r\n\
        element vertex 4\r\nproperty float y\r\nproperty float x\r\nproperty uchar red\r\n\
        property float z\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n\
        end_header\r\n0 0 255 0\r\n0 1 0 0\r\n1 1 3 0\r\n1 0 4 0.5\r\n4 0 1 2 3\r\n3 0 2 3\r\n";

    #[test]
    fn ascii_with_permuted_properties_comments_crlf_and_quads() {
        let s = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(s.vertex_count(), 4);
        assert_eq!(s.positions[1], Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(s.positions[3], Vec3::new(0.0, 1.0, 0.5));
        assert_eq!(s.face(0), &[0, 1, 2, 3]);
        assert_eq!(s.face(1), &[0, 2, 3]);
        let (_, extra) = read(ASCII.as_bytes(), Path::new("t.ply"), true).unwrap();
        assert_eq!(extra, vec![("red".to_string(), vec![255.0, 0.0, 3.0, 4.0])]);
    }

    /// A binary file with faces before vertices, an edge element with a
    /// list, a material element, a list in the vertex element, and face
    /// properties around the index list.
    fn tricky_binary(big: bool) -> Vec<u8> {
        let header = format!(
            "ply\nformat binary_{}_endian 1.0\ncomment tricky\n\
             element material 1\nproperty uchar r\nproperty double shininess\n\
             element face 2\nproperty ushort flags\nproperty list uchar int vertex_index\n\
             property list int float texcoord\n\
             element vertex 4\nproperty double z\nproperty list uchar uchar tags\n\
             property float x\nproperty double y\nproperty float quality\n\
             element edge 1\nproperty list uchar int vertex_indices\nproperty uchar crease\n\
             end_header\n",
            if big { "big" } else { "little" }
        );
        let mut b = Bin::new(&header, big);
        b.u8(7).f64(0.5);
        b.u16(1).u8(4).i32(0).i32(1).i32(2).i32(3);
        b.i32(2).f32(0.25).f32(0.75);
        b.u16(2).u8(3).i32(3).i32(2).i32(1);
        b.i32(0);
        let xyz = [
            [0.0, 0.0, 0.1],
            [1.0, 0.0, 0.2],
            [1.0, 1.0, 0.3],
            [0.0, 1.0, 0.4],
        ];
        for (i, p) in xyz.iter().enumerate() {
            b.f64(p[2]).u8(i as u8);
            for _ in 0..i {
                b.u8(9);
            }
            b.f32(p[0] as f32).f64(p[1]).f32(i as f32 * 10.0);
        }
        b.u8(2).i32(0).i32(1).u8(1);
        b.out
    }

    #[test]
    fn binary_little_and_big_endian_with_lists_and_extra_elements() {
        for big in [false, true] {
            let bytes = tricky_binary(big);
            let (s, extra) = read(&bytes, Path::new("t.ply"), true).unwrap();
            assert_eq!(s.vertex_count(), 4, "big={big}");
            assert_eq!(s.positions[2], Vec3::new(1.0, 1.0, 0.3));
            assert_eq!(s.face(0), &[0, 1, 2, 3]);
            assert_eq!(s.face(1), &[3, 2, 1]);
            assert_eq!(
                extra,
                vec![("quality".to_string(), vec![0.0, 10.0, 20.0, 30.0])]
            );
            // every truncation is an error, never a panic
            for cut in 0..bytes.len() {
                assert!(parse(&bytes[..cut]).is_err(), "cut {cut} big={big}");
            }
        }
    }

    #[test]
    fn write_then_read_is_bit_exact_with_properties_and_big_faces() {
        let n = 300;
        let positions: Vec<Vec3> = (0..n)
            .map(|i| {
                let t = i as f64 * 0.1;
                Vec3::new(t.sin() / 3.0, -0.0, t.cos() * 1e-310)
            })
            .collect();
        let ring: Vec<u32> = (0..n as u32).collect();
        let soup = Soup::from_polygons(positions, &[ring, vec![0, 1, 2, 3]]);
        let k: Vec<f64> = (0..n).map(|i| i as f64 / 7.0).collect();
        let mut out = Vec::new();
        write(&mut out, &soup, &[("k1", &k)]).unwrap();
        let text = String::from_utf8_lossy(&out[..400]).to_string();
        assert!(
            text.contains("property list uint int vertex_indices"),
            "{text}"
        );
        let (back, extra) = read(&out, Path::new("x.ply"), true).unwrap();
        assert_eq!(back.offsets, soup.offsets);
        assert_eq!(back.indices, soup.indices);
        for (a, b) in back.positions.iter().zip(&soup.positions) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
        assert_eq!(extra[0].0, "k1");
        assert!(
            extra[0]
                .1
                .iter()
                .zip(&k)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        let small = Soup::from_polygons(soup.positions.clone(), &[[0u32, 1, 2]]);
        let mut out = Vec::new();
        write(&mut out, &small, &[]).unwrap();
        assert!(String::from_utf8_lossy(&out[..300]).contains("list uchar int vertex_indices"));
    }

    #[test]
    fn malformed_headers_name_the_line() {
        let e = err(b"plx\nformat ascii 1.0\nend_header\n");
        assert!(e.starts_with("t.ply:1: not a PLY file"), "{e}");
        let e = err(b"ply\nformat binary_middle_endian 1.0\nend_header\n");
        assert_eq!(e, "t.ply:2: unknown PLY format 'binary_middle_endian'");
        let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n");
        assert_eq!(e, "t.ply:4: unknown property type 'real'");
        let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n");
        assert_eq!(e, "t.ply:3: element vertex has no property z");
        let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
        assert!(e.contains("no end_header"), "{e}");
        let e = err(b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n");
        assert!(
            e.starts_with("t.ply:3: element vertex: cannot read count"),
            "{e}"
        );
        let e = err(b"ply\nelement vertex 1\nproperty float x\nend_header\n");
        assert!(e.contains("no format line"), "{e}");
        let e = err(b"ply\nformat ascii 1.0\nbogus line\nend_header\n");
        assert!(e.starts_with("t.ply:3: unexpected header line"), "{e}");
        let e = err(b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
        assert!(e.contains("no vertex element"), "{e}");
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

    #[test]
    fn malformed_ascii_bodies_name_line_and_element() {
        let f = |body: &str| err(format!("{HEAD}{body}").as_bytes());
        assert_eq!(
            f("0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
            "t.ply:11: vertex 1: expected 3 values, found 2"
        );
        assert!(
            f("0 0 0\n1 0 abc\n0 1 0\n3 0 1 2\n")
                .starts_with("t.ply:11: vertex 1: cannot read 'abc'")
        );
        assert!(
            f("0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n")
                .starts_with("t.ply:12: vertex 2: coordinate is not finite")
        );
        assert!(
            f("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
                .starts_with("t.ply:13: face 0: vertex index 3 out of range (3 vertices)")
        );
        assert!(
            f("0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n")
                .starts_with("t.ply:13: face 0: vertex index -1 out of range")
        );
        assert_eq!(
            f("0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
            "t.ply:13: face 0: has 2 vertices; a face needs at least 3"
        );
        assert_eq!(
            f("0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"),
            "t.ply:13: face 0: expected 5 values, found 4"
        );
        assert_eq!(
            f("0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n"),
            "t.ply:11: vertex 1: expected 3 values, found 4"
        );
        assert!(
            f("0 0 0\n1 0 0\n0 1 0\nx 0 1 2\n")
                .starts_with("t.ply:13: face 0: cannot read list length 'x'")
        );
        // the header announces more rows than the file has
        assert!(f("0 0 0\n1 0 0\n").starts_with("t.ply:11: vertex 2: unexpected end of file"));
        let huge = HEAD.replace("vertex 3", "vertex 4000000000000");
        let e = err(format!("{huge}0 0 0\n").as_bytes());
        assert!(e.contains("vertex 1: unexpected end of file"), "{e}");
    }

    #[test]
    fn malformed_binary_bodies_name_byte_and_element() {
        let head = HEAD.replace("ascii", "binary_little_endian");
        let mut b = Bin::new(&head, false);
        b.f32(0.0).f32(0.0).f32(0.0).f32(1.0).f32(f32::NAN).f32(0.0);
        b.f32(0.0).f32(1.0).f32(0.0).u8(3).i32(0).i32(1).i32(2);
        let e = err(&b.out);
        assert!(
            e.contains(&format!(
                "byte {}: vertex 1: coordinate is not finite",
                head.len() + 12
            )),
            "{e}"
        );
        let mut b = Bin::new(&head, false);
        for v in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            b.f32(v);
        }
        let good_vertices = b.out.clone();
        b.u8(3).i32(0).i32(1).i32(5);
        assert!(err(&b.out).contains("face 0: vertex index 5 out of range (3 vertices)"));
        let mut b = Bin {
            out: good_vertices.clone(),
            big: false,
        };
        b.u8(2).i32(0).i32(1);
        assert!(err(&b.out).contains("face 0: has 2 vertices"));
        let mut b = Bin {
            out: good_vertices.clone(),
            big: false,
        };
        b.u8(3).i32(0).i32(1);
        let e = err(&b.out);
        assert!(e.contains("face 0: file ends inside the element"), "{e}");
        // counts larger than the file are refused before allocating
        let huge = head.replace("vertex 3", "vertex 18446744073709551615");
        let e = err(&[huge.as_bytes(), &good_vertices[head.len()..]].concat());
        assert!(
            e.contains("element vertex: the header announces 18446744073709551615 rows"),
            "{e}"
        );
        let huge = head.replace("face 1", "face 3000000000");
        let e = err(&[huge.as_bytes(), &good_vertices[head.len()..]].concat());
        assert!(
            e.contains("element face: the header announces 3000000000 rows"),
            "{e}"
        );
    }
}
