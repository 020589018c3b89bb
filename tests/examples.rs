//! The Rust examples run in CI: `examples/rigid_cone.rs` (a problem composed in Rust with an
//! obstacle plugin of its own) at a small size — its K kit passes, every solver converges, the
//! solvers agree, and each balances the cone's force F = 0.3 (Σλ_i n_i·e₃ = F); and
//! `examples/punch_friction.toml` (a punch pressed, then pulled, with friction) by `saddle run`.

mod common;

#[path = "../examples/rigid_cone.rs"]
mod rigid_cone;

#[test]
fn rigid_cone_runs_and_every_solver_agrees() {
    let out = rigid_cone::run([8, 8, 4]);
    assert_eq!(out.len(), if cfg!(feature = "socp") { 4 } else { 3 });
    let v = out[0].v;
    assert!(v > 0.0, "the cone moves up into the body: V = {v}");
    for o in &out {
        assert!(o.converged, "{}", o.solver);
        assert!((o.force - 0.3).abs() <= 1e-8 * 0.3, "{}: force {}", o.solver, o.force);
        assert!((o.v - v).abs() <= 1e-7 * v, "{}: V = {} vs {v}", o.solver, o.v);
        assert_eq!(o.contact_nodes, out[0].contact_nodes, "{}", o.solver);
        assert!(o.contact_nodes > 1, "contact spreads beyond the apex node");
    }
}

/// `examples/punch_friction.toml` (theory §8.3): pressed by F = 0.5, then pulled by
/// Q = [0.075, 0] = 0.5 μF. summary.json names the extras U, Ux, Uy; at the pulled step the
/// punch's resultants balance F and Q to 1e-8 (newton's tolerance 1e-10), it moved along +x,
/// and its contact both sticks and slips (|Q| < μF: partial slip); pressed alone (Q at 0) the
/// tangential resultant vanishes.
#[test]
fn punch_friction_presses_then_pulls_with_partial_slip() {
    let text = std::fs::read_to_string(common::repo("examples/punch_friction.toml")).unwrap();
    let (code, stderr, dir) = common::run_scene_kept(&text);
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    let get = |s: &serde_json::Value, k: &str| {
        s["contact"][k].as_f64().or_else(|| s["extras"][k].as_f64()).unwrap_or_else(|| panic!("{k} in {s}"))
    };
    let (pressed, pulled) = (&steps[0], &steps[1]);
    println!("{pulled}");
    assert!(get(pressed, "force_x").abs() < 1e-8 * 0.5, "{}", get(pressed, "force_x"));
    assert!((get(pulled, "force") - 0.5).abs() < 1e-8 * 0.5 && (get(pulled, "force_x") - 0.075).abs() < 1e-8 * 0.5);
    assert!(get(pulled, "Ux") > 0.0 && get(pulled, "stick_nodes") > 0.0 && get(pulled, "slip_nodes") > 0.0);
}
