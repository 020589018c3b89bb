//! What every iterative solver does with the relative KKT residual of its iterate (theory §5):
//! record it in the report's history, show it to the monitor, never let NaN or Inf pass, and
//! report how the iteration ended (theory §4.5).

use saddle_core::problem::kkt::KktResiduals;
use saddle_core::{Monitor, SolveError, SolveReport, StopReason};
use std::collections::BTreeMap;

/// The residuals of one solve's iterates, in order, with the solver's name and tolerance.
pub(crate) struct History {
    solver: String,
    tol: f64,
    residuals: Vec<f64>,
}

impl History {
    /// An empty history of `solver` (its report's name) with tolerance `tol`.
    pub(crate) fn new(solver: &str, tol: f64) -> Self {
        Self { solver: solver.into(), tol, residuals: Vec::new() }
    }

    /// Records the residual `r` of iteration `it` and tells `monitor`; a non-finite residual is
    /// an error.
    pub(crate) fn record(&mut self, it: usize, r: f64, monitor: &mut dyn Monitor) -> Result<(), SolveError> {
        self.residuals.push(r);
        monitor.iteration(it, r, self.tol);
        if r.is_finite() {
            Ok(())
        } else {
            Err(SolveError::NonFinite { solver: self.solver.clone(), what: "the KKT residual".into(), iteration: it })
        }
    }

    /// The mean contraction q of the residual per iteration over the last quarter of the
    /// history (at least 100 iterations), the residual's geometric mean rate there; `None`
    /// for a shorter history or a residual that did not fall.
    pub(crate) fn contraction(&self) -> Option<f64> {
        let (n, window) = (self.residuals.len(), self.residuals.len() / 4);
        if window < 100 {
            return None;
        }
        let (first, last) = (self.residuals[n - 1 - window], self.residuals[n - 1]);
        let q = (last / first).powf(1.0 / window as f64);
        (q < 1.0 && q > 0.0).then_some(q)
    }

    /// The report of an iteration that ended for `stop` after `iterations` with the last
    /// residuals `kkt` — converged exactly when `stop` is [`StopReason::Converged`] — with its
    /// `phases` and `counters` and no warnings.
    pub(crate) fn report(
        self,
        stop: StopReason,
        iterations: usize,
        kkt: KktResiduals,
        phases: Vec<(String, f64)>,
        counters: BTreeMap<String, f64>,
    ) -> SolveReport {
        SolveReport {
            solver: self.solver,
            converged: stop == StopReason::Converged,
            stop_reason: stop,
            iterations,
            tolerance: self.tol,
            kkt,
            residual_history: self.residuals,
            phases,
            counters,
            warnings: Vec::new(),
        }
    }
}
