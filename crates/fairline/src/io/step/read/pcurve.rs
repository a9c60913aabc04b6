//! Trimming curves from the p-curves a file carries (ISO 10303-42
//! `SURFACE_CURVE` / `SEAM_CURVE` with `PCURVE`s: a `DEFINITIONAL_REPRESENTATION`
//! of a 2-D `LINE`, `CIRCLE`, `ELLIPSE` or B-spline curve in the surface's
//! parameters), mapped into the parameters of the face's NURBS and checked
//! against the exact 3-D edge.
//!
//! The map ([`PcurveMap`]) runs per coordinate: ISO 10303-42's parameter of
//! the surface → the surface's natural coordinate (angles times the file's
//! radians per angle unit, the extrusion vector's length, a conic profile's
//! angle to its NURBS parameter) → shifted by whole periods next to the
//! face's loop computed from the 3-D edges → the NURBS parameter (angles
//! through [`ArcMap::param`], the rational arcs' parameter; other
//! coordinates unchanged). Where every coordinate the p-curve varies in is
//! mapped affinely, the trim curve is the p-curve's piece between the edge's
//! vertices, exactly (lines, conic arcs, B-spline pieces split by knot
//! insertion); otherwise it is a dense polyline through mapped points of the
//! p-curve.
//!
//! A p-curve is used only when the trim curve it gives lies on the 3-D
//! edge: the NURBS evaluated along the trim curve stays within the
//! tolerance of the edge (and its ends on the edge's vertices). The
//! tolerance is the file's distance uncertainty or 1e-6 of the surface's
//! size, whichever is larger; where the 3-D curve is a polyline (a degree-1
//! B-spline, e.g. one the writer sampled from the p-curve), a polyline
//! through points of the curve deviates from it between its vertices by
//! about `L·θ/8` for a smooth curve (chord `L`, turning angle `θ` at its
//! ends) and by at most `L·θ/2` where the curve has a corner between the
//! two vertices (a corner of angle `α` lies at most `L·α/4` from the chord
//! and turns it by at least `α/2` at one end); `L·θ/2` is allowed there.

use super::curves::{Curve, conic_range, nearest_param};
use super::edges::EdgeUse;
use super::*;
use crate::bspline::basis::find_span;

/// One coordinate of [`PcurveMap`].
#[derive(Clone, Copy, Debug)]
pub(super) struct CoordMap {
    /// ISO parameter → natural coordinate factor.
    pub scale: f64,
    /// A conic profile's angle (after `scale`, taken in one turn) → its
    /// NURBS parameter.
    pub profile: Option<ArcMap>,
    /// Natural coordinate → NURBS parameter (angles); `None`: unchanged.
    pub arc: Option<ArcMap>,
    /// Period of the natural coordinate.
    pub period: Option<f64>,
    /// Middle of the face's natural range in this coordinate.
    pub centre: f64,
}

impl CoordMap {
    /// The identity (planes, B-spline surfaces).
    pub const IDENTITY: CoordMap = CoordMap {
        scale: 1.0,
        profile: None,
        arc: None,
        period: None,
        centre: 0.0,
    };

    fn natural(&self, x: f64) -> f64 {
        let n = self.scale * x;
        match &self.profile {
            Some(m) => m.param(n.rem_euclid(TAU)),
            None => n,
        }
    }

    /// Through the arcs' parameter inside their angle range; beyond it
    /// continued linearly (`scale · angle`, the value at the range's ends),
    /// so that a p-curve leaving the face's range leaves the NURBS domain
    /// instead of being clamped onto its border.
    fn param_of(&self, n: f64) -> f64 {
        self.arc.as_ref().map_or(n, |m| {
            let (lo, hi) = (
                m.start.min(m.start + m.sweep),
                m.start.max(m.start + m.sweep),
            );
            let slack = 1e-12 * m.sweep.abs();
            if n < lo - slack || n > hi + slack {
                m.scale * n
            } else {
                m.param(n)
            }
        })
    }

    /// Whether the whole map of this coordinate is affine.
    fn affine(&self) -> bool {
        self.profile.is_none() && self.arc.is_none()
    }
}

/// The map from a p-curve's (u, v) (ISO 10303-42's parameters of the
/// surface) to the parameters of the face's NURBS; see the module docs.
#[derive(Clone, Copy, Debug)]
pub(super) struct PcurveMap(pub [CoordMap; 2]);

impl PcurveMap {
    /// The identity map (planes: ISO's (u, v) are the plane frame's
    /// coordinates, which the plane's bilinear patch uses; B-spline
    /// surfaces: their own parameters).
    pub const IDENTITY: PcurveMap = PcurveMap([CoordMap::IDENTITY; 2]);

    fn natural(&self, p: Vec3) -> [f64; 2] {
        [self.0[0].natural(p.x), self.0[1].natural(p.y)]
    }

    fn param_of(&self, n: [f64; 2]) -> [f64; 2] {
        [self.0[0].param_of(n[0]), self.0[1].param_of(n[1])]
    }

    /// Natural coordinates moved by whole periods next to the face's range
    /// (for locating points whatever period the p-curve is written in).
    fn near_face(&self, n: [f64; 2]) -> [f64; 2] {
        [0, 1].map(|c| wrap_near(n[c], self.0[c].centre, self.0[c].period))
    }
}

fn wrap_near(x: f64, near: f64, period: Option<f64>) -> f64 {
    match period {
        Some(p) if p > 0.0 => x + p * ((near - x) / p).round(),
        _ => x,
    }
}

/// What the p-curves of one edge on one surface gave.
pub(super) enum PcurveUse {
    /// The edge has no (readable) p-curve on this surface.
    Absent,
    /// The trim curve from a p-curve that agrees with the 3-D edge.
    Used(TrimCurve),
    /// Every p-curve disagrees with the 3-D edge: the smallest largest
    /// distance and the tolerance.
    Rejected { distance: f64, tolerance: f64 },
}

/// Validation samples along a trim curve (its polyline vertices, at most
/// about 64, for degree 1; 33 equally spaced parameters otherwise).
fn check_params(c: &TrimCurve) -> Vec<f64> {
    let [a, b] = c.domain();
    if c.degree() == 1 {
        let knots: Vec<f64> = c.knots()[1..c.knots().len() - 1].to_vec();
        let step = knots.len().div_ceil(64).max(1);
        let mut out: Vec<f64> = knots.iter().copied().step_by(step).collect();
        out.push(b);
        return out;
    }
    (0..=32).map(|k| a + (b - a) * k as f64 / 32.0).collect()
}

/// The turning angle of a polyline at its vertex `i` (0 at the ends).
fn turning(points: &[Vec3], i: usize) -> f64 {
    if i == 0 || i + 1 >= points.len() {
        return 0.0;
    }
    let (d0, d1) = (points[i] - points[i - 1], points[i + 1] - points[i]);
    let l = d0.length() * d1.length();
    if l > 0.0 {
        (d0.dot(d1) / l).clamp(-1.0, 1.0).acos()
    } else {
        0.0
    }
}

/// Distance from `q` to the segment `[a, b]`.
fn segment_distance(q: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((q - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + t * ab)
}

/// Distance from `q` to the edge between its vertices: the nearest of the
/// edge's dense samples `(t, point)` (a coarse pass over every 16th, then
/// its neighbourhood), refined on the exact curve between that sample's
/// neighbours — closed forms for lines and conics, the chords of a polyline
/// (degree-1 B-spline) less their allowance `|chord| · θ / 2` (`θ` the
/// larger turning angle at the chord's ends; see the module docs),
/// golden-section search on other B-splines.
fn distance_to_edge(curve: &Curve, samples: &[(f64, Vec3)], q: Vec3) -> f64 {
    let n = samples.len();
    if n == 0 {
        return f64::INFINITY;
    }
    let d2 = |k: usize| samples[k].1.distance_squared(q);
    let nearest = |r: &mut dyn Iterator<Item = usize>| {
        r.min_by(|&a, &b| d2(a).total_cmp(&d2(b))).unwrap_or(0)
    };
    const STRIDE: usize = 16;
    let coarse = nearest(&mut (0..n).step_by(STRIDE).chain(std::iter::once(n - 1)));
    let k = nearest(&mut (coarse.saturating_sub(STRIDE)..=(coarse + STRIDE).min(n - 1)));
    let (ta, tb) = (
        samples[k.saturating_sub(1)].0,
        samples[(k + 1).min(n - 1)].0,
    );
    let (lo, hi) = (ta.min(tb), ta.max(tb));
    let sampled = d2(k).sqrt();
    let exact = match curve {
        Curve::Line { .. } => curve.eval(curve.param_of(q).clamp(lo, hi)).distance(q),
        Curve::Conic { .. } => {
            let t = wrap_near(curve.param_of(q), samples[k].0, Some(TAU));
            curve.eval(t.clamp(lo, hi)).distance(q)
        }
        Curve::Spline(c) if c.degree == 1 && c.points.len() >= 2 => {
            let m = c.points.len();
            let (s0, s1) = (
                find_span(&c.knots, 1, m, lo).clamp(1, m - 1),
                find_span(&c.knots, 1, m, hi).clamp(1, m - 1),
            );
            (s0..=s1)
                .map(|s| {
                    let (a, b) = (c.points[s - 1], c.points[s]);
                    let allowance =
                        a.distance(b) * turning(&c.points, s - 1).max(turning(&c.points, s)) / 2.0;
                    (segment_distance(q, a, b) - allowance).max(0.0)
                })
                .fold(f64::INFINITY, f64::min)
        }
        Curve::Spline(_) => {
            let t = nearest_param(lo, hi, 8, |t| curve.eval(t).distance(q));
            curve.eval(t).distance(q)
        }
    };
    exact.min(sampled)
}

/// The nearest point of an edge to points that run along it in traversal
/// order, each searched near the previous one (the correspondence of a
/// p-curve's parameter with the edge's is monotone): closed forms for
/// lines and conics (the angle taken next to the previous one), a walk
/// over the chords of a polyline (degree-1 B-spline) from the previous
/// nearest chord to the nearest one after it, less the chord's allowance
/// as in [`distance_to_edge`], and a golden-section search over a window
/// of the parameter next to the previous point on other B-splines.
struct EdgeWalk<'e> {
    curve: &'e Curve,
    /// The edge's parameter range, ascending.
    lo: f64,
    hi: f64,
    /// Traversal runs towards increasing parameters.
    increasing: bool,
    /// The parameter of the previous nearest point.
    at: f64,
    /// Polylines: the chords of the edge (`s` the chord from point `s - 1`
    /// to `s`) and the previous nearest one.
    chords: [usize; 2],
    chord: usize,
}

impl<'e> EdgeWalk<'e> {
    fn new(curve: &'e Curve, [t0, t1]: [f64; 2]) -> Self {
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let chords = match curve {
            Curve::Spline(c) if c.degree == 1 && c.points.len() >= 2 => {
                let m = c.points.len();
                [
                    find_span(&c.knots, 1, m, lo).clamp(1, m - 1),
                    find_span(&c.knots, 1, m, hi).clamp(1, m - 1),
                ]
            }
            _ => [0, 0],
        };
        let increasing = t1 >= t0;
        EdgeWalk {
            curve,
            lo,
            hi,
            increasing,
            at: t0,
            chords,
            chord: if increasing { chords[0] } else { chords[1] },
        }
    }

    /// The distance from `q` to the edge's point tracked next to the
    /// previous one (an upper bound of the distance to the edge).
    fn distance(&mut self, q: Vec3) -> f64 {
        let (lo, hi) = (self.lo, self.hi);
        match self.curve {
            Curve::Line { .. } => {
                let t = self.curve.param_of(q).clamp(lo, hi);
                self.curve.eval(t).distance(q)
            }
            Curve::Conic { .. } => {
                let t = wrap_near(self.curve.param_of(q), self.at, Some(TAU)).clamp(lo, hi);
                self.at = t;
                self.curve.eval(t).distance(q)
            }
            Curve::Spline(c) if c.degree == 1 && c.points.len() >= 2 => {
                self.walk_chords(&c.points, q)
            }
            Curve::Spline(n) => {
                // A window of 1/16 of the edge behind and 3/16 ahead.
                let w = (hi - lo) / 16.0;
                let (a, b) = if self.increasing {
                    ((self.at - w).max(lo), (self.at + 3.0 * w).min(hi))
                } else {
                    ((self.at - 3.0 * w).max(lo), (self.at + w).min(hi))
                };
                let t = nearest_param(a, b, 8, |t| n.eval(t).distance(q));
                self.at = t;
                n.eval(t).distance(q)
            }
        }
    }

    /// Polylines: from the previous nearest chord onwards while the next
    /// chord is no farther; the distance to the chord reached (or to a
    /// neighbour of it) less its allowance.
    fn walk_chords(&mut self, points: &[Vec3], q: Vec3) -> f64 {
        let [s0, s1] = self.chords;
        let dist = |s: usize| segment_distance(q, points[s - 1], points[s]);
        let next = |s: usize| {
            if self.increasing {
                (s < s1).then_some(s + 1)
            } else {
                (s > s0).then_some(s - 1)
            }
        };
        let mut s = self.chord;
        let mut d = dist(s);
        while let Some(n) = next(s) {
            let dn = dist(n);
            if dn > d {
                break;
            }
            (s, d) = (n, dn);
        }
        self.chord = s;
        (s.saturating_sub(1).max(s0)..=(s + 1).min(s1))
            .map(|k| {
                let allowance = points[k - 1].distance(points[k])
                    * turning(points, k - 1).max(turning(points, k))
                    / 2.0;
                (dist(k) - allowance).max(0.0)
            })
            .fold(f64::INFINITY, f64::min)
    }
}

impl<'a> Reader<'a> {
    /// The distance tolerance for p-curves on `s`: the file's distance
    /// uncertainty or 1e-6 of the surface's control-point box diagonal,
    /// whichever is larger.
    pub(super) fn pcurve_tolerance(&self, s: &BSplineSurface) -> f64 {
        let (lo, hi) = s.control_bounding_box();
        (1e-6 * (hi - lo).length()).max(self.uncertainty)
    }

    /// The p-curves of an edge's SURFACE_CURVE / SEAM_CURVE on surface
    /// `sid` (a seam has two), with the instance they came from. P-curves
    /// of a type that is not supported are left out.
    fn pcurves_on(&self, e: &EdgeUse, sid: u64) -> R<Vec<(&'a Instance, Curve)>> {
        let mut out = Vec::new();
        let ci = &self.ex.instances[&e.curve_entity];
        let Some(sc) = ci.part("SURFACE_CURVE").or_else(|| ci.part("SEAM_CURVE")) else {
            return Ok(out);
        };
        let Some(Value::List(assoc)) = sc.get(2) else {
            return Ok(out);
        };
        for a in assoc {
            let Value::Ref(pid) = a else { continue };
            let Some(pc) = self.ex.instances.get(pid) else {
                continue;
            };
            let Some(pp) = pc.part("PCURVE") else {
                continue;
            };
            if !matches!(pp.get(1), Some(Value::Ref(b)) if *b == sid) {
                continue;
            }
            let dr = self.refer(pc, pp, 2)?;
            let drp = self.params(dr, &["DEFINITIONAL_REPRESENTATION"])?;
            let items = self.refs(dr, self.list(dr, drp, 1)?)?;
            let Some(c2) = items.first() else { continue };
            if let Ok(curve) = self.curve(c2) {
                out.push((*c2, curve));
            }
        }
        Ok(out)
    }

    /// The trim curve of edge `e` from its p-curves on surface `sid` (the
    /// entity of `s`), through `map`; `seg` is the edge's stretch of the
    /// loop computed from the 3-D edges in natural coordinates (analytic
    /// faces), which decides the period a p-curve is placed in.
    pub(super) fn pcurve_trim(
        &self,
        s: &BSplineSurface,
        sid: u64,
        e: &EdgeUse,
        map: &PcurveMap,
        seg: Option<&[(f64, f64)]>,
    ) -> R<PcurveUse> {
        Ok(self.pcurve_trims(s, sid, e, map, seg, false)?.0)
    }

    /// [`Self::pcurve_trim`]; with `all`, also every further p-curve that
    /// agrees with the edge (a seam's second p-curve), in the file's order.
    pub(super) fn pcurve_trims(
        &self,
        s: &BSplineSurface,
        sid: u64,
        e: &EdgeUse,
        map: &PcurveMap,
        seg: Option<&[(f64, f64)]>,
        all: bool,
    ) -> R<(PcurveUse, Vec<TrimCurve>)> {
        let candidates = self.pcurves_on(e, sid)?;
        if candidates.is_empty() {
            return Ok((PcurveUse::Absent, Vec::new()));
        }
        let tolerance = self.pcurve_tolerance(s);
        // The edge's dense samples, for the full search where tracking
        // along the edge finds no point within the tolerance (rare: a
        // p-curve that disagrees).
        let samples = std::cell::OnceCell::new();
        let dense = || samples.get_or_init(|| self.edge_samples(e)).as_slice();
        let range = self.edge_range(e);
        let mut best = f64::INFINITY;
        let mut agreeing = Vec::new();
        for (_, curve) in candidates {
            // A p-curve that gives no valid trim curve disagrees with the
            // edge (it is not an error of the file's geometry).
            let Ok(Some(trim)) = self.pcurve_image(s, e, &curve, map, seg, tolerance) else {
                continue;
            };
            let d = disagreement(s, e, range, &dense, &trim, tolerance);
            if d <= tolerance {
                agreeing.push(trim);
                if !all {
                    break;
                }
                continue;
            }
            best = best.min(d);
        }
        if agreeing.is_empty() {
            return Ok((
                PcurveUse::Rejected {
                    distance: best,
                    tolerance,
                },
                agreeing,
            ));
        }
        let first = agreeing.remove(0);
        Ok((PcurveUse::Used(first), agreeing))
    }

    /// The p-curve's piece between the edge's vertices, in traversal order,
    /// mapped into the NURBS parameters (see the module docs); `None` when
    /// no piece can be found.
    fn pcurve_image(
        &self,
        s: &BSplineSurface,
        e: &EdgeUse,
        curve: &Curve,
        map: &PcurveMap,
        seg: Option<&[(f64, f64)]>,
        tolerance: f64,
    ) -> Result<Option<TrimCurve>, String> {
        let xy = |t: f64| curve.eval(t);
        // Surface point of a p-curve parameter, in whatever period.
        let located = |t: f64| {
            let [u, v] = map.param_of(map.near_face(map.natural(xy(t))));
            s.eval(u, v)
        };
        let param_in =
            |a: f64, b: f64, q: Vec3| nearest_param(a, b, 400, |t| located(t).distance(q));
        let [t0, t1] = match curve {
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                let near = |x: Vec3, y: Vec3| x.distance(y) <= tolerance;
                if e.closed {
                    if e.forward { [a, b] } else { [b, a] }
                } else if near(located(a), e.start) && near(located(b), e.end) {
                    [a, b]
                } else if near(located(b), e.start) && near(located(a), e.end) {
                    [b, a]
                } else {
                    [param_in(a, b, e.start), param_in(a, b, e.end)]
                }
            }
            // The p-curve has the edge curve's sense (ISO 10303-42
            // surface_curve).
            Curve::Conic { .. } => conic_range(
                param_in(0.0, TAU, e.start),
                param_in(0.0, TAU, e.end),
                e.closed,
                e.forward,
            ),
            // A line has the 3-D curve's parameters (ISO 10303-42
            // surface_curve: one parametrisation); checked afterwards.
            Curve::Line { .. } => self.edge_range(e),
        };
        if !(t0 - t1).is_normal() {
            return Ok(None);
        }
        // Whole periods that put the p-curve on the computed loop's stretch.
        let mut shift = [0.0; 2];
        if let Some(seg) = seg.filter(|s| !s.is_empty()) {
            let probe: Vec<[f64; 2]> = (0..=16)
                .map(|k| map.natural(xy(t0 + (t1 - t0) * k as f64 / 16.0)))
                .collect();
            for (c, sh) in shift.iter_mut().enumerate() {
                if let Some(p) = map.0[c].period.filter(|p| *p > 0.0) {
                    let mean_pc = probe.iter().map(|q| q[c]).sum::<f64>() / probe.len() as f64;
                    let mean_seg = seg
                        .iter()
                        .map(|q| if c == 0 { q.0 } else { q.1 })
                        .sum::<f64>()
                        / seg.len() as f64;
                    *sh = p * ((mean_seg - mean_pc) / p).round();
                }
            }
        }
        // (A zero shift is not added: -0.0 stays -0.0, so that written
        // p-curves read back bit-identical.)
        let shifted = |x: f64, sh: f64| if sh == 0.0 { x } else { x + sh };
        let to_uv = |q: Vec3| {
            let n = map.natural(q);
            map.param_of([shifted(n[0], shift[0]), shifted(n[1], shift[1])])
        };
        let piece = match curve {
            Curve::Line { .. } => Some(Nurbs3::segment(xy(t0), xy(t1), 0.0, 1.0)),
            Curve::Conic { .. } => curve.conic_arc([t0, t1]),
            Curve::Spline(n) => n.between(t0, t1),
        };
        let constant = |n: &Nurbs3, c: usize| {
            let x = |p: &Vec3| if c == 0 { p.x } else { p.y };
            let x0 = x(&n.points[0]);
            n.points
                .iter()
                .all(|p| (x(p) - x0).abs() <= 1e-14 * (1.0 + x0.abs()))
        };
        if let Some(n) = &piece {
            if (0..2).all(|c| map.0[c].affine() || constant(n, c)) {
                let pts = n.points.iter().map(|q| to_uv(*q)).collect();
                return TrimCurve::new(n.degree, n.knots.clone(), pts, n.weights.clone()).map(Some);
            }
            // A segment along a parameter line stays one through the
            // monotone maps of the coordinates.
            if n.degree == 1 && n.points.len() == 2 && (constant(n, 0) || constant(n, 1)) {
                return TrimCurve::line(to_uv(n.points[0]), to_uv(n.points[1])).map(Some);
            }
        }
        let count = match curve {
            Curve::Line { .. } => 64,
            Curve::Conic { .. } => ((t1 - t0).abs().to_degrees() * 2.0).ceil() as usize,
            Curve::Spline(n) => 16 * n.points.len() * n.degree,
        }
        .clamp(8, 4000);
        let pts: Vec<[f64; 2]> = (0..=count)
            .map(|k| to_uv(xy(t0 + (t1 - t0) * k as f64 / count as f64)))
            .collect();
        polyline(&pts).map(Some)
    }
}

/// The largest distance of the surface along a trim curve from the 3-D
/// edge (less the polyline allowance), its ends from the edges' vertices
/// included. Where the trim curve leaves the surface's domain, the surface
/// is continued linearly: the point of the clamped parameters plus the
/// excess times the surface's first derivatives there, so that a p-curve
/// running off the face is measured by how far off it runs.
///
/// The samples run along the edge in traversal order, so the nearest edge
/// point is tracked from one sample to the next ([`EdgeWalk`]); a sample
/// whose tracked point lies farther than `tolerance` is measured again by
/// the full search over the edge's dense samples (`dense`,
/// [`distance_to_edge`]). A tracked point is a point of the edge, so its
/// distance bounds the true distance from above: a p-curve accepted by the
/// tracking is within the tolerance everywhere it is sampled, and one the
/// full search accepts is accepted too.
fn disagreement<'s>(
    s: &BSplineSurface,
    e: &EdgeUse,
    range: [f64; 2],
    dense: &dyn Fn() -> &'s [(f64, Vec3)],
    c: &TrimCurve,
    tolerance: f64,
) -> f64 {
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    let [a, b] = c.domain();
    let at = |t: f64| {
        let [u, v] = c.eval(t);
        let (cu, cv) = (u.clamp(u0, u1), v.clamp(v0, v1));
        if (cu, cv) == (u, v) {
            return s.eval(u, v);
        }
        let d = s.derivatives(cu, cv);
        d.point + (u - cu) * d.su + (v - cv) * d.sv
    };
    let ends = [(a, e.start), (b, e.end)]
        .into_iter()
        .map(|(t, q)| at(t).distance(q));
    let mut walk = EdgeWalk::new(&e.curve, range);
    let along = check_params(c).into_iter().map(|t| {
        let q = at(t);
        let d = walk.distance(q);
        if d <= tolerance {
            d
        } else {
            d.min(distance_to_edge(&e.curve, dense(), q))
        }
    });
    ends.chain(along).fold(
        0.0,
        |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) },
    )
}
