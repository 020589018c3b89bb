//! Loads on u (tractions, body forces): uniaxial tension of a bar on rollers is exact for
//! P1/P0, elastic and plastic, for every solver; an elastic scene without contact is one linear
//! solve and builds no contact structures and runs no return mapping.

use saddle::core::{DiscreteProblem, energy};
use saddle::core::{Silent, Solver};
use saddle::io::scene::Scene;
use std::path::Path;

/// Rollers on the three coordinate planes through the origin: a body free to stretch and
/// contract laterally, held against rigid-body motion.
const ROLLERS: &str = r#"[[dirichlet]]
on = { group = "xmin" }
components = ["x"]
[[dirichlet]]
on = { group = "ymin" }
components = ["y"]
[[dirichlet]]
on = { group = "zmin" }
components = ["z"]"#;

fn bar(p: f64, plastic: bool) -> DiscreteProblem {
    let yield_table = if plastic { "[yield]\ntype = \"von_mises\"\nk0 = 1.0\nh = 5.0\n" } else { "" };
    let text = format!(
        r#"
[mesh]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 2.0]
cells = [2, 2, 4]
[material]
E = 100.0
nu = 0.3
{yield_table}
{ROLLERS}
[[load]]
type = "traction"
on = {{ group = "zmax" }}
t = [0.0, 0.0, {p}]
"#
    );
    Scene::from_toml(&text, Path::new("bar.toml")).unwrap().into_problem().unwrap().0
}

/// ε₁₁ and ε₃₃ of uniaxial tension σ₃₃ = p (theory §2 with |s| = sqrt(2/3) p).
fn strains(p: f64, plastic: bool) -> (f64, f64) {
    let (e, nu, k0, h) = (100.0, 0.3, 1.0, 5.0);
    let (mut e11, mut e33) = (-nu * p / e, p / e);
    let s = (2.0f64 / 3.0).sqrt() * p;
    if plastic && s > k0 {
        let pm = (s - k0) / h;
        e11 += pm * (-p / 3.0) / s;
        e33 += pm * (2.0 * p / 3.0) / s;
    }
    (e11, e33)
}

fn solvers() -> Vec<Box<dyn Solver>> {
    let mut v: Vec<Box<dyn Solver>> = vec![
        Box::new(saddle::solvers::Uzawa { tol: 1e-11, ..Default::default() }),
        Box::new(saddle::solvers::Newton::default()),
        Box::new(saddle::solvers::Penalty::default()),
    ];
    #[cfg(feature = "socp")]
    v.push(Box::new(saddle::solvers::Socp::default()));
    v
}

#[test]
fn uniaxial_tension_is_exact_for_every_solver() {
    for plastic in [false, true] {
        let p = 2.0;
        let l = bar(p, plastic);
        let (e11, e33) = strains(p, plastic);
        for s in solvers() {
            let sol = s.solve(&l.lagrangian(), &mut Silent).unwrap();
            assert!(
                sol.report.converged,
                "{} plastic={plastic}: {:?} kkt {:?} history {:?} counters {:?}",
                s.name(),
                sol.report.stop_reason,
                sol.report.kkt,
                sol.report.residual_history,
                sol.report.counters
            );
            for (x, d) in l.element.mesh().nodes.iter().zip(l.element.nodal_vectors(&sol.u)) {
                let exact = [e11 * x[0], e11 * x[1], e33 * x[2]];
                for c in 0..3 {
                    assert!(
                        (d[c] - exact[c]).abs() <= 1e-8 * e33 * 2.0,
                        "{} plastic={plastic}: node {x:?}: {d:?} vs {exact:?}",
                        s.name()
                    );
                }
            }
            assert!(sol.stress.sigma.iter().all(|sg| (sg[2] - p).abs() <= 1e-8 * p), "{}", s.name());
            assert_eq!(sol.stress.n_plastic(), if plastic { l.element.n_points() } else { 0 });
        }
    }
}

#[test]
fn an_elastic_scene_without_contact_is_one_linear_solve() {
    let l = bar(0.5, false);
    let uz = saddle::solvers::Uzawa::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert_eq!(uz.report.iterations, 1);
    assert_eq!(uz.report.counters["factorisations"], 1.0);
    assert_eq!(uz.report.counters["triangular_solve_pairs"], 1.0);
    assert_eq!(uz.report.counters["contact_structures"], 0.0);
    assert_eq!(uz.report.counters["return_mappings"], 0.0);
    assert!(uz.report.phases.iter().all(|(p, _)| p != "contact set-up"));
    let nt = saddle::solvers::Newton::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert_eq!((nt.report.iterations, nt.report.counters["factorisations"]), (1, 1.0));
    assert_eq!(nt.report.counters["return_mappings"], 0.0);
    // J = −½ f_u·u at the elastic solution (Clapeyron)
    let j = energy(&l.lagrangian(), &nt.u, &[], &mut saddle::core::Workspace::new(&l.lagrangian()));
    let work: f64 = l.lagrangian().data.nodal_load.iter().zip(&nt.u).map(|(f, u)| f * u).sum();
    assert!((j + 0.5 * work).abs() <= 1e-12 * work);
}

/// Max nodal error of the column under its own weight on `cells` layers and `cells / 4` cells
/// across (ν = 0, rollers, fixed bottom): u₃(z) = −(ρg/E)(H z − z²/2).
fn column_error(cells: usize) -> f64 {
    let lateral = cells / 4;
    let text = format!(
        r#"
[mesh]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
cells = [{lateral}, {lateral}, {cells}]
[material]
E = 100.0
nu = 0.0
{ROLLERS}
[[load]]
type = "body_force"
b = [0.0, 0.0, -0.8]
"#
    );
    let l = Scene::from_toml(&text, Path::new("col.toml")).unwrap().into_problem().unwrap().0;
    let sol = saddle::solvers::Newton::default().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    l.element
        .mesh()
        .nodes
        .iter()
        .zip(l.element.nodal_vectors(&sol.u))
        .map(|(x, d)| (d[2] + (0.8 / 100.0) * (x[2] - 0.5 * x[2] * x[2])).abs())
        .fold(0.0, f64::max)
}

#[test]
fn body_force_column_converges_to_the_closed_form() {
    // the top moves by −(ρg/E) H²/2 = −4e-3; halving h at least halves the nodal error
    // (measured: 1.96e-4 → 8.05e-5, a ratio of 2.4 on these pre-asymptotic meshes)
    let (e8, e16) = (column_error(8), column_error(16));
    assert!(e8 < 0.05 * 4e-3, "error {e8:e} on 8 layers");
    assert!(e8 / e16 > 2.0, "errors {e8:e} → {e16:e}: not converging");
}
