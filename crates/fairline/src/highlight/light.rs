//! Light sources: the array of coplanar parallel linear lights of Yong et
//! al. §2.1–2.2 and the circular light of Nishiyama et al. §2, Eq. (2.1).

use super::HighlightError;
use crate::Vec3;
use crate::mesh::SurfaceMesh;
use crate::solve::symmetric_eigen3;
use glam::DMat3;
use serde::{Deserialize, Serialize};

/// Smallest |sin| of the angle between the light direction and the plane
/// normal (and between a circle axis and its helper vector) that is accepted.
const PARALLEL_TOLERANCE: f64 = 1e-9;

fn unit(v: Vec3, what: &str) -> Result<Vec3, HighlightError> {
    let len = v.length();
    if !(len > 0.0) || !len.is_finite() || !v.is_finite() {
        return Err(HighlightError::InvalidLight(format!(
            "{what} must be a finite non-zero vector, got {v}"
        )));
    }
    Ok(v / len)
}

/// Which way is "up" for the default lights of a part: the light plane's
/// normal Z (see [`LightArray::default_for_mesh`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// From the part: its principal axis of least extent.
    #[default]
    Auto,
    /// +x.
    X,
    /// +y.
    Y,
    /// +z.
    Z,
}

/// An array of coplanar, parallel, equally spaced linear light sources
/// (Yong et al. §2.1–2.2).
///
/// The lights lie in the plane through `plane_point` A0 with unit normal
/// `plane_normal` Z; they run along the unit `direction` H (orthogonal to Z)
/// and light m passes through A0 + m·s·(Z × H), where s is the `spacing`
/// (Yong et al. Eq. (2)). Lengths are in mesh units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "LightArrayJson", into = "LightArrayJson")]
pub struct LightArray {
    plane_point: Vec3,
    plane_normal: Vec3,
    direction: Vec3,
    spacing: f64,
}

/// The JSON form of DESIGN.md §5:
/// `{"plane_point":[..],"plane_normal":[..],"direction":[..],"spacing":s}`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightArrayJson {
    plane_point: [f64; 3],
    plane_normal: [f64; 3],
    direction: [f64; 3],
    spacing: f64,
}

impl TryFrom<LightArrayJson> for LightArray {
    type Error = HighlightError;
    fn try_from(j: LightArrayJson) -> Result<Self, HighlightError> {
        LightArray::new(
            Vec3::from(j.plane_point),
            Vec3::from(j.plane_normal),
            Vec3::from(j.direction),
            j.spacing,
        )
    }
}

impl From<LightArray> for LightArrayJson {
    fn from(l: LightArray) -> Self {
        LightArrayJson {
            plane_point: l.plane_point.to_array(),
            plane_normal: l.plane_normal.to_array(),
            direction: l.direction.to_array(),
            spacing: l.spacing,
        }
    }
}

impl LightArray {
    /// A light array with base point A0, plane normal Z (normalised),
    /// light direction H (its component orthogonal to Z, normalised) and
    /// spacing s > 0 (Yong et al. §2.2). Errors when a vector is zero or not
    /// finite, H is parallel to Z, or s is not a positive finite number.
    pub fn new(
        plane_point: Vec3,
        plane_normal: Vec3,
        direction: Vec3,
        spacing: f64,
    ) -> Result<Self, HighlightError> {
        if !plane_point.is_finite() {
            return Err(HighlightError::InvalidLight(format!(
                "plane point must be finite, got {plane_point}"
            )));
        }
        let z = unit(plane_normal, "plane normal")?;
        let h0 = unit(direction, "light direction")?;
        let h = h0 - h0.dot(z) * z;
        if !(h.length() > PARALLEL_TOLERANCE) {
            return Err(HighlightError::InvalidLight(
                "light direction is parallel to the plane normal".into(),
            ));
        }
        if !(spacing > 0.0) || !spacing.is_finite() {
            return Err(HighlightError::InvalidLight(format!(
                "spacing must be a positive finite number, got {spacing}"
            )));
        }
        Ok(LightArray {
            plane_point,
            plane_normal: z,
            direction: h.normalize(),
            spacing,
        })
    }

    /// A light array for a mesh with bounding box [`bbox_min`, `bbox_max`]
    /// seen from `view_dir` (the direction from the mesh toward the viewer;
    /// `None` means +z): the light plane has normal Z = `view_dir`, lies one
    /// bounding-box diagonal above the box centre along Z, light 0 passes
    /// over the centre, H is the coordinate axis least aligned with Z (made
    /// orthogonal to Z) and the spacing puts about 20 lights across the
    /// box's extent along Z × H. A degenerate box gives spacing 1.
    pub fn default_for(bbox_min: Vec3, bbox_max: Vec3, view_dir: Option<Vec3>) -> Self {
        let z = view_dir
            .filter(|v| v.is_finite())
            .and_then(|v| v.try_normalize())
            .unwrap_or(Vec3::Z);
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        let mut h = Vec3::X;
        let mut best = f64::INFINITY;
        for a in axes {
            let c = a.dot(z).abs();
            if c < best - 1e-12 {
                best = c;
                h = a;
            }
        }
        let h = (h - h.dot(z) * z).normalize();
        let (lo, hi) = if bbox_min.is_finite() && bbox_max.is_finite() {
            (bbox_min.min(bbox_max), bbox_min.max(bbox_max))
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let centre = 0.5 * (lo + hi);
        let ext = hi - lo;
        let diag = ext.length();
        let across = z.cross(h);
        let width = ext.dot(across.abs());
        let spacing = if width > 0.0 && width.is_finite() {
            width / 20.0
        } else if diag > 0.0 && diag.is_finite() {
            diag / 20.0
        } else {
            1.0
        };
        let lift = if diag > 0.0 && diag.is_finite() {
            diag
        } else {
            1.0
        };
        LightArray {
            plane_point: centre + lift * z,
            plane_normal: z,
            direction: h,
            spacing,
        }
    }

    /// The default light array for a part, chosen from the part itself:
    ///
    /// - the plane normal Z is the `up` axis (+x, +y or +z), or with
    ///   [`UpAxis::Auto`] the principal axis of least extent of the vertex
    ///   cloud (the normal of a panel, the side of an elongated part), turned
    ///   to the side that the larger share of the surface area faces (for a
    ///   closed part, the side whose largest coordinate component is
    ///   positive);
    /// - the light direction H is the principal axis of largest extent made
    ///   orthogonal to Z, so the lights run along the part and the lines
    ///   cross its shorter side;
    /// - about 20 lights across the part's extent along Z × H, light 0 over
    ///   the bounding-box centre, the plane one bounding-box diagonal above
    ///   the centre along Z.
    ///
    /// This spacing is the scale of detection (`detect_irregularities`); for
    /// drawing, [`Self::readable_for_mesh`] thins the lines on round parts.
    ///
    /// `None` for a mesh without finite vertices.
    pub fn default_for_mesh(mesh: &SurfaceMesh, up: UpAxis) -> Option<Self> {
        let p: Vec<Vec3> = mesh
            .positions()
            .iter()
            .copied()
            .filter(|q| q.is_finite())
            .collect();
        if p.is_empty() {
            return None;
        }
        let (lo, hi) = crate::mesh::bounding_box(&p)?;
        let centre = 0.5 * (lo + hi);
        let mean = p.iter().copied().sum::<Vec3>() / p.len() as f64;
        let mut cov = DMat3::ZERO;
        for q in &p {
            let d = *q - mean;
            cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (values, vectors) = symmetric_eigen3(cov / p.len() as f64);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
        let least = vectors.col(order[0]);
        let largest = vectors.col(order[2]);
        let z = match up {
            UpAxis::X => Vec3::X,
            UpAxis::Y => Vec3::Y,
            UpAxis::Z => Vec3::Z,
            UpAxis::Auto => {
                let z = least.try_normalize().unwrap_or(Vec3::Z);
                // face areas once (they were computed twice: a whole pass
                // over the faces at 450k vertices); same sums, same bits
                let areas = crate::geom::face_areas(mesh);
                let area_normal: Vec3 = crate::geom::face_normals(mesh)
                    .iter()
                    .zip(&areas)
                    .map(|(n, a)| *n * *a)
                    .sum();
                let total: f64 = areas.iter().sum();
                let facing = area_normal.dot(z);
                let sign = if total > 0.0 && facing.abs() > 1e-3 * total {
                    facing.signum()
                } else {
                    let a = z.abs();
                    let k = if a.x >= a.y && a.x >= a.z {
                        z.x
                    } else if a.y >= a.z {
                        z.y
                    } else {
                        z.z
                    };
                    if k < 0.0 { -1.0 } else { 1.0 }
                };
                sign * z
            }
        };
        let mut h = largest - largest.dot(z) * z;
        if !(h.length() > 0.1) {
            let mid = vectors.col(order[1]);
            h = mid - mid.dot(z) * z;
        }
        let h = h
            .try_normalize()
            .unwrap_or_else(|| z.any_orthonormal_vector());
        // a deterministic sign for H: its largest component positive
        let a = h.abs();
        let k = if a.x >= a.y && a.x >= a.z {
            h.x
        } else if a.y >= a.z {
            h.y
        } else {
            h.z
        };
        let h = if k < 0.0 { -h } else { h };
        let across = z.cross(h);
        let (mut amin, mut amax) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in &p {
            let t = q.dot(across);
            amin = amin.min(t);
            amax = amax.max(t);
        }
        let width = amax - amin;
        let diag = (hi - lo).length();
        let spacing = if width > 0.0 && width.is_finite() {
            width / 20.0
        } else if diag > 0.0 && diag.is_finite() {
            diag / 20.0
        } else {
            1.0
        };
        let lift = if diag > 0.0 && diag.is_finite() {
            diag
        } else {
            1.0
        };
        Some(LightArray {
            plane_point: centre + lift * z,
            plane_normal: z,
            direction: h,
            spacing,
        })
    }

    /// The default lights for reading the lines on a part:
    /// [`Self::default_for_mesh`] with its spacing multiplied by
    /// [`Self::readable_multiple`].
    pub fn readable_for_mesh(mesh: &SurfaceMesh, up: UpAxis) -> Option<Self> {
        let base = Self::default_for_mesh(mesh, up)?;
        let k = base.readable_multiple(mesh);
        Some(LightArray {
            spacing: base.spacing * f64::from(k),
            ..base
        })
    }

    /// A copy with a different spacing (> 0, finite), e.g. for a denser array.
    pub fn with_spacing(self, spacing: f64) -> Result<Self, HighlightError> {
        LightArray::new(self.plane_point, self.plane_normal, self.direction, spacing)
    }

    /// The base point A0 (on light 0).
    pub fn plane_point(&self) -> Vec3 {
        self.plane_point
    }
    /// The unit plane normal Z.
    pub fn plane_normal(&self) -> Vec3 {
        self.plane_normal
    }
    /// The unit light direction H (orthogonal to Z).
    pub fn direction(&self) -> Vec3 {
        self.direction
    }
    /// The spacing s between adjacent lights (mesh units).
    pub fn spacing(&self) -> f64 {
        self.spacing
    }
    /// The unit vector Z × H along which the light index grows (Yong et al.
    /// §2.2, the property after Eq. (2)).
    pub fn across(&self) -> Vec3 {
        self.plane_normal.cross(self.direction)
    }
    /// A point of light m: A0 + m·s·(Z × H).
    pub fn light_point(&self, m: i64) -> Vec3 {
        self.plane_point + (m as f64 * self.spacing) * self.across()
    }

    /// Highlight distance value of a point P with unit normal N, Yong et al.
    /// Eq. (1) with the sign of DESIGN.md §3:
    /// d_P = ((P − A0) × N)·H / (Z·N), which equals (X_P − A0)·(Z × H) for
    /// the intersection X_P of the normal line P + tN with the light plane.
    /// `None` when |Z·N| < `min_cos` (the normal line is nearly parallel to
    /// the plane) or the result is not finite. Units: mesh units.
    #[inline]
    pub fn highlight_distance(&self, p: Vec3, n: Vec3, min_cos: f64) -> Option<f64> {
        let zn = self.plane_normal.dot(n);
        if !(zn.abs() >= min_cos) || zn == 0.0 {
            return None;
        }
        let d = (p - self.plane_point).cross(n).dot(self.direction) / zn;
        d.is_finite().then_some(d)
    }
}

/// Highlight distance d_P (Eq. (1)) and branch (sign of Z·N, 0 where
/// |Z·N| is below the default `min_normal_cos`) of every vertex, with the
/// area-weighted vertex normals of Yong et al. Eq. (3).
#[cfg(test)]
pub(crate) fn vertex_distances(mesh: &SurfaceMesh, light: &LightArray) -> (Vec<f64>, Vec<i8>) {
    let min_cos = super::HighlightOptions::default().min_normal_cos;
    crate::geom::vertex_normals(mesh)
        .iter()
        .zip(mesh.positions())
        .map(|(&n, &p)| vertex_distance(light, p, n, min_cos))
        .unzip()
}

/// Distance value and branch of one vertex.
#[inline]
pub(crate) fn vertex_distance(light: &LightArray, p: Vec3, n: Vec3, min_cos: f64) -> (f64, i8) {
    match light.highlight_distance(p, n, min_cos) {
        Some(d) => (
            d,
            if light.plane_normal().dot(n) > 0.0 {
                1
            } else {
                -1
            },
        ),
        None => (0.0, 0),
    }
}

/// A circular light source L(θ) = A + R(cos θ n + sin θ b), Nishiyama et
/// al. Eq. (2.1), with unit axis t = n × b. Lengths in surface units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircularLight {
    center: Vec3,
    axis: Vec3,
    n: Vec3,
    b: Vec3,
    radius: f64,
}

/// Closest approach of a surface normal line to a circular light
/// (Nishiyama et al. Eq. (2.5)–(2.18)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleApproach {
    /// Signed distance d_s of Eq. (2.18) (surface units).
    pub signed_distance: f64,
    /// Parameter τ of the nearest point Q + τN on the normal line, Eq. (2.3).
    pub tau: f64,
    /// Angle θ of the nearest point of the circle, Eq. (2.1), in (−π, π].
    pub theta: f64,
}

impl CircularLight {
    /// A circle of centre A, axis t (normalised) and radius R > 0. The
    /// in-plane frame (n, b) with t = n × b is chosen from the coordinate
    /// axis least aligned with t, so it is fixed for a given axis.
    pub fn new(center: Vec3, axis: Vec3, radius: f64) -> Result<Self, HighlightError> {
        if !center.is_finite() {
            return Err(HighlightError::InvalidLight(format!(
                "circle centre must be finite, got {center}"
            )));
        }
        let t = unit(axis, "circle axis")?;
        if !(radius > 0.0) || !radius.is_finite() {
            return Err(HighlightError::InvalidLight(format!(
                "circle radius must be a positive finite number, got {radius}"
            )));
        }
        let mut helper = Vec3::X;
        let mut best = f64::INFINITY;
        for a in [Vec3::X, Vec3::Y, Vec3::Z] {
            let c = a.dot(t).abs();
            if c < best - 1e-12 {
                best = c;
                helper = a;
            }
        }
        let n = (helper - helper.dot(t) * t).normalize();
        let b = t.cross(n);
        Ok(CircularLight {
            center,
            axis: t,
            n,
            b,
            radius,
        })
    }
    /// Centre A.
    pub fn center(&self) -> Vec3 {
        self.center
    }
    /// Unit axis t = n × b.
    pub fn axis(&self) -> Vec3 {
        self.axis
    }
    /// Radius R.
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// The in-plane frame (n, b) of Eq. (2.1).
    pub fn frame(&self) -> (Vec3, Vec3) {
        (self.n, self.b)
    }
    /// The point L(θ) of Eq. (2.1).
    pub fn point(&self, theta: f64) -> Vec3 {
        self.center + self.radius * (theta.cos() * self.n + theta.sin() * self.b)
    }
}

/// A family of concentric circular lights sharing centre and axis, in the
/// JSON form of DESIGN.md §5: `{"center":[..],"axis":[..],"radii":[..]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircularLights {
    /// Common centre A.
    pub center: [f64; 3],
    /// Common axis t (need not be unit).
    pub axis: [f64; 3],
    /// Radii R (each > 0).
    pub radii: Vec<f64>,
}

impl CircularLights {
    /// The circular lights, one per radius (Nishiyama et al. Eq. (2.1));
    /// errors on a zero axis or a non-positive radius.
    pub fn lights(&self) -> Result<Vec<CircularLight>, HighlightError> {
        self.radii
            .iter()
            .map(|&r| CircularLight::new(Vec3::from(self.center), Vec3::from(self.axis), r))
            .collect()
    }
}
