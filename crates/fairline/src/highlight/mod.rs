//! Highlight lines: linear light arrays on triangle meshes (Yong et al. §2,
//! Algorithm 1, with the corrections of DESIGN.md §3), circular lights
//! (Nishiyama et al. §2, Eq. (2.1)–(2.18)) evaluated on meshes, highlight
//! bands, and detection of irregular stretches of highlight lines.
//!
//! Assumes triangle meshes with consistently oriented faces; normals are the
//! area-weighted vertex normals of Yong et al. Eq. (3) from [`crate::geom`].
//! Node positions come from linear interpolation of the per-vertex field
//! along edges (Yong et al. Eq. (4), corrected).

mod circular;
mod contour;
pub mod detect;
mod drawn_stats;
mod light;
mod light_choice;
mod linear;
mod lines_file;
pub mod quartic;
pub mod readable;
pub mod surface;
mod surface_lines_file;

pub use circular::{circular_highlight_bands, circular_highlight_lines};
pub use contour::{HighlightLine, HighlightLines, NodeId};
pub use detect::{
    DetectOptions, Detection, IrregularRegion, LineFairness, NOT_JUDGED_SHARE, RegionDetection,
    Site, detect_irregularities, detect_region, detect_whole_part,
};
pub use drawn_stats::DrawnLineStats;
pub use light::{CircleApproach, CircularLight, CircularLights, LightArray, UpAxis};
pub use light_choice::LightChoice;
pub use linear::{HighlightModel, HighlightOptions, highlight_lines};
pub use lines_file::{highlight_lines_json, highlight_lines_obj};
/// The one quartic solver (Nishiyama et al. Eq. (2.15)–(2.16)), shared by
/// circular lights on meshes and on B-spline surfaces.
pub use quartic::{Roots, quartic_roots};
pub use readable::{LineStats, Readability};
pub use surface::{
    DEFAULT_CIRCULAR_RADII, PartLights, PatchHighlights, SurfaceHighlightLine,
    SurfaceHighlightOptions, SurfaceHighlights, SurfaceLight, default_circular_lights,
    default_circular_lights_for_mesh, linear_distance_gradient, linear_lights,
    linear_separation_on_screen, part_highlight_lines, part_light_array, part_view, patch_grid,
    readable_surface_lines, readable_surface_lines_in_view, surface_highlight_lines,
    surface_signed_distance,
};
pub use surface_lines_file::{SurfaceLineCounts, surface_highlight_lines_json, surface_line_json};

use crate::mesh::MeshError;

use serde::Serialize;
use thiserror::Error;

/// Counts of a set of highlight lines: the `"summary"` (and the top-level
/// `"lines"`, `"closed_lines"`, `"nodes"`) of `fairline highlight --report`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LineCounts {
    /// Polylines.
    pub lines: usize,
    /// Closed polylines among them.
    pub closed_lines: usize,
    /// Nodes (points) of all polylines.
    pub nodes: usize,
}

impl HighlightLines {
    /// The counts of these lines for reports.
    pub fn counts(&self) -> LineCounts {
        LineCounts {
            lines: self.lines.len(),
            closed_lines: self.lines.iter().filter(|l| l.closed).count(),
            nodes: self.node_count(),
        }
    }
}

/// Why a highlight computation could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum HighlightError {
    /// The mesh is unsuitable (e.g. not all triangles).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A light description is invalid (zero vector, parallel directions,
    /// non-positive spacing or radius).
    #[error("invalid light: {0}")]
    InvalidLight(String),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Default lights were asked for a mesh without a finite vertex.
    #[error("the mesh has no finite vertices")]
    NoFiniteVertices,
    /// The caller's [`crate::Control`] asked to stop.
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
}

/// Highlight bands of lights with a tube radius ρ (Nishiyama et al. §2, last
/// paragraph; for linear lights the strip |d_P − m·s| ≤ ρ of Yong et al.
/// Eq. (1)–(2)): for each light, the boundary level sets as two families of
/// polylines with the light's index.
#[derive(Clone, Debug, PartialEq)]
pub struct HighlightBands {
    /// The band radius ρ (mesh units).
    pub radius: f64,
    /// Level set at −ρ from each light.
    pub lower: HighlightLines,
    /// Level set at +ρ from each light.
    pub upper: HighlightLines,
}

#[cfg(test)]
mod detect_tests;
#[cfg(test)]
mod tests;
