//! Loads with factors of their own in a load path (`[load_path.loads]`, theory §11.2): a named
//! load follows its own list, every other load `factors`; the lists are checked naming the field.

mod common;
use common::*;

/// A rigid sphere pressed by F = 0.3 and pulled by Q = [0.045, 0] (Coulomb, μ = 0.3) into a
/// small elastic P1 box, solved by uzawa; `path` is the scene's `[load_path]` text, `name` the
/// obstacle's name (none: unnamed).
fn sphere(q: f64, name: Option<&str>, path: &str) -> String {
    let name = name.map_or(String::new(), |n| format!("name = \"{n}\"\n"));
    format!(
        r#"
[discretisation]
type = "p1"
[mesh]
type = "box"
min = [-2.0, -2.0, 0.0]
max = [2.0, 2.0, 2.0]
cells = [8, 8, 4]
grading = {{ toward = [0.0, 0.0, 0.0], ratio = 4.0 }}
[material]
E = 100.0
nu = 0.3
[[dirichlet]]
on = {{ any = [ {{ group = "xmin" }}, {{ group = "xmax" }}, {{ group = "ymin" }}, {{ group = "ymax" }}, {{ group = "zmax" }} ] }}
[obstacle]
{name}type = "rigid_sphere"
center = [0.0, 0.0, -5.0]
R = 5.0
direction = [0.0, 0.0, 1.0]
F = 0.3
Q = [{q}, 0.0]
zone = {{ all = [ {{ group = "zmin" }}, {{ disc = {{ center = [0.0, 0.0], radius = 0.8 }} }} ] }}
friction = {{ type = "coulomb", mu = 0.3 }}
[solver]
type = "uzawa"
tol = 1e-11
max_iter = 100000
extra_metric = 1.0
{path}
"#
    )
}

/// `summary.json` of `saddle run` on `text` (exit status 0).
fn run(text: &str) -> serde_json::Value {
    let (code, stderr, dir) = run_scene_kept(text);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap()
}

/// The extras V, Ux, Uy of a summary entry (a step, or a one-step summary).
fn extras(s: &serde_json::Value) -> [f64; 3] {
    ["V", "Ux", "Uy"].map(|k| s["extras"][k].as_f64().unwrap_or_else(|| panic!("{k} in {}", s["extras"])))
}

fn close(a: [f64; 3], b: [f64; 3], what: &str) {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-12 * scale, "{what}: {a:?} against {b:?}");
    }
}

/// Pressing without pulling, the first step of "press, then pull" (F at its factor 1, Q at 0)
/// is the scene with Q edited to 0 by hand; a list proportional to `factors` is the scene with
/// Q edited by the constant, at every step (sub-steps divide each list alike): the extras to
/// 1e-12 of their size (the same problem, whose Q is q × factor in one and the edited value ×
/// factor in the other; measured equal to the last bit).
#[test]
fn a_load_with_its_own_factors_equals_the_scene_edited_by_hand() {
    let q = 0.045;
    let pressed = run(&sphere(q, None, "[load_path]\nfactors = [1.0, 1.0]\n[load_path.loads]\nQ = [0.0, 1.0]\n"));
    let by_hand = run(&sphere(0.0, None, ""));
    close(extras(&pressed["steps"][0]), extras(&by_hand), "Q at factor 0");
    assert_eq!(pressed["steps"][1]["loads"]["Q"].as_f64(), Some(1.0));
    assert!(extras(&pressed["steps"][1])[1] > 0.0, "pulled along +x: {:?}", extras(&pressed["steps"][1]));
    let own = run(&sphere(
        q,
        Some("ball"),
        "[load_path]\nfactors = [0.5, 1.0]\nsubsteps = 2\n[load_path.loads]\n\"ball.Q\" = [-0.25, -0.5]\n",
    ));
    let edited = run(&sphere(-0.5 * q, Some("ball"), "[load_path]\nfactors = [0.5, 1.0]\nsubsteps = 2\n"));
    let steps = own["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    for (k, want) in [-0.25, -0.375, -0.5].into_iter().enumerate() {
        assert_eq!(steps[k]["loads"]["ball.Q"].as_f64(), Some(want), "step {k}");
        let named =
            |s: &serde_json::Value| ["V", "Ux", "Uy"].map(|x| s["extras"][format!("ball.{x}")].as_f64().unwrap());
        close(named(&steps[k]), named(&edited["steps"][k]), &format!("step {k}"));
    }
    assert_eq!(own["load_path"]["loads"]["ball.Q"], serde_json::json!([-0.25, -0.5]));
}

/// `[load_path.loads]` errors name the field and value: a name no load has (listing the
/// known ones, prefixed by the obstacle's name when it has one), a list of the wrong length, a
/// non-finite entry, and a list that takes a load where its plugin refuses it (F < 0).
#[test]
fn bad_load_lists_are_rejected_naming_the_field() {
    let with = |name: Option<&str>, loads: &str| {
        sphere(0.045, name, &format!("[load_path]\nfactors = [0.0, 1.0]\n[load_path.loads]\n{loads}\n"))
    };
    assert_rejected(&with(None, "P = [0.0, 1.0]"), &["load_path.loads.P = \"P\"", "known: F, Q"]);
    assert_rejected(&with(Some("ball"), "Q = [0.0, 1.0]"), &["load_path.loads.Q", "known: ball.F, ball.Q"]);
    assert_rejected(&with(None, "Q = [0.0, 1.0, 2.0]"), &["load_path.loads.Q = 3 entries", "load_path.factors (2)"]);
    assert_rejected(&with(None, "Q = [0.0, nan]"), &["load_path.loads.Q[1] = NaN", "finite"]);
    assert_rejected(&with(None, "F = [1.0, -1.0]"), &["load_path.factors[1]", "obstacle.F"]);
}

/// The punch of the default scene (paraboloid, R = 5) pressed by F = 0.5 and pulled by
/// Q = [q, 0] (Coulomb, μ = 0.3) on the box of [`sphere`], solved by uzawa.
fn punch(q: f64, path: &str) -> String {
    let sphere = sphere(q, None, path);
    let (head, rest) = sphere.split_once("[obstacle]\n").unwrap();
    let (_, tail) = rest.split_once("[solver]").unwrap();
    format!(
        "{head}[obstacle]\ntype = \"rigid_punch\"\nF = 0.5\nQ = [{q}, 0.0]\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n\
         zone = {{ all = [ {{ group = \"zmin\" }}, {{ disc = {{ center = [0.0, 0.0], radius = 0.8 }} }} ] }}\n\
         friction = {{ type = \"coulomb\", mu = 0.3 }}\n[solver]{tail}"
    )
}

/// The punches name `F` and `Q` as loads of their own (theory §8.2, §11.2): pressing without
/// pulling, the first step of "press, then pull" is the scene with Q edited to 0 by hand (the
/// extras U, Ux, Uy to 1e-12 of their size), the second pulls along +x; a name no load has is
/// refused listing the punch's.
#[test]
fn a_punch_pressed_then_pulled_by_its_own_factors() {
    let q = 0.075;
    let pressed = run(&punch(q, "[load_path]\nfactors = [1.0, 1.0]\n[load_path.loads]\nQ = [0.0, 1.0]\n"));
    let by_hand = run(&punch(0.0, ""));
    let extras = |s: &serde_json::Value| ["U", "Ux", "Uy"].map(|k| s["extras"][k].as_f64().unwrap());
    close(extras(&pressed["steps"][0]), extras(&by_hand), "Q at factor 0");
    assert_eq!(pressed["steps"][1]["loads"]["Q"].as_f64(), Some(1.0));
    assert!(extras(&pressed["steps"][1])[1] > 0.0, "pulled along +x: {:?}", extras(&pressed["steps"][1]));
    let bad = punch(q, "[load_path]\nfactors = [0.0, 1.0]\n[load_path.loads]\nP = [0.0, 1.0]\n");
    assert_rejected(&bad, &["load_path.loads.P = \"P\"", "known: F, Q"]);
}
