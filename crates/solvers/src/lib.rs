//! # saddle-solvers
//!
//! Interchangeable solvers of the discrete saddle problem of SPEC §3, all consuming the
//! Lagrangian trait of `saddle-core` and none knowing which yield surface or obstacle it holds:
//!
//! * [`Uzawa`] (`type = "uzawa"`) — the paper's Uzawa / Arrow–Hurwicz method (SPEC §4).

pub mod kh_projection;
pub mod uzawa;

pub use uzawa::{Uzawa, UzawaMetric};
