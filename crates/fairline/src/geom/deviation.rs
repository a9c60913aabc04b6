//! Deviation between two states of a surface: the signed distance, per
//! vertex of the measured mesh, to the reference mesh, and its statistics.
//!
//! - Same connectivity (the same vertex count and the same triangles,
//!   e.g. a mesh before and after fairing): the vertex displacement
//!   `d_i = (p_i − r_i) · n_i`, with `n_i` the area-weighted unit normal of
//!   the reference at vertex `i` ([`DeviationMethod::Displacement`]); the
//!   full length `|p_i − r_i|` is kept as well.
//! - Otherwise: the distance from `p_i` to its closest point `q` on the
//!   reference triangles ([`TriangleGrid`]), signed by the side of the
//!   reference it lies on: `+` where `(p_i − q) · n(q) > 0`, with `n(q)`
//!   the reference vertex normals interpolated at `q`
//!   ([`DeviationMethod::ClosestPoint`]). B-spline surfaces are compared
//!   through their tessellations; the distance is then exact to the
//!   tessellation's chordal error.
//!
//! Positive values: the measured surface lies outside the reference (on
//! the side its normals point to). Every value is finite: a vertex whose
//! closest point cannot be found (empty or non-finite reference) is 0 and
//! counted in `unmatched`.

use super::closest::TriangleGrid;
use super::normals::vertex_normals;
use crate::Vec3;
use crate::mesh::SurfaceMesh;
use rayon::prelude::*;
use serde::Serialize;

/// How a deviation was measured (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DeviationMethod {
    /// Same connectivity: signed normal component of the vertex motion.
    Displacement,
    /// Different meshes: signed distance to the closest reference point.
    ClosestPoint,
    /// B-spline surfaces: signed distance to the closest point of the
    /// surfaces themselves (point inversion,
    /// [`crate::bspline::surface_deviation`]).
    SurfacePoint,
}

/// Per-vertex deviation of a measured mesh from a reference.
#[derive(Clone, Debug)]
pub struct Deviation {
    /// How it was measured.
    pub method: DeviationMethod,
    /// Signed deviation per vertex of the measured mesh (length units of
    /// the meshes), finite.
    pub signed: Vec<f64>,
    /// Unsigned distance per vertex: `|p_i − r_i|` (displacement) or the
    /// closest-point distance; finite.
    pub distance: Vec<f64>,
    /// Vertices whose value could not be measured (set to 0).
    pub unmatched: usize,
    /// B-spline references: points whose closest point could not be
    /// refined onto a face and are measured against the tessellation
    /// ([`crate::bspline::surface_deviation`]); 0 for meshes.
    pub unrefined: usize,
}

/// Errors of [`deviation`].
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DeviationError {
    /// The reference mesh has polygons: triangulate it first.
    #[error("the reference mesh has polygons; deviation needs triangles")]
    NotTriangles,
    /// The reference holds no usable triangle.
    #[error(
        "the reference has no usable triangle (no face, or every face has a non-finite corner)"
    )]
    EmptyReference,
}

/// The deviation of `measured` from `reference` (a triangle mesh), per
/// vertex of `measured`; the method is chosen by connectivity (module
/// documentation). `measured` may have polygons (its vertices are used).
pub fn deviation(
    reference: &SurfaceMesh,
    measured: &SurfaceMesh,
) -> Result<Deviation, DeviationError> {
    if !reference.is_triangle_mesh() {
        return Err(DeviationError::NotTriangles);
    }
    if same_connectivity(reference, measured) {
        return Ok(displacement(reference, measured.positions()));
    }
    closest_point_deviation(reference, measured.positions())
}

/// Whether two meshes have the same vertex count and the same faces.
pub fn same_connectivity(a: &SurfaceMesh, b: &SurfaceMesh) -> bool {
    a.vertex_count() == b.vertex_count()
        && a.face_count() == b.face_count()
        && a.faces()
            .zip(b.faces())
            .all(|(f, g)| a.face_vertices(f).eq(b.face_vertices(g)))
}

/// The displacement deviation of `positions` (one per vertex of
/// `reference`, the same connectivity) from the reference positions.
pub fn displacement(reference: &SurfaceMesh, positions: &[Vec3]) -> Deviation {
    let n = vertex_normals(reference);
    let mut unmatched = 0;
    let (signed, distance): (Vec<f64>, Vec<f64>) = reference
        .positions()
        .iter()
        .zip(positions)
        .zip(&n)
        .map(|((r, p), n)| {
            let d = *p - *r;
            let (s, l) = (d.dot(*n), d.length());
            if s.is_finite() && l.is_finite() {
                (s, l)
            } else {
                unmatched += 1;
                (0.0, 0.0)
            }
        })
        .unzip();
    Deviation {
        method: DeviationMethod::Displacement,
        signed,
        distance,
        unmatched,
        unrefined: 0,
    }
}

/// The closest-point deviation of `points` from the triangle mesh
/// `reference` (module documentation).
pub fn closest_point_deviation(
    reference: &SurfaceMesh,
    points: &[Vec3],
) -> Result<Deviation, DeviationError> {
    if !reference.is_triangle_mesh() {
        return Err(DeviationError::NotTriangles);
    }
    let tris: Vec<[u32; 3]> = reference
        .faces()
        .map(|f| reference.triangle(f).map(|v| v.0))
        .collect();
    let grid = TriangleGrid::new(reference.positions(), &tris);
    if grid.is_empty() {
        return Err(DeviationError::EmptyReference);
    }
    let normals = vertex_normals(reference);
    let measured: Vec<Option<(f64, f64)>> = points
        .par_iter()
        .map(|&p| {
            let c = grid.closest(p)?;
            let t = tris[c.triangle];
            let w = c.barycentric;
            let mut n = w[0] * normals[t[0] as usize]
                + w[1] * normals[t[1] as usize]
                + w[2] * normals[t[2] as usize];
            if n.length_squared() < 1e-24 {
                let q = t.map(|i| reference.positions()[i as usize]);
                n = (q[1] - q[0]).cross(q[2] - q[0]);
            }
            let side = (p - c.point).dot(n);
            let s = if side < 0.0 { -c.distance } else { c.distance };
            (s.is_finite() && c.distance.is_finite()).then_some((s, c.distance))
        })
        .collect();
    let unmatched = measured.iter().filter(|m| m.is_none()).count();
    let (signed, distance) = measured
        .into_iter()
        .map(|m| m.unwrap_or((0.0, 0.0)))
        .unzip();
    Ok(Deviation {
        method: DeviationMethod::ClosestPoint,
        signed,
        distance,
        unmatched,
        unrefined: 0,
    })
}

/// Equal-width histogram of values.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Upper edge of the last bin.
    pub hi: f64,
    /// Counts per bin (values outside [lo, hi] go to the end bins).
    pub counts: Vec<usize>,
}

/// Statistics of a signed deviation (all finite; zeros for no value).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DeviationStats {
    /// Values counted.
    pub count: usize,
    /// Smallest signed value.
    pub min: f64,
    /// Largest signed value.
    pub max: f64,
    /// Largest magnitude.
    pub max_abs: f64,
    /// Mean signed value.
    pub mean: f64,
    /// Mean magnitude.
    pub mean_abs: f64,
    /// Root mean square.
    pub rms: f64,
    /// Percentiles of the magnitude: 50th, 90th, 95th, 99th.
    pub p50_abs: f64,
    /// 90th percentile of the magnitude.
    pub p90_abs: f64,
    /// 95th percentile of the magnitude.
    pub p95_abs: f64,
    /// 99th percentile of the magnitude.
    pub p99_abs: f64,
    /// Histogram of the signed values over [−max_abs, max_abs] (a range
    /// centred on zero).
    pub histogram: Histogram,
}

/// The statistics of `values` (non-finite ones are skipped), the
/// histogram with `bins` bins (at least 1) over a range centred on 0.
pub fn deviation_stats(values: &[f64], bins: usize) -> DeviationStats {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let bins = bins.max(1);
    if v.is_empty() {
        return DeviationStats {
            count: 0,
            min: 0.0,
            max: 0.0,
            max_abs: 0.0,
            mean: 0.0,
            mean_abs: 0.0,
            rms: 0.0,
            p50_abs: 0.0,
            p90_abs: 0.0,
            p95_abs: 0.0,
            p99_abs: 0.0,
            histogram: Histogram {
                lo: 0.0,
                hi: 0.0,
                counts: vec![0; bins],
            },
        };
    }
    let n = v.len() as f64;
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let max_abs = min.abs().max(max.abs());
    let mean = v.iter().sum::<f64>() / n;
    let mean_abs = v.iter().map(|x| x.abs()).sum::<f64>() / n;
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
    a.sort_by(f64::total_cmp);
    let q = |p: f64| a[((a.len() - 1) as f64 * p).round() as usize];
    let mut counts = vec![0usize; bins];
    if max_abs > 0.0 {
        let w = 2.0 * max_abs / bins as f64;
        for x in &v {
            let b = ((x + max_abs) / w).floor();
            let b = if b.is_finite() && b > 0.0 {
                b as usize
            } else {
                0
            };
            counts[b.min(bins - 1)] += 1;
        }
    } else {
        counts[bins / 2] = v.len();
    }
    DeviationStats {
        count: v.len(),
        min,
        max,
        max_abs,
        mean,
        mean_abs,
        rms,
        p50_abs: q(0.5),
        p90_abs: q(0.9),
        p95_abs: q(0.95),
        p99_abs: q(0.99),
        histogram: Histogram {
            lo: -max_abs,
            hi: max_abs,
            counts,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// Two concentric spheres: every vertex of the outer lies r2 − r1
    /// outside the inner (up to the inner's chordal error), and vice versa.
    #[test]
    fn concentric_spheres_are_their_radius_difference_apart() {
        let inner = shapes::icosphere(1.0, 4);
        let outer = shapes::uv_sphere(1.1, 48, 24);
        let d = deviation(&inner, &outer).unwrap();
        assert_eq!(d.method, DeviationMethod::ClosestPoint);
        assert_eq!(d.unmatched, 0);
        // chordal error of the 4-times subdivided icosahedron < 2e-3
        for s in &d.signed {
            assert!((s - 0.1).abs() < 3e-3, "{s}");
        }
        let back = deviation(&outer, &inner).unwrap();
        for s in &back.signed {
            assert!((s + 0.1).abs() < 5e-3, "{s}");
        }
    }

    /// The same mesh moved along its normals: the displacement method
    /// gives back the normal offset exactly.
    #[test]
    fn normal_offset_is_the_displacement() {
        let m = shapes::icosphere(2.0, 2);
        let n = vertex_normals(&m);
        let moved: Vec<Vec3> = m
            .positions()
            .iter()
            .zip(&n)
            .enumerate()
            .map(|(i, (p, n))| *p + (if i % 2 == 0 { 0.01 } else { -0.02 }) * *n)
            .collect();
        let mut m2 = m.clone();
        m2.set_positions(moved).unwrap();
        let d = deviation(&m, &m2).unwrap();
        assert_eq!(d.method, DeviationMethod::Displacement);
        for (i, s) in d.signed.iter().enumerate() {
            let want = if i % 2 == 0 { 0.01 } else { -0.02 };
            assert!((s - want).abs() < 1e-12);
            assert!((d.distance[i] - want.abs()).abs() < 1e-12);
        }
        let st = deviation_stats(&d.signed, 10);
        assert!((st.max_abs - 0.02).abs() < 1e-12);
        assert!((st.min + 0.02).abs() < 1e-12 && (st.max - 0.01).abs() < 1e-12);
        assert_eq!(st.histogram.counts.iter().sum::<usize>(), m.vertex_count());
        // -0.02 in the first bin, 0.01 in bin 7 of 10 over [-0.02, 0.02]
        assert_eq!(st.histogram.counts[0], m.vertex_count() / 2);
        assert_eq!(
            st.histogram.counts[7],
            m.vertex_count() - m.vertex_count() / 2
        );
    }

    #[test]
    fn stats_have_closed_forms() {
        let st = deviation_stats(&[-3.0, 1.0, 1.0, 1.0, f64::NAN], 4);
        assert_eq!(st.count, 4);
        assert_eq!((st.min, st.max, st.max_abs), (-3.0, 1.0, 3.0));
        assert_eq!(st.mean, 0.0);
        assert_eq!(st.mean_abs, 1.5);
        assert!((st.rms - 3.0f64.sqrt()).abs() < 1e-15);
        assert_eq!(st.histogram.counts, vec![1, 0, 3, 0]);
        let empty = deviation_stats(&[], 3);
        assert_eq!(empty.count, 0);
        assert_eq!(empty.histogram.counts, vec![0, 0, 0]);
        let zero = deviation_stats(&[0.0, 0.0], 3);
        assert_eq!(zero.histogram.counts, vec![0, 2, 0]);
    }

    #[test]
    fn polygon_reference_is_refused() {
        let q = shapes::quad_grid(3, 3, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
        let t = shapes::plane(3);
        assert_eq!(deviation(&q, &t).unwrap_err(), DeviationError::NotTriangles);
    }
}
