//! Issue 5, cases 1–7: stiff and extreme variants of the default scene (SPEC §6, small mesh),
//! each run by every solver with a measured outcome. The full table (more values per case) is
//! `cargo run --release --example stability`, which rewrites the README's stability table.

use saddle::core::{P1P0Lagrangian, Silent, StopReason};
use saddle::output::Summary;
use saddle::scene::Scene;
use saddle::stability::solver_from;
use saddle::stability::{
    Outcome, all_solvers, first_yield_force, locking, run, scene, sliver_scene, unclamped_scene, units_check,
};
use std::path::Path;

fn f(x: f64) -> toml::Value {
    toml::Value::Float(x)
}

/// Runs `solver` on `text`; asserts it converged with the recomputed KKT residual within its
/// tolerance and returns the summary.
fn converged(text: &str, solver: &str) -> Box<Summary> {
    match run(text, solver).0 {
        Outcome::Returned { summary, recomputed_kkt, .. } => {
            assert!(
                summary.converged,
                "{solver}: stopped {:?} after {} iterations",
                summary.stop_reason, summary.iterations
            );
            assert_eq!(summary.stop_reason, StopReason::Converged);
            assert!(
                recomputed_kkt <= summary.tolerance,
                "{solver}: recomputed KKT {recomputed_kkt:e} > tolerance {:e}",
                summary.tolerance
            );
            assert!(summary.U.unwrap().is_finite());
            summary
        }
        other => panic!("{solver}: {other:?}"),
    }
}

/// Every solver converges on `text` and agrees with Newton's U to `rel`; returns Newton's summary.
fn all_agree(text: &str, solvers: &[String], rel: f64) -> Box<Summary> {
    let reference = converged(text, "newton");
    for s in solvers.iter().filter(|s| *s != "newton") {
        let u = converged(text, s).U.unwrap();
        let r = reference.U.unwrap();
        assert!(((u - r) / r).abs() <= rel, "{s}: U = {u:e}, Newton's {r:e}");
    }
    reference
}

/// The solvers without the slow SOCP (run on fewer variants to keep CI short).
fn fast_solvers() -> Vec<String> {
    all_solvers().into_iter().filter(|s| s != "socp").collect()
}

/// Case 1: h/E down to 1e-8 and h = 0 — all solvers converge and agree; h = 0 warns.
#[test]
fn near_perfect_plasticity() {
    for h_rel in [1e-2, 1e-8] {
        let s = all_agree(&scene(&[("yield.h", f(100.0 * h_rel))]), &fast_solvers(), 1e-6);
        assert!(s.plastic_elements > 0, "h/E = {h_rel}: the case must be plastic");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }
    let text = scene(&[("yield.h", f(0.0))]);
    let s = all_agree(&text, &all_solvers(), 1e-6);
    assert!(s.warnings.iter().any(|w| w.contains("yield.h = 0") && w.contains("unique")), "{:?}", s.warnings);
}

/// Case 2: ν → ½ converges with every solver; P1 locking is measured: the coarse mesh's U falls
/// further below the fine mesh's as ν → ½.
#[test]
fn near_incompressibility_and_locking() {
    all_agree(&scene(&[("material.nu", f(0.49))]), &fast_solvers(), 1e-6);
    all_agree(&scene(&[("material.nu", f(0.4999))]), &all_solvers(), 1e-6);
    let lock = locking(&[0.3, 0.4999]);
    let ratio = |i: usize| lock[i].1 / lock[i].2;
    assert!(ratio(0) > 0.9 && ratio(0) < 1.0, "ν = 0.3: coarse/fine = {}", ratio(0));
    assert!(ratio(1) < ratio(0) - 0.2, "ν = 0.4999 locks: coarse/fine = {} vs {}", ratio(1), ratio(0));
}

/// Case 3: stresses ×1e9 and lengths ×1e-3 scale u by 1e-3 and σ by 1e9 to 1e-9, with the same
/// iteration counts.
#[test]
fn units_scale_exactly() {
    for s in all_solvers() {
        let c = units_check(&s, 1e9, 1e-3).unwrap();
        assert_eq!(c.iterations, c.scaled_iterations, "{s}");
        assert!(c.u_deviation < 1e-9 && c.sigma_deviation < 1e-9, "{c:?}");
    }
}

/// Case 4: a tiny force touches at a node or two; a huge force reaches the rim of Γ₀ and warns.
#[test]
fn tiny_and_huge_loads() {
    let tiny = all_agree(&scene(&[("obstacle.F", f(0.3e-8))]), &fast_solvers(), 1e-6);
    assert!((1..=2).contains(&tiny.contact_nodes), "{} contact nodes", tiny.contact_nodes);
    let huge = scene(&[("obstacle.F", f(100.0 * first_yield_force(100.0, 0.3, 1.0, 5.0)))]);
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
    let flat: toml::Value = toml::from_str::<toml::Table>("v = { type = \"flat\" }").unwrap()["v"].clone();
    let s = all_agree(&scene(&[("obstacle.gap", flat)]), &all_solvers(), 1e-6);
    let ratio = s.contact["rim_pressure_ratio"];
    assert!(ratio > 1.1, "rim/mean pressure {ratio}");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// Case 6: the penalty at μ = 1e-14 reports its conditioning; Uzawa with ρ above 2 stops early
/// with an error naming the bound.
#[test]
fn tiny_penalty_and_unstable_uzawa_step() {
    let text = scene(&[]);
    let s = converged(&text, "type = \"penalty\"\nmu = 1e-14");
    let cond = s.counters["condition_estimate"];
    assert!(cond.is_finite() && cond > 1e13, "condition estimate {cond:e}");
    match run(&text, "type = \"uzawa\"\nrho = 2.5").0 {
        Outcome::SolveError(e) => {
            assert!(e.contains("diverged") && e.contains("stable bound 2"), "{e}");
            let at: usize = e.split("iteration ").nth(1).unwrap().split(':').next().unwrap().parse().unwrap();
            assert!(at <= 50, "divergence detected only at iteration {at}");
        }
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
        match run(&unclamped_scene(), &solver).0 {
            Outcome::SceneError(e) => assert!(e.contains("dirichlet") && e.contains("rigid-body motion"), "{e}"),
            other => panic!("{solver}: {other:?}"),
        }
    }
    // the same L assembled in code (no scene check): every solver returns a typed error
    let scene = Scene::from_toml(&unclamped_scene(), Path::new("unclamped.toml")).unwrap();
    let mesh = scene.mesh.build(Path::new(".")).unwrap();
    let l = P1P0Lagrangian::new(mesh, &[], scene.material, scene.yield_surface, scene.obstacle).unwrap();
    for solver in all_solvers() {
        let s = solver_from(&format!("type = \"{solver}\""));
        match s.solve(&l, &mut Silent) {
            Err(e) => assert!(!e.to_string().is_empty()),
            Ok(sol) => panic!("{solver}: an unrestrained body solved: converged = {}", sol.report.converged),
        }
    }
}
