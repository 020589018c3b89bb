//! theory §7, homogeneous compression: P1/P0 represent the solution exactly, so every solver must
//! reproduce the closed form to its tolerance — below and above first yield.

mod common;
use common::*;
use saddle::core::problem::tensor::SQRT2;
use saddle::core::{Silent, Solution};

/// The closed form of theory §7: (σ₃₃, U, ξ, ε₁₁, ε₃₃).
fn closed_form(e: f64, nu: f64, k0: f64, h: f64, f: f64) -> (f64, f64, f64, f64, f64) {
    let s_norm = (2.0f64 / 3.0).sqrt() * f;
    // elastic part Aσ with σ = −F e₃⊗e₃
    let (mut e11, mut e33) = (nu * f / e, -f / e);
    let mut xi = 0.0;
    if s_norm > k0 {
        let p_mag = (s_norm - k0) / h;
        // s = diag(F/3, F/3, −2F/3), p = |p| s/|s|
        e11 += p_mag * (f / 3.0) / s_norm;
        e33 += p_mag * (-2.0 * f / 3.0) / s_norm;
        xi = h * p_mag;
    }
    (-f, -e33, xi, e11, e33)
}

fn check(sol: &Solution, l: &saddle::core::DiscreteProblem, f: f64, tol: f64) {
    let (s33, u_exact, xi, e11, e33) = closed_form(100.0, 0.3, 1.0, 5.0, f);
    let u = sol.extras[0];
    assert!((u - u_exact).abs() <= tol * u_exact, "U = {u:.12e}, closed form {u_exact:.12e}");
    for (i, s) in sol.stress.sigma.iter().enumerate() {
        let exact = saddle::core::Sym::new(0.0, 0.0, s33, 0.0, 0.0, 0.0);
        assert!((s - exact).norm() <= tol * f, "element {i}: σ = {s:?}");
        if xi > 0.0 {
            assert!((sol.stress.q(i)[0] - xi).abs() <= tol * xi, "element {i}: ξ = {}", sol.stress.q(i)[0]);
        }
    }
    assert_eq!(sol.stress.n_plastic(), if xi > 0.0 { l.element.n_points() } else { 0 });
    // the displacement field is linear: u₁ = ε₁₁ x₁, u₂ = ε₁₁ x₂, u₃ = ε₃₃ (x₃ − 1)
    for (x, d) in l.element.mesh().nodes.iter().zip(l.element.nodal_vectors(&sol.u)) {
        let exact = [e11 * x[0], e11 * x[1], e33 * (x[2] - 1.0)];
        for c in 0..3 {
            assert!((d[c] - exact[c]).abs() <= tol * u_exact, "node {x:?}: u = {d:?}, exact {exact:?}");
        }
    }
    let _ = SQRT2;
}

fn solve(f: f64, solver_toml: &str) -> (Solution, saddle::core::DiscreteProblem) {
    let mut t = example("homogeneous.toml");
    set(&mut t, "obstacle.F", toml::Value::Float(f));
    let (l, _) = build(&t);
    let sol = solver(solver_toml).solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    (sol, l)
}

#[test]
fn uzawa_below_yield() {
    // |s| = sqrt(2/3)·1 < k₀ = 1: elastic
    let (sol, l) = solve(1.0, "type = \"uzawa\"\ntol = 1e-11");
    check(&sol, &l, 1.0, 1e-8);
}

#[test]
fn uzawa_above_yield() {
    let (sol, l) = solve(2.0, "type = \"uzawa\"\ntol = 1e-11");
    check(&sol, &l, 2.0, 1e-8);
}

#[test]
fn example_scene_is_the_plastic_case() {
    let (l, solver) = build(&example("homogeneous.toml"));
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    check(&sol, &l, 2.0, 1e-8);
}
