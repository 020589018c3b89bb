//! The Rust examples run in CI: `examples/rigid_cone.rs` (a problem composed in Rust with an
//! obstacle plugin of its own) at a small size — its K kit passes, every solver converges, the
//! solvers agree, and each balances the cone's force F = 0.3 (Σλ_i n_i·e₃ = F).

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
