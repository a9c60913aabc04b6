//! ASCII PLY bodies: one row per element, each value checked to fit its
//! declared type.

use std::path::Path;

use super::header::{Element, Header, Kind, Role};
use super::{Plan, extra_props};
use crate::Vec3;
use crate::io::text::{Lines, capped_capacity, parse_f64, parse_i64, push_face, show, tokens};
use crate::io::{IoError, Location, VertexProperties as Extra, format_err};
use crate::mesh::Soup;

/// The ascii body: every element in header order, one row per line.
pub(super) fn read_ascii(
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
