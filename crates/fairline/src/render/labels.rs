//! Text labels on regions of a rendered mesh (the patch indices of a part
//! of many patches), placed at each region's visible
//! centre after the z-buffer pass.

use super::image::Image;

/// Labels for regions of the first mesh of a scene, for
/// [`super::render_labelled`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RegionLabels {
    /// Region of each triangle of `scene.meshes[0]`, in triangle order
    /// (`u32::MAX`: none). Triangles of other meshes belong to no region.
    pub triangle_region: Vec<u32>,
    /// Text of region `k` (an empty text, or a region without one, gets no
    /// label).
    pub texts: Vec<String>,
}

/// A label as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedLabel {
    /// The region.
    pub region: u32,
    /// Its text.
    pub text: String,
    /// The visible centre of the region (image pixel, x right, y down).
    pub anchor: [u32; 2],
    /// The label box: left, top, width, height (pixels).
    pub bounds: [i64; 4],
    /// Distance (pixels, chamfer 3-4 / 3) of the anchor from the region's
    /// visible outline.
    pub depth_px: f64,
}

/// Chamfer distance (3-4 metric, in thirds of a pixel) of every pixel from
/// the nearest pixel outside its own region (the image border counts as
/// outside); 0 for pixels of no region.
fn inner_distance(region: &[u32], w: usize, h: usize) -> Vec<u32> {
    const INF: u32 = u32::MAX / 2;
    let mut d = vec![INF; w * h];
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let r = region[k];
            let edge = r == u32::MAX
                || x == 0
                || y == 0
                || x + 1 == w
                || y + 1 == h
                || region[k - 1] != r
                || region[k + 1] != r
                || region[k - w] != r
                || region[k + w] != r;
            if edge {
                d[k] = if r == u32::MAX { 0 } else { 3 };
            }
        }
    }
    // Forward and backward passes of the 3-4 chamfer mask.
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let mut m = d[k];
            if x > 0 {
                m = m.min(d[k - 1] + 3);
            }
            if y > 0 {
                m = m.min(d[k - w] + 3);
                if x > 0 {
                    m = m.min(d[k - w - 1] + 4);
                }
                if x + 1 < w {
                    m = m.min(d[k - w + 1] + 4);
                }
            }
            d[k] = m;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let k = y * w + x;
            let mut m = d[k];
            if x + 1 < w {
                m = m.min(d[k + 1] + 3);
            }
            if y + 1 < h {
                m = m.min(d[k + w] + 3);
                if x + 1 < w {
                    m = m.min(d[k + w + 1] + 4);
                }
                if x > 0 {
                    m = m.min(d[k + w - 1] + 4);
                }
            }
            d[k] = m;
        }
    }
    d
}

/// Places the labels over the view (`size` pixels, drawn at row `top` of
/// `img`) from its per-pixel triangle ids, and draws them.
pub(super) fn place_and_draw(
    img: &mut Image,
    ids: &[u32],
    size: (u32, u32),
    top: u32,
    labels: &RegionLabels,
    scale: u32,
    first_mesh_triangles: usize,
) -> Vec<PlacedLabel> {
    let (w, h) = (size.0 as usize, size.1 as usize);
    if w == 0 || h == 0 || ids.len() != w * h {
        return Vec::new();
    }
    let region: Vec<u32> = ids
        .iter()
        .map(|&t| {
            let t = t as usize;
            if t < first_mesh_triangles {
                labels.triangle_region.get(t).copied().unwrap_or(u32::MAX)
            } else {
                u32::MAX
            }
        })
        .collect();
    let dist = inner_distance(&region, w, h);
    // The deepest pixel of every region (first in scan order on ties).
    let mut best: std::collections::BTreeMap<u32, (u32, usize)> = Default::default();
    for (k, (&r, &d)) in region.iter().zip(&dist).enumerate() {
        if r == u32::MAX {
            continue;
        }
        let e = best.entry(r).or_insert((d, k));
        if d > e.0 {
            *e = (d, k);
        }
    }
    let mut order: Vec<(u32, u32, usize)> = best.into_iter().map(|(r, (d, k))| (r, d, k)).collect();
    order.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let pad = scale.max(1) as i64 * 2;
    let mut placed: Vec<PlacedLabel> = Vec::new();
    let (iw, ih) = (img.width as i64, img.height as i64);
    for (r, d, k) in order {
        let Some(text) = labels.texts.get(r as usize).filter(|t| !t.is_empty()) else {
            continue;
        };
        let (ax, ay) = ((k % w) as i64, (k / w) as i64 + top as i64);
        let tw = Image::text_width(text, scale) as i64 + 2 * pad;
        let th = Image::cap_height(scale) as i64 + 2 * pad;
        let left = (ax - tw / 2).clamp(0, (iw - tw).max(0));
        let upper = (ay - th / 2).clamp(top as i64, (ih - th).max(top as i64));
        let overlaps = placed.iter().any(|p| {
            let [l, t, pw, ph] = p.bounds;
            left < l + pw && l < left + tw && upper < t + ph && t < upper + th
        });
        if overlaps {
            continue;
        }
        // A light box (70 % white over the picture) and dark text.
        for y in upper.max(0)..(upper + th).min(ih) {
            for x in left.max(0)..(left + tw).min(iw) {
                if let Some(px) = img.get(x as u32, y as u32) {
                    let mix = |c: u8| ((c as f64) * 0.3 + 255.0 * 0.7).round() as u8;
                    img.set(x, y, [mix(px[0]), mix(px[1]), mix(px[2]), 255]);
                }
            }
        }
        img.draw_text(left + pad, upper + pad, text, [15, 15, 20, 255], scale);
        placed.push(PlacedLabel {
            region: r,
            text: text.clone(),
            anchor: [ax as u32, ay as u32],
            bounds: [left, upper, tw, th],
            depth_px: d as f64 / 3.0,
        });
    }
    placed
}
