//! Errors of the linear algebra: factorisations, conjugate gradients, multigrid set-up.

use crate::error::ParameterError;
use thiserror::Error;

/// Failures of the sparse linear algebra.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum LinalgError {
    /// Cholesky met a non-positive pivot: the matrix is singular or indefinite.
    #[error("the {what} matrix ({n} unknowns) is not positive definite (singular or indefinite)")]
    NotPositiveDefinite { what: String, n: usize },
    /// The factor does not fit in the memory the machine gives (choose the multigrid).
    #[error(
        "the {what} matrix's Cholesky factor ({n} unknowns) needs {:.1} GB, which the machine cannot allocate: \
         use the multigrid (linear = \"amg\") or a smaller mesh",
        *bytes as f64 / 1e9
    )]
    OutOfMemory { what: String, n: usize, bytes: usize },
    /// faer reported an error (allocation, index overflow).
    #[error("sparse linear algebra failed for the {what} matrix: {message}")]
    Backend { what: String, message: String },
}

/// Failures of preconditioned conjugate gradients: a breakdown is reported, never a NaN.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum PcgError {
    /// A vector or matrix does not have the size of the workspace.
    #[error("{what} has size {found}, but the system has {expected} unknowns")]
    DimensionMismatch { what: String, expected: usize, found: usize },
    /// NaN or infinity in the data.
    #[error("{what} contains NaN or infinite entries")]
    NonFinite { what: String },
    /// A quantity that must be positive for an SPD system and preconditioner was not.
    #[error("conjugate gradients broke down in iteration {iteration}: {quantity} = {value:e}")]
    Breakdown { iteration: usize, quantity: String, value: f64 },
    /// A diagonal entry that must be positive (Jacobi) is not.
    #[error("row {row} has diagonal entry {value:e}; a symmetric positive definite matrix has a positive diagonal")]
    NonPositiveDiagonal { row: usize, value: f64 },
}

/// Failures of the algebraic multigrid set-up.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum AmgError {
    /// The matrix and the dof layout (or a refreshed matrix and the hierarchy) do not match.
    #[error("{what} has size {found}, expected {expected}")]
    DimensionMismatch { what: String, expected: usize, found: usize },
    /// A diagonal entry of the matrix on some level is not positive (or not finite).
    #[error(
        "level {level}, row {row}: diagonal entry {value:e}; the matrix must be symmetric positive definite \
         with finite entries"
    )]
    NonPositiveDiagonal { level: usize, row: usize, value: f64 },
    /// A parameter out of range.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The coarsest level's Cholesky factorisation failed.
    #[error("coarse-level solve: {0}")]
    Coarse(#[from] LinalgError),
}
