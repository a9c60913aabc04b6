//! Sparse linear solvers shared by every algorithm: sparse Cholesky with a
//! reusable symbolic factorisation (AMD or nested-dissection ordering),
//! normal equations of sparse least-squares problems (by Cholesky or by
//! matrix-free preconditioned conjugate gradients), preconditioned conjugate
//! gradients for any symmetric positive definite operator, triplet assembly,
//! the one constrained quadratic solve (fixed unknowns eliminated, symbolic
//! factorisation reused: [`ConstrainedSolver`]), and an exact
//! bound-constrained QP solver.
//!
//! All matrices are faer `SparseColMat<usize, f64>`.

mod amg;
mod banded;
mod box_qp;
mod cg;
mod cholesky;
mod constrained;
mod ordering;
mod small;
mod staged;
mod vector_amg;

pub use amg::CsrMatrix;
pub use banded::{BandedBlocks, banded_cholesky, banded_solve, sandwich_pcg};
pub use box_qp::{BoxQpOptions, BoxQpSolution, box_qp};
pub use cg::{
    BlockJacobi, CgOptions, CgReport, Preconditioner, normal_diagonal_blocks, normal_equations_cg,
    normal_equations_pcg, pcg, pcg_with,
};
pub use cholesky::{
    CholeskyOptions, CholeskyOrdering, CholeskySolver, least_squares, normal_matrix,
    sparse_from_triplets,
};
pub use constrained::{ConstrainedOptions, ConstrainedSolver};
pub use ordering::nested_dissection;
pub use small::{
    function_of_eigen3, height_monomials, solve_spd, symmetric_eigen3, symmetric_function3,
};
pub use staged::{
    AUTO_DIRECT_LIMIT, AUTO_JACOBI_BUDGET, AUTO_JACOBI_CHECK, MultigridBuilder, NormalEquations,
    NormalSolver, StagedOptions, StagedSolver, StagedStats,
};
pub use vector_amg::{SymmetricBlock, VectorAmg, VectorAmgOptions, VectorOperator};

/// The sparse matrix types of the solvers' signatures (faer's, re-exported
/// so that a caller needs no dependency of its own to name them).
pub use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};

use thiserror::Error;

/// Why a linear solve failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolveError {
    /// The matrix is not (numerically) symmetric positive definite.
    #[error("matrix is not symmetric positive definite (Cholesky failed)")]
    NotPositiveDefinite,
    /// Sizes do not match.
    #[error("dimension mismatch: {0}")]
    Dimension(String),
    /// The solution contains NaN or infinity.
    #[error("the solution is not finite")]
    NonFinite,
    /// Out of memory or another failure inside faer.
    #[error("sparse solver failure: {0}")]
    Backend(String),
}
