//! `saddle run` end to end: exit status, summary.json keys, solution.vtu.

mod common;
use common::*;
use std::process::Command;

#[test]
fn run_writes_summary_and_vtu() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hom");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", repo("examples/homogeneous.toml").to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("plastic elements") && stdout.contains("KKT residual"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "solver",
        "converged",
        "iterations",
        "wall_s",
        "U",
        "force",
        "contact_nodes",
        "plastic_elements",
        "J",
        "kkt_residual",
        "dofs",
        "elements",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["solver"], "uzawa");
    assert_eq!(summary["converged"], true);
    // F = 2 on the unit square (examples/homogeneous.toml: E = 100, k₀ = 1, h = 5), theory §7.1:
    // U = F/E + (2F − √6 k₀)₊/(3h) = 0.123367…, force = F
    let (f, e, k0, h) = (2.0, 100.0, 1.0, 5.0);
    let u_exact = f / e + (2.0 * f - 6f64.sqrt() * k0).max(0.0) / (3.0 * h);
    let u = summary["U"].as_f64().unwrap();
    let force = summary["force"].as_f64().unwrap();
    let u_err = (u - u_exact).abs() / u_exact;
    println!("U = {u:.15e}, closed form {u_exact:.15e}: relative error {u_err:.2e}");
    // Uzawa stops at a relative KKT residual of 1e-10; a stress error becomes a strain error
    // through the plastic compliance, E/h = 20 times the elastic one, so U is good to about
    // 20 · 1e-10 = 2e-9. Measured: 2.7e-10.
    assert!(u_err <= 2e-9, "U = {u}, closed form {u_exact}: {u_err:e}");
    assert!((force - f).abs() < 1e-9);
    assert!(summary["kkt_residual"].as_f64().unwrap() <= 1e-10);
    assert_eq!(summary["plastic_elements"], summary["elements"]);
    // end-to-end phases: the solver's own clock runs inside `solve`, and they add up
    let e2e = summary["end_to_end"].as_object().expect("end_to_end");
    let phase = |k: &str| e2e.get(k).and_then(|v| v.as_f64()).unwrap_or_else(|| panic!("end_to_end lacks {k}"));
    assert!(phase("solve") >= summary["wall_s"].as_f64().unwrap());
    let sum: f64 = ["read", "setup", "solve", "summary", "estimate", "write"].iter().map(|k| phase(k)).sum();
    assert!((sum - summary["end_to_end_s"].as_f64().unwrap()).abs() <= 1e-9 * sum.max(1.0));
    assert!(stdout.contains("end to end"), "{stdout}");
    let vtu = std::fs::read(out.join("solution.vtu")).unwrap();
    let head = String::from_utf8_lossy(&vtu[..vtu.len().min(3000)]);
    for name in ["displacement", "contact_force", "stress", "von_mises", "xi", "plastic", "NumberOfCells=\"162\""] {
        assert!(head.contains(name), "solution.vtu lacks {name}");
    }
}

#[test]
fn a_run_out_of_iterations_is_flagged_and_exits_non_zero() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = small_johnson();
    set(&mut t, "solver.max_iter", toml::Value::Integer(3));
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, toml::to_string(&t).unwrap()).unwrap();
    let out = dir.path().join("o");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", scene.to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["converged"], false);
    assert_eq!(summary["stop_reason"], "max_iterations");
    assert!(summary["kkt_residual"].as_f64().unwrap() > 1e-8);
}

/// `--cells` is the scene with `mesh.cells` replaced: the same mesh, so the same U to round-off
/// (a different mesh changes U in the third digit); bad counts are refused by name, nothing run.
#[test]
fn cells_on_the_command_line_are_the_scenes_mesh_cells() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = example("johnson.toml");
    set(&mut t, "mesh.grading.ratio", toml::Value::Float(2.0));
    let full = dir.path().join("full.toml");
    std::fs::write(&full, toml::to_string(&t).unwrap()).unwrap();
    set(&mut t, "mesh.cells", toml::Value::try_from([6, 6, 3]).unwrap());
    let edited = dir.path().join("edited.toml");
    std::fs::write(&edited, toml::to_string(&t).unwrap()).unwrap();
    let run = |scene: &std::path::Path, extra: &[&str], out: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
            .args(["run", scene.to_str().unwrap(), "--quiet", "--solver", "newton", "--out"])
            .arg(dir.path().join(out))
            .args(extra)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let u = |out: &str| -> f64 {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join(out).join("summary.json")).unwrap()).unwrap();
        s["U"].as_f64().unwrap()
    };
    assert_eq!(run(&full, &["--cells", "6,6,3"], "a").0, Some(0));
    assert_eq!(run(&edited, &[], "b").0, Some(0));
    assert!((u("a") - u("b")).abs() <= 1e-14 * u("b"), "{} against {}", u("a"), u("b"));
    let (code, err) = run(&full, &["--cells", "6,6"], "c");
    assert_eq!(code, Some(1));
    assert!(err.contains("--cells") && err.contains("6,6"), "{err}");
    let (code, err) = run(&full, &["--cells", "6,0,3"], "d");
    assert_eq!(code, Some(1));
    assert!(err.contains("mesh.cells[1]"), "{err}");
    assert!(!dir.path().join("c").exists() && !dir.path().join("d").exists());
}
