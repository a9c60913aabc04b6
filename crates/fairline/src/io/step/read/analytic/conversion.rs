//! Analytic surfaces converted exactly to NURBS over the span a face needs:
//! whole closed surfaces, poles, profiles of revolutions and extrusions.

use std::f64::consts::{FRAC_PI_2, PI};

use super::{Analytic, Frame, NaturalBox, NaturalLoop, Periods, SweptOffset};
use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::io::step::nurbs::{ArcMap, Nurbs3, arc, revolve};
use crate::io::step::p21::Instance;
use crate::io::step::read::curves::ToUv;
use crate::io::step::read::{R, Reader};

/// How far, as a share of its profile's domain, a face's bound may lie
/// beyond the profile's ends and still be read as reaching them.
const SEAM_SLACK: f64 = 1e-6;

impl<'a> Reader<'a> {
    /// Where a face bounded by one winding bound closes, on the face's side
    /// (`side`, ±1 in t) of the bound at mean `t`: the pole of a sphere, the
    /// apex of a cone, the end of a surface of revolution's profile.
    pub(super) fn pole(
        &self,
        f: &Instance,
        kind: &Analytic,
        axis: usize,
        side: f64,
        t: f64,
    ) -> R<f64> {
        let unbounded = || {
            self.err(
                f,
                "a single bound winds around the surface and the face's side of it is unbounded"
                    .into(),
            )
        };
        if axis != 0 {
            return Err(unbounded());
        }
        match kind {
            Analytic::Sphere { .. } => Ok(side * FRAC_PI_2),
            Analytic::Cone { r, tan } if *tan != 0.0 => {
                let apex = -r / tan;
                if (apex - t) * side > 0.0 {
                    Ok(apex)
                } else {
                    Err(unbounded())
                }
            }
            Analytic::Revolution { profile, .. } => {
                let [t0, t1] = profile.domain();
                Ok(if side > 0.0 { t1 } else { t0 })
            }
            _ => Err(unbounded()),
        }
    }

    /// A face with no edge loop on a closed surface: the whole sphere or
    /// torus, untrimmed.
    pub(super) fn whole_closed_surface(
        &self,
        f: &Instance,
        frame: Frame,
        kind: &Analytic,
    ) -> R<BSplineSurface> {
        let b = match kind {
            Analytic::Sphere { .. } => [-FRAC_PI_2, FRAC_PI_2],
            Analytic::Torus { .. } => [-PI, PI],
            _ => {
                return Err(self.err(
                    f,
                    "a face on an open surface needs at least one edge loop".into(),
                ));
            }
        };
        let span = NaturalBox { a: [-PI, PI], b };
        Ok(self.analytic_nurbs(f, frame, kind, span)?.0)
    }

    /// A swept profile's parameter must stay in its domain: shifts the
    /// loops and their box by whole periods into it, or refuses a face
    /// across the profile's seam. Other surfaces are returned unchanged.
    pub(super) fn shift_into_profile_domain(
        &self,
        f: &Instance,
        kind: &Analytic,
        periods: Periods,
        nat: &mut [NaturalLoop],
        span: NaturalBox,
    ) -> R<NaturalBox> {
        let NaturalBox {
            a: [mut a0, mut a1],
            b: [mut b0, mut b1],
        } = span;
        let profile_coordinate = match kind {
            Analytic::Revolution { profile, .. } => Some((1, profile.domain(), periods[1])),
            Analytic::Extrusion { profile, .. } => Some((0, profile.domain(), periods[0])),
            _ => None,
        };
        if let Some((axis, [t0, t1], period)) = profile_coordinate {
            let (lo, hi) = if axis == 0 { (a0, a1) } else { (b0, b1) };
            // a bound along the profile's seam may stray past it by the
            // precision of its edges (an offset surface's edges are
            // approximations, their natural coordinates projections):
            // within SEAM_SLACK of the domain it is put back onto it
            let slack = SEAM_SLACK * (t1 - t0);
            let shift = match period {
                Some(p) if p > 0.0 && lo < t0 - slack => p * ((t0 - lo) / p).ceil(),
                Some(p) if p > 0.0 && lo >= t1 - slack && hi > t1 + slack => {
                    -p * ((lo - t0) / p).floor()
                }
                _ => 0.0,
            };
            if lo + shift < t0 - slack || hi + shift > t1 + slack {
                return Err(self.err(f, "the face crosses the seam of its swept profile".into()));
            }
            let onto = |t: f64| (t + shift).clamp(t0, t1);
            for p in nat.iter_mut().flatten() {
                if axis == 0 {
                    p.0 = onto(p.0);
                } else {
                    p.1 = onto(p.1);
                }
            }
            if axis == 0 {
                (a0, a1) = (onto(a0), onto(a1));
            } else {
                (b0, b1) = (onto(b0), onto(b1));
            }
        }
        Ok(NaturalBox {
            a: [a0, a1],
            b: [b0, b1],
        })
    }

    /// The exact NURBS of an analytic surface over the natural box `span`
    /// (u along a, v along b; see [`crate::io::step::nurbs`]) and the map of
    /// natural coordinates `(a, b)` to its parameters `(u, v)`.
    pub(super) fn analytic_nurbs(
        &self,
        f: &Instance,
        (o, x, _y, z): Frame,
        kind: &Analytic,
        span: NaturalBox,
    ) -> R<(BSplineSurface, ToUv)> {
        let NaturalBox {
            a: [a0, a1],
            b: [b0, b1],
        } = span;
        let nurbs: (BSplineSurface, ToUv) = match kind {
            Analytic::Cylinder { r } | Analytic::Cone { r, .. } => {
                let tan = if let Analytic::Cone { tan, .. } = kind {
                    *tan
                } else {
                    0.0
                };
                let radius = |h: f64| r + h * tan;
                let scale = radius(b0).abs().max(radius(b1).abs()).max(1e-300);
                let map = ArcMap::new(a0, a1, scale);
                let profile = Nurbs3::segment(
                    o + radius(b0) * x + b0 * z,
                    o + radius(b1) * x + b1 * z,
                    b0,
                    b1,
                );
                (
                    self.revolved(f, o, z, &profile, &map)?,
                    ToUv([Some(map), None]),
                )
            }
            Analytic::Sphere { r } | Analytic::Torus { small: r, .. } => {
                let big = if let Analytic::Torus { big, .. } = kind {
                    *big
                } else {
                    0.0
                };
                let amap = ArcMap::new(a0, a1, big + r);
                let bmap = ArcMap::new(b0, b1, *r);
                let profile = arc(o + big * x, x, z, *r, &bmap);
                (
                    self.revolved(f, o, z, &profile, &amap)?,
                    ToUv([Some(amap), Some(bmap)]),
                )
            }
            Analytic::Revolution {
                profile, offset, ..
            } => {
                let scale = profile
                    .points
                    .iter()
                    .map(|q| ((*q - o) - (*q - o).dot(z) * z).length())
                    .fold(0.0, f64::max)
                    .max(1e-300);
                let map = ArcMap::new(a0, a1, scale);
                let basis = self.revolved(f, o, z, profile, &map)?;
                (self.offset(f, basis, offset)?, ToUv([Some(map), None]))
            }
            Analytic::Extrusion {
                profile, d, offset, ..
            } => {
                let basis = self.extruded(f, profile, *d, b0, b1)?;
                (self.offset(f, basis, offset)?, ToUv([None, None]))
            }
            Analytic::Plane => {
                return Err(self.err(f, "internal: planes are handled by plane_face".into()));
            }
        };
        Ok(nurbs)
    }

    /// `basis` offset on its parameters by `offset` ([`SweptOffset`],
    /// [`Reader::offset_on_parameters`]); `basis` itself without an
    /// offset.
    fn offset(
        &self,
        f: &Instance,
        basis: BSplineSurface,
        offset: &Option<SweptOffset>,
    ) -> R<BSplineSurface> {
        let Some(SweptOffset { distance, entity }) = *offset else {
            return Ok(basis);
        };
        self.offset_on_parameters(&basis, distance, entity)
            .map_err(|m| self.err(f, format!("#{entity} OFFSET_SURFACE: {m}")))
    }

    /// The ruled surface of `profile` moved by `b0·d` to `b1·d` (Piegl &
    /// Tiller §8.3): degree 1 across, the profile's knots and weights along.
    fn extruded(
        &self,
        f: &Instance,
        profile: &Nurbs3,
        d: Vec3,
        b0: f64,
        b1: f64,
    ) -> R<BSplineSurface> {
        let n = profile.points.len();
        let mut pts = Vec::with_capacity(2 * n);
        let mut w = Vec::with_capacity(2 * n);
        for (i, q) in profile.points.iter().enumerate() {
            let wi = profile.weights.as_ref().map_or(1.0, |ws| ws[i]);
            pts.push(*q + b0 * d);
            pts.push(*q + b1 * d);
            w.extend([wi, wi]);
        }
        BSplineSurface::from_flat(
            profile.degree,
            1,
            profile.knots.clone(),
            vec![b0, b0, b1, b1],
            [n, 2],
            pts,
            profile.weights.is_some().then_some(w),
        )
        .map_err(|e| self.err(f, e.to_string()))
    }

    fn revolved(
        &self,
        f: &Instance,
        o: Vec3,
        z: Vec3,
        profile: &Nurbs3,
        map: &ArcMap,
    ) -> R<BSplineSurface> {
        let (ku, pts, w) = revolve(o, z, profile, map);
        let nu = ku.len() - 3;
        BSplineSurface::from_flat(
            2,
            profile.degree,
            ku,
            profile.knots.clone(),
            [nu, profile.points.len()],
            pts,
            Some(w),
        )
        .map_err(|e| self.err(f, e.to_string()))
    }
}
