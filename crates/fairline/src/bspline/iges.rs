//! IGES import of rational B-spline surfaces (entity 128).
//!
//! Reads the fixed-format ASCII IGES file (IGES 5.3 §2): 80-column records
//! with the section letter (`S`, `G`, `D`, `P`, `T`) in column 73. The Global
//! section's first two fields set the parameter and record delimiters
//! (default `,` and `;`); Hollerith strings `nH…` may contain delimiters and
//! span records; parameter data occupy columns 1–64 of the `P` records and may
//! continue over several of them; directory entries come in pairs of `D`
//! records of ten 8-column fields. Reals may use `D` exponents (`1.0D+01`) or
//! omit digits (`1.`, `1.E-3`).
//!
//! Every entity 128 becomes a [`BSplineSurface`] (Piegl & Tiller's NURBS
//! form; IGES 5.3 §4.24): `K1, K2, M1, M2, PROP1..5`, knots S and T, weights,
//! control points and the parameter range `U0 U1 V0 V1`. A polynomial surface
//! (`PROP3 = 1`) is built without weights (they are still read and checked to
//! be numbers). A transformation matrix (entity 124, chained through its own
//! directory entry) referenced by directory field 7 is applied to the control
//! points. Trimming (entities 143 and 144) is ignored, but the surfaces it
//! refers to are counted and flagged.

use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat3};
use thiserror::Error;

use super::{BSplineError, BSplineSurface};
use crate::Vec3;

/// Why an IGES file could not be imported; names the file line and entity.
#[derive(Debug, Error)]
pub enum IgesError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The record structure is broken.
    #[error("line {line}: {message}")]
    Format {
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An entity's directory entry or parameter data is malformed.
    #[error("line {line}: entity {entity_type} (directory entry {entity}): {message}")]
    Entity {
        /// Directory entry sequence number (odd, 1-based).
        entity: usize,
        /// Entity type number.
        entity_type: i64,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An entity 128 does not make a valid B-spline surface.
    #[error("line {line}: entity 128 (directory entry {entity}): {source}")]
    Surface {
        /// Directory entry sequence number.
        entity: usize,
        /// 1-based line number of its parameter data.
        line: usize,
        /// The validation error.
        source: BSplineError,
    },
}

/// One imported entity 128.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesSurface {
    /// The surface (transformation already applied).
    pub surface: BSplineSurface,
    /// Directory entry sequence number of the entity (odd, 1-based).
    pub directory_entry: usize,
    /// Form number (0 = free form, 1 plane, 2 cylinder, …).
    pub form: i64,
    /// `PROP3 == 0`: declared rational (weights kept).
    pub rational: bool,
    /// `PROP1, PROP2`: closed in u, closed in v.
    pub closed: [bool; 2],
    /// `PROP4, PROP5`: periodic in u, periodic in v.
    pub periodic: [bool; 2],
    /// `U0, U1, V0, V1`: the parameter range the file declares.
    pub parameter_range: [f64; 4],
    /// A transformation matrix (entity 124) was applied.
    pub transformed: bool,
    /// Referenced by a trimmed (144) or bounded (143) surface entity.
    pub trimmed: bool,
}

/// The result of [`read_iges`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IgesImport {
    /// Every entity 128, in directory order.
    pub surfaces: Vec<IgesSurface>,
    /// How many of them are trimmed (their trimming was ignored).
    pub trimmed: usize,
    /// Unit name from the Global section (field 15), if given.
    pub units: Option<String>,
}

/// Reads every rational B-spline surface (entity 128) of an ASCII IGES file.
pub fn read_iges(path: impl AsRef<Path>) -> Result<IgesImport, IgesError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| IgesError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_iges_bytes(&bytes)
}

/// Parses IGES text; see [`read_iges`].
pub fn parse_iges(text: &str) -> Result<IgesImport, IgesError> {
    parse_iges_bytes(text.as_bytes())
}

/// One parameter of a free-format IGES record.
#[derive(Clone, Debug, PartialEq)]
enum Param {
    /// Defaulted (nothing between two delimiters).
    Empty,
    /// A number or other unquoted text, blanks removed.
    Text(String),
    /// A Hollerith string `nH…`.
    Hollerith(Vec<u8>),
}

/// A parameter and the byte offset where it starts.
#[derive(Clone, Debug, PartialEq)]
struct Token {
    start: usize,
    param: Param,
}

/// Splits free-format parameter data into parameters (IGES 5.3 §2.2.3).
/// Stops at the record delimiter; returns whether one was found. Errors carry
/// the byte offset of the problem.
fn tokenize(data: &[u8], pd: u8, rd: u8) -> Result<(Vec<Token>, bool), (usize, String)> {
    let len = data.len();
    let mut tokens = Vec::new();
    let mut pos = 0;
    loop {
        let mut q = pos;
        while q < len && data[q] == b' ' {
            q += 1;
        }
        let mut d = q;
        while d < len && data[d].is_ascii_digit() {
            d += 1;
        }
        if d > q && d < len && (data[d] == b'H' || data[d] == b'h') {
            let n: usize = std::str::from_utf8(&data[q..d])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or((q, "bad Hollerith length".to_string()))?;
            let start = d + 1;
            let end = start.checked_add(n).filter(|&e| e <= len).ok_or((
                q,
                format!("Hollerith string of {n} characters runs past the end"),
            ))?;
            tokens.push(Token {
                start: q,
                param: Param::Hollerith(data[start..end].to_vec()),
            });
            pos = end;
            while pos < len && data[pos] == b' ' {
                pos += 1;
            }
            if pos >= len {
                return Ok((tokens, false));
            }
            if data[pos] == rd {
                return Ok((tokens, true));
            }
            if data[pos] != pd {
                return Err((pos, "expected a delimiter after a Hollerith string".into()));
            }
            pos += 1;
        } else {
            let mut e = q;
            while e < len && data[e] != pd && data[e] != rd {
                e += 1;
            }
            let text: String = data[q..e]
                .iter()
                .filter(|&&c| c != b' ')
                .map(|&c| c as char)
                .collect();
            let at_end = e >= len;
            if !at_end || !text.is_empty() {
                tokens.push(Token {
                    start: q,
                    param: if text.is_empty() {
                        Param::Empty
                    } else {
                        Param::Text(text)
                    },
                });
            }
            if at_end {
                return Ok((tokens, false));
            }
            if data[e] == rd {
                return Ok((tokens, true));
            }
            pos = e + 1;
        }
    }
}

/// Parses an IGES real: `1.`, `.5`, `1.E-3`, `1.0D+01`, `-2`. Finite only.
fn parse_real(s: &str) -> Option<f64> {
    let t: String = s
        .chars()
        .map(|c| if c == 'D' || c == 'd' { 'E' } else { c })
        .collect();
    t.parse::<f64>().ok().filter(|x| x.is_finite())
}

/// Parses an IGES integer; accepts an integral real such as `3.`.
fn parse_int(s: &str) -> Option<i64> {
    s.parse::<i64>().ok().or_else(|| {
        parse_real(s)
            .filter(|x| x.fract() == 0.0 && x.abs() < 9.0e15)
            .map(|x| x as i64)
    })
}

/// Reads the parameter and record delimiters from the start of the Global
/// section (fields 1 and 2: `1Hx` or defaulted to `,` and `;`).
fn global_delimiters(g: &[u8]) -> Result<(u8, u8), String> {
    let mut pos = 0;
    let skip = |pos: &mut usize| {
        while *pos < g.len() && g[*pos] == b' ' {
            *pos += 1;
        }
    };
    let hollerith_char = |pos: usize| -> Option<u8> {
        (g.len() > pos + 2 && g[pos] == b'1' && (g[pos + 1] == b'H' || g[pos + 1] == b'h'))
            .then(|| g[pos + 2])
    };
    skip(&mut pos);
    let mut pd = b',';
    let mut rd = b';';
    if pos >= g.len() {
        return Ok((pd, rd));
    }
    if let Some(c) = hollerith_char(pos) {
        pd = c;
        pos += 3;
        skip(&mut pos);
    }
    match g.get(pos) {
        None => return Ok((pd, rd)),
        Some(&c) if c == pd => pos += 1,
        Some(&c) if c == rd => return Ok((pd, rd)),
        Some(&c) => {
            return Err(format!(
                "Global section: expected a delimiter after field 1, found `{}`",
                c as char
            ));
        }
    }
    skip(&mut pos);
    if let Some(c) = hollerith_char(pos) {
        rd = c;
    }
    Ok((pd, rd))
}

/// One record: 1-based file line and its bytes.
struct Record<'a> {
    line: usize,
    bytes: &'a [u8],
}

/// A directory entry (two D records).
struct DirEntry {
    entity_type: i64,
    param_start: i64,
    transform: i64,
    param_lines: i64,
    form: i64,
    line: usize,
}

struct Iges<'a> {
    dir: Vec<DirEntry>,
    params: Vec<Record<'a>>,
    pd: u8,
    rd: u8,
}

/// Field `k` (1-based, 8 columns each) of a D record; blank is 0.
fn d_field(rec: &Record<'_>, k: usize) -> Result<i64, IgesError> {
    let raw = &rec.bytes[(k - 1) * 8..k * 8];
    let s: String = raw
        .iter()
        .filter(|&&c| c != b' ')
        .map(|&c| c as char)
        .collect();
    if s.is_empty() {
        return Ok(0);
    }
    s.parse::<i64>().map_err(|_| IgesError::Format {
        line: rec.line,
        message: format!("directory field {k} is not an integer: `{s}`"),
    })
}

impl<'a> Iges<'a> {
    /// Directory entry index for a DE pointer (odd sequence number).
    fn entry(&self, de: i64) -> Option<usize> {
        (de > 0 && de % 2 == 1)
            .then(|| ((de - 1) / 2) as usize)
            .filter(|&k| k < self.dir.len())
    }

    fn entity_error(&self, k: usize, line: usize, message: String) -> IgesError {
        IgesError::Entity {
            entity: 2 * k + 1,
            entity_type: self.dir[k].entity_type,
            line,
            message,
        }
    }

    /// The parameters of directory entry `k` and the file line of each.
    fn parameters(&self, k: usize) -> Result<Vec<(Param, usize)>, IgesError> {
        let e = &self.dir[k];
        let first = e.param_start - 1;
        let count = e.param_lines.max(1);
        if first < 0 || (first + count) as usize > self.params.len() {
            return Err(self.entity_error(
                k,
                e.line,
                format!(
                    "parameter data at P {}..{} lies outside the P section ({} records)",
                    e.param_start,
                    e.param_start + count - 1,
                    self.params.len()
                ),
            ));
        }
        let recs = &self.params[first as usize..(first + count) as usize];
        let mut data = Vec::with_capacity(64 * recs.len());
        for r in recs {
            data.extend_from_slice(&r.bytes[..64]);
        }
        let (tokens, terminated) = tokenize(&data, self.pd, self.rd).map_err(|(at, msg)| {
            self.entity_error(k, recs[(at / 64).min(recs.len() - 1)].line, msg)
        })?;
        if !terminated {
            return Err(self.entity_error(
                k,
                recs[recs.len() - 1].line,
                format!(
                    "parameter data do not end with the record delimiter `{}`",
                    self.rd as char
                ),
            ));
        }
        Ok(tokens
            .into_iter()
            .map(|t| (t.param, recs[(t.start / 64).min(recs.len() - 1)].line))
            .collect())
    }

    /// The affine map of transformation entity (124) `k`, composed with the
    /// matrices it references in turn (IGES 5.3 §4.21).
    fn transform(&self, k: usize, depth: usize) -> Result<DAffine3, IgesError> {
        let e = &self.dir[k];
        if e.entity_type != 124 {
            return Err(self.entity_error(
                k,
                e.line,
                "referenced as a transformation matrix but is not entity 124".into(),
            ));
        }
        if depth > 64 {
            return Err(self.entity_error(
                k,
                e.line,
                "transformation matrices form a cycle".into(),
            ));
        }
        let p = self.parameters(k)?;
        let mut r = [0.0; 12];
        for (n, v) in r.iter_mut().enumerate() {
            *v = real(self, k, &p, n + 1, e.line)?;
        }
        let m = DAffine3::from_mat3_translation(
            DMat3::from_cols(
                Vec3::new(r[0], r[4], r[8]),
                Vec3::new(r[1], r[5], r[9]),
                Vec3::new(r[2], r[6], r[10]),
            ),
            Vec3::new(r[3], r[7], r[11]),
        );
        if e.transform != 0 {
            let outer = self.entry(e.transform).ok_or_else(|| {
                self.entity_error(
                    k,
                    e.line,
                    format!(
                        "transformation pointer {} is not a directory entry",
                        e.transform
                    ),
                )
            })?;
            Ok(self.transform(outer, depth + 1)? * m)
        } else {
            Ok(m)
        }
    }
}

fn text_of<'p>(p: &'p [(Param, usize)], n: usize) -> Option<&'p str> {
    match p.get(n) {
        Some((Param::Text(s), _)) => Some(s),
        _ => None,
    }
}

fn line_of(p: &[(Param, usize)], n: usize, fallback: usize) -> usize {
    p.get(n).or(p.last()).map_or(fallback, |t| t.1)
}

fn real(
    g: &Iges<'_>,
    k: usize,
    p: &[(Param, usize)],
    n: usize,
    line: usize,
) -> Result<f64, IgesError> {
    match p.get(n) {
        Some((Param::Empty, _)) => Ok(0.0),
        _ => text_of(p, n).and_then(parse_real).ok_or_else(|| {
            g.entity_error(
                k,
                line_of(p, n, line),
                format!(
                    "parameter {n}: expected a real number, found {}",
                    describe(p.get(n))
                ),
            )
        }),
    }
}

fn int(
    g: &Iges<'_>,
    k: usize,
    p: &[(Param, usize)],
    n: usize,
    line: usize,
) -> Result<i64, IgesError> {
    match p.get(n) {
        Some((Param::Empty, _)) => Ok(0),
        _ => text_of(p, n).and_then(parse_int).ok_or_else(|| {
            g.entity_error(
                k,
                line_of(p, n, line),
                format!(
                    "parameter {n}: expected an integer, found {}",
                    describe(p.get(n))
                ),
            )
        }),
    }
}

fn describe(p: Option<&(Param, usize)>) -> String {
    match p {
        None => "the end of the parameters".into(),
        Some((Param::Empty, _)) => "nothing".into(),
        Some((Param::Text(s), _)) => format!("`{s}`"),
        Some((Param::Hollerith(h), _)) => format!("the string `{}`", String::from_utf8_lossy(h)),
    }
}

fn parse_iges_bytes(bytes: &[u8]) -> Result<IgesImport, IgesError> {
    let mut global = Vec::new();
    let mut dir_recs = Vec::new();
    let mut params = Vec::new();
    for (n, raw) in bytes.split(|&c| c == b'\n').enumerate() {
        let line = n + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if raw.iter().all(|&c| c == b' ' || c == b'\x1a') {
            continue;
        }
        if raw.len() < 73 {
            return Err(IgesError::Format {
                line,
                message: format!(
                    "record has {} columns; fixed-format IGES needs the section letter in column 73",
                    raw.len()
                ),
            });
        }
        let rec = Record { line, bytes: raw };
        match raw[72] {
            b'S' | b'T' => {}
            b'G' => global.extend_from_slice(&raw[..72]),
            b'D' => dir_recs.push(rec),
            b'P' => params.push(rec),
            b'C' => {
                return Err(IgesError::Format {
                    line,
                    message: "compressed ASCII IGES is not supported".into(),
                });
            }
            c => {
                return Err(IgesError::Format {
                    line,
                    message: format!(
                        "unknown section letter `{}` in column 73 (binary IGES is not supported)",
                        c as char
                    ),
                });
            }
        }
    }
    let (pd, rd) =
        global_delimiters(&global).map_err(|message| IgesError::Format { line: 1, message })?;
    let units =
        tokenize(&global, pd, rd)
            .ok()
            .and_then(|(t, _)| match t.get(14).map(|t| &t.param) {
                Some(Param::Hollerith(h)) => Some(String::from_utf8_lossy(h).into_owned()),
                _ => None,
            });
    if dir_recs.len() % 2 != 0 {
        return Err(IgesError::Format {
            line: dir_recs.last().map_or(0, |r| r.line),
            message: "the directory section has an odd number of records".into(),
        });
    }
    let mut dir = Vec::with_capacity(dir_recs.len() / 2);
    for pair in dir_recs.chunks(2) {
        let (a, b) = (&pair[0], &pair[1]);
        dir.push(DirEntry {
            entity_type: d_field(a, 1)?,
            param_start: d_field(a, 2)?,
            transform: d_field(a, 7)?,
            param_lines: d_field(b, 4)?,
            form: d_field(b, 5)?,
            line: a.line,
        });
    }
    let g = Iges {
        dir,
        params,
        pd,
        rd,
    };
    // Surfaces referenced by trimmed (144) and bounded (143) surfaces.
    let mut trimmed = vec![false; g.dir.len()];
    for k in 0..g.dir.len() {
        let slot = match g.dir[k].entity_type {
            144 => 1,
            143 => 2,
            _ => continue,
        };
        let Ok(p) = g.parameters(k) else { continue };
        if let Some(t) = text_of(&p, slot)
            .and_then(parse_int)
            .and_then(|de| g.entry(de))
        {
            trimmed[t] = true;
        }
    }
    let mut out = IgesImport {
        units,
        ..IgesImport::default()
    };
    for k in 0..g.dir.len() {
        if g.dir[k].entity_type != 128 {
            continue;
        }
        let s = read_entity_128(&g, k, trimmed[k])?;
        out.trimmed += usize::from(s.trimmed);
        out.surfaces.push(s);
    }
    Ok(out)
}

/// Entity 128, rational B-spline surface (IGES 5.3 §4.24).
fn read_entity_128(g: &Iges<'_>, k: usize, trimmed: bool) -> Result<IgesSurface, IgesError> {
    let e = &g.dir[k];
    let p = g.parameters(k)?;
    let line = p.first().map_or(e.line, |t| t.1);
    let nonneg = |n: usize| -> Result<usize, IgesError> {
        let v = int(g, k, &p, n, line)?;
        usize::try_from(v).map_err(|_| {
            g.entity_error(
                k,
                line_of(&p, n, line),
                format!("parameter {n} is negative ({v})"),
            )
        })
    };
    let (k1, k2, m1, m2) = (nonneg(1)?, nonneg(2)?, nonneg(3)?, nonneg(4)?);
    let mut prop = [0i64; 5];
    for (n, v) in prop.iter_mut().enumerate() {
        *v = int(g, k, &p, 5 + n, line)?;
    }
    let (count_u, count_v) = (k1 + 1, k2 + 1);
    let (nk_u, nk_v) = (count_u + m1 + 1, count_v + m2 + 1);
    let c = count_u.checked_mul(count_v).unwrap_or(usize::MAX);
    let needed = 10usize
        .saturating_add(nk_u)
        .saturating_add(nk_v)
        .saturating_add(c.saturating_mul(4))
        .saturating_add(4);
    if p.len() < needed {
        return Err(g.entity_error(
            k,
            line_of(&p, p.len(), line),
            format!(
                "{} parameters, but K1={k1}, K2={k2}, M1={m1}, M2={m2} need {needed}",
                p.len()
            ),
        ));
    }
    let reals = |from: usize, n: usize| -> Result<Vec<f64>, IgesError> {
        (from..from + n).map(|i| real(g, k, &p, i, line)).collect()
    };
    let mut at = 10;
    let knots_u = reals(at, nk_u)?;
    at += nk_u;
    let knots_v = reals(at, nk_v)?;
    at += nk_v;
    let w_file = reals(at, c)?;
    at += c;
    let xyz = reals(at, 3 * c)?;
    at += 3 * c;
    let range = reals(at, 4)?;
    let transform = if e.transform != 0 {
        let t = g.entry(e.transform).ok_or_else(|| {
            g.entity_error(
                k,
                e.line,
                format!(
                    "transformation pointer {} is not a directory entry",
                    e.transform
                ),
            )
        })?;
        Some(g.transform(t, 0)?)
    } else {
        None
    };
    // IGES orders control points and weights with the u index fastest.
    let mut points = vec![Vec3::ZERO; c];
    let mut weights = vec![0.0; c];
    for j in 0..count_v {
        for i in 0..count_u {
            let f = j * count_u + i;
            let mut q = Vec3::new(xyz[3 * f], xyz[3 * f + 1], xyz[3 * f + 2]);
            if let Some(t) = &transform {
                q = t.transform_point3(q);
            }
            points[i * count_v + j] = q;
            weights[i * count_v + j] = w_file[f];
        }
    }
    let rational = prop[2] == 0;
    let surface = BSplineSurface::from_flat(
        m1,
        m2,
        knots_u,
        knots_v,
        [count_u, count_v],
        points,
        rational.then_some(weights),
    )
    .map_err(|source| IgesError::Surface {
        entity: 2 * k + 1,
        line,
        source,
    })?;
    Ok(IgesSurface {
        surface,
        directory_entry: 2 * k + 1,
        form: e.form,
        rational,
        closed: [prop[0] == 1, prop[1] == 1],
        periodic: [prop[3] == 1, prop[4] == 1],
        parameter_range: [range[0], range[1], range[2], range[3]],
        transformed: transform.is_some(),
        trimmed,
    })
}
