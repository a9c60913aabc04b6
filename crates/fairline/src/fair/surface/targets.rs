//! Target curves: the stretches between the user's endpoints snapped to the
//! pre-images, the cubic Hermite curves that replace them and their samples
//! (Nishiyama et al. §3.2–3.3), and the endpoint pairs around a disc.

use super::options::check_options;
use super::{EndpointPair, SurfaceFairError, SurfaceFairOptions};
use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::curves::CubicHermite;
use crate::highlight::CircularLight;
use crate::highlight::surface::{
    SurfaceHighlightLine, SurfaceHighlightOptions, SurfaceLight, contour_field, distance_field,
};
use rayon::prelude::*;
use serde::Serialize;

/// The smooth target of one stretch (Nishiyama et al. §3.2–3.3). In the
/// JSON report: radius, endpoints, tangents and the number of samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetCurve {
    /// Position of the stretch in the endpoints list.
    #[serde(skip)]
    pub index: usize,
    /// Position of its light in [`SurfaceFairOptions::lights`].
    #[serde(skip)]
    pub light: usize,
    /// Radius of that light.
    pub radius: f64,
    /// Endpoint e¹ snapped onto the pre-image.
    pub start: [f64; 2],
    /// Endpoint e² snapped onto the pre-image.
    pub end: [f64; 2],
    /// Tangent t¹ of Eq. (3.1) (direction from the Bézier fit, length Eq. (3.3)).
    pub tangent_start: [f64; 2],
    /// Tangent t² of Eq. (3.1).
    pub tangent_end: [f64; 2],
    /// The sample parameters h_i(t_j) of Eq. (3.4), n(i) of Eq. (3.5)
    /// (their number in the JSON report).
    #[serde(serialize_with = "serialize_count")]
    pub samples: Vec<[f64; 2]>,
    /// The pre-image polyline the endpoints were snapped to (u, v).
    #[serde(skip)]
    pub pre_image: Vec<[f64; 2]>,
    /// The stretch of that polyline between e¹ and e² (the part the target
    /// replaces), from e¹ to e².
    #[serde(skip)]
    pub stretch: Vec<[f64; 2]>,
    /// How far (in u, v) each given endpoint was from where it snapped:
    /// a large value means the point was not on a line of that radius
    /// (all of them:
    /// [`SurfaceFairReport::snap_distances`](super::SurfaceFairReport::snap_distances)).
    #[serde(skip)]
    pub snap_distance: [f64; 2],
}

/// Serialises a list as its length.
fn serialize_count<S: serde::Serializer, T>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(v.len() as u64)
}

/// The light of each endpoint pair: the one whose radius matches within
/// 1e-9 (relative).
pub(super) fn light_of(lights: &[CircularLight], radius: f64) -> Option<usize> {
    lights
        .iter()
        .position(|l| (l.radius() - radius).abs() <= 1e-9 * l.radius().max(1.0))
}

/// A pre-image polyline with cumulative arc length (in `(u, v)`).
pub(super) struct Arc<'a> {
    pts: &'a [[f64; 2]],
    closed: bool,
    /// `cum[k]` arc length at point k; for closed lines one extra entry
    /// (back to point 0).
    cum: Vec<f64>,
}

pub(super) fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

impl<'a> Arc<'a> {
    pub(super) fn new(line: &'a SurfaceHighlightLine) -> Self {
        let pts = &line.uv[..];
        let mut cum = vec![0.0];
        let n = pts.len();
        let segs = if line.closed { n } else { n.saturating_sub(1) };
        for k in 0..segs {
            let d = dist2(pts[k], pts[(k + 1) % n]).sqrt();
            cum.push(cum[k] + d);
        }
        Arc {
            pts,
            closed: line.closed,
            cum,
        }
    }
    fn length(&self) -> f64 {
        *self.cum.last().unwrap_or(&0.0)
    }
    /// Nearest point: (squared distance, arc position, point).
    pub(super) fn nearest(&self, p: [f64; 2]) -> (f64, f64, [f64; 2]) {
        let n = self.pts.len();
        let mut best = (f64::INFINITY, 0.0, self.pts[0]);
        if n == 1 {
            return (dist2(self.pts[0], p), 0.0, self.pts[0]);
        }
        for k in 0..self.cum.len() - 1 {
            let (a, b) = (self.pts[k], self.pts[(k + 1) % n]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let l2 = ab[0] * ab[0] + ab[1] * ab[1];
            let t = if l2 > 0.0 {
                (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = [a[0] + t * ab[0], a[1] + t * ab[1]];
            let d = dist2(p, q);
            if d < best.0 {
                best = (d, self.cum[k] + t * (self.cum[k + 1] - self.cum[k]), q);
            }
        }
        best
    }
    /// The polyline from arc position `s1` to `s2` travelling in direction
    /// `dir` (±1; wrapping on closed lines): the two end points and the
    /// vertices between them.
    fn between(&self, s1: f64, s2: f64, dir: f64) -> Vec<[f64; 2]> {
        let len = self.length();
        let n = self.pts.len();
        let mut out = vec![self.at(s1)];
        if !(len > 0.0) || n < 2 {
            return out;
        }
        let span = if self.closed {
            (dir * (s2 - s1)).rem_euclid(len)
        } else {
            (s2 - s1).abs()
        };
        // vertices k with arc position strictly inside the travelled span
        let mut inner: Vec<(f64, [f64; 2])> = (0..self.cum.len() - 1)
            .filter_map(|k| {
                let d = if self.closed {
                    (dir * (self.cum[k] - s1)).rem_euclid(len)
                } else {
                    dir * (self.cum[k] - s1)
                };
                (d > 0.0 && d < span).then_some((d, self.pts[k % n]))
            })
            .collect();
        inner.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.extend(inner.into_iter().map(|(_, p)| p));
        out.push(self.at(s2));
        out
    }
    /// The point at arc position `s` (wrapped on closed lines, clamped on
    /// open ones).
    fn at(&self, s: f64) -> [f64; 2] {
        let len = self.length();
        let n = self.pts.len();
        if len <= 0.0 || n < 2 {
            return self.pts[0];
        }
        let s = if self.closed {
            s.rem_euclid(len)
        } else {
            s.clamp(0.0, len)
        };
        let k = match self.cum.binary_search_by(|c| c.total_cmp(&s)) {
            Ok(k) => k.min(self.cum.len() - 2),
            Err(k) => k.saturating_sub(1).min(self.cum.len() - 2),
        };
        let (a, b) = (self.pts[k], self.pts[(k + 1) % n]);
        let d = self.cum[k + 1] - self.cum[k];
        let t = if d > 0.0 {
            ((s - self.cum[k]) / d).clamp(0.0, 1.0)
        } else {
            0.0
        };
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
    }
}

/// Direction of travel at an endpoint from the cubic through four points of
/// the regular part (Nishiyama et al. §3.2, Fig. 4(b)): `q[0]` is the
/// endpoint and `q[1..4]` go away from the stretch at equal arc steps. The
/// interpolating cubic at t = 0, 1/3, 2/3, 1 has derivative
/// (−11 q0 + 18 q1 − 9 q2 + 2 q3) / 2 at q0 (pointing away from the stretch).
pub(super) fn outward_direction(q: [[f64; 2]; 4]) -> Option<[f64; 2]> {
    let d = [
        0.5 * (-11.0 * q[0][0] + 18.0 * q[1][0] - 9.0 * q[2][0] + 2.0 * q[3][0]),
        0.5 * (-11.0 * q[0][1] + 18.0 * q[1][1] - 9.0 * q[2][1] + 2.0 * q[3][1]),
    ];
    let l = d[0].hypot(d[1]);
    (l > 0.0 && l.is_finite()).then(|| [d[0] / l, d[1] / l])
}

/// Target curves of Nishiyama et al. §3.2–3.3 for each endpoint pair:
///
/// 1. the pre-images of every light used are contoured on an
///    `opts.grid`² grid ([`crate::highlight::surface`]);
/// 2. the start is snapped to the nearest point of its radius' pre-image,
///    and the end to the nearest point of the same polyline;
/// 3. the stretch runs from e¹ to e² along the polyline (on closed lines the
///    shorter way); four points of the regular part on each side, spaced by
///    |e¹ − e²|/3 of arc length (less where an open line ends), give the
///    tangent directions through a cubic fit; their lengths are |e¹ − e²|
///    (Eq. (3.3));
/// 4. the cubic Hermite curve of Eq. (3.1)–(3.2) is sampled at
///    n(i) = 2 + ⌊|e¹ − e²| / s⌋ equally spaced parameters (Eq. (3.4)–(3.5)),
///    s = `opts.sample_spacing` × domain diagonal, clamped to the domain.
///
/// (Eq. (3.2) of the paper lists the Hermite basis with H₁ and H₂ swapped
/// relative to Eq. (3.1); [`CubicHermite`] uses the standard assignment.)
pub fn target_curves(
    surface: &BSplineSurface,
    opts: &SurfaceFairOptions,
) -> Result<Vec<TargetCurve>, SurfaceFairError> {
    check_options(opts)?;
    let (lights, endpoints) = (&opts.lights[..], &opts.endpoints[..]);
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let diag = (du[1] - du[0]).hypot(dv[1] - dv[0]);
    let s = opts.sample_spacing * diag;
    // Pre-images of the lights used (once per light).
    let mut used: Vec<usize> = Vec::new();
    let mut light_index = Vec::with_capacity(endpoints.len());
    for (k, e) in endpoints.iter().enumerate() {
        let finite = e.start.iter().chain(&e.end).all(|x| x.is_finite());
        if !(e.radius > 0.0 && e.radius.is_finite() && finite) {
            return Err(SurfaceFairError::Invalid(format!(
                "endpoint {k}: radius must be positive and coordinates finite"
            )));
        }
        let l = light_of(lights, e.radius).ok_or(SurfaceFairError::NoLight {
            index: k,
            radius: e.radius,
        })?;
        light_index.push(l);
        if !used.contains(&l) {
            used.push(l);
        }
    }
    let hopts = SurfaceHighlightOptions::default().grid(opts.grid);
    let pre_images: Vec<(usize, Vec<SurfaceHighlightLine>)> = used
        .par_iter()
        .map(|&l| {
            let light = SurfaceLight::Circular(lights[l]);
            let field = distance_field(surface, &light, opts.grid, opts.grid);
            (l, contour_field(surface, &light, l, &field, 0.0, &hopts))
        })
        .collect();
    let mut out = Vec::with_capacity(endpoints.len());
    for (k, e) in endpoints.iter().enumerate() {
        let l = light_index[k];
        let lines = &pre_images
            .iter()
            .find(|(x, _)| *x == l)
            .map(|(_, v)| v)
            .ok_or(SurfaceFairError::NoPreImage {
                index: k,
                radius: e.radius,
            })?;
        let arcs: Vec<Arc> = lines
            .iter()
            .filter(|x| x.uv.len() >= 2)
            .map(Arc::new)
            .collect();
        let start = surface_clamp(surface, e.start);
        let end = surface_clamp(surface, e.end);
        let (arc, (_, s1, e1)) = arcs
            .iter()
            .map(|a| (a, a.nearest(start)))
            .min_by(|x, y| x.1.0.total_cmp(&y.1.0))
            .ok_or(SurfaceFairError::NoPreImage {
                index: k,
                radius: e.radius,
            })?;
        let (_, s2, e2) = arc.nearest(end);
        let chord = dist2(e1, e2).sqrt();
        if !(chord > 1e-9 * diag) {
            return Err(SurfaceFairError::Invalid(format!(
                "endpoint {k}: start and end snap to the same point of the highlight line"
            )));
        }
        let len = arc.length();
        // Direction of travel along the arc from e1 to e2.
        let dir = if arc.closed {
            if (s2 - s1).rem_euclid(len) <= 0.5 * len {
                1.0
            } else {
                -1.0
            }
        } else if s2 >= s1 {
            1.0
        } else {
            -1.0
        };
        let h = chord / 3.0;
        let side = |s0: f64, away: f64| -> Option<[f64; 2]> {
            // Arc available beyond s0 in direction `away`.
            let avail = if arc.closed {
                f64::INFINITY
            } else if away > 0.0 {
                len - s0
            } else {
                s0
            };
            let step = h.min(avail / 3.0);
            if !(step > 1e-12 * diag) {
                return None;
            }
            let q = [0.0, 1.0, 2.0, 3.0].map(|m| arc.at(s0 + away * m * step));
            outward_direction(q)
        };
        let stretch = arc.between(s1, s2, dir);
        let chord_dir = [(e2[0] - e1[0]) / chord, (e2[1] - e1[1]) / chord];
        let t1 = side(s1, -dir).map_or(chord_dir, |d| [-d[0], -d[1]]);
        let t2 = side(s2, dir).unwrap_or(chord_dir);
        let hermite = CubicHermite {
            p0: Vec3::new(e1[0], e1[1], 0.0),
            p1: Vec3::new(e2[0], e2[1], 0.0),
            v0: Vec3::new(t1[0], t1[1], 0.0) * chord,
            v1: Vec3::new(t2[0], t2[1], 0.0) * chord,
        };
        let n = 2 + if s > 0.0 {
            ((chord / s).floor() as usize).min(100_000)
        } else {
            0
        };
        let samples = (0..n)
            .map(|j| {
                let p = hermite.point(j as f64 / (n - 1) as f64);
                surface_clamp(surface, [p.x, p.y])
            })
            .collect();
        out.push(TargetCurve {
            index: k,
            light: l,
            radius: lights[l].radius(),
            start: e1,
            end: e2,
            tangent_start: [t1[0] * chord, t1[1] * chord],
            tangent_end: [t2[0] * chord, t2[1] * chord],
            samples,
            pre_image: arc.pts.to_vec(),
            stretch,
            snap_distance: [dist2(e.start, e1).sqrt(), dist2(e.end, e2).sqrt()],
        });
    }
    Ok(out)
}

/// Raises the samples n(i) of every target by a common whole factor k
/// (spacing s/k of Eq. (3.5); the old samples stay among the new) until
/// there are at least as many samples as `unknowns`: Nishiyama et al. §3.3
/// choose n(i) "such that the linear system is always an overdetermined
/// system". At most 64 times as many samples.
pub(super) fn overdetermine(
    surface: &BSplineSurface,
    targets: &mut [TargetCurve],
    unknowns: usize,
) {
    let rows: usize = targets.iter().map(|t| t.samples.len()).sum();
    if rows == 0 || rows >= unknowns {
        return;
    }
    let k = unknowns.div_ceil(rows).clamp(2, 64);
    for t in targets.iter_mut() {
        let hermite = CubicHermite {
            p0: Vec3::new(t.start[0], t.start[1], 0.0),
            p1: Vec3::new(t.end[0], t.end[1], 0.0),
            v0: Vec3::new(t.tangent_start[0], t.tangent_start[1], 0.0),
            v1: Vec3::new(t.tangent_end[0], t.tangent_end[1], 0.0),
        };
        let n = (t.samples.len().max(2) - 1) * k + 1;
        t.samples = (0..n)
            .map(|j| {
                let p = hermite.point(j as f64 / (n - 1) as f64);
                surface_clamp(surface, [p.x, p.y])
            })
            .collect();
    }
}

pub(super) fn surface_clamp(surface: &BSplineSurface, p: [f64; 2]) -> [f64; 2] {
    let (u, v) = surface.clamp_parameters(p[0], p[1]);
    [u, v]
}

/// Endpoint pairs around a disc of the parameter domain: for every pre-image
/// of every light (zero level on a `grid`² grid) and every maximal run of its
/// points inside the disc of centre `center` and radius `radius` (in
/// `(u, v)`), the pair (last point before, first point after) the run — the
/// "two endpoints bounding the local irregularity" a user would click
/// (Nishiyama et al. Fig. 3). Runs that reach an open end of a line are
/// skipped (no regular part on that side).
pub fn endpoints_around(
    surface: &BSplineSurface,
    lights: &[CircularLight],
    center: [f64; 2],
    radius: f64,
    grid: usize,
) -> Vec<EndpointPair> {
    let hopts = SurfaceHighlightOptions::default().grid(grid);
    let mut out = Vec::new();
    if !(radius > 0.0) {
        return out;
    }
    for (k, light) in lights.iter().enumerate() {
        let sl = SurfaceLight::Circular(*light);
        let field = distance_field(surface, &sl, grid, grid);
        for line in contour_field(surface, &sl, k, &field, 0.0, &hopts) {
            let n = line.uv.len();
            if n < 3 {
                continue;
            }
            let inside: Vec<bool> = line
                .uv
                .iter()
                .map(|&p| dist2(p, center) <= radius * radius)
                .collect();
            if inside.iter().all(|&b| b) || !inside.iter().any(|&b| b) {
                continue;
            }
            // Start scanning at an outside point so runs do not wrap.
            let first_out = if line.closed {
                inside.iter().position(|&b| !b).unwrap_or(0)
            } else {
                0
            };
            let m = if line.closed { n } else { n - first_out };
            let idx = |t: usize| (first_out + t) % n;
            let mut t = 0;
            while t < m {
                if inside[idx(t)] {
                    let s = t;
                    while t < m && inside[idx(t)] {
                        t += 1;
                    }
                    if !line.closed && (s == 0 || t >= m) {
                        continue; // reaches an open end
                    }
                    out.push(EndpointPair {
                        radius: light.radius(),
                        start: line.uv[idx(s - 1)],
                        end: line.uv[idx(t)],
                    });
                } else {
                    t += 1;
                }
            }
        }
    }
    out
}
