//! Automatic step cutting in load paths (issue 25, theory §11.5): a failed step is halved and
//! retried, every cut reported; with `max_cuts = 0` the path stops as before; a path that cannot
//! go on names the smallest step it tried.

mod common;
use common::*;
use saddle::core::{Evolution, Silent};

/// The indentation example on a small mesh (8 × 8 × 4 cells, two sub-steps each way) with a
/// Newton budget of `max_iter` iterations and `[load_path]` `max_cuts` (absent: the default).
fn indentation(max_iter: i64, max_cuts: Option<i64>) -> toml::Table {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    set(&mut t, "load_path.substeps", toml::Value::Integer(2));
    set(&mut t, "solver.max_iter", toml::Value::Integer(max_iter));
    if let Some(c) = max_cuts {
        set(&mut t, "load_path.max_cuts", toml::Value::Integer(c));
    }
    t
}

/// `summary.json` of `saddle run` on `t`, with the exit code and the output folder.
fn run(t: &toml::Table) -> (i32, serde_json::Value, tempfile::TempDir) {
    let (code, stderr, dir) = run_scene_kept(&toml::to_string(t).unwrap());
    let json = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap_or_else(|_| panic!("{stderr}"));
    (code, serde_json::from_str(&json).unwrap(), dir)
}

/// Five Newton iterations do not solve the first plastic step (F: 0 → 0.15) of the indentation:
/// with `max_cuts = 0` the path stops there as before; by default the step is halved once, the
/// path completes, the cut is reported (summary `load_path.cuts`, the step's `cuts`, the csv
/// column), and the path's answer agrees with Uzawa's on the same steps.
#[test]
fn a_step_too_large_for_newton_is_cut_and_the_path_completes() {
    let (code, s, _) = run(&indentation(5, Some(0)));
    assert_eq!(code, 2, "max_cuts = 0 stops the path");
    assert_eq!(s["load_path"]["failed_step"].as_u64(), Some(1));
    assert!(s["load_path"]["cuts"].as_array().unwrap().is_empty());
    let (code, s, dir) = run(&indentation(5, None));
    assert_eq!(code, 0, "{:?}", s["warnings"]);
    let p = &s["load_path"];
    assert_eq!(p["completed"].as_bool(), Some(true));
    let cuts = p["cuts"].as_array().unwrap();
    assert_eq!(cuts.len(), 1, "{cuts:?}");
    assert_eq!((cuts[0]["factor"].as_f64(), cuts[0]["retry"].as_f64()), (Some(0.5), Some(0.25)));
    assert!(cuts[0]["reason"].as_str().unwrap().contains("MaxIterations"));
    assert_eq!(p["smallest_step"].as_f64(), Some(0.25));
    let steps = s["steps"].as_array().unwrap();
    let factors: Vec<f64> = steps.iter().map(|st| st["factor"].as_f64().unwrap()).collect();
    assert_eq!(factors, [0.0, 0.25, 0.5, 1.0, 0.5, 0.0], "the cut step, then on with half the increment");
    let halvings: Vec<u64> = steps.iter().map(|st| st["cuts"].as_u64().unwrap()).collect();
    assert_eq!(halvings, [0, 1, 1, 0, 0, 0]);
    let rows = csv_rows(&std::fs::read_to_string(dir.path().join("out/load_path.csv")).unwrap());
    assert_eq!(rows.iter().map(|r| csv_num(r, "cuts")).collect::<Vec<_>>(), [0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    // Uzawa on the same steps (Prandtl–Reuss depends on them): the same U under load and the
    // same residual imprint. Both solvers stop at relative KKT residuals ≤ 1e-10; measured
    // deviation at most 1.6e-11 of the peak imprint, tolerance 1e-8.
    let (l, _) = build(&indentation(50, None));
    let uzawa = solver("type = \"uzawa\"\ntol = 1e-10");
    let mut path = Evolution::new(&l);
    for (st, &f) in steps.iter().zip(&factors) {
        let step = path.step(f, uzawa.as_ref(), &mut Silent).unwrap();
        assert!(step.converged(), "uzawa at factor {f}");
        let imprint = |u: &[f64]| {
            let rows = step.problem.lagrangian().data.rows;
            (0..rows.n_rows()).map(|i| rows.row_times(i, u)).fold(f64::MIN, f64::max)
        };
        let (mine, newton) = (imprint(&step.solution.u), st["contact"]["imprint"].as_f64().unwrap());
        let scale = s["steps"][3]["contact"]["imprint"].as_f64().unwrap();
        println!("factor {f}: imprint uzawa {mine:.10e}, newton {newton:.10e}");
        assert!((mine - newton).abs() <= 1e-8 * scale, "factor {f}: imprint uzawa {mine:e}, newton {newton:e}");
    }
}

/// A path that cannot go on (three Newton iterations cannot solve the plastic steps however
/// small, down to `max_cuts` halvings) stops as before, naming the smallest step it tried.
#[test]
fn a_path_that_cannot_go_on_names_the_smallest_step_tried() {
    let (code, s, _) = run(&indentation(3, Some(2)));
    assert_eq!(code, 2);
    let p = &s["load_path"];
    assert_eq!(p["completed"].as_bool(), Some(false));
    let smallest = p["smallest_step"].as_f64().unwrap();
    assert_eq!(smallest, 0.5 / 4.0, "two halvings of the step 0.5");
    let error = p["error"].as_str().unwrap();
    assert!(error.contains("smallest step tried 1.25e-1"), "{error}");
    assert!(s["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("smallest step tried")));
}
