//! The highlight-lines file of `fairline highlight -o` for meshes (DESIGN.md
//! §4), one definition for the CLI and the Python package: JSON
//! `{"lines":[{"index":m,"closed":b,"points":[[x,y,z],..]}]}` (circular
//! lines also carry `"radius"`; bands under `"bands"`), or OBJ `l`
//! polylines in the groups `lines`, `band_lower`, `band_upper`.

use super::{HighlightBands, HighlightLine, HighlightLines};
use serde_json::{Value, json};

/// One line as JSON; `radii` (circular lights) gives its `"radius"`.
fn line_json(l: &HighlightLine, radii: Option<&[f64]>) -> Value {
    let pts: Vec<[f64; 3]> = l.points.iter().map(|p| p.to_array()).collect();
    let mut v = json!({"index": l.index, "closed": l.closed, "points": pts});
    if let Some(r) = radii.and_then(|r| r.get(l.index as usize)) {
        v["radius"] = json!(r);
    }
    v
}

fn lines_array(lines: &HighlightLines, radii: Option<&[f64]>) -> Vec<Value> {
    lines.lines.iter().map(|l| line_json(l, radii)).collect()
}

/// The JSON document of `lines` and, when given, `bands`; `radii` are the
/// radii of circular lights by line index (`None` for a linear array).
pub fn highlight_lines_json(
    lines: &HighlightLines,
    bands: Option<&HighlightBands>,
    radii: Option<&[f64]>,
) -> Value {
    let mut v = json!({"lines": lines_array(lines, radii)});
    if let Some(b) = bands {
        v["bands"] = json!({
            "radius": b.radius,
            "lower": lines_array(&b.lower, radii),
            "upper": lines_array(&b.upper, radii),
        });
    }
    v
}

/// The OBJ text of `lines` and, when given, `bands`: vertices and `l`
/// elements (a closed line repeats its first vertex) in the groups
/// `lines`, `band_lower`, `band_upper`.
pub fn highlight_lines_obj(lines: &HighlightLines, bands: Option<&HighlightBands>) -> String {
    use std::fmt::Write;
    let mut groups: Vec<(&str, &HighlightLines)> = vec![("lines", lines)];
    if let Some(b) = bands {
        groups.push(("band_lower", &b.lower));
        groups.push(("band_upper", &b.upper));
    }
    let mut text = String::from("# fairline highlight lines\n");
    let mut next = 1usize;
    for (name, ls) in groups {
        let _ = writeln!(text, "g {name}");
        for l in &ls.lines {
            let first = next;
            for p in &l.points {
                let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
            }
            text.push('l');
            for k in 0..l.points.len() {
                let _ = write!(text, " {}", first + k);
            }
            if l.closed {
                let _ = write!(text, " {first}");
            }
            text.push('\n');
            next += l.points.len();
        }
    }
    text
}
