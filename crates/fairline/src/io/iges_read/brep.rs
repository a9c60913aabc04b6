//! IGES B-rep faces (IGES 5.3 §4.136–4.148: manifold solid 186, shell 514,
//! face 510, loop 508, edge list 504, vertex list 502), read through the
//! STEP reader's topology.
//!
//! A face (510) is a surface bounded by loops (508) of oriented edges; an
//! edge is an entry of an edge list (504): a model-space curve from one
//! vertex (an entry of a vertex list, 502) to another. That is exactly
//! ISO 10303-42's `ADVANCED_FACE` – `FACE_BOUND` – `EDGE_LOOP` –
//! `ORIENTED_EDGE` – `EDGE_CURVE` – `VERTEX_POINT`, so every face is
//! written into an in-memory STEP exchange ([`Exchange`](crate::io::step::p21::Exchange)) and read by the
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

use super::boundary::Piece;
use super::{
    Iges, IgesError, IgesSurface, Nurbs3, Param, Unreadable, Vec3, params::INT, params::param,
};
use crate::bspline::BSplineSurface;
use crate::io::step::p21::Value;
use step_builder::{StepBuilder, flag, refs, text};

mod geometry;
mod step_builder;
#[cfg(test)]
mod tests;
mod topology;

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
    /// `CPTR`) become the loops ([`Self::face_of_loops`]).
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
        let mut loops = Vec::with_capacity(holes as usize + 1);
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
            loops.push((bl, pieces));
        }
        self.face_of_loops(line, surface, loops, b)
    }

    /// A bounded surface (143) on a surface the B-rep path translates (the
    /// analytic 190–198): its boundaries' (141) model-space curves, each
    /// reversed where its `SENSE` is 2, become the loops
    /// ([`Self::face_of_loops`]), the first the outer one.
    fn face_143(&self, k: usize, b: &mut StepBuilder) -> Result<(usize, u64), IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let surface = self.pointer(k, &p, 2, line, &TRANSLATED_SURFACES)?;
        let loops = self
            .boundaries_143(k, &p, line)?
            .into_iter()
            .map(|bk| {
                let c = self.curves_141(bk, false)?;
                Ok((c.line, c.model))
            })
            .collect::<Result<Vec<_>, IgesError>>()?;
        self.face_of_loops(line, surface, loops, b)
    }

    /// The face on `surface` bounded by `loops` (each its line, for the
    /// exchange's messages, and its model-space curve pieces in order along
    /// it; the first the outer bound): every piece (a member of a
    /// composite curve 102) is an edge, its ends vertices shared by
    /// position. Returns the surface and the face's id in `b`.
    fn face_of_loops(
        &self,
        line: usize,
        surface: usize,
        loops: Vec<(usize, Vec<Piece>)>,
        b: &mut StepBuilder,
    ) -> Result<(usize, u64), IgesError> {
        let mut vertices: Vec<(Vec3, u64)> = Vec::new();
        let mut bounds = Vec::new();
        let mut boundary = Vec::new();
        for (n, (bl, pieces)) in loops.into_iter().enumerate() {
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

    /// Reads every B-rep face (510) of the file, and the trimmed (144) and
    /// bounded (143) surfaces `trimmed` through the same translation.
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
            let slot = if self.dir[k].entity_type == 143 { 2 } else { 1 };
            if let Some(s) = self.parameters(k).ok().and_then(|p| {
                super::params::text_of(&p, slot)
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
            let face = match self.dir[k].entity_type {
                144 => self.face_144(k, &mut b),
                143 => self.face_143(k, &mut b),
                _ => self.brep_face(k, senses.get(&k).copied().unwrap_or(true), &mut b),
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
    match entity_type {
        144 => "a trimmed surface (144)",
        143 => "a bounded surface (143)",
        _ => "a B-rep face (510)",
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
