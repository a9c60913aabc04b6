//! The topology of B-rep faces as STEP entities: vertices (502), edges (504),
//! their parameter-space curves, loops (508) and faces (510).

use std::collections::HashMap;

use super::dense_points;
use super::geometry::one_piece;
use super::step_builder::{StepBuilder, flag, refs, text};
use crate::Vec3;
use crate::io::iges_read::IgesError;
use crate::io::iges_read::params::{INT, REAL, param};
use crate::io::iges_read::records::Iges;
use crate::io::step::nurbs::Nurbs3;
use crate::io::step::p21::Value;

impl Iges<'_> {
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
    pub(super) fn brep_face(
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
}
