//! Bad input gets a clear error naming the field and the value, and `saddle run` writes
//! nothing.

mod common;
use common::*;
use std::process::Command;

fn edited(path: &str, value: toml::Value) -> String {
    let mut t = small_johnson();
    set(&mut t, path, value);
    toml::to_string(&t).unwrap()
}

#[test]
fn non_positive_young_modulus() {
    assert_rejected(&edited("material.E", toml::Value::Float(0.0)), &["material.E = 0", "> 0"]);
    assert_rejected(&edited("material.E", toml::Value::Float(-100.0)), &["material.E = -100"]);
}

#[test]
fn poisson_ratio_out_of_range() {
    assert_rejected(&edited("material.nu", toml::Value::Float(0.5)), &["material.nu = 0.5", "(-1, 0.5)"]);
    assert_rejected(&edited("material.nu", toml::Value::Float(-1.2)), &["material.nu = -1.2"]);
}

#[test]
fn negative_yield_and_hardening() {
    assert_rejected(&edited("yield.k0", toml::Value::Float(-1.0)), &["yield.k0 = -1"]);
    assert_rejected(&edited("yield.h", toml::Value::Float(-0.5)), &["yield.h = -0.5"]);
}

#[test]
fn negative_force_is_rejected_and_zero_force_leaves_the_punch_undetermined() {
    assert_rejected(&edited("obstacle.F", toml::Value::Float(-0.3)), &["obstacle.F = -0.3", ">= 0"]);
    // F = 0 is one rule for scenes, sweeps and load paths (F ≥ 0): the punch carries no load,
    // so its contact forces vanish and U is undetermined (theory §11.3) — null in the summary,
    // the body unloaded: zero displacement, exactly
    let (code, err, dir) = run_scene_kept(&edited("obstacle.F", toml::Value::Float(0.0)));
    assert_eq!(code, 0, "{err}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
    assert!(s["U"].is_null() && s["extras"]["U"].is_null() && s["contact"]["U"].is_null(), "{s}");
    assert_eq!(s["contact"]["force"], 0.0);
    assert_eq!(s["contact_nodes"], 0);
    assert_eq!(s["plastic_elements"], 0);
    assert!(s["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("carries no load")), "{s}");
}

#[test]
fn not_a_number_is_rejected() {
    assert_rejected(&edited("material.E", toml::Value::Float(f64::NAN)), &["material.E = NaN", "finite"]);
}

#[test]
fn contact_zone_without_nodes() {
    let zone: toml::Value = toml::from_str::<toml::Table>(
        "z = { all = [ { group = \"zmin\" }, { disc = { center = [5.0, 5.0], radius = 0.1 } } ] }",
    )
    .unwrap()["z"]
        .clone();
    assert_rejected(&edited("obstacle.zone", zone), &["obstacle.zone"]);
}

#[test]
fn inverted_tetrahedron() {
    let text = r#"
[mesh]
type = "inline"
nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]]
tets = [[0, 1, 2, 3], [1, 3, 2, 4]]
[material]
E = 1.0
nu = 0.3
"#;
    assert_rejected(text, &["element 1", "inverted"]);
}

#[test]
fn unknown_plugin_type_lists_the_known_ones() {
    let mut t = small_johnson();
    set(&mut t, "yield.type", toml::Value::String("von_mieses".into()));
    assert_rejected(&toml::to_string(&t).unwrap(), &["von_mieses", "von_mises", "elastic"]);
    let mut t = small_johnson();
    set(&mut t, "solver.type", toml::Value::String("newtonn".into()));
    assert_rejected(&toml::to_string(&t).unwrap(), &["newtonn", "uzawa"]);
}

#[test]
fn unknown_field_lists_the_known_ones() {
    assert_rejected(&edited("yield.kO", toml::Value::Float(1.0)), &["kO", "k0"]);
    assert_rejected(&edited("material.poisson", toml::Value::Float(0.3)), &["poisson", "nu"]);
}

#[test]
fn unknown_solver_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", repo("examples/homogeneous.toml").to_str().unwrap(), "--quiet", "--solver", "nope", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("--solver nope") && err.contains("uzawa"), "{err}");
    assert!(!out.exists());
}
