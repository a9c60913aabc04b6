//! The geometry of B-rep faces as STEP entities: points (116), directions
//! (123), model-space curves and the surfaces (analytic 190–198, 120, 122, 128).

use super::TRANSLATED_SURFACES;
use super::step_builder::{StepBuilder, text};
use crate::Vec3;
use crate::io::iges_read::IgesError;
use crate::io::iges_read::boundary::Piece;
use crate::io::iges_read::params::{INT, Param, REAL, param};
use crate::io::iges_read::records::Iges;
use crate::io::step::nurbs::Nurbs3;
use crate::io::step::p21::Value;

impl Iges<'_> {
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
    pub(super) fn model_curve(&self, k: usize) -> Result<Nurbs3, IgesError> {
        let mut pieces = Vec::new();
        self.curve_pieces(k, 0, &mut pieces)?;
        if pieces.is_empty() {
            return Err(self.entity_error(k, self.dir[k].line, "the curve is empty".into()));
        }
        self.joined_pieces(k, pieces)
    }

    /// Writes the surface of a face into the exchange; errors name the
    /// surface entity.
    pub(super) fn brep_surface(
        &self,
        s: usize,
        id: u64,
        b: &mut StepBuilder,
    ) -> Result<(), IgesError> {
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
            120 => self.revolution_parts(s, &p, line, at, b)?,
            128 => {
                let surface =
                    super::super::bspline_surface::read_entity_128(self, s, false)?.surface;
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
}

impl Iges<'_> {
    /// The `SURFACE_OF_REVOLUTION` a surface of revolution `s` (120) is
    /// written as: its axis line (110) and generatrix, every point moved by
    /// `at` (the 120's transformation).
    fn revolution_parts(
        &self,
        s: usize,
        p: &[(Param, usize)],
        line: usize,
        at: impl Fn(Vec3) -> Vec3,
        b: &mut StepBuilder,
    ) -> Result<Vec<(&'static str, Vec<Value>)>, IgesError> {
        let axis_k = self.pointer(s, p, 1, line, &[110])?;
        let gen_k = self.pointer(s, p, 2, line, &[100, 102, 104, 110, 126])?;
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
        Ok(vec![(
            "SURFACE_OF_REVOLUTION",
            vec![text(""), Value::Ref(c), Value::Ref(ax)],
        )])
    }
}

/// Joins the pieces of one curve into one NURBS when it has one piece.
pub(super) fn one_piece(pieces: Vec<Piece>) -> Option<Nurbs3> {
    match <[Piece; 1]>::try_from(pieces) {
        Ok([p]) => Some(p.nurbs()),
        Err(_) => None,
    }
}
