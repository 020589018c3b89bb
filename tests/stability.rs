//! Issue 5, cases 1–7: stiff and extreme variants of the default scene (theory §6, small mesh),
//! each run by every solver with a measured outcome. The full table (more values per case) is
//! `cargo run --release --example stability`, which rewrites the table of docs/stability.md.
//!
//! The scenes and solvers are typed values ([`Johnson`] with one parameter changed); a case
//! that must fail is checked for its kind of error, so that a failure for another reason fails.

use saddle::core::P1P0Element;
use saddle::core::linalg::error::LinalgError;
use saddle::core::{DiscreteProblem, MeshSource, SceneError, Silent, SolveError, Solver, StopReason};
use saddle::io::summary::Summary;
use saddle::solvers::conformance::{Johnson, Setup, johnson_p2};
use saddle::studies::stability::{
    Outcome, P2_PERFECTLY_PLASTIC_FORCES, TRESCA_P2_FORCE, UNLOADING, all_solvers, default_solver, first_yield_force,
    newton_u, perfectly_plastic_p2, run, run_path, scene, sliver_scene, strongly_plastic, tiny_penalty, tresca_p2,
    unclamped_scene, units_check, unstable_uzawa,
};
use std::path::Path;

/// Runs `solver` on `scene`; asserts it converged with the recomputed KKT residual within its
/// tolerance and returns the summary.
fn converged(scene: &Setup, solver: &dyn Solver) -> Box<Summary> {
    let name = solver.name();
    match run(scene, solver).0 {
        Outcome::Returned { summary, recomputed_kkt, .. } => {
            assert!(
                summary.converged,
                "{name}: stopped {:?} after {} iterations",
                summary.stop_reason, summary.iterations
            );
            assert_eq!(summary.stop_reason, StopReason::Converged);
            assert!(
                recomputed_kkt <= summary.tolerance,
                "{name}: recomputed KKT {recomputed_kkt:e} > tolerance {:e}",
                summary.tolerance
            );
            assert!(summary.U.unwrap().is_finite());
            summary
        }
        other => panic!("{name}: {other:?}"),
    }
}

/// Every solver converges on `scene` and agrees with Newton's U to `rel`; returns Newton's summary.
fn all_agree(scene: &Setup, solvers: &[Box<dyn Solver>], rel: f64) -> Box<Summary> {
    let reference = converged(scene, default_solver("newton").as_ref());
    for s in solvers.iter().filter(|s| s.name() != "newton") {
        let u = converged(scene, s.as_ref()).U.unwrap();
        let r = reference.U.unwrap();
        assert!(((u - r) / r).abs() <= rel, "{}: U = {u:e}, Newton's {r:e}", s.name());
    }
    reference
}

/// The solvers without the slow SOCP (run on fewer variants to keep CI short).
fn fast_solvers() -> Vec<Box<dyn Solver>> {
    all_solvers().into_iter().filter(|s| s.name() != "socp").collect()
}

/// Case 1: h/E down to 1e-8 and h = 0 — all solvers converge and agree; h = 0 warns.
#[test]
fn near_perfect_plasticity() {
    for h_rel in [1e-2, 1e-8] {
        let s = all_agree(&Johnson { h: 100.0 * h_rel, ..Johnson::default() }.setup(), &fast_solvers(), 1e-6);
        assert!(s.plastic_elements > 0, "h/E = {h_rel}: the case must be plastic");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }
    let s = all_agree(&Johnson { h: 0.0, ..Johnson::default() }.setup(), &all_solvers(), 1e-6);
    assert!(s.warnings.iter().any(|w| w.contains("yield.h = 0") && w.contains("unique")), "{:?}", s.warnings);
}

/// Case 1 with P2 and h = 0 at the default force and beyond (issue 25): every solver converges
/// and agrees with Newton's U to 1e-6 (measured: the same 7 printed digits, U = 0.02528982 at
/// F = 1, 0.04387613 at F = 3), the plastic zone growing with the force.
#[test]
fn perfectly_plastic_p2_at_three_loads() {
    let mut plastic = vec![];
    for force in [0.3].into_iter().chain(P2_PERFECTLY_PLASTIC_FORCES) {
        let s = all_agree(&perfectly_plastic_p2(force), &all_solvers(), 1e-6);
        println!("F = {force}: U = {:?}, {} of {} elements plastic", s.U, s.plastic_elements, s.elements);
        plastic.push(s.plastic_elements);
    }
    assert!(plastic.windows(2).all(|w| w[0] < w[1]), "{plastic:?}");
}

/// Case 1 with Tresca (issue 25): P2, h = 0, F = 1 — newton, penalty and uzawa converge and
/// agree with Newton's U to 1e-6 (measured: U = 0.02553902 on all three, 144 of 648 elements
/// plastic); socp refuses Tresca (not a second-order cone) with a typed error.
#[test]
fn tresca_p2_with_perfect_plasticity() {
    let setup = tresca_p2(TRESCA_P2_FORCE);
    let solvers: Vec<_> = all_solvers().into_iter().filter(|s| s.name() != "socp").collect();
    let s = all_agree(&setup, &solvers, 1e-6);
    println!("Tresca: U = {:?}, {} of {} elements plastic", s.U, s.plastic_elements, s.elements);
    assert!(s.plastic_elements > 0);
    if cfg!(feature = "socp") {
        match run(&setup, default_solver("socp").as_ref()).0 {
            Outcome::SolveError(e) => assert!(matches!(*e, SolveError::Unsupported { .. }), "{e}"),
            other => panic!("socp on Tresca: {other:?}"),
        }
    }
}

/// Case 9 (issue 25): the small default scene loaded to F = 0.3 (path 0.4, 1) and unloaded to
/// 1 %, 0.1 % and 0 — every solver converges on every step, the recomputed residual within its
/// tolerance, and where the punch still carries a load its U agrees with Newton's to 1e-6.
#[test]
fn unloading_to_a_small_load() {
    for (label, last) in UNLOADING {
        let mut newton = None;
        let mut solvers = all_solvers();
        solvers.sort_by_key(|s| s.name() != "newton");
        for s in solvers {
            let name = s.name();
            let summary = match run_path(&scene(), &[0.4, 1.0, last], s.as_ref()) {
                Outcome::Returned { summary, recomputed_kkt, .. } => {
                    assert!(summary.converged, "{name}, unloaded to {label}: {:?}", summary.stop_reason);
                    assert!(recomputed_kkt <= summary.tolerance, "{name}, unloaded to {label}: KKT {recomputed_kkt:e}");
                    summary
                }
                other => panic!("{name}, unloaded to {label}: {other:?}"),
            };
            println!("{name}, unloaded to {label}: U = {:?}, {} iterations", summary.U, summary.iterations);
            if last > 0.0 {
                let (u, r) = (summary.U.unwrap(), *newton.get_or_insert(summary.U.unwrap()));
                assert!(((u - r) / r).abs() <= 1e-6, "{name}, unloaded to {label}: U = {u:e}, Newton's {r:e}");
            }
        }
    }
}

/// Case 2: ν → ½ converges with every solver; P1 locking is measured: the coarse mesh's U falls
/// further below the fine mesh's as ν → ½.
#[test]
fn near_incompressibility_and_locking() {
    all_agree(&Johnson { nu: 0.49, ..Johnson::default() }.setup(), &fast_solvers(), 1e-6);
    all_agree(&Johnson { nu: 0.4999, ..Johnson::default() }.setup(), &all_solvers(), 1e-6);
    let ratio = |nu: f64| newton_u(nu, [12, 12, 6], None) / newton_u(nu, [24, 24, 12], None);
    let (r3, r4999) = (ratio(0.3), ratio(0.4999));
    assert!(r3 > 0.9 && r3 < 1.0, "ν = 0.3: coarse/fine = {r3}");
    assert!(r4999 < r3 - 0.2, "ν = 0.4999 locks: coarse/fine = {r4999} vs {r3}");
    // P2 (B̄) on the nodes of the P1 mesh: every solver agrees at ν = 0.4999 (its locking
    // study is tests/p2.rs)
    all_agree(&Johnson { nu: 0.4999, ..johnson_p2() }.setup(), &all_solvers(), 1e-6);
}

/// Case 8: most of the body plastic (k₀ = 0.05): every solver converges and agrees with both
/// elements, and P1's answer is flagged as likely locked while P2's is not.
#[test]
fn strongly_plastic_with_both_elements() {
    let p1 = all_agree(&strongly_plastic(Johnson::default()), &all_solvers(), 1e-6);
    let p2 = all_agree(&strongly_plastic(johnson_p2()), &all_solvers(), 1e-6);
    assert!(p1.plastic_elements * 10 > p1.elements * 8, "{} of {}", p1.plastic_elements, p1.elements);
    let locked = |s: &Summary| s.warnings.iter().any(|w| w.contains("nearly incompressibly"));
    assert!(locked(&p1) && !locked(&p2), "{:?} / {:?}", p1.warnings, p2.warnings);
    // the locked P1 answer is stiffer: its U is well below P2's on the same nodes
    assert!(p1.U.unwrap() < 0.85 * p2.U.unwrap(), "U: p1 {:?}, p2 {:?}", p1.U, p2.U);
}

/// Case 3: stresses ×1e9 and lengths ×1e-3 scale u by 1e-3 and σ by 1e9 to 1e-9, with the same
/// iteration counts.
#[test]
fn units_scale_exactly() {
    for s in all_solvers() {
        let c = units_check(s.as_ref(), 1e9, 1e-3).unwrap();
        assert_eq!(c.iterations, c.scaled_iterations, "{}", s.name());
        assert!(c.u_deviation < 1e-9 && c.sigma_deviation < 1e-9, "{c:?}");
    }
}

/// Case 4: a tiny force touches at a node or two; a huge force reaches the rim of Γ₀ and warns.
#[test]
fn tiny_and_huge_loads() {
    let tiny = all_agree(&Johnson { force: 0.3e-8, ..Johnson::default() }.setup(), &fast_solvers(), 1e-6);
    assert!((1..=2).contains(&tiny.contact_nodes), "{} contact nodes", tiny.contact_nodes);
    let huge = Johnson { force: 100.0 * first_yield_force(100.0, 0.3, 1.0, 5.0), ..Johnson::default() }.setup();
    let s = all_agree(&huge, &fast_solvers(), 1e-6);
    assert!(
        s.warnings.iter().any(|w| w.contains("rim of obstacle.zone") && w.contains("too small")),
        "{:?}",
        s.warnings
    );
}

/// Case 5: the flat punch converges with every solver; its pressure concentrates at the edge
/// (rim pressure over mean > 1), and no "zone too small" warning (the zone is the punch face).
#[test]
fn flat_punch() {
    let flat = Johnson { gap: Box::new(saddle::contact::Flat::default()), ..Johnson::default() }.setup();
    let s = all_agree(&flat, &all_solvers(), 1e-6);
    let ratio = s.contact["rim_pressure_ratio"];
    assert!(ratio > 1.1, "rim/mean pressure {ratio}");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// Case 6: the penalty at μ = 1e-14 reports its conditioning; Uzawa with ρ above 2 stops early
/// with the divergence error naming the bound it broke.
#[test]
fn tiny_penalty_and_unstable_uzawa_step() {
    let scene = scene();
    let s = converged(&scene, tiny_penalty().solver.as_ref());
    let cond = s.counters["condition_estimate"];
    assert!(cond.is_finite() && cond > 1e13, "condition estimate {cond:e}");
    match run(&scene, unstable_uzawa().solver.as_ref()).0 {
        Outcome::SolveError(e) => match e.as_ref() {
            SolveError::Diverged { solver, iteration, residual, hint } => {
                assert_eq!(solver, "uzawa");
                assert!(
                    hint.contains("solver.rho = 2.5 is at or above the stable bound 2") && hint.contains("rho < 2"),
                    "{hint}"
                );
                assert!(*iteration <= 50, "divergence detected only at iteration {iteration}");
                assert!(residual.is_finite(), "{e}");
            }
            other => panic!("ρ = 2.5 must be reported as divergence, not: {other}"),
        },
        other => panic!("ρ = 2.5 must be reported as divergence: {other:?}"),
    }
}

/// Case 7: slivers of aspect ratio ~100 converge (quality reported and warned); a body with no
/// clamped node is a typed error for every solver, not a singular-matrix panic.
#[test]
fn slivers_and_unclamped_body() {
    let s = all_agree(&sliver_scene(), &fast_solvers(), 1e-6);
    assert!(s.mesh_quality.max_aspect_ratio > 90.0, "aspect ratio {}", s.mesh_quality.max_aspect_ratio);
    assert!(s.warnings.iter().any(|w| w.contains("aspect ratio")), "{:?}", s.warnings);
    for solver in all_solvers() {
        match run(&unclamped_scene(), solver.as_ref()).0 {
            Outcome::SceneError(e) => match e.as_ref() {
                SceneError::Region { field, message } => {
                    assert_eq!(field, "dirichlet", "{e}");
                    assert!(
                        message.contains("rigid-body motion free (a translation along")
                            || message.contains("rigid-body motion free (a rotation about"),
                        "{e}"
                    );
                }
                other => panic!("{}: the scene error must name the free rigid-body motion: {other}", solver.name()),
            },
            other => panic!("{}: {other:?}", solver.name()),
        }
    }
    // the same L assembled in code (no scene check): every solver reports the singular
    // stiffness as a typed linear-algebra error naming itself, not a panic or a NaN
    let scene = unclamped_scene();
    let mesh = scene.mesh.build(Path::new(".")).unwrap();
    let l = DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &[]).unwrap()),
        scene.elasticity,
        scene.stresses,
        scene.obstacles,
        &[],
    )
    .unwrap();
    for solver in all_solvers() {
        match solver.solve(&l.lagrangian(), &mut Silent) {
            Err(SolveError::LinearAlgebra { solver: name, source }) => {
                assert_eq!(name, solver.name());
                match source.downcast_ref::<LinalgError>() {
                    Some(LinalgError::NotPositiveDefinite { n, .. }) => assert_eq!(*n, l.element.n_dofs(), "{source}"),
                    _ => panic!("{name}: the singular stiffness must be reported as such: {source}"),
                }
            }
            Err(e) => panic!("{}: the singular stiffness must be a linear-algebra error, not: {e}", solver.name()),
            Ok(sol) => panic!("{}: an unrestrained body solved: converged = {}", solver.name(), sol.report.converged),
        }
    }
}
