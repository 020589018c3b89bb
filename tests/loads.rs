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

/// A box [0, max] of `cells` on [`ROLLERS`] (E = 100, ν = 0.3; von Mises k₀ = 1, h = 5 when
/// `plastic`) with the scene text `tail` (loads, more supports).
fn rollered_box(max: [f64; 3], cells: [usize; 3], plastic: bool, tail: &str) -> DiscreteProblem {
    let yield_table = if plastic { "[yield]\ntype = \"von_mises\"\nk0 = 1.0\nh = 5.0\n" } else { "" };
    let text = format!(
        "[mesh]\ntype = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = {max:?}\ncells = {cells:?}\n[material]\nE = 100.0\nnu = \
         0.3\n{yield_table}\n{ROLLERS}\n{tail}"
    );
    Scene::from_toml(&text, Path::new("bar.toml")).unwrap().into_problem().unwrap().0
}

fn bar(p: f64, plastic: bool) -> DiscreteProblem {
    let traction = format!("[[load]]\ntype = \"traction\"\non = {{ group = \"zmax\" }}\nt = [0.0, 0.0, {p}]");
    rollered_box([1.0, 1.0, 2.0], [2, 2, 4], plastic, &traction)
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

/// The tensile bar of examples/tensile_bar.toml, small: [0, 2] × [0, 1]², rollers on the three
/// planes through the origin, and a grip on x = 2 prescribing u_x = 0.1 (ε = 0.05), scaled by the
/// load factor. Von Mises with linear isotropic hardening (E = 100, ν = 0.3, k₀ = 1, h = 5).
fn tensile_bar() -> DiscreteProblem {
    let grip = "[[dirichlet]]\nname = \"grip\"\non = { group = \"xmax\" }\ncomponents = [\"x\"]\nvalue = [0.1]";
    rollered_box([2.0, 1.0, 1.0], [4, 2, 2], true, grip)
}

/// Uniaxial stress σ of the bar at axial strain ε after loading monotonically (theory §2 with
/// |dev σ| = √(2/3) σ): σ = Eε while √(2/3)Eε ≤ k₀; beyond, ε = σ/E + √(2/3)(√(2/3)σ − k₀)/h.
fn uniaxial_stress(eps: f64) -> f64 {
    let (e, k0, h) = (100.0, 1.0, 5.0);
    let s = (2.0f64 / 3.0).sqrt();
    if s * e * eps <= k0 { e * eps } else { (eps + s * k0 / h) / (1.0 / e + 2.0 / (3.0 * h)) }
}

/// A displacement-controlled tensile test (issue 28): the grip's reaction and every point's
/// stress against the closed form while loading to ε = 0.025 and 0.05, then unloading to the
/// closed-form residual elongation L ε_p, where the reaction vanishes; for every solver.
#[test]
fn tensile_bar_pulled_by_its_grip_follows_the_closed_form_for_every_solver() {
    let l = tensile_bar();
    let (length, area) = (2.0, 1.0);
    let s_max = uniaxial_stress(0.05);
    // ε_p = ε − σ/E at the peak: the residual strain after elastic unloading to σ = 0
    let residual = (0.05 - s_max / 100.0) * length;
    let factors = [0.5, 1.0, residual / 0.1];
    let solvers: [&str; 4] = [
        "type = \"newton\"\ntol = 1e-11",
        "type = \"uzawa\"\ntol = 1e-11",
        "type = \"penalty\"\ntol = 1e-10",
        "type = \"socp\"\ntol = 1e-11",
    ];
    for text in solvers {
        let solver: Box<dyn Solver> = toml::from_str(text).unwrap();
        let mut path = saddle::core::Evolution::new(&l);
        for (k, &factor) in factors.iter().enumerate() {
            let step = path.step(factor, solver.as_ref(), &mut Silent).unwrap();
            assert!(step.converged(), "{} step {k}: {:?}", solver.name(), step.solution.report.stop_reason);
            let sigma = if k < 2 { uniaxial_stress(0.05 * factor) } else { 0.0 };
            let view = step.problem.view();
            let reactions = view.reactions(&step.solution.stress.sigma);
            let grip = reactions.iter().find(|r| r.key == "grip").unwrap();
            let origin = reactions.iter().find(|r| r.key == "dirichlet[0]").unwrap();
            // measured: ≤ 1.3e-10 (Uzawa), ≤ 5e-11 the others; P1 holds the homogeneous state exactly
            let tol = 1e-8 * s_max * area;
            println!("{} factor {factor:.4}: F = {:.12} (exact {sigma:.12})", solver.name(), grip.force[0]);
            assert!((grip.force[0] - sigma * area).abs() <= tol, "{}: {grip:?} vs σA = {sigma}", solver.name());
            assert!((origin.force[0] + sigma * area).abs() <= tol, "{}: {origin:?}", solver.name());
            // Σ x × r over the face x = 2 of uniform forces: (0, z̄, −ȳ) σA with ȳ = z̄ = ½
            let m = [0.0, 0.5 * sigma * area, -0.5 * sigma * area];
            assert!(grip.moment.iter().zip(m).all(|(a, b)| (a - b).abs() <= tol), "{}: {grip:?}", solver.name());
            for s in &step.solution.stress.sigma {
                assert!((s[0] - sigma).abs() <= tol && s.iter().skip(1).all(|x| x.abs() <= tol), "{s:?}");
            }
            // the grip's nodes moved by the prescribed u_x
            let d = view.displacements(&step.solution.u);
            for (x, u) in l.element.mesh().nodes.iter().zip(&d) {
                if x[0] == length {
                    assert!((u[0] - 0.1 * factor).abs() <= 1e-15, "{x:?} {u:?}");
                }
            }
        }
    }
}
