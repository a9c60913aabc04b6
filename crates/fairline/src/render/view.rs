//! The one camera rule of a part's pictures: which way is up and from where
//! the part is seen, chosen from the part itself, so that every picture of
//! one part (a rendering, highlight lines, a curvature map, a deviation map,
//! the workbench's first view) shows the same side, upright.
//!
//! The rule ([`part_view`]):
//!
//! 1. **Up.** A part with a flat base stands on it: the largest set of
//!    near-coplanar faces whose normals agree (within [`BASE_ANGLE_DEG`])
//!    and that lies on a supporting plane of the part (no vertex beyond it)
//!    is the bottom when it holds at least [`BASE_MIN_SHARE`] of the area;
//!    up is the opposite of its normal. A flat sheet (all of it within
//!    [`CONTACT_SLAB`] of the diagonal of that plane) is a base with nothing
//!    on it: its face is seen, up along its normal. Otherwise the part stands on the
//!    coordinate axis it is modelled along: +z (CAD parts) or +y (scans and
//!    figures), whichever the part stands on more firmly — the one whose
//!    lowest slab (the vertices within [`CONTACT_SLAB`] of the diagonal of
//!    the lowest) spans the larger share of the part's footprint (the area
//!    of the convex hull of the slab over the area of the part's extent
//!    across the axis). Ties (within [`TIE`]) go to +z.
//! 2. **Front.** The horizontal principal axis of least spread of the
//!    area-weighted surface (the part's thin direction across its length:
//!    looking along it shows the part's long side), signed toward the
//!    modelling convention's front (−y for a z-up part, +z otherwise) and
//!    snapped to a coordinate axis within [`SNAP_DEG`]. A part whose
//!    horizontal spread is round (ratio below [`ROUND_RATIO`]) keeps the
//!    convention's front.
//! 3. **View.** From the front turned [`AZIMUTH_DEG`] toward the right
//!    (up × front) and raised [`ELEVATION_DEG`] above the horizontal: a front
//!    three-quarter view from a little above, the part upright. A flat part
//!    (its height along up under [`FLAT_RATIO`] of its width: a panel, a
//!    sheet) is seen from [`ELEVATION_FLAT_DEG`] above, so that its face is
//!    not foreshortened to a sliver.
//!
//! Everything is computed from finite vertices of triangles with in-range
//! indices and positive area; a part with none gets the z-up view. The
//! result is deterministic (a fixed order of summation, ties broken by
//! index).

use crate::Vec3;

/// Largest angle (degrees) between the normal of a face of a flat base and
/// the base's normal.
pub const BASE_ANGLE_DEG: f64 = 5.0;
/// Smallest share of the part's area a flat base must hold.
pub const BASE_MIN_SHARE: f64 = 0.05;
/// Height of the lowest slab a part stands on, as a fraction of its
/// bounding-box diagonal (the flat base's coplanarity tolerance too).
pub const CONTACT_SLAB: f64 = 0.02;
/// Relative difference of two standing scores below which they tie.
pub const TIE: f64 = 0.1;
/// Angle (degrees) within which the front is snapped to a coordinate axis.
pub const SNAP_DEG: f64 = 12.0;
/// Ratio of the horizontal principal spreads below which a part counts as
/// round across its up axis.
pub const ROUND_RATIO: f64 = 1.15;
/// Turn of the view from the front toward the right, in degrees.
pub const AZIMUTH_DEG: f64 = 35.0;
/// Height of the view above the horizontal, in degrees.
pub const ELEVATION_DEG: f64 = 25.0;
/// Height of the view of a flat part above the horizontal, in degrees.
pub const ELEVATION_FLAT_DEG: f64 = 55.0;
/// Height over width below which a part counts as flat.
pub const FLAT_RATIO: f64 = 0.2;

/// Why a [`PartView`] has its up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum UpReason {
    /// The part stands on a flat base.
    FlatBase,
    /// The part is a flat sheet, seen on the side its normals face.
    FlatSheet,
    /// The part stands more firmly on +z than on +y (modelled z-up).
    ModelledZUp,
    /// The part stands more firmly on +y than on +z (modelled y-up).
    ModelledYUp,
    /// Nothing to measure (no triangle with positive area): +z.
    Empty,
}

/// The camera of a part's pictures ([`part_view`]). Serialised with the
/// vectors as `[x, y, z]` arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartView {
    /// Viewing direction, unit, from the eye toward the part.
    pub view_dir: Vec3,
    /// Unit up axis of the part (the top of the picture).
    pub up: Vec3,
    /// Unit horizontal front axis (from the part toward the viewer of a
    /// front view); the view is this turned and raised.
    pub front: Vec3,
    /// Why `up` is up.
    pub reason: UpReason,
    /// Share of the area in the flat base (0 without one).
    pub base_share: f64,
    /// Standing scores on +z and +y (share of the footprint the lowest
    /// slab spans).
    pub standing: [f64; 2],
}

impl serde::Serialize for PartView {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(serde::Serialize)]
        struct Plain {
            view_dir: [f64; 3],
            up: [f64; 3],
            front: [f64; 3],
            reason: UpReason,
            base_share: f64,
            standing: [f64; 2],
        }
        Plain {
            view_dir: self.view_dir.to_array(),
            up: self.up.to_array(),
            front: self.front.to_array(),
            reason: self.reason,
            base_share: self.base_share,
            standing: self.standing,
        }
        .serialize(s)
    }
}

impl Default for PartView {
    fn default() -> Self {
        let up = Vec3::Z;
        let front = Vec3::NEG_Y;
        PartView {
            view_dir: view_from(front, up, ELEVATION_DEG),
            up,
            front,
            reason: UpReason::Empty,
            base_share: 0.0,
            standing: [0.0, 0.0],
        }
    }
}

/// The camera rule of the module documentation for the triangles
/// `triangles` (vertex indices into `positions`).
pub fn part_view(positions: &[Vec3], triangles: &[[u32; 3]]) -> PartView {
    let faces = valid_faces(positions, triangles);
    let area: f64 = faces.iter().map(|f| f.area).sum();
    let used = used_vertices(positions, &faces);
    let Some((lo, hi)) = bounds(&used) else {
        return PartView::default();
    };
    let diag = (hi - lo).length();
    if faces.is_empty() || !(area > 0.0) || !(diag > 0.0) || !diag.is_finite() {
        return PartView::default();
    }
    let standing = [
        standing_score(&used, Vec3::Z, diag),
        standing_score(&used, Vec3::Y, diag),
    ];
    let (modelled_up, modelled_reason) = if standing[1] > standing[0] * (1.0 + TIE) {
        (Vec3::Y, UpReason::ModelledYUp)
    } else {
        (Vec3::Z, UpReason::ModelledZUp)
    };
    let base = flat_base(&faces, &used, area, diag, modelled_up);
    let (up, reason, base_share) = match base {
        Some((n, share)) if share >= BASE_MIN_SHARE => {
            if extent(&used, n) <= CONTACT_SLAB * diag {
                (snap_up(n), UpReason::FlatSheet, share)
            } else {
                (snap_up(-n), UpReason::FlatBase, share)
            }
        }
        Some((_, share)) => (modelled_up, modelled_reason, share),
        None => (modelled_up, modelled_reason, 0.0),
    };
    let front = front_axis(&faces, up);
    let height = extent(&used, up);
    let width = (diag * diag - height * height).max(0.0).sqrt();
    let elevation = if height < FLAT_RATIO * width {
        ELEVATION_FLAT_DEG
    } else {
        ELEVATION_DEG
    };
    PartView {
        view_dir: view_from(front, up, elevation),
        up,
        front,
        reason,
        base_share,
        standing,
    }
}

/// The spread of `points` along `d`.
fn extent(points: &[Vec3], d: Vec3) -> f64 {
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p.dot(d)), hi.max(p.dot(d)))
    });
    (hi - lo).max(0.0)
}

/// The viewing direction (eye toward part) of the front `front` turned
/// [`AZIMUTH_DEG`] toward up × front and raised `elevation_deg`.
fn view_from(front: Vec3, up: Vec3, elevation_deg: f64) -> Vec3 {
    let right = up.cross(front).normalize_or_zero();
    let (sa, ca) = AZIMUTH_DEG.to_radians().sin_cos();
    let (se, ce) = elevation_deg.to_radians().sin_cos();
    let eye = ce * (ca * front + sa * right) + se * up;
    (-eye).try_normalize().unwrap_or(Vec3::NEG_Z)
}

/// A triangle of positive area with finite corners.
struct Face {
    corners: [Vec3; 3],
    idx: [u32; 3],
    normal: Vec3,
    area: f64,
}

fn valid_faces(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Face> {
    triangles
        .iter()
        .filter_map(|t| {
            let c = [
                *positions.get(t[0] as usize)?,
                *positions.get(t[1] as usize)?,
                *positions.get(t[2] as usize)?,
            ];
            if !c.iter().all(|p| p.is_finite()) {
                return None;
            }
            let n = (c[1] - c[0]).cross(c[2] - c[0]);
            let a = 0.5 * n.length();
            (a > 0.0 && a.is_finite()).then(|| Face {
                corners: c,
                idx: *t,
                normal: n / (2.0 * a),
                area: a,
            })
        })
        .collect()
}

/// The vertices of `faces`, each once, in index order.
fn used_vertices(positions: &[Vec3], faces: &[Face]) -> Vec<Vec3> {
    let mut seen = vec![false; positions.len()];
    for f in faces {
        for &i in &f.idx {
            seen[i as usize] = true;
        }
    }
    positions
        .iter()
        .zip(&seen)
        .filter_map(|(p, &s)| s.then_some(*p))
        .collect()
}

fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// The flat base candidate of `faces`: the unit outward normal and area
/// share of the largest set of faces lying on a supporting plane of the
/// part whose normals agree within [`BASE_ANGLE_DEG`]; among sets within
/// [`TIE`] of the largest, the one facing most nearly down `prefer_up`.
fn flat_base(
    faces: &[Face],
    points: &[Vec3],
    area: f64,
    diag: f64,
    prefer_up: Vec3,
) -> Option<(Vec3, f64)> {
    // candidate normals: the heaviest bins of normals quantised to 1/8
    let mut bins: std::collections::BTreeMap<[i32; 3], (f64, Vec3)> = Default::default();
    for f in faces {
        let key = (f.normal * 8.0).round().as_ivec3().to_array();
        let e = bins.entry(key).or_insert((0.0, Vec3::ZERO));
        e.0 += f.area;
        e.1 += f.area * f.normal;
    }
    let mut heavy: Vec<([i32; 3], f64, Vec3)> =
        bins.into_iter().map(|(k, (a, n))| (k, a, n)).collect();
    heavy.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let cos = BASE_ANGLE_DEG.to_radians().cos();
    let tol = CONTACT_SLAB * diag;
    let mut sets: Vec<(Vec3, f64)> = Vec::new();
    for (_, a, n) in heavy.into_iter().take(12) {
        if a < 0.5 * BASE_MIN_SHARE * area {
            break;
        }
        let Some(n) = n.try_normalize() else { continue };
        let support = points.iter().map(|p| p.dot(n)).fold(f64::MIN, f64::max);
        let on_plane = |f: &Face| {
            f.normal.dot(n) >= cos && f.corners.iter().all(|p| p.dot(n) >= support - tol)
        };
        let (mut s, mut sn) = (0.0, Vec3::ZERO);
        for f in faces.iter().filter(|f| on_plane(f)) {
            s += f.area;
            sn += f.area * f.normal;
        }
        if let Some(sn) = sn.try_normalize() {
            sets.push((sn, s / area));
        }
    }
    let largest = sets.iter().map(|s| s.1).fold(0.0, f64::max);
    sets.into_iter()
        .filter(|s| s.1 >= largest * (1.0 - TIE))
        .min_by(|a, b| a.0.dot(prefer_up).total_cmp(&b.0.dot(prefer_up)))
}

/// How firmly the part stands on `up` (a coordinate axis): the area of
/// the convex hull of the vertices within [`CONTACT_SLAB`] of the diagonal
/// of the lowest, over the area of the part's extent across `up`.
fn standing_score(points: &[Vec3], up: Vec3, diag: f64) -> f64 {
    let (a, b) = if up == Vec3::Z {
        (Vec3::X, Vec3::Y)
    } else {
        (Vec3::Z, Vec3::X)
    };
    let low = points.iter().map(|p| p.dot(up)).fold(f64::MAX, f64::min);
    let slab: Vec<[f64; 2]> = points
        .iter()
        .filter(|p| p.dot(up) <= low + CONTACT_SLAB * diag)
        .map(|p| [p.dot(a), p.dot(b)])
        .collect();
    let footprint = extent(points, a) * extent(points, b);
    if footprint > 0.0 && footprint.is_finite() {
        (hull_area(slab) / footprint).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Area of the convex hull of 2-D points (Andrew's monotone chain).
fn hull_area(mut p: Vec<[f64; 2]>) -> f64 {
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return 0.0;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    let n = hull.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    0.5 * twice.abs()
}

/// The convention's front for `up`: −y for a part standing mostly along z,
/// +z otherwise, made horizontal.
fn convention_front(up: Vec3) -> Vec3 {
    let a = up.abs();
    let f = if a.z >= a.x && a.z >= a.y {
        Vec3::NEG_Y
    } else {
        Vec3::Z
    };
    (f - f.dot(up) * up)
        .try_normalize()
        .unwrap_or_else(|| up.any_orthonormal_vector())
}

/// The front axis of the module documentation: the horizontal principal
/// axis of least spread of the area-weighted surface (second moments of
/// the triangles about their area centroid), signed toward and snapped
/// like the convention's front.
fn front_axis(faces: &[Face], up: Vec3) -> Vec3 {
    let conv = convention_front(up);
    let side = up.cross(conv).normalize_or_zero();
    // area centroid, then the 2x2 second moment in the (conv, side) plane
    let area: f64 = faces.iter().map(|f| f.area).sum();
    let centroid = faces
        .iter()
        .map(|f| f.area * (f.corners[0] + f.corners[1] + f.corners[2]) / 3.0)
        .sum::<Vec3>()
        / area;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for f in faces {
        // exact second moment of a triangle: A/12 (9 m mᵀ + Σ cᵢ cᵢᵀ)
        let q = f.corners.map(|c| c - centroid);
        let m = (q[0] + q[1] + q[2]) / 3.0;
        let mut acc = |x: f64, y: f64, w: f64| {
            sxx += w * x * x;
            sxy += w * x * y;
            syy += w * y * y;
        };
        acc(m.dot(conv), m.dot(side), 9.0 * f.area / 12.0);
        for c in q {
            acc(c.dot(conv), c.dot(side), f.area / 12.0);
        }
    }
    // eigenvalues of [[sxx, sxy], [sxy, syy]]
    let mean = 0.5 * (sxx + syy);
    let dev = (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
    let (big, small) = (mean + dev, mean - dev);
    if !(small > 0.0) || !(big / small >= ROUND_RATIO) || !big.is_finite() {
        return conv;
    }
    // eigenvector of the smaller eigenvalue: the longer of the two rows
    // of the adjugate (the other may vanish)
    let (a, b) = ((sxy, small - sxx), (small - syy, sxy));
    let (x, y) = if a.0.hypot(a.1) >= b.0.hypot(b.1) {
        a
    } else {
        b
    };
    let Some(mut f) = (x * conv + y * side).try_normalize() else {
        return conv;
    };
    if f.dot(conv) < 0.0 || (f.dot(conv) == 0.0 && f.dot(side) < 0.0) {
        f = -f;
    }
    snap(f, up)
}

/// `up` replaced by the coordinate axis within [`BASE_ANGLE_DEG`] of it,
/// if any (a base modelled on a coordinate plane, its normal averaged).
fn snap_up(up: Vec3) -> Vec3 {
    let cos = BASE_ANGLE_DEG.to_radians().cos();
    [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ]
    .into_iter()
    .find(|a| a.dot(up) >= cos)
    .unwrap_or(up)
}

/// `f` replaced by the horizontal coordinate axis within [`SNAP_DEG`] of
/// it, if any.
fn snap(f: Vec3, up: Vec3) -> Vec3 {
    let cos = SNAP_DEG.to_radians().cos();
    for axis in [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ] {
        if f.dot(axis) >= cos
            && axis.dot(up).abs() < 0.05
            && let Some(a) = (axis - axis.dot(up) * up).try_normalize()
        {
            return a;
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box `lo..hi` as 12 triangles, outward normals.
    fn cuboid(lo: Vec3, hi: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    /// A UV sphere of `n` rings centred at `c` with radii `r`.
    fn ellipsoid(c: Vec3, r: Vec3, n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for i in 0..=n {
            let th = std::f64::consts::PI * f64::from(i) / f64::from(n);
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * f64::from(j) / f64::from(n);
                p.push(c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        let mut t = Vec::new();
        let w = 2 * n;
        for i in 0..n {
            for j in 0..w {
                let (a, b) = (i * w + j, i * w + (j + 1) % w);
                let (c2, d) = (a + w, b + w);
                t.push([a, c2, b]);
                t.push([b, c2, d]);
            }
        }
        (p, t)
    }

    #[test]
    fn a_slab_stands_on_its_largest_flat_face() {
        // thin in x: the two large faces face ±x; the preferred bottom faces
        // down the modelled up, and a flat base wins over the convention
        let (p, t) = cuboid(Vec3::ZERO, Vec3::new(0.2, 3.0, 2.0));
        let v = part_view(&p, &t);
        assert_eq!(v.reason, UpReason::FlatBase);
        assert!(v.up.x.abs() > 0.999, "{v:?}");
        assert!(v.base_share > 0.4 && v.base_share < 0.5);
        // a plate lying flat stands on its underside: up is +z
        let (p, t) = cuboid(Vec3::ZERO, Vec3::new(3.0, 2.0, 0.2));
        let v = part_view(&p, &t);
        assert!(v.up.dot(Vec3::Z) > 0.999, "{v:?}");
    }

    #[test]
    fn the_view_is_a_front_three_quarter_from_above() {
        let (p, t) = cuboid(Vec3::ZERO, Vec3::new(3.0, 2.0, 1.2));
        let v = part_view(&p, &t);
        let eye = -v.view_dir;
        assert!((eye.dot(v.up) - ELEVATION_DEG.to_radians().sin()).abs() < 1e-12);
        // thinnest horizontal spread is y: seen from −y, turned toward +x
        assert_eq!(v.front, Vec3::NEG_Y);
        assert!(eye.x > 0.3 && eye.y < -0.5, "{eye}");
        assert!((v.view_dir.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_flat_sheet_shows_its_face_from_high_above() {
        // one-sided square in the xz plane, normals +y
        let p = vec![
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::X,
        ];
        let t = vec![[0, 1, 2], [0, 2, 3]];
        let v = part_view(&p, &t);
        assert_eq!(v.reason, UpReason::FlatSheet);
        assert_eq!(v.up, Vec3::Y);
        let eye = -v.view_dir;
        assert!((eye.dot(v.up) - ELEVATION_FLAT_DEG.to_radians().sin()).abs() < 1e-12);
    }

    #[test]
    fn a_figure_with_no_flat_base_stands_on_the_axis_it_rests_on() {
        // an egg lying along x with a wide, flattish bottom at low y: the
        // ellipsoid with its short axis along y stands on y
        let (p, t) = ellipsoid(Vec3::ZERO, Vec3::new(2.0, 0.6, 1.0), 24);
        let v = part_view(&p, &t);
        assert_ne!(v.reason, UpReason::FlatBase);
        assert!(v.standing.iter().all(|s| s.is_finite()));
        assert!(v.up == Vec3::Y || v.up == Vec3::Z);
        // the same egg turned to have its short axis along z stands on z
        let q: Vec<Vec3> = p.iter().map(|a| Vec3::new(a.x, a.z, a.y)).collect();
        let w = part_view(&q, &t);
        assert!(w.standing[0] > 0.0);
        assert_ne!(v.up, w.up);
    }

    #[test]
    fn deterministic_and_guarded() {
        let (p, t) = ellipsoid(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 1.3, 0.7), 16);
        assert_eq!(part_view(&p, &t), part_view(&p, &t));
        let d = part_view(&[], &[]);
        assert_eq!(d.reason, UpReason::Empty);
        assert!(d.view_dir.is_finite());
        let nan = [Vec3::splat(f64::NAN), Vec3::ONE, Vec3::X];
        let v = part_view(&nan, &[[0, 1, 2], [0, 1, 9]]);
        assert_eq!(v.reason, UpReason::Empty);
        let flat = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let v = part_view(&flat, &[[0, 1, 2], [1, 3, 2]]);
        assert!(v.view_dir.is_finite() && v.up.is_finite() && v.front.is_finite());
        assert!((v.view_dir.length() - 1.0).abs() < 1e-12);
    }
}
