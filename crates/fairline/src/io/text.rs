//! Shared helpers of the text mesh formats: lines and tokens, numbers as Rust
//! reads them, error excerpts, capacities bounded by the bytes left, and the
//! parallel formatting of output.

use std::io::Write;
use std::path::Path;

use super::{IoError, Location, format_err};
use crate::mesh::Soup;

/// Items formatted per parallel chunk before a group of chunks is written.
pub(super) const FORMAT_CHUNK: usize = 4096;

/// Chunks formatted at a time (bounds the text held in memory).
pub(super) const FORMAT_GROUP: usize = 64;

/// Writes items 0..count, each formatted into a byte buffer by
/// `format(i, buffer)`, in order: the same bytes as formatting them one
/// after another, formatted in parallel chunks (text output of large
/// meshes is bound by number formatting).
pub(crate) fn write_formatted(
    w: &mut impl Write,
    count: usize,
    format: impl Fn(usize, &mut Vec<u8>) -> std::io::Result<()> + Sync,
) -> std::io::Result<()> {
    use rayon::prelude::*;
    for group in (0..count).step_by(FORMAT_CHUNK * FORMAT_GROUP) {
        let end = (group + FORMAT_CHUNK * FORMAT_GROUP).min(count);
        let starts: Vec<usize> = (group..end).step_by(FORMAT_CHUNK).collect();
        let parts = starts
            .into_par_iter()
            .map(|start| {
                let mut buffer = Vec::new();
                for i in start..(start + FORMAT_CHUNK).min(end) {
                    format(i, &mut buffer)?;
                }
                Ok(buffer)
            })
            .collect::<std::io::Result<Vec<Vec<u8>>>>()?;
        for part in parts {
            w.write_all(&part)?;
        }
    }
    Ok(())
}

/// Lines of a text file: yields `(1-based line number, line)` without the
/// line ending: `\n`, `\r\n`, or (old Mac files) a lone `\r`.
pub(super) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    /// Whether a `\r` not followed by `\n` ends a line.
    lone_cr: bool,
}

impl<'a> Lines<'a> {
    /// Lines ended by `\n`, `\r\n` or a lone `\r`.
    pub(super) fn new(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            data,
            pos: 0,
            line: first_line,
            lone_cr: true,
        }
    }

    /// Lines ended by `\n` or `\r\n` only: for a header followed by binary
    /// data, where the byte after a `\r` may be data.
    pub(super) fn lf_only(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            lone_cr: false,
            ..Lines::new(data, first_line)
        }
    }

    /// Bytes not yet returned.
    pub(super) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let end = if self.lone_cr {
            rest.iter().position(|&b| b == b'\n' || b == b'\r')
        } else {
            rest.iter().position(|&b| b == b'\n')
        };
        let (line, advance) = match end {
            Some(i) if rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n') => (&rest[..i], i + 2),
            Some(i) if rest[i] == b'\n' && i > 0 && rest[i - 1] == b'\r' => (&rest[..i - 1], i + 1),
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        let n = self.line;
        self.line += 1;
        Some((n, line))
    }
}

/// Splits a line into whitespace-separated tokens.
pub(super) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// Parses a decimal floating-point token (Rust's `f64` grammar, which
/// also accepts `inf` and `nan`; callers check finiteness).
pub(super) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal integer token: an optional `+` or `-`, then one or more
/// ASCII digits (Rust's `i64` grammar); `None` on anything else or beyond
/// the range of `i64`. Read straight from the bytes (face indices are most of
/// the tokens of a mesh file).
pub(super) fn parse_i64(tok: &[u8]) -> Option<i64> {
    let (negative, digits) = match tok {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, tok),
    };
    if digits.is_empty() {
        return None;
    }
    // accumulated as a negative number, so that i64::MIN fits
    let mut v: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_sub(i64::from(d))?;
    }
    if negative { Some(v) } else { v.checked_neg() }
}

/// A token for an error message: lossy UTF-8, at most 40 characters.
pub(super) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        let cut: String = s.chars().take(40).collect();
        format!("{cut}...")
    } else {
        s.into_owned()
    }
}

/// A capacity to reserve for `count` items announced by a header when
/// `bytes` bytes remain and every item takes at least `min_item_bytes` of
/// them: never more than the file can hold.
pub(super) fn capped_capacity(count: usize, bytes: usize, min_item_bytes: usize) -> usize {
    count.min(bytes / min_item_bytes.max(1))
}

/// Refuses bytes after the end of binary data (`end`): they mean the header's
/// counts do not describe the file, and whatever they hold would be lost
/// silently. A final line ending (`\n` or `\r\n`, which some writers add) is
/// tolerated. Shared by binary PLY and binary STL.
pub(super) fn trailing_bytes(bytes: &[u8], end: usize, path: &Path) -> Result<(), IoError> {
    let tail = bytes.get(end..).unwrap_or_default();
    if tail.is_empty() || tail == b"\n" || tail == b"\r\n" {
        return Ok(());
    }
    Err(format_err(
        path,
        Location::Byte(end),
        format!(
            "{} bytes after the end of the data the header announces (wrong counts or a damaged file?)",
            tail.len()
        ),
    ))
}

/// Appends a face to a soup, failing when the index array would outgrow
/// 32-bit offsets.
pub(super) fn push_face(soup: &mut Soup, face: &[u32]) -> Result<(), &'static str> {
    if soup.indices.len() + face.len() > u32::MAX as usize {
        return Err("too many face indices for 32-bit offsets");
    }
    soup.push_face(face);
    Ok(())
}
