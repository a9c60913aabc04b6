//! # fairline
//!
//! Shows and repairs the shape quality of surfaces: highlight lines on
//! triangle meshes and B-spline surfaces, highlight-line fairing, the classic
//! smoothing family, structure-line fairing of quad meshes and feature
//! enhancement by vertex flow.
//!
//! The library never prints and never exits; every algorithm takes plain data
//! and an options struct and returns a result plus a report. Data flows one
//! way: [`io`] → [`mesh`] → [`geom`] → algorithms → [`io`] / [`render`].
//!
//! Conventions: f64 everywhere; faces are oriented counter-clockwise seen
//! from outside, so normals point outward and a sphere of radius r has
//! principal curvatures k1 = k2 = +1/r and mean curvature H = +1/r.

// `!(x > 0.0)` is the deliberate NaN-safe guard before a division: it is
// true for NaN as well as for non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Numeric kernels index several parallel arrays with one loop variable.
#![allow(clippy::needless_range_loop)]
// Nothing needs unsafe code: slices, rayon and faer's safe API suffice.
#![forbid(unsafe_code)]

pub mod bspline;
pub mod control;
pub mod curves;
pub mod enhance;
pub mod fair;
pub mod geom;
pub mod highlight;
pub mod io;
pub mod mesh;
pub mod picture;
pub mod render;
pub mod shapes;
pub mod smooth;
pub mod solve;

/// The test helper for `../shared/data` (one file shared by every test crate).
#[cfg(test)]
#[path = "../tests/support/shared_data.rs"]
mod shared_data;

/// A 3-vector of f64 (position, normal, direction).
pub type Vec3 = glam::DVec3;

pub use control::{Cancelled, Control, Output, Progress, SurfaceOutput};
pub use mesh::{EdgeId, FaceId, HalfedgeId, MeshError, Soup, SurfaceMesh, VertexId};
