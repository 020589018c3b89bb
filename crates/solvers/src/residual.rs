//! What every iterative solver does with the relative KKT residual of its iterate (theory §5):
//! record it in the report's history, show it to the monitor, and never let NaN or Inf pass.

use saddle_core::{Monitor, SolveError};

/// Records the residual `r` of iteration `it` of `solver` (tolerance `tol`) in `history` and
/// tells `monitor`; a non-finite residual is an error.
pub(crate) fn record(
    solver: &str,
    it: usize,
    r: f64,
    tol: f64,
    history: &mut Vec<f64>,
    monitor: &mut dyn Monitor,
) -> Result<(), SolveError> {
    history.push(r);
    monitor.iteration(it, r, tol);
    if r.is_finite() {
        Ok(())
    } else {
        Err(SolveError::NonFinite { solver: solver.into(), what: "the KKT residual".into(), iteration: it })
    }
}
