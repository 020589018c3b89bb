//! The linear algebra a distributed implementation of the element's operators brings (theory
//! §12): a symmetric positive definite matrix assembled from every rank's element values on its
//! local pattern, with chosen dofs fixed, and a Krylov solver for it. Solvers use it through this
//! trait and know nothing of the library underneath (PETSc in `saddle-mpi`).

use std::error::Error;

/// Boxed error of a distributed solve (the library's message).
pub type DistributedError = Box<dyn Error + Send + Sync>;

/// What a distributed solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DistributedSolve {
    /// Krylov iterations.
    pub iterations: usize,
    /// True when the tolerance was met within the iteration budget.
    pub converged: bool,
}

/// A symmetric positive definite matrix over the dofs of all ranks, assembled from each rank's
/// lower-triangle values on the operators' local pattern (its owned and ghost dofs), and its
/// solver. Vectors are a rank's owned dofs, or its local dofs (owned, then ghosts: the local
/// pattern's numbering) where said. Every method is collective.
pub trait DistributedSpd {
    /// The matrix from this rank's `values` on the local pattern (lower triangle by columns:
    /// column j's rows are `row_idx[col_ptr[j]..col_ptr[j + 1]]`, the diagonal first; the
    /// caller's, so that the solver keeps no copy of it), summed over the ranks, with the rows
    /// and columns of the owned dofs `fixed` (every rank its own) replaced by those of the
    /// identity. The nonzero structure is kept from one call to the next.
    fn assemble(
        &mut self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
        fixed: &[usize],
    ) -> Result<(), DistributedError>;

    /// The diagonal of the matrix `values` would assemble (summed over the ranks, nothing
    /// fixed), at the owned dofs; `col_ptr` as in [`DistributedSpd::assemble`].
    fn diagonal(&mut self, col_ptr: &[usize], values: &[f64], out: &mut [f64]) -> Result<(), DistributedError>;

    /// `local` = the vector `owned` (at the owned dofs) at every local dof, the ghosts' values
    /// from their owners: what a rank needs to know of data other ranks hold at its ghost dofs
    /// (the change of basis of general contact rows, theory §12.2).
    fn ghosted(&mut self, owned: &[f64], local: &mut [f64]) -> Result<(), DistributedError>;

    /// From now on the matrices are assembled in the coordinates y = T⁻¹ x of the owned dofs
    /// (those of general contact rows, theory §8.1, §12.2; T block diagonal over the owned
    /// dofs), `to_coordinates` mapping a vector over the owned dofs to them: the
    /// preconditioner's near-null space (the rigid-body modes) is mapped with it.
    fn change_coordinates(&mut self, to_coordinates: &dyn Fn(&mut [f64])) -> Result<(), DistributedError>;

    /// Solves A x = b with the last assembled matrix, from `x`, to the relative residual `rtol`;
    /// `b` and `x` over the owned dofs.
    fn solve(&mut self, b: &[f64], x: &mut [f64], rtol: f64) -> Result<DistributedSolve, DistributedError>;
}
