//! Semismooth Newton: exact on homogeneous compression, agrees with Uzawa, converges
//! quadratically at the end, warm-starts, and refuses rows it cannot handle.

use saddle_contact::{Paraboloid, RigidPunch};
use saddle_core::linalg::AmgParams;
use saddle_core::{BoxMesh, Dirichlet, DiscreteProblem, Elasticity, PhaseTimer, Region, Silent, Solver, Workspace};
use saddle_core::{P1P0Element, kkt};
use saddle_solvers::{ForcingRule, LinearSolver, Newton, Start, Uzawa};

mod common;
use common::{SCALED, homogeneous};

/// The default scene of theory §6 (k₀ = 1, hardening `h`) on the small mesh.
fn johnson(h: f64) -> DiscreteProblem {
    common::johnson([10, 10, 5], Some((1.0, h)), SCALED)
}

#[test]
fn homogeneous_compression_is_exact() {
    for f in [1.0, 2.0] {
        let l = homogeneous(f);
        let sol = Newton::default().solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged);
        // theory §7: U = F/E + ((|s| − k₀)/h)(2F/3)/|s| above yield
        let s = (2.0f64 / 3.0).sqrt() * f;
        let exact = f / 100.0 + if s > 1.0 { (s - 1.0) / 5.0 * (2.0 * f / 3.0) / s } else { 0.0 };
        assert!((sol.extras[0] - exact).abs() <= 1e-10 * exact, "F = {f}: U = {}, exact {exact}", sol.extras[0]);
        assert!(sol.stress.sigma.iter().all(|s| (s[2] + f).abs() <= 1e-10 * f && s[0].abs() <= 1e-10 * f));
    }
}

#[test]
fn agrees_with_uzawa_and_converges_quadratically() {
    let l = johnson(5.0);
    let newton = Newton { tol: 1e-12, ..Newton::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    let uzawa = Uzawa { tol: 1e-11, ..Uzawa::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(newton.report.converged && uzawa.report.converged);
    assert!(newton.report.iterations <= 15, "{} iterations", newton.report.iterations);
    assert!((newton.extras[0] - uzawa.extras[0]).abs() <= 1e-9 * newton.extras[0]);
    assert_eq!(newton.stress.plastic, uzawa.stress.plastic);
    // the end phase is quadratic: once below 1e-2, each residual is at most ~ the square of the
    // previous one (a constant of 10 allowed), until round-off
    let h = &newton.report.residual_history;
    let tail: Vec<f64> = h.iter().copied().skip_while(|r| *r > 1e-2).collect();
    assert!(tail.len() >= 2, "{h:?}");
    for w in tail.windows(2) {
        assert!(w[1] <= 10.0 * w[0] * w[0] || w[1] < 1e-13, "not quadratic: {h:?}");
    }
    // one symbolic analysis, shared by the elastic contact start and the tangents: counted
    // where it runs, against several numeric factorisations
    assert_eq!(newton.report.counters["symbolic_analyses"], 1.0);
    assert!(newton.report.counters["factorisations"] > 1.0, "{:?}", newton.report.counters);
    assert_eq!(newton.report.counters["elastic_phase_steps"], 0.0);
    assert!(newton.report.counters["elastic_contact_solves"] >= l.lagrangian().data.rows.n_rows() as f64);
    // the recomputed residual meets the tolerance
    assert!(kkt(&l.lagrangian(), &newton.iterate(), &mut Workspace::new(&l.lagrangian())).max() <= 1e-12);
}

/// The iterative backend (CG with the elastic multigrid, inexact Newton) reaches the same
/// solution as the direct one.
#[test]
fn amg_backend_agrees_with_the_direct_one() {
    let l = johnson(5.0);
    let direct = Newton { tol: 1e-11, linear: LinearSolver::Direct, ..Newton::default() };
    let amg = Newton { tol: 1e-11, linear: LinearSolver::Amg, ..Newton::default() };
    let (d, a) =
        (direct.solve(&l.lagrangian(), &mut Silent).unwrap(), amg.solve(&l.lagrangian(), &mut Silent).unwrap());
    assert!(d.report.converged && a.report.converged, "{:?}", a.report.residual_history);
    assert!((d.extras[0] - a.extras[0]).abs() <= 1e-9 * d.extras[0]);
    assert_eq!(d.stress.plastic, a.stress.plastic);
    assert_eq!((a.report.counters["factorisations"], a.report.counters["symbolic_analyses"]), (0.0, 0.0));
    assert!(a.report.counters["pcg_iterations"] > 0.0);
    assert!(kkt(&l.lagrangian(), &a.iterate(), &mut Workspace::new(&l.lagrangian())).max() <= 1e-11);
}

/// The Eisenstat–Walker forcing terms change how accurately each CG solve runs, not where Newton
/// stops: the same solution as the direct backend, its KKT residual recomputed below `tol`.
#[test]
fn eisenstat_walker_forcing_reaches_the_direct_solution() {
    let l = johnson(5.0);
    let direct = Newton { tol: 1e-11, linear: LinearSolver::Direct, ..Newton::default() };
    let ew =
        Newton { tol: 1e-11, linear: LinearSolver::Amg, forcing: ForcingRule::EisenstatWalker, ..Newton::default() };
    let (d, e) = (direct.solve(&l.lagrangian(), &mut Silent).unwrap(), ew.solve(&l.lagrangian(), &mut Silent).unwrap());
    assert!(e.report.converged, "{:?}", e.report.residual_history);
    assert!((d.extras[0] - e.extras[0]).abs() <= 1e-9 * d.extras[0], "{} vs {}", e.extras[0], d.extras[0]);
    assert_eq!(d.stress.plastic, e.stress.plastic);
    assert!(kkt(&l.lagrangian(), &e.iterate(), &mut Workspace::new(&l.lagrangian())).max() <= 1e-11);
}

#[test]
fn warm_start_from_a_nearby_solution_takes_few_steps() {
    let l = johnson(5.0);
    let rough = Uzawa { tol: 1e-5, ..Uzawa::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    let start = Start { u: rough.u.clone(), extras: rough.extras.clone(), lambda: rough.lambda.clone() };
    let sol = Newton::default()
        .solve_from(&l.lagrangian(), Some(start), &mut Silent, &mut PhaseTimer::default(), "newton")
        .unwrap();
    assert!(sol.report.converged);
    assert!(sol.report.iterations <= 4, "{} iterations from a 1e-5 start", sol.report.iterations);
    assert_eq!(sol.report.counters["elastic_phase_steps"], 0.0);
}

#[test]
fn weak_hardening_converges() {
    let l = johnson(0.5);
    let sol = Newton::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.residual_history);
    assert!(sol.stress.n_plastic() > 0);
}

/// (The return mappings of elastic problems: `tests/return_mappings.rs`.)
#[test]
fn elastic_problems_need_no_line_search() {
    let mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 4]).graded([0.0; 3], 3.0).mesh().unwrap();
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
    let l = DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap()),
        Elasticity::new(100.0, 0.3).unwrap(),
        None,
        saddle_core::Obstacles::one(Box::new(RigidPunch::new(0.3, zone, Box::new(Paraboloid::new(5.0))).unwrap())),
        &[],
    )
    .unwrap();
    let sol = Newton::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    assert_eq!(sol.report.counters["line_search_backtracks"], 0.0);
    let uz = Uzawa { tol: 1e-12, ..Uzawa::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!((sol.extras[0] - uz.extras[0]).abs() <= 1e-10 * uz.extras[0]);
}

/// The settings of the iterative backend reach it: the multigrid's parameters change the CG
/// iterations, the CG budget caps them.
#[test]
fn amg_settings_reach_the_backend() {
    let l = common::johnson([8, 8, 4], Some((1.0, 5.0)), SCALED);
    let amg = Newton { linear: LinearSolver::Amg, ..Newton::default() };
    let pcg = |n: &Newton| {
        let sol = n.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{n:?}: {:?}", sol.report.residual_history);
        (sol.report.counters["pcg_iterations"], sol.report.counters["pcg_unconverged"])
    };
    let (default_its, default_unconverged) = pcg(&amg);
    assert_eq!(default_unconverged, 0.0);
    // the default coarse size (3000) takes this small scene's stiffness whole: the preconditioner
    // is its exact inverse; a coarse size of 100 makes a real hierarchy, a weaker preconditioner
    let coarser = Newton { amg: AmgParams { coarse_size: 100, ..AmgParams::default() }, ..amg.clone() };
    let coarser_its = pcg(&coarser).0;
    assert!(coarser_its > default_its, "{coarser_its} CG iterations with a hierarchy, {default_its} without");
    // a budget of 5 CG iterations per solve is not enough for the forcing term
    let capped = Newton { cg_max_iter: 5, max_iter: 200, ..amg.clone() };
    let sol = capped.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.counters["pcg_unconverged"] > 0.0);
    assert!(sol.report.counters["pcg_iterations"] <= 5.0 * sol.report.counters["triangular_solve_pairs"]);
}

#[test]
fn settings_from_a_scene_table_and_invalid_values_name_the_field() {
    let s: Box<dyn Solver> = toml::from_str("type = \"newton\"").unwrap();
    assert_eq!((s.name(), s.tolerance()), ("newton", 1e-10));
    let text = "type = \"newton\"\nlinear = \"amg\"\ncg_forcing = 0.1\nforcing = \"eisenstat_walker\"\ncg_max_iter = 100\nauto_amg_dofs = 5\n\
                [amg]\ncoarse_size = 500";
    let s: Box<dyn Solver> = toml::from_str(text).unwrap();
    assert!(s.validate("solver").is_ok());
    let e = toml::from_str::<Box<dyn Solver>>("type = \"newton\"\n[amg]\ncoarse = 500").expect_err("unknown field");
    assert!(e.to_string().contains("coarse"), "{e}");
    for (n, field) in [
        (Newton { tol: 0.0, ..Newton::default() }, "solver.tol"),
        (Newton { cg_forcing: 1.0, ..Newton::default() }, "solver.cg_forcing"),
        (Newton { cg_forcing: f64::NAN, ..Newton::default() }, "solver.cg_forcing"),
        (Newton { cg_max_iter: 0, ..Newton::default() }, "solver.cg_max_iter"),
        (
            Newton { amg: AmgParams { smoother_range: 0.5, ..AmgParams::default() }, ..Newton::default() },
            "solver.amg.smoother_range",
        ),
    ] {
        let e = n.validate("solver").expect_err("invalid");
        assert_eq!(e.field, field, "{e}");
    }
}

#[test]
fn autos_direct_reserve_takes_over_once_cg_has_spent_its_budget_and_gives_the_same_step() {
    use saddle_core::Material;
    use saddle_solvers::active_set::ActiveSetSystem;
    let p = johnson(0.5);
    let l = p.lagrangian();
    let c = l.data.elasticity.stiffness_matrix();
    let k = l.stiffness(Material::Uniform(&c));
    let (n, nr) = (l.n_dofs(), l.data.rows.n_rows());
    // every row active at zero gap, a force ∇E: the elastic contact step
    let grad: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5).collect();
    let (active, gap) = (vec![true; nr], vec![0.0; nr]);
    let mut direct = ActiveSetSystem::new(&l, "newton").unwrap();
    let exact = direct.step(&l, &k, &active, &grad, &gap, 0.0).unwrap();
    let mut amg = ActiveSetSystem::multigrid(&l, "newton", &AmgParams::default(), 2000, 40).unwrap();
    // a budget of one CG iteration: the first step is CG's, every later one the factor's
    amg.keep_in_reserve(ActiveSetSystem::new(&l, "newton").unwrap(), 1.0);
    let err = |du: &[f64]| {
        let scale = exact.du.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        du.iter().zip(&exact.du).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale
    };
    let first = amg.step(&l, &k, &active, &grad, &gap, 1e-10).unwrap();
    let cg = amg.iterative().map(|it| (it.iterations, it.switched)).unwrap();
    assert!(cg.0 > 0 && !cg.1 && amg.factorisations == 0, "{cg:?}");
    let second = amg.step(&l, &k, &active, &grad, &gap, 1e-10).unwrap();
    let after = amg.iterative().map(|it| (it.iterations, it.switched)).unwrap();
    assert_eq!(after, (cg.0, true));
    assert_eq!(amg.factorisations, 1);
    // the reserve factorises the same matrix as the direct system (measured: identical), CG
    // stops at a relative residual of 1e-10 (measured 5.4e-11 in du)
    println!("CG step {:.1e}, reserve's step {:.1e}", err(&first.du), err(&second.du));
    assert!(err(&first.du) < 1e-7 && err(&second.du) < 1e-12);
}
