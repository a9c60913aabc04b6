//! Binary PLY bodies (little- and big-endian), read by slicing the bytes in
//! memory, every count checked against the bytes that remain.

use std::path::Path;

use super::header::{Element, Header, Kind, Property, Role, Scalar};
use super::{Plan, extra_props};
use crate::Vec3;
use crate::io::text::{push_face, trailing_bytes};
use crate::io::{IoError, Location, VertexProperties as Extra, format_err};
use crate::mesh::Soup;

/// The binary body: every element in header order, each by its role.
pub(super) fn read_binary(
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
