//! Faces whose bounds wind fully around a periodic direction (a band of a
//! cylinder, a face of a torus): the turns closed into loops of the NURBS.

use super::natural::{St, cut_between_holes, recut, turns};
use super::{Analytic, NaturalLoop, Periods};
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::step::p21::Instance;
use crate::io::step::read::curves::ToUv;
use crate::io::step::read::edges::EdgeUse;
use crate::io::step::read::pcurve::{PcurveMap, PcurveUse};
use crate::io::step::read::{R, Reader};

impl<'a> Reader<'a> {
    /// The loops of a face bounded by bounds that wind around its surface
    /// ([`Self::close_full_turns`]) from the edges' p-curves: used when
    /// the face has no hole, every winding bound has a vertex on the cut
    /// (`s = cut`, where the NURBS's periodic coordinate begins; so that no
    /// p-curve crosses it) and every edge's p-curve agrees with its 3-D
    /// edge. Each edge's p-curve is placed in the period whose middle of
    /// the edge lies in `[cut, cut + period)`; the outer loop is the first
    /// bound's curves from the cut round to it, a segment along the cut,
    /// the second bound's curves back (or, for one bound, segments through
    /// the pole or apex), a segment along the cut. `None` (counted as
    /// trims from the 3-D edges, rejected p-curves named in the warning)
    /// otherwise.
    pub(super) fn winding_pcurve_loops(
        &self,
        loops: &[(bool, Vec<EdgeUse>)],
        w: &WindingFace,
    ) -> R<Option<Vec<TrimLoop>>> {
        let all_edges = loops.iter().map(|l| l.1.len()).sum();
        let t = w.turns;
        let on_cut = |x: f64| {
            let d = (x - w.cut).rem_euclid(t.period);
            d.min(t.period - d) <= 1e-9 * t.period
        };
        let aligned = t.bands.iter().all(|b| {
            let l = &w.unwrapped[b.index];
            w.starts[b.index][..loops[b.index].1.len()]
                .iter()
                .any(|&k| on_cut(if t.axis == 0 { l[k].0 } else { l[k].1 } + w.moved[t.axis]))
        });
        if t.has_holes || !aligned {
            self.count_edges(all_edges);
            return Ok(None);
        }
        // Per band: the p-curves of its edges, placed by their stretches.
        let mut found: Vec<Vec<(usize, PcurveUse)>> = Vec::with_capacity(t.bands.len());
        for b in &t.bands {
            let l = &w.unwrapped[b.index];
            let st = &w.starts[b.index];
            let mut uses = Vec::new();
            for (k, e) in loops[b.index].1.iter().enumerate() {
                let seg = w.placed_stretch(&l[st[k]..=st[k + 1]], b.t_shift);
                uses.push((k, self.pcurve_trim(w.surface, w.sid, e, w.map, Some(&seg))?));
            }
            found.push(uses);
        }
        let used: Option<Vec<Vec<TrimCurve>>> = found
            .iter()
            .map(|uses| {
                uses.iter()
                    .map(|(_, u)| match u {
                        PcurveUse::Used(c) => Some(c.clone()),
                        _ => None,
                    })
                    .collect()
            })
            .collect();
        let outer = used.and_then(|bands| w.outer_loop(bands));
        for (b, uses) in t.bands.iter().zip(found) {
            for (k, u) in uses {
                let e = &loops[b.index].1[k];
                match (&outer, &u) {
                    (Some(_), _) | (None, PcurveUse::Rejected { .. }) => {
                        self.count_trim(e, u);
                    }
                    _ => self.count_edges(1),
                }
            }
        }
        Ok(outer.map(|curves| vec![TrimLoop { curves }]))
    }

    /// Faces bounded without a seam edge (ISO 10303-42 allows a periodic
    /// face to be bounded by loops that wind around its axis): a cylinder
    /// between two full circles, a sphere cap bounded by one circle. The
    /// winding bounds close into one outer loop of the face cut open along
    /// `s = cut` (`s` the coordinate they wind in): two winding bounds join
    /// along the cut; one is closed through the pole (sphere), the apex
    /// (cone) or the profile's end (surface of revolution) on the face's
    /// side. The face lies on the side of its bounds that `n × t` points to
    /// (`t` the bound's direction, `n` the face normal: the surface normal
    /// `S_a × S_b`, reversed when the face's `same_sense` is false). Bounds
    /// that do not wind stay holes, and the cut passes between them.
    /// `None` when no bound winds.
    pub(super) fn close_full_turns(
        &self,
        f: &Instance,
        kind: &Analytic,
        periods: Periods,
        nat: &[NaturalLoop],
        same_sense: bool,
    ) -> R<Option<FullTurns>> {
        let windings: Vec<[i64; 2]> = nat.iter().map(|l| turns(l, periods)).collect();
        if windings.iter().all(|w| *w == [0, 0]) {
            return Ok(None);
        }
        if windings
            .iter()
            .any(|w| w[0].abs() > 1 || w[1].abs() > 1 || (w[0] != 0 && w[1] != 0))
        {
            return Err(self.err(
                f,
                "a bound winds around the surface more than once or in both directions (not supported)".into(),
            ));
        }
        let axis = usize::from(windings.iter().all(|w| w[0] == 0));
        let other = 1 - axis;
        if windings.iter().any(|w| w[other] != 0) {
            return Err(self.err(
                f,
                "bounds wind around the surface in both directions (not supported)".into(),
            ));
        }
        let period = periods[axis].ok_or_else(|| {
            self.err(
                f,
                "a bound winds around a coordinate that does not wrap".into(),
            )
        })?;
        // (a, b) <-> (s, t): s is the coordinate the bounds wind in.
        let swap = |p: (f64, f64)| if axis == 0 { p } else { (p.1, p.0) };
        // In the (s, t) plane the face is left of its bounds when the face
        // normal agrees with the surface's and (s, t) = (a, b), or neither.
        let face_left = same_sense == (axis == 0);
        let mut bands: Vec<(Vec<St>, f64)> = Vec::new();
        let mut band_loops: Vec<Band> = Vec::new();
        let mut holes: Vec<Vec<St>> = Vec::new();
        for (index, (l, w)) in nat.iter().zip(&windings).enumerate() {
            let mut st: Vec<St> = l.iter().map(|&p| swap(p)).collect();
            if w[axis] == 0 {
                holes.push(st);
                continue;
            }
            let increasing = w[axis] > 0;
            if !increasing {
                st.reverse();
            }
            band_loops.push(Band {
                index,
                increasing,
                t_shift: 0.0,
            });
            // Left of a bound running towards +s is +t.
            let side = if face_left == increasing { 1.0 } else { -1.0 };
            bands.push((st, side));
        }
        let first_s = bands.first().and_then(|b| b.0.first()).map_or(0.0, |p| p.0);
        let cut = cut_between_holes(&holes, period, first_s);
        for h in &mut holes {
            let lo = h.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let shift = period * ((cut - lo) / period).ceil();
            for p in h.iter_mut() {
                p.0 += shift;
            }
        }
        let mean_t = |l: &[St]| l.iter().map(|p| p.1).sum::<f64>() / l.len().max(1) as f64;
        let mut pole = None;
        let outer: Vec<St> = match bands.as_slice() {
            [(first, side), (second, _)] => {
                let a = recut(first, cut, period);
                let mut b = recut(second, cut, period);
                if let Some(pt) = periods[other] {
                    // The second bound on the face's side of the first.
                    let d = mean_t(&b) - mean_t(&a);
                    let dm = d.rem_euclid(pt);
                    let want = if *side > 0.0 { dm } else { dm - pt };
                    for p in &mut b {
                        p.1 += want - d;
                    }
                    band_loops[1].t_shift = want - d;
                }
                b.reverse();
                a.into_iter().chain(b).collect()
            }
            [(only, side)] => {
                let mut a = recut(only, cut, period);
                let t = self.pole(f, kind, axis, *side, mean_t(&a))?;
                pole = Some(t);
                a.push((cut + period, t));
                a.push((cut, t));
                a
            }
            _ => {
                return Err(self.err(
                    f,
                    format!(
                        "{} bounds wind around the surface (one or two are supported)",
                        bands.len()
                    ),
                ));
            }
        };
        let has_holes = !holes.is_empty();
        let mut out = vec![outer];
        out.extend(holes);
        Ok(Some(FullTurns {
            loops: out
                .into_iter()
                .map(|l| l.into_iter().map(swap).collect())
                .collect(),
            axis,
            period,
            bands: band_loops,
            pole,
            has_holes,
        }))
    }
}

/// How [`Reader::close_full_turns`] closed the bounds that wind around a
/// face's surface.
pub(super) struct FullTurns {
    /// The natural loops: the outer loop first, then the holes.
    pub(super) loops: Vec<NaturalLoop>,
    /// The coordinate the bounds wind in (0: a, 1: b; called `s`, the
    /// other `t`) and its period.
    pub(super) axis: usize,
    period: f64,
    /// The winding bounds in the outer loop's order.
    bands: Vec<Band>,
    /// Where a single winding bound is closed (its `t`: pole, apex).
    pole: Option<f64>,
    /// Bounds that do not wind stay holes.
    has_holes: bool,
}

/// A bound that winds around the surface.
struct Band {
    /// Its index among the face's bounds.
    index: usize,
    /// It runs towards increasing `s`.
    increasing: bool,
    /// The whole periods its `t` was moved by (the second bound of a torus
    /// face, onto the face's side of the first).
    t_shift: f64,
}

/// What [`Reader::winding_pcurve_loops`] works with.
pub(super) struct WindingFace<'w> {
    pub(super) surface: &'w BSplineSurface,
    pub(super) sid: u64,
    pub(super) map: &'w PcurveMap,
    pub(super) to_uv: ToUv,
    pub(super) turns: &'w FullTurns,
    /// The bounds' natural coordinates before closing, and where each edge
    /// starts in them ([`Reader::natural_loops`]).
    pub(super) unwrapped: &'w [NaturalLoop],
    pub(super) starts: &'w [Vec<usize>],
    /// How far the loops were moved into a swept profile's domain, per
    /// natural coordinate.
    pub(super) moved: [f64; 2],
    /// Where the NURBS's `s` begins (the cut, after that move).
    pub(super) cut: f64,
}

impl WindingFace<'_> {
    /// An edge's stretch of its bound moved as the bound was (`t` by the
    /// band's whole periods, both by the profile-domain move) and its `s`
    /// by whole periods into `[cut, cut + period)` at its middle.
    fn placed_stretch(&self, seg: &[(f64, f64)], t_shift: f64) -> Vec<(f64, f64)> {
        let (axis, period) = (self.turns.axis, self.turns.period);
        let moved: Vec<[f64; 2]> = seg
            .iter()
            .map(|&(a, b)| {
                let mut p = [a + self.moved[0], b + self.moved[1]];
                p[1 - axis] += t_shift;
                p
            })
            .collect();
        let mean = moved.iter().map(|p| p[axis]).sum::<f64>() / moved.len().max(1) as f64;
        let whole = period * ((self.cut - mean) / period).ceil();
        moved
            .into_iter()
            .map(|mut p| {
                p[axis] += whole;
                (p[0], p[1])
            })
            .collect()
    }

    /// The outer loop from the bands' trim curves (per band in its edges'
    /// traversal order): the first band running towards `+s` from the
    /// cut, the second towards `−s` from the cut a period on (or the pole
    /// segments), consecutive curves that do not meet joined by segments
    /// (along the cut). `None` when a band has no curve starting on the cut.
    fn outer_loop(&self, bands: Vec<Vec<TrimCurve>>) -> Option<Vec<TrimCurve>> {
        let axis = self.turns.axis;
        let [lo, hi] = if axis == 0 {
            self.surface.domain_u()
        } else {
            self.surface.domain_v()
        };
        let near = |x: f64, y: f64| (x - y).abs() <= 1e-9 * (hi - lo);
        let mut chain: Vec<TrimCurve> = Vec::new();
        for (k, (b, mut curves)) in self.turns.bands.iter().zip(bands).enumerate() {
            // The first band towards +s, the second towards −s.
            if b.increasing != (k == 0) {
                curves.reverse();
                curves = curves
                    .iter()
                    .map(|c| c.reversed().ok())
                    .collect::<Option<_>>()?;
            }
            let from = if k == 0 { lo } else { hi };
            let first = curves
                .iter()
                .position(|c| near(c.eval(c.domain()[0])[axis], from))?;
            curves.rotate_left(first);
            chain.extend(curves);
        }
        if let Some(pole) = self.turns.pole {
            let t = pole + self.moved[1 - axis];
            let at = |s: f64| {
                let n = if axis == 0 { (s, t) } else { (t, s) };
                self.to_uv.at(n.0, n.1)
            };
            let (cut, period) = (self.cut, self.turns.period);
            chain.push(TrimCurve::line(at(cut + period), at(cut)).ok()?);
        }
        let ([u0, u1], [v0, v1]) = (self.surface.domain_u(), self.surface.domain_v());
        let gap = 1e-9 * (u1 - u0).hypot(v1 - v0);
        let n = chain.len();
        let mut out = Vec::with_capacity(n + 2);
        for (k, c) in chain.iter().enumerate() {
            out.push(c.clone());
            let next = &chain[(k + 1) % n];
            let (end, start) = (c.eval(c.domain()[1]), next.eval(next.domain()[0]));
            if (end[0] - start[0]).hypot(end[1] - start[1]) > gap {
                out.push(TrimCurve::line(end, start).ok()?);
            }
        }
        Some(out)
    }
}
