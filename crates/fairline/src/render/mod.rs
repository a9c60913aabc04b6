//! Pictures: a deterministic CPU software renderer producing PNG images of
//! surfaces, colour maps and legends for scalar fields, and a small SVG
//! plot writer for 2D curves.
//!
//! The renderer takes plain arrays ([`MeshLayer`] borrows positions and
//! triangles), so it does not depend on the mesh module. It is a z-buffer
//! rasteriser with exact fixed-point edge functions (top-left fill rule, so
//! closed meshes have no cracks), perspective-correct interpolation of
//! normals and colours, Blinn–Phong shading with a key light, a fill light
//! and a hemispherical ambient term (see [`Lighting`]), and supersampled
//! anti-aliasing (the scene is rendered at `supersample`× resolution and
//! box-filtered down). Shading happens in linear light; the image is sRGB.
//!
//! Work is split into horizontal bands rendered in parallel with rayon. Each
//! band is a pure function of the input, and triangles are drawn in index
//! order with "first wins" depth ties, so the output is byte-identical across
//! runs and thread counts.
//!
//! Robustness: triangles with out-of-range indices, non-finite or
//! coincident vertices, or a vertex behind the camera's near plane are
//! skipped; non-finite normals fall back to the face normal, non-finite
//! colours to the base colour; polyline points that are not finite break
//! the polyline. Nothing panics and nothing is printed.

mod camera;
mod colormap;
mod font;
mod image;
mod labels;
mod raster;
pub mod svg;
mod view;

pub use camera::{Camera, DEFAULT_FOV_Y_DEG, Projection, view_frame};
pub use colormap::{Colormap, Legend, NAN_COLOR, clipped, scalar_colors, scalar_range};
pub use image::{Image, linear_to_srgb8, side_by_side};
pub use labels::{PlacedLabel, RegionLabels};
pub use svg::SvgPlot;
pub use view::{PartView, UpReason, part_view};

use crate::Vec3;
use std::path::PathBuf;

/// Largest accepted image side in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Largest accepted supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Largest line width / marker radius in pixels (larger values are clamped).
pub const MAX_LINE_WIDTH_PX: f32 = 64.0;

/// Errors of the renderer and the picture writers.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Width or height is zero or larger than [`MAX_IMAGE_SIDE`].
    #[error("invalid image size {width}x{height}: each side must be 1..={MAX_IMAGE_SIDE} pixels")]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// The supersampling factor is 0 or larger than [`MAX_SUPERSAMPLE`].
    #[error("invalid supersampling factor {0}: must be 1..={MAX_SUPERSAMPLE}")]
    InvalidSupersample(u32),
    /// PNG encoding or decoding failed.
    #[error("PNG error: {0}")]
    Png(String),
    /// A file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file that was being written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// A triangle mesh to draw, as borrowed plain arrays.
#[derive(Clone, Copy, Debug)]
pub struct MeshLayer<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Triangles as vertex indices, counter-clockwise seen from the front.
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex unit normals for smooth shading (`positions.len()` of
    /// them); `None` shades each triangle flat with its face normal.
    pub normals: Option<&'a [Vec3]>,
    /// Per-vertex linear-light colours (0..1), interpolated across triangles
    /// (e.g. from [`scalar_colors`]); `None` uses `base_color`. Coloured
    /// layers get a weaker specular highlight so it does not wash out the
    /// colour map.
    pub colors: Option<&'a [[f32; 3]]>,
    /// Linear-light surface colour when `colors` is `None`.
    pub base_color: [f32; 3],
    /// Draw triangle edges in this colour as anti-aliased lines about one
    /// pixel wide (hidden edges are not drawn).
    pub wireframe: Option<[f32; 3]>,
    /// `true`: both sides are lit alike (open panels). `false`: back faces
    /// are drawn in a flat dark brown so an inverted orientation stands out.
    pub two_sided: bool,
    /// Reflection zebra stripes over the shading (smooth layers).
    pub zebra: Option<ReflectionZebra>,
}

/// A reflection zebra (as Rhino's Zebra, Alias' diagnostic shading): the
/// eye's ray reflected at each sample, R = V − 2(N·V)N, looks up an
/// environment of parallel tube lights at infinity along `axis`; the stripe
/// is the angle of R about the axis, atan2(R·(axis × zenith), R·zenith), in
/// steps of `period_deg`, dark over `band` of each step. Where the stripes
/// get closer than about three pixels they fade to their mean (a dark share
/// of `band`), never to speckle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectionZebra {
    /// The tubes' direction (unit).
    pub axis: Vec3,
    /// The direction the angle is measured from (unit, orthogonal to `axis`).
    pub zenith: Vec3,
    /// The angle of one stripe period, degrees (positive).
    pub period_deg: f64,
    /// The dark share of a period, in (0, 1).
    pub band: f64,
}

impl ReflectionZebra {
    /// The zebra of tubes along `axis` seen from `zenith` (both made unit
    /// and orthogonal; `None` when they are parallel or not finite), a
    /// period of `period_deg` degrees and half of each period dark.
    pub fn new(axis: Vec3, zenith: Vec3, period_deg: f64) -> Option<Self> {
        let axis = axis.try_normalize()?;
        let zenith = (zenith - axis * zenith.dot(axis)).try_normalize()?;
        (period_deg.is_finite() && period_deg > 0.0).then_some(ReflectionZebra {
            axis,
            zenith,
            period_deg,
            band: 0.5,
        })
    }

    /// The stripe coordinate (periods) of the reflection of the ray `ray`
    /// (from the eye) at unit normal `n`.
    pub fn stripe(&self, ray: Vec3, n: Vec3) -> f64 {
        let r = ray - n * (2.0 * n.dot(ray));
        let b = self.axis.cross(self.zenith);
        r.dot(b).atan2(r.dot(self.zenith)).to_degrees() / self.period_deg
    }

    /// The dark coverage (0..1) of a sample at stripe coordinate `t` whose
    /// neighbours one output pixel away differ by `dt` periods.
    pub fn coverage(&self, t: f64, dt: f64) -> f64 {
        // the angle jumps by a whole turn behind the axis: the smaller way
        let turn = 360.0 / self.period_deg;
        let dt = dt.abs() % turn;
        let aa = dt.min(turn - dt).min(0.5);
        let half = 0.5 * self.band.clamp(0.0, 1.0);
        let off = (t - (t + 0.5).floor()).abs();
        let edge = |x: f64| {
            let lo = half - aa;
            let hi = half + aa;
            if hi - lo < 1e-12 {
                f64::from(u8::from(x < half))
            } else {
                1.0 - smoothstep(lo, hi, x)
            }
        };
        let fade = smoothstep(0.15, 0.35, aa);
        edge(off) * (1.0 - fade) + self.band * fade
    }
}

/// Hermite step from 0 at `a` to 1 at `b`.
fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl<'a> MeshLayer<'a> {
    /// A flat-shaded, two-sided, light grey layer.
    pub fn new(positions: &'a [Vec3], triangles: &'a [[u32; 3]]) -> Self {
        MeshLayer {
            positions,
            triangles,
            normals: None,
            colors: None,
            base_color: [0.55, 0.57, 0.60],
            wireframe: None,
            two_sided: true,
            zebra: None,
        }
    }

    /// Draws a reflection zebra over the shading.
    pub fn with_zebra(mut self, zebra: Option<ReflectionZebra>) -> Self {
        self.zebra = zebra;
        self
    }

    /// Sets per-vertex normals (smooth shading).
    pub fn with_normals(mut self, normals: &'a [Vec3]) -> Self {
        self.normals = Some(normals);
        self
    }

    /// Sets per-vertex linear-light colours.
    pub fn with_colors(mut self, colors: &'a [[f32; 3]]) -> Self {
        self.colors = Some(colors);
        self
    }

    /// Sets the base colour (linear light).
    pub fn with_base_color(mut self, color: [f32; 3]) -> Self {
        self.base_color = color;
        self
    }

    /// Draws the triangle edges in `color` (linear light).
    pub fn with_wireframe(mut self, color: [f32; 3]) -> Self {
        self.wireframe = Some(color);
        self
    }

    /// Sets whether back faces are lit like front faces.
    pub fn with_two_sided(mut self, two_sided: bool) -> Self {
        self.two_sided = two_sided;
        self
    }
}

/// A 3D polyline drawn over the surfaces (e.g. a highlight line).
///
/// It is depth-tested with a small offset towards the camera
/// ([`RenderOptions::line_depth_offset`]): parts lying on a surface are
/// visible, parts behind an object are hidden.
#[derive(Clone, Debug, PartialEq)]
pub struct PolylineLayer {
    /// The points; a non-finite point breaks the line.
    pub points: Vec<Vec3>,
    /// Whether the last point connects back to the first.
    pub closed: bool,
    /// Linear-light colour.
    pub color: [f32; 3],
    /// Line width in output pixels (anti-aliased, round joins and caps).
    pub width_px: f32,
}

/// A round marker at a 3D point, depth-tested like polylines.
#[derive(Clone, Debug, PartialEq)]
pub struct PointMarker {
    /// Position.
    pub position: Vec3,
    /// Linear-light colour.
    pub color: [f32; 3],
    /// Radius in output pixels.
    pub radius_px: f32,
}

/// Everything to draw in one picture.
#[derive(Clone, Debug, Default)]
pub struct Scene<'a> {
    /// Triangle meshes.
    pub meshes: Vec<MeshLayer<'a>>,
    /// Polylines drawn over the meshes.
    pub polylines: Vec<PolylineLayer>,
    /// Point markers drawn over the meshes.
    pub points: Vec<PointMarker>,
    /// Colour bar shown at the right edge.
    pub legend: Option<Legend>,
    /// Title shown centred at the top.
    pub title: Option<String>,
}

/// Light set-up. Directions are in camera space (x to the right of the
/// image, y up, z towards the viewer) and point *towards* the light, so the
/// lighting looks the same from every view direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Direction towards the key light.
    pub key_dir: Vec3,
    /// Diffuse and specular strength of the key light.
    pub key_intensity: f64,
    /// Direction towards the fill light.
    pub fill_dir: Vec3,
    /// Strength of the fill light.
    pub fill_intensity: f64,
    /// Hemispherical ambient strength (brighter for normals facing the image top).
    pub ambient: f64,
    /// Strength of the white Blinn–Phong highlight.
    pub specular: f64,
    /// Blinn–Phong exponent (larger = smaller, glossier highlight).
    pub shininess: f64,
}

impl Default for Lighting {
    fn default() -> Self {
        Lighting {
            key_dir: Vec3::new(-0.45, 0.55, 0.70),
            key_intensity: 0.78,
            fill_dir: Vec3::new(0.65, -0.20, 0.75),
            fill_intensity: 0.28,
            ambient: 0.20,
            specular: 0.35,
            shininess: 60.0,
        }
    }
}

/// How to render a [`Scene`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Image width in pixels (1..=[`MAX_IMAGE_SIDE`]).
    pub width: u32,
    /// Image height in pixels (1..=[`MAX_IMAGE_SIDE`]).
    pub height: u32,
    /// Viewing direction (from the eye towards the object).
    pub view_dir: Vec3,
    /// Direction that should point to the top of the image.
    pub up: Vec3,
    /// Samples per pixel along each axis (1..=[`MAX_SUPERSAMPLE`]); 3 gives 9
    /// samples per pixel.
    pub supersample: u32,
    /// Linear-light background colour.
    pub background: [f32; 3],
    /// Lights.
    pub lighting: Lighting,
    /// Parallel instead of perspective projection (when `camera` is `None`).
    pub orthographic: bool,
    /// Explicit camera (its `aspect` is replaced by the drawing area's);
    /// `None` aims a [`Camera::framing`] camera at the centre of the scene's
    /// bounding box and then moves it as close as the scene's points allow,
    /// so the object fills the picture up to a small margin.
    pub camera: Option<Camera>,
    /// How far (as a fraction of the scene's bounding-box diagonal) a
    /// polyline or marker may lie behind the surface and still be drawn.
    pub line_depth_offset: f64,
}

crate::control::setters!(RenderOptions {
    width: u32,
    height: u32,
    view_dir: Vec3,
    up: Vec3,
    supersample: u32,
    background: [f32; 3],
    lighting: Lighting,
    orthographic: bool,
    camera: Option<Camera>,
    line_depth_offset: f64,
});

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1024,
            height: 768,
            view_dir: Vec3::new(-0.5, 0.8, -0.55),
            up: Vec3::Z,
            supersample: 3,
            background: [0.80, 0.82, 0.85],
            lighting: Lighting::default(),
            orthographic: false,
            camera: None,
            line_depth_offset: 0.004,
        }
    }
}

impl RenderOptions {
    /// Default options with the given image size.
    pub fn with_size(width: u32, height: u32) -> Self {
        RenderOptions {
            width,
            height,
            ..Default::default()
        }
    }
}

/// Axis-aligned bounding box of everything finite in the scene, or `None`.
pub fn scene_bounds(scene: &Scene) -> Option<(Vec3, Vec3)> {
    let mut lo = Vec3::splat(f64::INFINITY);
    let mut hi = Vec3::splat(f64::NEG_INFINITY);
    let mut add = |p: Vec3| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    for m in &scene.meshes {
        m.positions.iter().for_each(|&p| add(p));
    }
    for l in &scene.polylines {
        l.points.iter().for_each(|&p| add(p));
    }
    for p in &scene.points {
        add(p.position);
    }
    (lo.cmple(hi).all()).then_some((lo, hi))
}

/// Renders `scene` into an sRGB image of `opts.width` × `opts.height`.
///
/// The 3D view fills the image except for a strip at the top for the title
/// and a strip at the right for the legend, so neither covers the object.
/// An empty scene gives the background (plus title/legend).
///
/// Errors: [`RenderError::InvalidSize`] for a zero side or a side above
/// [`MAX_IMAGE_SIDE`]; [`RenderError::InvalidSupersample`].
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Image, RenderError> {
    render_impl(scene, opts, None).map(|(img, _)| img)
}

/// [`render`] with text labels on regions of the first mesh (e.g. the
/// patch indices of a part of many patches): each label is
/// drawn at its region's *visible centre* — the visible pixel of the region
/// farthest from the region's visible outline (chamfer distance transform of
/// the per-pixel triangle ids) — on a light box, largest visible regions
/// first; a label whose box would overlap one already drawn, or whose region
/// is not visible, is left out. Returns the picture and the labels drawn.
pub fn render_labelled(
    scene: &Scene,
    opts: &RenderOptions,
    labels: &RegionLabels,
) -> Result<(Image, Vec<PlacedLabel>), RenderError> {
    render_impl(scene, opts, Some(labels))
}

/// The picture's width and height, refused when zero or beyond the limits
/// (and a supersampling factor beyond its limit).
fn check_picture_size(opts: &RenderOptions) -> Result<(u32, u32), RenderError> {
    let (w, h) = (opts.width, opts.height);
    if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(RenderError::InvalidSize {
            width: w,
            height: h,
        });
    }
    if opts.supersample == 0 || opts.supersample > MAX_SUPERSAMPLE {
        return Err(RenderError::InvalidSupersample(opts.supersample));
    }
    Ok((w, h))
}

fn render_impl(
    scene: &Scene,
    opts: &RenderOptions,
    labels: Option<&RegionLabels>,
) -> Result<(Image, Vec<PlacedLabel>), RenderError> {
    let (w, h) = check_picture_size(opts)?;
    let bg = linear_to_srgb8(opts.background);
    let mut img = Image::new(w, h, bg);
    let mut placed = Vec::new();
    let scale = text_scale(w, h);
    let pad = 4 * scale;
    let text_colour = contrasting_text(opts.background);

    // Layout: title strip at the top, legend strip at the right.
    let title_h = match &scene.title {
        Some(t) if !t.is_empty() && h > 4 * Image::text_height(scale) => {
            Image::text_height(scale) + 2 * pad
        }
        _ => 0,
    };
    let legend_w = match &scene.legend {
        Some(l) if l.width(scale) * 3 < w => l.width(scale),
        _ => 0,
    };
    let (rw, rh) = (w - legend_w, h - title_h);

    if let Some((lo, hi)) = scene_bounds(scene) {
        let camera = frame_camera(scene, opts, (lo, hi), rw as f64 / rh as f64);
        let diag = (hi - lo).length();
        let (view, ids) = raster::render_view(scene, opts, &camera, rw, rh, diag, labels.is_some());
        img.blit(&view, 0, title_h as i64);
        if let (Some(labels), Some(ids)) = (labels, ids) {
            placed = labels::place_and_draw(
                &mut img,
                &ids,
                (rw, rh),
                title_h,
                labels,
                scale,
                scene.meshes.first().map_or(0, |m| m.triangles.len()),
            );
        }
    }

    if title_h > 0 {
        let title = scene.title.as_deref().unwrap_or_default();
        let tw = Image::text_width(title, scale) as i64;
        img.draw_text(
            ((w as i64 - tw) / 2).max(pad as i64),
            pad as i64,
            title,
            text_colour,
            scale,
        );
    }
    if legend_w > 0
        && let Some(legend) = &scene.legend
    {
        legend.draw(
            &mut img,
            (w - legend_w) as i64,
            title_h as i64,
            rh,
            scale,
            text_colour,
        );
    }
    Ok((img, placed))
}

/// The camera of a picture of `scene` (bounding box `lo`–`hi`) with the
/// drawing area's `aspect`: `opts.camera` when given, else a framing camera
/// along `opts.view_dir` moved as close as the scene allows ([`tighten`]).
fn frame_camera(
    scene: &Scene,
    opts: &RenderOptions,
    (lo, hi): (Vec3, Vec3),
    aspect: f64,
) -> Camera {
    match opts.camera {
        Some(mut c) => {
            c.aspect = aspect;
            c
        }
        None => {
            let c = if opts.orthographic {
                Camera::framing_orthographic(lo, hi, opts.view_dir, opts.up, aspect)
            } else {
                Camera::framing(lo, hi, opts.view_dir, opts.up, aspect)
            };
            tighten(c, scene, 0.5 * (lo + hi))
        }
    }
}

/// What a picture of `scene` shows, without the picture: the camera
/// [`render`] frames the scene with for `opts` (over the whole `width` ×
/// `height`: no title or legend strip) and the global triangle id (meshes in
/// scene order, as [`render_labelled`] counts them) seen at the centre of
/// each pixel, row-major, `u32::MAX` where none. `None` for a scene with
/// nothing finite to frame. Used to judge from which side a part's picture
/// shows the most of it. Errors as [`render`].
pub fn visible_triangles(
    scene: &Scene,
    opts: &RenderOptions,
) -> Result<Option<(Camera, Vec<u32>)>, RenderError> {
    let (w, h) = check_picture_size(opts)?;
    let Some((lo, hi)) = scene_bounds(scene) else {
        return Ok(None);
    };
    let camera = frame_camera(scene, opts, (lo, hi), w as f64 / h as f64);
    let (_, ids) = raster::render_view(scene, opts, &camera, w, h, (hi - lo).length(), true);
    Ok(ids.map(|ids| (camera, ids)))
}

/// Font scale for an image size: 1 below 600 px, 2 up to 1000 px, 3 for 1200 px, ...
fn text_scale(w: u32, h: u32) -> u32 {
    ((w.min(h) + 200) / 400).clamp(1, 8)
}

/// Moves a framing camera (aimed at `centre`) as close as the scene's actual
/// points allow, instead of the bounding-box corners, keeping the direction
/// and the centre. Corners of an oblique box stick out far beyond most
/// objects, so this makes the object fill the picture.
fn tighten(mut cam: Camera, scene: &Scene, centre: Vec3) -> Camera {
    use rayon::prelude::*;
    let (hx, hy) = cam.half_extent();
    let (f, r, u) = (cam.forward, cam.right, cam.up);
    let k = 1.0 - camera::MARGIN;
    let need = |p: &Vec3| -> f64 {
        if !p.is_finite() {
            return f64::MIN;
        }
        let v = *p - centre;
        let (x, y, z) = (v.dot(r), v.dot(u), v.dot(f));
        if cam.is_perspective() {
            (x.abs() / (hx * k) - z).max(y.abs() / (hy * k) - z)
        } else {
            (x.abs() / cam.aspect).max(y.abs()) / k
        }
    };
    let mut m = f64::MIN;
    for mesh in &scene.meshes {
        m = m.max(
            mesh.positions
                .par_iter()
                .map(need)
                .reduce(|| f64::MIN, f64::max),
        );
    }
    for l in &scene.polylines {
        m = m.max(l.points.iter().map(need).fold(f64::MIN, f64::max));
    }
    for p in &scene.points {
        m = m.max(need(&p.position));
    }
    if !m.is_finite() {
        return cam;
    }
    match cam.projection {
        Projection::Perspective { .. } => {
            let old = (cam.eye - centre).length();
            // Keep every point in front of the near plane.
            let min_z = scene_min_depth(scene, centre, f);
            let dist = m.max(-min_z + 1e-3 * old).min(old);
            if dist > 0.0 && dist.is_finite() {
                cam.eye = centre - f * dist;
                cam.near = (0.5 * (dist + min_z)).max(1e-9 * old);
            }
        }
        Projection::Orthographic { half_height } => {
            if m > 0.0 && m < half_height {
                cam.projection = Projection::Orthographic { half_height: m };
            }
        }
    }
    cam
}

/// Smallest signed depth of any scene point relative to `centre` along `f`.
fn scene_min_depth(scene: &Scene, centre: Vec3, f: Vec3) -> f64 {
    use rayon::prelude::*;
    let depth = |p: &Vec3| {
        if p.is_finite() {
            (*p - centre).dot(f)
        } else {
            f64::MAX
        }
    };
    let mut m = f64::MAX;
    for mesh in &scene.meshes {
        m = m.min(
            mesh.positions
                .par_iter()
                .map(depth)
                .reduce(|| f64::MAX, f64::min),
        );
    }
    for l in &scene.polylines {
        m = m.min(l.points.iter().map(depth).fold(f64::MAX, f64::min));
    }
    for p in &scene.points {
        m = m.min(depth(&p.position));
    }
    m
}

/// Dark text on light backgrounds, light text on dark ones.
fn contrasting_text(bg: [f32; 3]) -> [u8; 4] {
    let lum = 0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2];
    if lum > 0.18 {
        [20, 20, 24, 255]
    } else {
        [235, 235, 235, 255]
    }
}

#[cfg(test)]
mod tests;
