//! The z-buffer rasteriser behind [`super::render`].
//!
//! Pipeline, all at `s`× supersampled resolution ("samples"):
//! 1. project every vertex once (parallel) to fixed-point sample coordinates
//!    (8 sub-sample bits) and a depth key that is affine in screen space
//!    (`-1/z` for perspective, `z` for orthographic);
//! 2. bin triangles and line segments into horizontal bands by their
//!    y-range (counting sort, so each bin keeps index order);
//! 3. per band (parallel): rasterise the band's triangles into a depth +
//!    triangle-id buffer with exact i64 edge functions and the top-left
//!    rule; shade every covered sample (perspective-correct barycentrics,
//!    Blinn–Phong, wireframe from screen-space edge distances); draw the
//!    polylines/markers with coverage anti-aliasing and a depth test at the
//!    line's centre; box-filter down to output pixels and encode sRGB.
//!
//! The depth buffer of a band extends a few samples above and below it, so
//! the line depth test never has to look outside the band.

use rayon::prelude::*;

use super::image::{Image, encode_srgb};
use super::{Camera, MAX_LINE_WIDTH_PX, MeshLayer, RenderOptions, Scene};
use crate::Vec3;

/// Sub-sample steps per sample in fixed point.
const SUB: i64 = 256;
/// Output rows per band (fewer for very wide images, see [`MAX_BAND_SAMPLES`]).
const BAND_ROWS: usize = 16;
/// Upper bound on the samples of one band, to bound per-thread memory.
const MAX_BAND_SAMPLES: usize = 1 << 22;
/// Vertices further than this many samples outside the image are rejected
/// (keeps the i64 edge functions far from overflow).
const GUARD: f64 = 262_144.0;
/// Wireframe line width in output pixels.
const WIRE_WIDTH_PX: f64 = 1.0;
/// Specular factor on layers with per-vertex colours, so highlights do not
/// wash out the colour map's values.
const COLORED_SPECULAR: f64 = 0.3;
/// Colour of back faces of one-sided layers (linear light).
const BACK_FACE_COLOR: [f32; 3] = [0.16, 0.09, 0.05];
/// Linear-light colour of the dark stripes of a reflection zebra.
const ZEBRA_DARK: [f32; 3] = [0.02, 0.02, 0.02];

/// A projected vertex.
#[derive(Clone, Copy, Debug)]
struct PVert {
    /// Sample coordinates (x right, y down).
    x: f64,
    y: f64,
    /// Fixed-point sample coordinates.
    fx: i64,
    fy: i64,
    /// View depth along the camera's forward axis.
    z: f64,
    /// Depth key, affine in screen space; smaller is closer.
    key: f64,
    ok: bool,
}

const BAD: PVert = PVert {
    x: 0.0,
    y: 0.0,
    fx: 0,
    fy: 0,
    z: 0.0,
    key: 0.0,
    ok: false,
};

/// A projected line segment (or a marker when both ends coincide).
#[derive(Clone, Copy, Debug)]
struct Seg {
    ax: f64,
    ay: f64,
    akey: f64,
    bx: f64,
    by: f64,
    bkey: f64,
    /// Half width in samples.
    hw: f64,
    layer: u32,
    color: [f32; 3],
}

/// Items per band, in index order.
struct Bins {
    start: Vec<usize>,
    items: Vec<u32>,
}

impl Bins {
    /// Counting sort of items `i` with inclusive band range `ranges[i]` (empty when lo > hi).
    fn build(nbands: usize, ranges: &[(u32, u32)]) -> Bins {
        let mut count = vec![0usize; nbands + 1];
        for &(lo, hi) in ranges {
            for b in lo..=hi.min(nbands as u32 - 1) {
                count[b as usize + 1] += 1;
            }
        }
        for b in 0..nbands {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[nbands]];
        for (i, &(lo, hi)) in ranges.iter().enumerate() {
            for b in lo..=hi.min(nbands as u32 - 1) {
                items[fill[b as usize]] = i as u32;
                fill[b as usize] += 1;
            }
        }
        Bins {
            start: count,
            items,
        }
    }

    fn get(&self, band: usize) -> &[u32] {
        &self.items[self.start[band]..self.start[band + 1]]
    }
}

/// Lights and camera quantities in world space.
struct Shading {
    key: Vec3,
    fill: Vec3,
    up: Vec3,
    key_i: f64,
    fill_i: f64,
    ambient: f64,
    specular: f64,
    shininess: f64,
}

/// Shared, read-only state of one render.
struct Ctx<'s, 'a> {
    scene: &'s Scene<'a>,
    camera: &'s Camera,
    perspective: bool,
    /// Supersampled size.
    sw: usize,
    sh: usize,
    /// Output size of the view.
    w: usize,
    h: usize,
    s: usize,
    pverts: Vec<PVert>,
    vert_offset: Vec<usize>,
    tri_offset: Vec<usize>,
    segs: Vec<Seg>,
    /// Extra depth rows above/below a band, in samples.
    margin: usize,
    /// Output rows per band.
    band_rows: usize,
    background: [f32; 3],
    light: Shading,
    /// Allowed depth of a line behind the surface (world units).
    line_tol: f64,
    /// Half wireframe width in samples.
    wire_hw: f64,
}

#[inline]
fn edge(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

#[inline]
fn edge_f(ax: f64, ay: f64, bx: f64, by: f64, px: f64, py: f64) -> f64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// Whether samples exactly on edge a→b belong to the triangle (for positive
/// orientation). The rule is antisymmetric, so of two triangles sharing an
/// edge exactly one owns the samples on it.
#[inline]
fn owns_edge(ax: i64, ay: i64, bx: i64, by: i64) -> bool {
    let (dx, dy) = (bx - ax, by - ay);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Renders the 3D view of `scene` into a `w` × `h` sRGB image; with
/// `want_ids`, also the global triangle id (meshes in scene order, their
/// triangles in order) visible at the centre sample of every output pixel,
/// row-major, `u32::MAX` where no triangle is.
pub(crate) fn render_view(
    scene: &Scene,
    opts: &RenderOptions,
    camera: &Camera,
    w: u32,
    h: u32,
    diag: f64,
    want_ids: bool,
) -> (Image, Option<Vec<u32>>) {
    let s = opts.supersample.max(1) as usize;
    let (w, h) = (w as usize, h as usize);
    let projector = Projector {
        camera,
        sw: w * s,
        sh: h * s,
        perspective: camera.is_perspective(),
    };
    // 1. vertices, lines and markers
    let (vert_offset, tri_offset) = mesh_offsets(scene);
    let pverts = projector.project_meshes(scene, last(&vert_offset));
    let segs = projector.project_lines(scene, s);
    let ctx = Ctx::new(
        scene,
        opts,
        &projector,
        (w, h, s),
        (pverts, vert_offset, tri_offset, segs),
        diag,
    );
    // 2. binning
    let (tri_bins, seg_bins) = ctx.bin_triangles_and_segments();
    // 3. bands
    let (pixels, ids) = ctx.render_bands(&tri_bins, &seg_bins, want_ids);
    let image = Image {
        width: w as u32,
        height: h as u32,
        pixels,
    };
    (image, want_ids.then_some(ids))
}

/// The last entry of a prefix-sum list (0 when empty).
fn last(offsets: &[usize]) -> usize {
    offsets.last().copied().unwrap_or(0)
}

/// Prefix sums of the vertex and triangle counts of the scene's meshes:
/// mesh `m`'s vertices (triangles) are global indices
/// `offset[m]..offset[m + 1]`.
fn mesh_offsets(scene: &Scene) -> (Vec<usize>, Vec<usize>) {
    let mut vert_offset = vec![0usize];
    let mut tri_offset = vec![0usize];
    for m in &scene.meshes {
        vert_offset.push(last(&vert_offset) + m.positions.len());
        tri_offset.push(last(&tri_offset) + m.triangles.len());
    }
    (vert_offset, tri_offset)
}

/// Projection of world points to supersampled screen samples (step 1 of
/// the pipeline in the module docs).
struct Projector<'c> {
    camera: &'c Camera,
    /// Supersampled size.
    sw: usize,
    sh: usize,
    perspective: bool,
}

impl Projector<'_> {
    /// `p` in sample coordinates with its depth key; [`BAD`] behind the
    /// camera, far outside the image or not finite.
    fn project(&self, p: Vec3) -> PVert {
        let Some(q) = self.camera.project(p) else {
            return BAD;
        };
        let x = (q.x + 1.0) * 0.5 * self.sw as f64;
        let y = (1.0 - q.y) * 0.5 * self.sh as f64;
        let key = if self.perspective { -1.0 / q.z } else { q.z };
        if !(x.abs() < GUARD && y.abs() < GUARD && key.is_finite()) {
            return BAD;
        }
        PVert {
            x,
            y,
            fx: (x * SUB as f64).round() as i64,
            fy: (y * SUB as f64).round() as i64,
            z: q.z,
            key,
            ok: true,
        }
    }

    /// Every vertex of every mesh, meshes in scene order (parallel).
    fn project_meshes(&self, scene: &Scene, count: usize) -> Vec<PVert> {
        let mut pverts = Vec::with_capacity(count);
        for m in &scene.meshes {
            pverts.par_extend(m.positions.par_iter().map(|&p| self.project(p)));
        }
        pverts
    }

    /// Segment `a`–`b` clipped at the near plane (perspective) and
    /// projected; `None` when nothing of it can be drawn.
    fn clip_project(&self, a: Vec3, b: Vec3) -> Option<(PVert, PVert)> {
        if !(a.is_finite() && b.is_finite()) {
            return None;
        }
        let (mut a, mut b) = (a, b);
        if self.perspective {
            let camera = self.camera;
            let near = camera.near * (1.0 + 1e-9) + f64::MIN_POSITIVE;
            let (za, zb) = (camera.depth(a), camera.depth(b));
            if za < near && zb < near {
                return None;
            }
            if za < near {
                a = a + (b - a) * ((near - za) / (zb - za));
            } else if zb < near {
                b = b + (a - b) * ((near - zb) / (za - zb));
            }
        }
        let (pa, pb) = (self.project(a), self.project(b));
        (pa.ok && pb.ok).then_some((pa, pb))
    }

    /// The polylines and point markers of `scene` as projected segments
    /// (a marker is a segment whose ends coincide); each polyline and each
    /// marker is its own layer, in scene order. `s` is the supersampling.
    fn project_lines(&self, scene: &Scene, s: usize) -> Vec<Seg> {
        let px_to_samples = |px: f32| {
            let px = if px.is_finite() {
                px.clamp(0.0, MAX_LINE_WIDTH_PX)
            } else {
                1.0
            };
            px as f64 * s as f64
        };
        let mut segs = Vec::new();
        let mut layer = 0u32;
        for line in &scene.polylines {
            let hw = 0.5 * px_to_samples(line.width_px);
            let n = line.points.len();
            let nseg = if line.closed && n > 2 {
                n
            } else {
                n.saturating_sub(1)
            };
            for i in 0..nseg {
                if let Some((pa, pb)) = self.clip_project(line.points[i], line.points[(i + 1) % n])
                {
                    segs.push(Seg::new(pa, pb, hw, layer, line.color));
                }
            }
            if n == 1
                && let Some((pa, pb)) = self.clip_project(line.points[0], line.points[0])
            {
                segs.push(Seg::new(pa, pb, hw, layer, line.color));
            }
            layer += 1;
        }
        for m in &scene.points {
            if let Some((pa, pb)) = self.clip_project(m.position, m.position) {
                segs.push(Seg::new(pa, pb, px_to_samples(m.radius_px), layer, m.color));
            }
            layer += 1;
        }
        segs
    }
}

impl Seg {
    fn new(pa: PVert, pb: PVert, hw: f64, layer: u32, color: [f32; 3]) -> Seg {
        Seg {
            ax: pa.x,
            ay: pa.y,
            akey: pa.key,
            bx: pb.x,
            by: pb.y,
            bkey: pb.key,
            hw,
            layer,
            color,
        }
    }
}

/// What step 1 produced: projected vertices, the vertex and triangle
/// offsets of the meshes ([`mesh_offsets`]) and the projected segments.
type Projected = (Vec<PVert>, Vec<usize>, Vec<usize>, Vec<Seg>);

impl<'s, 'a> Ctx<'s, 'a> {
    /// The state of one render: sizes (`w`, `h` output pixels, `s`×
    /// supersampling), the projected geometry, band layout and the lights
    /// turned from camera space into world space.
    fn new(
        scene: &'s Scene<'a>,
        opts: &RenderOptions,
        projector: &Projector<'s>,
        (w, h, s): (usize, usize, usize),
        (pverts, vert_offset, tri_offset, segs): Projected,
        diag: f64,
    ) -> Self {
        let camera = projector.camera;
        let sw = projector.sw;
        let max_hw = segs.iter().map(|g| g.hw).fold(0.0, f64::max);
        let margin = (max_hw.ceil() as usize + 2).max(2);
        let l = &opts.lighting;
        let to_world = |d: Vec3| {
            (camera.right * d.x + camera.up * d.y - camera.forward * d.z)
                .try_normalize()
                .unwrap_or(-camera.forward)
        };
        let num = |v: f64, default: f64| if v.is_finite() { v } else { default };
        Ctx {
            scene,
            camera,
            perspective: projector.perspective,
            sw,
            sh: projector.sh,
            w,
            h,
            s,
            pverts,
            vert_offset,
            tri_offset,
            segs,
            margin,
            band_rows: (MAX_BAND_SAMPLES / (sw * s)).clamp(1, BAND_ROWS),
            background: opts.background,
            light: Shading {
                key: to_world(l.key_dir),
                fill: to_world(l.fill_dir),
                up: camera.up,
                key_i: num(l.key_intensity, 0.0),
                fill_i: num(l.fill_intensity, 0.0),
                ambient: num(l.ambient, 0.0),
                specular: num(l.specular, 0.0),
                shininess: num(l.shininess, 1.0).max(1.0),
            },
            line_tol: num(opts.line_depth_offset, 0.0).max(0.0)
                * if diag > 0.0 { diag } else { 1.0 },
            wire_hw: 0.5 * WIRE_WIDTH_PX * s as f64,
        }
    }

    /// Inclusive range of bands that samples `y_lo ..= y_hi`, widened by
    /// `extra` samples, touch (empty, `(1, 0)`, when outside the image).
    fn band_range(&self, y_lo: f64, y_hi: f64, extra: f64) -> (u32, u32) {
        let band_s = self.band_rows * self.s;
        let lo = ((y_lo - extra).floor().max(0.0)) as usize / band_s;
        let hi_f = (y_hi + extra).ceil();
        if hi_f < 0.0 || y_lo - extra >= self.sh as f64 {
            return (1, 0);
        }
        let hi = (hi_f as usize).min(self.sh - 1) / band_s;
        (lo as u32, hi as u32)
    }

    /// Step 2: the triangles and the segments of every band, in index
    /// order.
    fn bin_triangles_and_segments(&self) -> (Bins, Bins) {
        let nbands = self.h.div_ceil(self.band_rows);
        let sw = self.sw;
        let mut tri_ranges: Vec<(u32, u32)> = Vec::with_capacity(last(&self.tri_offset));
        for (mi, m) in self.scene.meshes.iter().enumerate() {
            tri_ranges.par_extend(m.triangles.par_iter().map(move |t| {
                let Some([a, b, c]) = self.tri_verts(mi, t) else {
                    return (1, 0);
                };
                let y_lo = a.y.min(b.y).min(c.y);
                let y_hi = a.y.max(b.y).max(c.y);
                let x_lo = a.x.min(b.x).min(c.x);
                let x_hi = a.x.max(b.x).max(c.x);
                if x_hi < 0.0 || x_lo > sw as f64 {
                    return (1, 0);
                }
                self.band_range(y_lo, y_hi, self.margin as f64 + 1.0)
            }));
        }
        let tri_bins = Bins::build(nbands, &tri_ranges);
        drop(tri_ranges);
        let seg_ranges: Vec<(u32, u32)> = self
            .segs
            .iter()
            .map(|g| self.band_range(g.ay.min(g.by), g.ay.max(g.by), g.hw + 1.0))
            .collect();
        let seg_bins = Bins::build(nbands, &seg_ranges);
        (tri_bins, seg_bins)
    }

    /// Step 3: every band rendered (parallel) into the output pixels and,
    /// with `want_ids`, the triangle ids (else an empty list).
    fn render_bands(
        &self,
        tri_bins: &Bins,
        seg_bins: &Bins,
        want_ids: bool,
    ) -> (Vec<[u8; 4]>, Vec<u32>) {
        let (w, h, band_rows) = (self.w, self.h, self.band_rows);
        let mut pixels = vec![[0u8; 4]; w * h];
        let mut ids = if want_ids {
            vec![u32::MAX; w * h]
        } else {
            Vec::new()
        };
        if want_ids {
            pixels
                .par_chunks_mut(band_rows * w)
                .zip(ids.par_chunks_mut(band_rows * w))
                .enumerate()
                .for_each(|(band, (out, id_out))| {
                    self.render_band(
                        band,
                        tri_bins.get(band),
                        seg_bins.get(band),
                        out,
                        Some(id_out),
                    )
                });
        } else {
            pixels
                .par_chunks_mut(band_rows * w)
                .enumerate()
                .for_each(|(band, out)| {
                    self.render_band(band, tri_bins.get(band), seg_bins.get(band), out, None)
                });
        }
        (pixels, ids)
    }
}

/// Per-triangle data cached while shading consecutive samples of one triangle.
struct TriShade {
    id: u32,
    p: [(f64, f64); 3],
    z: [f64; 3],
    face_n: Vec3,
    normals: Option<[Vec3; 3]>,
    colors: Option<[[f32; 3]; 3]>,
    base: [f32; 3],
    wire: Option<[f32; 3]>,
    /// 1 / length of the edge opposite each vertex (samples).
    inv_len: [f64; 3],
    /// Specular strength factor (reduced on colour-mapped layers).
    spec_scale: f64,
    two_sided: bool,
    zebra: Option<super::ReflectionZebra>,
}

impl<'s, 'a> Ctx<'s, 'a> {
    /// Projected vertices of triangle `t` of mesh `mi`, if it can be drawn.
    #[inline]
    fn tri_verts(&self, mi: usize, t: &[u32; 3]) -> Option<[PVert; 3]> {
        let n = self.scene.meshes[mi].positions.len();
        let off = self.vert_offset[mi];
        if t.iter().any(|&i| i as usize >= n) {
            return None;
        }
        let v = t.map(|i| self.pverts[off + i as usize]);
        (v[0].ok && v[1].ok && v[2].ok).then_some(v)
    }

    /// Mesh index and local triangle index of global triangle `id`.
    #[inline]
    fn locate(&self, id: u32) -> (usize, usize) {
        let id = id as usize;
        let mi = self.tri_offset.partition_point(|&o| o <= id) - 1;
        (mi, id - self.tri_offset[mi])
    }

    #[inline]
    fn key_to_z(&self, key: f64) -> f64 {
        if self.perspective { -1.0 / key } else { key }
    }

    fn render_band(
        &self,
        band: usize,
        tris: &[u32],
        segs: &[u32],
        out: &mut [[u8; 4]],
        id_out: Option<&mut [u32]>,
    ) {
        let s = self.s;
        let sw = self.sw;
        let oy0 = band * self.band_rows;
        let oy1 = (oy0 + self.band_rows).min(self.h);
        let (y0, y1) = (oy0 * s, oy1 * s);
        let ey0 = y0.saturating_sub(self.margin);
        let ey1 = (y1 + self.margin).min(self.sh);
        let rows = ey1 - ey0;
        let mut depth = vec![f32::INFINITY; sw * rows];
        let mut ids = vec![u32::MAX; sw * rows];
        for &t in tris {
            self.raster_triangle(t, ey0, ey1, &mut depth, &mut ids);
        }

        // Shade the band's own rows.
        let mut color = vec![self.background; sw * (y1 - y0)];
        let mut cache: Option<TriShade> = None;
        for y in y0..y1 {
            let drow = (y - ey0) * sw;
            let crow = (y - y0) * sw;
            for x in 0..sw {
                let id = ids[drow + x];
                if id == u32::MAX {
                    continue;
                }
                if cache.as_ref().is_none_or(|c| c.id != id) {
                    cache = Some(self.tri_shade(id));
                }
                if let Some(c) = &cache {
                    color[crow + x] = self.shade(c, x as f64 + 0.5, y as f64 + 0.5);
                }
            }
        }

        self.draw_segments(segs, &depth, ey0, ey1, y0, y1, &mut color);

        if let Some(id_out) = id_out {
            // The triangle at the centre sample of each output pixel.
            for oy in oy0..oy1 {
                let row = (oy * s + s / 2 - ey0) * sw;
                for ox in 0..self.w {
                    id_out[(oy - oy0) * self.w + ox] = ids[row + ox * s + s / 2];
                }
            }
        }

        // Box filter down and encode.
        let inv = 1.0 / (s * s) as f32;
        for oy in oy0..oy1 {
            for ox in 0..self.w {
                let mut acc = [0f32; 3];
                for sy in 0..s {
                    let row = (oy * s + sy - y0) * sw + ox * s;
                    for c in &color[row..row + s] {
                        acc[0] += c[0].clamp(0.0, 1.0);
                        acc[1] += c[1].clamp(0.0, 1.0);
                        acc[2] += c[2].clamp(0.0, 1.0);
                    }
                }
                out[(oy - oy0) * self.w + ox] = [
                    encode_srgb(acc[0] * inv),
                    encode_srgb(acc[1] * inv),
                    encode_srgb(acc[2] * inv),
                    255,
                ];
            }
        }
    }

    /// Rasterises global triangle `id` into the depth/id buffers covering sample rows `ey0..ey1`.
    fn raster_triangle(&self, id: u32, ey0: usize, ey1: usize, depth: &mut [f32], ids: &mut [u32]) {
        let (mi, ti) = self.locate(id);
        let Some([a, mut b, mut c]) = self.tri_verts(mi, &self.scene.meshes[mi].triangles[ti])
        else {
            return;
        };
        let mut area = edge(a.fx, a.fy, b.fx, b.fy, c.fx, c.fy);
        if area == 0 {
            return;
        }
        if area < 0 {
            std::mem::swap(&mut b, &mut c);
            area = -area;
        }
        let half = SUB / 2;
        let min_x = a.fx.min(b.fx).min(c.fx);
        let max_x = a.fx.max(b.fx).max(c.fx);
        let min_y = a.fy.min(b.fy).min(c.fy);
        let max_y = a.fy.max(b.fy).max(c.fy);
        // Sample i has its centre at i * SUB + SUB / 2.
        let x_lo = (min_x - half + SUB - 1).div_euclid(SUB).max(0);
        let x_hi = (max_x - half).div_euclid(SUB).min(self.sw as i64 - 1);
        let y_lo = (min_y - half + SUB - 1).div_euclid(SUB).max(ey0 as i64);
        let y_hi = (max_y - half).div_euclid(SUB).min(ey1 as i64 - 1);
        if x_lo > x_hi || y_lo > y_hi {
            return;
        }
        let (px, py) = (x_lo * SUB + half, y_lo * SUB + half);
        // e0 weighs a, e1 weighs b, e2 weighs c. The bias makes "inside" a
        // plain `>= 0` test: samples on a non-owned edge get -1.
        let bias = |ax, ay, bx, by| if owns_edge(ax, ay, bx, by) { 0 } else { -1 };
        let mut r0 = edge(b.fx, b.fy, c.fx, c.fy, px, py) + bias(b.fx, b.fy, c.fx, c.fy);
        let mut r1 = edge(c.fx, c.fy, a.fx, a.fy, px, py) + bias(c.fx, c.fy, a.fx, a.fy);
        let mut r2 = edge(a.fx, a.fy, b.fx, b.fy, px, py) + bias(a.fx, a.fy, b.fx, b.fy);
        let (sx0, sy0) = (-(c.fy - b.fy) * SUB, (c.fx - b.fx) * SUB);
        let (sx1, sy1) = (-(a.fy - c.fy) * SUB, (a.fx - c.fx) * SUB);
        let (sx2, sy2) = (-(b.fy - a.fy) * SUB, (b.fx - a.fx) * SUB);
        let inv_area = 1.0 / area as f64;
        let (ka, kb, kc) = (a.key * inv_area, b.key * inv_area, c.key * inv_area);
        let sw = self.sw;
        for y in y_lo..=y_hi {
            let row = (y as usize - ey0) * sw;
            let (mut e0, mut e1, mut e2) = (r0, r1, r2);
            for x in x_lo..=x_hi {
                if (e0 | e1 | e2) >= 0 {
                    let key = (e0 as f64 * ka + e1 as f64 * kb + e2 as f64 * kc) as f32;
                    let i = row + x as usize;
                    if key < depth[i] {
                        depth[i] = key;
                        ids[i] = id;
                    }
                }
                e0 += sx0;
                e1 += sx1;
                e2 += sx2;
            }
            r0 += sy0;
            r1 += sy1;
            r2 += sy2;
        }
    }

    fn tri_shade(&self, id: u32) -> TriShade {
        let (mi, ti) = self.locate(id);
        let m: &MeshLayer = &self.scene.meshes[mi];
        let t = m.triangles[ti].map(|i| i as usize);
        let off = self.vert_offset[mi];
        let pv = t.map(|i| self.pverts[off + i]);
        let pos = t.map(|i| m.positions[i]);
        let face_n = (pos[1] - pos[0])
            .cross(pos[2] - pos[0])
            .try_normalize()
            .unwrap_or(-self.camera.forward);
        let normals = m.normals.and_then(|ns| {
            let v = [ns.get(t[0])?, ns.get(t[1])?, ns.get(t[2])?];
            v.iter()
                .all(|n| n.is_finite() && n.length_squared() > 0.0)
                .then(|| v.map(|n| *n))
        });
        let colors = m.colors.and_then(|cs| {
            let v = [cs.get(t[0])?, cs.get(t[1])?, cs.get(t[2])?];
            v.iter()
                .all(|c| c.iter().all(|x| x.is_finite()))
                .then(|| v.map(|c| *c))
        });
        let p = pv.map(|v| (v.x, v.y));
        let len = |i: usize, j: usize| ((p[i].0 - p[j].0).hypot(p[i].1 - p[j].1)).max(1e-9);
        TriShade {
            id,
            p,
            z: pv.map(|v| v.z),
            face_n,
            normals,
            colors,
            base: m.base_color,
            wire: m.wireframe,
            inv_len: [1.0 / len(1, 2), 1.0 / len(2, 0), 1.0 / len(0, 1)],
            spec_scale: if colors.is_some() {
                COLORED_SPECULAR
            } else {
                1.0
            },
            two_sided: m.two_sided,
            zebra: m.zebra,
        }
    }

    /// The barycentric weights (perspective-correct) of sample (`px`, `py`)
    /// on triangle `t`, and its edge functions; `clamp`: weights of samples
    /// outside the triangle cut at 0 (shading), else continued linearly
    /// (derivatives).
    fn weights(&self, t: &TriShade, px: f64, py: f64, clamp: bool) -> ([f64; 3], [f64; 3]) {
        let [(ax, ay), (bx, by), (cx, cy)] = t.p;
        let e = [
            edge_f(bx, by, cx, cy, px, py),
            edge_f(cx, cy, ax, ay, px, py),
            edge_f(ax, ay, bx, by, px, py),
        ];
        let area = e[0] + e[1] + e[2];
        let mut w = if area.abs() > 1e-12 {
            e.map(|v| if clamp { (v / area).max(0.0) } else { v / area })
        } else {
            [1.0 / 3.0; 3]
        };
        if self.perspective {
            w = [w[0] / t.z[0], w[1] / t.z[1], w[2] / t.z[2]];
        }
        let sum = w[0] + w[1] + w[2];
        let w = if sum != 0.0 && sum.is_finite() {
            w.map(|v| v / sum)
        } else {
            [1.0 / 3.0; 3]
        };
        (w, e)
    }

    /// The ray from the eye through sample (`px`, `py`) and the
    /// interpolated unit normal there, facing the eye.
    fn ray_and_normal(&self, t: &TriShade, px: f64, py: f64) -> (Vec3, Vec3, bool) {
        let (w, _) = self.weights(t, px, py, false);
        let ndc_x = px / self.sw as f64 * 2.0 - 1.0;
        let ndc_y = 1.0 - py / self.sh as f64 * 2.0;
        let ray = self.camera.ray_direction(ndc_x, ndc_y);
        let back = t.face_n.dot(-ray) < 0.0;
        let mut n = match &t.normals {
            Some(ns) => (ns[0] * w[0] + ns[1] * w[1] + ns[2] * w[2])
                .try_normalize()
                .unwrap_or(t.face_n),
            None => t.face_n,
        };
        if back {
            n = -n;
        }
        (ray, n, back)
    }

    /// The zebra's dark coverage at sample (`px`, `py`) of triangle `t`:
    /// the stripe coordinate there and its change over one output pixel
    /// (the triangle's interpolation continued, so the filter sees the
    /// pattern's density on the screen).
    fn zebra_coverage(&self, t: &TriShade, z: &super::ReflectionZebra, px: f64, py: f64) -> f64 {
        let at = |x: f64, y: f64| {
            let (ray, n, _) = self.ray_and_normal(t, x, y);
            z.stripe(ray, n)
        };
        let step = self.s as f64;
        let t0 = at(px, py);
        let turn = 360.0 / z.period_deg;
        let wrap = |d: f64| {
            let d = d.abs() % turn;
            d.min(turn - d)
        };
        let dt = wrap(at(px + step, py) - t0).max(wrap(at(px, py + step) - t0));
        if !(t0.is_finite() && dt.is_finite()) {
            return 0.0;
        }
        z.coverage(t0, dt)
    }

    /// Linear-light colour of the sample at (`px`, `py`) (sample coordinates) on triangle `t`.
    fn shade(&self, t: &TriShade, px: f64, py: f64) -> [f32; 3] {
        let (w, e) = self.weights(t, px, py, true);

        let ndc_x = px / self.sw as f64 * 2.0 - 1.0;
        let ndc_y = 1.0 - py / self.sh as f64 * 2.0;
        let to_eye = -self.camera.ray_direction(ndc_x, ndc_y);
        let back = t.face_n.dot(to_eye) < 0.0;
        let mut n = match &t.normals {
            Some(ns) => (ns[0] * w[0] + ns[1] * w[1] + ns[2] * w[2])
                .try_normalize()
                .unwrap_or(t.face_n),
            None => t.face_n,
        };
        if back {
            n = -n;
        }
        let mut col = if back && !t.two_sided {
            BACK_FACE_COLOR
        } else {
            match &t.colors {
                Some(cs) => [0, 1, 2].map(|k| {
                    (cs[0][k] as f64 * w[0] + cs[1][k] as f64 * w[1] + cs[2][k] as f64 * w[2])
                        as f32
                }),
                None => t.base,
            }
        };

        let l = &self.light;
        let hemi = l.ambient * (0.75 + 0.25 * n.dot(l.up));
        let nk = n.dot(l.key);
        let nf = n.dot(l.fill);
        let diffuse = hemi + l.key_i * nk.max(0.0) + l.fill_i * nf.max(0.0);
        let mut spec = 0.0;
        if nk > 0.0 {
            let hk = (l.key + to_eye).normalize_or_zero();
            spec += l.specular * l.key_i * n.dot(hk).max(0.0).powf(l.shininess);
        }
        if nf > 0.0 {
            let hf = (l.fill + to_eye).normalize_or_zero();
            spec += 0.5 * l.specular * l.fill_i * n.dot(hf).max(0.0).powf(l.shininess);
        }
        let (diffuse, spec) = (diffuse as f32, (spec * t.spec_scale) as f32);
        for c in col.iter_mut() {
            *c = *c * diffuse + spec;
        }

        if let Some(z) = &t.zebra
            && (!back || t.two_sided)
        {
            let a = self.zebra_coverage(t, z, px, py) as f32;
            for k in 0..3 {
                col[k] += (ZEBRA_DARK[k] - col[k]) * a;
            }
        }

        if let Some(wc) = t.wire {
            let d = (e[0].abs() * t.inv_len[0])
                .min(e[1].abs() * t.inv_len[1])
                .min(e[2].abs() * t.inv_len[2]);
            let cov = (self.wire_hw + 0.5 - d).clamp(0.0, 1.0) as f32;
            if cov > 0.0 {
                for k in 0..3 {
                    col[k] += (wc[k] - col[k]) * cov;
                }
            }
        }
        col
    }

    /// Draws the band's segments into `color` (rows `y0..y1`), each layer
    /// with max-coverage so joints of one polyline do not darken.
    #[allow(clippy::too_many_arguments)]
    fn draw_segments(
        &self,
        items: &[u32],
        depth: &[f32],
        ey0: usize,
        ey1: usize,
        y0: usize,
        y1: usize,
        color: &mut [[f32; 3]],
    ) {
        if items.is_empty() {
            return;
        }
        let sw = self.sw;
        let mut cov = vec![0f32; sw * (y1 - y0)];
        // Touched box of the current layer: x0, x1, y0, y1 (exclusive ends, band rows).
        let mut bx = (usize::MAX, 0usize, usize::MAX, 0usize);
        let mut layer = u32::MAX;
        let mut layer_color = [0f32; 3];
        let flush = |cov: &mut [f32],
                     color: &mut [[f32; 3]],
                     bx: &mut (usize, usize, usize, usize),
                     lc: [f32; 3]| {
            for y in bx.2..bx.3 {
                for x in bx.0..bx.1 {
                    let i = y * sw + x;
                    let a = cov[i];
                    if a > 0.0 {
                        let c = &mut color[i];
                        for k in 0..3 {
                            c[k] += (lc[k] - c[k]) * a;
                        }
                        cov[i] = 0.0;
                    }
                }
            }
            *bx = (usize::MAX, 0, usize::MAX, 0);
        };
        for &si in items {
            let g = &self.segs[si as usize];
            if g.layer != layer {
                flush(&mut cov, color, &mut bx, layer_color);
                layer = g.layer;
                layer_color = g.color;
            }
            let reach = g.hw + 1.0;
            let gx0 = (g.ax.min(g.bx) - reach).floor().max(0.0) as usize;
            let gx1 = ((g.ax.max(g.bx) + reach).ceil().max(0.0) as usize).min(sw);
            let gy0 = ((g.ay.min(g.by) - reach).floor().max(y0 as f64) as usize).min(y1);
            let gy1 = ((g.ay.max(g.by) + reach).ceil().max(0.0) as usize).clamp(y0, y1);
            if gx0 >= gx1 || gy0 >= gy1 {
                continue;
            }
            bx = (
                bx.0.min(gx0),
                bx.1.max(gx1),
                bx.2.min(gy0 - y0),
                bx.3.max(gy1 - y0),
            );
            let (dx, dy) = (g.bx - g.ax, g.by - g.ay);
            let len2 = dx * dx + dy * dy;
            let inv_len2 = if len2 > 1e-12 { 1.0 / len2 } else { 0.0 };
            for y in gy0..gy1 {
                let py = y as f64 + 0.5;
                for x in gx0..gx1 {
                    let px = x as f64 + 0.5;
                    let t = (((px - g.ax) * dx + (py - g.ay) * dy) * inv_len2).clamp(0.0, 1.0);
                    let (cx, cy) = (g.ax + t * dx, g.ay + t * dy);
                    let d = (px - cx).hypot(py - cy);
                    let a = (g.hw + 0.5 - d).clamp(0.0, 1.0) as f32;
                    if a <= 0.0 {
                        continue;
                    }
                    // Depth test at the line's centre point.
                    let sx = (cx.floor().max(0.0) as usize).min(sw - 1);
                    let sy = (cy.floor().max(ey0 as f64) as usize).clamp(ey0, ey1 - 1);
                    let surface = depth[(sy - ey0) * sw + sx];
                    if surface.is_finite() {
                        let zl = self.key_to_z(g.akey + t * (g.bkey - g.akey));
                        let zs = self.key_to_z(surface as f64);
                        if zl > zs + self.line_tol {
                            continue;
                        }
                    }
                    let i = (y - y0) * sw + x;
                    if a > cov[i] {
                        cov[i] = a;
                    }
                }
            }
        }
        flush(&mut cov, color, &mut bx, layer_color);
    }
}
