//! Friction on the rigid sphere (theory §8.3): the kit with Tresca's law (prescribed and
//! force-controlled tangential motion), the rows of a node against their closed form, the normal
//! rows unchanged by friction, bad input named by field and value, and a broken law failing the
//! kit's friction check.

mod common;

use common::*;
use saddle_contact::conformance::check_friction;
use saddle_contact::{Coulomb, RigidSphere, Tresca, check_all};
use saddle_core::{AdmissibleDisplacements, FrictionLaw, ParameterError};
use serde::{Deserialize, Serialize};

const CENTER: [f64; 3] = [-0.5, -0.75, -3.0];

fn tresca(g: f64) -> Box<dyn FrictionLaw> {
    Box::new(Tresca { g })
}

fn moved(v: f64) -> RigidSphere {
    RigidSphere::moved(CENTER, 3.0, [3.0, 0.0, 4.0], v, disc(0.5))
}

fn pushed() -> RigidSphere {
    RigidSphere::pushed(CENTER, 3.0, [3.0, 0.0, 4.0], 0.3, disc(0.5))
}

/// Coulomb's law passes the kit (its projection onto the disc of radius μ λ_n and the
/// derivative in t and λ_n against central differences), prescribed and force-controlled.
#[test]
fn the_kit_passes_with_coulomb_prescribed_and_forced() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let coulomb = || Box::new(Coulomb { mu: 0.4 }) as Box<dyn FrictionLaw>;
    let w = RigidSphere { W: Some([0.003, -0.002]), ..moved(0.004).with_friction(coulomb()) };
    check_all(&w, &m, &d, 5, 0.01).unwrap();
    let q = RigidSphere { Q: Some([0.05, 0.01]), ..pushed().with_friction(coulomb()) };
    check_all(&q, &m, &d, 6, 0.01).unwrap();
}

#[test]
fn the_kit_passes_with_tresca_prescribed_and_forced() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let w = RigidSphere { W: Some([0.003, -0.002]), ..moved(0.004).with_friction(tresca(0.2)) };
    check_all(&w, &m, &d, 3, 0.01).unwrap();
    let q = RigidSphere { Q: Some([0.05, 0.01]), ..pushed().with_friction(tresca(0.2)) };
    check_all(&q, &m, &d, 4, 0.01).unwrap();
    assert_eq!(q.extra_names(), ["V", "Ux", "Uy"]);
    assert_eq!(q.load(), [0.3, 0.05, 0.01]);
}

/// The normal rows of a sphere with friction (and no tangential motion) are the frictionless
/// rows bit for bit; each is followed by two tangential rows; the frictionless sphere has none.
#[test]
fn friction_adds_tangential_rows_and_keeps_the_normal_rows() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let free = pushed().discretise(&m, &d, "obstacle").unwrap();
    assert!(!free.has_friction());
    let with = pushed().with_friction(tresca(0.1)).discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(with.n_rows(), 3 * free.n_rows());
    assert_eq!(with.friction.blocks.len(), free.n_rows());
    for (i, b) in with.friction.blocks.iter().enumerate() {
        assert_eq!((b.normal, b.tangent), (3 * i, 3 * i + 1));
        assert_eq!(with.row(b.normal), free.row(i));
        assert_eq!(with.extra_row(b.normal), free.extra_row(i));
        assert_eq!(with.offset[b.normal], free.offset[i]);
    }
}

/// The tangent frame of the node (0.25, 0.25, 0) in closed form: n = (3, 4, 12)/13 (see the
/// sphere's tests), d = (3, 0, 4)/5, so e₁ = (x₁ − (x₁·d)d)/|·| = (16, 0, −12)/20 = (0.8, 0, −0.6),
/// t₁ = e₁ − (e₁·n)n normalised, t₂ = n × t₁; the tangential rows are t_k on the node's dofs and
/// −t_k·d on V.
#[test]
fn tangential_rows_in_closed_form() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let k = pushed().with_friction(tresca(0.1));
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let node = node_at(&m, 0.25, 0.25);
    let b = rows.friction.blocks.iter().find(|b| rows.node[b.normal] == node).unwrap();
    let n = [3.0 / 13.0, 4.0 / 13.0, 12.0 / 13.0];
    let e1 = [0.8, 0.0, -0.6];
    let en: f64 = (0..3).map(|c| e1[c] * n[c]).sum();
    let t1u: Vec<f64> = (0..3).map(|c| e1[c] - en * n[c]).collect();
    let len = t1u.iter().map(|x| x * x).sum::<f64>().sqrt();
    let t1: Vec<f64> = t1u.iter().map(|x| x / len).collect();
    let t2 = [n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]];
    let dir = [0.6, 0.0, 0.8];
    for (r, t) in [(b.tangent, t1.as_slice()), (b.tangent + 1, &t2[..])] {
        let (cols, vals) = rows.row(r);
        for (c, tc) in t.iter().enumerate() {
            let j = d.free(node, c).unwrap();
            let v = cols.iter().position(|&x| x == j).map_or(0.0, |p| vals[p]);
            assert!((v - tc).abs() < 1e-15, "row {r} component {c}: {v} against {tc}");
        }
        let td: f64 = (0..3).map(|c| t[c] * dir[c]).sum();
        assert!((rows.extra_row(r)[0] + td).abs() < 1e-15);
        assert_eq!(rows.offset[r], 0.0);
    }
    // the weight is the node's third of the bottom facets around it, all facing the sphere: the
    // coarse mesh's bottom facets at this node are right triangles of legs 0.25 (area 1/32);
    // a node in the interior of the bottom face has 6 of them on the mesh's diagonal pattern
    let facets = m.boundary.iter().filter(|f| f.contains(&node)).count();
    assert!((b.weight - facets as f64 / 96.0).abs() < 1e-15, "{} for {facets} facets", b.weight);
}

#[test]
fn bad_friction_input_is_named_by_field_and_value() {
    let check = |k: RigidSphere, field: &str, value: &str| {
        let e: ParameterError = k.validate("obstacle").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), (field, value), "{e}");
    };
    check(pushed().with_friction(tresca(-1.0)), "obstacle.friction.g", "-1");
    check(pushed().with_friction(tresca(f64::NAN)), "obstacle.friction.g", "NaN");
    check(pushed().with_friction(Box::new(Coulomb { mu: -0.2 })), "obstacle.friction.mu", "-0.2");
    check(pushed().with_friction(Box::new(Coulomb { mu: f64::INFINITY })), "obstacle.friction.mu", "inf");
    check(RigidSphere { Q: Some([0.1, 0.0]), ..pushed() }, "obstacle.Q", "[0.1, 0]");
    check(
        RigidSphere { W: Some([f64::INFINITY, 0.0]), ..moved(0.0).with_friction(tresca(1.0)) },
        "obstacle.W[0]",
        "inf",
    );
    check(
        RigidSphere { Q: Some([0.1, 0.0]), W: Some([0.0, 0.2]), ..pushed().with_friction(tresca(1.0)) },
        "obstacle.Q",
        "[0.1, 0]",
    );
    // a scene table: the law's unknown fields, and friction on an obstacle without tangential rows
    let sphere = "type = \"rigid_sphere\"\ncenter = [0.0, 0.0, -5.0]\nR = 5.0\ndirection = [0.0, 0.0, 1.0]\nF = 0.3\n\
                  zone = { group = \"zmin\" }\n";
    let k: Box<dyn AdmissibleDisplacements> =
        toml::from_str(&format!("{sphere}friction = {{ type = \"tresca\", g = 0.1 }}")).unwrap();
    assert_eq!(k.extra_names(), ["V"]);
    let e = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&format!(
        "{sphere}friction = {{ type = \"tresca\", g = 0.1, mu = 0.3 }}"
    ))
    .unwrap_err();
    assert!(e.to_string().contains("mu"), "{e}");
    // the punches take friction too (crates/contact/tests/punch_friction.rs): a table with a law
    // reads, and its Q without a law is refused naming the field
    let punch = "type = \"rigid_punch\"\nF = 0.3\nzone = { group = \"zmin\" }\ngap = { type = \"flat\" }\n";
    let k: Box<dyn AdmissibleDisplacements> =
        toml::from_str(&format!("{punch}friction = {{ type = \"tresca\", g = 0.1 }}\nQ = [0.01, 0.0]")).unwrap();
    assert_eq!(k.extra_names(), ["U", "Ux", "Uy"]);
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(&format!("{punch}Q = [0.01, 0.0]")).unwrap();
    assert_eq!(k.validate("obstacle").unwrap_err().field, "obstacle.Q");
}

/// A law whose "projection" is the identity: not the disc's projection, caught by the kit.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct NoProjection {
    g: f64,
}

#[typetag::serde(name = "test_no_projection")]
impl FrictionLaw for NoProjection {
    fn validate(&self, _: &str) -> Result<(), ParameterError> {
        Ok(())
    }
    fn radius(&self, weight: f64, _: f64) -> f64 {
        self.g * weight
    }
    fn radius_slope(&self, _: f64) -> f64 {
        0.0
    }
    fn project(&self, _: f64, _: f64, t: [f64; 2]) -> [f64; 2] {
        t
    }
}

#[test]
fn a_broken_law_fails_the_friction_check() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let k = pushed().with_friction(Box::new(NoProjection { g: 0.1 }));
    let e = check_friction(&k, &m, &d, 1).unwrap_err();
    assert_eq!(e.check, "friction", "{e}");
    check_friction(&pushed().with_friction(tresca(0.1)), &m, &d, 1).unwrap();
}
