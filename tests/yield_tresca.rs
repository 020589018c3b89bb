//! Tresca with linear isotropic hardening (`type = "tresca"`, theory §9.2) in whole scenes:
//!
//! * (a) homogeneous compression (theory §7.1) above yield: the uniaxial state σ = −F e₃⊗e₃ is
//!   axisymmetric, its return is to the edge σ₁ = σ₂ of the hexagon, and σ, ξ and U have a closed
//!   form that newton, uzawa and penalty reproduce to 1e-8;
//! * (b) the small default scene with Tresca: the three solvers agree to 1e-7 in U and σ̂ (energy
//!   norm), some elements return to an edge, Newton needs at most twice the iterations it needs
//!   with von Mises, and the conic solver refuses with an error naming `tresca`.

mod common;
use common::*;
use saddle::core::{Silent, Solver, Sym};
use saddle::solvers::Newton;
use saddle::solvers::conformance::agreement;
use saddle::yield_surfaces::{Tresca, TrescaReturn};

/// The `[yield]` table of Tresca.
fn tresca(sigma0: f64, h: f64) -> toml::Value {
    yield_table("tresca", &[("sigma0", sigma0), ("h", h)])
}

/// Newton, Uzawa and the penalty method with these tolerances: the conic solver refuses Tresca.
fn solvers(newton: f64, uzawa: f64, penalty: f64) -> impl Iterator<Item = (&'static str, Box<dyn Solver>)> {
    solvers_with(newton, uzawa, penalty, 0.0).into_iter().filter(|(name, _)| *name != "socp")
}

/// Homogeneous compression with Tresca (theory §9.2): σ = −F e₃⊗e₃ has principal values
/// (0, 0, −F), so σ₁ − σ₃ = F and the body yields at F = σ₀. Above, the state sits on the edge
/// σ₁ = σ₂ with ξ = F − σ₀; the plastic strain p = ε − Aσ lies in the normal cone of the edge,
/// `p = γ_a (e₁ − e₃) + γ_b (e₂ − e₃)` with γ_a, γ_b ≥ 0 and `ξ = h(γ_a + γ_b)`, so
/// `p₃₃ = −(γ_a + γ_b) = −(F − σ₀)/h` and `U = −ε₃₃ = F/E + (F − σ₀)/h`. The split between γ_a
/// and γ_b (ε₁₁ against ε₂₂) is not determined: any split is a solution (the displacement is
/// not unique, while σ, ξ and U are). Returns (U, ξ).
fn closed_form(e: f64, sigma0: f64, h: f64, f: f64) -> (f64, f64) {
    let xi = (f - sigma0).max(0.0);
    (f / e + xi / h, xi)
}

fn homogeneous(sigma0: f64, h: f64, f: f64) {
    let mut t = example("homogeneous.toml");
    t.insert("yield".into(), tresca(sigma0, h));
    set(&mut t, "obstacle.F", toml::Value::Float(f));
    let (l, _) = build(&t);
    let (u_exact, xi) = closed_form(100.0, sigma0, h, f);
    assert!(xi > 0.1, "clearly plastic: ξ = {xi}");
    let tp = Tresca::new(sigma0, h).unwrap();
    let tol = 1e-8;
    for (name, s) in solvers(1e-12, 1e-11, 1e-10) {
        let sol = solve_converged(&l, name, s.as_ref());
        let u = sol.extras[0];
        let (mut es, mut eq) = (0.0f64, 0.0f64);
        for i in 0..l.element.n_points() {
            let exact = Sym::new(0.0, 0.0, -f, 0.0, 0.0, 0.0);
            es = es.max((sol.stress.sigma[i] - exact).norm() / f);
            eq = eq.max((sol.stress.q(i)[0] - xi).abs() / xi);
        }
        let mut eps = vec![Sym::zeros(); l.element.n_points()];
        l.element.strain(&sol.u, &mut eps);
        let edges =
            eps.iter().filter(|e| tp.return_kind(l.lagrangian().data.elasticity, e) == TrescaReturn::Edge).count();
        // the undetermined split: ε₁₁ − ε₂₂ = γ_a − γ_b
        let split = eps.iter().map(|e| e[0] - e[1]).fold(0.0f64, |a, b| a.max(b.abs()));
        let e_u = (u - u_exact).abs() / u_exact;
        println!(
            "tresca homogeneous σ₀ = {sigma0}, h = {h}, F = {f}: {name:>7} | {:>3} it | U {u:.10e} (closed form {u_exact:.10e}, error {e_u:.1e}) | σ {es:.1e} | ξ {eq:.1e} | edge returns {edges}/{} | max |ε₁₁ − ε₂₂| {split:.1e}",
            sol.report.iterations,
            l.element.n_points()
        );
        assert!(e_u <= tol, "{name}: U = {u:.12e}, closed form {u_exact:.12e}");
        assert!(es <= tol && eq <= tol, "{name}: σ {es:e}, ξ {eq:e}");
        assert_eq!(sol.stress.n_plastic(), l.element.n_points(), "{name}: every element plastic");
        assert_eq!(edges, l.element.n_points(), "{name}: every element returns to the edge σ₁ = σ₂");
    }
}

#[test]
fn homogeneous_compression_returns_to_the_edge_and_matches_the_closed_form() {
    homogeneous(1.5, 5.0, 2.0);
    homogeneous(1.0, 20.0, 3.0);
}

/// σ₀ of the scene: √(3/2) k₀ = σ_y, the Tresca hexagon through the von Mises circle at uniaxial
/// stress (the same uniaxial yield stress), inscribed in it. Measured plastic zones on this
/// scene: von Mises (k₀ = 1) 136 elements, Tresca with σ₀ = √(3/2) k₀ 142, with the shear match
/// σ₀ = √2 k₀ (circumscribed) 112.
const SIGMA0: f64 = 1.224_744_871_391_589;

#[test]
fn solvers_agree_on_the_small_default_scene_with_tresca() {
    let mut t = small_johnson();
    t.insert("yield".into(), tresca(SIGMA0, 5.0));
    let (l, _) = build(&t);
    assert_eq!(l.lagrangian().data.plasticity().unwrap().name(), "tresca");
    let reference = solve_converged(&l, "newton", &Newton { tol: 1e-12, ..Newton::default() });
    let plastic = reference.stress.n_plastic();
    let tp = Tresca::new(SIGMA0, 5.0).unwrap();
    let mut eps = vec![Sym::zeros(); l.element.n_points()];
    l.element.strain(&reference.u, &mut eps);
    let kinds: Vec<TrescaReturn> = eps.iter().map(|e| tp.return_kind(l.lagrangian().data.elasticity, e)).collect();
    let count = |k: TrescaReturn| kinds.iter().filter(|&&x| x == k).count();
    let (faces, edges) = (count(TrescaReturn::Face), count(TrescaReturn::Edge));
    println!(
        "tresca σ₀ = √(3/2) k₀, h = 5, small default scene: {} elements, {plastic} plastic: {faces} face returns, {edges} edge returns",
        l.element.n_points()
    );
    assert_eq!(faces + edges, plastic);
    assert!(edges > 0 && faces > 0, "faces {faces}, edges {edges}");

    for (name, s) in solvers(1e-10, 1e-10, 1e-10) {
        let sol = solve_converged(&l, name, s.as_ref());
        let a = agreement(&l.lagrangian(), &sol, &reference);
        println!(
            "tresca small default scene: {name:>7} vs newton 1e-12 | {:>4} it | KKT {:.1e} | U {:.1e} | σ̂ {:.1e} | plastic {}",
            sol.report.iterations,
            sol.report.kkt.max(),
            a.u_rel,
            a.stress_rel,
            sol.stress.n_plastic()
        );
        assert!(a.u_rel <= 1e-7 && a.stress_rel <= 1e-7, "{name}: U {:e}, σ̂ {:e}", a.u_rel, a.stress_rel);
    }

    // Newton's iterations against von Mises (k₀ = 1, h = 5) on the same scene, same tolerance
    let (lv, _) = build(&small_johnson());
    let newton = Newton::default();
    let vm = solve_converged(&lv, "newton (von Mises)", &newton);
    let tr = solve_converged(&l, "newton (Tresca)", &newton);
    println!(
        "newton at tol {:e}: von Mises {} iterations ({} plastic), Tresca {} iterations ({} plastic)",
        newton.tol,
        vm.report.iterations,
        vm.stress.n_plastic(),
        tr.report.iterations,
        tr.stress.n_plastic()
    );
    assert!(
        tr.report.iterations <= 2 * vm.report.iterations,
        "Tresca {} vs von Mises {} iterations",
        tr.report.iterations,
        vm.report.iterations
    );
}

/// The conic solver has no cone for Tresca and says so, naming the plugin.
#[cfg(feature = "socp")]
#[test]
fn socp_refuses_tresca_naming_it() {
    let mut t = small_johnson();
    t.insert("yield".into(), tresca(SIGMA0, 5.0));
    let (l, _) = build(&t);
    let e = saddle::solvers::Socp::default().solve(&l.lagrangian(), &mut Silent).unwrap_err();
    let msg = e.to_string();
    println!("socp on tresca: {msg}");
    assert!(msg.contains("tresca"), "{msg}");
    assert!(msg.contains("polyhedral") && msg.contains("semidefinite"), "{msg}");
}
