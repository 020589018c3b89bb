//! # saddle-solvers
//!
//! Interchangeable solvers of the discrete saddle problem of theory §3, all consuming the
//! Lagrangian trait of `saddle-core` and none knowing which yield surface or obstacle it holds:
//!
//! * [`Uzawa`] (`type = "uzawa"`) — the paper's Uzawa / Arrow–Hurwicz method (theory §4.1);
//! * [`Newton`] (`type = "newton"`) — semismooth Newton with a primal–dual active set;
//! * [`Penalty`] (`type = "penalty"`) — the regularised Lagrangian of the existence proof;
//! * `Socp` (`type = "socp"`, cargo feature `socp`, on by default) — the cone form handed to
//!   Clarabel, polished by active-set Newton.
//!
//! Beside them, [`limit`] (feature `socp`): limit analysis, the collapse multiplier of the
//! loads as one conic programme (theory §13).

pub mod active_set;
mod armijo;
pub mod conformance;
pub mod distributed_basis;
pub mod distributed_projection;
pub mod distributed_system;
mod fallback;
mod fixed_dofs;
pub mod forcing;
pub mod friction;
pub mod friction_qp;
pub mod kh_projection;
#[cfg(feature = "socp")]
pub mod limit;
pub mod linear;
mod local_law;
pub mod newton;
pub mod newton_friction;
pub mod penalty;
pub mod pressure_block;
mod residual;
pub mod row_basis;
#[cfg(feature = "socp")]
pub mod socp;
#[cfg(feature = "socp")]
mod triplets;
pub mod uzawa;
mod vector;
mod warm_start;

pub use active_set::LinearSolver;
pub use forcing::ForcingRule;
#[cfg(feature = "socp")]
pub use limit::{Collapse, LimitAnalysis, LimitError};
pub use newton::{Newton, Start};
pub use penalty::Penalty;
#[cfg(feature = "socp")]
pub use socp::Socp;
pub use uzawa::{Uzawa, UzawaAcceleration, UzawaMetric};
