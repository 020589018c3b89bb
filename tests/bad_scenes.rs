//! Issue 5, case 9: **bad scene files.** Every numeric field of every plugin — found by walking
//! the scene's TOML, not by a hand-made list — rejects NaN and both infinities with an error that
//! names the field's path; the out-of-range values of each bounded field are rejected the same
//! way; a missing mesh file names its path; and `saddle run` writes nothing for an invalid scene.

mod common;
use common::*;
use saddle::core::Solver;
use saddle::io::scene::Scene;
use std::path::Path;

/// Base scenes that together use every plugin and every numeric field: the examples plus
/// variants with each solver (all fields written out by serialising its defaults), each gap
/// shape, the displacement-controlled punch, loads and an inline mesh.
fn base_scenes() -> Vec<(String, toml::Table)> {
    let mut scenes = vec![];
    let solvers: Vec<Box<dyn Solver>> = vec![
        Box::new(saddle::solvers::Uzawa::default()),
        Box::new(saddle::solvers::Newton::default()),
        Box::new(saddle::solvers::Penalty::default()),
        #[cfg(feature = "socp")]
        Box::new(saddle::solvers::Socp::default()),
    ];
    for s in &solvers {
        let mut t = small_johnson();
        let value: toml::Value = toml::Value::try_from(s).expect("solvers serialise");
        t.insert("solver".into(), value);
        scenes.push((format!("johnson + {}", s.name()), t));
    }
    let table = |text: &str| -> toml::Value { toml::from_str::<toml::Table>(text).unwrap()["v"].clone() };
    let mut t = small_johnson();
    set(
        &mut t,
        "obstacle.gap",
        table("v = { type = \"elliptic_paraboloid\", R1 = 4.0, R2 = 6.0, c1 = 0.1, c2 = -0.1 }"),
    );
    scenes.push(("elliptic gap".into(), t));
    let mut t = small_johnson();
    set(&mut t, "obstacle.gap", table("v = { type = \"flat\", center = [0.0, 0.0] }"));
    scenes.push(("flat gap".into(), t));
    let mut t = small_johnson();
    set(
        &mut t,
        "obstacle",
        table(
            "v = { type = \"rigid_punch_displacement\", U = 0.01, zone = { all = [ { group = \"zmin\" }, \
             { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }, gap = { type = \"paraboloid\", R = 5.0, \
             center = [0.0, 0.0] } }",
        ),
    );
    scenes.push(("displacement punch".into(), t));
    let zone = "zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }";
    let mut t = small_johnson();
    set(
        &mut t,
        "obstacle",
        table(&format!(
            "v = {{ type = \"tilting_punch\", F = 0.3, at = [0.05, 0.0], {zone}, gap = {{ type = \"paraboloid\", \
             R = 5.0, center = [0.0, 0.0] }} }}"
        )),
    );
    scenes.push(("tilting punch".into(), t));
    let mut t = small_johnson();
    set(
        &mut t,
        "obstacle",
        table(&format!(
            "v = {{ type = \"rigid_sphere\", center = [0.0, 0.0, -5.0], R = 5.0, direction = [0.2, 0.0, 1.0], \
             F = 0.3, {zone} }}"
        )),
    );
    scenes.push(("rigid sphere".into(), t));
    let mut t = small_johnson();
    t.insert(
        "load".into(),
        table(
            "v = [ { type = \"traction\", on = { group = \"zmin\" }, t = [0.0, 0.0, 0.01] }, \
             { type = \"body_force\", b = [0.0, 0.0, -0.001] } ]",
        ),
    );
    scenes.push(("loads".into(), t));
    let inline = r#"
[mesh]
type = "inline"
nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
tets = [[0, 1, 2, 3]]
[material]
E = 100.0
nu = 0.3
[[dirichlet]]
on = { box = { min = [-1.0, -1.0, -1.0], max = [2.0, 2.0, 0.0] } }
"#;
    scenes.push(("inline mesh".into(), toml::from_str(inline).unwrap()));
    scenes.push(("hertz".into(), example("hertz.toml")));
    scenes.push(("homogeneous".into(), example("homogeneous.toml")));
    // supports (issue 28): a prescribed displacement, a pressure
    let mut t = example("tensile_bar.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([2, 1, 1]).unwrap());
    set(&mut t, "load", table("v = [ { type = \"pressure\", on = { group = \"ymax\" }, p = 0.5 } ]"));
    scenes.push(("tensile bar with a pressure".into(), t));
    scenes
}

/// Every numeric leaf of `v` with its path (`obstacle.zone.all[1].disc.center[0]`).
fn numeric_leaves(v: &toml::Value, path: String, out: &mut Vec<String>) {
    match v {
        toml::Value::Float(_) | toml::Value::Integer(_) => out.push(path),
        toml::Value::Table(t) => {
            for (k, x) in t {
                let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                numeric_leaves(x, p, out);
            }
        }
        toml::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                numeric_leaves(x, format!("{path}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// `t` with the leaf at `path` replaced by `value`.
fn with_leaf(t: &toml::Table, path: &str, value: toml::Value) -> toml::Table {
    let mut root = toml::Value::Table(t.clone());
    let mut cur = &mut root;
    for part in path.split('.') {
        let (key, indices) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        cur = cur.as_table_mut().unwrap().get_mut(key).unwrap();
        for idx in indices.split(['[', ']']).filter(|s| !s.is_empty()) {
            cur = &mut cur.as_array_mut().unwrap()[idx.parse::<usize>().unwrap()];
        }
    }
    *cur = value;
    match root {
        toml::Value::Table(t) => t,
        _ => unreachable!(),
    }
}

/// The error of building `t`, if any (parsing, validation, mesh, assembly).
fn error_of(t: &toml::Table) -> Option<String> {
    let text = toml::to_string(t).unwrap();
    match Scene::from_toml(&text, Path::new("sweep.toml")) {
        Err(e) => Some(e.to_string()),
        Ok(scene) => scene.into_problem().err().map(|e| e.to_string()),
    }
}

/// The path an error must name: the leaf's path, or for an array element the array's path.
fn accepted_names(path: &str) -> Vec<String> {
    let mut names = vec![path.to_string()];
    let mut p = path;
    while let Some(i) = p.rfind('[') {
        if !p.ends_with(']') {
            break;
        }
        p = &p[..i];
        names.push(p.to_string());
    }
    names
}

#[test]
fn every_numeric_field_rejects_nan_and_infinities_by_path() {
    let mut checked = 0;
    let mut failures = vec![];
    for (name, base) in base_scenes() {
        assert!(error_of(&base).is_none(), "base scene {name} must be valid: {:?}", error_of(&base));
        let mut leaves = vec![];
        numeric_leaves(&toml::Value::Table(base.clone()), String::new(), &mut leaves);
        for leaf in &leaves {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let t = with_leaf(&base, leaf, toml::Value::Float(bad));
                checked += 1;
                match error_of(&t) {
                    None => failures.push(format!("{name}: {leaf} = {bad} accepted")),
                    Some(e) if !accepted_names(leaf).iter().any(|p| e.contains(p.as_str())) => {
                        failures.push(format!("{name}: {leaf} = {bad}: error does not name the field: {e}"))
                    }
                    Some(_) => {}
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} of {checked} bad values mishandled:\n{}", failures.len(), failures.join("\n"));
    assert!(checked > 300, "only {checked} cases: the walk missed fields");
}

/// Out-of-range values of every bounded field, each named with its path and value.
#[test]
fn out_of_range_values_are_rejected_by_path() {
    let scenes = base_scenes();
    let scene = |n: &str| scenes.iter().find(|(name, _)| name.contains(n)).unwrap().1.clone();
    let cases: Vec<(&str, &str, toml::Value)> = vec![
        ("uzawa", "material.E", (-1.0).into()),
        ("uzawa", "material.nu", 0.5.into()),
        ("uzawa", "material.nu", (-1.0).into()),
        ("uzawa", "yield.k0", (-1.0).into()),
        ("uzawa", "yield.h", (-1e-3).into()),
        ("uzawa", "obstacle.F", (-0.3).into()),
        ("uzawa", "obstacle.gap.R", 0.0.into()),
        ("uzawa", "obstacle.zone.all[1].disc.radius", (-0.5).into()),
        ("uzawa", "mesh.cells[0]", 0.into()),
        ("uzawa", "mesh.cells[2]", (-3).into()),
        ("uzawa", "mesh.grading.ratio", 0.0.into()),
        ("uzawa", "mesh.max[2]", (-1.0).into()),
        ("uzawa", "solver.rho", 0.0.into()),
        ("uzawa", "solver.tol", 0.0.into()),
        ("uzawa", "solver.max_iter", 0.into()),
        ("newton", "solver.tol", (-1e-8).into()),
        ("newton", "solver.max_iter", 0.into()),
        ("penalty", "solver.mu", 0.0.into()),
        ("penalty", "solver.tol", 2.0.into()),
        ("elliptic", "obstacle.gap.R1", (-4.0).into()),
        ("elliptic", "obstacle.gap.R2", 0.0.into()),
        ("tilting", "obstacle.F", (-0.3).into()),
        ("tilting", "obstacle.at[0]", 0.9.into()),
        ("sphere", "obstacle.R", 0.0.into()),
        ("sphere", "obstacle.F", (-0.1).into()),
    ];
    let mut failures = vec![];
    for (base, path, value) in &cases {
        let t = with_leaf(&scene(base), path, value.clone());
        match error_of(&t) {
            None => failures.push(format!("{base}: {path} = {value} accepted")),
            Some(e) if !accepted_names(path).iter().any(|p| e.contains(p.as_str())) => {
                failures.push(format!("{base}: {path} = {value}: error does not name the field: {e}"))
            }
            Some(_) => {}
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn missing_mesh_file_names_the_path_and_nothing_is_written() {
    let mut t = example("gmsh_punch.toml");
    set(&mut t, "mesh.file", "no/such/mesh.msh".into());
    let (code, err, wrote) = run_scene(&toml::to_string(&t).unwrap());
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no/such/mesh.msh"), "{err}");
    assert!(!wrote, "nothing is written for an invalid scene");
}
