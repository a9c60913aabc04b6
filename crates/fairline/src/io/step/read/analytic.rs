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
    /// `profile_angle`: a conic profile's angle → its NURBS parameter;
    /// `offset`: the surface is the offset of this one.
    Revolution {
        profile: Nurbs3,
        profile_angle: Option<ArcMap>,
        offset: Option<SweptOffset>,
    },
    /// `d` the unit direction, `length` the extrusion vector's length
    /// (ISO's v runs along `length · d`); `offset` as for a revolution.
    Extrusion {
        profile: Nurbs3,
        profile_angle: Option<ArcMap>,
        d: Vec3,
        length: f64,
        offset: Option<SweptOffset>,
    },
}

/// A swept surface read as the offset of the surface it was swept as
/// (`OFFSET_SURFACE` over a `SURFACE_OF_REVOLUTION` or
/// `SURFACE_OF_LINEAR_EXTRUSION`): the natural coordinates stay the
/// basis's — a point moved along the normal keeps its foot on the basis,
/// within the basis's radius of curvature — and the NURBS of a face is the
/// basis's NURBS offset on its parameters
/// ([`crate::bspline::offset::offset_surface`]).
#[derive(Clone, Copy, Debug)]
struct SweptOffset {
    /// The distance along the basis's normal ISO 10303-42 gives it
    /// (Su × Sv, u the angle or the profile parameter).
    distance: f64,
    /// The outermost `OFFSET_SURFACE`, named in the warning of a fit.
    entity: u64,
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

/// Moves a straight `profile` (its control points on one line) of a
/// surface of revolution about the axis through `o` along the unit `z` by
/// `d` along the surface's normal — ISO 10303-42's Su × Sv with u the
/// angle, `(z × r) × P'`, the same all along a line — so that revolving it
/// gives the offset surface exactly. False (the profile untouched) for a
/// profile that is not straight or gives no normal (it lies on the axis).
fn move_straight_profile(profile: &mut Nurbs3, o: Vec3, z: Vec3, d: f64) -> bool {
    let (Some(&p0), Some(&p1)) = (profile.points.first(), profile.points.last()) else {
        return false;
    };
    let chord = p1 - p0;
    let size = chord.length();
    if !(size > 0.0 && size.is_finite()) {
        return false;
    }
    let straight = profile
        .points
        .iter()
        .all(|q| (*q - p0).cross(chord).length() <= 1e-12 * size * size);
    if !straight {
        return false;
    }
    let radial = |q: Vec3| (q - o) - (q - o).dot(z) * z;
    let far = if radial(p0).length() >= radial(p1).length() {
        p0
    } else {
        p1
    };
    let n = z.cross(radial(far)).cross(chord);
    let l = n.length();
    if !(l > 0.0 && l.is_finite()) {
        return false;
    }
    for q in &mut profile.points {
        *q += d * n / l;
    }
    true
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
                        offset: None,
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
                        offset: None,
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

    /// The surface an `OFFSET_SURFACE` `si` moves and the distance along
    /// that surface's normal: nested offsets add up, and a
    /// `RECTANGULAR_TRIMMED_SURFACE` between them (OCCT writes the offset
    /// of a trimmed extrusion so) stands for its basis surface — the face's
    /// edges bound it, not the rectangle — with the distance negated where
    /// exactly one of its senses is reversed (its normal Su × Sv is then
    /// the basis's reversed). Refused beyond [`MAX_OFFSET_DEPTH`] levels.
    pub(super) fn offset_basis(&self, si: &'a Instance) -> R<(&'a Instance, f64)> {
        let (mut basis, mut d, mut sign) = (si, 0.0, 1.0);
        for _ in 0..MAX_OFFSET_DEPTH {
            if basis.is("OFFSET_SURFACE") {
                let p = self.params(basis, &["OFFSET_SURFACE"])?;
                d += sign * self.num(basis, p, 2)?;
                basis = self.refer(basis, p, 1)?;
            } else if basis.is("RECTANGULAR_TRIMMED_SURFACE") {
                let p = self.params(basis, &["RECTANGULAR_TRIMMED_SURFACE"])?;
                if self.flag(basis, p, 6)? != self.flag(basis, p, 7)? {
                    sign = -sign;
                }
                basis = self.refer(basis, p, 1)?;
            } else {
                return Ok((basis, d));
            }
        }
        Err(self.err(
            si,
            format!("more than {MAX_OFFSET_DEPTH} nested offset or trimmed surfaces"),
        ))
    }

    /// An `OFFSET_SURFACE` (ISO 10303-42 §4.4.14: the basis moved by the
    /// distance d along its normal, on its parameters). Of an elementary
    /// surface it is a surface of the same kind on the same parameters,
    /// exactly: a plane moved along its normal, a cylinder or sphere with
    /// radius r + d, a torus with minor radius r + d (the normals of ISO's
    /// elementary surfaces point away from the axis or centre), a cone of
    /// semi-angle α with radius r + d·cos α and its placement moved by
    /// −d·sin α along the axis (its normal is cos α·ρ − sin α·z, so the
    /// point of height v moves to radius r + v·tan α + d·cos α at height
    /// v − d·sin α). Of a swept surface: a surface of revolution of a
    /// straight profile (a cone or cylinder swept from a line) is the
    /// revolution of the line moved along the normal, exactly; any other
    /// swept surface keeps its natural coordinates and its face's NURBS is
    /// offset on its parameters ([`SweptOffset`]: exact for a plane,
    /// otherwise fitted within a tolerance and warned). Nested offsets add
    /// up. Other bases (B-spline surfaces have their own path) and a radius
    /// that would not stay positive are refused, naming the entity.
    fn offset_analytic(&self, si: &'a Instance) -> R<(Frame, Analytic)> {
        let (basis, d) = self.offset_basis(si)?;
        let t = basis.type_name();
        let ((o, x, y, z), kind) = match t {
            "PLANE"
            | "CYLINDRICAL_SURFACE"
            | "CONICAL_SURFACE"
            | "SPHERICAL_SURFACE"
            | "TOROIDAL_SURFACE"
            | "SURFACE_OF_REVOLUTION"
            | "SURFACE_OF_LINEAR_EXTRUSION" => self.analytic(basis)?,
            _ => {
                return Err(self.err(
                    si,
                    format!("an offset of a {t} is not supported (offsets of B_SPLINE_SURFACE_WITH_KNOTS, PLANE, CYLINDRICAL_SURFACE, CONICAL_SURFACE, SPHERICAL_SURFACE, TOROIDAL_SURFACE, SURFACE_OF_REVOLUTION and SURFACE_OF_LINEAR_EXTRUSION are)"),
                ));
            }
        };
        if !d.is_finite() {
            return Err(self.err(si, format!("the offset distance {d} is not a number")));
        }
        let swept = Some(SweptOffset {
            distance: d,
            entity: si.id,
        });
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
            Analytic::Cone { r, tan } => {
                let cos = 1.0 / tan.hypot(1.0);
                let sin = tan * cos;
                (
                    (o - d * sin * z, x, y, z),
                    Analytic::Cone {
                        r: r + d * cos,
                        tan,
                    },
                )
            }
            Analytic::Revolution {
                mut profile,
                profile_angle,
                offset: inner,
            } => {
                debug_assert!(inner.is_none(), "nested offsets are added up above");
                if move_straight_profile(&mut profile, o, z, d) {
                    let kind = Analytic::Revolution {
                        profile,
                        profile_angle,
                        offset: None,
                    };
                    ((o, x, y, z), kind)
                } else {
                    let kind = Analytic::Revolution {
                        profile,
                        profile_angle,
                        offset: swept,
                    };
                    ((o, x, y, z), kind)
                }
            }
            Analytic::Extrusion {
                profile,
                profile_angle,
                d: dir,
                length,
                ..
            } => (
                (o, x, y, z),
                Analytic::Extrusion {
                    profile,
                    profile_angle,
                    d: dir,
                    length,
                    offset: swept,
                },
            ),
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
