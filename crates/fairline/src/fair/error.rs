//! Errors of the fairing algorithms.

use crate::highlight::HighlightError;
use crate::mesh::MeshError;
use crate::solve::SolveError;
use thiserror::Error;

/// Why a fairing run could not be carried out.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FairError {
    /// The mesh is unsuitable (e.g. not all triangles).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The highlight line model could not be built.
    #[error(transparent)]
    Highlight(#[from] HighlightError),
    /// A linear or quadratic solve failed.
    #[error("solver failure: {0}")]
    Solve(#[from] SolveError),
    /// The region description is invalid (bad JSON, index out of range,
    /// empty).
    #[error("invalid region: {0}")]
    Region(String),
    /// The region leaves no vertex that may move (Yong et al. §3.1).
    #[error("no movable vertex: {0}")]
    NoMovableVertex(String),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The caller stopped the run through [`crate::Control`].
    #[error("cancelled")]
    Cancelled(#[from] crate::Cancelled),
}

impl From<crate::io::RegionError> for FairError {
    fn from(e: crate::io::RegionError) -> Self {
        FairError::Region(e.0)
    }
}
