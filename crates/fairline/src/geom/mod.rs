//! Differential geometry of meshes: normals, areas, Laplacians, curvature,
//! triangle quality, energies and volume.
//!
//! One concept, one place: every algorithm of fairline takes these from here.
//! Conventions: faces are counter-clockwise seen from outside; normals point
//! outward; a sphere of radius r has k1 = k2 = H = +1/r and K = 1/r².
//! Degenerate faces (zero area) contribute nothing to sums and are never
//! divided by; a vertex whose normal cannot be defined gets the zero vector.

mod areas;
mod closest;
mod curvature;
mod deviation;
mod draft;
mod laplace;
mod measures;
mod normals;
pub(crate) use normals::{BATCH, face_area_vectors, gather_triangles, vertex_normals_into};
mod quadric;
mod section;
mod wavelength;

pub use areas::{
    barycentric_vertex_areas, barycentric_vertex_areas_at, face_areas, face_areas_at,
    mixed_corner_areas, mixed_vertex_areas, mixed_vertex_areas_at,
};
pub use closest::{ClosestPoint, TriangleGrid};
pub use curvature::{
    CurvatureError, CurvatureMethod, CurvatureOptions, CurvatureOutput, CurvatureReport,
    PrincipalCurvatures, curvature, gaussian_curvature, mean_curvature, mean_curvature_normals,
    principal_curvatures, principal_curvatures_meyer, principal_curvatures_rusinkiewicz,
};
pub use deviation::{
    Deviation, DeviationError, DeviationMethod, DeviationStats, Histogram, closest_point_deviation,
    deviation, deviation_stats, displacement, same_connectivity,
};
pub use draft::{DraftAngles, DraftError, DraftShares, draft_angles};
pub use laplace::{
    LaplaceWeights, LaplacianPattern, cotangent_laplacian, cotangents, cotangents_at,
    edge_length_laplacian, halfedge_weights, halfedge_weights_at, laplacian,
    laplacian_from_weights, uniform_laplacian,
};
pub use measures::{
    closest_point_on_triangle, corner_angles, edge_lengths, mean_edge_length, surface_area,
    triangle_qualities, triangle_quality, volume, volume_at, willmore_energy,
};
pub use normals::{
    face_normals, triangle_normal_area, vertex_normal, vertex_normals, vertex_normals_at,
    vertex_normals_max, vertex_normals_max_at,
};
pub use quadric::{QuadricFit, QuadricPatch, quadric_fit, quadric_fit_rings, quadric_patch_rings};
pub use section::{SectionCurve, parallel_sections, plane_section};
pub use wavelength::{WavelengthSplit, split_by_wavelength};

/// The degenerate-face threshold, defined with the meshes (whose inspection
/// counts degenerate faces) and used by every area and normal here.
pub use crate::mesh::DEGENERATE_RELATIVE_AREA;

/// Largest magnitude a cotangent is allowed to take (angles below about
/// 1e-6 rad); keeps near-degenerate triangles from dominating a Laplacian.
pub const COTANGENT_LIMIT: f64 = 1e6;

#[cfg(test)]
pub(crate) mod tests;
