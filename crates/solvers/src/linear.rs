//! Glue between the contracts and the linear algebra, which know nothing of each other: L's
//! sparsity pattern as the factorisation takes it, L's rigid-body modes as the multigrid's
//! near-nullspace, and linear-algebra failures as [`SolveError`]s that name the solver.

use saddle_core::linalg::{LowerCsc, NearNullSpace, SparseCholesky};
use saddle_core::problem::operators::RIGID_BODY_MODES;
use saddle_core::{Lagrangian, SolveError, SymmetricPattern};

/// The lower triangle of L's matrices (theory §3) as the linear algebra takes it.
pub fn lower(p: &SymmetricPattern) -> LowerCsc<'_> {
    LowerCsc::new(p.n(), p.col_ptr(), p.row_idx())
}

/// The symbolic Cholesky analysis of L's pattern for the matrix `what`, counted in `analyses`
/// (the `symbolic_analyses` counter of the report: counted here, where the analysis runs).
pub fn analyse(
    p: &SymmetricPattern,
    what: &str,
    solver: &str,
    analyses: &mut usize,
) -> Result<SparseCholesky, SolveError> {
    let chol = SparseCholesky::analyse(lower(p), what).in_solver(solver)?;
    *analyses += 1;
    Ok(chol)
}

/// The near-nullspace of L's elastic stiffness for a multigrid: the rigid-body modes, one
/// block per node; `None` when L has no nodal dofs.
pub fn near_null_space(l: &Lagrangian<'_>) -> Option<NearNullSpace> {
    let m = l.rigid_body_modes()?;
    NearNullSpace::new(m.node, m.modes, RIGID_BODY_MODES).ok()
}

/// `?` on a linear-algebra result inside a solver: the error becomes
/// [`SolveError::LinearAlgebra`] naming the solver.
pub trait InSolver<T> {
    /// The result, its error attributed to `solver`.
    fn in_solver(self, solver: &str) -> Result<T, SolveError>;
}

impl<T, E: std::error::Error + Send + Sync + 'static> InSolver<T> for Result<T, E> {
    fn in_solver(self, solver: &str) -> Result<T, SolveError> {
        self.map_err(|e| SolveError::linear_algebra(solver, e))
    }
}
