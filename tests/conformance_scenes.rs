//! The solvers' conformance kit (`saddle_solvers::conformance`) builds its scenes in code from
//! saddle-core's types; they are the example files' problems: the same data, field for field, as
//! the facade reads them from the files, and the same assembled problems.

use saddle::core::{DiscreteProblem, P1};
use saddle::io::scene::Scene;
use saddle::solvers::conformance::{Johnson, Setup, hertz, homogeneous};
use std::path::{Path, PathBuf};

/// The example file's scene without its title and solver, as data.
fn example(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name);
    Scene { title: None, solver: None, base_dir: PathBuf::new(), ..Scene::from_file(&path).unwrap() }
}

/// The kit's set-up as a scene (no title, loads, solver or load path).
fn scene_of(setup: &Setup) -> Scene {
    let s = setup.clone();
    Scene {
        title: None,
        mesh: Box::new(s.mesh),
        // the kit's default element is P1, a scene's P2: the scene states it
        discretisation: Some(s.element.unwrap_or_else(|| Box::new(P1::default()))),
        material: s.elasticity,
        yield_surface: s.stresses,
        dirichlet: s.dirichlet,
        load: s.loads,
        obstacle: s.obstacles,
        solver: None,
        load_path: None,
        base_dir: PathBuf::new(),
        petsc_options: None,
        output: Default::default(),
    }
}

/// Every field and plugin parameter of a scene, as plain data.
fn data(scene: &Scene) -> serde_json::Value {
    serde_json::to_value(scene).unwrap()
}

/// Asserts that two assembled problems are the same: sizes, mesh, dofs, K's rows and load, the
/// nodal loads, elasticity and P.
fn assert_same_problem(a: &DiscreteProblem, b: &DiscreteProblem, file: &str) {
    let (la, lb) = (a.lagrangian(), b.lagrangian());
    let sizes = |l: &saddle::core::Lagrangian<'_>| [l.n_dofs(), l.n_points(), l.n_rows(), l.n_extras()];
    assert_eq!(sizes(&la), sizes(&lb), "{file}: dofs, stress points, rows, extras");
    let (ma, mb) = (a.element.mesh(), b.element.mesh());
    assert_eq!((&ma.nodes, &ma.tets), (&mb.nodes, &mb.tets), "{file}: mesh");
    assert_eq!(a.element.dofs().dof, b.element.dofs().dof, "{file}: dof numbering");
    assert_eq!(a.obstacles.rows(), b.obstacles.rows(), "{file}: rows of K_h");
    assert_eq!(a.obstacles.load(), b.obstacles.load(), "{file}: load on the extras");
    assert_eq!(a.nodal_load, b.nodal_load, "{file}: nodal loads");
    assert_eq!(a.elasticity, b.elasticity, "{file}: elasticity");
    assert_eq!(serde_json::to_value(&a.stresses).unwrap(), serde_json::to_value(&b.stresses).unwrap(), "{file}: P");
}

/// The kit's scenes are the example files' problems: the same data, field for field, and the same
/// assembled problems.
#[test]
fn kit_scenes_are_the_example_files() {
    let cases = [
        ("johnson.toml", Johnson { cells: [32, 32, 16], ratio: 4.0, ..Johnson::default() }.setup()),
        ("homogeneous.toml", homogeneous(2.0)),
        ("hertz.toml", hertz([25, 25, 25], 79.5)),
    ];
    for (file, setup) in cases {
        let file_scene = example(file);
        assert_eq!(data(&scene_of(&setup)), data(&file_scene), "{file}");
        let (from_file, _) = file_scene.into_problem().unwrap();
        assert_same_problem(&setup.problem().unwrap(), &from_file, file);
    }
    // the small default differs from the example by its mesh only
    let (mut small, file) =
        (data(&scene_of(&Johnson::default().setup())), data(&example("johnson.toml").with_cells([12, 12, 6]).unwrap()));
    assert_eq!(small["mesh"]["grading"]["ratio"], 3.0);
    small["mesh"]["grading"]["ratio"] = file["mesh"]["grading"]["ratio"].clone();
    assert_eq!(small, file);
}
