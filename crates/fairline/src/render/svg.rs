//! A small SVG writer for 2D plots, e.g. highlight-line pre-images in the
//! (u, v) parameter domain of a B-spline surface.
//!
//! Data coordinates are mapped linearly into a plotting area inside the
//! image (y up); colours are sRGB bytes, as in [`super::Image`].

use std::fmt::{self, Write as _};
use std::path::Path;

use super::RenderError;
use super::image::write_atomic;

/// An SVG plot under construction.
#[derive(Clone, Debug, PartialEq)]
pub struct SvgPlot {
    width: f64,
    height: f64,
    x_range: (f64, f64),
    y_range: (f64, f64),
    margin: f64,
    title: Option<String>,
    body: String,
    legend: Vec<([u8; 3], String)>,
}

/// Most entries a legend shows (the rest are summarised in one line).
pub const MAX_LEGEND_ENTRIES: usize = 24;

fn clean_range(r: (f64, f64)) -> (f64, f64) {
    let (a, b) = r;
    if !(a.is_finite() && b.is_finite()) {
        return (0.0, 1.0);
    }
    let (lo, hi) = (a.min(b), a.max(b));
    if hi - lo > 1e-300 {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    }
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Tick positions at "nice" steps (1, 2, 5 × 10^k) covering `lo..hi`, about `n` of them.
fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span > 0.0 && span.is_finite()) {
        return vec![lo];
    }
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

impl SvgPlot {
    /// A plot of `width` × `height` pixels showing data `x_range` × `y_range`
    /// (each `(min, max)`; empty or non-finite ranges are widened/replaced).
    pub fn new(width: u32, height: u32, x_range: (f64, f64), y_range: (f64, f64)) -> SvgPlot {
        SvgPlot {
            width: width.max(1) as f64,
            height: height.max(1) as f64,
            x_range: clean_range(x_range),
            y_range: clean_range(y_range),
            margin: 48.0_f64.min(0.2 * width.min(height) as f64),
            title: None,
            body: String::new(),
            legend: Vec::new(),
        }
    }

    /// Image coordinates of the data point `p`.
    fn map(&self, p: [f64; 2]) -> (f64, f64) {
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let m = self.margin;
        let x = m + (p[0] - x0) / (x1 - x0) * (self.width - 2.0 * m);
        let y = self.height - m - (p[1] - y0) / (y1 - y0) * (self.height - 2.0 * m);
        (x, y)
    }

    /// Sets a title drawn above the plot.
    pub fn title(&mut self, title: &str) -> &mut Self {
        self.title = Some(title.to_string());
        self
    }

    /// Adds a polyline through `points` (data coordinates) in `colour` (sRGB),
    /// `width` pixels wide. Non-finite points split the line.
    pub fn polyline(&mut self, points: &[[f64; 2]], colour: [u8; 3], width: f64) -> &mut Self {
        let width = if width.is_finite() && width > 0.0 {
            width
        } else {
            1.0
        };
        for run in points.split(|p| !(p[0].is_finite() && p[1].is_finite())) {
            if run.len() < 2 {
                continue;
            }
            let mut pts = String::new();
            for &p in run {
                let (x, y) = self.map(p);
                let _ = write!(pts, "{x:.2},{y:.2} ");
            }
            let _ = writeln!(
                self.body,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="{width}" stroke-linejoin="round" stroke-linecap="round"/>"#,
                pts.trim_end(),
                hex(colour)
            );
        }
        self
    }

    /// Adds a round marker at `point` with an optional text `label` beside it.
    pub fn marker(&mut self, point: [f64; 2], colour: [u8; 3], label: &str) -> &mut Self {
        if !(point[0].is_finite() && point[1].is_finite()) {
            return self;
        }
        let (x, y) = self.map(point);
        let _ = writeln!(
            self.body,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="3.5" fill="{}" stroke="black" stroke-width="0.5"/>"#,
            hex(colour)
        );
        if !label.is_empty() {
            let _ = writeln!(
                self.body,
                r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="11">{}</text>"#,
                x + 5.0,
                y - 5.0,
                escape(label)
            );
        }
        self
    }

    /// Adds `text` (small, in `colour`) beside the data point `point`, e.g.
    /// the id of the line through it.
    pub fn text(&mut self, point: [f64; 2], colour: [u8; 3], text: &str) -> &mut Self {
        if !(point[0].is_finite() && point[1].is_finite()) || text.is_empty() {
            return self;
        }
        let (x, y) = self.map(point);
        let _ = writeln!(
            self.body,
            r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="10" fill="{}" stroke="white" stroke-width="2.5" paint-order="stroke">{}</text>"#,
            x + 3.0,
            y - 3.0,
            hex(colour),
            escape(text)
        );
        self
    }

    /// Adds a region label centred on the data point `point`: dark text on
    /// a light box, as the patch indices of the PNG pictures
    /// ([`super::RegionLabels`]), e.g. the index of the patch whose domain
    /// the plot shows.
    pub fn label(&mut self, point: [f64; 2], text: &str) -> &mut Self {
        if !(point[0].is_finite() && point[1].is_finite()) || text.is_empty() {
            return self;
        }
        let (x, y) = self.map(point);
        let (size, pad) = (16.0, 4.0);
        let (w, h) = (
            0.62 * size * text.chars().count() as f64 + 2.0 * pad,
            size + 2.0 * pad,
        );
        let _ = writeln!(
            self.body,
            r##"<g class="region-label"><rect x="{:.2}" y="{:.2}" width="{w:.2}" height="{h:.2}" fill="white" fill-opacity="0.7"/><text x="{x:.2}" y="{:.2}" font-family="sans-serif" font-size="{size}" fill="#0f0f14" text-anchor="middle">{}</text></g>"##,
            x - 0.5 * w,
            y - 0.5 * h,
            y + 0.35 * size,
            escape(text)
        );
        self
    }

    /// Sets the legend: one row per entry (a colour swatch and its text),
    /// drawn over the top-right corner of the plot on a white box; at most
    /// [`MAX_LEGEND_ENTRIES`] rows, the rest counted in a last row.
    pub fn legend(&mut self, entries: &[([u8; 3], String)]) -> &mut Self {
        self.legend = entries.to_vec();
        self
    }

    /// The legend as SVG elements.
    fn legend_svg(&self) -> String {
        let mut rows: Vec<(Option<[u8; 3]>, String)> = self
            .legend
            .iter()
            .take(MAX_LEGEND_ENTRIES)
            .map(|(c, t)| (Some(*c), t.clone()))
            .collect();
        if self.legend.len() > MAX_LEGEND_ENTRIES {
            rows.push((
                None,
                format!("... {} more", self.legend.len() - MAX_LEGEND_ENTRIES),
            ));
        }
        if rows.is_empty() {
            return String::new();
        }
        let row_h = 14.0;
        let longest = rows.iter().map(|r| r.1.chars().count()).max().unwrap_or(0) as f64;
        let (w, h) = (26.0 + 6.5 * longest, 6.0 + row_h * rows.len() as f64);
        let x0 = self.width - self.margin - w - 4.0;
        let y0 = self.margin + 4.0;
        let mut s = String::new();
        let _ = writeln!(
            s,
            r##"<g class="legend"><rect x="{x0:.2}" y="{y0:.2}" width="{w:.2}" height="{h:.2}" fill="white" fill-opacity="0.85" stroke="#888" stroke-width="0.5"/>"##
        );
        for (k, (colour, text)) in rows.iter().enumerate() {
            let y = y0 + 4.0 + row_h * (k as f64 + 0.5);
            if let Some(c) = colour {
                let _ = writeln!(
                    s,
                    r#"<line x1="{:.2}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}" stroke="{}" stroke-width="2.5"/>"#,
                    x0 + 5.0,
                    x0 + 19.0,
                    hex(*c)
                );
            }
            let _ = writeln!(
                s,
                r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="11">{}</text>"#,
                x0 + 23.0,
                y + 4.0,
                escape(text)
            );
        }
        s.push_str("</g>\n");
        s
    }

    /// Draws the plot frame, ticks with values at "nice" steps, and the axis labels.
    pub fn axes(&mut self, x_label: &str, y_label: &str) -> &mut Self {
        let m = self.margin;
        let (w, h) = (self.width, self.height);
        let mut s = String::new();
        let _ = writeln!(
            s,
            r##"<rect x="{m}" y="{m}" width="{}" height="{}" fill="none" stroke="#333" stroke-width="1"/>"##,
            w - 2.0 * m,
            h - 2.0 * m
        );
        for t in nice_ticks(self.x_range.0, self.x_range.1, 6) {
            let (x, _) = self.map([t, self.y_range.0]);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.2}" y1="{:.2}" x2="{x:.2}" y2="{:.2}" stroke="#333"/><text x="{x:.2}" y="{:.2}" font-family="sans-serif" font-size="10" text-anchor="middle">{}</text>"##,
                h - m,
                h - m + 4.0,
                h - m + 15.0,
                fmt_tick(t)
            );
        }
        for t in nice_ticks(self.y_range.0, self.y_range.1, 6) {
            let (_, y) = self.map([self.x_range.0, t]);
            let _ = writeln!(
                s,
                r##"<line x1="{:.2}" y1="{y:.2}" x2="{m}" y2="{y:.2}" stroke="#333"/><text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="10" text-anchor="end">{}</text>"##,
                m - 4.0,
                m - 6.0,
                y + 3.5,
                fmt_tick(t)
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="12" text-anchor="middle">{}</text>"#,
            w / 2.0,
            h - m / 4.0,
            escape(x_label)
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="12" text-anchor="middle" transform="rotate(-90 {:.2} {:.2})">{}</text>"#,
            m / 4.0 + 6.0,
            h / 2.0,
            m / 4.0 + 6.0,
            h / 2.0,
            escape(y_label)
        );
        // Axes go under the data.
        self.body.insert_str(0, &s);
        self
    }

    /// Writes the SVG document atomically (temporary file + rename).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        write_atomic(path.as_ref(), self.to_string().as_bytes())
    }
}

fn fmt_tick(v: f64) -> String {
    super::colormap::format_tick(if v.abs() < 1e-12 { 0.0 } else { v })
}

impl fmt::Display for SvgPlot {
    /// The complete SVG document.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#,
            w = self.width,
            h = self.height
        )?;
        writeln!(f, r#"<rect width="100%" height="100%" fill="white"/>"#)?;
        if let Some(t) = &self.title {
            writeln!(
                f,
                r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="14" text-anchor="middle">{}</text>"#,
                self.width / 2.0,
                (self.margin * 0.6).max(12.0),
                escape(t)
            )?;
        }
        f.write_str(&self.body)?;
        f.write_str(&self.legend_svg())?;
        writeln!(f, "</svg>")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_contains_elements_and_maps_y_up() {
        let mut plot = SvgPlot::new(400, 300, (0.0, 1.0), (0.0, 1.0));
        plot.axes("u", "v <&>")
            .polyline(
                &[[0.0, 0.0], [1.0, 1.0], [f64::NAN, 0.0], [0.2, 0.2]],
                [255, 0, 0],
                1.5,
            )
            .marker([0.5, 0.5], [0, 0, 255], "P1")
            .title("pre-images");
        let s = plot.to_string();
        assert!(s.starts_with("<svg"));
        assert!(s.trim_end().ends_with("</svg>"));
        assert_eq!(s.matches("<polyline").count(), 1);
        assert!(s.contains("#ff0000") && s.contains("P1") && s.contains("v &lt;&amp;&gt;"));
        let (_, y_low) = plot.map([0.0, 0.0]);
        let (_, y_high) = plot.map([0.0, 1.0]);
        assert!(y_high < y_low);
    }

    #[test]
    fn svg_write_is_atomic_and_readable() {
        let dir = std::env::temp_dir().join(format!("fairline-svg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("plot.svg");
        let plot = SvgPlot::new(100, 100, (0.0, 0.0), (f64::NAN, 1.0));
        plot.write(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, plot.to_string());
        let leftovers = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(leftovers, 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ticks_are_nice() {
        let t = nice_ticks(0.0, 1.0, 5);
        assert_eq!(t.len(), 6);
        assert!(
            t.iter()
                .enumerate()
                .all(|(i, v)| (v - 0.2 * i as f64).abs() < 1e-12)
        );
    }
}
