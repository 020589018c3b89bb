//! A discrete problem split over ranks (theory §12), as plain data: no MPI here. The elements
//! are partitioned (by a graph partitioner, `saddle-mpi`); each rank holds its elements, the
//! nodes they touch — the ones it owns first, then the ghosts other ranks own — its own dof
//! numbering, and the contact rows of its owned nodes ([`part`]). A distributed implementation
//! of the element's operators builds on a [`MeshPart`]; its reductions and solves go through
//! [`crate::problem::comm::Comm`] and [`crate::linalg::DistributedSpd`].

pub mod part;

pub use part::{MeshPart, Partition, PartitionError};
