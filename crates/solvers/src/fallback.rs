//! The globalisation of semismooth Newton (theory §4.2.1): a stall of the active-set iteration
//! is recognised from its KKT residuals, and a bounded run of the penalty method (theory §4.3),
//! which converges from any start, hands Newton an iterate near the solution.

use crate::penalty::Penalty;
use saddle_core::problem::lagrangian::Lagrangian;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, Solver, Start};
use std::collections::BTreeMap;

/// A residual that falls below this fraction of the best one so far is progress (theory
/// §4.2.1): a Newton iteration near the solution gains far more, a cycling active set none.
pub const STALL_DECREASE: f64 = 0.5;

/// Watches the KKT residuals of Newton's iterates for a stall: `window` iterations without a
/// residual below [`STALL_DECREASE`] times the best one before them (theory §4.2.1).
pub(crate) struct StallGuard {
    window: usize,
    /// The residual progress is measured against, and the iteration it was reached at.
    best: Option<(f64, usize)>,
}

impl StallGuard {
    /// A guard that calls `window` iterations without progress a stall (0: never).
    pub(crate) fn new(window: usize) -> Self {
        Self { window, best: None }
    }

    /// Records the residual `r` of iteration `it`; true when the iteration has stalled.
    pub(crate) fn stalled(&mut self, r: f64, it: usize) -> bool {
        match self.best {
            Some((best, _)) if r >= STALL_DECREASE * best => {}
            _ => self.best = Some((r, it)),
        }
        let (_, since) = self.best.expect("set above");
        self.window > 0 && it >= since + self.window
    }

    /// Starts watching afresh (after the elastic phase or a fallback).
    pub(crate) fn reset(&mut self) {
        self.best = None;
    }
}

/// Errors of a Newton step that come from a wrong active set, not from the problem: no active
/// row holds a loaded extra, or the tangent with that set is singular (theory §4.2.1).
pub(crate) fn caused_by_the_active_set(e: &SolveError) -> bool {
    matches!(e, SolveError::Unsupported { .. } | SolveError::LinearAlgebra { .. })
}

/// The robust steps of the fallback (theory §4.2.1): the penalty method with at most `max_iter`
/// iterations to the tolerance `tol`, from `start` (its own elastic start without one); the
/// time goes to the phase "fallback". Its solution, converged or not, is Newton's next iterate.
pub(crate) fn robust_steps(
    l: &Lagrangian<'_>,
    start: Option<&Start>,
    tol: f64,
    max_iter: usize,
    monitor: &mut dyn Monitor,
    timer: &mut PhaseTimer,
) -> Result<Solution, SolveError> {
    let penalty = Penalty { tol, max_iter, ..Penalty::default() };
    timer.time("fallback", || match start {
        Some(s) => penalty.solve_warm(l, s, monitor),
        None => penalty.solve(l, monitor),
    })
}

/// The linear algebra of the fallbacks' penalty runs, carried into Newton's counters as
/// `fallback_<name>` (the penalty's counters of the same names, summed over the fallbacks).
#[derive(Default)]
pub(crate) struct FallbackLinearAlgebra([usize; 2]);

impl FallbackLinearAlgebra {
    /// The penalty counters carried.
    const CARRIED: [&'static str; 2] = ["factorisations", "entering_row_updates"];

    /// Adds a fallback's penalty `counters`.
    pub(crate) fn add(&mut self, counters: &BTreeMap<String, f64>) {
        for (sum, name) in self.0.iter_mut().zip(Self::CARRIED) {
            *sum += counters.get(name).copied().unwrap_or(0.0) as usize;
        }
    }

    /// Puts them as `fallback_<name>`.
    pub(crate) fn report(&self, mut put: impl FnMut(&str, usize)) {
        for (sum, name) in self.0.iter().zip(Self::CARRIED) {
            put(&format!("fallback_{name}"), *sum);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::StallGuard;

    #[test]
    fn a_cycle_is_a_stall_and_a_newton_sequence_is_not() {
        let mut guard = StallGuard::new(4);
        let cycle = [0.9, 0.35, 0.41, 0.39, 1.0, 1.0, 1.0, 0.099, 1.0, 0.59, 1.0, 0.1];
        let first = cycle.iter().enumerate().position(|(it, r)| guard.stalled(*r, it));
        // the best residual 0.35 at iteration 1 is not halved in iterations 2–5
        assert_eq!(first, Some(5));
        let mut guard = StallGuard::new(4);
        assert!(
            ![1.0, 0.3, 0.2, 0.15, 0.12, 0.01, 1e-5, 1e-11].iter().enumerate().any(|(it, r)| guard.stalled(*r, it))
        );
    }
}
