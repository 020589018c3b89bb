//! Bad obstacle input (issue 12): each a clear error naming the field and the value, and
//! `saddle run` writes nothing — both or neither of a sphere's `F` and `V`, a zero `direction`,
//! duplicate or missing names with several obstacles, a zone node inside the sphere at the
//! reference configuration, and a tilting punch loaded outside its zone.

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
