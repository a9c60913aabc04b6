//! Analytic faces: `PLANE`, `CYLINDRICAL_SURFACE`, `CONICAL_SURFACE`,
//! `SPHERICAL_SURFACE`, `TOROIDAL_SURFACE`, `SURFACE_OF_REVOLUTION` and
//! `SURFACE_OF_LINEAR_EXTRUSION` (ISO 10303-42 §4.4), and `OFFSET_SURFACE`
//! (§4.4.14) of a plane, cylinder, sphere or torus (the surface of the same
//! kind moved or with its radius grown by the distance, on the basis's
//! parameters), converted exactly to
//! NURBS over the part of the surface the face's bounds span, the bounds
//! mapped into the NURBS parameters through the surface's natural
//! coordinates (see the parent module).

use super::curves::{Curve, nearest_param};
use super::*;

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

/// Most nested `OFFSET_SURFACE`s followed to their basis.
mod conversion;
mod face;
mod full_turns;
mod natural;

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
}
