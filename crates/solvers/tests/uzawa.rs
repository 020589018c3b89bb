//! The paper's Uzawa method: the metric and the extras' weight change the path, not the answer;
//! a step above the stable bound is detected early and named; an elastic problem costs one
//! factorisation and one solve pair per iteration. (Its return mappings are counted against the
//! yield surface's own count in `tests/return_mappings.rs`.)

use saddle_core::kkt;
use saddle_core::{DiscreteProblem, Silent, SolveError, Solver, StopReason, Workspace};
use saddle_solvers::{Uzawa, UzawaMetric};

mod common;

/// The default scene of theory §6 on a coarse graded mesh (elastic unless `plastic`).
fn johnson(plastic: bool) -> DiscreteProblem {
    common::johnson([10, 10, 5], plastic.then_some((1.0, 5.0)), common::SCALED)
}

fn uzawa() -> Uzawa {
    Uzawa { tol: 1e-10, ..Uzawa::default() }
}

#[test]
fn metric_and_extra_weight_change_the_path_not_the_solution() {
    let l = johnson(true);
    let reference = uzawa().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(reference.report.converged);
    assert!(reference.stress.n_plastic() > 0);
    let variants = [
        Uzawa { metric: UzawaMetric::Strain, rho: 1.5, max_iter: 100_000, ..uzawa() },
        Uzawa { extra_metric: 1.0, ..uzawa() },
    ];
    for v in variants {
        let sol = v.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{v:?}: {:?}", sol.report.stop_reason);
        let (u0, u1) = (reference.extras[0], sol.extras[0]);
        assert!((u0 - u1).abs() <= 1e-7 * u0, "{v:?}: U = {u1} vs {u0}");
        assert_eq!(sol.stress.n_plastic(), reference.stress.n_plastic());
        // the independently recomputed residual meets the tolerance
        assert!(kkt(&l.lagrangian(), &sol.iterate(), &mut Workspace::new(&l.lagrangian())).max() <= v.tol);
        // the paper's metric is the slow one: more iterations than the energy metric
        if v.metric == UzawaMetric::Strain {
            assert!(sol.report.iterations > reference.report.iterations);
        }
    }
}

#[test]
fn a_step_above_the_stable_bound_is_detected_early_and_named() {
    let l = johnson(true);
    match (Uzawa { rho: 2.5, ..uzawa() }).solve(&l.lagrangian(), &mut Silent) {
        Err(SolveError::Diverged { iteration, hint, .. }) => {
            assert!(iteration < 40, "detected late: {iteration}");
            assert!(hint.contains("solver.rho = 2.5") && hint.contains("bound 2"), "{hint}");
        }
        Err(e) => panic!("expected divergence, got {e}"),
        Ok(s) => panic!("expected divergence, got {:?} after {} iterations", s.report.stop_reason, s.report.iterations),
    }
    // just below the bound it still converges
    let sol = Uzawa { rho: 1.9, ..uzawa() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
}

#[test]
fn elastic_problems_cost_one_factorisation_and_one_solve_pair_per_iteration() {
    let l = johnson(false);
    let sol = uzawa().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    assert_eq!(sol.stress.n_plastic(), 0);
    // one analysis and one factorisation of M; one solve pair per iteration once the contact
    // rows are set up
    assert_eq!(sol.report.counters["symbolic_analyses"], 1.0);
    assert_eq!(sol.report.counters["factorisations"], 1.0);
    assert_eq!(sol.report.counters["triangular_solve_pairs"], sol.report.iterations as f64);
}

#[test]
fn the_iteration_budget_is_reported_not_hidden() {
    let l = johnson(true);
    let sol = Uzawa { max_iter: 2, ..uzawa() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(!sol.report.converged);
    assert_eq!(sol.report.stop_reason, StopReason::MaxIterations);
    assert!(sol.report.kkt.max() > 1e-10);
    assert_eq!(sol.report.residual_history.len(), 3);
}

#[test]
fn invalid_parameters_name_the_field() {
    for (u, field) in [
        (Uzawa { rho: -1.0, ..uzawa() }, "solver.rho"),
        (Uzawa { tol: 0.0, ..uzawa() }, "solver.tol"),
        (Uzawa { extra_metric: f64::NAN, ..uzawa() }, "solver.extra_metric"),
    ] {
        // validated once, where the parameters are read (a scene), not again by `solve`
        let e = u.validate("solver").expect_err("invalid parameters are an error");
        assert_eq!(e.field, field, "{e}");
    }
}
