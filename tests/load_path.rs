//! Load paths (theory §11): Prandtl–Reuss in load steps, checked against closed forms and
//! against the stationary problem, for every solver.

mod common;
use common::*;
use saddle::core::linalg::{LowerCsc, SparseCholesky};
use saddle::core::problem::tensor::deviator;
use saddle::core::{DiscreteProblem, dual_energy, energy, energy_of_stress};
use saddle::core::{Evolution, Material, Silent, Sym, Workspace, step_factors};

/// Every solver, tight enough that the closed forms hold to 1e-8.
const SOLVERS: [&str; 4] = [
    "type = \"newton\"\ntol = 1e-11",
    "type = \"uzawa\"\ntol = 1e-11",
    "type = \"penalty\"\ntol = 1e-9",
    "type = \"socp\"\ntol = 1e-11",
];

/// One step from the zero state is the stationary problem (theory §11.1): same u, V, σ̂, λ to
/// round-off, for every solver, on the small default scene.
#[test]
fn one_step_from_zero_is_the_stationary_problem_for_every_solver() {
    let (l, _) = build(&small_johnson());
    for text in SOLVERS {
        let solver = solver(text);
        let stationary = solver.solve(&l.lagrangian(), &mut Silent).unwrap();
        let mut path = Evolution::new(&l);
        let step = path.step(1.0, solver.as_ref(), &mut Silent).unwrap();
        assert!(step.converged() && stationary.report.converged, "{text}");
        let s = &step.solution;
        let rel = |a: &[f64], b: &[f64]| {
            let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
        };
        let du = rel(&s.u, &stationary.u);
        let dv = rel(&s.extras, &stationary.extras);
        let dl = rel(&s.lambda, &stationary.lambda);
        let flat = |f: &saddle::core::StressField| f.sigma.iter().flat_map(|x| x.iter().copied()).collect::<Vec<_>>();
        let ds = rel(&flat(&s.stress), &flat(&stationary.stress));
        println!("{}: u {du:.1e}, V {dv:.1e}, λ {dl:.1e}, σ {ds:.1e}", solver.name());
        // the same solver on the same problem: the step law differs from the local law only in
        // round-off (the von Mises step law from ξ_n = 0, ε_p = 0)
        for (what, d) in [("u", du), ("V", dv), ("λ", dl), ("σ", ds)] {
            assert!(d <= 1e-10, "{}: {what} differs by {d:.2e}", solver.name());
        }
    }
}

/// Theory §7 with a load path: the unit cube in homogeneous uniaxial compression σ₃₃ = −F,
/// loaded to F = 2 (beyond first yield at F = √(3/2)) and unloaded to 0.
struct Homogeneous {
    e: f64,
    k0: f64,
    h: f64,
}

impl Homogeneous {
    /// The plastic strain after loading to `f_max` (Prandtl–Reuss = Hencky on a radial path):
    /// p = ((|s| − k₀)/h) s/|s|, s = dev σ.
    fn plastic_strain(&self, f_max: f64) -> Sym {
        let s = deviator(&Sym::new(0.0, 0.0, -f_max, 0.0, 0.0, 0.0));
        let over = (s.norm() - self.k0).max(0.0) / self.h;
        s * (over / s.norm())
    }
}

#[test]
fn homogeneous_compression_loaded_and_unloaded_matches_the_closed_form_for_every_solver() {
    let mut t = example("homogeneous.toml");
    set(&mut t, "obstacle.F", toml::Value::Float(2.0));
    let (l, _) = build(&t);
    let c = Homogeneous { e: 100.0, k0: 1.0, h: 5.0 };
    let p = c.plastic_strain(2.0);
    let xi = c.h * p.norm();
    // F = 2·factor: 1 (elastic), 2 (plastic), 1 (elastic unloading), 0 (unloaded)
    let factors = [0.5, 1.0, 0.5, 0.0];
    for text in SOLVERS {
        let solver = solver(text);
        let name = solver.name();
        let mut path = Evolution::new(&l);
        // the largest relative deviation from the closed forms over the path
        let mut worst = 0.0f64;
        for (k, &factor) in factors.iter().enumerate() {
            let step = path.step(factor, solver.as_ref(), &mut Silent).unwrap();
            assert!(
                step.converged(),
                "{name}, step {k}: {:?} {:?} {:?}",
                step.solution.report.stop_reason,
                step.solution.report.residual_history,
                step.solution.report.counters
            );
            let f = 2.0 * factor;
            let sol = &step.solution;
            // σ = −F e₃⊗e₃ everywhere
            for (i, s) in sol.stress.sigma.iter().enumerate() {
                let exact = Sym::new(0.0, 0.0, -f, 0.0, 0.0, 0.0);
                worst = worst.max((s - exact).norm() / 2.0);
                assert!((s - exact).norm() <= 1e-8 * 2.0, "{name}, step {k}, element {i}: σ = {s:?}, exact {exact:?}");
            }
            // strong duality of the step problem (theory §11.1): J_n(u) equals the dual energy
            // −(½Aσ:σ + ½|q − q_n|²_H + (ε_p, σ) + λ·c) at the solution
            let mut ws = Workspace::new(&step.problem.lagrangian());
            let j = energy(&step.problem.lagrangian(), &sol.u, &sol.extras, &mut ws);
            let dual = dual_energy(&step.problem.lagrangian(), &sol.stress, &sol.lambda);
            // the work of the largest load, F·U, is the problem's energy scale (J → 0 unloaded)
            let scale = j.abs().max(2.0 * (2.0 / c.e - p[2]));
            assert!((j - dual).abs() <= 1e-8 * scale, "{name}, step {k}: J = {j:e}, dual {dual:e}");
            // J from the stresses (uzawa's safeguard, theory §4.1) is the same J: one formula
            // rearranged, so to round-off (measured: below 1e-14 of the scale)
            let mut ws2 = Workspace::new(&step.problem.lagrangian());
            saddle::core::kkt(&step.problem.lagrangian(), &step.solution.iterate(), &mut ws2);
            let j_stress = energy_of_stress(&step.problem.lagrangian(), &sol.u, &sol.extras, &ws2.stress, &ws2.force);
            assert!(
                (j - j_stress).abs() <= 1e-12 * scale,
                "{name}, step {k}: J = {j:e}, from the stresses {j_stress:e}"
            );
            // the plastic strain: none before F = 2, p after; ξ likewise
            let p_now = if k == 0 { Sym::zeros() } else { p };
            step.problem.lagrangian().strain(&sol.u, &mut ws.eps);
            for (i, e) in ws.eps.iter().enumerate() {
                let elastic = l.lagrangian().data.elasticity.compliance(&sol.stress.sigma[i]);
                let ep = e - elastic;
                worst = worst.max((ep - p_now).norm() / p.norm());
                assert!((ep - p_now).norm() <= 1e-8 * p.norm(), "{name}, step {k}, element {i}: ε_p = {ep:?}");
                let xi_now = if k == 0 { 0.0 } else { xi };
                assert!(
                    (sol.stress.q(i)[0] - xi_now).abs() <= 1e-8 * xi,
                    "{name}, step {k}: ξ = {}",
                    sol.stress.q(i)[0]
                );
            }
            // U = −ε₃₃ = F/E − p₃₃ while the punch is loaded: on unloading the slope dF/dU = E
            if f > 0.0 {
                let u_exact = f / c.e - p_now[2];
                let u = sol.extras[0];
                worst = worst.max((u - u_exact).abs() / u_exact);
                assert!(
                    (u - u_exact).abs() <= 1e-8 * u_exact,
                    "{name}, step {k}: U = {u:.12e}, closed form {u_exact:.12e}"
                );
                assert!(step.solution.undetermined.is_empty());
            } else {
                // F = 0: U undetermined, the residual strain is the plastic strain, σ = 0
                assert_eq!(step.solution.undetermined, vec![0], "{name}: U is undetermined at F = 0");
                assert!(!step.warnings.is_empty());
                let nodal = l.element.nodal_vectors(&sol.u);
                for (x, d) in l.element.mesh().nodes.iter().zip(nodal) {
                    let exact = [p[0] * x[0], p[1] * x[1], p[2] * (x[2] - 1.0)];
                    for q in 0..3 {
                        worst = worst.max((d[q] - exact[q]).abs() / p.norm());
                        assert!(
                            (d[q] - exact[q]).abs() <= 1e-8 * p.norm(),
                            "{name}: residual u at {x:?} = {d:?}, exact {exact:?}"
                        );
                    }
                }
                assert!(sol.lambda.iter().all(|x| *x == 0.0));
            }
        }
        println!("{name}: largest relative deviation from the closed forms over the path {worst:.1e}");
    }
}

/// The unit cube in homogeneous uniaxial stress σ₃₃ = T·factor: rollers on x₁ = 0, x₂ = 0,
/// x₃ = 0 and the traction (0, 0, T) on x₃ = 1; E = 100, ν = 0.3.
fn uniaxial(yield_table: &str, factors: &[f64]) -> saddle::io::scene::Scene {
    let text = format!(
        "[mesh]\ntype = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\ncells = [1, 1, 1]\n\
         [material]\nE = 100.0\nnu = 0.3\n[yield]\n{yield_table}\n\
         [[dirichlet]]\non = {{ group = \"xmin\" }}\ncomponents = [\"x\"]\n\
         [[dirichlet]]\non = {{ group = \"ymin\" }}\ncomponents = [\"y\"]\n\
         [[dirichlet]]\non = {{ group = \"zmin\" }}\ncomponents = [\"z\"]\n\
         [[load]]\ntype = \"traction\"\non = {{ group = \"zmax\" }}\nt = [0.0, 0.0, 1.0]\n\
         [load_path]\nfactors = {factors:?}\n"
    );
    saddle::io::scene::Scene::from_toml(&text, std::path::Path::new("uniaxial.toml")).unwrap()
}

/// The path's steps solved with `solver`: per step (σ₃₃, ε_p,33, plastic points) at the first
/// stress point (the field is homogeneous; every point is checked to carry the same).
fn uniaxial_path(scene: saddle::io::scene::Scene, solver_text: &str) -> Vec<(f64, f64, usize)> {
    let factors = scene.load_path.as_ref().unwrap().step_factors();
    let (l, _) = scene.into_problem().unwrap();
    let solver = solver(solver_text);
    let mut path = Evolution::new(&l);
    let mut out = Vec::new();
    for f in factors {
        let step = path.step(f, solver.as_ref(), &mut Silent).unwrap();
        assert!(step.converged(), "{solver_text}: factor {f}: {:?}", step.solution.report.stop_reason);
        let sol = &step.solution;
        let mut ws = Workspace::new(&step.problem.lagrangian());
        step.problem.lagrangian().strain(&sol.u, &mut ws.eps);
        let ep: Vec<Sym> = ws
            .eps
            .iter()
            .zip(&sol.stress.sigma)
            .map(|(e, s)| e - l.lagrangian().data.elasticity.compliance(s))
            .collect();
        for (s, p) in sol.stress.sigma.iter().zip(&ep) {
            assert!((s - sol.stress.sigma[0]).norm() <= 1e-9 && (p - ep[0]).norm() <= 1e-9, "homogeneous");
        }
        out.push((sol.stress.sigma[0][2], ep[0][2], sol.stress.n_plastic()));
    }
    out
}

/// With linear kinematic (and isotropic) hardening, after tension to σ_max reverse yielding
/// starts at |σ_rev| = √(3/2)(k₀ + (h − c)λ), λ = (√(2/3)σ_max − k₀)/(h + c): for pure
/// kinematic hardening σ_rev = σ_max − 2σ_y (the Bauschinger effect, theory §9.3, §11.4). Just
/// above σ_rev the step is elastic and ε_p unchanged; just below, the plastic strain grows
/// back by Δλ·ε-direction with Δλ = √(2/3)(|σ| − |σ_rev|)/(h + c).
#[test]
fn kinematic_hardening_reverse_yields_at_the_bauschinger_stress() {
    let k0 = 1.0f64;
    let sy = (1.5f64).sqrt() * k0;
    for (h, c) in [(0.0, 20.0), (5.0, 20.0)] {
        let smax = 1.5 * sy;
        let lam = ((2.0f64 / 3.0).sqrt() * smax - k0) / (h + c);
        let s_rev = -(1.5f64).sqrt() * (k0 + (h - c) * lam);
        // σ_rev = σ_max − 2σ_y for pure kinematic hardening
        if h == 0.0 {
            assert!((s_rev - (smax - 2.0 * sy)).abs() < 1e-14);
        }
        let before = s_rev * 0.99 + 0.01 * smax; // 1 % of the range short of σ_rev
        let beyond = s_rev - 0.05 * sy;
        let factors = [0.0, smax, before, beyond];
        let yield_table = format!("type = \"von_mises_kinematic\"\nk0 = {k0:?}\nh = {h:?}\nc = {c:?}");
        for text in SOLVERS {
            let steps = uniaxial_path(uniaxial(&yield_table, &factors), text);
            // ε_p,33 = λ·2/√6 after tension (n = diag(−1, −1, 2)/√6)
            let n33 = 2.0 / 6.0f64.sqrt();
            let (s1, p1, pl1) = steps[1];
            assert!((s1 - smax).abs() <= 1e-9 * smax && pl1 > 0, "{text}: σ = {s1}");
            assert!((p1 - lam * n33).abs() <= 1e-8 * lam * n33, "{text}: ε_p,33 = {p1}, closed form {}", lam * n33);
            let (s2, p2, pl2) = steps[2];
            assert!((s2 - before).abs() <= 1e-9 * smax, "{text}");
            assert_eq!(pl2, 0, "{text}, h = {h}, c = {c}: σ = {before:.4} is above σ_rev = {s_rev:.4}: elastic");
            assert!((p2 - p1).abs() <= 1e-9 * p1, "{text}: ε_p unchanged in the elastic step");
            let (_, p3, pl3) = steps[3];
            assert!(pl3 > 0, "{text}: σ = {beyond:.4} is beyond σ_rev = {s_rev:.4}: reverse yielding");
            let dlam = (2.0f64 / 3.0).sqrt() * (beyond.abs() - s_rev.abs()) / (h + c);
            let p3_exact = (lam - dlam) * n33;
            assert!(
                (p3 - p3_exact).abs() <= 1e-8 * p1,
                "{text}, h = {h}, c = {c}: ε_p,33 = {p3:.12e}, closed form {p3_exact:.12e}"
            );
            println!(
                "{}, h = {h}, c = {c}: σ_rev = {s_rev:.6}; ε_p,33 after tension {p1:.12e} (closed form {:.12e}), \
                 after reverse yielding {p3:.12e} (closed form {p3_exact:.12e})",
                text.lines().next().unwrap_or(""),
                lam * n33
            );
        }
    }
}

/// With isotropic hardening alone the yield surface grows to √(2/3)σ_max: reverse yielding
/// starts at σ_rev = −σ_max (theory §11.4), no Bauschinger effect.
#[test]
fn isotropic_hardening_reverse_yields_at_minus_the_maximum_stress() {
    let (k0, h) = (1.0f64, 5.0);
    let sy = (1.5f64).sqrt() * k0;
    let smax = 1.5 * sy;
    let lam = ((2.0f64 / 3.0).sqrt() * smax - k0) / h;
    let factors = [0.0, smax, -0.99 * smax, -1.05 * smax];
    let yield_table = format!("type = \"von_mises\"\nk0 = {k0:?}\nh = {h:?}");
    let n33 = 2.0 / 6.0f64.sqrt();
    for text in SOLVERS {
        let steps = uniaxial_path(uniaxial(&yield_table, &factors), text);
        let (_, p1, _) = steps[1];
        assert!((p1 - lam * n33).abs() <= 1e-8 * lam * n33, "{text}: ε_p,33 = {p1}");
        assert_eq!(steps[2].2, 0, "{text}: −0.99 σ_max is inside the grown yield surface");
        assert!((steps[2].1 - p1).abs() <= 1e-9 * p1, "{text}");
        assert!(steps[3].2 > 0, "{text}: −1.05 σ_max yields");
        // reverse flow along −n by Δλ = √(2/3)(1.05 − 1) σ_max / h
        let dlam = (2.0f64 / 3.0).sqrt() * 0.05 * smax / h;
        assert!((steps[3].1 - (lam - dlam) * n33).abs() <= 1e-8 * p1, "{text}: ε_p,33 = {}", steps[3].1);
    }
}

/// The small default scene (8 × 8 × 4 cells) with another yield table or obstacle table.
fn punch_scene(yield_table: Option<&str>, obstacle_tables: &str) -> DiscreteProblem {
    let mut t = small_johnson();
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    t.remove("yield");
    t.remove("obstacle");
    t.remove("solver");
    let mut text = toml::to_string(&t).unwrap();
    if let Some(y) = yield_table {
        text.push_str(&format!("\n[yield]\n{y}\n"));
    }
    text.push_str(obstacle_tables);
    let scene = saddle::io::scene::Scene::from_toml(&text, std::path::Path::new("t.toml")).unwrap();
    scene.into_problem().unwrap().0
}

/// The Cholesky factor of `l`'s elastic stiffness K.
fn elastic_solver(l: &DiscreteProblem) -> SparseCholesky {
    let c = l.lagrangian().data.elasticity.stiffness_matrix();
    let p = l.element.pattern();
    let mut chol = SparseCholesky::analyse(LowerCsc::new(p.n(), p.col_ptr(), p.row_idx()), "K").unwrap();
    chol.factorise(&l.element.stiffness(Material::Uniform(&c))).unwrap();
    chol
}

const ZONE: &str = "zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }";

/// Every yield surface runs a load path (theory §11) with every solver that takes it: load,
/// hold (a step at the same load changes nothing: the state is carried exactly), unload. An
/// elastic body returns to u = 0; a plastic one keeps an imprint between 0 and the loaded one,
/// which is the loaded state sprung back by the elastic stiffness: u − K⁻¹Gᵀλ.
#[test]
fn every_yield_surface_loads_holds_and_unloads() {
    let surfaces = [
        ("elastic", "type = \"elastic\""),
        ("von_mises", "type = \"von_mises\"\nk0 = 1.0\nh = 5.0"),
        ("von_mises_kinematic", "type = \"von_mises_kinematic\"\nk0 = 1.0\nh = 1.0\nc = 4.0"),
        ("tresca", "type = \"tresca\"\nsigma0 = 1.2\nh = 5.0"),
        ("drucker_prager", "type = \"drucker_prager\"\nk0 = 1.0\nalpha = 0.1\nh = 5.0"),
    ];
    let punch =
        format!("\n[obstacle]\ntype = \"rigid_punch\"\nF = 0.3\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n");
    for (name, table) in surfaces {
        let l = punch_scene(Some(table), &punch);
        let mut springback = elastic_solver(&l);
        for text in ["type = \"newton\"", "type = \"uzawa\"\ntol = 1e-10"] {
            let solver = solver(text);
            let mut path = Evolution::new(&l);
            let mut imprint = Vec::new();
            let mut loaded_u = Vec::new();
            let mut predicted = f64::NAN;
            for (k, f) in [1.0, 1.0, 0.0].into_iter().enumerate() {
                let step = path.step(f, solver.as_ref(), &mut Silent).unwrap();
                let r = &step.solution.report;
                assert!(r.converged, "{name}, {}, step {k}: {:?}", solver.name(), r.stop_reason);
                let sol = &step.solution;
                // the imprint: the largest u₃ of the punch's candidate nodes (its rows' G u)
                let rows = step.problem.lagrangian().data.rows;
                let m = (0..rows.n_rows()).map(|i| rows.row_times(i, &sol.u)).fold(f64::MIN, f64::max);
                imprint.push(m);
                if k == 1 {
                    // holding the load: the step from the loaded state is the loaded state
                    let d = sol.u.iter().zip(&loaded_u).map(|(a, b): (&f64, &f64)| (a - b).abs()).fold(0.0, f64::max);
                    let scale = loaded_u.iter().fold(0.0f64, |m, x: &f64| m.max(x.abs()));
                    assert!(
                        d <= 1e-7 * scale,
                        "{name}, {}: holding the load moved u by {d:.2e} of {scale:.2e}",
                        solver.name()
                    );
                }
                if k == 1 {
                    // unloading elastically: u − K⁻¹Gᵀλ (the stress σ + Cε(Δu) must balance
                    // nothing once the contact forces are gone)
                    let mut x = vec![0.0; l.element.n_dofs()];
                    rows.add_transpose(&sol.lambda, &mut x, &mut vec![0.0; rows.n_extras]);
                    springback.solve(&mut x);
                    let u_res: Vec<f64> = sol.u.iter().zip(&x).map(|(u, d)| u - d).collect();
                    predicted = (0..rows.n_rows()).map(|i| rows.row_times(i, &u_res)).fold(f64::MIN, f64::max);
                }
                if k == 2 {
                    assert_eq!(sol.stress.n_plastic(), 0, "{name}, {}: the unloading is elastic", solver.name());
                }
                loaded_u.clone_from(&sol.u);
            }
            let (max, residual) = (imprint[0], imprint[2]);
            println!(
                "{name} / {}: imprint loaded {max:.4e}, residual {residual:.4e}, elastic unloading predicts \
                 {predicted:.4e}: {:.1e}",
                solver.name(),
                (residual - predicted).abs() / max
            );
            // The residual imprint is the loaded state sprung back elastically (no point yields
            // while unloading, asserted above): each solver's u and λ are within about its KKT
            // tolerance (1e-10) of the discrete solution, so the two agree to a few 1e-10 of the
            // loaded imprint; tolerance 1e-9. Measured: at most 3.0e-11 (uzawa), 1.1e-12 (newton);
            // the residual imprints are 0 (elastic), 6.0 % (von Mises, kinematic), 7.7 % (Tresca)
            // and 0.32 % (Drucker–Prager) of the loaded ones.
            assert!(
                (residual - predicted).abs() <= 1e-9 * max,
                "{name}, {}: residual imprint {residual:e}, elastic unloading predicts {predicted:e}",
                solver.name()
            );
            if name == "elastic" {
                assert!(residual.abs() <= 1e-8 * max, "{name}: an elastic body springs back, imprint {residual:e}");
            } else {
                assert!(residual > 0.0 && residual < max, "{name}: residual imprint {residual:e} of {max:e}");
            }
        }
    }
}

/// Every obstacle plugin runs a load path: loaded, then unloaded to factor 0. A force-controlled
/// obstacle is then unloaded (its extras undetermined, reported, and the step solved); a
/// displacement-controlled one returns to its start. Both leave a residual imprint.
#[test]
fn every_obstacle_plugin_loads_and_unloads() {
    let sphere = |load: &str| {
        format!(
            "\n[obstacle]\ntype = \"rigid_sphere\"\ncenter = [0.0, 0.0, -5.0]\nR = 5.0\ndirection = [0.0, 0.0, 1.0]\n{load}\n{ZONE}\n"
        )
    };
    let punch = |kind: &str, load: &str| {
        format!("\n[obstacle]\ntype = \"{kind}\"\n{load}\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n")
    };
    let two = "\n[[obstacle]]\nname = \"left\"\ntype = \"rigid_punch\"\nF = 0.1\n\
               zone = { all = [ { group = \"zmin\" }, { disc = { center = [-0.35, 0.0], radius = 0.3 } } ] }\n\
               gap = { type = \"paraboloid\", R = 5.0, center = [-0.35, 0.0] }\n\
               [[obstacle]]\nname = \"right\"\ntype = \"rigid_punch_displacement\"\nU = 0.004\n\
               zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.35, 0.0], radius = 0.3 } } ] }\n\
               gap = { type = \"paraboloid\", R = 5.0, center = [0.35, 0.0] }\n";
    let cases = [
        ("rigid_punch", punch("rigid_punch", "F = 0.3"), vec!["U"]),
        ("rigid_punch_displacement", punch("rigid_punch_displacement", "U = 0.008"), vec![]),
        ("tilting_punch", punch("tilting_punch", "F = 0.3\nat = [0.05, 0.0]"), vec!["U", "slope_x1", "slope_x2"]),
        ("rigid_sphere F", sphere("F = 0.3"), vec!["V"]),
        ("rigid_sphere V", sphere("V = 0.008"), vec![]),
        ("two obstacles", two.to_string(), vec!["left.U"]),
    ];
    let newton = solver("type = \"newton\"");
    for (name, table, undetermined) in cases {
        let l = punch_scene(Some("type = \"von_mises\"\nk0 = 1.0\nh = 5.0"), &table);
        let mut path = Evolution::new(&l);
        let loaded = path.step(1.0, newton.as_ref(), &mut Silent).unwrap();
        assert!(loaded.converged() && loaded.solution.undetermined.is_empty(), "{name}: loaded");
        let force: f64 = loaded.solution.lambda.iter().sum();
        assert!(force > 0.05, "{name}: contact force {force}");
        let unloaded = path.step(0.0, newton.as_ref(), &mut Silent).unwrap();
        assert!(unloaded.converged(), "{name}: unloaded {:?}", unloaded.solution.report.stop_reason);
        let names: Vec<String> =
            unloaded.solution.undetermined.iter().map(|&k| l.view().extra_names()[k].clone()).collect();
        assert_eq!(names, undetermined, "{name}: undetermined extras");
        assert_eq!(unloaded.warnings.len(), usize::from(!undetermined.is_empty()), "{name}: {:?}", unloaded.warnings);
        // the unloaded body carries no contact force (a prescribed punch back at U = 0 is
        // clear of the imprint) and keeps a plastic imprint
        let residual_force: f64 = unloaded.solution.lambda.iter().sum();
        assert!(residual_force.abs() <= 1e-9 * force, "{name}: residual contact force {residual_force:e}");
        let max_u3 = l.element.nodal_vectors(&unloaded.solution.u).iter().map(|d| d[2]).fold(f64::MIN, f64::max);
        assert!(max_u3 > 0.0, "{name}: no residual imprint");
    }
}

/// The indentation example on a small mesh, end to end: one VTU per step in a ParaView series,
/// the table, `steps` in summary.json whose top level is the last step, U null (undetermined)
/// at F = 0 with a warning, and the residual state after unloading.
#[test]
fn saddle_run_writes_a_load_path() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    set(&mut t, "load_path.substeps", toml::Value::Integer(2));
    let (code, stderr, dir) = run_scene_kept(&toml::to_string(&t).unwrap());
    assert_eq!(code, 0, "{stderr}");
    let out = dir.path().join("out");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = s["steps"].as_array().unwrap();
    let factors = [0.0, 0.5, 1.0, 0.5, 0.0];
    assert_eq!(steps.len(), factors.len());
    for (k, (st, f)) in steps.iter().zip(factors).enumerate() {
        assert_eq!(st["factor"].as_f64(), Some(f));
        assert_eq!(st["converged"].as_bool(), Some(true));
        let file = format!("solution_{k:04}.vtu");
        assert_eq!(st["file"].as_str(), Some(file.as_str()));
        assert!(out.join(&file).exists(), "{file}");
        // U is undetermined exactly where the force is zero; the force is 0.3·factor
        assert_eq!(st["U"].is_null(), f == 0.0, "step {k}: U = {}", st["U"]);
        assert_eq!(st["extras"]["U"].is_null(), f == 0.0);
        assert!((st["force"].as_f64().unwrap() - 0.3 * f).abs() <= 1e-9, "step {k}");
    }
    // the top level is the last step (unloaded), plus the path
    assert!(s["U"].is_null() && s["extras"]["U"].is_null());
    assert!(s["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("undetermined")));
    let p = &s["load_path"];
    assert_eq!(p["completed"].as_bool(), Some(true));
    assert_eq!(
        p["total_iterations"].as_u64().unwrap(),
        steps.iter().map(|s| s["iterations"].as_u64().unwrap()).sum::<u64>()
    );
    // the residual imprint: positive, below the loaded one; residual stresses self-equilibrated
    // but not zero; the plastic strain of the loaded step kept
    let residual = p["residual"]["imprint"]["imprint"].as_f64().unwrap();
    let loaded = steps[2]["contact"]["imprint"].as_f64().unwrap();
    assert!(residual > 0.02 * loaded && residual < 0.5 * loaded, "imprint {residual} of {loaded}");
    assert!(p["residual"]["max_von_mises"].as_f64().unwrap() > 0.0);
    let ep = p["residual"]["max_equivalent_plastic_strain"].as_f64().unwrap();
    assert!(
        (ep - steps[2]["max_equivalent_plastic_strain"].as_f64().unwrap()).abs() <= 1e-9 * ep,
        "no plastic flow on unloading"
    );
    // the ParaView series lists the steps in order; the table has a row per step
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    let files: Vec<&str> =
        pvd.lines().filter_map(|l| l.split("file=\"").nth(1)).map(|f| f.trim_end_matches("\"/>")).collect();
    assert_eq!(files, (0..5).map(|k| format!("solution_{k:04}.vtu")).collect::<Vec<_>>());
    let rows = csv_rows(&std::fs::read_to_string(out.join("load_path.csv")).unwrap());
    assert_eq!(rows.len(), 5);
    assert_eq!(rows[4]["U"], "", "undetermined U is left empty");
    assert!((csv_num(&rows[2], "imprint") - loaded).abs() <= 1e-9 * loaded);
    assert!(out.join("solution.vtu").exists());
    #[cfg(feature = "report")]
    assert!(out.join("load_path.png").exists() && out.join("load_path.svg").exists());
}

/// A single obstacle with a name (extras `punch.U`): its undetermined U at zero load is null
/// under every key that shows it — `extras`, the top-level `U`, `contact` (plain names with one
/// obstacle) and its `obstacles` entry.
#[test]
fn a_named_obstacles_undetermined_extra_is_null_everywhere() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([4, 4, 2]).unwrap());
    set(&mut t, "obstacle.name", toml::Value::String("punch".into()));
    set(&mut t, "load_path.substeps", toml::Value::Integer(1));
    let (code, stderr, dir) = run_scene_kept(&toml::to_string(&t).unwrap());
    assert_eq!(code, 0, "{stderr}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
    let loaded = &s["steps"][1];
    assert!(loaded["extras"]["punch.U"].as_f64().unwrap() > 0.0 && loaded["U"].as_f64().unwrap() > 0.0);
    for v in [&s["extras"]["punch.U"], &s["U"], &s["contact"]["U"], &s["obstacles"][0]["U"]] {
        assert!(v.is_null(), "an undetermined U shows as {v}");
    }
    assert!(s["contact"]["imprint"].as_f64().is_some(), "the imprint stays determined");
}

/// A step that does not converge stops the path: the steps before it stay written, the failed
/// one is marked in summary.json and load_path.csv, no later step is solved, exit status 2.
#[test]
fn a_failed_step_stops_the_path_and_keeps_the_earlier_steps() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    set(&mut t, "load_path.substeps", toml::Value::Integer(2));
    // two Newton iterations solve the first plastic step's start but not the step; without
    // step cutting (theory §11.5) the path stops there
    set(&mut t, "solver.max_iter", toml::Value::Integer(2));
    set(&mut t, "load_path.max_cuts", toml::Value::Integer(0));
    let (code, stderr, dir) = run_scene_kept(&toml::to_string(&t).unwrap());
    assert_eq!(code, 2, "{stderr}");
    let out = dir.path().join("out");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = s["steps"].as_array().unwrap();
    let failed = s["load_path"]["failed_step"].as_u64().expect("a failed step") as usize;
    assert_eq!(steps.len(), failed + 1, "no step after the failed one");
    assert_eq!(s["load_path"]["completed"].as_bool(), Some(false));
    assert_eq!(s["converged"].as_bool(), Some(false));
    assert_eq!(steps[failed]["converged"].as_bool(), Some(false));
    assert_eq!(steps[failed]["stop_reason"].as_str(), Some("max_iterations"));
    for st in &steps[..failed] {
        assert_eq!(st["converged"].as_bool(), Some(true));
        assert!(out.join(st["file"].as_str().unwrap()).exists());
    }
    assert!(!out.join(format!("solution_{:04}.vtu", failed + 1)).exists());
    let rows = csv_rows(&std::fs::read_to_string(out.join("load_path.csv")).unwrap());
    assert_eq!(rows.len(), failed + 1);
    assert_eq!(rows[failed]["converged"], "false");
    assert!(s["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("stopped at step")));
}

/// `[load_path]` errors name the field: no factors, a non-finite one, zero sub-steps, and a
/// negative factor that a punch's force cannot take.
#[test]
fn bad_load_paths_are_rejected_naming_the_field() {
    let base = toml::to_string(&small_johnson()).unwrap();
    assert_rejected(&format!("{base}\n[load_path]\nfactors = []\n"), &["load_path.factors", "at least one"]);
    assert_rejected(&format!("{base}\n[load_path]\nfactors = [0.0, 1.0]\nsubsteps = 0\n"), &["load_path.substeps = 0"]);
    assert_rejected(
        &format!("{base}\n[load_path]\nfactors = [0.0, -1.0]\n"),
        &["load_path.factors[1] = -1", "obstacle.F"],
    );
    assert_rejected(&format!("{base}\n[load_path]\nfactors = [0.0, 1.0]\nsteps = 3\n"), &["steps"]);
}

/// The indentation (theory §11.4) on a small mesh. Unloading is elastic here (the residual
/// stresses stay inside the grown yield surface) and frictionless contact is reversible, so the
/// residual state does not depend on how many steps the unloading takes: one unloading step and
/// four give the same residual displacement to the solver's tolerance. Loading in one step
/// (Hencky) and in n steps differ, because the contact zone grows and the stress paths under it
/// are not radial: the n-step answers converge at first order in 1/n to a Prandtl–Reuss limit
/// that Hencky misses by more than the limit's uncertainty.
#[test]
fn indentation_unloads_elastically_and_hencky_differs_from_prandtl_reuss() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    let (l, s) = build(&t);
    let newton = s.unwrap();
    let run = |factors: &[f64]| {
        let mut path = Evolution::new(&l);
        let mut out = Vec::new();
        for &f in factors {
            let step = path.step(f, newton.as_ref(), &mut Silent).unwrap();
            assert!(step.converged(), "factor {f}");
            out.push(step.solution);
        }
        out
    };
    let load4 = [0.25, 0.5, 0.75, 1.0];
    let one = run(&[load4.as_slice(), &[0.0]].concat());
    let four = run(&[load4.as_slice(), &[0.75, 0.5, 0.25, 0.0]].concat());
    let (a, b) = (&one.last().unwrap().u, &four.last().unwrap().u);
    let scale = four[3].u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let d = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    println!("residual u, one unloading step against four: {d:.2e} of {scale:.2e}");
    assert!(d <= 1e-8 * scale, "unloading is elastic and reversible: {d:e}");
    for s in &four[4..] {
        assert_eq!(s.stress.n_plastic(), 0, "no reverse plasticity while unloading");
    }
    // Hencky (one loading step) against Prandtl–Reuss: n equal loading steps of backward Euler
    // converge at first order to the Prandtl–Reuss limit U_∞ (theory §11.1)
    let u_at_f = |n: usize| {
        let f: Vec<f64> = (1..=n).map(|k| k as f64 / n as f64).collect();
        run(&f)[n - 1].extras[0]
    };
    let [hencky, u8, u16, u32, u64] = [1, 8, 16, 32, 64].map(u_at_f);
    let order = ((u16 - u32) / (u32 - u64)).log2();
    let limit = u64 - (u32 - u64) / (2f64.powf(order) - 1.0);
    // the limit's uncertainty: how much it moves between the observed order and the exact 1
    let uncertainty = (limit - (2.0 * u64 - u32)).abs();
    let (rel, rel8) = ((hencky - limit) / limit, (hencky - u8) / u8);
    println!(
        "U at F: Hencky {hencky:.9e}; Prandtl–Reuss 8, 16, 32, 64 steps {u8:.9e}, {u16:.9e}, {u32:.9e}, {u64:.9e}: \
         order {order:.2}, limit {limit:.9e} ± {uncertainty:.1e}; Hencky above the limit by {:.3} %, above 8 steps \
         by {:.3} %",
        100.0 * rel,
        100.0 * rel8
    );
    // Measured: order 0.91, limit 6.772600e-3 ± 2.2e-8, Hencky 0.044 % above it (2.98e-6), and
    // 0.027 % above 8 steps. Asserted: the order of backward Euler, 1 ± 0.2; Hencky above the
    // limit by more than 20 times its uncertainty (measured 135 times), so the difference is the
    // path's and not the step size's; and 8 steps between the two (the steps converge
    // monotonically, each halving of the step lowers U).
    assert!((order - 1.0).abs() <= 0.2, "observed order {order} of backward Euler in the load steps");
    assert!(hencky - limit > 20.0 * uncertainty, "Hencky {hencky:e}, Prandtl–Reuss {limit:e} ± {uncertainty:e}");
    assert!(limit + uncertainty < u8 && u8 < hencky, "8 steps {u8:e} between {limit:e} and Hencky {hencky:e}");
}

/// Newton's warm solves along a path reuse the linear set-up of the previous step (the
/// multigrid hierarchy or the symbolic analysis) when pattern, elastic stiffness and rows are
/// unchanged, and rebuild it when the rows change (the unloaded steps drop the punch's rows):
/// the answers are those of fresh solvers, and the counters say which steps reused it.
#[test]
fn newton_reuses_its_set_up_along_a_path_with_the_same_answers() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    let (l, _) = build(&t);
    let factors = step_factors(&[0.0, 1.0, 0.0], 3);
    for linear in ["direct", "amg"] {
        let text = format!("type = \"newton\"\nlinear = \"{linear}\"\ntol = 1e-11");
        let kept = solver(&text);
        let (mut a, mut b) = (Evolution::new(&l), Evolution::new(&l));
        for (k, &f) in factors.iter().enumerate() {
            let x = a.step(f, kept.as_ref(), &mut Silent).unwrap();
            // a solver of its own for every step: nothing kept
            let y = b.step(f, solver(&text).as_ref(), &mut Silent).unwrap();
            assert!(x.converged() && y.converged(), "{linear}, step {k}");
            let reused = x.solution.report.counters.get("setup_reused").copied().unwrap_or(0.0);
            // steps 2..5 follow a step with the same rows; 0 is cold, 1 follows the unloaded
            // step 0 (no rows), 6 is unloaded again
            let expect = (2..factors.len() - 1).contains(&k);
            assert_eq!(reused == 1.0, expect, "{linear}, step {k}: setup_reused = {reused}");
            assert_eq!(y.solution.report.counters.get("setup_reused").copied().unwrap_or(0.0), 0.0);
            if expect {
                assert_eq!(x.solution.report.counters["symbolic_analyses"], 0.0, "{linear}: no analysis when reused");
            }
            let scale = y.solution.u.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
            let d = x.solution.u.iter().zip(&y.solution.u).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
            assert!(d <= 1e-9 * scale, "{linear}, step {k}: kept and fresh set-ups differ by {d:e} of {scale:e}");
        }
    }
}

/// A solver that fails on the first step (SOCP cannot take Tresca, which has no cone
/// description) leaves nothing to summarise: exit 1 with the step and the solver's reason, and
/// nothing written.
#[test]
fn a_solver_error_on_the_first_step_is_an_error_naming_the_step() {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([4, 4, 2]).unwrap());
    let mut y = toml::Table::new();
    y.insert("type".into(), "tresca".into());
    y.insert("sigma0".into(), 1.2.into());
    y.insert("h".into(), 5.0.into());
    t.insert("yield".into(), toml::Value::Table(y));
    let mut s = toml::Table::new();
    s.insert("type".into(), "socp".into());
    t.insert("solver".into(), toml::Value::Table(s));
    let (code, stderr, dir) = run_scene_kept(&toml::to_string(&t).unwrap());
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("step 0") && stderr.contains("tresca"), "{stderr}");
    assert!(!dir.path().join("out").exists(), "nothing written, no empty folder");
}
