//! Faces of an IGES file beyond the B-spline surface: trimmed and bounded
//! planes (entity 108 under a 144 or a 143) and the census of faces that
//! cannot be read.

use super::{
    ArcMap, Conversions, Iges, IgesError, IgesSurface, Nurbs3, Param, Revolved, TrimCurve,
    TrimLoop, Unreadable, Vec3, params::INT, params::REAL, params::param, trimmed::Faces,
};
use crate::bspline::BSplineSurface;

/// Surface entity types that make a face when they are independent
/// (subordinate switch 0) and not the base of a trimmed or bounded surface.
const SURFACE_TYPES: [i64; 12] = [108, 114, 118, 120, 122, 128, 140, 190, 192, 194, 196, 198];

impl Iges<'_> {
    /// `entity T (DE n, line l)` for messages.
    pub(super) fn describe_entity(&self, k: usize) -> String {
        format!(
            "entity {} (DE {}, line {})",
            self.dir[k].entity_type,
            2 * k + 1,
            self.dir[k].line
        )
    }

    /// Why the base surface `b` of a trimmed surface was not read.
    pub(super) fn why_not_read(&self, b: usize) -> String {
        match self.dir[b].entity_type {
            120 => format!(
                "its surface of revolution ({}) has a generatrix fairline does not read (it reads a line 110, a circular arc 100, an elliptic arc 104 or a B-spline curve 126)",
                self.describe_entity(b)
            ),
            t => format!(
                "its base surface is {}; fairline reads trimmed surfaces on 108, 114, 118, 120, 122, 128, 140 and 190–198, not on entity {t}",
                self.describe_entity(b)
            ),
        }
    }

    /// Lists the faces no trimmed surface (144) or B-rep face (510, see
    /// [`super::brep`]) covers that cannot be read: bounded surfaces (143,
    /// their base read untrimmed), independent surface entities of a type
    /// fairline does not read and surfaces of revolution whose generatrix
    /// it does not read.
    pub(super) fn untrimmed_faces(
        &self,
        bsplines: &[Option<IgesSurface>],
        revolved: &[Option<Revolved>],
        conv: &Conversions,
        trimmed: &[bool],
        brep_bases: &[bool],
        faces: &mut Faces,
    ) {
        for k in 0..self.dir.len() {
            if brep_bases[k] {
                // read (or listed) with its B-rep face
                continue;
            }
            let e = &self.dir[k];
            let independent = (e.status / 10_000) % 100 == 0;
            let reason = match e.entity_type {
                143 => {
                    let Some(reason) = faces.bounded_failed[k].take() else {
                        // read ([`Iges::bounded_surfaces`])
                        continue;
                    };
                    let base = self
                        .parameters(k)
                        .ok()
                        .and_then(|p| super::params::text_of(&p, 2).and_then(super::params::parse_int))
                        .and_then(|de| self.entry(de));
                    let mut area = None;
                    if let Some(b) = base {
                        area = bsplines[b]
                            .as_ref()
                            .map(|s| &s.surface)
                            .or(revolved[b].as_ref().map(|r| &r.surface))
                            .or(conv.surfaces[b].as_ref().map(|c| &c.surface))
                            .map(|s| crate::bspline::trimmed_area(s, 16, 16));
                    }
                    faces.unreadable.push(Unreadable {
                        entity: self.describe_entity(k),
                        reason: format!("a bounded surface (143): {reason}"),
                        estimated_area: area,
                    });
                    continue;
                }
                120 if independent && !trimmed[k] && revolved[k].is_none() => {
                    "a surface of revolution whose generatrix fairline does not read (it reads a line 110, a circular arc 100, an elliptic arc 104 or a B-spline curve 126)".into()
                }
                t if independent
                    && !trimmed[k]
                    && SURFACE_TYPES.contains(&t)
                    && !matches!(t, 120 | 128)
                    && conv.surfaces[k].is_none()
                    && !(t == 108 && e.form == 0) =>
                {
                    match &conv.failed[k] {
                        Some(m) => m.clone(),
                        None => format!("surface entity {t} is not read on its own (only under a trimmed surface 144 or a B-rep face 510)"),
                    }
                }
                _ => continue,
            };
            faces.unreadable.push(Unreadable {
                entity: self.describe_entity(k),
                reason,
                estimated_area: None,
            });
        }
    }

    /// A plane (entity 108, IGES 5.3 §4.12: `A B C D`, the plane `Ax + By +
    /// Cz = D`) trimmed by the 144 `k`: the 142s' model-space curves
    /// (`CPTR`; a plane has no parameter space in IGES) are its loops
    /// ([`Iges::plane_patch`]).
    pub(super) fn plane_face(
        &self,
        k: usize,
        b: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<IgesSurface, IgesError> {
        let n1 = param(self, k, p, 2, line, &INT)?;
        let n2 = param(self, k, p, 3, line, &INT)?;
        if n1 == 0 {
            return Err(self.unsupported(
                k,
                line,
                "a plane (108) trimmed without an outer boundary (N1 = 0) has no extent".into(),
            ));
        }
        let holes = usize::try_from(n2)
            .ok()
            .filter(|&h| h < p.len())
            .ok_or_else(|| self.entity_error(k, line, format!("N2 = {n2} inner boundaries")))?;
        let mut loops = Vec::with_capacity(holes + 1);
        for slot in 4..5 + holes {
            let de = param(self, k, p, slot, line, &INT)?;
            let b142 = self.entry(de).filter(|&j| self.dir[j].entity_type == 142);
            let Some(j) = b142 else {
                return Err(self.entity_error(
                    k,
                    line,
                    format!("boundary {de} is not an entity 142"),
                ));
            };
            let pj = self.parameters(j)?;
            let lj = pj.first().map_or(self.dir[j].line, |t| t.1);
            let cptr = param(self, j, &pj, 4, lj, &INT)?;
            let curve = self.entry(cptr).ok_or_else(|| {
                self.unsupported(
                    j,
                    lj,
                    format!("a boundary of a plane needs its model-space curve (CPTR = {cptr})"),
                )
            })?;
            let mut pieces = Vec::new();
            self.curve_pieces(curve, 0, &mut pieces)?;
            loops.push(PlaneLoop {
                entity: j,
                line: lj,
                pieces,
            });
        }
        self.plane_patch(k, line, b, &loops)
    }

    /// The plane `b` (entity 108) bounded by `loops` (model space; the
    /// first the outer one) for the trimmed or bounded surface `k`: a
    /// bilinear NURBS patch whose parameters are Cartesian coordinates in
    /// the plane (origin the foot of the perpendicular from the model
    /// origin, axes `x̂ × n`-based right-handed with the plane's normal
    /// `(A, B, C)`), spanning the control points of the loops, which are
    /// mapped into the plane's coordinates by its affine frame: exact, as
    /// rational B-splines are invariant under affine maps. A loop that
    /// leaves the plane, is empty or encloses no area is an error naming
    /// its entity.
    pub(super) fn plane_patch(
        &self,
        k: usize,
        line: usize,
        b: usize,
        model: &[PlaneLoop],
    ) -> Result<IgesSurface, IgesError> {
        let pb = self.parameters(b)?;
        let lb = pb.first().map_or(self.dir[b].line, |t| t.1);
        let mut c = [0.0; 4];
        for (i, v) in c.iter_mut().enumerate() {
            *v = param(self, b, &pb, i + 1, lb, &REAL)?;
        }
        let n = Vec3::new(c[0], c[1], c[2]);
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(self.entity_error(b, lb, "the plane's normal (A, B, C) is zero".into()));
        }
        let mut normal = n / len;
        let mut origin = normal * (c[3] / len);
        let helper = if normal.x.abs() < 0.9 {
            Vec3::X
        } else {
            Vec3::Y
        };
        let mut ex = helper.cross(normal).normalize();
        if self.dir[b].transform != 0 {
            let t = self.entry(self.dir[b].transform).ok_or_else(|| {
                self.entity_error(
                    b,
                    lb,
                    "the transformation pointer is not a directory entry".into(),
                )
            })?;
            let m = self.transform(t, 0)?;
            origin = m.transform_point3(origin);
            normal = m.transform_vector3(normal).normalize();
            ex = m.transform_vector3(ex);
            ex = (ex - normal * ex.dot(normal)).normalize();
        }
        let ey = normal.cross(ex);
        let mut loops = Vec::with_capacity(model.len());
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for PlaneLoop {
            entity: j,
            line: lj,
            pieces,
        } in model
        {
            let (j, lj) = (*j, *lj);
            let size = pieces
                .iter()
                .flat_map(|q| q.points.iter())
                .map(|q| (*q - origin).length())
                .fold(1.0_f64, f64::max);
            let mut curves = Vec::with_capacity(pieces.len());
            for piece in pieces {
                let mut uv = Vec::with_capacity(piece.points.len());
                for q in &piece.points {
                    let d = *q - origin;
                    let off = d.dot(normal);
                    if off.abs() > 1e-7 * size {
                        return Err(self.entity_error(
                            j,
                            lj,
                            format!("the boundary curve leaves the plane by {off:.3e}"),
                        ));
                    }
                    let (u, v) = (d.dot(ex), d.dot(ey));
                    lo = [lo[0].min(u), lo[1].min(v)];
                    hi = [hi[0].max(u), hi[1].max(v)];
                    uv.push([u, v]);
                }
                curves.push(
                    TrimCurve::new(piece.degree, piece.knots.clone(), uv, piece.weights.clone())
                        .map_err(|m| self.entity_error(j, lj, m))?,
                );
            }
            if curves.is_empty() {
                return Err(self.entity_error(j, lj, "the boundary curve is empty".into()));
            }
            loops.push(TrimLoop { curves });
        }
        // a margin so that no boundary runs along the patch's own edge
        let pad = 1e-3 * (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let (u0, u1, v0, v1) = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad);
        if !(u1 > u0 && v1 > v0 && (u1 - u0).is_finite() && (v1 - v0).is_finite()) {
            return Err(self.entity_error(k, line, "the plane's boundary has no area".into()));
        }
        let at = |u: f64, v: f64| origin + u * ex + v * ey;
        let mut surface = BSplineSurface::from_flat(
            1,
            1,
            vec![u0, u0, u1, u1],
            vec![v0, v0, v1, v1],
            [2, 2],
            vec![at(u0, v0), at(u0, v1), at(u1, v0), at(u1, v1)],
            None,
        )
        .map_err(|source| IgesError::Surface {
            entity: 2 * b + 1,
            line: lb,
            source,
        })?;
        surface
            .set_trims(loops)
            .map_err(|e| self.entity_error(k, line, e.to_string()))?;
        Ok(IgesSurface {
            surface,
            directory_entry: 2 * b + 1,
            entity_type: 108,
            form: self.dir[b].form,
            rational: false,
            closed: [false, false],
            periodic: [false, false],
            parameter_range: [u0, u1, v0, v1],
            transformed: self.dir[b].transform != 0,
            trimmed: true,
            trim_entity: Some(2 * k + 1),
        })
    }
}

/// One boundary of a plane in model space: the boundary entity (142 or
/// 141, for messages), its line, and its curves as B-spline pieces in
/// order along the loop.
pub(super) struct PlaneLoop {
    pub(super) entity: usize,
    pub(super) line: usize,
    pub(super) pieces: Vec<super::boundary::Piece>,
}

/// A boundary whose curves do not follow each other end to start (a
/// composite curve listing a seam's two sides in the order of the edges'
/// uses rather than along the loop) reordered into a chain: from the first
/// curve, each next curve is the unused one starting nearest the current
/// end. The order is kept unless the chain's total gap between ends and
/// starts is less than half the given order's (gaps that the file means,
/// such as degenerate edges at a pole it leaves out, stay).
pub(super) fn chained(l: TrimLoop) -> TrimLoop {
    let n = l.curves.len();
    if n < 3 {
        return l;
    }
    let ends: Vec<([f64; 2], [f64; 2])> = l
        .curves
        .iter()
        .map(|c| {
            let [a, b] = c.domain();
            (c.eval(a), c.eval(b))
        })
        .collect();
    let gap = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let total = |order: &[usize]| -> f64 {
        (0..n)
            .map(|k| gap(ends[order[k]].1, ends[order[(k + 1) % n]].0))
            .sum()
    };
    let given: Vec<usize> = (0..n).collect();
    let mut order = vec![0];
    let mut used = vec![false; n];
    used[0] = true;
    for _ in 1..n {
        let end = ends[*order.last().unwrap_or(&0)].1;
        let next = (0..n)
            .filter(|&j| !used[j])
            .min_by(|&a, &b| gap(end, ends[a].0).total_cmp(&gap(end, ends[b].0)));
        let Some(j) = next else { break };
        used[j] = true;
        order.push(j);
    }
    if order.len() == n && total(&order) < 0.5 * total(&given) {
        let mut curves: Vec<Option<TrimCurve>> = l.curves.into_iter().map(Some).collect();
        TrimLoop {
            curves: order.iter().filter_map(|&k| curves[k].take()).collect(),
        }
    } else {
        l
    }
}

impl Iges<'_> {
    /// Entity 104, conic arc (IGES 5.3 §4.5): `A B C D E F ZT X1 Y1 X2 Y2`,
    /// the conic `Ax² + Bxy + Cy² + Dx + Ey + F = 0` in the plane `z = ZT`
    /// of its definition space, from `(X1, Y1)` counter-clockwise to `(X2,
    /// Y2)`, in standard position (form 1 ellipse `Ax² + Cy² + F = 0`, form
    /// 2 hyperbola likewise with `A·C < 0`, form 3 parabola `Ax² + Ey = 0` or
    /// `Cy² + Dx = 0`), as an exact rational quadratic B-spline in its
    /// definition space (the entity's transformation is applied by the
    /// caller). The ellipse comes with its [`ArcMap`] (parameter = the
    /// eccentric angle at the arcs' joints, as IGES parametrises it).
    pub(super) fn conic(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<(Nurbs3, Option<ArcMap>), IgesError> {
        let mut r = [0.0; 11];
        for (n, v) in r.iter_mut().enumerate() {
            *v = param(self, k, p, n + 1, line, &REAL)?;
        }
        let [a, b, c, d, e, f, z, x1, y1, x2, y2] = r;
        let scale = [a, b, c, d, e, f]
            .iter()
            .fold(0.0_f64, |m, x| m.max(x.abs()));
        let zero = |x: f64| x.abs() <= 1e-12 * scale;
        let bad = |what: &str| self.entity_error(k, line, format!("the conic arc {what}"));
        if !(scale > 0.0) {
            return Err(bad("has no coefficients"));
        }
        let at = |x: f64, y: f64| Vec3::new(x, y, z);
        if zero(b) && zero(d) && zero(e) && !zero(a) && !zero(c) && !zero(f) {
            let (ra, rc) = (-f / a, -f / c);
            if ra > 0.0 && rc > 0.0 {
                // ellipse x²/ra + y²/rc = 1
                let (sa, sc) = (ra.sqrt(), rc.sqrt());
                let t0 = (y1 / sc).atan2(x1 / sa);
                let mut t1 = (y2 / sc).atan2(x2 / sa);
                while t1 <= t0 + 1e-12 {
                    t1 += std::f64::consts::TAU;
                }
                let map = ArcMap::new(t0, t1, 1.0);
                let curve = super::super::step::nurbs::ellipse_arc(
                    at(0.0, 0.0),
                    Vec3::X,
                    Vec3::Y,
                    sa,
                    sc,
                    &map,
                );
                return Ok((curve, Some(map)));
            }
            if ra * rc < 0.0 {
                // hyperbola: transverse axis x (ra > 0) or y
                let swap = ra < 0.0;
                let (sa, sb) = if swap {
                    (rc.sqrt(), (-ra).sqrt())
                } else {
                    (ra.sqrt(), (-rc).sqrt())
                };
                let (ax, ay) = if swap {
                    (Vec3::Y, Vec3::X)
                } else {
                    (Vec3::X, Vec3::Y)
                };
                let local = |x: f64, y: f64| if swap { (y, x) } else { (x, y) };
                let ((p1, q1), (p2, q2)) = (local(x1, y1), local(x2, y2));
                if p1 * p2 <= 0.0 {
                    return Err(bad("runs across both branches of the hyperbola"));
                }
                let branch = p1.signum();
                let (t0, t1) = ((q1 / sb).asinh(), (q2 / sb).asinh());
                let curve = hyperbola_arc(at(0.0, 0.0), branch * ax, ay, sa, sb, t0, t1);
                return Ok((curve, None));
            }
            return Err(self.unsupported(
                k,
                line,
                "the conic arc is not a real ellipse or hyperbola".into(),
            ));
        }
        // parabola y = −(A/E)·x² or x = −(C/D)·y²
        let (kq, along_x) = if zero(b) && zero(c) && zero(d) && zero(f) && !zero(a) && !zero(e) {
            (-a / e, true)
        } else if zero(a) && zero(b) && zero(e) && zero(f) && !zero(c) && !zero(d) {
            (-c / d, false)
        } else {
            return Err(self.unsupported(
                k,
                line,
                "the conic arc is not in standard position (IGES 5.3 §4.5)".into(),
            ));
        };
        let (s0, s1) = if along_x { (x1, x2) } else { (y1, y2) };
        let pt = |s: f64| {
            if along_x {
                at(s, kq * s * s)
            } else {
                at(kq * s * s, s)
            }
        };
        let mid = if along_x {
            at(0.5 * (s0 + s1), kq * s0 * s1)
        } else {
            at(kq * s0 * s1, 0.5 * (s0 + s1))
        };
        if s0 == s1 {
            return Err(bad("has no length"));
        }
        Ok((
            Nurbs3 {
                degree: 2,
                knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
                points: vec![pt(s0), mid, pt(s1)],
                weights: None,
            },
            None,
        ))
    }

    /// Applies entity `k`'s transformation matrix (124), if any, to `c`.
    pub(super) fn transform_nurbs(&self, k: usize, c: &mut Nurbs3) -> Result<(), IgesError> {
        let e = &self.dir[k];
        if e.transform == 0 {
            return Ok(());
        }
        let t = self.entry(e.transform).ok_or_else(|| {
            self.entity_error(
                k,
                e.line,
                "the transformation pointer is not a directory entry".into(),
            )
        })?;
        let m = self.transform(t, 0)?;
        for q in &mut c.points {
            *q = m.transform_point3(*q);
        }
        Ok(())
    }
}

/// The hyperbola arc `c + a·cosh t·x + b·sinh t·y`, `t` from `t0` to `t1`,
/// as rational quadratic arcs of at most 1 in `t` (middle control point at
/// the tangents' intersection, weight `cosh δ` for the half span `δ`; the
/// hyperbolic analogue of Piegl & Tiller A7.1), parameter `t` at the joints.
fn hyperbola_arc(c: Vec3, x: Vec3, y: Vec3, a: f64, b: f64, t0: f64, t1: f64) -> Nurbs3 {
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let arcs = (((hi - lo).ceil()) as usize).clamp(1, 64);
    let d = (hi - lo) / arcs as f64;
    let pt = |t: f64| c + a * t.cosh() * x + b * t.sinh() * y;
    let mut knots = vec![lo; 3];
    let (mut points, mut weights) = (vec![pt(lo)], vec![1.0]);
    for k in 0..arcs {
        let (s0, s1) = (lo + k as f64 * d, lo + (k + 1) as f64 * d);
        let (tm, h) = (0.5 * (s0 + s1), 0.5 * d);
        points.push(c + (a * tm.cosh() * x + b * tm.sinh() * y) / h.cosh());
        weights.push(h.cosh());
        points.push(pt(s1));
        weights.push(1.0);
        if k + 1 < arcs {
            knots.extend([s1, s1]);
        }
    }
    knots.extend([hi; 3]);
    let n = Nurbs3 {
        degree: 2,
        knots,
        points,
        weights: Some(weights),
    };
    if t1 < t0 { n.reversed() } else { n }
}

/// Where `side` changes between `lo` and `hi` (bisection to the last bit).
pub(super) fn crossing(side: &impl Fn(f64) -> bool, mut lo: f64, mut hi: f64) -> f64 {
    let s0 = side(lo);
    for _ in 0..64 {
        let m = 0.5 * (lo + hi);
        if m <= lo || m >= hi {
            break;
        }
        if side(m) == s0 {
            lo = m;
        } else {
            hi = m;
        }
    }
    0.5 * (lo + hi)
}

/// Deepest bisection of one piece in [`hermite_trim`] (2^16 pieces).
const HERMITE_DEPTH: u32 = 16;

/// The plane curve `f` on `[a, b]` as a C¹ piecewise cubic trim curve
/// (cubic Hermite pieces as Bézier segments joined by triple knots, with
/// `f`'s own parameter): `f` is interpolated with its derivative (central
/// differences inside each piece between `breaks`, where `f` may have a
/// kink) at parameters bisected until every piece is within `tolerance` of
/// `f` at ¼, ½ and ¾ of it.
pub(super) fn hermite_trim(
    f: &impl Fn(f64) -> [f64; 2],
    a: f64,
    b: f64,
    breaks: &mut Vec<f64>,
    tolerance: f64,
) -> Result<TrimCurve, String> {
    if !(b > a) {
        return Err(format!("the curve's parameter range [{a}, {b}] is empty"));
    }
    breaks.retain(|&x| x > a && x < b);
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    let mut ends = vec![a];
    ends.extend(breaks.iter().copied());
    ends.push(b);
    let mut knots = vec![a; 4];
    let mut points = vec![f(a)];
    for w in ends.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let d = |x: f64| -> [f64; 2] {
            let h = 1e-6 * (hi - lo);
            let (p, q) = ((x - h).max(lo), (x + h).min(hi));
            let (fp, fq) = (f(p), f(q));
            [(fq[0] - fp[0]) / (q - p), (fq[1] - fp[1]) / (q - p)]
        };
        let mut stack = vec![(lo, hi, 0u32)];
        while let Some((t0, t1, depth)) = stack.pop() {
            let h = t1 - t0;
            let (p0, p1, d0, d1) = (f(t0), f(t1), d(t0), d(t1));
            let bez = [
                p0,
                [p0[0] + h / 3.0 * d0[0], p0[1] + h / 3.0 * d0[1]],
                [p1[0] - h / 3.0 * d1[0], p1[1] - h / 3.0 * d1[1]],
                p1,
            ];
            let at = |x: f64| -> [f64; 2] {
                let y = 1.0 - x;
                let c = [y * y * y, 3.0 * x * y * y, 3.0 * x * x * y, x * x * x];
                let mut r = [0.0; 2];
                for (k, q) in bez.iter().enumerate() {
                    r[0] += c[k] * q[0];
                    r[1] += c[k] * q[1];
                }
                r
            };
            let miss = [0.25, 0.5, 0.75]
                .iter()
                .map(|&x| {
                    let (p, q) = (at(x), f(t0 + x * h));
                    (p[0] - q[0]).hypot(p[1] - q[1])
                })
                .fold(0.0, f64::max);
            if depth < HERMITE_DEPTH && !(miss <= tolerance) {
                let tm = 0.5 * (t0 + t1);
                // the right half first on the stack: pieces come off in order
                stack.push((tm, t1, depth + 1));
                stack.push((t0, tm, depth + 1));
            } else {
                points.extend([bez[1], bez[2], bez[3]]);
                knots.extend([t1; 3]);
            }
        }
    }
    knots.push(b);
    TrimCurve::new(3, knots, points, None)
}

#[cfg(test)]
mod tests {
    use super::super::parse_iges;
    use super::super::tests::{GLOBAL, iges_file};
    use crate::bspline::trimmed_area;
    use std::f64::consts::{FRAC_PI_2, PI, TAU};

    #[test]
    fn iges_trimmed_plane_with_a_hole_is_exact_and_unread_faces_are_listed() {
        let entities = [
            (108, 0, 0, "108,0.,0.,1.,0.,0,0.,0.,0.,0.;"),
            (110, 0, 0, "110,0.,0.,0.,10.,0.,0.;"),
            (110, 0, 0, "110,10.,0.,0.,10.,5.,0.;"),
            (110, 0, 0, "110,10.,5.,0.,0.,5.,0.;"),
            (110, 0, 0, "110,0.,5.,0.,0.,0.,0.;"),
            (102, 0, 0, "102,4,3,5,7,9;"),
            (142, 0, 0, "142,0,1,0,11,2;"),
            (100, 0, 0, "100,0.,5.,2.5,6.,2.5,6.,2.5;"),
            (142, 0, 0, "142,0,1,0,15,2;"),
            (144, 0, 0, "144,1,1,1,13,17;"),
            // a trimmed tabulated cylinder (122) whose boundary does not
            // lie on it and a B-rep face (510) on a plane 108: not read,
            // listed
            (122, 0, 0, "122,3,0.,0.,1.;"),
            (144, 0, 0, "144,21,1,0,13;"),
            (510, 0, 1, "510,1,0,0;"),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert_eq!(imp.surfaces.len(), 1);
        let plane = &imp.surfaces[0];
        assert_eq!((plane.entity_type, plane.trim_entity), (108, Some(19)));
        let area = trimmed_area(&plane.surface, 64, 64);
        let want = 50.0 - PI;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
        let names: Vec<&str> = imp.unreadable.iter().map(|u| u.entity.as_str()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        assert!(names[0].starts_with("entity 144 (DE 23"), "{names:?}");
        assert!(
            imp.unreadable[0].reason.contains("trimmed surface (144)"),
            "{:?}",
            imp.unreadable[0]
        );
        assert!(names[1].starts_with("entity 510 (DE 25"), "{names:?}");
        assert!(
            imp.unreadable[1].reason.contains("surface entity 108"),
            "{:?}",
            imp.unreadable[1]
        );
    }

    #[test]
    fn iges_sphere_of_revolution_of_an_arc_with_omitted_pole_edges_has_its_full_area() {
        // A half circle of radius 15 revolved about the y axis; the trim
        // runs down one seam and up the other, leaving out the degenerate
        // edges at the poles (as OpenCASCADE writes it).
        let (h, t) = (FRAC_PI_2, TAU);
        let top = format!("110,{h},{t},0.,{},{t},0.;", -h);
        let bottom = format!("110,{},0.,0.,{h},0.,0.;", -h);
        let entities = [
            (110, 0, 0, "110,0.,-15.,0.,0.,15.,0.;"),
            (100, 0, 0, "100,0.,0.,0.,0.,-15.,0.,15.;"),
            (120, 0, 0, "120,1,3,0.,6.283185307179586;"),
            (110, 0, 0, top.as_str()),
            (110, 0, 0, bottom.as_str()),
            (102, 0, 0, "102,2,7,9;"),
            (142, 0, 0, "142,0,5,11,0,1;"),
            (144, 0, 0, "144,5,1,0,13;"),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let s = &imp.surfaces[0].surface;
        let area = trimmed_area(s, 64, 64);
        let want = 4.0 * PI * 225.0;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
        // the surface is the sphere
        let (u, v) = s.domain_center();
        assert!((s.eval(u, v).length() - 15.0).abs() < 1e-9);
    }

    #[test]
    fn iges_torus_whose_seam_pcurves_come_out_of_order_is_chained() {
        // As OpenCASCADE writes a torus: the composite lists the p-curves
        // in the order of the edge uses (right, bottom, left, top).
        let entities = [
            (144, 0, 0, "144,3,1,0,11;"),
            (120, 0, 0, "120,5,7,0.,6.283185307;"),
            (110, 0, 0, "110,0.,0.,1.,0.,0.,0.;"),
            (100, 9, 0, "100,0.,0.,0.,6.,0.,6.,0.;"),
            (124, 0, 0, "124,1.,0.,0.,20.,0.,0.,-1.,0.,0.,1.,-0.,0.;"),
            (142, 0, 0, "142,0,3,13,0,1;"),
            (102, 0, 0, "102,4,15,17,19,21;"),
            (
                110,
                0,
                0,
                "110,6.283185307,0.,0.,6.283185307,6.283185307,0.;",
            ),
            (110, 0, 0, "110,0.,0.,0.,6.283185307,0.,0.;"),
            (110, 0, 0, "110,0.,6.283185307,0.,0.,0.,0.;"),
            (
                110,
                0,
                0,
                "110,6.283185307,6.283185307,0.,0.,6.283185307,0.;",
            ),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
        let want = 4.0 * PI * PI * 20.0 * 6.0;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
    }
}
