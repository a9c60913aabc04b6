//! Free-format parameter data (IGES 5.3 §2.2.3): splitting records into
//! parameters, the Global section's delimiters, numbers with `D` exponents,
//! and typed access to an entity's parameters with defaults and errors.

use super::IgesError;
use super::records::Iges;

/// One parameter of a free-format IGES record.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Param {
    /// Defaulted (nothing between two delimiters).
    Empty,
    /// A number or other unquoted text, blanks removed.
    Text(String),
    /// A Hollerith string `nH…`.
    Hollerith(Vec<u8>),
}

/// A parameter and the byte offset where it starts.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Token {
    pub(super) start: usize,
    pub(super) param: Param,
}

/// Splits free-format parameter data into parameters (IGES 5.3 §2.2.3).
/// Stops at the record delimiter; returns whether one was found. Errors carry
/// the byte offset of the problem.
pub(super) fn tokenize(data: &[u8], pd: u8, rd: u8) -> Result<(Vec<Token>, bool), (usize, String)> {
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
pub(super) fn parse_real(s: &str) -> Option<f64> {
    let t: String = s
        .chars()
        .map(|c| if c == 'D' || c == 'd' { 'E' } else { c })
        .collect();
    t.parse::<f64>().ok().filter(|x| x.is_finite())
}

/// Parses an IGES integer; accepts an integral real such as `3.`.
pub(super) fn parse_int(s: &str) -> Option<i64> {
    s.parse::<i64>().ok().or_else(|| {
        parse_real(s)
            .filter(|x| x.fract() == 0.0 && x.abs() < 9.0e15)
            .map(|x| x as i64)
    })
}

/// Reads the parameter and record delimiters from the start of the Global
/// section (fields 1 and 2: `1Hx` or defaulted to `,` and `;`).
pub(super) fn global_delimiters(g: &[u8]) -> Result<(u8, u8), String> {
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

pub(super) fn text_of(p: &[(Param, usize)], n: usize) -> Option<&str> {
    match p.get(n) {
        Some((Param::Text(s), _)) => Some(s),
        _ => None,
    }
}

pub(super) fn line_of(p: &[(Param, usize)], n: usize, fallback: usize) -> usize {
    p.get(n).or(p.last()).map_or(fallback, |t| t.1)
}

/// How a parameter of one kind is read: parsed from its text, or `blank`
/// when the parameter is empty (IGES 5.3 §2.2.3: defaulted parameters).
pub(super) struct ParamKind<T> {
    /// What the parameter should be, for errors ("a real number").
    expected: &'static str,
    parse: fn(&str) -> Option<T>,
    blank: T,
}

pub(super) const REAL: ParamKind<f64> = ParamKind {
    expected: "a real number",
    parse: parse_real,
    blank: 0.0,
};

pub(super) const INT: ParamKind<i64> = ParamKind {
    expected: "an integer",
    parse: parse_int,
    blank: 0,
};

/// Parameter `n` of entity `k` read as `kind`; the error names the entity,
/// the line, the parameter, what was expected and what was found.
pub(super) fn param<T: Copy>(
    g: &Iges<'_>,
    k: usize,
    p: &[(Param, usize)],
    n: usize,
    line: usize,
    kind: &ParamKind<T>,
) -> Result<T, IgesError> {
    match p.get(n) {
        Some((Param::Empty, _)) => Ok(kind.blank),
        _ => text_of(p, n).and_then(kind.parse).ok_or_else(|| {
            g.entity_error(
                k,
                line_of(p, n, line),
                format!(
                    "parameter {n}: expected {}, found {}",
                    kind.expected,
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
