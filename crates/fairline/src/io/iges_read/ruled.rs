//! Ruled surface (118, IGES 5.3 §4.18) converted to a B-spline surface:
//! exact where a NURBS form is exact, the form of equal arc length
//! between rails whose arc lengths are not proportional fitted.

use super::curve_ops::compatible;
use super::surfaces::{Axis, Converted};
use super::{Iges, IgesError, Nurbs3, Param, Vec3, params::INT, params::param};
use crate::bspline::BSplineSurface;
use crate::bspline::fit::fit_bicubic;

impl Iges<'_> {
    /// Entity 118, ruled surface (IGES 5.3 §4.16): `DE1 DE2 DIRFLG DEVFLG`,
    /// `S(u, v) = (1 − v)·C1(u) + v·C2(u)` (`C2` reversed when `DIRFLG =
    /// 1`; `DEVFLG` is not needed). Form 1 (equal parametric values): the
    /// rails made compatible ([`compatible`]) span the surface; exact when
    /// both rails have the same parameter map (lines, B-spline curves, or
    /// arcs of the same sweep), otherwise fitted ([`Self::ruled_fit`]) on
    /// the rails' own parameter maps. Form 0 (equal arc length): exact the same
    /// way when the rails' arc lengths are proportional along their
    /// parameters (to 1e-9 of their lengths at 1024 points: lines, arcs of
    /// one sweep, one curve and its translate); otherwise no NURBS is
    /// exact and the surface is fitted ([`Self::equal_arc_length_fit`]).
    pub(super) fn ruled_surface(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Converted, IgesError> {
        let rails = [100, 102, 104, 110, 112, 126];
        let (k1, k2) = (
            self.pointer(k, p, 1, line, &rails)?,
            self.pointer(k, p, 2, line, &rails)?,
        );
        let reverse = param(self, k, p, 3, line, &INT)? == 1;
        let (c1, a1) = self.normalized_curve(k1)?;
        let (mut c2, mut a2) = self.normalized_curve(k2)?;
        let file_rails = (c1.clone(), a1, c2.clone(), a2);
        if reverse {
            c2 = c2.reversed();
            a2 = a2.filter(|a| *a == Axis::Identity);
        }
        let (r1, r2) = compatible(&c1, &c2).ok_or_else(|| {
            self.unsupported(k, line, "the rails cannot be made compatible".into())
        })?;
        let equal_arc_length = self.dir[k].form == 0;
        let same_map = a1.is_some() && a1 == a2;
        let (lengths_agree, lengths_linear) = if equal_arc_length {
            let (s1, s2) = (arc_fractions(&r1), arc_fractions(&r2));
            let agree = s1.iter().zip(&s2).all(|(a, b)| (a - b).abs() <= 1e-9);
            let linear = s1
                .iter()
                .enumerate()
                .all(|(i, a)| (a - i as f64 / (s1.len() - 1) as f64).abs() <= 1e-9);
            (agree, linear)
        } else {
            (true, true)
        };
        if equal_arc_length && !lengths_agree {
            return self.equal_arc_length_fit(k, line, &r1, &r2);
        }
        if !equal_arc_length && !same_map {
            // Each rail at the file's normalised parameter u (the second
            // at 1 − u when reversed): no NURBS is exact, the fit is.
            let (c1, a1, c2, a2) = file_rails;
            let (Some(a1), Some(a2)) = (a1, a2) else {
                return Err(self.unsupported(
                    k,
                    line,
                    "a ruled surface of equal parameter (118 form 1) over a rail whose file parameter fairline cannot map (a conic other than an ellipse, or a composite curve with arcs)".into(),
                ));
            };
            let at1 = |u: f64| c1.eval(a1.apply(u));
            let at2 = |u: f64| c2.eval(a2.apply(if reverse { 1.0 - u } else { u }));
            return self.ruled_fit(k, line, [&c1, &c2], &at1, &at2, "equal parameter (118 form 1) whose rails are parametrised differently (a line or spline against an arc)");
        }
        let rational = r1.weights.is_some() || r2.weights.is_some();
        let n = r1.points.len();
        let w = |c: &Nurbs3, i: usize| c.weights.as_ref().map_or(1.0, |w| w[i]);
        let mut points = Vec::with_capacity(2 * n);
        let mut weights = Vec::with_capacity(2 * n);
        for i in 0..n {
            points.extend([r1.points[i], r2.points[i]]);
            weights.extend([w(&r1, i), w(&r2, i)]);
        }
        let surface = BSplineSurface::from_flat(
            r1.degree,
            1,
            r1.knots.clone(),
            vec![0.0, 0.0, 1.0, 1.0],
            [n, 2],
            points,
            rational.then_some(weights),
        )
        .map_err(|source| IgesError::Surface {
            entity: 2 * k + 1,
            line,
            source,
        })?;
        // `v` is linear where both rails have the same weights
        let same_weights = (0..n).all(|i| (w(&r1, i) - w(&r2, i)).abs() <= 1e-14 * w(&r1, i));
        let u_axis = if equal_arc_length {
            lengths_linear.then_some(Axis::Identity)
        } else {
            a1
        };
        Ok(Converted {
            surface,
            axes: u_axis.filter(|_| same_weights).map(|a| [a, Axis::Identity]),
            fit: None,
            transformed: false,
        })
    }
}

/// A curve by its relative arc length: the point at a fraction `s` of its
/// length, from 8192 chords (the parameter interpolated linearly between
/// them, so every point lies on the curve).
struct ByArcLength<'c> {
    curve: &'c Nurbs3,
    /// Parameters and relative arc lengths of the chord ends, ascending.
    params: Vec<f64>,
    fractions: Vec<f64>,
}

impl<'c> ByArcLength<'c> {
    const CHORDS: usize = 8192;

    /// `None` for a curve of no length.
    fn new(curve: &'c Nurbs3) -> Option<Self> {
        let [a, b] = curve.domain();
        let params: Vec<f64> = (0..=Self::CHORDS)
            .map(|i| a + (b - a) * i as f64 / Self::CHORDS as f64)
            .collect();
        let mut fractions = Vec::with_capacity(params.len());
        let (mut s, mut prev) = (0.0, curve.eval(a));
        for &t in &params {
            let q = curve.eval(t);
            s += q.distance(prev);
            prev = q;
            fractions.push(s);
        }
        if !(s > 0.0 && s.is_finite()) {
            return None;
        }
        fractions.iter_mut().for_each(|x| *x /= s);
        Some(ByArcLength {
            curve,
            params,
            fractions,
        })
    }

    fn at(&self, s: f64) -> Vec3 {
        let s = s.clamp(0.0, 1.0);
        let i = self
            .fractions
            .partition_point(|&f| f < s)
            .clamp(1, self.fractions.len() - 1);
        let (f0, f1) = (self.fractions[i - 1], self.fractions[i]);
        let w = if f1 > f0 { (s - f0) / (f1 - f0) } else { 0.0 };
        let (t0, t1) = (self.params[i - 1], self.params[i]);
        self.curve.eval(t0 + w * (t1 - t0))
    }
}

impl Iges<'_> {
    /// A ruled surface of equal relative arc length (118 form 0) between
    /// rails whose arc lengths are not proportional along their
    /// parameters: `S(u, v) = (1 − v)·C1(s1⁻¹(u)) + v·C2(s2⁻¹(u))`, u the
    /// relative arc length along both (IGES 5.3 §4.18), has no exact NURBS
    /// form; it is fitted ([`Self::ruled_fit`]). A rail of no length is
    /// `Unsupported`, saying so.
    fn equal_arc_length_fit(
        &self,
        k: usize,
        line: usize,
        r1: &Nurbs3,
        r2: &Nurbs3,
    ) -> Result<Converted, IgesError> {
        let (Some(a1), Some(a2)) = (ByArcLength::new(r1), ByArcLength::new(r2)) else {
            return Err(self.unsupported(
                k,
                line,
                "a rail of the ruled surface has no length".into(),
            ));
        };
        self.ruled_fit(
            k,
            line,
            [r1, r2],
            &|u| a1.at(u),
            &|u| a2.at(u),
            "equal arc length (118 form 0) whose rails' arc lengths are not proportional",
        )
    }

    /// `S(u, v) = (1 − v)·at1(u) + v·at2(u)` over the unit square, the
    /// rails' points at the file's parameter u, fitted by a bicubic
    /// B-spline within 1e-7 of the rails' size ([`fit_bicubic`]), on the
    /// file's parameters; the fit is reported (a warning naming the
    /// entity). A fit that does not reach the tolerance is `Unsupported`,
    /// naming the surface as `what`.
    fn ruled_fit(
        &self,
        k: usize,
        line: usize,
        rails: [&Nurbs3; 2],
        at1: &dyn Fn(f64) -> Vec3,
        at2: &dyn Fn(f64) -> Vec3,
        what: &str,
    ) -> Result<Converted, IgesError> {
        let [r1, r2] = rails;
        let (lo, hi) = r1
            .points
            .iter()
            .chain(&r2.points)
            .fold((r1.points[0], r1.points[0]), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let tolerance = 1e-7 * (hi - lo).length();
        let whole = [(0.0, true), (1.0, true)];
        let (surface, worst) = fit_bicubic(
            &whole,
            &whole,
            |u, v| Ok((1.0 - v) * at1(u) + v * at2(u)),
            tolerance,
        )
        .map_err(|m| {
            self.unsupported(
                k,
                line,
                format!("a ruled surface of {what} has no exact NURBS form, and {m}"),
            )
        })?;
        Ok(Converted {
            surface,
            axes: Some([Axis::Identity, Axis::Identity]),
            fit: Some((tolerance, worst)),
            transformed: false,
        })
    }
}

/// The arc length from the start at 1025 equally spaced parameters, as a
/// fraction of the whole (chords of 8 sub-steps each); all zero for a
/// curve of no length.
fn arc_fractions(c: &Nurbs3) -> Vec<f64> {
    let [a, b] = c.domain();
    let steps = 1024 * 8;
    let mut out = Vec::with_capacity(1025);
    let mut s = 0.0;
    let mut prev = c.eval(a);
    out.push(0.0);
    for i in 1..=steps {
        let q = c.eval(a + (b - a) * i as f64 / steps as f64);
        s += q.distance(prev);
        prev = q;
        if i % 8 == 0 {
            out.push(s);
        }
    }
    if s > 0.0 && s.is_finite() {
        out.iter_mut().for_each(|x| *x /= s);
    } else {
        out.iter_mut().for_each(|x| *x = 0.0);
    }
    out
}
