//! The highlight-lines file of `fairline highlight -o` for B-spline
//! surfaces (DESIGN.md §4), one definition for the CLI and the Python
//! package: `{"lines":[{"id":k,"light":i,"level":0,"closed":b,
//! "uv":[[u,v],..],"points":[[x,y,z],..]}],"bands":{..}}`; circular lines
//! carry `"radius"`, linear ones the light `"index"` m, and the lines of a
//! file of several surfaces their `"surface"`. `"id"` is the position in
//! `"lines"` (named by `fair-surface --from ID:T`).

use super::{PatchHighlights, SurfaceHighlightLine, SurfaceLight};
use serde::Serialize;
use serde_json::{Value, json};

/// One line as JSON: radius (circular) or index (linear), closed, uv,
/// points; `surface` when the file holds several.
pub fn surface_line_json(
    l: &SurfaceHighlightLine,
    lights: &[SurfaceLight],
    surface: Option<usize>,
) -> Value {
    let pts: Vec<[f64; 3]> = l.points.iter().map(|p| p.to_array()).collect();
    let mut v =
        json!({"light": l.light, "level": l.level, "closed": l.closed, "uv": l.uv, "points": pts});
    if let Some(r) = l.radius {
        v["radius"] = json!(r);
    }
    if let Some(SurfaceLight::Linear { index, .. }) = lights.get(l.light) {
        v["index"] = json!(index);
    }
    if let Some(s) = surface {
        v["surface"] = json!(s);
    }
    v
}

/// Counts of the lines of a part: the `"lines"`, `"closed_lines"` and
/// `"points"` of `fairline highlight --report` for surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SurfaceLineCounts {
    /// Highlight-line polylines (band boundaries not counted).
    pub lines: usize,
    /// Closed polylines among them.
    pub closed_lines: usize,
    /// Points of all of them.
    pub points: usize,
}

/// The lines document of a part: `patches` holds (surface index, that
/// surface's lines) in file order; `"surface"` is written when there is
/// more than one; `band` (ρ) adds the band boundaries. With the counts.
pub fn surface_highlight_lines_json(
    patches: &[(usize, &PatchHighlights)],
    band: Option<f64>,
) -> (Value, SurfaceLineCounts) {
    let multi = patches.len() > 1;
    let tag = |k: usize| multi.then_some(k);
    let mut lines = Vec::new();
    let (mut lower, mut upper) = (Vec::new(), Vec::new());
    let mut counts = SurfaceLineCounts::default();
    for (k, p) in patches {
        let (lights, h) = (&p.lights, &p.highlights);
        lines.extend(
            h.lines
                .iter()
                .map(|l| surface_line_json(l, lights, tag(*k))),
        );
        lower.extend(
            h.band_lower
                .iter()
                .map(|l| surface_line_json(l, lights, tag(*k))),
        );
        upper.extend(
            h.band_upper
                .iter()
                .map(|l| surface_line_json(l, lights, tag(*k))),
        );
        counts.closed_lines += h.lines.iter().filter(|l| l.closed).count();
        counts.points += h.lines.iter().map(|l| l.uv.len()).sum::<usize>();
    }
    for (id, l) in lines.iter_mut().enumerate() {
        l["id"] = json!(id);
    }
    counts.lines = lines.len();
    let mut out = json!({"lines": lines});
    if let Some(rho) = band {
        out["bands"] = json!({"radius": rho, "lower": lower, "upper": upper});
    }
    (out, counts)
}
