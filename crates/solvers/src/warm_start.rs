//! The warm start of a load step (theory §11.2), as every iterative solver takes it.

use saddle_core::{Lagrangian, Solution, SolveError, Start};

/// `solve` from the previous step's `start`, which is first checked against `l` (errors name
/// `solver`); the report counts `warm_start = 1`.
pub(crate) fn warm_solve(
    l: &Lagrangian<'_>,
    start: &Start,
    solver: &str,
    solve: impl FnOnce() -> Result<Solution, SolveError>,
) -> Result<Solution, SolveError> {
    start.check(l, solver)?;
    let mut sol = solve()?;
    sol.report.counters.insert("warm_start".into(), 1.0);
    Ok(sol)
}
