//! The `return_mappings` counter of every solver is the number of return mappings that ran,
//! measured by the yield surface itself ([`common::Counting`] counts its calls), not by the
//! solver's bookkeeping; and an elastic scene (an unbounded P) runs none at all.

use saddle_core::{AdmissibleStresses, Silent, Solution, Solver};
use saddle_solvers::{LinearSolver, Newton, Penalty, Socp, Uzawa};
use saddle_yield::{Elastic, VonMises};
use std::sync::atomic::Ordering;

mod common;
use common::Counting;

/// Every solver, and the Newton backends separately.
fn solvers() -> Vec<(&'static str, Box<dyn Solver>)> {
    vec![
        ("uzawa", Box::new(Uzawa { tol: 1e-10, ..Uzawa::default() })),
        ("newton direct", Box::new(Newton { linear: LinearSolver::Direct, ..Newton::default() })),
        ("newton amg", Box::new(Newton { linear: LinearSolver::Amg, ..Newton::default() })),
        ("penalty", Box::new(Penalty::default())),
        ("socp", Box::new(Socp::default())),
    ]
}

/// Solves the default scene with P = `p` counted by each solver: the solution and the return
/// mappings P saw.
fn solve_counted(p: impl Fn() -> Box<dyn AdmissibleStresses>) -> Vec<(&'static str, Solution, usize)> {
    solvers()
        .into_iter()
        .map(|(name, solver)| {
            let (p, calls) = Counting::wrap(p());
            let l = common::johnson_yield([8, 8, 4], p);
            let sol = solver.solve(&l.lagrangian(), &mut Silent).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(sol.report.converged, "{name}: {:?}", sol.report.stop_reason);
            (name, sol, calls.load(Ordering::Relaxed))
        })
        .collect()
}

#[test]
fn every_return_mapping_is_counted() {
    for (name, sol, calls) in solve_counted(|| Box::new(VonMises::new(1.0, 5.0).unwrap())) {
        assert!(sol.stress.n_plastic() > 0, "{name}: the scene must yield");
        assert!(calls > 0, "{name}");
        assert_eq!(sol.report.counters["return_mappings"], calls as f64, "{name}: counter against P's own count");
    }
}

#[test]
fn elastic_scene_runs_no_return_mapping() {
    for (name, sol, calls) in solve_counted(|| Box::new(Elastic {})) {
        assert_eq!(calls, 0, "{name}: P's local law or projection ran");
        assert_eq!(sol.report.counters["return_mappings"], 0.0, "{name}");
        assert_eq!(sol.stress.n_plastic(), 0, "{name}");
    }
}
