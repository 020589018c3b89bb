//! saddle-mpi: the distributed foundation of saddle (issue 24) — MPI through rsmpi, a narrow and
//! safe interface to PETSc written in the project (bindgen over the installed headers), the
//! collectives the solvers need, and a mesh partitioner. Plain slices and global indices; no
//! mesh or framework types.
//!
//! Everything is behind features, off by default: without them the crate is empty and needs no
//! MPI, no PETSc, no libclang.
//! * `partition`: `partition_elements` (METIS, vendored; no MPI).
//! * `petsc`: the rest (and `partition`); the facade's feature `mpi` turns it on.
//!
//! # Installing (Debian 12 / Ubuntu)
//! ```text
//! apt-get install --no-install-recommends libpetsc-real-dev libopenmpi-dev openmpi-bin libclang-dev pkg-config
//! ```
//! (`libpetsc-real-dev` is PETSc 3.18 on Debian 12, also named `libpetsc-real3.18-dev`; it comes
//! with hypre, MUMPS and PTScotch and links OpenMPI.) `.ci/install-mpi` does this when a package
//! is missing. Build with `cargo build --release --features mpi`; run with
//! `mpirun -n 4 target/release/saddle …` (as root OpenMPI wants
//! `OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1`; more ranks than cores:
//! `--oversubscribe`; one thread per rank: `RAYON_NUM_THREADS=1`).
//!
//! # A cluster's own PETSc
//! The build script looks for PETSc, in this order:
//! 1. `PETSC_DIR` (and `PETSC_ARCH` for an in-place build): headers in `$PETSC_DIR/include` and
//!    `$PETSC_DIR/$PETSC_ARCH/include`, the library named in
//!    `$PETSC_DIR/$PETSC_ARCH/lib/petsc/conf/petscvariables` (`PETSC_LIB_BASIC`). The loader
//!    must find it at run time too (`LD_LIBRARY_PATH`, as `module load petsc` sets).
//! 2. pkg-config `PETSc` (or `petsc`): add `<prefix>/lib/pkgconfig` to `PKG_CONFIG_PATH` for a
//!    prefix or Spack install.
//!
//! MPI is found by rsmpi's probe (`mpicc` on `PATH`, or pkg-config; `MPI_PKG_CONFIG` names the
//! package): it must be the MPI PETSc was built with (the build warns when it can tell they
//! differ). bindgen needs libclang (`LIBCLANG_PATH` if it is not found).
//!
//! # PetscInt and scalars
//! PETSc must be ≥ 3.18, configured with real double scalars (`--with-scalar-type=real
//! --with-precision=double`); the build stops with a message naming the setting otherwise. The
//! width of `PetscInt` is read from `petscconf.h` (`PETSC_USE_64BIT_INDICES`: 64-bit, else
//! 32-bit); the bindings follow it and `Index` is that type, so both builds work. A compile-time
//! check refuses headers whose `PetscInt` disagrees with the `petscconf.h` that was read (two
//! PETSc installations mixed on the include path). Global indices above 2³¹ − 1 need a 64-bit
//! PETSc (`--with-64-bit-indices`); counts that do not fit are reported as
//! `Error::IndexOverflow`.
//!
//! # Errors
//! PETSc's default error handler (print a traceback, sometimes abort) is replaced by one that
//! records the message; every PETSc call's code is checked and becomes `PetscError` with
//! PETSc's message. An error on one rank reaches every rank through `agree`, so that all end
//! together instead of waiting in the next collective.
//!
//! # Threads
//! MPI is initialised with threading "funneled": rayon may run inside a rank, but MPI and PETSc
//! are called from the main thread only (the PETSc types are neither `Send` nor `Sync`).

#[cfg(feature = "petsc")]
mod collective;
#[cfg(feature = "petsc")]
mod error;
/// The raw bindings (an allowlist of PETSc's API): for extending the safe wrappers.
#[cfg(feature = "petsc")]
pub mod ffi;
#[cfg(feature = "petsc")]
mod ksp;
#[cfg(feature = "petsc")]
mod matrix;
#[cfg(feature = "petsc")]
mod near_null_space;
#[cfg(feature = "partition")]
mod partition;
#[cfg(feature = "petsc")]
mod session;
#[cfg(feature = "petsc")]
mod vector;

#[cfg(feature = "petsc")]
pub use collective::{
    SCATTER_CHUNK, agree, broadcast, broadcast_bytes, max, min, scatter_bytes, scatter_bytes_in_chunks, sum,
    sum_in_place,
};
#[cfg(feature = "petsc")]
pub use error::{Error, PetscError, Result};
#[cfg(feature = "petsc")]
pub use ksp::{Ksp, Method, Settings, SolveReport};
#[cfg(feature = "petsc")]
pub use matrix::Matrix;
#[cfg(feature = "petsc")]
pub use mpi;
#[cfg(feature = "partition")]
pub use partition::{Graph, PartitionError, face_dual_graph, partition_elements};
#[cfg(feature = "petsc")]
pub use session::Petsc;
#[cfg(feature = "petsc")]
pub use vector::{GhostVector, Local, LocalMut};

/// PETSc's index type (`PetscInt`): i32, or i64 for a PETSc built with 64-bit indices.
#[cfg(feature = "petsc")]
pub type Index = ffi::PetscInt;
