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
//! ## The one shape of every algorithm
//!
//! An algorithm is a function of the mesh (by reference: the input is never
//! modified) and an options struct, returning `Result<`[`Output`]`<Report>,
//! Error>`: the new vertex positions and a report that derives
//! `serde::Serialize` (its keys are those of the CLI's `--report` JSON).
//! Options structs implement `Default`, have a builder setter for every
//! field and are `#[non_exhaustive]`, so build them with
//! `Options::default().field(value)`. Fixed vertices are always
//! `fixed: Vec<VertexId>`, regions `region: Vec<FaceId>`. A [`Control`] in
//! the options receives [`Progress`] once per iteration and stops the run
//! with the error type's `Cancelled` variant once its cancel flag is raised
//! (see [`control`]).
//!
//! ```
//! use fairline::smooth::{
//!     LaplaceOptions, SmoothError, TaubinOptions, laplace_smooth, taubin_smooth,
//! };
//! use fairline::{Control, VertexId, shapes};
//! use std::sync::Arc;
//! use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
//!
//! // a noisy sphere, built in code
//! let mut mesh = shapes::icosphere(1.0, 3);
//! for (i, p) in mesh.positions_mut().iter_mut().enumerate() {
//!     *p *= 1.0 + 0.01 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
//! }
//!
//! // Taubin λ|μ smoothing, 20 iterations, vertex 0 held where it is
//! let options = TaubinOptions::default()
//!     .iterations(20)
//!     .fixed(vec![VertexId(0)]);
//! let out = taubin_smooth(&mesh, &options)?;
//! assert_eq!(out.positions.len(), mesh.vertex_count());
//! assert_eq!(out.positions[0], mesh.positions()[0]);
//! assert_eq!(out.report.iterations, 20);
//! // λ|μ keeps the volume far better than plain Laplace smoothing
//! let taubin = out.report.volume_after / out.report.volume_before;
//! let plain = laplace_smooth(&mesh, &LaplaceOptions::default().iterations(20))?;
//! let laplace = plain.report.volume_after / plain.report.volume_before;
//! assert!((taubin - 1.0).abs() < (laplace - 1.0).abs(), "{taubin} vs {laplace}");
//! // the report is the JSON of `fairline smooth --report`
//! let json = serde_json::to_value(&out.report).unwrap();
//! assert_eq!(json["iterations"], 20);
//! mesh.set_positions(out.positions)?; // keep the result, if wanted
//!
//! // watch the run, and stop it from another thread through the flag
//! let steps = Arc::new(AtomicU64::new(0));
//! let seen = Arc::clone(&steps);
//! let stop = Arc::new(AtomicBool::new(false));
//! let flag = Arc::clone(&stop);
//! let control = Control::new()
//!     .cancel_flag(Arc::clone(&stop))
//!     .on_progress(move |p| {
//!         seen.store(p.done, Ordering::Relaxed);
//!         if p.done == 5 {
//!             flag.store(true, Ordering::Relaxed); // e.g. the user pressed Stop
//!         }
//!     });
//! let result = taubin_smooth(&mesh, &options.control(control));
//! assert!(matches!(result, Err(SmoothError::Cancelled(_))));
//! assert_eq!(steps.load(Ordering::Relaxed), 5);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ### Where an algorithm returns something else than new positions
//!
//! A few functions measure or draw rather than move vertices; they keep the
//! shape (input by reference, an options struct with `Default`, builders,
//! `#[non_exhaustive]` and a [`Control`], `Result` with a `Cancelled`
//! variant) and return what they compute:
//!
//! - [`geom::curvature`] returns per-vertex fields, one value per vertex in
//!   vertex order ([`geom::CurvatureOutput`]: principal curvatures and
//!   directions, mean and Gaussian curvature) and a `Serialize` report;
//! - [`highlight::highlight_lines`], [`highlight::circular_highlight_lines`]
//!   and [`highlight::circular_highlight_bands`] return polylines
//!   ([`highlight::HighlightLines`]; their counts for reports come from
//!   [`highlight::HighlightLines::counts`]) and take the lights as a
//!   separate argument: the lights are what the mesh is looked at with, as
//!   the mesh is what is looked at. [`highlight::HighlightModel`] is the
//!   model behind them, kept by the fairing loop to update incrementally;
//! - [`mesh::repair`] takes a face list that may be broken ([`Soup`], not a
//!   mesh: a mesh cannot hold what it repairs) and [`mesh::RepairOptions`],
//!   and returns a new face list with its `Serialize` report
//!   ([`mesh::Repaired`]): vertices may be removed or split, so there are
//!   no "new positions" of the input's vertices.
//!
//! The library returns plain data: what a run did (its report's fields)
//! and nothing worded for a front end. The commands a user runs — which
//! steps in which order, the JSON report, the warnings and the advice in
//! them — are the crate `fairline-commands`, which the CLI, the Python
//! package and the workbench all call.
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

/// A 3 × 3 matrix of f64 (per-vertex tensors, small symmetric systems;
/// [`solve::symmetric_eigen3`]).
pub type Mat3 = glam::DMat3;

pub use control::{Cancelled, Control, Output, Progress, SurfaceOutput};
pub use mesh::{EdgeId, FaceId, HalfedgeId, MeshError, Soup, SurfaceMesh, VertexId};
