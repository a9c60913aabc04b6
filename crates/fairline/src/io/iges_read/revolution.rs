//! Surfaces of revolution (entity 120) converted exactly to NURBS, and
//! their trimming loops mapped from the file's `(t, θ)`.

use glam::DMat3;

use super::params::{INT, REAL, param};
use super::records::Iges;
use super::{IgesError, IgesSurface, faces};
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::step::nurbs::{ArcMap, Nurbs3, revolve};

/// A surface of revolution (entity 120) converted to NURBS.
#[derive(Clone, Debug)]
pub(super) struct Revolved {
    /// `u`: the generatrix parameter; `v`: the arcs' parameter.
    pub(super) surface: BSplineSurface,
    /// The arcs in `v` (parameter = angle at their joints).
    pub(super) map: ArcMap,
    /// The arcs in `u` of a circular-arc generatrix (100), whose file
    /// parameter is the arc's angle; `None`: `u` is the file's `t`.
    pub(super) tmap: Option<ArcMap>,
    /// `[SA, TA]`.
    pub(super) angles: [f64; 2],
    /// A transformation matrix (124) of the 120 was applied.
    transformed: bool,
}

impl Revolved {
    /// A trimming loop in the file's `(t, θ)` mapped to the surface's
    /// `(t, v)`: a degree-1 curve whose every segment is parallel to an axis
    /// keeps its form (the map of θ is monotone, so such a segment stays a
    /// segment), with each control point's θ mapped exactly; any other curve
    /// becomes a C¹ piecewise cubic within 1e-9 of the domain's diagonal of
    /// the curve with θ mapped, broken where the curve has a knot or crosses
    /// an arc joint ([`faces::hermite_trim`]).
    pub(super) fn map_loop(&self, l: &TrimLoop) -> Result<TrimLoop, String> {
        let curves = l
            .curves
            .iter()
            .map(|c| {
                let pts = c.control_points();
                let axis_parallel = c.degree() == 1
                    && c.weights().is_none()
                    && pts
                        .windows(2)
                        .all(|w| w[0][0] == w[1][0] || w[0][1] == w[1][1]);
                let t = |x: f64| self.tmap.map_or(x, |m| m.param(x));
                if axis_parallel {
                    let mapped = pts
                        .iter()
                        .map(|p| [t(p[0]), self.map.param(p[1])])
                        .collect();
                    TrimCurve::new(1, c.knots().to_vec(), mapped, None)
                } else {
                    let [t0, t1] = c.domain();
                    let n = (64 * pts.len() * c.degree()).clamp(64, 8000);
                    let f = |x: f64| {
                        let p = c.eval(x);
                        [t(p[0]), self.map.param(p[1])]
                    };
                    // kinks: the curve's own knots and where it crosses an
                    // arc joint of either map
                    let mut breaks: Vec<f64> = c.knots().to_vec();
                    let joints = |m: &ArcMap| -> Vec<f64> {
                        (1..m.arcs)
                            .map(|k| m.start + k as f64 * m.sweep / m.arcs as f64)
                            .collect()
                    };
                    let at = |k: usize| t0 + (t1 - t0) * k as f64 / n as f64;
                    for (coord, m) in [(1, Some(self.map)), (0, self.tmap)] {
                        let Some(m) = m else { continue };
                        for j in joints(&m) {
                            let side = |x: f64| c.eval(x)[coord] < j;
                            for k in 0..n {
                                let (lo, hi) = (at(k), at(k + 1));
                                if side(lo) != side(hi) {
                                    breaks.push(faces::crossing(&side, lo, hi));
                                }
                            }
                        }
                    }
                    let (du, dv) = (self.surface.domain_u(), self.surface.domain_v());
                    let tol = 1e-9 * (du[1] - du[0]).hypot(dv[1] - dv[0]);
                    faces::hermite_trim(&f, t0, t1, &mut breaks, tol)
                }
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(TrimLoop { curves })
    }

    /// The import record of entity `k`.
    pub(super) fn into_iges_surface(self, k: usize, trimmed: bool) -> IgesSurface {
        let (u, v) = (self.surface.domain_u(), self.angles);
        let full_turn = (v[1] - v[0]).abs() >= 2.0 * std::f64::consts::PI * (1.0 - 1e-12);
        IgesSurface {
            surface: self.surface,
            directory_entry: 2 * k + 1,
            entity_type: 120,
            form: 0,
            rational: true,
            closed: [false, full_turn],
            periodic: [false, false],
            parameter_range: [u[0], u[1], v[0], v[1]],
            transformed: self.transformed,
            trimmed,
            trim_entity: None,
        }
    }
}

impl Iges<'_> {
    /// Entity 120, surface of revolution (IGES 5.3 §4.18): `L C SA TA`,
    /// the axis line `L` (110) directed from its start to its end point,
    /// the generatrix `C(t)` rotated about it by the right-hand rule from
    /// `SA` to `TA` (radians, measured from the generatrix's position). The
    /// generatrix must be one line (110) or B-spline curve (126); otherwise
    /// `None` (counted in [`IgesImport::skipped_surfaces`](super::IgesImport::skipped_surfaces)). Exact: Piegl &
    /// Tiller A8.1 ([`revolve`]) with arcs of at most 90°.
    pub(super) fn read_entity_120(&self, k: usize) -> Result<Option<Revolved>, IgesError> {
        self.revolved_offset(k, 0.0)
    }

    /// [`Self::read_entity_120`] of the surface offset by `offset` along
    /// its normal `Su × Sv` (IGES 5.3 §4.20), for a line generatrix (110)
    /// whose offset is the line moved by `offset` along that normal (the
    /// same all along it): exact. `None` for other generatrices when
    /// `offset ≠ 0`, and where the transformation (124) is not a rigid
    /// motion.
    pub(super) fn revolved_offset(
        &self,
        k: usize,
        offset: f64,
    ) -> Result<Option<Revolved>, IgesError> {
        let e = &self.dir[k];
        let p = self.parameters(k)?;
        let line = p.first().map_or(e.line, |t| t.1);
        let pointer = |n: usize| -> Result<usize, IgesError> {
            let de = param(self, k, &p, n, line, &INT)?;
            self.entry(de).ok_or_else(|| {
                self.entity_error(k, line, format!("pointer {de} is not a directory entry"))
            })
        };
        let (axis_k, gen_k) = (pointer(1)?, pointer(2)?);
        let (sa, ta) = (
            param(self, k, &p, 3, line, &REAL)?,
            param(self, k, &p, 4, line, &REAL)?,
        );
        if !(sa.is_finite() && ta.is_finite() && ta > sa) {
            return Err(self.entity_error(
                k,
                line,
                format!("start angle {sa} and terminate angle {ta}: need SA < TA"),
            ));
        }
        if self.dir[axis_k].entity_type != 110 {
            return Err(self.entity_error(
                k,
                line,
                format!(
                    "the axis is entity {}, not a line (110)",
                    self.dir[axis_k].entity_type
                ),
            ));
        }
        let mut axis = Vec::new();
        self.curve_pieces(axis_k, 0, &mut axis)?;
        let (a, b) = match axis.first().map(|l| &l.points[..]) {
            Some([a, b]) => (*a, *b),
            _ => return Err(self.entity_error(k, line, "the axis line has no points".into())),
        };
        let dir = b - a;
        let len = dir.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(self.entity_error(k, line, "the axis line has no length".into()));
        }
        if offset != 0.0 && self.dir[gen_k].entity_type != 110 {
            return Ok(None);
        }
        let Some((mut profile, tmap)) = self.generatrix(gen_k)? else {
            return Ok(None);
        };
        if offset != 0.0 && !offset_line_profile(&mut profile, a, dir / len, offset) {
            return Ok(None);
        }
        let map = ArcMap::new(sa, ta, 1.0);
        let (knots_v, pts, w) = revolve(a, dir / len, &profile, &map);
        // revolve lays the net out angle-major; the file's u is the
        // generatrix parameter: transpose.
        let (nv, nu) = (knots_v.len() - 3, profile.points.len());
        let transform = if e.transform != 0 {
            let t = self.entry(e.transform).ok_or_else(|| {
                self.entity_error(
                    k,
                    line,
                    format!(
                        "transformation pointer {} is not a directory entry",
                        e.transform
                    ),
                )
            })?;
            Some(self.transform(t, 0)?)
        } else {
            None
        };
        if offset != 0.0
            && let Some(m) = &transform
        {
            let g = m.matrix3.transpose() * m.matrix3;
            if !g.abs_diff_eq(DMat3::IDENTITY, 1e-12) {
                return Ok(None);
            }
        }
        let mut points = Vec::with_capacity(nu * nv);
        let mut weights = Vec::with_capacity(nu * nv);
        for i in 0..nu {
            for j in 0..nv {
                let q = pts[j * nu + i];
                points.push(transform.map_or(q, |t| t.transform_point3(q)));
                weights.push(w[j * nu + i]);
            }
        }
        let surface = BSplineSurface::from_flat(
            profile.degree,
            2,
            profile.knots.clone(),
            knots_v,
            [nu, nv],
            points,
            Some(weights),
        )
        .map_err(|source| IgesError::Surface {
            entity: 2 * k + 1,
            line,
            source,
        })?;
        Ok(Some(Revolved {
            surface,
            map,
            tmap,
            angles: [sa, ta],
            transformed: transform.is_some(),
        }))
    }
}

impl Iges<'_> {
    /// The generatrix `gen_k` of a surface of revolution as one NURBS curve,
    /// with the map from the file's parameter to the curve's for an arc (100)
    /// or an elliptic arc (104); `None` for a generatrix that is not one line
    /// (110), B-spline curve (126), circular arc or elliptic arc.
    fn generatrix(&self, gen_k: usize) -> Result<Option<(Nurbs3, Option<ArcMap>)>, IgesError> {
        Ok(Some(match self.dir[gen_k].entity_type {
            110 | 126 => {
                let mut generatrix = Vec::new();
                self.curve_pieces(gen_k, 0, &mut generatrix)?;
                let [profile] = &generatrix[..] else {
                    return Ok(None);
                };
                (profile.nurbs(), None)
            }
            100 => {
                let (c, m) = self.arc_generatrix(gen_k)?;
                (c, Some(m))
            }
            104 => {
                let p = self.parameters(gen_k)?;
                let l = p.first().map_or(self.dir[gen_k].line, |t| t.1);
                match self.conic(gen_k, &p, l) {
                    // an ellipse's file parameter is its eccentric angle,
                    // which the arcs' parameter equals at their joints
                    Ok((mut c, Some(m))) => {
                        self.transform_nurbs(gen_k, &mut c)?;
                        (c, Some(m))
                    }
                    Ok(_) | Err(IgesError::Unsupported { .. }) => return Ok(None),
                    Err(e) => return Err(e),
                }
            }
            _ => return Ok(None),
        }))
    }
}

/// Moves a line generatrix `profile` by `offset` along the normal of the
/// surface it sweeps about the axis through `a` along the unit `z` (the
/// same all along a line); false when the line gives no normal.
fn offset_line_profile(profile: &mut Nurbs3, a: Vec3, z: Vec3, offset: f64) -> bool {
    let radial = |q: Vec3| (q - a) - (q - a).dot(z) * z;
    let [p0, p1] = [profile.points[0], profile.points[profile.points.len() - 1]];
    let far = if radial(p0).length() >= radial(p1).length() {
        p0
    } else {
        p1
    };
    let n = (p1 - p0).cross(z.cross(radial(far)));
    let l = n.length();
    if !(l > 0.0 && l.is_finite()) {
        return false;
    }
    for q in &mut profile.points {
        *q += offset * n / l;
    }
    true
}

impl Iges<'_> {
    /// A circular arc (100) as the generatrix of a surface of revolution:
    /// rational quadratic arcs of at most 90° whose parameter is the arc's
    /// angle at their joints and ends ([`ArcMap`] with scale 1; the IGES
    /// arc is parametrised by its angle, IGES 5.3 §4.3), the arc's
    /// transformation matrix applied.
    pub(super) fn arc_generatrix(&self, k: usize) -> Result<(Nurbs3, ArcMap), IgesError> {
        let e = &self.dir[k];
        let p = self.parameters(k)?;
        let line = p.first().map_or(e.line, |t| t.1);
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
        let map = ArcMap::new(a0, a1, 1.0);
        let mut curve =
            crate::io::step::nurbs::arc(Vec3::new(c[0], c[1], z), Vec3::X, Vec3::Y, radius, &map);
        if e.transform != 0 {
            let t = self.entry(e.transform).ok_or_else(|| {
                self.entity_error(
                    k,
                    line,
                    "the transformation pointer is not a directory entry".into(),
                )
            })?;
            let m = self.transform(t, 0)?;
            for q in &mut curve.points {
                *q = m.transform_point3(*q);
            }
        }
        Ok((curve, map))
    }
}
