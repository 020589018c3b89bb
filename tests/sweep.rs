//! `saddle sweep`: every load times each factor, each point the stationary problem (from the zero
//! state, its solve started from the secant prediction of the points before). Checked against
//! what the factors must do: an elastic displacement-controlled flat punch responds linearly
//! (force ∝ U, d ln F / d ln U = 1); a force-controlled punch carries exactly F × factor (Σλ = F);
//! a perfectly plastic strip punch bends the curve over (the indicator falls below 1).

mod common;

use common::{CsvRow, csv_num as num, csv_rows, example, set, small_johnson};
use std::process::Command;

/// Runs `saddle sweep` on a scene table; returns (exit code, sweep.csv rows as maps, sweep.md).
fn sweep(t: &toml::Table, factors: &str) -> (i32, Vec<CsvRow>, String) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, toml::to_string(t).unwrap()).unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["sweep", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--factors", factors])
        .output()
        .unwrap();
    let code = o.status.code().unwrap();
    if code == 1 {
        return (code, vec![], String::from_utf8_lossy(&o.stderr).into_owned());
    }
    let rows: Vec<CsvRow> = csv_rows(&std::fs::read_to_string(out.join("sweep.csv")).unwrap());
    // the plot needs two points
    let plotted = out.join("sweep.png").exists() && out.join("sweep.svg").exists();
    assert_eq!(plotted, rows.len() >= 2);
    (code, rows, std::fs::read_to_string(out.join("sweep.md")).unwrap())
}

/// The strip punch of examples/strip_punch.toml on a coarse mesh, with P1 elements.
fn coarse_strip() -> toml::Table {
    let mut t = example("strip_punch.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([16, 2, 8]).unwrap());
    set(&mut t, "discretisation.type", toml::Value::String("p1".into()));
    t
}

#[test]
fn an_elastic_flat_punch_responds_in_proportion() {
    let mut t = coarse_strip();
    t.remove("yield");
    let (code, rows, md) = sweep(&t, "1,2.5,4");
    assert_eq!(code, 0, "{md}");
    let f1 = num(&rows[0], "force");
    for (r, f) in rows.iter().zip([1.0, 2.5, 4.0]) {
        assert_eq!(r["converged"], "true");
        assert!((num(r, "U") - 0.01 * f).abs() <= 1e-15, "U = {}", r["U"]);
        assert!((num(r, "force") - f * f1).abs() <= 1e-9 * f * f1, "force {} at factor {f}", r["force"]);
    }
    assert!(md.contains("over the last interval: 1.000"), "{md}");
}

#[test]
fn a_force_controlled_punch_carries_the_scaled_force() {
    let (code, rows, md) = sweep(&small_johnson(), "0.5,1,2");
    assert_eq!(code, 0, "{md}");
    for (r, f) in rows.iter().zip([0.5, 1.0, 2.0]) {
        assert!((num(r, "force") - 0.3 * f).abs() <= 1e-9, "force {} at factor {f}", r["force"]);
        assert!(num(r, "plastic_elements") > 0.0);
    }
    // more force, deeper: U grows faster than the force once plastic (d ln F / d ln U < 1)
    let u: Vec<f64> = rows.iter().map(|r| num(r, "U")).collect();
    assert!(u[0] < u[1] && u[1] < u[2], "{u:?}");
}

#[test]
fn a_perfectly_plastic_strip_bends_over() {
    let (code, rows, md) = sweep(&coarse_strip(), "1,10");
    assert_eq!(code, 0, "{md}");
    let (f1, f10) = (num(&rows[0], "force"), num(&rows[1], "force"));
    // ten times the indentation, far less than ten times the force (an elastic strip: exactly
    // ten times, above)
    assert!(f10 > f1 && f10 < 3.0 * f1, "{f1} → {f10}");
    let k: f64 = md.split("over the last interval: ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    // no plateau on this coarse P1 mesh (it locks: theory §10, README), but well below 1
    assert!(k > 0.0 && k < 0.75, "{md}");
}

#[test]
fn bad_factors_and_unscalable_scenes_are_refused() {
    // a force-controlled punch takes no negative factor (F ≥ 0): the error names the factor,
    // the obstacle's field, the scene's own value and the scaled one
    let (code, _, err) = sweep(&small_johnson(), "1,-2");
    assert_eq!(code, 1);
    assert!(err.contains("--factors[1] = -2") && err.contains("obstacle.F = 0.3 × -2 = -0.6"), "{err}");
    // factor 0 is the rule of load paths too: the punch carries no load and its U is
    // undetermined (theory §11.3) — empty in the CSV, the force 0
    let (code, rows, md) = sweep(&small_johnson(), "0,0.5,1");
    assert_eq!(code, 0, "{md}");
    assert_eq!(num(&rows[0], "force"), 0.0);
    assert!(rows[0]["U"].is_empty() && num(&rows[1], "U") > 0.0, "{md}");
}

#[test]
fn each_point_starts_from_the_secant_prediction_and_keeps_the_cold_answer() {
    // the P2 strip at h = 0 on 16 × 1 × 8 cells, Newton: the points 2 and 5 started from the
    // secant prediction (theory §11.2) against each solved alone, from zero (a one-point sweep)
    let mut t = example("strip_punch.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([16, 1, 8]).unwrap());
    let (code, warm, md) = sweep(&t, "1,2,5");
    assert_eq!(code, 0, "{md}");
    for (r, f) in warm.iter().skip(1).zip(["2", "5"]) {
        let (code, cold, md) = sweep(&t, f);
        assert_eq!(code, 0, "{md}");
        let (fw, fc) = (num(r, "force"), num(&cold[0], "force"));
        // both converged to tol 1e-8: the same stationary problem, the same force
        assert!((fw - fc).abs() <= 1e-9 * fc, "factor {f}: warm {fw}, cold {fc}");
    }
    // what the start buys (no fallback once the mechanism has formed) is measured end to end,
    // docs/plastic_tangent.md, not here
}
