//! Measurements of the solvers and the discretisation, on top of [`crate::app`] and
//! [`crate::io`]:
//!
//! | module | study |
//! |---|---|
//! | [`report`] | `saddle report`: work–precision, mesh convergence, P1 against P2 |
//! | [`bench`](mod@bench) | `saddle bench`: cost against problem size |
//! | `peer` | `saddle bench --meshes`: end to end on Gmsh meshes beside a peer code (feature `gmsh`) |
//! | [`stability`] | stiff and extreme variants of the default scene, every solver |

pub mod bench;
#[cfg(feature = "gmsh")]
pub mod peer;
pub mod report;
pub mod stability;
