//! Drucker–Prager with linear isotropic hardening (`type = "drucker_prager"`, theory §9.1) in
//! whole scenes, through every solver:
//!
//! * (a) homogeneous compression (theory §7.1) above yield against its closed form, with the
//!   plastic dilatancy 3αγ in the displacement U;
//! * (b) α = 0 gives the von Mises solution of the small default scene to round-off;
//! * (c) scenes whose elements return to the apex (hydrostatic tension): a laterally confined
//!   cube pulled down at its bottom face against the punch (homogeneous, every element at the
//!   apex, against its closed form) and the same cube with the punch on a quarter disc only
//!   (inhomogeneous: apex and smooth-return elements side by side), where the four
//!   solvers agree.

mod common;
use common::*;
use saddle::core::DiscreteProblem;
use saddle::core::problem::tensor::{deviator, trace};
use saddle::core::{Silent, Solution, Solver, Sym};
use saddle::solvers::conformance::agreement;
use saddle::solvers::{Newton, Penalty, Uzawa};
use std::path::Path;

/// The `[yield]` table of Drucker–Prager.
fn drucker_prager(k0: f64, alpha: f64, h: f64) -> toml::Value {
    yield_table("drucker_prager", &[("k0", k0), ("alpha", alpha), ("h", h)])
}

/// The solvers of the tests, tight enough for 1e-8 on the closed forms.
fn solvers() -> Vec<(&'static str, Box<dyn Solver>)> {
    solvers_with(1e-12, 1e-11, 1e-10, 1e-11)
}

/// Homogeneous compression (theory §7.1, §9.1): σ = −F e₃⊗e₃ exactly, so tr σ = −F,
/// s = diag(F/3, F/3, −2F/3), |s| = √(2/3)F and n = s/|s| = diag(1, 1, −2)/√6. Above yield the
/// consistency condition |s| + α tr σ = k₀ + ξ gives ξ = √(2/3)F − αF − k₀, the associated
/// flow p = γ(n + αI) with ξ = hγ gives γ = ξ/h, and ε = Aσ + p:
/// ε₁₁ = νF/E + γ(1/√6 + α), ε₃₃ = −F/E + γ(α − 2/√6). The plastic volume change tr p = 3αγ
/// is positive (dilatancy), so U = −ε₃₃ = F/E + γ(2/√6 − α) is smaller than the von Mises
/// value with the same γ. Returns (U, ξ, ε₁₁, ε₃₃).
fn compression_closed_form(e: f64, nu: f64, k0: f64, alpha: f64, h: f64, f: f64) -> (f64, f64, f64, f64) {
    let xi = ((2.0f64 / 3.0).sqrt() * f - alpha * f - k0).max(0.0);
    let gamma = xi / h;
    let r6 = 6.0f64.sqrt();
    let e11 = nu * f / e + gamma * (1.0 / r6 + alpha);
    let e33 = -f / e + gamma * (alpha - 2.0 / r6);
    (-e33, xi, e11, e33)
}

#[test]
fn homogeneous_compression_matches_the_closed_form() {
    let (k0, alpha, h, f) = (1.0, 0.2, 5.0, 3.0);
    let mut t = example("homogeneous.toml");
    t.insert("yield".into(), drucker_prager(k0, alpha, h));
    set(&mut t, "obstacle.F", toml::Value::Float(f));
    let (l, _) = build(&t);
    let (u_exact, xi, e11, e33) = compression_closed_form(100.0, 0.3, k0, alpha, h, f);
    assert!(xi > 0.5, "clearly plastic: ξ = {xi}");
    let tol = 1e-8;
    for (name, s) in solvers() {
        let sol = solve_converged(&l, name, s.as_ref());
        let u = sol.extras[0];
        let (es, eu) = compression_errors(&l, &sol, f, e11, e33, u_exact);
        let eq = (0..l.element.n_points()).map(|i| (sol.stress.q(i)[0] - xi).abs() / xi).fold(0.0f64, f64::max);
        let e_u = (u - u_exact).abs() / u_exact;
        println!(
            "DP homogeneous compression k0 = {k0}, α = {alpha}, h = {h}, F = {f}: {name:>7} | {:>3} it | U {e_u:.1e} | σ {es:.1e} | ξ {eq:.1e} | u {eu:.1e}",
            sol.report.iterations
        );
        assert!(e_u <= tol, "{name}: U = {u:.12e}, closed form {u_exact:.12e}");
        assert!(es <= tol && eq <= tol && eu <= tol, "{name}: σ {es:e}, ξ {eq:e}, u {eu:e}");
        assert_eq!(sol.stress.n_plastic(), l.element.n_points(), "{name}: every element plastic");
    }
}

/// α = 0 is von Mises: the small default scene gives the same U and σ̂ to round-off.
#[test]
fn alpha_zero_is_von_mises_on_the_small_default_scene() {
    let mut text = std::fs::read_to_string(repo("examples/johnson.toml")).unwrap();
    text = text.replace("cells = [32, 32, 16]", "cells = [12, 12, 6]").replace("ratio = 4.0", "ratio = 3.0");
    let dp_text = text.replace("type = \"von_mises\"", "type = \"drucker_prager\"\nalpha = 0.0");
    assert!(
        dp_text.contains("drucker_prager") && text.contains("cells = [12, 12, 6]") && text.contains("ratio = 3.0 ")
    );
    let problem =
        |s: &str| saddle::io::scene::Scene::from_toml(s, Path::new("x.toml")).unwrap().into_problem().unwrap().0;
    let (lv, ld) = (problem(&text), problem(&dp_text));
    assert_eq!(ld.lagrangian().data.plasticity().unwrap().name(), "drucker_prager");
    let newton = Newton { tol: 1e-12, ..Newton::default() };
    let a = solve_converged(&lv, "newton", &newton);
    let b = solve_converged(&ld, "newton", &newton);
    let ag = agreement(&ld.lagrangian(), &b, &a);
    println!(
        "DP α = 0 vs von Mises, small default scene: newton {} / {} it | U {:.1e} | σ̂ {:.1e} | plastic {} / {}",
        a.report.iterations,
        b.report.iterations,
        ag.u_rel,
        ag.stress_rel,
        a.stress.n_plastic(),
        b.stress.n_plastic()
    );
    assert!(a.stress.n_plastic() > 0);
    assert!(ag.u_rel <= 1e-12 && ag.stress_rel <= 1e-12, "U {:e}, σ̂ {:e}", ag.u_rel, ag.stress_rel);
    assert_eq!(a.stress.n_plastic(), b.stress.n_plastic());
}

/// The elements whose stress is on the apex: plastic, s = 0 and α tr σ = k₀ + ξ.
fn apex_elements(sol: &Solution, k0: f64, alpha: f64) -> usize {
    (0..sol.stress.sigma.len())
        .filter(|&i| {
            let s = &sol.stress.sigma[i];
            let on_surface = (alpha * trace(s) - k0 - sol.stress.q(i)[0]).abs() <= 1e-8 * (1.0 + s.norm());
            sol.stress.plastic[i] && deviator(s).norm() <= 1e-8 * s.norm() && on_surface
        })
        .count()
}

/// The laterally confined cube (rollers on all four sides, u₃ = 0 on top) pulled down by the
/// traction p on its bottom face, with the flat punch pushing up with force F on `zone`.
fn confined_cube(k0: f64, alpha: f64, h: f64, p: f64, f: f64, zone: &str, cells: usize) -> DiscreteProblem {
    let text = format!(
        r#"
title = "Laterally confined cube in tension against a punch (theory §9.1)"
# P1–P0, stated: the closed forms count one stress point per element (`apex_elements`)
[discretisation]
type = "p1"
[mesh]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
cells = [{cells}, {cells}, {cells}]
[material]
E = 100.0
nu = 0.3
[yield]
type = "drucker_prager"
k0 = {k0:?}
alpha = {alpha:?}
h = {h:?}
[[dirichlet]]
on = {{ any = [ {{ group = "xmin" }}, {{ group = "xmax" }} ] }}
components = ["x"]
[[dirichlet]]
on = {{ any = [ {{ group = "ymin" }}, {{ group = "ymax" }} ] }}
components = ["y"]
[[dirichlet]]
on = {{ group = "zmax" }}
components = ["z"]
[[load]]
type = "traction"
on = {{ group = "zmin" }}
t = [0.0, 0.0, {minus_p:?}]
[obstacle]
type = "rigid_punch"
F = {f:?}
zone = {zone}
gap = {{ type = "flat" }}
"#,
        minus_p = -p
    );
    saddle::io::scene::Scene::from_toml(&text, Path::new("x.toml")).unwrap().into_problem().unwrap().0
}

/// Homogeneous uniaxial-strain tension at the apex (theory §9.1). With the punch on the whole
/// bottom face the bar carries σ₃₃ = S = p − F; ε₁₁ = ε₂₂ = 0 makes the lateral stresses
/// reactions. At the apex σ = S I, ξ = 3αS − k₀, γ = ξ/h, and the plastic strain
/// γ(ν + αI) with a deviator |ν| ≤ 1 must cancel the lateral elastic strain S/(3K_b):
/// ν₁₁ = ν₂₂ = −S/(3K_bγ) − α, ν₃₃ = −2ν₁₁, so ε₃₃ = S/K_b + 3αγ and U = −ε₃₃. The apex is
/// the solution when √6|ν₁₁| ≤ 1 (strictly here: 0.60 for the numbers below).
#[test]
fn confined_tension_returns_every_element_to_the_apex() {
    let (k0, alpha, h, p, f) = (0.5, 0.2, 5.0, 4.0, 1.0);
    let l = confined_cube(k0, alpha, h, p, f, "{ group = \"zmin\" }", 3);
    let (e, nu) = (100.0, 0.3);
    let kb = e / (3.0 * (1.0 - 2.0 * nu));
    let s = p - f;
    let xi = 3.0 * alpha * s - k0;
    let gamma = xi / h;
    let nu11 = -s / (3.0 * kb * gamma) - alpha;
    assert!(6.0f64.sqrt() * nu11.abs() < 0.65, "strictly inside the normal cone: {}", 6.0f64.sqrt() * nu11.abs());
    let u_exact = -(s / kb + 3.0 * alpha * gamma);
    // Every element on the apex makes the consistent tangent purely volumetric (K_b h/v) I⊗I:
    // the global tangent stiffness is singular on the discrete isochoric fields that satisfy
    // the boundary conditions, and u itself is not unique (U, σ and ξ are). Newton and the
    // Newton polish of the SOCP solver need that tangent; the interior point alone does not.
    match (Newton { tol: 1e-12, ..Newton::default() }).solve(&l.lagrangian(), &mut Silent) {
        Ok(sol) => println!("DP confined tension: newton converged = {}", sol.report.converged),
        Err(e) => println!("DP confined tension: newton fails as expected on the singular tangent: {e}"),
    }
    let mut list: Vec<(&str, Box<dyn Solver>)> = vec![
        ("uzawa", Box::new(Uzawa { tol: 1e-11, ..Uzawa::default() })),
        ("penalty", Box::new(Penalty { tol: 1e-10, ..Penalty::default() })),
    ];
    #[cfg(feature = "socp")]
    list.push((
        "socp (no polish)",
        Box::new(saddle::solvers::Socp {
            polish: false,
            ipm_tol: 1e-12,
            tol: 1e-6,
            ..saddle::solvers::Socp::default()
        }),
    ));
    for (name, sv) in list {
        let sol = solve_converged(&l, name, sv.as_ref());
        let u = sol.extras[0];
        let e_u = (u - u_exact).abs() / u_exact.abs();
        let es = sol.stress.sigma.iter().map(|x| (x - Sym::new(s, s, s, 0.0, 0.0, 0.0)).norm() / s).fold(0.0, f64::max);
        let eq = (0..l.element.n_points()).map(|i| (sol.stress.q(i)[0] - xi).abs() / xi).fold(0.0, f64::max);
        let apex = apex_elements(&sol, k0, alpha);
        println!(
            "DP confined tension S = {s}: {name:>16} | {:>3} it | U {e_u:.1e} | σ {es:.1e} | ξ {eq:.1e} | apex {apex} / {}",
            sol.report.iterations,
            l.element.n_points()
        );
        assert!(e_u <= 1e-8 && es <= 1e-8 && eq <= 1e-8, "{name}: U {e_u:e} ({u} vs {u_exact}), σ {es:e}, ξ {eq:e}");
        assert_eq!(apex, l.element.n_points(), "{name}: every element on the apex");
    }
}

/// The confined cube with the punch on the quarter disc of radius 0.5 only: compression above
/// the punch, hydrostatic tension away from it. All four solvers (Newton at its default
/// tolerance) agree with Newton at 1e-12 to 1e-7 in U and σ̂.
#[test]
fn all_solvers_agree_on_a_scene_with_apex_returns() {
    let (k0, alpha, h) = (0.5, 0.2, 5.0);
    let zone = "{ all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }";
    let l = confined_cube(k0, alpha, h, 4.0, 1.0, zone, 6);
    let reference = solve_converged(&l, "newton", &Newton { tol: 1e-12, ..Newton::default() });
    let apex = apex_elements(&reference, k0, alpha);
    println!(
        "DP confined tension, punch on a quarter disc: {} elements, {} plastic, {apex} on the apex",
        l.element.n_points(),
        reference.stress.n_plastic()
    );
    assert!(apex > 0 && apex < l.element.n_points(), "apex elements: {apex}");
    // the reference itself is Newton at 1e-12; compare Newton at its default tolerance
    let mut list = solvers();
    list[0].1 = Box::new(Newton::default());
    for (name, s) in list {
        let sol = solve_converged(&l, name, s.as_ref());
        let a = agreement(&l.lagrangian(), &sol, &reference);
        println!(
            "DP confined tension, punch on a quarter disc: {name:>7} vs newton 1e-12 | {:>4} it | U {:.1e} | σ̂ {:.1e} | apex {}",
            sol.report.iterations,
            a.u_rel,
            a.stress_rel,
            apex_elements(&sol, k0, alpha)
        );
        assert!(a.u_rel <= 1e-7 && a.stress_rel <= 1e-7, "{name}: U {:e}, σ̂ {:e}", a.u_rel, a.stress_rel);
        assert!(a.contact_mismatch.is_empty() && a.plastic_mismatch.is_empty(), "{name}: {a:?}");
    }
}
