//! The KKT residual of a returned solution, recomputed independently of the solver, is below
//! the solver's tolerance; each of its four components (theory §3.4) equals the same quantity
//! computed here by hand from u, U, σ̂, λ and the scene's data; and the conditions hold when
//! checked one by one from scratch.

mod common;
use common::*;
use saddle::core::{DiscreteProblem, dual_energy, kkt};
use saddle::core::{Iterate, Material, Silent, Sym, Workspace, contact_set};

/// The data of `small_johnson()` (examples/johnson.toml): E, ν, k₀, h, the punch's F and R.
const E: f64 = 100.0;
const NU: f64 = 0.3;
const K0: f64 = 1.0;
const H: f64 = 5.0;
const F: f64 = 0.3;
const R: f64 = 5.0;

/// The Euclidean norm.
fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The energy inner product Aσ:τ + ξη/h of theory §1.2, A = ((1 + ν)σ − ν tr σ I)/E.
fn energy(s: &Sym, xi: f64, t: &Sym, eta: f64) -> f64 {
    let tr = s[0] + s[1] + s[2];
    let a_s = (s * (1.0 + NU) - Sym::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0) * (NU * tr)) / E;
    a_s.dot(t) + xi * eta / H
}

/// σ̂(u) = P_D(Cε(u), 0) by the radial return of theory §2.2, written out: tr σ = tr σ_tr,
/// s = t/r · s_tr with t = (h r + 2G k₀)/(h + 2G), ξ = t − k₀ where r = |s_tr| > k₀.
fn radial_return(eps: &Sym) -> (Sym, f64) {
    let (g, kb) = (E / (2.0 * (1.0 + NU)), E / (3.0 * (1.0 - 2.0 * NU)));
    let id = Sym::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0);
    let tr = eps[0] + eps[1] + eps[2];
    let s_tr = (eps - id * (tr / 3.0)) * (2.0 * g);
    let r = s_tr.norm();
    let (s, xi) = if r <= K0 {
        (s_tr, 0.0)
    } else {
        let t = (H * r + 2.0 * g * K0) / (H + 2.0 * g);
        (s_tr * (t / r), t - K0)
    };
    (s + id * (kb * tr), xi)
}

/// [equilibrium, load balance, complementarity, constitutive] of theory §3.4 from the formulas,
/// with σ̂(u) by [`radial_return`], the contact forces Gᵀλ and the gaps g_i = u₃ + |x|²/(2R) − U
/// from the mesh's coordinates and the paraboloid, the element volumes from the mesh and F from
/// the scene: none of L's local law, rows, weights or `kkt`. L's strain and divergence
/// operators are used (they define the discretisation).
fn kkt_by_hand(l: &DiscreteProblem, it: &Iterate<'_>) -> [f64; 4] {
    let (mesh, dofs, rows) = (l.element.mesh(), l.element.dofs(), l.lagrangian().data.rows);
    assert!(l.lagrangian().data.nodal_load.iter().all(|f| *f == 0.0), "the punch is the only load");
    let u3 = |node: usize| dofs.free(node, 2).map_or(0.0, |d| it.u[d]);
    let phi = |node: usize| {
        let x = mesh.nodes[node];
        (x[0] * x[0] + x[1] * x[1]) / (2.0 * R)
    };
    // the rows are the candidate nodes: on z = 0 inside the disc of radius 0.5, u₃ free
    let zone: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| {
            let x = mesh.nodes[n];
            x[2] == 0.0 && x[0] * x[0] + x[1] * x[1] <= 0.25 && dofs.free(n, 2).is_some()
        })
        .collect();
    let mut nodes = rows.node.clone();
    nodes.sort_unstable();
    assert_eq!(nodes, zone, "one row per candidate node");
    // equilibrium: ‖Bᵀσ(u) − Gᵀλ‖ / max(‖Bᵀσ(u)‖, ‖Gᵀλ‖), G_i = e₃ at row i's node
    let mut eps = vec![Sym::zeros(); l.element.n_points()];
    l.element.strain(it.u, &mut eps);
    let law: Vec<(Sym, f64)> = eps.iter().map(radial_return).collect();
    let sigma: Vec<Sym> = law.iter().map(|(s, _)| *s).collect();
    let mut internal = vec![0.0; l.element.n_dofs()];
    l.element.divergence(&sigma, &mut internal);
    let mut contact = vec![0.0; l.element.n_dofs()];
    for (&node, &lambda) in rows.node.iter().zip(it.lambda) {
        contact[dofs.free(node, 2).unwrap()] += lambda;
    }
    let diff: Vec<f64> = internal.iter().zip(&contact).map(|(a, b)| a - b).collect();
    let equilibrium = norm(&diff) / norm(&internal).max(norm(&contact));
    // load balance: |F − Σλ| / max(F, Σλ)
    let sum: f64 = it.lambda.iter().sum();
    let load_balance = (F - sum).abs() / F.max(sum);
    // complementarity: max_i |min(λ_i/λ_s, g_i/g_s)|
    let u = it.extras[0];
    let lambda_s = it.lambda.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let g_s = it.u.iter().chain(&[u]).map(|x| x.abs()).chain(rows.node.iter().map(|&n| phi(n))).fold(0.0, f64::max);
    let complementarity = rows
        .node
        .iter()
        .zip(it.lambda)
        .map(|(&n, &lambda)| (lambda / lambda_s).min((u3(n) + phi(n) - u) / g_s).abs())
        .fold(0.0, f64::max);
    // constitutive: ‖σ̂ − σ̂(u)‖_E / ‖σ̂(u)‖_E with the element volumes as weights
    let (mut num, mut den) = (0.0, 0.0);
    for (i, tet) in mesh.tets.iter().enumerate() {
        let [a, b, c, d] = tet.map(|n| mesh.nodes[n]);
        let e = |p: [f64; 3]| [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
        let (x, y, z) = (e(b), e(c), e(d));
        let volume = (x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0])
            + x[2] * (y[0] * z[1] - y[1] * z[0]))
            .abs()
            / 6.0;
        let (s0, xi0) = law[i];
        let (ds, dxi) = (it.stress.sigma[i] - s0, it.stress.q(i)[0] - xi0);
        num += volume * energy(&ds, dxi, &ds, dxi);
        den += volume * energy(&s0, xi0, &s0, xi0);
    }
    [equilibrium, load_balance, complementarity, (num / den).sqrt()]
}

/// The reported components of `it` and [`kkt_by_hand`], printing each.
fn compare(l: &DiscreteProblem, what: &str, it: &Iterate<'_>) -> [(f64, f64); 4] {
    let k = kkt(&l.lagrangian(), it, &mut Workspace::new(&l.lagrangian()));
    let reported = [k.equilibrium, k.load_balance, k.complementarity, k.constitutive];
    let by_hand = kkt_by_hand(l, it);
    for (name, (a, b)) in NAMES.iter().zip(reported.iter().zip(&by_hand)) {
        println!("{what:>10} {name:>16}: reported {a:.6e}, by hand {b:.6e}, difference {:.1e}", (a - b).abs());
    }
    std::array::from_fn(|k| (reported[k], by_hand[k]))
}

const NAMES: [&str; 4] = ["equilibrium", "load balance", "complementarity", "constitutive"];

#[test]
fn uzawa_solution_meets_kkt_when_recomputed() {
    let (l, solver) = build(&small_johnson());
    let solver = solver.unwrap();
    let sol = solver.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    // 1. the trait's residual, from a fresh workspace, is what the solver reported
    let reported = kkt(&l.lagrangian(), &sol.iterate(), &mut Workspace::new(&l.lagrangian()));
    assert!(reported.max() <= solver.tolerance(), "{reported:?}");
    assert_eq!(reported, sol.report.kkt, "the solver reports the residual of what it returns");
    // ... and it is the formula of theory §3.4 computed by hand. At the solution three of the
    // four components sit at round-off (Uzawa's projection and local law are exact), so the
    // formulas are also compared on a perturbed iterate where no component is below 5e-4
    let at_solution = compare(&l, "solution", &sol.iterate());
    // Equilibrium (8.0e-9 here) is a difference of forces of order ‖Bᵀσ‖: the round-off of σ(u)
    // by another evaluation order, ~1e-16 · √(dofs) ≈ 5e-15 of ‖Bᵀσ‖, is 6e-7 of it; tolerance
    // 1e-5. The other three are round-off or zero (|Σλ − F| ~ 4e-16, gaps of touching rows
    // ~2e-16, σ̂ = σ̂(u) exactly): equal to 1e-14. Measured: equilibrium identical, the
    // complementarity 2.05e-16 against 2.24e-16, the rest identical.
    let (a, b) = at_solution[0];
    assert!((a - b).abs() <= 1e-5 * b, "equilibrium: reported {a:e}, by hand {b:e}");
    for (name, (a, b)) in NAMES.iter().zip(at_solution).skip(1) {
        assert!((a - b).abs() <= 1e-14, "{name} at the solution: reported {a:e}, by hand {b:e}");
    }
    let mut p = sol.clone();
    let u_max = sol.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (i, x) in p.u.iter_mut().enumerate() {
        *x += 1e-3 * u_max * ((i as f64) * 0.7).sin();
    }
    p.extras[0] *= 1.0 + 1e-3;
    let free = (0..p.lambda.len()).find(|&i| p.lambda[i] == 0.0).expect("a row out of contact");
    let lambda_max = sol.lambda.iter().fold(0.0f64, |m, x| m.max(*x));
    p.lambda.iter_mut().for_each(|x| *x *= 1.0 + 2e-3);
    p.lambda[free] = 1e-3 * lambda_max;
    for (i, s) in p.stress.sigma.iter_mut().enumerate() {
        *s *= 1.0 + 1e-3 * ((i as f64) * 0.3).cos();
    }
    // Perturbed, every component is 5e-4 or more (measured 0.31, 2.1e-3, 1.0e-3, 5.8e-2), and
    // reported and by hand differ only by the order of their sums: at most ~n ε = 5 184 · 1.1e-16
    // = 6e-13 relative; tolerance 1e-12. Measured: 1.1e-15 (constitutive), the rest identical.
    for (name, (a, b)) in NAMES.iter().zip(compare(&l, "perturbed", &p.iterate())) {
        assert!(b >= 5e-4, "{name}: the perturbation reaches every component ({b:e})");
        assert!((a - b).abs() <= 1e-12 * b, "{name} perturbed: reported {a:e}, by hand {b:e}");
    }
    // a perturbation with a known effect: λ scaled by 1 + α makes the load balance
    // |F − (1 + α)Σλ| / ((1 + α)Σλ) = α/(1 + α), up to the solution's own |Σλ − F|/F (3.7e-16);
    // tolerance 1e-14. Measured: 1.9e-16.
    let alpha = 1e-2;
    let mut q = sol.clone();
    q.lambda.iter_mut().for_each(|x| *x *= 1.0 + alpha);
    let lb = kkt(&l.lagrangian(), &q.iterate(), &mut Workspace::new(&l.lagrangian())).load_balance;
    println!("λ × (1 + {alpha}): load balance {lb:.15e}, α/(1 + α) = {:.15e}", alpha / (1.0 + alpha));
    assert!((lb - alpha / (1.0 + alpha)).abs() <= 1e-14, "load balance {lb:e}");
    // and σ̂ scaled by 1 + β makes the constitutive residual β (Uzawa's σ̂ is σ̂(u), so
    // (1 + β)σ̂ − σ̂(u) = βσ̂(u)), up to round-off; tolerance 1e-14. Measured: 1e-17.
    let beta = 1e-2;
    let mut q = sol.clone();
    q.stress.sigma.iter_mut().for_each(|s| *s *= 1.0 + beta);
    q.stress.q.iter_mut().for_each(|x| *x *= 1.0 + beta);
    let c = kkt(&l.lagrangian(), &q.iterate(), &mut Workspace::new(&l.lagrangian())).constitutive;
    println!("σ̂ × (1 + {beta}): constitutive {c:.15e}");
    assert!((c - beta).abs() <= 1e-14, "constitutive {c:e}");

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
    let j = saddle::core::energy(&l.lagrangian(), &sol.u, &sol.extras, &mut Workspace::new(&l.lagrangian()));
    let d = dual_energy(&l.lagrangian(), &sol.stress, &sol.lambda);
    assert!((j - d).abs() <= 1e-6 * j.abs(), "J = {j}, dual = {d}");
    // something happened: contact and plasticity
    assert!(contact_set(&sol.lambda).len() >= 5);
    assert!(sol.stress.n_plastic() > 0);
}
