//! The PLY header: elements, their properties and scalar types, the
//! encoding, and which properties are the vertex positions and face indices.

use std::path::Path;

use crate::io::text::{Lines, show};
use crate::io::{IoError, Location, format_err};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
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

    pub(super) fn size(self) -> usize {
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
    pub(super) fn holds(self, v: f64) -> bool {
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
    pub(super) fn name(self) -> &'static str {
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
    pub(super) fn get(self, b: &[u8], big: bool) -> f64 {
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
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<Property>,
    /// Header line that declared the element.
    pub(super) line: usize,
}

impl Element {
    /// Bytes of one row when it has no list property.
    pub(super) fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0, |acc, p| match p.kind {
            Kind::Scalar(s) => Some(acc + s.size()),
            Kind::List { .. } => None,
        })
    }

    /// The fewest bytes one row can take (lists empty).
    pub(super) fn min_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }

    pub(super) fn prop(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    Little,
    Big,
}

pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// Byte offset of the body.
    pub(super) body_start: usize,
    /// Number of header lines (the body starts on the next line).
    pub(super) lines: usize,
}

/// What a reader does with an element.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    Vertex,
    Face,
    Skip,
}

pub(super) fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
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
