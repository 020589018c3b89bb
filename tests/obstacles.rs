//! Several obstacles (theory §8: K = K₁ ∩ K₂ ∩ …, rows and extras concatenated, each extra keeping
//! its obstacle's name): two punches on disjoint discs of the default scene's bottom face, read
//! from `[[obstacle]]`, discretised, solved and summarised obstacle by obstacle; a single
//! `[obstacle]` table summarised as before; bad names rejected with the field and the value.

mod common;
use common::*;
use saddle::core::Silent;
use saddle::io::scene::Scene;
use saddle::io::summary::Summary;
use std::path::Path;

/// Forces of the two punches: different, so that swapped or shared columns of H show.
const F_LEFT: f64 = 0.1;
const F_RIGHT: f64 = 0.25;

/// The obstacle table of a punch with force `f` on the disc of radius 0.3 about (`x`, 0), its
/// paraboloid centred there; `name` first when given.
fn punch(name: Option<&str>, f: f64, x: f64) -> String {
    let name = name.map_or(String::new(), |n| format!("name = \"{n}\"\n"));
    format!(
        "{name}type = \"rigid_punch\"\nF = {f:?}\n\
         zone = {{ all = [ {{ group = \"zmin\" }}, {{ disc = {{ center = [{x:?}, 0.0], radius = 0.3 }} }} ] }}\n\
         gap = {{ type = \"paraboloid\", R = 5.0, center = [{x:?}, 0.0] }}\n"
    )
}

/// The default scene on a coarse 8×8×4 mesh with Uzawa to 1e-10, without its obstacle.
fn base() -> String {
    let mut t = example("johnson.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([8, 8, 4]).unwrap());
    set(&mut t, "mesh.grading.ratio", toml::Value::Float(2.0));
    set(&mut t, "solver.tol", toml::Value::Float(1e-10));
    set(&mut t, "solver.max_iter", toml::Value::Integer(20000));
    t.remove("obstacle");
    toml::to_string(&t).unwrap()
}

/// The base scene with two named punches, left on x < 0 and right on x > 0.
fn two_punches() -> String {
    format!(
        "{}\n[[obstacle]]\n{}\n[[obstacle]]\n{}",
        base(),
        punch(Some("left"), F_LEFT, -0.35),
        punch(Some("right"), F_RIGHT, 0.35)
    )
}

fn scene(text: &str) -> Scene {
    Scene::from_toml(text, Path::new("s.toml")).unwrap()
}

fn error(text: &str) -> String {
    Scene::from_toml(text, Path::new("s.toml")).unwrap_err().to_string()
}

#[test]
fn two_punches_parse_and_discretise_as_the_concatenation_of_each() {
    let s = scene(&two_punches());
    assert_eq!(s.obstacle.len(), 2);
    assert!(s.obstacle.is_array());
    let names: Vec<_> = s.obstacle.iter().map(|o| o.name.clone()).collect();
    assert_eq!(names, [Some("left".to_string()), Some("right".to_string())]);
    let (l, _) = s.into_problem().unwrap();
    assert_eq!(l.view().extra_names(), ["left.U", "right.U"]);
    assert_eq!(l.lagrangian().n_extras(), 2);
    assert_eq!(l.lagrangian().data.load, [F_LEFT, F_RIGHT]);

    // each punch alone, as a single [obstacle] table
    let alone = |text: String| scene(&format!("{}\n[obstacle]\n{text}", base())).into_problem().unwrap().0;
    let left = alone(punch(None, F_LEFT, -0.35));
    let right = alone(punch(None, F_RIGHT, 0.35));
    let (nl, nr) = (left.lagrangian().data.rows.n_rows(), right.lagrangian().data.rows.n_rows());
    assert!(nl > 0 && nr > 0);
    let rows = l.lagrangian().data.rows;
    assert_eq!(rows.n_rows(), nl + nr);
    assert_eq!(rows.n_extras, 2);
    // left's rows first with their H in column 0, right's after with theirs in column 1
    for i in 0..nl {
        assert_eq!(rows.row(i), left.lagrangian().data.rows.row(i));
        assert_eq!(rows.node[i], left.lagrangian().data.rows.node[i]);
        assert_eq!(rows.offset[i], left.lagrangian().data.rows.offset[i]);
        assert_eq!(rows.extra_row(i), [left.lagrangian().data.rows.extra_row(i)[0], 0.0]);
    }
    for i in 0..nr {
        assert_eq!(rows.row(nl + i), right.lagrangian().data.rows.row(i));
        assert_eq!(rows.node[nl + i], right.lagrangian().data.rows.node[i]);
        assert_eq!(rows.offset[nl + i], right.lagrangian().data.rows.offset[i]);
        assert_eq!(rows.extra_row(nl + i), [0.0, right.lagrangian().data.rows.extra_row(i)[0]]);
    }
    let parts = l.obstacles.parts();
    assert_eq!((parts[0].row_range.clone(), parts[1].row_range.clone()), (0..nl, nl..nl + nr));
    assert_eq!((parts[0].extra_range.clone(), parts[1].extra_range.clone()), (0..1, 1..2));

    // the direct gap of the concatenation is each obstacle's gap on its slice; the punch's rows
    // are exact, so it equals the linear rows at any (u, V)
    let u: Vec<f64> = (0..l.element.n_dofs()).map(|j| 1e-3 * ((j * 7919 % 101) as f64 - 50.0)).collect();
    let v = [0.013, -0.021];
    let (mut direct, mut linear) = (vec![0.0; nl + nr], vec![0.0; nl + nr]);
    l.obstacles.gap(l.element.mesh(), l.element.dofs(), &u, &v, &mut direct);
    rows.gap(&u, &v, &mut linear);
    for (a, b) in direct.iter().zip(&linear) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn each_punch_carries_its_own_force() {
    let (l, solver) = scene(&two_punches()).into_problem().unwrap();
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    let s = Summary::new(l.view(), &sol, None);
    let json = serde_json::to_value(&s).unwrap();
    assert_eq!(json["obstacles"].as_array().unwrap().len(), 2);
    for (i, (name, f)) in [("left", F_LEFT), ("right", F_RIGHT)].into_iter().enumerate() {
        let o = &json["obstacles"][i];
        assert_eq!(o["name"], name);
        assert_eq!(o["type"], "rigid_punch");
        let force = o["force"].as_f64().unwrap();
        assert!((force - f).abs() <= 1e-8 * f, "{name}: Σλ = {force}, F = {f}");
        assert!(o["contact_nodes"].as_u64().unwrap() > 0, "{name} touches");
        // its U is the extra of its name, and the same number in `contact`
        let u = json["extras"][format!("{name}.U")].as_f64().unwrap();
        assert_eq!(o["U"].as_f64(), Some(u));
        assert_eq!(json["contact"][format!("{name}.U")].as_f64(), Some(u));
        assert_eq!(json["contact"][format!("{name}.force")].as_f64(), Some(force));
        assert_eq!(u, sol.extras[i]);
    }
    assert_eq!(json["extras"].as_object().unwrap().len(), 2);
    // the stronger push moves its punch further
    assert!(json["extras"]["right.U"].as_f64() > json["extras"]["left.U"].as_f64());
    // the single-obstacle keys: no U or force of "the" punch, totals over both
    assert!(json["U"].is_null() && json["force"].is_null());
    let nodes: u64 = (0..2).map(|i| json["obstacles"][i]["contact_nodes"].as_u64().unwrap()).sum();
    assert_eq!(json["contact_nodes"].as_u64(), Some(nodes));
    let radius = (0..2).map(|i| json["obstacles"][i]["contact_radius"].as_f64().unwrap()).fold(0.0, f64::max);
    assert_eq!(json["contact_radius"].as_f64(), Some(radius));
}

#[test]
fn a_single_table_keeps_the_summary_keys_of_its_report() {
    let text = format!("{}\n[obstacle]\n{}", base(), punch(None, 0.3, 0.0));
    let (l, solver) = scene(&text).into_problem().unwrap();
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    let s = Summary::new(l.view(), &sol, None);
    // the obstacle's own report, asked directly
    let k = l.view().obstacle().expect("one obstacle");
    let r = k.report(l.element.mesh(), l.lagrangian().data.rows, &sol.extras, &sol.lambda);
    assert_eq!(s.U, r.get("U"));
    assert_eq!(s.force, r.get("force"));
    assert!(s.U.is_some() && s.force.is_some());
    assert_eq!(s.contact_nodes, r.contact_nodes);
    assert_eq!(s.contact_radius, r.contact_radius);
    // the plugin's quantities, and the generic `imprint` (theory §11.4): for the punch the
    // largest u₃ of its candidate nodes, which under load is U at the node of deepest contact
    assert_eq!(s.contact.len(), r.quantities.len() + 1);
    let u3 = l.element.nodal_vectors(&sol.u);
    let deepest = l.lagrangian().data.rows.node.iter().map(|&n| u3[n][2]).fold(f64::MIN, f64::max);
    assert_eq!(s.contact["imprint"], deepest);
    assert!((deepest - sol.extras[0]).abs() <= 1e-9 * sol.extras[0], "the punch touches at its deepest node");
    for (q, v) in &r.quantities {
        assert_eq!(s.contact.get(q), Some(v), "{q}");
    }
    let json = serde_json::to_value(&s).unwrap();
    assert_eq!(json["extras"], serde_json::json!({ "U": sol.extras[0] }));
    let o = &json["obstacles"][0];
    assert!(o["name"].is_null());
    assert_eq!(o["type"], "rigid_punch");
    assert_eq!(o["U"].as_f64(), r.get("U"));
    assert_eq!(o["force"].as_f64(), r.get("force"));
    assert_eq!(o["contact_nodes"].as_u64(), Some(r.contact_nodes as u64));
    assert_eq!(json["obstacles"].as_array().unwrap().len(), 1);
}

#[test]
fn scenes_are_written_back_in_the_shape_they_were_read() {
    // an array of two, a named single table, an unnamed single table, none
    let cases = [
        (two_punches(), vec!["left.U", "right.U"], true),
        (format!("{}\n[obstacle]\n{}", base(), punch(Some("p"), 0.3, 0.0)), vec!["p.U"], false),
        (format!("{}\n[obstacle]\n{}", base(), punch(None, 0.3, 0.0)), vec!["U"], false),
    ];
    for (text, names, array) in cases {
        let s = scene(&text);
        let written = toml::to_string(&s).unwrap();
        let again = scene(&written);
        assert_eq!(again.obstacle.is_array(), array, "{written}");
        assert_eq!(again.obstacle.extra_names(), names, "{written}");
        assert_eq!(toml::to_string(&again).unwrap(), written);
    }
    let none = scene(&base());
    assert!(none.obstacle.is_empty());
    assert!(scene(&toml::to_string(&none).unwrap()).obstacle.is_empty());
    // a one-element array stays an array: its paths are obstacle[0].…
    let one = format!("{}\n[[obstacle]]\n{}", base(), punch(None, 0.3, 0.0));
    let e = error(&one.replace("F = 0.3", "F = -0.3"));
    assert!(e.contains("obstacle[0].F = -0.3"), "{e}");
}

#[test]
fn bad_names_name_the_field_and_the_value() {
    let dup = two_punches().replace("name = \"right\"", "name = \"left\"");
    let e = error(&dup);
    assert!(e.contains("obstacle[1].name") && e.contains("\"left\"") && e.contains("unique"), "{e}");
    let missing = two_punches().replace("name = \"right\"\n", "");
    let e = error(&missing);
    assert!(e.contains("obstacle[1].name") && e.contains("(none)") && e.contains("name"), "{e}");
    let empty = two_punches().replace("name = \"left\"", "name = \"\"");
    let e = error(&empty);
    assert!(e.contains("obstacle[0].name = \"\""), "{e}");
    let number = two_punches().replace("name = \"left\"", "name = 3");
    let e = error(&number);
    assert!(e.contains("obstacle[0]") && e.contains("name = 3"), "{e}");
    // the plugin still rejects unknown fields, and parameters are checked under obstacle[i]
    let e = error(&two_punches().replace("name = \"right\"", "name = \"right\"\nradius = 2.0"));
    assert!(e.contains("obstacle[1]") && e.contains("radius"), "{e}");
    let e = error(&two_punches().replace(&format!("F = {F_RIGHT:?}"), "F = -0.1"));
    assert!(e.contains("obstacle[1].F = -0.1"), "{e}");
}

#[test]
fn saddle_run_writes_nothing_for_bad_names() {
    for text in
        [two_punches().replace("name = \"right\"", "name = \"left\""), two_punches().replace("name = \"right\"\n", "")]
    {
        let (code, err, wrote) = run_scene(&text);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains("obstacle[1].name"), "{err}");
        assert!(!wrote, "nothing is written for an invalid scene");
    }
}

#[test]
fn saddle_run_prints_each_obstacle_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, two_punches()).unwrap();
    let out = dir.path().join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", path.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    for line in ["obstacle left", "obstacle right", "left.U", "right.force"] {
        assert!(stdout.contains(line), "{line} missing:\n{stdout}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["extras"]["left.U"].is_f64() && summary["extras"]["right.U"].is_f64(), "{summary}");
}

/// The imprint is read off the normal rows only: a sphere pressed in by V and dragged across by
/// W ≫ V with a bound that sticks every contact node moves those nodes by about W along the
/// tangential rows (theory §8.3), but indents the body by no more than V — n·u = V n·d − φ ≤ V
/// at a contact node.
#[test]
fn the_imprint_of_a_dragged_sphere_is_its_indentation_not_its_slip() {
    let (v, w) = (0.01, 0.05);
    let mut t: toml::Table = toml::from_str(&base()).unwrap();
    t.remove("yield");
    let sphere = format!(
        "type = \"rigid_sphere\"\ncenter = [0.0, 0.0, -5.0]\nR = 5.0\ndirection = [0.0, 0.0, 1.0]\nV = {v:?}\n\
         W = [{w:?}, 0.0]\nfriction = {{ type = \"tresca\", g = 100.0 }}\n\
         zone = {{ all = [ {{ group = \"zmin\" }}, {{ disc = {{ center = [0.0, 0.0], radius = 0.5 }} }} ] }}"
    );
    t.insert("obstacle".into(), toml::Value::Table(toml::from_str(&sphere).unwrap()));
    let (l, solver) = scene(&toml::to_string(&t).unwrap()).into_problem().unwrap();
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    let json = serde_json::to_value(Summary::new(l.view(), &sol, None)).unwrap();
    let o = &json["obstacles"][0];
    assert!(o["stick_nodes"].as_f64().unwrap() > 0.0 && o["slip_nodes"].as_f64() == Some(0.0), "{o}");
    assert!((o["Ux"].as_f64().unwrap() - w).abs() < 1e-15, "{o}");
    let imprint = o["imprint"].as_f64().unwrap();
    assert!(imprint > 0.5 * v && imprint <= v * (1.0 + 1e-9), "imprint {imprint:e} against V = {v:e}, W = {w:e}");
}
