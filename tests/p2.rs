//! The locking-free element (issue 15, theory §10): `[discretisation] type = "p2"` reproduces
//! Prandtl's limit load of a flat strip punch where P1 keeps rising, and keeps its accuracy as
//! ν → ½ where P1 loses half of the displacement.

mod common;
use common::*;
use saddle::core::{Silent, Solver};
use saddle::io::summary::Summary;

/// Prandtl's limit force on the strip of `examples/strip_punch.toml`: (2 + π) k B t with
/// k = k₀/√2 = 1/√2, B = 1, thickness t = 0.25 (theory §10).
fn prandtl_force() -> f64 {
    (2.0 + std::f64::consts::PI) / 2f64.sqrt() * 0.25
}

/// The strip punch on a coarse mesh (32 × 1 × 16 cells) with `element` at punch displacement u.
fn strip(element: &str, u: f64) -> toml::Table {
    let mut t = example("strip_punch.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([32, 1, 16]).unwrap());
    set(&mut t, "obstacle.U", toml::Value::Float(u));
    let mut d = toml::Table::new();
    d.insert("type".into(), toml::Value::String(element.into()));
    t.insert("discretisation".into(), toml::Value::Table(d));
    t
}

/// The summary of a converged solve.
fn solve(t: &toml::Table) -> Summary {
    let (l, solver) = build(t);
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    Summary::new(l.view(), &sol, None)
}

/// Whether a summary carries the locking warning.
fn warns_of_locking(s: &Summary) -> bool {
    s.warnings.iter().any(|w| w.contains("nearly incompressibly") && w.contains("type = \"p2\""))
}

#[test]
fn p2_strip_punch_reaches_prandtls_limit_where_p1_keeps_rising() {
    let f = prandtl_force();
    let (s2_1, s2_2) = (solve(&strip("p2", 0.1)), solve(&strip("p2", 0.2)));
    let (s1_1, s1_2) = (solve(&strip("p1", 0.1)), solve(&strip("p1", 0.2)));
    let [p2_1, p2_2, p1_1, p1_2] = [&s2_1, &s2_2, &s1_1, &s1_2].map(|s| s.force.unwrap());
    println!("Prandtl {f:.4}; p2 {p2_1:.4} {p2_2:.4}; p1 {p1_1:.4} {p1_2:.4}");
    // p2: a plateau (doubling U changes the force by < 0.1 %) within 3 % of Prandtl (the issue
    // asks 10 % on a coarse mesh; measured +1.2 %)
    assert!((p2_2 / f - 1.0).abs() < 0.03, "p2 plateau {p2_2} against Prandtl {f}");
    assert!((p2_2 / p2_1 - 1.0).abs() < 1e-3, "p2 force still changing: {p2_1} → {p2_2}");
    // p1 on the same mesh locks: far above the limit and still rising
    assert!(p1_2 > 1.3 * f && p1_2 > 1.05 * p1_1, "p1 {p1_1} → {p1_2} against Prandtl {f}");
    // the locking indicator fires for p1 (most of the strip flows plastically with h = 0), and
    // not for p2, which does not lock
    println!(
        "near-incompressible fraction: p1 {:.2}, p2 {:.2}",
        s1_2.near_incompressible_fraction, s2_2.near_incompressible_fraction
    );
    assert!(s1_2.near_incompressible_fraction > 0.5 && warns_of_locking(&s1_2), "{:?}", s1_2.warnings);
    assert!(!warns_of_locking(&s2_2), "{:?}", s2_2.warnings);
}

#[test]
fn the_locking_indicator_is_quiet_on_the_default_scene() {
    // the plastic zone under the punch is under 1 % of the volume, the rest elastic with
    // ν = 0.3: no warning (P1 and P2 agree there to 1.3 % in U)
    let s = solve(&small_johnson());
    assert!(
        s.near_incompressible_fraction < 0.1 && !warns_of_locking(&s),
        "{} {:?}",
        s.near_incompressible_fraction,
        s.warnings
    );
}

/// The elastic default scene (small family, no yield surface) at ν = 0.4999: U with `element`
/// on `cells`.
fn incompressible_u(element: &str, cells: [usize; 3]) -> f64 {
    let mut t = small_johnson();
    t.remove("yield");
    set(&mut t, "material.nu", toml::Value::Float(0.4999));
    set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
    let mut d = toml::Table::new();
    d.insert("type".into(), toml::Value::String(element.into()));
    t.insert("discretisation".into(), toml::Value::Table(d));
    let (l, _) = build(&t);
    let newton = saddle::solvers::Newton { linear: saddle::solvers::LinearSolver::Direct, ..Default::default() };
    let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    assert_eq!(l.lagrangian().n_extras(), 1);
    sol.extras[0]
}

#[test]
fn p2_keeps_its_displacement_as_nu_tends_to_one_half() {
    // the small default mesh 12 × 12 × 6 against 16 × 16 × 8 cells: P2 within 5 %, P1 loses
    // much more (docs/locking.md: 12 × 12 × 6 against 24 × 24 × 12, P2 0.998)
    let p2 = incompressible_u("p2", [12, 12, 6]) / incompressible_u("p2", [16, 16, 8]);
    let p1 = incompressible_u("p1", [12, 12, 6]) / incompressible_u("p1", [16, 16, 8]);
    println!("U coarse / fine at ν = 0.4999: p2 {p2:.3}, p1 {p1:.3}");
    assert!((0.95..=1.05).contains(&p2), "p2 {p2}");
    assert!(p1 < 0.8, "p1 {p1}");
}

#[test]
fn both_newton_backends_solve_p2_alike() {
    // the default scene with P2 on 6×6×3 cells (the kit's), direct against multigrid
    let l = saddle::solvers::conformance::johnson_p2().problem();
    let solve = |linear| {
        let newton = saddle::solvers::Newton { linear, tol: 1e-11, ..Default::default() };
        let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{linear:?}: {:?}", sol.report.stop_reason);
        (sol.extras[0], sol.report.iterations, sol.report.counters.get("pcg_iterations").copied().unwrap_or(0.0))
    };
    let (u_d, it_d, _) = solve(saddle::solvers::LinearSolver::Direct);
    let (u_a, it_a, cg) = solve(saddle::solvers::LinearSolver::Amg);
    println!("direct: U {u_d:.9e}, {it_d} iterations; amg: U {u_a:.9e}, {it_a} iterations, {cg} CG iterations");
    assert!((u_a - u_d).abs() <= 1e-8 * u_d.abs(), "{u_a} vs {u_d}");
    assert!(cg > 0.0, "the multigrid backend ran CG");
}

#[test]
fn the_multigrid_that_follows_the_plastic_tangent_needs_fewer_cg_iterations_for_the_same_answer() {
    // the perfectly plastic strip (h = 0) with P2, past first yield: the tangent is nearly
    // incompressible in the plastic zone, where the elastic hierarchy no longer approximates it
    let strip_t = strip("p2", 0.02);
    let solve = |linear, amg_refresh_cg| {
        let (_, force, cg, refreshes) = newton_counts(
            &strip_t,
            saddle::solvers::Newton { linear, amg_refresh_cg, max_iter: 200, ..Default::default() },
        );
        (force, cg, refreshes)
    };
    let (f_direct, _, _) = solve(saddle::solvers::LinearSolver::Direct, 0);
    let (f_elastic, cg_elastic, r_elastic) = solve(saddle::solvers::LinearSolver::Amg, usize::MAX);
    let (f_follow, cg_follow, r_follow) =
        solve(saddle::solvers::LinearSolver::Amg, saddle::solvers::newton::AMG_REFRESH_CG);
    println!(
        "force: direct {f_direct:.10}, elastic multigrid {f_elastic:.10}, following {f_follow:.10}; CG per solve \
         {cg_elastic:.1} → {cg_follow:.1} ({r_follow} refreshes)"
    );
    // the stresses are unique at h = 0 (theory §1), so is the force: Newton's tol 1e-10
    for f in [f_elastic, f_follow] {
        assert!((f - f_direct).abs() <= 1e-8 * f_direct, "{f} vs {f_direct}");
    }
    assert_eq!(r_elastic, 0.0);
    assert!(r_follow > 0.0);
    assert!(cg_follow < 0.6 * cg_elastic, "{cg_follow} against {cg_elastic}");
}

#[test]
fn auto_above_its_size_threshold_prices_the_plastic_tangent_and_factorises_it() {
    // `auto` above `auto_amg_dofs` takes the multigrid unanalysed; on the perfectly plastic
    // strip (quasi-2D: a cheap factor) CG spends the iterations the size rule stood for, and
    // the deferred analysis prices the direct path below what CG already spent (theory §4.2)
    let (l, _) = build(&strip("p2", 0.02));
    let solve = |linear, auto_amg_dofs| {
        let newton = saddle::solvers::Newton { linear, auto_amg_dofs, max_iter: 200, ..Default::default() };
        let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{linear:?}: {:?}", sol.report.stop_reason);
        let c = sol.report.counters.clone();
        (Summary::new(l.view(), &sol, None).force.unwrap(), move |k: &str| c.get(k).copied())
    };
    let (f_direct, _) = solve(saddle::solvers::LinearSolver::Direct, 0);
    let (f_amg, amg) = solve(saddle::solvers::LinearSolver::Amg, 0);
    let (f_auto, auto) = solve(saddle::solvers::LinearSolver::Auto, 1000);
    let cg = |c: &dyn Fn(&str) -> Option<f64>| c("pcg_iterations").unwrap();
    println!(
        "force: direct {f_direct:.10}, amg {f_amg:.10}, auto {f_auto:.10}; CG amg {}, auto {}",
        cg(&amg),
        cg(&auto)
    );
    // the stresses, hence the force, are unique at h = 0 (theory §1): Newton's tol 1e-10
    assert!((f_auto - f_direct).abs() <= 1e-8 * f_direct, "{f_auto} vs {f_direct}");
    assert_eq!(auto("symbolic_analyses"), Some(1.0), "analysed once, when due");
    assert_eq!(auto("auto_switched_to_direct"), Some(1.0));
    let (direct, multigrid) = (auto("auto_direct_cost").unwrap(), auto("auto_amg_cost").unwrap());
    assert!(direct < multigrid, "the factor of a quasi-2D strip is cheap: {direct:e} against {multigrid:e}");
    // not before the iterations of the size rule's multigrid solve …
    assert!(cg(&auto) >= saddle::solvers::active_set::analysis_due(0.3), "{}", cg(&auto));
    // … and it stops renting the multigrid there (measured: 349 CG iterations against 626)
    assert!(cg(&auto) < 0.8 * cg(&amg), "{} against {}", cg(&auto), cg(&amg));
}

#[test]
fn auto_above_its_size_threshold_never_analyses_a_tangent_the_multigrid_approximates() {
    // the default scene with P2 (the kit's 6×6×3 cells, hardening h = 5): CG stays far below the
    // iterations of the size rule's multigrid solve, so the analysis is never paid for
    let l = saddle::solvers::conformance::johnson_p2().problem();
    let newton = saddle::solvers::Newton { auto_amg_dofs: 100, ..Default::default() };
    let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    let c = &sol.report.counters;
    println!("CG {:?}, analyses {:?}", c.get("pcg_iterations"), c.get("symbolic_analyses"));
    assert!(c["pcg_iterations"] > 0.0 && c["pcg_iterations"] < saddle::solvers::active_set::analysis_due(0.3));
    assert_eq!(c["symbolic_analyses"], 0.0);
    assert_eq!(c["auto_switched_to_direct"], 0.0);
}

/// The plain Uzawa (`acceleration = "none"`) on the perfectly plastic P2 strip at 5×
/// (U = 0.05): the projected gradient contracts by 0.99966 per iteration at the end of its
/// 20,000 (KKT 5.7e-6; theory §4.1, the rate), too slowly for any budget; stopped after 2,000
/// iterations it says so, with the rate and the solvers to use instead.
#[test]
fn uzawa_on_the_perfectly_plastic_p2_strip_names_why_it_stops_short() {
    let mut t = strip("p2", 0.05);
    set(&mut t, "mesh.cells", toml::Value::try_from([16, 1, 8]).unwrap());
    let (l, _) = build(&t);
    let acceleration = saddle::solvers::UzawaAcceleration::None;
    let uzawa = saddle::solvers::Uzawa { max_iter: 2000, acceleration, ..Default::default() };
    let sol = uzawa.solve(&l.lagrangian(), &mut Silent).unwrap();
    let r = &sol.report;
    assert_eq!(r.stop_reason, saddle::core::StopReason::MaxIterations);
    let w = r.warnings.iter().find(|w| w.contains("converges too slowly")).expect("the warning");
    println!("{w}");
    assert!(w.contains("use newton, penalty or socp"), "{w}");
    // the rate it states is the history's: the residual over the last quarter (500 iterations)
    let h = &r.residual_history;
    let q = (h[h.len() - 1] / h[h.len() - 1 - h.len() / 4]).powf(1.0 / (h.len() / 4) as f64);
    assert!(q > 0.99 && q < 1.0 && w.contains(&format!("{q:.6}")), "{q} in {w}");
}

#[test]
fn perfectly_plastic_p2_strip_converges_to_the_same_force_for_every_solver_up_to_20x() {
    // the strip on 16 × 1 × 8 cells, h = 0, at U = 0.01 (already yielded: 354 of 512 elements
    // plastic, so first yield is below it) and 2×, 5×, 10×, 20× that; the plain uzawa stopped
    // at its budget from 5× (KKT 5.7e-6 after 20,000 iterations: theory §4.1, the rate; the test
    // above), the accelerated one (the default) converges at every level (theory §4.1,
    // acceleration)
    let solvers = [("newton", ""), ("uzawa", ""), ("penalty", ""), ("socp", "")];
    let forces = coarse_strip_forces(None, &solvers, &[0.01, 0.02, 0.05, 0.1, 0.2]);
    // the stresses, hence the force, are unique at h = 0 (theory §1); newton, penalty and socp
    // agree to 7e-10 relative, uzawa at its tol = 1e-8 to 5.0e-9 (measured, `saddle sweep` at
    // each level: 276, 554, 1,052, 1,613, 2,593 iterations)
    assert_forces_agree(&forces, 1e-8);
    // a plateau within 5 % of Prandtl's force on this coarse mesh (measured +3.0 %)
    let f20 = forces[4].2;
    assert!((f20 / prandtl_force() - 1.0).abs() < 0.05, "{f20} against {}", prandtl_force());
}

/// The force of the P2 strip on 16 × 1 × 8 cells at each punch displacement of `us`, for each of
/// `solvers` (type and further settings as TOML; Newton with 200 iterations), with the yield
/// table `yield_surface` (None: the example's von Mises, h = 0): (solver, U, force).
fn coarse_strip_forces(
    yield_surface: Option<toml::Value>,
    solvers: &[(&'static str, &str)],
    us: &[f64],
) -> Vec<(&'static str, f64, f64)> {
    let mut forces = Vec::new();
    for &(solver, settings) in solvers {
        for &u in us {
            let mut t = strip("p2", u);
            set(&mut t, "mesh.cells", toml::Value::try_from([16, 1, 8]).unwrap());
            if let Some(y) = &yield_surface {
                t.insert("yield".into(), y.clone());
            }
            let mut s: toml::Table = toml::from_str(settings).unwrap();
            s.insert("type".into(), toml::Value::String(solver.into()));
            if solver == "newton" {
                s.insert("max_iter".into(), toml::Value::Integer(200));
            }
            t.insert("solver".into(), toml::Value::Table(s));
            forces.push((solver, u, solve(&t).force.unwrap()));
        }
    }
    println!("{forces:?}");
    forces
}

/// Every force of `forces` within `rel` of Newton's at the same U.
fn assert_forces_agree(forces: &[(&str, f64, f64)], rel: f64) {
    for &(solver, u, f) in forces {
        let newton = forces.iter().find(|x| x.0 == "newton" && x.1 == u).unwrap().2;
        assert!((f - newton).abs() <= rel * newton, "{solver} at U = {u}: {f} against newton's {newton}");
    }
}

/// Drucker–Prager (α = 0.1, k₀ = 1, h = 0) on the perfectly plastic P2 strip, U = 0.01 and 20×
/// that (issue 25): newton, penalty and socp converge and agree on the force to 1e-8 (measured:
/// 1.598699 and 1.934292 on all three to the 7 printed digits; the tolerances are 1e-10 and
/// 1e-8); the force still rises from 0.01 to 0.2, to 2.1× Prandtl's von Mises value, as the
/// compressive mean stress under the punch widens the surface.
#[test]
fn drucker_prager_on_the_perfectly_plastic_p2_strip_converges_up_to_20x() {
    let dp = yield_table("drucker_prager", &[("k0", 1.0), ("alpha", 0.1), ("h", 0.0)]);
    let forces = coarse_strip_forces(Some(dp), &[("newton", ""), ("penalty", ""), ("socp", "")], &[0.01, 0.2]);
    assert_forces_agree(&forces, 1e-8);
    assert!(forces[1].2 > forces[0].2, "{forces:?}");
}

/// Tresca with the shear yield of the von Mises strip (σ₀ = √2 k₀, k = σ₀/2; theory §9.2, h = 0)
/// on the perfectly plastic P2 strip at U = 0.01 and 0.2 (issue 25): with a fallback of 50
/// penalty iterations newton stopped at 200 iterations (KKT 0.98) at 0.2, and the penalty with
/// its default 50 stops short (KKT 0.59); Newton with its default fallback (now
/// `fallback_max_iter = 400`: one fallback of 140 penalty iterations, then 10 Newton iterations
/// in all) and the penalty with `max_iter = 400` (144 iterations) both converge and agree to
/// 1e-8 (measured: 0.9544680 and 0.9678019 on both).
/// The plateau is within 10 % of Prandtl's (2 + π)k per unit length (measured +6.5 % on this
/// coarse mesh; von Mises +3.0 %). socp has no Tresca cone; uzawa is too slow at h = 0.
#[test]
fn tresca_on_the_perfectly_plastic_p2_strip_converges_up_to_20x_with_a_larger_penalty_budget() {
    let tresca = yield_table("tresca", &[("sigma0", 2f64.sqrt()), ("h", 0.0)]);
    let solvers = [("newton", ""), ("penalty", "max_iter = 400")];
    let forces = coarse_strip_forces(Some(tresca), &solvers, &[0.01, 0.2]);
    assert_forces_agree(&forces, 1e-8);
    let f20 = forces[1].2;
    assert!((f20 / prandtl_force() - 1.0).abs() < 0.1, "{f20} against {}", prandtl_force());
}

/// `newton` on the scene `t`: (U, force, CG iterations per linear solve, multigrid refreshes).
fn newton_counts(t: &toml::Table, newton: saddle::solvers::Newton) -> (f64, f64, f64, f64) {
    let (l, _) = build(t);
    let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}: {:?}", newton.linear, sol.report.stop_reason);
    let get = |k: &str| sol.report.counters.get(k).copied().unwrap_or(0.0);
    let s = Summary::new(l.view(), &sol, None);
    let cg = get("pcg_iterations") / get("triangular_solve_pairs").max(1.0);
    (sol.extras.first().copied().unwrap_or(f64::NAN), s.force.unwrap(), cg, get("multigrid_refreshes"))
}

/// [`newton_counts`] with `linear` and the refreshed hierarchy's smoother degree `tangent_degree`.
fn newton_cg_per_solve(
    t: &toml::Table,
    linear: saddle::solvers::LinearSolver,
    tangent_degree: usize,
) -> (f64, f64, f64) {
    let amg = saddle::core::linalg::AmgParams { tangent_smoother_degree: tangent_degree, ..Default::default() };
    // the path this measures: CG on K with the multigrid of K, not the pressure block
    let newton =
        saddle::solvers::Newton { linear, amg, max_iter: 200, pressure_block_ratio: f64::MAX, ..Default::default() };
    let (u, force, cg, _) = newton_counts(t, newton);
    (u, force, cg)
}

/// The default scene with P2 at ν = 0.4999 on `cells`.
fn nearly_incompressible_p2(cells: [usize; 3]) -> toml::Table {
    let mut t = small_johnson();
    set(&mut t, "material.nu", toml::Value::Float(0.4999));
    set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
    let mut d = toml::Table::new();
    d.insert("type".into(), toml::Value::String("p2".into()));
    t.insert("discretisation".into(), toml::Value::Table(d));
    t
}

/// The pressure block (theory §10.1, issue 27): at ν = 0.4999 (κ/(2μ) = 2 500) the multigrid of
/// the stiffness cannot represent the nearly divergence-free modes, that of the deviatoric part
/// A can; MINRES on [A Bᵀ; B −C] preconditioned by diag(AMG(A), S̃) (Silvester–Wathen 1994,
/// Klawonn 1998) gives the direct solver's U and needs fewer iterations per solve than CG on K.
#[test]
fn the_pressure_block_gives_the_direct_answer_in_at_most_60_minres_iterations_per_solve_at_nu_04999() {
    use saddle::solvers::LinearSolver::{Amg, Direct};
    use saddle::solvers::newton::PRESSURE_BLOCK_RATIO;
    let t = nearly_incompressible_p2([8, 8, 4]);
    let run = |linear, pressure_block_ratio| {
        let newton = saddle::solvers::Newton { linear, pressure_block_ratio, max_iter: 200, ..Default::default() };
        let (l, _) = build(&t);
        let sol = newton.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{linear:?}: {:?}", sol.report.stop_reason);
        let get = |k: &str| sol.report.counters.get(k).copied().unwrap_or(0.0);
        let per_solve = get("pcg_iterations") / get("triangular_solve_pairs").max(1.0);
        (sol.extras[0], per_solve, get("pressure_block_solves"))
    };
    let (direct, ..) = run(Direct, PRESSURE_BLOCK_RATIO);
    let (u_cg, cg, none) = run(Amg, f64::MAX);
    let (u_block, minres, solves) = run(Amg, PRESSURE_BLOCK_RATIO);
    println!(
        "direct U {direct:.12e}; CG on K {u_cg:.12e}, {cg:.1} per solve; block {u_block:.12e}, {minres:.1} MINRES per solve ({solves} solves)"
    );
    assert!(none == 0.0 && solves > 0.0, "the block path: {none} and {solves} solves");
    for u in [u_cg, u_block] {
        assert!((u - direct).abs() <= 1e-8 * direct.abs(), "{u} against the direct {direct}");
    }
    // issue 27's target; measured 2026-11-25 (`c03b04d`): block 41.8, CG on K 55.7 per solve
    // on this scene, direct U 6.731469271768e-3, both iterative U within 2.4e-12 of it
    assert!(minres <= 60.0, "{minres} MINRES per solve (CG on K: {cg})");
}

#[test]
fn the_refreshed_hierarchys_degree_4_smoother_gives_the_direct_answer_within_measured_cg_bounds() {
    // issue 27: the perfectly plastic strip (h = 0) and the default scene at ν = 0.4999, P2;
    // the soft, nearly isochoric modes are left to the smoother of the refreshed hierarchy
    use saddle::solvers::LinearSolver::{Amg, Direct};
    let strip_t = strip("p2", 0.02);
    let mut nu_t = small_johnson();
    set(&mut nu_t, "material.nu", toml::Value::Float(0.4999));
    set(&mut nu_t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    let mut d = toml::Table::new();
    d.insert("type".into(), toml::Value::String("p2".into()));
    nu_t.insert("discretisation".into(), toml::Value::Table(d));
    for (name, t, answer, bound) in
        [("strip, h = 0", &strip_t, 1, (60.0, 53.0)), ("ν = 0.4999", &nu_t, 0, (83.0, 83.0))]
    {
        let pick = |r: (f64, f64, f64)| [r.0, r.1][answer];
        let direct = pick(newton_cg_per_solve(t, Direct, 4));
        let (u2, f2, cg2) = newton_cg_per_solve(t, Amg, 2);
        let (u4, f4, cg4) = newton_cg_per_solve(t, Amg, saddle::core::linalg::amg::TANGENT_SMOOTHER_DEGREE);
        println!(
            "{name}: direct {direct:.12e}; degree 2 {:.12e} {cg2:.1} CG per solve; degree 4 {:.12e} {cg4:.1}",
            pick((u2, f2, 0.0)),
            pick((u4, f4, 0.0))
        );
        for v in [pick((u2, f2, 0.0)), pick((u4, f4, 0.0))] {
            assert!((v - direct).abs() <= 1e-8 * direct.abs(), "{name}: {v} vs {direct}");
        }
        // measured (2026-11-25, `2394194`): strip 52.2 → 58.4 CG per solve (14k dofs: here the
        // degree does not pay; at 22k–108k it does, docs/plastic_tangent.md); ν = 0.4999 on
        // 8 × 8 × 4 cells 82.2 with either degree (no solve above `amg_refresh_cg` before the
        // last, so no refresh). CG counts are the same run to run: the bounds are the
        // measurements rounded up by less than one iteration per solve
        assert!(cg4 <= bound.0 && cg2 <= bound.1, "{name}: {cg4} and {cg2} against {bound:?}");
    }
}

/// The contact model's sweeps in which rows only enter A, solved on the last factor (theory
/// §4.3, the penalty's `update_share`), give the steps of the factorised sweeps: the same
/// iterate to round-off, and every sweep is either factorised or updated (the sweeps themselves
/// unchanged). The perfectly plastic strip: its contact set moves while the mechanism forms.
#[test]
fn entering_rows_on_the_last_factor_leave_the_penalty_iteration_unchanged() {
    let (l, _) = build(&strip("p2", 0.01));
    let solve = |update_share: f64| {
        let p = saddle::solvers::Penalty { update_share, ..Default::default() };
        let sol = p.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
        sol
    };
    let (updated, factorised) = (solve(saddle::solvers::penalty::UPDATE_SHARE), solve(0.0));
    let count = |s: &saddle::core::Solution, k: &str| s.report.counters[k];
    let updates = count(&updated, "entering_row_updates");
    assert!(updates > 0.0, "no sweep with entering rows: the test tests nothing");
    assert_eq!(count(&factorised, "entering_row_updates"), 0.0);
    assert_eq!(updated.report.iterations, factorised.report.iterations);
    assert_eq!(count(&updated, "contact_model_sweeps"), count(&factorised, "contact_model_sweeps"));
    assert_eq!(count(&updated, "factorisations") + updates, count(&factorised, "factorisations"));
    let scale = factorised.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let du = updated.u.iter().zip(&factorised.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    // measured: 1.5e-15 of the largest displacement (7 updates); 1e-10 leaves room for other
    // machines' round-off, far below a wrong update (a missing term 1/μ ≈ 1e12 times too large)
    assert!(du <= 1e-10 * scale, "u differs by {du:e} of {scale:e}");
}
