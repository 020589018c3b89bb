//! Bad obstacle input (issue 12): each a clear error naming the field and the value, and
//! `saddle run` writes nothing — both or neither of a sphere's `F` and `V`, a zero `direction`,
//! duplicate or missing names with several obstacles, a zone node inside the sphere at the
//! reference configuration, a tilting punch loaded outside its zone, and bad friction input on
//! every punch (theory §8.3).

mod common;
use common::*;

/// The small default scene with its obstacle table replaced by `obstacles` (TOML text).
fn scene(obstacles: &str) -> String {
    let mut t = small_johnson();
    t.remove("obstacle");
    format!("{}\n{obstacles}", toml::to_string(&t).unwrap())
}

const ZONE: &str = "zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }";

fn sphere(fields: &str) -> String {
    scene(&format!("[obstacle]\ntype = \"rigid_sphere\"\ncenter = [0.0, 0.0, -5.0]\nR = 5.0\n{fields}\n{ZONE}\n"))
}

#[test]
fn sphere_needs_exactly_one_of_force_and_displacement() {
    assert_rejected(&sphere("direction = [0.0, 0.0, 1.0]\nF = 0.3\nV = 0.01"), &["obstacle.F", "obstacle.V", "0.01"]);
    assert_rejected(&sphere("direction = [0.0, 0.0, 1.0]"), &["obstacle.F", "missing"]);
}

#[test]
fn a_zero_direction_is_refused() {
    assert_rejected(&sphere("direction = [0.0, 0.0, 0.0]\nF = 0.3"), &["obstacle.direction", "[0, 0, 0]"]);
}

#[test]
fn a_zone_node_inside_the_sphere_is_refused_with_the_node() {
    // the centre 4.9 below the face: the face cuts the sphere
    let text = sphere("direction = [0.0, 0.0, 1.0]\nF = 0.3")
        .replace("center = [0.0, 0.0, -5.0]", "center = [0.0, 0.0, -4.9]");
    assert_rejected(&text, &["obstacle.center", "-4.9", "inside the sphere", "node", "obstacle.R"]);
}

#[test]
fn a_tilting_punch_loaded_outside_its_zone_is_refused() {
    let text = scene(&format!(
        "[obstacle]\ntype = \"tilting_punch\"\nF = 0.3\nat = [0.7, 0.0]\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n"
    ));
    assert_rejected(&text, &["obstacle.at", "0.7", "tip"]);
}

#[test]
fn several_obstacles_need_unique_names() {
    let punch = |name: &str| {
        format!(
            "[[obstacle]]\n{name}type = \"rigid_punch\"\nF = 0.1\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n"
        )
    };
    let dup = scene(&format!("{}{}", punch("name = \"a\"\n"), punch("name = \"a\"\n")));
    assert_rejected(&dup, &["obstacle[1].name", "\"a\"", "unique"]);
    let missing = scene(&format!("{}{}", punch("name = \"a\"\n"), punch("")));
    assert_rejected(&missing, &["obstacle[1].name"]);
}

/// Bad friction input on each punch type, written as an array of tables (`obstacle[0]`): a
/// negative or NaN μ, a negative g, Q without a law, Q and W together — each error naming the
/// field path and the value.
#[test]
fn punches_with_bad_friction_input_are_refused_naming_field_and_value() {
    let punch = |kind: &str, extra: &str| {
        scene(&format!("[[obstacle]]\n{kind}\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n{extra}\n"))
    };
    for kind in [
        "type = \"rigid_punch\"\nF = 0.3",
        "type = \"rigid_punch_displacement\"\nU = 0.01",
        "type = \"tilting_punch\"\nF = 0.3",
    ] {
        let law = |l: &str| format!("friction = {{ type = {l} }}");
        assert_rejected(&punch(kind, "Q = [0.1, 0.0]"), &["obstacle[0].Q", "[0.1, 0]", "obstacle[0].friction"]);
        assert_rejected(&punch(kind, &law("\"coulomb\", mu = -0.3")), &["obstacle[0].friction.mu", "-0.3"]);
        assert_rejected(&punch(kind, &law("\"coulomb\", mu = nan")), &["obstacle[0].friction.mu", "NaN"]);
        assert_rejected(&punch(kind, &law("\"tresca\", g = -1.0")), &["obstacle[0].friction.g", "-1"]);
        let both = format!("{}\nQ = [0.1, 0.0]\nW = [0.0, 0.2]", law("\"tresca\", g = 1.0"));
        assert_rejected(&punch(kind, &both), &["obstacle[0].Q", "[0.1, 0]", "obstacle[0].W"]);
    }
}

/// A friction law on an obstacle whose rows have no tangent plane: the contact face's
/// tangential components are held by a roller support (`components = ["x", "y"]` on `zmin`), so
/// no node can slip; the error names the law's field, its type and the zone, on a punch and on
/// the sphere (theory §8.3). Newton solves (the scene's uzawa would first ask for
/// `extra_metric > 0`, an error of its own).
#[test]
fn friction_where_no_node_can_slip_is_refused_naming_the_law() {
    let rollers = "[[dirichlet]]\non = { group = \"zmin\" }\ncomponents = [\"x\", \"y\"]\n";
    let newton = |text: String| text.replacen("type = \"uzawa\"", "type = \"newton\"", 1);
    let punch = newton(scene(&format!(
        "{rollers}\n[obstacle]\ntype = \"rigid_punch\"\nF = 0.3\n{ZONE}\ngap = {{ type = \"paraboloid\", R = 5.0 }}\n\
         friction = {{ type = \"coulomb\", mu = 0.3 }}\n"
    )));
    assert_rejected(&punch, &["obstacle.friction", "coulomb", "obstacle.zone", "can slip"]);
    let sphere = newton(sphere("direction = [0.0, 0.0, 1.0]\nF = 0.3\nfriction = { type = \"tresca\", g = 0.1 }"))
        .replace("[obstacle]", &format!("{rollers}\n[obstacle]"));
    assert_rejected(&sphere, &["obstacle.friction", "tresca", "obstacle.zone", "can slip"]);
}
