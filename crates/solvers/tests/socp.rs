#![cfg(feature = "socp")]
//! The conic solver (theory §3 form 3, §4): the closed form of theory §7, agreement with Newton on
//! the default scene, the QP of an elastic problem, the signs of the displacements read from
//! the equality duals, invariance to units, perfect plasticity, and parameter errors.

use saddle_contact::{Flat, RigidPunch};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::tensor::{Sym, deviator};
use saddle_core::{
    BoxMesh, Dirichlet, DiscreteProblem, Region, Silent, Solution, SolveError, Solver, StopReason, StressField,
    Workspace, contact_set,
};
use saddle_core::{P1P0Element, kkt, stress_energy};
use saddle_solvers::{Newton, Socp};
use saddle_yield::VonMises;
use saddle_yield::mutant::Mutant;

mod common;
use common::{SCALED, Units, homogeneous, johnson};

/// The plastic default scene (k₀ = 1, h = 5) on the small mesh [10, 10, 5].
fn small_johnson() -> DiscreteProblem {
    johnson([10, 10, 5], Some((1.0, 5.0)), SCALED)
}

/// Newton to 1e-12: the reference.
fn newton(l: &DiscreteProblem) -> Solution {
    let sol = Newton { tol: 1e-12, max_iter: 60, line_search: true, ..Newton::default() }
        .solve(&l.lagrangian(), &mut Silent)
        .unwrap();
    assert!(sol.report.converged, "reference Newton: {:?}", sol.report.stop_reason);
    sol
}

/// [σ̂ − σ̂_ref]^{1/2} / [σ̂_ref]^{1/2} (theory §5).
fn energy_error(l: &DiscreteProblem, s: &StressField, reference: &StressField) -> f64 {
    let mut d = reference.clone();
    for (a, b) in d.sigma.iter_mut().zip(&s.sigma) {
        *a -= b;
    }
    for (a, b) in d.q.iter_mut().zip(&s.q) {
        *a -= b;
    }
    (stress_energy(&l.lagrangian(), &d) / stress_energy(&l.lagrangian(), reference)).sqrt()
}

/// ‖a − b‖ / ‖b‖.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den).sqrt()
}

fn print_report(tag: &str, sol: &Solution) {
    let r = &sol.report;
    eprintln!(
        "{tag}: converged {} ({:?}), iterations {}, KKT {:.2e}, history {:?}",
        r.converged,
        r.stop_reason,
        r.iterations,
        r.kkt.max(),
        r.residual_history
    );
    eprintln!("{tag}: phases {:?}", r.phases);
    eprintln!("{tag}: counters {:?}", r.counters);
}

#[test]
fn homogeneous_compression_matches_the_closed_form() {
    // theory §7 with E = 100, ν = 0.3, k₀ = 1, h = 5; first yield at F = sqrt(3/2)
    let (e, k0, h) = (100.0, 1.0, 5.0);
    for f in [2.0, 1.0] {
        let l = homogeneous(f);
        let sol = Socp::default().solve(&l.lagrangian(), &mut Silent).unwrap();
        print_report(&format!("homogeneous F = {f}"), &sol);
        assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
        let s_norm = (2.0f64 / 3.0).sqrt() * f;
        let (mut e33, mut xi) = (-f / e, 0.0);
        if s_norm > k0 {
            let p = (s_norm - k0) / h;
            e33 += p * (-2.0 * f / 3.0) / s_norm;
            xi = h * p;
        }
        let u_exact = -e33;
        let u = sol.extras[0];
        assert!((u - u_exact).abs() <= 1e-8 * u_exact, "F = {f}: U = {u:.12e}, closed form {u_exact:.12e}");
        let exact = Sym::new(0.0, 0.0, -f, 0.0, 0.0, 0.0);
        for (i, s) in sol.stress.sigma.iter().enumerate() {
            assert!((s - exact).norm() <= 1e-8 * f, "F = {f}, element {i}: σ = {s:?}");
            assert!((sol.stress.q(i)[0] - xi).abs() <= 1e-8 * f, "F = {f}, element {i}: ξ = {}", sol.stress.q(i)[0]);
        }
        assert_eq!(sol.stress.n_plastic(), if xi > 0.0 { l.element.n_points() } else { 0 });
    }
}

#[test]
fn small_default_scene_agrees_with_newton() {
    let l = small_johnson();
    let reference = newton(&l);
    let sol = Socp::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    print_report("small default scene", &sol);
    let r = &sol.report;
    assert!(r.converged && r.kkt.max() <= 1e-10, "{:?}, KKT {:e}", r.stop_reason, r.kkt.max());
    assert_eq!(r.solver, "socp");
    // the recomputed residual meets the tolerance
    assert!(kkt(&l.lagrangian(), &sol.iterate(), &mut Workspace::new(&l.lagrangian())).max() <= 1e-10);
    let (u0, u1) = (reference.extras[0], sol.extras[0]);
    assert!((u1 - u0).abs() <= 1e-8 * u0, "U = {u1:.12e} vs Newton {u0:.12e}");
    let es = energy_error(&l, &sol.stress, &reference.stress);
    assert!(es <= 1e-7, "energy-norm stress difference {es:e}");
    assert_eq!(contact_set(&sol.lambda), contact_set(&reference.lambda));
    assert_eq!(sol.stress.plastic, reference.stress.plastic);
    assert!(sol.stress.n_plastic() > 0);
    // the report: interior point numbers, then polishing
    let c = &r.counters;
    assert!(c["ipm_iterations"] >= 5.0 && c["ipm_status"] == 1.0, "{c:?}");
    assert!(c["ipm_duality_gap"] >= 0.0 && c["ipm_relative_gap"] <= 10.0 * Socp::default().ipm_tol, "{c:?}");
    assert!(c["ipm_kkt_residual"] > 1e-9, "the interior point alone is not that accurate: {c:?}");
    assert!(c["polish_iterations"] >= 1.0);
    assert_eq!(r.iterations, (c["ipm_iterations"] + c["polish_iterations"]) as usize);
    assert_eq!(r.residual_history[0], c["ipm_kkt_residual"]);
    assert_eq!(r.residual_history.len(), c["polish_iterations"] as usize + 2);
    assert!(c.contains_key("factorisations"), "Newton's counters are kept");
    let phases: Vec<&str> = r.phases.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(&phases[..2], &["cone programme", "interior point"]);
    assert!(phases.contains(&"factorisation and solves"), "{phases:?}");
}

#[test]
fn ipm_displacements_from_the_equality_duals_have_the_right_sign() {
    // u = −z_eq, V = −z_load: the interior point solution alone, before polishing, against Newton
    let l = small_johnson();
    let reference = newton(&l);
    let sol = Socp { polish: false, ipm_tol: 1e-8, ..Socp::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    print_report("IPM only", &sol);
    let (u0, u1) = (reference.extras[0], sol.extras[0]);
    eprintln!(
        "IPM only: U {u1:.10e} vs {u0:.10e} ({:.2e}); u {:.2e}; λ {:.2e}; σ̂ {:.2e}",
        (u1 - u0).abs() / u0,
        rel(&sol.u, &reference.u),
        rel(&sol.lambda, &reference.lambda),
        energy_error(&l, &sol.stress, &reference.stress)
    );
    assert!(u1 > 0.0 && (u1 - u0).abs() <= 1e-5 * u0, "U = {u1:e} vs Newton {u0:e}");
    assert!(rel(&sol.u, &reference.u) <= 1e-4);
    assert!(rel(&sol.lambda, &reference.lambda) <= 1e-4);
    assert!(energy_error(&l, &sol.stress, &reference.stress) <= 1e-4);
    // honest: not polished, so not converged to 1e-10, and it says why
    let r = &sol.report;
    assert!(!r.converged && r.kkt.max() > 1e-10);
    assert_eq!(r.residual_history, vec![r.counters["ipm_kkt_residual"]]);
    assert_eq!(r.counters["polish_iterations"], 0.0);
    assert_eq!(r.iterations, r.counters["ipm_iterations"] as usize);
    // a loose tolerance is met by the interior point alone
    let loose = Socp { polish: false, tol: 1e-3, ipm_tol: 1e-8, ..Socp::default() }
        .solve(&l.lagrangian(), &mut Silent)
        .unwrap();
    assert!(loose.report.converged);
}

#[test]
fn elastic_scene_is_a_qp() {
    // Hertz-like: no yield, the programme has no cones beyond λ ≥ 0
    let l = johnson([10, 10, 5], None, SCALED);
    let reference = newton(&l);
    let sol = Socp::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    print_report("elastic", &sol);
    assert!(sol.report.converged);
    assert_eq!(sol.report.counters["ipm_soc_cones"], 0.0);
    assert_eq!(sol.stress.q.dim(), 0);
    assert_eq!(sol.stress.n_plastic(), 0);
    let (u0, u1) = (reference.extras[0], sol.extras[0]);
    assert!((u1 - u0).abs() <= 1e-8 * u0, "U = {u1:e} vs {u0:e}");
    assert!(energy_error(&l, &sol.stress, &reference.stress) <= 1e-7);
    assert_eq!(contact_set(&sol.lambda), contact_set(&reference.lambda));
}

#[test]
fn results_do_not_depend_on_the_units() {
    // stresses × 1e9, lengths × 1e-3 (forces × 1e3): U scales by 1e-3, σ by 1e9, same iterations
    let units = Units { stress: 1e9, length: 1e-3 };
    let (a, b) = (johnson([6, 6, 3], Some((1.0, 5.0)), SCALED), johnson([6, 6, 3], Some((1.0, 5.0)), units));
    for polish in [false, true] {
        let s = Socp { polish, ..Socp::default() };
        let (sa, sb) = (s.solve(&a.lagrangian(), &mut Silent).unwrap(), s.solve(&b.lagrangian(), &mut Silent).unwrap());
        print_report("units 1", &sa);
        print_report("units 2", &sb);
        let (ua, ub) = (sa.extras[0], sb.extras[0] / units.length);
        let tol = if polish { 1e-9 } else { 1e-7 };
        assert!((ua - ub).abs() <= tol * ua, "polish {polish}: U {ua:.12e} vs {ub:.12e}");
        let sigma_b: Vec<f64> = sb.stress.sigma.iter().flat_map(|s| s.iter().map(|x| x / units.stress)).collect();
        let sigma_a: Vec<f64> = sa.stress.sigma.iter().flat_map(|s| s.iter().copied()).collect();
        assert!(rel(&sigma_b, &sigma_a) <= tol, "polish {polish}: σ {:e}", rel(&sigma_b, &sigma_a));
        let (ca, cb) = (&sa.report.counters, &sb.report.counters);
        assert_eq!(ca["ipm_iterations"], cb["ipm_iterations"]);
        assert_eq!(ca["polish_iterations"], cb["polish_iterations"]);
        assert!((ca["ipm_relative_gap"] - cb["ipm_relative_gap"]).abs() <= 1e-3 * ca["ipm_relative_gap"].max(1e-12));
        assert_eq!(sa.report.converged, sb.report.converged);
    }
}

#[test]
fn perfect_plasticity_fixes_the_hardening_variable() {
    // h = 0: ξ has an infinite metric and is fixed at 0; |dev σ| ≤ k₀ everywhere
    let l = johnson([8, 8, 4], Some((1.0, 0.0)), SCALED);
    let sol = Socp::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    print_report("h = 0", &sol);
    assert_eq!(sol.report.counters["ipm_fixed_hardening_variables"], 1.0);
    assert!(sol.stress.q.iter().all(|q| *q == 0.0));
    assert!(sol.stress.sigma.iter().all(|s| deviator(s).norm() <= 1.0 + 1e-8));
    assert!(sol.stress.n_plastic() > 0);
    // the stresses are unique even at h = 0 (theory §1): the interior point ones agree
    let ipm = Socp { polish: false, ipm_tol: 1e-8, ..Socp::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(energy_error(&l, &ipm.stress, &sol.stress) <= 1e-4);
    assert!(sol.report.converged, "{:?}: KKT {:e}", sol.report.stop_reason, sol.report.kkt.max());
}

#[test]
fn a_yield_surface_without_cones_is_unsupported() {
    let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
    let l = DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap()),
        Elasticity::new(100.0, 0.3).unwrap(),
        Some(Box::new(Mutant::of(VonMises::new(1.0, 5.0).unwrap()).with_cone(|_| None))),
        saddle_core::Obstacles::one(Box::new(
            RigidPunch::new(1.0, Region::Group("zmin".into()), Box::new(Flat::default())).unwrap(),
        )),
        &[],
    )
    .unwrap();
    match Socp::default().solve(&l.lagrangian(), &mut Silent) {
        Err(SolveError::Unsupported { solver, message }) => {
            assert_eq!(solver, "socp");
            assert!(message.contains("von_mises") && message.contains("cone"), "{message}");
        }
        other => panic!("expected Unsupported, got {:?}", other.map(|s| s.report)),
    }
}

#[test]
fn invalid_parameters_name_the_field() {
    for (s, field, value) in [
        (Socp { tol: 0.0, ..Socp::default() }, "solver.tol", "0"),
        (Socp { tol: f64::NAN, ..Socp::default() }, "solver.tol", "NaN"),
        (Socp { ipm_tol: -1e-8, ..Socp::default() }, "solver.ipm_tol", "-0.00000001"),
        (Socp { ipm_max_iter: 0, ..Socp::default() }, "solver.ipm_max_iter", "0"),
        (Socp { polish_max_iter: 0, ..Socp::default() }, "solver.polish_max_iter", "0"),
        (Socp { coulomb_tol: 1.5, ..Socp::default() }, "solver.coulomb_tol", "1.5"),
        (Socp { coulomb_max_iter: 0, ..Socp::default() }, "solver.coulomb_max_iter", "0"),
        (Socp { threads: usize::MAX, ..Socp::default() }, "solver.threads", &usize::MAX.to_string()),
    ] {
        let e = s.validate("solver").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), (field, value), "{e}");
    }
    // from TOML: defaults, and unknown fields rejected
    let s: Box<dyn Solver> = toml::from_str("type = \"socp\"").unwrap();
    assert_eq!((s.name(), s.tolerance()), ("socp", 1e-10));
    let s: Box<dyn Solver> = toml::from_str("type = \"socp\"\ntol = 1e-9\npolish = false\nthreads = 2").unwrap();
    assert_eq!(s.tolerance(), 1e-9);
    let err = toml::from_str::<Box<dyn Solver>>("type = \"socp\"\nipm_tolerance = 1e-9").unwrap_err();
    assert!(err.to_string().contains("ipm_tolerance"), "{err}");
}

#[test]
fn an_interior_point_cut_short_is_reported_and_polished() {
    // Clarabel stopped after 3 iterations: status MaxIterations (7), with a warning
    let l = small_johnson();
    let warned =
        |s: &saddle_core::Solution| s.report.warnings.iter().any(|w| w.contains("ended MaxIterations (status 7)"));
    let raw = Socp { ipm_max_iter: 3, polish: false, ..Socp::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    let r = &raw.report;
    assert!(!r.converged && r.stop_reason == StopReason::MaxIterations);
    assert_eq!(r.counters["ipm_status"], 7.0);
    assert!(warned(&raw), "{:?}", r.warnings);
    assert!(r.kkt.max() > 1e-2);
    // polishing still starts from that iterate; Newton's budget decides
    let short =
        Socp { ipm_max_iter: 3, polish_max_iter: 2, ..Socp::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(!short.report.converged && short.report.stop_reason == StopReason::MaxIterations);
    assert!(warned(&short));
    let sol = Socp { ipm_max_iter: 3, ..Socp::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    print_report("cut short, polished", &sol);
    assert!(sol.report.converged && warned(&sol));
    assert!(sol.report.counters["polish_iterations"] > 3.0);
}
