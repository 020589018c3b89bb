//! Sparse linear algebra, knowing nothing of meshes or mechanics: compressed storage
//! ([`Csr`], [`LowerCsc`]), sparse Cholesky with a symbolic/numeric split ([`SparseCholesky`],
//! faer underneath), preconditioned conjugate gradients ([`Pcg`]) and a smoothed-aggregation
//! multigrid preconditioner ([`SmoothedAggregation`]) that takes its near-nullspace as plain
//! vectors ([`NearNullSpace`]).

pub mod amg;
pub mod cholesky;
pub mod csr;
pub mod csr32;
pub mod dense_qp;
pub mod distributed;
pub mod error;
pub mod minres;
pub mod pcg;
pub mod reduce;

pub use amg::{AmgParams, LevelInfo, NearNullSpace, SmoothedAggregation};
pub use cholesky::SparseCholesky;
pub use csr::{Csr, LowerCsc};
pub use csr32::Csr32;
pub use dense_qp::{DenseQp, QpError, QpSolution};
pub use distributed::{DistributedError, DistributedSolve, DistributedSpd};
pub use error::{AmgError, LinalgError, PcgError};
pub use minres::{Minres, MinresReport, Residual, SymmetricOperator};
pub use pcg::{Identity, Jacobi, Pcg, PcgReport, Preconditioner};
