//! The tilting punch (theory §8) on the coarse default scene: the kit, rows and gap by hand, the
//! load and moment balance, parameter and tipping errors, the report, broken copies, TOML.

mod common;

use common::*;
use saddle_contact::{EllipticParaboloid, Flat, GapShape, Paraboloid, TiltingPunch, check_all};
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, ParameterError, Region, SceneError, TetMesh,
};
use serde::{Deserialize, Serialize};

/// The elliptic gap of `common::shapes`, centre (pivot) (0.25, −0.125).
fn elliptic() -> Box<dyn GapShape> {
    Box::new(EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.25, c2: -0.125 })
}

fn row_of(rows: &ConstraintRows, m: &TetMesh, x1: f64, x2: f64) -> usize {
    rows.node.iter().position(|&n| n == node_at(m, x1, x2)).unwrap()
}

#[test]
fn the_kit_passes_for_every_gap_shape_and_point_of_action() {
    let (m, d) = (mesh(), dofs(&mesh()));
    // the disc of radius 0.5 on the 0.25 grid: its hull is the diamond |x₁| + |x₂| ≤ 0.5
    for gap in shapes() {
        for at in [None, Some([0.2, 0.1]), Some([-0.125, -0.25])] {
            let mut k = TiltingPunch::new(0.3, disc(0.5), gap.clone()).unwrap();
            k.at = at;
            for (seed, scale) in [(1, 0.01), (2, 0.003), (3, 0.1)] {
                check_all(&k, &m, &d, seed, scale).unwrap_or_else(|e| panic!("{k:?}, seed {seed}: {e}"));
            }
        }
    }
}

#[test]
fn rows_and_gap_by_hand() {
    let m = mesh();
    let d = dofs(&m);
    let k = TiltingPunch::new(0.3, disc(0.5), elliptic()).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.node, bottom_nodes_in_disc(&m, 0.5));
    assert_eq!(rows.n_extras, 3);
    assert!(rows.warnings.is_empty(), "{:?}", rows.warnings);
    // node (0.25, 0.25): x − c = (0, 0.375), φ = 0 + 0.375²/16
    let r = row_of(&rows, &m, 0.25, 0.25);
    let n = node_at(&m, 0.25, 0.25);
    assert_eq!(rows.row(r), (&[d.free(n, 2).unwrap()][..], &[1.0][..]));
    assert_eq!(rows.extra_row(r), &[-1.0, -0.0, -0.375]);
    assert_eq!(rows.offset[r], 0.0087890625);
    // node (−0.5, 0): x − c = (−0.75, 0.125), φ = 0.75²/4 + 0.125²/16
    let r = row_of(&rows, &m, -0.5, 0.0);
    assert_eq!(rows.extra_row(r), &[-1.0, 0.75, -0.125]);
    assert_eq!(rows.offset[r], 0.1416015625);
    // gap() with u₃ = 0.01 there and (U, slope_x1, slope_x2) = (0.05, 0.1, −0.2):
    // w = 0.05 + 0.1·(−0.75) − 0.2·0.125 = −0.05, g = 0.01 + 0.1416015625 + 0.05
    let n = node_at(&m, -0.5, 0.0);
    let mut u = vec![0.0; d.n_free];
    u[d.free(n, 2).unwrap()] = 0.01;
    u[d.free(n, 0).unwrap()] = 0.5; // u₁ does not enter the vertical gap
    let mut g = vec![0.0; rows.n_rows()];
    k.gap(&m, &d, &rows, &u, &[0.05, 0.1, -0.2], &mut g);
    assert!((g[r] - 0.2016015625).abs() < 1e-15, "{}", g[r]);
    // the rows give the same (the gap is affine)
    let mut gr = vec![0.0; rows.n_rows()];
    rows.gap(&u, &[0.05, 0.1, -0.2], &mut gr);
    assert!((gr[r] - 0.2016015625).abs() < 1e-15, "{}", gr[r]);
}

#[test]
fn at_defaults_to_the_gap_centre_and_the_load_is_f_times_w_of_a() {
    let k = TiltingPunch::new(0.3, disc(0.5), elliptic()).unwrap();
    assert_eq!(k.at, None);
    assert_eq!(k.pivot(), [0.25, -0.125]);
    assert_eq!(k.point_of_action(), [0.25, -0.125]);
    assert_eq!(k.extra_names(), vec!["U", "slope_x1", "slope_x2"]);
    assert_eq!(k.load(), vec![0.3, 0.0, 0.0]);
    // F at (0.2, 0.1): f = F (1, 0.2 − 0.25, 0.1 + 0.125)
    let k = k.at([0.2, 0.1]).unwrap();
    assert_eq!(k.point_of_action(), [0.2, 0.1]);
    let f = k.load();
    let expected = [0.3, -0.015, 0.0675];
    assert!(f.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15), "{f:?}");
}

#[test]
fn balanced_multipliers_satisfy_force_and_moment_balance() {
    let m = mesh();
    let d = dofs(&m);
    // pivot at the origin, F = 0.3 at (0.25, 0): half the force at (0.5, 0), half at (0, 0)
    let k = TiltingPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap().at([0.25, 0.0]).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[row_of(&rows, &m, 0.5, 0.0)] = 0.15;
    lambda[row_of(&rows, &m, 0.0, 0.0)] = 0.15;
    // Hᵀλ = −f (the KKT condition on the extras, theory §8)
    let (mut fu, mut fv) = (vec![0.0; d.n_free], vec![0.0; 3]);
    rows.add_transpose(&lambda, &mut fu, &mut fv);
    let f = k.load();
    assert_eq!(f, vec![0.3, 0.075, 0.0]);
    assert!(fv.iter().zip(&f).all(|(h, f)| (h + f).abs() < 1e-15), "Hᵀλ = {fv:?}, f = {f:?}");
    let r = k.report(&m, &rows, &[0.001, 0.002, 0.003], &lambda);
    assert!((r.get("force").unwrap() - 0.3).abs() < 1e-15);
    assert!((r.get("moment_x1").unwrap() - 0.075).abs() < 1e-15);
    assert_eq!(r.get("moment_x2"), Some(0.0));
    // the same λ does not balance the force at the pivot: the moment about c is off by F·0.25
    let k0 = TiltingPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap();
    let f0 = k0.load();
    assert_eq!(f0, vec![0.3, 0.0, 0.0]);
    assert!((fv[0] + f0[0]).abs() < 1e-15 && (fv[1] + f0[1] + 0.075).abs() < 1e-15, "{fv:?}");
}

#[test]
fn report_by_hand() {
    let m = mesh();
    let d = dofs(&m);
    let k = TiltingPunch::new(0.3, disc(0.5), elliptic()).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[row_of(&rows, &m, 0.0, 0.0)] = 0.2;
    lambda[row_of(&rows, &m, -0.25, 0.0)] = 0.1;
    lambda[row_of(&rows, &m, 0.0, 0.25)] = 1e-12; // below the contact-set threshold
    let r = k.report(&m, &rows, &[0.0083, -0.01, 0.02], &lambda);
    assert_eq!((r.get("U"), r.get("slope_x1"), r.get("slope_x2")), (Some(0.0083), Some(-0.01), Some(0.02)));
    assert!((r.get("force").unwrap() - 0.300000000001).abs() < 1e-15);
    // Σλ (x₁ − c₁) = 0.2·(−0.25) + 0.1·(−0.5) + 1e-12·(−0.25)
    assert!((r.get("moment_x1").unwrap() + 0.10000000000025).abs() < 1e-15);
    // Σλ (x₂ − c₂) = 0.2·0.125 + 0.1·0.125 + 1e-12·0.375
    assert!((r.get("moment_x2").unwrap() - 0.037500000000375).abs() < 1e-15);
    assert_eq!(r.contact_nodes, 2);
    // farthest contact node from the pivot (0.25, −0.125): (−0.25, 0)
    assert!((r.contact_radius - 0.5f64.hypot(0.125)).abs() < 1e-15, "{}", r.contact_radius);
    // contact at the centre only: inside the zone, no warning, radius |c| from the pivot
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[row_of(&rows, &m, 0.0, 0.0)] = 0.3;
    let r = k.report(&m, &rows, &[0.0; 3], &lambda);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert!((r.contact_radius - 0.25f64.hypot(0.125)).abs() < 1e-15, "{}", r.contact_radius);
    // contact at (0.5, 0), next to (0.75, 0) outside the disc: the rim warning of the rigid punch
    lambda[row_of(&rows, &m, 0.5, 0.0)] = 0.05;
    let r = k.report(&m, &rows, &[0.0; 3], &lambda);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(
        r.warnings[0].contains("rim of obstacle.zone") && r.warnings[0].contains("(0.5, 0, 0)"),
        "{:?}",
        r.warnings
    );
    // a flat punch's rim is its edge: no warning
    let flat = TiltingPunch::new(0.3, disc(0.5), Box::new(Flat::default())).unwrap();
    assert!(flat.report(&m, &rows, &[0.0; 3], &lambda).warnings.is_empty());
}

#[test]
fn parameters_name_the_field_and_the_value() {
    let k = |f| TiltingPunch::new(f, disc(0.5), Box::new(Paraboloid::new(5.0)));
    for (f, shown) in [(-0.3, "-0.3"), (f64::NAN, "NaN")] {
        let e = k(f).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.F", shown));
    }
    assert!(k(0.0).is_ok(), "F = 0: no load, the extras undetermined (theory §11.3)");
    let k = |f| k(f).unwrap();
    let e = k(0.3).at([0.1, f64::INFINITY]).unwrap_err();
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.at[1]", "inf"));
    let e = TiltingPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(-1.0))).unwrap_err();
    assert_eq!(e.field, "obstacle.gap.R");
}

#[test]
fn a_force_outside_the_zone_hull_tips_the_punch_over() {
    let m = mesh();
    let d = dofs(&m);
    let k = |at| TiltingPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap().at(at).unwrap();
    // (0.4, 0.2) is inside the zone's bounding box [−0.5, 0.5]² but outside the diamond
    // |x₁| + |x₂| ≤ 0.5 spanned by the disc's nodes
    for (at, shown) in [([0.4, 0.2], "[0.4, 0.2]"), ([0.0, -0.6], "[0, -0.6]"), ([3.0, 3.0], "[3, 3]")] {
        match k(at).discretise(&m, &d, "obstacle").unwrap_err() {
            SceneError::Parameter(ParameterError { field, value, requirement }) => {
                assert_eq!((field.as_str(), value.as_str()), ("obstacle.at", shown));
                assert!(requirement.contains("convex hull") && requirement.contains("tip over"), "{requirement}");
                assert!(
                    requirement.contains("obstacle.zone") && requirement.contains("13 contact nodes"),
                    "{requirement}"
                );
            }
            other => panic!("{other}"),
        }
    }
    // on the hull's edge and at its corner: balanced by the edge's nodes
    for at in [[0.25, 0.25], [0.5, 0.0], [-0.125, 0.375], [0.0, 0.0]] {
        let rows = k(at).discretise(&m, &d, "obstacle").unwrap();
        assert_eq!(rows.n_rows(), 13);
        check_all(&k(at), &m, &d, 4, 0.01).unwrap_or_else(|e| panic!("{at:?}: {e}"));
    }
    // the default point of action is the gap's centre: an apex off the zone tips it over too
    let gap = EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.6, c2: 0.0 };
    let err = TiltingPunch::new(0.3, disc(0.5), Box::new(gap)).unwrap().discretise(&m, &d, "obstacle").unwrap_err();
    match &err {
        SceneError::Parameter(p) => {
            assert_eq!(p.field, "obstacle.at");
            assert!(p.value.starts_with("[0.6, 0]") && p.value.contains("default"), "{}", p.value);
        }
        other => panic!("{other}"),
    }
}

#[test]
fn a_zone_on_one_line_is_an_error() {
    let m = mesh();
    let d = dofs(&m);
    // the bottom nodes with x₂ = 0 and |x₁| ≤ 0.5: five nodes on the x₁ axis
    let line = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.5, -0.01, -1.0], max: [0.5, 0.01, 1.0] },
    ]);
    let err = TiltingPunch::new(0.3, line, Box::new(Paraboloid::new(5.0)))
        .unwrap()
        .discretise(&m, &d, "obstacle")
        .unwrap_err();
    match &err {
        SceneError::Region { field, message } => {
            assert_eq!(field, "obstacle.zone");
            assert!(message.contains("5 contact nodes lie on one line"), "{message}");
        }
        other => panic!("{other}"),
    }
}

/// What is wrong with a [`BrokenTilt`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
enum Flaw {
    /// The rows' H column of slope_x2 has the wrong sign.
    Slope2Sign,
    /// The rows' H column of slope_x1 measures x₁ from 0 instead of the pivot (c₁ = 0.25).
    Slope1ArmFromOrigin,
}

/// The tilting punch with a deliberate flaw in its rows.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct BrokenTilt {
    punch: TiltingPunch,
    flaw: Flaw,
}

#[typetag::serde(name = "test_broken_tilting_punch")]
impl AdmissibleDisplacements for BrokenTilt {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.punch.validate(path)
    }
    fn extra_names(&self) -> Vec<String> {
        self.punch.extra_names()
    }
    fn load(&self) -> Vec<f64> {
        self.punch.load()
    }
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let mut rows = self.punch.discretise(mesh, dofs, path)?;
        for (i, &n) in rows.node.clone().iter().enumerate() {
            match self.flaw {
                Flaw::Slope2Sign => rows.extra[3 * i + 2] *= -1.0,
                Flaw::Slope1ArmFromOrigin => rows.extra[3 * i + 1] = -mesh.nodes[n][0],
            }
        }
        Ok(rows)
    }
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        self.punch.gap(mesh, dofs, rows, u, extras, out)
    }
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        self.punch.report(mesh, rows, extras, lambda)
    }
}

#[test]
fn broken_copies_fail_the_kit_on_gap_derivative() {
    let (m, d) = (mesh(), dofs(&mesh()));
    for (flaw, extra) in [(Flaw::Slope2Sign, "slope_x2"), (Flaw::Slope1ArmFromOrigin, "slope_x1")] {
        let k =
            BrokenTilt { punch: TiltingPunch::new(0.3, disc(0.5), elliptic()).unwrap().at([0.2, 0.1]).unwrap(), flaw };
        for seed in [1, 2, 3] {
            let e = check_all(&k, &m, &d, seed, 0.01).expect_err(&format!("{flaw:?} passed the kit"));
            assert_eq!(e.check, "gap_derivative", "{flaw:?}: {e}");
            assert!(e.message.starts_with(&format!("∂g/∂V along the extra `{extra}`")), "{e}");
        }
    }
}

#[test]
fn scene_tables_parse_and_unknown_fields_are_rejected() {
    let src = "type = \"tilting_punch\"\nF = 0.3\nat = [0.2, 0.1]\n\
               zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }\n\
               gap = { type = \"elliptic_paraboloid\", R1 = 2.0, R2 = 8.0, c1 = 0.25, c2 = -0.125 }";
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(src).unwrap();
    assert_eq!(k.name(), "tilting_punch");
    k.validate("obstacle").unwrap();
    let f = k.load();
    assert!((f[0] - 0.3).abs() + (f[1] + 0.015).abs() + (f[2] - 0.0675).abs() < 1e-15, "{f:?}");
    let m = mesh();
    let d = dofs(&m);
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let built = TiltingPunch::new(0.3, disc(0.5), elliptic()).unwrap().at([0.2, 0.1]).unwrap();
    assert_eq!(rows, built.discretise(&m, &d, "obstacle").unwrap());
    let again: Box<dyn AdmissibleDisplacements> = toml::from_str(&toml::to_string(&k).unwrap()).unwrap();
    assert_eq!(again.discretise(&m, &d, "obstacle").unwrap(), rows);
    assert_eq!(again.load(), f);
    // without `at`: the force acts at the pivot, and the round trip keeps it absent
    let no_at = src.replace("at = [0.2, 0.1]\n", "");
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(&no_at).unwrap();
    assert_eq!(k.load(), vec![0.3, 0.0, 0.0]);
    let text = toml::to_string(&k).unwrap();
    assert!(!text.contains("at ="), "{text}");
    for bad in ["pivot = [0.0, 0.0]", "U = 0.0", "slope_x1 = 0.1"] {
        let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&format!("{src}\n{bad}")).unwrap_err();
        let name = bad.split(' ').next().unwrap();
        assert!(err.to_string().contains(&format!("unknown field `{name}`")), "{err}");
    }
    let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&src.replace("F = 0.3\n", "")).unwrap_err();
    assert!(err.to_string().contains("missing field `F`"), "{err}");
}
