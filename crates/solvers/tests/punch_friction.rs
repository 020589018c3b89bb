//! Friction on the punches (theory §8.3): `rigid_punch`, `rigid_punch_displacement` and
//! `tilting_punch` with Tresca's and Coulomb's laws, solved by uzawa, socp, newton and penalty
//! against each other and against the limits of the laws — g = 0 is the frictionless punch,
//! full sliding puts every tangential force on its rim, and a tangential force above what the
//! flat punch's friction can carry has no solution — with the friction conditions recomputed
//! from the rows (common::friction), not taken from the solvers' residuals.

mod common;

use common::friction::*;
use common::{SCALED, johnson_with};
use saddle_contact::{Coulomb, Flat, Paraboloid, RigidPunch, RigidPunchDisplacement, TiltingPunch, Tresca};
use saddle_core::{
    AdmissibleDisplacements, DiscreteProblem, FrictionLaw, Region, Silent, Solution, SolveError, Solver,
    normal_contact_set,
};
use saddle_solvers::{Newton, Penalty};

fn tresca(g: f64) -> Option<Box<dyn FrictionLaw>> {
    Some(Box::new(Tresca { g }))
}

fn coulomb(mu: f64) -> Option<Box<dyn FrictionLaw>> {
    Some(Box::new(Coulomb { mu }))
}

/// The default scene's body (elastic, 8 × 8 × 4 cells) with the obstacle `k(zone)`.
fn scene(k: impl FnOnce(Region) -> Box<dyn AdmissibleDisplacements>) -> DiscreteProblem {
    johnson_with([8, 8, 4], None, SCALED, |zone, _, _| k(zone))
}

/// The paraboloid punch (R = 5) moved up by U = 0.02 and across by `w`, with the law `law`.
fn moved(law: Option<Box<dyn FrictionLaw>>, w: [f64; 2]) -> DiscreteProblem {
    scene(|zone| {
        let k = RigidPunchDisplacement::new(0.02, zone, Box::new(Paraboloid::new(5.0))).unwrap();
        Box::new(RigidPunchDisplacement { friction: law, W: Some(w), ..k })
    })
}

/// The paraboloid punch (R = 5) pushed by F = 0.5 and pulled by `q`, with the law `law`.
fn pulled(law: Option<Box<dyn FrictionLaw>>, q: [f64; 2]) -> DiscreteProblem {
    scene(|zone| {
        let k = RigidPunch::new(0.5, zone, Box::new(Paraboloid::new(5.0))).unwrap();
        Box::new(RigidPunch { friction: law, Q: Some(q), ..k })
    })
}

/// Tresca (g = 0.1) under a prescribed motion across the axis W = (0.001, 0): partial slip,
/// the four solvers agree and meet |λ_t| ≤ g w, stick ⇒ s = 0, slip ⇒ s ∥ −λ_t.
#[test]
fn tresca_partial_slip_under_prescribed_motion() {
    let g = 0.1;
    agree(&moved(tresca(g), [0.001, 0.0]), |w, _| g * w, false, 1e-7);
}

/// Coulomb (μ = 0.3) under W = (0.001, 0.0005): partial slip, |λ_t| ≤ μ λ_n.
#[test]
fn coulomb_partial_slip_under_prescribed_motion() {
    let mu = 0.3;
    agree(&moved(coulomb(mu), [0.001, 0.0005]), |_, ln| mu * ln.max(0.0), false, 1e-7);
}

/// The resultants of uzawa's answer on the force-controlled punch balance the loads: `force`
/// = F and (`force_x`, `force_y`) = Q to 1e-8 of F (uzawa's tolerance 1e-11).
fn balanced(p: &DiscreteProblem, sol: &Solution, f: f64, q: [f64; 2]) {
    let reports = p.view().contact_reports(&sol.extras, &sol.lambda);
    let r = &reports[0].report;
    let (force, fx, fy) = (r.get("force").unwrap(), r.get("force_x").unwrap(), r.get("force_y").unwrap());
    println!("force {force}, force_x {fx}, force_y {fy}, Ux {:?}, Uy {:?}", r.get("Ux"), r.get("Uy"));
    assert!((force - f).abs() < 1e-8 * f && (fx - q[0]).abs() < 1e-8 * f && (fy - q[1]).abs() < 1e-8 * f);
    let n = sol.extras.len();
    assert_eq!([r.get("Ux").unwrap(), r.get("Uy").unwrap()], [sol.extras[n - 2], sol.extras[n - 1]]);
}

/// Coulomb (μ = 0.3) under force control: pushed by F = 0.5, pulled by Q = (0.5 μF, 0.2 μF)
/// (|Q| = 0.54 μF < μF): partial slip, the four solvers agree in u, λ and (U, Ux, Uy), and the
/// resultants balance F and Q. socp's λ to 3e-7 (measured 1.6e-7, 1.6e-7 again with
/// coulomb_tol = 1e-11: the interior point's own accuracy, as on the sphere's force-controlled
/// scene of friction.rs; its u 3.9e-8 and extras 7.4e-9 are within 1e-7).
#[test]
fn coulomb_partial_slip_under_force() {
    let (f, mu) = (0.5, 0.3);
    let q = [0.5 * mu * f, 0.2 * mu * f];
    let p = pulled(coulomb(mu), q);
    let su = agree(&p, |_, ln| mu * ln.max(0.0), true, 3e-7);
    balanced(&p, &su, f, q);
}

/// Tresca (g = 0.5) under force control: pushed by F = 0.5, pulled by Q = (0.3, 0): partial
/// slip (measured: 6 contact nodes stick, 3 slip; at Q = 0.15 all 9 stick, and with g = 0.1 the
/// radial slip of the pressed face alone makes every contact node slip), the solvers agree and
/// the resultants balance F and Q. (Tresca's bound acts at the separated zone nodes too.)
#[test]
fn tresca_partial_slip_under_force() {
    let (f, g, q) = (0.5, 0.5, [0.3, 0.0]);
    let p = pulled(tresca(g), q);
    let su = agree(&p, |w, _| g * w, true, 1e-7);
    balanced(&p, &su, f, q);
}

/// Full sliding under a prescribed motion that every contact node's stick would exceed
/// (Coulomb, μ = 0.3, W = (0.02, 0.01)): every contact node slips on the rim of its cone, so
/// Σ|λ_t| = μ Σλ_n over the contact nodes to 1e-10 on uzawa, newton and penalty, and the
/// Coulomb conditions hold.
#[test]
fn coulomb_full_sliding_under_prescribed_motion() {
    let mu = 0.3;
    let p = moved(coulomb(mu), [0.02, 0.01]);
    assert_full_sliding(&p, mu);
}

/// The flat punch pushed by F = 0.5 and pulled by Q = 1.5 μF (Coulomb, μ = 0.3): its rows'
/// normal is the axis everywhere, so the contact forces' resultant across it is Σλ_t with
/// |λ_t| ≤ μλ_n, at most μF < Q: no solution, and uzawa and newton (and socp, penalty) say so
/// (`BeyondCollapse`, theory §4.6), never a number.
#[test]
fn a_force_beyond_friction_has_no_solution() {
    let (f, mu) = (0.5, 0.3);
    let p = scene(|zone| {
        let k = RigidPunch::new(f, zone, Box::new(Flat::default())).unwrap();
        Box::new(RigidPunch { friction: coulomb(mu), Q: Some([1.5 * mu * f, 0.0]), ..k })
    });
    for s in [&uzawa_forced() as &dyn Solver, &Newton::default(), &socp(), &Penalty::default()] {
        match s.solve(&p.lagrangian(), &mut Silent) {
            Err(SolveError::BeyondCollapse { solver, evidence }) => println!("{solver}: {evidence}"),
            other => panic!("{}: {:?}", s.name(), other.map(|s| (s.report.converged, s.extras))),
        }
    }
}

/// Tresca with g = 0 (theory §8.3: g = 0 is frictionless, a huge g bonded) under W = (0.001, 0)
/// is the frictionless punch: u, the normal multipliers and U to 1e-10 of their size (socp, the
/// interior point alone with friction, to 1e-7), the frictionless one solved by newton to 1e-13.
#[test]
fn tresca_with_zero_bound_is_the_frictionless_punch() {
    let punch = |zone| RigidPunch::new(0.3, zone, Box::new(Paraboloid::new(5.0))).unwrap();
    let free = scene(|zone| Box::new(punch(zone)));
    let reference = solve(&Newton { tol: 1e-13, ..Newton::default() }, &free);
    let with = scene(|zone| Box::new(RigidPunch { friction: tresca(0.0), W: Some([0.001, 0.0]), ..punch(zone) }));
    let rows = with.lagrangian().data.rows.clone();
    assert!(rows.has_friction() && rows.n_rows() == 3 * free.lagrangian().data.rows.n_rows());
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let penalty = Penalty::default();
    let newton = Newton::default();
    for (s, tol) in [(&uzawa_forced() as &dyn Solver, 1e-10), (&socp(), 1e-7), (&newton, 1e-10), (&penalty, 1e-10)] {
        let sol = solve(s, &with);
        let normal: Vec<f64> = (0..rows.n_rows()).filter(|&i| !tangential[i]).map(|i| sol.lambda[i]).collect();
        let (du, dl, dv) =
            (rel(&sol.u, &reference.u), rel(&normal, &reference.lambda), rel(&sol.extras, &reference.extras));
        println!("{}: u {du:.2e}, λ_n {dl:.2e}, U {dv:.2e}", s.name());
        assert!(du < tol && dl < tol && dv < tol, "{}: u {du:e}, λ_n {dl:e}, U {dv:e}", s.name());
    }
}

/// The tilting punch pushed by F = 0.5 at a = (0.1, 0.05) and pulled by Q = (0.5 μF, 0)
/// (Coulomb, μ = 0.3): the four solvers agree in u, λ and the extras (U, slope_x1, slope_x2,
/// Ux, Uy); the slopes are not zero (the load is off the pivot), the resultants balance F and Q,
/// and the moments F (a − c).
#[test]
fn the_tilting_punch_with_friction_agrees_across_solvers() {
    let (f, mu, a) = (0.5, 0.3, [0.1, 0.05]);
    let q = [0.5 * mu * f, 0.0];
    let p = scene(|zone| {
        let k = TiltingPunch::new(f, zone, Box::new(Paraboloid::new(5.0))).unwrap().at(a).unwrap();
        Box::new(TiltingPunch { friction: coulomb(mu), Q: Some(q), ..k })
    });
    let su = agree(&p, |_, ln| mu * ln.max(0.0), true, 1e-7);
    println!("extras {:?}", su.extras);
    assert!(su.extras[1].abs() > 1e-6 && su.extras[2].abs() > 1e-6, "{:?}", su.extras);
    balanced(&p, &su, f, q);
    let reports = p.view().contact_reports(&su.extras, &su.lambda);
    let r = &reports[0].report;
    let (m1, m2) = (r.get("moment_x1").unwrap(), r.get("moment_x2").unwrap());
    assert!((m1 - f * a[0]).abs() < 1e-8 * f && (m2 - f * a[1]).abs() < 1e-8 * f, "{m1}, {m2}");
    // the contact set of the normal rows only
    let l = p.lagrangian();
    assert_eq!(r.contact_nodes, normal_contact_set(l.data.rows, &su.lambda).len());
}
