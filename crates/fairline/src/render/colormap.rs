//! Colour maps for scalar fields (curvature, deviation) and the colour-bar legend.

use super::image::{Image, decode_srgb, linear_to_srgb8};

/// Linear-light colour given to NaN / infinite scalar values (a neutral grey).
pub const NAN_COLOR: [f32; 3] = [0.25, 0.25, 0.25];

/// A colour map from `t ∈ [0, 1]` to a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Colormap {
    /// Perceptually uniform sequential map, dark violet → green → yellow
    /// (matplotlib's viridis, polynomial fit).
    Viridis,
    /// Moreland's diverging blue → light grey → red map, for signed values
    /// such as mean or Gaussian curvature (0 maps to the grey midpoint).
    Coolwarm,
    /// Google's Turbo rainbow map (polynomial fit): high contrast for
    /// spotting small variations, not perceptually uniform.
    Turbo,
    /// Black → white.
    Greys,
}

/// Moreland's cool-warm map sampled at 33 points (sRGB, 0–255).
#[rustfmt::skip]
const COOLWARM: [[u8; 3]; 33] = [
    [59, 76, 192], [68, 90, 204], [77, 104, 215], [87, 117, 225], [98, 130, 234],
    [108, 142, 241], [119, 154, 247], [130, 165, 251], [141, 176, 254], [152, 185, 255],
    [163, 194, 255], [174, 201, 253], [184, 208, 249], [194, 213, 244], [204, 217, 238],
    [213, 219, 230], [221, 221, 221], [229, 216, 209], [236, 211, 197], [241, 204, 185],
    [245, 196, 173], [247, 187, 160], [247, 177, 148], [247, 166, 135], [244, 154, 123],
    [241, 141, 111], [236, 127, 99], [229, 112, 88], [222, 96, 77], [213, 80, 66],
    [203, 62, 56], [192, 40, 47], [180, 4, 38],
];

impl Colormap {
    /// The colour of `t` as linear-light RGB in 0..1 (`t` is clamped to
    /// [0, 1]; NaN gives [`NAN_COLOR`]). The maps are defined in sRGB and
    /// converted here, so after the renderer's sRGB encoding the image shows
    /// the published colours.
    pub fn map(self, t: f64) -> [f32; 3] {
        if t.is_nan() {
            return NAN_COLOR;
        }
        let t = t.clamp(0.0, 1.0);
        let srgb = match self {
            Colormap::Viridis => viridis(t),
            Colormap::Coolwarm => coolwarm(t),
            Colormap::Turbo => turbo(t),
            Colormap::Greys => [t; 3],
        };
        srgb.map(|c| decode_srgb(c.clamp(0.0, 1.0) as f32))
    }

    /// Whether the map is diverging (meant for values symmetric about 0).
    pub fn is_diverging(self) -> bool {
        matches!(self, Colormap::Coolwarm)
    }
}

fn viridis(t: f64) -> [f64; 3] {
    // Polynomial fit by Matt Zucker (CC0), max error below 1/255.
    const C: [[f64; 3]; 7] = [
        [
            0.277_727_327_223_417_7,
            0.005_407_344_544_966_578,
            0.334_099_805_335_306_1,
        ],
        [
            0.105_093_043_108_577_4,
            1.404_613_529_898_575,
            1.384_590_162_594_685,
        ],
        [
            -0.330_861_828_725_556_3,
            0.214_847_559_468_213,
            0.095_095_163_028_236_59,
        ],
        [
            -4.634_230_498_983_486,
            -5.799_100_973_351_585,
            -19.332_440_956_279_87,
        ],
        [
            6.228_269_936_347_081,
            14.179_933_366_805_09,
            56.690_552_600_681_05,
        ],
        [
            4.776_384_997_670_288,
            -13.745_145_377_746_01,
            -65.353_032_633_372_34,
        ],
        [
            -5.435_455_855_934_631,
            4.645_852_612_178_535,
            26.312_435_249_583_2,
        ],
    ];
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut v = C[6][k];
        for i in (0..6).rev() {
            v = C[i][k] + t * v;
        }
        *o = v;
    }
    out
}

fn turbo(t: f64) -> [f64; 3] {
    // Polynomial approximation by Google (Apache-2.0), Mikhailov 2019.
    let (t2, t3, t4, t5) = (t * t, t * t * t, t * t * t * t, t * t * t * t * t);
    let r = 0.135_721_38 + 4.615_392_60 * t - 42.660_322_58 * t2 + 132.131_082_34 * t3
        - 152.942_393_96 * t4
        + 59.286_379_43 * t5;
    let g = 0.091_402_61 + 2.194_188_39 * t + 4.842_966_58 * t2 - 14.185_033_33 * t3
        + 4.277_298_57 * t4
        + 2.829_566_04 * t5;
    let b = 0.106_673_30 + 12.641_946_08 * t - 60.582_048_36 * t2 + 110.362_767_71 * t3
        - 89.903_109_12 * t4
        + 27.348_249_73 * t5;
    [r, g, b]
}

fn coolwarm(t: f64) -> [f64; 3] {
    let x = t * (COOLWARM.len() - 1) as f64;
    let i = (x.floor() as usize).min(COOLWARM.len() - 2);
    let f = x - i as f64;
    let (a, b) = (COOLWARM[i], COOLWARM[i + 1]);
    [0, 1, 2].map(|k| (a[k] as f64 * (1.0 - f) + b[k] as f64 * f) / 255.0)
}

/// The colour range of a scalar picture, the one rule of every picture
/// and of the workbench: for a `signed` quantity (mean or Gaussian
/// curvature, signed deviation) `(-m, m)` with `m` the 98th percentile of
/// the finite non-zero |values| (exact zeros, such as the vertices a fairing
/// left in place or the flat faces of a CAD part, carry no magnitude), so 0 is the neutral colour of a diverging map;
/// otherwise the 2nd to 98th percentile of the finite values. Either way a
/// few extreme values do not wash the map out; the values beyond are drawn
/// in the end colours (clipped). An empty field gets (−1, 1) or (0, 1); a
/// constant one a small non-empty range around its value.
pub fn scalar_range(values: &[f64], signed: bool) -> (f64, f64) {
    let (lo, hi) = auto_range(values, signed);
    widen_if_empty(lo, hi)
}

/// Colours for per-vertex scalar `values` (e.g. curvature) under `cmap`.
///
/// With `range = None` the range is [`scalar_range`] of the values, signed
/// for a diverging map. A given range is used as is (if `lo > hi` it is
/// swapped; a non-finite range falls back to the automatic one). NaN and
/// infinite values are drawn in [`NAN_COLOR`].
///
/// Returns the linear-light colours (one per value) and the range used,
/// which is what a [`Legend`] should show.
pub fn scalar_colors(
    values: &[f64],
    cmap: Colormap,
    range: Option<(f64, f64)>,
) -> (Vec<[f32; 3]>, (f64, f64)) {
    let (lo, hi) = match range {
        Some((a, b)) if a.is_finite() && b.is_finite() => (a.min(b), a.max(b)),
        _ => auto_range(values, cmap.is_diverging()),
    };
    let (lo, hi) = widen_if_empty(lo, hi);
    let inv = 1.0 / (hi - lo);
    let colors = values
        .iter()
        .map(|&v| {
            if v.is_finite() {
                cmap.map((v - lo) * inv)
            } else {
                NAN_COLOR
            }
        })
        .collect();
    (colors, (lo, hi))
}

/// Whether some finite value of `values` lies outside `range` (the picture
/// shows it in an end colour: its legend says so).
pub fn clipped(values: &[f64], range: (f64, f64)) -> bool {
    values
        .iter()
        .any(|v| v.is_finite() && (*v < range.0 || *v > range.1))
}

fn auto_range(values: &[f64], symmetric: bool) -> (f64, f64) {
    let mut finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return if symmetric { (-1.0, 1.0) } else { (0.0, 1.0) };
    }
    let n = finite.len();
    let rank = |q: f64| ((q * (n - 1) as f64).round() as usize).min(n - 1);
    if symmetric {
        let mut mag: Vec<f64> = finite
            .iter()
            .map(|v| v.abs())
            .filter(|&a| a > 0.0)
            .collect();
        if mag.is_empty() {
            return (-1.0, 1.0);
        }
        let k = ((0.98 * (mag.len() - 1) as f64).round() as usize).min(mag.len() - 1);
        let m = *mag.select_nth_unstable_by(k, f64::total_cmp).1;
        return (-m, m);
    }
    let (i_lo, i_hi) = (rank(0.02), rank(0.98));
    let hi = *finite.select_nth_unstable_by(i_hi, f64::total_cmp).1;
    let lo = *finite[..=i_hi]
        .select_nth_unstable_by(i_lo, f64::total_cmp)
        .1;
    (lo, hi)
}

fn widen_if_empty(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo && (hi - lo) > 1e-12 * lo.abs().max(hi.abs()) {
        return (lo, hi);
    }
    let mid = 0.5 * (lo + hi);
    let half = (mid.abs() * 1e-3).max(1e-12);
    (mid - half, mid + half)
}

/// A colour bar drawn in a corner of the picture: the map from `min`
/// (bottom) to `max` (top), tick labels at min, middle and max, and `title` above.
#[derive(Clone, Debug, PartialEq)]
pub struct Legend {
    /// Text above the bar, e.g. `"mean curvature (1/mm)"`.
    pub title: String,
    /// The colour map of the field.
    pub colormap: Colormap,
    /// Value at the bottom of the bar.
    pub min: f64,
    /// Value at the top of the bar.
    pub max: f64,
    /// Whether values beyond `min`..`max` exist and are drawn in the end
    /// colours: the bar then ends in arrowheads and says "beyond: clipped".
    pub clipped: bool,
}

impl Legend {
    /// Number of pixels the bar is wide at text `scale`.
    fn bar_width(scale: u32) -> u32 {
        8 * scale + 6
    }

    fn labels(&self) -> [String; 3] {
        [
            format_tick(self.max),
            format_tick(0.5 * (self.min + self.max)),
            format_tick(self.min),
        ]
    }

    /// Width in pixels the legend needs at text `scale`, margins included.
    pub(crate) fn width(&self, scale: u32) -> u32 {
        let pad = 4 * scale;
        let label_w = self
            .labels()
            .iter()
            .map(|l| Image::text_width(l, scale))
            .max()
            .unwrap_or(0);
        let body = Self::bar_width(scale) + 3 * scale + label_w;
        let note = if self.clipped {
            Image::text_width(CLIPPED_NOTE, scale)
        } else {
            0
        };
        body.max(Image::text_width(&self.title, scale)).max(note) + 2 * pad
    }

    /// Draws the legend into `img` inside the box `x, y, w, h` (bar vertically
    /// centred, at most 60% of the image height), text in `text_colour`.
    pub(crate) fn draw(
        &self,
        img: &mut Image,
        x: i64,
        y: i64,
        h: u32,
        scale: u32,
        text_colour: [u8; 4],
    ) {
        let pad = (4 * scale) as i64;
        let text_h = Image::text_height(scale) as i64;
        let cap = Image::cap_height(scale) as i64;
        // Gap between title and bar leaves room for the top tick label.
        let gap = pad + cap;
        let bar_w = Self::bar_width(scale) as i64;
        // arrowheads beyond the bar's ends and the note below: clipped values
        let (tip, note_h) = if self.clipped {
            (bar_w / 2 + 1, text_h + pad)
        } else {
            (0, 0)
        };
        let avail = h as i64 - 2 * pad - text_h - gap - cap - 2 * tip - note_h;
        let bar_h = (avail.min((img.height as f64 * 0.6) as i64)).max(8);
        let top = y + (h as i64 - bar_h - text_h - gap - note_h) / 2 + text_h + gap;
        let bar_x = x + pad;
        img.draw_text(bar_x, top - text_h - gap, &self.title, text_colour, scale);
        if self.clipped {
            let (hi_c, lo_c) = (
                linear_to_srgb8(self.colormap.map(1.0)),
                linear_to_srgb8(self.colormap.map(0.0)),
            );
            for r in 0..tip {
                let inset = (bar_w * (tip - r) / tip.max(1)) / 2;
                let w = (bar_w - 2 * inset).max(1) as u32;
                img.fill_rect(bar_x + inset, top - 1 - tip + r, w, 1, hi_c);
                img.fill_rect(bar_x + inset, top + bar_h + tip - r, w, 1, lo_c);
            }
            img.draw_text(
                bar_x,
                top + bar_h + tip + pad,
                CLIPPED_NOTE,
                text_colour,
                scale,
            );
        }
        for r in 0..bar_h {
            let t = 1.0 - r as f64 / (bar_h - 1).max(1) as f64;
            let c = linear_to_srgb8(self.colormap.map(t));
            img.fill_rect(bar_x, top + r, bar_w as u32, 1, c);
        }
        // Frame.
        let frame = [60, 60, 60, 255];
        img.fill_rect(bar_x - 1, top - 1, bar_w as u32 + 2, 1, frame);
        img.fill_rect(bar_x - 1, top + bar_h, bar_w as u32 + 2, 1, frame);
        img.fill_rect(bar_x - 1, top - 1, 1, bar_h as u32 + 2, frame);
        img.fill_rect(bar_x + bar_w, top - 1, 1, bar_h as u32 + 2, frame);
        for (i, label) in self.labels().iter().enumerate() {
            let ty = top + (bar_h - 1) * i as i64 / 2;
            img.fill_rect(bar_x + bar_w, ty, 2 * scale, scale.max(1), frame);
            img.draw_text(
                bar_x + bar_w + 3 * scale as i64,
                ty - cap / 2,
                label,
                text_colour,
                scale,
            );
        }
    }
}

/// The legend's note when values lie beyond its range.
const CLIPPED_NOTE: &str = "values beyond: clipped";

/// A short tick label: up to 4 significant digits, scientific notation for
/// very small or large magnitudes (`1.25e-3`), `0` for zero.
pub(crate) fn format_tick(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 || v.abs() < 1e-300 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-2..1e4).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 5) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srgb(c: [f32; 3]) -> [u8; 3] {
        let p = linear_to_srgb8(c);
        [p[0], p[1], p[2]]
    }

    fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
        (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= tol)
    }

    #[test]
    fn colormap_endpoints() {
        assert!(close(srgb(Colormap::Viridis.map(0.0)), [68, 1, 84], 4));
        assert!(close(srgb(Colormap::Viridis.map(1.0)), [253, 231, 37], 4));
        assert!(close(srgb(Colormap::Coolwarm.map(0.0)), [59, 76, 192], 1));
        assert!(close(srgb(Colormap::Coolwarm.map(0.5)), [221, 221, 221], 1));
        assert!(close(srgb(Colormap::Coolwarm.map(1.0)), [180, 4, 38], 1));
        // The polynomial Turbo is a fit: dark at 0, dark red at 1, bright green-yellow mid.
        let t0 = srgb(Colormap::Turbo.map(0.0));
        assert!(t0.iter().all(|&c| c < 60), "{t0:?}");
        let t1 = srgb(Colormap::Turbo.map(1.0));
        assert!(t1[0] > 100 && t1[1] < 40 && t1[2] < 40, "{t1:?}");
        let tm = srgb(Colormap::Turbo.map(0.5));
        assert!(tm[1] > 200 && tm[2] < 120, "{tm:?}");
        // Clamping and NaN.
        assert_eq!(Colormap::Viridis.map(-3.0), Colormap::Viridis.map(0.0));
        assert_eq!(Colormap::Viridis.map(7.0), Colormap::Viridis.map(1.0));
        assert_eq!(Colormap::Turbo.map(f64::NAN), NAN_COLOR);
    }

    #[test]
    fn scalar_colors_robust_range() {
        let mut v: Vec<f64> = (0..=100).map(|i| i as f64).collect();
        v.push(1e9); // outlier
        v.push(f64::NAN);
        let (c, (lo, hi)) = scalar_colors(&v, Colormap::Viridis, None);
        assert_eq!(c.len(), v.len());
        assert!((1.0..=3.0).contains(&lo), "{lo}");
        assert!((97.0..=100.0).contains(&hi), "{hi}");
        assert_eq!(c[102], NAN_COLOR);
        assert_eq!(c[101], Colormap::Viridis.map(1.0));

        let signed: Vec<f64> = (0..100).map(|i| i as f64 * 0.01 - 0.2).collect();
        let (c, (lo, hi)) = scalar_colors(&signed, Colormap::Coolwarm, None);
        assert_eq!(lo, -hi);
        assert!(hi > 0.7 && hi < 0.8);
        // value 0 maps to the neutral middle
        assert_eq!(c[20], Colormap::Coolwarm.map(0.5));

        let (_, r) = scalar_colors(&[2.0, 2.0], Colormap::Viridis, None);
        assert!(r.0 < 2.0 && r.1 > 2.0);
        let (_, r) = scalar_colors(&[], Colormap::Viridis, Some((5.0, 1.0)));
        assert_eq!(r, (1.0, 5.0));
    }

    #[test]
    fn signed_range_is_symmetric_and_ignores_exact_zeros() {
        // a fairing moved 100 of 1100 vertices: the zeros do not shrink the range
        let mut v = vec![0.0; 1000];
        v.extend((1..=100).map(|i| -f64::from(i) * 0.01));
        let (lo, hi) = scalar_range(&v, true);
        assert_eq!(lo, -hi);
        assert!(hi > 0.95 && hi <= 1.0, "{hi}");
        // one outlier beyond the 98th percentile is clipped, not the range
        v.push(50.0);
        let (_, hi) = scalar_range(&v, true);
        assert!(hi < 1.01, "{hi}");
        assert!(clipped(&v, (-hi, hi)));
        assert!(!clipped(&[0.5, f64::NAN], (-hi, hi)));
        assert_eq!(scalar_range(&[0.0, 0.0], true), (-1.0, 1.0));
        let (lo, hi) = scalar_range(&[1.0, 2.0, 3.0], false);
        assert!(lo >= 1.0 && hi <= 3.0 && lo < hi);
    }

    #[test]
    fn tick_format() {
        assert_eq!(format_tick(0.0), "0");
        assert_eq!(format_tick(1.5), "1.5");
        assert_eq!(format_tick(-0.25), "-0.25");
        assert_eq!(format_tick(0.001234), "1.23e-3");
        assert_eq!(format_tick(123.456), "123.5");
        assert_eq!(format_tick(25000.0), "2.50e4");
    }
}
