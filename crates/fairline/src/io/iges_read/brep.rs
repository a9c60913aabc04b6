//! IGES B-rep faces (IGES 5.3 §4.136–4.148: manifold solid 186, shell 514,
//! face 510, loop 508, edge list 504, vertex list 502), read through the
//! STEP reader's topology.
//!
//! A face (510) is a surface bounded by loops (508) of oriented edges; an
//! edge is an entry of an edge list (504): a model-space curve from one
//! vertex (an entry of a vertex list, 502) to another. That is exactly
//! ISO 10303-42's `ADVANCED_FACE` – `FACE_BOUND` – `EDGE_LOOP` –
//! `ORIENTED_EDGE` – `EDGE_CURVE` – `VERTEX_POINT`, so every face is
//! written into an in-memory STEP exchange ([`Exchange`]) and read by the
//! STEP reader, which converts analytic surfaces exactly to NURBS, handles
//! seams used twice, poles and faces with holes, and trims from the 3-D
//! edges ([`crate::io::step`]). The translation:
//!
//! - surfaces: plane 190, right circular cylinder 192, right circular cone
//!   194 (semi-angle in degrees), sphere 196, torus 198 (their points 116 and
//!   directions 123), surface of revolution 120 (axis line 110 and
//!   generatrix), tabulated cylinder 122 (directrix and the generatrix's
//!   end point) and rational B-spline surface 128; each entity's
//!   transformation matrix (124) is applied;
//! - edge curves: the curves [`Iges::curve_pieces`] reads (110, 100, 104,
//!   126, a 102 of one member), as exact NURBS in model space;
//! - a loop entry that is a vertex (`TYPE = 1`, a degenerate edge at a pole)
//!   carries no curve and is left out, as STEP writes poles;
//! - the loops' parameter-space curves (`ISOP`, `CURV`) are not used: the
//!   trims come from the exact 3-D edges;
//! - a face's orientation flag in its shell (514) is the face's
//!   `same_sense`; the outer-loop flag of the 510 marks its first loop as the
//!   outer bound.
//!
//! A face whose surface or an edge curve is of a type not read is listed in
//! [`IgesImport::unreadable`](super::IgesImport::unreadable), never dropped.

use std::collections::HashMap;

use glam::DAffine3;

use super::{
    Iges, IgesError, IgesSurface, Nurbs3, Param, Unreadable, Vec3, boundary::Piece, params::INT,
    params::REAL, params::param,
};
use crate::bspline::BSplineSurface;
use crate::io::step::p21::{Exchange, Instance, Value};

/// Surface entities the translation reads (under a 510, or under a 144
/// where the direct reading does not apply).
pub(super) const TRANSLATED_SURFACES: [i64; 11] =
    [114, 118, 120, 122, 128, 140, 190, 192, 194, 196, 198];

/// The faces of an IGES file's B-rep entities.
#[derive(Default)]
pub(super) struct BrepFaces {
    /// Every face read, in directory order.
    pub surfaces: Vec<IgesSurface>,
    /// Every face that could not be read.
    pub unreadable: Vec<Unreadable>,
    /// Directory entries that are the surface of a B-rep face (not faces
    /// on their own).
    pub bases: Vec<bool>,
}

/// An in-memory STEP exchange being written, instance by instance.
struct StepBuilder {
    ex: Exchange,
    next: u64,
    /// EDGE_CURVE and its SURFACE_CURVE of each edge-list entry
    /// `(504 index, entry)`.
    edges: HashMap<(usize, usize), (u64, u64)>,
    /// VERTEX_POINT of each vertex-list entry `(502 index, entry)`.
    vertices: HashMap<(usize, usize), u64>,
    /// Dense points of each EDGE_CURVE's curve.
    edge_points: HashMap<u64, Vec<Vec3>>,
    /// The edge curves' points of each ADVANCED_FACE's bounds.
    boundaries: HashMap<u64, Vec<Vec<Vec3>>>,
}

/// Points along a curve for [`trims_follow_boundary`]: 512 per curve
/// (a chord of a circle of radius `r` then deviates by less than 2e-5·r).
fn dense_points(c: &Nurbs3) -> Vec<Vec3> {
    let [a, b] = c.domain();
    (0..=512)
        .map(|i| c.eval(a + (b - a) * i as f64 / 512.0))
        .collect()
}

/// The farthest a point of the trimmed surface's trim curves (evaluated
/// on the surface) lies from the face's boundary curves, when it is
/// farther than 1e-3 of the boundary's size: trims that do not follow the
/// face's edges (a wrong period or side) would otherwise change the face
/// without a word.
fn trims_follow_boundary(s: &BSplineSurface, boundary: &[Vec<Vec3>]) -> Option<f64> {
    let pts: Vec<Vec3> = boundary.iter().flatten().copied().collect();
    let (lo, hi) = pts.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let size = (hi - lo).length();
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    let tolerance = 1e-3 * size;
    let distance = |q: Vec3| -> f64 {
        boundary
            .iter()
            .flat_map(|poly| poly.windows(2))
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let d = b - a;
                let l2 = d.length_squared();
                let t = if l2 > 0.0 {
                    ((q - a).dot(d) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                q.distance(a + t * d)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst = 0.0_f64;
    for l in s.trims() {
        for c in &l.curves {
            let mut uv = Vec::new();
            c.flatten_into(1e-6, &mut uv);
            let step = (uv.len() / 256).max(1);
            for p in uv.iter().step_by(step) {
                worst = worst.max(distance(s.eval(p[0], p[1])));
                if worst > tolerance {
                    return Some(worst);
                }
            }
        }
    }
    None
}

fn text(s: &str) -> Value {
    Value::Text(s.into())
}

fn flag(b: bool) -> Value {
    Value::Enum(if b { "T" } else { "F" }.into())
}

fn reals(xs: impl IntoIterator<Item = f64>) -> Value {
    Value::List(xs.into_iter().map(Value::Real).collect())
}

fn refs(ids: impl IntoIterator<Item = u64>) -> Value {
    Value::List(ids.into_iter().map(Value::Ref).collect())
}

/// Distinct knot values and their multiplicities.
fn knot_runs(knots: &[f64]) -> (Value, Value) {
    let mut values: Vec<f64> = Vec::new();
    let mut mults: Vec<i64> = Vec::new();
    for &k in knots {
        if values.last() == Some(&k) {
            *mults.last_mut().expect("a value has a count") += 1;
        } else {
            values.push(k);
            mults.push(1);
        }
    }
    (
        Value::List(mults.into_iter().map(Value::Integer).collect()),
        reals(values),
    )
}

impl StepBuilder {
    fn new() -> Self {
        StepBuilder {
            ex: Exchange::default(),
            next: 1,
            edges: HashMap::new(),
            vertices: HashMap::new(),
            edge_points: HashMap::new(),
            boundaries: HashMap::new(),
        }
    }

    fn add(&mut self, parts: Vec<(&str, Vec<Value>)>, line: usize) -> u64 {
        let id = self.reserve();
        self.insert(id, parts, line);
        id
    }

    /// An id for an instance written later with [`Self::insert`].
    fn reserve(&mut self) -> u64 {
        let id = self.next;
        self.next += 1;
        id
    }

    fn insert(&mut self, id: u64, parts: Vec<(&str, Vec<Value>)>, line: usize) {
        self.ex.instances.insert(
            id,
            Instance {
                id,
                parts: parts.into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
                line,
            },
        );
        self.ex.order.push(id);
    }

    /// Adds a p-curve (a 2-D B-spline curve in the surface's ISO 10303-42
    /// parameters) on surface `surface` to the SURFACE_CURVE `sc`.
    fn pcurve(&mut self, sc: u64, surface: u64, c: &Nurbs3, line: usize) {
        let curve = self.curve2(c, line);
        let dr = self.simple(
            "DEFINITIONAL_REPRESENTATION",
            vec![text(""), refs([curve]), Value::Unset],
            line,
        );
        let pc = self.simple(
            "PCURVE",
            vec![text(""), Value::Ref(surface), Value::Ref(dr)],
            line,
        );
        if let Some(Value::List(l)) = self
            .ex
            .instances
            .get_mut(&sc)
            .and_then(|i| i.parts.first_mut())
            .and_then(|(_, p)| p.get_mut(2))
        {
            l.push(Value::Ref(pc));
        }
    }

    fn simple(&mut self, name: &str, params: Vec<Value>, line: usize) -> u64 {
        self.add(vec![(name, params)], line)
    }

    fn point(&mut self, p: Vec3, line: usize) -> u64 {
        self.simple(
            "CARTESIAN_POINT",
            vec![text(""), reals([p.x, p.y, p.z])],
            line,
        )
    }

    fn direction(&mut self, d: Vec3, line: usize) -> u64 {
        self.simple("DIRECTION", vec![text(""), reals([d.x, d.y, d.z])], line)
    }

    /// AXIS2_PLACEMENT_3D at `o` with axis `z` and reference direction `x`
    /// (the placement's default when `None`).
    fn placement(&mut self, o: Vec3, z: Vec3, x: Option<Vec3>, line: usize) -> u64 {
        let o = self.point(o, line);
        let z = self.direction(z, line);
        let x = match x {
            Some(x) => Value::Ref(self.direction(x, line)),
            None => Value::Unset,
        };
        self.simple(
            "AXIS2_PLACEMENT_3D",
            vec![text(""), Value::Ref(o), Value::Ref(z), x],
            line,
        )
    }

    /// A B-spline curve instance (complex with RATIONAL_B_SPLINE_CURVE when
    /// it has weights).
    fn curve(&mut self, c: &Nurbs3, line: usize) -> u64 {
        let pts: Vec<u64> = c.points.iter().map(|p| self.point(*p, line)).collect();
        self.bspline_curve(c, pts, line)
    }

    /// [`Self::curve`] of a curve in a plane of parameters (`z` left out).
    fn curve2(&mut self, c: &Nurbs3, line: usize) -> u64 {
        let pts: Vec<u64> = c
            .points
            .iter()
            .map(|p| self.simple("CARTESIAN_POINT", vec![text(""), reals([p.x, p.y])], line))
            .collect();
        self.bspline_curve(c, pts, line)
    }

    fn bspline_curve(&mut self, c: &Nurbs3, pts: Vec<u64>, line: usize) -> u64 {
        let (mults, knots) = knot_runs(&c.knots);
        let head = vec![
            Value::Integer(c.degree as i64),
            refs(pts),
            Value::Enum("UNSPECIFIED".into()),
            flag(false),
            flag(false),
        ];
        let tail = vec![mults, knots, Value::Enum("UNSPECIFIED".into())];
        match &c.weights {
            None => {
                let mut p = vec![text("")];
                p.extend(head);
                p.extend(tail);
                self.simple("B_SPLINE_CURVE_WITH_KNOTS", p, line)
            }
            Some(w) => self.add(
                vec![
                    ("B_SPLINE_CURVE", head),
                    ("B_SPLINE_CURVE_WITH_KNOTS", tail),
                    ("RATIONAL_B_SPLINE_CURVE", vec![reals(w.iter().copied())]),
                ],
                line,
            ),
        }
    }

    /// A B-spline surface instance (complex with RATIONAL_B_SPLINE_SURFACE
    /// when it has weights); rows are the `u` index.
    fn bspline_surface(
        &mut self,
        s: &BSplineSurface,
        line: usize,
    ) -> Vec<(&'static str, Vec<Value>)> {
        let (nu, nv) = (s.count_u(), s.count_v());
        let rows: Vec<Value> = (0..nu)
            .map(|i| refs((0..nv).map(|j| self.point(s.control_point(i, j), line))))
            .collect();
        let (mu, ku) = knot_runs(s.knots_u());
        let (mv, kv) = knot_runs(s.knots_v());
        let head = vec![
            Value::Integer(s.degree_u() as i64),
            Value::Integer(s.degree_v() as i64),
            Value::List(rows),
            Value::Enum("UNSPECIFIED".into()),
            flag(false),
            flag(false),
            flag(false),
        ];
        let tail = vec![mu, mv, ku, kv, Value::Enum("UNSPECIFIED".into())];
        if s.is_rational() {
            let w: Vec<Value> = (0..nu)
                .map(|i| reals((0..nv).map(|j| s.weight(i, j))))
                .collect();
            vec![
                ("B_SPLINE_SURFACE", head),
                ("B_SPLINE_SURFACE_WITH_KNOTS", tail),
                ("RATIONAL_B_SPLINE_SURFACE", vec![Value::List(w)]),
            ]
        } else {
            let mut p = vec![text("")];
            p.extend(head);
            p.extend(tail);
            vec![("B_SPLINE_SURFACE_WITH_KNOTS", p)]
        }
    }
}

/// Joins the pieces of one curve into one NURBS when it has one piece.
fn one_piece(pieces: Vec<Piece>) -> Option<Nurbs3> {
    match <[Piece; 1]>::try_from(pieces) {
        Ok([p]) => Some(p.nurbs()),
        Err(_) => None,
    }
}

impl Iges<'_> {
    /// The transformation matrix (124) of entity `k`, if it has one.
    pub(super) fn own_transform(&self, k: usize) -> Result<Option<DAffine3>, IgesError> {
        let e = &self.dir[k];
        if e.transform == 0 {
            return Ok(None);
        }
        let t = self.entry(e.transform).ok_or_else(|| {
            self.entity_error(
                k,
                e.line,
                format!(
                    "transformation pointer {} is not a directory entry",
                    e.transform
                ),
            )
        })?;
        Ok(Some(self.transform(t, 0)?))
    }

    /// The directory index a pointer parameter names, checked to be of one
    /// of `types`.
    pub(super) fn pointer(
        &self,
        k: usize,
        p: &[(Param, usize)],
        n: usize,
        line: usize,
        types: &[i64],
    ) -> Result<usize, IgesError> {
        let de = param(self, k, p, n, line, &INT)?;
        let t = self.entry(de).ok_or_else(|| {
            self.entity_error(
                k,
                line,
                format!("parameter {n}: pointer {de} is not a directory entry"),
            )
        })?;
        if !types.contains(&self.dir[t].entity_type) {
            return Err(self.entity_error(
                k,
                line,
                format!(
                    "parameter {n}: entity {} where {} was expected",
                    self.dir[t].entity_type,
                    types
                        .iter()
                        .map(|t| t.to_string())
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
        Ok(t)
    }

    /// A point entity (116) in model space.
    fn point_116(&self, k: usize) -> Result<Vec3, IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let q = Vec3::new(
            param(self, k, &p, 1, line, &REAL)?,
            param(self, k, &p, 2, line, &REAL)?,
            param(self, k, &p, 3, line, &REAL)?,
        );
        Ok(self.own_transform(k)?.map_or(q, |m| m.transform_point3(q)))
    }

    /// A direction entity (123), normalised, in model space.
    fn direction_123(&self, k: usize) -> Result<Vec3, IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let mut d = Vec3::new(
            param(self, k, &p, 1, line, &REAL)?,
            param(self, k, &p, 2, line, &REAL)?,
            param(self, k, &p, 3, line, &REAL)?,
        );
        if let Some(m) = self.own_transform(k)? {
            d = m.transform_vector3(d);
        }
        let l = d.length();
        if l > 0.0 && l.is_finite() {
            Ok(d / l)
        } else {
            Err(self.entity_error(k, line, "the direction has no length".into()))
        }
    }

    /// A model-space curve entity as one exact NURBS, or an `Unsupported`
    /// error naming it.
    fn model_curve(&self, k: usize) -> Result<Nurbs3, IgesError> {
        let mut pieces = Vec::new();
        self.curve_pieces(k, 0, &mut pieces)?;
        if pieces.is_empty() {
            return Err(self.entity_error(k, self.dir[k].line, "the curve is empty".into()));
        }
        self.joined_pieces(k, pieces)
    }

    /// Writes the surface of a face into the exchange; errors name the
    /// surface entity.
    fn brep_surface(&self, s: usize, id: u64, b: &mut StepBuilder) -> Result<(), IgesError> {
        let e = &self.dir[s];
        let p = self.parameters(s)?;
        let line = p.first().map_or(e.line, |t| t.1);
        if e.entity_type == 140 && e.transform == 0 {
            let base = self.pointer(s, &p, 5, line, &TRANSLATED_SURFACES)?;
            if (190..=198).contains(&self.dir[base].entity_type) {
                let d = param(self, s, &p, 4, line, &REAL)?;
                return self.analytic_surface(base, d, id, b);
            }
        }
        self.analytic_surface(s, 0.0, id, b)
    }

    /// [`Self::brep_surface`] of surface `s`, offset by `offset` along its
    /// normal where it is a plane, cylinder, cone, sphere or torus (190–198,
    /// whose IGES parametrisations have `Su × Sv` pointing out of the solid
    /// they bound; IGES 5.3 §4.20): the offset is the same kind of surface,
    /// moved (plane), of radius `r + d` (cylinder, sphere), minor radius
    /// `r + d` (torus), or moved by `−d·sin θ` along its axis with radius
    /// `r + d·cos θ` (cone of semi-angle θ): exact.
    fn analytic_surface(
        &self,
        s: usize,
        offset: f64,
        id: u64,
        b: &mut StepBuilder,
    ) -> Result<(), IgesError> {
        let e = &self.dir[s];
        let p = self.parameters(s)?;
        let line = p.first().map_or(e.line, |t| t.1);
        let m = self.own_transform(s)?;
        let at = |q: Vec3| m.map_or(q, |m| m.transform_point3(q));
        let along = |d: Vec3| m.map_or(d, |m| m.transform_vector3(d).normalize());
        let point = |n: usize| -> Result<Vec3, IgesError> {
            Ok(at(self.point_116(self.pointer(
                s,
                &p,
                n,
                line,
                &[116],
            )?)?))
        };
        let direction = |n: usize| -> Result<Vec3, IgesError> {
            Ok(along(self.direction_123(self.pointer(
                s,
                &p,
                n,
                line,
                &[123],
            )?)?))
        };
        let optional_direction = |n: usize| -> Result<Option<Vec3>, IgesError> {
            if e.form == 1 && param(self, s, &p, n, line, &INT)? != 0 {
                direction(n).map(Some)
            } else {
                Ok(None)
            }
        };
        let positive = |n: usize, what: &str| -> Result<f64, IgesError> {
            let x = param(self, s, &p, n, line, &REAL)?;
            // a transformation may scale (IGES allows only rigid motions
            // for these surfaces, but a scale would apply to lengths)
            let x = m.map_or(x, |m| x * m.matrix3.determinant().abs().cbrt());
            if x > 0.0 && x.is_finite() {
                Ok(x)
            } else {
                Err(self.entity_error(s, line, format!("the {what} {x} is not positive")))
            }
        };
        let grown = |r: f64, what: &str| -> Result<f64, IgesError> {
            let x = r + offset;
            if x > 0.0 && x.is_finite() {
                Ok(x)
            } else {
                Err(self.unsupported(
                    s,
                    line,
                    format!("an offset by {offset} leaves the {what} {x}, not positive"),
                ))
            }
        };
        let parts = match e.entity_type {
            190 => {
                let n = direction(2)?;
                let o = point(1)? + offset * n;
                let x = optional_direction(3)?;
                let ax = b.placement(o, n, x, line);
                vec![("PLANE", vec![text(""), Value::Ref(ax)])]
            }
            192 => {
                let o = point(1)?;
                let z = direction(2)?;
                let r = grown(positive(3, "radius")?, "radius")?;
                let x = optional_direction(4)?;
                let ax = b.placement(o, z, x, line);
                vec![(
                    "CYLINDRICAL_SURFACE",
                    vec![text(""), Value::Ref(ax), Value::Real(r)],
                )]
            }
            194 => {
                let o = point(1)?;
                let z = direction(2)?;
                let r = param(self, s, &p, 3, line, &REAL)?;
                let semi = param(self, s, &p, 4, line, &REAL)?;
                if !(r >= 0.0 && r.is_finite() && semi > 0.0 && semi < 90.0) {
                    return Err(self.entity_error(
                        s,
                        line,
                        format!(
                            "radius {r} and semi-angle {semi}°: need r ≥ 0 and 0° < angle < 90°"
                        ),
                    ));
                }
                let (sin, cos) = semi.to_radians().sin_cos();
                let o = o - offset * sin * z;
                let r = r + offset * cos;
                if !(r >= 0.0 && r.is_finite()) {
                    return Err(self.unsupported(
                        s,
                        line,
                        format!("an offset by {offset} leaves the cone's radius {r}, negative"),
                    ));
                }
                let x = optional_direction(5)?;
                let ax = b.placement(o, z, x, line);
                vec![(
                    "CONICAL_SURFACE",
                    vec![
                        text(""),
                        Value::Ref(ax),
                        Value::Real(r),
                        Value::Real(semi.to_radians()),
                    ],
                )]
            }
            196 => {
                let o = point(1)?;
                let r = grown(positive(2, "radius")?, "radius")?;
                let (z, x) = if e.form == 1 {
                    (direction(3)?, optional_direction(4)?)
                } else {
                    (Vec3::Z, None)
                };
                let ax = b.placement(o, z, x, line);
                vec![(
                    "SPHERICAL_SURFACE",
                    vec![text(""), Value::Ref(ax), Value::Real(r)],
                )]
            }
            198 => {
                let o = point(1)?;
                let z = direction(2)?;
                let big = positive(3, "major radius")?;
                let small = grown(positive(4, "minor radius")?, "minor radius")?;
                let x = optional_direction(5)?;
                let ax = b.placement(o, z, x, line);
                vec![(
                    "TOROIDAL_SURFACE",
                    vec![
                        text(""),
                        Value::Ref(ax),
                        Value::Real(big),
                        Value::Real(small),
                    ],
                )]
            }
            120 => {
                let axis_k = self.pointer(s, &p, 1, line, &[110])?;
                let gen_k = self.pointer(s, &p, 2, line, &[100, 102, 104, 110, 126])?;
                let axis = self.model_curve(axis_k)?;
                let (a, z) = match axis.points.as_slice() {
                    [a, c] => (at(*a), at(*c) - at(*a)),
                    _ => {
                        return Err(self.entity_error(s, line, "the axis is not a line".into()));
                    }
                };
                let len = z.length();
                if !(len > 0.0 && len.is_finite()) {
                    return Err(self.entity_error(s, line, "the axis line has no length".into()));
                }
                let mut profile = self.model_curve(gen_k)?;
                profile.points.iter_mut().for_each(|q| *q = at(*q));
                let c = b.curve(&profile, line);
                let o = b.point(a, line);
                let d = b.direction(z / len, line);
                let ax = b.simple(
                    "AXIS1_PLACEMENT",
                    vec![text(""), Value::Ref(o), Value::Ref(d)],
                    line,
                );
                vec![(
                    "SURFACE_OF_REVOLUTION",
                    vec![text(""), Value::Ref(c), Value::Ref(ax)],
                )]
            }
            128 => {
                let surface = super::bspline_surface::read_entity_128(self, s, false)?.surface;
                b.bspline_surface(&surface, line)
            }
            // converted with their own transformation: not applied twice
            114 | 118 | 122 | 140 => {
                let surface = self.convert_surface(s, 0)?.surface;
                b.bspline_surface(&surface, line)
            }
            t => {
                return Err(self.unsupported(
                    s,
                    line,
                    format!("surface entity {t} under a B-rep face is not read (108 under 144; 114, 118, 120, 122, 128, 140, 190, 192, 194, 196, 198 under 510 are)"),
                ));
            }
        };
        b.insert(id, parts, line);
        Ok(())
    }

    /// The VERTEX_POINT of entry `n` (1-based) of vertex list `k`.
    fn brep_vertex(&self, k: usize, n: usize, b: &mut StepBuilder) -> Result<u64, IgesError> {
        if let Some(&id) = b.vertices.get(&(k, n)) {
            return Ok(id);
        }
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let count = param(self, k, &p, 1, line, &INT)?;
        if n == 0 || n as i64 > count {
            return Err(self.entity_error(k, line, format!("vertex {n} of a list of {count}")));
        }
        let c = |i: usize| param(self, k, &p, 2 + 3 * (n - 1) + i, line, &REAL);
        let q = Vec3::new(c(0)?, c(1)?, c(2)?);
        let q = self.own_transform(k)?.map_or(q, |m| m.transform_point3(q));
        let pt = b.point(q, line);
        let id = b.simple("VERTEX_POINT", vec![text(""), Value::Ref(pt)], line);
        b.vertices.insert((k, n), id);
        Ok(id)
    }

    /// The EDGE_CURVE of entry `n` (1-based) of edge list `k`: its curve
    /// from its start vertex to its end vertex.
    fn brep_edge(&self, k: usize, n: usize, b: &mut StepBuilder) -> Result<(u64, u64), IgesError> {
        if let Some(&ids) = b.edges.get(&(k, n)) {
            return Ok(ids);
        }
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let count = param(self, k, &p, 1, line, &INT)?;
        if n == 0 || n as i64 > count {
            return Err(self.entity_error(k, line, format!("edge {n} of a list of {count}")));
        }
        let f = 2 + 5 * (n - 1);
        let ck = self.pointer(k, &p, f, line, &[100, 102, 104, 110, 112, 126])?;
        let curve = self.model_curve(ck)?;
        let vertex = |i: usize, b: &mut StepBuilder| -> Result<u64, IgesError> {
            let list = self.pointer(k, &p, f + i, line, &[502])?;
            let index = param(self, k, &p, f + i + 1, line, &INT)?;
            let index = usize::try_from(index)
                .map_err(|_| self.entity_error(k, line, format!("vertex index {index}")))?;
            self.brep_vertex(list, index, b)
        };
        let (v0, v1) = (vertex(1, b)?, vertex(3, b)?);
        let c = b.curve(&curve, self.dir[ck].line);
        // p-curves are added to its list by the loops that use the edge
        let sc = b.simple(
            "SURFACE_CURVE",
            vec![
                text(""),
                Value::Ref(c),
                Value::List(Vec::new()),
                Value::Enum("PCURVE_S1".into()),
            ],
            line,
        );
        let id = b.simple(
            "EDGE_CURVE",
            vec![
                text(""),
                Value::Ref(v0),
                Value::Ref(v1),
                Value::Ref(sc),
                flag(true),
            ],
            line,
        );
        b.edges.insert((k, n), (id, sc));
        b.edge_points.insert(id, dense_points(&curve));
        Ok((id, sc))
    }

    /// The map from the IGES parameters of surface `s` to ISO 10303-42's,
    /// per coordinate (a scale), where p-curves on it are used: the
    /// B-spline surface's own parameters; the angles of the cylinder, cone,
    /// sphere and torus (192–198, in degrees) to radians, the cone's
    /// distance along its generator to the distance along its axis.
    /// `None` for the others (their trims come from the 3-D edges).
    fn pcurve_scale(&self, s: usize) -> Option<[f64; 2]> {
        let deg = std::f64::consts::PI / 180.0;
        match self.dir[s].entity_type {
            128 => Some([1.0, 1.0]),
            192 => Some([deg, 1.0]),
            196 | 198 => Some([deg, deg]),
            194 => {
                let p = self.parameters(s).ok()?;
                let semi = param(self, s, &p, 4, self.dir[s].line, &REAL).ok()?;
                Some([deg, semi.to_radians().cos()])
            }
            _ => None,
        }
    }

    /// The p-curve of a loop entry (`CURV`, one curve entity) mapped into
    /// ISO 10303-42's parameters by `scale`, in the edge curve's direction;
    /// `None` when it is not one curve fairline reads.
    fn brep_pcurve(&self, curv: i64, scale: [f64; 2], forward: bool) -> Option<Nurbs3> {
        let c = self.entry(curv)?;
        let mut pieces = Vec::new();
        self.curve_pieces(c, 0, &mut pieces).ok()?;
        let mut n = one_piece(pieces)?;
        for q in &mut n.points {
            *q = Vec3::new(q.x * scale[0], q.y * scale[1], 0.0);
        }
        Some(if forward { n } else { n.reversed() })
    }

    /// The EDGE_LOOP of loop entity `k` (508), `None` when it has no edge
    /// (a loop of vertices only), and whether its edges cancel in pairs
    /// (each used once in each direction: seams, as the one loop of a whole
    /// sphere, which bounds nothing).
    fn brep_loop(
        &self,
        k: usize,
        on: Option<(u64, [f64; 2])>,
        b: &mut StepBuilder,
        boundary: &mut Vec<Vec<Vec3>>,
    ) -> Result<Option<(u64, bool)>, IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let count = param(self, k, &p, 1, line, &INT)?;
        if count < 0 || count as usize > p.len() {
            return Err(self.entity_error(k, line, format!("{count} edges")));
        }
        let mut at = 2;
        let mut edges = Vec::new();
        let mut uses: HashMap<u64, i32> = HashMap::new();
        for _ in 0..count {
            let kind = param(self, k, &p, at, line, &INT)?;
            let pcurves = param(self, k, &p, at + 4, line, &INT)?;
            let pcurves = usize::try_from(pcurves)
                .ok()
                .filter(|&n| n <= p.len())
                .ok_or_else(|| self.entity_error(k, line, format!("{pcurves} p-curves")))?;
            match kind {
                0 => {
                    let list = self.pointer(k, &p, at + 1, line, &[504])?;
                    let index = param(self, k, &p, at + 2, line, &INT)?;
                    let index = usize::try_from(index)
                        .map_err(|_| self.entity_error(k, line, format!("edge index {index}")))?;
                    let forward = param(self, k, &p, at + 3, line, &INT)? != 0;
                    let (ec, sc) = self.brep_edge(list, index, b)?;
                    if let Some(pts) = b.edge_points.get(&ec) {
                        boundary.push(pts.clone());
                    }
                    *uses.entry(ec).or_default() += if forward { 1 } else { -1 };
                    if let Some((surface, scale)) = on
                        && pcurves > 0
                        && let Ok(curv) = param(self, k, &p, at + 6, line, &INT)
                        && let Some(c) = self.brep_pcurve(curv, scale, forward)
                    {
                        b.pcurve(sc, surface, &c, line);
                    }
                    edges.push(b.simple(
                        "ORIENTED_EDGE",
                        vec![
                            text(""),
                            Value::Derived,
                            Value::Derived,
                            Value::Ref(ec),
                            flag(forward),
                        ],
                        line,
                    ));
                }
                // a vertex: a degenerate edge at a pole, no curve
                1 => {}
                t => {
                    return Err(self.entity_error(
                        k,
                        line,
                        format!("loop entry type {t} (0 edge, 1 vertex)"),
                    ));
                }
            }
            at += 5 + 2 * pcurves;
        }
        if edges.is_empty() {
            return Ok(None);
        }
        let cancels = edges.len() == 2 * uses.len() && uses.values().all(|&n| n == 0);
        let id = b.simple("EDGE_LOOP", vec![text(""), refs(edges)], line);
        Ok(Some((id, cancels)))
    }

    /// Writes face `k` (510) into the exchange: its loops, then its
    /// surface, then the ADVANCED_FACE (so that a face that fails leaves no
    /// surface behind to be read on its own).
    fn brep_face(
        &self,
        k: usize,
        same_sense: bool,
        b: &mut StepBuilder,
    ) -> Result<(usize, u64), IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let surface = self.pointer(
            k,
            &p,
            1,
            line,
            &[
                108, 114, 118, 120, 122, 128, 140, 143, 144, 190, 192, 194, 196, 198,
            ],
        )?;
        let count = param(self, k, &p, 2, line, &INT)?;
        if count < 0 || count as usize > p.len() {
            return Err(self.entity_error(k, line, format!("{count} loops")));
        }
        let outer_first = param(self, k, &p, 3, line, &INT)? != 0;
        // the surface is written after the loops, under this id
        let si = b.reserve();
        let on = self.pcurve_scale(surface).map(|scale| (si, scale));
        let mut bounds = Vec::new();
        let mut boundary = Vec::new();
        for n in 0..count as usize {
            let lk = self.pointer(k, &p, 4 + n, line, &[508])?;
            if let Some((lp, cancels)) = self.brep_loop(lk, on, b, &mut boundary)? {
                if cancels && count == 1 {
                    // seams only: the face is the whole closed surface
                    continue;
                }
                let kind = if n == 0 && outer_first {
                    "FACE_OUTER_BOUND"
                } else {
                    "FACE_BOUND"
                };
                bounds.push(b.simple(kind, vec![text(""), Value::Ref(lp), flag(true)], line));
            }
        }
        self.brep_surface(surface, si, b)?;
        let face = b.simple(
            "ADVANCED_FACE",
            vec![text(""), refs(bounds), Value::Ref(si), flag(same_sense)],
            line,
        );
        b.boundaries.insert(face, boundary);
        Ok((surface, face))
    }

    /// The orientation flag of every face in a shell (514): `true` when
    /// the face's normal agrees with its surface's.
    fn face_senses(&self) -> HashMap<usize, bool> {
        let mut out = HashMap::new();
        for k in 0..self.dir.len() {
            if self.dir[k].entity_type != 514 {
                continue;
            }
            let Ok(p) = self.parameters(k) else { continue };
            let line = self.dir[k].line;
            let Ok(n) = param(self, k, &p, 1, line, &INT) else {
                continue;
            };
            for i in 0..n.clamp(0, p.len() as i64) as usize {
                let face = param(self, k, &p, 2 + 2 * i, line, &INT)
                    .ok()
                    .and_then(|de| self.entry(de));
                let sense = param(self, k, &p, 3 + 2 * i, line, &INT).unwrap_or(1);
                if let Some(f) = face {
                    out.insert(f, sense != 0);
                }
            }
        }
        out
    }

    /// A trimmed surface (144) whose boundaries' model-space curves (142's
    /// `CPTR`) become the loops: each piece of a boundary curve (a member of
    /// a composite curve 102) is an edge, its ends vertices shared by
    /// position.
    fn face_144(&self, k: usize, b: &mut StepBuilder) -> Result<(usize, u64), IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let surface = self.pointer(k, &p, 1, line, &TRANSLATED_SURFACES)?;
        if param(self, k, &p, 2, line, &INT)? == 0 {
            return Err(self.unsupported(
                k,
                line,
                "an outer boundary that is the boundary of the surface's domain (N1 = 0) on this surface".into(),
            ));
        }
        let holes = param(self, k, &p, 3, line, &INT)?;
        if holes < 0 || holes as usize > p.len() {
            return Err(self.entity_error(k, line, format!("{holes} inner boundaries")));
        }
        let mut vertices: Vec<(Vec3, u64)> = Vec::new();
        let mut bounds = Vec::new();
        let mut boundary = Vec::new();
        for n in 0..=holes as usize {
            let bk = self.pointer(k, &p, 4 + n, line, &[142])?;
            let bp = self.parameters(bk)?;
            let bl = bp.first().map_or(self.dir[bk].line, |t| t.1);
            let cptr = param(self, bk, &bp, 4, bl, &INT)?;
            let Some(c) = self.entry(cptr) else {
                return Err(self.unsupported(
                    bk,
                    bl,
                    "a boundary without a model-space curve (CPTR) on this surface".into(),
                ));
            };
            let mut pieces = Vec::new();
            self.curve_pieces(c, 0, &mut pieces)?;
            let size = pieces
                .iter()
                .flat_map(|q| q.points.iter())
                .fold(0.0_f64, |m, q| m.max(q.abs().max_element()));
            let close = 1e-9 * (1.0 + size);
            let mut vertex = |q: Vec3, b: &mut StepBuilder| -> u64 {
                if let Some((_, id)) = vertices.iter().find(|(v, _)| v.distance(q) <= close) {
                    return *id;
                }
                let pt = b.point(q, bl);
                let id = b.simple("VERTEX_POINT", vec![text(""), Value::Ref(pt)], bl);
                vertices.push((q, id));
                id
            };
            let mut edges = Vec::new();
            for piece in pieces {
                let n = piece.nurbs();
                let [t0, t1] = n.domain();
                let (v0, v1) = (vertex(n.eval(t0), b), vertex(n.eval(t1), b));
                boundary.push(dense_points(&n));
                let curve = b.curve(&n, bl);
                let ec = b.simple(
                    "EDGE_CURVE",
                    vec![
                        text(""),
                        Value::Ref(v0),
                        Value::Ref(v1),
                        Value::Ref(curve),
                        flag(true),
                    ],
                    bl,
                );
                edges.push(b.simple(
                    "ORIENTED_EDGE",
                    vec![
                        text(""),
                        Value::Derived,
                        Value::Derived,
                        Value::Ref(ec),
                        flag(true),
                    ],
                    bl,
                ));
            }
            let lp = b.simple("EDGE_LOOP", vec![text(""), refs(edges)], bl);
            let kind = if n == 0 {
                "FACE_OUTER_BOUND"
            } else {
                "FACE_BOUND"
            };
            bounds.push(b.simple(kind, vec![text(""), Value::Ref(lp), flag(true)], bl));
        }
        let si = b.reserve();
        self.brep_surface(surface, si, b)?;
        let face = b.simple(
            "ADVANCED_FACE",
            vec![text(""), refs(bounds), Value::Ref(si), flag(true)],
            line,
        );
        b.boundaries.insert(face, boundary);
        Ok((surface, face))
    }

    /// Reads every B-rep face (510) of the file, and the trimmed surfaces
    /// (144) `trimmed` through the same translation.
    pub(super) fn brep_faces(&self, trimmed: &[usize]) -> Result<BrepFaces, IgesError> {
        let mut out = BrepFaces {
            bases: vec![false; self.dir.len()],
            ..BrepFaces::default()
        };
        let faces: Vec<usize> = (0..self.dir.len())
            .filter(|&k| self.dir[k].entity_type == 510)
            .chain(trimmed.iter().copied())
            .collect();
        let faces = {
            let mut f = faces;
            f.sort_unstable();
            f
        };
        if faces.is_empty() {
            return Ok(out);
        }
        // every face's surface is the face's, whether the face reads or not
        for &k in &faces {
            if let Some(s) = self.parameters(k).ok().and_then(|p| {
                super::params::text_of(&p, 1)
                    .and_then(super::params::parse_int)
                    .and_then(|de| self.entry(de))
            }) {
                out.bases[s] = true;
            }
        }
        let senses = self.face_senses();
        let mut unread: Vec<(usize, Unreadable)> = Vec::new();
        let mut b = StepBuilder::new();
        let mut face_of: HashMap<u64, (usize, usize)> = HashMap::new();
        for &k in &faces {
            let face = if self.dir[k].entity_type == 144 {
                self.face_144(k, &mut b)
            } else {
                self.brep_face(k, senses.get(&k).copied().unwrap_or(true), &mut b)
            };
            match face {
                Ok((surface, id)) => {
                    face_of.insert(id, (k, surface));
                }
                Err(IgesError::Unsupported { message, .. }) => {
                    unread.push((
                        k,
                        Unreadable {
                            entity: self.describe_entity(k),
                            reason: format!("{}: {message}", face_kind(self.dir[k].entity_type)),
                            estimated_area: None,
                        },
                    ));
                }
                Err(e) => return Err(e),
            }
        }
        let read = crate::io::step::read_exchange(&b.ex).map_err(|e| IgesError::Format {
            line: self.dir[faces[0]].line,
            message: format!("B-rep faces: {e}"),
        })?;
        for s in read.surfaces {
            let Some(&(k, surface)) = face_of.get(&s.entity) else {
                continue;
            };
            if let Some(d) = b
                .boundaries
                .get(&s.entity)
                .and_then(|poly| trims_follow_boundary(&s.surface, poly))
            {
                unread.push((k, Unreadable {
                    entity: self.describe_entity(k),
                    reason: format!(
                        "{}: its trims, computed from its edges, leave its boundary curves by {d:.3e} (more than 1e-3 of the boundary's size): the face could not be bounded reliably",
                        face_kind(self.dir[k].entity_type)
                    ),
                    estimated_area: None,
                }));
                continue;
            }
            let rational = s.surface.is_rational();
            out.surfaces.push(IgesSurface {
                surface: s.surface,
                directory_entry: 2 * k + 1,
                entity_type: self.dir[k].entity_type,
                form: self.dir[surface].entity_type,
                rational,
                closed: [false; 2],
                periodic: [false; 2],
                parameter_range: [0.0; 4],
                transformed: self.dir[surface].transform != 0,
                trimmed: true,
                trim_entity: Some(2 * k + 1),
            });
        }
        for u in read.unreadable {
            let id = u
                .entity
                .trim_start_matches('#')
                .split(' ')
                .next()
                .and_then(|s| s.parse::<u64>().ok());
            let Some(&(k, _)) = id.and_then(|id| face_of.get(&id)) else {
                continue;
            };
            unread.push((
                k,
                Unreadable {
                    entity: self.describe_entity(k),
                    reason: format!(
                        "{}: {}",
                        face_kind(self.dir[k].entity_type),
                        strip_step_id(&u.reason)
                    ),
                    estimated_area: None,
                },
            ));
        }
        out.surfaces.sort_by_key(|s| s.directory_entry);
        unread.sort_by_key(|u| u.0);
        out.unreadable = unread.into_iter().map(|u| u.1).collect();
        Ok(out)
    }
}

/// What a face entity is, for messages.
fn face_kind(entity_type: i64) -> &'static str {
    if entity_type == 144 {
        "a trimmed surface (144)"
    } else {
        "a B-rep face (510)"
    }
}

/// A STEP reader message without its `line L: #id ` prefix (the ids are
/// those of the in-memory exchange, not of the IGES file).
fn strip_step_id(message: &str) -> &str {
    match message.find(": #") {
        Some(i) => {
            let rest = &message[i + 3..];
            rest.find(' ').map_or(rest, |j| &rest[j + 1..])
        }
        None => message,
    }
}

#[cfg(test)]
mod tests {
    use super::super::parse_iges;
    use super::super::tests::{GLOBAL, iges_file};
    use crate::bspline::trimmed_area;
    use std::f64::consts::PI;

    /// A cylinder face of radius 2 and height 3 as OpenCASCADE writes it
    /// in B-rep mode: a 510 on a 192 bounded by one loop of the two end
    /// circles and the seam used in both directions, with p-curves in
    /// (degrees, height).
    fn cylinder(pcurves: bool, surface_type: i64) -> String {
        let surface = format!("{surface_type},7,9,2.,11;");
        let lp = if pcurves {
            "508,4,0,15,1,1,1,0,25,0,15,3,1,1,0,27,0,15,2,0,1,0,29,0,15,3,0,1,0,31;"
        } else {
            "508,4,0,15,1,1,0,0,15,3,1,0,0,15,2,0,0,0,15,3,0,0;"
        };
        let entities = [
            (514, 0, 1, "514,1,3,1;"),
            (510, 0, 1, "510,5,1,1,13;"),
            (surface_type, 0, 1, surface.as_str()),
            (116, 0, 0, "116,0.,0.,0.,0;"),
            (123, 0, 0, "123,0.,0.,1.;"),
            (123, 0, 0, "123,1.,0.,0.;"),
            (508, 0, 1, lp),
            (504, 0, 1, "504,3,17,19,1,19,1,21,19,2,19,2,23,19,1,19,2;"),
            (100, 0, 0, "100,0.,0.,0.,2.,0.,2.,0.;"),
            (502, 0, 1, "502,2,2.,0.,0.,2.,0.,3.;"),
            (100, 0, 0, "100,3.,0.,0.,2.,0.,2.,0.;"),
            (110, 0, 0, "110,2.,0.,0.,2.,0.,3.;"),
            (110, 0, 0, "110,0.,0.,0.,360.,0.,0.;"),
            (110, 0, 0, "110,360.,0.,0.,360.,3.,0.;"),
            (110, 0, 0, "110,360.,3.,0.,0.,3.,0.;"),
            (110, 0, 0, "110,0.,3.,0.,0.,0.,0.;"),
        ];
        iges_file(GLOBAL, &entities)
    }

    #[test]
    fn iges_brep_cylinder_face_is_exact_with_and_without_pcurves() {
        for pcurves in [true, false] {
            let imp = parse_iges(&cylinder(pcurves, 192)).unwrap();
            assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
            assert_eq!(imp.surfaces.len(), 1);
            let face = &imp.surfaces[0];
            assert_eq!((face.entity_type, face.form), (510, 192));
            assert_eq!(face.trim_entity, Some(3));
            let area = trimmed_area(&face.surface, 64, 64);
            let want = 2.0 * PI * 2.0 * 3.0;
            assert!(
                (area - want).abs() <= 1e-6 * want,
                "p-curves {pcurves}: {area} vs {want}"
            );
        }
    }

    #[test]
    fn iges_brep_edge_on_a_composite_curve_is_read() {
        // the cylinder face with its bottom circle given as a composite
        // curve (102) of two half circles
        for pcurves in [true, false] {
            let text = cylinder(pcurves, 192);
            let mut entities: Vec<(i64, i64, i64, String)> = Vec::new();
            // re-made by hand: the fixture's list with DE 17 replaced
            let lp = if pcurves {
                "508,4,0,15,1,1,1,0,25,0,15,3,1,1,0,27,0,15,2,0,1,0,29,0,15,3,0,1,0,31;"
            } else {
                "508,4,0,15,1,1,0,0,15,3,1,0,0,15,2,0,0,0,15,3,0,0;"
            };
            for (t, tr, form, data) in [
                (514, 0, 1, "514,1,3,1;"),
                (510, 0, 1, "510,5,1,1,13;"),
                (192, 0, 1, "192,7,9,2.,11;"),
                (116, 0, 0, "116,0.,0.,0.,0;"),
                (123, 0, 0, "123,0.,0.,1.;"),
                (123, 0, 0, "123,1.,0.,0.;"),
                (508, 0, 1, lp),
                (504, 0, 1, "504,3,17,19,1,19,1,21,19,2,19,2,23,19,1,19,2;"),
                (102, 0, 0, "102,2,33,35;"),
                (502, 0, 1, "502,2,2.,0.,0.,2.,0.,3.;"),
                (100, 0, 0, "100,3.,0.,0.,2.,0.,2.,0.;"),
                (110, 0, 0, "110,2.,0.,0.,2.,0.,3.;"),
                (110, 0, 0, "110,0.,0.,0.,360.,0.,0.;"),
                (110, 0, 0, "110,360.,0.,0.,360.,3.,0.;"),
                (110, 0, 0, "110,360.,3.,0.,0.,3.,0.;"),
                (110, 0, 0, "110,0.,3.,0.,0.,0.,0.;"),
                (100, 0, 0, "100,0.,0.,0.,2.,0.,-2.,0.;"),
                (100, 0, 0, "100,0.,0.,0.,-2.,0.,2.,0.;"),
            ] {
                entities.push((t, tr, form, data.to_string()));
            }
            let list: Vec<(i64, i64, i64, &str)> = entities
                .iter()
                .map(|(a, b, c, d)| (*a, *b, *c, d.as_str()))
                .collect();
            let composite = iges_file(GLOBAL, &list);
            assert_ne!(composite, text);
            let imp = parse_iges(&composite).unwrap();
            assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
            assert_eq!(imp.surfaces.len(), 1);
            let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
            let want = 2.0 * PI * 2.0 * 3.0;
            assert!(
                (area - want).abs() <= 1e-6 * want,
                "p-curves {pcurves}: {area} vs {want}"
            );
        }
    }

    #[test]
    fn iges_brep_face_on_a_surface_not_read_is_listed_not_dropped() {
        // the same face on a plane (108), which is read only under a 144
        let imp = parse_iges(&cylinder(true, 108)).unwrap();
        assert!(imp.surfaces.is_empty());
        assert_eq!(imp.unreadable.len(), 1, "{:?}", imp.unreadable);
        let u = &imp.unreadable[0];
        assert!(u.entity.starts_with("entity 510 (DE 3"), "{u:?}");
        assert!(u.reason.contains("surface entity 108"), "{u:?}");
    }
}
