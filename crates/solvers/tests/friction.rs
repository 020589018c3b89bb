//! Tresca friction on the rigid sphere (theory §8.3): the solvers that run the law (uzawa, socp,
//! newton, penalty) against each other and against the limits of the law — g = 0 is frictionless, a g above every
//! tangential force the solution needs no longer changes it, and a g that every contact node
//! exceeds under a prescribed tangential motion makes every node slip with |λ_t| = g w — with the
//! friction conditions recomputed here from the rows, not taken from the solvers' residuals.

mod common;

use common::friction::*;
use common::{SCALED, johnson_with};
use saddle_contact::{Coulomb, RigidSphere, Tresca};
use saddle_core::FrictionLaw;
use saddle_core::{DiscreteProblem, Evolution, Silent, SolveError, Solver};
use saddle_solvers::{Newton, Penalty};

/// The default scene's body (elastic, 8 × 8 × 4 cells) indented by a sphere of radius 5 moved
/// up by 0.02 and across by `w`, with Tresca's law of bound `g` (`None`: frictionless).
fn scene(g: Option<f64>, w: Option<[f64; 2]>) -> DiscreteProblem {
    scene_with(g.map(|g| Box::new(Tresca { g }) as Box<dyn FrictionLaw>), w)
}

/// The scene of [`scene`] with the friction law `law`.
fn scene_with(law: Option<Box<dyn FrictionLaw>>, w: Option<[f64; 2]>) -> DiscreteProblem {
    johnson_with([8, 8, 4], None, SCALED, |zone, _, _| {
        let mut k = RigidSphere::moved([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.02, zone);
        k.friction = law.clone();
        k.W = w;
        Box::new(k)
    })
}

/// g = 0: the tangential forces vanish, and the answer is the frictionless one (the normal rows
/// are those of the sphere without friction): u, λ_n to 1e-10 of their size, for both solvers.
#[test]
fn tresca_with_zero_bound_is_frictionless() {
    let free = scene(None, None);
    let reference = solve(&Newton { tol: 1e-13, ..Newton::default() }, &free);
    let with = scene(Some(0.0), None);
    let rows = with.lagrangian().data.rows.clone();
    assert!(rows.has_friction() && rows.n_rows() == 3 * free.lagrangian().data.rows.n_rows());
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let penalty = Penalty::default();
    for (s, tol) in [(&uzawa() as &dyn Solver, 1e-10), (&socp(), 1e-7), (&Newton::default(), 1e-10), (&penalty, 1e-10)]
    {
        let sol = solve(s, &with);
        let normal: Vec<f64> = (0..rows.n_rows()).filter(|&i| !tangential[i]).map(|i| sol.lambda[i]).collect();
        let (du, dl) = (rel(&sol.u, &reference.u), rel(&normal, &reference.lambda));
        println!("{}: u {du:.2e}, λ_n {dl:.2e}", s.name());
        // uzawa to 1e-11 reaches 1e-10; socp's interior point alone (no polish with friction) 1e-7
        assert!(du < tol && dl < tol, "{}: u {du:e}, λ_n {dl:e}", s.name());
    }
    // Newton's own iterations (measured: u 1e-15, λ_n 1e-14)
    let sol = newton_from_zero(&with);
    let normal: Vec<f64> = (0..rows.n_rows()).filter(|&i| !tangential[i]).map(|i| sol.lambda[i]).collect();
    let (du, dl) = (rel(&sol.u, &reference.u), rel(&normal, &reference.lambda));
    println!("newton from zero: u {du:.2e}, λ_n {dl:.2e}");
    assert!(du < 1e-10 && dl < 1e-10, "newton from zero: u {du:e}, λ_n {dl:e}");
}

/// A prescribed tangential motion W with a bound g that every contact node's need exceeds: all
/// slip, |λ_t| = g w at every contact node, so Σ|λ_t| = g × (the contact nodes' area) — to 1e-10
/// with uzawa (whose projection puts λ_t on the rim exactly), newton (whose slipping pairs'
/// Robin condition does at convergence) and penalty (its force P_D(−ks) is on the rim of a
/// slipping pair); and the friction conditions hold.
#[test]
fn small_bound_under_prescribed_motion_slips_everywhere_at_g_times_area() {
    let g = 1e-4;
    let p = scene(Some(g), Some([0.01, 0.005]));
    for sol in solve_slipping_everywhere(&p) {
        let l = p.lagrangian();
        let rows = l.data.rows;
        let contact_rows = saddle_core::normal_contact_set(rows, &sol.lambda);
        let in_contact = |n: usize| contact_rows.contains(&n);
        let (mut sum, mut area) = (0.0, 0.0);
        for b in rows.friction.blocks.iter().filter(|b| in_contact(b.normal)) {
            sum += sol.lambda[b.tangent].hypot(sol.lambda[b.tangent + 1]);
            area += b.weight;
        }
        let name = &sol.report.solver;
        println!("{name}: Σ|λ_t| = {sum:.15e}, g × area = {:.15e}", g * area);
        assert!((sum - g * area).abs() <= 1e-10 * g * area, "{name}: Σ|λ_t| = {sum:e}, g × area = {:e}", g * area);
        let r = friction_conditions(&p, &sol, |w, _| g * w);
        assert!(r < 1e-7, "{name}: friction conditions {r:e}");
    }
}

/// Above every tangential force the solution needs (bonded contact, all contact nodes stick),
/// the bound no longer matters: g = 10 and g = 1000 give the same answer to 1e-9, every contact
/// node sticks; newton's iteration (from zero) on g = 1000 is uzawa's g = 10 to 1e-10
/// (measured: u 1e-15, λ 4e-15 — every pair active, the bonded problem solved exactly).
#[test]
fn a_bound_above_every_need_sticks_and_no_longer_matters() {
    let w = Some([0.002, 0.0]);
    let a = scene(Some(10.0), w);
    let b = scene(Some(1000.0), w);
    let (sa, sb) = (solve(&uzawa(), &a), solve(&uzawa(), &b));
    let du = rel(&sa.u, &sb.u);
    let dl = rel(&sa.lambda, &sb.lambda);
    println!("u {du:.2e}, λ {dl:.2e}");
    assert!(du < 1e-9 && dl < 1e-9, "u {du:e}, λ {dl:e}");
    let sn = newton_from_zero(&b);
    let (du, dl) = (rel(&sn.u, &sa.u), rel(&sn.lambda, &sa.lambda));
    println!("newton: u {du:.2e}, λ {dl:.2e}");
    assert!(du < 1e-10 && dl < 1e-10, "newton: u {du:e}, λ {dl:e}");
    let reports = a.view().contact_reports(&sa.extras, &sa.lambda);
    let report = &reports[0].report;
    assert_eq!(report.get("stick_nodes").unwrap() as usize, report.contact_nodes);
    assert!(report.contact_nodes > 4);
}

/// uzawa and socp on a scene of partial slip (g = 0.1: 8 contact nodes stick, 13 slip) agree
/// to 1e-7 (measured: u 1.5e-8, λ 5.6e-8 of their size), and each meets the friction
/// conditions recomputed here (and the library's KKT residual, equilibrium included).
#[test]
fn uzawa_and_socp_agree_on_partial_slip() {
    let g = 0.1;
    agree_on_partial_slip(&scene(Some(g), Some([0.001, 0.0])), |w, _| g * w);
}

/// uzawa, socp, newton (its iteration from zero) and penalty on the scene `p` of partial slip:
/// some contact nodes stick, some slip, all agree with uzawa to 1e-7 in u and λ (measured:
/// newton and penalty to 1e-12, socp 1.5e-8 and 8e-8), and each meets the friction conditions
/// of the bound `bound(w, λ_n)` recomputed here to 1e-6 and the library's KKT residual to its
/// own tolerance (uzawa 1e-11, socp 1e-7: measured 2.8e-8 with Tresca, 1.8e-8 with Coulomb;
/// newton 1e-10, penalty 1e-8).
fn agree_on_partial_slip(p: &DiscreteProblem, bound: impl Fn(f64, f64) -> f64 + Copy) {
    agree(p, bound, false, 1e-7);
}

/// Coulomb's law (μ = 0.3) on the partial-slip scene (15 contact nodes stick, 6 slip): uzawa
/// (the disc of the current normal multiplier inside its projection's sweeps) and socp (the
/// fixed point of Tresca problems, 6 solves) agree to 1e-7 (measured: u 1.5e-8, λ 8.0e-8 — the
/// interior point's accuracy: with coulomb_tol = 1e-10, 8 solves, the same 8.0e-8), and each
/// meets Coulomb's conditions |λ_t| ≤ μ λ_n, s = −κ λ_t recomputed here from the rows.
#[test]
fn coulomb_uzawa_and_socp_agree_on_partial_slip() {
    let mu = 0.3;
    agree_on_partial_slip(&scene_with(Some(Box::new(Coulomb { mu })), Some([0.001, 0.0])), |_, ln| mu * ln.max(0.0));
}

/// Full sliding under a prescribed tangential motion (theory §8.3): every contact node on the
/// rim of its cone, so Σ|λ_t| = μ Σλ_n over the contact nodes to 1e-10 (uzawa's projection
/// puts each λ_t on its rim exactly, at the radius of its own λ_n), newton and penalty alike.
#[test]
fn coulomb_full_sliding_under_prescribed_motion() {
    let mu = 0.3;
    let p = scene_with(Some(Box::new(Coulomb { mu })), Some([0.02, 0.01]));
    assert_full_sliding(&p, mu);
}

/// A load path (theory §11.6) on the partial-slip Tresca scene: the sphere pressed and moved
/// across (factors 0.5, 1), then half-way back (0.5). Each step's slip is the increment against
/// the previous step: recomputed here from the obstacle's own geometry (its exact gap's total
/// slip t·(u − V d − W) at this step minus the previous step's, not from the rows' shifted
/// offsets), it meets Tresca's conditions at every step; the dissipated energy the obstacles
/// report is Σ_steps Σ_i g w_i |Δs_i| recomputed from those increments (on the rim
/// −λ_t·Δs = r|Δs|); and the path matters: at the last step (factor 0.5 again, unloading) the
/// tangential force differs from the first step's (the total form at 0.5) — the hysteresis.
#[test]
fn a_load_path_slips_incrementally_and_dissipates() {
    let g = 0.1;
    let p = scene(Some(g), Some([0.001, 0.0]));
    let (mesh, dofs) = (p.element.mesh(), p.element.dofs());
    let mut evolution = Evolution::new(&p);
    let (mut previous, mut dissipated) = (None::<Vec<f64>>, 0.0);
    let (mut force_x, mut uzawa_dissipated) = (Vec::new(), Vec::new());
    for factor in [0.5, 1.0, 0.5] {
        let step = evolution.step(factor, &uzawa(), &mut Silent).unwrap();
        assert!(step.converged(), "factor {factor}: {:?}", step.solution.report.kkt);
        let sol = &step.solution;
        let obstacles = step.problem.obstacles();
        let rows = obstacles.rows();
        let mut total = vec![0.0; rows.n_rows()];
        obstacles.gap(mesh, dofs, &sol.u, &sol.extras, &mut total);
        // the normal rows' linear gaps, the tangential rows' increments of the exact slip
        let mut values = vec![0.0; rows.n_rows()];
        rows.gap(&sol.u, &sol.extras, &mut values);
        let mut step_dissipation = 0.0;
        for b in &rows.friction.blocks {
            for t in [b.tangent, b.tangent + 1] {
                values[t] = total[t] - previous.as_ref().map_or(0.0, |s| s[t]);
            }
            let ds = values[b.tangent].hypot(values[b.tangent + 1]);
            let on_rim = sol.lambda[b.tangent].hypot(sol.lambda[b.tangent + 1]) >= (1.0 - 1e-6) * g * b.weight;
            step_dissipation += if on_rim { g * b.weight * ds } else { 0.0 };
        }
        let r = conditions(rows, &sol.lambda, &values, |w, _| g * w);
        dissipated += step_dissipation;
        let reported = obstacles.dissipated(&sol.u, &sol.extras, &sol.lambda)[0];
        let reports = step.problem.view().contact_reports(&sol.extras, &sol.lambda);
        let report = &reports[0].report;
        force_x.push(report.get("force_x").unwrap());
        println!(
            "factor {factor}: conditions {r:.2e}, step dissipation {step_dissipation:.6e}, total {dissipated:.9e}, \
             reported {reported:.9e}, stick {:?}, slip {:?}, force_x {:?}",
            report.get("stick_nodes"),
            report.get("slip_nodes"),
            force_x.last()
        );
        // uzawa's tolerance 1e-11; the increments carry the exact slip's round-off
        assert!(r < 1e-6, "factor {factor}: incremental conditions {r:e}");
        assert!(step_dissipation > 0.0, "factor {factor}: no slip");
        assert!((reported - dissipated).abs() <= 1e-8 * dissipated, "{reported:e} against {dissipated:e}");
        uzawa_dissipated.push(reported);
        previous = Some(total);
    }
    // newton on the same path (warm-started steps: its semismooth iterations) dissipates the
    // same energy to 1e-7 (measured: 1e-12, uzawa's tolerance 1e-11)
    let mut evolution = Evolution::new(&p);
    for (factor, expected) in [0.5, 1.0, 0.5].into_iter().zip(&uzawa_dissipated) {
        let step = evolution.step(factor, &Newton::default(), &mut Silent).unwrap();
        assert!(step.converged(), "newton, factor {factor}: {:?}", step.solution.report.kkt);
        let sol = &step.solution;
        let reported = step.problem.obstacles().dissipated(&sol.u, &sol.extras, &sol.lambda)[0];
        println!("newton, factor {factor}: dissipated {reported:.12e} against uzawa's {expected:.12e}");
        assert!((reported - expected).abs() <= 1e-7 * expected, "newton: {reported:e} against {expected:e}");
    }
    let (first, last) = (force_x[0], force_x[2]);
    assert!((last - first).abs() > 0.1 * first.abs(), "force_x at 0.5 loading {first:e}, unloading {last:e}");
}

/// The scene of [`scene`] with the sphere pushed by the force `f` and pulled across by
/// `q = [Qx, 0]`, Coulomb's law of coefficient `mu`.
fn pulled(f: f64, qx: f64, mu: f64) -> DiscreteProblem {
    johnson_with([8, 8, 4], None, SCALED, |zone, _, _| {
        let k = RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], f, zone);
        Box::new(RigidSphere { Q: Some([qx, 0.0]), ..k.with_friction(Box::new(Coulomb { mu })) })
    })
}

/// Coulomb under force control (theory §8.3): pushed by F and pulled by Q = 0.5 μF, uzawa,
/// socp, newton and penalty agree (to 1e-7 in u and the extras `V`, `Ux`, `Uy`, 3e-7 in λ) and the sphere's
/// resultants balance F and Q; pulled by Q = 2 μF — more than friction and the tilt of the
/// contact normals can balance (bound in the test) — both report that the problem has no
/// solution (theory §4.6), never a number — all four solvers. (At Q = 1.2 μF the linearised rows still have a
/// solution: socp finds it at Ux = 0.30, the sphere climbing the tilted tangent planes of the
/// reference configuration far beyond the linearisation's validity; theory §8.3.)
#[test]
fn coulomb_force_control_partial_slip_and_sliding() {
    let (f, mu) = (0.5, 0.3);
    let p = pulled(f, 0.5 * mu * f, mu);
    let (su, ss) = (solve(&uzawa_forced(), &p), solve(&socp(), &p));
    // newton (cold: its elastic start needs the extras' metric, so its own iterations) and
    // penalty agree with uzawa to 1e-7 (measured: u 2e-12, λ 8e-12, extras 2e-12; penalty 5e-13,
    // 1.4e-12, 5e-13)
    for other in [solve(&Newton::default(), &p), solve(&Penalty::default(), &p)] {
        let (du, dl, dv) = (rel(&other.u, &su.u), rel(&other.lambda, &su.lambda), rel(&other.extras, &su.extras));
        println!("{} against uzawa: u {du:.2e}, λ {dl:.2e}, extras {dv:.2e}", other.report.solver);
        assert!(du < 1e-7 && dl < 1e-7 && dv < 1e-7, "{}: u {du:e}, λ {dl:e}, extras {dv:e}", other.report.solver);
        let r = friction_conditions(&p, &other, |_, ln| mu * ln.max(0.0));
        assert!(r < 1e-6, "{}: Coulomb conditions {r:e}", other.report.solver);
    }
    let (du, dl, dv) = (rel(&ss.u, &su.u), rel(&ss.lambda, &su.lambda), rel(&ss.extras, &su.extras));
    let reports = p.view().contact_reports(&su.extras, &su.lambda);
    let report = &reports[0].report;
    println!("socp against uzawa: u {du:.2e}, λ {dl:.2e}, extras {dv:.2e}; {:?}", report.quantities);
    // measured u 2.8e-8, λ 1.15e-7, extras 3.0e-9: socp's interior point (no polish with friction)
    assert!(du < 1e-7 && dl < 3e-7 && dv < 1e-7, "u {du:e}, λ {dl:e}, extras {dv:e}");
    let (force, force_x) = (report.get("force").unwrap(), report.get("force_x").unwrap());
    assert!((force - f).abs() < 1e-8 * f && (force_x - 0.5 * mu * f).abs() < 1e-8 * f, "{force}, {force_x}");
    assert!(report.get("stick_nodes").unwrap() > 0.0 && report.get("slip_nodes").unwrap() > 0.0);
    // Q = 2μF: the resultants Q = Σλ_n n_i·e₁ + Σλ_t·t_i·e₁ ≤ Σλ_n (sin θ + μ) and
    // F = Σλ_n n_i·d + Σλ_t·t_i·d ≥ Σλ_n (cos θ − μ sin θ), θ the largest tilt of a contact
    // normal from d (cos θ_i = n_i·d = −H_i of V): no λ balances Q/F above the ratio of the two
    let p = pulled(f, 2.0 * mu * f, mu);
    let l = p.lagrangian();
    let rows = l.data.rows;
    let tilt =
        rows.friction.blocks.iter().map(|b| (1.0 - rows.extra_row(b.normal)[0].powi(2)).sqrt()).fold(0.0, f64::max);
    let bound = (tilt + mu) / ((1.0 - tilt * tilt).sqrt() - mu * tilt);
    println!("largest tilt sin θ = {tilt:.4}: Q/F ≤ {bound:.4} < {}", 2.0 * mu);
    assert!(bound < 2.0 * mu);
    for s in [&uzawa_forced() as &dyn Solver, &socp(), &Newton::default(), &Penalty::default()] {
        match s.solve(&p.lagrangian(), &mut Silent) {
            Err(SolveError::BeyondCollapse { solver, evidence }) => println!("{solver}: {evidence}"),
            other => panic!("{}: {:?}", s.name(), other.map(|s| (s.report.converged, s.extras))),
        }
    }
}
