//! Reactions balance (issue 28, theory §14): on every example scene, the supports' reactions,
//! the applied loads and the obstacles' contact forces sum to zero, force and moment about the
//! origin, to 1e-10 of their size.

use saddle::core::fem::loads::nodal_loads;
use saddle::core::{DofMap, Silent, Solver};
use saddle::io::scene::Scene;

/// The force and the moment about the origin of nodal forces `f` (3 per node) at `x`.
fn resultant(x: &[[f64; 3]], f: impl Fn(usize, usize) -> f64) -> [f64; 6] {
    let mut r = [0.0; 6];
    for (n, p) in x.iter().enumerate() {
        let v = [f(n, 0), f(n, 1), f(n, 2)];
        for c in 0..3 {
            r[c] += v[c];
        }
        r[3] += p[1] * v[2] - p[2] * v[1];
        r[4] += p[2] * v[0] - p[0] * v[2];
        r[5] += p[0] * v[1] - p[1] * v[0];
    }
    r
}

#[test]
fn reactions_balance_loads_and_contact_forces_on_every_example() {
    let mut paths: Vec<_> = std::fs::read_dir("examples")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 8, "{paths:?}");
    for path in paths {
        // a coarser mesh of a box scene keeps the test short; the balance does not depend on h
        let mut t: toml::Table = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let mesh = t.get_mut("mesh").and_then(|m| m.as_table_mut()).unwrap();
        // a mesh family (`base`) only has levels k·base: its coarsest
        if let Some(base) = mesh.get("base").cloned() {
            mesh.insert("cells".into(), base);
        } else if let Some(cells) = mesh.get_mut("cells").and_then(|c| c.as_array_mut()) {
            for c in cells.iter_mut() {
                let n = c.as_integer().unwrap();
                *c = toml::Value::Integer(if n > 8 { (n / 4).max(4) } else { n });
            }
        }
        let mut scene = Scene::from_toml(&toml::to_string(&t).unwrap(), &path).unwrap();
        scene.base_dir = "examples".into();
        let loads = scene.load.clone();
        let (l, _) = scene.into_problem().unwrap();
        // Newton at 1e-12: the balance is the equilibrium residual of the solve summed; a scene
        // with friction (which Newton refuses, theory §8.3) by uzawa at 1e-12
        let sol = if l.lagrangian().data.rows.has_friction() {
            let uzawa =
                saddle::solvers::Uzawa { tol: 1e-12, max_iter: 100_000, extra_metric: 1.0, ..Default::default() };
            uzawa.solve(&l.lagrangian(), &mut Silent).unwrap()
        } else {
            saddle::solvers::Newton { tol: 1e-12, ..Default::default() }.solve(&l.lagrangian(), &mut Silent).unwrap()
        };
        assert!(sol.report.converged, "{}: {:?}", path.display(), sol.report.stop_reason);
        let view = l.view();
        let mesh = l.element.mesh();
        let reactions = view.reactions(&sol.stress.sigma);
        assert_eq!(reactions.len(), l.supports.as_ref().unwrap().entries().len());
        let all = DofMap::from_fixed(&vec![[false; 3]; mesh.n_nodes()]);
        let f = if loads.is_empty() { vec![0.0; 3 * mesh.n_nodes()] } else { nodal_loads(mesh, &all, &loads).unwrap() };
        let applied = resultant(&mesh.nodes, |n, c| f[3 * n + c]);
        let (mut gu, mut gv) = (vec![0.0; l.element.n_dofs()], vec![0.0; l.lagrangian().n_extras()]);
        l.lagrangian().data.rows.add_transpose(&sol.lambda, &mut gu, &mut gv);
        let dofs = l.element.dofs();
        let contact = resultant(&mesh.nodes, |n, c| dofs.free(n, c).map_or(0.0, |j| gu[j]));
        let mut total = [0.0; 6];
        let mut size = [0.0f64; 2];
        for r in &reactions {
            for c in 0..3 {
                total[c] += r.force[c];
                total[3 + c] += r.moment[c];
            }
            size[0] += r.force.iter().map(|x| x.abs()).sum::<f64>();
            size[1] += r.moment.iter().map(|x| x.abs()).sum::<f64>();
        }
        for k in 0..6 {
            total[k] += applied[k] + contact[k];
            size[k / 3] += applied[k].abs() + contact[k].abs();
        }
        let force = total[..3].iter().fold(0.0f64, |m, x| m.max(x.abs())) / size[0];
        let moment = total[3..].iter().fold(0.0f64, |m, x| m.max(x.abs())) / size[1];
        println!("{}: force {force:.1e}, moment {moment:.1e} (of {:.3e}, {:.3e})", path.display(), size[0], size[1]);
        assert!(size[0] > 0.0, "{}: nothing loaded", path.display());
        assert!(force <= 1e-10 && moment <= 1e-10, "{}: imbalance {total:?}", path.display());
    }
}
