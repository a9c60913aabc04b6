//! Boundary curves of trimmed surfaces (entity 142) and the curves they are
//! made of (126, 110, 100, 102) as NURBS pieces; boundaries given only in
//! model space are projected onto the surface.

use super::IgesError;
use super::params::{INT, Param, REAL, line_of, param};
use super::records::Iges;
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::step::nurbs::Nurbs3;
use crate::io::step::{invert_point, polyline};

/// A curve of an IGES file as NURBS pieces in model coordinates.
pub(super) struct Piece {
    pub(super) degree: usize,
    pub(super) knots: Vec<f64>,
    pub(super) points: Vec<Vec3>,
    pub(super) weights: Option<Vec<f64>>,
}

impl Piece {
    pub(super) fn to_trim(&self) -> Result<TrimCurve, String> {
        TrimCurve::new(
            self.degree,
            self.knots.clone(),
            self.points.iter().map(|p| [p.x, p.y]).collect(),
            self.weights.clone(),
        )
    }
}

impl Iges<'_> {
    /// Entity 142 (curve on a parametric surface, IGES 5.3 §4.32): `CRTN
    /// SPTR BPTR CPTR PREF`. The parameter-space curve `BPTR` is used; a
    /// boundary given only in model space (`BPTR = 0`) is projected onto
    /// `surface` ([`project_boundary`]); one with neither curve (`BPTR =
    /// CPTR = 0`) gives `None`.
    pub(super) fn boundary_loop(
        &self,
        owner: usize,
        de: i64,
        line: usize,
        surface: &BSplineSurface,
        domain: ([f64; 2], [f64; 2]),
    ) -> Result<Option<TrimLoop>, IgesError> {
        let k = self.entry(de).ok_or_else(|| {
            self.entity_error(
                owner,
                line,
                format!("boundary pointer {de} is not a directory entry"),
            )
        })?;
        if self.dir[k].entity_type != 142 {
            return Err(self.entity_error(
                owner,
                line,
                format!(
                    "boundary {de} is entity {}, not 142",
                    self.dir[k].entity_type
                ),
            ));
        }
        let p = self.parameters(k)?;
        let l142 = p.first().map_or(self.dir[k].line, |t| t.1);
        let bptr = param(self, k, &p, 3, l142, &INT)?;
        let cptr = param(self, k, &p, 4, l142, &INT)?;
        let model_space = || -> Result<Option<TrimLoop>, IgesError> {
            if cptr == 0 {
                return Ok(None);
            }
            let c = self.entry(cptr).ok_or_else(|| {
                self.entity_error(k, l142, format!("CPTR {cptr} is not a directory entry"))
            })?;
            let mut pieces = Vec::new();
            self.curve_pieces(c, 0, &mut pieces)?;
            project_boundary(surface, &pieces)
                .map(Some)
                .map_err(|m| self.entity_error(k, l142, m))
        };
        if bptr == 0 {
            return model_space();
        }
        let c = self.entry(bptr).ok_or_else(|| {
            self.entity_error(k, l142, format!("BPTR {bptr} is not a directory entry"))
        })?;
        let mut pieces = Vec::new();
        self.curve_pieces(c, 0, &mut pieces)?;
        let curves = pieces
            .iter()
            .map(Piece::to_trim)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|m| self.entity_error(c, self.dir[c].line, m))?;
        if curves.is_empty() {
            return Err(self.entity_error(k, l142, "the boundary curve is empty".into()));
        }
        if let Some(far) = beyond_domain(&curves, domain) {
            // parameter-space curves in other parameters than the
            // surface's (OCCT writes those of an offset of a tabulated
            // cylinder in the directrix's own parameter, not the 0..1 of
            // IGES 5.3 §4.19): the model-space curves stand for the
            // boundary; without them it cannot be read
            if cptr == 0 {
                return Err(self.unsupported(
                    k,
                    l142,
                    format!(
                        "its parameter-space curves leave the surface's parameter range {:?} × {:?} (by {far:.3e}) and it has no model-space curve",
                        domain.0, domain.1
                    ),
                ));
            }
            return model_space();
        }
        Ok(Some(TrimLoop { curves }))
    }

    /// The NURBS pieces of curve entity `k`: 126 (rational B-spline curve),
    /// 110 (line), 100 (circular arc, as rational quadratic arcs of at most
    /// 90°, Piegl & Tiller A7.1) and 102 (composite curve, its members in
    /// order); the entity's transformation matrix (124) is applied.
    pub(super) fn curve_pieces(
        &self,
        k: usize,
        depth: usize,
        out: &mut Vec<Piece>,
    ) -> Result<(), IgesError> {
        let e = &self.dir[k];
        if depth > 32 {
            return Err(self.entity_error(k, e.line, "composite curves nest too deeply".into()));
        }
        let p = self.parameters(k)?;
        let line = p.first().map_or(e.line, |t| t.1);
        let start = out.len();
        match e.entity_type {
            102 => {
                let n = param(self, k, &p, 1, line, &INT)?;
                let n = usize::try_from(n)
                    .ok()
                    .filter(|&n| n < p.len())
                    .ok_or_else(|| self.entity_error(k, line, format!("{n} member curves")))?;
                for m in 0..n {
                    let de = param(self, k, &p, 2 + m, line, &INT)?;
                    let c = self.entry(de).ok_or_else(|| {
                        self.entity_error(k, line, format!("member {de} is not a directory entry"))
                    })?;
                    self.curve_pieces(c, depth + 1, out)?;
                }
            }
            110 => {
                let mut r = [0.0; 6];
                for (n, v) in r.iter_mut().enumerate() {
                    *v = param(self, k, &p, n + 1, line, &REAL)?;
                }
                out.push(Piece {
                    degree: 1,
                    knots: vec![0.0, 0.0, 1.0, 1.0],
                    points: vec![Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5])],
                    weights: None,
                });
            }
            100 => {
                let mut r = [0.0; 7];
                for (n, v) in r.iter_mut().enumerate() {
                    *v = param(self, k, &p, n + 1, line, &REAL)?;
                }
                let (z, c) = (r[0], [r[1], r[2]]);
                let a0 = (r[4] - c[1]).atan2(r[3] - c[0]);
                let mut a1 = (r[6] - c[1]).atan2(r[5] - c[0]);
                let radius = (r[3] - c[0]).hypot(r[4] - c[1]);
                while a1 <= a0 {
                    a1 += 2.0 * std::f64::consts::PI;
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(self.entity_error(k, line, "the arc has no radius".into()));
                }
                out.push(arc_piece(c, z, radius, a0, a1));
            }
            126 => out.push(self.read_entity_126(k, &p, line)?),
            112 => out.push(self.read_entity_112(k, &p, line)?),
            104 => {
                let (c, _) = self.conic(k, &p, line)?;
                out.push(Piece {
                    degree: c.degree,
                    knots: c.knots,
                    points: c.points,
                    weights: c.weights,
                });
            }
            t => {
                return Err(self.unsupported(
                    k,
                    line,
                    format!("curve entity {t} is not supported in a trimming boundary (126, 112, 110, 104, 100, 102 are)"),
                ));
            }
        }
        if e.transform != 0 {
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
            let m = self.transform(t, 0)?;
            for piece in &mut out[start..] {
                for q in &mut piece.points {
                    *q = m.transform_point3(*q);
                }
            }
        }
        Ok(())
    }

    /// Entity 126, rational B-spline curve (IGES 5.3 §4.23): `K M PROP1..4`,
    /// knots, weights, control points, `V0 V1`.
    fn read_entity_126(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Piece, IgesError> {
        let kk = param(self, k, p, 1, line, &INT)?;
        let m = param(self, k, p, 2, line, &INT)?;
        let (Ok(kk), Ok(m)) = (usize::try_from(kk), usize::try_from(m)) else {
            return Err(self.entity_error(k, line, format!("K = {kk}, M = {m}")));
        };
        let count = kk + 1;
        let nk = count + m + 1;
        let needed = 7usize
            .saturating_add(nk)
            .saturating_add(count.saturating_mul(4))
            .saturating_add(2);
        if p.len() < needed {
            return Err(self.entity_error(
                k,
                line_of(p, p.len(), line),
                format!("{} parameters, but K={kk}, M={m} need {needed}", p.len()),
            ));
        }
        let polynomial = param(self, k, p, 5, line, &INT)? == 1;
        let reals = |from: usize, n: usize| -> Result<Vec<f64>, IgesError> {
            (from..from + n)
                .map(|i| param(self, k, p, i, line, &REAL))
                .collect()
        };
        let knots = reals(7, nk)?;
        let weights = reals(7 + nk, count)?;
        let xyz = reals(7 + nk + count, 3 * count)?;
        Ok(Piece {
            degree: m,
            knots,
            points: xyz.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect(),
            weights: (!polynomial).then_some(weights),
        })
    }
}

/// Samples per model-space curve piece projected onto a surface
/// ([`project_boundary`]) per control point and degree, at least 16.
const PROJECTION_SAMPLES: usize = 16;

impl Piece {
    /// The piece as a NURBS curve (for evaluation).
    pub(super) fn nurbs(&self) -> Nurbs3 {
        Nurbs3 {
            degree: self.degree,
            knots: self.knots.clone(),
            points: self.points.clone(),
            weights: self.weights.clone(),
        }
    }
}

/// The parameter-space curves of a boundary given only in model space
/// (142 with `BPTR = 0`): each piece is sampled (16 points per control
/// point and degree), every sample projected onto `surface` (closest point,
/// Newton from the previous sample's parameters, Piegl & Tiller §6.1) and
/// the parameters joined into a polyline. A sample farther from the surface
/// than 1e-4 of the control net's size is an error: the curve does not lie
/// on the surface.
pub(super) fn project_boundary(
    surface: &BSplineSurface,
    pieces: &[Piece],
) -> Result<TrimLoop, String> {
    let size = {
        let (a, b) = surface.control_bounding_box();
        (b - a).length().max(f64::MIN_POSITIVE)
    };
    let mut curves = Vec::with_capacity(pieces.len());
    let mut guess = None;
    for piece in pieces {
        let c = piece.nurbs();
        let [t0, t1] = c.domain();
        let n = (PROJECTION_SAMPLES * piece.points.len() * piece.degree.max(1)).clamp(16, 4000);
        let mut uv = Vec::with_capacity(n + 1);
        for k in 0..=n {
            let q = c.eval(t0 + (t1 - t0) * k as f64 / n as f64);
            let (u, v) = invert_point(surface, q, guess);
            let gap = surface.eval(u, v).distance(q);
            if !(gap <= 1e-4 * size) {
                return Err(format!(
                    "the model-space boundary curve is {gap:.3e} away from the surface at ({:.6}, {:.6}, {:.6}): it cannot be projected",
                    q.x, q.y, q.z
                ));
            }
            guess = Some((u, v));
            uv.push([u, v]);
        }
        curves.push(polyline(&uv)?);
    }
    if curves.is_empty() {
        return Err("the boundary curve is empty".into());
    }
    Ok(TrimLoop { curves })
}

/// A circular arc of `radius` around `c` in the plane `z`, from angle `a0`
/// to `a1 > a0`, as a rational quadratic B-spline (Piegl & Tiller A7.1).
fn arc_piece(c: [f64; 2], z: f64, radius: f64, a0: f64, a1: f64) -> Piece {
    let sweep = a1 - a0;
    let arcs = ((sweep / std::f64::consts::FRAC_PI_2).ceil() as usize).clamp(1, 4);
    let d = sweep / arcs as f64;
    let w1 = (0.5 * d).cos();
    let at = |a: f64, r: f64| Vec3::new(c[0] + r * a.cos(), c[1] + r * a.sin(), z);
    let mut points = vec![at(a0, radius)];
    let mut weights = vec![1.0];
    let mut knots = vec![0.0; 3];
    for i in 0..arcs {
        let am = a0 + (i as f64 + 0.5) * d;
        points.push(at(am, radius / w1));
        weights.push(w1);
        points.push(at(a0 + (i + 1) as f64 * d, radius));
        weights.push(1.0);
        let t = (i + 1) as f64 / arcs as f64;
        if i + 1 < arcs {
            knots.push(t);
            knots.push(t);
        }
    }
    knots.extend([1.0; 3]);
    Piece {
        degree: 2,
        knots,
        points,
        weights: Some(weights),
    }
}

/// How far the farthest of 32 points along each curve of a boundary lies
/// outside the parameter range `domain`, where that is more than 1e-6 of
/// the range's size (rounding of the file's numbers stays within it);
/// `None` when every point lies within.
fn beyond_domain(curves: &[TrimCurve], (u, v): ([f64; 2], [f64; 2])) -> Option<f64> {
    let size = (u[1] - u[0]).abs().max((v[1] - v[0]).abs());
    let slack = 1e-6 * size;
    let outside = |x: f64, [a, b]: [f64; 2]| (a.min(b) - x).max(x - a.max(b)).max(0.0);
    let far = curves
        .iter()
        .flat_map(|c| {
            let [t0, t1] = c.domain();
            (0..=32).map(move |i| c.eval(t0 + (t1 - t0) * i as f64 / 32.0))
        })
        .map(|q| outside(q[0], u).max(outside(q[1], v)))
        .fold(0.0, f64::max);
    (far > slack).then_some(far)
}
