//! Faces on analytic surfaces: the bounds mapped through the surface's
//! natural coordinates onto the NURBS, the loops of a face, and planes.

use super::full_turns::WindingFace;
use super::natural::{
    covers_box, natural_box, natural_polyline, shift_holes_next_to_outer,
    take_neighbour_angles_on_axis, unwrap_loop,
};
use super::{Analytic, Frame, NaturalBox, NaturalLoop, Periods};
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::step::p21::Instance;
use crate::io::step::read::curves::ToUv;
use crate::io::step::read::edges::EdgeUse;
use crate::io::step::read::pcurve::{CoordMap, PcurveMap};
use crate::io::step::read::{R, Reader, polyline};

impl<'a> Reader<'a> {
    /// The map of a p-curve's (u, v) on this surface (ISO 10303-42's
    /// parameters) to the parameters of its NURBS over `span`
    /// ([`super::pcurve`]).
    fn pcurve_map(&self, kind: &Analytic, to_uv: ToUv, span: NaturalBox) -> PcurveMap {
        let periods = kind.periods();
        let (scale, profile) = match kind {
            Analytic::Cylinder { .. } | Analytic::Cone { .. } => ([self.angle, 1.0], [None, None]),
            Analytic::Sphere { .. } | Analytic::Torus { .. } => {
                ([self.angle, self.angle], [None, None])
            }
            Analytic::Revolution { profile_angle, .. } => {
                let b = if profile_angle.is_some() {
                    self.angle
                } else {
                    1.0
                };
                ([self.angle, b], [None, *profile_angle])
            }
            Analytic::Extrusion {
                profile_angle,
                length,
                ..
            } => {
                let a = if profile_angle.is_some() {
                    self.angle
                } else {
                    1.0
                };
                ([a, *length], [*profile_angle, None])
            }
            Analytic::Plane => ([1.0, 1.0], [None, None]),
        };
        let centre = [0.5 * (span.a[0] + span.a[1]), 0.5 * (span.b[0] + span.b[1])];
        PcurveMap([0, 1].map(|c| CoordMap {
            scale: scale[c],
            profile: profile[c],
            arc: to_uv.0[c],
            period: periods[c],
            centre: centre[c],
        }))
    }

    /// An analytic face: natural coordinates of the bounds
    /// ([`Self::natural_loops`]), closed into one outer loop where they wind
    /// around the surface ([`Self::close_full_turns`]), the NURBS over the
    /// box they span ([`Self::analytic_nurbs`]), and the bounds mapped into
    /// its parameters. A sphere or torus face without edge loops is the
    /// whole surface.
    pub(in crate::io::step::read) fn analytic_face(
        &self,
        f: &Instance,
        si: &'a Instance,
        loops: &[(bool, Vec<EdgeUse>)],
        same_sense: bool,
    ) -> R<BSplineSurface> {
        let (frame, kind) = self.analytic(si)?;
        if loops.is_empty() {
            return self.whole_closed_surface(f, frame, &kind);
        }
        if let Analytic::Plane = kind {
            return self.plane_face(f, si.id, frame, loops);
        }
        let periods = kind.periods();
        let (unwrapped, starts) = self.natural_loops(frame, &kind, loops, periods);
        let turns = self.close_full_turns(f, &kind, periods, &unwrapped, same_sense)?;
        let (mut nat, outer_known) = match &turns {
            Some(closed) => (closed.loops.clone(), true),
            None => {
                let mut nat = unwrapped.clone();
                shift_holes_next_to_outer(&mut nat, periods);
                (nat, loops[0].0)
            }
        };
        let box_before = natural_box(&nat, periods)
            .ok_or_else(|| self.err(f, "the bounds enclose no area on the surface".into()))?;
        let span = self.shift_into_profile_domain(f, &kind, periods, &mut nat, box_before)?;
        let (surface, to_uv) = self.analytic_nurbs(f, frame, &kind, span)?;
        if let [outer] = nat.as_slice()
            && covers_box(outer, kind.nurbs_box(span))
        {
            // The face is the whole NURBS (a rectangle of natural
            // coordinates, e.g. a cylinder between two full circles).
            self.count_edges(loops.iter().map(|l| l.1.len()).sum());
            return Ok(surface);
        }
        let map = self.pcurve_map(&kind, to_uv, span);
        let trims = match &turns {
            None => loops
                .iter()
                .zip(&nat)
                .zip(&starts)
                .map(|(((_, edges), l), st)| {
                    self.analytic_loop(f, &surface, si.id, &map, to_uv, edges, l, st)
                })
                .collect::<R<Vec<_>>>()?,
            Some(closed) => {
                let face = WindingFace {
                    surface: &surface,
                    sid: si.id,
                    map: &map,
                    to_uv,
                    turns: closed,
                    unwrapped: &unwrapped,
                    starts: &starts,
                    moved: [span.a[0] - box_before.a[0], span.b[0] - box_before.b[0]],
                    cut: if closed.axis == 0 {
                        span.a[0]
                    } else {
                        span.b[0]
                    },
                };
                match self.winding_pcurve_loops(loops, &face)? {
                    Some(trims) => trims,
                    None => nat
                        .iter()
                        .map(|l| {
                            // The closed loops of `close_full_turns` end at
                            // the cut, not back at their first point: one
                            // curve must end where the loop starts (the
                            // trim's flattening closes the loop from the last
                            // curve's end).
                            let closed: Vec<(f64, f64)> = l
                                .iter()
                                .chain(l.first().filter(|&p| l.last() != Some(p)))
                                .copied()
                                .collect();
                            natural_polyline(&closed, to_uv).map(|c| TrimLoop { curves: vec![c] })
                        })
                        .collect::<Result<Vec<_>, String>>()
                        .map_err(|m| self.err(f, m))?,
                }
            }
        };
        self.attach(f, surface, trims, outer_known)
    }

    /// One loop of an analytic face: per edge, the trim curve from its
    /// p-curve where one agrees with the 3-D edge (see [`super::pcurve`]),
    /// else the edge's stretch `l[starts[k]..=starts[k + 1]]` of the loop
    /// computed from the 3-D edges. Without any p-curve used, the loop is
    /// the computed loop as one polyline.
    #[allow(clippy::too_many_arguments)]
    fn analytic_loop(
        &self,
        f: &Instance,
        surface: &BSplineSurface,
        sid: u64,
        map: &PcurveMap,
        to_uv: ToUv,
        edges: &[EdgeUse],
        l: &[(f64, f64)],
        starts: &[usize],
    ) -> R<TrimLoop> {
        let mut from_pcurves: Vec<Option<TrimCurve>> = Vec::with_capacity(edges.len());
        for (k, e) in edges.iter().enumerate() {
            let seg = l.get(starts[k]..=starts[k + 1]);
            let found = self.pcurve_trim(surface, sid, e, map, seg)?;
            from_pcurves.push(self.count_trim(e, found));
        }
        if from_pcurves.iter().all(Option::is_none) {
            let c = natural_polyline(l, to_uv).map_err(|m| self.err(f, m))?;
            return Ok(TrimLoop { curves: vec![c] });
        }
        let per_edge = from_pcurves
            .into_iter()
            .enumerate()
            .map(|(k, c)| match c {
                Some(c) => Ok(c),
                None => natural_polyline(&l[starts[k]..=starts[k + 1]], to_uv)
                    .map_err(|m| self.err(&self.ex.instances[&edges[k].edge], m)),
            })
            .collect::<R<Vec<_>>>()?;
        // Consecutive curves that do not meet — p-curves reaching a pole or
        // apex at their own angles — are joined by a segment along it (no
        // length in 3-D), so that the loop is closed in (u, v) too.
        let ([u0, u1], [v0, v1]) = (surface.domain_u(), surface.domain_v());
        let gap = 1e-9 * (u1 - u0).hypot(v1 - v0);
        let n = per_edge.len();
        let mut curves = Vec::with_capacity(n + 2);
        for (k, c) in per_edge.iter().enumerate() {
            curves.push(c.clone());
            let next = &per_edge[(k + 1) % n];
            let (end, start) = (c.eval(c.domain()[1]), next.eval(next.domain()[0]));
            if (end[0] - start[0]).hypot(end[1] - start[1]) > gap {
                curves.push(TrimCurve::line(end, start).map_err(|m| self.err(f, m))?);
            }
        }
        Ok(TrimLoop { curves })
    }

    /// The natural coordinates `(a, b)` of every loop (the edges' dense
    /// points, see [`Analytic::natural`]): points on the axis take the angle
    /// of a neighbour, and angles are unwrapped along the loop, so that a
    /// loop winding around a period ends a period from where it started.
    /// Also, per loop, where each edge starts in it (and, last, where the
    /// last edge ends): edge `k` is `loop[starts[k]..=starts[k + 1]]`.
    fn natural_loops(
        &self,
        frame: Frame,
        kind: &Analytic,
        loops: &[(bool, Vec<EdgeUse>)],
        periods: Periods,
    ) -> (Vec<NaturalLoop>, Vec<Vec<usize>>) {
        let mut nat: Vec<NaturalLoop> = Vec::with_capacity(loops.len());
        let mut starts: Vec<Vec<usize>> = Vec::with_capacity(loops.len());
        for (_, edges) in loops {
            let mut pts: Vec<(f64, f64, bool)> = Vec::new();
            let mut st = Vec::with_capacity(edges.len() + 1);
            for e in edges {
                let mut ep: Vec<(f64, f64, bool)> = self
                    .edge_points(e)
                    .into_iter()
                    .map(|q| kind.natural(frame, q))
                    .collect();
                if !pts.is_empty() {
                    ep.remove(0);
                }
                st.push(pts.len().saturating_sub(1));
                pts.extend(ep);
            }
            st.push(pts.len().saturating_sub(1));
            take_neighbour_angles_on_axis(&mut pts);
            nat.push(unwrap_loop(&pts, periods));
            starts.push(st);
        }
        (nat, starts)
    }

    /// A planar face: a bilinear patch over the bounds' box in the plane's
    /// frame, the bounds mapped exactly (affine map of their NURBS); an
    /// edge's p-curve on the plane (ISO's (u, v) are the frame's
    /// coordinates) replaces it where it agrees with the 3-D edge.
    fn plane_face(
        &self,
        f: &Instance,
        sid: u64,
        (o, x, y, _z): Frame,
        loops: &[(bool, Vec<EdgeUse>)],
    ) -> R<BSplineSurface> {
        let local = |q: Vec3| [(q - o).dot(x), (q - o).dot(y)];
        let mut curves: Vec<Vec<TrimCurve>> = Vec::new();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (_, edges) in loops {
            let mut l = Vec::new();
            for e in edges {
                let c = match self.edge_nurbs(e) {
                    Some(n) => TrimCurve::new(
                        n.degree,
                        n.knots,
                        n.points.iter().map(|q| local(*q)).collect(),
                        n.weights,
                    ),
                    None => {
                        let pts: Vec<[f64; 2]> =
                            self.edge_points(e).into_iter().map(local).collect();
                        polyline(&pts)
                    }
                }
                .map_err(|m| self.err(&self.ex.instances[&e.edge], m))?;
                for q in self.edge_points(e) {
                    let [a, b] = local(q);
                    lo = [lo[0].min(a), lo[1].min(b)];
                    hi = [hi[0].max(a), hi[1].max(b)];
                }
                l.push(c);
            }
            curves.push(l);
        }
        if hi[0] <= lo[0] || hi[1] <= lo[1] {
            return Err(self.err(f, "the bounds enclose no area".into()));
        }
        let corner = |a: f64, b: f64| o + a * x + b * y;
        let s = BSplineSurface::from_flat(
            1,
            1,
            vec![lo[0], lo[0], hi[0], hi[0]],
            vec![lo[1], lo[1], hi[1], hi[1]],
            [2, 2],
            vec![
                corner(lo[0], lo[1]),
                corner(lo[0], hi[1]),
                corner(hi[0], lo[1]),
                corner(hi[0], hi[1]),
            ],
            None,
        )
        .map_err(|e| self.err(f, e.to_string()))?;
        for ((_, edges), l) in loops.iter().zip(curves.iter_mut()) {
            for (e, c) in edges.iter().zip(l.iter_mut()) {
                let found = self.pcurve_trim(&s, sid, e, &PcurveMap::IDENTITY, None)?;
                if let Some(p) = self.count_trim(e, found) {
                    *c = p;
                }
            }
        }
        let trims = curves
            .into_iter()
            .map(|curves| TrimLoop { curves })
            .collect();
        self.attach(f, s, trims, loops[0].0)
    }
}
