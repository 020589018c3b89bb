//! Issue 12's bench ratio: Newton with a rigid sphere against Newton with the paraboloid punch
//! of the same radius, on the default mesh of `examples/johnson.toml` (the sphere's rows act on
//! three dofs each and are solved in the coordinates of `saddle_solvers::row_basis`). Runs the
//! two alternately, `RUNS` times each, and prints the median wall time (assembly of L and the
//! solve) and the iterations, with their ratios.
//!
//! ```text
//! cargo run --release --example obstacle_bench
//! ```

use saddle::core::{AdmissibleDisplacements, Obstacles, Region, Silent, Solver};
use saddle::io::scene::Scene;
use saddle_contact::RigidSphere;
use std::path::Path;
use std::time::Instant;

const RUNS: usize = 3;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/johnson.toml");
    let punch = Scene::from_file(&path).expect("examples/johnson.toml");
    // the punch's zone, and the paraboloid's sphere: centre R = 5 below the apex, pushed up by F = 0.3
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
    let sphere: Box<dyn AdmissibleDisplacements> =
        Box::new(RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.3, zone));
    let sphere_scene = Scene { obstacle: Obstacles::one(sphere), ..punch.clone() };
    let newton: Box<dyn Solver> = toml::from_str("type = \"newton\"").unwrap();
    let mut times = [Vec::new(), Vec::new()];
    let mut iterations = [0, 0];
    let mut dofs = 0;
    for run in 0..RUNS {
        for (k, scene) in [&punch, &sphere_scene].into_iter().enumerate() {
            let t = Instant::now();
            let (l, _) = scene.clone().into_problem().expect("problem");
            let sol = newton.solve(&l.lagrangian(), &mut Silent).expect("solve");
            times[k].push(t.elapsed().as_secs_f64());
            assert!(sol.report.converged);
            iterations[k] = sol.report.iterations;
            dofs = l.element.n_dofs();
            eprintln!("run {run}: {} {:.2} s, {} iterations", ["punch", "sphere"][k], times[k][run], iterations[k]);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (tp, ts) = (median(&mut times[0]), median(&mut times[1]));
    println!("default mesh ({dofs} free dofs), Newton, median of {RUNS}:");
    println!("| obstacle | iterations | time |");
    println!("|---|---:|---:|");
    println!("| paraboloid punch | {} | {tp:.2} s |", iterations[0]);
    println!("| rigid sphere | {} | {ts:.2} s |", iterations[1]);
    println!(
        "ratio sphere / punch: iterations {:.2}, time {:.2}",
        iterations[1] as f64 / iterations[0] as f64,
        ts / tp
    );
}
