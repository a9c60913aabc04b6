//! Circular highlight lines (Nishiyama et al. §2): the signed distance
//! between a surface normal line and a circular light, Eq. (2.5)–(2.18), and
//! its zero level sets on triangle meshes.

use super::contour::{self, Levels};
use super::light::{CircleApproach, CircularLight};
use super::quartic::quartic_roots;
use super::{HighlightBands, HighlightError, HighlightLines, HighlightOptions};
use crate::Vec3;
use crate::geom;
use crate::mesh::SurfaceMesh;
use rayon::prelude::*;

/// |α|² + |β|² below which the normal is taken as parallel to the circle
/// axis (the normal line keeps a constant distance from the circle).
const AXIS_PARALLEL: f64 = 1e-12;

impl CircularLight {
    /// Closest approach between the normal line E(τ) = Q + τN (Eq. (2.3)) of
    /// a point Q with normal N and this circle (Nishiyama et al. §2):
    ///
    /// 1. the stationary points of the squared distance, Eq. (2.7), reduce to
    ///    the quartic Eq. (2.15) with coefficients Eq. (2.16) in the notation
    ///    of Eq. (2.12); all its real roots τ are found by
    ///    [`super::quartic::quartic_roots`] (no allocation, near-double roots
    ///    never lost). The line is parametrised from its point nearest to the
    ///    centre A, Q₀ = Q + ((A − Q)·N)N, so that ε = (A − Q₀)·N = 0: the same
    ///    line, but Eq. (2.16) loses the terms in ε², ε³ whose cancellation
    ///    for a distant light (|ε| ≫ R) destroyed nearly merged roots, and
    ///    c₀ = −R²p² ≤ 0 < c₄ guarantees a real root of each sign;
    /// 2. for each root, θ follows from Eq. (2.10): (cos θ, sin θ) is
    ///    proportional to ((τN − A + Q)·n, (τN − A + Q)·b) with the factor
    ///    (τ − ε)/Det; the sign of that factor only picks the nearer or the
    ///    farther of two antipodal circle points, so the nearer is taken
    ///    directly, which needs no division by Det and covers Det = 0. When
    ///    the line point lies on the axis (every θ equidistant), θ is solved
    ///    from the first line of Eq. (2.8) (corrected as in DESIGN.md §3:
    ///    ε + R(cos θ α + sin θ β) = τ);
    /// 3. each candidate is scored by the distance of its circle point L(θ)
    ///    from the line, |P − (P·N)N| with P = L(θ) − Q₀ (τ eliminated as in
    ///    Eq. (2.8), first line), the nearest wins, and its θ is polished by
    ///    Newton steps on the derivative of that squared distance g(θ)
    ///    (kept only while g decreases) — so the distance is accurate to
    ///    rounding even where the quartic has a near-double root whose τ is
    ///    only known to ~sqrt(eps);
    /// 4. the signed distance is d_s = d·(N × L̇)/|N × L̇| of Eq. (2.18),
    ///    with L̇ of Eq. (2.17) and d from the line point to L(θ).
    ///
    /// A normal parallel to the axis (α = β = 0) makes the distance
    /// independent of τ; the point of the line in the circle's plane is used.
    /// Returns `None` where d_s is undefined: zero normal, N parallel to L̇,
    /// the line on the axis, or a non-finite result. No allocation.
    pub fn approach(&self, q: Vec3, normal: Vec3) -> Option<CircleApproach> {
        let nn = normal.try_normalize()?;
        if !q.is_finite() {
            return None;
        }
        let (n, b) = self.frame();
        let a = self.center();
        let r = self.radius();
        let eps0 = (a - q).dot(nn);
        let q = q + eps0 * nn;
        let bb = a - q;
        let alpha = n.dot(nn);
        let beta = b.dot(nn);
        let gamma = bb.dot(n);
        let delta = bb.dot(b);
        let c = alpha * alpha + beta * beta;
        // The circle point is carried as the unit vector (cos θ, sin θ) (no
        // trigonometry in the loop); L(θ) = A + R(cos θ n + sin θ b).
        let circle = |cs: f64, sn: f64| a + r * (cs * n + sn * b);
        // squared distance between L(θ) and the line, with P = L(θ) − Q₀
        let g = |cs: f64, sn: f64| {
            let p = circle(cs, sn) - q;
            let s = p.dot(nn);
            (p - s * nn).length_squared()
        };
        let mut best: Option<(f64, f64, f64)> = None; // (g, cos θ, sin θ)
        let mut consider = |cs: f64, sn: f64| {
            let d2 = g(cs, sn);
            if d2.is_finite() && best.is_none_or(|(b2, _, _)| d2 < b2) {
                best = Some((d2, cs, sn));
            }
        };
        let nearest_dir = |tau: f64| -> Option<(f64, f64)> {
            let w = q + tau * nn - a;
            let (wn, wb) = (w.dot(n), w.dot(b));
            let mut len = (wn * wn + wb * wb).sqrt();
            if !len.is_finite() {
                len = wn.hypot(wb);
            }
            (len > 1e-12 * r).then(|| (wn / len, wb / len))
        };
        if c < AXIS_PARALLEL {
            // N ∥ t: take the line point in the circle's plane
            let nt = nn.dot(self.axis());
            let tau = if nt.abs() > 0.0 {
                bb.dot(self.axis()) / nt
            } else {
                0.0
            };
            if let Some((cs, sn)) = nearest_dir(tau) {
                consider(cs, sn);
            }
        } else {
            let p = alpha * gamma + beta * delta;
            let qq = gamma * gamma + delta * delta;
            let r2 = r * r;
            // Eq. (2.16) with ε = 0
            let c4 = c;
            let c3 = -2.0 * p;
            let c2 = qq - r2 * c * c;
            let c1 = 2.0 * r2 * c * p;
            let c0 = -r2 * p * p;
            for tau in quartic_roots(c4, c3, c2, c1, c0) {
                match nearest_dir(tau) {
                    Some((cs, sn)) => consider(cs, sn),
                    None => {
                        // line point on the axis: θ from Eq. (2.8), first line
                        let rho = c.sqrt();
                        let phi = beta.atan2(alpha);
                        let cosv = (tau / (r * rho)).clamp(-1.0, 1.0);
                        let dv = cosv.acos();
                        for th in [phi + dv, phi - dv] {
                            let (sn, cs) = th.sin_cos();
                            consider(cs, sn);
                        }
                    }
                }
            }
        }
        let (mut g_best, mut cs, mut sn) = best?;
        // Newton polish of the stationary point: h = g/2,
        // h' = P·L' − (P·N)(L'·N), h'' = |L'|² + P·L'' − (L'·N)² − (P·N)(L''·N),
        // L' = R(−sin θ n + cos θ b), L'' = −(L − A). The step δ is applied
        // as the rotation by atan δ (same to third order, so still Newton's
        // quadratic convergence) to keep (cos θ, sin θ) without trigonometry.
        for _ in 0..3 {
            let rad = r * (cs * n + sn * b);
            let l1 = r * (-sn * n + cs * b);
            let p = a + rad - q;
            let (pn, l1n) = (p.dot(nn), l1.dot(nn));
            let h1 = p.dot(l1) - pn * l1n;
            let h2 = l1.length_squared() - p.dot(rad) - l1n * l1n + pn * rad.dot(nn);
            if !(h2 > 0.0) || h1 == 0.0 {
                break;
            }
            let step = -h1 / h2;
            let k = 1.0 / (1.0 + step * step).sqrt();
            let (cn, sn_next) = ((cs - step * sn) * k, (sn + step * cs) * k);
            let g_next = g(cn, sn_next);
            if g_next.is_finite() && g_next <= g_best {
                (cs, sn, g_best) = (cn, sn_next, g_next);
                if step.abs() <= 4.0 * f64::EPSILON {
                    break;
                }
            } else {
                break;
            }
        }
        let lp = circle(cs, sn);
        let tau = (lp - q).dot(nn);
        let d = lp - (q + tau * nn);
        // Eq. (2.17)
        let ldot = r * (-sn * n + cs * b);
        let m = nn.cross(ldot);
        let ml = m.length();
        if !(ml > 1e-12 * r) {
            return None;
        }
        let ds = d.dot(m) / ml;
        let theta = f64::atan2(sn, cs);
        let tau = tau + eps0;
        (ds.is_finite() && tau.is_finite()).then_some(CircleApproach {
            signed_distance: ds,
            tau,
            theta,
        })
    }

    /// Signed distance d_s between the normal line of (Q, N) and the circle,
    /// Nishiyama et al. Eq. (2.18) (surface units); `None` where undefined.
    /// See [`CircularLight::approach`].
    pub fn signed_distance(&self, q: Vec3, normal: Vec3) -> Option<f64> {
        self.approach(q, normal).map(|a| a.signed_distance)
    }
}

/// Per-vertex closest approaches of the mesh's normal lines (Eq. (3)
/// normals of Yong et al.) to one circular light.
fn vertex_approaches(
    mesh: &SurfaceMesh,
    normals: &[Vec3],
    light: &CircularLight,
) -> (Vec<f64>, Vec<i8>, Vec<f64>) {
    let res: Vec<Option<CircleApproach>> = mesh
        .positions()
        .par_iter()
        .zip(normals.par_iter())
        .map(|(&q, &n)| light.approach(q, n))
        .collect();
    let values = res
        .iter()
        .map(|a| a.map_or(0.0, |a| a.signed_distance))
        .collect();
    let branch = res.iter().map(|a| i8::from(a.is_some())).collect();
    let theta = res.iter().map(|a| a.map_or(0.0, |a| a.theta)).collect();
    (values, branch, theta)
}

/// Contours of d_s = `level` for each light; line index k = light number.
/// `done` counts the lights contoured before (bands contour each light
/// twice) and `total` all of them, for the progress of `options.control`.
fn circular_levels(
    mesh: &SurfaceMesh,
    lights: &[CircularLight],
    level: f64,
    options: &HighlightOptions,
    (done, total): (usize, usize),
) -> Result<HighlightLines, HighlightError> {
    mesh.require_triangles()?;
    let normals = geom::vertex_normals(mesh);
    let mut all = HighlightLines::default();
    for (k, light) in lights.iter().enumerate() {
        options
            .control
            .step("lights", (done + k) as u64, total as u64)?;
        let (values, branch, theta) = vertex_approaches(mesh, &normals, light);
        // d_s is discontinuous where the nearest circle point jumps (its sign
        // flips with the direction N × L̇): an edge whose two nearest circle
        // points are more than 90° apart carries no nodes.
        let edge_ok = |a: usize, b: usize| (theta[a] - theta[b]).cos() > 0.0;
        let lines = contour::contour(
            mesh,
            &values,
            &branch,
            Levels::Single {
                value: level,
                index: k as i64,
            },
            1,
            &edge_ok,
        );
        all.lines.extend(lines.lines);
    }
    options
        .control
        .progress("lights", (done + lights.len()) as u64, total as u64);
    Ok(all)
}

/// Circular highlight lines on a triangle mesh: for each light (typically
/// concentric circles of several radii), the zero level set of the
/// per-vertex signed distance d_s of Nishiyama et al. Eq. (2.18), contoured
/// like the linear model (Yong et al. §2.3–2.4). Line index k is the
/// position of the light in `lights`. Edges across which the nearest circle
/// point jumps by more than 90° carry no nodes (d_s is discontinuous there).
/// Of `options` only `control` applies (one step per light); errors with
/// [`HighlightError::Cancelled`] when it asks to stop.
pub fn circular_highlight_lines(
    mesh: &SurfaceMesh,
    lights: &[CircularLight],
    options: &HighlightOptions,
) -> Result<HighlightLines, HighlightError> {
    circular_levels(mesh, lights, 0.0, options, (0, lights.len()))
}

/// Circular highlight bands (Nishiyama et al. §2, last paragraph): the
/// level sets d_s = −ρ (`lower`) and d_s = +ρ (`upper`) of each light, a
/// torus-shaped light of tube radius ρ > 0. Line index k = light number.
///
/// Of `options` only `control` applies (one step per light and band side).
pub fn circular_highlight_bands(
    mesh: &SurfaceMesh,
    lights: &[CircularLight],
    rho: f64,
    options: &HighlightOptions,
) -> Result<HighlightBands, HighlightError> {
    if !(rho > 0.0) || !rho.is_finite() {
        return Err(HighlightError::InvalidOption(format!(
            "band radius must be a positive finite number, got {rho}"
        )));
    }
    Ok(HighlightBands {
        radius: rho,
        lower: circular_levels(mesh, lights, -rho, options, (0, 2 * lights.len()))?,
        upper: circular_levels(mesh, lights, rho, options, (lights.len(), 2 * lights.len()))?,
    })
}
