//! Closest points on B-spline surfaces and the exact deviation of points
//! from a part of surfaces.
//!
//! Point inversion (Piegl & Tiller §6.1, Eq. 6.3–6.6): the foot `S(u, v)`
//! of the perpendicular from `P` solves `f = S_u · r = 0`, `g = S_v · r = 0`
//! with `r = S(u, v) − P`; Newton's step solves
//! `[[|S_u|² + r·S_uu, S_u·S_v + r·S_uv], [S_u·S_v + r·S_uv, |S_v|² + r·S_vv]] δ = −[f, g]`,
//! each iterate clamped to the domain (a foot outside it ends on its
//! boundary).
//!
//! The deviation of points from a part ([`surface_deviation`]) starts each
//! point at the closest point of the part's tessellation (trimmed faces
//! tessellated inside their trims) and refines it by point inversion on
//! that triangle's surface; the refined foot is kept when it lies on the
//! face (inside its trims) and within the triangle's size of the
//! tessellation's closest point, otherwise the tessellation's closest
//! point stands (counted). The sign
//! is that of `(P − S) · N`, `N = S_u × S_v` normalised.

use super::{BSplineSurface, tessellate, unit_normal};
use crate::Vec3;
use crate::geom::{ClosestPoint, Deviation, DeviationError, DeviationMethod, TriangleGrid};
use rayon::prelude::*;

/// Most Newton steps of one point inversion.
const MAX_STEPS: usize = 30;

/// The closest point of `surface` to `p` by point inversion from `(u0, v0)`
/// (module documentation): the parameters and the point. Newton's step
/// where the Hessian of the squared distance is positive definite, else
/// steepest descent; each step halved until the distance does not grow.
/// Stops when a step moves less than 1e-15 of the domain's size, no
/// halving helps, or after [`MAX_STEPS`] steps; never leaves the domain.
pub fn closest_point_on_surface(
    surface: &BSplineSurface,
    p: Vec3,
    u0: f64,
    v0: f64,
) -> (f64, f64, Vec3) {
    let (mut u, mut v) = surface.clamp_parameters(u0, v0);
    let [a, b] = surface.domain_u();
    let [c, d] = surface.domain_v();
    let size = (b - a).abs().max((d - c).abs());
    for _ in 0..MAX_STEPS {
        let s = surface.derivatives(u, v);
        let r = s.point - p;
        let f = s.su.dot(r);
        let g = s.sv.dot(r);
        let j11 = s.su.length_squared() + r.dot(s.suu);
        let j12 = s.su.dot(s.sv) + r.dot(s.suv);
        let j22 = s.sv.length_squared() + r.dot(s.svv);
        let det = j11 * j22 - j12 * j12;
        let scale = (j11.abs() + j12.abs()) * (j12.abs() + j22.abs());
        // Newton where the Hessian is positive definite (a minimum ahead),
        // else steepest descent scaled by the first fundamental form
        let (du, dv) = if det > 1e-14 * scale && j11 > 0.0 && det.is_finite() {
            ((-f * j22 + g * j12) / det, (-g * j11 + f * j12) / det)
        } else {
            let e = s.su.length_squared() + s.sv.length_squared();
            if !(e > 1e-300) {
                break;
            }
            (-f / e, -g / e)
        };
        if !(du.is_finite() && dv.is_finite()) {
            break;
        }
        // halve the step until the distance does not grow
        let d0 = r.length_squared();
        let mut step = 1.0;
        let mut next = None;
        while step > 1e-6 {
            let (nu, nv) = surface.clamp_parameters(u + step * du, v + step * dv);
            if (surface.eval(nu, nv) - p).length_squared() <= d0 {
                next = Some((nu, nv));
                break;
            }
            step *= 0.5;
        }
        let Some((nu, nv)) = next else { break };
        let moved = (nu - u).abs().max((nv - v).abs());
        u = nu;
        v = nv;
        if moved <= 1e-15 * size {
            break;
        }
    }
    (u, v, surface.eval(u, v))
}

/// A part of B-spline surfaces prepared for distance queries: its
/// tessellation and a grid over the triangles, which give each point's
/// start for point inversion (module documentation).
pub struct SurfaceReference<'a> {
    surfaces: &'a [BSplineSurface],
    positions: Vec<Vec3>,
    uv: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
    patch: Vec<usize>,
    grid: TriangleGrid,
    /// The largest distance of a triangle's centroid from its surface: a
    /// surface comes within its distance plus this of the tessellation.
    sag: f64,
    /// The diagonal of the tessellation's bounding box.
    size: f64,
}

/// One point's distance from a [`SurfaceReference`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointDeviation {
    /// Signed distance, positive on the side `S_u × S_v` points to.
    pub signed: f64,
    /// Unsigned distance.
    pub distance: f64,
    /// Whether the foot was refined onto a face (else the tessellation's
    /// closest point stands).
    pub refined: bool,
}

impl<'a> SurfaceReference<'a> {
    /// Tessellates each surface `grid` × `grid` (inside its trims). Fails
    /// when the tessellations hold no usable triangle.
    pub fn new(surfaces: &'a [BSplineSurface], grid: usize) -> Result<Self, DeviationError> {
        let pieces: Vec<_> = surfaces
            .par_iter()
            .map(|s| tessellate(s, grid, grid))
            .collect();
        let (mut positions, mut uv, mut triangles, mut patch) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (k, t) in pieces.into_iter().enumerate() {
            let base = positions.len() as u32;
            positions.extend(t.positions);
            uv.extend(t.uv);
            for tri in t.triangles {
                triangles.push(tri.map(|i| i + base));
                patch.push(k);
            }
        }
        let grid = TriangleGrid::new(&positions, &triangles);
        if grid.is_empty() {
            return Err(DeviationError::EmptyReference);
        }
        // how far the triangles stand off their surfaces, at their centroids
        let sag = triangles
            .par_iter()
            .zip(&patch)
            .map(|(t, &k)| {
                let c = t.map(|i| positions[i as usize]);
                let centroid = (c[0] + c[1] + c[2]) / 3.0;
                let [u, v] =
                    [0, 1].map(|a| t.iter().map(|&i| uv[i as usize][a]).sum::<f64>() / 3.0);
                let d = surfaces[k].eval(u, v).distance(centroid);
                if d.is_finite() { d } else { 0.0 }
            })
            .reduce(|| 0.0, f64::max);
        let (lo, hi) = positions.iter().filter(|p| p.is_finite()).fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let size = (hi - lo).length();
        Ok(Self {
            surfaces,
            positions,
            uv,
            triangles,
            patch,
            grid,
            sag,
            size: if size.is_finite() { size } else { 0.0 },
        })
    }

    /// The distance of `p` from the part: the tessellation's closest point
    /// refined by point inversion on its triangle's surface; the refined
    /// foot is kept when it lies on the face (inside its trims) and within
    /// the triangle's size of the tessellation's closest point. Where other
    /// surfaces' triangles also come within that foot's distance plus twice
    /// the tessellation's largest sag (a centroid's distance from its
    /// surface) of `p` — near the edges where faces meet or overlap — the
    /// foot is refined on each of them too and the nearest refined foot is
    /// kept ([`NEIGHBOUR_CELLS`] bounds that search; a point whose first
    /// foot lies within 1e-12 of the part's size needs none).
    /// `None` where no finite value results.
    pub fn deviation(&self, p: Vec3) -> Option<PointDeviation> {
        let c = self.grid.closest(p)?;
        // a surface nearer than the foot on the closest triangle's own has
        // triangles within that distance plus the sag of the tessellation
        let first = self.refine(p, &c);
        let reach = first.map_or(c.distance + self.triangle_size(c.triangle), |f| f.2);
        let mut candidates = vec![c];
        // (a point on a surface, to rounding, has no nearer one)
        let on_surface = first.is_some() && reach <= 1e-12 * self.size;
        if !on_surface {
            self.grid
                .for_each_within(p, reach + 2.0 * self.sag, NEIGHBOUR_CELLS, |t| {
                    let k = self.patch[t.triangle];
                    match candidates.iter_mut().find(|x| self.patch[x.triangle] == k) {
                        Some(x) => {
                            if t.distance < x.distance {
                                *x = t;
                            }
                        }
                        None => candidates.push(t),
                    }
                });
        }
        let best = first
            .into_iter()
            .chain(candidates[1..].iter().filter_map(|t| self.refine(p, t)))
            .min_by(|a, b| a.2.total_cmp(&b.2));
        let (patch, foot, uv_foot, dist, refined) = match best {
            Some((patch, (foot, uv), dist)) => (patch, foot, uv, dist, true),
            None => {
                let t = self.triangles[c.triangle];
                let w = c.barycentric;
                let uv = self.uv_at(t, w);
                (self.patch[c.triangle], c.point, uv, c.distance, false)
            }
        };
        let s = &self.surfaces[patch];
        let d = s.derivatives(uv_foot[0], uv_foot[1]);
        let side = match unit_normal(d.su, d.sv) {
            Some(n) => (p - foot).dot(n),
            None => {
                let q3 = self.triangles[c.triangle].map(|i| self.positions[i as usize]);
                (p - foot).dot((q3[1] - q3[0]).cross(q3[2] - q3[0]))
            }
        };
        let signed = if side < 0.0 { -dist } else { dist };
        (signed.is_finite() && dist.is_finite()).then_some(PointDeviation {
            signed,
            distance: dist,
            refined,
        })
    }

    /// The longest side of a triangle of the tessellation.
    fn triangle_size(&self, triangle: usize) -> f64 {
        let q = self.triangles[triangle].map(|i| self.positions[i as usize]);
        q[0].distance(q[1])
            .max(q[1].distance(q[2]))
            .max(q[2].distance(q[0]))
    }

    /// The parameters at barycentric `w` of triangle `t`.
    fn uv_at(&self, t: [u32; 3], w: [f64; 3]) -> [f64; 2] {
        let uv = &self.uv;
        [0, 1].map(|i| {
            w[0] * uv[t[0] as usize][i] + w[1] * uv[t[1] as usize][i] + w[2] * uv[t[2] as usize][i]
        })
    }

    /// Point inversion of `p` on the surface of the tessellation's point
    /// `c`, started there: `(patch, (foot, uv), distance)` when the foot
    /// lies on the face — or, at a trim boundary the tessellation follows,
    /// has not moved off its start — and within the triangle's size of the
    /// tessellation's point (a chord is within it of its arc).
    fn refine(&self, p: Vec3, c: &ClosestPoint) -> Option<(usize, (Vec3, [f64; 2]), f64)> {
        let patch = self.patch[c.triangle];
        let s = &self.surfaces[patch];
        let start = self.uv_at(self.triangles[c.triangle], c.barycentric);
        let (u, v, q) = closest_point_on_surface(s, p, start[0], start[1]);
        let exact = q.distance(p);
        let [u0, u1] = s.domain_u();
        let [v0, v1] = s.domain_v();
        let stayed = (u - start[0]).abs() + (v - start[1]).abs()
            <= 1e-9 * ((u1 - u0).abs() + (v1 - v0).abs());
        ((s.contains_uv(u, v) || stayed)
            && exact <= c.distance + self.triangle_size(c.triangle)
            && exact.is_finite())
        .then_some((patch, (q, [u, v]), exact))
    }
}

/// Most grid cells searched around a point for other surfaces near its
/// closest one ([`SurfaceReference::deviation`]).
const NEIGHBOUR_CELLS: usize = 512;

/// Signed distance of every point of `points` from the part `surfaces`
/// (module documentation), each surface tessellated `grid` × `grid` for the
/// start ([`SurfaceReference`]). `unrefined` counts the points whose foot
/// could not be refined on a face (their value is the tessellation's),
/// `unmatched` those with no finite value (set to 0). Fails when the
/// tessellations hold no usable triangle.
pub fn surface_deviation(
    surfaces: &[BSplineSurface],
    points: &[Vec3],
    grid: usize,
) -> Result<Deviation, DeviationError> {
    Ok(SurfaceReference::new(surfaces, grid)?.deviations(points))
}

impl SurfaceReference<'_> {
    /// [`Self::deviation`] of every point, as a [`Deviation`]
    /// ([`surface_deviation`]).
    pub fn deviations(&self, points: &[Vec3]) -> Deviation {
        let measured: Vec<Option<PointDeviation>> =
            points.par_iter().map(|&p| self.deviation(p)).collect();
        let unmatched = measured.iter().filter(|m| m.is_none()).count();
        let unrefined = measured
            .iter()
            .filter(|m| m.is_some_and(|d| !d.refined))
            .count();
        let (signed, distance) = measured
            .into_iter()
            .map(|m| m.map_or((0.0, 0.0), |d| (d.signed, d.distance)))
            .unzip();
        Deviation {
            method: DeviationMethod::SurfacePoint,
            signed,
            distance,
            unmatched,
            unrefined,
        }
    }
}

/// Where the part `measured` lies farthest from a reference part, found
/// on the surfaces themselves rather than at sample points
/// ([`deviation_peak`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviationPeak {
    /// Index of the measured surface.
    pub face: usize,
    /// Its parameters there.
    pub u: f64,
    /// Its parameters there.
    pub v: f64,
    /// The point `S(u, v)`.
    pub point: Vec3,
    /// The signed distance there (its magnitude the peak).
    pub signed: f64,
    /// The largest exact |distance| over the `grid` × `grid` samples of
    /// every measured face, from which the search started.
    pub sampled: f64,
}

/// Starts of the peak search: the samples of largest |distance|.
const PEAK_STARTS: usize = 16;

/// The largest |signed distance| of the surfaces `measured` from
/// `reference` over the measured faces (inside their trims), found
/// between sample points: each face is sampled at the vertices of its
/// `grid` × `grid` tessellation, and from the [`PEAK_STARTS`] samples of
/// largest |distance| a pattern search over the face's parameters climbs
/// |d(u, v)| — steps of one grid cell in u, v and the diagonals, halved
/// where none climbs, down to 1e-10 of the domain — staying on the face.
/// Every value is an exact distance of [`SurfaceReference::deviation`]:
/// points whose foot could not be refined onto a face are left out, as
/// samples and as steps. `None` when no sample has an exact distance.
pub fn deviation_peak(
    reference: &SurfaceReference<'_>,
    measured: &[BSplineSurface],
    grid: usize,
) -> Option<DeviationPeak> {
    let samples: Vec<(usize, [f64; 2], f64)> = measured
        .par_iter()
        .enumerate()
        .flat_map_iter(|(k, s)| {
            let t = tessellate(s, grid, grid);
            t.uv.into_iter()
                .zip(t.positions)
                .filter_map(|(uv, p)| {
                    let d = reference.deviation(p)?;
                    d.refined.then_some((k, uv, d.signed))
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let sampled = samples.iter().map(|x| x.2.abs()).fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_by(|&a, &b| {
        samples[b]
            .2
            .abs()
            .total_cmp(&samples[a].2.abs())
            .then(a.cmp(&b))
    });
    order.truncate(PEAK_STARTS);
    let climbed: Vec<(usize, [f64; 2], f64)> = order
        .par_iter()
        .map(|&i| {
            let (k, uv, d) = samples[i];
            let (uv, d) = climb(reference, &measured[k], uv, d, grid);
            (k, uv, d)
        })
        .collect();
    let (face, [u, v], signed) = climbed
        .into_iter()
        .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))?;
    Some(DeviationPeak {
        face,
        u,
        v,
        point: measured[face].eval(u, v),
        signed,
        sampled,
    })
}

/// Pattern search for a local maximum of |d| on `surface` from `(uv, d)`
/// ([`deviation_peak`]).
fn climb(
    reference: &SurfaceReference<'_>,
    surface: &BSplineSurface,
    mut uv: [f64; 2],
    mut d: f64,
    grid: usize,
) -> ([f64; 2], f64) {
    let [a, b] = surface.domain_u();
    let [c, e] = surface.domain_v();
    let cells = grid.max(2) as f64 - 1.0;
    let (mut hu, mut hv) = ((b - a) / cells, (e - c) / cells);
    let (stop_u, stop_v) = (1e-10 * (b - a), 1e-10 * (e - c));
    const DIRECTIONS: [[f64; 2]; 8] = [
        [1.0, 0.0],
        [-1.0, 0.0],
        [0.0, 1.0],
        [0.0, -1.0],
        [1.0, 1.0],
        [-1.0, -1.0],
        [1.0, -1.0],
        [-1.0, 1.0],
    ];
    // each halving or climb is one step; the budget bounds the work
    for _ in 0..400 {
        if hu <= stop_u && hv <= stop_v {
            break;
        }
        let mut best: Option<([f64; 2], f64)> = None;
        for dir in DIRECTIONS {
            let (u, v) = (uv[0] + dir[0] * hu, uv[1] + dir[1] * hv);
            if !surface.contains_uv(u, v) {
                continue;
            }
            // only exact values: a foot not refined onto a face stands at
            // the tessellation's distance, which is no surface's
            let Some(q) = reference
                .deviation(surface.eval(u, v))
                .filter(|q| q.refined)
            else {
                continue;
            };
            if q.signed.abs() > best.map_or(d.abs(), |b| b.1.abs()) {
                best = Some(([u, v], q.signed));
            }
        }
        match best {
            Some((to, dd)) => {
                uv = to;
                d = dd;
            }
            None => {
                hu *= 0.5;
                hv *= 0.5;
            }
        }
    }
    (uv, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter cylinder of radius r about the z axis, height 1.
    fn quarter_cylinder(r: f64) -> BSplineSurface {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let ring = [
            (Vec3::new(r, 0.0, 0.0), 1.0),
            (Vec3::new(r, r, 0.0), w),
            (Vec3::new(0.0, r, 0.0), 1.0),
        ];
        BSplineSurface::new(
            2,
            1,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            ring.iter()
                .map(|(p, _)| vec![*p, *p + Vec3::new(0.0, 0.0, 1.0)])
                .collect(),
            Some(ring.iter().map(|(_, w)| vec![*w, *w]).collect()),
        )
        .unwrap()
    }

    #[test]
    fn points_off_a_cylinder_are_their_radial_distance_away_exactly() {
        let s = quarter_cylinder(2.0);
        // points at radius 2 ± h, angles inside the quarter, heights inside
        let mut points = Vec::new();
        let mut want = Vec::new();
        for i in 0..20 {
            let a = 0.05 + 1.4 * i as f64 / 19.0;
            let h = 0.1 * ((i as f64) - 9.5) / 9.5;
            points.push(Vec3::new(
                (2.0 + h) * a.cos(),
                (2.0 + h) * a.sin(),
                0.05 * i as f64,
            ));
            want.push(h);
        }
        let coarse = surface_deviation(std::slice::from_ref(&s), &points, 6).unwrap();
        assert_eq!(coarse.method, DeviationMethod::SurfacePoint);
        assert_eq!((coarse.unmatched, coarse.unrefined), (0, 0));
        for (got, h) in coarse.signed.iter().zip(&want) {
            // the cylinder's normal points outward: farther out is positive
            assert!((got - h).abs() < 1e-12, "{got} vs {h}");
        }
        // the tessellation alone is off by the chord error of a 6 × 6 grid
        let mesh = crate::bspline::tessellate(&s, 6, 6);
        let m = crate::SurfaceMesh::new(mesh.positions, &mesh.triangles).unwrap();
        let tess = crate::geom::closest_point_deviation(&m, &points).unwrap();
        let worst = tess
            .signed
            .iter()
            .zip(&want)
            .map(|(g, h)| (g - h).abs())
            .fold(0.0, f64::max);
        assert!(
            worst > 1e-3,
            "the chord error the projection removes: {worst}"
        );
    }

    #[test]
    fn the_foot_stays_in_the_domain_and_inversion_reaches_its_point() {
        let s = quarter_cylinder(1.0);
        let (u, v, q) = closest_point_on_surface(&s, s.eval(0.3, 0.7), 0.9, 0.1);
        assert!(
            (u - 0.3).abs() < 1e-12 && (v - 0.7).abs() < 1e-12,
            "{u} {v}"
        );
        assert!(q.distance(s.eval(0.3, 0.7)) < 1e-14);
        // beyond the end of the quarter: the foot on the domain's edge
        let (u, _, _) = closest_point_on_surface(&s, Vec3::new(-1.0, 0.5, 0.5), 0.5, 0.5);
        assert_eq!(u, 1.0);
        // no NaN from a point on the axis (every foot equally near)
        let (u, v, q) = closest_point_on_surface(&s, Vec3::new(0.0, 0.0, 0.5), 0.5, 0.5);
        assert!(u.is_finite() && v.is_finite() && q.is_finite());
    }

    /// The plane z = 0 over [−1, 2]², normal +z.
    fn floor() -> BSplineSurface {
        let p = |x: f64, y: f64| Vec3::new(x, y, 0.0);
        BSplineSurface::new(
            1,
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            vec![
                vec![p(-1.0, -1.0), p(-1.0, 2.0)],
                vec![p(2.0, -1.0), p(2.0, 2.0)],
            ],
            None,
        )
        .unwrap()
    }

    /// S(u, v) = (u, v, 3u(1 − u)²): its height peaks at u = 1/3 (4/9),
    /// between the samples of any grid of 3k + 2 … points.
    fn hump() -> BSplineSurface {
        let z = [0.0, 1.0, 0.0, 0.0];
        BSplineSurface::new(
            3,
            1,
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            (0..4)
                .map(|i| {
                    (0..2)
                        .map(|j| Vec3::new(i as f64 / 3.0, j as f64, z[i]))
                        .collect()
                })
                .collect(),
            None,
        )
        .unwrap()
    }

    #[test]
    fn the_deviation_peak_is_found_between_the_samples() {
        let reference = [floor()];
        let r = SurfaceReference::new(&reference, 16).unwrap();
        let measured = [hump()];
        let peak = deviation_peak(&r, &measured, 8).unwrap();
        // samples at u = k/7: the largest is at 2/7
        let at = |u: f64| 3.0 * u * (1.0 - u) * (1.0 - u);
        assert!((peak.sampled - at(2.0 / 7.0)).abs() < 1e-12, "{peak:?}");
        assert!((peak.signed - 4.0 / 9.0).abs() < 1e-12, "{peak:?}");
        assert!((peak.u - 1.0 / 3.0).abs() < 1e-5, "{peak:?}");
        assert_eq!(peak.face, 0);
        assert!((peak.point - measured[0].eval(peak.u, peak.v)).length() == 0.0);
    }

    #[test]
    fn the_deviation_peak_stays_on_the_trimmed_face() {
        let reference = [floor()];
        let r = SurfaceReference::new(&reference, 16).unwrap();
        // kept for u <= 0.25: the height grows up to the trim
        let outer =
            crate::bspline::TrimLoop::polygon(&[[0.0, 0.0], [0.25, 0.0], [0.25, 1.0], [0.0, 1.0]])
                .unwrap();
        let measured = [hump().with_trims(vec![outer]).unwrap()];
        let peak = deviation_peak(&r, &measured, 8).unwrap();
        // on the face or its trim (samples include the trim's points)
        assert!(peak.u <= 0.25, "{peak:?}");
        assert!((peak.signed - 0.421875).abs() < 1e-9, "{peak:?}");
        // nothing to measure against: no peak
        assert!(deviation_peak(&r, &[], 8).is_none());
    }
}
