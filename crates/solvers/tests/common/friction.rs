//! What the friction tests share (theory §8.3): the solvers as those tests run them, and the
//! friction conditions recomputed from the rows, not taken from the solvers' residuals.

use saddle_core::{ConstraintRows, DiscreteProblem, Silent, Solution, Solver, Start, Workspace, kkt};
use saddle_solvers::{Newton, Penalty, Socp, Uzawa};

pub fn solve(s: &dyn Solver, p: &DiscreteProblem) -> Solution {
    let sol = s.solve(&p.lagrangian(), &mut Silent).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
    assert!(
        sol.report.converged,
        "{}: {:?} {:?} {:?}",
        s.name(),
        sol.report.kkt,
        sol.report.warnings,
        sol.report.counters.get("ipm_status")
    );
    sol
}

pub fn uzawa() -> Uzawa {
    Uzawa { tol: 1e-11, max_iter: 100_000, ..Uzawa::default() }
}

/// Without a polish for friction the interior point's answer is socp's. Measured on the
/// partial-slip scene (8 stick, 13 slip): at ipm_tol = 1e-10 its KKT residual is 1.2e-7 and it
/// differs from uzawa's by 3.6e-7 in λ; at 1e-13, 2.8e-8 and 5.6e-8 (the complementarity of the
/// nodes between stick and slip; equilibrium 6e-15). So 1e-13, asked for 1e-7.
pub fn socp() -> Socp {
    Socp { tol: 1e-7, ipm_tol: 1e-13, ..Socp::default() }
}

/// Newton's semismooth iteration from u = 0, λ = 0 (theory §4.2, §8.3): from a cold start its
/// exact elastic start is the projection onto K_h with friction — uzawa's own — and would leave
/// the iteration nothing to do on an elastic body; this start makes it work.
pub fn newton_from_zero(p: &DiscreteProblem) -> Solution {
    let l = p.lagrangian();
    let zero =
        Start { u: vec![0.0; l.n_dofs()], extras: vec![0.0; l.n_extras()], lambda: vec![0.0; l.data.rows.n_rows()] };
    let newton = Newton { max_fallbacks: 0, ..Newton::default() };
    let sol = newton.solve_warm(&l, &zero, &mut Silent).unwrap_or_else(|e| panic!("newton: {e}"));
    assert!(
        sol.report.converged && sol.report.iterations >= 1,
        "newton: {:?} {:?}",
        sol.report.kkt,
        sol.report.iterations
    );
    sol
}

/// max|a − b| / max|b|.
pub fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    d / b.iter().map(|x| x.abs()).fold(0.0, f64::max)
}

/// The friction conditions of theory §8.3 recomputed from the rows: for each node with friction
/// (normal multiplier λ_n, tangential λ_t, slip s = the tangential rows' values, bound
/// r = `bound(w, λ_n)`: g w for Tresca, μ λ_n for Coulomb),
/// |λ_t| ≤ r, and s = −κ λ_t with κ ≥ 0 (stick: s = 0 inside the disc; slip: s opposite to
/// λ_t on its rim), each violation relative to the largest |λ| and |s|. Also the normal rows'
/// min(λ, g). Returns the largest violation.
pub fn friction_conditions(p: &DiscreteProblem, sol: &Solution, bound: impl Fn(f64, f64) -> f64) -> f64 {
    let l = p.lagrangian();
    let rows = l.data.rows;
    let mut gap = vec![0.0; rows.n_rows()];
    rows.gap(&sol.u, &sol.extras, &mut gap);
    conditions(rows, &sol.lambda, &gap, bound)
}

/// The conditions of [`friction_conditions`] for the multipliers `lambda` and the rows' values
/// `gap` (the normal rows' gaps and the tangential rows' slips).
pub fn conditions(rows: &ConstraintRows, lambda: &[f64], gap: &[f64], bound: impl Fn(f64, f64) -> f64) -> f64 {
    let lam_s = lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let s_s = gap.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let mut worst: f64 = 0.0;
    for i in (0..rows.n_rows()).filter(|&i| !tangential[i]) {
        worst = worst.max((lambda[i] / lam_s).min(gap[i] / s_s).abs());
    }
    for b in &rows.friction.blocks {
        let (lt, s) = ([lambda[b.tangent], lambda[b.tangent + 1]], [gap[b.tangent], gap[b.tangent + 1]]);
        let (nl, ns, r) = (lt[0].hypot(lt[1]), s[0].hypot(s[1]), bound(b.weight, lambda[b.normal]));
        worst = worst.max((nl - r).max(0.0) / lam_s);
        // s ∥ −λ_t: the component of s along λ_t's normal direction vanishes, and s·λ_t ≤ 0
        let cross = (s[0] * lt[1] - s[1] * lt[0]).abs() / (s_s * lam_s);
        let along = (s[0] * lt[0] + s[1] * lt[1]).max(0.0) / (s_s * lam_s);
        // inside the disc (by more than the residual's own scale) the node sticks
        let stick = if nl < r - 1e-6 * lam_s { ns / s_s } else { 0.0 };
        worst = worst.max(cross).max(along).max(stick);
    }
    worst
}

/// uzawa with the extras' metric the projection with friction needs (theory §8.3).
pub fn uzawa_forced() -> Uzawa {
    Uzawa { extra_metric: 1.0, ..uzawa() }
}

/// `p` solved by uzawa, newton (from zero) and penalty, each with every one of its (more than
/// 4) contact nodes slipping.
pub fn solve_slipping_everywhere(p: &DiscreteProblem) -> Vec<Solution> {
    let sols = vec![solve(&uzawa(), p), newton_from_zero(p), solve(&Penalty::default(), p)];
    for sol in &sols {
        slipping_everywhere(p, sol);
    }
    sols
}

/// Every one of the (more than 4) contact nodes of `sol` slips.
pub fn slipping_everywhere(p: &DiscreteProblem, sol: &Solution) {
    let reports = p.view().contact_reports(&sol.extras, &sol.lambda);
    let report = &reports[0].report;
    let (contact, slip) = (report.contact_nodes, report.get("slip_nodes").unwrap() as usize);
    assert!(contact > 4 && slip == contact, "{}: {contact} contact nodes, {slip} slip", sol.report.solver);
}

/// max|a − b| / max|b|, 0 for no entry.
pub fn rel_or_zero(a: &[f64], b: &[f64]) -> f64 {
    if b.is_empty() { 0.0 } else { rel(a, b) }
}

/// uzawa, socp, newton and penalty on the scene `p` of partial slip: some contact nodes stick,
/// some slip; all agree with uzawa to 1e-7 in u, λ and the extras, and each meets the friction
/// conditions of the bound `bound(w, λ_n)` recomputed from the rows to 1e-6 and the library's
/// KKT residual to its own tolerance. `forced`: extras under force control (uzawa with the
/// extras' metric, newton cold; else newton's own iterations from zero). `socp_lambda`: socp's
/// tolerance in λ, 1e-7 but where its interior point (no polish with friction, theory §8.3) was
/// measured further. Returns uzawa's answer.
pub fn agree(p: &DiscreteProblem, bound: impl Fn(f64, f64) -> f64 + Copy, forced: bool, socp_lambda: f64) -> Solution {
    let su = if forced { solve(&uzawa_forced(), p) } else { solve(&uzawa(), p) };
    let sn = if forced { solve(&Newton::default(), p) } else { newton_from_zero(p) };
    let (ss, sp) = (solve(&socp(), p), solve(&Penalty::default(), p));
    let reports = p.view().contact_reports(&su.extras, &su.lambda);
    let report = &reports[0].report;
    let (stick, slip) = (report.get("stick_nodes").unwrap(), report.get("slip_nodes").unwrap());
    println!("stick {stick}, slip {slip}, report {:?}", report.quantities);
    assert!(stick > 0.0 && slip > 0.0, "partial slip wanted: {stick} stick, {slip} slip");
    for other in [&ss, &sn, &sp] {
        let (du, dl) = (rel(&other.u, &su.u), rel(&other.lambda, &su.lambda));
        let dv = rel_or_zero(&other.extras, &su.extras);
        println!("{} against uzawa: u {du:.2e}, λ {dl:.2e}, extras {dv:.2e}", other.report.solver);
        let tol_l = if other.report.solver == "socp" { socp_lambda } else { 1e-7 };
        assert!(du < 1e-7 && dl < tol_l && dv < 1e-7, "{}: u {du:e}, λ {dl:e}, extras {dv:e}", other.report.solver);
    }
    for sol in [&su, &ss, &sn, &sp] {
        let r = friction_conditions(p, sol, bound);
        let l = p.lagrangian();
        let k = kkt(&l, &sol.iterate(), &mut Workspace::new(&l));
        println!("{}: friction conditions {r:.2e}, kkt {:?}", sol.report.solver, k);
        assert!(r < 1e-6 && k.max() < sol.report.tolerance, "{}: {r:e} {k:?}", sol.report.solver);
    }
    su
}

/// Full sliding under Coulomb's law of coefficient `mu` (theory §8.3): `p` solved by uzawa,
/// newton and penalty, every contact node slipping on the rim of its cone, so
/// Σ|λ_t| = μ Σλ_n to 1e-10, and the Coulomb conditions recomputed to 1e-7.
pub fn assert_full_sliding(p: &DiscreteProblem, mu: f64) {
    for sol in solve_slipping_everywhere(p) {
        let l = p.lagrangian();
        let rows = l.data.rows;
        let (mut tangential, mut normal) = (0.0, 0.0);
        for b in &rows.friction.blocks {
            tangential += sol.lambda[b.tangent].hypot(sol.lambda[b.tangent + 1]);
            normal += sol.lambda[b.normal];
        }
        let name = &sol.report.solver;
        println!("{name}: Σ|λ_t| = {tangential:.15e}, μ Σλ_n = {:.15e}", mu * normal);
        let defect = (tangential - mu * normal).abs();
        assert!(defect <= 1e-10 * mu * normal, "{name}: {tangential:e} against {:e}", mu * normal);
        let r = friction_conditions(p, &sol, |_, ln| mu * ln.max(0.0));
        assert!(r < 1e-7, "{name}: Coulomb conditions {r:e}");
    }
}
