//! Friction on the punches (theory §8.3): the kit on `rigid_punch`, `rigid_punch_displacement`
//! and `tilting_punch` with Tresca's and Coulomb's laws under Q and W, their rows against the
//! closed form (the axis is e₃: tangential rows u₁ − Ux, u₂ − Uy), the normal rows unchanged by
//! friction, and bad input named by field and value on each punch type.

mod common;

use common::*;
use saddle_contact::{Coulomb, Paraboloid, RigidPunch, RigidPunchDisplacement, TiltingPunch, Tresca, check_all};
use saddle_core::{AdmissibleDisplacements, FrictionLaw, ParameterError};

fn tresca(g: f64) -> Box<dyn FrictionLaw> {
    Box::new(Tresca { g })
}

fn coulomb(mu: f64) -> Box<dyn FrictionLaw> {
    Box::new(Coulomb { mu })
}

fn pushed() -> RigidPunch {
    RigidPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap()
}

fn moved() -> RigidPunchDisplacement {
    RigidPunchDisplacement::new(0.004, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap()
}

fn tilting() -> TiltingPunch {
    TiltingPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap().at([0.2, 0.1]).unwrap()
}

/// Every punch with each law, pulled by Q and moved by W, passes the kit (rows the
/// linearisation of the gap, load and resultants, the law's projection and derivative, the rows
/// at a factor against the scaled punch discretised again). (Not the displacement-controlled
/// punch under Q: its first extra is then Ux, and the kit takes the report's `force` for the
/// resultant on the first extra; the sphere moved by V and pulled by Q is in the same case.)
#[test]
fn the_kit_passes_on_every_punch_with_friction() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let (q, w) = (Some([0.05, 0.01]), Some([0.003, -0.002]));
    let mut seed = 10;
    for law in [tresca(0.2), coulomb(0.4)] {
        let ks: Vec<Box<dyn AdmissibleDisplacements>> = vec![
            Box::new(RigidPunch { Q: q, ..pushed().with_friction(law.clone()) }),
            Box::new(RigidPunch { W: w, ..pushed().with_friction(law.clone()) }),
            Box::new(RigidPunchDisplacement { W: w, ..moved().with_friction(law.clone()) }),
            Box::new(TiltingPunch { Q: q, ..tilting().with_friction(law.clone()) }),
            Box::new(TiltingPunch { W: w, ..tilting().with_friction(law.clone()) }),
            Box::new(RigidPunch { ..pushed().with_friction(law.clone()) }),
        ];
        for k in &ks {
            seed += 1;
            check_all(k.as_ref(), &m, &d, seed, 0.01).unwrap_or_else(|e| panic!("{k:?}: {e}"));
        }
    }
}

/// The extras and loads by name: `Ux`, `Uy` after the punch's own under Q, none under W; the
/// load names a path may scale, only when Q or W is given (a frictionless punch keeps the one
/// factor of the whole load, as before).
#[test]
fn extras_loads_and_load_names() {
    let q = Some([0.05, 0.01]);
    let k = RigidPunch { Q: q, ..pushed().with_friction(tresca(0.2)) };
    assert_eq!(
        (k.extra_names(), k.load(), k.load_names()),
        (names(&["U", "Ux", "Uy"]), vec![0.3, 0.05, 0.01], names(&["F", "Q"]))
    );
    let k = RigidPunchDisplacement { W: Some([0.1, 0.0]), ..moved().with_friction(tresca(0.2)) };
    assert_eq!((k.extra_names(), k.load(), k.load_names()), (names(&[]), vec![], names(&["U", "W"])));
    let k = TiltingPunch { Q: q, ..tilting().with_friction(tresca(0.2)) };
    assert_eq!(k.extra_names(), names(&["U", "slope_x1", "slope_x2", "Ux", "Uy"]));
    assert_eq!(k.load(), [0.3, 0.3 * 0.2, 0.3 * 0.1, 0.05, 0.01]);
    assert!(pushed().load_names().is_empty() && moved().load_names().is_empty() && tilting().load_names().is_empty());
    assert!(pushed().with_friction(tresca(0.2)).load_names().is_empty());
}

fn names(n: &[&str]) -> Vec<String> {
    n.iter().map(|s| s.to_string()).collect()
}

/// The rows of the punch pulled by Q, in closed form: each node's normal row is the
/// frictionless punch's (G, c and U's entry bit for bit, 0 on Ux, Uy), followed by u₁ − Ux and
/// u₂ − Uy (G = 1 on the node's u₁, u₂; H = (0, −1, 0), (0, 0, −1); c = 0); under W = (a, b)
/// the tangential offsets are −a and −b. The weight is the node's third of the bottom facets
/// around it (right triangles of legs 0.25, area 1/32: count/96).
#[test]
fn rows_in_closed_form() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let free = pushed().discretise(&m, &d, "obstacle").unwrap();
    let k = RigidPunch { Q: Some([0.05, 0.0]), ..pushed().with_friction(tresca(0.1)) };
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!((rows.n_rows(), rows.n_extras), (3 * free.n_rows(), 3));
    assert_eq!(rows.friction.blocks.len(), free.n_rows());
    for (i, b) in rows.friction.blocks.iter().enumerate() {
        let n = free.node[i];
        assert_eq!((b.normal, b.tangent, rows.node[b.normal]), (3 * i, 3 * i + 1, n));
        assert_eq!(rows.row(b.normal), free.row(i));
        assert_eq!(rows.offset[b.normal], free.offset[i]);
        assert_eq!(rows.extra_row(b.normal), [-1.0, 0.0, 0.0]);
        for (k, t) in [b.tangent, b.tangent + 1].into_iter().enumerate() {
            assert_eq!(rows.row(t), (&[d.free(n, k).unwrap()][..], &[1.0][..]));
            let mut h = [0.0, 0.0, 0.0];
            h[1 + k] = -1.0;
            assert_eq!(rows.extra_row(t), h);
            assert_eq!(rows.offset[t], 0.0);
        }
        let facets = m.boundary.iter().filter(|f| f.contains(&n)).count();
        assert!((b.weight - facets as f64 / 96.0).abs() < 1e-15, "{} for {facets} facets", b.weight);
    }
    let k = RigidPunchDisplacement { W: Some([0.003, -0.002]), ..moved().with_friction(coulomb(0.3)) };
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let plain = moved().discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.n_extras, 0);
    for (i, b) in rows.friction.blocks.iter().enumerate() {
        assert_eq!(rows.offset[b.normal], plain.offset[i]);
        assert_eq!([rows.offset[b.tangent], rows.offset[b.tangent + 1]], [-0.003, 0.002]);
    }
}

/// The tilting punch's rows: the normal rows those of the frictionless punch (with U's and the
/// slopes' entries bit for bit), the tangential rows without entries on U and the slopes.
#[test]
fn tilting_rows_keep_the_tilt_on_the_normal_rows() {
    let (m, d) = (mesh(), dofs(&mesh()));
    let free = tilting().discretise(&m, &d, "obstacle").unwrap();
    let rows = TiltingPunch { Q: Some([0.01, 0.02]), ..tilting().with_friction(coulomb(0.3)) }
        .discretise(&m, &d, "obstacle")
        .unwrap();
    for (i, b) in rows.friction.blocks.iter().enumerate() {
        assert_eq!(rows.row(b.normal), free.row(i));
        assert_eq!(&rows.extra_row(b.normal)[..3], free.extra_row(i));
        assert_eq!(rows.extra_row(b.tangent), [0.0, 0.0, 0.0, -1.0, 0.0]);
        assert_eq!(rows.extra_row(b.tangent + 1), [0.0, 0.0, 0.0, 0.0, -1.0]);
    }
}

/// Bad input on each punch type: a negative or non-finite μ or g (`obstacle.friction.mu`,
/// `.g`), Q without a law, Q and W together, each error naming the field and the value.
#[test]
fn bad_friction_input_is_named_on_every_punch() {
    let check = |k: &dyn AdmissibleDisplacements, field: &str, value: &str| {
        let e: ParameterError = k.validate("obstacle").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), (field, value), "{e}");
    };
    let both = (Some([0.1, 0.0]), Some([0.0, 0.2]));
    for (law, field, value) in [
        (coulomb(-0.2), "obstacle.friction.mu", "-0.2"),
        (coulomb(f64::NAN), "obstacle.friction.mu", "NaN"),
        (tresca(-1.0), "obstacle.friction.g", "-1"),
        (tresca(f64::INFINITY), "obstacle.friction.g", "inf"),
    ] {
        check(&pushed().with_friction(law.clone()), field, value);
        check(&moved().with_friction(law.clone()), field, value);
        check(&tilting().with_friction(law.clone()), field, value);
    }
    check(&RigidPunch { Q: Some([0.1, 0.0]), ..pushed() }, "obstacle.Q", "[0.1, 0]");
    check(&RigidPunchDisplacement { Q: Some([0.1, 0.0]), ..moved() }, "obstacle.Q", "[0.1, 0]");
    check(&TiltingPunch { W: Some([0.0, 0.5]), ..tilting() }, "obstacle.W", "[0, 0.5]");
    check(&RigidPunch { Q: both.0, W: both.1, ..pushed().with_friction(tresca(1.0)) }, "obstacle.Q", "[0.1, 0]");
    check(
        &RigidPunchDisplacement { Q: both.0, W: both.1, ..moved().with_friction(tresca(1.0)) },
        "obstacle.Q",
        "[0.1, 0]",
    );
    check(&TiltingPunch { Q: both.0, W: both.1, ..tilting().with_friction(tresca(1.0)) }, "obstacle.Q", "[0.1, 0]");
    check(&RigidPunch { W: Some([f64::NAN, 0.0]), ..pushed().with_friction(tresca(1.0)) }, "obstacle.W[0]", "NaN");
    // the message names the law's field to give
    let e = RigidPunch { Q: Some([0.1, 0.0]), ..pushed() }.validate("obstacle").unwrap_err();
    assert!(e.to_string().contains("obstacle.friction"), "{e}");
}
