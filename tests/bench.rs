//! `saddle bench` on a small size: writes its table, CSV and plot; every run converges; the
//! baselines and ratios are finite; the AMG and direct backends of Newton, which the bench
//! times side by side, give the same answer on the problem it measured.

use saddle::core::{Silent, contact_set};
use saddle::studies::bench::{cells_for, solver_spec};
use saddle::studies::report::SceneSource;
use saddle::studies::report::runs::errors;
use std::process::Command;

#[test]
fn bench_writes_table_csv_and_plot_with_finite_ratios() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/johnson.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["bench", scene, "--out", out.to_str().unwrap(), "--sizes", "3000"])
        .args(["--solvers", "newton-amg,newton-direct,uzawa"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    // two baselines, then the elastic scene and the scene for each of the three solvers
    assert_eq!(rows.len(), 2 + 2 * 3, "{csv}");
    for r in &rows {
        assert_eq!(r[col("converged")], "true", "{r:?}");
        let t: f64 = r[col("total_s")].parse().unwrap();
        let ratio: f64 = r[col("ratio_to_amg_cg")].parse().unwrap();
        assert!(t > 0.0 && t.is_finite() && ratio.is_finite() && ratio > 0.0, "{r:?}");
        if r[col("variant")] == "scene" {
            let kkt: f64 = r[col("kkt")].parse().unwrap();
            assert!(kkt <= 1e-8, "{r:?}");
            let peak: f64 = r[col("peak_mib")].parse().unwrap();
            assert!(peak > 0.0, "{r:?}");
        }
    }
    // the two Newton backends on the problem the bench measured (its size and scene): the same
    // answer to their KKT tolerance
    let source = SceneSource::read(scene.as_ref()).unwrap();
    let base_dofs = source.problem(None).unwrap().element.n_dofs();
    let l = source.problem(Some(cells_for(source.box_cells().unwrap(), base_dofs, 3000))).unwrap();
    assert!(rows.iter().all(|r| r[col("dofs")] == l.element.n_dofs().to_string()), "the bench's size: {csv}");
    let solve = |name: &str| {
        let sol = solver_spec(name).unwrap().0.solve(&l.lagrangian(), &mut Silent).unwrap();
        assert!(sol.report.converged, "{name}: {:?}", sol.report.stop_reason);
        sol
    };
    let (amg, direct) = (solve("newton-amg"), solve("newton-direct"));
    let e = errors(&l.lagrangian(), &amg, &direct);
    let force = |s: &saddle::core::Solution| s.lambda.iter().sum::<f64>();
    let force_rel = (force(&amg) - force(&direct)).abs() / force(&direct);
    println!(
        "{} dofs, newton-amg against newton-direct: U {:.1e}, σ̂ {:.1e}, ε(u) {:.1e}, force {force_rel:.1e}, \
         contact {} / {}, plastic {} / {}, KKT {:.1e} / {:.1e}",
        l.element.n_dofs(),
        e.u_rel,
        e.stress_rel,
        e.strain_rel,
        contact_set(&amg.lambda).len(),
        contact_set(&direct.lambda).len(),
        amg.stress.n_plastic(),
        direct.stress.n_plastic(),
        amg.report.kkt.max(),
        direct.report.kkt.max()
    );
    // Each answer is within about its KKT residual of the discrete solution: on the default
    // scene's work–precision ladder (docs/report/report.md) every solver's σ̂, U and ε(u)
    // errors are at most 1.22 × its KKT residual. So the two differ by at most
    // 1.22 (KKT_amg + KKT_direct), taken as 2 (KKT_amg + KKT_direct): 6e-15 here, both backends
    // ending below 2e-15 (their tolerance is 1e-10, Newton's last step overshoots it).
    // Measured: 6.2e-16 in σ̂, 5.9e-16 in ε(u), 1.1e-16 in U, force equal; the same 22 contact
    // nodes and 196 plastic elements.
    let bound = 2.0 * (amg.report.kkt.max() + direct.report.kkt.max());
    for (what, d) in [("U", e.u_rel), ("σ̂", e.stress_rel), ("ε(u)", e.strain_rel), ("force", force_rel)] {
        assert!(d <= bound, "newton-amg and newton-direct differ in {what} by {d:e} > {bound:e}");
    }
    assert_eq!(e.contact_mismatch, 0, "the same contact set");
    assert_eq!(amg.stress.n_plastic(), direct.stress.n_plastic(), "the same plastic elements");
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("| DOFs |") && md.contains("newton-amg:") && md.contains("elastic scene, uzawa"), "{md}");
    if cfg!(feature = "report") {
        assert!(std::fs::metadata(out.join("bench.png")).unwrap().len() > 10_000);
        assert!(std::fs::metadata(out.join("bench.svg")).unwrap().len() > 1_000);
    }
}

/// A size of zero DOFs is refused naming the flag and the value, before any scene is read.
#[test]
fn a_zero_size_is_refused_naming_the_flag() {
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["bench", "examples/johnson.toml", "--sizes", "10000,0"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(stderr.contains("'0'") && stderr.contains("--sizes"), "{stderr}");
}
