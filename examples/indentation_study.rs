//! The indentation of `examples/indentation.toml` (the default scene loaded to F = 0.3 and
//! unloaded, theory §11) solved with 1, 2, 4, …, 64 equal steps each way: how the loaded
//! displacement, the residual imprint and the residual stresses converge as the steps shrink,
//! and how far the one-step (Hencky) answer is from the many-step (Prandtl–Reuss) one. Prints
//! the table of docs/load_paths.md.
//!
//! ```text
//! cargo run --release --example indentation_study              # the scene's 32×32×16 cells
//! cargo run --release --example indentation_study -- 16 16 8   # other cell counts
//! ```

use saddle::core::{Evolution, Silent, step_factors};
use saddle::io::scene::Scene;
use saddle::io::summary::Summary;
use std::path::Path;
use std::time::Instant;

/// Steps each way (loading, then unloading); the two finest give the limit (Richardson).
const STEPS: [usize; 7] = [1, 2, 4, 8, 16, 32, 64];

/// What one path gives.
struct Run {
    steps: usize,
    u_loaded: f64,
    imprint_loaded: f64,
    imprint_residual: f64,
    residual_von_mises: f64,
    max_plastic_strain: f64,
    iterations: usize,
    wall_s: f64,
}

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("cell counts")).collect();
    let mut scene = Scene::from_file(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/indentation.toml")))
        .expect("examples/indentation.toml");
    if let [a, b, c] = args[..] {
        scene = scene.with_cells([a, b, c]).expect("cells");
    }
    let (l, solver) = scene.into_problem().expect("the scene assembles");
    let solver = solver.expect("the scene names newton");
    println!("{} dofs, {} elements, solver {}", l.element.n_dofs(), l.element.mesh().n_elements(), solver.name());
    let mut runs = Vec::new();
    for n in STEPS {
        let started = Instant::now();
        let mut path = Evolution::new(&l);
        let factors = step_factors(&[0.0, 1.0, 0.0], n);
        let (mut u_loaded, mut imprint_loaded, mut iterations) = (f64::NAN, f64::NAN, 0);
        let mut last = None;
        for (k, &f) in factors.iter().enumerate() {
            let step = path.step(f, solver.as_ref(), &mut Silent).expect("the step solves");
            assert!(step.converged(), "{n} steps, step {k}: {:?}", step.solution.report.stop_reason);
            iterations += step.solution.report.iterations;
            let s = Summary::new(step.problem.view(), &step.solution, None);
            if k == n {
                u_loaded = step.solution.extras[0];
                imprint_loaded = s.contact["imprint"];
            }
            last = Some(s);
        }
        let s = last.expect("steps");
        let run = Run {
            steps: factors.len() - 1,
            u_loaded,
            imprint_loaded,
            imprint_residual: s.contact["imprint"],
            residual_von_mises: s.max_von_mises,
            max_plastic_strain: s.max_equivalent_plastic_strain,
            iterations,
            wall_s: started.elapsed().as_secs_f64(),
        };
        println!(
            "{:>2} steps each way: U(F) {:.6e}, imprint {:.6e}, residual imprint {:.6e}, residual σ_vM {:.4}, ε̄_p {:.4e}, {} Newton its, {:.1} s",
            n,
            run.u_loaded,
            run.imprint_loaded,
            run.imprint_residual,
            run.residual_von_mises,
            run.max_plastic_strain,
            run.iterations,
            run.wall_s
        );
        runs.push(run);
    }
    // backward Euler is first order in the step: the limit by Richardson extrapolation of the
    // two finest paths (2·finest − next), checked by the observed order of the last three
    let [.., a, b, c] = &runs[..] else { panic!("at least three paths") };
    let order = |f: fn(&Run) -> f64| ((f(a) - f(b)) / (f(b) - f(c))).abs().log2();
    let limit = |f: fn(&Run) -> f64| 2.0 * f(c) - f(b);
    let (u_inf, r_inf) = (limit(|r| r.u_loaded), limit(|r| r.imprint_residual));
    println!(
        "\nobserved order in the step (last three paths): U {:.2}, residual imprint {:.2}; limits U {u_inf:.6e}, residual imprint {r_inf:.6e}",
        order(|r| r.u_loaded),
        order(|r| r.imprint_residual)
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    println!(
        "\n| steps (load + unload) | U at F | error | residual imprint | error | residual max σ_vM | max ε̄_p | Newton its | wall |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &runs {
        println!(
            "| {} + {} | {:.5e} | {:.1e} | {:.4e} | {:.1e} | {:.4} | {:.4e} | {} | {:.1} s |",
            r.steps / 2,
            r.steps / 2,
            r.u_loaded,
            rel(r.u_loaded, u_inf),
            r.imprint_residual,
            rel(r.imprint_residual, r_inf),
            r.residual_von_mises,
            r.max_plastic_strain,
            r.iterations,
            r.wall_s
        );
    }
    let hencky = &runs[0];
    println!(
        "\nHencky (one loading step) against Prandtl–Reuss (the limit) at F: U {:.5e} vs {u_inf:.5e} ({:+.3} %); \
         residual imprint after Hencky loading {:.5e} vs {r_inf:.5e} ({:+.2} %)",
        hencky.u_loaded,
        100.0 * (hencky.u_loaded - u_inf) / u_inf,
        hencky.imprint_residual,
        100.0 * (hencky.imprint_residual - r_inf) / r_inf
    );
}
