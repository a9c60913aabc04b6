//! The linear light array a user asks for: the default lights of the part
//! with the fields the user gave put in their place. One definition for
//! every front end: the `--direction`, `--plane-normal`, `--up`,
//! `--plane-point` and `--spacing` options of the CLI, the keywords of the
//! same names of the Python package, and the workbench.

use super::{HighlightError, LightArray, UpAxis};
use crate::Vec3;
use crate::mesh::SurfaceMesh;

/// The fields of a linear light array a user gave; `None` takes the
/// default of the part ([`LightArray::default_for_mesh`],
/// [`LightArray::default_for`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct LightChoice {
    /// Light direction H (made orthogonal to the plane normal).
    pub direction: Option<Vec3>,
    /// Normal Z of the light plane (default: from `up`).
    pub plane_normal: Option<Vec3>,
    /// Which side the lights are on when `plane_normal` is not given.
    pub up: UpAxis,
    /// Point A0 on light 0.
    pub plane_point: Option<Vec3>,
    /// Spacing s between lights.
    pub spacing: Option<f64>,
}

impl LightChoice {
    /// Sets [`LightChoice::direction`].
    pub fn direction(mut self, v: Option<Vec3>) -> Self {
        self.direction = v;
        self
    }
    /// Sets [`LightChoice::plane_normal`].
    pub fn plane_normal(mut self, v: Option<Vec3>) -> Self {
        self.plane_normal = v;
        self
    }
    /// Sets [`LightChoice::up`].
    pub fn up(mut self, v: UpAxis) -> Self {
        self.up = v;
        self
    }
    /// Sets [`LightChoice::plane_point`].
    pub fn plane_point(mut self, v: Option<Vec3>) -> Self {
        self.plane_point = v;
        self
    }
    /// Sets [`LightChoice::spacing`].
    pub fn spacing(mut self, v: Option<f64>) -> Self {
        self.spacing = v;
        self
    }

    /// The light array for `mesh`: with a plane normal given, the defaults
    /// of its bounding box ([`LightChoice::light_array_in_box`]); else the
    /// part's default lights for `up` ([`LightArray::default_for_mesh`]),
    /// with the given direction, plane point and spacing in their place.
    pub fn light_array(&self, mesh: &SurfaceMesh) -> Result<LightArray, HighlightError> {
        if self.plane_normal.is_some() {
            let (lo, hi) = crate::mesh::bounding_box(mesh.positions())
                .ok_or(HighlightError::NoFiniteVertices)?;
            return self.light_array_in_box(lo, hi);
        }
        let base =
            LightArray::default_for_mesh(mesh, self.up).ok_or(HighlightError::NoFiniteVertices)?;
        LightArray::new(
            self.plane_point.unwrap_or(base.plane_point()),
            base.plane_normal(),
            self.direction.unwrap_or(base.direction()),
            self.spacing.unwrap_or(base.spacing()),
        )
    }

    /// The light array for the bounding box `lo`–`hi` (B-spline parts):
    /// [`LightArray::default_for`] facing the given plane normal (or the
    /// `up` axis), with the given fields in place of the defaults.
    pub fn light_array_in_box(&self, lo: Vec3, hi: Vec3) -> Result<LightArray, HighlightError> {
        let base = LightArray::default_for(lo, hi, self.plane_normal.or(self.up.vector()));
        LightArray::new(
            self.plane_point.unwrap_or(base.plane_point()),
            self.plane_normal.unwrap_or(base.plane_normal()),
            self.direction.unwrap_or(base.direction()),
            self.spacing.unwrap_or(base.spacing()),
        )
    }

    /// The lights to draw and read lines with: `light` itself when the
    /// spacing was given, else `light` with its spacing multiplied by
    /// [`LightArray::readable_multiple`] (round parts get fewer, readable
    /// lines; panels keep about 20 across).
    pub fn readable(
        &self,
        mesh: &SurfaceMesh,
        light: LightArray,
    ) -> Result<LightArray, HighlightError> {
        if self.spacing.is_some() {
            return Ok(light);
        }
        let k = light.readable_multiple(mesh);
        light.with_spacing(light.spacing() * f64::from(k))
    }
}

impl UpAxis {
    /// The axis as a vector, `None` for [`UpAxis::Auto`].
    pub fn vector(self) -> Option<Vec3> {
        match self {
            UpAxis::Auto => None,
            UpAxis::X => Some(Vec3::X),
            UpAxis::Y => Some(Vec3::Y),
            UpAxis::Z => Some(Vec3::Z),
        }
    }
}
