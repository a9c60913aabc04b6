//! Pictures for `highlight` and `detect`: highlight lines drawn over the
//! smooth-shaded mesh, irregular stretches in a warning colour, suggested
//! regions tinted.

use crate::common::bad_input;
use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::Vec3;
use fairline::highlight::HighlightLines;
use fairline::mesh::FaceId;
use fairline::picture::MeshView;
use fairline::render::{Image, PolylineLayer, RenderOptions, Scene, render};
use std::path::Path;

/// Dark ink for highlight lines (linear light).
const LINE: [f32; 3] = [0.015, 0.02, 0.06];
/// Warning colour for irregular stretches (linear light).
const WARN: [f32; 3] = [0.95, 0.12, 0.02];
/// Band boundaries (±ρ level sets), lighter than the lines (linear light).
const BAND: [f32; 3] = [0.1, 0.25, 0.75];
/// Tint of faces in a suggested region (linear light).
const REGION: [f32; 3] = [0.85, 0.55, 0.25];

/// Checks that `path` names a .png file.
pub fn check_png(path: &Path) -> Result<()> {
    if path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        Ok(())
    } else {
        Err(bad_input(format!(
            "{}: --png must name a .png file",
            path.display()
        )))
    }
}

/// The default view for lights with plane normal Z: looking down −Z,
/// tilted a little so the relief shows.
pub fn default_view(z: Vec3, across: Vec3) -> Vec3 {
    -z + 0.35 * across
}

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
    /// Viewing direction (eye towards object) and up hint.
    pub view: (Vec3, Vec3),
    /// Title at the top.
    pub title: String,
}

/// Renders the mesh with the overlay and writes the PNG.
pub fn write(path: &Path, mesh: &SurfaceMesh, overlay: Overlay<'_>) -> Result<()> {
    image(mesh, overlay, (1200, 900))?.write_png(path)?;
    Ok(())
}

/// Renders the mesh with the overlay into an image of `size` (W, H).
pub fn image(mesh: &SurfaceMesh, overlay: Overlay<'_>, size: (u32, u32)) -> Result<Image> {
    let Overlay {
        lines,
        bands,
        flagged,
        region,
        view: (view, up),
        title,
    } = overlay;
    let mv = MeshView::new(mesh);
    let base = [0.55f32, 0.57, 0.60];
    let mut colors = vec![base; mesh.vertex_count()];
    if let Some(faces) = region {
        for f in faces {
            for v in mesh.triangle(*f) {
                colors[v.idx()] = REGION;
            }
        }
    }
    let layer = mv.layer().with_colors(&colors);
    let mut polylines = line_layers(lines, flagged);
    if let Some(b) = bands {
        polylines.extend(b.lines.iter().map(|l| PolylineLayer {
            points: l.points.clone(),
            closed: l.closed,
            color: BAND,
            width_px: 1.0,
        }));
    }
    let mut opts = RenderOptions::with_size(size.0, size.1);
    opts.view_dir = view;
    opts.up = if view.normalize_or_zero().cross(up).length() > 1e-3 {
        up
    } else {
        view.any_orthonormal_vector()
    };
    let scene = Scene {
        meshes: vec![layer],
        polylines,
        points: Vec::new(),
        legend: None,
        title: Some(title),
    };
    Ok(render(&scene, &opts)?)
}

/// A `warning:` text when the lights give no highlight line, or only
/// fragments (median line shorter than two spacings, or more than four
/// pieces per light), with the options to try; `None` when the lines are
/// readable.
pub fn line_warning(
    what: &Path,
    lines: &HighlightLines,
    light: &fairline::highlight::LightArray,
) -> Option<String> {
    let name = what.display();
    if lines.lines.is_empty() {
        return Some(format!(
            "warning: {name}: no highlight line found: the light plane (normal {}) sees no part of the surface at these light positions; try --up x, --up y or --up z, or --plane-normal X,Y,Z",
            fmt_vec(light.plane_normal())
        ));
    }
    let s = light.spacing();
    let mut lengths: Vec<f64> = lines
        .lines
        .iter()
        .map(|l| l.points.windows(2).map(|w| (w[1] - w[0]).length()).sum())
        .collect();
    lengths.sort_by(f64::total_cmp);
    let median = lengths[lengths.len() / 2];
    let mut indices: Vec<i64> = lines.lines.iter().map(|l| l.index).collect();
    indices.sort_unstable();
    indices.dedup();
    let per_light = lines.lines.len() as f64 / indices.len().max(1) as f64;
    if median < 2.0 * s || per_light > 4.0 {
        return Some(format!(
            "warning: {name}: the highlight lines are fragmented ({} pieces on {} lights, median length {:.1} spacings); try another --up (x, y, z) or --plane-normal, or a larger --spacing",
            lines.lines.len(),
            indices.len(),
            if s > 0.0 { median / s } else { 0.0 }
        ));
    }
    None
}

fn fmt_vec(v: Vec3) -> String {
    format!("{:.3},{:.3},{:.3}", v.x, v.y, v.z)
}
