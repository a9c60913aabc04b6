//! 8-bit sRGB images: PNG encoding, atomic writing, text, panels.

use std::io::Write;
use std::path::Path;

use super::RenderError;
use super::font::{CAP_H, CELL_H, CELL_W, glyph};

/// An RGBA image, 8 bits per channel, sRGB encoded, rows top to bottom.
///
/// `pixels[y * width + x]` is the pixel in column `x`, row `y` (row 0 at the top).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels, `[r, g, b, a]`, row-major from the top-left corner.
    pub pixels: Vec<[u8; 4]>,
}

/// Converts a linear-light colour (components 0..1, clamped) to 8-bit sRGB with alpha 255.
pub fn linear_to_srgb8(c: [f32; 3]) -> [u8; 4] {
    [encode_srgb(c[0]), encode_srgb(c[1]), encode_srgb(c[2]), 255]
}

/// One linear-light component (0..1, clamped; NaN gives 0) to an 8-bit sRGB value.
pub(crate) fn encode_srgb(v: f32) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// One sRGB component (0..1) to linear light.
pub(crate) fn decode_srgb(s: f32) -> f32 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

impl Image {
    /// A `width` × `height` image filled with `fill` (sRGBA).
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Image {
        Image {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// The pixel at (`x`, `y`), or `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        (x < self.width && y < self.height)
            .then(|| self.pixels[y as usize * self.width as usize + x as usize])
    }

    /// Sets the pixel at (`x`, `y`); coordinates outside the image are ignored.
    pub fn set(&mut self, x: i64, y: i64, colour: [u8; 4]) {
        if x >= 0 && y >= 0 && (x as u64) < self.width as u64 && (y as u64) < self.height as u64 {
            self.pixels[y as usize * self.width as usize + x as usize] = colour;
        }
    }

    /// Fills the rectangle with top-left corner (`x`, `y`) and size `w` × `h`,
    /// clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: u32, h: u32, colour: [u8; 4]) {
        let x0 = x.max(0);
        let y0 = y.max(0);
        let x1 = (x + w as i64).min(self.width as i64);
        let y1 = (y + h as i64).min(self.height as i64);
        for yy in y0..y1 {
            let row = yy as usize * self.width as usize;
            for xx in x0..x1 {
                self.pixels[row + xx as usize] = colour;
            }
        }
    }

    /// Copies `src` into this image with its top-left corner at (`x`, `y`), clipped.
    pub fn blit(&mut self, src: &Image, x: i64, y: i64) {
        for sy in 0..src.height as i64 {
            let ty = y + sy;
            if ty < 0 || ty >= self.height as i64 {
                continue;
            }
            for sx in 0..src.width as i64 {
                let tx = x + sx;
                if tx < 0 || tx >= self.width as i64 {
                    continue;
                }
                self.pixels[ty as usize * self.width as usize + tx as usize] =
                    src.pixels[sy as usize * src.width as usize + sx as usize];
            }
        }
    }

    /// Width in pixels of `text` drawn with [`Image::draw_text`] at `scale`
    /// (the widest line for multi-line text; no trailing spacing column).
    pub fn text_width(text: &str, scale: u32) -> u32 {
        let widest = text.lines().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
        (widest * CELL_W).saturating_sub(1) * scale.max(1)
    }

    /// Height in pixels of one line of text at `scale`, descenders included.
    pub fn text_height(scale: u32) -> u32 {
        (CELL_H - 1) * scale.max(1)
    }

    /// Height in pixels of capitals and digits at `scale` (the visual size of a label).
    pub fn cap_height(scale: u32) -> u32 {
        CAP_H * scale.max(1)
    }

    /// Draws `text` with the built-in 5×8 bitmap font, top-left corner of the
    /// first glyph cell at (`x`, `y`), each font pixel a `scale` × `scale`
    /// block (`scale` 0 is treated as 1). `\n` starts a new line; characters
    /// outside printable ASCII are drawn as `?`. Clipped to the image.
    pub fn draw_text(&mut self, x: i64, y: i64, text: &str, colour: [u8; 4], scale: u32) {
        let s = scale.max(1) as i64;
        for (line_no, line) in text.lines().enumerate() {
            let gy = y + line_no as i64 * CELL_H as i64 * s;
            for (i, c) in line.chars().enumerate() {
                let gx = x + i as i64 * CELL_W as i64 * s;
                for (col, bits) in glyph(c).iter().enumerate() {
                    for row in 0..8 {
                        if bits & (1 << row) != 0 {
                            self.fill_rect(
                                gx + col as i64 * s,
                                gy + row as i64 * s,
                                s as u32,
                                s as u32,
                                colour,
                            );
                        }
                    }
                }
            }
        }
    }

    /// The image as PNG bytes (8-bit RGBA). Deterministic: equal images give equal bytes.
    pub fn encode_png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        // Writing into a Vec cannot fail for a consistent image; a size
        // mismatch between `pixels` and `width * height` is repaired by padding
        // or truncating so that this function never panics.
        let n = self.width as usize * self.height as usize;
        let mut data: Vec<u8> = Vec::with_capacity(n * 4);
        for p in self.pixels.iter().take(n) {
            data.extend_from_slice(p);
        }
        data.resize(n * 4, 0);
        let mut encoder = png::Encoder::new(&mut out, self.width.max(1), self.height.max(1));
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        if n == 0 {
            data = vec![0; 4 * self.width.max(1) as usize * self.height.max(1) as usize];
        }
        if let Ok(mut writer) = encoder.write_header() {
            let _ = writer.write_image_data(&data);
            let _ = writer.finish();
        }
        out
    }

    /// Decodes PNG bytes (any colour type and bit depth the `png` crate
    /// reads; converted to 8-bit RGBA).
    pub fn decode_png(bytes: &[u8]) -> Result<Image, RenderError> {
        let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder
            .read_info()
            .map_err(|e| RenderError::Png(e.to_string()))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| RenderError::Png("image too large".into()))?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| RenderError::Png(e.to_string()))?;
        let (w, h) = (info.width, info.height);
        let channels = info.color_type.samples();
        let mut pixels = Vec::with_capacity(w as usize * h as usize);
        for y in 0..h as usize {
            let row = &buf[y * info.line_size..];
            for x in 0..w as usize {
                let p = &row[x * channels..(x + 1) * channels];
                pixels.push(match channels {
                    1 => [p[0], p[0], p[0], 255],
                    2 => [p[0], p[0], p[0], p[1]],
                    3 => [p[0], p[1], p[2], 255],
                    _ => [p[0], p[1], p[2], p[3]],
                });
            }
        }
        Ok(Image {
            width: w,
            height: h,
            pixels,
        })
    }

    /// Writes the image as a PNG file atomically: the bytes go to a temporary
    /// file in the same directory, which is then renamed over `path`, so a
    /// failure never leaves a half-written file.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        write_atomic(path.as_ref(), &self.encode_png())
    }
}

/// Writes `bytes` to `path` through [`crate::io::atomic_write`] (temporary
/// file in the same directory, then a rename; special files refused).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    crate::io::atomic_write(path, |w| w.write_all(bytes)).map_err(|e| match e {
        crate::io::IoError::Io { path, source } => RenderError::Io { path, source },
        other => RenderError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(other.to_string()),
        },
    })
}

/// Places `images` next to each other, left to right on a white background,
/// with `labels[i]` centred above panel `i` (missing labels are left blank).
/// Panels of different heights are aligned at the top. The text scale follows
/// the panel size so labels stay readable on large renders.
pub fn side_by_side(images: &[Image], labels: &[&str]) -> Image {
    let bg = [255, 255, 255, 255];
    if images.is_empty() {
        return Image::new(1, 1, bg);
    }
    let max_h = images.iter().map(|i| i.height).max().unwrap_or(1);
    let scale = (max_h / 300).clamp(1, 6);
    let gap = 6 * scale;
    let label_h = if labels.iter().any(|l| !l.is_empty()) {
        Image::text_height(scale) + 2 * gap
    } else {
        gap
    };
    let total_w = images.iter().map(|i| i.width).sum::<u32>() + gap * (images.len() as u32 + 1);
    let total_h = max_h + label_h + gap;
    let mut out = Image::new(total_w, total_h, bg);
    let mut x = gap as i64;
    for (i, img) in images.iter().enumerate() {
        if let Some(label) = labels.get(i) {
            let tw = Image::text_width(label, scale) as i64;
            let tx = x + (img.width as i64 - tw) / 2;
            out.draw_text(tx.max(x), gap as i64, label, [20, 20, 20, 255], scale);
        }
        out.blit(img, x, label_h as i64);
        x += (img.width + gap) as i64;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_size_and_pixels() {
        let mut img = Image::new(7, 5, [10, 20, 30, 255]);
        img.set(3, 2, [200, 100, 50, 255]);
        let back = Image::decode_png(&img.encode_png()).unwrap();
        assert_eq!(back, img);
    }

    #[test]
    fn srgb_conversion_endpoints() {
        assert_eq!(linear_to_srgb8([0.0, 1.0, 0.5]), [0, 255, 188, 255]);
        assert_eq!(encode_srgb(f32::NAN), 0);
        assert!((decode_srgb(188.0 / 255.0) - 0.5).abs() < 0.003);
    }

    #[test]
    fn text_draws_inside_its_box() {
        let mut img = Image::new(100, 30, [0, 0, 0, 255]);
        img.draw_text(2, 3, "1.5e-3", [255, 255, 255, 255], 2);
        let w = Image::text_width("1.5e-3", 2) as i64;
        let mut count = 0;
        for y in 0..30 {
            for x in 0..100 {
                if img.get(x, y).unwrap()[0] == 255 {
                    count += 1;
                    assert!((2..2 + w).contains(&(x as i64)));
                    assert!((3..3 + Image::text_height(2) as i64).contains(&(y as i64)));
                }
            }
        }
        assert!(count > 50);
    }

    #[test]
    fn side_by_side_size() {
        let a = Image::new(40, 30, [0, 0, 0, 255]);
        let b = Image::new(50, 20, [0, 0, 0, 255]);
        let s = side_by_side(&[a, b], &["before", "after"]);
        assert!(s.width >= 90 && s.height > 30);
    }
}
