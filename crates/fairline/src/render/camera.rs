//! Pinhole (perspective) and parallel (orthographic) cameras that frame a bounding box.

use crate::Vec3;

/// Vertical field of view used by [`Camera::framing`], in degrees.
pub const DEFAULT_FOV_Y_DEG: f64 = 30.0;

/// Fraction of the half-width/height left free around a framed object.
pub(crate) const MARGIN: f64 = 0.06;

/// How a [`Camera`] projects onto the image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole perspective with vertical field of view `fov_y_deg` (degrees).
    Perspective {
        /// Vertical field of view in degrees (0 < fov < 180).
        fov_y_deg: f64,
    },
    /// Parallel projection showing `half_height` world units above and below
    /// the view axis.
    Orthographic {
        /// Half the visible height in world units.
        half_height: f64,
    },
}

/// A camera: position, orthonormal frame and projection.
///
/// `forward` is the viewing direction, `right × up`-handedness is
/// `right = forward × up`, and `up` points to the top of the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (for orthographic cameras: a point behind the object on the view axis).
    pub eye: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector to the right of the image.
    pub right: Vec3,
    /// Unit vector to the top of the image.
    pub up: Vec3,
    /// Projection model.
    pub projection: Projection,
    /// Image width / height.
    pub aspect: f64,
    /// Perspective only: points closer than this (along `forward`) are not drawn.
    pub near: f64,
}

/// An orthonormal frame (forward, right, up) for looking along `view_dir`
/// with `up_hint` towards the top. A zero / non-finite `view_dir` becomes
/// −Z; an `up_hint` parallel to the view (or zero) is replaced by the
/// coordinate axis least aligned with the view.
pub fn view_frame(view_dir: Vec3, up_hint: Vec3) -> (Vec3, Vec3, Vec3) {
    let f = view_dir.try_normalize().unwrap_or(Vec3::NEG_Z);
    let hint = up_hint.try_normalize().unwrap_or(Vec3::Z);
    let mut r = f.cross(hint);
    if r.length() < 1e-6 || !r.is_finite() {
        let a = f.abs();
        let axis = if a.z <= a.x && a.z <= a.y {
            Vec3::Z
        } else if a.y <= a.x {
            Vec3::Y
        } else {
            Vec3::X
        };
        r = f.cross(axis);
    }
    let r = r.normalize();
    let u = r.cross(f).normalize();
    (f, r, u)
}

fn corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Sanitises a bounding box: non-finite or inverted boxes become the unit box.
fn clean_box(bbox_min: Vec3, bbox_max: Vec3) -> (Vec3, Vec3) {
    if bbox_min.is_finite() && bbox_max.is_finite() && bbox_min.cmple(bbox_max).all() {
        (bbox_min, bbox_max)
    } else {
        (Vec3::splat(-1.0), Vec3::splat(1.0))
    }
}

impl Camera {
    /// A perspective camera (vertical field of view [`DEFAULT_FOV_Y_DEG`])
    /// looking along `view_dir` with `up_hint` towards the top of an image of
    /// width/height `aspect`, aimed at the centre of the box
    /// `bbox_min..bbox_max` (which lands at the image centre) and placed as
    /// close as possible with the whole box visible inside a small margin.
    ///
    /// Handles `view_dir` parallel to `up_hint` (another up is chosen), flat
    /// or point-like boxes (a minimum extent is assumed) and non-finite input
    /// (the unit box).
    pub fn framing(
        bbox_min: Vec3,
        bbox_max: Vec3,
        view_dir: Vec3,
        up_hint: Vec3,
        aspect: f64,
    ) -> Camera {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (lo, hi) = clean_box(bbox_min, bbox_max);
        let (f, r, u) = view_frame(view_dir, up_hint);
        let radius = {
            let d = 0.5 * (hi - lo).length();
            if d > 0.0 && d.is_finite() { d } else { 1.0 }
        };
        let ty = (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).tan() * (1.0 - MARGIN);
        let tx = ty * aspect;
        let cs = corners(lo, hi);
        // The box centre is put at the image centre; the distance is the
        // smallest at which every corner fits (and lies in front of the eye).
        let c = 0.5 * (lo + hi);
        let dist = cs
            .iter()
            .map(|&p| {
                let v = p - c;
                let (x, y, z) = (v.dot(r), v.dot(u), v.dot(f));
                (x.abs() / tx - z)
                    .max(y.abs() / ty - z)
                    .max(0.05 * radius - z)
            })
            .fold(1e-3 * radius, f64::max);
        let min_depth = cs
            .iter()
            .map(|&p| (p - c).dot(f) + dist)
            .fold(f64::MAX, f64::min);
        Camera {
            eye: c - f * dist,
            forward: f,
            right: r,
            up: u,
            projection: Projection::Perspective {
                fov_y_deg: DEFAULT_FOV_Y_DEG,
            },
            aspect,
            near: (0.5 * min_depth).max(1e-6 * radius),
        }
    }

    /// An orthographic camera framing the box like [`Camera::framing`].
    pub fn framing_orthographic(
        bbox_min: Vec3,
        bbox_max: Vec3,
        view_dir: Vec3,
        up_hint: Vec3,
        aspect: f64,
    ) -> Camera {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (lo, hi) = clean_box(bbox_min, bbox_max);
        let (f, r, u) = view_frame(view_dir, up_hint);
        let radius = {
            let d = 0.5 * (hi - lo).length();
            if d > 0.0 && d.is_finite() { d } else { 1.0 }
        };
        let c = 0.5 * (lo + hi);
        let half = corners(lo, hi)
            .iter()
            .map(|&p| {
                let v = p - c;
                (v.dot(u).abs()).max(v.dot(r).abs() / aspect)
            })
            .fold(1e-3 * radius, f64::max)
            / (1.0 - MARGIN);
        Camera {
            eye: c - f * (2.0 * radius),
            forward: f,
            right: r,
            up: u,
            projection: Projection::Orthographic { half_height: half },
            aspect,
            near: 0.0,
        }
    }

    /// Whether the camera is a perspective camera.
    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// Half extents of the image plane: for perspective cameras the tangents
    /// of the half angles (x, y), for orthographic cameras world units.
    pub(crate) fn half_extent(&self) -> (f64, f64) {
        let hy = match self.projection {
            Projection::Perspective { fov_y_deg } => (0.5 * fov_y_deg.to_radians()).tan(),
            Projection::Orthographic { half_height } => half_height,
        };
        (hy * self.aspect, hy)
    }

    /// Distance of `p` in front of the camera, measured along `forward`.
    pub fn depth(&self, p: Vec3) -> f64 {
        (p - self.eye).dot(self.forward)
    }

    /// Projects `p` to normalised device coordinates: `x, y ∈ [-1, 1]` on the
    /// image (x right, y up) and `z` = depth along `forward`. `None` when `p`
    /// is non-finite or (perspective) closer than `near`.
    pub fn project(&self, p: Vec3) -> Option<Vec3> {
        let v = p - self.eye;
        let z = v.dot(self.forward);
        if !v.is_finite() {
            return None;
        }
        let (hx, hy) = self.half_extent();
        let (x, y) = (v.dot(self.right), v.dot(self.up));
        match self.projection {
            Projection::Perspective { .. } => {
                if z.is_nan() || z < self.near || z <= 0.0 {
                    return None;
                }
                Some(Vec3::new(x / (z * hx), y / (z * hy), z))
            }
            Projection::Orthographic { .. } => Some(Vec3::new(x / hx, y / hy, z)),
        }
    }

    /// Unit direction of the viewing ray through normalised device coordinates (`x`, `y`).
    pub fn ray_direction(&self, x: f64, y: f64) -> Vec3 {
        match self.projection {
            Projection::Perspective { .. } => {
                let (hx, hy) = self.half_extent();
                (self.forward + self.right * (x * hx) + self.up * (y * hy)).normalize()
            }
            Projection::Orthographic { .. } => self.forward,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_inside(cam: &Camera, lo: Vec3, hi: Vec3) -> f64 {
        let mut m: f64 = 0.0;
        for p in corners(lo, hi) {
            let q = cam.project(p).expect("corner visible");
            m = m.max(q.x.abs()).max(q.y.abs());
        }
        m
    }

    #[test]
    fn framing_fits_box_with_margin() {
        let (lo, hi) = (Vec3::new(-1.0, -2.0, 0.0), Vec3::new(3.0, 1.0, 0.5));
        for dir in [
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::X,
            Vec3::NEG_Z,
            Vec3::new(0.3, -2.0, -0.1),
        ] {
            for aspect in [0.5, 1.0, 4.0 / 3.0, 3.0] {
                let cam = Camera::framing(lo, hi, dir, Vec3::Z, aspect);
                let m = all_inside(&cam, lo, hi);
                assert!(m <= 1.0 && m > 0.8, "dir {dir} aspect {aspect}: {m}");
                let q = cam.project(0.5 * (lo + hi)).unwrap();
                assert!(q.x.abs() < 1e-9 && q.y.abs() < 1e-9);
                let cam = Camera::framing_orthographic(lo, hi, dir, Vec3::Z, aspect);
                let m = all_inside(&cam, lo, hi);
                assert!(m <= 1.0 && m > 0.85, "ortho dir {dir} aspect {aspect}: {m}");
            }
        }
    }

    #[test]
    fn framing_handles_parallel_up_and_degenerate_boxes() {
        let cam = Camera::framing(Vec3::ZERO, Vec3::ONE, Vec3::Z, Vec3::Z, 1.0);
        assert!(cam.right.is_finite() && cam.up.is_finite());
        assert!((cam.right.dot(cam.up)).abs() < 1e-12);
        // flat box seen edge on and a point
        let cam = Camera::framing(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::X, Vec3::Z, 1.0);
        assert!(all_inside(&cam, Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)) <= 1.0);
        let cam = Camera::framing(Vec3::ONE, Vec3::ONE, Vec3::ZERO, Vec3::ZERO, 0.0);
        assert!(cam.eye.is_finite() && cam.project(Vec3::ONE).is_some());
        let cam = Camera::framing(Vec3::splat(f64::NAN), Vec3::ONE, Vec3::NEG_Y, Vec3::Z, 1.0);
        assert!(cam.eye.is_finite());
    }

    #[test]
    fn up_is_image_top_and_right_is_image_right() {
        let cam = Camera::framing(Vec3::splat(-1.0), Vec3::splat(1.0), Vec3::Y, Vec3::Z, 1.0);
        let top = cam.project(Vec3::new(0.0, 0.0, 1.0)).unwrap();
        assert!(top.y > 0.5);
        // Looking along +Y with Z up, +X is to the right.
        let right = cam.project(Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!(right.x > 0.5);
    }
}
