//! `saddle bench` on a small size: writes its table, CSV and plot; every run converges; the
//! baselines and ratios are finite; the AMG and direct backends of Newton agree on the KKT
//! tolerance.

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
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("| DOFs |") && md.contains("newton-amg:") && md.contains("elastic scene, uzawa"), "{md}");
    if cfg!(feature = "report") {
        assert!(std::fs::metadata(out.join("bench.png")).unwrap().len() > 10_000);
        assert!(std::fs::metadata(out.join("bench.svg")).unwrap().len() > 1_000);
    }
}
