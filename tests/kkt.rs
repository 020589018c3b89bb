//! The KKT residual of a returned solution, recomputed independently of the solver, is below
//! the solver's tolerance; and the conditions hold when checked one by one from scratch.

mod common;
use common::*;
use saddle::core::{Material, Silent, Workspace, contact_set};
use saddle::core::{dual_energy, energy, kkt};

#[test]
fn uzawa_solution_meets_kkt_when_recomputed() {
    let (l, solver) = build(&small_johnson());
    let solver = solver.unwrap();
    let sol = solver.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    // 1. the trait's residual, from a fresh workspace
    let kkt = kkt(&l.lagrangian(), &sol.iterate(), &mut Workspace::new(&l.lagrangian()));
    assert!(kkt.max() <= solver.tolerance(), "{kkt:?}");
    assert_eq!(kkt, sol.report.kkt, "the solver reports the residual of what it returns");

    // 2. by hand: Σλ = F, λ ≥ 0, g ≥ 0, λ·g = 0, and equilibrium through the assembled
    //    tangent-free route K_elastic u − Bᵀ(Cε − σ) = Gᵀλ, i.e. Bᵀσ = Gᵀλ
    let f = 0.3;
    let sum: f64 = sol.lambda.iter().sum();
    assert!((sum - f).abs() <= 1e-10 * f, "Σλ = {sum}");
    let rows = l.lagrangian().data.rows;
    let mut g = vec![0.0; rows.n_rows()];
    rows.gap(&sol.u, &sol.extras, &mut g);
    let u_scale = sol.extras[0];
    for (i, (&li, &gi)) in sol.lambda.iter().zip(&g).enumerate() {
        assert!(li >= 0.0 && gi >= -1e-12 * u_scale, "row {i}: λ = {li}, g = {gi}");
        assert!((li * gi).abs() <= 1e-8 * f * u_scale, "row {i}: λ g = {}", li * gi);
    }
    // equilibrium with the elastic stiffness: K u − Bᵀ(C ε(u) − σ) equals Bᵀσ
    let c = l.lagrangian().data.elasticity.stiffness_matrix();
    let k = l.element.stiffness(Material::Uniform(&c));
    let mut ku = vec![0.0; l.element.n_dofs()];
    l.element.pattern().matvec(&k, &sol.u, &mut ku);
    let mut eps = vec![saddle::core::Sym::zeros(); l.element.n_points()];
    l.element.strain(&sol.u, &mut eps);
    let relax: Vec<_> = eps.iter().zip(&sol.stress.sigma).map(|(e, s)| c * e - s).collect();
    let mut br = vec![0.0; l.element.n_dofs()];
    l.element.divergence(&relax, &mut br);
    let mut gl = vec![0.0; l.element.n_dofs()];
    let mut gv = vec![0.0; 1];
    rows.add_transpose(&sol.lambda, &mut gl, &mut gv);
    let res: f64 = ku.iter().zip(&br).zip(&gl).map(|((a, b), c)| (a - b - c).powi(2)).sum::<f64>().sqrt();
    let scale: f64 = gl.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(res <= 1e-7 * scale, "equilibrium residual {res:e} vs {scale:e}");
    // duality: J equals the dual energy at the solution
    let j = energy(&l.lagrangian(), &sol.u, &sol.extras, &mut Workspace::new(&l.lagrangian()));
    let d = dual_energy(&l.lagrangian(), &sol.stress, &sol.lambda);
    assert!((j - d).abs() <= 1e-6 * j.abs(), "J = {j}, dual = {d}");
    // something happened: contact and plasticity
    assert!(contact_set(&sol.lambda).len() >= 5);
    assert!(sol.stress.n_plastic() > 0);
}
