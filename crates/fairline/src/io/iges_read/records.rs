//! The fixed-format file (IGES 5.3 §2.1): sections by column 73, directory
//! entries, and [`Iges`], the view of a file that gives an entity's
//! parameters and transformation matrix.

use glam::{DAffine3, DMat3};

use super::IgesError;
use super::params::{Param, REAL, param, tokenize};
use crate::Vec3;

/// One record: 1-based file line and its bytes.
pub(super) struct Record<'a> {
    line: usize,
    bytes: &'a [u8],
}

/// A directory entry (two D records).
pub(super) struct DirEntry {
    pub(super) entity_type: i64,
    param_start: i64,
    pub(super) transform: i64,
    param_lines: i64,
    pub(super) form: i64,
    /// Status number (field 9): blank, subordinate, use, hierarchy, two
    /// digits each.
    pub(super) status: i64,
    pub(super) line: usize,
}

pub(super) struct Iges<'a> {
    pub(super) dir: Vec<DirEntry>,
    pub(super) params: Vec<Record<'a>>,
    pub(super) pd: u8,
    pub(super) rd: u8,
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
    pub(super) fn entry(&self, de: i64) -> Option<usize> {
        (de > 0 && de % 2 == 1)
            .then(|| ((de - 1) / 2) as usize)
            .filter(|&k| k < self.dir.len())
    }

    pub(super) fn unsupported(&self, k: usize, line: usize, message: String) -> IgesError {
        IgesError::Unsupported {
            entity: 2 * k + 1,
            entity_type: self.dir[k].entity_type,
            line,
            message,
        }
    }

    pub(super) fn entity_error(&self, k: usize, line: usize, message: String) -> IgesError {
        IgesError::Entity {
            entity: 2 * k + 1,
            entity_type: self.dir[k].entity_type,
            line,
            message,
        }
    }

    /// The parameters of directory entry `k` and the file line of each.
    pub(super) fn parameters(&self, k: usize) -> Result<Vec<(Param, usize)>, IgesError> {
        let e = &self.dir[k];
        let first = e.param_start - 1;
        if first < 0 || first as usize >= self.params.len() {
            return Err(self.entity_error(
                k,
                e.line,
                format!(
                    "parameter data pointer {} lies outside the P section ({} records)",
                    e.param_start,
                    self.params.len()
                ),
            ));
        }
        // The records of this entity: those whose back-pointer (columns
        // 66–72) names it; if the writer left no usable back-pointers, the
        // directory's line count (field 14).
        let de = (2 * k + 1) as i64;
        let back = |r: &Record<'_>| -> Option<i64> {
            std::str::from_utf8(&r.bytes[64..72])
                .ok()?
                .trim()
                .parse()
                .ok()
        };
        let first = first as usize;
        let by_pointer = self.params[first..]
            .iter()
            .take_while(|r| back(r) == Some(de))
            .count();
        let count = if by_pointer > 0 {
            by_pointer as i64
        } else {
            e.param_lines.max(1)
        };
        let first = first as i64;
        if (first + count) as usize > self.params.len() {
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
    pub(super) fn transform(&self, k: usize, depth: usize) -> Result<DAffine3, IgesError> {
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
            *v = param(self, k, &p, n + 1, e.line, &REAL)?;
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

/// The records of a fixed-format IGES file by section (IGES 5.3 §2.1): the
/// global section's text (columns 1–72 joined), the directory and parameter
/// records; start and terminate records are skipped.
pub(super) struct Sections<'a> {
    pub(super) global: Vec<u8>,
    pub(super) directory: Vec<Record<'a>>,
    pub(super) parameters: Vec<Record<'a>>,
}

/// Splits the file into its sections by the letter in column 73.
pub(super) fn sections(bytes: &[u8]) -> Result<Sections<'_>, IgesError> {
    let mut out = Sections {
        global: Vec::new(),
        directory: Vec::new(),
        parameters: Vec::new(),
    };
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
            b'G' => out.global.extend_from_slice(&raw[..72]),
            b'D' => out.directory.push(rec),
            b'P' => out.parameters.push(rec),
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
    Ok(out)
}

/// The directory entries, two D records each (IGES 5.3 §2.2.4.4).
pub(super) fn directory(records: &[Record<'_>]) -> Result<Vec<DirEntry>, IgesError> {
    if !records.len().is_multiple_of(2) {
        return Err(IgesError::Format {
            line: records.last().map_or(0, |r| r.line),
            message: "the directory section has an odd number of records".into(),
        });
    }
    let mut dir = Vec::with_capacity(records.len() / 2);
    for pair in records.chunks(2) {
        let (a, b) = (&pair[0], &pair[1]);
        dir.push(DirEntry {
            entity_type: d_field(a, 1)?,
            param_start: d_field(a, 2)?,
            transform: d_field(a, 7)?,
            param_lines: d_field(b, 4)?,
            form: d_field(b, 5)?,
            status: d_field(a, 9).unwrap_or(0),
            line: a.line,
        });
    }
    Ok(dir)
}
