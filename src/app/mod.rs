//! The commands a user runs on a scene file, on top of [`crate::io`]:
//!
//! | module | command |
//! |---|---|
//! | [`setup`] | a scene read and assembled with its solver ([`setup::Loaded`]); a run's errors and outcome |
//! | `mpi` | `saddle run` under `mpirun` (feature `mpi`): the scene distributed, [`ranks::Ranks`] over MPI |
//! | [`ranks`] | where the problem lives: this process, or the ranks of `mpirun` (theory §12) |
//! | [`path`] | the steps of a `[load_path]` solved and written (theory §11) |
//! | [`run`] | `saddle run`: one step, or the load path |
//! | [`sweep`] | `saddle sweep`: the scene at each load factor |
//! | [`limit`] | `saddle limit`: the collapse multiplier as one conic solve (theory §13) |

#[cfg(feature = "socp")]
pub mod limit;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod path;
pub mod ranks;
pub mod run;
pub mod setup;
pub mod sweep;
