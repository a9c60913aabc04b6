//! Analytic faces: `PLANE`, `CYLINDRICAL_SURFACE`, `CONICAL_SURFACE`,
//! `SPHERICAL_SURFACE`, `TOROIDAL_SURFACE`, `SURFACE_OF_REVOLUTION` and
//! `SURFACE_OF_LINEAR_EXTRUSION` (ISO 10303-42 §4.4), and `OFFSET_SURFACE`
//! (§4.4.14) of a plane, cylinder, sphere or torus (the surface of the same
//! kind moved or with its radius grown by the distance, on the basis's
//! parameters), converted exactly to
//! NURBS over the part of the surface the face's bounds span, the bounds
//! mapped into the NURBS parameters through the surface's natural
//! coordinates (see the parent module).

use std::f64::consts::FRAC_PI_2;

use super::curves::{Curve, ToUv, nearest_param};
use super::edges::EdgeUse;
use super::pcurve::CoordMap;
use super::*;
use crate::bspline::polygon_signed_area2;

/// What an analytic surface is, in its placement frame `(o, x, y, z)`.
#[derive(Clone, Debug)]
enum Analytic {
    Plane,
    Cylinder {
        r: f64,
    },
    Cone {
        r: f64,
        tan: f64,
    },
    Sphere {
        r: f64,
    },
    Torus {
        big: f64,
        small: f64,
    },
    /// `profile_angle`: a conic profile's angle → its NURBS parameter.
    Revolution {
        profile: Nurbs3,
        profile_angle: Option<ArcMap>,
    },
    /// `d` the unit direction, `length` the extrusion vector's length
    /// (ISO's v runs along `length · d`).
    Extrusion {
        profile: Nurbs3,
        profile_angle: Option<ArcMap>,
        d: Vec3,
        length: f64,
    },
}

/// A placement frame: origin and the axes x, y, z.
type Frame = (Vec3, Vec3, Vec3, Vec3);

/// Periods of the natural coordinates `(a, b)`: angles wrap by 2π, the
/// parameter of a closed swept profile by its domain length; `None` where a
/// coordinate does not wrap.
type Periods = [Option<f64>; 2];

/// The natural coordinates `(a, b)` of the points of one bound, angles
/// unwrapped along it.
type NaturalLoop = Vec<(f64, f64)>;

/// The box `[a0, a1] × [b0, b1]` of natural coordinates a face spans.
#[derive(Clone, Copy, Debug, PartialEq)]
struct NaturalBox {
    a: [f64; 2],
    b: [f64; 2],
}

impl Analytic {
    /// The natural box the NURBS of [`Reader::analytic_nurbs`] spans over
    /// `span`: the whole profile of a swept surface in its coordinate.
    fn nurbs_box(&self, span: NaturalBox) -> NaturalBox {
        match self {
            Analytic::Revolution { profile, .. } => NaturalBox {
                b: profile.domain(),
                ..span
            },
            Analytic::Extrusion { profile, .. } => NaturalBox {
                a: profile.domain(),
                ..span
            },
            _ => span,
        }
    }

    /// See [`Periods`].
    fn periods(&self) -> Periods {
        // closed: the ends meet to rounding of the profile's size (a full
        // circle's ends differ by sin 2π)
        let closed_period = |n: &Nurbs3| {
            let [t0, t1] = n.domain();
            let (first, last) = (n.points.first()?, n.points.last()?);
            let size = n
                .points
                .iter()
                .map(|p| p.distance(*first))
                .fold(0.0, f64::max);
            (first.distance(*last) <= 1e-12 * size.max(f64::MIN_POSITIVE)).then_some(t1 - t0)
        };
        match self {
            Analytic::Torus { .. } => [Some(TAU), Some(TAU)],
            Analytic::Revolution { profile, .. } => [Some(TAU), closed_period(profile)],
            Analytic::Extrusion { profile, .. } => [closed_period(profile), None],
            _ => [Some(TAU), None],
        }
    }

    /// The natural coordinates `(a, b)` of a point `q` of the surface in its
    /// frame `(o, x, y, z)` — ISO 10303-42's parameters of the elementary
    /// surfaces: `a` the angle about the axis (the profile parameter of an
    /// extrusion); `b` the height (cylinder, cone), the latitude (sphere),
    /// the minor angle (torus), the profile parameter (revolution) or the
    /// distance along the extrusion — and whether `q` lies on the axis, where
    /// the angle is undefined.
    fn natural(&self, (o, x, y, z): Frame, q: Vec3) -> (f64, f64, bool) {
        let d = q - o;
        let (lx, ly, h) = (d.dot(x), d.dot(y), d.dot(z));
        let rho = lx.hypot(ly);
        let on_axis = rho <= 1e-12 * (1.0 + d.length());
        let a = ly.atan2(lx);
        match self {
            Analytic::Cylinder { .. } | Analytic::Cone { .. } => (a, h, on_axis),
            Analytic::Sphere { .. } => (a, h.atan2(rho), on_axis),
            Analytic::Torus { big, .. } => (a, h.atan2(rho - big), on_axis),
            Analytic::Revolution { profile, .. } => {
                let [t0, t1] = profile.domain();
                let t = nearest_param(t0, t1, (16 * profile.points.len()).min(2000), |t| {
                    let p = profile.eval(t) - o;
                    let ph = p.dot(z);
                    let pr = (p - ph * z).length();
                    (pr - rho).hypot(ph - h)
                });
                (a, t, on_axis)
            }
            Analytic::Extrusion {
                profile, d: dir, ..
            } => {
                let [t0, t1] = profile.domain();
                let perp = |v: Vec3| v - v.dot(*dir) * *dir;
                let t = nearest_param(t0, t1, (16 * profile.points.len()).min(2000), |t| {
                    perp(q - profile.eval(t)).length()
                });
                (t, (q - profile.eval(t)).dot(*dir), false)
            }
            Analytic::Plane => (lx, ly, false),
        }
    }
}

/// `x` shifted by whole periods to within half a period of `near`.
fn wrap(x: f64, near: f64, period: Option<f64>) -> f64 {
    match period {
        Some(p) if p > 0.0 => x + p * ((near - x) / p).round(),
        _ => x,
    }
}

/// Points on the axis (angle undefined) take the angle of the point before
/// them, going round the loop from the first point off the axis.
fn take_neighbour_angles_on_axis(pts: &mut [(f64, f64, bool)]) {
    if let Some(k) = pts.iter().position(|p| !p.2) {
        let n = pts.len();
        for s in 1..n {
            let (prev, cur) = ((k + s - 1) % n, (k + s) % n);
            if pts[cur].2 {
                pts[cur].0 = pts[prev].0;
            }
        }
    }
}

/// The loop with each coordinate shifted by whole periods to within half a
/// period of the point before it.
fn unwrap_loop(pts: &[(f64, f64, bool)], periods: Periods) -> NaturalLoop {
    let mut out: NaturalLoop = Vec::with_capacity(pts.len());
    for &(a, b, _) in pts {
        let (mut a, mut b) = (a, b);
        if let Some(&(pa, pb)) = out.last() {
            a = wrap(a, pa, periods[0]);
            b = wrap(b, pb, periods[1]);
        }
        out.push((a, b));
    }
    out
}

/// Holes shifted by whole periods next to the outer loop (their mean
/// within half a period of the outer loop's).
fn shift_holes_next_to_outer(nat: &mut [NaturalLoop], periods: Periods) {
    let mean = |l: &[(f64, f64)]| {
        let n = l.len().max(1) as f64;
        (
            l.iter().map(|p| p.0).sum::<f64>() / n,
            l.iter().map(|p| p.1).sum::<f64>() / n,
        )
    };
    let Some(outer) = nat.first() else { return };
    let (ma, mb) = mean(outer);
    for l in nat.iter_mut().skip(1) {
        let (la, lb) = mean(l);
        let (sa, sb) = (wrap(la, ma, periods[0]) - la, wrap(lb, mb, periods[1]) - lb);
        for p in l.iter_mut() {
            p.0 += sa;
            p.1 += sb;
        }
    }
}

/// The box of all loops' natural coordinates, each side at most one period
/// long; `None` when it encloses no area or spans more than a period.
fn natural_box(nat: &[NaturalLoop], periods: Periods) -> Option<NaturalBox> {
    let (mut a0, mut a1, mut b0, mut b1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(a, b) in nat.iter().flatten() {
        a0 = a0.min(a);
        a1 = a1.max(a);
        b0 = b0.min(b);
        b1 = b1.max(b);
    }
    let too_wide =
        |lo: f64, hi: f64, period: Option<f64>| period.is_some_and(|p| hi - lo > p * (1.0 + 1e-9));
    if a1 <= a0 || b1 <= b0 || too_wide(a0, a1, periods[0]) || too_wide(b0, b1, periods[1]) {
        return None;
    }
    let clip = |lo: f64, hi: f64, period: Option<f64>| period.map_or(hi, |p| hi.min(lo + p));
    Some(NaturalBox {
        a: [a0, clip(a0, a1, periods[0])],
        b: [b0, clip(b0, b1, periods[1])],
    })
}

/// Most nested `OFFSET_SURFACE`s followed to their basis.
const MAX_OFFSET_DEPTH: usize = 8;

impl<'a> Reader<'a> {
    fn analytic(&self, si: &'a Instance) -> R<(Frame, Analytic)> {
        if si.is("OFFSET_SURFACE") {
            return self.offset_analytic(si);
        }
        let t = si.type_name();
        let p = self.params(
            si,
            &[
                "PLANE",
                "CYLINDRICAL_SURFACE",
                "CONICAL_SURFACE",
                "SPHERICAL_SURFACE",
                "TOROIDAL_SURFACE",
                "SURFACE_OF_REVOLUTION",
                "SURFACE_OF_LINEAR_EXTRUSION",
            ],
        )
        .map_err(|_| {
            self.err(
                si,
                format!("surface type {t} is not supported (B_SPLINE_SURFACE_WITH_KNOTS, PLANE, CYLINDRICAL_SURFACE, CONICAL_SURFACE, SPHERICAL_SURFACE, TOROIDAL_SURFACE, SURFACE_OF_REVOLUTION, SURFACE_OF_LINEAR_EXTRUSION are)"),
            )
        })?;
        let positive = |x: f64, what: &str| -> R<f64> {
            if x > 0.0 && x.is_finite() {
                Ok(x)
            } else {
                Err(self.err(si, format!("the {what} {x} is not positive")))
            }
        };
        match t {
            "SURFACE_OF_REVOLUTION" => {
                let ci = self.refer(si, p, 1)?;
                let curve = self.curve(ci)?;
                let ax = self.refer(si, p, 2)?;
                let axp = self.params(ax, &["AXIS1_PLACEMENT"])?;
                let o = self.point(self.refer(ax, axp, 1)?)?;
                let z = match axp.get(2) {
                    Some(Value::Ref(_)) => self.direction(self.refer(ax, axp, 2)?)?,
                    _ => Vec3::Z,
                };
                let profile = self.whole_nurbs(ci, &curve)?;
                // The reference direction: where the profile lies.
                let rho = profile
                    .points
                    .iter()
                    .map(|q| (*q - o) - (*q - o).dot(z) * z)
                    .find(|r| r.length() > 1e-9 * (1.0 + (*r).length()))
                    .ok_or_else(|| self.err(si, "the profile lies on the axis".into()))?
                    .normalize();
                Ok((
                    (o, rho, z.cross(rho), z),
                    Analytic::Revolution {
                        profile,
                        profile_angle: self.profile_angle(&curve),
                    },
                ))
            }
            "SURFACE_OF_LINEAR_EXTRUSION" => {
                let ci = self.refer(si, p, 1)?;
                let curve = self.curve(ci)?;
                let v = self.refer(si, p, 2)?;
                let vp = self.params(v, &["VECTOR"])?;
                let d = self.direction(self.refer(v, vp, 1)?)?;
                let length = self.num(v, vp, 2)?;
                let profile = self.whole_nurbs(ci, &curve)?;
                Ok((
                    (Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z),
                    Analytic::Extrusion {
                        profile,
                        profile_angle: self.profile_angle(&curve),
                        d,
                        length,
                    },
                ))
            }
            _ => {
                let frame = self.placement(self.refer(si, p, 1)?)?;
                let kind = match t {
                    "PLANE" => Analytic::Plane,
                    "CYLINDRICAL_SURFACE" => Analytic::Cylinder {
                        r: positive(self.num(si, p, 2)?, "radius")?,
                    },
                    "CONICAL_SURFACE" => {
                        let a = self.num(si, p, 3)? * self.angle;
                        if a.abs() >= 0.5 * PI - 1e-9 {
                            return Err(self.err(si, format!("semi-angle {a} rad")));
                        }
                        Analytic::Cone {
                            r: self.num(si, p, 2)?,
                            tan: a.tan(),
                        }
                    }
                    "SPHERICAL_SURFACE" => Analytic::Sphere {
                        r: positive(self.num(si, p, 2)?, "radius")?,
                    },
                    _ => Analytic::Torus {
                        big: positive(self.num(si, p, 2)?, "major radius")?,
                        small: positive(self.num(si, p, 3)?, "minor radius")?,
                    },
                };
                Ok((frame, kind))
            }
        }
    }

    /// An `OFFSET_SURFACE` (ISO 10303-42 §4.4.14: the basis moved by the
    /// distance along its normal, on its parameters) of an elementary
    /// surface whose offset is of its own kind with the same parameters: a
    /// plane moved along its normal, a cylinder or sphere with radius
    /// r + d, a torus with minor radius r + d (the normals of ISO's
    /// elementary surfaces point away from the axis or centre). Nested
    /// offsets add up. Other bases (a cone, whose offset moves its height
    /// parameter; a swept or B-spline surface) and a radius that would not
    /// stay positive are refused, naming the entity.
    fn offset_analytic(&self, si: &'a Instance) -> R<(Frame, Analytic)> {
        let (mut basis, mut d) = (si, 0.0);
        for _ in 0..MAX_OFFSET_DEPTH {
            if !basis.is("OFFSET_SURFACE") {
                break;
            }
            let p = self.params(basis, &["OFFSET_SURFACE"])?;
            d += self.num(basis, p, 2)?;
            basis = self.refer(basis, p, 1)?;
        }
        if basis.is("OFFSET_SURFACE") {
            return Err(self.err(
                si,
                format!("more than {MAX_OFFSET_DEPTH} nested offset surfaces"),
            ));
        }
        let t = basis.type_name();
        let ((o, x, y, z), kind) = match t {
            "PLANE" | "CYLINDRICAL_SURFACE" | "SPHERICAL_SURFACE" | "TOROIDAL_SURFACE" => {
                self.analytic(basis)?
            }
            _ => {
                return Err(self.err(
                    si,
                    format!("an offset of a {t} is not supported (offsets of PLANE, CYLINDRICAL_SURFACE, SPHERICAL_SURFACE and TOROIDAL_SURFACE are)"),
                ));
            }
        };
        let grown = |r: f64| -> R<f64> {
            let g = r + d;
            if g > 0.0 && g.is_finite() {
                Ok(g)
            } else {
                Err(self.err(
                    si,
                    format!("the offset {d} leaves the radius {r} at {g}, not positive"),
                ))
            }
        };
        Ok(match kind {
            Analytic::Plane => ((o + d * z, x, y, z), Analytic::Plane),
            Analytic::Cylinder { r } => ((o, x, y, z), Analytic::Cylinder { r: grown(r)? }),
            Analytic::Sphere { r } => ((o, x, y, z), Analytic::Sphere { r: grown(r)? }),
            Analytic::Torus { big, small } => (
                (o, x, y, z),
                Analytic::Torus {
                    big,
                    small: grown(small)?,
                },
            ),
            _ => return Err(self.err(si, format!("an offset of a {t} is not supported"))),
        })
    }

    /// The map of a conic profile's angle to the parameter of its NURBS
    /// ([`Self::whole_nurbs`]); `None` for B-spline profiles (same
    /// parameter).
    fn profile_angle(&self, c: &Curve) -> Option<ArcMap> {
        matches!(c, Curve::Conic { .. }).then(|| ArcMap::new(0.0, TAU, 1.0))
    }

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

    /// A swept surface's whole basis curve as NURBS.
    fn whole_nurbs(&self, ci: &Instance, c: &Curve) -> R<Nurbs3> {
        match c {
            Curve::Spline(n) => Ok(n.clone()),
            Curve::Conic { c, x, y, rx, ry } => Ok(ellipse_arc(
                *c,
                *x,
                *y,
                *rx,
                *ry,
                &ArcMap::new(0.0, TAU, 1.0),
            )),
            Curve::Line { .. } => Err(self.err(
                ci,
                "an unbounded LINE cannot be swept into a bounded surface".into(),
            )),
        }
    }

    /// An analytic face: natural coordinates of the bounds
    /// ([`Self::natural_loops`]), closed into one outer loop where they wind
    /// around the surface ([`Self::close_full_turns`]), the NURBS over the
    /// box they span ([`Self::analytic_nurbs`]), and the bounds mapped into
    /// its parameters. A sphere or torus face without edge loops is the
    /// whole surface.
    pub(super) fn analytic_face(
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
    fn winding_pcurve_loops(
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
    fn close_full_turns(
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

    /// Where a face bounded by one winding bound closes, on the face's side
    /// (`side`, ±1 in t) of the bound at mean `t`: the pole of a sphere, the
    /// apex of a cone, the end of a surface of revolution's profile.
    fn pole(&self, f: &Instance, kind: &Analytic, axis: usize, side: f64, t: f64) -> R<f64> {
        let unbounded = || {
            self.err(
                f,
                "a single bound winds around the surface and the face's side of it is unbounded"
                    .into(),
            )
        };
        if axis != 0 {
            return Err(unbounded());
        }
        match kind {
            Analytic::Sphere { .. } => Ok(side * FRAC_PI_2),
            Analytic::Cone { r, tan } if *tan != 0.0 => {
                let apex = -r / tan;
                if (apex - t) * side > 0.0 {
                    Ok(apex)
                } else {
                    Err(unbounded())
                }
            }
            Analytic::Revolution { profile, .. } => {
                let [t0, t1] = profile.domain();
                Ok(if side > 0.0 { t1 } else { t0 })
            }
            _ => Err(unbounded()),
        }
    }

    /// A face with no edge loop on a closed surface: the whole sphere or
    /// torus, untrimmed.
    fn whole_closed_surface(
        &self,
        f: &Instance,
        frame: Frame,
        kind: &Analytic,
    ) -> R<BSplineSurface> {
        let b = match kind {
            Analytic::Sphere { .. } => [-FRAC_PI_2, FRAC_PI_2],
            Analytic::Torus { .. } => [-PI, PI],
            _ => {
                return Err(self.err(
                    f,
                    "a face on an open surface needs at least one edge loop".into(),
                ));
            }
        };
        let span = NaturalBox { a: [-PI, PI], b };
        Ok(self.analytic_nurbs(f, frame, kind, span)?.0)
    }

    /// A swept profile's parameter must stay in its domain: shifts the
    /// loops and their box by whole periods into it, or refuses a face
    /// across the profile's seam. Other surfaces are returned unchanged.
    fn shift_into_profile_domain(
        &self,
        f: &Instance,
        kind: &Analytic,
        periods: Periods,
        nat: &mut [NaturalLoop],
        span: NaturalBox,
    ) -> R<NaturalBox> {
        let NaturalBox {
            a: [mut a0, mut a1],
            b: [mut b0, mut b1],
        } = span;
        let profile_coordinate = match kind {
            Analytic::Revolution { profile, .. } => Some((1, profile.domain(), periods[1])),
            Analytic::Extrusion { profile, .. } => Some((0, profile.domain(), periods[0])),
            _ => None,
        };
        if let Some((axis, [t0, t1], period)) = profile_coordinate {
            let (lo, hi) = if axis == 0 { (a0, a1) } else { (b0, b1) };
            let shift = match period {
                Some(p) if p > 0.0 && lo < t0 - 1e-9 * p => p * ((t0 - lo) / p).ceil(),
                Some(p) if p > 0.0 && lo >= t1 => -p * ((lo - t0) / p).floor(),
                _ => 0.0,
            };
            let tol = 1e-9 * (t1 - t0);
            if lo + shift < t0 - tol || hi + shift > t1 + tol {
                return Err(self.err(f, "the face crosses the seam of its swept profile".into()));
            }
            for p in nat.iter_mut().flatten() {
                if axis == 0 {
                    p.0 += shift;
                } else {
                    p.1 += shift;
                }
            }
            if axis == 0 {
                (a0, a1) = (a0 + shift, a1 + shift);
            } else {
                (b0, b1) = (b0 + shift, b1 + shift);
            }
        }
        Ok(NaturalBox {
            a: [a0, a1],
            b: [b0, b1],
        })
    }

    /// The exact NURBS of an analytic surface over the natural box `span`
    /// (u along a, v along b; see [`super::super::nurbs`]) and the map of
    /// natural coordinates `(a, b)` to its parameters `(u, v)`.
    fn analytic_nurbs(
        &self,
        f: &Instance,
        (o, x, _y, z): Frame,
        kind: &Analytic,
        span: NaturalBox,
    ) -> R<(BSplineSurface, ToUv)> {
        let NaturalBox {
            a: [a0, a1],
            b: [b0, b1],
        } = span;
        let nurbs: (BSplineSurface, ToUv) = match kind {
            Analytic::Cylinder { r } | Analytic::Cone { r, .. } => {
                let tan = if let Analytic::Cone { tan, .. } = kind {
                    *tan
                } else {
                    0.0
                };
                let radius = |h: f64| r + h * tan;
                let scale = radius(b0).abs().max(radius(b1).abs()).max(1e-300);
                let map = ArcMap::new(a0, a1, scale);
                let profile = Nurbs3::segment(
                    o + radius(b0) * x + b0 * z,
                    o + radius(b1) * x + b1 * z,
                    b0,
                    b1,
                );
                (
                    self.revolved(f, o, z, &profile, &map)?,
                    ToUv([Some(map), None]),
                )
            }
            Analytic::Sphere { r } | Analytic::Torus { small: r, .. } => {
                let big = if let Analytic::Torus { big, .. } = kind {
                    *big
                } else {
                    0.0
                };
                let amap = ArcMap::new(a0, a1, big + r);
                let bmap = ArcMap::new(b0, b1, *r);
                let profile = arc(o + big * x, x, z, *r, &bmap);
                (
                    self.revolved(f, o, z, &profile, &amap)?,
                    ToUv([Some(amap), Some(bmap)]),
                )
            }
            Analytic::Revolution { profile, .. } => {
                let scale = profile
                    .points
                    .iter()
                    .map(|q| ((*q - o) - (*q - o).dot(z) * z).length())
                    .fold(0.0, f64::max)
                    .max(1e-300);
                let map = ArcMap::new(a0, a1, scale);
                (
                    self.revolved(f, o, z, profile, &map)?,
                    ToUv([Some(map), None]),
                )
            }
            Analytic::Extrusion { profile, d, .. } => {
                (self.extruded(f, profile, *d, b0, b1)?, ToUv([None, None]))
            }
            Analytic::Plane => {
                return Err(self.err(f, "internal: planes are handled by plane_face".into()));
            }
        };
        Ok(nurbs)
    }

    /// The ruled surface of `profile` moved by `b0·d` to `b1·d` (Piegl &
    /// Tiller §8.3): degree 1 across, the profile's knots and weights along.
    fn extruded(
        &self,
        f: &Instance,
        profile: &Nurbs3,
        d: Vec3,
        b0: f64,
        b1: f64,
    ) -> R<BSplineSurface> {
        let n = profile.points.len();
        let mut pts = Vec::with_capacity(2 * n);
        let mut w = Vec::with_capacity(2 * n);
        for (i, q) in profile.points.iter().enumerate() {
            let wi = profile.weights.as_ref().map_or(1.0, |ws| ws[i]);
            pts.push(*q + b0 * d);
            pts.push(*q + b1 * d);
            w.extend([wi, wi]);
        }
        BSplineSurface::from_flat(
            profile.degree,
            1,
            profile.knots.clone(),
            vec![b0, b0, b1, b1],
            [n, 2],
            pts,
            profile.weights.is_some().then_some(w),
        )
        .map_err(|e| self.err(f, e.to_string()))
    }

    fn revolved(
        &self,
        f: &Instance,
        o: Vec3,
        z: Vec3,
        profile: &Nurbs3,
        map: &ArcMap,
    ) -> R<BSplineSurface> {
        let (ku, pts, w) = revolve(o, z, profile, map);
        let nu = ku.len() - 3;
        BSplineSurface::from_flat(
            2,
            profile.degree,
            ku,
            profile.knots.clone(),
            [nu, profile.points.len()],
            pts,
            Some(w),
        )
        .map_err(|e| self.err(f, e.to_string()))
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

/// How [`Reader::close_full_turns`] closed the bounds that wind around a
/// face's surface.
struct FullTurns {
    /// The natural loops: the outer loop first, then the holes.
    loops: Vec<NaturalLoop>,
    /// The coordinate the bounds wind in (0: a, 1: b; called `s`, the
    /// other `t`) and its period.
    axis: usize,
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
struct WindingFace<'w> {
    surface: &'w BSplineSurface,
    sid: u64,
    map: &'w PcurveMap,
    to_uv: ToUv,
    turns: &'w FullTurns,
    /// The bounds' natural coordinates before closing, and where each edge
    /// starts in them ([`Reader::natural_loops`]).
    unwrapped: &'w [NaturalLoop],
    starts: &'w [Vec<usize>],
    /// How far the loops were moved into a swept profile's domain, per
    /// natural coordinate.
    moved: [f64; 2],
    /// Where the NURBS's `s` begins (the cut, after that move).
    cut: f64,
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
                curves = curves.iter().map(reversed).collect::<Option<_>>()?;
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

/// The same trim curve traversed backwards (knots mirrored, control points
/// and weights reversed).
fn reversed(c: &TrimCurve) -> Option<TrimCurve> {
    let k = c.knots();
    let (a, b) = (k[0], k[k.len() - 1]);
    TrimCurve::new(
        c.degree(),
        k.iter().rev().map(|x| a + b - x).collect(),
        c.control_points().iter().rev().copied().collect(),
        c.weights().map(|w| w.iter().rev().copied().collect()),
    )
    .ok()
}

/// A stretch of natural coordinates as a polyline in the NURBS parameters.
fn natural_polyline(l: &[(f64, f64)], to_uv: ToUv) -> Result<TrimCurve, String> {
    let pts: Vec<[f64; 2]> = l.iter().map(|&(a, b)| to_uv.at(a, b)).collect();
    polyline(&pts)
}

/// Whole periods a loop winds in each natural coordinate: its last point
/// (the end of its last edge, which closes the loop) minus its first, in
/// periods.
fn turns(l: &[(f64, f64)], periods: Periods) -> [i64; 2] {
    let (Some(f), Some(e)) = (l.first(), l.last()) else {
        return [0, 0];
    };
    let count = |d: f64, period: Option<f64>| match period {
        Some(p) if p > 0.0 => (d / p).round() as i64,
        _ => 0,
    };
    [count(e.0 - f.0, periods[0]), count(e.1 - f.1, periods[1])]
}

/// A point `(s, t)` of a loop in the coordinates where `s` is the one the
/// loop winds in.
type St = (f64, f64);

/// The loop `l` (winding once in `s`, first and last points one period
/// apart, `s` increasing overall) re-cut to run from `s = cut` to
/// `s = cut + period`: shifted by whole periods, rotated to start at its
/// first crossing of `cut` (the crossing point interpolated) and closed
/// one period on.
fn recut(l: &[St], cut: f64, period: f64) -> Vec<St> {
    let n = l.len();
    if n < 2 {
        return l.to_vec();
    }
    let shift = period * ((cut - l[0].0) / period).floor();
    let pts: Vec<St> = l[..n - 1].iter().map(|&(s, t)| (s + shift, t)).collect();
    // pts[0].0 <= cut < pts[0].0 + period; the loop continues with pts[0] + period.
    let at = |k: usize| -> St {
        if k < pts.len() {
            pts[k]
        } else {
            (pts[k - pts.len()].0 + period, pts[k - pts.len()].1)
        }
    };
    let m = pts.len();
    let k = (0..m)
        .find(|&k| at(k).0 <= cut && cut < at(k + 1).0)
        .unwrap_or(0);
    let (p, q) = (at(k), at(k + 1));
    let ds = q.0 - p.0;
    let w = if ds > 0.0 { (cut - p.0) / ds } else { 0.0 };
    let start = (cut, p.1 + w * (q.1 - p.1));
    let mut out = Vec::with_capacity(m + 2);
    out.push(start);
    for j in k + 1..=k + m {
        let r = at(j);
        if r.0 > cut && r.0 < cut + period {
            out.push(r);
        }
    }
    out.push((cut + period, start.1));
    out
}

/// An `s` at which to cut the surface open: in the middle of the widest gap
/// between the `s` ranges of the holes (so that no hole straddles the cut),
/// or `default` without holes.
fn cut_between_holes(holes: &[Vec<St>], period: f64, default: f64) -> f64 {
    let mut spans: Vec<(f64, f64)> = holes
        .iter()
        .filter_map(|h| {
            let lo = h.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let hi = h.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
            (lo <= hi).then(|| {
                let lo_mod = lo.rem_euclid(period);
                (lo_mod, lo_mod + (hi - lo))
            })
        })
        .collect();
    if spans.is_empty() {
        return default;
    }
    spans.sort_by(|x, y| x.0.total_cmp(&y.0));
    // Merge overlapping spans, then take the widest gap (cyclically).
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (lo, hi) in spans {
        match merged.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => merged.push((lo, hi)),
        }
    }
    let mut best = (f64::NEG_INFINITY, default);
    for (k, &(_, hi)) in merged.iter().enumerate() {
        let next_lo = if k + 1 < merged.len() {
            merged[k + 1].0
        } else {
            merged[0].0 + period
        };
        let gap = next_lo - hi;
        if gap > best.0 {
            best = (gap, 0.5 * (hi + next_lo));
        }
    }
    best.1
}

/// Whether a loop encloses its whole natural box (its area, by the shoelace
/// formula, is the box's to 1e-9): the face is then the untrimmed NURBS.
fn covers_box(l: &[(f64, f64)], span: NaturalBox) -> bool {
    let pts: Vec<[f64; 2]> = l.iter().map(|&(a, b)| [a, b]).collect();
    let area = 0.5 * polygon_signed_area2(&pts).abs();
    let whole = (span.a[1] - span.a[0]) * (span.b[1] - span.b[0]);
    whole > 0.0 && area >= whole * (1.0 - 1e-9)
}
