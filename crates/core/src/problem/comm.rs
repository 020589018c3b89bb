//! Reductions over the ranks that share a distributed problem (theory §12). A distributed
//! implementation of the element's operators holds each rank's part of the points, dofs and
//! rows; every sum or extremum of L's energies and residuals and of the solvers' decisions is a
//! rank's partial result reduced here, so that every rank takes the same decision. On one
//! process every reduction is the identity ([`Serial`]).

use std::fmt::Debug;

/// Global reductions of rank-local partial results. Implementations must give every rank the
/// same result, bit for bit (a decision taken on it is taken identically everywhere), and are
/// called from the thread that drives the solve.
pub trait Comm: Debug + Send + Sync {
    /// This rank (0 on one process).
    fn rank(&self) -> usize {
        0
    }

    /// Number of ranks (1 on one process).
    fn size(&self) -> usize {
        1
    }

    /// Σ over the ranks of `x`.
    fn sum(&self, x: f64) -> f64 {
        x
    }

    /// Σ over the ranks of each entry of `x`, in place.
    fn sum_in_place(&self, x: &mut [f64]) {
        let _ = x;
    }

    /// Σ over the ranks of a count.
    fn sum_count(&self, x: usize) -> usize {
        x
    }

    /// The largest `x` over the ranks; NaN if any rank's is NaN.
    fn max(&self, x: f64) -> f64 {
        x
    }

    /// The smallest `x` over the ranks; NaN if any rank's is NaN.
    fn min(&self, x: f64) -> f64 {
        x
    }

    /// True when any rank's `b` is.
    fn any(&self, b: bool) -> bool {
        b
    }
}

/// One process: every reduction is the identity.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Comm for Serial {}

/// The one-process communicator.
pub static SERIAL: Serial = Serial;
