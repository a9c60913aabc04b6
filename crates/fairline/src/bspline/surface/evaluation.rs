//! Evaluation of a surface: points, first and second derivatives (rational
//! ones from the homogeneous net, Piegl & Tiller A4.4), normals and
//! curvatures, at one parameter pair or over a grid, and which control
//! points a parameter's basis functions touch.

use std::ops::Range;

use glam::DVec4;
use rayon::prelude::*;

use super::{BSplineSurface, clamp_param};
use crate::Vec3;
use crate::bspline::basis::{BasisDerivs, MAX_ORDER, basis_funs, basis_funs_ders2, find_span};

/// Position and partial derivatives up to second order at one parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceDerivatives {
    /// `S(u, v)`.
    pub point: Vec3,
    /// `∂S/∂u`.
    pub su: Vec3,
    /// `∂S/∂v`.
    pub sv: Vec3,
    /// `∂²S/∂u²`.
    pub suu: Vec3,
    /// `∂²S/∂u∂v`.
    pub suv: Vec3,
    /// `∂²S/∂v²`.
    pub svv: Vec3,
}

/// Curvature at a surface point, from the first and second fundamental forms.
///
/// Signs: positive where the surface bends away from `normal` (a sphere with
/// outward `Su × Sv` has `k1 = k2 = +1/r`). `k1 >= k2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Curvature {
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// Mean curvature `(k1 + k2) / 2`.
    pub mean: f64,
    /// Gaussian curvature `k1 * k2`.
    pub gauss: f64,
    /// Unit principal direction of `k1` (tangent to the surface).
    pub d1: Vec3,
    /// Unit principal direction of `k2`, `normal × d1`.
    pub d2: Vec3,
    /// Unit normal `Su × Sv / |Su × Sv|` used for the signs.
    pub normal: Vec3,
}

/// Which control points influence a parameter `(u, v)`: the knot spans
/// (Piegl & Tiller A2.1) and the index ranges `span - degree ..= span`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BasisSupport {
    /// Knot span index in u.
    pub span_u: usize,
    /// Knot span index in v.
    pub span_v: usize,
    /// Control point rows `i` with possibly non-zero `N_{i,p}(u)`.
    pub rows: Range<usize>,
    /// Control point columns `j` with possibly non-zero `N_{j,q}(v)`.
    pub cols: Range<usize>,
}

/// The non-zero basis functions and their first and second derivatives at a
/// parameter (Piegl & Tiller A2.3): `du[k][r]` is the k-th derivative of
/// `N_{span_u - p + r, p}(u)`, `dv[l][s]` likewise in v.
///
/// For a non-rational surface `∂^{k+l} S / ∂u^k ∂v^l = Σ du[k][r] dv[l][s] P_{rs}`,
/// so these are also the derivatives of `S` with respect to the control points.
#[derive(Clone, Debug)]
pub struct SurfaceBasis {
    /// Knot span index in u; rows `span_u - p ..= span_u`.
    pub span_u: usize,
    /// Knot span index in v; columns `span_v - q ..= span_v`.
    pub span_v: usize,
    /// Basis values and derivatives in u.
    pub du: BasisDerivs,
    /// Basis values and derivatives in v.
    pub dv: BasisDerivs,
}

/// Relative threshold below which `|Su × Sv|` counts as degenerate.
const DEGENERATE: f64 = 1e-10;

/// Parameter nudges (fractions of the domain width) tried for the normal at
/// a degenerate point before giving up (the normal's error grows like
/// ε / nudge, so the first nudge is tiny).
const NORMAL_NUDGES: [f64; 4] = [1e-7, 1e-5, 1e-3, 1e-2];

/// Curvature needs second derivatives against a well-conditioned frame: its
/// error grows like ε / ratio² where `ratio = |Su × Sv| / max(|Su|, |Sv|)²`.
/// Points with a ratio below this are treated as degenerate for curvature.
const CURVATURE_REGULAR: f64 = 1e-5;

/// Parameter nudges tried for curvature at a (nearly) degenerate point.
const CURVATURE_NUDGES: [f64; 3] = [1e-4, 1e-3, 1e-2];

impl BSplineSurface {
    /// Knot span in u containing `u` (clamped), Piegl & Tiller A2.1.
    pub fn span_u(&self, u: f64) -> usize {
        let u = clamp_param(u, self.domain_u());
        find_span(&self.knots_u, self.degree_u, self.count_u, u)
    }

    /// Knot span in v containing `v` (clamped), Piegl & Tiller A2.1.
    pub fn span_v(&self, v: f64) -> usize {
        let v = clamp_param(v, self.domain_v());
        find_span(&self.knots_v, self.degree_v, self.count_v, v)
    }

    /// The control points that influence `S(u, v)`: rows `span_u - p ..= span_u`
    /// and columns `span_v - q ..= span_v` (Piegl & Tiller A2.1 and Eq. 2.4's
    /// local support). Some of them may have a zero basis value exactly at a knot.
    pub fn basis_support(&self, u: f64, v: f64) -> BasisSupport {
        let span_u = self.span_u(u);
        let span_v = self.span_v(v);
        BasisSupport {
            span_u,
            span_v,
            rows: span_u - self.degree_u..span_u + 1,
            cols: span_v - self.degree_v..span_v + 1,
        }
    }

    /// Indices `(i, j)` of the control points whose support
    /// `[knots_u[i], knots_u[i+p+1]] × [knots_v[j], knots_v[j+q+1]]` meets the
    /// parameter box `[u0, u1] × [v0, v1]` in a set of positive area, i.e.
    /// whose basis function is non-zero somewhere inside the box (the
    /// "control points that affect the bounding box" of Nishiyama et al. §3.2).
    /// The box is clamped to the domain; a box of zero width in a direction
    /// selects the basis functions non-zero at that parameter
    /// ([`BSplineSurface::basis_support`]). Row-major order.
    pub fn control_points_in_box(&self, u0: f64, u1: f64, v0: f64, v1: f64) -> Vec<(usize, usize)> {
        let rows = support_range(
            &self.knots_u,
            self.degree_u,
            self.count_u,
            self.domain_u(),
            u0,
            u1,
        );
        let cols = support_range(
            &self.knots_v,
            self.degree_v,
            self.count_v,
            self.domain_v(),
            v0,
            v1,
        );
        rows.flat_map(|i| cols.clone().map(move |j| (i, j)))
            .collect()
    }

    /// The non-zero basis functions and their derivatives up to second order
    /// at `(u, v)` (clamped), Piegl & Tiller A2.1 + A2.3.
    pub fn basis(&self, u: f64, v: f64) -> SurfaceBasis {
        let (span_u, du) = self.basis_u(u);
        let (span_v, dv) = self.basis_v(v);
        SurfaceBasis {
            span_u,
            span_v,
            du,
            dv,
        }
    }

    /// Knot span and basis derivatives (orders 0–2) in u at `u` (clamped).
    fn basis_u(&self, u: f64) -> (usize, BasisDerivs) {
        let u = clamp_param(u, self.domain_u());
        let span = find_span(&self.knots_u, self.degree_u, self.count_u, u);
        let mut d = [[0.0; MAX_ORDER]; 3];
        basis_funs_ders2(span, u, self.degree_u, &self.knots_u, &mut d);
        (span, d)
    }

    /// Knot span and basis derivatives (orders 0–2) in v at `v` (clamped).
    fn basis_v(&self, v: f64) -> (usize, BasisDerivs) {
        let v = clamp_param(v, self.domain_v());
        let span = find_span(&self.knots_v, self.degree_v, self.count_v, v);
        let mut d = [[0.0; MAX_ORDER]; 3];
        basis_funs_ders2(span, v, self.degree_v, &self.knots_v, &mut d);
        (span, d)
    }

    /// The surface point `S(u, v)` (parameters clamped to the domain):
    /// Piegl & Tiller A3.5 (`SurfacePoint`), or A4.3 for rational surfaces.
    pub fn eval(&self, u: f64, v: f64) -> Vec3 {
        let (u, v) = self.clamp_parameters(u, v);
        let (p, q) = (self.degree_u, self.degree_v);
        let span_u = find_span(&self.knots_u, p, self.count_u, u);
        let span_v = find_span(&self.knots_v, q, self.count_v, v);
        let mut nu = [0.0; MAX_ORDER];
        let mut nv = [0.0; MAX_ORDER];
        basis_funs(span_u, u, p, &self.knots_u, &mut nu);
        basis_funs(span_v, v, q, &self.knots_v, &mut nv);
        let (i0, j0) = (span_u - p, span_v - q);
        match &self.weights {
            None => {
                let mut s = Vec3::ZERO;
                for r in 0..=p {
                    let row = &self.points[self.index(i0 + r, j0)..][..=q];
                    let mut t = Vec3::ZERO;
                    for (c, &pt) in row.iter().enumerate() {
                        t += nv[c] * pt;
                    }
                    s += nu[r] * t;
                }
                s
            }
            Some(w) => {
                let mut s = DVec4::ZERO;
                for r in 0..=p {
                    let k = self.index(i0 + r, j0);
                    let row = &self.points[k..][..=q];
                    let wrow = &w[k..][..=q];
                    let mut t = DVec4::ZERO;
                    for c in 0..=q {
                        t += (nv[c] * wrow[c]) * row[c].extend(1.0);
                    }
                    s += nu[r] * t;
                }
                s.truncate() / s.w
            }
        }
    }

    /// Position and first and second partial derivatives at `(u, v)`
    /// (parameters clamped), analytic: Piegl & Tiller A3.6
    /// (`SurfaceDerivsAlgorithm1`) on the basis derivatives of A2.3 (computed
    /// by [`basis_funs_ders2`]); for a
    /// rational surface the homogeneous derivatives `A^{(k,l)}, w^{(k,l)}` are
    /// combined by the quotient rule of A4.4 (`RatSurfaceDerivs`, Eq. 4.20).
    /// At a knot the derivatives are those of the span to the right (the
    /// last span at the domain end). No allocation.
    pub fn derivatives(&self, u: f64, v: f64) -> SurfaceDerivatives {
        let (span_u, du) = self.basis_u(u);
        let (span_v, dv) = self.basis_v(v);
        self.contract(span_u, &du, span_v, &dv)
    }

    /// The tensor-product sums of A3.6 (and the quotient rule of A4.4) for
    /// given basis derivatives in u and v.
    #[inline]
    fn contract(
        &self,
        span_u: usize,
        du: &BasisDerivs,
        span_v: usize,
        dv: &BasisDerivs,
    ) -> SurfaceDerivatives {
        let (p, q) = (self.degree_u, self.degree_v);
        let (i0, j0) = (span_u - p, span_v - q);
        match &self.weights {
            None => {
                // a[k][l] = Σ_r du[k][r] Σ_s dv[l][s] P_rs.
                let mut a = [Vec3::ZERO; 6];
                for r in 0..=p {
                    let row = &self.points[self.index(i0 + r, j0)..][..=q];
                    let (mut t0, mut t1, mut t2) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                    for (s, &pt) in row.iter().enumerate() {
                        t0 += dv[0][s] * pt;
                        t1 += dv[1][s] * pt;
                        t2 += dv[2][s] * pt;
                    }
                    let (n0, n1, n2) = (du[0][r], du[1][r], du[2][r]);
                    a[0] += n0 * t0;
                    a[1] += n1 * t0;
                    a[2] += n0 * t1;
                    a[3] += n2 * t0;
                    a[4] += n1 * t1;
                    a[5] += n0 * t2;
                }
                SurfaceDerivatives {
                    point: a[0],
                    su: a[1],
                    sv: a[2],
                    suu: a[3],
                    suv: a[4],
                    svv: a[5],
                }
            }
            Some(w) => {
                let mut a = [DVec4::ZERO; 6];
                for r in 0..=p {
                    let k = self.index(i0 + r, j0);
                    let row = &self.points[k..][..=q];
                    let wrow = &w[k..][..=q];
                    let (mut t0, mut t1, mut t2) = (DVec4::ZERO, DVec4::ZERO, DVec4::ZERO);
                    for s in 0..=q {
                        let pw = wrow[s] * row[s].extend(1.0);
                        t0 += dv[0][s] * pw;
                        t1 += dv[1][s] * pw;
                        t2 += dv[2][s] * pw;
                    }
                    let (n0, n1, n2) = (du[0][r], du[1][r], du[2][r]);
                    a[0] += n0 * t0;
                    a[1] += n1 * t0;
                    a[2] += n0 * t1;
                    a[3] += n2 * t0;
                    a[4] += n1 * t1;
                    a[5] += n0 * t2;
                }
                rational_derivatives(&a)
            }
        }
    }

    /// Derivatives at every grid point `(us[a], vs[b])`, row-major
    /// (`a * vs.len() + b`), equal to [`BSplineSurface::derivatives`] at each
    /// point. The basis derivatives (A2.1 + A2.3) are computed once per grid
    /// row and column, so each point costs only the sums of A3.6/A4.4.
    /// Parallel over points with rayon; deterministic.
    pub fn derivatives_grid(&self, us: &[f64], vs: &[f64]) -> Vec<SurfaceDerivatives> {
        let nv = vs.len();
        let bu: Vec<(usize, BasisDerivs)> = us.par_iter().map(|&u| self.basis_u(u)).collect();
        let bv: Vec<(usize, BasisDerivs)> = vs.par_iter().map(|&v| self.basis_v(v)).collect();
        (0..us.len() * nv)
            .into_par_iter()
            .with_min_len(256)
            .map(|k| {
                let (su, du) = &bu[k / nv];
                let (sv, dv) = &bv[k % nv];
                self.contract(*su, du, *sv, dv)
            })
            .collect()
    }

    /// `f(S, S_u, S_v)` at every grid point `(us[a], vs[b])`, row-major
    /// (`a * vs.len() + b`): position and first partial derivatives only,
    /// for fields that need the normal but no curvature (highlight lines).
    /// The basis functions (Piegl & Tiller A2.1 + A2.3) are computed once
    /// per grid row and column; each row then contracts the control net in
    /// u once — `T_j = Σ_r N_r(u) P_{i0+r, j}` and `T'_j = Σ_r N'_r(u) P_{i0+r, j}`
    /// for every column j (homogeneous `P^w` for a rational surface) — so a
    /// grid point costs only the (q+1)-term sums in v of A3.6 (and the
    /// quotient rule of A4.4). The values equal those of
    /// [`BSplineSurface::derivatives`] up to rounding. Parallel over rows
    /// with rayon; deterministic.
    pub fn map_grid_first<T: Send>(
        &self,
        us: &[f64],
        vs: &[f64],
        f: impl Fn(Vec3, Vec3, Vec3) -> T + Sync,
    ) -> Vec<T> {
        let (p, q) = (self.degree_u, self.degree_v);
        let nc = self.count_v;
        let bv: Vec<(usize, BasisDerivs)> = vs.iter().map(|&v| self.basis_v(v)).collect();
        us.par_iter()
            .flat_map_iter(|&u| {
                let (span_u, du) = self.basis_u(u);
                let i0 = span_u - p;
                // the net contracted in u: value and u-derivative per column
                let mut t0 = vec![DVec4::ZERO; nc];
                let mut t1 = vec![DVec4::ZERO; nc];
                for r in 0..=p {
                    let k = self.index(i0 + r, 0);
                    let row = &self.points[k..][..nc];
                    let (n0, n1) = (du[0][r], du[1][r]);
                    match &self.weights {
                        None => {
                            for (j, pt) in row.iter().enumerate() {
                                let pw = pt.extend(0.0);
                                t0[j] += n0 * pw;
                                t1[j] += n1 * pw;
                            }
                        }
                        Some(w) => {
                            for (j, (pt, &wj)) in row.iter().zip(&w[k..][..nc]).enumerate() {
                                let pw = wj * pt.extend(1.0);
                                t0[j] += n0 * pw;
                                t1[j] += n1 * pw;
                            }
                        }
                    }
                }
                let rational = self.weights.is_some();
                let f = &f;
                bv.iter().map(move |(span_v, dv)| {
                    let j0 = span_v - q;
                    let (mut a, mut au, mut av) = (DVec4::ZERO, DVec4::ZERO, DVec4::ZERO);
                    for s in 0..=q {
                        a += dv[0][s] * t0[j0 + s];
                        au += dv[0][s] * t1[j0 + s];
                        av += dv[1][s] * t0[j0 + s];
                    }
                    if rational {
                        let inv = 1.0 / a.w;
                        let s00 = a.truncate() * inv;
                        let su = (au.truncate() - au.w * s00) * inv;
                        let sv = (av.truncate() - av.w * s00) * inv;
                        f(s00, su, sv)
                    } else {
                        f(a.truncate(), au.truncate(), av.truncate())
                    }
                })
            })
            .collect()
    }

    /// Derivatives at `(u, v)`, or at the first of a few parameters nudged
    /// towards the domain centre (by the fractions `nudges` of the domain
    /// width) if the point is degenerate, i.e. `|Su × Sv| <= tol · max(|Su|, |Sv|)²`
    /// (a pole or a collapsed edge). `None` if every try is degenerate.
    fn regular_derivatives(
        &self,
        u: f64,
        v: f64,
        tol: f64,
        nudges: &[f64],
    ) -> Option<(SurfaceDerivatives, Vec3)> {
        let regular = |d: SurfaceDerivatives| {
            let n = d.su.cross(d.sv).length();
            let m = d.su.length_squared().max(d.sv.length_squared());
            if n > tol * m {
                d.normal().map(|nn| (d, nn))
            } else {
                None
            }
        };
        let (u, v) = self.clamp_parameters(u, v);
        if let Some(r) = regular(self.derivatives(u, v)) {
            return Some(r);
        }
        let ([a, b], [c, e]) = (self.domain_u(), self.domain_v());
        let (uc, vc) = self.domain_center();
        let su = if u <= uc { 1.0 } else { -1.0 };
        let sv = if v <= vc { 1.0 } else { -1.0 };
        nudges
            .iter()
            .find_map(|&t| regular(self.derivatives(u + su * t * (b - a), v + sv * t * (e - c))))
    }

    /// Unit normal `Su × Sv / |Su × Sv|` (Nishiyama et al. Eq. (2.4)). At a
    /// degenerate point (`|Su × Sv|` below 1e-10 of `max(|Su|, |Sv|)²`, e.g.
    /// a pole) the normal of a nearby parameter (nudged towards the domain
    /// centre) is returned; `None` only if that fails too. Never NaN.
    pub fn normal(&self, u: f64, v: f64) -> Option<Vec3> {
        self.regular_derivatives(u, v, DEGENERATE, &NORMAL_NUDGES)
            .map(|(_, n)| n)
    }

    /// Principal curvatures, directions, mean and Gaussian curvature at
    /// `(u, v)` from the first (`E, F, G`) and second (`L, M, N`) fundamental
    /// forms (see [`SurfaceDerivatives::curvature`]). Where the parametrisation
    /// is (nearly) degenerate, `|Su × Sv| <= 1e-5 · max(|Su|, |Sv|)²`, the
    /// curvature of a parameter nudged towards the domain centre by 1e-4,
    /// 1e-3 or 1e-2 of the domain width is returned instead (at a pole, the
    /// limit is approached to that distance); `None` if all are degenerate.
    pub fn principal_curvatures(&self, u: f64, v: f64) -> Option<Curvature> {
        self.regular_derivatives(u, v, CURVATURE_REGULAR, &CURVATURE_NUDGES)
            .and_then(|(d, _)| d.curvature())
    }

    /// Gaussian curvature `K = (LN - M²) / (EG - F²)` at `(u, v)`.
    pub fn gaussian_curvature(&self, u: f64, v: f64) -> Option<f64> {
        self.principal_curvatures(u, v).map(|c| c.gauss)
    }

    /// Mean curvature `H = -(EN - 2FM + GL) / (2 (EG - F²))` at `(u, v)`
    /// (positive on a sphere with outward `Su × Sv`).
    pub fn mean_curvature(&self, u: f64, v: f64) -> Option<f64> {
        self.principal_curvatures(u, v).map(|c| c.mean)
    }
}

/// Quotient rule for rational surface derivatives up to order 2
/// (Piegl & Tiller A4.4 / Eq. 4.20): `S^{(k,l)} = (A^{(k,l)} - Σ binomials ·
/// w^{(i,j)} S^{(k-i,l-j)}) / w`. Input order: (0,0), (1,0), (0,1), (2,0), (1,1), (0,2).
fn rational_derivatives(a: &[DVec4; 6]) -> SurfaceDerivatives {
    let w = a[0].w;
    let inv = 1.0 / w;
    let (w10, w01, w20, w11, w02) = (a[1].w, a[2].w, a[3].w, a[4].w, a[5].w);
    let s00 = a[0].truncate() * inv;
    let s10 = (a[1].truncate() - w10 * s00) * inv;
    let s01 = (a[2].truncate() - w01 * s00) * inv;
    let s20 = (a[3].truncate() - 2.0 * w10 * s10 - w20 * s00) * inv;
    let s11 = (a[4].truncate() - w10 * s01 - w01 * s10 - w11 * s00) * inv;
    let s02 = (a[5].truncate() - 2.0 * w01 * s01 - w02 * s00) * inv;
    SurfaceDerivatives {
        point: s00,
        su: s10,
        sv: s01,
        suu: s20,
        suv: s11,
        svv: s02,
    }
}

/// Indices of the basis functions of one direction non-zero somewhere inside
/// `[t0, t1]` (or at `t0` if the interval is a point).
fn support_range(
    knots: &[f64],
    degree: usize,
    count: usize,
    domain: [f64; 2],
    t0: f64,
    t1: f64,
) -> Range<usize> {
    let (mut a, mut b) = (clamp_param(t0, domain), clamp_param(t1, domain));
    if a > b {
        std::mem::swap(&mut a, &mut b);
    }
    if a == b {
        let span = find_span(knots, degree, count, a);
        return span - degree..span + 1;
    }
    // N_i is non-zero on (knots[i], knots[i+p+1]); overlap with (a, b).
    let first = (0..count).find(|&i| knots[i + degree + 1] > a);
    let last = (0..count).rev().find(|&i| knots[i] < b);
    match (first, last) {
        (Some(f), Some(l)) if f <= l => f..l + 1,
        _ => 0..0,
    }
}

/// Unit normal `Su × Sv / |Su × Sv|` (Nishiyama et al. Eq. (2.4)), or `None`
/// where `|Su × Sv|` is below 1e-10 · max(|Su|, |Sv|)² (degenerate
/// parametrisation) or not finite. See [`SurfaceDerivatives::normal`].
#[inline]
pub fn unit_normal(su: Vec3, sv: Vec3) -> Option<Vec3> {
    let n = su.cross(sv);
    let len = n.length();
    let m = su.length_squared().max(sv.length_squared());
    if len > DEGENERATE * m && len.is_finite() {
        Some(n / len)
    } else {
        None
    }
}

impl SurfaceDerivatives {
    /// Unit normal `Su × Sv / |Su × Sv|`, or `None` where `|Su × Sv|` is below
    /// 1e-10 · max(|Su|, |Sv|)² (degenerate parametrisation) or not finite.
    pub fn normal(&self) -> Option<Vec3> {
        unit_normal(self.su, self.sv)
    }

    /// Curvature from the fundamental forms (do Carmo §3.3):
    /// `E = Su·Su, F = Su·Sv, G = Sv·Sv`, `L = Suu·N, M = Suv·N, N = Svv·N`,
    /// with `K = (LN - M²)/(EG - F²)` and `H = -(EN - 2FM + GL)/(2(EG - F²))`.
    /// The minus sign makes curvature positive where the surface bends away
    /// from `N` (a sphere with outward normal has `+1/r`).
    ///
    /// Computed stably: the second fundamental form is expressed in the
    /// orthonormal tangent frame `e1 = Su/|Su|`, `e2 = N × e1` as the
    /// symmetric matrix `[[a, b], [b, c]]` (`a = -L/E`, …), whose eigenvalues
    /// `k1,2 = (a+c)/2 ± √(((a-c)/2)² + b²)` and eigenvectors (angle
    /// `½ atan2(2b, a - c)` from `e1`) are the principal curvatures and
    /// directions; this keeps full precision at umbilic points, where
    /// `H ± √(H² - K)` would lose half the digits. `None` at a degenerate point.
    pub fn curvature(&self) -> Option<Curvature> {
        let normal = self.normal()?;
        let e = self.su.dot(self.su);
        let f = self.su.dot(self.sv);
        let g = self.sv.dot(self.sv);
        let l = self.suu.dot(normal);
        let m = self.suv.dot(normal);
        let n = self.svv.dot(normal);
        let su_len = e.sqrt();
        let perp = g - f * f / e;
        if !(perp > 0.0 && su_len > 0.0) {
            return None;
        }
        // e1 = x1·(Su, Sv) with x1 = (1/|Su|, 0); e2 = (α, β)·(Su, Sv).
        let beta = 1.0 / perp.sqrt();
        let alpha = -f / e * beta;
        let a = -l / e;
        let b = -(alpha * l + beta * m) / su_len;
        let c = -(alpha * alpha * l + 2.0 * alpha * beta * m + beta * beta * n);
        let mean = 0.5 * (a + c);
        let half = (0.5 * (a - c)).hypot(b);
        let (k1, k2) = (mean + half, mean - half);
        let gauss = a * c - b * b;
        let e1 = self.su / su_len;
        let e2 = normal.cross(e1);
        let theta = 0.5 * (2.0 * b).atan2(a - c);
        let d1 = theta.cos() * e1 + theta.sin() * e2;
        let d2 = normal.cross(d1);
        let finite = [k1, k2, mean, gauss].iter().all(|x| x.is_finite()) && d1.is_finite();
        finite.then_some(Curvature {
            k1,
            k2,
            mean,
            gauss,
            d1,
            d2,
            normal,
        })
    }
}
