//! saddle-parallel: a discrete problem of saddle distributed over the ranks of MPI, on PETSc
//! (issue 24, theory §12). It joins the framework (`saddle-core`) to the distributed foundation
//! (`saddle-mpi`), and nothing in it knows a particular element, yield surface or obstacle:
//!
//! * [`comm`] — `MpiComm`: core's [`saddle_core::problem::comm::Comm`] on MPI's world, every
//!   reduction the same bits on every rank;
//! * [`layout`] — `Layout`: where a rank's dofs sit in PETSc's vectors and matrices (three rows
//!   per node, owned nodes in the rank's range, the rest ghosts);
//! * [`element`] — `DistributedElement`: a rank's element operators, the ghost exchange inside
//!   ε = B u and Bᵀσ, so that solvers see the rank's owned dofs only;
//! * [`spd`] — `PetscSpd`: core's [`saddle_core::linalg::DistributedSpd`] as a PETSc matrix
//!   (MPIAIJ, block size 3, the rigid-body near-null space) and KSP (CG with GAMG by default);
//! * [`distribute`] — `distribute`: a scene's mesh, read on rank 0, partitioned by METIS and
//!   spread; each rank's part of the problem (its elements, dofs, contact rows, loads).
//!
//! Everything is behind the feature `petsc`; without it the crate is empty.

#[cfg(feature = "petsc")]
pub mod comm;
#[cfg(feature = "petsc")]
pub mod distribute;
#[cfg(feature = "petsc")]
pub mod element;
#[cfg(feature = "petsc")]
mod funneled;
#[cfg(feature = "petsc")]
pub mod layout;
#[cfg(feature = "petsc")]
pub mod spd;

#[cfg(feature = "petsc")]
pub use comm::MpiComm;
#[cfg(feature = "petsc")]
pub use distribute::{RankProblem, distribute};
#[cfg(feature = "petsc")]
pub use element::DistributedElement;
#[cfg(feature = "petsc")]
pub use layout::Layout;
#[cfg(feature = "petsc")]
pub use saddle_mpi;
#[cfg(feature = "petsc")]
pub use spd::PetscSpd;
