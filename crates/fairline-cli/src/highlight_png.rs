//! Pictures for `highlight` and `detect`: highlight lines drawn over the
//! smooth-shaded mesh, irregular stretches in a warning colour, suggested
//! regions tinted.

use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::Vec3;
use fairline::highlight::{HighlightLines, LightArray, LineStats};
use fairline::mesh::FaceId;
use fairline::picture::MeshView;
use fairline::render::{
    Image, PolylineLayer, ReflectionZebra, RenderOptions, Scene, linear_to_srgb8, render,
};
use std::path::Path;

/// Dark ink for highlight lines (linear light).
const LINE: [f32; 3] = [0.015, 0.02, 0.06];
/// Warning colour for irregular stretches (linear light).
const WARN: [f32; 3] = [0.95, 0.12, 0.02];
/// Band boundaries (±ρ level sets), lighter than the lines (linear light).
const BAND: [f32; 3] = [0.1, 0.25, 0.75];
/// Tint of faces in a suggested region (linear light).
const REGION: [f32; 3] = [0.85, 0.55, 0.25];
/// Tint of faces detection did not judge (linear light).
const UNJUDGED: [f32; 3] = [0.30, 0.42, 0.72];

/// Polyline layers for highlight lines (dark ink, 1.6 px) and irregular
/// stretches drawn over them (warning colour, 3.5 px).
pub fn line_layers(lines: &HighlightLines, flagged: &[Vec<Vec3>]) -> Vec<PolylineLayer> {
    let mut polylines: Vec<PolylineLayer> = lines
        .lines
        .iter()
        .map(|l| PolylineLayer {
            points: l.points.clone(),
            closed: l.closed,
            color: LINE,
            width_px: 1.6,
        })
        .collect();
    polylines.extend(flagged.iter().map(|pts| PolylineLayer {
        points: pts.clone(),
        closed: false,
        color: WARN,
        width_px: 3.5,
    }));
    polylines
}

/// What to draw over the mesh.
pub struct Overlay<'a> {
    /// Highlight lines (dark).
    pub lines: &'a HighlightLines,
    /// Highlight band boundaries (blue, thinner).
    pub bands: Option<&'a HighlightLines>,
    /// Irregular stretches (warning colour).
    pub flagged: &'a [Vec<Vec3>],
    /// Faces to tint.
    pub region: Option<&'a [FaceId]>,
    /// Faces `detect` did not judge (shape finer than its scale, mesh
    /// boundary), tinted apart so that "no region" is not read as "no
    /// defect" there.
    pub unjudged: Option<&'a [FaceId]>,
    /// Viewing direction (eye towards object) and up hint.
    pub view: (Vec3, Vec3),
    /// Title at the top.
    pub title: String,
    /// Light spacing of the drawn lines (for the key; `None` for circular
    /// lights).
    pub spacing: Option<f64>,
    /// A reflection zebra on the part, under the lines.
    pub zebra: Option<ReflectionZebra>,
}

/// The key of a highlight picture: what each colour means, one entry per
/// thing drawn (lines, band boundaries, flagged stretches, regions).
pub fn key_entries(overlay: &Overlay<'_>) -> Vec<([f32; 3], String)> {
    let mut key = vec![(
        LINE,
        match overlay.spacing {
            Some(s) => format!("highlight lines, light spacing {}", fmt_len(s)),
            None => "highlight lines".into(),
        },
    )];
    if overlay.bands.is_some() {
        key.push((BAND, "band boundaries".into()));
    }
    if overlay.region.is_some_and(|r| !r.is_empty()) {
        key.push((REGION, "suggested fairing region".into()));
    }
    if overlay.unjudged.is_some_and(|r| !r.is_empty()) {
        key.push((
            UNJUDGED,
            "not judged: shape finer than the measure's scale".into(),
        ));
    }
    if !overlay.flagged.is_empty() {
        key.push((WARN, "lines across a region".into()));
    }
    key
}

/// Draws a key (a swatch and a label per entry) on a light panel in the
/// corner of `img` where it covers the least of the picture: of the four
/// corners (the top ones below the title line), the one with the fewest
/// pixels that differ from the background (the colour most of the image's
/// corner pixels have), bottom-left on a tie.
pub fn draw_key(img: &mut Image, entries: &[([f32; 3], String)]) {
    if entries.is_empty() {
        return;
    }
    let scale = if img.width >= 1000 { 2 } else { 1 };
    let row = (Image::text_height(scale) + 6 * scale) as i64;
    let swatch = (14 * scale) as i64;
    let text_w = entries
        .iter()
        .map(|(_, l)| Image::text_width(l, scale))
        .max()
        .unwrap_or(0) as i64;
    let pad = (4 * scale) as i64;
    let panel_h = 2 * pad + row * entries.len() as i64;
    let panel_w = 2 * pad + swatch + 2 * pad + text_w;
    let (x0, y0) = key_corner(img, panel_w, panel_h, scale);
    img.fill_rect(x0, y0, panel_w as u32, panel_h as u32, [250, 250, 250, 255]);
    for (i, (colour, label)) in entries.iter().enumerate() {
        let y = y0 + pad + i as i64 * row;
        let c = linear_to_srgb8(*colour);
        img.fill_rect(
            x0 + pad,
            y + row / 2 - scale as i64 * 2,
            swatch as u32,
            4 * scale,
            c,
        );
        img.draw_text(
            x0 + 3 * pad + swatch,
            y + 2,
            label,
            [20, 20, 20, 255],
            scale,
        );
    }
}

/// Top-left corner of a `w`×`h` key panel: the image corner (8 px in,
/// the top ones below the title) whose rectangle holds the fewest pixels
/// other than the background; bottom-left first on a tie.
fn key_corner(img: &Image, w: i64, h: i64, scale: u32) -> (i64, i64) {
    let (iw, ih) = (img.width as i64, img.height as i64);
    let corners = [(0, 0), (iw - 1, 0), (0, ih - 1), (iw - 1, ih - 1)];
    let colours: Vec<[u8; 4]> = corners
        .iter()
        .filter_map(|&(x, y)| img.get(x.max(0) as u32, y.max(0) as u32))
        .collect();
    let background = colours
        .iter()
        .max_by_key(|c| colours.iter().filter(|d| d == c).count())
        .copied()
        .unwrap_or([255, 255, 255, 255]);
    let top = 8 + Image::text_height(scale) as i64 + 8;
    let candidates = [
        (8, ih - h - 8),
        (iw - w - 8, ih - h - 8),
        (8, top),
        (iw - w - 8, top),
    ];
    let covered = |(x0, y0): (i64, i64)| -> usize {
        let mut n = 0;
        for y in y0.max(0)..(y0 + h).min(ih) {
            for x in x0.max(0)..(x0 + w).min(iw) {
                if img
                    .get(x as u32, y as u32)
                    .is_some_and(|c| c.iter().zip(&background).any(|(a, b)| a.abs_diff(*b) > 8))
                {
                    n += 1;
                }
            }
        }
        n
    };
    let mut best = candidates[0];
    let mut least = covered(best);
    for &c in &candidates[1..] {
        let n = covered(c);
        if n < least {
            (best, least) = (c, n);
        }
    }
    best
}

/// A length for a key or a message: 3 significant digits.
pub fn fmt_len(x: f64) -> String {
    if x != 0.0 && (x.abs() >= 1e4 || x.abs() < 1e-3) {
        format!("{x:.2e}")
    } else {
        let digits = (2 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    }
}

/// Renders the mesh with the overlay into a picture of `size` (W, H) and
/// writes the PNG.
pub fn write(
    size: (u32, u32),
    path: &Path,
    mesh: &SurfaceMesh,
    overlay: Overlay<'_>,
) -> Result<()> {
    image(mesh, overlay, size)?.write_png(path)?;
    Ok(())
}

/// The render options of a highlight picture of `size` (W, H) seen along
/// `view` (direction, up; an up along the direction replaced by one
/// across it).
pub fn render_options(size: (u32, u32), (view, up): (Vec3, Vec3)) -> RenderOptions {
    let mut opts = RenderOptions::with_size(size.0, size.1);
    opts.view_dir = view;
    opts.up = if view.normalize_or_zero().cross(up).length() > 1e-3 {
        up
    } else {
        view.any_orthonormal_vector()
    };
    opts
}

/// Renders the mesh with the overlay into an image of `size` (W, H); over
/// a zebra the lines get light halos ([`fairline::picture::zebra_halos`]).
pub fn image(mesh: &SurfaceMesh, overlay: Overlay<'_>, size: (u32, u32)) -> Result<Image> {
    let key = key_entries(&overlay);
    let Overlay {
        lines,
        bands,
        flagged,
        region,
        unjudged,
        view: (view, up),
        title,
        spacing: _,
        zebra,
    } = overlay;
    let mv = MeshView::new(mesh);
    let base = [0.55f32, 0.57, 0.60];
    let mut colors = vec![base; mesh.vertex_count()];
    // the region over the unjudged tint: a region is always judged
    for (faces, tint) in [(unjudged, UNJUDGED), (region, REGION)] {
        for f in faces.unwrap_or_default() {
            for v in mesh.triangle(*f) {
                colors[v.idx()] = tint;
            }
        }
    }
    let layer = mv.layer().with_colors(&colors).with_zebra(zebra);
    let mut polylines = line_layers(lines, flagged);
    if let Some(b) = bands {
        polylines.extend(b.lines.iter().map(|l| PolylineLayer {
            points: l.points.clone(),
            closed: l.closed,
            color: BAND,
            width_px: 1.0,
        }));
    }
    if zebra.is_some() {
        polylines = fairline::picture::zebra_halos(&polylines);
    }
    let opts = render_options(size, (view, up));
    let scene = Scene {
        meshes: vec![layer],
        polylines,
        points: Vec::new(),
        legend: None,
        title: Some(title),
    };
    let mut img = render(&scene, &opts)?;
    draw_key(&mut img, &key);
    Ok(img)
}

/// A `warning:` text when the lights give no highlight line, or when the
/// drawn (readable) lines are fragmented (see [`fragmented`]; `width` is
/// the part's width across the lights), with the options to try; `None`
/// when the lines are readable.
pub fn line_warning(
    what: &Path,
    lines: &HighlightLines,
    drawn: &HighlightLines,
    light: &LightArray,
    width: f64,
) -> Option<String> {
    let name = what.display();
    if lines.lines.is_empty() {
        return Some(format!(
            "warning: {name}: no highlight line found: the light plane (normal {}) sees no part of the surface at these light positions; try --up x, --up y or --up z, or --plane-normal X,Y,Z",
            fmt_vec(light.plane_normal())
        ));
    }
    if drawn.lines.is_empty() {
        return Some(format!(
            "warning: {name}: the {} highlight line pieces are all too crowded or too short to draw; try a larger --spacing or another --up (x, y, z)",
            lines.lines.len()
        ));
    }
    let st = LineStats::of(drawn);
    if fragmented(&st, width) {
        return Some(format!(
            "warning: {name}: the highlight lines are fragmented (half of the drawn length is in pieces shorter than {:.2} of the part's width; {} pieces on {} lights); try another --up (x, y, z) or --plane-normal, or a larger --spacing",
            if width > 0.0 {
                st.n50_length / width
            } else {
                0.0
            },
            st.pieces,
            st.lights,
        ));
    }
    None
}

/// Detection at the scale of `light` (the measure) with the lines of
/// `shown_light` (the readable lights: `light` itself or a subset of its
/// lines): returns all lines of `shown_light`, their readable drawing, and
/// the detection, whose stretches lie on the drawn lines.
pub fn detect_with_lines(
    mesh: &SurfaceMesh,
    light: &LightArray,
    shown_light: &LightArray,
    highlight: fairline::highlight::HighlightOptions,
    detect: &fairline::highlight::DetectOptions,
) -> Result<
    (
        HighlightLines,
        HighlightLines,
        fairline::highlight::Detection,
    ),
    fairline::highlight::HighlightError,
> {
    let model = fairline::highlight::HighlightModel::new(mesh, *shown_light, highlight)?;
    let lines = model.lines(mesh);
    let shown = model.readable_lines(
        mesh,
        &lines,
        &fairline::highlight::Readability::for_part(mesh, shown_light),
    );
    let det = fairline::highlight::detect_whole_part(mesh, light, &shown, detect)?;
    Ok((lines, shown, det))
}

/// The irregular stretches of a detection (lines across its regions).
pub fn stretches(det: &fairline::highlight::Detection) -> Vec<Vec<Vec3>> {
    det.lines
        .iter()
        .flat_map(|l| l.stretches.iter().cloned())
        .collect()
}

/// Whether drawn lines are fragmented: half of their length lies in pieces
/// shorter than 0.15 of the part's `width` across the lights (a
/// length-weighted median, [`LineStats::n50_length`]).
pub fn fragmented(st: &LineStats, width: f64) -> bool {
    st.n50_length < FRAGMENT_N50_OF_WIDTH * width
}

/// The drawn lines are called fragmented below this N50 (fraction of the
/// part's width); tests/real_highlight.rs holds every real mesh to it.
pub const FRAGMENT_N50_OF_WIDTH: f64 = 0.15;

fn fmt_vec(v: Vec3) -> String {
    format!("{:.3},{:.3},{:.3}", v.x, v.y, v.z)
}
