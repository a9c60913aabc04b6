//! The oriented edges of a face bound: their curves, parameter ranges and
//! the points along them.

use super::curves::{Curve, conic_range, vertex_param};
use super::{R, Reader};
use crate::Vec3;
use crate::io::step::nurbs::Nurbs3;
use crate::io::step::p21::Instance;

/// An oriented edge of a face bound, as a piece of a curve.
pub(super) struct EdgeUse {
    /// `#id` of the EDGE_CURVE.
    pub(super) edge: u64,
    /// Its curve (a SURFACE_CURVE resolved to its 3-D curve).
    pub(super) curve: Curve,
    /// The instance the curve came from (for p-curves).
    pub(super) curve_entity: u64,
    /// Start and end points in traversal order.
    pub(super) start: Vec3,
    pub(super) end: Vec3,
    /// Start and end vertices are the same.
    pub(super) closed: bool,
    /// Traversal runs along the curve's parameter direction.
    pub(super) forward: bool,
}

impl<'a> Reader<'a> {
    /// The edges of one FACE_BOUND's EDGE_LOOP (None for a VERTEX_LOOP).
    pub(super) fn bound_edges(&self, bound: &'a Instance) -> R<Option<(bool, Vec<EdgeUse>)>> {
        let p = self.params(bound, &["FACE_OUTER_BOUND", "FACE_BOUND"])?;
        let outer = bound.type_name() == "FACE_OUTER_BOUND";
        let lp = self.refer(bound, p, 1)?;
        let sense = self.flag(bound, p, 2)?;
        if lp.type_name() == "VERTEX_LOOP" {
            return Ok(None);
        }
        let lpp = self.params(lp, &["EDGE_LOOP"])?;
        let mut edges = Vec::new();
        for oe in self.refs(lp, self.list(lp, lpp, 1)?)? {
            let op = self.params(oe, &["ORIENTED_EDGE"])?;
            let ec = self.refer(oe, op, 3)?;
            let orientation = self.flag(oe, op, 4)?;
            let ep = self.params(ec, &["EDGE_CURVE"])?;
            let vertex = |k: usize| -> R<(u64, Vec3)> {
                let v = self.refer(ec, ep, k)?;
                let vp = self.params(v, &["VERTEX_POINT"])?;
                Ok((v.id, self.point(self.refer(v, vp, 1)?)?))
            };
            let (v1, v2) = (vertex(1)?, vertex(2)?);
            let ci = self.refer(ec, ep, 3)?;
            let curve = self.curve(ci)?;
            let same = self.flag(ec, ep, 4)?;
            let (start, end) = if orientation { (v1, v2) } else { (v2, v1) };
            edges.push(EdgeUse {
                edge: ec.id,
                curve,
                curve_entity: ci.id,
                start: start.1,
                end: end.1,
                closed: v1.0 == v2.0 || v1.1 == v2.1,
                forward: same == orientation,
            });
        }
        if !sense {
            edges.reverse();
            for e in &mut edges {
                std::mem::swap(&mut e.start, &mut e.end);
                e.forward = !e.forward;
            }
        }
        Ok(Some((outer, edges)))
    }

    /// The traversal parameters `[t_start, t_end]` of an edge on its curve.
    pub(super) fn edge_range(&self, e: &EdgeUse) -> [f64; 2] {
        match &e.curve {
            Curve::Line { .. } => [e.curve.param_of(e.start), e.curve.param_of(e.end)],
            Curve::Conic { .. } => conic_range(
                e.curve.param_of(e.start),
                e.curve.param_of(e.end),
                e.closed,
                e.forward,
            ),
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                if e.closed {
                    if e.forward { [a, b] } else { [b, a] }
                } else {
                    let (ts, te) = (vertex_param(n, e.start), vertex_param(n, e.end));
                    seam_vertex_params(n, ts, te, e.forward)
                }
            }
        }
    }

    /// The edge as an exact NURBS curve in traversal order where one
    /// exists (lines, conic arcs, whole B-spline curves), else `None`.
    pub(super) fn edge_nurbs(&self, e: &EdgeUse) -> Option<Nurbs3> {
        let [t0, t1] = self.edge_range(e);
        match &e.curve {
            Curve::Line { .. } => Some(Nurbs3::segment(
                e.curve.eval(t0),
                e.curve.eval(t1),
                0.0,
                1.0,
            )),
            Curve::Conic { .. } => e.curve.conic_arc([t0, t1]),
            Curve::Spline(n) => {
                let [a, b] = n.domain();
                let tol = 1e-9 * (b - a);
                if (t0 - a).abs() <= tol && (t1 - b).abs() <= tol {
                    Some(n.clone())
                } else if (t0 - b).abs() <= tol && (t1 - a).abs() <= tol {
                    Some(n.reversed())
                } else {
                    None
                }
            }
        }
    }

    /// Dense points along an edge in traversal order (both ends included).
    pub(super) fn edge_points(&self, e: &EdgeUse) -> Vec<Vec3> {
        self.edge_samples(e).into_iter().map(|(_, q)| q).collect()
    }

    /// [`Self::edge_points`] with their curve parameters.
    pub(super) fn edge_samples(&self, e: &EdgeUse) -> Vec<(f64, Vec3)> {
        let [t0, t1] = self.edge_range(e);
        let n = match &e.curve {
            Curve::Line { .. } => 32,
            Curve::Conic { .. } => ((t1 - t0).abs().to_degrees() * 2.0).ceil() as usize,
            Curve::Spline(s) => 16 * s.points.len() * s.degree,
        }
        .clamp(8, 4000);
        (0..=n)
            .map(|k| {
                let t = t0 + (t1 - t0) * k as f64 / n as f64;
                (t, e.curve.eval(t))
            })
            .collect()
    }
}

/// The traversal parameters of an edge from `ts` to `te` on the B-spline
/// curve `n`: as they are, except on a closed curve (its ends meet to
/// 1e-9 of its size) where a vertex lies at the closure point, whose
/// parameter is either end of the domain: there the start takes the end
/// the traversal leaves from and the end the one it arrives at (`forward`:
/// along the curve's direction), so that the edge is the piece between
/// its vertices in its own sense and not the rest of the curve (OCCT
/// writes an arc of an offset circle as a closed B-spline curve with one
/// vertex at its start).
fn seam_vertex_params(n: &Nurbs3, ts: f64, te: f64, forward: bool) -> [f64; 2] {
    let [a, b] = n.domain();
    let (lo, hi) = n
        .points
        .iter()
        .fold((n.points[0], n.points[0]), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let closed = n.eval(a).distance(n.eval(b)) <= 1e-9 * (hi - lo).length();
    if !closed {
        return [ts, te];
    }
    let tol = 1e-9 * (b - a);
    let at_end = |t: f64| (t - a).abs() <= tol || (t - b).abs() <= tol;
    let (leave, arrive) = if forward { (a, b) } else { (b, a) };
    [
        if at_end(ts) { leave } else { ts },
        if at_end(te) { arrive } else { te },
    ]
}
